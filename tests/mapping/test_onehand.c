/* map-onehand (issue 12): one hand drives the ICT face through its rig. The plugin is loaded
 * by the host's loader and driven through plugin.h with a host of this test: the rig view is
 * built from rigs/ict-facekit.json with core/rig's API, the hands are made by core/hand's
 * forward kinematics and reach the mapping through core/pose, the session's own pose step
 * (joint positions as a tracker gives them, or joint angles alone as a glove gives them, with
 * the default wrist placement), under a fixed workspace calibration. The references are
 * independent of the plugin: the FK's joint angles (the thumb's flexion), the hand's motion
 * in millimetres before calibration (the 1:1 gain), the rig's own landmark positions. */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_plugin_host.h"
#include "fp_pose.h"
#include "fp_rig.h"
#include "fp_test_support.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define DEG (3.14159265358979323846 / 180.0)
#define R 3.0            /* support radius, mesh units (cm): clamp 0.45 R = 13.5 mm */
#define SCALE 0.06       /* the workspace calibration: mesh units per mm of hand */
#define STEP_NS 10000000 /* 100 frames a second */

/* ---- the face and its rig, once for the program ------------------------------------------ */

static fp_mesh *g_mesh;
static fp_rig *g_rig;
static fp_rig_view g_view;
static fp_rig_landmark g_lms[FP_RIG_MAX_LANDMARKS];
static fp_rig_channel_info g_chs[FP_RIG_MAX_CHANNELS];

static int setup_rig(void **state)
{
    (void)state;
    char err[1024];
    if (fp_mesh_load(fp_test_face_path(), &g_mesh, err, sizeof err)) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    if (fp_rig_load_for_mesh("rigs/ict-facekit.json", g_mesh->vertex_count, g_mesh->positions,
                             &g_rig, err, sizeof err)) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    fp_rig_view *v = &g_view;
    v->size = sizeof *v;
    v->name = fp_rig_name(g_rig);
    v->mm_per_unit = fp_rig_mm_per_unit(g_rig);
    fp_rig_axes(g_rig, v->up, v->forward, v->left);
    v->vertex_count = g_mesh->vertex_count;
    v->region = fp_rig_vertex_kinds(g_rig);
    v->landmark_count = fp_rig_landmark_count(g_rig);
    for (size_t i = 0; i < v->landmark_count; i++) {
        fp_rig_landmark_get(g_rig, i, &g_lms[i].name, &g_lms[i].vertex);
        memcpy(g_lms[i].position, &g_mesh->positions[3 * g_lms[i].vertex], sizeof g_lms[i].position);
    }
    v->landmarks = g_lms;
    v->channel_count = fp_rig_channel_count(g_rig);
    for (size_t i = 0; i < v->channel_count; i++) {
        fp_rig_channel_desc d;
        fp_rig_channel_get(g_rig, i, &d);
        g_chs[i] = (fp_rig_channel_info){d.name, d.min, d.max, d.neutral, d.neutral};
    }
    v->channels = g_chs;
    fp_rig_hinge(g_rig, v->hinge[0], v->hinge[1], NULL, NULL);
    return 0;
}

static int teardown_rig(void **state)
{
    (void)state;
    fp_rig_free(&g_rig);
    fp_mesh_free(&g_mesh);
    return 0;
}

static const fp_rig_landmark *landmark(const char *name)
{
    for (size_t i = 0; i < g_view.landmark_count; i++)
        if (!strcmp(g_lms[i].name, name)) return &g_lms[i];
    fail_msg("no landmark %s", name);
    return NULL;
}

/* ---- the host of this test ---------------------------------------------------------------- */

typedef struct fx {
    fp_host host;                 /* first: host_data points back */
    fp_host_rig rig_ext;
    bool offer_ext;               /* FP_HOST_EXT_RIG answered */
    char log[4096];
    fp_plugin plugin;
    fp_mapping *m;
    fp_control_set cs;
    float start[FP_CONTROL_CAPACITY][3], end[FP_CONTROL_CAPACITY][3];
    fp_channel ch[FP_CHANNEL_CAPACITY];
    fp_frame_input in;
    fp_pose_state pose;
    int rc;                       /* the last process() */
    double jaw_now;               /* jaw.open as the rig holds it: the last value the mapping
                                     set (it sets none while the hand rests), neutral first */
    size_t jaw_sets;              /* frames that set jaw.open */
} fx;

static void host_log(const fp_host *h, fp_log_level level, const char *msg)
{
    fx *x = h->host_data;
    size_t n = strlen(x->log);
    snprintf(x->log + n, sizeof x->log - n, "%d %s\n", (int)level, msg);
}

static const fp_rig_view *host_rig_get(const fp_host *h)
{
    fx *x = h->host_data;
    return x->offer_ext ? &g_view : NULL;
}

static const void *host_ext(const fp_host *h, const char *id)
{
    fx *x = h->host_data;
    return x->offer_ext && !strcmp(id, FP_HOST_EXT_RIG) ? &x->rig_ext : NULL;
}

static int64_t host_now(const fp_host *h)
{
    (void)h;
    return fp_test_mono_ns();
}

/* Load map-onehand and create it with params; ext: the host offers FP_HOST_EXT_RIG; the
 * frame's rig is g_view too unless the test clears it. */
