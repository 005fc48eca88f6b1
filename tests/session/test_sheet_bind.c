/* core/session/sheet_bind: two close sheets of different triangle sizes under a bend whose
 * piecewise-linear images cross (counted exactly, fp_contact_tri_tri) stop crossing when the
 * follower is carried with its leader; a single sheet, and sheets farther apart than the
 * gap, bind nothing; no vertex both follows and leads; ranges limit what moves, and a
 * follower the map left in place stays; a tuck (a vertex on a triangle of its own sheet) is
 * bound. */
#include "fp_contact.h"
#include "sheet_bind.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

typedef struct sheets {
    float *pos;
    uint32_t *tris;
    size_t n, t, n_a, t_a; /* sheet A: vertices [0, n_a), triangles [0, t_a) */
} sheets;

/* a (k+1) x (k+1) grid of spacing h over [-k h / 2, k h / 2]^2 at height z, offset in x, y */
static void add_grid(sheets *s, int k, double h, double z, double off)
{
    size_t v0 = s->n;
    for (int j = 0; j <= k; j++)
        for (int i = 0; i <= k; i++) {
            float *p = s->pos + 3 * s->n++;
            p[0] = (float)(off + h * (i - k / 2.0)), p[1] = (float)(off + h * (j - k / 2.0)), p[2] = (float)z;
        }
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            uint32_t a = (uint32_t)(v0 + (size_t)j * (k + 1) + i), b = a + 1, c = a + (uint32_t)k + 1, d = c + 1;
            uint32_t *t = s->tris + 3 * s->t;
            t[0] = a, t[1] = b, t[2] = d, t[3] = a, t[4] = d, t[5] = c;
            s->t += 2;
        }
}

/* sheet A (spacing 0.1, 21 x 21) at z 0 and, unless gap is NAN, sheet B (spacing 0.13) at gap */
static sheets make(double gap)
{
    sheets s = {0};
    s.pos = malloc(2000 * 3 * sizeof *s.pos);
    s.tris = malloc(2000 * 3 * sizeof *s.tris);
    add_grid(&s, 20, 0.1, 0.0, 0.0);
    s.n_a = s.n, s.t_a = s.t;
    if (!isnan(gap)) add_grid(&s, 14, 0.13, gap, 0.031);
    return s;
}

/* the bend: z - 3 (x^2 + y^2) - 0.01 (every vertex moves), whose chords sag below it by up to
 * 3 h^2 / 8 */
static float *bend(const sheets *s)
{
    float *x = malloc(s->n * 3 * sizeof *x);
    memcpy(x, s->pos, s->n * 3 * sizeof *x);
    for (size_t v = 0; v < s->n; v++) x[3 * v + 2] -= (float)(3.0 * (x[3 * v] * x[3 * v] + x[3 * v + 1] * x[3 * v + 1]) + 0.01);
    return x;
}

/* triangle pairs of A x B that cross in x */
static size_t crossings(const sheets *s, const float *x)
{
    size_t count = 0;
    for (size_t f = 0; f < s->t_a; f++)
        for (size_t g = s->t_a; g < s->t; g++) {
            double a[3][3], b[3][3];
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++)
                    a[c][k] = x[3 * (size_t)s->tris[3 * f + c] + k], b[c][k] = x[3 * (size_t)s->tris[3 * g + c] + k];
            count += fp_contact_tri_tri(a, b) != 0;
        }
    return count;
}

static void test_close_sheets_stop_crossing(void **state)
{
    (void)state;
    sheets s = make(0.004);
    fp_sheet_bind b;
    assert_int_equal(fp_sheet_bind_build(s.pos, s.n, s.tris, s.t, &b), 0);
    assert_true(b.count > 100);
    /* each binding joins A and B, and no vertex both follows and leads */
    char *role = calloc(s.n, 1);
    for (size_t i = 0; i < b.count; i++) {
        bool in_a = b.follower[i] < s.n_a;
        for (int c = 0; c < 3; c++) {
            assert_int_equal(b.leader[i][c] < s.n_a, !in_a);
            role[b.leader[i][c]] |= 2;
        }
        role[b.follower[i]] |= 1;
        if (i) assert_true(b.follower[i] > b.follower[i - 1]); /* sorted, once each */
    }
    for (size_t v = 0; v < s.n; v++) assert_int_not_equal(role[v], 3);
    float *x = bend(&s);
    size_t before = crossings(&s, x);
    if (getenv("FP_TEST_VERBOSE")) printf("  %zu bound, %zu crossings before\n", b.count, before);
    assert_true(before > 0); /* the bend's piecewise-linear sheets cross without binding */
    size_t moved = fp_sheet_bind_apply(&b, s.pos, x, NULL, 0);
    assert_int_equal(moved, b.count); /* all within half the gap: all carried whole */
    assert_int_equal(crossings(&s, x), 0);
    /* each follower keeps its distance to its leader triangle's plane (a bend turns it) */
    for (size_t i = 0; i < b.count; i++) {
        const uint32_t *f = b.leader[i];
        double d0 = 0, d1 = 0, n[3], u[3], w[3];
        for (int pass = 0; pass < 2; pass++) {
            const float *p = pass ? x : s.pos;
            for (int k = 0; k < 3; k++)
                u[k] = p[3 * f[1] + k] - p[3 * f[0] + k], w[k] = p[3 * f[2] + k] - p[3 * f[0] + k];
            n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), d = 0;
            for (int k = 0; k < 3; k++) d += n[k] / l * (p[3 * (size_t)b.follower[i] + k] - p[3 * f[0] + k]);
            *(pass ? &d1 : &d0) = d;
        }
        assert_true(fabs(d1 - d0) < 1e-5);
    }
    free(x), free(role);
    fp_sheet_bind_free(&b);
    free(s.pos), free(s.tris);
}

