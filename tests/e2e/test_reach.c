/* Reach: how far the skin follows the fingertips (issue 51), measured as a performer sees it.
 *
 * The three faces x the four Leap joints recordings, anchored, no rig, every frame at 30 fps
 * on the recordings' clock (replay fast=1, as `facepuppet run --fps 30 --rig none` steps). For
 * each active frame and each control vector whose start point lies within 0.5 R of the
 * gesture's base (a touching fingertip), the base vertex nearest that start point is the
 * grabbed skin; its reach is how far it moved (frame - base) over how far the fingertip asked
 * (|end - start|). Vectors that ask for less than 1e-4 R are left out (a resting finger
 * asks nothing). Asserted: the median over every run's vectors is at least 0.90 (issue 51's
 * first figure; measured 1.00) and every run's 10th percentile at least 0.60 (the issue's
 * second; the worst measured 0.62, Lee Perry-Smith's grab, where the contact guard holds
 * two sheets of skin under a millimetre apart by the eye). Printed: the table, each run's 10th percentile (FP_TEST_VERBOSE adds the
 * log). Experiments: FP_REACH_NO_CONTACT=1 (no contact guard), FP_REACH_MAPPING=SPEC (e.g.
 * anchored,widen=0.75), FP_REACH_RADIUS=R (mesh units), FP_REACH_SAVE=FILE.obj (the frame of the largest ask), FP_REACH_RIG=1 (each face's
 * own rig instead of none: its finger limit near bone cuts a drag's push toward the bone,
 * run medians 32-100%, docs/performance.md "The rig cuts the push only").
 *
 * Set FP_REACH_ONLY=FACE/RECORDING substrings to run one pair (e.g. "ict/grab"), and
 * FP_REACH_HANDS=DIR (every *_joints_mm.csv, *.json.lz or *.json in it) or one such file to run
 * other hands instead of the four (fp_test_recordings_from: transformed copies,
 * tools/hands-variants, leapjs-playback's other originals, or a recording of your own; in the
 * recordings' CSV format, docs/devices.md, or a Leap playback original). Forensics: FP_TEST_VERBOSE
 * lists the frames the contact guard scaled back, FP_REACH_SAVE_FRAME=K saves frame K (to
 * FP_REACH_SAVE) instead of the largest ask's, FP_REACH_PAIRS=1 prints the start and end
 * distances of the vectors within 2 R of each other in each frame the fold-over guard
 * limited (fingertips converging, or pulling apart skin they grabbed close together), and
 * FP_REACH_DUMP=1 each touching vector's asked and moved millimetres, every frame.
 * FP_REACH_KEYS=",key=value..." is appended to each replay SPEC (e.g. ",workspace=0": the
 * hands placed as a live tracker's, docs/performance.md "Live, replay and the replay placed
 * as live"). */
#define _GNU_SOURCE
#include "fp_session.h"
#include "fp_stats.h"
#include "fp_test_support.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

static void on_log(void *user, int level, const char *source, const char *message)
{
    (void)user;
    (void)level;
    if (getenv("FP_TEST_VERBOSE")) fprintf(stderr, "  [%s] %s\n", source, message);
}

typedef struct samples {
    double *v;
    size_t n, cap;
} samples;

static void push(samples *s, double x)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1024;
        s->v = realloc(s->v, s->cap * sizeof *s->v);
        assert_non_null(s->v);
    }
    s->v[s->n++] = x;
}

static size_t nearest_vertex(const float *b, size_t n, const float p[3], double *dist)
{
    double best = INFINITY;
    size_t bi = 0;
    for (size_t v = 0; v < n; v++) {
        double dx = b[3 * v] - p[0], dy = b[3 * v + 1] - p[1], dz = b[3 * v + 2] - p[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best) {
            best = d2;
            bi = v;
        }
    }
    *dist = sqrt(best);
    return bi;
}

static const char *faces[] = {"ict-facekit/generic_neutral_mesh.obj",
                              "lee-perry-smith/LeePerrySmith.obj",
                              "mediapipe-canonical/canonical_face_model.obj"};
static fp_test_recordings recs; /* the four, or FP_REACH_HANDS's */

/* One run of recording `rec` (a *_joints_mm.csv) named `rec_name`; its reach samples go to
 * `all` and its own percentiles are checked. */
