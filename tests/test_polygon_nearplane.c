/* Points near a polygon's plane, away from its edges (issue 18): solid angle and
 * coefficients relative to the solid angle, against references independent of
 * src/polygon.c and accurate however small the height h is:
 *  - solid angle: Van Oosterom-Strackee over the fan from vertex 0 of a convex
 *    polygon seen from outside its footprint.  Every triangle then has the same
 *    sign (no cancellation between terms); the triple product R0 . (Ri x Rj) = O(h)
 *    and the denominator are formed in double-double from the exact differences
 *    v - x (TwoSum), so they are accurate to ~30 |R|^3 eps^2 absolute, i.e. relative
 *    <= 1e-18 at h = 1e-12 (the denominator is O(|R|^3) here), and atan is accurate
 *    to an ulp: relative error of the reference <= ~3 eps = 7e-16.
 *  - coefficients: tensor Gauss-Legendre on the square in its own plane coordinates,
 *    dw = h dA / r^3, Y_lm from ref_sh_eval_grad (tests/ref_quad.c), h from a
 *    double-double plane distance.  The foot of x is >= 2 (axis case) / 1.5 (tilted)
 *    from the square, i.e. >= 2 panel widths away with 4 x 4 panels, so the
 *    integrand is analytic in each panel's Bernstein ellipse rho >= 4 + sqrt(15)
 *    per direction: 24 nodes per panel leave a rule error ~ rho^-48 ~ 1e-43, i.e.
 *    rounding only (~ 1e-15 of the solid angle for 9216 positive-weight terms).
 *    Near an edge the panels shrink to <= 1.25 x the foot's distance: rho >= 5,
 *    rho^-48 ~ 1e-33.
 * Inputs: square (+-1, +-1, 0) with x = (3, 0.5, h) (all v - x exact), and a tilted
 * square exactly planar in doubles: plane normal (1,2,2)/3, edges along the integer
 * vectors U = (2,1,-2), W = (2,-2,1) (mutually orthogonal with the normal), vertices
 * c + (+-U +- W)/4 exact, x = c + (3U + W/2)/4 + h n rounded (its own exact height is
 * recomputed in double-double).  Tolerances are the targets: 1e-13 (solid
 * angle, h in [1e-12, 1e-3]) and 1e-12 of the solid angle (lmax 8 and 14, h in
 * [1e-9, 1e-3], plus h = 0.05, 0.03, 0.02 around the switch between the boundary
 * recurrence and the planar rule at |h| = dmin / 64); the references' own errors
 * above are 100x below them. */
#include "harness.h"
#include "ref_quad.h"
#include "shlight.h"
#include <float.h>
#include <math.h>
#include <string.h>

typedef struct {
    double hi, lo;
} tdd;

static tdd t_two_sum(double a, double b)
{
    const double s = a + b, bb = s - a;
    return (tdd){s, (a - (s - bb)) + (b - bb)};
}
static tdd t_add(tdd x, tdd y)
{
    const tdd s = t_two_sum(x.hi, y.hi);
    const double lo = s.lo + x.lo + y.lo, hi = s.hi + lo;
    return (tdd){hi, lo - (hi - s.hi)};
}
static tdd t_mul(tdd x, tdd y)
{
    const double p = x.hi * y.hi, e = fma(x.hi, y.hi, -p) + (x.hi * y.lo + x.lo * y.hi);
    const double hi = p + e;
    return (tdd){hi, e - (hi - p)};
}
static tdd t_sub(tdd x, tdd y) { return t_add(x, (tdd){-y.hi, -y.lo}); }

/* sqrt of a double-double to ~eps^2 (one Newton step from the double sqrt) */
static tdd t_sqrt(tdd x)
{
    const double r = sqrt(x.hi);
    const tdd rr = t_mul((tdd){r, 0.0}, (tdd){r, 0.0});
    const tdd res = t_sub(x, rr);
    const double lo = (res.hi + res.lo) / (2.0 * r), hi = r + lo;
    return (tdd){hi, lo - (hi - r)};
}
static tdd t_dot(const tdd *a, const tdd *b)
{
    return t_add(t_add(t_mul(a[0], b[0]), t_mul(a[1], b[1])), t_mul(a[2], b[2]));
}

