/* One shl_ctx shared by several threads evaluating at once gives results
 * identical (bit for bit) to single-threaded evaluation.  Run under
 * ThreadSanitizer by `make SANITIZE=thread test-threads`.  The threaded batch
 * entry points (*_mt) equal their plain calls bit for bit for any thread count. */
#include "geom.h"
#include "harness.h"
#include "internal.h" /* shl__thread_fail_after: the test hook of the SHL_ALLOC_HOOKS build */
#include "parallel.h" /* shl__parallel_for_guided */
#include "shlight.h"
#include <pthread.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

enum { NTHREADS = 4, NCASES = 24, LMAX = 8, NC = SHL_NCOEFFS(LMAX) };

typedef struct {
    double x[3], v[18];
    int n;
} poly_case;

static poly_case cases[NCASES];
static double serial[NCASES][4 * NC];
static double parallel_out[NTHREADS][NCASES][4 * NC];
static const shl_ctx *shared_ctx;

/* out: coefficients (nc) then their gradient (3 nc) */
static void eval_case(const poly_case *c, double *out)
{
    double coeffs[NC];
    shl_polygon(shared_ctx, c->x, c->v, c->n, out);
    shl_polygon_grad(shared_ctx, c->x, c->v, c->n, coeffs, out + NC);
}

static void *worker(void *arg)
{
    const int t = (int)(long)arg;
    for (int i = 0; i < NCASES; ++i) {
        const int k = (i + 5 * t) % NCASES; /* threads walk the cases in different orders */
        eval_case(&cases[k], parallel_out[t][k]);
    }
    return NULL;
}

SHL_TEST(threads_shared_ctx_bit_identical)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(LMAX, &ctx) == SHL_OK);
    shared_ctx = ctx;
    rng_t r = {77};
    for (int i = 0; i < NCASES; ++i) {
        double center[3] = {rng_range(&r, -1, 1), rng_range(&r, -1, 1), 2.0}, nrm[3];
        rng_unit_vector(&r, nrm);
        cases[i].n = 3 + i % 4;
        random_polygon(&r, cases[i].n, i % 2, center, nrm, 1.0, cases[i].v);
        for (int k = 0; k < 3; ++k) cases[i].x[k] = rng_range(&r, -1, 1);
        eval_case(&cases[i], serial[i]);
    }
    pthread_t th[NTHREADS];
    int started = 0;
    for (long t = 0; t < NTHREADS; ++t)
        if (pthread_create(&th[t], NULL, worker, (void *)t) == 0) ++started;
    CHECK(started == NTHREADS);
    for (int t = 0; t < started; ++t) pthread_join(th[t], NULL);
    for (int t = 0; t < started; ++t)
        CHECK(memcmp(parallel_out[t], serial, sizeof serial) == 0);
    shl_ctx_destroy(ctx);
}

/* ---- threaded batch entry points (the *_mt calls) ---- */


enum { BL = 4, BNC = SHL_NCOEFFS(BL), NS = 1000, NL = 300, ND = 40 }; /* NS: 4 blocks of 256; NL: 5 blocks of 64 */

typedef struct {
    shl_ctx *ctx;
    shl_lights *set;
    float tri[9], center[3], radius, spts[3 * NS], lpts[3 * NL];
    double dpts[3 * ND];
} batch_case;

