/* Whose hands are whose (issue 55, item 4), through whole sessions on the ICT face on the
 * input clock, with two recordings that both give a right hand: three-claps (hands=right) and
 * grab, each replayed fast=1.
 *  - merged (no performer= key, as before): one performer, the second recording's right hand
 *    overwrites the first's in the session's one pair of hands;
 *  - grab with performer=B: two performers; the first performer's right hand follows the
 *    three-claps recording as it does alone, B's right hand follows grab as it does alone
 *    (each placed by its own calibration), and the anchored mapping gets both hands: more
 *    control vectors than the first recording alone gives, and a different shape than the
 *    merge; the same shape through the isolated mapping (--isolate all's helper);
 *  - a performer= key on the only input, or the same one on both, changes nothing: the shape
 *    bit for bit as without it.
 * The input clock aligns the recordings' time zeros (intents.h), so runs are repeatable bit
 * for bit and frames of different runs meet on one grid: the first performer's hand is
 * compared frame for frame; B's, whose first sample falls elsewhere on the grid than when
 * grab runs alone, within a tolerance. */
#define _GNU_SOURCE
#include "fp_calib_file.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#define MAX_FRAMES 2000

typedef struct run_out {
    size_t frames, performers;
    unsigned long vectors;          /* control vectors summed over the frames */
    size_t max_vectors;             /* the most in one frame */
    size_t moved;                   /* vertices of the final shape off the loaded one */
    unsigned long of[2];            /* control vectors whose end is nearest performer p's right
                                       fingertips (the grabbed skin's offset: under R) */
    size_t frames_both;             /* frames with vectors of both performers */
    bool have[2][MAX_FRAMES];       /* performer p's right hand present at frame k ... */
    float palm[2][MAX_FRAMES][3];   /* ... and its palm, mesh units */
    float *shape;                   /* the final shape, n x 3 */
    size_t n;
} run_out;

static char specs[4][2048];

/* The recordings as input SPECs: three-claps' right hand; grab with `key` (NULL: none). */
static const char *claps(const char *key)
{
    snprintf(specs[0], sizeof specs[0], "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,hands=right,"
             "fast=1%s%s", fp_test_data_dir(), key ? "," : "", key ? key : "");
    return specs[0];
}
static const char *grab(const char *key)
{
    snprintf(specs[1], sizeof specs[1], "replay:%s/hands/leap-motion/grab_joints_mm.csv,fast=1%s%s",
             fp_test_data_dir(), key ? "," : "", key ? key : "");
    return specs[1];
}

/* Whose hand each control vector of the frame follows: its end point's nearest fingertip of
 * the performers' right hands, within 2 R (an anchored vector ends at the fingertip plus the
 * offset to the skin it grabbed, under R). */
static void attribute(const fp_session *s, run_out *o)
{
    const fp_control_set *cs = fp_session_control_set(s);
    double reach = 2 * fp_session_radius(s);
    size_t n[2] = {0, 0};
    for (size_t i = 0; i < cs->count; i++) {
        double best = reach;
        int who = -1;
        for (size_t p = 0; p < 2 && p < fp_session_performer_count(s); p++) {
            const fp_hand_pose *h = fp_session_performer_hand(s, p, FP_HAND_RIGHT);
            for (int f = 0; h && f < FP_FINGERS; f++) {
                double d = 0;
                for (int c = 0; c < 3; c++) d += pow((double)cs->end[i][c] - h->joints[FP_JOINT_TIP(f)][c], 2);
                if (sqrt(d) < best) best = sqrt(d), who = (int)p;
            }
        }
        if (who >= 0) n[who]++;
    }
    o->of[0] += n[0];
    o->of[1] += n[1];
    o->frames_both += n[0] && n[1];
}

/* A session of the inputs with the anchored mapping (isolated: in its helper), stepped on the
 * input clock at 60 frames a second to the recordings' end, as `facepuppet run`. */
