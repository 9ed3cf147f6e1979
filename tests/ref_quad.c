/* Independent adaptive-quadrature reference for polygon SH projections (see ref_quad.h).
 *
 * Weights are set up in a plane frame: in-plane axes e0, e1 and the unit Newell
 * normal e2 (the polygon is counter-clockwise in (e0, e1)); x is at signed height
 * h above its foot point f.  World differences (v_i - x, v_i+1 - v_i, v_i - v_0)
 * are projected once each, and quantities whose cancellation would cost accuracy
 * (spherical triangle weights, triple products) are written as h times plane
 * cross products of the shortest such vectors.  The directions at which Y is
 * evaluated are built from world differences too, so that a tiny polygon far
 * away is not blurred by the frame's rounding. */
#include "ref_quad.h"
#include "internal.h"
#include "sh_basis.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NOUT 20        /* Gauss-Legendre nodes per outer panel (polar path)       */
#define NTRI 20        /* Gauss-Legendre nodes per direction on a triangle (area) */
#define NIN_MAX 64     /* upper bound on the inner (radial) rule size             */
#define MAX_DEPTH 40   /* bisection / subdivision depth limit                     */
#define REL_TOL 1e-15  /* requested abs error relative to the solid angle         */
#define ROUND_FLOOR (64.0 * DBL_EPSILON) /* differences at rounding level are accepted */

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double cross2(const double a[2], const double b[2]) { return a[0] * b[1] - a[1] * b[0]; }

/* The shorter of two plane vectors.  cross2(p - v_i, e_i) = cross2(p - v_i+1, e_i):
 * taking the endpoint nearer to p avoids cancellation when p is close to it. */
static const double *shorter(const double *a, const double *b)
{
    return a[0] * a[0] + a[1] * a[1] <= b[0] * b[0] + b[1] * b[1] ? a : b;
}

/* n-point Gauss-Legendre rule mapped to [0,1] (Newton on P_n). */
static void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-17) break;
        }
        const double wi = 1.0 / ((1.0 - z * z) * dp * dp);
        x[i] = 0.5 * (1.0 - z);
        x[n - 1 - i] = 0.5 * (1.0 + z);
        w[i] = w[n - 1 - i] = wi;
    }
}

/* ---- SH with Cartesian derivatives ------------------------------------- */

