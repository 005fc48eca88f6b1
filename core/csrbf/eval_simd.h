/* The fast path's kernels for one instruction set, written once over 16-lane vector
 * operations: csrbf_fast.c includes this file once per instruction set, with CSRBF_ISA set
 *   CSRBF_ISA_AVX512  one __m512 per block of 16 vertices, the V_* names are the AVX-512
 *                     intrinsics themselves (the code compiles as if written with them);
 *   CSRBF_ISA_AVX2    two __m256 halves (AVX2 + FMA), simd16_avx2.h: the same operations,
 *                     lane by lane (a mask is a vector of all-ones lanes, a masked add a
 *                     blend, the 14-bit reciprocal square root estimate the 12-bit one).
 * Each inclusion defines the per-block kernels, the fused drivers, the weight cache fills, the
 * selection refinement and the table SFX(isa) (eval_internal.h's eval_isa) of its functions.
 * Needs, before it: B (= 16), csrbf_points, block_select, ITEM_COST, block_stats,
 * weight_cache, copy_base, DRIVE_*, eval_isa. */

#if CSRBF_ISA == CSRBF_ISA_AVX512
#define SFX(name) name##_avx512
#define V_TARGET __attribute__((target("avx512f,fma")))
#define V_TARGET_POPCNT __attribute__((target("avx512f,fma,popcnt")))
#define VF __m512
#define VI __m512i
#define VM __mmask16
#define V_loadu_ps _mm512_loadu_ps
#define V_load_ps _mm512_load_ps
#define V_storeu_ps _mm512_storeu_ps
#define V_store_ps _mm512_store_ps
#define V_set1_ps _mm512_set1_ps
#define V_setzero_ps _mm512_setzero_ps
#define V_add_ps _mm512_add_ps
#define V_sub_ps _mm512_sub_ps
#define V_mul_ps _mm512_mul_ps
#define V_max_ps _mm512_max_ps
#define V_fmadd_ps _mm512_fmadd_ps
#define V_fnmadd_ps _mm512_fnmadd_ps
#define V_rsqrt_ps _mm512_rsqrt14_ps
#define V_cmplt_mask(a, b) _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ)
#define V_mask3_fmadd_ps _mm512_mask3_fmadd_ps
#define V_setzero_si _mm512_setzero_si512
#define V_set1_epi32 _mm512_set1_epi32
#define V_add_epi32 _mm512_add_epi32
#define V_mask_inc_epi32(c, m, one) _mm512_mask_add_epi32(c, m, c, one)
#define V_count_gt0(c, zero) __builtin_popcount((unsigned)_mm512_cmpgt_epi32_mask(c, zero))
#define V_storeu_si _mm512_storeu_si512
#define V_store_si _mm512_store_si512
#define V_reduce_add_epi32 _mm512_reduce_add_epi32
#define V_reduce_max_ps _mm512_reduce_max_ps
#define V_interleave interleave_avx512
#define VM_ANY(m) (m)
#define VM_BITS(m) ((uint16_t)(m))
#define VM_FROM_BITS(b) ((__mmask16)(b))
#elif CSRBF_ISA == CSRBF_ISA_AVX2
#define SFX(name) name##_avx2
#define V_TARGET __attribute__((target("avx2,fma")))
#define V_TARGET_POPCNT __attribute__((target("avx2,fma,popcnt")))
#define VF v16f
#define VI v16i
#define VM v16f
#define V_loadu_ps v16_loadu_ps
#define V_load_ps v16_load_ps
#define V_storeu_ps v16_storeu_ps
#define V_store_ps v16_store_ps
#define V_set1_ps v16_set1_ps
#define V_setzero_ps v16_setzero_ps
#define V_add_ps v16_add_ps
#define V_sub_ps v16_sub_ps
#define V_mul_ps v16_mul_ps
#define V_max_ps v16_max_ps
#define V_fmadd_ps v16_fmadd_ps
#define V_fnmadd_ps v16_fnmadd_ps
#define V_rsqrt_ps v16_rsqrt_ps
#define V_cmplt_mask v16_cmplt_mask
#define V_mask3_fmadd_ps v16_mask3_fmadd_ps
#define V_setzero_si v16_setzero_si
#define V_set1_epi32 v16_set1_epi32
#define V_add_epi32 v16_add_epi32
#define V_mask_inc_epi32 v16_mask_inc_epi32
#define V_count_gt0 v16_count_gt0
#define V_storeu_si v16_storeu_si
#define V_store_si v16_store_si
#define V_reduce_add_epi32 v16_reduce_add_epi32
#define V_reduce_max_ps v16_reduce_max_ps
#define V_interleave v16_interleave
#define VM_ANY v16m_any
#define VM_BITS v16m_bits
#define VM_FROM_BITS v16m_from_bits
#else
#error "eval_simd.h: CSRBF_ISA must be CSRBF_ISA_AVX512 or CSRBF_ISA_AVX2"
#endif

