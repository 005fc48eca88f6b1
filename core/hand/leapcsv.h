/*
 * leapcsv.h: reader of the two CSV formats of the Leap Motion recordings in
 * shared/data/hands/leap-motion (*_joints_mm.csv, *_cyberglove_like_angles_deg.csv; formats
 * in ../shared/data/README.md). Internal to the hand validation (fp-handcheck, tests/hand);
 * the replay input plugin has its own reader.
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Threads: reentrant. Errors (fp_error.h): a negative errno and a message in err naming the
 * file, the line and the column ("file:LINE: column N (name): ..."): -EBADMSG malformed
 * content, -ENOENT / -EACCES the file cannot be opened, -EIO a read failed, -ENOMEM,
 * -EINVAL a NULL argument.
 */
#ifndef FP_LEAPCSV_H
#define FP_LEAPCSV_H

#include <stddef.h>
#include <stdint.h>

#include "facepuppet/plugin.h"

typedef struct fp_leap_joints_row {
    long frame;
    int64_t timestamp_us;
    long hand_id;
    fp_hand_side side;
    float palm_mm[3], normal[3], direction[3];
    float joints_mm[FP_HAND_JOINTS][3];   /* fp_hand_joint layout; [FP_JOINT_PALM] = palm */
} fp_leap_joints_row;

typedef struct fp_leap_angles_row {
    long frame;
    int64_t timestamp_us;
    long hand_id;
    fp_hand_side side;
    float degrees[FP_GLOVE_SENSORS];     /* fp_glove_sensor order; 0 where empty */
    uint32_t valid;                      /* bit i: column i was not empty */
} fp_leap_angles_row;

/** Read a *_joints_mm.csv. On success *rows (free() it) holds *n rows in file order.
 *  Non-finite numbers, missing or extra fields, a wrong header, an unknown hand_type are
 *  errors. */
int fp_leapcsv_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                           size_t errlen);

/** Read a *_cyberglove_like_angles_deg.csv; empty angle fields are allowed (bit clear). */
int fp_leapcsv_read_angles(const char *path, fp_leap_angles_row **rows, size_t *n, char *err,
                           size_t errlen);

#endif
