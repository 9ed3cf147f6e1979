/* The interface between the library (src/) and the batch kernels (simd/): the
 * data the kernels read, their signatures and the per-ISA table of them.  The
 * kernel texts simd/poly_batch.h, simd/sphere_batch.h, simd/interp_batch.h and
 * simd/lights_batch.h include only this header (and the ISA's helper, which the
 * Makefile includes first); src/internal.h includes it for src/. */
#ifndef SHL_SIMD_KERNEL_API_H
#define SHL_SIMD_KERNEL_API_H

#include "../src/zh_tables.h"
#include "shlight.h"
#include <stddef.h>

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
    double perimeter;             /* of vd (the unresolved-point test, src/batch.c) */
} shl__batch_poly;

/* Kernel arguments: points pts[3p..3p+2] (unscaled floats) for 0 <= p < npts;
 * coeffs + p*nc and, if grad != NULL, grad + 3*nc*p as for shl_polygon_grad_f.
 * work: shl__isa.poly_work_bytes(lmax, grad != NULL) bytes, any alignment.
 * Returns the number of points its float geometry cannot resolve (the test of
 * shl__batch_poly_eval, src/batch.c), their indices in increasing order in
 * redo[0..] (room for npts). */
typedef int (*shl__poly_batch_fn)(const shl__batch_poly *poly, int lmax, int npts, const float *pts, float *coeffs,
                                  float *grad, void *work, int *redo);
/* As shl__poly_batch_fn for a light set's polygon (simd/poly_batch.h): the points p
 * with keep[p] (NULL: all) of a block of npts, their results times rgb[c] added in
 * the lobe domain to acc (poly_acc_floats(lmax, with_grad, npts) floats, zeroed
 * before the block's first light); redo points get nothing (the caller adds their
 * scalar-path results).  poly_acc_finish adds the block's reconstructed results to
 * its outputs (add), or stores them (layout of shl__lights_batch_f_block; grad
 * NULL: without gradients). */
typedef int (*shl__poly_batch_acc_fn)(const shl__batch_poly *poly, int lmax, int npts, const float *pts,
                                      const unsigned char *keep, const float rgb[3], int with_grad, float *acc,
                                      void *work, int *redo);
typedef void (*shl__poly_acc_finish_fn)(int lmax, int npts, const float *acc, int add, float *rgb, size_t rgb_stride,
                                        float *grad, size_t grad_stride, void *work);

/* Grid interpolation at one point (src/interp.c): the 8 corners of its cell
 * and the weights of the three methods, set up in double. */
typedef struct {
    size_t ofs[8];   /* element offset of corner j = ix + 2 iy + 4 iz */
    double u[3];     /* position in the cell, [0, 1] per axis */
    double w[8];     /* trilinear or Taylor (Annen Eq. 16) weights */
    double wd[8][3]; /* Taylor: w_j (p - p_j) */
    double hw[3][4]; /* Hermite basis per axis: value L, slope L, value R, slope R (slopes x spacing) */
} shl__interp_point;

/* The next point's corner rows, requested from memory a few cache lines at a
 * time while the current point is computed, so that a point's loads overlap
 * the previous point's arithmetic instead of waiting one row at a time (out of
 * cache the rows are random: no hardware prefetcher predicts them).  Set up by
 * src/interp.c: nrange rows (0: no next point) of `bytes` each; the kernels
 * call shl__interp_ahead_plan once with their number of blocks, then
 * shl__interp_ahead_step once per block, and shl__interp_ahead_finish. */
typedef struct {
    const char *row[8];
    int nrange;
    size_t bytes;       /* of each row */
    size_t lines, done; /* requests per row (shl__interp_ahead_step) and those made */
    size_t step;        /* lines per block */
} shl__interp_ahead;

/* Grids of at most this many bytes of node data stay in L2 (1-2 MB a core on
 * current x86 and ARM server cores) once touched: requests for lines already
 * cached only cost (measured on the AMD EPYC guest, lmax 8, Hermite, CPU time:
 * +20% at 0.84 MB, +5% at 1.3 MB, -10% at 2 MB, -30% at 6.7 MB), so
 * src/interp.c makes them only for larger grids. */
enum { SHL__INTERP_AHEAD_BYTES = 1 << 20 };

