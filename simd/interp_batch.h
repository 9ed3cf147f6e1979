/* Grid interpolation (Wu et al. 2020 Alg. 1 lines 9-16) from float node
 * storage, vectorized ACROSS COEFFICIENTS: one point at a time, each vector
 * holds VL consecutive coefficients k of one colour channel, so every load of
 * a corner's node data is contiguous.  The per-point set-up (cell, weights) is
 * computed once in double by src/interp.c and broadcast; the node data are
 * widened to double as they are loaded and the sums run in double FMAs, as in
 * the reference (float sums, measured 1.3-2x faster for Hermite, lost the
 * reference's guarantees: see README "Grid interpolation").  Written once
 * with the verbs of <isa>/helper.h and compiled once per ISA of
 * simd/isa_list.h (Makefile); for helpers without double verbs (SHL_VDLEN
 * undefined: scalar) it forwards to the readable double reference,
 * src/interp_kernel.h, whose formulas and comments this file follows line by
 * line.
 *
 * Each block also requests a share of the next point's corner rows
 * (shl__interp_ahead, simd/kernel_api.h), spread evenly over the blocks.
 *
 * Blocks: a row of n >= VL coefficients is covered by blocks at k = 0, VL, ...
 * and a last block at n - VL, which overlaps the previous one and rewrites the
 * same values.  Rows shorter than VL (nc < VL: lmax 0, one coefficient) run
 * the reference: a zero-padded copy measured 4-8x slower than it
 * (bench/bench_interp.c, lmax 0).  A helper may name a narrower ISA's kernel
 * for them instead, SHL_INTERP_SHORT_ROWS (avx512: lmax 1, 4 coefficients, on
 * the avx2 kernel). */
#include "kernel_api.h"

#define ISA(name) SHL_ISA_SUFFIX(name)

#ifndef SHL_VDLEN
void ISA(shl__interp_f)(const float *data, int method, int nc, const shl__interp_point *s, shl__interp_ahead *ahead,
                        double *out)
{
    shl__interp_ref_f(data, method, nc, s, ahead, out);
}
#else
#define VL SHL_VDLEN
#ifdef SHL_INTERP_SHORT_ROWS
void SHL_INTERP_SHORT_ROWS(const float *data, int method, int nc, const shl__interp_point *s, shl__interp_ahead *ahead,
                           double *out);
#endif

/* Start of the block after k in a row of n >= VL: the last one ends at n. */
static inline int block_start(int k, int n) { return k + VL <= n ? k : n - VL; }

/* Trilinear: out[i] = sum_j w_j f_j[i] over the 3 nc values (one contiguous row). */
/* Each kernel broadcasts only the point's weights it reads: broadcasting all of them into one
 * struct cost 48 vector stores per point (Hermite, lmax 4, avx512: 262 -> 221 ns per point). */
static void trilinear(const float *const f[8], const shl__interp_point *s, int nc, shl__interp_ahead *ahead, double *out)
{
    const int n = 3 * nc;
    vd w[8];
    for (int j = 0; j < 8; ++j) w[j] = vd_set1(s->w[j]);
    shl__interp_ahead_plan(ahead, (size_t)(n + VL - 1) / VL);
    for (int k = 0; k < n; k += VL) {
        const int i = block_start(k, n);
        shl__interp_ahead_step(ahead);
        vd v = vd_mul(w[0], vd_load_float(f[0] + i));
        for (int j = 1; j < 8; ++j) v = vd_fma(w[j], vd_load_float(f[j] + i), v);
        vd_store(out + i, v);
    }
}

/* The per-channel methods visit 3 channels of ceil(nc / VL) vectors each. */
static inline void channels_plan(int nc, shl__interp_ahead *ahead)
{
    shl__interp_ahead_plan(ahead, 3 * (size_t)((nc + VL - 1) / VL));
}

/* Channel c's vector at k: steps the prefetch and gives its value offset *vo and
 * x-gradient offset *go in a row (3 nc values, then 3 nc gradients per channel). */
static inline void channel_block(int c, int k, int nc, shl__interp_ahead *ahead, size_t *vo, size_t *go)
{
    const int i = block_start(k, nc);
    shl__interp_ahead_step(ahead);
    *vo = (size_t)c * nc + i;
    *go = 3 * (size_t)nc + 3 * (size_t)c * nc + i;
}

