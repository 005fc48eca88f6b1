/* csrbf_evaluate's block selection: the blocks whose box meets a support, with a 64-bit mask
 * of their centres, from one walk of the points' block tree for all centres at once (one
 * AVX-512 or two AVX2 box tests per node and centre where the CPU has them, portable C
 * elsewhere, the same decisions); beyond 64 centres, a block's centres through the centre
 * grid. Also the whole-box tests that decide whether a call selects at all. */
#include "eval_internal.h"

#include <math.h>

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

#endif

/* (eval_internal.h) */
void csrbf_sel_blocks(block_select *S, int simd, size_t m)
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

/* The walk of one part of a fused evaluation (eval_internal.h). */
void csrbf_sel_range(block_select *S, int simd, uint64_t all, size_t lo, size_t hi)
{
    const int top = S->P->tlevels - 1;
#if CSRBF_SIMD
    if (simd == SIMD_AVX512) {
        select_visit_avx512(S, top, 0, all, lo, hi);
        return;
    }
    if (simd == SIMD_AVX2) {
        select_visit_avx2(S, top, 0, all, lo, hi);
        return;
    }
#endif
    (void)simd;
    select_visit_c(S, top, 0, all, lo, hi);
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

/* Centres whose support meets block b; returns their count (list may be NULL with any: stop
 * at the first hit). */
size_t csrbf_sel_centres(const csrbf_solver *s, const csrbf_points *P, size_t b,
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

/* (eval_internal.h) */
double csrbf_sel_support_share(const csrbf_solver *s, const csrbf_points *P)
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


/* The support of every centre holds the whole vertex box (with a margin of 1e-6). */
int csrbf_sel_all_in(const csrbf_solver *s, const csrbf_points *P)
{
    int all_in = 1;
    const double R2 = s->R * s->R;
    for (size_t i = 0; i < s->m && all_in; i++) {
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double c = s->c[3 * i + a];
            double e = fmax(fabs(c - P->blo[a]), fabs(c - P->bhi[a]));
            d2 += e * e;
        }
        all_in = d2 < R2 * (1.0 - 1e-6);
    }
    return all_in;
}
