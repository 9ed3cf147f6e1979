/* Analytic SH Hessians (shl_polygon_hess, shl_sphere_hess, shl_lights_eval_hess).
 *
 * References:
 *  1. Richardson-extrapolated central differences of the analytic gradients
 *     (shl_polygon_grad / shl_sphere_grad, themselves tested against quadrature):
 *       D(h) = (G(x + h e_b) - G(x - h e_b)) / 2h = H + h^2 G'''/6 + h^4 G^(5)/120 + ...
 *       R(h) = (4 D(h/2) - D(h)) / 3 = H - h^4 G^(5)/480 + O(h^6).
 *     Error bound: |R - H| <= h^4 max|G^(5)|/480 + 3 delta/h, delta the rounding error of
 *     one gradient value (D(h/2) carries 2 delta/h, D(h) delta/h, weights 4/3, 1/3).  G is
 *     analytic within rho of x (rho: distance to the polygon's plane or to the sphere's
 *     surface), so by Cauchy's estimate on the disk of radius rho/2, max|G^(5)| <= 5! M 2^5 / rho^5
 *     with M = max|G| there, and the truncation is <= 8 (h/rho)^4 M/rho.  With h = rho/400
 *     that is 3e-10 M/(rho max|H|) of max|H|; M/(rho max|H|) is O(1) but not known a priori
 *     (h = rho/100 measured 1e-7, i.e. M/(rho max|H|) ~ 20), so the truncation is also
 *     estimated a posteriori, |R(h) - R(2h)| / 15, and required below 1e-8 max|H|.  Rounding:
 *     delta <= 1e-14 max|G| (the gradients' accuracy, with margin) and max|G| <~ rho max|H|
 *     give 3 delta/h <= 1.2e-11 max|H|.  So the reference is good to ~1e-8 of max|H| and the
 *     issue's target, 1e-7 of max|H|, is tested with margin.
 *  2. Independent of the library: the band-0 Hessian is Y_00 times the Hessian of the solid
 *     angle; that is differenced in long double from a Van Oosterom-Strackee fan (polygon)
 *     or 2 pi (1 - sqrt(1 - R^2/d^2)) (sphere) with two Richardson levels (error O(h^6)).
 *  3. An exact identity: the solid angle of a fixed surface is harmonic off it (the
 *     potential of a uniform double layer), so for polygons trace H_00 = 0.  The higher
 *     bands and the sphere's band 0 are not harmonic (2 pi (1 - cos a) ~ pi R^2/d^2 far
 *     away, whose Laplacian is 2 pi R^2/d^4), so no trace is tested there. */
#include "shlight.h"
#include "geom.h"
#include "harness.h"
#include "internal.h"
#include "testutil.h"
#include "fd_check.h"
#include "isa_ctx.h"
#include "polygon.h"
#include "sphere.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>
#include <string.h>

enum { LM = 14, NCM = SHL_NCOEFFS(LM) };
static const int hia[6] = {0, 0, 0, 1, 1, 2}, hib[6] = {0, 1, 2, 1, 2, 2};


/* The light: a polygon or a sphere, with the gradient entry point of its kind. */
typedef struct {
    int sphere, n;
    double verts[3 * 8], center[3], radius;
} light_t;

static int light_grad(const shl_ctx *ctx, const light_t *li, const double x[3], double *c, double *g)
{
    return li->sphere ? shl_sphere_grad(ctx, x, li->center, li->radius, c, g) : shl_polygon_grad(ctx, x, li->verts, li->n, c, g);
}
static int light_hess(const shl_ctx *ctx, const light_t *li, const double x[3], double *c, double *g, double *h)
{
    return li->sphere ? shl_sphere_hess(ctx, x, li->center, li->radius, c, g, h)
                      : shl_polygon_hess(ctx, x, li->verts, li->n, c, g, h);
}

/* D(h) of the gradient along axis b into d[3*nc] (all components a). */
static void central(const shl_ctx *ctx, const light_t *li, const double x[3], int b, double h, double *d)
{
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(ctx));
    static double c[NCM], gp[3 * NCM], gm[3 * NCM];
    double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
    xp[b] += h, xm[b] -= h;
    CHECK(light_grad(ctx, li, xp, c, gp) == SHL_OK);
    CHECK(light_grad(ctx, li, xm, c, gm) == SHL_OK);
    for (int k = 0; k < 3 * nc; ++k) d[k] = (gp[k] - gm[k]) / (2.0 * h);
}

/* Richardson R(h) of scheme 1 for the six components into r[6*nc]. */
static void richardson(const shl_ctx *ctx, const light_t *li, const double x[3], double h, double *r)
{
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(ctx));
    static double d1[3][3 * NCM], d2[3][3 * NCM];
    for (int b = 0; b < 3; ++b) {
        central(ctx, li, x, b, h, d1[b]);
        central(ctx, li, x, b, h / 2.0, d2[b]);
    }
    /* component (a, b) from the difference along b of gradient a; the symmetric pair's
     * average (a along b, b along a) has the same bound */
    for (int i = 0; i < 6; ++i)
        for (int k = 0; k < nc; ++k) {
            const int a = hia[i], b = hib[i];
            const double rab = (4.0 * d2[b][a * nc + k] - d1[b][a * nc + k]) / 3.0;
            const double rba = (4.0 * d2[a][b * nc + k] - d1[a][b * nc + k]) / 3.0;
            r[i * nc + k] = 0.5 * (rab + rba);
        }
}

/* max |hess - R(h)| / max|hess| at x, the a-posteriori truncation estimate / max|hess|, and
 * *tight = max |hess - (16 R(h) - R(2h))/15| / max|hess| (one more Richardson level, O(h^6)) */
static double fd_error(const shl_ctx *ctx, const light_t *li, const double x[3], double rho, double *trunc,
                       double *tight)
{
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(ctx));
    static double c[NCM], g[3 * NCM], hs[6 * NCM], r1[6 * NCM], r2[6 * NCM];
    CHECK(light_hess(ctx, li, x, c, g, hs) == SHL_OK);
    CHECK(all_finite(hs, 6 * nc));
    const double h = rho / 400.0;
    richardson(ctx, li, x, h, r1);
    richardson(ctx, li, x, 2.0 * h, r2);
    double m = 0.0, e = 0.0, t = 0.0, e2 = 0.0;
    for (int k = 0; k < 6 * nc; ++k) {
        m = fmax(m, fabs(hs[k]));
        e = fmax(e, fabs(hs[k] - r1[k]));
        t = fmax(t, fabs(r1[k] - r2[k]) / 15.0);
        e2 = fmax(e2, fabs(hs[k] - (16.0 * r1[k] - r2[k]) / 15.0));
    }
    *trunc = t / m;
    *tight = e2 / m;
    return e / m;
}

