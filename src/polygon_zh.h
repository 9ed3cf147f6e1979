/* ZH recurrence of Wang & Ramamoorthi 2018 (Sec. 4.1, Alg. 1), optionally with
 * the spatial gradient of every ZH integral (Wu et al. 2020, Sec. 5), in one
 * pass that shares the B/D edge recurrences and the Legendre values at the
 * vertices.  Instantiated by polygon.c with REAL = float (the double version is
 * simd/poly_zh_batch.h, the same arithmetic) and
 * WITH_GRAD = 0/1; SUFFIX names the instance.
 *
 * Gradient.  Wu 2020 Eq. (10)-(16): d/dx_a of the ZH integral of lobe w_c is
 * K_l sum_e mu_e[a] int_0^T_e P_l(h(t)) / ell(t) dt, with h = w_c . w(t) and
 * ell(t) the distance to the edge along w(t).  Instead of Eq. (23), which
 * divides by A = |(c_x, c_y)| and by sin T_e (both vanish in real scenes), we
 * write 1/ell(t) = f(t) = g_e . w(t), with g_e = q_e/|q_e|^2 and q_e the foot of
 * x on the edge's line, and integrate by parts: with V = g_e . w_c (note
 * f'h' + f h = V is constant on the arc) and h P_l' = l P_l + P_{l-1}',
 *   I_l = int f P_l(h) dt   = (V D_l - J_{l-1} - [f' P_l(h)]_0^T) / (l+1),
 *   J_l = int f P_l'(h) dt  = (2l-1) I_{l-1} + J_{l-2},   I_0 = f'(0) - f'(T),
 * where D_l is Wang's Eq. (32) recurrence.  No division by A or sin T remains.
 *
 * Small arcs.  In Eq. (31) the terms s P_{l-1}(a_{e+1}) + b P_{l-1}(a_e) are O(1)
 * while their sum is O(gamma): for a polygon 1e-5 rad across, the naive form
 * loses 10 digits.  We carry dP_l = P_l(a_{e+1}) - P_l(a_e) by its own
 * recurrence from da = a_{e+1} - a_e (taken from w_{e+1} - w_e built from vertex
 * differences) and write s P(a_{e+1}) + b P(a_e) = B_1 P(a_e) + s dP, with
 * B_1 = a sin(gamma) + b (1 - cos(gamma)) formed in double.
 *
 * Loop order (the float instances; the double recurrence is simd/poly_zh_batch.h,
 * the same arithmetic across lobes in vectors).  Lobes in blocks of SHL__ZH_LANES side by side (their recurrences
 * are independent: with one lobe at a time every band step waited on the
 * previous one), edges next, bands innermost with the lanes inside each band
 * step, so the lanes' chains overlap in the pipeline (or share SIMD registers).
 * Each lane does exactly the one-lobe arithmetic, so results are unchanged bit
 * for bit.  A partial last block repeats its last lobe in the spare lanes.
 * Two lanes: gcc -O2 keeps them in one SSE2 register; 3 or 4 lanes spilled the
 * state and measured slower (and pad more lobes at low lmax).  The lane loops
 * are unrolled (#pragma GCC unroll) so the lane arrays live in registers.
 * Each edge's recurrence state stays in registers and only the per-band sums
 * (Eq. 14 and the gradient) touch memory; the surface recurrence (Eq. 29) runs
 * afterwards over the sums. */

#ifndef SHL__ZH_LANES
#define SHL__ZH_LANES 2
#endif

void SUFFIX(shl__poly_zh)(const shl__poly_geom *g, int lmax, REAL *zh
#if WITH_GRAD
                          , REAL *zh_grad /* 3 blocks of the zh layout, one per axis */
#endif
)
{
    const int n = g->n, ndir = 2 * lmax + 1;
#if !WITH_GRAD
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* near-plane sliver: planar Gauss rule (polygon.c) */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) zh[dir * SHL__ZH_STRIDE + l] = (REAL)area[dir * SHL__ZH_STRIDE + l];
        return;
    }
#endif
    /* bands whose edge integrals are needed: B_l up to lmax-1 (Eq. 29); the gradient needs l = lmax too */
    const int ltop = WITH_GRAD ? lmax : lmax - 1;
    /* the double kernels' band constants (shl__zh_bands, polygon.h), rounded to REAL */
    const shl__zh_band_consts *bc = shl__zh_bands();
    REAL norm[SHL_LMAX_MAX + 1], s_b[SHL_LMAX_MAX + 1], s_s[SHL_LMAX_MAX + 1];
    REAL twol_m1[SHL_LMAX_MAX + 1], leg_a[SHL_LMAX_MAX + 1], leg_b[SHL_LMAX_MAX + 1], b_alpha[SHL_LMAX_MAX + 1],
        b_beta[SHL_LMAX_MAX + 1];
