/* Public entry points: argument validation, status codes, contexts.  Every
 * check happens here, before any output is written. */
#include "polygon.h"
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

int shl_eval_basis(int lmax, const double dir[3], double *y)
{
    if (!dir || !y) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    double u[3];
    const int st = shl__unit(dir, u);
    if (st) return st;
    shl__sh_eval(lmax, u[0], u[1], u[2], y);
    return SHL_OK;
}

int shl_eval_basis_f(int lmax, const float dir[3], float *y)
{
    if (!dir || !y) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const double d[3] = {dir[0], dir[1], dir[2]};
    double u[3], yd[SHL_NCOEFFS(SHL_LMAX_MAX)];
    const int st = shl__unit(d, u);
    if (st) return st;
    shl__sh_eval(lmax, u[0], u[1], u[2], yd);
    for (int k = 0; k < SHL_NCOEFFS(lmax); ++k) y[k] = (float)yd[k];
    return SHL_OK;
}

static int check_polygon_args(const void *x, const void *verts, int n, const void *out)
{
    if (!x || !verts || !out) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    return SHL_OK;
}

int shl_polygon(const shl_ctx *ctx, const double x[3], const double *verts, int n, double *coeffs)
{
    if (!ctx) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    double zh[SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, x, verts, n);
    shl__poly_zh_d(&g, ctx->lmax, zh);
    shl__zh_to_sh(ctx->lmax, zh, coeffs);
    return SHL_OK;
}

/* Float entry points: the geometry is set up in double from the float input,
 * the recurrences run in float (the near-plane planar rule in double, polygon.c),
 * the ZH -> SH reconstruction accumulates in double. */
static int float_polygon_input(const float x[3], const float *verts, int n, double xd[3], double *vd)
{
    if (shl__check_finite_f(x, 3) || shl__check_finite_f(verts, 3 * n)) return SHL_ENONFINITE;
    for (int k = 0; k < 3; ++k) xd[k] = x[k];
    for (int i = 0; i < 3 * n; ++i) vd[i] = verts[i];
    return SHL_OK;
}

int shl_polygon_f(const shl_ctx *ctx, const float x[3], const float *verts, int n, float *coeffs)
{
    if (!ctx) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    double xd[3], vd[3 * SHL_MAX_VERTS];
    if (!st) st = float_polygon_input(x, verts, n, xd, vd);
    if (st) return st;
    shl__poly_geom g;
    float zh[SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, xd, vd, n);
    shl__poly_zh_f(&g, ctx->lmax, zh);
    shl__zh_to_sh_f(ctx->lmax, zh, coeffs);
    return SHL_OK;
}

int shl_polygon_grad(const shl_ctx *ctx, const double x[3], const double *verts, int n,
                     double *coeffs, double *grad)
{
    if (!ctx || !grad) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    double zh[SHL__ZH_BLOCK], zh_grad[3 * SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, x, verts, n);
    shl__poly_zh_grad_d(&g, ctx->lmax, zh, zh_grad);
    shl__zh_to_sh(ctx->lmax, zh, coeffs);
    for (int a = 0; a < 3; ++a) shl__zh_to_sh(ctx->lmax, zh_grad + a * SHL__ZH_BLOCK, grad + a * ctx->nc);
    shl__poly_grad_unscale(&g, grad, 3 * ctx->nc);
    return SHL_OK;
}

int shl_polygon_grad_f(const shl_ctx *ctx, const float x[3], const float *verts, int n,
                       float *coeffs, float *grad)
{
    if (!ctx || !grad) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    double xd[3], vd[3 * SHL_MAX_VERTS];
    if (!st) st = float_polygon_input(x, verts, n, xd, vd);
    if (st) return st;
    shl__poly_geom g;
    float zh[SHL__ZH_BLOCK], zh_grad[3 * SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, xd, vd, n);
    shl__poly_zh_grad_f(&g, ctx->lmax, zh, zh_grad);
    shl__zh_to_sh_f(ctx->lmax, zh, coeffs);
    for (int a = 0; a < 3; ++a) shl__zh_to_sh_f(ctx->lmax, zh_grad + a * SHL__ZH_BLOCK, grad + a * ctx->nc);
    shl__poly_grad_unscale_f(&g, grad, 3 * ctx->nc);
    return SHL_OK;
}

int shl_polygon_solid_angle(const double x[3], const double *verts, int n, double *omega)
{
    int st = check_polygon_args(x, verts, n, omega);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    shl__poly_geom_init(&g, x, verts, n);
    *omega = g.solid_angle;
    return SHL_OK;
}
