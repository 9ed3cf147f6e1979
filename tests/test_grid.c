/* SH grids: fill against direct evaluation, thread independence, exactness of
 * the three interpolants on polynomial fields, accuracy on a real light field
 * (Wu 2020 Fig. 4 setup), clamping, bad input, allocation and thread failures. */
#include "batch_tol.h"
#include "geom.h"
#include "grid.h" /* struct shl_grid: the large path's alignment */
#include "harness.h"
#include "internal.h"
#include "isa_ctx.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { LMAX = 4, NC = SHL_NCOEFFS(LMAX), NV = 3 * NC, NG = 9 * NC };

static const double quad_light[12] = {-1.0, -0.5, 1.5, 1.0, -0.5, 1.5, 1.0, 0.5, 1.5, -1.0, 0.5, 1.5};

/* The set of two_lights(), with the copies batch_tol.h needs for its tolerances. */
static void two_lights_set(light_set *s)
{
    const double tri[9] = {0.5, 1.0, 2.0, 1.5, 1.2, 1.8, 0.8, 1.9, 2.2}, rgb1[3] = {1.0, 0.8, 0.6}, rgb2[3] = {0.2, 0.4, 3.0};
    memset(s, 0, sizeof *s);
    CHECK(shl_lights_create(&s->set) == SHL_OK);
    add_polygon(s, quad_light, 4, rgb1, 0); /* faces +z: lights z > 1.5 only */
    add_polygon(s, quad_light, 4, rgb2, 1);
    add_polygon(s, tri, 3, rgb2, 1);
}

static shl_lights *two_lights(void)
{
    static light_set s;
    two_lights_set(&s);
    return s.set;
}

/* Float grid node idx against the float batch and the double reference (the
 * contract of shl_grid_fill for float grids, include/shlight.h): the node equals
 * shl_lights_eval_batch_f at its position x rounded to float, bit for bit (*bad
 * counts mismatches), and lies within the derived batch tolerance (batch_tol.h)
 * of shl_lights_eval at that rounded position; the rounding moves x by at most
 * 2^-24 max(|lo[a]|, |hi[a]|) per axis.  Returns the worst error / tolerance. */
static double check_float_node(const shl_ctx *ctx, const light_set *s, const shl_grid *gf, const double lo[3],
                               const double hi[3], const int idx[3], int *bad)
{
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(ctx));
    double x[3], xr[3], got[3 * NCMAX], got_g[9 * NCMAX], ref[3 * NCMAX], ref_g[9 * NCMAX], tc[3][SHL_LMAX_MAX + 1],
           tg[3][SHL_LMAX_MAX + 1];
    float xf[3], bf[3 * NCMAX], bg[9 * NCMAX];
    CHECK(shl_grid_node_position(gf, idx, x) == SHL_OK);
    for (int a = 0; a < 3; ++a) {
        xf[a] = (float)x[a];
        xr[a] = xf[a];
        CHECK(fabs(xr[a] - x[a]) <= 0x1p-24 * fmax(fabs(lo[a]), fabs(hi[a])));
    }
    CHECK(shl_grid_get_node(gf, idx, got, got_g) == SHL_OK);
    CHECK(shl_lights_eval_batch_f(ctx, s->set, 1, xf, bf, bg) == SHL_OK);
    for (int k = 0; k < 3 * nc; ++k) *bad += got[k] != (double)bf[k];
    for (int k = 0; k < 9 * nc; ++k) *bad += got_g[k] != (double)bg[k];
    CHECK(shl_lights_eval(ctx, s->set, xr, ref, ref_g) == SHL_OK);
    tolerances(ctx, s, xr, tc, tg);
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) {
        double ec = 0.0, eg = 0.0, rc = 0.0, rg = 0.0;
        for (int k = 0; k < nc; ++k) {
            const double d = fabs(got[c * nc + k] - ref[c * nc + k]);
            ec = fmax(ec, d), rc = fmax(rc, tol_ratio(d, tc[c][band_of(k)]));
        }
        for (int k = 0; k < 3 * nc; ++k) {
            const double d = fabs(got_g[3 * c * nc + k] - ref_g[3 * c * nc + k]);
            eg = fmax(eg, d), rg = fmax(rg, tol_ratio(d, tg[c][band_of(k % nc)]));
        }
        if (!(rc <= 1.0 && rg <= 1.0))
            harness_fail(__FILE__, __LINE__, "float node (%d, %d, %d) colour %d: coeffs %.3g (error/tol %.3g), grad %.3g "
                         "(error/tol %.3g)", idx[0], idx[1], idx[2], c, ec, rc, eg, rg);
        worst = fmax(worst, fmax(rc, rg));
    }
    return worst;
}

static shl_grid *new_grid(const shl_ctx *ctx, const double lo[3], const double hi[3], const int res[3], int storage)
{
    shl_grid *g = NULL;
    CHECK(shl_grid_create(ctx, lo, hi, res, storage, &g) == SHL_OK);
    return g;
}

SHL_TEST(grid_bytes_per_node)
{
    int bf = -1, bd = -1; /* 3 colours x (value + 3 gradients) x nc x element size */
    CHECK(shl_grid_bytes_per_node(4, SHL_GRID_FLOAT, &bf) == SHL_OK && bf == 3 * 4 * 25 * 4);
    CHECK(shl_grid_bytes_per_node(8, SHL_GRID_DOUBLE, &bd) == SHL_OK && bd == 3 * 4 * 81 * 8);
    CHECK(shl_grid_bytes_per_node(-1, SHL_GRID_FLOAT, &bf) == SHL_ELMAX);
    CHECK(shl_grid_bytes_per_node(4, 2, &bf) == SHL_EDOMAIN);
    CHECK(shl_grid_bytes_per_node(4, SHL_GRID_FLOAT, NULL) == SHL_ENULL);
    CHECK(bf == 1200 && bd == 7776);
    harness_note("lmax 4 float: %d bytes/node; lmax 8 double: %d", bf, bd);
}

/* Every node of a double grid holds shl_lights_eval at its position, bit for
 * bit; every node of a float grid, for every ISA this machine runs, the float
 * batch at its position rounded to float, bit for bit, within the batch
 * tolerance of shl_lights_eval (check_float_node). */
SHL_TEST(grid_nodes_equal_direct_evaluation)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    light_set s;
    two_lights_set(&s);
    const double lo[3] = {-1.0, -0.8, -0.5}, hi[3] = {1.2, 0.9, 1.0};
    const int res[3] = {3, 4, 5};
    shl_grid *gd = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    CHECK(shl_grid_fill(gd, s.set, 1) == SHL_OK);
    int bad = 0;
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double x[3], want[NV], want_g[NG], got[NV], got_g[NG];
                CHECK(shl_grid_node_position(gd, idx, x) == SHL_OK);
                for (int a = 0; a < 3; ++a)
                    CHECK(x[a] == (idx[a] == res[a] - 1 ? hi[a] : lo[a] + idx[a] * (hi[a] - lo[a]) / (res[a] - 1)));
                CHECK(shl_lights_eval(ctx, s.set, x, want, want_g) == SHL_OK);
                CHECK(shl_grid_get_node(gd, idx, got, got_g) == SHL_OK);
                bad += memcmp(got, want, sizeof got) != 0 || memcmp(got_g, want_g, sizeof got_g) != 0;
            }
    CHECK(bad == 0);
    for (int t = 0; t < NISA; ++t) {
        shl_ctx *ictx = isa_ctx(isas[t], LMAX);
        if (!ictx) continue;
        shl_grid *gf = new_grid(ictx, lo, hi, res, SHL_GRID_FLOAT);
        CHECK(shl_grid_fill(gf, s.set, 2) == SHL_OK);
        int bad_f = 0;
        double worst = 0.0;
        for (int n = 0; n < res[0] * res[1] * res[2]; ++n) {
            const int idx[3] = {n % res[0], n / res[0] % res[1], n / res[0] / res[1]};
            worst = fmax(worst, check_float_node(ictx, &s, gf, lo, hi, idx, &bad_f));
        }
        CHECK(bad_f == 0);
        harness_note("%s float nodes: worst error / batch tolerance %.2f", isas[t], worst);
        shl_grid_destroy(gf);
        shl_ctx_destroy(ictx);
    }
    shl_grid_destroy(gd);
    shl_lights_destroy(s.set);
    shl_ctx_destroy(ctx);
}

/* Float grids off the float path (include/shlight.h): a box 1000 away from the
 * origin with spacing 0.25 < 2^-10 x 1000 (float rounding would move nodes by up
 * to 3e-5, 1.2e-4 of h), and one of spacing 2^-101: nodes are shl_lights_eval at
 * the node position rounded to float, bit for bit, as double grids are. */
SHL_TEST(grid_fill_float_off_batch_path)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l;
    const double white[3] = {1.0, 0.5, 2.0}, c[3] = {1000.2, 0.5, 2.0};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_sphere(l, c, 0.5, white) == SHL_OK);
    const double lo[2][3] = {{1000.0, 0.0, 0.0}, {0.0, 0.0, 0.0}}, hi[2][3] = {{1000.5, 1.0, 1.0}, {0x1p-100, 1.0, 1.0}};
    const int res[3] = {3, 3, 3};
    int bad = 0;
    for (int b = 0; b < 2; ++b) {
        shl_grid *g = new_grid(ctx, lo[b], hi[b], res, SHL_GRID_FLOAT);
        CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
        for (int n = 0; n < 27; ++n) {
            const int idx[3] = {n % 3, n / 3 % 3, n / 9};
            double x[3], want[NV], want_g[NG], got[NV], got_g[NG];
            CHECK(shl_grid_node_position(g, idx, x) == SHL_OK);
            CHECK(shl_lights_eval(ctx, l, x, want, want_g) == SHL_OK);
            CHECK(shl_grid_get_node(g, idx, got, got_g) == SHL_OK);
            for (int k = 0; k < NV; ++k) bad += got[k] != (double)(float)want[k];
            for (int k = 0; k < NG; ++k) bad += got_g[k] != (double)(float)want_g[k];
        }
        shl_grid_destroy(g);
    }
    CHECK(bad == 0);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

