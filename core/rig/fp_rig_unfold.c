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
 * RMS at jaw.open 1); only the vertices of triangles whose weights differ are posed, each
 * once an opening. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"
#include "fp_mesh.h"
#include "fp_vec.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#define UNFOLD_OPENINGS 8   /* openings sampled: max / 8, 2 max / 8, ... max */
#define UNFOLD_ROUNDS 200   /* evening rounds at most */

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
    return n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2] <= FP_FLIP_COS * l0 * l;
}

/* The repair's working state. An opening's candidates (cand, up to t) and the vertices they
 * need posed (vlist, up to n; vstamp[v] == clock: listed already; tstamp[k] == clock: triangle
 * k looked at). A round's marked triangles (marked, ascending; mark[k] set) and the vertices
 * it changed (freshv; fresh[v] set). Each vertex's triangles (adj[adj_start[v] ..
 * adj_start[v + 1]), fp_mesh_vertex_triangles), so that a round after the first looks only at the triangles of the
 * vertices the last one changed, not at all t (on the 1.7M-vertex face, ICT subdivided three
 * times, the rounds ran to their cap of 200, each over 3.4M triangles eight times). */
typedef struct unfold {
    uint32_t *cand, *vlist, *vstamp, *tstamp, clock;
    uint32_t *marked, *freshv, *adj_start, *adj;
    size_t nmarked, nfresh;
    uint8_t *mark, *fresh;
} unfold;

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* triangle k may turn: not marked yet, and its weights differ (equal weights: one rigid
 * motion, which never turns it over) */
static inline bool may_turn(const fp_rig *r, const unfold *u, const uint32_t *f, size_t k)
{
    return !u->mark[k] && !(r->w[f[0]] == r->w[f[1]] && r->w[f[1]] == r->w[f[2]]);
}

/* Mark the triangles turned over at any sampled opening, into u->marked (ascending) and
 * u->mark; their count. The first round looks at every triangle, a later one at those of
 * u->freshv. Only the candidates' vertices are posed (into posed, at their own places), each
 * once an opening. */
static size_t mark_turned(const fp_rig *r, const float *pos, const uint32_t *tris, size_t t,
                          const double *n0, bool first, float *posed, unfold *u)
{
    const channel *jc = &r->channels[r->jaw_open];
    float values[FP_RIG_MAX_CHANNELS];
    for (size_t c = 0; c < r->channel_count; c++) values[c] = r->channels[c].neutral;
    for (size_t i = 0; i < u->nmarked; i++) u->mark[u->marked[i]] = 0;
    u->nmarked = 0;
    for (int s = 1; s <= UNFOLD_OPENINGS; s++) {
        values[r->jaw_open] = (float)(jc->max * s / UNFOLD_OPENINGS);
        assert(u->clock < UINT32_MAX); /* (8 an opening's round, 200 rounds) */
        const uint32_t clk = ++u->clock;
        size_t nc = 0, nv = 0;
#define CANDIDATE(k)                                                                           \
    do {                                                                                       \
        const uint32_t *f = tris + 3 * (size_t)(k);                                            \
        if (may_turn(r, u, f, (k))) {                                                          \
            u->cand[nc++] = (uint32_t)(k);                                                     \
            for (int j = 0; j < 3; j++)                                                        \
                if (u->vstamp[f[j]] != clk) u->vstamp[f[j]] = clk, u->vlist[nv++] = f[j];      \
        }                                                                                      \
    } while (0)
        if (first) {
            for (size_t k = 0; k < t; k++) CANDIDATE(k);
        } else {
            for (size_t i = 0; i < u->nfresh; i++) {
                uint32_t v = u->freshv[i];
                for (uint32_t a = u->adj_start[v]; a < u->adj_start[v + 1]; a++) {
                    uint32_t k = u->adj[a];
                    if (u->tstamp[k] == clk) continue;
                    u->tstamp[k] = clk;
                    CANDIDATE(k);
                }
            }
        }
#undef CANDIDATE
        for (size_t i = 0; i < nv; i++) fp_rig_pose_range(r, pos, values, posed, u->vlist[i], 1);
        for (size_t i = 0; i < nc; i++) {
            size_t k = u->cand[i];
            if (turned(posed, tris + 3 * k, n0 + 3 * k)) {
                u->mark[k] = 1;
                u->marked[u->nmarked++] = (uint32_t)k;
            }
        }
    }
    qsort(u->marked, u->nmarked, sizeof *u->marked, cmp_u32);
    return u->nmarked;
}

