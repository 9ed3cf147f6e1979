/* SIMD kernels of spherical lights (shl_sphere_batch_f) and grid interpolation
 * (shl_grid_interp with float storage), for every ISA this machine runs.
 *  - Spheres: every ISA against the scalar double reference shl_sphere_grad on
 *    the float-rounded input; coefficients relative to |L00|, gradients
 *    relative to the point's largest gradient.
 *  - Interpolation: the vector kernels (simd/interp_batch.h) against the
 *    scalar table's reference (src/interp_kernel.h) on the same float node
 *    data, both summing in double; errors relative to the scale M of the data,
 *    max |value| and max |d/dx_a value| h_a. */
#include "isa_ctx.h"
#include "testutil.h"
#include <float.h>
#include <math.h>

#include "internal.h" /* shl__alloc_fail_after (src/alloc.c, built with SHL_ALLOC_HOOKS) */

/* ---------------------------------------------------------------- spheres */

enum { SP_MAXPTS = 40, SP_NCMAX = SHL_NCOEFFS(SHL_LMAX_MAX) };

/* Float tolerances, from the worst errors measured over every ISA (random
 * cases and hard cases below, lmax 0..30): coefficients relative to |L00|
 * 1.3e-5 up to lmax 14 (the target for polygons is 2e-5) and 7.1e-5
 * above, gradients relative to max|grad| 4.0e-6 and 1.1e-5.  These are float
 * recurrences at the level of the scalar float path, shl_sphere_grad_f, on the
 * same points (1.1e-5 and 8.0e-5, 4.0e-6 and 1.1e-5; the tests' notes report
 * both): the error grows with l and distance (Y_lm of the axis and P_l' near
 * cos a = 1).  The floor 16 FLT_MIN admits values below float range (a sphere
 * 1e30 radii away: L00 ~ 1e-60 rounds to 0, as in shl_sphere_f).  The rounding
 * of the float inputs is excluded: the reference takes the same float-rounded
 * point, centre and radius. */
static double coef_tol(int lmax) { return lmax <= 14 ? 2e-5 : 1.5e-4; }
static double grad_tol(int lmax) { return lmax <= 14 ? 1e-5 : 3e-5; }
#define UNDERFLOW_FLOOR (16.0 * FLT_MIN)

typedef struct { double coef, grad, f_coef, f_grad; } sp_err; /* batch; shl_sphere_grad_f */

/* Batch of npts points against shl_sphere_grad; every output finite, guards
 * intact, coefficients identical with and without gradients, and inside
 * points exactly (float) sqrt(4 pi), 0, zero gradient. */
static sp_err sphere_case(const shl_ctx *ctx, const float c[3], float r, int np, const float *pts)
{
    const int lmax = shl_ctx_lmax(ctx), nc = SHL_NCOEFFS(lmax);
    static float co[SP_MAXPTS * SP_NCMAX + 1], co2[SP_MAXPTS * SP_NCMAX + 1], gr[3 * SP_MAXPTS * SP_NCMAX + 1];
    static float cf[SP_NCMAX], gf[3 * SP_NCMAX];
    static double cr[SP_NCMAX], grr[3 * SP_NCMAX];
    sp_err e = {0, 0, 0, 0};
    co[np * nc] = co2[np * nc] = gr[3 * np * nc] = 7.0f;
    CHECK(shl_sphere_batch_f(ctx, c, r, np, pts, co, gr) == SHL_OK);
    CHECK(shl_sphere_batch_f(ctx, c, r, np, pts, co2, NULL) == SHL_OK);
    CHECK(co[np * nc] == 7.0f && co2[np * nc] == 7.0f && gr[3 * np * nc] == 7.0f);
    const double cd[3] = {c[0], c[1], c[2]};
    for (int p = 0; p < np; ++p) {
        const double x[3] = {pts[3 * p], pts[3 * p + 1], pts[3 * p + 2]};
        const float *cp = co + p * nc, *gp = gr + 3 * p * nc;
        CHECK(shl_sphere_grad(ctx, x, cd, r, cr, grr) == SHL_OK);
        CHECK(shl_sphere_grad_f(ctx, pts + 3 * p, c, r, cf, gf) == SHL_OK);
        int finite = 1;
        double gmax = 0, ec = 0, eg = 0, efc = 0, efg = 0;
        for (int k = 0; k < 3 * nc; ++k) gmax = fmax(gmax, fabs(grr[k]));
        for (int k = 0; k < nc; ++k) {
            finite &= isfinite(cp[k]) && cp[k] == co2[p * nc + k];
            ec = fmax(ec, fabs(cp[k] - cr[k]));
            efc = fmax(efc, fabs(cf[k] - cr[k]));
        }
        for (int k = 0; k < 3 * nc; ++k) {
            finite &= isfinite(gp[k]);
            eg = fmax(eg, fabs(gp[k] - grr[k]));
            efg = fmax(efg, fabs(gf[k] - grr[k]));
        }
        CHECK(finite);
        if (gmax == 0.0) { /* inside or on the sphere */
            CHECK(cp[0] == (float)sqrt(4.0 * M_PI));
            for (int k = 1; k < nc; ++k) CHECK(cp[k] == 0.0f);
            for (int k = 0; k < 3 * nc; ++k) CHECK(gp[k] == 0.0f);
            continue;
        }
        if (!(ec <= coef_tol(lmax) * fabs(cr[0]) + UNDERFLOW_FLOOR && eg <= grad_tol(lmax) * gmax + UNDERFLOW_FLOOR))
            harness_fail(__FILE__, __LINE__,
                         "[%s, lmax %d] sphere (%a, %a, %a) r %a, point %d (%a, %a, %a): coeffs %.3g, grad %.3g",
                         shl_ctx_isa(ctx), lmax, c[0], c[1], c[2], r, p, x[0], x[1], x[2], ec / fabs(cr[0]), eg / gmax);
        if (fabs(cr[0]) < 1e6 * FLT_MIN) continue; /* near float underflow: the floor only */
        e.coef = fmax(e.coef, ec / fabs(cr[0]));
        e.grad = fmax(e.grad, eg / gmax);
        e.f_coef = fmax(e.f_coef, efc / fabs(cr[0]));
        e.f_grad = fmax(e.f_grad, efg / gmax);
    }
    return e;
}

