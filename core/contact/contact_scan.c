/* The contact guard's index (the weld, the input's own crossings, the rest normals) and its
 * full check: the moved region's grid, the sweep, the pair test, and the stateless guard's
 * bisection (fp_contact.h: fp_contact_create, fp_contact_count_new, fp_contact_guard). */
#include "contact_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FP_CONTACT_CELL 1.0 /* the grid cell over the mean moved triangle extent */

/* One triangle in one cell of the check's grid (scan): the cell's index x + dx (y + dy z) in
 * the region's grid; sorted by it, a cell's triangles lie together. */
typedef struct cellrec {
    uint64_t key;
    uint32_t tri;
    uint32_t flags; /* bit 0: the triangle moved; bits 1-3: on which axes (bit k + 1 for axis
                       k) its box's lower corner lies in this cell */
} cellrec;

/* A triangle of the cell the sweep is in (scan): its box, and on which axes its box's lower
 * corner lies in this cell (bit k for axis k) */
typedef struct cellrun {
    float box[6];
    uint32_t tri, moved, lo;
    uint32_t w[3]; /* its welded vertices */
} cellrun;

static long scan(fp_contact *c, const float *ref, const float *cand, bool all, uint32_t *pairs,
                 size_t max_pairs, fp_contact_count *info);

/* ---- the index ------------------------------------------------------------------------------ */

/* A vertex with its position's sort keys, for the weld: keys ordered as the floats' values
 * under < (sign bit flipped, or every bit for a negative; -0 as +0, which < does not tell
 * apart), so that the order is that of (x, y, z) by value, then the index. */
typedef struct weld_item {
    uint32_t key[3];
    uint32_t v;
} weld_item;

static uint32_t float_key(float f)
{
    uint32_t u;
    if (f == 0) f = 0; /* -0 as +0 */
    memcpy(&u, &f, sizeof u);
    return u & 0x80000000u ? ~u : u | 0x80000000u;
}

/* LSD radix sort of (*r)[0, m) by (key[0], key[1], key[2]), ties in their order (stable),
 * through tmp (room for m); the sorted items end in *r. No state outside the arguments: two
 * creates on two threads do not meet (fp_contact.h: one fp_contact per thread). */
static void sort_weld(weld_item **r, weld_item **tmp, size_t m)
{
    enum { D = 11, B = 1 << D };
    size_t cnt[B];
    for (int axis = 2; axis >= 0; axis--)
        for (int sh = 0; sh < 32; sh += D) {
            const weld_item *src = *r;
            weld_item *dst = *tmp;
            memset(cnt, 0, B * sizeof *cnt);
            for (size_t i = 0; i < m; i++) cnt[(src[i].key[axis] >> sh) & (B - 1)]++;
            if (!m || cnt[(src[0].key[axis] >> sh) & (B - 1)] == m) continue; /* one digit */
            size_t sum = 0;
            for (size_t d = 0; d < B; d++) {
                size_t n = cnt[d];
                cnt[d] = sum;
                sum += n;
            }
            for (size_t i = 0; i < m; i++) dst[cnt[(src[i].key[axis] >> sh) & (B - 1)]++] = src[i];
            *tmp = *r;
            *r = dst;
        }
}

