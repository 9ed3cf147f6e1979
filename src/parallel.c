/* Parallel loop: threads wait at a start gate until all of them exist, then
 * claim chunks from a shared counter.  Results must not depend on which
 * worker runs a chunk (every caller writes per-item outputs only). */
#include "parallel.h"
#include <pthread.h>

#ifdef SHL_ALLOC_HOOKS
long shl__thread_fail_after = -1; /* tests: the N-th thread creation fails (< 0: never) */
static int create_should_fail(void) { return shl__hook_fails(&shl__thread_fail_after); }
#else
static int create_should_fail(void) { return 0; }
#endif

typedef struct {
    pthread_mutex_t lock;
    pthread_cond_t gate;
    int state; /* 0: wait, 1: run, -1: abort */
    long next, n, grain;
    long split; /* guided: a chunk is about the remaining items / split (0: fixed chunks of grain) */
    shl__range_fn fn;
    void *arg;
} pool;

typedef struct {
    pool *p;
    int worker;
} worker_arg;

static void run_chunks(pool *p, int worker)
{
    for (;;) {
        pthread_mutex_lock(&p->lock);
        const long begin = p->next, left = p->n - begin;
        if (begin < p->n) {
            const long want = p->split ? left / p->split / p->grain * p->grain : 0; /* a multiple of grain */
            const long size = want > p->grain ? want : p->grain;
            p->next = begin + (left < size ? left : size);
        }
        const long end = p->next;
        pthread_mutex_unlock(&p->lock);
        if (begin >= p->n) return;
        p->fn(p->arg, worker, begin, end);
    }
}

static void *thread_main(void *arg)
{
    const worker_arg *w = arg;
    pool *p = w->p;
    pthread_mutex_lock(&p->lock);
    while (p->state == 0) pthread_cond_wait(&p->gate, &p->lock);
    const int run = p->state > 0;
    pthread_mutex_unlock(&p->lock);
    if (run) run_chunks(p, w->worker);
    return NULL;
}

int shl__parallel_workers(long n, long grain, int nthreads)
{
    const long chunks = n > 0 ? (n + grain - 1) / grain : 1;
    return chunks < nthreads ? (int)chunks : nthreads;
}

static int parallel_run(long n, long grain, int nthreads, int guided, shl__range_fn fn, void *arg)
{
    const int nw = shl__parallel_workers(n, grain, nthreads);
    if (nw <= 1) {
        if (n > 0) fn(arg, 0, 0, n);
        return SHL_OK;
    }
    /* guided: chunks of 1/(4 nw) of what is left, so that the last ones, and the
     * wait for the slowest worker, are short (OpenMP's guided schedule, halved) */
    pool p = {.state = 0, .next = 0, .n = n, .grain = grain, .split = guided ? 4L * nw : 0, .fn = fn, .arg = arg};
    if (pthread_mutex_init(&p.lock, NULL)) return SHL_ETHREAD;
    if (pthread_cond_init(&p.gate, NULL)) {
        pthread_mutex_destroy(&p.lock);
        return SHL_ETHREAD;
    }
    pthread_t tid[SHL_MAX_THREADS];
    worker_arg wa[SHL_MAX_THREADS];
    int started = 0;
    for (int w = 1; w < nw; ++w) {
        wa[w].p = &p;
        wa[w].worker = w;
        if (create_should_fail() || pthread_create(&tid[w], NULL, thread_main, &wa[w])) break;
        ++started;
    }
    const int ok = started == nw - 1;
    pthread_mutex_lock(&p.lock);
    p.state = ok ? 1 : -1;
    pthread_cond_broadcast(&p.gate);
    pthread_mutex_unlock(&p.lock);
    if (ok) run_chunks(&p, 0);
    for (int w = 1; w <= started; ++w) pthread_join(tid[w], NULL);
    pthread_cond_destroy(&p.gate);
    pthread_mutex_destroy(&p.lock);
    return ok ? SHL_OK : SHL_ETHREAD;
}

int shl__parallel_for(long n, long grain, int nthreads, shl__range_fn fn, void *arg)
{
    return parallel_run(n, grain, nthreads, 0, fn, arg);
}

int shl__parallel_for_guided(long n, long grain, int nthreads, shl__range_fn fn, void *arg)
{
    return parallel_run(n, grain, nthreads, 1, fn, arg);
}

typedef struct {
    shl__ws_range_fn fn;
    void *arg;
    char *ws; /* per worker: stride bytes (NULL if none) */
    size_t stride;
} ws_job;

static void ws_range(void *arg, int worker, long begin, long end)
{
    const ws_job *job = arg;
    job->fn(job->arg, job->ws ? job->ws + job->stride * (size_t)worker : NULL, begin, end);
}

int shl__parallel_for_ws(long n, long grain, int nthreads, size_t ws_bytes, shl__ws_range_fn fn, void *arg)
{
    const int nw = shl__parallel_workers(n, grain, nthreads);
    ws_job job = {fn, arg, NULL, shl__ws_stride(ws_bytes)};
    if (job.stride > 0 && !(job.ws = shl__malloc(job.stride * (size_t)nw))) return SHL_ENOMEM;
    const int st = shl__parallel_for(n, grain, nw, ws_range, &job);
    shl__free(job.ws);
    return st;
}
