/*
 * test_hand: the hand skeleton (core/hand): analytic forward-kinematics cases, the
 * positions -> angles round trip, fitting, the Leap CSV reader's errors, and the fingertip
 * error on the real Leap recordings of shared/data.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "fp_hand.h"
#include "handcheck.h"
#include "fp_test_support.h"
#include "leapcsv.h"

#define PI 3.14159265358979323846

static double dist(const float a[3], const float b[3])
{
    return sqrt((double)(a[0] - b[0]) * (a[0] - b[0]) + (double)(a[1] - b[1]) * (a[1] - b[1]) +
                (double)(a[2] - b[2]) * (a[2] - b[2]));
}

/* A model without the rest yaw and thumb opposition, so that a flat hand is straight. */
static void straight_model(fp_hand_model *m)
{
    fp_hand_model_init(m);
    m->middle_yaw_rad = 0;
    m->rest_rad[FP_SENSOR_THUMB_ROTATE] = 0;
    m->rest_rad[FP_SENSOR_THUMB_AB] = 0;
}

static void test_straight_hand(void **state)
{
    (void)state;
    fp_hand_model m;
    straight_model(&m);
    m.size = 1.1f;
    float zero[22] = {0}, j[21][3];
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, zero, FP_HAND_ALL_SENSORS, NULL, NULL, j), 0);
    for (int f = 0; f < FP_FINGERS; f++) {
        double len = m.bone_mm[f][1] + m.bone_mm[f][2] + m.bone_mm[f][3] + m.tip_pad_mm[f];
        if (f == 0)
            len += m.bone_mm[0][0];
        /* tip = base + len * size along -z (the hand direction) */
        assert_float_equal(j[FP_JOINT_TIP(f)][0], m.base_mm[f][0] * m.size, 1e-3);
        assert_float_equal(j[FP_JOINT_TIP(f)][1], m.base_mm[f][1] * m.size, 1e-3);
        assert_float_equal(j[FP_JOINT_TIP(f)][2], (m.base_mm[f][2] - len) * m.size, 1e-3);
    }
    /* With a wrist pose the same holds along the rotated direction: 90 deg about +y turns -z
     * into -x. */
    float q[4] = {(float)cos(PI / 4), 0, (float)sin(PI / 4), 0}, p[3] = {10, 20, 30}, jw[21][3];
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, zero, FP_HAND_ALL_SENSORS, p, q, jw), 0);
    double len = (m.bone_mm[2][1] + m.bone_mm[2][2] + m.bone_mm[2][3] + m.tip_pad_mm[2]) * m.size;
    float d[3] = {jw[FP_JOINT_TIP(2)][0] - jw[FP_JOINT(2, 0)][0], jw[FP_JOINT_TIP(2)][1] - jw[FP_JOINT(2, 0)][1],
                  jw[FP_JOINT_TIP(2)][2] - jw[FP_JOINT(2, 0)][2]};
    assert_float_equal(d[0], -len, 1e-3);
    assert_float_equal(d[1], 0, 1e-3);
    assert_float_equal(d[2], 0, 1e-3);
}

static void test_mcp_right_angle(void **state)
{
    (void)state;
    fp_hand_model m;
    straight_model(&m);
    float a[22] = {0}, j[21][3];
    a[FP_SENSOR_INDEX_MPJ] = (float)(PI / 2);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, NULL, NULL, j), 0);
    const float *mcp = j[FP_JOINT(1, 0)], *pip = j[FP_JOINT(1, 1)], *tip = j[FP_JOINT_TIP(1)];
    /* The proximal phalanx points into the palm (-y), at a right angle to the hand direction. */
    assert_float_equal(pip[0] - mcp[0], 0, 1e-3);
    assert_float_equal(pip[1] - mcp[1], -m.bone_mm[1][1], 1e-3);
    assert_float_equal(pip[2] - mcp[2], 0, 1e-3);
    assert_float_equal(tip[2], mcp[2], 1e-3);
    /* The other fingers stay straight. */
    assert_float_equal(j[FP_JOINT(2, 1)][1], j[FP_JOINT(2, 0)][1], 1e-3);
    /* 90 deg at the PIP as well: the middle phalanx points back toward the wrist (+z). */
    a[FP_SENSOR_INDEX_PIJ] = (float)(PI / 2);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, NULL, NULL, j), 0);
    assert_float_equal(j[FP_JOINT(1, 2)][2] - j[FP_JOINT(1, 1)][2], m.bone_mm[1][2], 1e-3);
    assert_float_equal(j[FP_JOINT(1, 2)][1], j[FP_JOINT(1, 1)][1], 1e-3);
}