static void batch_case_init(batch_case *b)
{
    CHECK(shl_ctx_create(BL, &b->ctx) == SHL_OK);
    CHECK(shl_lights_create(&b->set) == SHL_OK);
    const double tri[9] = {-1.0, -0.5, 1.0, 1.0, -0.25, 1.25, 0.0, 1.0, 0.75}, c[3] = {0.5, -1.0, -2.0};
    const double rgb1[3] = {1.0, 0.5, 2.0}, rgb2[3] = {0.3, 1.0, -0.5};
    CHECK(shl_lights_add_polygon(b->set, tri, 3, rgb1, 0) == SHL_OK);
    CHECK(shl_lights_add_sphere(b->set, c, 0.4, rgb2) == SHL_OK);
    for (int k = 0; k < 9; ++k) b->tri[k] = (float)tri[k];
    for (int k = 0; k < 3; ++k) b->center[k] = (float)c[k];
    b->radius = 0.4f;
    rng_t r = {2026};
    for (int i = 0; i < 3 * NS; ++i) b->spts[i] = (float)rng_range(&r, -0.5, 0.5);
    for (int i = 0; i < 3 * NL; ++i) b->lpts[i] = (float)rng_range(&r, -0.5, 0.5);
    for (int i = 0; i < 3 * ND; ++i) b->dpts[i] = rng_range(&r, -0.5, 0.5);
}

static void batch_case_free(batch_case *b)
{
    shl_lights_destroy(b->set);
    shl_ctx_destroy(b->ctx);
}

/* Entry point e (0: polygon, 1: sphere, 2: float set, 3: double set) on nthreads
 * threads (0: the plain call), with gradients or not; outputs as bytes. */
static int run_batch(const batch_case *b, int e, int nthreads, int with_grad, void *out, void *grad)
{
    float *fo = out, *fg = with_grad ? grad : NULL;
    double *dout = out, *dg = with_grad ? grad : NULL;
    switch (e) {
    case 0:
        return nthreads ? shl_polygon_batch_f_mt(b->ctx, b->tri, 3, NS, b->spts, fo, fg, nthreads)
                        : shl_polygon_batch_f(b->ctx, b->tri, 3, NS, b->spts, fo, fg);
    case 1:
        return nthreads ? shl_sphere_batch_f_mt(b->ctx, b->center, b->radius, NS, b->spts, fo, fg, nthreads)
                        : shl_sphere_batch_f(b->ctx, b->center, b->radius, NS, b->spts, fo, fg);
    case 2:
        return nthreads ? shl_lights_eval_batch_f_mt(b->ctx, b->set, NL, b->lpts, fo, fg, nthreads)
                        : shl_lights_eval_batch_f(b->ctx, b->set, NL, b->lpts, fo, fg);
    default:
        return nthreads ? shl_lights_eval_batch_mt(b->ctx, b->set, ND, b->dpts, dout, dg, nthreads)
                        : shl_lights_eval_batch(b->ctx, b->set, ND, b->dpts, dout, dg);
    }
}

/* value bytes of entry point e (its gradients take three times as many) */
static size_t out_bytes(int e)
{
    const size_t per = e < 2 ? sizeof(float) * BNC : e == 2 ? sizeof(float) * 3 * BNC : sizeof(double) * 3 * BNC;
    return per * (size_t)(e < 2 ? NS : e == 2 ? NL : ND);
}

static unsigned char ref_v[sizeof(double) * 3 * BNC * ND + sizeof(float) * BNC * NS]; /* >= every out_bytes(e) */
static unsigned char ref_g[3 * sizeof ref_v], got_v[sizeof ref_v + 64], got_g[sizeof ref_g + 64];

/* Every entry point on 1, 2, 3, 8 and SHL_MAX_THREADS threads, with and without
 * gradients, equals its plain call bit for bit (several blocks, the last partial),
 * and writes nothing past its outputs. */
SHL_TEST(threads_batch_mt_bit_identical)
{
    batch_case b;
    batch_case_init(&b);
    const int threads[5] = {1, 2, 3, 8, SHL_MAX_THREADS};
    int bad = 0;
    for (int e = 0; e < 4; ++e)
        for (int wg = 0; wg < 2; ++wg) {
            const size_t nv = out_bytes(e), ng = 3 * nv;
            CHECK(run_batch(&b, e, 0, wg, ref_v, ref_g) == SHL_OK);
            for (int t = 0; t < 5; ++t) {
                memset(got_v, 0xA5, nv + 64);
                memset(got_g, 0xA5, ng + 64);
                CHECK(run_batch(&b, e, threads[t], wg, got_v, got_g) == SHL_OK);
                bad += memcmp(got_v, ref_v, nv) != 0 || (wg && memcmp(got_g, ref_g, ng) != 0);
                for (int k = 0; k < 64; ++k) bad += got_v[nv + k] != 0xA5 || got_g[(wg ? ng : 0) + k] != 0xA5;
            }
        }
    CHECK(bad == 0);
    batch_case_free(&b);
}