/* r = r2 * rsqrt(r2): the hardware estimate plus one Newton step (relative error below 1e-7
 * from the 14-bit estimate, about 3e-7 from the 12-bit one) replaces the slower square root;
 * lanes outside the support are masked off (their accumulators keep their bits).
 * The support mask `in` (lanes within the support of the centre (CX, CY, CZ)) and, from
 * the squared scaled distance r2, the kernel weight `w` at the 16 lanes X, Y, Z: declarations,
 * shared by the per-block kernel, the fused driver and the weight cache (the same
 * expressions, so the same operations and roundings). SIMD_DIST(J): the centre packed at
 * cp[8 J]. */
#define SIMD_DIST_AT(CX, CY, CZ)                                                               \
    VF dx = V_sub_ps(X, V_set1_ps(CX));                                                        \
    VF dy = V_sub_ps(Y, V_set1_ps(CY));                                                        \
    VF dz = V_sub_ps(Z, V_set1_ps(CZ));                                                        \
    VF r2 = V_mul_ps(dx, dx);                                                                  \
    r2 = V_fmadd_ps(dy, dy, r2);                                                               \
    r2 = V_fmadd_ps(dz, dz, r2);                                                               \
    r2 = V_mul_ps(r2, ir2);                                                                    \
    VM in = V_cmplt_mask(r2, one)
#define SIMD_DIST(J) SIMD_DIST_AT(cp[8 * (J)], cp[8 * (J) + 1], cp[8 * (J) + 2])
#define SIMD_WEIGHT(PSI)                                                                       \
    VF q = V_max_ps(r2, tiny);                                                                 \
    VF e = V_rsqrt_ps(q);                                                                      \
    VF hq = V_mul_ps(half, q);                                                                 \
    e = V_mul_ps(e, V_fnmadd_ps(V_mul_ps(hq, e), e, three_half));                              \
    VF r = V_mul_ps(q, e);                                                                     \
    VF t1 = V_sub_ps(one, r);                                                                  \
    VF w = PSI

/* The Wendland functions of r (t1 = 1 - r) as vector expressions. */
#define T2 V_mul_ps(t1, t1)
#define PSI31_V V_mul_ps(V_mul_ps(T2, T2), V_fmadd_ps(V_set1_ps(4.0f), r, one))
#define PSI32_V                                                                                \
    V_mul_ps(V_mul_ps(V_mul_ps(T2, T2), T2),                                                   \
             V_fmadd_ps(V_fmadd_ps(V_set1_ps(35.0f / 3.0f), r, V_set1_ps(6.0f)), r, one))

