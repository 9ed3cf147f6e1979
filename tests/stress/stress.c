/* make stress: N random polygons and spheres (default 10^7) over lmax 0..30, in
 * double and float, a large share of them near-degenerate:
 *   polygons: generic; shading point within 1e-9 (or a few ulps) of the light's
 *   plane; an edge of length 1e-9 .. 1e-15 (a near-repeated vertex); an edge
 *   whose great circle contains, or whose plane is normal to, a lobe direction
 *   of the shared table (shl__zh_dir); tiny and huge polygons; the point
 *   1e-9 .. 1e-15 off an edge or a vertex;
 *   spheres: generic; tiny; tangent from outside and inside (gaps 1e-3 .. 1e-14
 *   of the radius); inside; distant.
 * Every case runs shl_polygon / shl_polygon_f (resp. shl_sphere / shl_sphere_f)
 * and, one case in four, the gradient versions; every output is checked for
 * NaN / infinity (the count must be 0).  Two cheap proxies rank the cases:
 *   P1 (double): |L_00 / K_0 - Omega| and the excess of |L_lm| / K_l over Omega
 *       (Omega: ref_polygon_solid_angle, resp. the cap's 2 pi (1 - cos a)), divided for
 *       polygons by the fuzz targets' slack model Omega + 300 eps P + 8 eps S G (P the
 *       angular perimeter, G = sum_e gamma_e / d_e, S the largest coordinate), for
 *       spheres by Omega;
 *   P2 (float): max |L_float - L_double| on the float-rounded input, divided by the
 *       float slack model K_lmax (1e-4 Omega + 64 (lmax+1) eps_f P + 8 eps S G), for
 *       spheres by K_0 Omega;
 * the 50 worst by each proxy, for polygons and for spheres (200 cases), are then
 * evaluated against the quadrature references (ref_polygon_sh of tests/ref_quad.c,
 * capref_sphere of tests/capref.c) and their errors printed as max |err| / Omega.
 *   usage: stress [N] [threads]                            (case i is reproducible from i) */
#include "capref.h"
#include "geom.h"
#include "ref_quad.h"
#include "shlight.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX), MAXV = 8, TOPK = 50, NPCAT = 7, NSCAT = 5, MAXT = 64 };

static const char *const pcat_name[NPCAT] = {"generic", "near plane", "short edge", "lobe on edge plane",
                                             "tiny / huge", "near edge", "near vertex"};
static const char *const scat_name[NSCAT] = {"generic", "tiny", "tangent", "inside", "distant"};

typedef struct {
    long index;
    int sphere, cat, lmax, n;
    double x[3], v[3 * MAXV], c[3], r;        /* double input */
    double xf[3], vf[3 * MAXV], cf[3], rf;    /* float-rounded input, as double */
    double p1, p2;
} cand;

/* the TOPK highest-scoring cases */
typedef struct {
    cand item[TOPK];
    double score[TOPK];
    int count;
} worst;

static void worst_add(worst *w, const cand *c, double score)
{
    if (!(score > 0.0) && !(score != score)) return;
    if (score != score) score = INFINITY; /* NaN proxy: most suspicious */
    if (w->count < TOPK) {
        w->item[w->count] = *c;
        w->score[w->count++] = score;
        return;
    }
    int lo = 0;
    for (int i = 1; i < TOPK; ++i)
        if (w->score[i] < w->score[lo]) lo = i;
    if (score > w->score[lo]) {
        w->item[lo] = *c;
        w->score[lo] = score;
    }
}

typedef struct {
    long begin, end;
    worst poly_p1, poly_p2, sph_p1, sph_p2;
    long cases[2][NPCAT], nonfinite[2][4]; /* [poly/sphere][coef d, coef f, grad d, grad f] */
    double max_p1[2], max_p2[2];
    long plane_zone, ill_posed[2], above_hemisphere[2];
    long lmax_count[SHL_LMAX_MAX + 1];
} worker;

static shl_ctx *ctxs[SHL_LMAX_MAX + 1];

/* v rounded to float.  Through a volatile: GCC 12.2 -O2 on x86-64 vectorizes a short loop of
 * double -> float -> double round trips into plain copies of the doubles (SLP; see
 * tests/fuzz/crashes/gcc12-slp-float-roundtrip.c). */
static float to_float(double v)
{
    volatile float f = (float)v;
    return f;
}

static double kl(int l) { return sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); }

static void rng_seed(rng_t *r, long i) { r->s = 0x5348494c49474854ull ^ ((uint64_t)i * 0x9E3779B97F4A7C15ull); }

