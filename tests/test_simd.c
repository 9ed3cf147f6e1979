/* Batched SIMD kernels (shl_polygon_batch_f) against the scalar double
 * reference (shl_polygon, shl_polygon_grad on the float-rounded input) and,
 * lane by lane, against the scalar float path (shl_polygon_f,
 * shl_polygon_grad_f), for every ISA this machine runs (contexts from
 * shl_ctx_create_isa).  Errors: coefficients relative to |L00| of the reference,
 * gradients relative to the largest reference gradient of the point. */
#include "float_tol.h"
#include "geom.h"
#include "../src/internal.h"
#include "harness.h"
#include "isa_ctx.h"
#include "ref_quad.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { LMAX = 14, NC = SHL_NCOEFFS(LMAX), NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX), MAXPTS = 40 };

/* A polygon (float) and points. */
typedef struct {
    const char *what;
    int n, npts;
    float v[3 * SHL_MAX_VERTS], p[3 * MAXPTS];
} batch_case;

/* Worst errors over points: relative to their tolerances, and raw (coefficients
 * / |L00|, gradients / max|grad|), and raw for polygons subtending theta >= 0.5 rad. */
typedef struct { double coef, grad, lane_coef, lane_grad, raw_coef, raw_grad, raw_coef_big, raw_grad_big; } errors;

/* Tolerances: float_tol.h (derived, per band).  The hard cases add the
 * conditioning term 8 FLT_EPSILON * scale * max|grad| of 1-ulp moves of the
 * inputs (scale: the largest coordinate), as test_polygon.c does in double. */

/* Run one case on ctx: every point against the double reference and against the
 * scalar float path (twice the tolerance: both carry float error), all outputs
 * finite, exact zeros where nothing is seen, guards after the outputs intact,
 * coefficients identical with and without gradients. */
static errors run_case(const shl_ctx *ctx, const batch_case *bc, int hard)
{
    const int lmax = shl_ctx_lmax(ctx), nc = SHL_NCOEFFS(lmax), np = bc->npts;
    static float c[MAXPTS * NCMAX + 1], g[3 * MAXPTS * NCMAX + 1], c2[MAXPTS * NCMAX + 1];
    static float cf[NCMAX], gf[3 * NCMAX];
    static double cr[NCMAX], gr[3 * NCMAX];
    double vd[3 * SHL_MAX_VERTS], scale = 0.0;
    errors e = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int i = 0; i < 3 * bc->n; ++i) scale = fmax(scale, fabs(vd[i] = bc->v[i]));
    c[np * nc] = c2[np * nc] = g[3 * np * nc] = 7.0f;
    CHECK(shl_polygon_batch_f(ctx, bc->v, bc->n, np, bc->p, c, g) == SHL_OK);
    CHECK(shl_polygon_batch_f(ctx, bc->v, bc->n, np, bc->p, c2, NULL) == SHL_OK);
    CHECK(c[np * nc] == 7.0f && c2[np * nc] == 7.0f && g[3 * np * nc] == 7.0f);
    for (int p = 0; p < np; ++p) {
        const double x[3] = {bc->p[3 * p], bc->p[3 * p + 1], bc->p[3 * p + 2]};
        const float *cp = c + p * nc, *gp = g + 3 * p * nc;
        double omega, gmax = 0, ec = 0, eg = 0, lc = 0, lg = 0, rc = 0, rg = 0, rlc = 0, rlg = 0, tc[SHL_LMAX_MAX + 1],
                      tg[SHL_LMAX_MAX + 1];
        int finite = 1;
        CHECK(shl_polygon_grad(ctx, x, vd, bc->n, cr, gr) == SHL_OK);
        CHECK(shl_polygon_grad_f(ctx, bc->p + 3 * p, bc->v, bc->n, cf, gf) == SHL_OK);
        CHECK(shl_polygon_solid_angle(x, vd, bc->n, &omega) == SHL_OK);
        for (int k = 0; k < 3 * nc; ++k) gmax = fmax(gmax, fabs(gr[k]));
        for (int k = 0; k < nc; ++k) finite &= isfinite(cp[k]) && cp[k] == c2[p * nc + k];
        for (int k = 0; k < 3 * nc; ++k) finite &= isfinite(gp[k]);
        CHECK(finite);
        if (omega == 0.0) { /* sees nothing: exact zeros, as the scalar paths */
            for (int k = 0; k < nc; ++k) CHECK(cp[k] == 0.0f && cf[k] == 0.0f);
            for (int k = 0; k < 3 * nc; ++k) CHECK(gp[k] == 0.0f);
            continue;
        }
        float_poly_tol(lmax, x, vd, bc->n, omega, gmax, 1, tc, tg);
        const double l00 = fabs(cr[0]), theta = sqrt(omega);
        const double cond = hard ? 8.0 * FLT_EPSILON * fmax(scale, fmax(fabs(x[0]), fmax(fabs(x[1]), fabs(x[2])))) * gmax : 0.0;
        for (int l = 0; l <= lmax; ++l)
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                const double dc = fabs(cp[k] - cr[k]), dl = fabs(cp[k] - cf[k]);
                ec = fmax(ec, dc), lc = fmax(lc, dl);
                rc = fmax(rc, dc / (tc[l] + cond)), rlc = fmax(rlc, dl / (tc[l] + cond));
                for (int a = 0; a < 3; ++a) {
                    const double dg = fabs(gp[a * nc + k] - gr[a * nc + k]), dgl = fabs(gp[a * nc + k] - gf[a * nc + k]);
                    eg = fmax(eg, dg), lg = fmax(lg, dgl);
                    rg = fmax(rg, dg / tg[l]), rlg = fmax(rlg, dgl / tg[l]);
                }
            }
        ec /= l00, eg /= gmax;
        if (!(rc <= 1.0 && rg <= 1.0 && rlc <= 2.0 && rlg <= 2.0))
            harness_fail(__FILE__, __LINE__,
                         "%s [%s, lmax %d] point %d (%a, %a, %a), theta %.2g: coeffs %.3g |L00| (error/tol %.3g), "
                         "grad %.3g max|grad| (error/tol %.3g), vs scalar float error/tol %.3g, %.3g",
                         bc->what, shl_ctx_isa(ctx), lmax, p, x[0], x[1], x[2], theta, ec, rc, eg, rg, rlc, rlg);
        e.raw_coef = fmax(e.raw_coef, ec);
        e.raw_grad = fmax(e.raw_grad, eg);
        if (theta >= 0.5) e.raw_coef_big = fmax(e.raw_coef_big, ec), e.raw_grad_big = fmax(e.raw_grad_big, eg);
        e.coef = fmax(e.coef, rc);
        e.grad = fmax(e.grad, rg);
        e.lane_coef = fmax(e.lane_coef, rlc);
        e.lane_grad = fmax(e.lane_grad, rlg);
    }
    return e;
}

