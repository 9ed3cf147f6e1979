/* Light sets in float through the batch kernels (shl_lights_eval_batch_f), for
 * every ISA this machine runs, against the scalar double reference
 * shl_lights_eval on the float-rounded points.
 *
 * Tolerance: the derived batch tolerance of tests/batch_tol.h. */
#include "batch_tol.h"
#include "geom.h"
#include "isa_ctx.h"
#include "ref_quad.h"
#include "testutil.h"
#include <float.h>
#include <math.h>
#include <string.h>

#include "internal.h" /* shl__alloc_fail_after (src/alloc.c, built with SHL_ALLOC_HOOKS) */

enum { MAXPTS = 150 };

/* The batch against shl_lights_eval at every point; returns the worst error / tolerance. */
static double check_set(const shl_ctx *ctx, const light_set *s, const float *pts, int npts, const char *what)
{
    const int lmax = shl_ctx_lmax(ctx), nc = SHL_NCOEFFS(lmax);
    static float rgb[3 * MAXPTS * NCMAX + 1], grad[9 * MAXPTS * NCMAX + 1], rgb2[3 * MAXPTS * NCMAX + 1];
    static double ref[3 * NCMAX], ref_grad[9 * NCMAX];
    double worst = 0.0;
    rgb[3 * npts * nc] = grad[9 * npts * nc] = rgb2[3 * npts * nc] = 7.0f;
    CHECK(shl_lights_eval_batch_f(ctx, s->set, npts, pts, rgb, grad) == SHL_OK);
    CHECK(shl_lights_eval_batch_f(ctx, s->set, npts, pts, rgb2, NULL) == SHL_OK);
    CHECK(rgb[3 * npts * nc] == 7.0f && grad[9 * npts * nc] == 7.0f && rgb2[3 * npts * nc] == 7.0f);
    for (int p = 0; p < npts; ++p) {
        const double x[3] = {pts[3 * p], pts[3 * p + 1], pts[3 * p + 2]};
        double tc[3][SHL_LMAX_MAX + 1], tg[3][SHL_LMAX_MAX + 1];
        CHECK(shl_lights_eval(ctx, s->set, x, ref, ref_grad) == SHL_OK);
        tolerances(ctx, s, x, tc, tg);
        const float *rp = rgb + 3 * (size_t)nc * p, *gp = grad + 9 * (size_t)nc * p;
        for (int c = 0; c < 3; ++c) {
            double ec = 0.0, eg = 0.0, rc = 0.0, rg = 0.0;
            int ok = 1;
            for (int k = 0; k < nc; ++k) {
                ok &= isfinite(rp[c * nc + k]) && rp[c * nc + k] == rgb2[3 * (size_t)nc * p + c * nc + k];
                const double d = fabs(rp[c * nc + k] - ref[c * nc + k]);
                ec = fmax(ec, d), rc = fmax(rc, tol_ratio(d, tc[c][band_of(k)]));
            }
            for (int k = 0; k < 3 * nc; ++k) {
                ok &= isfinite(gp[3 * c * nc + k]);
                const double d = fabs(gp[3 * c * nc + k] - ref_grad[3 * c * nc + k]);
                eg = fmax(eg, d), rg = fmax(rg, tol_ratio(d, tg[c][band_of(k % nc)]));
            }
            CHECK(ok);
            if (!(rc <= 1.0 && rg <= 1.0))
                harness_fail(__FILE__, __LINE__,
                             "%s [%s, lmax %d] point %d (%a, %a, %a) colour %d: coeffs %.3g (error/tol %.3g), grad %.3g "
                             "(error/tol %.3g)",
                             what, shl_ctx_isa(ctx), lmax, p, x[0], x[1], x[2], c, ec, rc, eg, rg);
            worst = fmax(worst, fmax(rc, rg));
        }
    }
    return worst;
}

/* Six random polygons (triangles, quads, concave hexagons; one-sided and
 * two-sided, radiance of either sign) and two spheres around the origin, and
 * npts points in [-2, 2]^3 outside the spheres. */
