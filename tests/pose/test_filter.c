/* core/pose/fp_filter.h: the One Euro filter against its definition (Casiez, Roussel, Vogel,
 * CHI 2012), the filter keys; core/pose/fp_pose.h: each hand at the frame's time
 * (fp_pose_build_at) and the per-input filter of fp_pose_take_event_filtered. */
#define _GNU_SOURCE
#include "fp_filter.h"
#include "fp_pose.h"
#include "pose_events.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#define MS 1000000LL

/* the tracker's cutoffs in the paper's filter (no trend): its equations are checked exactly */
static const fp_filter_config tracker = {FP_FILTER_ONEEURO, FP_FILTER_MINCUTOFF, FP_FILTER_BETA,
                                         FP_FILTER_DCUTOFF, 0.0};

static uint64_t g_rng = 7;
static double gauss(void)
{
    double u[2];
    for (int i = 0; i < 2; i++) {
        uint64_t z = (g_rng += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        z ^= z >> 31;
        u[i] = ((double)(z >> 11) + 0.5) / 9007199254740992.0;
    }
    return sqrt(-2 * log(u[0])) * cos(6.283185307179586 * u[1]);
}

/* alpha = 1 / (1 + tau / Te), tau = 1 / (2 pi fc) */
static void test_alpha(void **state)
{
    (void)state;
    double tau = 1 / (2 * M_PI * 5.0), te = 0.01;
    assert_true(fabs(fp_oneeuro_alpha(5.0, te) - 1 / (1 + tau / te)) < 1e-15);
    assert_true(fp_oneeuro_alpha(1.0, 1e-3) < fp_oneeuro_alpha(1.0, 1e-2)); /* slower sampling: more weight */
    assert_true(fp_oneeuro_alpha(1.0, 100.0) > 0.998);                      /* after a long pause: follow */
}

/* The first sample passes through; a constant stays that constant. */
static void test_constant(void **state)
{
    (void)state;
    fp_oneeuro f;
    fp_oneeuro_reset(&f);
    double x[3] = {12.5, -3.25, 400.0}, out[3];
    for (int i = 0; i < 500; i++) {
        fp_oneeuro_filter(&f, &tracker, 3, 1.0, x, (int64_t)i * 9 * MS, out);
        for (int k = 0; k < 3; k++) assert_true(fabs(out[k] - x[k]) <= 1e-12 * fabs(x[k]));
        if (i == 0) assert_memory_equal(out, x, sizeof x);
    }
}

/* Steady ramps: the output trails the input by exactly the lag fp_oneeuro_lag solves (the
 * paper's equations: lambda = tau(mincutoff + beta (v + v lambda / Te))), below the bound
 * 1 / (2 pi (mincutoff + beta v)); with beta 0, by 1 / (2 pi mincutoff) at any speed. */
static void check_ramp(const fp_filter_config *c, double v_mm_s, double rate_hz)
{
    fp_oneeuro f;
    fp_oneeuro_reset(&f);
    double te = 1 / rate_hz, out = 0;
    int n = (int)(30 * rate_hz); /* 30 s: long past the 1 Hz derivative filter's settling */
    for (int i = 0; i <= n; i++) {
        double x = v_mm_s * i * te;
        fp_oneeuro_filter(&f, c, 1, 1.0, &x, llround(i * te * 1e9), &out);
    }
    double lag = (v_mm_s * n * te - out) / v_mm_s; /* seconds */
    double want = fp_oneeuro_lag(c, v_mm_s, rate_hz), bound = fp_oneeuro_lag(c, v_mm_s, 0);
    printf("ramp %.0f mm/s at %.0f Hz, mincutoff %g beta %g: lag %.3f ms (formula %.3f ms, bound %.3f ms)\n",
           v_mm_s, rate_hz, c->mincutoff, c->beta, lag * 1e3, want * 1e3, bound * 1e3);
    assert_true(fabs(lag - want) < 1e-6 * want + 1e-9);
    assert_true(want <= bound * (1 + 1e-12));
    if (c->beta == 0) assert_true(fabs(want - 1 / (2 * M_PI * c->mincutoff)) < 1e-12);
}

static void test_ramp_lag(void **state)
{
    (void)state;
    fp_filter_config still = tracker;
    still.beta = 0;
    check_ramp(&still, 100, 108);
    check_ramp(&tracker, 20, 108);
    check_ramp(&tracker, 100, 108);
    check_ramp(&tracker, 300, 57);
    check_ramp(&tracker, 300, 30);
    fp_filter_config glove = tracker;
    glove.mincutoff = FP_FILTER_GLOVE_MINCUTOFF;
    check_ramp(&glove, 200, 150);
    /* faster motion, less lag */
    assert_true(fp_oneeuro_lag(&tracker, 300, 108) < fp_oneeuro_lag(&tracker, 30, 108));
}

/* White noise on a still joint (sigma 1 mm, 108 Hz): the filter's cutoff stays near
 * mincutoff (the noise's own speed estimate raises it a little), so a third of the noise is
 * left at most (a first-order low pass at mincutoff leaves sqrt(alpha / (2 - alpha)): 0.12 at
 * 0.5 Hz) and the sample-to-sample jitter drops at least 8x. */
static void test_noise(void **state)
{
    (void)state;
    fp_oneeuro f;
    fp_oneeuro_reset(&f);
    const double rate = 108, te = 1 / rate;
    double sum2_in = 0, sum2_out = 0, step2_in = 0, step2_out = 0, prev_in[3] = {0}, prev_out[3] = {0};
    long m = 0;
    for (int i = 0; i < 20000; i++) {
        double x[3] = {gauss(), gauss(), gauss()}, out[3];
        fp_oneeuro_filter(&f, &tracker, 3, 1.0, x, llround(i * te * 1e9), out);
        if (i >= 1000) {
            for (int k = 0; k < 3; k++) {
                sum2_in += x[k] * x[k];
                sum2_out += out[k] * out[k];
                step2_in += pow(x[k] - prev_in[k], 2);
                step2_out += pow(out[k] - prev_out[k], 2);
            }
            m++;
        }
        memcpy(prev_in, x, sizeof x);
        memcpy(prev_out, out, sizeof out);
    }
    double a = fp_oneeuro_alpha(tracker.mincutoff, te);
    double sd_in = sqrt(sum2_in / (3.0 * m)), sd_out = sqrt(sum2_out / (3.0 * m));
    double jit_in = sqrt(step2_in / (3.0 * m)), jit_out = sqrt(step2_out / (3.0 * m));
    printf("still joint, 1 mm noise at 108 Hz: %.3f mm left (a %g Hz low pass leaves %.3f); "
           "sample-to-sample %.3f -> %.4f mm (%.0fx less)\n", sd_out, tracker.mincutoff,
           sqrt(a / (2 - a)), jit_in, jit_out, jit_in / jit_out);
    assert_true(fabs(sd_in - 1) < 0.03);
    assert_true(sd_out < 0.34);
    assert_true(jit_out * 8 < jit_in);
}

/* The speed raises the cutoff: a fast move is followed closely, a slow one smoothed. */
static void test_adaptive(void **state)
{
    (void)state;
    fp_filter_config c = tracker;
    c.beta = 0;
    double lag_fixed = fp_oneeuro_lag(&c, 400, 108), lag = fp_oneeuro_lag(&tracker, 400, 108);
    assert_true(lag < lag_fixed / 5);
}

/* Holt's trend (trend > 0): a steady ramp is followed exactly once the trend has settled
 * (a lag of 0, where the paper's filter at the same cutoffs trails by fp_oneeuro_lag), and a
 * still joint's noise is left about as the paper's filter leaves it: the trend adds some
 * sample-to-sample jitter, the price of the lag (FP_FILTER_TREND's table, fp_filter.h). The
 * same filter with trend 0 is the paper's bit for bit (test_ramp_lag, test_noise). */
static void test_trend(void **state)
{
    (void)state;
    fp_filter_config with = tracker, without = tracker;
    with.trend = FP_FILTER_TREND;
    const double rate = 57, te = 1 / rate, v = 80; /* a slow thumb, at a slow tracker's rate */
    fp_oneeuro f, g;
    fp_oneeuro_reset(&f);
    fp_oneeuro_reset(&g);
    double out_with = 0, out_without = 0, x = 0;
    int n = (int)(5 * rate);
    for (int i = 0; i <= n; i++) {
        x = v * i * te;
        fp_oneeuro_filter(&f, &with, 1, 1.0, &x, llround(i * te * 1e9), &out_with);
        fp_oneeuro_filter(&g, &without, 1, 1.0, &x, llround(i * te * 1e9), &out_without);
    }
    double lag_with = (x - out_with) / v, lag_without = (x - out_without) / v;
    printf("ramp %.0f mm/s at %.0f Hz: lag %.3f ms with the trend, %.1f ms without (formula %.1f)\n",
           v, rate, lag_with * 1e3, lag_without * 1e3, fp_oneeuro_lag(&without, v, rate) * 1e3);
    assert_true(fabs(lag_with) < 1e-6);
    assert_true(fabs(lag_without - fp_oneeuro_lag(&without, v, rate)) < 1e-6);
    assert_true(lag_without > 0.015); /* over a frame at 60 fps without it */
    assert_true(fp_oneeuro_lag(&with, v, rate) == 0);
    /* a sudden stop from 300 mm/s: the trend of the finished motion fades as the hand falls
     * FP_FILTER_TREND_SLACK_MM to FP_FILTER_TREND_STOP_MM behind, the output goes a little
     * past the hand (Holt's trend alone: 10.8 mm) and settles on it */
    fp_oneeuro_reset(&f);
    double past = 0, y = 0;
    for (int i = 0; i <= n + (int)(3 * rate); i++) {
        y = 300 * (i < n ? i : n) * te;
        fp_oneeuro_filter(&f, &with, 1, 1.0, &y, llround(i * te * 1e9), &out_with);
        if (i > n && out_with - y > past) past = out_with - y;
    }
    printf("a sudden stop from 300 mm/s: %.2f mm past the hand at most, %.4f mm off after 3 s\n", past,
           out_with - y);
    assert_true(past < FP_FILTER_TREND_STOP_MM + 1.5);
    assert_true(fabs(out_with - y) < 0.05);
    /* a gap: the hand away for a second after moving at 300 mm/s comes back where it left; no
     * motion is guessed across the gap (the output stays between the input and the last) */
    fp_oneeuro_reset(&f);
    int i = 0;
    for (; i <= n; i++) {
        y = 300 * i * te;
        fp_oneeuro_filter(&f, &with, 1, 1.0, &y, llround(i * te * 1e9), &out_with);
    }
    double before = out_with;
    fp_oneeuro_filter(&f, &with, 1, 1.0, &y, llround(((i - 1) * te + 1.0) * 1e9), &out_with);
    printf("back after a 1 s gap at the same place: %.3f mm off (was %.3f)\n", out_with - y, before - y);
    assert_true(fabs(out_with - y) <= fabs(before - y) + 1e-9);

    fp_oneeuro_reset(&f);
    double step2_in = 0, step2_out = 0, prev_in = 0, prev_out = 0;
    for (int i = 0; i < 20000; i++) {
        double y = gauss(), o;
        fp_oneeuro_filter(&f, &with, 1, 1.0, &y, llround(i * (1e9 / 108)), &o);
        if (i >= 1000) {
            step2_in += (y - prev_in) * (y - prev_in);
            step2_out += (o - prev_out) * (o - prev_out);
        }
        prev_in = y;
        prev_out = o;
    }
    printf("still joint, 1 mm noise at 108 Hz, trend %g Hz: sample-to-sample %.1fx less\n", with.trend,
           sqrt(step2_in / step2_out));
    assert_true(step2_out * 25 < step2_in);
}

/* The trend's fade is continuous in the sample: from a joint moving at 100 mm/s (57 Hz), the
 * next sample swept from 2 mm ahead of the smoothed position to 8 mm behind it along the
 * motion in steps of 1 um moves the output by at most 5 um a step (the slope of the fade,
 * about 0.6 mm per mm, and the low pass's alpha). A switch at one distance would jump by the
 * whole prediction, (1 - alpha) T_e |B|: about 1.7 mm here. */
static void test_trend_fade_continuous(void **state)
{
    (void)state;
    fp_filter_config with = tracker;
    with.trend = FP_FILTER_TREND;
    const double rate = 57, te = 1 / rate, v = 100;
    fp_oneeuro f;
    fp_oneeuro_reset(&f);
    double x = 0, out = 0;
    int n = (int)rate;
    for (int i = 0; i <= n; i++) {
        x = v * i * te;
        fp_oneeuro_filter(&f, &with, 1, 1.0, &x, llround(i * te * 1e9), &out);
    }
    double largest = 0, prev = NAN, first = NAN;
    for (int k = 0; k <= 10000; k++) {
        fp_oneeuro g = f;                          /* the same state, each sample in turn */
        double y = out + 2.0 - k * 1e-3, o;
        fp_oneeuro_filter(&g, &with, 1, 1.0, &y, llround((n + 1) * te * 1e9), &o);
        if (k) largest = fmax(largest, fabs(o - prev));
        else first = o;
        prev = o;
    }
    printf("the next sample swept 10 mm across the fade in 1 um steps: the output moved %.2f mm, "
           "at most %.4f mm a step\n", first - prev, largest);
    assert_true(largest < 0.005);
    assert_true(first - prev > 0.5);  /* and it does move with the sample */
}

/* A hand's joints share the fastest joint's cutoff: beside a joint moving at 400 mm/s, a
 * still joint's 1 mm step is followed as the moving joint's cutoff allows, far faster than
 * its own filter would (alone, at mincutoff); each joint's own filter otherwise: two joints
 * alike give what fp_oneeuro_filter gives each. */
static void test_shared_cutoff(void **state)
{
    (void)state;
    const double te = 1 / 108.0; /* the stamps are whole ns: the filter's T_e is near it */
    fp_oneeuro hand[2], alone;
    fp_oneeuro_reset(&hand[0]);
    fp_oneeuro_reset(&hand[1]);
    fp_oneeuro_reset(&alone);
    double x[2][3], a[3], prev_speed = 0;
    int n = 200;
    for (int i = 0; i <= n; i++) {
        int64_t t = llround(i * te * 1e9);
        double step = i == n ? 1.0 : 0.0;
        x[0][0] = 400.0 * i * te, x[0][1] = x[0][2] = 0;  /* the moving joint */
        x[1][0] = step, x[1][1] = x[1][2] = 0;               /* still, then a 1 mm step */
        a[0] = step, a[1] = a[2] = 0;
        if (i == n) prev_speed = sqrt(hand[0].dx[0] * hand[0].dx[0]);
        fp_oneeuro_filter_joints(hand, 2, &tracker, x, t);
        fp_oneeuro_filter(&alone, &tracker, 3, 1.0, a, t, a);
    }
    /* the step's share taken: alpha at the fastest joint's cutoff (its dXhat this sample) */
    double speed = hand[0].dx[0];
    double want = fp_oneeuro_alpha(tracker.mincutoff + tracker.beta * speed, hand[1].te);
    printf("a still joint's 1 mm step beside a joint at 400 mm/s: %.3f mm taken at once "
           "(alone: %.3f mm)\n", x[1][0], a[0]);
    assert_true(prev_speed > 300 && speed > 300);
    assert_true(fabs(x[1][0] - want) < 1e-12);
    assert_true(x[1][0] > 4 * a[0]);
    /* alike joints: the same as each alone, bit for bit */
    fp_oneeuro two[2], one;
    fp_oneeuro_reset(&two[0]);
    fp_oneeuro_reset(&two[1]);
    fp_oneeuro_reset(&one);
    for (int i = 0; i < 300; i++) {
        double v = 50.0 * sin(i * 0.05) + (i % 7) * 0.3;
        double y[2][3] = {{v, -v, 2 * v}, {v, -v, 2 * v}}, z[3] = {v, -v, 2 * v};
        int64_t t = (int64_t)i * 9 * MS;
        fp_oneeuro_filter_joints(two, 2, &tracker, y, t);
        fp_oneeuro_filter(&one, &tracker, 3, 1.0, z, t, z);
        assert_memory_equal(y[0], z, sizeof z);
        assert_memory_equal(y[1], z, sizeof z);
    }
}

/* A repeated stamp uses the last period; a non-finite sample resets the filter. */
static void test_stamps(void **state)
{
    (void)state;
    fp_oneeuro f;
    fp_oneeuro_reset(&f);
    double x = 0, out;
    fp_oneeuro_filter(&f, &tracker, 1, 1.0, &x, 0, &out);
    x = 1;
    fp_oneeuro_filter(&f, &tracker, 1, 1.0, &x, 10 * MS, &out);
    assert_true(fabs(f.te - 0.01) < 1e-15);
    x = 2;
    fp_oneeuro_filter(&f, &tracker, 1, 1.0, &x, 10 * MS, &out); /* the same stamp */
    assert_true(fabs(f.te - 0.01) < 1e-15);
    assert_true(isfinite(out) && out > 0 && out < 2);
    x = NAN;
    fp_oneeuro_filter(&f, &tracker, 1, 1.0, &x, 20 * MS, &out);
    assert_false(f.started);
    x = 5;
    fp_oneeuro_filter(&f, &tracker, 1, 1.0, &x, 30 * MS, &out);
    assert_true(out == 5);
}

/* The keys: defaults per kind of input, tuning, refusals. */
static void test_keys(void **state)
{
    (void)state;
    fp_filter_config c;
    char err[256];
    fp_filter_default("osc", &c);
    assert_int_equal(c.kind, FP_FILTER_AUTO);
    assert_true(c.mincutoff == FP_FILTER_MINCUTOFF && c.beta == FP_FILTER_BETA && c.dcutoff == FP_FILTER_DCUTOFF);
    assert_true(c.trend == FP_FILTER_TREND);
    fp_filter_default("cyberglove", &c);
    assert_int_equal(c.kind, FP_FILTER_ONEEURO);
    assert_true(c.mincutoff == FP_FILTER_GLOVE_MINCUTOFF && c.trend == 0);
    const char *off[] = {"replay", "take", "pedal", "fixture", NULL};
    for (int i = 0; i < 5; i++) {
        fp_filter_default(off[i], &c);
        assert_int_equal(c.kind, FP_FILTER_OFF);
    }
    assert_int_equal(fp_filter_parse("replay", NULL, NULL, NULL, NULL, NULL, &c, err, sizeof err), 0);
    assert_int_equal(c.kind, FP_FILTER_OFF);
    assert_int_equal(fp_filter_parse("replay", "oneeuro", NULL, NULL, NULL, NULL, &c, err, sizeof err), 0);
    assert_int_equal(c.kind, FP_FILTER_ONEEURO);
    assert_true(c.beta == FP_FILTER_BETA);
    assert_int_equal(fp_filter_parse("replay", "oneeuro", "2", "0.01", ".5", NULL, &c, err, sizeof err), 0);
    assert_true(c.mincutoff == 2 && c.beta == 0.01 && c.dcutoff == 0.5 && c.trend == FP_FILTER_TREND);
    assert_int_equal(fp_filter_parse("replay", "oneeuro", NULL, NULL, NULL, "0", &c, err, sizeof err), 0);
    assert_true(c.trend == 0);
    assert_int_equal(fp_filter_parse("osc", NULL, NULL, NULL, NULL, "2.5", &c, err, sizeof err), 0);
    assert_true(c.kind == FP_FILTER_AUTO && c.trend == 2.5);
    assert_int_equal(fp_filter_parse("osc", NULL, NULL, "0.02", NULL, NULL, &c, err, sizeof err), 0);
    assert_true(c.kind == FP_FILTER_AUTO && c.beta == 0.02 && c.mincutoff == FP_FILTER_MINCUTOFF);
    assert_int_equal(fp_filter_parse("replay", "auto", "1", NULL, NULL, NULL, &c, err, sizeof err), 0);
    assert_true(c.kind == FP_FILTER_AUTO && c.mincutoff == 1);
    assert_int_equal(fp_filter_parse("osc", "oneeuro", NULL, NULL, NULL, NULL, &c, err, sizeof err), 0);
    assert_int_equal(c.kind, FP_FILTER_ONEEURO);
    assert_int_equal(fp_filter_parse("osc", "off", NULL, NULL, NULL, NULL, &c, err, sizeof err), 0);
    assert_int_equal(c.kind, FP_FILTER_OFF);
    /* refusals leave *out untouched and name the key */
    fp_filter_config keep = c;
    struct { const char *f, *m, *b, *d, *t, *needle; } bad[] = {
        {"kalman", NULL, NULL, NULL, NULL, "filter=kalman"},
        {NULL, "1", NULL, NULL, NULL, "filter=oneeuro"},          /* replay: off by default */
        {"off", NULL, "0.1", NULL, NULL, "beta="},
        {"oneeuro", "0", NULL, NULL, NULL, "mincutoff=0"},
        {"oneeuro", "-1", NULL, NULL, NULL, "mincutoff=-1"},
        {"oneeuro", "nan", NULL, NULL, NULL, "mincutoff=nan"},
        {"oneeuro", "0x10", NULL, NULL, NULL, "mincutoff=0x10"},
        {"oneeuro", "1001", NULL, NULL, NULL, "mincutoff=1001"},
        {"oneeuro", NULL, "-0.1", NULL, NULL, "beta=-0.1"},
        {"oneeuro", NULL, "inf", NULL, NULL, "beta=inf"},
        {"oneeuro", NULL, "", NULL, NULL, "beta="},
        {"oneeuro", NULL, NULL, "0", NULL, "dcutoff=0"},
        {"oneeuro", NULL, NULL, NULL, "-1", "trend=-1"},
        {"oneeuro", NULL, NULL, NULL, "1e9", "trend=1e9"},
        {"off", NULL, NULL, NULL, "6", "trend="},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = 0;
        assert_int_equal(fp_filter_parse("replay", bad[i].f, bad[i].m, bad[i].b, bad[i].d, bad[i].t, &c, err, sizeof err), -EINVAL);
        assert_memory_equal(&c, &keep, sizeof c);
        if (!strstr(err, bad[i].needle)) fail_msg("%zu: '%s' lacks '%s'", i, err, bad[i].needle);
    }
    char line[512];
    fp_filter_describe(&tracker, line, sizeof line);
    assert_non_null(strstr(line, "oneeuro"));
    assert_non_null(strstr(line, "a steady motion lags"));
    printf("%s\n", line);
    fp_filter_config o = {0};
    fp_filter_describe(&o, line, sizeof line);
    assert_string_equal(line, "filter off");
    fp_filter_default("osc", &o);
    fp_filter_describe(&o, line, sizeof line);
    assert_non_null(strstr(line, "where the tracker does not smooth them"));
    assert_non_null(strstr(line, "trend=6"));
    assert_non_null(strstr(line, "without lag once its trend has settled (about 27 ms"));
    printf("%s\n", line);
}

/* ---- fp_pose at the frame's time ------------------------------------------------------- */

static fp_event positions(int hand, double x, int64_t t, uint32_t source)
{
    float mm[FP_HAND_JOINTS][3];
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        mm[j][0] = (float)(x + j);
        mm[j][1] = (float)(2 * x);
        mm[j][2] = -5.f;
    }
    fp_event ev = joints_event(hand, (const float (*)[3])mm, t);
    ev.header.source = source;
    return ev;
}