static void errors_max(errors *a, errors b)
{
    a->coef = fmax(a->coef, b.coef);
    a->grad = fmax(a->grad, b.grad);
    a->lane_coef = fmax(a->lane_coef, b.lane_coef);
    a->lane_grad = fmax(a->lane_grad, b.lane_grad);
    a->raw_coef = fmax(a->raw_coef, b.raw_coef);
    a->raw_grad = fmax(a->raw_grad, b.raw_grad);
    a->raw_coef_big = fmax(a->raw_coef_big, b.raw_coef_big);
    a->raw_grad_big = fmax(a->raw_grad_big, b.raw_grad_big);
}

/* Random polygon as in test_polygon.c (triangle, quad, concave hexagon) and
 * npts points at distance 0.5..dmax from its centre, on both sides of its
 * plane and at least 0.05 off it in direction cosine. */
static void random_batch(rng_t *r, int kind, int npts, double dmax, batch_case *bc)
{
    double center[3], nrm[3], v[18];
    for (int k = 0; k < 3; ++k) center[k] = rng_range(r, -1.0, 1.0);
    rng_unit_vector(r, nrm);
    bc->n = kind == 0 ? 3 : kind == 1 ? 4 : 6;
    random_polygon(r, bc->n, kind == 2, center, nrm, rng_range(r, 0.3, 2.0), v);
    for (int i = 0; i < 3 * bc->n; ++i) bc->v[i] = (float)v[i];
    bc->npts = npts;
    for (int p = 0; p < npts; ++p) {
        double off[3];
        rng_unit_vector(r, off);
        const double dist = rng_range(r, 0.5, dmax), side = off[0] * nrm[0] + off[1] * nrm[1] + off[2] * nrm[2];
        if (fabs(side) < 0.05)
            for (int k = 0; k < 3; ++k) off[k] += (side < 0 ? -0.1 : 0.1) * nrm[k];
        for (int k = 0; k < 3; ++k) bc->p[3 * p + k] = (float)(center[k] + dist * off[k]);
    }
}

#define NOTE_ERRORS(isa, e)                                                                                   \
    harness_note("%s: coeffs %.1e |L00|, grad %.1e max|grad| (theta >= 0.5: %.1e, %.1e); worst error/tol %.2f, " \
                 "%.2f (vs scalar float %.2f, %.2f)",                                                             \
                 isa, (e).raw_coef, (e).raw_grad, (e).raw_coef_big, (e).raw_grad_big, (e).coef, (e).grad,         \
                 (e).lane_coef / 2, (e).lane_grad / 2)

SHL_TEST(simd_random_vs_double_reference)
{
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LMAX);
        if (!ctx) continue;
        rng_t r = {41};
        errors worst = {0, 0, 0, 0, 0, 0, 0, 0};
        for (int it = 0; it < 30; ++it) {
            batch_case bc = {"random", 0, 0, {0}, {0}};
            random_batch(&r, it % 3, 19, it < 15 ? 4.0 : 100.0, &bc);
            errors_max(&worst, run_case(ctx, &bc, 0));
        }
        NOTE_ERRORS(isas[i], worst);
        shl_ctx_destroy(ctx);
    }
}

SHL_TEST(simd_every_lmax)
{
    for (int i = 0; i < NISA; ++i) {
        errors worst = {0, 0, 0, 0, 0, 0, 0, 0};
        int ran = 0;
        for (int lmax = 0; lmax <= SHL_LMAX_MAX; lmax += lmax < 16 ? 1 : 7) {
            shl_ctx *ctx = isa_ctx(isas[i], lmax);
            if (!ctx) break;
            ran = 1;
            rng_t r = {(uint64_t)(100 + lmax)};
            batch_case bc = {"lmax sweep", 0, 0, {0}, {0}};
            random_batch(&r, lmax % 3, 11, 4.0, &bc);
            errors_max(&worst, run_case(ctx, &bc, 0));
            shl_ctx_destroy(ctx);
        }
        if (ran) NOTE_ERRORS(isas[i], worst);
    }
}

/* ---- hard cases of test_polygon.c and test_polygon_grad.c, in float ---- */

static void set_points(batch_case *bc, const double (*p)[3], int np)
{
    bc->npts = np;
    for (int i = 0; i < np; ++i)
        for (int k = 0; k < 3; ++k) bc->p[3 * i + k] = (float)p[i][k];
}

static void set_verts(batch_case *bc, const double *v, int n)
{
    bc->n = n;
    for (int i = 0; i < 3 * n; ++i) bc->v[i] = (float)v[i];
}

