/* The contact guard: new self-crossings among moved triangles, and the bisection (contact.h). */
#define _POSIX_C_SOURCE 200809L /* sched_yield */
#include "contact.h"
#include "fp_plugin_host.h" /* fp_now_ns, the host's clock */

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
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

struct fp_contact {
    const uint32_t *tris;
    size_t t, n;
    uint32_t *weld;       /* n: the first vertex at the same position */
    uint8_t *moved;       /* n: vertex moved this check */
    uint32_t *ins;        /* triangles in the grid */
    float (*box)[6];      /* t: candidate bounding box (min xyz, max xyz) of inserted ones */
    struct cellrec *rec, *rec_tmp; /* the check's grid: (cell, triangle), sorted by cell */
    size_t rec_cap;
    struct cellrun *run;  /* one cell's triangles, as the check's sweep reads them */
    size_t run_cap;
    uint8_t *own;         /* t: the triangle crosses another in the weld shape */
    float (*nrm)[3];      /* t: the rest normals (flips are against them): the weld shape's
                             triangle normals (unnormalised), carried by fp_contact_set_pose */
    float (*nrm_weld)[3]; /* t: the weld shape's, kept at the first fp_contact_set_pose */
    struct track *tk;     /* the incremental guard (fp_contact_step), made on first use */
    float *weld_copy;     /* n x 3: the weld shape, the tracker's first P (freed then) */
    size_t prewarm;       /* fp_contact_set_prewarm */
    bool certify;         /* fp_contact_set_certify */
    int threads;          /* fp_contact_set_threads: 1 or 2 */
    size_t share_min;     /* fp_contact_set_threads: moved triangles from which a check is shared */
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

/* A triangle t's plane for the tests of points against it: e1 = t[1] - t[0], e2 = t[2] - t[0],
 * the six products of orient3d's minors made once (n: e1 x e2 with the sign convention of
 * orient3d's expansion, f: the permanent's factors). plane_side(pl, q) is then
 * orient3d(t[0], q, t[1], t[2]) bit for bit (same operations in the same order), whose exact
 * sign is orient3d(t[0], t[1], t[2], q)'s (a cyclic permutation of the determinant's rows);
 * deg: e1 x e2 is exactly 0 in double (a degenerate triangle, which meets nothing here). */
typedef struct tplane {
    const double *o;
    double n[3], f[3];
    bool deg;
} tplane;

static inline void plane_of(const double t[3][3], tplane *pl)
{
    double ux = t[1][0] - t[0][0], uy = t[1][1] - t[0][1], uz = t[1][2] - t[0][2];
    double vx = t[2][0] - t[0][0], vy = t[2][1] - t[0][1], vz = t[2][2] - t[0][2];
    double m1 = uy * vz, m2 = uz * vy, m3 = ux * vz, m4 = uz * vx, m5 = ux * vy, m6 = uy * vx;
    pl->o = t[0];
    pl->n[0] = m1 - m2;
    pl->n[1] = m3 - m4;
    pl->n[2] = m5 - m6;
    pl->f[0] = fabs(m1) + fabs(m2);
    pl->f[1] = fabs(m3) + fabs(m4);
    pl->f[2] = fabs(m5) + fabs(m6);
    pl->deg = pl->n[0] == 0 && pl->n[1] == 0 && pl->n[2] == 0;
}

static inline int plane_side(const tplane *pl, const double *q)
{
    double cx = q[0] - pl->o[0], cy = q[1] - pl->o[1], cz = q[2] - pl->o[2];
    double det = cx * pl->n[0] - cy * pl->n[1] + cz * pl->n[2];
    double perm = fabs(cx) * pl->f[0] + fabs(cy) * pl->f[1] + fabs(cz) * pl->f[2];
    double bound = (7.0 + 56.0 * FP_EPS) * FP_EPS * perm;
    return (det > bound) - (det < -bound);
}

/* fp_contact_tri_tri with the planes made (pa NULL: made here when needed) */
static int tri_tri_pl(const double a[3][3], const tplane *pa, const double b[3][3], const tplane *pb)
{
    /* each vertex against the other's plane, once (every edge test starts with these); a
     * triangle certainly on one side of the other's plane shares no point with it */
    int oa[3], ob[3];
    for (int i = 0; i < 3; i++) oa[i] = plane_side(pb, a[i]);
    if (oa[0] && oa[0] == oa[1] && oa[1] == oa[2]) return 0;
    tplane own;
    if (!pa) {
        plane_of(a, &own);
        pa = &own;
    }
    for (int i = 0; i < 3; i++) ob[i] = plane_side(pa, b[i]);
    if (ob[0] && ob[0] == ob[1] && ob[1] == ob[2]) return 0;
    for (int e = 0; e < 3; e++) {
        int f = (e + 1) % 3;
        if (seg_tri(a[e], a[f], b, oa[e], oa[f]) || seg_tri(b[e], b[f], a, ob[e], ob[f])) return 1;
    }
    return 0;
}

int fp_contact_tri_tri(const double a[3][3], const double b[3][3])
{
    tplane pb;
    plane_of(b, &pb);
    return tri_tri_pl(a, NULL, b, &pb);
}

/* b is not degenerate and shares a point with a, whose plane pa is made (a not degenerate) */
static inline bool meets_pl(const double a[3][3], const tplane *pa, const double b[3][3])
{
    tplane pb;
    plane_of(b, &pb);
    return !pb.deg && tri_tri_pl(a, pa, b, &pb);
}

/* neither triangle degenerate (tplane.deg) and fp_contact_tri_tri(a, b), each plane made
 * once */
static bool tris_meet(const double a[3][3], const double b[3][3])
{
    tplane pa;
    plane_of(a, &pa);
    return !pa.deg && meets_pl(a, &pa, b);
}

typedef struct fp_contact_count fp_contact_count;
static void track_free(struct track *k);
static void cross3(const double a[3], const double b[3], double o[3]);
static void tri_of(const float *pos, const uint32_t *v, double out[3][3]);
static long scan(fp_contact *c, const float *ref, const float *cand, bool all, uint32_t *pairs,
                 size_t max_pairs, fp_contact_count *info);
static inline bool welded_adjacent(const uint32_t a[3], const uint32_t b[3]);
static int reserve(void **p, size_t *cap, size_t need, size_t el);

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
 * creates on two threads do not meet (contact.h: one fp_contact per thread). */
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

static void bg_join(fp_contact *c);

int fp_contact_dilate_own(fp_contact *c, int rings)
{
    bg_join(c);
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
    bg_join(c);
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

/* the closed boxes meet; without a branch (track_check's filter takes it by the data) */
static inline bool boxes_meet(const float *a, const float *b)
{
    return (a[0] <= b[3]) & (b[0] <= a[3]) & (a[1] <= b[4]) & (b[1] <= a[4]) & (a[2] <= b[5]) & (b[2] <= a[5]);
}

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

/* n (e1 x e2 in double) turned by more than acos(FP_CONTACT_FLIP_COS) from triangle i's rest
 * normal (a unit vector): d < FP_CONTACT_FLIP_COS |n|, without a square root */
static inline bool flipped_n(const fp_contact *c, const double n[3], size_t i)
{
    double d = n[0] * c->nrm[i][0] + n[1] * c->nrm[i][1] + n[2] * c->nrm[i][2];
    return d < 0 || d * d < FP_CONTACT_FLIP_COS * FP_CONTACT_FLIP_COS * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
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
    return flipped_n(c, n, i);
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
        if (info && ref && flipped(c, cand, v, i) && !flipped(c, ref, v, i))
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
    bg_join(c);
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
#define FP_TRACK_RECENTRE 0.5     /* after a step, a moved triangle whose box in P comes within
                                     this share of the skin of its envelope's side gets a new
                                     one around that box (recentre, on the worker) */

#define FP_CONTACT_LOCAL_ROUNDS 3 /* a local scale-back: times its blocking set may grow */
#define FP_TRACK_INLINE 6          /* list entries kept in the dyn itself (one cache line) */

#define FP_CONTACT_MAX_THREADS 2  /* the caller and one worker (fp_contact_set_threads) */
#define FP_BVH_LEAF 24            /* triangles in a leaf of the hierarchy, at most */
#define FP_CERT_MIN 48            /* a patch (node) with this many triangles or more ... */
#define FP_CERT_MAX 65536         /* ... and no more may be certified (its boundary made once;
                                     262,144 or 1,048,576 certified no more patches of the
                                     1.68M face, 28 a frame, and its failed tries cost more) */

typedef struct bnode {            /* a node of the hierarchy: a patch of triangles (64 bytes,
                                     one cache line; its stamp is in nstamp) */
    float box[6];                 /* its triangles' box in P (in the shape checked, in a check) */
    uint32_t first, count;        /* its triangles: order[first .. first + count) */
    uint32_t right;               /* its right child (the left one is the next node); 0: leaf */
    uint32_t cert;                /* its boundary cycle (index into cert); FP_TRACK_NONE: none */
    float nlo[3], nhi[3];         /* a box that holds its triangles' unit normals (in P) */
} bnode;
_Static_assert(sizeof(bnode) == 64, "a node is one cache line");

typedef struct cert {             /* a patch whose boundary is one simple cycle */
    uint32_t start, len;          /* the cycle's vertices: cyc[start .. start + len) */
} cert;


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
                                     envelope and welded vertices (read in order, not through
                                     slot, dyn and the mesh) */
    float env[6];
    uint32_t tri;
    uint32_t w[3];
} centry;

typedef struct cellvec {          /* a cell of the dynamic grid */
    int64_t key[3];
    centry *ids;
    uint32_t len, cap;
    bool used;
} cellvec;

typedef struct lane {             /* one thread's part of a hierarchy check: scratch and counts */
    double *xy;                   /* a contour's projection (2 per vertex) */
    size_t cap_xy;
    uint32_t *gcount, *gseg;      /* its segments by grid cell */
    size_t cap_gcount, cap_gseg;
    uint16_t (*grange)[4];        /* each segment's cells (x0, x1, y0, y1) */
    size_t cap_grange;
    float (*sbox)[4];             /* each segment's box in float, rounded outwards (x0, x1,
                                     y0, y1; the upper corner over the margin el) */
    size_t cap_sbox;
    size_t certified, tested;     /* patches certified, triangle pairs tested */
    size_t moved;                 /* moved triangles its refit tasks met */
    uint32_t *mq;                 /* one refit task's moved places (gather) */
    size_t nmq, cap_mq;
    uint32_t *mv, *mo;            /* its share of the marking (collect_mark): moved vertices,
                                     moved own triangles */
    size_t nmv, nmo, cap_mv, cap_mo;
    long found, flips;            /* its tasks' new pairs and flips; -ENOMEM sticks */
    uint32_t *rec;                /* the blocking triangles it found: the newly flipped ones
                                     of a check's update, and with record those of its new
                                     pairs (their vertices into off: rec_merge) */
    size_t nrec, cap_rec;
} lane;

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
    uint32_t *rx;                 /* one cell's requests: their triangles, envelopes and
                                     welded vertices */
    float *renv;                  /* their envelopes by coordinate: renv[a nr + i] (nr of them) */
    uint32_t (*rw)[3];
    uint32_t *rlo;                /* the axes (bits 0-2) where its envelope's lower corner is
                                     in the cell */
    size_t cap_rx, cap_renv, cap_rw, cap_rlo;
    size_t renewed;               /* envelopes renewed, for fp_contact_result */
    bool tree;                    /* the hierarchy (below), not envelopes (a large mesh) */
    bnode *node;                  /* the hierarchy over the triangles not own, root node[0] */
    uint32_t *nstamp;             /* by node: == tclock when it holds a moved triangle */
    size_t nnode;
    uint32_t *order;              /* its triangles, by node */
    uint32_t *tpos;               /* t: a triangle's place in order (FP_TRACK_NONE: own) */
    float (*tn)[3];               /* by place in order: its normal in P (tri_normal_f) */
    float (*tbox)[6];             /* by place in order: its box in P */
    uint32_t *pstamp;             /* by place in order: == tclock when moved (gather) */
    uint32_t *vstamp;             /* n: == tclock when the vertex moved (mark_range); in
                                     tree_build, boundary's check numbers first (bgen) */
    uint32_t bgen;                /* boundary: the last check's number */
    uint32_t *bidx;               /* n, tree_build only: boundary's edge index by source */
    uint8_t *has_own;             /* n: the vertex has an own triangle */
    uint32_t *bstamp, *sbstamp;   /* by block of 64 and of 4096 places: == rclock when one of
                                     them has a vertex in D_P (the region: every moved
                                     triangle is in it; the refit looks for them there,
                                     maybe_moved) */
    uint32_t rclock;              /* the region's clock: a new one when D_P is emptied */
    uint32_t *vtp;                /* beside vt: the triangle's place in order (tpos) */
    uint32_t (*ow)[3];            /* by place in order: its vertices welded (adjacency) */
    uint32_t (*ov)[3];            /* by place in order: its vertices */
    size_t nmq;                   /* the hierarchy's moved triangles (counted by the refit) */
    cert *cert;
    size_t ncert;
    uint32_t *cyc;                /* the certifiable patches' boundary cycles */
    lane lane[FP_CONTACT_MAX_THREADS]; /* [0]: the caller's thread; [1]: the pool's worker */
    struct pool *pool;            /* the worker (fp_contact_set_threads), made on first use */
    size_t shared;                /* this step: checks shared with the worker */
    int64_t waited_ns;            /* the caller's waits for the worker's tasks (job_finish), ns,
                                     all told */
    uint32_t *off;                /* a local scale-back: the blocking triangles' vertices */
    size_t noff, cap_off;
    uint8_t *off_mark;            /* n: in off */
    double *ramp;                 /* per moved vertex: the share of its motion always kept */
    size_t cap_ramp;
    size_t updates;               /* the hierarchy: tree_update calls so far */
    uint32_t *probe;              /* the hierarchy: triangles newly flipped in the step's last
                                     check that had any (a bisection's check tries them first) */
    size_t nprobe, cap_probe;
    uint32_t *kd_ix;              /* local_ramp: off's vertices, in its k-d tree's order */
    size_t cap_kd_ix;
    struct kdnode *kd;            /* local_ramp's k-d tree over them (node 0 the root) */
    size_t cap_kd;
    bool bg;                      /* a recentre job is posted to the worker (bg_join) */
    bool broken;                  /* a call ran out of memory half way: unusable */
};

