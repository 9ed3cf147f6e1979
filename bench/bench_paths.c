/* Which lighting path is fastest, by number of lights and lmax, and at what error.
 * One procedural receiver (points on a bumped sphere, no external files) lit by light sets
 * of 1, 2, 4, ..., 256 lights, each path timed per frame on the same thread count:
 *  - per-vertex double      shl_lights_eval_batch   (coefficients only; the error reference),
 *  - per-vertex float SIMD  shl_lights_eval_batch_f (the fastest per-vertex path),
 *  - grids of 8^3 and 16^3 float nodes over the receivers' bounding box: shl_grid_fill
 *    (per frame when lights move) + shl_grid_interp (Hermite, trilinear, Taylor b = 2).
 * Prints markdown tables, the fastest path per light count and, per grid configuration,
 * the light count from which it beats the float SIMD path.  `bench_paths --help`. */
#include "parfor.h"
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

enum { MAXL = 16, NPATH = 8, MAXREPS = 7 };

static const char *usage =
    "usage: bench_paths [--quick] [--cpu] [-n VERTICES] [-l LMAX[,LMAX...]] [-L MAXLIGHTS] [-t THREADS]\n"
    "                   [-e TOL] [-o CSV]\n"
    "\n"
    "Which lighting path is fastest for a given number of lights and lmax, and how accurate it is.\n"
    "A procedural receiver (N points on a bumped sphere; default N = 36000) is lit by light sets of\n"
    "1, 2, 4, ..., 256 lights (quads and triangles, one in 8 a sphere; all outside the grid box).\n"
    "Every path runs on the same thread count (default 1) and is timed per frame and per vertex:\n"
    "  per-vertex double      shl_lights_eval_batch   (coefficients only; the error reference)\n"
    "  per-vertex float SIMD  shl_lights_eval_batch_f\n"
    "  grid 8^3 and 16^3, float nodes: shl_grid_fill + shl_grid_interp with Hermite, trilinear and\n"
    "      Taylor (b = 2); fill + interp is the frame when lights move, interp alone when they are static\n"
    "Error: per vertex, |c - c_ref| / |c_ref| (2-norms over its 3 x (lmax+1)^2 RGB coefficients),\n"
    "c_ref from the double path; max and mean over the vertices.\n"
    "Prints markdown tables to stdout: time, error, the fastest path per light count, and the light\n"
    "count from which each grid configuration is faster than the float SIMD path.  Progress on stderr.\n"
    "\n"
    "  --quick     8192 vertices, up to 64 lights, shorter timing (about 15 s idle)\n"
    "  -n N        receiver vertices (default 36000)\n"
    "  -l LIST     lmax values, comma-separated (default 4,8)\n"
    "  -L MAX      largest light count; powers of 2 from 1 (default 256)\n"
    "  -t T        threads for every path (default 1)\n"
    "  --cpu       time by the process's CPU time (all threads) instead of wall time: on a loaded machine\n"
    "              it leaves out the time spent waiting for a core (not cache or memory contention)\n"
    "  -e TOL      the time table's last column: fastest path with max error <= TOL (default 1e-2)\n"
    "  -o FILE     CSV output, one row per (lmax, lights, path) (default build/bench/bench_paths.csv)\n"
    "  -h, --help  this text\n"
    "\n"
    "Run time with the defaults: about 2.5 minutes on one idle core (130 s of CPU time on a 2-core AMD EPYC\n"
    "guest); with -t 2 the same work on two cores.\n";

static void *xmalloc(size_t n)
{
    void *p = malloc(n);
    if (!p) {
        fprintf(stderr, "bench_paths: out of memory (%zu bytes)\n", n);
        exit(1);
    }
    return p;
}

static void must(int st, const char *what)
{
    if (st != SHL_OK) {
        fprintf(stderr, "bench_paths: %s: %s\n", what, shl_strerror(st));
        exit(1);
    }
}

