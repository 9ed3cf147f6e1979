/* Adaptive vs uniform grids (issue 19 item 3): error vs nodes and error vs fill time
 * on Wu 2020's Fig. 12 case (bench/scenes/wu-fig12.scene: a two-sided quad inside the
 * grid's box) and on a Table 1 stand-in (wu-monkey.scene: every light outside the box).
 * lmax 8, float nodes, Hermite.
 * 1. Coefficient proxy: lights from the scene files (mesh objects skipped); the box is the
 * receivers' bounding box the scene files state, x, z in [-2.5, 2.5], y in [0, 1.9].  At
 * NPTS random points uniform in the box and NPTS on the floor (y = 0, the receiver plane the
 * Fig. 12 light stands on), e(p) = max over colours of the L2 norm of the coefficient error
 * against shl_lights_eval (double), i.e. the L2 error of the radiance function over the
 * sphere (Parseval); reported as mean e / mean |L| (rel. MAE) over both sets.  Ratios:
 * against uniform 32^3, the adaptive run with the fewest nodes and the one with the least
 * fill time among those at an error <= uniform 32^3's (rel. MAE; on wu-monkey also the
 * largest error: on wu-fig12 that is the jump across the light, unresolved by any grid).
 * Writes DIR/bench_agrid.csv: scene,kind,res,tol,nodes,samples,levels,fill_s,cpu_s,rel_mae,
 * rel_max,bytes (fill_s wall, cpu_s process CPU time of the fill, best of the repetitions;
 * samples: the estimate's light-set evaluations without gradients (stats.samples), the
 * fill's cost beyond its nodes; with the node count a cost proxy that load does not disturb).
 * 2. Image error (the measure): the scenes of --image-scenes (default wu-fig12,wu-monkey)
 * rendered as bench_tables renders them
 * (meshes from --meshes DIR, else $SHLIGHT_MESHES, else ../shared/meshes; skipped with a
 * note when absent), per-vertex analytic float SIMD at the visible vertices as the
 * reference, uniform grids and adaptive grids (SHL_AGRID_MEAN: coarse 4^3 and 8^3 at
 * tolerances, 4^3 at budgets; each without receivers, kinds mean and budget, and with every
 * mesh vertex a receiver, shl_agrid_set_receivers, kinds mean-recv and budget-recv, and with
 * them weighted by the pixels they cover, shl_agrid_set_weighted_receivers, kinds mean-wrecv and
 * budget-wrecv, its cost timed with the fill's) lighting every vertex; rel. MAE of the image
 * (bench/common/image.h) against the reference; fill times from fills of the same grids
 * outside the frame.  Writes DIR/bench_agrid_image.csv:
 * scene,kind,res,tol,budget,nodes,samples,fill_s,cpu_s,rel_mae.
 * All from this run.  Usage: bench_agrid [--quick] [--threads N]
 * [--only wu-fig12|wu-monkey|image] [--image-scenes a,b,...] [--recv-only] [--meshes DIR] [-d DIR]
 * (default DIR build/bench; --recv-only: the adaptive runs with receivers only). */
#include "image.h"
#include "meshes.h"
#include "prt.h"
#include "scene.h"
#include "shlight.h"
#include "util.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { NPTS = 4000, LMAX = 8, NC = SHL_NCOEFFS(LMAX) };

static const double box_lo[3] = {-2.5, 0.0, -2.5}, box_hi[3] = {2.5, 1.9, 2.5};

static void must(int st, const char *what)
{
    if (st != SHL_OK) {
        fprintf(stderr, "bench_agrid: %s: %s\n", what, shl_strerror(st));
        exit(1);
    }
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, "bench_agrid: out of memory\n");
        exit(1);
    }
    return p;
}