static void sample_angles(float a[22], unsigned seed)
{
    srand(seed);
    for (int i = 0; i < 22; i++)
        a[i] = (float)((rand() / (double)RAND_MAX) * 1.2 - 0.1);
    a[FP_SENSOR_MIDDLE_INDEX_AB] *= 0.3f;
    a[FP_SENSOR_RING_MIDDLE_AB] *= 0.3f;
    a[FP_SENSOR_PINKIE_RING_AB] *= 0.3f;
}

static void test_repeatable(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    float a[22], b[22], j1[21][3], j2[21][3], jx[21][3];
    sample_angles(a, 1);
    sample_angles(b, 2);
    float q[4] = {0.9f, 0.1f, -0.3f, 0.2f}, p[3] = {1, 2, 3};
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, p, q, j1), 0);
    for (int k = 0; k < 100; k++) /* other poses in between must leave no trace */
        assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, b, FP_HAND_ALL_SENSORS, p, q, jx), 0);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, p, q, j2), 0);
    assert_memory_equal(j1, j2, sizeof j1);
    assert_memory_not_equal(j1, jx, sizeof j1);
}

static void test_left_mirrors_right(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    float a[22], l[21][3], r[21][3];
    sample_angles(a, 3);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, NULL, NULL, r), 0);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_LEFT, a, FP_HAND_ALL_SENSORS, NULL, NULL, l), 0);
    for (int i = 0; i < 21; i++) {
        assert_float_equal(l[i][0], -r[i][0], 1e-5);
        assert_float_equal(l[i][1], r[i][1], 1e-5);
        assert_float_equal(l[i][2], r[i][2], 1e-5);
    }
    /* Right thumb on -x (little finger on +x), left thumb on +x. */
    assert_true(r[FP_JOINT(0, 0)][0] < r[FP_JOINT(4, 0)][0]);
    assert_true(l[FP_JOINT(0, 0)][0] > l[FP_JOINT(4, 0)][0]);
}

static void test_size_linear(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    float a[22], j1[21][3], j2[21][3];
    sample_angles(a, 4);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, NULL, NULL, j1), 0);
    m.size = 1.37f;
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, NULL, NULL, j2), 0);
    for (int i = 0; i < 21; i++)
        for (int k = 0; k < 3; k++)
            assert_float_equal(j2[i][k], 1.37 * j1[i][k], 1e-3);
}

static void test_masked_is_default(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    m.rest_rad[FP_SENSOR_RING_MPJ] = 0.4f; /* a non-trivial default */
    float rest[21][3], masked[21][3], j[21][3], a[22];
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, m.rest_rad, FP_HAND_ALL_SENSORS, NULL, NULL, rest), 0);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, NULL, 0, NULL, NULL, masked), 0);
    assert_memory_equal(rest, masked, sizeof rest);
    /* A masked sensor is ignored even when it holds garbage. */
    memcpy(a, m.rest_rad, sizeof a);
    a[FP_SENSOR_RING_MPJ] = NAN;
    a[FP_SENSOR_THUMB_IJ] = 5.0f;
    uint32_t mask = FP_HAND_ALL_SENSORS & ~((1u << FP_SENSOR_RING_MPJ) | (1u << FP_SENSOR_THUMB_IJ));
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, mask, NULL, NULL, j), 0);
    assert_memory_equal(rest, j, sizeof rest);
    /* ... and a valid one is not. */
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, mask | (1u << FP_SENSOR_THUMB_IJ), NULL, NULL, j), 0);
    assert_true(dist(j[FP_JOINT_TIP(0)], rest[FP_JOINT_TIP(0)]) > 5);
}

