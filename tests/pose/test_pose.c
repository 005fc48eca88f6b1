/* core/pose: hand state from events, forward kinematics, workspace calibration. */
#define _GNU_SOURCE
#include "fp_calib_file.h"
#include "fp_calib_fit.h"
#include "fp_mesh.h"
#include "fp_pose.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "pose_events.h"

static fp_event positions_event(int hand, float base, int64_t t)
{
    float mm[FP_HAND_JOINTS][3];
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) mm[j][k] = base + 10.f * j + k;
    return joints_event(hand, (const float (*)[3])mm, t);
}

/* Joint positions go through p = scale * mm + offset, exactly (double, rounded once). */
static void test_positions_calibrated(void **state)
{
    (void)state;
    fp_calibration c = {0.25, {1.0, -2.0, 3.5}, {0, 0, 0, 0}, {{0, 0, 0}, {0, 0, 0}}, {0, 0, 0, 0}};
    fp_pose_state p;
    fp_pose_init(&p, 0, &c);
    fp_event ev = positions_event(FP_HAND_RIGHT, 100.f, 42);
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_LEFT].present);
    assert_true(p.poses[FP_HAND_RIGHT].present);
    assert_int_equal(p.poses[FP_HAND_RIGHT].time_ns, 42);
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++)
            assert_true(p.poses[FP_HAND_RIGHT].joints[j][k] ==
                        (float)(0.25 * ev.positions.mm[j][k] + c.offset[k]));
    /* A disconnect hides the hand until its next event. */
    fp_event st;
    memset(&st, 0, sizeof st);
    st.header.type = FP_EVENT_STATUS;
    st.header.hand = FP_HAND_RIGHT;
    st.status.code = FP_STATUS_DISCONNECTED;
    fp_pose_take_event(&p, &st);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_RIGHT].present);
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    assert_true(p.poses[FP_HAND_RIGHT].present);
    /* An event without a hand changes nothing. */
    fp_event none = positions_event(-1, 0.f, 1);
    fp_pose_take_event(&p, &none);
    fp_pose_build(&p);
    assert_false(p.poses[FP_HAND_LEFT].present);
}

/* Angles only: forward kinematics from the default wrist (no wrist pose) or the given one;
 * checked against fp_hand_fk called directly, and the two wrists differ by their offset. */
static void test_angles_forward_kinematics(void **state)
{
    (void)state;
    fp_calibration id = {1.0, {0, 0, 0}, {1, 0, 0, 0}, {{0, 0, 0}, {0, 0, 0}}, {0, 0, 0, 0}};
    fp_pose_state p;
    fp_pose_init(&p, 1.1, &id);
    assert_true(fabsf(p.model.size - 1.1f) < 1e-6f);
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.angles;
    ev.header.type = FP_EVENT_JOINT_ANGLES;
    ev.header.hand = FP_HAND_LEFT;
    ev.angles.valid = (1u << FP_GLOVE_SENSORS) - 1;
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) ev.angles.radians[i] = 0.02f * (float)i;
    fp_pose_take_event(&p, &ev);
    fp_pose_build(&p);
    float pos[3], rot[4], want[FP_HAND_JOINTS][3];
    fp_pose_default_wrist(FP_HAND_LEFT, pos, rot);
    assert_true(pos[0] == -80.f && pos[1] == 200.f && pos[2] == 60.f && rot[0] == 1.f);
    assert_int_equal(fp_hand_fk(&p.model, FP_HAND_LEFT, ev.angles.radians, ev.angles.valid, pos, rot, want), 0);
    assert_memory_equal(p.poses[FP_HAND_LEFT].joints, want, sizeof want);
    /* A wrist pose moves the hand by its offset (same rotation). */
    fp_event w;
    memset(&w, 0, sizeof w);
    w.header.size = sizeof w.wrist;
    w.header.type = FP_EVENT_WRIST_POSE;
    w.header.hand = FP_HAND_LEFT;
    w.wrist.position_mm[0] = -80.f + 5.f;
    w.wrist.position_mm[1] = 200.f;
    w.wrist.position_mm[2] = 60.f;
    w.wrist.rotation[0] = 1.f;
    fp_pose_take_event(&p, &w);
    fp_pose_build(&p);
    for (int j = 0; j < FP_HAND_JOINTS; j++) assert_true(fabsf(p.poses[FP_HAND_LEFT].joints[j][0] - want[j][0] - 5.f) < 1e-3f);
}

