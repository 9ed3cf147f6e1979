/* Polygon-light coefficient benchmark (Wang & Ramamoorthi 2018):
 *  - time per evaluation vs lmax split into shl_polygon's stages (Fig. 6): set-up, ZH
 *    recurrence (the context's ISA kernel) and reconstruction (rotation),
 *  - time vs number of edges (Fig. 7), with fitted exponents,
 *  - ZH recurrence vs the monomial-moment baseline (Table 2 "Monomial"),
 *  - speed-up over a frozen copy of the issue-16 kernels (bench/common/poly_baseline.c),
 *  - gradient cost: shl_polygon_grad / shl_polygon, whole call and ZH part (Wu 2020 Table 1),
 *    and central differences (7 shl_polygon calls: the coefficients and 6 offsets) /
 *    shl_polygon_grad,
 *  - scalar evaluations per second per core (the SIMD baseline).
 * All ratios come from one run; the frozen-kernel, monomial and gradient sections' from paired
 * rounds on thread CPU time.  CSV: build/bench/bench_polygon.csv (-o overrides); --help.
 * CSV rows "lmax": ns_zh = set-up + ZH recurrence as shl_polygon runs them, ns_rotation the
 * reconstruction (the whole call minus those); "grad": ns_total and ns_zh of the gradient
 * calls; "baseline": ns_total of shl_polygon, ns_zh of the frozen baseline pipeline;
 * "zhmono": ns_zh of the scalar-ISA ZH kernel, ns_rotation of the context's ISA kernel,
 * ns_monomial_total of the monomial baseline (ZH part only). */
#include "monomial.h"
#include "poly_baseline.h"
#include "polygon.h"
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdlib.h>
#include <time.h>

enum { NPTS = 64 };

typedef struct {
    const shl_ctx *ctx;
    int lmax, n;
    double verts[3 * SHL_MAX_VERTS];
    double pts[NPTS][3];
    float vf[3 * SHL_MAX_VERTS], pf[NPTS][3];
    long inner;
    shl__poly_geom geom[NPTS];
} job;

static double zh_buf[(2 * SHL_LMAX_MAX + 1) * SHL__ZH_STRIDE], coef_buf[SHL_NCOEFFS(SHL_LMAX_MAX)];

static void run_full(void *p)
{
    job *j = p;
    double acc = 0;
    for (long i = 0; i < j->inner; ++i) {
        shl_polygon(j->ctx, j->pts[i % NPTS], j->verts, j->n, coef_buf);
        acc += coef_buf[0];
    }
    bench_sink += acc;
}

static void run_full_f(void *p)
{
    job *j = p;
    float out[SHL_NCOEFFS(SHL_LMAX_MAX)];
    double acc = 0;
    for (long i = 0; i < j->inner; ++i) {
        shl_polygon_f(j->ctx, j->pf[i % NPTS], j->vf, j->n, out);
        acc += out[0];
    }
    bench_sink += acc;
}

static void run_setup(void *p) /* shl_polygon's set-up (the geometry without gradient terms) */
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl__poly_geom_init_values(&j->geom[0], j->pts[i % NPTS], j->verts, j->n);
        bench_sink += j->geom[0].solid_angle;
    }
}

static void run_geom_zh(void *p) /* shl_polygon's set-up + ZH recurrence (the context's ISA kernel) */
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl__poly_geom_init_values(&j->geom[0], j->pts[i % NPTS], j->verts, j->n);
        j->ctx->isa->poly_zh(&j->geom[0], j->lmax, zh_buf);
        bench_sink += zh_buf[1];
    }
}

