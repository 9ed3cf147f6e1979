/* libFuzzer target: shl_polygon_f, shl_polygon_grad_f (float), against the
 * double path on the same (float) input.
 *
 * Input: lmax byte, flags byte, polygon (decoded as doubles, rounded to float),
 * point (rounded to float).
 * Properties:
 *  - status SHL_OK or the documented code; nothing written on error;
 *  - finite coefficients; finite gradient unless its bound K_l sum_e gamma_e/d_e
 *    exceeds FLT_MAX / 1e4 (then the true gradient need not be representable);
 *  - structured polygons (exactly planar and simple in float):
 *      |L_lm| <= K_l Omega + slack_f,  |L_00 - K_0 Omega| <= slack_f,
 *      |L_lm(float) - L_lm(double)| <= slack_f + slack_d,
 *      |dL/dx| <= K_l G (1 + 1e-4) + ...,  |grad_f - grad_d| <= K_l (2e-4 G + ...),
 *    slack_f = K_l (1e-4 Omega + 64 (l+1) eps_f P + 8 eps_d S G) + K_l 1e-36:
 *    1e-4 relative is 5x the float tolerance of test_polygon.c (2e-5 Omega for
 *    polygons over 0.05 rad); 64 (l+1) eps_f P bounds the float rounding of the
 *    boundary sums (P = angular perimeter; it is the 3e-5 / theta term of
 *    test_simd.c's model, which dominates for small polygons); the geometry is set
 *    up in double, so its conditioning term is the double one; 1e-36 covers float
 *    underflow (denormal results);
 *  - a point exactly in the plane gets exact zeros. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_polygon_f";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    (void)fz_u8(&in); /* flags: reserved */
    fz_poly P;
    fz_polygon_ex(&in, &P, 1);
    double xd[3];
    fz_point(&in, &P, xd);
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return 0;
    fz_dump_poly(&P);
    const shl_ctx *ctx = fz_ctx(lmax);
    const int nc = SHL_NCOEFFS(lmax), nv = P.nv;
    float vf[3 * (SHL_MAX_VERTS + 2)], xf[3];
    double vd[3 * (SHL_MAX_VERTS + 2)];
    for (int i = 0; i < 3 * nv; ++i) vd[i] = vf[i] = fz_to_float(P.v[i]);
    for (int k = 0; k < 3; ++k) xd[k] = xf[k] = fz_to_float(xd[k]);
    fz_dump_vec("x (float)", xd, 3);
    const int nbad = !(P.n >= 3 && P.n <= SHL_MAX_VERTS);
    const int nonfinite = !all_finite_f(xf, 3) || (!nbad && !all_finite_f(vf, 3 * P.n));
    const int want = nbad ? SHL_ENVERTS : nonfinite ? SHL_ENONFINITE : SHL_OK;

    float *c = fz_guarded(sizeof(float) * nc), *c2 = fz_guarded(sizeof(float) * nc);
    float *g = fz_guarded(sizeof(float) * 3 * nc);
    double *cd = fz_guarded(sizeof(double) * nc), *gd = fz_guarded(sizeof(double) * 3 * nc);
    const int st = shl_polygon_f(ctx, xf, vf, P.n, c);
    const int sg = shl_polygon_grad_f(ctx, xf, vf, P.n, c2, g);
    FUZZ_CHECK(st == want && sg == want, "status %d %d, want %d", st, sg, want);
    if (want != SHL_OK) {
        FUZZ_CHECK(fz_untouched(c, sizeof(float) * nc) && fz_untouched(c2, sizeof(float) * nc) &&
                       fz_untouched(g, sizeof(float) * 3 * nc),
                   "output written on error %d", want);
        goto done;
    }
    FUZZ_CHECK(all_finite_f(c, nc) && all_finite_f(c2, nc), "non-finite float coefficient, lmax %d", lmax);
    FUZZ_CHECK(shl_polygon_grad(ctx, xd, vd, P.n, cd, gd) == SHL_OK, "double path failed");

    fz_geom G;
    const int sane = P.structured && P.exact && fz_poly_geom(&P, xd, &G) && G.scale > 0.0L && G.rmax > 0.0L;
    if (!sane) goto done;
    const long double gbound = fz_kl(lmax) * G.gsum;
    if (gbound < FLT_MAX / 1e4) FUZZ_CHECK(all_finite_f(g, 3 * nc), "non-finite float gradient, bound %.3Lg", gbound);
    if (G.height == 0.0L) {
        for (int k = 0; k < nc; ++k) FUZZ_CHECK(c[k] == 0.0f && c2[k] == 0.0f, "in-plane coefficient %d = %a", k, c[k]);
        for (int k = 0; k < 3 * nc; ++k) FUZZ_CHECK(g[k] == 0.0f, "in-plane gradient %d = %a", k, g[k]);
        goto done;
    }
    const long double A = G.omega, epsd = DBL_EPSILON, epsf = FLT_EPSILON;
    const long double rnd = 8.0L * (epsd * G.scale + 0x1p-1074L);
    const long double cond = rnd * G.gsum, gcond = rnd * G.g2sum;
    const int may_be_plane = G.height <= 8.5L * epsd * G.rmax;
    if (fz_is_verbose())
        fprintf(stderr, "Omega_ref %.17Lg height %.3Lg rmax %.3Lg perim %.3Lg G %.3Lg cond %.3Lg\n", A, G.height,
                G.rmax, G.perim, G.gsum, cond);
    for (int l = 0; l <= lmax; ++l) {
        const long double kl = fz_kl(l);
        const long double sd = kl * (1e-9L * A + 300.0L * epsd * G.perim + cond) + 1e-300L;
        const long double sf = kl * (1e-4L * A + 64.0L * (l + 1) * epsf * G.perim + cond + 1e-36L);
        const long double gb = kl * G.gsum * (1.0L + 1e-4L) + kl * gcond + kl * 1e-36L;
        const long double gs = kl * (2e-4L * G.gsum + 64.0L * (l + 1) * epsf * G.gsum + 2.0L * gcond + 1e-36L);
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            FUZZ_CHECK(fabsl(c[k]) <= kl * A + sf, "|L[%d]| = %.9g > K_l Omega %.9Lg + slack %.3Lg", k, c[k], kl * A, sf);
            FUZZ_CHECK(fabsl((long double)c[k] - cd[k]) <= sf + sd, "L[%d] float %.9g vs double %.17g (slack %.3Lg)", k,
                       c[k], cd[k], sf + sd);
            FUZZ_CHECK(c2[k] == c[k] || fabsl((long double)c2[k] - c[k]) <= sf, "grad-call L[%d] %.9g vs %.9g", k, c2[k],
                       c[k]);
            for (int a = 0; a < 3; ++a) {
                const float ga = g[a * nc + k];
                if (!isfinite(ga)) continue; /* overflow allowed above FLT_MAX / 1e4 (checked above) */
                FUZZ_CHECK(fabsl(ga) <= gb, "|dL[%d]/dx%d| = %.9g > bound %.9Lg", k, a, ga, gb);
                FUZZ_CHECK(fabsl((long double)ga - gd[a * nc + k]) <= gs, "dL[%d]/dx%d float %.9g vs double %.17g (slack %.3Lg)",
                           k, a, ga, gd[a * nc + k], gs);
            }
        }
    }
    if (!(may_be_plane && c[0] == 0.0f)) {
        const long double s0 = fz_kl(0) * (1e-4L * A + 64.0L * epsf * G.perim + cond + 1e-36L);
        FUZZ_CHECK(fabsl(c[0] - fz_kl(0) * A) <= s0, "L00 %.9g vs K0 Omega %.17Lg (slack %.3Lg)", c[0], fz_kl(0) * A, s0);
    }
done:
    free(c);
    free(c2);
    free(g);
    free(cd);
    free(gd);
    return 0;
}
