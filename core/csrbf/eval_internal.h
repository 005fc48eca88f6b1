/* csrbf_evaluate's internals, shared by its files (not part of the public API):
 *   csrbf_eval.c     the entry points and the plan (what a call does, its scratch, its
 *                    block selection);
 *   csrbf_select.c   the selection: blocks meeting a support through the block tree, a
 *                    block's centres through the centre grid;
 *   csrbf_sched.c    the work split over threads (parts, chunks, stealing) and the kept
 *                    selection's weight cache;
 *   csrbf_fast.c     the fast path (eval_simd.h's kernels, once per instruction set) and
 *                    its runners;
 *   csrbf_general.c  the general path (portable kernels, polynomial, Jacobian);
 *   csrbf_touch.c    csrbf_touch and the bookkeeping of what each call wrote.
 * All are compiled with -O3 -ffp-contract=fast (core/csrbf/CMakeLists.txt). */
#ifndef CSRBF_EVAL_INTERNAL_H
#define CSRBF_EVAL_INTERNAL_H

#include "internal.h"

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define B CSRBF_BLOCK

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__ELF__)
#define CSRBF_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CSRBF_CLONES
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && CSRBF_BLOCK == 16
#include <immintrin.h>
/* the fast path: AVX-512 or AVX2 + FMA kernels (eval_simd.h), picked at run time */
#define CSRBF_SIMD 1
#else
#define CSRBF_SIMD 0
#endif
/* The instruction set a call runs on (csrbf_isa_pick): the tree walk and the kernels follow
 * it. */
enum { SIMD_NONE = 0, SIMD_AVX2 = 1, SIMD_AVX512 = 2 };

/* The per-block kernel of the general path: acc (from -0.0f, so that a vertex outside every
 * support keeps its base bit for bit) += a_j psi(|x - c_j| / R) over the listed centres, cnt
 * += pairs in support; the B vertices are the lanes. */
typedef void (*block_fn)(const float *, const float *, const float *, const uint32_t *, size_t,
                         const float *, const float *, const float *, const float *,
                         const float *, const float *, float, float *, float *, float *, int *);

/* Statistics of a run of blocks (the fast path counts them per block, in registers). */
typedef struct {
    size_t pairs, moved;
    float maxd2;
} block_stats;

/* A kept selection's kernel weights (see eval_simd.h's SIMD_FILL). */
typedef struct {
    const float *w;
    const uint16_t *in;
    const uint32_t *off;
} weight_cache;

/* The base positions of blocks b0..b1-1 into the output (a plain copy: the points keep the
 * vertices as given). */
static inline void copy_base(const csrbf_points *P, float *out, size_t b0, size_t b1)
{
    size_t v0 = b0 * B, v1 = b1 * B < P->n ? b1 * B : P->n;
    if (v1 > v0) memcpy(out + 3 * v0, P->xyz + 3 * v0, (v1 - v0) * 3 * sizeof(float));
}

static inline size_t align64(size_t bytes) { return (bytes + 63) & ~(size_t)63; }

/* First index i in blk[0..k) with blk[i] >= b. */
static inline size_t lower_bound(const uint32_t *blk, size_t k, size_t b)
{
    size_t lo = 0, hi = k;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (blk[mid] < b) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* The fast path's modes (see eval_simd.h's SIMD_DRIVER): every block with every centre; the
 * listed blocks with their centre masks; the listed blocks and the gaps between them. */
enum { DRIVE_ALL = 0, DRIVE_LIST = 1, DRIVE_GAPS = 2 };

typedef void (*drive_fn)(const csrbf_points *, float *, const uint32_t *, const uint64_t *,
                         size_t, size_t, size_t, size_t, size_t, const float *, float,
                         const weight_cache *, block_stats *);
typedef void (*fill_fn)(const csrbf_points *, const uint32_t *, const uint64_t *, size_t,
                        const float *, float, float *, uint16_t *, uint32_t *);

/* The blocks whose box meets a support, found through the block tree (csrbf_points) for all
 * centres at once: a node is opened only for the centres whose support meets its box, so the
 * cost follows the supports (nodes near a support), not the mesh. Output in increasing block
 * order: blk[k], msk[k] (bit j: centre j meets block blk[k]). */
