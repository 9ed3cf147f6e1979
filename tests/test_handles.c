/* Handles: every *_create sets its out-pointer to NULL on every failure (bad
 * arguments, injected allocation failures), the documented exception to "on
 * error no output is written" (include/shlight.h), so cleanup code may destroy
 * the handle unconditionally.  Each call starts from a non-NULL garbage value. */
#include "harness.h"
#include "shlight.h"
#include <math.h>
#include <stddef.h>

#include "internal.h" /* shl__alloc_fail_after (src/alloc.c, built with SHL_ALLOC_HOOKS) */

static char garbage_obj; /* its address is the garbage value: non-NULL, never a real handle */
#define GARBAGE(type) ((type *)(void *)&garbage_obj)

/* Create with allocation k failing, for k = 0, 1, ... until the call succeeds:
 * every failure must return SHL_ENOMEM with *out = NULL.  Returns the number of
 * failing allocations seen (the count of allocations on the success path). */
#define CHECK_ALLOC_FAILURES(type, call, out, destroy, nallocs)                 \
    do {                                                                      \
        long k_ = 0;                                                          \
        for (;; ++k_) {                                                       \
            out = GARBAGE(type);                                              \
            shl__alloc_fail_after = k_;                                       \
            const int st_ = (call);                                           \
            shl__alloc_fail_after = -1;                                       \
            if (st_ == SHL_OK) break;                                         \
            CHECK(st_ == SHL_ENOMEM && out == NULL);                          \
            if (out != GARBAGE(type)) destroy(out); /* the cleanup idiom */  \
            if (k_ > 16) break;                                               \
        }                                                                     \
        CHECK(k_ == (nallocs) && out != NULL && out != GARBAGE(type));        \
        if (out != GARBAGE(type)) destroy(out);                               \
        harness_note("%s: %ld allocation failures -> NULL", #call, k_);       \
    } while (0)

SHL_TEST(handles_ctx_create_null_on_failure)
{
    shl_ctx *ctx = GARBAGE(shl_ctx);
    CHECK(shl_ctx_create(4, NULL) == SHL_ENULL);
    const int bad_lmax[3] = {-1, SHL_LMAX_MAX + 1, -1000000};
    for (int i = 0; i < 3; ++i) {
        ctx = GARBAGE(shl_ctx);
        CHECK(shl_ctx_create(bad_lmax[i], &ctx) == SHL_ELMAX && ctx == NULL);
        if (ctx != GARBAGE(shl_ctx)) shl_ctx_destroy(ctx); /* the cleanup idiom */
    }
    CHECK_ALLOC_FAILURES(shl_ctx, shl_ctx_create(4, &ctx), ctx, shl_ctx_destroy, 1);
}

SHL_TEST(handles_lights_create_null_on_failure)
{
    shl_lights *l;
    CHECK(shl_lights_create(NULL) == SHL_ENULL);
    CHECK_ALLOC_FAILURES(shl_lights, shl_lights_create(&l), l, shl_lights_destroy, 1);
}

SHL_TEST(handles_grid_create_null_on_failure)
{
    shl_ctx *ctx;
    CHECK(shl_ctx_create(2, &ctx) == SHL_OK);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, nan3[3] = {0, NAN, 0};
    const double hi_den[3] = {1, 0x1p-1074, 1}, huge_lo[3] = {-1e308, 0, 0}, huge_hi[3] = {1e308, 1, 1};
    const int res[3] = {2, 3, 2}, res1[3] = {2, 1, 2}, resbig[3] = {2, SHL_GRID_RES_MAX + 1, 2};
    struct {
        const shl_ctx *ctx;
        const double *lo, *hi;
        const int *res;
        int storage, want;
    } bad[] = {
        {NULL, lo, hi, res, SHL_GRID_FLOAT, SHL_ENULL},
        {ctx, NULL, hi, res, SHL_GRID_FLOAT, SHL_ENULL},
        {ctx, lo, NULL, res, SHL_GRID_FLOAT, SHL_ENULL},
        {ctx, lo, hi, NULL, SHL_GRID_FLOAT, SHL_ENULL},
        {ctx, lo, hi, res, 7, SHL_EDOMAIN},
        {ctx, nan3, hi, res, SHL_GRID_DOUBLE, SHL_ENONFINITE},
        {ctx, lo, hi, res1, SHL_GRID_FLOAT, SHL_EDOMAIN},
        {ctx, lo, hi, resbig, SHL_GRID_FLOAT, SHL_EDOMAIN},
        {ctx, hi, lo, res, SHL_GRID_FLOAT, SHL_EDOMAIN},
        {ctx, lo, hi_den, res, SHL_GRID_FLOAT, SHL_EDOMAIN},
        {ctx, huge_lo, huge_hi, res, SHL_GRID_FLOAT, SHL_EDOMAIN},
    };
    shl_grid *g;
    CHECK(shl_grid_create(ctx, lo, hi, res, SHL_GRID_FLOAT, NULL) == SHL_ENULL);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        g = GARBAGE(shl_grid);
        const int st = shl_grid_create(bad[i].ctx, bad[i].lo, bad[i].hi, bad[i].res, bad[i].storage, &g);
        if (st != bad[i].want || g != NULL) harness_fail(__FILE__, __LINE__, "case %zu: status %d (want %d), *out %p", i, st, bad[i].want, (void *)g);
        if (g != GARBAGE(shl_grid)) shl_grid_destroy(g);
    }
    /* two allocations: the grid record and its node array */
    CHECK_ALLOC_FAILURES(shl_grid, shl_grid_create(ctx, lo, hi, res, SHL_GRID_DOUBLE, &g), g, shl_grid_destroy, 2);
    shl_ctx_destroy(ctx);
}

