/* What changed since the viewer last asked (changed.h, fp_session_touched,
 * fp_session_base_touched): the range union against a bitmap reference on random lists, and
 * the session's contract on the ICT face with and without its rig, driven by control sets
 * (fp_session_apply_controls): outside the reported ranges the shown shape and the base are
 * bit for bit what they were at the previous call, through gestures, commits, idle frames,
 * cancels, undo, reset, a jaw channel and calls that skip frames; and the ranges stay small
 * where the engine's supports are (not "everything" in disguise), commits with a rig
 * included. And a rig commit through the touched ranges against the whole-mesh commit
 * (fp_session_options.whole_rig_commit), two sessions bit for bit; without a rig, a commit
 * where the guard checked the frame writes where the step moved vertices, not the engine's
 * whole supports (fp_cg_commit_ranges), again bit for bit the whole-mesh commit. */
#define _GNU_SOURCE
#include "changed.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

/* ---- the union ------------------------------------------------------------------------- */

static uint64_t rng = 88172645463325252ull;
static uint32_t next_u32(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)(rng >> 11);
}

/* A random increasing, disjoint list (adjacent pairs allowed) below n; its pairs into r. */
static size_t random_ranges(uint32_t *r, size_t max_pairs, uint32_t n, unsigned char *mark)
{
    size_t k = 0;
    uint32_t at = next_u32() % 50;
    while (k < max_pairs && at < n) {
        uint32_t len = 1 + next_u32() % 40;
        if (at + len > n) len = n - at;
        r[2 * k] = at;
        r[2 * k + 1] = len;
        for (uint32_t v = at; v < at + len; v++) mark[v] = 1;
        k++;
        at += len + next_u32() % 60; /* sometimes 0: adjacent */
    }
    return k;
}

static void test_changed_union(void **state)
{
    (void)state;
    enum { N = 5000 };
    static unsigned char ref[N];
    static uint32_t r[2 * 400];
    fp_changed c = {0};
    const uint32_t *out;
    /* nothing is recorded before the first take, which says "anything" */
    fp_changed_add(&c, (const uint32_t[]){1, 2}, 1);
    assert_int_equal(fp_changed_take(&c, &out), SIZE_MAX);
    assert_null(out);
    assert_int_equal(fp_changed_take(&c, &out), 0);
    for (int round = 0; round < 200; round++) {
        memset(ref, 0, sizeof ref);
        int adds = 1 + (int)(next_u32() % 5);
        for (int a = 0; a < adds; a++) {
            size_t k = random_ranges(r, 400, N, ref);
            fp_changed_add(&c, r, k);
        }
        bool all = round % 17 == 3;
        if (all) fp_changed_all(&c);
        fp_changed_add(&c, r, 0);
        size_t k = fp_changed_take(&c, &out);
        if (all) {
            assert_int_equal(k, SIZE_MAX);
            continue;
        }
        unsigned char got[N] = {0};
        uint64_t last_end = 0;
        for (size_t i = 0; i < k; i++) {
            assert_true(out[2 * i + 1] > 0);
            if (i) assert_true(out[2 * i] > last_end); /* disjoint, not adjacent: joined */
            last_end = (uint64_t)out[2 * i] + out[2 * i + 1];
            assert_true(last_end <= N);
            for (uint32_t v = out[2 * i]; v < last_end; v++) got[v] = 1;
        }
        assert_memory_equal(got, ref, N);
    }
    fp_changed_add(&c, NULL, SIZE_MAX);
    assert_int_equal(fp_changed_take(&c, &out), SIZE_MAX);
    fp_changed_free(&c);
}

/* ---- the session ----------------------------------------------------------------------- */

typedef struct fixture {
    fp_session *s;
    size_t n;
    float *shown, *base;     /* as at the last take */
    unsigned char *cover;
    float start[3][3], end[3][3];
    fp_control_set cs;
    double radius;
    int64_t t;
} fixture;

