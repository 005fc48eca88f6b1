/* input-crashy: a third-party input that faults on a thread of its own, for the isolated
 * inputs' tests (fp_isolate.h, tests/plugin/test_isolate_input.sh). start() runs a thread
 * that pushes `events=N` (default 20) right-hand joint positions, `period_ms=MS` (default
 * 10) apart, each stamped when pushed, and then, by `mode=`: segv (default: a store to an
 * unmapped address), abort, exit (exit status 3), hang (spins for good, pushing nothing), or
 * end (an FP_STATUS_END_OF_STREAM: a healthy input). stop() joins the thread, except a hang's
 * (then it never returns). */
#define _POSIX_C_SOURCE 200809L
#include <facepuppet/plugin.h>

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef struct crashy {
    fp_input in; /* first: the fp_input the host sees */
    const fp_host *host;
    int events, period_ms;
    char mode[16];
    pthread_t thread;
    int running;
} crashy;

static void *run(void *arg)
{
    crashy *c = arg;
    const fp_host *host = c->host;
    for (int k = 0; k < c->events; k++) {
        fp_event_joint_positions jp;
        memset(&jp, 0, sizeof jp);
        jp.header = (fp_event_header){sizeof jp, FP_EVENT_JOINT_POSITIONS, 0, host->now_ns(host), 0, FP_HAND_RIGHT};
        for (int j = 0; j < FP_HAND_JOINTS; j++) {
            jp.mm[j][0] = 10.0f * (float)(j % 5) + 0.5f * (float)k;
            jp.mm[j][1] = 150.0f + 8.0f * (float)(j / 5);
            jp.mm[j][2] = 40.0f;
        }
        while (!host->push_event(host, &jp.header)) {
            struct timespec ts = {0, 1000000};
            nanosleep(&ts, NULL);
        }
        struct timespec ts = {c->period_ms / 1000, (c->period_ms % 1000) * 1000000L};
        nanosleep(&ts, NULL);
    }
    if (!strcmp(c->mode, "segv")) {
        volatile int *volatile nowhere = (int *)16; /* (not NULL: UBSan would stop that first) */
        *nowhere = 1;
    } else if (!strcmp(c->mode, "abort")) {
        abort();
    } else if (!strcmp(c->mode, "exit")) {
        _exit(3);
    } else if (!strcmp(c->mode, "hang")) {
        for (volatile unsigned long i = 0;; i++) {
        }
    }
    fp_event_status st;
    memset(&st, 0, sizeof st);
    st.header = (fp_event_header){sizeof st, FP_EVENT_STATUS, 0, host->now_ns(host), 0, -1};
    st.code = FP_STATUS_END_OF_STREAM;
    host->push_event(host, &st.header);
    return NULL;
}

static int start(fp_input *self, char *err, size_t errlen)
{
    crashy *c = (crashy *)self;
    if (pthread_create(&c->thread, NULL, run, c)) {
        strncpy(err, "cannot start its thread", errlen);
        return -11;
    }
    c->running = 1;
    return 0;
}

static void stop(fp_input *self)
{
    crashy *c = (crashy *)self;
    if (c->running) pthread_join(c->thread, NULL);
    c->running = 0;
}

static void destroy(fp_input *self) { free(self); }

static int create(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                  fp_input **out, char *err, size_t errlen)
{
    (void)arg;
    crashy *c = calloc(1, sizeof *c);
    if (!c) return -12;
    c->host = host;
    c->events = 20;
    c->period_ms = 10;
    strcpy(c->mode, "segv");
    for (size_t i = 0; i < nparams; i++) {
        if (!strcmp(params[i].key, "events")) c->events = atoi(params[i].value);
        else if (!strcmp(params[i].key, "period_ms")) c->period_ms = atoi(params[i].value);
        else if (!strcmp(params[i].key, "mode") && strlen(params[i].value) < sizeof c->mode)
            strcpy(c->mode, params[i].value);
        else {
            strncpy(err, "unknown key (events=, period_ms=, mode=)", errlen);
            free(c);
            return -22;
        }
    }
    c->in.size = sizeof c->in;
    c->in.plugin_data = c;
    c->in.start = start;
    c->in.stop = stop;
    c->in.destroy = destroy;
    *out = &c->in;
    return 0;
}

static const fp_input_factory factory = {.size = sizeof factory, .name = "crashy",
                                         .description = "an input that faults on its own thread (tests)",
                                         .usage = "crashy[,events=N][,period_ms=MS][,mode=segv|abort|exit|hang|end]",
                                         .create = create};
static const void *get_factory(const char *id) { return !strcmp(id, FP_INPUT_FACTORY_ID) ? &factory : NULL; }
static bool init(const char *path) { (void)path; return true; }
FP_PLUGIN_DECLARE_ENTRY = {{FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR}, "org.facepuppet.test-crashy", "0", init, NULL,
                           get_factory};
