/* Gradients, sparse grids and interpolation (Wu et al. 2020, Sec. 6-7):
 *  - Fig. 4: coefficient (7,2) along a line, trilinear / Taylor (Annen 2004) / Hermite from 10 samples,
 *  - Fig. 6: d/dx of (6,-3) and (7,2), analytic vs central differences,
 *  - cost of the analytic gradient vs coefficients only and vs finite differences,
 *  - Fig. 8: many lights on a heightfield, per-vertex analytic vs 8^3 grid + Hermite,
 *  - Fig. 9: grid resolution vs time and error; thread scaling of fill and interpolation,
 *  - grid fill per node vs the float light-set batch per point (issue 17), 2 threads vs 1 on every
 *    batch entry point.
 * All ratios come from one run; --help.  CSVs (dir: -d, default build/bench):
 *  <dir>/bench_grid_fig4.csv: the Fig. 4 curves, then the 10 samples with their d/dx;
 *  <dir>/bench_grid.csv: one row per table row, value1/value2 = fig4: max error, / max |L72|;
 *  fig6: max |analytic - FD|, relative; gradcost: grad/coeffs and FD/analytic time ratios;
 *  gradcost_set: s per light without/with gradients; fig8: per-vertex s, grid s;
 *  fig9: grid s, Hermite max error; threads: 1-thread s, 2-thread s;
 *  fillrate: fill s per node, shl_lights_eval_batch_f s per point (16^3, gradients, 1 thread);
 *  threads_batch: 1-thread s, 2-thread s of each batch entry point. */
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static FILE *csv;
static shl_lights *subdivided_light(int nl);

static shl_ctx *new_ctx(int lmax)
{
    shl_ctx *ctx;
    if (shl_ctx_create(lmax, &ctx) != SHL_OK) exit(1);
    return ctx;
}

static void must(int st, const char *what)
{
    if (st != SHL_OK) {
        fprintf(stderr, "%s: %s\n", what, shl_strerror(st));
        exit(1);
    }
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n);
    if (!p) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    return p;
}

/* ---- Wu 2020 Fig. 4 -------------------------------------------------------- */

/* Square light (-1,-1,2)-(1,1,2); line y = 0.3, z = 0, x in [-2, 2]; lmax 7.
 * The 10 samples are a 10 x 2 x 2 grid whose y/z extent is 1e-6, so each method
 * acts along the line only (tests/test_grid.c uses the same setup). */
