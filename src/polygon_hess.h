/* Per-edge setup of the polygon Hessian (polygon_hess.c, derivation (H1)-(H6) there),
 * shared by the scalar reference shl__poly_zh_hess_d and the kernels vectorized across
 * lobes (simd/poly_hess_batch.h), which do per lane the reference's arithmetic. */
#ifndef SHL_POLYGON_HESS_H
#define SHL_POLYGON_HESS_H

#include "polygon.h"

/* Gauss-Legendre nodes of the rule for edges seen nearly end-on (polygon_hess.c, NEAR_RADIAL). */
enum { SHL__HESS_NQ = 8 };

/* Per-edge quantities of (H2)-(H6), scaled units. */
typedef struct {
    double g2, e0, ffp1, fe2, ff2, ffd; /* ffd = [f f'] = G2 T - 2 E_0 (H3) */
    /* H_e = S(mu, r), r = 2 I_l g - P_l(a_e) bp - dP_l bd - c M_l mu (H2, H6) */
    double tg[3], bp[3], bd[3];
    int quad;                   /* E_l and I_l by the Gauss rule */
    double qc[SHL__HESS_NQ], qs[SHL__HESS_NQ]; /* its nodes t_j (cos, sin) */
    double qf[SHL__HESS_NQ], qw[SHL__HESS_NQ]; /* weights times f(t_j), f(t_j)^2 */
} shl__hess_edge;

/* The edges of g into he[0 .. g->n - 1]; returns 1 if any takes the Gauss rule. */
int shl__hess_edges_init(const shl__poly_geom *g, shl__hess_edge *he);

/* Wang 2018 Eq. 33's weights (zh_tables.h) transposed, for the reconstruction vectorized
 * across orders m (simd/poly_hess_batch.h).  Band l, with P(n) = n rounded up to 8 (zero
 * padded): even row k <= l at even + even_ofs[l] + k P(l + 1) holds shl__zh_even_w's
 * weight (m, k) at m <= l; odd row k < l at odd + odd_ofs[l] + k P(l) holds shl__zh_odd_w's
 * weight (m, k) at j = l - m (m = l .. 1, the increasing addresses of coeff index l(l+1) - m). */
#define SHL__WT_PAD(n) (((n) + 7) / 8 * 8)
typedef struct {
    int even_ofs[SHL_LMAX_MAX + 1], odd_ofs[SHL_LMAX_MAX + 1];
    double even[SHL__ZH_EVEN_SIZE + 7 * (SHL_LMAX_MAX + 1) * (SHL_LMAX_MAX + 2) / 2]; /* sum (l+1) (P(l+1) - l - 1) */
    double odd[SHL__ZH_ODD_SIZE + 7 * SHL_LMAX_MAX * (SHL_LMAX_MAX + 1) / 2];
} shl__zh_wt_table;
/* The table, built once (thread safe). */
const shl__zh_wt_table *shl__zh_wt(void);

#endif
