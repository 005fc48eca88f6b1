/* csrbf_evaluate: T(x) at every vertex. Blocks of CSRBF_BLOCK Morton-sorted vertices are
 * matched against the centres whose support meets the block's box; within a block the loop
 * runs over the selected centres and vectorises over the vertices (SIMD clones for AVX-512,
 * AVX2+FMA and the baseline, picked at load time). Blocks run in parallel with OpenMP. */
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

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#define CSRBF_AVX512 1
/* AVX-512 kernels (B = 16 = one vector). r = r2 * rsqrt(r2): the 14-bit estimate plus one
 * Newton step (relative error below 1e-7) replaces the slower vsqrtps; lanes outside the
 * support are masked off (their accumulators keep their bits). */
#define AVX512_KERNEL(NAME, PSI)                                                               \
    __attribute__((target("avx512f,fma"))) static void NAME(                                   \
        const float *restrict x, const float *restrict y, const float *restrict z,            \
        const uint32_t *restrict list, size_t k, const float *restrict cx,                     \
        const float *restrict cy, const float *restrict cz, const float *restrict ax,          \
        const float *restrict ay, const float *restrict az, float inv_r2,                      \
        float *restrict accx, float *restrict accy, float *restrict accz, int *restrict cnt)   \
    {                                                                                          \
        const __m512 X = _mm512_loadu_ps(x), Y = _mm512_loadu_ps(y), Z = _mm512_loadu_ps(z);   \
        const __m512 one = _mm512_set1_ps(1.0f), half = _mm512_set1_ps(0.5f),                  \
                     three_half = _mm512_set1_ps(1.5f), tiny = _mm512_set1_ps(1e-30f),         \
                     ir2 = _mm512_set1_ps(inv_r2);                                             \
        __m512 sx = _mm512_set1_ps(-0.0f), sy = sx, sz = sx;                                   \
        __m512i sc = _mm512_setzero_si512();                                                   \
        const __m512i ione = _mm512_set1_epi32(1);                                             \
        for (size_t t = 0; t < k; t++) {                                                       \
            const uint32_t j = list[t];                                                        \
            __m512 dx = _mm512_sub_ps(X, _mm512_set1_ps(cx[j]));                               \
            __m512 dy = _mm512_sub_ps(Y, _mm512_set1_ps(cy[j]));                               \
            __m512 dz = _mm512_sub_ps(Z, _mm512_set1_ps(cz[j]));                               \
            __m512 r2 = _mm512_mul_ps(dx, dx);                                                 \
            r2 = _mm512_fmadd_ps(dy, dy, r2);                                                  \
            r2 = _mm512_fmadd_ps(dz, dz, r2);                                                  \
            r2 = _mm512_mul_ps(r2, ir2);                                                       \
            __mmask16 in = _mm512_cmp_ps_mask(r2, one, _CMP_LT_OQ);                            \
            if (!in) continue;                                                                 \
            __m512 q = _mm512_max_ps(r2, tiny);                                                \
            __m512 e = _mm512_rsqrt14_ps(q);                                                   \
            __m512 hq = _mm512_mul_ps(half, q);                                                \
            e = _mm512_mul_ps(e, _mm512_fnmadd_ps(_mm512_mul_ps(hq, e), e, three_half));       \
            __m512 r = _mm512_mul_ps(q, e);                                                    \
            __m512 t1 = _mm512_sub_ps(one, r);                                                 \
            __m512 w = PSI;                                                                    \
            sx = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(ax[j]), sx, in);                      \
            sy = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(ay[j]), sy, in);                      \
            sz = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(az[j]), sz, in);                      \
            sc = _mm512_mask_add_epi32(sc, in, sc, ione);                                      \
        }                                                                                      \
        _mm512_storeu_ps(accx, sx);                                                            \
        _mm512_storeu_ps(accy, sy);                                                            \
        _mm512_storeu_ps(accz, sz);                                                            \
        _mm512_storeu_si512(cnt, sc);                                                          \
    }

#define T2 _mm512_mul_ps(t1, t1)
AVX512_KERNEL(block_psi31_avx512,
              _mm512_mul_ps(_mm512_mul_ps(T2, T2), _mm512_fmadd_ps(_mm512_set1_ps(4.0f), r, one)))
