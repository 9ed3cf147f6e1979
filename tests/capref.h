/* Independent reference for spherical caps and lights: product quadrature about
 * the cap axis (Gauss-Legendre in u = cos(angle to the axis), trapezoid in the
 * azimuth).  The azimuthal average of Y_lm over a circle is a polynomial of
 * degree <= l in u, so the rule is exact up to rounding for l <= CAPREF_LMAX. */
#ifndef SHL_TEST_CAPREF_H
#define SHL_TEST_CAPREF_H

#define CAPREF_LMAX 30

/* Gauss-Legendre rule of n <= 64 nodes on [-1, 1] (Newton on P_n). */
void capref_gauss_legendre(int n, double *x, double *w);

/* coeffs[k] = integral of Y_k over the cap {w : axis . w >= 1 - t} (axis unit,
 * 0 <= t <= 2; t passed directly so that tiny caps keep full accuracy). */
void capref_cap(int lmax, const double axis[3], double t, double *coeffs);

/* The cap subtended by the sphere (c, r) at x; the whole sphere of directions
 * when x is inside or on it. */
void capref_sphere(int lmax, const double x[3], const double c[3], double r, double *coeffs);

#endif
