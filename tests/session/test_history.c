/* core/session/history: one undo level per gesture, a ring of FP_HISTORY_LEVELS, reset. */
#include "history.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

#define N 5

static void fill(float *v, float x)
{
    for (int i = 0; i < 3 * N; i++) v[i] = x + (float)i;
}

static void test_commit_and_undo(void **state)
{
    (void)state;
    float base[3 * N], loaded[3 * N], d[3 * N], want[3 * N];
    fill(loaded, 0);
    memcpy(base, loaded, sizeof base);
    fp_history h;
    fp_history_init(&h, N, base);
    assert_false(fp_history_undo(&h));
    /* one gesture, two commits: one level */
    fill(d, 1);
    fp_history_commit(&h, d);
    fill(d, 2);
    fp_history_commit(&h, d);
    assert_memory_equal(base, d, sizeof d);
    fp_history_end_gesture(&h);
    fill(d, 3);
    fp_history_commit(&h, d); /* a second gesture */
    assert_int_equal(h.count, 2);
    assert_true(fp_history_undo(&h));
    fill(want, 2);
    assert_memory_equal(base, want, sizeof want);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, loaded, sizeof loaded);
    assert_false(fp_history_undo(&h));
    /* reset is undoable when the base differed, and not otherwise */
    fill(d, 7);
    fp_history_commit(&h, d);
    fp_history_reset(&h, loaded);
    assert_memory_equal(base, loaded, sizeof loaded);
    assert_int_equal(h.count, 2);
    fp_history_reset(&h, loaded);
    assert_int_equal(h.count, 2);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, d, sizeof d);
    fp_history_free(&h);
}

/* More gestures than levels: the newest FP_HISTORY_LEVELS can be undone, in order. */
static void test_ring(void **state)
{
    (void)state;
    float base[3 * N], d[3 * N], want[3 * N];
    fill(base, 0);
    fp_history h;
    fp_history_init(&h, N, base);
    const int gestures = FP_HISTORY_LEVELS + 10;
    for (int g = 1; g <= gestures; g++) {
        fill(d, (float)g * 100);
        fp_history_commit(&h, d);
        fp_history_end_gesture(&h);
    }
    assert_int_equal(h.count, FP_HISTORY_LEVELS);
    for (int k = 1; k <= FP_HISTORY_LEVELS; k++) {
        assert_true(fp_history_undo(&h));
        fill(want, (float)(gestures - k) * 100);
        assert_memory_equal(base, want, sizeof want);
    }
    assert_false(fp_history_undo(&h));
    fp_history_free(&h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_commit_and_undo),
        cmocka_unit_test(test_ring),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
