/* AArch64 NEON vector verbs: 4 float lanes (simd/scalar/helper.h documents each). */
#ifndef SHL_SIMD_HELPER_H
#define SHL_SIMD_HELPER_H

#include <arm_neon.h>
#include <stddef.h>

#define SHL_VLEN 4
#define SHL_ISA_SUFFIX(name) name##_neon

typedef float32x4_t vf;
typedef uint32x4_t vm;

static inline vf vf_set1(float a) { return vdupq_n_f32(a); }
static inline vf vf_load(const float *p) { return vld1q_f32(p); }
static inline void vf_store(float *p, vf a) { vst1q_f32(p, a); }
static inline vf vf_add(vf a, vf b) { return vaddq_f32(a, b); }
static inline vf vf_sub(vf a, vf b) { return vsubq_f32(a, b); }
static inline vf vf_mul(vf a, vf b) { return vmulq_f32(a, b); }
static inline vf vf_div(vf a, vf b) { return vdivq_f32(a, b); }
static inline vf vf_sqrt(vf a) { return vsqrtq_f32(a); }
static inline vf vf_fma(vf a, vf b, vf c) { return vfmaq_f32(c, a, b); }
static inline vf vf_fms(vf a, vf b, vf c) { return vnegq_f32(vfmsq_f32(c, a, b)); }
static inline vf vf_fnma(vf a, vf b, vf c) { return vfmsq_f32(c, a, b); }
static inline vf vf_abs(vf a) { return vabsq_f32(a); }
static inline vf vf_min(vf a, vf b) { return vminq_f32(a, b); }
static inline vf vf_max(vf a, vf b) { return vmaxq_f32(a, b); }
static inline vm vf_lt(vf a, vf b) { return vcltq_f32(a, b); }
static inline vm vf_gt(vf a, vf b) { return vcgtq_f32(a, b); }
static inline vf vf_sel(vm m, vf a, vf b) { return vbslq_f32(m, a, b); }
static inline vf vf_mulsign(vf a, vf b)
{
    const uint32x4_t sign = vandq_u32(vreinterpretq_u32_f32(b), vdupq_n_u32(0x80000000u));
    return vreinterpretq_f32_u32(veorq_u32(vreinterpretq_u32_f32(a), sign));
}
static inline vf vf_copysign(vf a, vf b) { return vbslq_f32(vdupq_n_u32(0x80000000u), b, a); }

/* Double lanes (grid interpolation, simd/interp_batch.h): 2 per vector. */
#define SHL_VDLEN 2
typedef float64x2_t vd;
static inline vd vd_set1(double a) { return vdupq_n_f64(a); }
static inline vd vd_load_float(const float *p) { return vcvt_f64_f32(vld1_f32(p)); } /* p[0..1] widened */
static inline void vd_store(double *p, vd a) { vst1q_f64(p, a); }
static inline vd vd_add(vd a, vd b) { return vaddq_f64(a, b); }
static inline vd vd_mul(vd a, vd b) { return vmulq_f64(a, b); }
static inline vd vd_fma(vd a, vd b, vd c) { return vfmaq_f64(c, a, b); }

/* Tile transpose-store (see simd/avx2/helper.h): vld4q de-interleaves the
 * 4 rows of 4 lanes into the 4 lanes' rows. */
static inline void vf_store_transposed(const float *src, float *dst, size_t stride, int nvalid)
{
    const float32x4x4_t t = vld4q_f32(src);
    vst1q_f32(dst, t.val[0]);
    if (nvalid > 1) vst1q_f32(dst + stride, t.val[1]);
    if (nvalid > 2) vst1q_f32(dst + 2 * stride, t.val[2]);
    if (nvalid > 3) vst1q_f32(dst + 3 * stride, t.val[3]);
}

#endif