/* The per-block kernel (block_fn) of the general path. */
#define SIMD_KERNEL(NAME, PSI)                                                                 \
    V_TARGET static void NAME(                                                                 \
        const float *restrict x, const float *restrict y, const float *restrict z,            \
        const uint32_t *restrict list, size_t k, const float *restrict cx,                     \
        const float *restrict cy, const float *restrict cz, const float *restrict ax,          \
        const float *restrict ay, const float *restrict az, float inv_r2,                      \
        float *restrict accx, float *restrict accy, float *restrict accz, int *restrict cnt)   \
    {                                                                                          \
        const VF X = V_loadu_ps(x), Y = V_loadu_ps(y), Z = V_loadu_ps(z);                      \
        const VF one = V_set1_ps(1.0f), half = V_set1_ps(0.5f), three_half = V_set1_ps(1.5f), \
                 tiny = V_set1_ps(1e-30f), ir2 = V_set1_ps(inv_r2);                            \
        VF sx = V_set1_ps(-0.0f), sy = sx, sz = sx;                                            \
        VI sc = V_setzero_si();                                                                \
        const VI ione = V_set1_epi32(1);                                                       \
        for (size_t t = 0; t < k; t++) {                                                       \
            const uint32_t j = list[t];                                                        \
            SIMD_DIST_AT(cx[j], cy[j], cz[j]);                                                 \
            if (!VM_ANY(in)) continue;                                                         \
            SIMD_WEIGHT(PSI);                                                                  \
            sx = V_mask3_fmadd_ps(w, V_set1_ps(ax[j]), sx, in);                                \
            sy = V_mask3_fmadd_ps(w, V_set1_ps(ay[j]), sy, in);                                \
            sz = V_mask3_fmadd_ps(w, V_set1_ps(az[j]), sz, in);                                \
            sc = V_mask_inc_epi32(sc, in, ione);                                               \
        }                                                                                      \
        V_storeu_ps(accx, sx);                                                                 \
        V_storeu_ps(accy, sy);                                                                 \
        V_storeu_ps(accz, sz);                                                                 \
        V_storeu_si(cnt, sc);                                                                  \
    }

SIMD_KERNEL(SFX(block_psi31), PSI31_V)
SIMD_KERNEL(SFX(block_psi30), T2)
SIMD_KERNEL(SFX(block_psi32), PSI32_V)

/* A block's output: base + displacement, interleaved (the general path's full blocks). */
V_TARGET static void SFX(write_block)(float *restrict out, const float *restrict x,
                                      const float *restrict y, const float *restrict z,
                                      const float *restrict accx, const float *restrict accy,
                                      const float *restrict accz)
{
    V_interleave(out, V_add_ps(V_loadu_ps(x), V_loadu_ps(accx)),
                 V_add_ps(V_loadu_ps(y), V_loadu_ps(accy)),
                 V_add_ps(V_loadu_ps(z), V_loadu_ps(accz)));
}

/* One centre's contribution to the 16 lanes (shared by the fused driver below). With SKIP (a
 * compile-time constant) a centre whose support holds none of the 16 vertices costs only the
 * distance test (blocks whose box meets a support they do not reach: the ends of grid rows). */
#define SIMD_PAIR(PSI, J, SKIP)                                                                \
    do {                                                                                       \
        SIMD_DIST(J);                                                                          \
        if ((SKIP) && !VM_ANY(in)) break;                                                      \
        SIMD_WEIGHT(PSI);                                                                      \
        sx = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * (J) + 3]), sx, in);                          \
        sy = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * (J) + 4]), sy, in);                          \
        sz = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * (J) + 5]), sz, in);                          \
        if (stats_on) cntv = V_mask_inc_epi32(cntv, in, ione);                                 \
    } while (0)

/* A partial block (the mesh's last, nv < B vertices): base + displacement, and with stats its
 * largest squared displacement and (count) its pairs and moved vertices straight into *bs.
 * Kept out of the drivers' loop (and its registers). */
