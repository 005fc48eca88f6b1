/* sheet_bind.c: close sheets carried together (sheet_bind.h). */
#include "sheet_bind.h"
#include "weld.h"

#include <assert.h>
#include <stdbool.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- the nearest point of a triangle (Ericson, Real-Time Collision Detection, 5.1.5) ---- */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* barycentric coordinates (of a, b, c) of the point of triangle abc nearest p */
static void nearest_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double bary[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
        bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) { bary[0] = 1, bary[1] = bary[2] = 0; return; }
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) { bary[1] = 1, bary[0] = bary[2] = 0; return; }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        bary[0] = 1 - v, bary[1] = v, bary[2] = 0;
        return;
    }
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) { bary[2] = 1, bary[0] = bary[1] = 0; return; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        bary[0] = 1 - w, bary[1] = 0, bary[2] = w;
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        bary[0] = 0, bary[1] = 1 - w, bary[2] = w;
        return;
    }
    double den = 1 / (va + vb + vc);
    bary[1] = vb * den, bary[2] = vc * den, bary[0] = 1 - bary[1] - bary[2];
}

/* ---- the candidates ------------------------------------------------------------------------ */

typedef struct cand {
    double dist;
    uint32_t v, t;
    float bary[3];
} cand;

static int by_dist(const void *a, const void *b)
{
    const cand *p = a, *q = b;
    if (p->dist != q->dist) return p->dist < q->dist ? -1 : 1;
    return p->v != q->v ? (p->v < q->v ? -1 : 1) : (p->t > q->t) - (p->t < q->t);
}

/* a cell's key: its coordinates' bits interleaved (Morton order), so that cells near in space
 * are mostly near in the grid's sorted entries */
static uint64_t spread(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffu;
    x = (x | x << 16) & 0x1f0000ff0000ffu;
    x = (x | x << 8) & 0x100f00f00f00f00fu;
    x = (x | x << 4) & 0x10c30c30c30c30c3u;
    x = (x | x << 2) & 0x1249249249249249u;
    return x;
}

static uint64_t cell_key(long i, long j, long k)
{
    return spread((uint64_t)i) | spread((uint64_t)j) << 1 | spread((uint64_t)k) << 2;
}

typedef struct cell_tri {
    uint64_t cell;
    uint32_t t;
} cell_tri;

/* sorts by cell (stable: by triangle within a cell, as they were made), 11 bits a pass up to
 * the highest bit of max_key. Returns 0 or -ENOMEM. */
static int radix_sort(cell_tri *a, size_t count, uint64_t max_key)
{
    cell_tri *tmp = malloc((count + 1) * sizeof *tmp);
    size_t *hist = malloc(2049 * sizeof *hist);
    if (!tmp || !hist) {
        free(tmp), free(hist);
        return -ENOMEM;
    }
    for (int shift = 0; shift < 64 && (max_key >> shift); shift += 11) {
        memset(hist, 0, 2049 * sizeof *hist);
        for (size_t i = 0; i < count; i++) hist[((a[i].cell >> shift) & 2047) + 1]++;
        for (int d = 0; d < 2048; d++) hist[d + 1] += hist[d];
        for (size_t i = 0; i < count; i++) tmp[hist[(a[i].cell >> shift) & 2047]++] = a[i];
        memcpy(a, tmp, count * sizeof *a);
    }
    free(tmp), free(hist);
    return 0;
}

/* every triangle under each cell its box meets, sorted by cell */
typedef struct grid {
    cell_tri *ct;
    float (*box)[6];  /* each triangle's box: low corner, high corner */
    size_t count;
    double lo[3], cell;
} grid;

static long cell_of(const grid *g, double x, int k) { return (long)floor((x - g->lo[k]) / g->cell); }

static int grid_build(grid *g, const float *pos, const uint32_t *tris, size_t t, double cell)
{
    memset(g, 0, sizeof *g);
    g->cell = cell;
    for (int k = 0; k < 3; k++) g->lo[k] = INFINITY;
    for (size_t i = 0; i < 3 * t; i++)
        for (int k = 0; k < 3; k++) g->lo[k] = fmin(g->lo[k], pos[3 * (size_t)tris[i] + k]);
    size_t cap = 2 * t + 16;
    uint64_t max_key = 0;
    g->ct = malloc(cap * sizeof *g->ct);
    g->box = malloc((t + 1) * sizeof *g->box);
    if (!g->ct || !g->box) return -ENOMEM;
    for (size_t f = 0; f < t; f++) {
        long lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            double a = pos[3 * (size_t)tris[3 * f] + k], b = a;
            for (int c = 1; c < 3; c++) {
                double x = pos[3 * (size_t)tris[3 * f + c] + k];
                a = x < a ? x : a, b = x > b ? x : b;
            }
            lo[k] = cell_of(g, a, k), hi[k] = cell_of(g, b, k);
            g->box[f][k] = (float)a, g->box[f][3 + k] = (float)b;
        }
        for (long i = lo[0]; i <= hi[0]; i++)
            for (long j = lo[1]; j <= hi[1]; j++)
                for (long k = lo[2]; k <= hi[2]; k++) {
                    if (g->count == cap) {
                        cell_tri *grown = realloc(g->ct, 2 * cap * sizeof *grown);
                        if (!grown) return -ENOMEM;
                        g->ct = grown, cap *= 2;
                    }
                    g->ct[g->count++] = (cell_tri){cell_key(i, j, k), (uint32_t)f};
                    max_key |= g->ct[g->count - 1].cell;
                }
    }
    return radix_sort(g->ct, g->count, max_key);
}

