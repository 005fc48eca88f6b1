/* The contact guard's hierarchy ("(3b)" in fp_contact.h), its building: clusters grown across
 * edges bottom up, the layout, the patches' boundary cycles (their certificates' contours).
 * The check: contact_bvh.c. */
#include "contact_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- the hierarchy: building ---- */

/* ---- the hierarchy, bottom up ---- */

typedef struct cbuild {           /* cluster_build's state */
    size_t m;                     /* triangles not own; clusters 0 .. m - 1 are them */
    uint32_t *list;               /* cluster i < m: triangle list[i] */
    uint32_t *idx;                /* t: a triangle's cluster < m (FP_TRACK_NONE: own) */
    uint32_t *tw;                 /* 3 t: a half-edge's twin (3 b + q), FP_TRACK_NONE: none */
    uint32_t *cnt, *lc, *rc, *uf; /* per cluster: triangles, children, union-find parent */
    uint32_t **bnd, *nbnd;        /* clusters >= m: the half-edges whose twin is outside */
    uint32_t *round;              /* the round a cluster was paired in */
    float *cen;                   /* per cluster: its triangles' centroid sum (3) */
    float *nb;                    /* per cluster: a box of its unit normals (lo 3, hi 3) */
    size_t nc;                    /* clusters made */
} cbuild;

static uint32_t cfind(cbuild *b, uint32_t x)
{
    while (b->uf[x] != x) {
        b->uf[x] = b->uf[b->uf[x]];
        x = b->uf[x];
    }
    return x;
}

/* cluster x's boundary half-edges */
static const uint32_t *cbnd(const cbuild *b, uint32_t x, uint32_t tmp[3], uint32_t *len)
{
    if (x < b->m) {
        for (int j = 0; j < 3; j++) tmp[j] = 3 * b->list[x] + (uint32_t)j;
        *len = 3;
        return tmp;
    }
    *len = b->nbnd[x];
    return b->bnd[x];
}

/* a new cluster over x and y (children); 0 or -ENOMEM */
static int cjoin(cbuild *b, uint32_t x, uint32_t y, uint32_t *out)
{
    uint32_t z = (uint32_t)b->nc++;
    b->cnt[z] = b->cnt[x] + b->cnt[y];
    b->lc[z] = x;
    b->rc[z] = y;
    b->uf[z] = z;
    b->uf[x] = b->uf[y] = z;
    for (int j = 0; j < 3; j++) {
        b->cen[3 * z + j] = b->cen[3 * x + j] + b->cen[3 * y + j];
        b->nb[6 * z + j] = min_f(b->nb[6 * x + j], b->nb[6 * y + j]);
        b->nb[6 * z + 3 + j] = max_f(b->nb[6 * x + 3 + j], b->nb[6 * y + 3 + j]);
    }
    uint32_t tx[3], ty[3], lx, ly;
    const uint32_t *ex = cbnd(b, x, tx, &lx), *ey = cbnd(b, y, ty, &ly);
    uint32_t *e = malloc(((size_t)lx + ly + 1) * sizeof *e), ne = 0;
    if (!e) return -ENOMEM;
    for (int h = 0; h < 2; h++) {
        const uint32_t *src = h ? ey : ex;
        for (uint32_t i = 0, l = h ? ly : lx; i < l; i++) {
            uint32_t w = b->tw[src[i]];
            if (w == FP_TRACK_NONE || cfind(b, b->idx[w / 3]) != z) e[ne++] = src[i];
        }
    }
    if (x >= b->m) free(b->bnd[x]), b->bnd[x] = NULL;
    if (y >= b->m) free(b->bnd[y]), b->bnd[y] = NULL;
    b->bnd[z] = e;
    b->nbnd[z] = ne;
    *out = z;
    return 0;
}

/* the clusters items[0 .. n) joined by median splits of their centroids (cen: the mean, for
 * the items); the root in *out */
