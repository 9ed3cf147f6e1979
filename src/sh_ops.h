/* Internal declarations of the spherical-light, ZH/SH-operation, BRDF-table and
 * HVL modules (sphere.c, sh_rotate.c, sh_convolve.c, quad.c, brdf.c, hvl.c). */
#ifndef SHL_SH_OPS_H
#define SHL_SH_OPS_H

#include "internal.h"
#include <math.h>

/* ---- SH basis (sh_basis.c) ----------------------------------------------- */
/* y[l(l+1)+m] = w[l] Y_lm(u) for a unit vector u, l <= lmax (w == NULL: 1). */
void shl__sh_eval_w_d(int lmax, const double u[3], const double *w, double *y);
void shl__sh_eval_w_f(int lmax, const float u[3], const float *w, float *y);
/* Y_lm(u) for a unit vector u into y[(lmax+1)^2] and, when grad != NULL, the
 * surface gradient grad[a*stride + k] = d/du_a of Y_k(u/|u|) at |u| = 1. */
void shl__sh_eval_grad_d(int lmax, const double u[3], double *y, double *grad, int stride);
void shl__sh_eval_grad_f(int lmax, const float u[3], float *y, float *grad, int stride);
/* One pass: y[k] = w[l] Y_k(u) and grad[a*stride + k] = al[l] G_a + u_a (be[l] Y_k - al[l] u.G)
 * with G = grad of Y_k's polynomial extension (al = 1, be = 0: the surface gradient). */
void shl__sh_eval_wgrad_d(int lmax, const double u[3], const double *w, const double *al, const double *be,
                          double *restrict y, double *restrict grad, int stride);
void shl__sh_eval_wgrad_f(int lmax, const float u[3], const float *w, const float *al, const float *be,
                          float *restrict y, float *restrict grad, int stride);

/* ---- spherical caps and lights (sphere.c) ------------------------------ */

/* Funk-Hecke factors of the cap {w : axis . w >= cos a}: the integral of Y_lm
 * over it is w[l] Y_lm(axis), w[l] = 2 pi int_{cos a}^1 P_l(u) du (its ZH is
 * K_l w[l]).  t = 1 - cos a, s2 = sin^2 a and c = cos a are passed separately,
 * each with full relative accuracy.  dw (optional) = d w[l] / d cos a. */
void shl__cap_weights_d(int lmax, double t, double s2, double c, double *w, double *dw);
void shl__cap_weights_f(int lmax, float t, float s2, float c, float *w, float *dw);

/* A sphere seen from a point, set up in double. */
typedef struct {
    int inside;        /* |center - x| <= radius: the whole sphere of directions */
    double u[3];       /* unit axis, towards the centre                           */
    double t, s2, c;   /* 1 - cos a, sin^2 a, cos a                               */
    double k_alpha;    /* d cos a / dx = -k_alpha u                               */
    double inv_d;      /* 1 / |center - x|: d u / dx = -(I - u u^T) inv_d           */
    /* the same in scaled units (internal.h): center - x times 2^-e, largest component
     * in [1, 2); k_alpha = k_alpha_s 2^-e, inv_d = inv_d_s 2^-e (inf only if beyond DBL_MAX) */
    double k_alpha_s, inv_d_s;
    double grad_scale[2]; /* product 2^-e (shl__pow2_split) */
} shl__sphere_geom;

void shl__sphere_geom_init(shl__sphere_geom *g, const double x[3], const double center[3],
                           double radius);
/* SH of the cap (and, when grad != NULL, d/dx with grad[a*nc + k]). */
void shl__sphere_sh_d(int lmax, const shl__sphere_geom *g, double *coeffs, double *grad);
void shl__sphere_sh_f(int lmax, const shl__sphere_geom *g, float *coeffs, float *grad);

/* ---- SH rotation (sh_rotate.c) ------------------------------------------ */
/* Number of doubles holding the band matrices of bands 0..lmax. */
size_t shl__rot_size(int lmax);
/* Band matrices D_l (band l at offset l(2l-1)(2l+1)/3, row-major (2l+1)^2) of the
 * proper rotation R (row-major): the coefficients of f(R^T w) are D_l f_l. */
void shl__rot_build(int lmax, const double rot[9], double *d);
/* out_l = D_l in_l for every band; out may equal in. */
void shl__rot_apply(int lmax, const double *d, const double *in, double *out);

/* ---- quadrature (quad.c) ------------------------------------------------ */
/* n-point Gauss-Legendre rule on [-1, 1] (Newton on P_n). */
void shl__gauss_legendre(int n, double *x, double *w);
/* The n-point rule (glx, glw from shl__gauss_legendre) mapped to [a, b]. */
void shl__gl_panel(int n, const double *glx, const double *glw, double a, double b, double *x,
                   double *w);
/* Breakpoints lo = b_0 < ... < b_n = hi graded towards feature points pos[f]
 * (lobe peaks, kinks, cut-offs): near a feature the panel width is about
 * max(w/4, distance to it), so it halves on approach (w = w_below[f]) and
 * doubles away (w = w_above[f]); at most pi/8 elsewhere; every feature inside
 * (lo, hi) is a breakpoint.  Gauss-Legendre on such panels converges
 * geometrically for lobes of width ~w and for algebraic end-point behaviour.
 * Returns n <= SHL__MAX_PANELS; brk has n + 1 entries. */
#define SHL__MAX_PANELS 128
int shl__graded_breaks(double lo, double hi, int nf, const double *pos, const double *w_below,
                       const double *w_above, double *brk);

/* ---- BRDF tables (brdf.c) ---------------------------------------------- */
struct shl_brdf_table {
    int lmax, nc, ntheta;
    double *data; /* sample j: F at data + 2 j nc, F' at data + (2 j + 1) nc */
};

/* Local frame (rows x, y, z) from the unit normal and unit outgoing direction. */
void shl__brdf_frame(const double n[3], const double wo[3], double frame[9]);
/* F and F' (either may be NULL) at the outgoing angle with cosine cos_o and
 * sine sin_o >= 0: interpolated; zero when cos_o <= 0. */
void shl__brdf_table_at(const shl_brdf_table *t, double cos_o, double sin_o, double *f_cos,
                        double *f);

#endif
