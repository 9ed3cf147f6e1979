/* Exact references for unshadowed diffuse shading by polygon lights, independent
 * of the library's SH code: Lambert's closed form for the irradiance of a
 * polygon clipped to the receiver's horizon, E = 1/2 |sum_e Theta_e n . Gamma_e|
 * (Theta_e: arc of edge e seen from x, Gamma_e: unit normal of the plane through
 * x and the edge), and the Van Oosterom-Strackee solid angle. */
#ifndef SHL_BENCH_LAMBERT_H
#define SHL_BENCH_LAMBERT_H

#include "scene.h"

/* Irradiance at x (unit normal nrm) from the unit-radiance convex polygon v[3n]. */
double lambert_irradiance(const double *v, int n, const double x[3], const double nrm[3]);
/* Solid angle of the convex polygon v[3n] seen from x. */
double lambert_solid_angle(const double *v, int n, const double x[3]);
/* Does polygon light i of the scene reach x (one-sided lights: x in front)? */
int lambert_lit(const scene_polygon *p, const double x[3]);
/* Exact outgoing radiance albedo/pi * E per receiver vertex, all polygon lights
 * (spherical lights are ignored): out[3 v + c]. */
void lambert_scene(const scene *s, float *out);

#endif
