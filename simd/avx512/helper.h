/* AVX-512 (F, DQ, VL, BW) vector verbs: 16 float lanes, compares into
 * __mmask16 lane masks (simd/scalar/helper.h documents each verb). */
#ifndef SHL_SIMD_HELPER_H
#define SHL_SIMD_HELPER_H

#include <immintrin.h>
#include <stddef.h>

#define SHL_VLEN 16
#define SHL_ISA_SUFFIX(name) name##_avx512

typedef __m512 vf;
typedef __mmask16 vm;

static inline vf vf_set1(float a) { return _mm512_set1_ps(a); }
static inline vf vf_load(const float *p) { return _mm512_loadu_ps(p); }
static inline void vf_store(float *p, vf a) { _mm512_storeu_ps(p, a); }
static inline vf vf_add(vf a, vf b) { return _mm512_add_ps(a, b); }
static inline vf vf_sub(vf a, vf b) { return _mm512_sub_ps(a, b); }
static inline vf vf_mul(vf a, vf b) { return _mm512_mul_ps(a, b); }
static inline vf vf_div(vf a, vf b) { return _mm512_div_ps(a, b); }
static inline vf vf_sqrt(vf a) { return _mm512_sqrt_ps(a); }
static inline vf vf_fma(vf a, vf b, vf c) { return _mm512_fmadd_ps(a, b, c); }
static inline vf vf_fms(vf a, vf b, vf c) { return _mm512_fmsub_ps(a, b, c); }
static inline vf vf_fnma(vf a, vf b, vf c) { return _mm512_fnmadd_ps(a, b, c); }
static inline vf vf_signmask(void) { return _mm512_set1_ps(-0.0f); }
static inline vf vf_abs(vf a) { return _mm512_andnot_ps(vf_signmask(), a); }
static inline vf vf_min(vf a, vf b) { return _mm512_min_ps(a, b); }
static inline vf vf_max(vf a, vf b) { return _mm512_max_ps(a, b); }
static inline vm vf_lt(vf a, vf b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
static inline vm vf_gt(vf a, vf b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
static inline vf vf_sel(vm m, vf a, vf b) { return _mm512_mask_blend_ps(m, b, a); }
static inline vf vf_mulsign(vf a, vf b) { return _mm512_xor_ps(a, _mm512_and_ps(b, vf_signmask())); }
static inline vf vf_copysign(vf a, vf b)
{
    return _mm512_or_ps(_mm512_andnot_ps(vf_signmask(), a), _mm512_and_ps(b, vf_signmask()));
}

/* Double lanes (grid interpolation, simd/interp_batch.h): 8 per vector. */
#define SHL_VDLEN 8
typedef __m512d vd;
static inline vd vd_set1(double a) { return _mm512_set1_pd(a); }
static inline vd vd_load_float(const float *p) { return _mm512_cvtps_pd(_mm256_loadu_ps(p)); } /* p[0..7] widened */
static inline void vd_store(double *p, vd a) { _mm512_storeu_pd(p, a); }
static inline vd vd_mul(vd a, vd b) { return _mm512_mul_pd(a, b); }
static inline vd vd_fma(vd a, vd b, vd c) { return _mm512_fmadd_pd(a, b, c); }

/* Tile transpose-store: src holds 16 rows of 16 lanes (row i at src + 16 i);
 * lane j of every row goes to dst + j * stride (16 floats), for j < nvalid.
 * As simd/avx2/helper.h within each 128-bit block (unpack pairs of rows,
 * shuffle pairs of pairs: u[4g + k] holds element 4q + k of rows 4g..4g+3 in
 * block q), then two rounds of 128-bit block shuffles gather block q of
 * u[k], u[4 + k], u[8 + k], u[12 + k] into column 4q + k. */
static inline void vf_store_transposed(const float *src, float *dst, size_t stride, int nvalid)
{
    __m512 u[16];
    for (int g = 0; g < 4; ++g) {
        const float *s = src + 64 * g;
        const __m512 r0 = _mm512_loadu_ps(s), r1 = _mm512_loadu_ps(s + 16);
        const __m512 r2 = _mm512_loadu_ps(s + 32), r3 = _mm512_loadu_ps(s + 48);
        const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
        const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
        u[4 * g] = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
        u[4 * g + 1] = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
        u[4 * g + 2] = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
        u[4 * g + 3] = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
    }
    for (int k = 0; k < 4; ++k) {
        /* blocks 0, 1 (lo) or 2, 3 (hi) of u[k] and u[4 + k], of u[8 + k] and u[12 + k] */
        const __m512 ab_lo = _mm512_shuffle_f32x4(u[k], u[4 + k], 0x44), ab_hi = _mm512_shuffle_f32x4(u[k], u[4 + k], 0xEE);
        const __m512 cd_lo = _mm512_shuffle_f32x4(u[8 + k], u[12 + k], 0x44), cd_hi = _mm512_shuffle_f32x4(u[8 + k], u[12 + k], 0xEE);
        const __m512 col[4] = {_mm512_shuffle_f32x4(ab_lo, cd_lo, 0x88), _mm512_shuffle_f32x4(ab_lo, cd_lo, 0xDD),
                               _mm512_shuffle_f32x4(ab_hi, cd_hi, 0x88), _mm512_shuffle_f32x4(ab_hi, cd_hi, 0xDD)};
        for (int q = 0; q < 4; ++q)
            if (4 * q + k < nvalid) _mm512_storeu_ps(dst + (size_t)(4 * q + k) * stride, col[q]);
    }
}

#endif
