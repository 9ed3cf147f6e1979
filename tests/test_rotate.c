/* SH rotation and ZH -> SH rotation (HVL Eq. 15): energy per band, composition,
 * rotated directions, closed form about z, reflections, in place, numerical
 * integration over rotated caps, bad input and allocation failure. */
#include "capref.h"
#include "harness.h"
#include "rotutil.h"
#include "shlight.h"
#include <float.h>
#include <math.h>
#include "internal.h" /* shl__alloc_fail_after (src/alloc.c, built with SHL_ALLOC_HOOKS) */

enum { L = SHL_LMAX_MAX, NC = SHL_NCOEFFS(SHL_LMAX_MAX) };

static void random_coeffs(rng_t *r, double *c, int n)
{
    for (int k = 0; k < n; ++k) c[k] = rng_range(r, -1.0, 1.0);
}

/* Rounding analysis behind the tolerances of the first two tests.  The band
 * matrices come from the Ivanic-Ruedenberg recurrence, whose column
 * normalisation (1/sqrt(den)) can amplify an error by up to sqrt(l) per band, so
 * a worst-case bound grows without a useful limit; the tolerances use the
 * probabilistic model instead (Higham & Mary, SIAM J. Sci. Comput. 41, 2019):
 * roundings are independent, mean 0, |delta| <= u, variance <= u^2 / 3.  Every
 * entry of D_l is a sum of at most 5 products with about c = 12 roundings over
 * terms whose magnitudes add to T <= 3, so each band adds an error of standard
 * deviation sqrt(c / 3) T u = 6 u to every entry, and after l bands
 * sigma_l = 6 u sqrt(l).  For coefficients f_l and an error matrix E with
 * independent entries of deviation sigma, f^T E f / |f|^2 has deviation sigma and
 * each component of E f has deviation sigma |f|.  A bound of lambda = 6
 * deviations fails with probability < 2e-9 per quantity (Gaussian tail), < 1e-5
 * over the 10^4 quantities checked here. */
static double rot_sigma(int l) { return 6.0 * (DBL_EPSILON / 2) * sqrt((double)l); }
enum { LAMBDA = 6 };

SHL_TEST(rotate_preserves_band_energy)
{
    rng_t r = {21};
    double worst = 0.0;
    for (int it = 0; it < 10; ++it) {
        double rot[9], f[NC], g[NC];
        random_rotation(&r, rot);
        random_coeffs(&r, f, NC);
        CHECK(shl_sh_rotate(L, rot, f, g) == SHL_OK);
        for (int l = 0; l <= L; ++l) {
            double ef = 0.0, eg = 0.0;
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                ef += f[k] * f[k];
                eg += g[k] * g[k];
            }
            worst = fmax(worst, fabs(eg / ef - 1.0));
        }
    }
    /* |g|^2 / |f|^2 - 1 = 2 f^T E f / |f|^2 + O(u^2) */
    const double tol = LAMBDA * 2.0 * rot_sigma(L);
    CHECK(worst < tol);
    harness_note("max |band energy ratio - 1| %.1e (lmax %d; tol %.1e, 6 deviations of the rounding model)", worst, L,
                 tol);
}

