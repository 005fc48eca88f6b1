/* csrbf_points: the base vertices as structure-of-arrays blocks of CSRBF_BLOCK consecutive
 * vertices with bounding boxes, so that csrbf_evaluate skips blocks outside every support
 * and still writes its output contiguously. Locality comes from the mesh's own vertex order
 * (scanned and modelled meshes, grids: consecutive vertices are neighbours); a scrambled
 * order stays correct but gains nothing from the boxes. */
#define _POSIX_C_SOURCE 200112L
#include "internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

uint64_t csrbf_new_stamp(void)
{
    static _Atomic uint64_t counter = 0;
    return atomic_fetch_add(&counter, 1) + 1;
}

static int check(size_t n, const float *xyz)
{
    for (size_t i = 0; i < 3 * n; i++)
        if (!(fabsf(xyz[i]) <= (float)CSRBF_MAX_COORD)) return CSRBF_ERR_INVALID;
    return CSRBF_OK;
}

/* Recompute blocks b0..b1 from p->xyz; the global box grows to hold them (it never
 * shrinks here, which only makes csrbf_evaluate's whole-box test more conservative). */
static void fill_block_range(csrbf_points *p, size_t b0, size_t b1)
{
    size_t n = p->n;
    for (size_t b = b0; b < b1; b++) {
        size_t k0 = b * CSRBF_BLOCK, k1 = k0 + CSRBF_BLOCK < n ? k0 + CSRBF_BLOCK : n;
        for (int a = 0; a < 3; a++) {
            float lo = INFINITY, hi = -INFINITY;
            for (size_t k = k0; k < k1; k++) {
                float v = p->xyz[3 * k + a];
                p->s[a][k] = v;
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
            }
            for (size_t k = k1; k < k0 + CSRBF_BLOCK; k++) p->s[a][k] = p->s[a][k0]; /* padding */
            p->lo[a][b] = lo;
            p->hi[a][b] = hi;
            if (lo < p->blo[a]) p->blo[a] = lo;
            if (hi > p->bhi[a]) p->bhi[a] = hi;
        }
    }
}

/* Recompute the superblock boxes that hold blocks b0..b1-1. */
static void fill_super_range(csrbf_points *p, size_t b0, size_t b1)
{
    if (b1 <= b0) return;
    for (size_t sb = b0 / CSRBF_SUPER; sb <= (b1 - 1) / CSRBF_SUPER; sb++) {
        size_t k0 = sb * CSRBF_SUPER, k1 = k0 + CSRBF_SUPER < p->nblocks ? k0 + CSRBF_SUPER : p->nblocks;
        for (int a = 0; a < 3; a++) {
            float lo = INFINITY, hi = -INFINITY;
            for (size_t b = k0; b < k1; b++) {
                lo = p->lo[a][b] < lo ? p->lo[a][b] : lo;
                hi = p->hi[a][b] > hi ? p->hi[a][b] : hi;
            }
            p->slo[a][sb] = lo;
            p->shi[a][sb] = hi;
        }
    }
}

static size_t pad_fan(size_t n) { return (n + CSRBF_FAN - 1) / CSRBF_FAN * CSRBF_FAN; }

/* Recompute the block tree's nodes above blocks b0..b1-1 from their children (exact: a
 * node's box is the union of its children's, padding boxes being empty). */
static void fill_tree_range(csrbf_points *p, size_t b0, size_t b1)
{
    if (b1 <= b0) return;
    size_t i0 = b0, i1 = b1 - 1; /* inclusive node range at the current level */
    for (int l = 1; l < p->tlevels; l++) {
        i0 /= CSRBF_FAN;
        i1 /= CSRBF_FAN;
        for (int a = 0; a < 3; a++) {
            const float *clo = p->tlo[l - 1][a], *chi = p->thi[l - 1][a];
            for (size_t i = i0; i <= i1; i++) {
                float lo = INFINITY, hi = -INFINITY;
                for (size_t c = CSRBF_FAN * i; c < CSRBF_FAN * i + CSRBF_FAN; c++) {
                    lo = clo[c] < lo ? clo[c] : lo;
                    hi = chi[c] > hi ? chi[c] : hi;
                }
                p->tlo[l][a][i] = lo;
                p->thi[l][a][i] = hi;
            }
        }
    }
}

static void fill_blocks(csrbf_points *p)
{
    for (int a = 0; a < 3; a++) {
        p->blo[a] = INFINITY;
        p->bhi[a] = -INFINITY;
    }
    fill_block_range(p, 0, p->nblocks);
    fill_super_range(p, 0, p->nblocks);
    fill_tree_range(p, 0, p->nblocks);
}

void csrbf_points_destroy(csrbf_points **pp)
{
    if (!pp || !*pp) return;
    csrbf_points *p = *pp;
    free(p->xyz);
    for (int a = 0; a < 3; a++) {
        free(p->s[a]);
        free(p->lo[a]);
        free(p->hi[a]);
        free(p->slo[a]);
        free(p->shi[a]);
        for (int l = 1; l < p->tlevels; l++) {
            free(p->tlo[l][a]);
            free(p->thi[l][a]);
        }
    }
    free(p);
    *pp = NULL;
}