/* Distance of x from the plane of polygon v (n vertices). */
static double plane_distance(const double *v, int n, const double x[3])
{
    double nrm[3] = {0, 0, 0};
    for (int i = 1; i + 1 < n; ++i) {
        const double *a = v + 3 * i, *b = v + 3 * (i + 1);
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) e1[k] = a[k] - v[k], e2[k] = b[k] - v[k];
        nrm[0] += e1[1] * e2[2] - e1[2] * e2[1];
        nrm[1] += e1[2] * e2[0] - e1[0] * e2[2];
        nrm[2] += e1[0] * e2[1] - e1[1] * e2[0];
    }
    const double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    return fabs(nrm[0] * (x[0] - v[0]) + nrm[1] * (x[1] - v[1]) + nrm[2] * (x[2] - v[2])) / len;
}

static void random_polygon_light(rng_t *r, int n, int concave, light_t *li)
{
    double nrm[3], c[3] = {rng_range(r, -0.3, 0.3), rng_range(r, -0.3, 0.3), rng_range(r, -0.3, 0.3)};
    rng_unit_vector(r, nrm);
    li->sphere = 0, li->n = n;
    random_polygon(r, n, concave, c, nrm, rng_range(r, 0.3, 1.0), li->verts);
}

SHL_TEST(hess_polygon_vs_fd_gradient)
{
    rng_t r = {1901};
    const int lmaxes[2] = {8, LM};
    double worst = 0.0, worst_tr = 0.0, worst_tight = 0.0;
    int cases = 0;
    for (int il = 0; il < 2; ++il) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmaxes[il], &ctx) == SHL_OK);
        for (int it = 0; it < 24; ++it) {
            light_t li;
            random_polygon_light(&r, 3 + it % 4, it % 3 == 2, &li);
            double x[3], rho;
            do { /* random points, some close to the plane (down to 1e-2 of the size) */
                for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.5, 1.5);
                if (it % 4 == 3) /* near an edge: 3e-2 from the midpoint of edge 0, off the plane */
                    for (int k = 0; k < 3; ++k)
                        x[k] = 0.5 * (li.verts[k] + li.verts[3 + k]) + 0.03 * rng_range(&r, -1.0, 1.0);
                rho = plane_distance(li.verts, li.n, x);
            } while (rho < 1e-2);
            double tr, tight;
            const double e = fd_error(ctx, &li, x, rho, &tr, &tight);
            worst = fmax(worst, e), worst_tr = fmax(worst_tr, tr), worst_tight = fmax(worst_tight, tight);
            ++cases;
            if (!(e <= 1e-7 && tr <= 1e-8))
                harness_fail(__FILE__, __LINE__, "lmax %d case %d: |H - R| %.3g, truncation estimate %.3g (of max|H|)",
                             lmaxes[il], it, e, tr);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(worst_tight <= 1e-9); /* the O(h^6) level: its error is far below the O(h^4) estimate */
    harness_note("max |H - R(h)| / max|H| %.1e (a-posteriori truncation %.1e), vs the O(h^6) level %.1e (%d polygons, "
                 "lmax 8 and %d)",
                 worst, worst_tr, worst_tight, cases, LM);
}

SHL_TEST(hess_sphere_vs_fd_gradient)
{
    rng_t r = {1902};
    const int lmaxes[2] = {8, LM};
    double worst = 0.0, worst_tr = 0.0, worst_tight = 0.0;
    for (int il = 0; il < 2; ++il) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmaxes[il], &ctx) == SHL_OK);
        for (int it = 0; it < 24; ++it) {
            light_t li = {.sphere = 1};
            double dir[3], x[3];
            rng_unit_vector(&r, dir);
            const double d = rng_range(&r, 0.5, 5.0);
            li.radius = d * (it % 4 == 3 ? rng_range(&r, 0.9, 0.99) : rng_range(&r, 0.02, 0.9)); /* some near the surface */
            for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0), li.center[k] = x[k] + d * dir[k];
            double tr, tight;
            const double e = fd_error(ctx, &li, x, d - li.radius, &tr, &tight);
            worst = fmax(worst, e), worst_tr = fmax(worst_tr, tr), worst_tight = fmax(worst_tight, tight);
            if (!(e <= 1e-7 && tr <= 1e-8))
                harness_fail(__FILE__, __LINE__, "lmax %d case %d: |H - R| %.3g, truncation estimate %.3g (of max|H|)",
                             lmaxes[il], it, e, tr);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(worst_tight <= 1e-9);
    harness_note("max |H - R(h)| / max|H| %.1e (a-posteriori truncation %.1e), vs the O(h^6) level %.1e (48 spheres, "
                 "lmax 8 and %d)",
                 worst, worst_tr, worst_tight, LM);
}

/* The same against fd_check.h (the project's FD check with a derived tolerance): the 6th- vs
 * 8th-order differences of the gradient give the truncation, E = 1e-13 max|G| its evaluation
 * error (the gradients' rounding, measured ~1e-15; the margin covers the near-edge cases), and
 * E_g = 1e-10 max|H| the Hessian's allowance; step h = the power of two below rho/32. */
typedef struct {
    const shl_ctx *ctx;
    const light_t *li;
} grad_arg;

static void grad_values(void *arg, const double x[3], double *out)
{
    const grad_arg *a = arg;
    static double c[NCM];
    CHECK(light_grad(a->ctx, a->li, x, c, out) == SHL_OK);
}

SHL_TEST(hess_vs_fd_check)
{
    rng_t r = {1905};
    shl_ctx *ctx;
    CHECK(shl_ctx_create(8, &ctx) == SHL_OK);
    const int nc = 81;
    static double c[NCM], g[3 * NCM], hs[6 * NCM], gh[9 * NCM];
    double worst = 0.0;
    for (int it = 0; it < 24; ++it) {
        light_t li;
        double x[3], rho;
        if (it & 1) {
            double dir[3];
            rng_unit_vector(&r, dir);
            const double d = rng_range(&r, 0.5, 4.0);
            li.sphere = 1, li.radius = d * rng_range(&r, 0.05, 0.95);
            for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0), li.center[k] = x[k] + d * dir[k];
            rho = d - li.radius;
        } else {
            random_polygon_light(&r, 3 + it % 4, it % 3 == 2, &li);
            do {
                for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.5, 1.5);
                rho = plane_distance(li.verts, li.n, x);
            } while (rho < 1e-2);
        }
        CHECK(light_hess(ctx, &li, x, c, g, hs) == SHL_OK);
        double hm = 0.0;
        for (int i = 0; i < 6; ++i)
            for (int k = 0; k < nc; ++k) {
                const int a = hia[i], b = hib[i];
                gh[a * 3 * nc + b * nc + k] = gh[b * 3 * nc + a * nc + k] = hs[i * nc + k]; /* d grad_b / dx_a */
                hm = fmax(hm, fabs(hs[i * nc + k]));
            }
        grad_arg arg = {ctx, &li};
        const double h = ldexp(1.0, ilogb(rho / 32.0));
        const fd_result fr = fd_compare(grad_values, &arg, x, h, 3 * nc, gh);
        const double ratio = fr.err / fd_bound(&fr, 1e-13 * fr.fbig, 1e-10 * hm);
        worst = fmax(worst, ratio);
        if (!(ratio <= 1.0))
            harness_fail(__FILE__, __LINE__, "case %d (%s): |H - D8| %.3g > bound %.3g", it, li.sphere ? "sphere" : "polygon",
                         fr.err, fd_bound(&fr, 1e-13 * fr.fbig, 1e-10 * hm));
    }
    harness_note("worst |H - D8| / derived bound %.2f (12 polygons, 12 spheres, lmax 8)", worst);
    shl_ctx_destroy(ctx);
}

