/* Generic double vectors of W = 2, 4 and 8 lanes for the single-call polygon kernels
 * (poly_zh_coeff.h, poly_zh_grad.h, poly_hess_batch.h): the type dvW and its verbs
 * dvW_set1, dvW_load (W doubles, any alignment), dvW_dot (u . p per lane as (u0 p0 + u1 p1) + u2 p2, the order of the one-lobe
 * recurrence of src/polygon_zh.h) and dvW_scatter (the first count lanes, stride apart).
 * Widths above 2 only up to the ISA's double width SHL_VDLEN: a wider generic vector
 * would be passed in memory, with a different ABI (gcc's -Wpsabi). */
#ifndef SHL_SIMD_DVEC_H
#define SHL_SIMD_DVEC_H
#include <stddef.h>
#include <string.h>

#ifdef __clang__
#pragma clang fp contract(off) /* as gcc in C11 mode: every ISA rounds as the scalar one (no FMA) */
#endif

/* The kernels' full width: the ISA's double lanes, at least 2 (the scalar ISA: two SSE2 /
 * NEON lanes or plain code). */
#if defined(SHL_VDLEN) && SHL_VDLEN > 2
#define SHL_DVEC_WIDTH SHL_VDLEN
#else
#define SHL_DVEC_WIDTH 2
#endif

#define SHL__DVEC(W)                                                                                   \
    typedef double dv##W __attribute__((vector_size(W * sizeof(double))));                            \
    static inline dv##W dv##W##_set1(double x)                                                         \
    {                                                                                                  \
        double t[W];                                                                                   \
        for (int k = 0; k < W; ++k) t[k] = x;                                                          \
        dv##W v;                                                                                       \
        memcpy(&v, t, sizeof v);                                                                       \
        return v;                                                                                      \
    }                                                                                                  \
    static inline dv##W dv##W##_dot(dv##W ux, dv##W uy, dv##W uz, const double p[3])                  \
    {                                                                                                  \
        return ux * dv##W##_set1(p[0]) + uy * dv##W##_set1(p[1]) + uz * dv##W##_set1(p[2]);            \
    }                                                                                                  \
    static inline dv##W dv##W##_load(const double *p)                                                 \
    {                                                                                                  \
        dv##W v;                                                                                       \
        memcpy(&v, p, sizeof v);                                                                       \
        return v;                                                                                      \
    }                                                                                                  \
    static inline void dv##W##_scatter(dv##W v, double *out, ptrdiff_t stride, int count)              \
    {                                                                                                  \
        double t[W];                                                                                   \
        memcpy(t, &v, sizeof t);                                                                       \
        for (int k = 0; k < count; ++k) out[k * stride] = t[k];                                        \
    }

SHL__DVEC(2)
#if defined(SHL_VDLEN) && SHL_VDLEN >= 4
SHL__DVEC(4)
/* lanes i, j, k, l of a and b's 8 (a's are 0-3, b's 4-7), in the registers */
#ifdef __clang__
#define dv4_shuffle(a, b, i, j, k, l) __builtin_shufflevector(a, b, i, j, k, l)
#else
typedef long long shl__dv4_index __attribute__((vector_size(4 * sizeof(long long))));
#define dv4_shuffle(a, b, i, j, k, l) __builtin_shuffle(a, b, (shl__dv4_index){i, j, k, l})
#endif
#endif
#if defined(SHL_VDLEN) && SHL_VDLEN >= 8
SHL__DVEC(8)
#endif
#undef SHL__DVEC

#endif