V_TARGET __attribute__((noinline, cold)) static void
SFX(finish_partial)(float *o, const float *x, const float *y, const float *z, size_t nv, VF sx,
                    VF sy, VF sz, VI cntv, int stats, int count, block_stats *bs)
{
    _Alignas(64) float acc[3][B];
    _Alignas(64) int32_t cnt[B];
    V_store_ps(acc[0], sx);
    V_store_ps(acc[1], sy);
    V_store_ps(acc[2], sz);
    V_store_si(cnt, cntv);
    for (size_t v = 0; v < nv; v++) {
        o[3 * v] = x[v] + acc[0][v];
        o[3 * v + 1] = y[v] + acc[1][v];
        o[3 * v + 2] = z[v] + acc[2][v];
        if (stats && count) {
            bs->pairs += (size_t)cnt[v];
            bs->moved += cnt[v] > 0;
        }
        if (stats) {
            /* the same operations as the full blocks' (mul, fma, fma), lane by lane */
            float d2 = fmaf(acc[2][v], acc[2][v], fmaf(acc[1][v], acc[1][v], acc[0][v] * acc[0][v]));
            if (d2 > bs->maxd2) bs->maxd2 = d2;
        }
    }
}

/* The fast path without polynomial, one copy per MODE (compile-time): DRIVE_ALL: blocks
 * i0..i1-1, each with all m centres (blk, msk unused). DRIVE_LIST: the work items i0..i1-1,
 * block blk[i] with the centres of the bit mask msk[i] (bit j: centre j, j < 64), or restored
 * to the base where msk[i] is 0. DRIVE_GAPS: as DRIVE_LIST, and the blocks of [g0, g1) that
 * no item names are copied from the base (a full evaluation: items and gaps cover the range
 * in order). Blocks are computed in registers and stored interleaved. With STATS (also
 * compile-time) the pairs in support are counted per lane with one masked add per pair, and
 * moved vertices and the largest squared displacement per block, into *bs (padding lanes
 * excluded; the lane counts are flushed every 2^16 blocks so that they cannot overflow). With
 * CACHED (compile-time; LIST and GAPS, any kernel: PSI unused) the items are the kept
 * selection's and each pair's weights and support mask come from its weight cache *wc instead
 * of the kernel (the same values, added by the same masked fused multiply-adds); its pairs
 * and moved vertices are not counted (counted once at the cache's fill: the solver's
 * sel_w_pairs, sel_w_moved). */
