/* Tests of core/rig against the three faces of ../shared/data and broken rig files. */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "csrbf.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_rig_internal.h" /* (test_mobility_brute_force: the ramp) */
#define RIG_CHECK_NO_FOLDS
#include "rig_check.h"

#include <errno.h>
#include <stdbool.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const char *data_dir(void)
{
    const char *d = getenv("FP_SHARED_DATA");
    return d && *d ? d : "../shared/data";
}

static fp_mesh *load_face(const char *rel)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/faces/%s", data_dir(), rel);
    fp_mesh *m = NULL;
    char err[512];
    int rc = fp_mesh_load(path, &m, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    return m;
}

static fp_rig *find_rig(const fp_mesh *m)
{
    char path[4096], err[512];
    int rc = fp_rig_find(FP_TEST_RIGS_DIR, m->vertex_count, m->positions, path, sizeof path, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    fp_rig *r = NULL;
    rc = fp_rig_load_for_mesh(path, m->vertex_count, m->positions, &r, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_true(fp_rig_checksum_matches(r, m->vertex_count, m->positions));
    return r;
}

/* Best rigid fit of the vertices of one kind (rig_check.h, Horn's method). */
static void rigid_fit(const float *a, const float *b, const uint8_t *kinds, int kind, size_t n, double *resid,
                      double *disp, double *angle_deg)
{
    uint8_t *sel = malloc(n);
    assert_non_null(sel);
    for (size_t v = 0; v < n; v++) sel[v] = kinds[v] == kind;
    assert_true(rig_check_rigid_fit(a, b, sel, n, resid, disp, angle_deg, NULL) > 3);
    free(sel);
}

static void assert_skull_still(const fp_rig *r, const float *ref, const float *out)
{
    const uint8_t *kinds = fp_rig_vertex_kinds(r);
    size_t bad = 0;
    for (size_t v = 0; v < fp_rig_vertex_count(r); v++)
        if (kinds[v] == FP_RIG_SKULL && memcmp(&ref[3 * v], &out[3 * v], 3 * sizeof(float))) bad++;
    assert_int_equal(bad, 0);
}

static void test_ict_pose(void **state)
{
    (void)state;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    fp_rig *r = find_rig(m);
    assert_string_equal(fp_rig_name(r), "ict-facekit");
    size_t n = m->vertex_count;
    float *out = malloc(n * 3 * sizeof *out);
    float vals[FP_RIG_MAX_CHANNELS];
    const char *names[] = {"jaw.open", "no.such"};
    const float v1[] = {1.0f, 3.0f};
    assert_int_equal(fp_rig_channel_values(r, names, v1, 2, vals), 1);
    assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
    assert_skull_still(r, m->positions, out);
    double resid, disp, angle, deg;
    fp_rig_hinge(r, NULL, NULL, &deg, NULL);
    rigid_fit(m->positions, out, fp_rig_vertex_kinds(r), FP_RIG_JAW, n, &resid, &disp, &angle);
    printf("ICT jaw.open=1: lower jaw residual %.3g (%.4f%% of displacement %.3f), angle %.3f (rig %.1f)\n",
           resid, 100 * resid / disp, disp, angle, deg);
    assert_true(resid < 0.01 * disp);
    assert_true(fabs(angle - deg) < 0.5);
    /* out of range values are clamped: 3 behaves as 1 */
    float *out2 = malloc(n * 3 * sizeof *out2);
    vals[fp_rig_channel_index(r, "jaw.open")] = 3.0f;
    fp_rig_pose(r, m->positions, vals, out2);
    assert_memory_equal(out, out2, n * 3 * sizeof *out);
    /* the command line refuses them */
    char err[256];
    assert_int_equal(fp_rig_channel_check(r, "jaw.open", 1.5, err, sizeof err), -ERANGE);
    assert_non_null(strstr(err, "jaw.open"));
    assert_int_equal(fp_rig_channel_check(r, "jaw.shut", 0.5, err, sizeof err), -ENOENT);
    /* landmarks: the chin goes down and back, the upper lip stays, the lower lip follows */
    long chin = fp_rig_landmark_index(r, "chin"), ul = fp_rig_landmark_index(r, "upper_lip"),
         ll = fp_rig_landmark_index(r, "lower_lip"), nose = fp_rig_landmark_index(r, "nose_tip");
    assert_true(chin >= 0 && ul >= 0 && ll >= 0 && nose >= 0);
    assert_true(out[3 * chin + 1] < m->positions[3 * chin + 1] - 1.0); /* down > 1 cm */
    assert_true(out[3 * chin + 2] < m->positions[3 * chin + 2]);       /* back */
    assert_true(fabsf(out[3 * ul + 1] - m->positions[3 * ul + 1]) < 0.05f);
    assert_true(out[3 * ll + 1] < m->positions[3 * ll + 1] - 0.8);
    assert_memory_equal(&out[3 * nose], &m->positions[3 * nose], 3 * sizeof(float));
    /* neutral pose is the base, bit for bit */
    fp_rig_pose(r, m->positions, NULL, out2);
    assert_memory_equal(m->positions, out2, n * 3 * sizeof *out);
    free(out), free(out2);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

/* Fingers pressing on the forehead with the jaw fully open, through the engine. */
static void test_ict_fingers(void **state)
{
    (void)state;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    fp_rig *r = find_rig(m);
    size_t n = m->vertex_count;
    float *posed = malloc(n * 3 * sizeof *posed), *warped = malloc(n * 3 * sizeof *warped),
          *out = malloc(n * 3 * sizeof *out);
    float vals[FP_RIG_MAX_CHANNELS];
    fp_rig_channel_values(r, NULL, NULL, 0, vals);
    vals[fp_rig_channel_index(r, "jaw.open")] = 1.0f;
    assert_int_equal(fp_rig_pose(r, m->positions, vals, posed), 0);
    /* five fingertips on the forehead above the brows, pushed 1 cm into the head, and one on
     * the chin pushed up: R = 4 cm (the supports reach the brows and the lower lip) */
    long brow_l = fp_rig_landmark_index(r, "brow_left"), brow_r = fp_rig_landmark_index(r, "brow_right"),
         chin = fp_rig_landmark_index(r, "chin");
    float up[3], fwd[3];
    fp_rig_axes(r, up, fwd, NULL);
    float start[6][3], end[6][3];
    for (int f = 0; f < 5; f++) {
        double t = f / 4.0;
        for (int i = 0; i < 3; i++) {
            start[f][i] = (float)((1 - t) * posed[3 * brow_r + i] + t * posed[3 * brow_l + i] + 2.0 * up[i]);
            end[f][i] = start[f][i] - 1.0f * fwd[i];
        }
    }
    for (int i = 0; i < 3; i++) start[5][i] = posed[3 * chin + i], end[5][i] = start[5][i] + 0.8f * up[i];
    csrbf_options o = {0};
    o.radius = 4.0;
    csrbf_solver *s = NULL;
    csrbf_points *pts = NULL;
    assert_int_equal(csrbf_solver_create(&o, &s), 0);
    assert_true(csrbf_solver_solve(s, 6, &start[0][0], &end[0][0]) >= 0);
    assert_int_equal(csrbf_points_create(n, posed, &pts), 0);
    csrbf_eval_stats st;
    assert_int_equal(csrbf_evaluate(s, pts, warped, 0, &st), 0);
    assert_true(st.max_displacement > 0.5); /* the fingers did move the raw map */
    assert_int_equal(fp_rig_apply_mobility(r, posed, warped, out), 0);
    assert_skull_still(r, posed, out);
    /* every skull vertex is also bit-identical to the posed base, which is the base itself */
    assert_skull_still(r, m->positions, out);
    double resid, disp, angle, deg;
    fp_rig_hinge(r, NULL, NULL, &deg, NULL);
    rigid_fit(m->positions, out, fp_rig_vertex_kinds(r), FP_RIG_JAW, n, &resid, &disp, &angle);
    printf("ICT fingers + jaw.open=1: jaw residual %.3g = %.4f%% of %.3f, angle %.3f (rig %.1f)\n", resid,
           100 * resid / disp, disp, angle, deg);
    assert_true(resid < 0.01 * disp);
    assert_true(fabs(angle - deg) < 0.5);
    /* soft tissue under the fingers did move: the brows went in */
    double moved = 0;
    const float *mob = fp_rig_mobility(r);
    for (size_t v = 0; v < n; v++)
        if (mob[v] > 0.5f) moved = fmax(moved, fabs(out[3 * v + 2] - posed[3 * v + 2]));
    assert_true(moved > 0.2);
    csrbf_points_destroy(&pts);
    csrbf_solver_destroy(&s);
    free(posed), free(warped), free(out);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

/* The local finger clamp: |grad m| per vertex against a brute-force distance to the nearest
 * rigid vertex; a finger on the cheek (its support reaches no bone's ramp) is free up to the
 * engine's 0.45 R and moves the skin that far; a finger on the lower lip, near the teeth, is
 * limited to 1/2 over the steepest slope its support reaches. */
static double ref_limit(const fp_rig *r, const float *pos, size_t n, const double *slope, const float c[3], double R)
{
    (void)r;
    double g = 0;
    for (size_t v = 0; v < n; v++) {
        double d = 0;
        for (int i = 0; i < 3; i++) d += (pos[3 * v + i] - c[i]) * (pos[3 * v + i] - c[i]);
        if (d < R * R) g = fmax(g, slope[v]);
    }
    return g > 0 ? FP_RIG_FINGER_MARGIN / g : INFINITY;
}

static void test_ict_finger_limit(void **state)
{
    (void)state;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    fp_rig *r = find_rig(m);
    size_t n = m->vertex_count;
    const float *pos = m->positions, *g = fp_rig_mobility_slope(r);
    const uint8_t *kind = fp_rig_vertex_kinds(r);
    double ramp = 3 * fp_rig_max_finger_displacement(r);
    /* reference slopes: 6 t (1 - t) / ramp of the brute-force distance to the nearest rigid vertex */
    size_t nrigid = 0;
    uint32_t *rigid = malloc(n * sizeof *rigid);
    double *slope = calloc(n, sizeof *slope);
    for (size_t v = 0; v < n; v++)
        if (kind[v] != FP_RIG_SOFT) rigid[nrigid++] = (uint32_t)v;
    for (size_t v = 0; v < n; v++) {
        if (kind[v] != FP_RIG_SOFT) continue;
        double best = INFINITY;
        for (size_t k = 0; k < nrigid; k++) {
            double d = 0;
            for (int i = 0; i < 3; i++) d += pow(pos[3 * rigid[k] + i] - pos[3 * v + i], 2);
            best = fmin(best, d);
        }
        double t = sqrt(best) / ramp;
        slope[v] = t > 0 && t < 1 ? 6 * t * (1 - t) / ramp : 0;
        assert_true(fabs(g[v] - slope[v]) < 1e-4 / ramp);
    }
    double R = 1.5; /* cm */
    /* the cheek: the skin vertex nearest (4.5, -1.5, 8.5) cm, 2 cm beside the mouth corner */
    float q[3] = {4.5f, -1.5f, 8.5f};
    size_t cheek = 0;
    double best = INFINITY;
    for (size_t v = 0; v < 9409; v++) {
        double d = pow(pos[3 * v] - q[0], 2) + pow(pos[3 * v + 1] - q[1], 2) + pow(pos[3 * v + 2] - q[2], 2);
        if (d < best) best = d, cheek = v;
    }
    double lim_cheek = fp_rig_finger_limit(r, pos, &pos[3 * cheek], R);
    assert_true(isinf(ref_limit(r, pos, n, slope, &pos[3 * cheek], R)));
    assert_true(isinf(lim_cheek));
    /* the lower lip's inner edge, a few mm from the lower teeth */
    long lip = fp_rig_landmark_index(r, "lower_lip_inner");
    double lim_lip = fp_rig_finger_limit(r, pos, &pos[3 * lip], R), ref_lip = ref_limit(r, pos, n, slope, &pos[3 * lip], R);
    printf("finger limit (R = %.1f cm): cheek vertex %zu unlimited (0.45 R = %.3f cm applies); lower lip %.4f cm "
           "(reference %.4f, global ramp/3 %.4f)\n", R, cheek, 0.45 * R, lim_lip, ref_lip, ramp / 3);
    assert_true(fabs(lim_lip - ref_lip) < 1e-4 * ref_lip);
    assert_true(lim_lip < 0.45 * R && lim_lip >= ramp / 3 * (1 - 1e-6));
    /* the cheek finger pushed 0.45 R into the face: the skin under it moves that far */
    float fwd[3];
    fp_rig_axes(r, NULL, fwd, NULL);
    float start[3], end[3];
    for (int i = 0; i < 3; i++) start[i] = pos[3 * cheek + i], end[i] = start[i] - (float)(0.45 * R) * fwd[i];
    csrbf_options o = {0};
    o.radius = R;
    csrbf_solver *s = NULL;
    csrbf_points *pts = NULL;
    float *warped = malloc(n * 3 * sizeof *warped), *out = malloc(n * 3 * sizeof *out);
    assert_int_equal(csrbf_solver_create(&o, &s), 0);
    assert_true(csrbf_solver_solve(s, 1, start, end) >= 0);
    assert_int_equal(csrbf_points_create(n, pos, &pts), 0);
    assert_int_equal(csrbf_evaluate(s, pts, warped, 0, NULL), 0);
    assert_int_equal(fp_rig_apply_mobility(r, pos, warped, out), 0);
    double d = 0;
    for (int i = 0; i < 3; i++) d += pow(out[3 * cheek + i] - pos[3 * cheek + i], 2);
    printf("cheek finger: the skin under it moved %.4f cm (0.45 R = %.4f)\n", sqrt(d), 0.45 * R);
    assert_true(fabs(sqrt(d) - 0.45 * R) < 1e-4);
    csrbf_points_destroy(&pts);
    csrbf_solver_destroy(&s);
    free(warped), free(out), free(rigid), free(slope);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

static void other_face(const char *rel, const char *name)
{
    fp_mesh *m = load_face(rel);
    fp_rig *r = find_rig(m);
    assert_string_equal(fp_rig_name(r), name);
    size_t n = m->vertex_count;
    float *out = malloc(n * 3 * sizeof *out);
    float vals[FP_RIG_MAX_CHANNELS];
    fp_rig_channel_values(r, NULL, NULL, 0, vals);
    vals[fp_rig_channel_index(r, "jaw.open")] = 1.0f;
    assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
    assert_skull_still(r, m->positions, out);
    long chin = fp_rig_landmark_index(r, "chin");
    float up[3];
    fp_rig_axes(r, up, NULL, NULL);
    double dy = 0;
    for (int i = 0; i < 3; i++) dy += (out[3 * chin + i] - m->positions[3 * chin + i]) * up[i];
    printf("%s: chin moves %.2f mm along up at jaw.open=1\n", name, dy * fp_rig_mm_per_unit(r));
    assert_true(dy * fp_rig_mm_per_unit(r) < -10); /* down by more than 1 cm */
    double resid, disp, angle, deg;
    fp_rig_hinge(r, NULL, NULL, &deg, NULL);
    rigid_fit(m->positions, out, fp_rig_vertex_kinds(r), FP_RIG_JAW, n, &resid, &disp, &angle);
    assert_true(resid < 0.01 * disp);
    assert_true(fabs(angle - deg) < 0.5);
    free(out);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

/* The blocked finger limit (fp_rig_slope_index) against the full scan, bit for bit: the ICT
 * face at rest and with the jaw open, start points on the surface and off it, radii from a
 * few millimetres to beyond the head, and after ranged moves of the posed base (the boxes
 * grow: a session's ranged commits); also the ranged pose and unpose against the whole ones. */
#define LRNG_SEED 0x9e3779b97f4a7c15ull
static uint64_t lrng = LRNG_SEED; /* each test that draws starts from the seed */
static double lrand(void)
{
    lrng ^= lrng << 13;
    lrng ^= lrng >> 7;
    lrng ^= lrng << 17;
    return (double)(lrng >> 11) / 9007199254740992.0;
}

static size_t check_limits(const fp_rig *r, const fp_rig_slope_index *ix, const float *posed, size_t n)
{
    static const double radii[] = {0.3, 0.8, 1.5, 2.5, 4.0, 40.0};
    size_t finite = 0;
    for (int q = 0; q < 400; q++) {
        size_t v = (size_t)(lrand() * (double)n) % n;
        float start[3];
        for (int i = 0; i < 3; i++) start[i] = posed[3 * v + i] + (q % 2 ? (float)(lrand() - 0.5) : 0.f);
        for (size_t k = 0; k < sizeof radii / sizeof radii[0]; k++) {
            double full = fp_rig_finger_limit(r, posed, start, radii[k]);
            double fast = fp_rig_finger_limit_indexed(ix, start, radii[k]);
            if (memcmp(&full, &fast, sizeof full))
                fail_msg("vertex %zu, R %g: indexed %.17g, full scan %.17g", v, radii[k], fast, full);
            finite += isfinite(full);
            /* the directional limit toward an end point in a random direction, from a few
             * millimetres to a few centimetres away: its blocks skipped by their directions'
             * box and the Wendland weight at their gap, the result still the full scan's */
            float end[3];
            double len = 0.05 + 3 * lrand();
            for (int i = 0; i < 3; i++) end[i] = start[i] + (float)(len * (lrand() - 0.5));
            full = fp_rig_finger_limit_toward(r, posed, start, end, radii[k]);
            fast = fp_rig_finger_limit_toward_indexed(ix, start, end, radii[k]);
            if (memcmp(&full, &fast, sizeof full))
                fail_msg("vertex %zu, R %g: toward, indexed %.17g, full scan %.17g", v, radii[k], fast, full);
            /* the clamp: end kept where within that limit, else a vector within the full
             * scan's limit for itself, the push cut or (rounds unsettled) scaled */
            float out[3];
            int rc = fp_rig_finger_clamp_indexed(ix, start, end, radii[k], out);
            double asked = 0, got = 0;
            for (int i = 0; i < 3; i++) {
                asked += ((double)end[i] - start[i]) * ((double)end[i] - start[i]);
                got += ((double)out[i] - start[i]) * ((double)out[i] - start[i]);
            }
            assert_int_equal(rc == 0, !(sqrt(asked) > full));
            if (rc == 0) assert_memory_equal(out, end, sizeof out);
            else assert_true(sqrt(got) <= fp_rig_finger_limit_toward(r, posed, start, out, radii[k]) * (1 + 1e-6) + 1e-7);
        }
        /* no support (radius 0): the global bound, ramp / 3, as the limit says */
        float end[3] = {start[0] + 5.f, start[1], start[2]}, out[3];
        assert_int_equal(fp_rig_finger_clamp_indexed(ix, start, end, 0, out), 2);
        assert_float_equal(out[0] - start[0], fp_rig_max_finger_displacement(r), 1e-5);
    }
    return finite;
}

/* The clamp moves continuously with the end point: a finger dragging on from a start point
 * on the ICT face (at rest and with the jaw open) in steps of 0.05 mm, its support widened
 * with the drag as the anchored mapping widens it (twice the drag, at least R), never makes
 * the clamped end jump: each step's clamped end moves at most 30x as far as the asked end
 * (its weights grow with the support; over 40 seeds of the 80 drags, the most was 5.9-13.8x,
 * at most 0.69 mm). The clamp whose constraints were weighed on each cut vector's own
 * capsule moved 375x (18.8 mm in one step). The test draws from its own seed, so the tests
 * before it do not choose its drags. */
static void test_ict_clamp_continuous(void **state)
{
    (void)state;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    fp_rig *r = find_rig(m);
    size_t n = m->vertex_count;
    float *posed = malloc(n * 3 * sizeof *posed);
    assert_non_null(posed);
    fp_rig_slope_index *ix = NULL;
    assert_int_equal(fp_rig_slope_index_create(r, &ix), 0);
    float vals[FP_RIG_MAX_CHANNELS] = {0};
    long jo = fp_rig_channel_index(r, "jaw.open");
    const double R = 2.85, step = 0.005; /* the session's R on this face; 0.05 mm steps */
    lrng = LRNG_SEED;
    double worst = 0, jump = 0;
    size_t steps = 0, cut = 0;
    for (int o = 0; o < 2; o++) {
        vals[jo] = o ? 0.7f : 0.f;
        assert_int_equal(fp_rig_pose(r, m->positions, vals, posed), 0);
        fp_rig_slope_index_set(ix, posed);
        for (int q = 0; q < 40; q++) {
            size_t v = (size_t)(lrand() * (double)n) % n;
            const float *start = &posed[3 * v];
            double d[3], dn = 0;
            for (int i = 0; i < 3; i++) {
                d[i] = lrand() - 0.5;
                dn += d[i] * d[i];
            }
            float prev[3];
            memcpy(prev, start, sizeof prev);
            for (double len = step; len <= 5.0; len += step) {
                float end[3], out[3];
                for (int i = 0; i < 3; i++) end[i] = start[i] + (float)(len * d[i] / sqrt(dn));
                cut += fp_rig_finger_clamp_indexed(ix, start, end, fmax(R, 2 * len), out) != 0;
                double moved = 0;
                for (int i = 0; i < 3; i++) moved += ((double)out[i] - prev[i]) * ((double)out[i] - prev[i]);
                worst = fmax(worst, sqrt(moved) / step);
                jump = fmax(jump, sqrt(moved));
                memcpy(prev, out, sizeof prev);
                steps++;
            }
        }
    }
    printf("clamp continuity: %zu steps of %.3f (%zu cut): the clamped end moved at most %.2fx the step "
           "(%.4f mesh units)\n", steps, step, cut, worst, jump);
    assert_true(cut > steps / 10);
    assert_true(worst <= 30.0);
    fp_rig_slope_index_destroy(&ix);
    free(posed);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

static void test_ict_finger_limit_indexed(void **state)
{
    (void)state;
    lrng = LRNG_SEED;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    fp_rig *r = find_rig(m);
    size_t n = m->vertex_count;
    float *posed = malloc(n * 3 * sizeof *posed), *ranged = malloc(n * 3 * sizeof *ranged);
    float *un = malloc(n * 3 * sizeof *un), *un_ranged = malloc(n * 3 * sizeof *un_ranged);
    assert_true(posed && ranged && un && un_ranged);
    fp_rig_slope_index *ix = NULL;
    assert_int_equal(fp_rig_slope_index_create(NULL, &ix), -EINVAL);
    assert_int_equal(fp_rig_slope_index_create(r, &ix), 0);
    float vals[FP_RIG_MAX_CHANNELS] = {0};
    long jo = fp_rig_channel_index(r, "jaw.open");
    assert_true(jo >= 0);
    static const float opens[] = {0.f, 0.7f};
    for (int o = 0; o < 2; o++) {
        vals[jo] = opens[o];
        assert_int_equal(fp_rig_pose(r, m->positions, vals, posed), 0);
        /* the ranged pose in uneven pieces = the whole pose */
        memset(ranged, 0xff, n * 3 * sizeof *ranged);
        for (size_t v0 = 0; v0 < n;) {
            size_t c = 1 + (size_t)(lrand() * 700);
            if (c > n - v0) c = n - v0;
            assert_int_equal(fp_rig_pose_range(r, m->positions, vals, ranged, v0, c), 0);
            v0 += c;
        }
        assert_memory_equal(ranged, posed, n * 3 * sizeof *posed);
        assert_int_equal(fp_rig_pose_range(r, m->positions, vals, ranged, n, 1), -EINVAL);
        struct timespec t0, t1, t2;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        fp_rig_slope_index_set(ix, posed);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double full_ms = 0, fast_ms = 0, sink = 0;
        for (int q = 0; q < 300; q++) { /* the cost, for the record (not asserted) */
            const float *st = &posed[3 * ((size_t)(lrand() * (double)n) % n)];
            clock_gettime(CLOCK_MONOTONIC, &t1);
            sink += fp_rig_finger_limit(r, posed, st, 1.2);
            clock_gettime(CLOCK_MONOTONIC, &t2);
            full_ms += (double)(t2.tv_sec - t1.tv_sec) * 1e3 + (double)(t2.tv_nsec - t1.tv_nsec) / 1e6;
            sink += fp_rig_finger_limit_indexed(ix, st, 1.2);
            clock_gettime(CLOCK_MONOTONIC, &t1);
            fast_ms += (double)(t1.tv_sec - t2.tv_sec) * 1e3 + (double)(t1.tv_nsec - t2.tv_nsec) / 1e6;
        }
        printf("finger limit, jaw.open %.1f, R 1.2 cm: full scan %.4f ms, indexed %.4f ms per query (%g)\n",
               opens[o], full_ms / 300, fast_ms / 300, sink > 0 ? 1.0 : 0.0);
        size_t finite = check_limits(r, ix, posed, n);
        printf("finger limit, jaw.open %.1f: indexed = full scan on 2400 queries (%zu limited)\n", opens[o], finite);
        assert_true(finite > 100);
        /* ranged moves of the posed base (a commit's pieces): boxes grow, limits still equal */
        uint32_t rg[2 * 6];
        for (int j = 0; j < 6; j++) {
            rg[2 * j] = (uint32_t)(j * (n / 6) + (size_t)(lrand() * 1000));
            rg[2 * j + 1] = 64 + (uint32_t)(lrand() * 400);
            for (uint32_t v = rg[2 * j]; v < rg[2 * j] + rg[2 * j + 1]; v++)
                for (int i = 0; i < 3; i++) posed[3 * v + i] += (float)(0.3 * (lrand() - 0.5));
        }
        fp_rig_slope_index_update_ranges(ix, posed, rg, 6);
        check_limits(r, ix, posed, n);
        /* the same skin dragged 2.5 cm aside and back: the boxes, made again from their
         * vertices, follow it there and back (a box left where the skin was would skip it
         * come back: the limits would differ from the full scan). */
        for (int way = 0; way < 2; way++) {
            for (int j = 0; j < 6; j++)
                for (uint32_t v = rg[2 * j]; v < rg[2 * j] + rg[2 * j + 1]; v++)
                    posed[3 * v] += way ? -2.5f : 2.5f;
            fp_rig_slope_index_update_ranges(ix, posed, rg, 6);
            check_limits(r, ix, posed, n);
        }
        /* a long performance, for the record: 300 drags of 500 vertices each 2.5 cm aside and
         * back over the whole face, then the queries' cost (boxes that only grew would now
         * span the drags' paths) */
        for (int d = 0; d < 300; d++) {
            uint32_t one[2] = {(uint32_t)((size_t)(lrand() * (double)(n - 500))), 500};
            for (int way = 0; way < 2; way++) {
                for (uint32_t v = one[0]; v < one[0] + one[1]; v++)
                    posed[3 * v + (size_t)(d % 3)] += way ? -2.5f : 2.5f;
                fp_rig_slope_index_update_ranges(ix, posed, one, 1);
            }
        }
        check_limits(r, ix, posed, n);
        double back_ms = 0; /* the queries' cost once the skin is back, for the record */
        for (int q = 0; q < 300; q++) {
            const float *st = &posed[3 * ((size_t)(lrand() * (double)n) % n)];
            clock_gettime(CLOCK_MONOTONIC, &t1);
            float end[3] = {st[0] + 0.5f, st[1], st[2]};
            sink += fp_rig_finger_limit_toward_indexed(ix, st, end, 1.2);
            clock_gettime(CLOCK_MONOTONIC, &t2);
            back_ms += (double)(t2.tv_sec - t1.tv_sec) * 1e3 + (double)(t2.tv_nsec - t1.tv_nsec) / 1e6;
        }
        printf("finger limit toward, jaw.open %.1f, R 1.2 cm, after 300 drags of skin 2.5 cm aside and back: "
               "%.4f ms per query (%g)\n", opens[o], back_ms / 300, sink > 0 ? 1.0 : 0.0);
        /* the ranged unpose = the whole one where shown moved, the base where it did not */
        assert_int_equal(fp_rig_pose(r, m->positions, vals, ranged), 0); /* unmoved posed */
        assert_int_equal(fp_rig_unpose(r, m->positions, vals, posed, un), 0);
        memcpy(un_ranged, un, n * 3 * sizeof *un);
        for (int j = 0; j < 6; j++)
            assert_int_equal(fp_rig_unpose_range(r, m->positions, ranged, vals, posed, un_ranged, rg[2 * j],
                                                 rg[2 * j + 1]), 0);
        assert_memory_equal(un_ranged, un, n * 3 * sizeof *un);
        size_t drift = 0;
        assert_int_equal(fp_rig_unpose_range(r, m->positions, ranged, vals, posed, un_ranged, 0, n), 0);
        for (size_t v = 0; v < n; v++) {
            bool moved = memcmp(&posed[3 * v], &ranged[3 * v], 3 * sizeof(float)) != 0;
            if (!moved) {
                assert_memory_equal(&un_ranged[3 * v], &m->positions[3 * v], 3 * sizeof(float));
                drift += memcmp(&un[3 * v], &m->positions[3 * v], 3 * sizeof(float)) != 0;
            } else {
                assert_memory_equal(&un_ranged[3 * v], &un[3 * v], 3 * sizeof(float));
            }
        }
        printf("unpose, jaw.open %.1f: %zu unmoved vertices the plain unpose moves by its round trip, "
               "kept by the posed-aware one\n", opens[o], drift);
        if (o == 0) assert_int_equal(drift, 0);
    }
    fp_rig_slope_index_destroy(&ix);
    assert_null(ix);
    free(posed);
    free(ranged);
    free(un);
    free(un_ranged);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

/* The mobility m and its slope |grad m| (fp_rig_bind; the nearest rigid vertex found by a k-d
 * tree, core/rig/fp_rig_near.c) against a brute-force search over every skull and jaw vertex,
 * the same arithmetic (float differences, squared and summed in double): equal bit for bit on
 * each face with its rig. (The ramp is read from the rig's insides, fp_rig_internal.h: ramp / 3
 * times 3 need not give it back to the bit.) */
static double smooth01(double x) { return x <= 0 ? 0 : x >= 1 ? 1 : x * x * (3 - 2 * x); }

static void mobility_is_brute_force(const char *rel)
{
    fp_mesh *m = load_face(rel);
    fp_rig *r = find_rig(m);
    size_t n = m->vertex_count, soft = 0, sloped = 0;
    const uint8_t *kind = fp_rig_vertex_kinds(r);
    const float *mob = fp_rig_mobility(r), *g = fp_rig_mobility_slope(r), *p = m->positions;
    double ramp = r->geom.ramp;
    for (size_t v = 0; v < n; v++) {
        if (kind[v] != FP_RIG_SOFT) {
            assert_true(mob[v] == 0);
            continue;
        }
        soft++;
        double best = INFINITY;
        for (size_t u = 0; u < n; u++) {
            if (kind[u] == FP_RIG_SOFT) continue;
            double d0 = p[3 * u] - p[3 * v], d1 = p[3 * u + 1] - p[3 * v + 1], d2 = p[3 * u + 2] - p[3 * v + 2];
            double e = d0 * d0 + d1 * d1 + d2 * d2;
            if (e < best) best = e;
        }
        double d = sqrt(best), t = d / ramp;
        float want_m = (float)smooth01(t), want_g = t > 0 && t < 1 ? (float)(6 * t * (1 - t) / ramp) : 0.0f;
        if (mob[v] != want_m || g[v] != want_g)
            fail_msg("%s: vertex %zu: m %.9g g %.9g, brute force %.9g %.9g", rel, v, mob[v], g[v], want_m, want_g);
        sloped += g[v] > 0;
    }
    printf("%s: mobility of %zu soft vertices (%zu on the ramp) equal to the brute force's\n", rel, soft, sloped);
    assert_true(sloped > 0);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

static void test_mobility_brute_force(void **state)
{
    (void)state;
    mobility_is_brute_force("ict-facekit/generic_neutral_mesh.obj");
    mobility_is_brute_force("lee-perry-smith/LeePerrySmith.obj");
    mobility_is_brute_force("mediapipe-canonical/canonical_face_model.obj");
}

static void test_lee_perry_smith(void **state)
{
    (void)state;
    other_face("lee-perry-smith/LeePerrySmith.obj", "lee-perry-smith");
}

static void test_mediapipe(void **state)
{
    (void)state;
    other_face("mediapipe-canonical/canonical_face_model.obj", "mediapipe-canonical");
}

/* A copy of a rig's mesh split at seams (fp_rig_match_positions, fp_rig_remap): the
 * MediaPipe face's vertices in reverse order, every 10th one written twice more at the end
 * (515 for 468). Every vertex finds its rig vertex; the remapped rig gives each its rig
 * vertex's kind and poses it where the rig poses that vertex on the mesh itself; a landmark
 * goes to its vertex's first copy. A copy without a landmark's vertex is refused by name,
 * the rig unchanged. */
static void test_split_copy(void **state)
{
    (void)state;
    fp_mesh *m = load_face("mediapipe-canonical/canonical_face_model.obj");
    fp_rig *r = find_rig(m);
    const size_t n = m->vertex_count, extra = (n + 9) / 10, n2 = n + extra;
    float *pos = malloc(n2 * 3 * sizeof *pos), *out = malloc(n * 3 * sizeof *out);
    float *out2 = malloc(n2 * 3 * sizeof *out2);
    uint32_t *map = malloc(n2 * sizeof *map), want[1024];
    assert_true(pos && out && out2 && map && n2 <= 1024);
    for (size_t i = 0; i < n; i++) want[i] = (uint32_t)(n - 1 - i);
    for (size_t k = 0; k < extra; k++) want[n + k] = (uint32_t)(10 * k);
    for (size_t i = 0; i < n2; i++) memcpy(pos + 3 * i, m->positions + 3 * want[i], 3 * sizeof(float));
    assert_int_equal(fp_rig_match_positions(n, m->positions, n2, pos, map), 0);
    for (size_t i = 0; i < n2; i++) /* (coincident vertices: the lowest) */
        assert_memory_equal(m->positions + 3 * map[i], m->positions + 3 * want[i], 3 * sizeof(float));
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s", fp_rig_source(r));
    fp_rig *s = NULL;
    assert_int_equal(fp_rig_load(path, &s, err, sizeof err), 0);
    assert_int_equal(fp_rig_remap(s, n2, map, pos, err, sizeof err), 0);
    assert_int_equal(fp_rig_bind(s, n2, pos, err, sizeof err), 0);
    assert_int_equal(fp_rig_vertex_count(s), n2);
    assert_true(fp_rig_checksum_matches(s, n2, pos));
    const uint8_t *k1 = fp_rig_vertex_kinds(r), *k2 = fp_rig_vertex_kinds(s);
    for (size_t i = 0; i < n2; i++) assert_int_equal(k2[i], k1[map[i]]);
    for (size_t l = 0; l < fp_rig_landmark_count(r); l++) {
        const char *name;
        uint32_t v1, v2;
        assert_int_equal(fp_rig_landmark_get(r, l, &name, &v1), 0);
        assert_int_equal(fp_rig_landmark_get(s, l, &name, &v2), 0);
        assert_int_equal(v2, n - 1 - v1); /* its first copy: the reversed vertex */
    }
    float vals[FP_RIG_MAX_CHANNELS], vals2[FP_RIG_MAX_CHANNELS];
    const char *names[] = {"jaw.open"};
    const float v[] = {0.6f};
    fp_rig_channel_values(r, names, v, 1, vals);
    fp_rig_channel_values(s, names, v, 1, vals2);
    assert_int_equal(fp_rig_pose(r, m->positions, vals, out), 0);
    assert_int_equal(fp_rig_pose(s, pos, vals2, out2), 0);
    size_t moved = 0;
    for (size_t i = 0; i < n2; i++) {
        assert_memory_equal(out2 + 3 * i, out + 3 * map[i], 3 * sizeof(float));
        moved += memcmp(out2 + 3 * i, pos + 3 * i, 3 * sizeof(float)) != 0;
    }
    assert_true(moved > n / 10);
    fp_rig_free(&s);
    /* without the chin's vertex (its copies too): refused by the landmark's name */
    const long c = fp_rig_landmark_index(r, "chin");
    assert_true(c >= 0);
    const uint32_t chin = (uint32_t)c;
    size_t n3 = 0;
    for (size_t i = 0; i < n2; i++)
        if (map[i] != chin) map[n3] = map[i], memcpy(pos + 3 * n3, pos + 3 * i, 3 * sizeof(float)), n3++;
    assert_int_equal(fp_rig_load(path, &s, err, sizeof err), 0);
    assert_int_equal(fp_rig_remap(s, n3, map, pos, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "landmark chin"));
    assert_int_equal(fp_rig_vertex_count(s), n);
    fp_rig_free(&s);
    /* a vertex at no rig vertex's position */
    pos[0] += 1e-3f;
    assert_int_equal(fp_rig_match_positions(n, m->positions, n3, pos, map), 1);
    assert_int_equal(map[0], UINT32_MAX);
    free(pos), free(out), free(out2), free(map);
    fp_rig_free(&r);
    fp_mesh_free(&m);
}

static char *read_text(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long l = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)l + 1);
    assert_int_equal(fread(b, 1, (size_t)l, f), (size_t)l);
    b[l] = 0;
    fclose(f);
    *len = (size_t)l;
    return b;
}

/* Replace the first occurrence of `from` by `to` in text (a new string). */
static char *edit(const char *text, const char *from, const char *to)
{
    const char *p = strstr(text, from);
    assert_non_null(p);
    size_t a = (size_t)(p - text), lf = strlen(from), lt = strlen(to), lt0 = strlen(text);
    char *o = malloc(lt0 - lf + lt + 1);
    memcpy(o, text, a);
    memcpy(o + a, to, lt);
    memcpy(o + a + lt, p + lf, lt0 - a - lf + 1);
    return o;
}

/* A rig folder whose only rig for the mesh has an error: fp_rig_find skips it, and says so
 * (the file and the JSON path), not only "no rig fits this mesh" (an artist's own rig in
 * $FACEPUPPET_RIGS was skipped without a word). */
static void test_find_names_unread(void **state)
{
    (void)state;
    size_t len;
    char *good = read_text(FP_TEST_RIGS_DIR "/mediapipe-canonical.json", &len);
    char *bad = edit(good, "\"open_degrees\": 29.9", "\"open_degrees\": \"30\"");
    fp_mesh *m = load_face("mediapipe-canonical/canonical_face_model.obj"); /* (first: no folder left) */
    char dir[] = "/tmp/fp-test-rig-find-XXXXXX", path[4096], found[4096], err[1024];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/mine.json", dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bad, 1, strlen(bad), f), strlen(bad));
    assert_int_equal(fclose(f), 0);
    int rc = fp_rig_find(dir, m->vertex_count, m->positions, found, sizeof found, err, sizeof err);
    printf("find in a folder of one broken rig: %s\n", err);
    remove(path);
    rmdir(dir);
    assert_int_equal(rc, -ENOENT);
    assert_non_null(strstr(err, "no rig fits this mesh"));
    assert_non_null(strstr(err, "mine.json"));
    assert_non_null(strstr(err, "jaw.open_degrees"));
    fp_mesh_free(&m);
    free(bad);
    free(good);
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, strlen(text), f), strlen(text));
    assert_int_equal(fclose(f), 0);
}

/* A rig folder of many files is read whole (fp_rig_find read the first 512 in readdir's
 * order, so a rig past them was not found), and two rigs with the mesh's checksum are both
 * named, not the first by name taken without a word. */
static void test_find_all_and_twins(void **state)
{
    (void)state;
    size_t len;
    char *good = read_text(FP_TEST_RIGS_DIR "/mediapipe-canonical.json", &len);
    fp_mesh *m = load_face("mediapipe-canonical/canonical_face_model.obj");
    char dir[] = "/tmp/fp-test-rig-many-XXXXXX", path[4096], found[4096], err[1024];
    assert_non_null(mkdtemp(dir));
    enum { JUNK = 600 };
    for (int i = 0; i < JUNK; i++) {
        snprintf(path, sizeof path, "%s/junk%03d.json", dir, i);
        write_file(path, "{}");
    }
    int rc = fp_rig_find(dir, m->vertex_count, m->positions, found, sizeof found, err, sizeof err);
    printf("find among %d files that are no rigs: %s\n", JUNK, err);
    assert_int_equal(rc, -ENOENT);
    assert_non_null(strstr(err, "600 files not read as a rig"));
    snprintf(path, sizeof path, "%s/b-face.json", dir);
    write_file(path, good);
    assert_int_equal(fp_rig_find(dir, m->vertex_count, m->positions, found, sizeof found, err, sizeof err), 0);
    assert_string_equal(found, path);
    snprintf(path, sizeof path, "%s/a-face.json", dir);
    write_file(path, good);
    rc = fp_rig_find(dir, m->vertex_count, m->positions, found, sizeof found, err, sizeof err);
    printf("find with two rigs of the mesh: %s\n", err);
    assert_int_equal(rc, -EEXIST);
    assert_non_null(strstr(err, "a-face.json and "));
    assert_non_null(strstr(err, "b-face.json both fit this mesh"));
    for (int i = 0; i < JUNK; i++) {
        snprintf(path, sizeof path, "%s/junk%03d.json", dir, i);
        remove(path);
    }
    snprintf(path, sizeof path, "%s/a-face.json", dir);
    remove(path);
    snprintf(path, sizeof path, "%s/b-face.json", dir);
    remove(path);
    assert_int_equal(rmdir(dir), 0);
    fp_mesh_free(&m);
    free(good);
}

/* A channel's range ends that are no floats (0.7, -0.3): the ends themselves are in range for
 * fp_rig_channel_check (pose --set refused brow.raise=0.7 as outside [-0.3, 0.7]). */
static void test_channel_range_ends(void **state)
{
    (void)state;
    size_t len;
    char *good = read_text(FP_TEST_RIGS_DIR "/mediapipe-canonical.json", &len);
    char *two = edit(good, "\"channels\": [", "\"channels\": [{\"name\": \"brow.raise\", \"min\": -0.3, \"max\": 0.7}, ");
    fp_rig *r = NULL;
    char err[512];
    assert_int_equal(fp_rig_parse(two, strlen(two), "two.json", &r, err, sizeof err), 0);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", 0.7, err, sizeof err), 0);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", -0.3, err, sizeof err), 0);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", 0.1, err, sizeof err), 0);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", 0.71, err, sizeof err), -ERANGE);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", -0.31, err, sizeof err), -ERANGE);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", NAN, err, sizeof err), -ERANGE);
    assert_int_equal(fp_rig_channel_check(r, "brow.raise", 1e300, err, sizeof err), -ERANGE);
    assert_int_equal(fp_rig_channel_check(r, "jaw.open", 1.0, err, sizeof err), 0);
    fp_rig_free(&r);
    free(two);
    free(good);
}