/* The life-size fit's promises, on a made-up head and workspace. */
static void test_fit_workspace(void **state)
{
    (void)state;
    float ws_min[3], ws_max[3];
    fp_pose_default_workspace(ws_min, ws_max);
    assert_true(ws_min[0] == -150.f && ws_max[1] == 330.f && ws_min[2] == -120.f);
    const float fmin[3] = {-8.f, -10.f, -4.f}, fmax[3] = {8.f, 14.f, 6.f};
    fp_calibration c;
    fp_pose_fit_workspace(&c, 10.0, ws_min, ws_max, fmin, fmax);
    assert_true(fabs(c.scale - 0.1) < 1e-15); /* 1 / mm_per_unit: the hands life-size */
    float centre[3] = {0.5f * (ws_min[0] + ws_max[0]), 0.5f * (ws_min[1] + ws_max[1]), ws_min[2]}, out[3];
    fp_pose_to_mesh(&c, FP_HAND_RIGHT, centre, out);
    assert_true(fabsf(out[0] - 0.f) < 1e-5f);
    assert_true(fabsf(out[1] - 2.f) < 1e-5f);
    assert_true(fabsf(out[2] - (6.f - (float)(FP_POSE_REACH_PRESS_MM * 0.1))) < 1e-5f); /* front at the face's */
    /* A rotation and a per-hand offset: a quarter turn about y maps +x to -z. */
    c.rotation[0] = c.rotation[2] = sqrt(0.5);
    c.hand_offset[FP_HAND_LEFT][1] = 3;
    float a[3] = {0, 0, 0}, b[3] = {10, 0, 0}, pa[3], pb[3];
    fp_pose_to_mesh(&c, FP_HAND_LEFT, a, pa);
    fp_pose_to_mesh(&c, FP_HAND_LEFT, b, pb);
    assert_true(fabsf(pb[0] - pa[0]) < 1e-5f && fabsf(pb[2] - pa[2] + 1.f) < 1e-5f);
    assert_true(fabsf(pa[1] - (float)(c.offset[1] + 3)) < 1e-5f);
}

static fp_mesh *load_face(const char *rel)
{
    char path[1024], err[512];
    const char *root = getenv("FP_SHARED_DATA");
    snprintf(path, sizeof path, "%s/faces/%s", root && *root ? root : "../shared/data", rel);
    fp_mesh *m = NULL;
    if (fp_mesh_load(path, &m, err, sizeof err)) fail_msg("%s", err);
    return m;
}

/* The mesh's unit from the head, on the three real faces: the ICT face is in centimetres
 * (10 mm per unit); Lee Perry-Smith (head and shoulders) and the MediaPipe mask get a head of
 * plausible size: a 190 mm hand spans 0.75..0.95 of the head's height (230 mm chin to crown
 * for heads), the head box is 130..230 mm wide. */