static void pool_free(struct pool *p);

static void track_free(struct track *k)
{
    if (!k) return;
    pool_free(k->pool);
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
    free(k->rw);
    free(k->rlo);
    free(k->renv);
    free(k->node);
    free(k->nstamp);
    free(k->order);
    free(k->tpos);
    free(k->tn);
    free(k->tbox);
    free(k->pstamp);
    free(k->vtp);
    free(k->ow);
    free(k->ov);
    free(k->bstamp);
    free(k->sbstamp);
    free(k->vstamp);
    free(k->has_own);
    free(k->cert);
    free(k->cyc);
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        free(k->lane[i].xy);
        free(k->lane[i].rec);
        free(k->lane[i].gcount);
        free(k->lane[i].gseg);
        free(k->lane[i].grange);
        free(k->lane[i].sbox);
        free(k->lane[i].mq);
        free(k->lane[i].mv);
        free(k->lane[i].mo);
    }
    free(k->off);
    free(k->off_mark);
    free(k->ramp);
    free(k->probe);
    free(k->kd_ix);
    free(k->kd);
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

/* A zero stored on every page of p's n bytes (volatile: a memset of fresh memory may be
 * folded into calloc, which leaves the pages untouched). Fresh pages fault at their first
 * read and again at their first write, microseconds each on a virtual machine (10 such
 * faults made the ICT face's first deforming frame 0.4-1.3 ms): memory a step writes is
 * written here, at the build, not in a gesture's first frames. */
static void write_pages(void *p, size_t n)
{
    for (size_t i = 0; p && i < n; i += 4096) ((volatile char *)p)[i] = 0;
}

/* n zeroed elements of size el, every page written now (write_pages), or NULL */
static void *zalloc(size_t n, size_t el)
{
    void *p = calloc(n, el);
    write_pages(p, n * el);
    return p;
}

