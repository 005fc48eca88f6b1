/* An input plugin in a helper process, host side (fp_isolate.h): the proxy fp_input, the
 * reader thread that pushes the helper's events into the instance's queue, the faults and
 * the restarts. The helper's side is isolate_input_helper.c. */
#define _GNU_SOURCE
#include "fp_isolate.h"
#include "isolate_proc.h"

#include "fp_clock.h"
#include "fp_file.h"

#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

enum { PHASE_UP = 0, PHASE_RESTARTING = 1, PHASE_GONE = 2 };

typedef struct iproxy {
    fp_input in;                /* first: the fp_input the host holds */
    const fp_host *host;        /* the instance's: push_event, log */
    fp_iso_proc proc;           /* the helper; replaced by the reader under `lock` */
    pthread_mutex_t lock;
    pthread_t reader;
    bool reader_on;
    atomic_bool stopping;
    atomic_int phase;
    int file_fd;
    fp_spec keys;
    char exe[4096], file[4096], name[64], arg[4096];
    bool has_arg;
    uint32_t ext;               /* FP_ISO_EXT_* as the first helper answered */
    float ws_min[3], ws_max[3];
    fp_recording_info info;
    fp_iso_joints *joints;
    size_t njoints;
    bool own_clock;             /* fp_input_own_clock of the plugin's instance */
    int64_t last_time;          /* the latest event time forwarded (the reader's) */
    int64_t up_since;           /* when the helper now serving started its input */
    int streak;                 /* faults in a row */
    atomic_ulong faults, restarts;
    atomic_bool gave_up;
} iproxy;

static void relay_log(void *user, int level, const char *message)
{
    iproxy *x = user;
    x->host->log(x->host, (fp_log_level)level, message);
}

static void nap(long ns)
{
    struct timespec ts = {0, ns};
    nanosleep(&ts, NULL);
}

/* An event as the helper sent it, into the instance's queue (the host's push_event and its
 * checks, as in process), waiting for room: a full queue holds the helper back, as it holds
 * back a plugin in process, and drops nothing here. */
static void forward(void *user, const void *bytes, size_t n)
{
    iproxy *x = user;
    fp_event ev;
    if (n < sizeof ev.header) return;
    memset(&ev, 0, sizeof ev);
    memcpy(&ev, bytes, n < sizeof ev ? n : sizeof ev);
    while (!x->host->push_event(x->host, &ev.header) && !atomic_load(&x->stopping)) nap(200000);
    if (ev.header.size >= sizeof ev.header && ev.header.time_ns > x->last_time) x->last_time = ev.header.time_ns;
}

static void push_status(iproxy *x, uint32_t code, int hand, const char *text, int64_t t)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.status.header.size = sizeof ev.status;
    ev.status.header.type = FP_EVENT_STATUS;
    ev.status.header.time_ns = t;
    ev.status.header.hand = hand;
    ev.status.code = code;
    snprintf(ev.status.text, sizeof ev.status.text, "%.115s", text);
    forward(x, &ev, sizeof ev.status);
}

static void fill_arg(void *user, fp_iso_shm *shm)
{
    const iproxy *x = user;
    shm->in_has_arg = x->has_arg;
    snprintf(shm->in_arg, sizeof shm->in_arg, "%s", x->arg);
}

/* A helper for the plugin (a restart loads it through the descriptor opened at create, as a
 * mapping's does). 0 or a negative errno. */
static int spawn(iproxy *x, bool restart)
{
    char via_fd[64];
    snprintf(via_fd, sizeof via_fd, "/proc/self/fd/%d", x->file_fd);
    int rc = fp_iso_proc_spawn(&x->proc, x->exe, FP_ISOLATE_INPUT_HELPER_ARG, restart ? via_fd : x->file,
                               restart ? x->file_fd : -1, x->name, x->keys.params, x->keys.nparams,
                               sizeof(fp_iso_shm), 0, fill_arg, x);
    x->proc.on_event = forward;
    x->proc.event_user = x;
    return rc;
}

/* The helper's create (loaded, created, its extensions answered): 0, or the code with what
 * happened in err; the helper is ended on failure. */
