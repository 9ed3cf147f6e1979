/* Parallel loop on a process-wide pool of parked worker threads: created when a
 * call first needs them, woken by later calls (the creation and join of threads
 * per call cost 10-100x the wake-up on the 2-vCPU guests, bench_grid -f), joined
 * at exit.  A call claims chunks from its own counter; results must not depend
 * on which worker runs a chunk (every caller writes per-item outputs only). */
#include "parallel.h"
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>

#ifdef SHL_ALLOC_HOOKS
long shl__thread_fail_after = -1; /* tests: the N-th worker a call takes fails to start (< 0: never) */
static int start_should_fail(void) { return shl__hook_fails(&shl__thread_fail_after); }
#else
static int start_should_fail(void) { return 0; }
#endif

typedef struct {
    pthread_mutex_t lock;
    long next, n, grain;
    long split; /* guided: a chunk is about the remaining items / split (0: fixed chunks of grain) */
    shl__range_fn fn;
    void *arg;
} loop;

/* Claims the next chunk [*begin, p->next); 0 when none is left (caller holds p->lock). */
static int claim_chunk(loop *p, long *begin)
{
    const long left = p->n - p->next;
    *begin = p->next;
    if (left <= 0) return 0;
    const long want = p->split ? left / p->split / p->grain * p->grain : 0; /* a multiple of grain */
    const long size = want > p->grain ? want : p->grain;
    p->next += left < size ? left : size;
    return 1;
}

static void run_chunks(loop *p, int worker)
{
    for (;;) {
        long begin;
        pthread_mutex_lock(&p->lock);
        const int more = claim_chunk(p, &begin);
        const long end = p->next;
        pthread_mutex_unlock(&p->lock);
        if (!more) return;
        p->fn(p->arg, worker, begin, end);
    }
}

#ifdef SHL_SERIAL_POOL
/* Fuzz builds (Makefile, SANITIZE=fuzzer): a round's chunks run one after the other on the
 * calling thread, chunk k as worker k mod nw.  Coverage counters bumped by racing threads,
 * and chunks taken in timing order, made the same fixed-seed fuzz run find different inputs
 * from one run to the next; the results contract (independent of the worker that runs a
 * chunk) is the same, and the threaded pool is tested by make test and ThreadSanitizer. */
static int serial_round(long n, long grain, int nw, int guided, shl__range_fn fn, void *arg)
{
    loop p = {.next = 0, .n = n, .grain = grain, .split = guided ? 4L * nw : 0, .fn = fn, .arg = arg};
    long begin;
    for (int k = 0; claim_chunk(&p, &begin); k = (k + 1) % nw) fn(arg, k, begin, p.next);
    return SHL_OK;
}
#endif

/* The pool, under pool_lock.  One call at a time owns it (busy); the owner alone
 * creates workers and changes size.  Worker w (1 <= w <= size) takes part in a
 * round if w < round_workers and it wakes while the owner still works on the
 * round's job: the owner waits only for the workers that joined (running), never
 * for one that other processes kept off the CPU. */
static pthread_mutex_t pool_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t pool_wake = PTHREAD_COND_INITIALIZER; /* a new round, or exit */
static pthread_cond_t pool_done = PTHREAD_COND_INITIALIZER; /* the round's last worker finished */
static struct {
    int busy, size, exiting, hooks_set;
    unsigned long round;
    loop *job;
    int round_workers, running;
    unsigned long born[SHL_MAX_THREADS]; /* round at worker w's creation: it waits for the next one */
    pthread_t tid[SHL_MAX_THREADS];
} pool;

static void *worker_main(void *arg)
{
    const int w = (int)(intptr_t)arg;
    pthread_mutex_lock(&pool_lock);
    unsigned long seen = pool.born[w];
    for (;;) {
        while (pool.round == seen && !pool.exiting) pthread_cond_wait(&pool_wake, &pool_lock);
        if (pool.exiting) break;
        seen = pool.round;
        if (pool.job && w < pool.round_workers) {
            loop *job = pool.job;
            ++pool.running;
            pthread_mutex_unlock(&pool_lock);
            run_chunks(job, w);
            pthread_mutex_lock(&pool_lock);
            if (--pool.running == 0) pthread_cond_signal(&pool_done);
        }
    }
    pthread_mutex_unlock(&pool_lock);
    return NULL;
}

