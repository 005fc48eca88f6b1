/*
 * glove_cal.h: CyberGlove calibration, raw sensor value -> joint angle in radians.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Internal to the input-cyberglove plugin and the glove emulator (static library
 * fp_glovecal); not part of the plugin ABI.
 *
 * Every supported format reduces to one line per sensor, in the 8-bit raw scale (1..254):
 *     angle[i] = gain[i] * raw + offset[i]      (radians)
 * A 16-bit (CyberGlove III) value v in 1..4094 enters as raw = v / 16.
 *
 * Formats (fpg_cal_load detects them from the first non-comment line):
 *  - asr two-point (shared/data/cyberglove/ files; asr-ros/asr_cyberglove_lib): exactly 22
 *    lines `rad1:raw1 rad2:raw2`; angle = (rad2-rad1)*(raw-raw1)/(raw2-raw1) + rad1. Line i is
 *    in asr's joint order; FPG_ASR_LINE_SENSOR[i] is the glove sensor it calibrates
 *    (shared/docs/devices.md, asr include/gloveConstants.h). A line with rad1 == rad2 (asr's
 *    palm arch) carries no information: that sensor is marked unused.
 *  - gain/offset: lines `SENSOR GAIN OFFSET` (SENSOR 0..21 in glove order, GAIN radians per
 *    raw step, OFFSET radians), `#` comments and blank lines allowed, each sensor at most
 *    once; sensors not listed keep the default map.
 *  - none (default map): raw 1..254 -> 0..90 degrees of flexion, linear.
 * Numbers in both formats are finite decimals (facepuppet/decimal.h: no hexadecimal, inf or
 * nan), as every number facepuppet reads.
 */
#ifndef FP_GLOVE_CAL_H
#define FP_GLOVE_CAL_H

#include <stddef.h>
#include <stdint.h>

#define FPG_SENSORS 22

typedef enum fpg_cal_format {
    FPG_CAL_DEFAULT = 0,
    FPG_CAL_ASR = 1,
    FPG_CAL_GAIN_OFFSET = 2
} fpg_cal_format;

typedef struct fpg_cal {
    fpg_cal_format format;
    float gain[FPG_SENSORS];    /* radians per 8-bit raw step */
    float offset[FPG_SENSORS];  /* radians */
    uint32_t used;              /* bit i: sensor i is calibrated to something (gain != 0) */
} fpg_cal;

/** asr line i calibrates glove sensor FPG_ASR_LINE_SENSOR[i]. */
extern const int FPG_ASR_LINE_SENSOR[FPG_SENSORS];

/** Sensor i's name in the glove's order (shared/docs/devices.md: "ThumbRotate" ..
 *  "WristYaw"); "?" outside 0..FPG_SENSORS-1. Static strings. [any-thread] */
const char *fpg_sensor_name(int i);

/** The format's name for a person ("asr two-point", "gain/offset", "default map").
 *  [any-thread] */
const char *fpg_cal_format_name(fpg_cal_format f);

/** Fill *cal with the default map (raw 1..254 -> 0..pi/2). Never fails. */
void fpg_cal_default(fpg_cal *cal);

/** Load a calibration file (format detected). Returns 0, or a negative errno code
 *  (-ENOENT, -EISDIR, -ENXIO and the like for the file, -EBADMSG for bad content (exit 65),
 *  including a gain or offset that is not finite as a float) after writing "FILE:LINE: what"
 *  (or "FILE: what") to err.
 *  [any-thread, reentrant] */
int fpg_cal_load(const char *path, fpg_cal *cal, char *err, size_t errlen);

/** Angle in radians of sensor i for an 8-bit-scale raw value (may be fractional). */
static inline float fpg_cal_angle(const fpg_cal *cal, int i, double raw)
{
    return (float)(cal->gain[i] * raw + cal->offset[i]);
}

/** Inverse (for the emulator): the raw value, rounded and clamped to [lo, hi], that the glove
 *  sends for `radians` at `scale` raw units per 8-bit step (1 for 8-bit, 16 for 16-bit).
 *  An unused sensor gives the middle of the range. *clamped (may be NULL) tells whether the
 *  angle lay outside the range. */
int fpg_cal_inverse(const fpg_cal *cal, int i, double radians, double scale, int lo, int hi,
                    int *clamped);

#endif
