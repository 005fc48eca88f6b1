/* The contact guard's envelopes ("(3a)" in fp_contact.h): the dynamic grid, the envelopes
 * and their lists, the batched renewals, the incremental check over the lists, and the
 * re-centring after a step. */
#include "contact_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

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
int fpc_envelope(fp_contact *c, uint32_t x, const float box[6])
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
int fpc_renew_lists(fp_contact *c)
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

/* New pairs and newly flipped triangles of shape s (P but for the moved vertices) against
 * ref, among the pairs with a moved triangle (mt); cand_boxes: s is the candidate (mbox). */

#define FP_CHECK_CHUNK 64 /* list entries filtered at once (track_check) */

long fpc_track_check(fp_contact *c, const float *s, const float *ref, bool cand_boxes,
                        size_t *flips, bool record)
{
    struct track *k = c->tk;
    long found = 0;
    if (!cand_boxes) *flips = 0; /* else counted with the candidate's boxes (fp_contact_step) */
    for (size_t i = 0; i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        if (!cand_boxes && fpc_new_flip(c, fpc_flips(c, s, va, a), ref, va, a)) {
            (*flips)++;
            if (!record) return 0; /* a bisection's check: a flip decides (check) */
            if (fpc_add_off(c, va)) return -ENOMEM;
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
                if (record && (fpc_add_off(c, va) || fpc_add_off(c, vb))) return -ENOMEM;
                found++;
            }
        }
    }
    if (!cand_boxes) {
        long f = fpc_own_flips(c, s, ref, record);
        if (f < 0) return -ENOMEM;
        *flips += (size_t)f;
    }
    return found;
}

/* ---- envelopes re-centred after a step (fp_contact.h, fp_contact_set_threads) ---- */

/* The moved triangles of the last step (mt) whose box in P comes within FP_TRACK_RECENTRE of
 * the skin of their envelope's side: a new envelope around that box (envelope: it holds P's
 * box, as every envelope must), their lists made (renew_lists). A step's renewals are the
 * boxes that left their envelopes; a motion that goes on leaves them frame after frame (the
 * ICT three-claps replay: about 1,860 renewals in 75-78 of its frames, about 3.7 us each
 * with the caches cold, up to 125 in a frame), and re-centred on P after each step fewer
 * leave (about 700, in 16-17 frames; the job re-centres about 7 a frame, 0.12 ms median of
 * the worker's time). Runs as the worker's job between steps (bg_post); writes the grid,
 * the envelopes and lists, and the query scratch, never P or D_P. 0 or -ENOMEM. */
int fpc_recentre(fp_contact *c)
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
        if (fpc_envelope(c, a, b)) return -ENOMEM;
    }
    return fpc_renew_lists(c);
}