static int open_onehand(fx *x, const fp_param *params, size_t n, bool ext, char *err)
{
    memset(x, 0, sizeof *x);
    x->host.size = sizeof x->host;
    x->host.abi = (fp_version){FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    x->host.host_data = x;
    x->host.log = host_log;
    x->host.now_ns = host_now;
    x->host.get_extension = host_ext;
    x->rig_ext.get = host_rig_get;
    x->offer_ext = ext;
    int rc = fp_plugin_load(fp_test_plugin_path(), FP_PLUGIN_MAPPING, "onehand", &x->plugin, err, 1024);
    if (rc) return rc;
    const fp_mapping_factory *f = x->plugin.factory;
    rc = f->create(&x->host, params, n, &x->m, err, 1024);
    x->cs.size = sizeof x->cs;
    x->cs.capacity = FP_CONTROL_CAPACITY;
    x->cs.start = x->start;
    x->cs.end = x->end;
    x->cs.channels = x->ch;
    x->cs.channel_capacity = FP_CHANNEL_CAPACITY;
    x->in.size = sizeof x->in;
    x->in.radius = R;
    x->in.time_ns = 1000000000;
    x->in.rig = &g_view;
    x->in.mm_per_unit = g_view.mm_per_unit;
    memcpy(x->in.face_up, g_view.up, sizeof x->in.face_up);
    memcpy(x->in.face_forward, g_view.forward, sizeof x->in.face_forward);
    memcpy(x->in.face_left, g_view.left, sizeof x->in.face_left);
    for (int h = 0; h < FP_HANDS; h++)
        for (int k = 0; k < FP_FINGERS; k++) x->in.tip_distance[h][k] = INFINITY;
    fp_calibration c = {.scale = SCALE, .offset = {0, -4, 16}};
    fp_pose_init(&x->pose, 0, &c);
    return rc;
}

static void close_onehand(fx *x)
{
    if (x->m) x->m->destroy(x->m);
    x->m = NULL;
    fp_plugin_unload(&x->plugin);
}

/* One frame: the pose step builds the hands, the mapping runs. */
static void step(fx *x, uint32_t requested)
{
    fp_pose_build(&x->pose);
    memcpy(x->in.hands, x->pose.poses, sizeof x->in.hands);
    x->in.requested = requested;
    x->rc = x->m->process(x->m, &x->in, &x->cs);
    for (size_t i = 0; i < x->cs.channel_count; i++)
        if (!strcmp(x->ch[i].name, "jaw.open")) {
            x->jaw_now = x->ch[i].value;
            x->jaw_sets++;
        }
    x->in.frame++;
    x->in.time_ns += STEP_NS;
}

/* jaw.open after the last frame, as the rig holds it (the value the mapping set last). */
static double jaw(const fx *x) { return x->jaw_now; }

/* A hand pose: angles (22, radians, a flat hand with the model's rest thumb) and a wrist. */
typedef struct hand {
    float a[FP_GLOVE_SENSORS];
    float pos[3], rot[4];
} hand;

static hand rest_hand(int side)
{
    hand h;
    fp_hand_model m;
    fp_hand_model_init(&m);
    memcpy(h.a, m.rest_rad, sizeof h.a);
    fp_pose_default_wrist(side, h.pos, h.rot);
    return h;
}

/* The hand as a tracker gives it (joint positions, mm) or as a glove (angles alone). */
static void put(fx *x, int side, const hand *h, bool angles_only)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    if (angles_only) {
        ev.angles.header = (fp_event_header){sizeof ev.angles, FP_EVENT_JOINT_ANGLES, 0,
                                             x->in.time_ns, 0, side};
        ev.angles.valid = FP_HAND_ALL_SENSORS;
        memcpy(ev.angles.radians, h->a, sizeof h->a);
    } else {
        ev.positions.header = (fp_event_header){sizeof ev.positions, FP_EVENT_JOINT_POSITIONS, 0,
                                                x->in.time_ns, 0, side};
        assert_int_equal(fp_hand_fk(&x->pose.model, side, h->a, FP_HAND_ALL_SENSORS, h->pos,
                                    h->rot, ev.positions.mm), 0);
    }
    fp_pose_take_event(&x->pose, &ev);
}

/* The right hand at rest, given as joint positions, then the engage request: the pose most
 * tests start from (its pose the zero); returns that hand. */
static hand engaged_rest(fx *x)
{
    hand h = rest_hand(FP_HAND_RIGHT);
    put(x, FP_HAND_RIGHT, &h, false);
    step(x, FP_INTENT_ENGAGE);
    return h;
}

static void gone(fx *x, int side)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.status.header = (fp_event_header){sizeof ev.status, FP_EVENT_STATUS, 0, x->in.time_ns, 0, side};
    ev.status.code = FP_STATUS_DISCONNECTED;
    fp_pose_take_event(&x->pose, &ev);
}

/* The joints in mm (device frame) of a hand, by the same FK the tracker path uses. */
static void joints_mm(fx *x, int side, const hand *h, float j[FP_HAND_JOINTS][3])
{
    assert_int_equal(fp_hand_fk(&x->pose.model, side, h->a, FP_HAND_ALL_SENSORS, h->pos, h->rot, j), 0);
}

/* The index of landmark `name` among the control set's start points. */
static size_t slot_of(const fx *x, const char *name)
{
    const fp_rig_landmark *lm = landmark(name);
    for (size_t i = 0; i < x->cs.count; i++)
        if (!memcmp(x->start[i], lm->position, sizeof lm->position)) return i;
    fail_msg("no start point at %s", name);
    return 0;
}

/* ---- tests ---------------------------------------------------------------------------------- */

/* jaw.open for u (the thumb's measure beyond neutral over its range) as the usage states it:
 * u^2 / 2e below e (ease, 0.3 by default), |u| - e/2 above, clamped to [0, 1]. */