/* Annen 2004 Eq. (15): sum_j w_j (c_j + grad c_j . d_j), per channel. */
static void taylor(const float *const f[8], const shl__interp_point *s, int nc, shl__interp_ahead *ahead, double *out)
{
    vd w[8], wd[8][3];
    for (int j = 0; j < 8; ++j) {
        w[j] = vd_set1(s->w[j]);
        for (int a = 0; a < 3; ++a) wd[j][a] = vd_set1(s->wd[j][a]);
    }
    channels_plan(nc, ahead);
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < nc; k += VL) {
            size_t vo, go;
            channel_block(c, k, nc, ahead, &vo, &go);
            vd o = vd_set1(0.0f);
            for (int j = 0; j < 8; ++j) {
                o = vd_fma(w[j], vd_load_float(f[j] + vo), o);
                o = vd_fma(wd[j][0], vd_load_float(f[j] + go), o);
                o = vd_fma(wd[j][1], vd_load_float(f[j] + go + nc), o);
                o = vd_fma(wd[j][2], vd_load_float(f[j] + go + 2 * (size_t)nc), o);
            }
            vd_store(out + vo, o);
        }
}

/* Wu 2020 Alg. 4 lines 4-7 for corners a = 2q and b = 2q + 1: along x, the
 * value g and the y- and z-gradients g_y, g_z carried linearly (lines 6-7). */
typedef struct {
    vd g, g_y, g_z;
} along_x;

static inline along_x hermite_x(const float *a, const float *b, size_t vo, size_t gxo, size_t gyo, size_t gzo,
                                const vd x[4], vd ux, vd vx)
{
    along_x r;
    r.g = vd_fma(x[0], vd_load_float(a + vo),
                 vd_fma(x[1], vd_load_float(a + gxo), vd_fma(x[2], vd_load_float(b + vo), vd_mul(x[3], vd_load_float(b + gxo)))));
    r.g_y = vd_fma(vx, vd_load_float(a + gyo), vd_mul(ux, vd_load_float(b + gyo)));
    r.g_z = vd_fma(vx, vd_load_float(a + gzo), vd_mul(ux, vd_load_float(b + gzo)));
    return r;
}

/* Wu 2020 Alg. 4 per channel, nested as the reference: along x (lines 4-7), y
 * (lines 8-11), z (line 12); for rows shorter than 4 vectors (lmax 1-2 on avx2),
 * where it is faster than the weighted sum below (-17% per point at lmax 2).
 * Straight-line code per block, each y-row (corners 0-3, then 4-7) reduced as
 * soon as its two x-rows exist: with the q loop and arrays of the reference,
 * gcc -O2 kept g, g_y, g_z on the stack (a store and a reload per value). */
static void hermite_nested(const float *const f[8], const shl__interp_point *s, int nc, shl__interp_ahead *ahead, double *out)
{
    const vd x[4] = {vd_set1(s->hw[0][0]), vd_set1(s->hw[0][1]), vd_set1(s->hw[0][2]), vd_set1(s->hw[0][3])};
    const vd y0 = vd_set1(s->hw[1][0]), y1 = vd_set1(s->hw[1][1]), y2 = vd_set1(s->hw[1][2]), y3 = vd_set1(s->hw[1][3]);
    const vd z0 = vd_set1(s->hw[2][0]), z1 = vd_set1(s->hw[2][1]), z2 = vd_set1(s->hw[2][2]), z3 = vd_set1(s->hw[2][3]);
    const vd ux = vd_set1(s->u[0]), vx = vd_set1(1.0 - s->u[0]), uy = vd_set1(s->u[1]), vy = vd_set1(1.0 - s->u[1]);
    channels_plan(nc, ahead);
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < nc; k += VL) {
            size_t vo, gxo;
            channel_block(c, k, nc, ahead, &vo, &gxo);
            const size_t gyo = gxo + nc, gzo = gxo + 2 * (size_t)nc;
            /* lines 8-11: along y; line 12: along z */
            const along_x q0 = hermite_x(f[0], f[1], vo, gxo, gyo, gzo, x, ux, vx);
            const along_x q1 = hermite_x(f[2], f[3], vo, gxo, gyo, gzo, x, ux, vx);
            const vd h0 = vd_fma(y0, q0.g, vd_fma(y1, q0.g_y, vd_fma(y2, q1.g, vd_mul(y3, q1.g_y))));
            const vd h0_z = vd_fma(vy, q0.g_z, vd_mul(uy, q1.g_z));
            const along_x q2 = hermite_x(f[4], f[5], vo, gxo, gyo, gzo, x, ux, vx);
            const along_x q3 = hermite_x(f[6], f[7], vo, gxo, gyo, gzo, x, ux, vx);
            const vd h1 = vd_fma(y0, q2.g, vd_fma(y1, q2.g_y, vd_fma(y2, q3.g, vd_mul(y3, q3.g_y))));
            const vd h1_z = vd_fma(vy, q2.g_z, vd_mul(uy, q3.g_z));
            vd_store(out + vo, vd_fma(z0, h0, vd_fma(z1, h0_z, vd_fma(z2, h1, vd_mul(z3, h1_z)))));
        }
}