/* ---- reference 2: band 0 from the solid angle in long double ---- */

typedef long double ld;

static ld solid_angle_polygon_ld(const light_t *li, const ld x[3])
{
    ld total = 0.0L, r[8][3], len[8];
    for (int i = 0; i < li->n; ++i) {
        for (int k = 0; k < 3; ++k) r[i][k] = (ld)li->verts[3 * i + k] - x[k];
        len[i] = sqrtl(r[i][0] * r[i][0] + r[i][1] * r[i][1] + r[i][2] * r[i][2]);
    }
    for (int i = 1; i + 1 < li->n; ++i) { /* signed Van Oosterom-Strackee fan from vertex 0 */
        const ld *a = r[0], *b = r[i], *c = r[i + 1];
        const ld det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
        const ld ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], ac = a[0] * c[0] + a[1] * c[1] + a[2] * c[2],
                 bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
        total += 2.0L * atan2l(det, len[0] * len[i] * len[i + 1] + ab * len[i + 1] + ac * len[i] + bc * len[0]);
    }
    return fabsl(total);
}

static ld solid_angle_sphere_ld(const light_t *li, const ld x[3])
{
    ld d2 = 0.0L;
    for (int k = 0; k < 3; ++k) d2 += ((ld)li->center[k] - x[k]) * ((ld)li->center[k] - x[k]);
    const ld s2 = (ld)li->radius * (ld)li->radius / d2;
    return 2.0L * (ld)M_PI * s2 / (1.0L + sqrtl(1.0L - s2)); /* 2 pi (1 - cos a) */
}

static ld omega_at(const light_t *li, const double x[3], int a, ld ha, int b, ld hb)
{
    ld y[3] = {x[0], x[1], x[2]};
    y[a] += ha, y[b] += hb;
    return li->sphere ? solid_angle_sphere_ld(li, y) : solid_angle_polygon_ld(li, y);
}

/* Second central difference d2 Omega / dx_a dx_b with step h (O(h^2) error series in h^2). */
static ld second_diff(const light_t *li, const double x[3], int a, int b, ld h)
{
    if (a == b)
        return (omega_at(li, x, a, h, b, 0.0L) - 2.0L * omega_at(li, x, a, 0.0L, b, 0.0L) + omega_at(li, x, a, -h, b, 0.0L)) /
               (h * h);
    return (omega_at(li, x, a, h, b, h) - omega_at(li, x, a, h, b, -h) - omega_at(li, x, a, -h, b, h) +
            omega_at(li, x, a, -h, b, -h)) /
           (4.0L * h * h);
}

/* Two Richardson levels on h, h/2, h/4: error O(h^6).  Rounding: each difference errs by
 * <= 4 (a few ulps of long double) |Omega| / h^2 (~1e-18 |Omega| / h^2 on x87 extended),
 * amplified <= 25x by the levels (weights (16 (4 D(h/4) - D(h/2))/3 - (4 D(h/2) - D(h))/3)/15,
 * steps h/4 squared); with h = rho/32 and |Omega| <= 4 pi: <= 3e-11 / rho^2.  Truncation by
 * Cauchy's estimate (Omega analytic in the ball of radius rho, |Omega| <= 2 pi): the O(h^6)
 * term is <= 2 (h/rho)^6 2 pi / rho^2 / 64 <= 2e-10 / rho^2. */
static ld omega_hessian(const light_t *li, const double x[3], int a, int b, ld h)
{
    const ld d0 = second_diff(li, x, a, b, h), d1 = second_diff(li, x, a, b, h / 2.0L), d2 = second_diff(li, x, a, b, h / 4.0L);
    const ld r0 = (4.0L * d1 - d0) / 3.0L, r1 = (4.0L * d2 - d1) / 3.0L;
    return (16.0L * r1 - r0) / 15.0L;
}

static void band0_case(const light_t *li, const double x[3], double rho, double *err, double *trace)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    const int nc = 9;
    double c[9], g[27], hs[54], m = 0.0, e = 0.0;
    CHECK(light_hess(ctx, li, x, c, g, hs) == SHL_OK);
    const double y00 = 0.5 / sqrt(M_PI);
    for (int i = 0; i < 6; ++i) {
        const double want = (double)omega_hessian(li, x, hia[i], hib[i], (ld)rho / 32.0L) * y00;
        m = fmax(m, fabs(hs[i * nc]));
        e = fmax(e, fabs(hs[i * nc] - want));
    }
    *err = e / m;
    *trace = fabs(hs[0] + hs[3 * nc] + hs[5 * nc]) / m;
    shl_ctx_destroy(ctx);
}

SHL_TEST(hess_band0_vs_solid_angle)
{
    /* Reference error (above) <= 2.3e-10 / rho^2 absolute; |H_00| ~ Y_00 |Omega| / rho^2 and the
     * cases keep |Omega| >= 1e-2 (rho <= size): relative <= ~1e-7 in the worst case, ~1e-11 typically.
     * Tolerance 1e-8 of max |H_00|: the analytic value's rounding (~1e-13 measured) plus a margin for
     * the reference, whose actual error is measured by the spread below. */
    if (LDBL_MANT_DIG < 64) {
        harness_note("skipped: long double has %d mantissa bits (the reference needs >= 64)", LDBL_MANT_DIG);
        return;
    }
    rng_t r = {1903};
    double worst_p = 0.0, worst_s = 0.0, worst_trace = 0.0;
    for (int it = 0; it < 16; ++it) {
        light_t li;
        random_polygon_light(&r, 3 + it % 4, it % 3 == 2, &li);
        double x[3], rho;
        do {
            for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0);
            rho = plane_distance(li.verts, li.n, x);
        } while (rho < 5e-2);
        double e, tr;
        band0_case(&li, x, rho, &e, &tr);
        worst_p = fmax(worst_p, e), worst_trace = fmax(worst_trace, tr);
        CHECK(e <= 1e-8);
        CHECK(tr <= 1e-11); /* exact 0: rounding of the boundary sums, ~eps x (edges) x (r / size) */
    }
    for (int it = 0; it < 16; ++it) {
        light_t li = {.sphere = 1};
        double dir[3], x[3];
        rng_unit_vector(&r, dir);
        const double d = rng_range(&r, 0.5, 4.0);
        li.radius = d * rng_range(&r, 0.05, 0.95);
        for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0), li.center[k] = x[k] + d * dir[k];
        double e, tr;
        band0_case(&li, x, d - li.radius, &e, &tr);
        worst_s = fmax(worst_s, e);
        CHECK(e <= 1e-8);
    }
    harness_note("band 0 vs long-double solid angle: polygons %.1e, spheres %.1e; polygon trace %.1e (of max|H_00|)", worst_p,
                 worst_s, worst_trace);
}

