/* Spherical-light kernels, instantiated by sphere.c for REAL = double and float;
 * SUFFIX(name) names the instance.
 *
 * SH gradient.  With N_l^m(z) = K_lm P_l^m(z) / sin^m(theta) (a polynomial in z,
 * Condon-Shortley sign included) and C_m + i S_m = (x + i y)^m, the polynomial
 * extension g(x,y,z) = sqrt(2) N_l^m(z) C_m equals Y_lm on the unit sphere, with
 *   d C_m/dx = m C_{m-1},  d C_m/dy = -m S_{m-1},  d S_m/dx = m S_{m-1},
 *   d S_m/dy = m C_{m-1},  d N_l^m/dz = -sqrt((l-m)(l+m+1)) N_l^{m+1}
 * (N_l^m is proportional to the m-th derivative of P_l).  The gradient of
 * Y_lm(v/|v|) at |v| = 1 is the tangential part (I - u u^T) grad g. */

void SUFFIX(shl__sh_eval_grad)(int lmax, const REAL u[3], REAL *y, REAL *grad, int stride)
{
    const REAL x = u[0], yy = u[1], z = u[2], r2 = (REAL)M_SQRT2;
    REAL cm[SHL_LMAX_MAX + 1], sm[SHL_LMAX_MAX + 1], diag[SHL_LMAX_MAX + 1];
    REAL col[SHL_LMAX_MAX + 2], next[SHL_LMAX_MAX + 2]; /* N_l^m and N_l^{m+1} over l */
    cm[0] = 1;
    sm[0] = 0;
    diag[0] = (REAL)sqrt(0.25 / M_PI);
    for (int m = 1; m <= lmax; ++m) {
        cm[m] = cm[m - 1] * x - sm[m - 1] * yy;
        sm[m] = cm[m - 1] * yy + sm[m - 1] * x;
        diag[m] = diag[m - 1] * (REAL)-sqrt((2.0 * m + 1.0) / (2.0 * m)); /* N_m^m */
    }
    for (int l = 0; l <= lmax + 1; ++l) next[l] = 0;
    for (int m = lmax; m >= 0; --m) {
        col[m] = diag[m];
        if (m < lmax) col[m + 1] = (REAL)sqrt(2.0 * m + 3.0) * z * diag[m];
        for (int l = m + 2; l <= lmax; ++l) {
            const double l2 = (double)l * l, m2 = (double)m * m;
            const REAL a = (REAL)sqrt((4.0 * l2 - 1.0) / (l2 - m2));
            const REAL b = (REAL)sqrt(((l - 1.0) * (l - 1.0) - m2) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
            col[l] = a * (z * col[l - 1] - b * col[l - 2]);
        }
        for (int l = m; l <= lmax; ++l) {
            const int base = l * (l + 1);
            const REAL n = col[l];
            if (m == 0) {
                y[base] = n;
            } else {
                y[base + m] = r2 * n * cm[m];
                y[base - m] = r2 * n * sm[m];
            }
            if (!grad) continue;
            const REAL dn = (REAL)-sqrt((double)(l - m) * (l + m + 1.0)) * next[l];
            REAL g[2][3];
            int kk[2] = {base + m, base - m}, count = 1;
            if (m == 0) {
                g[0][0] = 0;
                g[0][1] = 0;
                g[0][2] = dn;
            } else {
                const REAL nm = r2 * n * (REAL)m;
                g[0][0] = nm * cm[m - 1];
                g[0][1] = -nm * sm[m - 1];
                g[0][2] = r2 * dn * cm[m];
                g[1][0] = nm * sm[m - 1];
                g[1][1] = nm * cm[m - 1];
                g[1][2] = r2 * dn * sm[m];
                count = 2;
            }
            for (int i = 0; i < count; ++i) {
                const REAL radial = g[i][0] * x + g[i][1] * yy + g[i][2] * z;
                for (int a = 0; a < 3; ++a) grad[a * stride + kk[i]] = g[i][a] - radial * u[a];
            }
        }
        for (int l = m; l <= lmax; ++l) next[l] = col[l];
        if (m > 0) next[m - 1] = 0; /* N_{m-1}^m = 0 */
    }
}

void SUFFIX(shl__cap_weights)(int lmax, REAL t, REAL s2, REAL c, REAL *w, REAL *dw)
{
    const REAL two_pi = (REAL)(2.0 * M_PI);
    w[0] = two_pi * t; /* HVL Eq. (14), l = 0: sqrt(4 pi) zh_0 = 2 pi (1 - cos a) */
    if (dw) dw[0] = -two_pi;
    REAL p_prev = 1, p = c, dp_prev = 0, dp = 1; /* P_{l-1}, P_l, P'_{l-1}, P'_l at l = 1 */
    for (int l = 1; l <= lmax; ++l) {
        /* HVL Eq. (13)-(14): 2 pi int_c^1 P_l = 2 pi (P_{l-1}(c) - P_{l+1}(c)) / (2l+1)
         * = 2 pi (1 - c^2) P_l'(c) / (l(l+1)): no cancellation as a -> 0 */
        w[l] = two_pi * s2 * dp / (REAL)(l * (l + 1.0));
        if (dw) dw[l] = -two_pi * p; /* d/dc of 2 pi int_c^1 P_l */
        const REAL p_next = ((REAL)(2 * l + 1) * c * p - (REAL)l * p_prev) / (REAL)(l + 1);
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
    SUFFIX(shl__sh_eval_grad)(lmax, u, coeffs, grad, nc); /* Y_lm(axis) and its gradient */
    for (int l = 0; l <= lmax; ++l)
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            if (grad) {
                /* d/dx [w_l(cos a) Y(u)] = w_l' (d cos a/dx) Y - (w_l / d) (I - u u^T) grad Y */
                const REAL radial = (REAL)g->k_alpha_s * dw[l] * coeffs[k], tang = w[l] * (REAL)g->inv_d_s;
                for (int a = 0; a < 3; ++a) /* back from scaled units in double (sh_ops.h) */
                    grad[a * nc + k] = (REAL)((-radial * u[a] - tang * grad[a * nc + k]) * g->grad_scale[0] * g->grad_scale[1]);
            }
            coeffs[k] *= w[l]; /* HVL Eq. (15): sqrt(4 pi/(2l+1)) zh_l Y_lm(axis) = w_l Y_lm(axis) */
        }
}
