/* Internal declarations of spherical caps and lights (sphere.c). */
#ifndef SHL_SPHERE_H
#define SHL_SPHERE_H

#include "internal.h"
#include "sh_basis.h"

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
    /* Set by shl__sphere_geom_init and the float set-up only.  sin^2 a < 2^-64
     * (r/d < 2^-32): s2_e != 0 and s2 = s2_x 2^s2_e, t = t_x 2^s2_e, k_alpha_s =
     * k_alpha_x 2^s2_e with s2_x in [2^-4, 4) (formed from r/d times a power of two,
     * so never subnormal); x_scale = 2^(s2_e - e) (product), the gradient's factor from
     * units of s2_x and scaled lengths.  Every w_l, al_l, be_l is proportional to s2,
     * so the gradient kernels use the _x values where s2 itself would lose bits (below
     * SHL__S2_TINY_D, resp. _F) and scale the results once. */
    int s2_e;
    double s2_x, t_x, k_alpha_x, x_scale[2];
} shl__sphere_geom;

/* sin^2 a below which the REAL kernels take the _x values of shl__sphere_geom:
 * 2^62 above the smallest normal, the margin for the kernels' factors (P_l', Y_lm,
 * 1/d in scaled units) so that no intermediate product is subnormal. */
#define SHL__S2_TINY_D 0x1p-960
#define SHL__S2_TINY_F 0x1p-64

void shl__sphere_geom_init(shl__sphere_geom *g, const double x[3], const double center[3],
                           double radius);
/* SH of the cap (and, when grad != NULL, d/dx with grad[a*nc + k]). */
void shl__sphere_sh_d(int lmax, const shl__sphere_geom *g, double *coeffs, double *grad);
void shl__sphere_sh_f(int lmax, const shl__sphere_geom *g, float *coeffs, float *grad);

/* The six second-derivative rows hess[i*nc + k] (i = xx, xy, xz, yy, yz, zz) of the
 * unit-radiance cap's SH coefficients, unscaled; sphere_hess.c. */
void shl__sphere_sh_hess(int lmax, const shl__sphere_geom *g, double *hess, int nc);

#endif