static void sp_max(sp_err *a, sp_err b)
{
    a->coef = fmax(a->coef, b.coef);
    a->grad = fmax(a->grad, b.grad);
    a->f_coef = fmax(a->f_coef, b.f_coef);
    a->f_grad = fmax(a->f_grad, b.f_grad);
}

/* Random sphere (centre in [-2, 2]^3, radius 0.05..1.5) and points at 1.01..50 radii. */
static void random_sphere(rng_t *r, int np, float c[3], float *rad, float *pts)
{
    for (int k = 0; k < 3; ++k) c[k] = (float)rng_range(r, -2.0, 2.0);
    *rad = (float)rng_range(r, 0.05, 1.5);
    for (int p = 0; p < np; ++p) {
        double u[3];
        rng_unit_vector(r, u);
        const double d = *rad * exp(rng_range(r, log(1.01), log(50.0)));
        for (int k = 0; k < 3; ++k) pts[3 * p + k] = (float)(c[k] + d * u[k]);
    }
}

SHL_TEST(simd_sphere_random_every_lmax)
{
    for (int i = 0; i < NISA; ++i) {
        sp_err worst14 = {0, 0, 0, 0}, worst = {0, 0, 0, 0};
        int ran = 0;
        for (int lmax = 0; lmax <= SHL_LMAX_MAX; ++lmax) {
            shl_ctx *ctx = isa_ctx(isas[i], lmax);
            if (!ctx) break;
            ran = 1;
            rng_t r = {(uint64_t)(500 + lmax)};
            for (int it = 0; it < 4; ++it) {
                float c[3], rad, pts[3 * 19];
                random_sphere(&r, 19, c, &rad, pts);
                const sp_err e = sphere_case(ctx, c, rad, 19, pts);
                sp_max(lmax <= 14 ? &worst14 : &worst, e);
            }
            shl_ctx_destroy(ctx);
        }
        if (ran)
            harness_note("%s: lmax <= 14 coeffs %.1e |L00|, grad %.1e max|grad| (shl_sphere_grad_f %.1e, %.1e); "
                         "lmax 15..30 %.1e, %.1e (%.1e, %.1e)", isas[i], worst14.coef, worst14.grad, worst14.f_coef,
                         worst14.f_grad, worst.coef, worst.grad, worst.f_coef, worst.f_grad);
    }
}

/* On the sphere, just outside (1 ulp and 1e-6), on the axes (zero components
 * of u), far away (1e6 and 1e30 radii), tiny spheres (1e-4 at 10, 1e-30 at 1),
 * huge coordinates, the centre itself. */
SHL_TEST(simd_sphere_hard_cases)
{
    const float c[3] = {0.5f, -0.25f, 2.0f}, r = 1.5f;
    const float pts[][3] = {{0.5f, -0.25f, 3.5f},  {0.5f, -0.25f, 0.5f},  {2.0f, -0.25f, 2.0f},
                            {0.5f, -0.25f, 2.0f},  {0.5f, -0.25f, 0.4999999f}, {0.5f, -0.25f, 3.5000005f},
                            {0.5f, 1.2500015f, 2.0f}, {0.5f, -0.25f, -1.0f}, {4.0f, -0.25f, 2.0f},
                            {0.5f, -0.25f, 1.5e6f}, {0.5f, 1.5e30f, 2.0f}, {-3e37f, 2e37f, 1e37f},
                            {1.3f, 0.8f, 0.1f},    {0.5f, -0.25f, 2.0f - 1.5f * 1.000001f}};
    const int np = sizeof pts / sizeof pts[0];
    const float tiny_c[3] = {0.0f, 0.0f, 10.0f}, tiny_pts[][3] = {{0, 0, 0}, {1, 2, 3}, {0, 0, 10.001f}, {0, 0, 9.9999f}};
    const float micro_c[3] = {1.0f, 0.0f, 0.0f}, micro_pts[][3] = {{0, 0, 0}, {1, 0, 1e-29f}, {1, 3e-30f, 0}};
    for (int i = 0; i < NISA; ++i) {
        const int lmaxes[3] = {0, 14, SHL_LMAX_MAX};
        sp_err worst = {0, 0, 0, 0};
        for (int j = 0; j < 3; ++j) {
            shl_ctx *ctx = isa_ctx(isas[i], lmaxes[j]);
            if (!ctx) continue;
            sp_max(&worst, sphere_case(ctx, c, r, np, &pts[0][0]));
            sp_max(&worst, sphere_case(ctx, tiny_c, 1e-4f, 4, &tiny_pts[0][0]));
            sp_max(&worst, sphere_case(ctx, micro_c, 1e-30f, 3, &micro_pts[0][0]));
            shl_ctx_destroy(ctx);
        }
        if (worst.coef > 0 || worst.grad > 0)
            harness_note("%s: coeffs %.1e |L00|, grad %.1e max|grad| (shl_sphere_grad_f %.1e, %.1e)", isas[i],
                         worst.coef, worst.grad, worst.f_coef, worst.f_grad);
    }
}

/* Point counts 1..17 around the vector widths: results equal, bit for bit, those
 * of one batch of 17 and of the same points at other lane positions; nothing is
 * written outside the outputs. */
