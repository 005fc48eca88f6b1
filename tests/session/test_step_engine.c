/* core/session/step_engine: factor or reuse (bitwise start points), solve, evaluate, the
 * engine's codes unchanged and logged once, fingertip distances against a double brute
 * force. */
#include "log_capture.h"
#include "step_engine.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define G 21 /* a G x G x 2 grid of vertices, spacing 0.1 */

static float *grid(size_t *n)
{
    *n = G * G * 2;
    float *v = malloc(*n * 3 * sizeof *v);
    size_t k = 0;
    for (int z = 0; z < 2; z++)
        for (int y = 0; y < G; y++)
            for (int x = 0; x < G; x++) {
                v[3 * k] = 0.1f * x;
                v[3 * k + 1] = 0.1f * y;
                v[3 * k + 2] = 0.1f * z;
                k++;
            }
    return v;
}

static void test_factor_reuse_and_interpolation(void **state)
{
    (void)state;
    size_t n;
    float *base = grid(&n), *out = malloc(n * 3 * sizeof *out);
    fp_engine_step e;
    assert_int_equal(fp_engine_step_init(&e, n, base, 1), 0);
    float start[2][3] = {{0.5f, 0.5f, 0.f}, {1.5f, 1.5f, 0.1f}}, end[2][3];
    memcpy(end, start, sizeof end);
    end[0][2] += 0.1f;
    end[1][0] -= 0.05f;
    fp_control_set cs = {0};
    cs.size = sizeof cs;
    cs.active = true;
    cs.radius = 0.5;
    cs.capacity = 2;
    cs.count = 2;
    cs.start = start;
    cs.end = end;
    fp_engine_result r;
    assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
    assert_true(r.refactored);
    assert_true(r.pairs > 0);
    assert_non_null(fp_engine_step_solver(&e));
    /* T(s_i) = d_i: both start points are grid vertices (5,5,0) and (15,15,1) */
    size_t v0 = 5 * G + 5, v1 = G * G + 15 * G + 15;
    for (int k = 0; k < 3; k++) {
        assert_true(fabsf(out[3 * v0 + k] - end[0][k]) < 1e-5f);
        assert_true(fabsf(out[3 * v1 + k] - end[1][k]) < 1e-5f);
    }
    /* a vertex beyond every support does not move, bit for bit */
    assert_memory_equal(&out[3 * (G * G - 1)], &base[3 * (G * G - 1)], 3 * sizeof(float));
    /* same start points: the factor is reused; a moved start or a new radius refactors */
    end[0][2] += 0.05f;
    assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
    assert_false(r.refactored);
    start[1][0] += 1e-6f;
    assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
    assert_true(r.refactored);
    cs.radius = 0.6;
    assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
    assert_true(r.refactored);
    fp_engine_step_invalidate(&e);
    assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
    assert_true(r.refactored);
    fp_engine_step_free(&e);
    free(base);
    free(out);
}

/* An engine error (a radius the engine refuses) comes back as the engine's code and is
 * logged once, then counted. */
static void test_engine_error_once(void **state)
{
    (void)state;
    size_t n;
    float *base = grid(&n), *out = malloc(n * 3 * sizeof *out);
    fp_engine_step e;
    assert_int_equal(fp_engine_step_init(&e, n, base, 1), 0);
    float start[1][3] = {{0.5f, 0.5f, 0.f}}, end[1][3] = {{0.5f, 0.5f, 0.1f}};
    fp_control_set cs = {0};
    cs.radius = 1e20; /* above the engine's limit */
    cs.count = 1;
    cs.capacity = 1;
    cs.start = start;
    cs.end = end;
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    fp_engine_result r;
    for (int f = 0; f < 5; f++) assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, &log), CSRBF_ERR_INVALID);
    assert_int_equal(cap.count, 1);
    assert_string_equal(cap.source, "engine");
    fp_engine_step_flush(&e, &log);
    assert_int_equal(cap.count, 2);
    assert_non_null(strstr(cap.lines[1], "repeated 4 more times"));
    fp_engine_step_free(&e);
    free(base);
    free(out);
}

static void test_tip_distances(void **state)
{
    (void)state;
    size_t n;
    float *base = grid(&n);
    fp_hand_pose hands[FP_HANDS];
    memset(hands, 0, sizeof hands);
    hands[FP_HAND_RIGHT].present = true;
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) hands[FP_HAND_RIGHT].joints[j][k] = 0.37f * (float)(j % 7) - 0.3f + 0.11f * k;
    float d[FP_HANDS][FP_FINGERS];
    fp_engine_tip_distances(base, n, hands, d);
    for (int f = 0; f < FP_FINGERS; f++) {
        assert_true(isinf(d[FP_HAND_LEFT][f]));
        const float *t = hands[FP_HAND_RIGHT].joints[FP_JOINT_TIP(f)];
        double best = INFINITY;
        for (size_t v = 0; v < n; v++) {
            double q = 0;
            for (int k = 0; k < 3; k++) q += ((double)base[3 * v + k] - t[k]) * ((double)base[3 * v + k] - t[k]);
            best = fmin(best, sqrt(q));
        }
        assert_true(fabs(d[FP_HAND_RIGHT][f] - best) < 1e-5);
    }
    free(base);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_factor_reuse_and_interpolation),
        cmocka_unit_test(test_engine_error_once),
        cmocka_unit_test(test_tip_distances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
