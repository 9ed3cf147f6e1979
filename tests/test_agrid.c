/* Adaptive grids (shl_agrid_*): bad input and allocation/thread failures (nothing
 * written, handles NULL), accuracy against shl_lights_eval (double) at independent
 * random points, C0 continuity across level boundaries, the node budget, thread
 * independence, refills equal to fresh fills, a light inside the box refined around
 * instead of blurred, and budget-driven (best-first) fills, receivers and weighted
 * receivers. */
#include "harness.h"
#include "agrid.h"    /* shl__alevel: the refined cells */
#include "internal.h" /* shl__alloc_fail_after, shl__thread_fail_after */
#include "testutil.h"
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { LMAX = 4, NC = SHL_NCOEFFS(LMAX), NV = 3 * NC };

static const double box_lo[3] = {-1.0, -1.0, -1.0}, box_hi[3] = {1.0, 1.0, 1.0};

/* max over colours of the L2 norm of the nc-coefficient difference (the estimate's norm, shlight.h) */
static double err_norm(const double *a, const double *b)
{
    double m = 0.0;
    for (int c = 0; c < 3; ++c) {
        double s = 0.0;
        for (int k = 0; k < NC; ++k) s += (a[c * NC + k] - b[c * NC + k]) * (a[c * NC + k] - b[c * NC + k]);
        m = fmax(m, sqrt(s));
    }
    return m;
}

/* Lights outside the box (distance >= 0.5): a smooth field inside it. */
static shl_lights *outside_lights(void)
{
    shl_lights *l;
    const double quad[12] = {-1, -1, 1.6, 1, -1, 1.6, 1, 1, 1.6, -1, 1, 1.6}, c1[3] = {1.0, 0.8, 0.6};
    const double ctr[3] = {1.8, -0.3, 0.2}, c2[3] = {0.4, 0.5, 2.0};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_polygon(l, quad, 4, c1, 1) == SHL_OK);
    CHECK(shl_lights_add_sphere(l, ctr, 0.3, c2) == SHL_OK);
    return l;
}

/* Wu 2020 Fig. 12 in miniature: a two-sided quad standing inside the box at x = 0.3. */
static shl_lights *inside_light(void)
{
    shl_lights *l;
    const double quad[12] = {0.3, -0.9, -0.5, 0.3, -0.9, 0.5, 0.3, 0.2, 0.5, 0.3, 0.2, -0.5}, c[3] = {2.0, 4.0, 7.0};
    CHECK(shl_lights_create(&l) == SHL_OK);
    CHECK(shl_lights_add_polygon(l, quad, 4, c, 1) == SHL_OK);
    return l;
}

static shl_ctx *ctx_new(void)
{
    shl_ctx *ctx = NULL;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    return ctx;
}

/* An adaptive grid on the coarse 4^3 lattice of the test box with nrecv receivers
 * recv (weights w, NULL: unweighted; none if nrecv = 0), filled (2 threads), its stats in *st. */
static shl_agrid *filled_for(const shl_ctx *ctx, const shl_lights *l, int criterion, double tol, long budget, int nrecv,
                             const double *recv, const double *w, shl_agrid_stats *st)
{
    const int r4[3] = {4, 4, 4};
    shl_agrid *g = NULL;
    CHECK(shl_agrid_create(ctx, box_lo, box_hi, r4, criterion, tol, budget, &g) == SHL_OK);
    CHECK(shl_agrid_set_weighted_receivers(g, nrecv, recv, w) == SHL_OK);
    CHECK(shl_agrid_fill(g, l, 2) == SHL_OK);
    CHECK(shl_agrid_get_stats(g, st) == SHL_OK);
    return g;
}

static shl_agrid *filled(const shl_ctx *ctx, const shl_lights *l, int criterion, double tol, long budget,
                         shl_agrid_stats *st)
{
    return filled_for(ctx, l, criterion, tol, budget, 0, NULL, NULL, st);
}

/* n points: positions, the exact values there and room for an interpolant's values. */
typedef struct {
    int n;
    double *pts, *ref, *out;
} probe;

static probe probe_new(int n)
{
    probe p = {n, malloc(sizeof(double) * 3 * (size_t)n), malloc(sizeof(double) * NV * (size_t)n),
               malloc(sizeof(double) * NV * (size_t)n)};
    CHECK(p.pts && p.ref && p.out);
    return p;
}

static void probe_free(probe *p)
{
    free(p->pts);
    free(p->ref);
    free(p->out);
}

/* Mean over the probe's points of the error of values a (err_norm). */
static double mean_err(const probe *p, const double *a)
{
    double m = 0.0;
    for (int i = 0; i < p->n; ++i) m += err_norm(a + (size_t)i * NV, p->ref + (size_t)i * NV) / p->n;
    return m;
}

/* Mean error at the probe's points of the adaptive grid g. */
static double agrid_mean_err(const shl_agrid *g, probe *p)
{
    CHECK(shl_agrid_interp(g, p->n, p->pts, p->out, 2) == SHL_OK);
    return mean_err(p, p->out);
}

/* Mean error at the probe's points of the uniform Hermite grid (float nodes) with
 * the fewest nodes res^3 >= nodes; its res into *res. */
