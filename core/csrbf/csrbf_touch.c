/* csrbf_touch: the persistent output's state (which blocks the last csrbf_evaluate_touched
 * computed, which vertex ranges it wrote), its public functions (csrbf.h), the composed
 * step's access (internal.h), and the bookkeeping each path of an evaluation does with it
 * (eval_internal.h): a touched call's work list (the selection merged with the last call's
 * blocks), and the blocks and ranges it leaves. Invariant, asserted (debug builds) wherever a
 * call leaves the state: the blocks lie inside the mesh (< nblocks, increasing), the ranges
 * inside its n vertices. */
#include "eval_internal.h"

#include <assert.h>
#include <stdlib.h>

/* The invariant (above); O(blocks + ranges), nothing without assertions. */
static void touch_check(const csrbf_touch *t)
{
#ifndef NDEBUG
    const size_t n = t->points->n;
    assert(t->nprev <= t->nblocks);
    for (size_t i = 0; i < t->nprev; i++)
        assert(t->prev[i] < t->nblocks && (i == 0 || t->prev[i - 1] < t->prev[i]));
    assert(t->nranges <= t->nblocks + 1);
    for (size_t r = 0; r < t->nranges; r++)
        assert(t->ranges[2 * r] <= n && t->ranges[2 * r + 1] <= n - t->ranges[2 * r]);
#else
    (void)t;
#endif
}

int csrbf_touch_create(const csrbf_points *points, csrbf_touch **out)
{
    if (!out) return CSRBF_ERR_INVALID;
    *out = NULL;
    if (!points) return CSRBF_ERR_INVALID;
    csrbf_touch *t = calloc(1, sizeof *t);
    if (!t) return CSRBF_ERR_NOMEM;
    t->points = points;
    t->nblocks = points->nblocks;
    t->prev = malloc(t->nblocks * sizeof *t->prev);
    t->ranges = malloc((t->nblocks + 1) * 2 * sizeof *t->ranges);
    if (!t->prev || !t->ranges) {
        csrbf_touch_destroy(&t);
        return CSRBF_ERR_NOMEM;
    }
    t->full = 1;
    *out = t;
    return CSRBF_OK;
}

void csrbf_touch_destroy(csrbf_touch **tp)
{
    if (!tp || !*tp) return;
    free((*tp)->prev);
    free((*tp)->ranges);
    free(*tp);
    *tp = NULL;
}

void csrbf_touch_reset(csrbf_touch *t)
{
    if (t) t->full = 1;
}

void csrbf_touch_commit(csrbf_touch *t)
{
    if (!t) return;
    t->full = 0; /* the output is the base: a reset before it is answered too */
    t->nprev = 0;
    t->nranges = 0;
    t->sel_id = 0;
    t->ranges_sel = 0;
}

size_t csrbf_touch_ranges(const csrbf_touch *t, const uint32_t **ranges)
{
    if (ranges) *ranges = t ? t->ranges : NULL;
    return t ? t->nranges : 0;
}

const uint32_t *csrbf_touch_prev(const csrbf_touch *t, size_t *k, int *full)
{
    *k = t->nprev;
    if (full) *full = t->full;
    return t->prev;
}

int csrbf_touch_for(const csrbf_touch *t, const csrbf_points *p)
{
    return t && p && t->points == p && t->nblocks == p->nblocks;
}

size_t csrbf_block_ranges(const uint32_t *blk, size_t k, size_t n, uint32_t *ranges)
{
    size_t nr = 0;
    for (size_t i = 0; i < k;) {
        size_t b0 = blk[i], b1 = b0 + 1;
        assert(b0 * B < n); /* a block inside the mesh */
        for (i++; i < k && blk[i] == b1; i++) b1++;
        size_t v1 = b1 * B < n ? b1 * B : n;
        ranges[2 * nr] = (uint32_t)(b0 * B);
        ranges[2 * nr + 1] = (uint32_t)(v1 - b0 * B);
        nr++;
    }
    return nr;
}

void csrbf_touch_set(csrbf_touch *t, const uint32_t *blk, size_t k, const uint32_t *wr, size_t kw,
                     int all)
{
    if (blk != t->prev) memcpy(t->prev, blk, k * sizeof *blk);
    t->nprev = k;
    t->full = 0;
    t->sel_id = 0;
    t->ranges_sel = 0;
    if (all) {
        t->ranges[0] = 0;
        t->ranges[1] = (uint32_t)t->points->n;
        t->nranges = 1;
    } else {
        t->nranges = csrbf_block_ranges(wr, kw, t->points->n, t->ranges);
    }
    touch_check(t);
}

/* ---------------------------------------- an evaluation's bookkeeping (eval_internal.h) */

/* t->ranges from k increasing blocks: runs of consecutive blocks as vertex ranges. */
static void ranges_of_blocks(csrbf_touch *t, const uint32_t *blk, size_t k)
{
    t->nranges = csrbf_block_ranges(blk, k, t->points->n, t->ranges);
}

