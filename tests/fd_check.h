/* Checking an analytic gradient against central differences, with a tolerance
 * derived from the differences themselves instead of calibrated by hand.
 *
 * Along each axis, from the samples f(x +- j h), j = 1..4, the central
 * differences of orders 6 and 8 are formed (weights w6 = {45, -9, 1} / 60 h,
 * w8 = {672, -168, 32, -3} / 840 h).  Their truncation errors are
 * -h^6 f^(7) / 140 and h^8 f^(9) / 630; with the step below a fraction of the
 * length over which f changes (h kappa << 1), the 8th-order error is a small
 * fraction rho ~ (h kappa)^2 of the 6th-order one, so for rho <= 1/2
 *   |D8 - f'| <= rho / (1 - rho) |D6 - D8| <= |D6 - D8|          (truncation)
 * plus the rounding of the samples: an evaluation error of at most E reaches
 * D8 as at most E sum|w8| / h, sum|w8| = 2 (672 + 168 + 32 + 3) / 840 = 2.083,
 * and D6 likewise (sum|w6| = 1.833).  An analytic gradient g with error at most
 * E_g therefore satisfies, at every component,
 *   |g - D8| <= max_k |D6 - D8| + (2.083 + 1.833) E / h + E_g.
 * The first term is a maximum over all components of one point: a component
 * where D6 and D8 happen to agree still gets the point's truncation estimate. */
#ifndef SHL_TEST_FD_CHECK_H
#define SHL_TEST_FD_CHECK_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* out[0..n) = f(x), n <= FD_MAXN. */
typedef void (*fd_func)(void *arg, const double x[3], double *out);
enum { FD_MAXN = 9 * 961 };

typedef struct {
    double err;   /* max_k |g_k - D8_k| */
    double trunc; /* max_k |D6_k - D8_k| */
    double fbig;  /* max |f| over the samples */
    double h;
} fd_result;

/* Compares g[a*n + k] with the 8th-order differences of f at x, step h (x +- j h
 * should be exact: h a power of two no larger than the coordinates' ulp scale allows). */
static inline fd_result fd_compare(fd_func f, void *arg, const double x[3], double h, int n, const double *g)
{
    static const double w6[3] = {45.0, -9.0, 1.0}, w8[4] = {672.0, -168.0, 32.0, -3.0};
    double *fp = malloc(sizeof(double) * 2 * (size_t)n), *fm = fp + n;
    double *d6 = calloc((size_t)n, sizeof(double)), *d8 = calloc((size_t)n, sizeof(double));
    fd_result r = {0.0, 0.0, 0.0, h};
    for (int a = 0; a < 3; ++a) {
        memset(d6, 0, sizeof(double) * (size_t)n);
        memset(d8, 0, sizeof(double) * (size_t)n);
        for (int s = 1; s <= 4; ++s) {
            double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
            xp[a] += s * h;
            xm[a] -= s * h;
            f(arg, xp, fp);
            f(arg, xm, fm);
            for (int k = 0; k < n; ++k) {
                const double dif = fp[k] - fm[k];
                r.fbig = fmax(r.fbig, fmax(fabs(fp[k]), fabs(fm[k])));
                d8[k] += w8[s - 1] * dif;
                if (s <= 3) d6[k] += w6[s - 1] * dif;
            }
        }
        for (int k = 0; k < n; ++k) {
            const double e8 = d8[k] / (840.0 * h), e6 = d6[k] / (60.0 * h);
            r.trunc = fmax(r.trunc, fabs(e6 - e8));
            r.err = fmax(r.err, fabs(g[a * n + k] - e8));
        }
    }
    free(fp);
    free(d6);
    free(d8);
    return r;
}

/* The bound of the header comment for evaluation error E and gradient error E_g. */
static inline double fd_bound(const fd_result *r, double eval_err, double grad_err)
{
    return r->trunc + (2.083 + 1.833) * eval_err / r->h + grad_err;
}

#endif
