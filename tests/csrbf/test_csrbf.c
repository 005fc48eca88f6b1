/* Tests of the csrbf engine against formulas, finite differences and an independent dense
 * double-precision solve (Gaussian elimination of the full saddle system). */
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

/* cmocka 1.1 compares floats only; doubles with a tolerance, failing on NaN. */
#define assert_double_equal(a, b, eps)                                                        \
    do {                                                                                       \
        double a_ = (a), b_ = (b), e_ = (eps);                                                 \
        if (!(fabs(a_ - b_) <= e_))                                                            \
            fail_msg("%s = %.17g and %s = %.17g differ by more than %g", #a, a_, #b, b_, e_);  \
    } while (0)

/* ------------------------------------------------------------------------- helpers */

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double urand(void) /* [0, 1) */
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * 0x1p-53;
}

/* n random points in [0, L]^3 at least dmin apart (rejection), as floats. */
static float *random_points(size_t n, double L, double dmin)
{
    float *p = malloc(n * 3 * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        for (int tries = 0;; tries++) {
            for (int a = 0; a < 3; a++) p[3 * i + a] = (float)(urand() * L);
            int ok = 1;
            for (size_t j = 0; j < i && ok; j++) {
                double d2 = 0;
                for (int a = 0; a < 3; a++) d2 += pow(p[3 * i + a] - p[3 * j + a], 2);
                ok = d2 >= dmin * dmin;
            }
            if (ok || tries > 100) break;
        }
    }
    return p;
}

static float *displaced(const float *s, size_t n, double amp)
{
    float *d = malloc(n * 3 * sizeof *d);
    for (size_t i = 0; i < 3 * n; i++) d[i] = s[i] + (float)((urand() * 2 - 1) * amp);
    return d;
}

static csrbf_solver *make_solver(double R, csrbf_kernel k, csrbf_poly poly, int dense_limit)
{
    csrbf_options o = {0};
    o.radius = R;
    o.kernel = k;
    o.poly = poly;
    o.dense_limit = dense_limit;
    csrbf_solver *s = NULL;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
    assert_non_null(s);
    return s;
}

/* Reference formulas straight from csrbf.md (psi32 normalised by 1/3 as documented). */
static double ref_psi(csrbf_kernel k, double r)
{
    if (r >= 1) return 0;
    switch (k) {
    case CSRBF_PSI30: return pow(1 - r, 2);
    case CSRBF_PSI31: return 1 - 10 * r * r + 20 * r * r * r - 15 * pow(r, 4) + 4 * pow(r, 5);
    default: return pow(1 - r, 6) * (35 * r * r + 18 * r + 3) / 3;
    }
}
static double ref_dpsi(csrbf_kernel k, double r)
{
    if (r >= 1) return 0;
    switch (k) {
    case CSRBF_PSI30: return -2 * (1 - r);
    case CSRBF_PSI31: return -20 * r * pow(1 - r, 3);
    default: return -56 * r * pow(1 - r, 5) * (5 * r + 1) / 3;
    }
}

/* Independent solve: the full (n+4) x (n+4) saddle system [A P; P^T 0] with P = [1 x y z]
 * (raw coordinates), or just A without polynomial, by Gaussian elimination with partial
 * pivoting. coef: n x 3 alpha then 4 x 3 polynomial b0, Bx, By, Bz. */
static void reference_solve(csrbf_kernel k, double R, int poly, size_t n, const float *s,
                            const float *d, double *coef)
{
    size_t N = n + (poly ? 4 : 0);
    double *M = calloc(N * N, sizeof *M), *rhs = calloc(N * 3, sizeof *rhs);
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < n; j++) {
            double r2 = 0;
            for (int a = 0; a < 3; a++) r2 += pow((double)s[3 * i + a] - s[3 * j + a], 2);
            M[i * N + j] = ref_psi(k, sqrt(r2) / R);
        }
        if (poly) {
            double q[4] = {1, s[3 * i], s[3 * i + 1], s[3 * i + 2]};
            for (int l = 0; l < 4; l++) M[i * N + n + l] = M[(n + l) * N + i] = q[l];
        }
        for (int a = 0; a < 3; a++) rhs[i * 3 + a] = (double)d[3 * i + a] - s[3 * i + a];
    }
    for (size_t c = 0; c < N; c++) {
        size_t p = c;
        for (size_t r = c + 1; r < N; r++)
            if (fabs(M[r * N + c]) > fabs(M[p * N + c])) p = r;
        if (p != c) {
            for (size_t j = 0; j < N; j++) {
                double t = M[c * N + j];
                M[c * N + j] = M[p * N + j];
                M[p * N + j] = t;
            }
            for (int a = 0; a < 3; a++) {
                double t = rhs[c * 3 + a];
                rhs[c * 3 + a] = rhs[p * 3 + a];
                rhs[p * 3 + a] = t;
            }
        }
        assert_true(fabs(M[c * N + c]) > 1e-300);
        for (size_t r = c + 1; r < N; r++) {
            double f = M[r * N + c] / M[c * N + c];
            if (f == 0) continue;
            for (size_t j = c; j < N; j++) M[r * N + j] -= f * M[c * N + j];
            for (int a = 0; a < 3; a++) rhs[r * 3 + a] -= f * rhs[c * 3 + a];
        }
    }
    for (size_t c = N; c-- > 0;) {
        for (int a = 0; a < 3; a++) {
            double v = rhs[c * 3 + a];
            for (size_t j = c + 1; j < N; j++) v -= M[c * N + j] * rhs[j * 3 + a];
            rhs[c * 3 + a] = v / M[c * N + c];
        }
    }
    memset(coef, 0, (n + 4) * 3 * sizeof *coef);
    memcpy(coef, rhs, N * 3 * sizeof *coef);
    free(M);
    free(rhs);
}

static void reference_map(csrbf_kernel k, double R, size_t n, const float *s, const double *coef,
                          const double x[3], double out[3])
{
    for (int a = 0; a < 3; a++) out[a] = x[a];
    for (size_t i = 0; i < n; i++) {
        double r2 = 0;
        for (int a = 0; a < 3; a++) r2 += pow(x[a] - s[3 * i + a], 2);
        double p = ref_psi(k, sqrt(r2) / R);
        for (int a = 0; a < 3; a++) out[a] += coef[3 * i + a] * p;
    }
    const double *b = coef + 3 * n;
    for (int a = 0; a < 3; a++) out[a] += b[a] + b[3 + a] * x[0] + b[6 + a] * x[1] + b[9 + a] * x[2];
}

/* Max |T(s_i) - d_i| / max(1, |d_i|) through csrbf_evaluate (float) on the start points. */
static double interpolation_error(csrbf_solver *s, size_t n, const float *st, const float *en)
{
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(n, st, &p), CSRBF_OK);
    float *out = malloc(n * 3 * sizeof *out);
    assert_int_equal(csrbf_evaluate(s, p, out, 0, NULL), CSRBF_OK);
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        double e = 0, m = 0;
        for (int a = 0; a < 3; a++) {
            e += pow((double)out[3 * i + a] - en[3 * i + a], 2);
            m += pow(en[3 * i + a], 2);
        }
        worst = fmax(worst, sqrt(e) / fmax(1, sqrt(m)));
    }
    free(out);
    csrbf_points_destroy(&p);
    return worst;
}

/* ---------------------------------------------------------------------------- kernels */

