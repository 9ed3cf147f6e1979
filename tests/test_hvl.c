/* BRDF SH tables (HVL Eq. 16-18) and Harmonics Virtual Lights (Eq. 19-26):
 * BRDF values, tables against closed forms and independent quadrature, lookup
 * and frame change, allocation failure, the overlap factor H, the HVL sum
 * against an assembly from public pieces, the radius heuristics, bad input. */
#include "asin_ref.h"
#include "capref.h"
#include "harness.h"
#include "rotutil.h"
#include "shlight.h"
#include <float.h>
#include <math.h>
#include "internal.h" /* shl__alloc_fail_after (src/alloc.c, built with SHL_ALLOC_HOOKS) */

enum { L = SHL_LMAX_MAX, NC = SHL_NCOEFFS(SHL_LMAX_MAX) };

static double band_k(int l) { return sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); }

/* Independent BRDF (local frame, unit vectors). */
static double ref_brdf(const shl_brdf *b, const double wi[3], const double wo[3])
{
    if (wi[2] <= 0.0 || wo[2] <= 0.0) return 0.0;
    double f = b->kd / M_PI;
    if (b->model == SHL_BRDF_PHONG) {
        const double r[3] = {-wo[0], -wo[1], wo[2]}, c = r[0] * wi[0] + r[1] * wi[1] + r[2] * wi[2];
        return f + (c > 0.0 ? b->ks * (b->exponent + 2.0) / (2.0 * M_PI) * pow(c, b->exponent) : 0.0);
    }
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    const double hn = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int k = 0; k < 3; ++k) h[k] /= hn;
    const double a2 = b->alpha * b->alpha, th = acos(fmin(1.0, h[2]));
    const double d = a2 / (M_PI * pow(cos(th), 4) * pow(a2 + tan(th) * tan(th), 2));
    const double ti = tan(acos(wi[2])), to = tan(acos(wo[2]));
    const double g = 2.0 / (1.0 + sqrt(1.0 + a2 * ti * ti) + sqrt(1.0 + a2 * to * to) - 1.0);
    const double cd = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
    const double fr = b->f0 + (1.0 - b->f0) * pow(1.0 - cd, 5);
    return f + b->ks * d * g * fr / (4.0 * wi[2] * wo[2]);
}

SHL_TEST(brdf_eval_values)
{
    const shl_brdf ggx = {SHL_BRDF_GGX, 0.3, 0.8, 0.25, 0.04, 0.0}, ph = {SHL_BRDF_PHONG, 0.2, 0.5, 0, 0, 30.0};
    const double n[3] = {0, 0, 1}, below[3] = {0.3, 0.1, -0.2};
    double v, worst = 0.0;
    /* normal incidence: D = 1/(pi alpha^2), G = 1, F = f0 */
    CHECK(shl_brdf_eval(&ggx, n, n, &v) == SHL_OK);
    CHECK_NEAR(v, 0.3 / M_PI + 0.8 * 0.04 / (4.0 * M_PI * 0.25 * 0.25), 1e-15);
    /* Phong at the mirror direction */
    const double wo[3] = {0.6, 0.0, 0.8}, r[3] = {-0.6, 0.0, 0.8};
    CHECK(shl_brdf_eval(&ph, r, wo, &v) == SHL_OK);
    CHECK_NEAR(v, 0.2 / M_PI + 0.5 * 32.0 / (2.0 * M_PI), 1e-14);
    CHECK(shl_brdf_eval(&ph, below, wo, &v) == SHL_OK && v == 0.0);
    CHECK(shl_brdf_eval(&ggx, wo, below, &v) == SHL_OK && v == 0.0);
    rng_t rg = {41};
    for (int it = 0; it < 200; ++it) { /* reciprocity, independent formula, unnormalized inputs */
        double a[3], b[3], ab = 0.0, ba = 0.0;
        rng_unit_vector(&rg, a);
        rng_unit_vector(&rg, b);
        a[2] = fabs(a[2]);
        b[2] = fabs(b[2]);
        const double a3[3] = {3 * a[0], 3 * a[1], 3 * a[2]};
        const shl_brdf *m = (it & 1) ? &ggx : &ph;
        CHECK(shl_brdf_eval(m, a3, b, &ab) == SHL_OK && shl_brdf_eval(m, b, a, &ba) == SHL_OK);
        worst = fmax(worst, fabs(ab - ba) / ab + fabs(ab - ref_brdf(m, a, b)) / ab);
    }
    CHECK(worst < 1e-12);
    harness_note("reciprocity + independent formula: max rel diff %.1e", worst);
}

/* 2 pi K_l int_0^1 t^p P_l(t) dt for p = 0, 1 (exact Gauss-Legendre) */
static double zh_power(int l, int p)
{
    double gx[32], gw[32], s = 0.0;
    capref_gauss_legendre(32, gx, gw);
    for (int i = 0; i < 32; ++i) {
        const double t = 0.5 * (gx[i] + 1.0);
        s += 0.5 * gw[i] * (p ? t : 1.0) * legendre_p(l, t);
    }
    return 2.0 * M_PI * band_k(l) * s;
}

SHL_TEST(brdf_table_diffuse_exact)
{
    const shl_brdf b = {SHL_BRDF_GGX, 0.7, 0.0, 0.5, 0.0, 0.0};
    shl_brdf_table *t;
    CHECK(shl_brdf_table_create(L, &b, 10, &t) == SHL_OK);
    CHECK(shl_brdf_table_lmax(t) == L);
    double worst = 0.0, fr[9], fc[NC], f[NC];
    for (int j = 0; j < 10; ++j) {
        const double th = j * 0.5 * M_PI / 10, n[3] = {0, 0, 1}, wo[3] = {sin(th), 0, cos(th)};
        CHECK(shl_brdf_table_lookup(t, n, wo, fr, fc, f) == SHL_OK);
        for (int l = 0; l <= L; ++l)
            for (int m = -l; m <= l; ++m) {
                const int k = l * (l + 1) + m;
                const double wc = m ? 0.0 : 0.7 / M_PI * zh_power(l, 1), wf = m ? 0.0 : 0.7 / M_PI * zh_power(l, 0);
                worst = fmax(worst, fmax(fabs(fc[k] - wc), fabs(f[k] - wf)));
            }
    }
    CHECK(worst < 3e-15);
    harness_note("Lambertian F, F' vs closed form: max |err| %.1e (lmax %d)", worst, L);
    shl_brdf_table_destroy(t);
}

/* F, F' at (theta_o, 0) by brute force: Gauss-Legendre in cos(theta_i) on 8
 * panels x the trapezoid rule in s with phi = s + beta sin(s) (periodic, so
 * still spectrally accurate; beta near 1 packs the nodes around the lobe at
 * phi = pi), on a grid unrelated to the library's. */
