/* Generated real-SH recurrence tables (src/sh_tables.c, tools/gen_sh_tables.c) against
 * their defining formulas in long double, and the table-driven basis kernels
 * (both code paths: register column pairs up to band 16, band rows above) against a
 * long double evaluation at every lmax, in double, float and weighted form. */
#include "harness.h"
#include "ref_quad.h"
#include "sh_basis.h"
#include "testutil.h"
#include <float.h>
#include <math.h>

#define L SHL_LMAX_MAX
#define NC SHL_NCOEFFS(L)

static const long double PI_L = 3.141592653589793238462643383279502884L;

static double rel(long double got, long double want)
{
    return want == 0.0L ? (double)fabsl(got) : (double)fabsl(got / want - 1.0L);
}

/* Error analysis of the generator (double): a, b, dz, lega, legb, capk and k15 are one
 * rounded quotient (pi: one more rounding), a square root or product of it and one
 * more rounding: <= 1.25 ulp <= 1.25 eps relative; the diagonal N_m^m is a product of
 * m such factors and sqrt(1/(4 pi)), each multiplication rounded: <= 1.25 (m+1) + 0.5 m
 * eps.  Float tables: the double value rounded to float (0.5 eps_f, plus the double's
 * error), the float diagonal a float product: <= (m+1) eps_f. */
SHL_TEST(sh_tables_vs_long_double)
{
    double worst = 0.0, worst_diag = 0.0, worst_f = 0.0, worst_diag_f = 0.0;
    long double diag = sqrtl(0.25L / PI_L);
    for (int m = 0; m <= L; ++m) {
        if (m > 0) diag *= -sqrtl((2.0L * m + 1.0L) / (2.0L * m));
        const double e = rel(shl__sh_diag_d[m], diag) / (DBL_EPSILON * (1.25 * (m + 1) + 0.5 * m));
        const double ef = rel(shl__sh_diag_f[m], diag) / (FLT_EPSILON * (m + 1));
        worst_diag = fmax(worst_diag, e), worst_diag_f = fmax(worst_diag_f, ef);
    }
    for (int l = 0; l <= L; ++l) {
        const long double one[6] = {sqrtl(4.0L * PI_L / (2.0L * l + 1.0L)), (2.0L * l + 1.0L) / (l + 1.0L),
                                    (long double)l / (l + 1.0L), l ? 2.0L * PI_L / (l * (l + 1.0L)) : 0.0L, 1.0L};
        const double got[5] = {shl__sh_k15_d[l], shl__sh_lega_d[l], shl__sh_legb_d[l], shl__sh_capk_d[l], shl__sh_one_d[l]};
        const float gotf[5] = {shl__sh_k15_f[l], shl__sh_lega_f[l], shl__sh_legb_f[l], shl__sh_capk_f[l], shl__sh_one_f[l]};
        for (int k = 0; k < 5; ++k) {
            worst = fmax(worst, rel(got[k], one[k]) / (1.25 * DBL_EPSILON));
            worst_f = fmax(worst_f, rel(gotf[k], one[k]) / FLT_EPSILON);
        }
        for (int m = 0; m <= l; ++m) {
            const int t = l * (l + 1) / 2 + m;
            const long double l2 = (long double)l * l, m2 = (long double)m * m, k2 = (l - 1.0L) * (l - 1.0L);
            const long double a = m == l ? 0.0L : m == l - 1 ? sqrtl(2.0L * m + 3.0L) : sqrtl((4 * l2 - 1) / (l2 - m2));
            const long double b = m < l - 1 ? sqrtl((k2 - m2) / (4 * k2 - 1)) : 0.0L;
            const long double dz = -sqrtl((long double)(l - m) * (l + m + 1.0L));
            const long double want[3] = {a, b, dz};
            const double g[3] = {shl__sh_a_d[t], shl__sh_b_d[t], shl__sh_dz_d[t]};
            const float gf[3] = {shl__sh_a_f[t], shl__sh_b_f[t], shl__sh_dz_f[t]};
            for (int k = 0; k < 3; ++k) {
                worst = fmax(worst, rel(g[k], want[k]) / (1.25 * DBL_EPSILON));
                worst_f = fmax(worst_f, rel(gf[k], want[k]) / FLT_EPSILON);
            }
        }
    }
    harness_note("worst error / bound: double factors %.2f, diagonal %.2f; float factors %.2f, diagonal %.2f", worst,
                 worst_diag, worst_f, worst_diag_f);
    CHECK(worst <= 1.0 && worst_diag <= 1.0 && worst_f <= 1.0 && worst_diag_f <= 1.0);
}

