/* ZH integrals and their gradients (shl_polygon_grad, and the scalar ISA's
 * shl__poly_zh_grad) for one block of GW lobes side by side, GW doubles per vector;
 * included by simd/poly_zh_batch.h once per width it uses (its full width ZW, and 2 and 4
 * below that for a partial last block of lobes, as poly_zh_coeff.h), with GW defined.
 * Each lane does exactly the one-lobe arithmetic of src/polygon_zh.h (elementwise
 * operations, no contraction), so the width changes no bit. */
#define GV_CAT2(a, b) a##b
#define GV_CAT(a, b) GV_CAT2(a, b)
#define gv GV_CAT(dv, GW) /* simd/dvec.h */
#define gv_set1 GV_CAT(gv, _set1)
#define gv_dot GV_CAT(gv, _dot)
#define gv_scatter GV_CAT(gv, _scatter)
#define gv_edges GV_CAT(gv_edges_, GW)
#define gv_accumulate GV_CAT(gv_accumulate_, GW)
#define gv_block GV_CAT(gv_block_, GW)

/* *sum += x; fresh: *sum = 0 + x (the sum's first term: no zeroing pass, and 0 + x keeps the
 * bits of adding x to a zeroed sum, -0 included) */
__attribute__((always_inline)) static inline void gv_accumulate(gv *sum, gv x, const int fresh)
{
    *sum = fresh ? gv_set1(0.0) + x : *sum + x;
}

/* The edges e0 .. e0 + G - 1 (G <= 3) of one block of lobes, in two sweeps over the bands.
 * The first is the coefficient recurrence (as simd/poly_zh_coeff.h: the G edges side by
 * side in each band step, so their chains overlap), which also keeps P_l(a_e), dP_l and
 * D_l of every band; the second runs Wu's I_l, J_l recurrence from them and adds mu_e I_l
 * into the gradient sums.  One sweep carrying both recurrences held ~20 vectors per edge
 * live and spilled them every band.  Every bsum[l] and gsum[ax][l] still adds the edges in
 * order (Eq. 14; Wu Eq. 11, 29) and every value is the same expression, so the bits equal
 * one edge and one sweep at a time.  first: edge e0 starts the sums (they are not zeroed
 * before; gcc zeroed them with a memset call, ~4% of shl_polygon_grad). */
