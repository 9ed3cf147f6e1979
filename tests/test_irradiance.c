/* Irradiance (src/irradiance.c) and SH windowing (src/sh_window.c) against
 * independent references:
 *  - the rectangle-to-point form factor (closed form) over angular sizes 1e-9..20;
 *  - a tilted square crossing the horizon: the v-integral in closed form, the u-integral
 *    by Gauss-Legendre (the integrand is analytic on the clipped interval);
 *  - random polygons: above the horizon, n . int w dw from the band-1 coefficients of
 *    the quadrature reference tests/ref_quad.c; across it, an adaptive Gauss rule over
 *    the plane polygon clipped in its own 2D coordinates (this file);
 *  - shl_sh_irradiance(shl_polygon) -> shl_polygon_irradiance as lmax grows, within the
 *    truncation bound sum_{l>L} |A_l| (2l+1)/(4 pi) x solid angle;
 *  - window factors against their closed forms; windows shrink the negative lobes of a
 *    truncated delta. */
#include "capref.h"
#include "geom.h"
#include "harness.h"
#include "ref_quad.h"
#include "shlight.h"
#include <float.h>
#include <math.h>
#include <string.h>

enum { NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX) };

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void crs(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static double irr(const double x[3], const double n[3], const double *v, int nv)
{
    double e = NAN;
    CHECK(shl_polygon_irradiance(x, n, v, nv, &e) == SHL_OK);
    return e;
}

/* ---- references ---------------------------------------------------------- */

/* Irradiance at the origin, normal +z, from the rectangle [0,a] x [0,b] at height c
 * (unit radiance): pi times the classic point-to-parallel-rectangle form factor,
 * E = 1/2 [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))],
 * A = a/c, B = b/c.  Sums of positive terms: ~10 ulps. */
static double rect_closed(double a, double b, double c)
{
    const double A = a / c, B = b / c, sa = sqrt(1.0 + A * A), sb = sqrt(1.0 + B * B);
    return 0.5 * (A / sa * atan(B / sa) + B / sb * atan(A / sb));
}

/* Tilted square: z = 1, [-1,1]^2, x = 0, n = (sin t, 0, cos t).  n . p >= 0 is u >= u0 =
 * -cot t.  With a^2 = 1 + u^2: E = int_{u0}^1 (u sin t + cos t) int_{-1}^1 dv/(a^2+v^2)^2 du
 * and int_{-1}^1 dv/(a^2+v^2)^2 = 1/(a^2 (a^2+1)) + atan(1/a)/a^3.  The u-integrand is
 * analytic near [-1, 1] (poles at u = +-i, +-i sqrt(2)): 8 panels of 20 Gauss nodes,
 * error far below 1e-16. */
static double tilted_square_ref(double t)
{
    const double s = sin(t), c = cos(t), u0 = fmax(-1.0, -c / s);
    if (u0 >= 1.0) return 0.0;
    double gx[20], gw[20], sum = 0.0;
    capref_gauss_legendre(20, gx, gw);
    for (int p = 0; p < 8; ++p) {
        const double lo = u0 + (1.0 - u0) * p / 8.0, hi = u0 + (1.0 - u0) * (p + 1) / 8.0;
        for (int i = 0; i < 20; ++i) {
            const double u = 0.5 * (lo + hi) + 0.5 * (hi - lo) * gx[i], a2 = 1.0 + u * u, a = sqrt(a2);
            const double inner = 1.0 / (a2 * (a2 + 1.0)) + atan(1.0 / a) / (a2 * a);
            sum += 0.5 * (hi - lo) * gw[i] * (u * s + c) * inner;
        }
    }
    return sum;
}

/* Band-1 reference: n . int_poly w dw from ref_polygon_sh's l = 1 coefficients
 * (Y_1-1 = -c y, Y_10 = c z, Y_11 = -c x, c = sqrt(3/(4 pi))): equals the irradiance
 * when the whole polygon is above the horizon.  ref_quad's accuracy 1e-15 x solid angle. */
static double band1_ref(const double x[3], const double n[3], const double *v, int nv)
{
    double co[4], unit[3];
    CHECK(ref_polygon_sh(1, x, v, nv, co, NULL) == 0);
    const double c = sqrt(3.0 / (4.0 * M_PI)), len = sqrt(dot(n, n));
    for (int k = 0; k < 3; ++k) unit[k] = n[k] / len;
    return (-unit[1] * co[1] + unit[2] * co[2] - unit[0] * co[3]) / c;
}

/* Plane-area reference for any polygon and normal: 2D coordinates (u, v) in the polygon's
 * plane, the half-plane n . (p - x) >= 0 clipped in 2D, then int h (n . (p - x)) / r^4 dA
 * (h = distance of x to the plane) over the fan of 2D triangles, each by an adaptive
 * collapsed 10x10 Gauss rule (split in 4 until two levels agree to 1e-13 relative or
 * 1e-17 x the solid angle; the accepted children are then accurate to ~1e-16). */
typedef struct {
    double o[3], e1[3], e2[3], x[3], n[3], h;
} plane_ctx;

static double tri_rule(const plane_ctx *P, const double a[2], const double b[2], const double c[2])
{
    static double gx[10], gw[10];
    static int init;
    if (!init) { capref_gauss_legendre(10, gx, gw); init = 1; }
    const double area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    double s = 0.0;
    for (int i = 0; i < 10; ++i) {
        const double u = 0.5 * (gx[i] + 1.0);
        for (int j = 0; j < 10; ++j) {
            const double w = 0.5 * (gx[j] + 1.0);
            double q2[2], p[3];
            for (int k = 0; k < 2; ++k) q2[k] = a[k] + u * (b[k] - a[k]) + u * w * (c[k] - b[k]);
            for (int k = 0; k < 3; ++k) p[k] = P->o[k] + q2[0] * P->e1[k] + q2[1] * P->e2[k] - P->x[k];
            const double r2 = dot(p, p);
            s += 0.25 * gw[i] * gw[j] * u * P->h * dot(P->n, p) / (r2 * r2);
        }
    }
    return area2 * s;
}

static double tri_adapt(const plane_ctx *P, const double a[2], const double b[2], const double c[2], double whole,
                        double abs_tol, int depth)
{
    const double ab[2] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])}, bc[2] = {0.5 * (b[0] + c[0]), 0.5 * (b[1] + c[1])},
                 ca[2] = {0.5 * (c[0] + a[0]), 0.5 * (c[1] + a[1])};
    const double t0 = tri_rule(P, a, ab, ca), t1 = tri_rule(P, ab, b, bc), t2 = tri_rule(P, ca, bc, c),
                 t3 = tri_rule(P, ab, bc, ca), sum = t0 + t1 + t2 + t3;
    /* |sum - whole| estimates the parent's error; the children's is far smaller once the
     * rule resolves the integrand (10-point Gauss: error ratio ~ 2^-20 per halving) */
    if (depth >= 12 || fabs(sum - whole) <= 1e-13 * fabs(sum) + abs_tol) return sum;
    return tri_adapt(P, a, ab, ca, t0, abs_tol, depth + 1) + tri_adapt(P, ab, b, bc, t1, abs_tol, depth + 1) +
           tri_adapt(P, ca, bc, c, t2, abs_tol, depth + 1) + tri_adapt(P, ab, bc, ca, t3, abs_tol, depth + 1);
}