static int wait_created(iproxy *x, char *err, size_t errlen)
{
    int rc = fp_iso_proc_wait_ready(&x->proc, FP_ISOLATE_CREATE_MS, relay_log, x);
    bool in_create = x->proc.shm && atomic_load(&x->proc.shm->stage) >= FP_ISO_STAGE_CREATE;
    char why[96] = "did not answer";
    if (rc == FP_ISO_DIED) {
        fp_iso_proc_kill(&x->proc, why, sizeof why);
        snprintf(err, errlen, "its helper process %s %s%s", why,
                 in_create ? "in the plugin's create" : "while loading ", in_create ? "" : x->file);
        return FP_EPLUGIN_FAULT;
    }
    if (rc) {
        fp_iso_proc_kill(&x->proc, NULL, 0);
        snprintf(err, errlen, "the plugin's %s did not end within %g s (in its helper process)",
                 in_create ? "create" : "loading", FP_ISOLATE_CREATE_MS / 1e3);
        return FP_EPLUGIN_FAULT;
    }
    if (x->proc.ready_rc) {
        snprintf(err, errlen, "%s", x->proc.ready_text);
        fp_iso_proc_kill(&x->proc, NULL, 0);
        return x->proc.ready_rc;
    }
    if ((rc = fp_iso_proc_follow(&x->proc))) {
        fp_iso_proc_kill(&x->proc, NULL, 0);
        return fp_errorf(err, errlen, rc, "cannot map its helper's memory: %s", strerror(-rc));
    }
    return 0;
}

/* The helper's start: 0, or the code with the plugin's message or the helper's fate. */
static int start_helper(iproxy *x, char *err, size_t errlen)
{
    int rc = fp_iso_proc_call(&x->proc, FP_ISO_OP_START, FP_ISOLATE_CREATE_MS, NULL, relay_log, x);
    if (rc == FP_ISO_DIED) {
        char why[96] = "went away";
        fp_iso_proc_kill(&x->proc, why, sizeof why);
        snprintf(err, errlen, "its helper process %s in the plugin's start", why);
        return FP_EPLUGIN_FAULT;
    }
    if (rc) {
        fp_iso_proc_kill(&x->proc, NULL, 0);
        snprintf(err, errlen, "the plugin's start did not return within %g s (in its helper process)",
                 FP_ISOLATE_CREATE_MS / 1e3);
        return FP_EPLUGIN_FAULT;
    }
    if (x->proc.shm->rc) snprintf(err, errlen, "%s", x->proc.shm->in_err);
    return x->proc.shm->rc;
}

/* The helper is gone (`why`): said once, in the take too (a status the session logs under the
 * input's name), and the input's hands released as an unplugged device's; then a new helper
 * after the back-off, or the end of the stream. True when a new helper serves. [reader] */