void ref_sh_eval_grad(int lmax, const double d[3], double *y, double *g)
{
    const int nc = (lmax + 1) * (lmax + 1);
    const double x = d[0], yy = d[1], z = d[2];
    double nmm = sqrt(0.25 / M_PI), cm = 1.0, sm = 0.0;
    for (int m = 0; m <= lmax; ++m) {
        /* (x+iy)^m and its derivatives m (x+iy)^(m-1), i m (x+iy)^(m-1) */
        const double k = M_SQRT2 * m, dcx = k * cm, dcy = -k * sm, dsx = k * sm, dsy = k * cm;
        if (m > 0) {
            nmm *= -sqrt((2.0 * m + 1.0) / (2.0 * m));
            const double c = cm * x - sm * yy;
            sm = cm * yy + sm * x;
            cm = c;
        }
        const double sc = (m == 0) ? 1.0 : M_SQRT2 * cm, ss = M_SQRT2 * sm;
        double p1 = 0.0, p2 = 0.0, d1 = 0.0, d2 = 0.0; /* N_{l-1}, N_{l-2} and z-derivatives */
        for (int l = m; l <= lmax; ++l) {
            double p, dp;
            if (l == m) {
                p = nmm;
                dp = 0.0;
            } else if (l == m + 1) {
                p = sqrt(2.0 * m + 3.0) * z * nmm;
                dp = sqrt(2.0 * m + 3.0) * nmm;
            } else {
                const double l2 = (double)l * l, m2 = (double)m * m;
                const double a = sqrt((4.0 * l2 - 1.0) / (l2 - m2));
                const double b = sqrt(((l - 1.0) * (l - 1.0) - m2) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
                p = a * (z * p1 - b * p2);
                dp = a * (p1 + z * d1 - b * d2);
            }
            p2 = p1;
            p1 = p;
            d2 = d1;
            d1 = dp;
            const int i = l * (l + 1) + m;
            y[i] = p * sc;
            g[i] = p * dcx;
            g[nc + i] = p * dcy;
            g[2 * nc + i] = dp * sc;
            if (m > 0) {
                const int j = l * (l + 1) - m;
                y[j] = p * ss;
                g[j] = p * dsx;
                g[nc + j] = p * dsy;
                g[2 * nc + j] = dp * ss;
            }
        }
    }
}

/* ---- geometry ---------------------------------------------------------- */

struct geom {
    int n;
    const double *v;  /* world vertices                                        */
    double x[3];      /* world observer                                        */
    double ax[3][3];  /* world axes e0, e1 (in plane), e2 (unit Newell normal)  */
    double h;         /* signed height of x above the plane                    */
    /* plane coordinates of world differences, each rounded once:
     * a[i] = v_i - x (i.e. relative to the foot point f), e[i] = v_i+1 - v_i,
     * q[i] = v_i - v_0 */
    double (*a)[2], (*e)[2], (*q)[2];
};

static void plane_coords(const struct geom *g, const double d[3], double out[2])
{
    out[0] = dot3(d, g->ax[0]);
    out[1] = dot3(d, g->ax[1]);
}

/* g->a must hold 3 n pairs (a, e and q); returns 0 or REF_EDEGEN. */
static int geom_init(struct geom *g, const double x[3], const double *v, int n)
{
    double nrm[3] = {0.0, 0.0, 0.0};
    for (int i = 1; i + 1 < n; ++i) {
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; ++k) {
            a[k] = v[3 * i + k] - v[k];
            b[k] = v[3 * (i + 1) + k] - v[k];
        }
        cross3(a, b, c);
        for (int k = 0; k < 3; ++k) nrm[k] += c[k];
    }
    const double len = sqrt(dot3(nrm, nrm));
    if (!(len > 0.0)) return REF_EDEGEN;
    double *e0 = g->ax[0], *e1 = g->ax[1], *e2 = g->ax[2];
    for (int k = 0; k < 3; ++k) e2[k] = nrm[k] / len;
    /* e0: the world axis most orthogonal to the normal, projected (exact for
     * axis-aligned planes, so their plane coordinates carry no rounding) */
    int ax = 0;
    for (int k = 1; k < 3; ++k)
        if (fabs(e2[k]) < fabs(e2[ax])) ax = k;
    for (int k = 0; k < 3; ++k) e0[k] = (k == ax) - e2[ax] * e2[k];
    const double l0 = sqrt(dot3(e0, e0));
    for (int k = 0; k < 3; ++k) e0[k] /= l0;
    cross3(e2, e0, e1);
    g->n = n;
    g->v = v;
    memcpy(g->x, x, sizeof g->x);
    g->e = g->a + n;
    g->q = g->a + 2 * n;
    double best = INFINITY;
    for (int i = 0; i < n; ++i) {
        const double *vi = v + 3 * i, *vj = v + 3 * ((i + 1) % n);
        const double da[3] = {vi[0] - x[0], vi[1] - x[1], vi[2] - x[2]};
        const double de[3] = {vj[0] - vi[0], vj[1] - vi[1], vj[2] - vi[2]};
        const double dq[3] = {vi[0] - v[0], vi[1] - v[1], vi[2] - v[2]};
        plane_coords(g, da, g->a[i]);
        plane_coords(g, de, g->e[i]);
        plane_coords(g, dq, g->q[i]);
        if (dot3(da, da) < best) { /* height measured from the nearest vertex */
            best = dot3(da, da);
            g->h = -dot3(da, e2);
        }
    }
    return 0;
}

static void to_world(const struct geom *g, const double l[3], double w[3])
{
    for (int k = 0; k < 3; ++k) w[k] = l[0] * g->ax[0][k] + l[1] * g->ax[1][k] + l[2] * g->ax[2][k];
}

/* Vector from the observer to vertex i + d (d: world offset in the plane) from
 * world differences, so that the directions at which Y is evaluated carry a
 * single rounding; moved along the normal onto the plane at height -h, which
 * the weights assume (input vertices are planar only up to rounding). */
static void obs_vector(const struct geom *g, int i, const double d[3], double out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = (g->v[3 * i + k] - g->x[k]) + d[k];
    const double off = dot3(out, g->ax[2]) + g->h;
    for (int k = 0; k < 3; ++k) out[k] -= off * g->ax[2][k];
}

