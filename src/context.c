/* Public entry points: argument validation, status codes, contexts.  Every
 * check happens here, before any output is written. */
#include "polygon.h"
#include "sh_basis.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

/* Infinite or NaN: all exponent bits set, i.e. adding one unit to the exponent field carries
 * into the sign bit.  Blocks of 16 (a fixed count: gcc -O2 vectorizes them), then the rest. */
int shl__check_finite(const double *v, size_t count)
{
    const uint64_t exp = 0x7ff0000000000000u, one = 0x0010000000000000u;
    uint64_t bad = 0;
    size_t i = 0;
    for (; i + 16 <= count; i += 16) {
        uint64_t u[16];
        memcpy(u, v + i, sizeof u);
        for (int k = 0; k < 16; ++k) bad |= (u[k] & exp) + one;
    }
    for (; i < count; ++i) {
        uint64_t u;
        memcpy(&u, v + i, sizeof u);
        bad |= (u & exp) + one;
    }
    return bad >> 63 ? SHL_ENONFINITE : SHL_OK;
}

int shl__check_finite_f(const float *v, size_t count)
{
    const uint32_t exp = 0x7f800000u, one = 0x00800000u;
    uint32_t bad = 0;
    size_t i = 0;
    for (; i + 16 <= count; i += 16) {
        uint32_t u[16];
        memcpy(u, v + i, sizeof u);
        for (int k = 0; k < 16; ++k) bad |= (u[k] & exp) + one;
    }
    for (; i < count; ++i) {
        uint32_t u;
        memcpy(&u, v + i, sizeof u);
        bad |= (u & exp) + one;
    }
    return bad >> 31 ? SHL_ENONFINITE : SHL_OK;
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
