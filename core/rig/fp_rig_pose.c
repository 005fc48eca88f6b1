/* fp_rig_pose: the jaw pose and its inverse and the mobility blend of a bound rig
 * (fp_rig.h); the finger limit and clamp are fp_rig_slope.c's. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include <errno.h>
#include <math.h>
#include <string.h>

static double jaw_open_value(const fp_rig *r, const float *values)
{
    const channel *jc = &r->channels[r->jaw_open];
    double open = values ? values[r->jaw_open] : jc->neutral;
    if (isnan(open)) open = jc->neutral;
    return fmin(jc->max, fmax(jc->min, open));
}

double fp_rig_glide_fraction(const fp_rig *r, double open)
{
    if (!r || !(open > 0)) return 0;
    if (open >= 1) return 1;
    double t = (open - r->glide_start) / (1 - r->glide_start);
    return t > 0 ? t : 0;
}

/* Rodrigues: rotation matrix by angle a (radians) about unit axis k. */
static void rotation(const double k[3], double a, double R[9])
{
    double c = cos(a), s = sin(a), t = 1 - c;
    R[0] = t * k[0] * k[0] + c, R[1] = t * k[0] * k[1] - s * k[2], R[2] = t * k[0] * k[2] + s * k[1];
    R[3] = t * k[0] * k[1] + s * k[2], R[4] = t * k[1] * k[1] + c, R[5] = t * k[1] * k[2] - s * k[0];
    R[6] = t * k[0] * k[2] - s * k[1], R[7] = t * k[1] * k[2] + s * k[0], R[8] = t * k[2] * k[2] + c;
}

int fp_rig_pose(const fp_rig *r, const float *base, const float *values, float *out)
{
    return fp_rig_pose_range(r, base, values, out, 0, r ? r->n : 0);
}

int fp_rig_pose_range(const fp_rig *r, const float *base, const float *values, float *out,
                      size_t v0, size_t count)
{
    if (!r || !base || !out || !r->w || v0 > r->n || count > r->n - v0) return -EINVAL;
    double open = jaw_open_value(r, values);
    double theta = open * r->open_deg * M_PI / 180, slide = fp_rig_glide_fraction(r, open);
    double R1[9];
    rotation(r->geom.axis, theta, R1);
    for (size_t v = v0; v < v0 + count; v++) {
        double w = r->w[v];
        if (w == 0 || theta == 0) {
            if (out != base) memcpy(&out[3 * v], &base[3 * v], 3 * sizeof(float));
            continue;
        }
        double Rw[9];
        const double *R = R1;
        if (w != 1) {
            rotation(r->geom.axis, w * theta, Rw);
            R = Rw;
        }
        double d[3] = {base[3 * v] - r->geom.hinge_r[0], base[3 * v + 1] - r->geom.hinge_r[1], base[3 * v + 2] - r->geom.hinge_r[2]};
        double g = w * slide;
        for (int i = 0; i < 3; i++)
            out[3 * v + i] = (float)(r->geom.hinge_r[i] + R[3 * i] * d[0] + R[3 * i + 1] * d[1] + R[3 * i + 2] * d[2] +
                                     g * (r->geom.glide[0] * r->geom.fwd[i] - r->geom.glide[1] * r->geom.up[i]));
    }
    return 0;
}

int fp_rig_unpose(const fp_rig *r, const float *base, const float *values, const float *shown, float *out)
{
    return fp_rig_unpose_range(r, base, NULL, values, shown, out, 0, r ? r->n : 0);
}

int fp_rig_unpose_range(const fp_rig *r, const float *base, const float *posed, const float *values,
                        const float *shown, float *out, size_t v0, size_t count)
{
    if (!r || !base || !shown || !out || !r->w || !r->m || v0 > r->n || count > r->n - v0) return -EINVAL;
    double open = jaw_open_value(r, values);
    double theta = open * r->open_deg * M_PI / 180, slide = fp_rig_glide_fraction(r, open);
    for (size_t v = v0; v < v0 + count; v++) {
        double w = r->w[v];
        const float *p = &shown[3 * v];
        if (r->m[v] == 0 || (posed && p[0] == posed[3 * v] && p[1] == posed[3 * v + 1] && p[2] == posed[3 * v + 2])) {
            memcpy(&out[3 * v], &base[3 * v], 3 * sizeof(float));
            continue;
        }
        if (w == 0 || theta == 0) {
            memcpy(&out[3 * v], p, 3 * sizeof(float));
            continue;
        }
        double R[9], d[3];
        rotation(r->geom.axis, w * theta, R);
        double g = w * slide;
        for (int i = 0; i < 3; i++)
            d[i] = p[i] - r->geom.hinge_r[i] - g * (r->geom.glide[0] * r->geom.fwd[i] - r->geom.glide[1] * r->geom.up[i]);
        for (int i = 0; i < 3; i++) /* R^T d */
            out[3 * v + i] = (float)(r->geom.hinge_r[i] + R[i] * d[0] + R[3 + i] * d[1] + R[6 + i] * d[2]);
    }
    return 0;
}

int fp_rig_apply_mobility(const fp_rig *r, const float *posed, const float *warped, float *out)
{
    return fp_rig_apply_mobility_range(r, posed, warped, out, 0, r ? r->n : 0);
}

int fp_rig_apply_mobility_range(const fp_rig *r, const float *posed, const float *warped, float *out,
                                size_t v0, size_t count)
{
    if (!r || !posed || !warped || !out || !r->m || v0 > r->n || count > r->n - v0) return -EINVAL;
    for (size_t v = v0; v < v0 + count; v++) {
        float m = r->m[v];
        for (int i = 0; i < 3; i++) {
            size_t k = 3 * v + i;
            out[k] = m == 0 ? posed[k] : posed[k] + m * (warped[k] - posed[k]);
        }
    }
    return 0;
}

double fp_rig_max_finger_displacement(const fp_rig *r)
{
    return r ? r->geom.ramp / 3 : 0;
}

const float *fp_rig_mobility_slope(const fp_rig *r) { return r ? r->g : NULL; }