static void run_full_grad(void *p)
{
    job *j = p;
    static double grad_buf[3 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    double acc = 0;
    for (long i = 0; i < j->inner; ++i) {
        shl_polygon_grad(j->ctx, j->pts[i % NPTS], j->verts, j->n, coef_buf, grad_buf);
        acc += grad_buf[0];
    }
    bench_sink += acc;
}

static void run_zh_grad_only(void *p)
{
    job *j = p;
    static double zg[3 * SHL__ZH_BLOCK];
    for (long i = 0; i < j->inner; ++i) shl__poly_zh_grad_d(&j->geom[i % NPTS], j->lmax, zh_buf, zg);
    bench_sink += zg[1];
}

static void run_zh_only(void *p) /* recurrence only, geometry precomputed */
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) shl__poly_zh_d(&j->geom[i % NPTS], j->lmax, zh_buf);
    bench_sink += zh_buf[1];
}

static void run_baseline_full(void *p)
{
    job *j = p;
    double acc = 0;
    for (long i = 0; i < j->inner; ++i) {
        baseline_polygon(j->lmax, j->pts[i % NPTS], j->verts, j->n, coef_buf);
        acc += coef_buf[0];
    }
    bench_sink += acc;
}

static void run_zh_isa(void *p) /* the context's ISA kernel (shl_polygon's), geometry precomputed */
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) j->ctx->isa->poly_zh(&j->geom[i % NPTS], j->lmax, zh_buf);
    bench_sink += zh_buf[1];
}

/* What shl_polygon_grad returns, by central differences: the coefficients at x and the
 * gradient from 6 offset points, 7 shl_polygon calls (the "7 evaluations") */
static void run_central_diff(void *p)
{
    job *j = p;
    double acc = 0;
    for (long i = 0; i < j->inner; ++i) {
        shl_polygon(j->ctx, j->pts[i % NPTS], j->verts, j->n, coef_buf);
        acc += coef_buf[0];
        for (int a = 0; a < 3; ++a)
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double x[3] = {j->pts[i % NPTS][0], j->pts[i % NPTS][1], j->pts[i % NPTS][2]};
                x[a] += sgn * 1e-6;
                shl_polygon(j->ctx, x, j->verts, j->n, coef_buf);
                acc += coef_buf[0];
            }
    }
    bench_sink += acc;
}

static void run_monomial_only(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) monomial_poly_zh(&j->geom[i % NPTS], j->lmax, zh_buf);
    bench_sink += zh_buf[1];
}

/* Seconds per evaluation (median of 7), with the inner count chosen for ~20 ms per repetition. */
static double timed(void (*fn)(void *), job *j)
{
    j->inner = 1;
    const double t0 = bench_now();
    long n = 0;
    while (bench_now() - t0 < 0.005) { fn(j); ++n; }
    j->inner = (long)fmax(1.0, 0.02 * n / (bench_now() - t0));
    return bench_run(fn, j, j->inner, 7).median;
}

/* The gradient section's clock: thread CPU time, so time the thread spends descheduled on a
 * loaded host is not counted (wall-clock repetitions of one function taken hundreds of ms after
 * another's made its shl_polygon time disagree with the other sections' by 1.7x). */
static double thread_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Paired rounds: nf functions, each with its inner count calibrated for ~20 ms; every round
 * times one repetition of each, in an order rotated from round to round, so all nf of a round
 * are measured within ~nf x 20 ms of each other.  t[f][r]: seconds per evaluation. */
enum { PAIR_ROUNDS = 11, PAIR_MAXF = 5 };
static void paired_rounds(int nf, void (*const fn[])(void *), job *j, double t[][PAIR_ROUNDS])
{
    long inner[PAIR_MAXF];
    for (int f = 0; f < nf; ++f) {
        j->inner = 1;
        const double t0 = thread_now();
        long n = 0;
        while (thread_now() - t0 < 0.005) { fn[f](j); ++n; }
        inner[f] = (long)fmax(1.0, 0.02 * n / (thread_now() - t0));
        j->inner = inner[f];
        fn[f](j); /* warm-up */
    }
    for (int r = 0; r < PAIR_ROUNDS; ++r)
        for (int i = 0; i < nf; ++i) {
            const int f = (i + r) % nf;
            j->inner = inner[f];
            const double t0 = thread_now();
            fn[f](j);
            t[f][r] = (thread_now() - t0) / (double)inner[f];
        }
}

