/*
 * test_glove_decode.c: the CyberGlove record decoder (plugins/input-cyberglove/glove_decode.h)
 * fed byte-exact records directly, without a pseudo-terminal: 8-bit records with and without
 * timestamp and status bytes, trailing and bare error messages, 16-bit frames, garbage
 * between records (resynchronisation), records split across reads; raw -> angle never
 * yields a non-finite angle; calibration values beyond float range are refused with
 * FILE:LINE.
 */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "glove_cal.h"
#include "fp_test_support.h"
#include "glove_decode.h"

#define MAX_UNITS 64

typedef struct sink {
    fpg_unit u[MAX_UNITS];
    int n;
} sink;

static void collect(void *user, const fpg_unit *u)
{
    sink *s = user;
    assert_true(s->n < MAX_UNITS);
    s->u[s->n++] = *u;
}

/* An 8-bit record: cmd, n sensor bytes (first + i), optional 5 timestamp bytes and a status
 * byte, then 0x00 or the error pair `e` errc 0x00. Returns its length. */
static size_t rec8(uint8_t *b, char cmd, int n, int first, bool ts, int status, int errc)
{
    size_t k = 0;
    b[k++] = (uint8_t)cmd;
    for (int i = 0; i < n; i++) b[k++] = (uint8_t)(first + i);
    if (ts) {
        const uint8_t t[5] = {0x00, 0x12, 0x34, 0x00, 0x56}; /* any bytes, zeros included */
        memcpy(b + k, t, 5);
        k += 5;
    }
    if (status >= 0) b[k++] = (uint8_t)status;
    if (errc) {
        b[k++] = 'e';
        b[k++] = (uint8_t)errc;
    }
    b[k++] = 0x00;
    return k;
}

/* A 16-bit frame: 0D 0A 00, timestamp text, 'S', 22 big-endian values v[i]. */
static size_t frame16(uint8_t *b, const char *stamp, const unsigned v[FPG_SENSORS])
{
    size_t k = 0;
    b[k++] = 0x0D;
    b[k++] = 0x0A;
    b[k++] = 0x00;
    memcpy(b + k, stamp, strlen(stamp));
    k += strlen(stamp);
    b[k++] = 'S';
    for (int i = 0; i < FPG_SENSORS; i++) {
        b[k++] = (uint8_t)(v[i] >> 8);
        b[k++] = (uint8_t)(v[i] & 0xFF);
    }
    return k;
}

static void expect_record(const fpg_unit *u, int n, int first, bool plugged, int errc)
{
    assert_int_equal(u->kind, FPG_UNIT_RECORD);
    assert_int_equal(u->nraw, n);
    for (int i = 0; i < n; i++) assert_true(u->raw[i] == first + i);
    assert_int_equal(u->plugged, plugged);
    assert_int_equal(u->errc, errc);
}

static void test_8bit_plain(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, false);
    uint8_t b[64];
    size_t len = rec8(b, 'S', 22, 1, false, -1, 0);
    assert_int_equal(len, 24);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, len, collect, &s);
    assert_int_equal(s.n, 1);
    expect_record(&s.u[0], 22, 1, true, 0);
    assert_int_equal(d.len, 0);
}

static void test_8bit_timestamp_status(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 18, true, true);
    uint8_t b[256];
    size_t k = rec8(b, 'G', 18, 100, true, 0x01, 0);   /* plugged */
    assert_int_equal(k, 1 + 18 + 5 + 1 + 1);
    k += rec8(b + k, 'G', 18, 50, true, 0x00, 0);      /* status bit clear: unplugged */
    k += rec8(b + k, 'S', 18, 7, true, 0x03, 'g');     /* trailing `eg` */
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 3);
    expect_record(&s.u[0], 18, 100, true, 0);
    expect_record(&s.u[1], 18, 50, false, 0);
    expect_record(&s.u[2], 18, 7, true, 'g');
}

/* status_seen (the box never said whether U is on): each record shows it, a byte 1..7
 * before the terminator or the error pair; without one the glove counts as plugged. */
