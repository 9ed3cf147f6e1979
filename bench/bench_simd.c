/* Batched SIMD kernel benchmark (shl_polygon_batch_f, shl_sphere_batch_f), one core, triangle light:
 *  - speed vs the scalar double single-point loop (shl_polygon, shl_polygon_grad), lmax 2..14,
 *  - the same kernel compiled scalar (SHLIGHT_ISA=scalar) and the scalar float path, for scale,
 *  - fraction of peak: this core's FMA throughput measured in the same run
 *    (independent FMA chains in registers) against the kernel's counted flops,
 *  - spherical light: shl_sphere_batch_f vs shl_sphere / shl_sphere_grad (and the same kernel
 *    compiled scalar, and shl_sphere_f), lmax 2..14,
 *  - light set (8 triangles, 2 spheres): shl_lights_eval_batch_f vs shl_lights_eval (and the
 *    same kernels compiled scalar, and shl_lights_eval_batch_f one point per call), lmax 2..14,
 *  - ISA comparison at lmax 8: every ISA of simd/isa_list.h this CPU runs (shl_ctx_create_isa)
 *    on the polygon, sphere, light-set and interpolation batches, time ratios to avx2 (or the
 *    first vector ISA) within each round, the polygon batch as a share of the peak of its own
 *    vector width (the 512-bit FMA peak for avx512, measured in the same rounds).
 * All ratios come from one run.  CSV: build/bench/bench_simd.csv (-o overrides); --help. */
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

/* 256 points per batch call: the outputs of a call (up to 0.7 MB: lmax 14 with
 * gradients) stay in this core's L2, as the single-point loops' do. */
enum { NPTS = 256, NV = 3 };

typedef struct {
    const shl_ctx *ctx;
    float vf[3 * NV], pf[3 * NPTS], *out, *grad;
    double vd[3 * NV], pd[3 * NPTS], *outd, *gradd;
    const shl_lights *set; /* light-set variants */
    const shl_grid *grid;  /* interpolation: method, IP_CHUNK points ip_pts, outputs ip_out */
    int method;
    const double *ip_pts;
    double *ip_out;
    long inner; /* evaluations per timed call */
} job;

static void run_batch(void *p)
{
    job *j = p;
    for (long done = 0; done < j->inner; done += NPTS)
        shl_polygon_batch_f(j->ctx, j->vf, NV, NPTS, j->pf, j->out, j->grad);
    bench_sink += j->out[1];
}

static void run_scalar_double(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const double *x = j->pd + 3 * (i % NPTS);
        if (j->gradd) shl_polygon_grad(j->ctx, x, j->vd, NV, j->outd, j->gradd);
        else shl_polygon(j->ctx, x, j->vd, NV, j->outd);
    }
    bench_sink += j->outd[1];
}

static void run_scalar_float(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const float *x = j->pf + 3 * (i % NPTS);
        if (j->grad) shl_polygon_grad_f(j->ctx, x, j->vf, NV, j->out, j->grad);
        else shl_polygon_f(j->ctx, x, j->vf, NV, j->out);
    }
    bench_sink += j->out[1];
}

/* Spherical light (radius 0.5, centre (0, 0, 3)) at the same points. */
static const float sphere_cf[3] = {0.0f, 0.0f, 3.0f};
static const double sphere_cd[3] = {0.0, 0.0, 3.0};

static void run_sphere_batch(void *p)
{
    job *j = p;
    for (long done = 0; done < j->inner; done += NPTS)
        shl_sphere_batch_f(j->ctx, sphere_cf, 0.5f, NPTS, j->pf, j->out, j->grad);
    bench_sink += j->out[1];
}

static void run_sphere_double(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const double *x = j->pd + 3 * (i % NPTS);
        if (j->gradd) shl_sphere_grad(j->ctx, x, sphere_cd, 0.5, j->outd, j->gradd);
        else shl_sphere(j->ctx, x, sphere_cd, 0.5, j->outd);
    }
    bench_sink += j->outd[1];
}

static void run_sphere_float(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) {
        const float *x = j->pf + 3 * (i % NPTS);
        if (j->grad) shl_sphere_grad_f(j->ctx, x, sphere_cf, 0.5f, j->out, j->grad);
        else shl_sphere_f(j->ctx, x, sphere_cf, 0.5f, j->out);
    }
    bench_sink += j->out[1];
}

/* Light set: shl_lights_eval_batch_f on NPTS points per call, the double
 * single-point shl_lights_eval, and the float batch with one point per call. */