static void unit_from_obs(const struct geom *g, int i, const double d[3], double out[3])
{
    obs_vector(g, i, d, out);
    const double l = sqrt(dot3(out, out));
    for (int k = 0; k < 3; ++k) out[k] /= l;
}

/* Vector from the observer to the plane point at p relative to the foot point. */
static void from_obs(const struct geom *g, const double p[2], double out[3])
{
    out[0] = p[0];
    out[1] = p[1];
    out[2] = -g->h;
}

/* Whether the foot point is inside the polygon (crossing number). */
static int foot_inside(const struct geom *g)
{
    int c = 0;
    for (int i = 0, j = g->n - 1; i < g->n; j = i++) {
        const double *a = g->a[i], *b = g->a[j];
        if ((a[1] > 0.0) != (b[1] > 0.0) && 0.0 < (b[0] - a[0]) * -a[1] / (b[1] - a[1]) + a[0]) c = !c;
    }
    return c;
}

/* Distance in the plane from the foot point to the polygon (0 inside). */
static double foot_distance(const struct geom *g)
{
    if (foot_inside(g)) return 0.0;
    double best = INFINITY;
    for (int i = 0; i < g->n; ++i) {
        const double *a = g->a[i], *e = g->e[i], ee = e[0] * e[0] + e[1] * e[1];
        const double t = ee > 0.0 ? fmin(1.0, fmax(0.0, -(a[0] * e[0] + a[1] * e[1]) / ee)) : 0.0;
        best = fmin(best, hypot(a[0] + t * e[0], a[1] + t * e[1]));
    }
    return best;
}

/* Van Oosterom-Strackee over the signed fan of triangles (apex p, v_i, v_i+1),
 * det[a,b,c] = -h cross2(v_i - p, e_i); the apex p is the foot point (nadir) or
 * vertex 0; *err = first-order rounding bound.  With the nadir apex the
 * denominator is |h| (lb lc + b.c + |h| (lb + lc)), and
 * lb lc + b.c = |b x c|^2 / (lb lc - b.c) when b.c < 0, so that edges passing
 * close to the foot point cancel nothing. */
static double vos_fan(const struct geom *g, int nadir, double *err)
{
    const double hh = fabs(g->h), zero[2] = {0.0, 0.0};
    double a[3], sum = 0.0;
    from_obs(g, nadir ? zero : g->a[0], a);
    const double la = sqrt(dot3(a, a));
    *err = 0.0;
    for (int i = 0; i < g->n; ++i) {
        const int j = (i + 1) % g->n;
        const double *u = nadir ? shorter(g->a[i], g->a[j]) : shorter(g->q[i], g->q[j]), *e = g->e[i];
        double b[3], c[3];
        from_obs(g, g->a[i], b);
        from_obs(g, g->a[j], c);
        const double lb = sqrt(dot3(b, b)), lc = sqrt(dot3(c, c)), bc = dot3(b, c), cr = cross2(u, e);
        const double ue = hypot(u[0], u[1]) * hypot(e[0], e[1]);
        double num, den, snum, sden;
        if (nadir) {
            num = g->h > 0.0 ? -cr : cr;
            den = (bc >= 0.0 ? lb * lc + bc : (hh * hh * (e[0] * e[0] + e[1] * e[1]) + cr * cr) / (lb * lc - bc)) +
                  hh * (lb + lc);
            snum = ue;
            sden = den;
        } else {
            num = -g->h * cr;
            den = la * lb * lc + dot3(a, b) * lc + dot3(a, c) * lb + bc * la;
            snum = hh * ue;
            sden = la * lb * lc + fabs(dot3(a, b)) * lc + fabs(dot3(a, c)) * lb + fabs(bc) * la;
        }
        const double q2 = num * num + den * den;
        sum += 2.0 * atan2(num, den);
        if (q2 > 0.0) *err += 8.0 * DBL_EPSILON * (fabs(num) * sden + fabs(den) * snum) / q2;
    }
    return g->h > 0.0 ? -sum : sum;
}

/* The better conditioned of the fans from the foot point and from vertex 0. */
static double geom_solid_angle(const struct geom *g)
{
    if (g->h == 0.0) return 0.0;
    double e0, e1;
    const double o0 = vos_fan(g, 1, &e0), o1 = vos_fan(g, 0, &e1);
    return e0 <= e1 ? o0 : o1;
}

