/* core/pose fp_pose_auto: a live input's workspace estimated as it runs (issue 51). */
#define _GNU_SOURCE
#include "fp_pose_auto.h"
#include "leapcsv.h"
#include "pose_events.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

static const char *data_dir(void)
{
    const char *d = getenv("FP_SHARED_DATA");
    return d && *d ? d : "../shared/data";
}

/* A hand whose joints spread over a 100 x 100 x 100 mm box from (x, y, z). */
static void spread_hand(float mm[FP_HAND_JOINTS][3], float x, float y, float z)
{
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        mm[j][0] = x + 5.f * j;
        mm[j][1] = y + 5.f * ((j * 7) % FP_HAND_JOINTS);
        mm[j][2] = z + 5.f * ((j * 11) % FP_HAND_JOINTS);
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The replay's rule on the four real recordings, every row kept (fed 20 ms apart, above the
 * 1/64 s spacing and within the 20 s window): the box within half a bin (0.5 mm) of the
 * sorted-index percentiles of the same joints (input-replay's replay_workspace). */
static void test_box_is_the_replays_rule(void **state)
{
    (void)state;
    static const char *recs[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    for (size_t r = 0; r < 4; r++) {
        char path[4200], err[512];
        snprintf(path, sizeof path, "%s/hands/leap-motion/%s_joints_mm.csv", data_dir(), recs[r]);
        fp_leap_joints_row *rows = NULL;
        size_t n = 0;
        assert_int_equal(fp_leapcsv_read_joints(path, &rows, &n, err, sizeof err), 0);
        assert_true(n > 100 && n * 0.02 < FP_POSE_AUTO_WINDOW_S);
        fp_pose_auto *a;
        assert_int_equal(fp_pose_auto_create(&a), 0);
        float *v = malloc(n * FP_HAND_JOINTS * sizeof *v);
        assert_non_null(v);
        for (size_t i = 0; i < n; i++) {
            fp_event ev = joints_event((int)rows[i].side, rows[i].joints_mm, (int64_t)i * 20000000);
            fp_pose_auto_take(a, &ev);
        }
        assert_int_equal(fp_pose_auto_samples(a), n);
        float lo[3], hi[3];
        assert_true(fp_pose_auto_box(a, lo, hi));
        size_t m = n * FP_HAND_JOINTS;
        for (int k = 0; k < 3; k++) {
            for (size_t i = 0; i < n; i++)
                for (int j = 0; j < FP_HAND_JOINTS; j++) v[i * FP_HAND_JOINTS + j] = rows[i].joints_mm[j][k];
            qsort(v, m, sizeof *v, cmp_float);
            float rlo = v[(size_t)(0.02 * (double)(m - 1) + 0.5)], rhi = v[(size_t)(0.98 * (double)(m - 1) + 0.5)];
            if (!(fabsf(lo[k] - rlo) <= 0.5f + 1e-3f) || !(fabsf(hi[k] - rhi) <= 0.5f + 1e-3f))
                fail_msg("%s axis %d: box %.2f..%.2f, the replay's %.2f..%.2f", recs[r], k, lo[k], hi[k], rlo, rhi);
        }
        printf("%-17s %zu rows: x %.1f..%.1f y %.1f..%.1f z %.1f..%.1f mm\n", recs[r], n, lo[0], hi[0],
               lo[1], hi[1], lo[2], hi[2]);
        free(v);
        free(rows);
        fp_pose_auto_destroy(&a);
        assert_null(a);
    }
}

/* Samples closer than 1/64 s to their hand's last are skipped (per hand), the window keeps
 * FP_POSE_AUTO_WINDOW_S of the newest sample's time, events that are not a hand's finite
 * joint positions are ignored, and a few glitches 3 m away move nothing. */
static void test_samples_window_and_glitches(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    float mm[FP_HAND_JOINTS][3], lo[3], hi[3];
    assert_false(fp_pose_auto_box(a, lo, hi));
    spread_hand(mm, 0, 100, -50);
    for (int i = 0; i < 1000; i++) { /* 1 kHz for 1 s, both hands */
        fp_event l = joints_event(FP_HAND_LEFT, mm, (int64_t)i * 1000000);
        fp_event r = joints_event(FP_HAND_RIGHT, mm, (int64_t)i * 1000000);
        fp_pose_auto_take(a, &l);
        fp_pose_auto_take(a, &r);
    }
    /* every 16th ms per hand (15.625 ms spacing): 63 each */
    assert_int_equal(fp_pose_auto_samples(a), 2 * 63);
    fp_event none = joints_event(FP_HAND_LEFT, mm, 2000000000);
    none.header.hand = -1; /* (no hand: a button's) */
    fp_pose_auto_take(a, &none);
    fp_event angles = joints_event(FP_HAND_LEFT, mm, 2000000000);
    angles.header.type = FP_EVENT_JOINT_ANGLES;
    fp_pose_auto_take(a, &angles);
    float bad[FP_HAND_JOINTS][3];
    memcpy(bad, mm, sizeof bad);
    bad[3][1] = NAN;
    fp_event nan_ev = joints_event(FP_HAND_LEFT, bad, 2000000000);
    fp_pose_auto_take(a, &nan_ev);
    assert_int_equal(fp_pose_auto_samples(a), 2 * 63);
    assert_true(fp_pose_auto_box(a, lo, hi));
    assert_float_equal(lo[2], -49.5, 1e-3); /* the middle of the first joints' bin */
    /* one glitch sample in 60 (1.6%: under the 2%) 3 m away leaves the box */
    float far[FP_HAND_JOINTS][3];
    spread_hand(far, 3000, 3000, -3000);
    float lo2[3], hi2[3];
    for (int i = 0; i < 60; i++) {
        fp_event ev = joints_event(FP_HAND_RIGHT, i == 30 ? far : mm, 2000000000 + (int64_t)i * 20000000);
        fp_pose_auto_take(a, &ev);
    }
    assert_true(fp_pose_auto_box(a, lo2, hi2));
    for (int k = 0; k < 3; k++) {
        assert_float_equal(lo2[k], lo[k], 1e-6);
        assert_float_equal(hi2[k], hi[k], 1e-6);
    }
    /* the performer steps back 300 mm: after the window only the new place counts */
    float back[FP_HAND_JOINTS][3];
    spread_hand(back, 0, 100, 250);
    int64_t t = 4000000000;
    for (int i = 0; i < (int)(25 * 50); i++, t += 20000000) {
        fp_event ev = joints_event(FP_HAND_RIGHT, back, t);
        fp_pose_auto_take(a, &ev);
    }
    assert_int_equal(fp_pose_auto_samples(a), (size_t)(FP_POSE_AUTO_WINDOW_S * 50) + 1);
    assert_true(fp_pose_auto_box(a, lo2, hi2));
    assert_float_equal(lo2[2], 250.5, 1e-3);
    fp_pose_auto_destroy(&a);
    fp_pose_auto_destroy(&a); /* (NULL: nothing) */
}

static const float head_min[3] = {-8, -12, -10}, head_max[3] = {8, 12, 11};

/* When it refits: at the first sample, every call while the samples span under
 * FP_POSE_AUTO_SETTLE_S, then once per FP_POSE_AUTO_REFIT_S; never while engaged nor without
 * a new sample. The calibration is fp_pose_fit_workspace of the box, life-size. */
static void test_refit_schedule(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    fp_pose_state p;
    fp_calibration c0 = {0.1, {1, 2, 3}, {1, 0, 0, 0}, {{0, 0, 0}, {0, 0, 0}}, {0, 0, 0, 0}};
    fp_pose_init(&p, 0, &c0);
    assert_false(fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0)); /* no sample */
    float mm[FP_HAND_JOINTS][3];
    int64_t t = 0;
    unsigned refits = 0, frames = 0;
    for (int f = 0; f < 120; f++, t += 16666667) { /* 2 s at 60 frames a second */
        spread_hand(mm, (float)f, 100, -50 - (float)f);
        fp_event ev = joints_event(FP_HAND_RIGHT, mm, t);
        fp_pose_auto_take(a, &ev);
        bool r = fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0);
        frames++;
        refits += r;
        if (t < (int64_t)(FP_POSE_AUTO_SETTLE_S * 1e9)) assert_true(r); /* settling: each frame */
        if (f == 0) {
            float lo[3], hi[3];
            fp_calibration want;
            assert_true(fp_pose_auto_box(a, lo, hi));
            fp_pose_fit_workspace(&want, 10.0, lo, hi, head_min, head_max);
            assert_memory_equal(&p.calib, &want, sizeof want);
            assert_float_equal(p.calib.scale, 0.1, 0);
        }
    }
    /* 60 frames of settling (t < 1 s), then one every 0.25 s: 4 */
    assert_int_equal(refits, 60 + 4);
    assert_int_equal(fp_pose_auto_refits(a), refits);
    assert_false(fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0)); /* nothing new */
    /* engaged: nothing moves, however long; released: refitted at once */
    fp_calibration held = p.calib;
    for (int f = 0; f < 60; f++, t += 16666667) {
        spread_hand(mm, 200, 100, 100);
        fp_event ev = joints_event(FP_HAND_RIGHT, mm, t);
        fp_pose_auto_take(a, &ev);
        assert_false(fp_pose_auto_refit(a, &p, true, 10.0, head_min, head_max, 0));
        assert_memory_equal(&p.calib, &held, sizeof held);
    }
    assert_true(fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0));
    assert_memory_not_equal(&p.calib, &held, sizeof held);
    fp_pose_auto_destroy(&a);
}