/* Wu 2020 Alg. 4 as one weighted sum of the 32 rows it reads: the nesting
 * along x (lines 4-7), y (lines 8-11) and z (line 12) multiplied out, each
 * row's weight computed once per point in double (shl__hermite_row_weights,
 * simd/kernel_api.h), so
 * that out = sum_j w_j v_j + wd_j . grad_j as in Taylor.  The reference's value up
 * to the rounding of the weights' products and the order of the sum (double,
 * a few ulps).  Row by row: each weight is broadcast once for 4 consecutive
 * blocks, corners 0-3 and 4-7 summed apart, then added: 8 independent FMA
 * chains (the nested form's chains and 16 broadcast weights spilled registers;
 * per point -8% at lmax 4 on the AMD EPYC guest). */

/* One row times weight w into nb (3 or 4, a constant where inlined) consecutive blocks. */
__attribute__((always_inline)) static inline void row_blocks(double w, const float *row, int nb, vd *a0, vd *a1,
                                                             vd *a2, vd *a3)
{
    const vd wv = vd_set1(w);
    *a0 = vd_fma(wv, vd_load_float(row), *a0);
    *a1 = vd_fma(wv, vd_load_float(row + VL), *a1);
    *a2 = vd_fma(wv, vd_load_float(row + 2 * VL), *a2);
    if (nb == 4) *a3 = vd_fma(wv, vd_load_float(row + 3 * VL), *a3);
}

/* Corner j's four rows of a channel: value at vo, gradients at gxo + a nc. */
__attribute__((always_inline)) static inline void corner_blocks(const float *f, double w, const double wd[3], int nc,
                                                                size_t vo, size_t gxo, int nb, vd *a0, vd *a1,
                                                                vd *a2, vd *a3)
{
    row_blocks(w, f + vo, nb, a0, a1, a2, a3);
    row_blocks(wd[0], f + gxo, nb, a0, a1, a2, a3);
    row_blocks(wd[1], f + gxo + nc, nb, a0, a1, a2, a3);
    row_blocks(wd[2], f + gxo + 2 * (size_t)nc, nb, a0, a1, a2, a3);
}

/* Channel c's nb (3 or 4) blocks from coefficient k: corners 0-3 into a0..a3, 4-7 into b0..b3.
 * Each lane's sum is the same whatever nb. */
__attribute__((always_inline)) static inline void hermite_blocks(const float *const f[8], const double w[8],
                                                                 double wd[8][3], int nc, int c, int k, int nb,
                                                                 double *out)
{
    const size_t vo = (size_t)c * nc + k, gxo = 3 * (size_t)nc + 3 * (size_t)c * nc + k;
    vd a0 = vd_set1(0.0), a1 = a0, a2 = a0, a3 = a0, b0 = a0, b1 = a0, b2 = a0, b3 = a0;
    for (int j = 0; j < 4; ++j) {
        corner_blocks(f[j], w[j], wd[j], nc, vo, gxo, nb, &a0, &a1, &a2, &a3);
        corner_blocks(f[j + 4], w[j + 4], wd[j + 4], nc, vo, gxo, nb, &b0, &b1, &b2, &b3);
    }
    vd_store(out + vo, vd_add(a0, b0));
    vd_store(out + vo + VL, vd_add(a1, b1));
    vd_store(out + vo + 2 * VL, vd_add(a2, b2));
    if (nb == 4) vd_store(out + vo + 3 * VL, vd_add(a3, b3));
}

static void hermite4(const float *const f[8], const double w[8], double wd[8][3], int nc, int c, int k, double *out)
{
    hermite_blocks(f, w, wd, nc, c, k, 4, out);
}

static void hermite3(const float *const f[8], const double w[8], double wd[8][3], int nc, int c, int k, double *out)
{
    hermite_blocks(f, w, wd, nc, c, k, 3, out);
}

