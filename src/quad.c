/* Gauss-Legendre quadrature on panels, used to project lobes (GGX kernel, BRDF
 * tables) whose width can be far below the resolution of any fixed rule. */
#include "quad.h"

void shl__gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double t = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) { /* Newton on P_n */
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            const double dt = p1 / dp;
            t -= dt;
            if (fabs(dt) <= 1e-15) break;
        }
        x[i] = t;
        x[n - 1 - i] = -t;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
}

void shl__gl_panel(int n, const double *glx, const double *glw, double a, double b, double *x,
                   double *w)
{
    for (int i = 0; i < n; ++i) {
        x[i] = a + 0.5 * (b - a) * (glx[i] + 1.0);
        w[i] = 0.5 * (b - a) * glw[i];
    }
}

int shl__graded_breaks(double lo, double hi, int nf, const double *pos, const double *w_below,
                       const double *w_above, double *brk)
{
    int n = 0;
    double x = lo;
    brk[0] = lo;
    while (x < hi && n < SHL__MAX_PANELS - 1) {
        double step = M_PI / 8.0, stop = hi;
        for (int f = 0; f < nf; ++f) {
            const double d = pos[f] - x;
            if (d > 0.0) { /* approaching: halve the distance, down to w/4 */
                stop = fmin(stop, pos[f]);
                step = fmin(step, fmax(0.25 * w_below[f], 0.5 * d));
            } else { /* leaving: widths double from w/4 */
                step = fmin(step, fmax(0.25 * w_above[f], -d));
            }
        }
        x = (x + step >= stop - 1e-9 * step) ? stop : x + step;
        brk[++n] = x;
    }
    if (x < hi) brk[++n] = hi; /* panel budget exhausted (not reached in the supported domain) */
    return n;
}
