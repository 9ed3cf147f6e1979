/* Batched spherical light: argument checks, then the context's SIMD kernel
 * (simd/sphere_batch.h) over all points. */
#include "../simd/batch.h"
#include <math.h>

int shl_sphere_batch_f(const shl_ctx *ctx, const float center[3], float radius, int npts, const float *pts,
                       float *coeffs, float *grad)
{
    if (!ctx || !center || (npts > 0 && (!pts || !coeffs))) return SHL_ENULL;
    if (npts < 0) return SHL_EDOMAIN;
    if (shl__check_finite_f(center, 3) || !isfinite(radius)) return SHL_ENONFINITE;
    if (!(radius > 0.0f)) return SHL_EDOMAIN;
    for (int p = 0; p < npts; ++p)
        if (shl__check_finite_f(pts + 3 * (size_t)p, 3)) return SHL_ENONFINITE;
    if (npts == 0) return SHL_OK;
    void *work = shl__malloc(ctx->isa->sphere_work_bytes(ctx->lmax, grad != NULL));
    if (!work) return SHL_ENOMEM;
    const double c[3] = {center[0], center[1], center[2]};
    ctx->isa->sphere_batch(ctx->lmax, c, radius, npts, pts, coeffs, grad, work);
    shl__free(work);
    return SHL_OK;
}
