/* Regular grids of RGB SH coefficients and gradients over a box, filled from
 * a light set (Wu et al. 2020, Alg. 1 lines 2-8), in parallel: float grids in
 * blocks of nodes through the float SIMD light-set batch (lights_batch.c),
 * double grids node by node through shl__lights_eval. */
#include "grid.h"
#include "lights.h"
#include "parallel.h"
#include <float.h>
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
    g->data = shl__calloc_large(nnodes * node_len, esize);
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
    shl__free(grid->light_box);
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
    shl_ctx ctx;     /* the grid's lmax and batch kernels */
    char *ws;        /* per worker: stride bytes of workspace */
    size_t stride;
} fill_job;

static void node_index(const shl_grid *g, long node, int idx[3])
{
    idx[0] = (int)(node % g->res[0]);
    idx[1] = (int)(node / g->res[0] % g->res[1]);
    idx[2] = (int)(node / g->res[0] / g->res[1]);
}

/* Double path, per node: shl__lights_eval, stored (rounded) in the grid's type. */
static void fill_range(void *arg, int worker, long begin, long end)
{
    const fill_job *job = arg;
    shl_grid *g = job->g;
    double *out = (double *)(job->ws + job->stride * (size_t)worker), *lws = out + g->node_len;
    for (long node = begin; node < end; ++node) {
        int idx[3];
        double x[3];
        node_index(g, node, idx);
        shl__grid_node_pos(g, idx, x);
        shl__lights_eval(job->lights, g->lmax, lws, x, out, out + 3 * g->nc); /* Wu 2020 Alg. 1 l. 5-7 */
        store(g, (size_t)node * g->node_len, out, g->node_len);
    }
}

/* Float path, per block of SHL__LIGHTS_BLOCK nodes: the float light-set batch at
 * the node positions rounded to float, written straight into the nodes (values
 * and gradients, stride node_len: the layout of shl_lights_eval). */
static void fill_range_f(void *arg, int worker, long begin, long end)
{
    const fill_job *job = arg;
    shl_grid *g = job->g;
    void *buf = job->ws ? job->ws + job->stride * (size_t)worker : NULL;
    float pts[3 * SHL__LIGHTS_BLOCK];
    for (long b = begin; b < end; ++b) {
        const long n0 = b * SHL__LIGHTS_BLOCK, left = (long)g->nnodes - n0;
        const int m = left < SHL__LIGHTS_BLOCK ? (int)left : SHL__LIGHTS_BLOCK;
        for (int j = 0; j < m; ++j) {
            int idx[3];
            double x[3];
            node_index(g, n0 + j, idx);
            shl__grid_node_pos(g, idx, x);
            for (int a = 0; a < 3; ++a) pts[3 * j + a] = (float)x[a];
        }
        float *node = (float *)g->data + (size_t)n0 * g->node_len;
        shl__lights_batch_f_block(&job->ctx, job->lights, m, pts, node, g->node_len, node + 3 * g->nc, g->node_len,
                                  buf); /* Wu 2020 Alg. 1 l. 5-7 */
    }
}

/* Float path when rounding the node positions to float keeps them finite and
 * moves them by at most 2^-24 max(|lo|, |hi|) <= 2^-14 h per axis (include/shlight.h). */
static int float_path(const shl_grid *g)
{
    if (g->storage != SHL_GRID_FLOAT) return 0;
    for (int a = 0; a < 3; ++a) {
        const double m = fmax(fabs(g->lo[a]), fabs(g->hi[a]));
        if (!(m <= 0x1p126 && g->h[a] >= 0x1p-10 * m && g->h[a] >= 0x1p-100)) return 0;
    }
    return 1;
}

/* ---- lights meeting the box (closed sets, decided in floating point) ---- */

/* (a - b) / (c - d), the differences halved where one overflows (its operands then exceed 2^969: exact halves). */
static double diff_ratio(double a, double b, double c, double d)
{
    double num = a - b, den = c - d;
    if (isinf(num) || isinf(den)) {
        num = 0.5 * a - 0.5 * b;
        den = 0.5 * c - 0.5 * d;
    }
    return num / den;
}

/* Does the segment from a to b meet the closed box [lo, hi]?  Its parameter
 * interval t in [0, 1] clipped by the three slabs lo <= a + t (b - a) <= hi. */
