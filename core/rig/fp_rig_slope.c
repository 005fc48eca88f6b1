/* fp_rig_slope: the finger limit of a bound rig (fp_rig.h): by brute force, and through the
 * index of slope vertices in blocks (with a tree of the blocks' boxes), and the directional
 * clamp of a control vector that the session applies. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

double fp_rig_finger_limit(const fp_rig *r, const float *posed, const float start[3], double radius)
{
    if (!r || !posed || !start || !r->g || !(radius > 0)) return r && r->g ? r->geom.ramp / 3 : 0;
    double gmax = 0, r2 = radius * radius;
    for (size_t k = 0; k < r->slope_count; k++) {
        uint32_t v = r->slope_v[k];
        if (r->g[v] <= gmax) continue;
        double d0 = posed[3 * v] - start[0], d1 = posed[3 * v + 1] - start[1], d2 = posed[3 * v + 2] - start[2];
        if (d0 * d0 + d1 * d1 + d2 * d2 < r2) gmax = r->g[v];
    }
    return gmax > 0 ? FP_RIG_FINGER_MARGIN / gmax : INFINITY;
}

/* The squared distance from p to the segment a -> a + d (dd = |d|^2). */
static double seg_dist2(const float p[3], const float a[3], const double d[3], double dd)
{
    double w[3] = {(double)p[0] - a[0], (double)p[1] - a[1], (double)p[2] - a[2]};
    double t = dd > 0 ? (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double q = 0;
    for (int i = 0; i < 3; i++) q += (w[i] - t * d[i]) * (w[i] - t * d[i]);
    return q;
}

/* Wendland's psi_{3,1} (csrbf.md): the share of a centre's displacement at distance r R. */
static double wendland(double r)
{
    double a = 1 - r;
    return r < 1 ? a * a * a * a * (4 * r + 1) : 0;
}

/* One slope vertex's push: its slope times the share of the unit direction u against its
 * grad m (toward the rigid vertex), 0 when u pulls away or runs along. */
static double push_of(float g, const float *dir, const double u[3])
{
    double c = -(dir[0] * u[0] + dir[1] * u[1] + dir[2] * u[2]);
    return c > 0 ? g * c : 0;
}

static void capsule_of(const float start[3], const float end[3], double d[3], double u[3], double *dd)
{
    *dd = 0;
    for (int i = 0; i < 3; i++) {
        d[i] = (double)end[i] - start[i];
        *dd += d[i] * d[i];
    }
    double len = sqrt(*dd);
    for (int i = 0; i < 3; i++) u[i] = len > 0 ? d[i] / len : 0;
}

double fp_rig_finger_limit_toward(const fp_rig *r, const float *posed, const float start[3], const float end[3],
                                  double radius)
{
    if (!r || !posed || !start || !end || !r->g || !(radius > 0)) return r && r->g ? r->geom.ramp / 3 : 0;
    double d[3], u[3], dd, cmax = 0, r2 = radius * radius;
    capsule_of(start, end, d, u, &dd);
    for (size_t k = 0; k < r->slope_count; k++) {
        uint32_t v = r->slope_v[k];
        double c = push_of(r->g[v], &r->slope_dir[3 * k], u);
        if (c <= cmax) continue;
        double q = seg_dist2(&posed[3 * v], start, d, dd);
        if (q < r2) cmax = fmax(cmax, c * wendland(sqrt(q) / radius));
    }
    return cmax > 0 ? FP_RIG_FINGER_MARGIN / cmax : INFINITY;
}

/* ---- the finger limit by blocks of slope vertices ------------------------------------- */

/* Slope vertices per block: until the first posed base is given, consecutive entries of
 * slope_v (ascending vertex index); from then on consecutive in the Morton order of that
 * base's positions, so that each block's box and directions' box are tight (a mesh's vertex
 * order need not keep neighbours close: on the ICT face a block's box spanned the jaw, and
 * the directional query scanned 100-170 of 255 blocks). */
#define SLOPE_BLOCK 32

/* The blocks' boxes in a tree (the capsule's search, tree_collect): level 0 the blocks in the
 * order laid out (neighbours in space once spatial), a node of level l the union of
 * SLOPE_FAN nodes below it; levels up to at most SLOPE_FAN nodes at the top. A query marks
 * its blocks in a bitmap of SLOPE_MARK_WORDS words on its stack (more blocks than that: every
 * block is scanned, as without the tree). */
#define SLOPE_FAN 8
#define SLOPE_LEVELS 12
#define SLOPE_MARK_WORDS 1024

typedef struct {
    float lo[3], hi[3];  /* box of the block's vertices in the posed base */
    float dlo[3], dhi[3]; /* box of their grad m directions (the rig's, fixed) */
    float gmax;          /* the block's largest slope (the rig's, fixed) */
    uint32_t count;      /* slope vertices in it (SLOPE_BLOCK but for one) */
} slope_block;

typedef struct {
    float g;
    uint32_t b;
} block_key;

typedef struct {
    uint32_t code; /* Morton code of the entry's position */
    uint32_t k;    /* the entry */
} spatial_key;

struct fp_rig_slope_index {
    const fp_rig *rig;
    size_t nb;           /* blocks */
    slope_block *block;  /* nb, steepest first */
    float *p;            /* nb x SLOPE_BLOCK x 4: each block's vertices (x, y, z of the posed
                            base, slope), block after block in that order */
    float *dir;          /* nb x SLOPE_BLOCK x 3: their grad m directions (slope_dir) */
    uint32_t *slot;      /* slope_count: where entry k of slope_v sits in p (block = slot /
                            SLOPE_BLOCK) */
    block_key *keys;     /* nb: layout's scratch */
    spatial_key *order;  /* slope_count: the entries in the order laid out (by position
                            once layout_spatial ran; code 0 and entry order before) */
    bool spatial;        /* the blocks hold entries close in the first posed base given
                            (fp_rig_slope_index_set), not in vertex order */
    uint32_t *pos;       /* nb: block b of the order laid out -> its place in block */
    uint32_t *seq;       /* nb: place -> b */
    int levels;          /* tree levels above the blocks (0: nb <= SLOPE_FAN) */
    size_t tcount[SLOPE_LEVELS + 1];  /* nodes a level; tcount[0] = nb */
    float (*tbox[SLOPE_LEVELS + 1])[6]; /* levels 1..levels: each node's box, lo then hi */
    uint8_t *tdirty[SLOPE_LEVELS + 1]; /* levels 1..levels: nodes to refit (a box below changed) */
    uint8_t *bdirty;     /* nb: a block whose box update_ranges recomputes (it is in bdlist) */
    uint32_t *bdlist;    /* nb: those blocks */
};

/* Node i of level l's box (level 0: block b = i's, at its place) */
static const float *node_lo(const fp_rig_slope_index *ix, int l, size_t i)
{
    return l ? ix->tbox[l][i] : ix->block[ix->pos[i]].lo;
}
static const float *node_hi(const fp_rig_slope_index *ix, int l, size_t i)
{
    return l ? ix->tbox[l][i] + 3 : ix->block[ix->pos[i]].hi;
}

/* Node i of level l >= 1 from its children (exact: the union of their boxes) */
static void tree_refit_node(fp_rig_slope_index *ix, int l, size_t i)
{
    float *bx = ix->tbox[l][i];
    for (int a = 0; a < 3; a++) bx[a] = INFINITY, bx[3 + a] = -INFINITY;
    size_t c1 = (i + 1) * SLOPE_FAN < ix->tcount[l - 1] ? (i + 1) * SLOPE_FAN : ix->tcount[l - 1];
    for (size_t c = i * SLOPE_FAN; c < c1; c++) {
        const float *lo = node_lo(ix, l - 1, c), *hi = node_hi(ix, l - 1, c);
        for (int a = 0; a < 3; a++) {
            bx[a] = lo[a] < bx[a] ? lo[a] : bx[a];
            bx[3 + a] = hi[a] > bx[3 + a] ? hi[a] : bx[3 + a];
        }
    }
}

/* The tree above the blocks refit: every node (all), or the nodes marked dirty (a level 1
 * node by slope_put, each refit node marking its parent) */
static void tree_refit(fp_rig_slope_index *ix, bool all)
{
    for (int l = 1; l <= ix->levels; l++) {
        uint8_t *d = ix->tdirty[l];
        for (size_t i = 0; i < ix->tcount[l]; i++) {
            uint64_t w;
            if (!all && i % 8 == 0 && i + 8 <= ix->tcount[l] && (memcpy(&w, d + i, 8), w == 0)) {
                i += 7;
                continue;
            }
            if (!all && !d[i]) continue;
            d[i] = 0;
            tree_refit_node(ix, l, i);
            if (l < ix->levels) ix->tdirty[l + 1][i / SLOPE_FAN] = 1;
        }
    }
}


static int by_gmax_desc(const void *a, const void *b)
{
    const block_key *x = a, *y = b;
    return x->g > y->g ? -1 : x->g < y->g ? 1 : (x->b > y->b) - (x->b < y->b);
}

/* Blocks of SLOPE_BLOCK entries in the order of ix->order, sorted steepest first: their
 * slopes, directions and directions' boxes (the positions' boxes are _set's). */
static void layout(fp_rig_slope_index *ix)
{
    const fp_rig *r = ix->rig;
    const spatial_key *ord = ix->order;
    block_key *keys = ix->keys;
    for (size_t b = 0; b < ix->nb; b++) {
        size_t k1 = (b + 1) * SLOPE_BLOCK < r->slope_count ? (b + 1) * SLOPE_BLOCK : r->slope_count;
        float g = 0;
        for (size_t j = b * SLOPE_BLOCK; j < k1; j++) g = fmaxf(g, r->g[r->slope_v[ord[j].k]]);
        keys[b] = (block_key){g, (uint32_t)b};
    }
    qsort(keys, ix->nb, sizeof *keys, by_gmax_desc);
    for (size_t o = 0; o < ix->nb; o++) {
        size_t b = keys[o].b, k0 = b * SLOPE_BLOCK;
        size_t k1 = k0 + SLOPE_BLOCK < r->slope_count ? k0 + SLOPE_BLOCK : r->slope_count;
        slope_block *bl = &ix->block[o];
        ix->pos[b] = (uint32_t)o;
        ix->seq[o] = (uint32_t)b;
        bl->gmax = keys[o].g;
        bl->count = (uint32_t)(k1 - k0);
        for (int i = 0; i < 3; i++) {
            bl->lo[i] = bl->dlo[i] = INFINITY; /* the positions' until _set */
            bl->hi[i] = bl->dhi[i] = -INFINITY;
        }
        for (size_t j = k0; j < k1; j++) {
            const size_t k = ord[j].k;
            ix->slot[k] = (uint32_t)(o * SLOPE_BLOCK + (j - k0));
            ix->p[4 * (size_t)ix->slot[k] + 3] = r->g[r->slope_v[k]];
            memcpy(&ix->dir[3 * (size_t)ix->slot[k]], &r->slope_dir[3 * k], 3 * sizeof *ix->dir);
            for (int i = 0; i < 3; i++) {
                bl->dlo[i] = fminf(bl->dlo[i], r->slope_dir[3 * k + i]);
                bl->dhi[i] = fmaxf(bl->dhi[i], r->slope_dir[3 * k + i]);
            }
        }
    }
}

int fp_rig_slope_index_create(const fp_rig *r, fp_rig_slope_index **out)
{
    if (!out) return -EINVAL;
    *out = NULL;
    if (!r || !r->g) return -EINVAL;
    fp_rig_slope_index *ix = calloc(1, sizeof *ix);
    if (!ix) return -ENOMEM;
    ix->rig = r;
    ix->nb = (r->slope_count + SLOPE_BLOCK - 1) / SLOPE_BLOCK;
    size_t nb = ix->nb ? ix->nb : 1, ns = r->slope_count ? r->slope_count : 1;
    ix->block = calloc(nb, sizeof *ix->block);
    ix->p = calloc(nb * SLOPE_BLOCK * 4, sizeof *ix->p);
    ix->dir = calloc(nb * SLOPE_BLOCK * 3, sizeof *ix->dir);
    ix->slot = malloc(ns * sizeof *ix->slot);
    ix->keys = malloc(nb * sizeof *ix->keys);
    ix->order = malloc(ns * sizeof *ix->order);
    ix->pos = malloc(nb * sizeof *ix->pos);
    ix->seq = malloc(nb * sizeof *ix->seq);
    ix->bdirty = calloc(nb, 1);
    ix->bdlist = malloc(nb * sizeof *ix->bdlist);
    bool ok = ix->block && ix->p && ix->dir && ix->slot && ix->keys && ix->order && ix->pos && ix->seq &&
              ix->bdirty && ix->bdlist;
    ix->tcount[0] = ix->nb;
    while (ok && ix->tcount[ix->levels] > SLOPE_FAN && ix->levels < SLOPE_LEVELS) {
        int l = ++ix->levels;
        ix->tcount[l] = (ix->tcount[l - 1] + SLOPE_FAN - 1) / SLOPE_FAN;
        ix->tbox[l] = malloc(ix->tcount[l] * sizeof *ix->tbox[l]);
        ix->tdirty[l] = calloc(ix->tcount[l], 1);
        ok = ix->tbox[l] && ix->tdirty[l];
    }
    if (!ok) {
        fp_rig_slope_index_destroy(&ix);
        return -ENOMEM;
    }
    for (size_t k = 0; k < r->slope_count; k++) ix->order[k] = (spatial_key){0, (uint32_t)k};
    layout(ix);
    tree_refit(ix, true);
    *out = ix;
    return 0;
}

void fp_rig_slope_index_destroy(fp_rig_slope_index **ix)
{
    if (!ix || !*ix) return;
    free((*ix)->block);
    free((*ix)->p);
    free((*ix)->dir);
    free((*ix)->slot);
    free((*ix)->keys);
    free((*ix)->order);
    free((*ix)->pos);
    free((*ix)->seq);
    free((*ix)->bdirty);
    free((*ix)->bdlist);
    for (int l = 1; l <= SLOPE_LEVELS; l++) {
        free((*ix)->tbox[l]);
        free((*ix)->tdirty[l]);
    }
    free(*ix);
    *ix = NULL;
}

/* Slope entry k takes vertex v's position in posed; its block's box grows to hold it (and
 * its level 1 node is marked for the refit). */
static void slope_put(fp_rig_slope_index *ix, size_t k, const float *posed)
{
    uint32_t sl = ix->slot[k];
    const float *q = &posed[3 * (size_t)ix->rig->slope_v[k]];
    float *p = &ix->p[4 * (size_t)sl];
    slope_block *bl = &ix->block[sl / SLOPE_BLOCK];
    if (ix->levels) ix->tdirty[1][ix->seq[sl / SLOPE_BLOCK] / SLOPE_FAN] = 1;
    for (int i = 0; i < 3; i++) {
        p[i] = q[i];
        bl->lo[i] = q[i] < bl->lo[i] ? q[i] : bl->lo[i];
        bl->hi[i] = q[i] > bl->hi[i] ? q[i] : bl->hi[i];
    }
}

static uint32_t spread10(uint32_t x) /* 10 bits to every third of 30 */
{
    x &= 0x3ffu;
    x = (x | x << 16) & 0x030000ffu;
    x = (x | x << 8) & 0x0300f00fu;
    x = (x | x << 4) & 0x030c30c3u;
    x = (x | x << 2) & 0x09249249u;
    return x;
}

static int by_code(const void *a, const void *b)
{
    const spatial_key *x = a, *y = b;
    return x->code != y->code ? (x->code > y->code) - (x->code < y->code) : (x->k > y->k) - (x->k < y->k);
}

/* The entries in the Morton order of their positions in posed (ties by entry), laid out
 * anew: blocks of neighbours. Which block holds a vertex changes no query's result. */
static void layout_spatial(fp_rig_slope_index *ix, const float *posed)
{
    const fp_rig *r = ix->rig;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < r->slope_count; k++)
        for (int i = 0; i < 3; i++) {
            lo[i] = fminf(lo[i], posed[3 * (size_t)r->slope_v[k] + i]);
            hi[i] = fmaxf(hi[i], posed[3 * (size_t)r->slope_v[k] + i]);
        }
    for (size_t k = 0; k < r->slope_count; k++) {
        uint32_t code = 0;
        for (int i = 0; i < 3; i++) {
            double x = hi[i] > lo[i] ? (posed[3 * (size_t)r->slope_v[k] + i] - lo[i]) / ((double)hi[i] - lo[i]) : 0;
            x = x * 1023.0; /* NaN (an unusable position) to cell 0 */
            code |= spread10(x > 0 ? (x < 1023 ? (uint32_t)x : 1023u) : 0u) << i;
        }
        ix->order[k] = (spatial_key){code, (uint32_t)k};
    }
    qsort(ix->order, r->slope_count, sizeof *ix->order, by_code);
    layout(ix);
    ix->spatial = true;
}