static void test_8bit_status_seen(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, false);
    d.status_seen = true;
    uint8_t b[256];
    size_t k = rec8(b, 'S', 22, 10, false, 0x01, 0);   /* status: plugged */
    k += rec8(b + k, 'S', 22, 20, false, -1, 0);       /* none */
    k += rec8(b + k, 'S', 22, 30, false, 0x06, 'g');   /* status, not plugged, then `eg` */
    k += rec8(b + k, 'S', 22, 40, false, -1, 's');     /* none, then `es` */
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 4);
    expect_record(&s.u[0], 22, 10, true, 0);
    expect_record(&s.u[1], 22, 20, true, 0);
    expect_record(&s.u[2], 22, 30, false, 'g');
    expect_record(&s.u[3], 22, 40, true, 's');
    assert_int_equal(d.len, 0);
}

/* A status 0 (the glove out of its box) where the box never said whether U is on: the 0
 * followed by the terminator or an error pair is the status, not the end; three records in
 * a row read alike settle the layout. */
static void test_8bit_status_zero_seen(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, false);
    d.status_seen = true;
    uint8_t b[512];
    size_t k = rec8(b, 'S', 22, 10, false, 0x00, 0);   /* status 0, then the terminator */
    k += rec8(b + k, 'S', 22, 20, false, 0x00, 'g');   /* status 0, then `eg` */
    k += rec8(b + k, 'S', 22, 30, false, 0x01, 0);     /* plugged again */
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 3);
    expect_record(&s.u[0], 22, 10, false, 0);
    expect_record(&s.u[1], 22, 20, false, 'g');
    expect_record(&s.u[2], 22, 30, true, 0);
    assert_int_equal(d.len, 0);
    /* three read with a status byte: settled, so a record cut after its status 0 waits */
    assert_false(d.status_seen);
    assert_true(d.status_on);
    s.n = 0;
    k = rec8(b, 'S', 22, 40, false, 0x00, 0);
    fpg_decoder_feed(&d, b, k - 1, collect, &s);
    assert_int_equal(s.n, 0);
    fpg_decoder_feed(&d, b + k - 1, 1, collect, &s);
    assert_int_equal(s.n, 1);
    expect_record(&s.u[0], 22, 40, false, 0);
}

/* A polled answer without a status byte, where the box never said: the 0 at its end could
 * be a status 0 until the line stays quiet (fpg_decoder_settle), then it is the terminator. */
static void test_8bit_settle(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 18, false, false);
    d.status_seen = true;
    uint8_t b[64];
    size_t k = rec8(b, 'G', 18, 60, false, -1, 0);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 0);
    assert_int_equal(d.len, k);
    fpg_decoder_settle(&d, collect, &s);
    assert_int_equal(s.n, 1);
    expect_record(&s.u[0], 18, 60, true, 0);
    assert_int_equal(d.len, 0);
    fpg_decoder_settle(&d, collect, &s); /* nothing held: nothing reported */
    assert_int_equal(s.n, 1);
}

/* `S` `e` `g` 0x00: a box that sends the error in place of the record's values. */
static void test_error_in_place_of_record(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, true);
    uint8_t b[128] = {'S', 'e', 'g', 0x00, 'G', 'e', 's', 0x00};
    size_t k = 8 + rec8(b + 8, 'S', 22, 3, false, 0x01, 0);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 3);
    assert_int_equal(s.u[0].kind, FPG_UNIT_ERROR);
    assert_int_equal(s.u[0].errc, 'g');
    assert_int_equal(s.u[1].kind, FPG_UNIT_ERROR);
    assert_int_equal(s.u[1].errc, 's');
    expect_record(&s.u[2], 22, 3, true, 0);
}

/* Fewer sensors sampled than the glove has (?N, the software mask ?M): the record carries
 * those, and each value lands on its own sensor. */
static void test_sampled_order(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, false);
    const uint8_t bad[3] = {4, 4, 9};
    assert_int_equal(fpg_decoder_set_order(&d, 3, bad), -EINVAL);   /* not increasing */
    const uint8_t far[1] = {22};
    assert_int_equal(fpg_decoder_set_order(&d, 1, far), -EINVAL);
    assert_int_equal(fpg_decoder_set_order(&d, 0, far), -EINVAL);
    assert_int_equal(d.sensors, 22);
    const uint8_t order[5] = {0, 4, 7, 20, 21};
    assert_int_equal(fpg_decoder_set_order(&d, 5, order), 0);
    uint8_t b[32];
    size_t k = rec8(b, 'S', 5, 100, false, -1, 0);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 1);
    expect_record(&s.u[0], 5, 100, true, 0);
    fpg_cal cal;
    fpg_cal_default(&cal);
    float rad[FPG_SENSORS];
    uint32_t valid;
    assert_int_equal(fpg_angles_from_raw(&cal, &s.u[0], rad, &valid), 0);
    uint32_t want = 0;
    for (int i = 0; i < 5; i++) want |= 1u << order[i];
    assert_int_equal(valid, want & cal.used);
    for (int i = 0; i < 5; i++)
        if (cal.used & (1u << order[i]))
            assert_float_equal(rad[order[i]], fpg_cal_angle(&cal, order[i], 100 + i), 1e-6);
}

