/* core/session/step_mapping (the control set's check, errors reported once with a count),
 * step_rig (the pass-through) and session_log's repeat counter. */
#include "fp_test_support.h"
#include "csrbf.h"
#include "fp_mesh.h"
#include "log_capture.h"
#include "step_mapping.h"
#include "step_rig.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

static float starts[4][3], ends[4][3];
static int mode; /* 0 ok, 1 returns -EIO, 2 over capacity, 3 NaN end, 4 radius 0, 5 inactive with radius 0 */

static int fake_process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    (void)self;
    (void)in;
    out->active = mode != 5;
    out->intents = FP_INTENT_ENGAGE;
    out->radius = mode == 4 || mode == 5 ? 0.0 : 1.0;
    out->count = mode == 2 ? out->capacity + 1 : 2;
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 3; k++) out->start[i][k] = out->end[i][k] = (float)(i + k);
    if (mode == 3) out->end[1][2] = NAN;
    return mode == 1 ? -EIO : 0;
}

static void setup_cs(fp_control_set *cs)
{
    memset(cs, 0, sizeof *cs);
    cs->size = sizeof *cs;
    cs->capacity = 4;
    cs->start = starts;
    cs->end = ends;
}

static void test_check(void **state)
{
    (void)state;
    fp_control_set cs;
    setup_cs(&cs);
    cs.active = true;
    cs.radius = 1.0;
    cs.count = 4;
    assert_int_equal(fp_control_set_check(&cs), 0);
    cs.count = 5;
    assert_int_equal(fp_control_set_check(&cs), -ERANGE);
    cs.count = 1;
    cs.radius = INFINITY;
    assert_int_equal(fp_control_set_check(&cs), -EINVAL);
    cs.radius = 1e300; /* finite, but past the engine's range (a take would read it as damage) */
    assert_int_equal(fp_control_set_check(&cs), -EINVAL);
    cs.radius = 1e-20;
    assert_int_equal(fp_control_set_check(&cs), -EINVAL);
    cs.active = false; /* an inactive set's radius is not the mapping's (fp_control_check.h), */
    assert_int_equal(fp_control_set_check(&cs), 0);
    starts[0][1] = NAN; /* its points are */
    assert_int_equal(fp_control_set_check(&cs), -EINVAL);
    starts[0][1] = 0;
    cs.active = true;
    cs.radius = 1.0;
    starts[0][1] = NAN;
    assert_int_equal(fp_control_set_check(&cs), -EINVAL);
    starts[0][1] = 0;
    cs.channel_count = 1; /* no channel array */
    assert_int_equal(fp_control_set_check(&cs), -ERANGE);
}

/* Every failure deactivates the frame's set; one line for a run of the same error, then its
 * count when it ends or another comes. */
static void test_errors_once_with_count(void **state)
{
    (void)state;
    fp_mapping m = {0};
    m.size = sizeof m;
    m.process = fake_process;
    fp_mapping_step st = {0};
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    fp_control_set cs;
    setup_cs(&cs);
    fp_frame_input in = {0};
    mode = 0;
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), 0);
    assert_true(cs.active);
    mode = 1;
    for (int f = 0; f < 10; f++) {
        in.frame = (uint64_t)f;
        assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), -EIO);
        assert_false(cs.active);
        assert_int_equal(cs.intents, 0);
    }
    assert_int_equal(cap.count, 1);
    assert_string_equal(cap.source, "mapping 'anchored'");
    assert_non_null(strstr(cap.lines[0], "frame 0"));
    mode = 3; /* another error: the count of the first, then the new one */
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), -EINVAL);
    assert_int_equal(cap.count, 3);
    assert_non_null(strstr(cap.lines[1], "repeated 9 more times"));
    mode = 2;
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), -ERANGE);
    assert_int_equal(cs.count, 0); /* a refused set is emptied, not kept as written */
    in.radius = 2.5;
    mode = 4;
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), -EINVAL);
    assert_int_equal(cap.count, 5);
    /* what a take records of it: inactive, empty, the session's radius (before: the radius 0
     * the mapping wrote, which a take's reader reads as damage) */
    assert_false(cs.active);
    assert_int_equal(cs.count, 0);
    assert_int_equal(cs.channel_count, 0);
    assert_true(cs.radius == 2.5);
    mode = 0; /* success flushes nothing when the error did not repeat */
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), 0);
    assert_int_equal(cap.count, 5);
    /* an inactive set with radius 0 is no error (`plugins check` passes it: one rule,
     * fp_control_check.h); what is recorded has the session's radius */
    mode = 5;
    assert_int_equal(fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log), 0);
    assert_int_equal(cap.count, 5);
    assert_false(cs.active);
    assert_true(cs.radius == 2.5);
    mode = 0;
    assert_int_equal(st.errors.total, 13);
    mode = 1;
    fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log);
    fp_mapping_step_run(&st, &m, "anchored", &in, &cs, &log);
    fp_mapping_step_flush(&st, &log);
    assert_int_equal(cap.count, 7);
    assert_non_null(strstr(cap.lines[6], "repeated 1 more time)"));
}

