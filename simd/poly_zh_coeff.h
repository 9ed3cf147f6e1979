/* Coefficient-only ZH integrals (shl_polygon) for one block of CW lobes side by side,
 * CW doubles per vector; included by simd/poly_zh_batch.h once per width it uses
 * (its full width ZW, and 2 and 4 below that for a partial last block of lobes), with
 * CW defined.  Each lane does exactly the one-lobe arithmetic of poly_zh_batch.h's
 * zh_lanes (elementwise operations, no contraction), so the width changes no bit:
 * test_polygon's hard_extreme_scales compares shl_polygon with shl_polygon_grad.
 * The G edges of a group (3, or 2 where 2 or 4 are left) run side by side in each
 * band step: their recurrences are independent, so G dependency chains (the dP
 * chain, 4 operations per band) overlap instead of each edge waiting on the previous
 * edge's last band.  Every bsum[l] still adds the edges in order (Eq. 14). */
#define CW_CAT2(a, b) a##b
#define CW_CAT(a, b) CW_CAT2(a, b)
#define cv CW_CAT(dv, CW) /* simd/dvec.h */
#define cv_set1 CW_CAT(cv, _set1)
#define cv_dot CW_CAT(cv, _dot)
#define cv_edges CW_CAT(cv_edges_, CW)
#define cv_block CW_CAT(cv_block_, CW)

__attribute__((always_inline)) static inline void cv_edges(const shl__poly_geom *g, int e0, const int G, int lmax,
                                                           cv ux, cv uy, cv uz, const shl__zh_band_consts *bc,
                                                           cv *bsum)
{
    enum { GMAX = 3 };
    if (lmax <= 2) { /* B_0, B_1 only: a_e, b_e, c_e of Eq. 20, none of the recurrences' inputs */
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            const int e = e0 + k;
            const cv gamma = cv_set1(g->gamma[e]), c = cv_dot(ux, uy, uz, g->mu[e]);
            bsum[0] += c * gamma;
            if (lmax == 2)
                bsum[1] += c * (cv_dot(ux, uy, uz, g->w[e]) * cv_set1(g->sin_gamma[e]) +
                                cv_dot(ux, uy, uz, g->lam[e]) * cv_set1(g->omc_gamma[e])); /* B_1, Eq. 27 */
        }
        return;
    }
    cv a[GMAX], c[GMAX], af[GMAX], c2[GMAX], s[GMAX], b1[GMAX], da[GMAX];
    cv p_lm1[GMAX], p_lm2[GMAX], dp_lm1[GMAX], dp_lm2[GMAX], b_lm1[GMAX], b_lm2[GMAX], d_lm1[GMAX], d_lm2[GMAX];
