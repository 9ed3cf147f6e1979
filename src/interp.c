/* Interpolation of grid coefficients at arbitrary points (Wu et al. 2020,
 * Alg. 1 lines 9-16): trilinear, first-order Taylor blended by inverse
 * distance (Annen et al. 2004, Eq. 14-16), tricubic Hermite (Wu 2020 Alg. 4). */
#include "grid.h"
#include "parallel.h"
#include <limits.h>
#include <math.h>

/* Per-point quantities shared by the kernels of interp_kernel.h and simd/interp_batch.h. */
typedef shl__interp_point point_setup;

#define ELEM float
#define SUFFIX(name) name##_f
#include "interp_kernel.h"
#undef ELEM
#undef SUFFIX
#define ELEM double
#define SUFFIX(name) name##_d
#include "interp_kernel.h"
#undef ELEM
#undef SUFFIX

/* The scalar table's interpolation (dispatch.c): the reference above. */
void shl__interp_ref_f(const float *data, int method, int nc, const shl__interp_point *s, shl__interp_ahead *ahead,
                       double *out)
{
    interp_f(data, method, nc, s, ahead, out);
}

/* The float-sum reference (the scalar instance of simd/interp_batch.h's
 * shl__interp_ff): the weighted sums of shl__interp_point_ff in plain C and in
 * the SIMD kernels' order -- trilinear, corners 0..7; Taylor and Hermite, per
 * channel, corners 0-3 and 4-7 summed apart (value, then x, y, z gradient rows),
 * then added. */
static void interp_ff_point(const float *data, int method, int nc, const shl__interp_point_ff *s, float *out)
{
    const float *f[8];
    for (int j = 0; j < 8; ++j) f[j] = data + s->ofs[j];
    if (method == SHL_INTERP_TRILINEAR) {
        for (int i = 0; i < 3 * nc; ++i) {
            float v = s->w[0] * f[0][i];
            for (int j = 1; j < 8; ++j) v += s->w[j] * f[j][i];
            out[i] = v;
        }
        return;
    }
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < nc; ++k) {
            float half[2] = {0.0f, 0.0f};
            for (int j = 0; j < 8; ++j) {
                const float *gx = f[j] + 3 * nc + 3 * c * nc + k;
                half[j >> 2] += s->w[j] * f[j][c * nc + k];
                half[j >> 2] += s->wd[j][0] * gx[0];
                half[j >> 2] += s->wd[j][1] * gx[nc];
                half[j >> 2] += s->wd[j][2] * gx[2 * nc];
            }
            out[c * nc + k] = half[0] + half[1];
        }
}

void shl__interp_ff_ref(const float *data, int method, int nc, const shl__interp_point_ff *s,
                        const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2)
{
    shl__interp_ahead_plan(ahead, 1);
    shl__interp_ahead_step(ahead);
    interp_ff_point(data, method, nc, s, out);
    if (s2) interp_ff_point(data, method, nc, s2, out2);
}

/* Cell and local coordinates of p, clamped to the box. */
static void locate(const shl_grid *g, const double p[3], point_setup *s)
{
    int cell[3];
    for (int a = 0; a < 3; ++a) { /* p is finite (grid_interp checked): comparisons, not the fmin/fmax calls */
        const double x = p[a] < g->lo[a] ? g->lo[a] : p[a] > g->hi[a] ? g->hi[a] : p[a];
        const double t = (x - g->lo[a]) / g->h[a];
        cell[a] = t < g->res[a] - 1 ? (int)t : g->res[a] - 2;
        s->u[a] = t - cell[a] < 1.0 ? t - cell[a] : 1.0;
    }
    for (int j = 0; j < 8; ++j) {
        const size_t ix = (size_t)cell[0] + (j & 1), iy = (size_t)cell[1] + ((j >> 1) & 1), iz = (size_t)cell[2] + (j >> 2);
        s->ofs[j] = (ix + (size_t)g->res[0] * (iy + (size_t)g->res[1] * iz)) * g->node_len;
    }
}

static void trilinear_weights(point_setup *s)
{
    for (int j = 0; j < 8; ++j)
        s->w[j] = (j & 1 ? s->u[0] : 1.0 - s->u[0]) * (j & 2 ? s->u[1] : 1.0 - s->u[1]) *
                  (j & 4 ? s->u[2] : 1.0 - s->u[2]);
}

/* Annen 2004 Eq. (16), w_j = |p - p_j|^-b / sum_i |p - p_i|^-b, evaluated as
 * (d_min / d_j)^b normalized so that nothing overflows; at a node, its value.
 * Each distance is held as r_j 2^e_j, r_j in [1, 2 sqrt 3), from its components
 * in units of 2^e_j, the largest one's power of two: squares of huge or tiny
 * components would over/underflow, and so would a common unit when the cell's
 * sides differ by more than ~2^1000.  The ratios d_min / d_j are then exact
 * scalings.  The nearest corner is found without branches (mispredicted on random
 * points, they cost 20% of the set-up). */
