/* Tests of twist_path.h: fingertips that turn together get waypoints on the turn, which keep
 * their distances; a drag, a stretch and fingertips closing onto one point keep the straight
 * line (no waypoints); clusters apart are apart; and through the engine step, a pinch turned
 * half a turn is reached in full where the straight line stops short. */
#define _GNU_SOURCE /* M_PI */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "step_engine.h"
#include "twist_path.h"

static double dist(const float *a, const float *b)
{
    double d = 0;
    for (int c = 0; c < 3; c++) d += ((double)a[c] - b[c]) * ((double)a[c] - b[c]);
    return sqrt(d);
}

/* point i of a pinch about centre (cx, 0, 0), half gap r, turned by angle a about z */
static void pinch(float p[2][3], double cx, double r, double a)
{
    p[0][0] = (float)(cx - r * cos(a)), p[0][1] = (float)(-r * sin(a)), p[0][2] = 0;
    p[1][0] = (float)(cx + r * cos(a)), p[1][1] = (float)(r * sin(a)), p[1][2] = 0;
}

/* A pinch turned by 180, 135 and 100 degrees: waypoints that keep the tips apart (the
 * straight lines meet at 180 degrees); legs of at most 45 degrees; the gap on the way within
 * the start's and the end's (rigid turn: the same). */
static void test_turned_pinch(void **state)
{
    (void)state;
    const double turns[3] = {M_PI, 0.75 * M_PI, 100 * M_PI / 180};
    const size_t legs[3] = {3, 2, 2};
    for (int t = 0; t < 3; t++) {
        float st[2][3], en[2][3], via[FP_TWIST_MAX_VIA * 2][3];
        pinch(st, 0, 0.1, 0);
        pinch(en, 0.5, 0.1, turns[t] - 1e-3); /* (a half turn exactly: either way) */
        size_t k = fp_twist_path(2, (const float(*)[3])st, (const float(*)[3])en, 1.0, &via[0][0]);
        assert_int_equal(k, legs[t]);
        for (size_t j = 0; j < k; j++) {
            double g = dist(via[2 * j], via[2 * j + 1]);
            if (t < 2) assert_true(fabs(g - 0.2) < 2e-4); /* w = 1: the turn (less its tie-break) */
            else assert_true(g > 0.2 * cos(50 * M_PI / 180) && g < 0.2 + 1e-5); /* blended */
            /* the centre moves straight */
            double u = (double)(j + 1) / (double)(k + 1);
            assert_true(fabs(0.5 * ((double)via[2 * j][0] + via[2 * j + 1][0]) - 0.5 * u) < 1e-5);
        }
    }
}

/* Straight stays straight: a five-tip drag, a stretch, a pinch closing onto one point, and a
 * single fingertip give no waypoints (the engine's step bit for bit as before). */
static void test_straight_kept(void **state)
{
    (void)state;
    float st[5][3], en[5][3], via[FP_TWIST_MAX_VIA * 5][3];
    for (int i = 0; i < 5; i++) {
        st[i][0] = 0.1f * i, st[i][1] = 0.02f * i * i, st[i][2] = 0;
        en[i][0] = st[i][0] + 0.7f, en[i][1] = st[i][1] - 0.3f, en[i][2] = 0.2f;
    }
    assert_int_equal(fp_twist_path(5, (const float(*)[3])st, (const float(*)[3])en, 1.0, &via[0][0]), 0);
    for (int i = 0; i < 5; i++) en[i][0] = 2.5f * st[i][0]; /* stretched along the row */
    assert_int_equal(fp_twist_path(5, (const float(*)[3])st, (const float(*)[3])en, 1.0, &via[0][0]), 0);
    float a[2][3], b[2][3];
    pinch(a, 0, 0.3, 0.2);
    pinch(b, 0.1, 0.01, 0.2); /* closing onto one point: the end is the nearest */
    assert_int_equal(fp_twist_path(2, (const float(*)[3])a, (const float(*)[3])b, 1.0, &via[0][0]), 0);
    assert_int_equal(fp_twist_path(1, (const float(*)[3])a, (const float(*)[3])b, 1.0, &via[0][0]), 0);
    assert_int_equal(fp_twist_path(0, (const float(*)[3])a, (const float(*)[3])b, 1.0, &via[0][0]), 0);
}

