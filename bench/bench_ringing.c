/* SH ringing benchmark: how often truncated SH irradiance goes negative, and its
 * error against the exact irradiance, without and with each window of shl_sh_window.
 * Run with --help for what it measures, run time and output. */
#include "shlight.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

enum { NPTS = 4000, NLIGHTS = 3, NL = 6, NW = 6, LTOP = 14, NT = 20001 };
static const int LMAXES[NL] = {2, 4, 6, 8, 10, 14};
static const char *WNAMES[NW] = {"none", "hanning", "lanczos", "laplacian", "laplacian*", "poussin"};

static void usage(void)
{
    printf("bench_ringing [-o FILE.csv] [--help]\n"
           "SH ringing of irradiance from polygon lights (shl_sh_window, shl_sh_irradiance).\n"
           "Scene (procedural, no files): %d receiver points on a unit sphere (Fibonacci lattice),\n"
           "normals outward, %d two-sided unit-radiance quads at 1.4-3 from the centre (one\n"
           "large and near, two smaller).  Per point: RGB SH of the light set at lmax %d\n"
           "(shl_lights_eval, channel 0 used), truncated to lmax 2, 4, 6, 8, 10, 14, windowed\n"
           "(none; Hanning and Lanczos with width lmax+1; Laplacian with lambda = 1/(lmax(lmax+1))^2,\n"
           "i.e. the last band halved; Laplacian* with the smallest lambda for which the windowed\n"
           "clamped-cosine kernel K(t) = sum_l h_l A_l (2l+1)/(4 pi) P_l(t) is >= 0 on %d samples\n"
           "of [-1, 1] (bisection; then any non-negative radiance gives non-negative irradiance);\n"
           "de la Vallee Poussin with degree lmax (non-negative by construction)),\n"
           "then shl_sh_irradiance; the exact value is the sum of\n"
           "shl_polygon_irradiance over the lights.\n"
           "A last row per lmax clamps the unwindowed result at 0.\n"
           "Prints, per lmax and window: the fraction of points with negative irradiance, the\n"
           "most negative value / max exact, RMS error / RMS exact, max |error| / max exact.\n"
           "Run time: about 1 s.  Writes the table to stdout and a CSV to\n"
           "build/bench/bench_ringing.csv (or FILE.csv).\n",
           NPTS, NLIGHTS, LTOP, NT);
}

/* quad with centre c, in-plane half-axes a and b */
static void quad(const double c[3], const double a[3], const double b[3], double *v)
{
    const double s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) v[3 * i + k] = c[k] + s[i][0] * a[k] + s[i][1] * b[k];
}

/* min over t of the windowed irradiance kernel K(t) = sum_l h_l A_l (2l+1)/(4 pi) P_l(t),
 * A_l = sqrt(4 pi/(2l+1)) zh_l (shl_zh_clamped_cosine), on NT samples of [-1, 1] */
static double kernel_min(int L, double lambda)
{
    double zh[SHL_LMAX_MAX + 1], h[SHL_LMAX_MAX + 1], c[SHL_LMAX_MAX + 1], mn = INFINITY;
    if (shl_zh_clamped_cosine(L, zh) || shl_sh_window_factors(L, SHL_WINDOW_LAPLACIAN, lambda, h)) return NAN;
    for (int l = 0; l <= L; ++l) c[l] = h[l] * zh[l] * sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
    for (int i = 0; i < NT; ++i) {
        const double t = -1.0 + 2.0 * i / (NT - 1.0);
        double p0 = 1.0, p1 = t, k = c[0];
        for (int l = 1; l <= L; ++l) {
            k += c[l] * p1;
            const double p2 = ((2.0 * l + 1.0) * t * p1 - l * p0) / (l + 1.0);
            p0 = p1;
            p1 = p2;
        }
        mn = fmin(mn, k);
    }
    return mn;
}