typedef struct block_select {
    const csrbf_points *P;
    const float *cx, *cy, *cz;
    float r2c, inv_r2; /* box test limit; the kernel's 1 / R^2 (AVX-512 refinement) */
    uint32_t *blk;
    uint64_t *msk;
    size_t *cum;     /* k + 1: cum[i] = cost (ITEM_COST) of items 0..i-1, for splitting */
    size_t k, evals; /* blocks listed, sum of their mask bits */
} block_select;

/* The cost of a work item in half vector evaluations (16 vertices x 1 centre): a computed
 * block costs about two evaluations (loads, statistics, the interleaved store) besides one
 * per centre; a block restored to the base, one. A copied gap block (full writes) costs 1. */
#define ITEM_COST(bits) ((bits) ? 4 + 2 * (size_t)(bits) : 2)
/* The prefix cost of the first i items of a cached selection with p pairs among them (a
 * cached pair: three fused multiply-adds and a 64-byte load). */
#define ITEM_COST_CACHED(i, p) (4 * (size_t)(i) + (size_t)(p))

/* The weight cache pays while a frame's data stays in the cores' caches: it trades about 20
 * vector operations per pair for a 66-byte read, which a frame that streams its data from
 * memory (a full write of a large mesh) pays for dearly. So a frame uses it only when the
 * bytes it moves (24 per written vertex: base in, output out; 66 per cached pair) come to at
 * most CSRBF_WCACHE_THREAD_BYTES per thread (the L2 of a core on the machine it was measured
 * on; docs/performance.md has the measurements). */
#ifndef CSRBF_WCACHE_THREAD_BYTES
#define CSRBF_WCACHE_THREAD_BYTES ((size_t)2 << 20)
#endif
#define WCACHE_PAIR_BYTES (B * sizeof(float) + sizeof(uint16_t))

/* Cost (ITEM_COST units, half a vector evaluation) above which an evaluation forks its
 * threads: below it (about 8 us of work on one core of the machine it was tuned on) a
 * fork/join costs more than it saves, and a frame loop's sleeping workers wake slowly. */
#define PARALLEL_COST 6000

/* Chunks a thread's part of a parallel drive is cut into (csrbf_sched_drive), for stealing. */
#define STEAL_CHUNKS 8

/* Parts per thread of a fused walk-and-evaluate (scheduled dynamically: the costs of the
 * parts are not known before their walks). */
#define SPLIT_PARTS 4

/* Vertex-centre lane pairs (estimated, csrbf_sel_support_share) above which a full write
 * whose selection is not kept walks the tree and evaluates in parallel parts. */
#define PARALLEL_LANES 50000
/* The same for a touched call (which writes only the selected blocks, so forks for less). */
#define PARALLEL_LANES_TOUCHED 20000

/* sel_k of a selection seen once and not kept (the next use with the same key keeps it). */
#define SEL_PENDING SIZE_MAX

/* A thread's part of a parallel drive: its chunks [lo, hi) not yet taken, as lo | hi << 32,
 * on a cache line of its own. */
typedef struct {
    _Alignas(64) _Atomic uint64_t span;
} steal_part;

/* The fast path's functions for one instruction set (eval_simd.h defines one per inclusion,
 * csrbf_fast.c includes it once per instruction set). */
typedef struct eval_isa {
    block_fn kern[3];          /* per-block kernels, [ki]: psi31, psi30, psi32 */
    drive_fn drivers[3][2][3]; /* [ki][stats][mode] */
    drive_fn cached[2][2];     /* weight-cache drivers, [stats][mode - DRIVE_LIST] */
    fill_fn fills[3];          /* weight cache fills, [ki] */
    size_t (*refine)(block_select *S);
    void (*write_block)(float *out, const float *x, const float *y, const float *z,
                        const float *accx, const float *accy, const float *accz);
} eval_isa;

/* Persistent-output state of csrbf_evaluate_touched (see csrbf.h); csrbf_touch.c keeps it.
 * Invariants (asserted there): prev holds nprev <= nblocks increasing blocks < nblocks; the
 * ranges lie inside the points' n vertices. */
