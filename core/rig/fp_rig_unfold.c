/* fp_rig_unfold: jaw weights that turn no triangle over (fp_rig.h, fp_rig_unfold_jaw).
 *
 * The jaw pose turns each soft vertex by its own fraction w of the hinge angle. Where w
 * changes much across a triangle, the triangle is sheared, and past some opening turned
 * over: on the ICT face at jaw.open 0.6, four gum triangles between the rigid lower gums and
 * the soft tongue gums, and at 1.0 also fourteen sub-millimetre triangles at the corners of
 * the lower lip, where the falloff's lip band is narrower than they are. The repair: at
 * openings sampled over the channel's range, every triangle turned over gives its soft
 * vertices the mean weight of its three (a triangle whose weights are equal turns rigidly,
 * which never turns it over), round after round, until none is turned over at any sampled
 * opening; after the first round only triangles with a vertex the last round changed are
 * looked at again (the others' weights, hence their poses, are as they were). Only the
 * vertices of such triangles change (on ICT 56 of 26,719, the face's vertices by 0.025 mm
 * RMS at jaw.open 1); only triangles whose weights differ are posed. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#define UNFOLD_OPENINGS 8   /* openings sampled: max / 8, 2 max / 8, ... max */
#define UNFOLD_ROUNDS 200   /* evening rounds at most */
#define UNFOLD_COS 1e-5     /* turned over: normal within acos(this) of 90 degrees or past it
                               (the contact guard's FP_CONTACT_FLIP_COS) */

static void normal(const float *p, const uint32_t *t, double n[3])
{
    const float *a = p + 3 * (size_t)t[0], *b = p + 3 * (size_t)t[1], *c = p + 3 * (size_t)t[2];
    double u[3] = {(double)b[0] - a[0], (double)b[1] - a[1], (double)b[2] - a[2]};
    double v[3] = {(double)c[0] - a[0], (double)c[1] - a[1], (double)c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

/* Triangle t of `posed` turned over against its normal n0 in the rest shape. */
static bool turned(const float *posed, const uint32_t *t, const double n0[3])
{
    double n[3];
    normal(posed, t, n);
    double l0 = sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]);
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l0 > 0)) return false; /* degenerate at rest: no normal to turn */
    return n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2] <= UNFOLD_COS * l0 * l;
}

/* Mark the triangles turned over at any sampled opening (mark: t flags); their count. Only
 * triangles whose weights differ can turn (equal weights: one rigid motion), so only their
 * vertices are posed (into posed, at their own places). */
static size_t mark_turned(const fp_rig *r, const float *pos, const uint32_t *tris, size_t t,
                          const double *n0, const uint8_t *fresh, float *posed, uint8_t *mark)
{
    const channel *jc = &r->channels[r->jaw_open];
    float values[FP_RIG_MAX_CHANNELS];
    for (size_t c = 0; c < r->channel_count; c++) values[c] = r->channels[c].neutral;
    size_t count = 0;
    memset(mark, 0, t);
    for (int s = 1; s <= UNFOLD_OPENINGS; s++) {
        values[r->jaw_open] = (float)(jc->max * s / UNFOLD_OPENINGS);
        for (size_t k = 0; k < t; k++) {
            const uint32_t *f = tris + 3 * k;
            if (mark[k] || (r->w[f[0]] == r->w[f[1]] && r->w[f[1]] == r->w[f[2]])) continue;
            if (fresh && !fresh[f[0]] && !fresh[f[1]] && !fresh[f[2]]) continue;
            for (int j = 0; j < 3; j++) fp_rig_pose_range(r, pos, values, posed, f[j], 1);
            if (turned(posed, f, n0 + 3 * k)) {
                count++;
                mark[k] = 1;
            }
        }
    }
    return count;
}

int fp_rig_unfold_jaw(fp_rig *r, const float *pos, const uint32_t *tris, size_t t, size_t *changed)
{
    if (changed) *changed = 0;
    if (!r || !pos || (!tris && t) || !r->w) return -EINVAL;
    for (size_t i = 0; i < 3 * t; i++)
        if (tris[i] >= r->n) return -EINVAL;
    if (r->jaw_open < 0 || !(r->open_deg > 0) || !t) return 0;
    double *n0 = malloc(3 * t * sizeof *n0);
    float *posed = malloc(3 * r->n * sizeof *posed);
    uint8_t *mark = malloc(t), *touched = calloc(r->n, 1), *fresh = calloc(r->n, 1);
    int rc = -ENOMEM;
    if (!n0 || !posed || !mark || !touched || !fresh) goto out;
    for (size_t k = 0; k < t; k++) normal(pos, tris + 3 * k, n0 + 3 * k);
    rc = 0;
    for (int round = 0; round < UNFOLD_ROUNDS; round++) {
        if (!mark_turned(r, pos, tris, t, n0, round ? fresh : NULL, posed, mark)) break;
        memset(fresh, 0, r->n);
        /* each turned triangle's soft vertices take the triangle's mean weight, in turn */
        bool moved = false;
        for (size_t k = 0; k < t; k++) {
            const uint32_t *f = tris + 3 * k;
            if (!mark[k]) continue;
            double mean = (r->w[f[0]] + r->w[f[1]] + r->w[f[2]]) / 3;
            for (int j = 0; j < 3; j++)
                if (r->kind[f[j]] == FP_RIG_SOFT && r->w[f[j]] != (float)mean) {
                    r->w[f[j]] = (float)mean;
                    touched[f[j]] = fresh[f[j]] = 1;
                    moved = true;
                }
        }
        if (!moved) break; /* what is left turned over has no soft vertex to give */
    }
    if (changed)
        for (size_t v = 0; v < r->n; v++) *changed += touched[v]; /* (soft vertices only) */
out:
    free(n0);
    free(posed);
    free(mark);
    free(touched);
    free(fresh);
    return rc;
}
