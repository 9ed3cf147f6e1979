/* Batched polygon evaluation: argument checks, the polygon prepared once in
 * double (scaled, repeated vertices dropped, plane and fan data), then the
 * context's SIMD kernel (simd/poly_batch.h) over all points, and the scalar path
 * for the rare points its float geometry cannot resolve.  Light sets
 * (src/lights_batch.c) run the same two steps per polygon. */
#include "parallel.h"
#include "polygon.h"
#include <math.h>
#include <stdint.h>
#include <string.h>

/* Repeated vertices dropped as in shl__poly_geom_init (polygon.c); P->n = 0
 * when fewer than 3 remain or the polygon has zero area. */
void shl__batch_poly_prepare(const double *verts, int n, shl__batch_poly *P)
{
    double kept[3 * SHL_MAX_VERTS];
    const int m = shl__drop_repeated(verts, n, kept);
    P->n = 0;
    if (m < 3) return;
    double ext = 0.0; /* extent about v_0 */
    for (int i = 1; i < m; ++i)
        for (int k = 0; k < 3; ++k) ext = fmax(ext, fabs(kept[3 * i + k] - kept[k]));
    if (!(ext > 0.0)) return; /* vertices equal up to the sign of zero: zero area */
    P->inv_scale = shl__ldexp(1.0, -shl__ilogb(ext)); /* extent in [1, 2) after scaling */
    for (int i = 0; i < m; ++i)
        for (int k = 0; k < 3; ++k) P->vd[i][k] = kept[3 * i + k] * P->inv_scale;
    double normal[3] = {0.0, 0.0, 0.0}, c[SHL_MAX_VERTS][3]; /* Newell, relative to v_0 */
    for (int i = 1; i + 1 < m; ++i) {
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = P->vd[i][k] - P->vd[0][k];
            e2[k] = P->vd[i + 1][k] - P->vd[0][k];
        }
        shl__cross3(e1, e2, c[i]);
        for (int k = 0; k < 3; ++k) normal[k] += c[i][k];
    }
    const double len2 = shl__dot3(normal, normal);
    if (!(len2 > 0.0)) return; /* zero area: sees nothing */
    memcpy(P->normal, normal, sizeof normal);
    P->len2 = len2;
    double centroid[3] = {0.0, 0.0, 0.0};
    P->perimeter = 0.0;
    for (int i = 0; i < m; ++i) {
        const int f = i + 1 == m ? 0 : i + 1;
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = P->vd[f][k] - P->vd[i][k];
        P->perimeter += sqrt(shl__dot3(d, d));
        for (int k = 0; k < 3; ++k) {
            P->v[i][k] = (float)(P->vd[i][k] - P->vd[0][k]); /* relative to v_0: within float range */
            P->edge[i][k] = (float)(P->vd[f][k] - P->vd[i][k]);
            centroid[k] += (P->vd[i][k] - P->vd[0][k]) / m; /* relative to v_0, as P->v */
        }
        P->fan[i] = 0.0f;
    }
    for (int i = 1; i + 1 < m; ++i)
        P->fan[i] = (float)(shl__dot3(normal, c[i]) / len2);
    const double inv_len = 1.0 / sqrt(len2);
    for (int k = 0; k < 3; ++k) {
        P->unit_normal[k] = (float)(normal[k] * inv_len);
        P->proxy[k] = centroid[k] + normal[k] * inv_len;
    }
    P->inv_len = (float)inv_len;
    P->n = m;
}

/* Such a point takes the scalar path of shl_polygon_grad_f (geometry in double). */
void shl__batch_poly_point(const shl_ctx *ctx, const double *verts, int n, const float *pt, float *coeffs, float *grad)
{
    const double xd[3] = {pt[0], pt[1], pt[2]};
    float zh[SHL__ZH_BLOCK], zh_grad[3 * SHL__ZH_BLOCK];
    shl__poly_geom g;
    shl__poly_geom_init(&g, xd, verts, n);
    shl__poly_zh_grad_f(&g, ctx->lmax, zh, zh_grad); /* coefficients independent of the gradient request */
    shl__zh_to_sh_f(ctx->lmax, zh, coeffs);
    if (!grad) return;
    for (int a = 0; a < 3; ++a) shl__zh_to_sh_f(ctx->lmax, zh_grad + a * SHL__ZH_BLOCK, grad + a * ctx->nc);
    shl__poly_grad_unscale_f(&g, grad, 3 * ctx->nc);
}

/* Points the all-float geometry cannot resolve: closer to the plane than 2^-16 of
 * their distance to the farthest vertex (the side, hence the sign of the gradient's
 * normal component, would be decided by float rounding), or within 2^-16 extents of
 * a vertex (float cannot separate them from it).  Not those of the kernel's own
 * cases: in the plane by the double test (zeros) or beyond 2^40 extents (zeros);
 * the kernel tests them all, in double, in lanes_setup (simd/poly_batch.h):
 * x scaled, rmax2 and rmin2 the largest and smallest squared distance to a vertex,
 * h the plane distance times |N|:
 *   rmax2 <= 2^80, h^2 > (8 DBL_EPSILON)^2 rmax2 |N|^2 (not the kernel's own cases), and
 *   h^2 <= 2^-32 rmax2 |N|^2 or rmin2 < 2^-32 or perimeter^2 2^10 < rmin2 or
 *   perimeter rmax2 > 2^13 |h|.  Distances in the scaled units of P.
 * Also the points where the float boundary sums cancel: the kernel's error is about
 * FLT_EPSILON sum_e gamma_e / omega of omega (cf. shl__poly_zh_f, polygon.c; measured
 * 2.5e-4 for a square 1e-3 rad across, where the ratio is 4e3).  With edge arcs
 * gamma_e ~ |edge_e| / r and omega ~ area |h_n| / r^3 (h_n = h / |N|, |N| = 2 area) the
 * ratio is about 2 perimeter r^2 / |h|, and at least 4 r / perimeter.  Two cases take
 * the scalar path, whose double recurrence keeps ~1e-7 of omega:
 *  - small lights, perimeter < r_min / 32 (a square under 1/128 rad: ratio > 2^9; the
 *    kernel's error above is <= 5e-5 of omega);
 *  - points so close to a light's plane that the ratio exceeds 2^14 (kernel error
 *    there ~1e-3 of omega; the square (+-1, +-1, 0) seen from (3, 0.5, h): h < 2.2e-3).
 *    The band above, where the kernel keeps 3e-5..2e-4 of omega (there h = 1e-2..3e-3),
 *    stays on the kernel: routing it (ratio > 2^9) cost +23% in a room with a ceiling
 *    light (~5% of the points routed, each at ~5 kernel lanes' cost). */