struct csrbf_touch {
    const csrbf_points *points; /* the points it was made for */
    size_t nblocks;
    uint32_t *prev;             /* blocks the last call computed from the kernel, increasing */
    size_t nprev;
    int full;                   /* the next call writes every block */
    uint64_t sel_id;            /* prev is exactly the solver's kept selection of this id
                                   (0: it is not) */
    int ranges_sel;             /* and the ranges are exactly that selection's */
    uint32_t *ranges;           /* 2 x nranges: first vertex, count */
    size_t nranges;
};

/* One csrbf_evaluate(_touched) call: what it does (made by csrbf_eval.c's plan_make), its
 * scratch (plan_scratch), its block selection (plan_select), and what the runner it goes to
 * (csrbf_run_fast or csrbf_run_general) counted. */
typedef struct eval_plan {
    /* the call */
    csrbf_solver *s;           /* read-only but for the kept selection and the scratch */
    const csrbf_points *P;
    float *out;
    csrbf_eval_stats *st;      /* NULL: no statistics */
    csrbf_touch *touch;        /* NULL: csrbf_evaluate (every block written) */
    size_t n, nb, m;           /* vertices, blocks, centres */
    int nt;                    /* threads */
    int poly, want_jac;
    int full_write;            /* every block is written */
    int all_in;                /* every support holds the whole vertex box */
    int use_tree;              /* blocks and their centre masks from the block tree */
    int fast;                  /* the fast path (eval_simd.h's drivers) */
    int all_in_kept;           /* all in, fast: kept as a selection of every block from the
                                  second use on */
    int fused;                 /* the selection is walked per part inside the threads */
    int own;                   /* scratch of its own (a concurrent caller), not the solver's */
    int ki, simd;              /* kernel index (psi31, psi30, psi32), SIMD_* */
    const eval_isa *isa;       /* NULL: no fast path on this CPU or compiler */
    double R2;
    float inv_r2, r2c;         /* the kernel's 1 / R^2; the box tests' limit */
    block_select S;            /* the selection (use_tree) */
    /* scratch sizes (plan_sizes) */
    size_t per_thread, blk_m, blk_b, blk_c, mrg, nchunks, chunk_b, splits, gen_m, gen_f, gen_t,
        pack, fparts, fmax, fthr, fpart, fsz, need;
    void *mem;                 /* the scratch: the solver's or (own) malloc()ed */
    /* scratch pointers (plan_scratch) */
    float *cpack;              /* fast path: centre j's x, y, z, alpha x, y, z at 8 j */
    size_t *isplit, *bsplit;   /* chunks: items, blocks (nchunks + 1 each) */
    size_t *psplit;            /* parts: items, then blocks (nt + 1 each) */
    steal_part *spans;         /* nt */
    uint64_t *mrg_msk;         /* a touched call's merged work list (nb each) */
    uint32_t *mrg_blk;
    size_t *mrg_cum;
    uint64_t *gen_mask;        /* general path: every block's centre mask (nb) */
    uint8_t *tcur, *tprev;     /* general path with a touch: blocks computed now, at the last call */
    unsigned char *tbase;      /* general path: per_thread bytes a thread (its centre list) */
    unsigned char *fbuf;       /* fused walk: fthr bytes per thread, then fpart */
    unsigned char *fbase;      /* a concurrent caller's own selection */
    /* results */
    size_t pairs, moved;
    double maxd, minjac;       /* squared */
} eval_plan;

/* ---- csrbf_select.c */
/* Every centre's support holds the whole vertex box (no selection needed). */
int csrbf_sel_all_in(const csrbf_solver *s, const csrbf_points *P);
/* Walk the tree for the m centres into S (blk / msk / cum with room for every block; k,
 * evals set); simd: SIMD_AVX512, SIMD_AVX2 or SIMD_NONE (the portable walk). */
void csrbf_sel_blocks(block_select *S, int simd, size_t m);
/* The blocks of [lo, hi) meeting a support of the centres of mask `all`, appended to S
 * (blk, msk; no costs): one part of a fused walk. */
void csrbf_sel_range(block_select *S, int simd, uint64_t all, size_t lo, size_t hi);
/* Centres whose support meets block b through the centre grid; returns their count (any:
 * stop at the first). */