/* Median and range over the rounds of t[a][r] / t[b][r]. */
static double round_ratio(double t[][PAIR_ROUNDS], int a, int b, double *lo, double *hi)
{
    double q[PAIR_ROUNDS];
    for (int r = 0; r < PAIR_ROUNDS; ++r) q[r] = t[a][r] / t[b][r];
    const double med = bench_median(q, PAIR_ROUNDS); /* sorts q */
    *lo = q[0], *hi = q[PAIR_ROUNDS - 1];
    return med;
}

/* t(slow) / t(fast) in PAIR_ROUNDS paired rounds: the median of the per-round ratios (range in lo,
 * hi), the times the medians over the rounds.  Each round's two times are taken ~20 ms apart on
 * thread CPU time: on a noisy host, medians of 7 wall-clock repetitions taken ~150 ms apart gave
 * monomial/recurrence ratios of 0.74-1.40x at lmax 2-5 over six runs (bench/RESULTS.md). */
static double paired_ratio(void (*slow)(void *), void (*fast)(void *), job *j, double *t_slow, double *t_fast,
                           double *lo, double *hi)
{
    void (*const fns[2])(void *) = {slow, fast};
    double t[2][PAIR_ROUNDS];
    paired_rounds(2, fns, j, t);
    const double r = round_ratio(t, 0, 1, lo, hi);
    *t_slow = bench_median(t[0], PAIR_ROUNDS);
    *t_fast = bench_median(t[1], PAIR_ROUNDS);
    return r;
}