static void taylor_weights(const shl_grid *g, double b, point_setup *s)
{
    double d[8][3], r[8], rmin = INFINITY, sum = 0.0;
    int e[8], emin = INT_MAX, at_node = 0;
    for (int j = 0; j < 8; ++j) {
        double m = 0.0, q = 0.0;
        for (int a = 0; a < 3; ++a) {
            d[j][a] = (s->u[a] - ((j >> a) & 1)) * g->h[a];
            m = fabs(d[j][a]) > m ? fabs(d[j][a]) : m; /* finite: not the fmax call */
        }
        if (m == 0.0) { /* p is node j */
            at_node = 1;
            r[j] = 0.0;
            e[j] = 0;
            continue;
        }
        e[j] = shl__ilogb(m);
        double unit[2]; /* 2^-e_j, as two factors where it exceeds the double range (m subnormal) */
        if (e[j] >= -1022) {
            unit[0] = shl__ldexp(1.0, -e[j]);
            unit[1] = 1.0;
        } else
            shl__pow2_split(-e[j], unit);
        for (int a = 0; a < 3; ++a) {
            const double ds = d[j][a] * unit[0] * unit[1];
            q += ds * ds;
        }
        r[j] = sqrt(q);
        emin = e[j] < emin ? e[j] : emin;
    }
    if (!at_node) /* d_min = rmin 2^emin: a corner with e_j >= emin + 2 is farther than every one at emin */
        for (int j = 0; j < 8; ++j) {
            const int shift = e[j] - emin < 2 ? e[j] - emin : 2;
            const double key = r[j] * (double)(1 << shift);
            rmin = key < rmin ? key : rmin;
        }
    for (int j = 0; j < 8; ++j) {
        s->w[j] = at_node ? (double)(r[j] == 0.0) : pow(shl__ldexp(rmin / r[j], emin - e[j]), b);
        sum += s->w[j];
    }
    for (int j = 0; j < 8; ++j) {
        s->w[j] /= sum;
        for (int a = 0; a < 3; ++a) s->wd[j][a] = s->w[j] * d[j][a];
    }
}

/* Cubic Hermite basis on [0, 1] (Wu 2020 Eq. 33-35 with x_L = 0, x_R = h):
 * q = (1+2u)(1-u)^2 f_L + u(1-u)^2 h f'_L + u^2(3-2u) f_R - u^2(1-u) h f'_R, exact at u = 0, 1. */
static void hermite_weights(const shl_grid *g, point_setup *s)
{
    for (int a = 0; a < 3; ++a) {
        const double u = s->u[a], v = 1.0 - u;
        s->hw[a][0] = (1.0 + 2.0 * u) * v * v;
        s->hw[a][1] = u * v * v * g->h[a];
        s->hw[a][2] = u * u * (3.0 - 2.0 * u);
        s->hw[a][3] = -u * u * v * g->h[a];
    }
}

typedef struct {
    const shl_grid *g;
    int method;
    double b;
    const double *pts;
    double *out;
    int ahead; /* request the next point's rows (grids above SHL__INTERP_AHEAD_BYTES) */
} interp_job;

static void setup_at(const shl_grid *g, int method, double b, const double x[3], point_setup *s)
{
    locate(g, x, s);
    if (method == SHL_INTERP_TAYLOR)
        taylor_weights(g, b, s);
    else if (method == SHL_INTERP_HERMITE)
        hermite_weights(g, s);
    else
        trilinear_weights(s);
}

static void setup_point(const interp_job *job, long p, point_setup *s)
{
    setup_at(job->g, job->method, job->b, job->pts + 3 * p, s);
}

/* The rows point s reads: Taylor and Hermite, all 12 nc elements of each
 * corner, corners 2q and 2q+1 adjacent nodes (one row of two nodes each);
 * trilinear, the 3 nc values of each corner. */
static void ahead_rows(const shl_grid *g, int method, const size_t ofs[8], shl__interp_ahead *a)
{
    const size_t esize = g->storage == SHL_GRID_DOUBLE ? sizeof(double) : sizeof(float);
    const char *data = g->data;
    const int pairs = method != SHL_INTERP_TRILINEAR;
    a->nrange = pairs ? 4 : 8;
    a->bytes = (pairs ? 2 * g->node_len : 3 * (size_t)g->nc) * esize;
    for (int r = 0; r < a->nrange; ++r) a->row[r] = data + ofs[pairs ? 2 * r : r] * esize;
}

