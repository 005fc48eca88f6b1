/* The contact guard's hierarchy ("(3b)" in fp_contact.h), the check: the patches'
 * certificates, the marking's tasks, the refit, the walk over node pairs, and their split
 * into the worker's tasks (contact_worker.c). Building it: contact_cluster.c. */
#include "contact_internal.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* ==== the hierarchy (fp_contact.h, "The hierarchy"): a large mesh's broad phase ==== */

/* ---- a patch's certificate (fp_contact.h, "(3)") ---- */

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
 * projection is one to one on the patch (fp_contact.h, "(3)"), so no two of its triangles meet
 * but where they share a vertex. 1: certified, 0: not, -ENOMEM. */
static int certified(const struct track *k, lane *ln, const float *s, const bnode *x)
{
    double ad[3];
    if (!cert_axis(x, ad)) return 0;
    /* a basis (u, w) of the plane across the axis */
    double h[3] = {fabs(ad[0]) < 0.6 ? 1 : 0, fabs(ad[0]) < 0.6 ? 0 : 1, 0}, u[3], w[3];
    fp_cross3(ad, h, u);
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int j = 0; j < 3; j++) u[j] /= lu;
    fp_cross3(ad, u, w);
    const cert *ct = &k->cert[x->cert];
    int r = contour_tangled(ln, s, k->cyc + ct->start, ct->len, u, w);
    return r < 0 ? r : !r;
}

/* ---- the hierarchy: the check ---- */

/* the lanes' rec, their triangles' vertices, into off (add_off; the caller, after a job),
 * emptied. 0 or -ENOMEM */
int fpc_rec_merge(fp_contact *c)
{
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        lane *ln = &c->tk->lane[i];
        for (size_t j = 0; j < ln->nrec; j++)
            if (fpc_add_off(c, c->tris + 3 * (size_t)ln->rec[j])) return -ENOMEM;
        ln->nrec = 0;
    }
    return 0;
}

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
        if (ref && fpc_new_flip(c, flips_n(c, nd, k->order[q]), ref, va, k->order[q])) {
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
void fpc_update_subtree(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, size_t cut)
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
int fpc_mark_range(fp_contact *c, lane *ln, const float *a, uint32_t x, uint32_t y, uint32_t z)
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
 * ref; neither degenerate; a and b into ln->rec when record or the track's rec_pairs), 0,
 * -ENOMEM */
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
    if ((record || c->tk->rec_pairs) &&
        (push_u32(&ln->rec, &ln->nrec, &ln->cap_rec, a) || push_u32(&ln->rec, &ln->nrec, &ln->cap_rec, b)))
        return -ENOMEM;
    return 1;
}

/* the pairs between leaves x and y (x == y: within x) with a moved triangle whose boxes meet
 * in s: new ones counted (test_pair). y's boxes are copied by axis first, so that each of
 * x's triangles meets them four at a time (boxes_hit: SSE2, which GCC's -O3 did not make of
 * the scalar loop); the pairs to test are then the set bits of a mask (boxes meet, a moved
 * triangle, within x each pair once), not a branch for each of y's triangles. */
_Static_assert(FP_BVH_LEAF <= 32, "a leaf's triangles are the bits of a uint32_t");
#define LEAF_PAD ((FP_BVH_LEAF + 3) & ~3) /* y's boxes in groups of four */

/* the bits q < ny of y's boxes (by axis: lo, hi) that box ba meets */
static inline uint32_t boxes_hit(const float *ba, const float (*lo)[LEAF_PAD], const float (*hi)[LEAF_PAD],
                                 uint32_t ny)
{
    uint32_t m = 0;
#if defined(__SSE2__)
    /* four of y's boxes a compare (x86-64's baseline): the scalar loop's tests, lane by lane */
    const __m128 a0 = _mm_set1_ps(ba[0]), a1 = _mm_set1_ps(ba[1]), a2 = _mm_set1_ps(ba[2]),
                 a3 = _mm_set1_ps(ba[3]), a4 = _mm_set1_ps(ba[4]), a5 = _mm_set1_ps(ba[5]);
    for (uint32_t q = 0; q < ny; q += 4) {
        __m128 h = _mm_and_ps(_mm_cmple_ps(a0, _mm_loadu_ps(hi[0] + q)), _mm_cmple_ps(_mm_loadu_ps(lo[0] + q), a3));
        h = _mm_and_ps(h, _mm_and_ps(_mm_cmple_ps(a1, _mm_loadu_ps(hi[1] + q)), _mm_cmple_ps(_mm_loadu_ps(lo[1] + q), a4)));
        h = _mm_and_ps(h, _mm_and_ps(_mm_cmple_ps(a2, _mm_loadu_ps(hi[2] + q)), _mm_cmple_ps(_mm_loadu_ps(lo[2] + q), a5)));
        m |= (uint32_t)_mm_movemask_ps(h) << q;
    }
    return ny < 32 ? m & ((1u << ny) - 1) : m;
#else
    for (uint32_t q = 0; q < ny; q++)
        m |= (uint32_t)((ba[0] <= hi[0][q]) & (lo[0][q] <= ba[3]) & (ba[1] <= hi[1][q]) & (lo[1][q] <= ba[4]) &
                        (ba[2] <= hi[2][q]) & (lo[2][q] <= ba[5])) << q;
    return m;
#endif
}

