/* SIGINT and SIGTERM end a session cleanly, even with a plugin stuck (app_stop.h). */
#define _GNU_SOURCE
#include "app_stop.h"

#include "fp_clock.h"
#include "fp_plugin_crash.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

enum { ST_OFF, ST_IDLE, ST_STEP, ST_TAKEN, ST_DONE };

static atomic_int state = ST_OFF;   /* the frame loop's: OFF until install */
static atomic_int got;              /* the first signal's number, 0 before */
static int wake[2] = {-1, -1};      /* the handler's pipe to the watchdog */
static pthread_t watchdog;
static bool watching;               /* the watchdog runs (install could start it) */
static const char *cmd_name;
static fp_app_stop_fn takeover_fn;
static void *takeover_user;

static const char *sig_name(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "signal"; }

/* async-signal-safe: write(2) of a string */
static void say(const char *a, const char *b, const char *c)
{
    const char *parts[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        ssize_t w = parts[i] ? write(STDERR_FILENO, parts[i], strlen(parts[i])) : 0;
        (void)w;
    }
}

static _Atomic int64_t got_ns; /* when the first came (CLOCK_MONOTONIC) */

static int64_t now_ns(void) /* (async-signal-safe: clock_gettime) */
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void on_signal(int sig)
{
    int saved = errno, none = 0;
    if (!atomic_compare_exchange_strong(&got, &none, sig)) {
        /* the second: at once, unless it is the first's echo (timeout(1) signals the command,
         * then its process group: the command gets the signal twice) */
        if (now_ns() - atomic_load(&got_ns) < FP_APP_STOP_REPEAT_NS) {
            errno = saved;
            return;
        }
        say(cmd_name, ": second ", sig == SIGINT ? "SIGINT: ending at once\n" : "SIGTERM: ending at once\n");
        _exit(128 + sig);
    }
    atomic_store(&got_ns, now_ns());
    char b = 's';
    ssize_t w = write(wake[1], &b, 1);
    (void)w;
    errno = saved;
}

/* the take-over's own limit (FP_APP_STOP_TAKEOVER_S) */
static void on_alarm(int sig)
{
    (void)sig;
    say(cmd_name, ": the take-over did not finish in time: ending without it\n", NULL);
    _exit(128 + atomic_load(&got));
}

/* The frame is abandoned: one line, the command's take-over, then the process ends. Runs
 * once, on the watchdog thread, which holds the frame loop's state (ST_TAKEN). */
static _Noreturn void take_over(int sig, const fp_plugin_call_info *call, int64_t now)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_alarm;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGALRM, &sa, NULL); /* (delivered to a thread that does not block it) */
    alarm(FP_APP_STOP_TAKEOVER_S);
    char line[1024];
    if (call)
        snprintf(line, sizeof line, "%s: %s: plugin '%s' has not returned from %s (frame %llu) "
                 "for %.2f s: ending without that frame; the take is closed and the outputs "
                 "written up to the frame before (exit %d)\n", cmd_name, sig_name(sig), call->who,
                 call->call ? call->call : "a call", (unsigned long long)call->frame,
                 (double)(now - call->since_ns) * 1e-9, 128 + sig);
    else
        snprintf(line, sizeof line, "%s: %s: the frame in progress has not ended %.1f s later "
                 "(not in a plugin call): ending without it; the take is closed (exit %d)\n",
                 cmd_name, sig_name(sig), FP_APP_STOP_STEP_LIMIT_NS * 1e-9, 128 + sig);
    say(line, NULL, NULL);
    if (takeover_fn) takeover_fn(takeover_user, sig, call != NULL);
    _exit(128 + sig);
}

/* 0 on the signal, 1 on stop (uninstall), 2 when nothing came within timeout_ms */
static int wait_wake(int timeout_ms)
{
    struct pollfd p = {.fd = wake[0], .events = POLLIN};
    int r = poll(&p, 1, timeout_ms);
    if (r <= 0) return 2; /* (EINTR cannot come: every signal is blocked here) */
    char b = 0;
    if (read(wake[0], &b, 1) != 1) return 2;
    return b == 'q';
}

static void *watch(void *u)
{
    (void)u;
    int w;
    while ((w = wait_wake(-1)) == 2) {}
    if (w == 1) return NULL;
    int64_t t_sig = fp_now_ns();
    for (;;) {
        int st = atomic_load(&state);
        if (st == ST_DONE) return NULL; /* the loop saw it and ends the command itself */
        int64_t now = fp_now_ns();
        if (st == ST_STEP && now - t_sig >= FP_APP_STOP_GRACE_NS) {
            fp_plugin_call_info call;
            bool in_plugin = fp_plugin_call_oldest(&call) && now - call.since_ns >= FP_APP_STOP_GRACE_NS;
            int want = ST_STEP;
            if ((in_plugin || now - t_sig >= FP_APP_STOP_STEP_LIMIT_NS) &&
                atomic_compare_exchange_strong(&state, &want, ST_TAKEN))
                take_over(atomic_load(&got), in_plugin ? &call : NULL, now);
        }
        if (wait_wake(10) == 1) return NULL;
    }
}

/* the watchdog and its pipe: 0 or a negative errno */
static int start_watchdog(void)
{
    if (pipe2(wake, O_CLOEXEC)) return -errno;
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, &old); /* the watchdog takes no signal */
    int rc = pthread_create(&watchdog, NULL, watch, NULL);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (rc) {
        close(wake[0]);
        close(wake[1]);
        wake[0] = wake[1] = -1; /* (the handler's write then fails: EBADF) */
        return -rc;
    }
    watching = true;
    return 0;
}

int fp_app_stop_install(const char *cmd, fp_app_stop_fn takeover, void *user)
{
    cmd_name = cmd;
    takeover_fn = takeover;
    takeover_user = user;
    atomic_store(&got, 0);
    int rc = start_watchdog(); /* without it, the handlers still end the loop after a frame */
    atomic_store(&state, ST_IDLE);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaddset(&sa.sa_mask, SIGINT);  /* (one handler at a time: the second is the second) */
    sigaddset(&sa.sa_mask, SIGTERM);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    return rc;
}

bool fp_app_stop_requested(void) { return atomic_load(&got) != 0; }
int fp_app_stop_signal(void) { return atomic_load(&got); }

void fp_app_stop_step_begin(void)
{
    int want = ST_IDLE;
    atomic_compare_exchange_strong(&state, &want, ST_STEP); /* (only this thread leaves IDLE) */
}

void fp_app_stop_step_end(void)
{
    int want = ST_STEP;
    if (atomic_compare_exchange_strong(&state, &want, ST_IDLE) || want != ST_TAKEN) return;
    for (;;) pause(); /* the watchdog ends the process */
}

void fp_app_stop_loop_end(void)
{
    int want = ST_IDLE;
    atomic_compare_exchange_strong(&state, &want, ST_DONE);
}

void fp_app_stop_uninstall(void)
{
    if (atomic_load(&state) == ST_OFF) return;
    fp_app_stop_loop_end();
    if (watching) {
        char b = 'q';
        ssize_t w = write(wake[1], &b, 1);
        (void)w;
        pthread_join(watchdog, NULL);
        watching = false;
    }
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (wake[0] >= 0) {
        close(wake[0]);
        close(wake[1]);
        wake[0] = wake[1] = -1;
    }
    atomic_store(&state, ST_OFF);
}
