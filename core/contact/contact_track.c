/* The contact guard's incremental state (fp_contact.h, "The incremental guard"): its
 * making and freeing, the moved vertices and triangles, the reference (fp_contact_reference),
 * the blocking set, the accessors and settings, the rest normals under a pose. */
#include "contact_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void fpc_track_free(struct track *k)
{
    if (!k) return;
    fpc_pool_free(k->pool);
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
    free(k->carry);
    free(k->probe);
    fpc_kd_free(&k->kd);
    free(k);
}

/* n zeroed elements of size el, every page written now (write_pages), or NULL */
static void *zalloc(size_t n, size_t el)
{
    void *p = calloc(n, el);
    write_pages(p, n * el);
    return p;
}

int fpc_track_build(fp_contact *c)
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
        fpc_track_free(k);
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
    if (t > c->prewarm) return fpc_tree_build(c, k); /* a large mesh: the hierarchy */
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
        if (fpc_envelope(c, (uint32_t)i, b)) goto fail;
    }
    if (fpc_renew_lists(c)) goto fail;
    k->renewed = 0;
    /* the worker now, not in a frame (a thread's start took 0.5-0.8 ms on the 2-core VM) */
    if (c->threads >= 2) fpc_pool_get(c);
    return 0;
fail:
    fpc_track_free(k);
    c->tk = NULL;
    return -ENOMEM;
}

/* the next clock of the moved stamps */
void fpc_tick(fp_contact *c)
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
int fpc_mark_tris(fp_contact *c, uint32_t v)
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
long fpc_own_flips(fp_contact *c, const float *s, const float *ref, bool record)
{
    struct track *k = c->tk;
    long f = 0;
    for (size_t i = 0; i < k->nmo; i++) {
        const uint32_t *v = c->tris + 3 * (size_t)k->mo[i];
        if (fpc_new_flip(c, fpc_flips(c, s, v, k->mo[i]), ref, v, k->mo[i])) {
            f++;
            if (record && fpc_add_off(c, v)) return -ENOMEM;
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
int fpc_collect_moved(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges)
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

/* The hierarchy's collect_moved and marking at once (mark_range): the vertices where a
 * differs from P, looked for in D_P and the ranges, into k->mv, their own triangles into
 * k->mo, the others stamped; on two threads when there are many to look at (each thread's
 * lists in its lane, then joined). Returns 0 or -ENOMEM. */
int fpc_collect_mark(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    size_t nvisit = visits(c, ranges, nranges);
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        lane *ln = &k->lane[i];
        ln->nmv = ln->nmo = 0;
        ln->flips = ln->found = 0;
    }
    pool *p = 2 * nvisit >= c->share_min ? fpc_pool_get(c) : NULL;
    size_t g = nvisit / 16 < 256 ? 256 : nvisit / 16 > FP_MARK_GRAIN ? FP_MARK_GRAIN : nvisit / 16;
    if (p && fpc_job_open(c, p, FP_JOB_MARK, a, NULL, false)) return -ENOMEM;
#define FP_SPAN(x0, x1, z)                                                                      \
    for (size_t i_ = (x0); i_ < (x1); i_ += g) {                                                \
        uint32_t e_ = (uint32_t)(i_ + g < (x1) ? i_ + g : (x1));                                \
        if (p) fpc_add_task(c, p, (uint32_t)i_, e_, (z));                                           \
        else if (fpc_mark_range(c, &k->lane[0], a, (uint32_t)i_, e_, (z))) return -ENOMEM;          \
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
    if (p) fpc_job_finish(c, p);
    if (fpc_lanes_sum(k, true) < 0) return -ENOMEM;
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
    if (!c->tk && fpc_track_build(c)) return -ENOMEM;
    fpc_bg_join(c);
    if (c->tk->broken) return -ENOMEM;
    int rc = reference(c, ref, ranges, nranges);
    if (rc) c->tk->broken = true;
    return rc;
}

static int reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges)
{
    struct track *k = c->tk;
    fpc_tick(c);
    k->nmt = k->nmo = k->nmq = 0;
    /* P := ref where they differ: D_P, then the ranges (or everything); the hierarchy's
     * triangles there marked */
    if (k->tree ? fpc_collect_mark(c, ref, ranges, nranges) : fpc_collect_moved(c, ref, ranges, nranges))
        return -ENOMEM;
    for (size_t i = 0; i < k->ndp; i++) k->in_dp[k->dp[i]] = 0;
    k->ndp = 0;
    if (k->tree) { /* the triangles that changed: their normals and the boxes above them */
        for (size_t i = 0; i < k->nmv; i++)
            memcpy(k->p + 3 * (size_t)k->mv[i], ref + 3 * (size_t)k->mv[i], 3 * sizeof(float));
        if (fpc_tree_update(c, k->p, NULL, false) < 0) return -ENOMEM;
        if (++k->rclock == 0) { /* the region empty, as D_P */
            size_t t = c->t ? c->t : 1;
            memset(k->bstamp, 0, ((t >> FP_BLOCK_SHIFT) + 1) * sizeof *k->bstamp);
            memset(k->sbstamp, 0, ((t >> FP_SUPER_SHIFT) + 1) * sizeof *k->sbstamp);
            k->rclock = 1;
        }
        return 0;
    }
    for (size_t i = 0; i < k->nmv; i++)
        if (fpc_mark_tris(c, k->mv[i])) return -ENOMEM;
    for (size_t i = 0; i < k->nmv; i++)
        memcpy(k->p + 3 * (size_t)k->mv[i], ref + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    /* the triangles that changed: an envelope that holds them */
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        float b[6];
        tri_box(k->p, c->tris + 3 * (size_t)a, b);
        if ((k->slot[a] == FP_TRACK_NONE || !box_holds(k->dyn[k->slot[a]].env, b)) && fpc_envelope(c, a, b))
            return -ENOMEM;
    }
    return fpc_renew_lists(c);
}

/* the vertices of triangle v into off, once each */
int fpc_add_off(fp_contact *c, const uint32_t *v)
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

const float *fp_contact_shape(const fp_contact *c) { return c && c->tk ? c->tk->p : NULL; }

size_t fp_contact_differs(const fp_contact *c, const uint32_t **verts)
{
    *verts = c && c->tk ? c->tk->dp : NULL;
    return c && c->tk ? c->tk->ndp : 0;
}

size_t fp_contact_moved(const fp_contact *c, const uint32_t **verts)
{
    *verts = c && c->tk ? c->tk->mv : NULL;
    return c && c->tk ? c->tk->nmv : 0;
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
    fpc_bg_join(c);
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

int fp_contact_set_pose(fp_contact *c, const float *base, const float *posed)
{
    if (!c || (!base) != (!posed)) return -EINVAL;
    fpc_bg_join(c);
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
                    fp_cross3(a, b, ax);
                    fp_cross3(ax, w, t1);
                    fp_cross3(ax, t1, t2);
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

void fp_contact_set_carry(fp_contact *c, bool on)
{
    if (c) c->carry = on;
}

void fp_contact_set_gallop(fp_contact *c, size_t min_tris)
{
    if (c) c->gallop_min = min_tris;
}

void fp_contact_set_local(fp_contact *c, double radius)
{
    if (c) c->local_r = radius > 0 && isfinite(radius) ? radius : 0;
}
