/* Batched spherical light: argument checks, then the context's SIMD kernel
 * (simd/sphere_batch.h) over all points.  Light sets (src/lights_batch.c)
 * share shl__batch_sphere_eval. */
#include "parallel.h"
#include "sphere.h"
#include <math.h>

/* The kernel sets each lane's cap up in double without rescaling, and stores
 * 1/|center - x| as a float: |center - x|^2 must stay within the double range for
 * float points x, and |center - x| > radius within the float range.  Both hold
 * when every centre coordinate is 0 or within 2^-126..2^126 in magnitude (then
 * 2^-178 <= |center - x| < 2^129 wherever center != x: both are multiples of
 * 2^-178) and 2^-126 <= radius <= 2^126.  Other spheres (radii below float's
 * normal range included) take the scalar float path per point. */
static int kernel_range(const double center[3], double radius)
{
    for (int k = 0; k < 3; ++k) {
        const double a = fabs(center[k]);
        if (a > 0x1p126 || (a != 0.0 && a < 0x1p-126)) return 0;
    }
    return radius >= 0x1p-126 && radius <= 0x1p126;
}

void shl__batch_sphere_eval(const shl_ctx *ctx, const double center[3], double radius, int npts, const float *pts,
                            float *coeffs, float *grad, void *work)
{
    if (kernel_range(center, radius)) {
        ctx->isa->sphere_batch(ctx->lmax, center, radius, npts, pts, coeffs, grad, work);
        return;
    }
    const size_t nc = (size_t)ctx->nc;
    for (int p = 0; p < npts; ++p) { /* as shl_sphere_grad_f: geometry in double, scaled */
        const double x[3] = {pts[3 * p], pts[3 * p + 1], pts[3 * p + 2]};
        shl__sphere_geom g;
        shl__sphere_geom_init(&g, x, center, radius);
        shl__sphere_sh_f(ctx->lmax, &g, coeffs + nc * p, grad ? grad + 3 * nc * p : NULL);
    }
}

typedef struct {
    double center[3], radius;
} sphere_light;

static void sphere_eval(const shl_ctx *ctx, const void *light, int npts, const float *pts, float *coeffs, float *grad,
                        void *work)
{
    const sphere_light *s = light;
    shl__batch_sphere_eval(ctx, s->center, s->radius, npts, pts, coeffs, grad, work);
}

int shl_sphere_batch_f_mt(const shl_ctx *ctx, const float center[3], float radius, int npts, const float *pts,
                          float *coeffs, float *grad, int nthreads)
{
    if (!ctx || !center || (npts > 0 && (!pts || !coeffs))) return SHL_ENULL;
    if (npts < 0 || shl__check_threads(nthreads)) return SHL_EDOMAIN;
    if (shl__check_finite_f(center, 3) || !isfinite(radius)) return SHL_ENONFINITE;
    if (!(radius > 0.0f)) return SHL_EDOMAIN;
    if (shl__check_finite_f(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    if (npts == 0) return SHL_OK;
    const sphere_light s = {{center[0], center[1], center[2]}, radius};
    return shl__batch_run(ctx, sphere_eval, &s, ctx->isa->sphere_work_bytes(ctx->lmax, grad != NULL), npts, pts, coeffs,
                          grad, nthreads);
}

int shl_sphere_batch_f(const shl_ctx *ctx, const float center[3], float radius, int npts, const float *pts,
                       float *coeffs, float *grad)
{
    return shl_sphere_batch_f_mt(ctx, center, radius, npts, pts, coeffs, grad, 1);
}
