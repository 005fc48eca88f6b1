/* test_stats.c: fp_median / fp_percentile (core/common/fp_stats.h) against their definitions
 * computed independently (counting ranks, no sort). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>

#include "fp_stats.h"

/* The k-th smallest (0-based) of v by counting: the value with < k smaller and >= k+1 <=. */
static double kth(const double *v, size_t n, size_t k)
{
    for (size_t i = 0; i < n; i++) {
        size_t lt = 0, le = 0;
        for (size_t j = 0; j < n; j++) {
            lt += v[j] < v[i];
            le += v[j] <= v[i];
        }
        if (lt <= k && k < le) return v[i];
    }
    return -1;
}

static void test_against_ranks(void **state)
{
    (void)state;
    srand(7);
    for (size_t n = 1; n < 60; n++) {
        double v[60], w[60];
        for (size_t i = 0; i < n; i++) v[i] = (double)(rand() % 20) - 5.5; /* with ties */
        for (size_t i = 0; i < n; i++) w[i] = v[i];
        double med = n % 2 ? kth(v, n, n / 2) : 0.5 * (kth(v, n, n / 2 - 1) + kth(v, n, n / 2));
        assert_true(fp_median(w, n) == med);
        for (size_t i = 1; i < n; i++) assert_true(w[i - 1] <= w[i]); /* sorted in place */
        for (size_t q = 1; q <= 4; q++) { /* q/4: exact in binary, so ceil(q n / 4) is too */
            size_t rank = (q * n + 3) / 4;
            assert_true(fp_percentile(w, n, (double)q / 4) == kth(v, n, rank - 1));
        }
    }
}

static void test_edges(void **state)
{
    (void)state;
    double v[100];
    for (int i = 0; i < 100; i++) v[i] = 100 - i;
    assert_true(fp_median(v, 100) == 50.5);
    assert_true(fp_percentile(v, 100, 0.99) == 99);
    assert_true(fp_percentile(v, 100, 1.0) == 100);
    assert_true(fp_percentile(v, 100, 0.0) == 1);
    assert_true(fp_median(NULL, 0) == 0 && fp_percentile(NULL, 0, 0.5) == 0);
    double one = 7;
    assert_true(fp_median(&one, 1) == 7 && fp_percentile(&one, 1, 0.99) == 7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_ranks),
        cmocka_unit_test(test_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
