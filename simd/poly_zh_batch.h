/* Single-call polygon ZH integrals in double (shl_polygon, shl_polygon_grad),
 * vectorized ACROSS LOBES: the recurrence of src/polygon_zh.h (see its comments:
 * Wang 2018 Eq. 11, 14, 26-32, the small-arc dP terms, Wu 2020's gradient by
 * parts) for ZW lobes side by side in one vector, ZW = the ISA's double width
 * SHL_VDLEN (4 on AVX2), at least 2 (the scalar ISA: two SSE2 / NEON lanes or
 * plain code).  The lobes' recurrences are independent, so one band step of ZW
 * lobes is one chain of vector operations instead of ZW chains.  Written with the
 * compilers' generic vector type (elementwise + - *, no fused multiply-add: gcc's
 * C11 mode and the clang pragma below), each lane does exactly the one-lobe
 * arithmetic of polygon_zh.h (and of the Hessian's recurrence, polygon_hess.c,
 * whose values and gradients test_hessian compares with these), so all ISAs give
 * the same bits.  A partial last block repeats its last lobe.  Compiled once
 * per ISA of simd/isa_list.h (Makefile); needs the polygon geometry of
 * src/polygon.h, so it includes that header. */
#include "../src/polygon.h"
#include "kernel_api.h"
#include <string.h>

#ifdef __clang__
#pragma clang fp contract(off) /* as gcc in C11 mode: every ISA rounds as the scalar one */
#endif

#if defined(SHL_VDLEN) && SHL_VDLEN > 2
#define ZW SHL_VDLEN
#else
#define ZW 2
#endif
typedef double zv __attribute__((vector_size(ZW * sizeof(double))));

static inline zv zv_set1(double x)
{
    double t[ZW];
    for (int k = 0; k < ZW; ++k) t[k] = x;
    zv v;
    memcpy(&v, t, sizeof v);
    return v;
}

/* u . p per lane: (u0 p0 + u1 p1) + u2 p2, the order of polygon_zh.h */
static inline zv zv_dot(zv ux, zv uy, zv uz, const double p[3])
{
    return ux * zv_set1(p[0]) + uy * zv_set1(p[1]) + uz * zv_set1(p[2]);
}

static inline void zv_scatter(zv v, double *out, ptrdiff_t stride, int count)
{
    double t[ZW];
    memcpy(t, &v, sizeof t);
    for (int k = 0; k < count; ++k) out[k * stride] = t[k];
}

/* The edges e0 .. e0 + G - 1 (G <= 3) of one block of lobes side by side in each band step,
 * as simd/poly_zh_coeff.h does for the coefficients: their recurrences are independent, so
 * the G dependency chains overlap.  Every bsum[l] and gsum[ax][l] still adds the edges in
 * order (Eq. 14; Wu Eq. 11, 29), so the bits equal one edge at a time. */
