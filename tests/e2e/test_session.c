/* End to end on real data: the ICT face deformed by the real three-claps recording through
 * each mapping, in-process, checking every frame: no NaN, and no displacement outside every
 * support (the engine runs without the polynomial, so T is exactly the identity there). */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_plugin_host.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

typedef struct outcome {
    unsigned long frames, active, commits, checked_outside, guarded;
    double max_disp;
} outcome;

static void run_session(const char *mapping, outcome *o)
{
    char input[4300];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,speed=4",
             fp_test_data_dir());
    const char *inputs[] = {input};
    fp_session *s = fp_test_session_start(mapping, inputs, 1);
    size_t n = fp_session_vertex_count(s);
    const float *loaded = fp_session_loaded(s);
    double R = fp_session_radius(s);
    memset(o, 0, sizeof *o);
    float *before = malloc(n * 3 * sizeof(float));
    int64_t deadline = fp_now_ns() + 60LL * 1000000000LL;
    while (!fp_session_finished(s) && fp_now_ns() < deadline) {
        memcpy(before, fp_session_base(s), n * 3 * sizeof(float));
        fp_frame_stats st;
        fp_session_step(s, fp_now_ns(), &st);
        o->frames++;
        const float *shown = fp_session_positions(s);
        for (size_t i = 0; i < 3 * n; i++) assert_true(isfinite(shown[i]));
        if (st.active) {
            o->active++;
            o->commits += st.committed;
        }
        /* Outside every support the shape is the base before this frame, bit for bit; not on
         * a frame the contact guard scaled back: its shape lies between the last frame's and
         * this one's, so skin the last frame's (wider) support moved stays partly moved (seen
         * under ASan and on a loaded machine, where frames are few and far apart) */
        if (st.active && st.collide_t < 1) o->guarded++;
        if (st.active && !(st.collide_t < 1)) {
            const fp_control_set *cs = fp_session_control_set(s);
            for (size_t v = 0; v < n; v++) {
                bool inside = false;
                for (size_t c = 0; c < cs->count && !inside; c++) {
                    /* the fold-over guard may compose sub-steps whose centres lie on the
                     * segment start -> end: the union of their supports is the capsule */
                    double se[3], sv[3], ss = 0, t = 0, d2 = 0;
                    for (int k = 0; k < 3; k++) {
                        se[k] = (double)cs->end[c][k] - cs->start[c][k];
                        sv[k] = (double)before[3 * v + k] - cs->start[c][k];
                        ss += se[k] * se[k];
                        t += se[k] * sv[k];
                    }
                    t = ss > 0 ? fmin(1, fmax(0, t / ss)) : 0;
                    for (int k = 0; k < 3; k++) d2 += pow(sv[k] - t * se[k], 2);
                    /* (the control set's radius: the anchored mapping widens it for long drags) */
                    inside = d2 < cs->radius * cs->radius * 1.0001;
                }
                if (inside) continue;
                assert_memory_equal(&shown[3 * v], &before[3 * v], 3 * sizeof(float));
                o->checked_outside++;
            }
        }
        struct timespec ts = {0, 2000000};
        nanosleep(&ts, NULL);
    }
    assert_true(fp_session_finished(s));
    const float *fin = fp_session_positions(s);
    for (size_t v = 0; v < n; v++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) d2 += pow(fin[3 * v + k] - loaded[3 * v + k], 2);
        if (sqrt(d2) > o->max_disp) o->max_disp = sqrt(d2);
    }
    printf("%s: %lu frames, %lu deforming (%lu scaled back by the contact guard), %lu commits, max "
           "displacement %.4g (R %.4g), %lu vertex checks outside the supports\n", mapping, o->frames,
           o->active, o->guarded, o->commits, o->max_disp, R, o->checked_outside);
    free(before);
    fp_session_destroy(&s);
}

static void test_anchored_on_real_data(void **state)
{
    (void)state;
    outcome o;
    run_session("anchored", &o);
    assert_true(o.active > 0);        /* the hands reached the face */
    assert_true(o.commits > 0);       /* and let go again */
    assert_true(o.max_disp > 0);      /* the face changed */
    assert_true(o.checked_outside > 0);
}

