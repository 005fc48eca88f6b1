/* csrbf_evaluate: T(x) at every vertex. Blocks of CSRBF_BLOCK consecutive vertices are
 * matched against the centres whose support meets the block's box, found through the points'
 * block tree for all centres at once (64-bit masks, kept in the solver while the centres and
 * the points stay; csrbf_select.c) or, beyond 64 centres, the centre grid; within a block the
 * loop runs over the selected centres and vectorises over the vertices (csrbf_fast.c with
 * eval_simd.h: AVX-512, else AVX2 + FMA, picked at run time; else csrbf_general.c's SIMD
 * clones). Blocks run in parallel with OpenMP, one contiguous part of equal cost per thread
 * (csrbf_sched.c). csrbf_evaluate_touched writes only the blocks in a support now or at its
 * last call (csrbf_touch.c).
 *
 * This file: the entry points and the plan of a call: what it does (plan_make), its scratch
 * (plan_sizes, plan_scratch), its block selection (plan_select), then the runner, the fast
 * path or the general one, and the statistics (plan_finish). */
#include "eval_internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

/* What the call does: the checks, the path, the threads. */
static int plan_make(eval_plan *p, const csrbf_solver *cs, const csrbf_points *P, float *out,
                     unsigned flags, csrbf_eval_stats *st, csrbf_touch *touch)
{
    if (!cs || !P || !out || (flags & ~(unsigned)CSRBF_EVAL_JACOBIAN)) return CSRBF_ERR_INVALID;
    if (!cs->have_start) return CSRBF_ERR_STATE;
    /* every other field is set below, in plan_sizes, plan_scratch or plan_select, before it
     * is read; these a path may leave alone (no memset of the whole plan, 512 bytes: the
     * smallest calls are short) */
    p->fused = p->own = 0;
    p->mem = NULL;
    p->pairs = p->moved = 0;
    p->maxd = 0.0;
    /* The scratch buffer is the only state evaluate touches; a concurrent caller that finds it
     * busy allocates its own. The solver itself is read-only here (but for the kept
     * selection, which only the scratch's holder uses). */
    csrbf_solver *s = (csrbf_solver *)cs;
    p->s = s;
    p->P = P;
    p->out = out;
    p->st = st;
    p->touch = touch;
    p->n = P->n;
    p->nb = P->nblocks;
    p->m = s->m;
    p->poly = s->k > 0;
    p->want_jac = st && (flags & CSRBF_EVAL_JACOBIAN);
    p->full_write = !touch || touch->full;
    const int nt = s->opt.threads > 0 ? s->opt.threads : omp_get_max_threads();
    p->nt = nt < 1 ? 1 : nt;
    p->minjac = 1.0;

    /* every centre's support holds the whole vertex box: no selection needed */
    p->all_in = csrbf_sel_all_in(s, P);
    /* up to CSRBF_FAST_MAX_CENTRES centres: blocks and their centre masks from the block
     * tree; beyond, the centre grid per block (general path) */
    const int tree_ok = p->m <= CSRBF_FAST_MAX_CENTRES;
    p->use_tree = !p->all_in && tree_ok; /* (all in: may change in plan_select, at a second use) */
    p->ki = s->opt.kernel == CSRBF_PSI30 ? 1 : s->opt.kernel == CSRBF_PSI32 ? 2 : 0;
    p->simd = csrbf_isa_pick(&p->isa);
    /* the fused AVX-512 path: no polynomial, no Jacobian, all centres or tree masks
     * (statistics are counted inside it) */
    p->fast = p->isa && !p->want_jac && !p->poly && (p->all_in || p->use_tree);
    /* all in, fast: at the second use of these centres and points (an anchored frame) the
     * tree's way, for the kept selection (every block, every centre) and its weight cache,
     * where that cache will be used (its bytes within the threads' share, as in
     * csrbf_wcache_for); else the tree's masks only cost (docs/performance.md, the scale
     * case) */
    const size_t all_evals = p->nb * p->m, all_cost = ITEM_COST_CACHED(p->nb, all_evals);
    const size_t all_bytes = 24 * p->nb * B + WCACHE_PAIR_BYTES * all_evals;
    p->all_in_kept = p->all_in && tree_ok && p->fast &&
                     all_bytes <= (all_cost <= PARALLEL_COST ? 1 : (size_t)p->nt) *
                                      CSRBF_WCACHE_THREAD_BYTES;
    p->R2 = s->R * s->R;
    p->inv_r2 = (float)(1.0 / p->R2);
    p->r2c = (float)(p->R2 * (1.0 + 1e-5)) + 1e-30f;
    return CSRBF_OK;
}

/* The scratch's parts: the merged work list of a touched call, and for the general path
 * dense masks, block flags and a centre list per thread; a concurrent caller (without the
 * solver's scratch) also holds its own block selection. */