static void test_kernel_values(void **state)
{
    (void)state;
    for (int k = 0; k < 3; k++)
        for (int i = 0; i <= 120; i++) {
            double r = i / 100.0, p, d;
            assert_int_equal(csrbf_kernel_eval((csrbf_kernel)k, r, &p, &d), CSRBF_OK);
            assert_double_equal(p, ref_psi((csrbf_kernel)k, r), 1e-13);
            assert_double_equal(d, ref_dpsi((csrbf_kernel)k, r), 1e-12);
            if (r > 0.01 && r < 0.99) { /* derivative vs central differences */
                double h = 1e-6, pp, pm;
                csrbf_kernel_eval((csrbf_kernel)k, r + h, &pp, NULL);
                csrbf_kernel_eval((csrbf_kernel)k, r - h, &pm, NULL);
                assert_double_equal(d, (pp - pm) / (2 * h), 1e-7);
            }
        }
    double p;
    assert_int_equal(csrbf_kernel_eval(CSRBF_PSI31, 0.0, &p, NULL), CSRBF_OK);
    assert_double_equal(p, 1.0, 0);
    assert_int_equal(csrbf_kernel_eval(CSRBF_PSI32, 0.0, &p, NULL), CSRBF_OK);
    assert_double_equal(p, 1.0, 1e-15);
    assert_int_equal(csrbf_kernel_eval(CSRBF_PSI31, -0.1, &p, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_kernel_eval(CSRBF_PSI31, NAN, &p, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_kernel_eval((csrbf_kernel)7, 0.5, &p, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_kernel_eval(CSRBF_PSI31, 0.5, NULL, NULL), CSRBF_ERR_INVALID);
    /* fold-over bounds from csrbf.md: 0.47, 0.5, 0.40 */
    assert_double_equal(csrbf_kernel_foldover_bound(CSRBF_PSI31), 0.474, 1e-3);
    assert_double_equal(csrbf_kernel_foldover_bound(CSRBF_PSI30), 0.5, 1e-12);
    assert_double_equal(csrbf_kernel_foldover_bound(CSRBF_PSI32), 0.40, 0.01);
    /* each bound is 1 / max |psi'| on [0, 1]: against a fine scan of csrbf_kernel_eval */
    for (int k = CSRBF_PSI31; k <= CSRBF_PSI32; k++) {
        double mx = 0.0;
        for (int i = 0; i <= 200000; i++) {
            double p, d;
            assert_int_equal(csrbf_kernel_eval((csrbf_kernel)k, i / 200000.0, &p, &d), CSRBF_OK);
            mx = fmax(mx, fabs(d));
        }
        assert_double_equal(csrbf_kernel_foldover_bound((csrbf_kernel)k), 1.0 / mx, 1e-8);
    }
}

/* -------------------------------------------------------------------------- interpolation */

static void check_interpolation(csrbf_kernel k, csrbf_poly poly)
{
    size_t n = 60;
    float *st = random_points(n, 10.0, 1.0), *en = displaced(st, n, 0.5);
    csrbf_solver *s = make_solver(4.0, k, poly, 0);
    assert_true(csrbf_solver_solve(s, n, st, en) >= 0);
    double e = interpolation_error(s, n, st, en);
    assert_true(e < 1e-5);
    /* exact map_point in double interpolates to near machine precision */
    for (size_t i = 0; i < n; i++) {
        double x[3] = {st[3 * i], st[3 * i + 1], st[3 * i + 2]}, y[3];
        assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_OK);
        for (int a = 0; a < 3; a++) assert_double_equal(y[a], en[3 * i + a], 1e-9);
    }
    csrbf_solver_destroy(&s);
    assert_null(s);
    free(st);
    free(en);
}

static void test_interpolation(void **state)
{
    (void)state;
    for (int k = 0; k < 3; k++) {
        check_interpolation((csrbf_kernel)k, CSRBF_POLY_NONE);
        check_interpolation((csrbf_kernel)k, CSRBF_POLY_LINEAR);
    }
}

/* A touch's ranges rg (nr of them): increasing, apart (runs of adjacent blocks joined), non-empty
 * and within nv vertices; with last (the output before the call), out equals it outside them
 * (nothing changed there). Returns the vertices they cover. */
static size_t check_ranges(const float *out, const float *last, size_t nv, const uint32_t *rg,
                           size_t nr)
{
    size_t prev_end = 0, covered = 0;
    for (size_t r = 0; r < nr; r++) {
        assert_true(rg[2 * r] >= prev_end);
        if (r > 0) assert_true(rg[2 * r] > prev_end);
        assert_true(rg[2 * r + 1] > 0);
        if (last)
            assert_memory_equal(out + 3 * prev_end, last + 3 * prev_end,
                                (rg[2 * r] - prev_end) * 3 * sizeof(float));
        prev_end = rg[2 * r] + rg[2 * r + 1];
        covered += rg[2 * r + 1];
        assert_true(prev_end <= nv);
    }
    if (last)
        assert_memory_equal(out + 3 * prev_end, last + 3 * prev_end, (nv - prev_end) * 3 * sizeof(float));
    return covered;
}

/* A commit of scattered ranges (csrbf_points_update_ranges) refits the block tree above every
 * one of them, whatever order the ranges come in: blocks carried far off the grid are found
 * there by an evaluation whose support holds only them, as on a fresh index of the same
 * positions (a node left unrefit would skip them and leave them in place). */
static void test_update_ranges_tree(void **state)
{
    (void)state;
    size_t nx = 203, ny = 150, nv = nx * ny; /* 1,904 blocks: three levels of the tree */
    float *v = malloc(nv * 3 * sizeof *v), *a = malloc(nv * 3 * sizeof *a), *b = malloc(nv * 3 * sizeof *b);
    assert_non_null(v);
    assert_non_null(a);
    assert_non_null(b);
    /* ascending, then the same ranges in another order (the range-by-range path) */
    const uint32_t up[] = {100, 40, 5000, 3, 5020, 17, 5100, 0, 20000, 300, (uint32_t)nv - 50, 50};
    const uint32_t mixed[] = {20000, 300, 100, 40, (uint32_t)nv - 50, 50, 5020, 17, 5000, 3};
    const uint32_t *sets[2] = {up, mixed};
    const size_t counts[2] = {6, 5};
    for (int k = 0; k < 2; k++) {
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++) {
                float *q = v + 3 * (j * nx + i);
                q[0] = (float)i * 0.5f;
                q[1] = (float)j * 0.5f;
                q[2] = 0.0f;
            }
        csrbf_points *p = NULL, *fresh = NULL;
        assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
        for (size_t r = 0; r < counts[k]; r++) /* carried 500 units off the grid, in a column */
            for (uint32_t x = sets[k][2 * r]; x < sets[k][2 * r] + sets[k][2 * r + 1]; x++) {
                v[3 * x] = 500.0f;
                v[3 * x + 1] = 500.0f;
                v[3 * x + 2] = (float)x * 1e-3f;
            }
        assert_int_equal(csrbf_points_update_ranges(p, v, sets[k], counts[k]), CSRBF_OK);
        assert_int_equal(csrbf_points_create(nv, v, &fresh), CSRBF_OK);
        /* one centre in the column's middle, its support the whole column and nothing else */
        csrbf_solver *s = make_solver(40.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
        const float st[3] = {500.0f, 500.0f, 15.0f}, en[3] = {501.0f, 500.0f, 15.0f};
        assert_true(csrbf_solver_solve(s, 1, st, en) >= 0);
        assert_int_equal(csrbf_evaluate(s, p, a, 0, NULL), CSRBF_OK);
        assert_int_equal(csrbf_evaluate(s, fresh, b, 0, NULL), CSRBF_OK);
        assert_memory_equal(a, b, nv * 3 * sizeof *a);
        for (size_t r = 0; r < counts[k]; r++) /* each carried vertex moved with the centre */
            for (uint32_t x = sets[k][2 * r]; x < sets[k][2 * r] + sets[k][2 * r + 1]; x++)
                assert_true(a[3 * x] > v[3 * x] + 0.1f);
        assert_memory_equal(a + 3 * 1000, v + 3 * 1000, 3 * sizeof *a); /* the grid stays */
        csrbf_solver_destroy(&s);
        csrbf_points_destroy(&fresh);
        csrbf_points_destroy(&p);
    }
    free(v);
    free(a);
    free(b);
}

/* The persistent-output evaluation: on a grid, fingertips that move (and jump away) give
 * bit-identical output to csrbf_evaluate every frame; vertices outside the reported ranges are
 * unchanged from the last frame; a commit through csrbf_points_update_ranges and
 * csrbf_touch_commit leaves an index equal to a fresh one. */
static void test_touched(void **state)
{
    (void)state;
    size_t nx = 203, ny = 150, nv = nx * ny; /* not a multiple of 16 */
    float *v = malloc(nv * 3 * sizeof *v), *out = malloc(nv * 3 * sizeof *out),
          *ref = malloc(nv * 3 * sizeof *ref), *last = malloc(nv * 3 * sizeof *last);
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            float *q = v + 3 * (j * nx + i);
            q[0] = (float)i * 0.5f;
            q[1] = (float)j * 0.5f;
            q[2] = 0.1f * sinf((float)i * 0.1f);
        }
    csrbf_points *p = NULL;
    csrbf_touch *tc = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_touch_create(p, &tc), CSRBF_OK);
    assert_int_equal(csrbf_touch_ranges(tc, NULL), 0);
    csrbf_solver *s = make_solver(4.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    float st[3 * 5], en[3 * 5];
    for (int frame = 0; frame < 12; frame++) {
        for (int i = 0; i < 5; i++) {
            double cx = frame == 6 ? 90.0 : 10.0 + 12.0 * i + 0.7 * frame; /* frame 6 jumps */
            st[3 * i] = (float)cx;
            st[3 * i + 1] = (float)(20.0 + 3.0 * i);
            st[3 * i + 2] = 0.0f;
            en[3 * i] = st[3 * i] + 0.5f;
            en[3 * i + 1] = st[3 * i + 1] - 0.3f;
            en[3 * i + 2] = 0.4f;
        }
        if (frame == 6)
            for (int i = 0; i < 5; i++) st[3 * i + 1] = en[3 * i + 1] = (float)(5 + 12 * i);
        assert_true(csrbf_solver_solve(s, 5, st, en) >= 0);
        csrbf_eval_stats a, b;
        assert_int_equal(csrbf_evaluate(s, p, ref, 0, &a), CSRBF_OK);
        if (frame > 0) memcpy(last, out, nv * 3 * sizeof *out);
        assert_int_equal(csrbf_evaluate_touched(s, p, tc, out, 0, &b), CSRBF_OK);
        assert_memory_equal(out, ref, nv * 3 * sizeof *out);
        assert_int_equal(a.pairs, b.pairs);
        const uint32_t *rg;
        size_t nr = csrbf_touch_ranges(tc, &rg);
        assert_true(nr > 0);
        /* outside the ranges nothing changed since the last frame */
        size_t covered = check_ranges(out, frame > 0 ? last : NULL, nv, rg, nr);
        if (frame == 0) assert_int_equal(covered, nv); /* the first call writes everything */
        else assert_true(covered < nv / 2);
        if (frame == 9) { /* commit: the output becomes the base, only touched blocks re-indexed */
            assert_int_equal(csrbf_points_update_ranges(p, out, rg, nr), CSRBF_OK);
            memcpy(v, out, nv * 3 * sizeof *v);
            csrbf_touch_commit(tc);
            assert_int_equal(csrbf_touch_ranges(tc, NULL), 0);
            csrbf_points *fresh = NULL;
            assert_int_equal(csrbf_points_create(nv, v, &fresh), CSRBF_OK);
            assert_int_equal(csrbf_evaluate(s, fresh, ref, 0, NULL), CSRBF_OK);
            assert_int_equal(csrbf_evaluate(s, p, last, 0, NULL), CSRBF_OK);
            assert_memory_equal(ref, last, nv * 3 * sizeof *out);
            csrbf_points_destroy(&fresh);
        }
    }
    /* reset: the next call writes everything */
    csrbf_touch_reset(tc);
    assert_int_equal(csrbf_evaluate_touched(s, p, tc, out, 0, NULL), CSRBF_OK);
    size_t nr = csrbf_touch_ranges(tc, NULL);
    assert_int_equal(nr, 1);
    /* a reset (or a fresh touch) then a commit over an output equal to the base: the next
     * call writes only the blocks in a support, and the output is still csrbf_evaluate's */
    memcpy(out, v, nv * 3 * sizeof *out);
    csrbf_touch_reset(tc);
    csrbf_touch_commit(tc);
    assert_int_equal(csrbf_evaluate_touched(s, p, tc, out, 0, NULL), CSRBF_OK);
    assert_int_equal(csrbf_evaluate(s, p, ref, 0, NULL), CSRBF_OK);
    assert_memory_equal(out, ref, nv * 3 * sizeof *out);
    const uint32_t *rg2;
    size_t nr2 = csrbf_touch_ranges(tc, &rg2), covered2 = 0;
    for (size_t r = 0; r < nr2; r++) covered2 += rg2[2 * r + 1];
    assert_true(covered2 > 0 && covered2 < nv / 2);
    /* a touch of other points is refused */
    csrbf_points *q = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &q), CSRBF_OK);
    assert_int_equal(csrbf_evaluate_touched(s, q, tc, out, 0, NULL), CSRBF_ERR_INVALID);
    const uint32_t bad[2] = {(uint32_t)nv - 1, 5};
    assert_int_equal(csrbf_points_update_ranges(p, v, bad, 1), CSRBF_ERR_INVALID);
    csrbf_points_destroy(&q);
    csrbf_touch_destroy(&tc);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    free(v);
    free(out);
    free(ref);
    free(last);
}

