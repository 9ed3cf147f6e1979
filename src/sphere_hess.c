/* Second spatial derivatives of a sphere light's lobe integrals and SH
 * coefficients (derivation: README "Hessians", (S1)-(S4)).
 *
 * Lobe d, band l (HVL Eq. 14-15 by Funk-Hecke, as lights.c): Z = K_l W P_l(z) with
 * W = w_l(cos a), w_l(c) = 2 pi int_c^1 P_l, z = dir_d . u, u = (center - x)/dist.
 * cos a = phi(dist) = sqrt(1 - R^2/dist^2) depends on the distance only:
 *   phi' = sin^2 a / (dist cos a) = k,   phi'' = -(k / dist) (3 + sin^2 a / cos^2 a),        (S1)
 * and w_l' = -2 pi P_l(c), w_l'' = -2 pi P_l'(c) (the Legendre polynomials' derivative
 * recurrence).  With d dist/dx = -u, du/dx = -(I - u u^T)/dist, tau = dir - z u:
 *   dz/dx = -tau / dist,   d2z/dx2 = -(z (I - u u^T) + u tau^T + tau u^T) / dist^2,        (S2)
 *   dW/dx = -w' k u,       d2W/dx2 = (w'' k^2 + w' phi'') u u^T + (w' k / dist) (I - u u^T),   (S3)
 * and the product rule gives
 *   d2Z/dx2 / K_l = A u u^T + B (I - u u^T) + C (u tau^T + tau u^T) + D tau tau^T,          (S4)
 *   A = (w'' k^2 + w' phi'') P_l,   B = (w' k P_l - w z P_l' / dist) / dist,
 *   C = P_l' (w' k - w / dist) / dist,   D = w P_l'' / dist^2.
 * For l = 0 this is the Hessian of the solid angle 2 pi (1 - phi(dist)) as a radial function. */
#include "polygon.h"
#include "sphere.h"
#include "zh_tables.h"
#include <math.h>