static void random_set(rng_t *r, light_set *s, float *pts, int npts)
{
    memset(s, 0, sizeof *s);
    CHECK(shl_lights_create(&s->set) == SHL_OK);
    for (int i = 0; i < 6; ++i) {
        double center[3], nrm[3], v[18], rgb[3];
        for (int k = 0; k < 3; ++k) center[k] = rng_range(r, -2.5, 2.5), rgb[k] = rng_range(r, -0.5, 2.0);
        rng_unit_vector(r, nrm);
        const int n = i % 3 == 0 ? 3 : i % 3 == 1 ? 4 : 6;
        random_polygon(r, n, n == 6, center, nrm, rng_range(r, 0.3, 1.5), v);
        add_polygon(s, v, n, rgb, i % 2);
    }
    for (int i = 0; i < 2; ++i) {
        double center[3], rgb[3];
        for (int k = 0; k < 3; ++k) center[k] = rng_range(r, -3.0, 3.0), rgb[k] = rng_range(r, 0.0, 3.0);
        add_sphere(s, center, rng_range(r, 0.1, 0.6), rgb);
    }
    for (int p = 0; p < npts; ++p) {
        double x[3];
        int outside;
        do {
            for (int k = 0; k < 3; ++k) x[k] = (float)rng_range(r, -2.0, 2.0);
            outside = 1;
            for (int i = 0; i < s->count; ++i)
                if (s->sphere[i]) {
                    const double d[3] = {x[0] - s->center[i][0], x[1] - s->center[i][1], x[2] - s->center[i][2]};
                    outside &= sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 1.1 * s->radius[i];
                }
        } while (!outside);
        for (int k = 0; k < 3; ++k) pts[3 * p + k] = (float)x[k];
    }
}

SHL_TEST(simd_lights_random_vs_double_reference)
{
    static const int lmaxes[] = {0, 1, 2, 4, 8, 14, 30};
    rng_t r = {20261201};
    static float pts[3 * MAXPTS];
    for (int i = 0; i < NISA; ++i)
        for (size_t li = 0; li < sizeof lmaxes / sizeof lmaxes[0]; ++li) {
            shl_ctx *ctx = isa_ctx(isas[i], lmaxes[li]);
            if (!ctx) continue;
            double worst = 0.0;
            const int nsets = lmaxes[li] == 30 ? 1 : 4;
            for (int t = 0; t < nsets; ++t) {
                light_set s;
                random_set(&r, &s, pts, 37);
                worst = fmax(worst, check_set(ctx, &s, pts, 37, "random set"));
                shl_lights_destroy(s.set);
            }
            if (lmaxes[li] == 8 || lmaxes[li] == 30) harness_note("%s lmax %d: worst error/tol %.2f", isas[i], lmaxes[li], worst);
            shl_ctx_destroy(ctx);
        }
}

/* A single light of radiance (1, 1, 1): its channels are exactly the single-light
 * batch (0 + 1 u = u); chunks, tails and gathering change nothing: one call of
 * 150 points equals 150 calls of one point, bit for bit. */
SHL_TEST(simd_lights_single_light_and_chunks)
{
    static float pts[3 * MAXPTS], all[3 * MAXPTS * NCMAX], one[3 * NCMAX], single[MAXPTS * NCMAX];
    static float all_g[9 * MAXPTS * NCMAX], one_g[9 * NCMAX], single_g[3 * MAXPTS * NCMAX];
    const float tri_f[9] = {-1.0f, -0.5f, 1.0f, 1.0f, -0.25f, 1.25f, 0.0f, 1.0f, 0.75f};
    const double tri[9] = {-1.0, -0.5, 1.0, 1.0, -0.25, 1.25, 0.0, 1.0, 0.75}, white[3] = {1.0, 1.0, 1.0};
    rng_t r = {77};
    for (int p = 0; p < MAXPTS; ++p)
        for (int k = 0; k < 3; ++k) pts[3 * p + k] = (float)rng_range(&r, -2.0, 2.0);
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], 6);
        if (!ctx) continue;
        const int nc = SHL_NCOEFFS(6);
        shl_lights *set;
        CHECK(shl_lights_create(&set) == SHL_OK);
        CHECK(shl_lights_add_polygon(set, tri, 3, white, 1) == SHL_OK);
        CHECK(shl_polygon_batch_f(ctx, tri_f, 3, MAXPTS, pts, single, single_g) == SHL_OK);
        CHECK(shl_lights_eval_batch_f(ctx, set, MAXPTS, pts, all, all_g) == SHL_OK);
        int same = 1;
        for (int p = 0; p < MAXPTS; ++p) {
            CHECK(shl_lights_eval_batch_f(ctx, set, 1, pts + 3 * p, one, one_g) == SHL_OK);
            same &= memcmp(one, all + 3 * nc * p, sizeof(float) * 3 * nc) == 0;
            same &= memcmp(one_g, all_g + 9 * nc * p, sizeof(float) * 9 * nc) == 0;
            for (int c = 0; c < 3; ++c) {
                same &= memcmp(one + c * nc, single + nc * p, sizeof(float) * nc) == 0;
                same &= memcmp(one_g + 3 * c * nc, single_g + 3 * nc * p, sizeof(float) * 3 * nc) == 0;
            }
        }
        CHECK(same);
        shl_lights_destroy(set);
        shl_ctx_destroy(ctx);
    }
}