/* ------------------------------------------------- many centres, frames, block selection */

/* A wavy grid of nx x ny vertices (row by row, as scanned meshes come), spacing h. */
static float *wavy_grid(size_t nx, size_t ny, double h)
{
    float *v = malloc(nx * ny * 3 * sizeof *v);
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            float *q = v + 3 * (j * nx + i);
            q[0] = (float)(h * (double)i);
            q[1] = (float)(h * (double)j);
            q[2] = (float)(0.3 * sin(0.37 * (double)i) * cos(0.23 * (double)j));
        }
    return v;
}

/* n centres scattered over the grid's [0, w] x [0, h] just above its surface, displaced by amp. */
static void scatter_centres(size_t n, double w, double h, double amp, float *st, float *en)
{
    for (size_t i = 0; i < n; i++) {
        st[3 * i] = (float)(urand() * w);
        st[3 * i + 1] = (float)(urand() * h);
        st[3 * i + 2] = (float)(urand() * 0.4 - 0.2);
        for (int a = 0; a < 3; a++) en[3 * i + a] = st[3 * i + a] + (float)((urand() * 2 - 1) * amp);
    }
}

/* More than 32 centres (42: two hands of 21 joints; 64: the fast path's capacity; 65 and 100:
 * the general path) against the independent dense solve and map in double; the fast path
 * with and without statistics and the general path (Jacobian flag) agree bit for bit, the
 * statistics with a brute-force count, and every vertex outside all supports keeps its base
 * position exactly. */
static void test_many_centres(void **state)
{
    (void)state;
    size_t nx = 181, ny = 97, nv = nx * ny;
    double h = 0.25, R = 3.0;
    float *v = wavy_grid(nx, ny, h);
    float *o1 = malloc(nv * 3 * sizeof *o1), *o2 = malloc(nv * 3 * sizeof *o2),
          *o3 = malloc(nv * 3 * sizeof *o3);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    static const size_t counts[4] = {42, 64, 65, 100};
    for (int c = 0; c < 4; c++) {
        size_t n = counts[c];
        float *st = malloc(n * 3 * sizeof *st), *en = malloc(n * 3 * sizeof *en);
        scatter_centres(n, h * (double)(nx - 1), h * (double)(ny - 1), 0.15, st, en);
        csrbf_solver *s = make_solver(R, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
        int rc = csrbf_solver_solve(s, n, st, en);
        assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
        assert_int_equal(csrbf_solver_centres(s), n);
        csrbf_eval_stats a, b;
        assert_int_equal(csrbf_evaluate(s, p, o1, 0, NULL), CSRBF_OK);
        assert_int_equal(csrbf_evaluate(s, p, o2, 0, &a), CSRBF_OK);
        assert_int_equal(csrbf_evaluate(s, p, o3, CSRBF_EVAL_JACOBIAN, &b), CSRBF_OK);
        assert_memory_equal(o1, o2, nv * 3 * sizeof *o1);
        assert_memory_equal(o1, o3, nv * 3 * sizeof *o1);
        assert_int_equal(a.pairs, b.pairs);
        assert_int_equal(a.moved, b.moved);
        double *coef = malloc((n + 4) * 3 * sizeof *coef);
        reference_solve(CSRBF_PSI31, R, 0, n, st, en, coef);
        size_t pairs = 0, outside = 0;
        double worst = 0, dmax = 0;
        for (size_t i = 0; i < nv; i++) {
            double x[3] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]}, y[3];
            reference_map(CSRBF_PSI31, R, n, st, coef, x, y);
            size_t in = 0;
            for (size_t j = 0; j < n; j++) {
                double d2 = 0;
                for (int k = 0; k < 3; k++) d2 += pow(x[k] - st[3 * j + k], 2);
                in += d2 < R * R;
            }
            pairs += in;
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                worst = fmax(worst, fabs(o1[3 * i + k] - y[k]));
                d2 += pow(y[k] - x[k], 2);
            }
            dmax = fmax(dmax, sqrt(d2));
            if (!in) {
                outside++;
                assert_memory_equal(o1 + 3 * i, v + 3 * i, 3 * sizeof(float));
            }
        }
        assert_true(outside > 0);
        assert_true(worst < 2e-5 * 25); /* float evaluation of coordinates up to 45 */
        assert_true(a.pairs + 4 >= pairs && a.pairs <= pairs + 4);
        assert_double_equal(a.max_displacement, dmax, 1e-4);
        free(coef);
        csrbf_solver_destroy(&s);
        free(st);
        free(en);
    }
    csrbf_points_destroy(&p);
    free(v);
    free(o1);
    free(o2);
    free(o3);
}

/* Touched evaluation over many frames: 42 fingertips that press, slide, leave the mesh
 * altogether and come back; anchored stretches (same start points: the cached selection),
 * unanchored ones (new start points every frame), a switch to 100 centres (general path) and
 * back, and a polynomial frame (every vertex moves). Every frame equals csrbf_evaluate bit for
 * bit, vertices outside every support equal the base exactly (supports that moved away are
 * restored), and outside the reported ranges nothing changed since the last frame. */
static void test_touched_frames(void **state)
{
    (void)state;
    size_t nx = 157, ny = 131, nv = nx * ny; /* not a multiple of 16 */
    double h = 0.2, R = 1.5, W = h * (double)(nx - 1), H = h * (double)(ny - 1);
    float *v = wavy_grid(nx, ny, h);
    float *out = malloc(nv * 3 * sizeof *out), *ref = malloc(nv * 3 * sizeof *ref),
          *last = malloc(nv * 3 * sizeof *last);
    enum { NMAX = 100 };
    float st0[3 * NMAX], en0[3 * NMAX], st[3 * NMAX], en[3 * NMAX];
    scatter_centres(NMAX, W, H, 0.1, st0, en0);
    csrbf_points *p = NULL;
    csrbf_touch *tc = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_touch_create(p, &tc), CSRBF_OK);
    csrbf_solver *s = make_solver(R, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    csrbf_solver *sp = make_solver(R, CSRBF_PSI31, CSRBF_POLY_LINEAR, 0);
    size_t n_last = 0;
    for (int frame = 0; frame < 60; frame++) {
        /* 0-9 anchored 42; 10-19 unanchored 42 sliding; 20-24 all away (far off the mesh);
         * 25-29 back, anchored; 30-34 100 centres; 35 polynomial; 36-59 anchored 42 again
         * with a jump at 45 */
        size_t n = frame >= 30 && frame < 35 ? NMAX : 42;
        double dx = 0, dy = 0;
        if (frame >= 10 && frame < 20) dx = 0.35 * (frame - 9);
        if (frame >= 20 && frame < 25) dx = 4 * W;
        if (frame >= 45) dy = 2.0;
        for (size_t i = 0; i < n; i++) {
            st[3 * i] = st0[3 * i] + (float)dx;
            st[3 * i + 1] = st0[3 * i + 1] + (float)dy;
            st[3 * i + 2] = st0[3 * i + 2];
            double ph = 0.3 * frame + (double)i;
            for (int a = 0; a < 3; a++)
                en[3 * i + a] = st[3 * i + a] + (en0[3 * i + a] - st0[3 * i + a]) * (float)cos(ph + a);
        }
        csrbf_solver *cur = frame == 35 ? sp : s;
        int anchored = n == n_last && frame != 10 && frame != 20 && frame != 25 &&
                       frame != 45 && frame != 36 && !(frame > 10 && frame < 20);
        if (anchored)
            assert_true(csrbf_solver_set_end_points(cur, en) >= 0);
        else
            assert_true(csrbf_solver_solve(cur, n, st, en) >= 0);
        if (frame == 35) assert_true(csrbf_solver_solve(sp, n, st, en) >= 0);
        n_last = frame == 35 ? 0 : n;
        csrbf_eval_stats a, b;
        assert_int_equal(csrbf_evaluate(cur, p, ref, 0, &a), CSRBF_OK);
        if (frame > 0) memcpy(last, out, nv * 3 * sizeof *out);
        assert_int_equal(csrbf_evaluate_touched(cur, p, tc, out, 0, &b), CSRBF_OK);
        assert_memory_equal(out, ref, nv * 3 * sizeof *out);
        assert_int_equal(a.pairs, b.pairs);
        assert_int_equal(a.moved, b.moved);
        assert_double_equal(a.max_displacement, b.max_displacement, 0);
        if (frame >= 20 && frame < 25) { /* every support is off the mesh: the base exactly */
            assert_int_equal(b.pairs, 0);
            assert_memory_equal(out, v, nv * 3 * sizeof *out);
        }
        const uint32_t *rg;
        size_t nr = csrbf_touch_ranges(tc, &rg);
        size_t covered = check_ranges(out, frame > 0 ? last : NULL, nv, rg, nr);
        if (frame == 0 || frame == 35 || frame == 36) assert_int_equal(covered, nv);
        if (frame == 21 || frame == 22) assert_int_equal(nr, 0); /* nothing left to restore */
        if (frame > 2 && frame < 10) assert_true(covered < nv);
    }
    csrbf_touch_destroy(&tc);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    csrbf_solver_destroy(&sp);
    free(v);
    free(out);
    free(ref);
    free(last);
}