int fp_contact_create(const uint32_t *tris, size_t t, size_t n, const float *weld, fp_contact **out)
{
    *out = NULL;
    if ((t && !tris) || (n && !weld)) return -EINVAL;
    for (size_t i = 0; i < 3 * t; i++)
        if (tris[i] >= n) return -EINVAL;
    fp_contact *c = calloc(1, sizeof *c);
    if (!c) return -ENOMEM;
    c->tris = tris;
    c->t = t;
    c->n = n;
    c->prewarm = FP_CONTACT_PREWARM;
    c->certify = true;
    c->carry = true;
    c->gallop_min = FP_CONTACT_GALLOP_MIN_TRIS;
    c->threads = 1;
    c->share_min = FP_CONTACT_SHARE_MIN;
    c->weld = malloc((n ? n : 1) * sizeof *c->weld);
    c->moved = malloc(n ? n : 1);
    c->ins = malloc((t ? t : 1) * sizeof *c->ins);
    c->box = malloc((t ? t : 1) * sizeof *c->box);
    /* the items and the sort's spare room in one block: at 1.7M vertices (54 MB) over glibc's
     * largest dynamic mmap threshold (32 MB), so freeing it leaves the threshold alone. Two
     * blocks of 27 MB raised it, and fp_contact_reference on the 1.7M face then took 0.3-0.8
     * s longer (not with the threshold fixed through GLIBC_TUNABLES) */
    weld_item *items = malloc(2 * (n ? n : 1) * sizeof *items), *order = items, *spare = items + (n ? n : 1);
    if (!c->weld || !c->moved || !c->ins || !c->box || !items) {
        free(items);
        fp_contact_destroy(&c);
        return -ENOMEM;
    }
    for (size_t v = 0; v < n; v++) {
        for (int k = 0; k < 3; k++) order[v].key[k] = float_key(weld[3 * v + k]);
        order[v].v = (uint32_t)v;
    }
    sort_weld(&order, &spare, n);
    /* a vertex welds to the first of the run of its position's bits (same value, same sign) */
    for (size_t i = 0; i < n; i++) {
        bool same = i && !memcmp(weld + 3 * (size_t)order[i].v, weld + 3 * (size_t)order[i - 1].v,
                                 3 * sizeof(float));
        c->weld[order[i].v] = same ? c->weld[order[i - 1].v] : order[i].v;
    }
    free(items);
    c->weld_copy = malloc((n ? n : 1) * 3 * sizeof(float));
    if (!c->weld_copy) {
        fp_contact_destroy(&c);
        return -ENOMEM;
    }
    memcpy(c->weld_copy, weld, n * 3 * sizeof(float));
    c->own = calloc(t ? t : 1, 1);
    c->nrm = malloc((t ? t : 1) * sizeof *c->nrm);
    if (!c->own || !c->nrm) {
        fp_contact_destroy(&c);
        return -ENOMEM;
    }
    for (size_t i = 0; i < t; i++) {
        double tr[3][3], e1[3], e2[3];
        tri_of(weld, tris + 3 * i, tr);
        for (int k = 0; k < 3; k++) {
            e1[k] = tr[1][k] - tr[0][k];
            e2[k] = tr[2][k] - tr[0][k];
        }
        double nr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        double l = sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
        for (int k = 0; k < 3; k++) c->nrm[i][k] = l > 0 ? (float)(nr[k] / l) : 0.f; /* unit */
    }
    if (scan(c, NULL, weld, true, NULL, 0, NULL) < 0) {
        fp_contact_destroy(&c);
        return -ENOMEM;
    }
    *out = c;
    return 0;
}

int fp_contact_dilate_own(fp_contact *c, int rings)
{
    fpc_bg_join(c);
    uint8_t *mark = calloc(c->n ? c->n : 1, 1);
    if (!mark) return -ENOMEM;
    for (int r = 0; r < rings; r++) {
        for (size_t i = 0; i < c->t; i++)
            if (c->own[i])
                for (int k = 0; k < 3; k++) mark[c->weld[c->tris[3 * i + k]]] = 1;
        for (size_t i = 0; i < c->t; i++)
            for (int k = 0; k < 3; k++)
                if (mark[c->weld[c->tris[3 * i + k]]]) c->own[i] = 1;
    }
    free(mark);
    return 0;
}

void fp_contact_destroy(fp_contact **cp)
{
    fp_contact *c = *cp;
    if (!c) return;
    fpc_bg_join(c);
    free(c->weld);
    free(c->moved);
    free(c->ins);
    free(c->box);
    free(c->rec);
    free(c->rec_tmp);
    free(c->run);
    free(c->own);
    free(c->nrm);
    free(c->nrm_weld);
    fpc_track_free(c->tk);
    free(c->weld_copy);
    free(c);
    *cp = NULL;
}

/* ---- the check ------------------------------------------------------------------------------ */

/* a coordinate's cell along one axis of the check's grid: x = (coordinate - region's lower
 * side) / cell, clamped to [0, 2^21] (NaN to 0); monotonic in x */
static inline uint64_t cell_ix(double x)
{
    return x > 0 ? (x < 0x1p21 ? (uint64_t)x : (uint64_t)1 << 21) : 0;
}

/* LSD radix sort of (*r)[0, m) by key, whose set bits lie below `bits`, through tmp (room for
 * m): stable; the sorted records end in *r (the buffers swapped when an odd number of passes
 * ran). A digit every record shares is skipped. */
