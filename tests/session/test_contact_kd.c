/* The contact guard's k-d tree (core/contact/contact_kd.h) against brute force: the nearest
 * blocking vertex (a local scale-back's ramp) and the weighted motion sums (a carried round's
 * carry, whose nodes wholly inside the sphere add polynomial moments instead of their
 * vertices). Point sets: a uniform cloud, a thin curved sheet as skin is (most nodes cut by
 * the sphere along a curve), duplicates, and the same sheet moved 1,000 units away (the
 * moments are taken about the root's centre, so they must not lose their digits there). */
#include "contact_kd.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

static uint64_t rng = 88172645463325252ull;
static double rnd(void) /* xorshift64, [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

typedef struct cloud {
    size_t n;
    float *pos, *cand;
    uint32_t *verts; /* every other vertex: the tree holds a subset, as off is of the mesh */
    size_t nv;
} cloud;

/* kind 0: uniform in [0, 2]^3; 1: a sheet z = 0.3 sin(x) cos(y) over [0, 4]^2 (skin-like);
 * 2: the sheet with each point twice (duplicates); offset added to every coordinate */
static cloud make(int kind, size_t n, double offset)
{
    cloud c = {.n = kind == 2 ? 2 * n : n};
    c.pos = malloc(3 * c.n * sizeof *c.pos);
    c.cand = malloc(3 * c.n * sizeof *c.cand);
    c.verts = malloc(c.n * sizeof *c.verts);
    assert_non_null(c.pos);
    assert_non_null(c.cand);
    assert_non_null(c.verts);
    for (size_t i = 0; i < n; i++) {
        double x, y, z;
        if (kind == 0) x = 2 * rnd(), y = 2 * rnd(), z = 2 * rnd();
        else x = 4 * rnd(), y = 4 * rnd(), z = 0.3 * sin(x) * cos(y);
        for (size_t copy = 0; copy < (kind == 2 ? 2u : 1u); copy++) {
            size_t v = kind == 2 ? 2 * i + copy : i;
            c.pos[3 * v] = (float)(x + offset), c.pos[3 * v + 1] = (float)(y + offset),
            c.pos[3 * v + 2] = (float)(z + offset);
            for (int a = 0; a < 3; a++) /* a motion that varies over the set */
                c.cand[3 * v + a] = (float)(c.pos[3 * v + a] + 0.2 * sin(3.0 * x + a) + 0.1 * (a - 1) * y);
        }
    }
    for (size_t v = 0; v < c.n; v += 2) c.verts[c.nv++] = (uint32_t)v;
    return c;
}

static void unmake(cloud *c)
{
    free(c->pos);
    free(c->cand);
    free(c->verts);
}

/* the brute force's sums at p (as fpc_kd_sums defines them), and the sum of the terms'
 * magnitudes (the scale of their rounding) */
static void brute_sums(const cloud *c, const double p[3], double R2, double acc[4], double mag[4])
{
    memset(acc, 0, 4 * sizeof *acc);
    memset(mag, 0, 4 * sizeof *mag);
    for (size_t i = 0; i < c->nv; i++) {
        const float *q = c->pos + 3 * (size_t)c->verts[i], *m = c->cand + 3 * (size_t)c->verts[i];
        double e2 = 0;
        for (int a = 0; a < 3; a++) e2 += (p[a] - q[a]) * (p[a] - q[a]);
        if (e2 >= R2) continue;
        double w = (1 - e2 / R2) * (1 - e2 / R2);
        acc[0] += w;
        mag[0] += w;
        for (int a = 0; a < 3; a++) {
            double d = (double)m[a] - q[a];
            acc[1 + a] += w * d;
            mag[1 + a] += fabs(w * d) + w; /* (+w: the moments' rounding follows the weights) */
        }
    }
}

static double brute_nearest2(const cloud *c, const double p[3])
{
    double best = INFINITY;
    for (size_t i = 0; i < c->nv; i++) {
        const float *q = c->pos + 3 * (size_t)c->verts[i];
        double e2 = 0;
        for (int a = 0; a < 3; a++) e2 += (p[a] - q[a]) * (p[a] - q[a]);
        best = fmin(best, e2);
    }
    return best;
}

/* queries near the set (some on its points, some off it), over radii from a few points'
 * spacing to the whole set; the sums and nearest distances against brute force */