/* Into L2, not L1 (locality 2: prefetcht1 on x86, prfm pldl2keep on AArch64): the next
 * point's rows (lmax 8 Hermite: 31 KB) and the current point's do not both fit in a 32 KB
 * L1D, and L1 requests queue on its few miss buffers.  Measured on the AMD EPYC Zen 4 guest
 * (lmax 8, Hermite, 1.25 GB float grid, random points): 2833 -> 1743 ns per vertex against
 * locality 3; locality 0 (non-temporal) 2852 ns. */
#if defined(__GNUC__) || defined(__clang__)
#define SHL__PREFETCH(p) __builtin_prefetch((p), 0, 2)
#else
#define SHL__PREFETCH(p) ((void)(p)) /* no portable prefetch: demand loads only */
#endif

static inline void shl__interp_ahead_plan(shl__interp_ahead *a, size_t nblocks)
{
    a->lines = a->nrange ? (a->bytes + 63) / 64 + 1 : 0; /* offsets 0, 64, ... below b, then b - 1: every line of the row */
    a->done = 0;
    a->step = nblocks ? (a->lines + nblocks - 1) / nblocks : a->lines;
}

/* Requests the next step lines of every row (at most up to the row's last byte), row by
 * row: runs of consecutive lines (measured on the AMD EPYC Zen 4 guest, lmax 8 Hermite,
 * 1.25 GB float grid, random points: 1781-1793 -> 1676 ns per vertex against line by line
 * across the rows). */
static inline void shl__interp_ahead_step(shl__interp_ahead *a)
{
    const size_t end = a->lines - a->done < a->step ? a->lines : a->done + a->step;
    for (int r = 0; r < a->nrange; ++r)
        for (size_t l = a->done; l < end; ++l) SHL__PREFETCH(a->row[r] + (64 * l < a->bytes ? 64 * l : a->bytes - 1));
    a->done = end;
}

static inline void shl__interp_ahead_finish(shl__interp_ahead *a)
{
    a->step = a->lines;
    shl__interp_ahead_step(a);
}

/* Interpolated 3 nc values out[c nc + k] of point s (method SHL_INTERP_*) from
 * float node data (layout of grid.h), requesting the next point's rows (ahead,
 * planned by the kernel) meanwhile. */
typedef void (*shl__interp_fn)(const float *data, int method, int nc, const shl__interp_point *s,
                               shl__interp_ahead *ahead, double *out);

/* Float-output interpolation at one point (shl_grid_interp_f): every method as a
 * weighted sum of corner rows, weights formed in double (shl__interp_setup_ff;
 * Taylor: src/interp.c) and rounded to float.  Trilinear: out[i] = sum_j w_j
 * f_j[i] over the 3 nc values;
 * Taylor (Annen Eq. 15) and Hermite (Wu Alg. 4 multiplied out,
 * shl__hermite_row_weights): per channel c, out[c nc + k] = sum_j w_j v_j[k] +
 * wd_j . grad_j[k], summed as corners 0-3 plus corners 4-7 (README "Grid
 * interpolation" counts the roundings). */
typedef struct {
    size_t ofs[8];   /* as shl__interp_point */
    float w[8];      /* value weights */
    float wd[8][3];  /* gradient weights (Taylor, Hermite), carrying the spacing */
} shl__interp_point_ff;

/* The 3 nc values out[c nc + k] of point s from float node data in float sums;
 * trilinear: method == SHL_INTERP_TRILINEAR (wd unused), else the gradient form.
 * s2: NULL, or a second point of the same cell (equal ofs), whose values go to
 * out2: each corner row is then loaded once for both; each point's values are
 * those of a call for it alone, bit for bit. */
typedef void (*shl__interp_ff_fn)(const float *data, int method, int nc, const shl__interp_point_ff *s,
                                  const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2);

/* A grid's geometry (src/grid.h) for shl__interp_setup_ff. */
typedef struct {
    double lo[3], hi[3], h[3];
    int res[3];
    size_t node_len;
} shl__interp_geom;

/* Points per call of shl__interp_setup_ff. */
enum { SHL__INTERP_FF_BLOCK = 8 };

/* The set-up of n <= SHL__INTERP_FF_BLOCK points pts[3 i .. 3 i + 2] (finite),
 * trilinear or Hermite, into s[0 .. n - 1] (simd/interp_batch.h): those of
 * src/interp.c's locate, trilinear_weights or hermite_weights and
 * shl__hermite_row_weights, bit for bit, rounded to float. */