AVX512_KERNEL(block_psi30_avx512, T2)
AVX512_KERNEL(block_psi32_avx512,
              _mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(T2, T2), T2),
                            _mm512_fmadd_ps(_mm512_fmadd_ps(_mm512_set1_ps(35.0f / 3.0f), r,
                                                            _mm512_set1_ps(6.0f)),
                                            r, one)))
#undef T2

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

__attribute__((target("avx512f"))) static void write_block_avx512(
    float *restrict out, const float *restrict x, const float *restrict y,
    const float *restrict z, const float *restrict accx, const float *restrict accy,
    const float *restrict accz)
{
    interleave_avx512(out, _mm512_add_ps(_mm512_loadu_ps(x), _mm512_loadu_ps(accx)),
                      _mm512_add_ps(_mm512_loadu_ps(y), _mm512_loadu_ps(accy)),
                      _mm512_add_ps(_mm512_loadu_ps(z), _mm512_loadu_ps(accz)));
}

/* One centre's contribution to the 16 lanes (shared by the fused drivers below). */
#define AVX512_PAIR(PSI, J)                                                                    \
    do {                                                                                       \
        __m512 dx = _mm512_sub_ps(X, _mm512_set1_ps(cx[J]));                                   \
        __m512 dy = _mm512_sub_ps(Y, _mm512_set1_ps(cy[J]));                                   \
        __m512 dz = _mm512_sub_ps(Z, _mm512_set1_ps(cz[J]));                                   \
        __m512 r2 = _mm512_mul_ps(dx, dx);                                                     \
        r2 = _mm512_fmadd_ps(dy, dy, r2);                                                      \
        r2 = _mm512_fmadd_ps(dz, dz, r2);                                                      \
        r2 = _mm512_mul_ps(r2, ir2);                                                           \
        __mmask16 in = _mm512_cmp_ps_mask(r2, one, _CMP_LT_OQ);                                \
        __m512 q = _mm512_max_ps(r2, tiny);                                                    \
        __m512 e = _mm512_rsqrt14_ps(q);                                                       \
        __m512 hq = _mm512_mul_ps(half, q);                                                    \
        e = _mm512_mul_ps(e, _mm512_fnmadd_ps(_mm512_mul_ps(hq, e), e, three_half));           \
        __m512 r = _mm512_mul_ps(q, e);                                                        \
        __m512 t1 = _mm512_sub_ps(one, r);                                                     \
        __m512 w = PSI;                                                                        \
        sx = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(ax[J]), sx, in);                          \
        sy = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(ay[J]), sy, in);                          \
        sz = _mm512_mask3_fmadd_ps(w, _mm512_set1_ps(az[J]), sz, in);                          \
        if (stats_on) cntv = _mm512_mask_add_epi32(cntv, in, cntv, ione);                       \
    } while (0)

/* Statistics of a run of blocks (the fast path counts them per block, in registers). */
typedef struct {
    size_t pairs, moved;
    float maxd2;
} block_stats;

/* The fast path without polynomial: blocks b0..b1 end to end. mask (centres j < 32 whose
 * support meets the block) or, with mask NULL, all m centres. Untouched blocks are copied;
 * touched ones computed in registers and stored interleaved. With STATS (a compile-time
 * constant: a second copy of the driver) the pairs in support are counted per lane with one
 * masked add per pair, and moved vertices and the largest squared displacement per block,
 * into *bs (padding lanes excluded). */
