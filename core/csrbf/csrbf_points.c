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

static void fill_blocks(csrbf_points *p)
{
    for (int a = 0; a < 3; a++) {
        p->blo[a] = INFINITY;
        p->bhi[a] = -INFINITY;
    }
    fill_block_range(p, 0, p->nblocks);
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
    for (int a = 0; a < 3 && ok; a++) {
        p->s[a] = alloc64(padded * sizeof(float));
        p->lo[a] = alloc64(p->nblocks * sizeof(float));
        p->hi[a] = alloc64(p->nblocks * sizeof(float));
        ok = p->s[a] && p->lo[a] && p->hi[a];
    }
    if (!ok) {
        csrbf_points_destroy(&p);
        return CSRBF_ERR_NOMEM;
    }
    memcpy(p->xyz, xyz, n * 3 * sizeof(float));
    fill_blocks(p);
    *out = p;
    return CSRBF_OK;
}

int csrbf_points_update(csrbf_points *p, const float *xyz)
{
    if (!p || !xyz || check(p->n, xyz)) return CSRBF_ERR_INVALID;
    memcpy(p->xyz, xyz, p->n * 3 * sizeof(float));
    fill_blocks(p);
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
    }
    return CSRBF_OK;
}

size_t csrbf_points_count(const csrbf_points *p) { return p ? p->n : 0; }