/* Y_lm(d) for l <= lmax in long double: the same normalized recurrences, every factor
 * a long double square root. */
static void ld_basis(int lmax, const double d[3], long double *y)
{
    const long double x = d[0], yy = d[1], z = d[2];
    long double nmm = sqrtl(0.25L / PI_L), cm = 1.0L, sm = 0.0L;
    for (int m = 0; m <= lmax; ++m) {
        if (m > 0) {
            nmm *= -sqrtl((2.0L * m + 1.0L) / (2.0L * m));
            const long double c = cm * x - sm * yy;
            sm = cm * yy + sm * x;
            cm = c;
        }
        long double p2 = 0.0L, p1 = nmm;
        for (int l = m; l <= lmax; ++l) {
            long double p = nmm;
            if (l == m + 1) {
                p = sqrtl(2.0L * m + 3.0L) * z * nmm;
            } else if (l > m + 1) {
                const long double l2 = (long double)l * l, m2 = (long double)m * m, k2 = (l - 1.0L) * (l - 1.0L);
                p = sqrtl((4 * l2 - 1) / (l2 - m2)) * (z * p1 - sqrtl((k2 - m2) / (4 * k2 - 1)) * p2);
            }
            if (l > m) p2 = p1, p1 = p;
            y[l * (l + 1) + m] = m ? sqrtl(2.0L) * p * cm : p;
            if (m) y[l * (l + 1) - m] = sqrtl(2.0L) * p * sm;
        }
    }
}

/* Error analysis: a step of the normalized three-term recurrence commits <= 3 roundings
 * and inherits the table factors' <= 1.25 ulp each; the forward recurrence for the
 * normalized associated Legendre functions is stable (earlier errors are not
 * amplified beyond the scale of the values), so column m at band l carries <= about
 * 5 (l - m) eps of the band's scale K_l = sqrt((2l+1)/(4 pi)) (>= every |Y_lm|, by the
 * addition theorem); (x + iy)^m adds <= 2m eps and the output products 2 eps.  Bound:
 * 6 (l+1) eps K_l (eps of the arithmetic: double or float), times |w_l| when weighted
 * (one more rounding, inside the bound). */
SHL_TEST(sh_basis_every_lmax_vs_long_double)
{
    rng_t r = {16};
    static long double yl[NC];
    static double y[NC], yr[NC], g[3 * NC], w[L + 1];
    static float yf[NC], wf[L + 1];
    double worst = 0.0, worst_f = 0.0, worst_w = 0.0, worst_ref = 0.0;
    for (int l = 0; l <= L; ++l) {
        w[l] = 1.0 / (1.0 + l) - 0.3; /* weights of both signs, none zero */
        wf[l] = (float)w[l];
    }
    for (int lmax = 0; lmax <= L; ++lmax)
        for (int it = 0; it < 40; ++it) {
            double d[3];
            rng_unit_vector(&r, d);
            if (it < 2) d[0] = d[1] = 0.0, d[2] = it ? -1.0 : 1.0; /* the poles */
            const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            ld_basis(lmax, d, yl);
            shl__sh_eval(lmax, d[0], d[1], d[2], y);
            ref_sh_eval_grad(lmax, d, yr, g);
            for (int l = 0; l <= lmax; ++l) {
                const double tol = 6.0 * (l + 1) * DBL_EPSILON * sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
                for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                    worst = fmax(worst, (double)fabsl(y[k] - yl[k]) / tol);
                    worst_ref = fmax(worst_ref, fabs(y[k] - yr[k]));
                }
            }
            shl__sh_eval_w_d(lmax, d, w, y);
            for (int l = 0; l <= lmax; ++l) {
                const double tol = 6.0 * (l + 1) * DBL_EPSILON * sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * fabs(w[l]);
                for (int k = l * l; k < (l + 1) * (l + 1); ++k)
                    worst_w = fmax(worst_w, (double)fabsl(y[k] - (long double)w[l] * yl[k]) / tol);
            }
            /* float: the reference is taken at the float-rounded direction (the same
             * polynomial extension), so only the float arithmetic is measured */
            const double dd[3] = {df[0], df[1], df[2]};
            ld_basis(lmax, dd, yl);
            shl__sh_eval_w_f(lmax, df, wf, yf);
            for (int l = 0; l <= lmax; ++l) {
                const double tol = 6.0 * (l + 1) * FLT_EPSILON * sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * fabs(w[l]);
                for (int k = l * l; k < (l + 1) * (l + 1); ++k)
                    worst_f = fmax(worst_f, (double)fabsl(yf[k] - (long double)wf[l] * yl[k]) / tol);
            }
        }
    harness_note("worst error / bound (lmax 0..%d): double %.3f, weighted %.3f, float weighted %.3f", L, worst,
                 worst_w, worst_f);
    /* the double kernel performs the former per-call recurrence's operations in the
     * same order (only its factors are now read from tables), and tests/ref_quad.c
     * keeps that recurrence: the values agree exactly */
    harness_note("max |shl__sh_eval - ref_sh_eval_grad values| %.1e", worst_ref);
    CHECK(worst <= 1.0 && worst_w <= 1.0 && worst_f <= 1.0);
    CHECK(worst_ref == 0.0);
}

