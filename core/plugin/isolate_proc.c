/* An isolated mapping's helper process, host side: the shared memory, the wake-ups, the
 * spawn, the round trips with their deadline and the end (isolate_proc.h). */
#define _GNU_SOURCE
#include "isolate_proc.h"

#include "fp_clock.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

static size_t round_page(size_t n) { return (n + 4095) & ~(size_t)4095; }

int fp_iso_proc_reserve(fp_iso_proc *p, size_t bytes)
{
    bytes = round_page(bytes);
    if (bytes <= p->mapped) return 0;
    if (ftruncate(p->memfd, (off_t)bytes)) return -errno;
    void *m = mremap(p->shm, p->mapped, bytes, MREMAP_MAYMOVE);
    if (m == MAP_FAILED) return -errno;
    p->shm = m;
    p->mapped = bytes;
    atomic_store(&p->shm->size, bytes);
    return 0;
}

static void close_fd(int *fd)
{
    if (*fd >= 0) close(*fd);
    *fd = -1;
}

void fp_iso_proc_init(fp_iso_proc *p)
{
    memset(p, 0, sizeof *p);
    p->memfd = p->go = p->done = p->sock = -1;
}

static void release(fp_iso_proc *p)
{
    close_fd(&p->memfd);
    close_fd(&p->go);
    close_fd(&p->done);
    close_fd(&p->sock);
    if (p->shm) munmap(p->shm, p->mapped);
    p->shm = NULL;
    p->mapped = 0;
    p->pid = 0;
}

int fp_iso_proc_spawn(fp_iso_proc *p, const char *exe, const char *mode, const char *file, int file_fd,
                      const char *name,
                      const fp_param *params, size_t nparams, size_t bytes, uint32_t offers,
                      void (*fill)(void *user, fp_iso_shm *shm), void *fill_user)
{
    fp_iso_proc_init(p);
    int sv[2] = {-1, -1};
    int rc = 0;
    p->memfd = memfd_create("facepuppet-isolate", MFD_CLOEXEC);
    p->go = eventfd(0, EFD_CLOEXEC);
    p->done = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (p->memfd < 0 || p->go < 0 || p->done < 0 ||
        socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv)) {
        rc = -errno;
        goto fail;
    }
    p->sock = sv[0];
    size_t size = round_page(bytes > sizeof(fp_iso_shm) ? bytes : sizeof(fp_iso_shm));
    if (ftruncate(p->memfd, (off_t)size)) {
        rc = -errno;
        goto fail;
    }
    p->shm = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED, p->memfd, 0);
    if (p->shm == MAP_FAILED) {
        p->shm = NULL;
        rc = -errno;
        goto fail;
    }
    p->mapped = size;
    p->shm->magic = FP_ISO_MAGIC;
    p->shm->version = FP_ISO_VERSION;
    atomic_store(&p->shm->size, size);
    p->shm->offers = offers;
    memset(p->shm->start[FP_CONTROL_CAPACITY], FP_ISO_CANARY, sizeof p->shm->start[0] * FP_ISO_GUARD);
    memset(p->shm->end[FP_CONTROL_CAPACITY], FP_ISO_CANARY, sizeof p->shm->end[0] * FP_ISO_GUARD);
    memset(&p->shm->channels[FP_CHANNEL_CAPACITY], FP_ISO_CANARY, sizeof p->shm->channels[0] * FP_ISO_GUARD);
    if (fill) fill(fill_user, p->shm); /* the rig, for the plugin's create */

    char fds[4][16];
    snprintf(fds[0], sizeof fds[0], "%d", p->memfd);
    snprintf(fds[1], sizeof fds[1], "%d", p->go);
    snprintf(fds[2], sizeof fds[2], "%d", p->done);
    snprintf(fds[3], sizeof fds[3], "%d", sv[1]);
    char kv[FP_SPEC_MAX_PARAMS][512];
    char *argv[8 + FP_SPEC_MAX_PARAMS + 1];
    size_t a = 0;
    /* run as `exe` (/proc/self/exe: this very program, even if its file was replaced since),
     * named in ps as the file it came from */
    char name0[4096];
    ssize_t nl = readlink(exe, name0, sizeof name0 - 1);
    if (nl > 0) name0[nl] = '\0';
    else snprintf(name0, sizeof name0, "%s", exe);
    argv[a++] = name0;
    argv[a++] = (char *)mode;
    for (int i = 0; i < 4; i++) argv[a++] = fds[i];
    argv[a++] = (char *)file;
    argv[a++] = (char *)name;
    for (size_t i = 0; i < nparams && i < FP_SPEC_MAX_PARAMS; i++) {
        snprintf(kv[i], sizeof kv[i], "%s=%s", params[i].key, params[i].value ? params[i].value : "");
        argv[a++] = kv[i];
    }
    argv[a] = NULL;

    posix_spawn_file_actions_t fa;
    posix_spawnattr_t at;
    posix_spawn_file_actions_init(&fa);
    posix_spawnattr_init(&at);
    /* dup2 onto itself clears close-on-exec for the helper's four descriptors only */
    posix_spawn_file_actions_adddup2(&fa, p->memfd, p->memfd);
    posix_spawn_file_actions_adddup2(&fa, p->go, p->go);
    posix_spawn_file_actions_adddup2(&fa, p->done, p->done);
    posix_spawn_file_actions_adddup2(&fa, sv[1], sv[1]);
    if (file_fd >= 0) posix_spawn_file_actions_adddup2(&fa, file_fd, file_fd);
    sigset_t none, all;
    sigemptyset(&none);
    sigfillset(&all);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setsigdefault(&at, &all);
    posix_spawnattr_setpgroup(&at, 0); /* its own group: the terminal's ^C is the host's */
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
    pid_t pid;
    rc = -posix_spawn(&pid, exe, &fa, &at, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    close(sv[1]);
    sv[1] = -1;
    if (rc) goto fail;
    p->pid = pid;
    p->started_ns = fp_now_ns();
    return 0;
fail:
    if (sv[1] >= 0) close(sv[1]);
    release(p);
    return rc ? rc : -EIO;
}