/* Touched calls whose selection is new at each call (unanchored frames, with enough pairs
 * that the threads fork) walk the block tree and evaluate in the same parallel parts, each
 * part merging its selection with the last call's blocks there (or, writing every block,
 * copying its gaps). On 2 and 3 threads, at two radii, every
 * frame equals a full evaluation by a second solver (given the same points: its own
 * selection) bit for bit, with equal statistics; outside the reported ranges the output is
 * unchanged since the last frame. The frames slide the start points, jump them (blocks left
 * behind restored to the base), keep them (the kept selection's merge, after a call that
 * kept none), take every support off the mesh and back, and follow a reset (a full write). */
static void test_touched_fused(void **state)
{
    (void)state;
    size_t nx = 203, ny = 151, nv = nx * ny; /* not a multiple of 16 */
    double h = 0.5, W = h * (double)(nx - 1), H = h * (double)(ny - 1);
    float *v = wavy_grid(nx, ny, h);
    float *out = malloc(nv * 3 * sizeof *out), *ref = malloc(nv * 3 * sizeof *ref),
          *last = malloc(nv * 3 * sizeof *last);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    enum { N = 10 };
    for (int cfg = 0; cfg < 4; cfg++) {
        csrbf_options o = {0};
        /* ten supports of 28 x 28 over 101 x 75 (about 30,000 lanes: touched calls fork), or
         * of 44 x 44 (about 60,000: full writes, the first call and a reset's, fork too) */
        o.radius = cfg < 2 ? 14.0 : 22.0;
        o.threads = 2 + cfg % 2;
        csrbf_solver *s = NULL, *r = NULL;
        csrbf_touch *tc = NULL;
        assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
        assert_int_equal(csrbf_solver_create(&o, &r), CSRBF_OK);
        assert_int_equal(csrbf_touch_create(p, &tc), CSRBF_OK);
        float st[3 * N], en[3 * N];
        for (int frame = 0; frame < 24; frame++) {
            /* 0-7 slide; 8 jumps by a third of the grid; 9-11 slide; 12-13 keep 11's start
             * points; 14-15 slide; 16 after a reset; 17-19 slide; 20 every support off the
             * mesh; 21-23 back, sliding */
            int keep = frame == 12 || frame == 13;
            double dx = 1.3 * frame - (frame >= 8 ? 8.0 : 0.0), dy = frame >= 8 ? H / 3 : 0.0;
            if (frame == 20) dx += 4 * W;
            for (int i = 0; i < N && !keep; i++) {
                st[3 * i] = (float)(0.1 * W + 0.17 * W * (i % 5) + dx);
                st[3 * i + 1] = (float)(0.2 * H + 0.4 * H * (i / 5) + dy);
                st[3 * i + 2] = (float)(0.05 * i);
            }
            for (int i = 0; i < N; i++)
                for (int a = 0; a < 3; a++)
                    en[3 * i + a] = st[3 * i + a] + (float)(0.4 * cos(0.7 * frame + i + 2.0 * a));
            if (frame == 16) csrbf_touch_reset(tc);
            if (keep) {
                assert_true(csrbf_solver_set_end_points(s, en) >= 0);
            } else {
                assert_true(csrbf_solver_solve(s, N, st, en) >= 0);
            }
            assert_true(csrbf_solver_solve(r, N, st, en) >= 0);
            csrbf_eval_stats a, b;
            if (frame > 0) memcpy(last, out, nv * 3 * sizeof *out);
            assert_int_equal(csrbf_evaluate_touched(s, p, tc, out, 0, &b), CSRBF_OK);
            assert_int_equal(csrbf_evaluate(r, p, ref, 0, &a), CSRBF_OK);
            assert_memory_equal(out, ref, nv * 3 * sizeof *out);
            assert_int_equal(a.pairs, b.pairs);
            assert_int_equal(a.moved, b.moved);
            assert_double_equal(a.max_displacement, b.max_displacement, 0);
            if (frame == 20) assert_int_equal(b.pairs, 0);
            else assert_true(b.pairs > 15000);
            const uint32_t *rg;
            /* (runs joined across the parts as well) */
            size_t nr = csrbf_touch_ranges(tc, &rg);
            size_t covered = check_ranges(out, frame > 0 ? last : NULL, nv, rg, nr);
            if (frame == 0 || frame == 16) assert_int_equal(covered, nv);
            else if (frame != 8) assert_true(covered < nv); /* 8: the old blocks and the new */
        }
        csrbf_touch_destroy(&tc);
        csrbf_solver_destroy(&s);
        csrbf_solver_destroy(&r);
    }
    csrbf_points_destroy(&p);
    free(v);
    free(out);
    free(ref);
    free(last);
}

/* The cached block selection follows the points: one solver alternates between two vertex
 * sets and one of them is moved (csrbf_points_update, then csrbf_points_update_ranges);
 * every result equals a fresh vertex set's through a fresh solver. */
static void test_selection_cache(void **state)
{
    (void)state;
    size_t nx = 120, ny = 90, nv = nx * ny;
    float *v = wavy_grid(nx, ny, 0.1), *w = wavy_grid(nx, ny, 0.1);
    for (size_t i = 0; i < nv; i++) w[3 * i] += 3.0f; /* shifted by 3 in x */
    float *o1 = malloc(nv * 3 * sizeof *o1), *o2 = malloc(nv * 3 * sizeof *o2);
    float st[3 * 42], en[3 * 42];
    scatter_centres(42, 11.9, 8.9, 0.05, st, en);
    csrbf_solver *s = make_solver(0.8, CSRBF_PSI32, CSRBF_POLY_NONE, 0);
    assert_true(csrbf_solver_solve(s, 42, st, en) >= 0);
    csrbf_points *a = NULL, *b = NULL, *fresh = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &a), CSRBF_OK);
    assert_int_equal(csrbf_points_create(nv, w, &b), CSRBF_OK);
    for (int round = 0; round < 4; round++) {
        const float *pos = round < 2 ? w : v; /* rounds 2, 3: b holds v's positions */
        if (round == 2) assert_int_equal(csrbf_points_update(b, v), CSRBF_OK);
        if (round == 3) { /* move one row of b by 3 in y, under other supports */
            uint32_t rg[2] = {(uint32_t)(nx * 40), (uint32_t)nx};
            float *mix = malloc(nv * 3 * sizeof *mix);
            memcpy(mix, v, nv * 3 * sizeof *mix);
            for (size_t i = nx * 40; i < nx * 41; i++) mix[3 * i + 1] += 3.0f;
            assert_int_equal(csrbf_points_update_ranges(b, mix, rg, 1), CSRBF_OK);
            assert_int_equal(csrbf_points_create(nv, mix, &fresh), CSRBF_OK);
            free(mix);
        } else {
            assert_int_equal(csrbf_points_create(nv, pos, &fresh), CSRBF_OK);
        }
        assert_int_equal(csrbf_evaluate(s, a, o1, 0, NULL), CSRBF_OK);
        assert_int_equal(csrbf_evaluate(s, b, o1, 0, NULL), CSRBF_OK);
        csrbf_solver *s2 = make_solver(0.8, CSRBF_PSI32, CSRBF_POLY_NONE, 0);
        assert_true(csrbf_solver_solve(s2, 42, st, en) >= 0);
        assert_int_equal(csrbf_evaluate(s2, fresh, o2, 0, NULL), CSRBF_OK);
        assert_memory_equal(o1, o2, nv * 3 * sizeof *o1);
        csrbf_solver_destroy(&s2);
        csrbf_points_destroy(&fresh);
    }
    csrbf_points_destroy(&a);
    csrbf_points_destroy(&b);
    csrbf_solver_destroy(&s);
    free(v);
    free(w);
    free(o1);
    free(o2);
}