/* Edges of the domain: one-sided lights seen from behind and from their plane
 * (exact zeros), points inside and on a sphere (rgb sqrt(4 pi), zero gradient),
 * and lights beyond float's normal range, which take the scalar float path: a
 * square of side 2e200 (the point sees nearly a hemisphere), a sphere of radius
 * 1e100 at distance 2e100 (a 30-degree cap) and one of radius 1e-130
 * (coefficients below float range: zeros). */
SHL_TEST(simd_lights_hard_cases)
{
    const double sq[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const double big[12] = {-1e200, -1e200, 0, 1e200, -1e200, 0, 1e200, 1e200, 0, -1e200, 1e200, 0};
    const double rgb[3] = {1.0, 0.5, -2.0};
    const float pts[] = {0.25f, 0.5f, -1.0f, 0.25f, 0.5f, 0.0f, 3.0f, 0.0f, 0.0f, /* behind, in the plane, beside */
                         0.3f, 0.2f, 5.0f, 0.0f, 0.0f, 5.5f};                      /* inside, on the small sphere */
    enum { NP = 5 };
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], 8);
        if (!ctx) continue;
        const int nc = SHL_NCOEFFS(8);
        static float out[3 * NP * NCMAX], g[9 * NP * NCMAX];
        light_set s;
        memset(&s, 0, sizeof s);
        CHECK(shl_lights_create(&s.set) == SHL_OK);
        add_polygon(&s, sq, 4, rgb, 0); /* faces +z */
        const double c0[3] = {0.0, 0.0, 5.0};
        add_sphere(&s, c0, 0.5, rgb);
        CHECK(shl_lights_eval_batch_f(ctx, s.set, NP, pts, out, g) == SHL_OK);
        /* points 0-2 see only the sphere (0: behind the square, 1: in its plane,
         * 2: in its plane outside it): the set equals the sphere alone */
        float sph[NP * NCMAX], sph_g[3 * NP * NCMAX];
        const float c0f[3] = {0.0f, 0.0f, 5.0f};
        CHECK(shl_sphere_batch_f(ctx, c0f, 0.5f, NP, pts, sph, sph_g) == SHL_OK);
        int same = 1;
        for (int p = 0; p < 3; ++p)
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < nc; ++k) same &= out[3 * nc * p + c * nc + k] == (float)rgb[c] * sph[nc * p + k];
        CHECK(same);
        for (int p = 3; p < NP; ++p) /* inside or on the sphere, in front of the square */
            for (int c = 0; c < 3; ++c) {
                static double sqc[NCMAX], sqg[3 * NCMAX];
                const double x[3] = {pts[3 * p], pts[3 * p + 1], pts[3 * p + 2]};
                double omega, gmax = 0.0, tc[9], tg[9];
                CHECK(shl_polygon_grad(ctx, x, sq, 4, sqc, sqg) == SHL_OK);
                CHECK(shl_polygon_solid_angle(x, sq, 4, &omega) == SHL_OK);
                for (int k = 0; k < 3 * nc; ++k) gmax = fmax(gmax, fabs(sqg[k]));
                float_poly_tol(8, x, sq, 4, omega, gmax, 1, tc, tg);
                /* L00 = rgb (sqrt(4 pi) + square's L00): float rounding of both terms and the
                 * square's derived band-0 batch tolerance (float_tol.h) */
                const double tol = fabs(rgb[c]) * (4.0 * FLT_EPSILON * sqrt(4.0 * M_PI) + tc[0]);
                CHECK_NEAR(out[3 * nc * p + c * nc], rgb[c] * (sqrt(4.0 * M_PI) + sqc[0]), tol);
            }
        check_set(ctx, &s, pts, NP, "one-sided square and sphere");
        shl_lights_destroy(s.set);

        memset(&s, 0, sizeof s);
        CHECK(shl_lights_create(&s.set) == SHL_OK);
        add_polygon(&s, big, 4, rgb, 1);
        const double cbig[3] = {0.0, 0.0, 2e100}, ctiny[3] = {0.0, 1e-30, 1.0};
        add_sphere(&s, cbig, 1e100, rgb);
        add_sphere(&s, ctiny, 1e-130, rgb);
        const float far_pts[] = {0.0f, 0.0f, 1.0f, 0.5f, -0.25f, -3.0f, 1e30f, 0.0f, 1.0f};
        check_set(ctx, &s, far_pts, 3, "lights beyond float range");
        shl_lights_destroy(s.set);
        shl_ctx_destroy(ctx);
    }
}