__attribute__((always_inline)) static inline void zg_edges(const shl__poly_geom *g, int e0, const int G, int lmax,
                                                           zv ux, zv uy, zv uz, const shl__zh_band_consts *bc,
                                                           zv *bsum, zv (*gsum)[SHL_LMAX_MAX + 1])
{
    enum { GMAX = 3 };
    zv a[GMAX], c[GMAX], af[GMAX], c2[GMAX], s[GMAX], b1[GMAX], da[GMAX], v[GMAX], i0[GMAX], fp1[GMAX];
    zv p_lm1[GMAX], p_lm2[GMAX], dp_lm1[GMAX], dp_lm2[GMAX], b_lm1[GMAX], b_lm2[GMAX], d_lm1[GMAX], d_lm2[GMAX];
    zv i_lm1[GMAX], j_lm1[GMAX], j_lm2[GMAX], pl[GMAX], dpl[GMAX], dl[GMAX];
    double m[3][GMAX]; /* mu_e, the weight of edge e's I_l in the gradient */
#pragma GCC unroll 3
    for (int k = 0; k < G; ++k) {
        const int e = e0 + k, f = (e + 1 == g->n) ? 0 : e + 1;
        const zv gamma = zv_set1(g->gamma[e]);
        /* Eq. 20: coordinates of the lobe axes in the edge frame */
        a[k] = zv_dot(ux, uy, uz, g->w[e]);
        const zv b = zv_dot(ux, uy, uz, g->lam[e]);
        c[k] = zv_dot(ux, uy, uz, g->mu[e]), af[k] = zv_dot(ux, uy, uz, g->w[f]);
        c2[k] = c[k] * c[k]; /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
        s[k] = a[k] * zv_set1(g->sin_gamma[e]) - b * zv_set1(g->cos_gamma[e]);
        b1[k] = a[k] * zv_set1(g->sin_gamma[e]) + b * zv_set1(g->omc_gamma[e]); /* B_1, Eq. 27 */
        da[k] = zv_dot(ux, uy, uz, g->dw[e]);
        p_lm1[k] = a[k], p_lm2[k] = zv_set1(1.0);    /* P_{l-1}(a_e), P_{l-2}(a_e) */
        dp_lm1[k] = da[k], dp_lm2[k] = zv_set1(0.0); /* dP_{l-1}, dP_{l-2} */
        b_lm1[k] = b1[k], b_lm2[k] = gamma;          /* B_1, B_0 (Eq. 26-27) */
        d_lm1[k] = gamma, d_lm2[k] = zv_set1(0.0);   /* D_1, D_0 (Eq. 28) */
        bsum[0] += c[k] * gamma;
        if (lmax >= 2) bsum[1] += c[k] * b1[k];
        i0[k] = zv_set1(g->f_integral[e]), fp1[k] = zv_set1(g->fprime1[e]);
        v[k] = zv_dot(ux, uy, uz, g->gvec[e]);
        /* [f' P_l]_0^T = f'(T) dP_l - I_0 P_l(a_e), since f'(T) - f'(0) = -I_0 */
        i_lm1[k] = (v[k] * gamma - (fp1[k] * da[k] - i0[k] * a[k])) * zv_set1(0.5); /* I_1 */
        j_lm1[k] = i0[k], j_lm2[k] = zv_set1(0.0);                                 /* J_1, J_0 = 0 */
        for (int ax = 0; ax < 3; ++ax) m[ax][k] = g->mu[e][ax];
    }
    for (int ax = 0; ax < 3; ++ax) /* Wu Eq. 11, 29: sum over edges of mu_e I_l, edges in order */
        for (int k = 0; k < G; ++k) {
            gsum[ax][0] += zv_set1(m[ax][k]) * i0[k];
            if (lmax >= 1) gsum[ax][1] += zv_set1(m[ax][k]) * i_lm1[k];
        }
    for (int l = 2; l <= lmax; ++l) {
        const zv rl = zv_set1(bc->inv_l[l]), lm1 = zv_set1(bc->l_m1[l]), tlm1 = zv_set1(bc->twol_m1[l]);
        const zv rl1 = zv_set1(bc->inv_l[l + 1]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            pl[k] = (tlm1 * a[k] * p_lm1[k] - lm1 * p_lm2[k]) * rl; /* Eq. 11 */
            dl[k] = tlm1 * b_lm1[k] + d_lm2[k];                     /* Eq. 32 */
            /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
            dpl[k] = (tlm1 * (af[k] * dp_lm1[k] + da[k] * p_lm1[k]) - lm1 * dp_lm2[k]) * rl;
            const zv il = (v[k] * dl[k] - j_lm1[k] - (fp1[k] * dpl[k] - i0[k] * pl[k])) * rl1;
            const zv jl = tlm1 * i_lm1[k] + j_lm2[k];
            j_lm2[k] = j_lm1[k], j_lm1[k] = jl, i_lm1[k] = il;
        }
        for (int ax = 0; ax < 3; ++ax)
            for (int k = 0; k < G; ++k) gsum[ax][l] += zv_set1(m[ax][k]) * i_lm1[k];
        if (l == lmax) break; /* B_lmax is not needed (Eq. 29 reads B_l, l < lmax) */
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            /* Eq. 31: C_{l-1} */
            const zv cl = (b1[k] * p_lm1[k] + s[k] * dp_lm1[k] - c2[k] * d_lm1[k] + lm1 * b_lm2[k]) * rl;
            const zv bl = (tlm1 * cl - lm1 * b_lm2[k]) * rl; /* Eq. 30 */
            b_lm2[k] = b_lm1[k], b_lm1[k] = bl;
            bsum[l] += c[k] * bl; /* Eq. 14, edges in order */
            p_lm2[k] = p_lm1[k], p_lm1[k] = pl[k];
            dp_lm2[k] = dp_lm1[k], dp_lm1[k] = dpl[k];
            d_lm2[k] = d_lm1[k], d_lm1[k] = dl[k];
        }
    }
}