/* The fixture around its session f->s: buffers, the support radius (0.06 x the mesh's
 * diagonal) and a control set of 3 over start and end. */
static void fixture_ready(fixture *f)
{
    f->n = fp_session_vertex_count(f->s);
    f->shown = malloc(f->n * 3 * sizeof(float));
    f->base = malloc(f->n * 3 * sizeof(float));
    f->cover = malloc(f->n);
    assert_true(f->shown && f->base && f->cover);
    float lo[3], hi[3];
    fp_mesh_bounds(fp_session_mesh(f->s), lo, hi);
    f->radius = 0.06 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                            (hi[2] - lo[2]) * (hi[2] - lo[2]));
    f->cs.size = sizeof f->cs;
    f->cs.radius = f->radius;
    f->cs.capacity = 3;
    f->cs.start = f->start;
    f->cs.end = f->end;
}

/* Take both records and check them against the last; returns the shown shape's count and
 * writes the covered fraction to *frac (1 for SIZE_MAX). */
static size_t take_one(fixture *f, bool base, double *frac, size_t *bcount)
{
    const uint32_t *r;
    size_t k = base ? fp_session_base_touched(f->s, &r) : fp_session_touched(f->s, &r);
    const float *now = base ? fp_session_base(f->s) : fp_session_positions(f->s);
    float *prev = base ? f->base : f->shown;
    if (k != SIZE_MAX) {
        memset(f->cover, 0, f->n);
        size_t covered = 0;
        for (size_t i = 0; i < k; i++) {
            assert_true((size_t)r[2 * i] + r[2 * i + 1] <= f->n);
            for (uint32_t v = r[2 * i]; v < r[2 * i] + r[2 * i + 1]; v++) f->cover[v] = 1, covered++;
        }
        for (size_t v = 0; v < f->n; v++)
            if (!f->cover[v] && memcmp(&now[3 * v], &prev[3 * v], 3 * sizeof(float)))
                fail_msg("%s: vertex %zu changed outside the %zu reported ranges", base ? "base" : "shown", v, k);
        *frac = (double)covered / (double)f->n;
    } else {
        *frac = 1;
    }
    memcpy(prev, now, f->n * 3 * sizeof(float));
    if (bcount) *bcount = k;
    return k;
}

static size_t take(fixture *f, double *frac, size_t *base_k)
{
    double bf;
    take_one(f, true, &bf, base_k);
    return take_one(f, false, frac, NULL);
}

static void frame(fixture *f, bool active, uint32_t intents, double phase)
{
    f->cs.active = active;
    f->cs.intents = intents;
    f->cs.count = active ? 3 : 0;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            f->end[i][k] = f->start[i][k] + (float)(0.08 * f->radius * sin(phase + i + 2.1 * k));
    fp_session_apply_controls(f->s, f->t += 16666667, &f->cs, intents, NULL);
}

/* Start points at three vertices of the face (cheek, chin, forehead area by index). */
static void place(fixture *f, uint32_t a, uint32_t b, uint32_t c)
{
    const float *p = fp_session_base(f->s);
    uint32_t v[3] = {a, b, c};
    for (int i = 0; i < 3; i++) memcpy(f->start[i], &p[3 * v[i]], sizeof f->start[i]);
}

/* A session on the ICT face, anchored, rigs from the source tree (rig_path: fp_session_options;
 * whole: whole_rig_commit) */
static fp_session *rig_session_of(bool whole, const char *rig_path)
{
    char err[2048];
    fp_session_options so;
    fp_test_face_options(&so, "anchored", FP_TEST_RIGS_DIR);
    so.rig_path = rig_path;
    so.whole_rig_commit = whole;
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    return s;
}