/* The paths a selection takes: new (a full write with large supports walks and evaluates per
 * part of the mesh in the threads), seen twice (kept and trimmed), kept (reused), touched;
 * all give the same output bit for bit, close to the dense reference, with equal statistics. */
static void test_selection_paths(void **state)
{
    (void)state;
    size_t nx = 301, ny = 299, nv = nx * ny, n = 42;
    double h = 0.1, R = 6.0;
    float *v = wavy_grid(nx, ny, h);
    float *o[4], st[3 * 42], en[3 * 42];
    for (int i = 0; i < 4; i++) o[i] = malloc(nv * 3 * sizeof *o[i]);
    scatter_centres(n, h * (double)(nx - 1), h * (double)(ny - 1), 0.3, st, en);
    csrbf_options opt = {0};
    opt.radius = R;
    opt.threads = 2;
    csrbf_solver *s = NULL;
    assert_int_equal(csrbf_solver_create(&opt, &s), CSRBF_OK);
    int rc = csrbf_solver_solve(s, n, st, en);
    assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
    csrbf_points *p = NULL;
    csrbf_touch *tc = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_touch_create(p, &tc), CSRBF_OK);
    csrbf_eval_stats es[4];
    for (int i = 0; i < 3; i++) assert_int_equal(csrbf_evaluate(s, p, o[i], 0, &es[i]), CSRBF_OK);
    assert_int_equal(csrbf_evaluate_touched(s, p, tc, o[3], 0, &es[3]), CSRBF_OK);
    for (int i = 1; i < 4; i++) {
        assert_memory_equal(o[0], o[i], nv * 3 * sizeof *o[0]);
        assert_int_equal(es[0].pairs, es[i].pairs);
        assert_int_equal(es[0].moved, es[i].moved);
        assert_double_equal(es[0].max_displacement, es[i].max_displacement, 0);
    }
    assert_true(es[0].pairs > 10 * nv / 10); /* large supports: about 10 per vertex */
    double *coef = malloc((n + 4) * 3 * sizeof *coef), worst = 0;
    reference_solve(CSRBF_PSI31, R, 0, n, st, en, coef);
    for (size_t i = 0; i < nv; i += 7) {
        double x[3] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]}, y[3];
        reference_map(CSRBF_PSI31, R, n, st, coef, x, y);
        for (int a = 0; a < 3; a++) worst = fmax(worst, fabs(o[0][3 * i + a] - y[a]));
    }
    assert_true(worst < 2e-5 * 30);
    free(coef);
    csrbf_touch_destroy(&tc);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    for (int i = 0; i < 4; i++) free(o[i]);
    free(v);
}

/* Statistics from the fast path (counted per block inside the vectorised kernel) equal the
 * general path's (taken with the Jacobian flag), with a padded last block, for the masked
 * (some centres) and the all-in (every vertex in every support) cases. */
static void test_stats_fast_path(void **state)
{
    (void)state;
    size_t n = 8, nv = 20001;
    float *st = random_points(n, 10.0, 1.0), *en = displaced(st, n, 0.3);
    float *v = malloc(nv * 3 * sizeof *v), *out = malloc(nv * 3 * sizeof *out);
    for (size_t i = 0; i < 3 * nv; i++) v[i] = (float)(urand() * 20 - 5);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    const double radii[2] = {3.0, 80.0};
    for (int k = 0; k < 2; k++) {
        csrbf_solver *s = make_solver(radii[k], CSRBF_PSI31, CSRBF_POLY_NONE, 0);
        assert_true(csrbf_solver_solve(s, n, st, en) >= 0);
        csrbf_eval_stats a, b;
        assert_int_equal(csrbf_evaluate(s, p, out, 0, &a), CSRBF_OK);
        assert_int_equal(csrbf_evaluate(s, p, out, CSRBF_EVAL_JACOBIAN, &b), CSRBF_OK);
        assert_int_equal(a.pairs, b.pairs);
        assert_int_equal(a.moved, b.moved);
        assert_true(a.pairs > 1000);
        if (k == 1) assert_int_equal(a.pairs, n * nv);
        assert_double_equal(a.max_displacement, b.max_displacement, 1e-5 * b.max_displacement);
        assert_true(a.min_jacobian_det == 1.0);
        csrbf_solver_destroy(&s);
    }
    csrbf_points_destroy(&p);
    free(st);
    free(en);
    free(v);
    free(out);
}

/* Vertices outside every support keep their base position bit for bit (no polynomial), and
 * the pair statistics match a brute-force count. */
static void test_outside_support_exact(void **state)
{
    (void)state;
    size_t n = 8, nv = 20000;
    float *st = random_points(n, 10.0, 1.0), *en = displaced(st, n, 0.8);
    float *v = malloc(nv * 3 * sizeof *v), *out = malloc(nv * 3 * sizeof *out);
    for (size_t i = 0; i < 3 * nv; i++) v[i] = (float)(urand() * 40 - 15);
    v[0] = -0.0f; /* a negative zero far from every centre stays negative zero */
    v[1] = -30.0f;
    v[2] = -0.0f;
    double R = 3.0;
    csrbf_solver *s = make_solver(R, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    assert_int_equal(csrbf_solver_solve(s, n, st, en), CSRBF_OK);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    csrbf_eval_stats stats;
    assert_int_equal(csrbf_evaluate(s, p, out, 0, &stats), CSRBF_OK);
    size_t pairs = 0, moved = 0, outside = 0;
    for (size_t i = 0; i < nv; i++) {
        size_t in = 0;
        for (size_t j = 0; j < n; j++) {
            double d2 = 0;
            for (int a = 0; a < 3; a++) {
                float dd = v[3 * i + a] - st[3 * j + a];
                d2 += (double)dd * dd;
            }
            in += d2 < R * R * (1 - 1e-6);
        }
        pairs += in;
        moved += in > 0;
        if (!in) {
            outside++;
            assert_memory_equal(out + 3 * i, v + 3 * i, 3 * sizeof(float));
        }
    }
    assert_true(outside > nv / 2);
    assert_true(pairs > 100);
    /* float boundary decisions may differ from the double count by a pair or two */
    assert_true(stats.pairs + 2 >= pairs && stats.pairs <= pairs + 2);
    assert_true(stats.moved + 2 >= moved && stats.moved <= moved + 2);
    assert_true(signbit(out[0]) && signbit(out[2]));
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    free(st);
    free(en);
    free(v);
    free(out);
}

/* ------------------------------------------------------------------ dense reference */

static void check_reference(size_t n, double L, double R, csrbf_kernel k, int poly,
                            int dense_limit)
{
    float *st = random_points(n, L, 0.05 * R), *en = displaced(st, n, 0.05 * R);
    csrbf_solver *s = make_solver(R, k, poly ? CSRBF_POLY_LINEAR : CSRBF_POLY_NONE, dense_limit);
    int rc = csrbf_solver_solve(s, n, st, en);
    assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
    assert_int_equal(csrbf_solver_centres(s), n);
    double *coef = malloc((n + 4) * 3 * sizeof *coef);
    reference_solve(k, R, poly, n, st, en, coef);
    /* the coefficients themselves (no merging here: same order) */
    double *al = malloc(n * 3 * sizeof *al), *cen = malloc(n * 3 * sizeof *cen), pl[12];
    assert_int_equal(csrbf_solver_get_coefficients(s, cen, al, pl), CSRBF_OK);
    double amax = 1e-3;
    for (size_t i = 0; i < 3 * n; i++) amax = fmax(amax, fabs(coef[i]));
    for (size_t i = 0; i < 3 * n; i++) {
        assert_double_equal(al[i], coef[i], 1e-8 * amax);
        assert_double_equal(cen[i], st[i], 0);
    }
    for (int a = 0; a < 3; a++) {
        assert_double_equal(pl[a], coef[3 * n + a], 1e-8 * fmax(1, L));
        for (int l = 0; l < 3; l++)
            assert_double_equal(pl[3 + 3 * a + l], coef[3 * n + 3 + 3 * l + a], 1e-8);
    }
    free(al);
    free(cen);
    double worst = 0;
    for (int t = 0; t < 200; t++) {
        double x[3], y[3], z[3];
        if (t < 100) {
            size_t i = (size_t)(urand() * n);
            for (int a = 0; a < 3; a++) x[a] = st[3 * i + a] + (urand() - 0.5) * R;
        } else {
            for (int a = 0; a < 3; a++) x[a] = urand() * L;
        }
        assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_OK);
        reference_map(k, R, n, st, coef, x, z);
        for (int a = 0; a < 3; a++) worst = fmax(worst, fabs(y[a] - z[a]));
    }
    assert_true(worst < 1e-8 * fmax(1.0, L));
    csrbf_solver_destroy(&s);
    free(coef);
    free(st);
    free(en);
}

static void test_dense_reference(void **state)
{
    (void)state;
    check_reference(10, 5.0, 3.0, CSRBF_PSI31, 0, 0);
    check_reference(10, 5.0, 3.0, CSRBF_PSI31, 1, 0);
    check_reference(100, 10.0, 3.0, CSRBF_PSI32, 1, 0);
    check_reference(100, 10.0, 3.0, CSRBF_PSI30, 0, 0);
    check_reference(1000, 20.0, 3.0, CSRBF_PSI31, 0, 0); /* CHOLMOD path (> dense limit) */
    check_reference(1000, 20.0, 3.0, CSRBF_PSI31, 1, 0);
}

