/* Single-call polygon Hessians (shl_polygon_hess) vectorized ACROSS LOBES, as
 * simd/poly_zh_batch.h does for coefficients and gradients: the recurrence of the
 * scalar reference shl__poly_zh_hess_d (src/polygon_hess.c, derivation (H1)-(H6)
 * there) for ZW lobes side by side in one vector, ZW = the ISA's double width
 * SHL_VDLEN (8 on AVX-512, 4 on AVX2), at least 2.  Generic vector types, no fused
 * multiply-add (gcc's C11 mode and the clang pragma below): each lane does exactly
 * the reference's one-lobe arithmetic, so every ISA gives the reference's bits
 * (tests/test_hessian.c, hess_isa_kernels_match_reference).  The contraction
 * of (H2) is done inside the band loop instead of after it (the same sums, edges in
 * the same order).  A partial last block repeats its last lobe.  Also the ZH -> SH
 * reconstruction (Wang 2018 Eq. 33) of the interleaved blocks, vectorized across
 * blocks, the same sums in the same order as shl__zh_to_sh. */
#include "../src/polygon_hess.h"
#include "kernel_api.h"
#include <string.h>

#ifdef __clang__
#pragma clang fp contract(off) /* as gcc in C11 mode: every ISA rounds as the scalar one */
#endif

#if defined(SHL_VDLEN) && SHL_VDLEN > 2
#define ZW SHL_VDLEN
#else
#define ZW 2
#endif
typedef double hv __attribute__((vector_size(ZW * sizeof(double))));

static inline hv hv_set1(double x)
{
    double t[ZW];
    for (int k = 0; k < ZW; ++k) t[k] = x;
    hv v;
    memcpy(&v, t, sizeof v);
    return v;
}

/* u . p per lane: (u0 p0 + u1 p1) + u2 p2, the order of shl__dot3 */
static inline hv hv_dot(const hv u[3], const double p[3])
{
    return u[0] * hv_set1(p[0]) + u[1] * hv_set1(p[1]) + u[2] * hv_set1(p[2]);
}

/* The per-edge, per-band terms of (H2) and Wu's gradient (Eq. 11) added to the band's sums:
 * il = I_l of (H2), sm = c M_l, p = P_l(a_e), dp = dP_l, ig = I_l of the gradient. */
__attribute__((always_inline)) static inline void hess_add(const shl__hess_edge *h, const double mu[3], hv il, hv sm, hv p, hv dp, hv ig, hv *hs,
                            hv *gs)
{
    const hv al = hv_set1(h->dff2) * p + hv_set1(h->ff2) * dp, bl = hv_set1(h->fe2) * p; /* (H6) */
    const hv qw = il * hv_set1(2.0 * h->gw) - bl * hv_set1(h->dlw);
    const hv ql = il * hv_set1(2.0 * h->gl) - al - bl * hv_set1(h->dll);
    for (int i = 0; i < 6; ++i) hs[i] += qw * hv_set1(h->tw[i]) + ql * hv_set1(h->tl[i]) - sm * hv_set1(h->tm[i]);
    for (int ax = 0; ax < 3; ++ax) gs[ax] += hv_set1(mu[ax]) * ig;
}

