/* Batched kernels: the polygon prepared once per call (src/batch.c), the
 * per-ISA kernel table (src/dispatch.c), shared with the kernels compiled
 * once per ISA from simd/poly_batch.h, simd/sphere_batch.h, simd/interp_batch.h
 * and simd/lights_batch.h. */
#ifndef SHL_SIMD_BATCH_H
#define SHL_SIMD_BATCH_H

#include "internal.h"
#include "zh_tables.h"

/* A polygon prepared for many shading points, in scaled units: every
 * coordinate (vertices and points) is multiplied by inv_scale, a power of two
 * that brings the polygon's extent near 1, so the float geometry neither
 * underflows nor overflows (exact; coefficients are scale invariant). */
typedef struct {
    int n;                        /* vertices after dropping repeated ones; 0: sees nothing */
    double inv_scale;             /* 2^-k */
    double vd[SHL_MAX_VERTS][3];  /* kept vertices (scaled, exact) */
    double normal[3], len2;       /* Newell normal of vd (relative to vd[0]) and its squared length */
    float v[SHL_MAX_VERTS][3];    /* kept vertices relative to vd[0], as float (within float range) */
    float edge[SHL_MAX_VERTS][3]; /* v_{e+1} - v_e from the doubles: accurate for nearby vertices */
    /* fan triangle i = (v_0, v_i, v_i+1), 1 <= i <= n-2: its triple product seen
     * from x is (v_0 - x) . c_i = h * fan[i], with h = normal . (v_0 - x) and
     * fan[i] = normal . c_i / len2 (c_i parallel to normal for a planar polygon) */
    float fan[SHL_MAX_VERTS];
    float unit_normal[3], inv_len; /* normal / |normal|, 1 / |normal| */
    double proxy[3];              /* an off-plane point relative to vd[0], evaluated in masked lanes */
} shl__batch_poly;

/* Kernel arguments: points pts[3p..3p+2] (unscaled floats) for 0 <= p < npts;
 * coeffs + p*nc and, if grad != NULL, grad + 3*nc*p as for shl_polygon_grad_f.
 * work: shl__isa.poly_work_bytes(lmax, grad != NULL) bytes, any alignment. */
typedef void (*shl__poly_batch_fn)(const shl__batch_poly *poly, int lmax, int npts, const float *pts,
                                   float *coeffs, float *grad, void *work);

/* Grid interpolation at one point (src/interp.c): the 8 corners of its cell
 * and the weights of the three methods, set up in double. */
typedef struct {
    size_t ofs[8];   /* element offset of corner j = ix + 2 iy + 4 iz */
    double u[3];     /* position in the cell, [0, 1] per axis */
    double w[8];     /* trilinear or Taylor (Annen Eq. 16) weights */
    double wd[8][3]; /* Taylor: w_j (p - p_j) */
    double hw[3][4]; /* Hermite basis per axis: value L, slope L, value R, slope R (slopes x spacing) */
} shl__interp_point;

/* Interpolated 3 nc values out[c nc + k] of point s (method SHL_INTERP_*) from
 * float node data (layout of grid.h). */
typedef void (*shl__interp_fn)(const float *data, int method, int nc, const shl__interp_point *s, double *out);

/* Sphere kernel arguments: the sphere (center, radius > 0, finite), points
 * pts[3p..3p+2] for 0 <= p < npts, outputs as for shl_sphere_batch_f.  work:
 * shl__isa.sphere_work_bytes(lmax, grad != NULL) bytes, any alignment. */
typedef void (*shl__sphere_batch_fn)(int lmax, const double center[3], double radius, int npts, const float *pts,
                                     float *coeffs, float *grad, void *work);

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

/* One table per instruction set, defined in src/dispatch.c (designated
 * initializers, one field per line). */
struct shl__isa {
    const char *name;  /* "scalar", "avx2", "neon" */
    int vlen;          /* float lanes */
    size_t (*poly_work_bytes)(int lmax, int with_grad);
    shl__poly_batch_fn poly_batch;
    size_t (*sphere_work_bytes)(int lmax, int with_grad);
    shl__sphere_batch_fn sphere_batch;
    shl__interp_fn interp_f; /* scalar: the double reference of src/interp_kernel.h */
    void (*accumulate)(size_t n, float s, const float *x, float *y); /* y += s x (simd/lights_batch.h) */
};

/* Kernels of simd/poly_batch.h, one instance per ISA (simd/<isa>/). */
#define SHL__DECLARE_POLY_BATCH(isa)                                                                    \
    size_t shl__poly_work_bytes_##isa(int lmax, int with_grad);                                        \
    void shl__poly_batch_##isa(const shl__batch_poly *poly, int lmax, int npts, const float *pts,      \
                               float *coeffs, float *grad, void *work);
SHL__DECLARE_POLY_BATCH(scalar)
SHL__DECLARE_POLY_BATCH(avx2)
SHL__DECLARE_POLY_BATCH(neon)

/* Kernels of simd/sphere_batch.h, one instance per ISA. */
#define SHL__DECLARE_SPHERE_BATCH(isa)                                                                 \
    size_t shl__sphere_work_bytes_##isa(int lmax, int with_grad);                                      \
    void shl__sphere_batch_##isa(int lmax, const double center[3], double radius, int npts, const float *pts, \
                                 float *coeffs, float *grad, void *work);
SHL__DECLARE_SPHERE_BATCH(scalar)
SHL__DECLARE_SPHERE_BATCH(avx2)
SHL__DECLARE_SPHERE_BATCH(neon)

/* Light-set accumulation of simd/lights_batch.h, one instance per ISA. */
void shl__accumulate_scalar(size_t n, float s, const float *x, float *y);
void shl__accumulate_avx2(size_t n, float s, const float *x, float *y);
void shl__accumulate_neon(size_t n, float s, const float *x, float *y);

/* Interpolation: the reference (src/interp.c) and simd/interp_batch.h per vector ISA. */
void shl__interp_ref_f(const float *data, int method, int nc, const shl__interp_point *s, double *out);
void shl__interp_f_avx2(const float *data, int method, int nc, const shl__interp_point *s, double *out);
void shl__interp_f_neon(const float *data, int method, int nc, const shl__interp_point *s, double *out);

extern const shl__isa shl__isa_scalar;
extern const shl__isa shl__isa_avx2;
extern const shl__isa shl__isa_neon;

/* Float copies of the lobe table (zh_tables.h), filled once by shl__isa_select(). */
extern float shl__zh_dir_f[SHL__ZH_NDIR][3];
extern float shl__zh_even_w_f[SHL__ZH_EVEN_SIZE];
extern float shl__zh_odd_w_f[SHL__ZH_ODD_SIZE];

/* The table named name if compiled in and supported by this CPU, else NULL (dispatch.c). */
const shl__isa *shl__isa_find(const char *name);

#endif