SHL_TEST(simd_lights_bad_input_and_alloc_failure)
{
    shl_ctx *ctx;
    shl_lights *set, *empty;
    CHECK(shl_ctx_create(4, &ctx) == SHL_OK);
    CHECK(shl_lights_create(&set) == SHL_OK);
    CHECK(shl_lights_create(&empty) == SHL_OK);
    const double tri[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1}, rgb[3] = {1, 2, 3}, c[3] = {0, 0, -2};
    CHECK(shl_lights_add_polygon(set, tri, 3, rgb, 0) == SHL_OK);
    CHECK(shl_lights_add_sphere(set, c, 0.5, rgb) == SHL_OK);
    const int nc = SHL_NCOEFFS(4);
    float pts[6] = {0.1f, 0.2f, 0.0f, 0.0f, 0.0f, 0.0f}, out[6 * SHL_NCOEFFS(4)], g[18 * SHL_NCOEFFS(4)];
    CHECK(shl_lights_eval_batch_f(NULL, set, 1, pts, out, NULL) == SHL_ENULL);
    CHECK(shl_lights_eval_batch_f(ctx, NULL, 1, pts, out, NULL) == SHL_ENULL);
    CHECK(shl_lights_eval_batch_f(ctx, set, 1, NULL, out, NULL) == SHL_ENULL);
    CHECK(shl_lights_eval_batch_f(ctx, set, 1, pts, NULL, NULL) == SHL_ENULL);
    CHECK(shl_lights_eval_batch_f(ctx, set, -1, pts, out, NULL) == SHL_EDOMAIN);
    CHECK(shl_lights_eval_batch_f(ctx, set, 0, NULL, NULL, NULL) == SHL_OK);
    for (int k = 0; k < 3 * nc; ++k) out[k] = 7.0f;
    pts[4] = NAN; /* the second point: nothing is written */
    CHECK(shl_lights_eval_batch_f(ctx, set, 2, pts, out, g) == SHL_ENONFINITE);
    pts[4] = INFINITY;
    CHECK(shl_lights_eval_batch_f(ctx, set, 2, pts, out, g) == SHL_ENONFINITE);
    int untouched = 1;
    for (int k = 0; k < 3 * nc; ++k) untouched &= out[k] == 7.0f;
    CHECK(untouched);
    pts[4] = 0.0f;
    CHECK(shl_lights_eval_batch_f(ctx, empty, 2, pts, out, g) == SHL_OK);
    int zeros = 1;
    for (int k = 0; k < 6 * nc; ++k) zeros &= out[k] == 0.0f;
    for (int k = 0; k < 18 * nc; ++k) zeros &= g[k] == 0.0f;
    CHECK(zeros);
    for (long fail = 0; fail < 2; ++fail) { /* one allocation; on failure nothing is written */
        for (int k = 0; k < 6 * nc; ++k) out[k] = 7.0f;
        shl__alloc_fail_after = fail;
        const int st = shl_lights_eval_batch_f(ctx, set, 2, pts, out, g);
        shl__alloc_fail_after = -1;
        CHECK(st == (fail == 0 ? SHL_ENOMEM : SHL_OK));
        untouched = 1;
        for (int k = 0; k < 6 * nc; ++k) untouched &= out[k] == 7.0f;
        CHECK(untouched == (fail == 0));
    }
    shl_lights_destroy(set);
    shl_lights_destroy(empty);
    shl_ctx_destroy(ctx);
}

