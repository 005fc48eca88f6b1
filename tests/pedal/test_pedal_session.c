/* End to end: an emulated USB foot pedal (umockdev) engages and commits the anchored mapping
 * over a replayed two-hand recording on the ICT face, in a headless session. With auto=0
 * only the pedal starts and ends deformations: left engages, left again commits, right
 * cancels (the default binding, docs/pedal.md). */
#define _GNU_SOURCE
#include "fp_session.h"
#include "fp_test_support.h"
#include "pedal_emu.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>

static void press(emu *e, uint8_t bit)
{
    uint8_t down[2] = {bit, 0}, up[2] = {0, 0};
    emu_send(e, down, 2);
    emu_send(e, up, 2);
}

/* Step until `pred` holds for a frame, or 20 s pass. Returns the frame's stats. */
typedef bool (*frame_pred)(const fp_frame_stats *);
static bool is_engaged(const fp_frame_stats *st) { return st->engaged; }
static bool is_committed(const fp_frame_stats *st) { return st->committed; }
static bool is_cancelled(const fp_frame_stats *st) { return st->cancelled; }

static unsigned long engaged_seen;
static bool step_until(fp_session *s, frame_pred pred)
{
    int64_t deadline = fp_now_ns() + 20LL * 1000000000LL;
    while (fp_now_ns() < deadline) {
        fp_frame_stats st;
        fp_session_step(s, fp_now_ns(), &st);
        engaged_seen += st.engaged;
        if (pred(&st)) return true;
        struct timespec ts = {0, 3000000};
        nanosleep(&ts, NULL);
    }
    return false;
}

/* The nearest fingertip's distance to the loaded surface's vertices (mesh units). */
static double tip_distance(fp_session *s)
{
    size_t n = fp_session_vertex_count(s);
    const float *v = fp_session_loaded(s);
    double best = INFINITY;
    for (int h = 0; h < FP_HANDS; h++) {
        const fp_hand_pose *p = fp_session_hand(s, h);
        if (!p || !p->present) continue;
        for (int f = 0; f < FP_FINGERS; f++) {
            const float *t = p->joints[FP_JOINT_TIP(f)];
            for (size_t i = 0; i < n; i++) {
                double d2 = 0;
                for (int k = 0; k < 3; k++) d2 += pow(v[3 * i + k] - t[k], 2);
                if (d2 < best) best = d2;
            }
        }
    }
    return sqrt(best);
}

/* Step until a fingertip is within `factor` x R of the face (the performer's hand at the
 * face, where a press of the pedal grabs the surface), or 20 s pass. */
static bool step_until_near(fp_session *s, double factor)
{
    int64_t deadline = fp_now_ns() + 20LL * 1000000000LL;
    while (fp_now_ns() < deadline) {
        fp_session_step(s, fp_now_ns(), NULL);
        if (tip_distance(s) < factor * fp_session_radius(s)) return true;
        struct timespec ts = {0, 3000000};
        nanosleep(&ts, NULL);
    }
    return false;
}

static void test_pedal_drives_anchored(void **state)
{
    (void)state;
    emu *e = emu_new();
    assert_non_null(e);
    assert_int_equal(emu_plug(e, EMU_VEC, 5), 0);
    char input[4300];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,loop=1",
             fp_test_data_dir());
    const char *inputs[] = {input, "pedal,strict=1"};
    fp_session *s = fp_test_session_start("anchored,auto=0", inputs, 2);
    size_t bytes = fp_session_vertex_count(s) * 3 * sizeof(float);

    /* Hands move for half a second: with auto=0 nothing engages by itself. */
    int64_t until = fp_now_ns() + 500000000LL;
    while (fp_now_ns() < until) {
        fp_frame_stats st;
        fp_session_step(s, fp_now_ns(), &st);
        assert_false(st.active);
        struct timespec ts = {0, 3000000};
        nanosleep(&ts, NULL);
    }
    assert_memory_equal(fp_session_base(s), fp_session_loaded(s), bytes);

    /* The hands at rest hover in front of the face (docs/calibration.md): press when they
     * reach it, as a performer would, so that the grab holds the surface. */
    assert_true(step_until_near(s, 0.3));
    press(e, 0x01); /* left: engage */
    assert_true(step_until(s, is_engaged));
    /* Let the fingers move the control vectors' end points for a while, then commit. */
    until = fp_now_ns() + 700000000LL;
    while (fp_now_ns() < until) {
        fp_session_step(s, fp_now_ns(), NULL);
        struct timespec ts = {0, 3000000};
        nanosleep(&ts, NULL);
    }
    press(e, 0x01); /* left again: commit */
    assert_true(step_until(s, is_committed));
    assert_memory_not_equal(fp_session_base(s), fp_session_loaded(s), bytes);

    float *committed = malloc(bytes);
    memcpy(committed, fp_session_base(s), bytes);
    press(e, 0x01); /* engage again, then right: cancel; the base stays */
    assert_true(step_until(s, is_engaged));
    press(e, 0x04);
    assert_true(step_until(s, is_cancelled));
    fp_session_step(s, fp_now_ns(), NULL);
    assert_memory_equal(fp_session_base(s), committed, bytes);
    assert_memory_equal(fp_session_positions(s), committed, bytes);
    assert_int_equal(engaged_seen, 2);
    free(committed);
    fp_session_destroy(&s);
    emu_free(&e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_pedal_drives_anchored)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