static int grids_equal(const shl_grid *a, const shl_grid *b, const int res[3])
{
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double va[NV], ga[NG], vb[NV], gb[NG];
                shl_grid_get_node(a, idx, va, ga);
                shl_grid_get_node(b, idx, vb, gb);
                if (memcmp(va, vb, sizeof va) || memcmp(ga, gb, sizeof ga)) return 0;
            }
    return 1;
}

/* Float: 693 nodes, 11 blocks of the float fill, the last one partial; double:
 * 120 nodes (threads take single nodes).  Any thread count gives the 1-thread
 * grid bit for bit. */
SHL_TEST(grid_fill_threads_bit_identical)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l = two_lights();
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    for (int storage = 0; storage < 2; ++storage) {
        const int st = storage ? SHL_GRID_DOUBLE : SHL_GRID_FLOAT;
        const int res[3] = {storage ? 5 : 9, storage ? 4 : 7, storage ? 6 : 11};
        shl_grid *ref = new_grid(ctx, lo, hi, res, st);
        CHECK(shl_grid_fill(ref, l, 1) == SHL_OK);
        const int threads[4] = {2, 3, 8, SHL_MAX_THREADS};
        for (int t = 0; t < 4; ++t) {
            shl_grid *g = new_grid(ctx, lo, hi, res, st);
            CHECK(shl_grid_fill(g, l, threads[t]) == SHL_OK);
            CHECK(grids_equal(ref, g, res));
            shl_grid_destroy(g);
        }
        shl_grid_destroy(ref);
    }
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Polygons and spheres (one overlapping the box, so some nodes lie inside it):
 * every node holds shl_lights_eval (bit for bit in double) = the sum of
 * rgb x shl_polygon_grad and rgb x shl_sphere_grad; float nodes are the float
 * batch's (check_float_node); the three interpolants
 * return the node values at the nodes; threads do not change the fill. */
SHL_TEST(grid_fill_mixed_set_with_spheres)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    const double tri[9] = {0.5, 1.0, 2.0, 1.5, 1.2, 1.8, 0.8, 1.9, 2.2}, prgb[2][3] = {{1.0, 0.8, 0.6}, {0.2, 0.4, 3.0}};
    const double sc[2][3] = {{0.4, -0.3, 0.2}, {-1.0, 0.5, 3.0}}, sr[2] = {0.45, 0.7}, srgb[2][3] = {{2.0, 1.0, 0.5}, {0.3, -0.2, 1.5}};
    light_set s;
    memset(&s, 0, sizeof s);
    CHECK(shl_lights_create(&s.set) == SHL_OK);
    add_sphere(&s, sc[0], sr[0], srgb[0]);
    add_polygon(&s, quad_light, 4, prgb[0], 1);
    add_sphere(&s, sc[1], sr[1], srgb[1]);
    add_polygon(&s, tri, 3, prgb[1], 1);
    shl_lights *l = s.set;
    const double lo[3] = {-1.0, -0.8, -0.5}, hi[3] = {1.2, 0.9, 1.0};
    const int res[3] = {5, 4, 6};
    shl_grid *gd = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE), *gf = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(gd, l, 3) == SHL_OK);
    CHECK(shl_grid_fill(gf, l, 1) == SHL_OK);
    int bad = 0, inside = 0;
    double ev = 0.0, eg = 0.0, enode = 0.0, worst_f = 0.0;
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double x[3], direct[NV], direct_g[NG], got[NV], got_g[NG], want[NV] = {0}, want_g[NG] = {0};
                CHECK(shl_grid_node_position(gd, idx, x) == SHL_OK);
                CHECK(shl_lights_eval(ctx, l, x, direct, direct_g) == SHL_OK);
                CHECK(shl_grid_get_node(gd, idx, got, got_g) == SHL_OK);
                bad += memcmp(got, direct, sizeof got) != 0 || memcmp(got_g, direct_g, sizeof got_g) != 0;
                worst_f = fmax(worst_f, check_float_node(ctx, &s, gf, lo, hi, idx, &bad));
                /* the sum of the parts */
                for (int p = 0; p < 4; ++p) {
                    double co[NC], gr[3 * NC];
                    const double *rgb = p < 2 ? srgb[p] : prgb[p - 2];
                    if (p < 2)
                        CHECK(shl_sphere_grad(ctx, x, sc[p], sr[p], co, gr) == SHL_OK);
                    else
                        CHECK(shl_polygon_grad(ctx, x, p == 2 ? quad_light : tri, p == 2 ? 4 : 3, co, gr) == SHL_OK);
                    for (int ch = 0; ch < 3; ++ch)
                        for (int m = 0; m < NC; ++m) {
                            want[ch * NC + m] += rgb[ch] * co[m];
                            for (int a = 0; a < 3; ++a) want_g[(ch * 3 + a) * NC + m] += rgb[ch] * gr[a * NC + m];
                        }
                }
                double sv = 0.0, sg = 0.0, dv = 0.0, dg = 0.0;
                for (int c = 0; c < NV; ++c) sv = fmax(sv, fabs(want[c])), dv = fmax(dv, fabs(direct[c] - want[c]));
                for (int c = 0; c < NG; ++c) sg = fmax(sg, fabs(want_g[c])), dg = fmax(dg, fabs(direct_g[c] - want_g[c]));
                ev = fmax(ev, dv / sv);
                eg = fmax(eg, dg / sg);
                const double dx[3] = {x[0] - sc[0][0], x[1] - sc[0][1], x[2] - sc[0][2]};
                inside += dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2] <= sr[0] * sr[0];
                /* interpolation at the node returns the node (double grid) */
                double out[NV];
                for (int m = 0; m < 3; ++m) {
                    CHECK(shl_grid_interp(gd, m, 2.0, 1, x, out, 1) == SHL_OK);
                    for (int c = 0; c < NV; ++c) enode = fmax(enode, fabs(out[c] - direct[c]) / sv);
                }
            }
    CHECK(bad == 0);
    CHECK(inside >= 2);
    CHECK(ev <= 1e-13 && eg <= 1e-12);
    CHECK(enode <= 1e-14);
    shl_grid *g2 = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g2, l, 8) == SHL_OK);
    CHECK(grids_equal(gf, g2, res));
    harness_note("%d nodes (%d inside a sphere): vs sum of parts coeffs %.1e, grads %.1e; interp at nodes %.1e; "
                 "float nodes worst error / batch tolerance %.2f", res[0] * res[1] * res[2], inside, ev, eg, enode, worst_f);
    shl_grid_destroy(g2);
    shl_grid_destroy(gd);
    shl_grid_destroy(gf);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* A sphere light above an 8^3 float box (Wu 2020 Fig. 4-style check for spheres):
 * all coefficients at 2000 random points against direct evaluation, relative to max |L00|. */
SHL_TEST(grid_interp_sphere_light_box)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l;
    const double white[3] = {1, 1, 1}, c[3] = {0.3, -0.2, 1.6};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_sphere(l, c, 0.6, white) == SHL_OK);
    const double lo[3] = {-1.5, -1.5, -1.0}, hi[3] = {1.5, 1.5, 0.5};
    const int res[3] = {8, 8, 8};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    enum { NP = 2000 };
    static double pts[3 * NP], ref[NP * NV], out[NP * NV];
    rng_t r = {41};
    for (int p = 0; p < NP; ++p)
        for (int a = 0; a < 3; ++a) pts[3 * p + a] = rng_range(&r, lo[a], hi[a]);
    CHECK(shl_lights_eval_batch(ctx, l, NP, pts, ref, NULL) == SHL_OK);
    double scale = 0.0, err[3] = {0, 0, 0};
    for (int p = 0; p < NP; ++p) scale = fmax(scale, fabs(ref[p * NV]));
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 2.0, NP, pts, out, 2) == SHL_OK);
        for (int i = 0; i < NP * NV; ++i) err[m] = fmax(err[m], fabs(out[i] - ref[i]) / scale);
    }
    CHECK(err[2] * 5.0 <= err[0] && err[2] * 5.0 <= err[1]); /* as the polygon box above (measured ~10x) */
    CHECK(err[2] <= 5e-2);                                     /* measured 2.4e-2: the cells are ~0.43 wide, the sphere 0.5 away */
    harness_note("8^3 float, sphere r 0.6 at distance >= 0.5 from the box: max err trilinear %.1e, Taylor %.1e, Hermite %.1e",
                 err[0], err[1], err[2]);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Polynomial test fields: channel ch holds (1 + ch/10) * F(x) + ch. */
typedef void (*field_fn)(const double x[3], double *f, double g[3]);

static void set_field(shl_grid *grid, const int res[3], field_fn fn)
{
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double x[3], f, g[3], v[NV], gr[NG];
                shl_grid_node_position(grid, idx, x);
                fn(x, &f, g);
                for (int c = 0; c < 3; ++c)
                    for (int m = 0; m < NC; ++m) {
                        const double s = 1.0 + (c * NC + m) / 10.0;
                        v[c * NC + m] = s * f + (c * NC + m);
                        for (int a = 0; a < 3; ++a) gr[(c * 3 + a) * NC + m] = s * g[a];
                    }
                CHECK(shl_grid_set_node(grid, idx, v, gr) == SHL_OK);
            }
}

/* max over random points in the box (and on its faces) of |interp - field| / max|field| */
static double field_error(const shl_grid *grid, int method, double b, const double lo[3], const double hi[3], field_fn fn)
{
    enum { NP = 300 };
    static double pts[3 * NP], out[NP * NV];
    rng_t r = {99};
    for (int p = 0; p < NP; ++p)
        for (int a = 0; a < 3; ++a) {
            pts[3 * p + a] = rng_range(&r, lo[a], hi[a]);
            if (p % 10 == a) pts[3 * p + a] = p % 20 < 10 ? lo[a] : hi[a];
        }
    CHECK(shl_grid_interp(grid, method, b, NP, pts, out, 1) == SHL_OK);
    double err = 0.0, scale = 0.0;
    for (int p = 0; p < NP; ++p) {
        double f, g[3];
        fn(pts + 3 * p, &f, g);
        for (int ch = 0; ch < NV; ++ch) {
            const double want = (1.0 + ch / 10.0) * f + ch;
            err = fmax(err, fabs(out[p * NV + ch] - want));
            scale = fmax(scale, fabs(want));
        }
    }
    return err / scale;
}

