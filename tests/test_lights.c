/* Light sets: sums of per-light shl_polygon / shl_polygon_grad scaled by the
 * radiance, the quadrature reference (ref_quad.c), finite differences,
 * one-sided emission, bad input and allocation failures. */
#include "geom.h"
#include "fd_check.h"
#include "harness.h"
#include "internal.h"
#include "ref_quad.h"
#include <float.h>
#include <math.h>
#include <string.h>

enum { LMAX = 6, NC = SHL_NCOEFFS(LMAX), NLIGHTS = 5 };

/* A fixed random scene: NLIGHTS polygons (3..6 vertices, one concave) around the origin. */
typedef struct {
    double verts[NLIGHTS][18];
    int n[NLIGHTS];
    double rgb[NLIGHTS][3];
} scene;

static void make_scene(scene *s, unsigned seed)
{
    rng_t r = {seed};
    for (int i = 0; i < NLIGHTS; ++i) {
        double center[3], nrm[3];
        for (int k = 0; k < 3; ++k) center[k] = rng_range(&r, -2.0, 2.0);
        center[2] += 3.0; /* above the test points (|x| <= 1) */
        rng_unit_vector(&r, nrm);
        s->n[i] = 3 + i % 4;
        random_polygon(&r, s->n[i], s->n[i] == 6, center, nrm, rng_range(&r, 0.4, 1.2), s->verts[i]);
        for (int c = 0; c < 3; ++c) s->rgb[i][c] = rng_range(&r, -0.5, 2.0);
    }
}

static shl_lights *scene_lights(const scene *s, int two_sided)
{
    shl_lights *l = NULL;
    CHECK(shl_lights_create(&l) == SHL_OK);
    for (int i = 0; i < NLIGHTS; ++i) CHECK(shl_lights_add_polygon(l, s->verts[i], s->n[i], s->rgb[i], two_sided) == SHL_OK);
    return l;
}

static double max_abs(const double *v, int n)
{
    double m = 0.0;
    for (int i = 0; i < n; ++i) m = fmax(m, fabs(v[i]));
    return m;
}

/* The set equals sum_i rgb_i x shl_polygon(_grad) of light i (the set
 * accumulates ZH integrals before one reconstruction: rounding differs). */