static int top_split(cbuild *b, uint32_t *items, size_t n, uint32_t *out)
{
    if (n == 1) {
        *out = items[0];
        return 0;
    }
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            float v = b->cen[3 * (size_t)items[i] + a];
            lo[a] = min_f(lo[a], v);
            hi[a] = max_f(hi[a], v);
        }
    int a = 0;
    for (int j = 1; j < 3; j++)
        if (hi[j] - lo[j] > hi[a] - lo[a]) a = j;
    fp_select_mid(items, 0, n, n / 2, a, b->cen);
    uint32_t l, r;
    if (top_split(b, items, n / 2, &l) || top_split(b, items + n / 2, n - n / 2, &r)) return -ENOMEM;
    return cjoin(b, l, r, out);
}

/* the preorder layout of cluster z's subtree into k->node (a cluster of FP_BVH_LEAF
 * triangles or fewer is a leaf), its triangles into k->order */
static void lay_tris(const cbuild *b, struct track *k, uint32_t z, uint32_t *pos)
{
    if (z < b->m) {
        k->order[(*pos)++] = b->list[z];
        return;
    }
    lay_tris(b, k, b->lc[z], pos);
    lay_tris(b, k, b->rc[z], pos);
}

static void lay(const cbuild *b, struct track *k, uint32_t z, uint32_t *pos)
{
    uint32_t x = (uint32_t)k->nnode++;
    bnode *nd = &k->node[x];
    memset(nd, 0, sizeof *nd);
    nd->first = *pos;
    nd->count = b->cnt[z];
    nd->cert = FP_TRACK_NONE;
    if (z < b->m || b->cnt[z] <= FP_BVH_LEAF) {
        lay_tris(b, k, z, pos);
        return;
    }
    lay(b, k, b->lc[z], pos);
    k->node[x].right = (uint32_t)k->nnode;
    lay(b, k, b->rc[z], pos);
}

/* the union of two boxes of unit normals (lo 3, hi 3) faces a direction (certified's test) */
static bool faces(const float *p, const float *q)
{
    double lo[3], hi[3], ad[3], l = 0, mn = 0;
    for (int j = 0; j < 3; j++) {
        lo[j] = min_f(p[j], q[j]);
        hi[j] = max_f(p[3 + j], q[3 + j]);
        ad[j] = 0.5 * (lo[j] + hi[j]);
        l += ad[j] * ad[j];
    }
    l = sqrt(l);
    if (!(l > 1e-3)) return false;
    for (int j = 0; j < 3; j++) mn += ad[j] >= 0 ? ad[j] / l * lo[j] : ad[j] / l * hi[j];
    return mn > 1e-4;
}

/* The first clusters: each triangle not own (k->order[0 .. b->m)) one, with its centroid and
 * its unit normal's box (a degenerate triangle's: every direction); all of them active */
static void cluster_leaves(const fp_contact *c, const struct track *k, cbuild *b, uint32_t *act)
{
    size_t t = c->t, m = b->m;
    memcpy(b->list, k->order, m * sizeof *b->list);
    for (size_t i = 0; i < t; i++) b->idx[i] = FP_TRACK_NONE;
    for (size_t i = 0; i < m; i++) {
        uint32_t a = b->list[i];
        const uint32_t *v = c->tris + 3 * (size_t)a;
        b->idx[a] = (uint32_t)i;
        b->cnt[i] = 1;
        b->uf[i] = (uint32_t)i;
        for (int j = 0; j < 3; j++)
            b->cen[3 * i + j] = (k->p[3 * (size_t)v[0] + j] + k->p[3 * (size_t)v[1] + j] + k->p[3 * (size_t)v[2] + j]) / 3.f;
        double nd[3];
        float nf[3];
        tri_normal_f(k->p, v, nf, nd);
        bool deg = nf[0] == 0.f && nf[1] == 0.f && nf[2] == 0.f;
        for (int j = 0; j < 3; j++) {
            b->nb[6 * i + j] = deg ? -1.f : nf[j];
            b->nb[6 * i + 3 + j] = deg ? 1.f : nf[j];
        }
        act[i] = (uint32_t)i;
    }
    b->nc = m;
}

