/*
 * test_eventlog.c: the event-log writer and reader (core/eventlog): bit-exact round trips of
 * every event type, crash safety, and reader errors naming line and column.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "fp_eventlog.h"

#include <errno.h>
#include <float.h>
#include <ftw.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

/* The extreme times the format holds (fp_eventlog.h). */
#define FP_EVENT_TIME_MAX_FOR_TEST FP_EVENTLOG_TIME_MAX

static char tmpdir[256];

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path);
}

static int group_setup(void **state)
{
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/fp-eventlog-XXXXXX", base && *base ? base : "/tmp");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    return nftw(tmpdir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
}

static void tmp_path(char *buf, size_t len, const char *name)
{
    snprintf(buf, len, "%s/%s", tmpdir, name);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(fputs(text, f) >= 0, 1);
    assert_int_equal(fclose(f), 0);
}

/* xorshift64*, for reproducible "random" floats. */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint64_t rng(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}

static float random_finite_float(void)
{
    for (;;) {
        uint32_t bits = (uint32_t)(rng() >> 32);
        float f;
        memcpy(&f, &bits, sizeof f);
        if (isfinite(f)) return f;
    }
}

static fp_event make(int type, int64_t t, int hand)
{
    fp_event e;
    memset(&e, 0, sizeof e);
    static const uint32_t sizes[] = {0, sizeof(fp_event_joint_angles),
                                     sizeof(fp_event_joint_positions), sizeof(fp_event_wrist_pose),
                                     sizeof(fp_event_button), sizeof(fp_event_status)};
    e.header.size = sizes[type];
    e.header.type = (uint16_t)type;
    e.header.time_ns = t;
    e.header.hand = hand;
    return e;
}

/* Every event type, odd floats, every status code, every escape, extreme times. */
static size_t build_events(fp_event *ev, size_t cap)
{
    size_t n = 0;
    static const float odd[] = {0.0f, -0.0f, 1e-45f, -1e-45f, FLT_MIN, FLT_MAX, -FLT_MAX,
                                0.1f, 3.14159265f, 1.0f / 3.0f, 16777217.0f, -123.456f};
    /* angles: full mask with odd values, a partial mask with zeros where invalid */
    ev[n] = make(FP_EVENT_JOINT_ANGLES, -FP_EVENT_TIME_MAX_FOR_TEST, FP_HAND_LEFT);
    ev[n].angles.valid = (1u << FP_GLOVE_SENSORS) - 1;
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        ev[n].angles.radians[i] = odd[i % (sizeof odd / sizeof odd[0])];
    n++;
    ev[n] = make(FP_EVENT_JOINT_ANGLES, 0, FP_HAND_RIGHT);
    ev[n].angles.valid = 0x07fffe;
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        ev[n].angles.radians[i] = (ev[n].angles.valid >> i & 1) ? random_finite_float() : 0.0f;
    n++;
    /* positions, wrist */
    for (int k = 0; k < 3; k++) {
        ev[n] = make(FP_EVENT_JOINT_POSITIONS, 1000 + k, k % 2);
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int c = 0; c < 3; c++) ev[n].positions.mm[j][c] = random_finite_float();
        n++;
        ev[n] = make(FP_EVENT_WRIST_POSE, 1000 + k, k % 2);
        for (int c = 0; c < 3; c++) ev[n].wrist.position_mm[c] = random_finite_float();
        for (int c = 0; c < 4; c++) ev[n].wrist.rotation[c] = odd[(k + c) % 12];
        n++;
    }
    /* buttons, with header source and flags set */
    for (uint32_t b = 0; b < 3; b++) {
        ev[n] = make(FP_EVENT_BUTTON, 5000 + b, -1);
        ev[n].button.button = 1u << b;
        ev[n].button.down = b & 1;
        ev[n].button.mask = 7u ^ (1u << b);
        ev[n].header.source = 42 + b;
        ev[n].header.flags = (uint16_t)(b == 2 ? 0xffff : b);
        n++;
    }
    ev[n] = make(FP_EVENT_BUTTON, 6000, FP_HAND_RIGHT);
    ev[n].button = (fp_event_button){ev[n].header, UINT32_MAX, UINT32_MAX, UINT32_MAX};
    n++;
    /* status: every code, an unknown one, every escape, the longest text */
    static const char *const texts[] = {
        "", "plain", "quote \" backslash \\ newline \n cr \r tab \t",
        "ctl \x01\x02\x1f del \x7f", "utf-8 caf\xc3\xa9 \xe2\x86\x92 # not a comment",
        "  leading and trailing  "};
    for (uint32_t code = 1; code <= 7; code++) {
        ev[n] = make(FP_EVENT_STATUS, FP_EVENT_TIME_MAX_FOR_TEST - 7 + code, code == 7 ? FP_HAND_LEFT : -1);
        ev[n].status.code = code == 7 ? 99 : code;
        snprintf(ev[n].status.text, sizeof ev[n].status.text, "%s", texts[code % 6]);
        n++;
    }
    ev[n] = make(FP_EVENT_STATUS, -5, -1);
    ev[n].status.code = FP_STATUS_WARNING;
    memset(ev[n].status.text, '"', sizeof ev[n].status.text - 1); /* 115 bytes, all escaped */
    n++;
    assert_true(n <= cap);
    return n;
}