static void fig4(const char *dir)
{
    enum { NP = 2000, NS = 10, N7 = SHL_NCOEFFS(7), K72 = 7 * 8 + 2 };
    const double rect[12] = {-1, -1, 2, 1, -1, 2, 1, 1, 2, -1, 1, 2}, white[3] = {1, 1, 1};
    const double lo[3] = {-2.0, 0.3, 0.0}, hi[3] = {2.0, 0.3 + 1e-6, 1e-6};
    const int res[3] = {NS, 2, 2};
    shl_ctx *ctx = new_ctx(7);
    shl_lights *l;
    shl_grid *g;
    must(shl_lights_create(&l), "lights");
    must(shl_lights_add_polygon(l, rect, 4, white, 1), "add");
    must(shl_grid_create(ctx, lo, hi, res, SHL_GRID_DOUBLE, &g), "grid");
    must(shl_grid_fill(g, l, 1), "fill");
    double *pts = xmalloc(sizeof(double) * 3 * NP), *ref = xmalloc(sizeof(double) * 3 * N7 * NP);
    double *out[5];
    for (int p = 0; p < NP; ++p) {
        pts[3 * p] = lo[0] + (hi[0] - lo[0]) * p / (NP - 1);
        pts[3 * p + 1] = lo[1];
        pts[3 * p + 2] = lo[2];
    }
    must(shl_lights_eval_batch(ctx, l, NP, pts, ref, NULL), "reference");
    const char *names[5] = {"trilinear", "Taylor b=1", "Taylor b=2", "Taylor b=4", "Hermite"};
    const int methods[5] = {SHL_INTERP_TRILINEAR, SHL_INTERP_TAYLOR, SHL_INTERP_TAYLOR, SHL_INTERP_TAYLOR, SHL_INTERP_HERMITE};
    const double bexp[5] = {0, 1, 2, 4, 0};
    double err[5] = {0}, scale = 0.0;
    for (int p = 0; p < NP; ++p) scale = fmax(scale, fabs(ref[p * 3 * N7 + K72]));
    for (int m = 0; m < 5; ++m) {
        out[m] = xmalloc(sizeof(double) * 3 * N7 * NP);
        must(shl_grid_interp(g, methods[m], bexp[m], NP, pts, out[m], 1), "interp");
        for (int p = 0; p < NP; ++p) err[m] = fmax(err[m], fabs(out[m][p * 3 * N7 + K72] - ref[p * 3 * N7 + K72]));
    }
    char path[512];
    snprintf(path, sizeof path, "%s/bench_grid_fig4.csv", dir);
    FILE *f = fopen(path, "w");
    if (f) {
        fprintf(f, "kind,x,reference,trilinear,taylor_b2,hermite,ddx\n");
        for (int p = 0; p < NP; ++p)
            fprintf(f, "curve,%.6f,%.9e,%.9e,%.9e,%.9e,\n", pts[3 * p], ref[p * 3 * N7 + K72], out[0][p * 3 * N7 + K72],
                    out[2][p * 3 * N7 + K72], out[4][p * 3 * N7 + K72]);
        for (int i = 0; i < NS; ++i) { /* the samples: node value and d/dx */
            const int idx[3] = {i, 0, 0};
            double pos[3], v[3 * N7], gr[9 * N7];
            must(shl_grid_node_position(g, idx, pos), "node");
            must(shl_grid_get_node(g, idx, v, gr), "node");
            fprintf(f, "sample,%.6f,%.9e,,,,%.9e\n", pos[0], v[K72], gr[K72]);
        }
        fclose(f);
    }
    printf("\n## Wu 2020 Fig. 4: coefficient (7,2) along a line from %d samples (lmax 7)\n\n", NS);
    printf("Square light (-1,-1,2)-(1,1,2), two-sided; line y = 0.3, z = 0, x in [-2, 2]; reference: %d points,\n"
           "per-point analytic; max |L72| on the line %.4f.  Curve: %s\n\n", NP, scale, path);
    printf("| method | max abs error | max error / max abs L72 | Hermite is more accurate by |\n|---|---|---|---|\n");
    for (int m = 0; m < 5; ++m) {
        printf("| %s | %.3e | %.2e | %.1fx |\n", names[m], err[m], err[m] / scale, err[m] / err[4]);
        if (csv) fprintf(csv, "fig4,%s,%d,%.6e,%.6e\n", names[m], NS, err[m], err[m] / scale);
    }
    printf("\nTarget: Hermite >= 10x more accurate than trilinear and Taylor: %s\n",
           err[4] * 10 <= err[0] && err[4] * 10 <= err[1] && err[4] * 10 <= err[2] && err[4] * 10 <= err[3] ? "met" : "NOT met");
    for (int m = 0; m < 5; ++m) free(out[m]);
    free(pts);
    free(ref);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* ---- Wu 2020 Fig. 6 -------------------------------------------------------- */

static void fig6(void)
{
    enum { NPIX = 64, N8 = SHL_NCOEFFS(8) };
    const double rect[12] = {-5, -5, 1, 5, -5, 1, 5, 5, 1, -5, 5, 1}, delta = 1e-3;
    const int ks[2] = {6 * 7 - 3, 7 * 8 + 2};
    shl_ctx *ctx = new_ctx(8);
    double diff[2] = {0, 0}, scale[2] = {0, 0};
    for (int i = 0; i < NPIX; ++i)
        for (int j = 0; j < NPIX; ++j) {
            const double x[3] = {3.0 + 3.0 * (i + 0.5) / NPIX, 3.0 + 3.0 * (j + 0.5) / NPIX, 0.0};
            const double xp[3] = {x[0] + delta, x[1], x[2]}, xm[3] = {x[0] - delta, x[1], x[2]};
            double c[N8], gr[3 * N8], cp[N8], cm[N8];
            must(shl_polygon_grad(ctx, x, rect, 4, c, gr), "grad");
            must(shl_polygon(ctx, xp, rect, 4, cp), "polygon");
            must(shl_polygon(ctx, xm, rect, 4, cm), "polygon");
            for (int q = 0; q < 2; ++q) {
                const double fd = (cp[ks[q]] - cm[ks[q]]) / (2 * delta);
                diff[q] = fmax(diff[q], fabs(gr[ks[q]] - fd));
                scale[q] = fmax(scale[q], fabs(gr[ks[q]]));
            }
        }
    printf("\n## Wu 2020 Fig. 6: d/dx of two coefficients, analytic vs central differences\n\n");
    printf("Light (-5,-5,1)-(5,5,1); %dx%d pixel centres over (3,3,0)-(6,6,0); FD step %.0e; lmax 8.\n\n", NPIX, NPIX, delta);
    printf("| (l,m) | max abs d/dx | max abs(analytic - FD) | relative |\n|---|---|---|---|\n");
    const char *lm[2] = {"(6,-3)", "(7,2)"};
    for (int q = 0; q < 2; ++q) {
        printf("| %s | %.4e | %.2e | %.1e |\n", lm[q], scale[q], diff[q], diff[q] / scale[q]);
        if (csv) fprintf(csv, "fig6,%s,%d,%.6e,%.6e\n", lm[q], NPIX * NPIX, diff[q], diff[q] / scale[q]);
    }
    printf("\n(the difference is the FD truncation error, O(delta^2))\n");
    shl_ctx_destroy(ctx);
}

/* ---- cost of gradients ----------------------------------------------------- */

enum { GPTS = 64 };
typedef struct {
    const shl_ctx *ctx;
    double verts[12];
    double pts[GPTS][3];
    long inner;
} grad_job;

static double gbuf[4 * SHL_NCOEFFS(SHL_LMAX_MAX)];

static void run_coeffs(void *p)
{
    grad_job *j = p;
    for (long i = 0; i < j->inner; ++i) shl_polygon(j->ctx, j->pts[i % GPTS], j->verts, 4, gbuf);
    bench_sink += gbuf[0];
}

static void run_grad(void *p)
{
    grad_job *j = p;
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(j->ctx));
    for (long i = 0; i < j->inner; ++i) shl_polygon_grad(j->ctx, j->pts[i % GPTS], j->verts, 4, gbuf, gbuf + nc);
    bench_sink += gbuf[0];
}

static void run_fd(void *p) /* value + central differences: 7 coefficient evaluations */
{
    grad_job *j = p;
    const int nc = SHL_NCOEFFS(shl_ctx_lmax(j->ctx));
    const double h = 1e-3;
    for (long i = 0; i < j->inner; ++i) {
        const double *x = j->pts[i % GPTS];
        shl_polygon(j->ctx, x, j->verts, 4, gbuf);
        for (int a = 0; a < 3; ++a) {
            double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
            xp[a] += h;
            xm[a] -= h;
            shl_polygon(j->ctx, xp, j->verts, 4, gbuf + nc);
            shl_polygon(j->ctx, xm, j->verts, 4, gbuf + 2 * nc);
            for (int k = 0; k < nc; ++k) gbuf[3 * nc + k] = (gbuf[nc + k] - gbuf[2 * nc + k]) / (2 * h);
        }
    }
    bench_sink += gbuf[3 * SHL_NCOEFFS(shl_ctx_lmax(j->ctx))];
}

static const shl_lights *set_lights;

