/*
 * test_cyberglove.c: the input-cyberglove plugin (loaded with dlopen, as the host does)
 * against the byte-exact glove emulator (fp_gloveemu, in-process on its own thread).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Waits are on conditions with generous deadlines (the machine is shared); no sleep is an
 * assertion. Figures (latency, record rate) are printed, not asserted.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "cyberglove.h"
#include "facepuppet/plugin.h"
#include "glove_cal.h"
#include "fp_stats.h"
#include "fp_test_support.h"
#include "gloveemu.h"

#define CAL_RIGHT "../shared/data/cyberglove/GloveCalibrationRight.cal"
#define CAL_LEFT "../shared/data/cyberglove/GloveCalibrationLeft.cal"
#define CSV_GRAB "../shared/data/hands/leap-motion/grab_cyberglove_like_angles_deg.csv"
#define CSV_CLAPS "../shared/data/hands/leap-motion/three-claps_cyberglove_like_angles_deg.csv"
#define WAIT_MS 8000

static const fp_input_factory *factory;
static void *plugin_so;
static char tmpdir[64];

/* ------------------------------------------------------------------------------------- */
/* Plugin and emulator helpers                                                           */

static int group_setup(void **state)
{
    (void)state;
    factory = fp_test_plugin_open("input-cyberglove.so", FP_INPUT_FACTORY_ID, &plugin_so);
    if (!factory || strcmp(factory->name, "cyberglove") != 0)
        return -1;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/fp-cyberglove-XXXXXX");
    if (!mkdtemp(tmpdir))
        return -1;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    fp_test_plugin_close(&plugin_so);
    rmdir(tmpdir);
    return 0;
}

/* Create an input from "k=v" strings (NULL-terminated). Returns the create() result. */
static int create_input(fp_test_host *f, const char *arg, fp_input **out, char *err, size_t errlen,
                        ...)
{
    fp_param params[16];
    char store[16][256];
    size_t n = 0;
    va_list ap;
    va_start(ap, errlen);
    const char *kv;
    while ((kv = va_arg(ap, const char *)) && n < 16) {
        snprintf(store[n], sizeof store[n], "%s", kv);
        char *eq = strchr(store[n], '=');
        assert_non_null(eq);
        *eq = '\0';
        params[n].key = store[n];
        params[n].value = eq + 1;
        n++;
    }
    va_end(ap);
    /* unless the test is about it, a silence timeout long enough for a loaded machine, so
     * that a scheduling stall cannot look like a glove that stopped answering */
    bool has_timeout = false;
    for (size_t i = 0; i < n; i++)
        has_timeout |= strcmp(params[i].key, "timeout") == 0;
    if (!has_timeout && n < 16) {
        params[n].key = "timeout";
        params[n].value = "3000";
        n++;
    }
    err[0] = '\0';
    return factory->create(&f->host, arg, params, n, out, err, errlen);
}

static fp_gloveemu *emu_new(fp_gloveemu_options o, const char *name)
{
    char link[256];
    snprintf(link, sizeof link, "%s/%s", tmpdir, name);
    o.link_path = link;
    fp_gloveemu *e = NULL;
    char err[512];
    int rc = fp_gloveemu_create(&o, &e, err, sizeof err);
    if (rc)
        fprintf(stderr, "emulator: %s\n", err);
    assert_int_equal(rc, 0);
    return e;
}

static void start_input(fp_input *in)
{
    char err[256] = "";
    int rc = in->start(in, err, sizeof err);
    if (rc)
        fprintf(stderr, "start: %s\n", err);
    assert_int_equal(rc, 0);
}

static void stop_input(fp_input **in)
{
    (*in)->stop(*in);
    (*in)->destroy(*in);
    *in = NULL;
}

static fp_cyberglove_stats plugin_stats(fp_input *in)
{
    const fp_cyberglove_ext *x = in->get_extension(in, FP_CYBERGLOVE_EXT_ID);
    assert_non_null(x);
    fp_cyberglove_stats s = {.size = sizeof s};
    x->get_stats(in, &s);
    return s;
}

/* Check angle events in [from, to) one by one against emulator records seq0, seq0+1, ...:
 * no record lost or invented, every measured sensor within one raw step of the angle the
 * emulator made the record from (sensors clamped to the raw range excepted). Returns the
 * number of events checked. */
static size_t check_against_records(fp_test_host *f, fp_gloveemu *e, const fpg_cal *cal,
                                    size_t from, size_t to, uint64_t seq0, int hand)
{
    size_t k = 0;
    for (size_t i = from; i < to; i++) {
        fp_event ev = fp_test_host_get(f, i);
        if (ev.header.type != FP_EVENT_JOINT_ANGLES)
            continue;
        fp_gloveemu_record r;
        assert_int_equal(fp_gloveemu_get_record(e, seq0 + k, &r), 0);
        assert_int_equal(ev.header.hand, hand);
        assert_true(ev.header.time_ns >= r.sent_ns);
        uint32_t want = r.present & cal->used;
        if (ev.angles.valid != want)
            fprintf(stderr, "event %zu: valid %#x, want %#x\n", i, ev.angles.valid, want);
        assert_int_equal(ev.angles.valid, want);
        for (int s = 0; s < 22; s++) {
            if (!(want & (1u << s)) || (r.clamped & (1u << s)))
                continue;
            double step = fabs(cal->gain[s]) / (r.bits == 16 ? 16.0 : 1.0);
            double d = fabs(ev.angles.radians[s] - r.radians[s]);
            if (d > step + 1e-5)
                fprintf(stderr, "record %llu sensor %d: got %.5f want %.5f (step %.5f)\n",
                        (unsigned long long)r.seq, s, ev.angles.radians[s], r.radians[s], step);
            assert_true(d <= step + 1e-5);
        }
        k++;
    }
    return k;
}

static void print_wire_latency(fp_test_host *f, fp_gloveemu *e, size_t from, size_t to,
                               uint64_t seq0, const char *what)
{
    double *d = calloc(to - from + 1, sizeof *d);
    size_t n = 0, k = 0;
    for (size_t i = from; i < to; i++) {
        fp_event ev = fp_test_host_get(f, i);
        if (ev.header.type != FP_EVENT_JOINT_ANGLES)
            continue;
        fp_gloveemu_record r;
        if (fp_gloveemu_get_record(e, seq0 + k++, &r) == 0)
            d[n++] = (ev.header.time_ns - r.sent_ns) / 1e3;
    }
    if (n)
        printf("  %s: emulator write -> plugin read: median %.1f us, p99 %.1f us (%zu records)\n",
               what, fp_median(d, n), fp_percentile(d, n, 0.99), n);
    free(d);
}

