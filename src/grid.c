/* Regular grids of RGB SH coefficients and gradients over a box, filled from
 * a light set (Wu et al. 2020, Alg. 1 lines 2-8), in parallel over nodes. */
#include "grid.h"
#include "lights.h"
#include "parallel.h"
#include <math.h>
#include <stdint.h>

static size_t elem_size(int storage) { return storage == SHL_GRID_DOUBLE ? sizeof(double) : sizeof(float); }

int shl_grid_bytes_per_node(int lmax, int storage, int *bytes)
{
    if (!bytes) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (storage != SHL_GRID_FLOAT && storage != SHL_GRID_DOUBLE) return SHL_EDOMAIN;
    *bytes = (int)(12 * SHL_NCOEFFS(lmax) * elem_size(storage)); /* 3 colours x (value + 3 gradients) x nc */
    return SHL_OK;
}

int shl_grid_create(const shl_ctx *ctx, const double lo[3], const double hi[3], const int res[3],
                    int storage, shl_grid **out)
{
    if (!out) return SHL_ENULL;
    *out = NULL; /* on every failure below (the exception in shlight.h) */
    if (!ctx || !lo || !hi || !res) return SHL_ENULL;
    if (storage != SHL_GRID_FLOAT && storage != SHL_GRID_DOUBLE) return SHL_EDOMAIN;
    if (shl__check_finite(lo, 3) || shl__check_finite(hi, 3)) return SHL_ENONFINITE;
    size_t nnodes = 1;
    for (int a = 0; a < 3; ++a) {
        if (res[a] < 2 || res[a] > SHL_GRID_RES_MAX || !(lo[a] < hi[a])) return SHL_EDOMAIN;
        const double h = (hi[a] - lo[a]) / (res[a] - 1);
        if (!isfinite(h) || !(h > 0.0)) return SHL_EDOMAIN; /* extent overflows, or spacing underflows to 0 */
        nnodes *= (size_t)res[a];
    }
    const size_t node_len = 12 * (size_t)ctx->nc, esize = elem_size(storage);
    if (nnodes > SIZE_MAX / node_len / esize) return SHL_ENOMEM;
    shl_grid *g = shl__calloc(1, sizeof *g);
    if (!g) return SHL_ENOMEM;
    g->data = shl__calloc(nnodes * node_len, esize);
    if (!g->data) {
        shl__free(g);
        return SHL_ENOMEM;
    }
    g->lmax = ctx->lmax;
    g->nc = ctx->nc;
    g->storage = storage;
    g->isa = ctx->isa;
    g->nnodes = nnodes;
    g->node_len = node_len;
    for (int a = 0; a < 3; ++a) {
        g->res[a] = res[a];
        g->lo[a] = lo[a];
        g->hi[a] = hi[a];
        g->h[a] = (hi[a] - lo[a]) / (res[a] - 1);
    }
    *out = g;
    return SHL_OK;
}

void shl_grid_destroy(shl_grid *grid)
{
    if (!grid) return;
    shl__free(grid->data);
    shl__free(grid);
}

void shl__grid_node_pos(const shl_grid *g, const int idx[3], double pos[3])
{
    for (int a = 0; a < 3; ++a) pos[a] = idx[a] == g->res[a] - 1 ? g->hi[a] : g->lo[a] + idx[a] * g->h[a];
}

static size_t node_offset(const shl_grid *g, const int idx[3])
{
    return ((size_t)idx[0] + (size_t)g->res[0] * ((size_t)idx[1] + (size_t)g->res[1] * (size_t)idx[2])) * g->node_len;
}

static int check_node(const shl_grid *g, const int idx[3])
{
    if (!g || !idx) return SHL_ENULL;
    for (int a = 0; a < 3; ++a)
        if (idx[a] < 0 || idx[a] >= g->res[a]) return SHL_EDOMAIN;
    return SHL_OK;
}

