/* fp_file.c: temporary files beside their targets, new files' mode (fp_file.h). */
#define _GNU_SOURCE /* mkostemp */
#include "fp_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

int fp_file_open_regular(const char *path)
{
    if (!path) return -EINVAL;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) return errno == ENXIO ? -ENXIO : -errno; /* (ENXIO: a socket, a FIFO's other end) */
    struct stat st;
    int rc = fstat(fd, &st) ? -errno : S_ISDIR(st.st_mode) ? -EISDIR : !S_ISREG(st.st_mode) ? -ENXIO : 0;
    int fl = rc ? 0 : fcntl(fd, F_GETFL);
    if (!rc && (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0)) rc = -errno;
    if (rc) {
        close(fd);
        return rc;
    }
    return fd;
}

int fp_file_target(const char *path, char *real, size_t n)
{
    if (!path || !real || !n) return -EINVAL;
    char cur[4096], link[4096];
    if ((size_t)snprintf(cur, sizeof cur, "%s", path) >= sizeof cur) return -ENAMETOOLONG;
    for (int depth = 0;; depth++) {
        struct stat st;
        if (lstat(cur, &st) != 0) {
            if (errno != ENOENT) return -errno;
            break; /* a new file (its folder's absence is the temporary file's error) */
        }
        if (S_ISREG(st.st_mode)) break;
        if (S_ISDIR(st.st_mode)) return -EISDIR;
        if (!S_ISLNK(st.st_mode)) return -ENXIO;
        if (depth == 16) return -ELOOP;
        ssize_t k = readlink(cur, link, sizeof link - 1);
        if (k < 0) return -errno;
        link[k] = '\0';
        if (link[0] == '/') { /* absolute: the link's text; relative: beside the link */
            if ((size_t)snprintf(cur, sizeof cur, "%s", link) >= sizeof cur) return -ENAMETOOLONG;
        } else {
            char *slash = strrchr(cur, '/');
            if (slash) {
                size_t dir = (size_t)(slash - cur) + 1;
                if (dir + (size_t)k >= sizeof cur) return -ENAMETOOLONG;
                memcpy(cur + dir, link, (size_t)k + 1);
            } else {
                memcpy(cur, link, (size_t)k + 1);
            }
        }
    }
    if ((size_t)snprintf(real, n, "%s", cur) >= n) return -ENAMETOOLONG;
    return 0;
}

const char *fp_file_error_text(int code)
{
    switch (code) {
    case -EISDIR: return "is a folder, not a file";
    case -ENXIO: return "is not a regular file (a FIFO, device or socket)";
    case -ELOOP: return "too many symbolic links";
    default: return strerror(code < 0 ? -code : code);
    }
}

FILE *fp_file_fopen_regular(const char *path, int *code)
{
    int fd = fp_file_open_regular(path);
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!f) {
        *code = fd < 0 ? fd : -ENOMEM;
        if (fd >= 0) close(fd);
    }
    return f;
}

int fp_file_output_code(int e)
{
    switch (e) {
    case ENOENT: case ENOTDIR: return -ENOENT;
    case EACCES: case EPERM: case EROFS: return -EACCES;
    case ENOSPC: case EDQUOT: return -ENOSPC;
    case ENOMEM: return -ENOMEM;
    default: return -EIO;
    }
}