/* Per channel: groups of 4 blocks from k = 0, 4 VL, ...; the rest (nc - 4 VL groups, if any) as
 * one more group ending at nc, of 3 blocks where they cover it (lmax 4 on avx2: 25 = 16 + 9,
 * 7 blocks per channel, not 8), else of 4, overlapping the previous one and rewriting the same
 * values. */
static void hermite(const float *const f[8], const shl__interp_point *s, int nc, shl__interp_ahead *ahead, double *out)
{
    const int width = 4 * VL;
    if (nc < width) {
        hermite_nested(f, s, nc, ahead, out);
        return;
    }
    double w[8], wd[8][3];
    shl__hermite_row_weights(s, w, wd);
    const int groups = nc / width, rest = nc - groups * width;
    shl__interp_ahead_plan(ahead, 3 * (size_t)(groups + (rest > 0)));
    for (int c = 0; c < 3; ++c) {
        for (int g = 0; g < groups; ++g) {
            shl__interp_ahead_step(ahead);
            hermite4(f, w, wd, nc, c, g * width, out);
        }
        if (rest > 0) shl__interp_ahead_step(ahead);
        if (rest > 0 && rest <= 3 * VL)
            hermite3(f, w, wd, nc, c, nc - 3 * VL, out);
        else if (rest > 0)
            hermite4(f, w, wd, nc, c, nc - width, out);
    }
}

void ISA(shl__interp_f)(const float *data, int method, int nc, const shl__interp_point *s, shl__interp_ahead *ahead,
                        double *out)
{
    if (nc < VL) { /* rows shorter than a vector: nothing to vectorize at this width */
#ifdef SHL_INTERP_SHORT_ROWS
        SHL_INTERP_SHORT_ROWS(data, method, nc, s, ahead, out);
#else
        shl__interp_ref_f(data, method, nc, s, ahead, out);
#endif
        return;
    }
    const float *f[8];
    for (int j = 0; j < 8; ++j) f[j] = data + s->ofs[j];
    if (method == SHL_INTERP_TRILINEAR)
        trilinear(f, s, nc, ahead, out);
    else if (method == SHL_INTERP_TAYLOR)
        taylor(f, s, nc, ahead, out);
    else
        hermite(f, s, nc, ahead, out);
    shl__interp_ahead_finish(ahead);
}
#endif

/* ---- Float sums' set-up (shl__interp_setup_ff, simd/kernel_api.h) ----
 * Per point the operations of src/interp.c's locate, hermite_weights or
 * trilinear_weights and shl__hermite_row_weights, so the same double weights;
 * here in fixed-count loops across SHL__INTERP_FF_BLOCK points (lanes past n
 * repeat point 0), which the compiler vectorizes at this ISA's width. */