/* ------------------------------------------------------------------------------------- */
/* Tests                                                                                 */

/* Probe, 22-sensor right glove, stream mode, the real right calibration, timestamps on. */
static void test_stream_22_right_calibrated(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.sensors = 22, .recording = CSV_GRAB,
                                                   .calibration = CAL_RIGHT, .timestamps = true},
                             "g1");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "cal=" CAL_RIGHT,
                                  "rate=200", (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0);
    fp_event ce = fp_test_host_get(f, (size_t)c);
    assert_non_null(strstr(ce.status.text, "22 sensors"));
    assert_non_null(strstr(ce.status.text, "right hand"));
    assert_non_null(strstr(ce.status.text, "CyberGlove emu 1.0"));
    long end = fp_test_host_wait_angles(f, (size_t)c, 100, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;   /* records arrived, so the emulator has executed S */
    fp_gloveemu_get_stats(e, &es);
    assert_int_equal(es.streaming, 8);
    assert_true(es.status_byte);                 /* the plugin turned U on */
    assert_true(es.timestamps);
    assert_int_equal(es.period_w1, 576);         /* t 576 1 = 200 Hz */
    assert_int_equal(es.period_w2, 1);
    assert_int_equal(es.unknown, 0);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 100);
    print_wire_latency(f, e, (size_t)c, (size_t)end, es.session_seq, "stream 200 Hz");
    fp_cyberglove_stats s = plugin_stats(in);
    assert_true(s.records >= 100);
    assert_int_equal(s.noise_bytes, 0);
    assert_int_equal(s.sensors, 22);
    assert_int_equal(s.right_hand, 1);
    printf("  plugin: last byte -> event median %.1f us, p99 %.1f us over %llu records\n",
           s.latency_median_us, s.latency_p99_us, (unsigned long long)s.latency_samples);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* 18-sensor left glove, hand from ?R, default map: DIJ bits clear. */
static void test_stream_18_left_default_map(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.sensors = 18, .left = true,
                                                   .recording = CSV_CLAPS}, "g2");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "18 sensors", WAIT_MS);
    assert_true(c >= 0);
    long end = fp_test_host_wait_angles(f, (size_t)c, 60, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    fpg_cal cal;
    fpg_cal_default(&cal);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_LEFT), 60);
    fp_event ev = fp_test_host_get(f, (size_t)end - 1);
    assert_int_equal(ev.angles.valid, 0x3FFFFFu & ~((1u << 6) | (1u << 9) | (1u << 13) | (1u << 17)));
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* A box that streams with timestamps on (D at power-up) and does not answer ?D (nor the
 * `D value` command, which it still executes): the plugin turns the timestamps off with
 * `D 0` where ?D said nothing, so the records have the length it expects. Before, it took
 * the timestamps as off, found 30-byte records where it expected 25, and flapped between
 * connected and "no well-formed record" every 0.2 s, no angle ever decoded. */
static void test_timestamps_unsaid(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.sensors = 22, .recording = CSV_GRAB,
                                                   .timestamps = true, .unanswered = "D"},
                             "g17");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "hand=right",
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "22 sensors", 3 * WAIT_MS);
    assert_true(c >= 0);
    long end = fp_test_host_wait_angles(f, (size_t)c, 60, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    fpg_cal cal;
    fpg_cal_default(&cal);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 60);
    assert_int_equal(plugin_stats(in).noise_bytes, 0);
    for (long i = c; i <= end; i++) {
        fp_event ev = fp_test_host_get(f, (size_t)i);
        assert_false(ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_DISCONNECTED);
    }
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* A minimal box, as an emulator written from docs/devices.md alone may be: ?R, ?V, ?D, ?U
 * and `U 1` never answered (executed all the same: the status byte is on), only `^c` stops a
 * stream, and it streams from power-up. The glove still connects, and every record decodes
 * with the status byte the box sends (its layout from the acknowledged-or-not U, not a guess
 * that would shift every sensor by one byte). */
static void test_minimal_box(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.sensors = 22, .recording = CSV_GRAB,
                                                   .unanswered = "RVDU", .caret_stop_only = true,
                                                   .streaming_at_start = true},
                             "g9");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "hand=right",
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "22 sensors", 3 * WAIT_MS);
    assert_true(c >= 0);
    long end = fp_test_host_wait_angles(f, (size_t)c, 60, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    assert_true(es.status_byte);
    fpg_cal cal;
    fpg_cal_default(&cal);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 60);
    assert_int_equal(plugin_stats(in).noise_bytes, 0);
    stop_input(&in);
    /* a box that stops only on ^c is left stopped (the stop sends 0x03 and ^c) */
    int64_t deadline = fp_test_mono_ns() + (int64_t)WAIT_MS * 1000000;
    do {
        usleep(5000);
        fp_gloveemu_get_stats(e, &es);
    } while (es.streaming && fp_test_mono_ns() < deadline);
    assert_int_equal(es.streaming, 0);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* Occurrences of `what` in `text`. */
static int occurrences(const char *text, const char *what)
{
    int n = 0;
    for (const char *p = strstr(text, what); p; p = strstr(p + 1, what))
        n++;
    return n;
}

/* An unplug is said once to the performer, with the port: the session logs a DISCONNECTED
 * status's text itself (core/session/intents.c), so the event names the port and the plugin
 * does not log it too (before: "PATH: glove unplugged ..." from the plugin, and "cyberglove:
 * glove unplugged ..." from the session, two lines); the plugging back, which the session
 * does not log, is one line of the plugin's naming the port. */
static void said_once(fp_test_host *f, const char *path, size_t d, size_t r)
{
    const fp_event ev_d = fp_test_host_get(f, d), ev_r = fp_test_host_get(f, r);
    assert_non_null(strstr(ev_d.status.text, path));
    assert_non_null(strstr(ev_r.status.text, path));
    char log[sizeof f->log];
    pthread_mutex_lock(&f->lock);
    snprintf(log, sizeof log, "%s", f->log);
    pthread_mutex_unlock(&f->lock);
    if (occurrences(log, "unplugged") != 0 || occurrences(log, "plugged into its box again") != 1)
        fprintf(stderr, "plugin log:\n%s", log);
    assert_int_equal(occurrences(log, "unplugged"), 0);
    assert_int_equal(occurrences(log, "plugged into its box again"), 1);
    char line[256];
    snprintf(line, sizeof line, "%s: glove plugged into its box again", path);
    assert_non_null(strstr(log, line));
}

/* The glove unplugged from its box (the box keeps answering: records with the status bit
 * clear and `eg`, or `S e g 0x00` frames with error_frames) and plugged back: "unplugged",
 * no angles while out, "plugged", angles again, no line noise, no reconnection needed. */
