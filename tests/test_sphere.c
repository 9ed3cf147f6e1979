/* Spherical lights: coefficients and gradients against the independent cap
 * quadrature (capref.c), tiny / distant / tangent / inside spheres, float
 * paths, the analytic SH gradient, bad input. */
#include "capref.h"
#include "fd_check.h"
#include "geom.h"
#include "harness.h"
#include "sh_basis.h"
#include "testutil.h"
#include <float.h>
#include <math.h>

enum { L = SHL_LMAX_MAX, NC = SHL_NCOEFFS(SHL_LMAX_MAX) };

/* max |got - want| / max |want| */
static double rel_err(const double *got, const double *want, int n)
{
    double e = 0.0, m = 0.0;
    for (int k = 0; k < n; ++k) {
        e = fmax(e, fabs(got[k] - want[k]));
        m = fmax(m, fabs(want[k]));
    }
    return e / m;
}

/* max over bands of |got_l - want_l| / |want_l| (Euclidean norms per band) */
static double band_rel_err(const double *got, const double *want, int lmax)
{
    double worst = 0.0;
    for (int l = 0; l <= lmax; ++l) {
        double e = 0.0, m = 0.0;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            e += (got[k] - want[k]) * (got[k] - want[k]);
            m += want[k] * want[k];
        }
        worst = fmax(worst, sqrt(e / m));
    }
    return worst;
}

static shl_ctx *ctx_or_die(int lmax)
{
    shl_ctx *ctx = NULL;
    CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
    return ctx;
}

static void random_sphere(rng_t *r, double x[3], double c[3], double *rad)
{
    double dir[3];
    rng_unit_vector(r, dir);
    const double d = rng_range(r, 0.5, 5.0);
    *rad = d * rng_range(r, 0.02, 0.98);
    for (int k = 0; k < 3; ++k) {
        x[k] = rng_range(r, -1.0, 1.0);
        c[k] = x[k] + d * dir[k];
    }
}

SHL_TEST(sphere_random_vs_quadrature)
{
    rng_t r = {11};
    shl_ctx *ctx = ctx_or_die(L);
    double worst = 0.0;
    for (int it = 0; it < 40; ++it) {
        double x[3], c[3], rad, got[NC], want[NC];
        random_sphere(&r, x, c, &rad);
        CHECK(shl_sphere(ctx, x, c, rad, got) == SHL_OK);
        capref_sphere(L, x, c, rad, want);
        worst = fmax(worst, rel_err(got, want, NC));
    }
    CHECK(worst < 2e-14);
    harness_note("max |err|/max|coeff| %.1e (40 spheres, lmax %d)", worst, L);
    shl_ctx_destroy(ctx);
}

SHL_TEST(sphere_prefix_consistency)
{
    rng_t r = {12};
    shl_ctx *big = ctx_or_die(L), *small = ctx_or_die(7);
    double x[3], c[3], rad, a[NC], b[64];
    random_sphere(&r, x, c, &rad);
    CHECK(shl_sphere(big, x, c, rad, a) == SHL_OK);
    CHECK(shl_sphere(small, x, c, rad, b) == SHL_OK);
    CHECK(memcmp(a, b, sizeof b) == 0); /* bit for bit */
    shl_ctx_destroy(big);
    shl_ctx_destroy(small);
}

/* The ZH is HVL Eq. (14) rewritten; for caps that are not small the literal
 * Eq. (14) is accurate, and both must agree. */
SHL_TEST(sphere_zh_cap_matches_eq14)
{
    double zh[L + 1], worst = 0.0;
    for (double a = 0.3; a <= M_PI; a += 0.2) {
        CHECK(shl_zh_cap(L, a, zh) == SHL_OK);
        const double al = cos(a);
        CHECK_NEAR(zh[0], sqrt(M_PI) * (1.0 - al), 1e-15);
        for (int l = 1; l <= L; ++l) {
            const double eq14 = sqrt(M_PI / (2.0 * l + 1.0)) * (legendre_p(l - 1, al) - legendre_p(l + 1, al));
            worst = fmax(worst, fabs(zh[l] - eq14));
        }
    }
    CHECK(worst < 3e-15);
    harness_note("max |zh - Eq.14| %.1e for a >= 0.3", worst);
}

/* The kernel paths: lmax <= 5 has unrolled kernels (values and gradients) and
 * moderate geometry a register-only set-up (src/sphere_impl.h, sphere.c); the
 * general kernels, the scaled set-up (inputs times 2^+-200 in double, 2^+-110 in
 * float, outside the moderate range; exact scalings, gradients then scale by
 * 2^-200 exactly) and shl_sphere_grad's coefficients must give the same values bit
 * for bit (each path forms every value by the same operations); and lmax 2 and 5
 * against the quadrature with the bound of sphere_random_vs_quadrature. */
