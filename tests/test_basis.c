/* SH basis: closed forms, sum rule, addition theorem, orthonormality by
 * quadrature, prefix consistency, bad input. */
#include "harness.h"
#include "internal.h"
#include "testutil.h"
#include <math.h>

SHL_TEST(basis_closed_forms_l2)
{
    rng_t r = {1};
    const double c1 = sqrt(3.0 / (4.0 * M_PI)), c2 = 0.5 * sqrt(15.0 / M_PI);
    for (int it = 0; it < 100; ++it) {
        double d[3], y[9];
        rng_unit_vector(&r, d);
        const double scale = rng_range(&r, 0.1, 10.0), ds[3] = {d[0] * scale, d[1] * scale, d[2] * scale};
        CHECK(shl_eval_basis(2, ds, y) == SHL_OK);
        const double x = d[0], yy = d[1], z = d[2];
        const double want[9] = {0.5 / sqrt(M_PI), -c1 * yy, c1 * z, -c1 * x,
                                c2 * x * yy, -c2 * yy * z, 0.25 * sqrt(5.0 / M_PI) * (3 * z * z - 1),
                                -c2 * x * z, 0.5 * c2 * (x * x - yy * yy)};
        for (int k = 0; k < 9; ++k) CHECK_NEAR(y[k], want[k], 2e-15); /* a few ulps of the recurrence */
    }
}

SHL_TEST(basis_sum_rule_and_addition_theorem)
{
    rng_t r = {2};
    double worst = 0.0;
    for (int it = 0; it < 200; ++it) {
        double a[3], b[3], ya[SHL_NCOEFFS(SHL_LMAX_MAX)], yb[SHL_NCOEFFS(SHL_LMAX_MAX)];
        rng_unit_vector(&r, a);
        rng_unit_vector(&r, b);
        CHECK(shl_eval_basis(SHL_LMAX_MAX, a, ya) == SHL_OK);
        CHECK(shl_eval_basis(SHL_LMAX_MAX, b, yb) == SHL_OK);
        const double t = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for (int l = 0; l <= SHL_LMAX_MAX; ++l) {
            double sq = 0.0, cross = 0.0;
            for (int m = -l; m <= l; ++m) {
                sq += ya[l * (l + 1) + m] * ya[l * (l + 1) + m];
                cross += ya[l * (l + 1) + m] * yb[l * (l + 1) + m];
            }
            const double k = (2.0 * l + 1.0) / (4.0 * M_PI);
            /* sum_m Y_lm^2 = (2l+1)/(4 pi); sum_m Y_lm(a) Y_lm(b) = (2l+1)/(4 pi) P_l(a.b) */
            CHECK_NEAR(sq / k, 1.0, 1e-13);
            CHECK_NEAR(cross / k, legendre_p(l, t), 1e-12);
            worst = fmax(worst, fabs(cross / k - legendre_p(l, t)));
        }
    }
    harness_note("max |addition theorem residual| %.2e (l<=%d)", worst, SHL_LMAX_MAX);
}

/* Gauss-Legendre nodes on [-1,1] by Newton iteration on P_n. */
static void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; ++i) {
        double t = cos(M_PI * (i + 0.75) / (n + 0.5));
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            const double dp = n * (t * p1 - p0) / (t * t - 1.0);
            const double dt = p1 / dp;
            t -= dt;
            if (fabs(dt) < 1e-16) {
                x[i] = t;
                w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
                break;
            }
        }
    }
}

SHL_TEST(basis_orthonormal_by_quadrature)
{
    enum { L = SHL_LMAX_MAX, NC = SHL_NCOEFFS(L), NZ = L + 2, NPHI = 2 * L + 2 };
    static double gram[NC][NC];
    double zs[NZ], ws[NZ], y[NC];
    gauss_legendre(NZ, zs, ws); /* exact for the degree-2L polynomials in z */
    memset(gram, 0, sizeof gram);
    for (int i = 0; i < NZ; ++i)
        for (int j = 0; j < NPHI; ++j) {
            const double phi = 2.0 * M_PI * j / NPHI, s = sqrt(1.0 - zs[i] * zs[i]);
            const double d[3] = {s * cos(phi), s * sin(phi), zs[i]};
            shl_eval_basis(L, d, y);
            const double w = ws[i] * 2.0 * M_PI / NPHI;
            for (int a = 0; a < NC; ++a)
                for (int b = 0; b <= a; ++b) gram[a][b] += w * y[a] * y[b];
        }
    double worst = 0.0;
    for (int a = 0; a < NC; ++a)
        for (int b = 0; b <= a; ++b) worst = fmax(worst, fabs(gram[a][b] - (a == b)));
    CHECK(worst < 1e-12);
    harness_note("max |Gram - I| %.2e over l<=%d", worst, L);
}

