/* Grid interpolation benchmark (shl_grid_interp, float storage), one core unless stated:
 *  - vertices per second for trilinear, Taylor (Annen 2004) and Hermite (Wu 2020 Alg. 4)
 *    at lmax 4 and 8, from an L2-resident grid (4^3 nodes) and from a grid far larger
 *    than the last-level cache (4 x the L3 size sysconf reports, at least 120 MB; random
 *    vertex order: every corner misses);
 *  - the context's SIMD kernel (simd/interp_batch.h) against the scalar reference
 *    (SHLIGHT_ISA=scalar: src/interp_kernel.h), as a ratio within each round;
 *  - grid bytes read per vertex and the achieved share of this core's read bandwidth,
 *    measured in the same run (STREAM-like read and triad kernels; the reference is the faster
 *    of the read from ordinary memory and from huge pages, where the large grids live): from DRAM for the
 *    out-of-cache grid, from an L2-resident array of the L2 grid's size for the L2 grid;
 *  - before/after of the look-ahead (src/interp.c: the next vertex's corner rows are
 *    requested during the current vertex's arithmetic) in the same run: calls of one
 *    vertex have no next vertex, so they run the previous order (one vertex's rows at a
 *    time, on demand);
 *  - the access pattern's ceiling: the Hermite lmax 8 kernel from DRAM against a read-only sum
 *    of the same vertices' corner rows (same layout, same look-ahead requests, no arithmetic),
 *    and the same read on demand loads only, alternated in the same rounds;
 *  - per-vertex set-up cost: lmax 0 (3 coefficients, shorter than a vector: both
 *    variants run the reference) is the cell search and weights plus 8 tiny loads,
 *    the part vectorizing across coefficients does not touch; 2 threads against 1 for
 *    shl_grid_interp and shl_grid_interp_f (CSV sections threads, threads_float_out),
 *    with the CPU efficiency (process CPU time, 1 thread / 2 threads) and, from DRAM, the share
 *    of the read bandwidth of both cores together (the memory-bound ceiling);
 *  - float output: shl_grid_interp_f (float vertices, float sums, float output) against
 *    shl_grid_interp, Hermite at lmax 4 and 8, L2 and DRAM, alternated in the same rounds
 *    (CSV section float_out: ns_simd is the float call's, ns_reference the double call's);
 *  - the papers' implied GPU throughput (Wang 2018, Wu 2020 Table 1) next to ours.
 * CSV: build/bench/bench_interp.csv (-o overrides); --help; --mb caps the out-of-cache size. */
#if defined(__linux__) && !defined(_DEFAULT_SOURCE)
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE: the huge-page read bandwidth (informational) */
#endif
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

enum { CHUNK = 128, NPTS = 1 << 16, MAX_ROUNDS = 11 };

static int rounds = MAX_ROUNDS; /* --quick: 3 */

/* Clock of the one-core timings: wall clock, or (--cpu-time) this thread's CPU time, which
 * leaves out the time other processes hold the core (memory stalls still count). */
static double thread_cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
static double (*one_core_now)(void) = bench_now;

/* CPU time of the whole process (all threads), seconds. */
static double process_cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
static size_t max_bytes; /* --mb: a cap on out_of_cache_bytes (0: none) */

/* Bytes that cannot stay in any cache: 4 x the last-level cache, at least 120 MB
 * (32 MB assumed where sysconf does not know the L3); at most --mb. */
static size_t out_of_cache_bytes(void)
{
    if (max_bytes) return max_bytes;
    const long l3 = sysconf(_SC_LEVEL3_CACHE_SIZE);
    const size_t llc = l3 > 0 ? (size_t)l3 : (size_t)32 << 20;
    return 4 * llc > ((size_t)120 << 20) ? 4 * llc : (size_t)120 << 20;
}

/* Nodes per axis of the out-of-cache grid at lmax (float storage). */
static int out_of_cache_res(int lmax)
{
    int bytes;
    shl_grid_bytes_per_node(lmax, SHL_GRID_FLOAT, &bytes);
    return (int)ceil(cbrt((double)out_of_cache_bytes() / bytes));
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n);
    if (!p) {
        fprintf(stderr, "bench_interp: out of memory (%zu bytes)\n", n);
        exit(1);
    }
    return p;
}

/* n bytes, 2 MiB-aligned and advised as huge pages where the kernel has the advice (as the
 * library's grid nodes of >= 4 MiB, src/alloc.c); *advised: 1 if the advice was taken. */
static void *huge_malloc(size_t n, int *advised)
{
    const size_t page = (size_t)2 << 20, padded = (n + page - 1) / page * page;
    void *p = aligned_alloc(page, padded);
    if (!p) {
        fprintf(stderr, "bench_interp: out of memory (%zu bytes)\n", padded);
        exit(1);
    }
    *advised = 0;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    *advised = madvise(p, padded, MADV_HUGEPAGE) == 0;
#endif
    return p;
}

/* This process's anonymous memory in transparent huge pages, MB (Linux; -1 elsewhere). */
static double anon_huge_mb(void)
{
    FILE *f = fopen("/proc/self/smaps_rollup", "r");
    if (!f) return -1.0;
    char line[256];
    double kb = -1.0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "AnonHugePages: %lf kB", &kb) == 1) break;
    fclose(f);
    return kb < 0 ? -1.0 : kb / 1024.0;
}

/* ---- memory bandwidth of this core: read (sum) and triad a = b + s c ---- */
static size_t bw_doubles; /* out_of_cache_bytes() / 8, at least 256 MB: far beyond the caches */

/* Bytes per second reading a[0 .. n) reps times (n a multiple of 8). */
static double read_bw(const double *a, size_t n, int reps)
{
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0;
    const double t0 = one_core_now();
    for (int r = 0; r < reps; ++r)
        for (size_t i = 0; i < n; i += 8) {
            s0 += a[i];
            s1 += a[i + 1];
            s2 += a[i + 2];
            s3 += a[i + 3];
            s4 += a[i + 4];
            s5 += a[i + 5];
            s6 += a[i + 6];
            s7 += a[i + 7];
        }
    const double t = one_core_now() - t0;
    bench_sink += s0 + s1 + s2 + s3 + s4 + s5 + s6 + s7;
    return (double)reps * n * sizeof(double) / t;
}

