/* Polygonal lights: per-edge geometry, solid angle, and the ZH recurrence of
 * Wang & Ramamoorthi 2018 (Sec. 4.1).  The recurrence is written once in
 * polygon_zh.h and instantiated for double and float. */
#include "polygon.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>
#include <string.h>

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static inline void sub3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

/* Signed solid angle of the planar polygon p[0..n-1] (relative to x) as a fan of
 * signed triangles, each by the Van Oosterom-Strackee atan2 form.  Unlike the
 * sum-of-angles formula (Wang 2018 Eq. 24) it keeps full relative accuracy for
 * tiny polygons and handles concave ones.  Edges are taken from the input
 * vertices (e_i = v_i - v_0), so the triple product never cancels. */
static double signed_solid_angle(const double (*rel)[3], const double *dist,
                                 const double *verts, int n)
{
    double total = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        double e1[3], e2[3], c[3];
        sub3(verts + 3 * i, verts, e1);
        sub3(verts + 3 * (i + 1), verts, e2);
        cross3(e1, e2, c);
        const double triple = dot3(rel[0], c);
        const double den = dist[0] * dist[i] * dist[i + 1] + dot3(rel[0], rel[i]) * dist[i + 1] +
                           dot3(rel[0], rel[i + 1]) * dist[i] + dot3(rel[i], rel[i + 1]) * dist[0];
        total += 2.0 * atan2(triple, den);
    }
    return total;
}

/* Signed distance of x from the polygon's plane, and the polygon's extent as seen from x. */
static int point_in_plane(const double *verts, int n, const double (*rel)[3], const double *dist)
{
    double normal[3] = {0.0, 0.0, 0.0}; /* Newell's method, relative to v_0 */
    for (int i = 1; i + 1 < n; ++i) {
        double e1[3], e2[3], c[3];
        sub3(verts + 3 * i, verts, e1);
        sub3(verts + 3 * (i + 1), verts, e2);
        cross3(e1, e2, c);
        for (int k = 0; k < 3; ++k) normal[k] += c[k];
    }
    const double len = sqrt(dot3(normal, normal));
    double rmax = 0.0;
    for (int i = 0; i < n; ++i) rmax = fmax(rmax, dist[i]);
    if (!(len > 0.0)) return 1; /* zero-area polygon: sees nothing */
    const double height = fabs(dot3(normal, rel[0])) / len;
    /* Below a few ulps of the distances the side of the plane is decided by rounding. */
    return height <= 8.0 * DBL_EPSILON * rmax;
}

void shl__poly_geom_init(shl__poly_geom *g, const double x[3], const double *verts, int n)
{
    double kept[SHL_MAX_VERTS * 3];
    int m = 0;
    for (int i = 0; i < n; ++i) { /* drop vertices repeating their predecessor (zero-length edges) */
        const double *v = verts + 3 * i;
        if (m > 0 && memcmp(v, kept + 3 * (m - 1), sizeof(double) * 3) == 0) continue;
        memcpy(kept + 3 * m, v, sizeof(double) * 3);
        ++m;
    }
    while (m > 1 && memcmp(kept, kept + 3 * (m - 1), sizeof(double) * 3) == 0) --m;
    g->n = 0;
    g->solid_angle = 0.0;
    if (m < 3) return;

    for (int i = 0; i < m; ++i) {
        sub3(kept + 3 * i, x, g->rel[i]);
        g->dist[i] = sqrt(dot3(g->rel[i], g->rel[i]));
        if (!(g->dist[i] > 0.0)) return; /* x on a vertex: in the plane */
    }
    if (point_in_plane(kept, m, (const double(*)[3])g->rel, g->dist)) return;

    double omega = signed_solid_angle((const double(*)[3])g->rel, g->dist, kept, m);
    if (omega < 0.0) { /* orient counter-clockwise seen from outside: reverse the order */
        for (int i = 0, j = m - 1; i < j; ++i, --j)
            for (int k = 0; k < 3; ++k) {
                const double t = kept[3 * i + k];
                kept[3 * i + k] = kept[3 * j + k];
                kept[3 * j + k] = t;
            }
        for (int i = 0; i < m; ++i) {
            sub3(kept + 3 * i, x, g->rel[i]);
            g->dist[i] = sqrt(dot3(g->rel[i], g->rel[i]));
        }
        omega = -omega;
    }
    g->n = m;
    g->solid_angle = omega;

    for (int e = 0; e < m; ++e)
        for (int k = 0; k < 3; ++k) g->w[e][k] = g->rel[e][k] / g->dist[e];
    for (int e = 0; e < m; ++e) {
        const int f = (e + 1) % m;
        double edge[3], c[3];
        sub3(kept + 3 * f, kept + 3 * e, edge); /* from the input vertices: exact for nearby ones */
        cross3(g->rel[e], edge, c); /* = rel_e x rel_f without cancellation */
        const double clen = sqrt(dot3(c, c));
        /* Wang 2018 Eq. 20: gamma from atan2 is accurate for tiny and near-pi arcs */
        g->gamma[e] = atan2(clen, dot3(g->rel[e], g->rel[f]));
        g->sin_gamma[e] = sin(g->gamma[e]);
        g->cos_gamma[e] = cos(g->gamma[e]);
        const double half = sin(0.5 * g->gamma[e]);
        g->omc_gamma[e] = 2.0 * half * half;
        /* w_f - w_e = edge/r_f + rel_e (r_e - r_f)/(r_e r_f), r_e - r_f = -edge.(rel_e + rel_f)/(r_e + r_f) */
        double sum[3];
        for (int k = 0; k < 3; ++k) sum[k] = g->rel[e][k] + g->rel[f][k];
        const double dr = -dot3(edge, sum) / (g->dist[e] + g->dist[f]);
        for (int k = 0; k < 3; ++k)
            g->dw[e][k] = edge[k] / g->dist[f] + g->rel[e][k] * (dr / (g->dist[e] * g->dist[f]));
        if (clen > 0.0) {
            for (int k = 0; k < 3; ++k) g->mu[e][k] = c[k] / clen;
            cross3(g->mu[e], g->w[e], g->lam[e]);
            /* foot of x on the edge's line: q = edge x c / |edge|^2, so q/|q|^2 = edge x c / |c|^2 */
            double q[3], gxmu[3];
            cross3(edge, c, q);
            for (int k = 0; k < 3; ++k) g->gvec[e][k] = q[k] / clen / clen;
            cross3(g->gvec[e], g->mu[e], gxmu); /* f'(t) = w(t) . (g x mu) since w' = mu x w */
            g->fprime1[e] = dot3(g->w[f], gxmu);
            /* I_0 = g . int_0^gamma w(t) dt = g . (w_e sin(gamma) + lambda_e (1 - cos(gamma))) */
            g->f_integral[e] = dot3(g->gvec[e], g->w[e]) * g->sin_gamma[e] +
                               dot3(g->gvec[e], g->lam[e]) * g->omc_gamma[e];
        } else { /* underflowed arc: contributes nothing (gamma = 0, c_e = 0) */
            for (int k = 0; k < 3; ++k) g->mu[e][k] = g->lam[e][k] = g->gvec[e][k] = 0.0;
            g->fprime1[e] = g->f_integral[e] = 0.0;
        }
    }
}

#define REAL double
#define WITH_GRAD 0
#define SUFFIX(name) name##_d
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#define WITH_GRAD 1
#define SUFFIX(name) name##_grad_d
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#undef REAL

#define REAL float
#define WITH_GRAD 0
#define SUFFIX(name) name##_f
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#define WITH_GRAD 1
#define SUFFIX(name) name##_grad_f
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#undef REAL