static void run_contract(const char *rig_path)
{
    fixture f = {0};
    f.s = rig_session_of(false, rig_path);
    fixture_ready(&f);
    bool rig = fp_session_rig(f.s) != NULL;
    double frac;
    size_t bk;

    assert_int_equal(take(&f, &frac, &bk), SIZE_MAX); /* the first call */
    assert_int_equal(bk, SIZE_MAX);
    frame(&f, false, 0, 0);
    assert_int_equal(take(&f, &frac, &bk), 0);          /* idle: nothing */
    assert_int_equal(bk, 0);

    /* a gesture: each frame a few blocks; the commit moves the base there too */
    place(&f, 3000, 8000, 12000);
    int partial = 0;
    for (int i = 0; i < 8; i++) {
        frame(&f, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.4 * i);
        size_t k = take(&f, &frac, &bk);
        assert_int_equal(bk, 0);
        if (i == 0) continue; /* the engine's first run writes its whole output */
        if (!(k != SIZE_MAX && k > 0 && frac < 0.5)) fail_msg("frame %d: %zu ranges, %.3f of the vertices", i, k, frac);
        partial++;
    }
    assert_int_equal(partial, 7);
    frame(&f, true, FP_INTENT_COMMIT, 3.2);
    size_t k = take(&f, &frac, &bk);
    /* the commit's ranges (with a rig too: unposed, posed and re-indexed there only) */
    assert_true(k != SIZE_MAX && frac < 0.5);
    assert_true(bk > 0 && bk != SIZE_MAX);
    frame(&f, false, 0, 0);
    take(&f, &frac, &bk);
    frame(&f, false, 0, 0);
    assert_int_equal(take(&f, &frac, &bk), 0);
    assert_int_equal(bk, 0);

    /* frames not asked about: the union covers them all; a cancelled gesture goes back */
    place(&f, 500, 15000, 20000);
    for (int i = 0; i < 5; i++) frame(&f, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.3 * i);
    k = take(&f, &frac, &bk);
    assert_true(k != SIZE_MAX && k > 0 && frac < 0.5);
    frame(&f, true, FP_INTENT_CANCEL, 2);
    take(&f, &frac, &bk);
    frame(&f, false, 0, 0); /* the base again: where the last output differed */
    k = take(&f, &frac, &bk);
    assert_true(k != SIZE_MAX && k > 0);
    assert_memory_equal(fp_session_positions(f.s), fp_session_base(f.s), rig ? 0 : f.n * 3 * sizeof(float));

    /* undo and reset: everything */
    assert_true(fp_session_undo(f.s));
    assert_int_equal(take(&f, &frac, &bk), SIZE_MAX);
    assert_int_equal(bk, SIZE_MAX);
    frame(&f, false, 0, 0);
    assert_int_equal(take(&f, &frac, &bk), 0);
    fp_session_reset(f.s);
    assert_int_equal(take(&f, &frac, &bk), SIZE_MAX);

    if (rig) { /* a channel poses the face: everything, then gestures are partial again */
        assert_int_equal(fp_session_set_channel(f.s, "jaw.open", 0.5), 0);
        frame(&f, false, 0, 0);
        assert_int_equal(take(&f, &frac, &bk), SIZE_MAX);
        place(&f, 3000, 8000, 12000);
        for (int i = 0; i < 4; i++) {
            frame(&f, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.5 * i);
            k = take(&f, &frac, &bk);
            if (i) assert_true(k != SIZE_MAX && frac < 0.5);
        }
        /* a commit with the jaw open: the base and the posed base change on its ranges only
         * (vertices the fingers did not move keep their base bit for bit) */
        frame(&f, true, FP_INTENT_COMMIT, 2.0);
        k = take(&f, &frac, &bk);
        assert_true(k != SIZE_MAX && frac < 0.5);
        assert_true(bk > 0 && bk != SIZE_MAX);
        frame(&f, false, 0, 0);
        take(&f, &frac, &bk);
        place(&f, 5000, 9000, 14000);
        for (int i = 0; i < 3; i++) {
            frame(&f, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.5 * i);
            k = take(&f, &frac, &bk);
            assert_true(k != SIZE_MAX && frac < 0.5); /* partial from the first run after it */
        }
    }
    fp_session_destroy(&f.s);
    free(f.shown);
    free(f.base);
    free(f.cover);
}