SHL_TEST(sphere_unrolled_and_scaled_paths_bit_identical)
{
    rng_t r = {21};
    shl_ctx *big = ctx_or_die(L);
    double worst = 0.0;
    int bad = 0;
    for (int lmax = 0; lmax <= 8; ++lmax) {
        shl_ctx *ctx = ctx_or_die(lmax);
        const int nc = SHL_NCOEFFS(lmax);
        for (int it = 0; it < 25; ++it) {
            double x[3], c[3], rad, a[NC], b[NC], g[3 * NC], want[NC];
            float xf[3], cf[3], af[NC], bf[NC];
            random_sphere(&r, x, c, &rad);
            if (it % 5 == 0) rad *= 1e-6; /* small caps: t and s2 far from c */
            for (int k = 0; k < 3; ++k) xf[k] = (float)x[k], cf[k] = (float)c[k];
            CHECK(shl_sphere(ctx, x, c, rad, a) == SHL_OK && shl_sphere(big, x, c, rad, b) == SHL_OK);
            bad += memcmp(a, b, (size_t)nc * sizeof a[0]) != 0;
            CHECK(shl_sphere_grad(ctx, x, c, rad, b, g) == SHL_OK);
            bad += memcmp(a, b, (size_t)nc * sizeof a[0]) != 0;
            { /* gradients: lmax vs the prefix of lmax L, and at scale 2^200 (ldexp(g, -200) exactly) */
                static double bb[NC], gb[3 * NC], gs[3 * NC];
                double xs[3], cs[3];
                CHECK(shl_sphere_grad(big, x, c, rad, bb, gb) == SHL_OK);
                for (int k = 0; k < 3; ++k) xs[k] = ldexp(x[k], 200), cs[k] = ldexp(c[k], 200);
                CHECK(shl_sphere_grad(ctx, xs, cs, ldexp(rad, 200), bb, gs) == SHL_OK);
                for (int ax = 0; ax < 3; ++ax)
                    for (int k = 0; k < nc; ++k)
                        bad += g[ax * nc + k] != gb[ax * NC + k] || ldexp(g[ax * nc + k], -200) != gs[ax * nc + k];
                float gf[3 * NC], gbf[3 * NC], tmp[NC];
                CHECK(shl_sphere_grad_f(ctx, xf, cf, (float)rad, tmp, gf) == SHL_OK);
                CHECK(shl_sphere_grad_f(big, xf, cf, (float)rad, tmp, gbf) == SHL_OK);
                for (int ax = 0; ax < 3; ++ax)
                    for (int k = 0; k < nc; ++k) bad += gf[ax * nc + k] != gbf[ax * NC + k];
            }
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double xs[3], cs[3];
                for (int k = 0; k < 3; ++k) xs[k] = ldexp(x[k], 200 * sgn), cs[k] = ldexp(c[k], 200 * sgn);
                CHECK(shl_sphere(ctx, xs, cs, ldexp(rad, 200 * sgn), b) == SHL_OK);
                bad += memcmp(a, b, (size_t)nc * sizeof a[0]) != 0;
            }
            CHECK(shl_sphere_f(ctx, xf, cf, (float)rad, af) == SHL_OK);
            CHECK(shl_sphere_f(big, xf, cf, (float)rad, bf) == SHL_OK);
            bad += memcmp(af, bf, (size_t)nc * sizeof af[0]) != 0;
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                float xs[3], cs[3];
                if (sgn < 0 && it % 5 == 0) continue; /* the small radius would be a subnormal float */
                for (int k = 0; k < 3; ++k) xs[k] = ldexpf(xf[k], 110 * sgn), cs[k] = ldexpf(cf[k], 110 * sgn);
                CHECK(shl_sphere_f(ctx, xs, cs, ldexpf((float)rad, 110 * sgn), bf) == SHL_OK);
                bad += memcmp(af, bf, (size_t)nc * sizeof af[0]) != 0;
            }
            if (lmax == 2 || lmax == 5) {
                capref_sphere(lmax, x, c, rad, want);
                worst = fmax(worst, rel_err(a, want, nc));
            }
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0);
    CHECK(worst < 2e-14);
    harness_note("lmax 0..8, 25 spheres each: %d coefficient sets or gradient values differ between paths; lmax 2, 5 vs quadrature "
                 "max |err|/max|coeff| %.1e",
                 bad, worst);
    shl_ctx_destroy(big);
}

/* Reference ZH of a cap by Gauss-Legendre in q = 1 - u on [0, t]. */
static void zh_cap_ref(int lmax, double t, double *zh)
{
    double gx[32], gw[32];
    capref_gauss_legendre(32, gx, gw);
    for (int l = 0; l <= lmax; ++l) zh[l] = 0.0;
    for (int i = 0; i < 32; ++i) {
        const double u = 1.0 - 0.5 * t * (1.0 - gx[i]), w = 0.5 * t * gw[i];
        for (int l = 0; l <= lmax; ++l)
            zh[l] += w * 2.0 * M_PI * sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * legendre_p(l, u);
    }
}

