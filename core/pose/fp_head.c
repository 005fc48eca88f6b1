/* The head in a face mesh and the mesh's unit (fp_head.h says how). */
#include "fp_head.h"

#include "fp_vec.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SLICES 64

int fp_head_detect(const float *pos, size_t n, fp_head *out) { return fp_head_detect_used(pos, n, NULL, out); }

int fp_head_detect_used(const float *pos, size_t n, const uint8_t *used, fp_head *out)
{
    if (!pos || !out || n < 4) return -EINVAL;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t m = 0;
    for (size_t v = 0; v < n; v++) {
        if (used && !used[v]) continue;
        m++;
        for (int k = 0; k < 3; k++) {
            float c = pos[3 * v + k];
            if (!isfinite(c)) return -EINVAL;
            lo[k] = fminf(lo[k], c);
            hi[k] = fmaxf(hi[k], c);
        }
    }
    double height = (double)hi[1] - lo[1];
    if (m < 4 || !(height > 0) || !(hi[0] > lo[0])) return -EINVAL;
    /* Per slice: x and z extents of its vertices. */
    float (*ext)[4] = malloc(SLICES * sizeof *ext);   /* xmin, xmax, zmin, zmax */
    if (!ext) return -ENOMEM;
    for (int s = 0; s < SLICES; s++) ext[s][0] = ext[s][2] = INFINITY, ext[s][1] = ext[s][3] = -INFINITY;
    for (size_t v = 0; v < n; v++) {
        if (used && !used[v]) continue;
        int s = (int)((pos[3 * v + 1] - lo[1]) / height * SLICES);
        if (s >= SLICES) s = SLICES - 1;
        if (s < 0) s = 0;
        ext[s][0] = fminf(ext[s][0], pos[3 * v]);
        ext[s][1] = fmaxf(ext[s][1], pos[3 * v]);
        ext[s][2] = fminf(ext[s][2], pos[3 * v + 2]);
        ext[s][3] = fmaxf(ext[s][3], pos[3 * v + 2]);
    }
    double width[SLICES];
    for (int s = 0; s < SLICES; s++) {
        float e[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
        for (int t = s - 1; t <= s + 1; t++) {
            if (t < 0 || t >= SLICES) continue;
            e[0] = fminf(e[0], ext[t][0]);
            e[1] = fmaxf(e[1], ext[t][1]);
            e[2] = fminf(e[2], ext[t][2]);
            e[3] = fmaxf(e[3], ext[t][3]);
        }
        width[s] = e[1] >= e[0] ? (double)e[1] - e[0] : 0;
    }
    free(ext);
    /* Walk down from the top. */
    int widest = SLICES - 1, neck = -1, narrow = -1;
    for (int s = SLICES - 1; s >= 0; s--) {
        if (narrow < 0) {
            if (width[s] > width[widest]) widest = s;
            else if (width[s] < 0.85 * width[widest]) narrow = s;
            continue;
        }
        if (width[s] < width[narrow]) narrow = s;
        else if (width[s] > 1.2 * width[narrow]) {
            neck = narrow;
            break;
        }
    }
    memset(out, 0, sizeof *out);
    float y_neck = neck > 0 ? (float)(lo[1] + (neck + 0.5) * height / SLICES) : lo[1];
    for (int pass = 0; pass < 2; pass++) {
        for (int k = 0; k < 3; k++) out->min[k] = INFINITY, out->max[k] = -INFINITY;
        for (size_t v = 0; v < n; v++) {
            if ((used && !used[v]) || pos[3 * v + 1] < y_neck) continue;
            for (int k = 0; k < 3; k++) {
                out->min[k] = fminf(out->min[k], pos[3 * v + k]);
                out->max[k] = fmaxf(out->max[k], pos[3 * v + k]);
            }
        }
        double w = (double)out->max[0] - out->min[0], d = (double)out->max[2] - out->min[2];
        if (pass == 1) break;
        if (d < 0.8 * w) { /* a mask: no back of the head; the whole mesh is the face */
            out->method = FP_HEAD_FACE_WIDTH;
            out->mm_per_unit = FP_HEAD_FACE_WIDTH_MM / ((double)hi[0] - lo[0]);
            snprintf(out->how, sizeof out->how,
                     "detected from the face: a mask %.4g units wide = %g mm (depth %.2f of width)",
                     (double)hi[0] - lo[0], FP_HEAD_FACE_WIDTH_MM, d / w);
            y_neck = lo[1];
            continue;
        }
        double h = (double)hi[1] - y_neck;
        if (!(h > 0)) return -EINVAL; /* no height above the neck (a mesh of a few float steps) */
        out->method = neck > 0 ? FP_HEAD_NECK : FP_HEAD_NO_NECK;
        out->mm_per_unit = FP_HEAD_HEIGHT_MM / h;
        snprintf(out->how, sizeof out->how, "detected from the head: %.4g units %s to crown = %g mm",
                 h, neck > 0 ? "neck" : "bottom", FP_HEAD_HEIGHT_MM);
        break;
    }
    out->neck_y = y_neck;
    return 0;
}

int fp_head_surface_z(const float *pos, size_t n, float x, float y, float r, float y_lo,
                      float y_hi, float *z)
{
    int found = 0;
    float best = -INFINITY, r2 = r * r;
    for (size_t v = 0; v < n; v++) {
        const float *p = pos + 3 * v;
        if (p[1] < y_lo || p[1] > y_hi) continue;
        float dx = p[0] - x, dy = p[1] - y;
        if (dx * dx + dy * dy > r2) continue;
        if (p[2] > best) best = p[2];
        found = 1;
    }
    if (found) *z = best;
    return found;
}

bool fp_head_scale_plausible(double diagonal, double mm_per_unit, double *across_mm)
{
    const double across = diagonal * mm_per_unit;
    if (across_mm) *across_mm = across;
    return across >= FP_HEAD_ACROSS_MIN_MM && across <= FP_HEAD_ACROSS_MAX_MM;
}

int fp_head_detect_turned(const float *pos, size_t n, const uint8_t *used, const double face[4], float *turned,
                          fp_head *out)
{
    if (!pos || !face || !turned || !out) return -EINVAL;
    const double back[4] = {face[0], -face[1], -face[2], -face[3]}; /* the inverse */
    for (size_t v = 0; v < n; v++) {
        const double p[3] = {pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]};
        double c[3];
        fp_qrot(back, p, c);
        for (int i = 0; i < 3; i++) turned[3 * v + i] = (float)c[i];
    }
    return fp_head_detect_used(turned, n, used, out);
}