/* A refused set is reported naming what is wrong in it (before: "invalid control set (radius
 * or points): -22 (Invalid argument)" for all three, so the author had to guess which vector,
 * which point, or whether the radius). */
static void test_refusal_named(void **state)
{
    (void)state;
    fp_mapping m = {0};
    m.size = sizeof m;
    m.process = fake_process;
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    fp_control_set cs;
    fp_frame_input in = {0};
    in.radius = 1.0;
    in.frame = 7;
    fp_mapping_step st = {0};
    setup_cs(&cs);
    mode = 3; /* end[1][2] NaN */
    assert_int_equal(fp_mapping_step_run(&st, &m, "pinch", &in, &cs, &log), -EINVAL);
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.lines[0], "vector 1's end point (1, 2, nan) is not finite"));
    assert_non_null(strstr(cap.lines[0], "on frame 7; the base shown"));
    memset(&st, 0, sizeof st);
    setup_cs(&cs);
    mode = 4; /* an active set with radius 0 */
    assert_int_equal(fp_mapping_step_run(&st, &m, "pinch", &in, &cs, &log), -EINVAL);
    assert_int_equal(cap.count, 2);
    assert_non_null(strstr(cap.lines[1], "radius 0 of an active set, outside [1e-15, 1e+15]"));
    memset(&st, 0, sizeof st);
    setup_cs(&cs);
    mode = 2; /* count past capacity: the count named, not the channels */
    assert_int_equal(fp_mapping_step_run(&st, &m, "pinch", &in, &cs, &log), -ERANGE);
    assert_int_equal(cap.count, 3);
    assert_non_null(strstr(cap.lines[2], "count 5 > capacity 4 on frame 7"));
    assert_null(strstr(cap.lines[2], "channel"));
}

static void test_rig_pass_through(void **state)
{
    (void)state;
    fp_rig_step r = {0};
    fp_control_set cs;
    setup_cs(&cs);
    cs.count = 3;
    fp_control_set copy = cs;
    assert_ptr_equal(fp_rig_step_run(&r, &cs), &cs);
    assert_memory_equal(&copy, &cs, sizeof cs);
}

/* A mapping's channel value that is not a number is ignored and said once, naming the
 * channel (before: ignored without a word); a finite one is clamped to the range. */
static void test_rig_nan_channel_said(void **state)
{
    (void)state;
    char err[512];
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(fp_test_face_path(), &m, err, sizeof err), 0);
    fp_rig *rig = NULL;
    assert_int_equal(fp_rig_load_for_mesh("rigs/ict-facekit.json", m->vertex_count, m->positions, &rig, err,
                                          sizeof err), 0);
    fp_rig_step r;
    assert_int_equal(fp_rig_step_init(&r, rig, m->vertex_count, m->positions), 0);
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    fp_channel ch[1] = {{"jaw.open", 0.5f}};
    fp_control_set cs;
    setup_cs(&cs);
    cs.channels = ch;
    cs.channel_capacity = cs.channel_count = 1;
    fp_rig_step_update(&r, &cs, m->positions, &log);
    assert_true(fp_rig_step_channel(&r, "jaw.open") == 0.5f);
    assert_int_equal(cap.count, 0);
    ch[0].value = NAN;
    for (int i = 0; i < 3; i++) fp_rig_step_update(&r, &cs, m->positions, &log);
    assert_true(fp_rig_step_channel(&r, "jaw.open") == 0.5f); /* kept */
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.lines[0], "\"jaw.open\" with a value that is not a number"));
    fp_rig_step_free(&r);
    fp_mesh_free(&m);
}

/* The rig's finger clamp on the ICT face, against the brute force fp_rig_finger_limit_toward
 * computed afresh on the current posed base (the step's clamp goes through the slope index),
 * through an anchored gesture, after a start point moves, the radius changes, the jaw is
 * posed anew (the posed base changed), and after commits that move the base on ranges
 * (fp_rig_step_rebase_ranges, whose slope index update waits for the next limits); vectors
 * pushed toward bone and pulled away. Every clamped vector is within the brute force's bound
 * for its own segment; one within the bound as asked is kept bit for bit; one cut keeps
 * more than the whole vector scaled to its limit (the clamp before) when what it lost was
 * the push alone (counted in *longer, of *cut). */
