/* csrbf_evaluate: T(x) at every vertex. Blocks of CSRBF_BLOCK consecutive vertices are
 * matched against the centres whose support meets the block's box, found through the points'
 * block tree for all centres at once (64-bit masks, kept in the solver while the centres and
 * the points stay) or, beyond 64 centres, the centre grid; within a block the loop runs over
 * the selected centres and vectorises over the vertices (eval_simd.h: AVX-512, else AVX2 +
 * FMA, picked at run time by isa_pick; else the general path's SIMD clones). Blocks run in parallel with OpenMP,
 * one contiguous part of equal cost per thread. csrbf_evaluate_touched writes only the blocks
 * in a support now or at its last call. */
#include "internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__ELF__)
#define CSRBF_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CSRBF_CLONES
#endif

#define B CSRBF_BLOCK

/* The block kernel over one block of B vertices: acc (initialised to -0.0f so that a vertex
 * outside every support keeps its base bit for bit) += a_j psi(|x - c_j| / R) over the listed
 * centres; cnt += pairs in support. The centre loop is outside, the B vertices are the SIMD
 * lanes. r = sqrt(r2): vsqrtps under -fno-math-errno. */
#define DEFINE_BLOCK_KERNEL(NAME, PSI)                                                         \
    CSRBF_CLONES static void NAME(const float *restrict x, const float *restrict y,           \
                                  const float *restrict z, const uint32_t *restrict list,     \
                                  size_t k, const float *restrict cx,                         \
                                  const float *restrict cy, const float *restrict cz,         \
                                  const float *restrict ax, const float *restrict ay,         \
                                  const float *restrict az, float inv_r2,                     \
                                  float *restrict accx, float *restrict accy,                 \
                                  float *restrict accz, int *restrict cnt)                    \
    {                                                                                          \
        float sx[B], sy[B], sz[B];                                                             \
        int sc[B];                                                                             \
        for (int v = 0; v < B; v++) {                                                          \
            sx[v] = sy[v] = sz[v] = -0.0f;                                                     \
            sc[v] = 0;                                                                         \
        }                                                                                      \
        for (size_t t = 0; t < k; t++) {                                                       \
            const uint32_t j = list[t];                                                        \
            const float px = cx[j], py = cy[j], pz = cz[j];                                    \
            const float qx = ax[j], qy = ay[j], qz = az[j];                                    \
            _Pragma("omp simd") for (int v = 0; v < B; v++)                                    \
            {                                                                                  \
                float dx = x[v] - px, dy = y[v] - py, dz = z[v] - pz;                          \
                float r2 = (dx * dx + dy * dy + dz * dz) * inv_r2;                             \
                float r = sqrtf(r2 < 1.0f ? r2 : 1.0f);                                        \
                float t1 = 1.0f - r;                                                           \
                float w = PSI;                                                                 \
                int in = r2 < 1.0f;                                                            \
                sx[v] = in ? sx[v] + qx * w : sx[v];                                           \
                sy[v] = in ? sy[v] + qy * w : sy[v];                                           \
                sz[v] = in ? sz[v] + qz * w : sz[v];                                           \
                sc[v] += in;                                                                   \
            }                                                                                  \
        }                                                                                      \
        for (int v = 0; v < B; v++) {                                                          \
            accx[v] = sx[v];                                                                   \
            accy[v] = sy[v];                                                                   \
            accz[v] = sz[v];                                                                   \
            cnt[v] = sc[v];                                                                    \
        }                                                                                      \
    }

DEFINE_BLOCK_KERNEL(block_psi31, (t1 * t1) * (t1 * t1) * (4.0f * r + 1.0f))
DEFINE_BLOCK_KERNEL(block_psi30, t1 * t1)
DEFINE_BLOCK_KERNEL(block_psi32,
                    ((t1 * t1) * (t1 * t1) * (t1 * t1)) * ((35.0f / 3.0f) * r2 + 6.0f * r + 1.0f))

typedef void (*block_fn)(const float *, const float *, const float *, const uint32_t *, size_t,
                         const float *, const float *, const float *, const float *,
                         const float *, const float *, float, float *, float *, float *, int *);

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && CSRBF_BLOCK == 16
#include <immintrin.h>
/* the fast path: AVX-512 or AVX2 + FMA kernels (eval_simd.h), picked at run time */
#define CSRBF_SIMD 1
#else
#define CSRBF_SIMD 0
#endif
/* The instruction set a call runs on (isa_pick): the tree walk and the kernels follow it. */
enum { SIMD_NONE = 0, SIMD_AVX2 = 1, SIMD_AVX512 = 2 };

#if CSRBF_SIMD
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

/* The fast path's modes (see eval_simd.h's SIMD_DRIVER): every block with every centre; the
 * listed blocks with their centre masks; the listed blocks and the gaps between them. */
enum { DRIVE_ALL = 0, DRIVE_LIST = 1, DRIVE_GAPS = 2 };

typedef void (*drive_fn)(const csrbf_points *, float *, const uint32_t *, const uint64_t *,
                         size_t, size_t, size_t, size_t, size_t, const float *, float,
                         const weight_cache *, block_stats *);
typedef void (*fill_fn)(const csrbf_points *, const uint32_t *, const uint64_t *, size_t,
                        const float *, float, float *, uint16_t *, uint32_t *);
#endif

/* out[3v + a] = base + acc (+ p(x)) for the nv <= B vertices of a block: contiguous stores. */
CSRBF_CLONES static void write_block(float *restrict out, const float *restrict x,
                                     const float *restrict y, const float *restrict z,
                                     const float *restrict accx, const float *restrict accy,
                                     const float *restrict accz, size_t nv)
{
    if (nv == B) {
#pragma omp simd
        for (int v = 0; v < B; v++) {
            out[3 * v] = x[v] + accx[v];
            out[3 * v + 1] = y[v] + accy[v];
            out[3 * v + 2] = z[v] + accz[v];
        }
    } else {
        for (size_t v = 0; v < nv; v++) {
            out[3 * v] = x[v] + accx[v];
            out[3 * v + 1] = y[v] + accy[v];
            out[3 * v + 2] = z[v] + accz[v];
        }
    }
}

/* Portable group_masks_avx512 (same operations, same decisions): cm[l] gets bit j where
 * centre j of mask meets box first + l. Returns the lanes with a centre. */
