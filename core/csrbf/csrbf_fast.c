/* csrbf_evaluate's fast path (no polynomial, no Jacobian, up to CSRBF_FAST_MAX_CENTRES
 * centres or all of them): the kernels and drivers of eval_simd.h, written once over 16-lane
 * operations and compiled here twice, AVX-512 (one zmm per block) and AVX2 + FMA (two ymm
 * halves, simd16_avx2.h), picked at run time by csrbf_isa_pick; and its two runners: a
 * selection walked and evaluated part by part inside the threads (fused: a selection used
 * once), or a work list (every block, the selection with the gaps between its blocks, or the
 * selection merged with the last call's blocks) driven through csrbf_sched_drive, with the
 * kept selection's weight cache where it pays. */
#include "eval_internal.h"

#include <assert.h>
#include <omp.h>
#include <stdlib.h>

#if CSRBF_SIMD
/* Interleave 16 x, y, z (+ displacement) into 48 contiguous floats. */
static inline __attribute__((target("avx512f"), always_inline)) void
interleave_avx512(float *restrict out, __m512 X, __m512 Y, __m512 Z)
{
    /* output float f = 16 k + i holds component f % 3 of vertex f / 3: first pick x or y
     * (index < 16: X, >= 16: Y; z lanes are placeholders), then insert z (16 + v) */
    static const int32_t ixy[3][16] = {
        {0, 16, 0, 1, 17, 1, 2, 18, 2, 3, 19, 3, 4, 20, 4, 5},
        {21, 5, 6, 22, 6, 7, 23, 7, 8, 24, 8, 9, 25, 9, 10, 26},
        {10, 11, 27, 11, 12, 28, 12, 13, 29, 13, 14, 30, 14, 15, 31, 15}};
    static const int32_t iz[3][16] = {
        {0, 1, 16, 3, 4, 17, 6, 7, 18, 9, 10, 19, 12, 13, 20, 15},
        {0, 21, 2, 3, 22, 5, 6, 23, 8, 9, 24, 11, 12, 25, 14, 15},
        {26, 1, 2, 27, 4, 5, 28, 7, 8, 29, 10, 11, 30, 13, 14, 31}};
    for (int k = 0; k < 3; k++) {
        __m512 xy = _mm512_permutex2var_ps(X, _mm512_loadu_si512(ixy[k]), Y);
        __m512 o = _mm512_permutex2var_ps(xy, _mm512_loadu_si512(iz[k]), Z);
        _mm512_storeu_ps(out + 16 * k, o);
    }
}

#define CSRBF_ISA_AVX512 1
#define CSRBF_ISA_AVX2 2
#define CSRBF_ISA CSRBF_ISA_AVX512
#include "eval_simd.h"
#undef CSRBF_ISA
#include "simd16_avx2.h"
#define CSRBF_ISA CSRBF_ISA_AVX2
#include "eval_simd.h"
#undef CSRBF_ISA
#endif

/* The instruction set of the fast path: AVX-512 where the CPU has it, else AVX2 with FMA,
 * else none (the portable general path). The environment variable CSRBF_ISA=avx2 or =none
 * (or =portable, the name csrbf_simd_path gives it) asks for less than the CPU has (tests
 * run every path on one machine); any other value changes nothing. */
int csrbf_isa_pick(const eval_isa **isa)
{
#if CSRBF_SIMD
    static const eval_isa *_Atomic picked;
    static _Atomic int known;
    if (!atomic_load(&known)) { /* benign race: every thread finds the same */
        __builtin_cpu_init();
        const char *want = getenv("CSRBF_ISA");
        const int cap = __builtin_cpu_supports("avx512f") ? 2
                        : __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") ? 1
                                                                                          : 0;
        int use = cap;
        if (want && !strcmp(want, "avx2") && use > 1) use = 1;
        if (want && (!strcmp(want, "none") || !strcmp(want, "portable"))) use = 0;
        atomic_store(&picked, use == 2 ? &isa_avx512 : use == 1 ? &isa_avx2 : NULL);
        atomic_store(&known, 1);
    }
    const eval_isa *got = atomic_load(&picked);
    *isa = got;
    return got == &isa_avx512 ? SIMD_AVX512 : got ? SIMD_AVX2 : SIMD_NONE;
#else
    *isa = NULL;
    return SIMD_NONE;
#endif
}

/* A selection not kept (unanchored frames): each thread walks the tree for its parts of the
 * mesh and evaluates them at once. A full write copies each part's gaps; a touched call's
 * work list is the part's selection merged with the last call's blocks there. */
