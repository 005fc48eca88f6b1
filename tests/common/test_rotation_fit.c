/* Tests of fp_rotation_fit (fp_similarity.h): a known turn of a spanning set is recovered
 * (to the tie-break's share of its angle); two points and collinear ones, whose turn about
 * their line is free, get the least turn that carries them (checked against the angle
 * between their directions); coincident points the identity; a translation no turn. */
#define _GNU_SOURCE /* M_PI */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "fp_similarity.h"
#include "fp_vec.h"

/* the angle of unit quaternion q (w >= 0), radians */
static double angle(const double q[4])
{
    return 2 * atan2(sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), q[0]);
}

static void test_known_turn(void **state)
{
    (void)state;
    const double a[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 1.5}, {1, 1, 1}};
    const double axis[3] = {1 / sqrt(3), 1 / sqrt(3), -1 / sqrt(3)}, th = 2.0; /* 115 degrees */
    const double q0[4] = {cos(th / 2), sin(th / 2) * axis[0], sin(th / 2) * axis[1], sin(th / 2) * axis[2]};
    double b[5][3], q[4];
    for (int i = 0; i < 5; i++) {
        fp_qrot(q0, a[i], b[i]);
        b[i][0] += 3, b[i][1] -= 1, b[i][2] += 0.5;
    }
    fp_rotation_fit(a, (const double(*)[3])b, 5, q);
    for (int k = 0; k < 4; k++) assert_true(fabs(q[k] - q0[k]) < 3 * FP_ROTATION_FIT_BIAS);
    assert_true(fabs(angle(q) - th) < 3 * FP_ROTATION_FIT_BIAS * th);
}

static void test_free_turns(void **state)
{
    (void)state;
    /* two points: from along x to along (cos 150, sin 150, 0) degrees: the least turn is 150
     * degrees about z (any other carrying them is larger) */
    const double a[2][3] = {{-1, 0, 0}, {1, 0, 0}};
    const double c = cos(150 * M_PI / 180), s = sin(150 * M_PI / 180);
    const double b[2][3] = {{5 - c, -s, 2}, {5 + c, s, 2}};
    double q[4];
    fp_rotation_fit(a, b, 2, q);
    assert_true(fabs(angle(q) - 150 * M_PI / 180) < 1e-2);
    assert_true(fabs(q[1]) < 1e-6 && fabs(q[2]) < 1e-6);
    /* three collinear points, a quarter turn about y */
    const double l[3][3] = {{0, 0, 0}, {1, 0, 0}, {3, 0, 0}}, m[3][3] = {{0, 0, 0}, {0, 0, -1}, {0, 0, -3}};
    fp_rotation_fit(l, m, 3, q);
    assert_true(fabs(angle(q) - M_PI / 2) < 1e-2);
    assert_true(fabs(q[1]) < 1e-6 && fabs(q[3]) < 1e-6);
    /* coincident points, and a translation: the identity */
    const double p[3][3] = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}, r[3][3] = {{4, 0, 1}, {4, 0, 1}, {4, 0, 1}};
    fp_rotation_fit(p, r, 3, q);
    assert_true(q[0] == 1 && q[1] == 0 && q[2] == 0 && q[3] == 0);
    const double t[3][3] = {{1, 1, 1}, {2, 0, 1}, {0, 3, 0}};
    double tt[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) tt[i][k] = t[i][k] + (k == 1 ? 7 : 0);
    fp_rotation_fit(t, (const double(*)[3])tt, 3, q);
    assert_true(angle(q) < 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_known_turn), cmocka_unit_test(test_free_turns)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
