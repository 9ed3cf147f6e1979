/* Public entry points: argument validation, status codes, contexts.  Every
 * check happens here, before any output is written. */
#include "polygon.h"
#include "sh_basis.h"
#include <math.h>
#include <stdlib.h>

const char *shl_strerror(int status)
{
    switch (status) {
    case SHL_OK: return "success";
    case SHL_ENULL: return "a required pointer argument is NULL";
    case SHL_ELMAX: return "lmax out of range";
    case SHL_ENVERTS: return "polygon vertex count out of range";
    case SHL_ENONFINITE: return "non-finite (NaN or infinite) input";
    case SHL_ENOMEM: return "out of memory";
    case SHL_EDOMAIN: return "argument outside its domain";
    case SHL_ETHREAD: return "thread creation failed";
    default: return "unknown status code";
    }
}

int shl__check_finite(const double *v, int count)
{
    for (int i = 0; i < count; ++i)
        if (!isfinite(v[i])) return SHL_ENONFINITE;
    return SHL_OK;
}

int shl__check_finite_f(const float *v, int count)
{
    for (int i = 0; i < count; ++i)
        if (!isfinite(v[i])) return SHL_ENONFINITE;
    return SHL_OK;
}

/* A context with the kernels of isa (NULL: unknown or unsupported, SHL_EDOMAIN). */
static int ctx_create(int lmax, const shl__isa *isa, shl_ctx **out)
{
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (!isa) return SHL_EDOMAIN;
    shl_ctx *ctx = shl__calloc(1, sizeof *ctx);
    if (!ctx) return SHL_ENOMEM;
    ctx->lmax = lmax;
    ctx->nc = SHL_NCOEFFS(lmax);
    ctx->isa = isa;
    *out = ctx;
    return SHL_OK;
}

int shl_ctx_create(int lmax, shl_ctx **out)
{
    if (!out) return SHL_ENULL;
    *out = NULL; /* on every failure (the exception in shlight.h) */
    return ctx_create(lmax, shl__isa_select(), out);
}

int shl_ctx_create_isa(int lmax, const char *isa, shl_ctx **out)
{
    if (!out) return SHL_ENULL;
    *out = NULL; /* on every failure (the exception in shlight.h) */
    if (!isa) return SHL_ENULL;
    return ctx_create(lmax, shl__isa_find(isa), out);
}

void shl_ctx_destroy(shl_ctx *ctx) { shl__free(ctx); }

int shl_ctx_lmax(const shl_ctx *ctx) { return ctx ? ctx->lmax : SHL_ENULL; }