static bool fault(iproxy *x, const char *why_first)
{
    char why[160];
    snprintf(why, sizeof why, "%s", why_first);
    /* a helper that served a while ends a row (not a restart that failed: it never served) */
    if (fp_now_ns() - x->up_since >= (int64_t)(FP_ISOLATE_INPUT_HEALTHY_MS * 1e6)) x->streak = 0;
    for (;;) {
        x->streak++;
        atomic_fetch_add(&x->faults, 1);
        bool give_up = x->own_clock || x->streak >= FP_ISOLATE_MAX_FAULTS;
        double wait = FP_ISOLATE_BACKOFF_MS;
        for (int i = 1; i < x->streak && wait < FP_ISOLATE_BACKOFF_MAX_MS; i++) wait *= 2;
        if (wait > FP_ISOLATE_BACKOFF_MAX_MS) wait = FP_ISOLATE_BACKOFF_MAX_MS;
        char text[256]; /* (cut to the status's 116 bytes: the forms below fit with a signal's name) */
        if (give_up && x->own_clock)
            snprintf(text, sizeof text, "isolated: the helper process %.60s; hands released, a recording is not "
                     "restarted: its stream ends", why);
        else if (give_up)
            snprintf(text, sizeof text, "isolated: the helper process %.60s; hands released; %d faults in a row: "
                     "given up, its stream ends", why, x->streak);
        else
            snprintf(text, sizeof text, "isolated: the helper process %.60s; hands released, restarts in %.1f s "
                     "(fault %d in a row)", why, wait / 1e3, x->streak);
        int64_t t = x->own_clock && x->last_time ? x->last_time : fp_now_ns();
        push_status(x, FP_STATUS_WARNING, -1, text, t);
        push_status(x, FP_STATUS_DISCONNECTED, FP_HAND_LEFT, "", t);
        push_status(x, FP_STATUS_DISCONNECTED, FP_HAND_RIGHT, "", t);
        if (give_up) {
            push_status(x, FP_STATUS_END_OF_STREAM, -1, "", t);
            atomic_store(&x->gave_up, true);
            atomic_store(&x->phase, PHASE_GONE);
            return false;
        }
        for (int64_t until = fp_now_ns() + (int64_t)(wait * 1e6); fp_now_ns() < until;) {
            if (atomic_load(&x->stopping)) return false;
            nap(10000000);
        }
        pthread_mutex_lock(&x->lock);
        int rc = atomic_load(&x->stopping) ? -ECANCELED : spawn(x, true);
        pthread_mutex_unlock(&x->lock);
        if (rc == -ECANCELED) return false;
        char err[1000] = "";
        if (rc) snprintf(err, sizeof err, "could not be started again (%s)", strerror(-rc));
        else if (!(rc = wait_created(x, err, sizeof err)) && !(rc = start_helper(x, err, sizeof err))) {
            x->up_since = fp_now_ns();
            atomic_fetch_add(&x->restarts, 1);
            atomic_store(&x->phase, PHASE_UP);
            char line[160];
            snprintf(line, sizeof line, "isolated: the helper is back (restart %lu, pid %d)",
                     atomic_load(&x->restarts), (int)x->proc.pid);
            relay_log(x, FP_LOG_INFO, line);
            return true;
        }
        pthread_mutex_lock(&x->lock);
        fp_iso_proc_kill(&x->proc, NULL, 0); /* (where the failed step left it) */
        pthread_mutex_unlock(&x->lock);
        if (atomic_load(&x->stopping)) return false;
        snprintf(why, sizeof why, "%.150s", err); /* ("its helper process died of ..." and the like) */
        if (!strncmp(why, "its helper process ", 19)) memmove(why, why + 19, strlen(why + 19) + 1);
    }
}

/* [reader] The helper's events and lines, as they come, until it is stopped or given up. */
static void *reader_main(void *arg)
{
    iproxy *x = arg;
    for (;;) {
        struct pollfd q = {x->proc.sock, POLLIN, 0};
        if (poll(&q, 1, 100) < 0 && errno != EINTR) nap(1000000);
        if (fp_iso_proc_drain_log(&x->proc, relay_log, x)) continue;
        if (atomic_load(&x->stopping)) break;
        char why[96] = "went away";
        pthread_mutex_lock(&x->lock);
        atomic_store(&x->phase, PHASE_RESTARTING);
        fp_iso_proc_kill(&x->proc, why, sizeof why);
        pthread_mutex_unlock(&x->lock);
        if (atomic_load(&x->stopping) || !fault(x, why)) break;
    }
    return NULL;
}

static int proxy_start(fp_input *self, char *err, size_t errlen)
{
    iproxy *x = self->plugin_data;
    if (x->proc.pid <= 0) return fp_errorf(err, errlen, FP_EPLUGIN_FAULT, "its helper process is gone");
    int rc = start_helper(x, err, errlen);
    if (rc) return rc;
    x->up_since = fp_now_ns();
    atomic_store(&x->phase, PHASE_UP);
    if (pthread_create(&x->reader, NULL, reader_main, x))
        return fp_errorf(err, errlen, -ENOMEM, "cannot start the thread that reads its helper");
    x->reader_on = true;
    return 0;
}

/* QUIT to a helper that serves (its plugin's stop and destroy run there, its last events come
 * meanwhile); SIGKILL to one being restarted. [under lock] */
