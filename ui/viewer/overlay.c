/* The live viewer's overlays: hands, fingertip supports and their cues, the rig (overlay.h). */
#define _GNU_SOURCE
#include "overlay.h"

#include "fp_rig.h"
#include "vmath.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const float fp_tip_far_sphere[4] = {0.55f, 0.8f, 1.f, 0.13f}, fp_tip_touch_sphere[4] = {0.25f, 1.f, 0.4f, 0.3f},
            fp_tip_far_color[4] = {0.85f, 0.87f, 0.92f, 0.85f}, fp_tip_touch_color[4] = {0.25f, 1.f, 0.4f, 1.f};

typedef struct vbuf {
    float *v;
    size_t n, cap;
} vbuf;

static void vb_add(vbuf *b, const float p[3], const float c[4])
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 256;
        float *g = realloc(b->v, cap * 7 * sizeof *g);
        if (!g) return;
        b->v = g;
        b->cap = cap;
    }
    float *o = b->v + 7 * b->n++;
    memcpy(o, p, 3 * sizeof *o);
    memcpy(o + 3, c, 4 * sizeof *o);
}

void fp_overlay_tip_cues(const fp_session *s, fp_tip_cues *out)
{
    memset(out, 0, sizeof *out);
    out->nearest = INFINITY;
    double radius = fp_session_radius(s);
    float q[FP_TIP_CUES_MAX][3];
    for (size_t who = 0; who < fp_session_performer_count(s) && who < FP_PERFORMER_CAPACITY; who++)
        for (int h = 0; h < FP_HANDS; h++) {
            const fp_hand_pose *p = fp_session_performer_hand(s, who, h);
            for (int f = 0; p && f < FP_FINGERS; f++) memcpy(q[out->count++], p->joints[FP_JOINT_TIP(f)], sizeof q[0]);
        }
    fp_surface_hit hit[FP_TIP_CUES_MAX];
    if (!out->count || fp_session_surface_nearest(s, (const float (*)[3])q, out->count,
                                                  (float)(FP_TIP_CUE_REACH * radius), hit)) {
        for (size_t i = 0; i < out->count; i++) out->dist[i] = INFINITY;
        memcpy(out->tip, q, out->count * sizeof q[0]);
        return;
    }
    for (size_t i = 0; i < out->count; i++) {
        memcpy(out->tip[i], q[i], sizeof q[0]);
        memcpy(out->skin[i], hit[i].position, sizeof q[0]);
        out->dist[i] = hit[i].distance;
        out->touching[i] = hit[i].distance <= radius;
        out->touch_count += out->touching[i];
        if (hit[i].distance < out->nearest) out->nearest = hit[i].distance;
    }
}

/* Each fingertip's support sphere (radius R): faint blue while it does not reach the skin,
 * green and stronger while it does; the depth cue: a line from the fingertip to the nearest
 * skin point and a spot there (over the face, no depth test: a front view shows where the
 * finger is over the skin, the line's length how far, its colour whether it touches). */
static void draw_tips(fp_render *r, const fp_tip_cues *c, float radius, const float pv[16],
                      const float view[16])
{
    float far_tips[FP_TIP_CUES_MAX][3], near_tips[FP_TIP_CUES_MAX][3];
    size_t nfar = 0, nnear = 0;
    vbuf ticks = {0}, spots = {0};
    for (size_t i = 0; i < c->count; i++) {
        if (c->touching[i]) memcpy(near_tips[nnear++], c->tip[i], sizeof c->tip[i]);
        else memcpy(far_tips[nfar++], c->tip[i], sizeof c->tip[i]);
        if (!isfinite(c->dist[i])) continue;
        const float *col = c->touching[i] ? fp_tip_touch_color : fp_tip_far_color;
        vb_add(&ticks, c->tip[i], col);
        vb_add(&ticks, c->skin[i], col);
        vb_add(&spots, c->skin[i], col);
    }
    fp_render_spheres(r, pv, view, &far_tips[0][0], nfar, radius, fp_tip_far_sphere);
    fp_render_spheres(r, pv, view, &near_tips[0][0], nnear, radius, fp_tip_touch_sphere);
    fp_render_lines(r, pv, ticks.v, ticks.n, GL_LINES, 1.f, false);
    fp_render_lines(r, pv, spots.v, spots.n, GL_POINTS, 4.f, false);
    free(ticks.v);
    free(spots.v);
}