typedef void (*shl__interp_setup_ff_fn)(const shl__interp_geom *g, int method, int n, const float *pts,
                                        shl__interp_point_ff *s);

/* Wu 2020 Alg. 4 multiplied out into one weighted sum of the 32 rows it reads:
 * out = z0 h0 + z1 h0_z + z2 h1 + z3 h1_z weighs g[q], g_y[q], g_z[q] (pair q:
 * corners 2q, 2q+1) by G[q], Gy[q], Gz[q]; so corner 2q's value by G x0, its
 * x-gradient by G x1, its y and z ones by Gy vx, Gz vx; corner 2q+1's by G x2,
 * G x3, Gy ux, Gz ux. */
static inline void shl__hermite_row_weights(const shl__interp_point *s, double w[8], double wd[8][3])
{
    const double *x = s->hw[0], *y = s->hw[1], *z = s->hw[2];
    const double ux = s->u[0], vx = 1.0 - ux, uy = s->u[1], vy = 1.0 - uy;
    const double G[4] = {z[0] * y[0], z[0] * y[2], z[2] * y[0], z[2] * y[2]};
    const double Gy[4] = {z[0] * y[1], z[0] * y[3], z[2] * y[1], z[2] * y[3]};
    const double Gz[4] = {z[1] * vy, z[1] * uy, z[3] * vy, z[3] * uy};
    for (int q = 0; q < 4; ++q) {
        w[2 * q] = G[q] * x[0];
        wd[2 * q][0] = G[q] * x[1];
        wd[2 * q][1] = Gy[q] * vx;
        wd[2 * q][2] = Gz[q] * vx;
        w[2 * q + 1] = G[q] * x[2];
        wd[2 * q + 1][0] = G[q] * x[3];
        wd[2 * q + 1][1] = Gy[q] * ux;
        wd[2 * q + 1][2] = Gz[q] * ux;
    }
}

/* Sphere kernel arguments: the sphere (center, radius > 0, finite), points
 * pts[3p..3p+2] for 0 <= p < npts, outputs as for shl_sphere_batch_f.  work:
 * shl__isa.sphere_work_bytes(lmax, grad != NULL) bytes, any alignment. */
typedef void (*shl__sphere_batch_fn)(int lmax, const double center[3], double radius, int npts, const float *pts,
                                     float *coeffs, float *grad, void *work);

/* Single-call polygon ZH integrals in double, vectorized across lobes
 * (simd/poly_zh_batch.h): the layouts and scaled units of shl__poly_zh_d and
 * shl__poly_zh_grad_d (src/polygon.h), results equal to theirs. */
struct shl__poly_geom;
typedef void (*shl__poly_zh_fn)(const struct shl__poly_geom *g, int lmax, double *zh);
/* shl_polygon after the set-up: the ZH integrals of shl__poly_zh_d reconstructed as by
 * shl__zh_to_sh, results equal to theirs. */
typedef void (*shl__poly_sh_fn)(const struct shl__poly_geom *g, int lmax, double *coeffs);
/* shl_polygon_grad after the set-up: coefficients and gradient (unscaled) from the ZH
 * integrals of shl__poly_zh_grad_d reconstructed as by shl__zh_to_sh, results equal to theirs. */
typedef void (*shl__poly_grad_sh_fn)(const struct shl__poly_geom *g, int lmax, double *coeffs, double *grad, int nc);
/* Single-call polygon Hessians (simd/poly_hess_batch.h): shl__poly_zh_hess_d and the ten
 * reconstructions of shl__zh_to_sh_multi into out[b] (src/polygon.h) in one call,
 * vectorized, bit for bit the scalar ones. */
typedef void (*shl__poly_hess_fn)(const struct shl__poly_geom *g, int lmax, int unscaled, double *const *out);

/* The kernels of one instruction set; src/dispatch.c builds one per line of
 * simd/isa_list.h. */