/* The light set of a scene file, parsed without its `object ... mesh` lines. */
static shl_lights *scene_lights(const char *file)
{
    char path[512], err[512];
    snprintf(path, sizeof path, "bench/scenes/%s", file);
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "bench_agrid: cannot read %s (run from the repository root)\n", path);
        exit(1);
    }
    char *text = xmalloc(1 << 16), line[4096];
    size_t len = 0;
    text[0] = '\0';
    while (fgets(line, sizeof line, f))
        if (!(strncmp(line, "object", 6) == 0 && strstr(line, " mesh ")) && len + strlen(line) < (1 << 16)) {
            memcpy(text + len, line, strlen(line) + 1);
            len += strlen(line);
        }
    fclose(f);
    scene s;
    if (scene_parse(text, file, "bench/scenes", &s, err, sizeof err)) {
        fprintf(stderr, "bench_agrid: %s: %s\n", file, err);
        exit(1);
    }
    shl_lights *l = scene_light_set(&s);
    if (!l) exit(1);
    scene_free(&s);
    free(text);
    return l;
}

typedef struct {
    const shl_ctx *ctx;
    double *pts, *ref, *out, mean_ref;
    int n;
} probe;

static unsigned long long rng = 88172645463325252ull;
static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1p-53;
}

static double vnorm(const double *v) /* max over colours of the L2 norm of nc coefficients */
{
    double m = 0.0;
    for (int c = 0; c < 3; ++c) {
        double s = 0.0;
        for (int k = 0; k < NC; ++k) s += v[c * NC + k] * v[c * NC + k];
        m = fmax(m, sqrt(s));
    }
    return m;
}

static void probe_init(probe *p, const shl_ctx *ctx, const shl_lights *l, int nthreads)
{
    p->ctx = ctx;
    p->n = 2 * NPTS;
    p->pts = xmalloc(sizeof(double) * 3 * (size_t)p->n);
    p->ref = xmalloc(sizeof(double) * 3 * NC * (size_t)p->n);
    p->out = xmalloc(sizeof(double) * 3 * NC * (size_t)p->n);
    for (int i = 0; i < p->n; ++i)
        for (int a = 0; a < 3; ++a)
            p->pts[3 * i + a] = a == 1 && i >= NPTS ? 0.0 : box_lo[a] + (box_hi[a] - box_lo[a]) * urand();
    must(shl_lights_eval_batch_mt(ctx, l, p->n, p->pts, p->ref, NULL, nthreads), "reference");
    p->mean_ref = 0.0;
    for (int i = 0; i < p->n; ++i) p->mean_ref += vnorm(p->ref + 3 * NC * (size_t)i) / p->n;
}

/* Relative mean and max error of p->out. */
static void probe_error(const probe *p, double *mae, double *mx)
{
    double *d = xmalloc(sizeof(double) * 3 * NC);
    *mae = *mx = 0.0;
    for (int i = 0; i < p->n; ++i) {
        for (int k = 0; k < 3 * NC; ++k) d[k] = p->out[3 * NC * (size_t)i + k] - p->ref[3 * NC * (size_t)i + k];
        const double e = vnorm(d);
        *mae += e / p->n;
        *mx = fmax(*mx, e);
    }
    *mae /= p->mean_ref;
    *mx /= p->mean_ref;
    free(d);
}

/* CPU seconds of the process (all threads): a fill's cost that load on the shared
 * machine disturbs far less than the wall time. */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct {
    double res, tol, fill, cpu, mae, mx;
    long nodes, samples;
    long long bytes;
    int levels;
    const char *kind;
} result;

static FILE *csv;

static void record(const char *scene, const char *kind, result *r)
{
    r->kind = kind;
    printf("  %-8s res %3.0f  tol %9.3g  nodes %7ld  samples %7ld  levels %d  fill %8.2f ms  cpu %8.2f ms  rel MAE %.3e  rel max "
           "%.3e  %6.1f MB\n",
           kind, r->res, r->tol, r->nodes, r->samples, r->levels, r->fill * 1e3, r->cpu * 1e3, r->mae, r->mx,
           (double)r->bytes / 1e6);
    if (csv)
        fprintf(csv, "%s,%s,%.0f,%.4e,%ld,%ld,%d,%.6f,%.6f,%.5e,%.5e,%lld\n", scene, kind, r->res, r->tol, r->nodes, r->samples,
                r->levels, r->fill, r->cpu, r->mae, r->mx, r->bytes);
}