static void run_set(void *p) /* a light set: ZH integrals accumulated, one reconstruction per point */
{
    grad_job *j = p;
    static double out[GPTS * 3 * SHL_NCOEFFS(8)];
    for (long i = 0; i < j->inner; ++i) shl_lights_eval_batch(j->ctx, set_lights, GPTS, j->pts[0], out, NULL);
    bench_sink += out[0];
}

static void run_set_grad(void *p)
{
    grad_job *j = p;
    static double out[GPTS * 3 * SHL_NCOEFFS(8)], g[GPTS * 9 * SHL_NCOEFFS(8)];
    for (long i = 0; i < j->inner; ++i) shl_lights_eval_batch(j->ctx, set_lights, GPTS, j->pts[0], out, g);
    bench_sink += out[0];
}

static double timed(void (*fn)(void *), grad_job *j) /* seconds per evaluation, median of 7 x ~20 ms */
{
    j->inner = 1;
    const double t0 = bench_now();
    long n = 0;
    while (bench_now() - t0 < 0.005) { fn(j); ++n; }
    j->inner = (long)fmax(1.0, 0.02 * n / (bench_now() - t0));
    return bench_run(fn, j, j->inner, 7).median;
}

static void grad_cost(void)
{
    printf("\n## Cost of analytic gradients (one quad light, double, one core)\n\n");
    printf("| lmax | shl_polygon ns | shl_polygon_grad ns | grad / coeffs (target <= 1.4; paper Table 1: 1.19-1.38) |"
           " central FD (7 evaluations) ns | FD / analytic (target >= 4; paper 3) |\n|---|---|---|---|---|---|\n");
    const int lmaxes[2] = {4, 8};
    static grad_job j;
    const double quad[12] = {-1, -1, 2, 1, -1, 2, 1, 1, 2, -1, 1, 2};
    memcpy(j.verts, quad, sizeof quad);
    srand(1);
    for (int p = 0; p < GPTS; ++p)
        for (int a = 0; a < 3; ++a) j.pts[p][a] = 2.0 * rand() / RAND_MAX - 1.0;
    for (int i = 0; i < 2; ++i) {
        shl_ctx *ctx = new_ctx(lmaxes[i]);
        j.ctx = ctx;
        const double tc = timed(run_coeffs, &j), tg = timed(run_grad, &j), tf = timed(run_fd, &j);
        printf("| %d | %.0f | %.0f | %.2f | %.0f | %.1fx |\n", lmaxes[i], tc * 1e9, tg * 1e9, tg / tc, tf * 1e9, tf / tg);
        if (csv) fprintf(csv, "gradcost,lmax%d,4,%.6e,%.6e\n", lmaxes[i], tg / tc, tf / tg);
        shl_ctx_destroy(ctx);
    }
    shl_lights *l = subdivided_light(64);
    set_lights = l;
    printf("\nIn a light set the reconstruction is shared (64 triangle lights, %d points per call):\n\n"
           "| lmax | coefficients ns per light | with gradients ns per light | ratio |\n|---|---|---|---|\n", GPTS);
    for (int i = 0; i < 2; ++i) {
        shl_ctx *ctx = new_ctx(lmaxes[i]);
        j.ctx = ctx;
        const double tc = timed(run_set, &j) / (GPTS * 64.0), tg = timed(run_set_grad, &j) / (GPTS * 64.0);
        printf("| %d | %.0f | %.0f | %.2f |\n", lmaxes[i], tc * 1e9, tg * 1e9, tg / tc);
        if (csv) fprintf(csv, "gradcost_set,lmax%d,64,%.6e,%.6e\n", lmaxes[i], tc, tg);
        shl_ctx_destroy(ctx);
    }
    shl_lights_destroy(l);
}

/* ---- many lights (Wu 2020 Figs. 8-9) -------------------------------------- */

enum { HF = 100, NVERT = HF * HF, MLMAX = 4, MNC = SHL_NCOEFFS(MLMAX) };

/* 100 x 100-vertex heightfield z = 0.15 sin(3x) cos(2y) over [-1,1]^2; its bounding box. */
static double *heightfield(double lo[3], double hi[3])
{
    double *v = xmalloc(sizeof(double) * 3 * NVERT);
    for (int a = 0; a < 3; ++a) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (int i = 0; i < HF; ++i)
        for (int j = 0; j < HF; ++j) {
            double *p = v + 3 * (i * HF + j);
            p[0] = -1.0 + 2.0 * j / (HF - 1);
            p[1] = -1.0 + 2.0 * i / (HF - 1);
            p[2] = 0.15 * sin(3 * p[0]) * cos(2 * p[1]);
            for (int a = 0; a < 3; ++a) {
                lo[a] = fmin(lo[a], p[a]);
                hi[a] = fmax(hi[a], p[a]);
            }
        }
    return v;
}

/* The rectangle (-0.8,-0.8,1)-(0.8,0.8,1), facing down (one-sided), as nl lights:
 * nl = 1: one quad; else nl/2 strips along x of two triangles each.  The field is the same for every nl. */
static shl_lights *subdivided_light(int nl)
{
    shl_lights *l;
    const double rgb[3] = {1.0, 0.9, 0.8}, z = 1.0, a = -0.8, b = 0.8;
    must(shl_lights_create(&l), "lights");
    if (nl == 1) {
        const double quad[12] = {a, a, z, a, b, z, b, b, z, b, a, z}; /* clockwise from above: faces -z */
        must(shl_lights_add_polygon(l, quad, 4, rgb, 0), "add");
        return l;
    }
    for (int s = 0; s < nl / 2; ++s) {
        const double x0 = a + (b - a) * s / (nl / 2), x1 = a + (b - a) * (s + 1) / (nl / 2);
        const double t1[9] = {x0, a, z, x0, b, z, x1, b, z}, t2[9] = {x0, a, z, x1, b, z, x1, a, z};
        must(shl_lights_add_polygon(l, t1, 3, rgb, 0), "add");
        must(shl_lights_add_polygon(l, t2, 3, rgb, 0), "add");
    }
    return l;
}