/* twins: (u, v) of a, (v, u) of the one other triangle not own that has it */
static void cluster_twins(const fp_contact *c, const struct track *k, cbuild *b)
{
    for (size_t i = 0; i < b->m; i++) {
        uint32_t a = b->list[i];
        const uint32_t *v = c->tris + 3 * (size_t)a;
        for (int j = 0; j < 3; j++) {
            uint32_t u = v[j], w = v[(j + 1) % 3], found = FP_TRACK_NONE, nf = 0;
            for (uint32_t q = k->vt_start[w]; q < k->vt_start[w + 1]; q++) {
                uint32_t o = k->vt[q];
                if (o == a || b->idx[o] == FP_TRACK_NONE) continue;
                const uint32_t *vo = c->tris + 3 * (size_t)o;
                for (int r = 0; r < 3; r++)
                    if (vo[r] == w && vo[(r + 1) % 3] == u) {
                        found = 3 * o + (uint32_t)r;
                        nf++;
                    }
            }
            b->tw[3 * (size_t)a + j] = nf == 1 ? found : FP_TRACK_NONE;
        }
    }
}

/* The hierarchy over the m triangles not own (k->order holds them): clusters grown across
 * edges, bottom up. The triangles are the first clusters; each round pairs every cluster not
 * yet paired with the unpaired neighbour (across an edge (u, v) / (v, u)) it shares most
 * edges with. Clusters grown so stay connected and mostly discs, which a certificate needs;
 * what finds no partner (separate components: an eyeball, the teeth) is joined at the top by
 * median splits. 0 or -ENOMEM. */
