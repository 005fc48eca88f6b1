/* core/pose: hand state from events, forward kinematics, workspace calibration. */
#include "fp_pose.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

static fp_event positions_event(int hand, float base, int64_t t)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.positions;
    ev.header.type = FP_EVENT_JOINT_POSITIONS;
    ev.header.hand = hand;
    ev.header.time_ns = t;
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) ev.positions.mm[j][k] = base + 10.f * j + k;
    return ev;
}

/* Joint positions go through p = scale * mm + offset, exactly (double, rounded once). */
static void test_positions_calibrated(void **state)
{
    (void)state;
    fp_calibration c = {0.25, {1.0, -2.0, 3.5}};
    fp_pose_state p;
    fp_pose_init(&p, 0, &c);
    fp_event ev = positions_event(FP_HAND_RIGHT, 100.f, 42);
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_LEFT].present);
    assert_true(p.poses[FP_HAND_RIGHT].present);
    assert_int_equal(p.poses[FP_HAND_RIGHT].time_ns, 42);
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++)
            assert_true(p.poses[FP_HAND_RIGHT].joints[j][k] ==
                        (float)(0.25 * ev.positions.mm[j][k] + c.offset[k]));
    /* A disconnect hides the hand until its next event. */
    fp_event st;
    memset(&st, 0, sizeof st);
    st.header.type = FP_EVENT_STATUS;
    st.header.hand = FP_HAND_RIGHT;
    st.status.code = FP_STATUS_DISCONNECTED;
    fp_pose_take_event(&p, &st);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_RIGHT].present);
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    assert_true(p.poses[FP_HAND_RIGHT].present);
    /* An event without a hand changes nothing. */
    fp_event none = positions_event(-1, 0.f, 1);
    fp_pose_take_event(&p, &none);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_LEFT].present);
}

/* Angles only: forward kinematics from the default wrist (no wrist pose) or the given one;
 * checked against fp_hand_fk called directly, and the two wrists differ by their offset. */
static void test_angles_forward_kinematics(void **state)
{
    (void)state;
    fp_calibration id = {1.0, {0, 0, 0}};
    fp_pose_state p;
    fp_pose_init(&p, 1.1, &id);
    assert_true(fabsf(p.model.size - 1.1f) < 1e-6f);
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.angles;
    ev.header.type = FP_EVENT_JOINT_ANGLES;
    ev.header.hand = FP_HAND_LEFT;
    ev.angles.valid = (1u << FP_GLOVE_SENSORS) - 1;
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) ev.angles.radians[i] = 0.02f * (float)i;
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    float pos[3], rot[4], want[FP_HAND_JOINTS][3];
    fp_pose_default_wrist(FP_HAND_LEFT, pos, rot);
    assert_true(pos[0] == -80.f && pos[1] == 200.f && pos[2] == 60.f && rot[0] == 1.f);
    assert_int_equal(fp_hand_fk(&p.model, FP_HAND_LEFT, ev.angles.radians, ev.angles.valid, pos, rot, want), 0);
    assert_memory_equal(p.poses[FP_HAND_LEFT].joints, want, sizeof want);
    /* A wrist pose moves the hand by its offset (same rotation). */
    fp_event w;
    memset(&w, 0, sizeof w);
    w.header.size = sizeof w.wrist;
    w.header.type = FP_EVENT_WRIST_POSE;
    w.header.hand = FP_HAND_LEFT;
    w.wrist.position_mm[0] = -80.f + 5.f;
    w.wrist.position_mm[1] = 200.f;
    w.wrist.position_mm[2] = 60.f;
    w.wrist.rotation[0] = 1.f;
    fp_pose_take_event(&p, &w);
    fp_pose_build(&p);
    for (int j = 0; j < FP_HAND_JOINTS; j++) assert_true(fabsf(p.poses[FP_HAND_LEFT].joints[j][0] - want[j][0] - 5.f) < 1e-3f);
}

/* The fit's three promises, on a made-up face and workspace. */
static void test_fit_workspace(void **state)
{
    (void)state;
    float ws_min[3], ws_max[3];
    fp_pose_default_workspace(ws_min, ws_max);
    assert_true(ws_min[0] == -150.f && ws_max[1] == 330.f && ws_min[2] == -120.f);
    const float fmin[3] = {-8.f, -10.f, -4.f}, fmax[3] = {8.f, 14.f, 6.f};
    fp_calibration c;
    fp_pose_fit_workspace(&c, ws_min, ws_max, fmin, fmax);
    /* width 16 / 300, height 24 / 250: the smaller ratio */
    assert_true(fabs(c.scale - 16.0 / 300.0) < 1e-12);
    float centre[3] = {0.5f * (ws_min[0] + ws_max[0]), 0.5f * (ws_min[1] + ws_max[1]), ws_min[2]}, out[3];
    fp_pose_to_mesh(&c, centre, out);
    assert_true(fabsf(out[0] - 0.f) < 1e-5f);
    assert_true(fabsf(out[1] - 2.f) < 1e-5f);
    assert_true(fabsf(out[2] - (6.f - 0.15f * 10.f)) < 1e-5f);
}

/* No input tells a workspace: false, box untouched. */
static void test_inputs_workspace_unknown(void **state)
{
    (void)state;
    float a[3] = {1, 2, 3}, b[3] = {4, 5, 6};
    fp_input *none[2] = {NULL, NULL};
    assert_false(fp_pose_inputs_workspace(none, 2, a, b));
    assert_true(a[0] == 1 && b[2] == 6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_positions_calibrated),
        cmocka_unit_test(test_angles_forward_kinematics),
        cmocka_unit_test(test_fit_workspace),
        cmocka_unit_test(test_inputs_workspace_unknown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