SHL_TEST(simd_sphere_tails_and_lane_independence)
{
    enum { NP = 17, LM = 5, NCL = SHL_NCOEFFS(LM) };
    rng_t r = {78};
    float c[3], rad, pts[3 * (NP + 1)];
    random_sphere(&r, NP + 1, c, &rad, pts);
    for (int k = 0; k < 3; ++k) pts[3 * 4 + k] = c[k]; /* point 4 inside */
    for (int i = 0; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], LM);
        if (!ctx) continue;
        static float full_c[NP * NCL], full_g[3 * NP * NCL], co[NP * NCL + 2], g[3 * NP * NCL + 2];
        CHECK(shl_sphere_batch_f(ctx, c, rad, NP, pts, full_c, full_g) == SHL_OK);
        for (int np = 1; np <= NP; ++np)
            for (int shift = 0; shift <= 1 && shift + np <= NP; ++shift) {
                for (int k = 0; k < np * NCL + 2; ++k) co[k] = 7.0f;
                for (int k = 0; k < 3 * np * NCL + 2; ++k) g[k] = 7.0f;
                CHECK(shl_sphere_batch_f(ctx, c, rad, np, pts + 3 * shift, co + 1, g + 1) == SHL_OK);
                CHECK(co[0] == 7.0f && co[np * NCL + 1] == 7.0f && g[0] == 7.0f && g[3 * np * NCL + 1] == 7.0f);
                CHECK(memcmp(co + 1, full_c + shift * NCL, sizeof(float) * np * NCL) == 0);
                CHECK(memcmp(g + 1, full_g + 3 * shift * NCL, sizeof(float) * 3 * np * NCL) == 0);
            }
        CHECK(full_c[4 * NCL] == (float)sqrt(4.0 * M_PI) && full_c[4 * NCL + 1] == 0.0f);
        shl_ctx_destroy(ctx);
    }
}

SHL_TEST(simd_sphere_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(3, &ctx) == SHL_OK);
    const float c[3] = {0, 0, 3};
    float pts[6] = {0.2f, 0.3f, 0.0f, 0.5f, 0.5f, -1.0f}, co[33], g[97];
    for (int k = 0; k < 33; ++k) co[k] = 7.0f;
    for (int k = 0; k < 97; ++k) g[k] = 7.0f;
    CHECK(shl_sphere_batch_f(NULL, c, 1.0f, 2, pts, co, g) == SHL_ENULL);
    CHECK(shl_sphere_batch_f(ctx, NULL, 1.0f, 2, pts, co, g) == SHL_ENULL);
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 2, NULL, co, g) == SHL_ENULL);
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 2, pts, NULL, g) == SHL_ENULL);
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, -1, pts, co, g) == SHL_EDOMAIN);
    CHECK(shl_sphere_batch_f(ctx, c, 0.0f, 2, pts, co, g) == SHL_EDOMAIN);
    CHECK(shl_sphere_batch_f(ctx, c, -1.0f, 2, pts, co, g) == SHL_EDOMAIN);
    CHECK(shl_sphere_batch_f(ctx, c, NAN, 2, pts, co, g) == SHL_ENONFINITE);
    CHECK(shl_sphere_batch_f(ctx, c, INFINITY, 2, pts, co, g) == SHL_ENONFINITE);
    const float cbad[3] = {0, INFINITY, 3};
    CHECK(shl_sphere_batch_f(ctx, cbad, 1.0f, 2, pts, co, g) == SHL_ENONFINITE);
    pts[5] = NAN; /* the last point: checked before anything is written */
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 2, pts, co, g) == SHL_ENONFINITE);
    pts[5] = -1.0f;
    shl__alloc_fail_after = 0;
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 2, pts, co, g) == SHL_ENOMEM);
    shl__alloc_fail_after = -1;
    for (int k = 0; k < 33; ++k) CHECK(co[k] == 7.0f);
    for (int k = 0; k < 97; ++k) CHECK(g[k] == 7.0f);
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 0, NULL, NULL, NULL) == SHL_OK);
    CHECK(shl_sphere_batch_f(ctx, c, 1.0f, 2, pts, co, NULL) == SHL_OK && co[0] > 0.0f && co[32] == 7.0f);
    CHECK(g[0] == 7.0f);
    shl_ctx_destroy(ctx);
}

/* ---------------------------------------------------------- interpolation */

/* |SIMD - reference| <= tol DBL_EPSILON M, 2.5-3 times the worst measured over
 * AVX2 and NEON (trilinear 1, Taylor 4, Hermite 3 DBL_EPSILON M; the note of
 * simd_interp_vs_reference): both sum the float data in double, in another
 * order and with FMAs, so they differ by a few roundings of the scale of their
 * terms (Taylor: w_j (|c_j| + |grad c_j . d_j|), up to 4 M).  For scale, the
 * note also reports what float storage itself costs (against a double grid). */
static const double interp_tol[3] = {3.0, 10.0, 8.0}; /* trilinear, Taylor, Hermite */

enum { IP_LMAX = 8, IP_NC = SHL_NCOEFFS(IP_LMAX), IP_NP = 300 };

/* Random node data: values in [-1, 1], gradients in [-1, 1] / h_a; returns M
 * (1 when h is the node spacing). */
static double random_nodes(rng_t *r, shl_grid *const *grids, int ngrids, const int res[3], const double h[3], int nc)
{
    static double rgb[3 * IP_NC], grad[9 * IP_NC];
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                for (int q = 0; q < 3 * nc; ++q) rgb[q] = rng_range(r, -1.0, 1.0);
                for (int c = 0; c < 3; ++c)
                    for (int a = 0; a < 3; ++a)
                        for (int q = 0; q < nc; ++q) grad[(3 * c + a) * nc + q] = rng_range(r, -1.0, 1.0) / h[a];
                for (int g = 0; g < ngrids; ++g) CHECK(shl_grid_set_node(grids[g], idx, rgb, grad) == SHL_OK);
            }
    return 1.0;
}

/* Random points in the box, on nodes, on cell faces (one coordinate on a node
 * plane), on the box's faces, and outside (clamped). */
static void interp_points(rng_t *r, const double lo[3], const double hi[3], const int res[3], double *pts)
{
    for (int p = 0; p < IP_NP; ++p) {
        const int kind = p % 5;
        for (int a = 0; a < 3; ++a) {
            const double h = (hi[a] - lo[a]) / (res[a] - 1);
            const int node = (int)rng_range(r, 0.0, res[a] - 0.01);
            double x = rng_range(r, lo[a], hi[a]);
            if (kind == 1 || (kind == 2 && a == p % 3)) x = node == res[a] - 1 ? hi[a] : lo[a] + node * h;
            if (kind == 3 && a == p % 3) x = p % 2 ? lo[a] : hi[a];
            if (kind == 4) x = rng_range(r, lo[a] - 2.0, hi[a] + 2.0);
            pts[3 * p + a] = x;
        }
    }
}