/* The same events and engagements give the same calibrations, bit for bit. */
static void test_deterministic(void **state)
{
    (void)state;
    fp_calibration seen[2][200];
    for (int run = 0; run < 2; run++) {
        fp_pose_auto *a;
        assert_int_equal(fp_pose_auto_create(&a), 0);
        fp_pose_state p;
        fp_pose_init(&p, 0, NULL);
        float mm[FP_HAND_JOINTS][3];
        for (int f = 0; f < 200; f++) {
            spread_hand(mm, 30.f * sinf(0.1f * f), 150 + 20.f * cosf(0.07f * f), -60.f * sinf(0.05f * f));
            fp_event ev = joints_event(f % 3 ? FP_HAND_RIGHT : FP_HAND_LEFT, mm, (int64_t)f * 9000000);
            fp_pose_auto_take(a, &ev);
            fp_pose_auto_refit(a, &p, f % 50 > 40, 10.24, head_min, head_max, 0);
            seen[run][f] = p.calib;
        }
        fp_pose_auto_destroy(&a);
    }
    assert_memory_equal(seen[0], seen[1], sizeof seen[0]);
}

/* Gloves placed by fp_pose_place_gloves keep their place on the face when the hands' (a
 * tracker's) placement is refined: their device wrists move by the offset's change. */
