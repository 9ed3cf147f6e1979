/* libFuzzer target: shl_polygon, shl_polygon_grad, shl_polygon_solid_angle (double).
 *
 * Input: lmax byte, flags byte, polygon (fuzz_common.h), point.
 * Properties:
 *  - no crash, no sanitizer report; status is SHL_OK or the documented code for
 *    the input (NULL pointer, lmax, vertex count, non-finite coordinate);
 *  - on error nothing is written (guard-filled buffers byte-identical);
 *  - on success every output is finite (a gradient: when its bound below is
 *    under 1e290; for raw, possibly non-planar polygons the same bound from the
 *    vertices, fz_raw_grad_bound);
 *  - for structured (exactly planar, simple) polygons with moderate coordinates:
 *      |L_lm| <= K_l Omega + slack           (K_l = sqrt((2l+1)/(4 pi)) >= |Y_lm|)
 *      |L_00 - K_0 Omega| <= slack, |omega_lib - Omega| <= slack / K_0
 *      |dL_lm/dx_a| <= K_l sum_e gamma_e / d_e + slack'   (moving-boundary bound;
 *                         +-inf where it exceeds DBL_MAX: the gradient overflows)
 *    with Omega the independent long-double solid angle (fz_poly_geom) and
 *      slack = K_l (1e-9 Omega + 300 eps P + 8 eps S G) + 1e-300:
 *    1e-9 relative is 10x the worst error/Omega measured against quadrature at
 *    lmax 30 (test_polygon.c, tol 1e-10); 300 eps P (P = angular perimeter) is
 *    the rounding of the boundary sums, which are O(gamma_e) per edge;
 *    8 eps S G is the conditioning term of test_polygon.c's hard cases (a move
 *    of 4 ulps of the largest coordinate S changes L_lm by at most
 *    4 eps S K_l G, G = sum_e gamma_e / d_e bounding |grad L| / K_l);
 *  - a point exactly in the plane gets exact zeros (coefficients, gradient, omega);
 *  - repeated vertices do not change the result (bit-identical);
 *  - shl_polygon_grad's coefficients agree with shl_polygon's within the slack. */
#include "fuzz_common.h"

