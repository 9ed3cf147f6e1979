/* Single-call polygon ZH integrals in double (shl_polygon, shl_polygon_grad),
 * vectorized ACROSS LOBES: the recurrence of src/polygon_zh.h (see its comments:
 * Wang 2018 Eq. 11, 14, 26-32, the small-arc dP terms, Wu 2020's gradient by
 * parts) for ZW lobes side by side in one vector, ZW = the ISA's double width
 * SHL_VDLEN (4 on AVX2), at least 2 (the scalar ISA: two SSE2 / NEON lanes or
 * plain code).  The lobes' recurrences are independent, so one band step of ZW
 * lobes is one chain of vector operations instead of ZW chains.  Written with the
 * compilers' generic vector type (elementwise + - *, no fused multiply-add: gcc's
 * C11 mode and the clang pragma of dvec.h), each lane does exactly the one-lobe
 * arithmetic of polygon_zh.h (and of the Hessian's recurrence, polygon_hess.c,
 * whose values and gradients test_hessian compares with these), so all ISAs give
 * the same bits.  A partial last block repeats its last lobe.  Compiled once
 * per ISA of simd/isa_list.h (Makefile); needs the polygon geometry of
 * src/polygon.h, so it includes that header. */
#include "../src/polygon.h"
#include "kernel_api.h"
#include <string.h>
#include "dvec.h" /* also: no FMA contraction, every ISA rounds as the scalar one */

#define ZW SHL_DVEC_WIDTH
#define ZV_CAT2(a, b) a##b
#define ZV_CAT(a, b) ZV_CAT2(a, b)
#define zv ZV_CAT(dv, ZW) /* simd/dvec.h's full-width vector and its verbs */
#define zv_set1 ZV_CAT(zv, _set1)
#define zv_load ZV_CAT(zv, _load)
/* Every lobe of zh_lanes' outputs (gv_block of simd/poly_zh_grad.h): blocks of ZW lobes, a
 * partial last block of at most 2 or 4 lobes on 2- or 4-lane vectors (as shl__poly_zh below). */
#define GV_BLOCK2(w) gv_block_##w
#define GV_BLOCK(w) GV_BLOCK2(w)
#define GW ZW
#include "poly_zh_grad.h"
#undef GW
#if ZW > 2
#define GW 2
#include "poly_zh_grad.h"
#undef GW
#endif
#if ZW > 4
#define GW 4
#include "poly_zh_grad.h"
#undef GW
#endif

#if ZW >= 4
#define ZQ 4 /* doubles per vector in zh_lobe and grad_sh; NQ vectors hold the 4 outputs */
#else
#define ZQ 2
#endif
enum { NQ = 4 / ZQ };
typedef double zq __attribute__((vector_size(ZQ * sizeof(double))));

/* A lone lobe d (2 lmax + 1 = 1 mod ZW: lmax 8 on AVX2 is 16 + 1 lobes) with its edges side by
 * side instead, LW per vector (groups of LW in edge order, spare lanes repeating the group's last
 * edge): one chain of vector operations where gv_block would run G copies of the lobe, one per
 * edge.  Lane k does edge e0 + k's arithmetic of gv_edges, operation for operation (gv_dot's
 * u . p per lane is these products and sums), and the sums over edges (Eq. 14; Wu Eq. 11, 29)
 * add each edge's terms (c_e B_l, mu_e I_l as the 4 doubles of zq) in edge order from 0 + the
 * first, as gv_accumulate: gv_block's bits. */
#if ZW >= 4
#define LW 4
#else
#define LW 2
#endif
#define lv ZV_CAT(dv, LW)
#define lv_set1 ZV_CAT(lv, _set1)

/* lanes p[k[0]], p[k[1]], ... (column c of rows k[0], ...), built in registers */
#if LW == 4
#define LV_LANES(x) (lv){x(0), x(1), x(2), x(3)}
#else
#define LV_LANES(x) (lv){x(0), x(1)}
#endif
static inline lv lv_gather(const double *p, const int *k)
{
#define LV_AT(j) p[k[j]]
    return LV_LANES(LV_AT);
#undef LV_AT
}
static inline lv lv_col(const double (*p)[3], int c, const int *k)
{
#define LV_AT(j) p[k[j]][c]
    return LV_LANES(LV_AT);
#undef LV_AT
}
#undef LV_LANES