/* p with the identity calibration (mesh units = mm), no hand seen. */
static fp_pose_state *identity_pose(fp_pose_state *p)
{
    fp_calibration c = {1.0, {0, 0, 0}, {0, 0, 0, 0}, {{0, 0, 0}, {0, 0, 0}}, {0, 0, 0, 0}};
    fp_pose_init(p, 0, &c);
    return p;
}

/* Interpolated before the latest sample, predicted after it up to one period, held beyond;
 * held without an earlier sample or across a pause longer than FP_POSE_MAX_PERIOD_NS. */
static void test_frame_time(void **state)
{
    (void)state;
    static fp_pose_state ps;
    fp_pose_state *p = identity_pose(&ps);
    const int R = FP_HAND_RIGHT;
    fp_event a = positions(R, 10, 100 * MS, 0), b = positions(R, 20, 110 * MS, 0);
    fp_pose_take_event(p, &a);
    fp_pose_build_at(p, 105 * MS);
    assert_true(p->poses[R].joints[0][0] == 10.f); /* one sample: as it is */
    fp_pose_take_event(p, &b);
    /* u past the knee: FP_POSE_KNEE + (1 - FP_POSE_KNEE)(1 - e^-(u - FP_POSE_KNEE)/(1 - FP_POSE_KNEE)) */
    const double k = 1 - FP_POSE_KNEE;
    double at1 = FP_POSE_KNEE + k * (1 - exp(-(1 - FP_POSE_KNEE) / k));
    double at3 = FP_POSE_KNEE + k * (1 - exp(-(3 - FP_POSE_KNEE) / k));
    struct { int64_t t; double x; } want[] = {
        {110 * MS, 20}, {115 * MS, 25}, {119 * MS, 29},                 /* ahead, on the line */
        {120 * MS, 20 + 10 * at1}, {140 * MS, 20 + 10 * at3},           /* bent below a period */
        {105 * MS, 15}, {100 * MS, 10}, {50 * MS, 10},                  /* between, capped */
    };
    float last = 0;
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        fp_pose_build_at(p, want[i].t);
        float x = p->poses[R].joints[0][0];
        if (fabs(x - want[i].x) > 1e-5) fail_msg("at %lld ms: %.7f, want %.7f", (long long)(want[i].t / MS), x, want[i].x);
        assert_true(x <= 30.f);                              /* never beyond one period ahead */
        if (i >= 1 && i <= 4) assert_true(x > last);         /* still moving in a gap */
        last = x;
        assert_true(fabsf(p->poses[R].joints[3][0] - (x + 3)) < 1e-5f);
        assert_true(fabsf(p->poses[R].joints[0][1] - 2 * x) < 1e-5f);
        assert_true(p->poses[R].joints[0][2] == -5.f);
        assert_int_equal(p->poses[R].time_ns, 110 * MS); /* the latest event's time */
    }
    fp_pose_build_at(p, 10000 * MS);                     /* stopped long ago: held */
    assert_true(fabsf(p->poses[R].joints[0][0] - 30.f) < 1e-5f);
    fp_pose_build(p); /* the latest sample as it is */
    assert_true(p->poses[R].joints[0][0] == 20.f);
    /* a pause longer than FP_POSE_MAX_PERIOD_NS: held */
    fp_event c = positions(R, 50, 110 * MS + FP_POSE_MAX_PERIOD_NS + 1, 0);
    fp_pose_take_event(p, &c);
    fp_pose_build_at(p, 110 * MS + FP_POSE_MAX_PERIOD_NS + 5 * MS);
    assert_true(p->poses[R].joints[0][0] == 50.f);
    /* a disconnect forgets the earlier sample */
    fp_event d = positions(R, 60, 110 * MS + FP_POSE_MAX_PERIOD_NS + 10 * MS, 0);
    fp_pose_take_event(p, &d);
    fp_event st;
    memset(&st, 0, sizeof st);
    st.header.type = FP_EVENT_STATUS;
    st.header.hand = R;
    st.status.code = FP_STATUS_DISCONNECTED;
    fp_pose_take_event(p, &st);
    fp_event e = positions(R, 70, 110 * MS + FP_POSE_MAX_PERIOD_NS + 20 * MS, 0);
    fp_pose_take_event(p, &e);
    fp_pose_build_at(p, 110 * MS + FP_POSE_MAX_PERIOD_NS + 25 * MS);
    assert_true(p->poses[R].joints[0][0] == 70.f);
}