/* Reference solid angle of a convex polygon (vertex fan, all terms one sign; the
 * triple product and denominator in double-double, so neither cancels). */
static double ref_vos_dd(const double x[3], const double *v, int n)
{
    tdd r[8][3], len[8];
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) r[i][k] = t_two_sum(v[3 * i + k], -x[k]);
        len[i] = t_sqrt(t_dot(r[i], r[i]));
    }
    double total = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        const int j = i + 1;
        tdd trip = {0.0, 0.0};
        for (int k = 0; k < 3; ++k) {
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            const tdd c = t_sub(t_mul(r[i][k1], r[j][k2]), t_mul(r[i][k2], r[j][k1]));
            trip = t_add(trip, t_mul(r[0][k], c));
        }
        tdd den = t_mul(t_mul(len[0], len[i]), len[j]);
        den = t_add(den, t_mul(t_dot(r[0], r[i]), len[j]));
        den = t_add(den, t_mul(t_dot(r[0], r[j]), len[i]));
        den = t_add(den, t_mul(t_dot(r[i], r[j]), len[0]));
        CHECK(den.hi > 0.0); /* a triangle seen under less than pi */
        total += 2.0 * atan(trip.hi / den.hi);
    }
    return fabs(total);
}

/* The two test geometries: square centre c, unit plane axes eu, ew, unit normal nn,
 * half-side s (in plane units), and the point at in-plane offset (k0 s, s/2) and height h. */
typedef struct {
    double c[3], eu[3], ew[3], nn[3], half;
    double verts[12], x[3];
    double a; /* exact height of x (double-double, rounded) */
    double k0;
} np_case;