void shl__sphere_zh_hess(const shl__sphere_geom *g, int lmax, double *z10)
{
    const int ndir = 2 * lmax + 1;
    if (g->inside) { /* the whole sphere of directions: constant */
        for (int d = 0; d < ndir; ++d)
            for (int l = 0; l <= lmax; ++l) {
                double *o = z10 + SHL__Z10(lmax, d, l);
                o[0] = l == 0 ? sqrt(4.0 * M_PI) : 0.0;
                for (int b = 1; b < SHL__ZH_MULTI; ++b) o[b] = 0.0;
            }
        return;
    }
    /* scaled units (sphere.h): 1/dist and k in units 2^e; results times 2^-e (gradient), 2^-2e (Hessian) */
    const double id = g->inv_d_s, k = g->k_alpha_s, sc = g->grad_scale[0] * g->grad_scale[1];
    const double phi2 = -k * id * (3.0 + g->s2 / (g->c * g->c)); /* (S1) */
    /* 2^-e (gradient) and 2^-2e (Hessian) folded into the per-band factors when that keeps
     * them normal (a power of two: the same values as multiplying afterwards), else after */
    const int fold = sc >= 0x1p-500 && sc <= 0x1p500;
    const double gs = fold ? sc : 1.0, hs = fold ? sc * sc : 1.0;
    double w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1], cw[SHL_LMAX_MAX + 1][7], ra[SHL_LMAX_MAX + 1], rb[SHL_LMAX_MAX + 1];
    shl__cap_weights_d(lmax, g->t, g->s2, g->c, w, dw);
    double pc = 1.0, pc_prev = 0.0, dpc = 0.0, dpc_prev = 0.0; /* P_l(c), P_l'(c) */
    for (int l = 0; l <= lmax; ++l) {
        const double kl = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)), d2w = -2.0 * M_PI * dpc; /* w_l'' */
        ra[l] = (2.0 * l + 1.0) / (l + 1.0), rb[l] = l / (l + 1.0); /* P_{l+1} = ra z P_l - rb P_{l-1} */
        cw[l][0] = kl * w[l];
        cw[l][1] = kl * dw[l] * k * gs;                        /* K w' k: gradient */
        cw[l][2] = kl * w[l] * id * gs;                        /* K w / dist */
        cw[l][3] = kl * (d2w * k * k + dw[l] * phi2) * hs;     /* (S4): A / P_l */
        cw[l][4] = kl * dw[l] * k * id * hs;                   /* B = (c4 P_l - c5 z P_l') */
        cw[l][5] = kl * w[l] * id * id * hs;                   /* C = (c4 - c5) P_l', D = c5 P_l'' */
        const double pn = ra[l] * g->c * pc - rb[l] * pc_prev;
        const double dpn = dpc_prev + (2.0 * l + 1.0) * pc; /* P'_{l+1} = P'_{l-1} + (2l+1) P_l */
        pc_prev = pc, pc = pn, dpc_prev = dpc, dpc = dpn;
    }
    const double *u = g->u;
    static const int ia[6] = {0, 0, 0, 1, 1, 2}, ib[6] = {0, 1, 2, 1, 2, 2};
    double uu[6];
    for (int i = 0; i < 6; ++i) uu[i] = u[ia[i]] * u[ib[i]];
    for (int d = 0; d < ndir; ++d) {
        const double *dir = shl__zh_dir[d];
        const double z = fmin(1.0, fmax(-1.0, shl__dot3(dir, u)));
        const double tau[3] = {dir[0] - z * u[0], dir[1] - z * u[1], dir[2] - z * u[2]};
        double ut[6], tt[6];
        for (int i = 0; i < 6; ++i) {
            ut[i] = u[ia[i]] * tau[ib[i]] + tau[ia[i]] * u[ib[i]];
            tt[i] = tau[ia[i]] * tau[ib[i]];
        }
        double p = 1.0, p_prev = 0.0, dp = 0.0, dp_prev = 0.0, d2p = 0.0, d2p_prev = 0.0; /* P_l, P_l', P_l'' at z */
        for (int l = 0; l <= lmax; ++l) {
            double *o = z10 + SHL__Z10(lmax, d, l);
            o[0] = cw[l][0] * p;
            const double radial = cw[l][1] * p, tang = cw[l][2] * dp; /* dZ/dx = -radial u - tang tau */
            for (int a = 0; a < 3; ++a) o[1 + a] = -radial * u[a] - tang * tau[a];
            /* (S4) with I - u u^T expanded: (A - B) u u^T + B I + C (u tau^T + tau u^T) + D tau tau^T */
            const double cb = cw[l][4] * p - cw[l][5] * z * dp, ca = cw[l][3] * p - cb;
            const double cc = (cw[l][4] - cw[l][5]) * dp, cd = cw[l][5] * d2p;
            for (int i = 0; i < 6; ++i) o[4 + i] = ca * uu[i] + cc * ut[i] + cd * tt[i];
            o[4] += cb, o[7] += cb, o[9] += cb;
            const double pn = ra[l] * z * p - rb[l] * p_prev;
            const double dpn = dp_prev + (2.0 * l + 1.0) * p, d2pn = d2p_prev + (2.0 * l + 1.0) * dp;
            p_prev = p, p = pn, dp_prev = dp, dp = dpn, d2p_prev = d2p, d2p = d2pn;
        }
    }
    if (!fold) /* back from scaled units, in double (internal.h) */
        for (int d = 0; d < ndir; ++d)
            for (int l = 0; l <= lmax; ++l) {
                double *o = z10 + SHL__Z10(lmax, d, l);
                for (int b = 1; b < SHL__ZH_MULTI; ++b) o[b] = o[b] * sc;
                for (int b = 4; b < SHL__ZH_MULTI; ++b) o[b] = o[b] * sc;
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
    double z10[SHL__Z10_SIZE(SHL_LMAX_MAX)];
    shl__sphere_zh_hess(&g, lmax, z10);
    double *const out[6] = {hess, hess + nc, hess + 2 * nc, hess + 3 * nc, hess + 4 * nc, hess + 5 * nc};
    ctx->isa->zh_to_sh_hess6(lmax, z10, out); /* shl__zh_to_sh_hess6 vectorized, bit for bit */
    return SHL_OK;
}