SHL_TEST(sphere_tiny_and_distant_relative_accuracy)
{
    /* r = 1e-4 at d = 10 (the case) and r = 1 at d = 1e6 */
    const double cases[2][2] = {{1e-4, 10.0}, {1.0, 1e6}};
    shl_ctx *ctx = ctx_or_die(L);
    rng_t r = {13};
    double worst_d[2] = {0, 0}, worst_f[2] = {0, 0}, naive = 0.0, naive_f = 0.0;
    for (int cs = 0; cs < 2; ++cs)
        for (int it = 0; it < 20; ++it) {
            double dir[3], got[NC], want[NC];
            float gotf[NC];
            rng_unit_vector(&r, dir);
            const double x[3] = {0.25, -0.5, 0.125}, rad = cases[cs][0], d = cases[cs][1];
            const double c[3] = {x[0] + d * dir[0], x[1] + d * dir[1], x[2] + d * dir[2]};
            const float xf[3] = {0.25f, -0.5f, 0.125f}, cf[3] = {(float)c[0], (float)c[1], (float)c[2]};
            CHECK(shl_sphere(ctx, x, c, rad, got) == SHL_OK);
            capref_sphere(L, x, c, rad, want);
            worst_d[cs] = fmax(worst_d[cs], band_rel_err(got, want, L));
            CHECK(shl_sphere_f(ctx, xf, cf, (float)rad, gotf) == SHL_OK);
            double wantf[NC], gotfd[NC]; /* reference at the float-rounded geometry */
            const double xr[3] = {xf[0], xf[1], xf[2]}, cr[3] = {cf[0], cf[1], cf[2]};
            capref_sphere(L, xr, cr, (float)rad, wantf);
            for (int k = 0; k < NC; ++k) gotfd[k] = gotf[k];
            worst_f[cs] = fmax(worst_f[cs], band_rel_err(gotfd, wantf, L));
        }
    /* the ZH themselves, relative per band, down to a = 1e-6 */
    double worst_zh = 0.0;
    for (double a = 1e-6; a < 0.5; a *= 3.7) {
        double zh[L + 1], ref[L + 1];
        CHECK(shl_zh_cap(L, a, zh) == SHL_OK);
        zh_cap_ref(L, 2.0 * sin(0.5 * a) * sin(0.5 * a), ref);
        for (int l = 0; l <= L; ++l)
            if (a * l < 0.5) worst_zh = fmax(worst_zh, fabs(zh[l] / ref[l] - 1.0)); /* ZH not near a zero */
    }
    { /* the literal Eq. (14) cancels catastrophically: the case, l = 30 */
        const double s2 = (1e-4 / 10.0) * (1e-4 / 10.0), al = sqrt(1.0 - s2), t = s2 / (1.0 + al);
        double ref[L + 1];
        zh_cap_ref(L, t, ref);
        naive = fabs(sqrt(M_PI / 61.0) * (legendre_p(29, al) - legendre_p(31, al)) / ref[30] - 1.0);
        naive_f = ((float)al == 1.0f) ? 1.0 : 0.0; /* cos a rounds to 1 in float: every band above 0 vanishes */
    }
    CHECK(worst_d[0] < 1e-13 && worst_d[1] < 1e-13);
    CHECK(worst_f[0] < 2e-5 && worst_f[1] < 2e-5);
    CHECK(worst_zh < 6e-14); /* ~l^2 ulp: cos a itself is rounded */
    harness_note("per-band rel err r=1e-4,d=10: double %.1e float %.1e; r=1,d=1e6: double %.1e float %.1e",
                 worst_d[0], worst_f[0], worst_d[1], worst_f[1]);
    harness_note("ZH rel err a>=1e-6: %.1e (literal Eq.14, r=1e-4,d=10, l=30: double %.1e, float %.0f)",
                 worst_zh, naive, naive_f);
    shl_ctx_destroy(ctx);
}

SHL_TEST(sphere_tangent_and_inside)
{
    shl_ctx *ctx = ctx_or_die(L);
    const double c[3] = {0.5, -0.25, 2.0}, rad = 1.5;
    double worst = 0.0;
    for (int e = 3; e <= 12; e += 3) { /* x at distance rad (1 + 10^-e) */
        const double gap = rad * pow(10.0, -e);
        const double x[3] = {c[0] - (rad + gap) * 0.6, c[1] + (rad + gap) * 0.8, c[2]};
        double got[NC], want[NC];
        CHECK(shl_sphere(ctx, x, c, rad, got) == SHL_OK);
        capref_sphere(L, x, c, rad, want);
        /* cos a ~ sqrt(2 gap / r) inherits the rounding of |c - x| amplified by r / gap */
        const double e_rel = rel_err(got, want, NC), bound = 1e-14 + 1e-16 * sqrt(rad / gap);
        CHECK(e_rel < bound);
        worst = fmax(worst, e_rel / bound);
    }
    harness_note("tangent (gap 1e-3..1e-12 r): max rel err / (1e-14 + 1e-16 sqrt(r/gap)) = %.2f", worst);
    /* inside, on the surface (exactly representable), at the centre */
    const double xs[3][3] = {{0.6, -0.1, 2.3}, {0.5 + 1.5, -0.25, 2.0}, {0.5, -0.25, 2.0}};
    for (int i = 0; i < 3; ++i) {
        double got[NC], grad[3 * NC];
        float gf[NC], ggf[3 * NC];
        const float xf[3] = {(float)xs[i][0], (float)xs[i][1], (float)xs[i][2]};
        const float cf[3] = {0.5f, -0.25f, 2.0f};
        CHECK(shl_sphere_grad(ctx, xs[i], c, rad, got, grad) == SHL_OK);
        CHECK(shl_sphere_grad_f(ctx, xf, cf, 1.5f, gf, ggf) == SHL_OK);
        CHECK(got[0] == sqrt(4.0 * M_PI) && gf[0] == (float)sqrt(4.0 * M_PI));
        for (int k = 1; k < NC; ++k) CHECK(got[k] == 0.0 && gf[k] == 0.0f);
        for (int k = 0; k < 3 * NC; ++k) CHECK(grad[k] == 0.0 && ggf[k] == 0.0f);
    }
    shl_ctx_destroy(ctx);
}