/* max and mean |got - want| / max |want L00| over all vertices, colours and coefficients */
static void field_error(const double *got, const double *want, double *max_err, double *mean_err)
{
    double scale = 0.0, mx = 0.0, sum = 0.0;
    for (int p = 0; p < NVERT; ++p) scale = fmax(scale, fabs(want[p * 3 * MNC]));
    for (long i = 0; i < (long)NVERT * 3 * MNC; ++i) {
        const double e = fabs(got[i] - want[i]);
        mx = fmax(mx, e);
        sum += e;
    }
    *max_err = mx / scale;
    *mean_err = sum / ((double)NVERT * 3 * MNC) / scale;
}

/* A res^3 float grid over the box filled from the lights: best fill time of `reps`. */
static shl_grid *filled_grid(const shl_ctx *ctx, const shl_lights *l, const double lo[3], const double hi[3], int res,
                             int nthreads, int reps, double *fill_s)
{
    const int r3[3] = {res, res, res};
    shl_grid *g;
    must(shl_grid_create(ctx, lo, hi, r3, SHL_GRID_FLOAT, &g), "grid");
    *fill_s = INFINITY;
    for (int rep = 0; rep < reps; ++rep) {
        const double t0 = bench_now();
        must(shl_grid_fill(g, l, nthreads), "fill");
        *fill_s = fmin(*fill_s, bench_now() - t0);
    }
    return g;
}

/* Interpolate every vertex: best time of `reps`. */
static double interp_all(const shl_grid *g, int method, int nthreads, int reps, const double *verts, double *out)
{
    double best = INFINITY;
    for (int rep = 0; rep < reps; ++rep) {
        const double t0 = bench_now();
        must(shl_grid_interp(g, method, 2.0, NVERT, verts, out, nthreads), "interp");
        best = fmin(best, bench_now() - t0);
    }
    return best;
}

static double per_vertex(const shl_ctx *ctx, const shl_lights *l, int reps, const double *verts, double *out)
{
    double best = INFINITY;
    for (int rep = 0; rep < reps; ++rep) {
        const double t0 = bench_now();
        must(shl_lights_eval_batch(ctx, l, NVERT, verts, out, NULL), "per-vertex");
        best = fmin(best, bench_now() - t0);
    }
    return best;
}

static void many_lights(void)
{
    double lo[3], hi[3];
    double *verts = heightfield(lo, hi);
    double *ref = xmalloc(sizeof(double) * NVERT * 3 * MNC), *out = xmalloc(sizeof(double) * NVERT * 3 * MNC);
    shl_ctx *ctx = new_ctx(MLMAX);
    printf("\n## Wu 2020 Fig. 8: lighting every vertex of a heightfield with many lights (lmax %d, one thread)\n\n", MLMAX);
    printf("Mesh: %dx%d-vertex heightfield z = 0.15 sin(3x) cos(2y) over [-1,1]^2 (%d vertices).  Lights: the\n"
           "rectangle (-0.8,-0.8,1)-(0.8,0.8,1), one-sided facing the mesh, as 1 quad or n triangles (n/2 strips).\n"
           "Grid: 8^3 float nodes over the mesh's bounding box, filled with coefficients + gradients, then\n"
           "Hermite-interpolated at every vertex.  Times: best of 3 (2 from 256 lights).  Errors vs per-vertex\n"
           "analytic, relative to max |L00| (the field is the same for every light count).\n\n", HF, HF, NVERT);
    printf("| lights | per-vertex analytic ms | grid fill ms | Hermite interp ms | grid total ms | speed-up | max err | mean err |\n"
           "|---|---|---|---|---|---|---|---|\n");
    int crossover = -1;
    for (int nl = 1; nl <= 512; nl *= 2) {
        shl_lights *l = subdivided_light(nl);
        const int reps = nl >= 256 ? 2 : 3;
        const double tv = per_vertex(ctx, l, reps, verts, ref);
        double tf;
        shl_grid *g = filled_grid(ctx, l, lo, hi, 8, 1, reps, &tf);
        const double ti = interp_all(g, SHL_INTERP_HERMITE, 1, 3, verts, out);
        double emax, emean;
        field_error(out, ref, &emax, &emean);
        const double tg = tf + ti;
        if (crossover < 0 && tg < tv) crossover = nl;
        printf("| %d | %.1f | %.2f | %.2f | %.2f | %.1fx | %.1e | %.1e |\n", nl, tv * 1e3, tf * 1e3, ti * 1e3, tg * 1e3,
               tv / tg, emax, emean);
        if (csv) fprintf(csv, "fig8,lights%d,%d,%.6e,%.6e\n", nl, NVERT, tv, tg);
        shl_grid_destroy(g);
        shl_lights_destroy(l);
    }
    if (crossover > 0)
        printf("\nCrossover against per-vertex double (the paper's comparison; per-vertex float SIMD is faster, see\n"
               "build/bench/bench_paths): the grid pipeline is faster from %d light(s) on.\n", crossover);
    else
        printf("\nCrossover against per-vertex double: the grid pipeline was never faster up to 512 lights.\n");

    enum { NLR = 32 };
    shl_lights *l = subdivided_light(NLR);
    must(shl_lights_eval_batch(ctx, l, NVERT, verts, ref, NULL), "per-vertex");
    printf("\n## Wu 2020 Fig. 9: grid resolution vs time and error (%d triangle lights, lmax %d, one thread)\n\n", NLR, MLMAX);
    int bpn;
    must(shl_grid_bytes_per_node(MLMAX, SHL_GRID_FLOAT, &bpn), "bytes");
    printf("Float nodes: %d bytes per node (3 colours x (value + 3 gradients) x %d coefficients x 4 bytes).\n"
           "Errors relative to max |L00| over all vertices, colours and coefficients.  Times: best of 3 (fill of 32^3: 1).\n\n",
           bpn, MNC);
    printf("| grid | memory KiB | fill ms | Hermite interp ms | Hermite max / mean err | trilinear max / mean err | Taylor (b=2) max / mean err |\n"
           "|---|---|---|---|---|---|---|\n");
    for (int res = 4; res <= 32; res *= 2) {
        double tf, e[3][2];
        shl_grid *g = filled_grid(ctx, l, lo, hi, res, 1, res < 32 ? 3 : 1, &tf);
        const double ti = interp_all(g, SHL_INTERP_HERMITE, 1, 3, verts, out);
        field_error(out, ref, &e[0][0], &e[0][1]);
        interp_all(g, SHL_INTERP_TRILINEAR, 1, 1, verts, out);
        field_error(out, ref, &e[1][0], &e[1][1]);
        interp_all(g, SHL_INTERP_TAYLOR, 1, 1, verts, out);
        field_error(out, ref, &e[2][0], &e[2][1]);
        printf("| %d^3 | %.0f | %.1f | %.2f | %.1e / %.1e | %.1e / %.1e | %.1e / %.1e |\n", res,
               (double)res * res * res * bpn / 1024.0, tf * 1e3, ti * 1e3, e[0][0], e[0][1], e[1][0], e[1][1], e[2][0], e[2][1]);
        if (csv) fprintf(csv, "fig9,res%d,%d,%.6e,%.6e\n", res, NVERT, tf + ti, e[0][0]);
        shl_grid_destroy(g);
    }

    printf("\n## Thread scaling, 16^3 grid, %d lights, %d vertices (best of 3)\n\n"
           "| step | 1 thread ms | 2 threads ms | speed-up |\n|---|---|---|---|\n", NLR, NVERT);
    double tf1, tf2;
    shl_grid *g1 = filled_grid(ctx, l, lo, hi, 16, 1, 3, &tf1), *g2 = filled_grid(ctx, l, lo, hi, 16, 2, 3, &tf2);
    const double ti1 = interp_all(g1, SHL_INTERP_HERMITE, 1, 5, verts, out), ti2 = interp_all(g1, SHL_INTERP_HERMITE, 2, 5, verts, out);
    printf("| grid fill | %.1f | %.1f | %.2fx |\n", tf1 * 1e3, tf2 * 1e3, tf1 / tf2);
    printf("| Hermite interpolation | %.2f | %.2f | %.2fx |\n", ti1 * 1e3, ti2 * 1e3, ti1 / ti2);
    printf("\nHermite interpolation, one thread: %.0f ns per vertex (%d coefficients x 3 colours).\n", ti1 / NVERT * 1e9, MNC);
    if (csv) {
        fprintf(csv, "threads,fill16,%d,%.6e,%.6e\n", NLR, tf1, tf2);
        fprintf(csv, "threads,interp,%d,%.6e,%.6e\n", NVERT, ti1, ti2);
    }
    shl_grid_destroy(g1);
    shl_grid_destroy(g2);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
    free(verts);
    free(ref);
    free(out);
}