static void test_session_contract_no_rig(void **state)
{
    (void)state;
    run_contract("none");
}

static void test_session_contract_rig(void **state)
{
    (void)state;
    run_contract(NULL); /* the ICT face's rig, found by its checksum */
}

/* ---- a rig commit: ranged = whole ------------------------------------------------------ */

static fp_session *rig_session(bool whole)
{
    fp_session *s = rig_session_of(whole, NULL);
    assert_non_null(fp_session_rig(s));
    return s;
}

/* The posed base computed here from the session's base and jaw.open (fp_rig_pose, whole). */
static void expect_posed(fp_session *s, float *tmp, const char *when)
{
    const fp_rig *rig = fp_session_rig(s);
    float vals[FP_RIG_MAX_CHANNELS];
    for (size_t c = 0; c < fp_rig_channel_count(rig); c++) {
        fp_rig_channel_desc d;
        fp_rig_channel_get(rig, c, &d);
        vals[c] = (float)fp_session_channel(s, d.name);
    }
    assert_int_equal(fp_rig_pose(rig, fp_session_base(s), vals, tmp), 0);
    if (memcmp(tmp, fp_session_positions(s), fp_session_vertex_count(s) * 3 * sizeof(float)))
        fail_msg("%s: the shown shape is not the pose of the base", when);
}

typedef struct pair {
    fixture *f;
    fp_session *w;
    float *tmp;
    size_t commits, ranged_commits, guarded, guarded_ranged;
    double ms_ranged, ms_whole;
} pair;

/* One frame of both sessions on the same control set, compared; amp scales the control
 * vectors (fractions of R). */
static void both(pair *p, bool active, uint32_t intents, double phase, double amp)
{
    fixture *f = p->f;
    size_t bytes = f->n * 3 * sizeof(float);
    f->cs.active = active;
    f->cs.intents = intents;
    f->cs.count = active ? 3 : 0;
    for (int i = 0; i < 3 && amp >= 0; i++) /* amp < 0: the end points as the caller set them */
        for (int k = 0; k < 3; k++)
            f->end[i][k] = f->start[i][k] + (float)(amp * f->radius * sin(phase + i + 2.1 * k));
    fp_frame_stats a, b;
    f->t += 16666667;
    fp_session_apply_controls(f->s, f->t, &f->cs, intents, &a);
    fp_session_apply_controls(p->w, f->t, &f->cs, intents, &b);
    assert_memory_equal(fp_session_base(f->s), fp_session_base(p->w), bytes);
    assert_memory_equal(fp_session_positions(f->s), fp_session_positions(p->w), bytes);
    assert_int_equal(a.committed, b.committed);
    p->guarded += a.collide_t < 1;
    double frac;
    size_t bk;
    take(f, &frac, &bk); /* the ranged session's ranges cover every change */
    /* commits of the guard's shape (on its D_P and the touched ranges) */
    p->guarded_ranged += a.collide_t < 1 && a.committed;
    if (a.committed) {
        p->commits++;
        p->ms_ranged += a.stage_ms[FP_STAGE_COMMIT];
        p->ms_whole += b.stage_ms[FP_STAGE_COMMIT];
        if (fp_session_rig(f->s)) expect_posed(f->s, p->tmp, "after a commit");
        p->ranged_commits += bk != SIZE_MAX;
    }
}

/* Two sessions on the ICT face with its rig, the same control sets: one commits through the
 * touched ranges (the default), the other the whole mesh (whole_rig_commit). Base and shown
 * shape bit for bit equal after every frame (so the posed base, the engine's output and its
 * index, the blend and the finger limits are too, or the next frames would differ), through
 * anchored commits at rest and with the jaw open, a second commit over the first one's
 * region, one-shot committed steps, undo, reset; the shown shape after a commit is the pose
 * of the base computed afresh; the ranged session's reported ranges cover every change;
 * commits of the contact guard's shape among them. */