static void sort_cells(cellrec **r, cellrec **tmp, size_t m, int bits)
{
    enum { D = 11, B = 1 << D };
    size_t cnt[B];
    for (int sh = 0; sh < bits; sh += D) {
        const cellrec *src = *r;
        cellrec *dst = *tmp;
        memset(cnt, 0, B * sizeof *cnt);
        for (size_t i = 0; i < m; i++) cnt[(src[i].key >> sh) & (B - 1)]++;
        if (cnt[(src[0].key >> sh) & (B - 1)] == m) continue;
        size_t sum = 0;
        for (size_t d = 0; d < B; d++) {
            size_t n = cnt[d];
            cnt[d] = sum;
            sum += n;
        }
        for (size_t i = 0; i < m; i++) dst[cnt[(src[i].key >> sh) & (B - 1)]++] = src[i];
        *tmp = *r;
        *r = dst;
    }
}

unsigned fpc_flips(const fp_contact *c, const float *pos, const uint32_t *v, size_t i)
{
    double t[3][3], e1[3], e2[3];
    tri_of(pos, v, t);
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    return flips_n(c, n, i);
}

/* One pair of the check (scan): a moved, b near it (both moved: a the lower), their boxes
 * meeting in cand, not adjacent. Adds to *found when they cross in cand and (ref not NULL)
 * not in ref, away from the input's own crossings; ref NULL: marks both own. */
static void scan_pair(fp_contact *c, const float *ref, const float *cand, uint32_t a, uint32_t b,
                      uint32_t *pairs, size_t max_pairs, long *found, fp_contact_count *info)
{
    const uint32_t *va = c->tris + 3 * (size_t)a, *vb = c->tris + 3 * (size_t)b;
    double ta[3][3], tb[3][3];
    tplane pa;
    tri_of(cand, va, ta);
    plane_of(ta, &pa);
    if (pa.deg) return;
    tri_of(cand, vb, tb);
    if (!meets_pl(ta, &pa, tb)) return;
    if (!ref) { /* the weld shape's own crossings */
        c->own[a] = c->own[b] = 1;
        ++*found;
        return;
    }
    double ra[3][3], rb[3][3];
    tplane pra;
    tri_of(ref, va, ra);
    plane_of(ra, &pra);
    tri_of(ref, vb, rb);
    if (!pra.deg && meets_pl(ra, &pra, rb)) return;
    if (c->own[a] || c->own[b]) { /* next to the input's own crossings */
        if (info) info->near_own++;
        return;
    }
    if (pairs && (size_t)*found < max_pairs) {
        pairs[2 * *found] = a < b ? a : b;
        pairs[2 * *found + 1] = a < b ? b : a;
    }
    ++*found;
}

#define FP_SCAN_BATCH 64 /* pairs of a cell filtered at once (scan) */

/* The pairs of a moved triangle and a triangle near it that cross in cand and (ref not NULL)
 * not in ref; all: every triangle counts as moved (ref NULL: the weld shape's own crossings,
 * marked in c->own). The broad phase: a uniform grid over the moved region (cell: the mean
 * moved extent), each triangle whose box meets the region recorded in every cell its box
 * covers, the records sorted by cell (no hashing: a cell's triangles are read together, in
 * the order of the cells); in each cell every pair with a moved triangle whose boxes meet is
 * taken, once: in the cell of its boxes' common lower corner. */