/* For each lmax 0..8 (tails: nc = 1, 4, 9, ..., 81 against 8- and 4-lane
 * vectors; rows shorter than a vector run the reference) and method: every vector ISA against the scalar reference, on the
 * same float grid and points; exact at nodes; independent of nthreads. */
SHL_TEST(simd_interp_vs_reference)
{
    const double lo[3] = {-1.0, 0.25, -0.5}, hi[3] = {1.5, 1.0, 2.5};
    const int res[3] = {4, 3, 5};
    const double h[3] = {(hi[0] - lo[0]) / 3, (hi[1] - lo[1]) / 2, (hi[2] - lo[2]) / 4};
    const char *names[3] = {"trilinear", "Taylor", "Hermite"};
    static double pts[3 * IP_NP], want[3 * IP_NC * IP_NP], got[3 * IP_NC * IP_NP], got2[3 * IP_NC * IP_NP];
    static double wantd[3 * IP_NC * IP_NP];
    double worst[3] = {0, 0, 0}, storage[3] = {0, 0, 0};
    int nisa = 0;
    for (int i = 1; i < NISA; ++i) {
        int ran = 0;
        for (int lmax = 0; lmax <= IP_LMAX; ++lmax) {
            shl_ctx *ctx = isa_ctx(isas[i], lmax), *ref = isa_ctx("scalar", lmax);
            if (!ctx || !ref) {
                shl_ctx_destroy(ctx);
                shl_ctx_destroy(ref);
                break;
            }
            ran = 1;
            const int nc = SHL_NCOEFFS(lmax), nv = 3 * nc;
            shl_grid *grids[3] = {NULL, NULL, NULL};
            CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &grids[0]) == SHL_OK);
            CHECK(shl_grid_create(ref, lo, hi, res, SHL_GRID_FLOAT, &grids[1]) == SHL_OK);
            CHECK(shl_grid_create(ref, lo, hi, res, SHL_GRID_DOUBLE, &grids[2]) == SHL_OK);
            rng_t r = {(uint64_t)(900 + lmax)};
            const double M = random_nodes(&r, grids, 3, res, h, nc);
            interp_points(&r, lo, hi, res, pts);
            for (int m = 0; m < 3; ++m) {
                const double b = m == SHL_INTERP_TAYLOR ? (lmax % 2 ? 0.7 : 2.0) : 0.0;
                CHECK(shl_grid_interp(grids[1], m, b, IP_NP, pts, want, 1) == SHL_OK);
                CHECK(shl_grid_interp(grids[2], m, b, IP_NP, pts, wantd, 1) == SHL_OK);
                CHECK(shl_grid_interp(grids[0], m, b, IP_NP, pts, got, 1) == SHL_OK);
                CHECK(shl_grid_interp(grids[0], m, b, IP_NP, pts, got2, 2) == SHL_OK);
                CHECK(memcmp(got, got2, sizeof(double) * nv * IP_NP) == 0);
                for (int p = 0; p < IP_NP; ++p) {
                    double e = 0.0;
                    for (int q = 0; q < nv; ++q) {
                        const double gq = got[p * nv + q], wq = want[p * nv + q];
                        e = fmax(e, isfinite(gq) ? fabs(gq - wq) / (DBL_EPSILON * M) : INFINITY);
                        storage[m] = fmax(storage[m], fabs(wq - wantd[p * nv + q]) / (FLT_EPSILON * M));
                    }
                    if (p % 5 == 1 && e != 0.0) /* on a node: the node's value, exactly */
                        harness_fail(__FILE__, __LINE__, "[%s, lmax %d] %s at node (%a, %a, %a): error %.3g DBL_EPSILON M",
                                     isas[i], lmax, names[m], pts[3 * p], pts[3 * p + 1], pts[3 * p + 2], e);
                    if (!(e <= interp_tol[m]))
                        harness_fail(__FILE__, __LINE__, "[%s, lmax %d] %s point %d (%a, %a, %a): error %.3g DBL_EPSILON M",
                                     isas[i], lmax, names[m], p, pts[3 * p], pts[3 * p + 1], pts[3 * p + 2], e);
                    worst[m] = fmax(worst[m], e);
                }
            }
            for (int g = 0; g < 3; ++g) shl_grid_destroy(grids[g]);
            shl_ctx_destroy(ctx);
            shl_ctx_destroy(ref);
        }
        nisa += ran;
    }
    if (nisa)
        harness_note("worst |SIMD - reference| / (DBL_EPSILON M): trilinear %.2f, Taylor %.2f, Hermite %.2f "
                     "(float vs double storage / (FLT_EPSILON M): %.2f, %.2f, %.2f)",
                     worst[0], worst[1], worst[2], storage[0], storage[1], storage[2]);
}

/* Look-ahead (src/interp.c: a point's set-up and, for grids above
 * SHL__INTERP_AHEAD_BYTES, its corner rows are prepared while the previous
 * point is computed) changes no value: on every ISA, storage and method, for a
 * grid below and one above that size, a call over all points, a call over an
 * odd sub-range and calls of 3 threads equal one call per point (which has no
 * next point), bit for bit. */
