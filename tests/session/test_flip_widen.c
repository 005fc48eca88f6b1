/* core/session/step_contact: fp_cg_next_widen, the widening of a gesture the contact guard
 * held back for flipped triangles alone: 1.5x at the first such frame, 2.25x at the next,
 * no further; crossings, whole frames and inactive frames leave it as it was. */
#include "step_contact.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

static fp_frame_stats frame(bool active, double t, long pairs)
{
    fp_frame_stats st;
    memset(&st, 0, sizeof st);
    st.active = active;
    st.collide_t = t;
    st.collide_pairs = pairs;
    return st;
}

static void test_widen_for_flips_alone(void **state)
{
    (void)state;
    fp_frame_stats flips = frame(true, 0.4, 0), cross = frame(true, 0.4, 3), whole = frame(true, 1.0, 0),
                   idle = frame(false, 0.4, 0);
    assert_true(fp_cg_next_widen(0.0, &whole) == 1.0);
    assert_true(fp_cg_next_widen(1.0, &cross) == 1.0);
    assert_true(fp_cg_next_widen(1.0, &idle) == 1.0);
    double w = fp_cg_next_widen(1.0, &flips);
    assert_true(w == FP_FLIP_WIDEN);
    assert_true(fp_cg_next_widen(w, &whole) == w); /* kept for the gesture */
    assert_true(fp_cg_next_widen(w, &cross) == w);
    w = fp_cg_next_widen(w, &flips);
    assert_true(w == FP_FLIP_WIDEN * FP_FLIP_WIDEN);
    assert_true(fp_cg_next_widen(w, &flips) == FP_FLIP_WIDEN_MAX);
    assert_true(FP_FLIP_WIDEN_MAX == FP_FLIP_WIDEN * FP_FLIP_WIDEN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_widen_for_flips_alone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
