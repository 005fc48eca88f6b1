/* take_testutil.h: deterministic frames and headers for the take tests, the fuzz seeds and
 * the benchmark. A frame's content is a function of its number, so a reader's frame can be
 * checked against a freshly made one. */
#ifndef TAKE_TESTUTIL_H
#define TAKE_TESTUTIL_H

#include "fp_take.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TT_MAX_VEC 16
#define TT_MAX_CHAN 4
#define TT_MAX_EV 8
#define TT_ORIGIN 1043500000000LL   /* host time of frame 0 and of timecode in */

typedef struct tt_frame {
    fp_take_frame f;
    fp_control_set cs;
    float start[TT_MAX_VEC][3], end[TT_MAX_VEC][3];
    fp_channel chan[TT_MAX_CHAN];
    fp_event ev[TT_MAX_EV];
} tt_frame;

static inline uint64_t tt_hash(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdULL; x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ULL; x ^= x >> 33;
    return x;
}
static inline float tt_float(uint64_t seed, int i)
{
    /* Finite floats of every kind: ordinary values, negative zero, a subnormal, large. */
    uint64_t h = tt_hash(seed * 1315423911u + (uint64_t)i);
    switch (h % 16) {
    case 0: return -0.0f;
    case 1: return 1.40129846e-45f;
    case 2: return 3.40282347e+38f;
    default: return (float)((double)(h >> 11) / 9007199254740992.0 * 400.0 - 200.0);
    }
}

/* Frame n: vectors 0..TT_MAX_VEC-1 and events of every type, chosen by n; `rich` false gives
 * the bench's typical frame (10 vectors, 2 position + 2 wrist events). */
static inline void tt_make(tt_frame *t, uint64_t n, int rich)
{
    memset(t, 0, sizeof *t);
    uint64_t h = tt_hash(n + 17);
    t->cs.size = sizeof t->cs;
    t->cs.active = rich ? (h & 1) != 0 : true;
    t->cs.intents = rich ? (uint32_t)(h >> 8) & 7u : 0;
    t->cs.radius = rich ? 0.5 + (double)(h % 1000) / 997.0 : 2.4;
    t->cs.capacity = TT_MAX_VEC;
    t->cs.count = rich ? (size_t)(h >> 16) % (TT_MAX_VEC + 1) : 10;
    t->cs.start = t->start;
    t->cs.end = t->end;
    for (size_t i = 0; i < t->cs.count; i++)
        for (int k = 0; k < 3; k++) {
            t->start[i][k] = tt_float(n, (int)(6 * i + (size_t)k));
            t->end[i][k] = tt_float(n, (int)(6 * i + 3 + (size_t)k));
        }
    t->cs.channel_capacity = TT_MAX_CHAN;
    t->cs.channel_count = rich ? (size_t)(h >> 24) % (TT_MAX_CHAN + 1) : 0;
    t->cs.channels = t->chan;
    for (size_t i = 0; i < t->cs.channel_count; i++) {
        snprintf(t->chan[i].name, sizeof t->chan[i].name, "jaw.open.%zu.%llu", i,
                 (unsigned long long)n);
        t->chan[i].value = tt_float(n, 500 + (int)i);
    }
    size_t ne = rich ? (size_t)(h >> 32) % (TT_MAX_EV + 1) : 4;
    for (size_t i = 0; i < ne; i++) {
        fp_event *e = &t->ev[i];
        int type = rich ? 1 + (int)((h >> (40 + i)) + i) % 5 : (i < 2 ? 2 : 3);
        e->header.type = (uint16_t)type;
        e->header.time_ns = TT_ORIGIN + (int64_t)(n * 16666667 + i * 1000) - 5;
        e->header.source = (uint32_t)(i % 2); /* (tt_header lists 2 inputs) */
        e->header.hand = type >= 4 ? -1 : (int)(i & 1);
        e->header.flags = 0;
        switch (type) {
        case FP_EVENT_JOINT_ANGLES:
            e->header.size = sizeof e->angles;
            e->angles.valid = 0x3fffff & (uint32_t)h;
            for (int k = 0; k < FP_GLOVE_SENSORS; k++) e->angles.radians[k] = tt_float(n, 600 + k);
            break;
        case FP_EVENT_JOINT_POSITIONS:
            e->header.size = sizeof e->positions;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) e->positions.mm[j][k] = tt_float(n, 700 + 3 * j + k);
            break;
        case FP_EVENT_WRIST_POSE:
            e->header.size = sizeof e->wrist;
            for (int k = 0; k < 3; k++) e->wrist.position_mm[k] = tt_float(n, 800 + k);
            for (int k = 0; k < 4; k++) e->wrist.rotation[k] = tt_float(n, 810 + k);
            break;
        case FP_EVENT_BUTTON:
            e->header.size = sizeof e->button;
            e->button.button = 1u << (h % 3);
            e->button.down = (uint32_t)(h >> 3) & 1;
            e->button.mask = (uint32_t)(h >> 4) & 7;
            break;
        default:
            e->header.size = sizeof e->status;
            e->status.code = 1 + (uint32_t)(h % 6);
            snprintf(e->status.text, sizeof e->status.text, "status \"%llu\"\n\x01 ok",
                     (unsigned long long)n);
            break;
        }
    }
    t->f.frame = n;
    t->f.time_ns = TT_ORIGIN + (int64_t)(n * 16666667);
    t->f.events = t->ev;
    t->f.event_count = ne;
    t->f.requested = rich ? (uint32_t)(h >> 50) & 7u : 0;
    t->f.control = (rich && h % 11 == 0) ? NULL : &t->cs;
}