static void plan_sizes(eval_plan *p)
{
    const size_t nb = p->nb, nt = (size_t)p->nt;
    const int fast = p->fast, use_tree = p->use_tree;
    p->per_thread = align64(p->m * sizeof(uint32_t));
    p->blk_m = align64(nb * sizeof(uint64_t));
    p->blk_b = align64(nb * sizeof(uint32_t));
    p->blk_c = align64((nb + 1) * sizeof(size_t));
    p->mrg = fast && (use_tree || p->all_in_kept) && !p->full_write ? p->blk_m + p->blk_b + p->blk_c
                                                                    : 0;
    p->nchunks = nt * STEAL_CHUNKS;
    p->chunk_b = align64(2 * (p->nchunks + nt + 2) * sizeof(size_t));
    p->splits = fast ? p->chunk_b + nt * sizeof(steal_part) : 0;
    p->gen_m = !fast && use_tree ? p->blk_m : 0;
    p->gen_f = !fast && p->touch ? align64(2 * nb) : 0;
    p->gen_t = !fast ? nt * p->per_thread : 0;
    p->pack = fast ? align64(p->m * 8 * sizeof(float)) : 0;
    /* a fused walk-and-evaluate (a selection not kept): per thread, the selection of one
     * part of the mesh (its masks, and its blocks unless a touch keeps them per part), and
     * with a touch the masks of the part's work list; per part with a touch, its selected
     * blocks (the next call's last-call list) and its written ones (the ranges) */
    p->fparts = SPLIT_PARTS * nt;
    p->fmax = nb / p->fparts + 2;
    p->fthr = align64(p->fmax * sizeof(uint64_t)) +
              (p->touch ? align64(p->fmax * sizeof(uint64_t)) : align64(p->fmax * sizeof(uint32_t)));
    p->fpart = p->touch ? 2 * align64(p->fparts * p->fmax * sizeof(uint32_t)) +
                              align64(2 * p->fparts * sizeof(size_t))
                        : 0;
    p->fsz = fast && use_tree && nt > 1 ? nt * p->fthr + p->fpart : 0;
    p->need = p->pack + p->splits + p->mrg + p->gen_m + p->gen_f + p->gen_t + p->fsz + 64;
}

/* The solver's scratch (and room for its kept selection) when free, else memory of the
 * call's own; then the parts' places in it. */
static int plan_scratch(eval_plan *p)
{
    csrbf_solver *s = p->s;
    const size_t nb = p->nb;
    plan_sizes(p);
    size_t need = p->need;
    if (!atomic_flag_test_and_set(&s->scratch_busy)) {
        if (s->scratch_cap < need) {
            void *q = realloc(s->scratch, need);
            if (!q) {
                atomic_flag_clear(&s->scratch_busy);
                return CSRBF_ERR_NOMEM;
            }
            s->scratch = q;
            s->scratch_cap = need;
        }
        if ((p->use_tree || p->all_in_kept) && s->sel_cap < nb) {
            uint32_t *b2 = realloc(s->sel_blk, nb * sizeof *b2);
            if (b2) s->sel_blk = b2;
            uint64_t *m2 = b2 ? realloc(s->sel_msk, nb * sizeof *m2) : NULL;
            if (m2) s->sel_msk = m2;
            size_t *c2 = m2 ? realloc(s->sel_cum, (nb + 1) * sizeof *c2) : NULL;
            if (c2) s->sel_cum = c2;
            if (!b2 || !m2 || !c2) {
                atomic_flag_clear(&s->scratch_busy);
                return CSRBF_ERR_NOMEM;
            }
            s->sel_cap = nb;
            s->sel_pts = s->sel_ctr = 0;
        }
        p->mem = s->scratch;
    } else {
        need += p->use_tree ? p->blk_m + p->blk_b + p->blk_c : 0;
        p->mem = malloc(need);
        if (!p->mem) return CSRBF_ERR_NOMEM;
        p->own = 1;
    }
    unsigned char *sp = (unsigned char *)(((uintptr_t)p->mem + 63) & ~(uintptr_t)63);
    p->cpack = (float *)sp;
    p->isplit = (size_t *)(sp += p->pack);
    p->bsplit = p->isplit + p->nchunks + 1;
    p->psplit = p->bsplit + p->nchunks + 1;
    p->spans = (steal_part *)(sp + p->chunk_b);
    p->mrg_msk = (uint64_t *)(sp += p->splits);
    p->mrg_blk = (uint32_t *)(sp + (p->mrg ? p->blk_m : 0));
    p->mrg_cum = (size_t *)(sp + (p->mrg ? p->blk_m + p->blk_b : 0));
    p->gen_mask = (uint64_t *)(sp += p->mrg);
    p->tcur = (uint8_t *)(sp += p->gen_m);
    p->tprev = p->tcur + nb;
    p->tbase = (sp += p->gen_f);
    p->fbuf = p->tbase + p->gen_t;
    p->fbase = p->fbuf + p->fsz;
    return CSRBF_OK;
}

/* The solver's kept selection for these points and centres: reused (anchored frames), or
 * left to the threads' fused walks (a selection not seen before, large enough), or walked
 * now; refined at its second use. */