/* ---- consistency, scaling, special points ---- */

SHL_TEST(hess_values_match_gradient_functions)
{
    rng_t r = {1904};
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LM, &ctx) == SHL_OK);
    const int nc = NCM;
    static double c1[NCM], g1[3 * NCM], c2[NCM], g2[3 * NCM], h[6 * NCM];
    double worst = 0.0;
    for (int it = 0; it < 8; ++it) {
        light_t li;
        random_polygon_light(&r, 3 + it % 4, it & 1, &li);
        const double x[3] = {rng_range(&r, -1, 1), rng_range(&r, -1, 1), rng_range(&r, -1, 1)};
        CHECK(shl_polygon_grad(ctx, x, li.verts, li.n, c1, g1) == SHL_OK);
        CHECK(shl_polygon_hess(ctx, x, li.verts, li.n, c2, g2, h) == SHL_OK);
        double m = 0.0, e = 0.0;
        for (int k = 0; k < nc; ++k) m = fmax(m, fabs(c1[k])), e = fmax(e, fabs(c1[k] - c2[k]));
        worst = fmax(worst, e / m);
        m = e = 0.0;
        for (int k = 0; k < 3 * nc; ++k) m = fmax(m, fabs(g1[k])), e = fmax(e, fabs(g1[k] - g2[k]));
        worst = fmax(worst, e / m);
        /* the sphere's coefficients and gradient are shl_sphere_grad's, bit for bit */
        const double cen[3] = {x[0] + 1.0, x[1] - 0.5, x[2] + 0.25};
        CHECK(shl_sphere_grad(ctx, x, cen, 0.4, c1, g1) == SHL_OK);
        CHECK(shl_sphere_hess(ctx, x, cen, 0.4, c2, g2, h) == SHL_OK);
        CHECK(memcmp(c1, c2, sizeof c1) == 0 && memcmp(g1, g2, sizeof g1) == 0);
    }
    /* the same recurrence sums in the same order: equal up to the compiler's contraction */
    CHECK(worst <= 1e-15);
    harness_note("polygon coeffs/grad vs shl_polygon_grad: %.1e (of max)", worst);
    shl_ctx_destroy(ctx);
}

SHL_TEST(hess_scaling_and_translation)
{
    /* Scaling x and the light by 2^s scales the Hessian by 2^-2s: the kernels work in
     * scaled units (a power of two commutes with every rounding), so up to underflow the
     * results agree to rounding; 2^+-300 takes the squared distances beyond the double range. */
    shl_ctx *ctx;
    CHECK(shl_ctx_create(8, &ctx) == SHL_OK);
    const int nc = 81;
    const double v[12] = {0.1, -0.2, 1.0, 1.1, 0.0, 1.2, 0.9, 0.8, 0.9, -0.1, 0.7, 1.0};
    const double x[3] = {0.3, 0.1, -0.2}, cen[3] = {0.2, 1.5, 0.4};
    double c0[81], g0[243], h0[486], c1[81], g1[243], h1[486];
    double worst = 0.0;
    for (int kind = 0; kind < 2; ++kind) {
        if (kind == 0)
            CHECK(shl_polygon_hess(ctx, x, v, 4, c0, g0, h0) == SHL_OK);
        else
            CHECK(shl_sphere_hess(ctx, x, cen, 0.3, c0, g0, h0) == SHL_OK);
        double m = 0.0;
        for (int k = 0; k < 6 * nc; ++k) m = fmax(m, fabs(h0[k]));
        const int sc[2] = {-300, 300};
        for (int si = 0; si < 2; ++si) {
            double xs[3], vs[12], cs[3];
            for (int k = 0; k < 3; ++k) xs[k] = ldexp(x[k], sc[si]), cs[k] = ldexp(cen[k], sc[si]);
            for (int k = 0; k < 12; ++k) vs[k] = ldexp(v[k], sc[si]);
            if (kind == 0)
                CHECK(shl_polygon_hess(ctx, xs, vs, 4, c1, g1, h1) == SHL_OK);
            else
                CHECK(shl_sphere_hess(ctx, xs, cs, ldexp(0.3, sc[si]), c1, g1, h1) == SHL_OK);
            for (int k = 0; k < 6 * nc; ++k) worst = fmax(worst, fabs(ldexp(h1[k], 2 * sc[si]) - h0[k]) / m);
        }
    }
    CHECK(worst <= 1e-13);
    harness_note("Hessian at 2^+-300 scale vs unscaled: %.1e (of max)", worst);
    shl_ctx_destroy(ctx);
}

SHL_TEST(hess_edge_seen_end_on)
{
    /* x close to the line of an edge, far from the edge (r/rho = 3e2 .. 3e5): the Hessian is
     * invariant under translating x and the light together, so the spread over translations
     * (which round the inputs differently) measures its rounding error: the recurrence's
     * G2 B_l and |g| I_l terms gave 1.8e-5 of max|H| at r/rho = 3e5 before those edges went to
     * the Gauss rule (polygon_hess.c, NEAR_RADIAL); now a few eps times the growth of H over
     * the input's rounding (rho/r ~ 1e-5 of eps |x| / rho: below 1e-12). */
    shl_ctx *ctx;
    CHECK(shl_ctx_create(8, &ctx) == SHL_OK);
    const int nc = 81;
    const double v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    static double c[81], g[243], h0[486], h1[486];
    double worst = 0.0;
    const double offs[3] = {1e-2, 1e-3, 1e-5};
    for (int p = 0; p < 3; ++p) {
        const double x[3] = {3.0, offs[p], 0.5 * offs[p]}; /* beyond v_1 on the line of edge (v_0, v_1) */
        CHECK(shl_polygon_hess(ctx, x, v, 4, c, g, h0) == SHL_OK);
        double m = 0.0;
        for (int k = 0; k < 6 * nc; ++k) m = fmax(m, fabs(h0[k]));
        for (int t = 1; t < 12; ++t) {
            const double sh[3] = {0.1234567 * t, -0.0987654 * t, 0.0555555 * t};
            double vs[12], xs[3];
            for (int i = 0; i < 12; ++i) vs[i] = v[i] + sh[i % 3];
            for (int k = 0; k < 3; ++k) xs[k] = x[k] + sh[k];
            CHECK(shl_polygon_hess(ctx, xs, vs, 4, c, g, h1) == SHL_OK);
            for (int k = 0; k < 6 * nc; ++k) worst = fmax(worst, fabs(h1[k] - h0[k]) / m);
        }
    }
    CHECK(worst <= 1e-12);
    harness_note("translation spread of H / max|H| at r/rho up to 3e5: %.1e", worst);
    shl_ctx_destroy(ctx);
}