static void roundtrip_every_type_bit_exact(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "all.fplog");
    fp_event ev[64];
    size_t n = build_events(ev, 64);
    char err[256];
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);
    assert_int_equal(fp_eventlog_writer_comment(w, "slate 1 take 3\nsecond line"), 0);
    for (size_t i = 0; i < n; i++) assert_int_equal(fp_eventlog_writer_write(w, &ev[i]), 0);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);
    assert_null(w);

    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
        /* header line 1, comment line 2: events from line 3 */
        assert_int_equal(fp_eventlog_reader_line(r), (long)i + 3);
        if (memcmp(&got, &ev[i], sizeof got) != 0) fail_msg("event %zu differs after the round trip", i);
    }
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    assert_int_equal(fp_eventlog_reader_truncated_line(r), 0);
    fp_eventlog_reader_close(&r);
    assert_null(r);
}

static void roundtrip_random_floats(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "floats.fplog");
    enum { EVENTS = 1600 }; /* 100,800 floats */
    static float want[EVENTS][FP_HAND_JOINTS][3];
    char err[256];
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);
    for (int k = 0; k < EVENTS; k++) {
        fp_event e = make(FP_EVENT_JOINT_POSITIONS, k, FP_HAND_RIGHT);
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int c = 0; c < 3; c++) want[k][j][c] = e.positions.mm[j][c] = random_finite_float();
        assert_int_equal(fp_eventlog_writer_write(w, &e), 0);
    }
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    for (int k = 0; k < EVENTS; k++) {
        assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
        assert_memory_equal(got.positions.mm, want[k], sizeof want[k]);
    }
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    fp_eventlog_reader_close(&r);
}

static void writer_rejects_bad_events_and_writes_nothing(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "reject.fplog");
    char err[256];
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);

    fp_event e = make(FP_EVENT_JOINT_POSITIONS, 1, FP_HAND_LEFT);
    e.positions.mm[20][2] = NAN;
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);
    assert_non_null(strstr(fp_eventlog_writer_error(w), "float 63 is not finite"));
    assert_non_null(strstr(fp_eventlog_writer_error(w), path));
    e.positions.mm[20][2] = INFINITY;
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);

    e = make(FP_EVENT_BUTTON, 1, 2);
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);
    assert_non_null(strstr(fp_eventlog_writer_error(w), "hand 2"));
    e = make(FP_EVENT_BUTTON, 1, -1);
    e.header.type = 9;
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);
    e = make(FP_EVENT_JOINT_ANGLES, 1, 0);
    e.angles.valid = 1u << FP_GLOVE_SENSORS;
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);
    e = make(FP_EVENT_WRIST_POSE, 1, 0);
    e.header.size = sizeof(fp_event_header);
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);
    e = make(FP_EVENT_STATUS, 1, -1);
    memset(e.status.text, 'a', sizeof e.status.text); /* no NUL */
    assert_int_equal(fp_eventlog_writer_write(w, &e), -EINVAL);

    e = make(FP_EVENT_BUTTON, 77, -1);
    e.button.button = FP_BUTTON_MIDDLE;
    assert_int_equal(fp_eventlog_writer_write(w, &e), 0);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);

    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
    assert_memory_equal(&got, &e, sizeof got);
    assert_int_equal(fp_eventlog_reader_line(r), 2); /* nothing was written before it */
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    fp_eventlog_reader_close(&r);
}

