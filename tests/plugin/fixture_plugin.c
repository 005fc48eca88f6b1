/* Test fixtures: plugins that are broken in one way each, selected at compile time.
 *   FIXTURE_ABI_MAJOR   entry built against another ABI major
 *   FIXTURE_NO_ENTRY    no facepuppet_plugin_entry symbol at all
 *   FIXTURE_INIT_FAILS  init returns false
 *   FIXTURE_CRASH_INIT  init dereferences a null pointer
 *   FIXTURE_HANG_INIT   init never returns
 *   FIXTURE_CRASH_THREAD start() runs a thread of its own that dereferences a null pointer
 *   FIXTURE_BAD_EVENTS  start() pushes a right hand's joint positions 600 times, each stamped when pushed
 *                       (a hand held still 40 mm in front of the tracker's origin), with
 *                       malformed events among them: joint positions with a NaN, one
 *                       beyond 10 m, an unknown type, a joint positions event of a wrong
 *                       size, a wrist pose whose rotation is not a unit quaternion, a
 *                       pose event without a hand; then the end of the stream
 *   FIXTURE_GOOD        a working input that pushes FIXTURE_EVENTS events then ends;
 *                       key open_ms=N: its create takes N ms (a slow device's open: the
 *                       viewer's opening screen is read while it waits); key log=N:
 *                       create logs "created", start runs a thread of its own that logs
 *                       "line 0" .. "line N-1" (warnings) and ends (joined by stop);
 *                       key nostart=1: its instance has no start() (NULL); key
 *                       errfill=1: create fills err to its very end (no NUL) and fails;
 *                       key stuck=1: start runs a thread that never ends (a read loop
 *                       blocked for good), which stop joins: stop never returns;
 *                       stuck=2: the same thread also pushes a status event and logs a
 *                       line every 50 ms (a read that woke up after its input was abandoned);
 *                       key oversize=N: start first pushes N joint angles events whose
 *                       header.size is 64 bytes over sizeof(fp_event) (a plugin built
 *                       with a larger event), each once, logging "oversize push returned
 *                       false" where push_event says the queue is full; with
 *                       oversize_retry=1 it pushes each again while push_event says so,
 *                       as a pacer waiting for room does (fp_pacer_push);
 *                       key zeroed=N: start first pushes N events whose header is all
 *                       zeros (size 0, type 0: a memset event whose header was never set) */
#define _POSIX_C_SOURCE 200809L /* nanosleep */
#include <facepuppet/plugin.h>

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef FIXTURE_NO_ENTRY
#if defined(FIXTURE_CRASH_INIT) || defined(FIXTURE_CRASH_THREAD)
static void crash(void)
{
    /* a store to an unmapped address in this plugin's code (not NULL: UBSan, in sanitizer
     * builds, would stop a NULL store before it faults) */
    volatile int *volatile nowhere = (int *)16;
    *nowhere = 1;
}
#endif
#include <pthread.h>
#ifdef FIXTURE_CRASH_THREAD
#include <unistd.h>
static void *crashing_thread(void *arg)
{
    (void)arg;
    crash();
    return NULL;
}
#endif
typedef struct fixture {
    fp_input in; /* first: the fp_input the host sees */
    const fp_host *host;
    int log_lines;
    pthread_t logger;
    int logging;
    int stuck;
    int oversize, oversize_retry, zeroed;
} fixture;

static void *stuck_thread(void *arg)
{
    fixture *fx = arg;
    for (;;) {
        struct timespec ts = {fx->stuck == 2 ? 0 : 1, fx->stuck == 2 ? 50000000L : 0};
        nanosleep(&ts, NULL);
        if (fx->stuck != 2) continue;
        fp_event_status st = {{sizeof st, FP_EVENT_STATUS, 0, fx->host->now_ns(fx->host), 0, -1},
                              FP_STATUS_CONNECTED, "woke"};
        fx->host->push_event(fx->host, &st.header);
        fx->host->log(fx->host, FP_LOG_WARNING, "woke");
    }
    return NULL;
}

static void *logger(void *arg)
{
    fixture *f = arg;
    char line[32];
    for (int i = 0; i < f->log_lines; i++) {
        snprintf(line, sizeof line, "line %d", i);
        f->host->log(f->host, FP_LOG_WARNING, line);
    }
    return NULL;
}

