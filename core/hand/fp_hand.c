/*
 * fp_hand.c: hand skeleton, forward kinematics, positions -> angles, fitting.
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Internals work in double on the mean adult right hand in its own frame (fp_hand.h), then
 * scale, mirror and place. Rotations are 3x3 row-major matrices.
 */
#include "fp_vec.h"
#include "fp_hand.h"

#include "fp_error.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#define DEG(x) ((x) * (M_PI / 180.0))
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef double mat3[3][3];

const char *fp_hand_strerror(int code)
{
    switch (code) {
    case -ERANGE: return "non-finite value (NaN or infinity) in the input";
    case -EDOM: return "degenerate geometry (zero vector, zero quaternion or coincident joints)";
    default: return fp_strerror(code);
    }
}

/* ---------------------------------------------------------------------------------- */
/* Small linear algebra                                                                */

static void rot_x(double a, mat3 r)
{
    double c = cos(a), s = sin(a);
    mat3 t = {{1, 0, 0}, {0, c, -s}, {0, s, c}};
    memcpy(r, t, sizeof t);
}

static void rot_y(double a, mat3 r)
{
    double c = cos(a), s = sin(a);
    mat3 t = {{c, 0, s}, {0, 1, 0}, {-s, 0, c}};
    memcpy(r, t, sizeof t);
}

static void rot_z(double a, mat3 r)
{
    double c = cos(a), s = sin(a);
    mat3 t = {{c, -s, 0}, {s, c, 0}, {0, 0, 1}};
    memcpy(r, t, sizeof t);
}

static void mat_mul(const mat3 a, const mat3 b, mat3 out)
{
    mat3 t;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            t[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
    memcpy(out, t, sizeof t);
}

static void mat_vec(const mat3 a, const double v[3], double out[3])
{
    double t[3];
    for (int i = 0; i < 3; i++)
        t[i] = a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2];
    memcpy(out, t, sizeof t);
}

static void mat_tvec(const mat3 a, const double v[3], double out[3])
{
    double t[3];
    for (int i = 0; i < 3; i++)
        t[i] = a[0][i] * v[0] + a[1][i] * v[1] + a[2][i] * v[2];
    memcpy(out, t, sizeof t);
}

static double normalize3(double v[3])
{
    double n = sqrt(fp_dot3(v, v));
    if (n > 0) {
        v[0] /= n;
        v[1] /= n;
        v[2] /= n;
    }
    return n;
}