/* In the exact space of Wu 2020 Alg. 4 (see shl_grid_interp): cubics in each
 * variable, xyz, x y^3, y z^3, x z^3, x y z^3. */
static void cubic_field(const double x[3], double *f, double g[3])
{
    const double X = x[0], Y = x[1], Z = x[2];
    *f = 0.3 + X - 2 * Y + 0.5 * Z + X * X * X - 0.7 * Y * Y + 0.4 * Y * Y * Y - 0.9 * Z * Z * Z + 1.1 * X * Y * Z +
         0.6 * X * Y * Y * Y - 0.8 * Y * Z * Z * Z + 0.5 * X * Z * Z * Z + 0.3 * X * Y * Z * Z * Z + 0.2 * X * Y;
    g[0] = 1 + 3 * X * X + 1.1 * Y * Z + 0.6 * Y * Y * Y + 0.5 * Z * Z * Z + 0.3 * Y * Z * Z * Z + 0.2 * Y;
    g[1] = -2 - 1.4 * Y + 1.2 * Y * Y + 1.1 * X * Z + 1.8 * X * Y * Y - 0.8 * Z * Z * Z + 0.3 * X * Z * Z * Z + 0.2 * X;
    g[2] = 0.5 - 2.7 * Z * Z + 1.1 * X * Y - 2.4 * Y * Z * Z + 1.5 * X * Z * Z + 0.9 * X * Y * Z * Z;
}

/* x^2 y: outside that space (d/dy = x^2 is carried linearly along x). */
static void x2y_field(const double x[3], double *f, double g[3])
{
    *f = x[0] * x[0] * x[1];
    g[0] = 2 * x[0] * x[1];
    g[1] = x[0] * x[0];
    g[2] = 0.0;
}

static void trilinear_field(const double x[3], double *f, double g[3])
{
    *f = 0.5 + 2 * x[0] - x[1] + 3 * x[2] + 0.7 * x[0] * x[1] - 0.4 * x[1] * x[2] + 0.3 * x[0] * x[2] + 1.3 * x[0] * x[1] * x[2];
    g[0] = 2 + 0.7 * x[1] + 0.3 * x[2] + 1.3 * x[1] * x[2];
    g[1] = -1 + 0.7 * x[0] - 0.4 * x[2] + 1.3 * x[0] * x[2];
    g[2] = 3 - 0.4 * x[1] + 0.3 * x[0] + 1.3 * x[0] * x[1];
}

static void linear_field(const double x[3], double *f, double g[3])
{
    *f = 0.5 + 2 * x[0] - x[1] + 3 * x[2];
    g[0] = 2;
    g[1] = -1;
    g[2] = 3;
}

/* Reproduction on double grids: the error is rounding only (values ~ 10, a few
 * dozen operations: tolerance 1e-13 relative to the largest value). */
SHL_TEST(grid_interp_reproduces_polynomials)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    const double lo[3] = {-1.0, -0.5, 0.2}, hi[3] = {1.3, 1.0, 1.1};
    const int res[3] = {4, 6, 3};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    set_field(g, res, cubic_field);
    const double e_herm = field_error(g, SHL_INTERP_HERMITE, 0, lo, hi, cubic_field);
    set_field(g, res, x2y_field);
    const double e_x2y = field_error(g, SHL_INTERP_HERMITE, 0, lo, hi, x2y_field);
    set_field(g, res, trilinear_field);
    const double e_tri = field_error(g, SHL_INTERP_TRILINEAR, 0, lo, hi, trilinear_field);
    const double e_herm_tri = field_error(g, SHL_INTERP_HERMITE, 0, lo, hi, trilinear_field);
    set_field(g, res, linear_field);
    double e_tay = 0.0;
    const double bs[4] = {0.5, 1.0, 2.0, 8.0};
    for (int i = 0; i < 4; ++i) e_tay = fmax(e_tay, field_error(g, SHL_INTERP_TAYLOR, bs[i], lo, hi, linear_field));
    CHECK(e_herm <= 1e-13 && e_herm_tri <= 1e-13 && e_tri <= 1e-13 && e_tay <= 1e-13);
    CHECK(e_x2y > 1e-4); /* documented limit of Alg. 4's linear gradient interpolation */
    harness_note("Hermite cubic %.1e, Hermite trilinear %.1e, trilinear %.1e, Taylor linear (b 0.5..8) %.1e; "
                 "Hermite on x^2 y %.1e (not exact by design)", e_herm, e_herm_tri, e_tri, e_tay, e_x2y);
    shl_grid_destroy(g);
    shl_ctx_destroy(ctx);
}

/* At the nodes all three methods return the node values; across cell faces
 * the Hermite interpolant is continuous.  Random node data (values and gradients). */
SHL_TEST(grid_interp_node_values_and_continuity)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    const double lo[3] = {-0.3, 0.1, -2.0}, hi[3] = {0.7, 0.9, 1.0};
    const int res[3] = {5, 3, 4};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    rng_t r = {17};
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double v[NV], gr[NG];
                for (int c = 0; c < NV; ++c) v[c] = rng_range(&r, -1, 1);
                for (int c = 0; c < NG; ++c) gr[c] = rng_range(&r, -1, 1);
                CHECK(shl_grid_set_node(g, idx, v, gr) == SHL_OK);
            }
    double worst = 0.0;
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                double x[3], v[NV], out[NV];
                shl_grid_node_position(g, idx, x);
                shl_grid_get_node(g, idx, v, NULL);
                for (int m = 0; m < 3; ++m) {
                    CHECK(shl_grid_interp(g, m, 2.0, 1, x, out, 1) == SHL_OK);
                    for (int c = 0; c < NV; ++c) worst = fmax(worst, fabs(out[c] - v[c]));
                }
            }
    CHECK(worst <= 1e-14); /* |values| <= 1; only the local coordinate's rounding remains */
    /* continuity: points 1e-12 on either side of interior node planes */
    double jump = 0.0;
    for (int it = 0; it < 50; ++it) {
        const int a = it % 3, plane = 1 + it % (res[a] - 2);
        double p[6];
        for (int b = 0; b < 3; ++b) p[b] = p[3 + b] = rng_range(&r, lo[b], hi[b]);
        const double at = lo[a] + plane * (hi[a] - lo[a]) / (res[a] - 1);
        p[a] = at - 1e-12;
        p[3 + a] = at + 1e-12;
        double out[2 * NV];
        CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 2, p, out, 1) == SHL_OK);
        for (int c = 0; c < NV; ++c) jump = fmax(jump, fabs(out[c] - out[NV + c]));
    }
    CHECK(jump <= 1e-10); /* slope <= ~10 per unit length x 2e-12 */
    harness_note("node values max |diff| %.1e; max jump across faces (2e-12 apart) %.1e", worst, jump);
    shl_grid_destroy(g);
    shl_ctx_destroy(ctx);
}

/* Wu 2020 Fig. 4 setup: coefficient (7,2) of a rectangular light along a line,
 * 10 samples with analytic gradients; a 10 x 2 x 2 grid whose y and z extent is
 * 1e-6 reduces every method to 1D along the line.  Errors over 400 points
 * against per-point evaluation, relative to max |L_72| on the line. */
SHL_TEST(grid_interp_real_light_line)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(7, &ctx) == SHL_OK);
    enum { N7 = SHL_NCOEFFS(7), K72 = 7 * 8 + 2, NP = 400 };
    const double rect[12] = {-1.0, -1.0, 2.0, 1.0, -1.0, 2.0, 1.0, 1.0, 2.0, -1.0, 1.0, 2.0}, white[3] = {1, 1, 1};
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_polygon(l, rect, 4, white, 1) == SHL_OK);
    const double lo[3] = {-2.0, 0.3, 0.0}, hi[3] = {2.0, 0.3 + 1e-6, 1e-6}; /* as bench_grid.c */
    const int res[3] = {10, 2, 2};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    static double pts[3 * NP], ref[NP * 3 * N7], out[NP * 3 * N7];
    for (int p = 0; p < NP; ++p) {
        pts[3 * p] = lo[0] + (hi[0] - lo[0]) * p / (NP - 1);
        pts[3 * p + 1] = lo[1];
        pts[3 * p + 2] = lo[2];
    }
    CHECK(shl_lights_eval_batch(ctx, l, NP, pts, ref, NULL) == SHL_OK);
    double scale = 0.0, err[3] = {0, 0, 0};
    for (int p = 0; p < NP; ++p) scale = fmax(scale, fabs(ref[p * 3 * N7 + K72]));
    const int methods[3] = {SHL_INTERP_TRILINEAR, SHL_INTERP_TAYLOR, SHL_INTERP_HERMITE};
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, methods[m], 2.0, NP, pts, out, 1) == SHL_OK);
        for (int p = 0; p < NP; ++p) err[m] = fmax(err[m], fabs(out[p * 3 * N7 + K72] - ref[p * 3 * N7 + K72]) / scale);
    }
    CHECK(err[2] * 10.0 <= err[0] && err[2] * 10.0 <= err[1]);
    harness_note("max err / max|L72|: trilinear %.2e, Taylor(b=2) %.2e, Hermite %.2e (%.0fx, %.0fx)", err[0], err[1],
                 err[2], err[0] / err[2], err[1] / err[2]);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* 3D: an 8^3 float grid over a box below a quad light; all coefficients at
 * 2000 random points, error relative to max |L00|. */