static void zh_lobe(const shl__poly_geom *g, int lmax, int d, const shl__zh_band_consts *bc, double *zh,
                    double *zh_grad, double *zh4, double gscale, int area)
{
    enum { NF = 24 }; /* per-edge inputs: w_e, lambda_e, mu_e, w_f, dw_e, gvec_e, 4 of gamma, I_0, f' */
    const int n = g->n, ndir = 2 * lmax + 1;
    const lv ux = lv_set1(shl__zh_dir[d][0]), uy = lv_set1(shl__zh_dir[d][1]), uz = lv_set1(shl__zh_dir[d][2]);
    zq sum[SHL_LMAX_MAX + 1][NQ]; /* per band: sum_e c_e B_l (Eq. 14), sum_e mu_e I_l (Wu Eq. 11, 29) */
    for (int l = 0; l <= lmax; ++l)
        for (int q = 0; q < NQ; ++q) sum[l][q] = (zq){0};
    for (int e0 = 0; e0 < n; e0 += LW) {
        const int cnt = n - e0 < LW ? n - e0 : LW;
        int ek[LW], fk[LW];
        for (int k = 0; k < LW; ++k) {
            ek[k] = e0 + (k < cnt ? k : cnt - 1);
            fk[k] = ek[k] + 1 == n ? 0 : ek[k] + 1;
        }
        /* the lanes built in registers (scalar stores read back as a vector would stall) */
        lv in[NF];
        for (int c = 0; c < 3; ++c) {
            in[c] = lv_col(g->w, c, ek), in[3 + c] = lv_col(g->lam, c, ek), in[6 + c] = lv_col(g->mu, c, ek);
            in[9 + c] = lv_col(g->w, c, fk), in[12 + c] = lv_col(g->dw, c, ek), in[15 + c] = lv_col(g->gvec, c, ek);
        }
        in[18] = lv_gather(g->gamma, ek), in[19] = lv_gather(g->sin_gamma, ek);
        in[20] = lv_gather(g->cos_gamma, ek), in[21] = lv_gather(g->omc_gamma, ek);
        in[22] = lv_gather(g->f_integral, ek), in[23] = lv_gather(g->fprime1, ek);
        const lv gamma = in[18], i0 = in[22], fp1 = in[23], mx = in[6], my = in[7], mz = in[8];
        /* Eq. 20 (gv_edges) */
        const lv a = ux * in[0] + uy * in[1] + uz * in[2], b = ux * in[3] + uy * in[4] + uz * in[5];
        const lv c = ux * mx + uy * my + uz * mz, af = ux * in[9] + uy * in[10] + uz * in[11];
        const lv da = ux * in[12] + uy * in[13] + uz * in[14], v = ux * in[15] + uy * in[16] + uz * in[17];
        const lv c2 = c * c, s = a * in[19] - b * in[20], b1 = a * in[19] + b * in[21]; /* B_1, Eq. 27 */
        lv p_lm1 = a, p_lm2 = lv_set1(1.0), dp_lm1 = da, dp_lm2 = lv_set1(0.0);
        lv b_lm1 = b1, b_lm2 = gamma, d_lm1 = gamma, d_lm2 = lv_set1(0.0);
        lv i_lm1 = (v * gamma - (fp1 * da - i0 * a)) * lv_set1(0.5), j_lm1 = i0, j_lm2 = lv_set1(0.0); /* I_1, J_1, J_0 */
        lv tb = c * gamma, ti = i0; /* band l's c_e B_l and I_l */
        for (int l = 0; l <= lmax; ++l) {
            if (l >= 2) {
                const lv pa = lv_set1(bc->leg_a[l]), pb = lv_set1(bc->leg_b[l]), tlm1 = lv_set1(bc->twol_m1[l]);
                const lv pl = pa * a * p_lm1 - pb * p_lm2;                    /* Eq. 11 */
                const lv dl = tlm1 * b_lm1 + d_lm2;                           /* Eq. 32 */
                const lv dpl = pa * (af * dp_lm1 + da * p_lm1) - pb * dp_lm2; /* dP_l */
                ti = (v * dl - j_lm1 - (fp1 * dpl - i0 * pl)) * lv_set1(bc->inv_l[l + 1]);
                const lv jl = tlm1 * i_lm1 + j_lm2;
                j_lm2 = j_lm1, j_lm1 = jl, i_lm1 = ti;
                if (l < lmax) { /* Eq. 30-31 */
                    const lv bl = lv_set1(bc->b_alpha[l]) * (b1 * p_lm1 + s * dp_lm1 - c2 * d_lm1) +
                                  lv_set1(bc->b_beta[l]) * b_lm2;
                    b_lm2 = b_lm1, b_lm1 = bl;
                    tb = c * bl;
                }
                p_lm2 = p_lm1, p_lm1 = pl;
                dp_lm2 = dp_lm1, dp_lm1 = dpl;
                d_lm2 = d_lm1, d_lm1 = dl;
            } else if (l == 1)
                tb = c * b1, ti = i_lm1;
            const lv tx = mx * ti, ty = my * ti, tz = mz * ti;
#if LW == 4 /* ZQ 4 too */
            /* edge k's 4 terms are lane k of tb, tx, ty, tz: a 4 x 4 transpose in the registers
             * (lane reads of the vectors went through the stack: store-forwarding stalls) */
            const lv t0 = dv4_shuffle(tb, tx, 0, 4, 2, 6), t1 = dv4_shuffle(tb, tx, 1, 5, 3, 7);
            const lv t2 = dv4_shuffle(ty, tz, 0, 4, 2, 6), t3 = dv4_shuffle(ty, tz, 1, 5, 3, 7);
            const lv q[4] = {dv4_shuffle(t0, t2, 0, 1, 4, 5), dv4_shuffle(t1, t3, 0, 1, 4, 5), dv4_shuffle(t0, t2, 2, 3, 6, 7),
                             dv4_shuffle(t1, t3, 2, 3, 6, 7)};
#pragma GCC unroll 4
            for (int k = 0; k < LW; ++k) /* edges in order */
                if (k < cnt) sum[l][0] += q[k];
#else
            for (int k = 0; k < cnt; ++k) { /* edges in order */
                const double q[4] = {tb[k], tx[k], ty[k], tz[k]};
                for (int h = 0; h < NQ; ++h) {
                    zq x;
                    memcpy(&x, q + h * ZQ, sizeof x);
                    sum[l][h] += x;
                }
            }
#endif
        }
    }
    double surf[SHL_LMAX_MAX + 1];
    surf[0] = g->solid_angle; /* S_0 */
    if (lmax >= 1) surf[1] = sum[0][0][0] * 0.5; /* S_1, Eq. 25 */
    for (int l = 2; l <= lmax; ++l) surf[l] = bc->s_b[l] * sum[l - 1][0][0] + bc->s_s[l] * surf[l - 2]; /* Eq. 29 */
    for (int l = 0; l <= lmax; ++l) { /* Eq. 13 */
        const double kl = bc->norm[l];
        if (zh4) { /* the sums' vectors times K_l gscale, then the value over lane 0 (not read back) */
            double *o = zh4 + 4 * ((ptrdiff_t)l * ndir + d);
            for (int h = 0; h < NQ; ++h) {
                const zq x = sum[l][h] * (bc->norm[l] * gscale);
                memcpy(o + h * ZQ, &x, sizeof x);
            }
            o[0] = kl * surf[l];
            continue;
        }
        const ptrdiff_t at = (ptrdiff_t)d * SHL__ZH_STRIDE + l;
        double o[4];
        memcpy(o, sum[l], sizeof o);
        if (!area) zh[at] = kl * surf[l];
        for (int ax = 0; ax < 3; ++ax) zh_grad[ax * SHL__ZH_BLOCK + at] = kl * o[1 + ax];
    }
}

