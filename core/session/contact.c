/* The contact guard: new self-crossings among moved triangles, and the bisection (contact.h). */
#include "contact.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#define FP_CONTACT_CELL 1.0 /* the grid cell over the mean moved triangle extent */



struct fp_contact {
    const uint32_t *tris;
    size_t t, n;
    uint32_t *weld;       /* n: the first vertex at the same position */
    uint8_t *moved;       /* n: vertex moved this check */
    uint32_t *mtris;      /* moved triangles */
    uint32_t *ins;        /* triangles in the grid */
    float (*box)[6];      /* t: candidate bounding box (min xyz, max xyz) of inserted ones */
    uint32_t *bucket_start;
    struct entry { float box[6]; uint32_t tri, moved; } *entries; /* the grid, by bucket */
    size_t bucket_cap, entry_cap;
    uint8_t *own;         /* t: the triangle crosses another in the weld shape */
    float (*nrm)[3];      /* t: the weld shape's triangle normals (unnormalised) */
};

/* ---- the triangle-triangle test ---------------------------------------------------------- */

static double orient3d(const double *p, const double *q, const double *r, const double *s)
{
    double ax = q[0] - p[0], ay = q[1] - p[1], az = q[2] - p[2];
    double bx = r[0] - p[0], by = r[1] - p[1], bz = r[2] - p[2];
    double cx = s[0] - p[0], cy = s[1] - p[1], cz = s[2] - p[2];
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
}

static double orient2d(const double *p, const double *q, const double *r)
{
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
}

static int sgn(double x) { return (x > 0) - (x < 0); }

/* r on the closed segment pq, given collinear */
static bool on_seg2(const double *p, const double *q, const double *r)
{
    return fmin(p[0], q[0]) <= r[0] && r[0] <= fmax(p[0], q[0]) && fmin(p[1], q[1]) <= r[1] &&
           r[1] <= fmax(p[1], q[1]);
}

static bool seg_seg2(const double *p, const double *q, const double *a, const double *b)
{
    int d1 = sgn(orient2d(p, q, a)), d2 = sgn(orient2d(p, q, b));
    int d3 = sgn(orient2d(a, b, p)), d4 = sgn(orient2d(a, b, q));
    if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    return (!d1 && on_seg2(p, q, a)) || (!d2 && on_seg2(p, q, b)) || (!d3 && on_seg2(a, b, p)) ||
           (!d4 && on_seg2(a, b, q));
}

static bool in_tri2(const double *p, const double t[3][2])
{
    int s1 = sgn(orient2d(t[0], t[1], p)), s2 = sgn(orient2d(t[1], t[2], p)),
        s3 = sgn(orient2d(t[2], t[0], p));
    return !((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0));
}