static double plane_ref(const double x[3], const double n[3], const double *v, int nv)
{
    const double omega = ref_polygon_solid_angle(x, v, nv);
    plane_ctx P;
    double m[3] = {0, 0, 0};
    for (int i = 1; i + 1 < nv; ++i) { /* Newell normal */
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; ++k) { a[k] = v[3 * i + k] - v[k]; b[k] = v[3 * i + 3 + k] - v[k]; }
        crs(a, b, c);
        for (int k = 0; k < 3; ++k) m[k] += c[k];
    }
    const double ml = sqrt(dot(m, m)), nl = sqrt(dot(n, n));
    for (int k = 0; k < 3; ++k) { m[k] /= ml; P.n[k] = n[k] / nl; P.o[k] = v[k]; P.x[k] = x[k]; }
    plane_basis(m, P.e1, P.e2);
    double ox[3];
    for (int k = 0; k < 3; ++k) ox[k] = v[k] - x[k];
    P.h = fabs(dot(m, ox));
    /* 2D polygon, then clip by g(u, v) = n.(o - x) + u n.e1 + v n.e2 >= 0 */
    double poly[64][2], out[130][2], g[64];
    for (int i = 0; i < nv; ++i) {
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = v[3 * i + k] - v[k];
        poly[i][0] = dot(d, P.e1);
        poly[i][1] = dot(d, P.e2);
    }
    const double g0 = dot(P.n, ox), gu = dot(P.n, P.e1), gv = dot(P.n, P.e2);
    for (int i = 0; i < nv; ++i) g[i] = g0 + gu * poly[i][0] + gv * poly[i][1];
    int no = 0;
    for (int i = 0; i < nv; ++i) {
        const int j = (i + 1) % nv;
        if (g[i] >= 0.0) { out[no][0] = poly[i][0]; out[no][1] = poly[i][1]; ++no; }
        if ((g[i] >= 0.0) != (g[j] >= 0.0)) {
            const double t = g[i] / (g[i] - g[j]);
            out[no][0] = poly[i][0] + t * (poly[j][0] - poly[i][0]);
            out[no][1] = poly[i][1] + t * (poly[j][1] - poly[i][1]);
            ++no;
        }
    }
    double total = 0.0;
    for (int i = 1; i + 1 < no; ++i) {
        const double whole = tri_rule(&P, out[0], out[i], out[i + 1]);
        total += tri_adapt(&P, out[0], out[i], out[i + 1], whole, 1e-17 * omega, 0);
    }
    return fabs(total); /* the 2D orientation follows plane_basis, not the winding */
}

/* ---- polygon irradiance ------------------------------------------------- */

/* Centred square of half-side s at height c, facing x (normal +z): 4 corner rectangles.
 * Tolerance 4e-14 relative: the closed form ~10 ulps; the library sums <= 100 positive
 * terms (area rule, each ~8 ulps) or 4 positive Lambert terms: <= 110 eps = 2.4e-14. */
SHL_TEST(irradiance_square_closed_form)
{
    const double x[3] = {0.5, -0.25, 3.0}; /* offsets below are exact in binary */
    double worst = 0.0;
    for (int e = -30; e <= 4; ++e) {
        const double s = ldexp(1.0, e), c = 1.0;
        const double v[12] = {x[0] - s, x[1] - s, x[2] + c, x[0] + s, x[1] - s, x[2] + c,
                              x[0] + s, x[1] + s, x[2] + c, x[0] - s, x[1] + s, x[2] + c};
        const double n[3] = {0, 0, 2.5}, want = 4.0 * rect_closed(s, s, c);
        const double got = irr(x, n, v, 4), rel = fabs(got - want) / want;
        worst = fmax(worst, rel);
        if (!(rel <= 4e-14)) harness_fail(__FILE__, __LINE__, "half-side 2^%d: %.17g vs %.17g (rel %.3g)", e, got, want, rel);
    }
    harness_note("max rel error vs closed form, half-side 2^-30..2^4 at distance 1: %.2e (tol 4e-14)", worst);
}

/* Rectangles with a corner at the foot of x (the closed form's own configuration), sizes
 * 1e-7..40 at distance 0.75, aspect ratios up to 15: same tolerance. */