SHL_TEST(rotate_composition)
{
    rng_t r = {22};
    double worst = 0.0;
    for (int it = 0; it < 10; ++it) {
        double r1[9], r2[9], r21[9], f[NC], a[NC], b[NC];
        random_rotation(&r, r1);
        random_rotation(&r, r2);
        mat_mul3(r2, r1, r21);
        random_coeffs(&r, f, NC);
        CHECK(shl_sh_rotate(L, r1, f, a) == SHL_OK);
        CHECK(shl_sh_rotate(L, r2, a, a) == SHL_OK); /* in place */
        CHECK(shl_sh_rotate(L, r21, f, b) == SHL_OK);
        for (int k = 0; k < NC; ++k) worst = fmax(worst, fabs(a[k] - b[k]));
    }
    /* (E2 D1 + D2 E1 - E21) f_l: three independent errors of deviation sigma |f_l| each,
     * |f_l| = sqrt((2L+1)/3) for uniform [-1, 1] coefficients; the three applications add
     * sums of 2L+1 rounded products, deviation sqrt((2L+1) / 3) u |f_l| each */
    const double fl = sqrt((2.0 * L + 1.0) / 3.0);
    const double tol = LAMBDA * sqrt(3.0) * (rot_sigma(L) + fl * (DBL_EPSILON / 2)) * fl;
    CHECK(worst < tol);
    harness_note("max |R2(R1 f) - (R2 R1) f| %.1e (unit-range coefficients; tol %.1e, 6 deviations of the rounding "
                 "model)", worst, tol);
}

/* g(R w) = f(w) at random directions: the definition of the rotation. */
SHL_TEST(rotate_matches_rotated_directions)
{
    rng_t r = {23};
    double worst = 0.0, scale = 0.0;
    for (int it = 0; it < 10; ++it) {
        double rot[9], f[NC], g[NC];
        random_rotation(&r, rot);
        if (it == 0) /* a reflection (det -1) */
            for (int k = 0; k < 3; ++k) rot[k] = -rot[k];
        random_coeffs(&r, f, NC);
        CHECK(shl_sh_rotate(L, rot, f, g) == SHL_OK);
        for (int p = 0; p < 20; ++p) {
            double w[3], rw[3], vf, vg;
            rng_unit_vector(&r, w);
            mat_vec3(rot, w, rw);
            CHECK(shl_sh_eval(L, f, w, &vf) == SHL_OK);
            CHECK(shl_sh_eval(L, g, rw, &vg) == SHL_OK);
            worst = fmax(worst, fabs(vf - vg));
            scale = fmax(scale, fabs(vf));
        }
    }
    CHECK(worst < 4e-14 * scale);
    harness_note("max |g(Rw) - f(w)| / max|f| %.1e (lmax %d, incl. a reflection)", worst / scale, L);
}

SHL_TEST(rotate_about_z_closed_form)
{
    rng_t r = {24};
    const double ang = 0.7;
    const double rot[9] = {cos(ang), -sin(ang), 0, sin(ang), cos(ang), 0, 0, 0, 1};
    double f[NC], g[NC], worst = 0.0;
    random_coeffs(&r, f, NC);
    CHECK(shl_sh_rotate(L, rot, f, g) == SHL_OK);
    for (int l = 0; l <= L; ++l) {
        const int b = l * (l + 1);
        worst = fmax(worst, fabs(g[b] - f[b]));
        for (int m = 1; m <= l; ++m) { /* f(phi - ang): (cos, sin) pairs turn by m ang */
            const double c = cos(m * ang), s = sin(m * ang);
            worst = fmax(worst, fabs(g[b + m] - (c * f[b + m] - s * f[b - m])));
            worst = fmax(worst, fabs(g[b - m] - (s * f[b + m] + c * f[b - m])));
        }
    }
    CHECK(worst < 6e-15);
    harness_note("max |err| vs the z-rotation closed form %.1e", worst);
    /* identity, and -I (the antipodal map: band l gets (-1)^l) */
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, neg[9] = {-1, 0, 0, 0, -1, 0, 0, 0, -1};
    CHECK(shl_sh_rotate(L, id, f, g) == SHL_OK);
    for (int k = 0; k < NC; ++k) CHECK(g[k] == f[k]);
    CHECK(shl_sh_rotate(L, neg, f, g) == SHL_OK);
    for (int l = 0; l <= L; ++l)
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) CHECK(g[k] == ((l & 1) ? -f[k] : f[k]));
}

/* Eq. (15) against rotating the ZH placed on the z axis, and against the
 * quadrature over the rotated cap. */