/* Joint angles: each sensor valid in both samples extrapolated before forward kinematics;
 * the hand at the frame's time equals forward kinematics of the extrapolated angles. */
static void test_frame_time_angles(void **state)
{
    (void)state;
    static fp_pose_state ps, qs;
    fp_pose_state *p = identity_pose(&ps), *q = identity_pose(&qs);
    fp_event ev[3];
    memset(ev, 0, sizeof ev);
    for (int i = 0; i < 3; i++) {
        ev[i].header.size = sizeof ev[i].angles;
        ev[i].header.type = FP_EVENT_JOINT_ANGLES;
        ev[i].header.hand = FP_HAND_LEFT;
        ev[i].header.time_ns = (int64_t)i * 8 * MS;
        ev[i].angles.valid = (1u << FP_SENSOR_INDEX_MPJ) | (1u << FP_SENSOR_MIDDLE_PIJ);
        ev[i].angles.radians[FP_SENSOR_INDEX_MPJ] = 0.1f * (float)i;
        ev[i].angles.radians[FP_SENSOR_MIDDLE_PIJ] = 0.5f;
    }
    fp_pose_take_event(p, &ev[0]);
    fp_pose_take_event(p, &ev[1]);
    fp_pose_build_at(p, 12 * MS); /* half a period ahead: index MCP 0.15 */
    ev[2].angles.radians[FP_SENSOR_INDEX_MPJ] = 0.15f;
    fp_pose_take_event(q, &ev[2]);
    fp_pose_build(q);
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++)
            assert_true(fabsf(p->poses[FP_HAND_LEFT].joints[j][k] - q->poses[FP_HAND_LEFT].joints[j][k]) < 1e-4f);
}