SHL_TEST(grid_interp_real_light_box)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l;
    const double white[3] = {1, 1, 1};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_polygon(l, quad_light, 4, white, 1) == SHL_OK);
    const double lo[3] = {-1.5, -1.5, -1.0}, hi[3] = {1.5, 1.5, 0.5};
    const int res[3] = {8, 8, 8};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    enum { NP = 2000 };
    static double pts[3 * NP], ref[NP * NV], out[NP * NV];
    rng_t r = {4};
    for (int p = 0; p < NP; ++p)
        for (int a = 0; a < 3; ++a) pts[3 * p + a] = rng_range(&r, lo[a], hi[a]);
    CHECK(shl_lights_eval_batch(ctx, l, NP, pts, ref, NULL) == SHL_OK);
    double scale = 0.0, err[3] = {0, 0, 0}, mean[3] = {0, 0, 0};
    for (int p = 0; p < NP; ++p) scale = fmax(scale, fabs(ref[p * NV]));
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 2.0, NP, pts, out, 2) == SHL_OK);
        for (int i = 0; i < NP * NV; ++i) {
            err[m] = fmax(err[m], fabs(out[i] - ref[i]) / scale);
            mean[m] += fabs(out[i] - ref[i]) / scale / (NP * NV);
        }
    }
    CHECK(err[2] * 5.0 <= err[0] && err[2] * 5.0 <= err[1]);
    CHECK(mean[2] * 10.0 <= mean[0] && mean[2] * 10.0 <= mean[1]);
    harness_note("8^3 float, max/mean err: trilinear %.1e/%.1e, Taylor %.1e/%.1e, Hermite %.1e/%.1e", err[0], mean[0],
                 err[1], mean[1], err[2], mean[2]);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Outside points equal the interpolant at the clamped point; threads do not change results. */
SHL_TEST(grid_interp_clamp_and_threads)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l = two_lights();
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    const int res[3] = {4, 4, 4};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 1) == SHL_OK);
    enum { NP = 1000 };
    static double pts[3 * NP], clamped[3 * NP], a[NP * NV], b[NP * NV];
    rng_t r = {8};
    for (int i = 0; i < 3 * NP; ++i) {
        pts[i] = rng_range(&r, -3.0, 3.0);
        clamped[i] = fmin(fmax(pts[i], -1.0), 1.0);
    }
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 1.5, NP, pts, a, 1) == SHL_OK);
        CHECK(shl_grid_interp(g, m, 1.5, NP, clamped, b, 1) == SHL_OK);
        CHECK(memcmp(a, b, sizeof a) == 0);
        const int threads[3] = {2, 3, 64};
        for (int t = 0; t < 3; ++t) {
            CHECK(shl_grid_interp(g, m, 1.5, NP, pts, b, threads[t]) == SHL_OK);
            CHECK(memcmp(a, b, sizeof a) == 0);
        }
    }
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

SHL_TEST(grid_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    enum { N2 = 3 * SHL_NCOEFFS(2) };
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, nan3[3] = {0, NAN, 0};
    const int res[3] = {2, 3, 2}, res1[3] = {2, 1, 2}, resbig[3] = {2, SHL_GRID_RES_MAX + 1, 2};
    shl_grid *g = NULL, *out = NULL;
    CHECK(shl_grid_create(NULL, lo, hi, res, SHL_GRID_FLOAT, &out) == SHL_ENULL);
    CHECK(shl_grid_create(ctx, NULL, hi, res, SHL_GRID_FLOAT, &out) == SHL_ENULL);
    CHECK(shl_grid_create(ctx, lo, hi, NULL, SHL_GRID_FLOAT, &out) == SHL_ENULL);
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, NULL) == SHL_ENULL);
    CHECK(shl_grid_create(ctx, lo, hi, res1, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    CHECK(shl_grid_create(ctx, lo, hi, resbig, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    CHECK(shl_grid_create(ctx, hi, lo, res, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    CHECK(shl_grid_create(ctx, lo, lo, res, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    const double hi_den[3] = {1, 0x1p-1074, 1}; /* spacing 2^-1074 / 2 underflows to 0 */
    CHECK(shl_grid_create(ctx, lo, hi_den, res, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    CHECK(shl_grid_create(ctx, lo, hi, res, 7, &out) == SHL_EDOMAIN);
    CHECK(shl_grid_create(ctx, nan3, hi, res, SHL_GRID_FLOAT, &out) == SHL_ENONFINITE);
    const double huge_lo[3] = {-1e308, 0, 0}, huge_hi[3] = {1e308, 1, 1};
    CHECK(shl_grid_create(ctx, huge_lo, huge_hi, res, SHL_GRID_FLOAT, &out) == SHL_EDOMAIN);
    CHECK(out == NULL);
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_DOUBLE, &g) == SHL_OK);

    const int idx[3] = {1, 2, 1}, bad_idx[3] = {2, 0, 0}, neg_idx[3] = {0, -1, 0};
    double v[N2 + 1], gr[3 * N2 + 1], pos[4];
    guard_fill(v, N2 + 1);
    guard_fill(gr, 3 * N2 + 1);
    guard_fill(pos, 4);
    CHECK(shl_grid_node_position(NULL, idx, pos) == SHL_ENULL);
    CHECK(shl_grid_node_position(g, NULL, pos) == SHL_ENULL);
    CHECK(shl_grid_node_position(g, idx, NULL) == SHL_ENULL);
    CHECK(shl_grid_node_position(g, bad_idx, pos) == SHL_EDOMAIN);
    CHECK(shl_grid_get_node(g, neg_idx, v, gr) == SHL_EDOMAIN);
    CHECK(shl_grid_get_node(g, idx, NULL, gr) == SHL_ENULL);
    CHECK(guard_intact(v, N2 + 1) && guard_intact(gr, 3 * N2 + 1) && guard_intact(pos, 4));
    /* set_node: a NaN anywhere leaves the node untouched */
    for (int i = 0; i < N2; ++i) v[i] = 1.0;
    for (int i = 0; i < 3 * N2; ++i) gr[i] = 2.0;
    gr[3 * N2 - 1] = NAN;
    CHECK(shl_grid_set_node(g, idx, v, gr) == SHL_ENONFINITE);
    CHECK(shl_grid_set_node(g, idx, v, NULL) == SHL_ENULL);
    CHECK(shl_grid_set_node(g, bad_idx, v, gr) == SHL_EDOMAIN);
    CHECK(shl_grid_set_node(NULL, idx, v, gr) == SHL_ENULL);
    CHECK(shl_grid_get_node(g, idx, v, gr) == SHL_OK);
    for (int i = 0; i < N2; ++i) CHECK(v[i] == 0.0);
    for (int i = 0; i < 3 * N2; ++i) CHECK(gr[i] == 0.0);

    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_grid_fill(NULL, l, 1) == SHL_ENULL);
    CHECK(shl_grid_fill(g, NULL, 1) == SHL_ENULL);
    CHECK(shl_grid_fill(g, l, 0) == SHL_EDOMAIN);
    CHECK(shl_grid_fill(g, l, SHL_MAX_THREADS + 1) == SHL_EDOMAIN);

    const double pts[6] = {0.5, 0.5, 0.5, 0.1, INFINITY, 0.2};
    double o[2 * N2 + 1];
    guard_fill(o, 2 * N2 + 1);
    CHECK(shl_grid_interp(NULL, SHL_INTERP_HERMITE, 0, 1, pts, o, 1) == SHL_ENULL);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 1, NULL, o, 1) == SHL_ENULL);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 1, pts, NULL, 1) == SHL_ENULL);
    CHECK(shl_grid_interp(g, 3, 0, 1, pts, o, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, -1, 0, 1, pts, o, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, 0.0, 1, pts, o, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, -1.0, 1, pts, o, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, NAN, 1, pts, o, 1) == SHL_ENONFINITE);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, -1, pts, o, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 1, pts, o, 0) == SHL_EDOMAIN);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 2, pts, o, 1) == SHL_ENONFINITE); /* second point bad */
    CHECK(guard_intact(o, 2 * N2 + 1));
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, NAN, 1, pts, o, 1) == SHL_OK); /* b is ignored unless Taylor */
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, 0, pts, o, 1) == SHL_OK);
    CHECK(o[N2] == GUARD_VALUE);
    shl_grid_destroy(NULL);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Every allocation (create: 2, fill: 2, the lights' box flags and the workspace)
 * fails in turn; every thread creation of a 4-thread fill and interpolation fails
 * in turn: SHL_ENOMEM / SHL_ETHREAD, outputs untouched (nodes and box flags),
 * nothing leaked (ASan), the grid still usable.  The threaded fill runs on a
 * 12 x 12 x 3 grid: 7 blocks of 64 nodes (float fill), so 4 threads are made. */
SHL_TEST(grid_alloc_and_thread_failures)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    enum { N2 = 3 * SHL_NCOEFFS(2) };
    shl_lights *l;
    const double white[3] = {1, 1, 1};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_polygon(l, quad_light, 4, white, 1) == SHL_OK);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    const int res[3] = {3, 3, 3}, idx[3] = {1, 1, 1};
    int nomem = 0;
    for (long fail = 0;; ++fail) {
        shl_grid *g = NULL;
        shl__alloc_fail_after = fail;
        int st = shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &g);
        if (st == SHL_OK) st = shl_grid_fill(g, l, 2);
        shl__alloc_fail_after = -1;
        if (st == SHL_OK) {
            shl_grid_destroy(g);
            break;
        }
        CHECK(st == SHL_ENOMEM);
        ++nomem;
        if (g) {
            double v[N2];
            int nin = -1;
            CHECK(shl_grid_get_node(g, idx, v, NULL) == SHL_OK && v[0] == 0.0); /* fill wrote nothing */
            CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 0, NULL, &nin) == SHL_OK && nin == 0);
            shl_grid_destroy(g);
        }
    }
    CHECK(nomem == 4);

    shl_grid *g = NULL;
    const int res_t[3] = {12, 12, 3};
    CHECK(shl_grid_create(ctx, lo, hi, res_t, SHL_GRID_FLOAT, &g) == SHL_OK);
    int ethread = 0;
    for (long fail = 0; fail < 3; ++fail) {
        shl__thread_fail_after = fail;
        const int st = shl_grid_fill(g, l, 4);
        shl__thread_fail_after = -1;
        CHECK(st == SHL_ETHREAD);
        ethread += st == SHL_ETHREAD;
        double v[N2], vg[3 * N2];
        int nin = -1, written = 0; /* every node, values and gradients, still 0 */
        for (int n = 0; n < res_t[0] * res_t[1] * res_t[2]; ++n) {
            const int ni[3] = {n % res_t[0], n / res_t[0] % res_t[1], n / res_t[0] / res_t[1]};
            CHECK(shl_grid_get_node(g, ni, v, vg) == SHL_OK);
            for (int k = 0; k < N2; ++k) written += v[k] != 0.0 || vg[k] != 0.0 || vg[N2 + k] != 0.0 || vg[2 * N2 + k] != 0.0;
        }
        CHECK(written == 0);
        CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 0, NULL, &nin) == SHL_OK && nin == 0);
    }
    CHECK(shl_grid_fill(g, l, 4) == SHL_OK);
    int nnear = -1; /* the quad at z = 1.5 is 0.5 above the box, within one spacing (h = 1) */
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 0, NULL, &nnear) == SHL_OK && nnear == 1);
    enum { NP = 2000 };
    static double pts[3 * NP], o[NP * N2 + 1], want[NP * N2];
    for (int i = 0; i < 3 * NP; ++i) pts[i] = -1.0 + 2.0 * i / (3 * NP);
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, NP, pts, want, 1) == SHL_OK);
    for (long fail = 0; fail < 3; ++fail) {
        guard_fill(o, NP * N2 + 1);
        shl__thread_fail_after = fail;
        const int st = shl_grid_interp(g, SHL_INTERP_HERMITE, 0, NP, pts, o, 4);
        shl__thread_fail_after = -1;
        CHECK(st == SHL_ETHREAD);
        ethread += st == SHL_ETHREAD;
        CHECK(guard_intact(o, NP * N2 + 1));
    }
    CHECK(shl_grid_interp(g, SHL_INTERP_HERMITE, 0, NP, pts, o, 4) == SHL_OK);
    CHECK(memcmp(o, want, sizeof want) == 0);
    harness_note("%d allocation failures, %d thread-creation failures handled", nomem, ethread);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Taylor weights of huge and tiny cells (issue 8, K5): the box, the point and the
 * node values times (1, 2^-k for gradients) at scale 2^k are exact, and the
 * weights are ratios of distances taken in units of a power of two, so the
 * interpolated values must equal the scale-1 ones bit for bit (scale 1 is
 * checked against polynomials in grid_interp_reproduces_polynomials).  Before:
 * NaN above 2^511, equal weights below 2^-537.  Double storage: the reference kernel. */