static const double unit_square[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

/* Every hard case on ctx; returns the worst errors (relative to their tolerances). */
static errors hard_cases(const shl_ctx *ctx)
{
    errors worst = {0, 0, 0, 0, 0, 0, 0, 0};
    const double r2 = M_SQRT2;
    batch_case bc = {"", 0, 0, {0}, {0}};
    /* unit square: near the plane (inside, grazing, below), in the plane (zeros),
     * on a vertex (zeros), 1e-6 from an edge, edge arc ~pi, both sides */
    const double sq_pts[][3] = {{0.3, 0.6, 1e-7},     {1.7, 0.4, 1e-7},    {0.5, 0.5, -1e-7},      {0.5, 0.5, 0},
                                {3, 0.5, 0},          {0.5, 0, 0},         {1, 1, 0},              {-2, -7, 0},
                                {0, 0, 0},            {0.2, 0.3, 0.8},     {0.5, -1e-6 / r2, 1e-6 / r2},
                                {0.5, -1e-7 / r2, 1e-7 / r2}, {0.4, 0.45, -2.5}, {0.3, 0.6, 1e-3}};
    bc.what = "unit square";
    set_verts(&bc, unit_square, 4);
    set_points(&bc, sq_pts, sizeof sq_pts / sizeof sq_pts[0]);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* tiny (1e-4 at distance 10) and huge (1e4 at distance 1) */
    const double s = 1e-4, h = 1e4;
    const double tiny[12] = {0, 0, 10, s, 0, 10, s, s, 10, 0, s, 10};
    const double huge[12] = {-h / 2, -h / 2, 1, h / 2, -h / 2, 1, h / 2, h / 2, 1, -h / 2, h / 2, 1};
    const double tiny_pts[][3] = {{0.3, -0.2, 0.0}, {0, 0, 20}, {-1, 2, 9.5}};
    const double huge_pts[][3] = {{0.3, 0.1, 0}, {0, 0, 2}, {100, -40, 0.5}, {3e3, 2e3, -1}};
    bc.what = "tiny";
    set_verts(&bc, tiny, 4);
    set_points(&bc, tiny_pts, 3);
    errors_max(&worst, run_case(ctx, &bc, 1));
    bc.what = "huge";
    set_verts(&bc, huge, 4);
    set_points(&bc, huge_pts, 4);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* repeated and collinear vertices; degenerate polygons see nothing */
    const double messy[24] = {0, 0, 0, 0, 0, 0, 0.5, 0, 0, 1, 0, 0, 1, 1, 0, 1, 1, 0, 0, 1, 0, 0, 0, 0};
    const double point[9] = {1, 2, 3, 1, 2, 3, 1, 2, 3}, segment[12] = {0, 0, 1, 1, 0, 1, 1, 0, 1, 0, 0, 1};
    const double messy_pts[][3] = {{0.2, 0.3, 0.8}, {0.5, 0.5, -0.3}, {2, 2, 2}};
    bc.what = "repeated+collinear";
    set_verts(&bc, messy, 8);
    set_points(&bc, messy_pts, 3);
    errors_max(&worst, run_case(ctx, &bc, 1));
    bc.what = "single point";
    set_verts(&bc, point, 3);
    errors_max(&worst, run_case(ctx, &bc, 1));
    bc.what = "segment";
    set_verts(&bc, segment, 4);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* concave star */
    const double star[18] = {1, 0, 2, 0.2, 0.3, 2, 0, 1, 2, -0.3, 0.1, 2, -1, -1, 2, 0.1, -0.2, 2};
    const double star_pts[][3] = {{0.1, 0.2, 0.5}, {0, 0, 3}, {0.5, 0.5, 2.01}, {-0.2, 0.1, 1.9}};
    bc.what = "concave star";
    set_verts(&bc, star, 6);
    set_points(&bc, star_pts, 4);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* an edge of length 1e-6 */
    const double short_edge[12] = {0, 0, 0, 1, 0, 0, 1, 1e-6, 0, 0, 1, 0};
    const double short_pts[][3] = {{0.3, 0.4, 0.7}, {1.0, 0.0, 0.01}, {2, 0.5, -1}};
    bc.what = "edge length 1e-6";
    set_verts(&bc, short_edge, 4);
    set_points(&bc, short_pts, 3);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* the largest polygon: SHL_MAX_VERTS vertices on a circle */
    double circle[3 * SHL_MAX_VERTS];
    for (int i = 0; i < SHL_MAX_VERTS; ++i) {
        circle[3 * i] = cos(2 * M_PI * i / SHL_MAX_VERTS);
        circle[3 * i + 1] = sin(2 * M_PI * i / SHL_MAX_VERTS);
        circle[3 * i + 2] = 1.0;
    }
    const double circle_pts[][3] = {{0, 0, 0}, {0.5, 0.2, 1.5}, {2, 0, 1}};
    bc.what = "64-gon";
    set_verts(&bc, circle, SHL_MAX_VERTS);
    set_points(&bc, circle_pts, 3);
    errors_max(&worst, run_case(ctx, &bc, 1));
    /* lobe on an edge's plane (c_e = 0, Wang 2018 Eq. 20) and on an edge plane's
     * normal (A = 0 in Wu 2020 Eq. 23), for lobes of the table */
    const int lmax = shl_ctx_lmax(ctx), lobes[4] = {0, 1, 3, 2 * lmax};
    const double origin[][3] = {{0, 0, 0}, {0.05, -0.02, 0.01}};
    for (int i = 0; i < 4; ++i) {
        const double *d = shl__zh_dir[lobes[i]];
        double u[3], w[3], v[9], vn[9];
        plane_basis(d, u, w);
        for (int k = 0; k < 3; ++k) {
            v[k] = 2.0 * (d[k] + 0.3 * u[k]);
            v[3 + k] = 1.5 * (d[k] - 0.4 * u[k]);
            v[6 + k] = 1.8 * (d[k] + 0.5 * w[k]);
            vn[k] = 1.3 * u[k];
            vn[3 + k] = 0.9 * (0.6 * u[k] + 0.8 * w[k]);
            vn[6 + k] = 1.1 * (0.3 * u[k] + 0.3 * w[k] + 0.9 * d[k]);
        }
        bc.what = "lobe on edge plane";
        set_verts(&bc, v, 3);
        set_points(&bc, origin, 2);
        errors_max(&worst, run_case(ctx, &bc, 1));
        bc.what = "lobe on edge-plane normal";
        set_verts(&bc, vn, 3);
        errors_max(&worst, run_case(ctx, &bc, 1));
    }
    return worst;
}

SHL_TEST(simd_hard_cases)
{
    for (int i = 0; i < NISA; ++i) {
        const int lmaxes[2] = {LMAX, SHL_LMAX_MAX};
        for (int j = 0; j < 2; ++j) {
            shl_ctx *ctx = isa_ctx(isas[i], lmaxes[j]);
            if (!ctx) continue;
            const errors e = hard_cases(ctx);
            harness_note("%s lmax %d: worst error/tol coeffs %.2f, grad %.2f (vs scalar float %.2f, %.2f)", isas[i],
                         lmaxes[j], e.coef, e.grad, e.lane_coef / 2, e.lane_grad / 2);
            shl_ctx_destroy(ctx);
        }
    }
}

/* Point counts 1..17 around the vector widths: the first npts results equal, bit
 * for bit, those of one batch of 17 and of the same points at other lane
 * positions; nothing is written outside the outputs. */
SHL_TEST(simd_tails_and_lane_independence)
{
    enum { NP = 17, LM = 5, NCL = SHL_NCOEFFS(LM) };
    rng_t r = {77};
    batch_case bc = {"tails", 0, 0, {0}, {0}};
    random_batch(&r, 1, NP + 1, 3.0, &bc);
    memcpy(bc.p + 3 * 5, bc.v + 3, sizeof(float) * 3); /* point 5 on vertex 1: zeros */
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        static float full_c[NP * NCL], full_g[3 * NP * NCL], c[NP * NCL + 2], g[3 * NP * NCL + 2];
        CHECK(shl_polygon_batch_f(ctx, bc.v, bc.n, NP, bc.p, full_c, full_g) == SHL_OK);
        for (int np = 1; np <= NP; ++np)
            for (int shift = 0; shift <= 1 && shift + np <= NP; ++shift) {
                for (int k = 0; k < np * NCL + 2; ++k) c[k] = 7.0f;
                for (int k = 0; k < 3 * np * NCL + 2; ++k) g[k] = 7.0f;
                CHECK(shl_polygon_batch_f(ctx, bc.v, bc.n, np, bc.p + 3 * shift, c + 1, g + 1) == SHL_OK);
                CHECK(c[0] == 7.0f && c[np * NCL + 1] == 7.0f && g[0] == 7.0f && g[3 * np * NCL + 1] == 7.0f);
                CHECK(memcmp(c + 1, full_c + shift * NCL, sizeof(float) * np * NCL) == 0);
                CHECK(memcmp(g + 1, full_g + 3 * shift * NCL, sizeof(float) * 3 * np * NCL) == 0);
            }
        for (int k = 0; k < NCL; ++k) CHECK(full_c[5 * NCL + k] == 0.0f);
        shl_ctx_destroy(ctx);
    }
}

