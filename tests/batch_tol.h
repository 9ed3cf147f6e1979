/* Derived tolerance of the float light-set batch (shl_lights_eval_batch_f and
 * what goes through it: the float grid fill) against the scalar double
 * reference shl_lights_eval at the same (float-rounded) point.
 *
 * Tolerance: the set's result is the sum over lights of rgb_c times each
 * light's unit-radiance result, so its error is at most the sum of the lights'
 * own errors times |rgb_c|, plus the float summation over the n lights
 * (worst case n u_f |terms|, |L_lm| <= sqrt(2l+1) |L00|, |grad| <= max|grad|).  Each
 * light's error is bounded by the tolerance its own batch test states:
 * polygons: the per-band tolerances of float_tol.h (derived), spheres (test_simd_sphere_interp.c)
 * 2e-5 |L00| and 1e-5 max|grad| up to lmax 14, 1.5e-4 and 3e-5 above.  Per
 * light, |L00| and max|grad| come from shl_polygon_grad / shl_sphere_grad in
 * double.  The floor 16 FLT_MIN per light
 * admits results below float range (the gradient of a light 1e100 away). */
#ifndef SHL_BATCH_TOL_H
#define SHL_BATCH_TOL_H

#include "float_tol.h"
#include "harness.h"
#include "shlight.h"
#include <float.h>
#include <math.h>
#include <string.h>

enum { MAXLIGHTS = 12, NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX) };

/* A light set and a copy of what went into it (for the per-light scales). */
typedef struct {
    shl_lights *set;
    int count, n[MAXLIGHTS], two_sided[MAXLIGHTS], sphere[MAXLIGHTS];
    double v[MAXLIGHTS][3 * SHL_MAX_VERTS], rgb[MAXLIGHTS][3], center[MAXLIGHTS][3], radius[MAXLIGHTS];
} light_set;

static inline void add_polygon(light_set *s, const double *v, int n, const double rgb[3], int two_sided)
{
    const int i = s->count++;
    CHECK(shl_lights_add_polygon(s->set, v, n, rgb, two_sided) == SHL_OK);
    memcpy(s->v[i], v, sizeof(double) * 3 * n);
    memcpy(s->rgb[i], rgb, sizeof(double) * 3);
    s->n[i] = n;
    s->two_sided[i] = two_sided;
    s->sphere[i] = 0;
}

static inline void add_sphere(light_set *s, const double center[3], double radius, const double rgb[3])
{
    const int i = s->count++;
    CHECK(shl_lights_add_sphere(s->set, center, radius, rgb) == SHL_OK);
    memcpy(s->center[i], center, sizeof(double) * 3);
    memcpy(s->rgb[i], rgb, sizeof(double) * 3);
    s->radius[i] = radius;
    s->sphere[i] = 1;
}

/* Band of coefficient k (k = l^2 .. l^2 + 2l). */
static inline int band_of(int k) { return (int)sqrt(k + 0.5); }

/* err / tol; a zero tolerance (nothing reaches x in this channel) admits only exact zeros. */
static inline double tol_ratio(double err, double tol) { return tol > 0.0 ? err / tol : (err == 0.0 ? 0.0 : HUGE_VAL); }

/* Per-colour, per-band tolerances tc[c][l], tg[c][l] at x: the sum over lights
 * reaching x of |rgb_c| times the light's tolerance (see the top of the file). */
static inline void tolerances(const shl_ctx *ctx, const light_set *s, const double x[3], double tc[3][SHL_LMAX_MAX + 1],
                              double tg[3][SHL_LMAX_MAX + 1])
{
    const int lmax = shl_ctx_lmax(ctx), nc = SHL_NCOEFFS(lmax);
    static double c[NCMAX], g[3 * NCMAX];
    const double sum_c = s->count * (FLT_EPSILON / 2); /* float sum over the lights, |L_lm| <= sqrt(2l+1) |L00| */
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l <= lmax; ++l) tc[k][l] = tg[k][l] = 0.0;
    for (int i = 0; i < s->count; ++i) {
        double ct = 0.0, gt = 0.0, omega = 0.0; /* spheres: relative to |L00|, max|grad| */
        if (s->sphere[i]) {
            CHECK(shl_sphere_grad(ctx, x, s->center[i], s->radius[i], c, g) == SHL_OK);
            ct = lmax <= 14 ? 2e-5 : 1.5e-4;
            gt = lmax <= 14 ? 1e-5 : 3e-5;
        } else {
            double nrm[3] = {0, 0, 0};
            const double *v = s->v[i];
            for (int j = 1; j + 1 < s->n[i]; ++j) { /* Newell normal, fan from v_0 */
                const double e[3] = {v[3 * j] - v[0], v[3 * j + 1] - v[1], v[3 * j + 2] - v[2]};
                const double f[3] = {v[3 * j + 3] - v[0], v[3 * j + 4] - v[1], v[3 * j + 5] - v[2]};
                nrm[0] += e[1] * f[2] - e[2] * f[1];
                nrm[1] += e[2] * f[0] - e[0] * f[2];
                nrm[2] += e[0] * f[1] - e[1] * f[0];
            }
            const double front = nrm[0] * (x[0] - v[0]) + nrm[1] * (x[1] - v[1]) + nrm[2] * (x[2] - v[2]);
            if (!s->two_sided[i] && !(front > 0.0)) continue;
            CHECK(shl_polygon_grad(ctx, x, v, s->n[i], c, g) == SHL_OK);
            CHECK(shl_polygon_solid_angle(x, v, s->n[i], &omega) == SHL_OK);
            if (omega == 0.0) continue;
        }
        double gmax = 0.0;
        for (int k = 0; k < 3 * nc; ++k) gmax = fmax(gmax, fabs(g[k]));
        double tcl[SHL_LMAX_MAX + 1], tgl[SHL_LMAX_MAX + 1];
        if (s->sphere[i])
            for (int l = 0; l <= lmax; ++l) tcl[l] = ct * fabs(c[0]), tgl[l] = gt * gmax;
        else
            float_poly_tol(lmax, x, s->v[i], s->n[i], omega, gmax, 1, tcl, tgl);
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l <= lmax; ++l) {
                tc[k][l] += fabs(s->rgb[i][k]) * (tcl[l] + sum_c * sqrt(2.0 * l + 1.0) * fabs(c[0]) + 16.0 * FLT_MIN);
                tg[k][l] += fabs(s->rgb[i][k]) * (tgl[l] + sum_c * gmax + 16.0 * FLT_MIN);
            }
    }
}

#endif