static void unplug_cycle(fp_gloveemu_options o, const char *name)
{
    const bool error_frames = o.error_frames;
    fp_gloveemu *e = emu_new(o, name);
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0 && fp_test_host_wait_angles(f, (size_t)c, 10, WAIT_MS) > 0);
    fp_gloveemu_set_plugged(e, false);
    long d = fp_test_host_wait_status(f, (size_t)c, FP_STATUS_DISCONNECTED, "unplugged", WAIT_MS);
    assert_true(d >= 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    uint64_t target = es.records + 20;
    int64_t deadline = fp_test_mono_ns() + (int64_t)WAIT_MS * 1000000;
    while (es.records < target && fp_test_mono_ns() < deadline) {
        usleep(5000);
        fp_gloveemu_get_stats(e, &es);
    }
    if (!error_frames)
        assert_true(es.records >= target);
    else
        usleep(200000); /* (error frames are not records: 20 periods) */
    fp_gloveemu_set_plugged(e, true);
    long r = fp_test_host_wait_status(f, (size_t)d, FP_STATUS_CONNECTED, "plugged", WAIT_MS);
    assert_true(r > d);
    for (long i = d + 1; i < r; i++)
        assert_int_not_equal(fp_test_host_get(f, (size_t)i).header.type, FP_EVENT_JOINT_ANGLES);
    assert_true(fp_test_host_wait_angles(f, (size_t)r, 10, WAIT_MS) > 0);
    assert_int_equal(plugin_stats(in).noise_bytes, 0);
    assert_int_equal(plugin_stats(in).connects, 1);
    said_once(f, fp_gloveemu_path(e), (size_t)d, (size_t)r);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* Unplugged from a box that never said whether its status byte is on (U 1 and ?U go
 * unanswered): the status 0 of the records is read as such, by records with their status
 * clear and by `S e g 0x00` frames in place of records alike. */
static void test_minimal_box_unplug(void **state)
{
    (void)state;
    unplug_cycle((fp_gloveemu_options){.recording = CSV_GRAB, .loop = true, .unanswered = "RVDU"}, "g10");
    unplug_cycle((fp_gloveemu_options){.recording = CSV_GRAB, .loop = true, .unanswered = "RVDU",
                                       .error_frames = true}, "g11");
}

/* Fewer sensors sampled than the glove has (?N 19 of ?S 22, the software mask ?M saying
 * which): records of 19 values, each on its own sensor. */
static void test_sampled_fewer(void **state)
{
    (void)state;
    uint32_t mask = ((1u << 22) - 1) & ~(1u << 2 | 1u << 10 | 1u << 19);
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB, .calibration = CAL_RIGHT,
                                                   .sampled = mask}, "g12");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err,
                                  "cal=" CAL_RIGHT, "hand=right", (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "22 sensors (19 sampled)", WAIT_MS);
    assert_true(c >= 0);
    long end = fp_test_host_wait_angles(f, (size_t)c, 60, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 60);
    fp_event ev = fp_test_host_get(f, (size_t)end - 1);
    assert_int_equal(ev.angles.valid & (1u << 2 | 1u << 10), 0);
    assert_int_equal(plugin_stats(in).noise_bytes, 0);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* Poll mode: one G per record. */
static void test_poll_mode(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB,
                                                   .calibration = CAL_RIGHT}, "g3");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "mode=poll",
                                  "rate=250", "cal=" CAL_RIGHT, "hand=right", (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "poll", WAIT_MS);
    assert_true(c >= 0);
    long end = fp_test_host_wait_angles(f, (size_t)c, 50, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    assert_int_equal(es.streaming, 0);
    assert_true(es.polls >= 50);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 50);
    fp_gloveemu_record r;
    assert_int_equal(fp_gloveemu_get_record(e, es.session_seq, &r), 0);
    assert_int_equal(r.start, 'G');
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* CyberGlove III 16-bit frames; from a box that answers no query too (docs/devices.md
 * gives the III only `1eu` and `1S`). */
static void sixteen_bit(const char *unanswered, const char *name)
{
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB,
                                                   .calibration = CAL_RIGHT,
                                                   .unanswered = unanswered}, name);
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "bits=16",
                                  "cal=" CAL_RIGHT, (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "16-bit", WAIT_MS);
    assert_true(c >= 0);
    /* a 16-bit frame carries all 22 (before: "22 sensors (1 sampled)" where ?S answered) */
    fp_event ce = fp_test_host_get(f, (size_t)c);
    const char *text = ce.status.text;
    if (!strstr(text, "22 sensors, "))
        fprintf(stderr, "connected: %s\n", text);
    assert_non_null(strstr(text, "22 sensors, "));
    long end = fp_test_host_wait_angles(f, (size_t)c, 60, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    assert_int_equal(es.streaming, 16);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 60);
    fp_gloveemu_record r;
    assert_int_equal(fp_gloveemu_get_record(e, es.session_seq + 5, &r), 0);
    assert_int_equal(r.bits, 16);
    assert_int_equal(plugin_stats(in).noise_bytes, 0);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

static void test_sixteen_bit(void **state)
{
    (void)state;
    sixteen_bit(NULL, "g4");
    sixteen_bit("GSRVDU", "g13");
}

/* Calibration against numbers read off the real files by hand (independent of the parser):
 * right glove, asr line 0 (wrist yaw, sensor 21) `0.3:46 -0.5:164`: raw 105 -> -0.1;
 * line 3 (thumb rotate, sensor 0) `0:74 -0.4:98`: raw 86 -> -0.2; line 6 (index MPJ,
 * sensor 4) `0:117 -1.5:185`: raw 151 -> -0.75; line 11 (palm arch, sensor 19) `0:60 0:144`:
 * no slope, so not valid. */
static void test_calibration_asr_by_hand(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){0}, "g5");
    uint8_t raw[22];
    memset(raw, 100, sizeof raw);
    raw[21] = 105;
    raw[0] = 86;
    raw[4] = 151;
    fp_gloveemu_set_raw(e, raw);
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "cal=" CAL_RIGHT,
                                  "hand=left", (char *)NULL), 0);
    start_input(in);
    long end = fp_test_host_wait_angles(f, 0, 3, WAIT_MS);
    assert_true(end > 0);
    /* hand=left on a glove that says right: a warning, and the SPEC wins */
    assert_true(fp_test_host_wait_status(f, 0, FP_STATUS_WARNING, "hand=left but the glove says right",
                               0) >= 0);
    fp_event ev = fp_test_host_get(f, (size_t)end - 1);
    assert_int_equal(ev.header.hand, FP_HAND_LEFT);
    assert_float_equal(ev.angles.radians[21], -0.1, 1e-5);
    assert_float_equal(ev.angles.radians[0], -0.2, 1e-5);
    assert_float_equal(ev.angles.radians[4], -0.75, 1e-5);
    assert_int_equal(ev.angles.valid & (1u << 19), 0);
    assert_int_equal(ev.angles.valid, 0x3FFFFFu & ~(1u << 19));
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* A glove whose sensors send raw[], read through the calibration text cal_text, until three
 * angle events have come. Fills *run; returns the index just past the third. */