#define AVX512_DRIVER(NAME, PSI, STATS)                                                        \
    __attribute__((target("avx512f,fma"))) static void NAME(                                   \
        const csrbf_points *P, float *restrict out, size_t b0, size_t b1,                      \
        const uint32_t *restrict mask, size_t m, const float *restrict cx,                     \
        const float *restrict cy, const float *restrict cz, const float *restrict ax,          \
        const float *restrict ay, const float *restrict az, float inv_r2, block_stats *bs,     \
        uint8_t *restrict cur, const uint8_t *restrict prev)                                   \
    {                                                                                          \
        const __m512 one = _mm512_set1_ps(1.0f), half = _mm512_set1_ps(0.5f),                 \
                     three_half = _mm512_set1_ps(1.5f), tiny = _mm512_set1_ps(1e-30f),         \
                     ir2 = _mm512_set1_ps(inv_r2);                                             \
        const __m512i ione = _mm512_set1_epi32(1), izero = _mm512_setzero_si512();             \
        enum { stats_on = STATS };                                                             \
        __m512i pairv = izero;                                                                 \
        __m512 maxd = _mm512_setzero_ps();                                                     \
        size_t nmoved = 0;                                                                     \
        const size_t n = P->n;                                                                 \
        for (size_t b = b0; b < b1; b++) {                                                     \
            const size_t k0 = b * B, nv = k0 + B <= n ? B : n - k0;                            \
            float *o = out + 3 * k0;                                                           \
            uint32_t mk = mask ? mask[b] : 0;                                                  \
            if (cur) cur[b] = !mask || mk;                                                     \
            if (mask && !mk) {                                                                 \
                if (prev && !prev[b]) continue; /* the output holds the base already */        \
                if (nv == B)                                                                   \
                    interleave_avx512(o, _mm512_loadu_ps(P->s[0] + k0),                        \
                                      _mm512_loadu_ps(P->s[1] + k0),                           \
                                      _mm512_loadu_ps(P->s[2] + k0));                          \
                else                                                                           \
                    memcpy(o, P->xyz + 3 * k0, nv * 3 * sizeof(float));                        \
                continue;                                                                      \
            }                                                                                  \
            const __m512 X = _mm512_loadu_ps(P->s[0] + k0), Y = _mm512_loadu_ps(P->s[1] + k0), \
                         Z = _mm512_loadu_ps(P->s[2] + k0);                                    \
            __m512 sx = _mm512_set1_ps(-0.0f), sy = sx, sz = sx;                               \
            __m512i cntv = izero;                                                              \
            if (mask) {                                                                        \
                while (mk) {                                                                   \
                    const unsigned j = (unsigned)__builtin_ctz(mk);                            \
                    mk &= mk - 1;                                                              \
                    AVX512_PAIR(PSI, j);                                                       \
                }                                                                              \
            } else {                                                                           \
                for (size_t j = 0; j < m; j++) AVX512_PAIR(PSI, j);                            \
            }                                                                                  \
            if (STATS) {                                                                       \
                const __mmask16 valid = nv == B ? (__mmask16)0xFFFF                            \
                                                : (__mmask16)((1u << nv) - 1u);                \
                pairv = _mm512_mask_add_epi32(pairv, valid, pairv, cntv);                      \
                nmoved += (size_t)__builtin_popcount(                                          \
                    (unsigned)_mm512_mask_cmpgt_epi32_mask(valid, cntv, izero));               \
                __m512 d2 = _mm512_mul_ps(sx, sx);                                             \
                d2 = _mm512_fmadd_ps(sy, sy, d2);                                              \
                d2 = _mm512_fmadd_ps(sz, sz, d2);                                              \
                maxd = _mm512_mask_max_ps(maxd, valid, maxd, d2);                              \
            }                                                                                  \
            _Alignas(64) float acc[3][B];                                                      \
            _mm512_store_ps(acc[0], sx);                                                       \
            _mm512_store_ps(acc[1], sy);                                                       \
            _mm512_store_ps(acc[2], sz);                                                       \
            if (nv == B)                                                                       \
                interleave_avx512(o, _mm512_add_ps(X, sx), _mm512_add_ps(Y, sy),               \
                                  _mm512_add_ps(Z, sz));                                       \
            else                                                                               \
                for (size_t v = 0; v < nv; v++) {                                              \
                    o[3 * v] = P->s[0][k0 + v] + acc[0][v];                                    \
                    o[3 * v + 1] = P->s[1][k0 + v] + acc[1][v];                                \
                    o[3 * v + 2] = P->s[2][k0 + v] + acc[2][v];                                \
                }                                                                              \
        }                                                                                      \
        if (STATS) {                                                                           \
            bs->pairs += (size_t)(uint32_t)_mm512_reduce_add_epi32(pairv);                     \
            bs->moved += nmoved;                                                               \
            float mx = _mm512_reduce_max_ps(maxd);                                             \
            if (mx > bs->maxd2) bs->maxd2 = mx;                                                \
        }                                                                                      \
        (void)bs;                                                                              \
    }

#define T2 _mm512_mul_ps(t1, t1)
#define PSI31_AVX512 _mm512_mul_ps(_mm512_mul_ps(T2, T2), _mm512_fmadd_ps(_mm512_set1_ps(4.0f), r, one))
#define PSI32_AVX512                                                                           \
    _mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(T2, T2), T2),                                    \
                  _mm512_fmadd_ps(_mm512_fmadd_ps(_mm512_set1_ps(35.0f / 3.0f), r,             \
                                                  _mm512_set1_ps(6.0f)),                       \
                                  r, one))