/* Either winding, and every point seeing its own side: each lane applies its sign. */
SHL_TEST(simd_winding_per_lane)
{
    rng_t r = {91};
    batch_case bc = {"winding", 0, 0, {0}, {0}}, rev;
    random_batch(&r, 2, 16, 3.0, &bc);
    rev = bc;
    for (int i = 0; i < bc.n; ++i) memcpy(rev.v + 3 * i, bc.v + 3 * (bc.n - 1 - i), sizeof(float) * 3);
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LMAX);
        if (!ctx) continue;
        errors e = run_case(ctx, &bc, 0);
        errors_max(&e, run_case(ctx, &rev, 0));
        harness_note("%s: worst error/tol both windings %.2f, grad %.2f", isas[i], e.coef, e.grad);
        shl_ctx_destroy(ctx);
    }
}

SHL_TEST(simd_dispatch)
{
    const shl__isa *best = NULL; /* the default: the last line of simd/isa_list.h this CPU runs */
    for (int i = NISA - 1; i >= 0 && !best; --i) best = shl__isa_find(isas[i]);
    CHECK(best != NULL);
    shl_ctx *ctx = NULL;
    const char *old = getenv("SHLIGHT_ISA");
    char saved[64] = "";
    if (old) snprintf(saved, sizeof saved, "%s", old);
    unsetenv("SHLIGHT_ISA");
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK && best && !strcmp(shl_ctx_isa(ctx), best->name));
    shl_ctx_destroy(ctx);
    const char *values[3] = {"bogus", "", "AVX2"}; /* ignored: the best ISA */
    for (int i = 0; i < 3; ++i) {
        setenv("SHLIGHT_ISA", values[i], 1);
        CHECK(shl_ctx_create(2, &ctx) == SHL_OK && best && !strcmp(shl_ctx_isa(ctx), best->name));
        shl_ctx_destroy(ctx);
    }
    if (old) setenv("SHLIGHT_ISA", saved, 1);
    else unsetenv("SHLIGHT_ISA");
    ctx = isa_ctx("scalar", 2);
    CHECK(ctx != NULL);
    shl_ctx_destroy(ctx);
    /* shl_ctx_create_isa: a name not compiled in or not supported, wrong case, empty: SHL_EDOMAIN;
     * NULL name or out: SHL_ENULL; bad lmax: SHL_ELMAX; *out = NULL on every failure. */
    const char *bad[4] = {"bogus", "AVX2", "", shl__isa_find("avx2") ? "sse9" : "avx2"};
    for (int i = 0; i < 4; ++i) {
        ctx = (shl_ctx *)&ctx;
        CHECK(shl_ctx_create_isa(2, bad[i], &ctx) == SHL_EDOMAIN && ctx == NULL);
    }
    ctx = (shl_ctx *)&ctx;
    CHECK(shl_ctx_create_isa(2, NULL, &ctx) == SHL_ENULL && ctx == NULL);
    CHECK(shl_ctx_create_isa(2, "scalar", NULL) == SHL_ENULL);
    ctx = (shl_ctx *)&ctx;
    CHECK(shl_ctx_create_isa(SHL_LMAX_MAX + 1, "scalar", &ctx) == SHL_ELMAX && ctx == NULL);
    setenv("SHLIGHT_ISA", "scalar", 1); /* the explicit name wins over the environment */
    CHECK(shl_ctx_create_isa(2, best->name, &ctx) == SHL_OK && !strcmp(shl_ctx_isa(ctx), best->name));
    shl_ctx_destroy(ctx);
    if (old) setenv("SHLIGHT_ISA", saved, 1);
    else unsetenv("SHLIGHT_ISA");
    CHECK(!strcmp(shl_ctx_isa(NULL), ""));
    const char *info = shl_build_info();
    CHECK(info && strstr(info, "scalar") && strstr(info, SHL_VERSION_STRING));
    for (int i = 0; i < NISA; ++i) /* every ISA this CPU runs is listed as compiled in */
        if (shl__isa_find(isas[i])) CHECK(strstr(info, isas[i]) != NULL);
    harness_note("default %s; %s", best ? best->name : "?", info);
}