static double seg_angle(const float j[21][3], int f, int k)
{
    double u[3], v[3], uu = 0, vv = 0, uv = 0;
    for (int c = 0; c < 3; c++) {
        u[c] = j[FP_JOINT(f, k)][c] - j[FP_JOINT(f, k - 1)][c];
        v[c] = j[FP_JOINT(f, k + 1)][c] - j[FP_JOINT(f, k)][c];
        uu += u[c] * u[c], vv += v[c] * v[c], uv += u[c] * v[c];
    }
    return acos(uv / sqrt(uu * vv));
}

static void test_dip_coupling(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    float a[22] = {0}, j[21][3];
    a[FP_SENSOR_MIDDLE_PIJ] = 0.9f;
    a[FP_SENSOR_MIDDLE_DIJ] = 0.1f; /* ignored: DIJ masked (18-sensor glove) */
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS & ~FP_HAND_DIJ_BITS, NULL, NULL, j), 0);
    assert_float_equal(seg_angle(j, 2, 2), 0.6, 1e-4);
    assert_float_equal(seg_angle(j, 2, 1), 0.9, 1e-4);
    /* PIJ masked too: the rest value (0) for both. */
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS & ~FP_HAND_DIJ_BITS &
                                ~(1u << FP_SENSOR_MIDDLE_PIJ), NULL, NULL, j), 0);
    assert_float_equal(seg_angle(j, 2, 2), 0.0, 1e-3);
}

static void test_errors(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    float a[22] = {0}, j[21][3], before[21][3];
    memset(j, 0x5a, sizeof j);
    memcpy(before, j, sizeof j);
    float p[3] = {0}, q0[4] = {0}, q[4] = {1, 0, 0, 0};
    assert_int_equal(fp_hand_fk(NULL, FP_HAND_RIGHT, a, 0, NULL, NULL, j), -EINVAL);
    assert_int_equal(fp_hand_fk(&m, (fp_hand_side)7, a, 0, NULL, NULL, j), -EINVAL);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, NULL, 1, NULL, NULL, j), -EINVAL);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, 0, p, NULL, j), -EINVAL);
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, 0, p, q0, j), -EDOM);
    a[3] = INFINITY;
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, p, q, j), -ERANGE);
    a[3] = 0;
    p[1] = NAN;
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, FP_HAND_ALL_SENSORS, p, q, j), -ERANGE);
    m.size = 0;
    assert_int_equal(fp_hand_fk(&m, FP_HAND_RIGHT, a, 0, NULL, NULL, j), -EINVAL);
    assert_memory_equal(j, before, sizeof j);
    assert_string_equal(fp_hand_strerror(-EDOM),
                        "degenerate geometry (zero vector, zero quaternion or coincident joints)");
}

/* A random proper rotation as a quaternion. */
static void sample_pose(unsigned seed, float p[3], float q[4])
{
    srand(seed);
    double n = 0;
    for (int k = 0; k < 4; k++) {
        q[k] = (float)(rand() / (double)RAND_MAX - 0.5);
        n += q[k] * q[k];
    }
    for (int k = 0; k < 4; k++)
        q[k] = (float)(q[k] / sqrt(n));
    for (int k = 0; k < 3; k++)
        p[k] = (float)(rand() % 400 - 200);
}