/* reserve, then every page of the room written (write_pages) */
static int reserve_written(void **p, size_t *cap, size_t need, size_t el)
{
    if (reserve(p, cap, need, el)) return -ENOMEM;
    write_pages(*p, *cap * el);
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

/* box b's largest side, in double */
static inline double box_extent(const float b[6])
{
    return fmax(fmax((double)b[3] - b[0], (double)b[4] - b[1]), (double)b[5] - b[2]);
}

/* box b grown by m on every side into out */
static inline void box_grown(const float b[6], float m, float out[6])
{
    for (int i = 0; i < 3; i++) {
        out[i] = b[i] - m;
        out[3 + i] = b[3 + i] + m;
    }
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

static int grid_add(fp_contact *c, dyn *d)
{
    struct track *k = c->tk;
    const uint32_t *v = c->tris + 3 * (size_t)d->tri;
    const uint32_t w[3] = {c->weld[v[0]], c->weld[v[1]], c->weld[v[2]]};
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
                memcpy(en->w, w, sizeof w);
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

/* k->q = the triangles not own, other than x and not adjacent to it, whose envelope meets
 * box q. */
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
        for (size_t i = 0; i < k->ndyn; i++) FP_DYNAMIC(k->dyn[i].tri);
    } else {
        for (int64_t cx = lo[0]; cx <= hi[0]; cx++)
            for (int64_t cy = lo[1]; cy <= hi[1]; cy++)
                for (int64_t cz = lo[2]; cz <= hi[2]; cz++) {
                    int64_t key[3] = {cx, cy, cz};
                    const cellvec *cv = cell_find(k, key, false);
                    for (uint32_t i = 0; cv && i < cv->len; i++) FP_DYNAMIC(cv->ids[i].tri);
                }
        for (size_t i = 0; i < k->ndbig; i++) FP_DYNAMIC(k->dbig[i]);
    }
#undef FP_DYNAMIC
#undef FP_NOT_ADJ
    return 0;
}

/* Give triangle x (not own) the envelope box +
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
    box_grown(box, (float)(FP_TRACK_SKIN * box_extent(box)), d->env);
    d->len = 0;
    if (grid_add(c, d)) return -ENOMEM;
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

/* two triangles given by their welded vertices share one */
static inline bool welded_adjacent(const uint32_t a[3], const uint32_t b[3])
{
    return a[0] == b[0] || a[0] == b[1] || a[0] == b[2] || a[1] == b[0] || a[1] == b[1] || a[1] == b[2] ||
           a[2] == b[0] || a[2] == b[1] || a[2] == b[2];
}

static bool adjacent(const fp_contact *c, uint32_t x, uint32_t y)
{
    const uint32_t *vx = c->tris + 3 * (size_t)x, *vy = c->tris + 3 * (size_t)y;
    const uint32_t wx[3] = {c->weld[vx[0]], c->weld[vx[1]], c->weld[vx[2]]},
                   wy[3] = {c->weld[vy[0]], c->weld[vy[1]], c->weld[vy[2]]};
    return welded_adjacent(wx, wy);
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

#define FP_RENEW_BATCH 64 /* requests tested at once against a registered envelope */

/* the axes (bit a for axis a) on which box b's lower corner lies in the cell key */
static inline uint32_t lower_in(const struct track *k, const float *b, const int64_t key[3])
{
    return (uint32_t)(cell_coord(b[0], k->ih) == key[0]) | (uint32_t)(cell_coord(b[1], k->ih) == key[1]) << 1 |
           (uint32_t)(cell_coord(b[2], k->ih) == key[2]) << 2;
}

/* One cell of the batch: requests R (nr of them) against the triangles registered in the
 * cell (static: the bucket's, whose boxes are the weld shape's; dynamic: the cell's). A
 * pair is taken in the cell of its boxes' common lower corner only (so once). */
static int renew_cell(fp_contact *c, const int64_t key[3], const uint32_t *R, size_t nr, uint32_t clock)
{
    struct track *k = c->tk;
    /* the requests' triangles and envelopes, side by side */
    if (reserve((void **)&k->renv, &k->cap_renv, 6 * nr, sizeof *k->renv) ||
        reserve((void **)&k->rx, &k->cap_rx, nr, sizeof *k->rx) ||
        reserve((void **)&k->rw, &k->cap_rw, nr, sizeof *k->rw) ||
        reserve((void **)&k->rlo, &k->cap_rlo, nr, sizeof *k->rlo))
        return -ENOMEM;
    for (size_t i = 0; i < nr; i++) {
        k->rx[i] = k->rq[R[i]];
        const float *env = k->dyn[k->slot[k->rx[i]]].env;
        for (int a = 0; a < 6; a++) k->renv[a * nr + i] = env[a];
        for (int j = 0; j < 3; j++) k->rw[i][j] = c->weld[c->tris[3 * (size_t)k->rx[i] + j]];
        k->rlo[i] = lower_in(k, env, key);
    }
    const cellvec *cv = cell_find(k, key, false);
    if (!cv) return 0;
    /* each registered triangle's envelope against every request in one branch-free loop
     * (vectorised: the hits whose pair is this cell's), then those.
     * The pair's cell is that of its boxes' common lower corner, max(ex, b) on each axis:
     * cell_coord is monotonic, so that is this cell (which holds both lower corners or
     * cells beyond them) iff on each axis one of the two lower corners is in it. */
    const float *lx = k->renv, *ly = lx + nr, *lz = ly + nr, *hx = lz + nr, *hy = hx + nr, *hz = hy + nr;
    const uint32_t *rlo = k->rlo;
    for (size_t i0 = 0; i0 < nr; i0 += FP_RENEW_BATCH) {
        size_t i1 = nr - i0 > FP_RENEW_BATCH ? i0 + FP_RENEW_BATCH : nr;
        for (uint32_t j = 0; j < cv->len; j++) { /* (own triangles have no envelope) */
            const centry *en = &cv->ids[j];
            const float b0 = en->env[0], b1 = en->env[1], b2 = en->env[2], b3 = en->env[3],
                        b4 = en->env[4], b5 = en->env[5];
            uint32_t blo = lower_in(k, en->env, key), any = 0, hit[FP_RENEW_BATCH];
            for (size_t i = i0; i < i1; i++) {
                uint32_t h = (uint32_t)(lx[i] <= b3) & (uint32_t)(b0 <= hx[i]) & (uint32_t)(ly[i] <= b4) &
                             (uint32_t)(b1 <= hy[i]) & (uint32_t)(lz[i] <= b5) & (uint32_t)(b2 <= hz[i]) &
                             (uint32_t)((rlo[i] | blo) == 7);
                hit[i - i0] = h;
                any |= h;
            }
            for (size_t i = i0; any && i < i1; i++) {
                if (!hit[i - i0]) continue;
                uint32_t x = k->rx[i];
                if (en->tri != x && !welded_adjacent(k->rw[i], en->w) && link(c, x, en->tri, clock))
                    return -ENOMEM;
            }
        }
    }
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
    for (size_t i = 0; i < k->ndbig; i++) {
        uint32_t y = k->dbig[i];
        if (c->own[y]) continue;
        float yb[6];
        memcpy(yb, k->dyn[k->slot[y]].env, sizeof yb);
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

/* ==== the hierarchy (contact.h, "The hierarchy"): a large mesh's broad phase ==== */

/* ---- a patch's certificate (contact.h, "(3)") ---- */

/* Triangle v's unit normal in pos (e1 x e2 normalised, as flipped; in double, stored as
 * floats) into out, or 0 when e1 x e2 is within 1e-10 |e1|_1 |e2|_1 of 0 (degenerate: its
 * direction there is rounding), NaN or beyond float's range. e1 x e2 (double) into nd for
 * the flip test. A certificate's test (certified: 1e-4 over a unit normal) then errs only
 * towards "not facing". */
static inline void tri_normal_f(const float *pos, const uint32_t *v, float out[3], double nd[3])
{
    const float *p0 = pos + 3 * (size_t)v[0], *p1 = pos + 3 * (size_t)v[1], *p2 = pos + 3 * (size_t)v[2];
    double e1[3], e2[3];
    for (int j = 0; j < 3; j++) {
        e1[j] = (double)p1[j] - p0[j];
        e2[j] = (double)p2[j] - p0[j];
    }
    nd[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nd[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nd[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l1 = fabs(nd[0]) + fabs(nd[1]) + fabs(nd[2]);
    double m = 1e-10 * (fabs(e1[0]) + fabs(e1[1]) + fabs(e1[2])) * (fabs(e2[0]) + fabs(e2[1]) + fabs(e2[2]));
    if (!(l1 > m) || !(l1 < 1e30)) {
        out[0] = out[1] = out[2] = 0.f;
        return;
    }
    double il = 1 / sqrt(nd[0] * nd[0] + nd[1] * nd[1] + nd[2] * nd[2]);
    for (int j = 0; j < 3; j++) out[j] = (float)(nd[j] * il);
}

/* min and max of finite doubles, inline */
static inline double dmin(double a, double b) { return b < a ? b : a; }
static inline double dmax(double a, double b) { return b > a ? b : a; }

/* 2D orientation of (a, b, c): twice the signed area */
static inline double orient2(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* finite x as a float not above it, and not below it: moved out by 2^-22 of itself (over
 * the 2^-24 of rounding to float) and 2^-126 (where float is subnormal) before rounding */
static inline float f_down(double x) { return (float)(x - fabs(x) * 0x1p-22 - 0x1p-126); }
static inline float f_up(double x) { return (float)(x + fabs(x) * 0x1p-22 + 0x1p-126); }

/* two boxes (x0, x1, y0, y1) meet */
static inline bool boxes2_meet(const float *a, const float *b)
{
    return (a[0] <= b[1]) & (b[0] <= a[1]) & (a[2] <= b[3]) & (b[2] <= a[3]);
}

/* closed segments ab and cd may meet: not certainly apart (signs beyond the margin e) */
static bool segs_may_meet(const double *a, const double *b, const double *c, const double *d, double e,
                          double el)
{
    if (dmax(a[0], b[0]) + el < dmin(c[0], d[0]) || dmax(c[0], d[0]) + el < dmin(a[0], b[0]) ||
        dmax(a[1], b[1]) + el < dmin(c[1], d[1]) || dmax(c[1], d[1]) + el < dmin(a[1], b[1]))
        return false;
    double d1 = orient2(a, b, c), d2 = orient2(a, b, d);
    if ((d1 > e && d2 > e) || (d1 < -e && d2 < -e)) return false;
    double d3 = orient2(c, d, a), d4 = orient2(c, d, b);
    if ((d3 > e && d4 > e) || (d3 < -e && d4 < -e)) return false;
    return true;
}

/* The cycle cyc (len vertices, positions in s) projected along direction d is certainly a
 * simple polygon: no two segments meet but neighbours at their shared vertex, and neighbours
 * do not fold back over each other. Projections in double; a sign within a margin far over
 * their rounding counts as uncertain, and uncertain is "not simple". Segments meet only in
 * grid cells they share (a grid of about len cells over the polygon's box). 0: simple, 1: not,
 * -ENOMEM. */
static int contour_tangled(lane *k, const float *s, const uint32_t *cyc, uint32_t len, const double *u,
                           const double *w)
{
    if (len < 3) return 1;
    if (reserve((void **)&k->xy, &k->cap_xy, 2 * (size_t)len, sizeof *k->xy)) return -ENOMEM;
    double *xy = k->xy, lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, big = 0;
    for (uint32_t i = 0; i < len; i++) {
        if (i + 12 < len) __builtin_prefetch(s + 3 * (size_t)cyc[i + 12]);
        const float *p = s + 3 * (size_t)cyc[i];
        double x = p[0] * u[0] + p[1] * u[1] + p[2] * u[2], y = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
        xy[2 * i] = x;
        xy[2 * i + 1] = y;
        lo[0] = dmin(lo[0], x), hi[0] = dmax(hi[0], x);
        lo[1] = dmin(lo[1], y), hi[1] = dmax(hi[1], y);
        big = dmax(big, dmax(fabs(p[0]), dmax(fabs(p[1]), fabs(p[2]))));
    }
    double ext = dmax(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(ext > 0) || !isfinite(big)) return 1;
    double scale = ext + big, el = 1e-9 * scale, e = 1e-9 * scale * scale;
    /* neighbours: not folded back (collinear with the next one turned around) */
    for (uint32_t i = 0; i < len; i++) {
        const double *a = xy + 2 * (size_t)(i ? i - 1 : len - 1), *b = xy + 2 * (size_t)i,
                     *c = xy + 2 * (size_t)(i + 1 < len ? i + 1 : 0);
        if (fabs(orient2(a, b, c)) <= e &&
            (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1]) <= e)
            return 1;
    }
    if (len == 3) return 0;
    /* the others, by grid cell */
    uint32_t g = 1;
    while ((size_t)g * g < len) g++;
    double ic = g / ext;
#define FP_CELL(x, a) ((uint16_t)dmin((double)(g - 1), dmax(0.0, ((x) - lo[a]) * ic)))
    /* (g - 1 < 65536 for len < 2^32: a cell index fits 16 bits) */
    if (reserve((void **)&k->grange, &k->cap_grange, len, sizeof *k->grange) ||
        reserve((void **)&k->sbox, &k->cap_sbox, len, sizeof *k->sbox))
        return -ENOMEM;
    uint16_t(*gr)[4] = k->grange; /* each segment's cells, made once */
    float(*sb)[4] = k->sbox;
    size_t ne = 0;
    for (uint32_t i = 0; i < len; i++) {
        const double *a = xy + 2 * (size_t)i, *b = xy + 2 * (size_t)(i + 1 < len ? i + 1 : 0);
        double x0 = dmin(a[0], b[0]), x1 = dmax(a[0], b[0]) + el, y0 = dmin(a[1], b[1]), y1 = dmax(a[1], b[1]) + el;
        gr[i][0] = FP_CELL(x0 - el, 0);
        gr[i][1] = FP_CELL(x1, 0);
        gr[i][2] = FP_CELL(y0 - el, 1);
        gr[i][3] = FP_CELL(y1, 1);
        ne += (size_t)(gr[i][1] - gr[i][0] + 1) * (gr[i][3] - gr[i][2] + 1);
        sb[i][0] = f_down(x0);
        sb[i][1] = f_up(x1);
        sb[i][2] = f_down(y0);
        sb[i][3] = f_up(y1);
    }
#undef FP_CELL
    if (ne > 16 * (size_t)len) return 1; /* segments long against the polygon: not worth it */
    if (reserve((void **)&k->gcount, &k->cap_gcount, (size_t)g * g + 1, sizeof *k->gcount) ||
        reserve((void **)&k->gseg, &k->cap_gseg, ne, sizeof *k->gseg))
        return -ENOMEM;
    uint32_t *cnt = k->gcount, *seg = k->gseg;
    memset(cnt, 0, ((size_t)g * g + 1) * sizeof *cnt);
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t i = 0; i < len; i++)
            for (uint32_t x = gr[i][0]; x <= gr[i][1]; x++)
                for (uint32_t y = gr[i][2]; y <= gr[i][3]; y++) {
                    if (!pass) cnt[(size_t)y * g + x + 1]++;
                    else seg[cnt[(size_t)y * g + x]++] = i;
                }
        if (!pass)
            for (size_t q = 0; q < (size_t)g * g; q++) cnt[q + 1] += cnt[q];
    }
    /* the fill moved each start to the next cell's: cell q is seg[(q ? cnt[q - 1] : 0) .. cnt[q]).
     * A pair whose float boxes are apart is apart in segs_may_meet's first test (the boxes
     * hold the double ones, the upper corners over el): only the others are tested. */
    for (size_t q = 0; q < (size_t)g * g; q++) {
        uint32_t b0 = q ? cnt[q - 1] : 0, b1 = cnt[q];
        for (uint32_t i = b0; i < b1; i++) {
            const float *bi = sb[seg[i]];
            for (uint32_t j = i + 1; j < b1; j++) {
                if (!boxes2_meet(bi, sb[seg[j]])) continue;
                uint32_t x = seg[i], y = seg[j];
                if (x > y) {
                    uint32_t z = x;
                    x = y;
                    y = z;
                }
                if (y == x + 1 || (x == 0 && y == len - 1)) continue; /* neighbours: above */
                const double *a = xy + 2 * (size_t)x, *b = xy + 2 * (size_t)(x + 1),
                             *c = xy + 2 * (size_t)y, *dd = xy + 2 * (size_t)(y + 1 < len ? y + 1 : 0);
                if (segs_may_meet(a, b, c, dd, e, el)) return 1;
            }
        }
    }
    return 0;
}

/* Node x's certificate axis ad (unit): the centre of its normals' box, when every unit
 * normal n in the box has n . ad at least the box's least corner value, clearing 1e-4 (over
 * the unit normals' float rounding, tri_normal_f's and normalising's); false: none (no
 * certificate) */
static bool cert_axis(const bnode *x, double ad[3])
{
    double l = 0, mn = 0;
    for (int j = 0; j < 3; j++) {
        ad[j] = 0.5 * ((double)x->nlo[j] + x->nhi[j]);
        l += ad[j] * ad[j];
    }
    l = sqrt(l);
    if (!(l > 1e-3)) return false;
    for (int j = 0; j < 3; j++) {
        ad[j] /= l;
        mn += ad[j] >= 0 ? ad[j] * x->nlo[j] : ad[j] * x->nhi[j];
    }
    return mn > 1e-4;
}

/* Node x's certificate in s: every triangle of it faces the axis a of cert_axis and its
 * boundary cycle, projected along a, is a simple polygon (contour_tangled). Then the
 * projection is one to one on the patch (contact.h, "(3)"), so no two of its triangles meet
 * but where they share a vertex. 1: certified, 0: not, -ENOMEM. */
static int certified(const struct track *k, lane *ln, const float *s, const bnode *x)
{
    double ad[3];
    if (!cert_axis(x, ad)) return 0;
    /* a basis (u, w) of the plane across the axis */
    double h[3] = {fabs(ad[0]) < 0.6 ? 1 : 0, fabs(ad[0]) < 0.6 ? 0 : 1, 0}, u[3], w[3];
    cross3(ad, h, u);
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int j = 0; j < 3; j++) u[j] /= lu;
    cross3(ad, u, w);
    const cert *ct = &k->cert[x->cert];
    int r = contour_tangled(ln, s, k->cyc + ct->start, ct->len, u, w);
    return r < 0 ? r : !r;
}

/* ---- the hierarchy: building ---- */

/* order[lo .. hi) partially sorted so that order[mid] has the mid-th key on axis a (keys
 * key[3 item + a], 3 per item: a cluster's mean centroid, a vertex's position; Hoare
 * partitions, median of three) */
static void select_mid(uint32_t *order, size_t lo, size_t hi, size_t mid, int a, const float *key)
{
#define KEY(i) key[3 * (size_t)order[i] + a]
    while (hi - lo > 1) {
        size_t m = lo + (hi - lo) / 2;
        float x = KEY(lo), y = KEY(m), z = KEY(hi - 1);
        float piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        size_t i = lo, j = hi - 1;
        for (;;) {
            while (KEY(i) < piv) i++;
            while (piv < KEY(j)) j--;
            if (i >= j) break;
            uint32_t tmp = order[i];
            order[i] = order[j];
            order[j] = tmp;
            i++;
            j--;
        }
        if (i == j) { /* [lo, j) <= piv == order[j] <= (j, hi): order[j] is in place */
            if (mid == j) return;
            if (mid < j) hi = j;
            else lo = j + 1;
            continue;
        }
        /* i > j: [lo, j] <= piv <= [j + 1, hi), both sides non-empty */
        if (mid <= j) hi = j + 1;
        else lo = j + 1;
    }
#undef KEY
}

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
    select_mid(items, 0, n, n / 2, a, b->cen);
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
    memcpy(b.list, k->order, m * sizeof *b.list);
    for (size_t i = 0; i < t; i++) b.idx[i] = FP_TRACK_NONE;
    for (size_t i = 0; i < m; i++) {
        uint32_t a = b.list[i];
        const uint32_t *v = c->tris + 3 * (size_t)a;
        b.idx[a] = (uint32_t)i;
        b.cnt[i] = 1;
        b.uf[i] = (uint32_t)i;
        for (int j = 0; j < 3; j++)
            b.cen[3 * i + j] = (k->p[3 * (size_t)v[0] + j] + k->p[3 * (size_t)v[1] + j] + k->p[3 * (size_t)v[2] + j]) / 3.f;
        double nd[3];
        float nf[3];
        tri_normal_f(k->p, v, nf, nd);
        bool deg = nf[0] == 0.f && nf[1] == 0.f && nf[2] == 0.f;
        for (int j = 0; j < 3; j++) {
            b.nb[6 * i + j] = deg ? -1.f : nf[j];
            b.nb[6 * i + 3 + j] = deg ? 1.f : nf[j];
        }
        act[i] = (uint32_t)i;
    }
    b.nc = m;
    /* twins: (u, v) of a, (v, u) of the one other triangle not own that has it */
    for (size_t i = 0; i < m; i++) {
        uint32_t a = b.list[i];
        const uint32_t *v = c->tris + 3 * (size_t)a;
        for (int j = 0; j < 3; j++) {
            uint32_t u = v[j], w = v[(j + 1) % 3], found = FP_TRACK_NONE, nf = 0;
            for (uint32_t q = k->vt_start[w]; q < k->vt_start[w + 1]; q++) {
                uint32_t o = k->vt[q];
                if (o == a || b.idx[o] == FP_TRACK_NONE) continue;
                const uint32_t *vo = c->tris + 3 * (size_t)o;
                for (int r = 0; r < 3; r++)
                    if (vo[r] == w && vo[(r + 1) % 3] == u) {
                        found = 3 * o + (uint32_t)r;
                        nf++;
                    }
            }
            b.tw[3 * (size_t)a + j] = nf == 1 ? found : FP_TRACK_NONE;
        }
    }
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

/* ---- the hierarchy: the check ---- */

static int add_off(fp_contact *c, const uint32_t *v);
static long own_flips(fp_contact *c, const float *s, const float *ref, bool record);

static int append_u32(uint32_t **p, size_t *len, size_t *cap, const uint32_t *src, size_t n);

/* the lanes' rec, their triangles' vertices, into off (add_off; the caller, after a job),
 * emptied. 0 or -ENOMEM */
static int rec_merge(fp_contact *c)
{
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        lane *ln = &c->tk->lane[i];
        for (size_t j = 0; j < ln->nrec; j++)
            if (add_off(c, c->tris + 3 * (size_t)ln->rec[j])) return -ENOMEM;
        ln->nrec = 0;
    }
    return 0;
}

#define FP_BLOCK_SHIFT 6  /* bstamp: blocks of 64 places */
#define FP_SUPER_SHIFT 12 /* sbstamp: blocks of 4096 places */

/* node b's places may hold a moved triangle (a block of the region meets them; a node the
 * size of a few super blocks or more reads those) */
static bool maybe_moved(const struct track *k, const bnode *b)
{
    if (!b->count) return false;
    uint32_t lo = b->first, hi = b->first + b->count - 1;
    const uint32_t *st = k->bstamp;
    int sh = FP_BLOCK_SHIFT;
    if (b->count >> FP_SUPER_SHIFT >= 4) {
        st = k->sbstamp;
        sh = FP_SUPER_SHIFT;
    }
    for (uint32_t i = lo >> sh; i <= hi >> sh; i++)
        if (st[i] == k->rclock) return true;
    return false;
}

/* Node x (one whose places may hold a moved triangle) and those below it that hold one:
 * stamped (nstamp), the moved triangles (a vertex stamped in vstamp) stamped (pstamp) and
 * their places into ln->mq in order (ln->moved counts them). cut > 0: not below nodes of
 * cut triangles or fewer (their tasks did those; their stamps say). Returns whether x
 * holds a moved triangle. Writes only x's subtree. */
static bool gather(struct track *k, lane *ln, uint32_t x, size_t cut)
{
    const uint32_t clk = k->tclock;
    const bnode *b = &k->node[x];
    bool any = false;
    if (!b->right) {
        const uint32_t *vs = k->vstamp;
        for (uint32_t i = b->first; i < b->first + b->count; i++)
            if (vs[k->ov[i][0]] == clk || vs[k->ov[i][1]] == clk || vs[k->ov[i][2]] == clk) {
                k->pstamp[i] = clk;
                any = true;
                if (push_u32(&ln->mq, &ln->nmq, &ln->cap_mq, i)) {
                    ln->flips = -ENOMEM;
                    return true;
                }
            }
    } else {
        uint32_t ch[2] = {x + 1, b->right};
        for (int h = 0; h < 2; h++) {
            const bnode *d = &k->node[ch[h]];
            if (cut && d->count <= cut) any |= k->nstamp[ch[h]] == clk;
            else if (maybe_moved(k, d)) any |= gather(k, ln, ch[h], cut);
        }
    }
    if (any) k->nstamp[x] = clk;
    return any;
}

/* The moved triangles at places mq[0 .. n): boxes and unit normals in s, their vertices
 * fetched ahead (place, vertices, positions: three dependent loads that would otherwise
 * miss the cache in turn); ref not NULL: the newly flipped ones counted, their vertices into
 * ln->rec. Returns the count or -ENOMEM. Writes only those places' tbox and tn, and ln. */
static long flat_pass(fp_contact *c, lane *ln, const float *s, const float *ref, const uint32_t *mq, size_t n)
{
    struct track *k = c->tk;
    long flips = 0;
    for (size_t i = 0; i < n; i++) {
        if (i + 16 < n) {
            __builtin_prefetch(k->ov[mq[i + 16]]);
            if (ref) __builtin_prefetch(k->order + mq[i + 16]);
        }
        if (i + 8 < n) {
            const uint32_t *w = k->ov[mq[i + 8]];
            __builtin_prefetch(s + 3 * (size_t)w[0]);
            __builtin_prefetch(s + 3 * (size_t)w[1]);
            __builtin_prefetch(s + 3 * (size_t)w[2]);
            if (ref) __builtin_prefetch(c->nrm[k->order[mq[i + 8]]]);
        }
        uint32_t q = mq[i];
        const uint32_t *va = k->ov[q];
        double nd[3];
        tri_box(s, va, k->tbox[q]);
        tri_normal_f(s, va, k->tn[q], nd);
        if (ref && flipped_n(c, nd, k->order[q]) && !flipped(c, ref, va, k->order[q])) {
            flips++;
            if (push_u32(&ln->rec, &ln->nrec, &ln->cap_rec, k->order[q])) return -ENOMEM;
        }
    }
    return flips;
}

/* Node x and those below it stamped (gather): their boxes and normal boxes from their
 * triangles'; cut > 0: not below nodes of cut triangles or fewer (done already, by the
 * refit job's tasks) */
static void refit(struct track *k, uint32_t x, size_t cut)
{
    bnode *b = &k->node[x];
    float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    float nlo[3] = {1.f, 1.f, 1.f}, nhi[3] = {-1.f, -1.f, -1.f};
    if (!b->right) {
        for (uint32_t i = b->first; i < b->first + b->count; i++) {
            const float *tb = k->tbox[i], *n = k->tn[i];
            for (int j = 0; j < 3; j++) {
                box[j] = min_f(box[j], tb[j]);
                box[3 + j] = max_f(box[3 + j], tb[3 + j]);
            }
            bool deg = n[0] == 0.f && n[1] == 0.f && n[2] == 0.f; /* its box spans all */
            for (int j = 0; j < 3; j++) {
                nlo[j] = min_f(nlo[j], deg ? -1.f : n[j]);
                nhi[j] = max_f(nhi[j], deg ? 1.f : n[j]);
            }
        }
    } else {
        uint32_t ch[2] = {x + 1, b->right};
        for (int h = 0; h < 2; h++) {
            bnode *d = &k->node[ch[h]];
            if (k->nstamp[ch[h]] == k->tclock && d->count > cut) refit(k, ch[h], cut);
            for (int j = 0; j < 3; j++) {
                box[j] = min_f(box[j], d->box[j]);
                box[3 + j] = max_f(box[3 + j], d->box[3 + j]);
                nlo[j] = min_f(nlo[j], d->nlo[j]);
                nhi[j] = max_f(nhi[j], d->nhi[j]);
            }
        }
    }
    memcpy(b->box, box, sizeof box);
    memcpy(b->nlo, nlo, sizeof nlo);
    memcpy(b->nhi, nhi, sizeof nhi);
}

/* Node x's subtree brought to shape s, where it may hold a moved triangle: gather, the flat
 * pass on what it found, refit; new flips into ln->flips (-ENOMEM sticks there), moved
 * triangles into ln->moved. cut as gather's. */
static void update_subtree(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, size_t cut)
{
    struct track *k = c->tk;
    ln->nmq = 0;
    if (!gather(k, ln, x, cut) || ln->flips < 0) return;
    ln->moved += ln->nmq;
    long f = flat_pass(c, ln, s, ref, ln->mq, ln->nmq);
    ln->flips = f < 0 ? f : ln->flips + f;
    refit(k, x, cut);
}

/* One task of the hierarchy's marking (collect_mark): of the vertices dp[x .. y) (z == 0)
 * or x .. y - 1 not in D_P (z == 1), those where a differs from P into ln->mv and stamped
 * (vstamp; the refit finds their triangles from it, gather). Those not in D_P join the
 * region: their triangles' blocks of places stamped (bstamp, sbstamp: stores only, the
 * same value from either thread; a vertex of D_P joined it so when it joined D_P, hence the
 * region holds every moved triangle). Own triangles claimed (tstamp, atomically) into
 * ln->mo. 0 or -ENOMEM. */
static int mark_range(fp_contact *c, lane *ln, const float *a, uint32_t x, uint32_t y, uint32_t z)
{
    struct track *k = c->tk;
    const uint32_t clk = k->tclock, rclk = k->rclock;
    for (uint32_t i = x; i < y; i++) {
        uint32_t v = z ? i : k->dp[i];
        if ((z && k->in_dp[v]) || !vert_differs(a, k->p, v)) continue;
        if (push_u32(&ln->mv, &ln->nmv, &ln->cap_mv, v)) return -ENOMEM;
        k->vstamp[v] = clk;
        if (!z && !k->has_own[v]) continue;
        for (uint32_t j = k->vt_start[v]; j < k->vt_start[v + 1]; j++) {
            uint32_t q = k->vtp[j];
            if (q == FP_TRACK_NONE) { /* an own triangle: flips only */
                uint32_t o = k->vt[j];
                if (__atomic_load_n(&k->tstamp[o], __ATOMIC_RELAXED) == clk ||
                    __atomic_exchange_n(&k->tstamp[o], clk, __ATOMIC_RELAXED) == clk)
                    continue;
                if (push_u32(&ln->mo, &ln->nmo, &ln->cap_mo, o)) return -ENOMEM;
                continue;
            }
            if (!z) continue;
            /* a store only where the stamp is not there yet: the blocks' lines, which both
             * threads read, then stay shared instead of passing between the cores */
            if (__atomic_load_n(&k->bstamp[q >> FP_BLOCK_SHIFT], __ATOMIC_RELAXED) != rclk)
                __atomic_store_n(&k->bstamp[q >> FP_BLOCK_SHIFT], rclk, __ATOMIC_RELAXED);
            if (__atomic_load_n(&k->sbstamp[q >> FP_SUPER_SHIFT], __ATOMIC_RELAXED) != rclk)
                __atomic_store_n(&k->sbstamp[q >> FP_SUPER_SHIFT], rclk, __ATOMIC_RELAXED);
        }
    }
    return 0;
}

/* the pair (a, b), not adjacent, not both unmoved: 1 when it is new in s (crosses in s, not in
 * ref; neither degenerate; their vertices into ln->rec when record), 0, -ENOMEM */
static int test_pair(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t a, uint32_t b, bool record)
{
    const uint32_t *va = c->tris + 3 * (size_t)a, *vb = c->tris + 3 * (size_t)b;
    double ta[3][3], tb[3][3];
    ln->tested++;
    tri_of(s, va, ta);
    tri_of(s, vb, tb);
    if (!tris_meet(ta, tb)) return 0;
    tri_of(ref, va, ta);
    tri_of(ref, vb, tb);
    if (tris_meet(ta, tb)) return 0;
    if (record &&
        (push_u32(&ln->rec, &ln->nrec, &ln->cap_rec, a) || push_u32(&ln->rec, &ln->nrec, &ln->cap_rec, b)))
        return -ENOMEM;
    return 1;
}

/* the pairs between leaves x and y (x == y: within x) with a moved triangle whose boxes meet
 * in s: new ones counted (test_pair). y's boxes are copied by axis first, so that each of
 * x's triangles meets them all in one loop the compiler vectorises; the pairs to test are
 * then the set bits of a mask (boxes meet, a moved triangle, within x each pair once), not a
 * branch for each of y's triangles. */
_Static_assert(FP_BVH_LEAF <= 32, "a leaf's triangles are the bits of a uint32_t");
static long leaf_pairs(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y,
                       bool record)
{
    struct track *k = c->tk;
    const uint32_t clk = k->tclock;
    const bnode *bx = &k->node[x], *by = &k->node[y];
    float lo[3][FP_BVH_LEAF], hi[3][FP_BVH_LEAF];
    uint32_t jy[FP_BVH_LEAF], ny = 0, jm = 0; /* jm: y's moved ones, by bit */
    for (uint32_t j = by->first; j < by->first + by->count; j++) {
        const float *b = k->tbox[j];
        if (x != y && !boxes_meet(b, bx->box)) continue;
        for (int a = 0; a < 3; a++) {
            lo[a][ny] = b[a];
            hi[a][ny] = b[3 + a];
        }
        jm |= (uint32_t)(k->pstamp[j] == clk) << ny;
        jy[ny++] = j;
    }
    long found = 0;
    for (uint32_t i = bx->first; ny && i < bx->first + bx->count; i++) {
        const float *ba = k->tbox[i];
        if (x != y && !boxes_meet(ba, by->box)) continue;
        /* within x: only y's triangles after i (y's are x's, in order) */
        uint32_t q0 = x == y ? i - bx->first + 1 : 0;
        unsigned char hit[FP_BVH_LEAF];
        for (uint32_t q = q0; q < ny; q++)
            hit[q] = (ba[0] <= hi[0][q]) & (lo[0][q] <= ba[3]) & (ba[1] <= hi[1][q]) & (lo[1][q] <= ba[4]) &
                     (ba[2] <= hi[2][q]) & (lo[2][q] <= ba[5]);
        uint32_t m = 0;
        for (uint32_t q = q0; q < ny; q++) m |= (uint32_t)hit[q] << q;
        if (k->pstamp[i] != clk) m &= jm; /* neither moved: nothing new */
        for (; m; m &= m - 1) {
            uint32_t j = jy[__builtin_ctz(m)];
            if (welded_adjacent(k->ow[i], k->ow[j])) continue;
            int r = test_pair(c, ln, s, ref, k->order[i], k->order[j], record);
            if (r < 0) return r;
            found += r;
        }
    }
    return found;
}

/* Of nodes *x and *y, not both leaves: the one to split (the larger internal one) into *x,
 * the other into *y; returns *x's node */
static const bnode *into_larger(const struct track *k, uint32_t *x, uint32_t *y)
{
    const bnode *bx = &k->node[*x], *by = &k->node[*y];
    if (!bx->right || (by->right && by->count > bx->count)) {
        uint32_t t = *x;
        *x = *y;
        *y = t;
        return by;
    }
    return bx;
}

/* the pairs between nodes x and y with a moved triangle: new ones counted */
static long node_pairs(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y,
                       bool record)
{
    struct track *k = c->tk;
    const bnode *bx = &k->node[x], *by = &k->node[y];
    if ((k->nstamp[x] != k->tclock && k->nstamp[y] != k->tclock) || !boxes_meet(bx->box, by->box)) return 0;
    if (!bx->right && !by->right) return leaf_pairs(c, ln, s, ref, x, y, record);
    bx = into_larger(k, &x, &y);
    long a = node_pairs(c, ln, s, ref, x + 1, y, record);
    if (a < 0) return a;
    long b = node_pairs(c, ln, s, ref, bx->right, y, record);
    return b < 0 ? b : a + b;
}

/* the pairs within node x with a moved triangle: new ones counted; a certified patch has none */
static long node_self(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, bool record)
{
    struct track *k = c->tk;
    const bnode *b = &k->node[x];
    if (k->nstamp[x] != k->tclock) return 0;
    if (c->certify && b->cert != FP_TRACK_NONE) {
        int r = certified(k, ln, s, b);
        if (r < 0) return r;
        if (r) {
            ln->certified++;
            return 0;
        }
    }
    if (!b->right) return leaf_pairs(c, ln, s, ref, x, x, record);
    long l = node_self(c, ln, s, ref, x + 1, record);
    if (l < 0) return l;
    long r = node_self(c, ln, s, ref, b->right, record);
    if (r < 0) return r;
    long p = node_pairs(c, ln, s, ref, x + 1, b->right, record);
    return p < 0 ? p : l + r + p;
}


/* ---- the worker: a step's marking, and a check's refit and walk, on two threads ---- */

/* A job is a list of tasks that both threads claim one at a time (a CAS on next, which
 * carries the job's number, so a late worker claims nothing of a newer job). The caller
 * opens the job and adds its tasks while the worker may already run them (each task is
 * written before the count that publishes it; the worker waits for more while the caller
 * is filling); then the caller works too and waits only for a task the worker holds
 * (busy), never for a worker that has not started: a worker kept off its core costs
 * nothing but its share. Tasks read the shapes and the hierarchy and write their own lane
 * and, in the marking, the stamps (the same value from either thread; own triangles are
 * claimed by an exchange), in the refit their own subtree's triangles and nodes; the
 * caller's writes before a job are published by the job's number (release), the worker's
 * by busy's clearing. */
#define FP_POOL_IDLE_NS 20000000  /* the worker polls (yielding) this long for the next job */
#define FP_WALK_GRAIN 16384       /* triangles of a node (pair) walked whole by one task, at most */
#define FP_ACCEPT_GRAIN 2048      /* moved vertices of one accept_range task */

typedef struct wtask {            /* a task: the marking's mark_range(x, y, z), the refit of
                                     node x (update_subtree), or the walk's node_self(x) (y ==
                                     FP_TRACK_NONE) or node_pairs(x, y) (z == 0) or its
                                     accept_range(x, y) (z == 1) */
    uint32_t x, y, z;
} wtask;

enum { FP_JOB_MARK, FP_JOB_REFIT, FP_JOB_WALK, FP_JOB_RECENTRE };

static int recentre(fp_contact *c);

typedef struct pool {
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool quit;                    /* under mu */
    uint32_t gen;                 /* under mu: the newest job's number */
    atomic_uint agen;             /* gen, for the worker's polling */
    _Atomic uint64_t next;        /* gen << 32 | the next task */
    atomic_uint ntask;            /* the job's tasks so far */
    atomic_bool filling;          /* the caller is still adding tasks to the job */
    atomic_int busy;              /* the worker may hold a task */
    atomic_bool stop;             /* quit, for the worker's polling */
    fp_contact *c;                /* the job (written before its number is published) */
    int kind;
    bool record;                  /* the walk's: new pairs' vertices into the lanes' rec */
    const float *s, *ref;
    wtask *task;
    size_t cap_task;
    size_t ntask_max;             /* the open job's list: tasks beyond it run on the caller */
} pool;

/* The acceptance of the step's candidate s, ahead of its check's verdict, on the moved
 * vertices mv[x .. y): P's old positions into pv, P := s there, and those that now differ
 * from ref and are not in D_P into ln->mv (they join it). The walk reads s and ref, never
 * P, so its tasks may run beside these; a candidate that fails gets P back from pv. 0 or
 * -ENOMEM. */
static int accept_range(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y)
{
    struct track *k = c->tk;
    for (uint32_t i = x; i < y; i++) {
        uint32_t v = k->mv[i];
        float *pp = k->p + 3 * (size_t)v;
        memcpy(k->pv + 3 * (size_t)i, pp, 3 * sizeof(float));
        memcpy(pp, s + 3 * (size_t)v, 3 * sizeof(float));
        if (!k->in_dp[v] && vert_differs(s, ref, v) && push_u32(&ln->mv, &ln->nmv, &ln->cap_mv, v))
            return -ENOMEM;
    }
    return 0;
}

static void run_task(pool *p, lane *ln, const wtask *t)
{
    long r;
    if (ln->found < 0 || ln->flips < 0) return; /* out of memory: the job fails anyway */
    if (p->kind == FP_JOB_MARK) {
        if (mark_range(p->c, ln, p->s, t->x, t->y, t->z)) ln->flips = -ENOMEM;
    } else if (p->kind == FP_JOB_RECENTRE) {
        if (recentre(p->c)) ln->flips = -ENOMEM;
    } else if (p->kind == FP_JOB_REFIT) {
        update_subtree(p->c, ln, p->s, p->ref, t->x, 0);
    } else if (t->z) {
        if (accept_range(p->c, ln, p->s, p->ref, t->x, t->y)) ln->found = -ENOMEM;
    } else {
        r = t->y == FP_TRACK_NONE ? node_self(p->c, ln, p->s, p->ref, t->x, p->record)
                                  : node_pairs(p->c, ln, p->s, p->ref, t->x, t->y, p->record);
        ln->found = r < 0 ? r : ln->found + r;
    }
}

static inline void cpu_pause(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

/* claim and run job gen's tasks until none is left and none is coming */
static void run_tasks(pool *p, lane *ln, uint32_t gen)
{
    for (unsigned spins = 0;;) {
        uint64_t cur = atomic_load(&p->next);
        if ((uint32_t)(cur >> 32) != gen) return;
        if ((uint32_t)cur >= atomic_load(&p->ntask)) {
            if (!atomic_load(&p->filling)) {
                if ((uint32_t)cur >= atomic_load(&p->ntask)) return; /* (one added before) */
                continue;
            }
            if (++spins > 1024) sched_yield(); /* the caller is making the next task */
            else cpu_pause();
            continue;
        }
        if (atomic_compare_exchange_weak(&p->next, &cur, cur + 1)) run_task(p, ln, &p->task[(uint32_t)cur]);
    }
}

/* The worker: asleep until a job comes (a step's first is its marking), then it polls for jobs,
 * yielding its core between polls, until none has come for FP_POOL_IDLE_NS: through a
 * deformation at 60 frames a second it does not sleep between frames. Waking it from a sleep
 * took over a millisecond on a 2-core virtual machine, and now and then a whole step: with a
 * 3 ms poll it took no task in about 7% of the 1.7M frames (contact p99 6.6 ms), with 20 ms
 * in none (p99 4.7 ms). */
static void *pool_main(void *arg)
{
    pool *p = arg;
    uint32_t seen = 0;
    for (;;) {
        pthread_mutex_lock(&p->mu);
        while (!p->quit && p->gen == seen) pthread_cond_wait(&p->cv, &p->mu);
        bool quit = p->quit;
        pthread_mutex_unlock(&p->mu);
        if (quit) return NULL;
        for (int64_t idle = fp_now_ns();;) {
            uint32_t g = atomic_load(&p->agen);
            if (g != seen) {
                seen = g;
                atomic_store(&p->busy, 1);
                run_tasks(p, &p->c->tk->lane[1], g);
                atomic_store(&p->busy, 0);
                idle = fp_now_ns();
                continue;
            }
            if (fp_now_ns() - idle > FP_POOL_IDLE_NS || atomic_load(&p->stop)) break;
            sched_yield();
        }
    }
}

static void pool_free(pool *p)
{
    if (!p) return;
    atomic_store(&p->stop, true);
    pthread_mutex_lock(&p->mu);
    p->quit = true;
    pthread_cond_signal(&p->cv);
    pthread_mutex_unlock(&p->mu);
    pthread_join(p->th, NULL);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->cv);
    free(p->task);
    free(p);
}

/* c's worker, started on first use; NULL: one thread (fp_contact_set_threads 1, or no
 * thread could be made: the check runs on the caller's alone) */
static pool *pool_get(fp_contact *c)
{
    struct track *k = c->tk;
    if (c->threads < 2) return NULL;
    if (k->pool) return k->pool;
    pool *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    atomic_init(&p->next, 0);
    atomic_init(&p->ntask, 0);
    atomic_init(&p->busy, 0);
    atomic_init(&p->agen, 0);
    atomic_init(&p->stop, false);
    p->c = c;
    if (pthread_mutex_init(&p->mu, NULL)) {
        free(p);
        return NULL;
    }
    if (pthread_cond_init(&p->cv, NULL)) {
        pthread_mutex_destroy(&p->mu);
        free(p);
        return NULL;
    }
    if (pthread_create(&p->th, NULL, pool_main, p)) {
        pthread_cond_destroy(&p->cv);
        pthread_mutex_destroy(&p->mu);
        free(p);
        c->threads = 1; /* not again every frame */
        return NULL;
    }
    k->pool = p;
    return p;
}

/* Open a job of this kind on shape s (and ref): the worker may start on its tasks as the
 * caller adds them (add_task), then job_finish. The list holds a quarter of c's share_min
 * tasks, 16 to 1,024 (1,024 by default; 16 for the tests, which share every check, so that
 * their jobs go beyond it): a task beyond it runs on the caller's thread at once. 0 or
 * -ENOMEM. */
static int job_open(fp_contact *c, pool *p, int kind, const float *s, const float *ref, bool record)
{
    size_t most = c->share_min / 4 < 16 ? 16 : c->share_min / 4 > 1024 ? 1024 : c->share_min / 4;
    if (reserve((void **)&p->task, &p->cap_task, most, sizeof *p->task)) return -ENOMEM;
    p->ntask_max = most;
    p->kind = kind;
    p->record = record;
    p->s = s;
    p->ref = ref;
    atomic_store(&p->ntask, 0);
    atomic_store(&p->filling, true);
    pthread_mutex_lock(&p->mu);
    uint32_t gen = ++p->gen;
    atomic_store(&p->next, (uint64_t)gen << 32);
    atomic_store(&p->agen, gen);
    pthread_cond_signal(&p->cv);
    pthread_mutex_unlock(&p->mu);
    return 0;
}

/* a task (x, y) into the open job (written, then counted: the count publishes it), or run
 * on the caller's lane now when the list is full */
static void add_task(fp_contact *c, pool *p, uint32_t x, uint32_t y, uint32_t z)
{
    wtask t = {x, y, z};
    uint32_t n = atomic_load_explicit(&p->ntask, memory_order_relaxed);
    if (n >= p->ntask_max) {
        run_task(p, &c->tk->lane[0], &t);
        return;
    }
    p->task[n] = t;
    atomic_store_explicit(&p->ntask, n + 1, memory_order_release);
}

/* the open job closed: a task not claimed yet is never run (a worker that wakes late claims
 * nothing while the next job's list is made); the caller waits for the one the worker
 * holds, if any */
static void job_close(fp_contact *c, pool *p)
{
    struct track *k = c->tk;
    atomic_store(&p->filling, false);
    atomic_store(&p->next, (uint64_t)p->gen << 32 | UINT32_MAX);
    if (!atomic_load(&p->busy)) return;
    int64_t w0 = fp_now_ns(); /* timed only when there is a wait */
    for (unsigned spins = 0; atomic_load(&p->busy); spins++)
        if (spins > 256) sched_yield(); /* the worker finishes its task */
    k->waited_ns += fp_now_ns() - w0;
}

/* the open job's tasks run on both threads to the last; the lanes' counts hold its results */
static void job_finish(fp_contact *c, pool *p)
{
    atomic_store(&p->filling, false);
    run_tasks(p, &c->tk->lane[0], p->gen);
    job_close(c, p);
}

/* the lanes' sum of a job's results (found or flips), or -ENOMEM */
static long lanes_sum(const struct track *k, bool flips)
{
    long sum = 0;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        long r = flips ? k->lane[i].flips : k->lane[i].found;
        if (r < 0) return r;
        sum += r;
    }
    return sum;
}

/* a check's task sizes: a quarter of its moved triangles, within the grains (a small check,
 * as in the tests, still splits). The walk's split also makes a task of each certifiable
 * patch and leaf pair on its way, so there are still many; a finer split cost the caller
 * more in making the tasks than it saved the walk. */
static size_t grain(const struct track *k, size_t most)
{
    size_t g = (k->nmq ? k->nmq : 2 * k->nmv) / 4; /* before the refit: about 2 a vertex */
    return g < 64 ? 64 : g > most ? most : g;
}

/* the walk's tasks from node x (y == FP_TRACK_NONE: node_self(x); else node_pairs(x, y)),
 * split as those functions recurse down to nodes of `grain` triangles or fewer, a
 * certifiable node whose normals face one way (its contour, then maybe its children, in the
 * task) or leaves, into the open job (the worker starts on them as they come) */
static void walk_tasks(fp_contact *c, pool *p, uint32_t x, uint32_t y, size_t g)
{
    struct track *k = c->tk;
    const bnode *bx = &k->node[x];
    if (y == FP_TRACK_NONE) {
        if (k->nstamp[x] != k->tclock) return;
        double ad[3]; /* a patch whose normals already fail its certificate: split further */
        if (!bx->right || bx->count <= g ||
            (c->certify && bx->cert != FP_TRACK_NONE && cert_axis(bx, ad))) {
            add_task(c, p, x, y, 0);
            return;
        }
        walk_tasks(c, p, x + 1, FP_TRACK_NONE, g);
        walk_tasks(c, p, bx->right, FP_TRACK_NONE, g);
        walk_tasks(c, p, x + 1, bx->right, g);
        return;
    }
    const bnode *by = &k->node[y];
    if ((k->nstamp[x] != k->tclock && k->nstamp[y] != k->tclock) || !boxes_meet(bx->box, by->box)) return;
    if ((!bx->right && !by->right) || (size_t)bx->count + by->count <= g) {
        add_task(c, p, x, y, 0);
        return;
    }
    bx = into_larger(k, &x, &y);
    walk_tasks(c, p, x + 1, y, g);
    walk_tasks(c, p, bx->right, y, g);
}

/* the refit's tasks: the nodes of g triangles or fewer right below larger ones, where a
 * moved triangle may be (the caller refits the nodes above them), into the open job */
static void refit_tasks(fp_contact *c, pool *p, uint32_t x, size_t g)
{
    const bnode *b = &c->tk->node[x];
    if (!maybe_moved(c->tk, b)) return;
    if (!b->right || b->count <= g) {
        add_task(c, p, x, 0, 0);
        return;
    }
    refit_tasks(c, p, x + 1, g);
    refit_tasks(c, p, b->right, g);
}

/* The moved triangles' boxes and directions in s, the nodes above them refit (refit; on
 * two threads for a large check); ref not NULL: the newly flipped moved triangles (own ones
 * too) counted, the moved ones into the lanes' rec (emptied first) and, without record,
 * into the probe; with record all their vertices into off. Returns the count, or -ENOMEM. */
static long tree_update(fp_contact *c, const float *s, const float *ref, bool record)
{
    struct track *k = c->tk;
    k->updates++;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        k->lane[i].flips = k->lane[i].found = 0;
        k->lane[i].moved = 0;
        k->lane[i].nrec = 0;
    }
    k->nmq = 0;
    pool *p = 2 * k->nmv < c->share_min ? NULL : pool_get(c);
    size_t cut = 0; /* on two threads: subtrees of cut triangles first, then the top */
    if (p && k->nnode) {
        cut = grain(k, FP_WALK_GRAIN);
        if (job_open(c, p, FP_JOB_REFIT, s, ref, false)) return -ENOMEM;
        refit_tasks(c, p, 0, cut);
        job_finish(c, p);
    }
    if (k->nnode && k->node[0].count > cut && maybe_moved(k, &k->node[0]))
        update_subtree(c, &k->lane[0], s, ref, 0, cut);
    long flips = lanes_sum(k, true);
    if (flips < 0) return flips;
    k->nmq = k->lane[0].moved + k->lane[1].moved;
    k->nmt = k->nmq;
    if (!ref) return flips;
    if (record && rec_merge(c)) return -ENOMEM;
    if (!record && flips) { /* the next bisection's checks try these first */
        k->nprobe = 0;
        for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++)
            if (append_u32(&k->probe, &k->nprobe, &k->cap_probe, k->lane[i].rec, k->lane[i].nrec))
                return -ENOMEM;
    }
    long g = own_flips(c, s, ref, record);
    return g < 0 ? g : flips + g;
}

