/* ZH recurrence of Wang & Ramamoorthi 2018 (Sec. 4.1, Alg. 1), optionally with
 * the spatial gradient of every ZH integral (Wu et al. 2020, Sec. 5), in one
 * pass that shares the B/D edge recurrences and the Legendre values at the
 * vertices.  Instantiated by polygon.c with REAL = double/float and
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
 * B_1 = a sin(gamma) + b (1 - cos(gamma)) formed in double. */

void SUFFIX(shl__poly_zh)(const shl__poly_geom *g, int lmax, REAL *zh
#if WITH_GRAD
                          , REAL *zh_grad /* 3 blocks of the zh layout, one per axis */
#endif
)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    if (n == 0) {
        for (int d = 0; d < ndir; ++d)
            for (int l = 0; l <= lmax; ++l) {
                zh[d * SHL__ZH_STRIDE + l] = 0;
#if WITH_GRAD
                for (int a = 0; a < 3; ++a) zh_grad[a * SHL__ZH_BLOCK + d * SHL__ZH_STRIDE + l] = 0;
#endif
            }
        return;
    }
    REAL a[SHL_MAX_VERTS], p_lm1[SHL_MAX_VERTS], p_lm2[SHL_MAX_VERTS], p_l[SHL_MAX_VERTS];
    REAL b1[SHL_MAX_VERTS], c[SHL_MAX_VERTS], c2[SHL_MAX_VERTS], s[SHL_MAX_VERTS];
    REAL da[SHL_MAX_VERTS], dp_lm1[SHL_MAX_VERTS], dp_lm2[SHL_MAX_VERTS];
    REAL b_lm1[SHL_MAX_VERTS], b_lm2[SHL_MAX_VERTS], d_lm1[SHL_MAX_VERTS], d_lm2[SHL_MAX_VERTS];
    REAL surf[SHL_LMAX_MAX + 1], norm[SHL_LMAX_MAX + 1];
#if WITH_GRAD
    REAL v[SHL_MAX_VERTS], i_lm1[SHL_MAX_VERTS], j_lm1[SHL_MAX_VERTS], j_lm2[SHL_MAX_VERTS];
    REAL i0[SHL_MAX_VERTS], fp1[SHL_MAX_VERTS], mu[SHL_MAX_VERTS][3];
    REAL gsum[SHL_LMAX_MAX + 1][3];
    for (int e = 0; e < n; ++e) {
        i0[e] = (REAL)g->f_integral[e];
        fp1[e] = (REAL)g->fprime1[e];
        for (int k = 0; k < 3; ++k) mu[e][k] = (REAL)g->mu[e][k];
    }