/* ---- shared integration state ------------------------------------------- */

struct arc {
    double wa[3], wp[3]; /* start direction, unit tangent along the arc (world)  */
    double m[3];         /* unit normal of the arc's great circle (world)       */
    double theta, cm;    /* arc length; c . m (computed without cancellation)   */
    double ia, ib;       /* 1/r(theta) = ia cos(theta) + ib sin(theta)          */
};

struct work {
    const struct geom *g;
    int lmax, nc, nv, grad;
    double tol_c, tol_g; /* absolute tolerances, coefficients and gradient            */
    double span;         /* total parameter measure (arc length or |2 x area|)        */
    double err;          /* accumulated error estimate of the coefficients            */
    double *acc, *stack, *y, *dy;
    /* polar path */
    double c[3], orient; /* centre direction (world); -sign(h)                        */
    int nin;
    double xin[NIN_MAX], win[NIN_MAX], xo[NOUT], wo[NOUT];
    /* area path */
    double xt[NTRI], wt[NTRI];
};

/* Compare fine = sum of nparts blocks of nv with coarse; add fine to acc if accepted.
 * resolved: the panel is small enough against the integrand's scale that the rule
 * has converged; further splitting would only chase rounding noise. */
static int settle(struct work *w, const double *coarse, const double *parts, int nparts,
                  double frac, int resolved)
{
    double ec = 0.0, sc = 0.0, eg = 0.0, sg = 0.0;
    for (int k = 0; k < w->nv; ++k) {
        double s = 0.0, mag = 0.0;
        for (int j = 0; j < nparts; ++j) {
            s += parts[j * w->nv + k];
            mag += fabs(parts[j * w->nv + k]);
        }
        const double e = fabs(s - coarse[k]);
        if (k < w->nc) {
            ec = fmax(ec, e);
            sc = fmax(sc, mag);
        } else {
            eg = fmax(eg, e);
            sg = fmax(sg, mag);
        }
    }
    const int ok = (ec <= fmax(w->tol_c * frac, ROUND_FLOOR * sc) &&
                    eg <= fmax(w->tol_g * frac, ROUND_FLOOR * sg)) || resolved;
    if (ok) {
        for (int j = 0; j < nparts; ++j)
            for (int k = 0; k < w->nv; ++k) w->acc[k] += parts[j * w->nv + k];
        w->err += ec;
    }
    return ok;
}

static void axpy(int n, double a, const double *x, double *y)
{
    for (int k = 0; k < n; ++k) y[k] += a * x[k];
}

/* ---- polar path ---------------------------------------------------------- */

/* Outer node theta of an arc with weight wgt: the spherical triangle (c, w(theta))
 * contributes (c.m)/sin^2(rho_e) int_0^rho_e Y sin(rho) drho, rho_e = angle(c, w);
 * the gradient gets m Y(w) / r(theta). */
static void polar_node(struct work *w, const struct arc *a, double th, double wgt, double *out)
{
    const int nc = w->nc;
    const double ct = cos(th), st = sin(th);
    double om[3];
    for (int k = 0; k < 3; ++k) om[k] = ct * a->wa[k] + st * a->wp[k];
    if (a->cm != 0.0) {
        const double cr = dot3(w->c, om);
        double t[3];
        for (int k = 0; k < 3; ++k) t[k] = om[k] - cr * w->c[k];
        const double sr = sqrt(dot3(t, t)), re = atan2(sr, cr);
        if (sr > 0.0)
            for (int k = 0; k < 3; ++k) t[k] /= sr;
        const double base = wgt * a->cm * w->orient;
        for (int i = 0; i < w->nin; ++i) {
            const double rho = w->xin[i] * re, sp = sin(rho), cp = cos(rho);
            shl__sh_eval(w->lmax, cp * w->c[0] + sp * t[0], cp * w->c[1] + sp * t[1], cp * w->c[2] + sp * t[2], w->y);
            /* re sin(rho) / sin^2(rho_e) -> s as rho_e -> 0 */
            const double fac = sr > 1e-150 ? re * sp / (sr * sr) : w->xin[i];
            axpy(nc, base * w->win[i] * fac, w->y, out);
        }
    }
    if (w->grad) {
        shl__sh_eval(w->lmax, om[0], om[1], om[2], w->y);
        const double s = wgt * w->orient * (a->ia * ct + a->ib * st);
        for (int d = 0; d < 3; ++d) axpy(nc, s * a->m[d], w->y, out + nc + d * nc);
    }
}