static long scan(fp_contact *c, const float *ref, const float *cand, bool all, uint32_t *pairs,
                 size_t max_pairs, fp_contact_count *info)
{
    size_t nm = 0;
    for (size_t v = 0; v < c->n; v++)
        c->moved[v] = all || memcmp(ref + 3 * v, cand + 3 * v, 3 * sizeof(float)) != 0;
    float reg[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    double cell = 0, sum = 0;
    for (size_t i = 0; i < c->t; i++) {
        const uint32_t *v = c->tris + 3 * i;
        if (!(c->moved[v[0]] | c->moved[v[1]] | c->moved[v[2]])) continue;
        nm++;
        float b[6];
        tri_box(cand, v, b);
        double ext = 0;
        for (int k = 0; k < 3; k++) {
            reg[k] = fminf(reg[k], b[k]);
            reg[3 + k] = fmaxf(reg[3 + k], b[3 + k]);
            ext = fmax(ext, (double)b[3 + k] - b[k]);
        }
        cell = fmax(cell, ext);
        sum += ext;
        /* a triangle turned over against its rest normal (and not already in ref); own
         * triangles too: a flip is no crossing, the input's own crossings do not excuse it */
        if (info && ref && fpc_new_flip(c, fpc_flips(c, cand, v, i), ref, v, i))
            info->flipped++;
    }
    if (info) info->moved_tris = nm;
    if (!nm) return 0;
    /* the cell: the mean moved extent, at most 32 cells across the largest one (a few
     * large triangles, the back of a head, must not make one cell of the whole region), at
     * most 2^20 cells along an axis (a cell's index fits 64 bits) */
    cell = fmax(FP_CONTACT_CELL * sum / (double)nm, cell / 32.0);
    for (int k = 0; k < 3; k++) cell = fmax(cell, ((double)reg[3 + k] - reg[k]) * 0x1p-20);
    if (!(cell > 0)) cell = 1e-9;
    const double ic = 1.0 / cell;
    /* cells of a box (clamped to the region: every moved box lies inside it) */
#define CELL_RANGE(b, lo, hi)                                                                  \
    for (int k = 0; k < 3; k++) {                                                              \
        lo[k] = cell_ix(((double)fmaxf((b)[k], reg[k]) - reg[k]) * ic);                         \
        hi[k] = cell_ix(((double)fminf((b)[3 + k], reg[3 + k]) - reg[k]) * ic);                 \
    }
    uint64_t dim[3];
    for (int k = 0; k < 3; k++) dim[k] = cell_ix(((double)reg[3 + k] - reg[k]) * ic) + 1;
    int bits = 0;
    while (bits < 64 && (dim[0] * dim[1] * dim[2] - 1) >> bits) bits++;
    /* the triangles whose candidate box meets the moved region, and their cells */
    size_t ni = 0, ne = 0;
    for (size_t i = 0; i < c->t; i++) {
        float b[6];
        tri_box(cand, c->tris + 3 * i, b);
        if (!boxes_meet(b, reg)) continue;
        memcpy(c->box[i], b, sizeof b);
        c->ins[ni++] = (uint32_t)i;
        uint64_t lo[3], hi[3];
        CELL_RANGE(b, lo, hi)
        ne += (size_t)((hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1));
    }
    if (ne > c->rec_cap) { /* (not reserve: the two buffers trade places in the sort, so
                            * they share one capacity, and neither's records need keeping) */
        free(c->rec);
        free(c->rec_tmp);
        c->rec_cap = ne + ne / 4;
        c->rec = malloc(c->rec_cap * sizeof *c->rec);
        c->rec_tmp = malloc(c->rec_cap * sizeof *c->rec_tmp);
        if (!c->rec || !c->rec_tmp) {
            free(c->rec);
            free(c->rec_tmp);
            c->rec = c->rec_tmp = NULL;
            c->rec_cap = 0;
            return -ENOMEM;
        }
    }
    cellrec *rec = c->rec;
    size_t w = 0;
    for (size_t j = 0; j < ni; j++) {
        uint32_t i = c->ins[j];
        const uint32_t *v = c->tris + 3 * (size_t)i;
        uint32_t moved = c->moved[v[0]] | c->moved[v[1]] | c->moved[v[2]];
        uint64_t lo[3], hi[3];
        CELL_RANGE(c->box[i], lo, hi)
        for (uint64_t z = lo[2]; z <= hi[2]; z++)
            for (uint64_t y = lo[1]; y <= hi[1]; y++)
                for (uint64_t x = lo[0]; x <= hi[0]; x++)
                    rec[w++] = (cellrec){x + dim[0] * (y + dim[1] * z), i,
                                         moved | (uint32_t)(x == lo[0]) << 1 | (uint32_t)(y == lo[1]) << 2 |
                                             (uint32_t)(z == lo[2]) << 3};
    }
    sort_cells(&c->rec, &c->rec_tmp, ne, bits);
    rec = c->rec;
    /* the sweep: each cell's triangles, every pair once */
    long found = 0;
    for (size_t r0 = 0, r1; r0 < ne; r0 = r1) {
        uint64_t key = rec[r0].key;
        for (r1 = r0 + 1; r1 < ne && rec[r1].key == key; r1++) {
        }
        size_t m = r1 - r0;
        if (m < 2) continue;
        if (reserve((void **)&c->run, &c->run_cap, m, sizeof *c->run)) return -ENOMEM;
        cellrun *run = c->run;
        for (size_t i = 0; i < m; i++) {
            cellrun *u = &run[i];
            u->tri = rec[r0 + i].tri;
            u->moved = rec[r0 + i].flags & 1;
            u->lo = rec[r0 + i].flags >> 1;
            memcpy(u->box, c->box[u->tri], sizeof u->box);
            for (int k = 0; k < 3; k++) u->w[k] = c->weld[c->tris[3 * (size_t)u->tri + k]];
        }
        /* (i, j), i < j, with a moved triangle, boxes meeting, their common lower corner in
         * this cell (cell_ix is monotonic: on each axis one of the two lower corners is
         * here, both boxes covering this cell), filtered without a branch */
        for (size_t i = 0; i + 1 < m; i++) {
            const cellrun *u = &run[i];
            for (size_t j0 = i + 1; j0 < m; j0 += FP_SCAN_BATCH) {
                size_t j1 = m - j0 > FP_SCAN_BATCH ? j0 + FP_SCAN_BATCH : m, nh = 0;
                uint32_t hit[FP_SCAN_BATCH];
                for (size_t j = j0; j < j1; j++) {
                    hit[nh] = (uint32_t)j;
                    nh += (u->moved | run[j].moved) & (uint32_t)boxes_meet(u->box, run[j].box) &
                          (uint32_t)((u->lo | run[j].lo) == 7);
                }
                for (size_t h = 0; h < nh; h++) {
                    const cellrun *q = &run[hit[h]];
                    if (welded_adjacent(u->w, q->w)) continue;
                    /* a: the moved one (both: the lower) */
                    bool lower = u->moved && (!q->moved || u->tri < q->tri);
                    uint32_t a = lower ? u->tri : q->tri, b = lower ? q->tri : u->tri;
                    scan_pair(c, ref, cand, a, b, pairs, max_pairs, &found, info);
                }
            }
        }
    }
#undef CELL_RANGE
    return found;
}

long fp_contact_count_new(fp_contact *c, const float *ref, const float *cand, uint32_t *pairs,
                          size_t max_pairs, fp_contact_count *info)
{
    if (info) memset(info, 0, sizeof *info);
    fpc_bg_join(c);
    return scan(c, ref, cand, false, pairs, max_pairs, info);
}

static void lerp(const fp_contact *c, const float *ref, const float *cand, double t, float *out)
{
    if (t >= 1) {
        memcpy(out, cand, c->n * 3 * sizeof(float));
        return;
    }
    memcpy(out, ref, c->n * 3 * sizeof(float));
    if (t <= 0) return;
    for (size_t i = 0; i < 3 * c->n; i++)
        if (cand[i] != ref[i]) out[i] = (float)((double)ref[i] + t * ((double)cand[i] - ref[i]));
}

int fp_contact_guard(fp_contact *c, const float *ref, const float *cand, float *out, int iters,
                     fp_contact_result *res)
{
    memset(res, 0, sizeof *res);
    res->t = res->kept = 1;
    fp_contact_count info;
    long k = fp_contact_count_new(c, ref, cand, NULL, 0, &info);
    res->moved_tris = info.moved_tris;
    res->flipped = info.flipped;
    res->checks = 1;
    if (k < 0) {
        lerp(c, ref, cand, 0, out);
        res->t = res->kept = 0;
        return (int)k;
    }
    res->pairs = k;
    k += (long)info.flipped;
    if (!k) {
        lerp(c, ref, cand, 1, out);
        return 0;
    }
    double lo = 0, hi = 1;
    for (int i = 0; i < iters; i++) {
        double mid = 0.5 * (lo + hi);
        lerp(c, ref, cand, mid, out);
        long m = fp_contact_count_new(c, ref, out, NULL, 0, &info);
        if (m >= 0) m += (long)info.flipped;
        res->checks++;
        if (m < 0) {
            lo = 0;
            break;
        }
        if (m) hi = mid;
        else lo = mid;
    }
    lerp(c, ref, cand, lo, out);
    res->t = res->kept = lo;
    return 0;
}