void fp_rig_slope_index_set(fp_rig_slope_index *ix, const float *posed)
{
    if (!ix || !posed) return;
    if (!ix->spatial) layout_spatial(ix, posed);
    for (size_t b = 0; b < ix->nb; b++)
        for (int i = 0; i < 3; i++) ix->block[b].lo[i] = INFINITY, ix->block[b].hi[i] = -INFINITY;
    for (size_t k = 0; k < ix->rig->slope_count; k++) slope_put(ix, k, posed);
    tree_refit(ix, true);
}

void fp_rig_slope_index_update_ranges(fp_rig_slope_index *ix, const float *posed, const uint32_t *ranges,
                                      size_t nranges)
{
    if (!ix || !posed || (nranges && !ranges)) return;
    const fp_rig *r = ix->rig;
    size_t nd = 0; /* blocks touched */
    for (size_t j = 0; j < nranges; j++) {
        uint64_t a = ranges[2 * j], e = a + ranges[2 * j + 1];
        size_t lo = 0, hi = r->slope_count; /* the first slope vertex >= a */
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (r->slope_v[mid] < a) lo = mid + 1;
            else hi = mid;
        }
        for (size_t k = lo; k < r->slope_count && r->slope_v[k] < e; k++) {
            slope_put(ix, k, posed);
            uint32_t b = ix->slot[k] / SLOPE_BLOCK;
            if (!ix->bdirty[b]) ix->bdirty[b] = 1, ix->bdlist[nd++] = b;
        }
    }
    /* the touched blocks' boxes made again from their vertices: slope_put only grows them,
     * and skin that went and came back would leave them as wide as its path, the tree's
     * pruning weaker frame after frame in a long unanchored performance */
    for (size_t j = 0; j < nd; j++) {
        slope_block *bl = &ix->block[ix->bdlist[j]];
        const float *p = &ix->p[4 * (size_t)ix->bdlist[j] * SLOPE_BLOCK];
        ix->bdirty[ix->bdlist[j]] = 0;
        for (int i = 0; i < 3; i++) bl->lo[i] = INFINITY, bl->hi[i] = -INFINITY;
        for (uint32_t v = 0; v < bl->count; v++, p += 4)
            for (int i = 0; i < 3; i++) {
                bl->lo[i] = p[i] < bl->lo[i] ? p[i] : bl->lo[i];
                bl->hi[i] = p[i] > bl->hi[i] ? p[i] : bl->hi[i];
            }
    }
    tree_refit(ix, false);
}