/* The float entry points' set-up (geom_units_f, src/sphere.c) near tangency: x at
 * distance r (1 + 10^-e), e = 1..6, rounded to float (the gap moves by at most
 * ~4e-7, below 1.5e-6), against the quadrature at the float-rounded geometry.  Bound
 * 1e-5 of max|coeff|, the float contract (sphere_float_random): the set-up's own error
 * in cos a, ~eps r / gap <= 1e-10 relative (double arithmetic, sphere.c), is far
 * below the float rounding of the kernels' inputs.  shl_sphere_grad_f's
 * coefficients must equal shl_sphere_f's bit for bit (the same set-up). */
SHL_TEST(sphere_float_tangent)
{
    shl_ctx *ctx = ctx_or_die(L);
    const float cf[3] = {0.5f, -0.25f, 2.0f}, rf = 1.5f;
    const double c[3] = {cf[0], cf[1], cf[2]};
    rng_t r = {31};
    double worst = 0.0;
    int bad = 0;
    for (int e = 1; e <= 6; ++e)
        for (int it = 0; it < 4; ++it) {
            static float got[NC], got2[NC], g[3 * NC];
            double dir[3], x[3], gd[NC], want[NC];
            float xf[3];
            rng_unit_vector(&r, dir);
            const double d = rf * (1.0 + pow(10.0, -e));
            for (int k = 0; k < 3; ++k) x[k] = xf[k] = (float)(c[k] - d * dir[k]);
            CHECK(shl_sphere_f(ctx, xf, cf, rf, got) == SHL_OK);
            CHECK(shl_sphere_grad_f(ctx, xf, cf, rf, got2, g) == SHL_OK);
            bad += memcmp(got, got2, sizeof got) != 0;
            capref_sphere(L, x, c, rf, want);
            for (int k = 0; k < NC; ++k) gd[k] = got[k];
            worst = fmax(worst, rel_err(gd, want, NC));
        }
    CHECK(bad == 0);
    CHECK(worst < 1e-5);
    harness_note("float, gap 1e-1..1e-6 r: max |err|/max|coeff| %.1e; %d coefficient sets differ with the gradient", worst,
                 bad);
    shl_ctx_destroy(ctx);
}

SHL_TEST(sphere_float_random)
{
    rng_t r = {14};
    shl_ctx *ctx = ctx_or_die(L);
    double worst = 0.0;
    for (int it = 0; it < 20; ++it) {
        double x[3], c[3], rad, want[NC], got[NC];
        float xf[3], cf[3], gf[NC];
        random_sphere(&r, x, c, &rad);
        for (int k = 0; k < 3; ++k) {
            xf[k] = (float)x[k];
            cf[k] = (float)c[k];
            x[k] = round_to_float(x[k]);
            c[k] = round_to_float(c[k]);
        }
        rad = round_to_float(rad);
        CHECK(shl_sphere_f(ctx, xf, cf, (float)rad, gf) == SHL_OK);
        capref_sphere(L, x, c, rad, want);
        for (int k = 0; k < NC; ++k) got[k] = gf[k];
        worst = fmax(worst, rel_err(got, want, NC));
    }
    CHECK(worst < 1e-5);
    harness_note("float max |err|/max|coeff| %.1e", worst);
    shl_ctx_destroy(ctx);
}

/* The analytic SH gradient against central differences along tangent directions. */
SHL_TEST(sphere_sh_gradient_vs_fd)
{
    rng_t r = {15};
    double worst = 0.0, radial = 0.0;
    for (int it = 0; it < 30; ++it) {
        double u[3], y[NC], g[3 * NC], t[3], e[3] = {0.3, -0.7, 0.2};
        rng_unit_vector(&r, u);
        if (it == 0) u[0] = u[1] = 0.0, u[2] = 1.0; /* the pole */
        shl__sh_eval_grad_d(L, u, y, g, NC);
        /* tangent t = e - (e.u) u, normalized */
        const double eu = shl__dot3(e, u);
        for (int k = 0; k < 3; ++k) t[k] = e[k] - eu * u[k];
        const double tn = sqrt(shl__dot3(t, t));
        for (int k = 0; k < 3; ++k) t[k] /= tn;
        const double h = 1e-4;
        double yq[2][2][NC]; /* Y at angles -2h, -h, h, 2h along t */
        for (int s = 0; s < 2; ++s)
            for (int sg = 0; sg < 2; ++sg) {
                const double ang = (sg ? 1.0 : -1.0) * (s + 1) * h;
                double v[3];
                for (int k = 0; k < 3; ++k) v[k] = cos(ang) * u[k] + sin(ang) * t[k];
                shl__sh_eval(L, v[0], v[1], v[2], yq[s][sg]);
            }
        double gmax = 0.0;
        for (int k = 0; k < NC; ++k) gmax = fmax(gmax, fabs(g[k]) + fabs(g[NC + k]) + fabs(g[2 * NC + k]));
        for (int k = 0; k < NC; ++k) {
            /* 4th-order central difference in the angle (d/dangle = d/dt at angle 0) */
            const double dd = (8.0 * (yq[0][1][k] - yq[0][0][k]) - (yq[1][1][k] - yq[1][0][k])) / (12.0 * h);
            const double an = g[k] * t[0] + g[NC + k] * t[1] + g[2 * NC + k] * t[2];
            worst = fmax(worst, fabs(an - dd) / gmax);
            radial = fmax(radial, fabs(g[k] * u[0] + g[NC + k] * u[1] + g[2 * NC + k] * u[2]) / gmax);
        }
    }
    CHECK(worst < 1e-11);
    CHECK(radial < 1e-15);
    harness_note("dY/dt vs 4th-order FD (h=1e-4): %.1e of max|grad|; radial part %.1e", worst, radial);
}