/* ---- grid fill through the float batch; threads on every batch entry point ---- */

/* Process CPU seconds: one-thread timings that other processes on the cores do not inflate. */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Busy and total seconds of all CPUs since boot (the first line of /proc/stat; 0 and 0 where
 * it cannot be read): with the process CPU time, the share of the cores other processes held. */
static void machine_cpu(double *busy, double *total)
{
    unsigned long long v[8] = {0};
    FILE *f = fopen("/proc/stat", "r");
    const int got = f ? fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                               &v[6], &v[7])
                      : 0;
    if (f) fclose(f);
    const double tick = (double)sysconf(_SC_CLK_TCK);
    double sum = 0.0;
    for (int k = 0; k < 8; ++k) sum += (double)v[k];
    *total = got == 8 ? sum / tick : 0.0;
    *busy = got == 8 ? (sum - (double)v[3] - (double)v[4]) / tick : 0.0; /* all but idle and iowait */
}

enum { ROUNDS = 11 }; /* interleaved rounds of the -f tables (after one warm-up call of each variant) */

/* Wall-clock and process CPU seconds of one call of fn(arg). */
static void time_call(void (*fn)(void *), void *arg, double *wall, double *cpu)
{
    const double w0 = bench_now(), c0 = cpu_now();
    fn(arg);
    const double c1 = cpu_now(), w1 = bench_now();
    *wall = w1 - w0;
    *cpu = c1 - c0;
}

/* ROUNDS rounds of a against b, back to back under the same load, the order alternating
 * between rounds (after a warm-up call of each: outputs and workspaces touched).  Per round:
 * wall and process CPU seconds of both; returns the medians and the medians of the
 * per-round ratios a / b (wall and CPU). */
typedef struct {
    double wall_a, wall_b, cpu_a, cpu_b, wall_ratio, cpu_ratio;
} paired;

static paired time_pair(void (*fa)(void *), void *a, void (*fb)(void *), void *b)
{
    double wa[ROUNDS], wb[ROUNDS], ca[ROUNDS], cb[ROUNDS], wr[ROUNDS], cr[ROUNDS];
    fa(a);
    fb(b);
    for (int r = 0; r < ROUNDS; ++r) {
        if (r & 1) time_call(fb, b, &wb[r], &cb[r]);
        time_call(fa, a, &wa[r], &ca[r]);
        if (!(r & 1)) time_call(fb, b, &wb[r], &cb[r]);
        wr[r] = wa[r] / wb[r];
        cr[r] = ca[r] / cb[r];
    }
    const paired m = {bench_median(wa, ROUNDS), bench_median(wb, ROUNDS), bench_median(ca, ROUNDS),
                      bench_median(cb, ROUNDS), bench_median(wr, ROUNDS), bench_median(cr, ROUNDS)};
    return m;
}

