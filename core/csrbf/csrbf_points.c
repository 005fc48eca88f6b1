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

int csrbf_points_clone(const csrbf_points *src, csrbf_points **out)
{
    if (!out) return CSRBF_ERR_INVALID;
    *out = NULL;
    return src ? csrbf_points_create(src->n, src->xyz, out) : CSRBF_ERR_INVALID;
}

int csrbf_points_copy(csrbf_points *dst, const csrbf_points *src)
{
    if (!dst || !src || dst->n != src->n) return CSRBF_ERR_INVALID;
    if (dst == src) return CSRBF_OK;
    size_t nf = pad_fan(src->nblocks);
    memcpy(dst->xyz, src->xyz, src->n * 3 * sizeof(float));
    for (int a = 0; a < 3; a++) {
        memcpy(dst->s[a], src->s[a], src->nblocks * CSRBF_BLOCK * sizeof(float));
        memcpy(dst->lo[a], src->lo[a], nf * sizeof(float));
        memcpy(dst->hi[a], src->hi[a], nf * sizeof(float));
        memcpy(dst->slo[a], src->slo[a], src->nsuper * sizeof(float));
        memcpy(dst->shi[a], src->shi[a], src->nsuper * sizeof(float));
        for (int l = 1; l < src->tlevels; l++) {
            memcpy(dst->tlo[l][a], src->tlo[l][a], pad_fan(src->tcount[l]) * sizeof(float));
            memcpy(dst->thi[l][a], src->thi[l][a], pad_fan(src->tcount[l]) * sizeof(float));
        }
        dst->blo[a] = src->blo[a];
        dst->bhi[a] = src->bhi[a];
    }
    dst->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

/* SIMD clones of the box pass (AVX-512, AVX2, baseline), as csrbf_eval.c's kernels. No
 * multiply-add contraction in this file (-ffp-contract=off): distances equal a plain loop's. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__ELF__)
#define PTS_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PTS_CLONES
#endif

/* Squared distances from q to the boxes k0..k1-1 of (lo, hi) into out[0..k1-k0) (0 inside),
 * in float with the same rounding a vertex of the box would see on each axis (|q - v| >=
 * |q - box| exactly, and float squares and sums round monotonically), so a box's value never
 * exceeds one of its vertices' own squared distance. Returns the index (from 0) of the
 * smallest, the first among equals. One vectorised pass. */
PTS_CLONES static size_t boxes_d2(const float *const lo[3], const float *const hi[3], size_t k0,
                                  size_t k1, const float q[3], float *restrict out)
{
    const float *restrict lx = lo[0] + k0, *restrict ly = lo[1] + k0, *restrict lz = lo[2] + k0;
    const float *restrict hx = hi[0] + k0, *restrict hy = hi[1] + k0, *restrict hz = hi[2] + k0;
    const float qx = q[0], qy = q[1], qz = q[2];
    size_t k = k1 - k0;
    uint32_t least = UINT32_MAX; /* non-negative floats order as their bit patterns */
    for (size_t i = 0; i < k; i++) {
        float ax = lx[i] - qx, bx = qx - hx[i], ay = ly[i] - qy, by = qy - hy[i];
        float az = lz[i] - qz, bz = qz - hz[i];
        float dx = ax > bx ? ax : bx, dy = ay > by ? ay : by, dz = az > bz ? az : bz;
        dx = dx > 0.0f ? dx : 0.0f;
        dy = dy > 0.0f ? dy : 0.0f;
        dz = dz > 0.0f ? dz : 0.0f;
        float d = dx * dx + dy * dy + dz * dz;
        out[i] = d;
        uint32_t u;
        memcpy(&u, &d, sizeof u);
        least = u < least ? u : least;
    }
    for (size_t i = 0; i < k; i++) {
        uint32_t u;
        memcpy(&u, &out[i], sizeof u);
        if (u == least) return i;
    }
    return 0;
}

/* Block b against query q: improves *best / *idx (ties: the smaller vertex index). */
static inline void scan_block(const csrbf_points *p, size_t b, const float q[3], float *best,
                              uint32_t *idx)
{
    size_t k0 = b * CSRBF_BLOCK, nv = k0 + CSRBF_BLOCK <= p->n ? CSRBF_BLOCK : p->n - k0;
    const float *x = p->s[0] + k0, *y = p->s[1] + k0, *z = p->s[2] + k0;
    float d2[CSRBF_BLOCK], least = INFINITY;
    for (size_t l = 0; l < CSRBF_BLOCK; l++) { /* vectorised: 16 lanes (padding: copies) */
        float dx = x[l] - q[0], dy = y[l] - q[1], dz = z[l] - q[2];
        d2[l] = dx * dx + dy * dy + dz * dz;
        least = d2[l] < least ? d2[l] : least;
    }
    if (least > *best) return;
    for (size_t l = 0; l < nv; l++)
        if (d2[l] < *best || (d2[l] == *best && (uint32_t)(k0 + l) < *idx)) {
            *best = d2[l];
            *idx = (uint32_t)(k0 + l);
        }
}

/* Superblock sb against query q: its nearest block first, then every block whose box may
 * hold a vertex as near as *best and within lim. */
static void scan_super(const csrbf_points *p, size_t sb, const float q[3], float lim, float *best,
                       uint32_t *idx)
{
    float bd[CSRBF_SUPER];
    size_t b0 = sb * CSRBF_SUPER, b1 = b0 + CSRBF_SUPER < p->nblocks ? b0 + CSRBF_SUPER : p->nblocks;
    size_t first = boxes_d2((const float *const *)p->lo, (const float *const *)p->hi, b0, b1, q, bd);
    if (bd[first] > lim || bd[first] > *best) return;
    scan_block(p, b0 + first, q, best, idx);
    for (size_t i = 0; i < b1 - b0; i++)
        if (i != first && bd[i] <= *best && bd[i] <= lim) scan_block(p, b0 + i, q, best, idx);
}

int csrbf_points_nearest(const csrbf_points *p, const float *queries, size_t nq, float max_dist,
                         float *out_dist, uint32_t *out_index)
{
    if (!p || (nq && (!queries || !out_dist)) || isnan(max_dist) || max_dist < 0)
        return CSRBF_ERR_INVALID;
    for (size_t i = 0; i < nq; i++)
        for (int a = 0; a < 3; a++)
            if (!isfinite(queries[3 * i + a])) return CSRBF_ERR_INVALID;
    enum { SCHUNK = 1024 }; /* superblock distances per pass (on the stack) */
    /* the pruning bound on squared distances: above every d2 whose sqrtf is <= max_dist
     * (a relative margin of 1e-6, far beyond float rounding); +inf stays +inf */
    const double md = (double)max_dist * (1.0 + 1e-6);
    const float lim = (float)(md * md);
    float sd[SCHUNK];
    for (size_t i = 0; i < nq; i++) {
        const float *q = queries + 3 * i;
        float best = INFINITY;
        uint32_t idx = UINT32_MAX;
        /* per chunk of superblocks: the nearest first (a good first candidate), then those
         * whose boxes may still hold a nearer vertex */
        for (size_t c0 = 0; c0 < p->nsuper; c0 += SCHUNK) {
            size_t c1 = c0 + SCHUNK < p->nsuper ? c0 + SCHUNK : p->nsuper;
            size_t first = boxes_d2((const float *const *)p->slo, (const float *const *)p->shi, c0,
                                    c1, q, sd);
            if (sd[first] > lim || sd[first] > best) continue;
            scan_super(p, c0 + first, q, lim, &best, &idx);
            for (size_t k = 0; k < c1 - c0; k++)
                if (k != first && sd[k] <= best && sd[k] <= lim) scan_super(p, c0 + k, q, lim, &best, &idx);
        }
        float d = idx != UINT32_MAX ? sqrtf(best) : INFINITY;
        int hit = d <= max_dist;
        out_dist[i] = hit ? d : INFINITY;
        if (out_index) out_index[i] = hit ? idx : UINT32_MAX;
    }
    return CSRBF_OK;
}