static result uniform(const shl_ctx *ctx, const shl_lights *l, probe *p, int res, int reps, int nthreads)
{
    const int r3[3] = {res, res, res};
    shl_grid *g;
    must(shl_grid_create(ctx, box_lo, box_hi, r3, SHL_GRID_FLOAT, &g), "grid");
    result r = {res, 0, INFINITY, INFINITY, 0, 0, (long)res * res * res, 0, 0, 1, "uniform"};
    for (int k = 0; k < reps; ++k) {
        const double t0 = bench_now(), c0 = cpu_now();
        must(shl_grid_fill(g, l, nthreads), "fill");
        r.fill = fmin(r.fill, bench_now() - t0);
        r.cpu = fmin(r.cpu, cpu_now() - c0);
    }
    int bpn;
    must(shl_grid_bytes_per_node(LMAX, SHL_GRID_FLOAT, &bpn), "bytes");
    r.bytes = (long long)bpn * r.nodes;
    must(shl_grid_interp(g, SHL_INTERP_HERMITE, 0.0, p->n, p->pts, p->out, nthreads), "interp");
    probe_error(p, &r.mae, &r.mx);
    shl_grid_destroy(g);
    return r;
}

static result adaptive(const shl_ctx *ctx, const shl_lights *l, probe *p, int res, int criterion, double tol, long budget,
                       int reps, int nthreads)
{
    const int r3[3] = {res, res, res};
    shl_agrid *g;
    must(shl_agrid_create(ctx, box_lo, box_hi, r3, criterion, tol, budget, &g), "agrid");
    result r = {res, tol, INFINITY, INFINITY, 0, 0, 0, 0, 0, 0, ""};
    for (int k = 0; k < reps; ++k) {
        const double t0 = bench_now(), c0 = cpu_now();
        must(shl_agrid_fill(g, l, nthreads), "afill");
        r.fill = fmin(r.fill, bench_now() - t0);
        r.cpu = fmin(r.cpu, cpu_now() - c0);
    }
    shl_agrid_stats st;
    must(shl_agrid_get_stats(g, &st), "stats");
    r.nodes = st.nodes;
    r.samples = st.samples;
    r.levels = st.levels;
    r.bytes = st.bytes;
    must(shl_agrid_interp(g, p->n, p->pts, p->out, nthreads), "ainterp");
    probe_error(p, &r.mae, &r.mx);
    shl_agrid_destroy(g);
    return r;
}

/* light_in_box: the max error is then set by the field's jump across the light (no grid
 * resolves it), so only the mean is compared. */