#endif
    /* per-band constants, hoisted out of the lobe loop */
    REAL inv_l[SHL_LMAX_MAX + 2], s_b[SHL_LMAX_MAX + 1], s_s[SHL_LMAX_MAX + 1];
    inv_l[lmax + 1] = (REAL)(1.0 / (lmax + 1));
    for (int l = 0; l <= lmax; ++l) {
        norm[l] = (REAL)sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); /* K_l */
        inv_l[l] = (REAL)(1.0 / (l + (l == 0)));
        s_b[l] = (REAL)((2.0 * l - 1.0) / (l * (l + 1.0) + (l == 0)));   /* Eq. 29 weights */
        s_s[l] = (REAL)((l - 2.0) * (l - 1.0) / (l * (l + 1.0) + (l == 0)));
    }

    for (int dir = 0; dir < ndir; ++dir) {
        const double *lobe = shl__zh_dir[dir];
        REAL bsum = 0, bsum0 = 0;
#if WITH_GRAD
        for (int l = 0; l <= lmax; ++l) gsum[l][0] = gsum[l][1] = gsum[l][2] = 0;
#endif
        for (int e = 0; e < n; ++e) {
            /* Eq. 20: coordinates of the lobe axis in the edge frame */
            const double ae = lobe[0] * g->w[e][0] + lobe[1] * g->w[e][1] + lobe[2] * g->w[e][2];
            const double be = lobe[0] * g->lam[e][0] + lobe[1] * g->lam[e][1] + lobe[2] * g->lam[e][2];
            const double ce = lobe[0] * g->mu[e][0] + lobe[1] * g->mu[e][1] + lobe[2] * g->mu[e][2];
            a[e] = (REAL)ae;
            c[e] = (REAL)ce;
            c2[e] = (REAL)(ce * ce); /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
            s[e] = (REAL)(ae * g->sin_gamma[e] - be * g->cos_gamma[e]);
            b1[e] = (REAL)(ae * g->sin_gamma[e] + be * g->omc_gamma[e]);
            da[e] = (REAL)(lobe[0] * g->dw[e][0] + lobe[1] * g->dw[e][1] + lobe[2] * g->dw[e][2]);
            p_lm2[e] = 1;
            p_lm1[e] = a[e];
            dp_lm2[e] = 0;                                   /* dP_0 */
            dp_lm1[e] = da[e];                               /* dP_1 */
            b_lm2[e] = (REAL)g->gamma[e];                    /* B_0, Eq. 26 */
            b_lm1[e] = b1[e];                                /* B_1, Eq. 27 */
            d_lm2[e] = 0;                                    /* D_0, Eq. 28 */
            d_lm1[e] = (REAL)g->gamma[e];                    /* D_1 */
            bsum0 += c[e] * b_lm2[e];
            bsum += c[e] * b_lm1[e];
        }
#if WITH_GRAD
        for (int e = 0; e < n; ++e) {
            /* [f' P_l]_0^T = f'(T) dP_l - I_0 P_l(a_e), since f'(T) - f'(0) = -I_0 */
            v[e] = (REAL)(lobe[0] * g->gvec[e][0] + lobe[1] * g->gvec[e][1] + lobe[2] * g->gvec[e][2]);
            const REAL i1 = (v[e] * d_lm1[e] - (fp1[e] * da[e] - i0[e] * a[e])) / 2; /* I_1 */
            j_lm2[e] = 0;                                                     /* J_0 */
            j_lm1[e] = i0[e];                                                 /* J_1 */
            i_lm1[e] = i1;
            for (int k = 0; k < 3; ++k) {
                gsum[0][k] += mu[e][k] * i0[e];
                if (lmax >= 1) gsum[1][k] += mu[e][k] * i1;
            }
        }
#endif
        surf[0] = (REAL)g->solid_angle;                      /* S_0 */
        if (lmax >= 1) surf[1] = bsum0 / 2;                  /* S_1, Eq. 25 */
        for (int l = 2; l <= lmax; ++l) {
            /* Eq. 29, with bsum = B_{l-1} */
            surf[l] = s_b[l] * bsum + s_s[l] * surf[l - 2];
#if !WITH_GRAD
            if (l == lmax) break;
#endif
            const REAL rl = inv_l[l], lm1 = (REAL)(l - 1), twol_m1 = (REAL)(2 * l - 1);
            for (int vtx = 0; vtx < n; ++vtx) /* Legendre recurrence: P_l(a_v) (Wang Eq. 11) */
                p_l[vtx] = (twol_m1 * a[vtx] * p_lm1[vtx] - lm1 * p_lm2[vtx]) * rl;
            bsum = 0;
            for (int e = 0; e < n; ++e) {
                const int f = (e + 1 == n) ? 0 : e + 1;
                /* Eq. 31: C_{l-1}, with P_{l-1} at both arc ends */
                const REAL cl = (b1[e] * p_lm1[e] + s[e] * dp_lm1[e] - c2[e] * d_lm1[e] + lm1 * b_lm2[e]) * rl;
                const REAL bl = (twol_m1 * cl - lm1 * b_lm2[e]) * rl;   /* Eq. 30 */
                const REAL dl = twol_m1 * b_lm1[e] + d_lm2[e];             /* Eq. 32 */
                /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
                const REAL dpl = (twol_m1 * (a[f] * dp_lm1[e] + da[e] * p_lm1[e]) - lm1 * dp_lm2[e]) * rl;
                dp_lm2[e] = dp_lm1[e];
                dp_lm1[e] = dpl;
#if WITH_GRAD
                const REAL il = (v[e] * dl - j_lm1[e] - (fp1[e] * dpl - i0[e] * p_l[e])) * inv_l[l + 1];
                const REAL jl = twol_m1 * i_lm1[e] + j_lm2[e];
                j_lm2[e] = j_lm1[e];
                j_lm1[e] = jl;
                i_lm1[e] = il;
                for (int k = 0; k < 3; ++k) gsum[l][k] += mu[e][k] * il; /* Wu Eq. 11, 29 */
#endif
                b_lm2[e] = b_lm1[e];
                b_lm1[e] = bl;
                d_lm2[e] = d_lm1[e];
                d_lm1[e] = dl;
                bsum += c[e] * bl;                                          /* Eq. 14 */
            }
            for (int vtx = 0; vtx < n; ++vtx) {
                p_lm2[vtx] = p_lm1[vtx];
                p_lm1[vtx] = p_l[vtx];
            }
        }
        for (int l = 0; l <= lmax; ++l) { /* Eq. 13 */
            zh[dir * SHL__ZH_STRIDE + l] = norm[l] * surf[l];
#if WITH_GRAD
            for (int k = 0; k < 3; ++k) zh_grad[k * SHL__ZH_BLOCK + dir * SHL__ZH_STRIDE + l] = norm[l] * gsum[l][k];
#endif
        }
    }
}
