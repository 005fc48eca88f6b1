/*
 * fp-handcheck: run the Leap recordings' joint angles through the hand kinematics and print
 * the fingertip error against the recorded joints, per recording, hand and finger.
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * usage: fp-handcheck [--fit geometry|size|none] [--tip-pad F] [--data DIR] [RECORDING...]
 * RECORDING is a name such as "grab" (files DIR/hands/leap-motion/NAME_joints_mm.csv and
 * NAME_cyberglove_like_angles_deg.csv); default: the four shared recordings. DIR defaults to
 * $FP_SHARED_DATA, else ../shared/data if it exists, else the path configured at build time.
 * Exit 0, 1 when a recording could not be read, 64 a bad option (named).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "handcheck.h"
#include <facepuppet/plugin_util.h> /* fp_parse_decimal: numbers as in every option */

static const char *const default_recordings[] = {"HandSplay-110fps", "Waiting-110fps", "grab",
                                                 "three-claps"};

static void usage(FILE *f)
{
    fprintf(f, "usage: fp-handcheck [--fit geometry|size|none] [--tip-pad F] [--data DIR] [RECORDING...]\n"
               "  Fingertip error (mm) of fp_hand_fk on the Leap recordings' angles against their\n"
               "  joints, in the hand frame. --fit: what is fitted per hand (default geometry:\n"
               "  size, MCP offsets, middle rest yaw, rest thumb rotation). --tip-pad: share of the\n"
               "  soft tip in the model's tips (default 0: Leap tips are bone ends).\n");
}

int main(int argc, char **argv)
{
    fp_handcheck_options opt = {0};
    const char *data = getenv("FP_SHARED_DATA");
    if (!data || !*data)
        data = access("../shared/data/hands", F_OK) == 0 ? "../shared/data" : FP_SHARED_DATA;
    int first = argc;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--fit") && i + 1 < argc) {
            const char *v = argv[++i];
            if (!strcmp(v, "geometry"))
                opt.fit = FP_HANDCHECK_FIT_GEOMETRY;
            else if (!strcmp(v, "size"))
                opt.fit = FP_HANDCHECK_FIT_SIZE;
            else if (!strcmp(v, "none"))
                opt.fit = FP_HANDCHECK_FIT_NONE;
            else {
                fprintf(stderr, "fp-handcheck: --fit: unknown value '%s' (geometry, size, none)\n", v);
                return 64;
            }
        } else if (!strcmp(argv[i], "--tip-pad") && i + 1 < argc) {
            double pad;
            if (!fp_parse_decimal(argv[++i], &pad) || !(pad >= 0 && pad <= 1)) {
                fprintf(stderr, "fp-handcheck: --tip-pad: expected a number in [0, 1], got '%s'\n", argv[i]);
                return 64;
            }
            opt.tip_pad = (float)pad;
        } else if (!strcmp(argv[i], "--data") && i + 1 < argc) {
            data = argv[++i];
        } else if (argv[i][0] == '-') {
            fprintf(stderr, "fp-handcheck: unknown option '%s'\n", argv[i]);
            usage(stderr);
            return 64;
        } else {
            first = i;
            break;
        }
    }
    const char *const *names = first < argc ? (const char *const *)argv + first : default_recordings;
    int count = first < argc ? argc - first : 4;
    static const char *const fit_name[] = {"geometry", "size", "none"};
    printf("fit: %s, tip_pad %.2f, data %s\n", fit_name[opt.fit], opt.tip_pad, data);
    printf("%-18s %4s %-5s %6s %5s  %-35s %-35s %6s %6s %6s\n", "recording", "hand", "side",
           "frames", "size", "median mm thumb index middle ring little",
           "p90 mm thumb index middle ring little", "median", "p90", "rtrip");
    int status = 0;
    float all_med = 0;
    int nh = 0;
    for (int r = 0; r < count; r++) {
        char jp[4096], ap[4096], err[512];
        snprintf(jp, sizeof jp, "%s/hands/leap-motion/%s_joints_mm.csv", data, names[r]);
        snprintf(ap, sizeof ap, "%s/hands/leap-motion/%s_cyberglove_like_angles_deg.csv", data, names[r]);
        fp_handcheck_hand h[8];
        size_t n = 0;
        if (fp_handcheck_recording(jp, ap, &opt, h, 8, &n, err, sizeof err)) {
            fprintf(stderr, "fp-handcheck: %s\n", err);
            status = 1;
            continue;
        }
        for (size_t i = 0; i < n; i++) {
            printf("%-18s %4ld %-5s %6zu %5.3f  %6.1f %6.1f %6.1f %6.1f %6.1f      %6.1f %6.1f %6.1f %6.1f %6.1f      %6.2f %6.2f %6.2f\n",
                   names[r], h[i].hand_id, h[i].side == FP_HAND_LEFT ? "left" : "right", h[i].frames,
                   h[i].model.size, h[i].median_mm[0], h[i].median_mm[1], h[i].median_mm[2],
                   h[i].median_mm[3], h[i].median_mm[4], h[i].p90_mm[0], h[i].p90_mm[1],
                   h[i].p90_mm[2], h[i].p90_mm[3], h[i].p90_mm[4], h[i].median_all_mm,
                   h[i].p90_all_mm, h[i].roundtrip_median_mm);
            all_med += h[i].median_all_mm;
            nh++;
        }
    }
    if (nh)
        printf("mean over hands of the median fingertip error: %.2f mm\n", all_med / nh);
    return status;
}