static void test_gloves_keep_their_place(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    fp_pose_state p;
    fp_calibration c0;
    float wmin[3], wmax[3];
    fp_pose_default_workspace(wmin, wmax);
    fp_pose_fit_workspace(&c0, 10.0, wmin, wmax, head_min, head_max);
    fp_pose_init(&p, 0, &c0);
    p.glove_placed = true;
    const float g[FP_HANDS][3] = {{-80, 200, 60}, {80, 210, 40}};
    memcpy(p.glove_pos, g, sizeof g);
    float before[FP_HANDS][3];
    for (int h = 0; h < FP_HANDS; h++) fp_pose_to_mesh(&p.calib, h, g[h], before[h]);
    float mm[FP_HAND_JOINTS][3];
    spread_hand(mm, 300, -200, 400);
    fp_event ev = joints_event(FP_HAND_RIGHT, mm, 5);
    fp_pose_auto_take(a, &ev);
    assert_true(fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0));
    for (int h = 0; h < FP_HANDS; h++) {
        float after[3];
        fp_pose_to_mesh(&p.calib, h, p.glove_pos[h], after);
        for (int k = 0; k < 3; k++) assert_float_equal(after[k], before[h][k], 1e-4);
        assert_true(fabsf(p.glove_pos[h][0] - g[h][0]) > 100); /* the device wrist did move */
    }
    fp_pose_auto_destroy(&a);
}

/* Still hands hover (FP_POSE_STILL_MM): while no fingertip has moved 10 mm from its first
 * sample, a refit places the hands `hover` farther out in depth than the range would; one
 * glitch sample does not end it, two in a row do, and the refit then comes at once (not on
 * the schedule), without the hover. */
