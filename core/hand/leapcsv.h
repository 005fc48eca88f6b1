/*
 * leapcsv.h: the one reader of the two CSV formats of the Leap Motion recordings in
 * shared/data/hands/leap-motion (*_joints_mm.csv, *_cyberglove_like_angles_deg.csv; formats
 * in ../shared/data/README.md). Used by the hand validation (fp-handcheck, tests/hand) and by
 * the replay input plugin (static library `fp_leapcsv`, PIC, hidden symbols).
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * What a file must be: line 1 exactly the format's header (column count checked before
 * names); every row the header's number of fields; frame, timestamp_us, hand_id integers;
 * hand_type "left" or "right"; every value a decimal (facepuppet/decimal.h: no blanks,
 * hexadecimal, inf or nan) finite as a float (C locale, whatever the process's locale); empty
 * fields only in the angles format; in the joints format every value within FP_EVENT_MAX_MM (10 m)
 * of the tracker; timestamp_us never smaller
 * than the row before's and within +-FP_LEAPCSV_TIME_MAX_US (so that it converts to ns and
 * differences of times never overflow, as for the event log's times); no NUL
 * byte. Blank lines are skipped; a CR before the newline is dropped. A last line without a
 * newline is read when it is a whole row (it parses, and its last field has as many decimals
 * as the row before's: a writer that ends the file without a newline); otherwise (a recording
 * cut off inside it) it is dropped and reported through *truncated_line.
 *
 * Errors (core/common/fp_error.h): -EBADMSG for malformed content, with the message
 * "FILE:LINE:COLUMN: reason" (COLUMN 1-based, in bytes; the reason names the column, e.g.
 * `bad number "1x0" in column palm_y`); -errno with "FILE: cannot open: ..." when the file
 * cannot be opened (a FIFO or a device is not waited on: -ENXIO); -EBADMSG "larger than 1 GiB"
 * for a file over FP_LEAPCSV_MAX_BYTES (by its size, before reading); -EIO when a read fails; -ENOMEM.
 * Threads: reentrant, [any-thread].
 */
#ifndef FP_LEAPCSV_H
#define FP_LEAPCSV_H

#include <stddef.h>
#include <stdint.h>

#include "facepuppet/plugin.h"

/** The largest recording read, bytes (1 GiB: an hour of two hands at 115 Hz is about 0.5 GB). */
#define FP_LEAPCSV_MAX_BYTES ((size_t)1 << 30)

typedef enum fp_leapcsv_format {
    FP_LEAPCSV_ANY = 0,    /* as an argument: take the format the header names */
    FP_LEAPCSV_JOINTS = 1, /* *_joints_mm.csv: 4 lead columns, palm xyz, normal, direction,
                              then 5 fingers x (mcp, pip, dip, tip) x xyz, in mm */
    FP_LEAPCSV_ANGLES = 2  /* *_cyberglove_like_angles_deg.csv: 4 lead columns, then the 22
                              sensors in fp_glove_sensor order, in degrees, may be empty */
} fp_leapcsv_format;

/** The largest |timestamp_us| (10^15 us, about 31.7 years; in ns the event log's
 *  FP_EVENTLOG_TIME_MAX). */
#define FP_LEAPCSV_TIME_MAX_US 1000000000000000LL

enum {
    FP_LEAPCSV_LEAD = 4,                                          /* frame..hand_type */
    FP_LEAPCSV_JOINT_VALUES = 9 + 4 * FP_FINGERS * 3,             /* 69 */
    FP_LEAPCSV_MAX_COLUMNS = FP_LEAPCSV_LEAD + FP_LEAPCSV_JOINT_VALUES /* 73 */
};

/** One data row as the reader hands it to a callback (valid during the call only). */
typedef struct fp_leapcsv_row {
    const char *path;
    fp_leapcsv_format format;
    long line;                                   /* 1-based line of the file */
    long frame;
    int64_t timestamp_us;
    long hand_id;
    fp_hand_side side;
    int nvalues;                                 /* 69 (joints) or 22 (angles) */
    double value[FP_LEAPCSV_JOINT_VALUES];       /* column LEAD + i as strtod reads it; 0 if empty */
    float valuef[FP_LEAPCSV_JOINT_VALUES];       /* the same as strtof reads it (nearest float) */
    uint32_t valid;                              /* angles: bit i: column LEAD + i not empty;
                                                    joints: every bit of the 22 set */
    long col[FP_LEAPCSV_MAX_COLUMNS];            /* 1-based byte column of each field */
} fp_leapcsv_row;

/** Called once per data row in file order. Return 0 to go on, or a negative code after
 *  writing a message into err (errlen bytes) to stop the read with that code. */
typedef int (*fp_leapcsv_row_fn)(void *user, const fp_leapcsv_row *row, char *err,
                                 size_t errlen);

/** The name of column i (0-based) of format (e.g. "palm_y", "index_mcp"); "?" outside. */
const char *fp_leapcsv_column_name(fp_leapcsv_format format, int i);

/** Read `path` whole and call fn for each row. want: the format required, or FP_LEAPCSV_ANY
 *  (the header decides: "palm_x" as column 5 means joints, else angles). *format (may be
 *  NULL) receives the format read; *truncated_line (may be NULL) the number of a last line
 *  without a newline dropped as cut off (above), else 0. Returns 0 or a negative code (above). */
int fp_leapcsv_read(const char *path, fp_leapcsv_format want, fp_leapcsv_format *format,
                    fp_leapcsv_row_fn fn, void *user, long *truncated_line, char *err,
                    size_t errlen);

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

/** A joints-format row (in->format FP_LEAPCSV_JOINTS, 69 values) as an fp_leap_joints_row:
 *  the lead columns, and the values as valuef[] holds them (mm; the palm also as joint
 *  FP_JOINT_PALM). No errors, no allocation; both pointers the caller's, not NULL.
 *  Reentrant, [any-thread]. Used by both readers (leapcsv.c, leapjson.c). */
void fp_leap_joints_from_row(const fp_leapcsv_row *in, fp_leap_joints_row *out);

/** Read a *_joints_mm.csv whole. On success *rows (free() it) holds *n >= 1 rows in file
 *  order; a file without data rows is -EBADMSG. */
int fp_leapcsv_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                           size_t errlen);

/** Read a *_cyberglove_like_angles_deg.csv whole; empty angle fields are allowed (bit clear). */
int fp_leapcsv_read_angles(const char *path, fp_leap_angles_row **rows, size_t *n, char *err,
                           size_t errlen);

#endif
