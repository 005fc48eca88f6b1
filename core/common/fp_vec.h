/*
 * fp_vec.h: the small 3D vector and quaternion helpers the core libraries share, in double
 * precision (the session's calibration, the rig's frames; core/pose, core/rig). Header-only,
 * no allocation, reentrant, [any-thread]. Internal: plugins reach the same arithmetic through
 * their own code (the installed headers carry no vector library).
 *
 * Quaternions are (w, x, y, z), unit where a rotation is meant.
 */
#ifndef FP_VEC_H
#define FP_VEC_H

#include <math.h>

/** A triangle is turned over (flipped) when its normal is more than acos(FP_FLIP_COS) from its
 *  rest normal: 90 degrees less 0.0006 of a degree, a margin over the rest normal's rounding
 *  to float. One rule for the contact guard (FP_CONTACT_FLIP_COS, fp_contact.h, where the
 *  margin's reason is) and the rig's jaw weights (fp_rig_unfold_jaw). */
#define FP_FLIP_COS 1e-5

/** a . b */
static inline double fp_dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/** out = a x b (out may be a or b). */
static inline void fp_cross3(const double a[3], const double b[3], double out[3])
{
    const double t[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]};
    out[0] = t[0];
    out[1] = t[1];
    out[2] = t[2];
}

/** out = q v q* : v turned by the unit quaternion q (w, x, y, z); out may be v. */
static inline void fp_qrot(const double q[4], const double v[3], double out[3])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double tx = 2 * (y * v[2] - z * v[1]), ty = 2 * (z * v[0] - x * v[2]),
                 tz = 2 * (x * v[1] - y * v[0]);
    out[0] = v[0] + w * tx + (y * tz - z * ty);
    out[1] = v[1] + w * ty + (z * tx - x * tz);
    out[2] = v[2] + w * tz + (x * ty - y * tx);
}

/* The unit quaternion (w, x, y, z) of the rotation whose matrix has the columns left, up and
 * forward (orthonormal, left = up x forward): it turns +x, +y, +z into them. Shepperd's
 * method (the largest of the four diagonal combinations); w >= 0. */
static inline void fp_quat_from_axes(const double left[3], const double up[3], const double fwd[3], double q[4])
{
    double M[3][3];
    for (int i = 0; i < 3; i++) M[i][0] = left[i], M[i][1] = up[i], M[i][2] = fwd[i];
    double tr = M[0][0] + M[1][1] + M[2][2];
    if (tr >= M[0][0] && tr >= M[1][1] && tr >= M[2][2]) {
        double w = 2 * sqrt(fmax(0, 1 + tr));
        q[0] = w / 4, q[1] = (M[2][1] - M[1][2]) / w, q[2] = (M[0][2] - M[2][0]) / w, q[3] = (M[1][0] - M[0][1]) / w;
    } else if (M[0][0] >= M[1][1] && M[0][0] >= M[2][2]) {
        double w = 2 * sqrt(fmax(0, 1 + M[0][0] - M[1][1] - M[2][2]));
        q[0] = (M[2][1] - M[1][2]) / w, q[1] = w / 4, q[2] = (M[0][1] + M[1][0]) / w, q[3] = (M[0][2] + M[2][0]) / w;
    } else if (M[1][1] >= M[2][2]) {
        double w = 2 * sqrt(fmax(0, 1 + M[1][1] - M[0][0] - M[2][2]));
        q[0] = (M[0][2] - M[2][0]) / w, q[1] = (M[0][1] + M[1][0]) / w, q[2] = w / 4, q[3] = (M[1][2] + M[2][1]) / w;
    } else {
        double w = 2 * sqrt(fmax(0, 1 + M[2][2] - M[0][0] - M[1][1]));
        q[0] = (M[1][0] - M[0][1]) / w, q[1] = (M[0][2] + M[2][0]) / w, q[2] = (M[1][2] + M[2][1]) / w, q[3] = w / 4;
    }
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++) q[i] = (q[0] < 0 ? -q[i] : q[i]) / n;
}

#endif