static double uniform_mean_err(const shl_ctx *ctx, const shl_lights *l, long nodes, const probe *p, int *res)
{
    *res = 4;
    while ((long)*res * *res * *res < nodes) ++*res;
    const int ru[3] = {*res, *res, *res};
    shl_grid *u;
    double *b = malloc(sizeof(double) * NV * (size_t)p->n);
    CHECK(b != NULL);
    CHECK(shl_grid_create(ctx, box_lo, box_hi, ru, SHL_GRID_FLOAT, &u) == SHL_OK);
    CHECK(shl_grid_fill(u, l, 2) == SHL_OK);
    CHECK(shl_grid_interp(u, SHL_INTERP_HERMITE, 0.0, p->n, p->pts, b, 2) == SHL_OK);
    const double e = mean_err(p, b);
    free(b);
    shl_grid_destroy(u);
    return e;
}

SHL_TEST(agrid_bad_input)
{
    shl_ctx *ctx = ctx_new();
    static char garbage;
    shl_agrid *g = (shl_agrid *)(void *)&garbage;
    const int r4[3] = {4, 4, 4}, r1[3] = {4, 1, 4}, rbig[3] = {4, SHL_GRID_RES_MAX + 1, 4};
    const double nan3[3] = {0, NAN, 0}, far[3] = {1e300, 1e300, 1e300}, far2[3] = {2e300, 2e300, 2e300};
    CHECK(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, 1000, NULL) == SHL_ENULL);
#define BAD(call, want)                                                                                                \
    do {                                                                                                               \
        g = (shl_agrid *)(void *)&garbage;                                                                             \
        CHECK((call) == (want) && g == NULL);                                                                          \
    } while (0)
    BAD(shl_agrid_create(NULL, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_ENULL);
    BAD(shl_agrid_create(ctx, NULL, box_hi, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_ENULL);
    BAD(shl_agrid_create(ctx, box_lo, NULL, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_ENULL);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, NULL, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_ENULL);
    BAD(shl_agrid_create(ctx, nan3, box_hi, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_ENONFINITE);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, NAN, 1000, &g), SHL_ENONFINITE);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, INFINITY, 1000, &g), SHL_ENONFINITE);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 0.0, 1000, &g), SHL_EDOMAIN);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, -1.0, 1000, &g), SHL_EDOMAIN);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, 2, 1e-3, 1000, &g), SHL_EDOMAIN); /* no such criterion */
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r1, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_EDOMAIN);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, rbig, SHL_AGRID_MAX, 1e-3, 100000000, &g), SHL_EDOMAIN);
    BAD(shl_agrid_create(ctx, box_hi, box_lo, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_EDOMAIN);
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, 63, &g), SHL_EDOMAIN);       /* < 4^3 */
#if LONG_MAX > 0x7FFFFFFFL
    BAD(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, 0x80000000L, &g), SHL_EDOMAIN); /* > 2^31 - 1 */
#endif
    BAD(shl_agrid_create(ctx, far, far2, r4, SHL_AGRID_MAX, 1e-3, 1000, &g), SHL_EDOMAIN);          /* beyond the float fill */
#undef BAD
    /* allocation failures: every one SHL_ENOMEM with *out = NULL, until the call succeeds */
    long k = 0;
    for (;; ++k) {
        g = (shl_agrid *)(void *)&garbage;
        shl__alloc_fail_after = k;
        const int st = shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, 1000, &g);
        shl__alloc_fail_after = -1;
        if (st == SHL_OK) break;
        CHECK(st == SHL_ENOMEM && g == NULL);
        if (k > 64) break;
    }
    CHECK(k <= 64 && g != NULL);
    harness_note("create: %ld allocation failures -> NULL", k);

    shl_lights *l = outside_lights();
    const double pt[6] = {0, 0, 0, 0.1, NAN, 0};
    double out[2 * NV];
    for (int i = 0; i < 2 * NV; ++i) out[i] = 42.0;
    shl_agrid_stats st;
    CHECK(shl_agrid_fill(NULL, l, 1) == SHL_ENULL);
    CHECK(shl_agrid_fill(g, NULL, 1) == SHL_ENULL);
    CHECK(shl_agrid_fill(g, l, 0) == SHL_EDOMAIN);
    CHECK(shl_agrid_fill(g, l, SHL_MAX_THREADS + 1) == SHL_EDOMAIN);
    CHECK(shl_agrid_interp(NULL, 1, pt, out, 1) == SHL_ENULL);
    CHECK(shl_agrid_interp(g, 1, NULL, out, 1) == SHL_ENULL);
    CHECK(shl_agrid_interp(g, 1, pt, NULL, 1) == SHL_ENULL);
    CHECK(shl_agrid_interp(g, -1, pt, out, 1) == SHL_EDOMAIN);
    CHECK(shl_agrid_interp(g, 1, pt, out, 0) == SHL_EDOMAIN);
    CHECK(shl_agrid_interp(g, 2, pt, out, 1) == SHL_ENONFINITE);
    CHECK(shl_agrid_interp(g, 0, NULL, NULL, 1) == SHL_OK);
    int untouched = 1;
    for (int i = 0; i < 2 * NV; ++i) untouched &= out[i] == 42.0;
    CHECK(untouched);
    CHECK(shl_agrid_get_stats(NULL, &st) == SHL_ENULL);
    CHECK(shl_agrid_get_stats(g, NULL) == SHL_ENULL);
    /* before any fill: level 0, zeros */
    CHECK(shl_agrid_get_stats(g, &st) == SHL_OK);
    CHECK(st.nodes == 64 && st.levels == 1 && st.cells == 27 && st.bytes > 64 * 12 * NC * 4);
    CHECK(shl_agrid_interp(g, 1, pt, out, 1) == SHL_OK);
    int zero = 1;
    for (int i = 0; i < NV; ++i) zero &= out[i] == 0.0;
    CHECK(zero);
    shl_agrid_destroy(g);
    shl_agrid_destroy(NULL);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* A failed fill (allocation, thread creation) leaves the grid as it was: same
 * interpolated values bit for bit, same stats. */