static int segment_meets_box(const double *a, const double *b, const double lo[3], const double hi[3])
{
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        if (a[k] == b[k]) {
            if (a[k] < lo[k] || a[k] > hi[k]) return 0;
            continue;
        }
        double ta = diff_ratio(lo[k], a[k], b[k], a[k]), tb = diff_ratio(hi[k], a[k], b[k], a[k]);
        if (ta > tb) {
            const double t = ta;
            ta = tb;
            tb = t;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        if (t0 > t1) return 0;
    }
    return 1;
}

/* Is some point of the closed box in the (planar, simple) polygon v[0..n-1],
 * given that no edge meets the box?  Then the box's section by the polygon's
 * plane, convex and connected, meets no edge: it lies wholly inside or wholly
 * outside the polygon, and one of its points q decides (crossing-number test in
 * the plane of the two axes other than the normal's largest component). */
static int section_in_polygon(const double nrm[3], const double *v, int n, const double lo[3], const double hi[3])
{
    const double m = fmax(fabs(nrm[0]), fmax(fabs(nrm[1]), fabs(nrm[2])));
    if (!(m > 0.0)) return 0; /* collinear vertices: no area, the edges are all of it */
    double c[8][3], f[8];
    int e = INT_MIN;
    for (int j = 0; j < 8; ++j)
        for (int k = 0; k < 3; ++k) {
            c[j][k] = (j >> k) & 1 ? hi[k] : lo[k];
            const int ek = shl__ilogb_diff(c[j][k], v[k]);
            e = ek > e ? ek : e;
        }
    if (e == INT_MIN) return 1; /* unreachable (lo < hi): every corner at v_0 */
    int pos = 0, neg = 0, on = -1; /* corners in front of, behind, on the plane: signed distances in units 2^e m */
    for (int j = 0; j < 8; ++j) {
        f[j] = 0.0;
        for (int k = 0; k < 3; ++k) f[j] += nrm[k] / m * shl__diff_scaled(c[j][k], v[k], -e);
        pos += f[j] > 0.0;
        neg += f[j] < 0.0;
        on = f[j] == 0.0 ? j : on;
    }
    double q[3];
    if (on >= 0)
        memcpy(q, c[on], sizeof q);
    else if (!pos || !neg)
        return 0; /* the plane misses the box */
    else { /* a box edge j -> j ^ 2^a whose ends lie on opposite sides (the cube's edges connect its corners) */
        int j = 0, a = -1;
        for (int jj = 0; jj < 8 && a < 0; ++jj)
            for (int aa = 0; aa < 3 && a < 0; ++aa)
                if (f[jj] < 0.0 && f[jj ^ (1 << aa)] > 0.0) {
                    j = jj;
                    a = aa;
                }
        const double t = f[j] / (f[j] - f[j ^ (1 << a)]); /* in (0, 1): no cancellation */
        memcpy(q, c[j], sizeof q);
        q[a] = fmin(fmax(c[j][a] * (1.0 - t) + c[j ^ (1 << a)][a] * t, lo[a]), hi[a]);
    }
    const int kd = fabs(nrm[0]) == m ? 0 : fabs(nrm[1]) == m ? 1 : 2, i0 = (kd + 1) % 3, i1 = (kd + 2) % 3;
    int inside = 0;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        const double *p = v + 3 * i, *r = v + 3 * j;
        if ((p[i1] > q[i1]) != (r[i1] > q[i1])) {
            const double s = diff_ratio(q[i1], p[i1], r[i1], p[i1]); /* in [0, 1] */
            inside ^= q[i0] < p[i0] * (1.0 - s) + r[i0] * s;
        }
    }
    return inside;
}

/* Does the ball |x - c| <= r meet the closed box?  Its distance to the box,
 * sqrt(sum_k d_k^2), d_k = max(lo_k - c_k, 0, c_k - hi_k), against r, squares
 * taken in units of 2^ilogb(max d_k) so that none over- or underflows. */