SHL_TEST(hess_special_points)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(6, &ctx) == SHL_OK);
    const int nc = 49;
    double c[49], g[147], h[294];
    const double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    /* in the polygon's plane (inside and outside the polygon): everything 0 */
    const double inplane[2][3] = {{0.2, 0.2, 0.0}, {2.0, 3.0, 0.0}};
    for (int p = 0; p < 2; ++p) {
        CHECK(shl_polygon_hess(ctx, inplane[p], v, 3, c, g, h) == SHL_OK);
        int zero = 1;
        for (int k = 0; k < nc; ++k) zero &= c[k] == 0.0;
        for (int k = 0; k < 3 * nc; ++k) zero &= g[k] == 0.0;
        for (int k = 0; k < 6 * nc; ++k) zero &= h[k] == 0.0;
        CHECK(zero);
    }
    /* close to an edge (1e-6 off its midpoint, off the plane): finite, growing like 1/distance^2 */
    const double near_edge[3] = {0.5, -1e-6, 1e-6};
    CHECK(shl_polygon_hess(ctx, near_edge, v, 3, c, g, h) == SHL_OK);
    CHECK(all_finite(h, 6 * nc) && all_finite(g, 3 * nc));
    double m = 0.0;
    for (int k = 0; k < 6 * nc; ++k) m = fmax(m, fabs(h[k]));
    CHECK(m > 1e9 && m < 1e14);
    harness_note("max|H| at 1.4e-6 from an edge: %.1e", m);
    /* inside and on a sphere: constant, grad and hess 0 */
    const double cen[3] = {0, 0, 0}, in[2][3] = {{0.1, 0.2, 0.3}, {1.0, 0.0, 0.0}};
    for (int p = 0; p < 2; ++p) {
        CHECK(shl_sphere_hess(ctx, in[p], cen, 1.0, c, g, h) == SHL_OK);
        int ok = c[0] == sqrt(4.0 * M_PI);
        for (int k = 1; k < nc; ++k) ok &= c[k] == 0.0;
        for (int k = 0; k < 3 * nc; ++k) ok &= g[k] == 0.0;
        for (int k = 0; k < 6 * nc; ++k) ok &= h[k] == 0.0;
        CHECK(ok);
    }
    /* just outside the surface: finite */
    const double out[3] = {1.0 + 1e-9, 0.0, 0.0};
    CHECK(shl_sphere_hess(ctx, out, cen, 1.0, c, g, h) == SHL_OK);
    CHECK(all_finite(h, 6 * nc));
    shl_ctx_destroy(ctx);
}

SHL_TEST(hess_lights_vs_single)
{
    /* The set adds rgb_c times each light's values; it sums lobe integrals before the
     * (linear) reconstruction, so it agrees to rounding: a few eps of the largest term. */
    shl_ctx *ctx;
    shl_lights *set;
    CHECK(shl_ctx_create(8, &ctx) == SHL_OK);
    CHECK(shl_lights_create(&set) == SHL_OK);
    const int nc = 81;
    const double quad[12] = {-1, -1, 2, 1, -1, 2, 1, 1, 2.2, -1, 1, 2.2};       /* two-sided */
    const double tri[9] = {0, -2, -1, 2, -2, -1, 0, -2, 1};                       /* one-sided, facing -y */
    const double cen[3] = {2.0, 1.0, 0.5}, rgb_q[3] = {1.0, 0.5, 0.25}, rgb_t[3] = {0.3, 2.0, 1.0}, rgb_s[3] = {4.0, 1.0, 0.5};
    CHECK(shl_lights_add_polygon(set, quad, 4, rgb_q, 1) == SHL_OK);
    CHECK(shl_lights_add_polygon(set, tri, 3, rgb_t, 0) == SHL_OK);
    CHECK(shl_lights_add_sphere(set, cen, 0.4, rgb_s) == SHL_OK);
    static double rgb[3 * 81], grad[9 * 81], hess[18 * 81], c[81], g[243], h[486], want[18 * 81];
    const double pts[2][3] = {{0.1, 0.2, 0.3}, {0.5, -2.5, 0.0}}; /* tri's front: y < -2 */
    double worst = 0.0;
    for (int p = 0; p < 2; ++p) {
        CHECK(shl_lights_eval_hess(ctx, set, pts[p], rgb, grad, hess) == SHL_OK);
        memset(want, 0, sizeof want);
        double tri_n[3] = {0, 0, 0};
        const double e1[3] = {2, 0, 0}, e2[3] = {0, 0, 2};
        tri_n[0] = e1[1] * e2[2] - e1[2] * e2[1], tri_n[1] = e1[2] * e2[0] - e1[0] * e2[2], tri_n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        const int tri_front = tri_n[0] * (pts[p][0] - tri[0]) + tri_n[1] * (pts[p][1] - tri[1]) + tri_n[2] * (pts[p][2] - tri[2]) > 0;
        for (int li = 0; li < 3; ++li) {
            const double *w = li == 0 ? rgb_q : li == 1 ? rgb_t : rgb_s;
            if (li == 0) CHECK(shl_polygon_hess(ctx, pts[p], quad, 4, c, g, h) == SHL_OK);
            if (li == 1) {
                if (!tri_front) continue;
                CHECK(shl_polygon_hess(ctx, pts[p], tri, 3, c, g, h) == SHL_OK);
            }
            if (li == 2) CHECK(shl_sphere_hess(ctx, pts[p], cen, 0.4, c, g, h) == SHL_OK);
            for (int ch = 0; ch < 3; ++ch)
                for (int k = 0; k < 6 * nc; ++k) want[ch * 6 * nc + k] += w[ch] * h[k];
        }
        double m = 0.0, e = 0.0;
        for (int k = 0; k < 18 * nc; ++k) m = fmax(m, fabs(want[k])), e = fmax(e, fabs(hess[k] - want[k]));
        worst = fmax(worst, e / m);
        CHECK(all_finite(rgb, 3 * nc) && all_finite(grad, 9 * nc));
    }
    CHECK(worst <= 1e-13);
    harness_note("light set vs sum of single lights: %.1e (of max|H|)", worst);
    /* rgb and grad are those of shl_lights_eval to rounding */
    static double rgb2[3 * 81], grad2[9 * 81];
    CHECK(shl_lights_eval(ctx, set, pts[1], rgb2, grad2) == SHL_OK);
    CHECK(shl_lights_eval_hess(ctx, set, pts[1], rgb, grad, hess) == SHL_OK);
    double m = 0.0, e = 0.0;
    for (int k = 0; k < 9 * nc; ++k) m = fmax(m, fabs(grad2[k])), e = fmax(e, fabs(grad[k] - grad2[k]));
    for (int k = 0; k < 3 * nc; ++k) e = fmax(e, fabs(rgb[k] - rgb2[k]));
    CHECK(e <= 1e-13 * m);
    shl_lights_destroy(set);
    shl_ctx_destroy(ctx);
}