static void *alloc64(size_t bytes)
{
    void *q = NULL;
    return posix_memalign(&q, 64, bytes ? bytes : 64) ? NULL : q;
}

int csrbf_points_create(size_t n, const float *xyz, csrbf_points **out)
{
    if (!out) return CSRBF_ERR_INVALID;
    *out = NULL;
    if (!xyz || n == 0 || n >= UINT32_MAX || check(n, xyz)) return CSRBF_ERR_INVALID;
    csrbf_points *p = calloc(1, sizeof *p);
    if (!p) return CSRBF_ERR_NOMEM;
    p->n = n;
    p->nblocks = (n + CSRBF_BLOCK - 1) / CSRBF_BLOCK;
    size_t padded = p->nblocks * CSRBF_BLOCK;
    p->xyz = malloc(n * 3 * sizeof(float));
    int ok = p->xyz != NULL;
    /* the block tree's levels: counts down to at most CSRBF_FAN nodes at the top */
    p->tcount[0] = p->nblocks;
    p->tlevels = 1;
    while (p->tcount[p->tlevels - 1] > CSRBF_FAN) {
        p->tcount[p->tlevels] = (p->tcount[p->tlevels - 1] + CSRBF_FAN - 1) / CSRBF_FAN;
        p->tlevels++;
    }
    for (int a = 0; a < 3 && ok; a++) {
        p->s[a] = alloc64(padded * sizeof(float));
        p->lo[a] = alloc64(pad_fan(p->nblocks) * sizeof(float));
        p->hi[a] = alloc64(pad_fan(p->nblocks) * sizeof(float));
        p->tlo[0][a] = p->lo[a];
        p->thi[0][a] = p->hi[a];
        for (int l = 0; l < p->tlevels && p->lo[a] && p->hi[a]; l++) {
            size_t np = pad_fan(p->tcount[l]);
            if (l > 0) {
                p->tlo[l][a] = alloc64(np * sizeof(float));
                p->thi[l][a] = alloc64(np * sizeof(float));
                if (!p->tlo[l][a] || !p->thi[l][a]) {
                    ok = 0;
                    break;
                }
            }
            for (size_t i = p->tcount[l]; i < np; i++) { /* padding: empty boxes */
                p->tlo[l][a][i] = INFINITY;
                p->thi[l][a][i] = -INFINITY;
            }
        }
        p->nsuper = (p->nblocks + CSRBF_SUPER - 1) / CSRBF_SUPER;
        p->slo[a] = malloc(p->nsuper * sizeof(float));
        p->shi[a] = malloc(p->nsuper * sizeof(float));
        ok = ok && p->s[a] && p->lo[a] && p->hi[a] && p->slo[a] && p->shi[a];
    }
    if (!ok) {
        csrbf_points_destroy(&p);
        return CSRBF_ERR_NOMEM;
    }
    memcpy(p->xyz, xyz, n * 3 * sizeof(float));
    fill_blocks(p);
    p->stamp = csrbf_new_stamp();
    *out = p;
    return CSRBF_OK;
}

int csrbf_points_update(csrbf_points *p, const float *xyz)
{
    if (!p || !xyz || check(p->n, xyz)) return CSRBF_ERR_INVALID;
    memcpy(p->xyz, xyz, p->n * 3 * sizeof(float));
    fill_blocks(p);
    p->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

int csrbf_points_update_ranges(csrbf_points *p, const float *xyz, const uint32_t *ranges,
                               size_t nranges)
{
    if (!p || !xyz || (!ranges && nranges)) return CSRBF_ERR_INVALID;
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        if (v0 > p->n || c > p->n - v0 || check(c, xyz + 3 * v0)) return CSRBF_ERR_INVALID;
    }
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        if (!c) continue;
        memcpy(p->xyz + 3 * v0, xyz + 3 * v0, c * 3 * sizeof(float));
        fill_block_range(p, v0 / CSRBF_BLOCK, (v0 + c + CSRBF_BLOCK - 1) / CSRBF_BLOCK);
        fill_super_range(p, v0 / CSRBF_BLOCK, (v0 + c + CSRBF_BLOCK - 1) / CSRBF_BLOCK);
        fill_tree_range(p, v0 / CSRBF_BLOCK, (v0 + c + CSRBF_BLOCK - 1) / CSRBF_BLOCK);
    }
    p->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

size_t csrbf_points_count(const csrbf_points *p) { return p ? p->n : 0; }

/* Squared distance from q to block b's box (0 inside), float, the same rounding as a vertex
 * of the block would see on each axis (|q - v| >= |q - box| exactly, and float squares and
 * sums round monotonically), so it never exceeds a vertex's own squared distance. */