static void make_case(int tilted, double h, double k0, np_case *t)
{
    memset(t, 0, sizeof *t);
    t->k0 = k0;
    if (!tilted) {
        t->eu[0] = 1.0, t->ew[1] = 1.0, t->nn[2] = 1.0, t->half = 1.0;
        const double sq[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
        memcpy(t->verts, sq, sizeof sq);
        t->x[0] = k0, t->x[1] = 0.5, t->x[2] = h;
        t->a = h;
        return;
    }
    const double U[3] = {2, 1, -2}, W[3] = {2, -2, 1}, N[3] = {1, 2, 2};
    const double c[3] = {0.375, -0.125, 0.5};
    const int su[4] = {-1, 1, 1, -1}, sw[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 3; ++k) {
        t->c[k] = c[k];
        t->eu[k] = U[k] / 3.0, t->ew[k] = W[k] / 3.0, t->nn[k] = N[k] / 3.0;
        for (int i = 0; i < 4; ++i) t->verts[3 * i + k] = c[k] + 0.25 * (su[i] * U[k] + sw[i] * W[k]);
        t->x[k] = c[k] + 0.25 * (k0 * U[k] + 0.5 * W[k]) + h * N[k] / 3.0;
    }
    t->half = 0.75;
    tdd s = {0.0, 0.0}; /* N . (x - c) exactly up to the final rounding; N has small integers */
    for (int k = 0; k < 3; ++k) {
        const tdd d = t_two_sum(t->x[k], -c[k]);
        s = t_add(s, (tdd){N[k] * d.hi, N[k] * d.lo});
    }
    t->a = (s.hi + s.lo) / 3.0;
}

enum { NG = 24, NCM = SHL_NCOEFFS(14) };

/* Gauss-Legendre nodes/weights on [-1, 1] (Newton on P_n), independent of the library. */
static void gl_nodes(int n, double *xs, double *ws)
{
    for (int i = 0; i < n; ++i) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z;
            for (int l = 2; l <= n; ++l) {
                const double p2 = ((2.0 * l - 1.0) * z * p1 - (l - 1.0) * p0) / l;
                p0 = p1, p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-17) break;
        }
        xs[i] = z;
        ws[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* out: coefficients; grad (may be NULL): d out / d x, layout of shl_polygon_grad,
 * by differentiating the integrand: -grad_q [Y(q/r) h / r^3], q = p - x, with
 * grad_q Y(q/r) = (g - (qh . g) qh) / r (g the Cartesian gradient of Y's polynomial
 * extension, qh = q/r) and grad_q (|n.q| / r^3) = -n / r^3 - 3 h q / r^5 (n.q = -h). */
static void ref_coeffs(const np_case *t, int lmax, double *out, double *grad)
{
    /* panels of width <= 1.25 x the foot's distance from the square (k0 - 1) s: rho >= 2.6 + 2.4 */
    const int NPAN = (int)fmax(4.0, ceil(1.6 / (t->k0 - 1.0)));
    const int nc = SHL_NCOEFFS(lmax);
    double gx[NG], gw[NG], y[NCM], g[3 * NCM];
    gl_nodes(NG, gx, gw);
    double xo[3], fu = 0.0, fw = 0.0; /* in-plane coordinates of the foot of x */
    for (int k = 0; k < 3; ++k) xo[k] = t->x[k] - t->c[k];
    for (int k = 0; k < 3; ++k) fu += xo[k] * t->eu[k], fw += xo[k] * t->ew[k];
    for (int k = 0; k < nc; ++k) out[k] = 0.0;
    if (grad)
        for (int k = 0; k < 3 * nc; ++k) grad[k] = 0.0;
    const double pw = 2.0 * t->half / NPAN;
    for (int pu = 0; pu < NPAN; ++pu)
        for (int pv = 0; pv < NPAN; ++pv)
            for (int i = 0; i < NG; ++i)
                for (int j = 0; j < NG; ++j) {
                    const double u = -t->half + pw * (pu + 0.5 * (gx[i] + 1.0)) - fu;
                    const double w = -t->half + pw * (pv + 0.5 * (gx[j] + 1.0)) - fw;
                    const double r = sqrt(u * u + w * w + t->a * t->a);
                    double d[3];
                    for (int k = 0; k < 3; ++k) d[k] = (u * t->eu[k] + w * t->ew[k] - t->a * t->nn[k]) / r;
                    ref_sh_eval_grad(lmax, d, y, g);
                    const double wt = 0.25 * pw * pw * gw[i] * gw[j] * t->a / (r * r * r);
                    for (int k = 0; k < nc; ++k) out[k] += wt * y[k];
                    if (!grad) continue;
                    for (int k = 0; k < nc; ++k) {
                        const double dg = d[0] * g[k] + d[1] * g[nc + k] + d[2] * g[2 * nc + k];
                        for (int b = 0; b < 3; ++b) {
                            const double gy = (g[b * nc + k] - dg * d[b]) / r;
                            const double gw_ = -t->nn[b] / (r * r * r) - 3.0 * t->a * d[b] / (r * r * r * r);
                            grad[b * nc + k] -= 0.25 * pw * pw * gw[i] * gw[j] * (gy * t->a / (r * r * r) + y[k] * gw_);
                        }
                    }
                }
}

SHL_TEST(nearplane_solid_angle_sweep)
{
    for (int tilted = 0; tilted < 2; ++tilted) {
        double worst = 0.0;
        for (int p = 3; p <= 12; ++p) {
            np_case t;
            make_case(tilted, pow(10.0, -p), 3.0, &t);
            double omega;
            CHECK(shl_polygon_solid_angle(t.x, t.verts, 4, &omega) == SHL_OK);
            const double want = ref_vos_dd(t.x, t.verts, 4), e = fabs(omega - want) / want;
            worst = fmax(worst, e);
            if (!(e <= 1e-13))
                harness_fail(__FILE__, __LINE__, "%s h=1e-%d: omega %.17g want %.17g rel %.3g", tilted ? "tilted" : "axis",
                             p, omega, want, e);
        }
        harness_note("%s: max rel error %.2e (h 1e-3..1e-12, tol 1e-13)", tilted ? "tilted" : "axis", worst);
    }
}

SHL_TEST(nearplane_coeffs_sweep)
{
    const int lmaxes[2] = {8, 14};
    for (int tilted = 0; tilted < 2; ++tilted)
        for (int li = 0; li < 2; ++li) {
            const int lmax = lmaxes[li], nc = SHL_NCOEFFS(lmax);
            shl_ctx *ctx;
            CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
            double worst = 0.0;
            const double hs[10] = {0.05, 0.03, 0.02, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
            for (int p = 0; p < 10; ++p) {
                np_case t;
                make_case(tilted, hs[p], 3.0, &t);
                double got[NCM], want[NCM], omega, err = 0.0;
                CHECK(shl_polygon(ctx, t.x, t.verts, 4, got) == SHL_OK);
                CHECK(shl_polygon_solid_angle(t.x, t.verts, 4, &omega) == SHL_OK);
                ref_coeffs(&t, lmax, want, NULL);
                for (int k = 0; k < nc; ++k) err = fmax(err, fabs(got[k] - want[k]));
                err /= omega;
                worst = fmax(worst, err);
                if (!(err <= 1e-12))
                    harness_fail(__FILE__, __LINE__, "%s lmax %d h=%g: max error / omega %.3g", tilted ? "tilted" : "axis",
                                 lmax, hs[p], err);
            }
            harness_note("%s lmax %d: max error/omega %.2e (h 0.05..1e-9, tol 1e-12)", tilted ? "tilted" : "axis", lmax,
                         worst);
            shl_ctx_destroy(ctx);
        }
}

/* Gradient in the same sweep, against the differentiated reference integrand
 * (rule error ~1e-40 as above, rounding ~1e-15 of each part).  The normal
 * derivative (~ omega / h) dwarfs the in-plane one (~ omega / distance), so both
 * are checked on their own scale: error of the normal components / their max, and
 * of the in-plane parts (grad minus its normal component) / their max.  Tolerance
 * 1e-12 of each, the target of the coefficients; for the in-plane part plus the
 * floor of writing the normal part in xyz doubles for a tilted plane: each component
 * is rounded by eps |normal part|, in result and reference (8 eps max|normal| / max|in-plane|). */
SHL_TEST(nearplane_grad_sweep)
{
    for (int tilted = 0; tilted < 2; ++tilted) {
        const int lmax = 8, nc = SHL_NCOEFFS(lmax);
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
        double worst[2] = {0.0, 0.0};
        const double hs[7] = {0.05, 0.02, 1e-3, 1e-5, 1e-7, 1e-8, 1e-9};
        for (int p = 0; p < 7; ++p) {
            np_case t;
            make_case(tilted, hs[p], 3.0, &t);
            double got[NCM], want[NCM], ggot[3 * NCM], gwant[3 * NCM], err[2] = {0, 0}, scale[2] = {0, 0};
            CHECK(shl_polygon_grad(ctx, t.x, t.verts, 4, got, ggot) == SHL_OK);
            ref_coeffs(&t, lmax, want, gwant);
            for (int k = 0; k < nc; ++k) {
                double ng = 0.0, nw = 0.0;
                for (int b = 0; b < 3; ++b) ng += t.nn[b] * ggot[b * nc + k], nw += t.nn[b] * gwant[b * nc + k];
                err[0] = fmax(err[0], fabs(ng - nw));
                scale[0] = fmax(scale[0], fabs(nw));
                for (int b = 0; b < 3; ++b) {
                    const double tg = ggot[b * nc + k] - ng * t.nn[b], tw = gwant[b * nc + k] - nw * t.nn[b];
                    err[1] = fmax(err[1], fabs(tg - tw));
                    scale[1] = fmax(scale[1], fabs(tw));
                }
            }
            for (int q = 0; q < 2; ++q) {
                const double e = err[q] / scale[q], tol = 1e-12 + (q ? 8.0 * DBL_EPSILON * scale[0] / scale[1] : 0.0);
                worst[q] = fmax(worst[q], e);
                if (!(e <= tol))
                    harness_fail(__FILE__, __LINE__, "%s lmax %d h=%g: %s grad max error / max %.3g",
                                 tilted ? "tilted" : "axis", lmax, hs[p], q ? "in-plane" : "normal", e);
            }
        }
        harness_note("%s lmax %d: grad error / max, normal %.2e, in-plane %.2e (h 0.05..1e-9, tol 1e-12 + floor)",
                     tilted ? "tilted" : "axis", lmax, worst[0], worst[1]);
        shl_ctx_destroy(ctx);
    }
}

/* Foot of x closer to an edge (1 and 0.75 half-sides outside it, the latter at the
 * planar rule's limit dmin = extent / 4, where it subdivides the fan triangles nearest
 * the foot, polygon.c); same targets and references. */
SHL_TEST(nearplane_closer)
{
    const double k0s[2] = {2.0, 1.75}, hs[2] = {1e-4, 1e-9};
    shl_ctx *ctx;
    CHECK(shl_ctx_create(14, &ctx) == SHL_OK);
    const int nc = SHL_NCOEFFS(14);
    double worst = 0.0, worst_sa = 0.0;
    for (int tilted = 0; tilted < 2; ++tilted)
        for (int a = 0; a < 2; ++a)
            for (int p = 0; p < 2; ++p) {
                np_case t;
                make_case(tilted, hs[p], k0s[a], &t);
                double got[NCM], want[NCM], omega, err = 0.0;
                CHECK(shl_polygon(ctx, t.x, t.verts, 4, got) == SHL_OK);
                CHECK(shl_polygon_solid_angle(t.x, t.verts, 4, &omega) == SHL_OK);
                ref_coeffs(&t, 14, want, NULL);
                for (int k = 0; k < nc; ++k) err = fmax(err, fabs(got[k] - want[k]));
                err /= omega;
                worst = fmax(worst, err);
                const double sa = fabs(omega - ref_vos_dd(t.x, t.verts, 4)) / omega;
                worst_sa = fmax(worst_sa, sa);
                if (!(err <= 1e-12 && sa <= 1e-13))
                    harness_fail(__FILE__, __LINE__, "%s k0 %g h=%g: max error / omega %.3g, solid angle %.3g",
                                 tilted ? "tilted" : "axis", k0s[a], hs[p], err, sa);
            }
    harness_note("lmax 14 max error/omega %.2e (tol 1e-12), solid angle %.2e (tol 1e-13)", worst, worst_sa);
    shl_ctx_destroy(ctx);
}

/* The foot of x exactly on an edge or a vertex (found by fuzz_batch: a triangle seen
 * from 1 above the vertex (0, 0)): the in-plane angle of that edge is +-pi or
 * undefined, so the foot-fan split omega_i = theta_i + (omega_i - theta_i) cannot be
 * used and the direct fan sum must be (it was 0.546 instead of 1.025 sr).  Against
 * the double-double Van Oosterom-Strackee sum; at these heights the direct sum has
 * full relative accuracy (no O(1) terms cancel), so the sweep's 1e-13 holds. */
SHL_TEST(nearplane_foot_on_boundary)
{
    static const double tri[9] = {0, 0, 0, 3, 0, 0, 0, 4, 0};
    static const double sq[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const double heights[4] = {1.0, 0.1, 1e-3, -0.5};
    double worst = 0.0;
    int cases = 0;
    for (int shape = 0; shape < 2; ++shape) {
        const double *v = shape == 0 ? tri : sq;
        const int n = shape == 0 ? 3 : 4;
        for (int i = 0; i < n; ++i) {
            const double *a = v + 3 * i, *b = v + 3 * ((i + 1) % n);
            for (int q = 0; q <= 4; ++q) { /* the vertex a (q = 0) and points a + q/4 (b - a): exact in binary */
                for (int hk = 0; hk < 4; ++hk) {
                    const double x[3] = {a[0] + 0.25 * q * (b[0] - a[0]), a[1] + 0.25 * q * (b[1] - a[1]), heights[hk]};
                    double omega, c[SHL_NCOEFFS(0)];
                    shl_ctx *ctx = NULL;
                    CHECK(shl_ctx_create(0, &ctx) == SHL_OK);
                    CHECK(shl_polygon_solid_angle(x, v, n, &omega) == SHL_OK);
                    CHECK(shl_polygon(ctx, x, v, n, c) == SHL_OK);
                    shl_ctx_destroy(ctx);
                    const double want = ref_vos_dd(x, v, n);
                    const double e = fmax(fabs(omega - want), fabs(c[0] * 2.0 * sqrt(M_PI) - want)) / want;
                    worst = fmax(worst, e);
                    ++cases;
                    if (!(e <= 1e-13))
                        harness_fail(__FILE__, __LINE__, "%s edge %d q %d h %g: omega %.17g L00 2 sqrt(pi) %.17g want %.17g",
                                     shape ? "square" : "triangle", i, q, x[2], omega, c[0] * 2.0 * sqrt(M_PI), want);
                }
            }
        }
    }
    harness_note("%d feet on edges and vertices: max rel error %.2e (tol 1e-13)", cases, worst);
}