/* Small lights in a set (issue 18's sweep): two squares of angular size theta =
 * 1e-3, 1e-4, 1e-5 at distances 1, 10, 100, side by side, radiances (1, 0.5, 2)
 * and (0.25, 1, -1), through shl_lights_eval_batch_f, against the quadrature
 * reference of each light on the float-rounded input.  Each light goes the way
 * of shl_polygon_batch_f (scalar double recurrence for lights under 1/128 rad,
 * src/batch.c), so channel c may err by sum_i |rgb_ic| tol(theta) omega_i, tol the
 * float contract of issue 18 (1e-4 at theta = 1e-3, 1e-3 below), plus the float
 * sum over the lights (2 FLT_EPSILON sum_i |rgb_ic| |L_i|, |L_i| <= omega_i). */
SHL_TEST(simd_lights_float_small_lights)
{
    enum { LM = 8, N8 = SHL_NCOEFFS(LM) };
    static const double rgb[2][3] = {{1.0, 0.5, 2.0}, {0.25, 1.0, -1.0}};
    static float out[3 * N8];
    double worst[3] = {0, 0, 0};
    int isa_count = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        ++isa_count;
        for (int ai = 0; ai < 3; ++ai)
            for (int di = 0; di < 3; ++di) {
                const double theta = ai == 0 ? 1e-3 : ai == 1 ? 1e-4 : 1e-5, d = di == 0 ? 1.0 : di == 1 ? 10.0 : 100.0;
                const double s = theta * d, tol = theta >= 1e-3 ? 1e-4 : 1e-3;
                const float xf[3] = {0.05f, -0.1f, 0.02f};
                const double x[3] = {xf[0], xf[1], xf[2]};
                shl_lights *set;
                CHECK(shl_lights_create(&set) == SHL_OK);
                double v[2][12], ref[2][N8], omega[2];
                for (int L = 0; L < 2; ++L) {
                    const double x0 = 0.3 * d + 2.0 * L * s;
                    const double v0[12] = {x0, 0.2 * d, d, x0 + s, 0.2 * d, d,
                                           x0 + s, 0.2 * d + s, d + 0.3 * s, x0, 0.2 * d + s, d + 0.3 * s};
                    for (int k = 0; k < 12; ++k) v[L][k] = (float)v0[k];
                    CHECK(shl_lights_add_polygon(set, v[L], 4, rgb[L], 1) == SHL_OK);
                    CHECK(ref_polygon_sh(LM, x, v[L], 4, ref[L], NULL) == 0);
                    omega[L] = ref_polygon_solid_angle(x, v[L], 4);
                }
                CHECK(shl_lights_eval_batch_f(ctx, set, 1, xf, out, NULL) == SHL_OK);
                for (int ch = 0; ch < 3; ++ch) {
                    double scale = 0.0;
                    for (int L = 0; L < 2; ++L) scale += fabs(rgb[L][ch]) * omega[L];
                    for (int k = 0; k < N8; ++k) {
                        const double want = rgb[0][ch] * ref[0][k] + rgb[1][ch] * ref[1][k];
                        const double e = fabs(out[ch * N8 + k] - want) / scale;
                        worst[ai] = fmax(worst[ai], e);
                        if (!(e <= tol + 2.0 * FLT_EPSILON))
                            harness_fail(__FILE__, __LINE__, "%s theta %.0e d %g channel %d k %d: error %.3g > %.3g",
                                         isas[i], theta, d, ch, k, e, tol + 2.0 * FLT_EPSILON);
                    }
                }
                shl_lights_destroy(set);
            }
        shl_ctx_destroy(ctx);
    }
    CHECK(isa_count > 0);
    harness_note("%d ISAs, lmax %d, error / sum |rgb| omega over d = 1, 10, 100: theta 1e-3 %.1e, 1e-4 %.1e, 1e-5 %.1e "
                 "(tol 1e-4, 1e-3, 1e-3)", isa_count, LM, worst[0], worst[1], worst[2]);
}

/* Solid angle of the triangle v (z = 0 plane, normal N = (0, 0, nz)) seen from x, long
 * double, Van Oosterom-Strackee: tan(Omega/2) = |det| / (|a||b||c| + (a.b)|c| + (a.c)|b| +
 * (b.c)|a|), a, b, c = v_i - x, with det = N . (v_0 - x) = -nz x_z exactly (no cancellation
 * for a thin triangle, where the triple product formed from a, b, c would lose it all). */