static uint64_t mix64(uint64_t x)
{
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/* The k-th uniform number in [0, 1) of stream s. */
static double u01(uint64_t s, uint64_t k) { return (double)(mix64(s * 0x9E3779B97F4A7C15ull + k) >> 11) * 0x1.0p-53; }

/* ---- receiver and lights ------------------------------------------------------ */

/* n points on r = 0.8 (1 + 0.12 sin(5 theta) cos(3 phi)), Fibonacci spiral order (neighbours in
 * memory are neighbours in space, as in a mesh); their bounding box in lo, hi. */
static double *receiver(int n, double lo[3], double hi[3])
{
    double *p = xmalloc(sizeof(double) * 3 * (size_t)n);
    const double golden = M_PI * (3.0 - sqrt(5.0));
    for (int a = 0; a < 3; ++a) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n, s = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
        const double theta = acos(z), r = 0.8 * (1.0 + 0.12 * sin(5.0 * theta) * cos(3.0 * phi));
        const double x[3] = {r * s * cos(phi), r * s * sin(phi), r * z};
        for (int a = 0; a < 3; ++a) {
            p[3 * i + a] = x[a];
            lo[a] = fmin(lo[a], x[a]);
            hi[a] = fmax(hi[a], x[a]);
        }
    }
    return p;
}

/* Light i, the same in every set (the set of L lights is the first L): at distance 1.8-3.0 from
 * the origin in a random direction u; a sphere (radius 0.1-0.25, centre at that distance plus
 * the radius) when i = 3 mod 8, else a quad (i even) or triangle (i odd) of circumradius 0.25-0.6
 * in the plane through R u perpendicular to u, one-sided, facing the origin.  rgb in [0.5, 1.5] / nl.
 * Returns 1 if the light lies outside the box [lo, hi] (polygon: every box corner strictly in
 * front of its plane; sphere: box farther from its centre than its radius). */
static int add_light(shl_lights *set, int i, int nl, const double lo[3], const double hi[3], int *is_sphere)
{
    const uint64_t s = (uint64_t)i + 1;
    const double z = 2.0 * u01(s, 0) - 1.0, phi = 2.0 * M_PI * u01(s, 1), rxy = sqrt(1.0 - z * z);
    const double u[3] = {rxy * cos(phi), rxy * sin(phi), z}, R = 1.8 + 1.2 * u01(s, 2);
    double rgb[3];
    for (int c = 0; c < 3; ++c) rgb[c] = (0.5 + u01(s, 3 + (uint64_t)c)) / nl;
    *is_sphere = i % 8 == 3;
    if (*is_sphere) {
        const double rad = 0.1 + 0.15 * u01(s, 6), c[3] = {(R + rad) * u[0], (R + rad) * u[1], (R + rad) * u[2]};
        must(shl_lights_add_sphere(set, c, rad, rgb), "add sphere");
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) {
            const double d = fmax(0.0, fmax(lo[a] - c[a], c[a] - hi[a]));
            d2 += d * d;
        }
        return d2 > rad * rad;
    }
    /* tangent basis t, b with t x b = u; vertices clockwise about u, so the Newell normal is -u */
    double t[3] = {-u[1], u[0], 0.0};
    if (fabs(u[2]) > 0.9) {
        t[0] = 0.0;
        t[1] = -u[2];
        t[2] = u[1];
    }
    const double tn = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int a = 0; a < 3; ++a) t[a] /= tn;
    const double b[3] = {u[1] * t[2] - u[2] * t[1], u[2] * t[0] - u[0] * t[2], u[0] * t[1] - u[1] * t[0]};
    const int n = i % 2 ? 3 : 4;
    const double size = 0.25 + 0.35 * u01(s, 7), rot = 2.0 * M_PI * u01(s, 8);
    double v[12];
    for (int k = 0; k < n; ++k) {
        const double ang = rot - 2.0 * M_PI * k / n;
        for (int a = 0; a < 3; ++a) v[3 * k + a] = R * u[a] + size * (cos(ang) * t[a] + sin(ang) * b[a]);
    }
    must(shl_lights_add_polygon(set, v, n, rgb, 0), "add polygon");
    for (int k = 0; k < 8; ++k) { /* the plane is {x : u . x = R}; the box must lie in u . x < R */
        double d = 0.0;
        for (int a = 0; a < 3; ++a) d += u[a] * ((k >> a & 1) ? hi[a] : lo[a]);
        if (!(d < R)) return 0;
    }
    return 1;
}