static void test_cholmod_vs_dense(void **state)
{
    (void)state;
    size_t n = 150;
    float *st = random_points(n, 10.0, 0.2), *en = displaced(st, n, 0.3);
    for (int poly = 0; poly < 2; poly++) {
        csrbf_solver *a = make_solver(3.0, CSRBF_PSI31, poly, 1000); /* dense */
        csrbf_solver *b = make_solver(3.0, CSRBF_PSI31, poly, -1);   /* always CHOLMOD */
        assert_true(csrbf_solver_solve(a, n, st, en) >= 0);
        assert_true(csrbf_solver_solve(b, n, st, en) >= 0);
        for (int t = 0; t < 100; t++) {
            double x[3] = {urand() * 10, urand() * 10, urand() * 10}, ya[3], yb[3], ja[9], jb[9];
            assert_int_equal(csrbf_solver_map_point(a, x, ya, ja), CSRBF_OK);
            assert_int_equal(csrbf_solver_map_point(b, x, yb, jb), CSRBF_OK);
            for (int c = 0; c < 3; c++) assert_double_equal(ya[c], yb[c], 1e-9);
            for (int c = 0; c < 9; c++) assert_double_equal(ja[c], jb[c], 1e-8);
        }
        csrbf_solver_destroy(&a);
        csrbf_solver_destroy(&b);
    }
    free(st);
    free(en);
}

/* ------------------------------------------------------------------ degenerate centres */

static void test_coincident_centres(void **state)
{
    (void)state;
    float st[] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 1.00001f, 0, 0};
    float en[] = {0, 0, 0.1f, 1, 0, 0.2f, 1, 0, 0.4f, 0, 1, 0.1f, 1, 0, 0.6f};
    csrbf_solver *s = make_solver(2.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    int rc = csrbf_solver_solve(s, 5, st, en);
    assert_int_equal(rc, CSRBF_WARN_MERGED);
    assert_true(csrbf_solver_warnings(s) & (1u << CSRBF_WARN_MERGED));
    assert_non_null(strstr(csrbf_solver_message(s), "merged"));
    assert_int_equal(csrbf_solver_centres(s), 3);
    /* the merged centre moves by the mean displacement (0.2 + 0.4 + 0.6) / 3 */
    double x[3] = {1, 0, 0}, y[3];
    assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_OK);
    assert_double_equal(y[2], 0.4, 1e-6);
    assert_double_equal(y[0], 1.0 - 0.00001 / 3, 1e-7); /* the third member sat at 1.00001 */
    double x0[3] = {0, 1, 0};
    assert_int_equal(csrbf_solver_map_point(s, x0, y, NULL), CSRBF_OK);
    assert_double_equal(y[2], (double)0.1f, 1e-9);
    csrbf_solver_destroy(&s);

    /* just above the tolerance: kept apart, still finite and interpolating */
    float st2[] = {0, 0, 0, 0.001f, 0, 0};
    float en2[] = {0, 0, 0.01f, 0.001f, 0, -0.01f};
    s = make_solver(2.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    rc = csrbf_solver_solve(s, 2, st2, en2);
    assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
    assert_int_equal(csrbf_solver_centres(s), 2);
    double x2[3] = {0.001, 0, 0};
    assert_int_equal(csrbf_solver_map_point(s, x2, y, NULL), CSRBF_OK);
    assert_double_equal(y[2], -0.01, 1e-6);
    csrbf_solver_destroy(&s);
}

static void test_coplanar_poly(void **state)
{
    (void)state;
    size_t n = 30;
    float *st = random_points(n, 10.0, 1.0);
    for (size_t i = 0; i < 3 * n; i++) st[i] = floorf(st[i] * 64) / 64; /* exact sums below */
    for (size_t i = 0; i < n; i++) st[3 * i + 2] = 2.0f; /* the plane z = 2 */
    float *en = displaced(st, n, 0.3);
    csrbf_solver *s = make_solver(3.0, CSRBF_PSI31, CSRBF_POLY_LINEAR, 0);
    int rc = csrbf_solver_solve(s, n, st, en);
    assert_true(csrbf_solver_warnings(s) & (1u << CSRBF_WARN_POLY_RANK));
    assert_true(rc > 0);
    assert_non_null(strstr(csrbf_solver_message(s), "coplanar"));
    assert_true(interpolation_error(s, n, st, en) < 1e-5);
    /* a translation is reproduced everywhere by the polynomial, far points included */
    for (size_t i = 0; i < 3 * n; i++) en[i] = st[i] + (i % 3 == 0 ? 0.5f : i % 3 == 1 ? -0.25f : 0.125f);
    assert_true(csrbf_solver_set_end_points(s, en) >= 0);
    double x[3] = {100, -50, 7}, y[3];
    assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_OK);
    assert_double_equal(y[0], 100.5, 1e-9);
    assert_double_equal(y[1], -50.25, 1e-9);
    assert_double_equal(y[2], 7.125, 1e-9);
    csrbf_solver_destroy(&s);
    free(st);
    free(en);
}

static void test_small_n_poly(void **state)
{
    (void)state;
    float st[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    float en[] = {0.1f, 0.2f, 0.3f, 1.1f, 0.3f, 0.1f, 0.2f, 1.1f, -0.2f};
    for (size_t n = 1; n <= 3; n++) {
        csrbf_solver *s = make_solver(2.0, CSRBF_PSI31, CSRBF_POLY_LINEAR, 0);
        int rc = csrbf_solver_solve(s, n, st, en);
        assert_true(rc > 0);
        assert_true(csrbf_solver_warnings(s) & (1u << CSRBF_WARN_POLY_RANK));
        assert_true(interpolation_error(s, n, st, en) < 1e-5);
        double x[3] = {50, 50, 50}, y[3];
        assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_OK);
        for (int a = 0; a < 3; a++) assert_true(isfinite(y[a]));
        if (n == 1) /* one control vector: a pure translation */
            for (int a = 0; a < 3; a++) assert_double_equal(y[a] - x[a], en[a] - st[a], 1e-6);
        csrbf_solver_destroy(&s);
    }
}

/* ------------------------------------------------------------------ factor reuse */

static void test_reuse_factor(void **state)
{
    (void)state;
    size_t n = 300;
    float *st = random_points(n, 12.0, 0.3);
    float *e1 = displaced(st, n, 0.2), *e2 = displaced(st, n, 0.2);
    for (int poly = 0; poly < 2; poly++) {
        csrbf_solver *a = make_solver(3.0, CSRBF_PSI31, poly, 0);
        csrbf_solver *b = make_solver(3.0, CSRBF_PSI31, poly, 0);
        assert_true(csrbf_solver_solve(a, n, st, e1) >= 0);
        assert_true(csrbf_solver_set_end_points(a, e2) >= 0); /* reused factor */
        assert_true(csrbf_solver_solve(b, n, st, e2) >= 0);   /* fresh */
        for (int t = 0; t < 100; t++) {
            double x[3] = {urand() * 12, urand() * 12, urand() * 12}, ya[3], yb[3];
            csrbf_solver_map_point(a, x, ya, NULL);
            csrbf_solver_map_point(b, x, yb, NULL);
            for (int c = 0; c < 3; c++) assert_double_equal(ya[c], yb[c], 1e-12);
        }
        csrbf_solver_destroy(&a);
        csrbf_solver_destroy(&b);
    }
    free(st);
    free(e1);
    free(e2);
}

/* ------------------------------------------------------------- evaluate vs map_point */

static void check_evaluate(size_t n, double R, csrbf_kernel k, csrbf_poly poly, int threads)
{
    size_t nv = 5000;
    float *st = random_points(n, 10.0, 0.1 * R), *en = displaced(st, n, 0.1 * R);
    float *v = malloc(nv * 3 * sizeof *v), *out = malloc(nv * 3 * sizeof *out);
    for (size_t i = 0; i < 3 * nv; i++) v[i] = (float)(urand() * 12 - 1);
    csrbf_options o = {0};
    o.radius = R;
    o.kernel = k;
    o.poly = poly;
    o.threads = threads;
    csrbf_solver *s = NULL;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
    assert_true(csrbf_solver_solve(s, n, st, en) >= 0);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    csrbf_eval_stats stats;
    assert_int_equal(csrbf_evaluate(s, p, out, CSRBF_EVAL_JACOBIAN, &stats), CSRBF_OK);
    double worst = 0, maxd = 0, minj = 1;
    for (size_t i = 0; i < nv; i++) {
        double x[3] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]}, y[3], J[9];
        assert_int_equal(csrbf_solver_map_point(s, x, y, J), CSRBF_OK);
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
            worst = fmax(worst, fabs(out[3 * i + a] - y[a]));
            d2 += pow(y[a] - x[a], 2);
        }
        maxd = fmax(maxd, sqrt(d2));
        double det = J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) +
                     J[2] * (J[3] * J[7] - J[4] * J[6]);
        minj = fmin(minj, det);
    }
    assert_true(worst < 2e-5 * 12);
    assert_double_equal(stats.max_displacement, maxd, 1e-4);
    assert_double_equal(stats.min_jacobian_det, minj, 1e-9);
    /* the same result without statistics (the fast path) */
    float *out2 = malloc(nv * 3 * sizeof *out2);
    assert_int_equal(csrbf_evaluate(s, p, out2, 0, NULL), CSRBF_OK);
    assert_memory_equal(out, out2, nv * 3 * sizeof *out);
    free(out2);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    free(st);
    free(en);
    free(v);
    free(out);
}