/* atexit: the workers return and are joined (unless a call on another thread
 * still owns the pool: the process then ends with them).  Later calls run on
 * their calling thread. */
static void pool_exit(void)
{
    pthread_mutex_lock(&pool_lock);
    const int idle = !pool.busy;
    pool.busy = 1;
    pool.exiting = idle;
    pthread_cond_broadcast(&pool_wake);
    pthread_mutex_unlock(&pool_lock);
    for (int w = 1; idle && w <= pool.size; ++w) pthread_join(pool.tid[w], NULL);
}

/* fork: the child has none of the workers; it starts an empty pool. */
static void pool_fork_prepare(void) { pthread_mutex_lock(&pool_lock); }
static void pool_fork_parent(void) { pthread_mutex_unlock(&pool_lock); }
static void pool_fork_child(void)
{
    pthread_cond_init(&pool_wake, NULL); /* waiters of the parent's threads are gone */
    pthread_cond_init(&pool_done, NULL);
    pool.busy = pool.size = pool.running = 0;
    pool.job = NULL;
    pthread_mutex_unlock(&pool_lock);
}

/* The owner: workers 1 .. nw-1 exist, created here if missing (the exit and fork
 * handlers registered before the first); 0 if one cannot be. */
static int take_workers(int nw)
{
    if (!pool.hooks_set) {
        if (atexit(pool_exit) || pthread_atfork(pool_fork_prepare, pool_fork_parent, pool_fork_child)) return 0;
        pool.hooks_set = 1;
    }
    for (int w = 1; w < nw; ++w) {
        if (start_should_fail()) return 0;
        if (w <= pool.size) continue;
        pool.born[w] = pool.round;
        if (pthread_create(&pool.tid[w], NULL, worker_main, (void *)(intptr_t)w)) return 0;
        pool.size = w;
    }
    return 1;
}

int shl__parallel_workers(long n, long grain, int nthreads)
{
    const long chunks = n > 0 ? (n + grain - 1) / grain : 1;
    return chunks < nthreads ? (int)chunks : nthreads;
}

static int parallel_run(long n, long grain, int nthreads, int guided, shl__range_fn fn, void *arg)
{
    const int nw = shl__parallel_workers(n, grain, nthreads);
#ifdef SHL_SERIAL_POOL
    if (nw > 1) return serial_round(n, grain, nw, guided, fn, arg);
#endif
    int own = 0; /* 0 with one worker, or while a call on another thread (or from a worker) owns the pool */
    if (nw > 1) {
        pthread_mutex_lock(&pool_lock);
        own = !pool.busy;
        pool.busy = 1;
        pthread_mutex_unlock(&pool_lock);
    }
    if (!own) {
        if (n > 0) fn(arg, 0, 0, n);
        return SHL_OK;
    }
    /* guided: chunks of 1/(4 nw) of what is left, so that the last ones, and the
     * wait for the slowest worker, are short (OpenMP's guided schedule, halved) */
    loop p = {.next = 0, .n = n, .grain = grain, .split = guided ? 4L * nw : 0, .fn = fn, .arg = arg};
    const int ok = !pthread_mutex_init(&p.lock, NULL);
    const int started = ok && take_workers(nw);
    pthread_mutex_lock(&pool_lock);
    if (started) {
        pool.job = &p;
        pool.round_workers = nw;
        ++pool.round;
        pthread_cond_broadcast(&pool_wake);
        pthread_mutex_unlock(&pool_lock);
        run_chunks(&p, 0); /* returns when every chunk is claimed */
        pthread_mutex_lock(&pool_lock);
        pool.job = NULL; /* workers waking from now on skip this round */
        while (pool.running > 0) pthread_cond_wait(&pool_done, &pool_lock);
    }
    pool.busy = 0;
    pthread_mutex_unlock(&pool_lock);
    if (ok) pthread_mutex_destroy(&p.lock);
    return started ? SHL_OK : SHL_ETHREAD;
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