/* 0 when `got` equals frame `want` bit for bit; else which part differs (1-based). */
static inline int tt_compare(const fp_take_frame *got, const fp_take_frame *want)
{
    if (got->frame != want->frame) return 1;
    if (got->time_ns != want->time_ns) return 2;
    if (got->requested != want->requested) return 3;
    if (got->event_count != want->event_count) return 4;
    for (size_t i = 0; i < got->event_count; i++)
        if (memcmp(&got->events[i], &want->events[i], sizeof(fp_event))) return 5;
    if (!got->control != !want->control) return 6;
    if (!got->control) return 0;
    const fp_control_set *a = got->control, *b = want->control;
    if (a->active != b->active || a->intents != b->intents ||
        memcmp(&a->radius, &b->radius, sizeof a->radius) || a->count != b->count ||
        a->channel_count != b->channel_count)
        return 7;
    if (a->count && (memcmp(a->start, b->start, a->count * sizeof *a->start) ||
                     memcmp(a->end, b->end, a->count * sizeof *a->end)))
        return 8;
    for (size_t i = 0; i < a->channel_count; i++)
        if (strcmp(a->channels[i].name, b->channels[i].name) ||
            memcmp(&a->channels[i].value, &b->channels[i].value, sizeof(float)))
            return 9;
    return 0;
}

static inline void tt_header(fp_take_header *h, const char *slate)
{
    memset(h, 0, sizeof *h);
    snprintf(h->slate, sizeof h->slate, "%s", slate);
    h->rate.num = 60;
    h->rate.den = 1;
    h->timecode_in.hours = 10;
    h->timecode_in.minutes = 4;
    h->timecode_in.seconds = 31;
    h->timecode_in.frames = 12;
    h->time_origin_ns = TT_ORIGIN;
    h->mesh_path = "../shared/data/faces/ict/neutral.obj";
    h->mesh_crc32 = 0x1a2b3c4du;
    h->mesh_crc_of = "positions";
    h->mesh_vertices = 26719;
    h->rig_path = NULL;
    h->mapping = "anchored";
    h->mapping_keys[0].key = "release";
    h->mapping_keys[0].value = "1.5";
    h->mapping_keys[1].key = "clamp";
    h->mapping_keys[1].value = "0.45";
    h->mapping_key_count = 2;
    h->inputs[0] = "replay:three-claps.csv,speed=2";
    h->inputs[1] = "pedal";
    h->input_count = 2;
    h->calibration[1].present = true;
    h->calibration[1].scale = 0.1;
    h->calibration[1].rotation[0] = 0.7071067811865476;
    h->calibration[1].rotation[2] = -0.7071067811865475;
    h->calibration[1].offset[0] = 1.0 / 3.0;
    h->calibration[1].offset[1] = 1.5;
    h->calibration[1].offset[2] = -12e-17;
    h->performer_count = 2; /* (format 1.3) */
    h->performers[0] = (fp_take_performer){.name = "", .scale = 0.1, .rotation = {1, 0, 0, 0},
                                           .offset = {0.1, 1.0 / 7.0, 12.5}};
    h->performers[1] = (fp_take_performer){.name = "B", .scale = 0.2 / 3.0,
                                           .rotation = {0.7071067811865476, 0, -0.7071067811865475, 0},
                                           .offset = {-4.1, 1e-300, 21.1},
                                           .hand_offset = {{0.5, 0, 0}, {-0.5, 0, 1.0 / 3.0}}};
    h->radius = 2.4000000000000004;
    h->description = "claps, \"second\" try\n";
    h->rating = 4;
}

#endif
