/*
 * glove_decode.h: the pure part of the CyberGlove input (no fd, no threads, no host): the
 * record decoder with its resynchronisation, and raw values -> calibrated angles. Private to
 * plugins/input-cyberglove; tests/cyberglove/test_glove_decode.c feeds it bytes directly.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Wire formats (shared/docs/devices.md, "CyberGlove"):
 *  - 8-bit record (streamed `S` or polled `G`): the command byte, one byte per sensor
 *    sampled (`?N` of them, the sensors of the software mask `?M` in glove order; 1..255:
 *    the glove never sends 0 inside a record), then with `D 1` (timestamp on) five
 *    timestamp bytes, with `U 1` (status on) one status byte (bit 0: glove plugged into its
 *    box; 0 is a valid status), then 0x00 -- or, instead of the 0x00, an error pair
 *    `e` `g`|`s` and 0x00.
 *  - a bare error message `e` X 0x00 (X one of ? g s n y): the box answers, no record; and
 *    the same after a record's command byte, `S`|`G` `e` `g`|`s` 0x00 (a box that sends the
 *    error in place of the record's values while the glove is out).
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

#define FPG_DECODE_CAP 1024 /* bytes held between feeds; far above the longest unit (64: a
                               16-bit frame with a 16-character timestamp) */

/** What the decoder found. */
typedef enum fpg_unit_kind {
    FPG_UNIT_RECORD = 1, /* a record or frame: raw, plugged, errc */
    FPG_UNIT_ERROR = 2,  /* a bare error message `e` X 0x00: errc = X */
    FPG_UNIT_NOISE = 3   /* `noise` bytes skipped while resynchronising */
} fpg_unit_kind;

typedef struct fpg_unit {
    fpg_unit_kind kind;
    int nraw;                  /* RECORD: values in raw (the sensors sampled for 8-bit, 22 for
                                  16-bit) */
    double raw[FPG_SENSORS];   /* RECORD: wire order, 8-bit scale (16-bit values / 16) */
    const uint8_t *order;      /* RECORD: the glove sensor (0..21) of each raw value, nraw of
                                  them (valid during the call), or NULL: the whole glove's
                                  order for 22 values, the 18-sensor glove's for 18 */
    bool plugged;              /* RECORD: status bit 0, true without a status byte */
    int errc;                  /* RECORD: 'g' or 's' of a trailing error pair, else 0;
                                  ERROR: the code byte */
    size_t noise;              /* NOISE: bytes skipped */
} fpg_unit;

/** Decoder state; fill with fpg_decoder_init. */
typedef struct fpg_decoder {
    int bits;        /* 8 or 16 */
    int sensors;     /* 8-bit records: values a record carries (the sensors sampled, 1..22) */
    bool has_order;  /* order below was set (fpg_decoder_set_order) */
    uint8_t order[FPG_SENSORS]; /* the glove sensor of each value */
    bool ts_on;      /* 8-bit records carry 5 timestamp bytes */
    bool status_on;  /* 8-bit records carry a status byte */
    bool status_seen; /* set after init where the box never said whether U is on (U 1 and ?U
                         unanswered): each record shows it, a byte 1..7 (docs/devices.md:
                         bits plugged, wrist switch, light) where the values end, or a 0
                         followed by the terminator or an error pair, being the status
                         byte; three records in a row read alike settle it (status_on,
                         status_seen cleared) */
    int status_votes; /* records in a row read with status_on's reading while status_seen */
    uint8_t acc[FPG_DECODE_CAP];
    size_t len;      /* bytes waiting in acc */
} fpg_decoder;

/** Start a decoder for this wire format (bits 8 or 16; sensors 18 or 22 for 8-bit: the
 *  glove's own order, or the 18-sensor glove's). */
void fpg_decoder_init(fpg_decoder *d, int bits, int sensors, bool ts_on, bool status_on);

