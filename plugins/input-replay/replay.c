/*
 * replay.c: the input-replay plugin. Replays a recorded hand (Leap CSV, Leap playback
 * original or facepuppet event log) as live input, on its own thread, at the recorded pace or
 * faster.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Flow: create() parses the SPEC and loads the whole file (replay_load.c), so that every
 * error shows before the session starts; start() launches one pthread that waits for each
 * event's moment (a timed wait on a condition variable over CLOCK_MONOTONIC, so stop() wakes
 * it at once) and pushes it; stop() sets a flag, signals and joins.
 */
#define _GNU_SOURCE
#include "replay_load.h"

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


typedef struct replay {
    fp_input input;
    const fp_host *host;
    char *path;
    replay_recording rec;
    double speed;
    bool loop, fast;
    bool workspace;          /* state the recording's range (FP_EXT_WORKSPACE); workspace=0: not */

    fp_pacer pacer;          /* the thread, waits stop() interrupts, lossless pushes (fp_pacer.h) */
} replay;

static const char usage_text[] =
    "replay:FILE[,speed=X][,loop=1][,fast=1][,hands=left|right|both][,workspace=0][,timeout=S]\n"
    "  Replays a recording as live input, at the recorded pace (timestamp_us or time_ns).\n"
    "  FILE is detected by its first bytes:\n"
    "    Leap joint-positions CSV (*_joints_mm.csv): per hand and row, joint positions in the\n"
    "      palm, thumb..pinky MCP/PIP/DIP/tip layout and a wrist pose (palm position; rotation\n"
    "      from palm normal and hand direction);\n"
    "    Leap joint-angles CSV (*_cyberglove_like_angles_deg.csv): joint angles, degrees to\n"
    "      radians, empty fields marked not valid;\n"
    "    Leap playback original (leapjs-playback's *.json.lz, LZ-string base64, or *.json;\n"
    "      its formats 0.1, 1 and the packed 2): its frames' hands read as the\n"
    "      joint-positions CSV's rows;\n"
    "    facepuppet event log (docs/eventlog.md): the events as recorded.\n"
    "  speed=X  play X times as fast (0.001 to 1e6, default 1)\n"
    "  loop=1   start over at the end; event times keep increasing (default 0)\n"
    "  fast=1   as fast as possible (a full queue is always retried, never dropped)\n"
    "  hands=H  left, right or both (default both)\n"
    "  workspace=0  keep the recording's range to itself: the hands are placed as they\n"
    "           arrive, as a live tracker's (docs/calibration.md; default 1: placed from the\n"
    "           whole recording's range in advance, and brought closer where its fingertips\n"
    "           would never come within reach of the face)\n"
    "  timeout=S  a hand missing from the recording for S seconds (the tracker lost it) is\n"
    "           reported gone then, as a live osc input does (0.01 to 3600, default 1, as\n"
    "           osc's; 0: never; not for event logs, which hold the statuses they were\n"
    "           recorded with)\n"
    "  Event times are the recording's own clock (the host clock at start + the sample's\n"
    "  time), whatever the speed; speed and fast only change the pacing. Without loop, the replay ends\n"
    "  with an end-of-stream status. A malformed row fails at creation (FILE:LINE:COLUMN; in a\n"
    "  Leap original FILE: JSON.PATH, e.g. frames[12].hands[0].palmNormal); a\n"
    "  last line without a newline is replayed when it is a whole row (a CSV's: its last number\n"
    "  with the row before's decimals); one cut short is dropped and reported with an error\n"
    "  status (the recording is damaged) after the rows before it were replayed.\n";

/* ------------------------------------------------------------------------------------- */
/* Thread                                                                                 */