SHL_TEST(irradiance_corner_rectangle_closed_form)
{
    const double x[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    double worst = 0.0;
    const double sizes[][2] = {{1e-7, 3e-7}, {0.01, 0.5}, {1.0, 1.0}, {3.0, 0.2}, {40.0, 25.0}};
    for (int i = 0; i < 5; ++i) {
        const double a = sizes[i][0], b = sizes[i][1], c = 0.75;
        const double v[12] = {0, 0, c, a, 0, c, a, b, c, 0, b, c};
        const double want = rect_closed(a, b, c), got = irr(x, n, v, 4), rel = fabs(got - want) / want;
        worst = fmax(worst, rel);
        CHECK(rel <= 4e-14);
    }
    harness_note("max rel error, corner rectangles: %.2e (tol 4e-14)", worst);
}

/* Tilted square crossing the horizon, t = 10..170 degrees; beyond 135 degrees every
 * vertex is below the horizon: exactly 0.  Tolerance 1e-14 relative to E(0) = the
 * facing value: the horizon edge's clip points are exact to a few ulps and Lambert's
 * terms are of size <= 2 pi / 2 (~ E(0)), so a few tens of ulps of E(0). */
SHL_TEST(irradiance_tilted_square_horizon)
{
    const double x[3] = {0, 0, 0}, v[12] = {-1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1};
    const double e0 = tilted_square_ref(0.0);
    CHECK_NEAR(e0, 4.0 * rect_closed(1, 1, 1), 1e-15);
    double worst = 0.0;
    for (int d = 10; d <= 170; d += 5) {
        const double t = d * M_PI / 180.0, n[3] = {sin(t), 0.0, cos(t)};
        const double want = tilted_square_ref(t), got = irr(x, n, v, 4);
        if (d > 135) CHECK(got == 0.0);
        worst = fmax(worst, fabs(got - want) / e0);
        if (!(fabs(got - want) <= 1e-14 * e0))
            harness_fail(__FILE__, __LINE__, "t = %d deg: %.17g vs %.17g", d, got, want);
    }
    harness_note("max |error| / E(facing), 10..170 deg: %.2e (tol 1e-14)", worst);
}

/* A small square (half-side s) straight ahead, the horizon cutting it at u = s/3:
 * n = (1, 0, -s/3), z = 1, x = 0; reference as tilted_square_ref with the v-integral
 * over [-s, s]: int_{-s}^{s} dv/(a^2+v^2)^2 = s/(a^2 (a^2+s^2)) + atan(s/a)/a^3.
 * The clip line's position is known to ~eps (distance 1), so E is known to a relative
 * ~eps/s (shlight.h): tolerance 64 eps / s.  The polygon is small: the area rule runs. */
static double small_clipped_ref(double s)
{
    const double u0 = s / 3.0, nl = sqrt(1.0 + u0 * u0);
    double gx[20], gw[20], sum = 0.0;
    capref_gauss_legendre(20, gx, gw);
    for (int i = 0; i < 20; ++i) {
        const double u = 0.5 * (u0 + s) + 0.5 * (s - u0) * gx[i], a2 = 1.0 + u * u, a = sqrt(a2);
        const double inner = s / (a2 * (a2 + s * s)) + atan(s / a) / (a2 * a);
        sum += 0.5 * (s - u0) * gw[i] * (u - u0) / nl * inner;
    }
    return sum;
}

SHL_TEST(irradiance_small_polygon_across_horizon)
{
    const double x[3] = {0, 0, 0};
    double worst = 0.0;
    for (int e = -24; e <= -4; e += 4) {
        const double s = ldexp(1.0, e), n[3] = {1.0, 0.0, -s / 3.0};
        const double v[12] = {-s, -s, 1, s, -s, 1, s, s, 1, -s, s, 1};
        const double want = small_clipped_ref(s), got = irr(x, n, v, 4), rel = fabs(got - want) / want;
        worst = fmax(worst, rel * s / DBL_EPSILON);
        if (!(rel <= 64 * DBL_EPSILON / s))
            harness_fail(__FILE__, __LINE__, "s = 2^%d: %.17g vs %.17g (rel %.3g)", e, got, want, rel);
    }
    harness_note("max rel error x size / eps, sizes 2^-24..2^-4: %.2f (tol 64)", worst);
}

/* Random triangles, quads, concave hexagons and random normals.  Above the horizon the
 * band-1 reference (1e-15 x solid angle) and the plane reference agree; across it, the
 * plane reference.  Tolerance 1e-13 x solid angle: both references ~1e-15 Omega, the
 * library's Lambert sum at most ~100 ulps of sum_e gamma_e / 2 <= 2 pi ~ a few Omega
 * for these sizes (polygons of 0.3-2 at distance 0.5-4). */
SHL_TEST(irradiance_random_vs_quadrature)
{
    rng_t r = {901};
    double worst_above = 0.0, worst_cross = 0.0, worst_refs = 0.0;
    int n_above = 0, n_cross = 0, n_zero = 0;
    for (int it = 0; it < 120; ++it) {
        double center[3], nrm[3], off[3], x[3], n[3], v[18];
        for (int k = 0; k < 3; ++k) center[k] = rng_range(&r, -1, 1);
        rng_unit_vector(&r, nrm);
        const int nv = it % 3 == 0 ? 3 : it % 3 == 1 ? 4 : 6;
        random_polygon(&r, nv, nv == 6, center, nrm, rng_range(&r, 0.3, 2.0), v);
        rng_unit_vector(&r, off);
        if (fabs(dot(off, nrm)) < 0.1)
            for (int k = 0; k < 3; ++k) off[k] += 0.2 * nrm[k];
        const double dist = rng_range(&r, 0.5, 4.0);
        for (int k = 0; k < 3; ++k) x[k] = center[k] + dist * off[k];
        rng_unit_vector(&r, n);
        double omega;
        CHECK(shl_polygon_solid_angle(x, v, nv, &omega) == SHL_OK);
        int above = 0, below = 0;
        for (int i = 0; i < nv; ++i) {
            double d[3];
            for (int k = 0; k < 3; ++k) d[k] = v[3 * i + k] - x[k];
            above += dot(n, d) > 0.0;
            below += dot(n, d) < 0.0;
        }
        const double got = irr(x, n, v, nv), pref = plane_ref(x, n, v, nv);
        if (above == 0) {
            CHECK(got == 0.0);
            ++n_zero;
            continue;
        }
        double err = fabs(got - pref) / omega;
        if (below == 0) {
            const double bref = band1_ref(x, n, v, nv);
            worst_refs = fmax(worst_refs, fabs(pref - bref) / omega);
            err = fmax(err, fabs(got - bref) / omega);
            worst_above = fmax(worst_above, err);
            ++n_above;
        } else {
            worst_cross = fmax(worst_cross, err);
            ++n_cross;
        }
        if (!(err <= 1e-13)) harness_fail(__FILE__, __LINE__, "case %d: %.17g vs %.17g, err/omega %.3g", it, got, pref, err);
    }
    CHECK(worst_refs <= 1e-14);
    harness_note("err/omega: above %.2e (%d cases), crossing %.2e (%d), below %d exact 0; refs agree %.1e (tol 1e-13)",
                 worst_above, n_above, worst_cross, n_cross, n_zero, worst_refs);
}

/* Small polygons at every angular size 1e-12..1 and tilts up to 80 degrees, against the
 * band-1 reference (whole polygon above the horizon).  Stated accuracy (shlight.h):
 * area rule below 1/16: relative error a few tens of ulps; Lambert above it, cancelling by
 * <= tan(tilt) / size: with tan(80 deg) = 5.7 and size >= 1/16 about 90 x rounding.
 * Tolerance: 2e-14 relative to E plus the reference's 1e-15 Omega / cos(tilt). */
SHL_TEST(irradiance_small_polygons_relative)
{
    rng_t r = {77};
    double worst = 0.0, worst_lambert = 0.0;
    for (int it = 0; it < 60; ++it) {
        const double size = pow(10.0, rng_range(&r, -12.0, 0.0)), tilt = rng_range(&r, 0.0, 80.0) * M_PI / 180.0;
        const double x[3] = {0.125, 0.5, -0.25}, center[3] = {0.125, 0.5, 0.75}, pn[3] = {0, 0, 1};
        double v[18];
        const int nv = 3 + it % 4;
        random_polygon(&r, nv, nv == 6, center, pn, size, v); /* 6: concave star */
        const double phi = rng_range(&r, 0, 2 * M_PI), n[3] = {sin(tilt) * cos(phi), sin(tilt) * sin(phi), cos(tilt)};
        double omega;
        CHECK(shl_polygon_solid_angle(x, v, nv, &omega) == SHL_OK);
        const double got = irr(x, n, v, nv), want = band1_ref(x, n, v, nv);
        const double tol = 2e-14 * want + 1e-15 * omega / cos(tilt) + 1e-15 * omega;
        const double rel = fabs(got - want) / want;
        worst = fmax(worst, rel);
        if (size > 1.0 / 16.0) worst_lambert = fmax(worst_lambert, rel);
        if (!(fabs(got - want) <= tol))
            harness_fail(__FILE__, __LINE__, "size %.3g tilt %.1f: %.17g vs %.17g (rel %.3g)", size,
                         tilt * 180 / M_PI, got, want, rel);
    }
    harness_note("max rel error, sizes 1e-12..1, tilt <= 80 deg: %.2e (Lambert-path cases %.2e)", worst, worst_lambert);
}

/* Winding, cyclic order, normal length, repeated vertices: the same value to rounding.
 * A different vertex 0 changes the order of Lambert's sum, whose terms are <= gamma_e / 2
 * with sum_e gamma_e ~ 2-3 here (size 1 at distance ~1.5, Omega ~ 0.3-0.5): a few ulps
 * of the terms, 1e-14 x Omega.  Relative to E it can be larger where the polygon is
 * near or across the horizon (E << Omega; the conditioning stated in shlight.h). */
SHL_TEST(irradiance_invariances)
{
    rng_t r = {5};
    double worst = 0.0;
    for (int it = 0; it < 40; ++it) {
        double center[3], nrm[3], x[3], n[3], v[18], rev[18], rot[18], rep[21];
        for (int k = 0; k < 3; ++k) center[k] = rng_range(&r, -1, 1);
        rng_unit_vector(&r, nrm);
        const int nv = 4 + it % 3;
        random_polygon(&r, nv, it & 1, center, nrm, 1.0, v);
        for (int k = 0; k < 3; ++k) x[k] = center[k] + 1.5 * nrm[k] + rng_range(&r, -0.5, 0.5);
        rng_unit_vector(&r, n);
        for (int i = 0; i < nv; ++i)
            for (int k = 0; k < 3; ++k) {
                rev[3 * i + k] = v[3 * (nv - 1 - i) + k];
                rot[3 * i + k] = v[3 * ((i + 2) % nv) + k];
            }
        memcpy(rep, v, sizeof(double) * 3); /* vertex 0 twice */
        memcpy(rep + 3, v, sizeof(double) * 3 * nv);
        const double big[3] = {n[0] * 0x1p900, n[1] * 0x1p900, n[2] * 0x1p900},
                     tiny[3] = {n[0] * 0x1p-900, n[1] * 0x1p-900, n[2] * 0x1p-900};
        const double e = irr(x, n, v, nv);
        double omega;
        CHECK(shl_polygon_solid_angle(x, v, nv, &omega) == SHL_OK);
        const double vals[5] = {irr(x, n, rev, nv), irr(x, n, rot, nv), irr(x, big, v, nv), irr(x, tiny, v, nv),
                                irr(x, n, rep, nv + 1)};
        for (int j = 0; j < 5; ++j) {
            const double d = fabs(vals[j] - e);
            worst = fmax(worst, d / omega);
            if (!(d <= 1e-14 * omega)) harness_fail(__FILE__, __LINE__, "case %d variant %d: %.17g vs %.17g", it, j, vals[j], e);
        }
    }
    harness_note("max spread / Omega over winding / rotation / normal length / repeats: %.2e (tol 1e-14)", worst);
}

/* Points in the plane (inside, outside, on a vertex) and a polygon wholly below the
 * horizon: exactly 0; a point just above a huge polygon facing it: E -> pi. */
SHL_TEST(irradiance_special_cases)
{
    const double v[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, up[3] = {0, 0, 1}, down[3] = {0, 0, -1};
    const double in_plane[3][3] = {{0.2, 0.3, 0}, {5, 5, 0}, {1, 1, 0}};
    for (int i = 0; i < 3; ++i) CHECK(irr(in_plane[i], up, v, 4) == 0.0);
    const double above[3] = {0.1, 0.2, 0.5};
    CHECK(irr(above, up, v, 4) == 0.0); /* facing away */
    const double tilt[3] = {-1, 0, 3};
    CHECK(irr(above, tilt, v, 4) == 0.0); /* tilted, every vertex below: max n.(v-x) = 1.1 - 1.5 */
    const double big[12] = {-1e6, -1e6, 0, 1e6, -1e6, 0, 1e6, 1e6, 0, -1e6, 1e6, 0};
    const double e = irr(above, down, big, 4);
    /* facing a square of half-side 1e6 at distance 0.5: pi (1 - O(h/size)), closed form */
    const double a[4] = {1e6 - 0.1, 1e6 + 0.1, 1e6 - 0.2, 1e6 + 0.2};
    const double want = rect_closed(a[0], a[2], 0.5) + rect_closed(a[1], a[2], 0.5) + rect_closed(a[0], a[3], 0.5) +
           rect_closed(a[1], a[3], 0.5);
    CHECK_NEAR(e, want, 1e-13);
    CHECK(e <= M_PI);
    harness_note("half-space limit: %.15f (pi %.15f)", e, M_PI);
}

SHL_TEST(irradiance_bad_input)
{
    const double x[3] = {0, 0, 1}, n[3] = {0, 0, -1}, zero[3] = {0, 0, 0}, nan3[3] = {0, NAN, 1},
                 inf3[3] = {INFINITY, 0, 1};
    double v[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, out = GUARD_VALUE;
    CHECK(shl_polygon_irradiance(NULL, n, v, 4, &out) == SHL_ENULL);
    CHECK(shl_polygon_irradiance(x, NULL, v, 4, &out) == SHL_ENULL);
    CHECK(shl_polygon_irradiance(x, n, NULL, 4, &out) == SHL_ENULL);
    CHECK(shl_polygon_irradiance(x, n, v, 4, NULL) == SHL_ENULL);
    CHECK(shl_polygon_irradiance(x, n, v, 2, &out) == SHL_ENVERTS);
    CHECK(shl_polygon_irradiance(x, n, v, SHL_MAX_VERTS + 1, &out) == SHL_ENVERTS);
    CHECK(shl_polygon_irradiance(x, zero, v, 4, &out) == SHL_EDOMAIN);
    CHECK(shl_polygon_irradiance(nan3, n, v, 4, &out) == SHL_ENONFINITE);
    CHECK(shl_polygon_irradiance(x, inf3, v, 4, &out) == SHL_ENONFINITE);
    v[7] = NAN;
    CHECK(shl_polygon_irradiance(x, n, v, 4, &out) == SHL_ENONFINITE);
    CHECK(out == GUARD_VALUE);

    double co[4] = {1, 0, 0, 0};
    CHECK(shl_sh_irradiance(1, NULL, n, &out) == SHL_ENULL);
    CHECK(shl_sh_irradiance(1, co, NULL, &out) == SHL_ENULL);
    CHECK(shl_sh_irradiance(1, co, n, NULL) == SHL_ENULL);
    CHECK(shl_sh_irradiance(-1, co, n, &out) == SHL_ELMAX);
    CHECK(shl_sh_irradiance(SHL_LMAX_MAX + 1, co, n, &out) == SHL_ELMAX);
    CHECK(shl_sh_irradiance(1, co, zero, &out) == SHL_EDOMAIN);
    CHECK(shl_sh_irradiance(1, co, nan3, &out) == SHL_ENONFINITE);
    co[3] = INFINITY;
    CHECK(shl_sh_irradiance(1, co, n, &out) == SHL_ENONFINITE);
    CHECK(out == GUARD_VALUE);

    double h[4] = {GUARD_VALUE, GUARD_VALUE, GUARD_VALUE, GUARD_VALUE};
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_HANNING, 0.0, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_LANCZOS, -1.0, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_LAPLACIAN, -1e-9, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, 0, 1.0, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_POUSSIN, 2.5, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_POUSSIN, 31.0, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_POUSSIN, -1.0, h) == SHL_EDOMAIN);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_HANNING, NAN, h) == SHL_ENONFINITE);
    CHECK(shl_sh_window_factors(-1, SHL_WINDOW_HANNING, 4.0, h) == SHL_ELMAX);
    CHECK(shl_sh_window_factors(3, SHL_WINDOW_HANNING, 4.0, NULL) == SHL_ENULL);
    CHECK(guard_intact(h, 4));
    double c4[4] = {1, 2, NAN, 4};
    CHECK(shl_sh_window(1, SHL_WINDOW_HANNING, 2.0, c4) == SHL_ENONFINITE);
    CHECK(c4[0] == 1 && c4[1] == 2 && c4[3] == 4);
    CHECK(shl_sh_window(1, SHL_WINDOW_HANNING, 2.0, NULL) == SHL_ENULL);
}

