/* Single-call polygon Hessians (shl_polygon_hess) vectorized ACROSS LOBES, as
 * simd/poly_zh_batch.h does for coefficients and gradients: the recurrence of the
 * scalar reference shl__poly_zh_hess_d (src/polygon_hess.c, derivation (H1)-(H6)
 * there) for ZW lobes side by side in one vector, ZW = the ISA's double width
 * SHL_VDLEN (8 on AVX-512, 4 on AVX2), at least 2.  Generic vector types, no fused
 * multiply-add (gcc's C11 mode and the clang pragma of dvec.h): each lane does exactly
 * the reference's one-lobe arithmetic, so every ISA gives the reference's bits
 * (tests/test_hessian.c, hess_isa_kernels_match_reference).  The contraction
 * of (H2) is done inside the band loop instead of after it (the same sums, edges in
 * the same order).  A partial last block repeats its last lobe, at full width: run on 2- or
 * 4-lane vectors (as poly_zh_batch.h's coefficient blocks) or with two edges side by side,
 * this kernel measured slower on AVX-512 (AMD EPYC, 2026-12-02): a block costs its
 * instructions and spills per edge and band, about the same at any width.  The ZH -> SH
 * reconstruction (Wang 2018 Eq. 33) of the ten blocks (shl__zh_to_sh_multi) follows in
 * the same call, vectorized across orders m: the same sums in the same order as shl__zh_to_sh. */
#include "../src/polygon_hess.h"
#include "kernel_api.h"
#include <string.h>
#include "dvec.h" /* also: no FMA contraction, every ISA rounds as the scalar one */

#define ZW SHL_DVEC_WIDTH
#define HV_CAT2(a, b) a##b
#define HV_CAT(a, b) HV_CAT2(a, b)
#define hv HV_CAT(dv, ZW) /* simd/dvec.h */
#define hv_set1 HV_CAT(hv, _set1)

/* u . p per lane: (u0 p0 + u1 p1) + u2 p2, the order of shl__dot3 */
static inline hv hv_dot(const hv u[3], const double p[3]) { return HV_CAT(hv, _dot)(u[0], u[1], u[2], p); }

/* A band's sums over the edges: Hessian (H2), gradient (Wu Eq. 11), Wang's B_l (Eq. 30).
 * The first edge starts them from zero in registers (zeroing them in memory first, gcc
 * emitted a rep stos per band, ~30 cycles to start on AMD Zen 3: 20% of the call). */
typedef struct {
    hv hs[6], gs[3], bs;
} band_sums;

/* The sum so far: zero at the first edge (0 + x, as the reference's sums from 0). */
static inline hv sum_so_far(int first, hv s) { return first ? hv_set1(0.0) : s; }

/* The per-edge, per-band terms of (H2) and Wu's gradient (Eq. 11) added to the band's sums
 * (first: the first edge): il = I_l of (H2), sm = c M_l, p = P_l(a_e), dp = dP_l, ig = I_l of
 * the gradient. */
__attribute__((always_inline)) static inline void hess_add(const shl__hess_edge *h, const double mu[3], hv il, hv sm,
                                                            hv p, hv dp, hv ig, band_sums *sb, int first)
{
    hv *hs = sb->hs, *gs = sb->gs;
    hv r[3]; /* (H2) with (H6) */
#pragma GCC unroll 3
    for (int ax = 0; ax < 3; ++ax)
        r[ax] = il * hv_set1(h->tg[ax]) - p * hv_set1(h->bp[ax]) - dp * hv_set1(h->bd[ax]) - sm * hv_set1(mu[ax]);
    /* (H2) as S(mu, r): xx xy xz yy yz zz, off the diagonal 2 S (halved with hnorm, as the reference) */
    const hv m0 = hv_set1(mu[0]), m1 = hv_set1(mu[1]), m2 = hv_set1(mu[2]);
    hs[0] = sum_so_far(first, hs[0]) + m0 * r[0], hs[1] = sum_so_far(first, hs[1]) + (m0 * r[1] + m1 * r[0]);
    hs[2] = sum_so_far(first, hs[2]) + (m0 * r[2] + m2 * r[0]), hs[3] = sum_so_far(first, hs[3]) + m1 * r[1];
    hs[4] = sum_so_far(first, hs[4]) + (m1 * r[2] + m2 * r[1]), hs[5] = sum_so_far(first, hs[5]) + m2 * r[2];
#pragma GCC unroll 3
    for (int ax = 0; ax < 3; ++ax) gs[ax] = sum_so_far(first, gs[ax]) + hv_set1(mu[ax]) * ig;
}