static bool finite3f(const float v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

int fp_hand_quat_to_mat(const float qf[4], double r[3][3])
{
    double w = qf[0], x = qf[1], y = qf[2], z = qf[3];
    double n = sqrt(w * w + x * x + y * y + z * z);
    if (!(n >= 1e-6) || !isfinite(n))
        return -EINVAL;
    w /= n, x /= n, y /= n, z /= n;
    r[0][0] = 1 - 2 * (y * y + z * z);
    r[0][1] = 2 * (x * y - w * z);
    r[0][2] = 2 * (x * z + w * y);
    r[1][0] = 2 * (x * y + w * z);
    r[1][1] = 1 - 2 * (x * x + z * z);
    r[1][2] = 2 * (y * z - w * x);
    r[2][0] = 2 * (x * z - w * y);
    r[2][1] = 2 * (y * z + w * x);
    r[2][2] = 1 - 2 * (x * x + y * y);
    return 0;
}

/* A matrix is a quaternion: fp_hand_quat_to_mat / fp_hand_mat_to_quat (fp_hand.h). */
static bool quat_to_mat(const float qf[4], mat3 r)
{
    return fp_hand_quat_to_mat(qf, r) == 0;
}

void fp_hand_mat_to_quat(const double r[3][3], float q[4])
{
    double t = r[0][0] + r[1][1] + r[2][2], w, x, y, z;
    if (t > 0) {
        double s = 2 * sqrt(1 + t);
        w = s / 4, x = (r[2][1] - r[1][2]) / s, y = (r[0][2] - r[2][0]) / s, z = (r[1][0] - r[0][1]) / s;
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        double s = 2 * sqrt(1 + r[0][0] - r[1][1] - r[2][2]);
        w = (r[2][1] - r[1][2]) / s, x = s / 4, y = (r[0][1] + r[1][0]) / s, z = (r[0][2] + r[2][0]) / s;
    } else if (r[1][1] > r[2][2]) {
        double s = 2 * sqrt(1 + r[1][1] - r[0][0] - r[2][2]);
        w = (r[0][2] - r[2][0]) / s, x = (r[0][1] + r[1][0]) / s, y = s / 4, z = (r[1][2] + r[2][1]) / s;
    } else {
        double s = 2 * sqrt(1 + r[2][2] - r[0][0] - r[1][1]);
        w = (r[1][0] - r[0][1]) / s, x = (r[0][2] + r[2][0]) / s, y = (r[1][2] + r[2][1]) / s, z = s / 4;
    }
    if (w < 0)
        w = -w, x = -x, y = -y, z = -z;
    double n = sqrt(w * w + x * x + y * y + z * z);
    q[0] = (float)(w / n), q[1] = (float)(x / n), q[2] = (float)(y / n), q[3] = (float)(z / n);
}

/* ---------------------------------------------------------------------------------- */
/* Model                                                                               */

void fp_hand_model_init(fp_hand_model *m)
{
    if (!m)
        return;
    /* Buryanov & Kotiuk 2010: metacarpal, proximal, middle, distal; soft tip. */
    static const float bones[FP_FINGERS][4] = {
        {46.2f, 31.6f, 0.0f, 21.7f},   /* thumb */
        {68.1f, 39.8f, 22.4f, 15.8f},  /* index */
        {64.6f, 44.6f, 26.3f, 17.4f},  /* middle */
        {58.0f, 41.4f, 25.7f, 17.3f},  /* ring */
        {53.7f, 32.6f, 18.1f, 16.0f},  /* little */
    };
    static const float pads[FP_FINGERS] = {5.7f, 3.8f, 4.0f, 4.0f, 3.7f};
    /* Mean rest geometry of the five hands of shared/data/hands/leap-motion (each divided by
     * its fitted size factor), moved so that the middle MCP is at (0, 0, -64.6). */
    static const float base[FP_FINGERS][3] = {
        {-23.88f, -3.73f, 8.42f},    /* thumb CMC */
        {-24.43f, -0.85f, -59.17f},  /* index MCP */
        {0.0f, 0.0f, -64.6f},        /* middle MCP */
        {21.09f, 0.32f, -61.08f},    /* ring MCP */
        {39.08f, -5.88f, -52.67f},   /* little MCP */
    };
    memset(m, 0, sizeof *m);
    m->size = 1.0f;
    memcpy(m->bone_mm, bones, sizeof bones);
    memcpy(m->tip_pad_mm, pads, sizeof pads);
    m->tip_pad = 1.0f;
    memcpy(m->base_mm, base, sizeof base);
    m->palm_mm[0] = 1.34f;
    m->palm_mm[1] = -2.89f;
    m->palm_mm[2] = -44.32f;
    m->middle_yaw_rad = (float)DEG(-11.0);
    m->thumb_twist_rad = (float)DEG(90.0);
    m->rest_rad[FP_SENSOR_THUMB_ROTATE] = (float)DEG(9.0);
    m->rest_rad[FP_SENSOR_THUMB_AB] = (float)DEG(45.0);
}

static bool model_ok(const fp_hand_model *m)
{
    if (!(m->size > 0) || !isfinite(m->size) || !isfinite(m->tip_pad) ||
        !isfinite(m->middle_yaw_rad) || !isfinite(m->thumb_twist_rad) || !finite3f(m->palm_mm))
        return false;
    for (int f = 0; f < FP_FINGERS; f++) {
        if (!finite3f(m->base_mm[f]) || !isfinite(m->tip_pad_mm[f]))
            return false;
        for (int b = 0; b < 4; b++)
            if (!isfinite(m->bone_mm[f][b]))
                return false;
    }
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        if (!isfinite(m->rest_rad[i]))
            return false;
    return true;
}

/* The palm-arch turn of finger f's metacarpal (about the z axis, + moves +x toward -y). */
static double arch_share(int f)
{
    return f == 4 ? 1.0 : f == 3 ? 0.5 : 0.0;
}

/* Finger frame from in-plane yaw psi (+ toward the thumb) and projected flexion phi: the
 * proximal phalanx points along R (0,0,-1), the flexion axis is R (-1,0,0). The elevation
 * phi' solves tan(phi) = tan(phi') / cos(psi) so that phi is the angle seen in the plane of
 * the hand direction and the palm normal (the convention of the Leap recordings). */
static void finger_frame(double psi, double phi, mat3 r)
{
    double phip = atan2(sin(phi) * cos(psi), cos(phi));
    mat3 a, b;
    rot_y(psi, a);
    rot_x(-phip, b);
    mat_mul(a, b, r);
}

/* Forward kinematics of the size-1 right hand in its own frame, angles final. */
static void fk_right(const fp_hand_model *m, const double a[FP_GLOVE_SENSORS], double j[21][3])
{
    static const int mpj[5] = {FP_SENSOR_THUMB_MPJ, FP_SENSOR_INDEX_MPJ, FP_SENSOR_MIDDLE_MPJ,
                               FP_SENSOR_RING_MPJ, FP_SENSOR_PINKIE_MPJ};
    const double down[3] = {0, 0, -1};
    double yaw[5];
    yaw[2] = m->middle_yaw_rad;
    yaw[1] = yaw[2] + a[FP_SENSOR_MIDDLE_INDEX_AB];
    yaw[3] = yaw[2] - a[FP_SENSOR_RING_MIDDLE_AB];
    yaw[4] = yaw[3] - a[FP_SENSOR_PINKIE_RING_AB];
    yaw[0] = yaw[1] + a[FP_SENSOR_THUMB_AB];

    for (int k = 0; k < 3; k++)
        j[FP_JOINT_PALM][k] = m->palm_mm[k];

    for (int f = 1; f < 5; f++) {
        mat3 arch, r, t;
        double p[3], d[3];
        rot_z(-arch_share(f) * a[FP_SENSOR_PALM_ARCH], arch);
        for (int k = 0; k < 3; k++)
            p[k] = m->base_mm[f][k];
        mat_vec(arch, p, p);
        finger_frame(yaw[f], a[mpj[f]], r);
        mat_mul(arch, r, r);
        double len[3] = {m->bone_mm[f][FP_BONE_PROXIMAL], m->bone_mm[f][FP_BONE_MIDDLE],
                         m->bone_mm[f][FP_BONE_DISTAL] + m->tip_pad * m->tip_pad_mm[f]};
        memcpy(j[FP_JOINT(f, 0)], p, sizeof p);
        for (int s = 0; s < 3; s++) {
            if (s > 0) { /* PIJ follows MPJ in the sensor list, DIJ follows PIJ */
                rot_x(-a[mpj[f] + s], t);
                mat_mul(r, t, r);
            }
            mat_vec(r, down, d);
            for (int k = 0; k < 3; k++)
                p[k] += len[s] * d[k];
            memcpy(j[FP_JOINT(f, s + 1)], p, sizeof p);
        }
    }

    /* Thumb: metacarpal from the CMC, yaw in the palm plane, elevation toward the palm
     * (THUMB_ROTATE), then the flexion axis twisted about the metacarpal. */
    {
        mat3 r, t;
        double p[3], d[3];
        rot_y(yaw[0], r);
        rot_x(-a[FP_SENSOR_THUMB_ROTATE], t);
        mat_mul(r, t, r);
        rot_z(m->thumb_twist_rad, t);
        mat_mul(r, t, r);
        for (int k = 0; k < 3; k++)
            p[k] = m->base_mm[0][k];
        memcpy(j[FP_JOINT(0, 0)], p, sizeof p);
        double len[3] = {m->bone_mm[0][FP_BONE_METACARPAL], m->bone_mm[0][FP_BONE_PROXIMAL],
                         m->bone_mm[0][FP_BONE_DISTAL] + m->tip_pad * m->tip_pad_mm[0]};
        double flex[3] = {0, a[FP_SENSOR_THUMB_MPJ], a[FP_SENSOR_THUMB_IJ]};
        for (int s = 0; s < 3; s++) {
            if (s > 0) {
                rot_x(-flex[s], t);
                mat_mul(r, t, r);
            }
            mat_vec(r, down, d);
            for (int k = 0; k < 3; k++)
                p[k] += len[s] * d[k];
            memcpy(j[FP_JOINT(0, s + 1)], p, sizeof p);
        }
    }

    /* Wrist: the whole hand turns about the origin. */
    {
        mat3 w, t;
        rot_y(a[FP_SENSOR_WRIST_YAW], w);
        rot_x(-a[FP_SENSOR_WRIST_PITCH], t);
        mat_mul(w, t, w);
        for (int i = 0; i < FP_HAND_JOINTS; i++)
            mat_vec(w, j[i], j[i]);
    }
}

static const int pij_of_dij[FP_GLOVE_SENSORS] = {
    [FP_SENSOR_INDEX_DIJ] = FP_SENSOR_INDEX_PIJ, [FP_SENSOR_MIDDLE_DIJ] = FP_SENSOR_MIDDLE_PIJ,
    [FP_SENSOR_RING_DIJ] = FP_SENSOR_RING_PIJ, [FP_SENSOR_PINKIE_DIJ] = FP_SENSOR_PINKIE_PIJ};

int fp_hand_fk(const fp_hand_model *model, fp_hand_side side, const float angles_rad[22],
               uint32_t valid_mask, const float wrist_pos_mm[3], const float wrist_rot_wxyz[4],
               float joints_mm[FP_HAND_JOINTS][3])
{
    if (!model || !joints_mm || (side != FP_HAND_LEFT && side != FP_HAND_RIGHT))
        return -EINVAL;
    if ((valid_mask & FP_HAND_ALL_SENSORS) && !angles_rad)
        return -EINVAL;
    if ((wrist_pos_mm == NULL) != (wrist_rot_wxyz == NULL))
        return -EINVAL;
    if (!(model->size > 0))
        return isfinite(model->size) ? -EINVAL : -ERANGE;
    if (!model_ok(model))
        return -ERANGE;

    double a[FP_GLOVE_SENSORS];
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) {
        if (valid_mask & (1u << i)) {
            if (!isfinite(angles_rad[i]))
                return -ERANGE;
            a[i] = angles_rad[i];
        } else {
            a[i] = model->rest_rad[i];
        }
    }
    /* 18-sensor gloves: DIP = 2/3 PIP where only the PIJ was measured. */
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) {
        int p = pij_of_dij[i];
        if (p && !(valid_mask & (1u << i)) && (valid_mask & (1u << p)))
            a[i] = (2.0 / 3.0) * a[p];
    }

    mat3 rot;
    if (wrist_rot_wxyz) {
        if (!finite3f(wrist_pos_mm) || !finite3f(wrist_rot_wxyz) || !isfinite(wrist_rot_wxyz[3]))
            return -ERANGE;
        if (!quat_to_mat(wrist_rot_wxyz, rot))
            return -EDOM;
    }

    double j[FP_HAND_JOINTS][3];
    fk_right(model, a, j);
    for (int i = 0; i < FP_HAND_JOINTS; i++) {
        double p[3] = {j[i][0] * model->size, j[i][1] * model->size, j[i][2] * model->size};
        if (side == FP_HAND_LEFT)
            p[0] = -p[0];
        if (wrist_rot_wxyz) {
            mat_vec(rot, p, p);
            for (int k = 0; k < 3; k++)
                p[k] += wrist_pos_mm[k];
        }
        j[i][0] = p[0], j[i][1] = p[1], j[i][2] = p[2];
    }
    for (int i = 0; i < FP_HAND_JOINTS; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(j[i][k]))
                return -ERANGE; /* only from absurd model values */
    for (int i = 0; i < FP_HAND_JOINTS; i++)
        for (int k = 0; k < 3; k++)
            joints_mm[i][k] = (float)j[i][k];
    return 0;
}

