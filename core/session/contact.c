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
    float (*nrm)[3];      /* t: the rest normals (flips are against them): the weld shape's
                             triangle normals (unnormalised), carried by fp_contact_set_pose */
    float (*nrm_weld)[3]; /* t: the weld shape's, kept at the first fp_contact_set_pose */
    struct track *tk;     /* the incremental guard (fp_contact_step), made on first use */
    float *weld_copy;     /* n x 3: the weld shape, the tracker's first P (freed then) */
    size_t prewarm;       /* fp_contact_set_prewarm */
    double local_r;       /* fp_contact_set_local: 0, a scale-back is global */
};

/* ---- the triangle-triangle test ---------------------------------------------------------- */

/* Signs of orientation determinants, filtered: a determinant within its rounding error
 * bound (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric
 * predicates", 1997: errboundA, which covers the differences too) has sign 0, as if exactly
 * degenerate. Every decision below treats 0 as "may touch", so an uncertain case counts as
 * meeting: the test is exact where the signs are certain and errs towards a crossing where
 * they are not. The guard's bisection drives triangles towards touching, frame after frame
 * (each frame keeps the largest passing share), until within rounding; there a plain sign
 * could let through what an exact test (CGAL, in the tests) sees as touching. */
#define FP_EPS 1.1102230246251565e-16 /* 2^-53 */