/* New pairs and newly flipped triangles (*flips) of shape s (P but for the moved vertices)
 * against ref, among the pairs with a moved triangle: update, then the hierarchy from its
 * root. accepted not NULL (a step's first check, s its candidate): when the walk is shared,
 * its job also makes P := s at the moved vertices ahead of the verdict (accept_range: the
 * old P into pv, the vertices that join D_P into the lanes' mv), and *accepted = true.
 * Neither accepted nor record (a bisection's check): a flip decides, no walk (check).
 * Returns the new pairs or -ENOMEM. */
static long tree_check(fp_contact *c, const float *s, const float *ref, size_t *flips, bool record,
                       bool *accepted)
{
    struct track *k = c->tk;
    if (!record && !accepted) /* a bisection's: one of the last flips still there decides it */
        for (size_t i = 0; i < k->nprobe; i++) {
            const uint32_t *v = c->tris + 3 * (size_t)k->probe[i];
            if (flipped(c, s, v, k->probe[i]) && !flipped(c, ref, v, k->probe[i])) {
                *flips = 1;
                return 0;
            }
        }
    long f = tree_update(c, s, ref, record);
    if (f < 0) return f;
    *flips = (size_t)f;
    if (!k->nnode || (f && !record && !accepted)) return 0; /* a bisection's: a flip decides */
    pool *p = k->nmq < c->share_min ? NULL : pool_get(c);
    if (!p) {
        long r = node_self(c, &k->lane[0], s, ref, 0, record);
        return r >= 0 && record && rec_merge(c) ? -ENOMEM : r;
    }
    if (job_open(c, p, FP_JOB_WALK, s, ref, record)) return -ENOMEM;
    walk_tasks(c, p, 0, FP_TRACK_NONE, grain(k, FP_WALK_GRAIN));
    if (accepted) { /* last: they fill the threads' ends of the walk */
        for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) k->lane[i].nmv = 0;
        for (size_t i = 0; i < k->nmv; i += FP_ACCEPT_GRAIN)
            add_task(c, p, (uint32_t)i, (uint32_t)(i + FP_ACCEPT_GRAIN < k->nmv ? i + FP_ACCEPT_GRAIN : k->nmv), 1);
        *accepted = true;
    }
    job_finish(c, p);
    k->shared++;
    long r = lanes_sum(k, false);
    return r >= 0 && record && rec_merge(c) ? -ENOMEM : r;
}

