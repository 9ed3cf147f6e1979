/* make demo: the embedded default light set (no files needed).  Prints, per
 * light, its SH coefficients at a shading point, the time per evaluation at
 * several lmax, and the agreement with an independent Monte Carlo estimate
 * (area sampling, with its standard error). */
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>

typedef struct {
    const char *name;
    int n;
    double v[18];
} light;

static const light lights[] = {
    {"ceiling quad", 4, {-1, -1, 3, 1, -1, 3, 1, 1, 3, -1, 1, 3}},
    {"wall triangle", 3, {2.5, -1, 0, 2.5, 1, 0.5, 2.5, 0, 2}},
    {"concave L (tilted)", 6, {-2, -2, 0.5, -1, -2, 0.5, -1, -1.5, 1.5, -1.5, -1.5, 1.5, -1.5, -1, 2.5, -2, -1, 2.5}},
};
static const double shading_point[3] = {0.2, -0.3, 0.0};

static uint64_t rng_state = 42;
static double uniform01(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * 0x1.0p-53;
}

/* Monte Carlo estimate of the lmax-2 coefficients: fan triangles sampled by area;
 * estimator Y(s) |n.s| A / r^2 (the polygons here are convex or fan-convex from vertex 0). */
static void monte_carlo(const light *L, long samples, double mean[9], double stderr_[9])
{
    double area[SHL_MAX_VERTS], total = 0, nrm[3] = {0, 0, 0};
    for (int i = 1; i + 1 < L->n; ++i) {
        const double *a = L->v, *b = L->v + 3 * i, *c = L->v + 3 * (i + 1);
        const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        area[i] = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        for (int k = 0; k < 3; ++k) nrm[k] += cr[k];
        total += area[i];
    }
    const double nl = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    double sum[9] = {0}, sum2[9] = {0};
    for (long s = 0; s < samples; ++s) {
        double pick = uniform01() * total;
        int i = 1;
        while (i + 2 < L->n && pick > area[i]) pick -= area[i++];
        double u = uniform01(), w = uniform01();
        if (u + w > 1) { u = 1 - u; w = 1 - w; }
        const double *a = L->v, *b = L->v + 3 * i, *c = L->v + 3 * (i + 1);
        double d[3], y[9];
        for (int k = 0; k < 3; ++k) d[k] = a[k] + u * (b[k] - a[k]) + w * (c[k] - a[k]) - shading_point[k];
        const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double cosl = fabs(d[0] * nrm[0] + d[1] * nrm[1] + d[2] * nrm[2]) / (nl * sqrt(r2));
        shl_eval_basis(2, d, y);
        for (int k = 0; k < 9; ++k) {
            const double f = y[k] * cosl * total / r2;
            sum[k] += f;
            sum2[k] += f * f;
        }
    }
    for (int k = 0; k < 9; ++k) {
        mean[k] = sum[k] / samples;
        stderr_[k] = sqrt(fmax(0.0, sum2[k] / samples - mean[k] * mean[k]) / samples);
    }
}

int main(void)
{
    printf("shlight %s demo: analytic SH coefficients of polygonal lights (Wang & Ramamoorthi 2018)\n",
           SHL_VERSION_STRING);
    printf("shading point (%.1f, %.1f, %.1f)\n\n", shading_point[0], shading_point[1], shading_point[2]);
    shl_ctx *ctx;
    if (shl_ctx_create(2, &ctx) != SHL_OK) return 1;
    printf("| light | solid angle (sr) | L00 | L1-1 | L10 | L11 | max |analytic - MC| / MC std. error (l<=2, 4e5 samples) |\n");
    printf("|---|---|---|---|---|---|---|\n");
    for (unsigned i = 0; i < sizeof lights / sizeof lights[0]; ++i) {
        double c[9], mc[9], se[9], omega, worst = 0;
        shl_polygon(ctx, shading_point, lights[i].v, lights[i].n, c);
        shl_polygon_solid_angle(shading_point, lights[i].v, lights[i].n, &omega);
        monte_carlo(&lights[i], 400000, mc, se);
        for (int k = 0; k < 9; ++k) worst = fmax(worst, fabs(c[k] - mc[k]) / se[k]);
        printf("| %s | %.6f | %.6f | %.6f | %.6f | %.6f | %.2f |\n", lights[i].name, omega, c[0], c[1], c[2], c[3], worst);
    }
    shl_ctx_destroy(ctx);

    printf("\n| lmax | coefficients | time per light (us) | lights per second per core |\n|---|---|---|---|\n");
    const int lmaxes[] = {2, 4, 8, 14, 30};
    for (unsigned i = 0; i < sizeof lmaxes / sizeof lmaxes[0]; ++i) {
        shl_ctx_create(lmaxes[i], &ctx);
        double out[SHL_NCOEFFS(SHL_LMAX_MAX)];
        long evals = 0;
        const double t0 = bench_now();
        while (bench_now() - t0 < 0.1)
            for (unsigned k = 0; k < 3; ++k, ++evals) shl_polygon(ctx, shading_point, lights[k].v, lights[k].n, out);
        const double per = (bench_now() - t0) / evals;
        printf("| %d | %d | %.2f | %.3g |\n", lmaxes[i], SHL_NCOEFFS(lmaxes[i]), per * 1e6, 1.0 / per);
        shl_ctx_destroy(ctx);
    }
    printf("\nA |analytic - MC| / std. error below ~4 is the agreement expected of an exact result.\n");
    return 0;
}
