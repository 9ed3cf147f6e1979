/* Light sets with second derivatives: as shl__lights_eval (lights.c), each
 * polygon's lobe integrals, their gradient and their Hessian (polygon_hess.c) are
 * accumulated per colour channel and reconstructed once per point (Wang 2018 Eq. 33
 * is linear): 3 x 10 reconstructions per point, in three calls of
 * shl__zh_to_sh_multi.  Spheres are added after, directly in the SH basis
 * (shl__sphere_sh_d, shl__sphere_sh_hess: no lobe integrals to reconstruct). */
#include "lights.h"
#include "polygon.h"
#include "sphere.h"
#include <string.h>

enum { NBLK = SHL__ZH_MULTI }; /* value, 3 gradient, 6 Hessian components, interleaved (polygon.h) */

size_t shl__lights_hess_ws_size(int lmax) { return 4 * (size_t)SHL__Z10_SIZE(lmax); } /* one light, 3 colours */

/* The interleaved lobe integrals of one unit-radiance polygon light at x, unscaled; 0 if it does not reach x. */
static int polygon_zh_hess(const shl_lights *lights, const shl__light *li, int lmax, const double x[3], double *z10)
{
    shl__poly_geom g;
    if (!shl__light_poly_geom(lights, li, x, &g)) return 0;
    const int fold = shl__poly_hess_fold(&g);
    shl__poly_zh_hess_d(&g, lmax, z10, fold);
    if (!fold) /* gradient: 2^-E once, Hessian: twice */
        for (int d = 0; d <= 2 * lmax; ++d)
            for (int l = 0; l <= lmax; ++l) {
                double *o = z10 + SHL__Z10(lmax, d, l);
                shl__poly_grad_unscale(&g, o + 1, NBLK - 1);
                shl__poly_grad_unscale(&g, o + 4, NBLK - 4);
            }
    return 1;
}

/* Sphere light li seen from x, radiance rgb_c, added to the outputs; sh (10 nc doubles)
 * receives its unit-radiance coefficients, gradient and Hessian (as shl_sphere_hess). */
static void add_sphere_hess(const shl__light *li, int lmax, const double x[3], double *sh, double *rgb, double *grad,
                            double *hess)
{
    const int nc = SHL_NCOEFFS(lmax);
    shl__sphere_geom g;
    shl__sphere_geom_init(&g, x, li->center, li->radius);
    shl__sphere_sh_d(lmax, &g, sh, sh + nc);
    shl__sphere_sh_hess(lmax, &g, sh + 4 * nc, nc);
    for (int c = 0; c < 3; ++c) {
        const double s = li->rgb[c];
        for (int k = 0; k < nc; ++k) rgb[c * nc + k] += s * sh[k];
        for (int k = 0; k < 3 * nc; ++k) grad[c * 3 * nc + k] += s * sh[nc + k];
        for (int k = 0; k < 6 * nc; ++k) hess[c * 6 * nc + k] += s * sh[4 * nc + k];
    }
}

void shl__lights_eval_hess(const shl_lights *lights, int lmax, double *ws, const double x[3], double *rgb,
                           double *grad, double *hess)
{
    const int nc = SHL_NCOEFFS(lmax);
    const size_t na = (size_t)SHL__Z10_SIZE(lmax);
    double *z10 = ws, *acc = ws + na; /* colour c at c * na */
    memset(acc, 0, sizeof(double) * 3 * na);
    for (int i = 0; i < lights->count; ++i) {
        const shl__light *li = &lights->items[i];
        if (li->kind != SHL__LIGHT_POLYGON || !polygon_zh_hess(lights, li, lmax, x, z10)) continue;
        for (int c = 0; c < 3; ++c) {
            const double s = li->rgb[c];
            double *dst = acc + c * na;
            for (size_t j = 0; j < na; ++j) dst[j] += s * z10[j];
        }
    }
    for (int c = 0; c < 3; ++c) {
        double *g = grad + c * 3 * nc, *h = hess + c * 6 * nc;
        double *const out[SHL__ZH_MULTI] = {rgb + c * nc, g,          g + nc,     g + 2 * nc, h,
                                            h + nc,       h + 2 * nc, h + 3 * nc, h + 4 * nc, h + 5 * nc};
        shl__zh_to_sh_multi(lmax, acc + c * na, out);
    }
    for (int i = 0; i < lights->count; ++i) /* z10 (na >= 10 nc doubles) free again */
        if (lights->items[i].kind == SHL__LIGHT_SPHERE) add_sphere_hess(&lights->items[i], lmax, x, z10, rgb, grad, hess);
}

int shl_lights_eval_hess(const shl_ctx *ctx, const shl_lights *lights, const double x[3], double *rgb,
                         double *grad, double *hess)
{
    if (!ctx || !lights || !x || !rgb || !grad || !hess) return SHL_ENULL;
    if (shl__check_finite(x, 3)) return SHL_ENONFINITE;
    double *ws = shl__malloc(sizeof(double) * shl__lights_hess_ws_size(ctx->lmax));
    if (!ws) return SHL_ENOMEM;
    shl__lights_eval_hess(lights, ctx->lmax, ws, x, rgb, grad, hess);
    shl__free(ws);
    return SHL_OK;
}