/* ---- SH irradiance -------------------------------------------------------- */

/* |A_l| for l = 0..N by the exact ratio recurrence of 2 pi int_0^1 t P_l(t) dt:
 * I_0 = 1/2, I_1 = 1/3, I_{l+2} = I_l (1 - l) / (l + 4). */
static double a_hat(int l)
{
    double i_even = 0.5, i_odd = 1.0 / 3.0;
    for (int k = 0; k + 2 <= l; ++k) {
        if (k & 1) i_odd *= (1.0 - k) / (k + 4.0);
        else i_even *= (1.0 - k) / (k + 4.0);
    }
    return 2.0 * M_PI * ((l & 1) ? i_odd : i_even);
}

/* A_l as seen through shl_sh_irradiance: the input coeffs = Y_lm(n) on band l only gives
 * E = A_l sum_m Y_lm(n)^2 = A_l (2l+1)/(4 pi) (addition theorem), compared with the closed
 * values and, for l >= 7, with the exact ratio recurrence a_hat (this file).  Tolerance
 * 1e-14 relative: sum_m Y_lm^2 carries ~(2l+1) ulps. */
SHL_TEST(sh_irradiance_kernel_values)
{
    const double want[7] = {M_PI, 2 * M_PI / 3, M_PI / 4, 0.0, -M_PI / 24, 0.0, M_PI / 64};
    const double n[3] = {0.3, -0.4, 0.866};
    double y[NCMAX], worst = 0.0;
    CHECK(shl_eval_basis(SHL_LMAX_MAX, n, y) == SHL_OK);
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) {
        double co[NCMAX] = {0}, e;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) co[k] = y[k];
        CHECK(shl_sh_irradiance(l, co, n, &e) == SHL_OK);
        const double a = e * 4 * M_PI / (2 * l + 1), ref = l < 7 ? want[l] : a_hat(l);
        if (l < 7) CHECK_NEAR(a_hat(l), want[l], 2 * DBL_EPSILON * M_PI); /* the test's recurrence */
        const double err = fabs(a - ref);
        worst = fmax(worst, err);
        if (!(err <= 1e-14 * (fabs(ref) + 1e-3)))
            harness_fail(__FILE__, __LINE__, "l = %d: A_l %.17g vs %.17g", l, a, ref);
    }
    /* constant unit radiance: E = pi for any normal */
    double co[1] = {sqrt(4 * M_PI)}, e;
    CHECK(shl_sh_irradiance(0, co, n, &e) == SHL_OK);
    CHECK_NEAR(e, M_PI, 4 * DBL_EPSILON * M_PI);
    harness_note("max |A_l - closed form| l <= 30: %.2e", worst);
}

