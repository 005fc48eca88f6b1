/* The plugin validator's guard (fp_plugin_check.h, fp_plugin_check): the checks run in a
 * child process that reports its findings, its progress and its verdict through a pipe; the
 * parent relays the findings and judges the child's end (a signal, an exit without a verdict,
 * no progress within the deadline). */
#define _GNU_SOURCE
#include "fp_plugin_check.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

enum { REC_FINDING = 1, REC_PROGRESS = 2, REC_VERDICT = 3 };

/* One record on the pipe, written with one write() of at most PIPE_BUF bytes (atomic): the
 * header, then `len` bytes of the fields used. */
typedef struct rec {
    uint32_t type, len;
    int32_t code;                 /* FINDING: the fp_check_level; VERDICT: the return code */
    uint64_t frame;               /* PROGRESS */
    char call[48];                /* PROGRESS: the call; FINDING: the check's name */
    fp_check_summary sum;         /* FINDING, VERDICT: the child's summary so far */
    char text[2048];              /* FINDING: the message; VERDICT: err */
} rec;

_Static_assert(sizeof(rec) <= PIPE_BUF, "a record is written atomically");

#define REC_HEAD offsetof(rec, code)

/* ---- the child ----------------------------------------------------------------------- */

typedef struct writer {
    int fd;
    fp_check_summary *sum;
} writer;

static void send_rec(writer *w, rec *r, size_t used)
{
    r->len = (uint32_t)(used - REC_HEAD);
    const char *p = (const char *)r;
    while (used) {
        ssize_t n = write(w->fd, p, used);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) _exit(0); /* the parent is gone: nobody to tell */
        p += n;
        used -= (size_t)n;
    }
}

/* A record of `type` about `call`, its bytes up to `used` zeroed (those it sends). */
static void rec_begin(rec *r, uint32_t type, const char *call, size_t used)
{
    memset(r, 0, used);
    r->type = type;
    snprintf(r->call, sizeof r->call, "%s", call);
}

static void child_finding(void *user, fp_check_level level, const char *check, const char *message)
{
    writer *w = user;
    rec r;
    rec_begin(&r, REC_FINDING, check, offsetof(rec, text));
    r.code = level;
    r.sum = *w->sum;
    size_t n = strlen(message);
    if (n >= sizeof r.text) n = sizeof r.text - 1;
    memcpy(r.text, message, n);
    r.text[n] = '\0';
    send_rec(w, &r, offsetof(rec, text) + n + 1);
}

static void child_progress(void *user, const char *call, uint64_t frame)
{
    writer *w = user;
    rec r;
    rec_begin(&r, REC_PROGRESS, call, offsetof(rec, sum));
    r.frame = frame;
    send_rec(w, &r, offsetof(rec, sum));
}

static _Noreturn void child_main(int fd, pid_t parent, const char *file, const fp_check_options *opt)
{
    prctl(PR_SET_PDEATHSIG, SIGKILL); /* the checker interrupted: the plugin with it */
    if (getppid() != parent) _exit(0);
    signal(SIGPIPE, SIG_DFL);
    dup2(STDERR_FILENO, STDOUT_FILENO); /* a plugin's printf: not among the findings */
    fp_check_summary sum;
    memset(&sum, 0, sizeof sum);
    writer w = {fd, &sum};
    rec r;
    memset(&r, 0, sizeof r);
    int rc = fp_plugin_check_direct(file, opt, child_finding, &w, child_progress, &w, &sum, r.text,
                                    sizeof r.text);
    fflush(NULL);
    r.type = REC_VERDICT;
    r.code = rc;
    r.sum = sum;
    send_rec(&w, &r, offsetof(rec, text) + strlen(r.text) + 1);
    _exit(0); /* not exit(): nothing of the plugin's runs at exit */
}

/* ---- the parent ---------------------------------------------------------------------- */

typedef struct judge {
    fp_check_fn fn;
    void *user;
    fp_check_summary *sum;
    unsigned passed, failed, skipped;  /* the findings relayed */
    char call[48];                     /* the call in progress, "" before the first */
    uint64_t frame;
    bool verdict;
    int rc;
    char err[2048];
} judge;

static int64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/* Read exactly n bytes; false at the end of the pipe (or an error) first. */
static bool read_full(int fd, void *buf, size_t n)
{
    char *p = buf;
    while (n) {
        ssize_t k = read(fd, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return false;
        p += k;
        n -= (size_t)k;
    }
    return true;
}

static void relay(judge *j, fp_check_level level, const char *check, const char *message)
{
    if (level == FP_CHECK_PASS) j->passed++;
    if (level == FP_CHECK_FAIL) j->failed++;
    if (level == FP_CHECK_SKIP) j->skipped++;
    if (j->fn) j->fn(j->user, level, check, message);
}

/* One record from the child into j; false at the end of the pipe. */
static bool take_rec(judge *j, int fd)
{
    rec r;
    if (!read_full(fd, &r, REC_HEAD) || r.len > sizeof r - REC_HEAD || !read_full(fd, &r.code, r.len))
        return false;
    ((char *)&r)[REC_HEAD + r.len < sizeof r ? REC_HEAD + r.len : sizeof r - 1] = '\0';
    r.text[sizeof r.text - 1] = '\0';
    r.call[sizeof r.call - 1] = '\0';
    if (r.type == REC_PROGRESS) {
        snprintf(j->call, sizeof j->call, "%s", r.call);
        j->frame = r.frame;
    } else if (r.type == REC_FINDING && r.len >= offsetof(rec, text) - REC_HEAD) {
        *j->sum = r.sum;
        relay(j, (fp_check_level)r.code, r.call, r.text);
    } else if (r.type == REC_VERDICT && r.len >= offsetof(rec, text) - REC_HEAD) {
        *j->sum = r.sum;
        j->verdict = true;
        j->rc = r.code;
        snprintf(j->err, sizeof j->err, "%s", r.text);
    }
    return true;
}

/* Wait for the child to end, up to ms (then SIGKILL it); its wait status. */
static int reap(pid_t pid, int64_t ms, bool *killed)
{
    int status = 0;
    int64_t end = mono_ms() + ms;
    *killed = false;
    for (;;) {
        pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid || (r < 0 && errno != EINTR)) return status;
        if (mono_ms() >= end) break;
        struct timespec ts = {0, 5000000};
        nanosleep(&ts, NULL);
    }
    kill(pid, SIGKILL);
    *killed = true;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    return status;
}

