/* Tests of the exact self-intersection counter on constructed cases: two crossing triangles,
 * a clean tetrahedron, a strip folded through itself, touching neighbours and OBJ-style
 * seams (duplicated vertices) that are adjacency, not crossings. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "selfx.h"

static void test_two_crossing(void **state)
{
    (void)state;
    /* a triangle in z = 0 pierced by a vertical one */
    const float p[18] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0.5f, 0.5f, -1, 0.5f, 0.5f, 1, 1.5f, 0.2f, 0};
    const uint32_t t[6] = {0, 1, 2, 3, 4, 5};
    assert_int_equal(fp_selfx_count(p, 6, t, 2), 1);
    /* moved away: none */
    float q[18];
    memcpy(q, p, sizeof q);
    for (int v = 3; v < 6; v++) q[3 * v] += 5.0f;
    assert_int_equal(fp_selfx_count(q, 6, t, 2), 0);
    /* the diff: crossing in p, not in q */
    long own = -1;
    uint32_t pairs[2];
    assert_int_equal(fp_selfx_count_new(q, p, 6, t, 2, pairs, 1, &own), 1);
    assert_int_equal(own, 0);
    assert_int_equal(pairs[0], 0);
    assert_int_equal(pairs[1], 1);
    assert_int_equal(fp_selfx_count_new(p, p, 6, t, 2, NULL, 0, &own), 0);
    assert_int_equal(own, 1);
}

static void test_tetrahedron(void **state)
{
    (void)state;
    const float p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const uint32_t t[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    assert_int_equal(fp_selfx_count(p, 4, t, 4), 0);
    /* the same with every face on its own vertices (a triangle soup, welded by position) */
    float q[36];
    uint32_t u[12];
    for (int k = 0; k < 12; k++) {
        memcpy(q + 3 * k, p + 3 * t[k], 3 * sizeof(float));
        u[k] = (uint32_t)k;
    }
    assert_int_equal(fp_selfx_count(q, 12, u, 4), 0);
    /* bad index */
    const uint32_t bad[3] = {0, 1, 9};
    assert_int_equal(fp_selfx_count(p, 4, bad, 1), -EINVAL);
    assert_int_equal(fp_selfx_count(NULL, 4, t, 4), -EINVAL);
}

/* A strip of 2 x 20 quads along x in z = 0; the far half folded back over the near half,
 * tilted so that it passes through it. */
static void test_folded_strip(void **state)
{
    (void)state;
    enum { NX = 21, NV = 2 * NX, NT = 2 * (NX - 1) };
    float flat[3 * NV], fold[3 * NV];
    uint32_t t[3 * NT];
    for (int i = 0; i < NX; i++)
        for (int j = 0; j < 2; j++) {
            float *f = flat + 3 * (2 * i + j), *g = fold + 3 * (2 * i + j);
            double x = 10.0 * i / (NX - 1);
            f[0] = (float)x;
            f[1] = (float)j;
            f[2] = 0.0f;
            g[0] = (float)(x <= 5 ? x : 10 - x);
            g[1] = (float)j;
            g[2] = (float)(x <= 5 ? 0.0 : (x - 5) * 0.2 - 0.6); /* crosses z = 0 at x = 8 */
        }
    for (int i = 0; i < NX - 1; i++) {
        uint32_t a = 2 * i, b = 2 * i + 1, c = 2 * i + 2, d = 2 * i + 3;
        uint32_t *q = t + 6 * i;
        q[0] = a, q[1] = c, q[2] = b, q[3] = b, q[4] = c, q[5] = d;
    }
    assert_int_equal(fp_selfx_count(flat, NV, t, NT), 0);
    long n = fp_selfx_count(fold, NV, t, NT);
    assert_true(n > 0);
    long own = -1;
    assert_int_equal(fp_selfx_count_new(flat, fold, NV, t, NT, NULL, 0, &own), n);
    assert_int_equal(own, 0);
    /* a fold that only bends (no pass-through: the far half above the near one) crosses
     * nothing, although every triangle of the far half overlaps the near one in x, y */
    for (int i = 0; i < NX; i++)
        for (int j = 0; j < 2; j++) {
            double x = 10.0 * i / (NX - 1);
            if (x > 5) fold[3 * (2 * i + j) + 2] = (float)(0.1 + (x - 5) * 0.1);
        }
    assert_int_equal(fp_selfx_count(fold, NV, t, NT), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_crossing),
        cmocka_unit_test(test_tetrahedron),
        cmocka_unit_test(test_folded_strip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