/* The CPU checks of src/dispatch.c against the compiler's own CPU model
 * (__builtin_cpu_supports: CPUID and, for AVX and AVX-512 state, XGETBV, in
 * libgcc / compiler-rt): each x86 ISA is supported exactly when every feature
 * its flags enable is (avx512: F, DQ, VL, BW, with AVX2 and FMA).  So on a CPU
 * with AVX-512 the SIMD tests cannot silently skip it. */
SHL_TEST(simd_isa_matches_cpu)
{
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    const int avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    const int avx512 = avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                       __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw");
    CHECK((shl__isa_find("avx2") != NULL) == avx2);
#ifdef SHL_AVX512_EMULATE
    /* make AVX512_EMULATE=1: the avx512 kernels are SIMDe's AVX2 + FMA code, so
     * they run, and are the default choice, exactly where avx2 does. */
    CHECK((shl__isa_find("avx512") != NULL) == avx2);
    const char *old = getenv("SHLIGHT_ISA");
    char saved[64] = "";
    if (old) snprintf(saved, sizeof saved, "%s", old);
    unsetenv("SHLIGHT_ISA");
    CHECK(!strcmp(shl__isa_select()->name, avx2 ? "avx512" : "scalar"));
    if (old) setenv("SHLIGHT_ISA", saved, 1);
    harness_note("CPU: avx2+fma %s, avx512 f/dq/vl/bw %s; avx512 emulated (SIMDe): %s", avx2 ? "yes" : "no",
                 avx512 ? "yes" : "no", shl__isa_find("avx512") ? "runs, the default" : "not run");
#else
    CHECK((shl__isa_find("avx512") != NULL) == avx512);
    harness_note("CPU: avx2+fma %s, avx512 f/dq/vl/bw %s", avx2 ? "yes" : "no", avx512 ? "yes" : "no");
#endif
#else
    harness_note("not x86-64: nothing to compare");
#endif
}

SHL_TEST(simd_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(3, &ctx) == SHL_OK);
    const float v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    float pts[6] = {0.2f, 0.3f, 1.0f, 0.5f, 0.5f, -1.0f}, c[33], g[97], big[3 * (SHL_MAX_VERTS + 1)] = {0};
    for (int k = 0; k < 33; ++k) c[k] = 7.0f;
    for (int k = 0; k < 97; ++k) g[k] = 7.0f;
    CHECK(shl_polygon_batch_f(NULL, v, 4, 2, pts, c, g) == SHL_ENULL);
    CHECK(shl_polygon_batch_f(ctx, NULL, 4, 2, pts, c, g) == SHL_ENULL);
    CHECK(shl_polygon_batch_f(ctx, v, 4, 2, NULL, c, g) == SHL_ENULL);
    CHECK(shl_polygon_batch_f(ctx, v, 4, 2, pts, NULL, g) == SHL_ENULL);
    CHECK(shl_polygon_batch_f(ctx, v, 2, 2, pts, c, g) == SHL_ENVERTS);
    CHECK(shl_polygon_batch_f(ctx, big, SHL_MAX_VERTS + 1, 2, pts, c, g) == SHL_ENVERTS);
    CHECK(shl_polygon_batch_f(ctx, v, 4, -1, pts, c, g) == SHL_EDOMAIN);
    pts[5] = NAN; /* the last point: checked before anything is written */
    CHECK(shl_polygon_batch_f(ctx, v, 4, 2, pts, c, g) == SHL_ENONFINITE);
    pts[5] = -1.0f;
    float vbad[12];
    memcpy(vbad, v, sizeof v);
    vbad[4] = INFINITY;
    CHECK(shl_polygon_batch_f(ctx, vbad, 4, 2, pts, c, g) == SHL_ENONFINITE);
    shl__alloc_fail_after = 0;
    CHECK(shl_polygon_batch_f(ctx, v, 4, 2, pts, c, g) == SHL_ENOMEM);
    shl__alloc_fail_after = -1;
    for (int k = 0; k < 33; ++k) CHECK(c[k] == 7.0f);
    for (int k = 0; k < 97; ++k) CHECK(g[k] == 7.0f);
    CHECK(shl_polygon_batch_f(ctx, v, 4, 0, NULL, NULL, NULL) == SHL_OK);
    CHECK(shl_polygon_batch_f(ctx, v, 4, 2, pts, c, NULL) == SHL_OK && c[0] > 0.0f && c[32] == 7.0f);
    shl_ctx_destroy(ctx);
}

