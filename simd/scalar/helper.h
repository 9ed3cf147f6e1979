/* Scalar fallback of the vector verbs: one float lane, so the kernel texts of
 * simd/poly_batch.h and simd/sphere_batch.h compile as plain C on every target
 * (SHTns style).  No double verbs (vd_*, SHL_VDLEN): simd/interp_batch.h then
 * forwards to the double reference of src/interp_kernel.h. */
#ifndef SHL_SIMD_HELPER_H
#define SHL_SIMD_HELPER_H

#include <math.h>
#include <stddef.h>

#define SHL_VLEN 1
#define SHL_ISA_SUFFIX(name) name##_scalar

typedef float vf;
typedef int vm; /* lane mask: nonzero = true */

static inline vf vf_set1(float a) { return a; }
static inline vf vf_load(const float *p) { return *p; }
static inline void vf_store(float *p, vf a) { *p = a; }
static inline vf vf_add(vf a, vf b) { return a + b; }
static inline vf vf_sub(vf a, vf b) { return a - b; }
static inline vf vf_mul(vf a, vf b) { return a * b; }
static inline vf vf_div(vf a, vf b) { return a / b; }
static inline vf vf_sqrt(vf a) { return sqrtf(a); }
static inline vf vf_fma(vf a, vf b, vf c) { return a * b + c; }  /* a*b + c */
static inline vf vf_fms(vf a, vf b, vf c) { return a * b - c; }  /* a*b - c */
static inline vf vf_fnma(vf a, vf b, vf c) { return c - a * b; } /* c - a*b */
static inline vf vf_abs(vf a) { return fabsf(a); }
static inline vf vf_min(vf a, vf b) { return a < b ? a : b; }
static inline vf vf_max(vf a, vf b) { return a > b ? a : b; }
static inline vm vf_lt(vf a, vf b) { return a < b; }
static inline vm vf_gt(vf a, vf b) { return a > b; }
static inline vf vf_sel(vm m, vf a, vf b) { return m ? a : b; } /* m ? a : b per lane */
/* a with the sign of b flipped in (a * sign(b), also for b = -0) */
static inline vf vf_mulsign(vf a, vf b) { return signbit(b) ? -a : a; }
/* |a| with the sign of b */
static inline vf vf_copysign(vf a, vf b) { return copysignf(a, b); }
/* Tile transpose-store: src holds SHL_VLEN rows of SHL_VLEN lanes; lane j of
 * every row goes to dst + j * stride (SHL_VLEN floats), for j < nvalid. */
static inline void vf_store_transposed(const float *src, float *dst, size_t stride, int nvalid)
{
    (void)stride;
    (void)nvalid;
    *dst = *src;
}

#endif