static int orient3d(const double *p, const double *q, const double *r, const double *s)
{
    double ax = q[0] - p[0], ay = q[1] - p[1], az = q[2] - p[2];
    double bx = r[0] - p[0], by = r[1] - p[1], bz = r[2] - p[2];
    double cx = s[0] - p[0], cy = s[1] - p[1], cz = s[2] - p[2];
    double m1 = by * cz, m2 = bz * cy, m3 = bx * cz, m4 = bz * cx, m5 = bx * cy, m6 = by * cx;
    double det = ax * (m1 - m2) - ay * (m3 - m4) + az * (m5 - m6);
    double perm = fabs(ax) * (fabs(m1) + fabs(m2)) + fabs(ay) * (fabs(m3) + fabs(m4)) +
                  fabs(az) * (fabs(m5) + fabs(m6));
    double bound = (7.0 + 56.0 * FP_EPS) * FP_EPS * perm;
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

static int orient2d(const double *p, const double *q, const double *r)
{
    double l = (q[0] - p[0]) * (r[1] - p[1]), rr = (q[1] - p[1]) * (r[0] - p[0]), det = l - rr;
    double bound = (3.0 + 16.0 * FP_EPS) * FP_EPS * (fabs(l) + fabs(rr));
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

/* closed segments pq and ab in a plane: they meet iff each one's endpoints are not strictly
 * on one side of the other's line, or, collinear, their boxes overlap (an uncertain sign is 0:
 * a meeting) */
static bool seg_seg2(const double *p, const double *q, const double *a, const double *b)
{
    int d1 = orient2d(p, q, a), d2 = orient2d(p, q, b);
    int d3 = orient2d(a, b, p), d4 = orient2d(a, b, q);
    if ((!d1 && !d2) || (!d3 && !d4))
        return fmax(p[0], q[0]) >= fmin(a[0], b[0]) && fmax(a[0], b[0]) >= fmin(p[0], q[0]) &&
               fmax(p[1], q[1]) >= fmin(a[1], b[1]) && fmax(a[1], b[1]) >= fmin(p[1], q[1]);
    return d1 * d2 <= 0 && d3 * d4 <= 0;
}

static bool in_tri2(const double *p, const double t[3][2])
{
    int s1 = orient2d(t[0], t[1], p), s2 = orient2d(t[1], t[2], p), s3 = orient2d(t[2], t[0], p);
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

/* closed segment pq against closed triangle t (not degenerate); op, oq: the signs of
 * orient3d(t[0], t[1], t[2], p) and (..., q) */
static bool seg_tri(const double *p, const double *q, const double t[3][3], int op, int oq)
{
    if (op * oq > 0) return false;
    if (!op && !oq) return seg_tri_coplanar(p, q, t);
    int s1 = orient3d(p, q, t[0], t[1]), s2 = orient3d(p, q, t[1], t[2]), s3 = orient3d(p, q, t[2], t[0]);
    return !((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0));
}

int fp_contact_tri_tri(const double a[3][3], const double b[3][3])
{
    /* each vertex against the other's plane, once (every edge test starts with these) */
    int oa[3], ob[3];
    for (int i = 0; i < 3; i++) {
        oa[i] = orient3d(b[0], b[1], b[2], a[i]);
        ob[i] = orient3d(a[0], a[1], a[2], b[i]);
    }
    for (int e = 0; e < 3; e++) {
        int f = (e + 1) % 3;
        if (seg_tri(a[e], a[f], b, oa[e], oa[f]) || seg_tri(b[e], b[f], a, ob[e], ob[f])) return 1;
    }
    return 0;
}

typedef struct fp_contact_count fp_contact_count;
static void track_free(struct track *k);
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
    c->prewarm = FP_CONTACT_PREWARM;
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
    free(c->nrm_weld);
    track_free(c->tk);
    free(c->weld_copy);
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

/* min and max of finite floats, inline (fminf and fmaxf are calls, for NaN's sake) */
static inline float min_f(float a, float b) { return b < a ? b : a; }
static inline float max_f(float a, float b) { return b > a ? b : a; }

static inline void tri_box(const float *pos, const uint32_t *v, float b[6])
{
    const float *p0 = pos + 3 * (size_t)v[0], *p1 = pos + 3 * (size_t)v[1], *p2 = pos + 3 * (size_t)v[2];
    for (int k = 0; k < 3; k++) {
        b[k] = min_f(p0[k], min_f(p1[k], p2[k]));
        b[3 + k] = max_f(p0[k], max_f(p1[k], p2[k]));
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
    double d = n[0] * c->nrm[i][0] + n[1] * c->nrm[i][1] + n[2] * c->nrm[i][2];
    /* turned by more than acos(FP_CONTACT_FLIP_COS) (the rest normal is a unit vector): d <
     * FP_CONTACT_FLIP_COS |n|, without a square root */
    return d < 0 || d * d < FP_CONTACT_FLIP_COS * FP_CONTACT_FLIP_COS * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
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
        /* a triangle turned over against its rest normal (and not already in ref); own
         * triangles too: a flip is no crossing, the input's own crossings do not excuse it */
        if (info && ref && flipped(c, cand, v, i) && !flipped(c, ref, v, i))
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
                        /* two cells of one box in one bucket: one entry is enough (the
                         * copies are next to each other, filled box by box) */
                        if (e > bs[h] && en[-1].tri == en->tri) continue;
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

/* ---- the incremental guard (contact.h "The incremental guard") ------------------------------ */

#define FP_TRACK_NONE UINT32_MAX
#define FP_TRACK_BIG_CELLS 4096.0 /* a box over more grid cells goes to a list of its own */
#define FP_TRACK_SKIN 0.1         /* an envelope: the box grown by this share of its extent */

#define FP_CONTACT_LOCAL_ROUNDS 3 /* a local scale-back: times its blocking set may grow */
#define FP_TRACK_INLINE 6          /* list entries kept in the dyn itself (one cache line) */

typedef struct dyn {              /* a triangle that has left the weld shape */
    float env[6];                 /* its envelope: holds its box in P (and in the candidate) */
    uint32_t tri;
    uint32_t len, cap;            /* its list: every triangle whose envelope meets env (and
                                     maybe some more); cap 0: in inl */
    bool big;                     /* registered in the big list, not in the grid */
    union {
        uint32_t inl[FP_TRACK_INLINE];
        uint32_t *heap;
    } u;
} dyn;

static inline uint32_t *dyn_list(dyn *d) { return d->cap ? d->u.heap : d->u.inl; }

/* append y to d's list (no check for duplicates) */
static int dyn_push(dyn *d, uint32_t y)
{
    if (!d->cap && d->len < FP_TRACK_INLINE) {
        d->u.inl[d->len++] = y;
        return 0;
    }
    if (!d->cap || d->len == d->cap) {
        uint32_t nc = d->cap ? 2 * d->cap : 2 * FP_TRACK_INLINE;
        uint32_t *h = malloc(nc * sizeof *h);
        if (!h) return -ENOMEM;
        memcpy(h, dyn_list(d), d->len * sizeof *h);
        if (d->cap) free(d->u.heap);
        d->u.heap = h;
        d->cap = nc;
    }
    d->u.heap[d->len++] = y;
    return 0;
}

typedef struct rq_cell {          /* a cell of a renewed envelope */
    int64_t key[3];
    uint32_t r;                   /* the request (index into rq) */
} rq_cell;

typedef struct centry {           /* a triangle registered in a cell, with a copy of its
                                     envelope (read in order, not through slot and dyn) */
    float env[6];
    uint32_t tri;
} centry;

typedef struct cellvec {          /* a cell of the dynamic grid */
    int64_t key[3];
    centry *ids;
    uint32_t len, cap;
    bool used;
} cellvec;

struct track {
    float *p;                     /* n x 3: P, the shape last accepted */
    uint32_t *vt_start, *vt;      /* vertex v's triangles: vt[vt_start[v] .. vt_start[v + 1]) */
    uint32_t *dp;                 /* D_P: every vertex where P may differ from the reference */
    size_t ndp;
    uint8_t *in_dp;               /* n */
    uint32_t *mv;                 /* moved vertices (P -> candidate) */
    size_t nmv, cap_mv;
    float *pv, *cv;               /* their positions in P and in the candidate (3 each) */
    size_t cap_pv;
    uint32_t *mt;                 /* moved triangles, own ones left out */
    float (*mbox)[6];             /* their boxes in the candidate */
    size_t nmt, cap_mt, cap_mbox;
    uint32_t *mo;                 /* moved own triangles: checked for flips only */
    size_t nmo, cap_mo;
    uint32_t *tstamp, tclock;     /* t: == tclock when in mt */
    uint32_t *qstamp, qclock;     /* t: == qclock when seen by this query */
    double ih;                    /* the grid cell's inverse (cell_coord) */
    uint32_t *sg_start, *sg_ids;  /* the static grid: the weld shape's boxes by hashed cell */
    uint32_t *sg_dead;            /* entries of triangles gone dynamic, cut from the bucket's end */
    size_t sg_nb;
    uint32_t *sbig;               /* ... and those over FP_TRACK_BIG_CELLS cells */
    size_t nsbig;
    uint32_t *slot;               /* t: index into dyn; FP_TRACK_NONE: static (P = weld shape) */
    dyn *dyn;
    size_t ndyn, cap_dyn;
    cellvec *cells;               /* the dynamic grid: open addressing, cap a power of 2 */
    size_t cap_cells, used_cells;
    uint32_t *dbig;
    size_t ndbig, cap_dbig;
    uint32_t *q;                  /* one query's triangles */
    size_t nq, cap_q;
    uint32_t *rq;                 /* triangles with a new envelope, their lists to make */
    size_t nrq, cap_rq;
    struct rq_cell *rc, *rcs;     /* (cell, request) of the batch, and sorted by hashed cell */
    size_t cap_rc, cap_rcs;
    uint32_t *rcb, *rr;           /* the sort's buckets; one cell's requests */
    size_t cap_rcb, cap_rr;
    uint32_t *rx;                 /* one cell's requests: their triangles and envelopes */
    float (*renv)[6];
    size_t cap_rx, cap_renv;
    size_t renewed;               /* envelopes renewed, for fp_contact_result */
    uint32_t *off;                /* a local scale-back: the blocking triangles' vertices */
    size_t noff, cap_off;
    uint8_t *off_mark;            /* n: in off */
    double *ramp;                 /* per moved vertex: the share of its motion always kept */
    size_t cap_ramp;
    bool broken;                  /* a call ran out of memory half way: unusable */
};

static void track_free(struct track *k)
{
    if (!k) return;
    free(k->p);
    free(k->vt_start);
    free(k->vt);
    free(k->dp);
    free(k->in_dp);
    free(k->mv);
    free(k->pv);
    free(k->cv);
    free(k->mt);
    free(k->mo);
    free(k->mbox);
    free(k->tstamp);
    free(k->qstamp);
    free(k->sg_start);
    free(k->sg_ids);
    free(k->sg_dead);
    free(k->sbig);
    free(k->slot);
    for (size_t i = 0; i < k->ndyn; i++)
        if (k->dyn[i].cap) free(k->dyn[i].u.heap);
    free(k->dyn);
    for (size_t i = 0; i < k->cap_cells; i++) free(k->cells[i].ids);
    free(k->cells);
    free(k->dbig);
    free(k->q);
    free(k->rq);
    free(k->rc);
    free(k->rcs);
    free(k->rcb);
    free(k->rr);
    free(k->rx);
    free(k->renv);
    free(k->off);
    free(k->off_mark);
    free(k->ramp);
    free(k);
}

/* grow *p (elements of size el) to hold need; 0 or -ENOMEM */
static int reserve(void **p, size_t *cap, size_t need, size_t el)
{
    if (need <= *cap) return 0;
    size_t nc = need < 16 ? 16 : need + need / 2;
    void *q = realloc(*p, nc * el);
    if (!q) return -ENOMEM;
    *p = q;
    *cap = nc;
    return 0;
}

static int push_u32(uint32_t **p, size_t *len, size_t *cap, uint32_t v)
{
    if (reserve((void **)p, cap, *len + 1, sizeof **p)) return -ENOMEM;
    (*p)[(*len)++] = v;
    return 0;
}

/* the grid cell of coordinate x: floor(x ih), ih the cell's inverse (a product, not a
 * quotient: monotonic in x all the same, which is all the grid needs), clamped to +-1e15
 * (NaN: -1e15) */
static inline int64_t cell_coord(double x, double ih)
{
    double q = x * ih;
    if (!(q > -1e15)) q = -1e15;
    if (q > 1e15) q = 1e15;
    int64_t i = (int64_t)q;
    return i - (q < (double)i);
}

/* the grid cells of box b; returns their number (as a double: it may be huge) */
static inline double cells_of(double ih, const float b[6], int64_t lo[3], int64_t hi[3])
{
    double cnt = 1;
    for (int k = 0; k < 3; k++) {
        lo[k] = cell_coord(b[k], ih);
        hi[k] = cell_coord(b[3 + k], ih);
        cnt *= (double)(hi[k] - lo[k] + 1);
    }
    return cnt;
}

static inline bool same_key(const int64_t a[3], const int64_t b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static uint64_t key_hash(int64_t x, int64_t y, int64_t z)
{
    uint64_t h = (uint64_t)x * 0x9E3779B97F4A7C15ull ^ (uint64_t)y * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)z * 0x165667B19E3779F9ull;
    return h ^ (h >> 29);
}

static bool box_holds(const float *outer, const float *inner)
{
    return outer[0] <= inner[0] && outer[1] <= inner[1] && outer[2] <= inner[2] &&
           inner[3] <= outer[3] && inner[4] <= outer[4] && inner[5] <= outer[5];
}

/* bitwise, as memcmp (inline: three words) */
static inline bool vert_differs(const float *a, const float *b, size_t v)
{
    uint32_t x[3], y[3];
    memcpy(x, a + 3 * v, sizeof x);
    memcpy(y, b + 3 * v, sizeof y);
    return ((x[0] ^ y[0]) | (x[1] ^ y[1]) | (x[2] ^ y[2])) != 0;
}

/* ---- the dynamic grid ---- */

static cellvec *cell_find(struct track *k, const int64_t key[3], bool create)
{
    if (create && 2 * (k->used_cells + 1) > k->cap_cells) {
        size_t nc = k->cap_cells ? 2 * k->cap_cells : 1024;
        cellvec *nt = calloc(nc, sizeof *nt);
        if (!nt) return NULL;
        for (size_t i = 0; i < k->cap_cells; i++) {
            cellvec *o = &k->cells[i];
            if (!o->used) continue;
            size_t j = key_hash(o->key[0], o->key[1], o->key[2]) & (nc - 1);
            while (nt[j].used) j = (j + 1) & (nc - 1);
            nt[j] = *o;
        }
        free(k->cells);
        k->cells = nt;
        k->cap_cells = nc;
    }
    if (!k->cap_cells) return NULL;
    size_t m = k->cap_cells - 1;
    for (size_t i = key_hash(key[0], key[1], key[2]) & m;; i = (i + 1) & m) {
        cellvec *cv = &k->cells[i];
        if (!cv->used) {
            if (!create) return NULL;
            memset(cv, 0, sizeof *cv);
            cv->used = true;
            memcpy(cv->key, key, sizeof cv->key);
            k->used_cells++;
            return cv;
        }
        if (same_key(cv->key, key)) return cv;
    }
}

static int grid_add(struct track *k, dyn *d)
{
    int64_t lo[3], hi[3];
    d->big = cells_of(k->ih, d->env, lo, hi) > FP_TRACK_BIG_CELLS;
    if (d->big) return push_u32(&k->dbig, &k->ndbig, &k->cap_dbig, d->tri);
    for (int64_t x = lo[0]; x <= hi[0]; x++)
        for (int64_t y = lo[1]; y <= hi[1]; y++)
            for (int64_t z = lo[2]; z <= hi[2]; z++) {
                int64_t key[3] = {x, y, z};
                cellvec *cv = cell_find(k, key, true);
                if (!cv) return -ENOMEM;
                size_t cap = cv->cap;
                if (reserve((void **)&cv->ids, &cap, (size_t)cv->len + 1, sizeof *cv->ids)) return -ENOMEM;
                cv->cap = (uint32_t)cap;
                centry *en = &cv->ids[cv->len++];
                memcpy(en->env, d->env, sizeof en->env);
                en->tri = d->tri;
            }
    return 0;
}

static void grid_remove(struct track *k, const dyn *d)
{
    if (d->big) {
        for (size_t i = 0; i < k->ndbig; i++)
            if (k->dbig[i] == d->tri) {
                k->dbig[i] = k->dbig[--k->ndbig];
                return;
            }
        return;
    }
    int64_t lo[3], hi[3];
    cells_of(k->ih, d->env, lo, hi);
    for (int64_t x = lo[0]; x <= hi[0]; x++)
        for (int64_t y = lo[1]; y <= hi[1]; y++)
            for (int64_t z = lo[2]; z <= hi[2]; z++) {
                int64_t key[3] = {x, y, z};
                cellvec *cv = cell_find(k, key, false);
                for (uint32_t i = 0; cv && i < cv->len; i++)
                    if (cv->ids[i].tri == d->tri) {
                        cv->ids[i] = cv->ids[--cv->len];
                        break;
                    }
            }
}

/* ---- queries ---- */

/* k->q = the triangles not own, other than x and not adjacent to it, whose envelope (a static
 * one's: its box in P, which is the weld shape's) meets box q. */
static int query(fp_contact *c, const float q[6], uint32_t x)
{
    struct track *k = c->tk;
    k->nq = 0;
    if (++k->qclock == 0) {
        memset(k->qstamp, 0, c->t * sizeof *k->qstamp);
        k->qclock = 1;
    }
    uint32_t clock = k->qclock;
    k->qstamp[x] = clock;
    const uint32_t *vx = c->tris + 3 * (size_t)x;
    uint32_t w0 = c->weld[vx[0]], w1 = c->weld[vx[1]], w2 = c->weld[vx[2]];
#define FP_NOT_ADJ(y)                                                                           \
    (c->weld[c->tris[3 * (size_t)(y)]] != w0 && c->weld[c->tris[3 * (size_t)(y)]] != w1 &&      \
     c->weld[c->tris[3 * (size_t)(y)]] != w2 && c->weld[c->tris[3 * (size_t)(y) + 1]] != w0 &&  \
     c->weld[c->tris[3 * (size_t)(y) + 1]] != w1 && c->weld[c->tris[3 * (size_t)(y) + 1]] != w2 && \
     c->weld[c->tris[3 * (size_t)(y) + 2]] != w0 && c->weld[c->tris[3 * (size_t)(y) + 2]] != w1 && \
     c->weld[c->tris[3 * (size_t)(y) + 2]] != w2)
#define FP_STATIC(y)                                                                            \
    do {                                                                                        \
        uint32_t y_ = (y);                                                                      \
        if (k->slot[y_] != FP_TRACK_NONE || k->qstamp[y_] == clock || c->own[y_]) break;        \
        k->qstamp[y_] = clock;                                                                  \
        float b_[6];                                                                            \
        tri_box(k->p, c->tris + 3 * (size_t)y_, b_);                                            \
        if (boxes_meet(b_, q) && FP_NOT_ADJ(y_) && push_u32(&k->q, &k->nq, &k->cap_q, y_))      \
            return -ENOMEM;                                                                     \
    } while (0)
#define FP_DYNAMIC(y)                                                                           \
    do {                                                                                        \
        uint32_t y_ = (y);                                                                      \
        if (k->qstamp[y_] == clock || c->own[y_]) break;                                        \
        k->qstamp[y_] = clock;                                                                  \
        if (boxes_meet(k->dyn[k->slot[y_]].env, q) && FP_NOT_ADJ(y_) &&                         \
            push_u32(&k->q, &k->nq, &k->cap_q, y_))                                             \
            return -ENOMEM;                                                                     \
    } while (0)
    int64_t lo[3], hi[3];
    bool huge = cells_of(k->ih, q, lo, hi) > FP_TRACK_BIG_CELLS;
    if (huge) {
        for (size_t y = 0; y < c->t; y++) FP_STATIC((uint32_t)y);
        for (size_t i = 0; i < k->ndyn; i++) FP_DYNAMIC(k->dyn[i].tri);
    } else {
        size_t m = k->sg_nb - 1;
        for (int64_t cx = lo[0]; cx <= hi[0]; cx++)
            for (int64_t cy = lo[1]; cy <= hi[1]; cy++)
                for (int64_t cz = lo[2]; cz <= hi[2]; cz++) {
                    size_t bkt = key_hash(cx, cy, cz) & m;
                    for (uint32_t e = k->sg_start[bkt]; e < k->sg_start[bkt + 1] - k->sg_dead[bkt]; e++)
                        FP_STATIC(k->sg_ids[e]);
                    int64_t key[3] = {cx, cy, cz};
                    const cellvec *cv = cell_find(k, key, false);
                    for (uint32_t i = 0; cv && i < cv->len; i++) FP_DYNAMIC(cv->ids[i].tri);
                }
        for (size_t i = 0; i < k->nsbig; i++) FP_STATIC(k->sbig[i]);
        for (size_t i = 0; i < k->ndbig; i++) FP_DYNAMIC(k->dbig[i]);
    }
#undef FP_STATIC
#undef FP_DYNAMIC
#undef FP_NOT_ADJ
    return 0;
}

/* Static triangle x (P still the weld shape there) out of the static grid: each of its
 * entries cut out of its bucket (order kept, so a triangle's copies stay next to each other) */
static void static_remove(fp_contact *c, uint32_t x)
{
    struct track *k = c->tk;
    float b[6];
    int64_t lo[3], hi[3];
    tri_box(k->p, c->tris + 3 * (size_t)x, b);
    if (cells_of(k->ih, b, lo, hi) > FP_TRACK_BIG_CELLS) {
        for (size_t i = 0; i < k->nsbig; i++)
            if (k->sbig[i] == x) {
                memmove(k->sbig + i, k->sbig + i + 1, (k->nsbig - i - 1) * sizeof *k->sbig);
                k->nsbig--;
                break;
            }
        return;
    }
    for (int64_t cx = lo[0]; cx <= hi[0]; cx++)
        for (int64_t cy = lo[1]; cy <= hi[1]; cy++)
            for (int64_t cz = lo[2]; cz <= hi[2]; cz++) {
                size_t bkt = key_hash(cx, cy, cz) & (k->sg_nb - 1);
                uint32_t s0 = k->sg_start[bkt], e = k->sg_start[bkt + 1] - k->sg_dead[bkt];
                for (uint32_t i = s0; i < e; i++)
                    if (k->sg_ids[i] == x) {
                        memmove(k->sg_ids + i, k->sg_ids + i + 1, (e - i - 1) * sizeof *k->sg_ids);
                        k->sg_dead[bkt]++;
                        break;
                    }
            }
}

/* Give triangle x (not own; a static one already out of the static grid) the envelope box +
 * skin in the dynamic grid and an empty list (renew_lists fills it); x joins the requests
 * k->rq. */
static int envelope(fp_contact *c, uint32_t x, const float box[6])
{
    struct track *k = c->tk;
    if (k->slot[x] == FP_TRACK_NONE) {
        if (reserve((void **)&k->dyn, &k->cap_dyn, k->ndyn + 1, sizeof *k->dyn)) return -ENOMEM;
        memset(&k->dyn[k->ndyn], 0, sizeof k->dyn[0]); /* an empty inline list */
        k->dyn[k->ndyn].tri = x;
        k->slot[x] = (uint32_t)k->ndyn++;
    } else {
        grid_remove(k, &k->dyn[k->slot[x]]);
    }
    dyn *d = &k->dyn[k->slot[x]];
    double ext = 0;
    for (int i = 0; i < 3; i++) ext = fmax(ext, (double)box[3 + i] - box[i]);
    float skin = (float)(FP_TRACK_SKIN * ext);
    for (int i = 0; i < 3; i++) {
        d->env[i] = box[i] - skin;
        d->env[3 + i] = box[3 + i] + skin;
    }
    d->len = 0;
    if (grid_add(k, d)) return -ENOMEM;
    return push_u32(&k->rq, &k->nrq, &k->cap_rq, x);
}

/* y into d's list unless there */
static int list_add(dyn *d, uint32_t y)
{
    const uint32_t *l = dyn_list(d);
    for (uint32_t j = 0; j < d->len; j++)
        if (l[j] == y) return 0;
    return dyn_push(d, y);
}

static bool adjacent(const fp_contact *c, uint32_t x, uint32_t y)
{
    const uint32_t *vx = c->tris + 3 * (size_t)x, *vy = c->tris + 3 * (size_t)y;
    for (int i = 0; i < 3; i++) {
        uint32_t w = c->weld[vx[i]];
        if (w == c->weld[vy[0]] || w == c->weld[vy[1]] || w == c->weld[vy[2]]) return true;
    }
    return false;
}

/* y into x's list, and x into y's unless y is being renewed too (its list is being made) or
 * has x already; `clock` marks the requests in qstamp */
static int link(fp_contact *c, uint32_t x, uint32_t y, uint32_t clock)
{
    struct track *k = c->tk;
    if (dyn_push(&k->dyn[k->slot[x]], y)) return -ENOMEM;
    if (k->slot[y] == FP_TRACK_NONE || k->qstamp[y] == clock) return 0;
    return list_add(&k->dyn[k->slot[y]], x);
}

/* One cell of the batch: requests R (nr of them) against the triangles registered in the
 * cell (static: the bucket's, whose boxes are the weld shape's; dynamic: the cell's). A
 * pair is taken in the cell of its boxes' common lower corner only (so once). */
static int renew_cell(fp_contact *c, const int64_t key[3], const uint32_t *R, size_t nr, uint32_t clock)
{
    struct track *k = c->tk;
    /* the requests' triangles and envelopes, side by side */
    if (reserve((void **)&k->renv, &k->cap_renv, nr, sizeof *k->renv) ||
        reserve((void **)&k->rx, &k->cap_rx, nr, sizeof *k->rx))
        return -ENOMEM;
    for (size_t i = 0; i < nr; i++) {
        k->rx[i] = k->rq[R[i]];
        memcpy(k->renv[i], k->dyn[k->slot[k->rx[i]]].env, sizeof k->renv[i]);
    }
#define FP_TRY(Y, YBOX)                                                                         \
    for (size_t i_ = 0; i_ < nr; i_++) {                                                        \
        uint32_t x_ = k->rx[i_];                                                                \
        const float *ex_ = k->renv[i_];                                                         \
        if (!boxes_meet(ex_, (YBOX)) || (Y) == x_) continue;                                    \
        bool mine_ = true;                                                                      \
        for (int a_ = 0; a_ < 3 && mine_; a_++)                                                 \
            mine_ = cell_coord(max_f(ex_[a_], (YBOX)[a_]), k->ih) == key[a_];                    \
        if (mine_ && !adjacent(c, x_, (Y)) && link(c, x_, (Y), clock)) return -ENOMEM;          \
    }
    size_t bkt = key_hash(key[0], key[1], key[2]) & (k->sg_nb - 1);
    for (uint32_t e = k->sg_start[bkt]; e < k->sg_start[bkt + 1] - k->sg_dead[bkt]; e++) {
        uint32_t y = k->sg_ids[e];
        if ((e > k->sg_start[bkt] && k->sg_ids[e - 1] == y) || k->slot[y] != FP_TRACK_NONE || c->own[y])
            continue;
        float yb[6];
        tri_box(k->p, c->tris + 3 * (size_t)y, yb);
        FP_TRY(y, yb)
    }
    const cellvec *cv = cell_find(k, key, false);
    for (uint32_t j = 0; cv && j < cv->len; j++) { /* (own triangles have no envelope) */
        uint32_t y = cv->ids[j].tri;
        FP_TRY(y, cv->ids[j].env)
    }
#undef FP_TRY
    return 0;
}

/* The lists of the requests (k->rq, envelopes in the grid already), batched by cell: each
 * cell's registered triangles are read once for all the requests that cover it. */
static int renew_lists(fp_contact *c)
{
    struct track *k = c->tk;
    size_t nrq = k->nrq;
    if (!nrq) return 0;
    if (++k->qclock == 0) {
        memset(k->qstamp, 0, c->t * sizeof *k->qstamp);
        k->qclock = 1;
    }
    uint32_t clock = k->qclock;
    for (size_t r = 0; r < nrq; r++) k->qstamp[k->rq[r]] = clock;
    /* the cells of every request's envelope (big ones go through query below) */
    size_t ne = 0;
    for (size_t r = 0; r < nrq; r++) {
        const dyn *d = &k->dyn[k->slot[k->rq[r]]];
        if (d->big) continue;
        int64_t lo[3], hi[3];
        ne += (size_t)cells_of(k->ih, d->env, lo, hi);
    }
    size_t nb = 64;
    while (nb < ne) nb *= 2;
    if (reserve((void **)&k->rc, &k->cap_rc, ne, sizeof *k->rc) ||
        reserve((void **)&k->rcs, &k->cap_rcs, ne, sizeof *k->rcs) ||
        reserve((void **)&k->rcb, &k->cap_rcb, nb + 1, sizeof *k->rcb) ||
        reserve((void **)&k->rr, &k->cap_rr, nrq, sizeof *k->rr))
        return -ENOMEM;
    size_t w = 0;
    for (size_t r = 0; r < nrq; r++) {
        const dyn *d = &k->dyn[k->slot[k->rq[r]]];
        if (d->big) continue;
        int64_t lo[3], hi[3];
        cells_of(k->ih, d->env, lo, hi);
        for (int64_t x = lo[0]; x <= hi[0]; x++)
            for (int64_t y = lo[1]; y <= hi[1]; y++)
                for (int64_t z = lo[2]; z <= hi[2]; z++) {
                    rq_cell *rc = &k->rc[w++];
                    rc->key[0] = x;
                    rc->key[1] = y;
                    rc->key[2] = z;
                    rc->r = (uint32_t)r;
                }
    }
    /* counting sort by hashed cell */
    memset(k->rcb, 0, (nb + 1) * sizeof *k->rcb);
    for (size_t i = 0; i < ne; i++)
        k->rcb[(key_hash(k->rc[i].key[0], k->rc[i].key[1], k->rc[i].key[2]) & (nb - 1)) + 1]++;
    for (size_t b = 0; b < nb; b++) k->rcb[b + 1] += k->rcb[b];
    for (size_t i = 0; i < ne; i++)
        k->rcs[k->rcb[key_hash(k->rc[i].key[0], k->rc[i].key[1], k->rc[i].key[2]) & (nb - 1)]++] = k->rc[i];
    memmove(k->rcb + 1, k->rcb, nb * sizeof *k->rcb);
    k->rcb[0] = 0;
    for (size_t b = 0; b < nb; b++) {
        size_t s0 = k->rcb[b], s1 = k->rcb[b + 1];
        for (size_t i = s0; i < s1; i++) {
            const int64_t *key = k->rcs[i].key;
            bool seen = false;
            for (size_t j = s0; j < i && !seen; j++) seen = same_key(k->rcs[j].key, key);
            if (seen) continue; /* that cell is done */
            size_t nr = 0;
            for (size_t j = i; j < s1; j++)
                if (same_key(k->rcs[j].key, key)) k->rr[nr++] = k->rcs[j].r;
            if (renew_cell(c, key, k->rr, nr, clock)) return -ENOMEM;
        }
    }
    /* big triangles (in no cell) against every request in cells */
    for (size_t i = 0; i < k->nsbig + k->ndbig; i++) {
        uint32_t y = i < k->nsbig ? k->sbig[i] : k->dbig[i - k->nsbig];
        if (c->own[y] || (i < k->nsbig && k->slot[y] != FP_TRACK_NONE)) continue;
        float yb[6];
        if (i < k->nsbig) tri_box(k->p, c->tris + 3 * (size_t)y, yb);
        else memcpy(yb, k->dyn[k->slot[y]].env, sizeof yb);
        for (size_t r = 0; r < nrq; r++) {
            uint32_t x = k->rq[r];
            const dyn *d = &k->dyn[k->slot[x]];
            if (d->big || y == x || !boxes_meet(d->env, yb) || adjacent(c, x, y)) continue;
            if (link(c, x, y, clock)) return -ENOMEM;
        }
    }
    /* big requests: a query each (every registered triangle; links as above, but a request
     * in a cell has found this one already: link checks y's list) */
    for (size_t r = 0; r < nrq; r++) {
        uint32_t x = k->rq[r];
        if (!k->dyn[k->slot[x]].big) continue;
        float env[6];
        memcpy(env, k->dyn[k->slot[x]].env, sizeof env);
        if (query(c, env, x)) return -ENOMEM;
        for (size_t i = 0; i < k->nq; i++) {
            uint32_t y = k->q[i];
            if (list_add(&k->dyn[k->slot[x]], y)) return -ENOMEM; /* another big one may */
            if (k->slot[y] != FP_TRACK_NONE && list_add(&k->dyn[k->slot[y]], x)) return -ENOMEM;
        }
    }
    k->renewed += nrq;
    k->nrq = 0;
    return 0;
}

/* ---- building ---- */

static int track_build(fp_contact *c)
{
    struct track *k = calloc(1, sizeof *k);
    if (!k) return -ENOMEM;
    size_t n = c->n, t = c->t;
    k->p = c->weld_copy; /* P starts as the weld shape: every triangle static */
    k->vt_start = calloc(n + 1, sizeof *k->vt_start);
    k->vt = malloc((t ? 3 * t : 1) * sizeof *k->vt);
    k->dp = malloc((n ? n : 1) * sizeof *k->dp);
    k->in_dp = calloc(n ? n : 1, 1);
    k->off_mark = calloc(n ? n : 1, 1);
    k->tstamp = calloc(t ? t : 1, sizeof *k->tstamp);
    k->qstamp = calloc(t ? t : 1, sizeof *k->qstamp);
    k->slot = malloc((t ? t : 1) * sizeof *k->slot);
    if (!k->p || !k->vt_start || !k->vt || !k->dp || !k->in_dp || !k->off_mark || !k->tstamp || !k->qstamp || !k->slot) {
        if (k->p) c->weld_copy = NULL;
        track_free(k);
        return -ENOMEM;
    }
    c->weld_copy = NULL;
    memset(k->slot, 0xff, t * sizeof *k->slot);
    for (size_t i = 0; i < 3 * t; i++) k->vt_start[c->tris[i] + 1]++;
    for (size_t v = 0; v < n; v++) k->vt_start[v + 1] += k->vt_start[v];
    for (size_t i = 0; i < t; i++)
        for (int j = 0; j < 3; j++) k->vt[k->vt_start[c->tris[3 * i + j]]++] = (uint32_t)i;
    for (size_t v = n; v > 0; v--) k->vt_start[v] = k->vt_start[v - 1];
    k->vt_start[0] = 0;
    /* the cell: twice the mean extent of a triangle not own */
    double sum = 0;
    size_t cnt = 0;
    for (size_t i = 0; i < t; i++) {
        if (c->own[i]) continue;
        float b[6];
        tri_box(k->p, c->tris + 3 * i, b);
        sum += fmax(fmax((double)b[3] - b[0], (double)b[4] - b[1]), (double)b[5] - b[2]);
        cnt++;
    }
    k->ih = cnt && sum > 0 ? 1.0 / (2.0 * sum / (double)cnt) : 1.0;
    /* the static grid: counting sort of (cell, triangle) entries by hashed cell */
    size_t ne = 0;
    for (int pass = 0; pass < 2; pass++) {
        if (pass) {
            size_t nb = 64;
            while (2 * nb < ne) nb *= 2;
            k->sg_nb = nb;
            k->sg_start = calloc(nb + 1, sizeof *k->sg_start);
            k->sg_dead = calloc(nb, sizeof *k->sg_dead);
            k->sg_ids = malloc((ne ? ne : 1) * sizeof *k->sg_ids);
            if (!k->sg_start || !k->sg_dead || !k->sg_ids) {
                track_free(k);
                return -ENOMEM;
            }
            for (size_t i = 0; i < t; i++) { /* counts */
                if (c->own[i]) continue;
                float b[6];
                int64_t lo[3], hi[3];
                tri_box(k->p, c->tris + 3 * i, b);
                if (cells_of(k->ih, b, lo, hi) > FP_TRACK_BIG_CELLS) continue;
                for (int64_t x = lo[0]; x <= hi[0]; x++)
                    for (int64_t y = lo[1]; y <= hi[1]; y++)
                        for (int64_t z = lo[2]; z <= hi[2]; z++)
                            k->sg_start[(key_hash(x, y, z) & (nb - 1)) + 1]++;
            }
            for (size_t b = 0; b < nb; b++) k->sg_start[b + 1] += k->sg_start[b];
        }
        size_t cap_big = 0;
        for (size_t i = 0; i < t; i++) {
            if (c->own[i]) continue;
            float b[6];
            int64_t lo[3], hi[3];
            tri_box(k->p, c->tris + 3 * i, b);
            double nc = cells_of(k->ih, b, lo, hi);
            if (nc > FP_TRACK_BIG_CELLS) {
                if (pass && push_u32(&k->sbig, &k->nsbig, &cap_big, (uint32_t)i)) {
                    track_free(k);
                    return -ENOMEM;
                }
                continue;
            }
            if (!pass) {
                ne += (size_t)nc;
                continue;
            }
            for (int64_t x = lo[0]; x <= hi[0]; x++)
                for (int64_t y = lo[1]; y <= hi[1]; y++)
                    for (int64_t z = lo[2]; z <= hi[2]; z++)
                        k->sg_ids[k->sg_start[key_hash(x, y, z) & (k->sg_nb - 1)]++] = (uint32_t)i;
        }
    }
    /* the fill moved each start to the next bucket's */
    memmove(k->sg_start + 1, k->sg_start, k->sg_nb * sizeof *k->sg_start);
    k->sg_start[0] = 0;
    c->tk = k;
    if (t > c->prewarm) return 0;
    /* a face-sized mesh: every triangle gets its envelope and list now, in one batch (the
     * static grid left empty), so that the first touch of a region costs its frame no more
     * than the next (about 1 us a triangle) */
    for (size_t b = 0; b < k->sg_nb; b++) k->sg_dead[b] = k->sg_start[b + 1] - k->sg_start[b];
    k->nsbig = 0;
    for (size_t i = 0; i < t; i++) {
        if (c->own[i]) continue;
        float b[6];
        tri_box(k->p, c->tris + 3 * i, b);
        if (envelope(c, (uint32_t)i, b)) goto fail;
    }
    if (renew_lists(c)) goto fail;
    k->renewed = 0;
    return 0;
fail:
    track_free(k);
    c->tk = NULL;
    return -ENOMEM;
}

/* the next clock of the moved stamps */
static void tick(struct track *k, size_t t)
{
    if (++k->tclock == 0) {
        memset(k->tstamp, 0, t * sizeof *k->tstamp);
        k->tclock = 1;
    }
}

static int add_off(fp_contact *c, const uint32_t *v);

/* the triangles of vertex v into mt (own ones into mo), once per clock */
static int mark_tris(fp_contact *c, uint32_t v)
{
    struct track *k = c->tk;
    for (uint32_t j = k->vt_start[v]; j < k->vt_start[v + 1]; j++) {
        uint32_t a = k->vt[j];
        if (k->tstamp[a] == k->tclock) continue;
        k->tstamp[a] = k->tclock;
        if (c->own[a]) {
            if (push_u32(&k->mo, &k->nmo, &k->cap_mo, a)) return -ENOMEM;
            continue;
        }
        if (reserve((void **)&k->mt, &k->cap_mt, k->nmt + 1, sizeof *k->mt)) return -ENOMEM;
        k->mt[k->nmt++] = a;
    }
    return 0;
}

/* newly flipped moved own triangles of shape s (their vertices into off when record) */
static long own_flips(fp_contact *c, const float *s, const float *ref, bool record)
{
    struct track *k = c->tk;
    long f = 0;
    for (size_t i = 0; i < k->nmo; i++) {
        const uint32_t *v = c->tris + 3 * (size_t)k->mo[i];
        if (flipped(c, s, v, k->mo[i]) && !flipped(c, ref, v, k->mo[i])) {
            f++;
            if (record && add_off(c, v)) return -ENOMEM;
        }
    }
    return f;
}

/* k->mv := the vertices where a differs (bitwise) from P, looked for where either may differ
 * from the reference: D_P, then the ranges (every vertex for nranges == SIZE_MAX). Returns 0
 * or -ENOMEM. */
static int collect_moved(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    k->nmv = 0;
#define FP_VISIT(v)                                                                             \
    do {                                                                                        \
        size_t v_ = (v);                                                                        \
        if (vert_differs(a, k->p, v_) && push_u32(&k->mv, &k->nmv, &k->cap_mv, (uint32_t)v_))   \
            return -ENOMEM;                                                                     \
    } while (0)
    for (size_t i = 0; i < k->ndp; i++) FP_VISIT(k->dp[i]);
    if (nranges == SIZE_MAX) {
        for (size_t v = 0; v < c->n; v++)
            if (!k->in_dp[v]) FP_VISIT(v);
    } else {
        for (size_t r = 0; r < nranges; r++)
            for (size_t v = ranges[2 * r]; v < (size_t)ranges[2 * r] + ranges[2 * r + 1] && v < c->n; v++)
                if (!k->in_dp[v]) FP_VISIT(v);
    }
#undef FP_VISIT
    return 0;
}

static int reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges);

int fp_contact_reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges)
{
    if (!c || !ref || (nranges != SIZE_MAX && nranges && !ranges)) return -EINVAL;
    if (!c->tk && track_build(c)) return -ENOMEM;
    if (c->tk->broken) return -ENOMEM;
    int rc = reference(c, ref, ranges, nranges);
    if (rc) c->tk->broken = true;
    return rc;
}

static int reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    tick(k, c->t);
    k->nmt = k->nmo = 0;
    /* P := ref where they differ: D_P, then the ranges (or everything) */
    if (collect_moved(c, ref, ranges, nranges)) return -ENOMEM;
    for (size_t i = 0; i < k->nmv; i++)
        if (mark_tris(c, k->mv[i])) return -ENOMEM;
    for (size_t i = 0; i < k->ndp; i++) k->in_dp[k->dp[i]] = 0;
    k->ndp = 0;
    /* the static triangles that change leave the static grid (P there still the weld shape) */
    for (size_t i = 0; i < k->nmt; i++)
        if (k->slot[k->mt[i]] == FP_TRACK_NONE) static_remove(c, k->mt[i]);
    for (size_t i = 0; i < k->nmv; i++)
        memcpy(k->p + 3 * (size_t)k->mv[i], ref + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    /* the triangles that changed: an envelope that holds them */
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        float b[6];
        tri_box(k->p, c->tris + 3 * (size_t)a, b);
        if ((k->slot[a] == FP_TRACK_NONE || !box_holds(k->dyn[k->slot[a]].env, b)) && envelope(c, a, b))
            return -ENOMEM;
    }
    return renew_lists(c);
}

/* New pairs and newly flipped triangles of shape s (P but for the moved vertices) against
 * ref, among the pairs with a moved triangle (mt); cand_boxes: s is the candidate (mbox). */

static long track_check(fp_contact *c, const float *s, const float *ref, bool cand_boxes,
                        size_t *flips, bool record)
{
    struct track *k = c->tk;
    long found = 0;
    if (!cand_boxes) *flips = 0; /* else counted with the candidate's boxes (fp_contact_step) */
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        if (!cand_boxes && flipped(c, s, va, a) && !flipped(c, ref, va, a)) {
            (*flips)++;
            if (record && add_off(c, va)) return -ENOMEM;
        }
        dyn *d = &k->dyn[k->slot[a]];
        if (!d->len) continue;
        float ba[6];
        if (cand_boxes) memcpy(ba, k->mbox[i], sizeof ba);
        else tri_box(s, va, ba);
        const uint32_t *list = dyn_list(d);
        double ta[3][3], ra[3][3];
        int deg_a = -1, rdeg_a = -1; /* not yet known */
        for (uint32_t j = 0; j < d->len; j++) {
            uint32_t b = list[j];
            if (b < a && k->tstamp[b] == k->tclock) continue; /* both moved: the lower one's */
            /* b's box in s straight away: its triangle and vertices lie near a's in memory
             * on a mesh numbered by region (the envelope, k->dyn[k->slot[b]], would be a
             * filter that reads no vertex, but a cache miss per entry on a large mesh) */
            const uint32_t *vb = c->tris + 3 * (size_t)b;
            float bb[6];
            tri_box(s, vb, bb);
            if (!boxes_meet(ba, bb)) continue;
            if (deg_a < 0) {
                tri_of(s, va, ta);
                deg_a = degenerate(ta);
            }
            if (deg_a) break;
            double tb[3][3], rb[3][3];
            tri_of(s, vb, tb);
            if (degenerate(tb) || !fp_contact_tri_tri(ta, tb)) continue;
            if (rdeg_a < 0) {
                tri_of(ref, va, ra);
                rdeg_a = degenerate(ra);
            }
            tri_of(ref, vb, rb);
            if (!rdeg_a && !degenerate(rb) && fp_contact_tri_tri(ra, rb)) continue;
            if (record && (add_off(c, va) || add_off(c, vb))) return -ENOMEM;
            found++;
        }
    }
    if (!cand_boxes) {
        long f = own_flips(c, s, ref, record);
        if (f < 0) return -ENOMEM;
        *flips += (size_t)f;
    }
    return found;
}

/* P at the moved vertices := P + t (candidate - P), as fp_contact_guard's lerp; ramp (not
 * NULL): vertex i's share is t + (1 - t) ramp[i] (a local scale-back) */
static void track_lerp(struct track *k, double t, const double *ramp)
{
    for (size_t i = 0; i < k->nmv; i++) {
        float *p = k->p + 3 * (size_t)k->mv[i];
        const float *a = k->pv + 3 * i, *b = k->cv + 3 * i;
        double w = ramp ? t + (1 - t) * ramp[i] : t;
        for (int j = 0; j < 3; j++)
            p[j] = w >= 1 ? b[j] : w <= 0 || a[j] == b[j] ? a[j] : (float)((double)a[j] + w * ((double)b[j] - a[j]));
    }
}

/* the vertices of triangle v into off, once each */
static int add_off(fp_contact *c, const uint32_t *v)
{
    struct track *k = c->tk;
    for (int j = 0; j < 3; j++) {
        uint32_t x = v[j];
        if (k->off_mark[x]) continue;
        if (push_u32(&k->off, &k->noff, &k->cap_off, x)) return -ENOMEM;
        k->off_mark[x] = 1;
    }
    return 0;
}

/* ramp[i] for the moved vertices: 0 within local_r of a vertex in off (positions in P, as
 * pv holds them), 1 beyond 2 local_r, smooth between */
static void local_ramp(fp_contact *c)
{
    struct track *k = c->tk;
    double r = c->local_r, r2 = r * r, r4 = 4 * r2, lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t j = 0; j < k->noff; j++) /* their box grown by 2r: beyond it, ramp 1 */
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], k->p[3 * (size_t)k->off[j] + a] - 2 * r);
            hi[a] = fmax(hi[a], k->p[3 * (size_t)k->off[j] + a] + 2 * r);
        }
    for (size_t i = 0; i < k->nmv; i++) {
        const float *p = k->pv + 3 * i;
        double d2 = INFINITY;
        if (p[0] < lo[0] || p[1] < lo[1] || p[2] < lo[2] || p[0] > hi[0] || p[1] > hi[1] || p[2] > hi[2]) {
            k->ramp[i] = 1;
            continue;
        }
        for (size_t j = 0; j < k->noff && d2 > r2; j++) {
            const float *q = k->p + 3 * (size_t)k->off[j];
            double dx = (double)p[0] - q[0], dy = (double)p[1] - q[1], dz = (double)p[2] - q[2];
            d2 = fmin(d2, dx * dx + dy * dy + dz * dz);
        }
        double u = d2 <= r2 ? 0 : d2 >= r4 ? 1 : (sqrt(d2) - r) / r;
        k->ramp[i] = u * u * (3 - 2 * u);
    }
}