double fp_rig_finger_limit_indexed(const fp_rig_slope_index *ix, const float start[3], double radius)
{
    const fp_rig *r = ix ? ix->rig : NULL;
    if (!r || !start || !r->g || !(radius > 0)) return r && r->g ? r->geom.ramp / 3 : 0;
    double gmax = 0, r2 = radius * radius;
    for (size_t b = 0; b < ix->nb; b++) {
        const slope_block *bl = &ix->block[b];
        if (bl->gmax <= gmax) break; /* this block and every later one: nothing steeper */
        /* a lower bound of every vertex's squared distance below, in the same arithmetic
         * (float differences, double squares): rounding is monotone */
        double q = 0;
        for (int i = 0; i < 3; i++) {
            float d = start[i] < bl->lo[i] ? bl->lo[i] - start[i] : start[i] > bl->hi[i] ? start[i] - bl->hi[i] : 0.f;
            q += (double)d * d;
        }
        if (!(q < r2)) continue;
        const float *p = &ix->p[4 * b * SLOPE_BLOCK];
        for (uint32_t k = 0; k < bl->count; k++, p += 4) {
            if (p[3] <= gmax) continue;
            double d0 = p[0] - start[0], d1 = p[1] - start[1], d2 = p[2] - start[2];
            if (d0 * d0 + d1 * d1 + d2 * d2 < r2) gmax = p[3];
        }
    }
    return gmax > 0 ? FP_RIG_FINGER_MARGIN / gmax : INFINITY;
}