SHL_TEST(grid_taylor_extreme_cells)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(1, &ctx) == SHL_OK);
    enum { N1 = 3 * SHL_NCOEFFS(1) };
    const int res[3] = {2, 3, 2}, ks[] = {-1000, -600, 600, 1000};
    const double lo1[3] = {-1, 0, 0.5}, hi1[3] = {1, 1, 2.5}, p1[6] = {0.25, 0.375, 1.0, -0.75, 0.875, 2.25};
    double ref[2 * N1], out[2 * N1];
    int bad = 0;
    for (int s = -1; s < (int)(sizeof ks / sizeof ks[0]); ++s) {
        const int k = s < 0 ? 0 : ks[s];
        double lo[3], hi[3], p[6];
        for (int a = 0; a < 3; ++a) lo[a] = ldexp(lo1[a], k), hi[a] = ldexp(hi1[a], k);
        for (int i = 0; i < 6; ++i) p[i] = ldexp(p1[i], k);
        shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
        for (int n = 0; n < 12; ++n) {
            const int idx[3] = {n % 2, n / 2 % 3, n / 6};
            double v[N1], gr[3 * N1];
            for (int i = 0; i < N1; ++i) v[i] = 0.125 * ((n * 7 + i * 3) % 11) - 0.5;
            for (int i = 0; i < 3 * N1; ++i) gr[i] = ldexp(0.25 * ((n * 5 + i) % 7) - 0.75, -k); /* d/dx scales by 2^-k */
            CHECK(shl_grid_set_node(g, idx, v, gr) == SHL_OK);
        }
        CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, 2.0, 2, p, s < 0 ? ref : out, 1) == SHL_OK);
        if (s >= 0) bad += memcmp(ref, out, sizeof out) != 0;
        shl_grid_destroy(g);
    }
    CHECK(bad == 0 && all_finite(ref, 2 * N1));
    harness_note("cells 2^-1000..2^1000: %d of 4 scales differ from scale 1", bad);
    shl_ctx_destroy(ctx);
}

/* Taylor weights of a sliver cell, x side 2^-1000, y and z sides 2^100 (found by
 * fuzz_grid: distances in one unit for all three sides lost the x component, so
 * a node was averaged with its x neighbour).  Closed forms: at each corner the
 * node's value exactly (Annen 2004 Eq. 16 with d_j = 0); at the middle of an
 * x edge the two ends weigh 1/2 each and the others (2^-1001 / 2^100)^b = 0,
 * so c = (c_0 + g_0 . d_0 + c_1 + g_1 . d_1) / 2 with d = -+(h_x / 2, 0, 0). */
SHL_TEST(grid_taylor_sliver_cell)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(1, &ctx) == SHL_OK);
    enum { N1 = 3 * SHL_NCOEFFS(1) };
    const double hx = ldexp(1.0, -1000), hy = ldexp(1.0, 100);
    const double lo[3] = {0.0, -hy, 0.0}, hi[3] = {hx, 0.0, hy};
    const int res[3] = {2, 2, 2};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    double v[8][N1], gr[8][3 * N1];
    for (int n = 0; n < 8; ++n) {
        const int idx[3] = {n & 1, (n >> 1) & 1, n >> 2};
        for (int i = 0; i < N1; ++i) v[n][i] = 0.125 * ((n * 7 + i * 3) % 11) - 0.5;
        for (int i = 0; i < 3 * N1; ++i) gr[n][i] = ldexp(0.25 * ((n * 5 + i) % 7) - 0.75, 990);
        CHECK(shl_grid_set_node(g, idx, v[n], gr[n]) == SHL_OK);
    }
    double max_corner = 0.0, max_edge = 0.0, out[N1];
    const double hxg = hi[0] - lo[0];
    for (int n = 0; n < 8; ++n) {
        const double p[3] = {n & 1 ? hi[0] : lo[0], n & 2 ? hi[1] : lo[1], n & 4 ? hi[2] : lo[2]};
        CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, 2.0, 1, p, out, 1) == SHL_OK);
        for (int i = 0; i < N1; ++i) max_corner = fmax(max_corner, fabs(out[i] - v[n][i]));
    }
    for (int n = 0; n < 8; n += 2) { /* the x edge from node n to node n + 1 */
        const double p[3] = {lo[0] + 0.5 * hxg, n & 2 ? hi[1] : lo[1], n & 4 ? hi[2] : lo[2]};
        CHECK(shl_grid_interp(g, SHL_INTERP_TAYLOR, 2.0, 1, p, out, 1) == SHL_OK);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < N1 / 3; ++k) {
                const int i = c * (N1 / 3) + k, ix = 3 * c * (N1 / 3) + k; /* d value i / dx (layout of shl_lights_eval) */
                const double want = 0.5 * (v[n][i] + gr[n][ix] * (0.5 * hxg) + v[n + 1][i] - gr[n + 1][ix] * (0.5 * hxg));
                max_edge = fmax(max_edge, fabs(out[i] - want) / (fabs(v[n][i]) + fabs(v[n + 1][i]) + 1.0));
            }
    }
    CHECK(max_corner == 0.0);
    CHECK(max_edge <= 8.0 * DBL_EPSILON);
    harness_note("sliver cell 2^-1000 x 2^100 x 2^100: corners exact (max err %.1e), x-edge midpoints %.1e of scale",
                 max_corner, max_edge);
    shl_grid_destroy(g);
    shl_ctx_destroy(ctx);
}

/* ---- lights meeting the box, clamped points (issue 13, item 6) ---- */

/* The lights of the last fill meeting the box (which = SHL_GRID_IN_BOX / _NEAR_BOX) as a bit mask. */
static unsigned box_mask(const shl_grid *g, int which)
{
    int idx[32], n = -1;
    CHECK(shl_grid_lights_in_box(g, which, 32, idx, &n) == SHL_OK && n >= 0 && n <= 32);
    unsigned m = 0;
    for (int i = 0; i < n; ++i) {
        CHECK(idx[i] >= 0 && idx[i] < 32 && (i == 0 || idx[i] > idx[i - 1]));
        m |= 1u << idx[i];
    }
    return m;
}

/* Spheres around the box [0,1]^3 (spacing h = 0.5): expected flags from the closed-form
 * distance centre-box, d = |c - clamp(c)|, against r (in box) and from the grown box
 * [-0.5, 1.5]^3 (near).  Distances and radii are chosen so that d^2 and r^2 are exact
 * or differ by far more than rounding. */