SHL_TEST(rotate_zh_to_sh_and_caps)
{
    rng_t r = {25};
    double worst_rot = 0.0, worst_cap = 0.0;
    for (int it = 0; it < 8; ++it) {
        double rot[9], zh[L + 1], onz[NC] = {0}, a[NC], b[NC], want[NC];
        random_rotation(&r, rot);
        const double axis[3] = {rot[2], rot[5], rot[8]}; /* R e_z */
        const double half = rng_range(&r, 0.05, 3.0);
        CHECK(shl_zh_cap(L, half, zh) == SHL_OK);
        for (int l = 0; l <= L; ++l) onz[l * (l + 1)] = zh[l];
        CHECK(shl_zh_to_sh(L, zh, axis, a) == SHL_OK);
        CHECK(shl_sh_rotate(L, rot, onz, b) == SHL_OK);
        capref_cap(L, axis, 2.0 * sin(0.5 * half) * sin(0.5 * half), want);
        for (int k = 0; k < NC; ++k) {
            worst_rot = fmax(worst_rot, fabs(a[k] - b[k]));
            worst_cap = fmax(worst_cap, fabs(b[k] - want[k]));
        }
    }
    CHECK(worst_rot < 2e-15);
    CHECK(worst_cap < 3e-14);
    harness_note("Eq.15 vs rotation %.1e; rotated cap vs quadrature %.1e", worst_rot, worst_cap);
}

SHL_TEST(rotate_bad_input_and_alloc_failure)
{
    double f[NC], out[NC + 1];
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, skew[9] = {1, 1e-3, 0, 0, 1, 0, 0, 0, 1};
    const double nanr[9] = {1, 0, 0, 0, NAN, 0, 0, 0, 1}, axis[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
    double zh[L + 1];
    for (int k = 0; k < NC; ++k) f[k] = 1.0 / (k + 1);
    for (int l = 0; l <= L; ++l) zh[l] = 1.0;
    guard_fill(out, NC + 1);
    CHECK(shl_sh_rotate(3, NULL, f, out) == SHL_ENULL);
    CHECK(shl_sh_rotate(3, id, NULL, out) == SHL_ENULL);
    CHECK(shl_sh_rotate(3, id, f, NULL) == SHL_ENULL);
    CHECK(shl_sh_rotate(-1, id, f, out) == SHL_ELMAX);
    CHECK(shl_sh_rotate(L + 1, id, f, out) == SHL_ELMAX);
    CHECK(shl_sh_rotate(3, skew, f, out) == SHL_EDOMAIN);
    CHECK(shl_sh_rotate(3, nanr, f, out) == SHL_ENONFINITE);
    f[5] = INFINITY;
    CHECK(shl_sh_rotate(3, id, f, out) == SHL_ENONFINITE);
    f[5] = 0.5;
    CHECK(shl_zh_to_sh(3, zh, zero, out) == SHL_EDOMAIN);
    CHECK(shl_zh_to_sh(3, NULL, axis, out) == SHL_ENULL);
    CHECK(shl_zh_to_sh(31, zh, axis, out) == SHL_ELMAX);
    double v = GUARD_VALUE;
    CHECK(shl_sh_eval(3, f, zero, &v) == SHL_EDOMAIN && v == GUARD_VALUE);
    CHECK(shl_sh_eval(3, f, axis, NULL) == SHL_ENULL);
    CHECK(guard_intact(out, NC + 1));
    /* every allocation failing in turn: SHL_ENOMEM, output untouched (leaks: ASan) */
    int failures = 0;
    for (long n = 0;; ++n) {
        shl__alloc_fail_after = n;
        const int st = shl_sh_rotate(L, id, f, out);
        shl__alloc_fail_after = -1;
        if (st == SHL_OK) break;
        CHECK(st == SHL_ENOMEM);
        CHECK(guard_intact(out, NC + 1));
        ++failures;
    }
    CHECK(failures == 1);
    CHECK(out[NC] == GUARD_VALUE && out[NC - 1] == f[NC - 1]);
}