static int cluster_build(fp_contact *c, struct track *k, size_t m)
{
    cbuild b = {0};
    size_t t = c->t, cap = 2 * m + 1;
    int rc = -ENOMEM;
    b.m = m;
    b.list = malloc((m + 1) * sizeof *b.list);
    b.idx = malloc((t + 1) * sizeof *b.idx);
    b.tw = malloc((3 * t + 1) * sizeof *b.tw);
    b.cnt = malloc(cap * sizeof *b.cnt);
    b.lc = malloc(cap * sizeof *b.lc);
    b.rc = malloc(cap * sizeof *b.rc);
    b.uf = malloc(cap * sizeof *b.uf);
    b.bnd = calloc(cap, sizeof *b.bnd);
    b.nbnd = calloc(cap, sizeof *b.nbnd);
    b.round = calloc(cap, sizeof *b.round);
    b.cen = malloc(3 * cap * sizeof *b.cen);
    b.nb = malloc(6 * cap * sizeof *b.nb);
    uint32_t *act = malloc((m + 1) * sizeof *act), *nxt = malloc((m + 1) * sizeof *nxt);
    uint32_t *vmark = calloc(c->n + 1, sizeof *vmark), *vseen = calloc(c->n + 1, sizeof *vseen), vclock = 0;
    if (!b.list || !b.idx || !b.tw || !b.cnt || !b.lc || !b.rc || !b.uf || !b.bnd || !b.nbnd || !b.round ||
        !b.cen || !b.nb || !act || !nxt || !vmark || !vseen)
        goto done;
    cluster_leaves(c, k, &b, act);
    cluster_twins(c, k, &b);
    size_t nact = m;
    for (uint32_t r = 1; nact > 1; r++) {
        size_t nn = 0, joined = 0;
        for (size_t i = 0; i < nact; i++) {
            uint32_t x = act[i];
            if (b.round[x] == r) continue;
            uint32_t nb[32], nbc[32], nnb = 0, tmp[3], len;
            const uint32_t *e = cbnd(&b, x, tmp, &len);
            for (uint32_t h = 0; h < len; h++) {
                uint32_t w = b.tw[e[h]];
                if (w == FP_TRACK_NONE) continue;
                uint32_t y = cfind(&b, b.idx[w / 3]);
                if (y == x || b.round[y] == r) continue;
                uint32_t q = 0;
                while (q < nnb && nb[q] != y) q++;
                if (q == nnb) {
                    if (nnb == 32) continue;
                    nb[nnb] = y;
                    nbc[nnb++] = 0;
                }
                nbc[q]++;
            }
            b.round[x] = r;
            if (!nnb) {
                nxt[nn++] = x;
                continue;
            }
            /* a partner whose union with x stays a disc: they share one arc, i.e. the
             * vertices on both boundaries are one more than the edges (a union of discs
             * glued along k arcs has k - 1 holes) */
            if (++vclock == 0) {
                memset(vmark, 0, c->n * sizeof *vmark);
                memset(vseen, 0, c->n * sizeof *vseen);
                vclock = 1;
            }
            uint32_t vx = vclock;
            for (uint32_t h = 0; h < len; h++) vmark[c->tris[e[h]]] = vx;
            uint32_t best = FP_TRACK_NONE;
            for (int tier = 2; tier >= 0 && best == FP_TRACK_NONE; tier--)
                for (uint32_t q = 0; q < nnb; q++) {
                    if (tier == 2 && !faces(b.nb + 6 * (size_t)x, b.nb + 6 * (size_t)nb[q])) continue;
                    /* (small unions: any; a pinch there is mostly healed by the next rounds) */
                    if (tier >= 1 && b.cnt[x] + b.cnt[nb[q]] >= FP_CERT_MIN / 2) {
                        if (++vclock == 0) vclock = 1; /* (a wrap here only costs a disc) */
                        uint32_t ty[3], ly, vs = 0;
                        const uint32_t *ey = cbnd(&b, nb[q], ty, &ly);
                        for (uint32_t h = 0; h < ly; h++) {
                            uint32_t v = c->tris[ey[h]];
                            if (vmark[v] == vx && vseen[v] != vclock) {
                                vseen[v] = vclock;
                                vs++;
                            }
                        }
                        if (vs != nbc[q] + 1) continue;
                    }
                    if (best == FP_TRACK_NONE || nbc[q] > nbc[best] || (nbc[q] == nbc[best] && b.cnt[nb[q]] < b.cnt[nb[best]]))
                        best = q;
                }
            uint32_t z;
            if (cjoin(&b, x, nb[best], &z)) goto done;
            b.round[nb[best]] = b.round[z] = r;
            nxt[nn++] = z;
            joined++;
        }
        uint32_t *sw = act;
        act = nxt;
        nxt = sw;
        nact = nn;
        if (!joined || joined < nact / 64) break; /* no partners left (or hardly any) */
    }
    for (size_t i = 0; i < nact; i++) /* the items' centroids: sums to means */
        for (int j = 0; j < 3; j++) b.cen[3 * (size_t)act[i] + j] /= (float)b.cnt[act[i]];
    uint32_t root;
    if (top_split(&b, act, nact, &root)) goto done;
    uint32_t pos = 0;
    lay(&b, k, root, &pos);
    rc = 0;
done:
    if (b.bnd)
        for (size_t i = m; i < b.nc; i++) free(b.bnd[i]);
    free(b.list);
    free(b.idx);
    free(b.tw);
    free(b.cnt);
    free(b.lc);
    free(b.rc);
    free(b.uf);
    free(b.bnd);
    free(b.nbnd);
    free(b.round);
    free(b.cen);
    free(b.nb);
    free(act);
    free(nxt);
    free(vmark);
    free(vseen);
    return rc;
}

/* e[0 .. n) (directed edges u << 32 | v) with every (u, v) cancelled against one (v, u):
 * what is left in place, its count returned (SIZE_MAX: out of memory). Pairs found by a
 * scan for short lists, else through an open-addressing table of the edges not yet paired. */
