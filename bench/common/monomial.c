#include "monomial.h"
#include "zh_tables.h"
#include <math.h>

/* Monomial coefficients of P_l: P_l(z) = sum_k coef[l][k] z^k. */
static double legendre_coef[SHL_LMAX_MAX + 1][SHL_LMAX_MAX + 1];
static int coef_ready;

static void init_coef(void)
{
    legendre_coef[0][0] = 1.0;
    legendre_coef[1][1] = 1.0;
    for (int l = 2; l <= SHL_LMAX_MAX; ++l)
        for (int k = 0; k <= l; ++k)
            legendre_coef[l][k] = ((k > 0 ? (2.0 * l - 1.0) * legendre_coef[l - 1][k - 1] : 0.0) -
                                   (l - 1.0) * legendre_coef[l - 2][k]) / l;
    coef_ready = 1;
}

void monomial_poly_zh(const shl__poly_geom *g, int lmax, double *zh)
{
    if (!coef_ready) init_coef();
    const int n = g->n;
    double a[SHL_MAX_VERTS], b[SHL_MAX_VERTS], c[SHL_MAX_VERTS], s[SHL_MAX_VERTS], r2[SHL_MAX_VERTS];
    double apow[SHL_MAX_VERTS], f_km1[SHL_MAX_VERTS], f_km2[SHL_MAX_VERTS];
    double moment[SHL_LMAX_MAX + 1], norm[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) norm[l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
    for (int dir = 0; dir < 2 * lmax + 1; ++dir) {
        const double *d = shl__zh_dir[dir];
        double edge_sum = 0.0;
        for (int e = 0; e < n; ++e) {
            a[e] = d[0] * g->w[e][0] + d[1] * g->w[e][1] + d[2] * g->w[e][2];
            b[e] = d[0] * g->lam[e][0] + d[1] * g->lam[e][1] + d[2] * g->lam[e][2];
            c[e] = d[0] * g->mu[e][0] + d[1] * g->mu[e][1] + d[2] * g->mu[e][2];
            s[e] = a[e] * g->sin_gamma[e] - b[e] * g->cos_gamma[e];
            r2[e] = a[e] * a[e] + b[e] * b[e];
            apow[e] = a[e];              /* a^{k-1} for k = 2 */
            f_km2[e] = g->gamma[e];      /* F_0 = int_0^gamma dt */
            f_km1[e] = s[e] + b[e];      /* F_1 = int_0^gamma (a cos t + b sin t) dt */
            edge_sum += c[e] * f_km2[e];
        }
        moment[0] = n ? g->solid_angle : 0.0;
        if (lmax >= 1) moment[1] = 0.5 * edge_sum;
        for (int k = 2; k <= lmax; ++k) {
            /* Stokes with V = (-y z^{k-1}, x z^{k-1}, 0): (k+1) M_k - (k-1) M_{k-2} = sum_e c_e F_{k-1,e} */
            edge_sum = 0.0;
            for (int e = 0; e < n; ++e) edge_sum += c[e] * f_km1[e];
            moment[k] = ((k - 1.0) * moment[k - 2] + edge_sum) / (k + 1.0);
            if (k == lmax) break;
            /* k F_k = (k-1)(a^2+b^2) F_{k-2} + s z_end^{k-1} + b a^{k-1}, z_end = a at the next vertex */
            for (int e = 0; e < n; ++e) {
                const int f = (e + 1 == n) ? 0 : e + 1;
                const double fk = ((k - 1.0) * r2[e] * f_km2[e] + s[e] * apow[f] + b[e] * apow[e]) / k;
                f_km2[e] = f_km1[e];
                f_km1[e] = fk;
            }
            for (int e = 0; e < n; ++e) apow[e] *= a[e];
        }
        for (int l = 0; l <= lmax; ++l) {
            double acc = 0.0;
            for (int k = l & 1; k <= l; k += 2) acc += legendre_coef[l][k] * moment[k];
            zh[dir * SHL__ZH_STRIDE + l] = norm[l] * acc;
        }
    }
}