static void ask_quit(iproxy *x)
{
    if (x->proc.pid <= 0) return;
    if (atomic_load(&x->phase) != PHASE_UP) {
        kill(x->proc.pid, SIGKILL);
        return;
    }
    x->proc.shm->op = FP_ISO_OP_QUIT;
    atomic_fetch_add(&x->proc.shm->req_seq, 1);
    uint64_t one = 1;
    if (write(x->proc.go, &one, sizeof one) != sizeof one) kill(x->proc.pid, SIGKILL);
}

static void proxy_stop(fp_input *self)
{
    iproxy *x = self->plugin_data;
    atomic_store(&x->stopping, true);
    pthread_mutex_lock(&x->lock);
    ask_quit(x);
    pthread_mutex_unlock(&x->lock);
    int64_t until = fp_now_ns() + (int64_t)(FP_ISOLATE_INPUT_STOP_MS * 1e6);
    if (x->reader_on) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts); /* (pthread_timedjoin_np's clock) */
        ts.tv_sec += (time_t)(FP_ISOLATE_INPUT_STOP_MS / 1000);
        if (pthread_timedjoin_np(x->reader, NULL, &ts)) {
            pthread_mutex_lock(&x->lock);
            bool up = x->proc.pid > 0;
            if (up) kill(x->proc.pid, SIGKILL); /* its stop did not return */
            pthread_mutex_unlock(&x->lock);
            pthread_join(x->reader, NULL);
            if (up) {
                char line[200];
                snprintf(line, sizeof line, "isolated: its stop has not returned within %g s: the helper "
                         "process was killed", FP_ISOLATE_INPUT_STOP_MS / 1e3);
                relay_log(x, FP_LOG_WARNING, line);
            }
        }
        x->reader_on = false;
    } else {
        while (fp_iso_proc_drain_log(&x->proc, relay_log, x) && fp_now_ns() < until) {
            struct pollfd q = {x->proc.sock, POLLIN, 0};
            (void)poll(&q, 1, 50);
        }
    }
    fp_iso_proc_kill(&x->proc, NULL, 0);
}

static void proxy_destroy(fp_input *self)
{
    iproxy *x = self->plugin_data;
    if (x->reader_on || x->proc.pid > 0) proxy_stop(self);
    if (x->file_fd >= 0) close(x->file_fd);
    free(x->joints);
    fp_spec_clear(&x->keys);
    pthread_mutex_destroy(&x->lock);
    free(x);
}

/* ---- the extensions, from the copies the first helper sent --------------------------- */

static bool ws_get(const fp_input *self, float min_mm[3], float max_mm[3])
{
    const iproxy *x = self->plugin_data;
    if (!(x->ext & FP_ISO_EXT_WORKSPACE_OK)) return false;
    memcpy(min_mm, x->ws_min, sizeof x->ws_min);
    memcpy(max_mm, x->ws_max, sizeof x->ws_max);
    return true;
}
static bool clock_on(const fp_input *self)
{
    return (((const iproxy *)self->plugin_data)->ext & FP_ISO_EXT_CLOCK_ON) != 0;
}
static bool info_get(const fp_input *self, fp_recording_info *info)
{
    const iproxy *x = self->plugin_data;
    if (!(x->ext & FP_ISO_EXT_INFO_OK)) return false;
    *info = x->info;
    return true;
}
static size_t joints_each(const fp_input *self, void (*fn)(void *ctx, int hand, const float (*mm)[3]), void *ctx)
{
    const iproxy *x = self->plugin_data;
    for (size_t i = 0; i < x->njoints; i++) fn(ctx, x->joints[i].hand, (const float (*)[3])x->joints[i].mm);
    return x->njoints;
}

static const fp_input_workspace ws_ext = {ws_get};
static const fp_input_clock clock_ext = {clock_on};
static const fp_input_recording info_ext = {info_get};
static const fp_input_recording_joints joints_ext = {joints_each};