static int start(fp_input *self, char *err, size_t errlen)
{
#ifdef FIXTURE_CRASH_THREAD
    pthread_t t;
    pthread_create(&t, NULL, crashing_thread, NULL);
    pthread_join(t, NULL);
#endif
    fixture *fx = (fixture *)self;
    const fp_host *host = fx->host;
    if (fx->log_lines > 0) fx->logging = !pthread_create(&fx->logger, NULL, logger, fx);
    else if (fx->stuck) fx->logging = !pthread_create(&fx->logger, NULL, stuck_thread, fx);
    for (int i = 0; i < fx->zeroed; i++) {
        fp_event zero;
        memset(&zero, 0, sizeof zero);
        host->push_event(host, &zero.header);
    }
    for (int i = 0; i < fx->oversize; i++) {
        union {
            fp_event_joint_angles ja;
            unsigned char bytes[sizeof(fp_event) + 64];
        } big;
        memset(&big, 0, sizeof big);
        big.ja.header = (fp_event_header){sizeof big, FP_EVENT_JOINT_ANGLES, 0, host->now_ns(host), 0, 1};
        while (!host->push_event(host, &big.ja.header)) {
            host->log(host, FP_LOG_WARNING, "oversize push returned false");
            if (!fx->oversize_retry) break;
            struct timespec ts = {0, 1000000};
            nanosleep(&ts, NULL);
        }
    }
#ifdef FIXTURE_BAD_EVENTS
    for (int k = 0; k < 600; k++) {
        /* stamped when pushed: 10 ms apart ahead of the clock would be up to 6 s in the
         * future, itself refused (fp_event_check_time) */
        const int64_t tk = host->now_ns(host);
        fp_event_joint_positions jp = {{sizeof jp, FP_EVENT_JOINT_POSITIONS, 0, tk, 0, 1}, {{0}}};
        for (int j = 0; j < FP_HAND_JOINTS; j++) {
            jp.mm[j][0] = 10.0f * (float)(j % 5);
            jp.mm[j][1] = 150.0f + 8.0f * (float)(j / 5);
            jp.mm[j][2] = 40.0f;
        }
        switch (k % 100) {
        case 10: jp.mm[7][1] = NAN; break;
        case 20: jp.mm[3][2] = 1e38f; break;
        case 30: jp.header.type = 99; break;
        case 40: jp.header.size = sizeof jp - 12; break;
        case 50: {
            fp_event_wrist_pose w = {{sizeof w, FP_EVENT_WRIST_POSE, 0, tk, 0, 1},
                                     {0, 150, 40}, {2, 0, 0, 0}};
            host->push_event(host, &w.header);
            continue;
        }
        case 60: jp.header.hand = -1; break;
        }
        while (!host->push_event(host, &jp.header)) {
            struct timespec ts = {0, 1000000};
            nanosleep(&ts, NULL);
        }
    }
#endif
    for (int i = 0; i < 3; i++) {
        fp_event_button b = {{sizeof b, FP_EVENT_BUTTON, 0, host->now_ns(host), 0, -1},
                             FP_BUTTON_LEFT, (uint32_t)(i % 2 == 0), (uint32_t)(i % 2 == 0)};
        host->push_event(host, &b.header);
    }
    fp_event_status st = {{sizeof st, FP_EVENT_STATUS, 0, host->now_ns(host), 0, -1},
                          FP_STATUS_END_OF_STREAM, "done"};
    host->push_event(host, &st.header);
    return 0;
}
static void stop(fp_input *self)
{
    fixture *fx = (fixture *)self;
    if (fx->logging) pthread_join(fx->logger, NULL);
    fx->logging = 0;
}
static void destroy(fp_input *self) { free(self); }

static int create(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                  fp_input **out, char *err, size_t errlen)
{
    int log_lines = 0, stuck = 0, nostart = 0, oversize = 0, oversize_retry = 0, zeroed = 0;
    for (size_t i = 0; i < nparams; i++) {
        if (!strcmp(params[i].key, "open_ms")) {
            long ms = strtol(params[i].value, NULL, 10);
            struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
            while (ms > 0 && nanosleep(&ts, &ts)) {
            }
        } else if (!strcmp(params[i].key, "log")) {
            log_lines = atoi(params[i].value);
        } else if (!strcmp(params[i].key, "stuck")) {
            stuck = atoi(params[i].value);
        } else if (!strcmp(params[i].key, "errfill")) {
            memset(err, 'E', errlen);
            return -22;
        } else if (!strcmp(params[i].key, "oversize")) {
            oversize = atoi(params[i].value);
        } else if (!strcmp(params[i].key, "zeroed")) {
            zeroed = atoi(params[i].value);
        } else if (!strcmp(params[i].key, "oversize_retry")) {
            oversize_retry = atoi(params[i].value);
        } else if (!strcmp(params[i].key, "nostart")) {
            nostart = atoi(params[i].value);
        } else if (strcmp(params[i].key, "ok")) {
            strncpy(err, "unknown key", errlen);
            return -22;
        }
    }
    fixture *fx = calloc(1, sizeof *fx);
    fx->host = host;
    fx->log_lines = log_lines;
    fx->stuck = stuck;
    fx->oversize = oversize;
    fx->oversize_retry = oversize_retry;
    fx->zeroed = zeroed;
    if (log_lines > 0) host->log(host, FP_LOG_INFO, "created");
    fp_input *in = &fx->in;
    in->size = sizeof *in;
    in->plugin_data = (void *)host;
    in->start = nostart ? NULL : start;
    in->stop = stop;
    in->destroy = destroy;
    *out = in;
    return 0;
}

/* Built as an ABI 1.0 plugin: its factory ends before the 1.1 field `params`. */
static const fp_input_factory factory = {.size = offsetof(fp_input_factory, params),
                                         .name = "fixture", .description = "test fixture",
                                         .usage = "", .create = create};
static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_INPUT_FACTORY_ID) ? &factory : NULL;
}
#ifdef FIXTURE_INIT_FAILS
static bool init(const char *path) { (void)path; return false; }
#elif defined(FIXTURE_CRASH_INIT)
static bool init(const char *path) { (void)path; crash(); return true; }
#elif defined(FIXTURE_HANG_INIT)
static bool init(const char *path)
{
    (void)path;
    for (;;) {
        struct timespec ts = {1, 0};
        nanosleep(&ts, NULL);
    }
    return true;
}
#else
static bool init(const char *path) { (void)path; return true; }
#endif
#ifdef FIXTURE_ABI_MAJOR
#define MAJOR FIXTURE_ABI_MAJOR
#else
#define MAJOR FP_PLUGIN_ABI_MAJOR
#endif
FP_PLUGIN_DECLARE_ENTRY = {{MAJOR, 0}, "org.facepuppet.test-fixture", "0", init, NULL, get_factory};
#else
FP_PLUGIN_EXPORT int not_a_facepuppet_plugin = 1;
#endif