/* ---------------------------------------------------------------------------------- */
/* Frames                                                                              */

/* Rotation whose columns are the hand axes x, y, z in the device frame. */
static void set_columns(const double x[3], const double y[3], const double z[3], mat3 r)
{
    for (int i = 0; i < 3; i++) {
        r[i][0] = x[i];
        r[i][1] = y[i];
        r[i][2] = z[i];
    }
}

int fp_hand_frame_from_palm(const fp_hand_model *model, fp_hand_side side,
                            const float palm_mm[3], const float palm_normal[3],
                            const float direction[3], float wrist_pos_mm[3],
                            float wrist_rot_wxyz[4])
{
    if (!model || !palm_mm || !palm_normal || !direction || !wrist_pos_mm || !wrist_rot_wxyz ||
        (side != FP_HAND_LEFT && side != FP_HAND_RIGHT) || !(model->size > 0))
        return -EINVAL;
    if (!finite3f(palm_mm) || !finite3f(palm_normal) || !finite3f(direction) || !model_ok(model))
        return -ERANGE;
    double y[3] = {-palm_normal[0], -palm_normal[1], -palm_normal[2]};
    double d[3] = {direction[0], direction[1], direction[2]};
    if (normalize3(y) < 1e-9 || normalize3(d) < 1e-9)
        return -EDOM;
    double dy = fp_dot3(d, y);
    double z[3] = {-(d[0] - dy * y[0]), -(d[1] - dy * y[1]), -(d[2] - dy * y[2])};
    if (normalize3(z) < 1e-3)
        return -EDOM;
    double x[3];
    fp_cross3(y, z, x);
    mat3 r;
    set_columns(x, y, z, r);
    double pl[3] = {model->palm_mm[0] * model->size, model->palm_mm[1] * model->size,
                    model->palm_mm[2] * model->size};
    if (side == FP_HAND_LEFT)
        pl[0] = -pl[0];
    mat_vec(r, pl, pl);
    for (int k = 0; k < 3; k++)
        wrist_pos_mm[k] = (float)(palm_mm[k] - pl[k]);
    fp_hand_mat_to_quat((const double (*)[3])r, wrist_rot_wxyz);
    return 0;
}