static void plan_kept(eval_plan *p)
{
    csrbf_solver *s = p->s;
    const csrbf_points *P = p->P;
    block_select *S = &p->S;
    S->blk = s->sel_blk;
    S->msk = s->sel_msk;
    S->cum = s->sel_cum;
    const int seen = s->sel_pts == P->stamp && s->sel_ctr == s->centres_stamp;
    int changed = 1;
    if (seen && s->sel_k != SEL_PENDING) {
        S->k = s->sel_k;
        S->evals = s->sel_evals;
        changed = 0;
    } else if (!seen && p->fast && p->fsz &&
               (double)p->n * csrbf_sel_support_share(s, P) >
                   (double)(p->full_write ? PARALLEL_LANES : PARALLEL_LANES_TOUCHED)) {
        /* a selection not seen before (unanchored frames): each thread walks the tree for
         * its parts of the mesh and evaluates them at once (csrbf_run_fast); the selection is
         * kept only if it is used again */
        p->fused = 1;
        s->sel_k = SEL_PENDING;
    } else {
        csrbf_sel_blocks(S, p->simd, p->m);
        s->sel_k = S->k;
        s->sel_evals = S->evals;
        s->sel_refined = 0;
    }
    if (seen && p->isa && !s->sel_refined && !p->fused) { /* used twice: refine it once */
        S->evals = p->isa->refine(S);
        s->sel_k = S->k;
        s->sel_evals = S->evals;
        s->sel_refined = 1;
        changed = 1;
    }
    if (changed) s->sel_id = csrbf_new_stamp();
    s->sel_pts = P->stamp;
    s->sel_ctr = s->centres_stamp;
}

/* The block selection: cached in the solver for these points and centres (anchored frames
 * reuse it), else a walk of the block tree. */
static void plan_select(eval_plan *p)
{
    csrbf_solver *s = p->s;
    const csrbf_points *P = p->P;
    p->S = (block_select){P, s->fc[0], s->fc[1], s->fc[2], p->r2c, p->inv_r2, NULL, NULL, NULL,
                          0, 0};
    /* all in: the first call with these centres and points computes every pair (no walk: an
     * unanchored frame's centres are new each time) and marks them seen; the next takes the
     * tree's way to a selection of every block with every centre, kept with its weights
     * (docs/performance.md: Table 1's R = 80 against R = 60 anchored updates) */
    if (p->all_in_kept && !p->own) {
        if (s->sel_pts == P->stamp && s->sel_ctr == s->centres_stamp) {
            p->use_tree = 1;
        } else {
            s->sel_pts = P->stamp;
            s->sel_ctr = s->centres_stamp;
            s->sel_k = SEL_PENDING;
        }
    }
    if (p->use_tree && p->own) {
        unsigned char *sp = p->fbase;
        p->S.msk = (uint64_t *)sp;
        p->S.blk = (uint32_t *)(sp + p->blk_m);
        p->S.cum = (size_t *)(sp + p->blk_m + p->blk_b);
        csrbf_sel_blocks(&p->S, p->simd, p->m);
    } else if (p->use_tree) {
        plan_kept(p);
    }
}

/* The scratch given back, the statistics out. */
static void plan_finish(eval_plan *p)
{
    if (p->own)
        free(p->mem);
    else
        atomic_flag_clear(&p->s->scratch_busy);
    if (p->st) {
        p->st->pairs = p->pairs;
        p->st->moved = p->moved;
        p->st->max_displacement = sqrt(p->maxd);
        p->st->min_jacobian_det = p->minjac;
    }
}

static int evaluate_impl(const csrbf_solver *cs, const csrbf_points *P, float *out,
                         unsigned flags, csrbf_eval_stats *st, csrbf_touch *touch)
{
    eval_plan p;
    int rc = plan_make(&p, cs, P, out, flags, st, touch);
    if (rc == CSRBF_OK) rc = plan_scratch(&p);
    if (rc != CSRBF_OK) return rc;
    plan_select(&p);
    if (p.fast)
        csrbf_run_fast(&p);
    else
        csrbf_run_general(&p);
    plan_finish(&p);
    return CSRBF_OK;
}

int csrbf_evaluate(const csrbf_solver *cs, const csrbf_points *P, float *out, unsigned flags,
                   csrbf_eval_stats *st)
{
    return evaluate_impl(cs, P, out, flags, st, NULL);
}

int csrbf_evaluate_touched(const csrbf_solver *cs, const csrbf_points *P, csrbf_touch *touch,
                           float *out, unsigned flags, csrbf_eval_stats *st)
{
    if (!touch || touch->points != P || !P || touch->nblocks != P->nblocks)
        return CSRBF_ERR_INVALID;
    return evaluate_impl(cs, P, out, flags, st, touch);
}

const char *csrbf_simd_path(void)
{
    const eval_isa *isa;
    const int simd = csrbf_isa_pick(&isa);
    return simd == SIMD_AVX512 ? "avx512" : simd == SIMD_AVX2 ? "avx2" : "portable";
}