/* A 57 Hz and a 108 Hz stream read at 60 frames a second: a new pose every frame (the last
 * sample held repeats one every 20th frame at 57 Hz). */
static void stream_at_60(double hz, int *repeated_held, int *repeated_at)
{
    static fp_pose_state ps, held;
    fp_pose_state *p = identity_pose(&ps);
    identity_pose(&held);
    float last_at = NAN, last_held = NAN;
    int next = 0;
    *repeated_held = *repeated_at = 0;
    for (int k = 0; k < 600; k++) {
        int64_t now = llround(k * 1e9 / 60);
        for (; llround(next * 1e9 / hz) <= now; next++) {
            int64_t t = llround(next * 1e9 / hz);
            fp_event ev = positions(FP_HAND_RIGHT, 100 * sin(t * 1e-9), t, 0);
            fp_pose_take_event(p, &ev);
            fp_pose_take_event(&held, &ev);
        }
        fp_pose_build_at(p, now);
        fp_pose_build(&held);
        float x = p->poses[FP_HAND_RIGHT].joints[0][0], y = held.poses[FP_HAND_RIGHT].joints[0][0];
        if (next >= 2) { /* (one sample shows no motion) */
            *repeated_at += x == last_at;
            *repeated_held += y == last_held;
        }
        last_at = x;
        last_held = y;
    }
}

