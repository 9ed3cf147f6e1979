/* Spherical-light benchmark (Mezieres et al. 2022, HVL):
 *  - HVL Fig. 6 as data: arithmetic operations per cap ZH projection vs band
 *    count for the Eq. (14) recurrence, Sloan's closed forms (bands 0..9) and
 *    the library's cancellation-free form, with measured time per projection
 *    (ZH only, and ZH + the Eq. (15) rotation to SH);
 *  - shl_sphere / shl_sphere_grad (double, float) time vs lmax 2..30 and the
 *    gradient / coefficient time ratio.
 * CSV: build/bench/bench_sphere.csv (-o overrides); --help. */
#include "sh_ops.h"
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdlib.h>

#define CLOSED_LMAX 9
#define NPTS 64

static const double SQRT_PI = 1.77245385090551602729;
static double rec_a[SHL_LMAX_MAX + 1], rec_b[SHL_LMAX_MAX + 1]; /* P_{l+1} = a c P_l - b P_{l-1} */
static double k14[SHL_LMAX_MAX + 1], k15[SHL_LMAX_MAX + 1], kst[SHL_LMAX_MAX + 1], cf[CLOSED_LMAX + 1];
/* counting arithmetic: function calls, so that nested counts are sequenced */
static long nops;
static double op_add(double a, double b) { ++nops; return a + b; }
static double op_sub(double a, double b) { ++nops; return a - b; }
static double op_mul(double a, double b) { ++nops; return a * b; }

#define FN(name) name##_count
#define ADD(a, b) op_add((a), (b))
#define SUB(a, b) op_sub((a), (b))
#define MUL(a, b) op_mul((a), (b))
#include "sphere_zh_forms.h"
#undef FN
#undef ADD
#undef SUB
#undef MUL
#define FN(name) name##_plain
#define ADD(a, b) ((a) + (b))
#define SUB(a, b) ((a) - (b))
#define MUL(a, b) ((a) * (b))
#include "sphere_zh_forms.h"

static void init_constants(void)
{
    static const double closed_den[CLOSED_LMAX + 1] = {1, 2, 2, 8, 8, 16, 16, 128, 128, 256};
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) {
        rec_a[l] = (2.0 * l + 1.0) / (l + 1.0);
        rec_b[l] = l / (l + 1.0);
        k14[l] = sqrt(M_PI / (2.0 * l + 1.0));
        k15[l] = sqrt(4.0 * M_PI / (2.0 * l + 1.0));
        kst[l] = l ? sqrt(M_PI * (2.0 * l + 1.0)) / (l * (l + 1.0)) : 0.0;
    }
    for (int l = 1; l <= CLOSED_LMAX; ++l) cf[l] = sqrt((2.0 * l + 1.0) * M_PI) / closed_den[l];
}

typedef struct {
    int lmax;
    long inner;
    const shl_ctx *ctx;
    double c[NPTS], t[NPTS], s2[NPTS], axis[NPTS][3];
    double x[NPTS][3], center[3], radius;
    float xf[NPTS][3], centerf[3];
} job;

static double zbuf[SHL_LMAX_MAX + 1], shbuf[SHL_NCOEFFS(SHL_LMAX_MAX)], gbuf[3 * SHL_NCOEFFS(SHL_LMAX_MAX)];
static float shf[SHL_NCOEFFS(SHL_LMAX_MAX)], gf[3 * SHL_NCOEFFS(SHL_LMAX_MAX)];

static void run_eq14(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        zh_eq14_plain(j->lmax, j->c[i % NPTS], zbuf);
        bench_sink += zbuf[j->lmax];
    }
}

static void run_closed(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        zh_closed_plain(j->lmax, j->c[i % NPTS], zbuf);
        bench_sink += zbuf[j->lmax];
    }
}

static void run_stable(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const int k = i % NPTS;
        zh_stable_plain(j->lmax, j->c[k], j->t[k], j->s2[k], zbuf);
        bench_sink += zbuf[j->lmax];
    }
}