/* Lobe order of the kernel's lanes ("lane order"): position p holds lobe 0 (p = 0), 2p - 1
 * (1 <= p <= lmax) or 2 (p - lmax) (p > lmax), so that the pairs (2k - 1, 2k) of Eq. 33 are
 * rows k and lmax + k: their sums and differences are vector operations. */

enum { NB = SHL__ZH_MULTI, FW = SHL_LMAX_MAX + 1 + ZW }; /* blocks; row length of zh_to_sh_rows' ev, od */

/* Orders c .. c + W - 1 of one part of a band (zh_to_sh_rows) for the ten blocks into
 * out[b] + at + c: W-lane vectors of type T, each weight vector loaded once for ten
 * independent sums, per lane the sums of shl__zh_to_sh in its order (a lane's value does
 * not depend on the chunk's start c).  Whole vectors stored straight from the registers;
 * lanes past the part land on coefficients written later (bands in order, the odd part
 * first), so the caller keeps at + c + W <= nc (part_rows). */
#define DEF_CHUNK(name, T)                                                                                             \
    __attribute__((always_inline)) static inline void name(const double *w, int pad, int len, int c,                \
                                                           const double (*f)[FW], double *const *out, int at)         \
    {                                                                                                                  \
        T acc[NB];                                                                                                     \
        _Pragma("GCC unroll 10") for (int b = 0; b < NB; ++b) acc[b] = (T){0};                                         \
        for (int k = 0; k < len; ++k) {                                                                                \
            T wk;                                                                                                      \
            memcpy(&wk, w + k * pad + c, sizeof wk);                                                                   \
            _Pragma("GCC unroll 10") for (int b = 0; b < NB; ++b) acc[b] += wk * f[b][k];                              \
        }                                                                                                              \
        _Pragma("GCC unroll 10") for (int b = 0; b < NB; ++b) memcpy(out[b] + at + c, &acc[b], sizeof acc[b]);         \
    }
DEF_CHUNK(chunk_full, hv)
#if ZW >= 4
/* Half-width vectors for a part's last 1 .. ZW/2 orders: half the zero-padded lanes */
typedef double hv_half __attribute__((vector_size(ZW / 2 * sizeof(double))));
DEF_CHUNK(chunk_half, hv_half)
#define HW (ZW / 2)
#else
#define chunk_half chunk_full
#define HW ZW
#endif

/* One part (len orders, weight rows pad apart) of a band into out[b] + at, lim = nc - at
 * values available from there: chunks of ZW orders, the last 1 .. HW ones at half width.  A
 * chunk that would run past nc starts earlier instead (lanes of the chunk before it
 * recomputed: the same bits), or, if no vector fits (lmax < HW), its lanes are summed one
 * by one (the same sums in the same order). */
static inline void part_rows(const double *w, int pad, int len, const double (*f)[FW], double *const *out, int at, int lim)
{
    for (int c = 0; c < len;) {
        const int full = len - c > HW, wd = full ? ZW : HW, st = c + wd <= lim ? c : lim - wd;
        if (st < 0)
            for (int b = 0; b < NB; ++b)
                for (int q = c; q < len; ++q) {
                    double acc = 0.0;
                    for (int k = 0; k < len; ++k) acc += w[k * pad + q] * f[b][k];
                    out[b][at + q] = acc;
                }
        else if (full)
            chunk_full(w, pad, len, st, f, out, at);
        else
            chunk_half(w, pad, len, st, f, out, at);
        c += wd;
    }
}

/* The reconstruction (Wang 2018 Eq. 33) of the ten blocks b from their lobe rows
 * z[(b (lmax + 1) + l) dp + p] (layout of shl__poly_hess below) into out[b] (nc values each),
 * vectorized across orders m with the transposed weights, the blocks side by side. */