/* ---- building ---- */

/* The hierarchy over the triangles not own (k: the parts common to both broad phases made);
 * c->tk = k. 0 or -ENOMEM (k freed). */
static int tree_build(fp_contact *c, struct track *k)
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
        track_free(k);
        return -ENOMEM;
    }
    /* the hierarchy over the triangles not own */
    size_t m = 0;
    for (size_t i = 0; i < t; i++) {
        k->tpos[i] = FP_TRACK_NONE;
        if (!c->own[i]) k->order[m++] = (uint32_t)i;
    }
    if (m && cluster_build(c, k, m)) {
        track_free(k);
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
        track_free(k);
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
            track_free(k);
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
    tree_update(c, k->p, NULL, false); /* no flips counted: no failure */
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
        track_free(k);
        return -ENOMEM;
    }
    return 0;
}

static int track_build(fp_contact *c)
{
    struct track *k = calloc(1, sizeof *k);
    if (!k) return -ENOMEM;
    size_t n = c->n, t = c->t;
    k->p = c->weld_copy; /* P starts as the weld shape: every triangle static */
    k->vt_start = calloc(n + 1, sizeof *k->vt_start);
    k->vt = malloc((t ? 3 * t : 1) * sizeof *k->vt);
    k->dp = zalloc(n ? n : 1, sizeof *k->dp);
    k->in_dp = zalloc(n ? n : 1, 1);
    k->off_mark = zalloc(n ? n : 1, 1);
    k->tstamp = zalloc(t ? t : 1, sizeof *k->tstamp);
    k->qstamp = zalloc(t ? t : 1, sizeof *k->qstamp);
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
    if (t > c->prewarm) return tree_build(c, k); /* a large mesh: the hierarchy */
    /* the cell: twice the mean extent of a triangle not own */
    double sum = 0;
    size_t cnt = 0;
    for (size_t i = 0; i < t; i++) {
        if (c->own[i]) continue;
        float b[6];
        tri_box(k->p, c->tris + 3 * i, b);
        sum += box_extent(b);
        cnt++;
    }
    k->ih = cnt && sum > 0 ? 1.0 / (2.0 * sum / (double)cnt) : 1.0;
    c->tk = k;
    /* the moved triangles' list has room for every triangle and one more (mark_tris
     * stores at nmt without a test, also a seen triangle, when nmt may be t) */
    if (reserve_written((void **)&k->mt, &k->cap_mt, t + 1, sizeof *k->mt)) goto fail;
    /* every triangle gets its envelope and list now, in one batch, so that a gesture's first
     * touch of a region costs its frame no more than the next (about 1 us a triangle) */
    for (size_t i = 0; i < t; i++) {
        if (c->own[i]) continue;
        float b[6];
        tri_box(k->p, c->tris + 3 * i, b);
        if (envelope(c, (uint32_t)i, b)) goto fail;
    }
    if (renew_lists(c)) goto fail;
    k->renewed = 0;
    /* the worker now, not in a frame (a thread's start took 0.5-0.8 ms on the 2-core VM) */
    if (c->threads >= 2) pool_get(c);
    return 0;
fail:
    track_free(k);
    c->tk = NULL;
    return -ENOMEM;
}