CSRBF_CLONES static unsigned group_masks_c(const float *const lo[3], const float *const hi[3],
                                           size_t first, uint64_t mask, const float *cx,
                                           const float *cy, const float *cz, float r2c,
                                           uint64_t cm[CSRBF_FAN])
{
    float d2[CSRBF_FAN];
    for (int l = 0; l < CSRBF_FAN; l++) cm[l] = 0;
    while (mask) {
        const unsigned j = (unsigned)__builtin_ctzll(mask);
        mask &= mask - 1;
        const float px = cx[j], py = cy[j], pz = cz[j];
#pragma omp simd
        for (int l = 0; l < CSRBF_FAN; l++) {
            const size_t b = first + (size_t)l;
            float ex = lo[0][b] - px > px - hi[0][b] ? lo[0][b] - px : px - hi[0][b];
            float ey = lo[1][b] - py > py - hi[1][b] ? lo[1][b] - py : py - hi[1][b];
            float ez = lo[2][b] - pz > pz - hi[2][b] ? lo[2][b] - pz : pz - hi[2][b];
            ex = ex > 0.0f ? ex : 0.0f;
            ey = ey > 0.0f ? ey : 0.0f;
            ez = ez > 0.0f ? ez : 0.0f;
            d2[l] = ex * ex + ey * ey + ez * ez;
        }
        for (int l = 0; l < CSRBF_FAN; l++) cm[l] |= d2[l] < r2c ? 1ull << j : 0ull;
    }
    unsigned any = 0;
    for (int l = 0; l < CSRBF_FAN; l++) any |= (unsigned)(cm[l] != 0) << l;
    return any;
}

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
 * most CSRBF_WCACHE_THREAD_BYTES per thread (measured on a 2-core machine with 2 MiB of L2 per
 * core: 33,025 vertices, 0.8-2.1 MB, 1.5-2.7x faster; 100,000 vertices, 2.5-2.9 MB on one
 * thread, 10-25% slower; 1M vertices, 6-20% slower). */
#ifndef CSRBF_WCACHE_THREAD_BYTES
#define CSRBF_WCACHE_THREAD_BYTES ((size_t)2 << 20)
#endif
#define WCACHE_PAIR_BYTES (B * sizeof(float) + sizeof(uint16_t))

/* The children of node group `first` of `level` (nodes first .. first + 15) that hold blocks
 * of [lo, hi): bit l for node first + l (0: none). */
static inline unsigned walk_range(int level, size_t first, size_t lo, size_t hi)
{
    _Static_assert(CSRBF_FAN == 16, "node n of level l holds blocks n 16^l .. (n+1) 16^l - 1");
    const unsigned sh = 4u * (unsigned)level;
    const size_t n0 = lo >> sh, n1 = ((hi - 1) >> sh) + 1; /* nodes n0..n1-1 hold [lo, hi) */
    if (n1 <= first || n0 >= first + CSRBF_FAN) return 0;
    const size_t l0 = n0 > first ? n0 - first : 0,
                 l1 = n1 - first < CSRBF_FAN ? n1 - first : CSRBF_FAN;
    return ((1u << l1) - 1u) & ~((1u << l0) - 1u);
}

/* The blocks of [lo, hi) whose box meets a support of mask, from node group first of level
 * down: NAME walks with GROUP_MASKS (a group_masks_*: cm[l], bit j for centre j of mask
 * meeting child l; returns the children with a centre) under ATTR. select_visit_c (portable)
 * and select_visit_avx2; select_visit_avx512 is the same walk with compress stores. */
#define DEFINE_SELECT_VISIT(NAME, ATTR, GROUP_MASKS)                                           \
    ATTR static void NAME(block_select *S, int level, size_t first, uint64_t mask, size_t lo,  \
                          size_t hi)                                                           \
    {                                                                                          \
        const unsigned range = walk_range(level, first, lo, hi);                               \
        if (!range) return;                                                                    \
        const csrbf_points *P = S->P;                                                          \
        uint64_t cm[CSRBF_FAN];                                                                \
        unsigned any = GROUP_MASKS((const float *const *)P->tlo[level],                        \
                                   (const float *const *)P->thi[level], first, mask, S->cx,    \
                                   S->cy, S->cz, S->r2c, cm) &                                 \
                       range;                                                                  \
        for (; any; any &= any - 1) {                                                          \
            const unsigned l = (unsigned)__builtin_ctz(any);                                   \
            if (level == 0) {                                                                  \
                S->blk[S->k] = (uint32_t)(first + l);                                          \
                S->msk[S->k++] = cm[l];                                                        \
            } else {                                                                           \
                NAME(S, level - 1, (first + l) * CSRBF_FAN, cm[l], lo, hi);                    \
            }                                                                                  \
        }                                                                                      \
    }

DEFINE_SELECT_VISIT(select_visit_c, , group_masks_c)

/* The selection's prefix costs: cum[i] = the cost of items 0..i-1 (cum[k]: all), the pairs
 * returned. */
static inline __attribute__((always_inline)) size_t count_bits(const uint64_t *msk, size_t k,
                                                              size_t *cum)
{
    size_t e = 0, c = 0;
    for (size_t i = 0; i < k; i++) {
        size_t bits = (size_t)__builtin_popcountll(msk[i]);
        cum[i] = c;
        c += ITEM_COST(bits);
        e += bits;
    }
    cum[k] = c;
    return e;
}

#if CSRBF_SIMD
/* The fast path's functions for one instruction set (eval_simd.h defines one per inclusion). */
typedef struct eval_isa {
    block_fn kern[3];          /* per-block kernels, [ki]: psi31, psi30, psi32 */
    drive_fn drivers[3][2][3]; /* [ki][stats][mode] */
    drive_fn cached[2][2];     /* weight-cache drivers, [stats][mode - DRIVE_LIST] */
    fill_fn fills[3];          /* weight cache fills, [ki] */
    size_t (*refine)(block_select *S);
    void (*write_block)(float *out, const float *x, const float *y, const float *z,
                        const float *accx, const float *accy, const float *accz);
} eval_isa;

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

/* The centres of mask (bit j: centre j) whose support meets each of the CSRBF_FAN boxes
 * lo/hi[first ..]: lane l of (c0, c1) gets bit j. Float, with the conservative margin r2c;
 * the same operations as the kernel's distance (per-axis gaps to the box never exceed a
 * vertex's, and the squares and sums round monotonically), so a block holding a vertex in a
 * support always meets it. Returns the lanes with a centre. */