int fp_head_nose(const float *pos, size_t n, const uint8_t *used, fp_head_front *out)
{
    if (!pos || !out) return -EINVAL;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; v++) {
        if (used && !used[v]) continue;
        for (int k = 0; k < 3; k++) lo[k] = fminf(lo[k], pos[3 * v + k]), hi[k] = fmaxf(hi[k], pos[3 * v + k]);
    }
    double ext[3];
    for (int k = 0; k < 3; k++)
        if (!((ext[k] = (double)hi[k] - lo[k]) > 0) || !isfinite(ext[k])) return -EINVAL;
    /* each end's cap (d = 2k for -k, 2k + 1 for +k): its box across, [d][j][0 min, 1 max] */
    float cap[6][3][2];
    for (int d = 0; d < 6; d++)
        for (int j = 0; j < 3; j++) cap[d][j][0] = INFINITY, cap[d][j][1] = -INFINITY;
    for (size_t v = 0; v < n; v++) {
        if (used && !used[v]) continue;
        const float *p = pos + 3 * v;
        for (int k = 0; k < 3; k++) {
            const double depth = FP_HEAD_CAP_DEPTH * ext[k];
            int d = (double)p[k] <= lo[k] + depth ? 2 * k : (double)p[k] >= hi[k] - depth ? 2 * k + 1 : -1;
            if (d < 0) continue;
            for (int j = 0; j < 3; j++) cap[d][j][0] = fminf(cap[d][j][0], p[j]), cap[d][j][1] = fmaxf(cap[d][j][1], p[j]);
        }
    }
    double area[6];
    for (int d = 0; d < 6; d++) {
        area[d] = 1;
        for (int j = 0; j < 3; j++)
            if (j != d / 2) area[d] *= ((double)cap[d][j][1] - cap[d][j][0]) / ext[j];
    }
    int best = -1;
    for (int d = 0; d < 6; d++)
        if (area[d ^ 1] >= FP_HEAD_NOSE_CONTRAST * area[d] && (best < 0 || area[d] < area[best])) best = d;
    if (best < 0) return -ENOENT;
    const int k = best / 2, a = (k + 1) % 3, b = (k + 2) % 3;
    out->axis = k;
    out->sign = best & 1 ? 1 : -1;
    out->up_axis = ext[a] >= ext[b] ? a : b;
    out->cap = area[best];
    out->opposite = area[best ^ 1];
    return 0;
}

