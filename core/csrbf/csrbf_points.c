/* csrbf_points: the base vertices as structure-of-arrays blocks of CSRBF_BLOCK consecutive
 * vertices with bounding boxes, so that csrbf_evaluate skips blocks outside every support
 * and still writes its output contiguously. Locality comes from the mesh's own vertex order
 * (scanned and modelled meshes, grids: consecutive vertices are neighbours); a scrambled
 * order stays correct but gains nothing from the boxes. The nearest-vertex queries can have
 * blocks of their own in Morton order (csrbf_points_index_nearest), compact whatever the
 * mesh's order: they write nothing contiguous, so their places need not be the vertices'. */
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

/* Recompute block b from p->xyz; the global box grows to hold it (it never shrinks here,
 * which only makes csrbf_evaluate's whole-box test more conservative). x: p's nearest index
 * (or NULL; a constant in each caller's loop, so the inlined copies differ): the block's
 * vertices whose position changed (bitwise: their old positions are still in s) go to their
 * places there, their blocks to refit (near_refit_dirty, by the caller). rec (or NULL, with
 * x NULL): those vertices appended there instead (room for CSRBF_BLOCK), for the index to
 * take later; returns how many. */
static inline __attribute__((always_inline)) size_t fill_block(csrbf_points *p, size_t b, struct csrbf_near *x,
                                                               uint32_t *rec)
{
    size_t n = p->n, k0 = b * CSRBF_BLOCK, k1 = k0 + CSRBF_BLOCK < n ? k0 + CSRBF_BLOCK : n;
    uint32_t moved = 0; /* by bit */
    for (int a = 0; a < 3; a++) {
        float lo = INFINITY, hi = -INFINITY;
        for (size_t k = k0; k < k1; k++) {
            float v = p->xyz[3 * k + a];
            if (x || rec) {
                uint32_t u, o;
                memcpy(&u, &v, sizeof u);
                memcpy(&o, &p->s[a][k], sizeof o);
                moved |= (uint32_t)(u != o) << (k - k0);
            }
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
    for (; x && moved; moved &= moved - 1) {
        size_t k = k0 + (size_t)__builtin_ctz(moved);
        uint32_t q = x->place[k];
        for (int a = 0; a < 3; a++) x->s[a][q] = p->s[a][k];
        x->dirty[0][q / CSRBF_BLOCK] = 1;
    }
    size_t nrec = 0;
    for (; rec && moved; moved &= moved - 1) rec[nrec++] = (uint32_t)(k0 + (size_t)__builtin_ctz(moved));
    return nrec;
}

/* Recompute blocks b0..b1 (fill_block) */
static void fill_block_range(csrbf_points *p, size_t b0, size_t b1)
{
    if (p->near)
        for (size_t b = b0; b < b1; b++) fill_block(p, b, p->near, NULL);
    else
        for (size_t b = b0; b < b1; b++) fill_block(p, b, NULL, NULL);
}

/* csrbf_points_index_nearest's index (below) */
static void near_free(struct csrbf_near *x);
static void near_fill(struct csrbf_near *x, size_t n, const float *xyz);
static void near_refit_dirty(struct csrbf_near *x, size_t n);

static size_t pad_fan(size_t n) { return (n + CSRBF_FAN - 1) / CSRBF_FAN * CSRBF_FAN; }

/* The block tree's node i at level l >= 1 from its children (exact: a node's box is the
 * union of its children's, padding boxes being empty) */
static void fill_tree_node(csrbf_points *p, int l, size_t i)
{
    for (int a = 0; a < 3; a++) {
        const float *clo = p->tlo[l - 1][a], *chi = p->thi[l - 1][a];
        float lo = INFINITY, hi = -INFINITY;
        for (size_t k = CSRBF_FAN * i; k < CSRBF_FAN * i + CSRBF_FAN; k++) {
            lo = clo[k] < lo ? clo[k] : lo;
            hi = chi[k] > hi ? chi[k] : hi;
        }
        p->tlo[l][a][i] = lo;
        p->thi[l][a][i] = hi;
    }
}

/* The block tree's nodes above the blocks of vertex ranges ((first, count) pairs), level by
 * level, a node shared by consecutive ranges refit once (ranges in any order give the same
 * boxes: each node is refit after its children). A range's own walk to the top cost a commit
 * of the 1.7M-vertex face's few thousand ranges of 16 vertices a fifth of a millisecond. */
static void fill_tree_ranges(csrbf_points *p, const uint32_t *ranges, size_t nranges)
{
    size_t div = 1;
    for (int l = 1; l < p->tlevels; l++) {
        div *= CSRBF_FAN;
        size_t last = SIZE_MAX; /* the last node refit at this level */
        for (size_t r = 0; r < nranges; r++) {
            size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
            if (!c) continue;
            size_t i0 = v0 / CSRBF_BLOCK / div, i1 = (v0 + c - 1) / CSRBF_BLOCK / div;
            for (size_t i = i0; i <= i1; i++) {
                if (i == last) continue; /* (every level below is refit: the same again) */
                last = i;
                fill_tree_node(p, l, i);
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
    const uint32_t all[2] = {0, (uint32_t)p->n}; /* (n < UINT32_MAX: csrbf_points_create) */
    fill_tree_ranges(p, all, 1);
}

void csrbf_points_destroy(csrbf_points **pp)
{
    if (!pp || !*pp) return;
    csrbf_points *p = *pp;
    free(p->xyz);
    free(p->pend);
    near_free(p->near);
    for (int a = 0; a < 3; a++) {
        free(p->s[a]);
        free(p->lo[a]);
        free(p->hi[a]);
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
        ok = ok && p->s[a] && p->lo[a] && p->hi[a];
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

/* The pending vertices' positions (p->xyz) into the nearest index, its boxes refit. */
static void near_take_pending(csrbf_points *p)
{
    struct csrbf_near *x = p->near;
    for (size_t i = 0; x && i < p->npend; i++) {
        uint32_t k = p->pend[i], q = x->place[k];
        for (int a = 0; a < 3; a++) x->s[a][q] = p->xyz[3 * (size_t)k + a];
        x->dirty[0][q / CSRBF_BLOCK] = 1;
    }
    if (x && p->npend) near_refit_dirty(x, p->n);
    p->npend = 0;
}

void csrbf_points_sync_nearest(csrbf_points *p)
{
    if (p) near_take_pending(p);
}

int csrbf_points_update(csrbf_points *p, const float *xyz)
{
    if (!p || !xyz || check(p->n, xyz)) return CSRBF_ERR_INVALID;
    near_take_pending(p); /* (the index learns what moved by comparing with the blocks) */
    memcpy(p->xyz, xyz, p->n * 3 * sizeof(float));
    fill_blocks(p);
    if (p->near) near_refit_dirty(p->near, p->n);
    p->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

/* csrbf_points_update_ranges and _later: later, the index's part is left to
 * near_take_pending (the vertices that moved kept in p->pend), else done now. */
static int update_ranges(csrbf_points *p, const float *xyz, const uint32_t *ranges, size_t nranges,
                         int later)
{
    if (!p || !xyz || (!ranges && nranges)) return CSRBF_ERR_INVALID;
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        if (v0 > p->n || c > p->n - v0 || check(c, xyz + 3 * v0)) return CSRBF_ERR_INVALID;
    }
    near_take_pending(p); /* one update pending at most */
    size_t room = 0; /* the most vertices a later update may leave pending: its blocks' */
    for (size_t r = 0; later && r < nranges; r++)
        if (ranges[2 * r + 1])
            room += ((ranges[2 * r] + (size_t)ranges[2 * r + 1] + CSRBF_BLOCK - 1) / CSRBF_BLOCK -
                     ranges[2 * r] / CSRBF_BLOCK) * CSRBF_BLOCK;
    if (later && p->near && room > p->pend_cap) {
        uint32_t *q = realloc(p->pend, room * sizeof *q);
        if (q) {
            p->pend = q;
            p->pend_cap = room;
        }
    }
    later = later && p->near && room <= p->pend_cap; /* (out of memory: now) */
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        if (!c) continue;
        memcpy(p->xyz + 3 * v0, xyz + 3 * v0, c * 3 * sizeof(float));
        size_t b0 = v0 / CSRBF_BLOCK, b1 = (v0 + c + CSRBF_BLOCK - 1) / CSRBF_BLOCK;
        if (later) /* (a block two ranges share: its vertices moved once, recorded once) */
            for (size_t b = b0; b < b1; b++) p->npend += fill_block(p, b, NULL, p->pend + p->npend);
        else
            fill_block_range(p, b0, b1);
    }
    fill_tree_ranges(p, ranges, nranges);
    if (!later && p->near) near_refit_dirty(p->near, p->n);
    p->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

int csrbf_points_update_ranges(csrbf_points *p, const float *xyz, const uint32_t *ranges,
                               size_t nranges)
{
    return update_ranges(p, xyz, ranges, nranges, 0);
}

int csrbf_points_update_ranges_later(csrbf_points *p, const float *xyz, const uint32_t *ranges,
                                     size_t nranges)
{
    return update_ranges(p, xyz, ranges, nranges, 1);
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
        for (int l = 1; l < src->tlevels; l++) {
            memcpy(dst->tlo[l][a], src->tlo[l][a], pad_fan(src->tcount[l]) * sizeof(float));
            memcpy(dst->thi[l][a], src->thi[l][a], pad_fan(src->tcount[l]) * sizeof(float));
        }
        dst->blo[a] = src->blo[a];
        dst->bhi[a] = src->bhi[a];
    }
    if (dst->near) near_fill(dst->near, dst->n, dst->xyz);
    dst->npend = 0; /* (the index was made from every position) */
    dst->stamp = csrbf_new_stamp();
    return CSRBF_OK;
}

/* SIMD clones of the box pass (AVX-512, AVX2, baseline), as csrbf_general.c's kernels. No
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

/* What csrbf_points_nearest walks: a box tree over blocks of CSRBF_BLOCK places (csrbf_points'
 * own, places = vertices, or its index's, places in Morton order) and the places' coordinates
 * and vertices (vert NULL: the place is the vertex). Places n and beyond are padding. */
typedef struct near_view {
    const size_t *count;
    float *const (*lo)[3], *const (*hi)[3];
    float *const *s;
    const uint32_t *vert;
    size_t n;
} near_view;

/* Block b against query q: improves *best / *idx (ties: the smaller vertex index). */
static inline void scan_block(const near_view *v, size_t b, const float q[3], float *best, uint32_t *idx)
{
    size_t k0 = b * CSRBF_BLOCK, nv = k0 + CSRBF_BLOCK <= v->n ? CSRBF_BLOCK : v->n - k0;
    const float *x = v->s[0] + k0, *y = v->s[1] + k0, *z = v->s[2] + k0;
    float d2[CSRBF_BLOCK], least = INFINITY;
    for (size_t l = 0; l < CSRBF_BLOCK; l++) { /* vectorised: 16 lanes (padding: copies) */
        float dx = x[l] - q[0], dy = y[l] - q[1], dz = z[l] - q[2];
        d2[l] = dx * dx + dy * dy + dz * dz;
        least = d2[l] < least ? d2[l] : least;
    }
    if (least > *best) return;
    for (size_t l = 0; l < nv; l++) {
        uint32_t id = v->vert ? v->vert[k0 + l] : (uint32_t)(k0 + l);
        if (d2[l] < *best || (d2[l] == *best && id < *idx)) {
            *best = d2[l];
            *idx = id;
        }
    }
}

/* The group of nodes g .. g + CSRBF_FAN - 1 of level l (blocks when l == 0) against query q:
 * the nearest box first, then, in order, every one that may hold a vertex as near as *best
 * and within lim; a node's children are the group CSRBF_FAN times its index on the level
 * below. Padding nodes (empty boxes, +inf) and those beyond the level's count are never
 * opened. Recursion depth: the tree's levels (at most CSRBF_TREE_MAX). */
static void visit_group(const near_view *v, int l, size_t g, const float q[3], float lim, float *best,
                        uint32_t *idx)
{
    float d2[CSRBF_FAN];
    size_t first = boxes_d2((const float *const *)v->lo[l], (const float *const *)v->hi[l], g, g + CSRBF_FAN,
                            q, d2);
    size_t end = v->count[l] - g < CSRBF_FAN ? v->count[l] - g : CSRBF_FAN;
    for (size_t k = 0; k < end; k++) {
        size_t c = k == 0 ? first : k == first ? 0 : k; /* the nearest first, then the others */
        if (d2[c] > lim || d2[c] > *best) continue;
        if (l == 0) scan_block(v, g + c, q, best, idx);
        else visit_group(v, l - 1, CSRBF_FAN * (g + c), q, lim, best, idx);
    }
}

int csrbf_points_nearest(const csrbf_points *p, const float *queries, size_t nq, float max_dist,
                         float *out_dist, uint32_t *out_index)
{
    if (!p || (nq && (!queries || !out_dist)) || isnan(max_dist) || max_dist < 0)
        return CSRBF_ERR_INVALID;
    for (size_t i = 0; i < nq; i++)
        for (int a = 0; a < 3; a++)
            if (!isfinite(queries[3 * i + a])) return CSRBF_ERR_INVALID;
    /* the pruning bound on squared distances: above every d2 whose sqrtf is <= max_dist
     * (a relative margin of 1e-6, far beyond float rounding); +inf stays +inf */
    const double md = (double)max_dist * (1.0 + 1e-6);
    const float lim = (float)(md * md);
    /* an index that has not taken the last update yet: the own blocks (the same answers) */
    const struct csrbf_near *x = p->npend ? NULL : p->near;
    near_view v = x ? (near_view){x->count, x->lo, x->hi, x->s, x->vert, p->n}
                    : (near_view){p->tcount, p->tlo, p->thi, p->s, NULL, p->n};
    int top = (x ? x->levels : p->tlevels) - 1;
    for (size_t i = 0; i < nq; i++) {
        const float *q = queries + 3 * i;
        float best = INFINITY;
        uint32_t idx = UINT32_MAX;
        visit_group(&v, top, 0, q, lim, &best, &idx);
        float d = idx != UINT32_MAX ? sqrtf(best) : INFINITY;
        int hit = d <= max_dist;
        out_dist[i] = hit ? d : INFINITY;
        if (out_index) out_index[i] = hit ? idx : UINT32_MAX;
    }
    return CSRBF_OK;
}

/* ---- csrbf_points_index_nearest: blocks in Morton order ---- */

static void near_free(struct csrbf_near *x)
{
    if (!x) return;
    free(x->vert);
    free(x->place);
    for (int a = 0; a < 3; a++) {
        free(x->s[a]);
        for (int l = 0; l < x->levels; l++) {
            free(x->lo[l][a]);
            free(x->hi[l][a]);
        }
    }
    for (int l = 0; l < x->levels; l++) free(x->dirty[l]);
    free(x);
}

/* Node i of level l refit: a block's box from its places (the last block's padding copied
 * from its first place first), a node's from its children's. */
static void near_refit_node(struct csrbf_near *x, size_t n, int l, size_t i)
{
    for (int a = 0; a < 3; a++) {
        float lo = INFINITY, hi = -INFINITY;
        if (l == 0) {
            float *c = x->s[a] + i * CSRBF_BLOCK;
            for (size_t k = n > i * CSRBF_BLOCK ? n - i * CSRBF_BLOCK : 0; k < CSRBF_BLOCK; k++) c[k] = c[0];
            for (size_t k = 0; k < CSRBF_BLOCK; k++) {
                lo = c[k] < lo ? c[k] : lo;
                hi = c[k] > hi ? c[k] : hi;
            }
        } else {
            const float *clo = x->lo[l - 1][a] + CSRBF_FAN * i, *chi = x->hi[l - 1][a] + CSRBF_FAN * i;
            for (size_t k = 0; k < CSRBF_FAN; k++) {
                lo = clo[k] < lo ? clo[k] : lo;
                hi = chi[k] > hi ? chi[k] : hi;
            }
        }
        x->lo[l][a][i] = lo;
        x->hi[l][a][i] = hi;
    }
}

/* Every place's coordinates from xyz (n x 3) and every box */
static void near_fill(struct csrbf_near *x, size_t n, const float *xyz)
{
    for (size_t k = 0; k < n; k++)
        for (int a = 0; a < 3; a++) x->s[a][k] = xyz[3 * (size_t)x->vert[k] + a];
    for (int l = 0; l < x->levels; l++)
        for (size_t i = 0; i < x->count[l]; i++) near_refit_node(x, n, l, i);
}

/* The dirty nodes refit, level by level (a refit node marks its parent) */
static void near_refit_dirty(struct csrbf_near *x, size_t n)
{
    for (int l = 0; l < x->levels; l++) {
        uint8_t *d = x->dirty[l];
        for (size_t i = 0; i < x->count[l]; i++) {
            uint64_t w;
            if (i % 8 == 0 && i + 8 <= x->count[l] && (memcpy(&w, d + i, 8), w == 0)) {
                i += 7;
                continue;
            }
            if (!d[i]) continue;
            d[i] = 0;
            near_refit_node(x, n, l, i);
            if (l + 1 < x->levels) x->dirty[l + 1][i / CSRBF_FAN] = 1;
        }
    }
}

/* x's bits spread to every third place (21 bits) */
static uint64_t spread3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

typedef struct { uint64_t key; uint32_t v; } morton_item;

static int morton_cmp(const void *a, const void *b)
{
    const morton_item *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->v < y->v ? -1 : x->v > y->v;
}

int csrbf_points_index_nearest(csrbf_points *p)
{
    if (!p) return CSRBF_ERR_INVALID;
    if (p->near) {
        near_take_pending(p);
        return CSRBF_OK;
    }
    size_t n = p->n, nb = (n + CSRBF_BLOCK - 1) / CSRBF_BLOCK, np = nb * CSRBF_BLOCK;
    struct csrbf_near *x = calloc(1, sizeof *x);
    morton_item *it = malloc(n * sizeof *it);
    if (!x || !it) {
        free(x);
        free(it);
        return CSRBF_ERR_NOMEM;
    }
    x->nblocks = nb;
    x->count[0] = nb;
    x->levels = 1;
    while (x->count[x->levels - 1] > CSRBF_FAN) {
        x->count[x->levels] = (x->count[x->levels - 1] + CSRBF_FAN - 1) / CSRBF_FAN;
        x->levels++;
    }
    int ok = (x->vert = malloc(np * sizeof *x->vert)) && (x->place = malloc(n * sizeof *x->place));
    for (int a = 0; a < 3 && ok; a++) ok = (x->s[a] = alloc64(np * sizeof(float))) != NULL;
    for (int l = 0; l < x->levels && ok; l++) {
        size_t m = pad_fan(x->count[l]);
        ok = (x->dirty[l] = calloc(m, 1)) != NULL;
        for (int a = 0; a < 3 && ok; a++) {
            ok = (x->lo[l][a] = alloc64(m * sizeof(float))) && (x->hi[l][a] = alloc64(m * sizeof(float)));
            for (size_t i = x->count[l]; ok && i < m; i++) { /* padding: empty boxes */
                x->lo[l][a][i] = INFINITY;
                x->hi[l][a][i] = -INFINITY;
            }
        }
    }
    if (!ok) {
        near_free(x);
        free(it);
        return CSRBF_ERR_NOMEM;
    }
    /* the places: vertices by the Morton code of their position in the set's box (21 bits an
     * axis), ties by index */
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = p->xyz[3 * v + a] < lo[a] ? p->xyz[3 * v + a] : lo[a];
            hi[a] = p->xyz[3 * v + a] > hi[a] ? p->xyz[3 * v + a] : hi[a];
        }
    double ext = 0;
    for (int a = 0; a < 3; a++) ext = (double)hi[a] - lo[a] > ext ? (double)hi[a] - lo[a] : ext;
    double sc = ext > 0 ? 2097151.0 / ext : 0;
    for (size_t v = 0; v < n; v++) {
        uint64_t key = 0;
        for (int a = 0; a < 3; a++) {
            double q = ((double)p->xyz[3 * v + a] - lo[a]) * sc;
            key |= spread3((uint64_t)(q < 0 ? 0 : q > 2097151.0 ? 2097151.0 : q)) << a;
        }
        it[v] = (morton_item){key, (uint32_t)v};
    }
    qsort(it, n, sizeof *it, morton_cmp);
    for (size_t k = 0; k < np; k++) x->vert[k] = it[k < n ? k : (nb - 1) * CSRBF_BLOCK].v;
    for (size_t k = 0; k < n; k++) x->place[x->vert[k]] = (uint32_t)k;
    free(it);
    near_fill(x, n, p->xyz);
    p->near = x;
    return CSRBF_OK;
}
