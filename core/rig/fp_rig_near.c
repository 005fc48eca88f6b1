/* fp_rig_near: each soft vertex's nearest rigid (skull or jaw) vertex within the mobility ramp,
 * for fp_rig_bind's mobility (fp_rig_internal.h, fpr_nearest_rigid). A k-d tree over the rigid
 * vertices, so that the cost grows as n log n with the mesh's density: the grid of ramp-sized
 * cells it replaces scanned every rigid vertex of 27 cells for each soft one, 47 s of the
 * 1.7M-vertex face's bind (ICT subdivided three times, its rig carried), where its rigid
 * vertices are 64 times as dense as on the ICT face. */
#include "fp_rig_internal.h"

#include "fp_select.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>

#define NEAR_LEAF 8

typedef struct knode {
    float lo[3], hi[3];   /* its points' box */
    uint32_t first, count; /* its points: ix[first .. first + count) */
    uint32_t left, right;  /* children (0: a leaf; node 0 is the root) */
} knode;

typedef struct tree {
    knode *node;
    size_t len;
    uint32_t *ix;
    const float *pos;
} tree;

static uint32_t build(tree *t, uint32_t first, uint32_t n)
{
    uint32_t x = (uint32_t)t->len++;
    knode *d = &t->node[x];
    for (int a = 0; a < 3; a++) d->lo[a] = INFINITY, d->hi[a] = -INFINITY;
    for (uint32_t i = first; i < first + n; i++)
        for (int a = 0; a < 3; a++) {
            float q = t->pos[3 * (size_t)t->ix[i] + a];
            d->lo[a] = fminf(d->lo[a], q);
            d->hi[a] = fmaxf(d->hi[a], q);
        }
    d->first = first;
    d->count = n;
    d->left = d->right = 0;
    if (n <= NEAR_LEAF) return x;
    int ax = 0;
    for (int a = 1; a < 3; a++)
        if (d->hi[a] - d->lo[a] > d->hi[ax] - d->lo[ax]) ax = a;
    fp_select_mid(t->ix, first, first + n, first + n / 2, ax, t->pos);
    uint32_t l = build(t, first, n / 2), r = build(t, first + n / 2, n - n / 2);
    t->node[x].left = l;
    t->node[x].right = r;
    return x;
}

/* A lower bound on the squared distance (as fp_rig_bind computes it: float differences,
 * squared and summed in double) from vertex v to any point of node d: rounding is monotone,
 * so each axis's float difference is at least the box's */
static double lb2(const knode *d, const float *p)
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        float e = p[a] < d->lo[a] ? d->lo[a] - p[a] : p[a] > d->hi[a] ? p[a] - d->hi[a] : 0.0f;
        s += (double)e * e;
    }
    return s;
}

typedef struct query {
    const float *p;
    size_t v;
    double best;    /* squared distance */
    uint64_t bkey;  /* the best's key */
    uint32_t bu;
} query;

static void search(const tree *t, const uint64_t *key, uint32_t x, query *q)
{
    const knode *d = &t->node[x];
    if (lb2(d, q->p) > q->best) return; /* (equal: a tie may lie there) */
    if (!d->left) {
        const float *pos = t->pos;
        size_t v = q->v;
        for (uint32_t i = d->first; i < d->first + d->count; i++) {
            size_t u = t->ix[i];
            /* the distance exactly as fp_rig_bind's grid computed it */
            double d0 = pos[3 * u] - pos[3 * v], d1 = pos[3 * u + 1] - pos[3 * v + 1],
                   d2 = pos[3 * u + 2] - pos[3 * v + 2];
            double e = d0 * d0 + d1 * d1 + d2 * d2;
            if (e < q->best || (e == q->best && key[u] < q->bkey)) q->best = e, q->bkey = key[u], q->bu = (uint32_t)u;
        }
        return;
    }
    /* the nearer child first */
    uint32_t a = d->left, b = d->right;
    if (lb2(&t->node[b], q->p) < lb2(&t->node[a], q->p)) a = d->right, b = d->left;
    search(t, key, a, q);
    search(t, key, b, q);
}

int fpr_nearest_rigid(const uint8_t *kind, size_t n, const float *pos, const uint64_t *key, double reach2,
                      uint32_t *bu, double *best)
{
    size_t nr = 0;
    for (size_t v = 0; v < n; v++) nr += kind[v] != FP_RIG_SOFT;
    tree t = {.pos = pos};
    t.ix = malloc(nr * sizeof *t.ix + 1);
    t.node = malloc((2 * (nr / (NEAR_LEAF / 2) + 1) + 1) * sizeof *t.node);
    if (!t.ix || !t.node) {
        free(t.ix), free(t.node);
        return -ENOMEM;
    }
    nr = 0;
    for (size_t v = 0; v < n; v++)
        if (kind[v] != FP_RIG_SOFT) t.ix[nr++] = (uint32_t)v;
    if (nr) build(&t, 0, (uint32_t)nr);
    for (size_t v = 0; v < n; v++) {
        best[v] = INFINITY;
        bu[v] = (uint32_t)v;
        if (kind[v] != FP_RIG_SOFT || !nr) continue;
        query q = {.p = pos + 3 * v, .v = v, .best = reach2, .bkey = UINT64_MAX, .bu = UINT32_MAX};
        search(&t, key, 0, &q);
        if (q.bu != UINT32_MAX) best[v] = q.best, bu[v] = q.bu;
    }
    free(t.ix), free(t.node);
    return 0;
}