AVX512_DRIVER(drive_psi31_avx512, PSI31_AVX512, 0)
AVX512_DRIVER(drive_psi30_avx512, T2, 0)
AVX512_DRIVER(drive_psi32_avx512, PSI32_AVX512, 0)
AVX512_DRIVER(drive_psi31_avx512_stats, PSI31_AVX512, 1)
AVX512_DRIVER(drive_psi30_avx512_stats, T2, 1)
AVX512_DRIVER(drive_psi32_avx512_stats, PSI32_AVX512, 1)
#undef PSI31_AVX512
#undef PSI32_AVX512
#undef T2

typedef void (*drive_fn)(const csrbf_points *, float *, size_t, size_t, const uint32_t *,
                         size_t, const float *, const float *, const float *, const float *,
                         const float *, const float *, float, block_stats *, uint8_t *,
                         const uint8_t *);

static int have_avx512(void)
{
    static int known = -1;
    if (known < 0) {
        __builtin_cpu_init();
        known = __builtin_cpu_supports("avx512f") != 0; /* benign race: same value */
    }
    return known;
}
#else
#define CSRBF_AVX512 0
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

/* Masks of the centres (m <= 32) whose support meets each block's box, in float with a
 * conservative margin (the kernel decides each pair exactly). Vectorised over blocks. */