static void test_evaluate_vs_map(void **state)
{
    (void)state;
    for (int k = 0; k < 3; k++) {
        check_evaluate(10, 30.0, (csrbf_kernel)k, CSRBF_POLY_NONE, 0);   /* all in support */
        check_evaluate(10, 2.0, (csrbf_kernel)k, CSRBF_POLY_NONE, 2);    /* block selection */
        check_evaluate(200, 2.0, (csrbf_kernel)k, CSRBF_POLY_LINEAR, 1); /* centre grid */
    }
    check_evaluate(400, 1.5, CSRBF_PSI31, CSRBF_POLY_NONE, 2);
}

/* points_update moves the vertices; the result follows. */
static void test_points_update(void **state)
{
    (void)state;
    float st[] = {0, 0, 0};
    float en[] = {0.1f, 0, 0};
    float v[] = {0, 0, 0, 5, 5, 5};
    float v2[] = {5, 5, 5, 0, 0, 0};
    float out[6];
    csrbf_solver *s = make_solver(1.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    assert_int_equal(csrbf_solver_solve(s, 1, st, en), CSRBF_OK);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(2, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_points_count(p), 2);
    assert_int_equal(csrbf_evaluate(s, p, out, 0, NULL), CSRBF_OK);
    assert_double_equal(out[0], 0.1, 1e-7);
    assert_double_equal(out[3], 5, 0);
    assert_int_equal(csrbf_points_update(p, v2), CSRBF_OK);
    assert_int_equal(csrbf_evaluate(s, p, out, 0, NULL), CSRBF_OK);
    assert_double_equal(out[0], 5, 0);
    assert_double_equal(out[3], 0.1, 1e-7);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
}

/* ------------------------------------------------------------------ Jacobian */

static void test_jacobian_fd(void **state)
{
    (void)state;
    size_t n = 20;
    float *st = random_points(n, 6.0, 0.5), *en = displaced(st, n, 0.3);
    for (int k = 0; k < 3; k++)
        for (int poly = 0; poly < 2; poly++) {
            csrbf_solver *s = make_solver(3.0, (csrbf_kernel)k, poly, 0);
            assert_true(csrbf_solver_solve(s, n, st, en) >= 0);
            for (int t = 0; t < 50; t++) {
                double x[3] = {urand() * 6, urand() * 6, urand() * 6}, y[3], J[9];
                assert_int_equal(csrbf_solver_map_point(s, x, y, J), CSRBF_OK);
                for (int b = 0; b < 3; b++) {
                    double h = 1e-6, xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, yp[3], ym[3];
                    xp[b] += h;
                    xm[b] -= h;
                    csrbf_solver_map_point(s, xp, yp, NULL);
                    csrbf_solver_map_point(s, xm, ym, NULL);
                    for (int a = 0; a < 3; a++)
                        assert_double_equal(J[a * 3 + b], (yp[a] - ym[a]) / (2 * h), 1e-5);
                }
            }
            csrbf_solver_destroy(&s);
        }
    free(st);
    free(en);
}

static void test_foldover(void **state)
{
    (void)state;
    float st[] = {0, 0, 0, 5, 0, 0};
    float small[] = {0.2f, 0, 0, 5, 0, 0};
    float big[] = {3.0f, 0, 0, 5, 0, 0};
    csrbf_solver *s = make_solver(4.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    assert_int_equal(csrbf_solver_solve(s, 2, st, small), CSRBF_OK);
    float v[3 * 200];
    for (int i = 0; i < 200; i++) {
        v[3 * i] = -4.0f + 0.05f * (float)i;
        v[3 * i + 1] = 0.0f;
        v[3 * i + 2] = 0.0f;
    }
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(200, v, &p), CSRBF_OK);
    float out[3 * 200];
    csrbf_eval_stats stats;
    assert_int_equal(csrbf_evaluate(s, p, out, CSRBF_EVAL_JACOBIAN, &stats), CSRBF_OK);
    assert_true(stats.min_jacobian_det > 0);
    assert_int_equal(csrbf_solver_set_end_points(s, big), CSRBF_WARN_FOLDOVER);
    assert_non_null(strstr(csrbf_solver_message(s), "fold-over"));
    assert_int_equal(csrbf_evaluate(s, p, out, CSRBF_EVAL_JACOBIAN, &stats), CSRBF_OK);
    assert_true(stats.min_jacobian_det < 0);
    /* without the flag the determinant is not computed */
    assert_int_equal(csrbf_evaluate(s, p, out, 0, &stats), CSRBF_OK);
    assert_double_equal(stats.min_jacobian_det, 1.0, 0);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
}

/* ------------------------------------------------------------------ invalid input */

static void test_invalid(void **state)
{
    (void)state;
    csrbf_options o = {0};
    csrbf_solver *s = (csrbf_solver *)1;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_ERR_INVALID);
    assert_null(s);
    assert_non_null(strstr(csrbf_options_message(), "radius"));
    o.radius = NAN;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_ERR_INVALID);
    o.radius = -1;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_ERR_INVALID);
    o.radius = 1;
    o.merge_tolerance = -1;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_ERR_INVALID);
    assert_non_null(strstr(csrbf_options_message(), "merge_tolerance"));
    o.merge_tolerance = 0;
    o.kernel = (csrbf_kernel)9;
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_ERR_INVALID);
    o.kernel = CSRBF_PSI31;
    assert_int_equal(csrbf_solver_create(NULL, &s), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_solver_create(&o, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);

    float st[] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, NAN};
    float en[] = {0, 0, 0, 1, 0, 0, 2, 0, INFINITY, 3, 0, 0};
    assert_int_equal(csrbf_solver_set_end_points(s, en), CSRBF_ERR_STATE);
    assert_int_equal(csrbf_solver_set_start_points(s, 4, st), CSRBF_ERR_INVALID);
    assert_non_null(strstr(csrbf_solver_message(s), "start point 3 has a NaN z coordinate"));
    assert_int_equal(csrbf_solver_set_start_points(s, 0, st), CSRBF_ERR_INVALID);
    assert_non_null(strstr(csrbf_solver_message(s), "n is 0"));
    assert_int_equal(csrbf_solver_set_start_points(s, 3, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_solver_set_start_points(s, 3, st), CSRBF_OK);
    assert_int_equal(csrbf_solver_set_end_points(s, en), CSRBF_ERR_INVALID);
    assert_non_null(strstr(csrbf_solver_message(s), "end point 2"));
    assert_int_equal(csrbf_solver_set_end_points(s, NULL), CSRBF_ERR_INVALID);
    float huge[] = {0, 0, 0, 1e20f, 0, 0, 2, 0, 0};
    assert_int_equal(csrbf_solver_set_end_points(s, huge), CSRBF_ERR_INVALID);
    assert_non_null(strstr(csrbf_solver_message(s), "end point 1"));
    /* a failed start leaves no start points */
    assert_int_equal(csrbf_solver_set_start_points(s, 4, st), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_solver_set_end_points(s, en), CSRBF_ERR_STATE);

    double x[3] = {0, 0, 0}, y[3];
    assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_ERR_STATE);
    csrbf_points *p = NULL;
    float v[] = {0, 0, 0};
    float out[3];
    assert_int_equal(csrbf_points_create(1, v, &p), CSRBF_OK);
    assert_int_equal(csrbf_evaluate(s, p, out, 0, NULL), CSRBF_ERR_STATE);
    assert_int_equal(csrbf_solver_set_start_points(s, 3, st), CSRBF_OK);
    assert_int_equal(csrbf_evaluate(s, p, NULL, 0, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_evaluate(s, NULL, out, 0, NULL), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_evaluate(s, p, out, 0x80, NULL), CSRBF_ERR_INVALID);
    x[1] = NAN;
    assert_int_equal(csrbf_solver_map_point(s, x, y, NULL), CSRBF_ERR_INVALID);
    csrbf_points *q = (csrbf_points *)1;
    float bad[] = {0, NAN, 0};
    assert_int_equal(csrbf_points_create(1, bad, &q), CSRBF_ERR_INVALID);
    assert_null(q);
    assert_int_equal(csrbf_points_create(0, v, &q), CSRBF_ERR_INVALID);
    assert_int_equal(csrbf_points_update(p, bad), CSRBF_ERR_INVALID);
    assert_string_equal(csrbf_strerror(CSRBF_ERR_INVALID), "invalid argument");
    assert_string_equal(csrbf_strerror(12345), "unknown result");
    csrbf_points_destroy(&p);
    csrbf_points_destroy(&p); /* NULL is a no-op */
    csrbf_solver_destroy(&s);
    csrbf_solver_destroy(&s);
    csrbf_solver_destroy(NULL);
}

/* csrbf_simd_path names the path this process runs: what CSRBF_ISA asks for, at most (this
 * file runs as test_csrbf, test_csrbf_avx2 and test_csrbf_portable). */
static void test_simd_path(void **state)
{
    (void)state;
    const char *path = csrbf_simd_path(), *want = getenv("CSRBF_ISA");
    assert_true(!strcmp(path, "avx512") || !strcmp(path, "avx2") || !strcmp(path, "portable"));
    /* "portable", the name csrbf_simd_path gives the path, asks for it as "none" does */
    if (want && (!strcmp(want, "none") || !strcmp(want, "portable")))
        assert_string_equal(path, "portable");
    if (want && !strcmp(want, "avx2")) assert_true(strcmp(path, "avx512") != 0);
    assert_ptr_equal(csrbf_simd_path(), path); /* chosen once */
}