static void test_head_detect(void **state)
{
    (void)state;
    static const struct { const char *rel; fp_head_method method; double lo, hi; } faces[] = {
        {"ict-facekit/generic_neutral_mesh.obj", FP_HEAD_NECK, 9.5, 10.5},
        {"lee-perry-smith/LeePerrySmith.obj", FP_HEAD_NECK, 35, 65},
        {"mediapipe-canonical/canonical_face_model.obj", FP_HEAD_FACE_WIDTH, 8, 11},
    };
    for (size_t i = 0; i < sizeof faces / sizeof faces[0]; i++) {
        fp_mesh *m = load_face(faces[i].rel);
        fp_head h;
        assert_int_equal(fp_head_detect(m->positions, m->vertex_count, &h), 0);
        print_message("%s: %.3f mm per unit, %s\n", faces[i].rel, h.mm_per_unit, h.how);
        assert_int_equal(h.method, faces[i].method);
        assert_true(h.mm_per_unit > faces[i].lo && h.mm_per_unit < faces[i].hi);
        double width_mm = (h.max[0] - h.min[0]) * h.mm_per_unit;
        assert_true(width_mm > 130 && width_mm < 230);
        if (h.method == FP_HEAD_NECK) {
            double height_mm = (h.max[1] - h.neck_y) * h.mm_per_unit;
            assert_true(190 / height_mm > 0.75 && 190 / height_mm < 0.95);
            /* Lee Perry-Smith's shoulders are not the head: the box is under half the mesh wide. */
            float lo[3], hi[3];
            fp_mesh_bounds(m, lo, hi);
            if (i == 1) assert_true(h.max[0] - h.min[0] < 0.5f * (hi[0] - lo[0]));
        }
        /* Gloves placed in front of each half of the face: palm toward it (the hand's +y,
         * its back, along +z), the open fingertips just in front of the surface. */
        fp_pose_state p;
        fp_calibration c;
        float ws_min[3], ws_max[3];
        fp_pose_default_workspace(ws_min, ws_max);
        fp_pose_fit_workspace(&c, h.mm_per_unit, ws_min, ws_max, h.min, h.max);
        fp_pose_init(&p, 0, &c);
        fp_pose_place_gloves(&p, m->positions, m->vertex_count, &h);
        assert_true(p.glove_placed);
        for (int hand = 0; hand < FP_HANDS; hand++) {
            fp_event ev;
            memset(&ev, 0, sizeof ev);
            ev.header.type = FP_EVENT_JOINT_ANGLES;
            ev.header.hand = hand;
            fp_pose_take_event(&p, &ev);
        }
        fp_pose_build(&p);
        float cx = 0.5f * (h.min[0] + h.max[0]);
        for (int hand = 0; hand < FP_HANDS; hand++) {
            const float (*j)[3] = p.poses[hand].joints;
            float tip = j[FP_JOINT_TIP(2)][0];
            assert_true(hand == FP_HAND_LEFT ? tip < cx : tip > cx);
            assert_true(j[FP_JOINT_TIP(2)][1] > j[FP_JOINT_PALM][1]); /* fingers up */
            float z;
            assert_true(fp_head_surface_z(m->positions, m->vertex_count, j[FP_JOINT_TIP(2)][0],
                                          j[FP_JOINT_TIP(2)][1], (float)(15 / h.mm_per_unit),
                                          h.neck_y, INFINITY, &z));
            double gap_mm = (j[FP_JOINT_TIP(2)][2] - z) * h.mm_per_unit;
            assert_true(gap_mm >= FP_POSE_GLOVE_GAP_MM - 0.01 && gap_mm < 60);
        }
        fp_mesh_free(&m);
    }
}

/* The nose (fp_head_nose): on the three real faces, along +z (so the session's hint stays
 * quiet on them); on a smooth head of evenly spread vertices (an ellipsoid with a nose bump)
 * turned every way a face is exported, along the axis it was turned to, and up along the
 * head's long axis. */
static void test_head_nose(void **state)
{
    (void)state;
    static const char *faces[] = {"ict-facekit/generic_neutral_mesh.obj", "lee-perry-smith/LeePerrySmith.obj",
                                  "mediapipe-canonical/canonical_face_model.obj"};
    fp_head_front f;
    for (size_t i = 0; i < sizeof faces / sizeof faces[0]; i++) {
        fp_mesh *m = load_face(faces[i]);
        assert_int_equal(fp_head_nose(m->positions, m->vertex_count, NULL, &f), 0);
        print_message("%s: nose along %c%c, cap %.3f against %.3f\n", faces[i], f.sign > 0 ? '+' : '-',
                      "xyz"[f.axis], f.cap, f.opposite);
        assert_int_equal(f.axis, 2);
        assert_int_equal(f.sign, 1);
        fp_mesh_free(&m);
    }
    enum { LAT = 60, LON = 90 };
    static float head[3 * (LAT + 1) * LON], pos[3 * (LAT + 1) * LON];
    for (int i = 0; i <= LAT; i++)
        for (int j = 0; j < LON; j++) {
            const double th = M_PI * i / LAT, ph = 2 * M_PI * j / LON;
            const double d[3] = {sin(th) * sin(ph), cos(th), sin(th) * cos(ph)}, a[3] = {7.5, 11.5, 9.5};
            const double nose = exp(-(pow(d[0] / 0.12, 2) + pow((d[1] + 0.05) / 0.2, 2))) * fmax(d[2], 0);
            for (int k = 0; k < 3; k++) head[3 * (i * LON + j) + k] = (float)(a[k] * d[k] * (1 + 0.25 * nose));
        }
    /* (up, facing) as axis indices with signs: Y-up, Z-up looking along -y, Z-up along +x, Y-up along -z */
    static const int turns[][4] = {{1, 1, 2, 1}, {2, 1, 1, -1}, {2, 1, 0, 1}, {1, 1, 2, -1}};
    for (size_t t = 0; t < sizeof turns / sizeof turns[0]; t++) {
        const int ua = turns[t][0], us = turns[t][1], fa = turns[t][2], fs = turns[t][3], la = 3 - ua - fa;
        for (int v = 0; v < (LAT + 1) * LON; v++) {
            const float *h = head + 3 * v;
            float *p = pos + 3 * v;
            p[la] = h[0], p[ua] = (float)us * h[1], p[fa] = (float)fs * h[2];
        }
        assert_int_equal(fp_head_nose(pos, (LAT + 1) * LON, NULL, &f), 0);
        assert_int_equal(f.axis, fa);
        assert_int_equal(f.sign, fs);
        assert_int_equal(f.up_axis, ua);
        assert_true(f.opposite >= FP_HEAD_NOSE_CONTRAST * f.cap);
    }
    /* a ball has no nose; a flat mesh is refused */
    for (int v = 0; v < (LAT + 1) * LON; v++) {
        const float *h = head + 3 * v;
        const double r = sqrt((double)h[0] * h[0] + (double)h[1] * h[1] + (double)h[2] * h[2]);
        for (int k = 0; k < 3; k++) pos[3 * v + k] = (float)(10 * h[k] / r);
    }
    assert_int_equal(fp_head_nose(pos, (LAT + 1) * LON, NULL, &f), -ENOENT);
    for (int v = 0; v < (LAT + 1) * LON; v++) pos[3 * v + 2] = 0;
    assert_int_equal(fp_head_nose(pos, (LAT + 1) * LON, NULL, &f), -EINVAL);
}