void shl__batch_poly_eval(const shl_ctx *ctx, const shl__batch_poly *P, const double *verts, int n, int npts,
                          const float *pts, float *coeffs, float *grad, void *work)
{
    const size_t nc = (size_t)ctx->nc;
    if (P->n == 0) {
        memset(coeffs, 0, sizeof(float) * nc * (size_t)npts);
        if (grad) memset(grad, 0, sizeof(float) * 3 * nc * (size_t)npts);
        return;
    }
    if (P->len2 < 0x1p-120) {
        /* A polygon too thin for the float geometry: |N| (twice its area in the scaled units,
         * extent in [1, 2)) below 2^-60.  Above it the kernel's float data stay normal and
         * finite: 1/|N| <= 2^60, |fan_i| <= |c_i| / |N| < 2^64, and a resolved point's
         * |h| > 2^-16 rmax |N| >= 2^-126 (rmax >= 2^-50, lanes_setup); below it 1/|N| or
         * fan_i overflowed to inf in float (NaN results: fuzz_lights-polygon-batch-f-nonfinite,
         * |N| = 2^-500).  Every point takes the scalar path (geometry in double). */
        for (int p = 0; p < npts; ++p)
            shl__batch_poly_point(ctx, verts, n, pts + 3 * (size_t)p, coeffs + nc * p, grad ? grad + 3 * nc * p : NULL);
        return;
    }
    int redo[SHL__BATCH_BLOCK];
    for (int p0 = 0; p0 < npts; p0 += SHL__BATCH_BLOCK) {
        const int m = npts - p0 < SHL__BATCH_BLOCK ? npts - p0 : SHL__BATCH_BLOCK;
        const float *x = pts + 3 * (size_t)p0;
        float *c = coeffs + nc * p0, *g = grad ? grad + 3 * nc * p0 : NULL;
        const int nredo = ctx->isa->poly_batch(P, ctx->lmax, m, x, c, g, work, redo);
        for (int r = 0; r < nredo; ++r) {
            const size_t p = (size_t)redo[r];
            shl__batch_poly_point(ctx, verts, n, x + 3 * p, c + nc * p, g ? g + 3 * nc * p : NULL);
        }
    }
}

typedef struct {
    const shl_ctx *ctx;
    shl__batch_eval_fn eval;
    const void *light;
    const float *pts;
    float *coeffs, *grad;
} batch_job;

static void batch_range(void *arg, void *ws, long begin, long end)
{
    const batch_job *job = arg;
    const size_t nc = (size_t)job->ctx->nc, p0 = (size_t)begin;
    job->eval(job->ctx, job->light, (int)(end - begin), job->pts + 3 * p0, job->coeffs + nc * p0,
              job->grad ? job->grad + 3 * nc * p0 : NULL, ws);
}

int shl__batch_run(const shl_ctx *ctx, shl__batch_eval_fn eval, const void *light, size_t work_bytes, int npts,
                   const float *pts, float *coeffs, float *grad, int nthreads)
{
    batch_job job = {ctx, eval, light, pts, coeffs, grad};
    return shl__parallel_for_ws(npts, SHL__BATCH_BLOCK, nthreads, work_bytes, batch_range, &job);
}

typedef struct {
    const shl__batch_poly *P;
    const double *verts;
    int n;
} poly_light;

static void poly_eval(const shl_ctx *ctx, const void *light, int npts, const float *pts, float *coeffs, float *grad,
                      void *work)
{
    const poly_light *L = light;
    shl__batch_poly_eval(ctx, L->P, L->verts, L->n, npts, pts, coeffs, grad, work);
}

int shl_polygon_batch_f_mt(const shl_ctx *ctx, const float *verts, int n, int npts, const float *pts, float *coeffs,
                           float *grad, int nthreads)
{
    if (!ctx || !verts || (npts > 0 && (!pts || !coeffs))) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    if (npts < 0 || shl__check_threads(nthreads)) return SHL_EDOMAIN;
    if (shl__check_finite_f(verts, 3 * (size_t)n) || shl__check_finite_f(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    if (npts == 0) return SHL_OK;
    double vd[3 * SHL_MAX_VERTS];
    for (int i = 0; i < 3 * n; ++i) vd[i] = verts[i];
    shl__batch_poly P;
    shl__batch_poly_prepare(vd, n, &P);
    const poly_light L = {&P, vd, n};
    return shl__batch_run(ctx, poly_eval, &L, ctx->isa->poly_work_bytes(ctx->lmax, grad != NULL), npts, pts, coeffs,
                          grad, nthreads);
}

int shl_polygon_batch_f(const shl_ctx *ctx, const float *verts, int n, int npts, const float *pts,
                        float *coeffs, float *grad)
{
    return shl_polygon_batch_f_mt(ctx, verts, n, npts, pts, coeffs, grad, 1);
}
