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
        if (n >= 1 && n <= 256) return n;
    }
    const long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 256 ? 256 : (int)n;
}

typedef struct {
    pthread_mutex_t lock;
    long next, n, grain;
    par_fn fn;
    void *arg;
} loop;

typedef struct {
    loop *lp;
    int worker;
} worker_arg;

static void run(loop *lp, int worker)
{
    for (;;) {
        pthread_mutex_lock(&lp->lock);
        const long begin = lp->next;
        lp->next = begin + lp->grain < lp->n ? begin + lp->grain : lp->n;
        const long end = lp->next;
        pthread_mutex_unlock(&lp->lock);
        if (begin >= end) return;
        lp->fn(lp->arg, begin, end, worker);
    }
}

static void *thread_main(void *p)
{
    worker_arg *w = p;
    run(w->lp, w->worker);
    return NULL;
}

int par_for(long n, long grain, int nthreads, par_fn fn, void *arg)
{
    if (n <= 0) return 0;
    if (grain < 1) grain = 1;
    if ((n + grain - 1) / grain < nthreads) nthreads = (int)((n + grain - 1) / grain);
    if (nthreads > 256) nthreads = 256;
    loop lp = {PTHREAD_MUTEX_INITIALIZER, 0, n, grain, fn, arg};
    pthread_t tid[256];
    worker_arg wa[256];
    int started = 0;
    for (int t = 1; t < nthreads; ++t) {
        wa[t].lp = &lp;
        wa[t].worker = t;
        if (pthread_create(&tid[t], NULL, thread_main, &wa[t]) != 0) break;
        started = t;
    }
    run(&lp, 0);
    for (int t = 1; t <= started; ++t) pthread_join(tid[t], NULL);
    pthread_mutex_destroy(&lp.lock);
    return nthreads > 1 && started == 0 ? -1 : 0;
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