static long leaf_pairs(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y,
                       bool record)
{
    struct track *k = c->tk;
    const uint32_t clk = k->tclock;
    const bnode *bx = &k->node[x], *by = &k->node[y];
    ln->leaf_pairs++;
    float lo[3][LEAF_PAD], hi[3][LEAF_PAD];
    uint32_t jy[FP_BVH_LEAF], ny = 0, jm = 0; /* jm: y's moved ones, by bit */
    /* y's boxes that meet x's box, compacted without a branch (each written at ny, which
     * moves on only when it meets: that branch was the loop's most mispredicted) */
    for (uint32_t j = by->first; j < by->first + by->count; j++) {
        const float *b = k->tbox[j];
        const uint32_t in = (x == y) | boxes_meet(b, bx->box);
        for (int a = 0; a < 3; a++) {
            lo[a][ny] = b[a];
            hi[a][ny] = b[3 + a];
        }
        jm |= (in & (uint32_t)(k->pstamp[j] == clk)) << ny;
        jy[ny] = j;
        ny += in;
    }
    for (uint32_t q = ny; q < ((ny + 3) & ~3u); q++) /* the last group's unused lanes: meet nothing */
        for (int a = 0; a < 3; a++) lo[a][q] = INFINITY, hi[a][q] = -INFINITY;
    long found = 0;
    for (uint32_t i = bx->first; ny && i < bx->first + bx->count; i++) {
        const float *ba = k->tbox[i];
        if (x != y && !boxes_meet(ba, by->box)) continue;
        /* within x: only y's triangles after i (y's are x's, in order) */
        uint32_t q0 = x == y ? i - bx->first + 1 : 0;
        uint32_t m = boxes_hit(ba, (const float(*)[LEAF_PAD])lo, (const float(*)[LEAF_PAD])hi, ny);
        m &= q0 < 32 ? ~((1u << q0) - 1) : 0u;
        if (k->pstamp[i] != clk) m &= jm; /* neither moved: nothing new */
        for (; m; m &= m - 1) {
            uint32_t j = jy[__builtin_ctz(m)];
            if (welded_adjacent(k->ow[i], k->ow[j])) continue;
            int r = test_pair(c, ln, s, ref, k->order[i], k->order[j], record);
            if (r < 0) return r;
            if (r && ln->npairs < FP_PAIR_PROBE) { /* (for the bisection's probe) */
                ln->pairs[2 * ln->npairs] = k->order[i];
                ln->pairs[2 * ln->npairs++ + 1] = k->order[j];
            }
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
long fpc_node_pairs(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y,
                       bool record)
{
    struct track *k = c->tk;
    const bnode *bx = &k->node[x], *by = &k->node[y];
    ln->node_pairs++;
    if ((k->nstamp[x] != k->tclock && k->nstamp[y] != k->tclock) || !boxes_meet(bx->box, by->box)) return 0;
    if (!bx->right && !by->right) return leaf_pairs(c, ln, s, ref, x, y, record);
    bx = into_larger(k, &x, &y);
    long a = fpc_node_pairs(c, ln, s, ref, x + 1, y, record);
    if (a < 0) return a;
    long b = fpc_node_pairs(c, ln, s, ref, bx->right, y, record);
    return b < 0 ? b : a + b;
}

/* the pairs within node x with a moved triangle: new ones counted; a certified patch has none */
long fpc_node_self(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, bool record)
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
    long l = fpc_node_self(c, ln, s, ref, x + 1, record);
    if (l < 0) return l;
    long r = fpc_node_self(c, ln, s, ref, b->right, record);
    if (r < 0) return r;
    long p = fpc_node_pairs(c, ln, s, ref, x + 1, b->right, record);
    return p < 0 ? p : l + r + p;
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
            fpc_add_task(c, p, x, y, 0);
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
        fpc_add_task(c, p, x, y, 0);
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
        fpc_add_task(c, p, x, 0, 0);
        return;
    }
    refit_tasks(c, p, x + 1, g);
    refit_tasks(c, p, b->right, g);
}

/* The moved triangles' boxes and directions in s, the nodes above them refit (refit; on
 * two threads for a large check); ref not NULL: the newly flipped moved triangles (own ones
 * too) counted, the moved ones into the lanes' rec (emptied first) and, without record,
 * into the probe; with record all their vertices into off. Returns the count, or -ENOMEM. */
long fpc_tree_update(fp_contact *c, const float *s, const float *ref, bool record)
{
    struct track *k = c->tk;
    k->updates++;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        k->lane[i].flips = k->lane[i].found = 0;
        k->lane[i].moved = 0;
        k->lane[i].nrec = 0;
        k->lane[i].npairs = 0;
    }
    k->nmq = 0;
    pool *p = 2 * k->nmv < c->share_min ? NULL : fpc_pool_get(c);
    size_t cut = 0; /* on two threads: subtrees of cut triangles first, then the top */
    if (p && k->nnode) {
        cut = grain(k, FP_WALK_GRAIN);
        if (fpc_job_open(c, p, FP_JOB_REFIT, s, ref, false)) return -ENOMEM;
        refit_tasks(c, p, 0, cut);
        fpc_job_finish(c, p);
    }
    if (k->nnode && k->node[0].count > cut && maybe_moved(k, &k->node[0]))
        fpc_update_subtree(c, &k->lane[0], s, ref, 0, cut);
    long flips = fpc_lanes_sum(k, true);
    if (flips < 0) return flips;
    k->nmq = k->lane[0].moved + k->lane[1].moved;
    k->nmt = k->nmq;
    if (!ref) return flips;
    if (record && fpc_rec_merge(c)) return -ENOMEM;
    if (!record && flips) { /* the next bisection's checks try these first */
        k->nprobe = 0;
        for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++)
            if (append_u32(&k->probe, &k->nprobe, &k->cap_probe, k->lane[i].rec, k->lane[i].nrec))
                return -ENOMEM;
    }
    long g = fpc_own_flips(c, s, ref, record);
    return g < 0 ? g : flips + g;
}