#define SIMD_DRIVER(NAME, PSI, STATS, MODE, CACHED)                                            \
    V_TARGET static void NAME(                                                                 \
        const csrbf_points *P, float *restrict out, const uint32_t *restrict blk,              \
        const uint64_t *restrict msk, size_t i0, size_t i1, size_t g0, size_t g1, size_t m,    \
        const float *restrict cp, float inv_r2, const weight_cache *wc, block_stats *bs)       \
    {                                                                                          \
        const VF one = V_set1_ps(1.0f), half = V_set1_ps(0.5f), three_half = V_set1_ps(1.5f), \
                 tiny = V_set1_ps(1e-30f), ir2 = V_set1_ps(inv_r2);                            \
        const VI ione = V_set1_epi32(1), izero = V_setzero_si();                               \
        enum { stats_on = STATS, count_on = STATS && !CACHED };                                \
        VI pairv = izero;                                                                      \
        VF maxd = V_setzero_ps();                                                              \
        size_t nmoved = 0;                                                                     \
        const size_t n = P->n;                                                                 \
        const float *const px = P->s[0], *const py = P->s[1], *const pz = P->s[2];             \
        size_t pos = g0;                                                                       \
        /* CACHED: the items' pairs lie in order from item i0's first on */                   \
        const float *restrict wv = CACHED ? wc->w + (size_t)wc->off[i0] * B : NULL;            \
        const uint16_t *restrict wi = CACHED ? wc->in + wc->off[i0] : NULL;                    \
        (void)wv;                                                                              \
        (void)wi;                                                                              \
        (void)g1;                                                                              \
        (void)m;                                                                               \
        (void)wc;                                                                              \
        for (size_t i = i0; i < i1; i++) {                                                     \
            const size_t b = MODE != DRIVE_ALL ? blk[i] : i;                                   \
            uint64_t mk = MODE != DRIVE_ALL ? msk[i] : 0;                                      \
            if (MODE != DRIVE_ALL) {                                                           \
                if (MODE == DRIVE_GAPS && pos < b) copy_base(P, out, pos, b);                  \
                pos = b + 1;                                                                   \
                if (!mk) { /* in a support last call, in none now: the base */                 \
                    copy_base(P, out, b, b + 1);                                               \
                    continue;                                                                  \
                }                                                                              \
            }                                                                                  \
            const size_t k0 = b * B, nv = k0 + B <= n ? B : n - k0;                            \
            float *o = out + 3 * k0;                                                           \
            const VF X = V_loadu_ps(px + k0), Y = V_loadu_ps(py + k0), Z = V_loadu_ps(pz + k0); \
            VF sx = V_set1_ps(-0.0f), sy = sx, sz = sx;                                        \
            VI cntv = izero;                                                                   \
            if (CACHED) {                                                                      \
                while (mk) {                                                                   \
                    const unsigned j = (unsigned)__builtin_ctzll(mk);                          \
                    mk &= mk - 1;                                                              \
                    const VF w = V_load_ps(wv);                                                \
                    const VM in = VM_FROM_BITS(*wi++);                                         \
                    wv += B;                                                                   \
                    sx = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * j + 3]), sx, in);                \
                    sy = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * j + 4]), sy, in);                \
                    sz = V_mask3_fmadd_ps(w, V_set1_ps(cp[8 * j + 5]), sz, in);                \
                    if (count_on) cntv = V_mask_inc_epi32(cntv, in, ione);                     \
                }                                                                              \
            } else if (MODE != DRIVE_ALL) {                                                    \
                while (mk) {                                                                   \
                    const unsigned j = (unsigned)__builtin_ctzll(mk);                          \
                    mk &= mk - 1;                                                              \
                    SIMD_PAIR(PSI, j, 1);                                                      \
                }                                                                              \
            } else {                                                                           \
                for (size_t j = 0; j < m; j++) SIMD_PAIR(PSI, j, 0);                           \
            }                                                                                  \
            if (nv == B) {                                                                     \
                if (count_on) {                                                                \
                    pairv = V_add_epi32(pairv, cntv);                                          \
                    nmoved += (size_t)V_count_gt0(cntv, izero);                                \
                }                                                                              \
                if (STATS) {                                                                   \
                    VF d2 = V_mul_ps(sx, sx);                                                  \
                    d2 = V_fmadd_ps(sy, sy, d2);                                               \
                    d2 = V_fmadd_ps(sz, sz, d2);                                               \
                    maxd = V_max_ps(maxd, d2);                                                 \
                }                                                                              \
                V_interleave(o, V_add_ps(X, sx), V_add_ps(Y, sy), V_add_ps(Z, sz));            \
            } else {                                                                           \
                SFX(finish_partial)(o, px + k0, py + k0, pz + k0, nv, sx, sy, sz, cntv, STATS, \
                                    count_on, bs);                                             \
            }                                                                                  \
            if (count_on && !((i - i0 + 1) & 0xFFFF)) { /* lane counts stay far from 2^32 */   \
                bs->pairs += (size_t)(uint32_t)V_reduce_add_epi32(pairv);                      \
                pairv = izero;                                                                 \
            }                                                                                  \
        }                                                                                      \
        if (MODE == DRIVE_GAPS && pos < g1) copy_base(P, out, pos, g1);                        \
        if (STATS) {                                                                           \
            bs->pairs += (size_t)(uint32_t)V_reduce_add_epi32(pairv);                          \
            bs->moved += nmoved;                                                               \
            float mx = V_reduce_max_ps(maxd);                                                  \
            if (mx > bs->maxd2) bs->maxd2 = mx;                                                \
        }                                                                                      \
        (void)bs;                                                                              \
    }