static void run_lights_batch(void *p)
{
    job *j = p;
    for (long done = 0; done < j->inner; done += NPTS)
        shl_lights_eval_batch_f(j->ctx, j->set, NPTS, j->pf, j->out, j->grad);
    bench_sink += j->out[1];
}

static void run_lights_double(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) shl_lights_eval(j->ctx, j->set, j->pd + 3 * (i % NPTS), j->outd, j->gradd);
    bench_sink += j->outd[1];
}

static void run_lights_one_point(void *p)
{
    job *j = p;
    for (long i = 0; i < j->inner; ++i) shl_lights_eval_batch_f(j->ctx, j->set, 1, j->pf + 3 * (i % NPTS), j->out, j->grad);
    bench_sink += j->out[1];
}

/* Grid interpolation (shl_grid_interp, one thread) of IP_CHUNK points per call. */
enum { IP_CHUNK = 128 };
static void run_interp(void *p)
{
    job *j = p;
    for (long done = 0; done < j->inner; done += IP_CHUNK)
        shl_grid_interp(j->grid, j->method, 2.0, IP_CHUNK, j->ip_pts, j->ip_out, 1);
    bench_sink += j->ip_out[1];
}

/* 8 triangles (the bench triangle rotated about z by k pi/4 and lifted by k/8;
 * even k one-sided, facing the points, odd k two-sided) and 2 spheres. */
enum { SET_POLYS = 8, SET_SPHERES = 2 };
static shl_lights *make_light_set(const double *tri)
{
    shl_lights *set;
    shl_lights_create(&set);
    for (int k = 0; k < SET_POLYS; ++k) {
        const double a = M_PI * k / 4, c = cos(a), s = sin(a), rgb[3] = {1.0, 0.5 + 0.1 * k, 0.25};
        double v[3 * NV];
        for (int i = 0; i < NV; ++i) {
            const int src = k % 2 ? i : NV - 1 - i; /* reversed: the front faces -z, toward the points */
            v[3 * i] = c * tri[3 * src] - s * tri[3 * src + 1];
            v[3 * i + 1] = s * tri[3 * src] + c * tri[3 * src + 1];
            v[3 * i + 2] = tri[3 * src + 2] + k / 8.0;
        }
        shl_lights_add_polygon(set, v, NV, rgb, k % 2);
    }
    const double c0[3] = {2.5, 0.0, 1.0}, c1[3] = {-2.0, 1.5, -1.0}, rgb[3] = {2.0, 2.0, 1.0};
    shl_lights_add_sphere(set, c0, 0.5, rgb);
    shl_lights_add_sphere(set, c1, 0.3, rgb);
    return set;
}

/* Calibrate j->inner (a multiple of granule) for calls of about 10 ms. */
static void calibrate(void (*fn)(void *), job *j, long granule)
{
    j->inner = granule;
    fn(j); /* warm-up */
    const double t0 = bench_now();
    fn(j);
    j->inner = granule * (long)fmax(1.0, 0.01 / fmax(bench_now() - t0, 1e-7));
}

/* Seconds per evaluation of one timed call. */
static double once(void (*fn)(void *), job *j)
{
    const double t0 = bench_now();
    fn(j);
    return (bench_now() - t0) / (double)j->inner;
}

/* As once, in this thread's CPU time (CLOCK_THREAD_CPUTIME_ID): time spent
 * descheduled on a loaded machine does not count (the ISA comparison). */
static double once_cpu(void (*fn)(void *), job *j)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
    fn(j);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
    return ((double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec)) / (double)j->inner;
}

/* Floating-point operations of one evaluation, counted from simd/poly_batch.h as
 * executed (add, sub, mul, div, sqrt: 1; FMA: 2; min, max, abs, sign, select: 0)
 * for a convex polygon of n vertices.  Geometry: 13 per vertex, 107 per edge
 * (+42 with gradients), 43 per fan triangle.  Per lobe pair (lobe 0 alone):
 * shared dot products 5 per vertex and 15 (+5) per edge; per lobe and edge 7 + 2
 * sums (+6) and per band step 20 + 1 sum (+9), a sum being a multiply on the
 * first edge and an FMA on the others; the S_l recurrence; with gradients the
 * sums over edges of mu_e I_l,e, 3 (2n - 1) per band used; the scaling and
 * pairing.  Reconstruction: 2((l+1)^2 + l^2) per band and quantity. */
