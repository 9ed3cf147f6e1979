#include "util.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef SHL_BUILD_FLAGS
#define SHL_BUILD_FLAGS "unknown"
#endif

volatile double bench_sink;

double bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bench_time bench_run(void (*fn)(void *), void *arg, long inner, int reps)
{
    double t[64];
    if (reps > 64) reps = 64;
    fn(arg); /* warm-up */
    for (int r = 0; r < reps; ++r) {
        const double t0 = bench_now();
        fn(arg);
        t[r] = (bench_now() - t0) / (double)inner;
    }
    const double median = bench_median(t, reps); /* sorts t */
    bench_time out = {t[0], median};
    return out;
}

long bench_calibrate(void (*fn_one)(void *), void *arg, double target)
{
    long n = 1;
    for (;;) {
        const double t0 = bench_now();
        for (long i = 0; i < n; ++i) fn_one(arg);
        const double dt = bench_now() - t0;
        if (dt > target / 4 || n > (1L << 30)) return (long)fmax(1.0, n * target / fmax(dt, 1e-9));
        n *= 4;
    }
}

void bench_print_machine(FILE *out)
{
    char model[256] = "unknown";
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        char line[512];
        while (fgets(line, sizeof line, f)) {
            if (!strncmp(line, "model name", 10)) {
                const char *c = strchr(line, ':');
                if (c) {
                    snprintf(model, sizeof model, "%s", c + 2);
                    model[strcspn(model, "\n")] = '\0';
                }
                break;
            }
        }
        fclose(f);
    }
    fprintf(out, "CPU: %s; compiler: %s; flags: %s\n", model,
#ifdef __VERSION__
            __VERSION__,
#else
            "unknown",
#endif
            SHL_BUILD_FLAGS);
}

double bench_loglog_slope(const double *x, const double *y, int n)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < n; ++i) {
        const double lx = log(x[i]), ly = log(y[i]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}