/* Every batch entry point rejects a non-finite coordinate wherever it is in the point array
 * (the check runs over the whole array in blocks of 16 values and a rest: src/context.c), and
 * accepts finite extremes; on rejection nothing is written.  Reference: C's isfinite.  Arrays
 * of 1, 5, 6, 11 and 40 points (3, 15, 18, 33, 120 values: a rest only, twice, then one block
 * + 2, two blocks + 1, seven blocks + 8), every position, NaN of both signs and both infinities. */
SHL_TEST(batch_nonfinite_points_any_position)
{
    enum { MAXP = 40, LMAX = 2, NC = 9 };
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *lights;
    CHECK(shl_lights_create(&lights) == SHL_OK);
    const double tri[9] = {-0.5, -0.5, 2.0, 0.5, -0.5, 2.0, 0.0, 0.5, 2.0}, rgb[3] = {1.0, 1.0, 1.0};
    CHECK(shl_lights_add_polygon(lights, tri, 3, rgb, 1) == SHL_OK);
    const double lo[3] = {-1.0, -1.0, -1.0}, hi[3] = {1.0, 1.0, 1.0};
    const int res[3] = {3, 3, 3};
    shl_grid *grid;
    shl_agrid *agrid;
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &grid) == SHL_OK);
    CHECK(shl_grid_fill(grid, lights, 1) == SHL_OK);
    CHECK(shl_agrid_create(ctx, lo, hi, res, SHL_AGRID_MAX, 1e-3, 200, &agrid) == SHL_OK);
    CHECK(shl_agrid_fill(agrid, lights, 1) == SHL_OK);
    const float tri_f[9] = {-0.5f, -0.5f, 2.0f, 0.5f, -0.5f, 2.0f, 0.0f, 0.5f, 2.0f}, center[3] = {0.0f, 0.0f, 3.0f};
    static float pf[3 * MAXP], cf[3 * NC * MAXP], gf[9 * NC * MAXP];
    static double pd[3 * MAXP], cd[3 * NC * MAXP], gd[9 * NC * MAXP];
    const float bad[4] = {NAN, -NAN, INFINITY, -INFINITY};
    const float extreme[4] = {FLT_MAX, -FLT_MAX, FLT_TRUE_MIN, -0.0f};
    const int counts[5] = {1, 5, 6, 11, MAXP};
    long rejected = 0, calls = 0;
    for (int ci = 0; ci < 5; ++ci) {
        const int n = counts[ci];
        for (int i = 0; i < 3 * n; ++i) {
            for (int b = 0; b < 8; ++b) {
                for (int k = 0; k < 3 * n; ++k) pf[k] = 0.1f * (float)(k % 7) - 0.3f;
                pf[i] = b < 4 ? bad[b] : extreme[b - 4];
                for (int k = 0; k < 3 * n; ++k) pd[k] = pf[k];
                const int want = b < 4 || !isfinite(pf[i]) ? SHL_ENONFINITE : SHL_OK;
                for (int k = 0; k < 3 * NC * n; ++k) cf[k] = 7.0f, cd[k] = 7.0;
                int got[7];
                got[0] = shl_polygon_batch_f(ctx, tri_f, 3, n, pf, cf, gf);
                got[1] = shl_sphere_batch_f(ctx, center, 0.5f, n, pf, cf, gf);
                got[2] = shl_lights_eval_batch_f(ctx, lights, n, pf, cf, gf);
                got[3] = shl_lights_eval_batch(ctx, lights, n, pd, cd, gd);
                got[4] = shl_grid_interp(grid, SHL_INTERP_HERMITE, 1.0, n, pd, cd, 1);
                got[5] = shl_grid_interp_f(grid, SHL_INTERP_HERMITE, 1.0, n, pf, cf, 1);
                got[6] = shl_agrid_interp(agrid, n, pd, cd, 1);
                for (int f = 0; f < 7; ++f) {
                    if (want == SHL_OK) CHECK(got[f] == SHL_OK);
                    else CHECK(got[f] == SHL_ENONFINITE);
                    rejected += got[f] == SHL_ENONFINITE;
                }
                calls += 7;
                if (want != SHL_OK)
                    for (int k = 0; k < 3 * NC * n; ++k) CHECK(cf[k] == 7.0f && cd[k] == 7.0);
            }
        }
    }
    harness_note("%ld calls, %ld rejected (every non-finite one)", calls, rejected);
    shl_agrid_destroy(agrid);
    shl_grid_destroy(grid);
    shl_lights_destroy(lights);
    shl_ctx_destroy(ctx);
}

/* Extreme scales of the float batch (issue 8, K3, B3), every ISA:
 *  - vertices equal up to the sign of zero (extent 0): zeros, no undefined
 *    behaviour (ilogb(0) was negated; UBSan in make SANITIZE=1);
 *  - a polygon with a denormal extent (2^-130 times small integers, exact) seen
 *    from 2^10 extents: the batch scales by the extent's power of two, so the
 *    coefficients equal those at scale 1 bit for bit and the gradients are
 *    exactly 2^130 times (finite: ~2^100); before, 2^130 overflowed float: NaN;
 *  - a 2^-60 polygon at z = -2^120 (coordinates 2^180 extents from the origin):
 *    every point is in its plane or farther than 2^40 extents, so zeros; before: NaN. */