/* Two points in flight: point p + 1's set-up is made before point p's
 * arithmetic (the core overlaps the two) and, if job->ahead, its corner rows
 * are requested during p's arithmetic (shl__interp_ahead).  The results are
 * those of one point at a time: the requests change no value. */
static void interp_range(void *arg, int worker, long begin, long end)
{
    const interp_job *job = arg;
    const shl_grid *g = job->g;
    const size_t nv = 3 * (size_t)g->nc;
    point_setup s[2];
    (void)worker;
    if (begin < end) setup_point(job, begin, &s[begin & 1]);
    for (long p = begin; p < end; ++p) {
        shl__interp_ahead ahead = {.nrange = 0};
        if (p + 1 < end) {
            setup_point(job, p + 1, &s[(p + 1) & 1]);
            if (job->ahead) ahead_rows(g, job->method, s[(p + 1) & 1].ofs, &ahead);
        }
        double *out = job->out + nv * (size_t)p;
        if (g->storage == SHL_GRID_DOUBLE)
            interp_d(g->data, job->method, g->nc, &s[p & 1], &ahead, out);
        else /* the context's kernel (simd/interp_batch.h; scalar: interp_f) */
            g->isa->interp_f(g->data, job->method, g->nc, &s[p & 1], &ahead, out);
    }
}

/* The checks of every entry point before its points' (same order). */
static int check_call(const shl_grid *grid, int method, double taylor_b, int npts, const void *pts, const void *rgb,
                      int nthreads)
{
    if (!grid || !pts || !rgb) return SHL_ENULL;
    if (method != SHL_INTERP_TRILINEAR && method != SHL_INTERP_TAYLOR && method != SHL_INTERP_HERMITE)
        return SHL_EDOMAIN;
    if (method == SHL_INTERP_TAYLOR) {
        if (!isfinite(taylor_b)) return SHL_ENONFINITE;
        if (!(taylor_b > 0.0)) return SHL_EDOMAIN;
    }
    if (npts < 0 || nthreads < 1 || nthreads > SHL_MAX_THREADS) return SHL_EDOMAIN;
    return SHL_OK;
}

/* Shared by both entry points: nclamped (if not NULL) receives the number of
 * points with a coordinate outside [lo[a], hi[a]], counted while validating,
 * in the calling thread (independent of nthreads), and written only on success. */