static void test_frame_from_palm(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    m.size = 0.93f;
    for (int side = 0; side < 2; side++) {
        float a[22], p[3], q[4], j[21][3], jh[21][3];
        sample_angles(a, 10 + side);
        sample_pose(20 + side, p, q);
        /* Wrist angles at rest: then the palm's axes are the hand frame's. */
        uint32_t mask = FP_HAND_ALL_SENSORS & ~((1u << FP_SENSOR_WRIST_PITCH) | (1u << FP_SENSOR_WRIST_YAW));
        assert_int_equal(fp_hand_fk(&m, side, a, mask, p, q, j), 0);
        assert_int_equal(fp_hand_fk(&m, side, a, mask, NULL, NULL, jh), 0);
        /* Palm normal = -y, direction = -z of the hand frame, rotated into the device. */
        float w = q[0], x = q[1], y = q[2], z = q[3];
        float ny[3] = {-2 * (x * y - w * z), -(1 - 2 * (x * x + z * z)), -2 * (y * z + w * x)};
        float dz[3] = {-2 * (x * z + w * y), -2 * (y * z - w * x), -(1 - 2 * (x * x + y * y))};
        float p2[3], q2[4], back[21][3];
        assert_int_equal(fp_hand_frame_from_palm(&m, side, j[FP_JOINT_PALM], ny, dz, p2, q2), 0);
        for (int k = 0; k < 3; k++)
            assert_float_equal(p2[k], p[k], 1e-3);
        double s = q2[0] * q[0] + q2[1] * q[1] + q2[2] * q[2] + q2[3] * q[3];
        assert_float_equal(fabs(s), 1.0, 1e-5);
        assert_int_equal(fp_hand_to_hand_frame(p2, q2, (const float(*)[3])j, 21, back), 0);
        for (int i = 0; i < 21; i++)
            assert_true(dist(back[i], jh[i]) < 1e-3);
    }
    float z3[3] = {0}, one[3] = {0, 1, 0}, p[3], q[4];
    assert_int_equal(fp_hand_frame_from_palm(&m, FP_HAND_RIGHT, z3, z3, one, p, q), -EDOM);
    assert_int_equal(fp_hand_frame_from_palm(&m, FP_HAND_RIGHT, z3, one, one, p, q), -EDOM);
}

static void test_from_positions_roundtrip(void **state)
{
    (void)state;
    fp_hand_model m;
    fp_hand_model_init(&m);
    m.size = 1.08f;
    for (unsigned t = 0; t < 20; t++) {
        fp_hand_side side = t % 2 ? FP_HAND_LEFT : FP_HAND_RIGHT;
        float a[22], p[3], q[4], j[21][3], j2[21][3];
        sample_angles(a, 100 + t);
        uint32_t mask = FP_HAND_ALL_SENSORS & ~((1u << FP_SENSOR_PALM_ARCH) | (1u << FP_SENSOR_WRIST_PITCH) |
                                                (1u << FP_SENSOR_WRIST_YAW));
        sample_pose(200 + t, p, q);
        assert_int_equal(fp_hand_fk(&m, side, a, mask, p, q, j), 0);
        fp_hand_angles h;
        assert_int_equal(fp_hand_from_positions(&m, side, (const float(*)[3])j, &h), 0);
        assert_int_equal(h.valid, mask);
        for (int i = 0; i < 22; i++)
            if (mask & (1u << i))
                assert_float_equal(h.radians[i], a[i], 1e-4);
        assert_int_equal(fp_hand_fk(&m, side, h.radians, h.valid, h.wrist_pos_mm, h.wrist_rot_wxyz, j2), 0);
        for (int i = 0; i < 21; i++)
            assert_true(dist(j[i], j2[i]) < 1e-2);
    }
    float j[21][3] = {{0}}, tips[5][3], tips10[10][3];
    fp_hand_angles h;
    assert_int_equal(fp_hand_from_positions(&m, FP_HAND_RIGHT, (const float(*)[3])j, &h), -EDOM);
    j[3][1] = NAN;
    assert_int_equal(fp_hand_from_positions(&m, FP_HAND_RIGHT, (const float(*)[3])j, &h), -ERANGE);
    /* Fingertips: joints 4, 8, 12, 16, 20. */
    for (int i = 0; i < 21; i++)
        j[i][0] = (float)i;
    assert_int_equal(fp_hand_fingertips((const float(*)[3])j, tips), 0);
    assert_int_equal(fp_hand_fingertips2((const float(*)[3])j, (const float(*)[3])j, tips10), 0);
    for (int f = 0; f < 5; f++) {
        assert_float_equal(tips[f][0], 4 + 4 * f, 0);
        assert_float_equal(tips10[5 + f][0], 4 + 4 * f, 0);
    }
}