/* Emulated offset, in host ns after the start, of recording time t in pass `pass`. */
static int64_t emulated_offset(const replay *r, uint64_t pass, int64_t t)
{
    double rec_ns = (double)pass * (double)r->rec.loop_period_ns + (double)t;
    if (r->speed == 1.0) return (int64_t)rec_ns;
    return (int64_t)llround(rec_ns / r->speed);
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static void *replay_thread(void *arg)
{
    replay *r = arg;
    const int64_t host_t0 = r->host->now_ns(r->host);
    const int64_t mono_t0 = fp_pacer_now_ns();
    int64_t last_time = host_t0;
    bool warned = false;
    if (!fp_pacer_push_status(&r->pacer, host_t0, FP_STATUS_CONNECTED, "replaying %s: %zu frames, %.3f s",
                     base_name(r->path), r->rec.frames, (double)r->rec.duration_ns * 1e-9))
        return NULL;
    for (uint64_t pass = 0;; pass++) {
        for (size_t i = 0; i < r->rec.count; i++) {
            const replay_item *it = &r->rec.items[i];
            int64_t off = emulated_offset(r, pass, it->t_ns);
            if (r->fast) {
                if (fp_pacer_stopped(&r->pacer)) return NULL;
            } else if (!fp_pacer_wait_until(&r->pacer, mono_t0 + off)) {
                return NULL;
            }
            fp_event ev = it->event;
            /* The time the sample was measured, on the recording's own clock (independent
             * of speed and of when it is pushed): a run steps on it deterministically. */
            ev.header.time_ns = last_time =
                host_t0 + (int64_t)pass * r->rec.loop_period_ns + it->t_ns;
            if (!fp_pacer_push(&r->pacer, &ev)) return NULL;
        }
        if (r->rec.truncated_line && !warned) {
            warned = true;
            if (!fp_pacer_push_status(&r->pacer, last_time, FP_STATUS_ERROR,
                             "%s:%ld: last line cut short (no newline), not replayed",
                             base_name(r->path), r->rec.truncated_line))
                return NULL;
        }
        if (!r->loop) break;
        /* Times keep increasing over passes: stop before the next pass's would overflow
         * (after centuries for a real recording; at once for hostile times). */
        int64_t next;
        if (__builtin_mul_overflow((int64_t)(pass + 1), r->rec.loop_period_ns, &next) ||
            __builtin_add_overflow(next, host_t0, &next) ||
            __builtin_add_overflow(next, r->rec.duration_ns, &next))
            break;
    }
    fp_pacer_push_status(&r->pacer, last_time, FP_STATUS_END_OF_STREAM, "end of %s", base_name(r->path));
    return NULL;
}

/* ------------------------------------------------------------------------------------- */
/* fp_input                                                                               */

static int replay_start(fp_input *self, char *err, size_t errlen)
{
    replay *r = self->plugin_data;
    return fp_pacer_start(&r->pacer, replay_thread, r, "replay", err, errlen);
}

static void replay_stop(fp_input *self)
{
    fp_pacer_stop(&((replay *)self->plugin_data)->pacer);
}

static void replay_destroy(fp_input *self)
{
    if (!self) return;
    replay *r = self->plugin_data;
    fp_pacer_destroy(&r->pacer); /* (stops the thread first) */
    replay_recording_free(&r->rec);
    free(r->path);
    free(r);
}

/* ------------------------------------------------------------------------------------- */
/* Factory                                                                                */

static int parse_bool(const fp_param *p, bool *out, char *err, size_t errlen)
{
    const int b = fp_parse_bool(p->value); /* (plugin_util.h: 1/true/yes/on, 0/false/no/off) */
    if (b < 0) {
        snprintf(err, errlen, "replay: %s=%s: expected 0 or 1", p->key, p->value);
        return -EINVAL;
    }
    *out = b == 1;
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* A hand the tracker lost                                                                */

static bool is_pose(const fp_event *ev)
{
    return ev->header.type == FP_EVENT_JOINT_POSITIONS || ev->header.type == FP_EVENT_JOINT_ANGLES;
}

static int cmp_loss(const void *a, const void *b)
{
    const replay_item *x = a, *y = b;
    if (x->t_ns != y->t_ns) return x->t_ns < y->t_ns ? -1 : 1;
    return x->event.header.hand - y->event.header.hand;
}

/* Inserts, for each gap of more than timeout_ns between a hand's poses and after its last
 * pose, a DISCONNECTED status for that hand timeout_ns after the pose before the gap: what an
 * osc input reports when its sender goes on without the hand, so a replayed recording lets
 * a lost hand's grab go as the same recording sent live does. The items stay in time order
 * (a loss before the poses of its moment). Returns 0 or -ENOMEM (rec unchanged). */
static int add_losses(replay_recording *rec, int64_t timeout_ns)
{
    size_t k = 0, cap = 0;
    replay_item *loss = NULL;
    int64_t last[FP_HANDS] = {-1, -1};
    for (size_t i = 0; i <= rec->count; i++) {
        const bool end = i == rec->count;
        const fp_event *ev = end ? NULL : &rec->items[i].event;
        const int hand = end || !is_pose(ev) ? -1 : ev->header.hand;
        for (int h = 0; h < FP_HANDS; h++) {
            if (last[h] < 0 || (!end && hand != h)) continue;
            const int64_t next = end ? rec->duration_ns : rec->items[i].t_ns;
            if (next - last[h] <= timeout_ns) continue;
            if (k == cap) {
                replay_item *grown = realloc(loss, (cap = cap ? 2 * cap : 8) * sizeof *grown);
                if (!grown) {
                    free(loss);
                    return -ENOMEM;
                }
                loss = grown;
            }
            replay_item *it = &loss[k++];
            memset(it, 0, sizeof *it);
            it->t_ns = last[h] + timeout_ns;
            it->event.status.header = (fp_event_header){.size = sizeof it->event.status,
                                                        .type = FP_EVENT_STATUS, .hand = h};
            it->event.status.code = FP_STATUS_DISCONNECTED;
            snprintf(it->event.status.text, sizeof it->event.status.text,
                     "%s hand: not in the recording for %.3g s from %.3f s: taken as gone",
                     h == FP_HAND_LEFT ? "left" : "right", (double)timeout_ns * 1e-9,
                     (double)last[h] * 1e-9);
        }
        if (hand == FP_HAND_LEFT || hand == FP_HAND_RIGHT) last[hand] = rec->items[i].t_ns;
    }
    if (!k) return 0;
    replay_item *all = malloc((rec->count + k) * sizeof *all);
    if (!all) {
        free(loss);
        return -ENOMEM;
    }
    qsort(loss, k, sizeof *loss, cmp_loss);
    for (size_t a = 0, b = 0, o = 0; o < rec->count + k; o++)
        all[o] = b < k && (a == rec->count || loss[b].t_ns <= rec->items[a].t_ns) ? loss[b++] : rec->items[a++];
    free(loss);
    free(rec->items);
    rec->items = all;
    rec->count += k;
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Extensions: the workspace the recording's hands move in, and what it holds             */

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The robust box: per axis the 2nd and 98th percentiles of every joint position, so that a
 * tracking glitch (a palm 3 m away for a few samples) moves nothing. */
static bool replay_workspace(const fp_input *self, float min_mm[3], float max_mm[3])
{
    const replay *r = self->plugin_data;
    size_t n = 0;
    for (size_t i = 0; i < r->rec.count; i++)
        if (r->rec.items[i].event.header.type == FP_EVENT_JOINT_POSITIONS) n += FP_HAND_JOINTS;
    if (!n) return false;
    float *v = malloc(n * sizeof *v);
    if (!v) return false;
    for (int k = 0; k < 3; k++) {
        size_t m = 0;
        for (size_t i = 0; i < r->rec.count; i++) {
            const fp_event *ev = &r->rec.items[i].event;
            if (ev->header.type != FP_EVENT_JOINT_POSITIONS) continue;
            for (int j = 0; j < FP_HAND_JOINTS; j++) v[m++] = ev->positions.mm[j][k];
        }
        qsort(v, m, sizeof *v, cmp_float);
        min_mm[k] = v[(size_t)(0.02 * (double)(m - 1) + 0.5)];
        max_mm[k] = v[(size_t)(0.98 * (double)(m - 1) + 0.5)];
    }
    free(v);
    return true;
}

static bool replay_recording_info(const fp_input *self, fp_recording_info *info)
{
    const replay *r = self->plugin_data;
    static const char *formats[] = {"", "joints-csv", "angles-csv", "eventlog", "leap-playback"};
    memset(info, 0, sizeof *info);
    uint64_t distinct = 0;
    int64_t last = -1;
    for (size_t i = 0; i < r->rec.count; i++) {
        const replay_item *it = &r->rec.items[i];
        if (it->event.header.type == FP_EVENT_STATUS) continue; /* (add_losses's) */
        if (it->t_ns != last) distinct++;
        last = it->t_ns;
        int h = it->event.header.hand;
        if (h == FP_HAND_LEFT || h == FP_HAND_RIGHT) info->hands |= 1u << h;
    }
    info->frames = distinct;
    info->duration_s = (double)r->rec.duration_ns / 1e9;
    info->rate_hz = distinct > 1 && r->rec.duration_ns > 0 ? (double)(distinct - 1) / info->duration_s : 0;
    const bool known = r->rec.format >= 1 && r->rec.format < sizeof formats / sizeof *formats;
    snprintf(info->format, sizeof info->format, "%s", known ? formats[r->rec.format] : "unknown");
    return true;
}

/* Every joint-position sample, in order (FP_EXT_RECORDING_JOINTS): the host's placement
 * looks at how near the fingertips come to the face before the first frame. */
static size_t replay_joints(const fp_input *self, void (*fn)(void *ctx, int hand, const float (*mm)[3]),
                            void *ctx)
{
    const replay *r = self->plugin_data;
    size_t n = 0;
    for (size_t i = 0; i < r->rec.count; i++) {
        const fp_event *ev = &r->rec.items[i].event;
        if (ev->header.type != FP_EVENT_JOINT_POSITIONS) continue;
        fn(ctx, ev->header.hand, (const float(*)[3])ev->positions.mm);
        n++;
    }
    return n;
}

static const fp_input_workspace workspace_ext = {.get = replay_workspace};
static const fp_input_recording recording_ext = {.get = replay_recording_info};
static const fp_input_recording_joints joints_ext = {.each = replay_joints};

static const void *replay_get_extension(const fp_input *self, const char *id)
{
    if (!strcmp(id, FP_EXT_WORKSPACE)) return ((const replay *)self->plugin_data)->workspace ? &workspace_ext : NULL;
    if (!strcmp(id, FP_EXT_RECORDING_INFO)) return &recording_ext;
    if (!strcmp(id, FP_EXT_RECORDING_JOINTS)) return ((const replay *)self->plugin_data)->workspace ? &joints_ext : NULL;
    return NULL;
}

static int replay_create(const fp_host *host, const char *arg, const fp_param *params,
                         size_t nparams, fp_input **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!host || !host->push_event || !host->now_ns) {
        snprintf(err, errlen, "replay: the host lacks push_event or now_ns");
        return -EINVAL;
    }
    if (!arg || !*arg) {
        snprintf(err, errlen, "replay: no FILE given (replay:FILE[,speed=X][,loop=1][,fast=1]"
                              "[,hands=left|right|both])");
        return -EINVAL;
    }
    double speed = 1.0;
    bool loop = false, fast = false, workspace = true;
    double timeout = 1.0;
    int hands = REPLAY_HAND_BOTH;
    for (size_t i = 0; i < nparams; i++) {
        const fp_param *p = &params[i];
        const char *v = p->value ? p->value : "";
        fp_param q = {.key = p->key ? p->key : "", .value = v};
        if (strcmp(q.key, "speed") == 0) {
            if (!fp_pacer_parse_speed(v, &speed)) {
                snprintf(err, errlen, "replay: speed=%s: expected a number from 0.001 to 1e6", v);
                return -EINVAL;
            }
        } else if (strcmp(q.key, "loop") == 0) {
            if (parse_bool(&q, &loop, err, errlen)) return -EINVAL;
        } else if (strcmp(q.key, "fast") == 0) {
            if (parse_bool(&q, &fast, err, errlen)) return -EINVAL;
        } else if (strcmp(q.key, "workspace") == 0) {
            if (parse_bool(&q, &workspace, err, errlen)) return -EINVAL;
        } else if (strcmp(q.key, "timeout") == 0) {
            if (!fp_parse_decimal(v, &timeout) || !(timeout == 0 || (timeout >= 0.01 && timeout <= 3600))) {
                snprintf(err, errlen, "replay: timeout=%s: expected 0 (never) or seconds from 0.01 to 3600 "
                         "(as osc's)", v);
                return -EINVAL;
            }
        } else if (strcmp(q.key, "hands") == 0) {
            hands = (int)fp_parse_hands(v);
            if (!hands) {
                snprintf(err, errlen, "replay: hands=%s: expected left, right or both", v);
                return -EINVAL;
            }
        } else {
            snprintf(err, errlen, "replay: unknown key \"%s\" (known: speed, loop, fast, hands, workspace, timeout)",
                     q.key);
            return -EINVAL;
        }
    }

    replay *r = calloc(1, sizeof *r);
    if (!r || !(r->path = strdup(arg))) {
        free(r);
        snprintf(err, errlen, "replay: out of memory");
        return -ENOMEM;
    }
    int rc = replay_load(arg, hands, &r->rec, err, errlen);
    if (rc) {
        free(r->path);
        free(r);
        return rc;
    }
    if (timeout > 0 && r->rec.format != REPLAY_FORMAT_EVENTLOG &&
        (rc = add_losses(&r->rec, (int64_t)llround(timeout * 1e9)))) {
        replay_recording_free(&r->rec);
        free(r->path);
        free(r);
        snprintf(err, errlen, "replay: out of memory");
        return rc;
    }
    if ((rc = fp_pacer_init(&r->pacer, host))) {
        replay_recording_free(&r->rec);
        free(r->path);
        free(r);
        snprintf(err, errlen, "replay: cannot set up its thread's clock: %s", strerror(-rc));
        return rc;
    }
    r->host = host;
    r->speed = speed;
    r->loop = loop;
    r->fast = fast;
    r->workspace = workspace;
    r->input = (fp_input){.size = sizeof(fp_input), .plugin_data = r, .start = replay_start,
                          .stop = replay_stop, .destroy = replay_destroy,
                          .get_extension = replay_get_extension};
    if (r->rec.repeated && host->log) {
        char msg[512];
        snprintf(msg, sizeof msg, "%s: %zu row%s repeat%s the time of the hand's row before (the "
                 "first: %s %ld); each such pair is one sample, the later row shown", arg,
                 r->rec.repeated, r->rec.repeated == 1 ? "" : "s", r->rec.repeated == 1 ? "s" : "",
                 r->rec.format == REPLAY_FORMAT_LEAP_JSON ? "frame" : "line", r->rec.first_repeat);
        host->log(host, FP_LOG_WARNING, msg);
    }
    if (r->rec.truncated_line && host->log) {
        char msg[512];
        snprintf(msg, sizeof msg, "%s:%ld: last line cut short (no newline): replay ends at "
                 "the row before", arg, r->rec.truncated_line);
        host->log(host, FP_LOG_WARNING, msg);
    }
    *out = &r->input;
    return 0;
}

/* The keys, typed (ABI 1.1), for `facepuppet plugins` and `plugins check`; create parses
 * them itself. */
static const fp_param_info replay_keys[] = {
    {.name = "speed", .type = FP_PARAM_FLOAT, .min = 1e-3, .max = 1e6, .default_value = "1",
     .unit = "x", .description = "play this many times as fast (0.001 to 1e6)"},
    {.name = "loop", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "start over at the end"},
    {.name = "fast", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "as fast as possible, retrying when the queue is full"},
    {.name = "hands", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands to replay"},
    {.name = "workspace", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "state the recording's range, so the hands are placed from it in advance (0: "
                    "placed as they arrive, as a live tracker's)"},
    {.name = "timeout", .type = FP_PARAM_FLOAT, .min = 0, .max = 3600, .default_value = "1", /* (or 0.01 up) */
     .unit = "s", .description = "a hand missing from the recording this long is reported gone "
                                 "(0: never; as osc's timeout)"},
    {.name = NULL},
};

static const fp_input_factory replay_factory = {
    .size = sizeof(fp_input_factory),
    .name = "replay",
    .description = "replays a recorded hand (Leap CSV, Leap playback original or facepuppet "
                   "event log) as live input",
    .usage = usage_text,
    .create = replay_create,
    .params = replay_keys,
};

static const void *replay_get_factory(const char *factory_id)
{
    if (factory_id && strcmp(factory_id, FP_INPUT_FACTORY_ID) == 0) return &replay_factory;
    return NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-replay",
    .version = "1.0.0",
    .get_factory = replay_get_factory,
};