/* The blocks a capsule's search looks at: those whose box lies within radius of the
 * segment's box (the gap, a lower bound of every vertex's distance to the segment), found
 * through the tree and set in a bitmap of their places (steepest first), so that push_scan
 * visits them in the order of a scan of every block. A node is skipped by the same test in
 * the same arithmetic; its box holds its children's, and rounding is monotone, so no block a
 * full scan would look at is left out. */
typedef struct {
    float slo[3], shi[3]; /* the segment's box */
    double r2;
    uint64_t mark[SLOPE_MARK_WORDS];
    bool all;             /* more blocks than the bitmap holds: every block */
} capsule_blocks;

static double box_gap2(const float slo[3], const float shi[3], const float lo[3], const float hi[3])
{
    double q = 0;
    for (int i = 0; i < 3; i++) {
        double g = shi[i] < lo[i] ? (double)lo[i] - shi[i] : slo[i] > hi[i] ? (double)slo[i] - hi[i] : 0;
        q += g * g;
    }
    return q;
}

static void tree_collect(const fp_rig_slope_index *ix, capsule_blocks *cb, int l, size_t i)
{
    if (!(box_gap2(cb->slo, cb->shi, node_lo(ix, l, i), node_hi(ix, l, i)) < cb->r2)) return;
    if (!l) {
        uint32_t o = ix->pos[i];
        cb->mark[o / 64] |= 1ull << (o % 64);
        return;
    }
    size_t c1 = (i + 1) * SLOPE_FAN < ix->tcount[l - 1] ? (i + 1) * SLOPE_FAN : ix->tcount[l - 1];
    for (size_t c = i * SLOPE_FAN; c < c1; c++) tree_collect(ix, cb, l - 1, c);
}