void ISA(shl__interp_setup_ff)(const shl__interp_geom *g, int method, int n, const float *pts, shl__interp_point_ff *s)
{
    double u[3][SHL__INTERP_FF_BLOCK];
    size_t base[SHL__INTERP_FF_BLOCK] = {0};
    for (int a = 0; a < 3; ++a) { /* locate */
        const double lo = g->lo[a], hi = g->hi[a], h = g->h[a];
        const int last = g->res[a] - 2;
        const size_t stride = a == 0 ? g->node_len : a == 1 ? g->node_len * g->res[0]
                                                              : g->node_len * g->res[0] * (size_t)g->res[1];
        double x[SHL__INTERP_FF_BLOCK];
        for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) x[i] = pts[3 * (i < n ? i : 0) + a];
        for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) {
            const double c = x[i] < lo ? lo : x[i] > hi ? hi : x[i];
            const double t = (c - lo) / h;
            const int cell = t < last + 1 ? (int)t : last;
            u[a][i] = t - cell < 1.0 ? t - cell : 1.0;
            base[i] += (size_t)cell * stride;
        }
    }
    size_t corner[8]; /* corner j's offset from corner 0 */
    for (int j = 0; j < 8; ++j)
        corner[j] = ((size_t)(j & 1) + (size_t)g->res[0] * ((size_t)((j >> 1) & 1) + (size_t)g->res[1] * (size_t)(j >> 2)))
                    * g->node_len;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 8; ++j) s[i].ofs[j] = base[i] + corner[j];
    if (method == SHL_INTERP_TRILINEAR) {
        double vu[3][2][SHL__INTERP_FF_BLOCK]; /* 1 - u, u */
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) {
                vu[a][0][i] = 1.0 - u[a][i];
                vu[a][1][i] = u[a][i];
            }
        for (int j = 0; j < 8; ++j) {
            const double *x = vu[0][j & 1], *y = vu[1][(j >> 1) & 1], *z = vu[2][j >> 2];
            float w[SHL__INTERP_FF_BLOCK];
            for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) w[i] = (float)(x[i] * y[i] * z[i]);
            for (int i = 0; i < n; ++i) s[i].w[j] = w[i];
        }
        return;
    }
    double hw[3][4][SHL__INTERP_FF_BLOCK]; /* hermite_weights */
    for (int a = 0; a < 3; ++a)
        for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) {
            const double ua = u[a][i], v = 1.0 - ua;
            hw[a][0][i] = (1.0 + 2.0 * ua) * v * v;
            hw[a][1][i] = ua * v * v * g->h[a];
            hw[a][2][i] = ua * ua * (3.0 - 2.0 * ua);
            hw[a][3][i] = -ua * ua * v * g->h[a];
        }
    float w[8][SHL__INTERP_FF_BLOCK], wd[8][3][SHL__INTERP_FF_BLOCK]; /* shl__hermite_row_weights, rounded */
    double vy[SHL__INTERP_FF_BLOCK];
    for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) vy[i] = 1.0 - u[1][i];
    for (int q = 0; q < 4; ++q) { /* G[q] = z[q & 2] y[2 (q & 1)], Gy[q] = z[q & 2] y[2 (q & 1) + 1], Gz[q] = z[(q & 2) + 1] (vy or uy) */
        const double *z = hw[2][q & 2], *zd = hw[2][(q & 2) + 1], *y = hw[1][2 * (q & 1)], *yd = hw[1][2 * (q & 1) + 1];
        const double *yz = q & 1 ? u[1] : vy;
        for (int i = 0; i < SHL__INTERP_FF_BLOCK; ++i) {
            const double ux = u[0][i], vx = 1.0 - ux, G = z[i] * y[i], Gy = z[i] * yd[i];
            const double Gz = zd[i] * yz[i];
            w[2 * q][i] = (float)(G * hw[0][0][i]);
            wd[2 * q][0][i] = (float)(G * hw[0][1][i]);
            wd[2 * q][1][i] = (float)(Gy * vx);
            wd[2 * q][2][i] = (float)(Gz * vx);
            w[2 * q + 1][i] = (float)(G * hw[0][2][i]);
            wd[2 * q + 1][0][i] = (float)(G * hw[0][3][i]);
            wd[2 * q + 1][1][i] = (float)(Gy * ux);
            wd[2 * q + 1][2][i] = (float)(Gz * ux);
        }
    }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 8; ++j) {
            s[i].w[j] = w[j][i];
            for (int a = 0; a < 3; ++a) s[i].wd[j][a] = wd[j][a][i];
        }
}

/* ---- Float sums (shl_grid_interp_f) ----
 * The same across-coefficient layout with float lanes (SHL_VLEN per vector) and
 * the point's weights already rounded to float (shl__interp_point_ff): plain
 * float loads, float FMAs, in the order of the reference shl__interp_ff_ref
 * (src/interp.c) -- trilinear, corners 0..7 in one chain; Taylor and Hermite
 * (both sum_j w_j v_j + wd_j . grad_j), per channel, corners 0-3 and 4-7 in
 * two chains, then added -- so every term sees at most the roundings README
 * "Grid interpolation" counts.  The scalar helper (one lane) forwards to the
 * reference; so do rows shorter than a vector (lmax 0-1 on avx2), unless the
 * helper names a narrower kernel, SHL_INTERP_FF_SHORT_ROWS. */
#if SHL_VLEN == 1
void ISA(shl__interp_ff)(const float *data, int method, int nc, const shl__interp_point_ff *s,
                         const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2)
{
    shl__interp_ff_ref(data, method, nc, s, s2, ahead, out, out2);
}
#else
#define VFL SHL_VLEN
#ifdef SHL_INTERP_FF_SHORT_ROWS
void SHL_INTERP_FF_SHORT_ROWS(const float *data, int method, int nc, const shl__interp_point_ff *s,
                              const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2);
#endif

/* Start of the float block after k in a row of n >= VFL: the last one ends at n. */
static inline int fblock_start(int k, int n) { return k + VFL <= n ? k : n - VFL; }

