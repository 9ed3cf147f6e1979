/* Whole-call time of shl_polygon (double) for a triangle at lmax 2, 4, 8, 14, 30.
 * Public API only (shl_ctx_create, shl_polygon, shl_ctx_destroy) and libc, so the
 * same source builds against an older libshlight.a: `make bench-vs-commit OLD=<rev>`
 * (bench/vs_commit.sh) runs it against the old and the current library in turn and
 * prints medians and old / new ratios.  The case is bench_polygon's: a regular
 * triangle of radius 1 in the plane z = 2, 64 shading points in [-1, 1]^3 (srand(1)),
 * the point changing with every call.  Output: one line per lmax, "lmax ns_per_call"
 * (the median of 5 repetitions of >= 20 ms each).  Time is the thread's CPU time
 * (CLOCK_THREAD_CPUTIME_ID): on an idle machine the wall time, on a loaded one it
 * leaves out the time other processes hold the core (not their cache traffic). */
#include "shlight.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { NPTS = 64, REPS = 5 };

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static volatile double sink;

/* seconds per call over `inner` calls */
static double run(const shl_ctx *ctx, const double *verts, double (*pts)[3], double *coeffs, long inner)
{
    double acc = 0.0;
    const double t0 = now();
    for (long i = 0; i < inner; ++i) {
        if (shl_polygon(ctx, pts[i % NPTS], verts, 3, coeffs)) return -1.0;
        acc += coeffs[0];
    }
    const double t = now() - t0;
    sink += acc;
    return t / inner;
}

static int cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc > 1) {
        const int help = !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h");
        fprintf(help ? stdout : stderr,
                "usage: polygon_call\n"
                "Time per shl_polygon call (double, a triangle, the shading point changing every call) at\n"
                "lmax 2, 4, 8, 14, 30: lines \"lmax ns\", the median of 5 repetitions of >= 20 ms of thread\n"
                "CPU time.  Public API only, so it links against an older libshlight.a too:\n"
                "make bench-vs-commit OLD=<rev> runs it against <rev> and this tree (bench/vs_commit.sh).\n");
        return help ? 0 : 2;
    }
    static const int lmaxes[] = {2, 4, 8, 14, 30};
    static double coeffs[SHL_NCOEFFS(30)];
    double verts[9], pts[NPTS][3];
    for (int i = 0; i < 3; ++i) {
        verts[3 * i] = cos(2 * M_PI * i / 3);
        verts[3 * i + 1] = sin(2 * M_PI * i / 3);
        verts[3 * i + 2] = 2.0;
    }
    srand(1);
    for (int p = 0; p < NPTS; ++p)
        for (int k = 0; k < 3; ++k) pts[p][k] = 2.0 * rand() / RAND_MAX - 1.0;
    for (size_t li = 0; li < sizeof lmaxes / sizeof lmaxes[0]; ++li) {
        shl_ctx *ctx;
        if (shl_ctx_create(lmaxes[li], &ctx)) return 1;
        long inner = 1;
        while (run(ctx, verts, pts, coeffs, inner) * inner < 0.005) inner *= 2; /* calibrate: >= 5 ms */
        inner *= 4;
        double t[REPS];
        for (int r = 0; r < REPS; ++r)
            if ((t[r] = run(ctx, verts, pts, coeffs, inner)) < 0.0) return 1;
        qsort(t, REPS, sizeof t[0], cmp);
        printf("%d %.1f\n", lmaxes[li], 1e9 * t[REPS / 2]);
        shl_ctx_destroy(ctx);
    }
    return 0;
}