SHL_TEST(simd_interp_lookahead_is_one_point_at_a_time)
{
    const double lo[3] = {-1.0, 0.25, -0.5}, hi[3] = {1.5, 1.0, 2.5};
    const int lmaxes[3] = {0, 3, IP_LMAX};
    static double pts[3 * IP_NP], one[3 * IP_NC * IP_NP], all[3 * IP_NC * IP_NP];
    for (int i = 0; i < NISA; ++i)
        for (int l = 0; l < 3; ++l) {
            shl_ctx *ctx = isa_ctx(isas[i], lmaxes[l]);
            if (!ctx) continue;
            const int nv = 3 * SHL_NCOEFFS(lmaxes[l]);
            for (int storage = 0; storage < 2; ++storage)
                for (int big = 0; big < 2; ++big) {
                    int bpn;
                    CHECK(shl_grid_bytes_per_node(lmaxes[l], storage ? SHL_GRID_DOUBLE : SHL_GRID_FLOAT, &bpn) == SHL_OK);
                    const int r = (int)ceil(cbrt((double)SHL__INTERP_AHEAD_BYTES / bpn)) + 1;
                    const int res[3] = {big ? r : 4, big ? r : 3, big ? r : 5};
                    CHECK(((size_t)res[0] * res[1] * res[2] * bpn > SHL__INTERP_AHEAD_BYTES) == big);
                    double h[3];
                    for (int a = 0; a < 3; ++a) h[a] = (hi[a] - lo[a]) / (res[a] - 1);
                    shl_grid *g = NULL;
                    CHECK(shl_grid_create(ctx, lo, hi, res, storage ? SHL_GRID_DOUBLE : SHL_GRID_FLOAT, &g) == SHL_OK);
                    rng_t rng = {(uint64_t)(70 + l)};
                    random_nodes(&rng, &g, 1, res, h, nv / 3);
                    interp_points(&rng, lo, hi, res, pts);
                    for (int m = 0; m < 3; ++m) {
                        for (int p = 0; p < IP_NP; ++p)
                            CHECK(shl_grid_interp(g, m, 1.5, 1, pts + 3 * p, one + (size_t)nv * p, 1) == SHL_OK);
                        const size_t bytes = sizeof(double) * nv * IP_NP;
                        CHECK(shl_grid_interp(g, m, 1.5, IP_NP, pts, all, 1) == SHL_OK);
                        CHECK(memcmp(one, all, bytes) == 0);
                        memset(all, 0, bytes);
                        CHECK(shl_grid_interp(g, m, 1.5, 101, pts + 3 * 7, all + (size_t)nv * 7, 1) == SHL_OK);
                        CHECK(memcmp(one + (size_t)nv * 7, all + (size_t)nv * 7, sizeof(double) * nv * 101) == 0);
                        CHECK(shl_grid_interp(g, m, 1.5, IP_NP, pts, all, 3) == SHL_OK);
                        CHECK(memcmp(one, all, bytes) == 0);
                    }
                    shl_grid_destroy(g);
                }
            shl_ctx_destroy(ctx);
        }
}

/* Double storage runs the reference on every ISA: identical results. */
SHL_TEST(simd_interp_double_storage_is_reference)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 1};
    const int res[3] = {3, 3, 2};
    const double h[3] = {0.5, 1.0, 1.0};
    static double pts[3 * IP_NP], want[3 * 25 * IP_NP], got[3 * 25 * IP_NP];
    for (int i = 1; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], 4), *ref = isa_ctx("scalar", 4);
        if (ctx && ref) {
            shl_grid *grids[2] = {NULL, NULL};
            CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_DOUBLE, &grids[0]) == SHL_OK);
            CHECK(shl_grid_create(ref, lo, hi, res, SHL_GRID_DOUBLE, &grids[1]) == SHL_OK);
            rng_t r = {31};
            random_nodes(&r, grids, 2, res, h, 25);
            interp_points(&r, lo, hi, res, pts);
            for (int m = 0; m < 3; ++m) {
                CHECK(shl_grid_interp(grids[0], m, 2.0, IP_NP, pts, got, 2) == SHL_OK);
                CHECK(shl_grid_interp(grids[1], m, 2.0, IP_NP, pts, want, 1) == SHL_OK);
                CHECK(memcmp(got, want, sizeof got) == 0);
            }
            shl_grid_destroy(grids[0]);
            shl_grid_destroy(grids[1]);
        }
        shl_ctx_destroy(ctx);
        shl_ctx_destroy(ref);
    }
}

/* Boxes of 1e-300 and 1e300 (node spacing far outside float range): the weights
 * stay double, so the SIMD results are finite and match the reference. */
SHL_TEST(simd_interp_extreme_boxes)
{
    static double pts[3 * IP_NP], want[3 * 25 * IP_NP], got[3 * 25 * IP_NP];
    const double scales[2] = {1e-300, 1e300};
    for (int i = 1; i < NISA; ++i) {
        shl_ctx *ctx = isa_ctx(isas[i], 4), *ref = isa_ctx("scalar", 4);
        for (int sc = 0; sc < 2 && ctx && ref; ++sc) {
            const double lo[3] = {-scales[sc], -2 * scales[sc], 0}, hi[3] = {scales[sc], 0, 3 * scales[sc]};
            const int res[3] = {3, 2, 4};
            /* gradients of order 1 / spacing, within float range: M = 1 */
            const double h[3] = {fmax(scales[sc], 1.0), fmax(2 * scales[sc], 1.0), fmax(scales[sc], 1.0)};
            shl_grid *grids[2] = {NULL, NULL};
            CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &grids[0]) == SHL_OK);
            CHECK(shl_grid_create(ref, lo, hi, res, SHL_GRID_FLOAT, &grids[1]) == SHL_OK);
            rng_t r = {(uint64_t)(41 + sc)};
            random_nodes(&r, grids, 2, res, h, 25);
            interp_points(&r, lo, hi, res, pts);
            for (int m = 0; m < 3; ++m) {
                CHECK(shl_grid_interp(grids[0], m, 2.0, IP_NP, pts, got, 1) == SHL_OK);
                CHECK(shl_grid_interp(grids[1], m, 2.0, IP_NP, pts, want, 1) == SHL_OK);
                double e = 0.0;
                for (int q = 0; q < 3 * 25 * IP_NP; ++q)
                    e = fmax(e, isfinite(got[q]) ? fabs(got[q] - want[q]) / DBL_EPSILON : INFINITY);
                if (!(e <= interp_tol[m]))
                    harness_fail(__FILE__, __LINE__, "[%s] box scale %g, method %d: error %.3g DBL_EPSILON M", isas[i],
                                 scales[sc], m, e);
            }
            shl_grid_destroy(grids[0]);
            shl_grid_destroy(grids[1]);
        }
        shl_ctx_destroy(ctx);
        shl_ctx_destroy(ref);
    }
}