static inline __attribute__((target("avx512f,fma"), always_inline)) __mmask16
group_masks_avx512(const float *const lo[3], const float *const hi[3], size_t first,
                   uint64_t mask, const float *cx, const float *cy, const float *cz, float r2c,
                   __m512i *c0out, __m512i *c1out)
{
    const __m512 lx = _mm512_loadu_ps(lo[0] + first), ly = _mm512_loadu_ps(lo[1] + first),
                 lz = _mm512_loadu_ps(lo[2] + first), hx = _mm512_loadu_ps(hi[0] + first),
                 hy = _mm512_loadu_ps(hi[1] + first), hz = _mm512_loadu_ps(hi[2] + first),
                 zero = _mm512_setzero_ps(), lim = _mm512_set1_ps(r2c);
    __m512i c0 = _mm512_setzero_si512(), c1 = c0;
    __mmask16 any = 0;
    while (mask) {
        const unsigned j = (unsigned)__builtin_ctzll(mask);
        mask &= mask - 1;
        const __m512 px = _mm512_set1_ps(cx[j]), py = _mm512_set1_ps(cy[j]),
                     pz = _mm512_set1_ps(cz[j]);
        __m512 ex = _mm512_max_ps(_mm512_max_ps(_mm512_sub_ps(lx, px), _mm512_sub_ps(px, hx)), zero);
        __m512 ey = _mm512_max_ps(_mm512_max_ps(_mm512_sub_ps(ly, py), _mm512_sub_ps(py, hy)), zero);
        __m512 ez = _mm512_max_ps(_mm512_max_ps(_mm512_sub_ps(lz, pz), _mm512_sub_ps(pz, hz)), zero);
        __m512 d2 = _mm512_mul_ps(ex, ex);
        d2 = _mm512_fmadd_ps(ey, ey, d2);
        d2 = _mm512_fmadd_ps(ez, ez, d2);
        const __mmask16 t = _mm512_cmp_ps_mask(d2, lim, _CMP_LT_OQ);
        const __m512i bit = _mm512_set1_epi64((long long)(1ull << j));
        c0 = _mm512_mask_or_epi64(c0, (__mmask8)t, c0, bit);
        c1 = _mm512_mask_or_epi64(c1, (__mmask8)(t >> 8), c1, bit);
        any |= t;
    }
    *c0out = c0;
    *c1out = c1;
    return any;
}

/* select_visit_c with AVX-512, restricted to the blocks [lo, hi): the leaves' masks and
 * block numbers compress-stored. */
__attribute__((target("avx512f,fma,popcnt"))) static void
select_visit_avx512(block_select *S, int level, size_t first, uint64_t mask, size_t lo,
                    size_t hi)
{
    const csrbf_points *P = S->P;
    const __mmask16 range = (__mmask16)walk_range(level, first, lo, hi);
    if (!range) return;
    __m512i c0, c1;
    __mmask16 any = group_masks_avx512((const float *const *)P->tlo[level],
                                       (const float *const *)P->thi[level], first, mask, S->cx,
                                       S->cy, S->cz, S->r2c, &c0, &c1) & range;
    if (!any) return;
    if (level == 0) {
        size_t k = S->k;
        const __mmask8 a0 = (__mmask8)any, a1 = (__mmask8)(any >> 8);
        _mm512_mask_compressstoreu_epi64(S->msk + k, a0, c0);
        _mm512_mask_compressstoreu_epi64(S->msk + k + __builtin_popcount(a0), a1, c1);
        const __m512i idx = _mm512_add_epi32(
            _mm512_set1_epi32((int)first),
            _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0));
        _mm512_mask_compressstoreu_epi32(S->blk + k, any, idx);
        S->k = k + (size_t)__builtin_popcount(any);
        return;
    }
    _Alignas(64) uint64_t cm[CSRBF_FAN];
    _mm512_store_si512(cm, c0);
    _mm512_store_si512(cm + 8, c1);
    for (unsigned a = any; a; a &= a - 1) {
        const unsigned l = (unsigned)__builtin_ctz(a);
        select_visit_avx512(S, level - 1, (first + l) * CSRBF_FAN, cm[l], lo, hi);
    }
}

/* group_masks_c with AVX2 (the 16 boxes as two halves of 8; the same operations as
 * group_masks_avx512: max, max, mul, fmadd, fmadd, compare, so the same decisions): cm[l] gets
 * bit j where centre j of mask meets box first + l. Returns the lanes with a centre. */
static inline __attribute__((target("avx2,fma"), always_inline)) unsigned
group_masks_avx2(const float *const lo[3], const float *const hi[3], size_t first, uint64_t mask,
                 const float *cx, const float *cy, const float *cz, float r2c,
                 uint64_t cm[CSRBF_FAN])
{
    const __m256 zero = _mm256_setzero_ps(), lim = _mm256_set1_ps(r2c);
    unsigned any = 0;
    for (int h = 0; h < 2; h++) { /* lanes 8h .. 8h + 7 */
        const size_t f = first + 8 * (size_t)h;
        const __m256 lx = _mm256_loadu_ps(lo[0] + f), ly = _mm256_loadu_ps(lo[1] + f),
                     lz = _mm256_loadu_ps(lo[2] + f), hx = _mm256_loadu_ps(hi[0] + f),
                     hy = _mm256_loadu_ps(hi[1] + f), hz = _mm256_loadu_ps(hi[2] + f);
        __m256i c0 = _mm256_setzero_si256(), c1 = c0; /* lanes 8h .. 8h + 3, 8h + 4 .. 8h + 7 */
        for (uint64_t mk = mask; mk; mk &= mk - 1) {
            const unsigned j = (unsigned)__builtin_ctzll(mk);
            const __m256 px = _mm256_set1_ps(cx[j]), py = _mm256_set1_ps(cy[j]),
                         pz = _mm256_set1_ps(cz[j]);
            __m256 ex = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lx, px), _mm256_sub_ps(px, hx)), zero);
            __m256 ey = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(ly, py), _mm256_sub_ps(py, hy)), zero);
            __m256 ez = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lz, pz), _mm256_sub_ps(pz, hz)), zero);
            __m256 d2 = _mm256_mul_ps(ex, ex);
            d2 = _mm256_fmadd_ps(ey, ey, d2);
            d2 = _mm256_fmadd_ps(ez, ez, d2);
            const __m256 t = _mm256_cmp_ps(d2, lim, _CMP_LT_OQ);
            const __m256i ti = _mm256_castps_si256(t), bit = _mm256_set1_epi64x((long long)(1ull << j));
            /* the 8 32-bit lane masks widened to 64 bits, four at a time */
            c0 = _mm256_or_si256(c0, _mm256_and_si256(_mm256_cvtepi32_epi64(_mm256_castsi256_si128(ti)), bit));
            c1 = _mm256_or_si256(c1, _mm256_and_si256(_mm256_cvtepi32_epi64(_mm256_extracti128_si256(ti, 1)), bit));
            any |= (unsigned)_mm256_movemask_ps(t) << (8 * h);
        }
        _mm256_storeu_si256((__m256i *)(cm + 8 * h), c0);
        _mm256_storeu_si256((__m256i *)(cm + 8 * h + 4), c1);
    }
    return any;
}

DEFINE_SELECT_VISIT(select_visit_avx2, __attribute__((target("avx2,fma,popcnt"))), group_masks_avx2)