static void check_polygon(const fz_poly *P, const double x[3], int lmax, const shl_ctx *ctx)
{
    const int nc = SHL_NCOEFFS(lmax);
    fz_dump_poly(P);
    fz_dump_vec("x", x, 3);
    double *c = fz_guarded(sizeof(double) * nc), *c2 = fz_guarded(sizeof(double) * nc);
    double *g = fz_guarded(sizeof(double) * 3 * nc), *omega = fz_guarded(sizeof(double));
    const int nbad = !(P->n >= 3 && P->n <= SHL_MAX_VERTS);
    const int nonfinite = !all_finite_d(x, 3) || (!nbad && !all_finite_d(P->v, 3 * P->n));
    const int want = nbad ? SHL_ENVERTS : nonfinite ? SHL_ENONFINITE : SHL_OK;

    const int st = shl_polygon(ctx, x, P->v, P->n, c);
    const int sg = shl_polygon_grad(ctx, x, P->v, P->n, c2, g);
    const int so = shl_polygon_solid_angle(x, P->v, P->n, omega);
    FUZZ_CHECK(st == want && sg == want && so == want, "status %d %d %d, want %d", st, sg, so, want);
    if (want != SHL_OK) {
        FUZZ_CHECK(fz_untouched(c, sizeof(double) * nc) && fz_untouched(c2, sizeof(double) * nc) &&
                       fz_untouched(g, sizeof(double) * 3 * nc) && fz_untouched(omega, sizeof(double)),
                   "output written on error %d", want);
        goto done;
    }
    FUZZ_CHECK(all_finite_d(c, nc), "non-finite coefficient, lmax %d", lmax);
    FUZZ_CHECK(all_finite_d(c2, nc), "non-finite coefficient (grad call), lmax %d", lmax);
    FUZZ_CHECK(isfinite(*omega) && *omega >= 0.0, "omega %g", *omega);

    /* repeated vertices are dropped: bit-identical to the polygon without them */
    if (P->has_dups && P->n_nodup >= 3) {
        double *d = fz_guarded(sizeof(double) * nc);
        FUZZ_CHECK(shl_polygon(ctx, x, P->v_nodup, P->n_nodup, d) == SHL_OK, "no-dup call failed");
        FUZZ_CHECK(memcmp(c, d, sizeof(double) * nc) == 0, "repeated vertices change the result");
        free(d);
    }

    fz_geom G;
    const int sane = P->structured && P->exact && fz_poly_geom(P, x, &G) && G.scale > 0.0L;
    /* the gradient is finite whenever 1/distance is representable with room to spare: for
     * any polygon (raw ones may be non-planar: the bound from their vertices) */
    const long double gsum = sane ? G.gsum : fz_raw_grad_bound(P->v, P->n, x);
    const double gmax_bound = (double)(fz_kl(lmax) * gsum);
    if (gmax_bound < 1e290)
        FUZZ_CHECK(all_finite_d(g, 3 * nc), "non-finite gradient, lmax %d, bound %g", lmax, gmax_bound);
    if (!sane) goto done;

    const long double eps = DBL_EPSILON, A = G.omega;
    const long double rnd = 8.0L * (eps * G.scale + 0x1p-1074L); /* 4 ulps of every input, denormals included */
    const long double cond = rnd * G.gsum, gcond = rnd * G.g2sum;
    const long double plane_tol = 8.5L * eps * G.rmax; /* the library's plane test, with margin */
    if (G.height == 0.0L) { /* exactly in the plane: exact zeros */
        for (int k = 0; k < nc; ++k) FUZZ_CHECK(c[k] == 0.0 && c2[k] == 0.0, "in-plane coefficient %d = %a", k, c[k]);
        for (int k = 0; k < 3 * nc; ++k) FUZZ_CHECK(g[k] == 0.0, "in-plane gradient %d = %a", k, g[k]);
        FUZZ_CHECK(*omega == 0.0, "in-plane omega %a", *omega);
        goto done;
    }
    const int may_be_plane = G.height <= plane_tol;
    if (fz_is_verbose()) fprintf(stderr, "Omega_ref %.17Lg height %.3Lg rmax %.3Lg perim %.3Lg G %.3Lg cond %.3Lg\n", A, G.height, G.rmax, G.perim, G.gsum, cond);
    for (int l = 0; l <= lmax; ++l) {
        const long double kl = fz_kl(l);
        const long double slack = kl * (1e-9L * A + 300.0L * eps * G.perim + cond) + 1e-300L;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            FUZZ_CHECK(fabsl(c[k]) <= kl * A + slack, "|L[%d]| = %.17g > K_l Omega %.17Lg + slack %.3Lg (l %d)", k,
                       c[k], kl * A, slack, l);
            FUZZ_CHECK(fabsl(c2[k] - c[k]) <= 2.0L * slack, "grad-call coefficient %d differs: %.17g vs %.17g", k,
                       c2[k], c[k]);
            for (int a = 0; a < 3; ++a) {
                const long double gb = kl * G.gsum * (1.0L + 1e-6L) + kl * gcond + 1e-300L;
                if (isinf(g[a * nc + k]) && gb >= DBL_MAX) continue; /* the true gradient may overflow */
                FUZZ_CHECK(fabsl(g[a * nc + k]) <= gb, "|dL[%d]/dx%d| = %.17g > bound %.17Lg", k, a, g[a * nc + k],
                           gb);
            }
        }
    }
    const long double s0 = 1e-9L * A + 300.0L * eps * G.perim + cond + 1e-300L;
    FUZZ_CHECK(*omega <= 2.0L * M_PI + s0, "omega %.17g above a hemisphere (planar polygon; slack %.3Lg)", *omega, s0);
    if (!(may_be_plane && *omega == 0.0)) {
        FUZZ_CHECK(fabsl(*omega - A) <= s0, "omega %.17g vs reference %.17Lg (slack %.3Lg, height %.3Lg)", *omega, A,
                   s0, G.height);
        FUZZ_CHECK(fabsl(c[0] - fz_kl(0) * A) <= fz_kl(0) * s0, "L00 %.17g vs K0 Omega %.17Lg (slack %.3Lg)", c[0],
                   fz_kl(0) * A, fz_kl(0) * s0);
    } else {
        for (int k = 0; k < nc; ++k) FUZZ_CHECK(c[k] == 0.0, "near-plane: omega 0 but L[%d] = %a", k, c[k]);
    }
done:
    free(c);
    free(c2);
    free(g);
    free(omega);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_polygon";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    const uint8_t flags = fz_u8(&in);
    fz_poly P;
    fz_polygon(&in, &P);
    double x[3];
    fz_point(&in, &P, x);
    if (lmax < 0 || lmax > SHL_LMAX_MAX) {
        shl_ctx *ctx = (shl_ctx *)&in; /* any non-NULL value: set to NULL on failure */
        FUZZ_CHECK(shl_ctx_create(lmax, &ctx) == SHL_ELMAX && ctx == NULL, "lmax %d accepted or *out not NULL", lmax);
        return 0;
    }
    const shl_ctx *ctx = fz_ctx(lmax);
    if (flags & 1) { /* NULL arguments: SHL_ENULL, nothing written */
        double c[4] = {0}, g[12] = {0};
        const int which = (flags >> 1) & 3;
        const double *xx = which == 0 ? NULL : x, *vv = which == 1 ? NULL : P.v;
        double *cc = which == 2 ? NULL : (lmax == 0 ? c : NULL);
        const shl_ctx *cx = which == 3 ? NULL : ctx;
        if (cc == NULL || xx == NULL || vv == NULL || cx == NULL) {
            FUZZ_CHECK(shl_polygon(cx, xx, vv, P.n, cc) == SHL_ENULL, "NULL not rejected");
            FUZZ_CHECK(shl_polygon_grad(cx, xx, vv, P.n, cc, g) == SHL_ENULL, "NULL not rejected (grad)");
            FUZZ_CHECK(shl_polygon_grad(ctx, x, P.v, P.n, c, NULL) == SHL_ENULL, "NULL grad not rejected");
        }
        return 0;
    }
    check_polygon(&P, x, lmax, ctx);
    return 0;
}
