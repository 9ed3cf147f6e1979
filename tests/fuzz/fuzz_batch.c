/* libFuzzer target: shl_polygon_batch_f (SIMD batches), every ISA this machine
 * runs (contexts of shl_ctx_create_isa("scalar") and of the default ISA).
 *
 * Input: lmax byte, flags byte (bit 0: gradients, bit 1: a NaN point, bit 2:
 * scalar ISA, bit 3: allocation failure, bits 4-7: NULL / bad npts), polygon
 * (float), npts byte, points (float).
 * Properties:
 *  - status SHL_OK or the documented code (NULL, vertex count, npts < 0,
 *    non-finite vertex or point, SHL_ENOMEM under an injected allocation
 *    failure); nothing written on error (all points are checked first);
 *  - finite outputs (gradients: unless their bound exceeds FLT_MAX / 1e4);
 *  - lane independence: point p's results equal, bit for bit, a batch of p alone;
 *    coefficients identical with and without gradients (test_simd.c);
 *  - structured polygons, each point, against shl_polygon_grad (double) on the
 *    same float input:
 *      |L_lm - L_lm(double)| <= K_l (1e-4 Omega + 64 (l+1) eps_f P + 8 eps_f S G) + ...,
 *    i.e. fuzz_polygon_f's float slack with the conditioning term in float (the
 *    batch sets up its geometry in float; test_simd.c's hard-case term), and the
 *    gradient within K_l (2e-4 G + 64 (l+1) eps_f G + 8 eps_f S G2);
 *    a point farther than 2^40 extents from every vertex may get zeros (documented);
 *  - a point the float geometry cannot resolve (height below 2^-16 of its distance
 *    to the farthest vertex, or within 2^-16 extents of a vertex) gets the results
 *    of shl_polygon_grad_f bit for bit (documented). */
#include "fuzz_common.h"

enum { MAXPTS = 17 };
static shl_ctx *ctx_isa[2][SHL_LMAX_MAX + 1];