/* Each line is on disk as soon as write returns; a cut last line is skipped and reported. */
static void crash_safety(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "crash.fplog");
    char err[256];
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);
    fp_event ev[4];
    for (int i = 0; i < 4; i++) {
        ev[i] = make(FP_EVENT_WRIST_POSE, 100 * i, FP_HAND_RIGHT);
        ev[i].wrist.position_mm[0] = (float)i + 0.25f;
        ev[i].wrist.rotation[0] = 1;
        assert_int_equal(fp_eventlog_writer_write(w, &ev[i]), 0);
    }
    /* Read while the writer is still open (no close, no explicit flush). */
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    for (int i = 0; i < 4; i++) {
        assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
        assert_memory_equal(&got, &ev[i], sizeof got);
    }
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    fp_eventlog_reader_close(&r);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);

    /* Cut the file in the middle of its last line, as a crash would. */
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fclose(f);
    assert_int_equal(truncate(path, size - 7), 0);
    r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
        assert_memory_equal(&got, &ev[i], sizeof got);
    }
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    assert_int_equal(fp_eventlog_reader_truncated_line(r), 5);
    fp_eventlog_reader_close(&r);
}

static void comments_blank_lines_crlf_tabs(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "comments.fplog");
    write_text(path, "# facepuppet-eventlog 1\r\n"
                     "# a comment\n"
                     "\n"
                     "   # an indented comment\n"
                     "  \t\n"
                     "12\tbutton  -\t4 1 5 \r\n"
                     "# end\n");
    char err[256];
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
    assert_int_equal(fp_eventlog_reader_line(r), 6);
    assert_int_equal(got.header.type, FP_EVENT_BUTTON);
    assert_int_equal(got.header.size, sizeof(fp_event_button));
    assert_int_equal(got.header.time_ns, 12);
    assert_int_equal(got.header.hand, -1);
    assert_int_equal(got.button.button, FP_BUTTON_RIGHT);
    assert_int_equal(got.button.down, 1);
    assert_int_equal(got.button.mask, FP_BUTTON_LEFT | FP_BUTTON_RIGHT);
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    fp_eventlog_reader_close(&r);
}

/* Opens `body` (after a valid header unless it starts with '#') and expects the first next()
 * to fail with "PATH:LINE:COL: " followed by `reason`. */
static void expect_read_error(const char *name, const char *body, int line, int col,
                              const char *reason)
{
    char path[512], text[2048], want[700], err[512];
    tmp_path(path, sizeof path, name);
    snprintf(text, sizeof text, "# facepuppet-eventlog 1\n%s", body);
    write_text(path, text);
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    int rc;
    while ((rc = fp_eventlog_reader_next(r, &got)) == 1) {}
    assert_int_equal(rc, -EBADMSG);
    snprintf(want, sizeof want, "%s:%d:%d: %s", path, line, col, reason);
    const char *msg = fp_eventlog_reader_error(r);
    if (strncmp(msg, want, strlen(want)) != 0)
        fail_msg("message \"%s\"\n   expected \"%s...\"", msg, want);
    assert_int_equal(fp_eventlog_reader_next(r, &got), -EBADMSG); /* sticky */
    fp_eventlog_reader_close(&r);
}