static void test_still_hands_hover(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    fp_pose_state p;
    fp_pose_init(&p, 0, NULL);
    assert_true(fp_pose_auto_still(a)); /* no sample yet */
    const double hover = 2.5;
    float mm[FP_HAND_JOINTS][3], lo[3], hi[3];
    fp_calibration want;
    int64_t t = 0;
    for (int f = 0; f < 90; f++, t += 16666667) { /* 1.5 s held (jitter 1 mm) */
        spread_hand(mm, 10.f + (float)(f % 2), 100, -50);
        if (f == 70) mm[FP_JOINT_TIP(2)][2] += 40.f; /* one glitch sample */
        fp_event ev = joints_event(FP_HAND_RIGHT, mm, t);
        fp_pose_auto_take(a, &ev);
        fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, hover);
        assert_true(fp_pose_auto_still(a));
        assert_true(fp_pose_auto_box(a, lo, hi));
        fp_pose_fit_workspace(&want, 10.0, lo, hi, head_min, head_max);
        if (f < 60) assert_float_equal(p.calib.offset[2], want.offset[2] + hover, 1e-9); /* (settling) */
    }
    /* the fingertips move 12 mm: after the second such sample the hover ends at once */
    for (int f = 0; f < 2; f++, t += 16666667) {
        spread_hand(mm, 22.f, 100, -50);
        fp_event ev = joints_event(FP_HAND_RIGHT, mm, t);
        fp_pose_auto_take(a, &ev);
        bool r = fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, hover);
        assert_int_equal(fp_pose_auto_still(a), f == 0);
        if (f == 1) assert_true(r);
    }
    assert_true(fp_pose_auto_box(a, lo, hi));
    fp_pose_fit_workspace(&want, 10.0, lo, hi, head_min, head_max);
    assert_memory_equal(&p.calib, &want, sizeof want);
    fp_pose_auto_destroy(&a);
}

/* fp_pose_auto_held: a hand whose thumb and index tips pinch (30 mm) while its palm and finger
 * bases stay within 2 mm is held in place once the samples span FP_POSE_HELD_S, not before,
 * and for good no more once a base has moved 12 mm in two samples in a row (one glitch sample
 * is not a move); a hand that moves as a whole never is. */
static void test_held_in_place(void **state)
{
    (void)state;
    for (int whole = 0; whole < 2; whole++) {
        fp_pose_auto *a;
        assert_int_equal(fp_pose_auto_create(&a), 0);
        assert_false(fp_pose_auto_held(a));
        float mm[FP_HAND_JOINTS][3];
        int64_t t = 0;
        const int frames = (int)(FP_POSE_HELD_S * 60) + 30;
        for (int f = 0; f <= frames; f++, t += 16666667) {
            double c = 0.5 * (1 - cos(2 * M_PI * f / 60.0)); /* a pinch a second */
            spread_hand(mm, 10.f + (float)(f % 3), 100, whole ? -50.f + 0.5f * (float)f : -50.f);
            mm[FP_JOINT_TIP(0)][0] += (float)(30 * c);
            mm[FP_JOINT_TIP(1)][0] -= (float)(30 * c);
            fp_event ev = joints_event(FP_HAND_RIGHT, mm, t);
            fp_pose_auto_take(a, &ev);
            bool due = (double)t >= FP_POSE_HELD_S * 1e9;
            if (!whole) assert_int_equal(fp_pose_auto_held(a), due && !fp_pose_auto_still(a));
            else assert_false(fp_pose_auto_held(a) && f > 30); /* (its base 12 mm off by 0.4 s) */
        }
        if (!whole) {
            assert_true(fp_pose_auto_held(a));
            spread_hand(mm, 10.f, 100, -38.f); /* one glitch sample: still held */
            fp_event ev = joints_event(FP_HAND_RIGHT, mm, t += 16666667);
            fp_pose_auto_take(a, &ev);
            spread_hand(mm, 10.f, 100, -50.f);
            ev = joints_event(FP_HAND_RIGHT, mm, t += 16666667);
            fp_pose_auto_take(a, &ev);
            assert_true(fp_pose_auto_held(a));
            for (int f = 0; f < 2; f++) { /* the base moves 12 mm: no more, and for good */
                spread_hand(mm, 10.f, 100, -38.f);
                ev = joints_event(FP_HAND_RIGHT, mm, t += 16666667);
                fp_pose_auto_take(a, &ev);
            }
            assert_false(fp_pose_auto_held(a));
            spread_hand(mm, 10.f, 100, -50.f);
            ev = joints_event(FP_HAND_RIGHT, mm, t += 16666667);
            fp_pose_auto_take(a, &ev);
            assert_false(fp_pose_auto_held(a));
        }
        fp_pose_auto_destroy(&a);
    }
}