static void test_bare_errors(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, false);
    const uint8_t b[] = {'e', 's', 0x00, 'e', 'g', 0x00, 'e', '?', 0x00};
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, sizeof b, collect, &s);
    assert_int_equal(s.n, 3);
    assert_int_equal(s.u[0].kind, FPG_UNIT_ERROR);
    assert_int_equal(s.u[0].errc, 's');
    assert_int_equal(s.u[1].errc, 'g');
    assert_int_equal(s.u[2].errc, '?');
}

static void test_16bit_frames(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 16, 22, false, false);
    unsigned v[FPG_SENSORS];
    for (int i = 0; i < FPG_SENSORS; i++) v[i] = 16u * (unsigned)(i + 1); /* raw i + 1 */
    uint8_t b[256];
    size_t k = frame16(b, "12:34:56.78", v);
    assert_int_equal(k, 3 + 11 + 1 + 44);
    v[0] = 1, v[21] = 4094; /* the extremes */
    size_t k2 = frame16(b + k, "00001234", v);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k + k2, collect, &s);
    assert_int_equal(s.n, 2);
    expect_record(&s.u[0], 22, 1, true, 0);
    assert_true(s.u[1].raw[0] == 1 / 16.0 && s.u[1].raw[21] == 4094 / 16.0);
    assert_true(s.u[1].raw[5] == 6);
    /* a value 0 (outside 1..4094) is no frame: its bytes are noise */
    v[3] = 0;
    k = frame16(b, "12:34:56.78", v);
    s.n = 0;
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 1);
    assert_int_equal(s.u[0].kind, FPG_UNIT_NOISE);
    assert_int_equal(s.u[0].noise, k);
}

static void test_garbage_resync(void **state)
{
    (void)state;
    fpg_decoder d;
    fpg_decoder_init(&d, 8, 22, false, true);
    uint8_t b[256];
    size_t k = 0;
    const uint8_t junk[] = {'x', 0x00, 0xFF, 'q', 0x00};
    memcpy(b, junk, sizeof junk);
    k += sizeof junk;
    k += rec8(b + k, 'S', 22, 30, false, 0x01, 0);
    /* a record cut short by a 0x00 inside its sensor bytes, then a whole one */
    const uint8_t cut[] = {'S', 9, 9, 0x00};
    memcpy(b + k, cut, sizeof cut);
    k += sizeof cut;
    k += rec8(b + k, 'S', 22, 60, false, 0x01, 0);
    b[k++] = 'z'; /* trailing junk, reported at the end of the feed */
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, k, collect, &s);
    assert_int_equal(s.n, 5);
    assert_int_equal(s.u[0].kind, FPG_UNIT_NOISE);
    assert_int_equal(s.u[0].noise, sizeof junk);
    expect_record(&s.u[1], 22, 30, true, 0);
    assert_int_equal(s.u[2].kind, FPG_UNIT_NOISE);
    assert_int_equal(s.u[2].noise, sizeof cut);
    expect_record(&s.u[3], 22, 60, true, 0);
    assert_int_equal(s.u[4].kind, FPG_UNIT_NOISE);
    assert_int_equal(s.u[4].noise, 1);
}