/* Truncation bound T(L) = sum_{l>L} |A_l| (2l+1)/(4 pi): explicit sum to N = 2^22, then the
 * remainder bounded with t_l = |A_l| (2l+1), t_{l+2}/t_l = (l-1)(2l+5)/((l+4)(2l+1))
 * <= (l/(l+2))^1.4 for even l >= 8 (checked below over the summed range): sum_{l>N} t_l
 * <= t_N int_0^inf (N/(N+2s))^1.4 ds = 1.25 N t_N. */
static void truncation_bounds(double *bound /* [SHL_LMAX_MAX + 1] */)
{
    enum { N = 1 << 22 };
    double tail = 0.0, ieven = 0.5, tN = 0.0;
    /* even l only (odd l >= 3 vanish): |I_l| */
    double partial[SHL_LMAX_MAX + 2] = {0};
    int ok = 1;
    for (int l = 0; l <= N; l += 2) {
        const double tl = 2 * M_PI * fabs(ieven) * (2.0 * l + 1.0) / (4 * M_PI);
        if (l > SHL_LMAX_MAX) tail += tl;
        else partial[l] = tl;
        if (l >= 8) {
            const double ratio = (l - 1.0) * (2.0 * l + 5.0) / ((l + 4.0) * (2.0 * l + 1.0));
            ok &= ratio <= pow(l / (l + 2.0), 1.4);
        }
        tN = tl;
        ieven *= (1.0 - l) / (l + 4.0);
    }
    CHECK(ok);
    tail += 1.25 * N * tN;
    for (int L = SHL_LMAX_MAX; L >= 0; --L) {
        bound[L] = tail;
        tail += partial[L];
    }
}

