/*
 * handcheck.h: check of the hand kinematics on a Leap Motion recording (internal to the
 * validation: fp-handcheck and tests/hand). For each hand of a recording: the joint angles of
 * *_cyberglove_like_angles_deg.csv (degrees, converted to radians) go through fp_hand_fk; the
 * fingertips are compared with those of *_joints_mm.csv in the same frames (matched on
 * frame + hand_id), both in the hand's own frame built from the Leap palm position, palm
 * normal and hand direction (fp_hand_frame_from_palm).
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_HANDCHECK_H
#define FP_HANDCHECK_H

#include <stddef.h>

#include "fp_hand.h"

typedef enum fp_handcheck_fit {
    FP_HANDCHECK_FIT_GEOMETRY = 0, /* size, MCP/CMC offsets, middle rest yaw, rest thumb
                                      rotation fitted per hand (fp_hand_fit_geometry) */
    FP_HANDCHECK_FIT_SIZE = 1,     /* only the size factor fitted (fp_hand_fit_size) */
    FP_HANDCHECK_FIT_NONE = 2      /* the mean adult model as it is */
} fp_handcheck_fit;

/** Options; zero-initialised = fit geometry, Leap tip convention (tip_pad 0). */
typedef struct fp_handcheck_options {
    fp_handcheck_fit fit;
    float tip_pad;            /* model tip_pad for the comparison (Leap tips are bone ends) */
} fp_handcheck_options;

typedef struct fp_handcheck_hand {
    long hand_id;
    fp_hand_side side;
    size_t frames;                /* frames matched and compared */
    fp_hand_model model;          /* the model as fitted */
    float median_mm[FP_FINGERS];  /* per finger (thumb first), fingertip distance */
    float p90_mm[FP_FINGERS];
    float median_all_mm, p90_all_mm; /* over all fingertips of all frames */
    float roundtrip_median_mm;    /* fp_hand_from_positions then fp_hand_fk on the Leap joints:
                                     median fingertip distance (what the model can represent) */
} fp_handcheck_hand;

/** Check one recording. Writes at most cap hands (in order of first appearance) to out and
 *  their number to *nout. Returns 0, or a negative code after writing a message naming the
 *  file, line and column (CSV errors), or the frame (no matching angle row), to err. */
int fp_handcheck_recording(const char *joints_csv, const char *angles_csv,
                           const fp_handcheck_options *opt, fp_handcheck_hand *out, size_t cap,
                           size_t *nout, char *err, size_t errlen);

/** Median (q = 0.5) or other quantile of v[0..n) by linear interpolation; sorts v in place. */
float fp_handcheck_quantile(float *v, size_t n, double q);

#endif