/* segment pq and triangle t in one plane: project away the normal's largest axis */
static bool seg_tri_coplanar(const double *p, const double *q, const double t[3][3])
{
    double e1[3], e2[3], nrm[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    nrm[0] = fabs(e1[1] * e2[2] - e1[2] * e2[1]);
    nrm[1] = fabs(e1[2] * e2[0] - e1[0] * e2[2]);
    nrm[2] = fabs(e1[0] * e2[1] - e1[1] * e2[0]);
    int drop = nrm[0] >= nrm[1] && nrm[0] >= nrm[2] ? 0 : nrm[1] >= nrm[2] ? 1 : 2;
    int i0 = drop == 0 ? 1 : 0, i1 = drop == 2 ? 1 : 2;
    double p2[2] = {p[i0], p[i1]}, q2[2] = {q[i0], q[i1]}, t2[3][2];
    for (int v = 0; v < 3; v++) {
        t2[v][0] = t[v][i0];
        t2[v][1] = t[v][i1];
    }
    if (in_tri2(p2, t2) || in_tri2(q2, t2)) return true;
    for (int v = 0; v < 3; v++)
        if (seg_seg2(p2, q2, t2[v], t2[(v + 1) % 3])) return true;
    return false;
}

/* closed segment pq against closed triangle t (not degenerate) */
static bool seg_tri(const double *p, const double *q, const double t[3][3])
{
    int op = sgn(orient3d(t[0], t[1], t[2], p)), oq = sgn(orient3d(t[0], t[1], t[2], q));
    if (op * oq > 0) return false;
    if (!op && !oq) return seg_tri_coplanar(p, q, t);
    int s1 = sgn(orient3d(p, q, t[0], t[1])), s2 = sgn(orient3d(p, q, t[1], t[2])),
        s3 = sgn(orient3d(p, q, t[2], t[0]));
    return !((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0));
}

int fp_contact_tri_tri(const double a[3][3], const double b[3][3])
{
    for (int e = 0; e < 3; e++)
        if (seg_tri(a[e], a[(e + 1) % 3], b) || seg_tri(b[e], b[(e + 1) % 3], a)) return 1;
    return 0;
}

typedef struct fp_contact_count fp_contact_count;
static void tri_of(const float *pos, const uint32_t *v, double out[3][3]);
static long scan(fp_contact *c, const float *ref, const float *cand, bool all, uint32_t *pairs,
                 size_t max_pairs, fp_contact_count *info);

/* ---- the index ------------------------------------------------------------------------------ */

static const float *weld_pos;

static int cmp_pos(const void *x, const void *y)
{
    const float *a = weld_pos + 3 * (size_t)*(const uint32_t *)x,
                *b = weld_pos + 3 * (size_t)*(const uint32_t *)y;
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return *(const uint32_t *)x < *(const uint32_t *)y ? -1 : 1;
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
    c->weld = malloc((n ? n : 1) * sizeof *c->weld);
    c->moved = malloc(n ? n : 1);
    c->mtris = malloc((t ? t : 1) * sizeof *c->mtris);
    c->ins = malloc((t ? t : 1) * sizeof *c->ins);
    c->box = malloc((t ? t : 1) * sizeof *c->box);
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    if (!c->weld || !c->moved || !c->mtris || !c->ins || !c->box || !order) {
        free(order);
        fp_contact_destroy(&c);
        return -ENOMEM;
    }
    for (size_t v = 0; v < n; v++) order[v] = (uint32_t)v;
    weld_pos = weld; /* qsort has no context argument in C11 */
    qsort(order, n, sizeof *order, cmp_pos);
    for (size_t i = 0; i < n; i++) {
        bool same = i && !memcmp(weld + 3 * (size_t)order[i], weld + 3 * (size_t)order[i - 1],
                                 3 * sizeof(float));
        c->weld[order[i]] = same ? c->weld[order[i - 1]] : order[i];
    }
    free(order);
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
        c->nrm[i][0] = (float)(e1[1] * e2[2] - e1[2] * e2[1]);
        c->nrm[i][1] = (float)(e1[2] * e2[0] - e1[0] * e2[2]);
        c->nrm[i][2] = (float)(e1[0] * e2[1] - e1[1] * e2[0]);
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
    free(c->weld);
    free(c->moved);
    free(c->mtris);
    free(c->ins);
    free(c->box);
    free(c->bucket_start);
    free(c->entries);
    free(c->own);
    free(c->nrm);
    free(c);
    *cp = NULL;
}

/* ---- the check ------------------------------------------------------------------------------ */

static void tri_of(const float *pos, const uint32_t *v, double out[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) out[i][k] = pos[3 * (size_t)v[i] + k];
}

static bool degenerate(const double t[3][3])
{
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    return e1[1] * e2[2] - e1[2] * e2[1] == 0 && e1[2] * e2[0] - e1[0] * e2[2] == 0 &&
           e1[0] * e2[1] - e1[1] * e2[0] == 0;
}

static void tri_box(const float *pos, const uint32_t *v, float b[6])
{
    for (int k = 0; k < 3; k++) {
        float a = pos[3 * (size_t)v[0] + k], m = pos[3 * (size_t)v[1] + k], z = pos[3 * (size_t)v[2] + k];
        b[k] = fminf(a, fminf(m, z));
        b[3 + k] = fmaxf(a, fmaxf(m, z));
    }
}

static bool boxes_meet(const float *a, const float *b)
{
    return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] && b[2] <= a[5];
}