/* ---- read bandwidth of both cores together: the ceiling of a read-bound loop on 2 threads ---- */
typedef struct {
    const double *a;
    size_t n; /* a multiple of 8 */
    double sum;
} read_part;

static void *sum_part(void *arg)
{
    read_part *p = arg;
    double s[8] = {0};
    for (size_t i = 0; i < p->n; i += 8)
        for (int k = 0; k < 8; ++k) s[k] += p->a[i + k];
    p->sum = ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
    return NULL;
}

/* Bytes per second of two threads reading a[0 .. n) together, one half each (n a multiple of
 * 16), by the wall clock from the thread's creation to its join (~50 us against ~10 ms). */
static double read_bw_two_cores(const double *a, size_t n)
{
    read_part half[2] = {{a, n / 2, 0.0}, {a + n / 2, n / 2, 0.0}};
    pthread_t t;
    const double t0 = bench_now();
    if (pthread_create(&t, NULL, sum_part, &half[1])) return 0.0;
    sum_part(&half[0]);
    pthread_join(t, NULL);
    const double dt = bench_now() - t0;
    bench_sink += half[0].sum + half[1].sum;
    return (double)n * sizeof(double) / dt;
}

static double triad_bw(double *a, const double *b, const double *c, size_t n)
{
    const double s = 1.0000001, t0 = one_core_now();
    for (size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    const double t = one_core_now() - t0;
    bench_sink += a[n / 2];
    return 3.0 * n * sizeof(double) / t; /* STREAM convention: 24 bytes per element */
}

/* ---- grids ---- */
static void must(int st, const char *what)
{
    if (st != SHL_OK) {
        fprintf(stderr, "bench_interp: %s: %s\n", what, shl_strerror(st));
        exit(1);
    }
}

/* Grid of res^3 nodes over [0, 1]^3 with pseudo-random node data (every page written). */
static shl_grid *make_grid(const shl_ctx *ctx, int res)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    const int r3[3] = {res, res, res}, nc = SHL_NCOEFFS(shl_ctx_lmax(ctx));
    shl_grid *g;
    must(shl_grid_create(ctx, lo, hi, r3, SHL_GRID_FLOAT, &g), "grid_create");
    double *rgb = xmalloc(sizeof(double) * 12 * nc), *grad = rgb + 3 * nc;
    uint64_t s = 12345;
    for (int k = 0; k < res; ++k)
        for (int j = 0; j < res; ++j)
            for (int i = 0; i < res; ++i) {
                for (int q = 0; q < 12 * nc; ++q) {
                    s = s * 6364136223846793005ull + 1442695040888963407ull;
                    rgb[q] = (double)(s >> 11) * 0x1p-53 - 0.5;
                }
                const int idx[3] = {i, j, k};
                must(shl_grid_set_node(g, idx, rgb, grad), "set_node");
            }
    free(rgb);
    return g;
}

typedef struct {
    const shl_grid *g;
    int method, nthreads;
    long chunk;          /* vertices per shl_grid_interp call */
    long npts;           /* vertices per timed call: chunks over pts[0 .. npts) */
    const double *pts;
    double *out;         /* chunk * 3 nc doubles, reused: stays in cache */
    int wall;            /* timed by the wall clock even with --cpu-time (thread comparisons) */
} job;

/* shl_grid_interp_f on job j's grid, method, chunks and vertices as floats (ptsf, outf): seconds per vertex. */
static double run_f(const job *j, const float *ptsf, float *outf)
{
    double (*now)(void) = j->wall ? bench_now : one_core_now;
    const double t0 = now();
    for (long p = 0; p < j->npts; p += j->chunk)
        must(shl_grid_interp_f(j->g, j->method, 2.0, (int)j->chunk, ptsf + 3 * p, outf, j->nthreads), "interp_f");
    const double t = now() - t0;
    bench_sink += outf[1];
    return t / (double)j->npts;
}

static double run(const job *j) /* seconds per vertex */
{
    double (*now)(void) = j->wall ? bench_now : one_core_now;
    const double t0 = now();
    for (long p = 0; p < j->npts; p += j->chunk)
        must(shl_grid_interp(j->g, j->method, 2.0, (int)j->chunk, j->pts + 3 * p, j->out, j->nthreads), "interp");
    const double t = now() - t0;
    bench_sink += j->out[1];
    return t / (double)j->npts;
}

/* Bytes of grid data one vertex reads: 8 corners x (values 3 nc, trilinear; values and
 * 9 nc gradients, Taylor and Hermite) x 4 bytes. */
static double bytes_per_vertex(int method, int nc)
{
    return 8.0 * (method == SHL_INTERP_TRILINEAR ? 3 : 12) * nc * sizeof(float);
}

static FILE *csv;

/* Vertices sorted by the cell they fall in (cells numbered x fastest) on a res^3 grid over [0, 1]^3. */
typedef struct {
    long cell;
    double p[3];
} keyed_point;

static int by_cell(const void *a, const void *b)
{
    const long x = ((const keyed_point *)a)->cell, y = ((const keyed_point *)b)->cell;
    return (x > y) - (x < y);
}

static double *sorted_by_cell(const double *pts, long n, int res)
{
    keyed_point *k = xmalloc(sizeof *k * n);
    for (long i = 0; i < n; ++i) {
        long cell = 0;
        for (int a = 2; a >= 0; --a) {
            const int c = (int)(pts[3 * i + a] * (res - 1));
            cell = cell * (res - 1) + (c < res - 2 ? c : res - 2);
            k[i].p[a] = pts[3 * i + a];
        }
        k[i].cell = cell;
    }
    qsort(k, n, sizeof *k, by_cell);
    double *out = xmalloc(sizeof(double) * 3 * n);
    for (long i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) out[3 * i + a] = k[i].p[a];
    free(k);
    return out;
}

