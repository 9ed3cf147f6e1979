/* Spherical-light kernels and the entry points' bodies (sphere_d, sphere_f; they
 * use entry_geom, geom_init and check_radius of sphere.c), instantiated by sphere.c
 * for REAL = double and float, with the public entry points shl_sphere[_grad][_f];
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

/* lmax <= SHL__SPHERE_SMALL without gradient: shl__cap_weights and shl__sh_eval_w
 * with lmax a compile-time constant L (one instance per L, chosen in sphere_value_regs)
 * and every loop unrolled, so that each value lives in a register: no calls, loop
 * control or stores but the outputs (at low lmax these, not the arithmetic, were
 * most of the time).  Each value is formed by the same operations in the same order
 * as there (HVL Eq. (13)-(15); recurrences of sh_basis_impl.h), so the coefficients
 * equal the general path's bit for bit. */
static SHL__ALWAYS_INLINE void SUFFIX(sphere_small)(const int L, const REAL u[3], REAL t, REAL s2, REAL c,
                                                    REAL *restrict y)
{
    enum { S = SHL__SPHERE_SMALL };
    const REAL x = u[0], yy = u[1], z = u[2], r2 = (REAL)M_SQRT2;
    REAL w[S + 1], sc[S + 1], ss[S + 1], q[S + 1][S + 1];
    w[0] = (REAL)(2.0 * M_PI) * t;
    REAL p_prev = 1, p = c, dp_prev = 0, dp = 1;
#pragma GCC unroll 16
    for (int l = 1; l <= L; ++l) {
        w[l] = TAB(capk)[l] * s2 * dp;
        const REAL p_next = TAB(lega)[l] * c * p - TAB(legb)[l] * p_prev;
        const REAL dp_next = dp_prev + (REAL)(2 * l + 1) * p;
        p_prev = p, p = p_next, dp_prev = dp, dp = dp_next;
    }
    REAL cm = 1, sm = 0;
#pragma GCC unroll 16
    for (int m = 1; m <= L; ++m) {
        const REAL cn = cm * x - sm * yy;
        sm = cm * yy + sm * x, cm = cn, sc[m] = r2 * cm, ss[m] = r2 * sm;
    }
    q[0][0] = TAB(diag)[0];
    y[0] = w[0] * q[0][0];
#pragma GCC unroll 16
    for (int l = 1; l <= L; ++l) {
        const REAL *a = TAB(a) + l * (l + 1) / 2, *b = TAB(b) + l * (l + 1) / 2;
        REAL *restrict yc = y + l * (l + 1);
#pragma GCC unroll 16
        for (int m = 0; m <= l; ++m)
            q[l][m] = m == l ? TAB(diag)[l] : m == l - 1 ? a[m] * z * q[l - 1][m]
                                                          : a[m] * (z * q[l - 1][m] - b[m] * q[l - 2][m]);
        yc[0] = w[l] * q[l][0];
#pragma GCC unroll 16
        for (int m = 1; m <= l; ++m) {
            const REAL v = w[l] * q[l][m];
            yc[m] = v * sc[m], yc[-m] = v * ss[m];
        }
    }
}

/* lmax <= SHL__SPHERE_SMALL with the gradient, unscaled geometry: shl__cap_weights,
 * the factors al, be of shl__sphere_sh and shl__sh_eval_wgrad (see there for the
 * formulas) with lmax a compile-time constant and every loop unrolled, as
 * sphere_small: the same operations in the same order, so the same values bit for
 * bit.  inv_d = 1 / |center - x|, ka = k_alpha (shl__sphere_geom). */
