/* Hessian cost (issue 19): shl_polygon_hess / shl_polygon and shl_sphere_hess / shl_sphere,
 * with the gradient calls for reference, at lmax 4, 8, 14, 30, all ratios from one run
 * (one core, double, the context's default ISA, printed).  The host is shared and noisy
 * (run-to-run swings of 1.5x): per lmax, ROUNDS rounds each time every call in turn (the
 * minimum of BATCHES batches of ~1 ms), a ratio is taken within each round and the table
 * prints the median over the rounds, and for the triangle's hess/coeffs also its range.
 * The target is shl_polygon_hess <= 2.5x shl_polygon at lmax 8.  Also one light set of
 * 4 quads and 2 spheres: shl_lights_eval_hess / shl_lights_eval (with gradients).
 * CSV: build/bench/bench_hess.csv (-o overrides); --help. */
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdlib.h>

enum { NPTS = 64 };

typedef struct {
    const shl_ctx *ctx;
    const shl_lights *set;
    int n;
    double verts[3 * 4], center[3], radius;
    double pts[NPTS][3];
    long inner;
} job;

static double cbuf[3 * SHL_NCOEFFS(SHL_LMAX_MAX)], gbuf[9 * SHL_NCOEFFS(SHL_LMAX_MAX)],
    hbuf[18 * SHL_NCOEFFS(SHL_LMAX_MAX)];

#define RUNNER(name, call)                                                                                             \
    static void name(void *p)                                                                                          \
    {                                                                                                                  \
        job *j = p;                                                                                                    \
        double acc = 0;                                                                                                \
        for (long i = 0; i < j->inner; ++i) {                                                                          \
            const double *x = j->pts[i % NPTS];                                                                        \
            call;                                                                                                      \
            acc += cbuf[0];                                                                                            \
        }                                                                                                              \
        bench_sink += acc;                                                                                             \
    }
RUNNER(run_poly, shl_polygon(j->ctx, x, j->verts, j->n, cbuf))
RUNNER(run_poly_grad, shl_polygon_grad(j->ctx, x, j->verts, j->n, cbuf, gbuf))
RUNNER(run_poly_hess, shl_polygon_hess(j->ctx, x, j->verts, j->n, cbuf, gbuf, hbuf))
RUNNER(run_sphere, shl_sphere(j->ctx, x, j->center, j->radius, cbuf))
RUNNER(run_sphere_grad, shl_sphere_grad(j->ctx, x, j->center, j->radius, cbuf, gbuf))
RUNNER(run_sphere_hess, shl_sphere_hess(j->ctx, x, j->center, j->radius, cbuf, gbuf, hbuf))
RUNNER(run_set_grad, shl_lights_eval(j->ctx, j->set, x, cbuf, gbuf))
RUNNER(run_set_hess, shl_lights_eval_hess(j->ctx, j->set, x, cbuf, gbuf, hbuf))

enum { ROUNDS = 9, BATCHES = 5 };

/* The calls timed, in the order of a round. */
enum { POLY, POLY_GRAD, POLY_HESS, SPHERE, SPHERE_GRAD, SPHERE_HESS, SET_GRAD, SET_HESS, NCALL };
static void (*const call_fn[NCALL])(void *) = {run_poly,   run_poly_grad,   run_poly_hess, run_sphere,
                                               run_sphere_grad, run_sphere_hess, run_set_grad,  run_set_hess};

/* Evaluations of fn in ~1 ms. */
static long calibrate(void (*fn)(void *), job *j)
{
    j->inner = 1;
    const double t0 = bench_now();
    long n = 0;
    while (bench_now() - t0 < 0.005) { fn(j); ++n; }
    return (long)fmax(1.0, 0.001 * n / (bench_now() - t0));
}

/* Seconds per evaluation of every call, ROUNDS interleaved rounds: t[call][round]. */
static void time_rounds(job *j, double t[NCALL][ROUNDS])
{
    long inner[NCALL];
    for (int c = 0; c < NCALL; ++c) inner[c] = calibrate(call_fn[c], j);
    for (int r = 0; r < ROUNDS; ++r)
        for (int c = 0; c < NCALL; ++c) {
            j->inner = inner[c];
            t[c][r] = bench_run(call_fn[c], j, inner[c], BATCHES).min; /* short calls: the minimum dodges preemption */
        }
}

/* Median over the rounds of t[a][r] / t[b][r]; lo, hi (if not NULL): its range. */
static double ratio_median(double t[NCALL][ROUNDS], int a, int b, double *lo, double *hi)
{
    double q[ROUNDS];
    for (int r = 0; r < ROUNDS; ++r) q[r] = t[a][r] / t[b][r];
    const double med = bench_median(q, ROUNDS); /* sorts q */
    if (lo) *lo = q[0], *hi = q[ROUNDS - 1];
    return med;
}