static inline float box_d2_of(const float *const lo3[3], const float *const hi3[3], size_t b,
                              const float q[3])
{
    float d[3];
    for (int a = 0; a < 3; a++) {
        float lo = lo3[a][b], hi = hi3[a][b];
        d[a] = q[a] < lo ? q[a] - lo : q[a] > hi ? q[a] - hi : 0.0f;
    }
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

static inline float box_d2(const csrbf_points *p, size_t b, const float q[3])
{
    return box_d2_of((const float *const *)p->lo, (const float *const *)p->hi, b, q);
}

static inline float super_d2(const csrbf_points *p, size_t sb, const float q[3])
{
    return box_d2_of((const float *const *)p->slo, (const float *const *)p->shi, sb, q);
}

/* Block b against query q: improves *best / *idx (ties: the smaller vertex index). */
static inline void scan_block(const csrbf_points *p, size_t b, const float q[3], float *best,
                              uint32_t *idx)
{
    size_t k0 = b * CSRBF_BLOCK, nv = k0 + CSRBF_BLOCK <= p->n ? CSRBF_BLOCK : p->n - k0;
    const float *x = p->s[0] + k0, *y = p->s[1] + k0, *z = p->s[2] + k0;
    float d2[CSRBF_BLOCK];
    for (size_t l = 0; l < CSRBF_BLOCK; l++) { /* vectorised: 16 lanes */
        float dx = x[l] - q[0], dy = y[l] - q[1], dz = z[l] - q[2];
        d2[l] = dx * dx + dy * dy + dz * dz;
    }
    for (size_t l = 0; l < nv; l++)
        if (d2[l] < *best || (d2[l] == *best && (uint32_t)(k0 + l) < *idx)) {
            *best = d2[l];
            *idx = (uint32_t)(k0 + l);
        }
}

int csrbf_points_nearest(const csrbf_points *p, const float *queries, size_t nq, float max_dist,
                         float *out_dist, uint32_t *out_index)
{
    if (!p || (nq && (!queries || !out_dist)) || isnan(max_dist) || max_dist < 0)
        return CSRBF_ERR_INVALID;
    enum { QMAX = 64 };
    for (size_t q0 = 0; q0 < nq; q0 += QMAX) {
        size_t m = nq - q0 < QMAX ? nq - q0 : QMAX;
        float best[QMAX], q[QMAX][3];
        uint32_t idx[QMAX];
        float lim = max_dist * max_dist; /* +inf stays +inf */
        for (size_t i = 0; i < m; i++) {
            memcpy(q[i], queries + 3 * (q0 + i), sizeof q[i]);
            best[i] = INFINITY;
            idx[i] = UINT32_MAX;
            if (!(isfinite(q[i][0]) && isfinite(q[i][1]) && isfinite(q[i][2])))
                return CSRBF_ERR_INVALID;
            /* a first candidate: the nearest block of the nearest superblock */
            size_t sbb = 0, bb = 0;
            float bd = INFINITY;
            for (size_t sb = 0; sb < p->nsuper; sb++) {
                float d = super_d2(p, sb, q[i]);
                if (d < bd) {
                    bd = d;
                    sbb = sb;
                }
            }
            bd = INFINITY;
            size_t k1 = (sbb + 1) * CSRBF_SUPER < p->nblocks ? (sbb + 1) * CSRBF_SUPER : p->nblocks;
            for (size_t b = sbb * CSRBF_SUPER; b < k1; b++) {
                float d = box_d2(p, b, q[i]);
                if (d < bd) {
                    bd = d;
                    bb = b;
                }
            }
            if (bd <= lim) scan_block(p, bb, q[i], &best[i], &idx[i]);
        }
        /* one pass over the superblocks and blocks for all queries: a box is opened only by
         * the queries whose current best it may improve */
        for (size_t sb = 0; sb < p->nsuper; sb++) {
            uint64_t want = 0;
            for (size_t i = 0; i < m; i++) {
                float d = super_d2(p, sb, q[i]);
                if (d <= best[i] && d <= lim) want |= 1ull << i;
            }
            if (!want) continue;
            size_t k1 = (sb + 1) * CSRBF_SUPER < p->nblocks ? (sb + 1) * CSRBF_SUPER : p->nblocks;
            for (size_t b = sb * CSRBF_SUPER; b < k1; b++)
                for (uint64_t w = want; w; w &= w - 1) {
                    size_t i = (size_t)__builtin_ctzll(w);
                    float d = box_d2(p, b, q[i]);
                    if (d <= best[i] && d <= lim) scan_block(p, b, q[i], &best[i], &idx[i]);
                }
        }
        for (size_t i = 0; i < m; i++) {
            int hit = idx[i] != UINT32_MAX && best[i] <= lim;
            out_dist[q0 + i] = hit ? sqrtf(best[i]) : INFINITY;
            if (out_index) out_index[q0 + i] = hit ? idx[i] : UINT32_MAX;
        }
    }
    return CSRBF_OK;
}