static void test_unanchored_on_real_data(void **state)
{
    (void)state;
    outcome o;
    run_session("unanchored", &o);
    assert_true(o.active > 0);
    assert_int_equal(o.commits, o.active); /* every step folds into the base */
    assert_true(o.max_disp > 0);
    assert_true(o.checked_outside > 0);
}

/* Commits write only the engine's touched ranges into the base and keep only the changed
 * pieces for undo (core/session/history.h): through the session on the ICT face without a rig
 * (so every commit takes that path), the real recording, each mapping: after every frame the
 * shown shape of a committing frame is the base; at the end every gesture is undone in turn
 * and the base equals the one before that gesture bit for bit, down to the loaded face. */
static void undo_all_exact(const char *mapping)
{
    char input[4300], err[2048];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,speed=4",
             fp_test_data_dir());
    fp_session_options so;
    fp_test_face_options(&so, mapping, NULL);
    so.inputs[0] = input;
    so.input_count = 1;
    so.rig_path = "none";
    so.input_clock = true; /* frame k at t0 + k / 60 s of the recording's clock (as `run`): every
                              gesture's frames, however slow a frame (a widened drag) */
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (!rc) rc = fp_session_start(s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    int64_t t0 = fp_test_session_t0(s);
    size_t n = fp_session_vertex_count(s), bytes = n * 3 * sizeof(float);
    enum { KEEP = FP_SESSION_UNDO_LEVELS };
    float *before = malloc(bytes), *snap[KEEP];
    for (int i = 0; i < KEEP; i++) snap[i] = malloc(bytes);
    unsigned long gestures = 0, commits = 0;
    int64_t deadline = fp_now_ns() + 60LL * 1000000000LL;
    for (uint64_t k = 0; !fp_session_finished(s) && fp_now_ns() < deadline; k++) {
        int64_t now = fp_test_frame_time(s, t0, k, 60.0);
        memcpy(before, fp_session_base(s), bytes);
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        if (st.committed) {
            commits++;
            assert_ptr_equal(fp_session_positions(s), fp_session_base(s));
        }
        if (fp_session_commits(s) > gestures) { /* a gesture opened: the base before it */
            assert_int_equal(fp_session_commits(s), gestures + 1);
            memcpy(snap[gestures % KEEP], before, bytes);
            gestures++;
        }
    }
    if (!(gestures > 0 && commits >= gestures)) printf("%s: %lu commits in %lu gestures\n", mapping, commits, gestures);
    assert_true(gestures > 0 && commits >= gestures);
    for (unsigned long g = gestures; g > 0 && gestures - g < KEEP; g--) {
        assert_true(fp_session_undo(s));
        assert_memory_equal(fp_session_base(s), snap[(g - 1) % KEEP], bytes);
        assert_memory_equal(fp_session_positions(s), snap[(g - 1) % KEEP], bytes);
    }
    if (gestures <= KEEP) {
        assert_memory_equal(fp_session_base(s), fp_session_loaded(s), bytes);
        assert_false(fp_session_undo(s));
    }
    printf("%s: %lu commits in %lu gestures, undone bit for bit\n", mapping, commits, gestures);
    for (int i = 0; i < KEEP; i++) free(snap[i]);
    free(before);
    fp_session_destroy(&s);
}

static void test_undo_after_ranged_commits(void **state)
{
    (void)state;
    undo_all_exact("anchored");
    undo_all_exact("unanchored");
}

/* fp_session_options.progress: the opening's steps in order, each naming its size, then NULL
 * once; on a failed create (a mesh that is not there, a mapping that is not there) NULL once
 * too, after the steps reached. */
typedef struct progress_log {
    char lines[8][512];
    int n, ends;
} progress_log;