static void test_rig_commit_ranged_equals_whole(void **state)
{
    (void)state;
    fixture f = {0};
    fp_session *w = rig_session(true);
    f.s = rig_session(false);
    fixture_ready(&f);
    size_t bytes = f.n * 3 * sizeof(float);
    float *tmp = malloc(bytes);
    assert_non_null(tmp);
    double frac;
    size_t bk;
    pair p = {&f, w, tmp, 0, 0, 0, 0, 0, 0};
    take(&f, &frac, &bk);
    static const uint32_t spots[][3] = {{3000, 8000, 12000}, {3010, 8020, 12005}, {500, 15000, 20000},
                                        {5000, 9000, 14000}, {3000, 8000, 12000}};
    for (int g = 0; g < 5; g++) {
        if (g == 3) { /* the jaw opens: both pose their base anew */
            assert_int_equal(fp_session_set_channel(f.s, "jaw.open", 0.6), 0);
            assert_int_equal(fp_session_set_channel(w, "jaw.open", 0.6), 0);
            both(&p, false, 0, 0, 0.0);
        }
        place(&f, spots[g][0], spots[g][1], spots[g][2]);
        for (int i = 0; i < 6; i++) both(&p, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.4 * i + g, 0.08);
        both(&p, true, FP_INTENT_COMMIT, 2.5 + g, 0.08);
        both(&p, false, 0, 0, 0.0);
        expect_posed(f.s, tmp, "idle after a commit");
    }
    /* one-shot steps pressing the mouth's and the eyes' landmarks along the face's axes
     * (upper down, lower up, the third in): the contact guard scales several back, and
     * commits of its shape are ranged too */
    {
        float up[3], fwd[3];
        fp_rig_axes(fp_session_rig(f.s), up, fwd, NULL);
        static const struct {
            uint32_t v[3];
            double amp;
        } push[] = {{{6213, 5708, 3742}, 0.25}, {{1507, 5517, 0}, 0.15}, {{1528, 0, 5518}, 0.10},
                    {{3742, 3742, 1528}, 0.15}, {{4857, 1528, 4857}, 0.30}};
        for (size_t t = 0; t < sizeof push / sizeof push[0]; t++) {
            place(&f, push[t].v[0], push[t].v[1], push[t].v[2]);
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    f.end[i][k] = f.start[i][k] + (float)(push[t].amp * f.radius *
                                                          (i == 0 ? -up[k] : i == 1 ? up[k] : -fwd[k]));
            both(&p, true, FP_INTENT_COMMIT, 0, -1);
            both(&p, false, 0, 0, 0.0);
        }
    }
    /* one-shot committed steps (unanchored): fresh start points each frame, small and large */
    for (int i = 0; i < 4; i++) {
        place(&f, (uint32_t)(4000 + 900 * i), (uint32_t)(11000 + 700 * i), (uint32_t)(16000 + 300 * i));
        both(&p, true, FP_INTENT_COMMIT, 0.7 * i, i % 2 ? 0.4 : 0.05);
    }
    both(&p, false, 0, 0, 0.0);
    for (int u = 0; u < 3; u++) {
        assert_true(fp_session_undo(f.s));
        assert_true(fp_session_undo(w));
        assert_memory_equal(fp_session_base(f.s), fp_session_base(w), bytes);
        assert_memory_equal(fp_session_positions(f.s), fp_session_positions(w), bytes);
        expect_posed(f.s, tmp, "after undo");
        take(&f, &frac, &bk);
        both(&p, false, 0, 0, 0.0);
    }
    place(&f, 3000, 8000, 12000); /* a gesture after undo */
    for (int i = 0; i < 4; i++) both(&p, true, i == 0 ? FP_INTENT_ENGAGE : 0, 0.3 * i, 0.1);
    both(&p, true, FP_INTENT_COMMIT, 1.5, 0.1);
    both(&p, false, 0, 0, 0.0);
    fp_session_reset(f.s);
    fp_session_reset(w);
    assert_memory_equal(fp_session_base(f.s), fp_session_loaded(f.s), bytes);
    assert_memory_equal(fp_session_positions(f.s), fp_session_positions(w), bytes);
    both(&p, false, 0, 0, 0.0);
    printf("rig commits: %zu, %zu of them ranged, commit stage "
           "%.3f ms ranged vs %.3f ms whole (sum); the contact guard scaled back %zu frames, %zu "
           "of them commits (of the guard's shape)\n",
           p.commits, p.ranged_commits, p.ms_ranged, p.ms_whole, p.guarded, p.guarded_ranged);
    assert_true(p.commits >= 15 && p.ranged_commits == p.commits && p.guarded_ranged >= 2);
    fp_session_destroy(&w);
    fp_session_destroy(&f.s);
    free(f.shown);
    free(f.base);
    free(f.cover);
    free(tmp);
}