static double max_abs(const double *v, int n)
{
    double m = 0.0;
    for (int k = 0; k < n; ++k) m = fmax(m, fabs(v[k]));
    return m;
}

typedef struct {
    int lmax;
    const double *c;
    double rad;
} capref_arg;

static void capref_values(void *arg, const double x[3], double *out)
{
    const capref_arg *a = arg;
    capref_sphere(a->lmax, x, a->c, a->rad, out);
}

/* Gradient vs 8th-order central differences of the quadrature reference, with the
 * derived bound of fd_check.h: the reference's error E = 2e-14 max|coeff| (product rule
 * exact for l <= 30; its rounding, sphere_random_vs_quadrature and the closed form of
 * sphere_zh_cap_matches_eq14 agree to 1.5e-14 and 4e-16) and the analytic gradient's
 * contract 1e-12 max|grad| (lights_sphere_equals_shl_sphere).  The step is a power of two
 * below min(gap, d / (lmax + 1)) / 32, the lengths over which the cap's coefficients vary,
 * so h kappa <= 1/32.  *err_d: error / bound; *raw_d: error / max|grad|. */
static void grad_case(shl_ctx *ctx, int lmax, const double x[3], const double c[3], double rad,
                      double *err_d, double *raw_d, double *err_f)
{
    const int nc = SHL_NCOEFFS(lmax);
    double coeffs[NC], grad[3 * NC], gd[3 * NC];
    float xf[3], cf[3], cof[NC], grf[3 * NC];
    const double v[3] = {c[0] - x[0], c[1] - x[1], c[2] - x[2]}, d = sqrt(shl__dot3(v, v));
    const double h = exp2(floor(log2(fmin(d - rad, d / (lmax + 1.0)) / 32.0))); /* x +- k h exact */
    CHECK(shl_sphere_grad(ctx, x, c, rad, coeffs, grad) == SHL_OK);
    capref_arg arg = {lmax, c, rad};
    const fd_result fr = fd_compare(capref_values, &arg, x, h, nc, grad);
    const double gm = max_abs(grad, 3 * nc);
    *err_d = fmax(*err_d, fr.err / fd_bound(&fr, 2e-14 * fr.fbig, 1e-12 * gm));
    *raw_d = fmax(*raw_d, fr.err / gm);
    for (int k = 0; k < 3; ++k) {
        xf[k] = (float)x[k];
        cf[k] = (float)c[k];
    }
    CHECK(shl_sphere_grad_f(ctx, xf, cf, (float)rad, cof, grf) == SHL_OK);
    /* float against the double gradient at the float-rounded geometry */
    const double xr[3] = {xf[0], xf[1], xf[2]}, cr[3] = {cf[0], cf[1], cf[2]};
    CHECK(shl_sphere_grad(ctx, xr, cr, (float)rad, coeffs, gd) == SHL_OK);
    const double gmf = max_abs(gd, 3 * nc);
    if (gmf == 0.0) return; /* rounding to float moved x inside the sphere */
    double e = 0.0;
    for (int k = 0; k < 3 * nc; ++k) e = fmax(e, fabs(grf[k] - gd[k]));
    *err_f = fmax(*err_f, e / gmf);
}

SHL_TEST(sphere_grad_vs_fd)
{
    rng_t r = {16};
    shl_ctx *ctx = ctx_or_die(L);
    double ed = 0.0, rd = 0.0, ef = 0.0, ed_hard = 0.0, rd_hard = 0.0, ed_tan[2] = {0.0, 0.0}, rd_tan[2] = {0.0, 0.0};
    for (int it = 0; it < 6; ++it) {
        double x[3], c[3], rad;
        random_sphere(&r, x, c, &rad);
        grad_case(ctx, L, x, c, rad, &ed, &rd, &ef);
    }
    /* tiny, distant, tangent (gap 1e-4 r and 1e-7 r) */
    const double x0[3] = {0.125, 0.25, -0.375};
    const double tiny_c[3] = {0.125 + 6.0, 0.25 + 8.0, -0.375};
    grad_case(ctx, L, x0, tiny_c, 1e-4, &ed_hard, &rd_hard, &ef);
    const double far_c[3] = {0.125, 0.25 - 6e5, -0.375 + 8e5};
    grad_case(ctx, L, x0, far_c, 1.0, &ed_hard, &rd_hard, &ef);
    for (int i = 0; i < 2; ++i) {
        const double rad = 2.0, d = rad * (1.0 + (i ? 1e-7 : 1e-4));
        const double c[3] = {x0[0] + 0.48 * d, x0[1] - 0.6 * d, x0[2] + 0.64 * d};
        grad_case(ctx, L, x0, c, rad, &ed_tan[i], &rd_tan[i], &ef);
    }
    CHECK(ed <= 1.0 && ed_hard <= 1.0 && ed_tan[0] <= 1.0 && ed_tan[1] <= 1.0);
    /* float: 1e-5 max|grad| (the shl_sphere_grad_f contract, README) */
    CHECK(ef < 1e-5);
    harness_note("max |grad - FD|/max|grad| (double): random %.1e, tiny+distant %.1e, tangent gap 1e-4 r %.1e, "
                 "gap 1e-7 r %.1e; error / derived bound at most %.2g; float vs double %.1e",
                 rd, rd_hard, rd_tan[0], rd_tan[1], fmax(fmax(ed, ed_hard), fmax(ed_tan[0], ed_tan[1])), ef);
    shl_ctx_destroy(ctx);
}

