/* Benchmark helpers: timing with warm-up and repetitions (min and median),
 * machine description, and a checksum sink so no work is optimized away. */
#ifndef SHL_BENCH_UTIL_H
#define SHL_BENCH_UTIL_H

#include <stdio.h>

double bench_now(void); /* seconds, monotonic */

typedef struct {
    double min, median; /* seconds per call of the timed function */
} bench_time;

/* Time fn(arg) (which performs `inner` evaluations): one warm-up call, then
 * `reps` timed calls; returns seconds per evaluation. */
bench_time bench_run(void (*fn)(void *), void *arg, long inner, int reps);

/* Median of v[0..n-1] (sorts v in place). */
double bench_median(double *v, int n);

/* Choose an inner count so that one timed call takes about target seconds. */
long bench_calibrate(void (*fn_one)(void *), void *arg, double target);

/* CPU model, compiler, flags. */
void bench_print_machine(FILE *out);

/* Accumulates results so the compiler must compute them. */
extern volatile double bench_sink;

/* Least-squares slope of log(y) against log(x): the fitted exponent. */
double bench_loglog_slope(const double *x, const double *y, int n);

#endif
