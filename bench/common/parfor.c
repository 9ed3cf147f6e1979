#include "parfor.h"
#include "util.h"
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

int par_threads(void)
{
    const char *env = getenv("SHLIGHT_THREADS");
    if (env) {
        const int n = atoi(env);
        if (n >= 1 && n <= SHL_MAX_THREADS) return n;
    }
    const long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > SHL_MAX_THREADS ? SHL_MAX_THREADS : (int)n;
}

/* One worker, or no thread could be created: the chunks in order on the calling thread. */
static void serial(long n, long grain, par_fn fn, void *arg)
{
    for (long b = 0; b < n; b += grain) fn(arg, 0, b, n - b < grain ? n : b + grain);
}

int par_for(long n, long grain, int nthreads, par_fn fn, void *arg)
{
    if (n <= 0) return 0;
    if (grain < 1) grain = 1;
    nthreads = nthreads < 1 ? 1 : nthreads > SHL_MAX_THREADS ? SHL_MAX_THREADS : nthreads;
    if (shl__parallel_workers(n, grain, nthreads) > 1) {
        /* SHL_ETHREAD means fn never ran (src/parallel.h): running it again here is safe */
        if (shl__parallel_for(n, grain, nthreads, fn, arg) == SHL_OK) return 0;
        serial(n, grain, fn, arg);
        return -1;
    }
    serial(n, grain, fn, arg);
    return 0;
}

struct par_progress {
    pthread_mutex_t lock;
    const char *name;
    long total, done;
    double start, last;
    int shown;
};

par_progress *par_progress_begin(const char *name, long total)
{
    par_progress *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    pthread_mutex_init(&p->lock, NULL);
    p->name = name;
    p->total = total > 0 ? total : 1;
    p->start = p->last = bench_now();
    return p;
}

void par_progress_add(par_progress *p, long done)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->done += done;
    const double now = bench_now();
    if (now - p->start > 1.0 && now - p->last > 0.5) {
        fprintf(stderr, "\r  %s: %3.0f%%", p->name, 100.0 * (double)p->done / (double)p->total);
        fflush(stderr);
        p->last = now;
        p->shown = 1;
    }
    pthread_mutex_unlock(&p->lock);
}

void par_progress_end(par_progress *p)
{
    if (!p) return;
    if (p->shown) fprintf(stderr, "\r  %s: done in %.1f s\n", p->name, bench_now() - p->start);
    pthread_mutex_destroy(&p->lock);
    free(p);
}
