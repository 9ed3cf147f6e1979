/* Light sets (Wu et al. 2020, Alg. 1 lines 5-7): the lights' contributions add
 * linearly.  Since the ZH -> SH reconstruction (Wang 2018 Eq. 33) is linear and
 * every polygon uses the same lobe directions, the per-light ZH integrals (and
 * their gradients) are accumulated per colour channel and reconstructed once
 * per point: 3 x 4 reconstructions instead of 4 per light. */
#include "lights.h"
#include "polygon.h"
#include <limits.h>
#include <stdint.h>
#include <string.h>

/* Accumulator block: lobes d <= 2 lmax, bands l <= lmax, ZH layout zh[d * SHL__ZH_STRIDE + l]. */
static size_t acc_block(int lmax) { return (size_t)(2 * lmax) * SHL__ZH_STRIDE + (size_t)lmax + 1; }

size_t shl__lights_ws_size(int lmax) { return 4 * (size_t)SHL__ZH_BLOCK + 12 * acc_block(lmax); }

static double front_distance(const shl__light *li, const double *v0, const double x[3])
{
    return li->normal[0] * (x[0] - v0[0]) + li->normal[1] * (x[1] - v0[1]) + li->normal[2] * (x[2] - v0[2]);
}

/* ZH integrals of one unit-radiance light at x into zh (and, with_grad, the
 * gradient blocks after it); 0 if the light does not reach x. */
static int light_zh(const shl_lights *lights, const shl__light *li, int lmax, const double x[3],
                    double *zh, int with_grad)
{
    switch (li->kind) {
    case SHL__LIGHT_POLYGON: {
        const double *v = lights->verts + li->vofs;
        if (!li->two_sided && !(front_distance(li, v, x) > 0.0)) return 0; /* behind or in its plane */
        shl__poly_geom g;
        shl__poly_geom_init(&g, x, v, li->n);
        if (with_grad)
            shl__poly_zh_grad_d(&g, lmax, zh, zh + SHL__ZH_BLOCK);
        else
            shl__poly_zh_d(&g, lmax, zh);
        return 1;
    }
    }
    return 0;
}

void shl__lights_eval(const shl_lights *lights, int lmax, double *ws, const double x[3],
                      double *rgb, double *grad)
{
    const int nc = SHL_NCOEFFS(lmax), nblk = grad ? 4 : 1, ndir = 2 * lmax + 1;
    const size_t nb = acc_block(lmax);
    double *zh = ws;                          /* one light: ZH, then d/dx, d/dy, d/dz blocks */
    double *acc = ws + 4 * SHL__ZH_BLOCK;     /* colour c, block b at (c * nblk + b) * nb */
    memset(acc, 0, sizeof(double) * 3 * (size_t)nblk * nb);
    for (int i = 0; i < lights->count; ++i) {
        const shl__light *li = &lights->items[i];
        if (!light_zh(lights, li, lmax, x, zh, grad != NULL)) continue;
        for (int b = 0; b < nblk; ++b) {
            const double *src = zh + (size_t)b * SHL__ZH_BLOCK;
            for (int c = 0; c < 3; ++c) {
                double *dst = acc + ((size_t)c * nblk + b) * nb;
                const double s = li->rgb[c];
                for (int d = 0; d < ndir; ++d)
                    for (int l = 0; l <= lmax; ++l) dst[d * SHL__ZH_STRIDE + l] += s * src[d * SHL__ZH_STRIDE + l];
            }
        }
    }
    for (int c = 0; c < 3; ++c) {
        shl__zh_to_sh(lmax, acc + (size_t)c * nblk * nb, rgb + c * nc);
        for (int a = 0; grad && a < 3; ++a)
            shl__zh_to_sh(lmax, acc + ((size_t)c * nblk + 1 + a) * nb, grad + (c * 3 + a) * nc);
    }
}

int shl_lights_create(shl_lights **out)
{
    if (!out) return SHL_ENULL;
    shl_lights *l = shl__calloc(1, sizeof *l);
    if (!l) return SHL_ENOMEM;
    *out = l;
    return SHL_OK;
}

void shl_lights_destroy(shl_lights *lights)
{
    if (!lights) return;
    shl__free(lights->items);
    shl__free(lights->verts);
    shl__free(lights);
}

int shl_lights_count(const shl_lights *lights) { return lights ? lights->count : SHL_ENULL; }