int shl_grid_node_position(const shl_grid *grid, const int idx[3], double pos[3])
{
    const int st = check_node(grid, idx);
    if (st) return st;
    if (!pos) return SHL_ENULL;
    shl__grid_node_pos(grid, idx, pos);
    return SHL_OK;
}

/* Copy n values between double and the grid's storage. */
static void store(const shl_grid *g, size_t ofs, const double *src, size_t n)
{
    if (g->storage == SHL_GRID_DOUBLE)
        for (size_t i = 0; i < n; ++i) ((double *)g->data)[ofs + i] = src[i];
    else
        for (size_t i = 0; i < n; ++i) ((float *)g->data)[ofs + i] = (float)src[i];
}

static void load(const shl_grid *g, size_t ofs, double *dst, size_t n)
{
    if (g->storage == SHL_GRID_DOUBLE)
        for (size_t i = 0; i < n; ++i) dst[i] = ((const double *)g->data)[ofs + i];
    else
        for (size_t i = 0; i < n; ++i) dst[i] = ((const float *)g->data)[ofs + i];
}

int shl_grid_get_node(const shl_grid *grid, const int idx[3], double *rgb, double *grad)
{
    const int st = check_node(grid, idx);
    if (st) return st;
    if (!rgb) return SHL_ENULL;
    const size_t ofs = node_offset(grid, idx), nv = 3 * (size_t)grid->nc;
    load(grid, ofs, rgb, nv);
    if (grad) load(grid, ofs + nv, grad, 3 * nv);
    return SHL_OK;
}

int shl_grid_set_node(shl_grid *grid, const int idx[3], const double *rgb, const double *grad)
{
    const int st = check_node(grid, idx);
    if (st) return st;
    if (!rgb || !grad) return SHL_ENULL;
    const int nv = 3 * grid->nc;
    if (shl__check_finite(rgb, nv) || shl__check_finite(grad, 3 * nv)) return SHL_ENONFINITE;
    const size_t ofs = node_offset(grid, idx);
    store(grid, ofs, rgb, (size_t)nv);
    store(grid, ofs + (size_t)nv, grad, 3 * (size_t)nv);
    return SHL_OK;
}

typedef struct {
    shl_grid *g;
    const shl_lights *lights;
    double *ws;      /* per worker: node_len doubles of output, then the light workspace */
    size_t ws_len;
} fill_job;

static void fill_range(void *arg, int worker, long begin, long end)
{
    const fill_job *job = arg;
    shl_grid *g = job->g;
    double *out = job->ws + (size_t)worker * job->ws_len, *lws = out + g->node_len;
    for (long node = begin; node < end; ++node) {
        const int idx[3] = {(int)(node % g->res[0]), (int)(node / g->res[0] % g->res[1]),
                            (int)(node / g->res[0] / g->res[1])};
        double x[3];
        shl__grid_node_pos(g, idx, x);
        shl__lights_eval(job->lights, g->lmax, lws, x, out, out + 3 * g->nc); /* Wu 2020 Alg. 1 l. 5-7 */
        store(g, (size_t)node * g->node_len, out, g->node_len);
    }
}

int shl_grid_fill(shl_grid *grid, const shl_lights *lights, int nthreads)
{
    if (!grid || !lights) return SHL_ENULL;
    if (nthreads < 1 || nthreads > SHL_MAX_THREADS) return SHL_EDOMAIN;
    const long n = (long)grid->nnodes, grain = 1;
    const int nw = shl__parallel_workers(n, grain, nthreads);
    fill_job job = {grid, lights, NULL, grid->node_len + shl__lights_ws_size(grid->lmax)};
    job.ws = shl__malloc(sizeof(double) * job.ws_len * (size_t)nw);
    if (!job.ws) return SHL_ENOMEM;
    const int st = shl__parallel_for(n, grain, nw, fill_range, &job);
    shl__free(job.ws);
    return st;
}