/* ---- polygon cases ------------------------------------------------------- */
static void poly_case(rng_t *r, int cat, int lmax, cand *c)
{
    double center[3], nrm[3], u[3], w[3];
    for (int k = 0; k < 3; ++k) center[k] = rng_range(r, -2.0, 2.0);
    rng_unit_vector(r, nrm);
    plane_basis(nrm, u, w);
    const int kind = (int)(rng_uniform(r) * 3);
    c->n = kind == 0 ? 3 : kind == 1 ? 4 : 6;
    double size = rng_range(r, 0.3, 2.0);
    if (cat == 4) size = rng_uniform(r) < 0.5 ? pow(10.0, rng_range(r, -9.0, -3.0)) : pow(10.0, rng_range(r, 3.0, 8.0));
    random_polygon(r, c->n, kind == 2, center, nrm, size, c->v);
    double off[3];
    rng_unit_vector(r, off);
    const double dist = cat != 4 ? rng_range(r, 0.5, 4.0) : size < 1.0 ? rng_range(r, 1.0, 10.0) : rng_range(r, 0.5, 2.0);
    const double side = off[0] * nrm[0] + off[1] * nrm[1] + off[2] * nrm[2];
    if (fabs(side) < 0.05)
        for (int k = 0; k < 3; ++k) off[k] += (side < 0 ? -0.1 : 0.1) * nrm[k];
    for (int k = 0; k < 3; ++k) c->x[k] = center[k] + dist * off[k];
    switch (cat) {
    case 1: { /* within 1e-9 (relative to the size) or a few ulps of the plane; foot inside or outside */
        const double a = rng_range(r, -1.5, 1.5) * size, b = rng_range(r, -1.5, 1.5) * size;
        const double h = rng_uniform(r) < 0.5 ? size * pow(10.0, rng_range(r, -16.0, -9.0))
                                              : ldexp(floor(rng_range(r, 1.0, 64.0)), -52) * size;
        const double sg = rng_uniform(r) < 0.5 ? -1.0 : 1.0;
        for (int k = 0; k < 3; ++k) c->x[k] = center[k] + a * u[k] + b * w[k] + sg * h * nrm[k];
        break;
    }
    case 2: { /* an edge of length 1e-9 .. 1e-15 of the size: insert a near-copy of a vertex */
        const int i = (int)(rng_uniform(r) * c->n);
        for (int j = c->n; j > i + 1; --j) memcpy(c->v + 3 * j, c->v + 3 * (j - 1), sizeof(double) * 3);
        const double e = size * pow(10.0, rng_range(r, -15.0, -9.0)), t = rng_range(r, 0.0, 2.0 * M_PI);
        for (int k = 0; k < 3; ++k) c->v[3 * (i + 1) + k] = c->v[3 * i + k] + e * (cos(t) * u[k] + sin(t) * w[k]);
        c->n += 1;
        break;
    }
    case 3: { /* an edge whose great circle contains a lobe, or whose plane is normal to it */
        const double *d = shl__zh_dir[(int)(rng_uniform(r) * (2 * lmax + 1))];
        double a[3], b[3];
        plane_basis(d, a, b);
        const double s0 = rng_range(r, 1.0, 3.0), s1 = rng_range(r, 1.0, 3.0), s2 = rng_range(r, 1.0, 3.0);
        const double p = rng_range(r, 0.1, 0.6), q = rng_range(r, 0.1, 0.6);
        c->n = 3;
        for (int k = 0; k < 3; ++k) { /* edge 0-1 in a plane containing d */
            c->v[k] = s0 * (d[k] + p * a[k]);
            c->v[3 + k] = s1 * (d[k] - q * a[k]);
            c->v[6 + k] = s2 * (d[k] + 0.5 * b[k]);
        }
        if (rng_uniform(r) < 0.5)
            for (int k = 0; k < 3; ++k) { /* edge 0-1 in the plane normal to d */
                c->v[k] = s0 * a[k];
                c->v[3 + k] = s1 * (0.6 * a[k] + 0.8 * b[k]);
                c->v[6 + k] = s2 * (0.3 * a[k] + 0.3 * b[k] + 0.9 * d[k]);
            }
        for (int k = 0; k < 3; ++k) c->x[k] = 0.0; /* the lobe frame is centred on x */
        if (rng_uniform(r) < 0.5) { /* translate: alignment then holds to rounding */
            for (int k = 0; k < 3; ++k) c->x[k] = rng_range(r, -1.0, 1.0);
            for (int i = 0; i < 3; ++i)
                for (int k = 0; k < 3; ++k) c->v[3 * i + k] += c->x[k];
        }
        break;
    }
    case 5: { /* 1e-9 .. 1e-15 (relative) off an edge, off the plane */
        const int i = (int)(rng_uniform(r) * c->n), j = (i + 1) % c->n;
        const double t = rng_range(r, 0.05, 0.95), e = size * pow(10.0, rng_range(r, -15.0, -9.0));
        double dir[3];
        rng_unit_vector(r, dir);
        for (int k = 0; k < 3; ++k) c->x[k] = c->v[3 * i + k] + t * (c->v[3 * j + k] - c->v[3 * i + k]) + e * dir[k];
        break;
    }
    case 6: { /* 1e-9 .. 1e-15 off a vertex */
        const int i = (int)(rng_uniform(r) * c->n);
        const double e = size * pow(10.0, rng_range(r, -15.0, -9.0));
        double dir[3];
        rng_unit_vector(r, dir);
        for (int k = 0; k < 3; ++k) c->x[k] = c->v[3 * i + k] + e * dir[k];
        break;
    }
    default: break;
    }
}

/* ---- sphere cases -------------------------------------------------------- */
static void sphere_case(rng_t *r, int cat, cand *c)
{
    double dir[3];
    rng_unit_vector(r, dir);
    for (int k = 0; k < 3; ++k) c->x[k] = rng_range(r, -1.0, 1.0);
    double d = rng_range(r, 0.5, 5.0), rad = d * rng_range(r, 0.02, 0.98);
    switch (cat) {
    case 1: rad = d * pow(10.0, rng_range(r, -12.0, -6.0)); break;
    case 2: rad = d / (1.0 + (rng_uniform(r) < 0.5 ? -1.0 : 1.0) * pow(10.0, rng_range(r, -14.0, -3.0))); break;
    case 3: rad = d * rng_range(r, 1.0, 3.0); break;
    case 4: d = pow(10.0, rng_range(r, 3.0, 8.0)), rad = rng_range(r, 0.1, 10.0); break;
    default: break;
    }
    for (int k = 0; k < 3; ++k) c->c[k] = c->x[k] + d * dir[k];
    c->r = rad;
    c->n = 0;
}