/* zh4 != NULL: instead of the blocks zh, zh_grad, the value and the 3 gradient
 * components of lobe d, band l side by side at zh4[4 (l (2 lmax + 1) + d) + 0..3] (grad_sh below),
 * the gradient's band weights K_l times gscale (a power of two, 1 for scaled units). */
__attribute__((always_inline)) static inline void zh_lanes(const shl__poly_geom *g, int lmax, double *zh,
                                                           double *zh_grad, double *zh4, double gscale)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    const int area = g->sliver && lmax <= SHL__AREA_LMAX; /* near-plane sliver: planar Gauss rule (polygon.c) */
    const shl__zh_band_consts *bc = shl__zh_bands(); /* the per-band constants, tabulated once */
    for (int d0 = 0; d0 < ndir; d0 += ZW) {
        double t[3][ZW];
        for (int k = 0; k < ZW; ++k)
            for (int c = 0; c < 3; ++c) t[c][k] = shl__zh_dir[d0 + k < ndir ? d0 + k : ndir - 1][c];
        zv ux, uy, uz;
        memcpy(&ux, t[0], sizeof ux);
        memcpy(&uy, t[1], sizeof uy);
        memcpy(&uz, t[2], sizeof uz);
        zv bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1], gsum[3][SHL_LMAX_MAX + 1];
        for (int l = 0; l <= lmax; ++l) bsum[l] = zv_set1(0.0);
        for (int a = 0; a < 3; ++a)
            for (int l = 0; l <= lmax; ++l) gsum[a][l] = zv_set1(0.0);
        for (int e0 = 0; e0 < n;) { /* n >= 3: groups of 3, of 2 where 2 or 4 are left */
            const int rest = n - e0;
            if (rest == 2 || rest == 4) {
                zg_edges(g, e0, 2, lmax, ux, uy, uz, bc, bsum, gsum);
                e0 += 2;
            } else {
                zg_edges(g, e0, 3, lmax, ux, uy, uz, bc, bsum, gsum);
                e0 += 3;
            }
        }
        surf[0] = zv_set1(g->solid_angle); /* S_0 */
        if (lmax >= 1) surf[1] = bsum[0] * zv_set1(0.5); /* S_1, Eq. 25 */
        for (int l = 2; l <= lmax; ++l) surf[l] = zv_set1(bc->s_b[l]) * bsum[l - 1] + zv_set1(bc->s_s[l]) * surf[l - 2]; /* Eq. 29 */
        const int cnt = ndir - d0 < ZW ? ndir - d0 : ZW;
        if (zh4) {
            for (int l = 0; l <= lmax; ++l) {
                const zv kl = zv_set1(bc->norm[l]), kg = zv_set1(bc->norm[l] * gscale);
                double t[4][ZW];
                zv_scatter(kl * surf[l], t[0], 1, ZW); /* Eq. 13 */
                for (int ax = 0; ax < 3; ++ax) zv_scatter(kg * gsum[ax][l], t[1 + ax], 1, ZW);
                double *o = zh4 + 4 * ((ptrdiff_t)l * ndir + d0);
                for (int k = 0; k < cnt; ++k)
                    for (int b = 0; b < 4; ++b) o[4 * k + b] = t[b][k];
            }
            continue;
        }
        for (int l = 0; l <= lmax; ++l) {
            const zv kl = zv_set1(bc->norm[l]);
            const ptrdiff_t at = (ptrdiff_t)d0 * SHL__ZH_STRIDE + l;
            if (!area) zv_scatter(kl * surf[l], zh + at, SHL__ZH_STRIDE, cnt); /* Eq. 13 */
            for (int ax = 0; ax < 3; ++ax) zv_scatter(kl * gsum[ax][l], zh_grad + ax * SHL__ZH_BLOCK + at, SHL__ZH_STRIDE, cnt);
        }
    }
    if (area && zh4) { /* coefficients as the non-gradient kernel */
        double za[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, za);
        for (int l = 0; l <= lmax; ++l)
            for (int d = 0; d < ndir; ++d) zh4[4 * ((ptrdiff_t)l * ndir + d)] = za[d * SHL__ZH_STRIDE + l];
    } else if (area)
        shl__poly_zh_area(g, lmax, zh);
}