static void on_progress(void *user, const char *stage)
{
    progress_log *p = user;
    if (!stage) {
        p->ends++;
        return;
    }
    assert_int_equal(p->ends, 0); /* no step after the end */
    assert_true(p->n < 8);
    snprintf(p->lines[p->n++], sizeof p->lines[0], "%s", stage);
}

static void test_open_progress(void **state)
{
    (void)state;
    char err[2048];
    fp_session_options so;
    fp_test_face_options(&so, "anchored", NULL);
    progress_log p = {0};
    so.progress = on_progress;
    so.progress_user = &p;
    fp_session *s = NULL;
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), 0);
    assert_int_equal(p.ends, 1);
    assert_int_equal(p.n, 4);
    assert_string_equal(p.lines[0], "loading generic_neutral_mesh.obj (3 MiB)"); /* 2,555,599 bytes */
    char want[256];
    snprintf(want, sizeof want, "indexing %zu vertices", fp_session_vertex_count(s));
    assert_string_equal(p.lines[1], want);
    snprintf(want, sizeof want, "building the contact guard over %zu triangles",
             fp_session_mesh(s)->triangle_count);
    assert_string_equal(p.lines[2], want);
    assert_string_equal(p.lines[3], "loading the mapping and 0 inputs");
    fp_session_destroy(&s);

    /* failures: the end is still reported, once */
    p = (progress_log){0};
    so.mapping = "no-such-mapping";
    assert_true(fp_session_create(&so, &s, err, sizeof err) < 0);
    assert_null(s);
    assert_int_equal(p.ends, 1);
    assert_int_equal(p.n, 4);
    p = (progress_log){0};
    so.mapping = "anchored";
    so.mesh_path = "/nonexistent/face.obj";
    assert_true(fp_session_create(&so, &s, err, sizeof err) < 0);
    assert_int_equal(p.ends, 1);
    assert_int_equal(p.n, 0); /* no size to give: no loading line */
}

/* An input plugin's log lines reach the session's log callback with the input's name, on the
 * thread that runs the frames, never the plugin's own (the fixture logs from a thread). */
typedef struct relayed {
    pthread_t runner;
    int n, on_runner, mapping_lines, mapping_on_runner;
    char lines[8][64];
    char mapping_line[64];
} relayed;

static void on_log(void *user, int level, const char *source, const char *message)
{
    (void)level;
    relayed *r = user;
    if (!strcmp(source, "mapping 'fixture'")) { /* the mapping's, relayed the same way */
        r->mapping_on_runner += pthread_equal(pthread_self(), r->runner) != 0;
        snprintf(r->mapping_line, sizeof r->mapping_line, "%s", message);
        r->mapping_lines++;
        return;
    }
    if (strcmp(source, "fixture")) return; /* (the session's own lines) */
    r->on_runner += pthread_equal(pthread_self(), r->runner) != 0;
    if (r->n < 8) snprintf(r->lines[r->n], sizeof r->lines[0], "%s", message);
    r->n++;
}

static void test_input_log_relayed(void **state)
{
    (void)state;
    char err[2048], fixtures[4200];
    snprintf(fixtures, sizeof fixtures, "%s/tests/plugins", fp_test_build_dir());
    const char *dirs[] = {fp_test_plugin_dir(), fixtures};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 2, NULL);
    fp_session_options so;
    fp_test_face_options(&so, "fixture", NULL); /* (tests/plugin/fixture_mapping.c) */
    so.plugin_path = &path;
    so.inputs[0] = "fixture,log=3";
    so.input_count = 1;
    so.frame_thread = -1; /* the frames on this thread */
    relayed r = {.runner = pthread_self()};
    so.log = on_log;
    so.log_user = &r;
    fp_session *s = NULL;
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), 0);
    assert_int_equal(r.n, 1); /* create's line, at create */
    assert_string_equal(r.lines[0], "created");
    assert_int_equal(r.mapping_lines, 1);
    assert_int_equal(r.mapping_on_runner, 1);
    assert_string_equal(r.mapping_line, "fixture A created");
    assert_int_equal(fp_session_start(s, err, sizeof err), 0);
    /* the plugin's thread logs meanwhile; the frames hand its lines over */
    for (int i = 0; i < 200 && r.n < 4; i++) {
        fp_frame_stats st;
        fp_session_step(s, fp_now_ns(), &st);
        fp_test_nap_ms(2);
    }
    assert_int_equal(r.n, 4); /* (before destroy, which hands over what is left) */
    fp_session_destroy(&s);
    assert_int_equal(r.n, 4);
    assert_int_equal(r.on_runner, 4);
    assert_string_equal(r.lines[1], "line 0");
    assert_string_equal(r.lines[3], "line 2");
    fp_plugin_path_clear(&path);
}

