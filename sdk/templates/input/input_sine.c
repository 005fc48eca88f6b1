/*
 * input-sine: a complete facepuppet input plugin, a template to copy.
 *
 * A synthetic glove: one hand whose fingers curl and open on a sine wave, pushed as joint
 * angles (what a CyberGlove gives) from a thread the plugin owns, at `rate` Hz for
 * `duration` seconds (0: until stopped), then an end-of-stream status so `facepuppet run`
 * finishes. A real device plugin has the same shape: create parses keys and opens nothing
 * slow; start opens the device and starts the thread; the thread pushes events through
 * host->push_event (lock-free, never blocks); stop joins the thread.
 *
 * SPDX-License-Identifier: CC0-1.0 (copy it freely)
 */
#define _POSIX_C_SOURCE 200809L
#include <facepuppet/mapping_util.h> /* fpmu_params_parse: keys from a typed table */
#include <facepuppet/plugin.h>

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct sine {
    fp_input input;
    const fp_host *host;
    int hand;
    double rate_hz, period_s, duration_s;
    pthread_t thread;
    bool running;
    atomic_bool stop;
} sine;

static void push_status(sine *s, uint32_t code, const char *text)
{
    fp_event_status st;
    memset(&st, 0, sizeof st);
    st.header.size = sizeof st;
    st.header.type = FP_EVENT_STATUS;
    st.header.time_ns = s->host->now_ns(s->host);
    st.header.hand = -1;
    st.code = code;
    strncpy(st.text, text, sizeof st.text - 1);
    s->host->push_event(s->host, &st.header);
}

/* [input-thread]: the plugin's own thread. */
static void *run(void *arg)
{
    sine *s = arg;
    push_status(s, FP_STATUS_CONNECTED, "sine: streaming");
    int64_t t0 = s->host->now_ns(s->host);
    int64_t step = (int64_t)(1e9 / s->rate_hz);
    for (int64_t k = 0; !atomic_load(&s->stop); k++) {
        int64_t t = t0 + k * step;
        double secs = (double)(t - t0) / 1e9;
        if (s->duration_s > 0 && secs > s->duration_s) break;
        fp_event_joint_angles ev;
        memset(&ev, 0, sizeof ev);
        ev.header.size = sizeof ev;
        ev.header.type = FP_EVENT_JOINT_ANGLES;
        ev.header.time_ns = t;
        ev.header.hand = s->hand;
        double curl = 0.5 * (1 - cos(2 * 3.14159265358979 * secs / s->period_s)); /* 0 open .. 1 fist */
        static const int flex[] = {FP_SENSOR_INDEX_MPJ, FP_SENSOR_INDEX_PIJ, FP_SENSOR_MIDDLE_MPJ,
                                   FP_SENSOR_MIDDLE_PIJ, FP_SENSOR_RING_MPJ, FP_SENSOR_RING_PIJ,
                                   FP_SENSOR_PINKIE_MPJ, FP_SENSOR_PINKIE_PIJ, FP_SENSOR_THUMB_MPJ};
        for (size_t i = 0; i < sizeof flex / sizeof flex[0]; i++) {
            ev.radians[flex[i]] = (float)(curl * 1.4);
            ev.valid |= 1u << flex[i];
        }
        s->host->push_event(s->host, &ev.header); /* a full queue drops it: fine for poses */
        struct timespec ts = {0, (long)step};
        nanosleep(&ts, NULL); /* a device would block on its port instead */
    }
    push_status(s, FP_STATUS_END_OF_STREAM, "sine: done");
    return NULL;
}

static int start(fp_input *self, char *err, size_t errlen)
{
    sine *s = self->plugin_data;
    atomic_store(&s->stop, false);
    if (pthread_create(&s->thread, NULL, run, s)) {
        strncpy(err, "sine: cannot start a thread", errlen);
        return -EAGAIN;
    }
    s->running = true;
    return 0;
}

static void stop(fp_input *self)
{
    sine *s = self->plugin_data;
    if (!s->running) return;
    atomic_store(&s->stop, true);
    pthread_join(s->thread, NULL);
    s->running = false;
}

static void destroy(fp_input *self) { free(self->plugin_data); }

enum { KEY_HAND, KEY_RATE, KEY_PERIOD, KEY_DURATION, KEY_COUNT };
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hand", .type = FP_PARAM_ENUM, .default_value = "right", .choices = "left|right",
     .description = "which hand the glove is"},
    {.name = "rate", .type = FP_PARAM_FLOAT, .min = 1, .max = 1000, .default_value = "60",
     .unit = "Hz", .description = "samples per second"},
    {.name = "period", .type = FP_PARAM_FLOAT, .min = 0.05, .max = 60, .default_value = "2",
     .unit = "s", .description = "one curl and release"},
    {.name = "duration", .type = FP_PARAM_FLOAT, .min = 0, .max = 86400, .default_value = "4",
     .unit = "s", .description = "then end of stream (0: never)"},
    {.name = NULL},
};

/* [main-thread] */
static int create(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                  fp_input **out, char *err, size_t errlen)
{
    if (arg) {
        strncpy(err, "sine: takes no ':ARG'", errlen);
        return -EINVAL;
    }
    fpmu_value v[KEY_COUNT];
    int rc = fpmu_params_parse("sine", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    sine *s = calloc(1, sizeof *s);
    if (!s) return -ENOMEM;
    s->host = host;
    s->hand = v[KEY_HAND].number == 0 ? FP_HAND_LEFT : FP_HAND_RIGHT;
    s->rate_hz = v[KEY_RATE].number;
    s->period_s = v[KEY_PERIOD].number;
    s->duration_s = v[KEY_DURATION].number;
    s->input.size = sizeof s->input;
    s->input.plugin_data = s;
    s->input.start = start;
    s->input.stop = stop;
    s->input.destroy = destroy;
    *out = &s->input;
    return 0;
}

static const fp_input_factory factory = {
    .size = sizeof(fp_input_factory),
    .name = "sine",
    .description = "template: a synthetic glove whose fingers curl on a sine wave",
    .usage = "sine[,hand=left|right][,rate=HZ][,period=S][,duration=S]",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_INPUT_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.example.input-sine",
    .version = "1.0",
    .get_factory = get_factory,
};