/* Room for one more record and `ndoubles` more vertex coordinates; on failure nothing changes. */
static int reserve(shl_lights *l, size_t ndoubles)
{
    if (l->count == INT_MAX / 2 || ndoubles > SIZE_MAX / (4 * sizeof(double)) - l->nverts) return SHL_ENOMEM;
    if (l->count == l->cap) {
        const int cap = l->cap ? 2 * l->cap : 8;
        if ((size_t)cap > SIZE_MAX / sizeof(shl__light)) return SHL_ENOMEM;
        shl__light *items = shl__malloc(sizeof *items * (size_t)cap);
        if (!items) return SHL_ENOMEM;
        if (l->count) memcpy(items, l->items, sizeof *items * (size_t)l->count);
        shl__free(l->items);
        l->items = items;
        l->cap = cap;
    }
    if (l->nverts + ndoubles > l->vcap) {
        size_t cap = l->vcap ? 2 * l->vcap : 8 * 3 * 4;
        while (cap < l->nverts + ndoubles) cap *= 2;
        double *verts = shl__malloc(sizeof *verts * cap);
        if (!verts) return SHL_ENOMEM;
        if (l->nverts) memcpy(verts, l->verts, sizeof *verts * l->nverts);
        shl__free(l->verts);
        l->verts = verts;
        l->vcap = cap;
    }
    return SHL_OK;
}

int shl_lights_add_polygon(shl_lights *lights, const double *verts, int n, const double rgb[3], int two_sided)
{
    if (!lights || !verts || !rgb) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    if (two_sided != 0 && two_sided != 1) return SHL_EDOMAIN;
    if (shl__check_finite(verts, 3 * n) || shl__check_finite(rgb, 3)) return SHL_ENONFINITE;
    const int st = reserve(lights, 3 * (size_t)n);
    if (st) return st;
    shl__light *li = &lights->items[lights->count];
    li->kind = SHL__LIGHT_POLYGON;
    li->two_sided = two_sided;
    memcpy(li->rgb, rgb, sizeof li->rgb);
    li->n = n;
    li->vofs = lights->nverts;
    li->normal[0] = li->normal[1] = li->normal[2] = 0.0;
    for (int i = 1; i + 1 < n; ++i) { /* Newell normal as a fan from v_0: exact for a triangle */
        const double *p = verts + 3 * i, *q = verts + 3 * (i + 1);
        const double e[3] = {p[0] - verts[0], p[1] - verts[1], p[2] - verts[2]};
        const double f[3] = {q[0] - verts[0], q[1] - verts[1], q[2] - verts[2]};
        li->normal[0] += e[1] * f[2] - e[2] * f[1];
        li->normal[1] += e[2] * f[0] - e[0] * f[2];
        li->normal[2] += e[0] * f[1] - e[1] * f[0];
    }
    memcpy(lights->verts + lights->nverts, verts, sizeof(double) * 3 * (size_t)n);
    lights->nverts += 3 * (size_t)n;
    ++lights->count;
    return SHL_OK;
}

static int check_eval(const shl_ctx *ctx, const shl_lights *lights, const void *x, const double *rgb)
{
    return (!ctx || !lights || !x || !rgb) ? SHL_ENULL : SHL_OK;
}

int shl_lights_eval(const shl_ctx *ctx, const shl_lights *lights, const double x[3], double *rgb, double *grad)
{
    int st = check_eval(ctx, lights, x, rgb);
    if (st) return st;
    if (shl__check_finite(x, 3)) return SHL_ENONFINITE;
    double *ws = shl__malloc(sizeof(double) * shl__lights_ws_size(ctx->lmax));
    if (!ws) return SHL_ENOMEM;
    shl__lights_eval(lights, ctx->lmax, ws, x, rgb, grad);
    shl__free(ws);
    return SHL_OK;
}

int shl_lights_eval_batch(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts,
                          double *rgb, double *grad)
{
    int st = check_eval(ctx, lights, pts, rgb);
    if (st) return st;
    if (npts < 0) return SHL_EDOMAIN;
    for (int p = 0; p < npts; ++p)
        if (shl__check_finite(pts + 3 * (size_t)p, 3)) return SHL_ENONFINITE;
    double *ws = shl__malloc(sizeof(double) * shl__lights_ws_size(ctx->lmax));
    if (!ws) return SHL_ENOMEM;
    const size_t nc = (size_t)ctx->nc;
    for (int p = 0; p < npts; ++p)
        shl__lights_eval(lights, ctx->lmax, ws, pts + 3 * (size_t)p, rgb + 3 * nc * p, grad ? grad + 9 * nc * p : NULL);
    shl__free(ws);
    return SHL_OK;
}