/* shl_polygon's lone lobe d, its edges side by side as in zh_lobe: lane k does edge e0 + k's
 * arithmetic of cv_edges (simd/poly_zh_coeff.h) operation for operation, and each bsum[l]
 * adds the edges' c_e B_l (Eq. 14) in edge order from 0 + the first, as cv_edges: cv_block's
 * bits, one chain of vector operations instead of a 2-lane block of copies of the lobe. */
static void cv_lobe(const shl__poly_geom *g, int lmax, int d, const shl__zh_band_consts *bc, double *zh)
{
    const int n = g->n;
    const lv ux = lv_set1(shl__zh_dir[d][0]), uy = lv_set1(shl__zh_dir[d][1]), uz = lv_set1(shl__zh_dir[d][2]);
    double bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) bsum[l] = 0.0;
    for (int e0 = 0; e0 < n; e0 += LW) {
        const int cnt = n - e0 < LW ? n - e0 : LW;
        int ek[LW], fk[LW];
        for (int k = 0; k < LW; ++k) {
            ek[k] = e0 + (k < cnt ? k : cnt - 1);
            fk[k] = ek[k] + 1 == n ? 0 : ek[k] + 1;
        }
        /* the lanes built in registers (scalar stores read back as a vector would stall) */
        lv in[19]; /* w_e, lambda_e, mu_e, w_f, dw_e, 4 of gamma */
        for (int c = 0; c < 3; ++c) {
            in[c] = lv_col(g->w, c, ek), in[3 + c] = lv_col(g->lam, c, ek), in[6 + c] = lv_col(g->mu, c, ek);
            in[9 + c] = lv_col(g->w, c, fk), in[12 + c] = lv_col(g->dw, c, ek);
        }
        in[15] = lv_gather(g->gamma, ek), in[16] = lv_gather(g->sin_gamma, ek);
        in[17] = lv_gather(g->cos_gamma, ek), in[18] = lv_gather(g->omc_gamma, ek);
        const lv gamma = in[15];
        /* Eq. 20 */
        const lv a = ux * in[0] + uy * in[1] + uz * in[2], b = ux * in[3] + uy * in[4] + uz * in[5];
        const lv c = ux * in[6] + uy * in[7] + uz * in[8], af = ux * in[9] + uy * in[10] + uz * in[11];
        const lv da = ux * in[12] + uy * in[13] + uz * in[14];
        const lv c2 = c * c, s = a * in[16] - b * in[17], b1 = a * in[16] + b * in[18]; /* B_1, Eq. 27 */
        lv p_lm1 = a, p_lm2 = lv_set1(1.0), dp_lm1 = da, dp_lm2 = lv_set1(0.0);
        lv b_lm1 = b1, b_lm2 = gamma, d_lm1 = gamma, d_lm2 = lv_set1(0.0);
        lv tb[SHL_LMAX_MAX]; /* c_e B_l, summed after the recurrence (lane reads of a fresh store would stall) */
        for (int l = 0; l < lmax; ++l) {
            if (l >= 2) {
                const lv bl = lv_set1(bc->b_alpha[l]) * (b1 * p_lm1 + s * dp_lm1 - c2 * d_lm1) +
                              lv_set1(bc->b_beta[l]) * b_lm2; /* Eq. 30-31 */
                tb[l] = c * bl;
                if (l + 1 == lmax) break; /* P_l, D_l, dP_l would feed band l + 1 only */
                const lv pa = lv_set1(bc->leg_a[l]), pb = lv_set1(bc->leg_b[l]), tlm1 = lv_set1(bc->twol_m1[l]);
                const lv pl = pa * a * p_lm1 - pb * p_lm2;                    /* Eq. 11 */
                const lv dl = tlm1 * b_lm1 + d_lm2;                           /* Eq. 32 */
                const lv dpl = pa * (af * dp_lm1 + da * p_lm1) - pb * dp_lm2; /* dP_l */
                b_lm2 = b_lm1, b_lm1 = bl;
                p_lm2 = p_lm1, p_lm1 = pl;
                dp_lm2 = dp_lm1, dp_lm1 = dpl;
                d_lm2 = d_lm1, d_lm1 = dl;
            } else
                tb[l] = c * (l ? b1 : gamma);
        }
        for (int l = 0; l < lmax; ++l)
            for (int k = 0; k < cnt; ++k) bsum[l] += tb[l][k]; /* edges in order */
    }
    surf[0] = g->solid_angle; /* S_0 */
    if (lmax >= 1) surf[1] = bsum[0] * 0.5; /* S_1, Eq. 25 */
    for (int l = 2; l <= lmax; ++l) surf[l] = bc->s_b[l] * bsum[l - 1] + bc->s_s[l] * surf[l - 2]; /* Eq. 29 */
    for (int l = 0; l <= lmax; ++l) zh[(ptrdiff_t)d * SHL__ZH_STRIDE + l] = bc->norm[l] * surf[l]; /* Eq. 13 */
}
#undef lv_set1
#undef lv
#undef LW

