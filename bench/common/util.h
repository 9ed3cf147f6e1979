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

/* ---- command line, progress and output files of the bench binaries ---- */

typedef struct {
    const char *flag;     /* short form, e.g. "-o" */
    const char *longflag; /* long form, e.g. "--csv", or NULL */
    const char *metavar;  /* value name, e.g. "FILE"; NULL: a switch (*value becomes "1") */
    const char **value;   /* receives the value; keeps its default when the option is absent */
    const char *help;     /* one line, with the default */
} bench_opt;

typedef struct {
    const char *name;     /* program name in messages */
    const char *synopsis; /* after the name: "[-o FILE]" */
    const char *about;    /* what it measures, typical run time, what it writes where */
    const bench_opt *opts;
    int nopts;
    int max_args; /* positional arguments accepted (they must not start with '-') */
} bench_cli;

/* Parses argv: -h / --help prints the usage to stdout and exits 0; an unknown option, a
 * missing value or too many arguments print the usage to stderr and exit 2.  Stores the
 * positional arguments in args[0..max_args-1] and returns their count.  Also makes stdout
 * line-buffered (tables appear as they are measured when it is redirected) and starts the
 * clock of bench_progress. */
int bench_parse(const bench_cli *cli, int argc, char **argv, const char **args);

/* One progress line on stderr, "<name> [<elapsed> s]: <message>", flushed. */
void bench_progress(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/* Creates the directory and its missing parents (mkdir -p); 0 on success. */
int bench_mkdirs(const char *dir);

/* fopen(path, mode) after creating path's parent directories; on failure prints
 * "<name>: cannot write <path>: <reason>" to stderr and returns NULL. */
FILE *bench_create(const char *path, const char *mode);

/* Writes n items of size bytes from a to dir/name (binary); 0 on success, -1 otherwise. */
int bench_write_binary(const char *dir, const char *name, const void *a, size_t size, size_t n);

/* The first line of /proc/loadavg ("unknown" where it cannot be read). */
void bench_loadavg(char *buf, size_t len);

#endif