CSRBF_CLONES static void block_masks(const csrbf_points *P, size_t b0, size_t b1, size_t m,
                                     const float *cx, const float *cy, const float *cz,
                                     float r2c, uint32_t *restrict mask)
{
    const float *lx = P->lo[0], *ly = P->lo[1], *lz = P->lo[2];
    const float *hx = P->hi[0], *hy = P->hi[1], *hz = P->hi[2];
    for (size_t b = b0; b < b1; b++) mask[b] = 0;
    for (size_t j = 0; j < m; j++) {
        const float px = cx[j], py = cy[j], pz = cz[j];
        const uint32_t bit = 1u << j;
#pragma omp simd
        for (size_t b = b0; b < b1; b++) {
            float ex = lx[b] - px > px - hx[b] ? lx[b] - px : px - hx[b];
            float ey = ly[b] - py > py - hy[b] ? ly[b] - py : py - hy[b];
            float ez = lz[b] - pz > pz - hz[b] ? lz[b] - pz : pz - hz[b];
            ex = ex > 0.0f ? ex : 0.0f;
            ey = ey > 0.0f ? ey : 0.0f;
            ez = ez > 0.0f ? ez : 0.0f;
            mask[b] |= ex * ex + ey * ey + ez * ez < r2c ? bit : 0u;
        }
    }
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
    if (m <= 32 || cells > (double)m) {
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

/* Persistent-output state of csrbf_evaluate_touched (see csrbf.h). */
struct csrbf_touch {
    const csrbf_points *points; /* the points it was made for */
    size_t nblocks;
    uint8_t *cur, *prev;        /* per block: rewritten from the kernel this call / last call */
    int full;                   /* the next call writes every block */
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
    t->cur = calloc(t->nblocks, 1);
    t->prev = calloc(t->nblocks, 1);
    t->ranges = malloc((t->nblocks + 1) * 2 * sizeof *t->ranges);
    if (!t->cur || !t->prev || !t->ranges) {
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
    free((*tp)->cur);
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
    memset(t->prev, 0, t->nblocks);
    t->nranges = 0;
}

size_t csrbf_touch_ranges(const csrbf_touch *t, const uint32_t **ranges)
{
    if (ranges) *ranges = t ? t->ranges : NULL;
    return t ? t->nranges : 0;
}

int csrbf_evaluate_touched(const csrbf_solver *cs, const csrbf_points *P, csrbf_touch *touch,
                           float *out, unsigned flags, csrbf_eval_stats *st)
{
    if (!touch || touch->points != P || !P || touch->nblocks != P->nblocks)
        return CSRBF_ERR_INVALID;
    return evaluate_impl(cs, P, out, flags, st, touch);
}

static int evaluate_impl(const csrbf_solver *cs, const csrbf_points *P, float *out,
                         unsigned flags, csrbf_eval_stats *st, csrbf_touch *touch)
{
    if (!cs || !P || !out || (flags & ~(unsigned)CSRBF_EVAL_JACOBIAN)) return CSRBF_ERR_INVALID;
    if (!cs->have_start) return CSRBF_ERR_STATE;
    uint8_t *tcur = touch ? touch->cur : NULL;
    const uint8_t *tprev = touch && !touch->full ? touch->prev : NULL;
    /* The scratch buffer is the only state evaluate touches; a concurrent caller that finds it
     * busy allocates its own. The solver itself is read-only here. */
    csrbf_solver *s = (csrbf_solver *)cs;
    const size_t n = P->n, nb = P->nblocks, m = s->m;
    const int poly = s->k > 0, want_jac = st && (flags & CSRBF_EVAL_JACOBIAN);
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
    const int use_mask = !all_in && m <= 32;
    block_fn kern = s->opt.kernel == CSRBF_PSI30   ? block_psi30
                    : s->opt.kernel == CSRBF_PSI32 ? block_psi32
                                                   : block_psi31;
    int avx512 = 0;
#if CSRBF_AVX512 && CSRBF_BLOCK == 16
    avx512 = have_avx512();
    if (avx512)
        kern = s->opt.kernel == CSRBF_PSI30   ? block_psi30_avx512
               : s->opt.kernel == CSRBF_PSI32 ? block_psi32_avx512
                                              : block_psi31_avx512;
#endif

    size_t per_thread = align64(m * sizeof(uint32_t));
    size_t mask_bytes = use_mask ? align64(nb * sizeof(uint32_t)) : 0;
    size_t need = mask_bytes + (size_t)nt * per_thread;
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
        mem = s->scratch;
    } else {
        mem = malloc(need);
        if (!mem) return CSRBF_ERR_NOMEM;
        own = 1;
    }
    uint32_t *mask = mem;
    unsigned char *tbase = (unsigned char *)mem + mask_bytes;

    /* work estimate: vertex-centre pairs, each centre counting the fraction of the vertex
     * box its support's bounding cube covers (axis by axis); small work stays on the
     * calling thread, where a fork/join would cost more than it saves */
    double est = 0.0;
    for (size_t i = 0; i < m; i++) {
        double frac = 1.0;
        for (int a = 0; a < 3; a++) {
            double ext = P->bhi[a] - P->blo[a], c = s->c[3 * i + a];
            if (ext <= 0.0) continue;
            double ov = fmin(c + s->R, P->bhi[a]) - fmax(c - s->R, P->blo[a]);
            frac *= ov > 0.0 ? ov / ext : 0.0;
        }
        est += frac;
    }
    size_t work = (size_t)((double)n * est);
    int threads = work > 50000 ? nt : 1;

    /* the fused AVX-512 path: no polynomial, no Jacobian, all centres or a mask (statistics
     * are counted inside it) */
    const int fast = avx512 && !want_jac && !poly && (all_in || use_mask);
    size_t pairs = 0, moved = 0;
    double maxd = 0.0, minjac = 1.0;
    const float inv_r2 = (float)(1.0 / R2), r2c = (float)(R2 * (1.0 + 1e-5)) + 1e-30f;
    const float pc0 = s->fpc[0], pc1 = s->fpc[1], pc2 = s->fpc[2];
    const float *G = s->fG, *g0 = s->fg0;
    const float *fcx = s->fc[0], *fcy = s->fc[1], *fcz = s->fc[2];
    const float *fax = s->fa[0], *fay = s->fa[1], *faz = s->fa[2];

#pragma omp parallel num_threads(threads) reduction(+ : pairs, moved) reduction(max : maxd) \
    reduction(min : minjac)
    {
        int tid = omp_get_thread_num();
        uint32_t *list = (uint32_t *)(tbase + (size_t)tid * per_thread);
        if (use_mask) {
            /* phase 1: masks, in chunks of 1024 blocks */
#pragma omp for schedule(static)
            for (size_t c = 0; c < (nb + 1023) / 1024; c++) {
                size_t b0 = c * 1024, b1 = b0 + 1024 < nb ? b0 + 1024 : nb;
                block_masks(P, b0, b1, m, fcx, fcy, fcz, r2c, mask);
            }
        }
        if (all_in)
            for (size_t i = 0; i < m; i++) list[i] = (uint32_t)i;
#if CSRBF_AVX512 && CSRBF_BLOCK == 16
        if (fast) {
            drive_fn drive = s->opt.kernel == CSRBF_PSI30   ? drive_psi30_avx512
                             : s->opt.kernel == CSRBF_PSI32 ? drive_psi32_avx512
                                                            : drive_psi31_avx512;
            if (st)
                drive = s->opt.kernel == CSRBF_PSI30   ? drive_psi30_avx512_stats
                        : s->opt.kernel == CSRBF_PSI32 ? drive_psi32_avx512_stats
                                                       : drive_psi31_avx512_stats;
            block_stats bs = {0, 0, 0.0f};
#pragma omp for schedule(dynamic, 1)
            for (size_t c = 0; c < (nb + 63) / 64; c++) {
                size_t b0 = c * 64, b1 = b0 + 64 < nb ? b0 + 64 : nb;
                drive(P, out, b0, b1, use_mask ? mask : NULL, m, fcx, fcy, fcz, fax, fay, faz,
                      inv_r2, &bs, tcur, tprev);
            }
            pairs += bs.pairs;
            moved += bs.moved;
            if ((double)bs.maxd2 > maxd) maxd = bs.maxd2;
        } else
#endif
        {
        _Alignas(64) float accx[B], accy[B], accz[B];
        _Alignas(64) int cnt[B];
#pragma omp for schedule(static, 64)
        for (size_t b = 0; b < nb; b++) {
            size_t k0 = b * B, nv = b + 1 < nb ? B : n - k0;
            float *o = out + 3 * k0;
            size_t k = m;
            if (use_mask) {
                uint32_t mk = mask[b];
                if (!mk && !poly && !want_jac) { /* outside every support: the base */
                    if (tcur) tcur[b] = 0;
                    if (!tprev || tprev[b]) memcpy(o, P->xyz + 3 * k0, nv * 3 * sizeof(float));
                    continue;
                }
                k = 0;
                while (mk) {
                    list[k++] = (uint32_t)__builtin_ctz(mk);
                    mk &= mk - 1;
                }
            } else if (!all_in) {
                k = select_centres(s, P, b, list, 0);
                if (!k && !poly && !want_jac) {
                    if (tcur) tcur[b] = 0;
                    if (!tprev || tprev[b]) memcpy(o, P->xyz + 3 * k0, nv * 3 * sizeof(float));
                    continue;
                }
            }
            if (tcur) tcur[b] = 1;
            const float *x = P->s[0] + k0, *y = P->s[1] + k0, *z = P->s[2] + k0;
            kern(x, y, z, list, k, fcx, fcy, fcz, fax, fay, faz, inv_r2, accx, accy, accz, cnt);
            if (poly)
                for (int v = 0; v < B; v++) {
                    float ex = x[v] - pc0, ey = y[v] - pc1, ez = z[v] - pc2;
                    accx[v] += g0[0] + G[0] * ex + G[1] * ey + G[2] * ez;
                    accy[v] += g0[1] + G[3] * ex + G[4] * ey + G[5] * ez;
                    accz[v] += g0[2] + G[6] * ex + G[7] * ey + G[8] * ez;
                }
#if CSRBF_AVX512 && CSRBF_BLOCK == 16
            if (avx512 && nv == B)
                write_block_avx512(o, x, y, z, accx, accy, accz);
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
    }
    if (own)
        free(mem);
    else
        atomic_flag_clear(&s->scratch_busy);
    if (touch) { /* the rewritten blocks as vertex ranges, then this call becomes the last */
        size_t nr = 0;
        for (size_t b = 0; b < nb;) {
            if (!(touch->full || touch->cur[b] || touch->prev[b])) {
                b++;
                continue;
            }
            size_t b0 = b;
            while (b < nb && (touch->full || touch->cur[b] || touch->prev[b])) b++;
            size_t v1 = b * B < n ? b * B : n;
            touch->ranges[2 * nr] = (uint32_t)(b0 * B);
            touch->ranges[2 * nr + 1] = (uint32_t)(v1 - b0 * B);
            nr++;
        }
        touch->nranges = nr;
        uint8_t *tmp = touch->prev;
        touch->prev = touch->cur;
        touch->cur = tmp;
        touch->full = 0;
    }
    if (st) {
        st->pairs = pairs;
        st->moved = moved;
        st->max_displacement = sqrt(maxd);
        st->min_jacobian_det = minjac;
    }
    return CSRBF_OK;
}