static void run_library_zh(void *p) /* the library's kernel (per-call constants) */
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const int k = i % NPTS;
        shl__cap_weights_d(j->lmax, j->t[k], j->s2[k], j->c[k], zbuf, NULL);
        bench_sink += zbuf[j->lmax];
    }
}

/* ZH + Eq. (15): sh = sqrt(4 pi/(2l+1)) zh_l Y_lm(axis) */
static void to_sh(int lmax, const double axis[3])
{
    shl__sh_eval(lmax, axis[0], axis[1], axis[2], shbuf);
    for (int l = 0; l <= lmax; ++l) {
        const double f = k15[l] * zbuf[l];
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) shbuf[k] *= f;
    }
}

static void run_eq14_sh(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        zh_eq14_plain(j->lmax, j->c[i % NPTS], zbuf);
        to_sh(j->lmax, j->axis[i % NPTS]);
        bench_sink += shbuf[1];
    }
}

static void run_closed_sh(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        zh_closed_plain(j->lmax, j->c[i % NPTS], zbuf);
        to_sh(j->lmax, j->axis[i % NPTS]);
        bench_sink += shbuf[1];
    }
}

static void run_sphere(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl_sphere(j->ctx, j->x[i % NPTS], j->center, j->radius, shbuf);
        bench_sink += shbuf[1];
    }
}

static void run_sphere_grad(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl_sphere_grad(j->ctx, j->x[i % NPTS], j->center, j->radius, shbuf, gbuf);
        bench_sink += gbuf[1];
    }
}

static void run_sphere_f(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl_sphere_f(j->ctx, j->xf[i % NPTS], j->centerf, (float)j->radius, shf);
        bench_sink += shf[1];
    }
}

static void run_sphere_grad_f(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        shl_sphere_grad_f(j->ctx, j->xf[i % NPTS], j->centerf, (float)j->radius, shf, gf);
        bench_sink += gf[1];
    }
}

/* Seconds per evaluation: minimum of 41 short repetitions (~2 ms each, robust
 * to other load on the machine). */
static double timed(void (*fn)(void *), job *j)
{
    j->inner = 1;
    const double t0 = bench_now();
    long n = 0;
    while (bench_now() - t0 < 0.005) {
        fn(j);
        ++n;
    }
    j->inner = (long)fmax(1.0, 0.002 * n / (bench_now() - t0));
    return bench_run(fn, j, j->inner, 41).min;
}

/* 64 shading points in the unit cube seeing a sphere of radius 0.5 at (0, 0, 3). */
static void setup(job *j, const shl_ctx *ctx)
{
    j->ctx = ctx;
    j->lmax = shl_ctx_lmax(ctx);
    j->radius = 0.5;
    j->center[0] = j->center[1] = 0.0;
    j->center[2] = 3.0;
    for (int k = 0; k < 3; ++k) j->centerf[k] = (float)j->center[k];
    srand(1);
    for (int p = 0; p < NPTS; ++p) {
        double v[3], d = 0.0;
        for (int k = 0; k < 3; ++k) {
            j->x[p][k] = 2.0 * rand() / RAND_MAX - 1.0;
            j->xf[p][k] = (float)j->x[p][k];
            v[k] = j->center[k] - j->x[p][k];
            d += v[k] * v[k];
        }
        d = sqrt(d);
        for (int k = 0; k < 3; ++k) j->axis[p][k] = v[k] / d;
        const double s = j->radius / d;
        j->s2[p] = s * s;
        j->c[p] = sqrt(1.0 - j->s2[p]);
        j->t[p] = j->s2[p] / (1.0 + j->c[p]);
    }
}

