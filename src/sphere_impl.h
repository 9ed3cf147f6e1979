/* Spherical-light kernels, instantiated by sphere.c for REAL = double and float;
 * SUFFIX(name) names the instance, TAB(name) its factor table (sh_tables.c); the
 * SH basis kernels are in sh_basis_impl.h. */

void SUFFIX(shl__cap_weights)(int lmax, REAL t, REAL s2, REAL c, REAL *w, REAL *dw)
{
    const REAL two_pi = (REAL)(2.0 * M_PI);
    w[0] = two_pi * t; /* HVL Eq. (14), l = 0: sqrt(4 pi) zh_0 = 2 pi (1 - cos a) */
    if (dw) dw[0] = -two_pi;
    REAL p_prev = 1, p = c, dp_prev = 0, dp = 1; /* P_{l-1}, P_l, P'_{l-1}, P'_l at l = 1 */
    for (int l = 1; l <= lmax; ++l) {
        /* HVL Eq. (13)-(14): 2 pi int_c^1 P_l = 2 pi (P_{l-1}(c) - P_{l+1}(c)) / (2l+1)
         * = 2 pi (1 - c^2) P_l'(c) / (l(l+1)): no cancellation as a -> 0; factors
         * tabulated (sh_tables.c), so no division waits in the P_l chain */
        w[l] = TAB(capk)[l] * s2 * dp;
        if (dw) dw[l] = -two_pi * p; /* d/dc of 2 pi int_c^1 P_l */
        const REAL p_next = TAB(lega)[l] * c * p - TAB(legb)[l] * p_prev;
        const REAL dp_next = dp_prev + (REAL)(2 * l + 1) * p; /* P'_{l+1} = P'_{l-1} + (2l+1) P_l */
        p_prev = p;
        p = p_next;
        dp_prev = dp;
        dp = dp_next;
    }
}

void SUFFIX(shl__sphere_sh)(int lmax, const shl__sphere_geom *g, REAL *coeffs, REAL *grad)
{
    const int nc = SHL_NCOEFFS(lmax);
    if (g->inside) {
        for (int k = 0; k < nc; ++k) coeffs[k] = 0;
        coeffs[0] = (REAL)sqrt(4.0 * M_PI);
        if (grad)
            for (int k = 0; k < 3 * nc; ++k) grad[k] = 0;
        return;
    }
    REAL w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1];
    const REAL u[3] = {(REAL)g->u[0], (REAL)g->u[1], (REAL)g->u[2]};
    SUFFIX(shl__cap_weights)(lmax, (REAL)g->t, (REAL)g->s2, (REAL)g->c, w, grad ? dw : NULL);
    if (!grad) {
        SUFFIX(shl__sh_eval_w)(lmax, u, w, coeffs); /* HVL Eq. (15): w_l Y_lm(axis) */
        return;
    }
    /* d/dx [w_l(cos a) Y(u)] = w_l' (d cos a/dx) Y - (w_l / d) (I - u u^T) grad Y with
     * d cos a/dx = -k_alpha u (HVL Eq. (15) differentiated): al = -w_l / d, be = -k_alpha w_l'
     * in shl__sh_eval_wgrad, which forms coefficients and gradient in one pass */
    REAL al[SHL_LMAX_MAX + 1], be[SHL_LMAX_MAX + 1];
    const REAL inv_d = (REAL)g->inv_d_s, ka = (REAL)g->k_alpha_s;
    for (int l = 0; l <= lmax; ++l) al[l] = -w[l] * inv_d, be[l] = -ka * dw[l];
    SUFFIX(shl__sh_eval_wgrad)(lmax, u, w, al, be, coeffs, grad, nc);
    if (g->grad_scale[0] != 1.0 || g->grad_scale[1] != 1.0)
        for (int k = 0; k < 3 * nc; ++k) /* back from scaled units in double (internal.h) */
            grad[k] = (REAL)(grad[k] * g->grad_scale[0] * g->grad_scale[1]);
}