/* A head of a few float steps (a face in metres moved 1e6 units off the origin: floats keep
 * steps of 0.0625 there) has no height above its neck: fp_head_detect said 0 with an infinite
 * mm per unit (run printed "inf mm per mesh unit" and a NaN summary, exit 0); it refuses it, and
 * whatever it returns 0 for has a finite unit > 0. */
static void test_head_detect_coarse(void **state)
{
    (void)state;
    enum { LAT = 60, LON = 80 };
    static float pos[3 * (LAT + 1) * LON];
    for (int i = 0; i <= LAT; i++)
        for (int j = 0; j < LON; j++) {
            const double th = M_PI * i / LAT, ph = 2 * M_PI * j / LON;
            float *p = pos + 3 * (i * LON + j);
            p[0] = (float)(1e6 + 0.075 * sin(th) * sin(ph));
            p[1] = (float)(1e6 + 0.115 * cos(th));
            p[2] = (float)(1e6 + 0.095 * sin(th) * cos(ph));
        }
    fp_head h;
    int rc = fp_head_detect(pos, (LAT + 1) * LON, &h);
    if (rc == 0 && !(isfinite(h.mm_per_unit) && h.mm_per_unit > 0))
        fail_msg("fp_head_detect returned 0 with %g mm per unit (%s)", h.mm_per_unit, h.how);
    assert_int_equal(rc, -EINVAL);
    /* the same head at the origin is found, about 1000 mm per unit (230 mm over 0.23 units) */
    for (int i = 0; i <= LAT; i++)
        for (int j = 0; j < LON; j++) {
            const double th = M_PI * i / LAT, ph = 2 * M_PI * j / LON;
            float *p = pos + 3 * (i * LON + j);
            p[0] = (float)(0.075 * sin(th) * sin(ph));
            p[1] = (float)(0.115 * cos(th));
            p[2] = (float)(0.095 * sin(th) * cos(ph));
        }
    assert_int_equal(fp_head_detect(pos, (LAT + 1) * LON, &h), 0);
    assert_true(h.mm_per_unit > 900 && h.mm_per_unit < 1100);
}

/* The face's frame (fp_calibration.face): a point goes through scale, R and the offsets in the
 * face's frame, then F turns it into the mesh's; fp_calibration_flatten folds F into R and the
 * offsets with the same result, and so does a calibration file saved from it; a face of all
 * zeros or the identity changes nothing, bit for bit. */