typedef struct cal_run {
    char calpath[256];
    fp_gloveemu *e;
    fp_test_host *f;
    fp_input *in;
} cal_run;

static long start_with_cal(cal_run *run, const char *name, const char *cal_text,
                           const uint8_t raw[22])
{
    snprintf(run->calpath, sizeof run->calpath, "%s/%s.cal", tmpdir, name);
    fp_test_write_file(run->calpath, cal_text);
    run->e = emu_new((fp_gloveemu_options){0}, name);
    fp_gloveemu_set_raw(run->e, raw);
    run->f = fp_test_host_new(0);
    run->in = NULL;
    char err[256], cal_kv[300];
    snprintf(cal_kv, sizeof cal_kv, "cal=%s", run->calpath);
    assert_int_equal(create_input(run->f, fp_gloveemu_path(run->e), &run->in, err, sizeof err,
                                  cal_kv, (char *)NULL), 0);
    start_input(run->in);
    long end = fp_test_host_wait_angles(run->f, 0, 3, WAIT_MS);
    assert_true(end > 0);
    return end;
}

static void finish_cal(cal_run *run)
{
    stop_input(&run->in);
    fp_test_host_free(run->f);
    fp_gloveemu_destroy(&run->e);
    unlink(run->calpath);
}

/* The gain/offset format and the default map, by hand. */
static void test_calibration_gain_and_default(void **state)
{
    (void)state;
    uint8_t raw[22];
    memset(raw, 128, sizeof raw);
    raw[0] = 100;
    raw[21] = 50;
    raw[1] = 1;
    raw[2] = 254;
    cal_run run;
    long end = start_with_cal(&run, "g6", "# sensor gain offset (radians)\n0 0.01 -0.5\n\n"
                              "21 -0.02 1.0   # wrist yaw\n", raw);
    fp_event ev = fp_test_host_get(run.f, (size_t)end - 1);
    assert_float_equal(ev.angles.radians[0], 0.5, 1e-5);
    assert_float_equal(ev.angles.radians[21], 0.0, 1e-5);
    /* unlisted sensors keep the default map: raw 1 -> 0, raw 254 -> pi/2, 128 -> 127/253 */
    assert_float_equal(ev.angles.radians[1], 0.0, 1e-6);
    assert_float_equal(ev.angles.radians[2], M_PI / 2, 1e-5);
    assert_float_equal(ev.angles.radians[5], (127.0 / 253.0) * M_PI / 2, 1e-5);
    assert_int_equal(ev.angles.valid, 0x3FFFFFu);
    finish_cal(&run);
}

/* A calibration file saved with a byte order mark (a Windows editor's) loads as the file
 * without it (before: its first line failed to parse) */
static void test_calibration_byte_order_mark(void **state)
{
    (void)state;
    FILE *in = fopen(CAL_RIGHT, "rb");
    assert_non_null(in);
    static char text[16384];
    size_t n = fread(text, 1, sizeof text - 1, in);
    fclose(in);
    assert_true(n > 0 && n < sizeof text - 1);
    char path[] = "/tmp/fp_cal_bom_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, "\xEF\xBB\xBF", 3), 3);
    assert_int_equal(write(fd, text, n), (ssize_t)n);
    close(fd);
    fpg_cal plain, marked;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &plain, cerr, sizeof cerr), 0);
    int rc = fpg_cal_load(path, &marked, cerr, sizeof cerr);
    unlink(path);
    if (rc) fail_msg("%s", cerr);
    assert_int_equal(marked.format, plain.format);
    assert_int_equal(marked.used, plain.used);
    assert_memory_equal(marked.gain, plain.gain, sizeof plain.gain);
    assert_memory_equal(marked.offset, plain.offset, sizeof plain.offset);
}

/* A gain whose angle leaves float range: the plugin pushes that sensor as invalid, never
 * an infinite angle (issue 16). */
static void test_calibration_never_infinite(void **state)
{
    (void)state;
    uint8_t raw[22];
    memset(raw, 100, sizeof raw);
    cal_run run; /* 3e38 is finite as a float, but 3e38 x raw 100 is not */
    long end = start_with_cal(&run, "g6i", "0 3e38 0\n", raw);
    for (long i = 0; i < end; i++) {
        fp_event ev = fp_test_host_get(run.f, (size_t)i);
        if (ev.header.type != FP_EVENT_JOINT_ANGLES) continue;
        assert_int_equal(ev.angles.valid, 0x3FFFFEu);
        for (int k = 0; k < 22; k++) assert_true(isfinite(ev.angles.radians[k]));
    }
    finish_cal(&run);
}

/* Glove unplugged from its box and plugged back. */
static void test_fault_unplug(void **state)
{
    (void)state;
    unplug_cycle((fp_gloveemu_options){.recording = CSV_GRAB, .loop = true}, "g7");
}

/* Cable pulled (master closed: EIO/HUP), reconnect with backoff once the link is back. */
static void test_fault_cable_pull(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB,
                                                   .calibration = CAL_RIGHT}, "g8");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "cal=" CAL_RIGHT,
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0 && fp_test_host_wait_angles(f, (size_t)c, 10, WAIT_MS) > 0);
    char before[64], after[64];
    fp_gloveemu_slave_path(e, before, sizeof before);
    assert_int_equal(fp_gloveemu_pull_cable(e), 0);
    long d = fp_test_host_wait_status(f, (size_t)c, FP_STATUS_DISCONNECTED, "cable pulled", WAIT_MS);
    assert_true(d >= 0);
    long r1 = fp_test_host_wait_status(f, (size_t)d, FP_STATUS_RECONNECTING, NULL, WAIT_MS);
    long r2 = fp_test_host_wait_status(f, (size_t)r1 + 1, FP_STATUS_RECONNECTING, NULL, WAIT_MS);
    assert_true(r1 > d && r2 > r1);   /* it keeps trying, backing off */
    assert_non_null(strstr(fp_test_host_get(f, (size_t)r2).status.text, "attempt 2"));
    assert_int_equal(fp_gloveemu_replug_cable(e), 0);
    fp_gloveemu_slave_path(e, after, sizeof after);
    long c2 = fp_test_host_wait_status(f, (size_t)r2, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c2 > r2);
    long end = fp_test_host_wait_angles(f, (size_t)c2, 30, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c2, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), 30);
    assert_int_equal(plugin_stats(in).connects, 2);
    printf("  cable pull: %s -> %s via %s\n", before, after, fp_gloveemu_path(e));
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* A box that answers with docs/devices.md's error replies, on a bare pty (fp_gloveemu answers
 * ?G with 1 when the glove is out; a box may answer `eg` instead): `?G` gets `g_reply`, `?S`
 * 22, the optional queries `e?`, `t w1 w2\r` `t_reply`; after `S`, records of `values`
 * values (none where 0), whatever ?S said. */