static const shl_ctx *batch_ctx(int scalar, int lmax)
{
    if (!ctx_isa[scalar][lmax]) {
        const int st = scalar ? shl_ctx_create_isa(lmax, "scalar", &ctx_isa[scalar][lmax])
                              : shl_ctx_create(lmax, &ctx_isa[scalar][lmax]);
        if (st != SHL_OK) abort();
    }
    return ctx_isa[scalar][lmax];
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_batch";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    const uint8_t flags = fz_u8(&in);
    fz_poly P;
    fz_polygon_ex(&in, &P, 1);
    int npts = fz_u8(&in) % (MAXPTS + 1);
    double xd[MAXPTS][3];
    float pts[3 * MAXPTS + 3], vf[3 * (SHL_MAX_VERTS + 2)];
    for (int p = 0; p < npts; ++p) {
        fz_point(&in, &P, xd[p]);
        for (int k = 0; k < 3; ++k) xd[p][k] = pts[3 * p + k] = fz_to_float(xd[p][k]);
    }
    const int bad_pt = npts > 0 && (flags & 2) ? fz_u8(&in) % npts : -1;
    if (bad_pt >= 0) pts[3 * bad_pt + fz_u8(&in) % 3] = (fz_u8(&in) & 1) ? NAN : INFINITY;
    const long fail_after = (flags & 8) ? fz_u8(&in) % 4 : -1;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return 0;
    const shl_ctx *ctx = batch_ctx((flags >> 2) & 1, lmax);
    const int nc = SHL_NCOEFFS(lmax), with_grad = flags & 1, nv = P.nv;
    for (int i = 0; i < 3 * nv; ++i) vf[i] = (float)P.v[i];
    fz_dump_poly(&P);

    /* NULL pointers and a negative count */
    const int special = (flags >> 4) & 7;
    if (special == 1) npts = -1 - fz_u8(&in);
    const float *vv = special == 2 ? NULL : vf, *pp = special == 3 ? NULL : pts;
    const int null_out = special == 4;

    const size_t cbytes = sizeof(float) * (size_t)nc * (npts > 0 ? npts : 1), gbytes = 3 * cbytes;
    float *c = fz_guarded(cbytes), *g = fz_guarded(gbytes);
    const int nbad = !(P.n >= 3 && P.n <= SHL_MAX_VERTS);
    int nonfinite = !nbad && vv && !all_finite_f(vf, 3 * P.n);
    for (int p = 0; p < npts && pp; ++p) nonfinite |= !all_finite_f(pts + 3 * p, 3);
    int want = SHL_OK;
    if (!vv || (npts > 0 && (!pp || null_out))) want = SHL_ENULL;
    else if (nbad) want = SHL_ENVERTS;
    else if (npts < 0) want = SHL_EDOMAIN;
    else if (nonfinite) want = SHL_ENONFINITE;

    shl__alloc_fail_after = fail_after;
    const int st = shl_polygon_batch_f(ctx, vv, P.n, npts, pp, null_out ? NULL : c, with_grad ? g : NULL);
    shl__alloc_fail_after = -1;
    const int injected = fail_after >= 0 && st == SHL_ENOMEM && want == SHL_OK;
    FUZZ_CHECK(st == want || injected, "status %d, want %d (npts %d, n %d)", st, want, npts, P.n);
    if (st != SHL_OK) {
        FUZZ_CHECK(fz_untouched(c, cbytes) && fz_untouched(g, gbytes), "output written on error %d", st);
        goto done;
    }
    if (npts <= 0) {
        FUZZ_CHECK(fz_untouched(c, cbytes) && fz_untouched(g, gbytes), "output written for npts = 0");
        goto done;
    }
    FUZZ_CHECK(all_finite_f(c, nc * npts), "non-finite batch coefficient");
    { /* lane independence and coefficients independent of the gradient request */
        const int p = fz_u8(&in) % npts;
        float *c1 = fz_guarded(sizeof(float) * nc), *g1 = fz_guarded(sizeof(float) * 3 * nc);
        FUZZ_CHECK(shl_polygon_batch_f(ctx, vf, P.n, 1, pts + 3 * p, c1, with_grad ? g1 : NULL) == SHL_OK, "single");
        FUZZ_CHECK(memcmp(c1, c + (size_t)nc * p, sizeof(float) * nc) == 0, "point %d differs alone vs in a batch of %d", p,
                   npts);
        if (with_grad)
            FUZZ_CHECK(memcmp(g1, g + (size_t)3 * nc * p, sizeof(float) * 3 * nc) == 0,
                       "gradient of point %d differs alone vs in a batch of %d", p, npts);
        FUZZ_CHECK(shl_polygon_batch_f(ctx, vf, P.n, 1, pts + 3 * p, c1, with_grad ? NULL : g1) == SHL_OK, "single 2");
        FUZZ_CHECK(memcmp(c1, c + (size_t)nc * p, sizeof(float) * nc) == 0,
                   "coefficients of point %d depend on the gradient request", p);
        free(c1);
        free(g1);
    }
    if (!(P.structured && P.exact)) goto done;
    double *cd = fz_guarded(sizeof(double) * nc), *gd = fz_guarded(sizeof(double) * 3 * nc);
    double vd[3 * (SHL_MAX_VERTS + 2)];
    for (int i = 0; i < 3 * nv; ++i) vd[i] = vf[i];
    long double ext = 0.0L;
    for (int i = 0; i < P.n; ++i)
        for (int k = 0; k < 3; ++k) ext = fmaxl(ext, fabsl((long double)vd[3 * i + k] - vd[k]));
    for (int p = 0; p < npts; ++p) {
        fz_geom G;
        if (!fz_poly_geom(&P, xd[p], &G) || !(G.rmax > 0.0L)) continue;
        const float *cp = c + (size_t)nc * p, *gp = g + (size_t)3 * nc * p;
        const long double gbound = fz_kl(lmax) * G.gsum;
        if (with_grad && gbound < FLT_MAX / 1e4)
            FUZZ_CHECK(all_finite_f(gp, 3 * nc), "non-finite batch gradient, point %d, bound %.3Lg", p, gbound);
        FUZZ_CHECK(shl_polygon_grad(ctx, xd[p], vd, P.n, cd, gd) == SHL_OK, "double path");
        if (G.height == 0.0L) {
            for (int k = 0; k < nc; ++k) FUZZ_CHECK(cp[k] == 0.0f, "in-plane point %d: L[%d] = %a", p, k, cp[k]);
            continue;
        }
        /* documented: farther than 2^40 extents from every vertex: zeros */
        long double dmin = INFINITY;
        for (int i = 0; i < P.n; ++i) {
            long double d2 = 0.0L;
            for (int k = 0; k < 3; ++k) d2 += ((long double)vd[3 * i + k] - xd[p][k]) * ((long double)vd[3 * i + k] - xd[p][k]);
            dmin = fminl(dmin, sqrtl(d2));
        }
        int zeros = 1;
        for (int k = 0; k < nc; ++k) zeros &= cp[k] == 0.0f;
        if (zeros && dmin > ldexpl(ext, 39)) continue;
        /* documented: a point the float geometry cannot resolve -- height below 2^-16 of
         * its distance to the farthest vertex, or within 2^-16 extents of a vertex (here
         * with a factor 2 margin), in front of the plane test and the 2^40-extents rule --
         * takes the scalar path: shl_polygon_grad_f's results, bit for bit */
        if (dmin < ldexpl(ext, 38) && G.height > ldexpl(G.rmax, -40) &&
            (G.height <= ldexpl(G.rmax, -17) || dmin < ldexpl(ext, -17))) {
            float *cf = fz_guarded(sizeof(float) * nc), *gf = fz_guarded(sizeof(float) * 3 * nc);
            FUZZ_CHECK(shl_polygon_grad_f(ctx, pts + 3 * p, vf, P.n, cf, gf) == SHL_OK, "scalar float path");
            FUZZ_CHECK(memcmp(cp, cf, sizeof(float) * nc) == 0, "point %d: unresolved point differs from shl_polygon_grad_f", p);
            if (with_grad)
                FUZZ_CHECK(memcmp(gp, gf, sizeof(float) * 3 * nc) == 0,
                           "point %d: unresolved point's gradient differs from shl_polygon_grad_f", p);
            free(cf);
            free(gf);
        }

        const long double A = G.omega, epsd = DBL_EPSILON, epsf = FLT_EPSILON;
        const long double condf = 8.0L * epsf * G.scale * G.gsum, gcondf = 8.0L * epsf * G.scale * G.g2sum;
        const long double conddbl = 8.0L * (epsd * G.scale + 0x1p-1074L) * G.gsum;
        if (fz_is_verbose())
            fprintf(stderr, "point %d: Omega_ref %.17Lg height %.3Lg rmax %.3Lg perim %.3Lg G %.3Lg condf %.3Lg\n", p, A,
                    G.height, G.rmax, G.perim, G.gsum, condf);
        for (int l = 0; l <= lmax; ++l) {
            const long double kl = fz_kl(l);
            const long double sd = kl * (1e-9L * A + 300.0L * epsd * G.perim + conddbl) + 1e-300L;
            const long double sf = kl * (1e-4L * A + 64.0L * (l + 1) * epsf * G.perim + condf + 1e-36L);
            const long double gs = kl * (2e-4L * G.gsum + 64.0L * (l + 1) * epsf * G.gsum + 2.0L * gcondf + 1e-36L);
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                /* any planar polygon subtends less than a hemisphere: |L_lm| <= K_l 2 pi */
                FUZZ_CHECK(fabsl(cp[k]) <= kl * 2.0L * M_PI + sf + sd, "point %d: |L[%d]| = %.9g above K_l 2 pi + %.3Lg", p,
                           k, cp[k], sf + sd);
                FUZZ_CHECK(fabsl((long double)cp[k] - cd[k]) <= sf + sd,
                           "point %d: L[%d] batch %.9g vs double %.17g (slack %.3Lg, K_l Omega %.3Lg)", p, k, cp[k], cd[k],
                           sf + sd, kl * A);
                for (int a = 0; with_grad && a < 3; ++a) {
                    const float ga = gp[a * nc + k];
                    if (!isfinite(ga)) continue;
                    FUZZ_CHECK(fabsl((long double)ga - gd[a * nc + k]) <= gs,
                               "point %d: dL[%d]/dx%d batch %.9g vs double %.17g (slack %.3Lg)", p, k, a, ga,
                               gd[a * nc + k], gs);
                }
            }
        }
    }
    free(cd);
    free(gd);
done:
    free(c);
    free(g);
    return 0;
}