static void brute_table(const shl_brdf *b, int lmax, double theta_o, int nph, double beta, double *fc,
                        double *f)
{
    enum { NU = 40, NPAN = 8 };
    const int nc = SHL_NCOEFFS(lmax);
    double gx[NU], gw[NU], y[SHL_NCOEFFS(CAPREF_LMAX)];
    const double wo[3] = {sin(theta_o), 0.0, cos(theta_o)};
    capref_gauss_legendre(NU, gx, gw);
    for (int k = 0; k < nc; ++k) fc[k] = f[k] = 0.0;
    for (int p = 0; p < NPAN; ++p)
        for (int i = 0; i < NU; ++i) {
            const double u = (p + 0.5 * (gx[i] + 1.0)) / NPAN, s = sqrt(1.0 - u * u);
            for (int j = 0; j < nph; ++j) {
                const double sv = 2.0 * M_PI * j / nph, phi = sv + beta * sin(sv);
                const double wi[3] = {s * cos(phi), s * sin(phi), u};
                const double w = 0.5 * gw[i] / NPAN * 2.0 * M_PI / nph * (1.0 + beta * cos(sv)) * ref_brdf(b, wi, wo);
                if (w == 0.0) continue;
                shl_eval_basis(lmax, wi, y);
                for (int k = 0; k < nc; ++k) {
                    f[k] += w * y[k];
                    fc[k] += w * u * y[k];
                }
            }
        }
}

SHL_TEST(brdf_table_vs_brute_force)
{
    enum { LL = 8, NN = SHL_NCOEFFS(8), NT = 90 };
    const shl_brdf bs[2] = {{SHL_BRDF_GGX, 0.2, 1.0, 0.1, 0.04, 0.0}, {SHL_BRDF_PHONG, 0.1, 0.9, 0, 0, 20.0}};
    /* 0, 30, 60, 85 degrees; GGX also at 88, where its lobe is 2 alpha cos(theta_o) wide across the plane */
    const int js[5] = {0, 30, 60, 85, 88};
    double worst = 0.0;
    for (int m = 0; m < 2; ++m) {
        shl_brdf_table *t;
        CHECK(shl_brdf_table_create(LL, &bs[m], NT, &t) == SHL_OK);
        for (int i = 0; i < (m ? 4 : 5); ++i) {
            const double th = js[i] * 0.5 * M_PI / NT, n[3] = {0, 0, 1}, wo[3] = {sin(th), 0, cos(th)};
            double fr[9], fc[NN], f[NN], rc[NN], rf[NN];
            CHECK(shl_brdf_table_lookup(t, n, wo, fr, fc, f) == SHL_OK);
            brute_table(&bs[m], LL, th, 1440, js[i] >= 85 ? 0.95 : 0.0, rc, rf);
            double e = 0;
            for (int k = 0; k < NN; ++k)
                e = fmax(e, fmax(fabs(fc[k] - rc[k]) / fabs(rc[0]), fabs(f[k] - rf[k]) / fabs(rf[0])));
            worst = fmax(worst, e);
        }
        shl_brdf_table_destroy(t);
    }
    CHECK(worst < 3e-12);
    harness_note("GGX 0.1 (0..88 deg) / Phong 20 (0..85 deg) vs brute force: max |err| / |F_00| %.1e", worst);
}

/* Normal incidence, where F is zonal.  Phong: 2 pi K_l times
 * int_0^1 t^n P_l(t) dt = 1/(n+1) int_0^inf e^-v P_l(e^(-v/(n+1))) dv
 * (t = e^(-v/(n+1))), Gauss-Legendre on 40 panels of [0, 40].  GGX: a 1D
 * quadrature in theta_h, through tan(theta_h) = alpha tan(psi) near the peak. */
static double phong_moment(int l, double n)
{
    double gx[16], gw[16], s = 0.0;
    capref_gauss_legendre(16, gx, gw);
    for (int p = 0; p < 40; ++p)
        for (int i = 0; i < 16; ++i) {
            const double v = p + 0.5 * (gx[i] + 1.0);
            s += 0.5 * gw[i] * exp(-v) * legendre_p(l, exp(-v / (n + 1.0)));
        }
    return s / (n + 1.0);
}

static void ggx_normal_ref(const shl_brdf *b, int lmax, double *fc)
{
    double gx[16], gw[16];
    capref_gauss_legendre(16, gx, gw);
    for (int l = 0; l <= lmax; ++l) fc[l] = 0.0;
    const double a = b->alpha, th1 = atan(fmin(1.0, 20.0 * a)), psi1 = atan(tan(th1) / a);
    const double n[3] = {0, 0, 1};
    for (int part = 0; part < 2; ++part) /* theta_h in [0, th1] by psi, then [th1, pi/4] */
        for (int p = 0; p < 200; ++p)
            for (int i = 0; i < 16; ++i) {
                double th, dth;
                if (part == 0) {
                    const double h = psi1 / 200, psi = h * (p + 0.5 * (gx[i] + 1.0)), tp = tan(psi);
                    th = atan(a * tp);
                    dth = 0.5 * h * gw[i] * a / (cos(psi) * cos(psi) * (1.0 + a * a * tp * tp));
                } else {
                    const double h = (0.25 * M_PI - th1) / 200;
                    th = th1 + h * (p + 0.5 * (gx[i] + 1.0));
                    dth = 0.5 * h * gw[i];
                }
                const double ti = 2.0 * th, wi[3] = {sin(ti), 0.0, cos(ti)};
                /* d omega_i = 2 pi sin(theta_i) d theta_i, d theta_i = 2 d theta_h */
                const double w = dth * 2.0 * 2.0 * M_PI * sin(ti) * ref_brdf(b, wi, n) * cos(ti);
                for (int l = 0; l <= lmax; ++l) fc[l] += w * band_k(l) * legendre_p(l, cos(ti));
            }
}

SHL_TEST(brdf_table_normal_incidence)
{
    const double n[3] = {0, 0, 1};
    double worst_p = 0.0, worst_g = 0.0;
    const double exps[5] = {0.5, 2.0, 1e3, 1e4, 1e5}; /* blunt lobes: cut off at the horizon */
    for (int i = 0; i < 5; ++i) {
        const shl_brdf b = {SHL_BRDF_PHONG, 0.0, 1.0, 0, 0, exps[i]};
        shl_brdf_table *t;
        double fr[9], fc[NC];
        CHECK(shl_brdf_table_create(L, &b, 2, &t) == SHL_OK);
        CHECK(shl_brdf_table_lookup(t, n, n, fr, fc, NULL) == SHL_OK);
        for (int l = 0; l <= L; ++l) {
            const double want = (exps[i] + 2.0) * band_k(l) * phong_moment(l, exps[i] + 1.0);
            worst_p = fmax(worst_p, fabs(fc[l * (l + 1)] - want) / band_k(l));
        }
        shl_brdf_table_destroy(t);
    }
    const double alphas[3] = {0.005, 0.02, 0.1};
    for (int i = 0; i < 3; ++i) {
        const shl_brdf b = {SHL_BRDF_GGX, 0.0, 1.0, alphas[i], 0.5, 0.0};
        shl_brdf_table *t;
        double fr[9], fc[NC], ref[L + 1];
        CHECK(shl_brdf_table_create(L, &b, 2, &t) == SHL_OK);
        CHECK(shl_brdf_table_lookup(t, n, n, fr, fc, NULL) == SHL_OK);
        ggx_normal_ref(&b, L, ref);
        for (int l = 0; l <= L; ++l) worst_g = fmax(worst_g, fabs(fc[l * (l + 1)] - ref[l]) / band_k(l));
        shl_brdf_table_destroy(t);
    }
    CHECK(worst_p < 3e-12 && worst_g < 5e-13);
    harness_note("normal incidence, |F_l0 - ref| / K_l: Phong n=0.5..1e5 %.1e, GGX alpha 0.005..0.1 %.1e",
                 worst_p, worst_g);
}