/* Without a rig: commits of the contact guard's shape (one-shot steps the guard scales back,
 * fresh start points each frame, as the unanchored mapping gives) through its D_P and the
 * touched ranges (the default) against the whole mesh (whole_rig_commit), two sessions bit
 * for bit after every frame, composed steps among them; the reported ranges cover every
 * change. */
static void test_guard_commit_ranged_equals_whole(void **state)
{
    (void)state;
    fixture f = {0};
    fp_session *w = rig_session_of(true, "none");
    f.s = rig_session_of(false, "none");
    assert_null(fp_session_rig(f.s));
    fixture_ready(&f);
    pair p = {&f, w, NULL, 0, 0, 0, 0, 0, 0};
    double frac;
    size_t bk;
    take(&f, &frac, &bk);
    /* the mouth's and the eyes' landmarks pressed along the face's axes, then pulled around
     * again and again, each frame a committed one-shot step from where the last one left */
    static const uint32_t spots[][3] = {{6213, 5708, 3742}, {1507, 5517, 0}, {1528, 0, 5518},
                                        {3742, 3742, 1528}, {4857, 1528, 4857}};
    static const float dir[3][3] = {{0, -1, 0}, {0, 1, 0}, {0, 0, -1}};
    for (size_t t = 0; t < sizeof spots / sizeof spots[0]; t++)
        for (int r = 0; r < 4; r++) {
            place(&f, spots[t][0], spots[t][1], spots[t][2]);
            double amp = 0.1 + 0.08 * r;
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    f.end[i][k] = f.start[i][k] +
                                  (float)(amp * f.radius * (dir[i][k] + 0.3 * sin(r + i + k)));
            both(&p, true, FP_INTENT_COMMIT, 0, -1);
        }
    both(&p, false, 0, 0, 0.0);
    for (int u = 0; u < 3; u++) { /* (one-shot steps with no idle frame between are one level) */
        bool a = fp_session_undo(f.s), b = fp_session_undo(w);
        assert_int_equal(a, b);
        both(&p, false, 0, 0, 0.0);
    }
    printf("commits without a rig: %zu, %zu of them of the contact guard's shape (ranged), commit "
           "stage %.3f ms ranged vs %.3f ms whole (sum)\n", p.commits, p.guarded_ranged, p.ms_ranged,
           p.ms_whole);
    assert_true(p.commits >= 15 && p.guarded_ranged >= 3);
    fp_session_destroy(&w);
    fp_session_destroy(&f.s);
    free(f.shown);
    free(f.base);
    free(f.cover);
}

/* Without a rig, a committed one-shot step where one of three fingertips moves and two stay
 * (their control vectors zero, their supports apart from the moving one's): the commit writes
 * the base where the step moved a vertex (fp_cg_commit_ranges), not in the two still supports
 * the engine wrote (its touched ranges, which the shown shape's ranges hold); the reported
 * ranges cover every change (take), and a session that commits the whole mesh
 * (whole_rig_commit) keeps the same base and shape, bit for bit. */