static void run_scene(const char *file, const char *name, int light_in_box, int quick, int nthreads)
{
    printf("\n== %s (%s), lmax %d, box [-2.5,2.5]x[0,1.9]x[-2.5,2.5], %d threads ==\n", name, file, LMAX, nthreads);
    shl_ctx *ctx;
    must(shl_ctx_create(LMAX, &ctx), "ctx");
    shl_lights *l = scene_lights(file);
    probe p;
    probe_init(&p, ctx, l, nthreads);
    printf("  %d lights; mean |L| over the probe points %.4g\n", shl_lights_count(l), p.mean_ref);
    const int reps = quick ? 1 : 3, ures[] = {8, 12, 16, 24, 32};
    result u32 = {0};
    for (unsigned i = 0; i < sizeof ures / sizeof ures[0]; ++i) {
        result r = uniform(ctx, l, &p, ures[i], reps, nthreads);
        record(name, "uniform", &r);
        if (ures[i] == 32) u32 = r;
    }
    /* Both criteria, tolerances relative to the mean |L| of the probe points (tol is absolute in
     * the API), at a budget of 32^3 nodes; then budget-driven runs: SHL_AGRID_MEAN at a tolerance
     * no run meets (1e-6) and smaller budgets, the refinement going best first by e 8^-l until
     * the budget refuses a cell. */
    const double rel[] = {1e-1, 3e-2, 1e-2, 3e-3, 2e-3, 1.5e-3, 1e-3, 3e-4};
    const long budgets[] = {3000, 5000, 7000, 9000, 12000, 16000};
    const int cres[] = {4, 8}, nrel = sizeof rel / sizeof rel[0], nb = sizeof budgets / sizeof budgets[0];
    result best_nodes[2], best_time[2];
    for (int m = 0; m < 2; ++m) {
        best_nodes[m].nodes = -1;
        best_time[m].fill = INFINITY;
    }
    for (unsigned c = 0; c < sizeof cres / sizeof cres[0]; ++c)
        for (int t = 0; t < 2 * nrel + nb; ++t) {
            const int criterion = t < nrel ? SHL_AGRID_MAX : SHL_AGRID_MEAN;
            const double tol = (t < 2 * nrel ? rel[t % nrel] : 1e-6) * p.mean_ref;
            const long budget = t < 2 * nrel ? 32L * 32 * 32 : budgets[t - 2 * nrel];
            result r = adaptive(ctx, l, &p, cres[c], criterion, tol, budget, reps, nthreads);
            record(name, t >= 2 * nrel ? "budget" : criterion == SHL_AGRID_MAX ? "max" : "mean", &r);
            for (int m = 0; m < 2; ++m) /* m = 0: at rel. MAE <= 32^3's; 1: at rel. max <= 32^3's */
                if (m ? r.mx <= u32.mx : r.mae <= u32.mae) {
                    if (best_nodes[m].nodes < 0 || r.nodes < best_nodes[m].nodes) best_nodes[m] = r;
                    if (r.fill < best_time[m].fill) best_time[m] = r;
                }
        }
    for (int m = 0; m < 2 - light_in_box; ++m) {
        const char *metric = m ? "rel. max" : "rel. MAE";
        const double target = m ? u32.mx : u32.mae;
        if (best_nodes[m].nodes < 0) {
            printf("  %s: no adaptive run reached uniform 32^3's %.3e\n", metric, target);
            continue;
        }
        printf("  %s <= uniform 32^3's (%.3e): fewest nodes %ld (%s, coarse %.0f^3, tol %.3g): %.1fx fewer nodes, %.1fx less "
               "fill time (%.1fx less CPU time) than 32^3\n",
               metric, target, best_nodes[m].nodes, best_nodes[m].kind, best_nodes[m].res, best_nodes[m].tol,
               (double)u32.nodes / best_nodes[m].nodes, u32.fill / best_nodes[m].fill, u32.cpu / best_nodes[m].cpu);
        printf("  %s <= uniform 32^3's: least fill time %.1f ms (%s, coarse %.0f^3, tol %.3g, %ld nodes): %.1fx less fill "
               "time (%.1fx less CPU time), %.1fx fewer nodes than 32^3\n",
               metric, best_time[m].fill * 1e3, best_time[m].kind, best_time[m].res, best_time[m].tol, best_time[m].nodes,
               u32.fill / best_time[m].fill, u32.cpu / best_time[m].cpu, (double)u32.nodes / best_time[m].nodes);
    }
    free(p.pts);
    free(p.ref);
    free(p.out);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
}

/* One frame of the rendered scene with lighting method m: its image error; then the method's
 * grid alone, filled reps times outside the frame: wall and CPU time of the fill (best of reps)
 * and the node count. */