static void setup(job *j, const shl_ctx *ctx, int n)
{
    j->ctx = ctx;
    j->lmax = shl_ctx_lmax(ctx);
    j->n = n;
    for (int i = 0; i < n; ++i) { /* regular n-gon of radius 1 in the plane z = 2 */
        j->verts[3 * i] = cos(2 * M_PI * i / n);
        j->verts[3 * i + 1] = sin(2 * M_PI * i / n);
        j->verts[3 * i + 2] = 2.0;
    }
    for (int k = 0; k < 3 * n; ++k) j->vf[k] = (float)j->verts[k];
    srand(1);
    for (int p = 0; p < NPTS; ++p) {
        for (int k = 0; k < 3; ++k) j->pts[p][k] = 2.0 * rand() / RAND_MAX - 1.0;
        for (int k = 0; k < 3; ++k) j->pf[p][k] = (float)j->pts[p][k];
        shl__poly_geom_init(&j->geom[p], j->pts[p], j->verts, n);
    }
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_polygon.csv";
    const bench_opt opts[] = {{"-o", "--csv", "FILE", &csv_path, "CSV output (default build/bench/bench_polygon.csv)"}};
    const bench_cli cli = {
        "bench_polygon", "[-o FILE]",
        "Polygon-light SH coefficients (shl_polygon, Wang & Ramamoorthi 2018), one core, scalar double:\n"
        "time per evaluation vs lmax 2..30 split into ZH recurrence and rotation (Fig. 6), vs edge count\n"
        "3..32 (Fig. 7) with fitted exponents, the speed-up over a frozen copy of the issue-16 kernels,\n"
        "the ZH recurrence vs the monomial-moment baseline at every lmax 2..30 (Table 2), the gradient\n"
        "cost (shl_polygon_grad / shl_polygon and central differences / shl_polygon_grad at lmax 4, 8,\n"
        "14, 30; Wu 2020 Table 1), and evaluations per second.  Ratios are medians of interleaved\n"
        "rounds.  About 60 s on an idle 2-core machine.\n"
        "Writes Markdown tables to stdout and one CSV row per table row to the CSV file.",
        opts, 1, 0};
    bench_parse(&cli, argc, argv, NULL);
    FILE *csv = bench_create(csv_path, "w");
    if (!csv) return 1;
    static job j;
    bench_print_machine(stdout);
    if (csv) fprintf(csv, "section,lmax,edges,ns_total,ns_zh,ns_rotation,ns_monomial_total\n");

    bench_progress("time vs lmax (step 1/6)...");
    printf("\n## Time per evaluation vs lmax (triangle light, double; Wang 2018 Fig. 6)\n\n");
    printf("shl_polygon's stages as it runs them (5 interleaved rounds): set-up (shl__poly_geom_init_values),\n"
           "ZH recurrence (the context's ISA kernel poly_zh: set-up + ZH minus set-up), reconstruction (the rest\n"
           "of poly_sh: the total minus set-up + ZH); each the median over the rounds of its difference within a\n"
           "round.  The differences are of separately timed calls: on a noisy host they carry its noise.\n\n");
    printf("| lmax | coeffs | total ns | set-up ns | ZH recurrence ns | rotation ns | ns/coeff |\n"
           "|---|---|---|---|---|---|---|\n");
    const int lmaxes[] = {2, 4, 6, 8, 10, 12, 14, 18, 22, 26, 30};
    double xs[16], ys[16];
    int nl = 0;
    for (unsigned i = 0; i < sizeof lmaxes / sizeof lmaxes[0]; ++i) {
        shl_ctx *ctx;
        shl_ctx_create(lmaxes[i], &ctx);
        setup(&j, ctx, 3);
        enum { NR = 5 }; /* interleaved rounds: the stages are medians of differences within a round */
        double rt[NR], rs[NR], rz[NR], dz[NR], dr[NR];
        for (int r = 0; r < NR; ++r) {
            rt[r] = timed(run_full, &j), rs[r] = timed(run_setup, &j), rz[r] = timed(run_geom_zh, &j);
            dz[r] = rz[r] - rs[r];
            dr[r] = rt[r] - rz[r];
        }
        const double t = bench_median(rt, NR), ts = bench_median(rs, NR), tz = ts + bench_median(dz, NR),
                     tr = bench_median(dr, NR);
        const int nc = SHL_NCOEFFS(lmaxes[i]);
        printf("| %d | %d | %.0f | %.0f | %.0f | %.0f | %.1f |\n", lmaxes[i], nc, t * 1e9, ts * 1e9, (tz - ts) * 1e9,
               tr * 1e9, t * 1e9 / nc);
        if (csv) fprintf(csv, "lmax,%d,3,%.1f,%.1f,%.1f,\n", lmaxes[i], t * 1e9, tz * 1e9, tr * 1e9);
        if (lmaxes[i] >= 4) { xs[nl] = nc; ys[nl] = t; ++nl; }
        shl_ctx_destroy(ctx);
    }
    printf("\nFitted exponent of time vs coefficient count (lmax 4..30): %.2f "
           "(1 = linear; the rotation is O(lmax^3) = coeffs^1.5 and takes over at high lmax)\n",
           bench_loglog_slope(xs, ys, nl));

    bench_progress("time vs edge count (step 2/6)...");
    printf("\n## Time per evaluation vs edge count (lmax 8, double; Wang 2018 Fig. 7)\n\n| edges | total ns |\n|---|---|\n");
    shl_ctx *ctx8;
    shl_ctx_create(8, &ctx8);
    int ne = 0;
    for (int n = 3; n <= 32; n = n < 8 ? n + 1 : n * 2) {
        setup(&j, ctx8, n);
        const double t = timed(run_full, &j);
        printf("| %d | %.0f |\n", n, t * 1e9);
        if (csv) fprintf(csv, "edges,8,%d,%.1f,,,\n", n, t * 1e9);
        xs[ne] = n;
        ys[ne] = t;
        ++ne;
    }
    printf("\nFitted exponent of time vs edges: %.2f (1 = linear)\n", bench_loglog_slope(xs, ys, ne));

    bench_progress("speed-up over the frozen issue-16 kernels (step 3/6)...");
    printf("\n## shl_polygon vs the frozen issue-16 kernels (triangle, double; %d paired rounds, thread CPU time)\n\n",
           PAIR_ROUNDS);
    printf("Baseline: bench/common/poly_baseline.c (one lobe at a time, row-by-row reconstruction) after the\n"
           "library's current set-up (shl__poly_geom_init is shared, so set-up gains are not in the ratio).\n"
           "Target (issue 16): >= 2.5x at lmax 8.  ISA: %s.\n\n", shl_ctx_isa(ctx8));
    printf("| lmax | baseline ns | shl_polygon ns | speed-up (range over the rounds) |\n|---|---|---|---|\n");
    const int base_l[4] = {4, 8, 14, 30};
    for (int i = 0; i < 4; ++i) {
        shl_ctx *ctx;
        shl_ctx_create(base_l[i], &ctx);
        setup(&j, ctx, 3);
        double tb, tc, lo, hi;
        const double r = paired_ratio(run_baseline_full, run_full, &j, &tb, &tc, &lo, &hi);
        printf("| %d | %.0f | %.0f | %.2fx (%.2f-%.2f) |\n", base_l[i], tb * 1e9, tc * 1e9, r, lo, hi);
        if (csv) fprintf(csv, "baseline,%d,3,%.1f,%.1f,,\n", base_l[i], tc * 1e9, tb * 1e9);
        shl_ctx_destroy(ctx);
    }

    bench_progress("ZH recurrence vs monomial baseline (step 4/6)...");
    printf("\n## ZH recurrence vs monomial-moment baseline (triangle; Wang 2018 Table 2)\n\n");
    printf("Equal care: both run two lobes per vector (the generic vector type, SSE2 on x86-64), the\n"
           "recurrence as the scalar ISA's kernel of simd/poly_zh_batch.h, the monomial method as\n"
           "bench/common/monomial.c; ZH part only, geometry precomputed; median of the per-round ratios of %d\n"
           "paired rounds on thread CPU time (range in brackets).\n"
           "The context's ISA kernel (shl_polygon's) is shown for reference.  Target: ratio >= 1 at every lmax.\n\n",
           PAIR_ROUNDS);
    printf("| lmax | recurrence ns | monomial ns | monomial/recurrence | %s kernel ns | max |recurrence - monomial| |\n"
           "|---|---|---|---|---|---|\n", shl_ctx_isa(ctx8));
    double worst = HUGE_VAL;
    for (int lm = 2; lm <= 30; ++lm) {
        shl_ctx *ctx;
        shl_ctx_create(lm, &ctx);
        setup(&j, ctx, 3);
        double tm, tz, lo, hi;
        const double r = paired_ratio(run_monomial_only, run_zh_only, &j, &tm, &tz, &lo, &hi);
        const double ti = timed(run_zh_isa, &j);
        worst = fmin(worst, r);
        static double za[(2 * SHL_LMAX_MAX + 1) * SHL__ZH_STRIDE], zb[(2 * SHL_LMAX_MAX + 1) * SHL__ZH_STRIDE];
        double diff = 0;
        for (int p = 0; p < NPTS; ++p) {
            shl__poly_zh_d(&j.geom[p], lm, za);
            monomial_poly_zh(&j.geom[p], lm, zb);
            for (int d = 0; d < 2 * lm + 1; ++d)
                for (int l = 0; l <= lm; ++l) diff = fmax(diff, fabs(za[d * SHL__ZH_STRIDE + l] - zb[d * SHL__ZH_STRIDE + l]));
        }
        printf("| %d | %.0f | %.0f | %.2fx (%.2f-%.2f) | %.0f | %.1e |\n", lm, tz * 1e9, tm * 1e9, r, lo, hi, ti * 1e9, diff);
        if (csv) fprintf(csv, "zhmono,%d,3,,%.1f,%.1f,%.1f\n", lm, tz * 1e9, ti * 1e9, tm * 1e9);
        shl_ctx_destroy(ctx);
    }
    printf("\nLeast monomial/recurrence ratio over lmax 2..30: %.2fx\n", worst);

    bench_progress("gradient cost (step 5/6)...");
    printf("\n## Gradient cost (triangle, double; Wu 2020 Table 1; %d paired rounds, thread CPU time)\n\n", PAIR_ROUNDS);
    printf("Each round times one ~20 ms repetition of each of the five functions, in an order rotated from\n"
           "round to round; ratios are medians of the per-round ratios (range in brackets), times medians\n"
           "over the rounds.  Central differences: 7 shl_polygon calls (coefficients at x, 6 offsets).  ZH part: the scalar ISA's kernels,\n"
           "geometry precomputed.  Targets (issue 16): grad/coeffs <= 1.3 at lmax 4 and 8; central\n"
           "differences / analytic >= 5.\n\n");
    printf("| lmax | shl_polygon ns | shl_polygon_grad ns | grad/coeffs | central diff. ns | FD/analytic | ZH recurrence ns | ZH + gradient ns | ratio, ZH part |\n"
           "|---|---|---|---|---|---|---|---|---|\n");
    const int grad_l[4] = {4, 8, 14, 30};
    for (int i = 0; i < 4; ++i) {
        shl_ctx *ctx;
        shl_ctx_create(grad_l[i], &ctx);
        setup(&j, ctx, 3);
        enum { FULL, GRAD, FD, ZH, ZHGRAD, NF };
        void (*const fns[NF])(void *) = {run_full, run_full_grad, run_central_diff, run_zh_only, run_zh_grad_only};
        double t[NF][PAIR_ROUNDS], med[NF], lo[3], hi[3];
        paired_rounds(NF, fns, &j, t);
        const double rg = round_ratio(t, GRAD, FULL, &lo[0], &hi[0]), rfd = round_ratio(t, FD, GRAD, &lo[1], &hi[1]);
        const double rz = round_ratio(t, ZHGRAD, ZH, &lo[2], &hi[2]);
        for (int f = 0; f < NF; ++f) med[f] = bench_median(t[f], PAIR_ROUNDS);
        printf("| %d | %.0f | %.0f | %.2f (%.2f-%.2f) | %.0f | %.2f (%.2f-%.2f) | %.0f | %.0f | %.2f (%.2f-%.2f) |\n",
               grad_l[i], med[FULL] * 1e9, med[GRAD] * 1e9, rg, lo[0], hi[0], med[FD] * 1e9, rfd, lo[1], hi[1],
               med[ZH] * 1e9, med[ZHGRAD] * 1e9, rz, lo[2], hi[2]);
        if (csv) fprintf(csv, "grad,%d,3,%.1f,%.1f,,\n", grad_l[i], med[GRAD] * 1e9, med[ZHGRAD] * 1e9);
        shl_ctx_destroy(ctx);
    }

    bench_progress("scalar throughput (step 6/6)...");
    setup(&j, ctx8, 3);
    const double td = timed(run_full, &j), tf = timed(run_full_f, &j);
    printf("\n## Scalar throughput, one core, triangle, lmax 8\n\n");
    printf("double: %.3g evaluations/s (%.0f ns); float path: %.3g evaluations/s (%.0f ns)\n",
           1.0 / td, td * 1e9, 1.0 / tf, tf * 1e9);
    if (csv) fprintf(csv, "throughput,8,3,%.1f,,,\n", td * 1e9);
    shl_ctx_destroy(ctx8);
    printf("\n(checksum %g)\n", (double)bench_sink);
    if (fclose(csv)) return 1;
    bench_progress("done; wrote %s", csv_path);
    return 0;
}