static void zh_to_sh_rows(int lmax, const double *z, int dp, double *const *out)
{
    const int nc = (lmax + 1) * (lmax + 1);
    const shl__zh_wt_table *wt = shl__zh_wt();
    for (int l = 0; l <= lmax; ++l) {
        double ev[NB][FW], od[NB][FW]; /* chunks of ZW may run past l */
        for (int b = 0; b < NB; ++b) {
            const double *zl = z + (b * (lmax + 1) + l) * dp;
            ev[b][0] = zl[0];
            for (int j = 0; j < l; j += ZW) { /* k = j + 1 .. : lobes 2k - 1 (row k) and 2k (row lmax + k) */
                hv z1, z2;
                memcpy(&z1, zl + 1 + j, sizeof z1);
                memcpy(&z2, zl + lmax + 1 + j, sizeof z2);
                const hv e = z1 + z2, o = z1 - z2;
                memcpy(&ev[b][1 + j], &e, sizeof e);
                memcpy(&od[b][j], &o, sizeof o);
            }
        }
        /* coefficients l(l+1) - l .. l(l+1) + l: odd part (m = l .. 1), then even (m = 0 .. l) */
        for (int part = 0; part < 2; ++part) {
            const int len = part ? l + 1 : l, pad = SHL__WT_PAD(len), at = l * l + (part ? l : 0);
            const double *w = part ? wt->even + wt->even_ofs[l] : wt->odd + wt->odd_ofs[l];
            const double(*f)[FW] = (const double(*)[FW])(part ? ev : od);
            part_rows(w, pad, len, f, out, at, nc - at);
        }
    }
}