static long count_ops(int which, int lmax)
{
    double z[SHL_LMAX_MAX + 1];
    nops = 0;
    if (which == 0) zh_eq14_count(lmax, 0.8, z);
    if (which == 1) zh_closed_count(lmax, 0.8, z);
    if (which == 2) zh_stable_count(lmax, 0.8, 0.2, 0.36, z);
    return nops;
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_sphere.csv";
    const bench_opt opts[] = {{"-o", "--csv", "FILE", &csv_path, "CSV output (default build/bench/bench_sphere.csv)"}};
    const bench_cli cli = {
        "bench_sphere", "[-o FILE]",
        "Spherical lights (Mezieres et al. 2022, HVL), one core: arithmetic operations and time per cap ZH\n"
        "projection vs band count for Eq. (14), Sloan's closed forms and the library's cancellation-free\n"
        "form (HVL Fig. 6 as data), and shl_sphere / shl_sphere_grad (double, float) time vs lmax 2..30.\n"
        "About 10 s on an idle 2-core machine.\n"
        "Writes Markdown tables to stdout and one CSV row per table row to the CSV file.",
        opts, 1, 0};
    bench_parse(&cli, argc, argv, NULL);
    FILE *csv = bench_create(csv_path, "w");
    if (!csv) return 1;
    static job j;
    init_constants();
    bench_print_machine(stdout);
    if (csv) fprintf(csv, "section,bands,ops_eq14,ops_closed,ops_stable,ns_eq14,ns_closed,ns_stable,ns_library_zh,"
                          "ns_eq14_sh,ns_closed_sh,ns_sphere,ns_sphere_grad,ns_sphere_f,ns_sphere_grad_f\n");

    /* the forms agree (moderate cap), and Eq. (14) cancels for a tiny one */
    double za[SHL_LMAX_MAX + 1], zb[SHL_LMAX_MAX + 1], zc[SHL_LMAX_MAX + 1], dmax = 0.0;
    zh_eq14_plain(CLOSED_LMAX, 0.8, za);
    zh_closed_plain(CLOSED_LMAX, 0.8, zb);
    zh_stable_plain(CLOSED_LMAX, 0.8, 0.2, 0.36, zc);
    for (int l = 0; l <= CLOSED_LMAX; ++l) dmax = fmax(dmax, fmax(fabs(za[l] - zb[l]), fabs(za[l] - zc[l])));
    const double s2 = 1e-10, c = sqrt(1.0 - s2); /* radius 1e-4 at distance 10 */
    zh_eq14_plain(SHL_LMAX_MAX, c, za);
    zh_stable_plain(SHL_LMAX_MAX, c, s2 / (1.0 + c), s2, zc);
    zh_closed_plain(CLOSED_LMAX, c, zb);
    printf("\nCheck: the three forms agree to %.1e at cos a = 0.8 (bands 0..9).  Radius 1e-4 at distance 10, "
           "relative error of band 30 / band 9: Eq. (14) %.1e / %.1e, closed form (band 9) %.1e "
           "(reference: the cancellation-free form).\n",
           dmax, fabs(za[30] / zc[30] - 1.0), fabs(za[9] / zc[9] - 1.0), fabs(zb[9] / zc[9] - 1.0));

    bench_progress("cap ZH projection vs band count (step 1/2)...");
    printf("\n## Cap ZH projection: arithmetic operations and time vs band count (HVL Fig. 6)\n\n");
    printf("Operations counted by an instrumented instantiation of the same code (per-band constants "
           "precomputed, as in the paper).  Times: ns per projection, minimum of 41 repetitions, 64 shading "
           "points; 'library form' is the bench's copy of the library's recurrence with precomputed constants, "
           "'shl kernel' the library's own shl__cap_weights_d.\n\n");
    printf("| bands | ops Eq.(14) | ops closed form | ops library form | ns Eq.(14) | ns closed | ns library "
           "form | ns shl kernel | ns Eq.(14)+Eq.(15) SH | ns closed+Eq.(15) SH | ns shl_sphere |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int lmax = 0; lmax <= SHL_LMAX_MAX; lmax = lmax < 11 ? lmax + 1 : lmax + 4) {
        shl_ctx *ctx;
        shl_ctx_create(lmax, &ctx);
        setup(&j, ctx);
        const int closed = lmax <= CLOSED_LMAX;
        const long o14 = count_ops(0, lmax), ocl = closed ? count_ops(1, lmax) : 0, ost = count_ops(2, lmax);
        const double t14 = timed(run_eq14, &j), tcl = closed ? timed(run_closed, &j) : 0.0;
        const double tst = timed(run_stable, &j), tlib = timed(run_library_zh, &j);
        const double t14s = timed(run_eq14_sh, &j), tcls = closed ? timed(run_closed_sh, &j) : 0.0;
        const double tsph = timed(run_sphere, &j);
        char ocl_s[32] = "-", tcl_s[32] = "-", tcls_s[32] = "-";
        if (closed) {
            snprintf(ocl_s, sizeof ocl_s, "%ld", ocl);
            snprintf(tcl_s, sizeof tcl_s, "%.1f", tcl * 1e9);
            snprintf(tcls_s, sizeof tcls_s, "%.0f", tcls * 1e9);
        }
        printf("| %d | %ld | %s | %ld | %.1f | %s | %.1f | %.1f | %.0f | %s | %.0f |\n", lmax + 1, o14, ocl_s, ost,
               t14 * 1e9, tcl_s, tst * 1e9, tlib * 1e9, t14s * 1e9, tcls_s, tsph * 1e9);
        if (csv)
            fprintf(csv, "fig6,%d,%ld,%s,%ld,%.2f,%s,%.2f,%.2f,%.1f,%s,%.1f,,,\n", lmax + 1, o14, closed ? ocl_s : "",
                    ost, t14 * 1e9, closed ? tcl_s : "", tst * 1e9, tlib * 1e9, t14s * 1e9, closed ? tcls_s : "",
                    tsph * 1e9);
        shl_ctx_destroy(ctx);
    }
    int cross = CLOSED_LMAX + 2; /* first band count from which the closed forms are never cheaper */
    for (int lmax = CLOSED_LMAX; lmax >= 1 && count_ops(1, lmax) >= count_ops(0, lmax); --lmax) cross = lmax + 1;
    printf("\nWith c^2 and sin^2 a shared and Horner evaluation, the closed forms cost about l + 1 operations "
           "for band l (quadratic in the band count) against 6 per band for Eq. (14); they need at least as many "
           "operations from %d bands on.\n",
           cross);

    bench_progress("shl_sphere and shl_sphere_grad vs lmax (step 2/2)...");
    printf("\n## shl_sphere and shl_sphere_grad vs lmax (sphere of radius 0.5 at distance ~3)\n\n");
    printf("| lmax | coeffs | coeffs ns | grad ns | grad/coeff | float coeffs ns | float grad ns | "
           "ns/coeff |\n|---|---|---|---|---|---|---|---|\n");
    double xs[16], ys[16], rmin = 1e30, rmax = 0.0;
    int n = 0;
    for (int lmax = 2; lmax <= SHL_LMAX_MAX; lmax += 2) {
        shl_ctx *ctx;
        shl_ctx_create(lmax, &ctx);
        setup(&j, ctx);
        const double t = timed(run_sphere, &j), tg = timed(run_sphere_grad, &j);
        const double tf = timed(run_sphere_f, &j), tgf = timed(run_sphere_grad_f, &j);
        const int nc = SHL_NCOEFFS(lmax);
        printf("| %d | %d | %.0f | %.0f | %.2f | %.0f | %.0f | %.2f |\n", lmax, nc, t * 1e9, tg * 1e9, tg / t,
               tf * 1e9, tgf * 1e9, t * 1e9 / nc);
        if (csv) fprintf(csv, "sphere,%d,,,,,,,,,,%.1f,%.1f,%.1f,%.1f\n", lmax + 1, t * 1e9, tg * 1e9, tf * 1e9, tgf * 1e9);
        xs[n] = nc;
        ys[n++] = t;
        rmin = fmin(rmin, tg / t);
        rmax = fmax(rmax, tg / t);
        shl_ctx_destroy(ctx);
    }
    printf("\nFitted exponent of shl_sphere time vs coefficient count (lmax 2..30): %.2f (1 = linear); "
           "gradient / coefficient time ratio %.2f..%.2f.\n",
           bench_loglog_slope(xs, ys, n), rmin, rmax);
    printf("\n(checksum %g)\n", (double)bench_sink);
    if (fclose(csv)) return 1;
    bench_progress("done; wrote %s", csv_path);
    return 0;
}