/* ------------------------------------------- float sums (shl_grid_interp_f) */

/* The bound of shl_grid_interp_f (include/shlight.h, README "Grid interpolation"):
 * gamma_n L M, with n the roundings a term sees (its weight's, its product's and
 * the sums') and L the sum of the weights' magnitudes in units of M; plus 16
 * DBL_EPSILON M for the double reference's own roundings and the double set-up,
 * and the underflow allowance 2^-45 M + 2^-144. */
static double ff_bound(int method, double M)
{
    const double u = 0x1p-24, n = method == SHL_INTERP_TRILINEAR ? 9.0 : 18.0;
    const double L = method == SHL_INTERP_TRILINEAR ? 1.0 : method == SHL_INTERP_TAYLOR ? 4.0 : 1.75;
    return n * u / (1.0 - n * u) * L * M + (16.0 * DBL_EPSILON + 0x1p-45) * M + 0x1p-144;
}

/* Per output entry q = c nc + k, the M of point x's cell: max over its 8 corners
 * of |value| and |d/dx_a value| h_a of that entry (the cell as src/interp.c's
 * locate picks it). */
static void ff_cell_scale(const shl_grid *g, const double lo[3], const double hi[3], const int res[3], const double x[3],
                          int nc, double *M)
{
    static double rgb[3 * IP_NC], grad[9 * IP_NC];
    int cell[3];
    double h[3];
    for (int a = 0; a < 3; ++a) {
        h[a] = (hi[a] - lo[a]) / (res[a] - 1);
        const double xc = x[a] < lo[a] ? lo[a] : x[a] > hi[a] ? hi[a] : x[a], t = (xc - lo[a]) / h[a];
        cell[a] = t < res[a] - 1 ? (int)t : res[a] - 2;
    }
    for (int q = 0; q < 3 * nc; ++q) M[q] = 0.0;
    for (int j = 0; j < 8; ++j) {
        const int idx[3] = {cell[0] + (j & 1), cell[1] + ((j >> 1) & 1), cell[2] + (j >> 2)};
        CHECK(shl_grid_get_node(g, idx, rgb, grad) == SHL_OK);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < nc; ++k) {
                double m = fabs(rgb[c * nc + k]);
                for (int a = 0; a < 3; ++a) m = fmax(m, fabs(grad[(3 * c + a) * nc + k]) * h[a]);
                M[c * nc + k] = fmax(M[c * nc + k], m);
            }
    }
}

/* random_nodes with every node scaled by its own 2^e, -6 <= e <= 6: cells of
 * different scales, so that the bound is checked against each cell's M. */
static void ff_nodes(rng_t *r, shl_grid *const *grids, int ngrids, const int res[3], const double h[3], int nc)
{
    static double rgb[3 * IP_NC], grad[9 * IP_NC];
    for (int k = 0; k < res[2]; ++k)
        for (int j = 0; j < res[1]; ++j)
            for (int i = 0; i < res[0]; ++i) {
                const int idx[3] = {i, j, k};
                const double s = ldexp(1.0, (int)floor(rng_range(r, -6.0, 7.0)));
                for (int q = 0; q < 3 * nc; ++q) rgb[q] = s * rng_range(r, -1.0, 1.0);
                for (int c = 0; c < 3; ++c)
                    for (int a = 0; a < 3; ++a)
                        for (int q = 0; q < nc; ++q) grad[(3 * c + a) * nc + q] = s * rng_range(r, -1.0, 1.0) / h[a];
                for (int g = 0; g < ngrids; ++g) CHECK(shl_grid_set_node(grids[g], idx, rgb, grad) == SHL_OK);
            }
}

/* Float sums on grids of spacing h (the box lo + (res - 1) h, h[a] = hscale
 * times 1, 1/2, 1/2: dyadic, so nodes are float points) on every ISA (scalar:
 * the float reference) against the double reference shl_grid_interp (scalar
 * context, same float node data) at the same float points, widened: within
 * ff_bound of each entry's cell M; on nodes the node's value exactly; 3 threads
 * equal 1.  Returns the worst error / (FLT_EPSILON M) per method in worst[]. */
static void ff_check(const char *isa, int lmax, double hscale, double worst[3])
{
    const char *names[3] = {"trilinear", "Taylor", "Hermite"};
    const int res[3] = {4, 3, 5};
    const double h[3] = {hscale, 0.5 * hscale, 0.5 * hscale};
    const double lo[3] = {-1.0 * hscale, 0.25 * hscale, -0.5 * hscale};
    const double hi[3] = {lo[0] + 3 * h[0], lo[1] + 2 * h[1], lo[2] + 4 * h[2]};
    static double pts[3 * IP_NP], ptd[3 * IP_NP], want[3 * IP_NC * IP_NP], M[3 * IP_NC];
    static float ptf[3 * IP_NP], got[3 * IP_NC * IP_NP], got3[3 * IP_NC * IP_NP];
    shl_ctx *ctx = isa_ctx(isa, lmax), *ref = isa_ctx("scalar", lmax);
    if (ctx && ref) {
        const int nc = SHL_NCOEFFS(lmax), nv = 3 * nc;
        shl_grid *grids[2] = {NULL, NULL};
        CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &grids[0]) == SHL_OK);
        CHECK(shl_grid_create(ref, lo, hi, res, SHL_GRID_FLOAT, &grids[1]) == SHL_OK);
        rng_t r = {(uint64_t)(500 + lmax)};
        ff_nodes(&r, grids, 2, res, h, nc);
        /* interp_points' offsets outside the box (up to 2) times hscale / 4: float points */
        interp_points(&r, lo, hi, res, pts);
        for (int q = 0; q < 3 * IP_NP; ++q) {
            const int a = q % 3;
            const double x = pts[q] < lo[a] ? lo[a] - (lo[a] - pts[q]) * 0.25 * hscale
                             : pts[q] > hi[a] ? hi[a] + (pts[q] - hi[a]) * 0.25 * hscale : pts[q];
            ptf[q] = (float)x;
            ptd[q] = ptf[q];
        }
        for (int m = 0; m < 3; ++m) {
            const double b = m == SHL_INTERP_TAYLOR ? (lmax % 2 ? 0.7 : 2.0) : 0.0;
            CHECK(shl_grid_interp_f(grids[0], m, b, IP_NP, ptf, got, 1) == SHL_OK);
            CHECK(shl_grid_interp_f(grids[0], m, b, IP_NP, ptf, got3, 3) == SHL_OK);
            CHECK(memcmp(got, got3, sizeof(float) * nv * IP_NP) == 0);
            CHECK(shl_grid_interp(grids[1], m, b, IP_NP, ptd, want, 1) == SHL_OK);
            for (int p = 0; p < IP_NP; ++p) {
                ff_cell_scale(grids[1], lo, hi, res, ptd + 3 * p, nc, M);
                for (int q = 0; q < nv; ++q) {
                    const double gq = got[p * nv + q], wq = want[p * nv + q], e = fabs(gq - wq);
                    if (p % 5 == 1 && gq != wq) /* on a node: the node's value, exactly */
                        harness_fail(__FILE__, __LINE__, "[%s, lmax %d, h %g] %s at node %d: %a, node value %a", isa,
                                     lmax, hscale, names[m], p, gq, wq);
                    if (!(e <= ff_bound(m, M[q])))
                        harness_fail(__FILE__, __LINE__, "[%s, lmax %d, h %g] %s point %d entry %d: error %.3g M, bound %.3g M",
                                     isa, lmax, hscale, names[m], p, q, e / M[q], ff_bound(m, M[q]) / M[q]);
                    if (M[q] > 0.0) worst[m] = fmax(worst[m], e / (FLT_EPSILON * M[q]));
                }
            }
        }
        shl_grid_destroy(grids[0]);
        shl_grid_destroy(grids[1]);
    }
    shl_ctx_destroy(ctx);
    shl_ctx_destroy(ref);
}