void SHL_ISA_SUFFIX(shl__poly_hess)(const struct shl__poly_geom *g, int lmax, int unscaled, double *const *out)
{
    const int n = g->n, ndir = 2 * lmax + 1, dp = (ndir + ZW - 1) / ZW * ZW;
    /* z[(b (lmax + 1) + l) dp + p]: block b (value, gradient, Hessian as the blocks of z10, polygon.h)
     * of the lobe at lane position p, band l; positions ndir .. dp - 1 repeat the last one */
    double z[SHL__ZH_MULTI * (SHL_LMAX_MAX + 1) * SHL__WT_PAD(2 * SHL_LMAX_MAX + 1) + ZW];
    for (int k = 0; k < ZW; ++k) z[SHL__ZH_MULTI * (lmax + 1) * dp + k] = 0.0; /* read past the last row (zh_to_sh_rows) */
    const double sc = g->grad_scale[0] * g->grad_scale[1];
    /* band constants tabulated once (shl__zh_bands: the reference's expressions, so its bits) */
    const shl__zh_band_consts *bc = shl__zh_bands();
    const double *norm = bc->norm, *s_b = bc->s_b, *s_s = bc->s_s;
    double gnorm[SHL_LMAX_MAX + 1], hnorm[SHL_LMAX_MAX + 1], hhalf[SHL_LMAX_MAX + 1], inv_l[SHL_LMAX_MAX + 3];
    for (int l = 0; l <= lmax; ++l) {
        gnorm[l] = unscaled ? norm[l] * sc : norm[l];
        hnorm[l] = unscaled ? norm[l] * sc * sc : norm[l];
        hhalf[l] = 0.5 * hnorm[l]; /* off-diagonal sums of 2 S (hess_add) */
        inv_l[l] = bc->inv_l[l];
    }
    inv_l[lmax + 1] = 1.0 / (lmax + 1), inv_l[lmax + 2] = 1.0 / (lmax + 2); /* past the table at SHL_LMAX_MAX */
    shl__hess_edge he[SHL_MAX_VERTS];
    /* the lobes' components in lane order, gathered before the blocks (a vector loaded right
     * after its scalar stores would wait for them: no store forwarding) */
    double t[3][SHL__WT_PAD(2 * SHL_LMAX_MAX + 1)];
    for (int c = 0; c < 3; ++c) { /* lane order, one loop per kind of lane (no branch per lane) */
        t[c][0] = shl__zh_dir[0][c];
        for (int k = 1; k <= lmax; ++k) t[c][k] = shl__zh_dir[2 * k - 1][c], t[c][lmax + k] = shl__zh_dir[2 * k][c];
        for (int p = ndir; p < dp; ++p) t[c][p] = t[c][ndir - 1];
    }
    shl__hess_edges_init(g, he);
    for (int d0 = 0; d0 < ndir; d0 += ZW) {
        hv u[3];
        for (int c = 0; c < 3; ++c) memcpy(&u[c], t[c] + d0, sizeof u[c]);
        band_sums sum[SHL_LMAX_MAX + 1];
        hv surf[SHL_LMAX_MAX + 1];
        if (n == 0) memset(sum, 0, (lmax + 1) * sizeof sum[0]); /* no edges: the sums are zero */
        for (int e = 0; e < n; ++e) {
            const int f = (e + 1 == n) ? 0 : e + 1, first = e == 0;
            const shl__hess_edge *h = &he[e];
            const double *mu = g->mu[e];
            const hv gamma = hv_set1(g->gamma[e]), i0 = hv_set1(g->f_integral[e]), fp1 = hv_set1(g->fprime1[e]);
            const hv a = hv_dot(u, g->w[e]), b = hv_dot(u, g->lam[e]), c = hv_dot(u, mu), c2 = c * c;
            const hv af = hv_dot(u, g->w[f]), da = hv_dot(u, g->dw[e]), v = hv_dot(u, g->gvec[e]);
            const hv s = a * hv_set1(g->sin_gamma[e]) - b * hv_set1(g->cos_gamma[e]);
            const hv b1 = a * hv_set1(g->sin_gamma[e]) + b * hv_set1(g->omc_gamma[e]); /* B_1, Wang Eq. 27 */
            const hv e0 = hv_set1(h->e0), g2 = hv_set1(h->g2), ffp1 = hv_set1(h->ffp1), ffd = hv_set1(h->ffd);
            /* edges seen end-on: E_l, I_l of (H2) by the Gauss rule, and c M_l (H4) from them
             * (qi, qm: I_l and c M_l of (H2), else from the recurrence below) */
            const int quad = h->quad;
            hv qe[SHL_LMAX_MAX + 1], qi[SHL_LMAX_MAX + 1], qm[SHL_LMAX_MAX + 1];
            qm[1] = hv_set1(0.0); /* set by the rule at lmax >= 1 (read only then); gcc cannot see it */
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
                if (lmax >= 1) qm[1] = c * qe[0];
                for (int l = 2; l <= lmax; ++l) {
                    const hv ml = hv_set1(2.0 * l - 1.0) * qe[l - 1] + mm2;
                    mm2 = mm1, mm1 = ml;
                    qm[l] = c * ml;
                }
            }
            hv p1 = a, p2 = hv_set1(1.0), dp1 = da, dp2 = hv_set1(0.0);
            hv bb1 = b1, bb2 = gamma, d1 = gamma, d2 = hv_set1(0.0);
            sum[0].bs = sum_so_far(first, sum[0].bs) + c * gamma;
            if (lmax >= 2) sum[1].bs = sum_so_far(first, sum[1].bs) + c * b1;
            /* l = 0 and 1 of Wu's I, J and of (H3)-(H4) */
            hv i1 = (v * gamma - (fp1 * da - i0 * a)) / hv_set1(2.0);
            hv j1 = i0, j2 = hv_set1(0.0), m2 = hv_set1(0.0), m1 = e0; /* M_0, M_1 = E_0 */
            hv e1 = (v * i0 - ffp1 * da - ffd * a + g2 * b1) / hv_set1(3.0); /* E_1 */
            /* I_l and c M_l of (H2): the rule's (quad) or the recurrence's (selected, not stored:
             * a vector stored and loaded back costs a store-to-load round trip per band) */
            hess_add(h, mu, quad ? qi[0] : i0, quad ? qm[0] : hv_set1(0.0), hv_set1(1.0), hv_set1(0.0), i0, &sum[0], first);
            if (lmax >= 1) hess_add(h, mu, quad ? qi[1] : i1, quad ? qm[1] : c * e0, a, da, i1, &sum[1], first);
            for (int l = 2; l <= lmax; ++l) {
                const hv pa = hv_set1(bc->leg_a[l]), pb = hv_set1(bc->leg_b[l]), tlm1 = hv_set1(bc->twol_m1[l]);
                const hv pl = pa * a * p1 - pb * p2;                                                /* Wang Eq. 11 */
                const hv dl = tlm1 * bb1 + d2;                                                      /* Wang Eq. 32 */
                const hv dpl = pa * (af * dp1 + da * p1) - pb * dp2;
                const hv il = (v * dl - j1 - (fp1 * dpl - i0 * pl)) * hv_set1(inv_l[l + 1]);      /* Wu I_l */
                const hv jl = tlm1 * i1 + j2;
                /* Eq. 30 with Eq. 31's C_{l-1} = (X + (l-1) B_{l-2}) / l: B_l = alpha X + beta B_{l-2} */
                const hv bl = hv_set1(bc->b_alpha[l]) * (b1 * p1 + s * dp1 - c2 * d1) + hv_set1(bc->b_beta[l]) * bb2;
                const hv ml = tlm1 * e1 + m2;                                                       /* (H4) */
                const hv el = (v * jl - m1 - ffp1 * dpl - ffd * pl + g2 * bl) * hv_set1(inv_l[l + 2]); /* (H3) */
                sum[l].bs = sum_so_far(first, sum[l].bs) + c * bl;
                hess_add(h, mu, quad ? qi[l] : il, quad ? qm[l] : c * ml, pl, dpl, il, &sum[l], first);
                p2 = p1, p1 = pl, dp2 = dp1, dp1 = dpl;
                bb2 = bb1, bb1 = bl, d2 = d1, d1 = dl;
                j2 = j1, j1 = jl, i1 = il;
                m2 = m1, m1 = ml, e1 = el;
            }
        }
        surf[0] = hv_set1(g->solid_angle);                 /* S_0 */
        if (lmax >= 1) surf[1] = sum[0].bs / hv_set1(2.0); /* S_1, Wang Eq. 25 */
        for (int l = 2; l <= lmax; ++l) surf[l] = hv_set1(s_b[l]) * sum[l - 1].bs + hv_set1(s_s[l]) * surf[l - 2]; /* Eq. 29 */
        /* each product stored straight from its register (through an array of them, gcc copied
         * it in 16-byte halves: the upper half waits, no store forwarding, 7% of the call) */
        for (int l = 0; l <= lmax; ++l) {
            double *zl = z + l * dp + d0; /* block b at zl + b (lmax + 1) dp */
            const hv o = hv_set1(norm[l]) * surf[l]; /* Wang Eq. 13 */
            memcpy(zl, &o, sizeof o);
#pragma GCC unroll 3
            for (int ax = 0; ax < 3; ++ax) {
                const hv go = hv_set1(gnorm[l]) * sum[l].gs[ax];
                memcpy(zl + (1 + ax) * (lmax + 1) * dp, &go, sizeof go);
            }
#pragma GCC unroll 6
            for (int i = 0; i < 6; ++i) {
                const hv ho = hv_set1(i == 1 || i == 2 || i == 4 ? hhalf[l] : hnorm[l]) * sum[l].hs[i]; /* (H2) */
                memcpy(zl + (4 + i) * (lmax + 1) * dp, &ho, sizeof ho);
            }
        }
    }
    if (g->sliver && lmax <= SHL__AREA_LMAX) { /* coefficients as shl__poly_zh_grad_d */
        double area[SHL__ZH_BLOCK];
        shl__poly_zh_area(g, lmax, area);
        for (int dir = 0; dir < ndir; ++dir)
            for (int l = 0; l <= lmax; ++l) z[l * dp + (dir & 1 ? (dir + 1) / 2 : dir ? lmax + dir / 2 : 0)] = area[dir * SHL__ZH_STRIDE + l];
    }
    zh_to_sh_rows(lmax, z, dp, out);
}
