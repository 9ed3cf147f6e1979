/* Light sets (Wu et al. 2020, Alg. 1 lines 5-7): the lights' contributions add
 * linearly.  Since the ZH -> SH reconstruction (Wang 2018 Eq. 33) is linear and
 * every light's lobe integrals use the same lobe directions, the per-light ZH
 * integrals (and their gradients) are accumulated per colour channel and
 * reconstructed once per point: 3 x 4 reconstructions instead of 4 per light.
 * Spheres (HVL Sec. 4.2) produce the same lobe integrals by Funk-Hecke. */
#include "lights.h"
#include "polygon.h"
#include "sphere.h"
#include "zh_tables.h"
#include <limits.h>
#include <stdint.h>
#include <string.h>

/* Accumulator block: lobes d <= 2 lmax, bands l <= lmax, ZH layout zh[d * SHL__ZH_STRIDE + l]. */
static size_t acc_block(int lmax) { return (size_t)(2 * lmax) * SHL__ZH_STRIDE + (size_t)lmax + 1; }

size_t shl__lights_ws_size(int lmax) { return 4 * (size_t)SHL__ZH_BLOCK + 12 * acc_block(lmax); }

double shl__light_front_distance(const shl__light *li, const double *v0, const double x[3])
{
    const int e = shl__scale_exponent(v0, x, 1);
    if (e == INT_MIN) return 0.0; /* x = v_0: in the plane */
    double d = 0.0;
    for (int k = 0; k < 3; ++k) d += li->normal[k] * shl__diff_scaled(x[k], v0[k], -e);
    return d;
}

/* Lobe integrals of a unit-radiance sphere seen from x, layout of shl__poly_zh_grad_d.
 * By Funk-Hecke the integral of P_l(dir_d . w) over the cap {w : u . w >= cos a}
 * is P_l(dir_d . u) w_l, w_l = 2 pi int_{cos a}^1 P_l (shl__cap_weights_d, free
 * of cancellation for small caps), so zh[d][l] = K_l w_l P_l(z_d), z_d = dir_d . u,
 * K_l = sqrt((2l+1)/(4 pi)).  Gradient (product rule, as in shl__sphere_sh_d):
 *   d zh[d][l]/dx = K_l (w_l' P_l(z_d) d cos a/dx + w_l P_l'(z_d) d z_d/dx),
 *   d cos a/dx = -k_alpha u,   d z_d/dx = -(dir_d - z_d u) / |center - x|.
 * Inside or on the sphere: the whole sphere of directions (only band 0, constant). */
static void sphere_zh(const shl__light *li, int lmax, const double x[3], double *zh, double *zh_grad)
{
    const int ndir = 2 * lmax + 1;
    shl__sphere_geom g;
    shl__sphere_geom_init(&g, x, li->center, li->radius);
    if (g.inside) {
        const double full = sqrt(4.0 * M_PI); /* integral of Y_00 over all directions */
        for (int d = 0; d < ndir; ++d)
            for (int l = 0; l <= lmax; ++l) zh[d * SHL__ZH_STRIDE + l] = l == 0 ? full : 0.0;
        for (int a = 0; zh_grad && a < 3; ++a)
            for (int d = 0; d < ndir; ++d)
                for (int l = 0; l <= lmax; ++l) zh_grad[a * SHL__ZH_BLOCK + d * SHL__ZH_STRIDE + l] = 0.0;
        return;
    }
    double w[SHL_LMAX_MAX + 1], dw[SHL_LMAX_MAX + 1], kw[SHL_LMAX_MAX + 1], kdw[SHL_LMAX_MAX + 1];
    double wx[SHL_LMAX_MAX + 1], kwg[SHL_LMAX_MAX + 1];
    shl__cap_weights_d(lmax, g.t, g.s2, g.c, w, zh_grad ? dw : NULL);
    /* sin^2 a below SHL__S2_TINY_D: the gradient in units of s2_x = sin^2 a 2^-s2_e
     * (w_l and k_alpha are proportional to sin^2 a; dw_l is not), scaled back by
     * x_scale, as sphere_grad_tiny (sphere_impl.h); the values as before */
    const int tiny = zh_grad && g.s2_e && g.s2 < SHL__S2_TINY_D;
    if (tiny) shl__cap_weights_d(lmax, g.t_x, g.s2_x, g.c, wx, NULL);
    const double ka = tiny ? g.k_alpha_x : g.k_alpha_s, *gs = tiny ? g.x_scale : g.grad_scale;
    for (int l = 0; l <= lmax; ++l) {
        const double k = sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
        kw[l] = k * w[l];
        if (zh_grad) {
            kdw[l] = k * dw[l] * ka; /* -(d zh / d cos a)(d cos a / dx) . u */
            kwg[l] = tiny ? k * wx[l] : kw[l];
        }
    }
    for (int d = 0; d < ndir; ++d) {
        const double *dir = shl__zh_dir[d];
        const double z = fmin(1.0, fmax(-1.0, shl__dot3(dir, g.u)));
        double *out = zh + d * SHL__ZH_STRIDE;
        double p_prev = 0.0, p = 1.0, dp_prev = 0.0, dp = 0.0; /* P_{l-1}, P_l, P'_{l-1}, P'_l at l = 0 */
        if (!zh_grad) {
            for (int l = 0; l <= lmax; ++l) {
                out[l] = kw[l] * p;
                const double p_next = ((2.0 * l + 1.0) * z * p - l * p_prev) / (l + 1.0);
                p_prev = p;
                p = p_next;
            }
            continue;
        }
        const double tan_dir[3] = {(dir[0] - z * g.u[0]) * g.inv_d_s, (dir[1] - z * g.u[1]) * g.inv_d_s,
                                   (dir[2] - z * g.u[2]) * g.inv_d_s}; /* -d z_d / dx, scaled units */
        double *og = zh_grad + d * SHL__ZH_STRIDE;
        for (int l = 0; l <= lmax; ++l) {
            out[l] = kw[l] * p;
            const double radial = kdw[l] * p, tang = kwg[l] * dp;
            for (int a = 0; a < 3; ++a) /* back from scaled units (internal.h) */
                og[a * SHL__ZH_BLOCK + l] = (-radial * g.u[a] - tang * tan_dir[a]) * gs[0] * gs[1];
            const double p_next = ((2.0 * l + 1.0) * z * p - l * p_prev) / (l + 1.0);
            const double dp_next = dp_prev + (2.0 * l + 1.0) * p; /* P'_{l+1} = P'_{l-1} + (2l+1) P_l */
            p_prev = p;
            p = p_next;
            dp_prev = dp;
            dp = dp_next;
        }
    }
}

