/* Second spatial derivatives of a sphere light's SH coefficients (derivation:
 * README "Hessians", (S1)-(S7)).  The Hessian is formed directly in the SH basis from
 * the cap weights and the SH polynomials' first and second derivatives, as the
 * gradient (sphere_impl.h, sh_basis_impl.h); tests/test_hessian.c checks it against
 * the lobe-integral route (S4) and finite differences. */
#include "sphere.h"
#include <string.h>

/* The six rows of second derivatives of a sphere light's SH coefficients, directly in the
 * SH basis: hess[i*nc + k], i = xx, xy, xz, yy, yz, zz (derivation: README "Hessians",
 * (S5)-(S7)).  Coefficient k = (l, m) is F = W_l(dist) Y_k(u), u = v/dist, v = center - x,
 * W_l = w_l(cos a) (HVL Eq. 14-15); with the polynomial extension g of Y_k (sh_basis_impl.h:
 * sqrt2 N_l^m(z) C_m(x, y)), G = grad g(u), H = grad grad g(u), h = H u, P = I - u u^T:
 *   d2F/dx2 = W'' Y u u^T + (W'/dist) Y P + (W'/dist - W/dist^2)(u q^T + q u^T)
 *             + (W/dist^2) (P H P - u q^T - q u^T - (u.G) P),   q = P G,          (S5)
 * (d/dv of Y(v/|v|) twice; the Hessian in x equals the one in v), W' = w' k, W'' = w'' k^2 +
 * w' phi'' with (S1): cos a = phi(dist) = sqrt(1 - R^2/dist^2), phi' = k = sin^2 a / (dist cos a),
 * phi'' = -(k/dist)(3 + sin^2 a / cos^2 a), w_l' = -2 pi P_l(c), w_l'' = -2 pi P_l'(c).  Expanded in the ambient basis:
 *   d2F/dx2 = del H + u e^T + e u^T + bet I + mu u u^T,                             (S6)
 *   del = W/dist^2, gam = W'/dist - del, bet = (W'/dist) Y - del (u.G), e = gam G - del h,
 *   mu = W'' Y - bet - 2 gam (u.G) + del (u.h).
 * On the m-column everything is a per-(l, m) scalar times C_{m-2}, C_{m-1}, C_m (S_ likewise):
 * with n = N_l^m, n' = dz_lm N_l^{m+1}, n'' = dz_lm dz_l,m+1 N_l^{m+2} (z-derivatives),
 *   u.G = (m n + z n') C_m,   h = (m C_{m-1} b1, -m S_{m-1} b1, (m n' + z n'') C_m),
 *   u.h = (m (m-1) n + 2 m z n' + z^2 n'') C_m,  b1 = (m-1) n + z n',                (S7)
 * from d C_m/dx = m C_{m-1}, d C_m/dy = -m S_{m-1} and x C_{m-1} - y S_{m-1} = C_m; the S_m
 * column is the C_m column with (C, S) -> (S, -C). */
