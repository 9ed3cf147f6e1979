/* Polygon SH gradients (Wu et al. 2020) against the independent reference
 * (ref_quad.c: moving-boundary or differentiated area-form quadrature).
 * Errors are relative to the largest gradient magnitude of the case. */
#include "float_tol.h"
#include "geom.h"
#include "harness.h"
#include "internal.h"
#include "isa_ctx.h"
#include "ref_quad.h"
#include "zh_tables.h"
#include <math.h>
#include <stdio.h>
#include <string.h>

enum { NC20 = SHL_NCOEFFS(20), NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX) };

/* max |got - want| / max |want| over the 3*nc gradient entries, and the coefficient error / omega */
static double grad_error(const shl_ctx *ctx, const double x[3], const double *v, int n, double *coef_err)
{
    const int lmax = shl_ctx_lmax(ctx), nc = SHL_NCOEFFS(lmax);
    static double c[NCMAX], gr[3 * NCMAX], rc[NCMAX], rg[3 * NCMAX];
    double omega, worst = 0.0, scale = 0.0;
    CHECK(shl_polygon_grad(ctx, x, v, n, c, gr) == SHL_OK);
    CHECK(ref_polygon_sh_grad(lmax, x, v, n, rc, rg, NULL) == 0);
    CHECK(shl_polygon_solid_angle(x, v, n, &omega) == SHL_OK);
    CHECK(all_finite(gr, 3 * nc) && all_finite(c, nc));
    for (int k = 0; k < 3 * nc; ++k) {
        scale = fmax(scale, fabs(rg[k]));
        worst = fmax(worst, fabs(gr[k] - rg[k]));
    }
    double ce = 0.0;
    for (int k = 0; k < nc; ++k) ce = fmax(ce, fabs(c[k] - rc[k]));
    if (coef_err) *coef_err = ce / omega;
    return worst / scale;
}

static void grad_case(const char *what, int lmax, const double x[3], const double *v, int n, double tol)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
    double ce;
    const double e = grad_error(ctx, x, v, n, &ce);
    if (!(e <= tol)) harness_fail(__FILE__, __LINE__, "%s: gradient error %.3g > %.3g", what, e, tol);
    /* the joint pass meets the coefficient bounds of shl_polygon */
    CHECK(ce <= (lmax <= 14 ? 1e-12 : 1e-10));
    harness_note("%s %.1e (coeffs %.1e)", what, e, ce);
    shl_ctx_destroy(ctx);
}

/* Case it of the random sweeps: a triangle, quad or concave hexagon v (returns n)
 * of size 0.3..2 and a point x 0.5..4 away, off the polygon's plane. */
static int random_case(rng_t *r, int it, double v[18], double x[3])
{
    double center[3], nrm[3], off[3];
    const int n = it % 3 == 0 ? 3 : it % 3 == 1 ? 4 : 6;
    for (int k = 0; k < 3; ++k) center[k] = rng_range(r, -1, 1);
    rng_unit_vector(r, nrm);
    random_polygon(r, n, n == 6, center, nrm, rng_range(r, 0.3, 2.0), v);
    rng_unit_vector(r, off);
    if (fabs(off[0] * nrm[0] + off[1] * nrm[1] + off[2] * nrm[2]) < 0.05)
        for (int k = 0; k < 3; ++k) off[k] += 0.1 * nrm[k];
    const double dist = rng_range(r, 0.5, 4.0);
    for (int k = 0; k < 3; ++k) x[k] = center[k] + dist * off[k];
    return n;
}

SHL_TEST(polygon_grad_vs_reference_random)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(20, &ctx) == SHL_OK);
    rng_t r = {21};
    double worst = 0.0;
    for (int it = 0; it < 30; ++it) {
        double v[18], x[3];
        const int n = random_case(&r, it, v, x);
        const double e = grad_error(ctx, x, v, n, NULL);
        worst = fmax(worst, e);
        if (!(e <= 1e-8)) harness_fail(__FILE__, __LINE__, "case %d: %.3g, x = (%a, %a, %a)", it, e, x[0], x[1], x[2]);
    }
    harness_note("lmax 20 max gradient error / max|grad| %.2e (tol 1e-8)", worst);
    shl_ctx_destroy(ctx);
}