int fp_rig_unfold_jaw(fp_rig *r, const float *pos, const uint32_t *tris, size_t t, size_t *changed)
{
    if (changed) *changed = 0;
    if (!r || !pos || (!tris && t) || !r->w) return -EINVAL;
    for (size_t i = 0; i < 3 * t; i++)
        if (tris[i] >= r->n) return -EINVAL;
    if (r->jaw_open < 0 || !(r->open_deg > 0) || !t) return 0;
    if (t > UINT32_MAX / 3) return -EINVAL;
    uint32_t *welded = NULL; /* a mesh split at seams (fp_rig_remap): its triangles joined */
    if (r->weld) {
        if (!(welded = malloc(3 * t * sizeof *welded))) return -ENOMEM;
        for (size_t i = 0; i < 3 * t; i++) welded[i] = r->weld[tris[i]];
        tris = welded;
    }
    size_t n = r->n;
    double *n0 = malloc(3 * t * sizeof *n0);
    float *posed = malloc(3 * n * sizeof *posed);
    uint8_t *touched = calloc(n, 1);
    unfold u = {.cand = malloc(t * sizeof *u.cand), .vlist = malloc(n * sizeof *u.vlist),
                .vstamp = calloc(n, sizeof *u.vstamp), .tstamp = calloc(t, sizeof *u.tstamp),
                .marked = malloc(t * sizeof *u.marked), .freshv = malloc(n * sizeof *u.freshv),
                .mark = calloc(t, 1), .fresh = calloc(n, 1)};
    int rc = -ENOMEM;
    if (!n0 || !posed || !touched || !u.cand || !u.vlist || !u.vstamp || !u.tstamp || !u.marked ||
        !u.freshv || !u.mark || !u.fresh)
        goto out;
    if ((rc = fp_mesh_vertex_triangles(tris, t, n, &u.adj_start, &u.adj))) goto out; /* (-ENOMEM, -EINVAL) */
    for (size_t k = 0; k < t; k++) normal(pos, tris + 3 * k, n0 + 3 * k);
    rc = 0;
    for (int round = 0; round < UNFOLD_ROUNDS; round++) {
        if (!mark_turned(r, pos, tris, t, n0, round == 0, posed, &u)) break;
        for (size_t i = 0; i < u.nfresh; i++) u.fresh[u.freshv[i]] = 0;
        u.nfresh = 0;
        /* each turned triangle's soft vertices take the triangle's mean weight, in turn (in
         * the triangles' order) */
        for (size_t i = 0; i < u.nmarked; i++) {
            const uint32_t *f = tris + 3 * (size_t)u.marked[i];
            double mean = (r->w[f[0]] + r->w[f[1]] + r->w[f[2]]) / 3;
            for (int j = 0; j < 3; j++)
                if (r->kind[f[j]] == FP_RIG_SOFT && r->w[f[j]] != (float)mean) {
                    r->w[f[j]] = (float)mean;
                    touched[f[j]] = 1;
                    if (!u.fresh[f[j]]) u.fresh[f[j]] = 1, u.freshv[u.nfresh++] = f[j];
                }
        }
        if (!u.nfresh) break; /* what is left turned over has no soft vertex to give */
    }
    if (r->weld) /* each split copy as its first */
        for (size_t v = 0; v < r->n; v++)
            if (r->w[v] != r->w[r->weld[v]]) r->w[v] = r->w[r->weld[v]], touched[v] = 1;
    if (changed)
        for (size_t v = 0; v < r->n; v++) *changed += touched[v]; /* (soft vertices only) */
out:
    free(welded);
    free(n0), free(posed), free(touched);
    free(u.cand), free(u.vlist), free(u.vstamp), free(u.tstamp), free(u.marked), free(u.freshv);
    free(u.adj_start), free(u.adj), free(u.mark), free(u.fresh);
    return rc;
}
