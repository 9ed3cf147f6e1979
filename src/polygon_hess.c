/* Second spatial derivatives of the polygon's ZH integrals, the recurrence of
 * Wang & Ramamoorthi 2018 (Alg. 1) and Wu et al. 2020's gradient (polygon_zh.h)
 * extended one order.  The equation numbers (H1)-(H6) are those of the derivation
 * note (README, "Hessians"), summarized here.
 *
 * Edge e as a straight segment: r(s) = v_e - x + s t (t its unit direction),
 * q the foot of x on its line, rho = |q|, f = 1/|r| = g . w(t) with g = q/rho^2
 * (polygon.h: gvec), z = u . r/|r| for the lobe u, F(r) = P_l(z)/|r|^3.  Wu's
 * gradient K_l sum_e mu_e I_l is, with dt = rho ds/|r|^2,
 *   d zh / dx = K_l sum_e n_e Phi_e,   n_e = (v_e - x) x t = rho mu_e,   Phi_e = int F ds = I_l / rho.   (H1)
 * Differentiating again: d n_e/dx_b = -(e_b x t) is antisymmetric and drops out
 * of the symmetric total, and d Phi/dx_b = -int dF/dr_b ds splits along t, q and mu:
 *   t:  int t . grad F ds = [F] (the ends);
 *   q:  Euler (F homogeneous of degree -3), q . grad F = -3F - s dF/ds, so int = -2 Phi - [s F];
 *   mu: mu . grad F = c P_l'(z)/|r|^4 (c = u . mu), int = M_l / rho, M_l = int_0^T f^2 P_l'(h) dt.
 * With rho t - s q/rho = |r| lambda(t) (the arc tangent) the ends combine into
 *   H_e = S(mu_e, 2 I_l g_e - [f^2 P_l(h) lambda]_0^T) - c M_l mu_e mu_e^T,
 *   d2 zh / dx dx^T = K_l sum_e H_e,   S(a, b) = (a b^T + b a^T) / 2.                                    (H2)
 * M_l by integration by parts as Wu's I_l: f^2 + f'^2 = |g|^2 = G2 and f h + f' h' = V = g . u
 * are constant on the arc (both sinusoids of t), so (f^2)'' = 2 G2 - 4 f^2 and with
 * h P_l' = l P_l + P_{l-1}':
 *   E_l = int f^2 P_l(h) dt = (V J_l - M_{l-1} - [f f' P_l]_0^T + G2 B_l) / (l + 2),                   (H3)
 *   M_l = (2l - 1) E_{l-1} + M_{l-2},   M_0 = 0,                                                     (H4)
 *   E_0 = f_e^2 (T + sin T cos T)/2 + f'_e^2 (T - sin T cos T)/2 + f_e f'_e sin^2 T,                 (H5)
 * (J_l, B_l as in polygon_zh.h), the ends written as in polygon_zh.h so that no O(1)
 * terms cancel: [f f' P_l] = (f f')(T) dP_l + [f f'] P_l(a_e), [f f'] = G2 T - 2 E_0, and
 *   [f^2 P_l lambda] = ((f_f^2 - f_e^2) P_l(a_e) + f_f^2 dP_l) lambda_f + f_e^2 P_l(a_e) (lambda_f - lambda_e),   (H6)
 * lambda_f - lambda_e = mu x (w_f - w_e), f_f - f_e = g . (w_f - w_e).  With S(mu, mu) = mu mu^T,
 * per edge, lobe and band H_e = S(mu, r), r = 2 I_l g - P_l(a_e) b_p - dP_l b_d - c M_l mu, from
 * the edge's vectors b_p = (f_f^2 - f_e^2) lambda_f + f_e^2 (lambda_f - lambda_e), b_d = f_f^2 lambda_f
 * (H6): three components of r, then six of S (18 multiplies, as the three tensors S(mu, w_f),
 * S(mu, lambda_f), mu mu^T times three scalars, but 9 edge constants and mu instead of 18).  The
 * off-diagonal sums hold 2 S, halved with the band weight (a power of two: the same values). */
#include "polygon_hess.h"
#include "quad.h"
#include "zh_tables.h"
#include <math.h>
#include <pthread.h>