typedef struct shl__isa shl__isa;
struct shl__isa {
    const char *name;  /* as in simd/isa_list.h: "scalar", "avx2", "neon" */
    size_t (*poly_work_bytes)(int lmax, int with_grad);
    shl__poly_batch_fn poly_batch;
    size_t (*poly_acc_floats)(int lmax, int with_grad, int npts);
    shl__poly_batch_acc_fn poly_batch_acc;
    shl__poly_acc_finish_fn poly_acc_finish;
    size_t (*sphere_work_bytes)(int lmax, int with_grad);
    shl__sphere_batch_fn sphere_batch;
    shl__interp_fn interp_f; /* scalar: the double reference of src/interp_kernel.h */
    shl__interp_ff_fn interp_ff; /* float sums (shl_grid_interp_f); scalar: shl__interp_ff_ref */
    shl__interp_setup_ff_fn interp_setup_ff; /* its points' set-up, trilinear and Hermite */
    void (*accumulate)(size_t n, float s, const float *x, float *y); /* y += s x (simd/lights_batch.h) */
    shl__poly_zh_fn poly_zh;           /* shl_polygon's ZH integrals (simd/poly_zh_batch.h) */
    shl__poly_grad_sh_fn poly_grad_sh; /* shl_polygon_grad */
    shl__poly_sh_fn poly_sh;           /* shl_polygon: poly_zh, then the reconstruction */
    shl__poly_hess_fn poly_hess;            /* shl_polygon_hess (simd/poly_hess_batch.h) */
};

/* The interpolation reference (src/interp.c, src/interp_kernel.h): the scalar
 * instance of simd/interp_batch.h, and the others for rows shorter than a vector. */
void shl__interp_ref_f(const float *data, int method, int nc, const shl__interp_point *s, shl__interp_ahead *ahead,
                       double *out);
/* The float-sum reference (src/interp.c): the scalar instance of shl__interp_ff, and
 * the others' for rows shorter than a float vector. */
void shl__interp_ff_ref(const float *data, int method, int nc, const shl__interp_point_ff *s,
                        const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2);

/* The kernels of one ISA, each defined by its kernel text compiled with that
 * ISA's helper (suffix _<isa>, SHL_ISA_SUFFIX); declared for every line of
 * simd/isa_list.h by src/dispatch.c. */
#define SHL__DECLARE_KERNELS(isa)                                                                      \
    size_t shl__poly_work_bytes_##isa(int lmax, int with_grad);                                        \
    int shl__poly_batch_##isa(const shl__batch_poly *poly, int lmax, int npts, const float *pts,       \
                              float *coeffs, float *grad, void *work, int *redo);                      \
    size_t shl__poly_acc_floats_##isa(int lmax, int with_grad, int npts);                              \
    int shl__poly_batch_acc_##isa(const shl__batch_poly *poly, int lmax, int npts, const float *pts,   \
                                  const unsigned char *keep, const float rgb[3], int with_grad, float *acc, \
                                  void *work, int *redo);                                              \
    void shl__poly_acc_finish_##isa(int lmax, int npts, const float *acc, int add, float *rgb,         \
                                    size_t rgb_stride, float *grad, size_t grad_stride, void *work);   \
    size_t shl__sphere_work_bytes_##isa(int lmax, int with_grad);                                      \
    void shl__sphere_batch_##isa(int lmax, const double center[3], double radius, int npts, const float *pts, \
                                 float *coeffs, float *grad, void *work);                              \
    void shl__interp_f_##isa(const float *data, int method, int nc, const shl__interp_point *s,         \
                             shl__interp_ahead *ahead, double *out);                                   \
    void shl__interp_ff_##isa(const float *data, int method, int nc, const shl__interp_point_ff *s,     \
                              const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out,    \
                              float *out2);                                                            \
    void shl__interp_setup_ff_##isa(const shl__interp_geom *g, int method, int n, const float *pts,   \
                                    shl__interp_point_ff *s);                                         \
    void shl__accumulate_##isa(size_t n, float s, const float *x, float *y);                          \
    void shl__poly_zh_##isa(const struct shl__poly_geom *g, int lmax, double *zh);                     \
    void shl__poly_grad_sh_##isa(const struct shl__poly_geom *g, int lmax, double *coeffs, double *grad, int nc); \
    void shl__poly_sh_##isa(const struct shl__poly_geom *g, int lmax, double *coeffs);                \
    void shl__poly_hess_##isa(const struct shl__poly_geom *g, int lmax, int unscaled, double *const *out);

#endif