/* Every ISA (scalar: the float reference), lmax 0..8 (nc = 1 .. 81 against 4-,
 * 8- and 16-lane float vectors: short rows, one block, groups of 1-4 blocks and
 * overlapping last blocks), every method, random points, points on nodes, cell
 * faces, box faces and clamped outside; spacings 1, 1/2, 1/2 and, at lmax 4,
 * 2^-99, 2^-100, 2^-100 (the lower limit) and 2^126, 2^125, 2^125 (the box up
 * to 2^127, so that its points are floats). */
SHL_TEST(simd_interp_f_vs_reference)
{
    char note[512] = "worst |shl_grid_interp_f - double reference| / (FLT_EPSILON M), trilinear, Taylor, Hermite "
                     "(bounds 4.5, 36, 15.75):";
    for (int i = 0; i < NISA; ++i) {
        double worst[3] = {-1, -1, -1}; /* stays negative when this CPU cannot run the ISA */
        for (int lmax = 0; lmax <= IP_LMAX; ++lmax) ff_check(isas[i], lmax, 1.0, worst);
        ff_check(isas[i], 4, 0x1p-99, worst);
        ff_check(isas[i], 4, 0x1p126, worst);
        if (worst[0] >= 0.0)
            snprintf(note + strlen(note), sizeof note - strlen(note), " %s %.2f, %.2f, %.2f;", isas[i], worst[0], worst[1],
                     worst[2]);
    }
    harness_note("%s", note);
}

/* pts reordered by cell (x fastest, as src/interp.c's locate picks it; stable):
 * runs of points of one cell, which the float kernels take two at a time. */
static void sort_by_cell(const double lo[3], const double hi[3], const int res[3], double *pts)
{
    static double tmp[3 * IP_NP];
    static long key[IP_NP];
    static int order[IP_NP];
    for (int p = 0; p < IP_NP; ++p) {
        key[p] = 0;
        for (int a = 2; a >= 0; --a) {
            const double h = (hi[a] - lo[a]) / (res[a] - 1), x = fmin(fmax(pts[3 * p + a], lo[a]), hi[a]);
            const double t = (x - lo[a]) / h;
            key[p] = key[p] * res[a] + (t < res[a] - 1 ? (int)t : res[a] - 2);
        }
        int q = p; /* insertion sort of the indices */
        for (; q > 0 && key[order[q - 1]] > key[p]; --q) order[q] = order[q - 1];
        order[q] = p;
    }
    memcpy(tmp, pts, sizeof tmp);
    for (int p = 0; p < IP_NP; ++p)
        for (int a = 0; a < 3; ++a) pts[3 * p + a] = tmp[3 * order[p] + a];
}

/* Look-ahead and threads change no value: on every ISA, lmax 0, 3, 5, 8, every
 * method, a grid below and one above SHL__INTERP_AHEAD_BYTES, random points and
 * the same sorted by cell (consecutive points of one cell: the kernels' pairs), a
 * call over all points, an odd sub-range and 3 threads equal one call per point,
 * bit for bit. */