int fp_hand_to_hand_frame(const float wrist_pos_mm[3], const float wrist_rot_wxyz[4],
                          const float (*in_mm)[3], size_t n, float (*out_mm)[3])
{
    if (!wrist_pos_mm || !wrist_rot_wxyz || (n && (!in_mm || !out_mm)))
        return -EINVAL;
    if (!finite3f(wrist_pos_mm) || !finite3f(wrist_rot_wxyz) || !isfinite(wrist_rot_wxyz[3]))
        return -ERANGE;
    mat3 r;
    if (!quat_to_mat(wrist_rot_wxyz, r))
        return -EDOM;
    for (size_t i = 0; i < n; i++)
        if (!finite3f(in_mm[i]))
            return -ERANGE;
    for (size_t i = 0; i < n; i++) {
        double p[3] = {in_mm[i][0] - wrist_pos_mm[0], in_mm[i][1] - wrist_pos_mm[1],
                       in_mm[i][2] - wrist_pos_mm[2]};
        mat_tvec(r, p, p);
        out_mm[i][0] = (float)p[0], out_mm[i][1] = (float)p[1], out_mm[i][2] = (float)p[2];
    }
    return 0;
}

/* Orthonormal triad from the palm centre and the index and little MCPs: e0 along
 * little -> index, e2 normal to the plane of the three points, e1 = e2 x e0. */