static double eased(double u, double e)
{
    double a = fabs(u), r = a < e ? a * a / (2 * e) : a - e / 2;
    return fmin(1.0, fmax(0.0, copysign(r, u)));
}

/* A curling thumb opens the jaw monotonically: 0 at the neutral hand, then u = (delta MPJ +
 * delta IJ) / flex_range of the FK's own angles eased in (eased), up to 1. For trackers and
 * for gloves. */
static void thumb_curl(bool angles_only)
{
    fx x;
    char err[1024];
    fp_param p[] = {{"jaw", "flexion"}}; /* the curl: an option (the default is the opening) */
    assert_int_equal(open_onehand(&x, p, 1, true, err), 0);
    hand h = rest_hand(FP_HAND_RIGHT);
    put(&x, FP_HAND_RIGHT, &h, angles_only);
    step(&x, 0);                               /* the defaults: engaged at first sight */
    assert_int_equal(x.rc, 0);
    assert_true(x.cs.active);
    assert_true(x.cs.intents & FP_INTENT_ENGAGE);
    assert_float_equal(jaw(&x), 0.0, 0);       /* that pose is the zero */
    double last = 0;
    float mpj0 = h.a[FP_SENSOR_THUMB_MPJ], ij0 = h.a[FP_SENSOR_THUMB_IJ];
    for (int k = 1; k <= 30; k++) {
        h.a[FP_SENSOR_THUMB_MPJ] = mpj0 + (float)(k * 1.0 * DEG);
        h.a[FP_SENSOR_THUMB_IJ] = ij0 + (float)(k * 1.5 * DEG);
        put(&x, FP_HAND_RIGHT, &h, angles_only);
        step(&x, 0);
        assert_int_equal(x.rc, 0);
        double v = jaw(&x), want = eased(k * 2.5 / 45.0, 0.3);
        assert_true(v >= last);                /* monotonic */
        assert_float_equal(v, want, 0.01);     /* against the FK's angles */
        last = v;
    }
    assert_float_equal(last, 1.0, 0);          /* 75 deg of curl: fully open, clamped */
    close_onehand(&x);
}
static void test_thumb_curl_opens_jaw(void **state)
{
    (void)state;
    thumb_curl(false);
}
static void test_angles_only_thumb(void **state)
{
    (void)state;
    thumb_curl(true);
}

/* The thumb-to-index opening of hand h as the mapping measures it: the distance between the
 * thumb's tip (joint 4) and the index tip (joint 8) of the FK's joints, mm. */
static double opening_mm(fx *x, const hand *h)
{
    float j[FP_HAND_JOINTS][3];
    joints_mm(x, FP_HAND_RIGHT, h, j);
    return sqrt(pow(j[4][0] - j[8][0], 2) + pow(j[4][1] - j[8][1], 2) + pow(j[4][2] - j[8][2], 2));
}

/* jaw=opening, the default (issue 53: a hand puppet's mouth): the thumb moving away from the
 * index opens the jaw by u = (opening - neutral opening) / 40 mm eased in (eased), the
 * opening measured on the FK's joints in mm; the same with no jaw= at all. */
static void jaw_opening(bool by_default)
{
    fx x;
    char err[1024];
    fp_param p[] = {{"jaw", "opening"}};
    assert_int_equal(open_onehand(&x, p, by_default ? 0 : 1, true, err), 0);
    hand h = engaged_rest(&x);
    double d0 = opening_mm(&x, &h);
    double last = 0;
    for (int k = 1; k <= 12; k++) {
        h.a[FP_SENSOR_THUMB_AB] += (float)(3 * DEG);
        double d = opening_mm(&x, &h);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        double v = jaw(&x);
        assert_true(v >= last);
        assert_float_equal(v, eased((d - d0) / 40.0, 0.3), 0.005);
        last = v;
    }
    assert_true(last > 0.3);
    close_onehand(&x);
}
static void test_jaw_opening(void **state)
{
    (void)state;
    jaw_opening(false);
    jaw_opening(true);
}

/* A trembling thumb (the opening up to 1.5 mm either side of neutral, a tracker's noise or a
 * resting hand's tremor) leaves the eased jaw all but shut: at most 0.0025 of its travel
 * (1.5 mm: (1.5/40)^2 / 0.6 = 0.0023), where the straight line (ease=0) opens it by every
 * outward twitch, over 10x as far. */
static void test_tremor_leaves_jaw_shut(void **state)
{
    (void)state;
    double most[2] = {0, 0};
    for (int straight = 0; straight <= 1; straight++) {
        fx x;
        char err[1024];
        fp_param p[] = {{"ease", "0"}};
        assert_int_equal(open_onehand(&x, p, straight ? 1 : 0, true, err), 0);
        hand h = engaged_rest(&x);
        double d0 = opening_mm(&x, &h);
        float ab0 = h.a[FP_SENSOR_THUMB_AB];
        for (int k = 0; k < 40; k++) {
            h.a[FP_SENSOR_THUMB_AB] = ab0 + (float)((k % 2 ? 1 : -1) * (0.2 + 0.02 * (k % 7)) * DEG);
            double d = opening_mm(&x, &h);
            assert_true(fabs(d - d0) <= 1.5);
            put(&x, FP_HAND_RIGHT, &h, false);
            step(&x, 0);
            assert_int_equal(x.rc, 0);
            most[straight] = fmax(most[straight], jaw(&x));
        }
        close_onehand(&x);
    }
    printf("tremor: jaw at most %.5f eased, %.5f straight\n", most[0], most[1]);
    assert_true(most[0] <= 0.0025);
    assert_true(most[1] > 10 * most[0]);
}