static void capsule_collect(const fp_rig_slope_index *ix, const float start[3], const float end[3], double radius,
                            capsule_blocks *cb)
{
    for (int i = 0; i < 3; i++) {
        cb->slo[i] = start[i] < end[i] ? start[i] : end[i];
        cb->shi[i] = start[i] < end[i] ? end[i] : start[i];
    }
    cb->r2 = radius * radius;
    cb->all = ix->nb > 64 * (size_t)SLOPE_MARK_WORDS;
    if (cb->all) return;
    memset(cb->mark, 0, (ix->nb + 63) / 64 * sizeof cb->mark[0]);
    for (size_t i = 0; i < ix->tcount[ix->levels]; i++) tree_collect(ix, cb, ix->levels, i);
}

/* The largest push c_v (fp_rig.h) over the slope vertices within radius of the segment
 * start -> end, through the index, for a vector along `along` (3 doubles, any length; NULL:
 * along the segment itself); with worst (may be NULL): that vertex's grad m direction and its
 * slope times its Wendland weight (its push is that times max(0, -dir . u)). cb: the blocks
 * capsule_collect found for this segment and radius. */
typedef struct {
    float dir[3];
    double k;
} slope_worst;

/* One block's part of push_scan: cmax raised to its vertices' largest push over it */
static double block_push(const fp_rig_slope_index *ix, size_t b, const float start[3], const double d[3], double dd,
                         const double u[3], double radius, double q, double cmax, slope_worst *worst)
{
    const slope_block *bl = &ix->block[b];
    /* the most any vertex here can push: its largest share of u against grad m (the
     * directions' box: a linear function's maximum over it is at a corner), over by
     * 1e-6 for the vertices' own rounding (about 1e-16 here), times the Wendland weight
     * at the box gap q (psi decreasing), over by a part in 1e9 and 1e-20 for the rounding
     * of the distances (about 1e-15 of r: relative to psi, 4e-15 / (1 - r), under 1e-9
     * where psi is over 1e-20). A block that cannot beat the push found is skipped: the
     * result stays the brute force's, bit for bit (a push equal to cmax changes nothing
     * there either) */
    double share = 1e-6, r2 = radius * radius;
    for (int i = 0; i < 3; i++) share += fmax(-(double)bl->dlo[i] * u[i], -(double)bl->dhi[i] * u[i]);
    if (share <= 0) return cmax; /* every vertex pulls away or runs along: push 0 */
    double w = wendland(sqrt(q) / radius) * (1 + 1e-9) + 1e-20;
    if (bl->gmax * fmin(share, 1.0 + 1e-6) * w <= cmax) return cmax;
    const float *p = &ix->p[4 * b * SLOPE_BLOCK], *dir = &ix->dir[3 * b * SLOPE_BLOCK];
    for (uint32_t k = 0; k < bl->count; k++, p += 4, dir += 3) {
        double c = push_of(p[3], dir, u);
        if (c <= cmax) continue;
        double qv = seg_dist2(p, start, d, dd);
        if (!(qv < r2)) continue;
        double wv = wendland(sqrt(qv) / radius);
        if (c * wv > cmax) {
            cmax = c * wv;
            if (worst) *worst = (slope_worst){{dir[0], dir[1], dir[2]}, p[3] * wv};
        }
    }
    return cmax;
}