static void image_row(FILE *f, prt *pr, const lighting_method *m, const float *ref, double exposure, float *img, int reps,
                      const char *kind, double tol_rel, double *mae, double *fill, double *cpu, long *nodes)
{
    prt_times t;
    if (prt_render(pr, m, NULL, 0, img, &t)) {
        fprintf(stderr, "bench_agrid: render failed\n");
        exit(1);
    }
    const image_error e = image_compare(pr->s->width, pr->s->height, img, ref, pr->mask, exposure);
    *mae = e.mae / e.mean_ref;
    shl_ctx *ctx;
    shl_lights *l = scene_light_set(pr->s);
    const int r3[3] = {m->grid_res, m->grid_res, m->grid_res};
    must(shl_ctx_create(m->lmax, &ctx), "ctx");
    shl_agrid *ag = NULL;
    shl_grid *ug = NULL;
    if (m->kind == LM_AGRID)
        must(shl_agrid_create(ctx, pr->lo, pr->hi, r3, m->agrid_criterion, m->agrid_tol, m->agrid_budget, &ag), "agrid");
    else
        must(shl_grid_create(ctx, pr->lo, pr->hi, r3, SHL_GRID_FLOAT, &ug), "grid");
    *cpu = INFINITY;
    *fill = INFINITY;
    for (int k = 0; k < reps; ++k) {
        const double t0 = bench_now(), c0 = cpu_now();
        if (ag) must(shl_agrid_set_weighted_receivers(ag, m->agrid_receivers ? m->agrid_nreceivers : 0, m->agrid_receivers,
                                                      m->agrid_receiver_weights),
                     "receivers"); /* timed with the fill: for a static mesh a one-off cost */
        must(ag ? shl_agrid_fill(ag, l, pr->nthreads) : shl_grid_fill(ug, l, pr->nthreads), "fill");
        *fill = fmin(*fill, bench_now() - t0);
        *cpu = fmin(*cpu, cpu_now() - c0);
    }
    shl_agrid_stats st = {0};
    if (ag) must(shl_agrid_get_stats(ag, &st), "stats");
    *nodes = ag ? st.nodes : (long)r3[0] * r3[1] * r3[2];
    shl_agrid_destroy(ag);
    shl_grid_destroy(ug);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
    printf("  %-8s res %3d  tol %9.3g  budget %7ld  nodes %7ld  samples %7ld  fill %8.2f ms  cpu %8.2f ms  image rel MAE "
           "%.3e\n",
           kind, m->grid_res, tol_rel, ag ? m->agrid_budget : 0L, *nodes, st.samples, *fill * 1e3, *cpu * 1e3, *mae);
    if (f)
        fprintf(f, "%s,%s,%d,%.4e,%ld,%ld,%ld,%.6f,%.6f,%.5e\n", pr->s->name, kind, m->grid_res, tol_rel,
                m->kind == LM_AGRID ? m->agrid_budget : 0L, *nodes, st.samples, *fill, *cpu, *mae);
}