/* A still hand moves nothing: every end point is its start point and jaw.open is neutral,
 * bit for bit, however long it stays. */
static void test_still_hand(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    assert_int_equal(open_onehand(&x, NULL, 0, true, err), 0);
    hand h = rest_hand(FP_HAND_RIGHT);
    h.a[FP_SENSOR_INDEX_MPJ] = (float)(20 * DEG);  /* any pose will do: it is the zero */
    h.a[FP_SENSOR_THUMB_IJ] = (float)(15 * DEG);
    for (int f = 0; f < 200; f++) {
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, f == 3 ? FP_INTENT_ENGAGE : 0); /* (a request while engaged: nothing new) */
        assert_int_equal(x.rc, 0);
        assert_float_equal(jaw(&x), 0.0, 0);
        assert_true(x.cs.active);              /* engaged at first sight (the defaults) */
        assert_int_equal(!!(x.cs.intents & FP_INTENT_ENGAGE), f == 0);
        assert_int_equal(x.cs.count, 5);
        assert_memory_equal(x.start, x.end, x.cs.count * sizeof x.start[0]);
    }
    close_onehand(&x);
}

/* The start points are exactly the rig's landmarks (table mouth), and stay bit-identical
 * frame after frame while the hand moves, so the host reuses its factorization; when the
 * host's view moves a landmark (the rig posed the face), the start point follows it. */
static void test_start_points_are_landmarks(void **state)
{
    (void)state;
    static const char *mouth[] = {"mouth_corner_right", "upper_lip", "mouth_corner_left",
                                  "brow_left", "brow_right"};
    for (int side = 0; side < FP_HANDS; side++) {
        fx x;
        char err[1024];
        fp_param p[] = {{"hand", side == FP_HAND_LEFT ? "left" : "right"}};
        assert_int_equal(open_onehand(&x, p, 1, true, err), 0);
        hand h = rest_hand(side);
        put(&x, side, &h, false);
        step(&x, FP_INTENT_ENGAGE);
        assert_int_equal(x.cs.count, 5);
        float s0[5][3];
        memcpy(s0, x.start, sizeof s0);
        for (int i = 0; i < 5; i++) {
            const fp_rig_landmark *lm = landmark(mouth[i]);
            const float *want = g_mesh->positions + 3 * lm->vertex;
            size_t k = slot_of(&x, mouth[i]);
            assert_memory_equal(x.start[k], want, sizeof x.start[k]);
        }
        /* which finger: index drives the corner nearer it on screen (right hand: the face's
         * right corner; left hand: the left corner) */
        size_t idx_slot = slot_of(&x, side == FP_HAND_RIGHT ? "mouth_corner_right" : "mouth_corner_left");
        for (int f = 0; f < 50; f++) {
            h.pos[1] += 0.2f;
            h.a[FP_SENSOR_INDEX_MPJ] += (float)(0.5 * DEG);
            put(&x, side, &h, false);
            step(&x, 0);
            assert_int_equal(x.rc, 0);
            assert_memory_equal(x.start, s0, sizeof s0);
        }
        assert_true(x.end[idx_slot][1] != x.start[idx_slot][1]);
        /* the host poses the face (the jaw carries a corner down): the start point is the
         * landmark where the view has it now, the displacement unchanged */
        fp_rig_landmark *lm = (fp_rig_landmark *)landmark("mouth_corner_left");
        float keep[3], d0[3];
        memcpy(keep, lm->position, sizeof keep);
        size_t k = slot_of(&x, "mouth_corner_left");
        for (int c = 0; c < 3; c++) d0[c] = x.end[k][c] - x.start[k][c];
        lm->position[1] -= 0.25f;
        put(&x, side, &h, false);
        step(&x, 0);
        assert_memory_equal(x.start[k], lm->position, sizeof keep);
        for (int c = 0; c < 3; c++) assert_float_equal(x.end[k][c] - x.start[k][c], d0[c], 1e-6);
        memcpy(lm->position, keep, sizeof keep);
        close_onehand(&x);
    }
}

/* end = landmark + gain x (tip now - tip at neutral): the hand's motion in mm (measured
 * before the calibration) over the rig's 10 mm per unit, in the face's axes; gain 1 is
 * 1:1 in physical units. Also through angles alone (a glove's finger flexion). */
