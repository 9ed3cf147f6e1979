/* Derived tolerances of the float polygon paths against a double reference,
 * per band l: the SIMD kernel simd/poly_batch.h (float_geometry = 1: geometry
 * in float after a double translation) and the float instance of
 * src/polygon_zh.h behind shl_polygon_f / shl_polygon_grad_f (float_geometry
 * = 0: geometry in double, rounded once to float).
 *
 * Model.  A worst-case bound (every rounding at u, the 1-norm of the lobe
 * table, |P_l'| <= l(l+1)/2 for the lobe-coordinate errors) is 10^2-10^3 times
 * the errors seen, so the tolerances use the probabilistic model of Higham &
 * Mary (SIAM J. Sci. Comput. 41, 2019), as test_rotate.c does: roundings are
 * independent, mean 0, |delta| <= u_f = FLT_EPSILON/2, variance <= u_f^2/3, so
 * N roundings on quantities of size T add an error of deviation
 * sqrt(N/3) u_f T; the tolerance is LAMBDA = 6 deviations (Gaussian tail
 * < 2e-9 per value).  Only counts and magnitudes enter, not the order of the
 * operations: the bound holds for every ISA (one kernel text; FMA contraction
 * or a reordered sum changes N by less than the counts' slack).
 *
 * (1) Edge terms, Wang 2018 Eq. 14: E_l = sum_e c_e B_l,e with |B_l,e| <=
 * gamma_e (Eq. 20).  The set-up (omega_v, mu_e, lambda_e, sin, 1 - cos,
 * gamma_e and the lobe coordinates a, b, c, da of Eq. 20 as dot products)
 * carries NG = 40 roundings (NG = 6 with double geometry: the roundings of a,
 * b, c, da, s, B_1 to float) of relative size u_f into each edge term, and a
 * vertex direction is shared by two edges (variance x 2).  Each band step
 * (Eq. 11 for P_l and dP_l, Eq. 30-32 for B_l, D_l) adds NB = 14.  These
 * three-term recurrences are forward stable for |a| <= 1: an error injected at
 * band k propagates as a solution of the same recurrence, bounded as P_l (by 1)
 * and B_l (by gamma_e), so injected errors add in quadrature (sqrt(l)
 * growth).  The sum over the n edges rounds partial sums <= sum_e gamma_e = P
 * (the angular perimeter):
 *   sigma_E(l)^2 = u_f^2 [(NG + NB l)/3 * 2 sum_e gamma_e^2 + n/3 * P^2].
 * This is the cancellation term: O(gamma_e) terms summing to O(omega), so
 * relative to omega it is ~ u_f sqrt(n l) P / omega, P / omega ~ 4/theta for
 * a polygon of angular size theta.
 * (2) Surfaces: S_0 = omega (Van Oosterom-Strackee fan: n-2 atan2 terms of
 * NA = 16 roundings each, on the fan's sum of |terms|; one rounding with double
 * geometry), S_1 = E_0/2, Eq. 29 S_l = s_b E_l-1 + s_s S_l-2, s_s < 1:
 *   sigma_S(l)^2 = s_b^2 sigma_E(l-1)^2 + s_s^2 sigma_S(l-2)^2 + u_f^2 omega^2/3.
 * (3) Reconstruction, Eq. 33 (zh_tables.h): L_lm = sum_d alpha_lmd K_l S_l(d).
 * The 2l+1 lobes' errors are independent, so they combine with the row 2-norm
 * R_l = max_m |alpha_lm.|_2 of the lobe table (at most 13.5, at l = 2; the
 * 1-norm reaches 53), plus l+2 roundings (pair sums, mat-vec) on terms <= K_l omega:
 *   sigma_c(l) = R_l sqrt(K_l^2 sigma_S(l)^2 + u_f^2 K_l^2 omega^2 (l+2)/3).
 * (4) Conditioning: the kernel rounds x - v_0 to float, a move of x by
 * u_f |x - v_0| per coordinate (deviation / sqrt(3)), times max|grad|.
 *   tc(l) = LAMBDA [sigma_c(l) + u_f |x - v_0| max|grad| / sqrt(3)].
 * Gradients (Wu 2020 Eq. 11; polygon_zh.h: sum_e mu_e I_l,e) repeat (1)-(3)
 * with the edge integrals I_0,e = int 1/ell dt >= |I_l,e| in place of gamma_e
 * and NI = 24 more roundings per band (the I_l and J_l steps); the direction
 * errors of (1) change the shape of the polygon by a relative u_f sqrt(NG/3)
 * G / omega (G = sqrt(2 sum gamma_e^2)), and the gradient with it (this term
 * dominates for grazing views, where the mu_e are nearly parallel); the move
 * of x in (4) acts through the second derivatives, estimated as
 * (l+2) max|grad| / rho (rho: distance from x to the nearest edge line or to
 * the plane):
 *   tg(l) = LAMBDA [R_l K_l sqrt(sigma_I(l)^2 + u_f^2 I^2 (l+2)/3)
 *                   + R_l K_l sqrt(4 pi) u_f sqrt(NG/3) G / omega max|grad|
 *                   + u_f |x - v_0| (l+2) max|grad| / (sqrt(3) rho)],
 *   sigma_I(l)^2 = u_f^2 [(NG + (NB + NI) l)/3 * 2 sum_e I_0,e^2 + n/3 * I^2],
 * I = sum_e |I_0,e|, I_0,e = (sin phi_f - sin phi_e) / h_e (h_e: distance from
 * x to edge e's line, phi: angle from the foot of x on it).  Every input is
 * computed here in double from the polygon and x.
 *
 * Measured (make test; scalar, avx2, avx512 alike): worst error / tolerance
 * 0.13-0.17 (coefficients) and 0.05-0.13 (gradients) for the kernel (random,
 * every-lmax, hard cases), 0.04-0.13 for light sets and float grid nodes, 0.39
 * for shl_polygon_f; over a sweep of 6400 points (grazing views, distances
 * 0.3-1000, lmax 30) 0.40 and 0.10 (kernel), 0.45 and 0.15 (shl_polygon_grad_f).
 * Margins: the largest of ~10^5 Gaussian values is ~4.5 of LAMBDA = 6
 * deviations, the counts are upper bounds, and P^2 >= sum gamma_e^2.  The
 * gradients' geometry term is written for the worst direction of the vertex
 * errors; it is what grazing views need (without it the sweep reached 1.6),
 * and it leaves ordinary views 10-50x inside (polygon_grad_float: one point,
 * 0.01; simd_winding_per_lane 0.02). */