/* shl_polygon_grad runs its context's ISA kernel: every ISA this CPU runs meets the
 * bound of polygon_grad_vs_reference_random (same cases, fewer), and gives the scalar
 * ISA's coefficients and gradient bit for bit (each lane and each reconstruction sum
 * does the scalar arithmetic in the scalar order, without contraction). */
SHL_TEST(polygon_grad_every_isa)
{
    char note[256] = "";
    static double c0[12][NC20], g0[12][3 * NC20];
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], 20);
        if (!ctx) continue;
        rng_t r = {21};
        double worst = 0.0;
        for (int it = 0; it < 12; ++it) {
            double v[18], x[3], c[NC20], g[3 * NC20];
            const int n = random_case(&r, it, v, x);
            const double e = grad_error(ctx, x, v, n, NULL);
            worst = fmax(worst, e);
            if (!(e <= 1e-8)) harness_fail(__FILE__, __LINE__, "%s case %d: %.3g", isas[i], it, e);
            CHECK(shl_polygon_grad(ctx, x, v, n, i ? c : c0[it], i ? g : g0[it]) == SHL_OK);
            if (i && (memcmp(c, c0[it], sizeof c) != 0 || memcmp(g, g0[it], sizeof g) != 0))
                harness_fail(__FILE__, __LINE__, "%s case %d differs from %s", isas[i], it, isas[0]);
        }
        snprintf(note + strlen(note), sizeof note - strlen(note), "%s %.2e; ", isas[i], worst);
        shl_ctx_destroy(ctx);
    }
    harness_note("lmax 20 max gradient error / max|grad| per ISA: %s(tol 1e-8)", note);
}

/* One configuration of the float path (double geometry) against the reference
 * gradient, with the derived per-band tolerance of float_tol.h.  Its error is
 * ~0.01 of the tolerance: a single point sits in the bulk of the rounding
 * distribution, while the tolerance is LAMBDA = 6 deviations for the tail
 * over many points (test_simd.c's sweeps reach 0.05-0.13). */
SHL_TEST(polygon_grad_float)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(14, &ctx) == SHL_OK);
    const float vf[12] = {-0.5f, -0.2f, 1.0f, 0.7f, -0.1f, 1.2f, 0.1f, 0.8f, 0.9f, -0.6f, 0.5f, 0.8f};
    const float xf[3] = {0.1f, 0.1f, 0.0f};
    double v[12], x[3] = {xf[0], xf[1], xf[2]}, rc[NCMAX], rg[3 * NCMAX], scale = 0, worst = 0, ratio = 0, omega;
    double tc[15], tg[15];
    float c[NCMAX], g[3 * NCMAX];
    for (int k = 0; k < 12; ++k) v[k] = vf[k];
    CHECK(shl_polygon_grad_f(ctx, xf, vf, 3, c, g) == SHL_OK);
    CHECK(ref_polygon_sh_grad(14, x, v, 3, rc, rg, NULL) == 0);
    CHECK(shl_polygon_solid_angle(x, v, 3, &omega) == SHL_OK);
    for (int k = 0; k < 3 * SHL_NCOEFFS(14); ++k) scale = fmax(scale, fabs(rg[k]));
    float_poly_tol(14, x, v, 3, omega, scale, 0, tc, tg); /* derived per-band tolerance */
    for (int k = 0; k < 3 * SHL_NCOEFFS(14); ++k) {
        worst = fmax(worst, fabs(g[k] - rg[k]));
        ratio = fmax(ratio, fabs(g[k] - rg[k]) / tg[(int)sqrt(k % SHL_NCOEFFS(14) + 0.5)]);
    }
    CHECK(ratio <= 1.0);
    harness_note("float lmax 14 gradient error / max|grad| %.1e; error / derived tolerance (float_tol.h) %.2f",
                 worst / scale, ratio);
    shl_ctx_destroy(ctx);
}

