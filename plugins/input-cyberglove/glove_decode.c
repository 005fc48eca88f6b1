/*
 * glove_decode.c: CyberGlove record decoder and raw -> angle conversion (glove_decode.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "glove_decode.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* Glove sensor of each of an 18-sensor glove's values (no DIJ of index..pinkie). */
static const int DIJ_SKIP[18] = {0, 1, 2, 3, 4, 5, 7, 8, 10, 11, 12, 14, 15, 16, 18, 19, 20, 21};

void fpg_decoder_init(fpg_decoder *d, int bits, int sensors, bool ts_on, bool status_on)
{
    memset(d, 0, sizeof *d);
    d->bits = bits;
    d->sensors = sensors;
    d->ts_on = ts_on;
    d->status_on = status_on;
}

int fpg_decoder_set_order(fpg_decoder *d, int n, const uint8_t *order)
{
    if (n < 1 || n > FPG_SENSORS)
        return -EINVAL;
    for (int k = 0; k < n; k++)
        if (order[k] >= FPG_SENSORS || (k && order[k] <= order[k - 1]))
            return -EINVAL;
    d->sensors = n;
    d->has_order = true;
    memcpy(d->order, order, (size_t)n);
    return 0;
}

/* An error pair e g|s and 0x00 at a[0..4)? 1 yes, 0 need more bytes, -1 no. */
static int error_pair(const uint8_t *a, size_t len)
{
    if (len < 1 || a[0] != 'e')
        return len < 1 ? 0 : -1;
    if (len < 3)
        return 0;
    return (a[1] == 'g' || a[1] == 's') && a[2] == 0 ? 1 : -1;
}

/* Where the box never said whether the status byte is on (status_seen): is there one in the
 * record at a[0..len), whose values (and timestamp) end before a[at]? 1 yes, 0 no, -1 need
 * more bytes. A byte 1..7 there is a status; a 0 is the terminator, or a status 0 (the glove
 * out of its box) when the terminator or an error pair follows it; `final` (no more bytes
 * are coming now: a polled record's answer is over) reads a 0 at the end as the terminator. */
static int status_here(const uint8_t *a, size_t len, size_t at, bool final)
{
    if (len < at + 1)
        return -1;
    if (a[at] != 0)
        return a[at] <= 7;
    if (len < at + 2)
        return final ? 0 : -1;
    int pair = a[at + 1] == 0 ? 1 : error_pair(a + at + 1, len - at - 1);
    return pair == 0 ? (final ? 0 : -1) : pair > 0;
}

/* Try to decode one 8-bit unit at a[0..len). Returns >0 bytes consumed, 0 need more,
 * -1 not a unit here (skip a byte). Where the status byte was unknown, three records in a
 * row read alike settle it for the records after them (d->status_on). */
static int decode8(fpg_decoder *d, const uint8_t *a, size_t len, bool final, fpg_unit *u)
{
    const size_t n = (size_t)d->sensors;
    if (a[0] == 'e') {   /* a bare error: `e` X 0x00 */
        if (len < 3)
            return 0;
        if (a[2] != 0 || a[1] == 0 || !strchr("?gsny", a[1]))
            return -1;
        u->kind = FPG_UNIT_ERROR;
        u->errc = a[1];
        return 3;
    }
    if (a[0] != 'S' && a[0] != 'G')
        return -1;
    if (len >= 2 && a[1] == 'e') { /* S|G e g|s 0x00: the error in place of the values */
        int pair = error_pair(a + 1, len - 1);
        if (pair == 0)
            return 0;
        if (pair > 0) {
            u->kind = FPG_UNIT_ERROR;
            u->errc = a[2];
            return 4;
        }
    }
    size_t avail = len < 1 + n ? len : 1 + n;
    for (size_t i = 1; i < avail; i++)
        if (a[i] == 0)
            return -1;
    bool status = d->status_on;
    if (d->status_seen) {
        int here = status_here(a, len, 1 + n + (d->ts_on ? 5 : 0), final);
        if (here < 0)
            return 0;
        status = here > 0;
    }
    const size_t body = 1 + n + (d->ts_on ? 5 : 0) + (status ? 1 : 0);
    if (len < body + 1)
        return 0;
    int errc = 0;
    size_t used;
    if (a[body] == 0) {
        used = body + 1;
    } else if (a[body] == 'e') {
        if (len < body + 3)
            return 0;
        if ((a[body + 1] != 'g' && a[body + 1] != 's') || a[body + 2] != 0)
            return -1;
        errc = a[body + 1];
        used = body + 3;
    } else {
        return -1;
    }
    if (d->status_seen) { /* three records in a row that agree settle it */
        d->status_votes = d->status_votes && d->status_on == status ? d->status_votes + 1 : 1;
        d->status_on = status;
        if (d->status_votes >= 3)
            d->status_seen = false;
    }
    u->kind = FPG_UNIT_RECORD;
    u->nraw = (int)n;
    u->order = d->has_order ? d->order : NULL;
    for (size_t i = 0; i < n; i++)
        u->raw[i] = a[1 + i];
    u->plugged = status ? (a[body - 1] & 1) != 0 : true;
    u->errc = errc;
    return (int)used;
}