#define SIMD_DRIVERS(NAME, PSI)                                                                \
    SIMD_DRIVER(SFX(NAME##_all), PSI, 0, DRIVE_ALL, 0)                                         \
    SIMD_DRIVER(SFX(NAME##_list), PSI, 0, DRIVE_LIST, 0)                                       \
    SIMD_DRIVER(SFX(NAME##_gaps), PSI, 0, DRIVE_GAPS, 0)                                       \
    SIMD_DRIVER(SFX(NAME##_all_stats), PSI, 1, DRIVE_ALL, 0)                                   \
    SIMD_DRIVER(SFX(NAME##_list_stats), PSI, 1, DRIVE_LIST, 0)                                 \
    SIMD_DRIVER(SFX(NAME##_gaps_stats), PSI, 1, DRIVE_GAPS, 0)
SIMD_DRIVERS(drive_psi31, PSI31_V)
SIMD_DRIVERS(drive_psi30, T2)
SIMD_DRIVERS(drive_psi32, PSI32_V)
SIMD_DRIVER(SFX(drive_cached_list), T2, 0, DRIVE_LIST, 1)
SIMD_DRIVER(SFX(drive_cached_gaps), T2, 0, DRIVE_GAPS, 1)
SIMD_DRIVER(SFX(drive_cached_list_stats), T2, 1, DRIVE_LIST, 1)
SIMD_DRIVER(SFX(drive_cached_gaps_stats), T2, 1, DRIVE_GAPS, 1)

/* The weight cache of a kept, refined selection (solver fields sel_w*): for each pair (item
 * i, centre j of msk[i], in increasing j), its 16 lanes' kernel weights and its support mask,
 * as SIMD_DIST / SIMD_WEIGHT compute them; item i's pairs are off[i] .. off[i+1]-1. The
 * weights depend on the vertices and the centres (the start points) only, so anchored frames
 * (only the end points, hence the coefficients, move) reuse them. */
#define SIMD_FILL(NAME, PSI)                                                                   \
    V_TARGET static void NAME(const csrbf_points *P, const uint32_t *restrict blk,             \
                              const uint64_t *restrict msk, size_t k, const float *restrict cp, \
                              float inv_r2, float *restrict wv, uint16_t *restrict win,        \
                              uint32_t *restrict off)                                          \
    {                                                                                          \
        const VF one = V_set1_ps(1.0f), half = V_set1_ps(0.5f), three_half = V_set1_ps(1.5f), \
                 tiny = V_set1_ps(1e-30f), ir2 = V_set1_ps(inv_r2);                            \
        uint32_t p = 0;                                                                        \
        for (size_t i = 0; i < k; i++) {                                                       \
            const size_t k0 = (size_t)blk[i] * B;                                              \
            const VF X = V_loadu_ps(P->s[0] + k0), Y = V_loadu_ps(P->s[1] + k0),               \
                     Z = V_loadu_ps(P->s[2] + k0);                                             \
            off[i] = p;                                                                        \
            for (uint64_t mk = msk[i]; mk; mk &= mk - 1, p++) {                                \
                const unsigned j = (unsigned)__builtin_ctzll(mk);                              \
                SIMD_DIST(j);                                                                  \
                SIMD_WEIGHT(PSI);                                                              \
                V_store_ps(wv + (size_t)p * B, w);                                             \
                win[p] = VM_BITS(in);                                                          \
            }                                                                                  \
        }                                                                                      \
        off[k] = p;                                                                            \
    }
SIMD_FILL(SFX(fill_psi31), PSI31_V)
SIMD_FILL(SFX(fill_psi30), T2)
SIMD_FILL(SFX(fill_psi32), PSI32_V)

/* Refine the selection to the pairs the kernel uses: a centre whose support holds none of a
 * block's 16 vertices (its box meets the support, its vertices do not: the ends of grid rows,
 * the rims of supports) is dropped from the block's mask, and a block left with none from the
 * list. The test is the kernels' own (same operations on the same floats), so the dropped
 * pairs are exactly those the kernels would mask off entirely: results are unchanged (such a
 * block's output is its base bit for bit either way), the kernels skip fewer empty pairs.
 * Done once on a kept selection's second use (anchored frames), not on a selection used once
 * (unanchored frames), where it would cost about a third of the evaluation. Then the prefix
 * costs; returns the pairs kept. */
V_TARGET_POPCNT static size_t SFX(refine)(block_select *S)
{
    const csrbf_points *P = S->P;
    const VF one = V_set1_ps(1.0f), ir2 = V_set1_ps(S->inv_r2);
    size_t e = 0, c = 0, k = 0;
    for (size_t i = 0; i < S->k; i++) {
        const size_t k0 = (size_t)S->blk[i] * B;
        const VF X = V_loadu_ps(P->s[0] + k0), Y = V_loadu_ps(P->s[1] + k0),
                 Z = V_loadu_ps(P->s[2] + k0);
        uint64_t keep = 0;
        for (uint64_t mk = S->msk[i]; mk; mk &= mk - 1) {
            const unsigned j = (unsigned)__builtin_ctzll(mk);
            SIMD_DIST_AT(S->cx[j], S->cy[j], S->cz[j]);
            if (VM_ANY(in)) keep |= 1ull << j;
        }
        if (!keep) continue;
        const size_t bits = (size_t)__builtin_popcountll(keep);
        S->blk[k] = S->blk[i];
        S->msk[k] = keep;
        S->cum[k++] = c;
        c += ITEM_COST(bits);
        e += bits;
    }
    S->k = k;
    S->cum[k] = c;
    return e;
}

static const eval_isa SFX(isa) = {
    .kern = {SFX(block_psi31), SFX(block_psi30), SFX(block_psi32)},
    .drivers = {{{SFX(drive_psi31_all), SFX(drive_psi31_list), SFX(drive_psi31_gaps)},
                 {SFX(drive_psi31_all_stats), SFX(drive_psi31_list_stats),
                  SFX(drive_psi31_gaps_stats)}},
                {{SFX(drive_psi30_all), SFX(drive_psi30_list), SFX(drive_psi30_gaps)},
                 {SFX(drive_psi30_all_stats), SFX(drive_psi30_list_stats),
                  SFX(drive_psi30_gaps_stats)}},
                {{SFX(drive_psi32_all), SFX(drive_psi32_list), SFX(drive_psi32_gaps)},
                 {SFX(drive_psi32_all_stats), SFX(drive_psi32_list_stats),
                  SFX(drive_psi32_gaps_stats)}}},
    .cached = {{SFX(drive_cached_list), SFX(drive_cached_gaps)},
               {SFX(drive_cached_list_stats), SFX(drive_cached_gaps_stats)}},
    .fills = {SFX(fill_psi31), SFX(fill_psi30), SFX(fill_psi32)},
    .refine = SFX(refine),
    .write_block = SFX(write_block),
};

#undef SIMD_DIST_AT
#undef SIMD_DIST
#undef SIMD_WEIGHT
#undef SIMD_KERNEL
#undef SIMD_PAIR
#undef SIMD_DRIVER
#undef SIMD_DRIVERS
#undef SIMD_FILL
#undef T2
#undef PSI31_V
#undef PSI32_V
#undef SFX
#undef V_TARGET
#undef V_TARGET_POPCNT
#undef VF
#undef VI
#undef VM
#undef V_loadu_ps
#undef V_load_ps
#undef V_storeu_ps
#undef V_store_ps
#undef V_set1_ps
#undef V_setzero_ps
#undef V_add_ps
#undef V_sub_ps
#undef V_mul_ps
#undef V_max_ps
#undef V_fmadd_ps
#undef V_fnmadd_ps
#undef V_rsqrt_ps
#undef V_cmplt_mask
#undef V_mask3_fmadd_ps
#undef V_setzero_si
#undef V_set1_epi32
#undef V_add_epi32
#undef V_mask_inc_epi32
#undef V_count_gt0
#undef V_storeu_si
#undef V_store_si
#undef V_reduce_add_epi32
#undef V_reduce_max_ps
#undef V_interleave
#undef VM_ANY
#undef VM_BITS
#undef VM_FROM_BITS
