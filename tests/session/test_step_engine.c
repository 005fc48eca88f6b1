/* core/session/step_engine: factor or reuse (bitwise start points), solve, evaluate, the
 * engine's codes unchanged and logged once, fingertip distances against a double brute
 * force. */
#include "fp_test_support.h"
#include "log_capture.h"
#include "step_engine.h"
#include "fp_mesh.h"

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

/* csrbf_points_nearest through the engine step equals the brute force bit for bit, on the
 * ICT face, for tips near and far from the surface, inside the head and beyond its box. */
static void test_tip_distances_indexed_ict(void **state)
{
    (void)state;
    const char *path = fp_test_face_path();
    char err[512];
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    size_t n = m->vertex_count;
    fp_engine_step e;
    assert_int_equal(fp_engine_step_init(&e, n, m->positions, 1), 0);
    float lo[3], hi[3];
    fp_mesh_bounds(m, lo, hi);
    srand(7);
    unsigned checked = 0, near_checked = 0, far_checked = 0;
    for (int trial = 0; trial < 60; trial++) {
        fp_hand_pose hands[FP_HANDS];
        memset(hands, 0, sizeof hands);
        for (int h = 0; h < FP_HANDS; h++) {
            hands[h].present = trial % 3 != h; /* one hand, the other, or both */
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) {
                    float u = (float)rand() / (float)RAND_MAX * 1.6f - 0.3f; /* beyond the box too */
                    float v = lo[k] + u * (hi[k] - lo[k]);
                    /* some tips exactly on a vertex */
                    if (j % 5 == 0) v = m->positions[3 * ((size_t)rand() % n) + k];
                    hands[h].joints[j][k] = v;
                }
        }
        if (trial % 7 == 0) /* a tip on a vertex, all three coordinates */
            memcpy(hands[0].joints[FP_JOINT_TIP(1)], m->positions + 3 * (size_t)(trial * 311 % n), 12);
        float a[FP_HANDS][FP_FINGERS], b[FP_HANDS][FP_FINGERS];
        fp_engine_step_tip_distances(&e, hands, INFINITY, a);
        fp_engine_tip_distances(m->positions, n, hands, b);
        assert_memory_equal(a, b, sizeof a);
        /* bounded (the session's reach): the brute force's value where it is within the
         * reach, bit for bit, "far" (+INFINITY) beyond it; a reach exactly at a tip's distance
         * still holds it */
        for (int h = 0; h < FP_HANDS; h++)
            for (int f = 0; f < FP_FINGERS; f++) {
                float reaches[4] = {0.f, 0.02f * (hi[1] - lo[1]), 0.1f * (hi[1] - lo[1]), b[h][f]};
                for (int r = 0; r < 4; r++) {
                    if (isinf(reaches[r])) continue;
                    float c[FP_HANDS][FP_FINGERS];
                    fp_engine_step_tip_distances(&e, hands, reaches[r], c);
                    for (int h2 = 0; h2 < FP_HANDS; h2++)
                        for (int f2 = 0; f2 < FP_FINGERS; f2++) {
                            if (b[h2][f2] <= reaches[r]) {
                                assert_memory_equal(&c[h2][f2], &b[h2][f2], sizeof(float));
                                near_checked++;
                            } else {
                                assert_true(isinf(c[h2][f2]) && c[h2][f2] > 0);
                                far_checked++;
                            }
                        }
                }
            }
        checked++;
    }
    assert_true(near_checked > 100 && far_checked > 100);
    /* the index: a vertex at the reported distance; max_dist cuts */
    float q[2][3] = {{0, 0, 0}, {hi[0] + 100, hi[1], hi[2]}}, d[2];
    uint32_t idx[2];
    memcpy(q[0], m->positions + 3 * 1234, sizeof q[0]);
    q[0][2] += 0.01f;
    assert_int_equal(csrbf_points_nearest(e.points, &q[0][0], 2, 50.f, d, idx), 0);
    assert_true(idx[0] < n);
    float dx = m->positions[3 * idx[0]] - q[0][0], dy = m->positions[3 * idx[0] + 1] - q[0][1],
          dz = m->positions[3 * idx[0] + 2] - q[0][2];
    assert_true(sqrtf(dx * dx + dy * dy + dz * dz) == d[0]);
    assert_true(d[0] <= 0.0101f);
    assert_true(isinf(d[1]));
    assert_int_equal(idx[1], UINT32_MAX);
    float bad[3] = {NAN, 0, 0};
    assert_int_equal(csrbf_points_nearest(e.points, bad, 1, INFINITY, d, idx), CSRBF_ERR_INVALID);
    printf("indexed fingertip distances equal the brute force on %u tip sets (ICT, %zu vertices); "
           "bounded: %u within reach equal, %u beyond it far\n", checked, n, near_checked, far_checked);
    fp_engine_step_free(&e);
    fp_mesh_free(&m);
}