/* Two threads evaluating the same const solver at once get the same result as one. */
static void test_concurrent_evaluate(void **state)
{
    (void)state;
    size_t n = 50, nv = 30000;
    float *st = random_points(n, 10.0, 0.5), *en = displaced(st, n, 0.2);
    float *v = malloc(nv * 3 * sizeof *v);
    for (size_t i = 0; i < 3 * nv; i++) v[i] = (float)(urand() * 10);
    csrbf_solver *s = make_solver(2.0, CSRBF_PSI31, CSRBF_POLY_NONE, 0);
    assert_true(csrbf_solver_solve(s, n, st, en) >= 0);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    float *ref = malloc(nv * 3 * sizeof *ref), *o[4];
    assert_int_equal(csrbf_evaluate(s, p, ref, 0, NULL), CSRBF_OK);
    for (int t = 0; t < 4; t++) o[t] = malloc(nv * 3 * sizeof *ref);
    int rc[4];
#pragma omp parallel for num_threads(4)
    for (int t = 0; t < 4; t++) rc[t] = csrbf_evaluate(s, p, o[t], 0, NULL);
    for (int t = 0; t < 4; t++) {
        assert_int_equal(rc[t], CSRBF_OK);
        assert_memory_equal(o[t], ref, nv * 3 * sizeof *ref);
        free(o[t]);
    }
    free(ref);
    csrbf_points_destroy(&p);
    csrbf_solver_destroy(&s);
    free(st);
    free(en);
    free(v);
}

/* Anchored frames (start points kept, end points moving) reuse the kept selection's kernel
 * weights from the second use on: every frame, full and touched, with and without statistics,
 * on one thread and two, equals a fresh solver's first evaluation (weights from the kernels)
 * bit for bit, for each kernel; and a new set of start points is never served old weights. */
static void test_weight_cache(void **state)
{
    (void)state;
    size_t nx = 157, ny = 131, nv = nx * ny, n = 42; /* not a multiple of 16 */
    double h = 0.2, W = h * (double)(nx - 1), H = h * (double)(ny - 1);
    float *v = wavy_grid(nx, ny, h);
    float *o1 = malloc(nv * 3 * sizeof *o1), *o2 = malloc(nv * 3 * sizeof *o2),
          *o3 = malloc(nv * 3 * sizeof *o3);
    float st[3 * 42], en[3 * 42], st2[3 * 42], en2[3 * 42];
    scatter_centres(n, W, H, 0.1, st, en);
    scatter_centres(n, W, H, 0.1, st2, en2);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    const csrbf_kernel kernels[3] = {CSRBF_PSI31, CSRBF_PSI30, CSRBF_PSI32};
    /* R = 1.5: a selection of blocks; R = 60: every support holds the whole grid (41 across),
     * whose anchored frames go from computing every pair to the kept selection's weights */
    for (int kk = 0; kk < 6; kk++)
        for (int threads = 1; threads <= 2; threads++) {
            csrbf_options o = {0};
            o.radius = kk < 3 ? 1.5 : 60.0;
            o.kernel = kernels[kk % 3];
            o.threads = threads;
            csrbf_solver *s = NULL;
            csrbf_touch *tc = NULL;
            assert_int_equal(csrbf_solver_create(&o, &s), CSRBF_OK);
            assert_int_equal(csrbf_touch_create(p, &tc), CSRBF_OK);
            for (int f = 0; f < 12; f++) {
                const float *sp = f < 8 ? st : st2; /* frame 8: new start points */
                float e[3 * 42];
                for (size_t i = 0; i < 3 * n; i++)
                    e[i] = (f < 8 ? en : en2)[i] + 0.02f * (float)sin(0.9 * f + (double)i);
                if (f == 0 || f == 8) {
                    int rc = csrbf_solver_set_start_points(s, n, sp);
                    assert_true(rc >= 0);
                }
                int rc = csrbf_solver_set_end_points(s, e);
                assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
                csrbf_eval_stats a, b, c;
                assert_int_equal(csrbf_evaluate(s, p, o1, 0, f % 2 ? &a : NULL), CSRBF_OK);
                assert_int_equal(csrbf_evaluate_touched(s, p, tc, o3, 0, &c), CSRBF_OK);
                csrbf_solver *fresh = NULL;
                assert_int_equal(csrbf_solver_create(&o, &fresh), CSRBF_OK);
                rc = csrbf_solver_solve(fresh, n, sp, e);
                assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
                assert_int_equal(csrbf_evaluate(fresh, p, o2, 0, &b), CSRBF_OK);
                assert_memory_equal(o1, o2, nv * 3 * sizeof *o1);
                assert_memory_equal(o3, o2, nv * 3 * sizeof *o3);
                assert_int_equal(c.pairs, b.pairs);
                assert_int_equal(c.moved, b.moved);
                assert_double_equal(c.max_displacement, b.max_displacement, 0);
                if (f % 2) {
                    assert_int_equal(a.pairs, b.pairs);
                    assert_int_equal(a.moved, b.moved);
                    assert_double_equal(a.max_displacement, b.max_displacement, 0);
                }
                assert_true(b.pairs > 0);
                csrbf_solver_destroy(&fresh);
            }
            csrbf_touch_destroy(&tc);
            csrbf_solver_destroy(&s);
        }
    csrbf_points_destroy(&p);
    free(v);
    free(o1);
    free(o2);
    free(o3);
}

/* A parallel evaluation whose threads steal each other's chunks (8 threads on fewer cores:
 * threads start late and are preempted, so their parts are taken from the far end) writes
 * every block once: full writes (NaN beforehand) and touched updates, with the kept
 * selection's weights and without, bit for bit as one thread, with equal statistics. */
static void test_threads_steal(void **state)
{
    (void)state;
    size_t nx = 181, ny = 183, nv = nx * ny, n = 10; /* costs well above one thread's share */
    float *v = wavy_grid(nx, ny, 0.1);
    float *o[4];
    for (int i = 0; i < 4; i++) o[i] = malloc(nv * 3 * sizeof *o[i]);
    float st[3 * 10], en[3 * 10];
    scatter_centres(n, 18.0, 18.2, 0.2, st, en);
    csrbf_points *p = NULL;
    assert_int_equal(csrbf_points_create(nv, v, &p), CSRBF_OK);
    csrbf_solver *s[2] = {NULL, NULL};
    csrbf_touch *tc[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        csrbf_options opt = {0};
        opt.radius = 3.0; /* about 40% of the grid in a support */
        opt.threads = k ? 8 : 1;
        assert_int_equal(csrbf_solver_create(&opt, &s[k]), CSRBF_OK);
        assert_int_equal(csrbf_touch_create(p, &tc[k]), CSRBF_OK);
    }
    for (int f = 0; f < 40; f++) {
        float e[3 * 10];
        for (size_t i = 0; i < 3 * n; i++) e[i] = en[i] + 0.1f * (float)sin(0.7 * f + (double)i);
        csrbf_eval_stats es[4];
        if (f % 20 == 0) /* new start points: a new selection, then kept */
            for (size_t i = 0; i < 3 * n; i++) st[i] += 0.05f;
        for (int k = 0; k < 2; k++) {
            if (f % 20 == 0) assert_true(csrbf_solver_set_start_points(s[k], n, st) >= 0);
            int rc = csrbf_solver_set_end_points(s[k], e);
            assert_true(rc == CSRBF_OK || rc == CSRBF_WARN_FOLDOVER);
            for (size_t i = 0; i < 3 * nv; i++) o[k][i] = NAN;
            assert_int_equal(csrbf_evaluate(s[k], p, o[k], 0, &es[k]), CSRBF_OK);
            assert_int_equal(csrbf_evaluate_touched(s[k], p, tc[k], o[2 + k], 0, &es[2 + k]),
                             CSRBF_OK);
        }
        assert_memory_equal(o[0], o[1], nv * 3 * sizeof *o[0]);
        assert_memory_equal(o[2], o[3], nv * 3 * sizeof *o[2]);
        assert_memory_equal(o[0], o[2], nv * 3 * sizeof *o[0]);
        for (int k = 1; k < 4; k++) {
            assert_int_equal(es[0].pairs, es[k].pairs);
            assert_int_equal(es[0].moved, es[k].moved);
            assert_double_equal(es[0].max_displacement, es[k].max_displacement, 0);
        }
        assert_true(es[0].moved > nv / 5 && es[0].moved < nv);
    }
    for (int k = 0; k < 2; k++) {
        csrbf_touch_destroy(&tc[k]);
        csrbf_solver_destroy(&s[k]);
    }
    csrbf_points_destroy(&p);
    for (int i = 0; i < 4; i++) free(o[i]);
    free(v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kernel_values),       cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_outside_support_exact), cmocka_unit_test(test_dense_reference),
        cmocka_unit_test(test_cholmod_vs_dense),    cmocka_unit_test(test_coincident_centres),
        cmocka_unit_test(test_coplanar_poly),       cmocka_unit_test(test_small_n_poly),
        cmocka_unit_test(test_reuse_factor),        cmocka_unit_test(test_evaluate_vs_map),
        cmocka_unit_test(test_points_update),       cmocka_unit_test(test_jacobian_fd),
        cmocka_unit_test(test_foldover),            cmocka_unit_test(test_invalid),
        cmocka_unit_test(test_concurrent_evaluate), cmocka_unit_test(test_stats_fast_path),
        cmocka_unit_test(test_touched), cmocka_unit_test(test_update_ranges_tree),             cmocka_unit_test(test_many_centres),
        cmocka_unit_test(test_touched_frames),      cmocka_unit_test(test_touched_fused),      cmocka_unit_test(test_selection_cache),
        cmocka_unit_test(test_selection_paths),     cmocka_unit_test(test_weight_cache),
        cmocka_unit_test(test_simd_path),           cmocka_unit_test(test_threads_steal),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
