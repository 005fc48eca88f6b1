/* csrbf_evaluate's scheduling: a fast-path work list split over the threads (one contiguous
 * part of equal cost per thread, cut into chunks that a thread done with its own part steals
 * from the far end of the others'), or kept on the calling thread when it is small; and the
 * kept selection's weight cache (each pair's 16 kernel weights and support mask, for anchored
 * frames small enough to stay in the cores' caches). */
#include "eval_internal.h"

#include <omp.h>
#include <stdlib.h>

/* The next chunk of part *sp: its first (the part's own thread takes them in order, or any
 * thread a part no thread owns) or, with back, its last (a thread done with its own part
 * steals from the other end, and leaves the owner its next chunk: where the threads are even,
 * no chunk changes core, so none runs from another core's cache); SIZE_MAX when none is left
 * to take. One compare-and-swap a chunk, on the owner's cache line: no transfer between cores
 * until a thread steals. Relaxed: the chunks' bounds are written before the parallel region,
 * its outputs are disjoint, and its end is a barrier. */
static size_t steal_take(steal_part *sp, int back)
{
    uint64_t v = atomic_load_explicit(&sp->span, memory_order_relaxed);
    for (;;) {
        const uint64_t lo = (uint32_t)v, hi = v >> 32;
        if (lo + (back ? 1 : 0) >= hi) return SIZE_MAX;
        const uint64_t nv = back ? lo | (hi - 1) << 32 : (lo + 1) | hi << 32;
        if (atomic_compare_exchange_weak_explicit(&sp->span, &v, nv, memory_order_relaxed,
                                                  memory_order_relaxed))
            return (size_t)(back ? hi - 1 : lo);
    }
}