/* Two hands apart (supports apart: start points over 2R apart): one turns a pinch, the other
 * drags; the dragging one's waypoints lie on its straight lines. */
static void test_clusters_apart(void **state)
{
    (void)state;
    float st[4][3], en[4][3], via[FP_TWIST_MAX_VIA * 4][3];
    pinch(st, 0, 0.1, 0);
    pinch(en, 0.3, 0.1, 0.9 * M_PI);
    float (*o)[3] = st + 2, (*oe)[3] = en + 2;
    pinch(o, 5, 0.2, 0);
    pinch(oe, 5.5, 0.2, 0.1);
    size_t k = fp_twist_path(4, (const float(*)[3])st, (const float(*)[3])en, 1.0, &via[0][0]);
    assert_int_equal(k, 3);
    for (size_t j = 0; j < k; j++) {
        double u = (double)(j + 1) / (double)(k + 1);
        assert_true(fabs(dist(via[4 * j], via[4 * j + 1]) - 0.2) < 2e-4);
        for (int i = 2; i < 4; i++)
            for (int c = 0; c < 3; c++)
                assert_true(fabs(via[4 * j + i][c] - (st[i][c] + u * ((double)en[i][c] - st[i][c]))) < 1e-6);
    }
}

/* Through the session's engine step on a lattice (R = 1): the pinch turned half a turn is
 * composed along the waypoints and reached (fp_engine_result.reached 1, via 3), where the
 * straight line would stop short (csrbf_guarded_step without them: under 60%). */
static void test_engine_reaches(void **state)
{
    (void)state;
    enum { Q = 16 };
    static float base[(Q + 1) * (Q + 1) * (Q + 1)][3], out[(Q + 1) * (Q + 1) * (Q + 1)][3];
    size_t n = 0;
    for (int z = 0; z <= Q; z++)
        for (int y = 0; y <= Q; y++)
            for (int x = 0; x <= Q; x++, n++)
                base[n][0] = -1.4f + 3.3f * x / Q, base[n][1] = -1.4f + 2.8f * y / Q, base[n][2] = -1.2f + 2.4f * z / Q;
    fp_engine_step e;
    assert_int_equal(fp_engine_step_init(&e, n, &base[0][0], 1), 0);
    memcpy(out, base, sizeof out);
    fp_engine_step_output_is_base(&e);
    float st[FP_ENGINE_MAX_CONTROL][3] = {{0}}, en[FP_ENGINE_MAX_CONTROL][3] = {{0}};
    pinch(st, 0, 0.1, 0);
    pinch(en, 0.5, 0.15, M_PI - 1e-3);
    fp_control_set cs = {.size = sizeof cs, .active = true, .radius = 1.0, .capacity = FP_ENGINE_MAX_CONTROL,
                         .count = 2, .start = st, .end = en};
    fp_engine_result r;
    assert_int_equal(fp_engine_step_run(&e, &cs, &out[0][0], &r, NULL), 0);
    assert_int_equal(r.via, 3);
    assert_true(r.reached == 1.0);
    assert_true(r.substeps > 3);
    /* the straight line: the engine alone */
    csrbf_solver *s;
    csrbf_options o = {0};
    o.radius = 1.0;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
    csrbf_points *p;
    assert_int_equal(csrbf_points_create(n, &base[0][0], &p), CSRBF_OK);
    csrbf_guard g = {FP_ENGINE_GUARD_MARGIN, FP_ENGINE_MAX_SUBSTEPS, 0u, FP_ENGINE_MAX_PAIRS, NULL, 0};
    csrbf_guard_stats gs;
    static float ref[(Q + 1) * (Q + 1) * (Q + 1)][3];
    assert_int_equal(csrbf_guarded_step(s, p, 2, &st[0][0], &en[0][0], &g, &ref[0][0], &gs), CSRBF_WARN_LIMITED);
    assert_true(gs.reached < 0.6);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    fp_engine_step_free(&e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_turned_pinch),
        cmocka_unit_test(test_straight_kept),
        cmocka_unit_test(test_clusters_apart),
        cmocka_unit_test(test_engine_reaches),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