void fp_overlay_hands(fp_render *r, const fp_session *s, const fp_tip_cues *cues,
                      const float pv[16], const float view[16])
{
    static const float side_colors[FP_HANDS][4] = {{0.35f, 0.65f, 1.f, 1.f}, {1.f, 0.6f, 0.25f, 1.f}};
    vbuf bones = {0}, joints = {0}, arrows = {0};
    size_t performers = fp_session_performer_count(s);
    for (size_t hh = 0; hh < performers * FP_HANDS; hh++) {
        size_t who = hh / FP_HANDS;
        int h = (int)(hh % FP_HANDS);
        const fp_hand_pose *p = fp_session_performer_hand(s, who, h);
        if (!p) continue;
        float col[4]; /* a later performer's paler: toward white by a third each */
        for (int c = 0; c < 4; c++)
            col[c] = c == 3 ? 1.f : side_colors[h][c] + (1.f - side_colors[h][c]) * (float)who / 3.f;
        for (int f = 0; f < FP_FINGERS; f++) {
            vb_add(&bones, p->joints[FP_JOINT_PALM], col);
            vb_add(&bones, p->joints[FP_JOINT(f, 0)], col);
            for (int k = 0; k < 3; k++) {
                vb_add(&bones, p->joints[FP_JOINT(f, k)], col);
                vb_add(&bones, p->joints[FP_JOINT(f, k + 1)], col);
            }
        }
        for (int j = 0; j < FP_HAND_JOINTS; j++) vb_add(&joints, p->joints[j], col);
    }
    /* Control vectors: a line from start to end and a two-stroke head in the plane that
     * faces the camera. */
    const fp_control_set *cs = fp_session_control_set(s);
    if (cs->active) {
        static const float yellow[4] = {1.f, 0.92f, 0.2f, 1.f};
        float eye_dir[3] = {view[2], view[6], view[10]}; /* camera +z in world */
        for (size_t i = 0; i < cs->count; i++) {
            const float *a = cs->start[i], *b = cs->end[i];
            float d[3];
            v3_sub(b, a, d);
            float len = v3_len(d);
            vb_add(&arrows, a, yellow);
            vb_add(&arrows, b, yellow);
            if (len <= 0) continue;
            float side[3];
            v3_cross(d, eye_dir, side);
            v3_norm(side);
            float hl = fminf(0.3f * len, 0.15f * (float)cs->radius);
            for (int s = -1; s <= 1; s += 2) {
                float q[3];
                for (int k = 0; k < 3; k++) q[k] = b[k] - d[k] / len * hl + side[k] * hl * 0.5f * (float)s;
                vb_add(&arrows, b, yellow);
                vb_add(&arrows, q, yellow);
            }
        }
    }
    draw_tips(r, cues, (float)fp_session_radius(s), pv, view);
    fp_render_lines(r, pv, bones.v, bones.n, GL_LINES, 1.f, true);
    fp_render_lines(r, pv, joints.v, joints.n, GL_POINTS, 5.f, true);
    fp_render_lines(r, pv, arrows.v, arrows.n, GL_LINES, 1.f, false);
    free(bones.v);
    free(joints.v);
    free(arrows.v);
}

/* The rig overlay's colours (G): skull, jaw, soft tissue at jaw weight 0 (it blends towards
 * the jaw's colour as the weight rises to 1), landmarks, the hinge axis. */
static const float rig_skull[3] = {0.3f, 0.45f, 1.f}, rig_jaw[3] = {1.f, 0.3f, 0.15f},
                   rig_soft[3] = {0.3f, 0.8f, 0.3f}, rig_landmark[4] = {1.f, 1.f, 1.f, 1.f},
                   rig_hinge[4] = {0.f, 0.9f, 1.f, 1.f};