/* Every split point of two records across two reads gives the same two records. */
static void test_split_reads(void **state)
{
    (void)state;
    uint8_t b[256];
    size_t k = rec8(b, 'S', 22, 5, true, 0x01, 0);
    k += rec8(b + k, 'S', 22, 40, true, 0x01, 's');
    for (size_t cutat = 0; cutat <= k; cutat++) {
        fpg_decoder d;
        fpg_decoder_init(&d, 8, 22, true, true);
        sink s = {.n = 0};
        fpg_decoder_feed(&d, b, cutat, collect, &s);
        fpg_decoder_feed(&d, b + cutat, k - cutat, collect, &s);
        assert_int_equal(s.n, 2);
        expect_record(&s.u[0], 22, 5, true, 0);
        expect_record(&s.u[1], 22, 40, true, 's');
        assert_int_equal(d.len, 0);
    }
    /* a 16-bit frame split inside its timestamp */
    unsigned v[FPG_SENSORS];
    for (int i = 0; i < FPG_SENSORS; i++) v[i] = 160;
    k = frame16(b, "12:34:56.78", v);
    fpg_decoder d;
    fpg_decoder_init(&d, 16, 22, false, false);
    sink s = {.n = 0};
    fpg_decoder_feed(&d, b, 7, collect, &s);
    assert_int_equal(s.n, 0);
    fpg_decoder_feed(&d, b + 7, k - 7, collect, &s);
    assert_int_equal(s.n, 1);
    assert_true(s.u[0].raw[0] == 10);
}

static void test_angles_finite(void **state)
{
    (void)state;
    fpg_cal cal;
    fpg_cal_default(&cal);
    fpg_unit u = {.kind = FPG_UNIT_RECORD, .nraw = 18, .plugged = true};
    for (int i = 0; i < 18; i++) u.raw[i] = 254;
    float rad[FPG_SENSORS];
    uint32_t valid;
    assert_int_equal(fpg_angles_from_raw(&cal, &u, rad, &valid), 0);
    /* an 18-sensor glove lacks the index..pinky DIPs (6, 9, 13, 17) */
    uint32_t want = 0x3FFFFFu & ~(1u << 6 | 1u << 9 | 1u << 13 | 1u << 17);
    assert_int_equal(valid, want);
    assert_float_equal(rad[21], M_PI / 2, 1e-5);
    assert_true(rad[6] == 0);
    /* a gain that overflows float range at this raw value: left out, not infinite */
    cal.gain[3] = 3e38f;
    cal.offset[4] = INFINITY; /* even a bad offset that got in some other way */
    assert_int_equal(fpg_angles_from_raw(&cal, &u, rad, &valid), 2);
    assert_int_equal(valid, want & ~(1u << 3 | 1u << 4));
    for (int i = 0; i < FPG_SENSORS; i++) assert_true(isfinite(rad[i]));
}

static void test_cal_beyond_float(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_glove_decode_XXXXXX", path[256], want[320], err[512];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/g.cal", dir);
    fpg_cal cal;
    fp_test_write_file(path, "0 0.01 0\n3 1e39 0\n");
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), -EBADMSG);
    snprintf(want, sizeof want, "%s:2: GAIN or OFFSET beyond float range", path);
    assert_string_equal(err, want);
    fp_test_write_file(path, "# offsets too\n\n4 0.01 -5e38\n");
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), -EBADMSG);
    snprintf(want, sizeof want, "%s:3: GAIN or OFFSET beyond float range", path);
    assert_string_equal(err, want);
    /* asr two-point: a slope beyond float range on line 2 */
    fp_test_write_file(path, "0.3:46 -0.5:164\n0:46 1e39:47\n");
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), -EBADMSG);
    snprintf(want, sizeof want, "%s:2: gain or offset beyond float range", path);
    assert_string_equal(err, want);
    /* the largest float still loads */
    fp_test_write_file(path, "3 3.4e38 0\n");
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), 0);
    assert_true(cal.gain[3] > 3e38f && isfinite(cal.gain[3]));
    unlink(path);
    rmdir(dir);
}

/* Numbers in a calibration are decimals, as in every option and data file: strtod's
 * hexadecimal ("0x1p-7" read as 0.0078125), inf and nan are refused, in both formats; every
 * decimal form, and a blank after the ':' (strtod skipped it), still reads. */
