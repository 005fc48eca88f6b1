/*
 * input_take.c: the input-take plugin, `--input take:FILE`: performs a take again. Pushes
 * the take's raw input events (every input's, in the order the session drained them) and the
 * performer's key requests, paced by the events' times, so that a new session runs them
 * through any mapping, rig or radius (and records a new take).
 *
 * source=N (1-based, as the session's messages number inputs): only the events the take's
 * input N pushed (recorded with header.source N-1), so that a take of several inputs is
 * performed again by one instance for each of them, each with its performer= and its own
 * filter and clock (the CLI splits a `take:FILE` of two or more inputs so:
 * ui/cli/app_util.c). The key requests
 * are pushed by the instance without source= or with source=1 only, so that several
 * instances do not request twice. N beyond the take's inputs: create() fails (-EINVAL)
 * naming the file and its input count.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Flow: create() opens the take (core/take's reader; a take cut short plays its intact
 * frames, with a warning) and gathers the items to push; start() launches one pthread that
 * waits for each item's moment (a timed wait over CLOCK_MONOTONIC, so stop() wakes it) and
 * pushes it; stop() sets a flag, signals and joins.
 *
 * Times: an item's time is its offset from the take's first event (of any source, so that
 * the instances of several source= keep in step), on the host clock from the start
 * (host_t0 + offset), whatever the speed: as input-replay does, so that a run stepping on
 * the inputs' clock sees the same events in the same frames. speed=X and fast=1 only change
 * the pacing. A full queue is retried, never dropped.
 *
 * Key requests: the intents the performer asked for by key (the frame's requested bits that
 * no pedal button of that frame explains) are pushed as an FP_BUTTON_REQUEST button event
 * (plugin.h) at the frame's time, after the frame's events; the pedal's own button events
 * are in the raw events and bind as before. The take's end-of-stream statuses are left out;
 * the plugin ends with its own.
 *
 * Not performed again: rig channels the performer set by key or the host's API (jaw.open by
 * J/K). The take holds them (docs/take-format.md 1.1: each frame's channels as posed), and
 * `play` applies them, but an input can only push events; the new session's own keys and
 * mapping set its channels.
 */
#define _GNU_SOURCE
#include "fp_take.h"

#include <facepuppet/plugin.h>
#include <facepuppet/plugin_util.h>
#include "fp_pacer.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>


typedef struct take_item {
    int64_t t_ns;        /* offset from the take's first event (or frame) */
    fp_event event;
} take_item;

typedef struct take_input {
    fp_input input;
    const fp_host *host;
    char *path;
    take_item *items;
    size_t count;
    uint64_t frames;
    uint32_t hands;
    int64_t duration_ns;
    double rate_hz;
    double speed;
    bool fast;
    uint32_t source;         /* source=N: only the take's input N's events; 0: every input's */
    char warning[512];

    fp_pacer pacer;          /* the thread, waits stop() interrupts, lossless pushes (fp_pacer.h) */
} take_input;

static const char usage_text[] =
    "take:FILE[,speed=X][,fast=1][,source=N]\n"
    "  Performs a take (FILE.fptake, docs/take-format.md) again: its raw input events and the\n"
    "  performer's key requests, at the recorded pace, through this session's mapping, rig\n"
    "  and radius. Pedal buttons come back as buttons; key requests as FP_BUTTON_REQUEST.\n"
    "  speed=X  play X times as fast (0.001 to 1e6, default 1)\n"
    "  fast=1   as fast as possible\n"
    "  source=N only the events of the take's input N (1 to its input count), and the key\n"
    "           requests only with 1; default: every input's. `run` and `live` perform a\n"
    "           take of two or more inputs as one take input for each of them (source=N,\n"
    "           the recorded performer= and calibration=): each keeps its hands and state\n"
    "  Event times are the take's own clock (the host clock at start + the event's offset in\n"
    "  the take), whatever the speed. A take cut short plays its intact frames (a warning\n"
    "  status first). Ends with an end-of-stream status.\n";

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static void *take_thread(void *arg)
{
    take_input *r = arg;
    const int64_t host_t0 = r->host->now_ns(r->host);
    const int64_t mono_t0 = fp_pacer_now_ns();
    int64_t last = host_t0;
    if (r->warning[0] && !fp_pacer_push_status(&r->pacer, host_t0, FP_STATUS_WARNING, "%.*s", 100, r->warning))
        return NULL;
    for (size_t i = 0; i < r->count; i++) {
        const take_item *it = &r->items[i];
        if (r->fast) {
            if (fp_pacer_stopped(&r->pacer)) return NULL;
        } else {
            int64_t off = r->speed == 1.0 ? it->t_ns : (int64_t)llround((double)it->t_ns / r->speed);
            if (!fp_pacer_wait_until(&r->pacer, mono_t0 + off)) return NULL;
        }
        fp_event ev = it->event;
        ev.header.time_ns = last = host_t0 + it->t_ns;
        if (!fp_pacer_push(&r->pacer, &ev)) return NULL;
    }
    fp_pacer_push_status(&r->pacer, last, FP_STATUS_END_OF_STREAM, "end of %s", base_name(r->path));
    return NULL;
}