static void expect_clamped(const fp_rig_step *r, const fp_control_set *in, const fp_control_set *out,
                           unsigned *cut, unsigned *longer)
{
    assert_int_equal(out->count, in->count);
    for (size_t i = 0; i < in->count; i++) {
        assert_memory_equal(out->start[i], in->start[i], sizeof in->start[i]);
        double limit = fp_rig_finger_limit_toward(r->rig, r->posed, in->start[i], in->end[i], in->radius);
        double d[3], len = 0;
        for (int k = 0; k < 3; k++) {
            d[k] = (double)in->end[i][k] - in->start[i][k];
            len += d[k] * d[k];
        }
        len = sqrt(len);
        if (!(len > limit)) {
            assert_memory_equal(out->end[i], in->end[i], sizeof in->end[i]);
            continue;
        }
        double got = 0;
        for (int k = 0; k < 3; k++) {
            double o = (double)out->end[i][k] - in->start[i][k];
            got += o * o;
        }
        double own = fp_rig_finger_limit_toward(r->rig, r->posed, out->start[i], out->end[i], in->radius);
        assert_true(sqrt(got) <= own * (1 + 1e-6) + 1e-7); /* within the bound (float ends) */
        (*cut)++;
        *longer += sqrt(got) > limit * (1 + 1e-9);
    }
}

static void test_rig_clamp_kept(void **state)
{
    (void)state;
    const char *path = fp_test_face_path();
    char err[512];
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    fp_rig *rig = NULL;
    assert_int_equal(fp_rig_load_for_mesh("rigs/ict-facekit.json", m->vertex_count, m->positions, &rig, err,
                                          sizeof err), 0);
    fp_rig_step r;
    assert_int_equal(fp_rig_step_init(&r, rig, m->vertex_count, m->positions), 0);
    /* start points on vertices all over the face (some near the jaw's ramp), long vectors */
    float st[4][3], en[4][3];
    fp_control_set cs;
    setup_cs(&cs);
    cs.start = st;
    cs.end = en;
    cs.count = 4;
    cs.radius = 2.0;
    cs.active = true;
    size_t n = m->vertex_count;
    float *moved = malloc(n * 3 * sizeof *moved), *scratch = malloc(n * 3 * sizeof *scratch);
    assert_non_null(moved);
    assert_non_null(scratch);
    unsigned limited = 0, looser = 0, cut = 0, longer = 0;
    for (int frame = 0; frame < 40; frame++) {
        if (frame == 0 || frame == 25) /* a new gesture: new start points */
            for (int i = 0; i < 4; i++)
                memcpy(st[i], m->positions + 3 * ((size_t)(frame * 97 + i * 6151) % n), sizeof st[i]);
        if (frame == 10) st[2][1] += 0.01f; /* one start point moves */
        if (frame == 15) cs.radius = 3.0;
        if (frame == 20) { /* the jaw opens: the posed base changes */
            assert_int_equal(fp_rig_step_set_channel(&r, "jaw.open", 0.8f), 0);
            assert_true(fp_rig_step_update(&r, NULL, m->positions, NULL));
        }
        if (frame == 30 || frame == 35) { /* commits: the base moves on ranges (rebase_ranges),
                                             a third of the face, then all of it */
            for (size_t v = 0; v < n; v++)
                for (int k = 0; k < 3; k++) moved[3 * v + k] = m->positions[3 * v + k] + (k == 0 ? 0.2f * (float)(frame - 29) : 0.f);
            uint32_t rg[2] = {frame == 30 ? (uint32_t)(n / 3) : 0, frame == 30 ? (uint32_t)(n / 3) : (uint32_t)n};
            fp_rig_step_rebase_ranges(&r, moved, scratch, rg, 1);
        }
        /* out of the face and back in, sideways both ways: toward and away from bones */
        float sgn = frame % 2 ? -1.f : 1.f;
        /* (vectors 0 and 1 mostly in or out, 2 and 3 mostly sideways with a little in or out) */
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++)
                en[i][k] = st[i][k] + sgn * (k == (i < 2 ? 2 : 0) ? 1.5f : 0.3f) * (float)(frame % 5 + 1);
        const fp_control_set *out = fp_rig_step_run(&r, &cs);
        expect_clamped(&r, &cs, out, &cut, &longer);
        for (size_t i = 0; i < 4; i++) {
            double l = fp_rig_finger_limit_toward(r.rig, r.posed, st[i], en[i], cs.radius);
            limited += l < 1.5;
            looser += l > 2 * fp_rig_finger_limit(r.rig, r.posed, st[i], cs.radius); /* the bound
                                                                   blind to direction */
        }
    }
    printf("rig clamp: %u vectors held under 1.5, %u let over twice as far as by |grad m| alone, of 160; "
           "%u cut, %u of them longer than the vector scaled whole\n", limited, looser, cut, longer);
    assert_true(limited > 0); /* pushes toward bone were held */
    assert_true(looser > 0);  /* and the others went farther */
    assert_true(cut > 0);
    assert_true(longer * 10 >= cut * 9); /* the part that does not push kept */
    fp_rig_step_free(&r);
    fp_mesh_free(&m);
    free(moved);
    free(scratch);
}

