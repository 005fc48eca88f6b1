/* core/pose: a tracker's jumps (fp_pose.h FP_POSE_JUMP_MM): a single sample far away is
 * dropped, a hand found elsewhere is absent a moment and starts afresh there, a tracker
 * sending nonsense leaves the hand absent, and the real recordings (at their rate, every
 * other row, 1.6x faster) never jump; a glove tracker's wrist poses go by the same rule. */
#define _GNU_SOURCE
#include "fp_pose.h"
#include "leapcsv.h"
#include "pose_events.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define PERIOD_NS 9091000LL /* 110 Hz, a Leap's rate */
#define FRAME_NS 16666667LL

/* A hand at (x, 200, 0): joints spread 5 mm apart along y. */
static void hand_at(float mm[FP_HAND_JOINTS][3], float x)
{
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        mm[j][0] = x;
        mm[j][1] = 200.f + 5.f * j;
        mm[j][2] = 0.f;
    }
}

static const fp_calibration identity = {1.0, {0, 0, 0}, {1, 0, 0, 0}, {{0, 0, 0}, {0, 0, 0}}, {0, 0, 0, 0}};

/* Feed the right hand at x(i) for samples i < n (one every PERIOD_NS), building a frame at
 * every FRAME_NS; out_x[f] the frame's joint 0 x (NAN: absent). Returns the frames. */
static size_t feed(fp_pose_state *p, size_t n, float (*x_of)(size_t i), float *out_x, size_t cap)
{
    size_t frames = 0, i = 0;
    for (int64_t now = 0; i < n || now <= (int64_t)n * PERIOD_NS; now += FRAME_NS) {
        for (; i < n && (int64_t)i * PERIOD_NS <= now; i++) {
            float mm[FP_HAND_JOINTS][3];
            hand_at(mm, x_of(i));
            fp_event ev = joints_event(FP_HAND_RIGHT, mm, (int64_t)i * PERIOD_NS);
            fp_pose_take_event(p, &ev);
        }
        fp_pose_build_at(p, now);
        if (frames < cap) out_x[frames] = p->poses[FP_HAND_RIGHT].present ? p->poses[FP_HAND_RIGHT].joints[0][0] : NAN;
        frames++;
    }
    return frames < cap ? frames : cap;
}

/* 1 mm a sample (0.11 m/s), sample 40 a glitch 200 mm away */
static float glitch_x(size_t i) { return (float)i + (i == 40 ? 200.f : 0.f); }
/* 1 mm a sample, 150 mm over from sample 40 on (a hand swapped, or found elsewhere) */
static float moved_x(size_t i) { return (float)i + (i >= 40 ? 150.f : 0.f); }
/* nonsense: each sample 0 or 300 mm at random */
static float chaos_x(size_t i) { return (float)(((i * 2654435761u) >> 7) % 4) * 100.f; }

static void test_glitch_dropped(void **state)
{
    (void)state;
    fp_pose_state p;
    fp_pose_init(&p, 0, &identity);
    float x[64];
    size_t nf = feed(&p, 80, glitch_x, x, 64);
    for (size_t f = 0; f < nf; f++) {
        double t = (double)f * FRAME_NS / PERIOD_NS; /* the frame's time in samples */
        assert_false(isnan(x[f]));
        if (!(fabs(x[f] - t) < 3.0)) fail_msg("frame %zu at x %.2f, the hand at %.2f (a glitch shown?)", f, x[f], t);
    }
    assert_int_equal(p.hands[FP_HAND_RIGHT].glitches, 1);
    assert_int_equal(p.hands[FP_HAND_RIGHT].jumps, 0);
}

static void test_found_elsewhere(void **state)
{
    (void)state;
    fp_pose_state p;
    fp_pose_init(&p, 0, &identity);
    float x[64];
    size_t nf = feed(&p, 80, moved_x, x, 64);
    int64_t found = 41 * PERIOD_NS; /* the second sample over there confirms it */
    size_t absent = 0;
    for (size_t f = 0; f < nf; f++) {
        int64_t now = (int64_t)f * FRAME_NS;
        double t = (double)now / PERIOD_NS;
        if (now >= found && now < found + FP_POSE_JUMP_ABSENT_NS) {
            assert_true(isnan(x[f])); /* a moment absent: a gesture it held lets go */
            absent++;
        } else if (now >= found + FP_POSE_JUMP_ABSENT_NS) {
            assert_false(isnan(x[f]));
            if (!(fabs(x[f] - (t + 150.0)) < 3.0)) fail_msg("frame %zu at %.2f, want about %.2f", f, x[f], t + 150.0);
        } else {
            assert_false(isnan(x[f]));
            if (!(fabs(x[f] - t) < 3.0)) fail_msg("frame %zu at %.2f before the jump, want about %.2f", f, x[f], t);
        }
    }
    assert_true(absent >= 2);
    assert_int_equal(p.hands[FP_HAND_RIGHT].jumps, 1);
}