void SHL_ISA_SUFFIX(shl__poly_zh_hess)(const struct shl__poly_geom *g, int lmax, double *z10, int unscaled)
{
    const int n = g->n, ndir = 2 * lmax + 1;
    const double sc = g->grad_scale[0] * g->grad_scale[1];
    double norm[SHL_LMAX_MAX + 1], gnorm[SHL_LMAX_MAX + 1], hnorm[SHL_LMAX_MAX + 1], inv_l[SHL_LMAX_MAX + 3],
        s_b[SHL_LMAX_MAX + 1], s_s[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) { /* as the reference */
        norm[l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
        gnorm[l] = unscaled ? norm[l] * sc : norm[l];
        hnorm[l] = unscaled ? norm[l] * sc * sc : norm[l];
        s_b[l] = (2.0 * l - 1.0) / (l * (l + 1.0) + (l == 0));
        s_s[l] = (l - 2.0) * (l - 1.0) / (l * (l + 1.0) + (l == 0));
    }
    for (int l = 0; l <= lmax + 2; ++l) inv_l[l] = 1.0 / (l + (l == 0));
    shl__hess_edge he[SHL_MAX_VERTS];
    shl__hess_edges_init(g, he);
    for (int d0 = 0; d0 < ndir; d0 += ZW) {
        double t[3][ZW];
        for (int k = 0; k < ZW; ++k)
            for (int c = 0; c < 3; ++c) t[c][k] = shl__zh_dir[d0 + k < ndir ? d0 + k : ndir - 1][c];
        hv u[3];
        for (int c = 0; c < 3; ++c) memcpy(&u[c], t[c], sizeof u[c]);
        hv bsum[SHL_LMAX_MAX + 1], surf[SHL_LMAX_MAX + 1], gsum[SHL_LMAX_MAX + 1][3], hsum[SHL_LMAX_MAX + 1][6];
        for (int l = 0; l <= lmax; ++l) {
            bsum[l] = hv_set1(0.0);
            for (int a = 0; a < 3; ++a) gsum[l][a] = hv_set1(0.0);
            for (int i = 0; i < 6; ++i) hsum[l][i] = hv_set1(0.0);
        }
        for (int e = 0; e < n; ++e) {
            const int f = (e + 1 == n) ? 0 : e + 1;
            const shl__hess_edge *h = &he[e];
            const double *mu = g->mu[e];
            const hv gamma = hv_set1(g->gamma[e]), i0 = hv_set1(g->f_integral[e]), fp1 = hv_set1(g->fprime1[e]);
            const hv a = hv_dot(u, g->w[e]), b = hv_dot(u, g->lam[e]), c = hv_dot(u, mu), c2 = c * c;
            const hv af = hv_dot(u, g->w[f]), da = hv_dot(u, g->dw[e]), v = hv_dot(u, g->gvec[e]);
            const hv s = a * hv_set1(g->sin_gamma[e]) - b * hv_set1(g->cos_gamma[e]);
            const hv b1 = a * hv_set1(g->sin_gamma[e]) + b * hv_set1(g->omc_gamma[e]); /* B_1, Wang Eq. 27 */
            const hv e0 = hv_set1(h->e0), g2 = hv_set1(h->g2), ffp1 = hv_set1(h->ffp1), te0 = hv_set1(2.0 * h->e0);
            /* edges seen end-on: E_l, I_l of (H2) by the Gauss rule, and c M_l (H4) from them
             * (qi, qm: I_l and c M_l of (H2), else from the recurrence below) */
            const int quad = h->quad;
            hv qe[SHL_LMAX_MAX + 1], qi[SHL_LMAX_MAX + 1], qm[SHL_LMAX_MAX + 1];
            if (quad) {
                for (int l = 0; l <= lmax; ++l) qe[l] = qi[l] = hv_set1(0.0);
                for (int j = 0; j < SHL__HESS_NQ; ++j) {
                    const hv z = a * hv_set1(h->qc[j]) + b * hv_set1(h->qs[j]);
                    const hv wq = hv_set1(h->qw[j]), wf = hv_set1(h->qf[j]);
                    hv q0 = hv_set1(0.0), q1 = hv_set1(1.0); /* P_{l-1}, P_l at l = 0 */
                    for (int l = 0; l <= lmax; ++l) {
                        qe[l] += wq * q1;
                        qi[l] += wf * q1;
                        const hv q2 = (hv_set1(2.0 * l + 1.0) * z * q1 - hv_set1(l) * q0) * hv_set1(inv_l[l + 1]);
                        q0 = q1, q1 = q2;
                    }
                }
                hv mm2 = hv_set1(0.0), mm1 = qe[0];
                qm[0] = hv_set1(0.0);
                qm[1] = c * qe[0]; /* unused at lmax 0 */
                for (int l = 2; l <= lmax; ++l) {
                    const hv ml = hv_set1(2.0 * l - 1.0) * qe[l - 1] + mm2;
                    mm2 = mm1, mm1 = ml;
                    qm[l] = c * ml;
                }
            }
            hv p1 = a, p2 = hv_set1(1.0), dp1 = da, dp2 = hv_set1(0.0);
            hv bb1 = b1, bb2 = gamma, d1 = gamma, d2 = hv_set1(0.0);
            bsum[0] += c * gamma;
            if (lmax >= 2) bsum[1] += c * b1;
            /* l = 0 and 1 of Wu's I, J and of (H3)-(H4) */
            hv i1 = (v * gamma - (fp1 * da - i0 * a)) / hv_set1(2.0);
            hv j1 = i0, j2 = hv_set1(0.0), m2 = hv_set1(0.0), m1 = e0; /* M_0, M_1 = E_0 */
            hv e1 = (v * i0 - ffp1 * da + te0 * a + g2 * (b1 - gamma * a)) / hv_set1(3.0); /* E_1 */
            if (!quad) /* I_l and c M_l of (H2) from the recurrence */
                qi[0] = i0, qm[0] = hv_set1(0.0), qi[1] = i1, qm[1] = c * e0;
            hess_add(h, mu, qi[0], qm[0], hv_set1(1.0), hv_set1(0.0), i0, hsum[0], gsum[0]);
            if (lmax >= 1) hess_add(h, mu, qi[1], qm[1], a, da, i1, hsum[1], gsum[1]);
            for (int l = 2; l <= lmax; ++l) {
                const hv rl = hv_set1(inv_l[l]), lm1 = hv_set1(l - 1.0), tlm1 = hv_set1(2.0 * l - 1.0);
                const hv pl = (tlm1 * a * p1 - lm1 * p2) * rl;                                      /* Wang Eq. 11 */
                const hv dl = tlm1 * bb1 + d2;                                                      /* Wang Eq. 32 */
                const hv dpl = (tlm1 * (af * dp1 + da * p1) - lm1 * dp2) * rl;
                const hv il = (v * dl - j1 - (fp1 * dpl - i0 * pl)) * hv_set1(inv_l[l + 1]);      /* Wu I_l */
                const hv jl = tlm1 * i1 + j2;
                const hv cl = (b1 * p1 + s * dp1 - c2 * d1 + lm1 * bb2) * rl;                     /* Eq. 31 */
                const hv bl = (tlm1 * cl - lm1 * bb2) * rl;                                         /* Eq. 30 */
                const hv ml = tlm1 * e1 + m2;                                                       /* (H4) */
                const hv el = (v * jl - m1 - ffp1 * dpl + te0 * pl + g2 * (bl - gamma * pl)) * hv_set1(inv_l[l + 2]); /* (H3) */
                bsum[l] += c * bl;
                if (!quad) qi[l] = il, qm[l] = c * ml;
                hess_add(h, mu, qi[l], qm[l], pl, dpl, il, hsum[l], gsum[l]);
                p2 = p1, p1 = pl, dp2 = dp1, dp1 = dpl;
                bb2 = bb1, bb1 = bl, d2 = d1, d1 = dl;
                j2 = j1, j1 = jl, i1 = il;
                m2 = m1, m1 = ml, e1 = el;
            }
        }
        surf[0] = hv_set1(g->solid_angle);                 /* S_0 */
        if (lmax >= 1) surf[1] = bsum[0] / hv_set1(2.0); /* S_1, Wang Eq. 25 */
        for (int l = 2; l <= lmax; ++l) surf[l] = hv_set1(s_b[l]) * bsum[l - 1] + hv_set1(s_s[l]) * surf[l - 2]; /* Eq. 29 */
        const int cnt = ndir - d0 < ZW ? ndir - d0 : ZW;
        for (int l = 0; l <= lmax; ++l) {
            double o[SHL__ZH_MULTI][ZW];
            const hv ol = hv_set1(norm[l]) * surf[l]; /* Wang Eq. 13 */
            memcpy(o[0], &ol, sizeof ol);
            for (int ax = 0; ax < 3; ++ax) {
                const hv t1 = hv_set1(gnorm[l]) * gsum[l][ax];
                memcpy(o[1 + ax], &t1, sizeof t1);
            }
            for (int i = 0; i < 6; ++i) {
                const hv t1 = hv_set1(hnorm[l]) * hsum[l][i]; /* (H2) */
                memcpy(o[4 + i], &t1, sizeof t1);
            }
            for (int k = 0; k < cnt; ++k)
                for (int bl = 0; bl < SHL__ZH_MULTI; ++bl) z10[SHL__Z10(lmax, d0 + k, l) + bl] = o[bl][k];
        }
    }
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* coefficients as shl__poly_zh_grad_d */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) z10[SHL__Z10(lmax, dir, l)] = area[dir * SHL__ZH_STRIDE + l];
    }
}