static void relative_motion(double gain, bool angles_only)
{
    fx x;
    char err[1024];
    char g[32];
    snprintf(g, sizeof g, "%g", gain);
    fp_param p[] = {{"gain", g}};
    assert_int_equal(open_onehand(&x, p, 1, true, err), 0);
    hand h = rest_hand(FP_HAND_RIGHT);
    float j0[FP_HAND_JOINTS][3], j1[FP_HAND_JOINTS][3];
    put(&x, FP_HAND_RIGHT, &h, angles_only);
    step(&x, FP_INTENT_ENGAGE);
    joints_mm(&x, FP_HAND_RIGHT, &h, j0);
    if (!angles_only) {      /* a tracker: the whole hand moves 6 mm right, 4 up, 3 toward you */
        h.pos[0] += 6;
        h.pos[1] += 4;
        h.pos[2] += 3;
    }
    h.a[FP_SENSOR_INDEX_MPJ] += (float)(5 * DEG);   /* and the fingers bend */
    h.a[FP_SENSOR_MIDDLE_PIJ] += (float)(6 * DEG);
    h.a[FP_SENSOR_RING_PIJ] += (float)(8 * DEG);
    h.a[FP_SENSOR_PINKIE_MPJ] += (float)(6 * DEG);
    put(&x, FP_HAND_RIGHT, &h, angles_only);
    step(&x, 0);
    joints_mm(&x, FP_HAND_RIGHT, &h, j1);
    assert_int_equal(x.rc, 0);
    static const struct { const char *lm; int finger; } map[] = {
        {"mouth_corner_right", 1}, {"upper_lip", 2}, {"mouth_corner_left", 3},
        {"brow_left", 4}, {"brow_right", 4}};
    for (int i = 0; i < 5; i++) {
        size_t k = slot_of(&x, map[i].lm);
        int t = FP_JOINT_TIP(map[i].finger);
        double want[3], len = 0;
        for (int c = 0; c < 3; c++) {  /* ICT: left +x, up +y, forward +z: the device's axes */
            want[c] = gain * (j1[t][c] - j0[t][c]) / g_view.mm_per_unit;
            len += want[c] * want[c];
        }
        double lim = 0.45 * R, f = sqrt(len) > lim ? lim / sqrt(len) : 1; /* the clamp */
        for (int c = 0; c < 3; c++)
            assert_float_equal(x.end[k][c] - x.start[k][c], want[c] * f, 2e-4 + 2e-3 * fabs(want[c]));
        assert_true(len > 0.01);  /* every finger did move its landmark */
    }
    close_onehand(&x);
}
static void test_relative_motion_tracker(void **state)
{
    (void)state;
    relative_motion(1.0, false);
    relative_motion(0.5, false);
}
static void test_angles_only_motion(void **state)
{
    (void)state;
    relative_motion(1.0, true);
}

/* hand=left ignores the right hand entirely. */
static void test_left_ignores_right(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    fp_param p[] = {{"hand", "left"}, {"still", "0.2"}, {"jaw", "flexion"}}; /* the thumb curls */
    assert_int_equal(open_onehand(&x, p, 3, true, err), 0);
    hand r = rest_hand(FP_HAND_RIGHT), l = rest_hand(FP_HAND_LEFT);
    for (int f = 0; f < 60; f++) {           /* a still right hand, a request: nothing */
        put(&x, FP_HAND_RIGHT, &r, false);
        step(&x, f == 30 ? FP_INTENT_ENGAGE : 0);
        assert_int_equal(x.rc, 0);
        assert_false(x.cs.active);
        assert_int_equal(x.cs.intents, 0);
        assert_float_equal(jaw(&x), 0.0, 0);
    }
    put(&x, FP_HAND_LEFT, &l, false);
    step(&x, FP_INTENT_ENGAGE);              /* the left hand engages */
    assert_true(x.cs.active);
    for (int f = 0; f < 40; f++) {           /* the right hand curls and moves: nothing */
        r.pos[1] += 1.0f;
        r.a[FP_SENSOR_THUMB_MPJ] += (float)(2 * DEG);
        r.a[FP_SENSOR_INDEX_MPJ] += (float)(2 * DEG);
        put(&x, FP_HAND_RIGHT, &r, false);
        put(&x, FP_HAND_LEFT, &l, false);
        step(&x, 0);
        assert_true(x.cs.active);
        assert_memory_equal(x.start, x.end, x.cs.count * sizeof x.start[0]);
        assert_float_equal(jaw(&x), 0.0, 0);
    }
    l.a[FP_SENSOR_THUMB_MPJ] += (float)(20 * DEG);  /* the left thumb does */
    put(&x, FP_HAND_LEFT, &l, false);
    step(&x, 0);
    assert_float_equal(jaw(&x), eased(20.0 / 45.0, 0.3), 0.01);
    close_onehand(&x);
}

/* hand=auto (the default): a lone left hand drives the face at its first frame, its index
 * the face's left mouth corner; where both are there, the right; when the driving hand goes
 * and the other stays, that frame ends the gesture (hold=0: cancelled) and the next engages
 * the other hand, which alone then drives. */