static void one_run(const char *face, const char *rec, const char *rec_name, samples *all,
                    int *runs_checked, double *worst_p10)
{
    char mesh[4300], input[4400], err[2048];
    snprintf(mesh, sizeof mesh, "%s/faces/%s", fp_test_data_dir(), face);
    snprintf(input, sizeof input, "replay:%s,fast=1%s", rec, getenv("FP_REACH_KEYS") ? getenv("FP_REACH_KEYS") : ""); /* (experiments) */
    fp_session_options so = {0};
    so.mesh_path = mesh;
    so.inputs[0] = input;
    so.input_count = 1;
    so.mapping = getenv("FP_REACH_MAPPING") ? getenv("FP_REACH_MAPPING") : "anchored"; /* (experiments) */
    so.rig_path = getenv("FP_REACH_RIG") ? NULL : "none"; /* (experiments: the mesh's own rig) */
    so.input_clock = true;
    so.plugin_path = fp_test_plugin_path();
    so.log = on_log;
    so.radius = getenv("FP_REACH_RADIUS") ? atof(getenv("FP_REACH_RADIUS")) : 0; /* (experiments) */
    so.no_contact_guard = getenv("FP_REACH_NO_CONTACT") != NULL; /* (experiments) */
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    rc = fp_session_start(s, err, sizeof err);
    assert_int_equal(rc, 0);
    int64_t t0 = fp_test_session_t0(s);
    size_t n = fp_session_vertex_count(s);
    double R = fp_session_radius(s), mm = fp_session_head(s)->mm_per_unit;
    samples run = {0};
    unsigned long frames = 0, active = 0, limited = 0, by_contact = 0, by_flip = 0, composed = 0;
    int substeps = 1;
    double max_asked = 0, max_moved = 0, max_update_ms = 0;
    uint64_t max_pairs = 0;
    for (uint64_t k = 0;; k++) {
        int64_t now = fp_test_frame_time(s, t0, k, 30.0);
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        frames++;
        if (st.active && !st.committed) {
            active++;
            limited += st.guard_reached < 1.0;
            by_contact += st.collide_t < 1.0;
            by_flip += st.collide_t < 1.0 && st.collide_pairs == 0;
            if (getenv("FP_TEST_VERBOSE") && st.collide_t < 1.0)
                fprintf(stderr, "  frame %llu: contact kept %.3f of the motion (%.3f near the blocking "
                        "triangles; %s)\n", (unsigned long long)k, st.collide_kept, st.collide_t,
                        st.collide_pairs ? "crossings" : "flips alone");
            if (getenv("FP_REACH_SAVE_FRAME") && (uint64_t)atoll(getenv("FP_REACH_SAVE_FRAME")) == k)
                fp_session_save(s, getenv("FP_REACH_SAVE"), err, sizeof err);
            composed += st.guard_substeps > 1;
            if (st.guard_substeps > substeps) substeps = st.guard_substeps;
            if (st.update_ms > max_update_ms) max_update_ms = st.update_ms;
            if (st.pairs > max_pairs) max_pairs = st.pairs;
            const fp_control_set *cs = fp_session_control_set(s);
            if (getenv("FP_REACH_PAIRS") && st.guard_reached < 1.0) {
                fprintf(stderr, "  frame %llu limited %.3f bound %.1f, %zu vectors:", (unsigned long long)k,
                        st.guard_reached, st.guard_bound, cs->count);
                for (size_t i = 0; i < cs->count; i++)
                    for (size_t j = i + 1; j < cs->count; j++) {
                        double ds = 0, de = 0;
                        for (int a = 0; a < 3; a++) {
                            ds += pow((double)cs->start[i][a] - cs->start[j][a], 2);
                            de += pow((double)cs->end[i][a] - cs->end[j][a], 2);
                        }
                        if (sqrt(ds) < 2 * R) fprintf(stderr, " [%zu,%zu s %.1f e %.1f]", i, j, sqrt(ds) * mm, sqrt(de) * mm);
                    }
                fprintf(stderr, "\n");
            }
            const float *base = fp_session_base(s), *pos = fp_session_positions(s);
            for (size_t i = 0; i < cs->count; i++) {
                double d;
                size_t v = nearest_vertex(base, n, cs->start[i], &d);
                if (d > 0.5 * R) continue;
                double asked = 0, moved = 0;
                for (int a = 0; a < 3; a++) {
                    asked += pow((double)cs->end[i][a] - cs->start[i][a], 2);
                    moved += pow((double)pos[3 * v + a] - base[3 * v + a], 2);
                }
                asked = sqrt(asked);
                if (asked < 1e-4 * R) continue;
                if (asked > max_asked) {
                    max_asked = asked;
                    if (getenv("FP_REACH_SAVE") && !getenv("FP_REACH_SAVE_FRAME")) fp_session_save(s, getenv("FP_REACH_SAVE"), err, sizeof err);
                }
                if (getenv("FP_REACH_DUMP")) fprintf(stderr, "  dump frame %llu v%zu asked %.2f moved %.2f\n", (unsigned long long)k, i, asked * mm, sqrt(moved) * mm);
                push(&run, sqrt(moved) / asked);
                if (sqrt(moved) > max_moved) max_moved = sqrt(moved);
            }
        }
        if (fp_session_finished(s)) break;
    }
    double med = run.n ? fp_median(run.v, run.n) : NAN, p10 = run.n ? fp_percentile(run.v, run.n, 0.10) : NAN;
    printf("%-14.14s %-16s frames %4lu active %4lu composed %3lu (up to %2d maps) limited %3lu "
           "contact-scaled %3lu (%3lu for flips alone) vectors %4zu reach median %5.1f%% p10 %5.1f%%, largest ask %.1f mm, "
           "largest drag %.1f mm (R %.1f mm); slowest engine update %.1f ms, most pairs %llu\n", face, rec_name, frames,
           active, composed, substeps, limited, by_contact, by_flip, run.n, 100 * med, 100 * p10, max_asked * mm,
           max_moved * mm, R * mm, max_update_ms, (unsigned long long)max_pairs);
    fflush(stdout);
    if (run.n) {
        if (p10 < *worst_p10) *worst_p10 = p10;
        (*runs_checked)++;
    }
    for (size_t i = 0; i < run.n; i++) push(all, run.v[i]);
    free(run.v);
    fp_session_destroy(&s);
}