static void reader_errors_name_line_and_column(void **state)
{
    expect_read_error("e1", "# c\n100 jump left\n", 3, 5, "unknown event type \"jump\"");
    expect_read_error("e2", "100 wrist left 1 2 x3 1 0 0 0\n", 2, 20, "bad number \"x3\"");
    expect_read_error("e3", "100 wrist left 1 2 inf 1 0 0 0\n", 2, 20, "a wrist coordinate in mm is \"inf\", not a finite");
    expect_read_error("e4", "100 button - 1 1\n", 2, 17, "line ends where mask was expected");
    expect_read_error("e5", "100 button - 1 1 1 zz\n", 2, 20, "unexpected \"zz\"");
    expect_read_error("e6", "100 button middle 1 1 1\n", 2, 12, "unknown hand \"middle\"");
    expect_read_error("e7", "5 button - 1 1 1\n1e3 button - 1 1 1\n", 3, 1, "bad time \"1e3\"");
    expect_read_error("e8", "100 status - warning \"abc\n", 2, 22, "status text has no closing quote");
    expect_read_error("e9", "100 status - warning \"a\\qb\"\n", 2, 24, "unknown escape \\q");
    expect_read_error("e10", "100 status - sleepy \"\"\n", 2, 14, "unknown status code \"sleepy\"");
    expect_read_error("e11", "100 button - -1 1 1\n", 2, 14, "bad button \"-1\"");
    expect_read_error("e12", "100 button - 1 1 1 flags=70000\n", 2, 26, "flags 70000 beyond 16 bits");
    expect_read_error("e13", "100 angles left 0x400000 0\n", 2, 17, "valid mask 0x400000 has bits beyond");
    expect_read_error("e14", "100 button - 1 1 1 source=1 source=2\n", 2, 29, "unexpected \"source=2\"");
    expect_read_error("e15", "99999999999999999999 button - 1 1 1\n", 2, 1, "time 99999999999999999999 out of range");
    /* a name the writer would refuse (fuzz_eventlog found one read and not written back) */
    expect_read_error("e16", "100 channel - jaw\x01open 0.5\n", 2, 18, "channel name with byte 0x01");
    expect_read_error("e17", "100 channel - jaw\xc3\xa9 0.5\n", 2, 18, "channel name with byte 0xc3");
    /* a line past 64 KiB (a file of NULs a crash left, a hostile one): refused as it passes
     * the limit, not read whole (3 GiB of NULs after the header took 3 GB of memory, then read
     * as "no events"); terminated or not, NULs or text */
    char path[512], err[512];
    tmp_path(path, sizeof path, "e18");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("# facepuppet-eventlog 1\n100 button - 1 1 1\n", f);
    for (int i = 0; i < 70000; i++) fputc(i % 2 ? 0 : 'x', f);
    fclose(f);
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
    assert_int_equal(fp_eventlog_reader_next(r, &got), -EBADMSG);
    char want[600];
    snprintf(want, sizeof want, "%s:3:65537: a line longer than 65536 bytes", path);
    if (strncmp(fp_eventlog_reader_error(r), want, strlen(want)))
        fail_msg("message \"%s\"", fp_eventlog_reader_error(r));
    fp_eventlog_reader_close(&r);
}

/* Floats are decimals, as every number facepuppet reads: strtof's hexadecimal floats were
 * read ("0x1p3" as 8), now a bad number naming line and column; inf and nan stay "not a
 * finite number"; every decimal form still reads, bit for bit as strtof gives it. */
