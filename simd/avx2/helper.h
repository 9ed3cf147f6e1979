/* AVX2 + FMA vector verbs: 8 float lanes (simd/scalar/helper.h documents each). */
#ifndef SHL_SIMD_HELPER_H
#define SHL_SIMD_HELPER_H

#include <immintrin.h>
#include <stddef.h>

#define SHL_VLEN 8
#define SHL_ISA_SUFFIX(name) name##_avx2

typedef __m256 vf;
typedef __m256 vm;

static inline vf vf_set1(float a) { return _mm256_set1_ps(a); }
static inline vf vf_load(const float *p) { return _mm256_loadu_ps(p); }
static inline void vf_store(float *p, vf a) { _mm256_storeu_ps(p, a); }
static inline vf vf_add(vf a, vf b) { return _mm256_add_ps(a, b); }
static inline vf vf_sub(vf a, vf b) { return _mm256_sub_ps(a, b); }
static inline vf vf_mul(vf a, vf b) { return _mm256_mul_ps(a, b); }
static inline vf vf_div(vf a, vf b) { return _mm256_div_ps(a, b); }
static inline vf vf_sqrt(vf a) { return _mm256_sqrt_ps(a); }
static inline vf vf_fma(vf a, vf b, vf c) { return _mm256_fmadd_ps(a, b, c); }
static inline vf vf_fms(vf a, vf b, vf c) { return _mm256_fmsub_ps(a, b, c); }
static inline vf vf_fnma(vf a, vf b, vf c) { return _mm256_fnmadd_ps(a, b, c); }
static inline vf vf_signmask(void) { return _mm256_set1_ps(-0.0f); }
static inline vf vf_abs(vf a) { return _mm256_andnot_ps(vf_signmask(), a); }
static inline vf vf_min(vf a, vf b) { return _mm256_min_ps(a, b); }
static inline vf vf_max(vf a, vf b) { return _mm256_max_ps(a, b); }
static inline vm vf_lt(vf a, vf b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline vm vf_gt(vf a, vf b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline vf vf_sel(vm m, vf a, vf b) { return _mm256_blendv_ps(b, a, m); }
static inline vf vf_mulsign(vf a, vf b) { return _mm256_xor_ps(a, _mm256_and_ps(b, vf_signmask())); }
static inline vf vf_copysign(vf a, vf b)
{
    return _mm256_or_ps(_mm256_andnot_ps(vf_signmask(), a), _mm256_and_ps(b, vf_signmask()));
}

/* Double lanes (grid interpolation, simd/interp_batch.h): 4 per vector. */
#define SHL_VDLEN 4
typedef __m256d vd;
static inline vd vd_set1(double a) { return _mm256_set1_pd(a); }
static inline vd vd_load_float(const float *p) { return _mm256_cvtps_pd(_mm_loadu_ps(p)); } /* p[0..3] widened */
static inline void vd_store(double *p, vd a) { _mm256_storeu_pd(p, a); }
static inline vd vd_add(vd a, vd b) { return _mm256_add_pd(a, b); }
static inline vd vd_mul(vd a, vd b) { return _mm256_mul_pd(a, b); }
static inline vd vd_fma(vd a, vd b, vd c) { return _mm256_fmadd_pd(a, b, c); }

/* Tile transpose-store: src holds 8 rows of 8 lanes (row i at src + 8 i); lane j
 * of every row goes to dst + j * stride (8 floats), for j < nvalid.  Unpack
 * pairs of rows, shuffle pairs of pairs, then swap 128-bit halves. */
static inline void vf_store_transposed(const float *src, float *dst, size_t stride, int nvalid)
{
    const __m256 r0 = _mm256_loadu_ps(src), r1 = _mm256_loadu_ps(src + 8), r2 = _mm256_loadu_ps(src + 16);
    const __m256 r3 = _mm256_loadu_ps(src + 24), r4 = _mm256_loadu_ps(src + 32), r5 = _mm256_loadu_ps(src + 40);
    const __m256 r6 = _mm256_loadu_ps(src + 48), r7 = _mm256_loadu_ps(src + 56);
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
    const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
    const __m256 t4 = _mm256_unpacklo_ps(r4, r5), t5 = _mm256_unpackhi_ps(r4, r5);
    const __m256 t6 = _mm256_unpacklo_ps(r6, r7), t7 = _mm256_unpackhi_ps(r6, r7);
    const __m256 u0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 u1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 u3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 u5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 u7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
    _mm256_storeu_ps(dst, _mm256_permute2f128_ps(u0, u4, 0x20));
    if (nvalid > 1) _mm256_storeu_ps(dst + stride, _mm256_permute2f128_ps(u1, u5, 0x20));
    if (nvalid > 2) _mm256_storeu_ps(dst + 2 * stride, _mm256_permute2f128_ps(u2, u6, 0x20));
    if (nvalid > 3) _mm256_storeu_ps(dst + 3 * stride, _mm256_permute2f128_ps(u3, u7, 0x20));
    if (nvalid > 4) _mm256_storeu_ps(dst + 4 * stride, _mm256_permute2f128_ps(u0, u4, 0x31));
    if (nvalid > 5) _mm256_storeu_ps(dst + 5 * stride, _mm256_permute2f128_ps(u1, u5, 0x31));
    if (nvalid > 6) _mm256_storeu_ps(dst + 6 * stride, _mm256_permute2f128_ps(u2, u6, 0x31));
    if (nvalid > 7) _mm256_storeu_ps(dst + 7 * stride, _mm256_permute2f128_ps(u3, u7, 0x31));
}

#endif
