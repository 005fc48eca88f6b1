/* More points of contact through the session (issue 12): anchored and unanchored with
 * points=tips+palm (11 per hand) and points=all (21 per hand) on the ICT face, driven by the
 * real two-hand three-claps recording, deform with more than 10 centres (anchored: the points
 * touching the skin, which grab it; one at a time in this recording) and add no
 * self-crossing: fp_selfx_count_new_away(the base before the frame, the shape shown) == 0 on
 * every tenth deforming frame (tests/support/selfx: CGAL's exact triangle-triangle test),
 * and the final shape against the loaded face. As in tests/e2e/test_guard, a pair with a
 * triangle that crosses another in the input (the ICT face's eyes and mouth interior
 * interpenetrate) is left out and counted beside: their intersection curves move under any
 * deformation that reaches them, as a long drag's widened support does. The session steps on the recording's own
 * clock (frame k at t0 + k / 60 s, as `facepuppet run`), so the run is deterministic and
 * the checks' time loses no frame. */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_session.h"
#include "fp_test_support.h"
#include "selfx.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>

#define FPS 60
#define SELFX_EVERY 10 /* selfx on every tenth deforming frame (up to a second each on a loaded machine) */

static void run(const char *mapping, size_t want_min_centres)
{
    char input[4300], err[2048];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv",
             fp_test_data_dir());
    fp_session_options so;
    fp_test_face_options(&so, mapping, NULL);
    so.inputs[0] = input;
    so.input_count = 1;
    so.input_clock = true; /* deterministic: frame k at t0 + k / FPS, as `facepuppet run` */
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(fp_session_start(s, err, sizeof err), 0);
    const fp_mesh *mesh = fp_session_mesh(s);
    size_t n = fp_session_vertex_count(s);
    float *before = malloc(n * 3 * sizeof(float));
    assert_non_null(before);
    unsigned long frames = 0, active = 0, commits = 0, checks = 0;
    size_t max_centres = 0;
    long new_pairs = 0, near_own = 0, near_total = 0;
    int64_t t0 = fp_test_session_t0(s), limit = fp_now_ns() + 900LL * 1000000000LL;
    for (uint64_t k = 0; !fp_session_finished(s) && fp_now_ns() < limit; k++) {
        int64_t now = fp_test_frame_time(s, t0, k, FPS);
        memcpy(before, fp_session_base(s), n * 3 * sizeof(float));
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        frames++;
        if (!st.active) continue;
        if (st.control_vectors > max_centres) max_centres = st.control_vectors;
        commits += st.committed;
        if (active++ % SELFX_EVERY == 0) {
            long nn = 0;
            long x = fp_selfx_count_new_away(before, fp_session_positions(s), n, mesh->triangles,
                                             mesh->triangle_count, 0, NULL, 0, NULL, &nn);
            assert_true(x >= 0);
            near_own += nn;
            new_pairs += x;
            checks++;
        }
    }
    if (!fp_session_finished(s)) fail_msg("%s: not finished after %lu frames", mapping, frames);
    long total = fp_selfx_count_new_away(fp_session_loaded(s), fp_session_positions(s), n,
                                         mesh->triangles, mesh->triangle_count, 0, NULL, 0, NULL,
                                         &near_total);
    double max_disp = 0;
    for (size_t v = 0; v < n; v++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) d2 += pow(fp_session_positions(s)[3 * v + k] - fp_session_loaded(s)[3 * v + k], 2);
        if (d2 > max_disp * max_disp) max_disp = sqrt(d2);
    }
    printf("%s: %lu frames, %lu deforming, %lu commits, up to %zu centres; %lu frames checked: "
           "%ld new crossings (+%ld next to the input's own); final shape vs loaded: %ld new crossings "
           "(+%ld next to the input's own), max displacement %.4g\n",
           mapping, frames, active, commits, max_centres, checks, new_pairs, near_own, total, near_total,
           max_disp);
    assert_true(active > 0);
    assert_true(max_centres >= want_min_centres);
    assert_true(max_disp > 0);
    assert_int_equal(new_pairs, 0);
    assert_int_equal(total, 0);
    free(before);
    fp_session_destroy(&s);
}

static void test_anchored_tips_palm(void **state)
{
    (void)state;
    /* anchored grabs only the points touching the skin (within engage x R): in three-claps
     * one point at a time touches the ICT face (the palm and knuckles stay off it) */
    run("anchored,points=tips+palm", 1);
}
static void test_anchored_all(void **state)
{
    (void)state;
    run("anchored,points=all", 1);
}
static void test_unanchored_tips_palm(void **state)
{
    (void)state;
    run("unanchored,points=tips+palm", 11);
}
static void test_unanchored_all(void **state)
{
    (void)state;
    run("unanchored,points=all", 21);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_anchored_tips_palm), cmocka_unit_test(test_anchored_all),
        cmocka_unit_test(test_unanchored_tips_palm), cmocka_unit_test(test_unanchored_all),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