/* shl_sh_irradiance of shl_polygon's coefficients (lmax 30) truncated at L = 2..30 against
 * shl_polygon_irradiance: |error| <= T(L) Omega + slack, slack = the coefficients' error
 * (test_polygon: <= 1e-10 Omega each at lmax 30) times sum_l |A_l| (2l+1) sqrt((2l+1)/(4pi)). */
SHL_TEST(sh_irradiance_converges_to_exact)
{
    double bound[SHL_LMAX_MAX + 1];
    truncation_bounds(bound);
    double slack = 0.0;
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) slack += fabs(a_hat(l)) * (2 * l + 1) * sqrt((2 * l + 1) / (4 * M_PI));
    slack *= 1e-10;
    shl_ctx *ctx;
    CHECK(shl_ctx_create(SHL_LMAX_MAX, &ctx) == SHL_OK);
    const double cases[4][15] = {
        {0, 0, 0, /* square facing, centred */ -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1},
        {0, 0, 0, /* square crossing the horizon of n below */ -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1},
        {0.3, 0.1, 0.2, /* triangle, oblique */ 2, 0, 0, 0, 2, 0.5, 0, 0, 2, 0, 0, 0},
        {0, 0, 0, /* small square */ -0.05, -0.05, 1, 0.05, -0.05, 1, 0.05, 0.05, 1, -0.05, 0.05, 1}};
    const double normals[4][3] = {{0, 0, 1}, {0.8, 0, 0.3}, {0.2, 0.3, 0.9}, {0.5, 0.5, 0.2}};
    double ratio_l2 = 0.0, err30_max = 0.0;
    for (int c = 0; c < 4; ++c) {
        const double *x = cases[c], *v = cases[c] + 3;
        const int nv = c == 2 ? 3 : 4;
        double co[NCMAX], omega, exact;
        CHECK(shl_polygon(ctx, x, v, nv, co) == SHL_OK);
        CHECK(shl_polygon_solid_angle(x, v, nv, &omega) == SHL_OK);
        exact = irr(x, normals[c], v, nv);
        for (int L = 2; L <= SHL_LMAX_MAX; ++L) {
            double e;
            CHECK(shl_sh_irradiance(L, co, normals[c], &e) == SHL_OK);
            const double err = fabs(e - exact), lim = bound[L] * omega + slack * omega;
            if (L == 2) ratio_l2 = fmax(ratio_l2, err / (bound[L] * omega));
            if (L == SHL_LMAX_MAX) err30_max = fmax(err30_max, err / omega);
            if (!(err <= lim)) harness_fail(__FILE__, __LINE__, "case %d L %d: |%.17g - %.17g| > %.3g", c, L, e, exact, lim);
        }
    }
    harness_note("bound T(2) = %.3f, T(30) = %.4f (x Omega); worst err/bound at L=2 %.2f; err/Omega at L=30 %.2e",
                 bound[2], bound[SHL_LMAX_MAX], ratio_l2, err30_max);
    shl_ctx_destroy(ctx);
}