/* Sharp Phong lobes at oblique incidence (issue 20's pattern in brdf.c: (r . wi)^n with
 * r . wi rounded near 1 put n 1e-16 relative into every node, and phi = pi - psi rounded
 * psi near the lobe: 3.4e-11 at n = 1e6).  Away from the horizon (sin(theta_o)^n <
 * e^-190 here) the lobe is circularly symmetric about r = (-sin theta_o, 0, cos theta_o)
 * in the table's frame, so by Funk-Hecke F'_lm = ks (n+2) int_0^1 t^n P_l(t) dt Y_lm(r):
 * F'_l0 = c_l K_l P_l(cos theta_o), band norm |c_l| K_l (addition theorem).  Tolerance
 * 1e-12 K_l: the projector's own budget (brdf.c: the panels leave out below 1e-12). */
SHL_TEST(brdf_table_sharp_phong_oblique)
{
    const double exps[3] = {1e4, 1e5, 1e6}, n[3] = {0, 0, 1};
    double worst = 0.0;
    for (int i = 0; i < 3; ++i) {
        const shl_brdf b = {SHL_BRDF_PHONG, 0.0, 1.0, 0, 0, exps[i]};
        shl_brdf_table *t;
        CHECK(shl_brdf_table_create(L, &b, 8, &t) == SHL_OK);
        for (int j = 0; j < 8; ++j) { /* table nodes theta_o = j pi/16, up to 78.75 deg */
            const double th = j * (0.5 * M_PI / 8), wo[3] = {sin(th), 0.0, cos(th)};
            double fr[9], f[NC];
            CHECK(shl_brdf_table_lookup(t, n, wo, fr, NULL, f) == SHL_OK);
            for (int l = 0; l <= L; ++l) {
                const double c = (exps[i] + 2.0) * phong_moment(l, exps[i]);
                double norm2 = 0.0;
                for (int m = -l; m <= l; ++m) norm2 += f[l * (l + 1) + m] * f[l * (l + 1) + m];
                worst = fmax(worst, fabs(f[l * (l + 1)] - c * band_k(l) * legendre_p(l, cos(th))) / band_k(l));
                worst = fmax(worst, fabs(sqrt(norm2) - fabs(c) * band_k(l)) / band_k(l));
            }
        }
        shl_brdf_table_destroy(t);
    }
    CHECK(worst < 1e-12);
    harness_note("Phong n=1e4..1e6, theta_o 0..79 deg, F' vs Funk-Hecke: max |err| / K_l %.1e", worst);
}

SHL_TEST(brdf_table_lookup_and_frame_change)
{
    enum { LL = 10, NN = SHL_NCOEFFS(10) };
    const shl_brdf b = {SHL_BRDF_GGX, 0.3, 0.7, 0.2, 0.04, 0.0};
    shl_brdf_table *t;
    CHECK(shl_brdf_table_create(LL, &b, 90, &t) == SHL_OK);
    rng_t r = {42};
    double worst_frame = 0.0, worst_interp = 0.0, worst_rot = 0.0;
    for (int it = 0; it < 10; ++it) {
        double rot[9], fr[9], fc[NN], f[NN];
        random_rotation(&r, rot);
        /* the sample theta_7 and the midpoint of theta_7, theta_8 in a random world frame */
        const double th7 = 7 * 0.5 * M_PI / 90, loc_n[3] = {0, 0, 1};
        double n[3], wo[3], wo_mid[3], fc7[NN], fc8[NN], fcm[NN];
        mat_vec3(rot, loc_n, n);
        const double l7[3] = {sin(th7), 0, cos(th7)}, lm[3] = {sin(th7 + M_PI / 360), 0, cos(th7 + M_PI / 360)};
        const double l8[3] = {sin(th7 + M_PI / 180), 0, cos(th7 + M_PI / 180)};
        double w8[3];
        mat_vec3(rot, l7, wo);
        mat_vec3(rot, lm, wo_mid);
        mat_vec3(rot, l8, w8);
        CHECK(shl_brdf_table_lookup(t, n, wo, fr, fc7, f) == SHL_OK);
        CHECK(shl_brdf_table_lookup(t, n, w8, fr, fc8, NULL) == SHL_OK);
        CHECK(shl_brdf_table_lookup(t, n, wo_mid, fr, fcm, NULL) == SHL_OK);
        for (int k = 0; k < NN; ++k) worst_interp = fmax(worst_interp, fabs(fcm[k] - 0.5 * (fc7[k] + fc8[k])));
        CHECK(shl_brdf_table_lookup(t, n, wo, fr, fc, f) == SHL_OK);
        /* frame: orthonormal rows, z = n, wo in the xz-plane with x . wo > 0 */
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double d = fr[3 * i] * fr[3 * j] + fr[3 * i + 1] * fr[3 * j + 1] + fr[3 * i + 2] * fr[3 * j + 2];
                worst_frame = fmax(worst_frame, fabs(d - (i == j)));
            }
        double wl[3];
        mat_vec3(fr, wo, wl);
        worst_frame = fmax(worst_frame, fabs(wl[1]) + fabs(fr[6] - n[0]) + fabs(fr[7] - n[1]) + fabs(fr[8] - n[2]));
        CHECK(wl[0] > 0.0);
        /* a sphere light: Eq. (15) with the local axis (frame change of Sec. 4.2)
         * equals the world SH vector rotated into the frame */
        shl_ctx *ctx;
        CHECK(shl_ctx_create(LL, &ctx) == SHL_OK);
        double x[3] = {0.1, 0.2, 0.3}, c[3], dir[3], lw[NN], ll[NN], zh[LL + 1], axl[3];
        rng_unit_vector(&r, dir);
        for (int k = 0; k < 3; ++k) c[k] = x[k] + 2.0 * dir[k];
        CHECK(shl_sphere(ctx, x, c, 0.7, lw) == SHL_OK);
        CHECK(shl_sh_rotate(LL, fr, lw, lw) == SHL_OK);
        CHECK(shl_zh_cap(LL, asin(0.35), zh) == SHL_OK);
        mat_vec3(fr, dir, axl);
        CHECK(shl_zh_to_sh(LL, zh, axl, ll) == SHL_OK);
        double d1 = 0.0, d2 = 0.0, sc = 0.0;
        for (int k = 0; k < NN; ++k) {
            d1 += lw[k] * fc[k];
            d2 += ll[k] * fc[k];
            sc += fabs(ll[k] * fc[k]);
        }
        worst_rot = fmax(worst_rot, fabs(d1 - d2) / sc);
        shl_ctx_destroy(ctx);
    }
    /* below the horizon: zeros; grazing holds the last sample */
    double fr[9], fc[NN], f[NN], g[NN];
    const double n[3] = {0, 0, 1}, back[3] = {0.5, 0, -0.1}, graze[3] = {1, 0, 1e-9}, last[3] = {sin(89 * M_PI / 180), 0, cos(89 * M_PI / 180)};
    CHECK(shl_brdf_table_lookup(t, n, back, fr, fc, f) == SHL_OK);
    for (int k = 0; k < NN; ++k) CHECK(fc[k] == 0.0 && f[k] == 0.0);
    CHECK(shl_brdf_table_lookup(t, n, graze, fr, fc, NULL) == SHL_OK);
    CHECK(shl_brdf_table_lookup(t, n, last, fr, g, NULL) == SHL_OK);
    for (int k = 0; k < NN; ++k) CHECK_NEAR(fc[k], g[k], 1e-12 * fabs(g[0]));
    CHECK(worst_frame < 1e-14 && worst_interp < 1e-15 && worst_rot < 1e-13);
    harness_note("frame %.1e, interpolation %.1e, L.F frame change vs SH rotation %.1e of sum|terms|", worst_frame,
                 worst_interp, worst_rot);
    shl_brdf_table_destroy(t);
}

