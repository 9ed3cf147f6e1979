/* AVX-512 (F, DQ, VL, BW) vector verbs: 16 float lanes, compares into
 * __mmask16 lane masks (simd/scalar/helper.h documents each verb).
 * With SHL_AVX512_EMULATE (make AVX512_EMULATE=1, make test-avx512-emu) the
 * same verbs compile through SIMDe's AVX-512 emulation in AVX2 + FMA code:
 * its native aliases map the _mm512_* names and __m512* types to simde's. */
#ifndef SHL_SIMD_HELPER_H
#define SHL_SIMD_HELPER_H

#ifdef SHL_AVX512_EMULATE
#define SIMDE_ENABLE_NATIVE_ALIASES
#include <simde/x86/avx512.h>
#undef _mm512_shuffle_f32x4 /* emulated by SIMDe 0.7.4, without its alias */
#define _mm512_shuffle_f32x4(a, b, imm8) simde_mm512_shuffle_f32x4(a, b, imm8)
#else
#include <immintrin.h>
#endif
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
#ifdef SHL_AVX512_EMULATE
static inline vd vd_load_float(const float *p) /* SIMDe 0.7.4 has no _mm512_cvtps_pd */
{
    double wide[8];
    for (int k = 0; k < 8; ++k) wide[k] = p[k];
    return _mm512_loadu_pd(wide);
}
#else
static inline vd vd_load_float(const float *p) { return _mm512_cvtps_pd(_mm256_loadu_ps(p)); } /* p[0..7] widened */
#endif
static inline void vd_store(double *p, vd a) { _mm512_storeu_pd(p, a); }
static inline vd vd_add(vd a, vd b) { return _mm512_add_pd(a, b); }
static inline vd vd_mul(vd a, vd b) { return _mm512_mul_pd(a, b); }
static inline vd vd_fma(vd a, vd b, vd c) { return _mm512_fmadd_pd(a, b, c); }
/* Rows shorter than 8 doubles (lmax 1: 4 coefficients) take the avx2 kernel
 * (4 lanes; avx512 support includes AVX2 and FMA) instead of the scalar
 * reference: 2.3x faster (bench/bench_simd.c --isa-only, Hermite at lmax 1). */
#define SHL_INTERP_SHORT_ROWS shl__interp_f_avx2
/* Likewise the float sums (shl__interp_ff): rows of 8 to 15 floats (lmax 2) on the avx2 kernel. */
#define SHL_INTERP_FF_SHORT_ROWS shl__interp_ff_avx2

/* Four rows r0..r3 (16 lanes) to u0..u3 with, in 128-bit block q, element 4q + k
 * of the four rows in u_k (simd/avx2/helper.h within each block: unpack pairs
 * of rows, then shuffle pairs of pairs). */
static inline void vf_transpose4x4_blocks(__m512 r0, __m512 r1, __m512 r2, __m512 r3, __m512 *u0, __m512 *u1, __m512 *u2,
                                          __m512 *u3)
{
    const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
    const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
    *u0 = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
    *u1 = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    *u2 = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
    *u3 = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* Columns k, 4 + k, 8 + k, 12 + k from a = u_k of rows 0..3, b of rows 4..7,
 * c of rows 8..11, d of rows 12..15: block q of each, in order, is column
 * 4q + k.  Two rounds of 128-bit block shuffles (blocks 0, 1 or 2, 3 of a and
 * b, and of c and d; then the even or odd blocks of those). */
static inline void vf_store_columns(__m512 a, __m512 b, __m512 c, __m512 d, float *dst, size_t stride, int k, int nvalid)
{
    const __m512 ab_lo = _mm512_shuffle_f32x4(a, b, 0x44), ab_hi = _mm512_shuffle_f32x4(a, b, 0xEE);
    const __m512 cd_lo = _mm512_shuffle_f32x4(c, d, 0x44), cd_hi = _mm512_shuffle_f32x4(c, d, 0xEE);
    _mm512_storeu_ps(dst + (size_t)k * stride, _mm512_shuffle_f32x4(ab_lo, cd_lo, 0x88));
    if (4 + k < nvalid) _mm512_storeu_ps(dst + (size_t)(4 + k) * stride, _mm512_shuffle_f32x4(ab_lo, cd_lo, 0xDD));
    if (8 + k < nvalid) _mm512_storeu_ps(dst + (size_t)(8 + k) * stride, _mm512_shuffle_f32x4(ab_hi, cd_hi, 0x88));
    if (12 + k < nvalid) _mm512_storeu_ps(dst + (size_t)(12 + k) * stride, _mm512_shuffle_f32x4(ab_hi, cd_hi, 0xDD));
}

/* Tile transpose-store: src holds 16 rows of 16 lanes (row i at src + 16 i);
 * lane j of every row goes to dst + j * stride (16 floats), for j < nvalid
 * (nvalid >= 1).  Straight-line code: every intermediate stays in a register. */
static inline void vf_store_transposed(const float *src, float *dst, size_t stride, int nvalid)
{
    __m512 a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3;
    vf_transpose4x4_blocks(_mm512_loadu_ps(src), _mm512_loadu_ps(src + 16), _mm512_loadu_ps(src + 32),
                           _mm512_loadu_ps(src + 48), &a0, &a1, &a2, &a3);
    vf_transpose4x4_blocks(_mm512_loadu_ps(src + 64), _mm512_loadu_ps(src + 80), _mm512_loadu_ps(src + 96),
                           _mm512_loadu_ps(src + 112), &b0, &b1, &b2, &b3);
    vf_transpose4x4_blocks(_mm512_loadu_ps(src + 128), _mm512_loadu_ps(src + 144), _mm512_loadu_ps(src + 160),
                           _mm512_loadu_ps(src + 176), &c0, &c1, &c2, &c3);
    vf_transpose4x4_blocks(_mm512_loadu_ps(src + 192), _mm512_loadu_ps(src + 208), _mm512_loadu_ps(src + 224),
                           _mm512_loadu_ps(src + 240), &d0, &d1, &d2, &d3);
    vf_store_columns(a0, b0, c0, d0, dst, stride, 0, nvalid);
    if (nvalid > 1) vf_store_columns(a1, b1, c1, d1, dst, stride, 1, nvalid);
    if (nvalid > 2) vf_store_columns(a2, b2, c2, d2, dst, stride, 2, nvalid);
    if (nvalid > 3) vf_store_columns(a3, b3, c3, d3, dst, stride, 3, nvalid);
}

#endif