static void run_fused(eval_plan *p)
{
    const csrbf_points *P = p->P;
    csrbf_touch *touch = p->touch;
    float *out = p->out;
    const float *cpack = p->cpack;
    const float inv_r2 = p->inv_r2;
    const int full_write = p->full_write, simd = p->simd;
    const size_t nb = p->nb, m = p->m, fparts = p->fparts, fmax = p->fmax, fthr = p->fthr;
    const drive_fn drive =
        p->isa->drivers[p->ki][p->st != NULL][full_write ? DRIVE_GAPS : DRIVE_LIST];
    const uint64_t all = m >= 64 ? ~0ull : (1ull << m) - 1;
    unsigned char *fbuf = p->fbuf;
    /* per part with a touch: its selected blocks (the next call's last-call list) and its
     * written ones (the ranges), fmax each, and their counts */
    uint32_t *psel = (uint32_t *)(fbuf + (size_t)p->nt * fthr),
             *pwr = psel + align64(fparts * fmax * sizeof(uint32_t)) / sizeof(uint32_t);
    size_t *nsel = (size_t *)(pwr + align64(fparts * fmax * sizeof(uint32_t)) /
                                        sizeof(uint32_t)),
           *nwr = nsel + fparts;
    const uint32_t *pv = touch ? touch->prev : NULL;
    const size_t np = touch ? touch->nprev : 0;
    const block_select S = p->S;
    size_t pairs = 0, moved = 0;
    float maxd2 = 0.0f;
#pragma omp parallel num_threads(p->nt) reduction(+ : pairs, moved) reduction(max : maxd2)
    {
        block_stats ts = {0, 0, 0.0f};
        /* the thread's own: the part's masks, and its blocks unless a touch keeps them per
         * part (then the masks of the part's work list) */
        unsigned char *mine = fbuf + (size_t)omp_get_thread_num() * fthr;
        block_select L = S;
        L.msk = (uint64_t *)mine;
        L.blk = (uint32_t *)(mine + align64(fmax * sizeof(uint64_t)));
        uint64_t *wm = (uint64_t *)(mine + align64(fmax * sizeof(uint64_t)));
#pragma omp for schedule(dynamic, 1)
        for (size_t q = 0; q < fparts; q++) {
            size_t lo = nb * q / fparts, hi = nb * (q + 1) / fparts;
            if (touch) nsel[q] = nwr[q] = 0;
            if (hi <= lo) continue;
            if (touch) L.blk = psel + q * fmax;
            L.k = 0;
            csrbf_sel_range(&L, simd, all, lo, hi);
            assert(L.k <= hi - lo && hi - lo <= fmax && hi <= nb); /* the part's blocks */
            if (full_write) {
                drive(P, out, L.blk, L.msk, 0, L.k, lo, hi, m, cpack, inv_r2, NULL, &ts);
            } else {
                uint32_t *wb = pwr + q * fmax;
                const size_t c0 = lower_bound(pv, np, lo), c1 = lower_bound(pv, np, hi);
                const size_t k = csrbf_touch_merge(L.blk, L.msk, L.k, pv + c0, c1 - c0, wb, wm);
                assert(k <= hi - lo);
                drive(P, out, wb, wm, 0, k, 0, 0, m, cpack, inv_r2, NULL, &ts);
                nwr[q] = k;
            }
            if (touch) nsel[q] = L.k;
        }
        pairs += ts.pairs;
        moved += ts.moved;
        if (ts.maxd2 > maxd2) maxd2 = ts.maxd2;
    }
    p->pairs += pairs;
    p->moved += moved;
    p->maxd = maxd2;
    if (touch) csrbf_touch_after_parts(touch, full_write, psel, nsel, pwr, nwr, fparts, fmax);
}

/* The work list: every block (all in), the selected blocks with the gaps between them copied
 * (a full write), or the selected blocks merged with the last call's (restored where no
 * support holds them now), through the weight cache where it serves. */
static void run_listed(eval_plan *p)
{
    const csrbf_solver *s = p->s;
    csrbf_touch *touch = p->touch;
    const block_select *S = &p->S;
    const uint32_t *ib = NULL;
    const uint64_t *im = NULL;
    const size_t *ic = NULL;
    size_t ni = p->nb, cost = p->nb * ITEM_COST(p->m);
    int gaps = 0, same = 0;
    if (p->use_tree) {
        ib = S->blk;
        im = S->msk;
        ic = S->cum;
        ni = S->k;
        if (p->full_write) {
            gaps = 1;
        } else if (!p->own && touch->sel_id == s->sel_id) {
            same = 1; /* the last call computed exactly these blocks: nothing to restore */
        } else {
            ni = csrbf_touch_merge_cost(S->blk, S->msk, S->cum, S->k, touch->prev, touch->nprev,
                                        p->mrg_blk, p->mrg_msk, p->mrg_cum);
            ib = p->mrg_blk;
            im = p->mrg_msk;
            ic = p->mrg_cum;
        }
        cost = ic[ni];
    }
    weight_cache wcv;
    const weight_cache *wc = csrbf_wcache_for(p, ib, &wcv, &ic);
    if (wc) cost = ic[ni];
    const int mode = !ib ? DRIVE_ALL : gaps ? DRIVE_GAPS : DRIVE_LIST;
    const drive_fn drive = wc ? p->isa->cached[p->st != NULL][mode - DRIVE_LIST]
                              : p->isa->drivers[p->ki][p->st != NULL][mode];
    block_stats bs = {0, 0, 0.0f};
    csrbf_sched_drive(p, drive, ib, im, ic, ni, gaps, cost, wc, &bs);
    /* the cached drivers leave the pairs and moved vertices to the cache's counts */
    p->pairs += bs.pairs + (wc ? s->sel_w_pairs : 0);
    p->moved += bs.moved + (wc ? s->sel_w_moved : 0);
    p->maxd = bs.maxd2;
    if (touch) /* this call's computed blocks become the last call's */
        csrbf_touch_after_listed(touch, p->use_tree, p->full_write, same, ib, ni, S->blk, S->k,
                                 p->own ? 0 : s->sel_id); /* (own memory: not the solver's) */
}

void csrbf_run_fast(eval_plan *p)
{
    const csrbf_solver *s = p->s;
    for (size_t j = 0; j < p->m; j++) {
        float *q = p->cpack + 8 * j;
        q[0] = s->fc[0][j], q[1] = s->fc[1][j], q[2] = s->fc[2][j];
        q[3] = s->fa[0][j], q[4] = s->fa[1][j], q[5] = s->fa[2][j];
        q[6] = q[7] = 0.0f;
    }
    if (p->fused) run_fused(p);
    else run_listed(p);
}
