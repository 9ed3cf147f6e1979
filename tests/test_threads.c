/* One shl_ctx shared by several threads evaluating at once gives results
 * identical (bit for bit) to single-threaded evaluation.  Run under
 * ThreadSanitizer by `make SANITIZE=thread test-threads`. */
#include "geom.h"
#include "harness.h"
#include "shlight.h"
#include <pthread.h>
#include <string.h>

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