static void test_auto_hand(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    assert_int_equal(open_onehand(&x, NULL, 0, true, err), 0);
    hand l = rest_hand(FP_HAND_LEFT), r = rest_hand(FP_HAND_RIGHT);
    put(&x, FP_HAND_LEFT, &l, false);
    step(&x, 0);                             /* the left hand's first frame: engaged */
    assert_int_equal(x.rc, 0);
    assert_true(x.cs.active);
    assert_true(x.cs.intents & FP_INTENT_ENGAGE);
    size_t li = slot_of(&x, "mouth_corner_left");
    for (int f = 0; f < 20; f++) {           /* the left index curls: the left corner moves */
        l.a[FP_SENSOR_INDEX_MPJ] += (float)(1.5 * DEG);
        put(&x, FP_HAND_LEFT, &l, false);
        step(&x, 0);
    }
    float dl = fabsf(x.end[li][0] - x.start[li][0]) + fabsf(x.end[li][1] - x.start[li][1]) +
               fabsf(x.end[li][2] - x.start[li][2]);
    assert_true(dl > 0.05f);                 /* (mesh units: half a millimetre) */
    size_t ri = slot_of(&x, "mouth_corner_right");
    assert_memory_equal(x.start[ri], x.end[ri], sizeof x.start[ri]); /* the left ring: still */
    /* the right hand arrives too: the left keeps driving */
    put(&x, FP_HAND_RIGHT, &r, false);
    put(&x, FP_HAND_LEFT, &l, false);
    step(&x, 0);
    assert_true(x.cs.active);
    assert_int_equal(x.cs.intents & FP_INTENT_CANCEL, 0);
    /* the left goes, the right stays: this frame ends the left's gesture */
    gone(&x, FP_HAND_LEFT);
    put(&x, FP_HAND_RIGHT, &r, false);
    step(&x, 0);
    assert_true(x.cs.intents & FP_INTENT_CANCEL);
    assert_false(x.cs.active);
    put(&x, FP_HAND_RIGHT, &r, false);
    step(&x, 0);                             /* and the right engages, its pose the zero */
    assert_true(x.cs.active);
    assert_true(x.cs.intents & FP_INTENT_ENGAGE);
    for (int f = 0; f < 20; f++) {           /* the right index curls: the right corner moves */
        r.a[FP_SENSOR_INDEX_MPJ] += (float)(1.5 * DEG);
        put(&x, FP_HAND_RIGHT, &r, false);
        step(&x, 0);
    }
    ri = slot_of(&x, "mouth_corner_right");
    li = slot_of(&x, "mouth_corner_left");
    float dr = fabsf(x.end[ri][0] - x.start[ri][0]) + fabsf(x.end[ri][1] - x.start[ri][1]) +
               fabsf(x.end[ri][2] - x.start[ri][2]);
    assert_true(dr > 0.05f);
    assert_memory_equal(x.start[li], x.end[li], sizeof x.start[li]);
    close_onehand(&x);
    /* both there from the start: the right */
    assert_int_equal(open_onehand(&x, NULL, 0, true, err), 0);
    l = rest_hand(FP_HAND_LEFT);
    r = rest_hand(FP_HAND_RIGHT);
    put(&x, FP_HAND_LEFT, &l, false);
    put(&x, FP_HAND_RIGHT, &r, false);
    step(&x, 0);
    assert_true(x.cs.active);
    for (int f = 0; f < 20; f++) {           /* only the left moves: nothing */
        l.a[FP_SENSOR_INDEX_MPJ] += (float)(1.5 * DEG);
        put(&x, FP_HAND_LEFT, &l, false);
        put(&x, FP_HAND_RIGHT, &r, false);
        step(&x, 0);
        assert_memory_equal(x.start, x.end, x.cs.count * sizeof x.start[0]);
    }
    close_onehand(&x);
}

/* auto=1: a hand held still for `still` seconds engages; a moving one does not. */
static void test_auto_still(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    fp_param half[] = {{"still", "0.5"}};     /* still_mm=10 (the default) */
    assert_int_equal(open_onehand(&x, half, 1, true, err), 0);
    hand h = rest_hand(FP_HAND_RIGHT);
    for (int f = 0; f < 100; f++) {          /* moving 11 mm a frame: never still */
        h.pos[0] += f % 20 < 10 ? 11.0f : -11.0f;
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        assert_false(x.cs.active);
    }
    int engaged_at = -1;
    for (int f = 0; f < 100 && engaged_at < 0; f++) {  /* now still (0.1 mm jitter) */
        h.pos[1] += (f % 2 ? 0.1f : -0.1f);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        if (x.cs.active) engaged_at = f;
    }
    assert_int_equal(engaged_at, 49);        /* 0.5 s after the last move, 100 frames/s */
    assert_true(x.cs.intents & FP_INTENT_ENGAGE);
    close_onehand(&x);
    fp_param p[] = {{"still", "0"}};          /* still=0: at first sight */
    assert_int_equal(open_onehand(&x, p, 1, true, err), 0);
    put(&x, FP_HAND_RIGHT, &h, false);
    step(&x, 0);
    assert_true(x.cs.active);
    close_onehand(&x);
    assert_int_equal(open_onehand(&x, NULL, 0, true, err), 0); /* the default: the same */
    h.pos[0] += 11.0f;                        /* (moving: no stillness asked) */
    put(&x, FP_HAND_RIGHT, &h, false);
    step(&x, 0);
    assert_true(x.cs.active);
    assert_true(x.cs.intents & FP_INTENT_ENGAGE);
    close_onehand(&x);
    fp_param q[] = {{"auto", "0"}};           /* auto=0: only by request */
    assert_int_equal(open_onehand(&x, q, 1, true, err), 0);
    for (int f = 0; f < 100; f++) {
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        assert_false(x.cs.active);
    }
    close_onehand(&x);
}

/* Commit and cancel end the gesture and put jaw.open back to neutral. With auto=0 the next
 * gesture waits for a request; on the defaults (engaged at first sight) the next frame
 * engages again with the hand's pose then as the zero: the committed shape stays in the
 * base, and a cancel (X) re-zeroes the hand. */
static void test_commit_cancel(void **state)
{
    (void)state;
    for (int automatic = 0; automatic <= 1; automatic++) {
        fx x;
        char err[1024];
        fp_param p[] = {{"jaw", "flexion"}, {"ease", "0"}, {"auto", "0"}}; /* the thumb curls, straight */
        assert_int_equal(open_onehand(&x, p, automatic ? 2 : 3, true, err), 0);
        hand h = engaged_rest(&x);
        assert_true(x.cs.active);
        h.a[FP_SENSOR_THUMB_MPJ] += (float)(20 * DEG);
        h.a[FP_SENSOR_INDEX_MPJ] += (float)(20 * DEG);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        assert_true(jaw(&x) > 0.4);
        step(&x, FP_INTENT_COMMIT);               /* this frame's shape goes into the base */
        assert_true(x.cs.active);
        assert_true(x.cs.intents & FP_INTENT_COMMIT);
        assert_true(jaw(&x) > 0.4);
        step(&x, 0);
        assert_float_equal(jaw(&x), 0.0, 0);
        if (automatic) {                          /* engaged again: this pose is the zero */
            assert_true(x.cs.active);
            assert_true(x.cs.intents & FP_INTENT_ENGAGE);
        } else {
            assert_false(x.cs.active);
            step(&x, FP_INTENT_ENGAGE);           /* a new gesture from this pose */
            assert_true(x.cs.active);
        }
        assert_memory_equal(x.start, x.end, x.cs.count * sizeof x.start[0]);
        h.a[FP_SENSOR_THUMB_MPJ] += (float)(10 * DEG);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        assert_true(jaw(&x) > 0.2);
        step(&x, FP_INTENT_CANCEL);
        assert_false(x.cs.active);
        assert_true(x.cs.intents & FP_INTENT_CANCEL);
        assert_float_equal(jaw(&x), 0.0, 0);
        step(&x, 0);
        assert_int_equal(x.cs.active, automatic); /* the defaults: re-zeroed at once */
        assert_float_equal(jaw(&x), 0.0, 0);
        if (automatic) assert_memory_equal(x.start, x.end, x.cs.count * sizeof x.start[0]);
        close_onehand(&x);
    }
}