SHL_TEST(agrid_failed_fill_unchanged)
{
    shl_ctx *ctx = ctx_new();
    shl_lights *l1 = outside_lights(), *l2 = inside_light();
    const int r4[3] = {4, 4, 4};
    shl_agrid *g;
    CHECK(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-2, 3000, &g) == SHL_OK);
    CHECK(shl_agrid_fill(g, l1, 2) == SHL_OK);
    enum { NP = 64 };
    rng_t r = {7};
    double pts[3 * NP], before[NP * NV], after[NP * NV];
    for (int i = 0; i < 3 * NP; ++i) pts[i] = rng_range(&r, -1.0, 1.0);
    shl_agrid_stats s0, s1;
    CHECK(shl_agrid_interp(g, NP, pts, before, 1) == SHL_OK);
    CHECK(shl_agrid_get_stats(g, &s0) == SHL_OK);
    long k = 0, bad = 0;
    for (;; ++k) {
        shl__alloc_fail_after = k;
        const int st = shl_agrid_fill(g, l2, 1);
        shl__alloc_fail_after = -1;
        if (st == SHL_OK) break;
        CHECK(st == SHL_ENOMEM);
        CHECK(shl_agrid_interp(g, NP, pts, after, 1) == SHL_OK);
        CHECK(shl_agrid_get_stats(g, &s1) == SHL_OK);
        bad += memcmp(before, after, sizeof before) != 0 || memcmp(&s0, &s1, sizeof s0) != 0;
        if (k > 2000) break;
    }
    CHECK(bad == 0 && k <= 2000);
    harness_note("fill: %ld allocation failures, grid unchanged after each", k);
    CHECK(shl_agrid_fill(g, l1, 2) == SHL_OK);
    shl__thread_fail_after = 0;
    const int st = shl_agrid_fill(g, l2, 2);
    shl__thread_fail_after = -1;
    CHECK(st == SHL_ETHREAD);
    CHECK(shl_agrid_interp(g, NP, pts, after, 1) == SHL_OK);
    CHECK(memcmp(before, after, sizeof before) == 0);
    shl_agrid_destroy(g);
    shl_lights_destroy(l1);
    shl_lights_destroy(l2);
    shl_ctx_destroy(ctx);
}