static void polar_panel(struct work *w, const struct arc *a, double t0, double t1, double *out)
{
    memset(out, 0, sizeof *out * (size_t)w->nv);
    for (int j = 0; j < NOUT; ++j) polar_node(w, a, t0 + (t1 - t0) * w->xo[j], (t1 - t0) * w->wo[j], out);
}

static void polar_adapt(struct work *w, const struct arc *a, double t0, double t1,
                        const double *coarse, int depth)
{
    double *l = w->stack + (size_t)depth * 2 * w->nv, *r = l + w->nv;
    const double mid = 0.5 * (t0 + t1);
    polar_panel(w, a, t0, mid, l);
    polar_panel(w, a, mid, t1, r);
    /* the outer integrand is analytic, varying on the scale 1/(lmax+1) */
    if (settle(w, coarse, l, 2, (t1 - t0) / w->span,
               depth + 1 >= MAX_DEPTH || (t1 - t0) * (w->lmax + 1) < 1e-3))
        return;
    polar_adapt(w, a, t0, mid, l, depth + 1);
    polar_adapt(w, a, mid, t1, r, depth + 1);
}

/* Largest angle between the direction to the plane point p (relative to the foot
 * point) and the directions to the vertices. */
static double centre_spread(const struct geom *g, const double p[2])
{
    double c[3], rmax = 0.0;
    from_obs(g, p, c);
    for (int i = 0; i < g->n; ++i) {
        double a[3], x[3];
        from_obs(g, g->a[i], a);
        cross3(c, a, x);
        rmax = fmax(rmax, atan2(sqrt(dot3(x, x)), dot3(c, a)));
    }
    return rmax;
}

static int run_polar(struct work *w, double omega)
{
    const struct geom *g = w->g;
    const int n = g->n;
    /* Centre: the nadir if the foot point is inside, else the centroid unless a
     * vertex is nearly antipodal to it (the fan then cancels less than from the nadir). */
    double cen[2] = {0.0, 0.0}, cf[2] = {0.0, 0.0}, area2 = 0.0, rmax = 0.0;
    for (int i = 0; i < n; ++i) {
        const double *p = g->q[i], *q = g->q[(i + 1) % n], cr = cross2(p, q);
        area2 += cr;
        cen[0] += (p[0] + q[0]) * cr;
        cen[1] += (p[1] + q[1]) * cr;
    }
    cen[0] /= 3.0 * area2; /* relative to vertex 0 */
    cen[1] /= 3.0 * area2;
    int nadir = foot_inside(g);
    if (!nadir) {
        cf[0] = cen[0] + g->a[0][0]; /* relative to the foot point */
        cf[1] = cen[1] + g->a[0][1];
        rmax = centre_spread(g, cf);
        nadir = rmax > 0.8 * M_PI;
    }
    if (nadir) {
        cf[0] = cf[1] = 0.0;
        rmax = centre_spread(g, cf);
        for (int k = 0; k < 3; ++k) w->c[k] = g->h > 0.0 ? -g->ax[2][k] : g->ax[2][k];
    } else {
        const double d[3] = {cen[0] * g->ax[0][0] + cen[1] * g->ax[1][0], cen[0] * g->ax[0][1] + cen[1] * g->ax[1][1],
                             cen[0] * g->ax[0][2] + cen[1] * g->ax[1][2]};
        unit_from_obs(g, 0, d, w->c);
    }
    double cv[3];
    from_obs(g, cf, cv);
    const double lc = sqrt(dot3(cv, cv));
    /* Inner rule: Y sin(rho) along a great circle is a trigonometric polynomial of
     * degree lmax+1; the arcs stay within rmax of c when rmax <= pi/2, within pi otherwise. */
    const double rb = rmax <= 0.5 * M_PI ? rmax : M_PI;
    w->nin = 10 + (int)ceil(0.5 * (w->lmax + 1) * rb); /* <= 59 < NIN_MAX */
    gauss_legendre(w->nin, w->xin, w->win);
    gauss_legendre(NOUT, w->xo, w->wo);
    w->orient = g->h > 0.0 ? -1.0 : 1.0;

    struct arc *arcs = malloc(sizeof *arcs * (size_t)n);
    if (!arcs) return REF_ENOMEM;
    int na = 0;
    double span = 0.0, bs = 0.0;
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        const double *e = g->e[i], *u = shorter(g->a[i], g->a[j]), zero[3] = {0.0, 0.0, 0.0};
        double A[3], B[3], axe[3];
        from_obs(g, g->a[i], A);
        from_obs(g, g->a[j], B);
        axe[0] = g->h * e[1]; /* A x E */
        axe[1] = -g->h * e[0];
        axe[2] = cross2(u, e);
        const double s = sqrt(dot3(axe, axe));
        if (!(s > 0.0)) continue; /* zero-length edge or x on its line: no arc */
        struct arc *a = &arcs[na++];
        const double la = sqrt(dot3(A, A)), ae = A[0] * e[0] + A[1] * e[1];
        for (int k = 0; k < 3; ++k) axe[k] /= s;
        to_world(g, axe, a->m);
        unit_from_obs(g, i, zero, a->wa);
        cross3(a->m, a->wa, a->wp);
        a->theta = atan2(s, dot3(A, B));
        /* c.m = h cross2(centre - v_i, e_i) / (|centre - x| |A x E|) */
        const double ci[2] = {cen[0] - g->q[i][0], cen[1] - g->q[i][1]}, cj[2] = {cen[0] - g->q[j][0], cen[1] - g->q[j][1]};
        const double *cq = nadir ? u : shorter(ci, cj);
        a->cm = (nadir ? -g->h : g->h) * cross2(cq, e) / (lc * s);
        a->ia = 1.0 / la;
        a->ib = -ae / (la * s);
        span += a->theta;
        bs += a->ia * sin(a->theta) + a->ib * (1.0 - cos(a->theta));
    }
    w->span = span;
    w->tol_c = REL_TOL * omega;
    w->tol_g = REL_TOL * 0.5 / sqrt(M_PI) * bs;
    double *coarse = w->stack + (size_t)MAX_DEPTH * 2 * w->nv;
    for (int i = 0; i < na; ++i) {
        polar_panel(w, &arcs[i], 0.0, arcs[i].theta, coarse);
        polar_adapt(w, &arcs[i], 0.0, arcs[i].theta, coarse, 0);
    }
    free(arcs);
    return 0;
}