static bool palm_triad(const double palm[3], const double idx[3], const double lit[3], mat3 r)
{
    double e0[3], v[3], e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e0[k] = idx[k] - lit[k];
        v[k] = palm[k] - 0.5 * (idx[k] + lit[k]);
    }
    if (normalize3(e0) < 1e-6)
        return false;
    fp_cross3(e0, v, e2);
    if (normalize3(e2) < 1e-6)
        return false;
    fp_cross3(e2, e0, e1);
    set_columns(e0, e1, e2, r);
    return true;
}

int fp_hand_from_positions(const fp_hand_model *model, fp_hand_side side,
                           const float joints_mm[FP_HAND_JOINTS][3], fp_hand_angles *out)
{
    if (!model || !joints_mm || !out || (side != FP_HAND_LEFT && side != FP_HAND_RIGHT) ||
        !(model->size > 0))
        return -EINVAL;
    if (!model_ok(model))
        return -ERANGE;
    for (int i = 0; i < FP_HAND_JOINTS; i++)
        if (!finite3f(joints_mm[i]))
            return -ERANGE;

    const double s = model->size, mx = side == FP_HAND_LEFT ? -1.0 : 1.0;
    /* Model points (device-frame scale, mirrored) at the rest pose, rest wrist included. */
    double a_rest[FP_GLOVE_SENSORS], jm[21][3];
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        a_rest[i] = model->rest_rad[i];
    fk_right(model, a_rest, jm);
    mat3 wrest, wt;
    rot_y(a_rest[FP_SENSOR_WRIST_YAW], wrest);
    rot_x(-a_rest[FP_SENSOR_WRIST_PITCH], wt);
    mat_mul(wrest, wt, wrest);
    for (int i = 0; i < 21; i++) {
        jm[i][0] *= s * mx;
        jm[i][1] *= s;
        jm[i][2] *= s;
    }
    double jd[21][3];
    for (int i = 0; i < 21; i++)
        for (int k = 0; k < 3; k++)
            jd[i][k] = joints_mm[i][k];
    mat3 fm, fd, r;
    if (!palm_triad(jm[0], jm[FP_JOINT(1, 0)], jm[FP_JOINT(4, 0)], fm) ||
        !palm_triad(jd[0], jd[FP_JOINT(1, 0)], jd[FP_JOINT(4, 0)], fd))
        return -EDOM;
    /* R = Fd Fm^T maps hand-frame vectors to the device frame. For the left hand both triads
     * are built from mirrored points, so R is still a proper rotation. */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[i][j] = fd[i][0] * fm[j][0] + fd[i][1] * fm[j][1] + fd[i][2] * fm[j][2];
    double org[3];
    mat_vec(r, jm[0], org);
    for (int k = 0; k < 3; k++)
        org[k] = jd[0][k] - org[k];

    /* Joints into the right-hand frame at size 1. */
    double h[21][3];
    for (int i = 0; i < 21; i++) {
        double p[3] = {jd[i][0] - org[0], jd[i][1] - org[1], jd[i][2] - org[2]};
        mat_tvec(r, p, p);
        p[0] *= mx / s, p[1] /= s, p[2] /= s;
        mat_tvec(wrest, p, h[i]); /* undo the rest wrist turn: joints as before the wrist */
    }

    double ang[FP_GLOVE_SENSORS];
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        ang[i] = model->rest_rad[i];
    static const int mpj[5] = {FP_SENSOR_THUMB_MPJ, FP_SENSOR_INDEX_MPJ, FP_SENSOR_MIDDLE_MPJ,
                               FP_SENSOR_RING_MPJ, FP_SENSOR_PINKIE_MPJ};
    double yaw[5];
    for (int f = 1; f < 5; f++) {
        mat3 arch, fr, t;
        double b[3][3];
        rot_z(-arch_share(f) * model->rest_rad[FP_SENSOR_PALM_ARCH], arch);
        for (int sg = 0; sg < 3; sg++) {
            for (int k = 0; k < 3; k++)
                b[sg][k] = h[FP_JOINT(f, sg + 1)][k] - h[FP_JOINT(f, sg)][k];
            mat_tvec(arch, b[sg], b[sg]);
            if (normalize3(b[sg]) < 1e-9)
                return -EDOM;
        }
        yaw[f] = atan2(-b[0][0], -b[0][2]);
        double phi = atan2(-b[0][1], -b[0][2]);
        ang[mpj[f]] = phi;
        finger_frame(yaw[f], phi, fr);
        for (int sg = 1; sg < 3; sg++) {
            double l[3];
            mat_tvec(fr, b[sg], l);
            double flex = atan2(-l[1], -l[2]);
            ang[mpj[f] + sg] = flex;
            rot_x(-flex, t);
            mat_mul(fr, t, fr);
        }
    }
    ang[FP_SENSOR_MIDDLE_INDEX_AB] = yaw[1] - yaw[2];
    ang[FP_SENSOR_RING_MIDDLE_AB] = yaw[2] - yaw[3];
    ang[FP_SENSOR_PINKIE_RING_AB] = yaw[3] - yaw[4];
    {
        double b[3][3];
        for (int sg = 0; sg < 3; sg++) {
            for (int k = 0; k < 3; k++)
                b[sg][k] = h[FP_JOINT(0, sg + 1)][k] - h[FP_JOINT(0, sg)][k];
            if (normalize3(b[sg]) < 1e-9)
                return -EDOM;
        }
        double ty = atan2(-b[0][0], -b[0][2]);
        double el = atan2(-b[0][1], hypot(b[0][0], b[0][2]));
        ang[FP_SENSOR_THUMB_AB] = ty - yaw[1];
        ang[FP_SENSOR_THUMB_ROTATE] = el;
        mat3 tr, t;
        rot_y(ty, tr);
        rot_x(-el, t);
        mat_mul(tr, t, tr);
        rot_z(model->thumb_twist_rad, t);
        mat_mul(tr, t, tr);
        static const int sens[3] = {0, FP_SENSOR_THUMB_MPJ, FP_SENSOR_THUMB_IJ};
        for (int sg = 1; sg < 3; sg++) {
            double l[3];
            mat_tvec(tr, b[sg], l);
            double flex = atan2(-l[1], -l[2]);
            ang[sens[sg]] = flex;
            rot_x(-flex, t);
            mat_mul(tr, t, tr);
        }
    }
    /* Wrap the differences of angles into (-pi, pi]. */
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) {
        while (ang[i] > M_PI)
            ang[i] -= 2 * M_PI;
        while (ang[i] <= -M_PI)
            ang[i] += 2 * M_PI;
    }
    for (int i = 0; i < FP_GLOVE_SENSORS; i++)
        out->radians[i] = (float)ang[i];
    out->valid = FP_HAND_ALL_SENSORS & ~((1u << FP_SENSOR_PALM_ARCH) |
                                         (1u << FP_SENSOR_WRIST_PITCH) |
                                         (1u << FP_SENSOR_WRIST_YAW));
    for (int k = 0; k < 3; k++)
        out->wrist_pos_mm[k] = (float)org[k];
    fp_hand_mat_to_quat((const double (*)[3])r, out->wrist_rot_wxyz);
    return 0;
}

