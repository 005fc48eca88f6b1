/* core/session/skin_reach: the reach against what a rig allowed. Four points on a line; three
 * vectors each ask 1 unit up from a point whose mobility is 0 (the skull), 0.5 (the blend's
 * ramp) and 1 (soft skin), and the shown shape moves each point as the mobility blend would
 * (0, 0.5, 1). The reach is what moved over what was asked (0, 0.5, 1); against what the rig
 * allowed, the ramp's point followed all it was let (1) and the skull's is counted as held,
 * not as skin that failed; the gesture's line says so. Without the mobility (NULL) the rig's
 * reach is the clamp's alone (0, 0.5, 1, none held). */
#include "log_capture.h"
#include "skin_reach.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

static const float ref[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
static const float shown[4][3] = {{0, 0, 0}, {1, 0.5f, 0}, {2, 1, 0}, {3, 0, 0}};
static const float mobility[4] = {0.f, 0.5f, 1.f, 1.f};

static void control_set(fp_control_set *cs, float (*start)[3], float (*end)[3], size_t n)
{
    memset(cs, 0, sizeof *cs);
    cs->size = sizeof *cs;
    cs->active = true;
    cs->radius = 1.0;
    cs->capacity = cs->count = n;
    cs->start = start;
    cs->end = end;
    for (size_t i = 0; i < n; i++) {
        memcpy(start[i], ref[i], sizeof start[i]);
        memcpy(end[i], ref[i], sizeof end[i]);
        end[i][1] += 1.f;
    }
}

/* The four points indexed (*pts, destroy it) and one frame of n of the vectors above, with the
 * mobility, into st, g and ga. */
static void first_frame(csrbf_points **pts, size_t n, fp_frame_stats *st, fp_skin_reach_gesture *g,
                        fp_skin_reach_gesture *ga)
{
    assert_int_equal(csrbf_points_create(4, &ref[0][0], pts), 0);
    float start[3][3], end[3][3];
    fp_control_set cs;
    control_set(&cs, start, end, n);
    memset(st, 0, sizeof *st);
    fp_skin_reach_frame(*pts, &ref[0][0], &shown[0][0], &cs, &cs, mobility, st, g, ga);
}

static void test_held_by_the_rig(void **state)
{
    (void)state;
    csrbf_points *pts = NULL;
    assert_int_equal(csrbf_points_create(4, &ref[0][0], &pts), 0);
    float start[3][3], end[3][3];
    fp_control_set cs;
    control_set(&cs, start, end, 3);
    fp_frame_stats st;
    fp_skin_reach_gesture g = {0}, ga = {0};
    memset(&st, 0, sizeof st);
    fp_skin_reach_frame(pts, &ref[0][0], &shown[0][0], &cs, &cs, mobility, &st, &g, &ga);
    assert_int_equal(st.reach_vectors, 3);
    assert_float_equal(st.reach[0], 0.0, 1e-6);
    assert_float_equal(st.reach[1], 0.5, 1e-6);
    assert_float_equal(st.reach[2], 1.0, 1e-6);
    assert_int_equal(st.reach_allowed_vectors, 2); /* the ramp's and the skin's */
    assert_float_equal(st.reach_allowed[0], 1.0, 1e-6);
    assert_float_equal(st.reach_allowed[1], 1.0, 1e-6);
    assert_int_equal(st.reach_held, 1);
    assert_int_equal(g.vectors, 3);
    assert_int_equal(ga.vectors, 2);
    assert_int_equal(ga.held, 1);
    log_capture cap = {0};
    fp_slog log = {.fn = capture_log, .user = &cap};
    fp_skin_reach_gesture_end(&g, &ga, 10.0, &log);
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.lines[0], "the skin followed the fingertips 50% this gesture"));
    assert_non_null(strstr(cap.lines[0], "; 100% of what the rig allowed: it holds back a push toward the skull or the jaw; "
                                         "1 of them grabbed the skull or the jaw, which the rig keeps still)"));
    assert_int_equal(g.vectors + ga.vectors + ga.held, 0); /* reset */

    /* without the mobility: the clamp's allowance alone, nothing held */
    memset(&st, 0, sizeof st);
    fp_skin_reach_frame(pts, &ref[0][0], &shown[0][0], &cs, &cs, NULL, &st, &g, &ga);
    assert_int_equal(st.reach_allowed_vectors, 3);
    assert_float_equal(st.reach_allowed[0], 0.0, 1e-6);
    assert_int_equal(st.reach_held, 0);
    fp_skin_reach_gesture_reset(&g);
    fp_skin_reach_gesture_reset(&ga);

    /* the skull alone grabbed: no reach against the rig, the line says why */
    fp_control_set one;
    float s1[1][3], e1[1][3];
    control_set(&one, s1, e1, 1);
    memset(&st, 0, sizeof st);
    fp_skin_reach_frame(pts, &ref[0][0], &shown[0][0], &one, &one, mobility, &st, &g, &ga);
    assert_int_equal(st.reach_vectors, 1);
    assert_int_equal(st.reach_allowed_vectors, 0);
    assert_int_equal(st.reach_held, 1);
    cap.count = 0;
    fp_skin_reach_gesture_end(&g, &ga, 10.0, &log);
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.lines[0], "0% this gesture"));
    assert_non_null(strstr(cap.lines[0], "; they grabbed the skull or the jaw, which the rig keeps still)"));
    assert_null(strstr(cap.lines[0], "of what the rig allowed"));
    csrbf_points_destroy(&pts);
}

/* A take played with a rig (play, export): its vectors are the rig's cut already, so the
 * gesture's line gives the reach against what the rig allowed and says so, never "followed the
 * fingertips" (it said 100% where the performer's fingertips were held back) */
static void test_played_take(void **state)
{
    (void)state;
    csrbf_points *pts = NULL;
    fp_frame_stats st;
    fp_skin_reach_gesture g = {.played = true}, ga = {0};
    first_frame(&pts, 3, &st, &g, &ga);
    log_capture cap = {0};
    fp_slog log = {.fn = capture_log, .user = &cap};
    fp_skin_reach_gesture_end(&g, &ga, 10.0, &log);
    assert_int_equal(cap.count, 1);
    printf("%s\n", cap.lines[0]);
    assert_null(strstr(cap.lines[0], "followed the fingertips"));
    assert_non_null(strstr(cap.lines[0], "the skin followed 100% of what the rig allowed this gesture (mean of 2; "
                                         "least 100%, under 90% in 0; longest drag 10.0 mm; the take holds the "
                                         "rig's vectors, not how far the fingertips asked; 1 more grabbed the "
                                         "skull or the jaw, which the rig keeps still)"));
    assert_false(g.played); /* (reset with the gesture: the session sets it each played frame) */
    /* the skull alone grabbed */
    fp_control_set one;
    float s1[1][3], e1[1][3];
    control_set(&one, s1, e1, 1);
    memset(&st, 0, sizeof st);
    g.played = true;
    fp_skin_reach_frame(pts, &ref[0][0], &shown[0][0], &one, &one, mobility, &st, &g, &ga);
    cap.count = 0;
    fp_skin_reach_gesture_end(&g, &ga, 10.0, &log);
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.lines[0], "the fingertips grabbed the skull or the jaw this gesture, which the rig "
                                         "keeps still (1 vector)"));
    csrbf_points_destroy(&pts);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_held_by_the_rig), cmocka_unit_test(test_played_take)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