SHL_TEST(agrid_threads_and_budget)
{
    shl_ctx *ctx = ctx_new();
    shl_lights *l = inside_light();
    const int r4[3] = {4, 4, 4};
    enum { NP = 500 };
    rng_t r = {11};
    double pts[3 * NP], *a = malloc(sizeof(double) * NP * NV), *b = malloc(sizeof(double) * NP * NV);
    for (int i = 0; i < 3 * NP; ++i) pts[i] = rng_range(&r, -1.0, 1.0);
    /* budgets: the node count never exceeds one; a tight one stops the refinement */
    const long budgets[4] = {64, 500, 3000, 20000};
    long prev = 0;
    for (int i = 0; i < 4; ++i) {
        shl_agrid *g;
        shl_agrid_stats s1, s2;
        CHECK(shl_agrid_create(ctx, box_lo, box_hi, r4, SHL_AGRID_MAX, 1e-3, budgets[i], &g) == SHL_OK);
        CHECK(shl_agrid_fill(g, l, 1) == SHL_OK);
        CHECK(shl_agrid_get_stats(g, &s1) == SHL_OK);
        CHECK(shl_agrid_interp(g, NP, pts, a, 1) == SHL_OK);
        CHECK(shl_agrid_fill(g, l, 2) == SHL_OK);
        CHECK(shl_agrid_get_stats(g, &s2) == SHL_OK);
        CHECK(shl_agrid_interp(g, NP, pts, b, 2) == SHL_OK);
        CHECK(memcmp(a, b, sizeof(double) * NP * NV) == 0 && memcmp(&s1, &s2, sizeof s1) == 0);
        CHECK(s1.nodes <= budgets[i] && s1.nodes >= prev);
        CHECK(s1.budget_hit == 1 && s1.unresolved != 0); /* a light in the box: tol 1e-3 is never met */
        if (i == 0) CHECK(s1.levels == 1 && s1.nodes == 64);
        harness_note("budget %ld: %ld nodes, %d levels", budgets[i], s1.nodes, s1.levels);
        prev = s1.nodes;
        shl_agrid_destroy(g);
    }
    free(a);
    free(b);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* The probe's exact values (shl_lights_eval_batch, double); returns the largest norm of one. */
static double reference_values(const shl_ctx *ctx, const shl_lights *l, probe *p)
{
    CHECK(shl_lights_eval_batch(ctx, l, p->n, p->pts, p->ref, NULL) == SHL_OK);
    double norm = 0.0;
    const double zero[NV] = {0};
    for (int i = 0; i < p->n; ++i) norm = fmax(norm, err_norm(p->ref + (size_t)i * NV, zero));
    return norm;
}

/* A probe of np random points in [-1, 1]^3 (rng seed) with the set's exact values;
 * the largest norm of a value into *norm. */
static probe reference_points(const shl_ctx *ctx, const shl_lights *l, int np, unsigned seed, double *norm)
{
    probe p = probe_new(np);
    rng_t r = {seed};
    for (int i = 0; i < 3 * np; ++i) p.pts[i] = rng_range(&r, -1.0, 1.0);
    *norm = reference_values(ctx, l, &p);
    return p;
}

/* A test's context, light set (owned) and probe of np random points (reference_points). */
typedef struct {
    shl_ctx *ctx;
    shl_lights *l;
    probe pr;
    double norm; /* the largest norm of an exact value at the probe's points */
} fixture;

static fixture fixture_new(shl_lights *l, int np, unsigned seed)
{
    fixture f = {ctx_new(), l, {0, NULL, NULL, NULL}, 0.0};
    f.pr = reference_points(f.ctx, l, np, seed, &f.norm);
    return f;
}

static void fixture_free(fixture *f)
{
    probe_free(&f->pr);
    shl_lights_destroy(f->l);
    shl_ctx_destroy(f->ctx);
}

/* Accuracy where the budget allows the tolerance (every cell's estimate <= tol,
 * stats.unresolved == 0), at NP random points independent of the estimate's samples,
 * against shl_lights_eval in double.  Acceptance, from the estimate's behaviour:
 * in a cell where the field is smooth on the scale h, the error of Alg. 4 is a sum
 * of terms each a product, over at most two axes, of the 1D shapes u^2 (1-u)^2
 * (cubic Hermite along an axis), u (1-u) and u (1-u) (1-2u) (the gradients carried
 * linearly); each shape's maximum over [0, 1] is at most 16/9 times its magnitude at
 * u = 1/4 and 3/4 (the samples; 16/9 for u^2 (1-u)^2), and the two samples see a
 * term odd and a term even under u -> 1-u as |even| + |odd|.  So the error is
 * <= (16/9)^2 tol = 3.2 tol for such cells, plus the float rounding of nodes and of
 * the batch that measured the samples (relative ~1e-6 of |L|, README "Batch
 * evaluation and SIMD").  Blended rings are a convex combination of two levels:
 * the coarser estimated there (its cell was not refined), the finer not (ring
 * cells keep the coarser cell's verdict, include/shlight.h), its error there
 * expected no larger (h^3 to h^4 smaller for a smooth field).  The bound is asymptotic (h small against the distance to the
 * lights: here >= 0.5 at h <= 0.33), so the test accepts 4 tol + 1e-5 max|L|;
 * it also requires the mean error to be below tol. */
/* A refill starts from the last fill's node and cell counts (src/agrid.c, level_init):
 * refills to fewer nodes (the outside lights), then to more (the inside light), then
 * of the same lights, then to far fewer on the finer levels (a small light above the
 * box) each equal a fresh grid's fill bit for bit, stats included (bytes held: a
 * function of the counts, not of earlier fills). */
SHL_TEST(agrid_refill_equals_fresh_fill)
{
    shl_ctx *ctx = ctx_new();
    shl_lights *in = inside_light(), *out = outside_lights(), *far;
    const double tri[9] = {-0.2, -0.2, 1.5, 0.2, -0.2, 1.5, 0.0, 0.2, 1.5}, c[3] = {1.0, 1.0, 1.0};
    CHECK(shl_lights_create(&far) == SHL_OK);
    CHECK(shl_lights_add_polygon(far, tri, 3, c, 1) == SHL_OK);
    enum { NP = 400 };
    rng_t r = {29};
    double pts[3 * NP], *a = malloc(sizeof(double) * NP * NV), *b = malloc(sizeof(double) * NP * NV);
    for (int i = 0; i < 3 * NP; ++i) pts[i] = rng_range(&r, -1.0, 1.0);
    shl_agrid_stats s;
    shl_agrid *g = filled(ctx, in, SHL_AGRID_MAX, 1e-3, 6000, &s);
    const shl_lights *order[4] = {out, in, in, far};
    long nodes[4];
    int same = 1;
    for (int k = 0; k < 4; ++k) {
        shl_agrid_stats sr, sf;
        CHECK(shl_agrid_fill(g, order[k], 1) == SHL_OK);
        CHECK(shl_agrid_get_stats(g, &sr) == SHL_OK);
        CHECK(shl_agrid_interp(g, NP, pts, a, 1) == SHL_OK);
        shl_agrid *fresh = filled(ctx, order[k], SHL_AGRID_MAX, 1e-3, 6000, &sf);
        CHECK(shl_agrid_interp(fresh, NP, pts, b, 1) == SHL_OK);
        same &= memcmp(a, b, sizeof(double) * NP * NV) == 0 && memcmp(&sr, &sf, sizeof sr) == 0;
        nodes[k] = sr.nodes;
        shl_agrid_destroy(fresh);
    }
    CHECK(same);
    CHECK(nodes[0] < s.nodes && nodes[1] == s.nodes && nodes[2] == s.nodes && nodes[3] < nodes[0]);
    harness_note("nodes %ld -> %ld -> %ld -> %ld -> %ld", s.nodes, nodes[0], nodes[1], nodes[2], nodes[3]);
    shl_agrid_destroy(g);
    shl_lights_destroy(in);
    shl_lights_destroy(out);
    shl_lights_destroy(far);
    shl_ctx_destroy(ctx);
    free(a);
    free(b);
}

SHL_TEST(agrid_smooth_within_tolerance)
{
    enum { NP = 2000 };
    fixture f = fixture_new(outside_lights(), NP, 3);
    const double tols[2] = {1e-2, 1e-3};
    for (int t = 0; t < 2; ++t) {
        const double tol = tols[t] * f.norm;
        shl_agrid_stats st;
        shl_agrid *g = filled(f.ctx, f.l, SHL_AGRID_MAX, tol, 200000, &st);
        CHECK(st.unresolved == 0 && st.budget_hit == 0 && st.max_estimate <= tol);
        CHECK(shl_agrid_interp(g, NP, f.pr.pts, f.pr.out, 2) == SHL_OK);
        double worst = 0.0, mean = 0.0;
        int over = 0;
        for (int p = 0; p < NP; ++p) {
            const double e = err_norm(f.pr.out + (size_t)p * NV, f.pr.ref + (size_t)p * NV);
            worst = fmax(worst, e);
            mean += e / NP;
            over += e > tol;
        }
        CHECK(worst <= 4.0 * tol + 1e-5 * f.norm);
        CHECK(mean <= tol);
        harness_note("tol %.0e max|L|: %ld nodes, %d levels; max err %.2f tol, mean %.2f tol, %d/%d points > tol",
                     tols[t], st.nodes, st.levels, worst / tol, mean / tol, over, NP);
        shl_agrid_destroy(g);
    }
    fixture_free(&f);
}

/* C0 across level boundaries: the boundaries of level l's cells (and their rings'
 * blends) lie on planes of the level-l lattice, x_a = lo + i h_l.  At random points
 * on such planes of every level built, A on the two sides (x_a -+ eps, eps = 2^-40)
 * must agree to rounding: the interpolant's change over 2 eps is at most 2 eps
 * max|grad A| <= 2^-39 * 2^8 max|A| / (h_0 2^-(levels-1)) ~ 1e-9 max|A| here, the
 * double arithmetic's 1e-15 max|A|; a C0 failure would leave a gap of the size of
 * the coarser level's error (the test notes A against the coarse uniform grid at
 * the same points, for scale).  Accepted: 1e-8 max|A|. */
SHL_TEST(agrid_continuous_across_levels)
{
    shl_ctx *ctx = ctx_new();
    shl_lights *l = inside_light();
    const int r4[3] = {4, 4, 4};
    shl_agrid_stats st;
    shl_agrid *g = filled(ctx, l, SHL_AGRID_MAX, 1e-2, 30000, &st);
    CHECK(st.levels >= 3);
    shl_grid *u;
    CHECK(shl_grid_create(ctx, box_lo, box_hi, r4, SHL_GRID_FLOAT, &u) == SHL_OK);
    CHECK(shl_grid_fill(u, l, 1) == SHL_OK);
    enum { NP = 4000 };
    rng_t r = {5};
    double worst = 0.0, amax = 0.0, coarse = 0.0;
    for (int p = 0; p < NP; ++p) {
        const int lev = p % st.levels, axis = (p / st.levels) % 3, n = 3 << lev; /* 3 = res - 1 cells per axis */
        double x[3], two[6], va[2 * NV], vu[NV];
        for (int a = 0; a < 3; ++a) x[a] = rng_range(&r, -1.0, 1.0);
        x[axis] = -1.0 + 2.0 * (double)(1 + (int)(rng_uniform(&r) * (n - 1))) / n; /* an inner lattice plane */
        for (int s = 0; s < 2; ++s) {
            memcpy(two + 3 * s, x, sizeof x);
            two[3 * s + axis] += s ? 0x1p-40 : -0x1p-40;
        }
        CHECK(shl_agrid_interp(g, 2, two, va, 1) == SHL_OK);
        CHECK(shl_grid_interp(u, SHL_INTERP_HERMITE, 0.0, 1, x, vu, 1) == SHL_OK);
        worst = fmax(worst, err_norm(va, va + NV));
        coarse = fmax(coarse, err_norm(va, vu));
        const double zero[NV] = {0};
        amax = fmax(amax, err_norm(va, zero));
    }
    CHECK(worst <= 1e-8 * amax);
    harness_note("%d levels: max gap %.2e max|A| across lattice planes; A vs coarse grid there: %.2e max|A|", st.levels,
                 worst / amax, coarse / amax);
    shl_grid_destroy(u);
    shl_agrid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* A light inside the box (Wu 2020 Fig. 12): the adaptive grid refines around it.
 * Points in the slab 0.05 < x < 0.55 around the quad (x = 0.3): mean error of A
 * against a uniform grid with at least as many nodes.  Model: near the quad the
 * error is dominated by the cells that straddle its discontinuity (the field jumps
 * across a two-sided light) and by its edges, so the mean error there scales with
 * the spacing at the quad.  The cells straddling it have the largest estimates of
 * their level (refined first), so the adaptive grid's spacing there is that of its
 * finest level, h_a = h_0 / 2^(levels-1), against h_u = 2 / (res - 1) for the
 * uniform grid: expected ea / eu ~ h_a / h_u.  Accepted: ea <= 1.25 (h_a / h_u) eu
 * (the 1.25 for the quad's offset from the lattice planes, which sets the straddled
 * volume: 0.2 and 0.15 of a cell here) and ea < eu. */
SHL_TEST(agrid_light_inside_refined)
{
    shl_ctx *ctx = ctx_new();
    shl_lights *l = inside_light();
    shl_agrid_stats st;
    shl_agrid *g = filled(ctx, l, SHL_AGRID_MAX, 1e-2, 30000, &st);
    CHECK(st.levels >= 4);
    enum { NP = 3000 };
    rng_t r = {9};
    probe pr = probe_new(NP);
    for (int p = 0; p < NP; ++p) {
        pr.pts[3 * p] = rng_range(&r, 0.05, 0.55);
        pr.pts[3 * p + 1] = rng_range(&r, -1.0, 1.0);
        pr.pts[3 * p + 2] = rng_range(&r, -1.0, 1.0);
    }
    reference_values(ctx, l, &pr);
    int res;
    const double ea = agrid_mean_err(g, &pr), eu = uniform_mean_err(ctx, l, st.nodes, &pr, &res);
    const double ha = (2.0 / 3.0) / (1 << (st.levels - 1)), hu = 2.0 / (res - 1);
    CHECK(ea <= 1.25 * (ha / hu) * eu && ea < eu);
    harness_note("near the light: adaptive %ld nodes (%d levels) mean err %.3e, uniform %d^3 mean err %.3e: ratio %.2f, "
                 "spacing ratio %.2f", st.nodes, st.levels, ea, res, eu, ea / eu, ha / hu);
    probe_free(&pr);
    shl_agrid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* SHL_AGRID_MEAN on the light inside the box: the criterion e 8^-l > tol stops
 * by itself at the discontinuity (e stays ~|L| there, the threshold grows 8x per
 * level), so with a large budget the fill ends with every estimated cell within it
 * (unresolved == 0, budget not hit).  Mean error over NP random points in the box:
 * each leaf cell c contributes about (its mean error) vol_c / V <= 3.2 e_c vol_c / V
 * (the sample-to-cell factor of agrid_smooth_within_tolerance) <= 3.2 tol / N0
 * (N0 = 27 coarse cells, vol_0 = V / N0), so mean <= 3.2 tol (leaf cells) / N0 <=
 * 3.2 tol cells / N0, a loose bound; the discontinuity is inside cells whose
 * estimate met the criterion, which is all the bound rests on. */
SHL_TEST(agrid_mean_criterion_light_inside)
{
    enum { NP = 3000 };
    fixture f = fixture_new(inside_light(), NP, 13);
    const double tol = 1e-3 * f.norm;
    shl_agrid_stats st;
    shl_agrid *g = filled(f.ctx, f.l, SHL_AGRID_MEAN, tol, 2000000, &st);
    CHECK(st.unresolved == 0 && st.budget_hit == 0 && st.max_estimate <= tol);
    const double mean = agrid_mean_err(g, &f.pr);
    CHECK(mean <= 3.2 * tol * (double)st.cells / 27.0);
    harness_note("tol 1e-3 max|L|: %ld nodes, %d levels, %ld cells; mean err %.2f tol (bound %.0f tol)", st.nodes, st.levels,
                 st.cells, mean / tol, 3.2 * (double)st.cells / 27.0);
    shl_agrid_destroy(g);
    fixture_free(&f);
}

/* Budget-driven fills: SHL_AGRID_MEAN at a tolerance no cell meets, so the budget
 * decides and the refinement goes best first by e 8^-l, on the light inside the box.
 * The queue's order does not depend on the budget, so fills at growing budgets refine
 * prefixes of one sequence, each step where the estimated share of the mean error is
 * largest: the mean error at NP random points against shl_lights_eval (double) must
 * fall as the budget grows 4x, and from 4000 nodes on be below that of the uniform
 * grid with at least as many nodes (the adaptive grid's purpose; at 1000 nodes the
 * ring each refinement carries, up to 5^3 nodes around an isolated refined coarse
 * cell, leaves too few refinements to win, and the ratio is only noted).  Both are
 * strict comparisons, no tolerance (the ratios are noted); the budget must be hit, and the
 * children still waiting unestimated make stats.unresolved unknown (-1) or > 0. */
SHL_TEST(agrid_budget_best_first)
{
    enum { NP = 3000 };
    fixture f = fixture_new(inside_light(), NP, 17);
    const long budgets[3] = {1000, 4000, 16000};
    double prev = INFINITY;
    for (int i = 0; i < 3; ++i) {
        shl_agrid_stats st;
        shl_agrid *g = filled(f.ctx, f.l, SHL_AGRID_MEAN, 1e-9 * f.norm, budgets[i], &st);
        CHECK(st.budget_hit == 1 && st.unresolved != 0 && st.nodes <= budgets[i]);
        int res;
        const double ea = agrid_mean_err(g, &f.pr), eu = uniform_mean_err(f.ctx, f.l, st.nodes, &f.pr, &res);
        CHECK(ea < prev && (budgets[i] < 4000 || ea < eu));
        harness_note("budget %ld: %ld nodes, %d levels, %ld samples; mean err %.3e max|L| (uniform %d^3: %.3e, ratio %.2f)",
                     budgets[i], st.nodes, st.levels, st.samples, ea / f.norm, res, eu / f.norm, ea / eu);
        prev = ea;
        shl_agrid_destroy(g);
    }
    fixture_free(&f);
}

/* Level-l cell index (clamped to the box) of point x, coarse 4^3 on box_lo..box_hi. */
static int cell_of(double x, int l)
{
    const int n = 3 << l;
    const int c = (int)floor((x - box_lo[0]) / (box_hi[0] - box_lo[0]) * n);
    return c < 0 ? 0 : c >= n ? n - 1 : c;
}

/* Whether a refined cell (the parent of a level-l cell all of whose corners are flagged,
 * src/agrid.h) of grid g holds one of the np points pts. */
static int refined_cells_hold(const shl_agrid *g, int np, const double *pts, int *outside)
{
    int ok = 1;
    *outside = 0;
    for (int l = 1; l < g->nlevels; ++l) {
        const shl__alevel *L = g->lev + l;
        for (size_t c = 0; c < L->ncells; ++c) {
            if (L->cell[c].flags != 0xFF) continue;
            const uint64_t k = L->cell_key[c] - 1, m = ((uint64_t)1 << 21) - 1;
            const int pc[3] = {(int)(k >> 42) >> 1, (int)(k >> 21 & m) >> 1, (int)(k & m) >> 1};
            int held = 0;
            for (int p = 0; p < np && !held; ++p)
                held = cell_of(pts[3 * p], l - 1) == pc[0] && cell_of(pts[3 * p + 1], l - 1) == pc[1] &&
                       cell_of(pts[3 * p + 2], l - 1) == pc[2];
            ok &= held;
            *outside |= box_lo[0] + pc[0] * (box_hi[0] - box_lo[0]) / (3 << (l - 1)) >= 0.0; /* wholly in x >= 0 */
        }
    }
    return ok;
}

/* Receivers (shl_agrid_set_receivers) only in the half x < 0 of the box, the
 * two-sided quad of inside_light() in the other half (x = 0.3), MEAN criterion, a
 * tolerance no cell meets and budgets 1000, 4000, 16000 ("the best N nodes"):
 * (1) every refined cell holds a receiver (checked against the receivers directly,
 * src/agrid.h's layout), none lies wholly in x >= 0, where the fill without
 * receivers does refine (around the light); (2) the mean error at the receivers
 * against shl_lights_eval (double) falls as the budget grows 4x, and is below that
 * of the same budget's fill without receivers.  Both comparative, strict, no
 * tolerance (the ratios are noted).  Bad input and a failed allocation: nothing changes. */
SHL_TEST(agrid_receivers_refine_their_half)
{
    enum { NP = 2000 };
    fixture f = fixture_new(inside_light(), NP, 29);
    for (int p = 0; p < NP; ++p) f.pr.pts[3 * p] = -0.5 * (f.pr.pts[3 * p] + 1.0); /* x in (-1, 0] */
    reference_values(f.ctx, f.l, &f.pr);
    {
        const int r4[3] = {4, 4, 4};
        const double nan_pt[3] = {0.0, NAN, 0.0};
        shl_agrid *g;
        CHECK(shl_agrid_create(f.ctx, box_lo, box_hi, r4, SHL_AGRID_MEAN, 1e-9 * f.norm, 1000, &g) == SHL_OK);
        CHECK(shl_agrid_set_receivers(g, 1, nan_pt) == SHL_ENONFINITE && g->recv == NULL);
        CHECK(shl_agrid_set_receivers(g, -1, f.pr.pts) == SHL_EDOMAIN && shl_agrid_set_receivers(g, 1, NULL) == SHL_ENULL);
        CHECK(shl_agrid_set_receivers(NULL, 0, NULL) == SHL_ENULL && g->recv == NULL);
        shl__alloc_fail_after = 0;
        const int oom = shl_agrid_set_receivers(g, NP, f.pr.pts);
        shl__alloc_fail_after = -1;
        CHECK(oom == SHL_ENOMEM && g->recv == NULL);
        shl_agrid_destroy(g);
    }
    const long budgets[3] = {1000, 4000, 16000};
    double prev = INFINITY;
    for (int i = 0; i < 3; ++i) {
        double e[2];
        shl_agrid_stats sw = {0};
        for (int with = 1; with >= 0; --with) {
            shl_agrid_stats st;
            shl_agrid *g = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, 1e-9 * f.norm, budgets[i], with ? NP : 0, f.pr.pts, NULL, &st);
            CHECK(st.budget_hit == 1 && st.nodes <= budgets[i] && st.levels >= 2);
            int outside;
            const int held = refined_cells_hold(g, NP, f.pr.pts, &outside);
            CHECK(with ? held && !outside : outside);
            e[with] = agrid_mean_err(g, &f.pr);
            if (with) sw = st;
            shl_agrid_destroy(g);
        }
        CHECK(e[1] < prev && e[1] < e[0]);
        harness_note("budget %ld with receivers: %ld nodes, %d levels, %ld samples; mean err at the receivers %.3e max|L| "
                     "(without receivers %.3e: ratio %.2f)",
                     budgets[i], sw.nodes, sw.levels, sw.samples, e[1] / f.norm, e[0] / f.norm, e[1] / e[0]);
        prev = e[1];
    }
    fixture_free(&f);
}

/* The grid's interpolated values at the probe's points and its stats equal those of grid h, bit for bit. */
static int same_grids(const shl_agrid *g, const shl_agrid *h, const probe *p)
{
    double *a = malloc(sizeof(double) * NV * (size_t)p->n), *b = malloc(sizeof(double) * NV * (size_t)p->n);
    shl_agrid_stats sg, sh;
    CHECK(a && b && shl_agrid_get_stats(g, &sg) == SHL_OK && shl_agrid_get_stats(h, &sh) == SHL_OK);
    CHECK(shl_agrid_interp(g, p->n, p->pts, a, 2) == SHL_OK && shl_agrid_interp(h, p->n, p->pts, b, 2) == SHL_OK);
    const int same = memcmp(a, b, sizeof(double) * NV * (size_t)p->n) == 0 && sg.nodes == sh.nodes &&
                     sg.samples == sh.samples && sg.levels == sh.levels && sg.max_estimate == sh.max_estimate;
    free(a);
    free(b);
    return same;
}

/* Weighted receivers (shl_agrid_set_weighted_receivers), light inside the box, MEAN,
 * budget-driven (4000 nodes).  Exact identities against independent set-ups, bit for
 * bit: (1) unit weights give the unweighted grid; (2) weight 2 on every receiver gives
 * the grid of every receiver listed twice with weight 1 (a cell's share of the weight
 * and its samples, at 1/4 and 3/4 of its cumulative weight, are the same: sums of small
 * integers are exact); (3) weight 0 on the receivers in x > 0 gives the grid of the
 * others alone.  (4) The weights steer the refinement: receivers in the whole box,
 * weight 1 in x < 0 and 1e-3 in x > 0 (where the light is): the weighted mean error at
 * the receivers is below that of the unweighted fill with the same budget (strict, the
 * ratio noted).  Bad weights (< 0, non-finite, all 0) and failed allocations: the call
 * fails, nothing changes. */
SHL_TEST(agrid_weighted_receivers)
{
    enum { NP = 1500 };
    fixture f = fixture_new(inside_light(), NP, 31);
    double *w = malloc(sizeof(double) * NP), *twice = malloc(sizeof(double) * 6 * NP), *left = malloc(sizeof(double) * 3 * NP);
    CHECK(w && twice && left);
    {
        const int r4[3] = {4, 4, 4};
        const double bad[3][2] = {{1.0, -1.0}, {1.0, NAN}, {0.0, 0.0}};
        const int want[3] = {SHL_EDOMAIN, SHL_ENONFINITE, SHL_EDOMAIN};
        shl_agrid *g;
        CHECK(shl_agrid_create(f.ctx, box_lo, box_hi, r4, SHL_AGRID_MEAN, 1.0, 1000, &g) == SHL_OK);
        for (int k = 0; k < 3; ++k) CHECK(shl_agrid_set_weighted_receivers(g, 2, f.pr.pts, bad[k]) == want[k] && g->recv == NULL);
        const double good[2] = {1.0, 3.0};
        for (long k = 0; k < 2; ++k) { /* the receivers' copy, then their prefix sums, failing */
            shl__alloc_fail_after = k;
            const int oom = shl_agrid_set_weighted_receivers(g, 2, f.pr.pts, good);
            shl__alloc_fail_after = -1;
            CHECK(oom == SHL_ENOMEM && g->recv == NULL && g->recv_cum == NULL);
        }
        CHECK(shl_agrid_set_weighted_receivers(g, 2, f.pr.pts, good) == SHL_OK && g->nrecv == 2 && g->recv_cum[2] == 4.0);
        shl_agrid_destroy(g);
    }
    const double tol = 1e-9 * f.norm;
    const long budget = 4000;
    shl_agrid_stats st;
    shl_agrid *plain = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, NP, f.pr.pts, NULL, &st);
    for (int p = 0; p < NP; ++p) w[p] = 1.0;
    shl_agrid *unit = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, NP, f.pr.pts, w, &st);
    CHECK(same_grids(unit, plain, &f.pr));
    for (int p = 0; p < NP; ++p) {
        w[p] = 2.0;
        memcpy(twice + 6 * p, f.pr.pts + 3 * p, 3 * sizeof(double));
        memcpy(twice + 6 * p + 3, f.pr.pts + 3 * p, 3 * sizeof(double));
    }
    shl_agrid *doubled = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, NP, f.pr.pts, w, &st);
    shl_agrid *listed_twice = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, 2 * NP, twice, NULL, &st);
    CHECK(same_grids(doubled, listed_twice, &f.pr));
    int nleft = 0;
    for (int p = 0; p < NP; ++p) {
        w[p] = f.pr.pts[3 * p] > 0.0 ? 0.0 : 1.0;
        if (w[p] > 0.0) memcpy(left + 3 * nleft++, f.pr.pts + 3 * p, 3 * sizeof(double));
    }
    shl_agrid *zeroed = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, NP, f.pr.pts, w, &st);
    shl_agrid *subset = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, nleft, left, NULL, &st);
    CHECK(same_grids(zeroed, subset, &f.pr));
    double wsum = 0.0;
    for (int p = 0; p < NP; ++p) wsum += w[p] = f.pr.pts[3 * p] > 0.0 ? 1e-3 : 1.0;
    shl_agrid *steered = filled_for(f.ctx, f.l, SHL_AGRID_MEAN, tol, budget, NP, f.pr.pts, w, &st);
    double e[2] = {0.0, 0.0};
    const shl_agrid *grids[2] = {plain, steered};
    for (int k = 0; k < 2; ++k) {
        CHECK(shl_agrid_interp(grids[k], NP, f.pr.pts, f.pr.out, 2) == SHL_OK);
        for (int p = 0; p < NP; ++p) e[k] += w[p] * err_norm(f.pr.out + (size_t)p * NV, f.pr.ref + (size_t)p * NV) / wsum;
    }
    CHECK(e[1] < e[0]);
    harness_note("budget %ld: weighted mean err %.3e max|L| with the weights, %.3e without (ratio %.2f)", budget,
                 e[1] / f.norm, e[0] / f.norm, e[1] / e[0]);
    shl_agrid *all[7] = {plain, unit, doubled, listed_twice, zeroed, subset, steered};
    for (int k = 0; k < 7; ++k) shl_agrid_destroy(all[k]);
    free(w);
    free(twice);
    free(left);
    fixture_free(&f);
}