SHL_TEST(grid_lights_in_box_spheres)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, white[3] = {1, 1, 1};
    const int res[3] = {3, 3, 3};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    int n = -1;
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 0, NULL, &n) == SHL_OK && n == 0); /* before any fill */
    static const struct { double c[3], r; int in, near; } S[] = {
        {{0.5, 0.5, 0.5}, 0.1, 1, 1},      /* inside */
        {{0.5, 0.5, 2.0}, 1.0, 1, 1},      /* touches the face z = 1: d = r = 1 */
        {{0.5, 0.5, 2.0}, 0.999, 0, 1},    /* d = 1 > r; grown box: d = 0.5 */
        {{2.0, 2.0, 2.0}, 1.7, 0, 1},      /* d = sqrt 3 = 1.732 > r, its bounding box overlaps; grown: d = 0.866 */
        {{2.0, 2.0, 2.0}, 1.75, 1, 1},     /* d = sqrt 3 < r */
        {{10.0, 10.0, 10.0}, 1.0, 0, 0},   /* far */
        {{0.5, 0.5, 0.5}, 100.0, 1, 1},    /* the box inside the ball */
        {{0.5, -1.0, 0.5}, 0.5, 0, 1},     /* d = 1; grown: d = 0.5 = r (touching) */
        {{0.5, -1.0, 0.5}, 0.499, 0, 0},   /* grown: d = 0.5 > r */
    };
    enum { NS = sizeof S / sizeof S[0] };
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    unsigned want_in = 0, want_near = 0;
    for (int i = 0; i < NS; ++i) {
        CHECK(shl_lights_add_sphere(l, S[i].c, S[i].r, white) == SHL_OK);
        want_in |= (unsigned)S[i].in << i;
        want_near |= (unsigned)S[i].near << i;
    }
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    const unsigned in = box_mask(g, SHL_GRID_IN_BOX), near = box_mask(g, SHL_GRID_NEAR_BOX);
    CHECK(in == want_in);
    CHECK(near == want_near);
    harness_note("%d spheres: in-box mask %#x (want %#x), near-box mask %#x (want %#x)", NS, in, want_in, near, want_near);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Polygons around the box [0,1]^3 (h = 0.5, grown box [-0.5, 1.5]^3), flags worked out by hand. */
SHL_TEST(grid_lights_in_box_polygons)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, white[3] = {1, 1, 1};
    const int res[3] = {3, 3, 3};
    static const struct { int n; double v[8][3]; int in, near; } P[] = {
        /* a small triangle inside */
        {3, {{0.2, 0.2, 0.5}, {0.8, 0.2, 0.5}, {0.5, 0.8, 0.6}}, 1, 1},
        /* crosses the face z = 1 (plane x = 0.5) */
        {4, {{0.5, 0.2, 0.5}, {0.5, 0.8, 0.5}, {0.5, 0.8, 1.5}, {0.5, 0.2, 1.5}}, 1, 1},
        /* plane x + y + z = 3.2 beyond the corner (1,1,1); its bounding box [0, 3.2]^3 holds the box;
         * distance to the corner 0.2 / sqrt 3 < h */
        {3, {{3.2, 0, 0}, {0, 3.2, 0}, {0, 0, 3.2}}, 0, 1},
        /* plane x + y + z = 3 touches the corner (1,1,1), which is inside the triangle */
        {3, {{3, 0, 0}, {0, 3, 0}, {0, 0, 3}}, 1, 1},
        /* concave U at z = 0.5 whose notch (-0.2 < x < 1.2, y > -0.2) holds the box's section: the
         * polygon misses the box by 0.2 (its convex hull and bounding box contain it) */
        {8, {{-1, -1, 0.5}, {2, -1, 0.5}, {2, 3, 0.5}, {1.2, 3, 0.5}, {1.2, -0.2, 0.5}, {-0.2, -0.2, 0.5},
             {-0.2, 3, 0.5}, {-1, 3, 0.5}}, 0, 1},
        /* a quad at z = 0.5 larger than the box: no edge meets it, the section lies inside */
        {4, {{-5, -5, 0.5}, {5, -5, 0.5}, {5, 5, 0.5}, {-5, 5, 0.5}}, 1, 1},
        /* the same in the plane of the face z = 1 (touching), and just above it */
        {4, {{-5, -5, 1}, {5, -5, 1}, {5, 5, 1}, {-5, 5, 1}}, 1, 1},
        {4, {{-5, -5, 1.25}, {5, -5, 1.25}, {5, 5, 1.25}, {-5, 5, 1.25}}, 0, 1},
        /* in the plane z = 0.5 beside the box: x in [2, 3], 0.5 beyond the grown box */
        {3, {{2, 0.2, 0.5}, {3, 0.2, 0.5}, {2.5, 0.8, 0.5}}, 0, 0},
        /* a vertex on the face x = 1, the rest outside */
        {3, {{1, 0.5, 0.5}, {2, 0.2, 0.5}, {2, 0.8, 0.5}}, 1, 1},
        /* an edge through the box's edge x = 1, z = 1 at y = 0.5 (the vertices outside) */
        {3, {{0.5, 0.5, 1.5}, {1.5, 0.5, 0.5}, {3, 0.5, 3}}, 1, 1},
        /* collinear vertices: a segment crossing the box */
        {3, {{-1, 0.5, 0.5}, {0.5, 0.5, 0.5}, {2, 0.5, 0.5}}, 1, 1},
        /* its plane x + y + z = 1.5 crosses the box, the triangle lies far away in it */
        {3, {{10, -4, -4.5}, {11, -4, -5.5}, {10, -3, -5.5}}, 0, 0},
        /* one-sided quad facing away: geometry alone counts (the crossing quad above, reversed) */
        {4, {{0.5, 0.2, 1.5}, {0.5, 0.8, 1.5}, {0.5, 0.8, 0.5}, {0.5, 0.2, 0.5}}, 1, 1},
    };
    enum { NP = sizeof P / sizeof P[0] };
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    unsigned want_in = 0, want_near = 0;
    for (int i = 0; i < NP; ++i) {
        CHECK(shl_lights_add_polygon(l, &P[i].v[0][0], P[i].n, white, i == NP - 1 ? 0 : 1) == SHL_OK);
        want_in |= (unsigned)P[i].in << i;
        want_near |= (unsigned)P[i].near << i;
    }
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_DOUBLE);
    CHECK(shl_grid_fill(g, l, 1) == SHL_OK);
    const unsigned in = box_mask(g, SHL_GRID_IN_BOX), near = box_mask(g, SHL_GRID_NEAR_BOX);
    CHECK(in == want_in);
    CHECK(near == want_near);
    harness_note("%d polygons: in-box mask %#x (want %#x), near-box mask %#x (want %#x)", NP, in, want_in, near, want_near);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Separating-axis gap between the triangle t and the box [lo, hi] (Akenine-Moller 2001):
 * the largest, over the 13 axes (3 box normals, the triangle's normal, the 9 products
 * box normal x edge), of the distance between the two projections, in long double.
 * Two convex sets are disjoint iff some axis separates them, so > 0 iff disjoint. */
static long double sat_gap(double t[3][3], const double lo[3], const double hi[3])
{
    long double v[3][3], e[3], f[3][3], axes[13][3], gap = -INFINITY;
    for (int k = 0; k < 3; ++k) {
        const long double c = 0.5L * ((long double)lo[k] + hi[k]);
        e[k] = 0.5L * ((long double)hi[k] - lo[k]);
        for (int i = 0; i < 3; ++i) v[i][k] = t[i][k] - c;
    }
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) f[i][k] = v[(i + 1) % 3][k] - v[i][k];
    int na = 0;
    for (int k = 0; k < 3; ++k, ++na)
        for (int a = 0; a < 3; ++a) axes[na][a] = a == k;
    axes[na][0] = f[0][1] * f[1][2] - f[0][2] * f[1][1];
    axes[na][1] = f[0][2] * f[1][0] - f[0][0] * f[1][2];
    axes[na][2] = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    ++na;
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i, ++na) { /* u_k x f_i */
            axes[na][k] = 0.0L;
            axes[na][(k + 1) % 3] = -f[i][(k + 2) % 3];
            axes[na][(k + 2) % 3] = f[i][(k + 1) % 3];
        }
    for (int j = 0; j < na; ++j) {
        const long double *L = axes[j];
        const long double len = sqrtl(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
        if (len < 1e-30L) continue; /* an edge parallel to a box normal */
        long double mn = INFINITY, mx = -INFINITY, r = 0.0L;
        for (int i = 0; i < 3; ++i) {
            const long double p = L[0] * v[i][0] + L[1] * v[i][1] + L[2] * v[i][2];
            mn = fminl(mn, p);
            mx = fmaxl(mx, p);
        }
        for (int k = 0; k < 3; ++k) r += e[k] * fabsl(L[k]);
        gap = fmaxl(gap, fmaxl(mn - r, -r - mx) / len);
    }
    return gap;
}

/* Random triangles, concave star polygons and spheres around a box: the flags against
 * independent references -- the triangles' and the stars' fan triangles' separating-axis
 * gaps (a star meets the box iff one of its fan triangles from its centre does), the
 * spheres' closed-form distance -- for the box and the box grown by h.  Cases within 1e-9
 * of touching are skipped (rounding decides them; the gaps are computed in long double). */
