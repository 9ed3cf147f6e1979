/* Test geometry: random planar polygons (convex and star-shaped concave) and rotations. */
#ifndef SHL_TEST_GEOM_H
#define SHL_TEST_GEOM_H

#include "testutil.h"

/* Orthonormal basis (u, v) of the plane with unit normal nrm. */
static inline void plane_basis(const double nrm[3], double u[3], double v[3])
{
    const double a[3] = {fabs(nrm[0]) < 0.9 ? 1.0 : 0.0, fabs(nrm[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    u[0] = a[1] * nrm[2] - a[2] * nrm[1];
    u[1] = a[2] * nrm[0] - a[0] * nrm[2];
    u[2] = a[0] * nrm[1] - a[1] * nrm[0];
    const double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; ++k) u[k] /= len;
    v[0] = nrm[1] * u[2] - nrm[2] * u[1];
    v[1] = nrm[2] * u[0] - nrm[0] * u[2];
    v[2] = nrm[0] * u[1] - nrm[1] * u[0];
}

/* Random simple polygon with n vertices around center in the plane of nrm.
 * concave != 0 alternates the radius (a star: concave for n >= 4). */
static inline void random_polygon(rng_t *r, int n, int concave, const double center[3],
                                  const double nrm[3], double size, double *verts)
{
    double u[3], v[3], ang[64];
    plane_basis(nrm, u, v);
    for (int i = 0; i < n; ++i) ang[i] = 2.0 * M_PI * (i + rng_range(r, 0.1, 0.9)) / n;
    for (int i = 0; i < n; ++i) {
        double rad = size * rng_range(r, 0.6, 1.0);
        if (concave && (i & 1)) rad *= 0.35;
        for (int k = 0; k < 3; ++k)
            verts[3 * i + k] = center[k] + rad * (cos(ang[i]) * u[k] + sin(ang[i]) * v[k]);
    }
}

/* Rotation matrix about a unit axis by angle t (Rodrigues). */
static inline void rotation_matrix(const double axis[3], double t, double m[3][3])
{
    const double c = cos(t), s = sin(t), C = 1.0 - c, x = axis[0], y = axis[1], z = axis[2];
    m[0][0] = c + x * x * C;     m[0][1] = x * y * C - z * s; m[0][2] = x * z * C + y * s;
    m[1][0] = y * x * C + z * s; m[1][1] = c + y * y * C;     m[1][2] = y * z * C - x * s;
    m[2][0] = z * x * C - y * s; m[2][1] = z * y * C + x * s; m[2][2] = c + z * z * C;
}

/* A sphere seen from far away: sin^2 a = (r/d)^2 below the smallest normal double (r/d from
 * 2^-512 to 2^-590, d from 2^-480 to 2^-540, so that the gradient ~r^2/d^3 and the Hessian
 * ~r^2/d^4 are normal numbers); first: the geometry of the fuzz reproducer
 * fuzz_lights-sphere-sin2-underflow-gradient.  Sets x and the centre c, returns the radius. */
static inline double tiny_sphere_case(rng_t *rg, int first, double x[3], double c[3])
{
    double dir[3];
    rng_unit_vector(rg, dir);
    const int ed = -480 - (int)(rng_uniform(rg) * 60), es = 512 + (int)(rng_uniform(rg) * (ed + 1070 - 512));
    const double d = ldexp(rng_range(rg, 1.0, 2.0), ed), r = ldexp(rng_range(rg, 1.0, 2.0), ed - es);
    for (int k = 0; k < 3; ++k) c[k] = ldexp(rng_range(rg, -1.0, 1.0), ed), x[k] = c[k] - d * dir[k];
    if (!first) return r;
    x[0] = 8.2e-149, x[1] = 8.2e-149, x[2] = -8.4e-149, c[0] = c[1] = c[2] = 0.0;
    return 3.3e-310;
}

#endif