size_t csrbf_sel_centres(const csrbf_solver *s, const csrbf_points *P, size_t b,
                         uint32_t *list, int any);
/* The summed share of the vertex box that the centres' support cubes cover, axis by axis: n
 * times it estimates the vertex-centre pairs to test before any selection. O(m). */
double csrbf_sel_support_share(const csrbf_solver *s, const csrbf_points *P);

/* ---- csrbf_sched.c */
/* The items [0, ni) of a fast-path work list (ib, im, prefix costs ic; ib NULL: every block,
 * DRIVE_ALL) through drive, with the gaps copied (gaps: a full write of nb blocks): on the
 * calling thread below PARALLEL_COST, else split over the plan's threads with stealing.
 * cost: ic[ni] (or the blocks' cost). Statistics into *bs. */
void csrbf_sched_drive(const eval_plan *p, drive_fn drive, const uint32_t *ib,
                       const uint64_t *im, const size_t *ic, size_t ni, int gaps, size_t cost,
                       const weight_cache *wc, block_stats *bs);
/* The kept selection's weight cache for this call's items (ib: the work list; the cache only
 * when they are the kept selection S.blk itself and its bytes stay within the threads'
 * share), filled at its first use after the selection is refined: *wcv filled and returned,
 * *ic its prefix costs; NULL when the kernels compute the weights. */
const weight_cache *csrbf_wcache_for(eval_plan *p, const uint32_t *ib, weight_cache *wcv,
                                     const size_t **ic);

/* ---- csrbf_fast.c */
/* The instruction set of the fast path (*isa; NULL: none) and its SIMD_* level. */
int csrbf_isa_pick(const eval_isa **isa);
/* The fast path: fused walks (p->fused) or the selected work list. */
void csrbf_run_fast(eval_plan *p);

/* ---- csrbf_general.c */
/* The general path: every block, its centres from the tree masks, all of them (all in), or
 * the centre grid (many centres); polynomial and Jacobian. */
void csrbf_run_general(eval_plan *p);

/* ---- csrbf_touch.c */
/* A touched call's work list: the selection (blocks sb, masks sm, k of them, increasing)
 * merged with the last call's blocks pv (np, increasing; those not selected now get mask 0:
 * restored to the base) into ob, om; returns the items. csrbf_touch_merge_cost also makes
 * their prefix costs ocum (k + 1) from the selection's scum. */
size_t csrbf_touch_merge(const uint32_t *sb, const uint64_t *sm, size_t k, const uint32_t *pv,
                         size_t np, uint32_t *ob, uint64_t *om);
size_t csrbf_touch_merge_cost(const uint32_t *sb, const uint64_t *sm, const size_t *scum,
                              size_t k, const uint32_t *pv, size_t np, uint32_t *ob,
                              uint64_t *om, size_t *ocum);
/* After a fused call: the parts' selected blocks (psel + q fmax, nsel[q] of them) become the
 * last call's, the written ones (pwr + q fmax, nwr[q]) the ranges (every vertex on a full
 * write). pwr is compacted in place. */
void csrbf_touch_after_parts(csrbf_touch *t, int full_write, const uint32_t *psel,
                             const size_t *nsel, uint32_t *pwr, const size_t *nwr,
                             size_t fparts, size_t fmax);
/* After a listed fast call: all in without the tree (every block computed), or the selection
 * sel (k blocks; kept selection of id sel_id, 0: none) with the written items ib[0 .. ni)
 * (same: they are the last call's exactly, nothing restored). */
void csrbf_touch_after_listed(csrbf_touch *t, int use_tree, int full_write, int same,
                              const uint32_t *ib, size_t ni, const uint32_t *sel, size_t k,
                              uint64_t sel_id);
/* The general path's flags: tprev[b] for the blocks the last call computed (all on a full
 * write); after it, the blocks computed (tcur) become the last call's and those written
 * (tcur or tprev) the ranges. */
void csrbf_touch_mark_prev(const csrbf_touch *t, uint8_t *tprev, int full_write);
void csrbf_touch_after_general(csrbf_touch *t, const uint8_t *tcur, const uint8_t *tprev);

#endif