SHL_TEST(brdf_table_bad_input_and_alloc_failure)
{
    const shl_brdf ok = {SHL_BRDF_PHONG, 0.5, 0.5, 0, 0, 10.0};
    shl_brdf bad = ok;
    shl_brdf_table *t = (shl_brdf_table *)&bad; /* sentinel: set to NULL on failure */
    shl_brdf_table *const sentinel = t;
    CHECK(shl_brdf_table_create(4, NULL, 90, &t) == SHL_ENULL);
    CHECK(shl_brdf_table_create(4, &ok, 90, NULL) == SHL_ENULL);
    CHECK(shl_brdf_table_create(-1, &ok, 90, &t) == SHL_ELMAX);
    CHECK(shl_brdf_table_create(31, &ok, 90, &t) == SHL_ELMAX);
    CHECK(shl_brdf_table_create(4, &ok, 1, &t) == SHL_EDOMAIN);
    CHECK(shl_brdf_table_create(4, &ok, 1025, &t) == SHL_EDOMAIN);
    bad.model = 7;
    CHECK(shl_brdf_table_create(4, &bad, 90, &t) == SHL_EDOMAIN);
    bad = ok;
    bad.kd = -0.1;
    CHECK(shl_brdf_table_create(4, &bad, 90, &t) == SHL_EDOMAIN);
    bad = ok;
    bad.exponent = NAN;
    CHECK(shl_brdf_table_create(4, &bad, 90, &t) == SHL_ENONFINITE);
    bad = ok;
    bad.exponent = 2e6;
    CHECK(shl_brdf_table_create(4, &bad, 90, &t) == SHL_EDOMAIN);
    const shl_brdf ggx_bad[3] = {{SHL_BRDF_GGX, 0.5, 0.5, 1e-4, 0.0, 0}, {SHL_BRDF_GGX, 0.5, 0.5, 0.5, 1.5, 0},
                                 {SHL_BRDF_GGX, 0.5, INFINITY, 0.5, 0.5, 0}};
    CHECK(shl_brdf_table_create(4, &ggx_bad[0], 90, &t) == SHL_EDOMAIN);
    CHECK(shl_brdf_table_create(4, &ggx_bad[1], 90, &t) == SHL_EDOMAIN);
    CHECK(shl_brdf_table_create(4, &ggx_bad[2], 90, &t) == SHL_ENONFINITE);
    CHECK(t == NULL); /* every call is checked in tests/test_handles.c */
    double v = GUARD_VALUE, fr[9], fc[25];
    const double n[3] = {0, 0, 1}, zero[3] = {0, 0, 0}, nan3[3] = {0, NAN, 1};
    CHECK(shl_brdf_eval(&ggx_bad[0], n, n, &v) == SHL_EDOMAIN);
    CHECK(shl_brdf_eval(&ok, zero, n, &v) == SHL_EDOMAIN);
    CHECK(shl_brdf_eval(&ok, n, nan3, &v) == SHL_ENONFINITE);
    CHECK(shl_brdf_eval(&ok, n, n, NULL) == SHL_ENULL);
    CHECK(v == GUARD_VALUE);
    guard_fill(fr, 9);
    guard_fill(fc, 25);
    CHECK(shl_brdf_frame(zero, n, fr) == SHL_EDOMAIN);
    CHECK(shl_brdf_frame(n, nan3, fr) == SHL_ENONFINITE);
    CHECK(shl_brdf_frame(n, n, NULL) == SHL_ENULL);
    CHECK(shl_brdf_table_lookup(NULL, n, n, fr, fc, NULL) == SHL_ENULL);
    CHECK(shl_brdf_table_lmax(NULL) == SHL_ENULL);
    shl_brdf_table_destroy(NULL);
    /* every allocation failing in turn: SHL_ENOMEM, *out = NULL, nothing leaked (ASan) */
    int failures = 0;
    for (long k = 0;; ++k) {
        t = sentinel;
        shl__alloc_fail_after = k;
        const int st = shl_brdf_table_create(4, &ok, 3, &t);
        shl__alloc_fail_after = -1;
        if (st == SHL_OK) break;
        CHECK(st == SHL_ENOMEM && t == NULL);
        ++failures;
    }
    CHECK(failures == 2);
    CHECK(shl_brdf_table_lookup(t, n, zero, fr, fc, NULL) == SHL_EDOMAIN);
    CHECK(guard_intact(fr, 9) && guard_intact(fc, 25));
    shl_brdf_table_destroy(t);
}

/* Exact fraction of a cap (half-angle a, axis at angle th from the normal)
 * above the horizon, by rings about the axis. */
static double cap_fraction_above(double a, double th)
{
    double s = 0.0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        const double rho = a * (i + 0.5) / n;
        const double x = cos(rho) * cos(th) / (sin(rho) * sin(th)); /* ring point above iff cos(phi) < x */
        const double ring = x >= 1.0 ? 1.0 : (x <= -1.0 ? 0.0 : 1.0 - acos(x) / M_PI);
        s += ring * sin(rho) * a / n;
    }
    return s / (1.0 - cos(a));
}