static void ranges_all(csrbf_touch *t)
{
    t->ranges[0] = 0;
    t->ranges[1] = (uint32_t)t->points->n;
    t->nranges = 1;
}

/* The touch's last-call list becomes blk[0..k) (copied, unless it is the list itself). */
static void touch_set_prev(csrbf_touch *t, const uint32_t *blk, size_t k)
{
    if (blk != t->prev) memcpy(t->prev, blk, k * sizeof *blk);
    t->nprev = k;
}

/* csrbf_touch_merge(_cost): with ocum, the prefix costs too (scum: the selection's). */
static inline __attribute__((always_inline)) size_t
merge_last(const uint32_t *sb, const uint64_t *sm, const size_t *scum, size_t k,
           const uint32_t *pv, size_t np, uint32_t *ob, uint64_t *om, size_t *ocum)
{
    size_t a = 0, c = 0, o = 0, cc = 0;
    while (a < k || c < np) {
        if (ocum) ocum[o] = cc;
        if (c >= np || (a < k && sb[a] < pv[c])) {
            if (ocum) cc += scum[a + 1] - scum[a];
            ob[o] = sb[a];
            om[o++] = sm[a++];
        } else if (a >= k || pv[c] < sb[a]) {
            if (ocum) cc += ITEM_COST(0);
            ob[o] = pv[c++];
            om[o++] = 0;
        } else {
            if (ocum) cc += scum[a + 1] - scum[a];
            ob[o] = sb[a];
            om[o++] = sm[a++];
            c++;
        }
    }
    if (ocum) ocum[o] = cc;
    return o;
}

size_t csrbf_touch_merge(const uint32_t *sb, const uint64_t *sm, size_t k, const uint32_t *pv,
                         size_t np, uint32_t *ob, uint64_t *om)
{
    return merge_last(sb, sm, NULL, k, pv, np, ob, om, NULL);
}

size_t csrbf_touch_merge_cost(const uint32_t *sb, const uint64_t *sm, const size_t *scum,
                              size_t k, const uint32_t *pv, size_t np, uint32_t *ob,
                              uint64_t *om, size_t *ocum)
{
    return merge_last(sb, sm, scum, k, pv, np, ob, om, ocum);
}

void csrbf_touch_after_parts(csrbf_touch *t, int full_write, const uint32_t *psel,
                             const size_t *nsel, uint32_t *pwr, const size_t *nwr,
                             size_t fparts, size_t fmax)
{
    size_t k = 0, w = 0;
    for (size_t q = 0; q < fparts; q++) {
        memcpy(t->prev + k, psel + q * fmax, nsel[q] * sizeof *psel);
        k += nsel[q];
        memmove(pwr + w, pwr + q * fmax, nwr[q] * sizeof *pwr);
        w += nwr[q];
    }
    t->nprev = k;
    if (full_write) ranges_all(t);
    else ranges_of_blocks(t, pwr, w);
    t->sel_id = 0;
    t->ranges_sel = 0;
    t->full = 0;
    touch_check(t);
}

void csrbf_touch_after_listed(csrbf_touch *t, int use_tree, int full_write, int same,
                              const uint32_t *ib, size_t ni, const uint32_t *sel, size_t k,
                              uint64_t sel_id)
{
    if (!use_tree) { /* (all in) */
        ranges_all(t);
        for (size_t b = 0; b < t->nblocks; b++) t->prev[b] = (uint32_t)b;
        t->nprev = t->nblocks;
        t->sel_id = 0;
        t->ranges_sel = 0;
    } else {
        if (full_write) {
            ranges_all(t);
            t->ranges_sel = 0;
        } else if (!same || !t->ranges_sel) {
            ranges_of_blocks(t, ib, ni);
            t->ranges_sel = ni == k;
        }
        if (!same) touch_set_prev(t, sel, k);
        t->sel_id = sel_id;
    }
    t->full = 0;
    touch_check(t);
}

void csrbf_touch_mark_prev(const csrbf_touch *t, uint8_t *tprev, int full_write)
{
    memset(tprev, full_write, t->nblocks);
    if (!full_write)
        for (size_t i = 0; i < t->nprev; i++) tprev[t->prev[i]] = 1;
}

void csrbf_touch_after_general(csrbf_touch *t, const uint8_t *tcur, const uint8_t *tprev)
{
    const size_t nb = t->nblocks, n = t->points->n;
    size_t k = 0, nr = 0;
    for (size_t b = 0; b < nb;) {
        if (!(tcur[b] || tprev[b])) {
            b++;
            continue;
        }
        size_t b0 = b;
        for (; b < nb && (tcur[b] || tprev[b]); b++)
            if (tcur[b]) t->prev[k++] = (uint32_t)b; /* tprev holds the old list */
        size_t v1 = b * B < n ? b * B : n;
        t->ranges[2 * nr] = (uint32_t)(b0 * B);
        t->ranges[2 * nr + 1] = (uint32_t)(v1 - b0 * B);
        nr++;
    }
    t->nranges = nr;
    t->nprev = k;
    t->sel_id = 0;
    t->ranges_sel = 0;
    t->full = 0;
    touch_check(t);
}