#ifndef SHL_FLOAT_TOL_H
#define SHL_FLOAT_TOL_H

#include "shlight.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>

enum { FT_LAMBDA = 6, FT_NA = 16, FT_NG = 40, FT_NG_SCALAR = 6, FT_NB = 14, FT_NI = 24 };

/* R_l: largest row 2-norm of band l's lobe weights (alpha of lobes 2k-1, 2k are both w_mk). */
static inline double ft_row_norm(int l)
{
    const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l), *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
    double r = 0.0;
    for (int m = 0; m <= l; ++m) {
        double s = 0.0;
        for (int k = 0; k <= l; ++k) s += (k ? 2.0 : 1.0) * we[m * (l + 1) + k] * we[m * (l + 1) + k];
        r = fmax(r, s);
    }
    for (int m = 1; m <= l; ++m) {
        double s = 0.0;
        for (int k = 0; k < l; ++k) s += 2.0 * wo[(m - 1) * l + k] * wo[(m - 1) * l + k];
        r = fmax(r, s);
    }
    return sqrt(r);
}

static inline double ft_dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline void ft_cross(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2], c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Tolerances tc[l], tg[l] (l <= lmax) of band l's coefficients and gradients
 * (absolute) at x for polygon v (n vertices, double), given the solid angle
 * omega and gmax = max|grad L_lm| of the double reference. */