SHL_TEST(simd_interp_f_lookahead_and_threads)
{
    const double lo[3] = {-1.0, 0.25, -0.5}, hi[3] = {1.5, 1.0, 2.5};
    const int lmaxes[4] = {0, 3, 5, IP_LMAX};
    static double pts[3 * IP_NP];
    static float ptf[3 * IP_NP], one[3 * IP_NC * IP_NP], all[3 * IP_NC * IP_NP];
    for (int i = 0; i < NISA; ++i)
        for (int l = 0; l < 4; ++l) {
            shl_ctx *ctx = isa_ctx(isas[i], lmaxes[l]);
            if (!ctx) continue;
            const int nv = 3 * SHL_NCOEFFS(lmaxes[l]);
            for (int big = 0; big < 2; ++big) {
                int bpn;
                CHECK(shl_grid_bytes_per_node(lmaxes[l], SHL_GRID_FLOAT, &bpn) == SHL_OK);
                const int r = (int)ceil(cbrt((double)SHL__INTERP_AHEAD_BYTES / bpn)) + 1;
                const int res[3] = {big ? r : 4, big ? r : 3, big ? r : 5};
                CHECK(((size_t)res[0] * res[1] * res[2] * bpn > SHL__INTERP_AHEAD_BYTES) == big);
                double h[3];
                for (int a = 0; a < 3; ++a) h[a] = (hi[a] - lo[a]) / (res[a] - 1);
                shl_grid *g = NULL;
                CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &g) == SHL_OK);
                rng_t rng = {(uint64_t)(170 + l)};
                random_nodes(&rng, &g, 1, res, h, nv / 3);
                interp_points(&rng, lo, hi, res, pts);
                for (int sorted = 0; sorted < 2; ++sorted) {
                    if (sorted) sort_by_cell(lo, hi, res, pts);
                    for (int q = 0; q < 3 * IP_NP; ++q) ptf[q] = (float)pts[q];
                    for (int m = 0; m < 3; ++m) {
                        for (int p = 0; p < IP_NP; ++p)
                            CHECK(shl_grid_interp_f(g, m, 1.5, 1, ptf + 3 * p, one + (size_t)nv * p, 1) == SHL_OK);
                        const size_t bytes = sizeof(float) * nv * IP_NP;
                        CHECK(shl_grid_interp_f(g, m, 1.5, IP_NP, ptf, all, 1) == SHL_OK);
                        CHECK(memcmp(one, all, bytes) == 0);
                        memset(all, 0, bytes);
                        CHECK(shl_grid_interp_f(g, m, 1.5, 101, ptf + 3 * 7, all + (size_t)nv * 7, 1) == SHL_OK);
                        CHECK(memcmp(one + (size_t)nv * 7, all + (size_t)nv * 7, sizeof(float) * nv * 101) == 0);
                        CHECK(shl_grid_interp_f(g, m, 1.5, IP_NP, ptf, all, 3) == SHL_OK);
                        CHECK(memcmp(one, all, bytes) == 0);
                    }
                }
                shl_grid_destroy(g);
            }
            shl_ctx_destroy(ctx);
        }
}

/* Errors before anything is written: those of shl_grid_interp, a double grid,
 * spacings outside [2^-100, 2^127] for Taylor and Hermite (trilinear runs), a
 * non-finite coordinate of the last point. */
SHL_TEST(grid_interp_f_errors)
{
    shl_ctx *ctx = NULL;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    const int res[3] = {2, 3, 2};
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    shl_grid *g = NULL, *gd = NULL;
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, &g) == SHL_OK);
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_DOUBLE, &gd) == SHL_OK);
    float pts[6] = {0.5f, 0.5f, 0.5f, 0.25f, 0.75f, 2.0f}, out[54];
    for (int k = 0; k < 54; ++k) out[k] = 7.0f;
    CHECK(shl_grid_interp_f(NULL, 0, 0.0, 2, pts, out, 1) == SHL_ENULL);
    CHECK(shl_grid_interp_f(g, 0, 0.0, 2, NULL, out, 1) == SHL_ENULL);
    CHECK(shl_grid_interp_f(g, 0, 0.0, 2, pts, NULL, 1) == SHL_ENULL);
    CHECK(shl_grid_interp_f(g, 3, 0.0, 2, pts, out, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, -1, 0.0, 2, pts, out, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, SHL_INTERP_TAYLOR, NAN, 2, pts, out, 1) == SHL_ENONFINITE);
    CHECK(shl_grid_interp_f(g, SHL_INTERP_TAYLOR, 0.0, 2, pts, out, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, SHL_INTERP_TAYLOR, -1.0, 2, pts, out, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, 0, 0.0, -1, pts, out, 1) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, 0, 0.0, 2, pts, out, 0) == SHL_EDOMAIN);
    CHECK(shl_grid_interp_f(g, 0, 0.0, 2, pts, out, SHL_MAX_THREADS + 1) == SHL_EDOMAIN);
    for (int m = 0; m < 3; ++m) CHECK(shl_grid_interp_f(gd, m, 1.0, 2, pts, out, 1) == SHL_EDOMAIN);
    pts[5] = NAN; /* the last point: checked before anything is written */
    CHECK(shl_grid_interp_f(g, SHL_INTERP_HERMITE, 0.0, 2, pts, out, 1) == SHL_ENONFINITE);
    pts[5] = -INFINITY;
    CHECK(shl_grid_interp_f(g, SHL_INTERP_TRILINEAR, 0.0, 2, pts, out, 1) == SHL_ENONFINITE);
    pts[5] = 2.0f;
    /* spacings just outside [2^-100, 2^127]: 2^-101 and 2^128 on axis 1 */
    const double tiny[3] = {0x1p-100, 2 * 0x1p-101, 0x1p-100}, huge[3] = {1, 2 * 0x1p128, 1};
    shl_grid *gt = NULL, *gh = NULL;
    CHECK(shl_grid_create(ctx, lo, tiny, res, SHL_GRID_FLOAT, &gt) == SHL_OK);
    CHECK(shl_grid_create(ctx, lo, huge, res, SHL_GRID_FLOAT, &gh) == SHL_OK);
    for (int m = SHL_INTERP_TAYLOR; m <= SHL_INTERP_HERMITE; ++m) {
        CHECK(shl_grid_interp_f(gt, m, 1.0, 2, pts, out, 1) == SHL_EDOMAIN);
        CHECK(shl_grid_interp_f(gh, m, 1.0, 2, pts, out, 1) == SHL_EDOMAIN);
    }
    for (int k = 0; k < 54; ++k) CHECK(out[k] == 7.0f);
    CHECK(shl_grid_interp_f(g, 0, 0.0, 0, pts, out, 1) == SHL_OK && out[0] == 7.0f);
    CHECK(shl_grid_interp_f(gt, SHL_INTERP_TRILINEAR, 0.0, 2, pts, out, 1) == SHL_OK && out[0] == 0.0f);
    CHECK(shl_grid_interp_f(gh, SHL_INTERP_TRILINEAR, 0.0, 2, pts, out, 1) == SHL_OK && out[0] == 0.0f);
    shl_grid_destroy(g);
    shl_grid_destroy(gd);
    shl_grid_destroy(gt);
    shl_grid_destroy(gh);
    shl_ctx_destroy(ctx);
}