static void reader_floats_are_decimals(void **state)
{
    (void)state;
    expect_read_error("h1", "100 wrist left 1 2 0x1p3 1 0 0 0\n", 2, 20,
                      "bad number \"0x1p3\" for a wrist coordinate in mm");
    expect_read_error("h2", "100 wrist left 1 2 3 -0X1.8P0 0 0 0\n", 2, 22,
                      "bad number \"-0X1.8P0\" for a quaternion component");
    expect_read_error("h3", "100 wrist left 0x10 2 3 1 0 0 0\n", 2, 16,
                      "bad number \"0x10\" for a wrist coordinate in mm");
    expect_read_error("h4", "100 wrist left 1 2 3 1 0 0 nan\n", 2, 28,
                      "a quaternion component is \"nan\", not a finite number");
    expect_read_error("h5", "100 wrist left 1 infinity 3 1 0 0 0\n", 2, 18,
                      "a wrist coordinate in mm is \"infinity\", not a finite number");
    char path[512], err[256];
    tmp_path(path, sizeof path, "decimals.fplog");
    write_text(path, "# facepuppet-eventlog 1\n"
                     "100 wrist left +1.5 .5 5. -0 1e-05 2E+2 -.25e1\n");
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event got;
    assert_int_equal(fp_eventlog_reader_next(r, &got), 1);
    const float *p = got.wrist.position_mm, *q = got.wrist.rotation;
    assert_true(p[0] == 1.5f && p[1] == 0.5f && p[2] == 5.0f);
    assert_true(q[0] == 0.0f && signbit(q[0]));
    assert_true(q[1] == strtof("1e-05", NULL) && q[2] == 200.0f && q[3] == -2.5f);
    assert_int_equal(fp_eventlog_reader_next(r, &got), 0);
    fp_eventlog_reader_close(&r);
}

/* Times near the int64 limits: before, INT64_MIN and INT64_MAX read back, and the replay's
 * "time minus the first time" overflowed (signed overflow, then times running backwards).
 * Now the reader refuses |TIME| > FP_EVENTLOG_TIME_MAX with FILE:LINE:COLUMN, the writer
 * refuses to write one, and the extremes that are accepted differ without overflow. */
static void times_near_int64_limits_refused(void **state)
{
    (void)state;
    expect_read_error("t1", "0 button - 1 1 1\n9223372036854775807 button - 1 1 1\n", 3, 1,
                      "time 9223372036854775807 out of range");
    expect_read_error("t2", "-9223372036854775808 button - 1 1 1\n", 2, 1,
                      "time -9223372036854775808 out of range");
    expect_read_error("t3", "  1000000000000000001 button - 1 1 1\n", 2, 3,
                      "time 1000000000000000001 out of range");
    expect_read_error("t4", "-1000000000000000001\tstatus - connected \"\"\n", 2, 1,
                      "time -1000000000000000001 out of range");
    expect_read_error("t5", "-99999999999999999999 button - 1 1 1\n", 2, 1,
                      "time -99999999999999999999 out of range");

    /* the extremes themselves read, and their difference is exact */
    char path[512], err[512];
    tmp_path(path, sizeof path, "t_ok.fplog");
    write_text(path, "# facepuppet-eventlog 1\n-1000000000000000000 button - 1 1 1\n"
                     "1000000000000000000 button - 1 0 0\n");
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    fp_event a, b;
    assert_int_equal(fp_eventlog_reader_next(r, &a), 1);
    assert_int_equal(fp_eventlog_reader_next(r, &b), 1);
    assert_int_equal(fp_eventlog_reader_next(r, &b), 0);
    fp_eventlog_reader_close(&r);
    assert_true(a.header.time_ns == -FP_EVENTLOG_TIME_MAX);
    assert_true(b.header.time_ns - a.header.time_ns == 2 * FP_EVENTLOG_TIME_MAX);

    /* the writer refuses what the reader would refuse, and writes nothing for it */
    tmp_path(path, sizeof path, "t_w.fplog");
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);
    fp_event ev = make(FP_EVENT_BUTTON, INT64_MAX, -1);
    assert_int_equal(fp_eventlog_writer_write(w, &ev), -EINVAL);
    assert_non_null(strstr(fp_eventlog_writer_error(w), "beyond"));
    ev.header.time_ns = INT64_MIN;
    assert_int_equal(fp_eventlog_writer_write(w, &ev), -EINVAL);
    ev.header.time_ns = FP_EVENTLOG_TIME_MAX;
    assert_int_equal(fp_eventlog_writer_write(w, &ev), 0);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);
    r = fp_eventlog_reader_open(path, err, sizeof err);
    assert_non_null(r);
    assert_int_equal(fp_eventlog_reader_next(r, &a), 1);
    assert_true(a.header.time_ns == FP_EVENTLOG_TIME_MAX);
    assert_int_equal(fp_eventlog_reader_next(r, &a), 0);
    fp_eventlog_reader_close(&r);
}