typedef struct {
    const shl_ctx *ctx;
    const shl_lights *l;
    shl_grid *g;
    int npts, nthreads;
    const float *pts, *tri, *center;
    float *rgb, *grad;
    const double *dpts;
    double *drgb, *dgrad;
    shl_agrid *ag;
} fr_job;

static void fr_fill(void *a) { const fr_job *j = a; must(shl_grid_fill(j->g, j->l, j->nthreads), "fill"); }
static void fr_set_f(void *a)
{
    const fr_job *j = a;
    must(shl_lights_eval_batch_f_mt(j->ctx, j->l, j->npts, j->pts, j->rgb, j->grad, j->nthreads), "batch_f");
}
static void fr_set_d(void *a)
{
    const fr_job *j = a;
    must(shl_lights_eval_batch_mt(j->ctx, j->l, j->npts, j->dpts, j->drgb, j->dgrad, j->nthreads), "batch");
}
static void fr_poly(void *a)
{
    const fr_job *j = a;
    must(shl_polygon_batch_f_mt(j->ctx, j->tri, 3, j->npts, j->pts, j->rgb, j->grad, j->nthreads), "polygon batch");
}
static void fr_afill(void *a) { const fr_job *j = a; must(shl_agrid_fill(j->ag, j->l, j->nthreads), "agrid fill"); }
static void fr_ainterp(void *a)
{
    const fr_job *j = a;
    must(shl_agrid_interp(j->ag, j->npts, j->dpts, j->drgb, j->nthreads), "agrid interp");
}
static void fr_sphere(void *a)
{
    const fr_job *j = a;
    must(shl_sphere_batch_f_mt(j->ctx, j->center, 0.3f, j->npts, j->pts, j->rgb, j->grad, j->nthreads), "sphere batch");
}

/* 100 calls of the light-set batch with an empty set at lmax 0 on 128 points (two blocks:
 * two workers when nthreads = 2, each with next to nothing to do). */
static void fr_empty_calls(void *a)
{
    const fr_job *j = a;
    for (int c = 0; c < 100; ++c)
        must(shl_lights_eval_batch_f_mt(j->ctx, j->l, j->npts, j->pts, j->rgb, NULL, j->nthreads), "empty batch");
}

/* The machine's own ceiling for compute-bound threads: a register-only loop (10 independent
 * multiply-then-add chains, no memory traffic: alone it keeps a core's two multiply pipes ~80%
 * busy, so a second hardware thread on the same core can add little), on the calling thread alone, then on the calling
 * thread and one more pthread of the same work (no library code).  Two vCPUs that are two
 * physical cores give 2x; two hardware threads of one core, or a host that runs one vCPU at a
 * time, give less. */
enum { PROBE_ITERS = 4000000 };
static void *fp_probe(void *arg)
{
    enum { CHAINS = 10 };
    double x[CHAINS], m = 0.999999, a = 1e-7;
    for (int k = 0; k < CHAINS; ++k) x[k] = 1.0 + k;
    for (int i = 0; i < PROBE_ITERS; ++i)
        for (int k = 0; k < CHAINS; ++k) x[k] = x[k] * m + a;
    double s = 0.0;
    for (int k = 0; k < CHAINS; ++k) s += x[k];
    *(double *)arg = s;
    return NULL;
}
static void fp_probe_one(void *a) { fp_probe(a); }
static void fp_probe_two(void *a)
{
    double other;
    pthread_t t;
    if (pthread_create(&t, NULL, fp_probe, &other) != 0) {
        fprintf(stderr, "bench_grid: pthread_create failed\n");
        exit(1);
    }
    fp_probe(a);
    pthread_join(t, NULL);
    *(double *)a += other;
}
static void machine_thread_ceiling(void)
{
    double s1 = 0.0, s2 = 0.0;
    const paired m = time_pair(fp_probe_one, &s1, fp_probe_two, &s2);
    printf("\nThe machine's ceiling (register-only multiply-add loop, no memory, no library code; the same work on\n"
           "1 thread, then on 2 pthreads, medians of %d interleaved rounds): 2 threads do %.2fx the work of 1 per\n"
           "second (CPU efficiency %.0f%%): the most any compute-bound entry point above can reach here.\n",
           ROUNDS, 2.0 * m.wall_ratio, 200.0 * m.cpu_ratio);
    if (csv) fprintf(csv, "threads_machine,fp_loop,%d,%.4f,%.4f\n", PROBE_ITERS, 2.0 * m.wall_ratio, 2.0 * m.cpu_ratio);
    bench_sink += s1 + s2;
}

/* The fixed cost of a threaded call: 2 threads minus 1 thread on two blocks of no work
 * (handing work to the second thread, waiting for it), against the shortest 2-thread
 * call of the table. */
