/* Reference quadrature over spherical caps (see capref.h). */
#include "capref.h"
#include "shlight.h"
#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

enum { NU = 18, NPHI = 64 }; /* exact for the degree-30 polynomials in u, trig degree < 64 */

void capref_gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; ++i) {
        double t = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            const double dt = p1 / dp;
            t -= dt;
            if (fabs(dt) < 1e-16) break;
        }
        x[i] = t;
        w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
}

void capref_cap(int lmax, const double axis[3], double t, double *coeffs)
{
    const int nc = SHL_NCOEFFS(lmax);
    double gx[NU], gw[NU], e1[3], e2[3], y[SHL_NCOEFFS(CAPREF_LMAX)];
    capref_gauss_legendre(NU, gx, gw);
    /* e1, e2: orthonormal, orthogonal to the axis */
    const double h[3] = {fabs(axis[0]) < 0.6 ? 1.0 : 0.0, fabs(axis[0]) < 0.6 ? 0.0 : 1.0, 0.0};
    e1[0] = h[1] * axis[2] - h[2] * axis[1];
    e1[1] = h[2] * axis[0] - h[0] * axis[2];
    e1[2] = h[0] * axis[1] - h[1] * axis[0];
    const double n1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int k = 0; k < 3; ++k) e1[k] /= n1;
    e2[0] = axis[1] * e1[2] - axis[2] * e1[1];
    e2[1] = axis[2] * e1[0] - axis[0] * e1[2];
    e2[2] = axis[0] * e1[1] - axis[1] * e1[0];
    memset(coeffs, 0, sizeof(double) * nc);
    for (int i = 0; i < NU; ++i) {
        const double q = 0.5 * t * (1.0 - gx[i]); /* 1 - u, accurate for tiny t */
        const double u = 1.0 - q, s = sqrt(q * (2.0 - q));
        const double wu = 0.5 * t * gw[i] * 2.0 * M_PI / NPHI;
        for (int j = 0; j < NPHI; ++j) {
            const double phi = 2.0 * M_PI * (j + 0.5) / NPHI, cp = cos(phi), sp = sin(phi);
            double d[3];
            for (int k = 0; k < 3; ++k) d[k] = u * axis[k] + s * (cp * e1[k] + sp * e2[k]);
            shl_eval_basis(lmax, d, y);
            for (int k = 0; k < nc; ++k) coeffs[k] += wu * y[k];
        }
    }
}

void capref_sphere(int lmax, const double x[3], const double c[3], double r, double *coeffs)
{
    /* geometry in long double, so that finite differences with steps far below
     * the gap to a tangent sphere are not swamped by the rounding of the distance */
    const long double v[3] = {(long double)c[0] - x[0], (long double)c[1] - x[1], (long double)c[2] - x[2]};
    const long double d = sqrtl(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (d <= r) {
        memset(coeffs, 0, sizeof(double) * SHL_NCOEFFS(lmax));
        coeffs[0] = sqrt(4.0 * M_PI);
        return;
    }
    const double axis[3] = {(double)(v[0] / d), (double)(v[1] / d), (double)(v[2] / d)};
    /* 1 - cos a = 1 - sqrt(d^2 - r^2)/d = r^2 / (d (d + sqrt(d^2 - r^2))) */
    capref_cap(lmax, axis, (double)((long double)r * r / (d * (d + sqrtl((d - r) * (d + r))))), coeffs);
}