static void check_cloud(int kind, double offset)
{
    cloud c = make(kind, 3000, offset);
    fpc_kd kd = {0};
    assert_int_equal(fpc_kd_build(&kd, c.verts, c.nv, c.pos), 0);
    assert_int_equal(fpc_kd_moments(&kd, c.cand), 0);
    const double radii[] = {0.05, 0.3, 1.0, 10.0};
    uint32_t hint = 0;
    size_t inside_used = 0, queries = 0;
    for (int qi = 0; qi < 400; qi++) {
        double p[3];
        const float *on = c.pos + 3 * (size_t)(rnd() * (double)c.n);
        for (int a = 0; a < 3; a++) p[a] = on[a] + (qi % 2 ? 0.1 * (rnd() - 0.5) : 0.0);
        double want = brute_nearest2(&c, p);
        double got = fpc_kd_nearest2(&kd, p, INFINITY, -1, &hint);
        assert_true(got == want); /* the same squared distance, from the same floats */
        assert_true(hint < c.nv);
        /* bounded: the bound when the nearest lies beyond it */
        double b2 = want * 0.5;
        if (want > 0) assert_true(fpc_kd_nearest2(&kd, p, b2, -1, &hint) == b2);
        /* enough: any distance at most enough2 will do */
        double e2 = 4 * want + 1e-6;
        assert_true(fpc_kd_nearest2(&kd, p, INFINITY, e2, &hint) <= e2);
        for (size_t ri = 0; ri < sizeof radii / sizeof radii[0]; ri++) {
            double R2 = radii[ri] * radii[ri], acc[4], ref[4], mag[4];
            fpc_kd_sums(&kd, c.cand, p, R2, acc);
            brute_sums(&c, p, R2, ref, mag);
            for (int a = 0; a < 4; a++) {
                if (fabs(acc[a] - ref[a]) > 1e-9 * (mag[a] + 1e-30))
                    fail_msg("kind %d offset %g query %d R %g sum %d: tree %.17g brute %.17g (scale %.3g)",
                             kind, offset, qi, radii[ri], a, acc[a], ref[a], mag[a]);
            }
            inside_used += ref[0] > 0;
            queries++;
        }
    }
    assert_true(inside_used > queries / 2); /* (most queries had vertices within R) */
    fpc_kd_free(&kd);
    unmake(&c);
}

static void test_uniform(void **state) { (void)state; check_cloud(0, 0.0); }
static void test_sheet(void **state) { (void)state; check_cloud(1, 0.0); }
static void test_duplicates(void **state) { (void)state; check_cloud(2, 0.0); }
static void test_far_from_origin(void **state) { (void)state; check_cloud(1, 1000.0); }

/* an empty tree finds nothing and sums to 0; a one-vertex tree is its vertex */
static void test_empty_and_one(void **state)
{
    (void)state;
    fpc_kd kd = {0};
    float pos[3] = {1, 2, 3}, cand[3] = {1.5f, 2, 3};
    uint32_t v = 0, hint = 0;
    double p[3] = {1, 2, 3.5}, acc[4];
    assert_int_equal(fpc_kd_build(&kd, &v, 0, pos), 0);
    assert_int_equal(fpc_kd_moments(&kd, cand), 0);
    assert_true(fpc_kd_nearest2(&kd, p, 7.0, -1, &hint) == 7.0);
    fpc_kd_sums(&kd, cand, p, 100.0, acc);
    for (int a = 0; a < 4; a++) assert_true(acc[a] == 0);
    assert_int_equal(fpc_kd_build(&kd, &v, 1, pos), 0);
    assert_int_equal(fpc_kd_moments(&kd, cand), 0);
    assert_true(fpc_kd_nearest2(&kd, p, INFINITY, -1, &hint) == 0.25);
    fpc_kd_sums(&kd, cand, p, 1.0, acc); /* w = (1 - 0.25)^2 = 0.5625; motion (0.5, 0, 0) */
    assert_true(fabs(acc[0] - 0.5625) < 1e-12);
    assert_true(fabs(acc[1] - 0.28125) < 1e-12);
    assert_true(acc[2] == 0 && acc[3] == 0);
    fpc_kd_sums(&kd, cand, p, 0.25, acc); /* exactly on the sphere: outside (w = 0) */
    assert_true(acc[0] == 0);
    fpc_kd_free(&kd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_and_one), cmocka_unit_test(test_uniform),
        cmocka_unit_test(test_sheet), cmocka_unit_test(test_duplicates),
        cmocka_unit_test(test_far_from_origin),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