__attribute__((always_inline)) static inline void zh_lanes(const shl__poly_geom *g, int lmax, double *zh,
                                                           double *zh_grad, double *zh4, double gscale)
{
    const int ndir = 2 * lmax + 1;
    const int area = g->sliver && lmax <= SHL__AREA_LMAX; /* near-plane sliver: planar Gauss rule (polygon.c) */
    const shl__zh_band_consts *bc = shl__zh_bands(); /* the per-band constants, tabulated once */
    const int full = ndir - ndir % ZW, rest = ndir - full;
    if (rest == 1) zh_lobe(g, lmax, full, bc, zh, zh_grad, zh4, gscale, area);
#if ZW > 2
    else if (rest > 0 && rest <= 2) GV_BLOCK(2)(g, lmax, full, rest, bc, zh, zh_grad, zh4, gscale, area);
#if ZW > 4
    else if (rest > 0 && rest <= 4) GV_BLOCK(4)(g, lmax, full, rest, bc, zh, zh_grad, zh4, gscale, area);
#endif
#endif
    else if (rest > 0) GV_BLOCK(ZW)(g, lmax, full, rest, bc, zh, zh_grad, zh4, gscale, area);
    for (int d0 = 0; d0 < full; d0 += ZW) GV_BLOCK(ZW)(g, lmax, d0, ZW, bc, zh, zh_grad, zh4, gscale, area);
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
/* out rows m0 .. m0 + R - 1 (index at + step m) = sum_k W[m][k] in[k], W row-major with
 * cols columns: the R rows' sums side by side (R independent add chains instead of one) */
__attribute__((always_inline)) static inline void quad_rows(const double *w, int m0, const int R, int cols,
                                                            const zq (*in)[NQ], const zq (*scale)[NQ],
                                                            double *coeffs, double *grad, int nc, int at, int step)
{
    enum { RMAX = 4 };
    zq acc[RMAX][NQ];
    memset(acc, 0, sizeof acc);
    for (int k = 0; k < cols; ++k)
#pragma GCC unroll 4
        for (int r = 0; r < R; ++r) {
            const double wk = w[(m0 + r) * cols + k];
            for (int q = 0; q < NQ; ++q) acc[r][q] += wk * in[k][q];
        }
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r) {
        double t[4];
        for (int q = 0; q < NQ; ++q) {
            if (scale) acc[r][q] = acc[r][q] * scale[0][q] * scale[1][q];
            memcpy(t + q * ZQ, &acc[r][q], sizeof acc[r][q]);
        }
        const int i = at + step * (m0 + r);
        coeffs[i] = t[0], grad[i] = t[1], grad[nc + i] = t[2], grad[2 * nc + i] = t[3];
    }
}