static void test_commit_follows_motion(void **state)
{
    (void)state;
    fixture f = {0};
    fp_session *w = rig_session_of(true, "none");
    f.s = rig_session_of(false, "none");
    fixture_ready(&f);
    double frac;
    size_t bk;
    take(&f, &frac, &bk);
    /* three vertices 3 R apart or more */
    const float *b = fp_session_base(f.s);
    uint32_t v[3] = {3000, 0, 0};
    int got = 1;
    for (uint32_t c = 0; c < f.n && got < 3; c += 97) {
        bool far = true;
        for (int j = 0; j < got; j++) {
            double d2 = 0;
            for (int k = 0; k < 3; k++) d2 += (b[3 * c + k] - b[3 * v[j] + k]) * (double)(b[3 * c + k] - b[3 * v[j] + k]);
            far = far && d2 > 9 * f.radius * f.radius;
        }
        if (far) v[got++] = c;
    }
    assert_int_equal(got, 3);
    double shown_frac = 0, base_frac = 0;
    for (int r = 0; r < 4; r++) {
        place(&f, v[0], v[1], v[2]);
        memcpy(f.end, f.start, sizeof f.end);
        f.end[0][1] += (float)(0.05 * f.radius * (r + 1)); /* one fingertip moves, two stay */
        f.cs.active = true;
        f.cs.intents = FP_INTENT_COMMIT;
        f.cs.count = 3;
        fp_frame_stats a, c;
        f.t += 16666667;
        fp_session_apply_controls(f.s, f.t, &f.cs, FP_INTENT_COMMIT, &a);
        fp_session_apply_controls(w, f.t, &f.cs, FP_INTENT_COMMIT, &c);
        assert_true(a.committed && c.committed);
        assert_memory_equal(fp_session_base(f.s), fp_session_base(w), f.n * 3 * sizeof(float));
        assert_memory_equal(fp_session_positions(f.s), fp_session_positions(w), f.n * 3 * sizeof(float));
        double bf;
        take_one(&f, true, &bf, NULL); /* the base: the commit's ranges */
        take_one(&f, false, &frac, NULL); /* the shown shape: the engine's touched ranges too */
        base_frac += bf;
        shown_frac += frac;
    }
    printf("committed one-shot steps, one fingertip of three moving: the base written on %.4f of "
           "the vertices a step, the shown shape reported on %.4f\n", base_frac / 4, shown_frac / 4);
    assert_true(base_frac > 0 && base_frac < 0.5 * shown_frac);
    fp_session_destroy(&w);
    fp_session_destroy(&f.s);
    free(f.shown);
    free(f.base);
    free(f.cover);
}

/* One anchored frame of the fixture's three control vectors, each end point its start moved
 * by amp x R along dir; its statistics into *st; the ranges taken and checked (take). */
static size_t pressed(fixture *f, const float dir[3][3], double amp, uint32_t intents, double *frac,
                      fp_frame_stats *st)
{
    size_t bk;
    f->cs.active = true;
    f->cs.intents = intents;
    f->cs.count = 3;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) f->end[i][k] = f->start[i][k] + (float)(amp * f->radius * dir[i][k]);
    fp_session_apply_controls(f->s, f->t += 16666667, &f->cs, intents, st);
    return take(f, frac, &bk);
}

/* Without a rig: the contact guard's shape shown through gestures that are not committed (the
 * lips pressed through each other, further each frame, then back), frames to and from it and
 * the posed base after it: the reported ranges cover every change (take), and where the
 * guard's shape is shown now or was last frame they are its D_P and the engine's ranges, a
 * part of the face, not everything. */