/* Reconstruction of interleaved blocks, vectorized across them: the blocks b0 .. b0+nb-1
 * of each z10 record (nb = 10 or 6, b0 + nb = 10) as lanes of an 8-lane vector holding
 * the record's last 8 entries and, for nb = 10, a 2-lane one holding its first 2; per
 * lane the sums of shl__zh_to_sh in its order (the unused lanes are discarded).
 * Generic vectors: any ISA runs them. */
typedef double r8 __attribute__((vector_size(8 * sizeof(double))));
typedef double r2 __attribute__((vector_size(2 * sizeof(double))));

__attribute__((always_inline)) static inline void zh_to_sh_vec(int lmax, const double *z10, const int nb,
                                                                double *const *out)
{
    enum { LO = SHL__ZH_MULTI - 8 }; /* lane j of the 8-lane vector: block LO + j */
    const int hi_used = nb > 8;
    for (int l = 0; l <= lmax; ++l) {
        r8 even_lo[SHL_LMAX_MAX + 1], odd_lo[SHL_LMAX_MAX + 1];
        r2 even_hi[SHL_LMAX_MAX + 1], odd_hi[SHL_LMAX_MAX + 1];
        for (int k = 0; k <= l; ++k) { /* even_k = z_{2k-1} + z_{2k}, odd_{k-1} = z_{2k-1} - z_{2k} (k >= 1) */
            const double *z1 = z10 + SHL__Z10(lmax, k ? 2 * k - 1 : 0, l), *z2 = z10 + SHL__Z10(lmax, 2 * k, l);
            r8 lo1, lo2;
            r2 hi1 = {0, 0}, hi2 = {0, 0};
            memcpy(&lo1, z1 + LO, sizeof lo1);
            memcpy(&lo2, z2 + LO, sizeof lo2);
            if (hi_used) {
                memcpy(&hi1, z1, sizeof hi1);
                memcpy(&hi2, z2, sizeof hi2);
            }
            if (k == 0) {
                even_lo[0] = lo1, even_hi[0] = hi1;
                continue;
            }
            even_lo[k] = lo1 + lo2, odd_lo[k - 1] = lo1 - lo2;
            even_hi[k] = hi1 + hi2, odd_hi[k - 1] = hi1 - hi2;
        }
        const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l), *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
        const int base = l * (l + 1);
        r8 res[2 * SHL_LMAX_MAX + 1];
        r2 res_hi[2 * SHL_LMAX_MAX + 1];
        for (int m = -l; m <= l; ++m) {
            r8 lo = {0, 0, 0, 0, 0, 0, 0, 0};
            r2 hi = {0, 0};
            if (m >= 0)
                for (int k = 0; k <= l; ++k) {
                    const double w = we[m * (l + 1) + k];
                    lo += (r8){w, w, w, w, w, w, w, w} * even_lo[k];
                    if (hi_used) hi += (r2){w, w} * even_hi[k];
                }
            else
                for (int k = 0; k < l; ++k) {
                    const double w = wo[(-m - 1) * l + k];
                    lo += (r8){w, w, w, w, w, w, w, w} * odd_lo[k];
                    if (hi_used) hi += (r2){w, w} * odd_hi[k];
                }
            res[m + l] = lo, res_hi[m + l] = hi;
        }
        /* the 2l + 1 results of each block to its contiguous row (storing each value as it is
         * computed, gcc -O2 vectorizes the 10 stores into a scatter, 3x slower on AMD Zen) */
        for (int b = 0; b < nb; ++b) {
            const int j = SHL__ZH_MULTI - nb + b; /* record entry */
            double *o = out[b] + base - l;
            if (j < LO)
                for (int m = 0; m <= 2 * l; ++m) o[m] = res_hi[m][j];
            else
                for (int m = 0; m <= 2 * l; ++m) o[m] = res[m][j - LO];
        }
    }
}

void SHL_ISA_SUFFIX(shl__zh_to_sh_multi)(int lmax, const double *z10, double *const *out)
{
    zh_to_sh_vec(lmax, z10, SHL__ZH_MULTI, out);
}

void SHL_ISA_SUFFIX(shl__zh_to_sh_hess6)(int lmax, const double *z10, double *const *out)
{
    zh_to_sh_vec(lmax, z10, 6, out);
}