typedef struct error_box {
    int master;
    const char *g_reply, *t_reply;
    size_t g_len, t_len;
    int values;
    bool streaming;
    atomic_bool stop;
    pthread_t thread;
} error_box;

static void *error_box_main(void *arg)
{
    error_box *b = arg;
    uint8_t cmd[64];
    size_t have = 0;
    while (!atomic_load(&b->stop)) {
        struct pollfd p = {.fd = b->master, .events = POLLIN};
        if (poll(&p, 1, 20) <= 0) {
            if (b->streaming && b->values > 0) {
                uint8_t rec[32] = {'S'};
                memset(rec + 1, 0x40, (size_t)b->values);
                (void)!write(b->master, rec, (size_t)b->values + 2); /* (0x00 last) */
            }
            continue;
        }
        ssize_t got = read(b->master, cmd + have, sizeof cmd - have);
        if (got <= 0)
            continue;
        have += (size_t)got;
        size_t i = 0;
        while (i < have) {
            uint8_t c = cmd[i];
            if ((c == '?' || c == 'U' || c == '^') && i + 1 >= have)
                break;                                  /* its second byte is still to come */
            if (c == 't') {
                uint8_t *cr = memchr(cmd + i, '\r', have - i);
                if (!cr)
                    break;
                (void)!write(b->master, b->t_reply, b->t_len);
                i = (size_t)(cr - cmd) + 1;
            } else if (c == '?' && cmd[i + 1] == 'G') {
                (void)!write(b->master, b->g_reply, b->g_len);
                i += 2;
            } else if (c == '?' && cmd[i + 1] == 'S') {
                (void)!write(b->master, "?S\x16", 4);
                i += 2;
            } else if (c == '?' || c == 'U') {
                (void)!write(b->master, "e?", 3);
                i += 2;
            } else {
                b->streaming = c == 'S' || (b->streaming && c != 0x03 && c != '^');
                i += c == '^' ? 2 : 1;                  /* 0x03, ^c, S: nothing to answer */
            }
        }
        memmove(cmd, cmd + i, have - i);
        have -= i;
    }
    return NULL;
}

/* Start an error box behind tmpdir/NAME (the link the plugin opens, written to path). */
static void error_box_start(error_box *b, const char *name, char *path, size_t pathlen)
{
    b->master = posix_openpt(O_RDWR | O_NOCTTY);
    assert_true(b->master >= 0);
    assert_int_equal(grantpt(b->master), 0);
    assert_int_equal(unlockpt(b->master), 0);
    snprintf(path, pathlen, "%s/%s", tmpdir, name);
    unlink(path);
    assert_int_equal(symlink(ptsname(b->master), path), 0);
    atomic_store(&b->stop, false);
    assert_int_equal(pthread_create(&b->thread, NULL, error_box_main, b), 0);
}

static void error_box_stop(error_box *b, const char *path)
{
    atomic_store(&b->stop, true);
    pthread_join(b->thread, NULL);
    close(b->master);
    unlink(path);
}

/* The box's error replies are said as what they mean: `eg` to ?G is a glove out of its box
 * (before: "no answer to ?G (is the glove box on, baud 115200?)", after waiting 500 ms for
 * an answer that had come), and `es` to the sample period names the rate as too fast (before:
 * "Connection timed out", after waiting for a reply that had come); records of another length than the probe's answers make are said as
 * such at the timeout, not as a glove that stopped answering. */
static void test_box_error_replies(void **state)
{
    (void)state;
    char path[256];
    error_box b = {.g_reply = "eg", .g_len = 3, .t_reply = "t", .t_len = 2};
    error_box_start(&b, "g14", path, sizeof path);
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, path, &in, err, sizeof err, (char *)NULL), 0);
    start_input(in);
    long d = fp_test_host_wait_status(f, 0, FP_STATUS_DISCONNECTED, NULL, WAIT_MS);
    assert_true(d >= 0);
    fp_event de = fp_test_host_get(f, (size_t)d);
    const char *text = de.status.text;
    if (!strstr(text, "glove not plugged into its box"))
        fprintf(stderr, "status: %s\n", text);
    assert_non_null(strstr(text, "glove not plugged into its box"));
    assert_non_null(strstr(text, "eg"));
    assert_non_null(strstr(text, path));
    /* the plugin keeps retrying (RECONNECTING, attempt after attempt), and says the same
     * failure once (before: a DISCONNECTED line at every retry, forever) */
    long r3 = fp_test_host_wait_status(f, (size_t)d, FP_STATUS_RECONNECTING, "(attempt 3)", WAIT_MS);
    assert_true(r3 > d);
    int disconnected = 0;
    for (long i = 0; i <= r3; i++) {
        fp_event ev = fp_test_host_get(f, (size_t)i);
        disconnected += ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_DISCONNECTED;
    }
    assert_int_equal(disconnected, 1);
    stop_input(&in);
    fp_test_host_free(f);
    error_box_stop(&b, path);

    /* (streaming records it reads: CONNECTED comes with the first record) */
    error_box b2 = {.g_reply = "?G\x03", .g_len = 4, .t_reply = "es", .t_len = 3, .values = 22};
    error_box_start(&b2, "g15", path, sizeof path);
    f = fp_test_host_new(0);
    assert_int_equal(create_input(f, path, &in, err, sizeof err, "hand=right", (char *)NULL), 0);
    start_input(in);
    long cb = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, "22 sensors", WAIT_MS);
    assert_true(cb >= 0);
    /* ?V unanswered: no version in the text, and no empty field for it (before:
     * "22 sensors, right hand, 8-bit stream, " with a dangling separator) */
    fp_event cbe = fp_test_host_get(f, (size_t)cb);
    size_t cbn = strlen(cbe.status.text);
    if (cbn < 6 || strcmp(cbe.status.text + cbn - 6, "stream") != 0)
        fprintf(stderr, "connected: %s\n", cbe.status.text);
    assert_true(cbn >= 6 && strcmp(cbe.status.text + cbn - 6, "stream") == 0);
    char log[sizeof f->log];
    pthread_mutex_lock(&f->lock);
    snprintf(log, sizeof log, "%s", f->log);
    pthread_mutex_unlock(&f->lock);
    if (!strstr(log, "not acknowledged (es: sampling too fast)"))
        fprintf(stderr, "plugin log:\n%s", log);
    assert_non_null(strstr(log, "not acknowledged (es: sampling too fast)"));
    stop_input(&in);
    fp_test_host_free(f);
    error_box_stop(&b2, path);

    /* records of 18 values from a box that said 22 (?S): all line noise, and the timeout
     * says so, naming both lengths (before: "glove stopped answering (no record for 500
     * ms)"); no record was read, so no CONNECTED: the probe that answered was one more
     * attempt (before: a CONNECTED/DISCONNECTED pair at every probe) */
    error_box b3 = {.g_reply = "?G\x03", .g_len = 4, .t_reply = "t", .t_len = 2, .values = 18};
    error_box_start(&b3, "g16", path, sizeof path);
    f = fp_test_host_new(0);
    assert_int_equal(create_input(f, path, &in, err, sizeof err, "timeout=500", (char *)NULL), 0);
    start_input(in);
    d = fp_test_host_wait_status(f, 0, FP_STATUS_DISCONNECTED, NULL, WAIT_MS);
    assert_true(d >= 0);
    de = fp_test_host_get(f, (size_t)d);
    if (!strstr(text, "records of 20 bytes, expected 24"))
        fprintf(stderr, "status: %s\n", text);
    assert_non_null(strstr(text, "records of 20 bytes, expected 24"));
    assert_true(fp_test_host_wait_status(f, (size_t)d, FP_STATUS_RECONNECTING, "(attempt 3)", WAIT_MS) > d);
    assert_true(fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, 0) < 0);
    assert_true(fp_test_host_wait_status(f, (size_t)d + 1, FP_STATUS_DISCONNECTED, NULL, 0) < 0);
    assert_true(plugin_stats(in).noise_bytes > 0);
    stop_input(&in);
    fp_test_host_free(f);
    error_box_stop(&b3, path);
}

