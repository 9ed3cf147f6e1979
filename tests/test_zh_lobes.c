/* ZH lobe table (zh_tables.c): mirror structure, reconstruction of Y_lm from
 * zonal lobes through the even/odd weight blocks, band condition numbers. */
#include "harness.h"
#include "internal.h"
#include "testutil.h"
#include "zh_tables.h"
#include "sh_basis.h"
#include <math.h>

#define LMAX SHL_LMAX_MAX
#define NSH SHL_NCOEFFS(LMAX)

SHL_TEST(zh_table_structure)
{
    const double(*d)[3] = shl__zh_dir;
    CHECK(d[0][1] == 0.0);
    for (int i = 0; i < SHL__ZH_NDIR; ++i)
        CHECK_NEAR(d[i][0] * d[i][0] + d[i][1] * d[i][1] + d[i][2] * d[i][2], 1.0, 1e-15);
    for (int k = 1; k <= LMAX; ++k) {
        CHECK(d[2 * k][0] == d[2 * k - 1][0]);
        CHECK(d[2 * k][1] == -d[2 * k - 1][1]);
        CHECK(d[2 * k][2] == d[2 * k - 1][2]);
        CHECK(d[2 * k - 1][1] != 0.0);
    }
    int even = 0, odd = 0;
    for (int l = 0; l <= LMAX; ++l) {
        CHECK(SHL__ZH_EVEN_OFS(l) == even);
        CHECK(SHL__ZH_ODD_OFS(l) == odd);
        even += (l + 1) * (l + 1);
        odd += l * l;
    }
    CHECK(SHL__ZH_EVEN_SIZE == even);
    CHECK(SHL__ZH_ODD_SIZE == odd);
    CHECK(all_finite(shl__zh_even_w, SHL__ZH_EVEN_SIZE));
    CHECK(all_finite(shl__zh_odd_w, SHL__ZH_ODD_SIZE));
}

/* A unit "delta light" at w has ZH integrals z_d = Y_l0(d . w) = K_l P_l(d . w)
 * and SH coefficients Y_lm(w); the weights must map the former to the latter. */
SHL_TEST(zh_reconstruction_identity)
{
    rng_t r = {77};
    double worst = 0.0, worst_rel = 0.0;
    int worst_l = 0;
    for (int it = 0; it < 200; ++it) {
        double w[3], y[NSH], z[SHL__ZH_NDIR][LMAX + 1];
        rng_unit_vector(&r, w);
        shl__sh_eval(LMAX, w[0], w[1], w[2], y);
        for (int d = 0; d < SHL__ZH_NDIR; ++d) {
            const double t = shl__zh_dir[d][0] * w[0] + shl__zh_dir[d][1] * w[1] + shl__zh_dir[d][2] * w[2];
            double p[LMAX + 1] = {1.0, t};
            for (int l = 2; l <= LMAX; ++l) p[l] = ((2.0 * l - 1.0) * t * p[l - 1] - (l - 1.0) * p[l - 2]) / l;
            for (int l = 0; l <= LMAX; ++l) z[d][l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * p[l];
        }
        for (int l = 0; l <= LMAX; ++l) {
            const double *we = shl__zh_even_w + SHL__ZH_EVEN_OFS(l);
            const double *wo = shl__zh_odd_w + SHL__ZH_ODD_OFS(l);
            double err = 0.0;
            for (int m = 0; m <= l; ++m) {
                double acc = we[m * (l + 1)] * z[0][l];
                for (int k = 1; k <= l; ++k) acc += we[m * (l + 1) + k] * (z[2 * k - 1][l] + z[2 * k][l]);
                err = fmax(err, fabs(acc - y[l * (l + 1) + m]));
            }
            for (int m = 1; m <= l; ++m) {
                double acc = 0.0;
                for (int k = 1; k <= l; ++k) acc += wo[(m - 1) * l + k - 1] * (z[2 * k - 1][l] - z[2 * k][l]);
                err = fmax(err, fabs(acc - y[l * (l + 1) - m]));
            }
            /* Y_lm itself is rounded to ~6e-15 near l = 30 (in the weights and
             * here), amplified by cond_l: measured <= 1.7e-14 * cond_l. */
            const double tol = 1e-13 * shl__zh_cond[l];
            if (!(err <= tol)) harness_fail(__FILE__, __LINE__, "l = %d: |error| %.3g > tol %.3g", l, err, tol);
            if (err > worst) {
                worst = err;
                worst_l = l;
            }
            worst_rel = fmax(worst_rel, err / shl__zh_cond[l]);
        }
    }
    harness_note("max |error| %.3g (l = %d), max |error|/cond %.3g", worst, worst_l, worst_rel);
}

/* Extreme eigenvalues of the symmetric n x n row-major g (cyclic Jacobi, destroyed). */
static void sym_eig_range(int n, double *g, double *lo, double *hi)
{
    for (int sweep = 0, rotated = 1; rotated && sweep < 100; ++sweep) {
        rotated = 0;
        for (int p = 0; p < n - 1; ++p)
            for (int q = p + 1; q < n; ++q) {
                const double gpq = g[p * n + q];
                if (fabs(gpq) <= 1e-15 * sqrt(fabs(g[p * n + p] * g[q * n + q]))) continue;
                rotated = 1;
                const double theta = (g[q * n + q] - g[p * n + p]) / (2.0 * gpq);
                const double t = copysign(1.0, theta) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < n; ++k) {
                    const double a = g[k * n + p], b = g[k * n + q];
                    g[k * n + p] = c * a - s * b;
                    g[k * n + q] = s * a + c * b;
                }
                for (int k = 0; k < n; ++k) {
                    const double a = g[p * n + k], b = g[q * n + k];
                    g[p * n + k] = c * a - s * b;
                    g[q * n + k] = s * a + c * b;
                }
            }
    }
    *lo = HUGE_VAL;
    *hi = 0.0;
    for (int i = 0; i < n; ++i) {
        *lo = fmin(*lo, g[i * n + i]);
        *hi = fmax(*hi, g[i * n + i]);
    }
}

/* Stored cond(A_l) is <= 100 and matches sqrt(cond(A_l^T A_l)) recomputed
 * from the stored directions, without using the mirror structure. */
SHL_TEST(zh_condition_numbers)
{
    static double a[SHL__ZH_NDIR][2 * LMAX + 1], g[SHL__ZH_NDIR * SHL__ZH_NDIR];
    double worst = 0.0, y[NSH];
    for (int l = 0; l <= LMAX; ++l) {
        const int n = 2 * l + 1;
        for (int d = 0; d < n; ++d) {
            shl__sh_eval(l, shl__zh_dir[d][0], shl__zh_dir[d][1], shl__zh_dir[d][2], y);
            for (int m = 0; m < n; ++m) a[d][m] = y[l * l + m];
        }
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                double s = 0.0;
                for (int d = 0; d < n; ++d) s += a[d][i] * a[d][j];
                g[i * n + j] = s;
            }
        double lo, hi;
        sym_eig_range(n, g, &lo, &hi);
        const double c = sqrt(hi / lo);
        CHECK_NEAR(shl__zh_cond[l], c, 1e-9 * c);
        CHECK(shl__zh_cond[l] <= 100.0);
        worst = fmax(worst, shl__zh_cond[l]);
    }
    harness_note("max cond %.3f", worst);
}