static void thread_start_cost(double shortest_call)
{
    enum { NPTS = 2 * 64 };
    shl_ctx *ctx = new_ctx(0);
    shl_lights *l;
    must(shl_lights_create(&l), "lights");
    float pts[3 * NPTS] = {0}, rgb[3 * NPTS];
    fr_job j1 = {ctx, l, NULL, NPTS, 1, pts, NULL, NULL, rgb, NULL, NULL, NULL, NULL, NULL}, j2 = j1;
    j2.nthreads = 2;
    const paired m = time_pair(fr_empty_calls, &j1, fr_empty_calls, &j2);
    const double cost = (m.wall_b - m.wall_a) / 100;
    printf("\nFixed cost of a 2-thread call (handing work to the second thread and waiting for it; 2 threads minus 1\n"
           "on two blocks of no work, medians of %d rounds of 100 calls): %.1f us per call, %.2f%% of the shortest 2-thread call above.\n",
           ROUNDS, cost * 1e6, 100.0 * cost / shortest_call);
    if (csv) fprintf(csv, "threads_start,empty_set,%d,%.6e,%.6e\n", NPTS, cost, cost / shortest_call);
    bench_sink += rgb[0];
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* Issue 17 target: a float grid's fill per node (gradients, 1 thread) <= 1.3x the
 * float light-set batch with gradients per point, same lights, at the same points
 * (the node positions rounded to float); then 2 threads vs 1 on every batch entry point. */
static void fill_rate(void)
{
    enum { R = 16, NN = R * R * R };
    double lo[3], hi[3];
    free(heightfield(lo, hi));
    const int r3[3] = {R, R, R};
    float *pts = xmalloc(sizeof(float) * 3 * NN);
    printf("\n## Grid fill per node vs the float light-set batch per point (16^3 float grid, gradients, one thread)\n\n"
           "Same lights (the Fig. 8 rectangle as n triangles), same points (the %d node positions rounded to float);\n"
           "process CPU time (one thread: not inflated by other processes); medians of %d interleaved rounds, fill / batch\n"
           "the median of the per-round ratios.  Target (issue 17): fill / batch <= 1.3.\n\n"
           "| lmax | lights | fill ns/node | shl_lights_eval_batch_f ns/point | fill / batch |\n|---|---|---|---|---|\n", NN,
           ROUNDS);
    const int lmaxes[2] = {4, 8}, nls[3] = {1, 8, 32};
    for (int li = 0; li < 2; ++li) {
        shl_ctx *ctx = new_ctx(lmaxes[li]);
        const int nc = SHL_NCOEFFS(lmaxes[li]);
        float *rgb = xmalloc(sizeof(float) * 3 * nc * NN), *grad = xmalloc(sizeof(float) * 9 * nc * NN);
        for (int n = 0; n < 3; ++n) {
            shl_lights *l = subdivided_light(nls[n]);
            shl_grid *g;
            must(shl_grid_create(ctx, lo, hi, r3, SHL_GRID_FLOAT, &g), "grid");
            for (int i = 0; i < NN; ++i) {
                const int idx[3] = {i % R, i / R % R, i / R / R};
                double x[3];
                must(shl_grid_node_position(g, idx, x), "node position");
                for (int a = 0; a < 3; ++a) pts[3 * i + a] = (float)x[a];
            }
            fr_job j = {ctx, l, g, NN, 1, pts, NULL, NULL, rgb, grad, NULL, NULL, NULL, NULL};
            const paired m = time_pair(fr_fill, &j, fr_set_f, &j);
            bench_sink += rgb[0];
            printf("| %d | %d | %.0f | %.0f | %.2f |\n", lmaxes[li], nls[n], m.cpu_a / NN * 1e9, m.cpu_b / NN * 1e9,
                   m.cpu_ratio);
            if (csv) fprintf(csv, "fillrate,lmax%d_lights%d,%d,%.6e,%.6e\n", lmaxes[li], nls[n], NN, m.cpu_a / NN, m.cpu_b / NN);
            shl_grid_destroy(g);
            shl_lights_destroy(l);
        }
        free(rgb);
        free(grad);
        shl_ctx_destroy(ctx);
    }

    enum { NP = 1 << 15, ND = 2000, TL = 8 };
    shl_ctx *ctx = new_ctx(TL);
    const int nc = SHL_NCOEFFS(TL);
    shl_lights *l = subdivided_light(8);
    float *bp = xmalloc(sizeof(float) * 3 * NP), *rgb = xmalloc(sizeof(float) * 3 * nc * NP),
          *grad = xmalloc(sizeof(float) * 9 * nc * NP);
    double *dp = xmalloc(sizeof(double) * 3 * NP / 4), *drgb = xmalloc(sizeof(double) * 3 * nc * NP / 4),
           *dgrad = xmalloc(sizeof(double) * 9 * nc * ND);
    for (int i = 0; i < NP; ++i) {
        bp[3 * i] = (float)(-1.0 + 2.0 * (i % 181) / 180.0);
        bp[3 * i + 1] = (float)(-1.0 + 2.0 * (i / 181 % 181) / 180.0);
        bp[3 * i + 2] = (float)(0.1 * (i % 7));
    }
    for (int i = 0; i < 3 * NP / 4; ++i) dp[i] = bp[i];
    const float tri[9] = {-0.8f, -0.8f, 1.0f, -0.8f, 0.8f, 1.0f, 0.8f, 0.8f, 1.0f}, center[3] = {0.0f, 0.0f, 1.5f};
    shl_grid *g;
    const int r32[3] = {32, 32, 32};
    must(shl_grid_create(ctx, lo, hi, r32, SHL_GRID_FLOAT, &g), "grid");
    /* adaptive: 8^3 coarse nodes, refined where the mean-error share exceeds 1e-4 (the light's
     * coefficients are O(1)), at most 32^3 nodes */
    shl_agrid *ag;
    const int r8[3] = {8, 8, 8};
    must(shl_agrid_create(ctx, lo, hi, r8, SHL_AGRID_MEAN, 1e-4, 32 * 32 * 32, &ag), "agrid");
    must(shl_agrid_fill(ag, l, 1), "agrid fill");
    shl_agrid_stats st;
    must(shl_agrid_get_stats(ag, &st), "agrid stats");
    char afill_name[96];
    snprintf(afill_name, sizeof afill_name, "shl_agrid_fill (8^3 coarse, %d levels; points: nodes)", st.levels);
    char load[64];
    bench_loadavg(load, sizeof load);
    printf("\n## Threads on every batch entry point (lmax %d, gradients, 8 triangle lights for the sets)\n\n"
           "Medians of %d interleaved rounds (1 thread and 2 threads back to back, the order alternating); speed-up:\n"
           "the median of the per-round wall-clock ratios.  CPU efficiency: process CPU time, 1 thread / 2 threads\n"
           "(both threads' time): below 100%%, each core works slower next to the other (shared L3 and DRAM\n"
           "bandwidth, clock); the speed-up the threads' CPU time allows is 2 x that, and a wall-clock speed-up\n"
           "below it is time a thread did not run (start, join, uneven ends or, on a loaded machine, other\n"
           "processes).  Load average before the table: %s\n\n"
           "| entry point | points | 1 thread ms | 2 threads ms | speed-up | CPU efficiency | speed-up by CPU time |\n"
           "|---|---|---|---|---|---|---|\n", TL, ROUNDS, load);
    struct {
        const char *name;
        void (*fn)(void *);
        int npts;
    } eps[7] = {{"shl_polygon_batch_f_mt", fr_poly, NP},
                {"shl_sphere_batch_f_mt", fr_sphere, NP},
                {"shl_lights_eval_batch_f_mt", fr_set_f, NP / 4},
                {"shl_lights_eval_batch_mt (double)", fr_set_d, ND},
                {"shl_grid_fill (32^3 float)", fr_fill, 32 * 32 * 32},
                {afill_name, fr_afill, (int)st.nodes},
                {"shl_agrid_interp", fr_ainterp, NP / 4}};
    double shortest = INFINITY, busy0, total0;
    machine_cpu(&busy0, &total0);
    const double own0 = cpu_now();
    for (int e = 0; e < 7; ++e) {
        fr_job j1 = {ctx, l, g, eps[e].npts, 1, bp, tri, center, rgb, grad, dp, drgb, dgrad, ag}, j2 = j1;
        j2.nthreads = 2;
        const paired m = time_pair(eps[e].fn, &j1, eps[e].fn, &j2);
        shortest = fmin(shortest, m.wall_b);
        printf("| %s | %d | %.2f | %.2f | **%.2fx** | %.0f%% | %.2fx |\n", eps[e].name, eps[e].npts, m.wall_a * 1e3,
               m.wall_b * 1e3, m.wall_ratio, 100.0 * m.cpu_ratio, 2.0 * m.cpu_ratio);
        if (csv) {
            fprintf(csv, "threads_batch,%s,%d,%.6e,%.6e\n", eps[e].name, eps[e].npts, m.wall_a, m.wall_b);
            fprintf(csv, "threads_batch_ratio,%s,%d,%.4f,%.4f\n", eps[e].name, eps[e].npts, m.wall_ratio, m.cpu_ratio);
        }
    }
    double busy1, total1;
    machine_cpu(&busy1, &total1);
    if (total1 > total0)
        printf("\nOther processes held %.0f%% of the machine's CPU time during the table (/proc/stat busy time less\n"
               "this process's CPU time): near 0 on an idle machine; the wall-clock speed-ups mean little above ~10%%.\n",
               100.0 * fmax(0.0, (busy1 - busy0) - (cpu_now() - own0)) / (total1 - total0));
    machine_thread_ceiling();
    thread_start_cost(shortest);
    bench_sink += rgb[0] + drgb[0];
    shl_agrid_destroy(ag);
    shl_grid_destroy(g);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
    free(pts);
    free(bp);
    free(rgb);
    free(grad);
    free(dp);
    free(drgb);
    free(dgrad);
}

int main(int argc, char **argv)
{
    const char *dir = "build/bench", *only = NULL;
    const bench_opt opts[] = {{"-d", "--dir", "DIR", &dir, "directory of the two CSV files (default build/bench)"},
                              {"-f", "--fill-rate", NULL, &only, "only the fill-rate and batch-thread tables (~30 s)"}};
    const bench_cli cli = {
        "bench_grid", "[-d DIR]",
        "Gradients, sparse grids and interpolation (Wu et al. 2020, Sec. 6-7): Fig. 4 (coefficient (7,2)\n"
        "along a line, trilinear / Taylor / Hermite from 10 samples), Fig. 6 (analytic gradients vs central\n"
        "differences), the cost of the analytic gradient, Fig. 8 (many lights: per-vertex analytic vs an\n"
        "8^3 grid + Hermite) and Fig. 9 (grid resolution vs time and error; thread scaling), then the grid\n"
        "fill per node against the float light-set batch per point and 2 threads vs 1 on every batch entry point.\n"
        "About 1 minute on a 2-core machine; progress on stderr.\n"
        "Writes Markdown tables to stdout, DIR/bench_grid.csv (one row per table row) and\n"
        "DIR/bench_grid_fig4.csv (the Fig. 4 curves and samples).",
        opts, 2, 0};
    bench_parse(&cli, argc, argv, NULL);
    char path[512];
    snprintf(path, sizeof path, "%s/bench_grid.csv", dir);
    csv = bench_create(path, "w");
    if (!csv) return 1;
    fprintf(csv, "section,case,count,value1,value2\n");
    const double t0 = bench_now();
    bench_print_machine(stdout);
    char load[64];
    bench_loadavg(load, sizeof load);
    printf("Load average at start (other processes share the 2 cores): %s\n", load);
    if (!only) {
        bench_progress("Fig. 4, interpolation along a line (step 1/5)...");
        fig4(dir);
        bench_progress("Fig. 6, gradients vs finite differences (step 2/5)...");
        fig6();
        bench_progress("cost of the analytic gradient (step 3/5)...");
        grad_cost();
        bench_progress("Figs. 8-9, many lights, grid resolution, threads (step 4/5)...");
        many_lights();
    }
    bench_progress("grid fill vs the float batch, threads on the batch entry points (step 5/5)...");
    fill_rate();
    printf("\n(total %.0f s; checksum %g)\n", bench_now() - t0, (double)bench_sink);
    if (fclose(csv)) return 1;
    bench_progress("done; wrote %s and %s/bench_grid_fig4.csv", path, dir);
    return 0;
}
