/* csrbf_eval_stats.min_jacobian_det against closed forms: one centre (alpha = d - s, A = [1])
 * gives T(x) = x + alpha psi(r), r = |x - s| / R, whose Jacobian I + alpha grad(phi)^T has
 * det 1 + alpha . grad(phi) = 1 + psi'(r) alpha . (x - s) / (R |x - s|). Vertices behind the
 * push (alpha . (x - s) < 0) all have det > 1: the minimum over them is above 1, not 1. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csrbf.h"

/* psi31'(r) = -20 r (1-r)^3 (csrbf.md table) */
static double dpsi31(double r) { return r < 1.0 ? -20.0 * r * pow(1.0 - r, 3) : 0.0; }

static void test_min_det_above_one(void **state)
{
    (void)state;
    const double R = 2.0, ax = (double)0.3f; /* alpha = (0.3, 0, 0) at the origin, as a float */
    const size_t nv = 40;
    float v[120], out[120];
    double want = INFINITY;
    for (size_t i = 0; i < nv; i++) { /* behind the push: x < 0, inside the support */
        double x = -0.2 - 1.0 * (double)i / nv, y = 0.4 * sin((double)i), z = 0.3 * cos(3.0 * i);
        v[3 * i] = (float)x;
        v[3 * i + 1] = (float)y;
        v[3 * i + 2] = (float)z;
        double X = v[3 * i], Y = v[3 * i + 1], Z = v[3 * i + 2], d = sqrt(X * X + Y * Y + Z * Z);
        want = fmin(want, 1.0 + dpsi31(d / R) * ax * X / (R * d));
    }
    assert_true(want > 1.01);
    csrbf_options o = {0};
    o.radius = R;
    csrbf_solver *s;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
    const float st[3] = {0, 0, 0}, en[3] = {(float)ax, 0, 0};
    assert_int_equal(csrbf_solver_solve(s, 1, st, en), CSRBF_OK);
    csrbf_points *p;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    csrbf_eval_stats es;
    assert_int_equal(csrbf_evaluate(s, p, out, CSRBF_EVAL_JACOBIAN, &es), CSRBF_OK);
    assert_int_equal(es.moved, nv);
    if (!(fabs(es.min_jacobian_det - want) < 1e-9))
        fail_msg("min_jacobian_det %.9g, closed form %.9g", es.min_jacobian_det, want);
    /* the guarded step's statistics: the one map it applied */
    csrbf_guard g = {0};
    g.eval_flags = CSRBF_EVAL_JACOBIAN;
    csrbf_guard_stats gs;
    assert_int_equal(csrbf_guarded_step(s, p, 1, st, en, &g, out, &gs), CSRBF_OK);
    if (!(fabs(gs.eval.min_jacobian_det - want) < 1e-9))
        fail_msg("guarded min_jacobian_det %.9g, closed form %.9g", gs.eval.min_jacobian_det, want);
    /* no vertex in the support: 1, as documented */
    float far[3] = {10, 10, 10}, fo[3];
    csrbf_points *q;
    assert_int_equal(csrbf_points_create(1, far, &q), CSRBF_OK);
    assert_int_equal(csrbf_evaluate(s, q, fo, CSRBF_EVAL_JACOBIAN, &es), CSRBF_OK);
    assert_int_equal(es.moved, 0);
    assert_true(es.min_jacobian_det == 1.0);
    csrbf_points_destroy(&q);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_min_det_above_one),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