static long double thin_omega(const double v[9], long double nz, const float x[3])
{
    long double a[3][3], len[3];
    for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) a[i][k] = (long double)v[3 * i + k] - x[k];
        len[i] = sqrtl(a[i][0] * a[i][0] + a[i][1] * a[i][1] + a[i][2] * a[i][2]);
    }
#define DOTL(p, q) (a[p][0] * a[q][0] + a[p][1] * a[q][1] + a[p][2] * a[q][2])
    const long double den = len[0] * len[1] * len[2] + DOTL(0, 1) * len[2] + DOTL(0, 2) * len[1] + DOTL(1, 2) * len[0];
#undef DOTL
    return 2.0L * atan2l(fabsl(nz * (long double)x[2]), den);
}

/* fuzz_lights-polygon-batch-f-nonfinite: a polygon much thinner than float resolution
 * (|N| = 2^-500 there) made the prepared float data overflow (1/|N| = inf) and the
 * batch return NaN.  Triangles of twice-area 2^-70 (float vertices: also
 * shl_polygon_batch_f) and 2^-499 (light set only), and the minimized reproducer, now
 * take the scalar path: finite coefficients and gradients, and for the triangles
 * L_00 = Omega / sqrt(4 pi) against the long-double closed form.  Tolerance: the scalar
 * float path's geometry is in double, its coefficients are float recurrences (float
 * contract, tests/fuzz/README.md: K_l (1e-4 Omega + 64 (l+1) eps_f P)); here the arcs'
 * contributions to L_00 cancel to Omega ~ 1e-21, so the absolute term dominates, with
 * the angular perimeter P of a spherical triangle below 2 pi: 64 * 2 pi eps_f K_0 =
 * 2.7e-5.  (The scalar float path's L_00 is ~1e-17 here where Omega / sqrt(4 pi) ~
 * 1e-22: float boundary-sum noise, inside that contract; the NaN was the defect.) */
SHL_TEST(simd_lights_thin_polygon_scalar_path)
{
    const float pts[] = {0.3f, 0.2f, 0.5f, -0.7f, 1.5f, -0.25f, 0.0f, 0.0f, 0.0f, 2.0f, -3.0f, 1e-3f, 0.1f, 0.0f, 4.0f};
    const int np = 5, lmax = 6, nc = SHL_NCOEFFS(6);
    const int exps[2] = {-70, -499};
    static float rgb[9 * 5 * NCMAX], grad[9 * 5 * NCMAX], single[5 * NCMAX], single_g[3 * 5 * NCMAX];
    double worst_abs = 0.0;
    int bad = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], lmax);
        if (!ctx) continue;
        for (int e = 0; e < 2; ++e) {
            const double tri[9] = {1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, ldexp(1.0, exps[e]), 0.0}, white[3] = {1, 1, 1};
            shl_lights *set;
            CHECK(shl_lights_create(&set) == SHL_OK && shl_lights_add_polygon(set, tri, 3, white, 1) == SHL_OK);
            CHECK(shl_lights_eval_batch_f(ctx, set, np, pts, rgb, grad) == SHL_OK);
            shl_lights_destroy(set);
            for (int k = 0; k < 3 * np * nc; ++k) bad += !isfinite(rgb[k]);
            for (int k = 0; k < 9 * np * nc; ++k) bad += !isfinite(grad[k]);
            if (e == 0) { /* float vertices are exact here */
                float tf[9];
                for (int k = 0; k < 9; ++k) tf[k] = (float)tri[k];
                CHECK(shl_polygon_batch_f(ctx, tf, 3, np, pts, single, single_g) == SHL_OK);
                for (int p = 0; p < np; ++p) bad += memcmp(single + nc * p, rgb + 3 * nc * p, sizeof(float) * nc) != 0;
            }
            for (int p = 0; p < np; ++p) {
                /* N = (v1 - v0) x (v2 - v0) = (0, 0, -2^(e+1)) */
                const long double om = thin_omega(tri, -ldexpl(1.0L, exps[e] + 1), pts + 3 * p);
                const long double want = om / sqrtl(4.0L * (long double)M_PI);
                const double err = (double)fabsl(rgb[3 * nc * p] - want);
                bad += err > 64.0 * 2.0 * M_PI * FLT_EPSILON * 0.2820947917738782;
                worst_abs = fmax(worst_abs, err);
            }
        }
        { /* the fuzz reproducer, minimized: fan triangles of area ~1 whose Newell sum is
           * ~2^-492 (|fan_i| ~ 2^492); the point on its vertex at the origin evaluated the
           * proxy lane with 1/|N| = inf */
            const double a = 0x1p-492, b = 0x1.2p-493, white[3] = {1, 1, 1};
            const double poly[15] = {1, 0, 0, -a, -a, -a, -a, -2, -a, -b, -a, -a, 0, 0, 0};
            shl_lights *set;
            CHECK(shl_lights_create(&set) == SHL_OK && shl_lights_add_polygon(set, poly, 5, white, 1) == SHL_OK);
            CHECK(shl_lights_eval_batch_f(ctx, set, np, pts, rgb, grad) == SHL_OK);
            shl_lights_destroy(set);
            for (int k = 0; k < 3 * np * nc; ++k) bad += !isfinite(rgb[k]);
            for (int k = 0; k < 9 * np * nc; ++k) bad += !isfinite(grad[k]);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0);
    harness_note("thin triangles (2 area 2^-70, 2^-499) and the minimized fuzz polygon, 5 points, every ISA: %d "
                 "non-finite / mismatched values; "
                 "max |L_00 - closed form| %.1e (bound 2.7e-5; Omega <= 4e-22)",
                 bad, worst_abs);
}