static void test_guard_shown_ranges(void **state)
{
    (void)state;
    fixture f = {0};
    f.s = rig_session_of(false, "none");
    fixture_ready(&f);
    double frac;
    size_t bk, guarded = 0, partial = 0, after = 0;
    take(&f, &frac, &bk);
    static const uint32_t spots[][3] = {{6213, 5708, 3742}, {1507, 5517, 1528}};
    static const float dir[3][3] = {{0, -1, 0}, {0, 1, 0}, {0, 0, -1}};
    for (size_t t = 0; t < sizeof spots / sizeof spots[0]; t++) {
        place(&f, spots[t][0], spots[t][1], spots[t][2]);
        bool was_guarded = false;
        for (int i = 0; i < 16; i++) {
            const double amp = 0.06 * (i < 10 ? i + 1 : 20 - i); /* to 0.6 R and back to 0.24 R */
            fp_frame_stats st;
            size_t k = pressed(&f, dir, amp, i == 0 ? FP_INTENT_ENGAGE : 0, &frac, &st);
            const bool g = st.collide_t < 1;
            if (i > 1 && (g || was_guarded)) { /* (the engine's first run writes its whole output) */
                guarded += g;
                after += !g;
                if (k != SIZE_MAX && frac < 0.8) partial++;
                else fail_msg("spot %zu frame %d (guard %d, last frame %d): %zu ranges, %.3f of the vertices",
                              t, i, g, was_guarded, k, frac);
            }
            was_guarded = g;
        }
        f.cs.active = false; /* the gesture ends: the posed base again */
        f.cs.count = 0;
        fp_session_apply_controls(f.s, f.t += 16666667, &f.cs, 0, NULL);
        size_t k = take(&f, &frac, &bk);
        if (was_guarded && !(k != SIZE_MAX && frac < 0.5))
            fail_msg("spot %zu: the base after the guard's shape: %zu ranges, %.3f", t, k, frac);
        assert_memory_equal(fp_session_positions(f.s), fp_session_base(f.s), f.n * 3 * sizeof(float));
    }
    /* the press slides along the mouth (its start points 0.05 R further each frame), so the
     * guard's shape differs from the base where the engine no longer writes; then the hands
     * go to the forehead: the engine's output is shown again, the change lies where the
     * guard's shape was (its D_P kept) */
    size_t slid = 0;
    for (int i = 0; i < 20; i++) {
        place(&f, spots[0][0], spots[0][1], spots[0][2]);
        for (int c = 0; c < 3; c++) f.start[c][0] += (float)(0.05 * i * f.radius);
        fp_frame_stats st;
        pressed(&f, dir, 0.5, i == 0 ? FP_INTENT_ENGAGE : 0, &frac, &st);
        slid += st.collide_t < 1;
        if (getenv("DBG")) printf("slide %d g %d frac %.3f\n", i, st.collide_t < 1, frac);
        if (i >= 6 && st.collide_t < 1) break; /* (the guard's shape shown last) */
    }
    place(&f, 12000, 12001, 12002);
    fp_frame_stats st;
    size_t k = pressed(&f, dir, 0.01, 0, &frac, &st); /* (take: covered) */
    assert_true(k != SIZE_MAX && st.collide_t >= 1);
    printf("the contact guard's shape shown in %zu frames, %zu more right after it: %zu of them "
           "reported in part; a sliding press shown in %zu frames\n", guarded, after, partial, slid);
    assert_true(guarded >= 4 && slid >= 3);
    fp_session_destroy(&f.s);
    free(f.shown);
    free(f.base);
    free(f.cover);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_changed_union),
        cmocka_unit_test(test_guard_commit_ranged_equals_whole),
        cmocka_unit_test(test_commit_follows_motion),
        cmocka_unit_test(test_guard_shown_ranges),
        cmocka_unit_test(test_session_contract_no_rig),
        cmocka_unit_test(test_session_contract_rig),
        cmocka_unit_test(test_rig_commit_ranged_equals_whole),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
