/* make demo: renders a scene (default: the embedded procedural one) with
 * software-rasterized PRT, once per lighting method, and prints the stages
 * that ran, their cost, each method's image error against per-vertex
 * analytic shading (double), and which of the library's paths (per-vertex
 * double or float SIMD, grid + Hermite / trilinear / Taylor) was fastest at
 * this scene's light count.  Writes <out>.png / <out>.pfm (grid + Hermite),
 * <out>-reference.png (per-vertex analytic, double) and <out>-error.png.
 *   usage: demo [scene-file] [-o out-prefix] [-c cache-dir]   (defaults: build/demo, build/cache) */
#include "image.h"
#include "parfor.h"
#include "prt.h"
#include "util.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Lights of s that touch or cross the box [lo, hi] (a polygon whose plane has box corners on
 * both sides and whose bounding box overlaps the box; a sphere nearer to the box than its
 * radius): the grid cannot follow the field near them. */
static int lights_in_box(const scene *s, const double lo[3], const double hi[3])
{
    int count = 0;
    for (int i = 0; i < s->npolys; ++i) {
        const scene_polygon *q = &s->polys[i];
        double nrm[3] = {0, 0, 0}, plo[3], phi[3];
        for (int k = 1; k + 1 < q->n; ++k) { /* Newell normal as a fan */
            const double *a = q->v, *b = q->v + 3 * k, *c = q->v + 3 * (k + 1);
            const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            nrm[0] += e1[1] * e2[2] - e1[2] * e2[1];
            nrm[1] += e1[2] * e2[0] - e1[0] * e2[2];
            nrm[2] += e1[0] * e2[1] - e1[1] * e2[0];
        }
        int below = 0, above = 0, overlap = 1;
        for (int k = 0; k < 8; ++k) {
            double d = 0.0;
            for (int a = 0; a < 3; ++a) d += nrm[a] * (((k >> a) & 1 ? hi[a] : lo[a]) - q->v[a]);
            below |= d <= 0;
            above |= d >= 0;
        }
        for (int a = 0; a < 3; ++a) {
            plo[a] = phi[a] = q->v[a];
            for (int k = 1; k < q->n; ++k) {
                plo[a] = fmin(plo[a], q->v[3 * k + a]);
                phi[a] = fmax(phi[a], q->v[3 * k + a]);
            }
            overlap &= plo[a] <= hi[a] && phi[a] >= lo[a];
        }
        count += below && above && overlap;
    }
    for (int i = 0; i < s->nspheres; ++i) {
        const scene_sphere *sp = &s->spheres[i];
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) {
            const double d = fmax(0.0, fmax(lo[a] - sp->center[a], sp->center[a] - hi[a]));
            d2 += d * d;
        }
        count += d2 <= sp->radius * sp->radius;
    }
    return count;
}

static int write_images(const char *out, const prt *p, const float *fast, const float *ref, double exposure)
{
    const int w = p->fb.w, h = p->fb.h;
    char path[1024];
    float *err = malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
    if (!err) return -1;
    for (size_t i = 0; i < 3 * (size_t)w * (size_t)h; ++i) err[i] = 10.0f * fabsf(fast[i] - ref[i]);
    int st = 0;
    snprintf(path, sizeof path, "%s.png", out);
    st |= image_write_png(path, w, h, fast, exposure);
    snprintf(path, sizeof path, "%s.pfm", out);
    st |= image_write_pfm(path, w, h, fast);
    snprintf(path, sizeof path, "%s-reference.png", out);
    st |= image_write_png(path, w, h, ref, exposure);
    snprintf(path, sizeof path, "%s-error.png", out);
    st |= image_write_png(path, w, h, err, exposure);
    free(err);
    return st;
}

