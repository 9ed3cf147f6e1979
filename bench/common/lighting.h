/* Per-vertex SH lighting of a scene's lights by one of several methods, all
 * producing the layout of shl_lights_eval (rgb[c*nc + k] per point), in float:
 *  - ANALYTIC:   shl_lights_eval_batch per vertex (double; Wang 2018), polygons and spheres;
 *  - ANALYTIC_F: shl_lights_eval_batch_f per vertex (float, SIMD kernels), polygons and spheres;
 *  - GRID:       a res^3 grid over the receivers (shl_grid_fill) interpolated by
 *                shl_grid_interp (Hermite, trilinear or Taylor);
 *  - AGRID:      an adaptive grid over the receivers (shl_agrid_create with a coarse
 *                grid_res^3 level, agrid_criterion, agrid_tol, agrid_budget; shl_agrid_fill)
 *                interpolated by shl_agrid_interp;
 *  - MC:         Monte Carlo projection, N samples per vertex (light picked by power,
 *                polygons sampled by area, spheres by cone);
 *  - MONOMIAL:   the monomial-moment baseline (bench/common/monomial.h) per polygon,
 *                spheres by shl_sphere;
 *  - SINGLE / TAYLOR1: one sample at a point, constant or extrapolated with its gradient
 *                (Annen 2004 Eq. 4); with npoints > 1 samples, their values (SINGLE) or
 *                first-order extrapolations (TAYLOR1) blended by inverse-distance weights
 *                (Annen 2004 Eq. 15-16, exponent taylor_b). */
#ifndef SHL_BENCH_LIGHTING_H
#define SHL_BENCH_LIGHTING_H

#include "scene.h"
#include <stddef.h>

#define LIGHTING_MAX_SAMPLES 8

typedef enum { LM_ANALYTIC, LM_ANALYTIC_F, LM_GRID, LM_MC, LM_MONOMIAL, LM_SINGLE, LM_TAYLOR1, LM_AGRID } lighting_kind;

typedef struct {
    lighting_kind kind;
    int lmax;
    int grid_res, interp, grid_storage; /* GRID: resolution, SHL_INTERP_*, SHL_GRID_FLOAT / DOUBLE */
    int agrid_criterion;                /* AGRID (coarse resolution grid_res): SHL_AGRID_MAX / MEAN, */
    double agrid_tol;                   /* its tolerance (absolute) */
    long agrid_budget;                  /* and node budget */
    const double *agrid_receivers;      /* AGRID: receivers (shl_agrid_set_receivers), NULL: none */
    int agrid_nreceivers;
    const double *agrid_receiver_weights; /* AGRID: their weights (shl_agrid_set_weighted_receivers), NULL: all 1 */
    double taylor_b;                    /* GRID with SHL_INTERP_TAYLOR; SINGLE / TAYLOR1 with npoints > 1 */
    long mc_samples;                    /* MC */
    int mc_stratified;                  /* MC, polygon lights only: about mc_samples jittered strata split over
                                           the lights' fan triangles by power, instead of iid area samples */
    int npoints;                        /* SINGLE, TAYLOR1: number of samples (0 means 1) */
    double point[LIGHTING_MAX_SAMPLES][3]; /* SINGLE, TAYLOR1: where the samples are taken */
} lighting_method;

typedef struct lighting lighting;

/* Per-frame preparation (grid fill, single sample) over the receiver box [lo, hi];
 * *fill_seconds: its wall time.  NULL on failure. */
lighting *lighting_prepare(const scene *s, const lighting_method *m, const double lo[3], const double hi[3],
                           int nthreads, double *fill_seconds);
/* Consumer of lighting_eval: points [begin, end) (end - begin <= LIGHTING_BLOCK), their
 * coefficients coef[(size_t)(p - begin) * 3 * nc ...], as worker `worker`. */
enum { LIGHTING_BLOCK = 64 };
typedef void (*lighting_consumer)(void *arg, int worker, long begin, long end, const float *coef);
/* Coefficients at n points, block by block into per-worker scratch, each block handed to
 * consume(arg, ...) while it is in cache (no n-point coefficient buffer).  *eval_share: the
 * fraction of the workers' time spent evaluating (the rest consuming), from CLOCK_MONOTONIC
 * around each block's two parts.  0 or -1. */
int lighting_eval(const lighting *L, long n, const double *pts, int nthreads, lighting_consumer consume, void *arg,
                  double *eval_share);
void lighting_free(lighting *L);
/* "grid 8^3 Hermite" etc. */
const char *lighting_name(const lighting_method *m, char *buf, size_t len);

#endif