#pragma GCC unroll 3
    for (int k = 0; k < G; ++k) {
        const int e = e0 + k, f = (e + 1 == g->n) ? 0 : e + 1;
        const cv gamma = cv_set1(g->gamma[e]);
        /* Eq. 20: coordinates of the lobe axes in the edge frame */
        a[k] = cv_dot(ux, uy, uz, g->w[e]);
        const cv b = cv_dot(ux, uy, uz, g->lam[e]);
        c[k] = cv_dot(ux, uy, uz, g->mu[e]), af[k] = cv_dot(ux, uy, uz, g->w[f]);
        c2[k] = c[k] * c[k]; /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
        s[k] = a[k] * cv_set1(g->sin_gamma[e]) - b * cv_set1(g->cos_gamma[e]);
        b1[k] = a[k] * cv_set1(g->sin_gamma[e]) + b * cv_set1(g->omc_gamma[e]); /* B_1, Eq. 27 */
        da[k] = cv_dot(ux, uy, uz, g->dw[e]);
        p_lm1[k] = a[k], p_lm2[k] = cv_set1(1.0);    /* P_{l-1}(a_e), P_{l-2}(a_e) */
        dp_lm1[k] = da[k], dp_lm2[k] = cv_set1(0.0); /* dP_{l-1}, dP_{l-2} */
        b_lm1[k] = b1[k], b_lm2[k] = gamma;          /* B_1, B_0 (Eq. 26-27) */
        d_lm1[k] = gamma, d_lm2[k] = cv_set1(0.0);   /* D_1, D_0 (Eq. 28) */
        bsum[0] += c[k] * gamma;
        if (lmax >= 2) bsum[1] += c[k] * b1[k];
    }
    /* B_l up to lmax-1 (Eq. 29); the last band's B_l needs no P_l, D_l, dP_l (they would feed
     * band l + 1 only): computed by the loop up to lmax - 2, then B_{lmax-1} alone */
    for (int l = 2; l + 1 < lmax; ++l) {
        const cv pa = cv_set1(bc->leg_a[l]), pb = cv_set1(bc->leg_b[l]), tlm1 = cv_set1(bc->twol_m1[l]);
        const cv alpha = cv_set1(bc->b_alpha[l]), beta = cv_set1(bc->b_beta[l]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            const cv pl = pa * a[k] * p_lm1[k] - pb * p_lm2[k]; /* Eq. 11 */
            const cv dl = tlm1 * b_lm1[k] + d_lm2[k];           /* Eq. 32 */
            /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
            const cv dpl = pa * (af[k] * dp_lm1[k] + da[k] * p_lm1[k]) - pb * dp_lm2[k];
            /* Eq. 30 with Eq. 31's C_{l-1} = (X + (l-1) B_{l-2}) / l: B_l = alpha X + beta B_{l-2} */
            const cv bl = alpha * (b1[k] * p_lm1[k] + s[k] * dp_lm1[k] - c2[k] * d_lm1[k]) + beta * b_lm2[k];
            b_lm2[k] = b_lm1[k], b_lm1[k] = bl;
            bsum[l] += c[k] * bl; /* Eq. 14, edges in order */
            p_lm2[k] = p_lm1[k], p_lm1[k] = pl;
            dp_lm2[k] = dp_lm1[k], dp_lm1[k] = dpl;
            d_lm2[k] = d_lm1[k], d_lm1[k] = dl;
        }
    }
    if (lmax >= 3) {
        const int l = lmax - 1;
        const cv alpha = cv_set1(bc->b_alpha[l]), beta = cv_set1(bc->b_beta[l]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k)
            bsum[l] += c[k] * (alpha * (b1[k] * p_lm1[k] + s[k] * dp_lm1[k] - c2[k] * d_lm1[k]) + beta * b_lm2[k]);
    }
}

/* Lobes d0 .. d0 + cnt - 1 (cnt <= CW; spare lanes repeat the last lobe) into zh. */
static void cv_block(const shl__poly_geom *g, int lmax, int d0, int cnt, const shl__zh_band_consts *bc, double *zh)
{
    cv ux = cv_set1(0.0), uy = ux, uz = ux, bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1];
    /* lanes set in registers (scalar stores reloaded as a vector stall store forwarding) */
#pragma GCC unroll 8
    for (int k = 0; k < CW; ++k) {
        const double *u = shl__zh_dir[d0 + (k < cnt ? k : cnt - 1)];
        ux[k] = u[0], uy[k] = u[1], uz[k] = u[2];
    }
    for (int l = 0; l <= lmax; ++l) bsum[l] = cv_set1(0.0);
    for (int e0 = 0; e0 < g->n;) { /* n >= 3: groups of 3, of 2 where 2 or 4 are left */
        const int rest = g->n - e0;
        if (rest == 2 || rest == 4) {
            cv_edges(g, e0, 2, lmax, ux, uy, uz, bc, bsum);
            e0 += 2;
        } else {
            cv_edges(g, e0, 3, lmax, ux, uy, uz, bc, bsum);
            e0 += 3;
        }
    }
    surf[0] = cv_set1(g->solid_angle); /* S_0 */
    if (lmax >= 1) surf[1] = bsum[0] * cv_set1(0.5); /* S_1, Eq. 25 */
    for (int l = 2; l <= lmax; ++l) surf[l] = cv_set1(bc->s_b[l]) * bsum[l - 1] + cv_set1(bc->s_s[l]) * surf[l - 2]; /* Eq. 29 */
    for (int l = 0; l <= lmax; ++l) { /* Eq. 13 */
        const cv z = cv_set1(bc->norm[l]) * surf[l];
        /* lane reads at constant indices where the block is full (through a stack copy, gcc
         * stored the vector and reloaded it in pieces: store-forwarding stalls, ~1/5 of the block) */
        if (cnt == CW)
#pragma GCC unroll 8
            for (int k = 0; k < CW; ++k) zh[(ptrdiff_t)(d0 + k) * SHL__ZH_STRIDE + l] = z[k];
        else
            for (int k = 0; k < cnt; ++k) zh[(ptrdiff_t)(d0 + k) * SHL__ZH_STRIDE + l] = z[k];
    }
}

#undef cv_block
#undef cv_edges
#undef cv_dot
#undef cv_set1
#undef cv
#undef CW_CAT
#undef CW_CAT2