SHL_TEST(simd_extreme_scales)
{
    enum { LM = 6, N6 = SHL_NCOEFFS(LM), NP = 3 };
    const float zeros[9] = {0.0f, 0.0f, 0.0f, -0.0f, 0.0f, 0.0f, 0.0f, -0.0f, 0.0f}, zp[3] = {0.5f, 0.5f, 1.0f};
    const float quad1[12] = {1, 0, 0, 3, 1, 0, 2, 3, 0, 0, 2, 0}, pts1[3 * NP] = {1024, 512, 768, -512, 256, 1024, 8, 4, -1024};
    float quad[12], pts[3 * NP], far[12], farp[3 * NP];
    for (int i = 0; i < 12; ++i) quad[i] = ldexpf(quad1[i], -130);
    for (int i = 0; i < 3 * NP; ++i) pts[i] = ldexpf(pts1[i], -130);
    for (int i = 0; i < 12; ++i) far[i] = i % 3 == 2 ? -0x1p120f : ldexpf(quad1[i], -60);
    for (int i = 0; i < 3 * NP; ++i) farp[i] = i % 3 == 2 ? (i == 5 ? 0x1p100f : -0x1p120f) : ldexpf(pts1[i], -70);
    int bad = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        static float c1[NP * N6], g1[3 * NP * N6], c[NP * N6], g[3 * NP * N6];
        CHECK(shl_polygon_batch_f(ctx, zeros, 3, 1, zp, c, g) == SHL_OK);
        for (int k = 0; k < N6; ++k) bad += c[k] != 0.0f;
        for (int k = 0; k < 3 * N6; ++k) bad += g[k] != 0.0f;
        CHECK(shl_polygon_batch_f(ctx, quad1, 4, NP, pts1, c1, g1) == SHL_OK);
        CHECK(shl_polygon_batch_f(ctx, quad, 4, NP, pts, c, g) == SHL_OK);
        bad += memcmp(c, c1, sizeof c) != 0 || !(c1[0] != 0.0f);
        for (int k = 0; k < 3 * NP * N6; ++k) bad += !(g[k] == ldexpf(g1[k], 130) && isfinite(g[k]));
        CHECK(shl_polygon_batch_f(ctx, far, 4, NP, farp, c, g) == SHL_OK);
        for (int k = 0; k < NP * N6; ++k) bad += c[k] != 0.0f;
        for (int k = 0; k < 3 * NP * N6; ++k) bad += g[k] != 0.0f;
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0);
    harness_note("signed-zero, denormal (2^-130) and far (2^180 extents) polygons: %d values differ", bad);
}

/* Points the all-float geometry cannot resolve (issue 8, B1, B2), every ISA:
 * heights below 2^-16 of the distance to the farthest vertex, where float rounding
 * decided the side (seen: dL00/dz with the wrong sign), and points within 2^-16
 * extents of a vertex (seen: |L_lm| = 2.4e11 > K_l 2 pi).  Documented: they take the
 * scalar path, so the batch equals shl_polygon_grad_f bit for bit there (that path
 * is checked against the quadrature reference in test_polygon.c), and the
 * gradient's normal component has the sign of the double reference's. */