#if SHL_VLEN == 1 /* the separate blocks are read by shl__poly_zh_grad_d (float path, light sets) only */
void SHL_ISA_SUFFIX(shl__poly_zh_grad)(const struct shl__poly_geom *g, int lmax, double *zh, double *zh_grad)
{
    zh_lanes(g, lmax, zh, zh_grad, NULL, 1.0);
}
#endif

/* Wang 2018 Eq. 33 with the lobe pairs of src/zh_lobes.c (lobe 2k-1 and its mirror 2k:
 * even block m >= 0 from their sums, odd block m < 0 from their differences) for the value
 * and the 3 gradient components at once, 4 doubles per lobe (one vector, or two of 2
 * without AVX): each weight is read once for all 4, and every coefficient is the sum over
 * k = 0, 1, ... in order, the sums of shl__zh_to_sh (so the coefficients equal
 * shl_polygon's bit for bit). */
#if ZW >= 4
#define ZQ 4 /* doubles per vector in grad_sh; NQ vectors hold the 4 outputs */
#else
#define ZQ 2
#endif
enum { NQ = 4 / ZQ };
typedef double zq __attribute__((vector_size(ZQ * sizeof(double))));

/* out row m (index at + step m) = sum_k W[m][k] in[k], W row-major rows x cols */
__attribute__((always_inline)) static inline void quad_matvec(const double *w, int rows, int cols,
                                                              const zq (*in)[NQ], const zq (*scale)[NQ],
                                                              double *coeffs, double *grad, int nc, int at,
                                                              int step)
{
    for (int m = 0; m < rows; ++m) {
        zq acc[NQ];
        memset(acc, 0, sizeof acc);
        for (int k = 0; k < cols; ++k) {
            const double wk = w[m * cols + k];
            for (int q = 0; q < NQ; ++q) acc[q] += wk * in[k][q];
        }
        double t[4];
        for (int q = 0; q < NQ; ++q) {
            if (scale) acc[q] = acc[q] * scale[0][q] * scale[1][q];
            memcpy(t + q * ZQ, &acc[q], sizeof acc[q]);
        }
        const int i = at + step * m;
        coeffs[i] = t[0], grad[i] = t[1], grad[nc + i] = t[2], grad[2 * nc + i] = t[3];
    }
}

/* The gradient rows are multiplied by grad_scale[0], then grad_scale[1], as
 * shl__poly_grad_unscale; grad_scale NULL: zh4's gradient is already unscaled. */