static void test_reach_anchored(void **state)
{
    (void)state;
    const char *only = getenv("FP_REACH_ONLY");
    samples all = {0};
    int runs = 0;
    double worst_p10 = INFINITY;
    fp_test_recordings_from("FP_REACH_HANDS", &recs);
    for (size_t fi = 0; fi < sizeof faces / sizeof faces[0]; fi++)
        for (size_t ri = 0; ri < recs.n; ri++) {
            char name[600];
            snprintf(name, sizeof name, "%s/%s", faces[fi], recs.name[ri]);
            if (only && !strcasestr(name, only)) continue;
            /* sanitizer builds (several times slower): the ICT face's four runs, the same
             * code as the others' */
            if (!only && fp_test_time_scale() > 1 && fi > 0) continue;
            one_run(faces[fi], recs.path[ri], recs.name[ri], &all, &runs, &worst_p10);
        }
    double med = all.n ? fp_median(all.v, all.n) : NAN;
    printf("all runs: %zu vectors in %d runs with touching fingertips, reach median %.1f%%, "
           "p10 %.1f%%, worst run's p10 %.1f%%\n", all.n, runs, 100 * med,
           all.n ? 100 * fp_percentile(all.v, all.n, 0.10) : NAN, 100 * worst_p10);
    assert_true(all.n > 0);
    /* The target is 0.90; measured 1.00 since the anchored mapping widens the
     * support of a long drag (widen=0.5; 0.88 before). */
    assert_true(med >= 0.90);
    /* The second figure: every run's 10th percentile >= 60% (measured: every run
     * 100% since the contact guard carries the skin it holds back along with the drag
     * (fp_contact_set_carry); before, the worst 92.0%, ICT's grab; Lee Perry-Smith's grab
     * 62.2% before its close sheets by the eye were carried together (sheet_bind.h) and
     * 22.9% before the local scale-back started narrow). */
    assert_true(worst_p10 >= 0.60);
    free(all.v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reach_anchored),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