static void ff_trilinear(const float *const f[8], const shl__interp_point_ff *s, int nc, shl__interp_ahead *ahead,
                         float *out)
{
    const int n = 3 * nc;
    vf w[8];
    for (int j = 0; j < 8; ++j) w[j] = vf_set1(s->w[j]);
    shl__interp_ahead_plan(ahead, (size_t)(n + VFL - 1) / VFL);
    for (int k = 0; k < n; k += VFL) {
        const int i = fblock_start(k, n);
        shl__interp_ahead_step(ahead);
        vf v = vf_mul(w[0], vf_load(f[0] + i));
        for (int j = 1; j < 8; ++j) v = vf_fma(w[j], vf_load(f[j] + i), v);
        vf_store(out + i, v);
    }
}

/* One row times weight w into the nb (1-4, a constant where inlined) blocks at row + k[b]. */
__attribute__((always_inline)) static inline void ff_row(float w, const float *row, const int k[4], int nb, vf *a0,
                                                         vf *a1, vf *a2, vf *a3)
{
    const vf wv = vf_set1(w);
    *a0 = vf_fma(wv, vf_load(row + k[0]), *a0);
    if (nb > 1) *a1 = vf_fma(wv, vf_load(row + k[1]), *a1);
    if (nb > 2) *a2 = vf_fma(wv, vf_load(row + k[2]), *a2);
    if (nb > 3) *a3 = vf_fma(wv, vf_load(row + k[3]), *a3);
}

/* Corner f's four rows of a channel (value at vo, gradients at gxo + a nc) with weights w, wd. */
__attribute__((always_inline)) static inline void ff_corner(const float *f, float w, const float wd[3], int nc,
                                                            size_t vo, size_t gxo, const int k[4], int nb, vf *a0,
                                                            vf *a1, vf *a2, vf *a3)
{
    ff_row(w, f + vo, k, nb, a0, a1, a2, a3);
    ff_row(wd[0], f + gxo, k, nb, a0, a1, a2, a3);
    ff_row(wd[1], f + gxo + nc, k, nb, a0, a1, a2, a3);
    ff_row(wd[2], f + gxo + 2 * (size_t)nc, k, nb, a0, a1, a2, a3);
}

/* Channel c's nb blocks starting at block b: each weight broadcast once for nb
 * blocks, 2 nb independent FMA chains.  Each lane's sum is the same whatever nb
 * and wherever its block starts (an overlapping last block rewrites equal values). */
__attribute__((always_inline)) static inline void ff_blocks(const float *const f[8], const shl__interp_point_ff *s,
                                                            int nc, int c, int b, int nb, float *out)
{
    const size_t vo = (size_t)c * nc, gxo = 3 * (size_t)nc + 3 * (size_t)c * nc;
    int k[4] = {0, 0, 0, 0};
    for (int i = 0; i < nb; ++i) k[i] = fblock_start((b + i) * VFL, nc);
    const vf zero = vf_set1(0.0f);
    vf a0 = zero, a1 = zero, a2 = zero, a3 = zero, b0 = zero, b1 = zero, b2 = zero, b3 = zero;
    for (int j = 0; j < 4; ++j) {
        ff_corner(f[j], s->w[j], s->wd[j], nc, vo, gxo, k, nb, &a0, &a1, &a2, &a3);
        ff_corner(f[j + 4], s->w[j + 4], s->wd[j + 4], nc, vo, gxo, k, nb, &b0, &b1, &b2, &b3);
    }
    vf_store(out + vo + k[0], vf_add(a0, b0));
    if (nb > 1) vf_store(out + vo + k[1], vf_add(a1, b1));
    if (nb > 2) vf_store(out + vo + k[2], vf_add(a2, b2));
    if (nb > 3) vf_store(out + vo + k[3], vf_add(a3, b3));
}

static void ff_blocks1(const float *const f[8], const shl__interp_point_ff *s, int nc, int c, int b, float *out)
{
    ff_blocks(f, s, nc, c, b, 1, out);
}

static void ff_blocks2(const float *const f[8], const shl__interp_point_ff *s, int nc, int c, int b, float *out)
{
    ff_blocks(f, s, nc, c, b, 2, out);
}

static void ff_blocks3(const float *const f[8], const shl__interp_point_ff *s, int nc, int c, int b, float *out)
{
    ff_blocks(f, s, nc, c, b, 3, out);
}

static void ff_blocks4(const float *const f[8], const shl__interp_point_ff *s, int nc, int c, int b, float *out)
{
    ff_blocks(f, s, nc, c, b, 4, out);
}

/* A loaded block kept in a register for both points' FMAs: on avx2, gcc and clang
 * otherwise fold the load into each FMA (two loads of the block; the pairs then saved
 * 9% of the Dragon & Bunny frame's interpolation CPU time, not 25%).  An empty asm
 * statement: no instruction. */
