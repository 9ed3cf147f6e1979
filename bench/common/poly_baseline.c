/* Frozen baseline kernels (poly_baseline.h): src/polygon_zh.h's double instance
 * and src/zh_lobes.c's reconstruction at commit 01a6269^, unchanged but for the
 * instance macros.  Do not optimize: it is the reference of the speed-up. */
#include "poly_baseline.h"
#include "zh_tables.h"
#include <math.h>

void baseline_poly_zh(const shl__poly_geom *g, int lmax, double *zh)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* near-plane sliver: planar Gauss rule (polygon.c) */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) zh[dir * SHL__ZH_STRIDE + l] = area[dir * SHL__ZH_STRIDE + l];
        return;
    }
    /* bands whose edge integrals are needed: B_l up to lmax-1 (Eq. 29) */
    const int ltop = lmax - 1;
    double norm[SHL_LMAX_MAX + 1], inv_l[SHL_LMAX_MAX + 2], s_b[SHL_LMAX_MAX + 1], s_s[SHL_LMAX_MAX + 1];
    double l_m1[SHL_LMAX_MAX + 1], twol_m1[SHL_LMAX_MAX + 1];
    inv_l[lmax + 1] = (1.0 / (lmax + 1));
    for (int l = 0; l <= lmax; ++l) {
        l_m1[l] = (l - 1);
        twol_m1[l] = (2 * l - 1);
        norm[l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); /* K_l */
        inv_l[l] = (1.0 / (l + (l == 0)));
        s_b[l] = ((2.0 * l - 1.0) / (l * (l + 1.0) + (l == 0)));   /* Eq. 29 weights */
        s_s[l] = ((l - 2.0) * (l - 1.0) / (l * (l + 1.0) + (l == 0)));
    }
    for (int dir = 0; dir < ndir; ++dir) {
        const double *lobe = shl__zh_dir[dir];
        double bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1];
        for (int l = 0; l <= lmax; ++l) bsum[l] = 0;
        for (int e = 0; e < n; ++e) {
            const int f = (e + 1 == n) ? 0 : e + 1;
            /* Eq. 20: coordinates of the lobe axis in the edge frame */
            const double ae = lobe[0] * g->w[e][0] + lobe[1] * g->w[e][1] + lobe[2] * g->w[e][2];
            const double be = lobe[0] * g->lam[e][0] + lobe[1] * g->lam[e][1] + lobe[2] * g->lam[e][2];
            const double ce = lobe[0] * g->mu[e][0] + lobe[1] * g->mu[e][1] + lobe[2] * g->mu[e][2];
            const double a = ae, c = ce;
            const double af = (lobe[0] * g->w[f][0] + lobe[1] * g->w[f][1] + lobe[2] * g->w[f][2]);
            const double c2 = (ce * ce); /* = 1 - a^2 - b^2 of Eq. 31, without cancellation */
            const double s = (ae * g->sin_gamma[e] - be * g->cos_gamma[e]);
            const double b1 = (ae * g->sin_gamma[e] + be * g->omc_gamma[e]); /* B_1, Eq. 27 */
            const double da = (lobe[0] * g->dw[e][0] + lobe[1] * g->dw[e][1] + lobe[2] * g->dw[e][2]);
            const double gamma = g->gamma[e];
            double p_lm1 = a, p_lm2 = 1;          /* P_{l-1}(a_e), P_{l-2}(a_e) */
            double dp_lm1 = da, dp_lm2 = 0;       /* dP_{l-1}, dP_{l-2} */
            double b_lm1 = b1, b_lm2 = gamma;     /* B_1, B_0 (Eq. 26-27) */
            double d_lm1 = gamma, d_lm2 = 0;      /* D_1, D_0 (Eq. 28) */
            bsum[0] += c * gamma;
            if (lmax >= 2) bsum[1] += c * b1;
            for (int l = 2; l <= ltop; ++l) {
                const double rl = inv_l[l], lm1 = l_m1[l], tlm1 = twol_m1[l];
                const double pl = (tlm1 * a * p_lm1 - lm1 * p_lm2) * rl;           /* Eq. 11 */
                const double dl = tlm1 * b_lm1 + d_lm2;                            /* Eq. 32 */
                /* dP_l from Eq. 11 at both ends: a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
                const double dpl = (tlm1 * (af * dp_lm1 + da * p_lm1) - lm1 * dp_lm2) * rl;
                    /* Eq. 31: C_{l-1} */
                    const double cl = (b1 * p_lm1 + s * dp_lm1 - c2 * d_lm1 + lm1 * b_lm2) * rl;
                    const double bl = (tlm1 * cl - lm1 * b_lm2) * rl;              /* Eq. 30 */
                    b_lm2 = b_lm1, b_lm1 = bl;
                    bsum[l] += c * bl;                                              /* Eq. 14 */
                p_lm2 = p_lm1, p_lm1 = pl;
                dp_lm2 = dp_lm1, dp_lm1 = dpl;
                d_lm2 = d_lm1, d_lm1 = dl;
            }
        }
        surf[0] = g->solid_angle;                                  /* S_0 */
        if (lmax >= 1) surf[1] = bsum[0] / 2;                            /* S_1, Eq. 25 */
        for (int l = 2; l <= lmax; ++l) surf[l] = s_b[l] * bsum[l - 1] + s_s[l] * surf[l - 2]; /* Eq. 29 */
        for (int l = 0; l <= lmax; ++l) { /* Eq. 13 */
            zh[dir * SHL__ZH_STRIDE + l] = norm[l] * surf[l];
        }
    }
}

static void reconstruct_band(int l, const double *even, const double *odd, double *out)
{
    const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l);
    const double *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
    for (int m = 0; m <= l; ++m) {
        double acc = 0.0;
        for (int k = 0; k <= l; ++k) acc += we[m * (l + 1) + k] * even[k];
        out[m] = acc;
    }
    for (int m = 1; m <= l; ++m) {
        double acc = 0.0;
        for (int k = 0; k < l; ++k) acc += wo[(m - 1) * l + k] * odd[k];
        out[-m] = acc;
    }
}

void baseline_zh_to_sh(int lmax, const double *zh, double *coeffs)
{
    for (int l = 0; l <= lmax; ++l) {
        double even[SHL_LMAX_MAX + 1], odd[SHL_LMAX_MAX + 1];
        even[0] = zh[l];
        for (int k = 1; k <= l; ++k) {
            const double z1 = zh[(2 * k - 1) * SHL__ZH_STRIDE + l], z2 = zh[2 * k * SHL__ZH_STRIDE + l];
            even[k] = z1 + z2;
            odd[k - 1] = z1 - z2;
        }
        reconstruct_band(l, even, odd, coeffs + l * (l + 1));
    }
}

void baseline_polygon(int lmax, const double x[3], const double *verts, int n, double *coeffs)
{
    shl__poly_geom g;
    double zh[SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, x, verts, n);
    baseline_poly_zh(&g, lmax, zh);
    baseline_zh_to_sh(lmax, zh, coeffs);
}