/** 8-bit records that carry n values (1..22), the k-th from glove sensor order[k] (strictly
 *  increasing, each 0..21: the sensors of the box's software mask `?M`, in glove order).
 *  Returns 0, or -EINVAL (d unchanged) for n or an order outside those rules. */
int fpg_decoder_set_order(fpg_decoder *d, int n, const uint8_t *order);

/** Called for each unit, in wire order; u is valid during the call only. */
typedef void (*fpg_unit_fn)(void *user, const fpg_unit *u);

/** Append n bytes and report every complete unit (and the noise between) to fn. */
void fpg_decoder_feed(fpg_decoder *d, const uint8_t *data, size_t n, fpg_unit_fn fn, void *user);

/** No more bytes are coming for now (a polled record's answer is over): report what the
 *  bytes held decode to when nothing follows them. Only a record whose status byte is
 *  unknown (status_seen) and whose last byte is a 0 waits for one more byte to tell a
 *  status 0 from the terminator; settled, that 0 is the terminator. */
void fpg_decoder_settle(fpg_decoder *d, fpg_unit_fn fn, void *user);

/** The length of the 8-bit records a box actually sends, seen on the wire whatever the probe
 *  said: the bytes from one record's command byte (`S` or `G` right after a 0x00) to the
 *  next's. Zero-initialised; seen 0 until two such starts were seen. For the text of a box
 *  whose records never match the probe's answers ("records of 21 bytes, expected 25").
 *  Single-threaded, no allocation, no errors. */
typedef struct fpg_lenmeter {
    int run;      /* bytes since the last record start */
    int seen;     /* the last distance between two record starts; 0 none yet */
    bool started; /* a record start was seen */
    uint8_t prev; /* the byte before */
} fpg_lenmeter;

/** Count n bytes as they came from the line. */
void fpg_lenmeter_feed(fpg_lenmeter *m, const uint8_t *data, size_t n);

/** Whether a line at `baud` bits/s (8N1: 10 bits a byte) cannot carry records of
 *  record_bytes bytes at rate_hz: where it cannot, writes the warning into text (len bytes:
 *  "baud=19200 carries at most 76 records/s (25 bytes), not rate=100: set rate=76") and
 *  returns true. Pure. */
bool fpg_line_too_slow(int baud, double rate_hz, int record_bytes, char *text, size_t len);

/** The default silence (ms) after which a glove at `baud` (8N1) sending records of
 *  record_bytes bytes has stopped answering: at least 3 records' time on the line, a poll's
 *  G with each (30 bytes take 250 ms at 1200 baud), and at least at_least_ms. Pure. */
int fpg_line_timeout_ms(int baud, int record_bytes, int at_least_ms);

/** The box's error reply `e` X (docs/devices.md: `e?` unknown command, `eg` glove not
 *  plugged, `en` bad number, `es` sampling too fast, `ey` sync too fast) as a negative errno
 *  (-ENOTSUP, -ENODEV, -EINVAL, -ERANGE, -EBUSY), 0 for another X. Pure. */
int fpg_box_error_code(uint8_t c);

/** What such a code, or -ETIMEDOUT ("no reply") or another -errno, means, for a message:
 *  a static string. Pure. */
const char *fpg_reply_text(int r);

/** Whether an optional query or command went unanswered: silence (-ETIMEDOUT) or one of
 *  the box's error codes. Pure. */
bool fpg_unanswered(int r);

/** The joint-angle event fields for one record: for each of the record's sensors (wire
 *  order mapped by u->order, or without one: an 18-sensor glove skips the 4 DIJ sensors it
 *  lacks) that the calibration
 *  uses, radians[i] = fpg_cal_angle and bit i of *valid. An angle that is not finite (a gain
 *  so large that gain * raw leaves float range) is left 0 and invalid: nothing non-finite is
 *  ever pushed. Returns the number of sensors dropped that way. */
int fpg_angles_from_raw(const fpg_cal *cal, const fpg_unit *u, float radians[FPG_SENSORS],
                        uint32_t *valid);

#endif
