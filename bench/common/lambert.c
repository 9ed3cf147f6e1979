#include "lambert.h"
#include "vec3.h"
#include <string.h>

double lambert_irradiance(const double *v, int n, const double x[3], const double nrm[3])
{
    double poly[2 * SHL_MAX_VERTS][3];
    int m = 0;
    for (int i = 0; i < n; ++i) { /* clip to the half-space above the tangent plane */
        double a[3], b[3];
        v3_sub(a, v + 3 * i, x);
        v3_sub(b, v + 3 * ((i + 1) % n), x);
        const double ha = v3_dot(a, nrm), hb = v3_dot(b, nrm);
        if (ha >= 0) memcpy(poly[m++], a, sizeof a);
        if ((ha >= 0) != (hb >= 0)) {
            for (int k = 0; k < 3; ++k) poly[m][k] = a[k] + ha / (ha - hb) * (b[k] - a[k]);
            ++m;
        }
    }
    double s = 0.0;
    for (int i = 0; m >= 3 && i < m; ++i) {
        double a[3], b[3], g[3];
        memcpy(a, poly[i], sizeof a);
        memcpy(b, poly[(i + 1) % m], sizeof b);
        if (v3_normalize(a) == 0 || v3_normalize(b) == 0) continue;
        v3_cross(g, a, b);
        if (v3_normalize(g) == 0) continue;
        s += acos(fmax(-1.0, fmin(1.0, v3_dot(a, b)))) * v3_dot(nrm, g);
    }
    return 0.5 * fabs(s);
}

double lambert_solid_angle(const double *v, int n, const double x[3])
{
    double sum = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        double a[3], b[3], c[3], bc[3];
        v3_sub(a, v, x);
        v3_sub(b, v + 3 * i, x);
        v3_sub(c, v + 3 * (i + 1), x);
        v3_cross(bc, b, c);
        const double la = v3_len(a), lb = v3_len(b), lc = v3_len(c);
        sum += fabs(2.0 * atan2(fabs(v3_dot(a, bc)), la * lb * lc + v3_dot(a, b) * lc + v3_dot(a, c) * lb + v3_dot(b, c) * la));
    }
    return sum;
}

int lambert_lit(const scene_polygon *p, const double x[3])
{
    double e1[3], e2[3], nrm[3], d[3];
    v3_sub(e1, p->v + 3, p->v);
    v3_sub(e2, p->v + 6, p->v);
    v3_cross(nrm, e1, e2);
    v3_sub(d, x, p->v);
    return p->two_sided || v3_dot(nrm, d) > 0;
}

void lambert_scene(const scene *s, float *out)
{
    const mesh *g = &s->geom;
    for (int v = 0; v < g->nv; ++v) {
        const double *x = g->pos + 3 * v, *n = g->nrm + 3 * v, *alb = s->mats[g->mat[v]].albedo;
        double e[3] = {0, 0, 0};
        for (int j = 0; j < s->npolys; ++j) {
            const scene_polygon *q = &s->polys[j];
            if (!lambert_lit(q, x)) continue;
            const double irr = lambert_irradiance(q->v, q->n, x, n);
            for (int c = 0; c < 3; ++c) e[c] += q->rgb[c] * irr;
        }
        for (int c = 0; c < 3; ++c) out[3 * v + c] = (float)(alb[c] / M_PI * e[c]);
    }
}