SHL_TEST(hvl_overlap_factor)
{
    double h, worst = 0.0;
    CHECK(shl_hvl_overlap(1.0, 0.3, &h) == SHL_OK && h == 1.0);
    CHECK(shl_hvl_overlap(0.0, 0.3, &h) == SHL_OK);
    CHECK_NEAR(h, 0.5, 1e-15);
    CHECK(shl_hvl_overlap(-1.0, 0.3, &h) == SHL_OK && h == 0.0);
    CHECK(shl_hvl_overlap(0.1, 0.0, &h) == SHL_OK && h == 1.0);
    CHECK(shl_hvl_overlap(-0.1, 0.0, &h) == SHL_OK && h == 0.0);
    for (double a = 0.05; a < 1.5; a += 0.2) {
        double prev = 2.0;
        for (double th = 0.0; th <= M_PI; th += 0.01) {
            CHECK(shl_hvl_overlap(cos(th), a, &h) == SHL_OK);
            CHECK(h <= prev && h >= 0.0 && h <= 1.0);
            prev = h;
            worst = fmax(worst, fabs(h - cap_fraction_above(a, th)));
        }
    }
    CHECK(worst < 0.1); /* a smoothstep approximation, not exact */
    harness_note("max |H - exact fraction of the cap above the horizon| %.3f (a 0.05..1.45)", worst);
    double g = GUARD_VALUE;
    CHECK(shl_hvl_overlap(1.5, 0.3, &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(0.5, -0.1, &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(0.5, 1.6, &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(NAN, 0.3, &g) == SHL_ENONFINITE);
    CHECK(shl_hvl_overlap(0.5, 0.3, NULL) == SHL_ENULL);
    CHECK(g == GUARD_VALUE);
}

/* ---- H for small caps (issue 20) ------------------------------------------
 * Independent reference (tests/asin_ref.h): asin(c) of the double c by its Taylor series in long
 * double, sum_n binom(2n, n) / (4^n (2n + 1)) x^(2n+1) for |x| <= 1/2 (term ratio
 * x^2 (2n-1)^2 / (2n (2n+1)) < 1/4: 40 terms leave 4^-40 ~ 1e-24 relative), and
 * pi/2 - 2 asin(sqrt((1 - |c|) / 2)) above (1 - |c| exact); then
 * S(clamp((a + asin c) / (2a), 0, 1)) in long double.  Its own error: a few
 * LDBL_EPSILON, absolute, in S.
 * Error of the library (src/hvl.c): asin within 1 ulp (glibc, musl), so
 * e = asin(c) is off by <= 2^-52 |e| < 2^-52 a inside the band; w = (a - |e|) / (2a)
 * rounds twice: |dw| <= 2^-52 a / (2a) + 2 * 2^-53 w <= 2^-52 (w <= 1/2); S' <= 3/2,
 * and the final roundings of S (<= 2^-55 + 2^-100) and of 1 - S (2^-53):
 * |H - H_exact| <= 1.5 * 2^-52 + 2^-53 + 2^-55 < 2.4 DBL_EPSILON, plus the 3e-30 of
 * the edge flush.  Tolerance 3 DBL_EPSILON + 16 LDBL_EPSILON (the issue asks 1e-12). */
static long double smoothstep_ref(long double x)
{
    if (x <= 0.0L) return 0.0L;
    if (x >= 1.0L) return 1.0L;
    return x * x * (3.0L - 2.0L * x);
}

#define H_TOL (3.0 * DBL_EPSILON + 16.0 * LDBL_EPSILON)

/* H(c, a) against the reference; beyond an edge (by more than the reference's
 * error) H must be exactly 1 or 0.  Returns |H - H_ref|. */
static double check_overlap_at(double c, double a)
{
    double h = -1.0;
    CHECK(shl_hvl_overlap(c, a, &h) == SHL_OK);
    const long double e = asin_ref(c), margin = 8.0L * LDBL_EPSILON * a;
    const double err = (double)fabsl((long double)h - smoothstep_ref(((long double)a + e) / (2.0L * a)));
    if (!(err <= H_TOL && h >= 0.0 && h <= 1.0))
        harness_fail(__FILE__, __LINE__, "H(%a, %a) = %.17g, |err| %.3g", c, a, h, err);
    if (e > a + margin && h != 1.0) harness_fail(__FILE__, __LINE__, "cap above: H(%a, %a) = %.17g != 1", c, a, h);
    if (e < -a - margin && h != 0.0) harness_fail(__FILE__, __LINE__, "cap below: H(%a, %a) = %.17g != 0", c, a, h);
    return err;
}

SHL_TEST(hvl_overlap_small_caps)
{
    /* the table of issue 20 */
    static const struct { double c, a, want; } tab[] = {
        {1.0, 1.2e-16, 1.0}, {1.0, 1e-15, 1.0}, {0.5, 1e-16, 1.0}, {1.0, 1e-300, 1.0}, {0.0, 1e-9, 0.5},
        {5e-7, 1e-6, 0.84375}};
    for (size_t i = 0; i < sizeof tab / sizeof *tab; ++i) {
        double h = -1.0;
        CHECK(shl_hvl_overlap(tab[i].c, tab[i].a, &h) == SHL_OK);
        CHECK_NEAR(h, tab[i].want, 1e-12); /* the values, rounded: 0.84375 is 0.84375 + 1.2e-14 */
        check_overlap_at(tab[i].c, tab[i].a);
    }
    /* Tiny caps in closed form: c = delta with |delta| <= 2a <= 2^-29, where
     * asin(delta) = delta (1 + delta^2/6 + ...) and the exact argument is
     * (a + delta) / (2a) + O(a^2) (< 2^-58): no asin in the reference at all.
     * delta at k/16 of a, and at +-a and 1 ulp either side of +-a. */
    static const double tiny[] = {0x1p-1074, 1e-320, 1e-310, DBL_MIN, 1e-300, 1e-200, 1e-100, 1e-30,
                                  1e-16, 1.2e-16, 1e-15, 1e-12, 1e-9, 0x1p-30};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof tiny / sizeof *tiny; ++i) {
        const double a = tiny[i];
        double deltas[41 + 6];
        int nd = 0;
        for (int k = -20; k <= 20; ++k) deltas[nd++] = k * (a / 16.0);
        for (int sg = -1; sg <= 1; sg += 2) {
            deltas[nd++] = sg * a;
            deltas[nd++] = nextafter(sg * a, 0.0);
            deltas[nd++] = nextafter(sg * a, sg * 1.0);
        }
        for (int k = 0; k < nd; ++k) {
            const double d = deltas[k];
            double h = -1.0;
            CHECK(shl_hvl_overlap(d, a, &h) == SHL_OK);
            const long double x = ((long double)a + d) / (2.0L * a);
            const double err = (double)fabsl((long double)h - smoothstep_ref(x));
            worst = fmax(worst, err);
            if (!(err <= H_TOL)) harness_fail(__FILE__, __LINE__, "H(%a, %a) = %.17g, |err| %.3g", d, a, h, err);
            if (fabs(d) >= a) CHECK(h == (d > 0.0 ? 1.0 : 0.0)); /* asin(delta) beyond +-a */
            /* 1 ulp inside an edge (normal a): w ~ 2^-53, flushed, exact H within 1e-31 of 0 or 1 */
            if (a >= DBL_MIN && fabs(d) < a && fabs(d) == nextafter(a, 0.0)) CHECK(h == (d > 0.0 ? 1.0 : 0.0));
        }
    }
    harness_note("tiny caps (a 5e-324..2^-30) vs closed form: max |err| %.1e", worst);
    /* a = 0: a point light; cap-less step with 1/2 on the horizon (the limit a -> 0) */
    double h = -1.0;
    CHECK(shl_hvl_overlap(0x1p-1074, 0.0, &h) == SHL_OK && h == 1.0);
    CHECK(shl_hvl_overlap(-0x1p-1074, 0.0, &h) == SHL_OK && h == 0.0);
    CHECK(shl_hvl_overlap(0.0, 0.0, &h) == SHL_OK && h == 0.5);
    CHECK(shl_hvl_overlap(-0.0, -0.0, &h) == SHL_OK && h == 0.5);
    CHECK(shl_hvl_overlap(1.0, 0.0, &h) == SHL_OK && h == 1.0);
    CHECK(shl_hvl_overlap(-1.0, 0.0, &h) == SHL_OK && h == 0.0);
    /* invalid input: status, nothing written */
    double g = GUARD_VALUE;
    CHECK(shl_hvl_overlap(nextafter(1.0, 2.0), 0.3, &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(0.5, nextafter(0.5 * M_PI, 2.0), &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(0.5, -0x1p-1074, &g) == SHL_EDOMAIN);
    CHECK(shl_hvl_overlap(INFINITY, 0.3, &g) == SHL_ENONFINITE);
    CHECK(shl_hvl_overlap(0.5, NAN, &g) == SHL_ENONFINITE);
    CHECK(g == GUARD_VALUE);
}

/* Ordinary and small caps against the series reference: c = sin(k a / 16) across
 * and beyond the band, the edges +-sin(a) and 4 ulps either side, +-1, 0. */
SHL_TEST(hvl_overlap_vs_series)
{
    static const double as[] = {1e-300, 1e-16, 1e-9, 1e-6, 1e-3, 0.05, 0.3, 0.7, 1.0, 1.3, 1.5, 1.5707963267948963,
                                0.5 * M_PI};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof as / sizeof *as; ++i) {
        const double a = as[i];
        for (int k = -24; k <= 24; ++k) worst = fmax(worst, check_overlap_at(sin(k * a / 16.0), a));
        for (int sg = -1; sg <= 1; sg += 2) {
            double c = sg * sin(a);
            for (int j = 0; j < 4; ++j) c = nextafter(c, -2.0);
            for (int j = 0; j <= 8; ++j, c = nextafter(c, 2.0))
                if (fabs(c) <= 1.0) worst = fmax(worst, check_overlap_at(c, a));
        }
        worst = fmax(worst, check_overlap_at(1.0, a));
        worst = fmax(worst, check_overlap_at(-1.0, a));
        worst = fmax(worst, check_overlap_at(0.0, a));
    }
    harness_note("a 1e-300..pi/2 vs long-double series: max |err| %.1e (%.2f eps)", worst, worst / DBL_EPSILON);
}

/* Property sweep (fixed seed): for 150 half-angles (log-uniform 2^-1074..pi/2,
 * the ends, powers of 2), runs of 4000 consecutive doubles c centred on the edges
 * +-sin(a), on sin(f a) for f = +-0.5, +-0.1, +-0.02 (near the middle, where the
 * plain product w^2 (3 - 2w) steps down by an ulp up to 62 times in such a run)
 * and on a random point, plus 2001 points across [-1, 1]: H in [0, 1], monotone
 * non-decreasing along each run, and every 7th within H_TOL of the reference. */
SHL_TEST(hvl_overlap_monotone_sweep)
{
    static const double fixed[] = {0.5 * M_PI, 0x1p-1074, 1.0, 0.5, 0x1p-20, 0x1p-1000};
    static const double frac[] = {-1.0, -0.5, -0.1, -0.02, 0.02, 0.1, 0.5, 1.0};
    enum { NF = sizeof fixed / sizeof *fixed, NW = sizeof frac / sizeof *frac, RUN = 4000 };
    rng_t r = {2020};
    double worst = 0.0;
    long n = 0;
    for (int i = 0; i < 150; ++i) {
        double a = i < NF ? fixed[i] : ldexp(rng_uniform(&r) + 0.5, -(int)(rng_uniform(&r) * 1074.0));
        if (a > 0.5 * M_PI) a = 0.5 * M_PI;
        for (int s = 0; s <= NW + 1; ++s) {
            double c = s < NW ? sin(frac[s] * a) : (s == NW ? rng_range(&r, -1.0, 1.0) : -1.0), prev = 0.0;
            for (int j = 0; j < RUN / 2 && c > -1.0; ++j) c = nextafter(c, -2.0);
            const int len = s <= NW ? RUN : 2001;
            for (int j = 0; j < len && c <= 1.0; ++j) {
                double h = -1.0;
                CHECK(shl_hvl_overlap(c, a, &h) == SHL_OK);
                if (!(h >= prev && h <= 1.0))
                    harness_fail(__FILE__, __LINE__, "a %a: H(%a) = %a after %a", a, c, h, prev);
                if (j % 7 == 0) worst = fmax(worst, check_overlap_at(c, a));
                prev = h;
                ++n;
                c = s <= NW ? nextafter(c, 2.0) : -1.0 + (j + 1) / 1000.0;
            }
        }
        if (harness_failed_current()) break;
    }
    harness_note("%ld evaluations monotone in [0, 1]; every 7th vs series: max |err| %.1e", n, worst);
}

/* shl_hvl_shade with a small HVL entirely above the horizon (H must be 1; the old
 * Eq. 22 gave 0 or -2.4 for a ~ 1e-16): Lambertian receiver and emitter, radius
 * 1e-8 down to 1e-150 at distance 3.  Closed form: the cap (solid angle
 * Omega = 2 pi t, t = s^2 / (1 + sqrt(1 - s^2)), s = sin a) times the receiver's F
 * truncated at lmax 30 in the cap's direction, (kd/pi) sum_l zh_l K_l P_l(cos theta)
 * (zh_l = zh_power, exact quadrature), up to O(l^2 a^2) < 1e-14 for a < 4e-9,
 * times the emission from the public pieces (Eq. 20-21).  Budget: the tables'
 * 3e-15 per coefficient (brdf_table_diffuse_exact) over 31 bands,
 * 3e-15 sum_l K_l ~ 1.5e-13 of the truncated F (0.21 here): 1e-12 relative. */
SHL_TEST(hvl_shade_small_hvl)
{
    const shl_brdf emit = {SHL_BRDF_PHONG, 1.0, 0.0, 0, 0, 1.0}, recv = {SHL_BRDF_PHONG, 0.8, 0.0, 0, 0, 1.0};
    shl_brdf_table *te, *tr;
    CHECK(shl_brdf_table_create(4, &emit, 90, &te) == SHL_OK);
    CHECK(shl_brdf_table_create(L, &recv, 90, &tr) == SHL_OK);
    const double x[3] = {0, 0, 0}, n[3] = {0, 0, 1}, wo[3] = {0.3, 0, 1}, th = 0.6, d = 3.0;
    static const double radii[] = {1e-8, 3.6e-16, 3e-15, 1e-100, 1e-150};
    double worst = 0.0, fr[9], fp[25], dl[3], e, ftrunc = 0.0;
    for (int l = 0; l <= L; ++l) ftrunc += 0.8 / M_PI * zh_power(l, 1) * band_k(l) * legendre_p(l, cos(th));
    const double mu[3] = {-sin(th), 0.0, -cos(th)};
    shl_hvl h = {{d * sin(th), 0.0, d * cos(th)}, {0.0, 0.0, -1.0}, {0.0, 0.0, -1.0}, 1.0, 2.0, te};
    CHECK(shl_brdf_table_lookup(te, h.normal, h.to_light, fr, NULL, fp) == SHL_OK);
    mat_vec3(fr, mu, dl);
    CHECK(shl_sh_eval(4, fp, dl, &e) == SHL_OK);
    for (size_t i = 0; i < sizeof radii / sizeof *radii; ++i) {
        const double rad = radii[i], s = rad / d, omega = 2.0 * M_PI * s * s / (1.0 + sqrt(1.0 - s * s));
        h.radius = rad;
        double got;
        CHECK(shl_hvl_shade(&h, 1, x, n, wo, tr, &got) == SHL_OK);
        const double want = 2.0 * e * cos(th) / (M_PI * rad * rad) * omega * ftrunc;
        worst = fmax(worst, fabs(got / want - 1.0));
    }
    CHECK(worst < 1e-12);
    harness_note("radius 1e-8..1e-150: max |radiance / closed form - 1| %.1e", worst);
    shl_brdf_table_destroy(te);
    shl_brdf_table_destroy(tr);
}

/* One HVL's term of Eq. (19) assembled from public pieces, with an SH rotation
 * into the receiver's frame instead of the library's frame change. */
static double hvl_term_ref(const shl_hvl *h, const double x[3], const double n[3], const double wo[3],
                           const shl_brdf_table *mat)
{
    const int lm = shl_brdf_table_lmax(mat), le = shl_brdf_table_lmax(h->brdf);
    double fx[9], f[NC], lcap[NC], frj[9], fp[NC], v[3], u[3];
    shl_ctx *ctx;
    shl_ctx_create(lm, &ctx);
    shl_brdf_table_lookup(mat, n, wo, fx, f, NULL);
    shl_sphere(ctx, x, h->pos, h->radius, lcap); /* world frame */
    shl_sh_rotate(lm, fx, lcap, lcap);            /* into the frame of x */
    double lf = 0.0;
    for (int k = 0; k < SHL_NCOEFFS(lm); ++k) lf += lcap[k] * f[k];
    shl_ctx_destroy(ctx);
    for (int k = 0; k < 3; ++k) v[k] = h->pos[k] - x[k];
    const double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k) u[k] = v[k] / d;
    shl_brdf_table_lookup(h->brdf, h->normal, h->to_light, frj, NULL, fp);
    double mu[3], dl[3], e, hh;
    for (int k = 0; k < 3; ++k) mu[k] = -u[k];
    mat_vec3(frj, mu, dl);
    shl_sh_eval(le, fp, dl, &e);
    const double nn = sqrt(h->normal[0] * h->normal[0] + h->normal[1] * h->normal[1] + h->normal[2] * h->normal[2]);
    const double cos_out = -(h->normal[0] * u[0] + h->normal[1] * u[1] + h->normal[2] * u[2]) / nn;
    const double nx = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    shl_hvl_overlap((n[0] * u[0] + n[1] * u[1] + n[2] * u[2]) / nx, asin(h->radius / d), &hh);
    return h->power * e * fmax(0.0, cos_out) / (M_PI * h->radius * h->radius) * hh * lf;
}

SHL_TEST(hvl_shade_matches_assembly)
{
    const shl_brdf emit = {SHL_BRDF_GGX, 0.5, 0.5, 0.4, 0.04, 0.0}, recv = {SHL_BRDF_PHONG, 0.3, 0.6, 0, 0, 15.0};
    shl_brdf_table *te, *tr;
    CHECK(shl_brdf_table_create(3, &emit, 90, &te) == SHL_OK);
    CHECK(shl_brdf_table_create(12, &recv, 90, &tr) == SHL_OK);
    rng_t r = {43};
    shl_hvl hv[16];
    const double x[3] = {0.0, 0.0, 0.0}, n[3] = {0.1, -0.2, 1.0}, wo[3] = {0.5, 0.3, 0.8};
    double want = 0.0, got, scale = 0.0;
    for (int j = 0; j < 16; ++j) {
        double dir[3];
        rng_unit_vector(&r, dir);
        dir[2] = fabs(dir[2]) + 0.3;
        const double d = rng_range(&r, 1.0, 4.0);
        for (int k = 0; k < 3; ++k) hv[j].pos[k] = d * dir[k];
        rng_unit_vector(&r, hv[j].normal);
        if (hv[j].normal[0] * dir[0] + hv[j].normal[1] * dir[1] + hv[j].normal[2] * dir[2] > 0)
            for (int k = 0; k < 3; ++k) hv[j].normal[k] = -hv[j].normal[k]; /* facing x */
        rng_unit_vector(&r, hv[j].to_light); /* mostly above the HVL's horizon */
        for (int k = 0; k < 3; ++k) hv[j].to_light[k] = hv[j].normal[k] + 0.8 * hv[j].to_light[k];
        hv[j].radius = rng_range(&r, 0.1, 0.8);
        hv[j].power = rng_range(&r, 0.5, 2.0);
        hv[j].brdf = te;
        const double term = hvl_term_ref(&hv[j], x, n, wo, tr);
        want += term;
        scale += fabs(term);
    }
    CHECK(shl_hvl_shade(hv, 16, x, n, wo, tr, &got) == SHL_OK);
    CHECK(scale > 0.0);
    CHECK(fabs(got - want) < 3e-15 * scale);
    harness_note("HVL sum vs assembly from public pieces: |diff| / sum|terms| %.1e", fabs(got - want) / scale);
    /* no HVL, or an HVL centred at x: 0 */
    CHECK(shl_hvl_shade(NULL, 0, x, n, wo, tr, &got) == SHL_OK && got == 0.0);
    shl_hvl at_x = hv[0];
    at_x.pos[0] = at_x.pos[1] = at_x.pos[2] = 0.0;
    CHECK(shl_hvl_shade(&at_x, 1, x, n, wo, tr, &got) == SHL_OK && got == 0.0);
    /* entering the sphere: the cap is clamped to the hemisphere, continuously */
    shl_hvl near = hv[0];
    double out_v, in_v;
    const double dn = sqrt(near.pos[0] * near.pos[0] + near.pos[1] * near.pos[1] + near.pos[2] * near.pos[2]);
    near.radius = dn * (1.0 - 1e-12);
    CHECK(shl_hvl_shade(&near, 1, x, n, wo, tr, &out_v) == SHL_OK);
    near.radius = dn * (1.0 + 1e-12);
    CHECK(shl_hvl_shade(&near, 1, x, n, wo, tr, &in_v) == SHL_OK);
    CHECK(out_v != 0.0 && fabs(in_v - out_v) < 1e-5 * fabs(out_v)); /* pi/2 - a ~ sqrt(2e-12) outside */
    shl_brdf_table_destroy(te);
    shl_brdf_table_destroy(tr);
}

/* A Lambertian receiver lit by one small, fully visible HVL: L . F tends to
 * (kd/pi) pi sin^2 a cos(theta) (the uniform spherical light) as lmax grows. */
SHL_TEST(hvl_shade_lambert_limit)
{
    const shl_brdf emit = {SHL_BRDF_PHONG, 1.0, 0.0, 0, 0, 1.0}, recv = {SHL_BRDF_PHONG, 0.8, 0.0, 0, 0, 1.0};
    shl_brdf_table *te, *tr;
    CHECK(shl_brdf_table_create(4, &emit, 90, &te) == SHL_OK);
    CHECK(shl_brdf_table_create(L, &recv, 90, &tr) == SHL_OK);
    const double x[3] = {0, 0, 0}, n[3] = {0, 0, 1}, wo[3] = {0.3, 0, 1};
    const double th = 0.6, d = 3.0, rad = 0.9, a = asin(rad / d);
    shl_hvl h = {{d * sin(th), 0.0, d * cos(th)}, {0.0, 0.0, -1.0}, {0.0, 0.0, -1.0}, rad, 2.0, te};
    double got, hh, e;
    CHECK(shl_hvl_shade(&h, 1, x, n, wo, tr, &got) == SHL_OK);
    CHECK(shl_hvl_overlap(cos(th), a, &hh) == SHL_OK);
    /* emission from the public pieces (Eq. 20-21) */
    double fr[9], fp[25], dl[3];
    const double mu[3] = {-sin(th), 0.0, -cos(th)};
    CHECK(shl_brdf_table_lookup(te, h.normal, h.to_light, fr, NULL, fp) == SHL_OK);
    mat_vec3(fr, mu, dl);
    CHECK(shl_sh_eval(4, fp, dl, &e) == SHL_OK);
    const double emission = 2.0 * e * cos(th) / (M_PI * rad * rad) * hh;
    const double lambert = 0.8 / M_PI * M_PI * sin(a) * sin(a) * cos(th);
    const double rel = fabs(got / (emission * lambert) - 1.0);
    CHECK(rel < 6e-5);
    harness_note("L.F / Lambert closed form - 1 at lmax %d: %.1e", L, rel);
    shl_brdf_table_destroy(te);
    shl_brdf_table_destroy(tr);
}

SHL_TEST(hvl_shade_bad_input)
{
    const shl_brdf b = {SHL_BRDF_PHONG, 0.5, 0.0, 0, 0, 1.0};
    shl_brdf_table *t;
    CHECK(shl_brdf_table_create(2, &b, 4, &t) == SHL_OK);
    const double x[3] = {0, 0, 0}, n[3] = {0, 0, 1}, zero[3] = {0, 0, 0}, nan3[3] = {NAN, 0, 0};
    shl_hvl h = {{0, 0, 2}, {0, 0, -1}, {0, 1, 0}, 0.5, 1.0, t};
    double v = GUARD_VALUE;
    CHECK(shl_hvl_shade(NULL, 1, x, n, n, t, &v) == SHL_ENULL);
    CHECK(shl_hvl_shade(&h, 1, NULL, n, n, t, &v) == SHL_ENULL);
    CHECK(shl_hvl_shade(&h, 1, x, n, n, NULL, &v) == SHL_ENULL);
    CHECK(shl_hvl_shade(&h, 1, x, n, n, t, NULL) == SHL_ENULL);
    CHECK(shl_hvl_shade(&h, -1, x, n, n, t, &v) == SHL_EDOMAIN);
    CHECK(shl_hvl_shade(&h, 1, nan3, n, n, t, &v) == SHL_ENONFINITE);
    CHECK(shl_hvl_shade(&h, 1, x, zero, n, t, &v) == SHL_EDOMAIN);
    shl_hvl bad = h;
    bad.radius = 0.0;
    CHECK(shl_hvl_shade(&bad, 1, x, n, n, t, &v) == SHL_EDOMAIN);
    bad = h;
    bad.power = INFINITY;
    CHECK(shl_hvl_shade(&bad, 1, x, n, n, t, &v) == SHL_ENONFINITE);
    bad = h;
    bad.brdf = NULL;
    CHECK(shl_hvl_shade(&bad, 1, x, n, n, t, &v) == SHL_ENULL);
    bad = h;
    bad.normal[0] = bad.normal[1] = bad.normal[2] = 0.0;
    CHECK(shl_hvl_shade(&bad, 1, x, n, n, t, &v) == SHL_EDOMAIN);
    CHECK(v == GUARD_VALUE);
    shl_brdf_table_destroy(t);
}

SHL_TEST(hvl_radius_heuristics)
{
    /* heuristic 1 on a 3x2 grid: unit spacing in the plane z = 0 */
    double pos[18], dist[6] = {1, 1, 1, 1, 1, 5}, rad[6];
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 3; ++j) {
            pos[3 * (3 * i + j)] = j;
            pos[3 * (3 * i + j) + 1] = i;
            pos[3 * (3 * i + j) + 2] = 0.0;
        }
    CHECK(shl_hvl_radius_grid(3, 2, pos, dist, 1e-3, 1.5, rad) == SHL_OK);
    /* cell 0: neighbours 1 (|dp| 1), 3 (1), 4 (sqrt 2), all at the same distance */
    CHECK_NEAR(rad[0], 1.5 * (2.0 + sqrt(2.0)) / 3.0, 1e-15);
    /* cell 2: neighbours 1 (w 1/eps), 4 (sqrt 2, w 1/eps), 5 (1, w 1/(4 + eps)) */
    const double w5 = 1.0 / (4.0 + 1e-3), w = 1e3;
    CHECK_NEAR(rad[2], 1.5 * (w * 1.0 + w * sqrt(2.0) + w5 * 1.0) / (2 * w + w5), 1e-15);
    /* heuristic 2: the Taylor form against d tan(gamma) (Eq. 25) */
    double d[3] = {0.0, 1.0, 7.5}, r2[3], worst = 0.0;
    CHECK(shl_hvl_radius_fov(3, d, 0.5, 1.0, r2) == SHL_OK);
    const double g = sqrt(2.0) * 0.5 / sqrt(3.0);
    CHECK(r2[0] == 0.0);
    CHECK_NEAR(r2[2], 7.5 * (g + g * g * g / 3.0), 1e-14);
    static double ones[400], rs[400];
    for (int i = 0; i < 400; ++i) ones[i] = 1.0;
    for (int m = 1; m <= 400; ++m) { /* the paper: within 0.01 while gamma <= 0.58 */
        CHECK(shl_hvl_radius_fov(m, ones, 0.2 * M_PI, 1.0, rs) == SHL_OK);
        const double gm = sqrt(2.0) * 0.2 * M_PI / sqrt((double)m);
        if (gm <= 0.58) worst = fmax(worst, fabs(rs[m - 1] - tan(gm)));
    }
    CHECK(worst < 0.0105);
    harness_note("max |Eq.26 - tan gamma| for gamma <= 0.58: %.4f", worst);
    /* bad input */
    double guard[6];
    guard_fill(guard, 6);
    CHECK(shl_hvl_radius_grid(1, 1, pos, dist, 1e-3, 1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_grid(0, 5, pos, dist, 1e-3, 1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_grid(3, 2, pos, dist, 0.0, 1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_grid(3, 2, pos, dist, 1e-3, -1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_grid(3, 2, NULL, dist, 1e-3, 1.0, guard) == SHL_ENULL);
    CHECK(shl_hvl_radius_grid(1 << 16, 1 << 16, pos, dist, 1e-3, 1.0, guard) == SHL_EDOMAIN);
    dist[4] = NAN;
    CHECK(shl_hvl_radius_grid(3, 2, pos, dist, 1e-3, 1.0, guard) == SHL_ENONFINITE);
    d[1] = -1.0;
    CHECK(shl_hvl_radius_fov(3, d, 0.5, 1.0, guard) == SHL_EDOMAIN);
    d[1] = 1.0;
    CHECK(shl_hvl_radius_fov(0, d, 0.5, 1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_fov(3, d, M_PI, 1.0, guard) == SHL_EDOMAIN);
    CHECK(shl_hvl_radius_fov(3, d, NAN, 1.0, guard) == SHL_ENONFINITE);
    CHECK(shl_hvl_radius_fov(3, NULL, 0.5, 1.0, guard) == SHL_ENULL);
    CHECK(guard_intact(guard, 6));
}