/* The Hermite kernel's access pattern without its arithmetic: per vertex, the 4 ranges of two
 * adjacent nodes (corners 2q, 2q + 1; node_floats floats each) of its cell on a res^3 float array
 * laid out as the library's grids (x fastest), one float of every 64 bytes and the range's last
 * one added (each load brings its whole line; one add per line, in 16 independent sums).  ahead: the next vertex's
 * lines requested as src/interp.c and simd/kernel_api.h do (into L2, one step of lines per row
 * with each block read); 0: demand loads only.  Seconds per vertex. */
/* The 4 ranges (corners 2q, 2q + 1) of point p's cell on pattern_read's array. */
static void corner_ranges(const float *nodes, size_t node_floats, int res, const double *p, const float *range[4])
{
    size_t c[3];
    for (int a = 0; a < 3; ++a) {
        const int i = (int)(p[a] * (res - 1));
        c[a] = (size_t)(i < res - 2 ? i : res - 2);
    }
    for (int q = 0; q < 4; ++q)
        range[q] = nodes + (c[0] + (size_t)res * ((c[1] + (q & 1)) + (size_t)res * (c[2] + (q >> 1)))) * node_floats;
}

static double pattern_read(const float *nodes, size_t node_floats, int res, const double *pts, long n, int ahead)
{
    enum { LINE_FLOATS = 16 };
    const size_t range = 2 * node_floats, lines = (range * sizeof(float) + 63) / 64 + 1;
    const size_t reads = 4 * (range / LINE_FLOATS); /* lines read per vertex (last ones aside) */
    float acc[LINE_FLOATS] = {0};
    const float *row[4], *next[4];
    const double t0 = one_core_now();
    if (n > 0) corner_ranges(nodes, node_floats, res, pts, row);
    for (long v = 0; v < n; ++v) {
        if (v + 1 < n) corner_ranges(nodes, node_floats, res, pts + 3 * (v + 1), next);
        size_t done = 0, read = 0;
        for (int q = 0; q < 4; ++q)
            for (size_t i = 0; i + LINE_FLOATS <= range; i += LINE_FLOATS) {
                /* the next vertex's lines spread evenly over this one's reads, one line of each
                 * range at a time (for this read the fastest schedule tried: bench/RESULTS.md) */
                const size_t due = ++read * lines / reads;
                for (; ahead && v + 1 < n && done < due; ++done) {
                    const size_t o = 64 * done < range * sizeof(float) ? 64 * done : range * sizeof(float) - 1;
                    for (int r = 0; r < 4; ++r) __builtin_prefetch((const char *)next[r] + o, 0, 2);
                }
                acc[read % LINE_FLOATS] += row[q][i];
            }
        for (int q = 0; q < 4; ++q) {
            acc[q] += row[q][range - 1]; /* the line of the range's end */
            if (v + 1 < n) row[q] = next[q];
        }
    }
    const double t = one_core_now() - t0;
    for (int k = 0; k < LINE_FLOATS; ++k) bench_sink += acc[k];
    return t / (double)n;
}

