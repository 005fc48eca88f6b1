/*
 * glove_decode.h: the pure part of the CyberGlove input (no fd, no threads, no host): the
 * record decoder with its resynchronisation, and raw values -> calibrated angles. Private to
 * plugins/input-cyberglove; tests/cyberglove/test_glove_decode.c feeds it bytes directly.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Wire formats (shared/docs/devices.md, "CyberGlove"):
 *  - 8-bit record (streamed `S` or polled `G`): the command byte, one byte per sensor
 *    (1..255: the glove never sends 0 inside a record), then with `U 1` (timestamp on) five
 *    timestamp bytes, with status on one status byte (bit 0: glove plugged into its box),
 *    then 0x00 -- or, instead of the 0x00, an error pair `e` `g`|`s` and 0x00.
 *  - a bare error message `e` X 0x00 (X one of ? g s n y): the box answers, no record.
 *  - 16-bit frame (CyberGlove III, `1eu` `1S`): 0D 0A 00, an ASCII timestamp of 8..16
 *    characters of digits, ':', ' ' or '.', 'S', then 22 big-endian 16-bit values in
 *    1..4094 (entering the calibration as v / 16, the 8-bit scale).
 * Bytes that start no unit are skipped one at a time until one decodes (resynchronisation);
 * the skipped count is reported before the unit that follows them (or at the end of a feed).
 * A unit cut across two feeds waits in the decoder for the rest.
 *
 * Thread rules: a decoder is single-threaded (the input thread's); the functions are
 * reentrant across decoders. No allocation.
 */
#ifndef FP_GLOVE_DECODE_H
#define FP_GLOVE_DECODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "glove_cal.h"

#define FPG_DECODE_CAP 1024 /* bytes held between feeds; far above the longest unit (51) */

/** What the decoder found. */
typedef enum fpg_unit_kind {
    FPG_UNIT_RECORD = 1, /* a record or frame: raw, plugged, errc */
    FPG_UNIT_ERROR = 2,  /* a bare error message `e` X 0x00: errc = X */
    FPG_UNIT_NOISE = 3   /* `noise` bytes skipped while resynchronising */
} fpg_unit_kind;

typedef struct fpg_unit {
    fpg_unit_kind kind;
    int nraw;                  /* RECORD: sensors in raw (18 or 22 for 8-bit, 22 for 16-bit) */
    double raw[FPG_SENSORS];   /* RECORD: wire order, 8-bit scale (16-bit values / 16) */
    bool plugged;              /* RECORD: status bit 0, true without a status byte */
    int errc;                  /* RECORD: 'g' or 's' of a trailing error pair, else 0;
                                  ERROR: the code byte */
    size_t noise;              /* NOISE: bytes skipped */
} fpg_unit;

/** Decoder state; fill with fpg_decoder_init. */
typedef struct fpg_decoder {
    int bits;        /* 8 or 16 */
    int sensors;     /* 8-bit records: 18 or 22 */
    bool ts_on;      /* 8-bit records carry 5 timestamp bytes */
    bool status_on;  /* 8-bit records carry a status byte */
    bool status_seen; /* set after init where the box never said whether U is on (U 1 and ?U
                         unanswered): each record shows it, a byte 0..7 (docs/devices.md:
                         bits plugged, wrist switch, light) before the terminator or error
                         pair being the status byte; status_on is then ignored */
    uint8_t acc[FPG_DECODE_CAP];
    size_t len;      /* bytes waiting in acc */
} fpg_decoder;

/** Start a decoder for this wire format (bits 8 or 16; sensors 18 or 22 for 8-bit). */
void fpg_decoder_init(fpg_decoder *d, int bits, int sensors, bool ts_on, bool status_on);

/** Called for each unit, in wire order; u is valid during the call only. */
typedef void (*fpg_unit_fn)(void *user, const fpg_unit *u);

/** Append n bytes and report every complete unit (and the noise between) to fn. */
void fpg_decoder_feed(fpg_decoder *d, const uint8_t *data, size_t n, fpg_unit_fn fn, void *user);

/** The joint-angle event fields for one record: for each of the record's sensors (wire
 *  order; an 18-sensor glove skips the 4 DIP/abduction sensors it lacks) that the calibration
 *  uses, radians[i] = fpg_cal_angle and bit i of *valid. An angle that is not finite (a gain
 *  so large that gain * raw leaves float range) is left 0 and invalid: nothing non-finite is
 *  ever pushed. Returns the number of sensors dropped that way. */
int fpg_angles_from_raw(const fpg_cal *cal, const fpg_unit *u, float radians[FPG_SENSORS],
                        uint32_t *valid);

#endif
