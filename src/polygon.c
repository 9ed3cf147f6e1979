/* Polygonal lights: per-edge geometry, solid angle, and the ZH recurrence of
 * Wang & Ramamoorthi 2018 (Sec. 4.1).  The recurrence is written once in
 * polygon_zh.h and instantiated for double and float. */
#include "polygon.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>
#include <string.h>

/* (a - b) 2^e per component (internal.h) */
static inline void scaled_sub3(const double a[3], const double b[3], int e, double out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = shl__diff_scaled(a[k], b[k], e);
}

/* Unit Newell normal of the polygon (counter-clockwise seen from its tip,
 * internal.h); 0 for a zero-area polygon (also vertices equal up to the sign of
 * zero). */
static int newell_normal(const double *verts, int n, double nrm[3])
{
    shl__newell_scaled(verts, n, nrm);
    const double len = shl__norm3(nrm);
    if (!(len > 0.0)) return 0;
    for (int k = 0; k < 3; ++k) nrm[k] /= len;
    return 1;
}

/* Solid angle of the polygon (magnitude) as a fan of Van Oosterom-Strackee
 * triangles, tan(omega/2) = N / D.  Unlike the sum-of-angles formula (Wang 2018
 * Eq. 24) this keeps full relative accuracy for tiny polygons and handles
 * concave ones.  Two fans, each used where its D is a sum of positive terms, so
 * nothing cancels and no term crosses atan2's branch cut:
 *  - far from the plane (|h| >= 2 x extent) the fan from vertex 0: all vertex
 *    directions lie within 60 degrees of each other;
 *  - otherwise the fan from the foot F of x on the plane, where with e_i the
 *    in-plane offsets of the vertices from F and a = |h|, N and D divided by a are
 *    n.(e_i x e_j) and r_i r_j + a (r_i + r_j) + a^2 + e_i.e_j, and for e_i.e_j < 0
 *    r_i r_j + e_i.e_j = (a^4 + a^2 (|e_i|^2 + |e_j|^2) + |e_i x e_j|^2) / (r_i r_j - e_i.e_j). */
static double solid_angle(const double (*rel)[3], const double *dist, const double *verts, int n, int e,
                          const double nrm[3], double height)
{
    double extent = 0.0, total = 0.0;
    for (int i = 1; i < n; ++i) {
        double d[3];
        scaled_sub3(verts + 3 * i, verts, e, d);
        extent = fmax(extent, sqrt(shl__dot3(d, d)));
    }
    if (fabs(height) >= 2.0 * extent) {
        for (int i = 1; i + 1 < n; ++i) {
            double e1[3], e2[3], c[3];
            scaled_sub3(verts + 3 * i, verts, e, e1);
            scaled_sub3(verts + 3 * (i + 1), verts, e, e2);
            shl__cross3(e1, e2, c);
            const double num = shl__dot3(rel[0], c);
            const double den = dist[0] * dist[i] * dist[i + 1] + shl__dot3(rel[0], rel[i]) * dist[i + 1] +
                               shl__dot3(rel[0], rel[i + 1]) * dist[i] + shl__dot3(rel[i], rel[i + 1]) * dist[0];
            total += 2.0 * atan2(num, den);
        }
        return fabs(total);
    }
    const double a = fabs(height);
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1 == n) ? 0 : i + 1;
        double ei[3], ej[3], edge[3], c[3];
        const double hi = shl__dot3(nrm, rel[i]), hj = shl__dot3(nrm, rel[j]);
        for (int k = 0; k < 3; ++k) {
            ei[k] = rel[i][k] - hi * nrm[k];
            ej[k] = rel[j][k] - hj * nrm[k];
        }
        scaled_sub3(verts + 3 * j, verts + 3 * i, e, edge); /* e_i x e_j = e_i x (v_j - v_i) */
        shl__cross3(ei, edge, c);
        const double num = shl__dot3(nrm, c), dot = shl__dot3(ei, ej), ri = dist[i], rj = dist[j];
        const double pair = dot >= 0.0 ? ri * rj + dot
                                       : (a * a * (a * a + shl__dot3(ei, ei) + shl__dot3(ej, ej)) + num * num) / (ri * rj - dot);
        total += 2.0 * atan2(num, pair + a * (ri + rj) + a * a);
    }
    return fabs(total);
}