/* An edge whose plane normal is exactly a lobe direction: A = 0 in Wu 2020 Eq. (23). */
SHL_TEST(polygon_grad_lobe_on_edge_plane_normal)
{
    const double x[3] = {0, 0, 0};
    const int lobes[3] = {0, 3, 2 * 20};
    for (int i = 0; i < 3; ++i) {
        const double *d = shl__zh_dir[lobes[i]];
        double u[3], w[3], v[9];
        plane_basis(d, u, w);
        for (int k = 0; k < 3; ++k) {
            v[k] = 1.3 * u[k];                              /* edge 0 -> 1 lies in the plane normal to d */
            v[3 + k] = 0.9 * (0.6 * u[k] + 0.8 * w[k]);
            v[6 + k] = 1.1 * (0.3 * u[k] + 0.3 * w[k] + 0.9 * d[k]);
        }
        char what[48];
        snprintf(what, sizeof what, "lobe %d on edge normal", lobes[i]);
        grad_case(what, 20, x, v, 3, 1e-8);
    }
}

SHL_TEST(polygon_grad_short_edge_and_near_edge)
{
    const double short_edge[12] = {0, 0, 0, 1, 0, 0, 1, 1e-6, 0, 0, 1, 0}; /* edge 1-2 has length 1e-6 */
    const double x1[3] = {0.3, 0.4, 0.7};
    grad_case("edge length 1e-6", 20, x1, short_edge, 4, 1e-8);
    const double square[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const double x2[3] = {0.5, -1e-6 / M_SQRT2, 1e-6 / M_SQRT2}; /* 1e-6 from an edge, off the plane */
    grad_case("point 1e-6 from an edge", 20, x2, square, 4, 1e-8);
    const double x3[3] = {0.3, 0.6, 1e-7};
    grad_case("point 1e-7 above the plane", 20, x3, square, 4, 1e-8);
}

SHL_TEST(polygon_grad_in_plane_and_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(4, &ctx) == SHL_OK);
    const double square[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, in_plane[3] = {2, 0.5, 0};
    double c[26], g[76];
    guard_fill(c, 26);
    guard_fill(g, 76);
    CHECK(shl_polygon_grad(ctx, in_plane, square, 4, c, g) == SHL_OK);
    for (int k = 0; k < 25; ++k) CHECK(c[k] == 0.0);
    for (int k = 0; k < 75; ++k) CHECK(g[k] == 0.0);
    CHECK(c[25] == GUARD_VALUE && g[75] == GUARD_VALUE);
    guard_fill(c, 26);
    guard_fill(g, 76);
    const double x[3] = {0.5, 0.5, 1}, bad[3] = {0.5, NAN, 1};
    CHECK(shl_polygon_grad(ctx, x, square, 4, c, NULL) == SHL_ENULL);
    CHECK(shl_polygon_grad(ctx, x, square, 4, NULL, g) == SHL_ENULL);
    CHECK(shl_polygon_grad(NULL, x, square, 4, c, g) == SHL_ENULL);
    CHECK(shl_polygon_grad(ctx, x, square, 2, c, g) == SHL_ENVERTS);
    CHECK(shl_polygon_grad(ctx, bad, square, 4, c, g) == SHL_ENONFINITE);
    CHECK(guard_intact(c, 26) && guard_intact(g, 76));
    shl_ctx_destroy(ctx);
}

/* A non-planar quad whose vertex 1, t (1, 3/4, 1/4), lies within t of x = 0, the whole
 * scaled by 2^s (exact).  In scaled units (largest coordinate near 1) the point is t from
 * the two edges' lines at vertex 1: at t = 2^-1040, 1/t overflowed there and the gradient
 * was NaN (fuzz_lights-subnormal-vertex-distance-float-nan); with s = 100 the gradient in x
 * units, ~2^940, is representable (at s = 0 it is not: +-inf, never NaN).  Reference: the same quad at t_ref = 2^-900, s = 0 (the
 * ordinary path: nothing over/underflows); the gradient is A / t + O(1) near the vertex, so
 * g(t, s) = 2^-s (t_ref / t) g_ref up to a relative O(t_ref) = 2^-900.  Tolerance: the
 * scaled coordinates of vertex 1 and the cross products rel_1 x edge are subnormal, each
 * rounded to 2^-1075 absolutely, a relative 2^-1075 / (t |edge| sin) (sin >= 1/4 here) in
 * the direction w_1, the edge normals mu and |gvec|; a few of them per term: 64 2^-1074 / t
 * relative (3.7e-9 at t = 2^-1040; measured up to 26 2^-1074 / t), for the coefficients
 * (<= K_0 4 pi < 4) too, on top of their 1e-12 (test_polygon.c). */
SHL_TEST(polygon_grad_nonplanar_vertex_subnormal_distance)
{
    enum { LMAX = 6, NC = SHL_NCOEFFS(LMAX) };
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    const double x[3] = {0, 0, 0};
    double worst = 0.0;
    int bad = 0, n_inf = 0;
    const int t_exp[3] = {-1030, -1040, -1050};
    for (int i = 0; i < 3; ++i) {
        double v[12], vref[12], c[NC], g[3 * NC], cref[NC], gref[3 * NC];
        const double quad[12] = {1, 0.2, 0.1, 1, 0.75, 0.25, 0.3, 1, 0.4, -0.2, 0.5, 1};
        for (int k = 0; k < 12; ++k) {
            const int near = k / 3 == 1;
            v[k] = ldexp(quad[k], 100 + (near ? t_exp[i] : 0));
            vref[k] = near ? ldexp(quad[k], -900) : quad[k];
        }
        CHECK(shl_polygon_grad(ctx, x, v, 4, c, g) == SHL_OK);
        CHECK(shl_polygon_grad(ctx, x, vref, 4, cref, gref) == SHL_OK);
        bad += !all_finite(g, 3 * NC) || !all_finite(c, NC);
        const double ratio = ldexp(1.0, -900 - t_exp[i] - 100); /* 2^-s t_ref / t */
        double err = 0.0, scale = 0.0;
        for (int k = 0; k < 3 * NC; ++k) {
            scale = fmax(scale, fabs(ratio * gref[k]));
            err = fmax(err, fabs(g[k] - ratio * gref[k]));
        }
        const double tol = 64.0 * ldexp(1.0, -1074 - t_exp[i]);
        bad += !(err <= tol * scale);
        worst = fmax(worst, err / scale);
        for (int k = 0; k < NC; ++k) bad += !(fabs(c[k] - cref[k]) <= 1e-12 + 4.0 * tol);
        /* s = 0: the gradient, ~2^1036 in x units, is not representable: no NaN (summed in
         * scaled units, unscaled at the end), +-inf where 2^-s (t_ref/t) g_ref >= 2^1025
         * (beyond the tolerance's reach of DBL_MAX) */
        for (int k = 0; k < 12; ++k) v[k] = k / 3 == 1 ? ldexp(quad[k], t_exp[i]) : quad[k];
        CHECK(shl_polygon_grad(ctx, x, v, 4, c, g) == SHL_OK);
        for (int k = 0; k < 3 * NC; ++k) {
            const double beyond = ldexp(gref[k], -900 - t_exp[i] - 1); /* +-inf when >= 2^1025 */
            bad += isnan(g[k]) || (isinf(beyond) && g[k] != beyond);
            n_inf += isinf(beyond) != 0;
        }
    }
    CHECK(bad == 0);
    CHECK(n_inf > 0);
    harness_note("vertex 2^-1030..2^-1050 from x (scaled units), gradient ~2^940 in x units: %d non-finite or "
                 "outside the tolerance; max |g - 2^-s (t_ref/t) g_ref| / max |g| %.2g (tol 64 2^-1074 / t); "
                 "at s = 0, %d entries beyond 2^1025: +-inf, no NaN",
                 bad, worst, n_inf);
    shl_ctx_destroy(ctx);
}