/* fp_pose_auto_each: every kept sample, oldest first, with its hand and its joints at their
 * bins' middles (within half a bin of what was sent). */
typedef struct seen {
    int n, hands[8];
    float first[FP_HAND_JOINTS][3];
} seen;

static void see(void *ctx, int hand, const float (*mm)[3])
{
    seen *s = ctx;
    if (s->n < 8) s->hands[s->n] = hand;
    if (!s->n) memcpy(s->first, mm, sizeof s->first);
    s->n++;
}

static void test_each_sample(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    float mm[FP_HAND_JOINTS][3];
    spread_hand(mm, -30.3f, 120.7f, 10.2f);
    for (int i = 0; i < 3; i++) {
        fp_event ev = joints_event(i == 1 ? FP_HAND_LEFT : FP_HAND_RIGHT, mm, (int64_t)i * 20000000);
        fp_pose_auto_take(a, &ev);
    }
    seen s = {0};
    fp_pose_auto_each(a, see, &s);
    assert_int_equal(s.n, 3);
    assert_int_equal(s.hands[0], FP_HAND_RIGHT);
    assert_int_equal(s.hands[1], FP_HAND_LEFT);
    assert_int_equal(s.hands[2], FP_HAND_RIGHT);
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) assert_true(fabsf(s.first[j][k] - mm[j][k]) <= 0.5f * FP_POSE_AUTO_BIN_MM);
    fp_pose_auto_destroy(&a);
}

/* Two hands: centred sideways and up between the hands' own centres, not on the box of both
 * (fp_pose_auto.h). One left sample 300..200 mm to the left, 60 right ones at 0..100 mm: the
 * box of both is nearly the right hand's (the left one's joints are under 2%), centred near
 * x 50 mm; each hand's own centre is -250 and 50, so the placement centres on -100. The width
 * and the depth stay the box's. Before, the placement centred on the box (x 50.5). */
static void test_two_hands_centre(void **state)
{
    (void)state;
    fp_pose_auto *a;
    assert_int_equal(fp_pose_auto_create(&a), 0);
    fp_pose_state p;
    fp_pose_init(&p, 0, NULL);
    float mm[FP_HAND_JOINTS][3];
    int64_t t = 0;
    spread_hand(mm, -300, 100, -50);
    fp_event ev = joints_event(FP_HAND_LEFT, mm, t);
    fp_pose_auto_take(a, &ev);
    for (int f = 0; f < 60; f++, t += 16666667) {
        spread_hand(mm, 0, 120, -50);
        ev = joints_event(FP_HAND_RIGHT, mm, t);
        fp_pose_auto_take(a, &ev);
    }
    assert_true(fp_pose_auto_refit(a, &p, false, 10.0, head_min, head_max, 0));
    float lo[3], hi[3];
    assert_true(fp_pose_auto_box(a, lo, hi));
    assert_true(0.5f * (lo[0] + hi[0]) > 40.f); /* (the box of both: the right hand's) */
    float mid[3] = {0.5f * (-250.f + 50.f) + 0.5f, 0.5f * (135.f + 155.f) + 0.5f, 0}; /* bin middles (y spans 0..70 mm) */
    float wlo[3], whi[3];
    for (int k = 0; k < 3; k++) {
        float half = 0.5f * (hi[k] - lo[k]);
        wlo[k] = k < 2 ? mid[k] - half : lo[k];
        whi[k] = k < 2 ? mid[k] + half : hi[k];
    }
    fp_calibration want;
    fp_pose_fit_workspace(&want, 10.0, wlo, whi, head_min, head_max);
    for (int k = 0; k < 3; k++)
        if (!(fabs(p.calib.offset[k] - want.offset[k]) < 1e-3))
            fail_msg("axis %d: offset %.4f, want %.4f (centred between the hands)", k, p.calib.offset[k], want.offset[k]);
    fp_pose_auto_destroy(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_is_the_replays_rule),
        cmocka_unit_test(test_samples_window_and_glitches),
        cmocka_unit_test(test_refit_schedule),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_gloves_keep_their_place),
        cmocka_unit_test(test_still_hands_hover),
        cmocka_unit_test(test_held_in_place),
        cmocka_unit_test(test_each_sample),
        cmocka_unit_test(test_two_hands_centre),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