static void test_fit(void **state)
{
    (void)state;
    fp_hand_model truth, m;
    fp_hand_model_init(&truth);
    truth.size = 1.17f;
    truth.middle_yaw_rad = -0.25f;
    truth.rest_rad[FP_SENSOR_THUMB_ROTATE] = 0.3f;
    truth.base_mm[1][0] -= 4;
    truth.base_mm[4][2] += 3;
    enum { N = 30 };
    static float frames[N][21][3];
    for (unsigned t = 0; t < N; t++) {
        float a[22];
        sample_angles(a, 300 + t);
        /* THUMB_ROTATE and middle yaw are not measured: rest values, as in the Leap data */
        uint32_t mask = FP_HAND_ALL_SENSORS & ~(1u << FP_SENSOR_THUMB_ROTATE) &
                        ~((1u << FP_SENSOR_PALM_ARCH) | (1u << FP_SENSOR_WRIST_PITCH) | (1u << FP_SENSOR_WRIST_YAW));
        assert_int_equal(fp_hand_fk(&truth, FP_HAND_LEFT, a, mask, NULL, NULL, frames[t]), 0);
    }
    float s;
    fp_hand_model_init(&m);
    assert_int_equal(fp_hand_fit_size(&m, (const float(*)[21][3])frames, N, &s), 0);
    assert_float_equal(s, 1.17, 1e-4);
    assert_int_equal(fp_hand_fit_geometry(&m, FP_HAND_LEFT, (const float(*)[21][3])frames, N), 0);
    assert_float_equal(m.size, 1.17, 1e-4);
    assert_float_equal(m.middle_yaw_rad, -0.25, 1e-4);
    assert_float_equal(m.rest_rad[FP_SENSOR_THUMB_ROTATE], 0.3, 1e-4);
    for (int f = 0; f < 5; f++)
        for (int k = 0; k < 3; k++)
            assert_float_equal(m.base_mm[f][k], truth.base_mm[f][k], 1e-2);
    assert_int_equal(fp_hand_fit_size(&m, (const float(*)[21][3])frames, 0, &s), -EINVAL);
}