/* Read the socket's messages: log lines to log_fn, a READY into p->ready/ready_rc/ready_text.
 * Returns false when the helper hung up. */
static bool drain_sock(fp_iso_proc *p, fp_iso_log_fn log_fn, void *user)
{
    for (;;) {
        fp_iso_msg m;
        ssize_t n = recv(p->sock, &m, sizeof m - 1, MSG_DONTWAIT);
        if (n == 0) return false;
        if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
        if ((size_t)n < offsetof(fp_iso_msg, text)) continue;
        ((char *)&m)[n] = '\0';
        m.text[sizeof m.text - 1] = '\0';
        if (m.type == FP_ISO_MSG_EVENT) {
            if (p->on_event) p->on_event(p->event_user, m.text, (size_t)n - offsetof(fp_iso_msg, text));
        } else if (m.type == FP_ISO_MSG_LOG && log_fn) {
            log_fn(user, m.rc, m.text);
        } else if (m.type == FP_ISO_MSG_READY) {
            p->ready = true;
            p->ready_rc = m.rc;
            snprintf(p->ready_text, sizeof p->ready_text, "%s", m.text);
        }
    }
}

int fp_iso_proc_wait_ready(fp_iso_proc *p, double timeout_ms, fp_iso_log_fn log_fn, void *user)
{
    int64_t end = fp_now_ns() + (int64_t)(timeout_ms * 1e6);
    while (!p->ready) {
        int64_t left = end - fp_now_ns();
        if (left <= 0) return timeout_ms > 0 ? FP_ISO_HUNG : FP_ISO_PENDING;
        struct pollfd q = {p->sock, POLLIN, 0};
        int k = poll(&q, 1, (int)((left + 999999) / 1000000));
        if (k < 0 && errno != EINTR) return FP_ISO_DIED;
        if (k > 0 && !drain_sock(p, log_fn, user)) return p->ready ? 0 : FP_ISO_DIED;
    }
    return 0;
}

int fp_iso_proc_poll_ready(fp_iso_proc *p, fp_iso_log_fn log_fn, void *user)
{
    if (!p->ready && !drain_sock(p, log_fn, user) && !p->ready) return FP_ISO_DIED;
    return p->ready ? 0 : FP_ISO_PENDING;
}