static double kernel_flops(int lmax, int n, int grad)
{
    const int nq = grad ? 4 : 1, lend = grad ? lmax : lmax - 1, steps = lend >= 2 ? lend - 1 : 0;
    double f = 13.0 * n + (107.0 + (grad ? 42 : 0)) * n + 43.0 * (n - 2) + 2;
    for (int k = 0; k <= lmax; ++k) {
        const int nl = k ? 2 : 1;
        f += 5.0 * n + (15.0 + (grad ? 5 : 0)) * n;
        for (int e = 0; e < n; ++e) {
            const double sum = e == 0 ? 1.0 : 2.0;
            f += nl * (7 + 2 * sum + steps * (20 + sum) + (grad ? 6 + 9.0 * steps : 0));
        }
        if (grad) f += nl * 3.0 * (lmax - k + 1) * (2.0 * n - 1);
        f += nl * ((lmax >= 1 ? 1 : 0) + 3.0 * (lmax >= 2 ? lmax - 1 : 0));
        f += nq * (lmax - k + 1) * (k ? 5.0 : 2.0);
    }
    for (int l = 0; l <= lmax; ++l) f += nq * 2.0 * ((l + 1) * (l + 1) + l * l);
    return f;
}

/* ---- this core's peak: 10 independent FMA chains in registers (more than
 * latency x throughput = 4 x 2 on current cores), no memory traffic ---- */
#define FMA_CHAINS 10
#define CHAINS(op) op(a0) op(a1) op(a2) op(a3) op(a4) op(a5) op(a6) op(a7) op(a8) op(a9)
#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx2,fma"))) static void fma_peak(void *p)
{
    const job *j = p;
    const __m256 m = _mm256_set1_ps(0.9999999f), c = _mm256_set1_ps(1e-7f);
    const float s = (float)(j->inner & 7); /* not a compile-time constant */
#define INIT(a) __m256 a = _mm256_set1_ps(s + (float)(#a)[1]); /* distinct starts */
#define STEP(a) a = _mm256_fmadd_ps(a, m, c);
#define SUM(a) t = _mm256_add_ps(t, a);
    CHAINS(INIT)
    for (long i = 0; i < j->inner; ++i) {
        CHAINS(STEP)
    }
    __m256 t = _mm256_setzero_ps();
    CHAINS(SUM)
    float out[8];
    _mm256_storeu_ps(out, t);
    bench_sink += out[0];
}
#define PEAK_ISA "avx2"
#define PEAK_FLOPS_PER_ITER (FMA_CHAINS * 8 * 2)
/* The same with 512-bit vectors (AVX-512F): 16 float lanes.  Called only when
 * shl_ctx_create_isa accepts "avx512" (CPU and OS support checked there). */
__attribute__((target("avx512f"))) static void fma_peak512(void *p)
{
    const job *j = p;
    const __m512 m = _mm512_set1_ps(0.9999999f), c = _mm512_set1_ps(1e-7f);
    const float s = (float)(j->inner & 7);
#define INIT512(a) __m512 a = _mm512_set1_ps(s + (float)(#a)[1]);
#define STEP512(a) a = _mm512_fmadd_ps(a, m, c);
#define SUM512(a) t = _mm512_add_ps(t, a);
    CHAINS(INIT512)
    for (long i = 0; i < j->inner; ++i) {
        CHAINS(STEP512)
    }
    __m512 t = _mm512_setzero_ps();
    CHAINS(SUM512)
    float out[16];
    _mm512_storeu_ps(out, t);
    bench_sink += out[0];
}
#define PEAK512_FLOPS_PER_ITER (FMA_CHAINS * 16 * 2)
#elif defined(__aarch64__)
static void fma_peak(void *p)
{
    const job *j = p;
    const float32x4_t m = vdupq_n_f32(0.9999999f), c = vdupq_n_f32(1e-7f);
    const float s = (float)(j->inner & 7); /* not a compile-time constant */
#define INIT(a) float32x4_t a = vdupq_n_f32(s + (float)(#a)[1]); /* distinct starts */
#define STEP(a) a = vfmaq_f32(c, a, m);
#define SUM(a) t = vaddq_f32(t, a);
    CHAINS(INIT)
    for (long i = 0; i < j->inner; ++i) {
        CHAINS(STEP)
    }
    float32x4_t t = vdupq_n_f32(0.0f);
    CHAINS(SUM)
    bench_sink += vgetq_lane_f32(t, 0);
}
#define PEAK_ISA "neon"
#define PEAK_FLOPS_PER_ITER (FMA_CHAINS * 4 * 2)
#endif

/* The peak loop of an ISA's vector width and its flops per iteration: the
 * 512-bit loop for avx512, else the loop above (avx2 or neon; scalar ISAs are
 * measured against it too).  NULL where none is compiled. */
