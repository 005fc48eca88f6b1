/* fp_file.c: outputs written through a temporary file beside their targets, new files' mode,
 * regular files opened for reading (fp_file.h). */
#define _GNU_SOURCE /* mkostemp */
#include "fp_file.h"
#include "fp_clock.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
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
    const long pid = (long)getpid(); /* (whose it is: fp_file_open_output removes a dead one's) */
    int len = slash ? snprintf(tmp, n, "%.*s/.%s%s.%ld.XXXXXX", (int)(slash - path), path, slash + 1, tag, pid)
                    : snprintf(tmp, n, ".%s%s.%ld.XXXXXX", path, tag, pid);
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

int fp_file_read_all(const char *path, size_t max, char **buf, size_t *len)
{
    if (buf) *buf = NULL;
    if (len) *len = 0;
    if (!path || !buf || !len) return -EINVAL;
    int code = 0;
    FILE *f = fp_file_fopen_regular(path, &code);
    if (!f) return code;
    struct stat st; /* a file already past max: refused before reading max bytes of it */
    if (fstat(fileno(f), &st) == 0 && st.st_size > 0 && (uintmax_t)st.st_size > (uintmax_t)max) {
        fclose(f);
        return -EFBIG;
    }
    char *b = NULL;
    size_t n = 0, cap = 0, lim = max < SIZE_MAX - 2 ? max + 1 : SIZE_MAX - 2;
    int rc = 0;
    for (;;) {
        if (n == cap) { /* grown by doubling, to max + 1 at most: one byte past max tells */
            size_t want = cap ? 2 * cap : 8192;
            if (want > lim || want < cap) want = lim;
            char *t = want > cap ? realloc(b, want + 1) : NULL;
            if (!t) {
                rc = want > cap ? -ENOMEM : -EFBIG;
                break;
            }
            b = t;
            cap = want;
        }
        size_t got = fread(b + n, 1, cap - n, f);
        n += got;
        if (n > max) {
            rc = -EFBIG;
            break;
        }
        if (got == 0) {
            if (ferror(f)) rc = -EIO;
            break;
        }
    }
    fclose(f);
    if (rc) {
        free(b);
        return rc;
    }
    if (!b && !(b = malloc(1))) return -ENOMEM; /* (an empty file) */
    b[n] = '\0';
    *buf = b;
    *len = n;
    return 0;
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

/* A temporary's name ends ".PID.XXXXXX": the PID (a positive decimal without sign or leading
 * zero) where p is "PID.XXXXXX" exactly, else 0. */
static long temp_pid(const char *p)
{
    char *end;
    if (*p < '1' || *p > '9') return 0;
    errno = 0;
    long pid = strtol(p, &end, 10);
    return errno || *end != '.' || strlen(end + 1) != 6 || pid > INT_MAX ? 0 : pid;
}

/* Whether name is a temporary fp_file_temp_beside made in a process that is gone (its PID
 * names no process: kill(PID, 0) fails with ESRCH; this process's are never). */
static bool dead_temp(const char *name)
{
    const char *dot = strrchr(name, '.');
    if (name[0] != '.' || !dot || dot - name < 3) return false;
    const char *p = dot - 1; /* back to the '.' before the PID */
    while (p > name && *p >= '0' && *p <= '9') p--;
    long pid = *p == '.' && p > name ? temp_pid(p + 1) : 0;
    return pid > 0 && pid != (long)getpid() && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

/* The dead processes' temporaries of the folder this thread last read, for a second: a
 * sequence of saves into one folder (obj-seq, png-seq, --frames-out: thousands of files) reads
 * it once a second, not once a file (3 ms a file in a folder of 10000). More than
 * FP_SWEEP_KEEP: read it each time. */
enum { FP_SWEEP_KEEP = 8 };
#define FP_SWEEP_NS 1000000000LL
static _Thread_local struct {
    char folder[4096];
    bool valid, overflow;
    int64_t read_ns;
    size_t n;
    char names[FP_SWEEP_KEEP][256];
} sweep;

/* Remove the temporaries fp_file_temp_beside made for `path` and `tag` in processes that are
 * gone (killed before their commit or abort): ".NAME<tag>.PID.XXXXXX" beside path whose PID
 * names no process. Best effort. Returns how many were removed. */
static size_t remove_stale(const char *path, const char *tag)
{
    const char *slash = strrchr(path, '/');
    char folder[4096], prefix[512];
    if (!slash) snprintf(folder, sizeof folder, ".");
    else if (slash == path) snprintf(folder, sizeof folder, "/");
    else if ((size_t)snprintf(folder, sizeof folder, "%.*s", (int)(slash - path), path) >= sizeof folder) return 0;
    int pl = snprintf(prefix, sizeof prefix, ".%s%s.", slash ? slash + 1 : path, tag);
    if (pl < 0 || (size_t)pl >= sizeof prefix) return 0;
    size_t removed = 0;
    const int64_t now = fp_now_ns();
    if (sweep.valid && !sweep.overflow && now - sweep.read_ns < FP_SWEEP_NS && !strcmp(sweep.folder, folder)) {
        for (size_t i = 0; i < sweep.n;) {
            if (strncmp(sweep.names[i], prefix, (size_t)pl) || !temp_pid(sweep.names[i] + pl)) {
                i++;
                continue;
            }
            char p[4096 + 260];
            snprintf(p, sizeof p, "%s/%s", folder, sweep.names[i]);
            removed += unlink(p) == 0;
            memcpy(sweep.names[i], sweep.names[--sweep.n], sizeof sweep.names[i]);
        }
        return removed;
    }
    DIR *d = opendir(folder);
    sweep.valid = d != NULL;
    sweep.read_ns = now;
    sweep.overflow = false;
    sweep.n = 0;
    snprintf(sweep.folder, sizeof sweep.folder, "%s", folder);
    if (!d) return 0;
    const struct dirent *e;
    while ((e = readdir(d))) {
        if (!dead_temp(e->d_name)) continue;
        if (!strncmp(e->d_name, prefix, (size_t)pl) && temp_pid(e->d_name + pl))
            removed += unlinkat(dirfd(d), e->d_name, 0) == 0;
        else if (sweep.n < FP_SWEEP_KEEP && strlen(e->d_name) < sizeof sweep.names[0])
            snprintf(sweep.names[sweep.n++], sizeof sweep.names[0], "%s", e->d_name);
        else
            sweep.overflow = true;
    }
    closedir(d);
    return removed;
}

/* o emptied: nothing open, no temporary (o->path kept). */
static void output_clear(fp_file_output *o)
{
    o->tmp[0] = '\0';
    o->fd = -1;
    o->f = NULL;
}

int fp_file_open_output(const char *path, const char *tag, const char *stdio_mode, unsigned flags,
                        fp_file_output *o)
{
    if (!o) return -EINVAL;
    output_clear(o);
    o->stale = 0;
    o->flags = flags;
    o->failed = FP_FILE_STEP_TARGET;
    int rc = fp_file_target(path, o->path, sizeof o->path); /* (path may be o->path) */
    if (rc < 0) return rc;
    o->failed = FP_FILE_STEP_TEMP;
    o->stale = remove_stale(o->path, tag ? tag : "");
    int fd = fp_file_temp_beside(o->path, tag, o->tmp, sizeof o->tmp);
    if (fd < 0) return fd;
    o->fd = fd;
    mode_t mode = (mode_t)fp_file_new_mode();
    struct stat st;
    if ((flags & FP_FILE_OUTPUT_KEEP_MODE) && stat(o->path, &st) == 0 && S_ISREG(st.st_mode))
        mode = st.st_mode & 07777;
    int e = 0;
    /* best effort: a file system without Unix modes (vfat, exFAT, some network shares)
     * refuses fchmod with EPERM, and a save there must still be made */
    (void)fchmod(fd, mode);
    if (stdio_mode && !(o->f = fdopen(fd, stdio_mode))) {
        e = errno ? errno : ENOMEM;
        o->failed = FP_FILE_STEP_STREAM;
    }
    if (e) {
        close(fd);
        unlink(o->tmp);
        output_clear(o);
        return -e;
    }
    o->failed = FP_FILE_STEP_NONE;
    return 0;
}

int fp_file_output_commit(fp_file_output *o)
{
    if (!o || !o->tmp[0]) {
        if (o) o->failed = FP_FILE_STEP_NONE;
        return -EINVAL;
    }
    int e = 0;
    fp_file_step step = FP_FILE_STEP_NONE;
    if (o->f) {
        if (fflush(o->f) != 0) e = errno ? errno : EIO;
        else if (ferror(o->f)) e = EIO; /* a write that failed earlier, its data dropped */
        else if (fsync(o->fd) != 0) e = errno;
        if (e) step = FP_FILE_STEP_SYNC;
        if (fclose(o->f) != 0 && !e) e = errno, step = FP_FILE_STEP_CLOSE;
    } else {
        if (fsync(o->fd) != 0) e = errno, step = FP_FILE_STEP_SYNC;
        if (close(o->fd) != 0 && !e) e = errno, step = FP_FILE_STEP_CLOSE;
    }
    o->f = NULL;
    o->fd = -1;
    if (!e && rename(o->tmp, o->path) != 0) e = errno, step = FP_FILE_STEP_RENAME;
    if (e) unlink(o->tmp);
    o->tmp[0] = '\0';
    o->failed = step;
    if (e) return -e;
    if (o->flags & FP_FILE_OUTPUT_SYNC_FOLDER) { /* the rename's durability */
        char dir[4096];
        const char *slash = strrchr(o->path, '/');
        if (!slash) snprintf(dir, sizeof dir, ".");
        else if (slash == o->path) snprintf(dir, sizeof dir, "/");
        else snprintf(dir, sizeof dir, "%.*s", (int)(slash - o->path), o->path);
        int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (dfd >= 0) {
            (void)fsync(dfd);
            close(dfd);
        }
    }
    return 0;
}

void fp_file_output_abort(fp_file_output *o)
{
    if (!o || !o->tmp[0]) return;
    if (o->f) fclose(o->f);
    else if (o->fd >= 0) close(o->fd);
    unlink(o->tmp);
    output_clear(o);
}

int fp_file_mkdirs(const char *path)
{
    if (!path || !*path) return -EINVAL;
    char p[4096];
    size_t n = strlen(path);
    if (n >= sizeof p) return -ENAMETOOLONG;
    memcpy(p, path, n + 1);
    while (n > 1 && p[n - 1] == '/') p[--n] = '\0'; /* (a trailing slash) */
    for (char *s = p + 1;; s++) { /* each parent in turn, then the whole */
        if (*s && *s != '/') continue;
        const char c = *s;
        *s = '\0';
        struct stat st;
        if (mkdir(p, 0777) != 0 && errno != EEXIST) return -errno;
        if (stat(p, &st) != 0) return -errno;
        if (!S_ISDIR(st.st_mode)) return -ENOTDIR;
        if (!c) return 0;
        *s = c;
    }
}