/* FP_EVENTLOG_EXCL: an existing file is refused with -EEXIST and left as it was. */
static void writer_exclusive_create(void **state)
{
    (void)state;
    char path[512], err[512];
    tmp_path(path, sizeof path, "excl.fplog");
    write_text(path, "precious\n");
    fp_eventlog_writer *w = NULL;
    assert_int_equal(fp_eventlog_writer_create(path, FP_EVENTLOG_EXCL, &w, err, sizeof err),
                     -EEXIST);
    assert_null(w);
    assert_non_null(strstr(err, path));
    FILE *f = fopen(path, "r");
    char line[64] = "";
    assert_non_null(fgets(line, sizeof line, f));
    fclose(f);
    assert_string_equal(line, "precious\n");
    assert_int_equal(fp_eventlog_writer_create(path, 0, &w, err, sizeof err), 0);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);
}

static void reader_rejects_other_files(void **state)
{
    char path[512], err[512], want[700];
    tmp_path(path, sizeof path, "notalog.csv");
    write_text(path, "frame,timestamp_us\n1,2\n");
    assert_null(fp_eventlog_reader_open(path, err, sizeof err));
    snprintf(want, sizeof want, "%s:1:1: not a facepuppet event log", path);
    assert_non_null(strstr(err, want));

    tmp_path(path, sizeof path, "v2.fplog");
    write_text(path, "# facepuppet-eventlog 2\n");
    assert_null(fp_eventlog_reader_open(path, err, sizeof err));
    snprintf(want, sizeof want, "%s:1:23: unsupported event-log version \"2\"", path);
    assert_non_null(strstr(err, want));

    tmp_path(path, sizeof path, "missing.fplog");
    assert_null(fp_eventlog_reader_open(path, err, sizeof err));
    snprintf(want, sizeof want, "%s: cannot open", path);
    assert_non_null(strstr(err, want));

    tmp_path(path, sizeof path, "nodir/x.fplog");
    assert_null(fp_eventlog_writer_open(path, err, sizeof err));
    assert_non_null(strstr(err, "cannot create"));
}

static void type_and_status_names(void **state)
{
    assert_string_equal(fp_eventlog_type_name(FP_EVENT_WRIST_POSE), "wrist");
    assert_null(fp_eventlog_type_name(0));
    assert_string_equal(fp_eventlog_type_name(FP_EVENT_CHANNEL), "channel");
    assert_null(fp_eventlog_type_name(FP_EVENT_CHANNEL + 1));
    assert_string_equal(fp_eventlog_status_name(FP_STATUS_END_OF_STREAM), "end-of-stream");
    assert_null(fp_eventlog_status_name(7));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(roundtrip_every_type_bit_exact),
        cmocka_unit_test(roundtrip_random_floats),
        cmocka_unit_test(writer_rejects_bad_events_and_writes_nothing),
        cmocka_unit_test(crash_safety),
        cmocka_unit_test(comments_blank_lines_crlf_tabs),
        cmocka_unit_test(reader_errors_name_line_and_column),
        cmocka_unit_test(reader_floats_are_decimals),
        cmocka_unit_test(times_near_int64_limits_refused),
        cmocka_unit_test(writer_exclusive_create),
        cmocka_unit_test(reader_rejects_other_files),
        cmocka_unit_test(type_and_status_names),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