static double push_scan(const fp_rig_slope_index *ix, const capsule_blocks *cb, const float start[3],
                        const float end[3], const double *along, double radius, slope_worst *worst)
{
    double d[3], u[3], dd, cmax = 0;
    capsule_of(start, end, d, u, &dd);
    if (along) {
        double q = sqrt(along[0] * along[0] + along[1] * along[1] + along[2] * along[2]);
        for (int i = 0; i < 3; i++) u[i] = q > 0 ? along[i] / q : 0;
    }
    /* the blocks in place order (steepest first), those the search found or every one */
    for (size_t wi = 0; wi < (ix->nb + 63) / 64; wi++) {
        uint64_t m = cb->all ? ~0ull : cb->mark[wi];
        for (; m; m &= m - 1) {
            size_t b = 64 * wi + (size_t)__builtin_ctzll(m);
            if (b >= ix->nb) break;
            const slope_block *bl = &ix->block[b];
            if (bl->gmax <= cmax) return cmax; /* a push is at most the slope: nothing larger after */
            double q = box_gap2(cb->slo, cb->shi, bl->lo, bl->hi);
            if (!(q < cb->r2)) continue;
            cmax = block_push(ix, b, start, d, dd, u, radius, q, cmax, worst);
        }
    }
    return cmax;
}