/* jaw.open is the mapping's only while a shape is shown: it sets none while the hand rests
 * (the audio input's jaw flap has the channel then), the shape's while engaged, and neutral
 * once when the shape goes, at the first frame and after a reset. */
static void test_jaw_left_alone_at_rest(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    fp_param p[] = {{"auto", "0"}, {"jaw", "flexion"}, {"ease", "0"}};
    assert_int_equal(open_onehand(&x, p, 3, true, err), 0);
    hand h = rest_hand(FP_HAND_RIGHT);
    for (int f = 0; f < 30; f++) {            /* a hand, not engaged; then none */
        if (f < 20) put(&x, FP_HAND_RIGHT, &h, false);
        else gone(&x, FP_HAND_RIGHT);
        step(&x, 0);
        assert_int_equal(x.rc, 0);
    }
    assert_int_equal(x.jaw_sets, 1);          /* the first frame's neutral, then none */
    put(&x, FP_HAND_RIGHT, &h, false);
    step(&x, FP_INTENT_ENGAGE);
    h.a[FP_SENSOR_THUMB_MPJ] += (float)(9 * DEG);
    put(&x, FP_HAND_RIGHT, &h, false);
    step(&x, 0);
    assert_float_equal(jaw(&x), 0.2, 0.01);
    size_t sets = x.jaw_sets;
    assert_int_equal(sets, 3);                /* and the engage frame's and this one's */
    step(&x, FP_INTENT_CANCEL);               /* the shape goes: neutral, once */
    assert_float_equal(jaw(&x), 0.0, 0);
    assert_int_equal(x.jaw_sets, sets + 1);
    for (int f = 0; f < 10; f++) step(&x, 0);
    assert_int_equal(x.jaw_sets, sets + 1);
    x.m->reset(x.m);                          /* reset: neutral once more, as at the start */
    for (int f = 0; f < 10; f++) step(&x, 0);
    assert_int_equal(x.jaw_sets, sets + 2);
    close_onehand(&x);
}

/* hold=1: the face stays posed while the hand is gone, and the next engage continues from
 * it; hold=0: the shape goes with the hand. */
static void test_hold(void **state)
{
    (void)state;
    for (int hold = 0; hold <= 1; hold++) {
        fx x;
        char err[1024];
        fp_param p[] = {{"hold", hold ? "1" : "0"}, {"jaw", "flexion"}, {"ease", "0"}}; /* straight */
        assert_int_equal(open_onehand(&x, p, 3, true, err), 0);
        hand h = engaged_rest(&x);
        h.pos[1] += 5;                        /* 5 mm up: every landmark 0.5 units up */
        h.a[FP_SENSOR_THUMB_MPJ] += (float)(9 * DEG);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        float e1[5][3];
        memcpy(e1, x.end, sizeof e1);
        double j1 = jaw(&x);
        assert_float_equal(j1, 0.2, 0.01);
        gone(&x, FP_HAND_RIGHT);
        step(&x, 0);
        if (!hold) {
            assert_false(x.cs.active);
            assert_true(x.cs.intents & FP_INTENT_CANCEL);
            assert_float_equal(jaw(&x), 0.0, 0);
            close_onehand(&x);
            continue;
        }
        for (int f = 0; f < 20; f++) {        /* gone: the last control set stays */
            assert_true(x.cs.active);
            assert_memory_equal(x.end, e1, sizeof e1);
            assert_float_equal(jaw(&x), j1, 0);
            step(&x, 0);
        }
        h.pos[1] -= 40;                       /* back elsewhere: the held shape until engage */
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        assert_memory_equal(x.end, e1, sizeof e1);
        step(&x, FP_INTENT_ENGAGE);           /* the new pose is the zero, shape kept */
        assert_memory_equal(x.end, e1, sizeof e1);
        h.pos[1] += 5;                        /* 5 mm more up: 1.0 unit above the landmarks */
        h.a[FP_SENSOR_THUMB_MPJ] += (float)(9 * DEG);
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, 0);
        size_t k = slot_of(&x, "upper_lip");
        assert_float_equal(x.end[k][1] - x.start[k][1], 1.0, 0.01);
        assert_float_equal(jaw(&x), 0.4, 0.01);
        step(&x, FP_INTENT_ENGAGE);           /* a clutch while engaged: re-zero, keep */
        assert_float_equal(x.end[k][1] - x.start[k][1], 1.0, 0.01);
        h.pos[1] -= 30;                       /* the hand moves down, re-zeroed, then stops */
        put(&x, FP_HAND_RIGHT, &h, false);
        step(&x, FP_INTENT_ENGAGE);
        assert_float_equal(x.end[k][1] - x.start[k][1], 1.0, 0.01);
        close_onehand(&x);
    }
}