SHL_TEST(sphere_bad_input)
{
    shl_ctx *ctx = ctx_or_die(3);
    const double x[3] = {0, 0, 0}, c[3] = {0, 0, 5}, nan3[3] = {0, NAN, 0}, inf3[3] = {INFINITY, 0, 0};
    const float xf[3] = {0, 0, 0}, cf[3] = {0, 0, 5}, nanf3[3] = {0, NAN, 0};
    double out[17], grad[49];
    float outf[17], gradf[49];
    guard_fill(out, 17);
    guard_fill(grad, 49);
    for (int k = 0; k < 17; ++k) outf[k] = (float)GUARD_VALUE;
    for (int k = 0; k < 49; ++k) gradf[k] = (float)GUARD_VALUE;
    CHECK(shl_sphere(NULL, x, c, 1.0, out) == SHL_ENULL);
    CHECK(shl_sphere(ctx, NULL, c, 1.0, out) == SHL_ENULL);
    CHECK(shl_sphere(ctx, x, NULL, 1.0, out) == SHL_ENULL);
    CHECK(shl_sphere(ctx, x, c, 1.0, NULL) == SHL_ENULL);
    CHECK(shl_sphere_grad(ctx, x, c, 1.0, out, NULL) == SHL_ENULL);
    CHECK(shl_sphere_grad(ctx, x, c, 1.0, NULL, grad) == SHL_ENULL);
    CHECK(shl_sphere(ctx, x, c, 0.0, out) == SHL_EDOMAIN);
    CHECK(shl_sphere(ctx, x, c, -1.0, out) == SHL_EDOMAIN);
    CHECK(shl_sphere(ctx, x, c, NAN, out) == SHL_ENONFINITE);
    CHECK(shl_sphere(ctx, x, c, INFINITY, out) == SHL_ENONFINITE);
    CHECK(shl_sphere(ctx, nan3, c, 1.0, out) == SHL_ENONFINITE);
    CHECK(shl_sphere(ctx, x, inf3, 1.0, out) == SHL_ENONFINITE);
    CHECK(shl_sphere_grad(ctx, x, c, 0.0, out, grad) == SHL_EDOMAIN);
    CHECK(shl_sphere_grad(ctx, inf3, c, 1.0, out, grad) == SHL_ENONFINITE);
    CHECK(guard_intact(out, 17) && guard_intact(grad, 49));
    CHECK(shl_sphere_f(ctx, xf, cf, 0.0f, outf) == SHL_EDOMAIN);
    CHECK(shl_sphere_f(ctx, nanf3, cf, 1.0f, outf) == SHL_ENONFINITE);
    CHECK(shl_sphere_f(ctx, xf, cf, (float)NAN, outf) == SHL_ENONFINITE);
    CHECK(shl_sphere_f(NULL, xf, cf, 1.0f, outf) == SHL_ENULL);
    CHECK(shl_sphere_grad_f(ctx, xf, cf, -1.0f, outf, gradf) == SHL_EDOMAIN);
    CHECK(shl_sphere_grad_f(ctx, xf, cf, 1.0f, outf, NULL) == SHL_ENULL);
    for (int k = 0; k < 17; ++k) CHECK(outf[k] == (float)GUARD_VALUE);
    for (int k = 0; k < 49; ++k) CHECK(gradf[k] == (float)GUARD_VALUE);
    /* lmax 3 writes exactly 16 coefficients and 48 gradient entries */
    CHECK(shl_sphere_grad(ctx, x, c, 1.0, out, grad) == SHL_OK);
    CHECK(out[16] == GUARD_VALUE && grad[48] == GUARD_VALUE);
    CHECK(all_finite(out, 16) && all_finite(grad, 48));
    /* shl_zh_cap */
    double zh[32];
    guard_fill(zh, 32);
    CHECK(shl_zh_cap(3, 0.5, NULL) == SHL_ENULL);
    CHECK(shl_zh_cap(-1, 0.5, zh) == SHL_ELMAX);
    CHECK(shl_zh_cap(SHL_LMAX_MAX + 1, 0.5, zh) == SHL_ELMAX);
    CHECK(shl_zh_cap(3, NAN, zh) == SHL_ENONFINITE);
    CHECK(shl_zh_cap(3, -0.1, zh) == SHL_EDOMAIN);
    CHECK(shl_zh_cap(3, 3.2, zh) == SHL_EDOMAIN);
    CHECK(guard_intact(zh, 32));
    CHECK(shl_zh_cap(3, M_PI, zh) == SHL_OK && zh[4] == GUARD_VALUE);
    CHECK_NEAR(zh[0], 2.0 * sqrt(M_PI), 1e-15); /* the whole sphere */
    shl_ctx_destroy(ctx);
}

