/* More points of contact through the session (issue 12): anchored and unanchored with
 * points=tips+palm (11 per hand) and points=all (21 per hand) on the ICT face, driven by the
 * real two-hand three-claps recording, deform with more than 10 centres and add no
 * self-crossing: fp_selfx_count_new(the base before the frame, the shape shown) == 0 on
 * every deforming frame (tests/support/selfx: CGAL's exact triangle-triangle test), and the
 * final shape against the loaded face. The replay is paced in real time, so the frames are
 * kept and checked after the run (a check takes tens of milliseconds). */
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

#define MAX_KEPT 160 /* deforming frames kept for the check after the run (2 x 0.3 MB each) */

static void run(const char *mapping, size_t want_min_centres)
{
    char input[4300];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,speed=2",
             fp_test_data_dir());
    const char *inputs[] = {input};
    fp_session *s = fp_test_session_start(mapping, inputs, 1);
    const fp_mesh *mesh = fp_session_mesh(s);
    size_t n = fp_session_vertex_count(s);
    float *kept = malloc(MAX_KEPT * 2 * n * 3 * sizeof(float)); /* before, shown */
    assert_non_null(kept);
    unsigned long frames = 0, active = 0, commits = 0;
    size_t max_centres = 0, nkept = 0;
    int64_t deadline = fp_now_ns() + 120LL * 1000000000LL;
    while (!fp_session_finished(s) && fp_now_ns() < deadline) {
        float *before = kept + nkept * 2 * n * 3;
        if (nkept < MAX_KEPT) memcpy(before, fp_session_base(s), n * 3 * sizeof(float));
        fp_frame_stats st;
        fp_session_step(s, fp_now_ns(), &st);
        frames++;
        if (st.active) {
            active++;
            if (st.control_vectors > max_centres) max_centres = st.control_vectors;
            commits += st.committed;
            if (nkept < MAX_KEPT) {
                memcpy(before + n * 3, fp_session_positions(s), n * 3 * sizeof(float));
                nkept++;
            }
        }
        struct timespec ts = {0, 2000000};
        nanosleep(&ts, NULL);
    }
    assert_true(fp_session_finished(s));
    long new_pairs = 0;
    for (size_t i = 0; i < nkept; i++) {
        const float *before = kept + i * 2 * n * 3;
        long k = fp_selfx_count_new(before, before + n * 3, n, mesh->triangles,
                                    mesh->triangle_count, NULL, 0, NULL);
        assert_true(k >= 0);
        new_pairs += k;
    }
    long total = fp_selfx_count_new(fp_session_loaded(s), fp_session_positions(s), n,
                                    mesh->triangles, mesh->triangle_count, NULL, 0, NULL);
    double max_disp = 0;
    for (size_t v = 0; v < n; v++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) d2 += pow(fp_session_positions(s)[3 * v + k] - fp_session_loaded(s)[3 * v + k], 2);
        if (d2 > max_disp * max_disp) max_disp = sqrt(d2);
    }
    printf("%s: %lu frames, %lu deforming, %lu commits, up to %zu centres; %zu frames checked: "
           "%ld new crossings; final shape vs loaded: %ld new crossings, max displacement %.4g\n",
           mapping, frames, active, commits, max_centres, nkept, new_pairs, total, max_disp);
    assert_true(active > 0);
    assert_true(max_centres >= want_min_centres);
    assert_true(max_disp > 0);
    assert_int_equal(new_pairs, 0);
    assert_int_equal(total, 0);
    free(kept);
    fp_session_destroy(&s);
}

static void test_anchored_tips_palm(void **state)
{
    (void)state;
    run("anchored,points=tips+palm", 11);
}
static void test_anchored_all(void **state)
{
    (void)state;
    run("anchored,points=all", 21);
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
