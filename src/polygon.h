/* Per-polygon geometry shared by the coefficient and gradient kernels. */
#ifndef SHL_POLYGON_H
#define SHL_POLYGON_H

#include "internal.h"

/* A polygon as seen from the shading point x, oriented so that its solid
 * angle is positive (counter-clockwise seen from outside the unit sphere
 * around x).  Edge e joins vertex e and vertex (e+1) % n.  All in double, lengths
 * in scaled units: v - x times 2^-E, the largest component in [1, 2) (internal.h). */
typedef struct shl__poly_geom {
    int n;                         /* vertices after dropping repeated ones; 0: sees nothing */
    double rel[SHL_MAX_VERTS][3];  /* (v_e - x) 2^-E */
    double dist[SHL_MAX_VERTS];    /* |rel_e| */
    double w[SHL_MAX_VERTS][3];    /* omega_e, unit direction to vertex e */
    double lam[SHL_MAX_VERTS][3];  /* lambda_e = mu_e x omega_e (Wang 2018 Eq. 16) */
    double mu[SHL_MAX_VERTS][3];   /* mu_e, unit normal of the edge's great circle (Eq. 19) */
    double gamma[SHL_MAX_VERTS];   /* arc angle of edge e (Eq. 20) */
    double sin_gamma[SHL_MAX_VERTS], cos_gamma[SHL_MAX_VERTS];
    double omc_gamma[SHL_MAX_VERTS]; /* 1 - cos(gamma) = 2 sin^2(gamma/2), no cancellation */
    double dw[SHL_MAX_VERTS][3];     /* omega_{e+1} - omega_e, from vertex differences */
    double solid_angle;            /* S_0 (Eq. 24), > 0 when n > 0 */
    /* gradient terms (polygon_zh.h): 1/ell(t) = gvec_e . w(t) along edge e, and
     * its t-derivative at the arc's ends */
    double gvec[SHL_MAX_VERTS][3];
    double fprime1[SHL_MAX_VERTS];   /* f'(gamma_e) */
    double f_integral[SHL_MAX_VERTS]; /* I_0 = int_0^gamma f dt = f'(0) - f'(gamma) */
    double grad_scale[2];            /* product 2^-E: d/dx = 2^-E d/dx_scaled (shl__pow2_split) */
    double gvec_max;                 /* max_e,k |gvec_e[k]| (0 when unset): shl__poly_hess_fold */
    /* near-plane sliver regime (polygon.c, shl__poly_zh_area): ZH integrals by a Gauss rule on the plane */
    int sliver;                      /* 1: the foot of x is outside the polygon, far from it, and |h| small */
    double nrm[3];                   /* unit normal of the plane */
    double height;                   /* |h|, distance of x from the plane (scaled units, a few ulps) */
} shl__poly_geom;

/* Build the geometry; the caller has validated n and finiteness. */
void shl__poly_geom_init(shl__poly_geom *g, const double x[3], const double *verts, int n);
/* Per-band constants of the double ZH recurrence, l <= SHL_LMAX_MAX, computed once
 * (pthread_once) and read by every double kernel (simd/poly_zh_coeff.h, simd/poly_zh_grad.h,
 * simd/poly_hess_batch.h, polygon_hess.c): the same constants, so the same bits. */
typedef struct {
    double norm[SHL_LMAX_MAX + 1];    /* K_l = sqrt((2l+1) / 4 pi) */
    double inv_l[SHL_LMAX_MAX + 2];   /* 1 / l (1 at l = 0), l <= SHL_LMAX_MAX + 1 */
    double twol_m1[SHL_LMAX_MAX + 1]; /* 2l - 1 */
    double leg_a[SHL_LMAX_MAX + 1];   /* (2l-1) / l and (l-1) / l: Eq. 11 as */
    double leg_b[SHL_LMAX_MAX + 1];   /* P_l = leg_a a P_{l-1} - leg_b P_{l-2}, and the same for dP_l */
    double b_alpha[SHL_LMAX_MAX + 1]; /* (2l-1) / l^2 and (l-1)^2 / l^2: Eq. 30 with Eq. 31's C_{l-1} as */
    double b_beta[SHL_LMAX_MAX + 1];  /* B_l = b_alpha (B_1 P_{l-1} + s dP_{l-1} - c^2 D_{l-1}) + b_beta B_{l-2} */
    double s_b[SHL_LMAX_MAX + 1];     /* Eq. 29 weights (2l-1) / (l(l+1)) */
    double s_s[SHL_LMAX_MAX + 1];     /* and (l-2)(l-1) / (l(l+1)) */
} shl__zh_band_consts;
const shl__zh_band_consts *shl__zh_bands(void);

/* The same without the gradient terms (gvec, fprime1, f_integral left unset), for
 * the coefficient kernels; every other field equal to shl__poly_geom_init's. */
void shl__poly_geom_init_values(shl__poly_geom *g, const double x[3], const double *verts, int n);