static int step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                size_t nranges, int iters, fp_contact_result *res);

int fp_contact_step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                    size_t nranges, int iters, fp_contact_result *res)
{
    memset(res, 0, sizeof *res);
    res->t = 1;
    if (!c || !ref || !cand || (nranges != SIZE_MAX && nranges && !ranges)) return -EINVAL;
    if (!c->tk && track_build(c)) return -ENOMEM;
    if (c->tk->broken) return -ENOMEM;
    int rc = step(c, ref, cand, ranges, nranges, iters, res);
    if (rc) c->tk->broken = true;
    return rc;
}

static int step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                size_t nranges, int iters, fp_contact_result *res)
{
    struct track *k = c->tk;
    tick(k, c->t);
    k->nmv = k->nmt = k->nmo = 0;
    size_t renewed0 = k->renewed;


    /* the moved vertices: where cand differs from P */
    if (collect_moved(c, cand, ranges, nranges)) return -ENOMEM;
    res->moved_verts = k->nmv;
    if (!k->nmv) return 0; /* nothing moved: P is the candidate */
    for (size_t i = 0; i < k->nmv; i++)
        if (mark_tris(c, k->mv[i])) return -ENOMEM;

    res->moved_tris = k->nmt;

    /* envelopes that hold each moved triangle in the candidate (and, before a bisection,
     * in P too, so in every shape between them) */
    if (reserve((void **)&k->mbox, &k->cap_mbox, k->nmt, sizeof *k->mbox)) return -ENOMEM;
    size_t fl = 0; /* newly flipped triangles of the candidate */
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        tri_box(cand, va, k->mbox[i]);
        if (k->slot[a] == FP_TRACK_NONE) static_remove(c, a); /* P is still the weld shape */
        if ((k->slot[a] == FP_TRACK_NONE || !box_holds(k->dyn[k->slot[a]].env, k->mbox[i])) &&
            envelope(c, a, k->mbox[i]))
            return -ENOMEM;
        if (flipped(c, cand, va, a) && !flipped(c, ref, va, a)) fl++;
    }
    fl += (size_t)own_flips(c, cand, ref, false);
    if (renew_lists(c)) return -ENOMEM;



    long found = track_check(c, cand, ref, true, &fl, false);
    res->checks = 1;
    res->pairs = found;
    res->flipped = fl;
    if (found || fl) {
        /* the bisection over P -> candidate: envelopes that hold P's boxes too */
        for (size_t i = 0; i < k->nmt; i++) {
            uint32_t a = k->mt[i];
            float hull[6];
            tri_box(k->p, c->tris + 3 * (size_t)a, hull);
            for (int j = 0; j < 3; j++) {
                hull[j] = min_f(hull[j], k->mbox[i][j]);
                hull[3 + j] = max_f(hull[3 + j], k->mbox[i][3 + j]);
            }
            if (!box_holds(k->dyn[k->slot[a]].env, hull) && envelope(c, a, hull)) return -ENOMEM;
        }
        if (renew_lists(c)) return -ENOMEM;
        size_t cap = k->cap_pv;
        if (reserve((void **)&k->pv, &cap, 3 * k->nmv, sizeof *k->pv) ||
            reserve((void **)&k->cv, &k->cap_pv, 3 * k->nmv, sizeof *k->cv))
            return -ENOMEM;
        float *pv = k->pv, *cv = k->cv;
        for (size_t i = 0; i < k->nmv; i++) {
            memcpy(pv + 3 * i, k->p + 3 * (size_t)k->mv[i], 3 * sizeof(float));
            memcpy(cv + 3 * i, cand + 3 * (size_t)k->mv[i], 3 * sizeof(float));
        }
        /* a local scale-back first: the motion near the blocking triangles is scaled, the
         * rest kept (ramp); the shape with none of the near motion must pass (else the
         * triangles it blocks join, FP_CONTACT_LOCAL_ROUNDS times), else the global one */
        const double *ramp = NULL;
        if (c->local_r > 0 && iters > 0) {
            if (reserve((void **)&k->ramp, &k->cap_ramp, k->nmv, sizeof *k->ramp)) return -ENOMEM;
            for (size_t i = 0; i < k->noff; i++) k->off_mark[k->off[i]] = 0;
            k->noff = 0;
            long m = track_check(c, cand, ref, false, &fl, true);
            for (int round = 0; m > 0 || fl; round++) {
                if (m < 0) return -ENOMEM;
                if (round == FP_CONTACT_LOCAL_ROUNDS) break;
                track_lerp(k, 0, NULL); /* P, where the distances are taken */
                local_ramp(c);
                track_lerp(k, 0, k->ramp);
                m = track_check(c, k->p, ref, false, &fl, true);
                res->checks++;
                if (!m && !fl) ramp = k->ramp;
            }
            track_lerp(k, 0, NULL);
        }
        double lo = 0, hi = 1;
        for (int i = 0; i < iters; i++) {
            double mid = 0.5 * (lo + hi);
            track_lerp(k, mid, ramp);
            long m = track_check(c, k->p, ref, false, &fl, false);
            res->checks++;
            if (m < 0) return -ENOMEM;
            if (m || fl) hi = mid;
            else lo = mid;
        }
        track_lerp(k, lo, ramp);
        res->t = lo;
        res->local = ramp != NULL;
    } else {
        for (size_t i = 0; i < k->nmv; i++)
            memcpy(k->p + 3 * (size_t)k->mv[i], cand + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    }
    res->renewed = k->renewed - renewed0;
    /* D_P: where P now differs from the reference */
    size_t w = 0;
    for (size_t i = 0; i < k->ndp; i++) {
        uint32_t v = k->dp[i];
        if (vert_differs(k->p, ref, v)) k->dp[w++] = v;
        else k->in_dp[v] = 0;
    }
    k->ndp = w;
    for (size_t i = 0; i < k->nmv; i++) {
        uint32_t v = k->mv[i];
        if (!k->in_dp[v] && vert_differs(k->p, ref, v)) {
            k->in_dp[v] = 1;
            k->dp[k->ndp++] = v;
        }
    }
    return 0;
}