__attribute__((always_inline)) static inline void gv_edges(const shl__poly_geom *g, int e0, const int G, int lmax,
                                                           gv ux, gv uy, gv uz, const shl__zh_band_consts *bc,
                                                           gv *bsum, gv (*gsum)[SHL_LMAX_MAX + 1], const int first)
{
    enum { GMAX = 3 };
    gv a[GMAX], c[GMAX], af[GMAX], c2[GMAX], s[GMAX], b1[GMAX], da[GMAX];
    gv p_lm1[GMAX], p_lm2[GMAX], dp_lm1[GMAX], dp_lm2[GMAX], b_lm1[GMAX], b_lm2[GMAX], d_lm1[GMAX], d_lm2[GMAX];
    gv pl[GMAX][SHL_LMAX_MAX + 1], dpl[GMAX][SHL_LMAX_MAX + 1], dl[GMAX][SHL_LMAX_MAX + 1]; /* bands 2..lmax */
#pragma GCC unroll 3
    for (int k = 0; k < G; ++k) {
        const int e = e0 + k, f = (e + 1 == g->n) ? 0 : e + 1;
        const gv gamma = gv_set1(g->gamma[e]);
        /* Eq. 20: coordinates of the lobe axes in the edge frame */
        a[k] = gv_dot(ux, uy, uz, g->w[e]);
        const gv b = gv_dot(ux, uy, uz, g->lam[e]);
        c[k] = gv_dot(ux, uy, uz, g->mu[e]), af[k] = gv_dot(ux, uy, uz, g->w[f]);
        c2[k] = c[k] * c[k]; /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
        s[k] = a[k] * gv_set1(g->sin_gamma[e]) - b * gv_set1(g->cos_gamma[e]);
        b1[k] = a[k] * gv_set1(g->sin_gamma[e]) + b * gv_set1(g->omc_gamma[e]); /* B_1, Eq. 27 */
        da[k] = gv_dot(ux, uy, uz, g->dw[e]);
        p_lm1[k] = a[k], p_lm2[k] = gv_set1(1.0);    /* P_{l-1}(a_e), P_{l-2}(a_e) */
        dp_lm1[k] = da[k], dp_lm2[k] = gv_set1(0.0); /* dP_{l-1}, dP_{l-2} */
        b_lm1[k] = b1[k], b_lm2[k] = gamma;          /* B_1, B_0 (Eq. 26-27) */
        d_lm1[k] = gamma, d_lm2[k] = gv_set1(0.0);   /* D_1, D_0 (Eq. 28) */
        const int fresh = first && k == 0; /* the first edge starts the sums */
        gv_accumulate(&bsum[0], c[k] * gamma, fresh);
        if (lmax >= 2) gv_accumulate(&bsum[1], c[k] * b1[k], fresh);
    }
    for (int l = 2; l <= lmax; ++l) {
        const gv pa = gv_set1(bc->leg_a[l]), pb = gv_set1(bc->leg_b[l]), tlm1 = gv_set1(bc->twol_m1[l]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            pl[k][l] = pa * a[k] * p_lm1[k] - pb * p_lm2[k]; /* Eq. 11 */
            dl[k][l] = tlm1 * b_lm1[k] + d_lm2[k];           /* Eq. 32 */
            /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
            dpl[k][l] = pa * (af[k] * dp_lm1[k] + da[k] * p_lm1[k]) - pb * dp_lm2[k];
        }
        if (l == lmax) break; /* B_lmax is not needed (Eq. 29 reads B_l, l < lmax) */
        const gv alpha = gv_set1(bc->b_alpha[l]), beta = gv_set1(bc->b_beta[l]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            /* Eq. 30 with Eq. 31's C_{l-1} = (X + (l-1) B_{l-2}) / l: B_l = alpha X + beta B_{l-2} */
            const gv bl = alpha * (b1[k] * p_lm1[k] + s[k] * dp_lm1[k] - c2[k] * d_lm1[k]) + beta * b_lm2[k];
            b_lm2[k] = b_lm1[k], b_lm1[k] = bl;
            gv_accumulate(&bsum[l], c[k] * bl, first && k == 0); /* Eq. 14, edges in order */
            p_lm2[k] = p_lm1[k], p_lm1[k] = pl[k][l];
            dp_lm2[k] = dp_lm1[k], dp_lm1[k] = dpl[k][l];
            d_lm2[k] = d_lm1[k], d_lm1[k] = dl[k][l];
        }
    }
    /* Wu's recurrence (polygon_zh.h), the G edges side by side in each band step (their chains,
     * I_l -> J_l+1 -> I_l+2, overlap), then Wu Eq. 11, 29: sum over edges of mu_e I_l, edges in order */
    gv i0[GMAX], fp1[GMAX], v[GMAX], mx[GMAX], my[GMAX], mz[GMAX], i_lm1[GMAX], j_lm1[GMAX], j_lm2[GMAX];
#pragma GCC unroll 3
    for (int k = 0; k < G; ++k) {
        const int e = e0 + k;
        i0[k] = gv_set1(g->f_integral[e]), fp1[k] = gv_set1(g->fprime1[e]), v[k] = gv_dot(ux, uy, uz, g->gvec[e]);
        mx[k] = gv_set1(g->mu[e][0]), my[k] = gv_set1(g->mu[e][1]), mz[k] = gv_set1(g->mu[e][2]);
        /* [f' P_l]_0^T = f'(T) dP_l - I_0 P_l(a_e), since f'(T) - f'(0) = -I_0 */
        i_lm1[k] = (v[k] * gv_set1(g->gamma[e]) - (fp1[k] * da[k] - i0[k] * a[k])) * gv_set1(0.5); /* I_1 */
        j_lm1[k] = i0[k], j_lm2[k] = gv_set1(0.0);                                                  /* J_1, J_0 = 0 */
        const int fresh = first && k == 0;
        gv_accumulate(&gsum[0][0], mx[k] * i0[k], fresh), gv_accumulate(&gsum[1][0], my[k] * i0[k], fresh);
        gv_accumulate(&gsum[2][0], mz[k] * i0[k], fresh);
        if (lmax >= 1) {
            gv_accumulate(&gsum[0][1], mx[k] * i_lm1[k], fresh), gv_accumulate(&gsum[1][1], my[k] * i_lm1[k], fresh);
            gv_accumulate(&gsum[2][1], mz[k] * i_lm1[k], fresh);
        }
    }
    for (int l = 2; l <= lmax; ++l) {
        const gv inv = gv_set1(bc->inv_l[l + 1]), tlm1 = gv_set1(bc->twol_m1[l]);
#pragma GCC unroll 3
        for (int k = 0; k < G; ++k) {
            const gv il = (v[k] * dl[k][l] - j_lm1[k] - (fp1[k] * dpl[k][l] - i0[k] * pl[k][l])) * inv;
            const gv jl = tlm1 * i_lm1[k] + j_lm2[k];
            j_lm2[k] = j_lm1[k], j_lm1[k] = jl, i_lm1[k] = il;
            const int fresh = first && k == 0;
            gv_accumulate(&gsum[0][l], mx[k] * il, fresh), gv_accumulate(&gsum[1][l], my[k] * il, fresh);
            gv_accumulate(&gsum[2][l], mz[k] * il, fresh);
        }
    }
}

/* Lobes d0 .. d0 + cnt - 1 (cnt <= GW; spare lanes repeat the last lobe).  zh4 != NULL:
 * instead of the blocks zh, zh_grad, the value and the 3 gradient components of lobe d,
 * band l side by side at zh4[4 (l (2 lmax + 1) + d) + 0..3] (grad_sh), the gradient's band
 * weights K_l times gscale (a power of two, 1 for scaled units).  area: zh is left to
 * the caller (the planar rule). */