int fp_iso_proc_call(fp_iso_proc *p, uint32_t op, double deadline_ms,
                     int (*surface)(void *user, fp_iso_shm *shm), fp_iso_log_fn log_fn, void *user)
{
    fp_iso_shm *s = p->shm;
    s->op = op;
    uint64_t seq = atomic_load(&s->req_seq) + 1;
    atomic_store(&s->req_seq, seq);
    uint64_t one = 1;
    if (write(p->go, &one, sizeof one) != sizeof one) return FP_ISO_DIED;
    int64_t end = fp_now_ns() + (int64_t)(deadline_ms * 1e6);

    for (;;) {
        /* a short spin first: the answer of a quick process() comes within microseconds,
         * sooner than a sleep and a wake-up */
        for (int i = 0; i < 2000 && atomic_load(&s->reply_seq) != seq; i++)
            __asm__ __volatile__("" ::: "memory");
        if (atomic_load(&s->reply_seq) == seq) {
            uint64_t n;
            (void)!read(p->done, &n, sizeof n);
            if (s->reply != FP_ISO_REPLY_SURFACE) return 0;
            s->surf_rc = surface ? surface(user, s) : -ENOTSUP;
            s = p->shm; /* (the service may have grown nothing, but be safe) */
            s->op = FP_ISO_OP_SURFACE;
            seq = atomic_load(&s->req_seq) + 1;
            atomic_store(&s->req_seq, seq);
            if (write(p->go, &one, sizeof one) != sizeof one) return FP_ISO_DIED;
            continue;
        }
        int64_t left = end - fp_now_ns();
        if (left <= 0) return FP_ISO_HUNG;
        struct pollfd q[2] = {{p->done, POLLIN, 0}, {p->sock, POLLIN, 0}};
        int ms = (int)((left + 999999) / 1000000);
        int k = poll(q, 2, ms);
        if (k < 0 && errno != EINTR) return FP_ISO_DIED;
        if (k > 0 && (q[1].revents & (POLLIN | POLLHUP | POLLERR)) && !drain_sock(p, log_fn, user)) {
            if (atomic_load(&s->reply_seq) == seq) continue; /* it answered, then went */
            return FP_ISO_DIED;
        }
        if (k > 0 && (q[0].revents & POLLIN)) {
            uint64_t n;
            if (atomic_load(&s->reply_seq) != seq) (void)!read(p->done, &n, sizeof n); /* stale */
        }
    }
}

bool fp_iso_proc_drain_log(fp_iso_proc *p, fp_iso_log_fn log_fn, void *user)
{
    return p->sock >= 0 && drain_sock(p, log_fn, user);
}

int fp_iso_proc_follow(fp_iso_proc *p)
{
    size_t want = (size_t)atomic_load(&p->shm->size);
    if (want <= p->mapped) return 0;
    void *m = mremap(p->shm, p->mapped, want, MREMAP_MAYMOVE);
    if (m == MAP_FAILED) return -errno;
    p->shm = m;
    p->mapped = want;
    return 0;
}

void fp_iso_proc_kill(fp_iso_proc *p, char *why, size_t whylen)
{
    if (p->pid > 0) {
        int status = 0;
        pid_t r = waitpid(p->pid, &status, WNOHANG);
        bool exited_already = r == p->pid;
        if (!exited_already) {
            kill(p->pid, SIGKILL);
            while ((r = waitpid(p->pid, &status, 0)) < 0 && errno == EINTR) {}
        }
        if (why) {
            const char *sig = WIFSIGNALED(status) ? sigabbrev_np(WTERMSIG(status)) : NULL;
            if (sig) snprintf(why, whylen, "died of SIG%s", sig);
            else if (WIFSIGNALED(status)) snprintf(why, whylen, "died of signal %d", WTERMSIG(status));
            else snprintf(why, whylen, "exited with status %d", WEXITSTATUS(status));
        }
    }
    release(p);
    p->ready = false;
}

void fp_iso_proc_end(fp_iso_proc *p, double wait_ms, fp_iso_log_fn log_fn, void *user)
{
    if (p->pid > 0 && p->shm) {
        p->shm->op = FP_ISO_OP_QUIT;
        atomic_fetch_add(&p->shm->req_seq, 1);
        uint64_t one = 1;
        if (write(p->go, &one, sizeof one) == sizeof one) {
            int64_t end = fp_now_ns() + (int64_t)(wait_ms * 1e6);
            for (;;) { /* the helper closes its socket as it exits */
                int64_t left = end - fp_now_ns();
                if (left <= 0) break;
                struct pollfd q = {p->sock, POLLIN, 0};
                if (poll(&q, 1, (int)((left + 999999) / 1000000)) <= 0) continue;
                if (!drain_sock(p, log_fn, user)) break;
            }
        }
    }
    fp_iso_proc_kill(p, NULL, 0);
}