/* nthreads outside 1..SHL_MAX_THREADS: SHL_EDOMAIN; each thread creation of a
 * 4-thread call failing in turn: SHL_ETHREAD and nothing written; then the call
 * succeeds with the plain call's results. */
SHL_TEST(threads_batch_mt_failures)
{
    batch_case b;
    batch_case_init(&b);
    int ethread = 0, bad = 0;
    for (int e = 0; e < 4; ++e) {
        const size_t nv = out_bytes(e), ng = 3 * nv;
        CHECK(run_batch(&b, e, 0, 1, ref_v, ref_g) == SHL_OK);
        memset(got_v, 0xA5, nv);
        memset(got_g, 0xA5, ng);
        CHECK(run_batch(&b, e, -1, 1, got_v, got_g) == SHL_EDOMAIN);
        CHECK(run_batch(&b, e, SHL_MAX_THREADS + 1, 1, got_v, got_g) == SHL_EDOMAIN);
        for (long fail = 0; fail < 3; ++fail) {
            shl__thread_fail_after = fail;
            const int st = run_batch(&b, e, 4, 1, got_v, got_g);
            shl__thread_fail_after = -1;
            CHECK(st == SHL_ETHREAD);
            ethread += st == SHL_ETHREAD;
            for (size_t k = 0; k < nv; ++k) bad += got_v[k] != 0xA5;
            for (size_t k = 0; k < ng; ++k) bad += got_g[k] != 0xA5;
        }
        CHECK(run_batch(&b, e, 4, 1, got_v, got_g) == SHL_OK);
        bad += memcmp(got_v, ref_v, nv) != 0 || memcmp(got_g, ref_g, ng) != 0;
    }
    CHECK(bad == 0 && ethread == 12);
    harness_note("%d thread-creation failures handled, nothing written", ethread);
    batch_case_free(&b);
}

/* ---- the process-wide worker pool (src/parallel.c) ---- */

typedef struct {
    const batch_case *b;
    unsigned char v[sizeof(float) * BNC * NS], g[3 * sizeof(float) * BNC * NS];
    int bad;
} pool_caller;

static void *pool_caller_main(void *arg)
{
    pool_caller *c = arg;
    for (int k = 0; k < 20; ++k) {
        c->bad += run_batch(c->b, 0, 2, 1, c->v, c->g) != SHL_OK;
        c->bad += memcmp(c->v, ref_v, sizeof c->v) != 0 || memcmp(c->g, ref_g, sizeof c->g) != 0;
    }
    return NULL;
}

/* Two threads making 2-thread calls at once (one owns the pool, the other then
 * runs alone): every result equals the plain call bit for bit. */
SHL_TEST(threads_pool_concurrent_callers)
{
    static batch_case b;
    static pool_caller callers[2];
    batch_case_init(&b);
    CHECK(run_batch(&b, 0, 0, 1, ref_v, ref_g) == SHL_OK);
    pthread_t th[2];
    int started = 0;
    for (int t = 0; t < 2; ++t) {
        callers[t].b = &b;
        callers[t].bad = 0;
        started += pthread_create(&th[t], NULL, pool_caller_main, &callers[t]) == 0;
    }
    CHECK(started == 2);
    for (int t = 0; t < started; ++t) pthread_join(th[t], NULL);
    CHECK(callers[0].bad == 0 && callers[1].bad == 0);
    batch_case_free(&b);
}