static void test_csv_errors(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_hand_test_XXXXXX", path[256], err[512];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/a.csv", dir);
    const char *hdr = "frame,timestamp_us,hand_id,hand_type,thumb_rotation,thumb_mcp,thumb_ip,thumb_abduction,"
                      "index_mcp,index_pip,index_dip,middle_mcp,middle_pip,middle_dip,middle_index_abduction,"
                      "ring_mcp,ring_pip,ring_dip,ring_middle_abduction,pinky_mcp,pinky_pip,pinky_dip,"
                      "pinky_ring_abduction,palm_arch,wrist_pitch,wrist_yaw\n";
    const char *good = "0,5,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n";
    char text[9000];
    fp_leap_angles_row *rows = NULL;
    size_t n = 0;
    snprintf(text, sizeof text, "%s%s%s", hdr, good, "1,6,1,right,,1,2,3,4,5,6,7,8,x9,10,11,12,13,14,15,16,17,18,,,\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:3:30: bad number \"x9\" in column middle_dip"));
    snprintf(text, sizeof text, "%s%s", hdr, "0,5,1,middle,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:2:7: unknown hand_type \"middle\""));
    snprintf(text, sizeof text, "%s%s", hdr, "0,5,1,right,,1,2\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:2:17: expected 26 fields, found 7 (row too short)"));
    fp_test_write_file(path, "frame,timestamp_us,hand_id,hand_type,thumb_rot\n");
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:1:47: header has 5 columns, expected 26"));
    /* one header column too many: named at the extra column, nothing read past the end */
    char want[256];
    snprintf(text, sizeof text, "%.*s,extra\n%s", (int)strlen(hdr) - 1, hdr, good);
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    snprintf(want, sizeof want, "a.csv:1:%d: header has 27 columns, expected 26", (int)strlen(hdr) + 1);
    assert_non_null(strstr(err, want));
    /* beyond float range is not finite; times must not run backwards */
    snprintf(text, sizeof text, "%s%s", hdr, "0,5,1,right,,1e39,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:2:14: \"1e39\" in column thumb_mcp is not a finite number"));
    /* numbers are decimals, as in every option: strtod's hexadecimal was read ("0x1p3" as 8)
     * and a leading blank skipped, now each is a bad number; inf and nan are not finite */
    static const struct { const char *value, *says; } nondecimal[] = {
        {"0x1p3", "a.csv:2:14: bad number \"0x1p3\" in column thumb_mcp"},
        {"0X10", "a.csv:2:14: bad number \"0X10\" in column thumb_mcp"},
        {"-0x1.8p1", "a.csv:2:14: bad number \"-0x1.8p1\" in column thumb_mcp"},
        {" 1", "a.csv:2:14: bad number \" 1\" in column thumb_mcp"},
        {"inf", "a.csv:2:14: \"inf\" in column thumb_mcp is not a finite number"},
        {"-Infinity", "a.csv:2:14: \"-Infinity\" in column thumb_mcp is not a finite number"},
        {"nan", "a.csv:2:14: \"nan\" in column thumb_mcp is not a finite number"},
    };
    for (size_t i = 0; i < sizeof nondecimal / sizeof nondecimal[0]; i++) {
        snprintf(text, sizeof text, "%s0,5,1,right,,%s,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n",
                 hdr, nondecimal[i].value);
        fp_test_write_file(path, text);
        assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
        if (!strstr(err, nondecimal[i].says)) fail_msg("%s: \"%s\"", nondecimal[i].value, err);
    }
    /* every decimal form reads */
    snprintf(text, sizeof text, "%s0,5,1,right,,+1.5,.5,5.,-0,1e-05,2E+2,-.25e1,8,9,10,11,12,13,14,15,16,17,18,,,\n",
             hdr);
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), 0);
    assert_int_equal(n, 1);
    const float want_deg[] = {1.5f, 0.5f, 5.0f, -0.0f, 1e-05f, 200.0f, -2.5f};
    for (int k = 0; k < 7; k++) assert_true(rows[0].degrees[1 + k] == want_deg[k]);
    assert_true(signbit(rows[0].degrees[4]));
    free(rows);
    rows = NULL;
    snprintf(text, sizeof text, "%s%s%s", hdr, good, "1,4,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:3:3: timestamp_us 4 goes backwards"));
    /* times whose span would overflow int64 ns are refused (|timestamp_us| <= 10^15) */
    snprintf(text, sizeof text, "%s%s%s", hdr,
             "0,-1000000000000000,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n",
             "1,9223372036854775,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n");
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv:3:3: timestamp_us 9223372036854775 out of range"));
    snprintf(text, sizeof text, "%s%s", hdr, good);
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), 0);
    assert_int_equal(n, 1);
    assert_int_equal(rows[0].valid, 0x3FFFFFu & ~1u & ~(7u << 19));
    assert_float_equal(rows[0].degrees[FP_SENSOR_PINKIE_RING_AB], 18, 0);
    /* saved by a spreadsheet as "CSV UTF-8" on Windows: a byte order mark and CRLF lines
     * read as the plain file (before: "header column 1 is ..." for the mark) */
    fp_leap_angles_row first = rows[0];
    free(rows);
    rows = NULL;
    snprintf(text, sizeof text, "\xEF\xBB\xBF%.*s\r\n%.*s\r\n", (int)strlen(hdr) - 1, hdr,
             (int)strlen(good) - 1, good);
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), 0);
    assert_int_equal(n, 1);
    assert_memory_equal(rows[0].degrees, first.degrees, sizeof first.degrees);
    assert_int_equal(rows[0].valid, first.valid);
    free(rows);
    rows = NULL;
    /* hand_type in any case, as other writers than Leap's JavaScript give it */
    snprintf(text, sizeof text, "%s0,5,1,Right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n"
             "1,6,2,LEFT,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n", hdr);
    fp_test_write_file(path, text);
    assert_int_equal(fp_leapcsv_read_angles(path, &rows, &n, err, sizeof err), 0);
    assert_int_equal(n, 2);
    assert_int_equal(rows[0].side, FP_HAND_RIGHT);
    assert_int_equal(rows[1].side, FP_HAND_LEFT);
    free(rows);
    /* The joints reader names the column of a bad value. */
    snprintf(text, sizeof text, "%s/hands/leap-motion/grab_joints_mm.csv", fp_test_data_dir());
    FILE *in = fopen(text, "r");
    assert_non_null(in);
    char line1[4096], line2[4096];
    assert_non_null(fgets(line1, sizeof line1, in));
    assert_non_null(fgets(line2, sizeof line2, in));
    fclose(in);
    char *c = line2;
    for (int k = 0; k < 20; k++) /* field 21 = thumb_dip_y */
        c = strchr(c, ',') + 1;
    *c = 'q';
    snprintf(text, sizeof text, "%s%s", line1, line2);
    fp_test_write_file(path, text);
    fp_leap_joints_row *jr = NULL;
    assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), -EBADMSG);
    snprintf(want, sizeof want, "a.csv:2:%ld: bad number \"q", (long)(c - line2) + 1);
    assert_non_null(strstr(err, want));
    assert_non_null(strstr(err, "in column thumb_dip_y"));
    /* A joint position beyond 10 m (FP_EVENT_MAX_MM), finite or not, is not a hand: the
     * replay would place the hands by it (a 98th percentile far away) and move nothing */
    static const char *far[] = {"1e38", "-10000.5", "25000"};
    for (size_t i = 0; i < sizeof far / sizeof far[0]; i++) {
        snprintf(text, sizeof text, "%.*s%s%s", (int)(c - line2), line2, far[i], strchr(c, ','));
        FILE *o = fopen(path, "w");
        assert_non_null(o);
        fputs(line1, o);
        fputs(text, o);
        fclose(o);
        assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), -EBADMSG);
        snprintf(want, sizeof want, "a.csv:2:%ld: %s in column thumb_dip_y is beyond 10 m", (long)(c - line2) + 1,
                 far[i]);
        assert_non_null(strstr(err, want));
    }
    snprintf(text, sizeof text, "%.*s%s%s", (int)(c - line2), line2, "9999.5", strchr(c, ','));
    FILE *o = fopen(path, "w");
    assert_non_null(o);
    fputs(line1, o);
    fputs(text, o);
    fclose(o);
    assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), 0); /* within: read */
    free(jr);
    jr = NULL;
    /* a file past FP_LEAPCSV_MAX_BYTES (the header, then a sparse 2 TiB): refused by its size
     * before a byte of it is read (read whole first, it ran out of memory: -ENOMEM) */
    assert_int_equal(truncate(path, (off_t)1 << 41), 0);
    assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "a.csv: larger than 1 GiB"));
    assert_null(jr);
    /* a FIFO: refused, never waited on for a writer */
    unlink(path);
    assert_int_equal(mkfifo(path, 0600), 0);
    assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), -ENXIO);
    assert_non_null(strstr(err, "a.csv: cannot open: is not a regular file"));
    unlink(path);
    rmdir(dir);
    assert_int_equal(fp_leapcsv_read_joints(path, &jr, &n, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, "a.csv"));
}