typedef struct {
    void (*fn)(void *);
    double flops_per_iter;
    const char *name;
} peak_loop;

static peak_loop peak_for(const char *isa)
{
#if defined(__x86_64__) || defined(__i386__)
    if (!strcmp(isa, "avx512")) return (peak_loop){fma_peak512, PEAK512_FLOPS_PER_ITER, "avx512"};
#endif
    (void)isa;
#ifdef PEAK_ISA
    return (peak_loop){fma_peak, PEAK_FLOPS_PER_ITER, PEAK_ISA};
#else
    return (peak_loop){NULL, 0.0, "none"};
#endif
}

static peak_loop peak_loop_default; /* that of the default ISA, for the per-lmax tables */

/* The four variants of one light kind: batch kernel (context's ISA, and the
 * same kernel with SHLIGHT_ISA=scalar), scalar double and float single-point loops. */
typedef struct {
    void (*batch)(void *), (*scalar_double)(void *), (*scalar_float)(void *);
} variants;

typedef struct {
    double batch, scalar_double, batch_scalar_isa, scalar_float; /* seconds per evaluation */
    double speedup, gflops, peak_gflops, peak_fraction;          /* medians of within-round ratios */
} timing;

/* ROUNDS rounds at lmax, each timing every variant once (and the FMA peak loop
 * when peak != NULL), so that the ratios compare calls made under the same load.
 * flops: per evaluation of the batch kernel (0: no rate reported). */
static timing time_variants(const variants *v, const job *base, int lmax, int with_grad, float *grad, double *gradd,
                            double flops, job *peak)
{
    enum { ROUNDS = 15 };
    shl_ctx *ctx, *ctx_scalar;
    shl_ctx_create(lmax, &ctx);
    setenv("SHLIGHT_ISA", "scalar", 1);
    shl_ctx_create(lmax, &ctx_scalar);
    unsetenv("SHLIGHT_ISA");
    job jb = *base, jd = *base, js = *base, jf = *base;
    jb.ctx = jd.ctx = jf.ctx = ctx;
    js.ctx = ctx_scalar;
    jb.grad = js.grad = jf.grad = with_grad ? grad : NULL;
    jd.gradd = with_grad ? gradd : NULL;
    calibrate(v->batch, &jb, NPTS);
    calibrate(v->batch, &js, NPTS);
    calibrate(v->scalar_double, &jd, 64);
    calibrate(v->scalar_float, &jf, 64);
    double tb[ROUNDS], td[ROUNDS], ts[ROUNDS], tf[ROUNDS], speed[ROUNDS], rate[ROUNDS], pk[ROUNDS], frac[ROUNDS];
    for (int r = 0; r < ROUNDS; ++r) {
        tb[r] = once(v->batch, &jb);
        td[r] = once(v->scalar_double, &jd);
        ts[r] = once(v->batch, &js);
        tf[r] = once(v->scalar_float, &jf);
        speed[r] = td[r] / tb[r];
        rate[r] = flops / tb[r];
        pk[r] = 0.0;
        if (peak && peak_loop_default.fn) pk[r] = peak_loop_default.flops_per_iter / once(peak_loop_default.fn, peak);
        frac[r] = pk[r] > 0 ? rate[r] / pk[r] : 0.0;
    }
    shl_ctx_destroy(ctx);
    shl_ctx_destroy(ctx_scalar);
    const timing t = {bench_median(tb, ROUNDS), bench_median(td, ROUNDS),   bench_median(ts, ROUNDS),
                      bench_median(tf, ROUNDS), bench_median(speed, ROUNDS), 1e-9 * bench_median(rate, ROUNDS),
                      1e-9 * bench_median(pk, ROUNDS), bench_median(frac, ROUNDS)};
    return t;
}

/* ---- ISA comparison at lmax 8: every ISA of simd/isa_list.h this CPU runs ---- */
static const char *const isa_names[] = {
#define SHL_ISA(name, flags, cpu) #name,
#include "../simd/isa_list.h"
#undef SHL_ISA
};
enum { NISA_LIST = sizeof isa_names / sizeof isa_names[0], CMP_LMAX = 8 };

typedef struct {
    const char *name;
    void (*fn)(void *);
    int with_grad, method, polygon; /* polygon: flops counted (kernel_flops) */
    long granule;
    int lmax1; /* interpolation from the lmax 1 grid (rows of 4 coefficients) */
} cmp_kernel;