#if defined(__SANITIZE_THREAD__)
#define UNDER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define UNDER_TSAN 1
#endif
#endif

/* A child forked after the pool's workers exist has none of them: its own
 * 2-thread call starts a new pool and equals the plain call (without the fork
 * handler it would wait for the parent's workers forever: alarm ends it).
 * ThreadSanitizer does not allow threads in a child of a threaded process. */
SHL_TEST(threads_pool_fork_child)
{
#ifdef UNDER_TSAN
    harness_note("skipped under ThreadSanitizer (no threads after a threaded fork)");
#else
    batch_case b;
    batch_case_init(&b);
    CHECK(run_batch(&b, 0, 0, 1, ref_v, ref_g) == SHL_OK);
    CHECK(run_batch(&b, 0, 2, 1, got_v, got_g) == SHL_OK);
    const pid_t pid = fork();
    if (pid == 0) {
        alarm(20);
        const size_t nv = out_bytes(0);
        const int ok = run_batch(&b, 0, 2, 1, got_v, got_g) == SHL_OK && !memcmp(got_v, ref_v, nv) &&
                       !memcmp(got_g, ref_g, 3 * nv);
        _exit(ok ? 0 : 1);
    }
    int status = -1;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    batch_case_free(&b);
#endif
}

/* ---- shl__parallel_for_guided (src/parallel.c: the grid interpolation's schedule) ---- */

enum { GUIDED_MAX = 8197, GUIDED_GRAIN = 32 };
static long guided_end[GUIDED_MAX]; /* chunk [b, guided_end[b]) ran (0: no chunk began at b) */
static int guided_visits[GUIDED_MAX];

static void guided_range(void *arg, int worker, long begin, long end)
{
    (void)arg;
    (void)worker;
    guided_end[begin] = end; /* chunks are disjoint: no two workers write one entry */
    for (long i = begin; i < end; ++i) ++guided_visits[i];
}

/* Every item runs exactly once; chunks begin at multiples of the grain, hold at
 * least a grain (the last may hold less), shrink in the order of the items, and
 * the first is about 1/(4 workers) of the items. */
SHL_TEST(threads_parallel_for_guided_chunks)
{
    const long sizes[] = {1, 31, 32, 33, 1000, 8192, GUIDED_MAX};
    int bad = 0, nchunks_8192_2 = 0;
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si)
        for (int nt = 1; nt <= 4; ++nt) {
            const long n = sizes[si];
            memset(guided_end, 0, sizeof guided_end);
            memset(guided_visits, 0, sizeof guided_visits);
            const int nw = shl__parallel_workers(n, GUIDED_GRAIN, nt);
            CHECK(shl__parallel_for_guided(n, GUIDED_GRAIN, nt, guided_range, NULL) == SHL_OK);
            for (long i = 0; i < n; ++i) bad += guided_visits[i] != 1;
            long b = 0, prev = n + 1;
            int nchunks = 0;
            while (b < n && guided_end[b] > b) {
                const long size = guided_end[b] - b;
                bad += b % GUIDED_GRAIN != 0 || size > prev || (size < GUIDED_GRAIN && guided_end[b] != n);
                if (b == 0 && nw > 1) { /* the first claim: (n / 4 nw) rounded down to the grain, at least the grain */
                    const long want = n / (4L * nw) / GUIDED_GRAIN * GUIDED_GRAIN;
                    bad += size != (want > GUIDED_GRAIN ? (want < n ? want : n) : (GUIDED_GRAIN < n ? GUIDED_GRAIN : n));
                }
                prev = size;
                b = guided_end[b];
                ++nchunks;
            }
            bad += b != n;
            if (n == 8192 && nt == 2) nchunks_8192_2 = nchunks;
        }
    CHECK(bad == 0);
    harness_note("8192 items, grain 32, 2 workers: %d chunks (fixed chunks of 32: 256, of 256: 32)", nchunks_8192_2);
}