static void test_one_sheet_or_far_sheets_bind_nothing(void **state)
{
    (void)state;
    double gaps[] = {NAN, 0.05};
    for (int g = 0; g < 2; g++) {
        sheets s = make(gaps[g]);
        fp_sheet_bind b;
        assert_int_equal(fp_sheet_bind_build(s.pos, s.n, s.tris, s.t, &b), 0);
        assert_int_equal(b.count, 0);
        fp_sheet_bind_free(&b);
        free(s.pos), free(s.tris);
    }
}

static void test_ranges_limit_the_followers(void **state)
{
    (void)state;
    sheets s = make(0.004);
    fp_sheet_bind b;
    assert_int_equal(fp_sheet_bind_build(s.pos, s.n, s.tris, s.t, &b), 0);
    float *x = bend(&s), *y = malloc(s.n * 3 * sizeof *y);
    memcpy(y, x, s.n * 3 * sizeof *y);
    uint32_t a_only[2] = {0, (uint32_t)s.n_a}, none[2] = {(uint32_t)s.n, 0};
    assert_int_equal(fp_sheet_bind_apply(&b, s.pos, y, none, 1), 0);
    assert_memory_equal(x, y, s.n * 3 * sizeof *y);
    size_t in_a = 0;
    for (size_t i = 0; i < b.count; i++) in_a += b.follower[i] < s.n_a;
    assert_int_equal(fp_sheet_bind_apply(&b, s.pos, y, a_only, 1), in_a);
    assert_memory_equal(x + 3 * s.n_a, y + 3 * s.n_a, (s.n - s.n_a) * 3 * sizeof *y); /* B untouched */
    /* a follower the map left where it was (outside every support) stays there */
    memcpy(y, x, s.n * 3 * sizeof *y);
    uint32_t v = b.follower[0];
    memcpy(y + 3 * (size_t)v, s.pos + 3 * (size_t)v, 3 * sizeof *y);
    assert_int_equal(fp_sheet_bind_apply(&b, s.pos, y, NULL, 0), b.count - 1);
    assert_memory_equal(y + 3 * (size_t)v, s.pos + 3 * (size_t)v, 3 * sizeof *y);
    free(x), free(y);
    fp_sheet_bind_free(&b);
    free(s.pos), free(s.tris);
}

/* v's signed distance to the plane of triangle f (vertices of x) */
static double above(const float *x, const uint32_t *f, uint32_t v)
{
    double e1[3], e2[3], n[3], d = 0, l = 0;
    for (int k = 0; k < 3; k++)
        e1[k] = (double)x[3 * (size_t)f[1] + k] - x[3 * (size_t)f[0] + k], e2[k] = (double)x[3 * (size_t)f[2] + k] - x[3 * (size_t)f[0] + k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    for (int k = 0; k < 3; k++) d += n[k] * ((double)x[3 * (size_t)v + k] - x[3 * (size_t)f[0] + k]), l += n[k] * n[k];
    return d / sqrt(l);
}

/* A tuck (Lee Perry-Smith's file has one by the ear: vertex 3250, 0.0001 from triangle 6295,
 * 0.4% of its mean edge, two of whose corners are its neighbours): a sliver (a, v, b) folded
 * flat under its neighbour T = (a, b, d) of the same sheet, v 1e-4 under T's centre. v is
 * within two rings of T, so it was never bound, and the bend (the map's interpolation error
 * on T, about 3 h^2 / 4 times the variance of its corners) put v 0.0066 through T. Bound
 * (within FP_SHEET_BIND_TUCK of its mean edge), v keeps its side. */
static void test_a_tuck_is_bound(void **state)
{
    (void)state;
    sheets s = make(NAN);
    /* T: the cell (12, 12)'s triangle a b d (add_grid's (a, b, d) split) */
    uint32_t a = 12 * 21 + 12, b = a + 1, d = a + 21 + 1, v = (uint32_t)s.n;
    uint32_t tri_t[3] = {a, b, d};
    float *p = s.pos + 3 * s.n++;
    for (int k = 0; k < 3; k++) p[k] = (s.pos[3 * a + k] + s.pos[3 * b + k] + s.pos[3 * d + k]) / 3.0f;
    p[2] -= 1e-4f;
    uint32_t *f = s.tris + 3 * s.t++;
    f[0] = a, f[1] = b, f[2] = v; /* the sliver, folded under T */
    assert_true(above(s.pos, tri_t, v) < 0);
    fp_sheet_bind bd;
    assert_int_equal(fp_sheet_bind_build(s.pos, s.n, s.tris, s.t, &bd), 0);
    assert_int_equal(bd.count, 1);
    assert_int_equal(bd.follower[0], v);
    uint32_t got[3] = {bd.leader[0][0], bd.leader[0][1], bd.leader[0][2]};
    for (int k = 0; k < 3; k++) assert_true(got[k] == a || got[k] == b || got[k] == d);
    assert_true(got[0] != got[1] && got[1] != got[2] && got[0] != got[2]);
    float *x = bend(&s);
    assert_true(above(x, tri_t, v) > 1e-3); /* the map alone: through T */
    assert_int_equal(fp_sheet_bind_apply(&bd, s.pos, x, NULL, 0), 1);
    assert_true(above(x, tri_t, v) < 0);
    assert_float_equal(above(x, tri_t, v), -1e-4, 2e-5);
    free(x);
    fp_sheet_bind_free(&bd);
    free(s.pos), free(s.tris);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_close_sheets_stop_crossing),
        cmocka_unit_test(test_one_sheet_or_far_sheets_bind_nothing),
        cmocka_unit_test(test_ranges_limit_the_followers),
        cmocka_unit_test(test_a_tuck_is_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