/* Measured (release build, this commit): median fingertip errors per hand, geometry fitted,
 * 7.6, 5.6, 7.3, 9.6 (three-claps left), 12.0 (three-claps right) mm; mean 8.4 mm.
 * Size only: mean 9.0 mm. The bounds leave about 20% margin. */
static void test_leap_recordings(void **state)
{
    (void)state;
    static const char *const recs[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    double sum = 0, sum_size = 0;
    int hands = 0;
    for (int r = 0; r < 4; r++) {
        char jp[1024], ap[1024], err[512];
        snprintf(jp, sizeof jp, "%s/hands/leap-motion/%s_joints_mm.csv", fp_test_data_dir(), recs[r]);
        snprintf(ap, sizeof ap, "%s/hands/leap-motion/%s_cyberglove_like_angles_deg.csv", fp_test_data_dir(), recs[r]);
        fp_handcheck_hand h[4], hs[4];
        size_t n = 0, ns = 0;
        fp_handcheck_options geo = {FP_HANDCHECK_FIT_GEOMETRY, 0}, size = {FP_HANDCHECK_FIT_SIZE, 0};
        int rc = fp_handcheck_recording(jp, ap, &geo, h, 4, &n, err, sizeof err);
        if (rc)
            fail_msg("%s", err);
        assert_int_equal(fp_handcheck_recording(jp, ap, &size, hs, 4, &ns, err, sizeof err), 0);
        assert_int_equal(n, r == 3 ? 2 : 1);
        for (size_t i = 0; i < n; i++) {
            print_message("%s hand %ld: median %.2f mm, p90 %.2f mm (size only: %.2f mm), size %.3f\n",
                          recs[r], h[i].hand_id, h[i].median_all_mm, h[i].p90_all_mm,
                          hs[i].median_all_mm, h[i].model.size);
            assert_true(h[i].frames > 250);
            assert_true(h[i].median_all_mm < 14.5);
            assert_true(h[i].model.size > 0.9 && h[i].model.size < 1.15);
            sum += h[i].median_all_mm;
            sum_size += hs[i].median_all_mm;
            hands++;
        }
    }
    assert_int_equal(hands, 5);
    assert_true(sum / hands < 10.0);
    assert_true(sum_size / hands < 11.0);
}

/* fp_hand_mat_to_quat / fp_hand_quat_to_mat against Rodrigues' formula (axis-angle, an
 * independent construction), including 180-degree turns, where a trace-only method fails. */
static void test_quaternion_matrix(void **state)
{
    (void)state;
    srand(3);
    for (int k = 0; k < 200; k++) {
        double a[3] = {rand() / (double)RAND_MAX - 0.5, rand() / (double)RAND_MAX - 0.5,
                       rand() / (double)RAND_MAX - 0.5};
        if (k % 4 == 0) a[k % 3] = 0; /* some axes in coordinate planes */
        double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int i = 0; i < 3; i++) a[i] /= n;
        double th = k < 20 ? PI : (rand() / (double)RAND_MAX) * 2 * PI - PI;
        double c = cos(th), s = sin(th), R[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) R[i][j] = (i == j ? c : 0) + (1 - c) * a[i] * a[j];
        R[0][1] -= s * a[2], R[0][2] += s * a[1], R[1][0] += s * a[2];
        R[1][2] -= s * a[0], R[2][0] -= s * a[1], R[2][1] += s * a[0];
        float q[4];
        fp_hand_mat_to_quat((const double (*)[3])R, q);
        assert_true(q[0] >= 0);
        /* q = +-(cos th/2, sin th/2 a) */
        double sg = cos(th / 2) >= 0 ? 1 : -1;
        if (fabs(cos(th / 2)) < 1e-6 && q[1] * a[0] + q[2] * a[1] + q[3] * a[2] < 0) sg = -sg;
        assert_float_equal(q[0], sg * cos(th / 2), 1e-6);
        for (int i = 0; i < 3; i++) assert_float_equal(q[1 + i], sg * sin(th / 2) * a[i], 1e-6);
        double back[3][3];
        assert_int_equal(fp_hand_quat_to_mat(q, back), 0);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) assert_float_equal(back[i][j], R[i][j], 1e-6);
    }
    const float zero[4] = {0, 0, 0, 0}, nan4[4] = {NAN, 0, 0, 0};
    double r[3][3];
    assert_int_equal(fp_hand_quat_to_mat(zero, r), -EINVAL);
    assert_int_equal(fp_hand_quat_to_mat(nan4, r), -EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_straight_hand),
        cmocka_unit_test(test_mcp_right_angle),
        cmocka_unit_test(test_repeatable),
        cmocka_unit_test(test_left_mirrors_right),
        cmocka_unit_test(test_size_linear),
        cmocka_unit_test(test_masked_is_default),
        cmocka_unit_test(test_dip_coupling),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_frame_from_palm),
        cmocka_unit_test(test_from_positions_roundtrip),
        cmocka_unit_test(test_fit),
        cmocka_unit_test(test_csv_errors),
        cmocka_unit_test(test_quaternion_matrix),
        cmocka_unit_test(test_leap_recordings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
