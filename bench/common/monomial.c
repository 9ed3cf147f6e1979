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

/* Lobes two side by side in one vector of the compilers' generic type (native on
 * SSE2 / NEON), exactly as the ZH recurrence's scalar-ISA kernel (simd/poly_zh_batch.h)
 * runs them: both methods get the same vectorization across lobes.  Each lane does
 * the one-lobe arithmetic. */
typedef double v2 __attribute__((vector_size(2 * sizeof(double))));
#define V2(x) ((v2){(x), (x)})

void monomial_poly_zh(const shl__poly_geom *g, int lmax, double *zh)
{
    if (!coef_ready) init_coef();
    const int n = g->n, ndir = 2 * lmax + 1;
    v2 a[SHL_MAX_VERTS], b[SHL_MAX_VERTS], c[SHL_MAX_VERTS], s[SHL_MAX_VERTS], r2[SHL_MAX_VERTS];
    v2 apow[SHL_MAX_VERTS], f_km1[SHL_MAX_VERTS], f_km2[SHL_MAX_VERTS], moment[SHL_LMAX_MAX + 1];
    double norm[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) norm[l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
    for (int d0 = 0; d0 < ndir; d0 += 2) {
        const double *d1 = shl__zh_dir[d0], *d2 = shl__zh_dir[d0 + 1 < ndir ? d0 + 1 : d0];
        const v2 dx = {d1[0], d2[0]}, dy = {d1[1], d2[1]}, dz = {d1[2], d2[2]};
        v2 edge_sum = V2(0.0);
        for (int e = 0; e < n; ++e) {
            a[e] = dx * V2(g->w[e][0]) + dy * V2(g->w[e][1]) + dz * V2(g->w[e][2]);
            b[e] = dx * V2(g->lam[e][0]) + dy * V2(g->lam[e][1]) + dz * V2(g->lam[e][2]);
            c[e] = dx * V2(g->mu[e][0]) + dy * V2(g->mu[e][1]) + dz * V2(g->mu[e][2]);
            s[e] = a[e] * V2(g->sin_gamma[e]) - b[e] * V2(g->cos_gamma[e]);
            r2[e] = a[e] * a[e] + b[e] * b[e];
            apow[e] = a[e];              /* a^{k-1} for k = 2 */
            f_km2[e] = V2(g->gamma[e]);  /* F_0 = int_0^gamma dt */
            f_km1[e] = s[e] + b[e];      /* F_1 = int_0^gamma (a cos t + b sin t) dt */
            edge_sum += c[e] * f_km2[e];
        }
        moment[0] = V2(n ? g->solid_angle : 0.0);
        if (lmax >= 1) moment[1] = V2(0.5) * edge_sum;
        for (int k = 2; k <= lmax; ++k) {
            /* Stokes with V = (-y z^{k-1}, x z^{k-1}, 0): (k+1) M_k - (k-1) M_{k-2} = sum_e c_e F_{k-1,e} */
            edge_sum = V2(0.0);
            for (int e = 0; e < n; ++e) edge_sum += c[e] * f_km1[e];
            moment[k] = (V2(k - 1.0) * moment[k - 2] + edge_sum) / V2(k + 1.0);
            if (k == lmax) break;
            /* k F_k = (k-1)(a^2+b^2) F_{k-2} + s z_end^{k-1} + b a^{k-1}, z_end = a at the next vertex */
            for (int e = 0; e < n; ++e) {
                const int f = (e + 1 == n) ? 0 : e + 1;
                const v2 fk = (V2(k - 1.0) * r2[e] * f_km2[e] + s[e] * apow[f] + b[e] * apow[e]) / V2(k);
                f_km2[e] = f_km1[e];
                f_km1[e] = fk;
            }
            for (int e = 0; e < n; ++e) apow[e] *= a[e];
        }
        for (int l = 0; l <= lmax; ++l) {
            v2 acc = V2(0.0);
            for (int k = l & 1; k <= l; k += 2) acc += V2(legendre_coef[l][k]) * moment[k];
            const v2 out = V2(norm[l]) * acc;
            zh[d0 * SHL__ZH_STRIDE + l] = out[0];
            if (d0 + 1 < ndir) zh[(d0 + 1) * SHL__ZH_STRIDE + l] = out[1];
        }
    }
}