/* Polygon batch (shl_polygon_batch_f) at lmax 8 on 256 points per call: seconds per point. */
static double polygon_batch_time(int n, int with_grad, const double *pts)
{
    enum { NP = 256 };
    shl_ctx *ctx;
    must(shl_ctx_create(8, &ctx), "ctx");
    float v[12], p[3 * NP];
    static float out[NP * 81], grad[3 * NP * 81];
    for (int i = 0; i < n; ++i) { /* triangle or square of radius 1 at z = 2, points in [-1, 1]^3 */
        v[3 * i] = (float)cos(2 * M_PI * i / n);
        v[3 * i + 1] = (float)sin(2 * M_PI * i / n);
        v[3 * i + 2] = 2.0f;
    }
    for (int k = 0; k < 3 * NP; ++k) p[k] = (float)(2.0 * pts[k] - 1.0);
    double t[MAX_ROUNDS];
    for (int r = 0; r <= rounds; ++r) { /* round 0: warm-up */
        const double t0 = one_core_now();
        for (int q = 0; q < 40; ++q)
            must(shl_polygon_batch_f(ctx, v, n, NP, p, out, with_grad ? grad : NULL), "polygon_batch");
        if (r) t[r - 1] = (one_core_now() - t0) / (40.0 * NP);
    }
    bench_sink += out[1];
    shl_ctx_destroy(ctx);
    return bench_median(t, rounds);
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_interp.csv", *mb_arg = NULL, *quick = NULL, *cpu_time = NULL;
    const double gb = (double)out_of_cache_bytes() / (1 << 30);
    char about[2048];
    snprintf(about, sizeof about,
             "Grid interpolation (shl_grid_interp, float storage): vertices per second for trilinear, Taylor and\n"
             "Hermite at lmax 0, 4 and 8 from an L2-resident grid and from a grid far larger than the caches\n"
             "(random vertex order), the SIMD kernel against the scalar reference, with and without the\n"
             "look-ahead (calls of one vertex: the order before it), bytes per vertex and the share of this\n"
             "core's read bandwidth (DRAM, resp. L2, measured in the same run), random vs cell-sorted vertex\n"
             "order, the Hermite kernel against a plain read of the same corner rows (its access pattern's\n"
             "ceiling), 2 threads against 1 for double and float output (from DRAM: the share of both cores' read\n"
             "bandwidth together), float output (shl_grid_interp_f) against double output for Hermite at lmax 4\n"
             "and 8, and the papers' GPU throughput next to ours.\n"
             "Memory: the out-of-cache size S is 4 x the L3 size sysconf reports, at least 120 MB; here S =\n"
             "%.2f GB.  Peak memory about 2 S: the bandwidth arrays (1.5 S, at least 384 MB), then two grids of S.\n"
             "--mb "
             "caps S (smaller S: faster, but a large L3 may then hold part of the grid).\n"
             "About 3-4 minutes on an idle 2-core machine with S = 1.5 GB (14 minutes at load average 13);\n"
             "progress on stderr.\n"
             "--quick: lmax 8 only, 3 rounds (a check that it works, not a measurement).  --cpu-time: the one-core\n"
             "timings (bandwidths too) in this thread's CPU time, which leaves out the time other processes hold\n"
             "the core: on a loaded machine; the 2-thread comparison stays wall clock.\n"
             "Writes Markdown tables to stdout and one CSV row per table row to the CSV file.",
             gb);
    const bench_opt opts[] = {{"-o", "--csv", "FILE", &csv_path, "CSV output (default build/bench/bench_interp.csv)"},
                              {"-m", "--mb", "MB", &mb_arg, "cap on the out-of-cache size S in MB (at least 16)"},
                              {"-q", "--quick", NULL, &quick, "lmax 8 only, 3 rounds (default: lmax 0, 4, 8, 11 rounds)"},
                              {"-c", "--cpu-time", NULL, &cpu_time, "one-core timings in thread CPU time (default: wall clock)"}};
    const bench_cli cli = {"bench_interp", "[-o FILE] [--mb MB] [--quick] [--cpu-time]", about, opts, 4, 0};
    bench_parse(&cli, argc, argv, NULL);
    if (quick) rounds = 3;
    if (cpu_time) one_core_now = thread_cpu_now;
    if (mb_arg) {
        char *end;
        const long mb = strtol(mb_arg, &end, 10);
        if (*end || mb < 16) {
            fprintf(stderr, "bench_interp: --mb needs a whole number of MB, at least 16 (got '%s')\n", mb_arg);
            return 2;
        }
        max_bytes = (size_t)mb << 20;
    }
    csv = bench_create(csv_path, "w");
    if (!csv) return 1;
    bench_print_machine(stdout);
    shl_ctx *probe;
    must(shl_ctx_create(0, &probe), "ctx");
    const char *isa = shl_ctx_isa(probe);
    printf("library: %s\nSIMD ISA: %s; reference: SHLIGHT_ISA=scalar (src/interp_kernel.h)\n", shl_build_info(), isa);
    printf("clock of the one-core timings: %s\n", cpu_time ? "thread CPU time (--cpu-time)" : "wall");

    /* vertices: uniform in the box, in random order (no locality between neighbours) */
    double *pts = xmalloc(sizeof(double) * 3 * NPTS);
    srand(7);
    for (int k = 0; k < 3 * NPTS; ++k) pts[k] = (double)rand() / RAND_MAX;

    bw_doubles = out_of_cache_bytes() / sizeof(double);
    if (bw_doubles < ((size_t)1 << 25)) bw_doubles = (size_t)1 << 25;
    bw_doubles &= ~(size_t)15; /* read_bw sums 8 at a time; read_bw_two_cores, two halves of 8 at a time */
    bench_progress("filling the bandwidth arrays, %.0f MB (step 1/5)...", 1.5 * sizeof(double) * (double)bw_doubles / (1 << 20));
    double *bw_a = xmalloc(sizeof(double) * bw_doubles), *bw_b = xmalloc(sizeof(double) * bw_doubles / 4),
           *bw_c = xmalloc(sizeof(double) * bw_doubles / 4);
    for (size_t i = 0; i < bw_doubles; ++i) bw_a[i] = 1.0 / (1.0 + (double)(i & 1023));
    for (size_t i = 0; i < bw_doubles / 4; ++i) bw_b[i] = bw_c[i] = bw_a[i], bw_a[i] = 0.0;
    /* L2: an array of the L2 grid's size at lmax 8 (4^3 nodes), read again and again */
    int l2_node_bytes;
    shl_grid_bytes_per_node(8, SHL_GRID_FLOAT, &l2_node_bytes);
    const size_t l2_doubles = (size_t)64 * l2_node_bytes / sizeof(double) & ~(size_t)7;
    /* The reference is the read bandwidth of ordinary memory (malloc: 4 KiB pages unless the
     * kernel's THP mode is "always"), what a streaming read gets without any help; the same
     * read from an array advised as huge pages, like the library's large grids, is shown too. */
    int hp_advised;
    double *bw_h = huge_malloc(sizeof(double) * bw_doubles, &hp_advised);
    for (size_t i = 0; i < bw_doubles; ++i) bw_h[i] = 1.0 / (1.0 + (double)(i & 1023));
    double rbw[5], tbw[5], l2bw[5], hbw[5], r2bw[5];
    bench_progress("memory bandwidth, 5 rounds (step 2/5)...");
    for (int r = 0; r < 5; ++r) {
        rbw[r] = read_bw(bw_a, bw_doubles, 1);
        r2bw[r] = read_bw_two_cores(bw_a, bw_doubles);
        hbw[r] = read_bw(bw_h, bw_doubles, 1);
        tbw[r] = triad_bw(bw_a, bw_b, bw_c, bw_doubles / 4);
        read_bw(bw_b, l2_doubles, 10); /* warm */
        l2bw[r] = read_bw(bw_b, l2_doubles, 2000);
    }
    const double ordinary_read = bench_median(rbw, 5), triad_peak = bench_median(tbw, 5), l2_peak = bench_median(l2bw, 5);
    const double huge_read = bench_median(hbw, 5), huge_mb = anon_huge_mb(), read_two = bench_median(r2bw, 5);
    const double read_peak = huge_read > ordinary_read ? huge_read : ordinary_read; /* the reference: the faster read */
    free(bw_h);
    free(bw_a); /* before the grids: the peak memory is then two grids, not the arrays as well */
    free(bw_b);
    free(bw_c);
    const double mb = sizeof(double) * (double)bw_doubles / (1 << 20);
    printf("\nLast-level cache (sysconf): %ld KB; out-of-cache size: %.0f MB\n", sysconf(_SC_LEVEL3_CACHE_SIZE) / 1024,
           (double)out_of_cache_bytes() / (1 << 20));
    printf("Memory bandwidth, one core (median of 5): read (sum of %.0f MB) %.1f GB/s from ordinary memory (malloc), %.1f GB/s\n"
           "from a 2 MiB-aligned array advised as huge pages like the library's large grids (%s; %.0f MB of this\n"
           "process in huge pages then); triad (3 x %.0f MB, 24 B/element) %.1f GB/s; L2 read (sum of %.0f KB, the L2\n"
           "grid's size at lmax 8, 2000 times) %.1f GB/s.  The read bandwidth below (\"read BW\") is the faster of\n"
           "the two reads: %.1f GB/s\n",
           mb, ordinary_read * 1e-9, huge_read * 1e-9, hp_advised ? "madvise MADV_HUGEPAGE taken" : "no huge-page advice here",
           huge_mb, mb / 4, triad_peak * 1e-9, l2_doubles * sizeof(double) / 1024.0, l2_peak * 1e-9, read_peak * 1e-9);
    printf("Read bandwidth of both cores together (2 threads, one half of the same ordinary %.0f MB each, wall clock,\n"
           "median of 5): %.1f GB/s, %.2fx one core's: the ceiling of a read-bound loop's 2-thread speed-up.\n",
           mb, read_two * 1e-9, read_two / ordinary_read);
    if (csv) {
        fprintf(csv, "section,lmax,method,grid,isa,ns_simd,ns_reference,speedup,mvertices_per_s,bytes_per_vertex,gb_per_s,of_read_bw,"
                     "ns_no_lookahead,of_read_bw_no_lookahead,cpu_efficiency\n");
        fprintf(csv, "bandwidth,,,,,,,,,,%.3f,%.3f,,,\n", ordinary_read * 1e-9, triad_peak * 1e-9);
        fprintf(csv, "bandwidth_l2,,,,,,,,,,%.3f,,,,\n", l2_peak * 1e-9);
        fprintf(csv, "bandwidth_two_cores,,,,,,,,,,%.3f,,,,\n", read_two * 1e-9);
        fprintf(csv, "bandwidth_huge_pages,,,,,,,,,,%.3f,,,,\n", huge_read * 1e-9);
    }

    const char *mname[3] = {"trilinear", "Taylor", "Hermite"};
    double hermite8[2] = {0, 0}, grid_huge_mb = -1.0; /* SIMD s/vertex, lmax 8: L2, DRAM; huge pages, lmax 8 DRAM grids */
    const int lmaxes[3] = {0, 4, 8}, lfirst = quick ? 2 : 0;
    printf("\n## Interpolation, one core: SIMD kernel (%s) vs scalar reference\n\n", isa);
    printf("Chunks of %d vertices per call (the output, %d x 3 nc doubles, stays in cache).  L2: 4^3-node grid;\n"
           "DRAM: %d^3 / %d^3 / %d^3 nodes at lmax 0 / 4 / 8 (about %.0f MB at lmax 4-8), vertices in random order.\n"
           "bytes/vertex: grid data read (8 corners); GB/s = bytes/vertex x vertices/s; of read BW: / the read bandwidth\n"
           "above (DRAM rows: DRAM read; L2 rows: L2 read).  No look-ahead: the SIMD kernel in calls of one vertex (no\n"
           "next vertex to request or set up: the order before the look-ahead), which adds the per-call argument checks;\n"
           "grids of at most 1 MiB (the L2 rows) make no requests, only the next vertex's set-up overlaps.\n\n",
           CHUNK, CHUNK, out_of_cache_res(0), out_of_cache_res(4), out_of_cache_res(8), (double)out_of_cache_bytes() / (1 << 20));
    printf("| lmax | method | grid | reference ns/vertex | SIMD ns/vertex | speed-up | SIMD Mvertices/s | bytes/vertex | GB/s | of read BW "
           "| no look-ahead ns/vertex | of read BW | look-ahead speed-up |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    double *out = xmalloc(sizeof(double) * CHUNK * 3 * SHL_NCOEFFS(8) * 64);
    /* float output (shl_grid_interp_f): the same vertices as floats; per lmax 4, 8 and grid, the
     * double and float timings of Hermite alternated in the same rounds, printed after this table */
    float *ptsf = xmalloc(sizeof(float) * 3 * NPTS), *outf = xmalloc(sizeof(float) * CHUNK * 3 * SHL_NCOEFFS(8));
    for (int k = 0; k < 3 * NPTS; ++k) ptsf[k] = (float)pts[k];
    double fo_d[3][2], fo_f[3][2], fo_sp[3][2]; /* [lmax index][big]: s/vertex double, float; speed-up */
    for (int li = lfirst; li < 3; ++li) {
        const int lmax = lmaxes[li], nc = SHL_NCOEFFS(lmax);
        shl_ctx *ctx, *ctx_ref;
        must(shl_ctx_create(lmax, &ctx), "ctx");
        setenv("SHLIGHT_ISA", "scalar", 1);
        must(shl_ctx_create(lmax, &ctx_ref), "ctx");
        unsetenv("SHLIGHT_ISA");
        for (int big = 0; big <= 1; ++big) {
            const int res = big ? out_of_cache_res(lmax) : 4;
            bench_progress("interpolation, lmax %d, %s grid: filling 2 x %d^3 nodes (step 3/5)...", lmax,
                           big ? "out-of-cache" : "L2", res);
            shl_grid *g = make_grid(ctx, res), *gr = make_grid(ctx_ref, res);
            if (big && lmax == 8) grid_huge_mb = anon_huge_mb();
            for (int m = 0; m < 3; ++m) {
                /* L2: the same chunk again and again; DRAM: fresh vertices every chunk */
                bench_progress("interpolation, lmax %d, %s grid: timing %s (step 3/5)...", lmax, big ? "out-of-cache" : "L2",
                               mname[m]);
                job js = {g, m, 1, CHUNK, big ? NPTS : CHUNK, pts, out, 0}, jr = js, j1 = js;
                jr.g = gr;
                j1.chunk = 1; /* no look-ahead */
                const long reps = big ? 1 : (lmax == 0 ? 400 : lmax == 4 ? 100 : 40);
                double ts[MAX_ROUNDS], tr[MAX_ROUNDS], t1[MAX_ROUNDS], sp[MAX_ROUNDS], sp1[MAX_ROUNDS];
                run(&js);
                run(&jr);
                run(&j1);
                for (int r = 0; r < rounds; ++r) {
                    ts[r] = tr[r] = t1[r] = 0.0;
                    for (long q = 0; q < reps; ++q) {
                        ts[r] += run(&js) / reps;
                        tr[r] += run(&jr) / reps;
                        t1[r] += run(&j1) / reps;
                    }
                    sp[r] = tr[r] / ts[r];
                    sp1[r] = t1[r] / ts[r];
                }
                const double ms = bench_median(ts, rounds), mr = bench_median(tr, rounds), msp = bench_median(sp, rounds);
                const double m1 = bench_median(t1, rounds), msp1 = bench_median(sp1, rounds);
                const double bpv = bytes_per_vertex(m, nc), gbs = bpv / ms, peak = big ? read_peak : l2_peak;
                if (lmax == 8 && m == SHL_INTERP_HERMITE) hermite8[big] = ms;
                printf("| %d | %s | %s | %.1f | %.1f | **%.2fx** | %.2f | %.0f | %.1f | **%.0f%%** | %.1f | %.0f%% | **%.2fx** |\n", lmax,
                       mname[m], big ? "DRAM" : "L2", mr * 1e9, ms * 1e9, msp, 1e-6 / ms, bpv, gbs * 1e-9, 100.0 * gbs / peak,
                       m1 * 1e9, 100.0 * bpv / m1 / peak, msp1);
                if (csv)
                    fprintf(csv, "interp,%d,%s,%s,%s,%.2f,%.2f,%.3f,%.3f,%.0f,%.3f,%.3f,%.2f,%.3f,\n", lmax, mname[m],
                            big ? "dram" : "l2", isa, ms * 1e9, mr * 1e9, msp, 1e-6 / ms, bpv, gbs * 1e-9, gbs / peak, m1 * 1e9,
                            bpv / m1 / peak);
                if (m == SHL_INTERP_HERMITE && lmax > 0) {
                    double td[MAX_ROUNDS], tf[MAX_ROUNDS], spf[MAX_ROUNDS];
                    run_f(&js, ptsf, outf);
                    for (int r = 0; r < rounds; ++r) {
                        td[r] = tf[r] = 0.0;
                        for (long q = 0; q < reps; ++q) {
                            td[r] += run(&js) / reps;
                            tf[r] += run_f(&js, ptsf, outf) / reps;
                        }
                        spf[r] = td[r] / tf[r];
                    }
                    fo_d[li][big] = bench_median(td, rounds);
                    fo_f[li][big] = bench_median(tf, rounds);
                    fo_sp[li][big] = bench_median(spf, rounds);
                }
            }
            shl_grid_destroy(g);
            shl_grid_destroy(gr);
        }
        shl_ctx_destroy(ctx);
        shl_ctx_destroy(ctx_ref);
    }

    printf("\n## Float output, Hermite, one core: shl_grid_interp_f (float vertices, float sums, float output) vs\n"
           "shl_grid_interp (double vertices, sums and output), SIMD kernel (%s)\n\n"
           "The grids, vertices and chunks of the table above; the two alternated in the same rounds.  of read BW:\n"
           "grid bytes/vertex x vertices/s / the read bandwidth above (DRAM rows: DRAM read; L2 rows: L2 read).\n\n",
           isa);
    printf("| lmax | grid | double output ns/vertex | float output ns/vertex | float / double speed-up | of read BW, double "
           "| of read BW, float |\n|---|---|---|---|---|---|---|\n");
    for (int li = lfirst > 1 ? lfirst : 1; li < 3; ++li)
        for (int big = 0; big <= 1; ++big) {
            const int lmax = lmaxes[li];
            const double bpv = bytes_per_vertex(SHL_INTERP_HERMITE, SHL_NCOEFFS(lmax)), peak = big ? read_peak : l2_peak;
            printf("| %d | %s | %.1f | %.1f | **%.2fx** | %.0f%% | **%.0f%%** |\n", lmax, big ? "DRAM" : "L2", fo_d[li][big] * 1e9,
                   fo_f[li][big] * 1e9, fo_sp[li][big], 100.0 * bpv / fo_d[li][big] / peak, 100.0 * bpv / fo_f[li][big] / peak);
            if (csv)
                fprintf(csv, "float_out,%d,Hermite,%s,%s,%.2f,%.2f,%.3f,%.3f,%.0f,%.3f,%.3f,,,\n", lmax, big ? "dram" : "l2", isa,
                        fo_f[li][big] * 1e9, fo_d[li][big] * 1e9, fo_sp[li][big], 1e-6 / fo_f[li][big], bpv,
                        bpv / fo_f[li][big] * 1e-9, bpv / fo_f[li][big] / peak);
        }

    printf("\nThe two lmax-8 out-of-cache grids (shl_grid_create: library allocation): %.0f MB of this process in huge pages.\n",
           grid_huge_mb);

    /* The vertex order is the caller's: the library keeps it (results in the caller's order) */
    {
        const int res = out_of_cache_res(8);
        printf("\n## Vertex order, Hermite, lmax 8, out-of-cache grid (%d^3 nodes): random vs sorted by cell\n\n"
               "The same %d vertices, in random order and sorted by cell (x fastest), in calls of %d.  Sorted, neighbouring\n"
               "vertices share corner rows and sweep the grid in address order, so the caches and the hardware\n"
               "prefetchers serve part of the nominal bytes/vertex: the share of read bandwidth is nominal.\n\n",
               res, NPTS, CHUNK);
        printf("| order | ns/vertex | nominal GB/s | of read BW | sorted / random speed-up |\n|---|---|---|---|---|\n");
        shl_ctx *ctx;
        must(shl_ctx_create(8, &ctx), "ctx");
        bench_progress("vertex order, lmax 8, out-of-cache grid: filling %d^3 nodes (step 4/5)...", res);
        shl_grid *g = make_grid(ctx, res);
        double *spts = sorted_by_cell(pts, NPTS, res);
        job jrand = {g, SHL_INTERP_HERMITE, 1, CHUNK, NPTS, pts, out, 0}, jsort = jrand;
        jsort.pts = spts;
        double tr[MAX_ROUNDS], ts[MAX_ROUNDS], sp[MAX_ROUNDS];
        run(&jrand);
        run(&jsort);
        for (int r = 0; r < rounds; ++r) {
            tr[r] = run(&jrand);
            ts[r] = run(&jsort);
            sp[r] = tr[r] / ts[r];
        }
        const double mr = bench_median(tr, rounds), ms = bench_median(ts, rounds), bpv = bytes_per_vertex(SHL_INTERP_HERMITE, 81);
        printf("| random | %.1f | %.1f | %.0f%% | |\n", mr * 1e9, bpv / mr * 1e-9, 100.0 * bpv / mr / read_peak);
        printf("| sorted by cell | %.1f | %.1f | %.0f%% | **%.2fx** |\n", ms * 1e9, bpv / ms * 1e-9, 100.0 * bpv / ms / read_peak,
               bench_median(sp, rounds));
        if (csv) fprintf(csv, "order,8,Hermite,dram,%s,%.2f,%.2f,%.3f,,%.0f,,,,,\n", isa, ms * 1e9, mr * 1e9, bench_median(sp, rounds), bpv);
        free(spts);

        /* The access pattern's own ceiling: the same rows read with no arithmetic */
        printf("\n## Access-pattern ceiling, Hermite, lmax 8, out-of-cache grid: the kernel against a plain read of the same rows\n\n"
               "Read only: the same random vertices' corner rows (4 ranges of two adjacent nodes, %d B each) from an\n"
               "array of the grid's size and layout (2 MiB-aligned, advised as huge pages like the library's grids),\n"
               "one float of each line added (the load brings the whole line) and no other work; with look-ahead, the next vertex's lines requested into L2\n"
               "as the kernel requests them; the three alternated in the same rounds.  What the read-only rows reach is\n"
               "what this core's memory system gives random 7.6 KB ranges: the kernel cannot beat it.\n\n",
               2 * l2_node_bytes);
        int advised;
        const size_t node_floats = (size_t)l2_node_bytes / sizeof(float), nfloats = (size_t)res * res * res * node_floats;
        float *nodes = huge_malloc(sizeof(float) * nfloats, &advised);
        for (size_t i = 0; i < nfloats; ++i) nodes[i] = (float)(i & 255);
        double tk[MAX_ROUNDS], ta[MAX_ROUNDS], td[MAX_ROUNDS], rk[MAX_ROUNDS];
        pattern_read(nodes, node_floats, res, pts, NPTS, 1);
        for (int r = 0; r < rounds; ++r) {
            tk[r] = run(&jrand);
            ta[r] = pattern_read(nodes, node_floats, res, pts, NPTS, 1);
            td[r] = pattern_read(nodes, node_floats, res, pts, NPTS, 0);
            rk[r] = ta[r] / tk[r];
        }
        free(nodes);
        const double mk = bench_median(tk, rounds), ma = bench_median(ta, rounds), md = bench_median(td, rounds);
        const double mrk = bench_median(rk, rounds);
        printf("| read of the corner rows | ns/vertex | GB/s | of read BW | kernel speed / read-only speed |\n|---|---|---|---|---|\n");
        printf("| Hermite kernel (shl_grid_interp, %s) | %.1f | %.1f | %.0f%% | |\n", isa, mk * 1e9, bpv / mk * 1e-9,
               100.0 * bpv / mk / read_peak);
        printf("| read only, look-ahead | %.1f | %.1f | %.0f%% | **%.0f%%** |\n", ma * 1e9, bpv / ma * 1e-9, 100.0 * bpv / ma / read_peak,
               100.0 * mrk);
        printf("| read only, demand loads | %.1f | %.1f | %.0f%% | |\n", md * 1e9, bpv / md * 1e-9, 100.0 * bpv / md / read_peak);
        if (csv) {
            fprintf(csv, "pattern_lookahead,8,Hermite,dram,%s,%.2f,%.2f,%.3f,,%.0f,%.3f,%.3f,,,\n", isa, mk * 1e9, ma * 1e9, mrk, bpv,
                    bpv / ma * 1e-9, bpv / ma / read_peak);
            fprintf(csv, "pattern_demand,8,Hermite,dram,%s,%.2f,%.2f,,,%.0f,%.3f,%.3f,,,\n", isa, mk * 1e9, md * 1e9, bpv,
                    bpv / md * 1e-9, bpv / md / read_peak);
        }
        shl_grid_destroy(g);
        shl_ctx_destroy(ctx);
    }

    printf("\n## Hermite interpolation, 2 threads vs 1 (SIMD kernel; calls of 8192 vertices, outputs not reused)\n\n"
           "output double: shl_grid_interp; float: shl_grid_interp_f (the same vertices as floats).\n\n");
    printf("CPU efficiency: CPU time of the process per vertex, 1 thread / 2 threads (both threads' CPU time): below\n"
           "100%%, each core works slower next to the other (shared memory, clock); the speed-up the threads' CPU time\n"
           "allows is 2 x that; a wall-clock speed-up below it is time the threads do not run (start, wake-up,\n"
           "uneven ends, or, on a loaded machine, other processes).\n\n");
    printf("From DRAM, 2 threads GB/s = grid bytes/vertex / 2-thread time per vertex, against the read bandwidth of both\n"
           "cores together (%.1f GB/s above): the memory-bound ceiling; from L2 each core reads its own cache.\n\n",
           read_two * 1e-9);
    printf("| lmax | grid | output | 1 thread ns/vertex | 2 threads ns/vertex | 2 threads / 1 thread speed-up | CPU efficiency "
           "| speed-up by CPU time | 2 threads GB/s | of the two-core read BW |\n|---|---|---|---|---|---|---|---|---|---|\n");
    double *big_out = xmalloc(sizeof(double) * 8192 * 3 * SHL_NCOEFFS(8));
    float *big_outf = xmalloc(sizeof(float) * 8192 * 3 * SHL_NCOEFFS(8));
    for (int li = quick ? 2 : 1; li < 3; ++li) {
        const int lmax = lmaxes[li];
        shl_ctx *ctx;
        must(shl_ctx_create(lmax, &ctx), "ctx");
        for (int big = 0; big <= 1; ++big) {
            bench_progress("2 threads vs 1, lmax %d, %s grid (step 4/5)...", lmax, big ? "out-of-cache" : "L2");
            shl_grid *g = make_grid(ctx, big ? out_of_cache_res(lmax) : 4);
            job j1 = {g, SHL_INTERP_HERMITE, 1, 8192, NPTS, pts, big_out, 1}, j2 = j1;
            j2.nthreads = 2;
            for (int fl = 0; fl <= 1; ++fl) {
                double t1[MAX_ROUNDS], t2[MAX_ROUNDS], sp[MAX_ROUNDS], eff[MAX_ROUNDS];
                if (fl) {
                    run_f(&j1, ptsf, big_outf);
                    run_f(&j2, ptsf, big_outf);
                } else {
                    run(&j1);
                    run(&j2);
                }
                for (int r = 0; r < rounds; ++r) {
                    const double c0 = process_cpu_now();
                    t1[r] = fl ? run_f(&j1, ptsf, big_outf) : run(&j1);
                    const double c1 = process_cpu_now();
                    t2[r] = fl ? run_f(&j2, ptsf, big_outf) : run(&j2);
                    eff[r] = (c1 - c0) / (process_cpu_now() - c1); /* CPU seconds, 1 thread / 2 threads */
                    sp[r] = t1[r] / t2[r];
                }
                const double m1 = bench_median(t1, rounds), m2 = bench_median(t2, rounds), msp = bench_median(sp, rounds);
                const double meff = bench_median(eff, rounds);
                const double bpv = bytes_per_vertex(SHL_INTERP_HERMITE, SHL_NCOEFFS(lmax)), gbs = bpv / m2 * 1e-9;
                printf("| %d | %s | %s | %.1f | %.1f | **%.2fx** | %.0f%% | %.2fx |", lmax, big ? "DRAM" : "L2", fl ? "float" : "double",
                       m1 * 1e9, m2 * 1e9, msp, 100.0 * meff, 2.0 * meff);
                if (big)
                    printf(" %.1f | **%.0f%%** |\n", gbs, 100.0 * gbs / (read_two * 1e-9));
                else
                    printf(" - | - |\n");
                if (csv)
                    fprintf(csv, "%s,%d,Hermite,%s,%s,%.2f,%.2f,%.3f,,%.0f,%.3f,%.3f,,,%.3f\n", fl ? "threads_float_out" : "threads",
                            lmax, big ? "dram" : "l2", isa, m2 * 1e9, m1 * 1e9, msp, bpv, big ? gbs : 0.0,
                            big ? gbs / (read_two * 1e-9) : 0.0, meff);
            }
            shl_grid_destroy(g);
        }
        shl_ctx_destroy(ctx);
    }
    printf("\nMedians over %d rounds; in each round all variants are timed under the same load and the\n"
           "speed-ups are ratios within the round.\n", rounds);

    /* The papers' GPU throughput, implied by their frame and stage times (constants below),
     * next to this run's per-core rates: different hardware, different work per frame. */
    bench_progress("polygon batch throughput for the papers' comparison (step 5/5)...");
    const double quad8 = polygon_batch_time(4, 0, pts), tri8g = polygon_batch_time(3, 1, pts);
    /* Wang 2018 Sec. 6 / Table 2: plant, 163K triangles, one rectangle light, lmax 8, 350 fps
     * (whole frame) on a GTX 1080 Ti; a closed triangle mesh has about half as many vertices. */
    const double wang = 163e3 / 2 * 350.0;
    /* Wu 2020 Table 1 (RTX 2080 Ti, lmax 8, 8^3 grid): Dragon & Bunny, 723 lights: coefficients
     * and gradients at 512 nodes x 723 lights in 20.2 ms; Hermite interpolation at the vertices
     * of 1.28M triangles (about 640K vertices, V ~ T/2) in 6.6 ms; Asian Dragon: 1.42M triangles
     * in 8.1 ms. */
    const double wu_grid = 512.0 * 723 / 20.2e-3, wu_interp = 1.28e6 / 2 / 6.6e-3, wu_interp2 = 1.42e6 / 2 / 8.1e-3;
    printf("\n## Throughput next to the papers' GPUs (different hardware: their rates are whole GPUs, ours one CPU core)\n\n");
    printf("| work (lmax 8) | paper: GPU, source | paper M/s | this run: benchmark | ours M/s per core |\n|---|---|---|---|---|\n");
    printf("| polygon coefficients per shading point | GTX 1080 Ti, Wang 2018 Table 2 (plant: 163K tris ~ 82K vertices x 350 fps, whole frame) | %.1f | shl_polygon_batch_f, square, %s | %.2f |\n",
           wang * 1e-6, isa, 1e-6 / quad8);
    printf("| polygon coefficients + gradients | RTX 2080 Ti, Wu 2020 Table 1 (Dragon & Bunny: 512 nodes x 723 lights in 20.2 ms) | %.1f | shl_polygon_batch_f with gradients, triangle, %s | %.2f |\n",
           wu_grid * 1e-6, isa, 1e-6 / tri8g);
    printf("| Hermite interpolation per vertex | RTX 2080 Ti, Wu 2020 Table 1 (Dragon & Bunny ~640K vertices in 6.6 ms; Asian Dragon ~710K in 8.1 ms) | %.0f, %.0f | shl_grid_interp Hermite, float grid, %s: L2-resident / DRAM random | %.2f / %.2f |\n",
           wu_interp * 1e-6, wu_interp2 * 1e-6, isa, 1e-6 / hermite8[0], 1e-6 / hermite8[1]);
    if (csv) {
        fprintf(csv, "papers,8,polygon,wang2018_gpu_mps,%s,%.3f,,,%.3f,,,,,,\n", isa, wang * 1e-6, 1e-6 / quad8);
        fprintf(csv, "papers,8,polygon_grad,wu2020_gpu_mps,%s,%.3f,,,%.3f,,,,,,\n", isa, wu_grid * 1e-6, 1e-6 / tri8g);
        fprintf(csv, "papers,8,Hermite,wu2020_gpu_mps,%s,%.3f,,,%.3f,,,,,,\n", isa, wu_interp * 1e-6, 1e-6 / hermite8[0]);
    }
    printf("\n(checksum %g)\n", (double)bench_sink);
    if (fclose(csv)) return 1;
    bench_progress("done; wrote %s", csv_path);
    free(pts);
    free(out);
    free(ptsf);
    free(outf);
    free(big_out);
    free(big_outf);
    shl_ctx_destroy(probe);
    return 0;
}