/* Median over the rounds of the call's time, in ns. */
static double ns_median(double t[NCALL][ROUNDS], int c)
{
    double q[ROUNDS];
    for (int r = 0; r < ROUNDS; ++r) q[r] = t[c][r] * 1e9;
    return bench_median(q, ROUNDS);
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_hess.csv";
    const bench_opt opts[] = {{"-o", "--csv", "FILE", &csv_path, "CSV output (default build/bench/bench_hess.csv)"}};
    const bench_cli cli = {
        "bench_hess", "[-o FILE]",
        "Cost of the analytic SH Hessians (issue 19), one core, double, the default ISA: shl_polygon_hess against\n"
        "shl_polygon and shl_polygon_grad (triangle), shl_sphere_hess against shl_sphere and shl_sphere_grad,\n"
        "at lmax 4, 8, 14, 30, and a light set (4 quads, 2 spheres) with shl_lights_eval_hess against\n"
        "shl_lights_eval with gradients.  Ratios within one run: medians over 9 interleaved rounds (and\n"
        "the range of the triangle's hess/coeffs).  About 2 s on an idle 2-core machine.\n"
        "Writes a Markdown table to stdout and one CSV row per table row to the CSV file.",
        opts, 1, 0};
    bench_parse(&cli, argc, argv, NULL);
    FILE *csv = bench_create(csv_path, "w");
    if (!csv) return 1;
    char load[128];
    bench_loadavg(load, sizeof load);
    bench_print_machine(stdout);
    printf("load average at start: %s\n", load);
    shl_ctx *ictx;
    if (shl_ctx_create(2, &ictx) == SHL_OK) printf("ISA of the kernels (default): %s\n", shl_ctx_isa(ictx));
    shl_ctx_destroy(ictx);
    fprintf(csv, "light,lmax,ns_coeffs,ns_grad,ns_hess,hess_over_coeffs,hess_over_grad\n");
    static job j;
    const double tri[9] = {-0.4, -0.3, 1.2, 0.6, -0.2, 1.0, 0.1, 0.7, 1.4};
    for (int k = 0; k < 9; ++k) j.verts[k] = tri[k];
    j.n = 3;
    j.center[0] = 0.3, j.center[1] = 0.2, j.center[2] = 2.0, j.radius = 0.4;
    srand(1);
    for (int p = 0; p < NPTS; ++p)
        for (int k = 0; k < 3; ++k) j.pts[p][k] = 2.0 * rand() / RAND_MAX - 1.0;
    shl_lights *set;
    shl_lights_create(&set);
    const double rgb[3] = {1.0, 0.8, 0.6};
    for (int q = 0; q < 4; ++q) {
        const double z = 1.5 + 0.3 * q, o = 0.5 * q - 0.75;
        const double quad[12] = {o, -0.5, z, o + 0.4, -0.5, z, o + 0.4, 0.5, z + 0.1, o, 0.5, z + 0.1};
        shl_lights_add_polygon(set, quad, 4, rgb, 1);
    }
    const double c1[3] = {1.5, 0.0, 0.5}, c2[3] = {-1.5, 0.3, -0.5};
    shl_lights_add_sphere(set, c1, 0.3, rgb);
    shl_lights_add_sphere(set, c2, 0.2, rgb);
    j.set = set;

    printf("\n## Hessian cost (one core, double, ns per point; medians of %d interleaved rounds, each the minimum of %d "
           "batches of ~1 ms; ratios within each round, [range] over the rounds)\n\n",
           ROUNDS, BATCHES);
    printf("| light | lmax | coeffs ns | grad ns | hess ns | hess/coeffs | hess/grad |\n|---|---|---|---|---|---|---|\n");
    const int lm[4] = {4, 8, 14, 30};
    for (int i = 0; i < 4; ++i) {
        shl_ctx *ctx;
        shl_ctx_create(lm[i], &ctx);
        j.ctx = ctx;
        bench_progress("lmax %d...", lm[i]);
        static double t[NCALL][ROUNDS];
        time_rounds(&j, t);
        double lo, hi;
        const double rph = ratio_median(t, POLY_HESS, POLY, &lo, &hi), rpg = ratio_median(t, POLY_HESS, POLY_GRAD, NULL, NULL);
        const double rsh = ratio_median(t, SPHERE_HESS, SPHERE, NULL, NULL), rsg = ratio_median(t, SPHERE_HESS, SPHERE_GRAD, NULL, NULL);
        const double rlh = ratio_median(t, SET_HESS, SET_GRAD, NULL, NULL);
        const double tp = ns_median(t, POLY), tpg = ns_median(t, POLY_GRAD), tph = ns_median(t, POLY_HESS);
        const double ts = ns_median(t, SPHERE), tsg = ns_median(t, SPHERE_GRAD), tsh = ns_median(t, SPHERE_HESS);
        const double tlg = ns_median(t, SET_GRAD), tlh = ns_median(t, SET_HESS);
        printf("| triangle | %d | %.0f | %.0f | %.0f | %.2fx [%.2f, %.2f] | %.2fx |\n", lm[i], tp, tpg, tph, rph, lo, hi, rpg);
        printf("| sphere | %d | %.0f | %.0f | %.0f | %.1fx | %.1fx |\n", lm[i], ts, tsg, tsh, rsh, rsg);
        printf("| set (4 quads, 2 spheres) | %d | | %.0f | %.0f | | %.2fx |\n", lm[i], tlg, tlh, rlh);
        fprintf(csv, "triangle,%d,%.1f,%.1f,%.1f,%.3f,%.3f\n", lm[i], tp, tpg, tph, rph, rpg);
        fprintf(csv, "sphere,%d,%.1f,%.1f,%.1f,%.3f,%.3f\n", lm[i], ts, tsg, tsh, rsh, rsg);
        fprintf(csv, "set,%d,,%.1f,%.1f,,%.3f\n", lm[i], tlg, tlh, rlh);
        shl_ctx_destroy(ctx);
    }
    bench_loadavg(load, sizeof load);
    printf("\nload average at end: %s\n", load);
    shl_lights_destroy(set);
    fclose(csv);
    return 0;
}