void shl__sphere_sh_hess(int lmax, const shl__sphere_geom *g, double *hess, int nc)
{
    if (g->inside) { /* constant coefficients */
        memset(hess, 0, sizeof(double) * 6 * (size_t)nc);
        return;
    }
    /* scaled units (sphere.h): 1/dist and k in units 2^e, the Hessian times 2^-2e; below
     * SHL__S2_TINY_D sin^2 a, t, k in units 2^s2_e (as sphere_grad_tiny), times 2^s2_e */
    const int tiny = g->s2_e != 0 && g->s2 < SHL__S2_TINY_D;
    const double s2 = tiny ? g->s2_x : g->s2, t = tiny ? g->t_x : g->t, k = tiny ? g->k_alpha_x : g->k_alpha_s;
    const double c = g->c, id = g->inv_d_s;
    const double phi2 = -k * id * (3.0 + g->s2 / (c * c)); /* (S1), in the units of k */
    double w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1], w2[SHL_LMAX_MAX + 1], gam[SHL_LMAX_MAX + 1],
        del[SHL_LMAX_MAX + 1], bet[SHL_LMAX_MAX + 1];
    shl__cap_weights_d(lmax, t, s2, c, w, dw);
    double d2w = 0.0, d2w_prev = 0.0; /* w_l'' = -2 pi P_l'(c): w''_{l+1} = w''_{l-1} + (2l+1) w_l' */
    for (int l = 0; l <= lmax; ++l) {
        const double w1 = dw[l] * k;                          /* W' = w' k */
        w2[l] = d2w * k * g->k_alpha_s + dw[l] * phi2;        /* W'' (w'' k^2: O(s2) smaller when tiny) */
        del[l] = w[l] * id * id;
        bet[l] = w1 * id;
        gam[l] = bet[l] - del[l];
        const double next = d2w_prev + (2.0 * l + 1.0) * dw[l];
        d2w_prev = d2w, d2w = next;
    }
    const double x = g->u[0], y = g->u[1], z = g->u[2];
    const double xx = x * x, xy = x * y, xz = x * z, yy = y * y, yz = y * z, zz = z * z;
    double sc[SHL_LMAX_MAX + 1], ss[SHL_LMAX_MAX + 1]; /* sqrt2 C_m, sqrt2 S_m (sh_basis_impl.h) */
    sc[0] = M_SQRT2, ss[0] = 0.0;
    for (int m = 1; m <= lmax; ++m) {
        const double cm = sc[m - 1] * x - ss[m - 1] * y;
        ss[m] = sc[m - 1] * y + ss[m - 1] * x, sc[m] = cm;
    }
    /* rows l-2, l-1, l of N_l^m (sh_basis.h), and n', n'' of row l with zeros past m = l */
    double rows[3][SHL_LMAX_MAX + 1], d1[SHL_LMAX_MAX + 2], d2[SHL_LMAX_MAX + 1];
    double *h0 = hess, *h1 = hess + nc, *h2 = hess + 2 * nc, *h3 = hess + 3 * nc, *h4 = hess + 4 * nc,
           *h5 = hess + 5 * nc;
    for (int l = 0; l <= lmax; ++l) {
        const int t3 = l * (l + 1) / 2, base = l * (l + 1);
        double *ql = rows[l % 3];
        const double *q1 = rows[(l + 2) % 3], *q2 = rows[(l + 1) % 3];
        for (int m = 0; m < l - 1; ++m) /* N_l^m = a (z N_{l-1}^m - b N_{l-2}^m) */
            ql[m] = shl__sh_a_d[t3 + m] * (z * q1[m] - shl__sh_b_d[t3 + m] * q2[m]);
        if (l > 0) ql[l - 1] = shl__sh_a_d[t3 + l - 1] * z * q1[l - 1];
        ql[l] = shl__sh_diag_d[l];
        d1[l] = d1[l + 1] = 0.0;
        for (int m = 0; m < l; ++m) d1[m] = shl__sh_dz_d[t3 + m] * ql[m + 1];
        for (int m = 0; m <= l; ++m) d2[m] = shl__sh_dz_d[t3 + m] * d1[m + 1];
        const double de = del[l], ga = gam[l], be = bet[l], wh = w2[l];
        { /* m = 0: Y = N_l^0 (no sqrt2), no azimuthal derivatives */
            const double n = ql[0], e1 = d1[0], e2 = d2[0], ug = z * e1;
            const double p2 = ga * e1 - de * z * e2, b0 = be * n - de * ug;
            const double mu = wh * n - b0 - 2.0 * ga * ug + de * zz * e2;
            h0[base] = b0 + mu * xx, h1[base] = mu * xy, h2[base] = x * p2 + mu * xz;
            h3[base] = b0 + mu * yy, h4[base] = y * p2 + mu * yz, h5[base] = de * e2 + 2.0 * z * p2 + b0 + mu * zz;
        }
        for (int m = 1; m <= l; ++m) {
            const double fm = m, n = ql[m], e1 = d1[m], e2 = d2[m];
            const double ug = fm * n + z * e1, b1 = ug - n; /* (S7): u.G / C_m, b1 */
            const double p1 = fm * (ga * n - de * b1);       /* e = (p1 C_{m-1}, -p1 S_{m-1}, p2 C_m) */
            const double p2 = ga * e1 - de * (fm * e1 + z * e2);
            const double b0 = be * n - de * ug;              /* bet / C_m */
            const double mu = wh * n - b0 - 2.0 * ga * ug + de * (fm * (fm - 1.0) * n + 2.0 * fm * z * e1 + zz * e2);
            const double hh = de * fm * (fm - 1.0) * n, hz = de * fm * e1 + z * p1;
            const double cxx = b0 + mu * xx, cxy = mu * xy, cxz = x * p2 + mu * xz, cyy = b0 + mu * yy,
                         cyz = y * p2 + mu * yz, czz = de * e2 + 2.0 * z * p2 + b0 + mu * zz;
            const double c0 = sc[m], s0 = ss[m], c1 = sc[m - 1], s1 = ss[m - 1];
            const double c2 = m >= 2 ? sc[m - 2] : 0.0, s2m = m >= 2 ? ss[m - 2] : 0.0;
            const double px = 2.0 * x * p1, py = 2.0 * y * p1;
            const int kp = base + m, kn = base - m;
            h0[kp] = hh * c2 + px * c1 + cxx * c0;
            h1[kp] = p1 * (y * c1 - x * s1) - hh * s2m + cxy * c0;
            h2[kp] = hz * c1 + cxz * c0;
            h3[kp] = cyy * c0 - hh * c2 - py * s1;
            h4[kp] = cyz * c0 - hz * s1;
            h5[kp] = czz * c0;
            h0[kn] = hh * s2m + px * s1 + cxx * s0;
            h1[kn] = p1 * (y * s1 + x * c1) + hh * c2 + cxy * s0;
            h2[kn] = hz * s1 + cxz * s0;
            h3[kn] = cyy * s0 - hh * s2m + py * c1;
            h4[kn] = cyz * s0 + hz * c1;
            h5[kn] = czz * s0;
        }
    }
    int e2x = -(shl__ilogb(g->grad_scale[0]) + shl__ilogb(g->grad_scale[1])); /* e of 2^-e */
    e2x = (tiny ? g->s2_e : 0) - 2 * e2x;
    if (e2x) { /* back from scaled units: 2^(s2_e - 2e) in two equal-signed factors (internal.h) */
        double f[2];
        shl__pow2_split(e2x, f);
        for (int i = 0; i < 6 * nc; ++i) hess[i] = hess[i] * f[0] * f[1];
    }
}

int shl_sphere_hess(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
                    double *coeffs, double *grad, double *hess)
{
    if (!ctx || !x || !center || !coeffs || !grad || !hess) return SHL_ENULL;
    if (shl__check_finite(x, 3) || shl__check_finite(center, 3) || !isfinite(radius)) return SHL_ENONFINITE;
    if (!(radius > 0.0)) return SHL_EDOMAIN;
    const int lmax = ctx->lmax, nc = ctx->nc;
    shl__sphere_geom g;
    shl__sphere_geom_init(&g, x, center, radius);
    shl__sphere_sh_d(lmax, &g, coeffs, grad); /* as shl_sphere_grad, bit for bit */
    shl__sphere_sh_hess(lmax, &g, hess, nc);
    return SHL_OK;
}