/* The RGB form: bit-identical to three single calls (same sums in the same order);
 * errors before anything is written. */
SHL_TEST(sh_irradiance_rgb_matches_single)
{
    rng_t r = {31};
    for (int it = 0; it < 20; ++it) {
        const int lmax = it % (SHL_LMAX_MAX + 1), nc = SHL_NCOEFFS(lmax);
        double rgb[3 * NCMAX], n[3], e3[3], e;
        for (int k = 0; k < 3 * nc; ++k) rgb[k] = rng_range(&r, -1, 1);
        rng_unit_vector(&r, n);
        n[0] *= 3.0;
        CHECK(shl_sh_irradiance_rgb(lmax, rgb, n, e3) == SHL_OK);
        for (int c = 0; c < 3; ++c) {
            CHECK(shl_sh_irradiance(lmax, rgb + c * nc, n, &e) == SHL_OK);
            CHECK(e == e3[c]);
        }
    }
    double rgb[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, NAN}, out[3] = {GUARD_VALUE, GUARD_VALUE, GUARD_VALUE};
    const double n[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
    CHECK(shl_sh_irradiance_rgb(1, rgb, n, out) == SHL_ENONFINITE);
    rgb[11] = 0.0;
    CHECK(shl_sh_irradiance_rgb(1, rgb, zero, out) == SHL_EDOMAIN);
    CHECK(shl_sh_irradiance_rgb(31, rgb, n, out) == SHL_ELMAX);
    CHECK(shl_sh_irradiance_rgb(1, NULL, n, out) == SHL_ENULL);
    CHECK(shl_sh_irradiance_rgb(1, rgb, NULL, out) == SHL_ENULL);
    CHECK(shl_sh_irradiance_rgb(1, rgb, n, NULL) == SHL_ENULL);
    CHECK(guard_intact(out, 3));
}

/* ---- windows --------------------------------------------------------------- */

SHL_TEST(sh_window_factors_closed_forms)
{
    double h[5];
    const double s2 = sqrt(2.0);
    CHECK(shl_sh_window_factors(4, SHL_WINDOW_HANNING, 4.0, h) == SHL_OK);
    const double hann[5] = {1, (2 + s2) / 4, 0.5, (2 - s2) / 4, 0};
    for (int l = 0; l < 5; ++l) CHECK_NEAR(h[l], hann[l], 2 * DBL_EPSILON);
    CHECK(shl_sh_window_factors(4, SHL_WINDOW_LANCZOS, 4.0, h) == SHL_OK);
    const double lanc[5] = {1, 2 * s2 / M_PI, 2 / M_PI, 2 * s2 / (3 * M_PI), 0};
    for (int l = 0; l < 5; ++l) CHECK_NEAR(h[l], lanc[l], 4 * DBL_EPSILON);
    CHECK(shl_sh_window_factors(4, SHL_WINDOW_LAPLACIAN, 0.01, h) == SHL_OK);
    const double lap[5] = {1, 1 / 1.04, 1 / 1.36, 1 / 2.44, 1 / 5.0};
    for (int l = 0; l < 5; ++l) CHECK_NEAR(h[l], lap[l], 2 * DBL_EPSILON);
    /* de la Vallee Poussin, p = 3: h_l = 3! 4! / ((3-l)! (4+l)!) = 1, 3/5, 1/5, 1/35, 0 */
    CHECK(shl_sh_window_factors(4, SHL_WINDOW_POUSSIN, 3.0, h) == SHL_OK);
    const double vp[5] = {1, 0.6, 0.2, 1.0 / 35, 0};
    for (int l = 0; l < 5; ++l) CHECK_NEAR(h[l], vp[l], 4 * DBL_EPSILON);
    CHECK(h[4] == 0.0);
    CHECK(shl_sh_window_factors(4, SHL_WINDOW_LAPLACIAN, 0.0, h) == SHL_OK);
    for (int l = 0; l < 5; ++l) CHECK(h[l] == 1.0);
    /* in place on a vector: band l scaled by h_l */
    double co[9], want[9];
    for (int k = 0; k < 9; ++k) co[k] = want[k] = k + 1.0;
    CHECK(shl_sh_window(2, SHL_WINDOW_HANNING, 4.0, co) == SHL_OK);
    for (int k = 0; k < 9; ++k) CHECK_NEAR(co[k], want[k] * hann[k == 0 ? 0 : k < 4 ? 1 : 2], 1e-15 * want[k]);
}

/* de la Vallee Poussin window, p = L: the windowed delta is the kernel ((1 + t)/2)^L
 * normalized (closed form: (L+1)/(4 pi) ((1+t)/2)^L, integral 1), and the windowed
 * clamped-cosine kernel sum_l h_l A_l (2l+1)/(4 pi) P_l(t) is a convolution of two
 * non-negative kernels: both >= 0 (to rounding, 1e-15 x peak) on 4001 samples, L = 1..30. */
SHL_TEST(sh_window_poussin_nonnegative)
{
    double worst_delta = 0.0, min_kernel = 0.0;
    for (int L = 1; L <= SHL_LMAX_MAX; ++L) {
        double h[SHL_LMAX_MAX + 1], zh[SHL_LMAX_MAX + 1];
        CHECK(shl_sh_window_factors(L, SHL_WINDOW_POUSSIN, L, h) == SHL_OK);
        CHECK(shl_zh_clamped_cosine(L, zh) == SHL_OK);
        for (int i = 0; i <= 4000; ++i) {
            const double t = cos(M_PI * i / 4000.0);
            double f = h[0] / (4 * M_PI), k = zh[0] * sqrt(1 / (4 * M_PI)), p0 = 1.0, p1 = t;
            for (int l = 1; l <= L; ++l) {
                f += h[l] * (2 * l + 1) / (4 * M_PI) * p1;
                k += h[l] * zh[l] * sqrt((2 * l + 1) / (4 * M_PI)) * p1; /* A_l (2l+1)/(4 pi) = zh_l K_l */
                const double p2 = ((2 * l + 1) * t * p1 - l * p0) / (l + 1);
                p0 = p1;
                p1 = p2;
            }
            const double want = (L + 1) / (4 * M_PI) * pow(0.5 * (1 + t), L), peak = (L + 1) / (4 * M_PI);
            worst_delta = fmax(worst_delta, fabs(f - want) / peak);
            min_kernel = fmin(min_kernel, k);
            CHECK(f >= -1e-15 * peak && k >= -1e-15);
        }
    }
    CHECK(worst_delta <= 1e-13); /* sums of <= 31 terms ~ peak, Legendre recurrence ~ l ulps */
    harness_note("windowed delta vs ((1+t)/2)^L closed form: %.2e x peak; min windowed irradiance kernel %.2e",
                 worst_delta, min_kernel);
}

/* A delta at +z truncated to band L: f(theta) = sum_l h_l (2l+1)/(4 pi) P_l(cos theta).
 * Without a window (h = 1) its side lobes reach ~ -0.1 to -0.2 of the peak (the
 * Dirichlet-like kernel); Hanning and Lanczos taper the band edge, whose jump is what
 * makes the side lobes (as for the Fejer and Hann kernels on the circle), and the
 * Laplacian window with lambda = 1/(L(L+1))^2 halves band L.  Property: each window's
 * most negative value relative to its peak is smaller in magnitude than unwindowed,
 * for L = 2..30 (theta sampled at 4000 points). */
SHL_TEST(sh_window_reduces_negative_lobes)
{
    double worst_ratio[3] = {0, 0, 0}, raw_at8 = 0, hann_at8 = 0;
    for (int L = 2; L <= SHL_LMAX_MAX; ++L) {
        double h[4][SHL_LMAX_MAX + 1];
        for (int l = 0; l <= L; ++l) h[0][l] = 1.0;
        CHECK(shl_sh_window_factors(L, SHL_WINDOW_HANNING, L + 1.0, h[1]) == SHL_OK);
        CHECK(shl_sh_window_factors(L, SHL_WINDOW_LANCZOS, L + 1.0, h[2]) == SHL_OK);
        CHECK(shl_sh_window_factors(L, SHL_WINDOW_LAPLACIAN, 1.0 / pow(L * (L + 1.0), 2), h[3]) == SHL_OK);
        double neg[4];
        for (int w = 0; w < 4; ++w) {
            double peak = 0.0, mn = 0.0;
            for (int i = 0; i <= 4000; ++i) {
                const double t = cos(M_PI * i / 4000.0);
                double f = h[w][0] / (4 * M_PI), p0 = 1.0, p1 = t;
                for (int l = 1; l <= L; ++l) {
                    f += h[w][l] * (2 * l + 1) / (4 * M_PI) * p1;
                    const double p2 = ((2 * l + 1) * t * p1 - l * p0) / (l + 1);
                    p0 = p1;
                    p1 = p2;
                }
                if (i == 0) peak = f;
                mn = fmin(mn, f);
            }
            neg[w] = -mn / peak;
        }
        for (int w = 1; w < 4; ++w) {
            worst_ratio[w - 1] = fmax(worst_ratio[w - 1], neg[w] / neg[0]);
            if (!(neg[w] < neg[0])) harness_fail(__FILE__, __LINE__, "L %d window %d: %.3g vs raw %.3g", L, w, neg[w], neg[0]);
        }
        if (L == 8) { raw_at8 = neg[0]; hann_at8 = neg[1]; }
    }
    harness_note("L=8 negative lobe/peak: raw %.3f, Hanning %.4f; worst windowed/raw over L 2..30: "
                 "Hanning %.3f, Lanczos %.3f, Laplacian %.3f", raw_at8, hann_at8, worst_ratio[0], worst_ratio[1],
                 worst_ratio[2]);
}