const float *fp_contact_shape(const fp_contact *c) { return c && c->tk ? c->tk->p : NULL; }

void fp_contact_set_prewarm(fp_contact *c, size_t max_tris)
{
    if (c) c->prewarm = max_tris;
}

/* the unnormalised normal of triangle v in pos */
static void tri_normal(const float *pos, const uint32_t *v, double n[3])
{
    double t[3][3], e1[3], e2[3];
    tri_of(pos, v, t);
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

int fp_contact_set_pose(fp_contact *c, const float *base, const float *posed)
{
    if (!c || (!base) != (!posed)) return -EINVAL;
    if (!c->nrm_weld) {
        if (!base || posed == base) return 0; /* the weld shape's, as made */
        c->nrm_weld = malloc((c->t ? c->t : 1) * sizeof *c->nrm_weld);
        if (!c->nrm_weld) return -ENOMEM;
        memcpy(c->nrm_weld, c->nrm, c->t * sizeof *c->nrm);
    }
    for (size_t i = 0; i < c->t; i++) {
        const uint32_t *v = c->tris + 3 * i;
        double w[3] = {c->nrm_weld[i][0], c->nrm_weld[i][1], c->nrm_weld[i][2]};
        /* a triangle the pose left in place keeps its normal (bit for bit what the rotation
         * below gives: the least rotation taking a to a is the identity), without its cost */
        if (base && posed != base &&
            (memcmp(base + 3 * (size_t)v[0], posed + 3 * (size_t)v[0], 3 * sizeof(float)) ||
             memcmp(base + 3 * (size_t)v[1], posed + 3 * (size_t)v[1], 3 * sizeof(float)) ||
             memcmp(base + 3 * (size_t)v[2], posed + 3 * (size_t)v[2], 3 * sizeof(float)))) {
            double a[3], b[3], la = 0, lb = 0;
            tri_normal(base, v, a);
            tri_normal(posed, v, b);
            for (int k = 0; k < 3; k++) la += a[k] * a[k], lb += b[k] * b[k];
            la = sqrt(la);
            lb = sqrt(lb);
            if (la > 0 && lb > 0) {
                for (int k = 0; k < 3; k++) a[k] /= la, b[k] /= lb;
                double cs = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], ax[3], t1[3], t2[3];
                if (cs > -0.999999) { /* w rotated by the least rotation taking a to b */
                    cross3(a, b, ax);
                    cross3(ax, w, t1);
                    cross3(ax, t1, t2);
                    for (int k = 0; k < 3; k++) w[k] += t1[k] + t2[k] / (1 + cs);
                } else { /* turned over by the pose: the posed normal's side */
                    double s = 0;
                    for (int k = 0; k < 3; k++) s += w[k] * w[k];
                    s = sqrt(s);
                    for (int k = 0; k < 3; k++) w[k] = b[k] * s;
                }
            }
        }
        for (int k = 0; k < 3; k++) c->nrm[i][k] = (float)w[k];
    }
    return 0;
}

void fp_contact_set_local(fp_contact *c, double radius)
{
    if (c) c->local_r = radius > 0 && isfinite(radius) ? radius : 0;
}
