/* Internal declarations shared by the library's translation units (prefix shl__). */
#ifndef SHL_INTERNAL_H
#define SHL_INTERNAL_H

#include "../simd/kernel_api.h" /* shl__isa, shl__batch_poly: the interface to simd/ */
#include "shlight.h"
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT2
#define M_SQRT2 1.41421356237309504880
#endif


struct shl_ctx {
    int lmax;
    int nc; /* SHL_NCOEFFS(lmax) */
    const shl__isa *isa; /* chosen once at creation (dispatch.c) */
};

/* The batch kernels for this CPU, or those forced by SHLIGHT_ISA (dispatch.c). */
const shl__isa *shl__isa_select(void);
/* The table of the ISA called name if compiled in and supported by this CPU, else NULL (dispatch.c). */
const shl__isa *shl__isa_find(const char *name);

/* src/batch.c: the polygon verts[0..3n) (finite doubles) prepared for the
 * kernel; the kernel over npts points followed by the scalar path for the
 * points its float geometry cannot resolve (zeros when P->n == 0); and the
 * scalar float path alone at one point (geometry in double, as shl_polygon_grad_f).
 * work: poly_work_bytes(lmax, grad != NULL) bytes. */
void shl__batch_poly_prepare(const double *verts, int n, shl__batch_poly *P);
void shl__batch_poly_eval(const shl_ctx *ctx, const shl__batch_poly *P, const double *verts, int n, int npts,
                          const float *pts, float *coeffs, float *grad, void *work);
void shl__batch_poly_point(const shl_ctx *ctx, const double *verts, int n, const float *pt, float *coeffs,
                           float *grad);

/* src/sphere_batch.c: the sphere (finite centre, finite radius > 0) at npts
 * points, outputs as shl_sphere_batch_f; the kernel where its unscaled double
 * set-up stays in range, else the scalar float path per point.
 * work: sphere_work_bytes(lmax, grad != NULL) bytes. */
void shl__batch_sphere_eval(const shl_ctx *ctx, const double center[3], double radius, int npts, const float *pts,
                            float *coeffs, float *grad, void *work);


/* Allocation hooks: every library allocation goes through these so that
 * tests can inject failures; not part of the public API. */
void *shl__malloc(size_t size);
void *shl__calloc(size_t count, size_t size);
void *shl__realloc(void *ptr, size_t size); /* realloc: NULL on failure, ptr then unchanged */
void shl__free(void *ptr);
/* shl__calloc for the large arrays read at random (grid nodes): from
 * SHL__LARGE_ARRAY bytes on, aligned to SHL__HUGE_PAGE and advised to the
 * kernel as huge pages where it supports it (Linux madvise MADV_HUGEPAGE:
 * fewer TLB misses on random corner-row reads); smaller arrays are shl__calloc.
 * Zeroed, one hooked allocation either way, freed with shl__free. */
#define SHL__HUGE_PAGE ((size_t)2 << 20)
#define SHL__LARGE_ARRAY ((size_t)4 << 20)
void *shl__calloc_large(size_t count, size_t size);
/* Failure injection, defined only in a library built with -DSHL_ALLOC_HOOKS (the
 * test runner's and the fuzzers' copies): the N-th allocation (alloc.c) or worker
 * thread a parallel call takes (parallel.c: created, or parked in the pool, as if
 * created) from now fails, N = the value; < 0: never. */
extern long shl__alloc_fail_after;
extern long shl__thread_fail_after;
#ifdef SHL_ALLOC_HOOKS
/* One step of such a counter: 1 when the failure is due (*left == 0), else
 * counts *left down (< 0: never fails). */
static inline int shl__hook_fails(long *left)
{
    if (*left < 0) return 0;
    if (*left == 0) return 1;
    --*left;
    return 0;
}
#endif

/* Argument checks shared by the API entry points (context.c): SHL_ENONFINITE when one of
 * the count values is infinite or NaN, else SHL_OK.  One pass over all of them without an
 * early exit, which the compiler vectorizes: a batch checks its whole point array in one
 * call (the per-point calls were 3% of the polygon batch's time at lmax 8, and serial). */
int shl__check_finite(const double *v, size_t count);
int shl__check_finite_f(const float *v, size_t count);

/* ---- small vector and polygon helpers (one copy for src/ and simd/) ---- */
static inline double shl__dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void shl__cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Fan triangle (p_0, p_t, p_t+1) of the points p: its edges ab = p_t - p_0 and
 * bc = p_t+1 - p_t, and c = ab x bc, twice its vector area. */
static inline void shl__fan_triangle(const double (*p)[3], int t, double ab[3], double bc[3], double c[3])
{
    for (int k = 0; k < 3; ++k) {
        ab[k] = p[t][k] - p[0][k];
        bc[k] = p[t + 1][k] - p[t][k];
    }
    shl__cross3(ab, bc, c);
}

/* out = in / |in| for a finite, non-zero vector, scaled first so that the norm
 * neither overflows nor underflows.  Returns SHL_ENONFINITE / SHL_EDOMAIN. */
static inline int shl__unit(const double in[3], double out[3])
{
    if (shl__check_finite(in, 3)) return SHL_ENONFINITE;
    const double big = fmax(fabs(in[0]), fmax(fabs(in[1]), fabs(in[2])));
    if (!(big > 0.0)) return SHL_EDOMAIN;
    const double v[3] = {in[0] / big, in[1] / big, in[2] / big};
    const double len = sqrt(shl__dot3(v, v));
    for (int k = 0; k < 3; ++k) out[k] = v[k] / len;
    return SHL_OK;
}

/* The polygon verts[0..n) (xyz interleaved) into kept[] without the vertices that
 * repeat their predecessor, the last one cyclically (zero-length edges); returns the
 * number kept.  kept has room for n vertices. */
