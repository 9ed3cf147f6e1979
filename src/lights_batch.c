/* Light sets at many shading points in float, through the SIMD kernels: for
 * each light, the points it reaches are gathered (a one-sided polygon reaches
 * the points in front of it, by the double test of shl_lights_eval), run through
 * the polygon or sphere batch kernel (simd/kernel_api.h), and added, times the
 * light's rgb, into their outputs.  The ZH -> SH reconstruction is not shared
 * across lights as in shl__lights_eval: in the kernel it is 13% of the time at
 * lmax 8 (bench/RESULTS.md sec. 4), the per-light SH accumulation it would
 * replace costs about as much as the lobe-domain one.  Threads take whole
 * blocks of SHL__LIGHTS_BLOCK points, so a point's result never depends on the
 * thread count.  The double batch shl_lights_eval_batch is here too. */
#include "lights.h"
#include "parallel.h"
#include <math.h>
#include <string.h>

enum { CHUNK = SHL__LIGHTS_BLOCK }; /* points per pass over the lights */

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

static size_t kernel_bytes(const shl_ctx *ctx, int with_grad)
{
    const size_t pb = ctx->isa->poly_work_bytes(ctx->lmax, with_grad), sb = ctx->isa->sphere_work_bytes(ctx->lmax, with_grad);
    return pb > sb ? pb : sb;
}

size_t shl__lights_batch_f_bytes(const shl_ctx *ctx, const shl_lights *lights, int with_grad)
{
    if (lights->count == 0) return 0;
    const size_t nq = with_grad ? 4 : 1; /* kernel workspace, then the block's unit-radiance outputs and gathered points */
    return kernel_bytes(ctx, with_grad) + sizeof(float) * (nq * (size_t)ctx->nc + 3) * CHUNK;
}

void shl__lights_batch_f_block(const shl_ctx *ctx, const shl_lights *lights, int m, const float *pts, float *rgb,
                               size_t rgb_stride, float *grad, size_t grad_stride, void *buf)
{
    const size_t nc = (size_t)ctx->nc, nq = grad ? 4 : 1;
    for (int j = 0; j < m; ++j) {
        memset(rgb + rgb_stride * j, 0, sizeof(float) * 3 * nc);
        if (grad) memset(grad + grad_stride * j, 0, sizeof(float) * 9 * nc);
    }
    if (lights->count == 0) return;
    float *unit = (float *)((char *)buf + kernel_bytes(ctx, grad != NULL)), *gathered = unit + nq * nc * CHUNK;
    float *ugrad = grad ? unit + nc * CHUNK : NULL;
    int index[CHUNK];
    for (int i = 0; i < lights->count; ++i) {
        const shl__light *li = &lights->items[i];
        int k = 0;
        for (int j = 0; j < m; ++j) {
            const float *pt = pts + 3 * (size_t)j;
            if (!li->two_sided) {
                const double x[3] = {pt[0], pt[1], pt[2]};
                if (!(shl__light_front_distance(li, lights->verts + li->vofs, x) > 0.0)) continue;
            }
            memcpy(gathered + 3 * k, pt, sizeof(float) * 3);
            index[k++] = j;
        }
        if (k == 0) continue;
        light_batch(ctx, lights, li, k, gathered, unit, ugrad, buf);
        for (int j = 0; j < k; ++j) /* Wu 2020 Alg. 1 line 7: the lights add linearly */
            for (int c = 0; c < 3; ++c) {
                const float s = (float)li->rgb[c];
                ctx->isa->accumulate(nc, s, unit + nc * j, rgb + rgb_stride * (size_t)index[j] + c * nc);
                if (grad) /* layout (c*3 + a)*nc + k */
                    ctx->isa->accumulate(3 * nc, s, ugrad + 3 * nc * j, grad + grad_stride * (size_t)index[j] + 3 * c * nc);
            }
    }
}

typedef struct {
    const shl_ctx *ctx;
    const shl_lights *lights;
    long npts;
    const float *pts;
    float *rgb, *grad;
} batch_f_job;

static void batch_f_range(void *arg, void *buf, long begin, long end) /* buf: NULL for an empty set */
{
    const batch_f_job *job = arg;
    const size_t nc = (size_t)job->ctx->nc;
    for (long b = begin; b < end; ++b) {
        const size_t p0 = (size_t)b * CHUNK;
        const int m = job->npts - (long)p0 < CHUNK ? (int)(job->npts - (long)p0) : CHUNK;
        shl__lights_batch_f_block(job->ctx, job->lights, m, job->pts + 3 * p0, job->rgb + 3 * nc * p0, 3 * nc,
                                  job->grad ? job->grad + 9 * nc * p0 : NULL, 9 * nc, buf);
    }
}

int shl_lights_eval_batch_f_mt(const shl_ctx *ctx, const shl_lights *lights, int npts, const float *pts, float *rgb,
                               float *grad, int nthreads)
{
    if (!ctx || !lights || (npts > 0 && (!pts || !rgb))) return SHL_ENULL;
    if (npts < 0 || shl__check_threads(nthreads)) return SHL_EDOMAIN;
    for (int p = 0; p < npts; ++p)
        if (shl__check_finite_f(pts + 3 * (size_t)p, 3)) return SHL_ENONFINITE;
    if (npts == 0) return SHL_OK;
    const long nblocks = (npts + CHUNK - 1) / CHUNK;
    batch_f_job job = {ctx, lights, npts, pts, rgb, grad};
    return shl__parallel_for_ws(nblocks, 1, nthreads, shl__lights_batch_f_bytes(ctx, lights, grad != NULL), batch_f_range,
                                &job); /* SHL_ENOMEM, SHL_ETHREAD: nothing written */
}

int shl_lights_eval_batch_f(const shl_ctx *ctx, const shl_lights *lights, int npts, const float *pts, float *rgb,
                            float *grad)
{
    return shl_lights_eval_batch_f_mt(ctx, lights, npts, pts, rgb, grad, 1);
}

/* ---- double: shl__lights_eval per point ---- */

typedef struct {
    const shl_lights *lights;
    int lmax;
    const double *pts;
    double *rgb, *grad;
} batch_job;

static void batch_range(void *arg, void *ws, long begin, long end) /* ws: shl__lights_ws_size(lmax) doubles */
{
    const batch_job *job = arg;
    const size_t nc = (size_t)SHL_NCOEFFS(job->lmax);
    for (long p = begin; p < end; ++p)
        shl__lights_eval(job->lights, job->lmax, ws, job->pts + 3 * (size_t)p, job->rgb + 3 * nc * (size_t)p,
                         job->grad ? job->grad + 9 * nc * (size_t)p : NULL);
}

int shl_lights_eval_batch_mt(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts, double *rgb,
                             double *grad, int nthreads)
{
    if (!ctx || !lights || !pts || !rgb) return SHL_ENULL;
    if (npts < 0 || shl__check_threads(nthreads)) return SHL_EDOMAIN;
    for (int p = 0; p < npts; ++p)
        if (shl__check_finite(pts + 3 * (size_t)p, 3)) return SHL_ENONFINITE;
    batch_job job = {lights, ctx->lmax, pts, rgb, grad};
    return shl__parallel_for_ws(npts, 1, nthreads, sizeof(double) * shl__lights_ws_size(ctx->lmax), batch_range,
                                &job); /* SHL_ENOMEM, SHL_ETHREAD: nothing written */
}

int shl_lights_eval_batch(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts, double *rgb,
                          double *grad)
{
    return shl_lights_eval_batch_mt(ctx, lights, npts, pts, rgb, grad, 1);
}