/* Garbage between records: a WARNING, every garbage byte skipped, no record lost. */
static void test_fault_garbage_resync(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB,
                                                   .calibration = CAL_RIGHT}, "g9");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "cal=" CAL_RIGHT,
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0 && fp_test_host_wait_angles(f, (size_t)c, 10, WAIT_MS) > 0);
    /* false starts ('S', 'G', 'e'), zeros, a 16-bit header, high bytes */
    static const uint8_t junk[] = {'S', 0x41, 0x00, 'G', 0x10, 0x20, 0x00, 0xff, 'e', 'x', 0x00,
                                   0x0D, 0x0A, 0x00, 'S', 'S', 0x7f, 0x80, 0x01, 0x02, 0x03,
                                   0xfe, 0x00, 0x00, 'e', 'g', 'S', 0x11, 0x22, 0x33, 0x44,
                                   0x55, 0x66, 0x77, 0x88, 0x99, 'S'};
    fp_gloveemu_inject_garbage(e, junk, sizeof junk);
    long w = fp_test_host_wait_status(f, (size_t)c, FP_STATUS_WARNING, "line noise", WAIT_MS);
    assert_true(w > c);
    long end = fp_test_host_wait_angles(f, (size_t)w, 30, WAIT_MS);
    assert_true(end > 0);
    fp_gloveemu_stats es;
    fp_gloveemu_get_stats(e, &es);
    assert_int_equal(es.garbage_sent, sizeof junk);
    fpg_cal cal;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &cal, cerr, sizeof cerr), 0);
    size_t total = 0;
    for (size_t i = (size_t)c; i < (size_t)end; i++)
        total += fp_test_host_get(f, i).header.type == FP_EVENT_JOINT_ANGLES;
    assert_int_equal(check_against_records(f, e, &cal, (size_t)c, (size_t)end, es.session_seq,
                                           FP_HAND_RIGHT), total);
    fp_cyberglove_stats s = plugin_stats(in);
    assert_int_equal(s.noise_bytes, sizeof junk);
    assert_int_equal(s.resyncs, 1);
    assert_int_equal(s.connects, 1);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* A glove that stops answering: timeout, reconnect attempts, recovery when it answers. */
static void test_fault_silence(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB}, "g10");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "timeout=300",
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0 && fp_test_host_wait_angles(f, (size_t)c, 10, WAIT_MS) > 0);
    fp_gloveemu_set_silent(e, true);
    long d = fp_test_host_wait_status(f, (size_t)c, FP_STATUS_DISCONNECTED, "stopped answering", WAIT_MS);
    assert_true(d > c);
    /* re-probed and got no answer: said as an event (RECONNECTING), the loss being said once
     * (before: a second DISCONNECTED, a second line; tests/cyberglove/test_glove_outage) */
    long d2 = fp_test_host_wait_status(f, (size_t)d + 1, FP_STATUS_RECONNECTING, "no answer", WAIT_MS);
    assert_true(d2 > d);
    for (long i = d + 1; i < d2; i++)
        assert_false(fp_test_host_get(f, (size_t)i).header.type == FP_EVENT_STATUS &&
                     fp_test_host_get(f, (size_t)i).status.code == FP_STATUS_DISCONNECTED);
    fp_gloveemu_set_silent(e, false);
    long c2 = fp_test_host_wait_status(f, (size_t)d2, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c2 > d2);
    assert_true(fp_test_host_wait_angles(f, (size_t)c2, 20, WAIT_MS) > 0);
    fp_cyberglove_stats s = plugin_stats(in);
    assert_true(s.timeouts >= 1);
    assert_int_equal(s.connects, 2);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* Slow glove (rate halved): no false alarm, events keep coming at the lower rate. */
static void test_fault_slow(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB}, "g11");
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "rate=100",
                                  (char *)NULL), 0);
    start_input(in);
    long c = fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS);
    assert_true(c >= 0 && fp_test_host_wait_angles(f, (size_t)c, 10, WAIT_MS) > 0);
    fp_gloveemu_set_slow(e, 2.0);
    size_t from = fp_test_host_count(f);
    long end = fp_test_host_wait_angles(f, from + 1, 30, WAIT_MS);   /* skip one in-flight record */
    assert_true(end > 0);
    int64_t t0 = 0, t1 = 0;
    size_t n = 0;
    for (size_t i = from + 1; i < (size_t)end; i++) {
        fp_event ev = fp_test_host_get(f, i);
        if (ev.header.type != FP_EVENT_JOINT_ANGLES)
            continue;
        if (!t0)
            t0 = ev.header.time_ns;
        t1 = ev.header.time_ns;
        n++;
    }
    double mean_ms = (t1 - t0) / 1e6 / (double)(n - 1);
    printf("  slow x2: mean interval %.1f ms (nominal 20)\n", mean_ms);
    assert_true(mean_ms > 15.0);   /* an emulator cannot send faster than its period */
    assert_int_equal(fp_test_host_wait_status(f, (size_t)c, FP_STATUS_DISCONNECTED, NULL, 0), -1);
    stop_input(&in);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