/* ---------------------------------------------------------------------------------- */
/* Fingertips                                                                          */

int fp_hand_fingertips(const float joints_mm[FP_HAND_JOINTS][3], float tips_mm[FP_FINGERS][3])
{
    if (!joints_mm || !tips_mm)
        return -EINVAL;
    for (int f = 0; f < FP_FINGERS; f++)
        memcpy(tips_mm[f], joints_mm[FP_JOINT_TIP(f)], sizeof tips_mm[f]);
    return 0;
}

int fp_hand_fingertips2(const float left_mm[FP_HAND_JOINTS][3],
                        const float right_mm[FP_HAND_JOINTS][3], float tips_mm[10][3])
{
    if (!tips_mm)
        return -EINVAL;
    if (left_mm)
        fp_hand_fingertips(left_mm, tips_mm);
    if (right_mm)
        fp_hand_fingertips(right_mm, tips_mm + FP_FINGERS);
    return 0;
}

/* ---------------------------------------------------------------------------------- */
/* Fitting                                                                             */

static bool frame_finite(const float j[FP_HAND_JOINTS][3])
{
    for (int i = 0; i < FP_HAND_JOINTS; i++)
        if (!finite3f(j[i]))
            return false;
    return true;
}

/* Size-1 model length of segment sg (0..2) of finger f, as the joints measure it. */
static double model_segment(const fp_hand_model *m, int f, int sg)
{
    if (f == 0) {
        static const int bone[3] = {FP_BONE_METACARPAL, FP_BONE_PROXIMAL, FP_BONE_DISTAL};
        return m->bone_mm[0][bone[sg]] + (sg == 2 ? m->tip_pad * m->tip_pad_mm[0] : 0);
    }
    return m->bone_mm[f][sg + 1] + (sg == 2 ? m->tip_pad * m->tip_pad_mm[f] : 0);
}

