/* fuzz_file.h: for fuzz targets whose parser reads a file by name. fuzz_file_init(ext) makes a
 * private mkdtemp() folder (in $TMPDIR or /tmp, removed at exit) once; fuzz_file_write(data,
 * size) writes one input to `fuzz_file_path` (input.EXT in that folder) and returns the path.
 * Any I/O failure aborts (the harness is broken, not the parser). Test code only. */
#ifndef FP_FUZZ_FILE_H
#define FP_FUZZ_FILE_H

#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char fuzz_file_dir[64];
static char fuzz_file_path[128];
static char fuzz_file_path2[128];

static void fuzz_file_cleanup(void)
{
    unlink(fuzz_file_path);
    unlink(fuzz_file_path2);
    rmdir(fuzz_file_dir);
}

/* Also prepares fuzz_file_path2 (output.EXT) for targets that write a file back. */
static void fuzz_file_init(const char *ext)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(fuzz_file_dir, sizeof fuzz_file_dir, "%s/fp_fuzz_XXXXXX",
             tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(fuzz_file_dir)) abort();
    snprintf(fuzz_file_path, sizeof fuzz_file_path, "%s/input.%s", fuzz_file_dir, ext);
    snprintf(fuzz_file_path2, sizeof fuzz_file_path2, "%s/output.%s", fuzz_file_dir, ext);
    atexit(fuzz_file_cleanup);
}

static const char *fuzz_file_write(const uint8_t *data, size_t size)
{
    int fd = open(fuzz_file_path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) abort();
    for (size_t off = 0; off < size;) {
        ssize_t put = write(fd, data + off, size - off);
        if (put <= 0) abort();
        off += (size_t)put;
    }
    if (close(fd)) abort();
    return fuzz_file_path;
}

#endif