/* Each kernel on each ISA, ROUNDS rounds timing every ISA once (calls of ~10 ms):
 * time per point, the speed against the reference ISA (avx2, else the first
 * vector ISA) as the median of within-round ratios, and for the polygon batch
 * the share of the FMA peak of the ISA's own width measured in the same round. */
static void isa_comparison(FILE *csv, const job *base, const shl_lights *set, const char *default_isa)
{
    enum { ROUNDS = 15 };
    static double ip_pts[3 * IP_CHUNK], ip_out[3 * IP_CHUNK * SHL_NCOEFFS(CMP_LMAX)];
    const double lo[3] = {-1.0, -1.0, -1.0}, hi[3] = {1.0, 1.0, 1.0};
    const int res[3] = {4, 4, 4}; /* 64 nodes x 3888 bytes: L2-resident, as the outputs */
    shl_ctx *ctx[NISA_LIST], *ctx1[NISA_LIST];
    shl_grid *grid[NISA_LIST], *grid1[NISA_LIST];
    const char *names[NISA_LIST];
    int n = 0, ref = -1;
    for (int i = 0; i < NISA_LIST; ++i) {
        shl_ctx *c, *c1;
        if (shl_ctx_create_isa(CMP_LMAX, isa_names[i], &c) != SHL_OK) continue; /* not run by this CPU */
        shl_grid *g, *g1;
        if (shl_ctx_create_isa(1, isa_names[i], &c1) != SHL_OK || shl_grid_create(c, lo, hi, res, SHL_GRID_FLOAT, &g) != SHL_OK ||
            shl_grid_fill(g, set, 1) != SHL_OK || shl_grid_create(c1, lo, hi, res, SHL_GRID_FLOAT, &g1) != SHL_OK ||
            shl_grid_fill(g1, set, 1) != SHL_OK) {
            fprintf(stderr, "bench_simd: grid set-up failed\n");
            exit(1);
        }
        if (!strcmp(isa_names[i], "avx2") || (ref < 0 && strcmp(isa_names[i], "scalar"))) ref = n;
        names[n] = isa_names[i];
        ctx[n] = c;
        ctx1[n] = c1;
        grid1[n] = g1;
        grid[n++] = g;
    }
    if (ref < 0) ref = 0;
    for (int k = 0; k < 3 * IP_CHUNK; ++k) ip_pts[k] = base->pd[k];
    const cmp_kernel kernels[] = {
        {"polygon batch", run_batch, 0, 0, 1, NPTS, 0},
        {"polygon batch + grad", run_batch, 1, 0, 1, NPTS, 0},
        {"sphere batch", run_sphere_batch, 0, 0, 0, NPTS, 0},
        {"sphere batch + grad", run_sphere_batch, 1, 0, 0, NPTS, 0},
        {"light set batch", run_lights_batch, 0, 0, 0, NPTS, 0},
        {"light set batch + grad", run_lights_batch, 1, 0, 0, NPTS, 0},
        {"interp trilinear", run_interp, 0, SHL_INTERP_TRILINEAR, 0, IP_CHUNK, 0},
        {"interp Taylor", run_interp, 0, SHL_INTERP_TAYLOR, 0, IP_CHUNK, 0},
        {"interp Hermite", run_interp, 0, SHL_INTERP_HERMITE, 0, IP_CHUNK, 0},
        {"interp Hermite lmax 1", run_interp, 0, SHL_INTERP_HERMITE, 0, IP_CHUNK, 1},
    };
    const int nk = (int)(sizeof kernels / sizeof kernels[0]);
    printf("\n## ISA comparison, lmax %d, one core (default ISA: %s; speed = time of %s / time of the ISA)\n\n",
           CMP_LMAX, default_isa, names[ref]);
    printf("Interpolation: shl_grid_interp of %d points per call from a %dx%dx%d float grid (L2-resident), one thread;\n"
           "also at lmax 1, whose rows of 4 coefficients are shorter than 8 double lanes (avx512: the avx2 kernel).\n\n",
           IP_CHUNK, res[0], res[1], res[2]);
    printf("| kernel | ISA | ns per point | speed vs %s | GFLOP/s | own-width peak GFLOP/s | of peak |\n", names[ref]);
    printf("|---|---|---|---|---|---|---|\n");
    if (csv) fprintf(csv, "isa_cmp_kernel,lmax,isa,ns_batch,ref_isa,speed_vs_ref,flops,gflops,peak_gflops,peak_fraction,,\n");
    for (int q = 0; q < nk; ++q) {
        const cmp_kernel *K = &kernels[q];
        bench_progress("ISA comparison: %s (%d/%d)...", K->name, q + 1, nk);
        const double flops = K->polygon ? kernel_flops(CMP_LMAX, NV, K->with_grad) : 0.0;
        job jb[NISA_LIST], jp = *base;
        jp.inner = 1L << 16;
        for (int i = 0; i < n; ++i) {
            jb[i] = *base;
            jb[i].ctx = ctx[i];
            jb[i].grad = K->with_grad ? base->grad : NULL;
            jb[i].grid = K->lmax1 ? grid1[i] : grid[i];
            jb[i].method = K->method;
            jb[i].ip_pts = ip_pts;
            jb[i].ip_out = ip_out;
            calibrate(K->fn, &jb[i], K->granule);
        }
        double t[NISA_LIST][ROUNDS], speed[NISA_LIST][ROUNDS], rate[NISA_LIST][ROUNDS], pk[NISA_LIST][ROUNDS],
            frac[NISA_LIST][ROUNDS];
        for (int r = 0; r < ROUNDS; ++r) {
            for (int i = 0; i < n; ++i) {
                t[i][r] = once_cpu(K->fn, &jb[i]);
                const peak_loop pl = peak_for(names[i]);
                pk[i][r] = K->polygon && pl.fn ? pl.flops_per_iter / once_cpu(pl.fn, &jp) : 0.0;
            }
            for (int i = 0; i < n; ++i) {
                speed[i][r] = t[ref][r] / t[i][r];
                rate[i][r] = flops / t[i][r];
                frac[i][r] = pk[i][r] > 0.0 ? rate[i][r] / pk[i][r] : 0.0;
            }
        }
        for (int i = 0; i < n; ++i) {
            const double ns = 1e9 * bench_median(t[i], ROUNDS), sp = bench_median(speed[i], ROUNDS);
            const double gf = 1e-9 * bench_median(rate[i], ROUNDS), pg = 1e-9 * bench_median(pk[i], ROUNDS);
            const double fr = bench_median(frac[i], ROUNDS);
            if (K->polygon)
                printf("| %s | %s | %.1f | **%.2fx** | %.1f | %.1f | **%.0f%%** |\n", K->name, names[i], ns, sp, gf, pg,
                       100.0 * fr);
            else
                printf("| %s | %s | %.1f | **%.2fx** | | | |\n", K->name, names[i], ns, sp);
            if (csv)
                fprintf(csv, "%s,%d,%s,%.2f,%s,%.3f,%.0f,%.2f,%.2f,%.3f,,\n", K->name, K->lmax1 ? 1 : CMP_LMAX, names[i], ns, names[ref], sp,
                        flops, gf, pg, fr);
        }
    }
    printf("\nMedians over %d rounds; in each round every ISA is timed once (calls of ~10 ms), in this\n"
           "thread's CPU time (time descheduled on a loaded machine does not count), and the speed and the\n"
           "share of peak are ratios within the round.  Peak: %d independent FMA chains of the ISA's vector\n"
           "width (512-bit for avx512, 256-bit for avx2 and scalar on x86).\n",
           ROUNDS, FMA_CHAINS);
    for (int i = 0; i < n; ++i) {
        shl_grid_destroy(grid[i]);
        shl_grid_destroy(grid1[i]);
        shl_ctx_destroy(ctx1[i]);
        shl_ctx_destroy(ctx[i]);
    }
}

