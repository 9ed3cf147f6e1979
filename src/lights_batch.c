/* Light sets at many shading points in float, through the SIMD kernels: for
 * each light, the points it reaches (a one-sided polygon reaches the points in
 * front of it, by the double test of shl_lights_eval) are run through the
 * polygon or sphere batch kernel (simd/kernel_api.h).  In sets of 4 lights or
 * more, polygons add their lobe integrals times the light's rgb to per-block
 * accumulators, reconstructed once per block and colour (Wang 2018 Eq. 33 is
 * linear; as shl__lights_eval); the others (spheres, polygons or points the
 * kernel does not take, every light of smaller sets) add their SH results,
 * times the rgb, into the outputs.  Threads take whole blocks of
 * SHL__LIGHTS_BLOCK points, so a point's result never depends on the thread
 * count.  The double batch shl_lights_eval_batch is here too. */
#include "lights.h"
#include "parallel.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
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
    /* kernel workspace, the block's unit-radiance outputs and gathered points, then (64-byte aligned) the accumulators */
    const size_t nq = with_grad ? 4 : 1;
    return kernel_bytes(ctx, with_grad) + sizeof(float) * (nq * (size_t)ctx->nc + 3) * CHUNK + 64 +
           sizeof(float) * ctx->isa->poly_acc_floats(ctx->lmax, with_grad, CHUNK);
}

/* out += rgb3[c] times the unit-radiance results of one point, for each colour c. */
static void add_point(const shl_ctx *ctx, const double rgb3[3], const float *unit, const float *ugrad, float *rgb,
                      float *grad)
{
    const size_t nc = (size_t)ctx->nc;
    for (int c = 0; c < 3; ++c) { /* Wu 2020 Alg. 1 line 7: the lights add linearly */
        const float s = (float)rgb3[c];
        ctx->isa->accumulate(nc, s, unit, rgb + c * nc);
        if (grad) ctx->isa->accumulate(3 * nc, s, ugrad, grad + 3 * c * nc); /* layout (c*3 + a)*nc + k */
    }
}

/* shl__light_front_distance(li, v0, x) > 0, decided by the unscaled sum where it can:
 * d = sum_k n_k (x_k - v0_k) over the same rounded differences as the scaled sum there
 * (that times 2^-e).  Each errs from the exact sum over those differences by at most
 * 3 eps S, S = sum_k |n_k (x_k - v0_k)|, plus underflows below 2^-1070 (1 + |n|) |x - v0|
 * (below 2^-800 when |n|, |x - v0| < 2^100), so |d| > 8 eps S + 2^-800 gives both the
 * exact sum's sign; otherwise (near the plane, extreme ranges, x = v0) the scaled test. */
static int in_front(const shl__light *li, const double *v0, const float *pt)
{
    const double x[3] = {pt[0], pt[1], pt[2]};
    double d = 0.0, s = 0.0, size = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double diff = x[k] - v0[k], t = li->normal[k] * diff;
        d += t;
        s += fabs(t);
        size += fabs(diff) + fabs(li->normal[k]);
    }
    if (size < 0x1p100 && fabs(d) > 8.0 * DBL_EPSILON * s + 0x1p-800) return d > 0.0;
    return shl__light_front_distance(li, v0, x) > 0.0;
}

/* The block's outputs zeroed, once (*zeroed). */
static void zero_outputs(int m, size_t nc, float *rgb, size_t rgb_stride, float *grad, size_t grad_stride, int *zeroed)
{
    for (int j = 0; !*zeroed && j < m; ++j) {
        memset(rgb + rgb_stride * j, 0, sizeof(float) * 3 * nc);
        if (grad) memset(grad + grad_stride * j, 0, sizeof(float) * 9 * nc);
    }
    *zeroed = 1;
}

