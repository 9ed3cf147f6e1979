/* Independent numerical reference for the SH projection of a uniform planar
 * polygonal light seen from a point x (tests only):
 *   coeffs[l*(l+1)+m] = integral over the solid angle of the polygon at x of Y_lm(w) dw,
 * real SH with the Condon-Shortley phase (shl__sh_eval), 0 <= lmax <= SHL_LMAX_MAX.
 * The polygon (n >= 3 vertices, xyz interleaved) is planar and simple, convex or
 * concave, either winding; the result does not depend on the winding.  A point
 * whose computed height above the plane is exactly 0 sees nothing (all zeros).
 *
 * Two independent adaptive quadratures (target: absolute error <= 1e-15 x solid angle):
 *  - REF_POLAR: fan of spherical triangles (c, arc of each edge) about a centre
 *    direction c (the nadir when the foot of x is inside the polygon, else the
 *    polygon's centroid); outer variable = arc length along the edge's great
 *    circle, inner = arc length from c.  Gradient by the moving-boundary
 *    (Reynolds) integral over the edges.
 *  - REF_AREA: integral of Y(s) |n.s| / r^2 over the plane polygon (signed fan of
 *    triangles, collapsed product Gauss-Legendre, midpoint subdivision); gradient
 *    by differentiating the integrand analytically.
 * REF_AUTO uses REF_AREA when the polygon's diameter is below a quarter of its
 * distance to x, REF_POLAR otherwise.  Requested accuracy 1e-15 x solid angle;
 * tests/test_ref_quad.c measures a few 1e-16 to ~5e-15 up to lmax 30.
 *
 * Limitations:
 *  - REF_AREA forced on x close to the polygon relative to its size needs deep
 *    refinement (seconds); REF_AUTO never does that.
 *  - The REF_POLAR gradient sums edge terms that cancel for polygons of small
 *    angular size (relative error ~ eps x distance / size); REF_AUTO uses REF_AREA.
 *  - Vertices of a tilted polygon are planar only up to rounding: near an edge or
 *    vertex, or with x close to the plane, the input itself is ambiguous at
 *    ~eps |v| / distance (relative).  Axis-aligned planes are exact.
 *
 * Return 0 on success, a negative REF_E* code otherwise (outputs untouched). */
#ifndef SHL_TEST_REF_QUAD_H
#define SHL_TEST_REF_QUAD_H

enum { REF_AUTO = 0, REF_POLAR = 1, REF_AREA = 2 };

#define REF_EARG     -1 /* NULL pointer, lmax or n out of range, non-finite input, bad method */
#define REF_EDEGEN   -2 /* polygon with zero area                                        */
#define REF_ENOMEM   -3 /* allocation failed                                             */
#define REF_EINPLANE -4 /* gradient requested for a point in the polygon's plane         */

/* *err_est (may be NULL) = estimated max abs error over the coefficients. */
int ref_polygon_sh(int lmax, const double x[3], const double *verts, int n,
                   double *coeffs, double *err_est);
/* Also grad[a*nc + k] = d coeffs[k] / d x[a], nc = (lmax+1)^2. */
int ref_polygon_sh_grad(int lmax, const double x[3], const double *verts, int n,
                        double *coeffs, double *grad, double *err_est);
/* Either path explicitly (method = REF_AUTO, REF_POLAR or REF_AREA); grad may be NULL. */
int ref_polygon_sh_method(int method, int lmax, const double x[3], const double *verts, int n,
                          double *coeffs, double *grad, double *err_est);
/* Solid angle by the Van Oosterom-Strackee formula over the vertex fan, with the
 * triple products taken as height x plane cross products (no cancellation);
 * 0 in the plane, NAN on invalid input. */
double ref_polygon_solid_angle(const double x[3], const double *verts, int n);

/* Y_lm at the unit direction d (same values as shl__sh_eval) and the Cartesian
 * gradient of the polynomial extension evaluated by that recurrence:
 * g[a*nc + k] = dY_k/dd_a.  Its tangential part is the surface gradient of Y_k. */
void ref_sh_eval_grad(int lmax, const double d[3], double *y, double *g);

#endif