/* the next clock of the moved stamps */
static void tick(fp_contact *c)
{
    struct track *k = c->tk;
    size_t t = c->t;
    if (++k->tclock == 0) {
        memset(k->tstamp, 0, t * sizeof *k->tstamp);
        if (k->nstamp) memset(k->nstamp, 0, k->nnode * sizeof *k->nstamp);
        if (k->pstamp) memset(k->pstamp, 0, t * sizeof *k->pstamp);
        if (k->vstamp) memset(k->vstamp, 0, c->n * sizeof *k->vstamp);
        k->tclock = 1;
    }
}


/* the triangles of vertex v into mt (own ones into mo), once per clock. mt has room for
 * every triangle and one more (track_build), so the stamp's test is a store and an add, no
 * branch: each triangle is met from its three vertices, so "seen" is decided by the data */
static int mark_tris(fp_contact *c, uint32_t v)
{
    struct track *k = c->tk;
    uint32_t j0 = k->vt_start[v], j1 = k->vt_start[v + 1], clock = k->tclock;
    uint32_t *mt = k->mt;
    size_t nmt = k->nmt;
    for (uint32_t j = j0; j < j1; j++) {
        uint32_t a = k->vt[j];
        unsigned fresh = k->tstamp[a] != clock;
        k->tstamp[a] = clock;
        if (fresh & c->own[a]) { /* rare: a triangle of the input's own crossings */
            if (push_u32(&k->mo, &k->nmo, &k->cap_mo, a)) return -ENOMEM;
            continue;
        }
        mt[nmt] = a;
        nmt += fresh;
    }
    k->nmt = nmt;
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

/* the vertices looked at for moved ones: D_P and the ranges (all n for SIZE_MAX), clipped to n */
static size_t visits(const fp_contact *c, const uint32_t *ranges, size_t nranges)
{
    size_t m = c->tk->ndp;
    if (nranges == SIZE_MAX) return m + c->n;
    for (size_t r = 0; r < nranges; r++)
        if (ranges[2 * r] < c->n)
            m += ranges[2 * r + 1] < c->n - ranges[2 * r] ? ranges[2 * r + 1] : c->n - ranges[2 * r];
    return m;
}

/* the vertices v in [f, e) not in D_P where a differs from P, appended to mv at nmv, whose
 * room is made: a store and an add, no branch (where a motion's support ends, "differs"
 * turns with the data); returns the new count */
static size_t moved_in(const struct track *k, const float *a, size_t f, size_t e, uint32_t *mv, size_t nmv)
{
    for (size_t v = f; v < e; v++) {
        mv[nmv] = (uint32_t)v;
        nmv += !k->in_dp[v] & vert_differs(a, k->p, v);
    }
    return nmv;
}

/* k->mv := the vertices where a differs (bitwise) from P, looked for where either may differ
 * from the reference: D_P, then the ranges (every vertex for nranges == SIZE_MAX), with room
 * for every vertex looked at made first. Returns 0 or -ENOMEM. */
static int collect_moved(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    size_t most = visits(c, ranges, nranges), cap0 = k->cap_mv;
    if (reserve((void **)&k->mv, &k->cap_mv, most ? most : 1, sizeof *k->mv)) return -ENOMEM;
    if (k->cap_mv != cap0) write_pages(k->mv, k->cap_mv * sizeof *k->mv); /* grown: no fault later */
    uint32_t *mv = k->mv;
    size_t nmv = 0;
    for (size_t i = 0; i < k->ndp; i++) {
        mv[nmv] = k->dp[i];
        nmv += vert_differs(a, k->p, k->dp[i]);
    }
    if (nranges == SIZE_MAX) nmv = moved_in(k, a, 0, c->n, mv, nmv);
    else
        for (size_t r = 0; r < nranges; r++) {
            size_t f = ranges[2 * r], e = f + ranges[2 * r + 1];
            nmv = moved_in(k, a, f, e < c->n ? e : c->n, mv, nmv);
        }
    k->nmv = nmv;
    return 0;
}

#define FP_MARK_GRAIN 8192 /* vertices looked at by one task of the marking, at most */

/* n values appended to the list (*p, *len, *cap); 0 or -ENOMEM */
static int append_u32(uint32_t **p, size_t *len, size_t *cap, const uint32_t *src, size_t n)
{
    if (reserve((void **)p, cap, *len + n, sizeof **p)) return -ENOMEM;
    if (n) memcpy(*p + *len, src, n * sizeof *src);
    *len += n;
    return 0;
}

/* The hierarchy's collect_moved and marking at once (mark_range): the vertices where a
 * differs from P, looked for in D_P and the ranges, into k->mv, their own triangles into
 * k->mo, the others stamped; on two threads when there are many to look at (each thread's
 * lists in its lane, then joined). Returns 0 or -ENOMEM. */
static int collect_mark(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    size_t nvisit = visits(c, ranges, nranges);
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        lane *ln = &k->lane[i];
        ln->nmv = ln->nmo = 0;
        ln->flips = ln->found = 0;
    }
    pool *p = 2 * nvisit >= c->share_min ? pool_get(c) : NULL;
    size_t g = nvisit / 16 < 256 ? 256 : nvisit / 16 > FP_MARK_GRAIN ? FP_MARK_GRAIN : nvisit / 16;
    if (p && job_open(c, p, FP_JOB_MARK, a, NULL, false)) return -ENOMEM;
#define FP_SPAN(x0, x1, z)                                                                      \
    for (size_t i_ = (x0); i_ < (x1); i_ += g) {                                                \
        uint32_t e_ = (uint32_t)(i_ + g < (x1) ? i_ + g : (x1));                                \
        if (p) add_task(c, p, (uint32_t)i_, e_, (z));                                           \
        else if (mark_range(c, &k->lane[0], a, (uint32_t)i_, e_, (z))) return -ENOMEM;          \
    }
    FP_SPAN(0, k->ndp, 0)
    if (nranges == SIZE_MAX) {
        FP_SPAN(0, c->n, 1)
    } else {
        for (size_t r = 0; r < nranges; r++) {
            size_t f = ranges[2 * r], e = f + ranges[2 * r + 1];
            FP_SPAN(f, e < c->n ? e : c->n, 1)
        }
    }
#undef FP_SPAN
    if (p) job_finish(c, p);
    if (lanes_sum(k, true) < 0) return -ENOMEM;
    lane *l0 = &k->lane[0], *l1 = &k->lane[1];
    k->nmv = k->nmo = 0;
    if (append_u32(&k->mv, &k->nmv, &k->cap_mv, l0->mv, l0->nmv) ||
        append_u32(&k->mv, &k->nmv, &k->cap_mv, l1->mv, l1->nmv) ||
        append_u32(&k->mo, &k->nmo, &k->cap_mo, l0->mo, l0->nmo) ||
        append_u32(&k->mo, &k->nmo, &k->cap_mo, l1->mo, l1->nmo))
        return -ENOMEM;
    return 0;
}