static void run(const char *const *inputs, int n, bool isolated, run_out *o)
{
    memset(o, 0, sizeof *o);
    char err[2048], helper[4096];
    fp_session_options so;
    fp_test_face_options(&so, "anchored", NULL);
    for (int i = 0; i < n; i++) so.inputs[i] = inputs[i];
    so.input_count = (size_t)n;
    so.input_clock = true;
    if (isolated) {
        snprintf(helper, sizeof helper, "%s/bin/facepuppet", fp_test_build_dir());
        so.isolate = 2; /* all */
        so.isolate_helper = helper;
        so.isolate_deadline_ms = 5000.0 * fp_test_time_scale();
    }
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) fail_msg("%s", err);
    if ((rc = fp_session_start(s, err, sizeof err))) fail_msg("%s", err);
    o->performers = fp_session_performer_count(s);
    int64_t t0 = fp_test_session_t0(s);
    for (size_t k = 0; k < MAX_FRAMES; k++) {
        int64_t now = fp_test_frame_time(s, t0, k, 60.0);
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        o->vectors += st.active ? st.control_vectors : 0;
        if (st.active && st.control_vectors > o->max_vectors) o->max_vectors = st.control_vectors;
        if (st.active) attribute(s, o);
        for (size_t p = 0; p < 2 && p < o->performers; p++) {
            const fp_hand_pose *h = fp_session_performer_hand(s, p, FP_HAND_RIGHT);
            o->have[p][k] = h != NULL;
            if (h) memcpy(o->palm[p][k], h->joints[FP_JOINT_PALM], sizeof o->palm[p][k]);
        }
        o->frames = k + 1;
        if (fp_session_finished(s)) break;
    }
    o->n = fp_session_vertex_count(s);
    o->shape = malloc(o->n * 3 * sizeof *o->shape);
    assert_non_null(o->shape);
    memcpy(o->shape, fp_session_positions(s), o->n * 3 * sizeof *o->shape);
    const float *loaded = fp_session_loaded(s);
    for (size_t v = 0; v < o->n; v++)
        if (memcmp(&loaded[3 * v], &o->shape[3 * v], 3 * sizeof(float))) o->moved++;
    fp_session_destroy(&s);
}

/* How far a's hand of performer pa strays from b's of performer pb: over the frames where
 * a's is present, the largest distance to the nearest of b's within `window` frames either
 * side (mesh units; the inputs' start apart shifts a second recording by a fraction of a
 * frame); *both: how many of a's frames had one of b's to compare. */
static double hand_gap(const run_out *a, int pa, const run_out *b, int pb, int window, size_t *both)
{
    double worst = 0;
    *both = 0;
    for (size_t k = 0; k < a->frames; k++) {
        if (!a->have[pa][k]) continue;
        double best = INFINITY;
        for (long j = (long)k - window; j <= (long)k + window; j++) {
            if (j < 0 || (size_t)j >= b->frames || !b->have[pb][j]) continue;
            double d = 0;
            for (int c = 0; c < 3; c++) d += pow((double)a->palm[pa][k][c] - b->palm[pb][j][c], 2);
            best = fmin(best, sqrt(d));
        }
        if (!isfinite(best)) continue;
        worst = fmax(worst, best);
        (*both)++;
    }
    return worst;
}

static void say(const char *what, const run_out *o)
{
    printf("# %-27s performers %zu, frames %zu, control vectors %lu (most in a frame %zu; "
           "following the first's right hand %lu, B's %lu; frames with both %zu), vertices moved "
           "%zu\n", what, o->performers, o->frames, o->vectors, o->max_vectors, o->of[0], o->of[1],
           o->frames_both, o->moved);
}