static void test_face_frame(void **state)
{
    (void)state;
    const double h = 0.70710678118654752440; /* F: 90 degrees about x (a Z-up mesh) */
    fp_calibration c = {0.1, {1, 2, 3}, {0.9238795325, 0, 0.3826834324, 0}, {{0.5, 0, 0}, {0, -0.5, 0.25}},
                        {h, h, 0, 0}},
                   flat, none = c, id = c, back;
    memset(none.face, 0, sizeof none.face);
    id.face[0] = 1, id.face[1] = id.face[2] = id.face[3] = 0;
    fp_calibration_flatten(&c, &flat);
    assert_true(flat.face[0] == 0 && flat.face[1] == 0 && flat.face[2] == 0 && flat.face[3] == 0);
    char dir[] = "/tmp/fp_face_XXXXXX", path[256], err[512];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/c.json", dir);
    assert_int_equal(fp_calibration_save(path, &c, "test", err, sizeof err), 0);
    assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), 0);
    const float pts[3][3] = {{0, 0, 0}, {120, -40, 75}, {-300, 210, -15}};
    for (int hand = 0; hand < FP_HANDS; hand++)
        for (int i = 0; i < 3; i++) {
            float a[3], b[3], f[3], u[3], v[3];
            fp_pose_to_mesh(&c, hand, pts[i], a);
            fp_pose_to_mesh(&none, hand, pts[i], u);
            fp_pose_to_mesh(&id, hand, pts[i], v);
            assert_memory_equal(u, v, sizeof u); /* (the identity: as no face) */
            /* F (x, y, z) = (x, -z, y) */
            assert_true(fabsf(a[0] - u[0]) < 1e-5f && fabsf(a[1] + u[2]) < 1e-5f && fabsf(a[2] - u[1]) < 1e-5f);
            fp_pose_to_mesh(&flat, hand, pts[i], b);
            fp_pose_to_mesh(&back, hand, pts[i], f);
            for (int k = 0; k < 3; k++) {
                assert_true(fabsf(a[k] - b[k]) < 1e-5f);
                assert_true(fabsf(a[k] - f[k]) < 1e-4f);
            }
        }
    unlink(path);
    rmdir(dir);
    /* a Z-up face's axes give that F; one axis, a long one or parallel ones are refused */
    const float zu[3] = {0, 0, 1}, ny[3] = {0, -1, 0}, zero[3] = {0, 0, 0}, two[3] = {0, 0, 2};
    double q[4];
    assert_int_equal(fp_face_from_axes(zu, ny, q), 0);
    assert_true(fabs(q[0] - h) < 1e-12 && fabs(q[1] - h) < 1e-12 && fabs(q[2]) < 1e-12 && fabs(q[3]) < 1e-12);
    assert_true(fp_face_turned(q));
    assert_int_equal(fp_face_from_axes(zu, zero, q), -EINVAL);
    assert_int_equal(fp_face_from_axes(two, ny, q), -EINVAL);
    assert_int_equal(fp_face_from_axes(zu, zu, q), -EINVAL);
    const double ident[4] = {1, 0, 0, 0}, hair[4] = {cos(0.2 * M_PI / 180), sin(0.2 * M_PI / 180), 0, 0};
    assert_false(fp_face_turned(ident));
    assert_false(fp_face_turned(hair)); /* (0.4 degrees) */
}