void shl__lights_batch_f_block(const shl_ctx *ctx, const shl_lights *lights, int m, const float *pts, float *rgb,
                               size_t rgb_stride, float *grad, size_t grad_stride, void *buf)
{
    const size_t nc = (size_t)ctx->nc, nq = grad ? 4 : 1;
    int zeroed = 0; /* outputs zeroed: before the first light that adds to them directly */
    if (lights->count == 0) {
        zero_outputs(m, nc, rgb, rgb_stride, grad, grad_stride, &zeroed);
        return;
    }
    float *unit = (float *)((char *)buf + kernel_bytes(ctx, grad != NULL)), *gathered = unit + nq * nc * CHUNK;
    float *ugrad = grad ? unit + nc * CHUNK : NULL;
    float *acc = (float *)(((uintptr_t)(gathered + 3 * CHUNK) + 63) & ~(uintptr_t)63);
    int index[CHUNK], redo[CHUNK];
    unsigned char keep[CHUNK];
    /* The 3 colours' reconstructions cost about one light's kernel (lmax 8, gradients, 512
     * points: 1 light 0.41 -> 0.53 ms, 4 lights 1.31 -> 1.30 ms): smaller sets reconstruct per light. */
    const int shared = lights->count >= 4;
    if (shared) memset(acc, 0, sizeof(float) * ctx->isa->poly_acc_floats(ctx->lmax, grad != NULL, m));
    for (int i = 0; i < lights->count; ++i) {
        const shl__light *li = &lights->items[i];
        /* spheres have no vertices (lights->verts may be NULL: no offset from it) */
        const double *v = li->kind == SHL__LIGHT_POLYGON ? lights->verts + li->vofs : NULL;
        int k = 0;
        for (int j = 0; j < m; ++j) {
            const float *pt = pts + 3 * (size_t)j;
            keep[j] = 1;
            if (!li->two_sided) {
                keep[j] = in_front(li, v, pt);
                if (!keep[j]) continue;
            }
            memcpy(gathered + 3 * k, pt, sizeof(float) * 3);
            index[k++] = j;
        }
        if (k == 0) continue;
        if (shared && li->kind == SHL__LIGHT_POLYGON && poly_kernel_range(v, li->n)) {
            shl__batch_poly P;
            shl__batch_poly_prepare(v, li->n, &P);
            if (P.n > 0 && P.len2 >= 0x1p-120) { /* else shl__batch_poly_eval's own cases, through light_batch */
                const float s[3] = {(float)li->rgb[0], (float)li->rgb[1], (float)li->rgb[2]};
                const int nredo = ctx->isa->poly_batch_acc(&P, ctx->lmax, m, pts, k < m ? keep : NULL, s, grad != NULL,
                                                           acc, buf, redo);
                for (int r = 0; r < nredo; ++r) { /* the points the kernel's float geometry cannot resolve */
                    const size_t p = (size_t)redo[r];
                    zero_outputs(m, nc, rgb, rgb_stride, grad, grad_stride, &zeroed);
                    shl__batch_poly_point(ctx, v, li->n, pts + 3 * p, unit, ugrad);
                    add_point(ctx, li->rgb, unit, ugrad, rgb + rgb_stride * p, grad ? grad + grad_stride * p : NULL);
                }
                continue;
            }
        }
        light_batch(ctx, lights, li, k, gathered, unit, ugrad, buf);
        zero_outputs(m, nc, rgb, rgb_stride, grad, grad_stride, &zeroed);
        for (int j = 0; j < k; ++j)
            add_point(ctx, li->rgb, unit + nc * j, grad ? ugrad + 3 * nc * j : NULL, rgb + rgb_stride * (size_t)index[j],
                      grad ? grad + grad_stride * (size_t)index[j] : NULL);
    }
    if (shared)
        ctx->isa->poly_acc_finish(ctx->lmax, m, acc, zeroed, rgb, rgb_stride, grad, grad_stride, buf);
    else /* no light reached the block: zeros */
        zero_outputs(m, nc, rgb, rgb_stride, grad, grad_stride, &zeroed);
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
    if (shl__check_finite_f(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
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
    if (shl__check_finite(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    batch_job job = {lights, ctx->lmax, pts, rgb, grad};
    return shl__parallel_for_ws(npts, 1, nthreads, sizeof(double) * shl__lights_ws_size(ctx->lmax), batch_range,
                                &job); /* SHL_ENOMEM, SHL_ETHREAD: nothing written */
}

int shl_lights_eval_batch(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts, double *rgb,
                          double *grad)
{
    return shl_lights_eval_batch_mt(ctx, lights, npts, pts, rgb, grad, 1);
}