/* ---- the kernels of every ISA against the scalar reference ---- */

/* shl_polygon_hess with the scalar reference (src/polygon_hess.c) in place of the ISA's
 * kernels (simd/poly_hess_batch.h): the entry point's steps otherwise unchanged. */
static void polygon_hess_reference(int lmax, const double x[3], const double *verts, int n, double *c, double *g,
                                   double *h)
{
    const int nc = SHL_NCOEFFS(lmax);
    shl__poly_geom geo;
    static double z10[SHL__Z10_SIZE(SHL_LMAX_MAX)];
    shl__poly_geom_init(&geo, x, verts, n);
    const int fold = shl__poly_hess_fold(&geo);
    shl__poly_zh_hess_d(&geo, lmax, z10, fold);
    double *const out[SHL__ZH_MULTI] = {c, g, g + nc, g + 2 * nc, h, h + nc, h + 2 * nc, h + 3 * nc, h + 4 * nc, h + 5 * nc};
    shl__zh_to_sh_multi(lmax, z10, out);
    if (!fold) {
        shl__poly_grad_unscale(&geo, g, 3 * nc);
        shl__poly_grad_unscale(&geo, h, 6 * nc);
        shl__poly_grad_unscale(&geo, h, 6 * nc);
    }
}

SHL_TEST(hess_isa_kernels_match_reference)
{
    /* Every lane of the vector kernels does the reference's one-lobe arithmetic in the same
     * order, with no fused multiply-add (simd/poly_hess_batch.h), and the reconstruction the
     * same sums in the same order: the bits must be equal, no tolerance.  Cases: random
     * polygons (3-8 vertices, convex and concave), every lmax 0..30 (2 lmax + 1 lobes: full
     * and partial last blocks of 2, 4 and 8 lanes), an edge seen end-on (the Gauss rule's
     * path), a near-plane sliver (area rule for the coefficients), a 2^600 scale (unfolded
     * 2^-E). */
    static double c0[SHL_NCOEFFS(SHL_LMAX_MAX)], g0[3 * SHL_NCOEFFS(SHL_LMAX_MAX)], h0[6 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    static double c1[SHL_NCOEFFS(SHL_LMAX_MAX)], g1[3 * SHL_NCOEFFS(SHL_LMAX_MAX)], h1[6 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    const double square[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    int ncase = 0, nisa = 0, differ = 0;
    for (int i = 0; i < NISA; ++i) {
        int ran = 0;
        for (int lmax = 0; lmax <= SHL_LMAX_MAX; ++lmax) {
            shl_ctx *ctx = isa_ctx(isas[i], lmax);
            if (!ctx) continue;
            ran = 1;
            const int nc = SHL_NCOEFFS(lmax);
            rng_t r = {7000u + (unsigned)lmax};
            for (int it = 0; it < 7; ++it) {
                light_t li;
                double x[3];
                if (it < 4) {
                    random_polygon_light(&r, 3 + (it + lmax) % 6, it & 1, &li);
                    for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1, 1);
                } else { /* the unit square: edge (v0, v1) seen end-on (and a sliver), a sliver, 2^600 scale */
                    li.sphere = 0, li.n = 4;
                    memcpy(li.verts, square, sizeof square);
                    const double xs[3][3] = {{3.0, 1e-5, 5e-6}, {4.0, 3.0, 1e-9}, {0.3, 0.4, 0.7}};
                    memcpy(x, xs[it - 4], sizeof x);
                    if (it == 6)
                        for (int k = 0; k < 12; ++k) li.verts[k] = ldexp(li.verts[k], 600), x[k % 3] = ldexp(xs[2][k % 3], 600);
                }
                CHECK(shl_polygon_hess(ctx, x, li.verts, li.n, c1, g1, h1) == SHL_OK);
                polygon_hess_reference(lmax, x, li.verts, li.n, c0, g0, h0);
                differ += memcmp(c0, c1, sizeof(double) * nc) != 0 || memcmp(g0, g1, sizeof(double) * 3 * nc) != 0 ||
                          memcmp(h0, h1, sizeof(double) * 6 * nc) != 0;
                ncase += 1;
            }
            shl_ctx_destroy(ctx);
        }
        nisa += ran;
    }
    CHECK(differ == 0 && nisa > 0);
    harness_note("%d cases (lmax 0..%d) x %d ISAs: %d differ from the scalar reference in any bit", nisa ? ncase / nisa : 0, SHL_LMAX_MAX,
                 nisa, differ);
}

/* ---- the sphere's Hessian through its lobe integrals (an independent route) ---- */

/* The route of README "Hessians" (S2)-(S4): lobe d, band l of the cap is Z = K_l W P_l(z),
 * z = dir_d . u, whose second derivatives are
 *   d2Z/dx2 / K_l = A u u^T + B (I - u u^T) + C (u tau^T + tau u^T) + D tau tau^T,  tau = dir_d - z u,
 *   A = W'' P_l,  B = (W' P_l - W z P_l'/dist)/dist,  C = P_l' (W' - W/dist)/dist,  D = W P_l''/dist^2,
 * (W' = w' k, W'' = w'' k^2 + w' phi'' of (S1)), reconstructed by Wang Eq. 33
 * (shl__zh_to_sh_multi, blocks 4..9): it shares only (S1) and the cap weights with the
 * direct kernel (shl__sphere_sh_hess).  x outside, geometry unscaled. */
static void sphere_hess_via_lobes(int lmax, const shl__sphere_geom *g, double *hess)
{
    static double z10[SHL__Z10_SIZE(SHL_LMAX_MAX)], blk[4][SHL_NCOEFFS(SHL_LMAX_MAX)];
    const int nc = SHL_NCOEFFS(lmax);
    const double id = g->inv_d, k = g->k_alpha, phi2 = -k * id * (3.0 + g->s2 / (g->c * g->c));
    double w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1], pc[SHL_LMAX_MAX + 2], dpc[SHL_LMAX_MAX + 2];
    shl__cap_weights_d(lmax, g->t, g->s2, g->c, w, dw);
    pc[0] = 1.0, pc[1] = g->c, dpc[0] = 0.0, dpc[1] = 1.0; /* P_l(c), P_l'(c) */
    for (int l = 1; l <= lmax; ++l)
        pc[l + 1] = ((2.0 * l + 1.0) * g->c * pc[l] - l * pc[l - 1]) / (l + 1.0), dpc[l + 1] = dpc[l - 1] + (2.0 * l + 1.0) * pc[l];
    for (int d = 0; d <= 2 * lmax; ++d) {
        const double *dir = shl__zh_dir[d], *u = g->u;
        const double z = dir[0] * u[0] + dir[1] * u[1] + dir[2] * u[2];
        const double tau[3] = {dir[0] - z * u[0], dir[1] - z * u[1], dir[2] - z * u[2]};
        double p[SHL_LMAX_MAX + 2], dp[SHL_LMAX_MAX + 2], d2p[SHL_LMAX_MAX + 2]; /* P_l, P_l', P_l'' at z */
        p[0] = 1.0, p[1] = z, dp[0] = 0.0, dp[1] = 1.0, d2p[0] = d2p[1] = 0.0;
        for (int l = 1; l <= lmax; ++l) {
            p[l + 1] = ((2.0 * l + 1.0) * z * p[l] - l * p[l - 1]) / (l + 1.0);
            dp[l + 1] = dp[l - 1] + (2.0 * l + 1.0) * p[l], d2p[l + 1] = d2p[l - 1] + (2.0 * l + 1.0) * dp[l];
        }
        for (int l = 0; l <= lmax; ++l) {
            const double kl = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)), w1 = dw[l] * k;
            const double w2 = -2.0 * M_PI * dpc[l] * k * k + dw[l] * phi2;
            const double A = w2 * p[l], B = (w1 * p[l] - w[l] * z * dp[l] * id) * id;
            const double C = dp[l] * (w1 - w[l] * id) * id, D = w[l] * d2p[l] * id * id;
            double *o = z10 + SHL__Z10(lmax, d, l);
            for (int b = 0; b < 4; ++b) o[b] = 0.0; /* value and gradient blocks unused */
            for (int i = 0; i < 6; ++i) {
                const int a = hia[i], c = hib[i];
                o[4 + i] = kl * (A * u[a] * u[c] + B * ((a == c) - u[a] * u[c]) + C * (u[a] * tau[c] + tau[a] * u[c]) +
                                 D * tau[a] * tau[c]);
            }
        }
    }
    double *const out[SHL__ZH_MULTI] = {blk[0], blk[1], blk[2], blk[3], hess, hess + nc, hess + 2 * nc, hess + 3 * nc,
                                        hess + 4 * nc, hess + 5 * nc};
    shl__zh_to_sh_multi(lmax, z10, out);
}