/* ---- paths and timing ----------------------------------------------------------- */

enum { P_DOUBLE, P_FLOAT, P_GRID };
typedef struct {
    const char *name;
    int kind, res, interp;
} path_def;

static const path_def paths[NPATH] = {
    {"per-vertex double", P_DOUBLE, 0, 0},
    {"per-vertex float SIMD", P_FLOAT, 0, 0},
    {"grid 8^3 Hermite", P_GRID, 8, SHL_INTERP_HERMITE},
    {"grid 8^3 trilinear", P_GRID, 8, SHL_INTERP_TRILINEAR},
    {"grid 8^3 Taylor", P_GRID, 8, SHL_INTERP_TAYLOR},
    {"grid 16^3 Hermite", P_GRID, 16, SHL_INTERP_HERMITE},
    {"grid 16^3 trilinear", P_GRID, 16, SHL_INTERP_TRILINEAR},
    {"grid 16^3 Taylor", P_GRID, 16, SHL_INTERP_TAYLOR},
};
static const char *short_name[NPATH] = {"double", "float SIMD", "8^3 Hermite", "8^3 trilinear", "8^3 Taylor",
                                        "16^3 Hermite", "16^3 trilinear", "16^3 Taylor"};

typedef struct {
    const shl_ctx *ctx;
    const shl_lights *set;
    shl_grid *grid;
    int kind, interp, nthreads, n;
    const double *pts;
    const float *ptsf;
    double *out;
    float *outf;
    int failed;
} job;

static void per_vertex_range(void *arg, int worker, long begin, long end)
{
    job *j = arg;
    const size_t nc3 = 3 * (size_t)SHL_NCOEFFS(shl_ctx_lmax(j->ctx));
    const int m = (int)(end - begin);
    int st;
    (void)worker;
    if (j->kind == P_DOUBLE)
        st = shl_lights_eval_batch(j->ctx, j->set, m, j->pts + 3 * begin, j->out + nc3 * (size_t)begin, NULL);
    else
        st = shl_lights_eval_batch_f(j->ctx, j->set, m, j->ptsf + 3 * begin, j->outf + nc3 * (size_t)begin, NULL);
    if (st != SHL_OK) j->failed = st;
}

/* One frame of the path (grids: kind P_GRID fills, kind -1 interpolates). */
static void run_once(job *j)
{
    if (j->kind == P_GRID) must(shl_grid_fill(j->grid, j->set, j->nthreads), "grid fill");
    else if (j->kind < 0) must(shl_grid_interp(j->grid, j->interp, 2.0, j->n, j->pts, j->out, j->nthreads), "interp");
    else if (j->nthreads == 1) per_vertex_range(j, 0, 0, j->n);
    else par_for(j->n, (j->n + 8L * j->nthreads - 1) / (8L * j->nthreads), j->nthreads, per_vertex_range, j);
    if (j->failed) must(j->failed, "per-vertex evaluation");
}

static double budget = 0.3; /* seconds of repetitions per measurement */
static int use_cpu;         /* --cpu: process CPU time instead of wall time */

/* Process CPU time in seconds (all threads). */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double clock_now(void) { return use_cpu ? cpu_now() : bench_now(); }
static double tol = 1e-2;   /* the "fastest within tolerance" column: max error at most tol */

/* Best of up to MAXREPS runs, stopping once `budget` seconds are spent (one run if it takes longer);
 * warm: one untimed run first (first touch of the output pages, caches). */
static double time_best(job *j, int warm)
{
    double best = INFINITY, spent = 0.0;
    if (warm) run_once(j);
    for (int r = 0; r < MAXREPS && spent < budget; ++r) {
        const double t0 = clock_now();
        run_once(j);
        const double dt = clock_now() - t0;
        best = fmin(best, dt);
        spent += dt;
    }
    return best;
}