/* Without a rig: a log line at create and an inactive control set every frame,
 * never a crash (a 1.1 frame with rig NULL, and a 1.0 frame without the field). */
static void test_no_rig(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    assert_int_equal(open_onehand(&x, NULL, 0, false, err), 0);
    assert_non_null(strstr(x.log, "onehand needs a rig (--rig)"));
    x.in.rig = NULL;
    hand h = engaged_rest(&x);
    assert_int_equal(x.rc, 0);
    assert_false(x.cs.active);
    assert_int_equal(x.cs.count, 0);
    assert_int_equal(x.cs.channel_count, 0);
    x.in.size = offsetof(fp_frame_input, mm_per_unit); /* an ABI 1.0 host */
    step(&x, FP_INTENT_ENGAGE);
    assert_int_equal(x.rc, 0);
    assert_false(x.cs.active);
    close_onehand(&x);
    /* the rig per frame only (no extension): the log warns at create, frames work */
    assert_int_equal(open_onehand(&x, NULL, 0, false, err), 0);
    put(&x, FP_HAND_RIGHT, &h, false);
    step(&x, FP_INTENT_ENGAGE);
    assert_int_equal(x.rc, 0);
    assert_true(x.cs.active);
    close_onehand(&x);
}

static void test_keys(void **state)
{
    (void)state;
    fx x;
    char err[1024];
    fp_param a[] = {{"hand", "both"}};
    assert_int_equal(open_onehand(&x, a, 1, true, err), -EINVAL);
    assert_non_null(strstr(err, "onehand: key 'hand': 'both' is not one of auto|left|right"));
    close_onehand(&x);
    fp_param b[] = {{"targets", "nose_tip/chin"}};
    assert_int_equal(open_onehand(&x, b, 1, true, err), -EINVAL);
    assert_non_null(strstr(err, "names 2 fingers; expected 4"));
    close_onehand(&x);
    fp_param c[] = {{"targets", "nose_tip/-/-/no_such_point"}};
    assert_int_equal(open_onehand(&x, c, 1, true, err), -EINVAL);
    assert_non_null(strstr(err, "landmark 'no_such_point' is not in rig 'ict-facekit' (key targets)"));
    close_onehand(&x);
    fp_param d[] = {{"targets", "a+b+c/-/-/-"}};
    assert_int_equal(open_onehand(&x, d, 1, true, err), -EINVAL);
    assert_non_null(strstr(err, "more than 2 landmarks for one finger"));
    close_onehand(&x);
    fp_param e[] = {{"gain", "-1"}};
    assert_int_equal(open_onehand(&x, e, 1, true, err), -EINVAL);
    assert_non_null(strstr(err, "key 'gain': '-1' is not a number in [0, 20] mm/mm"));
    close_onehand(&x);
    /* a custom table: nose_tip and both cheeks, index and ring only */
    fp_param ok[] = {{"targets", "nose_tip/-/cheek_left+cheek_right/-"}, {"map", "brows"}};
    assert_int_equal(open_onehand(&x, ok, 2, true, err), 0);
    hand h = engaged_rest(&x);
    assert_int_equal(x.cs.count, 3);
    slot_of(&x, "nose_tip");
    slot_of(&x, "cheek_left");
    slot_of(&x, "cheek_right");
    close_onehand(&x);
    fp_param br[] = {{"map", "brows"}, {"hand", "left"}};
    assert_int_equal(open_onehand(&x, br, 2, true, err), 0);
    h = rest_hand(FP_HAND_LEFT);
    put(&x, FP_HAND_LEFT, &h, false);
    step(&x, FP_INTENT_ENGAGE);
    assert_int_equal(x.cs.count, 4);
    /* the left hand's index drives the face's left outer brow (mirrored) */
    assert_memory_equal(x.start[0], landmark("brow_outer_left")->position, sizeof x.start[0]);
    close_onehand(&x);
    /* the typed table: every key has a type, a default, a description; numbers a range */
    assert_int_equal(open_onehand(&x, NULL, 0, true, err), 0);
    const fp_mapping_factory *f = x.plugin.factory;
    size_t n = 0;
    for (const fp_param_info *k = f->params; k->name; k++, n++) {
        assert_non_null(k->default_value);
        assert_non_null(k->description);
        if (k->type == FP_PARAM_FLOAT) assert_true(k->min < k->max);
        assert_non_null(strstr(f->usage, k->name));   /* documented in the usage text */
    }
    assert_int_equal(n, 14);
    close_onehand(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thumb_curl_opens_jaw), cmocka_unit_test(test_angles_only_thumb),
        cmocka_unit_test(test_jaw_opening),          cmocka_unit_test(test_tremor_leaves_jaw_shut),          cmocka_unit_test(test_still_hand),
        cmocka_unit_test(test_start_points_are_landmarks),
        cmocka_unit_test(test_relative_motion_tracker), cmocka_unit_test(test_angles_only_motion),
        cmocka_unit_test(test_left_ignores_right),   cmocka_unit_test(test_auto_still),
        cmocka_unit_test(test_auto_hand),
        cmocka_unit_test(test_commit_cancel),        cmocka_unit_test(test_hold),
        cmocka_unit_test(test_jaw_left_alone_at_rest),
        cmocka_unit_test(test_no_rig),               cmocka_unit_test(test_keys),
    };
    return cmocka_run_group_tests(tests, setup_rig, teardown_rig);
}
