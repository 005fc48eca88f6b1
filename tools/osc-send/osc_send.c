/*
 * osc_send.c: fp-osc-send, replays a Leap joints CSV (shared/data/hands/leap-motion/
 * *_joints_mm.csv) or a Leap playback original (*.json.lz, core/hand/leapjson.h) over OSC/UDP to facepuppet's input-osc, one bundle per frame with the
 * frame's timetag, at the recorded pace or as fast as possible. For tests and demos.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Usage: fp-osc-send [options] FILE   (see usage() or docs/osc.md). Exit 0, 64 usage, 65 bad
 * CSV, 69 send failed.
 */
#define _GNU_SOURCE
#include "fp_hand.h"
#include "leapcsv.h"
#include "leapjson.h"
#include <facepuppet/plugin_util.h> /* fp_parse_decimal, fp_parse_whole: numbers as in every option */

#include <lo/lo.h>

#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *const side_name[2] = {"left", "right"};

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fp-osc-send [--port P] [--host ADDR] [--format facepuppet|leap|mediapipe]\n"
            "                   [--send joints,wrist] [--hand left|right|both] [--fast | --speed X]\n"
            "                   [--no-bundle] [--frames N] [--quiet] FILE\n\n"
            "Replays a Leap joints CSV (*_joints_mm.csv), or a Leap playback original (*.json.lz,\n"
            "*.json), over OSC/UDP to facepuppet's osc input,\n"
            "one bundle per frame, timetag = now at start + the frame's recorded time.\n"
            "  --port P       UDP port (default 9000)   --host ADDR  (default 127.0.0.1)\n"
            "  --format F     facepuppet (default): /facepuppet/hand/H/joints (63 f), /wrist (7 f)\n"
            "                 leap: /hand<s> i i f f f and /finger<s>-<n> i i f f f (palm, tips)\n"
            "                 mediapipe: /lx/ /ly/ /lz/ (and /r..), 21 floats, inverse of the\n"
            "                 plugin's defaults (width 400 mm, aspect 0.75, height 200 mm, depth 0)\n"
            "  --send LIST    facepuppet format: joints, wrist or joints,wrist (default joints)\n"
            "  --hand H       hands to send (default both)\n"
            "  --fast         no pacing (a 200 us gap between frames)   --speed X  pace x X\n"
            "  --no-bundle    plain messages, no bundles (no timetags)\n"
            "  --frames N     stop after N frames\n");
}

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void sleep_until(int64_t t)
{
    struct timespec ts = {(time_t)(t / 1000000000), (long)(t % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {}
}

static lo_timetag add_ns(lo_timetag t, int64_t ns)
{
    uint64_t frac_ns = ((uint64_t)t.frac * 1000000000u) >> 32;
    uint64_t total = (uint64_t)t.sec * 1000000000u + frac_ns + (uint64_t)ns;
    lo_timetag r = {(uint32_t)(total / 1000000000u), 0};
    r.frac = (uint32_t)(((total % 1000000000u) << 32) / 1000000000u);
    return r;
}

enum { FMT_FP, FMT_LEAP, FMT_MP };

/* Adds one hand's messages to a bundle (or sends them at once when b is NULL). */
static int add_hand(lo_address a, lo_bundle b, int format, bool joints, bool wrist,
                    const fp_hand_model *model, const fp_leap_joints_row *r, int slot, int *msgs)
{
    lo_message ms[8];
    const char *paths[8];
    char pathbuf[8][48];
    int n = 0;
    if (format == FMT_FP) {
        if (joints) {
            lo_message m = lo_message_new();
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) lo_message_add_float(m, r->joints_mm[j][k]);
            snprintf(pathbuf[n], sizeof pathbuf[n], "/facepuppet/hand/%s/joints", side_name[r->side]);
            ms[n++] = m;
        }
        if (wrist) {
            float pos[3], rot[4];
            if (fp_hand_frame_from_palm(model, r->side, r->palm_mm, r->normal, r->direction, pos, rot) == 0) {
                lo_message m = lo_message_new();
                for (int k = 0; k < 3; k++) lo_message_add_float(m, pos[k]);
                for (int k = 0; k < 4; k++) lo_message_add_float(m, rot[k]);
                snprintf(pathbuf[n], sizeof pathbuf[n], "/facepuppet/hand/%s/wrist", side_name[r->side]);
                ms[n++] = m;
            }
        }
    } else if (format == FMT_LEAP) {
        lo_message m = lo_message_new();
        lo_message_add_int32(m, (int32_t)r->hand_id);
        lo_message_add_int32(m, 0);
        for (int k = 0; k < 3; k++) lo_message_add_float(m, r->palm_mm[k]);
        snprintf(pathbuf[n], sizeof pathbuf[n], "/hand%d", slot);
        ms[n++] = m;
        for (int f = 0; f < FP_FINGERS; f++) {
            m = lo_message_new();
            lo_message_add_int32(m, (int32_t)r->hand_id);
            lo_message_add_int32(m, f);
            for (int k = 0; k < 3; k++) lo_message_add_float(m, r->joints_mm[FP_JOINT_TIP(f)][k]);
            snprintf(pathbuf[n], sizeof pathbuf[n], "/finger%d-%d", slot, f);
            ms[n++] = m;
        }
    } else {
        /* MediaPipe landmarks: 0 the wrist (60 mm behind the palm centre along the hand
         * direction), 1..20 the joints; inverse of the plugin's default mapping. */
        float lm[21][3];
        float dl = sqrtf(r->direction[0] * r->direction[0] + r->direction[1] * r->direction[1] +
                         r->direction[2] * r->direction[2]);
        for (int k = 0; k < 3; k++) lm[0][k] = r->palm_mm[k] - 60.f * r->direction[k] / (dl > 0 ? dl : 1);
        for (int j = 1; j < 21; j++) memcpy(lm[j], r->joints_mm[j], sizeof lm[j]);
        for (int axis = 0; axis < 3; axis++) {
            lo_message m = lo_message_new();
            for (int j = 0; j < 21; j++) {
                float v = axis == 0   ? lm[j][0] / 400.f + 0.5f
                          : axis == 1 ? 0.5f - (lm[j][1] - 200.f) / 300.f
                                      : lm[j][2] / 400.f;
                lo_message_add_float(m, v);
            }
            snprintf(pathbuf[n], sizeof pathbuf[n], "/%c%c/", r->side == FP_HAND_LEFT ? 'l' : 'r', 'x' + axis);
            ms[n++] = m;
        }
    }
    int rc = 0;
    for (int i = 0; i < n; i++) {
        paths[i] = pathbuf[i];
        if (b) {
            lo_bundle_add_message(b, paths[i], ms[i]); /* the bundle frees it */
        } else {
            if (lo_send_message(a, paths[i], ms[i]) < 0) rc = -1;
            lo_message_free(ms[i]);
        }
        (*msgs)++;
    }
    return rc;
}

int main(int argc, char **argv)
{
    static const struct option opts[] = {
        {"port", required_argument, 0, 'p'}, {"host", required_argument, 0, 'H'},
        {"format", required_argument, 0, 'f'}, {"send", required_argument, 0, 's'},
        {"hand", required_argument, 0, 'h'}, {"fast", no_argument, 0, 'F'},
        {"speed", required_argument, 0, 'x'}, {"no-bundle", no_argument, 0, 'B'},
        {"frames", required_argument, 0, 'n'}, {"quiet", no_argument, 0, 'q'},
        {"help", no_argument, 0, '?' + 256}, {0, 0, 0, 0}};
    const char *port = "9000", *host = "127.0.0.1";
    int format = FMT_FP, hands = 3;
    bool joints = true, wrist = false, fast = false, bundles = true, quiet = false;
    double speed = 1.0;
    long max_frames = -1;
    for (int c; (c = getopt_long(argc, argv, "p:H:f:s:h:Fx:Bn:q", opts, NULL)) != -1;) {
        switch (c) {
        case 'p': port = optarg; break;
        case 'H': host = optarg; break;
        case 'f':
            if (!strcmp(optarg, "facepuppet")) format = FMT_FP;
            else if (!strcmp(optarg, "leap")) format = FMT_LEAP;
            else if (!strcmp(optarg, "mediapipe")) format = FMT_MP;
            else {
                fprintf(stderr, "fp-osc-send: --format %s: expected facepuppet, leap or mediapipe\n", optarg);
                return 64;
            }
            break;
        case 's':
            joints = strstr(optarg, "joints") != NULL;
            wrist = strstr(optarg, "wrist") != NULL;
            if (!joints && !wrist) {
                fprintf(stderr, "fp-osc-send: --send %s: expected joints, wrist or joints,wrist\n", optarg);
                return 64;
            }
            break;
        case 'h':
            hands = !strcmp(optarg, "left") ? 1 : !strcmp(optarg, "right") ? 2 : !strcmp(optarg, "both") ? 3 : 0;
            if (!hands) {
                fprintf(stderr, "fp-osc-send: --hand %s: expected left, right or both\n", optarg);
                return 64;
            }
            break;
        case 'F': fast = true; break;
        case 'x':
            if (!fp_parse_decimal(optarg, &speed) || !(speed > 0) || speed > 1e6) {
                fprintf(stderr, "fp-osc-send: --speed '%s': expected a number > 0 and at most 1e6\n", optarg);
                return 64;
            }
            break;
        case 'B': bundles = false; break;
        case 'n': {
            unsigned long long n;
            if (!fp_parse_whole(optarg, LONG_MAX, &n)) {
                fprintf(stderr, "fp-osc-send: --frames '%s': expected a whole number\n", optarg);
                return 64;
            }
            max_frames = (long)n;
            break;
        }
        case 'q': quiet = true; break;
        case '?' + 256: usage(stdout); return 0;
        default: usage(stderr); return 64;
        }
    }
    if (optind != argc - 1) {
        usage(stderr);
        return 64;
    }
    fp_leap_joints_row *rows = NULL;
    size_t nrows = 0;
    char err[512];
    char head[64] = "";
    FILE *hf = fopen(argv[optind], "rb");
    if (hf) {
        head[fread(head, 1, sizeof head - 1, hf)] = '\0';
        fclose(hf);
    }
    bool original = strncmp(head, "frame,", 6) && fp_leapjson_looks_like(head);
    if ((original ? fp_leapjson_read_joints(argv[optind], &rows, &nrows, err, sizeof err)
                  : fp_leapcsv_read_joints(argv[optind], &rows, &nrows, err, sizeof err)) < 0) {
        fprintf(stderr, "fp-osc-send: %s\n", err);
        return 65;
    }
    fp_hand_model model;
    fp_hand_model_init(&model);
    lo_address a = lo_address_new(host, port);
    if (!a) {
        fprintf(stderr, "fp-osc-send: bad address %s:%s\n", host, port);
        free(rows);
        return 64;
    }
    lo_timetag tt0;
    lo_timetag_now(&tt0);
    int64_t t0 = mono_ns();
    long frames = 0;
    int msgs = 0, failures = 0;
    for (size_t i = 0; i < nrows && (max_frames < 0 || frames < max_frames);) {
        size_t j = i;
        while (j < nrows && rows[j].timestamp_us == rows[i].timestamp_us) j++;
        int64_t rel_ns = (rows[i].timestamp_us - rows[0].timestamp_us) * 1000;
        if (fast) {
            if (frames) sleep_until(mono_ns() + 200000);
        } else {
            sleep_until(t0 + (int64_t)((double)rel_ns / speed));
        }
        lo_timetag tt;
        if (fast)
            lo_timetag_now(&tt); /* unpaced: the sending moment */
        else
            tt = add_ns(tt0, (int64_t)((double)rel_ns / speed));
        lo_bundle b = bundles ? lo_bundle_new(tt) : NULL;
        int slot = 0;
        for (size_t k = i; k < j; k++) {
            if (!(hands & (1 << rows[k].side))) continue;
            if (add_hand(a, b, format, joints, wrist, &model, &rows[k], slot++, &msgs)) failures++;
        }
        if (b) {
            if (lo_bundle_count(b) && lo_send_bundle(a, b) < 0) failures++;
            lo_bundle_free_recursive(b);
        }
        frames++;
        i = j;
    }
    if (!quiet)
        printf("fp-osc-send: %ld frames, %d messages to %s:%s in %.3f s%s\n", frames, msgs, host, port,
               (double)(mono_ns() - t0) / 1e9, failures ? " (some sends failed)" : "");
    if (failures) fprintf(stderr, "fp-osc-send: %d sends failed: %s\n", failures, lo_address_errstr(a));
    lo_address_free(a);
    free(rows);
    return failures ? 69 : 0;
}