static SHL__ALWAYS_INLINE void SUFFIX(sphere_small_grad)(const int L, const REAL u[3], REAL t, REAL s2, REAL c,
                                                         REAL inv_d, REAL ka, REAL *restrict y, REAL *restrict grad)
{
    enum { S = SHL__SPHERE_SMALL };
    const int nc = (L + 1) * (L + 1);
    const REAL x = u[0], yy = u[1], z = u[2], r2 = (REAL)M_SQRT2, two_pi = (REAL)(2.0 * M_PI);
    REAL w[S + 1], dw[S + 1], al[S + 1], be[S + 1], sc[S + 1], ss[S + 1], q[S + 1][S + 2];
    REAL *restrict gx = grad, *restrict gy = grad + nc, *restrict gz = grad + 2 * nc;
    w[0] = two_pi * t;
    dw[0] = -two_pi;
    REAL p_prev = 1, p = c, dp_prev = 0, dp = 1;
#pragma GCC unroll 16
    for (int l = 1; l <= L; ++l) {
        w[l] = TAB(capk)[l] * s2 * dp;
        dw[l] = -two_pi * p;
        const REAL p_next = TAB(lega)[l] * c * p - TAB(legb)[l] * p_prev;
        const REAL dp_next = dp_prev + (REAL)(2 * l + 1) * p;
        p_prev = p, p = p_next, dp_prev = dp, dp = dp_next;
    }
#pragma GCC unroll 16
    for (int l = 0; l <= L; ++l) al[l] = -w[l] * inv_d, be[l] = -ka * dw[l];
    REAL cm = 1, sm = 0;
    sc[0] = r2, ss[0] = 0;
#pragma GCC unroll 16
    for (int m = 1; m <= L; ++m) {
        const REAL cn = cm * x - sm * yy;
        sm = cm * yy + sm * x, cm = cn, sc[m] = r2 * cm, ss[m] = r2 * sm;
    }
    q[0][0] = TAB(diag)[0];
    {
        const REAL r = be[0] * q[0][0];
        y[0] = w[0] * q[0][0];
        gx[0] = x * r, gy[0] = yy * r, gz[0] = z * r;
    }
#pragma GCC unroll 16
    for (int l = 1; l <= L; ++l) {
        const int base = l * (l + 1);
        const REAL *ta = TAB(a) + l * (l + 1) / 2, *tb = TAB(b) + l * (l + 1) / 2, *dz = TAB(dz) + l * (l + 1) / 2;
#pragma GCC unroll 16
        for (int m = 0; m <= l; ++m)
            q[l][m] = m == l ? TAB(diag)[l] : m == l - 1 ? ta[m] * z * q[l - 1][m]
                                                          : ta[m] * (z * q[l - 1][m] - tb[m] * q[l - 2][m]);
        q[l][l + 1] = 0;
        const REAL wl = w[l], a = al[l], b = be[l];
        {
            const REAL n = q[l][0], d = dz[0] * q[l][1], r = b * n - a * (z * d);
            y[base] = wl * n;
            gx[base] = x * r, gy[base] = yy * r, gz[base] = a * d + z * r;
        }
#pragma GCC unroll 16
        for (int m = 1; m <= l; ++m) {
            const REAL n = q[l][m], v = wl * n, pm = a * n * TAB(mval)[m];
            if (m <= 2 * (l / 2)) {
                const REAL d = dz[m] * q[l][m + 1], r = b * n - (pm + a * (z * d)), h = a * d + z * r;
                const REAL rx = x * r, ry = yy * r;
                gz[base + m] = h * sc[m], gz[base - m] = h * ss[m];
                gx[base + m] = pm * sc[m - 1] + rx * sc[m], gx[base - m] = pm * ss[m - 1] + rx * ss[m];
                gy[base + m] = ry * sc[m] - pm * ss[m - 1], gy[base - m] = pm * sc[m - 1] + ry * ss[m];
            } else { /* m = l odd: dN/dz = 0 */
                const REAL r = b * n - pm, rx = x * r, ry = yy * r;
                gz[base + m] = z * r * sc[m], gz[base - m] = z * r * ss[m];
                gx[base + m] = pm * sc[m - 1] + rx * sc[m], gx[base - m] = pm * ss[m - 1] + rx * ss[m];
                gy[base + m] = ry * sc[m] - pm * ss[m - 1], gy[base - m] = pm * sc[m - 1] + ry * ss[m];
            }
            y[base + m] = v * sc[m], y[base - m] = v * ss[m];
        }
    }
}

static SHL__NOINLINE void SUFFIX(sphere_inside)(int lmax, REAL *coeffs)
{
    for (int k = 0; k < SHL_NCOEFFS(lmax); ++k) coeffs[k] = 0;
    coeffs[0] = (REAL)sqrt(4.0 * M_PI);
}

/* The coefficients outside the sphere from the geometry's values, passed in
 * registers (a geometry struct passed by address made the kernels wait on store
 * forwarding); one copy for every caller. */
static SHL__NOINLINE void SUFFIX(sphere_value_regs)(int lmax, REAL ux, REAL uy, REAL uz, REAL t, REAL s2, REAL c,
                                                    REAL *coeffs)
{
    const REAL u[3] = {ux, uy, uz};
    switch (lmax) {
    case 0: SUFFIX(sphere_small)(0, u, t, s2, c, coeffs); return;
    case 1: SUFFIX(sphere_small)(1, u, t, s2, c, coeffs); return;
    case 2: SUFFIX(sphere_small)(2, u, t, s2, c, coeffs); return;
    case 3: SUFFIX(sphere_small)(3, u, t, s2, c, coeffs); return;
    case 4: SUFFIX(sphere_small)(4, u, t, s2, c, coeffs); return;
    case 5: SUFFIX(sphere_small)(5, u, t, s2, c, coeffs); return;
    default: break;
    }
    REAL w[SHL_LMAX_MAX + 1];
    /* shl__cap_weights without dw, step for step (the same values) */
    w[0] = (REAL)(2.0 * M_PI) * t;
    REAL p_prev = 1, p = c, dp_prev = 0, dp = 1, two_l1 = 3; /* two_l1 = 2l + 1, exact */
    for (int l = 1; l <= lmax; ++l) {
        w[l] = TAB(capk)[l] * s2 * dp;
        const REAL p_next = TAB(lega)[l] * c * p - TAB(legb)[l] * p_prev;
        const REAL dp_next = dp_prev + two_l1 * p;
        p_prev = p, p = p_next, dp_prev = dp, dp = dp_next, two_l1 += 2;
    }
    SUFFIX(shl__sh_eval_w)(lmax, u, w, coeffs); /* HVL Eq. (15): w_l Y_lm(axis) */
}