/* A walk that found new pairs (found > 0): the lanes' first ones become the probe */
static void keep_pairs(struct track *k, long found)
{
    if (found <= 0) return;
    k->npair_probe = 0;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++)
        for (size_t j = 0; j < k->lane[i].npairs; j++, k->npair_probe++) {
            k->pair_probe[2 * k->npair_probe] = k->lane[i].pairs[2 * j];
            k->pair_probe[2 * k->npair_probe + 1] = k->lane[i].pairs[2 * j + 1];
        }
    assert(k->npair_probe > 0 && k->npair_probe <= FP_PAIR_PROBE * FP_CONTACT_MAX_THREADS);
}

/* New pairs and newly flipped triangles (*flips) of shape s (P but for the moved vertices)
 * against ref, among the pairs with a moved triangle: update, then the hierarchy from its
 * root. accepted not NULL (a step's first check, s its candidate): when the walk is shared,
 * its job also makes P := s at the moved vertices ahead of the verdict (accept_range: the
 * old P into pv, the vertices that join D_P into the lanes' mv), and *accepted = true.
 * Neither accepted nor record (a bisection's check): a flip decides, no walk (check). With
 * accepted the walk also keeps its new pairs' triangles in the lanes' rec (rec_pairs), the
 * blocking set of a local scale-back.
 * Returns the new pairs or -ENOMEM. */
long fpc_tree_check(fp_contact *c, const float *s, const float *ref, size_t *flips, bool record,
                       bool *accepted)
{
    struct track *k = c->tk;
    k->rec_pairs = accepted != NULL; /* a step's first check: its blocking set kept */
    if (!record && !accepted) { /* a bisection's: one of the last flips or new pairs still
                                   there decides it, before the refit and the walk */
        for (size_t i = 0; i < k->nprobe; i++) {
            const uint32_t *v = c->tris + 3 * (size_t)k->probe[i];
            if (fpc_new_flip(c, fpc_flips(c, s, v, k->probe[i]), ref, v, k->probe[i])) {
                *flips = 1;
                return 0;
            }
        }
        /* a pair the walk found new (neither own nor adjacent) that crosses in s and not in
         * ref is one of the full check's new pairs of s, whatever moved: s fails */
        for (size_t i = 0; i < k->npair_probe; i++) {
            int r = test_pair(c, &k->lane[0], s, ref, k->pair_probe[2 * i], k->pair_probe[2 * i + 1], false);
            if (r) {
                *flips = 0;
                return r;
            }
        }
    }
    long f = fpc_tree_update(c, s, ref, record);
    if (f < 0) return f;
    *flips = (size_t)f;
    if (!k->nnode || (f && !record && !accepted)) return 0; /* a bisection's: a flip decides */
    pool *p = k->nmq < c->share_min ? NULL : fpc_pool_get(c);
    if (!p) {
        long r = fpc_node_self(c, &k->lane[0], s, ref, 0, record);
        keep_pairs(k, r);
        return r >= 0 && record && fpc_rec_merge(c) ? -ENOMEM : r;
    }
    if (fpc_job_open(c, p, FP_JOB_WALK, s, ref, record)) return -ENOMEM;
    walk_tasks(c, p, 0, FP_TRACK_NONE, grain(k, FP_WALK_GRAIN));
    if (accepted) { /* last: they fill the threads' ends of the walk */
        for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) k->lane[i].nmv = 0;
        for (size_t i = 0; i < k->nmv; i += FP_ACCEPT_GRAIN)
            fpc_add_task(c, p, (uint32_t)i, (uint32_t)(i + FP_ACCEPT_GRAIN < k->nmv ? i + FP_ACCEPT_GRAIN : k->nmv), 1);
        *accepted = true;
    }
    fpc_job_finish(c, p);
    k->shared++;
    long r = fpc_lanes_sum(k, false);
    keep_pairs(k, r);
    return r >= 0 && record && fpc_rec_merge(c) ? -ENOMEM : r;
}