int main(int argc, char **argv)
{
    const char *scene_path = NULL, *out = "build/demo", *cache = "build/cache";
    const bench_opt opts[] = {{"-o", "--out", "PREFIX", &out, "image file prefix (default build/demo)"},
                              {"-c", "--cache", "DIR", &cache, "shadowed-transfer cache (default build/cache)"}};
    const bench_cli cli = {
        "demo", "[scene-file] [-o PREFIX] [-c DIR]",
        "make demo: renders a scene (default: the embedded procedural one; a file: see bench/scenes/README.md)\n"
        "with the software-rasterized PRT harness (bench/common: rasterizer, shadows, textured lights and\n"
        "indirect light are the harness's; the SH lighting is the library's), once per lighting method,\n"
        "and prints the stages that ran, their cost, and each method's image error against per-vertex\n"
        "analytic shading.  Default scene: 10-50 s on a 2-core machine, by load (shadow rays are cached\n"
        "after the first run); the paper scenes up to minutes (they need the test meshes: bench_tables\n"
        "--help).  Progress on stderr.\n"
        "Writes PREFIX.png and PREFIX.pfm (grid + Hermite), PREFIX-reference.png (per-vertex analytic)\n"
        "and PREFIX-error.png (10 x |difference|); shadowed transfer is cached under DIR.",
        opts, 2, 1};
    bench_parse(&cli, argc, argv, &scene_path);
    const double t_start = bench_now();
    const int nthreads = par_threads();
    printf("shlight %s demo: software-rasterized PRT with polygonal and spherical area lights\n", SHL_VERSION_STRING);
    bench_print_machine(stdout);
    printf("threads: %d (SHLIGHT_THREADS overrides); batch ISA: ", nthreads);
    shl_ctx *probe;
    if (shl_ctx_create(0, &probe) == SHL_OK) {
        printf("%s\n", shl_ctx_isa(probe));
        shl_ctx_destroy(probe);
    }

    scene s;
    char err[1024], fx[128];
    double t0 = bench_now();
    const int st = scene_path ? scene_load(scene_path, &s, err, sizeof err)
                              : scene_parse(scene_default_text, "default", ".", &s, err, sizeof err);
    if (st == SCENE_MISSING) {
        printf("scene skipped: %s\n(the paper scenes read ../shared/meshes beside the checkout; it is absent here)\n", err);
        return 0;
    }
    if (st) {
        fprintf(stderr, "demo: %s\n", err);
        return 1;
    }
    const double t_scene = bench_now() - t0;
    printf("\nscene \"%s\"%s: %d triangles, %d vertices, %d materials; %d light statements -> %d polygon lights + %d "
           "spherical; lmax %d; %dx%d; effects: %s\n",
           s.name, scene_path ? "" : " (embedded default)", s.geom.nt, s.geom.nv, s.nmats, s.light_statements, s.npolys,
           s.nspheres, s.lmax, s.width, s.height, scene_effects_str(s.effects, fx, sizeof fx));
    printf("  stage %-28s %9.3f s  parse, procedural meshes, OBJ loading, subdivision\n", "scene build", t_scene);
    char out_dir[1024]; /* the directory of the image prefix */
    snprintf(out_dir, sizeof out_dir, "%s", out);
    if (strrchr(out_dir, '/')) *strrchr(out_dir, '/') = '\0', bench_mkdirs(out_dir);

    prt p;
    bench_progress("precomputation for scene \"%s\"...", s.name);
    if (prt_init(&p, &s, nthreads, cache, stdout)) {
        fprintf(stderr, "demo: precomputation failed (out of memory?)\n");
        scene_free(&s);
        return 1;
    }
    const size_t npix = 3 * (size_t)s.width * (size_t)s.height;
    enum { NM = 7 };
    lighting_method m[NM];
    memset(m, 0, sizeof m);
    for (int i = 0; i < NM; ++i) {
        m[i].lmax = s.lmax;
        m[i].grid_res = s.grid_res;
        m[i].grid_storage = SHL_GRID_FLOAT;
        m[i].taylor_b = 2.0;
        m[i].mc_samples = s.mc_samples;
    }
    /* the library's paths (0: the reference), then the harness's baselines (monomial, MC) */
    enum { NLIB = 5 };
    m[0].kind = LM_ANALYTIC;
    m[1].kind = LM_ANALYTIC_F;
    m[2].kind = LM_GRID;
    m[2].interp = SHL_INTERP_HERMITE;
    m[3].kind = LM_GRID;
    m[3].interp = SHL_INTERP_TRILINEAR;
    m[4].kind = LM_GRID;
    m[4].interp = SHL_INTERP_TAYLOR;
    m[5].kind = LM_MONOMIAL;
    m[6].kind = LM_MC;
    float *img[NM];
    prt_times t[NM];
    int ok = 1;
    for (int i = 0; i < NM && ok; ++i) {
        char name[96];
        img[i] = malloc(sizeof(float) * npix);
        bench_progress("rendering with %s (%d/%d)...", lighting_name(&m[i], name, sizeof name), i + 1, NM);
        t0 = bench_now();
        ok = img[i] && !prt_render(&p, &m[i], NULL, 0, img[i], &t[i]);
        printf("  stage %-28s %9.3f s  lighting + shading + resolve\n", lighting_name(&m[i], name, sizeof name),
               bench_now() - t0);
        fflush(stdout);
    }
    if (!ok) {
        fprintf(stderr, "demo: rendering failed\n");
        return 1;
    }
    const double exposure = prt_exposure(&p, img[0]);
    /* lighting cost = prepare (grid fill) + per-vertex coefficients: the stages that differ by path;
     * the grids compete only when no light touches their box */
    const int inbox = lights_in_box(&s, p.lo, p.hi);
    double cost[NM];
    int best = 0;
    for (int i = 0; i < NM; ++i) {
        cost[i] = t[i].prepare + t[i].lighting;
        if (i < (inbox ? 2 : NLIB) && cost[i] < cost[best]) best = i;
    }
    const int wrote = write_images(out, &p, img[2], img[0], exposure);

    printf("\n## Precomputation (once per scene)\n\n");
    prt_print_stages(&p, stdout);
    const double raster = p.raster_seconds;
    printf("\n## Per frame, per lighting method (%d threads; lmax %d, %d coefficients x 3 colours; %d vertices)\n\n",
           nthreads, s.lmax, SHL_NCOEFFS(s.lmax), s.geom.nv);
    printf("Error: image of the method vs the image of per-vertex analytic shading, over the %ld pixels showing\n"
           "receivers; linear radiance (MAE, RMSE, relative = / mean reference radiance) and 8-bit sRGB at the\n"
           "image's exposure %.3g (MAE in [0,1] units x 1e-3, as Wu 2020 Table 1).  Frame = prepare + lighting +\n"
           "shade + resolve + visibility raster (%.1f ms, shared).\n\n",
           image_compare(s.width, s.height, img[0], img[0], p.mask, exposure).pixels, exposure, raster * 1e3);
    printf("| method | prepare ms | lighting ms | shade ms | resolve ms | frame ms | MAE | RMSE | rel. MAE | rel. RMSE | sRGB MAE x1e-3 |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|\n");
    static const char *tag[NM] = {" = reference", "", "", "", "", " (not in the library)", " (not in the library)"};
    for (int i = 0; i < NM; ++i) {
        char name[96];
        const image_error e = image_compare(s.width, s.height, img[i], img[0], p.mask, exposure);
        const double frame = t[i].prepare + t[i].lighting + t[i].shade + t[i].resolve + raster;
        printf("| %s%s%s | %.2f | %.2f | %.2f | %.2f | %.2f | %.3g | %.3g | %.2e | %.2e | %.3f |\n",
               lighting_name(&m[i], name, sizeof name), tag[i], i == best ? " = fastest" : "", t[i].prepare * 1e3, t[i].lighting * 1e3,
               t[i].shade * 1e3, t[i].resolve * 1e3, frame * 1e3, e.mae, e.rmse, e.mae / e.mean_ref,
               e.rmse / e.mean_ref, e.mae_srgb * 1e3);
    }
    /* Recommendation from this run's numbers: the fastest of the library's paths, the fastest whose
     * image error is at most TOL, and the fastest per-vertex path (float SIMD unless double measured
     * faster) or, when a per-vertex path wins, the fastest grid. */
    const double TOL = 1e-2;
    char na[96], nb[96];
    double rel[NLIB];
    for (int i = 0; i < NLIB; ++i) {
        const image_error ei = image_compare(s.width, s.height, img[i], img[0], p.mask, exposure);
        rel[i] = ei.mae / ei.mean_ref;
    }
    int good = 0;
    for (int i = 1; i < (inbox ? 2 : NLIB); ++i)
        if (rel[i] <= TOL && cost[i] < cost[good]) good = i;
    const int pv = cost[1] <= cost[0] ? 1 : 0, gbest = cost[2] <= cost[3] && cost[2] <= cost[4] ? 2 : cost[3] <= cost[4] ? 3 : 4;
    const int other = best >= 2 ? pv : gbest;
    printf("\nLighting cost = prepare (grid fill) + lighting (per-vertex coefficients), %d thread(s), every path alike;\n"
           "err = relative MAE of the image vs per-vertex double (the table's rel. MAE).\n", nthreads);
    printf("Recommendation for this scene (%d polygon + %d spherical lights, lmax %d, %d vertices):\n", s.npolys,
           s.nspheres, s.lmax, s.geom.nv);
    printf("  fastest at this light count: %s: %.1f ms, err %.1e\n", lighting_name(&m[best], na, sizeof na),
           cost[best] * 1e3, rel[best]);
    if (good != best)
        printf("  fastest at err <= %.0e: %s: %.1f ms, err %.1e\n", TOL, lighting_name(&m[good], na, sizeof na),
               cost[good] * 1e3, rel[good]);
    printf("  fastest %s: %s: %.1f ms, err %.1e", best >= 2 ? "per-vertex path" : "grid",
           lighting_name(&m[other], nb, sizeof nb), cost[other] * 1e3, rel[other]);
    if (inbox)
        printf(", not usable here:\n  %d light(s) touch the grid box (the receivers' bounding box) and grid results near them\n"
               "  are wrong\n", inbox);
    else
        printf(" (%.2fx the time of the fastest)\n  with static lights (grids filled once): Hermite %.1f ms, trilinear %.1f ms, "
               "Taylor %.1f ms a frame\n", cost[other] / cost[best], t[2].lighting * 1e3, t[3].lighting * 1e3,
               t[4].lighting * 1e3);
    printf("  (one run's timings on a possibly shared machine; build/bench/bench_paths measures every path by light\n"
           "  count and lmax.)\n");
    if (wrote)
        printf("could not write %s.png / .pfm (does the directory exist?)\n", out);
    else
        printf("wrote %s.png and %s.pfm (%s), %s-reference.png (per-vertex analytic, double), %s-error.png\n"
               "(10 x |difference|)\n", out, out, lighting_name(&m[2], na, sizeof na), out, out);
    printf("total run time %.2f s\n", bench_now() - t_start);
    for (int i = 0; i < NM; ++i) free(img[i]);
    prt_free(&p);
    scene_free(&s);
    return wrote ? 1 : 0;
}