/* The coefficients of shl__sphere_sh (no gradient). */
static SHL__ALWAYS_INLINE void SUFFIX(sphere_value)(int lmax, const shl__sphere_geom *g, REAL *coeffs)
{
    if (g->inside)
        SUFFIX(sphere_inside)(lmax, coeffs);
    else
        SUFFIX(sphere_value_regs)(lmax, (REAL)g->u[0], (REAL)g->u[1], (REAL)g->u[2], (REAL)g->t, (REAL)g->s2,
                                  (REAL)g->c, coeffs);
}

static SHL__NOINLINE void SUFFIX(sphere_inside_grad)(int lmax, REAL *coeffs, REAL *grad)
{
    SUFFIX(sphere_inside)(lmax, coeffs);
    for (int k = 0; k < 3 * SHL_NCOEFFS(lmax); ++k) grad[k] = 0;
}

/* shl__sphere_sh with the gradient for lmax <= SHL__SPHERE_SMALL and unscaled
 * geometry (grad_scale 1), inlined into the entry points. */
static SHL__ALWAYS_INLINE void SUFFIX(sphere_grad_small)(int lmax, const shl__sphere_geom *g, REAL *coeffs,
                                                         REAL *grad)
{
    if (g->inside) {
        SUFFIX(sphere_inside_grad)(lmax, coeffs, grad);
        return;
    }
    const REAL u[3] = {(REAL)g->u[0], (REAL)g->u[1], (REAL)g->u[2]};
    const REAL t = (REAL)g->t, s2 = (REAL)g->s2, c = (REAL)g->c, inv_d = (REAL)g->inv_d_s;
    const REAL ka = (REAL)(g->s2 / g->c * g->inv_d_s); /* k_alpha_s of shl__sphere_geom_init */
    switch (lmax) {
    case 0: SUFFIX(sphere_small_grad)(0, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    case 1: SUFFIX(sphere_small_grad)(1, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    case 2: SUFFIX(sphere_small_grad)(2, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    case 3: SUFFIX(sphere_small_grad)(3, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    case 4: SUFFIX(sphere_small_grad)(4, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    default: SUFFIX(sphere_small_grad)(5, u, t, s2, c, inv_d, ka, coeffs, grad); return;
    }
}

/* The gradient for sin^2 a below SHL__S2_TINY_D (double), SHL__S2_TINY_F (float)
 * (sphere.h): shl__sphere_sh in units of s2_x = sin^2 a 2^-s2_e, where s2 itself
 * would carry few or no significant bits, while every gradient component (~2 s2 / d)
 * may be a normal number; then times 2^(s2_e - e) (x_scale) from those units and the
 * scaled lengths', in double, rounded once.  The coefficients (~s2, below the
 * kernels' normal range) are those of the value path: the same bits with and without
 * the gradient. */
static SHL__NOINLINE void SUFFIX(sphere_grad_tiny)(int lmax, const shl__sphere_geom *g, REAL *coeffs, REAL *grad)
{
    shl__sphere_geom gx = *g;
    gx.t = g->t_x, gx.s2 = g->s2_x, gx.k_alpha_s = g->k_alpha_x, gx.s2_e = 0;
    gx.grad_scale[0] = gx.grad_scale[1] = 1.0;
    SUFFIX(shl__sphere_sh)(lmax, &gx, coeffs, grad);
    for (int k = 0; k < 3 * SHL_NCOEFFS(lmax); ++k)
        grad[k] = (REAL)((double)grad[k] * g->x_scale[0] * g->x_scale[1]);
    SUFFIX(sphere_value)(lmax, g, coeffs);
}

void SUFFIX(shl__sphere_sh)(int lmax, const shl__sphere_geom *g, REAL *coeffs, REAL *grad)
{
    if (grad && !g->inside && g->s2_e &&
        g->s2 < (sizeof(REAL) == sizeof(double) ? SHL__S2_TINY_D : SHL__S2_TINY_F)) {
        SUFFIX(sphere_grad_tiny)(lmax, g, coeffs, grad);
        return;
    }
    if (!grad) {
        SUFFIX(sphere_value)(lmax, g, coeffs);
        return;
    }
    const int nc = SHL_NCOEFFS(lmax);
    if (g->inside) {
        SUFFIX(sphere_inside_grad)(lmax, coeffs, grad);
        return;
    }
    REAL w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1];
    const REAL u[3] = {(REAL)g->u[0], (REAL)g->u[1], (REAL)g->u[2]};
    SUFFIX(shl__cap_weights)(lmax, (REAL)g->t, (REAL)g->s2, (REAL)g->c, w, dw);
    /* d/dx [w_l(cos a) Y(u)] = w_l' (d cos a/dx) Y - (w_l / d) (I - u u^T) grad Y with
     * d cos a/dx = -k_alpha u (HVL Eq. (15) differentiated): al = -w_l / d, be = -k_alpha w_l'
     * in shl__sh_eval_wgrad, which forms coefficients and gradient in one pass */
    REAL al[SHL_LMAX_MAX + 1], be[SHL_LMAX_MAX + 1];
    const REAL inv_d = (REAL)g->inv_d_s, ka = (REAL)g->k_alpha_s;
    al[0] = -w[0] * inv_d, be[0] = -ka * dw[0]; /* (band 0 outside the loop: lmax >= 0 unknown to gcc) */
    for (int l = 1; l <= lmax; ++l) al[l] = -w[l] * inv_d, be[l] = -ka * dw[l];
    SUFFIX(shl__sh_eval_wgrad)(lmax, u, w, al, be, coeffs, grad, nc);
    if (g->grad_scale[0] != 1.0 || g->grad_scale[1] != 1.0)
        for (int k = 0; k < 3 * nc; ++k) /* back from scaled units in double (internal.h) */
            grad[k] = (REAL)(grad[k] * g->grad_scale[0] * g->grad_scale[1]);
}

/* The rest of the entry points (sphere_d, sphere_f): argument checks unless
 * checked, geom_init (shl__sphere_geom_init, resp. geom_init_f), shl__sphere_sh; out
 * of line, so that the common paths need no frame for it.  The geometry in double
 * from the arguments (exact). */
static SHL__NOINLINE int SUFFIX(sphere_general)(int lmax, const REAL x[3], const REAL center[3], REAL radius,
                                                REAL *coeffs, REAL *grad, int checked)
{
    const double xd[3] = {x[0], x[1], x[2]}, cd[3] = {center[0], center[1], center[2]};
    if (!checked) {
        if (shl__check_finite(xd, 3) || shl__check_finite(cd, 3)) return SHL_ENONFINITE;
        const int st = check_radius(radius);
        if (st) return st;
    }
    shl__sphere_geom g;
    SUFFIX(geom_init)(&g, xd, cd, radius);
    SUFFIX(shl__sphere_sh)(lmax, &g, coeffs, grad);
    return SHL_OK;
}

/* The entry points.  entry_geom (sphere.c) true implies finite x and centre and a
 * finite radius > 0, so in the common case no further check is needed and no
 * scaling (the exponent e of shl__sphere_geom_init is 0); coefficients without
 * gradient, and with it up to band SHL__SPHERE_SMALL, then take their geometry to the
 * kernels in registers (the address of g is never taken). */
static SHL__ALWAYS_INLINE int SUFFIX(sphere)(const shl_ctx *ctx, const REAL x[3], const REAL center[3], REAL radius,
                                             REAL *coeffs, REAL *grad, int want_grad)
{
    if (!ctx || !x || !center || !coeffs || (want_grad && !grad)) return SHL_ENULL;
    const double xd[3] = {x[0], x[1], x[2]}, cd[3] = {center[0], center[1], center[2]};
    const int lmax = ctx->lmax;
    shl__sphere_geom g;
    const int ok = SUFFIX(entry_geom)(&g, xd, cd, radius, want_grad, !want_grad || lmax <= SHL__SPHERE_SMALL);
    if (ok && !want_grad) {
        SUFFIX(sphere_value)(lmax, &g, coeffs);
        return SHL_OK;
    }
    if (ok && lmax <= SHL__SPHERE_SMALL) {
        SUFFIX(sphere_grad_small)(lmax, &g, coeffs, grad);
        return SHL_OK;
    }
    return SUFFIX(sphere_general)(lmax, x, center, radius, coeffs, want_grad ? grad : NULL, ok);
}

int PUBLIC(shl_sphere)(const shl_ctx *ctx, const REAL x[3], const REAL center[3], REAL radius, REAL *coeffs)
{
    return SUFFIX(sphere)(ctx, x, center, radius, coeffs, NULL, 0);
}

int PUBLIC(shl_sphere_grad)(const shl_ctx *ctx, const REAL x[3], const REAL center[3], REAL radius, REAL *coeffs,
                            REAL *grad)
{
    return SUFFIX(sphere)(ctx, x, center, radius, coeffs, grad, 1);
}