/* the first entry of a cell, or count */
static size_t grid_find(const grid *g, uint64_t key)
{
    size_t lo = 0, hi = g->count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (g->ct[mid].cell < key) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

static void grid_free(grid *g) { free(g->ct), free(g->box); }

/* the vertices in the order of their cells (queries near in space run one after another) */
typedef struct vkey {
    uint64_t cell;
    uint32_t v;
} vkey;

static int by_vkey(const void *a, const void *b)
{
    const vkey *p = a, *q = b;
    if (p->cell != q->cell) return p->cell < q->cell ? -1 : 1;
    return (p->v > q->v) - (p->v < q->v);
}

/* ---- vertex rings ------------------------------------------------------------------------ */

typedef struct rings {
    uint32_t *start, *adj; /* CSR over welded vertices */
    uint32_t *stamp, *queue;
    uint32_t now;
} rings;

static int rings_build(rings *r, const uint32_t *weld, size_t n, const uint32_t *tris, size_t t)
{
    memset(r, 0, sizeof *r);
    r->start = calloc(n + 1, sizeof *r->start);
    r->adj = malloc(6 * t * sizeof *r->adj + 1);
    r->stamp = calloc(n, sizeof *r->stamp);
    r->queue = malloc(n * sizeof *r->queue + 1);
    if (!r->start || !r->adj || !r->stamp || !r->queue) return -ENOMEM;
    for (size_t f = 0; f < t; f++)
        for (int c = 0; c < 3; c++) r->start[weld[tris[3 * f + c]] + 1] += 2;
    for (size_t v = 0; v < n; v++) r->start[v + 1] += r->start[v];
    uint32_t *fill = r->stamp; /* (zero again after) */
    for (size_t f = 0; f < t; f++)
        for (int c = 0; c < 3; c++) {
            uint32_t a = weld[tris[3 * f + c]];
            r->adj[r->start[a] + fill[a]++] = weld[tris[3 * f + (c + 1) % 3]];
            r->adj[r->start[a] + fill[a]++] = weld[tris[3 * f + (c + 2) % 3]];
        }
    memset(r->stamp, 0, n * sizeof *r->stamp);
    return 0;
}

/* stamps the welded vertices within `depth` rings of w */
static void rings_mark(rings *r, uint32_t w, int depth)
{
    r->now++;
    size_t head = 0, tail = 0, level_end;
    r->queue[tail++] = w;
    r->stamp[w] = r->now;
    for (int d = 0; d < depth; d++) {
        level_end = tail;
        for (; head < level_end; head++) {
            uint32_t a = r->queue[head];
            for (uint32_t e = r->start[a]; e < r->start[a + 1]; e++)
                if (r->stamp[r->adj[e]] != r->now) r->stamp[r->adj[e]] = r->now, r->queue[tail++] = r->adj[e];
        }
    }
}

static void rings_free(rings *r) { free(r->start), free(r->adj), free(r->stamp), free(r->queue); }

static int by_follower(const void *a, const void *b)
{
    const cand *p = a, *q = b;
    return (p->v > q->v) - (p->v < q->v);
}

/* ---- build ----------------------------------------------------------------------------------- */

int fp_sheet_bind_build(const float *pos, size_t n, const uint32_t *tris, size_t t, fp_sheet_bind *b)
{
    memset(b, 0, sizeof *b);
    if (!n || !t) return 0;
    int rc = -ENOMEM;
    grid g = {0};
    rings r = {0};
    cand *cs = NULL;
    vkey *order = NULL;
    size_t nc = 0, cap = 0;
    double *edge = calloc(n, sizeof *edge);
    uint32_t *deg = calloc(n, sizeof *deg), *weld = malloc(n * sizeof *weld);
    uint8_t *role = calloc(n, 1); /* 1 follower, 2 a leader's corner */
    if (!edge || !deg || !weld || !role || fp_weld_by_position(pos, n, weld, NULL)) goto out;
    /* each welded vertex's mean edge length */
    double sum = 0;
    for (size_t f = 0; f < t; f++)
        for (int c = 0; c < 3; c++) {
            uint32_t a = tris[3 * f + c], o = tris[3 * f + (c + 1) % 3];
            double l = 0;
            for (int k = 0; k < 3; k++) l += pow((double)pos[3 * (size_t)a + k] - pos[3 * (size_t)o + k], 2);
            l = sqrt(l);
            edge[weld[a]] += l, deg[weld[a]]++, edge[weld[o]] += l, deg[weld[o]]++;
            sum += l;
        }
    double mean = sum / (3.0 * (double)t);
    if (!(mean > 0)) { rc = 0; goto out; }
    if ((rc = grid_build(&g, pos, tris, t, mean)) || (rc = rings_build(&r, weld, n, tris, t))) goto out;
    rc = -ENOMEM;
    if (!(order = malloc(n * sizeof *order))) goto out;
    for (size_t v = 0; v < n; v++)
        order[v] = (vkey){cell_key(cell_of(&g, pos[3 * v], 0), cell_of(&g, pos[3 * v + 1], 1),
                                   cell_of(&g, pos[3 * v + 2], 2)), (uint32_t)v};
    qsort(order, n, sizeof *order, by_vkey);
    for (size_t o = 0; o < n; o++) {
        size_t v = order[o].v;
        uint32_t w = weld[v];
        if (!deg[w]) continue;
        double reach = FP_SHEET_BIND_GAP * edge[w] / deg[w];
        const float *p = pos + 3 * v;
        long lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = (long)floor((p[k] - reach - g.lo[k]) / g.cell);
            hi[k] = (long)floor((p[k] + reach - g.lo[k]) / g.cell);
        }
        bool marked = false;
        double best = reach;
        cand c = {.dist = INFINITY};
        for (long i = lo[0]; i <= hi[0]; i++)
            for (long j = lo[1]; j <= hi[1]; j++)
                for (long k = lo[2]; k <= hi[2]; k++) {
                    uint64_t key = cell_key(i, j, k);
                    for (size_t e = grid_find(&g, key); e < g.count && g.ct[e].cell == key; e++) {
                        const float *bx = g.box[g.ct[e].t];
                        if (p[0] + best < bx[0] || p[1] + best < bx[1] || p[2] + best < bx[2] ||
                            p[0] - best > bx[3] || p[1] - best > bx[4] || p[2] - best > bx[5])
                            continue; /* (its box is out of reach) */
                        const uint32_t *f = tris + 3 * (size_t)g.ct[e].t;
                        if (weld[f[0]] == w || weld[f[1]] == w || weld[f[2]] == w) continue; /* its own */
                        double a[3], bb[3], cc[3], q[3] = {p[0], p[1], p[2]}, by[3], d = 0;
                        for (int m = 0; m < 3; m++)
                            a[m] = pos[3 * (size_t)f[0] + m], bb[m] = pos[3 * (size_t)f[1] + m],
                            cc[m] = pos[3 * (size_t)f[2] + m];
                        nearest_on_triangle(q, a, bb, cc, by);
                        for (int m = 0; m < 3; m++) d += pow(q[m] - (by[0] * a[m] + by[1] * bb[m] + by[2] * cc[m]), 2);
                        d = sqrt(d);
                        if (!(d < best)) continue;
                        if (!marked) rings_mark(&r, w, FP_SHEET_BIND_RINGS), marked = true;
                        if ((r.stamp[weld[f[0]]] == r.now || r.stamp[weld[f[1]]] == r.now ||
                             r.stamp[weld[f[2]]] == r.now) &&
                            !(d < FP_SHEET_BIND_TUCK * edge[w] / deg[w]))
                            continue; /* its own sheet (but a tuck: the vertex on a triangle near it) */
                        best = d;
                        c = (cand){d, (uint32_t)v, g.ct[e].t, {(float)by[0], (float)by[1], (float)by[2]}};
                    }
                }
        if (c.dist == INFINITY) continue;
        if (nc == cap) {
            cand *grown = realloc(cs, (2 * cap + 64) * sizeof *grown);
            if (!grown) goto out;
            cs = grown, cap = 2 * cap + 64;
        }
        cs[nc++] = c;
    }
    if (nc) qsort(cs, nc, sizeof *cs, by_dist);
    b->follower = malloc((nc + 1) * sizeof *b->follower);
    b->leader = malloc((nc + 1) * sizeof *b->leader);
    b->bary = malloc((nc + 1) * sizeof *b->bary);
    b->gap = malloc((nc + 1) * sizeof *b->gap);
    if (!b->follower || !b->leader || !b->bary || !b->gap) goto out;
    /* nearest first; a vertex is never both a follower and a leader's corner (welded) */
    size_t kept = 0;
    for (size_t i = 0; i < nc; i++) {
        const uint32_t *f = tris + 3 * (size_t)cs[i].t;
        uint32_t w = weld[cs[i].v];
        if (role[w] == 2 || role[weld[f[0]]] == 1 || role[weld[f[1]]] == 1 || role[weld[f[2]]] == 1) continue;
        role[w] = 1;
        for (int c = 0; c < 3; c++) role[weld[f[c]]] = 2;
        cs[kept++] = cs[i];
    }
    if (kept) qsort(cs, kept, sizeof *cs, by_follower); /* (fp_sheet_bind_apply walks them by range) */
    for (size_t i = 0; i < kept; i++) {
        uint32_t w = weld[cs[i].v];
        b->follower[i] = cs[i].v;
        memcpy(b->leader[i], tris + 3 * (size_t)cs[i].t, sizeof b->leader[0]);
        memcpy(b->bary[i], cs[i].bary, sizeof b->bary[0]);
        b->gap[i] = (float)(FP_SHEET_BIND_GAP * edge[w] / deg[w]);
    }
    b->count = kept;
    rc = 0;
out:
    if (rc) fp_sheet_bind_free(b);
    grid_free(&g), free(order), rings_free(&r), free(cs), free(edge), free(deg), free(weld), free(role);
    return rc;
}

