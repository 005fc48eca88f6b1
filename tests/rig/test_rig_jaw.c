/* The jaw pose alone on the ICT face (issue 11): at jaw.open 0, 0.25, 0.5, 0.75 and 1 it adds no
 * self-crossing (CGAL, fp_selfx, away from the face's own crossings as the session tests count
 * them) and folds no part of the surface; the skull stays bit for bit; the lower teeth move
 * rigidly (residual of the best rigid fit, Horn's method) and turn by jaw.open times the rig's
 * angle about an axis along the hinge; the weights follow anatomy at the landmarks (upper lip
 * still, lower lip and chin fully, mouth corners about half); after fp_rig_unfold_jaw no
 * triangle is turned over (its normal past 90 degrees), where the weights as the falloff
 * gives them turned some. */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_rig.h"
#include "rig_check.h"
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

#define LOWER_TEETH_FIRST 19247 /* ../shared/data/faces/ict-facekit/README.md */
#define LOWER_TEETH_LAST 21450

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void test_ict_jaw_pose(void **state)
{
    (void)state;
    const char *dd = getenv("FP_SHARED_DATA");
    char path[4096], rig_path[4096], err[1024];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj", dd && *dd ? dd : "../shared/data");
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    size_t n = m->vertex_count;
    assert_int_equal(fp_rig_find(FP_TEST_RIGS_DIR, n, m->positions, rig_path, sizeof rig_path, err, sizeof err), 0);
    fp_rig *r = NULL;
    int rc = fp_rig_load_for_mesh(rig_path, n, m->positions, &r, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_string_equal(fp_rig_name(r), "ict-facekit");
    float *out = malloc(n * 3 * sizeof *out), vals[FP_RIG_MAX_CHANNELS];
    /* the jaw's weights as the falloff gives them turn triangles over (normals past 90
     * degrees: 4 gum triangles at jaw.open 0.6, 20 at 1); fp_rig_unfold_jaw evens the weights
     * of those triangles (checked below at every opening: none turned) */
    long raw_turned = 0;
    fp_rig_channel_values(r, NULL, NULL, 0, vals);
    vals[fp_rig_channel_index(r, "jaw.open")] = 1;
    assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
    rig_check_folds(m->positions, out, m->triangles, m->triangle_count, &raw_turned);
    size_t changed = 0;
    assert_int_equal(fp_rig_unfold_jaw(r, m->positions, m->triangles, m->triangle_count, &changed), 0);
    printf("jaw.open 1 before fp_rig_unfold_jaw: %ld triangles turned over; %zu soft vertices' "
           "weights evened\n", raw_turned, changed);
    assert_true(raw_turned > 0);
    assert_true(changed > 0 && changed < 200);
    /* the weights at the landmarks */
    const float *w = fp_rig_jaw_weights(r);
    const char *fixed0[] = {"upper_lip", "nose_tip", "upper_lip_inner"}, *fixed1[] = {"lower_lip", "chin", "lower_lip_inner"};
    for (int i = 0; i < 3; i++) {
        float w0 = w[fp_rig_landmark_index(r, fixed0[i])], w1 = w[fp_rig_landmark_index(r, fixed1[i])];
        printf("w(%s) = %.3f, w(%s) = %.3f\n", fixed0[i], w0, fixed1[i], w1);
        if (i < 2) { /* the upper lip and the nose stay, the lower lip and the chin follow the jaw */
            assert_true(w0 == 0 && w1 == 1);
        } else { /* the lips' contact: the upper barely moves, the lower nearly fully */
            assert_true(w0 < 0.1 && w1 > 0.9);
        }
    }
    for (int s = 0; s < 2; s++) {
        const char *c = s ? "mouth_corner_left" : "mouth_corner_right";
        printf("w(%s) = %.3f\n", c, w[fp_rig_landmark_index(r, c)]);
        assert_true(fabs(w[fp_rig_landmark_index(r, c)] - 0.5) < 0.1);
    }
    float hr[3], hl[3];
    double open_deg, glide[2];
    fp_rig_hinge(r, hr, hl, &open_deg, glide);
    double ax[3] = {hl[0] - hr[0], hl[1] - hr[1], hl[2] - hr[2]}, al = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    uint8_t *teeth = calloc(n, 1);
    for (size_t v = LOWER_TEETH_FIRST; v <= LOWER_TEETH_LAST; v++) teeth[v] = 1;
    const uint8_t *kind = fp_rig_vertex_kinds(r);
    /* 0.6 and 0.65: either side of the ICT rig's glide_start (0.602), where the condyles
     * begin to slide; the others between the eighths fp_rig_unfold_jaw samples */
    static const float opens[] = {0, 0.1f, 0.25f, 0.3f, 0.45f, 0.5f, 0.6f, 0.65f, 0.7f, 0.75f, 0.9f, 1};
    for (size_t k = 0; k < sizeof opens / sizeof opens[0]; k++) {
        fp_rig_channel_values(r, NULL, NULL, 0, vals);
        vals[fp_rig_channel_index(r, "jaw.open")] = opens[k];
        assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
        for (size_t v = 0; v < n; v++)
            if (kind[v] == FP_RIG_SKULL && memcmp(&out[3 * v], &m->positions[3 * v], 12)) fail_msg("skull vertex %zu moved", v);
        double t0 = now_s();
        long own = 0, near = 0, raw;
        long x = fp_selfx_count_new_away(m->positions, out, n, m->triangles, m->triangle_count, 0, NULL, 0, &own, &near);
        double t1 = now_s();
        raw = fp_selfx_count_new(m->positions, out, n, m->triangles, m->triangle_count, NULL, 0, NULL);
        long turned = 0, folds = rig_check_folds(m->positions, out, m->triangles, m->triangle_count, &turned);
        double resid = 0, disp = 0, angle = 0, axis[3] = {0};
        rig_check_rigid_fit(m->positions, out, teeth, n, &resid, &disp, &angle, axis);
        double along = fabs(axis[0] * ax[0] + axis[1] * ax[1] + axis[2] * ax[2]) / al;
        printf("jaw.open %.2f: new crossings %ld (%ld more next to the face's own %ld; all new pairs %ld; CGAL "
               "%.2f s); folds %ld (normals turned past 90 degrees: %ld); lower teeth turned %.3f degrees "
               "(rig %.3f) about an axis %.3f degrees off the hinge, rigid-fit residual %.5f%% of %.3f cm\n",
               opens[k], x, near, own, raw, t1 - t0, folds, turned, angle, opens[k] * open_deg,
               acos(fmin(1, along)) * 180 / M_PI, disp > 0 ? 100 * resid / disp : 0.0, disp);
        assert_int_equal(x, 0);
        assert_int_equal(folds, 0);
        assert_int_equal(turned, 0);
        assert_true(fabs(angle - opens[k] * open_deg) < 0.5);
        if (opens[k] > 0) {
            assert_true(resid < 0.01 * disp);
            assert_true(along > cos(M_PI / 180));
        } else {
            assert_memory_equal(out, m->positions, n * 3 * sizeof *out);
        }
    }
    /* the arc (rigs/README.md, Posselt's envelope): the incisal opening (the upper central
     * incisors' lowest point minus the lower ones' highest, within 4 mm of the midline, cm) is
     * 22.5 mm at the last opening of pure rotation and 40 mm at jaw.open = 1 */
    long le = -1, ue = -1;
    for (size_t v = 17039; v <= LOWER_TEETH_LAST; v++) {
        const float *p = &m->positions[3 * v];
        if (fabsf(p[0]) >= 0.4f) continue;
        if (v >= LOWER_TEETH_FIRST) { if (le < 0 || p[1] > m->positions[3 * le + 1]) le = (long)v; }
        else if (ue < 0 || p[1] < m->positions[3 * ue + 1]) ue = (long)v;
    }
    assert_true(le >= 0 && ue >= 0);
    double start = 0;
    for (int i = 1; i <= 100; i++)
        if (fp_rig_glide_fraction(r, i / 100.0) == 0) start = i / 100.0;
    assert_true(start > 0.3 && start < 0.9 && fp_rig_glide_fraction(r, 1) == 1);
    static const double want_mm[2] = {22.5, 40.0};
    for (int k = 0; k < 2; k++) {
        fp_rig_channel_values(r, NULL, NULL, 0, vals);
        vals[fp_rig_channel_index(r, "jaw.open")] = k ? 1.0f : (float)start;
        assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
        double mm = 10 * (m->positions[3 * ue + 1] - out[3 * le + 1]);
        printf("incisal opening at jaw.open %.2f: %.1f mm (anatomy: %.1f)\n", k ? 1.0 : start, mm, want_mm[k]);
        assert_true(fabs(mm - want_mm[k]) < (k ? 0.5 : 1.0));
    }
    free(out), free(teeth);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_ict_jaw_pose)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