static size_t chain_sum(uint64_t *e, size_t n)
{
#define FP_REV(x) ((x) << 32 | (x) >> 32)
    uint8_t *dead = calloc(n ? n : 1, 1);
    if (!dead) return SIZE_MAX;
    if (n <= 48) {
        for (size_t i = 0; i < n; i++)
            for (size_t j = i + 1; j < n && !dead[i]; j++)
                if (!dead[j] && e[j] == FP_REV(e[i])) dead[i] = dead[j] = 1;
    } else {
        size_t cap = 64;
        while (cap < 2 * n) cap *= 2;
        uint32_t *tab = malloc(cap * sizeof *tab); /* index + 1, 0: empty */
        if (!tab) {
            free(dead);
            return SIZE_MAX;
        }
        memset(tab, 0, cap * sizeof *tab);
        for (size_t i = 0; i < n; i++) {
            uint64_t r = FP_REV(e[i]);
            size_t h = (size_t)((r * 0x9E3779B97F4A7C15ull) >> 32) & (cap - 1), hit = SIZE_MAX;
            for (size_t q = h; tab[q]; q = (q + 1) & (cap - 1))
                if (!dead[tab[q] - 1] && e[tab[q] - 1] == r) {
                    hit = tab[q] - 1;
                    break;
                }
            if (hit != SIZE_MAX) {
                dead[hit] = dead[i] = 1;
                continue;
            }
            size_t q = (size_t)((e[i] * 0x9E3779B97F4A7C15ull) >> 32) & (cap - 1);
            while (tab[q]) q = (q + 1) & (cap - 1);
            tab[q] = (uint32_t)i + 1;
        }
        free(tab);
    }
    size_t w = 0;
    for (size_t i = 0; i < n; i++)
        if (!dead[i]) e[w++] = e[i];
    free(dead);
    return w;
#undef FP_REV
}

/* The boundary of node x as a chain: its triangles' directed edges (u, v) (vertex indices,
 * as stored: a seam is boundary) summed, (u, v) and (v, u) cancelling. Made from its
 * children's; *len edges in *out (malloc'd; NULL for nodes over FP_CERT_MAX). A node with
 * FP_CERT_MIN .. FP_CERT_MAX triangles whose chain is one cycle through distinct vertices
 * (each edge once) gets it as its cert. 0 or -ENOMEM. */
static int boundary(fp_contact *c, struct track *k, uint32_t x, uint64_t **out, size_t *len, size_t *cap_cyc,
                    size_t *cap_cert)
{
    bnode *b = &k->node[x];
    *out = NULL;
    *len = 0;
    uint64_t *e = NULL;
    size_t ne = 0;
    if (!b->right) {
        e = malloc(3 * (size_t)b->count * sizeof *e);
        if (!e) return -ENOMEM;
        for (uint32_t i = b->first; i < b->first + b->count; i++) {
            const uint32_t *v = c->tris + 3 * (size_t)k->order[i];
            for (int j = 0; j < 3; j++) e[ne++] = (uint64_t)v[j] << 32 | v[(j + 1) % 3];
        }
    } else {
        uint64_t *l, *r;
        size_t nl, nr;
        if (boundary(c, k, x + 1, &l, &nl, cap_cyc, cap_cert)) return -ENOMEM;
        if (boundary(c, k, b->right, &r, &nr, cap_cyc, cap_cert)) {
            free(l);
            return -ENOMEM;
        }
        if (b->count > FP_CERT_MAX || !l || !r) {
            free(l);
            free(r);
            return 0;
        }
        e = realloc(l, (nl + nr ? nl + nr : 1) * sizeof *e);
        if (!e) {
            free(l);
            free(r);
            return -ENOMEM;
        }
        memcpy(e + nl, r, nr * sizeof *e);
        free(r);
        ne = nl + nr;
    }
    /* sum: each (u, v) cancels one (v, u) */
    ne = chain_sum(e, ne);
    if (ne == SIZE_MAX) {
        free(e);
        return -ENOMEM;
    }
    *out = e;
    *len = ne;
    if (b->count < FP_CERT_MIN || b->count > FP_CERT_MAX || ne < 3) return 0;
    /* one cycle through distinct vertices: sources distinct, the walk from the first edge
     * back to it covers all */
    /* sources distinct, then the walk from the least edge (edges as u << 32 | v) along each
     * edge's end to the edge leaving it. Each source is stamped with this check's number in
     * vstamp and its edge's index kept in bidx (the build's scratch: tree_build stamps every
     * vertex after the boundaries): O(ne), where sorting the edges for the check and for a
     * binary search per step was a seventh of the 1.7M face's hierarchy build */
    const uint32_t g = ++k->bgen;
    bool ok = true;
    size_t imin = 0;
    for (size_t i = 0; i < ne && ok; i++) {
        uint32_t u = (uint32_t)(e[i] >> 32);
        ok = k->vstamp[u] != g;
        k->vstamp[u] = g;
        k->bidx[u] = (uint32_t)i;
        if (e[i] < e[imin]) imin = i;
    }
    if (ok) {
        if (reserve((void **)&k->cyc, cap_cyc, k->ncert ? k->cert[k->ncert - 1].start + k->cert[k->ncert - 1].len + ne : ne,
                    sizeof *k->cyc) ||
            reserve((void **)&k->cert, cap_cert, k->ncert + 1, sizeof *k->cert))
            return -ENOMEM;
        uint32_t start = k->ncert ? k->cert[k->ncert - 1].start + k->cert[k->ncert - 1].len : 0;
        size_t steps = 0;
        const uint64_t first = e[imin];
        uint64_t cur = first;
        do {
            k->cyc[start + steps++] = (uint32_t)(cur >> 32);
            const uint32_t to = (uint32_t)cur; /* the edge leaving cur's end */
            if (k->vstamp[to] != g) {
                ok = false;
                break;
            }
            cur = e[k->bidx[to]];
        } while (cur != first && steps < ne);
        if (ok && cur == first && steps == ne) {
            cert *ct = &k->cert[k->ncert];
            ct->start = start;
            ct->len = (uint32_t)ne;
            b->cert = (uint32_t)k->ncert++;
        }
    }
    return 0;
}