/* shl_sphere_hess (directly in the SH basis, (S5)-(S7)) against the lobe route at every
 * lmax 0..30, including points near the surface (cos a -> 0, phi'' ~ 1/cos^3 a).  The two
 * routes share (S1) and the cap weights and differ in rounding only.  Per lobe entry the lobe
 * route sums four terms of about ten roundings each (P_l, P_l', P_l'' by their recurrences:
 * a few eps times l), <= ~50 eps of max|H| for l <= 30; Wang Eq. 33 amplifies lobe errors by
 * the band's condition number, <= 100 (shl__zh_cond, test zh_condition_numbers): ~5000 eps =
 * 1.1e-12.  The direct kernel's own rounding (a few eps per output, relative to the terms it
 * sums) is far below that.  Tolerance 2e-12 of max|H|. */
SHL_TEST(hess_sphere_direct_vs_lobes)
{
    static double c[SHL_NCOEFFS(SHL_LMAX_MAX)], g[3 * SHL_NCOEFFS(SHL_LMAX_MAX)], h[6 * SHL_NCOEFFS(SHL_LMAX_MAX)],
        ref[6 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    rng_t r = {4242};
    double worst = 0.0;
    for (int lmax = 0; lmax <= SHL_LMAX_MAX; ++lmax) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
        const int nc = SHL_NCOEFFS(lmax);
        for (int it = 0; it < 6; ++it) {
            double dir[3], x[3], cen[3];
            rng_unit_vector(&r, dir);
            const double d = rng_range(&r, 0.5, 4.0), rad = d * (it % 3 == 2 ? rng_range(&r, 0.95, 0.999) : rng_range(&r, 0.01, 0.9));
            for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0), cen[k] = x[k] + d * dir[k];
            CHECK(shl_sphere_hess(ctx, x, cen, rad, c, g, h) == SHL_OK);
            shl__sphere_geom sg;
            shl__sphere_geom_init(&sg, x, cen, rad);
            sphere_hess_via_lobes(lmax, &sg, ref);
            double m = 0.0, e = 0.0;
            for (int k = 0; k < 6 * nc; ++k) m = fmax(m, fabs(ref[k])), e = fmax(e, fabs(h[k] - ref[k]));
            worst = fmax(worst, e / m);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(worst <= 2e-12);
    harness_note("direct SH Hessian vs the lobe route (S4), lmax 0..%d: %.1e of max|H|", SHL_LMAX_MAX, worst);
}

/* Band 0 of a sphere seen from x in closed form, long double (x87: exponent range to 1e-4951,
 * so r^2 and d^4 below 1e-600 are exact to 64 bits): L_00 = sqrt(pi) F(d), F = 1 - cos a,
 * cos a = s/d, s = sqrt(d^2 - r^2) (HVL Eq. 14, l = 0), F' = -r^2/(d^2 s),
 * F'' = r^2 (2/(d^3 s) + 1/(d s^3)); with v = center - x, u = v/d:
 *   grad L_00 = -sqrt(pi) F' u,   H L_00 = sqrt(pi) (F'' u u^T + (F'/d)(I - u u^T)). */
static void l00_hess_ref(const double x[3], const double c[3], double r, long double g[3], long double h[6])
{
    long double v[3], d2 = 0.0L;
    for (int k = 0; k < 3; ++k) v[k] = (long double)c[k] - x[k], d2 += v[k] * v[k];
    const long double d = sqrtl(d2), rr = (long double)r * r, s = sqrtl(d2 - rr), sp = sqrtl((long double)M_PI);
    const long double f1 = -rr / (d2 * s), f2 = rr * (2.0L / (d2 * d * s) + 1.0L / (d * s * s * s));
    for (int a = 0; a < 3; ++a) g[a] = -sp * f1 * v[a] / d;
    for (int i = 0; i < 6; ++i) {
        const long double uu = v[hia[i]] * v[hib[i]] / d2;
        h[i] = sp * (f2 * uu + f1 / d * ((hia[i] == hib[i]) - uu));
    }
}

/* sin^2 a = (r/d)^2 below the smallest normal (r/d < 2^-511; the gradient's fuzz reproducer
 * fuzz_lights-sphere-sin2-underflow-gradient and random geometry): the coefficients are
 * subnormal but the Hessian (~r^2/d^4) is a normal number and must keep full relative
 * accuracy in shl_sphere_hess and shl_lights_eval_hess.  Error analysis of band 0 (first
 * order, eps = DBL_EPSILON/2 per rounding), from the set-up's errors as in
 * sphere_sin2_underflow_gradient (test_sphere.c: u_k 3.25 eps, 1/d 2.25, s2_x 6, k_x 9.25):
 * phi'' 14 eps, W'' = w' phi'' 15, bet = w' k / d 13, and with K_0 b0 = bet K_0 14, mu =
 * W'' K_0 - b0 16.5 (W'' K_0 ~ 3 units and -b0 ~ 1 unit add: no cancellation).  Output
 * (a, b) = b0 [a == b] + mu u_a u_b: error <= 15 |b0| [a == b] + 26 |mu| |u_a u_b|, in
 * Frobenius norm <= 15 sqrt3 |b0| + 26 |mu| = 130 units eps against |H| = sqrt(3^2 + 2) =
 * 3.3 units: 39 eps = 20 DBL_EPSILON; the power-of-two rescale is exact (the Hessian is normal
 * here) and the long-double reference good to 2^-63.  The light set adds rgb = 1 times the
 * same values: the same bound.  Gradients (in the set now those of shl_sphere_grad): 8
 * DBL_EPSILON, as there.  Before the fix: O(1) error. */
SHL_TEST(hess_sphere_sin2_underflow)
{
    static double co[SHL_NCOEFFS(9)], g[3 * SHL_NCOEFFS(9)], h[6 * SHL_NCOEFFS(9)], rgb[3 * SHL_NCOEFFS(9)],
            lg[9 * SHL_NCOEFFS(9)], lh[18 * SHL_NCOEFFS(9)];
    rng_t rg = {1919};
    double worst_h = 0.0, worst_lh = 0.0, worst_lg = 0.0;
    for (int lmax = 0; lmax <= 9; lmax += 3) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
        const int nc = SHL_NCOEFFS(lmax);
        for (int it = 0; it < 40; ++it) {
            double x[3], c[3];
            const double rad = tiny_sphere_case(&rg, it == 0, x, c);
            long double gref[3], href[6];
            l00_hess_ref(x, c, rad, gref, href);
            CHECK(shl_sphere_hess(ctx, x, c, rad, co, g, h) == SHL_OK);
            worst_h = fmax(worst_h, rel_norm_err(h, nc, href, 6));
            const double one[3] = {1.0, 1.0, 1.0};
            shl_lights *set;
            CHECK(shl_lights_create(&set) == SHL_OK && shl_lights_add_sphere(set, c, rad, one) == SHL_OK);
            CHECK(shl_lights_eval_hess(ctx, set, x, rgb, lg, lh) == SHL_OK);
            shl_lights_destroy(set);
            worst_lh = fmax(worst_lh, rel_norm_err(lh, nc, href, 6)); /* channel 0: (0*6 + i)*nc */
            worst_lg = fmax(worst_lg, rel_norm_err(lg, nc, gref, 3));
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(worst_h <= 20.0 * DBL_EPSILON && worst_lh <= 20.0 * DBL_EPSILON && worst_lg <= 8.0 * DBL_EPSILON);
    harness_note("r/d 2^-512..2^-590, band-0 Hessian rel err (Frobenius) vs closed form: shl_sphere_hess %.1f eps, "
                 "shl_lights_eval_hess %.1f eps (its gradient %.1f eps)",
                 worst_h / DBL_EPSILON, worst_lh / DBL_EPSILON, worst_lg / DBL_EPSILON);
}

SHL_TEST(hess_bad_input)
{
    shl_ctx *ctx;
    shl_lights *set;
    CHECK(shl_ctx_create(4, &ctx) == SHL_OK);
    CHECK(shl_lights_create(&set) == SHL_OK);
    enum { N = 25 };
    double c[N], g[3 * N], h[6 * N], rgb[3 * N], gr[9 * N], hs[18 * N];
    const double v[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1}, x[3] = {0.1, 0.1, 0.0}, cen[3] = {0, 0, 3};
    const double nan_x[3] = {0.0, NAN, 0.0}, inf_v[9] = {0, 0, 1, INFINITY, 0, 1, 0, 1, 1};
    guard_fill(c, N), guard_fill(g, 3 * N), guard_fill(h, 6 * N);
    guard_fill(rgb, 3 * N), guard_fill(gr, 9 * N), guard_fill(hs, 18 * N);
    CHECK(shl_polygon_hess(NULL, x, v, 3, c, g, h) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, NULL, v, 3, c, g, h) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, x, NULL, 3, c, g, h) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, x, v, 3, NULL, g, h) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, x, v, 3, c, NULL, h) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, x, v, 3, c, g, NULL) == SHL_ENULL);
    CHECK(shl_polygon_hess(ctx, x, v, 2, c, g, h) == SHL_ENVERTS);
    CHECK(shl_polygon_hess(ctx, x, v, SHL_MAX_VERTS + 1, c, g, h) == SHL_ENVERTS);
    CHECK(shl_polygon_hess(ctx, nan_x, v, 3, c, g, h) == SHL_ENONFINITE);
    CHECK(shl_polygon_hess(ctx, x, inf_v, 3, c, g, h) == SHL_ENONFINITE);
    CHECK(shl_sphere_hess(NULL, x, cen, 1.0, c, g, h) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, NULL, cen, 1.0, c, g, h) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, x, NULL, 1.0, c, g, h) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, x, cen, 1.0, NULL, g, h) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, x, cen, 1.0, c, NULL, h) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, x, cen, 1.0, c, g, NULL) == SHL_ENULL);
    CHECK(shl_sphere_hess(ctx, nan_x, cen, 1.0, c, g, h) == SHL_ENONFINITE);
    CHECK(shl_sphere_hess(ctx, x, cen, INFINITY, c, g, h) == SHL_ENONFINITE);
    CHECK(shl_sphere_hess(ctx, x, cen, NAN, c, g, h) == SHL_ENONFINITE);
    CHECK(shl_sphere_hess(ctx, x, cen, 0.0, c, g, h) == SHL_EDOMAIN);
    CHECK(shl_sphere_hess(ctx, x, cen, -1.0, c, g, h) == SHL_EDOMAIN);
    CHECK(shl_lights_eval_hess(NULL, set, x, rgb, gr, hs) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, NULL, x, rgb, gr, hs) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, set, NULL, rgb, gr, hs) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, set, x, NULL, gr, hs) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, set, x, rgb, NULL, hs) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, set, x, rgb, gr, NULL) == SHL_ENULL);
    CHECK(shl_lights_eval_hess(ctx, set, nan_x, rgb, gr, hs) == SHL_ENONFINITE);
    shl__alloc_fail_after = 0; /* the per-call workspace */
    const int st = shl_lights_eval_hess(ctx, set, x, rgb, gr, hs);
    shl__alloc_fail_after = -1;
    CHECK(st == SHL_ENOMEM);
    CHECK(guard_intact(c, N) && guard_intact(g, 3 * N) && guard_intact(h, 6 * N));
    CHECK(guard_intact(rgb, 3 * N) && guard_intact(gr, 9 * N) && guard_intact(hs, 18 * N));
    /* an empty set: zeros */
    CHECK(shl_lights_eval_hess(ctx, set, x, rgb, gr, hs) == SHL_OK);
    int zero = 1;
    for (int k = 0; k < 18 * N; ++k) zero &= hs[k] == 0.0;
    CHECK(zero);
    shl_lights_destroy(set);
    shl_ctx_destroy(ctx);
}