/* x - sin x at x = 2 gamma, gamma in [0, pi], from sg = sin gamma and cg = cos gamma (a few
 * ulps, polygon.c): Taylor series below x = 1 (terms fall by >= 20x; 9 terms leave < 1e-20
 * relative; the factors 1/((k-1) k) rounded, 0.5 ulp each), sin x = 2 sg cg above (an error of
 * a few ulps of 1 against x - sin x >= 1 - sin 1 = 0.16: at most 5 bits lost). */
static double two_gamma_minus_sin(double gam, double sg, double cg)
{
    static const double inv_fac[9] = {1.0 / 420, 1.0 / 342, 1.0 / 272, 1.0 / 210, 1.0 / 156,
                                      1.0 / 110, 1.0 / 72,  1.0 / 42,  1.0 / 20}; /* 1/((k-1) k), k = 21, 19, .., 5 */
    const double x = 2.0 * gam;
    if (x >= 1.0) return x - 2.0 * sg * cg;
    const double x2 = x * x;
    double t = 1.0;
    for (int i = 0; i < 9; ++i) t = 1.0 - t * x2 * inv_fac[i]; /* 1 - x^2/20 (1 - x^2/42 (...)) */
    return x * x2 / 6.0 * t;
}

/* Edges seen nearly end-on (x close to the edge's line, far from the edge): (H3) adds G2 B_l,
 * whose rounding (eps G2 T) is eps (r/rho)^2 of E_l = O(f^2 T) (r: distance to the nearer end),
 * and Wu's I_l (relative error ~eps r/rho, harmless in the gradient, where the edge's term is
 * small) enters (H2) times |g| = 1/rho: measured 1e-5 of the Hessian at r/rho = 3e5.  Beyond
 * (r/rho)^2 = NEAR_RADIAL those edges take E_l, and I_l for (H2), by a Gauss-Legendre rule on
 * the arc instead (the gradient keeps the recurrence's I_l, as shl__poly_zh_grad_d): both ends are then more than
 * 100 rho from the foot, so T < 2 / 100 (each end within atan(1/100) of the direction of the
 * line), and f^2 P_l(h(t)) is a trigonometric polynomial of frequency <= l + 2, whose
 * Taylor terms at the arc's midpoint fall like (T (l + 2) / 2)^k / k! <= 0.32^k / k! at
 * lmax 30: the NQ-point rule (exact for degree 2 NQ - 1) errs by < 0.32^16 / 16! < 1e-20
 * relative to (r/rho)^2 f^2 T, i.e. < 1e-16 of E_l. */
enum { NQ = SHL__HESS_NQ };
#define NEAR_RADIAL 1e4
typedef shl__hess_edge hess_edge;

static void hess_edge_init(const shl__poly_geom *g, int e, const double *glx, const double *glw, hess_edge *h)
{
    const int f = (e + 1 == g->n) ? 0 : e + 1;
    const double *gv = g->gvec[e], *mu = g->mu[e];
    const double fe = shl__dot3(gv, g->w[e]), ff = shl__dot3(gv, g->w[f]);
    const double fpe = shl__dot3(gv, g->lam[e]), df = shl__dot3(gv, g->dw[e]);
    const double gam = g->gamma[e], sg = g->sin_gamma[e], cg = g->cos_gamma[e];
    double lf[3], dl[3];
    shl__cross3(mu, g->w[f], lf);  /* lambda_f */
    shl__cross3(mu, g->dw[e], dl); /* lambda_f - lambda_e */
    h->g2 = shl__dot3(gv, gv);
    h->e0 = 0.5 * fe * fe * (gam + sg * cg) + 0.25 * fpe * fpe * two_gamma_minus_sin(gam, sg, cg) + fe * fpe * sg * sg; /* (H5) */
    h->ffp1 = ff * g->fprime1[e];
    h->ffd = h->g2 * gam - 2.0 * h->e0;
    h->fe2 = fe * fe;
    h->ff2 = ff * ff;
    /* (H6): [f^2 P_l lambda] = P_l(a_e) bp + dP_l bd */
    const double dff2 = df * (ff + fe);
    for (int k = 0; k < 3; ++k) {
        h->tg[k] = 2.0 * gv[k];
        h->bp[k] = dff2 * lf[k] + h->fe2 * dl[k];
        h->bd[k] = h->ff2 * lf[k];
    }
    h->quad = glx && h->g2 > NEAR_RADIAL * fmax(h->fe2, h->ff2);
    for (int j = 0; h->quad && j < NQ; ++j) {
        const double t = 0.5 * gam * (1.0 + glx[j]), c = cos(t), sn = sin(t), ft = fe * c + fpe * sn;
        h->qc[j] = c, h->qs[j] = sn, h->qf[j] = 0.5 * gam * glw[j] * ft, h->qw[j] = h->qf[j] * ft;
    }
}