static inline void float_poly_tol(int lmax, const double x[3], const double *v, int n, double omega, double gmax,
                                  int float_geometry, double *tc, double *tg)
{
    const double uf = FLT_EPSILON / 2, ng = float_geometry ? FT_NG : FT_NG_SCALAR;
    double g2 = 0.0, g1 = 0.0, i2 = 0.0, i1 = 0.0, fan = 0.0, rho = HUGE_VAL, nrm[3] = {0, 0, 0};
    double rel[SHL_MAX_VERTS][3] = {{0}}, r[SHL_MAX_VERTS] = {0};
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) rel[i][k] = v[3 * i + k] - x[k];
        r[i] = sqrt(ft_dot(rel[i], rel[i]));
    }
    for (int e = 0; e < n; ++e) {
        const int f = e + 1 == n ? 0 : e + 1;
        double c[3], t[3] = {rel[f][0] - rel[e][0], rel[f][1] - rel[e][1], rel[f][2] - rel[e][2]};
        ft_cross(rel[e], rel[f], c);
        for (int k = 0; k < 3; ++k) nrm[k] += c[k]; /* Newell normal */
        const double clen = sqrt(ft_dot(c, c)), gam = atan2(clen, ft_dot(rel[e], rel[f])), len = sqrt(ft_dot(t, t));
        g2 += gam * gam, g1 += gam;
        if (len > 0.0 && clen > 0.0) {
            const double h = clen / len; /* distance from x to the edge's line */
            const double i0 = (ft_dot(rel[f], t) / r[f] - ft_dot(rel[e], t) / r[e]) / (len * h);
            i2 += i0 * i0, i1 += fabs(i0), rho = fmin(rho, h);
        }
    }
    for (int i = 1; i + 1 < n; ++i) { /* |triangle (v_0, v_i, v_i+1)| of the fan */
        double c[3];
        ft_cross(rel[i], rel[i + 1], c);
        const double den = r[0] * r[i] * r[i + 1] + ft_dot(rel[0], rel[i]) * r[i + 1] +
                           ft_dot(rel[0], rel[i + 1]) * r[i] + ft_dot(rel[i], rel[i + 1]) * r[0];
        fan += fabs(2.0 * atan2(ft_dot(rel[0], c), den));
    }
    const double nlen = sqrt(ft_dot(nrm, nrm)), dx = float_geometry ? r[0] : 0.0; /* |x - v_0| rounded */
    if (nlen > 0.0) rho = fmin(rho, fabs(ft_dot(nrm, rel[0])) / nlen); /* distance to the plane */
    g2 = sqrt(2.0 * g2), i2 = sqrt(2.0 * i2);
    double sig_s[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) {
        const double ld = l, kl = sqrt((2.0 * ld + 1.0) / (4.0 * M_PI)), rl = ft_row_norm(l);
        /* sigma_E(l - 1): set-up, band steps, and the sum over the n edges */
        const double se = uf * sqrt((ng + FT_NB * (ld - 1.0)) / 3.0 * g2 * g2 + n / 3.0 * g1 * g1);
        if (l == 0)
            sig_s[0] = float_geometry ? uf * sqrt(FT_NA * (n - 2.0) / 3.0) * fmax(fan, omega) : uf * omega / sqrt(3.0);
        else if (l == 1)
            sig_s[1] = 0.5 * se;
        else {
            const double sb = (2.0 * ld - 1.0) / (ld * (ld + 1.0)), ss = (ld - 2.0) * (ld - 1.0) / (ld * (ld + 1.0));
            sig_s[l] = sqrt(sb * sb * se * se + ss * ss * sig_s[l - 2] * sig_s[l - 2] + uf * uf * omega * omega / 3.0);
        }
        const double round_c = uf * kl * omega * sqrt((ld + 2.0) / 3.0);
        const double sig_c = rl * sqrt(kl * kl * sig_s[l] * sig_s[l] + round_c * round_c);
        tc[l] = FT_LAMBDA * (sig_c + uf * dx / sqrt(3.0) * gmax);
        const double si = uf * sqrt((ng + (FT_NB + FT_NI) * ld) / 3.0 * i2 * i2 + n / 3.0 * i1 * i1);
        const double round_g = uf * kl * i1 * sqrt((ld + 2.0) / 3.0);
        tg[l] = FT_LAMBDA * (rl * sqrt(kl * kl * si * si + round_g * round_g) + rl * kl * sqrt(4.0 * M_PI) * uf * sqrt(ng / 3.0) * g2 / omega * gmax +
                             uf * dx / sqrt(3.0) * (ld + 2.0) * gmax / rho);
    }
}

#endif
