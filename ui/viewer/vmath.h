/* vmath.h: the few 3D vector and 4x4 matrix helpers the viewer needs (column-major, as
 * OpenGL takes them: m[col * 4 + row]). Internal to ui/. */
#ifndef FP_UI_VMATH_H
#define FP_UI_VMATH_H

#include <math.h>
#include <stddef.h>
#include <string.h>

static inline void v3_sub(const float a[3], const float b[3], float o[3])
{
    o[0] = a[0] - b[0]; o[1] = a[1] - b[1]; o[2] = a[2] - b[2];
}
static inline float v3_dot(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void v3_cross(const float a[3], const float b[3], float o[3])
{
    float x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    o[0] = x; o[1] = y; o[2] = z;
}
static inline float v3_len(const float a[3]) { return sqrtf(v3_dot(a, a)); }
static inline void v3_norm(float a[3])
{
    float l = v3_len(a);
    if (l > 0) { a[0] /= l; a[1] /= l; a[2] /= l; }
}

static inline void m4_identity(float m[16])
{
    memset(m, 0, 16 * sizeof *m);
    m[0] = m[5] = m[10] = m[15] = 1.f;
}

/* o = a * b (o may alias neither). */
static inline void m4_mul(const float a[16], const float b[16], float o[16])
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            float s = 0;
            for (int k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
            o[c * 4 + r] = s;
        }
}

/* gluPerspective: fovy in radians. */
static inline void m4_perspective(float m[16], float fovy, float aspect, float zn, float zf)
{
    float f = 1.f / tanf(fovy / 2);
    memset(m, 0, 16 * sizeof *m);
    m[0] = f / aspect;
    m[5] = f;
    m[10] = (zf + zn) / (zn - zf);
    m[11] = -1.f;
    m[14] = 2.f * zf * zn / (zn - zf);
}

static inline void m4_ortho(float m[16], float l, float r, float b, float t)
{
    m4_identity(m);
    m[0] = 2.f / (r - l);
    m[5] = 2.f / (t - b);
    m[10] = -1.f;
    m[12] = -(r + l) / (r - l);
    m[13] = -(t + b) / (t - b);
}

/* gluLookAt. */
static inline void m4_look_at(float m[16], const float eye[3], const float at[3], const float up[3])
{
    float f[3], s[3], u[3];
    v3_sub(at, eye, f);
    v3_norm(f);
    v3_cross(f, up, s);
    v3_norm(s);
    v3_cross(s, f, u);
    m4_identity(m);
    m[0] = s[0]; m[4] = s[1]; m[8] = s[2];
    m[1] = u[0]; m[5] = u[1]; m[9] = u[2];
    m[2] = -f[0]; m[6] = -f[1]; m[10] = -f[2];
    m[12] = -v3_dot(s, eye);
    m[13] = -v3_dot(u, eye);
    m[14] = v3_dot(f, eye);
}

/* The face's axes the camera turns about (left, up, forward in mesh coordinates: +x, +y, +z
 * for a face that looks along +z; fp_session_face_axes for a turned one) */
typedef struct face_axes {
    float x[3], y[3], z[3];
} face_axes;

/* up and forward (unit, orthogonal) or NULL: the identity; left = up x forward */
static inline void face_axes_set(face_axes *a, const float *up, const float *forward)
{
    const float y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    memcpy(a->y, up ? up : y, sizeof a->y);
    memcpy(a->z, forward ? forward : z, sizeof a->z);
    v3_cross(a->y, a->z, a->x);
}

/* the face-frame point l as mesh coordinates */
static inline void face_axes_to_mesh(const face_axes *a, const float l[3], float o[3])
{
    for (int i = 0; i < 3; i++) o[i] = l[0] * a->x[i] + l[1] * a->y[i] + l[2] * a->z[i];
}

/* the n points' box in the face's axes (lo, hi: along x, y, z of the face) */
static inline void face_axes_bounds(const face_axes *a, const float *pos, size_t n, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        const float *p = pos + 3 * i;
        const float c[3] = {v3_dot(p, a->x), v3_dot(p, a->y), v3_dot(p, a->z)};
        for (int k = 0; k < 3; k++) lo[k] = fminf(lo[k], c[k]), hi[k] = fmaxf(hi[k], c[k]);
    }
    if (!n)
        for (int k = 0; k < 3; k++) lo[k] = hi[k] = 0;
}

/* The n points' box in the face's axes: its centre in mesh coordinates (target) and its
 * extent along the face's left, up and forward (d): what the camera frames */
static inline void face_axes_frame(const face_axes *a, const float *pos, size_t n, float target[3], float d[3])
{
    float lo[3], hi[3], c[3];
    face_axes_bounds(a, pos, n, lo, hi);
    for (int i = 0; i < 3; i++) c[i] = 0.5f * (lo[i] + hi[i]), d[i] = hi[i] - lo[i];
    face_axes_to_mesh(a, c, target);
}

/* The camera's eye dist from target, turned by yaw about the face's up and pitch about its
 * left (radians; 0, 0: in front of the face) */
static inline void face_axes_eye(const face_axes *a, const float target[3], float dist, float yaw, float pitch,
                                 float eye[3])
{
    const float l[3] = {dist * cosf(pitch) * sinf(yaw), dist * sinf(pitch), dist * cosf(pitch) * cosf(yaw)};
    face_axes_to_mesh(a, l, eye);
    for (int i = 0; i < 3; i++) eye[i] += target[i];
}

/* The camera's distance (mesh units) that keeps a view framed on a box of front (width,
 * height) and depth (mesh units) at a fixed vertical field of view when the window's aspect
 * (width / height) goes from *from to `to` (then *from = to): the face keeps its place and the share of the
 * window it fills, with the orbit, pan and zoom chosen. The distance to the box's front scales
 * with the height the box needs at the new aspect against the old: narrower than the face, the
 * camera backs away instead of cutting it off; wider again, it comes back. */
static inline float frame_keep_dist(float dist, const float front[2], float depth, float *from, float to)
{
    if (!(*from > 0) || !(to > 0) || *from == to) return dist;
    const float need_old = fmaxf(front[1], front[0] / *from), need_new = fmaxf(front[1], front[0] / to);
    *from = to; /* (the aspect the view is now fitted to) */
    if (!(need_old > 0) || !(need_new > 0)) return dist;
    const float r = need_new / need_old, to_front = dist - 0.5f * depth;
    return to_front > 0 ? to_front * r + 0.5f * depth : dist * r;
}

#endif