int shl__hess_edges_init(const shl__poly_geom *g, hess_edge *he)
{
    int any_radial = 0;
    for (int e = 0; e < g->n; ++e) {
        hess_edge_init(g, e, NULL, NULL, &he[e]);
        any_radial |= he[e].g2 > NEAR_RADIAL * fmax(he[e].fe2, he[e].ff2);
    }
    if (any_radial) { /* rare: the rule's nodes only then */
        double glx[NQ], glw[NQ];
        shl__gauss_legendre(NQ, glx, glw);
        for (int e = 0; e < g->n; ++e) hess_edge_init(g, e, glx, glw, &he[e]);
    }
    return any_radial;
}

enum { NL = 2 }; /* lobes side by side, as SHL__ZH_LANES in polygon_zh.h */

void shl__poly_zh_hess_d(const shl__poly_geom *g, int lmax, double *z10, int unscaled)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    const double sc = g->grad_scale[0] * g->grad_scale[1];
    const shl__zh_band_consts *bc = shl__zh_bands(); /* the coefficient kernels' band constants, so their bits */
    const double *norm = bc->norm, *s_b = bc->s_b, *s_s = bc->s_s; /* K_l; Wang Eq. 29 weights */
    double gnorm[SHL_LMAX_MAX + 1], hnorm[SHL_LMAX_MAX + 1], hhalf[SHL_LMAX_MAX + 1], inv_l[SHL_LMAX_MAX + 3];
    for (int l = 0; l <= lmax; ++l) {
        gnorm[l] = unscaled ? norm[l] * sc : norm[l];
        hnorm[l] = unscaled ? norm[l] * sc * sc : norm[l];
        hhalf[l] = 0.5 * hnorm[l]; /* off-diagonal sums of 2 S(mu, r): the same bits as S, halved by a power of two */
    }
    for (int l = 0; l <= lmax + 2; ++l) inv_l[l] = 1.0 / (l + (l == 0));
    hess_edge he[SHL_MAX_VERTS];
    shl__hess_edges_init(g, he);
    for (int d0 = 0; d0 < ndir; d0 += NL) {
        const double *lobe[NL];
        for (int k = 0; k < NL; ++k) lobe[k] = shl__zh_dir[d0 + k < ndir ? d0 + k : ndir - 1];
        double bsum[SHL_LMAX_MAX + 1][NL], surf[SHL_LMAX_MAX + 1][NL];
        double gsum[SHL_LMAX_MAX + 1][NL][4], hsum[SHL_LMAX_MAX + 1][NL][6]; /* components innermost: vector steps */
        for (int l = 0; l <= lmax; ++l)
            for (int k = 0; k < NL; ++k) {
                bsum[l][k] = 0.0;
                for (int a = 0; a < 4; ++a) gsum[l][k][a] = 0.0;
                for (int i = 0; i < 6; ++i) hsum[l][k][i] = 0.0;
            }
        for (int e = 0; e < n; ++e) {
            const int f = (e + 1 == n) ? 0 : e + 1;
            const hess_edge *h = &he[e];
            const double gamma = g->gamma[e], i0 = g->f_integral[e], fp1 = g->fprime1[e];
            double a[NL], c[NL], af[NL], c2[NL], s[NL], b1[NL], da[NL], v[NL];
            double p1[NL], p2[NL], dp1[NL], dp2[NL], bb1[NL], bb2[NL], d1[NL], d2[NL];
            double i1[NL], j1[NL], j2[NL], e1[NL], m1[NL], m2[NL];
            /* per band: I_l, c M_l, P_l(a_e), dP_l of the two lanes (contracted after the recurrence) */
            double ei[SHL_LMAX_MAX + 1][NL], em[SHL_LMAX_MAX + 1][NL], ep[SHL_LMAX_MAX + 1][NL],
                edp[SHL_LMAX_MAX + 1][NL], eq[SHL_LMAX_MAX + 1][NL], eqi[SHL_LMAX_MAX + 1][NL];
            if (h->quad) /* E_l and I_l by the Gauss rule (NEAR_RADIAL) */
                for (int k = 0; k < NL; ++k) {
                    const double ae = shl__dot3(lobe[k], g->w[e]), be = shl__dot3(lobe[k], g->lam[e]);
                    for (int l = 0; l <= lmax; ++l) eq[l][k] = eqi[l][k] = 0.0;
                    for (int j = 0; j < NQ; ++j) {
                        const double z = ae * h->qc[j] + be * h->qs[j];
                        double q0 = 0.0, q1 = 1.0; /* P_{l-1}, P_l at l = 0 */
                        for (int l = 0; l <= lmax; ++l) {
                            eq[l][k] += h->qw[j] * q1;
                            eqi[l][k] += h->qf[j] * q1;
                            const double q2 = ((2.0 * l + 1.0) * z * q1 - l * q0) * inv_l[l + 1];
                            q0 = q1, q1 = q2;
                        }
                    }
                }
#pragma GCC unroll 8
            for (int k = 0; k < NL; ++k) {
                const double *u = lobe[k];
                const double ae = shl__dot3(u, g->w[e]), be = shl__dot3(u, g->lam[e]), ce = shl__dot3(u, g->mu[e]);
                a[k] = ae, c[k] = ce, c2[k] = ce * ce;
                af[k] = shl__dot3(u, g->w[f]);
                s[k] = ae * g->sin_gamma[e] - be * g->cos_gamma[e];
                b1[k] = ae * g->sin_gamma[e] + be * g->omc_gamma[e]; /* B_1, Wang Eq. 27 */
                da[k] = shl__dot3(u, g->dw[e]);
                v[k] = shl__dot3(u, g->gvec[e]);
                p1[k] = ae, p2[k] = 1.0, dp1[k] = da[k], dp2[k] = 0.0;
                bb1[k] = b1[k], bb2[k] = gamma, d1[k] = gamma, d2[k] = 0.0;
                bsum[0][k] += ce * gamma;
                if (lmax >= 2) bsum[1][k] += ce * b1[k];
                /* l = 0 and 1 of Wu's I, J (polygon_zh.h) and of (H3)-(H4) */
                i1[k] = (v[k] * gamma - (fp1 * da[k] - i0 * ae)) / 2.0;
                j1[k] = i0, j2[k] = 0.0;
                m2[k] = 0.0, m1[k] = h->e0; /* M_0, M_1 = E_0 */
                e1[k] = (v[k] * i0 - h->ffp1 * da[k] - h->ffd * ae + h->g2 * b1[k]) / 3.0; /* E_1 */
                ei[0][k] = i0, em[0][k] = 0.0, ep[0][k] = 1.0, edp[0][k] = 0.0;
                if (lmax >= 1) ei[1][k] = i1[k], em[1][k] = ce * h->e0, ep[1][k] = ae, edp[1][k] = da[k];
            }
            for (int l = 2; l <= lmax; ++l) {
                const double pa = bc->leg_a[l], pb = bc->leg_b[l], tlm1 = bc->twol_m1[l];
#pragma GCC unroll 8
                for (int k = 0; k < NL; ++k) {
                    const double pl = pa * a[k] * p1[k] - pb * p2[k];              /* Wang Eq. 11 */
                    const double dl = tlm1 * bb1[k] + d2[k];                       /* Wang Eq. 32 */
                    const double dpl = pa * (af[k] * dp1[k] + da[k] * p1[k]) - pb * dp2[k];
                    const double il = (v[k] * dl - j1[k] - (fp1 * dpl - i0 * pl)) * inv_l[l + 1]; /* Wu I_l */
                    const double jl = tlm1 * i1[k] + j2[k];
                    /* Eq. 30 with Eq. 31's C_{l-1} = (X + (l-1) B_{l-2}) / l: B_l = alpha X + beta B_{l-2} */
                    const double bl =
                        bc->b_alpha[l] * (b1[k] * p1[k] + s[k] * dp1[k] - c2[k] * d1[k]) + bc->b_beta[l] * bb2[k];
                    const double ml = tlm1 * e1[k] + m2[k];                                              /* (H4) */
                    /* (H3) with [f f' P_l] = (f f')(T) dP_l + (G2 T - 2 E_0) P_l(a_e) */
                    const double el = (v[k] * jl - m1[k] - h->ffp1 * dpl - h->ffd * pl + h->g2 * bl) *
                                      inv_l[l + 2];
                    bsum[l][k] += c[k] * bl;
                    ei[l][k] = il, em[l][k] = c[k] * ml, ep[l][k] = pl, edp[l][k] = dpl;
                    p2[k] = p1[k], p1[k] = pl, dp2[k] = dp1[k], dp1[k] = dpl;
                    bb2[k] = bb1[k], bb1[k] = bl, d2[k] = d1[k], d1[k] = dl;
                    j2[k] = j1[k], j1[k] = jl, i1[k] = il;
                    m2[k] = m1[k], m1[k] = ml, e1[k] = el;
                }
            }
            if (h->quad) /* c M_l (H4) from the rule's E_l */
                for (int k = 0; k < NL; ++k) {
                    const double ck = shl__dot3(lobe[k], g->mu[e]);
                    double mm2 = 0.0, mm1 = eq[0][k];
                    for (int l = 2; l <= lmax; ++l) {
                        const double ml = (2.0 * l - 1.0) * eq[l - 1][k] + mm2;
                        mm2 = mm1, mm1 = ml;
                        em[l][k] = ck * ml;
                    }
                    if (lmax >= 1) em[1][k] = ck * eq[0][k];
                }
            const double(*ih)[NL] = h->quad ? (const double(*)[NL])eqi : (const double(*)[NL])ei; /* I_l of (H2) */
            const double mu[4] = {g->mu[e][0], g->mu[e][1], g->mu[e][2], 0.0};
            for (int l = 0; l <= lmax; ++l) {
#pragma GCC unroll 8
                for (int k = 0; k < NL; ++k) {
                    const double il = ih[l][k], sm = em[l][k];
                    double *hp = hsum[l][k], *gp = gsum[l][k];
                    double r[3]; /* (H2) with (H6) */
                    for (int ax = 0; ax < 3; ++ax) r[ax] = il * h->tg[ax] - ep[l][k] * h->bp[ax] - edp[l][k] * h->bd[ax] - sm * mu[ax];
                    /* (H2) as S(mu, r): xx xy xz yy yz zz, off the diagonal 2 S (halved with hnorm) */
                    hp[0] += mu[0] * r[0], hp[1] += mu[0] * r[1] + mu[1] * r[0], hp[2] += mu[0] * r[2] + mu[2] * r[0];
                    hp[3] += mu[1] * r[1], hp[4] += mu[1] * r[2] + mu[2] * r[1], hp[5] += mu[2] * r[2];
#pragma GCC unroll 4
                    for (int ax = 0; ax < 4; ++ax) gp[ax] += mu[ax] * ei[l][k]; /* Wu Eq. 11 */
                }
            }
        }
        for (int k = 0; k < NL; ++k) {
            surf[0][k] = g->solid_angle;                           /* S_0 */
            if (lmax >= 1) surf[1][k] = bsum[0][k] / 2.0;          /* S_1, Wang Eq. 25 */
        }
        for (int l = 2; l <= lmax; ++l)
            for (int k = 0; k < NL; ++k) surf[l][k] = s_b[l] * bsum[l - 1][k] + s_s[l] * surf[l - 2][k]; /* Eq. 29 */
        for (int k = 0; k < NL && d0 + k < ndir; ++k)
            for (int l = 0; l <= lmax; ++l) {
                double *o = z10 + SHL__Z10(lmax, d0 + k, l);
                o[0] = norm[l] * surf[l][k]; /* Wang Eq. 13 */
                for (int ax = 0; ax < 3; ++ax) o[1 + ax] = gnorm[l] * gsum[l][k][ax];
                for (int i = 0; i < 6; ++i) o[4 + i] = (i == 1 || i == 2 || i == 4 ? hhalf[l] : hnorm[l]) * hsum[l][k][i]; /* (H2) */
            }
    }
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* coefficients as shl__poly_zh_grad_d */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) z10[SHL__Z10(lmax, dir, l)] = area[dir * SHL__ZH_STRIDE + l];
    }
}