#if WITH_GRAD
    REAL inv_lp1[SHL_LMAX_MAX + 1]; /* 1 / (l+1), Wu's I_l step */
    for (int l = 0; l <= lmax; ++l) inv_lp1[l] = (REAL)bc->inv_l[l + 1];
#endif
    for (int l = 0; l <= lmax; ++l) {
        twol_m1[l] = (REAL)bc->twol_m1[l];
        leg_a[l] = (REAL)bc->leg_a[l], leg_b[l] = (REAL)bc->leg_b[l];
        b_alpha[l] = (REAL)bc->b_alpha[l], b_beta[l] = (REAL)bc->b_beta[l];
        norm[l] = (REAL)bc->norm[l];                   /* K_l */
        s_b[l] = (REAL)bc->s_b[l], s_s[l] = (REAL)bc->s_s[l]; /* Eq. 29 weights */
    }
    enum { NL = SHL__ZH_LANES };
    for (int d0 = 0; d0 < ndir; d0 += NL) {
        const double *lobe[NL];
        for (int k = 0; k < NL; ++k) lobe[k] = shl__zh_dir[d0 + k < ndir ? d0 + k : ndir - 1];
        REAL bsum[SHL_LMAX_MAX + 1][NL], surf[SHL_LMAX_MAX + 1][NL];
#if WITH_GRAD
        /* I_l per edge; summed with the edge normals after the loop keeps mu out of the hot registers */
        REAL edge_i[SHL_MAX_VERTS][SHL_LMAX_MAX + 1][NL];
#endif
        for (int l = 0; l <= lmax; ++l)
            for (int k = 0; k < NL; ++k) bsum[l][k] = 0;
        for (int e = 0; e < n; ++e) {
            const int f = (e + 1 == n) ? 0 : e + 1;
            REAL a[NL], c[NL], af[NL], c2[NL], s[NL], b1[NL], da[NL];
            REAL p_lm1[NL], p_lm2[NL], dp_lm1[NL], dp_lm2[NL], b_lm1[NL], b_lm2[NL], d_lm1[NL], d_lm2[NL];
            const REAL gamma = (REAL)g->gamma[e];
#if WITH_GRAD
            const REAL i0 = (REAL)g->f_integral[e], fp1 = (REAL)g->fprime1[e];
            REAL v[NL], i_lm1[NL], j_lm1[NL], j_lm2[NL];
#endif
#pragma GCC unroll 8
            for (int k = 0; k < NL; ++k) {
                const double *u = lobe[k];
                /* Eq. 20: coordinates of the lobe axis in the edge frame */
                const double ae = u[0] * g->w[e][0] + u[1] * g->w[e][1] + u[2] * g->w[e][2];
                const double be = u[0] * g->lam[e][0] + u[1] * g->lam[e][1] + u[2] * g->lam[e][2];
                const double ce = u[0] * g->mu[e][0] + u[1] * g->mu[e][1] + u[2] * g->mu[e][2];
                a[k] = (REAL)ae, c[k] = (REAL)ce;
                af[k] = (REAL)(u[0] * g->w[f][0] + u[1] * g->w[f][1] + u[2] * g->w[f][2]);
                c2[k] = (REAL)(ce * ce); /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
                s[k] = (REAL)(ae * g->sin_gamma[e] - be * g->cos_gamma[e]);
                b1[k] = (REAL)(ae * g->sin_gamma[e] + be * g->omc_gamma[e]); /* B_1, Eq. 27 */
                da[k] = (REAL)(u[0] * g->dw[e][0] + u[1] * g->dw[e][1] + u[2] * g->dw[e][2]);
                p_lm1[k] = a[k], p_lm2[k] = 1;         /* P_{l-1}(a_e), P_{l-2}(a_e) */
                dp_lm1[k] = da[k], dp_lm2[k] = 0;      /* dP_{l-1}, dP_{l-2} */
                b_lm1[k] = b1[k], b_lm2[k] = gamma;    /* B_1, B_0 (Eq. 26-27) */
                d_lm1[k] = gamma, d_lm2[k] = 0;        /* D_1, D_0 (Eq. 28) */
                bsum[0][k] += c[k] * gamma;
                if (lmax >= 2) bsum[1][k] += c[k] * b1[k];
#if WITH_GRAD
                v[k] = (REAL)(u[0] * g->gvec[e][0] + u[1] * g->gvec[e][1] + u[2] * g->gvec[e][2]);
                /* [f' P_l]_0^T = f'(T) dP_l - I_0 P_l(a_e), since f'(T) - f'(0) = -I_0 */
                i_lm1[k] = (v[k] * gamma - (fp1 * da[k] - i0 * a[k])) / 2; /* I_1 */
                j_lm1[k] = i0, j_lm2[k] = 0;                                /* J_1, J_0 */
                edge_i[e][0][k] = i0;
                if (lmax >= 1) edge_i[e][1][k] = i_lm1[k];
#endif
            }
            for (int l = 2; l <= ltop; ++l) {
                const REAL pa = leg_a[l], pb = leg_b[l], tlm1 = twol_m1[l];
#pragma GCC unroll 8
                for (int k = 0; k < NL; ++k) {
                    const REAL pl = pa * a[k] * p_lm1[k] - pb * p_lm2[k]; /* Eq. 11 */
                    const REAL dl = tlm1 * b_lm1[k] + d_lm2[k];           /* Eq. 32 */
                    /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
                    const REAL dpl = pa * (af[k] * dp_lm1[k] + da[k] * p_lm1[k]) - pb * dp_lm2[k];
#if WITH_GRAD
                    const REAL il = (v[k] * dl - j_lm1[k] - (fp1 * dpl - i0 * pl)) * inv_lp1[l];
                    const REAL jl = tlm1 * i_lm1[k] + j_lm2[k];
                    j_lm2[k] = j_lm1[k], j_lm1[k] = jl, i_lm1[k] = il;
                    edge_i[e][l][k] = il;
                    /* B_lmax (l = ltop here) goes into the unused bsum[lmax]: no branch in the lanes */
#endif
                    /* Eq. 30 with Eq. 31's C_{l-1} = (X + (l-1) B_{l-2}) / l: B_l = alpha X + beta B_{l-2} */
                    const REAL bl =
                        b_alpha[l] * (b1[k] * p_lm1[k] + s[k] * dp_lm1[k] - c2[k] * d_lm1[k]) + b_beta[l] * b_lm2[k];
                    b_lm2[k] = b_lm1[k], b_lm1[k] = bl;
                    bsum[l][k] += c[k] * bl;                                              /* Eq. 14 */
                    p_lm2[k] = p_lm1[k], p_lm1[k] = pl;
                    dp_lm2[k] = dp_lm1[k], dp_lm1[k] = dpl;
                    d_lm2[k] = d_lm1[k], d_lm1[k] = dl;
                }
            }
        }
        for (int k = 0; k < NL; ++k) {
            surf[0][k] = (REAL)g->solid_angle;                               /* S_0 */
            if (lmax >= 1) surf[1][k] = bsum[0][k] / 2;                      /* S_1, Eq. 25 */
        }
        for (int l = 2; l <= lmax; ++l)
            for (int k = 0; k < NL; ++k) surf[l][k] = s_b[l] * bsum[l - 1][k] + s_s[l] * surf[l - 2][k]; /* Eq. 29 */
        for (int l = 0; l <= lmax; ++l) {
#if WITH_GRAD
            REAL gx[NL], gy[NL], gz[NL]; /* Wu Eq. 11, 29: sum over edges of mu_e I_l */
            for (int k = 0; k < NL; ++k) gx[k] = 0, gy[k] = 0, gz[k] = 0;
            for (int e = 0; e < n; ++e) {
                const REAL mx = (REAL)g->mu[e][0], my = (REAL)g->mu[e][1], mz = (REAL)g->mu[e][2];
                for (int k = 0; k < NL; ++k) {
                    gx[k] += mx * edge_i[e][l][k];
                    gy[k] += my * edge_i[e][l][k];
                    gz[k] += mz * edge_i[e][l][k];
                }
            }
#endif
            for (int k = 0; k < NL && d0 + k < ndir; ++k) {
                const int at = (d0 + k) * SHL__ZH_STRIDE + l;
                zh[at] = norm[l] * surf[l][k]; /* Eq. 13 */
#if WITH_GRAD
                zh_grad[at] = norm[l] * gx[k];
                zh_grad[SHL__ZH_BLOCK + at] = norm[l] * gy[k];
                zh_grad[2 * SHL__ZH_BLOCK + at] = norm[l] * gz[k];
#endif
            }
        }
    }
#if WITH_GRAD
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* coefficients as the non-gradient instance */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) zh[dir * SHL__ZH_STRIDE + l] = (REAL)area[dir * SHL__ZH_STRIDE + l];
    }
#endif
}