static uint32_t cell_hash(long x, long y, long z)
{
    uint64_t h = (uint64_t)x * 73856093u ^ (uint64_t)y * 19349663u ^ (uint64_t)z * 83492791u;
    return (uint32_t)(h ^ (h >> 29));
}

static int grow(uint32_t **p, size_t *cap, size_t need)
{
    if (need <= *cap) return 0;
    size_t nc = need + need / 2;
    uint32_t *q = realloc(*p, nc * sizeof *q);
    if (!q) return -ENOMEM;
    *p = q;
    *cap = nc;
    return 0;
}

static bool flipped(const fp_contact *c, const float *pos, const uint32_t *v, size_t i)
{
    double t[3][3], e1[3], e2[3];
    tri_of(pos, v, t);
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    return n[0] * c->nrm[i][0] + n[1] * c->nrm[i][1] + n[2] * c->nrm[i][2] < 0;
}

/* The pairs of a moved triangle and a triangle near it that cross in cand and (ref not NULL)
 * not in ref; all: every triangle counts as moved (ref NULL: the weld shape's own crossings,
 * marked in c->own). */
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
        c->mtris[nm++] = (uint32_t)i;
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
        /* a triangle turned over against the weld shape (and not already in ref) */
        if (info && ref && !c->own[i] && flipped(c, cand, v, i) && !flipped(c, ref, v, i))
            info->flipped++;
    }
    if (info) info->moved_tris = nm;
    if (!nm) return 0;
    /* the cell: the mean moved extent, at most 32 cells across the largest one (a few
     * large triangles, the back of a head, must not make one cell of the whole region) */
    cell = fmax(FP_CONTACT_CELL * sum / (double)nm, cell / 32.0);
    if (!(cell > 0)) cell = 1e-9;
    /* the triangles whose candidate box meets the moved region, into the grid */
    size_t ni = 0, ne = 0;
    for (size_t i = 0; i < c->t; i++) {
        float b[6];
        tri_box(cand, c->tris + 3 * i, b);
        if (!boxes_meet(b, reg)) continue;
        memcpy(c->box[i], b, sizeof b);
        c->ins[ni++] = (uint32_t)i;
    }
    /* cells of a box, clamped to the region (every query box lies inside it) */