/* out row m (index at + step m) = sum_k W[m][k] in[k], W row-major rows x cols; rows four at a time */
__attribute__((always_inline)) static inline void quad_matvec(const double *w, int rows, int cols,
                                                              const zq (*in)[NQ], const zq (*scale)[NQ],
                                                              double *coeffs, double *grad, int nc, int at,
                                                              int step)
{
    int m = 0;
    for (; m + 4 <= rows; m += 4) quad_rows(w, m, 4, cols, in, scale, coeffs, grad, nc, at, step);
    if (rows - m == 3) quad_rows(w, m, 3, cols, in, scale, coeffs, grad, nc, at, step);
    if (rows - m == 2) quad_rows(w, m, 2, cols, in, scale, coeffs, grad, nc, at, step);
    if (rows - m == 1) quad_rows(w, m, 1, cols, in, scale, coeffs, grad, nc, at, step);
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
 * arithmetic per lane, edges side by side); a lone last lobe by cv_lobe above from lmax 4
 * (below, building its 19 vectors of edge data lane by lane costs more than the few bands
 * save: lmax 2 on AVX2, cv_lobe took 8.0% of the samples, the 2-lane block 5.4%); another
 * partial last block of at most 2 or 4 lobes on 2- or 4-lane vectors, a fraction of a
 * full-width block's operations (AVX-512 runs lmax 5's 11 lobes as an 8-lane block and 3
 * of 4 lanes). */
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
    if (rest == 1 && lmax >= 4) cv_lobe(g, lmax, full, bc, zh);
#if ZW > 2
    else if (rest > 0 && rest <= 2) CW_BLOCK(2)(g, lmax, full, rest, bc, zh);