/* shl__zh_to_sh of the nb interleaved blocks b0 .. b0+nb-1 of z10 into out[0 .. nb-1]
 * (polygon.h): the same sums in the same order (bit for bit shl__zh_to_sh of each block),
 * the blocks innermost with a count fixed at each (inlined) call, so that the accumulators
 * stay in vector registers and each weight is loaded once for all blocks. */
static inline void zh_to_sh_blocks(int lmax, const double *z10, int b0, int nb, double *const *out)
{
    enum { MB = SHL__ZH_MULTI };
    for (int l = 0; l <= lmax; ++l) {
        double even[SHL_LMAX_MAX + 1][MB], odd[SHL_LMAX_MAX + 1][MB];
        for (int b = 0; b < nb; ++b) even[0][b] = z10[SHL__Z10(lmax, 0, l) + b0 + b];
        for (int k = 1; k <= l; ++k) {
            const double *z1 = z10 + SHL__Z10(lmax, 2 * k - 1, l) + b0, *z2 = z10 + SHL__Z10(lmax, 2 * k, l) + b0;
            for (int b = 0; b < nb; ++b) {
                even[k][b] = z1[b] + z2[b];
                odd[k - 1][b] = z1[b] - z2[b];
            }
        }
        const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l), *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
        const int base = l * (l + 1);
        for (int m = 0; m <= l; ++m) {
            double acc[MB] = {0};
            for (int k = 0; k <= l; ++k) {
                const double w = we[m * (l + 1) + k];
#pragma GCC unroll 16
                for (int b = 0; b < nb; ++b) acc[b] += w * even[k][b];
            }
            for (int b = 0; b < nb; ++b) out[b][base + m] = acc[b];
        }
        for (int m = 1; m <= l; ++m) {
            double acc[MB] = {0};
            for (int k = 0; k < l; ++k) {
                const double w = wo[(m - 1) * l + k];
#pragma GCC unroll 16
                for (int b = 0; b < nb; ++b) acc[b] += w * odd[k][b];
            }
            for (int b = 0; b < nb; ++b) out[b][base - m] = acc[b];
        }
    }
}