__attribute__((always_inline)) static inline void grad_sh(int lmax, const double *zh4, const double *grad_scale,
                                                          double *coeffs, double *grad, int nc)
{
    const int ndir = 2 * lmax + 1;
    zq scale[2][NQ];
    for (int j = 0; j < 2 && grad_scale; ++j) {
        const double t[4] = {1.0, grad_scale[j], grad_scale[j], grad_scale[j]};
        memcpy(scale[j], t, sizeof t);
    }
    for (int l = 0; l <= lmax; ++l) {
        const double *z = zh4 + 4 * (ptrdiff_t)l * ndir;
        zq even[SHL_LMAX_MAX + 1][NQ], odd[SHL_LMAX_MAX + 1][NQ];
        memcpy(even[0], z, sizeof even[0]);
        for (int k = 1; k <= l; ++k) {
            zq z1[NQ], z2[NQ];
            memcpy(z1, z + 4 * (2 * k - 1), sizeof z1);
            memcpy(z2, z + 4 * (2 * k), sizeof z2);
            for (int q = 0; q < NQ; ++q) {
                even[k][q] = z1[q] + z2[q];
                odd[k - 1][q] = z1[q] - z2[q];
            }
        }
        const zq(*sc)[NQ] = grad_scale ? (const zq(*)[NQ])scale : NULL;
        quad_matvec(shl__zh_even_w + SHL__ZH_EVEN_OFS(l), l + 1, l + 1, (const zq(*)[NQ])even, sc, coeffs, grad, nc,
                    l * (l + 1), 1);
        if (l > 0)
            quad_matvec(shl__zh_odd_w + SHL__ZH_ODD_OFS(l), l, l, (const zq(*)[NQ])odd, sc, coeffs, grad, nc,
                        l * (l + 1) - 1, -1);
    }
}

void SHL_ISA_SUFFIX(shl__poly_grad_sh)(const struct shl__poly_geom *g, int lmax, double *coeffs, double *grad, int nc)
{
    double zh4[4 * (2 * SHL_LMAX_MAX + 1) * (SHL_LMAX_MAX + 1)];
    if (shl__poly_hess_fold(g)) { /* 2^-E into the band weights: the same bits as multiplying afterwards */
        zh_lanes(g, lmax, NULL, NULL, zh4, g->grad_scale[0] * g->grad_scale[1]);
        grad_sh(lmax, zh4, NULL, coeffs, grad, nc);
    } else {
        zh_lanes(g, lmax, NULL, NULL, zh4, 1.0);
        grad_sh(lmax, zh4, g->grad_scale, coeffs, grad, nc);
    }
}

/* Coefficients only (shl_polygon): blocks of ZW lobes by simd/poly_zh_coeff.h (zh_lanes'
 * arithmetic per lane, edges side by side); a partial last block of at most 2 or 4 lobes
 * on 2- or 4-lane vectors, which cost a fraction of a full-width block's operations
 * (lmax 8 has 17 lobes: AVX-512 runs 8 + 8 + 1 lobes as two 8-lane blocks and one 2-lane
 * block instead of three 8-lane blocks). */
#define CW_BLOCK2(w) cv_block_##w
#define CW_BLOCK(w) CW_BLOCK2(w) /* the coefficient block of width w (poly_zh_coeff.h) */
#define CW ZW
#include "poly_zh_coeff.h"
#undef CW
#if ZW > 2
#define CW 2
#include "poly_zh_coeff.h"
#undef CW
#endif
#if ZW > 4
#define CW 4
#include "poly_zh_coeff.h"
#undef CW
#endif

void SHL_ISA_SUFFIX(shl__poly_zh)(const struct shl__poly_geom *g, int lmax, double *zh)
{
    const int ndir = 2 * lmax + 1;
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* near-plane sliver: planar Gauss rule (polygon.c) */
        shl__poly_zh_area(g, lmax, zh);
        return;
    }
    const shl__zh_band_consts *bc = shl__zh_bands(); /* zh_lanes' band constants, tabulated once */
    /* the partial block first: its few operations form a latency-bound chain, which the
     * out-of-order core overlaps with the full blocks issued after it */
    const int full = ndir - ndir % ZW, rest = ndir - full;
#if ZW > 2
    if (rest > 0 && rest <= 2) CW_BLOCK(2)(g, lmax, full, rest, bc, zh);
#if ZW > 4
    else if (rest > 0 && rest <= 4) CW_BLOCK(4)(g, lmax, full, rest, bc, zh);
#endif
    else
#endif
    if (rest > 0) CW_BLOCK(ZW)(g, lmax, full, rest, bc, zh);
    for (int d0 = 0; d0 < full; d0 += ZW) CW_BLOCK(ZW)(g, lmax, d0, ZW, bc, zh);
}