/* Two gloves on two ports at once: two instances, no shared state. */
static void test_two_gloves(void **state)
{
    (void)state;
    fp_gloveemu *el = emu_new((fp_gloveemu_options){.sensors = 18, .left = true,
                                                    .recording = CSV_CLAPS,
                                                    .calibration = CAL_LEFT}, "left");
    fp_gloveemu *er = emu_new((fp_gloveemu_options){.sensors = 22, .recording = CSV_CLAPS,
                                                    .calibration = CAL_RIGHT}, "right");
    fp_test_host *fl = fp_test_host_new(0), *fr = fp_test_host_new(0);
    fp_input *il = NULL, *ir = NULL;
    char err[256];
    assert_int_equal(create_input(fl, fp_gloveemu_path(el), &il, err, sizeof err,
                                  "cal=" CAL_LEFT, (char *)NULL), 0);
    assert_int_equal(create_input(fr, fp_gloveemu_path(er), &ir, err, sizeof err,
                                  "cal=" CAL_RIGHT, "rate=150", (char *)NULL), 0);
    start_input(il);
    start_input(ir);
    long cl = fp_test_host_wait_status(fl, 0, FP_STATUS_CONNECTED, "18 sensors, left", WAIT_MS);
    long cr = fp_test_host_wait_status(fr, 0, FP_STATUS_CONNECTED, "22 sensors, right", WAIT_MS);
    assert_true(cl >= 0 && cr >= 0);
    long endl = fp_test_host_wait_angles(fl, (size_t)cl, 60, WAIT_MS);
    long endr = fp_test_host_wait_angles(fr, (size_t)cr, 60, WAIT_MS);
    assert_true(endl > 0 && endr > 0);
    fpg_cal call, calr;
    char cerr[256];
    assert_int_equal(fpg_cal_load(CAL_LEFT, &call, cerr, sizeof cerr), 0);
    assert_int_equal(fpg_cal_load(CAL_RIGHT, &calr, cerr, sizeof cerr), 0);
    fp_gloveemu_stats sl, sr;
    fp_gloveemu_get_stats(el, &sl);
    fp_gloveemu_get_stats(er, &sr);
    assert_int_equal(check_against_records(fl, el, &call, (size_t)cl, (size_t)endl,
                                           sl.session_seq, FP_HAND_LEFT), 60);
    assert_int_equal(check_against_records(fr, er, &calr, (size_t)cr, (size_t)endr,
                                           sr.session_seq, FP_HAND_RIGHT), 60);
    assert_int_equal(sr.period_w1, 768);   /* 150 Hz: t 768 1 */
    assert_int_equal(sl.period_w1, 1152);  /* 100 Hz default */
    stop_input(&il);
    stop_input(&ir);
    fp_test_host_free(fl);
    fp_test_host_free(fr);
    fp_gloveemu_destroy(&el);
    fp_gloveemu_destroy(&er);
}

/* The line settings the plugin applied, as the emulator sees them on the master. */
static void test_line_settings(void **state)
{
    (void)state;
    const int bauds[2] = {115200, 19200};
    for (int k = 0; k < 2; k++) {
        fp_gloveemu *e = emu_new((fp_gloveemu_options){0}, "g12");
        fp_gloveemu_line l;
        assert_int_equal(fp_gloveemu_line_settings(e, &l), 0);
        assert_int_equal(l.baud, 9600);   /* power-up state: the checks below can fail */
        assert_false(l.raw);
        fp_test_host *f = fp_test_host_new(0);
        fp_input *in = NULL;
        char err[256], kv[32];
        snprintf(kv, sizeof kv, "baud=%d", bauds[k]);
        assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err,
                                      k ? kv : "mode=stream", (char *)NULL), 0);
        start_input(in);
        assert_true(fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS) >= 0);
        assert_int_equal(fp_gloveemu_line_settings(e, &l), 0);
        printf("  line: %s\n", l.text);
        assert_int_equal(l.baud, bauds[k]);
        assert_int_equal(l.ibaud, bauds[k]);
        assert_int_equal(l.data_bits, 8);
        assert_false(l.parity);
        assert_false(l.two_stop_bits);
        assert_true(l.raw);
        assert_false(l.echo);
        assert_false(l.crtscts);
        assert_true(l.clocal && l.cread);
        /* 19200 8N1 carries 1920 bytes/s: 76 of the 25-byte records, not the default
         * rate=100; said once, with the figures and what to set (before: nothing said, the
         * records falling behind). 115200 carries 460: nothing to say. */
        long said = fp_test_host_wait_status(f, 0, FP_STATUS_WARNING, "carries at most", k ? WAIT_MS : 300);
        if (k)
            assert_true(fp_test_host_wait_status(f, 0, FP_STATUS_WARNING, "baud=19200 carries at "
                        "most 76 records/s (25 bytes), not rate=100: set rate=76", 0) >= 0);
        else
            assert_true(said < 0);
        if (k)
            assert_true(fp_test_host_wait_status(f, (size_t)said + 1, FP_STATUS_WARNING,
                                                 "carries at most", 0) < 0);
        stop_input(&in);
        fp_test_host_free(f);
        fp_gloveemu_destroy(&e);
    }
}

/* Bad SPECs and bad calibration files: clear errors naming the key, file and line. */
static void expect_create_error(const char *arg, const char *kv, const char *must_contain)
{
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[512];
    int rc = create_input(f, arg, &in, err, sizeof err, kv, (char *)NULL);
    if (rc == 0 || !strstr(err, must_contain))
        fprintf(stderr, "SPEC %s,%s: rc %d, err \"%s\" (want \"%s\")\n", arg ? arg : "(null)",
                kv ? kv : "", rc, err, must_contain);
    assert_true(rc < 0);
    assert_null(in);
    assert_non_null(strstr(err, must_contain));
    fp_test_host_free(f);
}