/* The first item i in [lo, hi] whose prefix cost cum[i] reaches target (hi if none before). */
static size_t cost_reach(const size_t *cum, size_t lo, size_t hi, size_t target)
{
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (cum[mid] < target) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Split the work into parts of equal cost: part t is items isplit[t] .. isplit[t+1]-1 and,
 * with gaps (a full write), blocks bsplit[t] .. bsplit[t+1]-1 (a copied gap block costs 1,
 * so the split may fall inside a gap). ib NULL: ni blocks of equal cost. cum: prefix costs
 * of the items (ni + 1); total: the whole cost. */
static void split_work(const uint32_t *ib, const size_t *cum, size_t ni, int gaps, size_t nb,
                       size_t parts, size_t total, size_t *isplit, size_t *bsplit)
{
    isplit[0] = bsplit[0] = 0;
    for (size_t t = 1; t < parts; t++) {
        size_t target = total / parts * t + total % parts * t / parts;
        if (!ib) {
            isplit[t] = bsplit[t] = ni * t / parts;
        } else if (!gaps) {
            isplit[t] = cost_reach(cum, 0, ni, target);
        } else {
            /* cost of blocks 0..b-1: items before b plus the gap blocks among them */
            size_t lo = 0, hi = nb;
            while (lo < hi) {
                size_t mid = lo + (hi - lo) / 2, i = lower_bound(ib, ni, mid);
                if (cum[i] + (mid - i) < target) lo = mid + 1;
                else hi = mid;
            }
            bsplit[t] = lo;
            isplit[t] = lower_bound(ib, ni, lo);
        }
        if (isplit[t] < isplit[t - 1]) isplit[t] = isplit[t - 1];
        if (bsplit[t] < bsplit[t - 1]) bsplit[t] = bsplit[t - 1];
    }
    isplit[parts] = ni;
    bsplit[parts] = gaps ? nb : ni;
}

/* Each of split_work's parts (items ps_i[t] .. ps_i[t+1]-1, blocks ps_b[t] .. ps_b[t+1]-1)
 * cut into nc chunks of about equal item cost: chunk c = t nc + j is items isplit[c] ..
 * isplit[c+1]-1 and, with gaps, blocks bsplit[c] .. bsplit[c+1]-1 (a chunk copies the gap
 * blocks after its last item up to the next chunk's first item). A binary search on the
 * prefix costs a chunk, within its part (split_work's search over blocks does a search over
 * items at each step, about ten times the steps). ib NULL: blocks of equal cost. */
static void chunk_work(const uint32_t *ib, const size_t *cum, const size_t *ps_i,
                       const size_t *ps_b, size_t parts, size_t nc, size_t *isplit,
                       size_t *bsplit)
{
    for (size_t t = 0; t < parts; t++) {
        const size_t a = ps_i[t], e = ps_i[t + 1];
        isplit[t * nc] = a;
        bsplit[t * nc] = ps_b[t];
        for (size_t j = 1; j < nc; j++) {
            const size_t i = !ib ? a + (e - a) * j / nc
                                 : cost_reach(cum, a, e, cum[a] + (cum[e] - cum[a]) * j / nc);
            isplit[t * nc + j] = i;
            bsplit[t * nc + j] = !ib ? i : i < e ? ib[i] : ps_b[t + 1];
        }
    }
    isplit[parts * nc] = ps_i[parts];
    bsplit[parts * nc] = ps_b[parts];
}

void csrbf_sched_drive(const eval_plan *p, drive_fn drive, const uint32_t *ib,
                       const uint64_t *im, const size_t *ic, size_t ni, int gaps, size_t cost,
                       const weight_cache *wc, block_stats *bs)
{
    const csrbf_points *P = p->P;
    float *out = p->out;
    const float *cpack = p->cpack;
    const float inv_r2 = p->inv_r2;
    const size_t nb = p->nb, m = p->m, nt = (size_t)p->nt;
    /* threads by the computed blocks' cost; copying the gaps (a full write) is bound by
     * memory and does not count, but is shared out when threads run */
    if (cost <= PARALLEL_COST || nt == 1) {
        drive(P, out, ib, im, 0, ni, 0, gaps ? nb : 0, m, cpack, inv_r2, wc, bs);
        return;
    }
    /* one contiguous part of equal cost per thread, in STEAL_CHUNKS chunks: a thread takes
     * its own part's chunks in order, so that frame after frame the same blocks stay in the
     * same core's cache, and then steals from the far end of the others' (a core that the
     * host slows, or a thread that starts late, no longer holds the frame back: on a shared
     * machine one core may run the same part markedly slower than the other for minutes at
     * a time, docs/performance.md) */
    const size_t parts = nt;
    size_t *const isplit = p->isplit, *const bsplit = p->bsplit, *const psplit = p->psplit;
    steal_part *const spans = p->spans;
    split_work(ib, ic, ni, gaps, nb, parts, cost + (gaps ? nb - ni : 0), psplit,
               psplit + parts + 1);
    chunk_work(ib, ic, psplit, psplit + parts + 1, parts, STEAL_CHUNKS, isplit, bsplit);
    for (size_t t = 0; t < parts; t++)
        atomic_init(&spans[t].span,
                    (uint64_t)(t * STEAL_CHUNKS) | (uint64_t)((t + 1) * STEAL_CHUNKS) << 32);
    size_t pairs = 0, moved = 0;
    float maxd2 = 0.0f;
#pragma omp parallel num_threads(nt) reduction(+ : pairs, moved) reduction(max : maxd2)
    {
        block_stats ts = {0, 0, 0.0f};
        /* its own part, then the others' (those of threads missing from a smaller team than
         * asked for whole, from the front) */
        const size_t me = (size_t)omp_get_thread_num(), team = (size_t)omp_get_num_threads();
        for (size_t q = 0; q < parts; q++) {
            const size_t t = (me + q) % parts;
            for (size_t c; (c = steal_take(&spans[t], q && t < team)) != SIZE_MAX;)
                drive(P, out, ib, im, isplit[c], isplit[c + 1], gaps ? bsplit[c] : 0,
                      gaps ? bsplit[c + 1] : 0, m, cpack, inv_r2, wc, &ts);
        }
        pairs += ts.pairs;
        moved += ts.moved;
        if (ts.maxd2 > maxd2) maxd2 = ts.maxd2;
    }
    bs->pairs += pairs;
    bs->moved += moved;
    bs->maxd2 = maxd2;
}

/* The weight cache's parts in s->sel_wmem for k items and e pairs (see internal.h). */
typedef struct {
    float *w;
    uint16_t *in;
    uint32_t *off;
    size_t *cum;
} wcache_parts;

/* Byte offsets of the parts (o[0]: masks, o[1]: first pairs, o[2]: costs); returns the size
 * of the whole. */
static size_t wcache_bytes(size_t k, size_t e, size_t o[3])
{
    o[0] = e * B * sizeof(float);
    o[1] = align64(o[0] + e * sizeof(uint16_t));
    o[2] = align64(o[1] + (k + 1) * sizeof(uint32_t));
    return align64(o[2] + (k + 1) * sizeof(size_t));
}

static wcache_parts wcache_at(const csrbf_solver *s)
{
    size_t o[3];
    wcache_bytes(s->sel_k, s->sel_evals, o);
    unsigned char *mem = s->sel_wmem;
    return (wcache_parts){(float *)mem, (uint16_t *)(mem + o[0]), (uint32_t *)(mem + o[1]),
                          (size_t *)(mem + o[2])};
}

/* Fill the weight cache of the solver's kept (refined) selection; 0 when memory runs out (the
 * kernels then compute the weights). Its prefix costs count cached pairs. */
static int wcache_fill(csrbf_solver *s, const csrbf_points *P, const eval_isa *isa, int ki,
                       const float *cp, float inv_r2)
{
    size_t o[3], bytes = wcache_bytes(s->sel_k, s->sel_evals, o);
    if (bytes > s->sel_wbytes) {
        void *q = aligned_alloc(64, bytes);
        if (!q) return 0;
        free(s->sel_wmem);
        s->sel_wmem = q;
        s->sel_wbytes = bytes;
    }
    wcache_parts c = wcache_at(s);
    isa->fills[ki](P, s->sel_blk, s->sel_msk, s->sel_k, cp, inv_r2, c.w, c.in, c.off);
    for (size_t i = 0; i <= s->sel_k; i++) c.cum[i] = ITEM_COST_CACHED(i, c.off[i]);
    /* the statistics the cached drivers leave out: a lane past the mesh's end (its last,
     * partial block) is no vertex */
    size_t pairs = 0, moved = 0;
    for (size_t i = 0; i < s->sel_k; i++) {
        size_t k0 = (size_t)s->sel_blk[i] * B, nv = k0 + B <= P->n ? B : P->n - k0;
        unsigned lanes = (unsigned)((1u << nv) - 1), any = 0;
        for (uint32_t q = c.off[i]; q < c.off[i + 1]; q++) {
            pairs += (size_t)__builtin_popcount(c.in[q] & lanes);
            any |= c.in[q];
        }
        moved += (size_t)__builtin_popcount(any & lanes);
    }
    s->sel_w_pairs = pairs;
    s->sel_w_moved = moved;
    s->sel_w_id = s->sel_id;
    return 1;
}

/* The filled weight cache into *wc, its prefix costs into *cum; returns wc. */
static weight_cache *wcache_get(const csrbf_solver *s, weight_cache *wc, const size_t **cum)
{
    wcache_parts c = wcache_at(s);
    wc->w = c.w;
    wc->in = c.in;
    wc->off = c.off;
    *cum = c.cum;
    return wc;
}

const weight_cache *csrbf_wcache_for(eval_plan *p, const uint32_t *ib, weight_cache *wcv,
                                     const size_t **ic)
{
    csrbf_solver *s = p->s;
    const block_select *S = &p->S;
    /* the kept selection's weight cache, for frames whose items are exactly that selection
     * (full writes and unchanged touched ones) and whose bytes stay within
     * CSRBF_WCACHE_THREAD_BYTES per thread: filled at the first such frame after the
     * selection is refined (its second use) */
    if (!p->use_tree || p->own || ib != S->blk || !s->sel_refined || !S->k) return NULL;
    const size_t ccost = ITEM_COST_CACHED(S->k, S->evals);
    const size_t cthreads = ccost <= PARALLEL_COST ? 1 : (size_t)p->nt;
    const size_t bytes = 24 * (p->full_write ? p->n : S->k * B) + WCACHE_PAIR_BYTES * S->evals;
    if (bytes <= cthreads * CSRBF_WCACHE_THREAD_BYTES &&
        (s->sel_w_id == s->sel_id || wcache_fill(s, p->P, p->isa, p->ki, p->cpack, p->inv_r2)))
        return wcache_get(s, wcv, ic);
    return NULL;
}