/* Long-double geometry of a polygon seen from x (any polygon): the angular
 * perimeter P = sum_e gamma_e, G = sum_e gamma_e / d_e (d_e: distance from x to
 * edge e's line; |grad L_lm| <= K_l G for simple planar polygons), the height of x
 * above the Newell plane and rmax = max |v_i - x|. */
typedef struct {
    double perim, gsum, height, rmax, scale, nonplanar;
} pgeom;

static void poly_geom(const double x[3], const double *v, int n, pgeom *G)
{
    long double r[MAXV][3], nrm[3] = {0, 0, 0};
    memset(G, 0, sizeof *G);
    for (int k = 0; k < 3; ++k) G->scale = fmax(G->scale, fabs(x[k]));
    for (int i = 0; i < n; ++i) {
        long double d2 = 0.0L;
        for (int k = 0; k < 3; ++k) {
            r[i][k] = (long double)v[3 * i + k] - x[k];
            d2 += r[i][k] * r[i][k];
            G->scale = fmax(G->scale, fabs(v[3 * i + k]));
        }
        G->rmax = fmax(G->rmax, (double)sqrtl(d2));
    }
    for (int i = 1; i + 1 < n; ++i) {
        long double e[3], f[3];
        for (int k = 0; k < 3; ++k) e[k] = (long double)v[3 * i + k] - v[k], f[k] = (long double)v[3 * i + 3 + k] - v[k];
        nrm[0] += e[1] * f[2] - e[2] * f[1];
        nrm[1] += e[2] * f[0] - e[0] * f[2];
        nrm[2] += e[0] * f[1] - e[1] * f[0];
    }
    const long double nl = sqrtl(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    G->height = nl > 0 ? (double)(fabsl(nrm[0] * r[0][0] + nrm[1] * r[0][1] + nrm[2] * r[0][2]) / nl) : 0.0;
    for (int i = 1; i < n && nl > 0; ++i) { /* the vertices' distances from the Newell plane through v_0 */
        long double dv = 0.0L;
        for (int k = 0; k < 3; ++k) dv += nrm[k] * ((long double)v[3 * i + k] - v[k]);
        G->nonplanar = fmax(G->nonplanar, (double)(fabsl(dv) / nl));
    }
    for (int e = 0; e < n; ++e) {
        const int f = (e + 1) % n;
        long double ed[3], c[3];
        for (int k = 0; k < 3; ++k) ed[k] = (long double)v[3 * f + k] - v[3 * e + k];
        const long double el = sqrtl(ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2]);
        if (el == 0.0L) continue;
        c[0] = r[e][1] * ed[2] - r[e][2] * ed[1];
        c[1] = r[e][2] * ed[0] - r[e][0] * ed[2];
        c[2] = r[e][0] * ed[1] - r[e][1] * ed[0];
        const long double cl = sqrtl(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        const long double gam = atan2l(cl, r[e][0] * r[f][0] + r[e][1] * r[f][1] + r[e][2] * r[f][2]);
        G->perim += (double)gam;
        G->gsum += cl > 0.0L ? (double)(gam * el / cl) : INFINITY;
    }
}

/* In the documented in-plane zone (height <= 8 ulps of the distances, which the library
 * computes with rounding: 10 ulps here): zeros expected. */
static int in_plane_zone(const pgeom *G) { return G->height <= 10.0 * DBL_EPSILON * G->rmax; }
/* Ill-posed: the vertices leave the polygon's plane by more than a tenth of the point's
 * height (rounding of a tilted polygon, in double or after rounding to float): the
 * solid angle of "the planar polygon" is then not defined to better than ~100%. */
static int ill_posed(const pgeom *G) { return G->nonplanar > 0.1 * G->height; }

static double cap_t(const double x[3], const double cen[3], double r)
{
    const long double v[3] = {(long double)cen[0] - x[0], (long double)cen[1] - x[1], (long double)cen[2] - x[2]};
    const long double d = sqrtl(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (d <= r) return 2.0;
    return (double)((long double)r * r / (d * (d + sqrtl((d - r) * (d + r)))));
}

static int finite_d(const double *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}
static int finite_f(const float *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static void *run(void *arg)
{
    worker *W = arg;
    static __thread double cd[NCMAX], cdf[NCMAX], gd[3 * NCMAX];
    static __thread float cf[NCMAX], gf[3 * NCMAX];
    for (long i = W->begin; i < W->end; ++i) {
        rng_t r;
        rng_seed(&r, i);
        cand c;
        memset(&c, 0, sizeof c);
        c.index = i;
        c.lmax = (int)(i % (SHL_LMAX_MAX + 1)); /* uniform over 0..30 */
        c.sphere = (i / (SHL_LMAX_MAX + 1)) % 4 == 3; /* a quarter spheres */
        const int nc = SHL_NCOEFFS(c.lmax), grads = (i / 7) % 4 == 0;
        const shl_ctx *ctx = ctxs[c.lmax];
        W->lmax_count[c.lmax]++;
        float xf[3], vf[3 * MAXV], cenf[3], rf;
        if (!c.sphere) {
            const double u = rng_uniform(&r);
            c.cat = u < 0.25 ? 0 : 1 + (int)((u - 0.25) / 0.75 * (NPCAT - 1));
            if (c.cat >= NPCAT) c.cat = NPCAT - 1;
            poly_case(&r, c.cat, c.lmax, &c);
            W->cases[0][c.cat]++;
            for (int k = 0; k < 3; ++k) c.xf[k] = xf[k] = to_float(c.x[k]);
            for (int k = 0; k < 3 * c.n; ++k) c.vf[k] = vf[k] = to_float(c.v[k]);
            int bad[4] = {0, 0, 0, 0};
            if (shl_polygon(ctx, c.x, c.v, c.n, cd) != SHL_OK) bad[0] = 1;
            else bad[0] = !finite_d(cd, nc);
            if (shl_polygon_f(ctx, xf, vf, c.n, cf) != SHL_OK) bad[1] = 1;
            else bad[1] = !finite_f(cf, nc);
            shl_polygon(ctx, c.xf, c.vf, c.n, cdf);
            if (grads) {
                double cc[NCMAX];
                float ccf[NCMAX];
                bad[2] = shl_polygon_grad(ctx, c.x, c.v, c.n, cc, gd) != SHL_OK || !finite_d(gd, 3 * nc);
                bad[3] = shl_polygon_grad_f(ctx, xf, vf, c.n, ccf, gf) != SHL_OK || !finite_f(gf, 3 * nc);
            }
            for (int k = 0; k < 4; ++k) W->nonfinite[0][k] += bad[k];
            const double om = ref_polygon_solid_angle(c.x, c.v, c.n), omf = ref_polygon_solid_angle(c.xf, c.vf, c.n);
            pgeom G, Gf;
            poly_geom(c.x, c.v, c.n, &G);
            poly_geom(c.xf, c.vf, c.n, &Gf);
            const int zone = in_plane_zone(&G) || ill_posed(&G), zone_f = in_plane_zone(&Gf) || ill_posed(&Gf);
            W->plane_zone += in_plane_zone(&G);
            W->ill_posed[0] += !in_plane_zone(&G) && ill_posed(&G);
            W->ill_posed[1] += !in_plane_zone(&Gf) && ill_posed(&Gf);
            /* a planar polygon subtends less than a hemisphere: L_00 / K_0 = omega <= 2 pi (well-posed inputs) */
            W->above_hemisphere[0] += !zone && cd[0] / kl(0) > 2.0 * M_PI * (1.0 + 1e-12);
            W->above_hemisphere[1] += !zone_f && cf[0] / kl(0) > 2.0 * M_PI * (1.0 + 1e-6);
            if (om > 0.0 && !zone) {
                /* relative to the slack model (Omega + the rounding of the boundary sums + conditioning) */
                const double md = om + 300.0 * DBL_EPSILON * G.perim + 8.0 * DBL_EPSILON * G.scale * G.gsum;
                double p1 = fabs(cd[0] / kl(0) - om) / md;
                for (int l = 1; l <= c.lmax; ++l)
                    for (int k = l * l; k < (l + 1) * (l + 1); ++k) p1 = fmax(p1, (fabs(cd[k]) / kl(l) - om) / md);
                c.p1 = p1;
                W->max_p1[0] = fmax(W->max_p1[0], p1);
                worst_add(&W->poly_p1, &c, p1);
            }
            if (omf > 0.0 && !zone_f) {
                double p2 = 0.0;
                for (int k = 0; k < nc; ++k) p2 = fmax(p2, fabs(cf[k] - cdf[k]));
                c.p2 = p2 / (kl(c.lmax) * (1e-4 * omf + 64.0 * (c.lmax + 1) * FLT_EPSILON * Gf.perim +
                                           8.0 * DBL_EPSILON * Gf.scale * Gf.gsum));
                W->max_p2[0] = fmax(W->max_p2[0], c.p2);
                worst_add(&W->poly_p2, &c, c.p2);
            }
        } else {
            c.cat = (int)(rng_uniform(&r) * NSCAT);
            sphere_case(&r, c.cat, &c);
            W->cases[1][c.cat]++;
            for (int k = 0; k < 3; ++k) c.xf[k] = xf[k] = to_float(c.x[k]), c.cf[k] = cenf[k] = to_float(c.c[k]);
            c.rf = rf = to_float(c.r);
            int bad[4] = {0, 0, 0, 0};
            bad[0] = shl_sphere(ctx, c.x, c.c, c.r, cd) != SHL_OK || !finite_d(cd, nc);
            bad[1] = shl_sphere_f(ctx, xf, cenf, rf, cf) != SHL_OK || !finite_f(cf, nc);
            shl_sphere(ctx, c.xf, c.cf, c.rf, cdf);
            if (grads) {
                double cc[NCMAX];
                float ccf[NCMAX];
                bad[2] = shl_sphere_grad(ctx, c.x, c.c, c.r, cc, gd) != SHL_OK || !finite_d(gd, 3 * nc);
                bad[3] = shl_sphere_grad_f(ctx, xf, cenf, rf, ccf, gf) != SHL_OK || !finite_f(gf, 3 * nc);
            }
            for (int k = 0; k < 4; ++k) W->nonfinite[1][k] += bad[k];
            const double om = 2.0 * M_PI * cap_t(c.x, c.c, c.r), omf = 2.0 * M_PI * cap_t(c.xf, c.cf, c.rf);
            double p1 = fabs(cd[0] / kl(0) - om) / om;
            for (int l = 1; l <= c.lmax; ++l)
                for (int k = l * l; k < (l + 1) * (l + 1); ++k) p1 = fmax(p1, fabs(cd[k]) / (kl(l) * om) - 1.0);
            c.p1 = p1;
            W->max_p1[1] = fmax(W->max_p1[1], p1);
            worst_add(&W->sph_p1, &c, p1);
            double p2 = 0.0;
            for (int k = 0; k < nc; ++k) p2 = fmax(p2, fabs(cf[k] - cdf[k]));
            c.p2 = p2 / (kl(0) * omf);
            W->max_p2[1] = fmax(W->max_p2[1], c.p2);
            worst_add(&W->sph_p2, &c, c.p2);
        }
    }
    return NULL;
}

/* ---- reference evaluation of the candidates ------------------------------ */
typedef struct {
    cand c;
    int from_p2;
    int ref_status;
    double err_d, err_f, omega, omega_f, cond_d; /* errors / Omega; cond_d: 4 eps S max|grad| / Omega */
    double model_d, model_f; /* error / (the fuzz targets' slack model) */
    int ill_d, ill_f;        /* input ill-posed (in-plane zone or not planar to within the height): not ranked */
    double model_d1, model_f1; /* the same over bands l >= 1 only (L_00 is the fan-based solid angle) */
    double perim;
} result;

static result *results;
static int nresults, next_result;
static pthread_mutex_t res_lock = PTHREAD_MUTEX_INITIALIZER;

static void evaluate(result *R)
{
    const cand *c = &R->c;
    const int lmax = c->lmax, nc = SHL_NCOEFFS(lmax);
    const shl_ctx *ctx = ctxs[lmax];
    double got[NCMAX], ref[NCMAX], g[3 * NCMAX];
    float gotf[NCMAX];
    const float xf[3] = {(float)c->xf[0], (float)c->xf[1], (float)c->xf[2]};
    if (!c->sphere) {
        float vf[3 * MAXV];
        for (int k = 0; k < 3 * c->n; ++k) vf[k] = (float)c->vf[k];
        R->omega = ref_polygon_solid_angle(c->x, c->v, c->n);
        R->omega_f = ref_polygon_solid_angle(c->xf, c->vf, c->n);
        pgeom G0;
        poly_geom(c->x, c->v, c->n, &G0);
        R->ill_d = in_plane_zone(&G0) || ill_posed(&G0);
        poly_geom(c->xf, c->vf, c->n, &G0);
        R->ill_f = in_plane_zone(&G0) || ill_posed(&G0);
        double err = 0.0, scale = 0.0, gmax = 0.0;
        shl_polygon(ctx, c->x, c->v, c->n, got);
        R->ref_status = ref_polygon_sh(lmax, c->x, c->v, c->n, ref, NULL);
        double err1 = 0.0;
        if (R->ref_status == 0 && R->omega > 0.0) {
            for (int k = 0; k < nc; ++k) err = fmax(err, fabs(got[k] - ref[k]));
            for (int k = 1; k < nc; ++k) err1 = fmax(err1, fabs(got[k] - ref[k]));
            R->err_d = err / R->omega;
            /* conditioning: 4 eps S max|grad L|, the gradient from the reference (the library's is 0
             * when it treats x as in the plane) */
            double rc[NCMAX];
            if (ref_polygon_sh_grad(lmax, c->x, c->v, c->n, rc, g, NULL) != 0) shl_polygon_grad(ctx, c->x, c->v, c->n, rc, g);
            for (int k = 0; k < 3 * nc; ++k) gmax = fmax(gmax, fabs(g[k]));
            for (int k = 0; k < 3; ++k) scale = fmax(scale, fabs(c->x[k]));
            for (int k = 0; k < 3 * c->n; ++k) scale = fmax(scale, fabs(c->v[k]));
            R->cond_d = 4.0 * DBL_EPSILON * scale * gmax / R->omega;
            pgeom G;
            poly_geom(c->x, c->v, c->n, &G);
            R->perim = G.perim;
            const double md = kl(lmax) * (1e-9 * R->omega + 300.0 * DBL_EPSILON * G.perim + 8.0 * DBL_EPSILON * G.scale * G.gsum);
            R->model_d = err / md;
            R->model_d1 = err1 / md;
        }
        shl_polygon_f(ctx, xf, vf, c->n, gotf);
        const int st = ref_polygon_sh(lmax, c->xf, c->vf, c->n, ref, NULL);
        if (st == 0 && R->omega_f > 0.0) {
            err = 0.0, err1 = 0.0;
            for (int k = 0; k < nc; ++k) err = fmax(err, fabs(gotf[k] - ref[k]));
            for (int k = 1; k < nc; ++k) err1 = fmax(err1, fabs(gotf[k] - ref[k]));
            R->err_f = err / R->omega_f;
            pgeom G;
            poly_geom(c->xf, c->vf, c->n, &G);
            const double mf = kl(lmax) * (1e-4 * R->omega_f + 64.0 * (lmax + 1) * FLT_EPSILON * G.perim +
                                          8.0 * DBL_EPSILON * G.scale * G.gsum);
            R->model_f = err / mf;
            R->model_f1 = err1 / mf;
        }
        if (st && !R->ref_status) R->ref_status = st;
    } else {
        const float cf[3] = {(float)c->cf[0], (float)c->cf[1], (float)c->cf[2]};
        R->omega = 2.0 * M_PI * cap_t(c->x, c->c, c->r);
        R->omega_f = 2.0 * M_PI * cap_t(c->xf, c->cf, c->rf);
        double err = 0.0;
        shl_sphere(ctx, c->x, c->c, c->r, got);
        capref_sphere(lmax, c->x, c->c, c->r, ref);
        for (int k = 0; k < nc; ++k) err = fmax(err, fabs(got[k] - ref[k]));
        R->err_d = err / R->omega;
        { /* conditioning of the cap under the rounding of c - x (fuzz_sphere.c) */
            long double d2 = 0.0L, S = 0.0L;
            for (int k = 0; k < 3; ++k) {
                d2 += ((long double)c->c[k] - c->x[k]) * ((long double)c->c[k] - c->x[k]);
                S = fmaxl(S, fmaxl(fabsl(c->c[k]), fabsl(c->x[k])));
            }
            const long double d = sqrtl(d2), s = c->r / d, cs = d > c->r ? sqrtl((d - c->r) * (d + c->r)) / d : 0.0L;
            const long double t = R->omega / (2.0 * M_PI), rnd = 4.0L * DBL_EPSILON * S;
            const long double cond = cs > 0.0L ? rnd * s * s / (cs * d) + t * (lmax + 1) * (lmax + 1) * rnd / d : 0.0L;
            R->cond_d = (double)(cond / t);
            R->model_d = (double)(err / (kl(lmax) * 2.0 * M_PI * (1e-9L * t + cond)));
        }
        shl_sphere_f(ctx, xf, cf, (float)c->rf, gotf);
        capref_sphere(lmax, c->xf, c->cf, c->rf, ref);
        err = 0.0;
        for (int k = 0; k < nc; ++k) err = fmax(err, fabs(gotf[k] - ref[k]));
        R->err_f = err / R->omega_f;
        R->model_f = R->err_f / 1e-4;
    }
}

static void *eval_run(void *arg)
{
    (void)arg;
    for (;;) {
        pthread_mutex_lock(&res_lock);
        const int i = next_result++;
        pthread_mutex_unlock(&res_lock);
        if (i >= nresults) return NULL;
        evaluate(&results[i]);
    }
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmp_err_d(const void *a, const void *b)
{
    const double x = ((const result *)a)->err_d, y = ((const result *)b)->err_d;
    return x < y ? 1 : x > y ? -1 : 0;
}

static void print_case(const result *R)
{
    const cand *c = &R->c;
    printf("  case %ld: %s, %s, lmax %d, n %d: max|err|/Omega double %.2e (cond. %.1e, /model %.2f), float %.2e "
           "(/model %.2f); Omega %.3g; proxy %s %.2e\n",
           c->index, c->sphere ? "sphere" : "polygon", c->sphere ? scat_name[c->cat] : pcat_name[c->cat], c->lmax, c->n,
           R->err_d, R->cond_d, R->model_d, R->err_f, R->model_f, R->omega, R->from_p2 ? "P2" : "P1",
           R->from_p2 ? c->p2 : c->p1);
}

/* stress case I: regenerate case I, print its input (%a) and its errors. */
static int replay(long i)
{
    worker W;
    memset(&W, 0, sizeof W);
    W.begin = i;
    W.end = i + 1;
    run(&W);
    const worst *lists[4] = {&W.poly_p1, &W.poly_p2, &W.sph_p1, &W.sph_p2};
    for (int j = 0; j < 4; ++j)
        if (lists[j]->count) {
            result R;
            memset(&R, 0, sizeof R);
            R.c = lists[j]->item[0];
            R.from_p2 = j & 1;
            evaluate(&R);
            const cand *c = &R.c;
            printf("x = %a %a %a\n", c->x[0], c->x[1], c->x[2]);
            for (int k = 0; k < c->n; ++k) printf("v%d = %a %a %a\n", k, c->v[3 * k], c->v[3 * k + 1], c->v[3 * k + 2]);
            if (c->sphere) printf("centre = %a %a %a, r = %a\n", c->c[0], c->c[1], c->c[2], c->r);
            if (!c->sphere) {
                pgeom G;
                poly_geom(c->x, c->v, c->n, &G);
                printf("height %.3g rmax %.3g perim %.3g G %.3g scale %.3g\n", G.height, G.rmax, G.perim, G.gsum, G.scale);
                poly_geom(c->xf, c->vf, c->n, &G);
                printf("float input: height %.3g rmax %.3g perim %.3g G %.3g scale %.3g\n", G.height, G.rmax, G.perim,
                       G.gsum, G.scale);
            }
            print_case(&R);
            if (!c->sphere) { /* the error of L_00 (the solid angle) vs the other bands */
                double got[NCMAX], ref[NCMAX], e0, e1 = 0.0;
                shl_polygon(ctxs[c->lmax], c->x, c->v, c->n, got);
                if (ref_polygon_sh(c->lmax, c->x, c->v, c->n, ref, NULL) == 0) {
                    e0 = fabs(got[0] - ref[0]);
                    for (int k = 1; k < SHL_NCOEFFS(c->lmax); ++k) e1 = fmax(e1, fabs(got[k] - ref[k]));
                    printf("  double: max |err| per band:");
                    for (int l = 0; l <= c->lmax && l < 8; ++l) {
                        double el = 0.0;
                        for (int k = l * l; k < (l + 1) * (l + 1); ++k) el = fmax(el, fabs(got[k] - ref[k]));
                        printf(" l%d %.2g", l, el);
                    }
                    printf("\n");
                    double om_lib = -1.0;
                    shl_polygon_solid_angle(c->x, c->v, c->n, &om_lib);
                    printf("  double: |err L00| %.3g, max |err| l >= 1: %.3g (Omega %.3g; shl_polygon_solid_angle %.17g)\n",
                           e0, e1, R.omega, om_lib);
                }
                float xf[3], vf[3 * MAXV], gf[NCMAX];
                printf("  float input: x = %a %a %a\n", c->xf[0], c->xf[1], c->xf[2]);
                for (int k = 0; k < c->n; ++k) printf("    v%d = %a %a %a\n", k, c->vf[3 * k], c->vf[3 * k + 1], c->vf[3 * k + 2]);
                for (int k = 0; k < 3; ++k) xf[k] = (float)c->xf[k];
                for (int k = 0; k < 3 * c->n; ++k) vf[k] = (float)c->vf[k];
                shl_polygon(ctxs[c->lmax], c->xf, c->vf, c->n, got);
                shl_polygon_f(ctxs[c->lmax], xf, vf, c->n, gf);
                if (ref_polygon_sh(c->lmax, c->xf, c->vf, c->n, ref, NULL) == 0) {
                    double f0 = fabs(gf[0] - ref[0]), f1 = 0.0, d0 = fabs(got[0] - ref[0]), d1 = 0.0;
                    for (int k = 1; k < SHL_NCOEFFS(c->lmax); ++k)
                        f1 = fmax(f1, fabs(gf[k] - ref[k])), d1 = fmax(d1, fabs(got[k] - ref[k]));
                    printf("  float input: L00 ref %.9g, float %.9g, double %.9g; |err| l >= 1 float %.3g, double %.3g "
                           "(Omega %.3g)\n", ref[0], gf[0], got[0], f1, d1, R.omega_f);
                    (void)f0, (void)d0;
                }
            }
        }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 2 && !strcmp(argv[1], "case")) {
        for (int l = 0; l <= SHL_LMAX_MAX; ++l)
            if (shl_ctx_create(l, &ctxs[l]) != SHL_OK) return 1;
        return replay(atol(argv[2]));
    }
    const long N = argc > 1 ? atol(argv[1]) : 10000000L;
    int nt = argc > 2 ? atoi(argv[2]) : 2;
    if (N <= 0 || nt < 1 || nt > MAXT) {
        fprintf(stderr, "usage: %s [N > 0] [threads 1..%d]\n", argv[0], MAXT);
        return 2;
    }
    for (int l = 0; l <= SHL_LMAX_MAX; ++l)
        if (shl_ctx_create(l, &ctxs[l]) != SHL_OK) return 1;
    printf("shlight stress: %ld cases (lmax = i mod 31: uniform over 0..30; a quarter spheres), %d threads\n", N, nt);
    fflush(stdout);
    const double t0 = now();
    worker *W = calloc((size_t)nt, sizeof *W);
    pthread_t th[MAXT];
    for (int t = 0; t < nt; ++t) {
        W[t].begin = N * t / nt;
        W[t].end = N * (t + 1) / nt;
        if (pthread_create(&th[t], NULL, run, &W[t])) return 1;
    }
    for (int t = 0; t < nt; ++t) pthread_join(th[t], NULL);
    const double t1 = now();
    /* merge */
    worker S;
    memset(&S, 0, sizeof S);
    for (int t = 0; t < nt; ++t) {
        for (int k = 0; k < W[t].poly_p1.count; ++k) worst_add(&S.poly_p1, &W[t].poly_p1.item[k], W[t].poly_p1.score[k]);
        for (int k = 0; k < W[t].poly_p2.count; ++k) worst_add(&S.poly_p2, &W[t].poly_p2.item[k], W[t].poly_p2.score[k]);
        for (int k = 0; k < W[t].sph_p1.count; ++k) worst_add(&S.sph_p1, &W[t].sph_p1.item[k], W[t].sph_p1.score[k]);
        for (int k = 0; k < W[t].sph_p2.count; ++k) worst_add(&S.sph_p2, &W[t].sph_p2.item[k], W[t].sph_p2.score[k]);
        for (int s = 0; s < 2; ++s) {
            for (int k = 0; k < NPCAT; ++k) S.cases[s][k] += W[t].cases[s][k];
            for (int k = 0; k < 4; ++k) S.nonfinite[s][k] += W[t].nonfinite[s][k];
            S.max_p1[s] = fmax(S.max_p1[s], W[t].max_p1[s]);
            S.max_p2[s] = fmax(S.max_p2[s], W[t].max_p2[s]);
        }
        S.plane_zone += W[t].plane_zone;
        S.ill_posed[0] += W[t].ill_posed[0];
        S.ill_posed[1] += W[t].ill_posed[1];
        S.above_hemisphere[0] += W[t].above_hemisphere[0];
        S.above_hemisphere[1] += W[t].above_hemisphere[1];
        for (int l = 0; l <= SHL_LMAX_MAX; ++l) S.lmax_count[l] += W[t].lmax_count[l];
    }
    long np = 0, ns = 0;
    for (int k = 0; k < NPCAT; ++k) np += S.cases[0][k];
    for (int k = 0; k < NSCAT; ++k) ns += S.cases[1][k];
    printf("\nran %ld polygons and %ld spheres in %.1f s (%.2f us per case per thread)\n", np, ns, t1 - t0,
           (t1 - t0) * nt / (double)N * 1e6);
    printf("cases per lmax: %ld (lmax 0) .. %ld (lmax 30)\n", S.lmax_count[0], S.lmax_count[SHL_LMAX_MAX]);
    printf("polygon categories:");
    for (int k = 0; k < NPCAT; ++k) printf(" %s %ld%s", pcat_name[k], S.cases[0][k], k + 1 < NPCAT ? ";" : "\n");
    printf("sphere categories:");
    for (int k = 0; k < NSCAT; ++k) printf(" %s %ld%s", scat_name[k], S.cases[1][k], k + 1 < NSCAT ? ";" : "\n");
    printf("polygon cases in the documented in-plane zone (height <= 8 (here 10) ulps of the distances; zeros expected, not "
           "ranked): %ld\n", S.plane_zone);
    printf("polygon cases not ranked as ill-posed (vertices off the plane by more than 0.1 x the point's height): "
           "double input %ld, float-rounded input %ld\n", S.ill_posed[0], S.ill_posed[1]);
    printf("\nnon-finite outputs (cases with any NaN / inf output or a non-OK status; must be 0):\n");
    printf("  polygons: coefficients double %ld, float %ld; gradients (1 case in 4) double %ld, float %ld\n",
           S.nonfinite[0][0], S.nonfinite[0][1], S.nonfinite[0][2], S.nonfinite[0][3]);
    printf("  spheres:  coefficients double %ld, float %ld; gradients (1 case in 4) double %ld, float %ld\n",
           S.nonfinite[1][0], S.nonfinite[1][1], S.nonfinite[1][2], S.nonfinite[1][3]);
    printf("polygons with L_00 / K_0 (the solid angle) above 2 pi, impossible for a planar polygon (well-posed "
           "inputs): double %ld, float %ld\n", S.above_hemisphere[0], S.above_hemisphere[1]);
    printf("\nproxies over all cases: polygons max P1 %.2e, max P2 %.2e; spheres max P1 %.2e, max P2 %.2e\n", S.max_p1[0],
           S.max_p2[0], S.max_p1[1], S.max_p2[1]);
    fflush(stdout);

    /* the candidates against the references */
    nresults = S.poly_p1.count + S.poly_p2.count + S.sph_p1.count + S.sph_p2.count;
    results = calloc((size_t)nresults, sizeof *results);
    int k = 0;
    for (int i = 0; i < S.poly_p1.count; ++i) results[k].c = S.poly_p1.item[i], results[k++].from_p2 = 0;
    for (int i = 0; i < S.poly_p2.count; ++i) results[k].c = S.poly_p2.item[i], results[k++].from_p2 = 1;
    const int npoly = k;
    for (int i = 0; i < S.sph_p1.count; ++i) results[k].c = S.sph_p1.item[i], results[k++].from_p2 = 0;
    for (int i = 0; i < S.sph_p2.count; ++i) results[k].c = S.sph_p2.item[i], results[k++].from_p2 = 1;
    for (int t = 0; t < nt; ++t) pthread_create(&th[t], NULL, eval_run, NULL);
    for (int t = 0; t < nt; ++t) pthread_join(th[t], NULL);
    const double t2 = now();
    for (int part = 0; part < 2; ++part) {
        result *R = results + (part ? npoly : 0);
        const int cnt = part ? nresults - npoly : npoly;
        double wd = 0, wf = 0, wd_excess = 0, md = 0, mf = 0, md1 = 0, mf1 = 0;
        int refbad = 0;
        int ill_d = 0, ill_f = 0;
        for (int i = 0; i < cnt; ++i) { /* ill-posed inputs: errors zeroed, counted */
            ill_d += R[i].ill_d, ill_f += R[i].ill_f;
            if (R[i].ill_d) R[i].err_d = R[i].model_d = R[i].model_d1 = R[i].cond_d = 0.0;
            if (R[i].ill_f) R[i].err_f = R[i].model_f = R[i].model_f1 = 0.0;
        }
        for (int i = 0; i < cnt; ++i) {
            if (R[i].ref_status) ++refbad;
            wd = fmax(wd, R[i].err_d);
            wf = fmax(wf, R[i].err_f);
            md = fmax(md, R[i].model_d);
            mf = fmax(mf, R[i].model_f);
            md1 = fmax(md1, R[i].model_d1);
            mf1 = fmax(mf1, R[i].model_f1);
            /* beyond the hard-case bound of test_polygon.c: 1e-10 Omega + 4 eps S max|grad| */
            wd_excess = fmax(wd_excess, R[i].err_d / (1e-10 + R[i].cond_d));
        }

        printf("\n%s: %d candidates (%s) vs %s:\n", part ? "spheres" : "polygons", cnt,
               "50 worst by P1 + 50 worst by P2", part ? "capref_sphere" : "ref_polygon_sh");
        printf("  worst max|err|/Omega: double %.3e, float %.3e", wd, wf);
        printf("; worst double err / (1e-10 Omega + conditioning) = %.3g", wd_excess);
        printf("\n  worst error / slack model of the fuzz targets: double %.3g, float %.3g (<= 1: within)", md, mf);
        if (!part) printf("\n  the same over bands l >= 1 only (L_00 excluded): double %.3g, float %.3g", md1, mf1);
        if (ill_d + ill_f)
            printf("\n  (%d double and %d float candidate inputs are ill-posed -- not planar to within 0.1 x the point's "
                   "height, or in the in-plane zone -- and not counted)", ill_d, ill_f);
        if (refbad) printf("; reference failed on %d", refbad);
        printf("\n  the 10 worst (double):\n");
        qsort(R, (size_t)cnt, sizeof *R, cmp_err_d);
        for (int i = 0; i < cnt && i < 10; ++i) print_case(&R[i]);
        int im = 0, ie = 0;
        for (int i = 1; i < cnt; ++i) {
            if (R[i].model_d > R[im].model_d) im = i;
            if (R[i].err_d / (1e-10 + R[i].cond_d) > R[ie].err_d / (1e-10 + R[ie].cond_d)) ie = i;
        }
        int i1 = 0;
        for (int i = 1; i < cnt; ++i)
            if (R[i].model_d1 > R[i1].model_d1) i1 = i;
        if (cnt) {
            printf("  the worst (double) relative to the slack model, relative to 1e-10 Omega + conditioning%s:\n",
                   part ? "" : ", and over bands l >= 1 relative to the model");
            print_case(&R[im]);
            print_case(&R[ie]);
            if (!part) print_case(&R[i1]);
        }
        double wfl = 0.0, wfm = 0.0;
        const result *wr = NULL, *wm = NULL;
        for (int i = 0; i < cnt; ++i) {
            if (R[i].err_f > wfl) wfl = R[i].err_f, wr = &R[i];
            if (R[i].model_f > wfm) wfm = R[i].model_f, wm = &R[i];
        }
        if (wr) {
            printf("  the worst (float), by max|err|/Omega and relative to the slack model:\n");
            print_case(wr);
            if (wm) print_case(wm);
        }
    }
    printf("\nreference evaluation %.1f s; total %.1f s\n", t2 - t1, now() - t0);
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) shl_ctx_destroy(ctxs[l]);
    free(W);
    free(results);
    return 0;
}