/* ZH integrals zh[d * SHL__ZH_STRIDE + l] = int_Q Y_l0(dir_d . w) dw for
 * every lobe d < 2*lmax+1 of the shared lobe table and l <= lmax; the _grad
 * versions also write d zh / d x_a at zh_grad[a * SHL__ZH_BLOCK + d * SHL__ZH_STRIDE + l],
 * in scaled units: the caller multiplies by grad_scale (shl__poly_grad_unscale). */
void shl__poly_zh_d(const shl__poly_geom *g, int lmax, double *zh);
void shl__poly_zh_f(const shl__poly_geom *g, int lmax, float *zh);
void shl__poly_zh_grad_d(const shl__poly_geom *g, int lmax, double *zh, double *zh_grad);
void shl__poly_zh_grad_f(const shl__poly_geom *g, int lmax, float *zh, float *zh_grad);

/* Value, gradient and Hessian of the ZH integrals interleaved ("z10" layout, lobes d <= 2 lmax,
 * bands l <= lmax, packed): z10[SHL__Z10(lmax, d, l) + b], b = 0 the value (as shl__poly_zh_grad_d),
 * 1..3 d/dx, d/dy, d/dz, 4..9 the second derivatives xx, xy, xz, yy, yz, zz (polygon_hess.c).
 * unscaled = 0: in scaled units (the caller multiplies the gradient by grad_scale, the
 * Hessian by grad_scale twice); unscaled = 1 (only when shl__poly_hess_fold(g)): the
 * factors 2^-E, 2^-2E folded into the band weights. */
#define SHL__ZH_MULTI 10
#define SHL__Z10(lmax, d, l) (((d) * ((lmax) + 1) + (l)) * SHL__ZH_MULTI)
#define SHL__Z10_SIZE(lmax) ((2 * (lmax) + 1) * ((lmax) + 1) * SHL__ZH_MULTI)
void shl__poly_zh_hess_d(const shl__poly_geom *g, int lmax, double *z10, int unscaled);
/* 1 when 2^-E and 2^-2E times every band weight K_l (<= 2.5) are normal doubles
 * (2^-2E in [2^-1000, 2^1000]): a power of two commutes with every rounding, so folding
 * it in gives the values of multiplying afterwards, bit for bit, unless they leave the
 * normal range (where both over/underflow alike). */
static inline int shl__poly_hess_fold(const shl__poly_geom *g)
{
    const double s = g->grad_scale[0] * g->grad_scale[1];
    /* and no lane overflows: a gradient beyond ~2^900 in x units is summed in scaled units and
     * unscaled at the end (+-inf where it is beyond DBL_MAX; folded, inf - inf gave NaN) */
    return s >= 0x1p-500 && s <= 0x1p500 && g->gvec_max * s <= 0x1p900;
}

/* The same ZH integrals (double) as a planar integral, dw = |h| dA / r^3 (polygon.c);
 * used by the four instances above when g->sliver and lmax <= SHL__AREA_LMAX. */
void shl__poly_zh_area(const shl__poly_geom *g, int lmax, double *zh);
#define SHL__AREA_LMAX 16

/* Sparse ZH -> SH reconstruction (Wang 2018 Eq. 33) from the lobe table (zh_lobes.c);
 * zh laid out as above. */
void shl__zh_to_sh(int lmax, const double *zh, double *coeffs);
/* shl__zh_to_sh of each of the SHL__ZH_MULTI interleaved blocks of z10 (layout above)
 * into out[b], bit for bit, the blocks side by side (polygon_hess.c). */
void shl__zh_to_sh_multi(int lmax, const double *z10, double *const out[SHL__ZH_MULTI]);
/* shl__zh_to_sh's transposed weight blocks, for the ISA kernels (simd/poly_zh_batch.h): band
 * l's even block (l+1 rows and columns) starts at even + 2 even_at[l], its odd block (l rows
 * and columns) at odd + 2 odd_at[l]; column k of a block of r rows is the r + (r & 1) doubles
 * from (r + (r & 1)) k on: rows 0 .. r-1, then a zero where r is odd. */
typedef struct {
    const double *even, *odd;
    const int *even_at, *odd_at;
} shl__zh_blocks;
void shl__zh_lobe_blocks(shl__zh_blocks *b);
/* Float ZH in, float SH out; accumulates in double. */
void shl__zh_to_sh_f(int lmax, const float *zh, float *coeffs);

/* v[i] times grad_scale[0] grad_scale[1] = 2^-E, i < n: gradients from scaled
 * units, in double, so that only a result beyond the range overflows (to +-inf,
 * after the linear ZH -> SH reconstruction: no inf - inf). */
static inline void shl__poly_grad_unscale(const shl__poly_geom *g, double *v, int n)
{
    for (int i = 0; i < n; ++i) v[i] = v[i] * g->grad_scale[0] * g->grad_scale[1];
}
static inline void shl__poly_grad_unscale_f(const shl__poly_geom *g, float *v, int n)
{
    for (int i = 0; i < n; ++i) v[i] = (float)(v[i] * g->grad_scale[0] * g->grad_scale[1]);
}

#define SHL__ZH_STRIDE (SHL_LMAX_MAX + 1)
#define SHL__ZH_BLOCK ((2 * SHL_LMAX_MAX + 1) * SHL__ZH_STRIDE)

#endif