/* count_bits with the popcnt instruction (count_bits inlined under this target) */
__attribute__((target("popcnt"))) static size_t count_bits_popcnt(const uint64_t *msk, size_t k,
                                                                   size_t *cum)
{
    return count_bits(msk, k, cum);
}

/* The instruction set of the fast path: AVX-512 where the CPU has it, else AVX2 with FMA,
 * else none (the portable general path). The environment variable CSRBF_ISA=avx2 or =none
 * asks for less than the CPU has (tests run every path on one machine). */
static const eval_isa *isa_pick(void)
{
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
        if (want && !strcmp(want, "none")) use = 0;
        atomic_store(&picked, use == 2 ? &isa_avx512 : use == 1 ? &isa_avx2 : NULL);
        atomic_store(&known, 1);
    }
    return atomic_load(&picked);
}
#endif

/* Walk the tree for the solver's centres into S (blk / msk with room for every block); simd:
 * SIMD_AVX512, SIMD_AVX2 or 0 (the portable walk). */
static void select_blocks(block_select *S, int simd, size_t m)
{
    const uint64_t all = m >= 64 ? ~0ull : (1ull << m) - 1;
    S->k = 0;
#if CSRBF_SIMD
    if (simd) {
        if (simd == SIMD_AVX512) select_visit_avx512(S, S->P->tlevels - 1, 0, all, 0, S->P->nblocks);
        else select_visit_avx2(S, S->P->tlevels - 1, 0, all, 0, S->P->nblocks);
        S->evals = count_bits_popcnt(S->msk, S->k, S->cum);
        return;
    }
#endif
    (void)simd;
    select_visit_c(S, S->P->tlevels - 1, 0, all, 0, S->P->nblocks);
    S->evals = count_bits(S->msk, S->k, S->cum);
}

/* Does the support of centre c (radius R) meet the box [lo, hi]? Conservative by a hair. */
static inline int meets(const double c[3], const float lo[3], const float hi[3], double R2)
{
    double d2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double e = c[a] < lo[a] ? lo[a] - c[a] : c[a] > hi[a] ? c[a] - hi[a] : 0.0;
        d2 += e * e;
    }
    return d2 < R2 * (1.0 + 1e-6);
}

/* Centres whose support meets block b; returns their count (list may be NULL: count only
 * until the first hit). */
static size_t select_centres(const csrbf_solver *s, const csrbf_points *P, size_t b,
                             uint32_t *list, int any)
{
    float lo[3] = {P->lo[0][b], P->lo[1][b], P->lo[2][b]};
    float hi[3] = {P->hi[0][b], P->hi[1][b], P->hi[2][b]};
    double R2 = s->R * s->R;
    size_t k = 0, m = s->m;
    const csrbf_grid *g = &s->cgrid;
    int64_t c0[3], c1[3];
    double cells = 1.0;
    for (int a = 0; a < 3; a++) {
        c0[a] = csrbf_grid_coord(g, lo[a] - s->R, a);
        c1[a] = csrbf_grid_coord(g, hi[a] + s->R, a);
        cells *= (double)(c1[a] - c0[a] + 1);
    }
    if (!g->tsize || cells > (double)m) { /* (no table: a grid of few centres) */
        for (size_t i = 0; i < m; i++)
            if (meets(s->c + 3 * i, lo, hi, R2)) {
                if (any) return 1;
                list[k++] = (uint32_t)i;
            }
        return k;
    }
    for (int64_t z = c0[2]; z <= c1[2]; z++)
        for (int64_t y = c0[1]; y <= c1[1]; y++)
            for (int64_t x = c0[0]; x <= c1[0]; x++) {
                size_t bk = csrbf_grid_bucket(g, x, y, z);
                for (size_t t = g->start[bk]; t < g->start[bk + 1]; t++) {
                    uint32_t i = g->items[t];
                    if (g->cell[3 * i] != x || g->cell[3 * i + 1] != y || g->cell[3 * i + 2] != z)
                        continue;
                    if (meets(s->c + 3 * (size_t)i, lo, hi, R2)) {
                        if (any) return 1;
                        list[k++] = i;
                    }
                }
            }
    return k;
}

static size_t align64(size_t bytes) { return (bytes + 63) & ~(size_t)63; }

/* Jacobian determinant of T at x (double), over the listed centres. */
static double jacobian_det(const csrbf_solver *s, const double x[3], const uint32_t *list,
                           size_t k)
{
    double J[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double R2 = s->R * s->R, inv_r2 = 1.0 / R2;
    for (size_t t = 0; t < k; t++) {
        const double *c = s->c + 3 * (size_t)list[t];
        double d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
        double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (r2 >= R2) continue;
        double q = csrbf_dpsi_over_r(s->opt.kernel, sqrt(r2) * s->inv_R) * inv_r2;
        const double *al = s->alpha + 3 * (size_t)list[t];
        for (int a = 0; a < 3; a++)
            for (int bb = 0; bb < 3; bb++) J[a * 3 + bb] += al[a] * q * d[bb];
    }
    if (s->k > 0)
        for (int a = 0; a < 3; a++)
            for (int l = 0; l < 3; l++) J[a * 3 + l] += s->g[l + 1][a] * s->inv_R;
    return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) +
           J[2] * (J[3] * J[7] - J[4] * J[6]);
}

const char *csrbf_simd_path(void)
{
#if CSRBF_SIMD
    const eval_isa *isa = isa_pick();
    return isa == &isa_avx512 ? "avx512" : isa ? "avx2" : "portable";
#else
    return "portable";
#endif
}

/* Persistent-output state of csrbf_evaluate_touched (see csrbf.h). */
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

static int evaluate_impl(const csrbf_solver *cs, const csrbf_points *P, float *out,
                         unsigned flags, csrbf_eval_stats *st, csrbf_touch *touch);

int csrbf_evaluate(const csrbf_solver *cs, const csrbf_points *P, float *out, unsigned flags,
                   csrbf_eval_stats *st)
{
    return evaluate_impl(cs, P, out, flags, st, NULL);
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
}

int csrbf_evaluate_touched(const csrbf_solver *cs, const csrbf_points *P, csrbf_touch *touch,
                           float *out, unsigned flags, csrbf_eval_stats *st)
{
    if (!touch || touch->points != P || !P || touch->nblocks != P->nblocks)
        return CSRBF_ERR_INVALID;
    return evaluate_impl(cs, P, out, flags, st, touch);
}

/* The summed share of the vertex box that the centres' support cubes cover, axis by axis: n
 * times it estimates the vertex-centre pairs to test before any selection. O(m). */