/* The calibration file: a round trip, and errors naming the file and the field. */
static void test_calibration_file(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_calib_XXXXXX", path[256], err[512];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/c.json", dir);
    fp_calibration c = {0.1, {1, 2, 3}, {0, 0, 0, 1}, {{0.5, 0, 0}, {0, -0.5, 0}}, {0, 0, 0, 0}}, back;
    /* the mode a new file gets (0666 under the umask), not the temporary file's 0600 */
    mode_t um = umask(027);
    assert_int_equal(fp_calibration_save(path, &c, "test", err, sizeof err), 0);
    umask(um);
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_mode & 0777, 0640);
    assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), 0);
    assert_true(fabs(back.scale - 0.1) < 1e-15 && back.offset[2] == 3 && back.rotation[3] == 1 &&
                back.hand_offset[1][1] == -0.5);
    static const struct { const char *text, *field; int code; } bad[] = {
        {"{\"rotation\": [1,0,0,0]}", "mm_per_unit", -EBADMSG},
        {"{\"mm_per_unit\": -3}", "mm_per_unit", -ERANGE},
        {"{\"mm_per_unit\": 1e-300}", "mm_per_unit 1e-6 to 1e9", -ERANGE},
        {"{\"scale\": 1e-300}", "scale", -ERANGE},
        {"{\"scale\": 0.1, \"offset\": [0, 1e308, 0]}", "offset[1]: 1e+308 is beyond 1e9", -ERANGE},
        {"{\"scale\": 0.1, \"rotation\": [1, 0, 0]}", "rotation", -EBADMSG},
        {"{\"scale\": 0.1, \"right\": {\"offset\": [1, \"a\", 0]}}", "right.offset[1]", -EBADMSG},
        {"{\"scale\": 0.1, \"rotation\": [0, 0, 0, 0]}", "rotation", -ERANGE},
        {"not json", "not valid JSON", -EBADMSG},
        {"{\"scale\": 0.1,\n \"rotation\": [1, 0, 0, 0]", ":2:", -EBADMSG}, /* cut: the line */
        {"[1, 2]", "not a JSON object", -EBADMSG},
        {"{\"scale\": 0.1}\n{}", ":2:1: text after the JSON object", -EBADMSG},
        {"{\"scale\": 0.1, \"rotaton\": [1, 0, 0, 0]}", "unknown field \"rotaton\"", -EBADMSG},
        {"{\"comment\": 5, \"scale\": 0.1}", "field comment: expected a string", -EBADMSG},
        {"{\"scale\": 0.1, \"offset\": [0, 0, 0], \"offset\": [1, 1, 1]}", "offset given twice", -EBADMSG},
        {"{\"scale\": 0.1, \"left\": {\"offst\": [0, 0, 0]}}", "left.offst", -EBADMSG},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        FILE *f = fopen(path, "w");
        fputs(bad[i].text, f);
        fclose(f);
        assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), bad[i].code);
        assert_non_null(strstr(err, path));
        assert_non_null(strstr(err, bad[i].field));
    }
    { /* a valid calibration after 1 MiB of spaces: refused as too large, not read in part
         (a part would fail as "not valid JSON (it ends too soon)", misleading) */
        FILE *f = fopen(path, "w");
        for (int i = 0; i < 1100; i++) fprintf(f, "%1024s", "");
        fputs("{\"scale\": 0.1}", f);
        fclose(f);
        assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), -EBADMSG);
        assert_non_null(strstr(err, path));
        assert_non_null(strstr(err, "larger than 1 MiB"));
        f = fopen(path, "w"); /* the same under 1 MiB: read */
        for (int i = 0; i < 1000; i++) fprintf(f, "%1024s", "");
        fputs("{\"scale\": 0.1}", f);
        fclose(f);
        assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), 0);
    }
    snprintf(path, sizeof path, "%s/missing.json", dir);
    assert_int_equal(fp_calibration_load(path, &back, err, sizeof err), -ENOENT);
    /* An unwritable place: an error, nothing half-written. */
    snprintf(path, sizeof path, "%s/no/such/dir/c.json", dir);
    assert_int_equal(fp_calibration_save(path, &c, NULL, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, path));
    /* a rename that fails (the target is a folder): the temporary file goes, the folder stays */
    snprintf(path, sizeof path, "%s/sub", dir);
    assert_int_equal(mkdir(path, 0755), 0);
    assert_true(fp_calibration_save(path, &c, NULL, err, sizeof err) < 0);
    assert_int_equal(rmdir(path), 0);
    snprintf(path, sizeof path, "%s/c.json", dir);
    unlink(path);
    assert_int_equal(rmdir(dir), 0); /* (fails with a temporary file left in it) */
}

/* A given scale is a face's: 1 mm to 1 km across (the session's and calibrate's check). */
static void test_head_scale_plausible(void **state)
{
    (void)state;
    double across = 0;
    assert_true(fp_head_scale_plausible(47.5, 10, &across)); /* the ICT face at 10 mm per unit */
    assert_true(fabs(across - 475) < 1e-9);
    assert_true(fp_head_scale_plausible(1, FP_HEAD_ACROSS_MIN_MM, NULL));
    assert_true(fp_head_scale_plausible(1, FP_HEAD_ACROSS_MAX_MM, NULL));
    assert_false(fp_head_scale_plausible(47.5, 1e-300, NULL));
    assert_false(fp_head_scale_plausible(47.5, 1e300, &across));
    assert_false(fp_head_scale_plausible(47.5, NAN, NULL));
}