#if (defined(__GNUC__) || defined(__clang__)) && defined(__AVX2__) && SHL_VLEN == 8
#define FF_IN_REGISTER(x) __asm__("" : "+x"(x))
#else
#define FF_IN_REGISTER(x) ((void)(x))
#endif

/* One row into the nb blocks of two points of one cell (weights ws, wt; accumulators a0..a3,
 * b0..b3): each block loaded once.  Scalars, not arrays: gcc -O2 kept arrays of vectors on the stack. */
__attribute__((always_inline)) static inline void ff_row2(float ws, float wt, const float *row, const int k[4], int nb,
                                                          vf *a0, vf *a1, vf *a2, vf *a3, vf *b0, vf *b1, vf *b2,
                                                          vf *b3)
{
    const vf vs = vf_set1(ws), vt = vf_set1(wt);
    vf x = vf_load(row + k[0]);
    FF_IN_REGISTER(x);
    *a0 = vf_fma(vs, x, *a0);
    *b0 = vf_fma(vt, x, *b0);
    if (nb > 1) {
        x = vf_load(row + k[1]);
        FF_IN_REGISTER(x);
        *a1 = vf_fma(vs, x, *a1);
        *b1 = vf_fma(vt, x, *b1);
    }
    if (nb > 2) {
        x = vf_load(row + k[2]);
        FF_IN_REGISTER(x);
        *a2 = vf_fma(vs, x, *a2);
        *b2 = vf_fma(vt, x, *b2);
    }
    if (nb > 3) {
        x = vf_load(row + k[3]);
        FF_IN_REGISTER(x);
        *a3 = vf_fma(vs, x, *a3);
        *b3 = vf_fma(vt, x, *b3);
    }
}

/* Corners 4h .. 4h + 3 of channel c's nb blocks for points s (sums into a0..a3) and t (b0..b3),
 * stored to ps[0..nb-1] and pt[0..nb-1]: the chains of ff_blocks for that half, in the same order. */
__attribute__((always_inline)) static inline void ff_half2(const float *const f[8], const shl__interp_point_ff *s,
                                                           const shl__interp_point_ff *t, int nc, size_t vo,
                                                           size_t gxo, const int k[4], int nb, int h, vf ps[4],
                                                           vf pt[4])
{
    const vf zero = vf_set1(0.0f);
    vf a0 = zero, a1 = zero, a2 = zero, a3 = zero, b0 = zero, b1 = zero, b2 = zero, b3 = zero;
    for (int j = 4 * h; j < 4 * h + 4; ++j) {
        ff_row2(s->w[j], t->w[j], f[j] + vo, k, nb, &a0, &a1, &a2, &a3, &b0, &b1, &b2, &b3);
        ff_row2(s->wd[j][0], t->wd[j][0], f[j] + gxo, k, nb, &a0, &a1, &a2, &a3, &b0, &b1, &b2, &b3);
        ff_row2(s->wd[j][1], t->wd[j][1], f[j] + gxo + nc, k, nb, &a0, &a1, &a2, &a3, &b0, &b1, &b2, &b3);
        ff_row2(s->wd[j][2], t->wd[j][2], f[j] + gxo + 2 * (size_t)nc, k, nb, &a0, &a1, &a2, &a3, &b0, &b1, &b2,
                &b3);
    }
    ps[0] = a0, ps[1] = a1, ps[2] = a2, ps[3] = a3;
    pt[0] = b0, pt[1] = b1, pt[2] = b2, pt[3] = b3;
}

/* ff_blocks for two points of one cell: the halves one after the other (8 chains each; both
 * halves at once would need 16 accumulators), then added as there. */
__attribute__((always_inline)) static inline void ff_blocks_pair(const float *const f[8], const shl__interp_point_ff *s,
                                                                 const shl__interp_point_ff *t, int nc, int c, int b,
                                                                 int nb, float *out, float *out2)
{
    const size_t vo = (size_t)c * nc, gxo = 3 * (size_t)nc + 3 * (size_t)c * nc;
    int k[4] = {0, 0, 0, 0};
    for (int i = 0; i < nb; ++i) k[i] = fblock_start((b + i) * VFL, nc);
    vf as[4], at[4], bs[4], bt[4];
    ff_half2(f, s, t, nc, vo, gxo, k, nb, 0, as, at);
    ff_half2(f, s, t, nc, vo, gxo, k, nb, 1, bs, bt);
    for (int i = 0; i < nb; ++i) {
        vf_store(out + vo + k[i], vf_add(as[i], bs[i]));
        vf_store(out2 + vo + k[i], vf_add(at[i], bt[i]));
    }
}