/* ---- area path ------------------------------------------------------------ */

/* Integrand Y(s) |h| / r^3 at the point vertex 0 + d (world offset) with weight jw,
 * and its x-gradient. */
static void area_node(struct work *w, const double d[3], double jw, double *out)
{
    const struct geom *g = w->g;
    const int nc = w->nc;
    double rv[3], s[3];
    obs_vector(g, 0, d, rv);
    const double r2 = dot3(rv, rv), r = sqrt(r2), hh = fabs(g->h);
    for (int k = 0; k < 3; ++k) s[k] = rv[k] / r;
    const double wt = jw * hh / (r2 * r);
    if (!w->grad) {
        shl__sh_eval(w->lmax, s[0], s[1], s[2], w->y);
        axpy(nc, wt, w->y, out);
        return;
    }
    ref_sh_eval_grad(w->lmax, s, w->y, w->dy);
    axpy(nc, wt, w->y, out);
    /* d/dx = -d/dR of Y(R/r) |n.R| r^-3:  -(grad_t Y / r) wt - Y jw (sign(n.R) n / r^3 - 3 |h| s / r^4) */
    const double sz = g->h > 0.0 ? -1.0 : 1.0, *nz = g->ax[2];
    double cn[3];
    for (int k = 0; k < 3; ++k) cn[k] = jw * (sz * nz[k] / (r2 * r) - 3.0 * hh * s[k] / (r2 * r2));
    const double *gx = w->dy, *gy = gx + nc, *gz = gy + nc;
    double *o = out + nc;
    for (int k = 0; k < nc; ++k) {
        const double sd = s[0] * gx[k] + s[1] * gy[k] + s[2] * gz[k];
        o[k] -= wt * (gx[k] - s[0] * sd) / r + w->y[k] * cn[0];
        o[nc + k] -= wt * (gy[k] - s[1] * sd) / r + w->y[k] * cn[1];
        o[2 * nc + k] -= wt * (gz[k] - s[2] * sd) / r + w->y[k] * cn[2];
    }
}