static void test_bad_spec_and_cal(void **state)
{
    (void)state;
    expect_create_error(NULL, NULL, "missing device path");
    expect_create_error("/dev/null", "speed=9600", "unknown key `speed`");
    expect_create_error("/dev/null", "baud=12345", "baud=12345");
    expect_create_error("/dev/null", "bits=12", "bits=12");
    expect_create_error("/dev/null", "mode=push", "mode=push");
    expect_create_error("/dev/null", "hand=both", "hand=both");
    expect_create_error("/dev/null", "rate=0", "rate=0");
    expect_create_error("/dev/null", "timeout=abc", "timeout=abc");
    /* whole numbers as in every integer option: strtol took a leading blank */
    expect_create_error("/dev/null", "baud= 115200", "baud= 115200");
    expect_create_error("/dev/null", "timeout= 500", "timeout= 500");
    expect_create_error("/dev/null", "timeout=5e2", "timeout=5e2");
    expect_create_error("/dev/null", "cal=/nonexistent/glove.cal", "/nonexistent/glove.cal");
    char p[256], kv[300], want[300];
    snprintf(p, sizeof p, "%s/bad.cal", tmpdir);
    snprintf(kv, sizeof kv, "cal=%s", p);
    /* asr: line 3 malformed */
    fp_test_write_file(p, "0.3:46 -0.5:164\n0.9:73 -0.7:181\n-0.5:216 oops\n");
    snprintf(want, sizeof want, "%s:3:", p);
    expect_create_error("/dev/null", kv, want);
    /* asr: raw1 == raw2 on line 2 */
    fp_test_write_file(p, "0.3:46 -0.5:164\n0.9:73 -0.7:73\n");
    snprintf(want, sizeof want, "%s:2: raw1 equals raw2", p);
    expect_create_error("/dev/null", kv, want);
    /* asr: too few lines */
    fp_test_write_file(p, "0.3:46 -0.5:164\n0.9:73 -0.7:181\n");
    snprintf(want, sizeof want, "only 2 of 22");
    expect_create_error("/dev/null", kv, want);
    /* gain format: sensor out of range on line 2, and NaN gain on line 1 */
    fp_test_write_file(p, "0 0.01 0\n22 0.01 0\n");
    snprintf(want, sizeof want, "%s:2: sensor 22", p);
    expect_create_error("/dev/null", kv, want);
    fp_test_write_file(p, "5 nan 0\n");
    snprintf(want, sizeof want, "%s:1:", p);
    expect_create_error("/dev/null", kv, want);
    unlink(p);
    /* mode=poll with bits=16 is refused */
    fp_test_host *f = fp_test_host_new(0);
    fp_input *in = NULL;
    char err[256];
    assert_true(create_input(f, "/dev/null", &in, err, sizeof err, "bits=16", "mode=poll",
                             (char *)NULL) < 0);
    assert_non_null(strstr(err, "bits=16"));
    /* start() on a path that does not exist names it */
    assert_int_equal(create_input(f, "/nonexistent/ttyUSB9", &in, err, sizeof err, (char *)NULL),
                     0);
    assert_true(in->start(in, err, sizeof err) < 0);
    assert_non_null(strstr(err, "/nonexistent/ttyUSB9"));
    in->stop(in);   /* allowed without a successful start */
    in->destroy(in);
    /* a file that is no tty */
    assert_int_equal(create_input(f, CAL_RIGHT, &in, err, sizeof err, (char *)NULL), 0);
    assert_int_equal(in->start(in, err, sizeof err), -ENODEV); /* (66: a device that cannot be opened) */
    assert_non_null(strstr(err, "not a serial port"));
    in->destroy(in);
    fp_test_host_free(f);
}

/* Throughput and latency: the emulator streams as fast as the plugin takes records. */
static void test_throughput_and_latency(void **state)
{
    (void)state;
    fp_gloveemu *e = emu_new((fp_gloveemu_options){.recording = CSV_GRAB, .loop = true,
                                                   .fast = true, .calibration = CAL_RIGHT},
                             "g13");
    fp_test_host *f = fp_test_host_new(0);
    f->count_only = true;
    fp_input *in = NULL;
    char err[256];
    assert_int_equal(create_input(f, fp_gloveemu_path(e), &in, err, sizeof err, "cal=" CAL_RIGHT,
                                  (char *)NULL), 0);
    start_input(in);
    assert_true(fp_test_host_wait_status(f, 0, FP_STATUS_CONNECTED, NULL, WAIT_MS) >= 0);
    fp_cyberglove_stats s0 = plugin_stats(in);
    int64_t t0 = fp_test_mono_ns();
    while (fp_test_mono_ns() - t0 < 1500000000LL)
        usleep(50000);
    fp_cyberglove_stats s1 = plugin_stats(in);
    int64_t t1 = fp_test_mono_ns();
    double secs = (t1 - t0) / 1e9;
    double rate = (double)(s1.records - s0.records) / secs;
    printf("  throughput: %.0f records/s sustained over %.2f s (22 sensors, 8-bit, status byte; "
           "a 115200-baud line carries at most %.0f such records/s)\n",
           rate, secs, 11520.0 / 25.0);
    printf("  latency last byte read -> event pushed: median %.2f us, p99 %.2f us (%llu samples)\n",
           s1.latency_median_us, s1.latency_p99_us, (unsigned long long)s1.latency_samples);
    assert_true(s1.records > s0.records);
    in->stop(in);
    fp_cyberglove_stats s2 = plugin_stats(in);
    assert_int_equal(s2.noise_bytes, 0);   /* back-to-back records decode without resync */
    assert_int_equal(s2.events, s2.records);
    assert_int_equal(s2.dropped, 0);
    stop_input(&in);
    /* the log line at stop carries the same figures */
    assert_non_null(strstr(f->last_log, "latency last byte -> event median"));
    printf("  stop log: %s\n", f->last_log);
    fp_test_host_free(f);
    fp_gloveemu_destroy(&e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stream_22_right_calibrated),
        cmocka_unit_test(test_stream_18_left_default_map),
        cmocka_unit_test(test_minimal_box),
        cmocka_unit_test(test_minimal_box_unplug),
        cmocka_unit_test(test_sampled_fewer),
        cmocka_unit_test(test_poll_mode),
        cmocka_unit_test(test_sixteen_bit),
        cmocka_unit_test(test_calibration_asr_by_hand),
        cmocka_unit_test(test_calibration_gain_and_default),
        cmocka_unit_test(test_calibration_never_infinite),
        cmocka_unit_test(test_calibration_byte_order_mark),
        cmocka_unit_test(test_fault_unplug),
        cmocka_unit_test(test_fault_cable_pull),
        cmocka_unit_test(test_box_error_replies),
        cmocka_unit_test(test_timestamps_unsaid),
        cmocka_unit_test(test_fault_garbage_resync),
        cmocka_unit_test(test_fault_silence),
        cmocka_unit_test(test_fault_slow),
        cmocka_unit_test(test_two_gloves),
        cmocka_unit_test(test_line_settings),
        cmocka_unit_test(test_bad_spec_and_cal),
        cmocka_unit_test(test_throughput_and_latency),
    };
    return cmocka_run_group_tests_name("cyberglove", tests, group_setup, group_teardown);
}