/* ---- which way the face looks (fp_head_facing_hint) ---------------------------------- */

/* A face whose vertices are spread evenly (a smooth or procedural head: no detailed front)
 * leaves the mean in the middle; its nose still stands out (fp_head_nose): where it points
 * elsewhere than +z, the log says so, with the options to give. */
static bool nose_hint(const float *pos, size_t n, const uint8_t *used, char *msg, size_t len)
{
    fp_head_front f;
    if (fp_head_nose(pos, n, used, &f) || (f.axis == 2 && f.sign > 0)) return false;
    const char sign = f.sign > 0 ? '+' : '-', axis = "xyz"[f.axis], up = "xyz"[f.up_axis];
    snprintf(msg, len,
                   "no rig and no --up/--facing: the face is taken to look along +z with +y up, but "
                   "its most protruding end, a nose, points along %c%c (the vertices within %g of "
                   "the mesh's extent of its tip cover %.2f of the mesh's cross-section, those at "
                   "the other end %.2f): if it looks along %c%c, give --up and --facing (its head is longest "
                   "along %c: --up +%c --facing %c%c, or --up -%c where its crown is at -%c)",
                   sign, axis, FP_HEAD_CAP_DEPTH, f.cap, f.opposite, sign, axis, up, up, sign, axis,
                   up, up);
    return true;
}

#define FACING_HINT_MIN 0.12 /* the mean's offset, in the box's extent, that counts */
bool fp_head_facing_hint(const float *pos, size_t n, const uint8_t *used, char *msg, size_t len)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, sum[3] = {0, 0, 0};
    size_t k = 0;
    if (!pos || !msg || !len) return false;
    for (size_t v = 0; v < n; v++) {
        if (used && !used[v]) continue;
        for (int i = 0; i < 3; i++) {
            double x = pos[3 * v + i];
            lo[i] = fmin(lo[i], x), hi[i] = fmax(hi[i], x), sum[i] += x;
        }
        k++;
    }
    int best = -1;
    double off[3], most = 0;
    for (int i = 0; i < 3 && k; i++) {
        off[i] = hi[i] > lo[i] ? (sum[i] / (double)k - 0.5 * (lo[i] + hi[i])) / (hi[i] - lo[i]) : 0;
        if (fabs(off[i]) > most) most = fabs(off[i]), best = i;
    }
    if (best < 0 || most < FACING_HINT_MIN || (best == 2 && off[2] > 0))
        return nose_hint(pos, n, used, msg, len);
    const char sign = off[best] > 0 ? '+' : '-', axis = "xyz"[best];
    snprintf(msg, len,
                   "no rig and no --up/--facing: the face is taken to look along +z with +y up, but "
                   "its vertices lie most toward %c%c (%.2f of its extent off the middle; a face's "
                   "detailed front does): if it looks along %c%c, give --up and --facing (Blender's "
                   "Z-up: --up +z --facing -y)", sign, axis, fabs(off[best]), sign, axis);
    return true;
}