/* Extreme scales (issue 8, K4): every input times 2^k is exact here and the
 * geometry works in units of a power of two (src/internal.h), so coefficients
 * equal the scale-1 ones bit for bit and each gradient is ldexp(g_1, -k) (one
 * rounding; +-inf only where that exceeds DBL_MAX).  Cases: centre - x overflows
 * (components +-2^1023); a denormal distance 2^-1050 with radius 2^-1070, whose
 * gradient (~2^1010) is representable although 1/d is not; tiny and huge scales. */
static int sphere_scaled_mismatches(const shl_ctx *ctx, int k, const double x1[3], const double c1[3], double r1,
                                    int use_float)
{
    static double a[NC], ga[3 * NC], b[NC], gb[3 * NC];
    static float af[NC], gaf[3 * NC], bf[NC], gbf[3 * NC];
    double x[3], c[3];
    float x1f[3], c1f[3], xf[3], cf[3];
    for (int i = 0; i < 3; ++i) {
        xf[i] = (float)(x[i] = ldexp(x1[i], k)), cf[i] = (float)(c[i] = ldexp(c1[i], k));
        x1f[i] = (float)x1[i], c1f[i] = (float)c1[i];
    }
    const double r = ldexp(r1, k);
    int bad = 0;
    if (use_float) {
        CHECK(shl_sphere_grad_f(ctx, x1f, c1f, (float)r1, af, gaf) == SHL_OK);
        CHECK(shl_sphere_grad_f(ctx, xf, cf, (float)r, bf, gbf) == SHL_OK);
        for (int i = 0; i < NC; ++i) bad += af[i] != bf[i];
        for (int i = 0; i < 3 * NC; ++i) bad += gbf[i] != (float)ldexp(gaf[i], -k);
        return bad;
    }
    CHECK(shl_sphere_grad(ctx, x1, c1, r1, a, ga) == SHL_OK && shl_sphere_grad(ctx, x, c, r, b, gb) == SHL_OK);
    for (int i = 0; i < NC; ++i) bad += a[i] != b[i];
    for (int i = 0; i < 3 * NC; ++i) bad += !(gb[i] == ldexp(ga[i], -k));
    return bad + !(a[0] > 0.0 && a[0] < sqrt(4.0 * M_PI)); /* outside the sphere */
}

SHL_TEST(sphere_extreme_scales)
{
    shl_ctx *ctx = ctx_or_die(L);
    const double x[3] = {-1, 0.25, -0.5}, c[3] = {1, -0.5, 0.75}, o[3] = {0, 0, 0}, cd[3] = {1, 0.5, 0.25};
    int bad = 0;
    const int ks[] = {-1060, -1000, -500, 500, 1000, 1023};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i) bad += sphere_scaled_mismatches(ctx, ks[i], x, c, 0.5, 0);
    bad += sphere_scaled_mismatches(ctx, -1050, o, cd, 0x1p-20, 0); /* |c - x| ~ 2^-1050, r = 2^-1070 */
    const int kf[] = {-120, -60, 60, 100};
    for (size_t i = 0; i < sizeof kf / sizeof kf[0]; ++i) bad += sphere_scaled_mismatches(ctx, kf[i], x, c, 0.5, 1);
    CHECK(bad == 0);
    harness_note("2^-1060..2^1023 (double), 2^-120..2^100 (float): %d values differ from the scaled scale-1 result", bad);
    shl_ctx_destroy(ctx);
}

/* dL_00/dx of a sphere seen from x in closed form, long double (x87: exponent range to
 * 1e-4951, so r^2 and d^3 below 1e-600 are exact to 64 bits): L_00 = sqrt(pi) (1 - cos a)
 * (HVL Eq. 14, l = 0), cos a = sqrt(d^2 - r^2) / d, so d(1 - cos a)/dd = -r^2 / (d^2
 * sqrt(d^2 - r^2)) and dd/dx = -u: dL_00/dx = sqrt(pi) r^2 u / (d^2 sqrt(d^2 - r^2)). */
static void l00_grad_ref(const double x[3], const double c[3], double r, long double g[3])
{
    long double v[3], d2 = 0.0L;
    for (int k = 0; k < 3; ++k) v[k] = (long double)c[k] - x[k], d2 += v[k] * v[k];
    const long double d = sqrtl(d2), rr = (long double)r * r;
    const long double f = sqrtl((long double)M_PI) * rr / (d2 * sqrtl(d2 - rr)) / d; /* times v = d u */
    for (int k = 0; k < 3; ++k) g[k] = f * v[k];
}