/* Per vertex |c - ref| / |ref| over its m = 3 nc values (one of c, cf non-NULL): max and mean. */
static void rel_error(int n, int m, const double *ref, const double *c, const float *cf, double *emax, double *emean)
{
    double mx = 0.0, sum = 0.0;
    for (int p = 0; p < n; ++p) {
        double num = 0.0, den = 0.0;
        for (size_t k = (size_t)p * m; k < (size_t)(p + 1) * m; ++k) {
            const double d = (c ? c[k] : (double)cf[k]) - ref[k];
            num += d * d;
            den += ref[k] * ref[k];
        }
        const double e = sqrt(num / den);
        mx = fmax(mx, e);
        sum += e;
    }
    *emax = mx;
    *emean = sum / n;
}

typedef struct {
    double fill, interp, frame, emax, emean; /* seconds; fill only for grids */
} result;

/* ---- report ---------------------------------------------------------------------------- */

static void fmt_err(char *buf, size_t len, const result *r) { snprintf(buf, len, "%.1e / %.1e", r->emax, r->emean); }

/* Smallest count index from which (through the last) path p's time is below the float SIMD
 * path's; static: interp only.  -1: never. */
static int crossover(result res[][NPATH], int nlc, int p, int stat)
{
    int from = -1;
    for (int i = nlc - 1; i >= 0; --i) {
        const double t = stat ? res[i][p].interp : res[i][p].frame;
        if (t < res[i][P_FLOAT].frame) from = i;
        else break;
    }
    return from;
}

static void report(int lmax, int n, int nthreads, int nlc, const int *counts, result res[][NPATH])
{
    const int nc = SHL_NCOEFFS(lmax);
    printf("\n## lmax %d (%d coefficients x 3 colours), %d vertices, %d thread%s\n\n", lmax, nc, n, nthreads,
           nthreads > 1 ? "s" : "");
    printf("Time per frame in ms, ns per vertex in parentheses.  Grid: fill + interpolation (lights move every frame).\n"
           "Fastest: by time alone, then among the paths whose max error (next table) is at most %.0e (-e).\n\n", tol);
    printf("| lights |");
    for (int p = 0; p < NPATH; ++p) printf(" %s |", short_name[p]);
    printf(" fastest | fastest at max error <= %.0e |\n|---|", tol);
    for (int p = 0; p < NPATH; ++p) printf("---|");
    printf("---|---|\n");
    for (int i = 0; i < nlc; ++i) {
        int best = 0, good = 0;
        printf("| %d |", counts[i]);
        for (int p = 0; p < NPATH; ++p) {
            printf(" %.2f (%.0f) |", res[i][p].frame * 1e3, res[i][p].frame / n * 1e9);
            if (res[i][p].frame < res[i][best].frame) best = p;
            if (res[i][p].emax <= tol && res[i][p].frame < res[i][good].frame) good = p;
        }
        for (int k = 0; k < 2; ++k) {
            const int b = k ? good : best;
            if (b == P_FLOAT) printf(" float SIMD |");
            else printf(" %s, %.2fx float SIMD's speed |", short_name[b], res[i][P_FLOAT].frame / res[i][b].frame);
        }
        printf("\n");
    }
    printf("\nError vs per-vertex double, max / mean over vertices of |c - c_ref| / |c_ref| (per vertex, over its\n"
           "3 x %d RGB coefficients).\n\n",
           nc);
    printf("| lights |");
    for (int p = 1; p < NPATH; ++p) printf(" %s |", short_name[p]);
    printf("\n|---|");
    for (int p = 1; p < NPATH; ++p) printf("---|");
    printf("\n");
    for (int i = 0; i < nlc; ++i) {
        printf("| %d |", counts[i]);
        for (int p = 1; p < NPATH; ++p) {
            char e[48];
            fmt_err(e, sizeof e, &res[i][p]);
            printf(" %s |", e);
        }
        printf("\n");
    }
    printf("\nStatic lights (grid filled once): interpolation alone, ms per frame (ns per vertex), best over the\n"
           "light counts (it does not depend on them), and fill time per light.\n\n"
           "| grid | interp ms (ns/vertex) | fill ms per light (at %d lights) |\n|---|---|---|\n", counts[nlc - 1]);
    for (int p = 2; p < NPATH; ++p) {
        double ti = INFINITY;
        for (int i = 0; i < nlc; ++i) ti = fmin(ti, res[i][p].interp);
        printf("| %s | %.2f (%.0f) | %.3f |\n", short_name[p], ti * 1e3, ti / n * 1e9,
               res[nlc - 1][p].fill / counts[nlc - 1] * 1e3);
    }
    int fd = 0;
    for (int i = 0; i < nlc; ++i) fd += res[i][P_DOUBLE].frame < res[i][P_FLOAT].frame;
    printf("\nCrossover against per-vertex float SIMD, the fastest per-vertex path (per-vertex double was slower\n"
           "at %s): the smallest light count from which the grid is faster at every larger count\n"
           "measured, with both errors (max / mean) there.\n\n",
           fd ? "some light counts only -- see the time table" : "every light count");
    for (int p = 2; p < NPATH; ++p) {
        const int c = crossover(res, nlc, p, 0), cs = crossover(res, nlc, p, 1);
        char eg[48], ef[48];
        printf("- %s, lights moving (fill + interp): ", paths[p].name);
        if (c < 0) {
            printf("never faster up to %d lights (at %d: %.2f ms vs %.2f ms)", counts[nlc - 1], counts[nlc - 1],
                   res[nlc - 1][p].frame * 1e3, res[nlc - 1][P_FLOAT].frame * 1e3);
        } else {
            fmt_err(eg, sizeof eg, &res[c][p]);
            fmt_err(ef, sizeof ef, &res[c][P_FLOAT]);
            printf("faster from %d light%s on (at %d: %.2f ms, error %s; float SIMD %.2f ms, error %s)", counts[c],
                   counts[c] > 1 ? "s" : "", counts[c], res[c][p].frame * 1e3, eg, res[c][P_FLOAT].frame * 1e3, ef);
        }
        printf("; static lights (interp only): ");
        if (cs < 0) printf("never faster up to %d lights.\n", counts[nlc - 1]);
        else printf("faster from %d light%s on.\n", counts[cs], counts[cs] > 1 ? "s" : "");
    }
}