static double support_share(const csrbf_solver *s, const csrbf_points *P)
{
    double est = 0.0;
    for (size_t i = 0; i < s->m; i++) {
        double frac = 1.0;
        for (int a = 0; a < 3; a++) {
            double ext = P->bhi[a] - P->blo[a], c = s->c[3 * i + a];
            if (ext <= 0.0) continue;
            double ov = fmin(c + s->R, P->bhi[a]) - fmax(c - s->R, P->blo[a]);
            frac *= ov > 0.0 ? ov / ext : 0.0;
        }
        est += frac;
    }
    return est;
}

/* Cost (ITEM_COST units, half a vector evaluation) above which an evaluation forks its
 * threads: below it (about 8 us of work on one core) a fork/join costs more than it saves,
 * and a frame loop's sleeping workers wake slowly. */
#define PARALLEL_COST 6000

/* Chunks a thread's part of a parallel drive is cut into (chunk_work), for steal_take. */
#define STEAL_CHUNKS 8

/* A thread's part of a parallel drive: its chunks [lo, hi) not yet taken, as lo | hi << 32,
 * on a cache line of its own. */
typedef struct {
    _Alignas(64) _Atomic uint64_t span;
} steal_part;

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

/* Parts per thread of a fused walk-and-evaluate (scheduled dynamically: the costs of the
 * parts are not known before their walks). */
#define SPLIT_PARTS 4

/* Vertex-centre lane pairs (estimated, support_share) above which a full write whose
 * selection is not kept walks the tree and evaluates in parallel parts. */
#define PARALLEL_LANES 50000
/* The same for a touched call (which writes only the selected blocks, so forks for less). */
#define PARALLEL_LANES_TOUCHED 20000

/* sel_k of a selection seen once and not kept (the next use with the same key keeps it). */
#define SEL_PENDING SIZE_MAX

#if CSRBF_SIMD /* helpers of the fused path */
/* touch->ranges from k increasing blocks: runs of consecutive blocks as vertex ranges. */
static void ranges_of_blocks(csrbf_touch *t, size_t n, const uint32_t *blk, size_t k)
{
    t->nranges = csrbf_block_ranges(blk, k, n, t->ranges);
}

static void ranges_all(csrbf_touch *t, size_t n)
{
    t->ranges[0] = 0;
    t->ranges[1] = (uint32_t)n;
    t->nranges = 1;
}

/* First index i in blk[0..k) with blk[i] >= b. */
static size_t lower_bound(const uint32_t *blk, size_t k, size_t b)
{
    size_t lo = 0, hi = k;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (blk[mid] < b) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* A touched call's work list: the selection (blocks sb, masks sm, k of them, increasing)
 * merged with the last call's blocks pv (np, increasing; those not selected now get mask 0:
 * restored to the base) into ob, om; with cum, the prefix costs too (scum: the selection's,
 * into ocum, k + 1 of them). Returns the items. */
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

