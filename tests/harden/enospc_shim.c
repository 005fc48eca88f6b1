/* enospc_shim.c: an LD_PRELOAD library that makes a disk look full for one file, for the
 * tests of recordings that hit a full disk (test_outputs.sh). Files opened (open, open64,
 * openat, openat64, creat; forgotten at close) whose path ends with $FP_ENOSPC_MATCH are
 * watched; all watched files together may receive $FP_ENOSPC_AFTER bytes through write(); a
 * write past that takes what still fits (a short count) and the next fails with ENOSPC, as a
 * full disk does. Every other file and fd is untouched. Test code only: not thread-safe beyond what the recorder
 * needs (one writer thread per file; a mutex guards the table). fchmod: see below. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#define MAX_FD 4096

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned char watched[MAX_FD];
static long long used, limit = -1;

static int matches(const char *path)
{
    const char *m = getenv("FP_ENOSPC_MATCH");
    if (!m || !*m || !path) return 0;
    size_t lp = strlen(path), lm = strlen(m);
    return lp >= lm && strcmp(path + lp - lm, m) == 0;
}

static void note(int fd, const char *path)
{
    if (fd < 0 || fd >= MAX_FD) return;
    pthread_mutex_lock(&lock);
    watched[fd] = (unsigned char)matches(path);
    if (limit < 0) {
        const char *a = getenv("FP_ENOSPC_AFTER");
        limit = a ? atoll(a) : 0;
    }
    pthread_mutex_unlock(&lock);
}

#define OPEN_MODE(flags, mode)                                                                 \
    mode_t mode = 0;                                                                           \
    if ((flags) & (O_CREAT | O_TMPFILE)) {                                                     \
        va_list ap;                                                                            \
        va_start(ap, flags);                                                                   \
        mode = (mode_t)va_arg(ap, int);                                                        \
        va_end(ap);                                                                            \
    }

int open(const char *path, int flags, ...)
{
    OPEN_MODE(flags, mode);
    static int (*real)(const char *, int, ...);
    if (!real) real = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open");
    int fd = real(path, flags, mode);
    note(fd, path);
    return fd;
}

int open64(const char *path, int flags, ...)
{
    OPEN_MODE(flags, mode);
    static int (*real)(const char *, int, ...);
    if (!real) real = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open64");
    int fd = real(path, flags, mode);
    note(fd, path);
    return fd;
}

int openat(int dir, const char *path, int flags, ...)
{
    OPEN_MODE(flags, mode);
    static int (*real)(int, const char *, int, ...);
    if (!real) real = (int (*)(int, const char *, int, ...))dlsym(RTLD_NEXT, "openat");
    int fd = real(dir, path, flags, mode);
    note(fd, path);
    return fd;
}

int openat64(int dir, const char *path, int flags, ...)
{
    OPEN_MODE(flags, mode);
    static int (*real)(int, const char *, int, ...);
    if (!real) real = (int (*)(int, const char *, int, ...))dlsym(RTLD_NEXT, "openat64");
    int fd = real(dir, path, flags, mode);
    note(fd, path);
    return fd;
}

int creat(const char *path, mode_t mode)
{
    return open(path, O_WRONLY | O_CREAT | O_TRUNC, mode);
}

int close(int fd)
{
    static int (*real)(int);
    if (!real) real = (int (*)(int))dlsym(RTLD_NEXT, "close");
    if (fd >= 0 && fd < MAX_FD) watched[fd] = 0; /* the number may come back for another file */
    return real(fd);
}

ssize_t write(int fd, const void *buf, size_t n)
{
    static ssize_t (*real)(int, const void *, size_t);
    if (!real) real = (ssize_t(*)(int, const void *, size_t))dlsym(RTLD_NEXT, "write");
    if (fd < 0 || fd >= MAX_FD || !watched[fd] || n == 0) return real(fd, buf, n);
    pthread_mutex_lock(&lock);
    long long room = limit - used;
    if (room <= 0) {
        pthread_mutex_unlock(&lock);
        errno = ENOSPC;
        return -1;
    }
    size_t take = (long long)n > room ? (size_t)room : n;
    ssize_t put = real(fd, buf, take);
    if (put > 0) used += put;
    pthread_mutex_unlock(&lock);
    return put;
}

/* With $FP_FCHMOD_EPERM set (non-empty), fchmod fails with EPERM for every descriptor, as on
 * a file system without Unix modes (vfat, exFAT: a mode other than the mount's is refused). */
int fchmod(int fd, mode_t mode)
{
    static int (*real)(int, mode_t);
    const char *e = getenv("FP_FCHMOD_EPERM");
    if (e && *e) {
        errno = EPERM;
        return -1;
    }
    if (!real) real = (int (*)(int, mode_t))dlsym(RTLD_NEXT, "fchmod");
    return real(fd, mode);
}