static void test_cal_decimals(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_glove_decode_XXXXXX", path[256], want[320], err[512];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/g.cal", dir);
    fpg_cal cal;
    static const char *const gain_offset[] = {"3 0x1p-7 0\n", "3 0.01 0X10\n", "3 inf 0\n",
                                              "3 0.01 nan\n", "3 -infinity 0\n"};
    for (size_t i = 0; i < sizeof gain_offset / sizeof gain_offset[0]; i++) {
        char text[64];
        snprintf(text, sizeof text, "0 0.01 0\n%s", gain_offset[i]);
        fp_test_write_file(path, text);
        assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), -EBADMSG);
        snprintf(want, sizeof want, "%s:2: expected finite GAIN and OFFSET after sensor 3", path);
        assert_string_equal(err, want);
    }
    static const char *const asr[] = {"0x1p-2:46 -0.5:164", "0.3:0x2e -0.5:164",
                                      "0.3:46 nan:164", "0.3:46 -0.5:INF"};
    for (size_t i = 0; i < sizeof asr / sizeof asr[0]; i++) {
        char text[128];
        snprintf(text, sizeof text, "0.3:46 -0.5:164\n%s\n", asr[i]);
        fp_test_write_file(path, text);
        assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), -EBADMSG);
        snprintf(want, sizeof want, "%s:2: expected `rad1:raw1 rad2:raw2` (asr format), got \"%s\"",
                 path, asr[i]);
        assert_string_equal(err, want);
    }
    fp_test_write_file(path, "3 +.5E-1 -0\n4 1e-05 5.\n5\t-.25e1\t\t2E+0\n");
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), 0);
    assert_true(cal.gain[3] == 0.05f && cal.offset[3] == 0.0f && signbit(cal.offset[3]));
    assert_true(cal.gain[4] == 1e-05f && cal.offset[4] == 5.0f);
    assert_true(cal.gain[5] == -2.5f && cal.offset[5] == 2.0f);
    char text[2048] = "";
    for (int i = 0; i < FPG_SENSORS; i++) /* a blank after ':', as strtod allowed */
        snprintf(text + strlen(text), sizeof text - strlen(text), "+0.5: 10 -.5:2E2\n");
    fp_test_write_file(path, text);
    assert_int_equal(fpg_cal_load(path, &cal, err, sizeof err), 0);
    assert_float_equal(cal.gain[FPG_ASR_LINE_SENSOR[0]], -1.0 / 190, 1e-9);
    unlink(path);
    rmdir(dir);
}

/* The records' length as sent, from one record start (`S` after a 0x00) to the next, across
 * feeds: 21 for 18 values and a status byte; nothing before two starts. */
static void test_lenmeter(void **state)
{
    (void)state;
    uint8_t rec[21] = {'S'};
    memset(rec + 1, 0x40, 19); /* 18 values, status 0x40 stands for any non-zero byte */
    fpg_lenmeter m = {0};
    fpg_lenmeter_feed(&m, rec, sizeof rec - 1);
    assert_int_equal(m.seen, 0);
    fpg_lenmeter_feed(&m, rec + 20, 1); /* the terminator */
    fpg_lenmeter_feed(&m, rec, 7);      /* the next record's start */
    assert_int_equal(m.seen, 21);
}

/* 8N1: baud / 10 bytes a second. 19200 carries 76 records of 25 bytes: rate=100 is said,
 * with both figures and what to set; 115200 (460) and rate=76 are not. */
static void test_line_too_slow(void **state)
{
    (void)state;
    char text[160] = "";
    assert_true(fpg_line_too_slow(19200, 100, 25, text, sizeof text));
    assert_string_equal(text, "baud=19200 carries at most 76 records/s (25 bytes), not rate=100: set rate=76");
    assert_false(fpg_line_too_slow(19200, 76, 25, text, sizeof text));
    assert_false(fpg_line_too_slow(115200, 100, 25, text, sizeof text));
    assert_true(fpg_line_too_slow(1200, 100, 25, text, sizeof text)); /* 4.8 a second */
    assert_non_null(strstr(text, "at most 4 records/s"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_8bit_plain),
        cmocka_unit_test(test_8bit_timestamp_status),
        cmocka_unit_test(test_8bit_status_seen),
        cmocka_unit_test(test_8bit_status_zero_seen),
        cmocka_unit_test(test_8bit_settle),
        cmocka_unit_test(test_error_in_place_of_record),
        cmocka_unit_test(test_sampled_order),
        cmocka_unit_test(test_bare_errors),
        cmocka_unit_test(test_16bit_frames),
        cmocka_unit_test(test_garbage_resync),
        cmocka_unit_test(test_split_reads),
        cmocka_unit_test(test_angles_finite),
        cmocka_unit_test(test_cal_beyond_float),
        cmocka_unit_test(test_cal_decimals),
        cmocka_unit_test(test_lenmeter),
        cmocka_unit_test(test_line_too_slow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
