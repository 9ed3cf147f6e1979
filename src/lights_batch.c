/* Light sets at many shading points in float, through the SIMD kernels: for
 * each light, the points it reaches are gathered (a one-sided polygon reaches
 * the points in front of it, by the double test of shl_lights_eval), run through
 * the polygon or sphere batch kernel (simd/batch.h), and added, times the
 * light's rgb, into their outputs.  The ZH -> SH reconstruction is not shared
 * across lights as in shl__lights_eval: in the kernel it is 13% of the time at
 * lmax 8 (bench/RESULTS.md sec. 4), the per-light SH accumulation it would
 * replace costs about as much as the lobe-domain one. */
#include "../simd/batch.h"
#include "lights.h"
#include <math.h>
#include <string.h>

enum { CHUNK = 64 }; /* points per pass over the lights: a multiple of every vector length */

/* Double vertices the polygon kernel takes: coordinates up to 2^126 and an extent
 * of at least 2^-126, so that the scaled vertices and points (times at most 2^126)
 * and their squared distances stay within the double range (float input, up to
 * 2^128 with extents down to 2^-149, is within it too; shl_polygon_batch_f).
 * Other polygons take the scalar float path per point. */
static int poly_kernel_range(const double *v, int n)
{
    double ext = 0.0;
    for (int i = 0; i < 3 * n; ++i)
        if (!(fabs(v[i]) <= 0x1p126)) return 0;
    for (int i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) ext = fmax(ext, fabs(v[3 * i + k] - v[k]));
    return ext == 0.0 || ext >= 0x1p-126; /* ext = 0: zero area, the kernel path writes zeros */
}

/* Unit-radiance results of light li at the m gathered points. */
static void light_batch(const shl_ctx *ctx, const shl_lights *lights, const shl__light *li, int m, const float *pts,
                        float *coeffs, float *grad, void *work)
{
    if (li->kind == SHL__LIGHT_SPHERE) {
        shl__batch_sphere_eval(ctx, li->center, li->radius, m, pts, coeffs, grad, work);
        return;
    }
    const double *v = lights->verts + li->vofs;
    const size_t nc = (size_t)ctx->nc;
    if (!poly_kernel_range(v, li->n)) {
        for (int p = 0; p < m; ++p)
            shl__batch_poly_point(ctx, v, li->n, pts + 3 * p, coeffs + nc * p, grad ? grad + 3 * nc * p : NULL);
        return;
    }
    shl__batch_poly P;
    shl__batch_poly_prepare(v, li->n, &P);
    shl__batch_poly_eval(ctx, &P, v, li->n, m, pts, coeffs, grad, work);
}

int shl_lights_eval_batch_f(const shl_ctx *ctx, const shl_lights *lights, int npts, const float *pts, float *rgb,
                            float *grad)
{
    if (!ctx || !lights || (npts > 0 && (!pts || !rgb))) return SHL_ENULL;
    if (npts < 0) return SHL_EDOMAIN;
    for (int p = 0; p < npts; ++p)
        if (shl__check_finite_f(pts + 3 * (size_t)p, 3)) return SHL_ENONFINITE;
    if (npts == 0) return SHL_OK;
    const size_t nc = (size_t)ctx->nc, nq = grad ? 4 : 1;
    const size_t kernel_bytes = ctx->isa->poly_work_bytes(ctx->lmax, grad != NULL),
                 sphere_bytes = ctx->isa->sphere_work_bytes(ctx->lmax, grad != NULL);
    const size_t work_bytes = kernel_bytes > sphere_bytes ? kernel_bytes : sphere_bytes;
    /* kernel workspace, then the chunk's unit-radiance outputs and gathered points */
    float *buf = NULL;
    if (lights->count > 0 && !(buf = shl__malloc(work_bytes + sizeof(float) * (nq * nc + 3) * CHUNK)))
        return SHL_ENOMEM; /* before anything is written */
    memset(rgb, 0, sizeof(float) * 3 * nc * (size_t)npts);
    if (grad) memset(grad, 0, sizeof(float) * 9 * nc * (size_t)npts);
    if (!buf) return SHL_OK; /* empty set */
    float *unit = (float *)((char *)buf + work_bytes), *gathered = unit + nq * nc * CHUNK;
    int index[CHUNK];
    for (int p0 = 0; p0 < npts; p0 += CHUNK) {
        const int nchunk = npts - p0 < CHUNK ? npts - p0 : CHUNK;
        for (int i = 0; i < lights->count; ++i) {
            const shl__light *li = &lights->items[i];
            int m = 0;
            for (int j = 0; j < nchunk; ++j) {
                const float *pt = pts + 3 * (size_t)(p0 + j);
                if (!li->two_sided) {
                    const double x[3] = {pt[0], pt[1], pt[2]};
                    if (!(shl__light_front_distance(li, lights->verts + li->vofs, x) > 0.0)) continue;
                }
                memcpy(gathered + 3 * m, pt, sizeof(float) * 3);
                index[m++] = p0 + j;
            }
            if (m == 0) continue;
            float *ugrad = grad ? unit + nc * CHUNK : NULL;
            light_batch(ctx, lights, li, m, gathered, unit, ugrad, buf);
            for (int j = 0; j < m; ++j) /* Wu 2020 Alg. 1 line 7: the lights add linearly */
                for (int c = 0; c < 3; ++c) {
                    const float s = (float)li->rgb[c];
                    ctx->isa->accumulate(nc, s, unit + nc * j, rgb + (3 * (size_t)index[j] + c) * nc);
                    if (grad) /* layout (c*3 + a)*nc + k */
                        ctx->isa->accumulate(3 * nc, s, ugrad + 3 * nc * j, grad + (9 * (size_t)index[j] + 3 * c) * nc);
                }
        }
    }
    shl__free(buf);
    return SHL_OK;
}