/* "during process (frame 29)", "during create", "before its first call". */
static void where(const judge *j, char *buf, size_t len)
{
    if (!j->call[0]) snprintf(buf, len, "before its first call");
    else if (!strncmp(j->call, "process", 7) || !strcmp(j->call, "reset"))
        snprintf(buf, len, "during %s (frame %llu)", j->call, (unsigned long long)j->frame);
    else snprintf(buf, len, "during %s", j->call);
}

/* The child's end judged: a FAIL finding where it did not end with its verdict. */
static void judge_end(judge *j, int status, bool hung, double deadline_s)
{
    char at[96], msg[512];
    where(j, at, sizeof at);
    const char *check = j->call[0] ? j->call : "load";
    if (!strncmp(check, "process", 7)) check = "process";
    else if (!strcmp(check, "create in a helper process")) check = "isolated";
    if (hung) {
        snprintf(msg, sizeof msg, "no progress for %g s %s: the plugin hangs (the check was killed; "
                 "what followed was not checked)", deadline_s, at);
    } else if (WIFSIGNALED(status)) {
        const char *name = sigabbrev_np(WTERMSIG(status));
        char sig[32];
        if (name) snprintf(sig, sizeof sig, "SIG%s", name);
        else snprintf(sig, sizeof sig, "signal %d", WTERMSIG(status));
        snprintf(msg, sizeof msg, "the plugin died of %s %s (what followed was not checked)", sig, at);
    } else if (!j->verdict) {
        snprintf(msg, sizeof msg, "the plugin ended the process with exit status %d %s, without a verdict "
                 "(a plugin must not call exit(); what followed was not checked)",
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1, at);
    } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        snprintf(msg, sizeof msg, "the check's process ended with status %d after its verdict",
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    } else {
        return; /* ended with its verdict */
    }
    relay(j, FP_CHECK_FAIL, check, msg);
}

int fp_plugin_check(const char *file, const fp_check_options *opt, fp_check_fn fn, void *user,
                    fp_check_summary *sum, char *err, size_t errlen)
{
    fp_check_summary local;
    if (!sum) sum = &local;
    memset(sum, 0, sizeof *sum);
    const double deadline_s = opt && opt->deadline_s > 0 ? opt->deadline_s : FP_CHECK_DEADLINE_S;
    int fds[2];
    if (pipe2(fds, O_CLOEXEC)) return fp_errorf(err, errlen, -errno, "%s: cannot check: pipe: %s", file, strerror(errno));
    fflush(NULL); /* nothing buffered is written twice */
    pid_t parent = getpid(), pid = fork();
    if (pid < 0) {
        int e = errno;
        close(fds[0]);
        close(fds[1]);
        return fp_errorf(err, errlen, -e, "%s: cannot check: fork: %s", file, strerror(e));
    }
    if (pid == 0) {
        close(fds[0]);
        child_main(fds[1], parent, file, opt);
    }
    close(fds[1]);
    judge j = {.fn = fn, .user = user, .sum = sum};
    const int64_t wait_ms = (int64_t)(deadline_s * 1000);
    int64_t due = mono_ms() + wait_ms;
    bool hung = false;
    while (!j.verdict) {
        int64_t left = due - mono_ms();
        if (left <= 0) {
            hung = true;
            break;
        }
        struct pollfd q = {fds[0], POLLIN, 0};
        int k = poll(&q, 1, (int)left);
        if (k < 0 && errno == EINTR) continue;
        if (k == 0) continue;
        if (k < 0 || !take_rec(&j, fds[0])) break; /* the end of the pipe: the child is gone */
        due = mono_ms() + wait_ms;
    }
    close(fds[0]);
    bool killed;
    int status = hung ? (kill(pid, SIGKILL), reap(pid, wait_ms, &killed)) : reap(pid, wait_ms, &killed);
    hung |= killed && !j.verdict;
    judge_end(&j, status, hung, deadline_s);
    sum->passed = j.passed;
    sum->failed = j.failed;
    sum->skipped = j.skipped;
    if (j.verdict && j.rc != 0 && j.rc != FP_EPLUGIN_FAULT) {
        snprintf(err, errlen, "%s", j.err); /* not loaded at all: the loader's code */
        return j.rc;
    }
    if (j.failed) {
        snprintf(err, errlen, "%s: %u check(s) failed", file, j.failed);
        return FP_EPLUGIN_FAULT;
    }
    if (errlen) err[0] = '\0';
    return 0;
}