/* Twice the signed area of the triangle p (world offsets), relative to the normal. */
static double tri_area2(const struct geom *g, const double p[3][3])
{
    double d1[3], d2[3], c[3];
    for (int k = 0; k < 3; ++k) {
        d1[k] = p[1][k] - p[0][k];
        d2[k] = p[2][k] - p[1][k];
    }
    cross3(d1, d2, c);
    return dot3(c, g->ax[2]);
}

/* Collapsed (Duffy) product rule on the triangle p: p0 + u (p1-p0) + u v (p2-p1). */
static void area_tri(struct work *w, const double p[3][3], double *out)
{
    const double cr = tri_area2(w->g, p);
    memset(out, 0, sizeof *out * (size_t)w->nv);
    for (int i = 0; i < NTRI; ++i) {
        const double u = w->xt[i];
        for (int j = 0; j < NTRI; ++j) {
            const double v = w->xt[j];
            double d[3];
            for (int k = 0; k < 3; ++k) d[k] = p[0][k] + u * ((p[1][k] - p[0][k]) + v * (p[2][k] - p[1][k]));
            area_node(w, d, u * cr * w->wt[i] * w->wt[j], out);
        }
    }
}

/* The rule has converged on p once x is about 20 circumradii away: the integrand's
 * nearest singularity (x itself) is then far outside the triangle. */
static int tri_resolved(const struct geom *g, const double p[3][3])
{
    double cen[3], rad = 0.0;
    for (int c = 0; c < 3; ++c) cen[c] = (p[0][c] + p[1][c] + p[2][c]) / 3.0;
    for (int k = 0; k < 3; ++k) {
        const double d[3] = {p[k][0] - cen[0], p[k][1] - cen[1], p[k][2] - cen[2]};
        rad = fmax(rad, sqrt(dot3(d, d)));
    }
    for (int c = 0; c < 3; ++c) cen[c] += g->v[c] - g->x[c];
    return 20.0 * rad < sqrt(dot3(cen, cen));
}

static void area_adapt(struct work *w, const double p[3][3], const double *coarse, int depth)
{
    double m[3][3], ch[4][3][3];
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) m[k][c] = 0.5 * (p[k][c] + p[(k + 1) % 3][c]);
    /* corners and the middle triangle, all with the parent's orientation */
    const double *sets[4][3] = {{p[0], m[0], m[2]}, {m[0], p[1], m[1]}, {m[2], m[1], p[2]}, {m[1], m[2], m[0]}};
    double *parts = w->stack + (size_t)depth * 4 * w->nv;
    for (int j = 0; j < 4; ++j) {
        for (int k = 0; k < 3; ++k) memcpy(ch[j][k], sets[j][k], sizeof ch[j][k]);
        area_tri(w, (const double(*)[3])ch[j], parts + (size_t)j * w->nv);
    }
    if (settle(w, coarse, parts, 4, fabs(tri_area2(w->g, p)) / w->span,
               depth + 1 >= MAX_DEPTH || tri_resolved(w->g, p)))
        return;
    for (int j = 0; j < 4; ++j) area_adapt(w, (const double(*)[3])ch[j], parts + (size_t)j * w->nv, depth + 1);
}

/* Triangle i of the fan from vertex 0, as world offsets from vertex 0. */
static void fan_tri(const struct geom *g, int i, double t[3][3])
{
    for (int k = 0; k < 3; ++k) {
        t[0][k] = 0.0;
        t[1][k] = g->v[3 * i + k] - g->v[k];
        t[2][k] = g->v[3 * (i + 1) + k] - g->v[k];
    }
}

static int run_area(struct work *w, double omega)
{
    const struct geom *g = w->g;
    double t[3][3], *coarse = w->stack + (size_t)MAX_DEPTH * 4 * w->nv;
    gauss_legendre(NTRI, w->xt, w->wt);
    w->span = 0.0;
    for (int i = 1; i + 1 < g->n; ++i) {
        fan_tri(g, i, t);
        w->span += fabs(tri_area2(g, (const double(*)[3])t));
    }
    w->tol_c = REL_TOL * omega;
    w->tol_g = REL_TOL * 0.5 / sqrt(M_PI) * 3.0 * omega / hypot(g->h, foot_distance(g));
    for (int i = 1; i + 1 < g->n; ++i) {
        fan_tri(g, i, t);
        if (tri_area2(g, (const double(*)[3])t) == 0.0) continue;
        area_tri(w, (const double(*)[3])t, coarse);
        area_adapt(w, (const double(*)[3])t, coarse, 0);
    }
    return 0;
}