/* p's nearest vertices of the queries q (nq x 3) equal a brute force over v (n x 3) bit for
 * bit (the smallest index among equals), for bounds from 0 to none; counts into *hits / *far */
static void check_nearest(const csrbf_points *p, const float *v, size_t n, const float (*q)[3], size_t nq,
                          unsigned *hits, unsigned *far)
{
    const float bounds[] = {0.f, 0.05f, 0.3f, 1.f, INFINITY};
    float *d = malloc(nq * sizeof *d);
    uint32_t *idx = malloc(nq * sizeof *idx);
    for (size_t bi = 0; bi < sizeof bounds / sizeof bounds[0]; bi++) {
        assert_int_equal(csrbf_points_nearest(p, &q[0][0], nq, bounds[bi], d, idx), CSRBF_OK);
        for (size_t i = 0; i < nq; i++) {
            float best = INFINITY;
            uint32_t bidx = UINT32_MAX;
            for (size_t j = 0; j < n; j++) {
                float dx = v[3 * j] - q[i][0], dy = v[3 * j + 1] - q[i][1], dz = v[3 * j + 2] - q[i][2];
                float e = dx * dx + dy * dy + dz * dz;
                if (e < best) {
                    best = e;
                    bidx = (uint32_t)j;
                }
            }
            float bd = sqrtf(best);
            if (bd <= bounds[bi]) {
                assert_memory_equal(&d[i], &bd, sizeof bd);
                assert_int_equal(idx[i], bidx);
                (*hits)++;
            } else {
                assert_true(isinf(d[i]));
                assert_int_equal(idx[i], UINT32_MAX);
                (*far)++;
            }
        }
    }
    free(d);
    free(idx);
}

/* csrbf_points_nearest against a brute force (distance bit for bit, the smallest index among
 * equals) on a scrambled vertex order with duplicate vertices (ties), 150 queries in one
 * call, and bounds from 0 to none: through the points' own blocks, through the Morton index
 * (csrbf_points_index_nearest), and with the index after csrbf_points_update_ranges (some
 * ranges moved, the last vertex, whose block has padding, among them), csrbf_points_update
 * (all moved, then a few) and csrbf_points_copy. A vertex count that is not a multiple of 16. */