static int make_dirs(const char *file)
{
    char d[1024];
    snprintf(d, sizeof d, "%s", file);
    for (char *s = d + 1; *s; ++s)
        if (*s == '/') {
            *s = '\0';
            mkdir(d, 0777);
            *s = '/';
        }
    return 0;
}

int main(int argc, char **argv)
{
    int n = 36000, maxl = 256, nthreads = 1, quick = 0, lmaxs[8] = {4, 8}, nlmax = 2;
    const char *csv_path = "build/bench/bench_paths.csv";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--quick")) {
            quick = 1;
        } else if (!strcmp(a, "--cpu")) {
            use_cpu = 1;
        } else if (v && !strcmp(a, "-n")) {
            n = atoi(v);
            ++i;
        } else if (v && !strcmp(a, "-L")) {
            maxl = atoi(v);
            ++i;
        } else if (v && !strcmp(a, "-t")) {
            nthreads = atoi(v);
            ++i;
        } else if (v && !strcmp(a, "-e")) {
            tol = atof(v);
            ++i;
        } else if (v && !strcmp(a, "-o")) {
            csv_path = v;
            ++i;
        } else if (v && !strcmp(a, "-l")) {
            nlmax = 0;
            for (const char *s = v; *s && nlmax < 8; ++s) {
                lmaxs[nlmax++] = atoi(s);
                while (s[1] && *s != ',') ++s;
            }
            ++i;
        } else {
            fprintf(stderr, "bench_paths: unknown or incomplete option '%s'\n\n%s", a, usage);
            return 2;
        }
    }
    if (quick) {
        n = 8192;
        if (maxl > 64) maxl = 64;
        budget = 0.05;
    }
    if (n < 1 || maxl < 1 || nthreads < 1 || nthreads > SHL_MAX_THREADS) {
        fprintf(stderr, "bench_paths: need -n >= 1, -L >= 1, 1 <= -t <= %d\n", SHL_MAX_THREADS);
        return 2;
    }
    for (int k = 0; k < nlmax; ++k)
        if (lmaxs[k] < 0 || lmaxs[k] > SHL_LMAX_MAX) {
            fprintf(stderr, "bench_paths: lmax %d outside 0..%d\n", lmaxs[k], SHL_LMAX_MAX);
            return 2;
        }
    int counts[MAXL], nlc = 0;
    for (int c = 1; c <= maxl && nlc < MAXL; c *= 2) counts[nlc++] = c;

    make_dirs(csv_path);
    FILE *csv = fopen(csv_path, "w");
    if (!csv) fprintf(stderr, "bench_paths: cannot write %s (no CSV)\n", csv_path);
    else
        fprintf(csv, "lmax,lights,polygons,spheres,threads,vertices,path,grid_res,fill_s,interp_s,frame_s,ns_per_vertex,"
                     "max_rel_err,mean_rel_err\n");

    const double t_start = bench_now(), c_start = cpu_now();
    double lo[3], hi[3];
    double *pts = receiver(n, lo, hi);
    float *ptsf = xmalloc(sizeof(float) * 3 * (size_t)n);
    for (size_t k = 0; k < 3 * (size_t)n; ++k) ptsf[k] = (float)pts[k];
    shl_ctx *probe;
    must(shl_ctx_create(0, &probe), "context");
    char load[64] = "unknown";
    FILE *la = fopen("/proc/loadavg", "r");
    if (la) {
        if (!fgets(load, sizeof load, la)) snprintf(load, sizeof load, "unknown");
        load[strcspn(load, "\n")] = '\0';
        fclose(la);
    }
    printf("# shlight %s bench_paths: the fastest lighting path by light count and lmax\n\n", SHL_VERSION_STRING);
    bench_print_machine(stdout);
    printf("Batch ISA (shl_ctx_isa): %s.  Threads: %d for every path (the per-vertex calls%s,\n"
           "shl_grid_fill and shl_grid_interp alike).  Load average at start: %s.\n",
           shl_ctx_isa(probe), nthreads, nthreads > 1 ? " split in chunks" : " on the calling thread", load);
    shl_ctx_destroy(probe);
    printf("Command: ");
    for (int i = 0; i < argc; ++i) printf("%s%s", i ? " " : "", argv[i]);
    printf("\n\n"
           "Receiver: %d points on the bumped sphere r = 0.8 (1 + 0.12 sin 5theta cos 3phi), in Fibonacci\n"
           "spiral order; bounding box [%.3f, %.3f] x [%.3f, %.3f] x [%.3f, %.3f].\n"
           "Lights: light i (the same in every set; a set of L lights is the first L) lies 1.8-3.0 from the centre\n"
           "in a random direction: a sphere (radius 0.1-0.25) when i = 3 mod 8, else a one-sided quad (i even) or\n"
           "triangle (i odd) of circumradius 0.25-0.6 facing the receiver; radiance 0.5-1.5 per channel / L.\n"
           "Every light is outside the grid box (checked below).  A light inside or touching the box breaks the\n"
           "grid (its field there varies faster than the node spacing resolves: 13-24%% errors were measured\n"
           "near one), so the grid is an option only when its box is free of lights.\n"
           "Grid: res^3 float nodes (coefficients + gradients) over the receivers' bounding box; Taylor: b = 2.\n"
           "Times: %s.  Best of up to %d runs within %.2f s\n"
           "(one run when a run takes longer), after an untimed run at 1 light.\n",
           n, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2],
           use_cpu ? "process CPU time (--cpu: summed over threads)" : "wall time", MAXREPS, budget);

    const int nsteps = nlmax * nlc;
    int step = 0;
    for (int li = 0; li < nlmax; ++li) {
        const int lmax = lmaxs[li], nc3 = 3 * SHL_NCOEFFS(lmax);
        shl_ctx *ctx;
        must(shl_ctx_create(lmax, &ctx), "context");
        double *ref = xmalloc(sizeof(double) * (size_t)nc3 * (size_t)n), *out = xmalloc(sizeof(double) * (size_t)nc3 * (size_t)n);
        float *outf = xmalloc(sizeof(float) * (size_t)nc3 * (size_t)n);
        shl_grid *grid[2];
        const int gres[2] = {8, 16};
        for (int g = 0; g < 2; ++g) {
            const int r3[3] = {gres[g], gres[g], gres[g]};
            must(shl_grid_create(ctx, lo, hi, r3, SHL_GRID_FLOAT, &grid[g]), "grid create");
        }
        result (*res)[NPATH] = xmalloc(sizeof *res * (size_t)nlc);
        int outside = 1;
        for (int ci = 0; ci < nlc; ++ci) {
            const int nl = counts[ci];
            shl_lights *set;
            int nsph = 0;
            must(shl_lights_create(&set), "light set");
            for (int i = 0; i < nl; ++i) {
                int sph;
                outside &= add_light(set, i, nl, lo, hi, &sph);
                nsph += sph;
            }
            job j = {ctx, set, NULL, P_DOUBLE, 0, nthreads, n, pts, ptsf, ref, outf, 0};
            res[ci][P_DOUBLE] = (result){0, 0, time_best(&j, ci == 0), 0, 0};
            j.kind = P_FLOAT;
            res[ci][P_FLOAT] = (result){0, 0, time_best(&j, ci == 0), 0, 0};
            rel_error(n, nc3, ref, NULL, outf, &res[ci][P_FLOAT].emax, &res[ci][P_FLOAT].emean);
            for (int p = 2; p < NPATH; ++p) {
                result *r = &res[ci][p];
                j.grid = grid[paths[p].res == 8 ? 0 : 1];
                j.out = out;
                if (paths[p].interp == SHL_INTERP_HERMITE) { /* the first of each grid: fill for this set */
                    j.kind = P_GRID;
                    r->fill = time_best(&j, ci == 0);
                } else {
                    r->fill = res[ci][p - (paths[p].interp == SHL_INTERP_TRILINEAR ? 1 : 2)].fill;
                }
                j.kind = -1;
                j.interp = paths[p].interp;
                r->interp = time_best(&j, ci == 0);
                r->frame = r->fill + r->interp;
                rel_error(n, nc3, ref, out, NULL, &r->emax, &r->emean);
            }
            if (csv)
                for (int p = 0; p < NPATH; ++p) {
                    const result *r = &res[ci][p];
                    fprintf(csv, "%d,%d,%d,%d,%d,%d,%s,%d,%.6e,%.6e,%.6e,%.1f,%.3e,%.3e\n", lmax, nl, nl - nsph, nsph,
                            nthreads, n, paths[p].name, paths[p].res, r->fill, r->interp, r->frame, r->frame / n * 1e9,
                            r->emax, r->emean);
                }
            shl_lights_destroy(set);
            fprintf(stderr, "bench_paths: lmax %d, %d lights done (%d/%d), %.0f s elapsed\n", lmax, nl, ++step, nsteps,
                    bench_now() - t_start);
        }
        printf("\nLights outside the grid box at every count (lmax %d): %s.\n", lmax,
               outside ? "yes" : "NO -- grid errors below are not representative");
        report(lmax, n, nthreads, nlc, counts, res);
        fflush(stdout);
        free(res);
        for (int g = 0; g < 2; ++g) shl_grid_destroy(grid[g]);
        free(ref);
        free(out);
        free(outf);
        shl_ctx_destroy(ctx);
    }
    const double wall = bench_now() - t_start, cpu = cpu_now() - c_start;
    printf("\n(total %.0f s wall, %.0f s CPU: %.0f%% of %d core%s while running%s%s)\n", wall, cpu,
           100.0 * cpu / (wall * nthreads), nthreads, nthreads > 1 ? "s" : "", csv ? "; CSV: " : "", csv ? csv_path : "");
    if (csv) fclose(csv);
    free(pts);
    free(ptsf);
    return 0;
}