static void test_two_right_hands(void **state)
{
    (void)state;
    run_out alone, grab_alone, merged, two, two_iso;
    const char *in1[] = {claps(NULL)};
    run(in1, 1, false, &alone);
    const char *in1b[] = {grab(NULL)};
    run(in1b, 1, false, &grab_alone);
    const char *in2[] = {claps(NULL), grab(NULL)};
    run(in2, 2, false, &merged);
    const char *in3[] = {claps(NULL), grab("performer=B")};
    run(in3, 2, false, &two);
    run(in3, 2, true, &two_iso);
    say("three-claps right alone", &alone);
    say("grab alone", &grab_alone);
    say("both, no performer= (merge)", &merged);
    say("grab with performer=B", &two);
    say("performer=B, --isolate all", &two_iso);
    assert_int_equal(alone.performers, 1);
    assert_int_equal(merged.performers, 1);
    assert_int_equal(two.performers, 2);

    /* the first performer's right hand: as alone with performer=B, overwritten in the merge */
    size_t both;
    double gap_two = hand_gap(&two, 0, &alone, 0, 0, &both); /* (frame for frame) */
    printf("# first performer's right palm vs three-claps alone: at most %.4g mesh units apart "
           "over %zu frames (performer=B)", gap_two, both);
    assert_true(both > 100);
    double gap_merged = hand_gap(&merged, 0, &alone, 0, 3, &both);
    printf(", %.4g over %zu (merge, the nearest within 3 frames)\n", gap_merged, both);
    assert_true(gap_two == 0);     /* not overwritten: bit for bit as alone */
    assert_true(gap_merged > 2.0); /* the other recording's hand, centimetres away */
    /* B's right hand: as grab alone, placed by its own calibration */
    double gap_b = hand_gap(&two, 1, &grab_alone, 0, 3, &both);
    printf("# B's right palm vs grab alone: at most %.4g mesh units over %zu frames (the nearest "
           "within 3 frames)\n", gap_b, both);
    assert_true(both > 100);
    assert_true(gap_b < 0.5);

    /* both right hands drive vectors (each grabs while the gesture is open: together in a
     * frame or two); the merge's one hand, jumping between the recordings, hardly holds a
     * gesture; another shape */
    assert_true(two.of[0] > 0);
    assert_true(two.of[1] > 0);
    assert_true(two.vectors > 2 * merged.vectors);
    assert_true(two.moved != merged.moved || memcmp(two.shape, merged.shape, two.n * 3 * sizeof(float)));
    /* isolated: both performers' hands reach the helper's mapping: the same shape */
    assert_int_equal(two_iso.performers, 2);
    assert_int_equal(two_iso.vectors, two.vectors);
    assert_memory_equal(two_iso.shape, two.shape, two.n * 3 * sizeof(float));
    /* every input naming one performer is the merge without names, bit for bit */
    run_out same;
    const char *in4[] = {claps("performer=X"), grab("performer=X")};
    run(in4, 2, false, &same);
    say("both performer=X", &same);
    assert_int_equal(same.performers, 1);
    assert_int_equal(same.vectors, merged.vectors);
    assert_memory_equal(same.shape, merged.shape, merged.n * 3 * sizeof(float));
    run_out *all[] = {&alone, &grab_alone, &merged, &two, &two_iso, &same};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) free(all[i]->shape);
}

/* A name on the only performer's inputs changes nothing, bit for bit. */
static void test_one_named_performer(void **state)
{
    (void)state;
    run_out plain, named;
    const char *in1[] = {claps(NULL)};
    run(in1, 1, false, &plain);
    const char *in2[] = {claps("performer=A")};
    run(in2, 1, false, &named);
    say("three-claps", &plain);
    say("three-claps, performer=A", &named);
    assert_int_equal(named.performers, 1);
    assert_true(plain.moved > 0);
    assert_int_equal(plain.vectors, named.vectors);
    assert_int_equal(plain.n, named.n);
    assert_memory_equal(plain.shape, named.shape, plain.n * 3 * sizeof(float));
    free(plain.shape);
    free(named.shape);
}

/* calibration=FILE on B's input places B's hands by it alone: moving its offset by 2 mesh
 * units along x moves B's right palm by that in every frame and leaves the first performer's
 * hands and the frames' count as they were; a missing file, or two files for one performer,
 * is refused naming the input's SPEC. */