static void test_nonsense_absent(void **state)
{
    (void)state;
    fp_pose_state p;
    fp_pose_init(&p, 0, &identity);
    float x[128];
    size_t nf = feed(&p, 200, chaos_x, x, 128), shown = 0;
    for (size_t f = 0; f < nf; f++)
        if ((int64_t)f * FRAME_NS > 2 * FP_POSE_MAX_PERIOD_NS && !isnan(x[f])) shown++;
    printf("nonsense at 110 Hz: the hand shown in %zu of %zu frames past 0.2 s (%lu found elsewhere)\n", shown,
           nf, p.hands[FP_HAND_RIGHT].jumps);
    assert_true(shown * 10 <= nf); /* absent nearly all the time */
}

/* The four Leap recordings, as recorded, every other row (55 Hz) and 1.6x faster: no jump,
 * no glitch (their fingertips move 28 mm at most between samples, 1.7 m/s at most). */
static void test_recordings_never_jump(void **state)
{
    (void)state;
    const char *d = getenv("FP_SHARED_DATA");
    static const char *recs[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    for (size_t r = 0; r < 4; r++) {
        char path[4200], err[512];
        snprintf(path, sizeof path, "%s/hands/leap-motion/%s_joints_mm.csv", d && *d ? d : "../shared/data", recs[r]);
        fp_leap_joints_row *rows = NULL;
        size_t n = 0;
        assert_int_equal(fp_leapcsv_read_joints(path, &rows, &n, err, sizeof err), 0);
        static const int every[3] = {1, 2, 1};
        static const double speed[3] = {1.0, 1.0, 1.6};
        for (int v = 0; v < 3; v++) {
            fp_pose_state p;
            fp_pose_init(&p, 0, &identity);
            for (size_t i = 0; i < n; i += (size_t)every[v]) {
                fp_event ev = joints_event((int)rows[i].side, rows[i].joints_mm,
                                           (int64_t)llround((double)rows[i].timestamp_us * 1000.0 / speed[v]));
                fp_pose_take_event(&p, &ev);
            }
            for (int h = 0; h < FP_HANDS; h++)
                if (p.hands[h].jumps || p.hands[h].glitches)
                    fail_msg("%s (every %d, x%.1f), hand %d: %lu jumps, %lu glitches", recs[r], every[v], speed[v], h,
                             p.hands[h].jumps, p.hands[h].glitches);
        }
        free(rows);
    }
}

/* A glove's tracker (wrist poses beside joint angles): the same rule on the wrist's
 * position. 1 mm a sample; sample 30 a glitch 200 mm over, dropped; from sample 60 on 150 mm
 * over: absent a moment, then there. */
static void test_wrist_jumps(void **state)
{
    (void)state;
    fp_pose_state p;
    fp_pose_init(&p, 0, &identity);
    size_t absent = 0;
    int64_t found = 61 * PERIOD_NS;
    for (int64_t now = 0, i = 0; now < 100 * PERIOD_NS; now += FRAME_NS) {
        for (; i < 100 && i * PERIOD_NS <= now; i++) {
            fp_event a, w;
            memset(&a, 0, sizeof a);
            a.header.size = sizeof a.angles;
            a.header.type = FP_EVENT_JOINT_ANGLES;
            a.header.hand = FP_HAND_RIGHT;
            a.header.time_ns = i * PERIOD_NS;
            fp_pose_take_event(&p, &a);
            memset(&w, 0, sizeof w);
            w.header.size = sizeof w.wrist;
            w.header.type = FP_EVENT_WRIST_POSE;
            w.header.hand = FP_HAND_RIGHT;
            w.header.time_ns = i * PERIOD_NS;
            w.wrist.position_mm[0] = (float)i + (i == 30 ? 200.f : 0.f) + (i >= 60 ? 150.f : 0.f);
            w.wrist.position_mm[1] = 200.f;
            w.wrist.rotation[0] = 1.f;
            fp_pose_take_event(&p, &w);
        }
        fp_pose_build_at(&p, now);
        const fp_hand_pose *hp = &p.poses[FP_HAND_RIGHT];
        double t = (double)now / PERIOD_NS, want = t + (now >= found ? 150.0 : 0.0);
        if (now >= found && now < found + FP_POSE_JUMP_ABSENT_NS) {
            assert_false(hp->present);
            absent++;
        } else if (now > PERIOD_NS) {
            assert_true(hp->present);
            if (!(fabs(hp->joints[0][0] - want) < 3.0))
                fail_msg("frame at %.2f samples: wrist x %.2f, want about %.2f", t, hp->joints[0][0], want);
        }
    }
    assert_true(absent >= 2);
    assert_int_equal(p.hands[FP_HAND_RIGHT].glitches, 1);
    assert_int_equal(p.hands[FP_HAND_RIGHT].jumps, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_glitch_dropped),
        cmocka_unit_test(test_found_elsewhere),
        cmocka_unit_test(test_nonsense_absent),
        cmocka_unit_test(test_recordings_never_jump),
        cmocka_unit_test(test_wrist_jumps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