/* ZH integrals of one unit-radiance light at x into zh (and, with_grad, the
 * gradient blocks after it); 0 if the light does not reach x. */
static int light_zh(const shl_lights *lights, const shl__light *li, int lmax, const double x[3],
                    double *zh, int with_grad)
{
    switch (li->kind) {
    case SHL__LIGHT_POLYGON: {
        shl__poly_geom g;
        if (!shl__light_poly_geom(lights, li, x, &g)) return 0;
        if (with_grad) {
            shl__poly_zh_grad_d(&g, lmax, zh, zh + SHL__ZH_BLOCK);
            for (int a = 1; a <= 3; ++a) /* lobes d <= 2 lmax, bands l <= lmax of each block */
                for (int d = 0; d <= 2 * lmax; ++d)
                    shl__poly_grad_unscale(&g, zh + a * SHL__ZH_BLOCK + d * SHL__ZH_STRIDE, lmax + 1);
        } else
            shl__poly_zh_d(&g, lmax, zh);
        return 1;
    }
    case SHL__LIGHT_SPHERE: /* emits in every direction: no one-sided case */
        sphere_zh(li, lmax, x, zh, with_grad ? zh + SHL__ZH_BLOCK : NULL);
        return 1;
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
    *out = NULL; /* on failure (the exception in shlight.h) */
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
    memset(li, 0, sizeof *li);
    li->kind = SHL__LIGHT_POLYGON;
    li->two_sided = two_sided;
    memcpy(li->rgb, rgb, sizeof li->rgb);
    li->n = n;
    li->vofs = lights->nverts;
    shl__newell_scaled(verts, n, li->normal); /* a fan from v_0: exact for a triangle */
    memcpy(lights->verts + lights->nverts, verts, sizeof(double) * 3 * (size_t)n);
    lights->nverts += 3 * (size_t)n;
    ++lights->count;
    return SHL_OK;
}

int shl_lights_add_sphere(shl_lights *lights, const double center[3], double radius, const double rgb[3])
{
    if (!lights || !center || !rgb) return SHL_ENULL;
    if (shl__check_finite(center, 3) || shl__check_finite(rgb, 3) || !isfinite(radius)) return SHL_ENONFINITE;
    if (!(radius > 0.0)) return SHL_EDOMAIN;
    const int st = reserve(lights, 0);
    if (st) return st;
    shl__light *li = &lights->items[lights->count];
    memset(li, 0, sizeof *li);
    li->kind = SHL__LIGHT_SPHERE;
    li->two_sided = 1;
    memcpy(li->rgb, rgb, sizeof li->rgb);
    memcpy(li->center, center, sizeof li->center);
    li->radius = radius;
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