static int reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges);

int fp_contact_reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges)
{
    if (!c || !ref || (nranges != SIZE_MAX && nranges && !ranges)) return -EINVAL;
    if (!c->tk && track_build(c)) return -ENOMEM;
    bg_join(c);
    if (c->tk->broken) return -ENOMEM;
    int rc = reference(c, ref, ranges, nranges);
    if (rc) c->tk->broken = true;
    return rc;
}

static int reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    tick(c);
    k->nmt = k->nmo = k->nmq = 0;
    /* P := ref where they differ: D_P, then the ranges (or everything); the hierarchy's
     * triangles there marked */
    if (k->tree ? collect_mark(c, ref, ranges, nranges) : collect_moved(c, ref, ranges, nranges))
        return -ENOMEM;
    for (size_t i = 0; i < k->ndp; i++) k->in_dp[k->dp[i]] = 0;
    k->ndp = 0;
    if (k->tree) { /* the triangles that changed: their normals and the boxes above them */
        for (size_t i = 0; i < k->nmv; i++)
            memcpy(k->p + 3 * (size_t)k->mv[i], ref + 3 * (size_t)k->mv[i], 3 * sizeof(float));
        if (tree_update(c, k->p, NULL, false) < 0) return -ENOMEM;
        if (++k->rclock == 0) { /* the region empty, as D_P */
            size_t t = c->t ? c->t : 1;
            memset(k->bstamp, 0, ((t >> FP_BLOCK_SHIFT) + 1) * sizeof *k->bstamp);
            memset(k->sbstamp, 0, ((t >> FP_SUPER_SHIFT) + 1) * sizeof *k->sbstamp);
            k->rclock = 1;
        }
        return 0;
    }
    for (size_t i = 0; i < k->nmv; i++)
        if (mark_tris(c, k->mv[i])) return -ENOMEM;
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

#define FP_CHECK_CHUNK 64 /* list entries filtered at once (track_check) */

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
            if (!record) return 0; /* a bisection's check: a flip decides (check) */
            if (add_off(c, va)) return -ENOMEM;
        }
        dyn *d = &k->dyn[k->slot[a]];
        if (!d->len) continue;
        float ba[6];
        if (cand_boxes) memcpy(ba, k->mbox[i], sizeof ba);
        else tri_box(s, va, ba);
        const uint32_t *list = dyn_list(d);
        double ta[3][3], ra[3][3];
        tplane pa, pra;
        int deg_a = -1, rdeg_a = -1; /* not yet known */
        /* The list in chunks: first a filter without a branch, keeping the entries that
         * need the exact test (the two tests below were each decided about half the time
         * by the data, a misprediction an entry: 63 against 44 us a frame on the ICT
         * replay); then those. A pair of two moved triangles is the lower one's. b's box
         * in s straight away: its triangle and vertices lie near a's in memory on a mesh
         * numbered by region (the envelope, k->dyn[k->slot[b]], would be a filter that
         * reads no vertex, but a cache miss per entry on a large mesh). */
        for (uint32_t j0 = 0; j0 < d->len && deg_a <= 0; j0 += FP_CHECK_CHUNK) {
            uint32_t near[FP_CHECK_CHUNK], nn = 0;
            uint32_t j1 = d->len - j0 < FP_CHECK_CHUNK ? d->len : j0 + FP_CHECK_CHUNK;
            for (uint32_t j = j0; j < j1; j++) {
                uint32_t b = list[j];
                float bb[6];
                tri_box(s, c->tris + 3 * (size_t)b, bb);
                unsigned keep = !((b < a) & (k->tstamp[b] == k->tclock)) & boxes_meet(ba, bb);
                near[nn] = b;
                nn += keep;
            }
            for (uint32_t j = 0; j < nn; j++) {
                uint32_t b = near[j];
                const uint32_t *vb = c->tris + 3 * (size_t)b;
                if (deg_a < 0) { /* a's plane, once for its list */
                    tri_of(s, va, ta);
                    plane_of(ta, &pa);
                    deg_a = pa.deg;
                }
                if (deg_a) break;
                double tb[3][3], rb[3][3];
                tri_of(s, vb, tb);
                if (!meets_pl(ta, &pa, tb)) continue;
                if (rdeg_a < 0) {
                    tri_of(ref, va, ra);
                    plane_of(ra, &pra);
                    rdeg_a = pra.deg;
                }
                tri_of(ref, vb, rb);
                if (!rdeg_a && meets_pl(ra, &pra, rb)) continue;
                if (record && (add_off(c, va) || add_off(c, vb))) return -ENOMEM;
                found++;
            }
        }
    }
    if (!cand_boxes) {
        long f = own_flips(c, s, ref, record);
        if (f < 0) return -ENOMEM;
        *flips += (size_t)f;
    }
    return found;
}

/* ---- envelopes re-centred after a step (contact.h, fp_contact_set_threads) ---- */

/* The moved triangles of the last step (mt) whose box in P comes within FP_TRACK_RECENTRE of
 * the skin of their envelope's side: a new envelope around that box (envelope: it holds P's
 * box, as every envelope must), their lists made (renew_lists). A step's renewals are the
 * boxes that left their envelopes; a motion that goes on leaves them frame after frame (the
 * ICT three-claps replay: about 1,860 renewals in 75-78 of its frames, about 3.7 us each
 * with the caches cold, up to 125 in a frame), and re-centred on P after each step fewer
 * leave (about 700, in 16-17 frames; the job re-centres about 7 a frame, 0.12 ms median of
 * the worker's time). Runs as the worker's job between steps (bg_post); writes the grid,
 * the envelopes and lists, and the query scratch, never P or D_P. 0 or -ENOMEM. */
static int recentre(fp_contact *c)
{
    struct track *k = c->tk;
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        float b[6];
        tri_box(k->p, c->tris + 3 * (size_t)a, b);
        if (k->slot[a] != FP_TRACK_NONE) {
            float in[6];
            box_grown(b, (float)(FP_TRACK_RECENTRE * FP_TRACK_SKIN * box_extent(b)), in);
            if (box_holds(k->dyn[k->slot[a]].env, in)) continue; /* (it holds b too) */
        }
        if (envelope(c, a, b)) return -ENOMEM;
    }
    return renew_lists(c);
}

/* After an envelope step with moved triangles, with a worker (fp_contact_set_threads 2):
 * recentre posted as its job, not waited for; every later call on c that reads or writes
 * the track joins it first (bg_join). No worker (one thread, or none could be made): no
 * re-centring, the step's renewals as before. */
static void bg_post(fp_contact *c)
{
    struct track *k = c->tk;
    if (k->tree || !k->nmt || c->threads < 2) return;
    pool *p = pool_get(c);
    if (!p) return;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) k->lane[i].flips = k->lane[i].found = 0;
    if (job_open(c, p, FP_JOB_RECENTRE, k->p, NULL, false)) return;
    add_task(c, p, 0, 0, 0);
    atomic_store(&p->filling, false); /* the one task: the worker need not wait for more */
    k->bg = true;
}

/* The posted recentre finished, or dropped when the worker has not started it (a worker
 * woken from its sleep may take over a millisecond: the step then renews what its motion
 * needs, as without a worker, instead of waiting or re-centring here); out of memory in it:
 * the track is broken (the next call returns -ENOMEM) */
static void bg_join(fp_contact *c)
{
    struct track *k = c ? c->tk : NULL;
    if (!k || !k->bg) return;
    k->bg = false;
    job_close(c, k->pool); /* not started: dropped; started: waited for */
    if (lanes_sum(k, true) < 0) k->broken = true;
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

/* local_ramp's k-d tree over the blocking vertices: a node's points' box, and its points
 * (leaf: at most FP_KD_LEAF) or its children */
#define FP_KD_LEAF 8
typedef struct kdnode {
    double lo[3], hi[3];
    uint32_t first, count, left, right; /* left == 0: a leaf (node 0 is the root) */
} kdnode;

/* the node over the vertices ix[first .. first + n) (positions in pos) and those below it
 * into kd[*len ..); its index */
static uint32_t kd_build(kdnode *kd, size_t *len, uint32_t *ix, const float *pos, uint32_t first,
                         uint32_t n)
{
    uint32_t x = (uint32_t)(*len)++;
    kdnode *d = &kd[x];
    for (int a = 0; a < 3; a++) d->lo[a] = INFINITY, d->hi[a] = -INFINITY;
    for (uint32_t i = first; i < first + n; i++)
        for (int a = 0; a < 3; a++) {
            d->lo[a] = dmin(d->lo[a], pos[3 * (size_t)ix[i] + a]);
            d->hi[a] = dmax(d->hi[a], pos[3 * (size_t)ix[i] + a]);
        }
    d->first = first;
    d->count = n;
    d->left = d->right = 0;
    if (n <= FP_KD_LEAF) return x;
    int ax = 0; /* split at the median of the longest side */
    for (int a = 1; a < 3; a++)
        if (d->hi[a] - d->lo[a] > d->hi[ax] - d->lo[ax]) ax = a;
    select_mid(ix, first, first + n, first + n / 2, ax, pos);
    uint32_t l = kd_build(kd, len, ix, pos, first, n / 2);
    uint32_t r = kd_build(kd, len, ix, pos, first + n / 2, n - n / 2);
    kd[x].left = l;
    kd[x].right = r;
    return x;
}

static inline double kd_lb2(const kdnode *d, const double *p)
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        double e = dmax(dmax(d->lo[a] - p[a], p[a] - d->hi[a]), 0.0);
        s += e * e;
    }
    return s;
}

/* a new clock (tick), and the moved vertices whose share of the motion is below 1 (ramp
 * NULL: all) stamped with it: the hierarchy's next checks look at their triangles only */
static void stamp_scaled(fp_contact *c, const double *ramp)
{
    struct track *k = c->tk;
    tick(c);
    for (size_t i = 0; i < k->nmv; i++)
        if (!ramp || ramp[i] < 1) k->vstamp[k->mv[i]] = k->tclock;
}

/* ramp[i] for the moved vertices: 0 within local_r of a vertex in off (positions in P, as
 * pv holds them), 1 beyond 2 local_r, smooth between. The nearest off vertex within 2r comes
 * from a k-d tree over them, the search bounded first by the previous moved vertex's nearest
 * (its neighbour in memory, mostly on the surface): the brute force's distance where it
 * matters. A blocked frame on the 1.7M face (114,000 moved vertices, 866 triangles turned
 * over) took 74 ms in the brute force; a grid of 2r cells helped nothing (every moved vertex
 * lay within 2r: 50 ms for 93,000 against 493 blocking vertices); the tree, 1-9 ms. 0 or
 * -ENOMEM. */
static int local_ramp(fp_contact *c)
{
    struct track *k = c->tk;
    double r = c->local_r, r2 = r * r, r4 = 4 * r2;
    if (!k->noff) {
        for (size_t i = 0; i < k->nmv; i++) k->ramp[i] = 1;
        return 0;
    }
    if (reserve((void **)&k->kd_ix, &k->cap_kd_ix, k->noff, sizeof *k->kd_ix) ||
        reserve((void **)&k->kd, &k->cap_kd, 2 * k->noff, sizeof *k->kd))
        return -ENOMEM;
    uint32_t *ix = k->kd_ix;
    memcpy(ix, k->off, k->noff * sizeof *ix);
    size_t len = 0;
    kd_build(k->kd, &len, ix, k->p, 0, (uint32_t)k->noff);
    const kdnode *kd = k->kd;
    const float *q = k->p;
    uint32_t stack[64], w = 0; /* w: the last nearest point (a bound for the next search) */
    for (size_t i = 0; i < k->nmv; i++) {
        const float *pf = k->pv + 3 * i;
        double p[3] = {pf[0], pf[1], pf[2]};
        const float *qw = q + 3 * (size_t)ix[w];
        double best = r4, dx = p[0] - qw[0], dy = p[1] - qw[1], dz = p[2] - qw[2];
        double dw = dx * dx + dy * dy + dz * dz;
        if (dw < best) best = dw;
        uint32_t top = 0;
        stack[top++] = 0;
        while (top && best > r2) {
            const kdnode *d = &kd[stack[--top]];
            if (kd_lb2(d, p) >= best) continue;
            if (!d->left) {
                for (uint32_t j = d->first; j < d->first + d->count; j++) {
                    const float *qj = q + 3 * (size_t)ix[j];
                    dx = p[0] - qj[0], dy = p[1] - qj[1], dz = p[2] - qj[2];
                    double d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 < best) best = d2, w = j;
                }
                continue;
            }
            double ll = kd_lb2(&kd[d->left], p), lr = kd_lb2(&kd[d->right], p);
            uint32_t nearer = ll <= lr ? d->left : d->right, farther = ll <= lr ? d->right : d->left;
            if ((ll <= lr ? lr : ll) < best) stack[top++] = farther; /* (one a level: < 64) */
            if ((ll <= lr ? ll : lr) < best) stack[top++] = nearer;
        }
        double u = best <= r2 ? 0 : best >= r4 ? 1 : (sqrt(best) - r) / r;
        k->ramp[i] = u * u * (3 - 2 * u);
    }
    return 0;
}

