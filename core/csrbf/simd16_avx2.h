/* 16 float lanes as two AVX2 vectors: the operations eval_simd.h uses, lane by lane the same
 * as their AVX-512 namesakes except where noted. A mask (v16f) is a vector whose lanes are all
 * ones (in) or zero; bit l of its 16-bit form is lane l. Internal to csrbf_fast.c. */
#ifndef CSRBF_SIMD16_AVX2_H
#define CSRBF_SIMD16_AVX2_H

#include <immintrin.h>
#include <stdint.h>

typedef struct {
    __m256 lo, hi; /* lanes 0-7, 8-15 */
} v16f;
typedef struct {
    __m256i lo, hi;
} v16i;

#define V16_FN static inline __attribute__((target("avx2,fma"), always_inline))

V16_FN v16f v16_loadu_ps(const float *p) { return (v16f){_mm256_loadu_ps(p), _mm256_loadu_ps(p + 8)}; }
V16_FN v16f v16_load_ps(const float *p) { return (v16f){_mm256_load_ps(p), _mm256_load_ps(p + 8)}; }
V16_FN void v16_storeu_ps(float *p, v16f a)
{
    _mm256_storeu_ps(p, a.lo);
    _mm256_storeu_ps(p + 8, a.hi);
}
V16_FN void v16_store_ps(float *p, v16f a)
{
    _mm256_store_ps(p, a.lo);
    _mm256_store_ps(p + 8, a.hi);
}
V16_FN v16f v16_set1_ps(float x) { return (v16f){_mm256_set1_ps(x), _mm256_set1_ps(x)}; }
V16_FN v16f v16_setzero_ps(void) { return (v16f){_mm256_setzero_ps(), _mm256_setzero_ps()}; }
V16_FN v16f v16_add_ps(v16f a, v16f b) { return (v16f){_mm256_add_ps(a.lo, b.lo), _mm256_add_ps(a.hi, b.hi)}; }
V16_FN v16f v16_sub_ps(v16f a, v16f b) { return (v16f){_mm256_sub_ps(a.lo, b.lo), _mm256_sub_ps(a.hi, b.hi)}; }
V16_FN v16f v16_mul_ps(v16f a, v16f b) { return (v16f){_mm256_mul_ps(a.lo, b.lo), _mm256_mul_ps(a.hi, b.hi)}; }
V16_FN v16f v16_max_ps(v16f a, v16f b) { return (v16f){_mm256_max_ps(a.lo, b.lo), _mm256_max_ps(a.hi, b.hi)}; }
/* a b + c, one rounding */
V16_FN v16f v16_fmadd_ps(v16f a, v16f b, v16f c)
{
    return (v16f){_mm256_fmadd_ps(a.lo, b.lo, c.lo), _mm256_fmadd_ps(a.hi, b.hi, c.hi)};
}
/* -(a b) + c, one rounding */
V16_FN v16f v16_fnmadd_ps(v16f a, v16f b, v16f c)
{
    return (v16f){_mm256_fnmadd_ps(a.lo, b.lo, c.lo), _mm256_fnmadd_ps(a.hi, b.hi, c.hi)};
}
/* the 12-bit estimate of 1 / sqrt(a) (relative error at most 1.5 2^-12; AVX-512's is 2^-14) */
V16_FN v16f v16_rsqrt_ps(v16f a) { return (v16f){_mm256_rsqrt_ps(a.lo), _mm256_rsqrt_ps(a.hi)}; }
/* lanes where a < b (ordered, quiet) */
V16_FN v16f v16_cmplt_mask(v16f a, v16f b)
{
    return (v16f){_mm256_cmp_ps(a.lo, b.lo, _CMP_LT_OQ), _mm256_cmp_ps(a.hi, b.hi, _CMP_LT_OQ)};
}
/* a b + c where m, else c (c's bits kept) */
V16_FN v16f v16_mask3_fmadd_ps(v16f a, v16f b, v16f c, v16f m)
{
    return (v16f){_mm256_blendv_ps(c.lo, _mm256_fmadd_ps(a.lo, b.lo, c.lo), m.lo),
                  _mm256_blendv_ps(c.hi, _mm256_fmadd_ps(a.hi, b.hi, c.hi), m.hi)};
}
V16_FN v16i v16_setzero_si(void) { return (v16i){_mm256_setzero_si256(), _mm256_setzero_si256()}; }
V16_FN v16i v16_set1_epi32(int x) { return (v16i){_mm256_set1_epi32(x), _mm256_set1_epi32(x)}; }
V16_FN v16i v16_add_epi32(v16i a, v16i b)
{
    return (v16i){_mm256_add_epi32(a.lo, b.lo), _mm256_add_epi32(a.hi, b.hi)};
}
/* c + 1 where m (an all-ones lane is -1: subtracted) */
V16_FN v16i v16_mask_inc_epi32(v16i c, v16f m, v16i one)
{
    (void)one;
    return (v16i){_mm256_sub_epi32(c.lo, _mm256_castps_si256(m.lo)),
                  _mm256_sub_epi32(c.hi, _mm256_castps_si256(m.hi))};
}
/* the lanes of c above zero, counted */
V16_FN int v16_count_gt0(v16i c, v16i zero)
{
    unsigned lo = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(c.lo, zero.lo)));
    unsigned hi = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(c.hi, zero.hi)));
    return __builtin_popcount(lo | hi << 8);
}
V16_FN void v16_storeu_si(void *p, v16i a)
{
    _mm256_storeu_si256((__m256i *)p, a.lo);
    _mm256_storeu_si256((__m256i *)p + 1, a.hi);
}
V16_FN void v16_store_si(void *p, v16i a)
{
    _mm256_store_si256((__m256i *)p, a.lo);
    _mm256_store_si256((__m256i *)p + 1, a.hi);
}
V16_FN int v16_reduce_add_epi32(v16i a)
{
    __m256i s = _mm256_add_epi32(a.lo, a.hi);
    __m128i t = _mm_add_epi32(_mm256_castsi256_si128(s), _mm256_extracti128_si256(s, 1));
    t = _mm_add_epi32(t, _mm_shuffle_epi32(t, _MM_SHUFFLE(1, 0, 3, 2)));
    t = _mm_add_epi32(t, _mm_shuffle_epi32(t, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtsi128_si32(t);
}
V16_FN float v16_reduce_max_ps(v16f a)
{
    __m256 s = _mm256_max_ps(a.lo, a.hi);
    __m128 t = _mm_max_ps(_mm256_castps256_ps128(s), _mm256_extractf128_ps(s, 1));
    t = _mm_max_ps(t, _mm_shuffle_ps(t, t, _MM_SHUFFLE(1, 0, 3, 2)));
    t = _mm_max_ps(t, _mm_shuffle_ps(t, t, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(t);
}
/* any lane set */
V16_FN int v16m_any(v16f m) { return _mm256_movemask_ps(_mm256_or_ps(m.lo, m.hi)) != 0; }
/* the mask as 16 bits (bit l: lane l) */
V16_FN uint16_t v16m_bits(v16f m)
{
    return (uint16_t)((unsigned)_mm256_movemask_ps(m.lo) | (unsigned)_mm256_movemask_ps(m.hi) << 8);
}
/* the mask of 16 bits */
V16_FN v16f v16m_from_bits(uint16_t b)
{
    const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    const __m256i lo = _mm256_set1_epi32(b & 0xFF), hi = _mm256_set1_epi32(b >> 8);
    return (v16f){_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(lo, bit), bit)),
                  _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(hi, bit), bit))};
}
/* 8 x, y, z into 24 contiguous floats x0 y0 z0 x1 ... */
V16_FN void v8_interleave(float *out, __m256 x, __m256 y, __m256 z)
{
    __m256 rxy = _mm256_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0)); /* x0 x2 y0 y2 | x4 x6 y4 y6 */
    __m256 ryz = _mm256_shuffle_ps(y, z, _MM_SHUFFLE(3, 1, 3, 1)); /* y1 y3 z1 z3 | ... */
    __m256 rzx = _mm256_shuffle_ps(z, x, _MM_SHUFFLE(3, 1, 2, 0)); /* z0 z2 x1 x3 | ... */
    __m256 r03 = _mm256_shuffle_ps(rxy, rzx, _MM_SHUFFLE(2, 0, 2, 0)); /* x0 y0 z0 x1 | x4 y4 z4 x5 */
    __m256 r14 = _mm256_shuffle_ps(ryz, rxy, _MM_SHUFFLE(3, 1, 2, 0)); /* y1 z1 x2 y2 | y5 z5 x6 y6 */
    __m256 r25 = _mm256_shuffle_ps(rzx, ryz, _MM_SHUFFLE(3, 1, 3, 1)); /* z2 x3 y3 z3 | z6 x7 y7 z7 */
    _mm256_storeu_ps(out, _mm256_permute2f128_ps(r03, r14, 0x20));
    _mm256_storeu_ps(out + 8, _mm256_permute2f128_ps(r25, r03, 0x30));
    _mm256_storeu_ps(out + 16, _mm256_permute2f128_ps(r14, r25, 0x31));
}
/* 16 x, y, z into 48 contiguous floats */
V16_FN void v16_interleave(float *out, v16f x, v16f y, v16f z)
{
    v8_interleave(out, x.lo, y.lo, z.lo);
    v8_interleave(out + 24, x.hi, y.hi, z.hi);
}

#undef V16_FN
#endif