SHL_TEST(basis_prefix_consistency_and_float)
{
    rng_t r = {3};
    for (int it = 0; it < 50; ++it) {
        double d[3], big[SHL_NCOEFFS(SHL_LMAX_MAX)], small[36];
        float df[3], yf[SHL_NCOEFFS(14)];
        rng_unit_vector(&r, d);
        shl_eval_basis(SHL_LMAX_MAX, d, big);
        shl_eval_basis(5, d, small);
        CHECK(memcmp(big, small, sizeof small) == 0); /* bit for bit */
        for (int k = 0; k < 3; ++k) df[k] = (float)d[k];
        CHECK(shl_eval_basis_f(14, df, yf) == SHL_OK);
        for (int k = 0; k < SHL_NCOEFFS(14); ++k) CHECK_NEAR(yf[k], big[k], 2e-6);
    }
}

SHL_TEST(basis_bad_input)
{
    double y[SHL_NCOEFFS(SHL_LMAX_MAX) + 1];
    const double ok[3] = {0, 0, 1}, zero[3] = {0, 0, 0}, nan[3] = {0, NAN, 1}, inf[3] = {INFINITY, 0, 0};
    guard_fill(y, SHL_NCOEFFS(SHL_LMAX_MAX) + 1);
    CHECK(shl_eval_basis(2, NULL, y) == SHL_ENULL);
    CHECK(shl_eval_basis(2, ok, NULL) == SHL_ENULL);
    CHECK(shl_eval_basis(-1, ok, y) == SHL_ELMAX);
    CHECK(shl_eval_basis(SHL_LMAX_MAX + 1, ok, y) == SHL_ELMAX);
    CHECK(shl_eval_basis(2, zero, y) == SHL_EDOMAIN);
    CHECK(shl_eval_basis(2, nan, y) == SHL_ENONFINITE);
    CHECK(shl_eval_basis(2, inf, y) == SHL_ENONFINITE);
    CHECK(guard_intact(y, SHL_NCOEFFS(SHL_LMAX_MAX) + 1));
    /* lmax = SHL_LMAX_MAX writes exactly SHL_NCOEFFS entries; huge and tiny directions work */
    const double huge[3] = {1e300, -1e300, 1e300}, tiny[3] = {1e-310, 0, 0};
    CHECK(shl_eval_basis(SHL_LMAX_MAX, huge, y) == SHL_OK);
    CHECK(y[SHL_NCOEFFS(SHL_LMAX_MAX)] == GUARD_VALUE);
    CHECK(all_finite(y, SHL_NCOEFFS(SHL_LMAX_MAX)));
    CHECK(shl_eval_basis(1, tiny, y) == SHL_OK);
    CHECK_NEAR(y[3], -sqrt(3.0 / (4.0 * M_PI)), 1e-15);
    CHECK(strcmp(shl_strerror(SHL_ENULL), shl_strerror(12345)) != 0);
}

SHL_TEST(basis_ctx_create_bad_input_and_alloc_failure)
{
    shl_ctx *sentinel = (shl_ctx *)&sentinel, *ctx = sentinel;
    CHECK(shl_ctx_create(4, NULL) == SHL_ENULL);
    CHECK(shl_ctx_create(-1, &ctx) == SHL_ELMAX && ctx == NULL); /* *out = NULL on failure */
    ctx = sentinel;
    CHECK(shl_ctx_create(SHL_LMAX_MAX + 1, &ctx) == SHL_ELMAX && ctx == NULL);
    ctx = sentinel;
    shl__alloc_fail_after = 0;
    const int st = shl_ctx_create(4, &ctx);
    shl__alloc_fail_after = -1;
    CHECK(st == SHL_ENOMEM && ctx == NULL);
    CHECK(shl_ctx_create(SHL_LMAX_MAX, &ctx) == SHL_OK && ctx != NULL);
    CHECK(shl_ctx_lmax(ctx) == SHL_LMAX_MAX && shl_ctx_lmax(NULL) == SHL_ENULL);
    shl_ctx_destroy(ctx);
    shl_ctx_destroy(NULL);
}