static int take_start(fp_input *self, char *err, size_t errlen)
{
    take_input *r = self->plugin_data;
    return fp_pacer_start(&r->pacer, take_thread, r, "take", err, errlen);
}

static void take_stop(fp_input *self)
{
    fp_pacer_stop(&((take_input *)self->plugin_data)->pacer);
}

static void take_destroy(fp_input *self)
{
    if (!self) return;
    take_input *r = self->plugin_data;
    fp_pacer_destroy(&r->pacer); /* (stops the thread first) */
    free(r->items);
    free(r->path);
    free(r);
}

/* ---- extensions: what the take holds -------------------------------------------------- */

static bool take_recording_info(const fp_input *self, fp_recording_info *info)
{
    const take_input *r = self->plugin_data;
    memset(info, 0, sizeof *info);
    info->frames = r->frames;
    info->hands = r->hands;
    info->rate_hz = r->rate_hz;
    info->duration_s = (double)r->duration_ns * 1e-9;
    snprintf(info->format, sizeof info->format, "take");
    return true;
}

static const fp_input_recording recording_ext = {.get = take_recording_info};

static const void *take_get_extension(const fp_input *self, const char *id)
{
    (void)self;
    if (!strcmp(id, FP_EXT_RECORDING_INFO)) return &recording_ext;
    return NULL;
}

/* ---- loading ------------------------------------------------------------------------- */

static int add_item(take_input *r, size_t *cap, int64_t t, const fp_event *ev)
{
    if (r->count == *cap) {
        size_t c = *cap ? 2 * *cap : 1024;
        take_item *x = realloc(r->items, c * sizeof *x);
        if (!x) return -ENOMEM;
        r->items = x;
        *cap = c;
    }
    r->items[r->count].t_ns = t;
    r->items[r->count].event = *ev;
    r->count++;
    return 0;
}

/* The key requests of a frame: its requested intent bits less those its pedal buttons (or
 * earlier request events) explain. */
static uint32_t key_requests(const fp_take_frame *f)
{
    const uint32_t intents = FP_INTENT_ENGAGE | FP_INTENT_COMMIT | FP_INTENT_CANCEL;
    uint32_t explained = 0;
    for (size_t i = 0; i < f->event_count; i++) {
        const fp_event *e = &f->events[i];
        if (e->header.type != FP_EVENT_BUTTON || !e->button.down) continue;
        if (e->button.button == FP_BUTTON_LEFT) explained |= FP_INTENT_ENGAGE | FP_INTENT_COMMIT;
        else if (e->button.button == FP_BUTTON_RIGHT) explained |= FP_INTENT_CANCEL;
        else if (e->button.button == FP_BUTTON_REQUEST) explained |= e->button.mask;
    }
    return f->requested & intents & ~explained;
}

static int load(take_input *r, const char *path, char *err, size_t errlen)
{
    fp_take_reader *rd = NULL;
    int rc = fp_take_reader_open(path, &rd, err, errlen);
    if (rc) return rc;
    snprintf(r->warning, sizeof r->warning, "%s", fp_take_reader_warning(rd));
    const fp_take_header *h = fp_take_reader_header(rd);
    if (r->source > h->input_count) {
        snprintf(err, errlen, "take: %s: source=%u: the take has %zu input%s (source=1 to %zu)", path,
                 r->source, h->input_count, h->input_count == 1 ? "" : "s", h->input_count);
        fp_take_reader_close(&rd);
        return -EINVAL;
    }
    r->rate_hz = h->rate.den ? (double)h->rate.num / h->rate.den : 0;
    size_t cap = 0;
    bool have_t0 = false;
    int64_t t0 = 0, last_frame_t = 0;
    fp_take_frame f;
    while ((rc = fp_take_reader_next(rd, &f, err, errlen)) == 1) {
        r->frames++;
        if (!have_t0) {
            t0 = f.event_count ? f.events[0].header.time_ns : f.time_ns;
            for (size_t i = 0; i < f.event_count; i++)
                if (f.events[i].header.time_ns < t0) t0 = f.events[i].header.time_ns;
            have_t0 = true;
        }
        int64_t prev = r->count ? r->items[r->count - 1].t_ns : 0;
        int mem = 0;
        for (size_t i = 0; i < f.event_count && !mem; i++) {
            const fp_event *e = &f.events[i];
            if (e->header.type == FP_EVENT_STATUS && e->status.code == FP_STATUS_END_OF_STREAM)
                continue;
            if (r->source && e->header.source != r->source - 1) continue; /* another input's */
            if (e->header.hand == FP_HAND_LEFT || e->header.hand == FP_HAND_RIGHT)
                r->hands |= 1u << e->header.hand;
            int64_t t = e->header.time_ns - t0;
            if (t < prev) t = prev;   /* keep the order the session drained them in */
            prev = t;
            mem = add_item(r, &cap, t, e);
        }
        uint32_t keys = r->source <= 1 ? key_requests(&f) : 0;
        if (keys && !mem) {
            fp_event ev;
            memset(&ev, 0, sizeof ev);
            ev.button.header = (fp_event_header){.size = sizeof ev.button, .type = FP_EVENT_BUTTON,
                                                 .hand = -1};
            ev.button.button = FP_BUTTON_REQUEST;
            ev.button.down = 1;
            ev.button.mask = keys;
            int64_t t = f.time_ns - t0;
            mem = add_item(r, &cap, t < prev ? prev : t, &ev);
        }
        if (mem) {
            fp_take_reader_close(&rd);
            snprintf(err, errlen, "take: %s: out of memory", path);
            return -ENOMEM;
        }
        last_frame_t = f.time_ns - t0;
    }
    fp_take_reader_close(&rd);
    if (rc < 0) return rc;
    r->duration_ns = last_frame_t;
    return 0;
}