static const void *proxy_extension(const fp_input *self, const char *id)
{
    const iproxy *x = self->plugin_data;
    if (!id) return NULL;
    if (!strcmp(id, FP_EXT_WORKSPACE) && (x->ext & FP_ISO_EXT_WORKSPACE)) return &ws_ext;
    if (!strcmp(id, FP_EXT_INPUT_CLOCK) && (x->ext & FP_ISO_EXT_CLOCK)) return &clock_ext;
    if (!strcmp(id, FP_EXT_RECORDING_INFO) && (x->ext & FP_ISO_EXT_INFO)) return &info_ext;
    if (!strcmp(id, FP_EXT_RECORDING_JOINTS) && (x->ext & FP_ISO_EXT_JOINTS)) return &joints_ext;
    return NULL;
}

/* What the helper's instance answered, copied out of the shared memory. 0 or -ENOMEM. */
static int take_extensions(iproxy *x)
{
    const fp_iso_shm *s = x->proc.shm;
    x->ext = s->in_ext;
    memcpy(x->ws_min, s->in_ws_min, sizeof x->ws_min);
    memcpy(x->ws_max, s->in_ws_max, sizeof x->ws_max);
    x->info = s->in_info;
    x->own_clock = (x->ext & (FP_ISO_EXT_INFO | FP_ISO_EXT_CLOCK)) != 0;
    size_t n = (size_t)s->in_joints;
    if (!n || s->off_joints + n * sizeof *x->joints > x->proc.mapped) return 0;
    if (!(x->joints = malloc(n * sizeof *x->joints))) return -ENOMEM;
    memcpy(x->joints, (const char *)s + s->off_joints, n * sizeof *x->joints);
    x->njoints = n;
    return 0;
}

int fp_isolate_input_create(const fp_isolate_options *opt, const char *file, const char *name,
                            const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                            fp_input **out, char *err, size_t errlen)
{
    *out = NULL;
    if (arg && strlen(arg) >= sizeof ((iproxy *)0)->arg)
        return fp_errorf(err, errlen, -EINVAL, "its ARG is over %zu bytes", sizeof ((iproxy *)0)->arg - 1);
    int rc;
    int fd = fp_iso_open_plugin_file(file, &rc, err, errlen);
    if (fd < 0) return rc;
    iproxy *x = calloc(1, sizeof *x);
    if (!x || fp_iso_copy_keys(&x->keys, params, nparams)) {
        if (x) fp_spec_clear(&x->keys);
        free(x);
        close(fd);
        return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    fp_iso_proc_init(&x->proc);
    pthread_mutex_init(&x->lock, NULL);
    x->in.size = sizeof x->in;
    x->in.plugin_data = x;
    x->in.start = proxy_start;
    x->in.stop = proxy_stop;
    x->in.destroy = proxy_destroy;
    x->in.get_extension = proxy_extension;
    x->file_fd = fd;
    x->host = host;
    x->has_arg = arg != NULL;
    snprintf(x->arg, sizeof x->arg, "%s", arg ? arg : "");
    snprintf(x->exe, sizeof x->exe, "%s", opt && opt->helper ? opt->helper : "/proc/self/exe");
    snprintf(x->file, sizeof x->file, "%s", file);
    snprintf(x->name, sizeof x->name, "%s", name);
    rc = spawn(x, false);
    if (rc) {
        proxy_destroy(&x->in);
        return fp_errorf(err, errlen, -EIO, "cannot start its helper process %s: %s",
                         opt && opt->helper ? opt->helper : "/proc/self/exe", strerror(-rc));
    }
    if ((rc = wait_created(x, err, errlen)) || (rc = take_extensions(x))) {
        if (rc == -ENOMEM) snprintf(err, errlen, "out of memory");
        proxy_destroy(&x->in);
        return rc;
    }
    *out = &x->in;
    return 0;
}

bool fp_isolate_input_stats(const fp_input *in, fp_isolate_stats *out)
{
    if (!in || in->start != proxy_start) return false;
    iproxy *x = in->plugin_data;
    memset(out, 0, sizeof *out);
    out->faults = atomic_load(&x->faults);
    out->restarts = atomic_load(&x->restarts);
    out->gave_up = atomic_load(&x->gave_up);
    return true;
}