/* No input tells a workspace: false, box untouched. */
static void test_inputs_workspace_unknown(void **state)
{
    (void)state;
    float a[3] = {1, 2, 3}, b[3] = {4, 5, 6};
    fp_input *none[2] = {NULL, NULL};
    assert_false(fp_pose_inputs_workspace(none, 2, a, b));
    assert_true(a[0] == 1 && b[2] == 6);
}

/* Touch mode on a synthetic recording: the index fingertip rests on three known points
 * (0.8 s each), moves between them, and pauses briefly (0.15 s, not a touch) on the way; the
 * similarity fitted to landmarks made with a known scale, rotation and offset recovers them.
 * Independent reference: the landmarks are built from the mm touches by the known transform
 * (fp_pose_to_mesh), the fit must invert that. */
static void test_calibrate_touch(void **state)
{
    (void)state;
    fp_calibration want = {0};
    want.scale = 1.0 / 9.5;
    double ang = 0.3, ax[3] = {0.2, 1, 0.1}, na = sqrt(0.05 + 1);
    want.rotation[0] = cos(ang / 2);
    for (int k = 0; k < 3; k++) want.rotation[k + 1] = sin(ang / 2) * ax[k] / na;
    want.offset[0] = 1.5, want.offset[1] = -20, want.offset[2] = 4;
    const float touch_mm[3][3] = {{10, 120, -60}, {12, 185, -40}, {8, 250, -55}}; /* chin, nose, forehead */
    float lm[3][3];
    for (int i = 0; i < 3; i++) fp_pose_to_mesh(&want, -1, touch_mm[i], lm[i]);
    /* The recording, 100 Hz: rest 0.8 s at each touch, 0.5 s moves, a 0.15 s pause midway. */
    fp_calib_sample *smp = calloc(2000, sizeof *smp);
    size_t n = 0;
    float at[3] = {60, 100, 40};
    unsigned seed = 7;
    for (int i = 0; i <= 3; i++) {
        const float *to = i < 3 ? touch_mm[i] : (const float[3]){60, 100, 40};
        float from[3] = {at[0], at[1], at[2]};
        for (int f = 0; f < 50 + (i < 3 ? 80 : 0); f++) {
            float u = f < 50 ? (f < 20 ? f / 40.f : f < 35 ? 0.5f : (f - 15) / 40.f) : 1.f;
            for (int k = 0; k < 3; k++) at[k] = from[k] + u * (to[k] - from[k]);
            fp_calib_sample *sm = &smp[n];
            sm->t_ns = (int64_t)n * 10000000LL;
            sm->hand = FP_HAND_RIGHT;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) {
                    seed = seed * 1103515245u + 12345u;
                    float noise = ((float)((seed >> 16) & 0x7fff) / 32767.f - 0.5f) * 1.0f; /* +-0.5 mm */
                    sm->joints[j][k] = at[k] + noise;
                }
            n++;
        }
    }
    fp_calibration got;
    double touched[3][3], rms;
    char err[512];
    assert_int_equal(fp_calib_fit_touch(smp, n, (const float(*)[3])lm, &got, touched, &rms, err, sizeof err), 0);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            assert_true(fabs(touched[i][k] - touch_mm[i][k]) < 0.5);
        }
    print_message("touch fit: scale %.5f (want %.5f), rms %.3g mesh units\n", got.scale, want.scale, rms);
    assert_true(fabs(got.scale - want.scale) < 0.01 * want.scale);
    double dot = 0;
    for (int k = 0; k < 4; k++) dot += got.rotation[k] * want.rotation[k];
    assert_true(fabs(dot) > cos(0.5 * M_PI / 180)); /* within 1 degree */
    for (int k = 0; k < 3; k++) assert_true(fabs(got.offset[k] - want.offset[k]) < 0.2); /* 2 mm */
    /* Over the whole workspace the two maps agree within 2 mm. */
    for (int i = 0; i < 8; i++) {
        float p[3] = {i & 1 ? 150.f : -150.f, i & 2 ? 330.f : 80.f, i & 4 ? 120.f : -120.f}, pg[3], pw[3];
        fp_pose_to_mesh(&got, -1, p, pg);
        fp_pose_to_mesh(&want, -1, p, pw);
        for (int k = 0; k < 3; k++) assert_true(fabsf(pg[k] - pw[k]) < 0.2f);
    }
    /* Two touches only: refused with a message. */
    assert_int_equal(fp_calib_fit_touch(smp, 2 * 130 + 20, (const float(*)[3])lm, &got, NULL, NULL, err, sizeof err), -EDOM);
    assert_non_null(strstr(err, "need 3"));
    /* Collinear landmarks are refused. */
    float line[3][3] = {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}};
    assert_int_equal(fp_calib_fit_touch(smp, n, (const float(*)[3])line, &got, NULL, NULL, err, sizeof err), -EDOM);
    assert_non_null(strstr(err, "lie on a line"));
    /* ... its numbers as %g: touches 1e30 mm out print as 1e+30, not 31 digits each. Three
     * rests of 0.8 s at far points, 0.2 s moves between them (no noise). */
    const float far[4][3] = {{1e30f, 2e30f, 3e30f}, {2e30f, 4e30f, 6e30f}, {3e30f, 5e30f, 8e30f},
                             {0, 0, 0}};
    size_t m = 0;
    for (int i = 0; i < 3; i++)
        for (int f = 0; f < 100; f++, m++) {
            float u = f < 80 ? 0.f : (float)(f - 79) / 20.f;
            smp[m].t_ns = (int64_t)m * 10000000LL;
            smp[m].hand = FP_HAND_RIGHT;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) smp[m].joints[j][k] = far[i][k] + u * (far[i + 1][k] - far[i][k]);
        }
    assert_int_equal(fp_calib_fit_touch(smp, m, (const float(*)[3])line, &got, NULL, NULL, err, sizeof err), -EDOM);
    print_message("far touches: %s\n", err);
    assert_non_null(strstr(err, "lie on a line"));
    assert_non_null(strstr(err, "(1e+30 2e+30 3e+30)"));
    for (const char *p = err; *p; p++) assert_false(strspn(p, "0123456789") > 12);
    free(smp);
}