double fp_rig_finger_limit_toward_indexed(const fp_rig_slope_index *ix, const float start[3], const float end[3],
                                          double radius)
{
    const fp_rig *r = ix ? ix->rig : NULL;
    if (!r || !start || !end || !r->g || !(radius > 0)) return r && r->g ? r->geom.ramp / 3 : 0;
    capsule_blocks cb;
    capsule_collect(ix, start, end, radius, &cb);
    double cmax = push_scan(ix, &cb, start, end, NULL, radius, NULL);
    return cmax > 0 ? FP_RIG_FINGER_MARGIN / cmax : INFINITY;
}

/* The searches of fp_rig_finger_clamp_indexed (each adds the worst vertex's constraint)
 * before it scales what is left instead. */
#define CLAMP_ROUNDS 16

static double seg_len(const float a[3], const float b[3])
{
    double q = 0;
    for (int i = 0; i < 3; i++) q += ((double)b[i] - a[i]) * ((double)b[i] - a[i]);
    return sqrt(q);
}

/* out := start + f (end - start), rounded once to float; f == 1 keeps end bit for bit */
static void scaled_end(const float start[3], const float end[3], double f, float out[3])
{
    for (int i = 0; i < 3; i++) out[i] = f == 1 ? end[i] : (float)(start[i] + f * ((double)end[i] - start[i]));
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double det3(const double h[3][3])
{
    return h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1]) - h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0]) +
           h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
}

/* Solves the m x m (m <= 3) symmetric system g x = r by Cramer's rule; false when g is
 * near singular (constraints whose directions are dependent: another active set serves). */
static bool solve_small(int m, const double g[3][3], const double r[3], double x[3])
{
    if (m == 1) {
        if (!(g[0][0] > 1e-12)) return false;
        x[0] = r[0] / g[0][0];
        return true;
    }
    if (m == 2) {
        double det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
        if (!(fabs(det) > 1e-9)) return false;
        x[0] = (r[0] * g[1][1] - g[0][1] * r[1]) / det;
        x[1] = (g[0][0] * r[1] - r[0] * g[1][0]) / det;
        return true;
    }
    double det = det3(g);
    if (!(fabs(det) > 1e-9)) return false;
    for (int j = 0; j < 3; j++) {
        double h[3][3];
        memcpy(h, g, sizeof h);
        for (int i = 0; i < 3; i++) h[i][j] = r[i];
        x[j] = det3((const double (*)[3])h) / det;
    }
    return true;
}

/* The point of {v : a_j . v <= b_j for j < n} nearest v0 (a_j unit; n <= CLAMP_ROUNDS): the
 * Euclidean projection onto a convex polytope, unique and 1-Lipschitz in v0 and continuous
 * in the b_j. In 3-D it lies on at most 3 independent active constraints, so every active
 * set of up to 3 is tried (696 for n = 16) and the KKT point kept: multipliers
 * lambda >= 0 (v = v0 - sum lambda_j a_j) and every constraint met. False when rounding
 * leaves none (v untouched). */
static bool project_polytope(const double v0[3], const double (*a)[3], const double *b, int n, double v[3])
{
    double best = INFINITY;
    for (int i0 = 0; i0 < n; i0++)
        for (int i1 = i0; i1 < n; i1++)
            for (int i2 = i1; i2 < n; i2++) {
                /* the active sets {i0} as (i0, i0, i0), {i0, i1} as (i0, i1, i1), {i0, i1, i2} */
                if (i1 == i0 && i2 != i0) continue;
                int set[3] = {i0, i1, i2}, m = i1 == i0 ? 1 : i2 == i1 ? 2 : 3;
                double g[3][3], rhs[3], lam[3], w[3];
                for (int i = 0; i < m; i++) {
                    for (int j = 0; j < m; j++) g[i][j] = dot3(a[set[i]], a[set[j]]);
                    rhs[i] = dot3(a[set[i]], v0) - b[set[i]];
                }
                if (!solve_small(m, g, rhs, lam)) continue;
                bool ok = true;
                for (int i = 0; i < m; i++) ok = ok && lam[i] >= -1e-12;
                memcpy(w, v0, sizeof w);
                for (int i = 0; i < m; i++)
                    for (int c = 0; c < 3; c++) w[c] -= lam[i] * a[set[i]][c];
                for (int j = 0; j < n && ok; j++) ok = dot3(a[j], w) <= b[j] + 1e-12 * (1 + fabs(b[j]));
                double q = (w[0] - v0[0]) * (w[0] - v0[0]) + (w[1] - v0[1]) * (w[1] - v0[1]) +
                           (w[2] - v0[2]) * (w[2] - v0[2]);
                if (ok && q < best) {
                    best = q;
                    memcpy(v, w, sizeof w);
                }
            }
    return best < INFINITY;
}