static void gv_block(const shl__poly_geom *g, int lmax, int d0, int cnt, const shl__zh_band_consts *bc, double *zh,
                     double *zh_grad, double *zh4, double gscale, int area)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    gv ux = gv_set1(0.0), uy = ux, uz = ux;
    /* lanes set in registers (scalar stores reloaded as a vector stall store forwarding) */
#pragma GCC unroll 8
    for (int k = 0; k < GW; ++k) {
        const double *u = shl__zh_dir[d0 + (k < cnt ? k : cnt - 1)];
        ux[k] = u[0], uy[k] = u[1], uz[k] = u[2];
    }
    gv bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1], gsum[3][SHL_LMAX_MAX + 1];
    /* n = 0 (no polygon left, polygon.c: all sums 0) or n >= 3: groups of 3, of 2 where 2 or 4
     * are left; the first group starts the sums */
    int e0 = 0;
    if (n == 0) {
        for (int l = 0; l <= lmax; ++l) bsum[l] = gsum[0][l] = gsum[1][l] = gsum[2][l] = gv_set1(0.0);
    } else if (n == 4) {
        gv_edges(g, 0, 2, lmax, ux, uy, uz, bc, bsum, gsum, 1);
        e0 = 2;
    } else {
        gv_edges(g, 0, 3, lmax, ux, uy, uz, bc, bsum, gsum, 1);
        e0 = 3;
    }
    while (e0 < n) {
        const int rest = n - e0;
        if (rest == 2 || rest == 4) {
            gv_edges(g, e0, 2, lmax, ux, uy, uz, bc, bsum, gsum, 0);
            e0 += 2;
        } else {
            gv_edges(g, e0, 3, lmax, ux, uy, uz, bc, bsum, gsum, 0);
            e0 += 3;
        }
    }
    surf[0] = gv_set1(g->solid_angle); /* S_0 */
    if (lmax >= 1) surf[1] = bsum[0] * gv_set1(0.5); /* S_1, Eq. 25 */
    for (int l = 2; l <= lmax; ++l) surf[l] = gv_set1(bc->s_b[l]) * bsum[l - 1] + gv_set1(bc->s_s[l]) * surf[l - 2]; /* Eq. 29 */
    if (zh4) {
        for (int l = 0; l <= lmax; ++l) {
            const gv kl = gv_set1(bc->norm[l]), kg = gv_set1(bc->norm[l] * gscale);
            const gv z = kl * surf[l], zx = kg * gsum[0][l], zy = kg * gsum[1][l], zz = kg * gsum[2][l]; /* Eq. 13 */
            double *o = zh4 + 4 * ((ptrdiff_t)l * ndir + d0);
#if GW == 4
            if (cnt == 4) { /* a 4 x 4 transpose in two steps of two-vector shuffles (8 in all) */
                const gv t0 = dv4_shuffle(z, zx, 0, 4, 2, 6), t1 = dv4_shuffle(z, zx, 1, 5, 3, 7);
                const gv t2 = dv4_shuffle(zy, zz, 0, 4, 2, 6), t3 = dv4_shuffle(zy, zz, 1, 5, 3, 7);
                const gv q0 = dv4_shuffle(t0, t2, 0, 1, 4, 5), q1 = dv4_shuffle(t1, t3, 0, 1, 4, 5);
                const gv q2 = dv4_shuffle(t0, t2, 2, 3, 6, 7), q3 = dv4_shuffle(t1, t3, 2, 3, 6, 7);
                memcpy(o, &q0, sizeof q0), memcpy(o + 4, &q1, sizeof q1);
                memcpy(o + 8, &q2, sizeof q2), memcpy(o + 12, &q3, sizeof q3);
                continue;
            }
#endif
            /* lane k of the 4 vectors side by side, k a constant after unrolling: a shuffle
             * in the registers (with k a variable, or through a stack array, gcc stored the
             * vectors and loaded them back in pieces, a fifth of this kernel's time) */
#pragma GCC unroll 8
            for (int k = 0; k < GW; ++k)
                if (k < cnt) {
                    const double q[4] = {z[k], zx[k], zy[k], zz[k]};
                    memcpy(o + 4 * k, q, sizeof q);
                }
        }
        return;
    }
    for (int l = 0; l <= lmax; ++l) {
        const gv kl = gv_set1(bc->norm[l]);
        const ptrdiff_t at = (ptrdiff_t)d0 * SHL__ZH_STRIDE + l;
        if (!area) gv_scatter(kl * surf[l], zh + at, SHL__ZH_STRIDE, cnt); /* Eq. 13 */
        for (int ax = 0; ax < 3; ++ax) gv_scatter(kl * gsum[ax][l], zh_grad + ax * SHL__ZH_BLOCK + at, SHL__ZH_STRIDE, cnt);
    }
}

#undef gv_block
#undef gv_edges
#undef gv_accumulate
#undef gv_scatter
#undef gv_dot
#undef gv_set1
#undef gv
#undef GV_CAT
#undef GV_CAT2