/* ---- apply ----------------------------------------------------------------------------------- */

static void unit_normal(const float *x, const uint32_t f[3], double n[3])
{
    double u[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = (double)x[3 * (size_t)f[1] + k] - x[3 * (size_t)f[0] + k],
        w[k] = (double)x[3 * (size_t)f[2] + k] - x[3 * (size_t)f[0] + k];
    n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
    double l = sqrt(dot3(n, n));
    for (int k = 0; k < 3; k++) n[k] = l > 0 ? n[k] / l : 0;
}

/* carries binding i (sheet_bind.h); returns whether it moved its follower */
static bool carry(const fp_sheet_bind *b, size_t i, const float *ref, float *x)
{
    uint32_t v = b->follower[i];
    const uint32_t *f = b->leader[i];
    const float *l = b->bary[i];
    assert(v != f[0] && v != f[1] && v != f[2]); /* a follower is never its leader's corner */
    double p0[3], p1[3], o[3], d = 0;
    for (int k = 0; k < 3; k++) {
        p0[k] = l[0] * ref[3 * (size_t)f[0] + k] + l[1] * ref[3 * (size_t)f[1] + k] + l[2] * ref[3 * (size_t)f[2] + k];
        p1[k] = l[0] * x[3 * (size_t)f[0] + k] + l[1] * x[3 * (size_t)f[1] + k] + l[2] * x[3 * (size_t)f[2] + k];
        o[k] = (double)ref[3 * (size_t)v + k] - p0[k];
        d += o[k] * o[k];
    }
    d = sqrt(d);
    if (!(d < b->gap[i])) return false; /* parted in the reference */
    if (!memcmp(x + 3 * (size_t)v, ref + 3 * (size_t)v, 3 * sizeof *x)) return false; /* outside the supports */
    double w = d <= 0.5 * b->gap[i] ? 1.0 : 2.0 * (1.0 - d / b->gap[i]);
    double n0[3], n1[3];
    unit_normal(ref, f, n0);
    unit_normal(x, f, n1);
    double on = dot3(o, n0);
    for (int k = 0; k < 3; k++) {
        double bound = p1[k] + o[k] - on * n0[k] + on * n1[k];
        x[3 * (size_t)v + k] = (float)(w * bound + (1 - w) * x[3 * (size_t)v + k]);
    }
    return true;
}

/* the first binding whose follower is at least v (they are sorted by follower) */
static size_t first_at(const fp_sheet_bind *b, uint32_t v)
{
    size_t lo = 0, hi = b->count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (b->follower[mid] < v) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

size_t fp_sheet_bind_apply(const fp_sheet_bind *b, const float *ref, float *x, const uint32_t *ranges,
                           size_t nranges)
{
    size_t moved = 0;
    if (!ranges) {
        for (size_t i = 0; i < b->count; i++) moved += carry(b, i, ref, x);
        return moved;
    }
    for (size_t r = 0; r < nranges; r++)
        for (size_t i = first_at(b, ranges[2 * r]); i < b->count && b->follower[i] - ranges[2 * r] < ranges[2 * r + 1]; i++)
            moved += carry(b, i, ref, x);
    return moved;
}

void fp_sheet_bind_free(fp_sheet_bind *b)
{
    free(b->follower), free(b->leader), free(b->bary), free(b->gap);
    memset(b, 0, sizeof *b);
}