static void ff_pair1(const float *const f[8], const shl__interp_point_ff *s, const shl__interp_point_ff *t, int nc,
                     int c, int b, float *out, float *out2)
{
    ff_blocks_pair(f, s, t, nc, c, b, 1, out, out2);
}

static void ff_pair2(const float *const f[8], const shl__interp_point_ff *s, const shl__interp_point_ff *t, int nc,
                     int c, int b, float *out, float *out2)
{
    ff_blocks_pair(f, s, t, nc, c, b, 2, out, out2);
}

static void ff_pair3(const float *const f[8], const shl__interp_point_ff *s, const shl__interp_point_ff *t, int nc,
                     int c, int b, float *out, float *out2)
{
    ff_blocks_pair(f, s, t, nc, c, b, 3, out, out2);
}

static void ff_pair4(const float *const f[8], const shl__interp_point_ff *s, const shl__interp_point_ff *t, int nc,
                     int c, int b, float *out, float *out2)
{
    ff_blocks_pair(f, s, t, nc, c, b, 4, out, out2);
}

/* Taylor and Hermite: per channel, its ceil(nc / VFL) blocks in groups of 4
 * (lmax 4 on avx2: 25 = 8 + 8 + 8 + 1, blocks at 0, 8, 16, 17, one group; lmax 8:
 * 11 blocks, groups of 4, 4, 3), for s alone or for s and s2 together. */
static void ff_gradient_form(const float *const f[8], const shl__interp_point_ff *s, const shl__interp_point_ff *s2,
                             int nc, shl__interp_ahead *ahead, float *out, float *out2)
{
    const int nblk = (nc + VFL - 1) / VFL;
    /* with requests to make (out of cache), groups of ceil(nblk / 3) blocks at most: about 3
     * request steps per channel.  AMD EPYC Zen 4 guest, lmax 8 Hermite, 1.25 GB grid, random
     * points, avx512 (6 blocks a channel): groups of 4 and 2 blocks 2022 -> 1754 ns per vertex,
     * of 1 block 1877 ns */
    const int most = ahead->nrange && (nblk + 2) / 3 < 4 ? (nblk + 2) / 3 : 4;
    shl__interp_ahead_plan(ahead, 3 * (size_t)((nblk + most - 1) / most));
    for (int c = 0; c < 3; ++c)
        for (int b = 0; b < nblk; b += most) {
            shl__interp_ahead_step(ahead);
            const int nb = nblk - b < most ? nblk - b : most;
            if (s2 && nb == 4)
                ff_pair4(f, s, s2, nc, c, b, out, out2);
            else if (s2 && nb == 3)
                ff_pair3(f, s, s2, nc, c, b, out, out2);
            else if (s2 && nb == 2)
                ff_pair2(f, s, s2, nc, c, b, out, out2);
            else if (s2)
                ff_pair1(f, s, s2, nc, c, b, out, out2);
            else if (nb == 4)
                ff_blocks4(f, s, nc, c, b, out);
            else if (nb == 3)
                ff_blocks3(f, s, nc, c, b, out);
            else if (nb == 2)
                ff_blocks2(f, s, nc, c, b, out);
            else
                ff_blocks1(f, s, nc, c, b, out);
        }
}

void ISA(shl__interp_ff)(const float *data, int method, int nc, const shl__interp_point_ff *s,
                         const shl__interp_point_ff *s2, shl__interp_ahead *ahead, float *out, float *out2)
{
    if (nc < VFL) {
#ifdef SHL_INTERP_FF_SHORT_ROWS
        SHL_INTERP_FF_SHORT_ROWS(data, method, nc, s, s2, ahead, out, out2);
#else
        shl__interp_ff_ref(data, method, nc, s, s2, ahead, out, out2);
#endif
        return;
    }
    const float *f[8];
    for (int j = 0; j < 8; ++j) f[j] = data + s->ofs[j];
    if (method == SHL_INTERP_TRILINEAR) {
        ff_trilinear(f, s, nc, ahead, out);
        if (s2) { /* the look-ahead is done */
            shl__interp_ahead none = {.nrange = 0};
            ff_trilinear(f, s2, nc, &none, out2);
        }
    } else
        ff_gradient_form(f, s, s2, nc, ahead, out, out2);
    shl__interp_ahead_finish(ahead);
}
#endif
