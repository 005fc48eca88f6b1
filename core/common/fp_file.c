/* fp_file.c: temporary files beside their targets, new files' mode (fp_file.h). */
#define _GNU_SOURCE /* mkostemp */
#include "fp_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fp_file_temp_beside(const char *path, const char *tag, char *tmp, size_t n)
{
    if (!path || !tmp || !n) return -EINVAL;
    if (!tag) tag = "";
    const char *slash = strrchr(path, '/');
    int len = slash ? snprintf(tmp, n, "%.*s/.%s%s.XXXXXX", (int)(slash - path), path, slash + 1, tag)
                    : snprintf(tmp, n, ".%s%s.XXXXXX", path, tag);
    if (len < 0 || (size_t)len >= n) {
        tmp[0] = '\0';
        return -ENAMETOOLONG;
    }
    int fd = mkostemp(tmp, O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        tmp[0] = '\0';
        return -e;
    }
    return fd;
}

unsigned fp_file_new_mode(void)
{
    unsigned mask = 022;
    FILE *f = fopen("/proc/self/status", "re");
    if (f) {
        char line[256];
        unsigned m;
        while (fgets(line, sizeof line, f))
            if (sscanf(line, "Umask: %o", &m) == 1) mask = m;
        fclose(f);
    }
    return 0666 & ~mask;
}
