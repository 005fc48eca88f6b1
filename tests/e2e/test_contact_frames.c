/* The contact guard in the session, every frame (issue 18: the incremental guard, fp_contact.h):
 * the three faces (with their rigs) x the four Leap joints recordings x both mappings,
 * replayed on the inputs' own clock (every sample at its time, as `facepuppet run`). At every
 * deforming frame the shape shown is checked against the frame's reference (the posed base,
 * posed here again with fp_rig_pose from the session's channel values) by the full check,
 * fp_contact_count_new (its own contact guard, no incremental state): no new crossing pair, no
 * newly flipped triangle. At the end, and at two snapshots, CGAL's exact counter against the
 * loaded face (fp_selfx_count_new_away, the input's own crossings and 1 ring around them
 * left out, as the session's guard). Prints what the guard cost per frame (collide_ms). */
#define _GNU_SOURCE
#include "fp_contact.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_session.h"
#include "fp_stats.h"
#include "fp_test_support.h"
#include "selfx.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

static const char *faces[] = {"ict-facekit/generic_neutral_mesh.obj",
                              "lee-perry-smith/LeePerrySmith.obj",
                              "mediapipe-canonical/canonical_face_model.obj"};
static const char *takes[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};

/* the frame's reference: the base posed by the rig at the session's channel values */
static void reference(fp_session *s, float *out)
{
    const fp_rig *rig = fp_session_rig(s);
    size_t n = fp_session_vertex_count(s);
    if (!rig) {
        memcpy(out, fp_session_base(s), n * 3 * sizeof(float));
        return;
    }
    float values[FP_RIG_MAX_CHANNELS];
    for (size_t i = 0; i < fp_rig_channel_count(rig); i++) {
        fp_rig_channel_desc d;
        assert_int_equal(fp_rig_channel_get(rig, i, &d), 0);
        values[i] = (float)fp_session_channel(s, d.name);
    }
    assert_int_equal(fp_rig_pose(rig, fp_session_base(s), values, out), 0);
}

static unsigned long total_frames, total_scaled;

static void run(const char *face, const char *take, const char *mapping)
{
    char mesh[4300], input[4400];
    snprintf(mesh, sizeof mesh, "%s/faces/%s", fp_test_data_dir(), face);
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/%s_joints_mm.csv,fast=1",
             fp_test_data_dir(), take);
    const char *dirs[] = {fp_test_plugin_dir()};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    fp_session_options so = {0};
    so.mesh_path = mesh;
    so.inputs[0] = input;
    so.input_count = 1;
    so.mapping = mapping;
    so.plugin_path = &path;
    so.input_clock = true;
    fp_session *s = fp_test_session_open(&so);
    const fp_mesh *m = fp_session_mesh(s);
    size_t n = fp_session_vertex_count(s), t = m->triangle_count;
    fp_contact *full;
    assert_int_equal(fp_contact_create(m->triangles, t, n, fp_session_loaded(s), &full), 0);
    assert_int_equal(fp_contact_dilate_own(full, 1), 0);
    float *ref = malloc(n * 3 * sizeof(float)), *snap[2] = {NULL, NULL};
    size_t cap = 8192, ncms = 0;
    double *cms = malloc(cap * sizeof *cms);
    int64_t t0 = fp_test_session_t0(s);
    unsigned long active = 0, scaled = 0;
    double least = 1;
    for (uint64_t k = 0; !fp_session_finished(s); k++) {
        int64_t now = fp_test_frame_time(s, t0, k, 60);
        reference(s, ref); /* the base as the frame starts (a commit changes it at its end) */
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        if (!st.active) continue;
        /* the rig's channels may change before the engine runs: pose with this frame's
         * values, unless the frame committed (its shape, guarded, became the new base) */
        if (!st.committed) reference(s, ref);
        active++;
        scaled += st.collide_t < 1;
        least = fmin(least, st.collide_kept);
        if (ncms < cap) cms[ncms++] = st.collide_ms;
        fp_contact_count info;
        long kk = fp_contact_count_new(full, ref, fp_session_positions(s), NULL, 0, &info);
        if (kk || info.flipped)
            fprintf(stderr, "%s %s %s frame %lu: %ld new pairs, %zu flipped\n", face, take, mapping,
                    (unsigned long)k, kk, info.flipped);
        assert_int_equal(kk, 0);
        assert_int_equal(info.flipped, 0);
        if ((active == 40 || active == 80) && !snap[active / 40 - 1]) {
            snap[active / 40 - 1] = malloc(n * 3 * sizeof(float));
            memcpy(snap[active / 40 - 1], fp_session_positions(s), n * 3 * sizeof(float));
        }
    }
    long cg = fp_selfx_count_new_away(fp_session_loaded(s), fp_session_positions(s), n,
                                      m->triangles, t, 1, NULL, 0, NULL, NULL);
    for (int i = 0; i < 2; i++)
        if (snap[i]) {
            cg += fp_selfx_count_new_away(fp_session_loaded(s), snap[i], n, m->triangles, t, 1,
                                          NULL, 0, NULL, NULL);
            free(snap[i]);
        }
    size_t moved = 0;
    for (size_t v = 0; v < n; v++)
        moved += memcmp(fp_session_positions(s) + 3 * v, fp_session_loaded(s) + 3 * v, 3 * sizeof(float)) != 0;
    printf("%-13.13s %-16s %-10s deforming %4lu, scaled back %3lu (least %3.0f%%); contact guard "
           "median %.4f ms p99 %.4f ms; moved %5.2f%%; CGAL new crossings %ld\n",
           face, take, mapping, active, scaled, 100 * least, fp_median(cms, ncms),
           fp_percentile(cms, ncms, 0.99), 100.0 * (double)moved / (double)n, cg);
    fflush(stdout);
    assert_int_equal(cg, 0);
    total_frames += active;
    total_scaled += scaled;
    free(cms);
    free(ref);
    fp_contact_destroy(&full);
    fp_session_destroy(&s);
    fp_plugin_path_clear(&path);
}

static void all(const char *mapping)
{
    for (size_t f = 0; f < sizeof faces / sizeof faces[0]; f++)
        for (size_t k = 0; k < sizeof takes / sizeof takes[0]; k++) run(faces[f], takes[k], mapping);
}

static void test_anchored(void **state)
{
    (void)state;
    all("anchored");
}

static void test_unanchored(void **state)
{
    (void)state;
    all("unanchored");
    printf("every deforming frame checked (%lu), %lu scaled back by the guard\n", total_frames, total_scaled);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_anchored),
        cmocka_unit_test(test_unanchored),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