static void test_no_repeats(void **state)
{
    (void)state;
    int held, at;
    stream_at_60(57, &held, &at);
    printf("57 Hz at 60 fps, 600 frames: %d repeated held, %d at the frame's time\n", held, at);
    assert_true(held >= 25);
    assert_int_equal(at, 0);
    stream_at_60(108, &held, &at);
    printf("108 Hz at 60 fps, 600 frames: %d repeated held, %d at the frame's time\n", held, at);
    assert_int_equal(at, 0);
}

/* The filter runs per input: the source's state, none for a source past FP_POSE_MAX_INPUTS,
 * none with a NULL or off filter; a noisy still hand comes out steadier. */
static void test_filtered_events(void **state)
{
    (void)state;
    static fp_pose_state ps, qs, raw;
    fp_pose_state *p = identity_pose(&ps);
    fp_event a = positions(FP_HAND_RIGHT, 0, 0, 2), b = positions(FP_HAND_RIGHT, 10, 10 * MS, 2);
    fp_pose_take_event_filtered(p, &a, &tracker);
    fp_pose_take_event_filtered(p, &b, &tracker);
    assert_true(p->filters[2][FP_HAND_RIGHT].joints[0].started);
    assert_false(p->filters[0][FP_HAND_RIGHT].joints[0].started);
    assert_true(p->hands[FP_HAND_RIGHT].joints_mm[0][0] > 0 && p->hands[FP_HAND_RIGHT].joints_mm[0][0] < 10);
    fp_event c = positions(FP_HAND_RIGHT, 20, 20 * MS, FP_POSE_MAX_INPUTS);
    fp_pose_take_event_filtered(p, &c, &tracker);
    assert_true(p->hands[FP_HAND_RIGHT].joints_mm[0][0] == 20.f);
    fp_filter_config off = tracker;
    off.kind = FP_FILTER_OFF;
    fp_event d = positions(FP_HAND_RIGHT, 30, 30 * MS, 2);
    fp_pose_take_event_filtered(p, &d, &off);
    assert_true(p->hands[FP_HAND_RIGHT].joints_mm[0][0] == 30.f);
    /* auto: only the events flagged unsmoothed go through the filter */
    fp_filter_config automatic = tracker;
    automatic.kind = FP_FILTER_AUTO;
    fp_event e = positions(FP_HAND_LEFT, 0, 0, 3), f = positions(FP_HAND_LEFT, 10, 10 * MS, 3);
    fp_pose_take_event_filtered(p, &e, &automatic);
    fp_pose_take_event_filtered(p, &f, &automatic);
    assert_false(p->filters[3][FP_HAND_LEFT].joints[0].started);
    assert_true(p->hands[FP_HAND_LEFT].joints_mm[0][0] == 10.f);
    e.header.flags = f.header.flags = FP_EVENT_FLAG_UNSMOOTHED;
    fp_pose_take_event_filtered(p, &e, &automatic);
    fp_pose_take_event_filtered(p, &f, &automatic);
    assert_true(p->filters[3][FP_HAND_LEFT].joints[0].started);
    assert_true(p->hands[FP_HAND_LEFT].joints_mm[0][0] > 0 && p->hands[FP_HAND_LEFT].joints_mm[0][0] < 10);
    /* noise on a still hand, 100 Hz, read at 60 fps */
    fp_pose_state *q = identity_pose(&qs);
    identity_pose(&raw);
    double j_raw = 0, j_f = 0, last_raw = 0, last_f = 0;
    int next = 0;
    for (int k = 0; k < 300; k++) {
        int64_t now = llround(k * 1e9 / 60);
        for (; next * 10 * MS <= now; next++) {
            fp_event ev = positions(FP_HAND_LEFT, gauss(), next * 10 * MS, 1);
            fp_pose_take_event_filtered(q, &ev, &tracker);
            fp_pose_take_event(&raw, &ev);
        }
        fp_pose_build_at(q, now);
        fp_pose_build_at(&raw, now);
        double x = raw.poses[FP_HAND_LEFT].joints[0][0], y = q->poses[FP_HAND_LEFT].joints[0][0];
        if (k > 60) j_raw += pow(x - last_raw, 2), j_f += pow(y - last_f, 2);
        last_raw = x, last_f = y;
    }
    printf("still hand, 1 mm noise at 100 Hz, 60 fps: frame-to-frame %.3f mm raw, %.4f filtered\n",
           sqrt(j_raw / 239), sqrt(j_f / 239));
    assert_true(j_f * 25 < j_raw);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alpha),          cmocka_unit_test(test_constant),
        cmocka_unit_test(test_ramp_lag),       cmocka_unit_test(test_noise),
        cmocka_unit_test(test_adaptive),
        cmocka_unit_test(test_trend),       cmocka_unit_test(test_trend_fade_continuous),
        cmocka_unit_test(test_shared_cutoff),
        cmocka_unit_test(test_stamps),
        cmocka_unit_test(test_keys),           cmocka_unit_test(test_frame_time),
        cmocka_unit_test(test_frame_time_angles), cmocka_unit_test(test_no_repeats),
        cmocka_unit_test(test_filtered_events),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