static bool ts_char(uint8_t c) { return (c >= '0' && c <= '9') || c == ':' || c == ' ' || c == '.'; }

/* 16-bit frame: 0D 0A 00, ASCII timestamp (8..16 chars), 'S', 22 x BE16. */
static int decode16(const uint8_t *a, size_t len, fpg_unit *u)
{
    static const uint8_t hdr[3] = {0x0D, 0x0A, 0x00};
    for (size_t i = 0; i < 3; i++) {
        if (i >= len)
            return 0;
        if (a[i] != hdr[i])
            return -1;
    }
    size_t k = 3;
    for (; k < len && k < 3 + 17; k++) {
        if (a[k] == 'S')
            break;
        if (!ts_char(a[k]))
            return -1;
    }
    if (k >= 3 + 17)
        return -1;
    if (k >= len)
        return 0;
    if (k - 3 < 8)
        return -1;
    size_t need = k + 1 + 2 * FPG_SENSORS;
    if (len < need)
        return 0;
    for (int i = 0; i < FPG_SENSORS; i++) {
        unsigned v = (unsigned)a[k + 1 + 2 * i] << 8 | a[k + 2 + 2 * i];
        if (v < 1 || v > 4094)
            return -1;
        u->raw[i] = v / 16.0;
    }
    u->kind = FPG_UNIT_RECORD;
    u->nraw = FPG_SENSORS;
    u->order = NULL;
    u->plugged = true;
    u->errc = 0;
    return (int)need;
}

static void noise(size_t n, fpg_unit_fn fn, void *user)
{
    fpg_unit u;
    memset(&u, 0, sizeof u);
    u.kind = FPG_UNIT_NOISE;
    u.noise = n;
    fn(user, &u);
}

/* fpg_decoder_feed and fpg_decoder_settle: `final`, no more bytes are coming now. */
static void feed(fpg_decoder *d, const uint8_t *data, size_t n, bool final, fpg_unit_fn fn, void *user)
{
    fpg_unit u;
    do { /* (once at least: a settle feeds nothing new) */
        size_t take = FPG_DECODE_CAP - d->len;
        if (take > n)
            take = n;
        if (take) { /* (data is NULL for a settle) */
            memcpy(d->acc + d->len, data, take);
            d->len += take;
            data += take;
            n -= take;
        }
        size_t pos = 0, skipped = 0;
        while (pos < d->len) {
            int r = d->bits == 16 ? decode16(d->acc + pos, d->len - pos, &u)
                                  : decode8(d, d->acc + pos, d->len - pos, final && !n, &u);
            if (r == 0)
                break;
            if (r < 0) {
                pos++;
                skipped++;
                continue;
            }
            if (skipped) {
                noise(skipped, fn, user);
                skipped = 0;
            }
            fn(user, &u);
            pos += (size_t)r;
        }
        if (skipped)
            noise(skipped, fn, user);
        memmove(d->acc, d->acc + pos, d->len - pos);
        d->len -= pos;
        if (d->len == FPG_DECODE_CAP) {   /* cannot happen with well-formed limits; stay safe */
            noise(d->len, fn, user);
            d->len = 0;
        }
    } while (n);
}