/* ---- building ---- */

/* The hierarchy over the triangles not own (k: the parts common to both broad phases made);
 * c->tk = k. 0 or -ENOMEM (k freed). */
int fpc_tree_build(fp_contact *c, struct track *k)
{
    size_t t = c->t;
    k->tree = true;
    k->tpos = malloc((t ? t : 1) * sizeof *k->tpos);
    k->order = malloc((t ? t : 1) * sizeof *k->order);
    k->tn = malloc((t ? t : 1) * sizeof *k->tn);
    k->tbox = malloc((t ? t : 1) * sizeof *k->tbox);
    /* (the stamps: calloc, not zalloc: the build below writes every one in use) */
    k->pstamp = calloc(t ? t : 1, sizeof *k->pstamp);
    k->node = aligned_alloc(64, (t ? 2 * t : 1) * sizeof *k->node);
    k->nstamp = calloc(t ? 2 * t : 1, sizeof *k->nstamp);
    k->vtp = malloc((t ? 3 * t : 1) * sizeof *k->vtp);
    k->bstamp = calloc(((t ? t : 1) >> FP_BLOCK_SHIFT) + 1, sizeof *k->bstamp);
    k->sbstamp = calloc(((t ? t : 1) >> FP_SUPER_SHIFT) + 1, sizeof *k->sbstamp);
    k->vstamp = malloc((c->n ? c->n : 1) * sizeof *k->vstamp);
    k->has_own = malloc(c->n ? c->n : 1);
    if (!k->tpos || !k->order || !k->tn || !k->tbox || !k->pstamp || !k->node || !k->bstamp || !k->sbstamp ||
        !k->nstamp || !k->vtp || !k->vstamp || !k->has_own) {
        fpc_track_free(k);
        return -ENOMEM;
    }
    /* the hierarchy over the triangles not own */
    size_t m = 0;
    for (size_t i = 0; i < t; i++) {
        k->tpos[i] = FP_TRACK_NONE;
        if (!c->own[i]) k->order[m++] = (uint32_t)i;
    }
    if (m && cluster_build(c, k, m)) {
        fpc_track_free(k);
        return -ENOMEM;
    }
    for (size_t i = 0; i < m; i++) k->tpos[k->order[i]] = (uint32_t)i;
    for (size_t j = 0; j < 3 * t; j++) k->vtp[j] = k->tpos[k->vt[j]]; /* vt's places */
    for (size_t v = 0; v < c->n; v++) { /* (every byte written: no page faults in a frame) */
        uint8_t own = 0;
        for (uint32_t j = k->vt_start[v]; j < k->vt_start[v + 1]; j++) own |= k->vtp[j] == FP_TRACK_NONE;
        k->has_own[v] = own;
    }
    k->ow = malloc((m ? m : 1) * sizeof *k->ow);
    k->ov = malloc((m ? m : 1) * sizeof *k->ov);
    if (!k->ow || !k->ov) {
        fpc_track_free(k);
        return -ENOMEM;
    }
    for (size_t i = 0; i < m; i++)
        for (int j = 0; j < 3; j++) {
            k->ov[i][j] = c->tris[3 * (size_t)k->order[i] + j];
            k->ow[i][j] = c->weld[k->ov[i][j]];
        }
    if (m) {
        uint64_t *e;
        size_t ne, cap_cyc = 0, cap_cert = 0;
        memset(k->vstamp, 0, c->n * sizeof *k->vstamp); /* boundary's check numbers: from 1 */
        k->bgen = 0;
        k->bidx = malloc((c->n ? c->n : 1) * sizeof *k->bidx);
        if (!k->bidx || boundary(c, k, 0, &e, &ne, &cap_cyc, &cap_cert)) {
            free(k->bidx);
            k->bidx = NULL;
            fpc_track_free(k);
            return -ENOMEM;
        }
        free(k->bidx);
        k->bidx = NULL;
        free(e);
    }
    /* every triangle's normal and every node's boxes in P */
    k->tclock = k->rclock = 1;
    for (size_t v = 0; v < c->n; v++) k->vstamp[v] = 1; /* (vstamp's pages written here) */
    for (size_t i = 0; i <= (t ? t : 1) >> FP_BLOCK_SHIFT; i++) k->bstamp[i] = 1;
    for (size_t i = 0; i <= (t ? t : 1) >> FP_SUPER_SHIFT; i++) k->sbstamp[i] = 1;
    c->tk = k;
    fpc_tree_update(c, k->p, NULL, false); /* no flips counted: no failure */
    k->nmq = 0;
    k->rclock = 2; /* the region: empty, as D_P */
    /* the room a check's scratch grows to, made now (a gesture's first frame on the 1.7M
     * face grew it with about 70 page faults): each lane's contour for the longest cycle,
     * its moved places for a task of the walk's grain, its share of the marking's moved
     * vertices for a support of up to a sixteenth of the mesh; more still grows as needed */
    size_t maxcyc = 3, g = 1, nmv = c->n / 16 + 1;
    for (size_t i = 0; i < k->ncert; i++) maxcyc = k->cert[i].len > maxcyc ? k->cert[i].len : maxcyc;
    while (g * g < maxcyc) g++;
    int rc = reserve_written((void **)&k->mv, &k->cap_mv, nmv, sizeof *k->mv);
    for (int i = 0; i < FP_CONTACT_MAX_THREADS && !rc; i++) {
        lane *ln = &k->lane[i];
        rc = reserve_written((void **)&ln->xy, &ln->cap_xy, 2 * maxcyc, sizeof *ln->xy) ||
             reserve_written((void **)&ln->grange, &ln->cap_grange, maxcyc, sizeof *ln->grange) ||
             reserve_written((void **)&ln->sbox, &ln->cap_sbox, maxcyc, sizeof *ln->sbox) ||
             reserve_written((void **)&ln->gcount, &ln->cap_gcount, g * g + 1, sizeof *ln->gcount) ||
             reserve_written((void **)&ln->gseg, &ln->cap_gseg, 16 * maxcyc, sizeof *ln->gseg) ||
             reserve_written((void **)&ln->mq, &ln->cap_mq, m < FP_WALK_GRAIN ? m + 1 : FP_WALK_GRAIN,
                             sizeof *ln->mq) ||
             reserve_written((void **)&ln->mv, &ln->cap_mv, nmv / 2 + 1, sizeof *ln->mv);
    }
    if (rc) {
        c->tk = NULL;
        fpc_track_free(k);
        return -ENOMEM;
    }
    return 0;
}