static int ball_meets_box(const double c[3], double r, const double lo[3], const double hi[3])
{
    double d[3], dm = 0.0;
    for (int k = 0; k < 3; ++k) {
        d[k] = c[k] < lo[k] ? lo[k] - c[k] : c[k] > hi[k] ? c[k] - hi[k] : 0.0; /* overflow: inf > r */
        dm = d[k] > dm ? d[k] : dm;
    }
    if (dm > r) return 0;
    if (dm == 0.0 || r >= 2.0 * dm) return 1; /* distance <= sqrt(3) dm */
    const int e = shl__ilogb(dm);
    double q = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double s = shl__ldexp(d[k], -e);
        q += s * s;
    }
    const double rs = shl__ldexp(r, -e); /* in [1, 4) */
    return q <= rs * rs;
}

static int light_meets_box(const shl_lights *lights, const shl__light *li, const double lo[3], const double hi[3])
{
    if (li->kind == SHL__LIGHT_SPHERE) return ball_meets_box(li->center, li->radius, lo, hi);
    const double *v = lights->verts + li->vofs;
    for (int i = 0, j = li->n - 1; i < li->n; j = i++)
        if (segment_meets_box(v + 3 * j, v + 3 * i, lo, hi)) return 1;
    return section_in_polygon(li->normal, v, li->n, lo, hi);
}

/* SHL__BOX_* bits of every light; the grown box is clipped to the doubles (all geometry lies inside). */
static void classify_lights(const shl_grid *g, const shl_lights *lights, unsigned char *box)
{
    double glo[3], ghi[3];
    for (int a = 0; a < 3; ++a) {
        glo[a] = fmax(g->lo[a] - g->h[a], -DBL_MAX);
        ghi[a] = fmin(g->hi[a] + g->h[a], DBL_MAX);
    }
    for (int i = 0; i < lights->count; ++i) {
        const shl__light *li = &lights->items[i];
        box[i] = light_meets_box(lights, li, g->lo, g->hi) ? SHL__BOX_IN | SHL__BOX_NEAR
                 : light_meets_box(lights, li, glo, ghi) ? SHL__BOX_NEAR : 0;
    }
}

int shl_grid_fill(shl_grid *grid, const shl_lights *lights, int nthreads)
{
    if (!grid || !lights) return SHL_ENULL;
    if (nthreads < 1 || nthreads > SHL_MAX_THREADS) return SHL_EDOMAIN;
    unsigned char *box = NULL;
    if (lights->count > 0) {
        box = shl__malloc((size_t)lights->count);
        if (!box) return SHL_ENOMEM;
        classify_lights(grid, lights, box);
    }
    const int batch = float_path(grid);
    const long n = batch ? ((long)grid->nnodes + SHL__LIGHTS_BLOCK - 1) / SHL__LIGHTS_BLOCK : (long)grid->nnodes;
    const int nw = shl__parallel_workers(n, 1, nthreads);
    fill_job job = {grid, lights, {grid->lmax, grid->nc, grid->isa}, NULL, 0};
    job.stride = batch ? shl__ws_stride(shl__lights_batch_f_bytes(&job.ctx, lights, 1))
                       : shl__ws_stride(sizeof(double) * (grid->node_len + shl__lights_ws_size(grid->lmax)));
    if (job.stride > 0 && !(job.ws = shl__malloc(job.stride * (size_t)nw))) {
        shl__free(box);
        return SHL_ENOMEM;
    }
    const int st = shl__parallel_for(n, 1, nw, batch ? fill_range_f : fill_range, &job); /* SHL_ETHREAD: nothing written */
    shl__free(job.ws);
    if (st) {
        shl__free(box);
        return st;
    }
    shl__free(grid->light_box);
    grid->light_box = box;
    grid->nlights = lights->count;
    return SHL_OK;
}

int shl_grid_lights_in_box(const shl_grid *grid, int which, int cap, int *index, int *count)
{
    if (!grid || !count || (cap > 0 && !index)) return SHL_ENULL;
    if ((which != SHL_GRID_IN_BOX && which != SHL_GRID_NEAR_BOX) || cap < 0) return SHL_EDOMAIN;
    const unsigned char bit = which == SHL_GRID_IN_BOX ? SHL__BOX_IN : SHL__BOX_NEAR;
    int found = 0;
    for (int i = 0; i < grid->nlights; ++i)
        if (grid->light_box[i] & bit) {
            if (found < cap) index[found] = i;
            ++found;
        }
    *count = found;
    return SHL_OK;
}