/* sin^2 a = (r/d)^2 below the smallest normal (r/d < 2^-511; fuzz_lights-sphere-sin2-
 * underflow-gradient): the coefficients are subnormal, but the gradient (~2 sqrt(pi)
 * r^2 / d^3) is a normal number and must keep full relative accuracy in shl_sphere_grad
 * and shl_lights_eval alike, as at float scale (sin^2 a below FLT_MIN, r/d < 2^-63) in
 * shl_sphere_grad_f.  Tolerance, first order in eps = DBL_EPSILON/2 per rounding: the
 * scaled difference c - x (1 rounding), |v|^2 (2.5), d = sqrt (1.75), 1/d (2.25), sin a =
 * r/d (2.75), sin^2 a (6), k_alpha = sin^2 a / cos a / d (9.25), times 2 pi and K_0
 * (10.25, 11.25), times u_k (u_k within 3.25: 15 eps); the power-of-two rescale is exact
 * and the long-double reference within 2^-63: |grad L_00| within 16 eps = 8 DBL_EPSILON.
 * shl_lights_eval adds K_0 = sqrt(1/(4 pi)) and the ZH -> SH reconstruction of band 0
 * (a few roundings): 12 DBL_EPSILON.  Float: the kernels' inputs are rounded from
 * double (0.5 eps_f each) and combined in about eight float operations: 8 FLT_EPSILON.
 * Before the fix the double error was O(1) (0.6 at the fuzz reproducer's geometry),
 * the float one 8.6%. */
SHL_TEST(sphere_sin2_underflow_gradient)
{
    rng_t rg = {77};
    double worst_d = 0.0, worst_l = 0.0, worst_f = 0.0;
    const int lmaxes[] = {0, 3, 9};
    for (size_t li = 0; li < sizeof lmaxes / sizeof lmaxes[0]; ++li) {
        const int lmax = lmaxes[li], nc = SHL_NCOEFFS(lmax);
        shl_ctx *ctx = ctx_or_die(lmax);
        shl_lights *set = NULL;
        double co[NC], g[3 * NC], rgb[3 * NC], lg[9 * NC];
        for (int it = 0; it < 40; ++it) {
            double x[3], c[3];
            const double rad = tiny_sphere_case(&rg, it == 0, x, c);
            long double ref[3];
            l00_grad_ref(x, c, rad, ref);
            CHECK(shl_sphere_grad(ctx, x, c, rad, co, g) == SHL_OK);
            worst_d = fmax(worst_d, rel_norm_err(g, nc, ref, 3));
            const double one[3] = {1.0, 1.0, 1.0};
            CHECK(shl_lights_create(&set) == SHL_OK && shl_lights_add_sphere(set, c, rad, one) == SHL_OK);
            CHECK(shl_lights_eval(ctx, set, x, rgb, lg) == SHL_OK);
            shl_lights_destroy(set);
            worst_l = fmax(worst_l, rel_norm_err(lg, nc, ref, 3)); /* channel 0, layout (c*3 + a)*nc + k */
        }
        for (int it = 0; it < 40; ++it) {
            /* float: d from 2^-75 to 2^-5, r/d from 2^-33 to 2^-es_max with the gradient (~r^2/d^3)
             * above 2^-115 and r above 2^-140 (normal float results from near-normal inputs) */
            double dir[3], x[3], c[3];
            float xf[3], cf[3], cof[NC], gf[3 * NC];
            rng_unit_vector(&rg, dir);
            const int ed = -5 - (int)(rng_uniform(&rg) * 70);
            const int es_max = (115 - ed) / 2 < ed + 140 ? (115 - ed) / 2 : ed + 140;
            const int es = 33 + (int)(rng_uniform(&rg) * (es_max - 33));
            const double d = ldexp(rng_range(&rg, 1.0, 2.0), ed);
            float rf = (float)ldexp(rng_range(&rg, 1.0, 2.0), ed - es);
            for (int k = 0; k < 3; ++k)
                cf[k] = (float)ldexp(rng_range(&rg, -1.0, 1.0), ed), xf[k] = (float)(cf[k] - d * dir[k]);
            if (it == 0) /* r = 1e-44 seen from 1e-22 (the README's float case) */
                xf[0] = 1e-22f, xf[1] = xf[2] = 0.0f, cf[0] = cf[1] = cf[2] = 0.0f, rf = 1e-44f;
            for (int k = 0; k < 3; ++k) x[k] = xf[k], c[k] = cf[k];
            long double ref[3];
            l00_grad_ref(x, c, rf, ref);
            CHECK(shl_sphere_grad_f(ctx, xf, cf, rf, cof, gf) == SHL_OK);
            const double g0[3] = {gf[0], gf[nc], gf[2 * nc]};
            worst_f = fmax(worst_f, rel_norm_err(g0, 1, ref, 3));
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(worst_d <= 8.0 * DBL_EPSILON && worst_l <= 12.0 * DBL_EPSILON && worst_f <= 8.0 * FLT_EPSILON);
    harness_note("r/d 2^-512..2^-590, |grad L_00| rel err vs closed form: shl_sphere_grad %.1e eps, shl_lights_eval "
                 "%.1e eps; float r/d 2^-33..2^-95: %.2f eps_f",
                 worst_d / DBL_EPSILON, worst_l / DBL_EPSILON, worst_f / FLT_EPSILON);
}