/* The mobility blend over the engine's touched ranges only equals the whole blend bit for bit,
 * frame after frame: a real engine (csrbf, touched evaluation) on the ICT face's posed base
 * moving over it, the jaw posed anew halfway (the blend starts over). */
static void test_rig_finish_ranges(void **state)
{
    (void)state;
    const char *path = fp_test_face_path();
    char err[512];
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    size_t n = m->vertex_count, bytes = n * 3 * sizeof(float);
    fp_rig *rig = NULL;
    assert_int_equal(fp_rig_load_for_mesh("rigs/ict-facekit.json", n, m->positions, &rig, err, sizeof err), 0);
    fp_rig_step r;
    assert_int_equal(fp_rig_step_init(&r, rig, n, m->positions), 0);
    csrbf_points *pts = NULL;
    csrbf_touch *touch = NULL;
    csrbf_solver *sol = NULL;
    assert_int_equal(csrbf_points_create(n, r.posed, &pts), CSRBF_OK);
    assert_int_equal(csrbf_touch_create(pts, &touch), CSRBF_OK);
    csrbf_options o = {0};
    o.radius = 2.0;
    o.threads = 1;
    assert_true(csrbf_solver_create(&o, &sol) >= 0);
    float *out = malloc(bytes), *want = malloc(bytes);
    memcpy(out, r.posed, bytes);
    unsigned partial = 0;
    for (int frame = 0; frame < 30; frame++) {
        if (frame == 15) { /* the jaw: a new posed base, re-indexed */
            assert_int_equal(fp_rig_step_set_channel(&r, "jaw.open", 0.5f), 0);
            assert_true(fp_rig_step_update(&r, NULL, m->positions, NULL));
            assert_int_equal(csrbf_points_update(pts, r.posed), CSRBF_OK);
            csrbf_touch_reset(touch);
        }
        float st[2][3], en[2][3];
        for (int i = 0; i < 2; i++) { /* two fingers walking over the face */
            memcpy(st[i], r.posed + 3 * ((size_t)(frame * 211 + i * 9001) % n), sizeof st[i]);
            for (int k = 0; k < 3; k++) en[i][k] = st[i][k] + 0.3f;
        }
        assert_true(csrbf_solver_set_start_points(sol, 2, &st[0][0]) >= 0);
        assert_true(csrbf_solver_set_end_points(sol, &en[0][0]) >= 0);
        assert_true(csrbf_evaluate_touched(sol, pts, touch, out, 0u, NULL) >= 0);
        const uint32_t *ranges;
        size_t nr = csrbf_touch_ranges(touch, &ranges);
        const float *shown = fp_rig_step_finish(&r, out, ranges, nr);
        assert_ptr_equal(shown, r.shown);
        assert_int_equal(fp_rig_apply_mobility(rig, r.posed, out, want), 0);
        assert_memory_equal(shown, want, bytes);
        size_t covered = 0;
        for (size_t i = 0; i < nr; i++) covered += ranges[2 * i + 1];
        partial += covered < n;
    }
    assert_true(partial >= 20); /* most frames blended a part of the face only */
    free(out);
    free(want);
    csrbf_solver_destroy(&sol);
    csrbf_touch_destroy(&touch);
    csrbf_points_destroy(&pts);
    fp_rig_step_free(&r);
    fp_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check),
        cmocka_unit_test(test_errors_once_with_count),
        cmocka_unit_test(test_refusal_named),
        cmocka_unit_test(test_rig_pass_through),
        cmocka_unit_test(test_rig_nan_channel_said),
        cmocka_unit_test(test_rig_clamp_kept),
        cmocka_unit_test(test_rig_finish_ranges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