/* A hand the tracker loses mid-gesture lets go: three-claps with the right hand's rows
 * between 1.0 and 3.0 s taken out (the left hand goes on), on the ICT face, anchored, at 30
 * fps on the recording's clock. With the replay's default timeout (1 s, as a live osc
 * input's) the right hand is gone at 2.0 s and the gesture it held commits then; with
 * timeout=0 (a lost hand never reported: the behaviour before) the frozen right hand keeps
 * that gesture engaged past 2.5 s. */
static int lost_hand_commits(const char *csv, const char *keys, double from_s, double to_s)
{
    char input[4400];
    snprintf(input, sizeof input, "replay:%s,fast=1%s", csv, keys);
    fp_session_options so;
    fp_test_face_options(&so, "anchored", NULL);
    so.rig_path = "none";
    so.inputs[0] = input;
    so.input_count = 1;
    so.input_clock = true;
    fp_session *s = fp_test_session_open(&so);
    int64_t t0 = fp_test_session_t0(s);
    int commits = 0;
    for (uint64_t k = 0; !fp_session_finished(s); k++) {
        fp_frame_stats st;
        fp_session_step(s, fp_test_frame_time(s, t0, k, 30.0), &st);
        double t = (double)k / 30.0;
        if (st.committed && t >= from_s && t <= to_s) commits++;
    }
    fp_session_destroy(&s);
    return commits;
}

static void test_lost_hand_lets_go(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_lost_hand_XXXXXX", csv[64], src[4300];
    assert_non_null(mkdtemp(dir));
    snprintf(csv, sizeof csv, "%s/claps_joints_mm.csv", dir);
    snprintf(src, sizeof src, "%s/hands/leap-motion/three-claps_joints_mm.csv", fp_test_data_dir());
    FILE *in = fopen(src, "r"), *out = fopen(csv, "w");
    assert_non_null(in);
    assert_non_null(out);
    char line[8192];
    long long first_us = -1;
    int dropped = 0;
    for (int row = 0; fgets(line, sizeof line, in); row++) {
        long long us = 0;
        char hand[16] = "";
        /* frame,timestamp_us,hand_id,hand_type,... */
        if (row && sscanf(line, "%*[^,],%lld,%*[^,],%15[^,]", &us, hand) == 2) {
            if (first_us < 0) first_us = us;
            double t = (double)(us - first_us) * 1e-6;
            if (!strcmp(hand, "right") && t > 1.0 && t < 3.0) {
                dropped++;
                continue;
            }
        }
        fputs(line, out);
    }
    fclose(in);
    fclose(out);
    assert_true(dropped > 100);
    int with = lost_hand_commits(csv, "", 1.9, 2.5), without = lost_hand_commits(csv, ",timeout=0", 1.0, 3.0);
    printf("right hand lost from 1.0 to 3.0 s: %d commits between 1.9 and 2.5 s (timeout 1 s), "
           "%d between 1.0 and 3.0 s with timeout=0\n", with, without);
    assert_true(with >= 1);
    assert_int_equal(without, 0);
    unlink(csv);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_anchored_on_real_data),
        cmocka_unit_test(test_unanchored_on_real_data),
        cmocka_unit_test(test_undo_after_ranged_commits),
        cmocka_unit_test(test_open_progress),
        cmocka_unit_test(test_input_log_relayed),
        cmocka_unit_test(test_lost_hand_lets_go),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