/* The touch's last-call list becomes blk[0..k) (copied, unless it is the list itself). */
static void touch_set_prev(csrbf_touch *t, const uint32_t *blk, size_t k)
{
    if (blk != t->prev) memcpy(t->prev, blk, k * sizeof *blk);
    t->nprev = k;
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
#endif

static int evaluate_impl(const csrbf_solver *cs, const csrbf_points *P, float *out,
                         unsigned flags, csrbf_eval_stats *st, csrbf_touch *touch)
{
    if (!cs || !P || !out || (flags & ~(unsigned)CSRBF_EVAL_JACOBIAN)) return CSRBF_ERR_INVALID;
    if (!cs->have_start) return CSRBF_ERR_STATE;
    /* The scratch buffer is the only state evaluate touches; a concurrent caller that finds it
     * busy allocates its own. The solver itself is read-only here. */
    csrbf_solver *s = (csrbf_solver *)cs;
    const size_t n = P->n, nb = P->nblocks, m = s->m;
    const int poly = s->k > 0, want_jac = st && (flags & CSRBF_EVAL_JACOBIAN);
    const int full_write = !touch || touch->full; /* every block is written */
    int nt = s->opt.threads > 0 ? s->opt.threads : omp_get_max_threads();
    if (nt < 1) nt = 1;

    /* every centre's support holds the whole vertex box: no selection needed */
    int all_in = 1;
    double R2 = s->R * s->R;
    for (size_t i = 0; i < m && all_in; i++) {
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double c = s->c[3 * i + a];
            double e = fmax(fabs(c - P->blo[a]), fabs(c - P->bhi[a]));
            d2 += e * e;
        }
        all_in = d2 < R2 * (1.0 - 1e-6);
    }
    /* up to CSRBF_FAST_MAX_CENTRES centres: blocks and their centre masks from the block
     * tree; beyond, the centre grid per block (general path) */
    const int tree_ok = m <= CSRBF_FAST_MAX_CENTRES;
    int use_tree = !all_in && tree_ok; /* (all in: may change below, at a second use) */
    block_fn kern = s->opt.kernel == CSRBF_PSI30   ? block_psi30
                    : s->opt.kernel == CSRBF_PSI32 ? block_psi32
                                                   : block_psi31;
    const int ki = s->opt.kernel == CSRBF_PSI30 ? 1 : s->opt.kernel == CSRBF_PSI32 ? 2 : 0;
    int simd = SIMD_NONE;
#if CSRBF_SIMD
    const eval_isa *isa = isa_pick();
    simd = isa == &isa_avx512 ? SIMD_AVX512 : isa ? SIMD_AVX2 : SIMD_NONE;
    if (isa) kern = isa->kern[ki];
#else
    const void *isa = NULL;
    (void)ki;
#endif
    /* the fused AVX-512 path: no polynomial, no Jacobian, all centres or tree masks
     * (statistics are counted inside it) */
    const int fast = isa && !want_jac && !poly && (all_in || use_tree);
    /* all in, fast: at the second use of these centres and points (an anchored frame) the
     * tree's way, for the kept selection (every block, every centre) and its weight cache,
     * where that cache will be used (its bytes within the threads' share, as below); else
     * the tree's masks only cost (the 1M scale case: 4.25-4.43 ms against 3.25-3.83) */
    const size_t all_evals = nb * m, all_cost = ITEM_COST_CACHED(nb, all_evals);
    const size_t all_bytes = 24 * nb * B + WCACHE_PAIR_BYTES * all_evals;
    const int all_in_kept = all_in && tree_ok && fast &&
                            all_bytes <= (all_cost <= PARALLEL_COST ? 1 : (size_t)nt) *
                                             CSRBF_WCACHE_THREAD_BYTES;

    /* scratch: the merged work list of a touched call, and for the general path dense masks,
     * block flags and a centre list per thread; a concurrent caller (without the solver's
     * scratch) also holds its own block selection */
    size_t per_thread = align64(m * sizeof(uint32_t));
    size_t blk_m = align64(nb * sizeof(uint64_t)), blk_b = align64(nb * sizeof(uint32_t));
    size_t blk_c = align64((nb + 1) * sizeof(size_t));
    size_t mrg = fast && (use_tree || all_in_kept) && !full_write ? blk_m + blk_b + blk_c : 0;
    const size_t nchunks = (size_t)nt * STEAL_CHUNKS,
                 chunk_b = align64(2 * (nchunks + (size_t)nt + 2) * sizeof(size_t));
    size_t splits = fast ? chunk_b + (size_t)nt * sizeof(steal_part) : 0;
    size_t gen_m = !fast && use_tree ? blk_m : 0;
    size_t gen_f = !fast && touch ? align64(2 * nb) : 0;
    size_t gen_t = !fast ? (size_t)nt * per_thread : 0;
    size_t pack = fast ? align64(m * 8 * sizeof(float)) : 0;
    /* a fused walk-and-evaluate (a selection not kept): per thread, the selection of one
     * part of the mesh (its masks, and its blocks unless a touch keeps them per part), and
     * with a touch the masks of the part's work list; per part with a touch, its selected
     * blocks (the next call's last-call list) and its written ones (the ranges) */
    const size_t fparts = SPLIT_PARTS * (size_t)nt, fmax = nb / fparts + 2;
    size_t fthr = align64(fmax * sizeof(uint64_t)) +
                  (touch ? align64(fmax * sizeof(uint64_t)) : align64(fmax * sizeof(uint32_t)));
    size_t fpart = touch ? 2 * align64(fparts * fmax * sizeof(uint32_t)) +
                               align64(2 * fparts * sizeof(size_t))
                         : 0;
    size_t fsz = fast && use_tree && nt > 1 ? (size_t)nt * fthr + fpart : 0;
    size_t need = pack + splits + mrg + gen_m + gen_f + gen_t + fsz + 64;
    void *mem = NULL;
    int own = 0;
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
        if ((use_tree || all_in_kept) && s->sel_cap < nb) {
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
        mem = s->scratch;
    } else {
        need += use_tree ? blk_m + blk_b + blk_c : 0;
        mem = malloc(need);
        if (!mem) return CSRBF_ERR_NOMEM;
        own = 1;
    }
    unsigned char *sp = (unsigned char *)(((uintptr_t)mem + 63) & ~(uintptr_t)63);
    float *cpack = (float *)sp; /* fast path: centre j's x, y, z, alpha x, y, z at 8 j */
    size_t *isplit = (size_t *)(sp += pack), *bsplit = isplit + nchunks + 1;
    size_t *psplit = bsplit + nchunks + 1; /* split_work's parts: items, then blocks */
    steal_part *spans = (steal_part *)(sp + chunk_b);
    uint64_t *mrg_msk = (uint64_t *)(sp += splits);
    uint32_t *mrg_blk = (uint32_t *)(sp + (mrg ? blk_m : 0));
    size_t *mrg_cum = (size_t *)(sp + (mrg ? blk_m + blk_b : 0));
    uint64_t *gen_mask = (uint64_t *)(sp += mrg);
    uint8_t *tcur = (uint8_t *)(sp += gen_m);
    uint8_t *tprev = tcur + nb;
    unsigned char *tbase = (sp += gen_f);
    unsigned char *fbuf = tbase + gen_t;  /* fused walk: fthr bytes per thread */
    unsigned char *fbase = fbuf + fsz;    /* a concurrent caller's own selection */

    const float inv_r2 = (float)(1.0 / R2), r2c = (float)(R2 * (1.0 + 1e-5)) + 1e-30f;
    const float *fcx = s->fc[0], *fcy = s->fc[1], *fcz = s->fc[2];
    const float *fax = s->fa[0], *fay = s->fa[1], *faz = s->fa[2];

    /* the block selection: cached in the solver for these points and centres (anchored
     * frames reuse it), else a walk of the block tree */
    block_select S = {P, fcx, fcy, fcz, r2c, inv_r2, NULL, NULL, NULL, 0, 0};
    int fused = 0;
    /* all in: the first call with these centres and points computes every pair (no walk: an
     * unanchored frame's centres are new each time) and marks them seen; the next takes the
     * tree's way to a selection of every block with every centre, kept with its weights
     * (on an AVX2 core, Table 1's 33,025-vertex R = 80 anchored update 0.11 ms computing
     * every pair, its R = 60 one 0.05 from the weight cache) */
    if (all_in_kept && !own) {
        if (s->sel_pts == P->stamp && s->sel_ctr == s->centres_stamp) {
            use_tree = 1;
        } else {
            s->sel_pts = P->stamp;
            s->sel_ctr = s->centres_stamp;
            s->sel_k = SEL_PENDING;
        }
    }
    if (use_tree && own) {
        S.msk = (uint64_t *)(sp = fbase);
        S.blk = (uint32_t *)(sp + blk_m);
        S.cum = (size_t *)(sp + blk_m + blk_b);
        select_blocks(&S, simd, m);
    } else if (use_tree) {
        S.blk = s->sel_blk;
        S.msk = s->sel_msk;
        S.cum = s->sel_cum;
        const int seen = s->sel_pts == P->stamp && s->sel_ctr == s->centres_stamp;
        int changed = 1;
        if (seen && s->sel_k != SEL_PENDING) {
            S.k = s->sel_k;
            S.evals = s->sel_evals;
            changed = 0;
        } else if (!seen && fast && fsz &&
                   (double)n * support_share(s, P) >
                       (double)(full_write ? PARALLEL_LANES : PARALLEL_LANES_TOUCHED)) {
            /* a selection not seen before (unanchored frames): each thread walks the tree for
             * its parts of the mesh and evaluates them at once (below); the selection is kept
             * only if it is used again */
            fused = 1;
            s->sel_k = SEL_PENDING;
        } else {
            select_blocks(&S, simd, m);
            s->sel_k = S.k;
            s->sel_evals = S.evals;
            s->sel_refined = 0;
        }
#if CSRBF_SIMD
        if (seen && isa && !s->sel_refined && !fused) { /* used twice: refine it once */
            S.evals = isa->refine(&S);
            s->sel_k = S.k;
            s->sel_evals = S.evals;
            s->sel_refined = 1;
            changed = 1;
        }
#endif
        if (changed) s->sel_id = csrbf_new_stamp();
        s->sel_pts = P->stamp;
        s->sel_ctr = s->centres_stamp;
    }

    size_t pairs = 0, moved = 0;
    double maxd = 0.0, minjac = 1.0;
#if !CSRBF_SIMD
    (void)cpack, (void)isplit, (void)bsplit, (void)mrg_msk, (void)mrg_blk, (void)mrg_cum,
        (void)fused, (void)fbuf, (void)fthr, (void)fparts;
#else
    if (fast) {
        /* the work list: every block (all in), the selected blocks with the gaps between
         * them copied (a full write), or the selected blocks merged with the last call's
         * (restored where no support holds them now) */
        for (size_t j = 0; j < m; j++) {
            float *q = cpack + 8 * j;
            q[0] = fcx[j], q[1] = fcy[j], q[2] = fcz[j];
            q[3] = fax[j], q[4] = fay[j], q[5] = faz[j];
            q[6] = q[7] = 0.0f;
        }
        if (fused) {
            /* a full write copies each part's gaps; a touched call's work list is the part's
             * selection merged with the last call's blocks there (merge_last) */
            const drive_fn drive = isa->drivers[ki][st != NULL][full_write ? DRIVE_GAPS : DRIVE_LIST];
            const int top = P->tlevels - 1;
            const uint64_t all = m >= 64 ? ~0ull : (1ull << m) - 1;
            uint32_t *psel = (uint32_t *)(fbuf + (size_t)nt * fthr),
                     *pwr = psel + align64(fparts * fmax * sizeof(uint32_t)) / sizeof(uint32_t);
            size_t *nsel = (size_t *)(pwr + align64(fparts * fmax * sizeof(uint32_t)) /
                                                sizeof(uint32_t)),
                   *nwr = nsel + fparts;
            const uint32_t *pv = touch ? touch->prev : NULL;
            const size_t np = touch ? touch->nprev : 0;
            float maxd2 = 0.0f;
#pragma omp parallel num_threads(nt) reduction(+ : pairs, moved) reduction(max : maxd2)
            {
                block_stats ts = {0, 0, 0.0f};
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
                    if (simd == SIMD_AVX512) select_visit_avx512(&L, top, 0, all, lo, hi);
                    else select_visit_avx2(&L, top, 0, all, lo, hi);
                    if (full_write) {
                        drive(P, out, L.blk, L.msk, 0, L.k, lo, hi, m, cpack, inv_r2, NULL, &ts);
                    } else {
                        uint32_t *wb = pwr + q * fmax;
                        const size_t c0 = lower_bound(pv, np, lo), c1 = lower_bound(pv, np, hi);
                        const size_t k =
                            merge_last(L.blk, L.msk, NULL, L.k, pv + c0, c1 - c0, wb, wm, NULL);
                        drive(P, out, wb, wm, 0, k, 0, 0, m, cpack, inv_r2, NULL, &ts);
                        nwr[q] = k;
                    }
                    if (touch) nsel[q] = L.k;
                }
                pairs += ts.pairs;
                moved += ts.moved;
                if (ts.maxd2 > maxd2) maxd2 = ts.maxd2;
            }
            maxd = maxd2;
            if (touch) { /* the parts' lists in order: the last-call list and the ranges */
                size_t k = 0, w = 0;
                for (size_t q = 0; q < fparts; q++) {
                    memcpy(touch->prev + k, psel + q * fmax, nsel[q] * sizeof *psel);
                    k += nsel[q];
                    memmove(pwr + w, pwr + q * fmax, nwr[q] * sizeof *pwr);
                    w += nwr[q];
                }
                touch->nprev = k;
                if (full_write) ranges_all(touch, n);
                else ranges_of_blocks(touch, n, pwr, w);
                touch->sel_id = 0;
                touch->ranges_sel = 0;
            }
        } else {
            const uint32_t *ib = NULL;
            const uint64_t *im = NULL;
            const size_t *ic = NULL;
            size_t ni = nb, cost = nb * ITEM_COST(m);
            int gaps = 0, same = 0;
            if (use_tree) {
                ib = S.blk;
                im = S.msk;
                ic = S.cum;
                ni = S.k;
                if (full_write) {
                    gaps = 1;
                } else if (!own && touch->sel_id == s->sel_id) {
                    same = 1; /* the last call computed exactly these blocks: nothing to restore */
                } else {
                    ni = merge_last(S.blk, S.msk, S.cum, S.k, touch->prev, touch->nprev, mrg_blk,
                                    mrg_msk, mrg_cum);
                    ib = mrg_blk;
                    im = mrg_msk;
                    ic = mrg_cum;
                }
                cost = ic[ni];
            }
            /* the kept selection's weight cache, for frames whose items are exactly that
             * selection (full writes and unchanged touched ones) and whose bytes stay within
             * CSRBF_WCACHE_THREAD_BYTES per thread: filled at the first such frame after the
             * selection is refined (its second use) */
            weight_cache wcv = {NULL, NULL, NULL}, *wc = NULL;
            if (use_tree && !own && ib == S.blk && s->sel_refined && S.k) {
                const size_t ccost = ITEM_COST_CACHED(S.k, S.evals);
                const size_t cthreads = ccost <= PARALLEL_COST ? 1 : (size_t)nt;
                const size_t bytes = 24 * (full_write ? n : S.k * B) + WCACHE_PAIR_BYTES * S.evals;
                if (bytes <= cthreads * CSRBF_WCACHE_THREAD_BYTES &&
                    (s->sel_w_id == s->sel_id || wcache_fill(s, P, isa, ki, cpack, inv_r2)))
                    wc = wcache_get(s, &wcv, &ic);
            }
            if (wc) cost = ic[ni];
            const int mode = !ib ? DRIVE_ALL : gaps ? DRIVE_GAPS : DRIVE_LIST;
            const drive_fn drive =
                wc ? isa->cached[st != NULL][mode - DRIVE_LIST] : isa->drivers[ki][st != NULL][mode];
            block_stats bs = {0, 0, 0.0f};
            /* threads by the computed blocks' cost; copying the gaps (a full write) is bound by
             * memory and does not count, but is shared out when threads run */
            if (cost <= PARALLEL_COST || nt == 1) {
                drive(P, out, ib, im, 0, ni, 0, gaps ? nb : 0, m, cpack, inv_r2, wc, &bs);
            } else {
                /* one contiguous part of equal cost per thread, in STEAL_CHUNKS chunks: a
                 * thread takes its own part's chunks in order, so that frame after frame the
                 * same blocks stay in the same core's cache, and then steals from the far end
                 * of the others' (a core that the host slows, or a thread that starts late,
                 * no longer holds the frame back: on the 2-core VM one core ran the same part
                 * 1.4x slower than the other for minutes at a time) */
                const size_t parts = (size_t)nt;
                split_work(ib, ic, ni, gaps, nb, parts, cost + (gaps ? nb - ni : 0), psplit,
                           psplit + parts + 1);
                chunk_work(ib, ic, psplit, psplit + parts + 1, parts, STEAL_CHUNKS, isplit, bsplit);
                for (size_t t = 0; t < parts; t++)
                    atomic_init(&spans[t].span, (uint64_t)(t * STEAL_CHUNKS) |
                                                    (uint64_t)((t + 1) * STEAL_CHUNKS) << 32);
                float maxd2 = 0.0f;
#pragma omp parallel num_threads(nt) reduction(+ : pairs, moved) reduction(max : maxd2)
                {
                    block_stats ts = {0, 0, 0.0f};
                    /* its own part, then the others' (those of threads missing from a
                     * smaller team than asked for whole, from the front) */
                    const size_t me = (size_t)omp_get_thread_num(),
                                 team = (size_t)omp_get_num_threads();
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
                bs.maxd2 = maxd2;
            }
            /* the cached drivers leave the pairs and moved vertices to the cache's counts */
            pairs += bs.pairs + (wc ? s->sel_w_pairs : 0);
            moved += bs.moved + (wc ? s->sel_w_moved : 0);
            maxd = bs.maxd2;
            if (touch) { /* this call's computed blocks become the last call's */
                if (!use_tree) { /* (all in) */
                    ranges_all(touch, n);
                    for (size_t b = 0; b < nb; b++) touch->prev[b] = (uint32_t)b;
                    touch->nprev = nb;
                    touch->sel_id = 0;
                    touch->ranges_sel = 0;
                } else {
                    if (full_write) {
                        ranges_all(touch, n);
                        touch->ranges_sel = 0;
                    } else if (!same || !touch->ranges_sel) {
                        ranges_of_blocks(touch, n, ib, ni);
                        touch->ranges_sel = ni == S.k;
                    }
                    if (!same) touch_set_prev(touch, S.blk, S.k);
                    /* a selection computed into the caller's own memory is not the solver's */
                    touch->sel_id = own ? 0 : s->sel_id;
                }
            }
        }
    } else
#endif
    {
        /* the general path: every block, its centres from the tree masks, all of them (all
         * in), or the centre grid (many centres) */
        if (use_tree) {
            memset(gen_mask, 0, nb * sizeof *gen_mask);
            for (size_t i = 0; i < S.k; i++) gen_mask[S.blk[i]] = S.msk[i];
        }
        if (touch) {
            memset(tprev, full_write, nb);
            if (!full_write)
                for (size_t i = 0; i < touch->nprev; i++) tprev[touch->prev[i]] = 1;
        }
        const float pc0 = s->fpc[0], pc1 = s->fpc[1], pc2 = s->fpc[2];
        const float *G = s->fG, *g0 = s->fg0;
        size_t cost = use_tree ? S.cum[S.k] : all_in ? nb * ITEM_COST(m) : nb * ITEM_COST(1);
        int threads = cost > PARALLEL_COST || (m > CSRBF_FAST_MAX_CENTRES && !all_in) ? nt : 1;
#pragma omp parallel num_threads(threads) reduction(+ : pairs, moved) reduction(max : maxd) \
    reduction(min : minjac)
        {
            int tid = omp_get_thread_num();
            uint32_t *list = (uint32_t *)(tbase + (size_t)tid * per_thread);
            if (all_in)
                for (size_t i = 0; i < m; i++) list[i] = (uint32_t)i;
            _Alignas(64) float accx[B], accy[B], accz[B];
            _Alignas(64) int cnt[B];
#pragma omp for schedule(dynamic, 64)
            for (size_t b = 0; b < nb; b++) {
                size_t k0 = b * B, nv = b + 1 < nb ? B : n - k0;
                float *o = out + 3 * k0;
                size_t k = m;
                if (!all_in) {
                    if (use_tree) {
                        uint64_t mk = gen_mask[b];
                        k = 0;
                        while (mk) {
                            list[k++] = (uint32_t)__builtin_ctzll(mk);
                            mk &= mk - 1;
                        }
                    } else {
                        k = select_centres(s, P, b, list, 0);
                    }
                    if (!k && !poly && !want_jac) { /* outside every support: the base */
                        if (touch) tcur[b] = 0;
                        if (!touch || tprev[b]) memcpy(o, P->xyz + 3 * k0, nv * 3 * sizeof(float));
                        continue;
                    }
                }
                if (touch) tcur[b] = 1;
                const float *x = P->s[0] + k0, *y = P->s[1] + k0, *z = P->s[2] + k0;
                kern(x, y, z, list, k, fcx, fcy, fcz, fax, fay, faz, inv_r2, accx, accy, accz,
                     cnt);
                if (poly)
                    for (int v = 0; v < B; v++) {
                        float ex = x[v] - pc0, ey = y[v] - pc1, ez = z[v] - pc2;
                        accx[v] += g0[0] + G[0] * ex + G[1] * ey + G[2] * ez;
                        accy[v] += g0[1] + G[3] * ex + G[4] * ey + G[5] * ez;
                        accz[v] += g0[2] + G[6] * ex + G[7] * ey + G[8] * ez;
                    }
#if CSRBF_SIMD
                if (isa && nv == B)
                    isa->write_block(o, x, y, z, accx, accy, accz);
                else
#endif
                    write_block(o, x, y, z, accx, accy, accz, nv);
                if (st) {
                    for (size_t v = 0; v < nv; v++) {
                        pairs += (size_t)cnt[v];
                        moved += poly || cnt[v] > 0;
                        double d = (double)accx[v] * accx[v] + (double)accy[v] * accy[v] +
                                   (double)accz[v] * accz[v];
                        if (d > maxd) maxd = d;
                        if (want_jac && (poly || cnt[v] > 0)) {
                            double xv[3] = {x[v], y[v], z[v]};
                            double det = jacobian_det(s, xv, list, k);
                            if (det < minjac) minjac = det;
                        }
                    }
                }
            }
        }
        if (touch) { /* the written blocks (computed now or restored) as ranges */
            size_t k = 0, nr = 0;
            for (size_t b = 0; b < nb;) {
                if (!(tcur[b] || tprev[b])) {
                    b++;
                    continue;
                }
                size_t b0 = b;
                for (; b < nb && (tcur[b] || tprev[b]); b++)
                    if (tcur[b]) touch->prev[k++] = (uint32_t)b; /* tprev holds the old list */
                size_t v1 = b * B < n ? b * B : n;
                touch->ranges[2 * nr] = (uint32_t)(b0 * B);
                touch->ranges[2 * nr + 1] = (uint32_t)(v1 - b0 * B);
                nr++;
            }
            touch->nranges = nr;
            touch->nprev = k;
            touch->sel_id = 0;
            touch->ranges_sel = 0;
        }
    }
    if (own)
        free(mem);
    else
        atomic_flag_clear(&s->scratch_busy);
    if (touch) touch->full = 0;
    if (st) {
        st->pairs = pairs;
        st->moved = moved;
        st->max_displacement = sqrt(maxd);
        st->min_jacobian_det = minjac;
    }
    return CSRBF_OK;
}