/* A rig on a moved copy of its mesh (fp_rig_placement): the ICT face turned 90 degrees about x
 * (Blender's Z-up), in metres and moved gets the rig carried there by its landmarks; the jaw
 * weights and the mobility are the original's, and the jaw opens as the original's carried
 * there (the pose of the copy is the copy of the pose, within float rounding); mm_per_unit
 * follows the scale. The original mesh, and a copy moved by less than FP_RIG_PLACE_SAME of the
 * landmarks' spread, keep the file's coordinates (not placed); a face whose landmarks lie
 * nowhere like the rig's (the vertices shuffled) is not placed either. */
static void test_placement(void **state)
{
    (void)state;
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    size_t n = m->vertex_count;
    fp_rig *a = find_rig(m);
    fp_rig_placement pa = fp_rig_get_placement(a);
    assert_int_equal(pa.placed, 0);
    assert_int_equal(pa.misfit, 0);
    assert_true(pa.degrees < 0.01 && pa.rms < 1e-3);
    const double s = 0.01, t[3] = {0.3, -1.2, 0.05}; /* cm to m, then moved */
    float *q = malloc(n * 3 * sizeof *q), *pa_out = malloc(n * 3 * sizeof *pa_out), *pb_out = malloc(n * 3 * sizeof *pb_out);
    assert_non_null(q);
    assert_non_null(pa_out);
    assert_non_null(pb_out);
    for (size_t v = 0; v < n; v++) { /* (x, y, z) -> (x, -z, y): up is +z, the face looks along -y */
        const float *p = m->positions + 3 * v;
        q[3 * v] = (float)(s * p[0] + t[0]);
        q[3 * v + 1] = (float)(-s * p[2] + t[1]);
        q[3 * v + 2] = (float)(s * p[1] + t[2]);
    }
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s/ict-facekit.json", FP_TEST_RIGS_DIR);
    fp_rig *b = NULL;
    int rc = fp_rig_load_for_mesh(path, n, q, &b, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    fp_rig_placement pb = fp_rig_get_placement(b);
    assert_int_equal(pb.placed, 1);
    assert_int_equal(pb.misfit, 0);
    assert_true(fabs(pb.degrees - 90) < 0.01);
    assert_true(fabs(pb.scale / s - 1) < 1e-4);
    assert_true(pb.rms < 1e-5 * pb.spread * 100);
    assert_true(fabs(fp_rig_mm_per_unit(b) / (fp_rig_mm_per_unit(a) / s) - 1) < 1e-4);
    float up[3], fw[3], le[3];
    fp_rig_axes(b, up, fw, le);
    assert_true(fabs(up[2] - 1) < 1e-4 && fabs(fw[1] + 1) < 1e-4 && fabs(le[0] - 1) < 1e-4);
    /* the same weights, the same pose carried */
    const float *wa = fp_rig_jaw_weights(a), *wb = fp_rig_jaw_weights(b);
    const float *ma = fp_rig_mobility(a), *mb = fp_rig_mobility(b);
    double dw = 0, dm = 0;
    for (size_t v = 0; v < n; v++) {
        dw = fmax(dw, fabs((double)wa[v] - wb[v]));
        dm = fmax(dm, fabs((double)ma[v] - mb[v]));
    }
    printf("placed: %.4f degrees, scale %.6g, rms %.3g of spread %.3g; jaw weights differ by %.3g, mobility by %.3g\n",
           pb.degrees, pb.scale, pb.rms, pb.spread, dw, dm);
    assert_true(dw < 1e-3 && dm < 1e-3);
    float vals[FP_RIG_MAX_CHANNELS] = {0};
    vals[fp_rig_channel_index(a, "jaw.open")] = 0.7f;
    assert_int_equal(fp_rig_pose(a, m->positions, vals, pa_out), 0);
    assert_int_equal(fp_rig_pose(b, q, vals, pb_out), 0);
    double worst = 0, jaw_moved = 0;
    for (size_t v = 0; v < n; v++) {
        const float *p = pa_out + 3 * v;
        double c[3] = {s * p[0] + t[0], -s * p[2] + t[1], s * p[1] + t[2]};
        for (int k = 0; k < 3; k++) {
            worst = fmax(worst, fabs(c[k] - pb_out[3 * v + k]));
            jaw_moved = fmax(jaw_moved, fabs((double)pb_out[3 * v + k] - q[3 * v + k]));
        }
    }
    printf("jaw.open 0.7: the copy's pose is the pose carried within %.3g mm (the jaw moved up to %.3g mm)\n",
           worst * fp_rig_mm_per_unit(b), jaw_moved * fp_rig_mm_per_unit(b));
    assert_true(jaw_moved * fp_rig_mm_per_unit(b) > 5);    /* the jaw opened */
    assert_true(worst * fp_rig_mm_per_unit(b) < 0.01);     /* as the original's, carried */
    fp_rig_free(&b);
    /* moved by a hair: the file's coordinates */
    for (size_t v = 0; v < 3 * n; v++) q[v] = m->positions[v] + 1e-4f;
    assert_int_equal(fp_rig_load_for_mesh(path, n, q, &b, err, sizeof err), 0);
    assert_int_equal(fp_rig_get_placement(b).placed, 0);
    fp_rig_free(&b);
    /* the vertices reversed: the landmarks' layout is no copy of the rig's: not placed (and the
     * hinge check then judges the file's coordinates as ever) */
    for (size_t v = 0; v < n; v++) memcpy(q + 3 * v, m->positions + 3 * (n - 1 - v), 3 * sizeof *q);
    rc = fp_rig_load_for_mesh(path, n, q, &b, err, sizeof err);
    if (!rc) {
        assert_int_equal(fp_rig_get_placement(b).placed, 0);
        assert_int_equal(fp_rig_get_placement(b).misfit, 1); /* (the session then leaves it) */
        assert_int_equal(fp_rig_get_placement(b).mirrored, 0);
    }
    fp_rig_free(&b);
    /* mirrored, left for right, and in metres: no similarity fits (misfit), a mirrored one
     * does, said so (the session's rig line names it; it said "another face") */
    for (size_t v = 0; v < n; v++)
        for (int k = 0; k < 3; k++) q[3 * v + k] = (float)((k ? 0.01 : -0.01) * m->positions[3 * v + k]);
    rc = fp_rig_load_for_mesh(path, n, q, &b, err, sizeof err);
    if (!rc) {
        fp_rig_placement pm = fp_rig_get_placement(b);
        assert_int_equal(pm.placed, 0);
        assert_int_equal(pm.misfit, 1);
        assert_int_equal(pm.mirrored, 1);
    }
    fp_rig_free(&b);
    fp_rig_free(&a);
    free(q);
    free(pa_out);
    free(pb_out);
    fp_mesh_free(&m);
}

static void test_broken_files(void **state)
{
    (void)state;
    size_t len;
    char *good = read_text(FP_TEST_RIGS_DIR "/ict-facekit.json", &len);
    fp_rig *r = NULL;
    char err[1024];
    assert_int_equal(fp_rig_parse(good, len, "ict.json", &r, err, sizeof err), 0);
    fp_rig_free(&r);
    static const struct {
        const char *from, *to, *field;
    } cases[] = {
        {"\"version\": 1", "\"version\": 2", "version"},
        {"\"version\": 1", "\"version\": \"1\"", "version"},
        {"\"format\": \"facepuppet-rig\"", "\"format\": \"x\"", "format"},
        {"\"vertex_count\": 26719", "\"vertex_count\": 26719.5", "mesh.vertex_count"},
        {"\"positions_crc32\": \"", "\"positions_crc32\": \"zz", "mesh.positions_crc32"},
        /* 8 characters, but not 8 hex digits (strtoul took a 0x, a sign, a leading space) */
        {"\"positions_crc32\": \"577903df\"", "\"positions_crc32\": \"0x577903\"", "mesh.positions_crc32"},
        {"\"positions_crc32\": \"577903df\"", "\"positions_crc32\": \"-0000001\"", "mesh.positions_crc32"},
        {"\"positions_crc32\": \"577903df\"", "\"positions_crc32\": \" 577903d\"", "mesh.positions_crc32"},
        {"\"mm_per_unit\": 10.0", "\"mm_per_unit\": -1", "mm_per_unit"},
        {"\"up\": [0, 1, 0]", "\"up\": [0, 2, 0]", "axes.up"},
        {"\"left\": [1, 0, 0]", "\"left\": [-1, 0, 0]", "axes.left"},
        {"\"forward\": [0, 0, 1]", "\"forward\": [0, 0]", "axes.forward"},
        {"\"kind\": \"skull\"", "\"kind\": \"bone\"", "regions[0].kind"},
        {"\"vertices\": [", "\"vertices\": [99999999, ", "vertex 99999999 is out of range (the mesh has"},
        {"\"vertices\": [", "\"vertices\": [1e308, ", "regions[0].vertices[0]: vertex 1e+308 is out of range"},
        {"\"vertices\": [", "\"vertices\": [[10, 5], ", "regions[0].vertices[0]"},
        {"\"vertices\": [", "\"vertices\": [-1, ", "regions[0].vertices[0]"},
        {"\"vertices\": [", "\"vertices\": [19300, ", "regions[6].vertices"}, /* a lower tooth: overlaps jaw */
        /* a region of no vertex (was accepted without a word) */
        {"\"regions\": [", "\"regions\": [{\"name\": \"none\", \"kind\": \"jaw\", \"vertices\": []}, ",
         "broken.json: regions[0].vertices: empty: region \"none\" lists no vertex"},
        /* the whole mesh listed over and over (a hostile file: refused as counted, not walked) */
        {"\"vertices\": [", "\"vertices\": [[0, 26718], [0, 26718], [0, 26718], [0, 26718], ",
         "regions[0].vertices[4]: the regions list more than 4 x 26719 vertices"},
        {"\"chin\": 966", "\"chin\": 26719, \"x\": 966", "landmarks.chin"},
        {"\"nose_tip\": 4857", "\"nose tip\": 4857", "landmarks.nose tip"},
        {"\"right\": [", "\"right\": [\"a\", ", "jaw.hinge.right"},
        {"\"right\": [", "\"right\": [0, 0, 0], \"x\": [", "jaw.hinge.x"},
        /* a finite number past 1e12 is no coordinate, and was said to be "not a finite" one */
        {"\"right\": [-5.0, 0.5", "\"right\": [-1e300, 0.5", "jaw.hinge.right[0]: -1e+300 is beyond 1e12 mesh units"},
        {"\"open_degrees\": 29.9", "\"open_degrees\": 90", "jaw.open_degrees"},
        /* (%g said "reads version 1, the file is 1") */
        {"\"version\": 1", "\"version\": 1.0000001", "the file is 1.0000001"},
        /* the jaw outline degenerate: gonion on menton, gonion on the hinge (in the sagittal plane) */
        {"\"gonion\": [5.3, -5.0, 1.6]", "\"gonion\": [4.0, -8.0, 9.2]", "jaw.falloff.gonion: lies on the menton"},
        {"\"gonion\": [5.3, -5.0, 1.6]", "\"gonion\": [3.0, 0.5, 2.3]", "jaw.falloff.gonion: lies on the hinge"},
        {"\"lip_band\": ", "\"lip_band\": -", "jaw.falloff.lip_band"},
        {"\"ramp\": ", "\"ramp\": null, \"r\": ", "mobility.r"},
        {"\"name\": \"jaw.open\"", "\"name\": \"jaw.shut\"", "channels"},
        {"\"max\": 1", "\"max\": -1", "channels[0]"},
        {"\"mobility\": {", "\"extra\": 1, \"mobility\": {", "extra"},
        {"{", "[", ""},
        /* a glide of more than half the joints' distance (1e308 made the posed jaw infinite) */
        {"\"name\": \"ict-facekit\"", "\"name\": \"ict\\u001b[31m\"", "name"}, /* an ESC: no text */
        /* a NUL: cJSON ended the string there (read as "ict", accepted) */
        {"\"name\": \"ict-facekit\"", "\"name\": \"ict\\u0000x\"", "broken.json:4: \\u0000"},
        {"\"glide\": [0.735, 0.515]", "\"glide\": [1e308, 0.515]", "jaw.glide[0]"},
        {"\"glide\": [0.735, 0.515]", "\"glide\": [0.735, -100]", "jaw.glide[1]"},
        /* where the condyles start to slide: a fraction of the opening below 0.95 */
        {"\"glide_start\": 0.602", "\"glide_start\": 1", "jaw.glide_start"},
        {"\"glide_start\": 0.602", "\"glide_start\": -0.1", "jaw.glide_start"},
        {"\"glide_start\": 0.602", "\"glide_start\": \"0.6\"", "jaw.glide_start"},
        /* jaw.weights */
        {"\"weights\": {", "\"weights\": {\"x\": 1, ", "jaw.weights.x"},
        {"\"glide\": [", "\"weights\": 3, \"glide\": [", "jaw.weights"},
        {"\"values\": [\n    ", "\"values\": [\n    1.5, ", "jaw.weights.values[0]"},
        {"\"values\": [\n    ", "\"values\": [\n    \"a\", ", "jaw.weights.values[0]"},
        {"\"weights\": {\n   \"vertices\": [", "\"weights\": {\n   \"vertices\": [26718, ", "jaw.weights"}, /* a value short */
        {"\"weights\": {\n   \"vertices\": [", "\"weights\": {\n   \"vertices\": [17040, ", "jaw.weights.vertices[0]"},
        {"\"weights\": {\n   \"vertices\": [", "\"weights\": {\n   \"vertices\": [19300, ", "jaw.weights.vertices[0]"},
        {"\"weights\": {\n   \"vertices\": [\n    [18, 28]", "\"weights\": {\n   \"vertices\": [\n    [28, 18]",
         "jaw.weights.vertices[0]"},
        {"\"weights\": {\n   \"vertices\": [", "\"weights\": {\n   \"vertices\": [[0, 99999], ", "jaw.weights.vertices[0]"},
        {"\"weights\": {\n   \"vertices\": [", "\"weights\": {\n   \"vertices\": [26719, ", "jaw.weights.vertices[0]"},
        /* mesh.landmark_positions: every landmark, each 3 finite numbers, no other name */
        {"\"landmark_positions\": {", "\"landmark_positions\": {\"nosetip\": [0, 0, 0], ",
         "mesh.landmark_positions.nosetip"},
        {"\"chin\": [0.0, -7.5671, 10.432],", "", "mesh.landmark_positions: 22 of the 23 landmarks"},
        {"\"chin\": [0.0, -7.5671, 10.432]", "\"chin\": [0.0, \"a\", 10.432]", "mesh.landmark_positions.chin[1]"},
        {"\"chin\": [0.0, -7.5671, 10.432]", "\"chin\": [0.0, 1e999, 10.432]", "mesh.landmark_positions.chin"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char *bad = edit(good, cases[i].from, cases[i].to);
        err[0] = 0;
        int rc = fp_rig_parse(bad, strlen(bad), "broken.json", &r, err, sizeof err);
        printf("case %zu: %s\n", i, err);
        assert_int_equal(rc, -EBADMSG);
        assert_null(r);
        assert_non_null(strstr(err, "broken.json"));
        assert_non_null(strstr(err, cases[i].field));
        assert_true(strlen(err) < 400); /* (numbers as %g: 1e308 was 309 digits) */
        free(bad);
    }
    { /* an escaped backslash before u0000 is text, not a NUL: accepted */
        char *txt = edit(good, "\"description\": \"ICT", "\"description\": \"\\\\u0000 ICT");
        assert_non_null(strstr(txt, "\"\\\\u0000 ICT"));
        assert_int_equal(fp_rig_parse(txt, strlen(txt), "bs.json", &r, err, sizeof err), 0);
        fp_rig_free(&r);
        free(txt);
    }
    { /* one JSON value only: text after it is refused, white space is not */
        size_t gl = strlen(good);
        char *tail = malloc(gl + 16);
        assert_non_null(tail);
        memcpy(tail, good, gl);
        memcpy(tail + gl, " \n\t", 4);
        assert_int_equal(fp_rig_parse(tail, gl + 3, "ws.json", &r, err, sizeof err), 0);
        fp_rig_free(&r);
        memcpy(tail + gl, "\n{}", 4);
        assert_int_equal(fp_rig_parse(tail, gl + 3, "tail.json", &r, err, sizeof err), -EBADMSG);
        assert_non_null(strstr(err, "text after the rig's JSON object"));
        free(tail);
    }
    /* jaw.weights replaced by small objects: refused with the field named, or accepted */
    const char *wbeg = strstr(good, "\"weights\": {"), *wval = wbeg ? strstr(wbeg, "\"values\": [") : NULL;
    const char *wend = wval ? strstr(wval, "]\n  }") : NULL;
    assert_non_null(wend);
    wend += strlen("]\n  }");
    static const struct {
        const char *obj, *field; /* field NULL: accepted */
    } wcases[] = {
        {"{\"vertices\": 7, \"values\": []}", "jaw.weights.vertices"},
        {"{\"vertices\": [], \"values\": 0}", "jaw.weights.values"},
        {"{\"values\": [0.5]}", "jaw.weights.vertices"},
        {"{\"vertices\": [18]}", "jaw.weights.values"},
        {"{\"vertices\": [[18, 19]], \"values\": [0.5]}", "jaw.weights.vertices[0]"},
        {"{\"vertices\": [18, 19], \"values\": [0.5, 0.5, 0.5]}", "jaw.weights"},
        {"{\"vertices\": [18, [17, 19]], \"values\": [0.5, 0.5, 0.5, 0.5]}", "jaw.weights.vertices[1]"},
        {"{\"vertices\": [18, \"x\"], \"values\": [0.5, 0.5]}", "jaw.weights.vertices[1]"},
        {"{\"vertices\": [18, 19], \"values\": [0.5, -0.01]}", "jaw.weights.values[1]"},
        {"{\"vertices\": [18, 19], \"values\": [0.5, 0.25]}", NULL},
        {"{\"vertices\": [], \"values\": []}", NULL},
    };
    for (size_t i = 0; i < sizeof wcases / sizeof wcases[0]; i++) {
        size_t pre = (size_t)(wbeg - good), lo = strlen(wcases[i].obj), post = strlen(wend);
        char *txt = malloc(pre + 11 + lo + post + 1);
        memcpy(txt, good, pre);
        memcpy(txt + pre, "\"weights\": ", 11);
        memcpy(txt + pre + 11, wcases[i].obj, lo);
        memcpy(txt + pre + 11 + lo, wend, post + 1);
        err[0] = 0;
        int rc = fp_rig_parse(txt, strlen(txt), "weights.json", &r, err, sizeof err);
        printf("weights %s: %s\n", wcases[i].obj, rc ? err : "accepted");
        if (wcases[i].field) {
            assert_int_equal(rc, -EBADMSG);
            assert_null(r);
            assert_non_null(strstr(err, "weights.json"));
            assert_non_null(strstr(err, wcases[i].field));
        } else {
            assert_int_equal(rc, 0);
            fp_mesh *mm = load_face("ict-facekit/generic_neutral_mesh.obj");
            assert_int_equal(fp_rig_bind(r, mm->vertex_count, mm->positions, err, sizeof err), 0);
            if (strstr(wcases[i].obj, "0.25")) { /* the file's weights win over the falloff */
                assert_true(fp_rig_jaw_weights(r)[18] == 0.5f && fp_rig_jaw_weights(r)[19] == 0.25f);
            }
            fp_rig_free(&r);
            fp_mesh_free(&mm);
        }
        free(txt);
    }
    /* truncations at every 997th byte never crash and always fail */
    for (size_t cut = 0; cut < len - 2; cut += 997) {
        int rc = fp_rig_parse(good, cut, "cut.json", &r, err, sizeof err);
        assert_int_equal(rc, -EBADMSG);
    }
    /* a hinge outside the head and a mesh of another size are refused at bind */
    fp_mesh *m = load_face("ict-facekit/generic_neutral_mesh.obj");
    char *far = edit(good, "\"right\": [", "\"right\": [-500, ");
    char *far2 = edit(far, "-500, -5.0, ", "-500, ");
    assert_int_equal(fp_rig_parse(far2, strlen(far2), "far.json", &r, err, sizeof err), 0);
    assert_int_equal(fp_rig_bind(r, m->vertex_count, m->positions, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "jaw.hinge.right"));
    assert_int_equal(fp_rig_bind(r, 100, m->positions, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "mesh.vertex_count"));
    fp_rig_free(&r);
    free(far), free(far2);
    assert_int_equal(fp_rig_load("no/such/rig.json", &r, err, sizeof err), -ENOENT);
    { /* a file over FP_RIG_FILE_MAX is refused before it is read (1 GiB of "0," was 40 GB of cJSON) */
        char big[] = "/tmp/fp-test-rig-big-XXXXXX";
        int fd = mkstemp(big);
        assert_true(fd >= 0);
        assert_int_equal(ftruncate(fd, (off_t)FP_RIG_FILE_MAX + 1), 0);
        close(fd);
        int brc = fp_rig_load(big, &r, err, sizeof err);
        remove(big);
        assert_int_equal(brc, -EBADMSG);
        printf("a rig file of FP_RIG_FILE_MAX + 1 bytes: %s\n", err);
        assert_non_null(strstr(err, big));
        assert_non_null(strstr(err, "larger than 32 MiB"));
        assert_null(r);
    }
    fp_mesh_free(&m);
    free(good);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ict_pose),         cmocka_unit_test(test_ict_fingers),
        cmocka_unit_test(test_ict_finger_limit), cmocka_unit_test(test_ict_finger_limit_indexed),
        cmocka_unit_test(test_ict_clamp_continuous),
        cmocka_unit_test(test_lee_perry_smith),  cmocka_unit_test(test_mediapipe),
        cmocka_unit_test(test_mobility_brute_force),
        cmocka_unit_test(test_broken_files),     cmocka_unit_test(test_placement),
        cmocka_unit_test(test_find_names_unread), cmocka_unit_test(test_split_copy),
        cmocka_unit_test(test_find_all_and_twins), cmocka_unit_test(test_channel_range_ends),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