SHL_TEST(handles_brdf_table_create_null_on_failure)
{
    const shl_brdf ok = {SHL_BRDF_PHONG, 0.5, 0.5, 0, 0, 10.0};
    shl_brdf bad_model = ok, bad_kd = ok, nan_exp = ok;
    bad_model.model = 7;
    bad_kd.kd = -0.1;
    nan_exp.exponent = NAN;
    const shl_brdf bad_alpha = {SHL_BRDF_GGX, 0.5, 0.5, 1e-4, 0.0, 0};
    struct {
        int lmax;
        const shl_brdf *brdf;
        int ntheta, want;
    } bad[] = {
        {4, NULL, 90, SHL_ENULL},
        {-1, &ok, 90, SHL_ELMAX},
        {SHL_LMAX_MAX + 1, &ok, 90, SHL_ELMAX},
        {4, &ok, 1, SHL_EDOMAIN},
        {4, &ok, 1025, SHL_EDOMAIN},
        {4, &bad_model, 90, SHL_EDOMAIN},
        {4, &bad_kd, 90, SHL_EDOMAIN},
        {4, &nan_exp, 90, SHL_ENONFINITE},
        {4, &bad_alpha, 90, SHL_EDOMAIN},
    };
    shl_brdf_table *t;
    CHECK(shl_brdf_table_create(4, &ok, 90, NULL) == SHL_ENULL);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        t = GARBAGE(shl_brdf_table);
        const int st = shl_brdf_table_create(bad[i].lmax, bad[i].brdf, bad[i].ntheta, &t);
        if (st != bad[i].want || t != NULL) harness_fail(__FILE__, __LINE__, "case %zu: status %d (want %d), *out %p", i, st, bad[i].want, (void *)t);
        if (t != GARBAGE(shl_brdf_table)) shl_brdf_table_destroy(t);
    }
    /* two allocations: the table record and its data */
    CHECK_ALLOC_FAILURES(shl_brdf_table, shl_brdf_table_create(2, &ok, 3, &t), t, shl_brdf_table_destroy, 2);
}