/* The image error of uniform and adaptive grids on a rendered scene (see the top of the file). */
static void run_image(FILE *f, const char *file, const char *meshes, int quick, int recv_only, int nthreads)
{
    printf("\n== %s rendered (image error against the per-vertex reference), lmax %d, %d threads ==\n", file, LMAX,
           nthreads);
    char err[1024], path[1024];
    if (meshes_verify(meshes, err, sizeof err)) {
        printf("  skipped: the scene's mesh is not in %s (--meshes DIR):\n%s\n", meshes, err);
        return;
    }
    scene_mesh_dir = meshes;
    scene s;
    snprintf(path, sizeof path, "bench/scenes/%s", file);
    if (scene_load(path, &s, err, sizeof err)) {
        printf("  skipped: %s\n", err);
        return;
    }
    prt pr;
    if (prt_init(&pr, &s, nthreads, NULL, NULL)) {
        fprintf(stderr, "bench_agrid: precomputation failed\n");
        exit(1);
    }
    /* image weights of the receivers: the image is linear in the vertex radiances, pixel q showing
     * triangle t getting sum_k bary_k(q) v(t_k), so its mean absolute error weighs vertex v's error
     * by the sum of v's barycentric weights over the pixels (shl_agrid_set_weighted_receivers) */
    double *pixel_weight = calloc((size_t)s.geom.nv, sizeof(double));
    if (!pixel_weight) exit(1);
    for (size_t q = 0; q < (size_t)pr.fb.w * (size_t)pr.fb.h; ++q)
        if (pr.fb.mesh[q] == 0)
            for (int k = 0; k < 3; ++k) pixel_weight[s.geom.tri[3 * (size_t)pr.fb.tri[q] + k]] += pr.fb.bary[3 * q + k];
    const size_t len = 3 * (size_t)s.width * (size_t)s.height;
    float *ref = xmalloc(sizeof(float) * len), *img = xmalloc(sizeof(float) * len);
    int *idx = xmalloc(sizeof(int) * (size_t)s.geom.nv);
    const long nvis = prt_visible_vertices(&pr, idx);
    lighting_method m;
    memset(&m, 0, sizeof m);
    m.kind = LM_ANALYTIC_F;
    m.lmax = LMAX;
    prt_times t;
    if (prt_render(&pr, &m, idx, nvis, ref, &t)) exit(1);
    const double exposure = prt_exposure(&pr, ref);
    const int reps = quick ? 1 : 3, ures[] = {8, 12, 16, 24, 32};
    double mae, fill, cpu, u32_mae = 0, u32_fill = INFINITY, u32_cpu = INFINITY;
    long nodes;
    m.kind = LM_GRID;
    m.interp = SHL_INTERP_HERMITE;
    m.grid_storage = SHL_GRID_FLOAT;
    for (unsigned i = 0; i < sizeof ures / sizeof ures[0]; ++i) {
        m.grid_res = ures[i];
        image_row(f, &pr, &m, ref, exposure, img, reps, "uniform", 0.0, &mae, &fill, &cpu, &nodes);
        if (ures[i] == 32) {
            u32_mae = mae;
            u32_fill = fill;
            u32_cpu = cpu;
        }
    }
    /* tolerances relative to the mean |L| over the box (the same probe as above), at a budget of
     * 32^3; then budgets at a tolerance no run meets */
    shl_ctx *ctx;
    must(shl_ctx_create(LMAX, &ctx), "ctx");
    shl_lights *l = scene_light_set(&s);
    probe p;
    probe_init(&p, ctx, l, nthreads);
    shl_lights_destroy(l);
    shl_ctx_destroy(ctx);
    /* with receivers the MEAN criterion is e n_cell / n (a cell's share of the receivers, ~1e-2 of
     * level 0's volume share on a surface), so its tolerances go 100x lower */
    const double rels[2][10] = {{3e-2, 1e-2, 5e-3, 3e-3, 2e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5},
                                {1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8}};
    const long budgets[] = {3000, 5000, 7000, 9000, 12000, 16000, 24000};
    const int nrel = sizeof rels[0] / sizeof rels[0][0], nb = sizeof budgets / sizeof budgets[0];
    m.kind = LM_AGRID;
    m.agrid_criterion = SHL_AGRID_MEAN;
    static const char *kinds[3][2] = {{"mean", "budget"}, {"mean-recv", "budget-recv"}, {"mean-wrecv", "budget-wrecv"}};
    for (int rv = recv_only; rv < 3; ++rv) {
        /* without receivers, with the mesh vertices as receivers (shl_agrid_set_receivers), and with
         * them weighted by the pixels they cover (shl_agrid_set_weighted_receivers) */
        const double *rel = rels[rv > 0];
        m.agrid_receivers = rv ? s.geom.pos : NULL;
        m.agrid_nreceivers = rv ? s.geom.nv : 0;
        m.agrid_receiver_weights = rv == 2 ? pixel_weight : NULL;
        long best_nodes = -1;
        double best_fill = INFINITY, best_cpu = INFINITY;
        for (int k = 0; k < 2 * nrel + nb; ++k) { /* coarse 4^3 and 8^3 at each tolerance; budgets at 4^3 */
            m.grid_res = k < nrel || k >= 2 * nrel ? 4 : 8;
            const double trel = k < 2 * nrel ? rel[k % nrel] : 1e-12; /* budgets: a tolerance no cell meets */
            m.agrid_tol = trel * p.mean_ref;
            m.agrid_budget = k < 2 * nrel ? 32L * 32 * 32 : budgets[k - 2 * nrel];
            const char *kind = kinds[rv][k >= 2 * nrel];
            image_row(f, &pr, &m, ref, exposure, img, reps, kind, trel, &mae, &fill, &cpu, &nodes);
            if (mae <= u32_mae) {
                if (best_nodes < 0 || nodes < best_nodes) best_nodes = nodes;
                best_fill = fmin(best_fill, fill);
                best_cpu = fmin(best_cpu, cpu);
            }
        }
        const char *what = rv == 2 ? "with pixel-weighted receivers" : rv ? "with receivers" : "without receivers";
        if (best_nodes < 0)
            printf("  %s: image rel. MAE <= uniform 32^3's (%.3e): no adaptive run\n", what, u32_mae);
        else
            printf("  %s: image rel. MAE <= uniform 32^3's (%.3e): fewest nodes %ld (%.1fx fewer than 32768), least fill "
                   "time %.1f ms (%.1fx less than 32^3's %.1f ms), least fill CPU time %.1f ms (%.1fx less than 32^3's "
                   "%.1f ms)\n",
                   what, u32_mae, best_nodes, 32768.0 / best_nodes, best_fill * 1e3, u32_fill / best_fill, u32_fill * 1e3,
                   best_cpu * 1e3, u32_cpu / best_cpu, u32_cpu * 1e3);
    }
    free(p.pts);
    free(p.ref);
    free(p.out);
    free(ref);
    free(img);
    free(idx);
    free(pixel_weight);
    prt_free(&pr);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    const char *dir = "build/bench";
    const char *only = NULL, *meshes = getenv(MESHES_ENV);
    if (!meshes || !meshes[0]) meshes = MESHES_DEFAULT_DIR;
    const char *image_scenes = "wu-fig12,wu-monkey";
    int quick = 0, recv_only = 0, nthreads = 2;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--quick"))
            quick = 1;
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            nthreads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--only") && i + 1 < argc)
            only = argv[++i];
        else if (!strcmp(argv[i], "--recv-only"))
            recv_only = 1;
        else if (!strcmp(argv[i], "--image-scenes") && i + 1 < argc)
            image_scenes = argv[++i];
        else if (!strcmp(argv[i], "--meshes") && i + 1 < argc)
            meshes = argv[++i];
        else if (!strcmp(argv[i], "-d") && i + 1 < argc)
            dir = argv[++i];
        else {
            fprintf(stderr, "usage: bench_agrid [--quick] [--threads N] [--only wu-fig12|wu-monkey|image] [--image-scenes "
                            "a,b,...] [--recv-only] [--meshes DIR] [-d DIR]\n");
            return 2;
        }
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/bench_agrid.csv", dir);
    csv = only && !strcmp(only, "image") ? NULL : fopen(path, "w");
    if (csv) fprintf(csv, "scene,kind,res,tol,nodes,samples,levels,fill_s,cpu_s,rel_mae,rel_max,bytes\n");
    if (!only || !strcmp(only, "wu-fig12")) run_scene("wu-fig12.scene", "wu-fig12", 1, quick, nthreads);
    if (!only || !strcmp(only, "wu-monkey")) run_scene("wu-monkey.scene", "wu-monkey", 0, quick, nthreads);
    if (csv) {
        fclose(csv);
        printf("\nCSV: %s\n", path);
    }
    if (!only || !strcmp(only, "image")) {
        snprintf(path, sizeof path, "%s/bench_agrid_image.csv", dir);
        FILE *f = fopen(path, "w");
        if (f) fprintf(f, "scene,kind,res,tol,budget,nodes,samples,fill_s,cpu_s,rel_mae\n");
        char list[256], file[300];
        snprintf(list, sizeof list, "%s", image_scenes);
        for (char *sv = NULL, *tok = strtok_r(list, ",", &sv); tok; tok = strtok_r(NULL, ",", &sv)) {
            snprintf(file, sizeof file, "%s.scene", tok);
            run_image(f, file, meshes, quick, recv_only, nthreads);
        }
        if (f) {
            fclose(f);
            printf("\nCSV: %s\n", path);
        }
    }
    return 0;
}