static void test_nearest_scrambled_ties(void **state)
{
    (void)state;
    enum { N = 40003, Q = 150 };
    float *v = malloc(N * 3 * sizeof *v), *w = malloc(N * 3 * sizeof *w);
    srand(11);
    for (size_t i = 0; i < N; i++) {
        if (i > 100 && i % 9 == 0) { /* a copy of an earlier vertex: a tie */
            memcpy(v + 3 * i, v + 3 * ((size_t)rand() % i), 3 * sizeof *v);
            continue;
        }
        for (int k = 0; k < 3; k++) v[3 * i + k] = (float)rand() / (float)RAND_MAX * 10.f - 5.f;
    }
    csrbf_points *p = NULL, *ix = NULL;
    assert_int_equal(csrbf_points_create(N, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_points_create(N, v, &ix), CSRBF_OK);
    assert_int_equal(csrbf_points_index_nearest(ix), CSRBF_OK);
    assert_int_equal(csrbf_points_index_nearest(ix), CSRBF_OK); /* again: nothing */
    assert_int_equal(csrbf_points_index_nearest(NULL), CSRBF_ERR_INVALID);
    float q[Q][3];
    for (int i = 0; i < Q; i++)
        for (int k = 0; k < 3; k++)
            q[i][k] = i % 4 == 0 ? v[3 * (size_t)(i * 263 % N) + k] /* on a vertex */
                                 : (float)rand() / (float)RAND_MAX * 16.f - 8.f;
    unsigned hits = 0, far = 0;
    check_nearest(p, v, N, q, Q, &hits, &far);
    check_nearest(ix, v, N, q, Q, &hits, &far);
    /* some ranges moved (by up to 3 units: out of their blocks), the last vertex included;
     * half the queries on moved vertices */
    memcpy(w, v, N * 3 * sizeof *w);
    uint32_t ranges[] = {0, 5, 977, 300, 20000, 1, 39990, 13};
    for (size_t r = 0; r < 4; r++)
        for (uint32_t i = ranges[2 * r]; i < ranges[2 * r] + ranges[2 * r + 1]; i++)
            for (int k = 0; k < 3; k++) w[3 * (size_t)i + k] += (float)rand() / (float)RAND_MAX * 6.f - 3.f;
    for (int i = 0; i < Q; i += 2)
        memcpy(q[i], w + 3 * (size_t)(ranges[2 * (i % 4)] + (uint32_t)i % ranges[2 * (i % 4) + 1]), sizeof q[i]);
    assert_int_equal(csrbf_points_update_ranges(ix, w, ranges, 4), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* all moved */
    for (size_t i = 0; i < 3 * (size_t)N; i++) w[i] = w[i] * 0.5f + 1.f;
    assert_int_equal(csrbf_points_update(ix, w), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* a full update that changes a few vertices only (a rig's pose): they move far (half of
     * them along z only), some queries on them */
    for (int i = 0; i < 40; i++) {
        size_t j = (size_t)rand() % N;
        for (int k = i % 2 ? 0 : 2; k < 3; k++) w[3 * j + k] = -w[3 * j + k] + (float)(i % 3) + 1.f;
        if (i < Q / 3) memcpy(q[3 * i + 1], w + 3 * j, sizeof q[0]);
    }
    assert_int_equal(csrbf_points_update(ix, w), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* copied from a set without an index: the index follows */
    assert_int_equal(csrbf_points_copy(ix, p), CSRBF_OK);
    check_nearest(ix, v, N, q, Q, &hits, &far);
    assert_true(hits > 1000 && far > 1000);
    float d[1];
    uint32_t idx[1];
    assert_int_equal(csrbf_points_nearest(p, &q[0][0], 1, -1.f, d, idx), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_points_nearest(ix, &q[0][0], 1, NAN, d, idx), CSRBF_ERR_INVALID);
    csrbf_points_destroy(&p);
    csrbf_points_destroy(&ix);
    free(v);
    free(w);
}

/* csrbf_points_update_ranges_later (the session's commit): the nearest index takes the
 * positions at csrbf_points_sync_nearest, and meanwhile csrbf_points_nearest answers from the
 * own blocks; every answer as the brute force's, before and after the sync, after a second
 * later update (the first is taken first), after an update_ranges, after a whole update that
 * leaves the pending vertices where the later update put them (the index must still learn
 * them), after csrbf_points_index_nearest (it syncs) and after csrbf_points_copy; a later
 * update of no ranges changes nothing. The blocks
 * (evaluation) are current at once: bit for bit as a set made from the new positions. */
static void test_update_ranges_later(void **state)
{
    (void)state;
    enum { N = 30011, Q = 120 };
    float *v = malloc(N * 3 * sizeof *v), *w = malloc(N * 3 * sizeof *w);
    float *o1 = malloc(N * 3 * sizeof *o1), *o2 = malloc(N * 3 * sizeof *o2);
    assert_non_null(v);
    assert_non_null(w);
    assert_non_null(o1);
    assert_non_null(o2);
    srand(29);
    for (size_t i = 0; i < 3 * (size_t)N; i++) v[i] = (float)rand() / (float)RAND_MAX * 10.f - 5.f;
    memcpy(w, v, N * 3 * sizeof *w);
    csrbf_points *ix = NULL, *fresh = NULL;
    assert_int_equal(csrbf_points_create(N, v, &ix), CSRBF_OK);
    assert_int_equal(csrbf_points_index_nearest(ix), CSRBF_OK);
    float q[Q][3];
    unsigned hits = 0, far = 0;
    /* moves the ranges' vertices by up to 3 units; queries: every third on a moved vertex */
    uint32_t rg[] = {0, 40, 1000, 700, 15000, 3, 29990, 21};
    const size_t nr = 4;
#define MOVE_AND_QUERY()                                                                          \
    do {                                                                                          \
        for (size_t r = 0; r < nr; r++)                                                           \
            for (uint32_t i = rg[2 * r]; i < rg[2 * r] + rg[2 * r + 1]; i++)                      \
                for (int k = 0; k < 3; k++) w[3 * (size_t)i + k] += (float)rand() / (float)RAND_MAX * 6.f - 3.f; \
        for (int i = 0; i < Q; i++)                                                               \
            for (int k = 0; k < 3; k++)                                                           \
                q[i][k] = i % 3 == 0 ? w[3 * (size_t)(rg[2 * (i % 4)] + (uint32_t)i % rg[2 * (i % 4) + 1]) + k] \
                                     : (float)rand() / (float)RAND_MAX * 12.f - 6.f;              \
    } while (0)
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, nr), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far); /* pending: the own blocks */
    csrbf_points_sync_nearest(ix);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    csrbf_points_sync_nearest(ix); /* nothing pending: nothing */
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* a later update of no ranges (a commit where no vertex moved): nothing pending */
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, NULL, 0), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    csrbf_points_sync_nearest(ix);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* two later updates in a row on different ranges (the first taken first), then a later
     * and an immediate one */
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, 2), CSRBF_OK);
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg + 4, 2), CSRBF_OK);
    csrbf_points_sync_nearest(ix);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, 2), CSRBF_OK);
    assert_int_equal(csrbf_points_update_ranges(ix, w, rg + 4, 2), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* the blocks are current: evaluation as on a set made afresh */
    assert_int_equal(csrbf_points_create(N, w, &fresh), CSRBF_OK);
    csrbf_options opt = {0};
    opt.radius = 2.0;
    csrbf_solver *s = NULL;
    assert_int_equal(csrbf_solver_create(&opt, &s), CSRBF_OK);
    float st[24], en[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) {
            st[3 * i + k] = w[3 * (size_t)(rg[2 * (i % 4)] + (uint32_t)i % rg[2 * (i % 4) + 1]) + k];
            en[3 * i + k] = st[3 * i + k] + 0.05f * (float)(k + 1);
        }
    assert_true(csrbf_solver_set_start_points(s, 8, st) >= 0);
    assert_true(csrbf_solver_set_end_points(s, en) >= 0);
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, nr), CSRBF_OK);
    assert_int_equal(csrbf_points_update(fresh, w), CSRBF_OK);
    assert_true(csrbf_evaluate(s, fresh, o1, 0, NULL) >= 0);
    assert_true(csrbf_evaluate(s, ix, o2, 0, NULL) >= 0);
    assert_memory_equal(o1, o2, N * 3 * sizeof *o1);
    /* a whole update that leaves the pending vertices where they are and moves others */
    for (size_t i = 5000; i < 5100; i++) w[3 * i] += 2.5f;
    for (int i = 0; i < Q; i += 5) memcpy(q[i], w + 3 * (5000 + (size_t)i % 100), sizeof q[i]);
    assert_int_equal(csrbf_points_update(ix, w), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* csrbf_points_index_nearest takes what is pending */
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, nr), CSRBF_OK);
    assert_int_equal(csrbf_points_index_nearest(ix), CSRBF_OK);
    check_nearest(ix, w, N, q, Q, &hits, &far);
    /* a copy into a set with a pending update: the copy's positions */
    MOVE_AND_QUERY();
    assert_int_equal(csrbf_points_update_ranges_later(ix, w, rg, nr), CSRBF_OK);
    assert_int_equal(csrbf_points_update(fresh, v), CSRBF_OK);
    assert_int_equal(csrbf_points_copy(ix, fresh), CSRBF_OK);
    check_nearest(ix, v, N, q, Q, &hits, &far);
    csrbf_points_sync_nearest(NULL);
    assert_true(hits > 100 && far > 100);