#define CELL_RANGE(b, lo, hi)                                                                  \
    for (int k = 0; k < 3; k++) {                                                              \
        lo[k] = (long)floor(((double)fmaxf((b)[k], reg[k]) - reg[k]) / cell);                   \
        hi[k] = (long)floor(((double)fminf((b)[3 + k], reg[3 + k]) - reg[k]) / cell);           \
    }
    for (size_t j = 0; j < ni; j++) {
        long lo[3], hi[3];
        CELL_RANGE(c->box[c->ins[j]], lo, hi)
        ne += (size_t)(hi[0] - lo[0] + 1) * (size_t)(hi[1] - lo[1] + 1) * (size_t)(hi[2] - lo[2] + 1);
    }
    size_t nb = 64;
    while (nb < 2 * ne) nb *= 2;
    if (grow(&c->bucket_start, &c->bucket_cap, nb + 1)) return -ENOMEM;
    if (ne > c->entry_cap) {
        void *q = realloc(c->entries, (ne + ne / 2) * sizeof *c->entries);
        if (!q) return -ENOMEM;
        c->entries = q;
        c->entry_cap = ne + ne / 2;
    }
    uint32_t *bs = c->bucket_start;
    memset(bs, 0, (nb + 1) * sizeof *bs);
    for (int pass = 0; pass < 2; pass++) {
        for (size_t j = 0; j < ni; j++) {
            long lo[3], hi[3];
            CELL_RANGE(c->box[c->ins[j]], lo, hi)
            for (long x = lo[0]; x <= hi[0]; x++)
                for (long y = lo[1]; y <= hi[1]; y++)
                    for (long z = lo[2]; z <= hi[2]; z++) {
                        uint32_t h = cell_hash(x, y, z) & (uint32_t)(nb - 1);
                        if (!pass) bs[h + 1]++;
                        else {
                            struct entry *en = &c->entries[bs[h]++];
                            uint32_t i = c->ins[j];
                            const uint32_t *v = c->tris + 3 * (size_t)i;
                            memcpy(en->box, c->box[i], sizeof en->box);
                            en->tri = i;
                            en->moved = c->moved[v[0]] | c->moved[v[1]] | c->moved[v[2]];
                        }
                    }
        }
        if (!pass)
            for (size_t h = 0; h < nb; h++) bs[h + 1] += bs[h];
        else /* the fill moved each start to the next bucket's */
            memmove(bs + 1, bs, nb * sizeof *bs), bs[0] = 0;
    }
    long found = 0;
    for (size_t j = 0; j < nm; j++) {
        uint32_t a = c->mtris[j];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        double ta[3][3], ra[3][3];
        tri_of(cand, va, ta);
        if (degenerate(ta)) continue;
        bool rdeg_a = true;
        if (ref) {
            tri_of(ref, va, ra);
            rdeg_a = degenerate(ra);
        }
        long lo[3], hi[3];
        const float *ba = c->box[a];
        CELL_RANGE(ba, lo, hi)
        for (long x = lo[0]; x <= hi[0]; x++)
            for (long y = lo[1]; y <= hi[1]; y++)
                for (long z = lo[2]; z <= hi[2]; z++) {
                    uint32_t h = cell_hash(x, y, z) & (uint32_t)(nb - 1);
                    for (uint32_t e = bs[h]; e < bs[h + 1]; e++) {
                        const struct entry *en = &c->entries[e];
                        if (!boxes_meet(ba, en->box)) continue;
                        uint32_t b = en->tri;
                        if (b == a || (en->moved && b < a)) continue; /* a moved pair is the lower's */
                        /* a pair once: in the cell of its boxes' common lower corner */
                        long own[3], cur[3] = {x, y, z};
                        bool mine = true;
                        for (int k = 0; k < 3 && mine; k++) {
                            float l = fmaxf(fmaxf(ba[k], en->box[k]), reg[k]);
                            own[k] = (long)floor(((double)l - reg[k]) / cell);
                            mine = own[k] == cur[k];
                        }
                        if (!mine) continue;
                        const uint32_t *vb = c->tris + 3 * (size_t)b;
                        bool adjacent = false;
                        for (int p = 0; p < 3 && !adjacent; p++)
                            for (int q = 0; q < 3; q++)
                                if (c->weld[va[p]] == c->weld[vb[q]]) {
                                    adjacent = true;
                                    break;
                                }
                        if (adjacent) continue;
                        double tb[3][3], rb[3][3];
                        tri_of(cand, vb, tb);
                        if (degenerate(tb) || !fp_contact_tri_tri(ta, tb)) continue;
                        if (!ref) { /* the weld shape's own crossings */
                            c->own[a] = c->own[b] = 1;
                            found++;
                            continue;
                        }
                        tri_of(ref, vb, rb);
                        if (!rdeg_a && !degenerate(rb) && fp_contact_tri_tri(ra, rb)) continue;
                        if (c->own[a] || c->own[b]) { /* next to the input's own crossings */
                            if (info) info->near_own++;
                            continue;
                        }
                        if (pairs && (size_t)found < max_pairs) {
                            pairs[2 * found] = a < b ? a : b;
                            pairs[2 * found + 1] = a < b ? b : a;
                        }
                        found++;
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
    res->t = 1;
    fp_contact_count info;
    long k = fp_contact_count_new(c, ref, cand, NULL, 0, &info);
    res->moved_tris = info.moved_tris;
    res->flipped = info.flipped;
    res->checks = 1;
    if (k < 0) {
        lerp(c, ref, cand, 0, out);
        res->t = 0;
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
    res->t = lo;
    return 0;
}