/* Y_lm(d) and the Cartesian gradient G of its polynomial extension (see sh_basis_impl.h)
 * in long double, by an independent route: dN_l^m/dz from the l-recurrence
 * differentiated, dN_l = a (N_{l-1} + z dN_{l-1} - b dN_{l-2}) (dN_m^m = 0), not from
 * column m+1; every factor a long double square root. */
static void ld_basis_grad(int lmax, const long double d[3], long double *y, long double *gc)
{
    const int nc = (lmax + 1) * (lmax + 1);
    const long double x = d[0], yy = d[1], z = d[2], r2 = sqrtl(2.0L);
    long double nmm = sqrtl(0.25L / PI_L), cm = 1.0L, sm = 0.0L, cp = 0.0L, sp = 0.0L; /* C_m, S_m, C_{m-1}, S_{m-1} */
    for (int m = 0; m <= lmax; ++m) {
        if (m > 0) {
            nmm *= -sqrtl((2.0L * m + 1.0L) / (2.0L * m));
            cp = cm, sp = sm;
            const long double c = cm * x - sm * yy;
            sm = cm * yy + sm * x;
            cm = c;
        }
        long double p1 = 0.0L, p2 = 0.0L, d1 = 0.0L, d2 = 0.0L;
        for (int l = m; l <= lmax; ++l) {
            long double p = nmm, dp = 0.0L;
            if (l == m + 1) {
                p = sqrtl(2.0L * m + 3.0L) * z * nmm;
                dp = sqrtl(2.0L * m + 3.0L) * nmm;
            } else if (l > m + 1) {
                const long double l2 = (long double)l * l, m2 = (long double)m * m, k2 = (l - 1.0L) * (l - 1.0L);
                const long double a = sqrtl((4 * l2 - 1) / (l2 - m2)), b = sqrtl((k2 - m2) / (4 * k2 - 1));
                p = a * (z * p1 - b * p2);
                dp = a * (p1 + z * d1 - b * d2);
            }
            p2 = p1, p1 = p, d2 = d1, d1 = dp;
            const int k = l * (l + 1);
            if (m == 0) {
                y[k] = p;
                gc[k] = 0.0L, gc[nc + k] = 0.0L, gc[2 * nc + k] = dp;
                continue;
            }
            const long double pm = r2 * m * p;
            y[k + m] = r2 * p * cm, y[k - m] = r2 * p * sm;
            gc[k + m] = pm * cp, gc[nc + k + m] = -pm * sp, gc[2 * nc + k + m] = r2 * dp * cm;
            gc[k - m] = pm * sp, gc[nc + k - m] = pm * cp, gc[2 * nc + k - m] = r2 * dp * sm;
        }
    }
}

