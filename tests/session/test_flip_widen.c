/* core/session/step_contact: fp_cg_next_widen, the widening of a gesture the contact guard
 * held back for flipped triangles alone: 1.5x at the first such frame, 2.25x at the next,
 * no further; crossings, whole frames and inactive frames leave it as it was. And
 * fp_cg_end_gesture's line, which names what held the skin back: crossings, triangles turning
 * over, or both with their frames (the demo's six scaled-back frames were all of the second
 * kind and were said as the first). */
#include "step_contact.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
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

static char g_line[1024];
static int g_lines;

static void on_log(void *user, int level, const char *source, const char *message)
{
    (void)user;
    assert_int_equal(level, FP_LOG_WARNING);
    assert_string_equal(source, FP_SLOG_CONTACT);
    snprintf(g_line, sizeof g_line, "%s", message);
    g_lines++;
}

/* the line after a gesture of `frames` checked frames, `limited` scaled back, `turned` of
 * them for flips alone; NULL when none was said */
static const char *gesture_line_at(unsigned long frames, unsigned long limited, unsigned long turned, double least)
{
    fp_cg_step g;
    memset(&g, 0, sizeof g);
    g.sync = FP_CG_SYNCED;
    g.frames = frames, g.limited = limited, g.turned = turned, g.t_least = least;
    fp_slog log = {.fn = on_log};
    g_lines = 0;
    fp_cg_end_gesture(&g, &log);
    assert_true(g.frames == 0 && g.limited == 0 && g.turned == 0); /* the next gesture's afresh */
    return g_lines ? g_line : NULL;
}

static const char *gesture_line(unsigned long frames, unsigned long limited, unsigned long turned)
{
    return gesture_line_at(frames, limited, turned, 0.25);
}

static void test_gesture_line_names_the_rule(void **state)
{
    (void)state;
    assert_null(gesture_line(10, 0, 0));
    const char *l = gesture_line(10, 4, 0);
    assert_non_null(strstr(l, "stopped the surface from passing through itself: 4 of 10 frames scaled back"));
    assert_null(strstr(l, "folding"));
    l = gesture_line(10, 4, 4);
    assert_non_null(strstr(l, "stopped the skin from folding over"));
    assert_non_null(strstr(l, ": 4 of 10 frames scaled back (least share of a frame's motion kept 25%)"));
    assert_null(strstr(l, "passing through"));
    l = gesture_line(10, 4, 1);
    assert_non_null(strstr(l, "passing through itself (3 frames) and the skin from folding over (1): 4 of 10"));
    /* a frame held back by a hair is not said as 100% kept (as the HUD's line) */
    l = gesture_line_at(10, 1, 0, 0.9996);
    assert_non_null(strstr(l, "(least share of a frame's motion kept over 99%)"));
    l = gesture_line_at(10, 1, 0, 0.994);
    assert_non_null(strstr(l, "(least share of a frame's motion kept 99%)"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_widen_for_flips_alone),
        cmocka_unit_test(test_gesture_line_names_the_rule),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