/* smallest lambda (to 0.1%) with kernel_min >= -1e-15: bisection in log lambda on [1e-9, 10] */
static double lambda_nonneg(int L)
{
    double lo = log(1e-9), hi = log(10.0);
    while (hi - lo > 1e-3) {
        const double mid = 0.5 * (lo + hi);
        if (kernel_min(L, exp(mid)) >= -1e-15) hi = mid;
        else lo = mid;
    }
    return exp(hi);
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_ringing.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(); return 0; }
        if (!strcmp(argv[i], "-o") && i + 1 < argc) { csv_path = argv[++i]; continue; }
        fprintf(stderr, "bench_ringing: unknown argument '%s' (try --help)\n", argv[i]);
        return 2;
    }
    double lv[NLIGHTS][12];
    const double t0 = (double)clock() / CLOCKS_PER_SEC;
    const double c0[3] = {1.4, 0.0, 0.3}, a0[3] = {0.0, 0.9, 0.0}, b0[3] = {0.0, 0.0, 0.9};
    const double c1[3] = {-0.8, 1.9, 1.2}, a1[3] = {0.4, 0.2, 0.0}, b1[3] = {0.0, 0.1, 0.35};
    const double c2[3] = {0.3, -1.2, -2.6}, a2[3] = {0.5, 0.0, 0.0}, b2[3] = {0.0, 0.3, 0.2};
    quad(c0, a0, b0, lv[0]);
    quad(c1, a1, b1, lv[1]);
    quad(c2, a2, b2, lv[2]);
    shl_ctx *ctx = NULL;
    shl_lights *lights = NULL;
    const double white[3] = {1, 1, 1};
    int st = shl_ctx_create(LTOP, &ctx);
    if (!st) st = shl_lights_create(&lights);
    for (int i = 0; i < NLIGHTS && !st; ++i) st = shl_lights_add_polygon(lights, lv[i], 4, white, 1);
    if (st) { fprintf(stderr, "bench_ringing: %s\n", shl_strerror(st)); return 1; }

    const int nc = SHL_NCOEFFS(LTOP);
    double *rgb = malloc(sizeof(double) * 3 * nc), *exact = malloc(sizeof(double) * NPTS);
    double *approx = malloc(sizeof(double) * NPTS * NL * NW);
    double pts[NPTS][3], lstar[NL];
    for (int li = 0; li < NL; ++li) lstar[li] = lambda_nonneg(LMAXES[li]);
    if (!rgb || !exact || !approx) { fprintf(stderr, "bench_ringing: out of memory\n"); return 1; }
    for (int p = 0; p < NPTS && !st; ++p) {
        const double z = 1.0 - (2.0 * p + 1.0) / NPTS, r = sqrt(1.0 - z * z), phi = p * M_PI * (3.0 - sqrt(5.0));
        const double x[3] = {r * cos(phi), r * sin(phi), z};
        memcpy(pts[p], x, sizeof x);
        exact[p] = 0.0;
        for (int i = 0; i < NLIGHTS && !st; ++i) {
            double e;
            st = shl_polygon_irradiance(x, x, lv[i], 4, &e);
            exact[p] += e;
        }
        if (!st) st = shl_lights_eval(ctx, lights, x, rgb, NULL);
        for (int li = 0; li < NL && !st; ++li) {
            const int L = LMAXES[li];
            for (int w = 0; w < NW && !st; ++w) {
                double co[SHL_NCOEFFS(LTOP)];
                memcpy(co, rgb, sizeof(double) * SHL_NCOEFFS(L)); /* channel 0, bands 0..L */
                if (w == 1) st = shl_sh_window(L, SHL_WINDOW_HANNING, L + 1.0, co);
                if (w == 2) st = shl_sh_window(L, SHL_WINDOW_LANCZOS, L + 1.0, co);
                if (w == 3) st = shl_sh_window(L, SHL_WINDOW_LAPLACIAN, 1.0 / pow(L * (L + 1.0), 2), co);
                if (w == 4) st = shl_sh_window(L, SHL_WINDOW_LAPLACIAN, lstar[li], co);
                if (w == 5) st = shl_sh_window(L, SHL_WINDOW_POUSSIN, L, co);
                if (!st) st = shl_sh_irradiance(L, co, x, &approx[(p * NL + li) * NW + w]);
            }
        }
    }
    if (st) { fprintf(stderr, "bench_ringing: %s\n", shl_strerror(st)); return 1; }

    double emax = 0.0, esq = 0.0;
    int nlit = 0;
    for (int p = 0; p < NPTS; ++p) {
        emax = fmax(emax, exact[p]);
        esq += exact[p] * exact[p];
        nlit += exact[p] > 0.0;
    }
    const double erms = sqrt(esq / NPTS);
    mkdir("build", 0777);
    mkdir("build/bench", 0777);
    FILE *csv = fopen(csv_path, "w");
    if (!csv) { fprintf(stderr, "bench_ringing: cannot write %s\n", csv_path); return 1; }
    fprintf(csv, "lmax,window,param,frac_negative,min_over_max,rms_err_over_rms,max_err_over_max\n");
    printf("%d points on a unit sphere (normals outward), %d two-sided quads; %d points lit (exact E > 0),\n"
           "max exact E %.4f, RMS %.4f\n\n", NPTS, NLIGHTS, nlit, emax, erms);
    printf("| lmax | window | param | negative | min E / max E | RMS err / RMS E | max err / max E |\n"
           "| ---: | --- | ---: | ---: | ---: | ---: | ---: |\n");
    for (int li = 0; li < NL; ++li)
        for (int w = 0; w <= NW; ++w) { /* w == NW: no window, result clamped at 0 */
            const int L = LMAXES[li];
            const double param = w == 0 || w == NW ? 0.0
                                 : w == 3          ? 1.0 / pow(L * (L + 1.0), 2)
                                 : w == 4          ? lstar[li]
                                 : w == 5          ? L
                                                   : L + 1.0;
            int neg = 0;
            double mn = 0.0, sq = 0.0, mx = 0.0;
            for (int p = 0; p < NPTS; ++p) {
                const double a = w == NW ? fmax(0.0, approx[(p * NL + li) * NW]) : approx[(p * NL + li) * NW + w];
                const double d = a - exact[p];
                neg += a < 0.0;
                mn = fmin(mn, a);
                sq += d * d;
                mx = fmax(mx, fabs(d));
            }
            const double frac = (double)neg / NPTS, rms = sqrt(sq / NPTS) / erms;
            const char *name = w == NW ? "none, max(0, E)" : WNAMES[w];
            printf("| %d | %s | %.3g | %.1f%% | %.4f | %.4f | %.4f |\n", L, name, param, 100.0 * frac, mn / emax,
                   rms, mx / emax);
            fprintf(csv, "%d,%s,%.6g,%.6f,%.6g,%.6g,%.6g\n", L, w == NW ? "clamp" : WNAMES[w], param, frac,
                    mn / emax, rms, mx / emax);
        }
    fclose(csv);
    printf("\nCSV: %s (%.2f s CPU)\n", csv_path, (double)clock() / CLOCKS_PER_SEC - t0);
    free(rgb);
    free(exact);
    free(approx);
    shl_lights_destroy(lights);
    shl_ctx_destroy(ctx);
    return 0;
}
