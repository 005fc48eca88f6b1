/* csrbf_points: the base vertices, sorted along a Morton curve into blocks of CSRBF_BLOCK
 * with bounding boxes, so that csrbf_evaluate visits only blocks that meet a support. */
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

static uint64_t spread21(uint64_t v)
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

typedef struct { uint64_t key; uint32_t idx; } keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->idx > y->idx) - (x->idx < y->idx);
}

static void fill_sorted(csrbf_points *p)
{
    size_t n = p->n, nb = p->nblocks;
    for (int a = 0; a < 3; a++) {
        p->blo[a] = INFINITY;
        p->bhi[a] = -INFINITY;
    }
    for (size_t b = 0; b < nb; b++) {
        size_t k0 = b * CSRBF_BLOCK, k1 = k0 + CSRBF_BLOCK < n ? k0 + CSRBF_BLOCK : n;
        for (int a = 0; a < 3; a++) {
            float lo = INFINITY, hi = -INFINITY;
            for (size_t k = k0; k < k1; k++) {
                float v = p->xyz[3 * (size_t)p->perm[k] + a];
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

void csrbf_points_destroy(csrbf_points **pp)
{
    if (!pp || !*pp) return;
    csrbf_points *p = *pp;
    free(p->xyz);
    free(p->perm);
    for (int a = 0; a < 3; a++) {
        free(p->s[a]);
        free(p->lo[a]);
        free(p->hi[a]);
    }
    free(p);
    *pp = NULL;
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
    p->perm = malloc(n * sizeof *p->perm);
    keyed *keys = malloc(n * sizeof *keys);
    int ok = p->xyz && p->perm && keys;
    for (int a = 0; a < 3 && ok; a++) {
        p->s[a] = malloc(padded * sizeof(float));
        p->lo[a] = malloc(p->nblocks * sizeof(float));
        p->hi[a] = malloc(p->nblocks * sizeof(float));
        ok = p->s[a] && p->lo[a] && p->hi[a];
    }
    if (!ok) {
        free(keys);
        csrbf_points_destroy(&p);
        return CSRBF_ERR_NOMEM;
    }
    memcpy(p->xyz, xyz, n * 3 * sizeof(float));
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], xyz[3 * i + a]);
            hi[a] = fmax(hi[a], xyz[3 * i + a]);
        }
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    double scale = ext > 0.0 ? 2097151.0 / ext : 0.0; /* cubic cells: 21 bits on the widest axis */
    for (size_t i = 0; i < n; i++) {
        uint64_t key = 0;
        for (int a = 0; a < 3; a++)
            key |= spread21((uint64_t)((xyz[3 * i + a] - lo[a]) * scale)) << a;
        keys[i].key = key;
        keys[i].idx = (uint32_t)i;
    }
    qsort(keys, n, sizeof *keys, cmp_keyed);
    for (size_t i = 0; i < n; i++) p->perm[i] = keys[i].idx;
    free(keys);
    fill_sorted(p);
    *out = p;
    return CSRBF_OK;
}

int csrbf_points_update(csrbf_points *p, const float *xyz)
{
    if (!p || !xyz || check(p->n, xyz)) return CSRBF_ERR_INVALID;
    memcpy(p->xyz, xyz, p->n * 3 * sizeof(float));
    fill_sorted(p);
    return CSRBF_OK;
}

size_t csrbf_points_count(const csrbf_points *p) { return p ? p->n : 0; }