int main(int argc, char **argv)
{
    const char *csv_path = "build/bench/bench_simd.csv";
    const char *isa_only = NULL;
    const bench_opt opts[] = {{"-o", "--csv", "FILE", &csv_path, "CSV output (default build/bench/bench_simd.csv)"},
                              {"-i", "--isa-only", NULL, &isa_only, "only the ISA comparison at lmax 8 (~1 minute)"}};
    const bench_cli cli = {
        "bench_simd", "[-o FILE]",
        "Batched SIMD kernels, one core, lmax 2..14, with and without gradients: shl_polygon_batch_f\n"
        "(triangle light) against the scalar double loop, the same kernel compiled scalar\n"
        "(SHLIGHT_ISA=scalar) and the scalar float path, with counted flops against this core's measured\n"
        "FMA peak; shl_sphere_batch_f likewise; a light set (8 triangles, 2 spheres, RGB) through\n"
        "shl_lights_eval_batch_f against shl_lights_eval; then every ISA this CPU runs at lmax 8 on the\n"
        "polygon, sphere, light-set and interpolation batches, as speed ratios to avx2 within each round\n"
        "(and the polygon batch's share of the FMA peak of its own vector width: 512-bit for avx512).\n"
        "About 2-2.5 minutes on a 2-core machine (more under load); progress on stderr.\n"
        "Writes Markdown tables to stdout and one CSV row per table row to the CSV file.",
        opts, 2, 0};
    bench_parse(&cli, argc, argv, NULL);
    FILE *csv = bench_create(csv_path, "w");
    if (!csv) return 1;
    static job j;
    static float out[3 * NPTS * SHL_NCOEFFS(14)], grad[9 * NPTS * SHL_NCOEFFS(14)]; /* light sets: 3 colours */
    static double outd[3 * SHL_NCOEFFS(14)], gradd[9 * SHL_NCOEFFS(14)];
    shl_ctx *probe;
    shl_ctx_create(0, &probe);
    const char *isa = shl_ctx_isa(probe);
    bench_print_machine(stdout);
    printf("library: %s\nbatch ISA chosen: %s\n", shl_build_info(), isa);

    for (int i = 0; i < NV; ++i) { /* triangle of radius 1 in the plane z = 2, points in [-1, 1]^3 */
        j.vd[3 * i] = cos(2 * M_PI * i / NV);
        j.vd[3 * i + 1] = sin(2 * M_PI * i / NV);
        j.vd[3 * i + 2] = 2.0;
    }
    srand(1);
    for (int k = 0; k < 3 * NPTS; ++k) j.pd[k] = 2.0 * rand() / RAND_MAX - 1.0;
    for (int k = 0; k < 3 * NV; ++k) j.vf[k] = (float)j.vd[k];
    for (int k = 0; k < 3 * NPTS; ++k) j.pf[k] = (float)j.pd[k];
    j.out = out;
    j.outd = outd;

    job jp = j; /* the peak microbenchmark: 2^16 iterations of FMA_CHAINS FMAs per call */
    jp.inner = 1L << 16;
    peak_loop_default = peak_for(isa);
    if (peak_loop_default.fn)
        printf("peak: %d independent %s FMA chains in registers, measured in every round\n", FMA_CHAINS,
               peak_loop_default.name);
    const variants polygon = {run_batch, run_scalar_double, run_scalar_float};
    const variants sphere = {run_sphere_batch, run_sphere_double, run_sphere_float};
    const int full = !isa_only; /* the per-lmax tables; --isa-only: the ISA comparison alone */
    if (csv && full) fprintf(csv, "grad,lmax,isa,ns_batch,ns_scalar_double,speedup,ns_batch_scalar_isa,ns_scalar_float,flops,gflops,peak_gflops,peak_fraction\n");

    for (int with_grad = 0; full && with_grad <= 1; ++with_grad) {
        printf("\n## %s, triangle light, one core (%d points per batch call; time per point)\n\n",
               with_grad ? "Coefficients and gradients (shl_polygon_grad)" : "Coefficients (shl_polygon)", NPTS);
        printf("| lmax | scalar double ns | batch ns (%s) | speed-up | batch ns (scalar ISA) | scalar float ns | flops/eval "
               "| GFLOP/s | peak GFLOP/s | of peak |\n", isa);
        printf("|---|---|---|---|---|---|---|---|---|---|\n");
        for (int lmax = 2; lmax <= 14; lmax += 2) {
            bench_progress("polygon batch%s, lmax %d (step %d/6)...", with_grad ? " with gradients" : "", lmax, 1 + with_grad);
            const double flops = kernel_flops(lmax, NV, with_grad);
            const timing t = time_variants(&polygon, &j, lmax, with_grad, grad, gradd, flops, &jp);
            printf("| %d | %.0f | %.1f | **%.1fx** | %.0f | %.0f | %.0f | %.1f | %.1f | **%.0f%%** |\n", lmax,
                   t.scalar_double * 1e9, t.batch * 1e9, t.speedup, t.batch_scalar_isa * 1e9, t.scalar_float * 1e9, flops,
                   t.gflops, t.peak_gflops, 100.0 * t.peak_fraction);
            if (csv)
                fprintf(csv, "%d,%d,%s,%.2f,%.1f,%.2f,%.1f,%.1f,%.0f,%.2f,%.2f,%.3f\n", with_grad, lmax, isa, t.batch * 1e9,
                        t.scalar_double * 1e9, t.speedup, t.batch_scalar_isa * 1e9, t.scalar_float * 1e9, flops, t.gflops,
                        t.peak_gflops, t.peak_fraction);
        }
    }
    if (full)
        printf("\nMedians over 15 rounds; in each round every variant is timed once (calls of ~10 ms) and\n"
           "the speed-up and the fraction of peak are ratios within the round.\n"
           "flops/eval: counted from simd/poly_batch.h (kernel_flops in this file).\n");

    /* spherical light: shl_sphere_batch_f vs the single-point loops */
    if (csv && full) fprintf(csv, "sphere_grad,lmax,isa,ns_batch,ns_scalar_double,speedup,ns_batch_scalar_isa,ns_scalar_float,,,,\n");
    for (int with_grad = 0; full && with_grad <= 1; ++with_grad) {
        printf("\n## Sphere %s (radius 0.5 at distance ~3), one core (%d points per batch call; time per point)\n\n",
               with_grad ? "coefficients and gradients (shl_sphere_grad)" : "coefficients (shl_sphere)", NPTS);
        printf("| lmax | scalar double ns | batch ns (%s) | speed-up | batch ns (scalar ISA) | scalar float ns |\n", isa);
        printf("|---|---|---|---|---|---|\n");
        for (int lmax = 2; lmax <= 14; lmax += 2) {
            bench_progress("sphere batch%s, lmax %d (step %d/6)...", with_grad ? " with gradients" : "", lmax, 3 + with_grad);
            const timing t = time_variants(&sphere, &j, lmax, with_grad, grad, gradd, 0.0, NULL);
            printf("| %d | %.0f | %.1f | **%.1fx** | %.0f | %.0f |\n", lmax, t.scalar_double * 1e9, t.batch * 1e9, t.speedup,
                   t.batch_scalar_isa * 1e9, t.scalar_float * 1e9);
            if (csv)
                fprintf(csv, "%d,%d,%s,%.2f,%.1f,%.2f,%.1f,%.1f,,,,\n", with_grad, lmax, isa, t.batch * 1e9,
                        t.scalar_double * 1e9, t.speedup, t.batch_scalar_isa * 1e9, t.scalar_float * 1e9);
        }
    }
    if (full) printf("\nSphere: medians over 15 rounds, speed-ups within each round, as above.\n");

    /* light set: shl_lights_eval_batch_f vs the double single-point shl_lights_eval */
    shl_lights *set = make_light_set(j.vd);
    j.set = set;
    const variants lights = {run_lights_batch, run_lights_double, run_lights_one_point};
    if (csv && full) fprintf(csv, "lights_grad,lmax,isa,ns_batch,ns_scalar_double,speedup,ns_batch_scalar_isa,ns_batch_one_point,,,,\n");
    for (int with_grad = 0; full && with_grad <= 1; ++with_grad) {
        printf("\n## Light set (%d triangles, %d spheres, RGB) %s, one core (%d points per batch call; time per point)\n\n",
               SET_POLYS, SET_SPHERES, with_grad ? "coefficients and gradients" : "coefficients", NPTS);
        printf("| lmax | shl_lights_eval (double) ns | batch ns (%s) | speed-up | batch ns (scalar ISA) | batch, 1 point per "
               "call ns | batch ns per light |\n", isa);
        printf("|---|---|---|---|---|---|---|\n");
        for (int lmax = 2; lmax <= 14; lmax += 2) {
            bench_progress("light set batch%s, lmax %d (step %d/6)...", with_grad ? " with gradients" : "", lmax, 5 + with_grad);
            const timing t = time_variants(&lights, &j, lmax, with_grad, grad, gradd, 0.0, NULL);
            printf("| %d | %.0f | %.0f | **%.1fx** | %.0f | %.0f | %.1f |\n", lmax, t.scalar_double * 1e9, t.batch * 1e9,
                   t.speedup, t.batch_scalar_isa * 1e9, t.scalar_float * 1e9, t.batch * 1e9 / (SET_POLYS + SET_SPHERES));
            if (csv)
                fprintf(csv, "%d,%d,%s,%.2f,%.1f,%.2f,%.1f,%.1f,,,,\n", with_grad, lmax, isa, t.batch * 1e9,
                        t.scalar_double * 1e9, t.speedup, t.batch_scalar_isa * 1e9, t.scalar_float * 1e9);
        }
    }
    if (full) printf("\nLight set: medians over 15 rounds, speed-ups within each round, as above.\n");
    j.grad = grad;
    isa_comparison(csv, &j, set, isa);
    shl_lights_destroy(set);
    shl_ctx_destroy(probe);
    printf("(checksum %g)\n", (double)bench_sink);
    if (fclose(csv)) return 1;
    bench_progress("done; wrote %s", csv_path);
    return 0;
}
