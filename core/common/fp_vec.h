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

#endif