static void test_own_calibration(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp-perf-calib-XXXXXX", f1[64], f2[64], spec[2][1200], err[2048];
    assert_non_null(mkdtemp(dir));
    snprintf(f1, sizeof f1, "%s/b1.json", dir);
    snprintf(f2, sizeof f2, "%s/b2.json", dir);
    fp_calibration c = {.scale = 0.1, .offset = {-1, -20, -2}, .rotation = {1, 0, 0, 0}};
    assert_int_equal(fp_calibration_save(f1, &c, NULL, err, sizeof err), 0);
    c.offset[0] += 2;
    assert_int_equal(fp_calibration_save(f2, &c, NULL, err, sizeof err), 0);
    run_out a, b;
    snprintf(spec[0], sizeof spec[0], "performer=B,calibration=%s", f1);
    const char *in1[] = {claps(NULL), grab(spec[0])};
    run(in1, 2, false, &a);
    snprintf(spec[1], sizeof spec[1], "performer=B,calibration=%s", f2);
    const char *in2[] = {claps(NULL), grab(spec[1])};
    run(in2, 2, false, &b);
    assert_int_equal(a.frames, b.frames);
    size_t both = 0;
    double dx_min = INFINITY, dx_max = -INFINITY, other = 0;
    for (size_t k = 0; k < a.frames; k++) {
        assert_int_equal(a.have[0][k], b.have[0][k]);
        if (a.have[0][k]) assert_memory_equal(a.palm[0][k], b.palm[0][k], sizeof a.palm[0][k]);
        if (!a.have[1][k] || !b.have[1][k]) continue;
        both++;
        double dx = (double)b.palm[1][k][0] - a.palm[1][k][0];
        dx_min = fmin(dx_min, dx), dx_max = fmax(dx_max, dx);
        other = fmax(other, fmax(fabs((double)b.palm[1][k][1] - a.palm[1][k][1]),
                                 fabs((double)b.palm[1][k][2] - a.palm[1][k][2])));
    }
    printf("# B's calibration offset +2 along x: B's right palm moved %.6f..%.6f along x, %.2g "
           "across, over %zu frames; the first performer's hands bit for bit\n", dx_min, dx_max, other, both);
    assert_true(both > 100);
    assert_true(fabs(dx_min - 2) < 1e-4 && fabs(dx_max - 2) < 1e-4 && other < 1e-4);
    free(a.shape);
    free(b.shape);
    /* refusals */
    fp_session_options so;
    fp_test_face_options(&so, "anchored", NULL);
    char missing[3000], other_file[3000];
    snprintf(missing, sizeof missing, "%s,performer=B,calibration=%s/none.json", grab(NULL), dir);
    so.inputs[0] = claps(NULL);
    so.inputs[1] = missing;
    so.input_count = 2;
    fp_session *s = NULL;
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), -ENOENT);
    printf("# %s\n", err);
    assert_non_null(strstr(err, missing));
    snprintf(other_file, sizeof other_file, "%s,performer=B,calibration=%s", grab(NULL), f2);
    snprintf(missing, sizeof missing, "%s,performer=B,calibration=%s", claps(NULL), f1);
    so.inputs[0] = missing;
    so.inputs[1] = other_file;
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), -EINVAL);
    printf("# %s\n", err);
    assert_non_null(strstr(err, "one calibration a performer"));
    assert_non_null(strstr(err, other_file));
    unlink(f1);
    unlink(f2);
    rmdir(dir);
}

/* At most FP_PERFORMER_CAPACITY performers: the input that would open a fifth is named. */
static void test_too_many(void **state)
{
    (void)state;
    char in[5][2048];
    const char *inputs[5];
    for (int i = 0; i < 5; i++) {
        snprintf(in[i], sizeof in[i], "replay:%s/hands/leap-motion/grab_joints_mm.csv,performer=P%d",
                 fp_test_data_dir(), i);
        inputs[i] = in[i];
    }
    fp_session_options so;
    fp_test_face_options(&so, "anchored", NULL);
    for (int i = 0; i < 5; i++) so.inputs[i] = inputs[i];
    so.input_count = 5;
    fp_session *s = NULL;
    char err[2048] = "";
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), -EINVAL);
    assert_null(s);
    printf("# %s\n", err);
    assert_non_null(strstr(err, "performer=P4"));
    assert_non_null(strstr(err, in[4]));
    assert_non_null(strstr(err, "at most 4 performers"));
    /* a name that is no name */
    snprintf(in[0], sizeof in[0], "replay:%s/hands/leap-motion/grab_joints_mm.csv,performer=a b",
             fp_test_data_dir());
    so.input_count = 1;
    assert_int_equal(fp_session_create(&so, &s, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "performer=a b"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_right_hands),
        cmocka_unit_test(test_one_named_performer),
        cmocka_unit_test(test_own_calibration),
        cmocka_unit_test(test_too_many),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