/* ---- entry points ----------------------------------------------------------- */

static int all_finite(const double *v, int count)
{
    for (int i = 0; i < count; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

int ref_polygon_sh_method(int method, int lmax, const double x[3], const double *verts, int n,
                          double *coeffs, double *grad, double *err_est)
{
    if (!x || !verts || !coeffs || n < 3 || lmax < 0 || lmax > SHL_LMAX_MAX ||
        method < REF_AUTO || method > REF_AREA || !all_finite(x, 3) || !all_finite(verts, 3 * n))
        return REF_EARG;
    struct geom g;
    g.a = malloc(sizeof *g.a * 3 * (size_t)n);
    if (!g.a) return REF_ENOMEM;
    int rc = geom_init(&g, x, verts, n);
    const int nc = (lmax + 1) * (lmax + 1);
    if (rc != 0 || g.h == 0.0) { /* degenerate polygon, or x in its plane: no solid angle */
        if (rc == 0 && grad) {
            rc = REF_EINPLANE;
        } else if (rc == 0) {
            memset(coeffs, 0, sizeof *coeffs * (size_t)nc);
            if (err_est) *err_est = 0.0;
        }
        free(g.a);
        return rc;
    }
    if (method == REF_AUTO) {
        double diam = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = i + 1; j < n; ++j)
                diam = fmax(diam, hypot(g.q[i][0] - g.q[j][0], g.q[i][1] - g.q[j][1]));
        method = diam < 0.25 * hypot(g.h, foot_distance(&g)) ? REF_AREA : REF_POLAR;
    }
    struct work *w = calloc(1, sizeof *w);
    if (!w) {
        free(g.a);
        return REF_ENOMEM;
    }
    w->g = &g;
    w->lmax = lmax;
    w->nc = nc;
    w->grad = grad != NULL;
    w->nv = grad ? 4 * nc : nc;
    const size_t levels = (size_t)(MAX_DEPTH + 1) * (method == REF_AREA ? 4 : 2);
    w->acc = calloc((size_t)w->nv, sizeof *w->acc);
    w->stack = malloc(sizeof *w->stack * levels * (size_t)w->nv);
    w->y = malloc(sizeof *w->y * (size_t)nc);
    w->dy = malloc(sizeof *w->dy * 3 * (size_t)nc);
    rc = REF_ENOMEM;
    if (w->acc && w->stack && w->y && w->dy) {
        const double omega = geom_solid_angle(&g);
        rc = method == REF_AREA ? run_area(w, omega) : run_polar(w, omega);
    }
    if (rc == 0) {
        memcpy(coeffs, w->acc, sizeof *coeffs * (size_t)nc);
        if (grad) memcpy(grad, w->acc + nc, sizeof *grad * 3 * (size_t)nc);
        if (err_est) *err_est = w->err;
    }
    free(w->acc);
    free(w->stack);
    free(w->y);
    free(w->dy);
    free(w);
    free(g.a);
    return rc;
}

int ref_polygon_sh(int lmax, const double x[3], const double *verts, int n,
                   double *coeffs, double *err_est)
{
    return ref_polygon_sh_method(REF_AUTO, lmax, x, verts, n, coeffs, NULL, err_est);
}

int ref_polygon_sh_grad(int lmax, const double x[3], const double *verts, int n,
                        double *coeffs, double *grad, double *err_est)
{
    if (!grad) return REF_EARG;
    return ref_polygon_sh_method(REF_AUTO, lmax, x, verts, n, coeffs, grad, err_est);
}

double ref_polygon_solid_angle(const double x[3], const double *verts, int n)
{
    if (!x || !verts || n < 3 || !all_finite(x, 3) || !all_finite(verts, 3 * n)) return NAN;
    struct geom g;
    g.a = malloc(sizeof *g.a * 3 * (size_t)n);
    if (!g.a) return NAN;
    const double om = geom_init(&g, x, verts, n) == 0 ? geom_solid_angle(&g) : NAN;
    free(g.a);
    return om;
}