#if ZW > 4
    else if (rest > 0 && rest <= 4) CW_BLOCK(4)(g, lmax, full, rest, bc, zh);
#endif
#endif
    else if (rest > 0) CW_BLOCK(ZW)(g, lmax, full, rest, bc, zh);
    for (int d0 = 0; d0 < full; d0 += ZW) CW_BLOCK(ZW)(g, lmax, d0, ZW, bc, zh);
}

/* out[at + step m] = sum_k W[m][k] in[k] for the rows m < rows of a transposed block of
 * shl__zh_lobe_blocks: 2 ZW rows per pass over k (two independent sums), then ZW, then 2
 * (the padded column holds an even count); every coefficient is the sum over k = 0, 1, ...
 * in order, as in shl__zh_to_sh, so the results are its bits. */
__attribute__((always_inline)) static inline void sh_matvec(const double *wt, int rows, int cols, const double *in,
                                                            double *out, int at, int step)
{
    const int padded = rows + (rows & 1); /* doubles per column */
    int r = 0;
    for (; r + 2 * ZW <= padded; r += 2 * ZW) {
        zv acc0 = zv_set1(0.0), acc1 = acc0;
        for (int k = 0; k < cols; ++k) {
            const zv x = zv_set1(in[k]);
            acc0 += zv_load(wt + (ptrdiff_t)k * padded + r) * x;
            acc1 += zv_load(wt + (ptrdiff_t)k * padded + r + ZW) * x;
        }
        /* lane reads at constant indices, not a memcpy or a variable index: through memory gcc
         * stored the sums and loaded them back in pieces (store-forwarding stalls) */
#pragma GCC unroll 8
        for (int j = 0; j < ZW; ++j) out[at + step * (r + j)] = acc0[j];
#pragma GCC unroll 8
        for (int j = 0; j < ZW; ++j)
            if (r + ZW + j < rows) out[at + step * (r + ZW + j)] = acc1[j];
    }
    for (; r + ZW <= padded; r += ZW) {
        zv acc = zv_set1(0.0);
        for (int k = 0; k < cols; ++k) acc += zv_load(wt + (ptrdiff_t)k * padded + r) * zv_set1(in[k]);
#pragma GCC unroll 8
        for (int j = 0; j < ZW; ++j)
            if (r + j < rows) out[at + step * (r + j)] = acc[j];
    }
    for (; r < padded; r += 2) { /* ZW > 2 only */
        dv2 acc = dv2_set1(0.0);
        for (int k = 0; k < cols; ++k) acc += dv2_load(wt + (ptrdiff_t)k * padded + r) * dv2_set1(in[k]);
        out[at + step * r] = acc[0];
        if (r + 1 < rows) out[at + step * (r + 1)] = acc[1];
    }
}

/* shl_polygon after the set-up: the ZH integrals of shl__poly_zh above reconstructed as by
 * shl__zh_to_sh (Wang 2018 Eq. 33 with the lobe pairs of src/zh_lobes.c), its weights on
 * ZW rows per vector instead of 2. */
void SHL_ISA_SUFFIX(shl__poly_sh)(const struct shl__poly_geom *g, int lmax, double *coeffs)
{
    double zh[SHL__ZH_BLOCK];
    SHL_ISA_SUFFIX(shl__poly_zh)(g, lmax, zh);
    shl__zh_blocks w;
    shl__zh_lobe_blocks(&w);
    for (int l = 0; l <= lmax; ++l) {
        double even[SHL_LMAX_MAX + 1], odd[SHL_LMAX_MAX + 1];
        even[0] = zh[l];
        for (int k = 1; k <= l; ++k) {
            const double z1 = zh[l + (ptrdiff_t)(2 * k - 1) * SHL__ZH_STRIDE], z2 = zh[l + (ptrdiff_t)(2 * k) * SHL__ZH_STRIDE];
            even[k] = z1 + z2;
            odd[k - 1] = z1 - z2;
        }
        sh_matvec(w.even + 2 * (ptrdiff_t)w.even_at[l], l + 1, l + 1, even, coeffs, l * (l + 1), 1);
        if (l > 0) sh_matvec(w.odd + 2 * (ptrdiff_t)w.odd_at[l], l, l, odd, coeffs, l * (l + 1) - 1, -1);
    }
}