static int grid_interp(const shl_grid *grid, int method, double taylor_b, int npts, const double *pts, double *rgb,
                       int nthreads, int *nclamped)
{
    const int bad = check_call(grid, method, taylor_b, npts, pts, rgb, nthreads);
    if (bad) return bad;
    if (shl__check_finite(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    int outside = 0;
    for (int p = 0; p < npts; ++p) {
        const double *x = pts + 3 * (size_t)p;
        int out = 0;
        for (int a = 0; a < 3; ++a) out |= x[a] < grid->lo[a] || x[a] > grid->hi[a];
        outside += out;
    }
    const size_t esize = grid->storage == SHL_GRID_DOUBLE ? sizeof(double) : sizeof(float);
    interp_job job = {grid, method, taylor_b, pts, rgb, grid->nnodes * grid->node_len * esize > SHL__INTERP_AHEAD_BYTES};
    /* A worker per 256 points at most (a thread's create + join took >= 16 us
     * here, ~100 points at lmax 4; more when an idle vCPU must wake); chunks of
     * 32 points and more (guided), so that the workers end within ~32 points of
     * each other (lmax 8 in L2: ~11 us; 256-point chunks left up to 90 us);
     * each chunk's first point goes without look-ahead. */
    const int nw = shl__parallel_workers(npts, 256, nthreads);
    const int st = shl__parallel_for_guided(npts, 32, nw, interp_range, &job);
    if (st == SHL_OK && nclamped) *nclamped = outside;
    return st;
}

int shl_grid_interp(const shl_grid *grid, int method, double taylor_b, int npts, const double *pts,
                    double *rgb, int nthreads)
{
    return grid_interp(grid, method, taylor_b, npts, pts, rgb, nthreads, NULL);
}

int shl_grid_interp_clamped(const shl_grid *grid, int method, double taylor_b, int npts, const double *pts,
                            double *rgb, int nthreads, int *nclamped)
{
    if (!nclamped) return SHL_ENULL;
    return grid_interp(grid, method, taylor_b, npts, pts, rgb, nthreads, nclamped);
}

/* ---- Float sums (shl_grid_interp_f) ---- */

typedef struct {
    const shl_grid *g;
    int method;
    double b;
    const float *pts;
    float *out;
    int ahead; /* as interp_job */
    shl__interp_geom geom; /* g's, for shl__interp_setup_ff */
} interp_job_ff;

/* The set-up of points p0 .. p0 + n - 1 (n <= SHL__INTERP_FF_BLOCK) into sf[0 .. n - 1]:
 * trilinear and Hermite across the block by the context's kernel
 * (simd/interp_batch.h, shl__interp_setup_ff); Taylor (pow per corner) point by
 * point, setup_at; weights rounded to float once. */
static void setup_block_ff(const interp_job_ff *job, long p0, int n, shl__interp_point_ff *sf)
{
    const shl_grid *g = job->g;
    const float *pts = job->pts + 3 * p0;
    if (job->method != SHL_INTERP_TAYLOR) {
        g->isa->interp_setup_ff(&job->geom, job->method, n, pts, sf);
        return;
    }
    for (int i = 0; i < n; ++i) {
        const double x[3] = {pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]};
        point_setup s;
        setup_at(g, job->method, job->b, x, &s);
        for (int j = 0; j < 8; ++j) {
            sf[i].ofs[j] = s.ofs[j];
            sf[i].w[j] = (float)s.w[j];
            for (int a = 0; a < 3; ++a) sf[i].wd[j][a] = (float)s.wd[j][a];
        }
    }
}

/* Point k's set-up in interp_range_ff's ring of two blocks. */
static shl__interp_point_ff *ring_at(shl__interp_point_ff sf[2][SHL__INTERP_FF_BLOCK], long k)
{
    return &sf[(k / SHL__INTERP_FF_BLOCK) & 1][k % SHL__INTERP_FF_BLOCK];
}

/* interp_range with float sums: set-ups a block at a time, ahead of the points
 * (a ring of two blocks), the same look-ahead.  Two consecutive points of one
 * cell (most of a mesh's, in mesh order) go to the kernel together, which loads
 * their corner rows once; the results are those of one point at a time. */
static void interp_range_ff(void *arg, int worker, long begin, long end)
{
    const interp_job_ff *job = arg;
    const shl_grid *g = job->g;
    const size_t nv = 3 * (size_t)g->nc;
    const long n = end - begin;
    shl__interp_point_ff sf[2][SHL__INTERP_FF_BLOCK];
    long ready = 0; /* points begin .. begin + ready - 1 are set up */
    (void)worker;
    for (long k = 0; k < n;) {
        /* through k + 2 (a pair and the next point's rows): its block replaces the one before k's */
        while (ready < n && ready <= k + 2) {
            const int m = n - ready < SHL__INTERP_FF_BLOCK ? (int)(n - ready) : SHL__INTERP_FF_BLOCK;
            setup_block_ff(job, begin + ready, m, ring_at(sf, ready));
            ready += m;
        }
        const shl__interp_point_ff *cur = ring_at(sf, k), *cur2 = NULL;
        if (k + 1 < n && ring_at(sf, k + 1)->ofs[0] == cur->ofs[0]) cur2 = ring_at(sf, k + 1);
        const long next = k + 1 + (cur2 != NULL);
        shl__interp_ahead ahead = {.nrange = 0};
        if (next < n && job->ahead) ahead_rows(g, job->method, ring_at(sf, next)->ofs, &ahead);
        float *out = job->out + nv * (size_t)(begin + k);
        g->isa->interp_ff(g->data, job->method, g->nc, cur, cur2, &ahead, out, cur2 ? out + nv : NULL);
        k = next;
    }
}

/* Spacings whose float weights (Taylor, Hermite: up to h[a]) neither overflow nor
 * lose more than 2^-150 |gradient| <= 2^-50 M to underflow (README "Grid interpolation"). */
#define SPACING_FF_MIN 0x1p-100
#define SPACING_FF_MAX 0x1p127

int shl_grid_interp_f(const shl_grid *grid, int method, double taylor_b, int npts, const float *pts, float *rgb,
                      int nthreads)
{
    const int bad = check_call(grid, method, taylor_b, npts, pts, rgb, nthreads);
    if (bad) return bad;
    if (grid->storage != SHL_GRID_FLOAT) return SHL_EDOMAIN;
    for (int a = 0; a < 3 && method != SHL_INTERP_TRILINEAR; ++a)
        if (!(grid->h[a] >= SPACING_FF_MIN && grid->h[a] <= SPACING_FF_MAX)) return SHL_EDOMAIN;
    if (shl__check_finite_f(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    interp_job_ff job = {grid, method, taylor_b, pts, rgb,
                         grid->nnodes * grid->node_len * sizeof(float) > SHL__INTERP_AHEAD_BYTES,
                         {.node_len = grid->node_len}};
    for (int a = 0; a < 3; ++a) {
        job.geom.lo[a] = grid->lo[a];
        job.geom.hi[a] = grid->hi[a];
        job.geom.h[a] = grid->h[a];
        job.geom.res[a] = grid->res[a];
    }
    const int nw = shl__parallel_workers(npts, 256, nthreads); /* as grid_interp */
    return shl__parallel_for_guided(npts, 32, nw, interp_range_ff, &job);
}