/* A shape's check inside a step (s: P at the moved vertices), by the mesh's broad phase: the
 * new pairs and (*flips) the newly flipped triangles; record: their vertices into off (a local scale-back's blocking
 * set), every one counted. Without record (the bisection, which asks only whether the shape
 * adds any) a flip decides it: the pairs are not looked for (0, *flips >= 1). */
static long check(fp_contact *c, const float *s, const float *ref, size_t *flips, bool record)
{
    return c->tk->tree ? tree_check(c, s, ref, flips, record, NULL) : track_check(c, s, ref, false, flips, record);
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
    int64_t w0 = c->tk->waited_ns;
    bg_join(c); /* (a wait for it is the step's) */
    if (c->tk->broken) return -ENOMEM;
    int rc = step(c, ref, cand, ranges, nranges, iters, res);
    res->worker_wait_ms = (double)(c->tk->waited_ns - w0) / 1e6;
    if (rc) c->tk->broken = true;
    else bg_post(c);
    return rc;
}

static int step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                size_t nranges, int iters, fp_contact_result *res)
{
    struct track *k = c->tk;
    tick(c);
    k->nmv = k->nmt = k->nmo = k->nmq = k->nprobe = 0;
    size_t renewed0 = k->renewed;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) k->lane[i].certified = k->lane[i].tested = 0;
    k->shared = 0;

    /* the moved vertices: where cand differs from P */
    if (k->tree ? collect_mark(c, cand, ranges, nranges) : collect_moved(c, cand, ranges, nranges))
        return -ENOMEM;
    res->moved_verts = k->nmv;
    if (!k->nmv) return 0; /* nothing moved: P is the candidate */
    for (size_t i = 0; !k->tree && i < k->nmv; i++) {
        /* the vertex's triangle range, its triangles and their stamps fetched ahead: three
         * dependent loads that would otherwise miss the cache in turn (the marking of the
         * ICT replay's 480 moved vertices: 15-21 us against 19-28) */
        if (i + 16 < k->nmv) __builtin_prefetch(k->vt_start + k->mv[i + 16]);
        if (i + 8 < k->nmv) __builtin_prefetch(k->vt + k->vt_start[k->mv[i + 8]]);
        if (i + 4 < k->nmv)
            for (uint32_t j = k->vt_start[k->mv[i + 4]]; j < k->vt_start[k->mv[i + 4] + 1]; j++)
                __builtin_prefetch(k->tstamp + k->vt[j], 1);
        if (mark_tris(c, k->mv[i])) return -ENOMEM;
    }
    res->moved_tris = k->nmt; /* (the hierarchy counts them in its check's refit) */

    size_t fl = 0; /* newly flipped triangles of the candidate */
    long found;
    bool accepted = false; /* the walk job made P the candidate ahead (tree_check) */
    if (k->tree) {
        /* the walk job accepts the candidate ahead (accept_range), so that P's copy costs
         * the threads' idle ends, not a serial tail; pv holds the old P */
        size_t cap = k->cap_pv;
        if (reserve((void **)&k->pv, &cap, 3 * k->nmv, sizeof *k->pv) ||
            reserve((void **)&k->cv, &k->cap_pv, 3 * k->nmv, sizeof *k->cv))
            return -ENOMEM;
        found = tree_check(c, cand, ref, &fl, false, &accepted);
        if (found < 0) return -ENOMEM;
        res->moved_tris = k->nmt;
        if (accepted && (found || fl)) /* it fails: P back */
            for (size_t i = 0; i < k->nmv; i++)
                memcpy(k->p + 3 * (size_t)k->mv[i], k->pv + 3 * i, 3 * sizeof(float));
    } else {
    /* envelopes that hold each moved triangle in the candidate (and, before a bisection,
     * in P too, so in every shape between them) */
    if (reserve((void **)&k->mbox, &k->cap_mbox, k->nmt, sizeof *k->mbox)) return -ENOMEM;
    for (size_t i = 0; i < k->nmt; i++) {
        /* the triangle's vertices, slot and envelope fetched ahead: dependent loads that
         * would otherwise miss the cache in turn */
        if (i + 16 < k->nmt) {
            __builtin_prefetch(c->tris + 3 * (size_t)k->mt[i + 16]);
            __builtin_prefetch(k->slot + k->mt[i + 16]);
        }
        if (i + 8 < k->nmt) {
            const uint32_t *w = c->tris + 3 * (size_t)k->mt[i + 8];
            __builtin_prefetch(cand + 3 * (size_t)w[0]);
            __builtin_prefetch(cand + 3 * (size_t)w[1]);
            __builtin_prefetch(cand + 3 * (size_t)w[2]);
            __builtin_prefetch(c->nrm[k->mt[i + 8]]);
            const uint32_t sl = k->slot[k->mt[i + 8]];
            if (sl != FP_TRACK_NONE) __builtin_prefetch(k->dyn[sl].env);
        }
        uint32_t a = k->mt[i];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        tri_box(cand, va, k->mbox[i]);
        if ((k->slot[a] == FP_TRACK_NONE || !box_holds(k->dyn[k->slot[a]].env, k->mbox[i])) &&
            envelope(c, a, k->mbox[i]))
            return -ENOMEM;
        if (flipped(c, cand, va, a) && !flipped(c, ref, va, a)) fl++;
    }
    fl += (size_t)own_flips(c, cand, ref, false);
    if (renew_lists(c)) return -ENOMEM;
    found = track_check(c, cand, ref, true, &fl, false);
    }
    res->checks = 1;
    res->pairs = found;
    res->flipped = fl;
    if (found || fl) {
        /* the bisection over P -> candidate: envelopes that hold P's boxes too */
        for (size_t i = 0; !k->tree && i < k->nmt; i++) {
            uint32_t a = k->mt[i];
            float hull[6];
            tri_box(k->p, c->tris + 3 * (size_t)a, hull);
            for (int j = 0; j < 3; j++) {
                hull[j] = min_f(hull[j], k->mbox[i][j]);
                hull[3 + j] = max_f(hull[3 + j], k->mbox[i][3 + j]);
            }
            if (!box_holds(k->dyn[k->slot[a]].env, hull) && envelope(c, a, hull)) return -ENOMEM;
        }
        if (!k->tree && renew_lists(c)) return -ENOMEM;
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
            /* the blocking triangles: on the hierarchy, when the first check's walk found
             * no pair, its update's flips (the lanes' rec) and the own ones; else a check
             * that records them */
            long m = k->tree && !found ? (rec_merge(c) || own_flips(c, cand, ref, true) < 0 ? -ENOMEM : 0)
                                       : check(c, cand, ref, &fl, true);
            if (m < 0) return -ENOMEM;
            for (int round = 0; m > 0 || fl; round++) {
                if (m < 0) return -ENOMEM;
                if (round == FP_CONTACT_LOCAL_ROUNDS) break;
                track_lerp(k, 0, NULL); /* P, where the distances are taken */
                if (local_ramp(c)) return -ENOMEM;
                track_lerp(k, 0, k->ramp);
                if (k->tree) {
                    /* a vertex kept whole (share 1) is where the candidate has it, and a
                     * triangle of such vertices is not a blocking one, so a pair of them, or
                     * with unmoved ones, added nothing in the candidate: the check looks only
                     * at the triangles of the others (a new stamp; the rest hold the
                     * candidate's boxes and normals from its check) */
                    stamp_scaled(c, k->ramp);
                }
                m = check(c, k->p, ref, &fl, true);
                res->checks++;
                if (!m && !fl) ramp = k->ramp;
            }
            track_lerp(k, 0, NULL);
        }
        /* with a ramp the stamps stay the last round's: a vertex kept whole (share 1) is in
         * place for every t, and its triangles as in the candidate; without one (the rounds
         * failed) every moved vertex depends on t */
        if (!ramp && k->tree && c->local_r > 0) stamp_scaled(c, NULL);
        double lo = 0, hi = 1, held = ramp ? 0 : NAN; /* the t whose shape the hierarchy holds
                                                           (the passed ramp's: 0) */
        for (int i = 0; i < iters; i++) {
            double mid = 0.5 * (lo + hi);
            track_lerp(k, mid, ramp);
            size_t u0 = k->updates;
            long m = check(c, k->p, ref, &fl, false);
            res->checks++;
            if (m < 0) return -ENOMEM;
            if (k->updates != u0) held = mid; /* (not a probe's) */
            if (m || fl) hi = mid;
            else lo = mid;
        }
        track_lerp(k, lo, ramp);
        res->t = lo;
        res->local = ramp != NULL;
        /* the hierarchy: the normals and boxes of the shape kept, unless the last check that
         * updated them had it */
        if (k->tree && !(held == lo) && tree_update(c, k->p, NULL, false) < 0) return -ENOMEM;
    } else if (!accepted) {
        for (size_t i = 0; i < k->nmv; i++)
            memcpy(k->p + 3 * (size_t)k->mv[i], cand + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    }
    res->renewed = k->renewed - renewed0;
    res->shared = k->shared;
    res->certified = 0;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) res->certified += k->lane[i].certified;
    /* D_P: where P may differ from the reference. P changed only at the moved vertices, so
     * only they may join it; one that went back to the reference stays in it (a superset is
     * enough for (2); fp_contact_reference empties it), so the step costs its motion, not
     * the whole gesture's */
    if (accepted && !found && !fl) { /* accept_range found them */
        for (int j = 0; j < FP_CONTACT_MAX_THREADS; j++)
            for (size_t i = 0; i < k->lane[j].nmv; i++) {
                k->in_dp[k->lane[j].mv[i]] = 1;
                k->dp[k->ndp++] = k->lane[j].mv[i];
            }
        return 0;
    }
    for (size_t i = 0; i < k->nmv; i++) {
        uint32_t v = k->mv[i];
        if (!k->in_dp[v] && vert_differs(k->p, ref, v)) {
            k->in_dp[v] = 1;
            k->dp[k->ndp++] = v;
        }
    }
    return 0;
}

/* the vertices v in [f, e) where cand moved from P by less than eps in every coordinate,
 * and differs from ref: P's vertex back into cand (fp_contact_hold); returns their number */
static size_t hold_in(const float *p, const float *ref, float *cand, size_t f, size_t e, float eps)
{
    size_t held = 0;
    for (size_t v = f; v < e; v++) {
        float *q = cand + 3 * v;
        const float *a = p + 3 * v, *r = ref + 3 * v;
        bool near = fabsf(q[0] - a[0]) < eps && fabsf(q[1] - a[1]) < eps &&
                    fabsf(q[2] - a[2]) < eps; /* (false with a NaN) */
        if (!near || !memcmp(q, a, 3 * sizeof(float)) || !memcmp(q, r, 3 * sizeof(float))) continue;
        memcpy(q, a, 3 * sizeof(float));
        held++;
    }
    return held;
}

size_t fp_contact_hold(fp_contact *c, const float *ref, float *cand, const uint32_t *ranges,
                       size_t nranges, float eps)
{
    if (!c || !c->tk || !ref || !cand || !(eps > 0) || (!ranges && nranges != SIZE_MAX)) return 0;
    const float *p = c->tk->p;
    if (nranges == SIZE_MAX) return hold_in(p, ref, cand, 0, c->n, eps);
    size_t held = 0;
    for (size_t r = 0; r < nranges; r++) {
        size_t f = ranges[2 * r], e = f + ranges[2 * r + 1];
        if (f < c->n) held += hold_in(p, ref, cand, f, e < c->n ? e : c->n, eps);
    }
    return held;
}

const float *fp_contact_shape(const fp_contact *c) { return c && c->tk ? c->tk->p : NULL; }

size_t fp_contact_differs(const fp_contact *c, const uint32_t **verts)
{
    *verts = c && c->tk ? c->tk->dp : NULL;
    return c && c->tk ? c->tk->ndp : 0;
}

void fp_contact_set_prewarm(fp_contact *c, size_t max_tris)
{
    if (c) c->prewarm = max_tris;
}

void fp_contact_set_certify(fp_contact *c, bool on)
{
    if (c) c->certify = on;
}

void fp_contact_set_threads(fp_contact *c, int threads, size_t min_moved)
{
    if (!c) return;
    bg_join(c);
    c->threads = threads >= 2 ? 2 : 1;
    c->share_min = min_moved ? min_moved : FP_CONTACT_SHARE_MIN;
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
    bg_join(c);
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