void fpg_decoder_feed(fpg_decoder *d, const uint8_t *data, size_t n, fpg_unit_fn fn, void *user)
{
    feed(d, data, n, false, fn, user);
}

void fpg_decoder_settle(fpg_decoder *d, fpg_unit_fn fn, void *user)
{
    feed(d, NULL, 0, true, fn, user);
}

int fpg_angles_from_raw(const fpg_cal *cal, const fpg_unit *u, float radians[FPG_SENSORS],
                        uint32_t *valid)
{
    int dropped = 0;
    *valid = 0;
    memset(radians, 0, FPG_SENSORS * sizeof *radians);
    for (int k = 0; k < u->nraw && k < FPG_SENSORS; k++) {
        int i = u->order ? u->order[k] : u->nraw == FPG_SENSORS ? k : u->nraw == 18 ? DIJ_SKIP[k] : -1;
        if (i < 0 || i >= FPG_SENSORS)
            continue;
        if (!(cal->used & (1u << i)))
            continue;
        float a = fpg_cal_angle(cal, i, u->raw[k]);
        if (!isfinite(a)) {
            dropped++;
            continue;
        }
        radians[i] = a;
        *valid |= 1u << i;
    }
    return dropped;
}

void fpg_lenmeter_feed(fpg_lenmeter *m, const uint8_t *data, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        uint8_t b = data[i];
        if (m->prev == 0 && (b == 'S' || b == 'G')) {
            if (m->started)
                m->seen = m->run;
            m->started = true;
            m->run = 0;
        }
        if (m->run < 1 << 20)
            m->run++;
        m->prev = b;
    }
}

bool fpg_line_too_slow(int baud, double rate_hz, int record_bytes, char *text, size_t len)
{
    if (baud <= 0 || record_bytes <= 0)
        return false;
    int most = baud / (10 * record_bytes); /* whole records a second */
    if (rate_hz <= most)
        return false;
    snprintf(text, len, "baud=%d carries at most %d records/s (%d bytes), not rate=%g: set rate=%d",
             baud, most, record_bytes, rate_hz, most > 1 ? most : 1); /* (short: a status) */
    return true;
}

/* The box's error replies (docs/devices.md: `e?` unknown command, `eg` glove not plugged,
 * `en` bad number, `es` sampling too fast, `ey` sync too fast) as read_reply_n's codes (glove_decode.h). */
int fpg_box_error_code(uint8_t c)
{
    switch (c) {
    case '?': return -ENOTSUP;
    case 'g': return -ENODEV;
    case 'n': return -EINVAL;
    case 's': return -ERANGE;
    case 'y': return -EBUSY;
    default: return 0;
    }
}

/* What a read_reply_n code means, for a message. */
const char *fpg_reply_text(int r)
{
    switch (r) {
    case -ENOTSUP: return "e?: the box does not know the command";
    case -ENODEV: return "eg: glove not plugged into its box";
    case -EINVAL: return "en: the box refused the number";
    case -ERANGE: return "es: sampling too fast";
    case -EBUSY: return "ey: sync too fast";
    case -ETIMEDOUT: return "no reply";
    default: return strerror(-r);
    }
}

/* An optional query or command the box did not answer with a value: silence or an error
 * reply (a minimal box, or a glove pulled out of its box since ?G). */
bool fpg_unanswered(int r)
{
    return r == -ETIMEDOUT || r == -ENOTSUP || r == -ENODEV || r == -EINVAL || r == -ERANGE ||
           r == -EBUSY;
}

int fpg_line_timeout_ms(int baud, int record_bytes, int at_least_ms)
{
    long line_ms = baud > 0 ? (long)(3.0 * 10.0 * (record_bytes + 1) * 1000.0 / baud + 0.5) : 0;
    return line_ms > at_least_ms ? (int)line_ms : at_least_ms;
}