SHL_TEST(grid_lights_in_box_random_vs_sat)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(0, &ctx) == SHL_OK);
    const double lo[3] = {-0.5, 0.0, 0.25}, hi[3] = {1.0, 0.75, 2.0}, white[3] = {1, 1, 1};
    const int res[3] = {3, 3, 3};
    double glo[3], ghi[3];
    for (int a = 0; a < 3; ++a) {
        const double h = (hi[a] - lo[a]) / (res[a] - 1);
        glo[a] = lo[a] - h;
        ghi[a] = hi[a] + h;
    }
    enum { NL = 3000 };
    static signed char want[2][NL]; /* [in, near][light]: 1, 0, or -1 (too close to call) */
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    rng_t r = {77};
    int skipped = 0;
    for (int i = 0; i < NL; ++i) {
        double c[3], nrm[3], v[3 * 9];
        for (int a = 0; a < 3; ++a) c[a] = rng_range(&r, lo[a] - 1.0, hi[a] + 1.0);
        const int kind = i % 3; /* triangle, star, sphere */
        const double size = rng_range(&r, 0.05, 1.5);
        long double gap[2] = {INFINITY, INFINITY};
        if (kind == 2) {
            CHECK(shl_lights_add_sphere(l, c, size, white) == SHL_OK);
            for (int b = 0; b < 2; ++b) {
                long double d2 = 0.0L;
                for (int a = 0; a < 3; ++a) {
                    const long double bl = b ? glo[a] : lo[a], bh = b ? ghi[a] : hi[a];
                    const long double d = c[a] < bl ? bl - c[a] : c[a] > bh ? c[a] - bh : 0.0L;
                    d2 += d * d;
                }
                gap[b] = sqrtl(d2) - size;
            }
        } else {
            const int n = kind == 0 ? 3 : 5 + (int)(rng_uniform(&r) * 5);
            rng_unit_vector(&r, nrm);
            random_polygon(&r, n, kind == 1, c, nrm, size, v);
            CHECK(shl_lights_add_polygon(l, v, n, white, 1) == SHL_OK);
            for (int b = 0; b < 2; ++b)
                for (int j = 0; j < (kind == 0 ? 1 : n); ++j) {
                    double t[3][3];
                    for (int a = 0; a < 3; ++a) {
                        t[0][a] = kind == 0 ? v[a] : c[a];
                        t[1][a] = kind == 0 ? v[3 + a] : v[3 * j + a];
                        t[2][a] = kind == 0 ? v[6 + a] : v[3 * ((j + 1) % n) + a];
                    }
                    gap[b] = fminl(gap[b], sat_gap(t, b ? glo : lo, b ? ghi : hi));
                }
        }
        for (int b = 0; b < 2; ++b) want[b][i] = fabsl(gap[b]) < 1e-9L ? -1 : gap[b] <= 0.0L;
        skipped += want[0][i] < 0 || want[1][i] < 0;
    }
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    static int idx[NL];
    int bad = 0, count[2] = {0, 0};
    for (int b = 0; b < 2; ++b) {
        int n = -1;
        CHECK(shl_grid_lights_in_box(g, b ? SHL_GRID_NEAR_BOX : SHL_GRID_IN_BOX, NL, idx, &n) == SHL_OK);
        count[b] = n;
        for (int i = 0, k = 0; i < NL; ++i) {
            const int got = k < n && idx[k] == i;
            k += got;
            bad += want[b][i] >= 0 && got != want[b][i];
        }
    }
    CHECK(bad == 0);
    CHECK(count[0] > NL / 10 && count[1] > count[0] && count[1] < NL - NL / 10); /* both outcomes well represented */
    harness_note("%d lights (1/3 each triangles, concave stars, spheres): %d in box, %d near; %d mismatches, %d too close to call",
                 NL, count[0], count[1], bad, skipped);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* The flags follow the last successful fill: a refill with another set replaces them,
 * a failed fill (bad nthreads) keeps them; a short index buffer gets the first cap
 * indices, the rest untouched; bad arguments write nothing. */
SHL_TEST(grid_lights_in_box_refill_and_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(1, &ctx) == SHL_OK);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, white[3] = {1, 1, 1};
    const double in1[3] = {0.5, 0.5, 0.5}, in2[3] = {0.9, 0.1, 0.2}, far[3] = {9, 9, 9};
    const int res[3] = {2, 2, 2};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    shl_lights *a = NULL, *b = NULL;
    CHECK(shl_lights_create(&a) == SHL_OK);
    CHECK(shl_lights_create(&b) == SHL_OK);
    CHECK(shl_lights_add_sphere(a, far, 0.5, white) == SHL_OK);   /* 0: out */
    CHECK(shl_lights_add_sphere(a, in1, 0.1, white) == SHL_OK);   /* 1: in */
    CHECK(shl_lights_add_polygon(a, quad_light, 4, white, 1) == SHL_OK); /* 2: z = 1.5, near (h = 1) */
    CHECK(shl_lights_add_sphere(a, in2, 0.05, white) == SHL_OK);  /* 3: in */
    CHECK(shl_lights_add_sphere(b, far, 0.5, white) == SHL_OK);
    int idx[4] = {-7, -7, -7, -7}, n = -1;
    CHECK(shl_grid_fill(g, a, 1) == SHL_OK);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 4, idx, &n) == SHL_OK && n == 2 && idx[0] == 1 && idx[1] == 3 && idx[2] == -7);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 2, idx, &n) == SHL_OK && n == 3 && idx[0] == 1 && idx[1] == 2 && idx[2] == -7);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 0, idx, &n) == SHL_OK && n == 2 && idx[0] == 1); /* cap 0: count only */
    const int n_in = n;
    /* bad arguments: nothing written */
    n = -1;
    idx[0] = -7;
    CHECK(shl_grid_lights_in_box(NULL, SHL_GRID_IN_BOX, 4, idx, &n) == SHL_ENULL);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 4, idx, NULL) == SHL_ENULL);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 1, NULL, &n) == SHL_ENULL);
    CHECK(shl_grid_lights_in_box(g, 2, 4, idx, &n) == SHL_EDOMAIN);
    CHECK(shl_grid_lights_in_box(g, -1, 4, idx, &n) == SHL_EDOMAIN);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, -1, idx, &n) == SHL_EDOMAIN);
    CHECK(n == -1 && idx[0] == -7);
    /* a failed fill keeps the flags; later additions to the set count only after a refill */
    CHECK(shl_grid_fill(g, b, 0) == SHL_EDOMAIN);
    CHECK(shl_lights_add_sphere(a, in1, 0.2, white) == SHL_OK);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 0, NULL, &n) == SHL_OK && n == n_in);
    CHECK(shl_grid_fill(g, a, 2) == SHL_OK);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 4, idx, &n) == SHL_OK && n == 3 && idx[2] == 4);
    CHECK(shl_grid_fill(g, b, 1) == SHL_OK);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 4, idx, &n) == SHL_OK && n == 0);
    shl_lights_destroy(b); /* an empty set */
    CHECK(shl_lights_create(&b) == SHL_OK);
    CHECK(shl_grid_fill(g, a, 1) == SHL_OK && shl_grid_fill(g, b, 1) == SHL_OK);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 4, idx, &n) == SHL_OK && n == 0);
    harness_note("first fill: %d lights in box, refills replace and failed fills keep the flags", n_in);
    shl_grid_destroy(g);
    shl_lights_destroy(a);
    shl_lights_destroy(b);
    shl_ctx_destroy(ctx);
}

/* What the flags warn of: a sphere light inside an 8^3 box, then half a spacing
 * outside it.  Reference: direct evaluation (shl_lights_eval_batch; inside the ball
 * sqrt(4 pi) in L00).  The errors are recorded, not bounded: the interpolants are not
 * meant to resolve a kink in a cell or a field varying on the scale of a cell. */
SHL_TEST(grid_sphere_in_box_reported)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l;
    const double white[3] = {1, 1, 1}, c[3] = {0.05, -0.1, 0.0};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_sphere(l, c, 0.3, white) == SHL_OK);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    const int res[3] = {8, 8, 8};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 2) == SHL_OK);
    int n = -1, i0 = -1;
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 1, &i0, &n) == SHL_OK && n == 1 && i0 == 0);
    double ref[NV], out[NV], err_c[3];
    CHECK(shl_lights_eval(ctx, l, c, ref, NULL) == SHL_OK);
    CHECK_NEAR(ref[0], sqrt(4.0 * M_PI), 16 * DBL_EPSILON); /* the documented value inside the ball, to rounding */
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 2.0, 1, c, out, 1) == SHL_OK);
        err_c[m] = fabs(out[0] - ref[0]) / ref[0];
    }
    enum { NP = 2000 }; /* random points within 0.3 of the sphere's surface */
    static double pts[3 * NP], refs[NP * NV], outs[NP * NV];
    rng_t r = {5};
    for (int p = 0; p < NP; ++p) {
        double u[3];
        rng_unit_vector(&r, u);
        const double d = rng_range(&r, 0.0, 0.6);
        for (int a = 0; a < 3; ++a) pts[3 * p + a] = c[a] + d * u[a];
    }
    CHECK(shl_lights_eval_batch(ctx, l, NP, pts, refs, NULL) == SHL_OK);
    double err[3] = {0, 0, 0};
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 2.0, NP, pts, outs, 2) == SHL_OK);
        for (int p = 0; p < NP; ++p) err[m] = fmax(err[m], fabs(outs[p * NV] - refs[p * NV]) / sqrt(4.0 * M_PI));
    }
    /* the same sphere moved to 0.15 (half a spacing) outside the face x = 1: near, not in */
    shl_lights *l2;
    const double c2[3] = {1.45, -0.1, 0.0};
    CHECK(shl_lights_create(&l2) == SHL_OK);
    CHECK(shl_lights_add_sphere(l2, c2, 0.3, white) == SHL_OK);
    CHECK(shl_grid_fill(g, l2, 2) == SHL_OK);
    int n_in = -1, n_near = -1;
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_IN_BOX, 0, NULL, &n_in) == SHL_OK && n_in == 0);
    CHECK(shl_grid_lights_in_box(g, SHL_GRID_NEAR_BOX, 0, NULL, &n_near) == SHL_OK && n_near == 1);
    for (int p = 0; p < NP; ++p) { /* points of the box within 0.6 of the face x = 1 */
        pts[3 * p] = rng_range(&r, 0.4, 1.0);
        pts[3 * p + 1] = rng_range(&r, -1.0, 1.0);
        pts[3 * p + 2] = rng_range(&r, -1.0, 1.0);
    }
    CHECK(shl_lights_eval_batch(ctx, l2, NP, pts, refs, NULL) == SHL_OK);
    double err2[3] = {0, 0, 0}, scale2 = 0.0;
    for (int p = 0; p < NP; ++p) scale2 = fmax(scale2, fabs(refs[p * NV]));
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 2.0, NP, pts, outs, 2) == SHL_OK);
        for (int i = 0; i < NP * NV; ++i) err2[m] = fmax(err2[m], fabs(outs[i] - refs[i]) / scale2);
    }
    harness_note("sphere r 0.3 in an 8^3 box (h 0.29): L00 at its centre off by %.0f%%/%.0f%%/%.0f%% (trilinear/Taylor/Hermite); "
                 "within 0.3 of its surface max L00 error %.0f%%/%.0f%%/%.0f%% of sqrt(4 pi); moved 0.15 outside the box "
                 "(near): max error %.0f%%/%.0f%%/%.0f%% of max |L00|",
                 100 * err_c[0], 100 * err_c[1], 100 * err_c[2], 100 * err[0], 100 * err[1], 100 * err[2], 100 * err2[0],
                 100 * err2[1], 100 * err2[2]);
    shl_grid_destroy(g);
    shl_lights_destroy(l2);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Clamped counts: a point is clamped iff a coordinate lies outside [lo[a], hi[a]]; points on
 * faces, edges and corners (and -0.0 on a face at 0) are inside.  The expected count comes
 * from the construction of each point, the values must equal shl_grid_interp's bit for bit
 * for every method and thread count. */