SHL_TEST(simd_float_unresolved_points)
{
    enum { LM = 8, N8 = SHL_NCOEFFS(LM), NP = 5 };
    const float v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float p[3 * NP] = {3.0f, 0.5f, 0x1p-21f,  0.5f, 0.25f, -0x1p-22f, /* grazing; inside the footprint */
                             1.0f + 0x1p-20f, 1.0f - 0x1p-21f, 0x1p-19f,    /* next to vertex 2 */
                             -0x1p-18f, 0x1p-19f, -0x1p-20f, 2.0f, 2.0f, 0.0f}; /* next to vertex 0; in the plane */
    static float c[NP * N8], g[3 * NP * N8], cf[N8], gf[3 * N8];
    static double cd[N8], gd[3 * N8];
    const double vd[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    int bad = 0, isa_count = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        ++isa_count;
        CHECK(shl_polygon_batch_f(ctx, v, 4, NP, p, c, g) == SHL_OK);
        for (int q = 0; q < NP; ++q) {
            const double x[3] = {p[3 * q], p[3 * q + 1], p[3 * q + 2]};
            CHECK(shl_polygon_grad_f(ctx, p + 3 * q, v, 4, cf, gf) == SHL_OK);
            CHECK(shl_polygon_grad(ctx, x, vd, 4, cd, gd) == SHL_OK);
            bad += memcmp(c + q * N8, cf, sizeof cf) != 0 || memcmp(g + 3 * q * N8, gf, sizeof gf) != 0;
            bad += (g[(3 * q + 2) * N8] > 0.0f) != (gd[2 * N8] > 0.0); /* dL00/dz */
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0 && isa_count > 0);
    harness_note("%d points x %d ISAs: %d differ from shl_polygon_grad_f or in the sign of dL00/dz", NP, isa_count, bad);
}

/* Small lights (issue 18's sweep): squares of angular size theta = 1e-3, 1e-4,
 * 1e-5 at distances 1, 10, 100 (as in test_polygon.c), each batch mixing the far
 * point with two points 10 and 30 sides in front of the square (theta ~0.1, 0.03:
 * kernel lanes).  Against the quadrature reference on the float-rounded input.
 * The kernel's float boundary sums would lose ~FLT_EPSILON sum gamma / omega ~
 * 2.5e-7 / theta of omega (2e-2 at 1e-5); lights under 1/128 rad take the scalar
 * path (src/batch.c), so the far points must equal shl_polygon_grad_f bit for bit
 * and meet the float contract of issue 18: 1e-4 of omega at theta = 1e-3, 1e-3
 * below (the double recurrence there keeps a few FLT_EPSILON).  The near points
 * keep the kernel's derived per-band tolerance (float_tol.h). */
SHL_TEST(simd_float_small_lights)
{
    enum { LM = 8, N8 = SHL_NCOEFFS(LM), NP = 3 };
    static float c[NP * N8], g[3 * NP * N8], cf[N8], gf[3 * N8];
    double worst[3] = {0, 0, 0}, worst_near = 0.0;
    int bad = 0, isa_count = 0;
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        ++isa_count;
        for (int ai = 0; ai < 3; ++ai)
            for (int di = 0; di < 3; ++di) {
                const double theta = ai == 0 ? 1e-3 : ai == 1 ? 1e-4 : 1e-5, d = di == 0 ? 1.0 : di == 1 ? 10.0 : 100.0;
                const double s = theta * d;
                const double vd0[12] = {0.3 * d, 0.2 * d, d, 0.3 * d + s, 0.2 * d, d,
                                        0.3 * d + s, 0.2 * d + s, d + 0.3 * s, 0.3 * d, 0.2 * d + s, d + 0.3 * s};
                float v[12], p[3 * NP] = {0.05f, -0.1f, 0.02f};
                double vd[12];
                for (int k = 0; k < 12; ++k) vd[k] = v[k] = (float)vd0[k];
                for (int q = 1; q < NP; ++q) { /* centre minus 10 s, 30 s along z */
                    p[3 * q] = (float)(0.3 * d + 0.5 * s), p[3 * q + 1] = (float)(0.2 * d + 0.5 * s);
                    p[3 * q + 2] = (float)(d - (q == 1 ? 10.0 : 30.0) * s);
                }
                CHECK(shl_polygon_batch_f(ctx, v, 4, NP, p, c, g) == SHL_OK);
                for (int q = 0; q < NP; ++q) {
                    const double x[3] = {p[3 * q], p[3 * q + 1], p[3 * q + 2]};
                    double want[N8];
                    CHECK(ref_polygon_sh(LM, x, vd, 4, want, NULL) == 0);
                    const double omega = ref_polygon_solid_angle(x, vd, 4);
                    double e = 0.0;
                    for (int k = 0; k < N8; ++k) e = fmax(e, fabs(c[q * N8 + k] - want[k]) / omega);
                    if (q == 0) {
                        CHECK(shl_polygon_grad_f(ctx, p, v, 4, cf, gf) == SHL_OK);
                        bad += memcmp(c, cf, sizeof cf) != 0 || memcmp(g, gf, sizeof gf) != 0;
                        worst[ai] = fmax(worst[ai], e);
                        const double tol = theta >= 1e-3 ? 1e-4 : 1e-3;
                        if (!(e <= tol)) harness_fail(__FILE__, __LINE__, "%s theta %.0e d %g: error/omega %.3g > %.0e",
                                                      isas[i], theta, d, e, tol);
                    } else {
                        double tc[LM + 1], tg[LM + 1], gd[3 * N8], cd[N8], gmax = 0.0, r = 0.0;
                        CHECK(shl_polygon_grad(ctx, x, vd, 4, cd, gd) == SHL_OK);
                        for (int k = 0; k < 3 * N8; ++k) gmax = fmax(gmax, fabs(gd[k]));
                        float_poly_tol(LM, x, vd, 4, omega, gmax, 1, tc, tg);
                        for (int k = 0; k < N8; ++k) r = fmax(r, fabs(c[q * N8 + k] - want[k]) / tc[(int)sqrt(k + 0.5)]);
                        worst_near = fmax(worst_near, r);
                        if (!(r <= 1.0)) harness_fail(__FILE__, __LINE__, "%s theta %.0e d %g near point %d: error/tol %.3g",
                                                      isas[i], theta, d, q, r);
                    }
                }
            }
        shl_ctx_destroy(ctx);
    }
    CHECK(bad == 0 && isa_count > 0);
    harness_note("%d ISAs, lmax %d, error/omega over d = 1, 10, 100: theta 1e-3 %.1e, 1e-4 %.1e, 1e-5 %.1e "
                 "(tol 1e-4, 1e-3, 1e-3); near points worst error/tol %.2f",
                 isa_count, LM, worst[0], worst[1], worst[2], worst_near);
}

/* The generated float lobe tables (src/zh_tables.c, tools/gen_lobes.c) are exactly
 * the doubles rounded to float: the literals are printed with 9 significant digits,
 * enough to read back every float exactly, so no tolerance. */
SHL_TEST(simd_lobe_tables_float_copies)
{
    int differ = 0;
    for (int d = 0; d < SHL__ZH_NDIR; ++d)
        for (int k = 0; k < 3; ++k) differ += shl__zh_dir_f[d][k] != (float)shl__zh_dir[d][k];
    for (int i = 0; i < SHL__ZH_EVEN_SIZE; ++i) differ += shl__zh_even_w_f[i] != (float)shl__zh_even_w[i];
    for (int i = 0; i < SHL__ZH_ODD_SIZE; ++i) differ += shl__zh_odd_w_f[i] != (float)shl__zh_odd_w[i];
    CHECK(differ == 0);
    harness_note("%d of %d float entries differ from (float) of the double table", differ,
                 3 * SHL__ZH_NDIR + SHL__ZH_EVEN_SIZE + SHL__ZH_ODD_SIZE);
}