/* shl__sh_eval_wgrad (double and float) against al G + u (be Y - al u.G) formed from
 * ld_basis_grad in long double, with u.G taken as the dot product (the kernel uses the
 * identity u.G = (m N + z dN/dz) C_m instead), for random weights of both signs.
 * Error analysis: as above, column m at band l carries <= 5 (l - m) eps of the band's
 * scale K_l = sqrt((2l+1)/(4 pi)); dN/dz = dz N_l^{m+1} with |dz| <= l + 1 scales that
 * by l + 1, and the derivative of a degree-l polynomial is at most l^2 times its maximum
 * (Markov), so every Cartesian term (m N C_{m-1}, dN C_m, their sum with z) is bounded by
 * (l+1)^2 K_l and carries <= 6 (l+1)^3 eps K_l (4 more roundings in p, r, h and the
 * output sums, inside the factor 6).  Bound per band: 6 (l+1) eps K_l ((l+1)^2 |al| +
 * |be|) + 2 eps |w| K_l (eps of the arithmetic).  Float: the reference at the
 * float-rounded direction (the same polynomial extension). */
SHL_TEST(sh_wgrad_vs_long_double)
{
    rng_t r = {17};
    static long double yl[NC], gl[3 * NC];
    static double y[NC], g[3 * NC], w[L + 1], al[L + 1], be[L + 1];
    static float yf[NC], gf[3 * NC], wf[L + 1], alf[L + 1], bef[L + 1];
    double worst = 0.0, worst_f = 0.0;
    for (int lmax = 0; lmax <= L; ++lmax)
        for (int it = 0; it < 12; ++it) {
            double d[3];
            rng_unit_vector(&r, d);
            if (it < 2) d[0] = d[1] = 0.0, d[2] = it ? -1.0 : 1.0; /* the poles */
            for (int l = 0; l <= lmax; ++l) {
                w[l] = 2.0 * rng_uniform(&r) - 1.0, al[l] = 2.0 * rng_uniform(&r) - 1.0;
                be[l] = 2.0 * rng_uniform(&r) - 1.0;
                wf[l] = (float)w[l], alf[l] = (float)al[l], bef[l] = (float)be[l];
            }
            const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            for (int pass = 0; pass < 2; ++pass) {
                const int nc = SHL_NCOEFFS(lmax);
                const long double u[3] = {pass ? df[0] : d[0], pass ? df[1] : d[1], pass ? df[2] : d[2]};
                ld_basis_grad(lmax, u, yl, gl);
                if (pass)
                    shl__sh_eval_wgrad_f(lmax, df, wf, alf, bef, yf, gf, nc);
                else
                    shl__sh_eval_wgrad_d(lmax, d, w, al, be, y, g, nc);
                const double eps = pass ? FLT_EPSILON : DBL_EPSILON;
                for (int l = 0; l <= lmax; ++l) {
                    const long double wl = pass ? wf[l] : w[l], a = pass ? alf[l] : al[l], b = pass ? bef[l] : be[l];
                    const double kl = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)), l1 = l + 1.0;
                    const double tol_y = 6.0 * l1 * eps * kl * fabs((double)wl);
                    const double tol_g = 6.0 * l1 * eps * kl * (l1 * l1 * fabs((double)a) + fabs((double)b)) +
                                         2.0 * eps * kl * fabs((double)wl);
                    for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                        const long double ug = u[0] * gl[k] + u[1] * gl[nc + k] + u[2] * gl[2 * nc + k];
                        const double gy = pass ? yf[k] : y[k];
                        double e = (double)fabsl(gy - wl * yl[k]) / tol_y;
                        for (int c = 0; c < 3; ++c) {
                            const long double want = a * gl[c * nc + k] + u[c] * (b * yl[k] - a * ug);
                            const double got = pass ? gf[c * nc + k] : g[c * nc + k];
                            e = fmax(e, (double)fabsl(got - want) / tol_g);
                        }
                        if (pass)
                            worst_f = fmax(worst_f, e);
                        else
                            worst = fmax(worst, e);
                    }
                }
            }
        }
    harness_note("worst error / bound (lmax 0..%d, values and gradient): double %.3f, float %.3f", L, worst, worst_f);
    CHECK(worst <= 1.0 && worst_f <= 1.0);
}