SHL_TEST(grid_interp_clamped_counts)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l = two_lights();
    const double lo[3] = {-1.0, 0.0, 0.5}, hi[3] = {1.0, 2.0, 1.5};
    const int res[3] = {4, 3, 5};
    shl_grid *g = new_grid(ctx, lo, hi, res, SHL_GRID_FLOAT);
    CHECK(shl_grid_fill(g, l, 1) == SHL_OK);
    const double up = nextafter(1.5, 2.0), dn = nextafter(-1.0, -2.0);
    const double P[][4] = { /* x, y, z, clamped */
        {0.0, 1.0, 1.0, 0},   {-1.0, 1.0, 1.0, 0}, {1.0, 1.0, 1.0, 0},  {0.3, 0.0, 1.0, 0}, {0.3, -0.0, 1.0, 0},
        {0.3, 2.0, 1.5, 0},   {-1.0, 0.0, 0.5, 0}, {1.0, 2.0, 1.5, 0},  {0.2, 1.0, up, 1},  {dn, 1.0, 1.0, 1},
        {5.0, 1.0, 1.0, 1},   {0.0, -1e-300, 1.0, 1}, {0.0, 1.0, -3.0, 1}, {9.0, 9.0, 9.0, 1}, {-1e300, 1.0, 1.0, 1},
        {0.5, 0.5, 0.75, 0},  {1.0, 2.5, 0.5, 1},
    };
    enum { NPT = sizeof P / sizeof P[0] };
    double pts[3 * NPT];
    int want = 0;
    for (int p = 0; p < NPT; ++p) {
        for (int a = 0; a < 3; ++a) pts[3 * p + a] = P[p][a];
        want += (int)P[p][3];
    }
    static double a[NPT * NV], b[NPT * NV];
    int bad = 0;
    for (int m = 0; m < 3; ++m) {
        CHECK(shl_grid_interp(g, m, 1.5, NPT, pts, a, 1) == SHL_OK);
        const int threads[3] = {1, 2, 3};
        for (int t = 0; t < 3; ++t) {
            int nclamped = -1;
            CHECK(shl_grid_interp_clamped(g, m, 1.5, NPT, pts, b, threads[t], &nclamped) == SHL_OK);
            bad += nclamped != want || memcmp(a, b, sizeof a) != 0;
        }
        int n1 = -1; /* point by point */
        for (int p = 0; p < NPT; ++p) {
            int c1 = -1;
            CHECK(shl_grid_interp_clamped(g, m, 1.5, 1, pts + 3 * p, b, 1, &c1) == SHL_OK);
            bad += c1 != (int)P[p][3];
            n1 += c1;
        }
        bad += n1 + 1 != want;
    }
    CHECK(bad == 0);
    int nclamped = -1; /* no points */
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 0, pts, b, 1, &nclamped) == SHL_OK && nclamped == 0);
    /* bad input: status as shl_grid_interp, nothing written (count and values) */
    double o[NV + 1];
    const double badpt[6] = {0.0, 1.0, 1.0, 0.0, NAN, 1.0};
    guard_fill(o, NV + 1);
    nclamped = -1;
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 1, pts, o, 1, NULL) == SHL_ENULL);
    CHECK(shl_grid_interp_clamped(NULL, SHL_INTERP_HERMITE, 0, 1, pts, o, 1, &nclamped) == SHL_ENULL);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 1, NULL, o, 1, &nclamped) == SHL_ENULL);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 1, pts, NULL, 1, &nclamped) == SHL_ENULL);
    CHECK(shl_grid_interp_clamped(g, 3, 0, 1, pts, o, 1, &nclamped) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_TAYLOR, -1.0, 1, pts, o, 1, &nclamped) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, -1, pts, o, 1, &nclamped) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 1, pts, o, 0, &nclamped) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_clamped(g, SHL_INTERP_HERMITE, 0, 2, badpt, o, 1, &nclamped) == SHL_ENONFINITE);
    CHECK(nclamped == -1 && guard_intact(o, NV + 1));
    /* thread-creation failure: nothing written either */
    enum { NB = 1200 };
    static double many[3 * NB], mo[NB * NV + 1];
    for (int i = 0; i < 3 * NB; ++i) many[i] = -2.0 + 5.0 * i / (3 * NB);
    guard_fill(mo, NB * NV + 1);
    shl__thread_fail_after = 0;
    const int st = shl_grid_interp_clamped(g, SHL_INTERP_TRILINEAR, 0, NB, many, mo, 4, &nclamped);
    shl__thread_fail_after = -1;
    CHECK(st == SHL_ETHREAD && nclamped == -1 && guard_intact(mo, NB * NV + 1));
    harness_note("%d points (%d outside, %d on faces/edges/corners or inside): counts exact for 3 methods x 3 thread counts",
                 NPT, want, NPT - want);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Grids of at least SHL__LARGE_ARRAY bytes of nodes take the other allocation
 * (2 MiB-aligned, huge-page advice: alloc.c); nothing else may change.  A large
 * grid over [0, n-1]^3 (spacing 1) and a one-cell grid over [0,1]x[0,1]x[2,3]
 * have the same node positions (integers, exact) there, so the same fill gives
 * the same nodes, and the cell-local coordinates of a point inside the cell
 * ((p - lo) / 1, and p - 2 exact by Sterbenz) are the same: every node and every
 * interpolated value (3 methods) must be equal bit for bit; float storage at
 * lmax 8 and double storage at lmax 4.  Then allocation failure on the large
 * path: SHL_ENOMEM, *out NULL, nothing leaked (ASan). */
SHL_TEST(grid_large_allocation_bit_identical)
{
    const int lmaxes[2] = {8, 4}, storages[2] = {SHL_GRID_FLOAT, SHL_GRID_DOUBLE}, nres[2] = {11, 13};
    shl_lights *l = two_lights();
    enum { NP = 64, NCB = SHL_NCOEFFS(8) };
    static double pts[3 * NP], a[3 * NCB * NP], b[3 * NCB * NP], va[12 * NCB], vb[12 * NCB];
    uint64_t s = 99;
    for (int i = 0; i < 3 * NP; ++i) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        pts[i] = (double)(s >> 11) * 0x1p-53 * 0.96 + 0.02 + (i % 3 == 2 ? 2.0 : 0.0); /* inside the cell */
    }
    int bad = 0;
    size_t large_bytes = 0;
    for (int t = 0; t < 2; ++t) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmaxes[t], &ctx) == SHL_OK);
        const int nc = SHL_NCOEFFS(lmaxes[t]), n = nres[t], resl[3] = {n, n, n}, ress[3] = {2, 2, 2};
        int bpn;
        CHECK(shl_grid_bytes_per_node(lmaxes[t], storages[t], &bpn) == SHL_OK);
        large_bytes = (size_t)n * n * n * bpn;
        CHECK(large_bytes >= SHL__LARGE_ARRAY && 8 * (size_t)bpn < SHL__LARGE_ARRAY); /* the two paths */
        const double lol[3] = {0, 0, 0}, hil[3] = {n - 1, n - 1, n - 1}, los[3] = {0, 0, 2}, his[3] = {1, 1, 3};
        shl_grid *gl = new_grid(ctx, lol, hil, resl, storages[t]), *gs = new_grid(ctx, los, his, ress, storages[t]);
        CHECK((uintptr_t)gl->data % SHL__HUGE_PAGE == 0); /* the large path was taken */
        CHECK(shl_grid_fill(gl, l, 2) == SHL_OK && shl_grid_fill(gs, l, 1) == SHL_OK);
        for (int c = 0; c < 8; ++c) {
            const int is[3] = {c & 1, c >> 1 & 1, c >> 2}, il[3] = {is[0], is[1], is[2] + 2};
            CHECK(shl_grid_get_node(gl, il, va, va + 3 * nc) == SHL_OK && shl_grid_get_node(gs, is, vb, vb + 3 * nc) == SHL_OK);
            bad += memcmp(va, vb, sizeof(double) * 12 * nc) != 0;
            bad += va[0] == 0.0; /* the lights reach every node of the cell */
        }
        for (int m = 0; m < 3; ++m) {
            CHECK(shl_grid_interp(gl, m, 1.5, NP, pts, a, 2) == SHL_OK && shl_grid_interp(gs, m, 1.5, NP, pts, b, 1) == SHL_OK);
            bad += memcmp(a, b, sizeof(double) * 3 * nc * NP) != 0;
        }
        shl_grid_destroy(gl);
        shl_grid_destroy(gs);
        /* allocation failure, large path: the grid struct, then the node array */
        for (long fail = 0; fail < 2; ++fail) {
            shl_grid *g = (shl_grid *)&bad;
            shl__alloc_fail_after = fail;
            const int st = shl_grid_create(ctx, lol, hil, resl, storages[t], &g);
            shl__alloc_fail_after = -1;
            CHECK(st == SHL_ENOMEM && g == NULL);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0);
    harness_note("8 nodes and 3 x %d interpolated points equal bit for bit (large grids of %.1f MB and above vs one cell)",
                 NP, (double)large_bytes / 1e6);
    shl_lights_destroy(l);
}
