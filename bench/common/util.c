#include "util.h"
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
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

static const char *prog_name = "bench";
static double prog_start = -1.0;

static void print_usage(const bench_cli *cli, FILE *f, int full)
{
    fprintf(f, "usage: %s %s\n", cli->name, cli->synopsis);
    if (full) fprintf(f, "\n%s\n", cli->about);
    fprintf(f, "\noptions:\n  -h, --help%*s print this help and exit\n", 14, "");
    for (int i = 0; i < cli->nopts; ++i) {
        const bench_opt *o = &cli->opts[i];
        char lhs[64];
        snprintf(lhs, sizeof lhs, "%s%s%s%s%s", o->flag, o->longflag ? ", " : "", o->longflag ? o->longflag : "",
                 o->metavar ? " " : "", o->metavar ? o->metavar : "");
        fprintf(f, "  %-24s %s\n", lhs, o->help);
    }
}

int bench_parse(const bench_cli *cli, int argc, char **argv, const char **args)
{
    prog_name = cli->name;
    prog_start = bench_now();
    setvbuf(stdout, NULL, _IOLBF, 0);
    int nargs = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            print_usage(cli, stdout, 1);
            exit(0);
        }
        if (a[0] != '-' || !a[1]) {
            if (nargs == cli->max_args) {
                fprintf(stderr, "%s: unexpected argument '%s'\n", cli->name, a);
                print_usage(cli, stderr, 0);
                exit(2);
            }
            args[nargs++] = a;
            continue;
        }
        const bench_opt *o = NULL;
        for (int k = 0; k < cli->nopts && !o; ++k)
            if (!strcmp(a, cli->opts[k].flag) || (cli->opts[k].longflag && !strcmp(a, cli->opts[k].longflag)))
                o = &cli->opts[k];
        if (!o || (o->metavar && i + 1 >= argc)) {
            fprintf(stderr, o ? "%s: option %s needs a value\n" : "%s: unknown option '%s'\n", cli->name, a);
            print_usage(cli, stderr, 0);
            exit(2);
        }
        *o->value = o->metavar ? argv[++i] : "1";
    }
    return nargs;
}

void bench_progress(const char *fmt, ...)
{
    if (prog_start < 0) prog_start = bench_now();
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "%s [%3.0f s]: ", prog_name, bench_now() - prog_start);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    fflush(stderr);
    va_end(ap);
}

int bench_mkdirs(const char *dir)
{
    char p[1024];
    if (snprintf(p, sizeof p, "%s", dir) >= (int)sizeof p) return -1;
    for (char *c = p + 1; *c; ++c) {
        if (*c != '/') continue;
        *c = '\0';
        if (mkdir(p, 0777) && errno != EEXIST) return -1;
        *c = '/';
    }
    return mkdir(p, 0777) && errno != EEXIST ? -1 : 0;
}

FILE *bench_create(const char *path, const char *mode)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    FILE *f = NULL;
    if (!slash || slash == dir || (*slash = '\0', !bench_mkdirs(dir))) f = fopen(path, mode);
    if (!f) fprintf(stderr, "%s: cannot write %s: %s\n", prog_name, path, strerror(errno));
    return f;
}

void bench_loadavg(char *buf, size_t len)
{
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f || !fgets(buf, (int)len, f)) snprintf(buf, len, "unknown");
    if (f) fclose(f);
    buf[strcspn(buf, "\n")] = '\0';
}

int bench_write_binary(const char *dir, const char *name, const void *a, size_t size, size_t n)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    const int ok = fwrite(a, size, n, f) == n;
    return fclose(f) == 0 && ok ? 0 : -1;
}