void fp_overlay_rig_colors(fp_render *r, const fp_session *s, size_t n)
{
    const fp_rig *rig = fp_session_rig(s);
    const uint8_t *kind = rig ? fp_rig_vertex_kinds(rig) : NULL;
    const float *w = rig ? fp_rig_jaw_weights(rig) : NULL;
    float *rgb = kind && w && fp_rig_vertex_count(rig) == n ? malloc(n * 3 * sizeof *rgb) : NULL;
    if (!rgb) return;
    for (size_t i = 0; i < n; i++) {
        float t = fminf(1.f, fmaxf(0.f, w[i]));
        for (int k = 0; k < 3; k++)
            rgb[3 * i + k] = kind[i] == FP_RIG_SKULL ? rig_skull[k]
                           : kind[i] == FP_RIG_JAW   ? rig_jaw[k]
                                                     : rig_soft[k] + t * (rig_jaw[k] - rig_soft[k]);
    }
    fp_render_set_colors(r, rgb);
    free(rgb);
}

void fp_overlay_rig(fp_render *r, const fp_session *s, const float *pos, size_t n,
                    const float pv[16], int w, int h)
{
    const fp_rig *rig = fp_session_rig(s);
    if (!rig || !pos) return;
    vbuf pts = {0}, axis = {0};
    for (size_t i = 0, nl = fp_rig_landmark_count(rig); i < nl; i++) {
        const char *name;
        uint32_t vi;
        if (!fp_rig_landmark_get(rig, i, &name, &vi) && vi < n) vb_add(&pts, pos + 3 * (size_t)vi, rig_landmark);
    }
    float jr[3], jl[3], d[3], a[3], b[3];
    fp_rig_hinge(rig, jr, jl, NULL, NULL);
    v3_sub(jl, jr, d);
    for (int k = 0; k < 3; k++) {
        a[k] = jr[k] - 0.25f * d[k];
        b[k] = jl[k] + 0.25f * d[k];
    }
    vb_add(&axis, a, rig_hinge);
    vb_add(&axis, b, rig_hinge);
    /* 2 pixels wide (core profiles draw 1-pixel lines): again shifted a pixel right, up */
    for (int pass = 0; pass < 3; pass++) {
        float m[16];
        memcpy(m, pv, sizeof m);
        int row = pass - 1; /* clip x (pass 1) or y (pass 2) += one pixel's NDC times w */
        for (int c = 0; pass && c < 4; c++) m[4 * c + row] += 2.f / (float)(row ? h : w) * m[4 * c + 3];
        fp_render_lines(r, m, axis.v, axis.n, GL_LINES, 1.f, false);
    }
    axis.n = 0;
    vb_add(&axis, jr, rig_hinge);
    vb_add(&axis, jl, rig_hinge);
    fp_render_lines(r, pv, axis.v, axis.n, GL_POINTS, 9.f, false);
    fp_render_lines(r, pv, pts.v, pts.n, GL_POINTS, 5.f, false);
    free(pts.v);
    free(axis.v);
}

float fp_overlay_rig_legend(fp_render *r, const fp_session *s, int w, int h, float y, float scale,
                            float room)
{
    char jaw[64];
    double j = fp_session_channel(s, "jaw.open");
    snprintf(jaw, sizeof jaw, "jaw (jaw.open %.1f)", isnan(j) ? 0.0 : j);
    const struct { const char *text; const float *c; } rows[] = {
        {"rig (G):", NULL}, {"skull", rig_skull}, {jaw, rig_jaw},
        {"soft: jaw weight 0 .. 1", rig_soft}, {"landmarks", rig_landmark}, {"hinge axis", rig_hinge}};
    const float dim[4] = {0.8f, 0.85f, 0.9f, 1.f};
    float y0 = y;
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        /* the rows that fit above the strip; the heading alone says nothing: then none */
        float need = fp_render_text_height(rows[i].text, scale) * (i ? 1 : 2) + (i ? 0 : 2 * scale);
        if (y - y0 + need > room) break;
        float c[4] = {1, 1, 1, 1};
        if (rows[i].c) memcpy(c, rows[i].c, 3 * sizeof *c);
        y += fp_render_text(r, w, h, 8 + (rows[i].c ? 10 * scale : 0), y, scale, rows[i].text,
                            rows[i].c ? c : dim) + 2 * scale;
    }
    return y - y0;
}

float fp_overlay_rig_legend_height(float scale)
{
    return 6 * (fp_render_text_height("rig", scale) + 2 * scale); /* its six rows */
}