int fp_hand_fit_size(const fp_hand_model *model, const float (*joints_mm)[FP_HAND_JOINTS][3],
                     size_t n, float *size_out)
{
    if (!model || !joints_mm || !size_out || n == 0)
        return -EINVAL;
    if (!model_ok(model))
        return -ERANGE;
    double num = 0, den = 0;
    size_t used = 0;
    for (size_t i = 0; i < n; i++) {
        if (!frame_finite(joints_mm[i]))
            continue;
        used++;
        for (int f = 0; f < FP_FINGERS; f++)
            for (int sg = 0; sg < 3; sg++) {
                double d[3];
                for (int k = 0; k < 3; k++)
                    d[k] = (double)joints_mm[i][FP_JOINT(f, sg + 1)][k] - joints_mm[i][FP_JOINT(f, sg)][k];
                double mlen = model_segment(model, f, sg);
                num += sqrt(fp_dot3(d, d)) * mlen;
                den += mlen * mlen;
            }
    }
    if (!used || !(den > 0) || !(num > 0))
        return -EINVAL;
    *size_out = (float)(num / den);
    return 0;
}

int fp_hand_fit_geometry(fp_hand_model *model, fp_hand_side side,
                         const float (*joints_hand_mm)[FP_HAND_JOINTS][3], size_t n)
{
    if (!model || (side != FP_HAND_LEFT && side != FP_HAND_RIGHT))
        return -EINVAL;
    float size;
    int rc = fp_hand_fit_size(model, joints_hand_mm, n, &size);
    if (rc)
        return rc;
    const double mx = side == FP_HAND_LEFT ? -1.0 : 1.0;
    double base[FP_FINGERS][3] = {{0}}, ys = 0, yc = 0, el = 0;
    size_t used = 0;
    for (size_t i = 0; i < n; i++) {
        const float(*j)[3] = joints_hand_mm[i];
        if (!frame_finite(j))
            continue;
        used++;
        for (int f = 0; f < FP_FINGERS; f++)
            for (int k = 0; k < 3; k++)
                base[f][k] += ((double)j[FP_JOINT(f, 0)][k] - j[FP_JOINT_PALM][k]) * (k == 0 ? mx : 1.0);
        double b[3], u[3];
        for (int k = 0; k < 3; k++) {
            b[k] = ((double)j[FP_JOINT(2, 1)][k] - j[FP_JOINT(2, 0)][k]) * (k == 0 ? mx : 1.0);
            u[k] = ((double)j[FP_JOINT(0, 1)][k] - j[FP_JOINT(0, 0)][k]) * (k == 0 ? mx : 1.0);
        }
        double yaw = atan2(-b[0], -b[2]);
        ys += sin(yaw);
        yc += cos(yaw);
        el += atan2(-u[1], hypot(u[0], u[2]));
    }
    /* used > 0: fp_hand_fit_size found a finite frame. */
    fp_hand_model m = *model;
    m.size = size;
    for (int f = 0; f < FP_FINGERS; f++)
        for (int k = 0; k < 3; k++)
            m.base_mm[f][k] = (float)(base[f][k] / (double)used / size + model->palm_mm[k]);
    m.middle_yaw_rad = (float)atan2(ys, yc);
    m.rest_rad[FP_SENSOR_THUMB_ROTATE] = (float)(el / (double)used);
    if (!model_ok(&m))
        return -ERANGE;
    *model = m;
    return 0;
}