/* fuzz_lights-subnormal-vertex-distance-float-nan: a point 2^-1050 from one vertex and
 * 2^-560 from the next (scaled units; a non-planar pentagon, so it is off the Newell
 * plane).  Both distances squared underflow, and the set-up took the short-edge form of
 * w_f - w_e, whose edge / r_f reached 1e147: inf in the float recurrence of the batch's
 * scalar path, NaN from band 3 on.  The float light-set batch must agree with the double
 * set (the same double geometry, float recurrences) within the float contract of
 * tests/fuzz/README.md, K_l 64 (l+1) eps_f P (its 1e-4 Omega term covers what the double
 * geometry's own rounding leaves and is not needed here), P = sum of the edges' arcs
 * (long double, from the vertex directions). */
SHL_TEST(simd_lights_subnormal_vertex_distance)
{
    const double pent[15] = {1, 0, 1, 0x1p-560, 0, 0x1p-560, 0, 0x1p-1050, 0x1p-1050, 0, 1, 1, -1, -1, 3};
    const double white[3] = {1, 1, 1}, xd[3] = {0, 0, 0};
    const float xf[3] = {0, 0, 0};
    const int lmax = 6;
    long double perim = 0.0L;
    for (int i = 0; i < 5; ++i) {
        const double *a = pent + 3 * i, *b = pent + 3 * ((i + 1) % 5);
        long double la = 0.0L, lb = 0.0L, dot = 0.0L, cr[3];
        for (int k = 0; k < 3; ++k) la += (long double)a[k] * a[k], lb += (long double)b[k] * b[k], dot += (long double)a[k] * b[k];
        cr[0] = (long double)a[1] * b[2] - (long double)a[2] * b[1];
        cr[1] = (long double)a[2] * b[0] - (long double)a[0] * b[2];
        cr[2] = (long double)a[0] * b[1] - (long double)a[1] * b[0];
        perim += atan2l(sqrtl(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]), dot) * (la > 0 && lb > 0);
    }
    static float rgb[3 * NCMAX];
    static double ref[3 * NCMAX];
    double worst = 0.0;
    int bad = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], lmax);
        if (!ctx) continue;
        shl_lights *set;
        CHECK(shl_lights_create(&set) == SHL_OK && shl_lights_add_polygon(set, pent, 5, white, 1) == SHL_OK);
        CHECK(shl_lights_eval_batch_f(ctx, set, 1, xf, rgb, NULL) == SHL_OK);
        CHECK(shl_lights_eval(ctx, set, xd, ref, NULL) == SHL_OK);
        shl_lights_destroy(set);
        for (int l = 0; l <= lmax; ++l)
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                const double kl = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)), tol = kl * 64.0 * (l + 1) * FLT_EPSILON * (double)perim;
                const double err = fabs((double)rgb[k] - ref[k]);
                bad += !(err <= tol);
                worst = fmax(worst, err / tol);
            }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0);
    harness_note("every ISA, lmax 6: %d coefficients outside K_l 64 (l+1) eps_f P (P = %.3Lf rad), worst %.2g of it", bad,
                 perim, worst);
}