#undef MOVE_AND_QUERY
    csrbf_solver_destroy(&s);
    csrbf_points_destroy(&ix);
    csrbf_points_destroy(&fresh);
    free(v);
    free(w);
    free(o1);
    free(o2);
}

/* Ties at a distance: a scrambled integer grid (20 x 20 x 20) and queries at cell centres
 * and edge midpoints, whose 8 or 2 nearest vertices are exactly equidistant, in different
 * blocks (Morton blocks are aligned cubes of the grid): the smallest index among them, bit
 * for bit as the brute force, through the own blocks and the index. A box exactly at the
 * best distance must still be opened. */
static void test_nearest_grid_ties(void **state)
{
    (void)state;
    enum { S = 20, N = S * S * S, Q = 200 };
    float *v = malloc(N * 3 * sizeof *v);
    uint32_t *perm = malloc(N * sizeof *perm);
    for (uint32_t i = 0; i < N; i++) perm[i] = i;
    srand(5);
    for (uint32_t i = N - 1; i > 0; i--) { /* a random order of the grid's points */
        uint32_t j = (uint32_t)rand() % (i + 1), t = perm[i];
        perm[i] = perm[j];
        perm[j] = t;
    }
    for (size_t i = 0; i < N; i++) {
        uint32_t g = perm[i];
        v[3 * i] = (float)(g % S), v[3 * i + 1] = (float)(g / S % S), v[3 * i + 2] = (float)(g / (S * S));
    }
    float q[Q][3];
    for (int i = 0; i < Q; i++)
        for (int k = 0; k < 3; k++)
            q[i][k] = (float)(rand() % (S - 1)) + (i % 2 == 0 || k == 0 ? 0.5f : 0.f);
    csrbf_points *p = NULL, *ix = NULL;
    assert_int_equal(csrbf_points_create(N, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_points_create(N, v, &ix), CSRBF_OK);
    assert_int_equal(csrbf_points_index_nearest(ix), CSRBF_OK);
    unsigned hits = 0, far = 0;
    check_nearest(p, v, N, q, Q, &hits, &far);
    check_nearest(ix, v, N, q, Q, &hits, &far);
    assert_true(hits == 2 * 2 * Q && far == 2 * 3 * Q); /* every query 0.5 or 0.87 away: far within 0.3 */
    csrbf_points_destroy(&p);
    csrbf_points_destroy(&ix);
    free(v);
    free(perm);
}

/* The engine's persistent output (touched blocks only, partial re-index at commits, the
 * guard's limit and composed steps) equals, bit for bit, a plain full evaluation of the same
 * maps on the same base every frame: anchored frames, a commit, unanchored committed steps
 * (two close points pulled apart: composed), a base set back (undo). */
static void test_touched_equals_full(void **state)
{
    (void)state;
    size_t n;
    float *base = grid(&n), *loaded = malloc(n * 3 * sizeof *loaded);
    memcpy(loaded, base, n * 3 * sizeof *loaded);
    float *out = malloc(n * 3 * sizeof *out), *ref = malloc(n * 3 * sizeof *ref);
    float *rbase = malloc(n * 3 * sizeof *rbase);
    memcpy(rbase, base, n * 3 * sizeof *rbase);
    fp_engine_step e;
    assert_int_equal(fp_engine_step_init(&e, n, base, 1), 0);
    csrbf_options o = {0};
    o.radius = 0.3;
    o.threads = 1;
    csrbf_solver *rs;
    csrbf_points *rp;
    assert_int_equal(csrbf_solver_create(&o, &rs), 0);
    assert_int_equal(csrbf_points_create(n, rbase, &rp), 0);
    float start[2][3], end[2][3];
    fp_control_set cs = {0};
    cs.size = sizeof cs;
    cs.active = true;
    cs.radius = 0.3;
    cs.capacity = 2;
    cs.count = 2;
    cs.start = start;
    cs.end = end;
    unsigned composed = 0, limited = 0;
    for (int f = 0; f < 40; f++) {
        bool unanchored = f >= 12;
        float cx = 0.4f + 0.05f * (float)(f % 7), cy = 0.3f + 0.04f * (float)(f % 11);
        if (!unanchored) {
            float t = 0.02f * (float)f;
            float st[2][3] = {{0.5f, 0.5f, 0.1f}, {0.53f, 0.5f, 0.1f}};
            memcpy(start, st, sizeof st);
            memcpy(end, st, sizeof st);
            end[0][0] -= t;
            end[1][0] += t; /* pulled apart: folds without the guard */
            cs.intents = f == 11 ? FP_INTENT_COMMIT : 0;
        } else {
            float big = f % 5 == 0 ? 0.12f : 0.02f;
            float st[2][3] = {{cx, cy, 0.05f}, {cx + 0.02f, cy, 0.05f}};
            memcpy(start, st, sizeof st);
            memcpy(end, st, sizeof st);
            end[0][0] -= big;
            end[1][0] += big;
            end[1][2] += 0.01f;
            cs.intents = FP_INTENT_COMMIT;
        }
        fp_engine_result r;
        assert_int_equal(fp_engine_step_run(&e, &cs, out, &r, NULL), 0);
        composed += r.substeps > 1;
        limited += r.clusters_limited > 0;
        /* the reference: solve afresh, limit or compose, evaluate every vertex */
        assert_true(csrbf_solver_solve(rs, 2, &start[0][0], &end[0][0]) >= 0);
        csrbf_guard_stats gs;
        assert_true(csrbf_solver_limit_end_points(rs, FP_ENGINE_GUARD_MARGIN, &gs) >= 0);
        if (gs.clusters_limited) { /* composed, anchored (from the base) and unanchored alike */
            csrbf_guard g = {FP_ENGINE_GUARD_MARGIN, FP_ENGINE_MAX_SUBSTEPS, 0, FP_ENGINE_MAX_PAIRS};
            assert_true(csrbf_guarded_step(rs, rp, 2, &start[0][0], &end[0][0], &g, ref, NULL) >= 0);
        } else {
            assert_int_equal(csrbf_evaluate(rs, rp, ref, 0, NULL), 0);
        }
        assert_memory_equal(out, ref, n * 3 * sizeof *out);
        if (cs.intents & FP_INTENT_COMMIT) {
            memcpy(base, out, n * 3 * sizeof *base);
            fp_engine_step_commit(&e, base);
            memcpy(rbase, ref, n * 3 * sizeof *rbase);
            assert_int_equal(csrbf_points_update(rp, rbase), 0);
        }
        if (f == 25) { /* undo to the loaded shape */
            memcpy(base, loaded, n * 3 * sizeof *base);
            fp_engine_step_set_base(&e, base);
            memcpy(rbase, loaded, n * 3 * sizeof *rbase);
            assert_int_equal(csrbf_points_update(rp, rbase), 0);
        }
    }
    printf("touched = full on 40 frames (%u limited, %u composed)\n", limited, composed);
    assert_true(composed > 0);
    assert_true(limited >= composed); /* every map a cluster would limit is composed */
    csrbf_points_destroy(&rp);
    csrbf_solver_destroy(&rs);
    fp_engine_step_free(&e);
    free(base);
    free(loaded);
    free(out);
    free(ref);
    free(rbase);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_factor_reuse_and_interpolation),
        cmocka_unit_test(test_engine_error_once),
        cmocka_unit_test(test_tip_distances),
        cmocka_unit_test(test_tip_distances_indexed_ict),
        cmocka_unit_test(test_nearest_scrambled_ties),
        cmocka_unit_test(test_nearest_grid_ties),
        cmocka_unit_test(test_update_ranges_later),
        cmocka_unit_test(test_touched_equals_full),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