/* Hold mode: one hand's median palm lands on its hold target (the ICT face). */
static void test_calibrate_hold(void **state)
{
    (void)state;
    char path[4200], err[512];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj",
             getenv("FP_SHARED_DATA") ? getenv("FP_SHARED_DATA") : "../shared/data");
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    fp_head head;
    assert_int_equal(fp_head_detect(m->positions, m->vertex_count, &head), 0);
    fp_calib_sample smp[9] = {0};
    for (int i = 0; i < 9; i++) {
        smp[i].hand = i % 3 ? FP_HAND_RIGHT : FP_HAND_LEFT;
        for (int k = 0; k < 3; k++) smp[i].joints[FP_JOINT_PALM][k] = (float)(100 * k + i * (i % 2 ? 1 : -1));
    }
    fp_calibration c;
    assert_int_equal(fp_calib_fit_hold(smp, 9, m->positions, m->vertex_count, &head, &c, err, sizeof err), 0);
    assert_true(fabs(c.scale - 1 / head.mm_per_unit) < 1e-12);
    for (int h = 0; h < 2; h++) {
        float target[3], med[3], out[3];
        fp_calib_hold_target(m->positions, m->vertex_count, &head, h, target);
        /* medians: left samples 0, 3, 6 -> x {0, 3, -6}: 0; right 1,2,4,5,7,8 -> x {1,-2,-4,5,7,-8}: -0.5 */
        med[0] = h ? -0.5f : 0.f, med[1] = 100 + med[0], med[2] = 200 + med[0];
        fp_pose_to_mesh(&c, h, med, out);
        for (int k = 0; k < 3; k++) assert_true(fabsf(out[k] - target[k]) < 1e-4f);
        assert_true(target[2] > head.max[2] - 40 / head.mm_per_unit); /* on the front of the face */
    }
    fp_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_positions_calibrated),
        cmocka_unit_test(test_angles_forward_kinematics),
        cmocka_unit_test(test_fit_workspace),
        cmocka_unit_test(test_head_detect),
        cmocka_unit_test(test_head_detect_coarse),
        cmocka_unit_test(test_head_nose),
        cmocka_unit_test(test_calibration_file),
        cmocka_unit_test(test_face_frame),
        cmocka_unit_test(test_head_scale_plausible),
        cmocka_unit_test(test_inputs_workspace_unknown),
        cmocka_unit_test(test_calibrate_touch),
        cmocka_unit_test(test_calibrate_hold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