int fp_rig_finger_clamp_indexed(const fp_rig_slope_index *ix, const float start[3], const float end[3],
                                double radius, float out_end[3])
{
    const fp_rig *r = ix ? ix->rig : NULL;
    assert(start && end && out_end);
    memcpy(out_end, end, 3 * sizeof(float));
    if (!r || !r->g) return 0;
    double len = seg_len(start, end);
    if (!(radius > 0)) { /* no support to search: the global bound */
        double f = len > r->geom.ramp / 3 ? r->geom.ramp / 3 / len : 1;
        scaled_end(start, end, f, out_end);
        return f == 1 ? 0 : 2;
    }
    /* round 0: the vector asked, by the limit's own test. Then each round adds the worst
     * vertex's constraint (its push, the vector's component against its grad m, at most the
     * margin, a hair under) and takes the vector asked projected onto every constraint found:
     * the nearest vector that meets them, so what is cut is a push toward bone and no more.
     * The constraints are weighed on the asked vector's capsule (the finger's whole path),
     * so they follow `end` smoothly, and so does the projection onto them (a convex set
     * holding 0: the result is no longer than the vector asked). Last, the result's own
     * capsule, which may reach vertices the asked one does not, is searched once, and the
     * result scaled to its limit there where it is over: a continuous function of `end` too.
     * Constraints weighed on each cut vector's own capsule instead made the result depend on
     * which vertex a search met first: cuts that jumped from 21 to 10 mm between two frames
     * of a grab (docs/performance.md). */
    double v0[3], v[3], a[CLAMP_ROUNDS][3], b[CLAMP_ROUNDS];
    capsule_blocks asked, own_cb; /* the blocks of the asked vector's capsule, of a result's */
    capsule_collect(ix, start, end, radius, &asked);
    for (int i = 0; i < 3; i++) v[i] = v0[i] = (double)end[i] - start[i];
    for (int round = 0;; round++) {
        slope_worst w;
        float e[3];
        for (int i = 0; i < 3; i++) e[i] = round ? (float)(start[i] + v[i]) : end[i];
        double l = round ? seg_len(start, e) : len;
        double c = push_scan(ix, &asked, start, end, round ? v : NULL, radius, &w);
        if (!(l > FP_RIG_FINGER_MARGIN / c)) {
            if (!round) return 0; /* out_end = end */
            capsule_collect(ix, start, e, radius, &own_cb);
            double own = push_scan(ix, &own_cb, start, e, NULL, radius, NULL);
            if (!(l > FP_RIG_FINGER_MARGIN / own)) {
                memcpy(out_end, e, sizeof e);
                return 1;
            }
            scaled_end(start, e, FP_RIG_FINGER_MARGIN / own / l, out_end);
            return 2;
        }
        bool projected = false;
        if (round < CLAMP_ROUNDS && w.k > 0) {
            for (int i = 0; i < 3; i++) a[round][i] = -(double)w.dir[i];
            double an = sqrt(dot3(a[round], a[round]));
            for (int i = 0; i < 3; i++) a[round][i] /= an;
            b[round] = FP_RIG_FINGER_MARGIN * (1 - 1e-5) / (w.k * an);
            projected = project_polytope(v0, (const double (*)[3])a, b, round + 1, v);
        }
        if (!projected) {
            /* rounds spent (or rounding at the margin): the last vector scaled to its limit
             * on both capsules (its own lies in the one just searched) */
            capsule_collect(ix, start, e, radius, &own_cb);
            double own = push_scan(ix, &own_cb, start, e, NULL, radius, NULL);
            scaled_end(start, e, FP_RIG_FINGER_MARGIN / fmax(c, own) / l, out_end);
            return 2;
        }
    }
}