static inline int shl__drop_repeated(const double *verts, int n, double *kept)
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        if (m > 0 && memcmp(verts + 3 * i, kept + 3 * (m - 1), sizeof(double) * 3) == 0) continue;
        memcpy(kept + 3 * m++, verts + 3 * i, sizeof(double) * 3);
    }
    while (m > 1 && memcmp(kept, kept + 3 * (m - 1), sizeof(double) * 3) == 0) --m;
    return m;
}

/* ilogb and ldexp without a libm call where the operands are normal doubles
 * (the scaled-geometry set-up below calls them per vertex and component);
 * results identical to libm's: 2^e is exact, and d 2^e is rounded once. */
static inline int shl__ilogb(double d)
{
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    const int biased = (int)((bits >> 52) & 0x7ff);
    return biased != 0 && biased != 0x7ff ? biased - 1023 : ilogb(d);
}
static inline double shl__ldexp(double d, int e)
{
    if (e < -1022 || e > 1023) return ldexp(d, e);
    const uint64_t bits = (uint64_t)(e + 1023) << 52; /* 2^e, a normal double */
    double p;
    memcpy(&p, &bits, sizeof p);
    return d * p;
}

/* Geometry in scaled units (README, "Numerical contract"): differences of
 * coordinates are multiplied by a power of two 2^-E that brings the largest near
 * 1, so that no product of distances over- or underflows; results that are
 * ratios of lengths are unchanged (bit for bit when the unscaled arithmetic
 * does not over/underflow), and d/dx = 2^-E d/dx_scaled.
 * shl__ilogb(a - b), or INT_MIN when a == b; a - b may overflow: then both |a|, |b|
 * exceed 2^969 and their halves are exact. */
static inline int shl__ilogb_diff(double a, double b)
{
    const double d = a - b;
    if (d == 0.0) return INT_MIN;
    return isinf(d) ? shl__ilogb(0.5 * a - 0.5 * b) + 1 : shl__ilogb(d);
}
/* (a - b) 2^e, rounded once, as if the exponent range were unbounded (up to underflow). */
static inline double shl__diff_scaled(double a, double b, int e)
{
    const double d = a - b;
    return isinf(d) ? shl__ldexp(0.5 * a - 0.5 * b, e + 1) : shl__ldexp(d, e);
}
/* The exponent ex of the scaled units of the points v_i = pts[3i..3i+2], i < m,
 * seen from x: the largest component of any v_i - x times 2^-ex lies in [1, 2).
 * INT_MIN when x is one of the points (also up to the sign of zero). */
static inline int shl__scale_exponent(const double x[3], const double *pts, int m)
{
    int ex = INT_MIN;
    for (int i = 0; i < m; ++i) {
        int ei = INT_MIN;
        for (int k = 0; k < 3; ++k) {
            const int d = shl__ilogb_diff(pts[3 * i + k], x[k]);
            ei = d > ei ? d : ei;
        }
        if (ei == INT_MIN) return INT_MIN;
        ex = ei > ex ? ei : ex;
    }
    return ex;
}
/* 2^e as a product s[0] s[1] of two doubles (|e| <= 2200): multiplying by both
 * in turn rounds only where the final result underflows or overflows. */
static inline void shl__pow2_split(int e, double s[2])
{
    s[0] = shl__ldexp(1.0, e / 2);
    s[1] = shl__ldexp(1.0, e - e / 2);
}

/* Newell normal sum_{i=1}^{n-2} (v_i - v_0) x (v_{i+1} - v_0) of the polygon
 * verts[0..n) (xyz interleaved; counter-clockwise seen from its tip; exact for a
 * triangle) in scaled units: the differences v_i - v_0 times the power of two
 * 2^-E that brings the largest near 1, so that the cross products neither
 * overflow nor underflow.  The zero vector when the vertices are equal up to the
 * sign of zero. */
static inline void shl__newell_scaled(const double *verts, int n, double nrm[3])
{
    int e = INT_MIN;
    for (int i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const int ek = shl__ilogb_diff(verts[3 * i + k], verts[k]);
            e = ek > e ? ek : e;
        }
    nrm[0] = nrm[1] = nrm[2] = 0.0;
    for (int i = 1; i + 1 < n && e != INT_MIN; ++i) {
        double e1[3], e2[3], c[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = shl__diff_scaled(verts[3 * i + k], verts[k], -e);
            e2[k] = shl__diff_scaled(verts[3 * (i + 1) + k], verts[k], -e);
        }
        shl__cross3(e1, e2, c);
        for (int k = 0; k < 3; ++k) nrm[k] += c[k];
    }
}

/* |v|, scaled by a power of two first where v . v could under- or overflow (v a
 * cross product of short or long scaled edges: in polygon.c its length feeds
 * gamma and mu, Wang 2018 Eq. 19-20); 0 for the zero vector. */
static inline double shl__norm3(const double v[3])
{
    /* v . v in [2^-896, 2^900] implies the largest |v_k| in [2^-450, 2^450]: the plain
     * form below, without the fmax calls (libm calls at -O2) */
    const double d = shl__dot3(v, v);
    if (d >= 0x1p-896 && d <= 0x1p900) return sqrt(d);
    const double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
    if (!(m > 0.0)) return 0.0;
    if (m >= 0x1p-450 && m <= 0x1p450) return sqrt(shl__dot3(v, v));
    const int e = shl__ilogb(m);
    const double s[3] = {shl__ldexp(v[0], -e), shl__ldexp(v[1], -e), shl__ldexp(v[2], -e)};
    return shl__ldexp(sqrt(shl__dot3(s, s)), e);
}

#endif