static int parse_bool(const char *key, const char *v, bool *out, char *err, size_t errlen)
{
    const int b = fp_parse_bool(v); /* (plugin_util.h: 1/true/yes/on, 0/false/no/off) */
    if (b < 0) {
        snprintf(err, errlen, "take: %s=%s: expected 0 or 1", key, v);
        return -EINVAL;
    }
    *out = b == 1;
    return 0;
}

static int take_create(const fp_host *host, const char *arg, const fp_param *params,
                       size_t nparams, fp_input **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!host || !host->push_event || !host->now_ns) {
        snprintf(err, errlen, "take: the host lacks push_event or now_ns");
        return -EINVAL;
    }
    if (!arg || !*arg) {
        snprintf(err, errlen, "take: no FILE given (take:FILE.fptake[,speed=X][,fast=1][,source=N])");
        return -EINVAL;
    }
    double speed = 1.0;
    bool fast = false;
    unsigned long long source = 0;
    for (size_t i = 0; i < nparams; i++) {
        const char *k = params[i].key ? params[i].key : "", *v = params[i].value ? params[i].value : "";
        if (!strcmp(k, "speed")) {
            if (!fp_pacer_parse_speed(v, &speed)) {
                snprintf(err, errlen, "take: speed=%s: expected a number from 0.001 to 1e6", v);
                return -EINVAL;
            }
        } else if (!strcmp(k, "fast")) {
            if (parse_bool(k, v, &fast, err, errlen)) return -EINVAL;
        } else if (!strcmp(k, "source")) {
            if (!fp_parse_whole(v, FP_TAKE_MAX_INPUTS, &source) || !source) {
                snprintf(err, errlen, "take: source=%s: expected an input of the take, 1 to %d", v,
                         FP_TAKE_MAX_INPUTS);
                return -EINVAL;
            }
        } else {
            snprintf(err, errlen, "take: unknown key \"%s\" (known: speed, fast, source)", k);
            return -EINVAL;
        }
    }
    take_input *r = calloc(1, sizeof *r);
    if (!r || !(r->path = strdup(arg))) {
        free(r);
        snprintf(err, errlen, "take: out of memory");
        return -ENOMEM;
    }
    r->source = (uint32_t)source;
    int rc = load(r, arg, err, errlen);
    if (rc) {
        free(r->items);
        free(r->path);
        free(r);
        return rc;
    }
    if ((rc = fp_pacer_init(&r->pacer, host))) {
        free(r->items);
        free(r->path);
        free(r);
        snprintf(err, errlen, "take: cannot set up its thread's clock: %s", strerror(-rc));
        return rc;
    }
    r->host = host;
    r->speed = speed;
    r->fast = fast;
    r->input = (fp_input){.size = sizeof(fp_input), .plugin_data = r, .start = take_start,
                          .stop = take_stop, .destroy = take_destroy,
                          .get_extension = take_get_extension};
    if (r->warning[0] && host->log) host->log(host, FP_LOG_WARNING, r->warning);
    *out = &r->input;
    return 0;
}

/* The keys, typed (ABI 1.1), for `facepuppet plugins` and `plugins check`; take_create
 * parses them itself (the same ranges). */
static const fp_param_info take_keys[] = {
    {.name = "speed", .type = FP_PARAM_FLOAT, .min = 1e-3, .max = 1e6, .default_value = "1",
     .unit = "x", .description = "play this many times as fast (0.001 to 1e6)"},
    {.name = "fast", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "as fast as possible, retrying when the queue is full"},
    {.name = "source", .type = FP_PARAM_INT, .min = 1, .max = FP_TAKE_MAX_INPUTS, .default_value = "",
     .description = "only the take's input N's events (key requests: with 1 only); default every input's"},
    {.name = NULL},
};

static const fp_input_factory take_factory = {
    .size = sizeof(fp_input_factory),
    .name = "take",
    .description = "performs a take again: its raw input events and key requests",
    .usage = usage_text,
    .create = take_create,
    .params = take_keys,
};

static const void *take_get_factory(const char *factory_id)
{
    if (factory_id && !strcmp(factory_id, FP_INPUT_FACTORY_ID)) return &take_factory;
    return NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-take",
    .version = "1.0.0",
    .get_factory = take_get_factory,
};