void shl__poly_geom_init(shl__poly_geom *g, const double x[3], const double *verts, int n)
{
    double kept[SHL_MAX_VERTS * 3];
    const int m = shl__drop_repeated(verts, n, kept); /* zero-length edges */
    g->n = 0;
    g->solid_angle = 0.0;
    g->grad_scale[0] = g->grad_scale[1] = 1.0;
    if (m < 3) return;

    /* scaled units: v - x times 2^-ex, largest component in [1, 2) (internal.h) */
    const int ex = shl__scale_exponent(x, kept, m);
    if (ex == INT_MIN) return; /* x on a vertex: in the plane */
    for (int i = 0; i < m; ++i) {
        scaled_sub3(kept + 3 * i, x, -ex, g->rel[i]);
        g->dist[i] = shl__norm3(g->rel[i]); /* norm3: a vertex within 2^-537 of x would underflow rel . rel */
        if (!(g->dist[i] > 0.0)) return; /* within 2^-1074 of the farthest vertex: on it, in the plane */
    }
    double nrm[3], rmax = 0.0;
    if (!newell_normal(kept, m, nrm)) return; /* zero-area polygon: sees nothing */
    for (int i = 0; i < m; ++i) rmax = fmax(rmax, g->dist[i]);
    const double height = shl__dot3(nrm, g->rel[0]); /* signed: > 0 when the polygon lies along +nrm */
    /* Below a few ulps of the distances the side of the plane is decided by rounding. */
    if (fabs(height) <= 8.0 * DBL_EPSILON * rmax) return;
    /* Seen from x, the polygon is counter-clockwise from outside the unit sphere
     * (positive solid angle) exactly when it lies along +nrm: otherwise reverse. */
    if (height < 0.0) {
        for (int i = 0, j = m - 1; i < j; ++i, --j)
            for (int k = 0; k < 3; ++k) {
                const double t = kept[3 * i + k];
                kept[3 * i + k] = kept[3 * j + k];
                kept[3 * j + k] = t;
            }
        for (int i = 0; i < m; ++i) {
            scaled_sub3(kept + 3 * i, x, -ex, g->rel[i]);
            g->dist[i] = shl__norm3(g->rel[i]);
        }
    }
    const double omega = solid_angle((const double(*)[3])g->rel, g->dist, kept, m, -ex, nrm, height);
    g->n = m;
    g->solid_angle = omega;
    shl__pow2_split(-ex, g->grad_scale); /* d/dx = 2^-ex d/dx_scaled */

    for (int e = 0; e < m; ++e)
        for (int k = 0; k < 3; ++k) g->w[e][k] = g->rel[e][k] / g->dist[e];
    for (int e = 0; e < m; ++e) {
        const int f = (e + 1) % m;
        double edge[3], c[3];
        scaled_sub3(kept + 3 * f, kept + 3 * e, -ex, edge); /* from the input vertices: exact for nearby ones */
        shl__cross3(g->rel[e], edge, c); /* = rel_e x rel_f without cancellation */
        const double clen = shl__norm3(c);
        /* Wang 2018 Eq. 20: gamma from atan2 is accurate for tiny and near-pi arcs */
        g->gamma[e] = atan2(clen, shl__dot3(g->rel[e], g->rel[f]));
        g->sin_gamma[e] = sin(g->gamma[e]);
        g->cos_gamma[e] = cos(g->gamma[e]);
        const double half = sin(0.5 * g->gamma[e]);
        g->omc_gamma[e] = 2.0 * half * half;
        /* w_f - w_e = edge/r_f + w_e (r_e - r_f)/r_f, r_e - r_f = -edge.(rel_e + rel_f)/(r_e + r_f):
         * no cancellation for an edge short against the distances; for a longer one its terms
         * can reach |edge| / min(r) (and overflow), while w_f - w_e itself is then accurate */
        if (shl__norm3(edge) <= fmin(g->dist[e], g->dist[f])) {
            double sum[3];
            for (int k = 0; k < 3; ++k) sum[k] = g->rel[e][k] + g->rel[f][k];
            const double dr = -shl__dot3(edge, sum) / (g->dist[e] + g->dist[f]);
            for (int k = 0; k < 3; ++k) g->dw[e][k] = edge[k] / g->dist[f] + g->w[e][k] * (dr / g->dist[f]);
        } else {
            for (int k = 0; k < 3; ++k) g->dw[e][k] = g->w[f][k] - g->w[e][k];
        }
        if (clen > 0.0) {
            for (int k = 0; k < 3; ++k) g->mu[e][k] = c[k] / clen;
            shl__cross3(g->mu[e], g->w[e], g->lam[e]);
            /* foot of x on the edge's line: q = edge x c / |edge|^2, so q/|q|^2 = (edge x mu) / |c|
             * (no product of two edge lengths: nothing underflows for a tiny, distant polygon) */
            double q[3], gxmu[3];
            shl__cross3(edge, g->mu[e], q);
            for (int k = 0; k < 3; ++k) g->gvec[e][k] = q[k] / clen;
            shl__cross3(g->gvec[e], g->mu[e], gxmu); /* f'(t) = w(t) . (g x mu) since w' = mu x w */
            g->fprime1[e] = shl__dot3(g->w[f], gxmu);
            /* I_0 = g . int_0^gamma w(t) dt = g . (w_e sin(gamma) + lambda_e (1 - cos(gamma))) */
            g->f_integral[e] = shl__dot3(g->gvec[e], g->w[e]) * g->sin_gamma[e] +
                               shl__dot3(g->gvec[e], g->lam[e]) * g->omc_gamma[e];
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