SHL_TEST(lights_sum_of_polygons)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    scene s;
    make_scene(&s, 11);
    shl_lights *l = scene_lights(&s, 1);
    CHECK(shl_lights_count(l) == NLIGHTS);
    rng_t r = {5};
    double worst_v = 0.0, worst_g = 0.0;
    for (int it = 0; it < 20; ++it) {
        double x[3], rgb[3 * NC + 1], grad[9 * NC + 1], want[3 * NC], want_g[9 * NC];
        for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0);
        memset(want, 0, sizeof want);
        memset(want_g, 0, sizeof want_g);
        for (int i = 0; i < NLIGHTS; ++i) {
            double c[NC], g[3 * NC];
            CHECK(shl_polygon_grad(ctx, x, s.verts[i], s.n[i], c, g) == SHL_OK);
            for (int ch = 0; ch < 3; ++ch)
                for (int k = 0; k < NC; ++k) {
                    want[ch * NC + k] += s.rgb[i][ch] * c[k];
                    for (int a = 0; a < 3; ++a) want_g[(ch * 3 + a) * NC + k] += s.rgb[i][ch] * g[a * NC + k];
                }
        }
        guard_fill(rgb, 3 * NC + 1);
        guard_fill(grad, 9 * NC + 1);
        CHECK(shl_lights_eval(ctx, l, x, rgb, grad) == SHL_OK);
        CHECK(rgb[3 * NC] == GUARD_VALUE && grad[9 * NC] == GUARD_VALUE);
        CHECK(all_finite(rgb, 3 * NC) && all_finite(grad, 9 * NC));
        const double sv = max_abs(want, 3 * NC), sg = max_abs(want_g, 9 * NC);
        for (int k = 0; k < 3 * NC; ++k) worst_v = fmax(worst_v, fabs(rgb[k] - want[k]) / sv);
        for (int k = 0; k < 9 * NC; ++k) worst_g = fmax(worst_g, fabs(grad[k] - want_g[k]) / sg);
        double only[3 * NC]; /* the coefficients do not depend on whether gradients are asked for */
        CHECK(shl_lights_eval(ctx, l, x, only, NULL) == SHL_OK);
        CHECK(memcmp(only, rgb, sizeof only) == 0);
    }
    /* the sum differs only in summation order: a few ulps of the largest term */
    CHECK(worst_v <= 1e-13 && worst_g <= 1e-13);
    harness_note("max rel diff coeffs %.1e, grads %.1e (tol 1e-13)", worst_v, worst_g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* One point against the independent quadrature (ref_quad.c), light by light. */
SHL_TEST(lights_vs_quadrature_reference)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    scene s;
    make_scene(&s, 12);
    shl_lights *l = scene_lights(&s, 1);
    const double x[3] = {0.2, -0.3, 0.1};
    double rgb[3 * NC], grad[9 * NC], want[3 * NC] = {0}, want_g[9 * NC] = {0};
    for (int i = 0; i < NLIGHTS; ++i) {
        double c[NC], g[3 * NC];
        CHECK(ref_polygon_sh_grad(LMAX, x, s.verts[i], s.n[i], c, g, NULL) == 0);
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < NC; ++k) {
                want[ch * NC + k] += s.rgb[i][ch] * c[k];
                for (int a = 0; a < 3; ++a) want_g[(ch * 3 + a) * NC + k] += s.rgb[i][ch] * g[a * NC + k];
            }
    }
    CHECK(shl_lights_eval(ctx, l, x, rgb, grad) == SHL_OK);
    double ev = 0.0, eg = 0.0;
    for (int k = 0; k < 3 * NC; ++k) ev = fmax(ev, fabs(rgb[k] - want[k]));
    for (int k = 0; k < 9 * NC; ++k) eg = fmax(eg, fabs(grad[k] - want_g[k]));
    ev /= max_abs(want, 3 * NC);
    eg /= max_abs(want_g, 9 * NC);
    CHECK(ev <= 1e-10 && eg <= 1e-8); /* the polygon tests' tolerances vs the same reference */
    harness_note("vs quadrature: coeffs %.1e, grads %.1e", ev, eg);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Set gradient against central differences of the set's own coefficients:
 * step 1e-4 gives truncation ~ h^2 |f'''| ~ 1e-8 and rounding ~ eps/h ~ 1e-12. */
/* max |grad - central differences (step h)| / max|FD| of a light set over 10
 * random points in [-half, half]^3. */
typedef struct {
    const shl_ctx *ctx;
    const shl_lights *l;
} lights_arg;

static void lights_values(void *arg, const double x[3], double *rgb)
{
    const lights_arg *a = arg;
    CHECK(shl_lights_eval(a->ctx, a->l, x, rgb, NULL) == SHL_OK);
}

/* max over random points |x_k| <= half of |grad - FD| / bound (fd_check.h), with the
 * evaluation error E = 1e-12 sum_i |rgb_i| Omega_i(x) (the polygon contract, README: <= 1e-12
 * Omega per light up to lmax 14) and the gradient error 1e-8 max|grad| (polygon_grad_vs_reference_random);
 * spheres use the same with Omega <= 4 pi (their contract, 1e-13 relative, is tighter).  The
 * coefficients vary over lengths 1 / kappa >= distance / (lmax + 1) (and the gap to a sphere);
 * these scenes keep distances and gaps >= 0.4, so with h = 2^-13, h kappa < 3e-3 as fd_check.h
 * needs.  *raw: max |grad - FD| / max|grad|. */
static double grad_vs_central_differences(const shl_ctx *ctx, const shl_lights *l, unsigned seed, double half,
                                          double (*verts)[18], const int *nverts, double (*rgbs)[3],
                                          int nlights, double *raw, double *fd_only)
{
    rng_t r = {seed};
    const double h = 0x1p-13;
    double worst = 0.0;
    *raw = *fd_only = 0.0;
    for (int it = 0; it < 10; ++it) {
        double x[3], rgb[3 * NC], grad[9 * NC], g[9 * NC];
        for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -half, half);
        CHECK(shl_lights_eval(ctx, l, x, rgb, grad) == SHL_OK);
        for (int a = 0; a < 3; ++a) /* grad[(ch 3 + a) NC + k] -> g[a (3 NC) + ch NC + k] */
            for (int ch = 0; ch < 3; ++ch)
                for (int k = 0; k < NC; ++k) g[a * 3 * NC + ch * NC + k] = grad[(ch * 3 + a) * NC + k];
        double eval_err = 0.0;
        for (int i = 0; i < nlights; ++i) {
            double omega = 4.0 * M_PI; /* a sphere light: whole sphere as the bound */
            if (verts) CHECK(shl_polygon_solid_angle(x, verts[i], nverts[i], &omega) == SHL_OK);
            eval_err += 1e-12 * fmax(fabs(rgbs[i][0]), fmax(fabs(rgbs[i][1]), fabs(rgbs[i][2]))) * omega;
        }
        lights_arg arg = {ctx, l};
        const fd_result fr = fd_compare(lights_values, &arg, x, h, 3 * NC, g);
        const double gm = max_abs(g, 9 * NC);
        worst = fmax(worst, fr.err / fd_bound(&fr, eval_err, 1e-8 * gm));
        *raw = fmax(*raw, fr.err / gm);
        *fd_only = fmax(*fd_only, fr.err / fd_bound(&fr, eval_err, 0.0));
    }
    return worst;
}

SHL_TEST(lights_grad_vs_finite_differences)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    scene s;
    make_scene(&s, 13);
    shl_lights *l = scene_lights(&s, 0);
    double raw, fd_only;
    const double worst = grad_vs_central_differences(ctx, l, 7, 1.0, s.verts, s.n, s.rgb, NLIGHTS, &raw, &fd_only);
    CHECK(worst <= 1.0);
    harness_note("one-sided set: max |grad - FD| / max|grad| %.1e; error / derived bound %.2g (without the "
                 "gradient contract's term: %.2g)", raw, worst, fd_only);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

SHL_TEST(lights_one_sided)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(4, &ctx) == SHL_OK);
    enum { N4 = SHL_NCOEFFS(4) };
    const double tri[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1};              /* (v1-v0)x(v2-v0) = +z */
    const double star[18] = {1, 0, 1, 0.2, 0.2, 1, 0, 1, 1, -0.2, 0.2, 1, -1, 0, 1, 0, -0.5, 1}; /* concave, CCW from +z */
    const double white[3] = {1, 1, 1}, rgb[3] = {0.5, 1.5, -2.0};
    const double *polys[2] = {tri, star};
    const int ns[2] = {3, 6};
    for (int pi = 0; pi < 2; ++pi) {
        shl_lights *one = NULL, *two = NULL;
        CHECK(shl_lights_create(&one) == SHL_OK && shl_lights_create(&two) == SHL_OK);
        CHECK(shl_lights_add_polygon(one, polys[pi], ns[pi], rgb, 0) == SHL_OK);
        CHECK(shl_lights_add_polygon(two, polys[pi], ns[pi], rgb, 1) == SHL_OK);
        /* front (z > 1), including a point 1e-9 above the plane: identical to two-sided */
        const double front[3][3] = {{0.2, 0.3, 2.0}, {-3.0, 4.0, 1.5}, {0.1, 0.1, 1.0 + 1e-9}};
        for (int i = 0; i < 3; ++i) {
            double a[3 * N4], ga[9 * N4], b[3 * N4], gb[9 * N4];
            CHECK(shl_lights_eval(ctx, one, front[i], a, ga) == SHL_OK);
            CHECK(shl_lights_eval(ctx, two, front[i], b, gb) == SHL_OK);
            CHECK(memcmp(a, b, sizeof a) == 0 && memcmp(ga, gb, sizeof ga) == 0);
            CHECK(b[0] != 0.0);
        }
        /* behind (z < 1, including 1e-9 below) and in the plane (z = 1): nothing */
        const double back[4][3] = {{0.2, 0.3, 0.0}, {5.0, 5.0, -10.0}, {0.1, 0.1, 1.0 - 1e-9}, {0.1, 0.1, 1.0}};
        for (int i = 0; i < 4; ++i) {
            double a[3 * N4], ga[9 * N4], b[3 * N4], gb[9 * N4];
            CHECK(shl_lights_eval(ctx, one, back[i], a, ga) == SHL_OK);
            for (int k = 0; k < 3 * N4; ++k) CHECK(a[k] == 0.0);
            for (int k = 0; k < 9 * N4; ++k) CHECK(ga[k] == 0.0);
            CHECK(shl_lights_eval(ctx, two, back[i], b, gb) == SHL_OK);
            if (i < 3) CHECK(b[0] != 0.0); /* two-sided does light the back */
        }
        shl_lights_destroy(one);
        shl_lights_destroy(two);
    }
    /* Reversed winding faces -z; a one-sided and the reversed one-sided light together equal one two-sided light. */
    const double rev[9] = {0, 0, 1, 0, 1, 1, 1, 0, 1};
    shl_lights *pair = NULL, *two = NULL;
    CHECK(shl_lights_create(&pair) == SHL_OK && shl_lights_create(&two) == SHL_OK);
    CHECK(shl_lights_add_polygon(pair, tri, 3, white, 0) == SHL_OK);
    CHECK(shl_lights_add_polygon(pair, rev, 3, white, 0) == SHL_OK);
    CHECK(shl_lights_add_polygon(two, tri, 3, white, 1) == SHL_OK);
    const double pts[6] = {0.3, 0.2, 3.0, 0.3, 0.2, -3.0};
    double a[2 * 3 * N4], b[2 * 3 * N4];
    CHECK(shl_lights_eval_batch(ctx, pair, 2, pts, a, NULL) == SHL_OK);
    CHECK(shl_lights_eval_batch(ctx, two, 2, pts, b, NULL) == SHL_OK);
    for (int k = 0; k < 2 * 3 * N4; ++k) CHECK_NEAR(a[k], b[k], 1e-15); /* |L00| ~ 0.04: the winding only changes rounding */
    shl_lights_destroy(pair);
    shl_lights_destroy(two);
    shl_ctx_destroy(ctx);
}

SHL_TEST(lights_batch_equals_single_and_empty_set)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    scene s;
    make_scene(&s, 14);
    shl_lights *l = scene_lights(&s, 0);
    enum { NP = 7 };
    double pts[3 * NP], rgb[NP * 3 * NC + 1], grad[NP * 9 * NC + 1];
    rng_t r = {3};
    for (int k = 0; k < 3 * NP; ++k) pts[k] = rng_range(&r, -1.0, 1.0);
    guard_fill(rgb, NP * 3 * NC + 1);
    guard_fill(grad, NP * 9 * NC + 1);
    CHECK(shl_lights_eval_batch(ctx, l, NP, pts, rgb, grad) == SHL_OK);
    CHECK(rgb[NP * 3 * NC] == GUARD_VALUE && grad[NP * 9 * NC] == GUARD_VALUE);
    for (int p = 0; p < NP; ++p) {
        double a[3 * NC], g[9 * NC];
        CHECK(shl_lights_eval(ctx, l, pts + 3 * p, a, g) == SHL_OK);
        CHECK(memcmp(a, rgb + p * 3 * NC, sizeof a) == 0 && memcmp(g, grad + p * 9 * NC, sizeof g) == 0);
    }
    CHECK(shl_lights_eval_batch(ctx, l, 0, pts, rgb, NULL) == SHL_OK);
    shl_lights *empty;
    CHECK(shl_lights_create(&empty) == SHL_OK);
    CHECK(shl_lights_count(empty) == 0);
    CHECK(shl_lights_eval(ctx, empty, pts, rgb, grad) == SHL_OK);
    for (int k = 0; k < 3 * NC; ++k) CHECK(rgb[k] == 0.0);
    for (int k = 0; k < 9 * NC; ++k) CHECK(grad[k] == 0.0);
    shl_lights_destroy(empty);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

SHL_TEST(lights_bad_input)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    enum { N2 = SHL_NCOEFFS(2) };
    shl_lights *l;
    CHECK(shl_lights_create(NULL) == SHL_ENULL);
    CHECK(shl_lights_create(&l) == SHL_OK);
    const double tri[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1}, rgb[3] = {1, 1, 1};
    double bad_v[9], bad_rgb[3] = {1, NAN, 1}, inf_rgb[3] = {1, 1, INFINITY};
    memcpy(bad_v, tri, sizeof tri);
    bad_v[4] = NAN;
    CHECK(shl_lights_add_polygon(NULL, tri, 3, rgb, 0) == SHL_ENULL);
    CHECK(shl_lights_add_polygon(l, NULL, 3, rgb, 0) == SHL_ENULL);
    CHECK(shl_lights_add_polygon(l, tri, 3, NULL, 0) == SHL_ENULL);
    CHECK(shl_lights_add_polygon(l, tri, 2, rgb, 0) == SHL_ENVERTS);
    CHECK(shl_lights_add_polygon(l, tri, SHL_MAX_VERTS + 1, rgb, 0) == SHL_ENVERTS);
    CHECK(shl_lights_add_polygon(l, tri, 3, rgb, 2) == SHL_EDOMAIN);
    CHECK(shl_lights_add_polygon(l, tri, 3, rgb, -1) == SHL_EDOMAIN);
    CHECK(shl_lights_add_polygon(l, bad_v, 3, rgb, 0) == SHL_ENONFINITE);
    CHECK(shl_lights_add_polygon(l, tri, 3, bad_rgb, 0) == SHL_ENONFINITE);
    CHECK(shl_lights_add_polygon(l, tri, 3, inf_rgb, 1) == SHL_ENONFINITE);
    CHECK(shl_lights_count(l) == 0);
    CHECK(shl_lights_count(NULL) == SHL_ENULL);
    CHECK(shl_lights_add_polygon(l, tri, 3, rgb, 1) == SHL_OK);

    const double x[3] = {0.2, 0.2, 0}, xnan[3] = {0, NAN, 0};
    double out[3 * N2 + 1], g[9 * N2 + 1];
    guard_fill(out, 3 * N2 + 1);
    guard_fill(g, 9 * N2 + 1);
    CHECK(shl_lights_eval(NULL, l, x, out, g) == SHL_ENULL);
    CHECK(shl_lights_eval(ctx, NULL, x, out, g) == SHL_ENULL);
    CHECK(shl_lights_eval(ctx, l, NULL, out, g) == SHL_ENULL);
    CHECK(shl_lights_eval(ctx, l, x, NULL, g) == SHL_ENULL);
    CHECK(shl_lights_eval(ctx, l, xnan, out, g) == SHL_ENONFINITE);
    const double pts[6] = {0, 0, 0, 0, 0, INFINITY};
    CHECK(shl_lights_eval_batch(ctx, l, -1, pts, out, g) == SHL_EDOMAIN);
    CHECK(shl_lights_eval_batch(ctx, l, 2, pts, out, g) == SHL_ENONFINITE); /* the second point is bad: nothing written */
    CHECK(shl_lights_eval_batch(ctx, l, 1, NULL, out, g) == SHL_ENULL);
    CHECK(shl_lights_eval_batch(NULL, l, 1, pts, out, g) == SHL_ENULL);
    CHECK(guard_intact(out, 3 * N2 + 1) && guard_intact(g, 9 * N2 + 1));
    shl_lights_destroy(NULL);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Every allocation of create / add (growth of both arrays; polygons and spheres
 * interleaved, a sphere grows only the record array) / eval / eval_batch fails
 * in turn: SHL_ENOMEM, the set unchanged and usable, nothing leaked (ASan). */
SHL_TEST(lights_alloc_failures)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(3, &ctx) == SHL_OK);
    enum { N3 = SHL_NCOEFFS(3), NADD = 40 };
    const double quad[12] = {-1, -1, 2, 1, -1, 2, 1, 1, 2, -1, 1, 2}, rgb[3] = {1, 0.5, 0.25};
    const double x[3] = {0.1, 0.2, 0.3}, sc[3] = {0.5, -1.0, 1.5};
    double want[3 * N3];
    int failures = 0;
    for (long fail = 0;; ++fail) {
        shl_lights *l = NULL;
        shl__alloc_fail_after = fail;
        int st = shl_lights_create(&l);
        int added = 0;
        for (int i = 0; st == SHL_OK && i < NADD; ++i) {
            st = i % 2 ? shl_lights_add_sphere(l, sc, 0.4, rgb) : shl_lights_add_polygon(l, quad, 4, rgb, 1);
            if (st == SHL_OK) ++added;
            else CHECK(shl_lights_count(l) == added);
        }
        double out[3 * N3 + 1], g[9 * N3 + 1], bout[3 * N3 + 1], bg[9 * N3 + 1];
        guard_fill(out, 3 * N3 + 1);
        guard_fill(g, 9 * N3 + 1);
        guard_fill(bout, 3 * N3 + 1);
        guard_fill(bg, 9 * N3 + 1);
        int st_eval = SHL_OK;
        if (st == SHL_OK) st = st_eval = shl_lights_eval(ctx, l, x, out, g);
        if (st == SHL_OK) st = shl_lights_eval_batch(ctx, l, 1, x, bout, bg);
        shl__alloc_fail_after = -1;
        if (st != SHL_OK) {
            CHECK(st == SHL_ENOMEM);
            if (st_eval != SHL_OK) CHECK(guard_intact(out, 3 * N3 + 1) && guard_intact(g, 9 * N3 + 1));
            CHECK(guard_intact(bout, 3 * N3 + 1) && guard_intact(bg, 9 * N3 + 1));
            ++failures;
            if (l) { /* still usable after the failure */
                CHECK(shl_lights_add_polygon(l, quad, 4, rgb, 1) == SHL_OK);
                CHECK(shl_lights_add_sphere(l, sc, 0.4, rgb) == SHL_OK);
                CHECK(shl_lights_count(l) == added + 2);
                CHECK(shl_lights_eval(ctx, l, x, out, NULL) == SHL_OK);
            }
            shl_lights_destroy(l);
            continue;
        }
        /* NADD / 2 identical (polygon, sphere) pairs: NADD / 2 times one pair */
        shl_lights *one;
        CHECK(shl_lights_create(&one) == SHL_OK);
        CHECK(shl_lights_add_polygon(one, quad, 4, rgb, 1) == SHL_OK);
        CHECK(shl_lights_add_sphere(one, sc, 0.4, rgb) == SHL_OK);
        CHECK(shl_lights_eval(ctx, one, x, want, NULL) == SHL_OK);
        CHECK(memcmp(out, bout, sizeof(double) * 3 * N3) == 0 && memcmp(g, bg, sizeof(double) * 9 * N3) == 0);
        for (int k = 0; k < 3 * N3; ++k) CHECK_NEAR(out[k], NADD / 2 * want[k], 1e-13 * NADD * fabs(want[0]));
        shl_lights_destroy(one);
        shl_lights_destroy(l);
        break;
    }
    CHECK(failures >= 9); /* create, 4 record + 3 vertex growths, eval, batch */
    harness_note("%d allocation points failed in turn", failures);
    shl_ctx_destroy(ctx);
}

/* ---- spherical lights --------------------------------------------------- */

/* rgb_c x shl_sphere_grad of one sphere, added to want / want_g (set layouts). */
static void add_sphere_ref(const shl_ctx *ctx, int nc, const double x[3], const double c[3], double rad,
                           const double rgb[3], double *want, double *want_g)
{
    double co[SHL_NCOEFFS(SHL_LMAX_MAX)], g[3 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    CHECK(shl_sphere_grad(ctx, x, c, rad, co, g) == SHL_OK);
    for (int ch = 0; ch < 3; ++ch)
        for (int k = 0; k < nc; ++k) {
            want[ch * nc + k] += rgb[ch] * co[k];
            for (int a = 0; a < 3; ++a) want_g[(ch * 3 + a) * nc + k] += rgb[ch] * g[a * nc + k];
        }
}

/* A set holding one sphere equals rgb x shl_sphere / shl_sphere_grad: random
 * spheres and points, points inside, on the surface and at the centre, a point
 * just outside, tiny, distant and far-scaled spheres; lmax 0, 1, 6 and 30.
 * The set goes through the lobe integrals and their reconstruction (cond ~22
 * per band): coefficients within 1e-13 of the largest one up to lmax 6; at
 * lmax 30 the reconstruction alone, fed long-double lobe integrals rounded once,
 * is ~3e-13 away from shl_sphere (shl_sphere itself is within 3e-14 of a
 * long-double reference), hence 1e-12 there. */
SHL_TEST(lights_sphere_equals_shl_sphere)
{
    enum { LM = SHL_LMAX_MAX, NCM = SHL_NCOEFFS(SHL_LMAX_MAX) };
    static double rgb[3 * NCM + 1], grad[9 * NCM + 1], want[3 * NCM], want_g[9 * NCM], only[3 * NCM];
    const int lmaxes[4] = {0, 1, LMAX, LM};
    const double col[3] = {0.7, -1.3, 2.5};
    double worst_v = 0.0, worst_v30 = 0.0, worst_g = 0.0;
    int inside_pts = 0;
    for (int li = 0; li < 4; ++li) {
        shl_ctx *ctx;
        CHECK(shl_ctx_create(lmaxes[li], &ctx) == SHL_OK);
        const int nc = SHL_NCOEFFS(lmaxes[li]);
        rng_t r = {21 + (unsigned)li};
        for (int it = 0; it < 40; ++it) {
            double x[3], c[3], rad, dir[3];
            rng_unit_vector(&r, dir);
            for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0);
            double d = rng_range(&r, 0.5, 5.0);
            rad = d * rng_range(&r, 0.02, 0.98);
            switch (it) {
            case 0: rad = 1e-9; d = 1.0; break;          /* tiny */
            case 1: rad = 1e-150; d = 3.0; break;        /* tiny, w_l ~ 1e-300 */
            case 2: rad = 1.0; d = 1e8; break;           /* distant */
            case 3: rad = 1e199; d = 3e199; break;       /* far-scaled coordinates */
            case 4: rad = 2.0; d = 2.0 * (1.0 + 1e-12); break; /* just outside: gradient ~ 1e6 */
            case 5: rad = 2.0; d = 1.0; break;           /* inside */
            case 6: rad = 0.5; d = 0.0; break;           /* at the centre */
            case 7: rad = 4.0; d = 4.0; break;           /* on the surface (d = rad exactly for dir = e_z) */
            default: break;
            }
            for (int k = 0; k < 3; ++k) c[k] = x[k] + d * dir[k];
            if (it == 3) for (int k = 0; k < 3; ++k) c[k] = d * dir[k], x[k] = 0.0;
            if (it == 7) { /* dyadic coordinates: |center - x| = 4 = radius exactly */
                const double xs[3] = {0.25, -0.5, 0.5}, cs[3] = {0.25, -0.5, 4.5};
                memcpy(x, xs, sizeof xs);
                memcpy(c, cs, sizeof cs);
            }
            const int inside = it >= 5 && it <= 7;
            shl_lights *l;
            CHECK(shl_lights_create(&l) == SHL_OK);
            CHECK(shl_lights_add_sphere(l, c, rad, col) == SHL_OK && shl_lights_count(l) == 1);
            memset(want, 0, sizeof(double) * 3 * nc);
            memset(want_g, 0, sizeof(double) * 9 * nc);
            add_sphere_ref(ctx, nc, x, c, rad, col, want, want_g);
            guard_fill(rgb, 3 * nc + 1);
            guard_fill(grad, 9 * nc + 1);
            CHECK(shl_lights_eval(ctx, l, x, rgb, grad) == SHL_OK);
            CHECK(rgb[3 * nc] == GUARD_VALUE && grad[9 * nc] == GUARD_VALUE);
            CHECK(all_finite(rgb, 3 * nc) && all_finite(grad, 9 * nc));
            CHECK(shl_lights_eval(ctx, l, x, only, NULL) == SHL_OK);
            CHECK(memcmp(only, rgb, sizeof(double) * 3 * nc) == 0);
            const double sv = max_abs(want, 3 * nc), sg = max_abs(want_g, 9 * nc);
            CHECK(sv > 0.0);
            double ev = 0.0, eg = 0.0;
            for (int k = 0; k < 3 * nc; ++k) ev = fmax(ev, fabs(rgb[k] - want[k]) / sv);
            if (inside) { /* the whole sphere of directions: band 0 only, no gradient */
                ++inside_pts;
                CHECK(sg == 0.0);
                for (int k = 0; k < 9 * nc; ++k) CHECK(grad[k] == 0.0);
                for (int ch = 0; ch < 3; ++ch) {
                    CHECK_NEAR(rgb[ch * nc], col[ch] * sqrt(4.0 * M_PI), 1e-15 * fabs(col[ch]) * 4.0);
                    for (int k = 1; k < nc; ++k) CHECK(rgb[ch * nc + k] == 0.0);
                }
            } else {
                CHECK(sg > 0.0);
                for (int k = 0; k < 9 * nc; ++k) eg = fmax(eg, fabs(grad[k] - want_g[k]) / sg);
            }
            const double tol_v = lmaxes[li] <= LMAX ? 1e-13 : 1e-12;
            if (!(ev <= tol_v && eg <= 1e-12))
                harness_fail(__FILE__, __LINE__, "lmax %d case %d: rel diff coeffs %.2e grads %.2e", lmaxes[li], it, ev, eg);
            if (lmaxes[li] <= LMAX) worst_v = fmax(worst_v, ev);
            else worst_v30 = fmax(worst_v30, ev);
            worst_g = fmax(worst_g, eg);
            shl_lights_destroy(l);
        }
        shl_ctx_destroy(ctx);
    }
    CHECK(inside_pts == 12);
    harness_note("160 points: max rel diff coeffs lmax 0/1/6 %.1e (tol 1e-13), lmax 30 %.1e (tol 1e-12); "
                 "grads lmax 0..30 %.1e (tol 1e-12)", worst_v, worst_v30, worst_g);
}

/* Polygons and spheres in one set: the sum of rgb x shl_polygon_grad and rgb x shl_sphere_grad. */
SHL_TEST(lights_mixed_set_sum_of_parts)
{
    enum { NSPH = 3 };
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    scene s;
    make_scene(&s, 31);
    const double sc[NSPH][3] = {{0.5, -0.2, 0.3}, {-2.0, 1.0, 2.5}, {30.0, -40.0, 10.0}};
    const double sr[NSPH] = {0.6, 0.8, 1e-3}, srgb[NSPH][3] = {{1.0, 2.0, 0.5}, {-0.3, 0.4, 1.1}, {1e4, 2e4, 3e4}};
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    for (int i = 0; i < NLIGHTS; ++i) { /* interleaved */
        CHECK(shl_lights_add_polygon(l, s.verts[i], s.n[i], s.rgb[i], 1) == SHL_OK);
        if (i < NSPH) CHECK(shl_lights_add_sphere(l, sc[i], sr[i], srgb[i]) == SHL_OK);
    }
    CHECK(shl_lights_count(l) == NLIGHTS + NSPH);
    rng_t r = {9};
    double worst_v = 0.0, worst_g = 0.0;
    int inside_pts = 0;
    for (int it = 0; it < 30; ++it) {
        double x[3], rgb[3 * NC], grad[9 * NC], want[3 * NC] = {0}, want_g[9 * NC] = {0};
        for (int k = 0; k < 3; ++k) x[k] = rng_range(&r, -1.0, 1.0);
        if (it == 0) x[0] = 0.5, x[1] = -0.2, x[2] = 0.3; /* centre of sphere 0 */
        const double dx[3] = {x[0] - sc[0][0], x[1] - sc[0][1], x[2] - sc[0][2]};
        inside_pts += sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]) <= sr[0];
        for (int i = 0; i < NLIGHTS; ++i) {
            double c[NC], g[3 * NC];
            CHECK(shl_polygon_grad(ctx, x, s.verts[i], s.n[i], c, g) == SHL_OK);
            for (int ch = 0; ch < 3; ++ch)
                for (int k = 0; k < NC; ++k) {
                    want[ch * NC + k] += s.rgb[i][ch] * c[k];
                    for (int a = 0; a < 3; ++a) want_g[(ch * 3 + a) * NC + k] += s.rgb[i][ch] * g[a * NC + k];
                }
        }
        for (int i = 0; i < NSPH; ++i) add_sphere_ref(ctx, NC, x, sc[i], sr[i], srgb[i], want, want_g);
        CHECK(shl_lights_eval(ctx, l, x, rgb, grad) == SHL_OK);
        const double sv = max_abs(want, 3 * NC), sg = max_abs(want_g, 9 * NC);
        for (int k = 0; k < 3 * NC; ++k) worst_v = fmax(worst_v, fabs(rgb[k] - want[k]) / sv);
        for (int k = 0; k < 9 * NC; ++k) worst_g = fmax(worst_g, fabs(grad[k] - want_g[k]) / sg);
    }
    CHECK(inside_pts >= 2);
    CHECK(worst_v <= 1e-13 && worst_g <= 1e-12);
    harness_note("%d polygons + %d spheres, 30 points (%d inside a sphere): max rel diff coeffs %.1e, grads %.1e",
                 NLIGHTS, NSPH, inside_pts, worst_v, worst_g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* The set's sphere gradient against central differences of its own coefficients (h = 1e-5). */
SHL_TEST(lights_sphere_grad_vs_finite_differences)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    const double c1[3] = {0.3, 0.2, 2.0}, c2[3] = {-1.5, 0.5, -0.5};
    double rgbs[2][3] = {{1, 2, 3}, {0.5, -1, 0.25}};
    CHECK(shl_lights_add_sphere(l, c1, 0.9, rgbs[0]) == SHL_OK);
    CHECK(shl_lights_add_sphere(l, c2, 0.3, rgbs[1]) == SHL_OK);
    double raw, fd_only;
    const double worst = grad_vs_central_differences(ctx, l, 17, 0.8, NULL, NULL, rgbs, 2, &raw, &fd_only);
    CHECK(worst <= 1.0);
    harness_note("two spheres: max |grad - FD| / max|grad| %.1e; error / derived bound %.2g (without the "
                 "gradient contract's term: %.2g)", raw, worst, fd_only);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

SHL_TEST(lights_sphere_bad_input)
{
    shl_lights *l;
    CHECK(shl_lights_create(&l) == SHL_OK);
    const double c[3] = {0, 0, 2}, rgb[3] = {1, 1, 1}, cnan[3] = {0, NAN, 2}, cinf[3] = {-INFINITY, 0, 2};
    const double rgbnan[3] = {NAN, 1, 1}, rgbinf[3] = {1, 1, INFINITY};
    CHECK(shl_lights_add_sphere(NULL, c, 1.0, rgb) == SHL_ENULL);
    CHECK(shl_lights_add_sphere(l, NULL, 1.0, rgb) == SHL_ENULL);
    CHECK(shl_lights_add_sphere(l, c, 1.0, NULL) == SHL_ENULL);
    CHECK(shl_lights_add_sphere(l, cnan, 1.0, rgb) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, cinf, 1.0, rgb) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, 1.0, rgbnan) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, 1.0, rgbinf) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, NAN, rgb) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, INFINITY, rgb) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, -INFINITY, rgb) == SHL_ENONFINITE);
    CHECK(shl_lights_add_sphere(l, c, 0.0, rgb) == SHL_EDOMAIN);
    CHECK(shl_lights_add_sphere(l, c, -0.0, rgb) == SHL_EDOMAIN);
    CHECK(shl_lights_add_sphere(l, c, -1.0, rgb) == SHL_EDOMAIN);
    CHECK(shl_lights_count(l) == 0);
    /* the same inputs shl_sphere rejects, with the same codes */
    shl_ctx *ctx;
    CHECK(shl_ctx_create(1, &ctx) == SHL_OK);
    const double x[3] = {0, 0, 0};
    double co[4];
    CHECK(shl_sphere(ctx, x, cnan, 1.0, co) == SHL_ENONFINITE);
    CHECK(shl_sphere(ctx, x, c, NAN, co) == SHL_ENONFINITE);
    CHECK(shl_sphere(ctx, x, c, 0.0, co) == SHL_EDOMAIN);
    CHECK(shl_sphere(ctx, x, c, -1.0, co) == SHL_EDOMAIN);
    CHECK(shl_lights_add_sphere(l, c, DBL_MIN / 4, rgb) == SHL_OK); /* subnormal radius: valid, sees ~nothing */
    CHECK(shl_lights_add_sphere(l, c, 1.0, rgb) == SHL_OK);
    CHECK(shl_lights_count(l) == 2);
    double a[3 * 4];
    CHECK(shl_lights_eval(ctx, l, x, a, NULL) == SHL_OK);
    CHECK(shl_sphere(ctx, x, c, 1.0, co) == SHL_OK);
    for (int ch = 0; ch < 3; ++ch)
        for (int k = 0; k < 4; ++k) CHECK_NEAR(a[ch * 4 + k], co[k], 1e-15);
    shl_ctx_destroy(ctx);
    shl_lights_destroy(l);
}

/* Extreme scales (issue 8, K1/K4 through light sets): a one-sided polygon (its
 * front test and Newell normal in scaled units) and a sphere, every input times
 * 2^k (exact).  Coefficients equal the scale-1 ones bit for bit; gradients are
 * ldexp(g_1, -k) exactly for |k| <= 1000.  At k = 1023 (x - v_0 overflows; the
 * gradients ~2^-1023 are denormal) each accumulated lobe value is rounded to a
 * multiple of 2^-1074 before the reconstruction (<= 61 lobes, weights <= 25):
 * back at scale 1 that is <= 1525 2^-51 = 6.8e-13 absolute; tolerance 1e-11. */
static double lights_scaled_diff(const shl_ctx *ctx, int k, int with_sphere)
{
    enum { N = SHL_NCOEFFS(6) };
    const double tri[9] = {0, 0, -1, 1.5, 0, -1, 0, 1.5, -1}, x1[3] = {0.25, 0.5, 1}; /* faces +z: x in front */
    const double c1[3] = {0.5, -0.75, 0.25}, rgb[3] = {0.5, 1.5, -2.0}, rgb2[3] = {1, 2, 3};
    double v[9], x[3], c[3], a[3 * N], ga[9 * N], b[3 * N], gb[9 * N], worst = 0.0;
    for (int i = 0; i < 9; ++i) v[i] = ldexp(tri[i], k);
    for (int i = 0; i < 3; ++i) x[i] = ldexp(x1[i], k), c[i] = ldexp(c1[i], k);
    shl_lights *s1 = NULL, *sk = NULL;
    CHECK(shl_lights_create(&s1) == SHL_OK && shl_lights_create(&sk) == SHL_OK);
    CHECK(shl_lights_add_polygon(s1, tri, 3, rgb, 0) == SHL_OK && shl_lights_add_polygon(sk, v, 3, rgb, 0) == SHL_OK);
    if (with_sphere)
        CHECK(shl_lights_add_sphere(s1, c1, 0.25, rgb2) == SHL_OK && shl_lights_add_sphere(sk, c, ldexp(0.25, k), rgb2) == SHL_OK);
    CHECK(shl_lights_eval(ctx, s1, x1, a, ga) == SHL_OK && shl_lights_eval(ctx, sk, x, b, gb) == SHL_OK);
    CHECK(memcmp(a, b, sizeof a) == 0 && a[0] != 0.0);
    for (int i = 0; i < 9 * N; ++i) worst = fmax(worst, fabs(ldexp(gb[i], k) - ga[i]));
    worst = isnan(worst) ? INFINITY : worst; /* a NaN gradient fails */
    shl_lights_destroy(s1);
    shl_lights_destroy(sk);
    return worst;
}

SHL_TEST(lights_extreme_scales)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(6, &ctx) == SHL_OK);
    const int ks[] = {-1000, -500, 500, 1000};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i) CHECK(lights_scaled_diff(ctx, ks[i], 1) == 0.0);
    const double e = lights_scaled_diff(ctx, 1023, 0);
    CHECK(e <= 1e-11);
    harness_note("2^-1000..2^1000 exact; 2^1023 (x - v_0 overflows) gradient %.1e", e);
    shl_ctx_destroy(ctx);
}