void shl__zh_to_sh_multi(int lmax, const double *z10, double *const out[SHL__ZH_MULTI])
{
    zh_to_sh_blocks(lmax, z10, 0, SHL__ZH_MULTI, out);
}

static shl__zh_wt_table wt;
static pthread_once_t wt_once = PTHREAD_ONCE_INIT;

static void wt_init(void)
{
    int eo = 0, oo = 0;
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) {
        const int pe = SHL__WT_PAD(l + 1), po = SHL__WT_PAD(l);
        const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l), *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
        wt.even_ofs[l] = eo, wt.odd_ofs[l] = oo;
        for (int k = 0; k <= l; ++k)
            for (int m = 0; m <= l; ++m) wt.even[eo + k * pe + m] = we[m * (l + 1) + k];
        for (int k = 0; k < l; ++k)
            for (int j = 0; j < l; ++j) wt.odd[oo + k * po + j] = wo[(l - j - 1) * l + k];
        eo += (l + 1) * pe, oo += l * po;
    }
}

const shl__zh_wt_table *shl__zh_wt(void)
{
    pthread_once(&wt_once, wt_init);
    return &wt;
}

int shl_polygon_hess(const shl_ctx *ctx, const double x[3], const double *verts, int n, double *coeffs,
                     double *grad, double *hess)
{
    if (!ctx || !x || !verts || !coeffs || !grad || !hess) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    const int lmax = ctx->lmax, nc = ctx->nc;
    shl__poly_geom g;
    shl__poly_geom_init(&g, x, verts, n);
    const int fold = shl__poly_hess_fold(&g);
    double *const out[SHL__ZH_MULTI] = {coeffs,       grad,         grad + nc,    grad + 2 * nc, hess,
                                        hess + nc,    hess + 2 * nc, hess + 3 * nc, hess + 4 * nc, hess + 5 * nc};
    /* shl__poly_zh_hess_d and shl__zh_to_sh_multi across lobes and orders, bit for bit */
    ctx->isa->poly_hess(&g, lmax, fold, out);
    if (!fold) {
        shl__poly_grad_unscale(&g, grad, 3 * nc);
        shl__poly_grad_unscale(&g, hess, 6 * nc); /* 2^-2E: twice */
        shl__poly_grad_unscale(&g, hess, 6 * nc);
    }
    return SHL_OK;
}
