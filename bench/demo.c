/* make demo: renders a scene (default: the embedded procedural one) with
 * software-rasterized PRT, once per lighting method, and prints the stages
 * that ran, their cost, and each method's image error against per-vertex
 * analytic shading.  Writes <out>.png / <out>.pfm (grid + Hermite, the fast
 * method), <out>-reference.png (per-vertex analytic) and <out>-error.png.
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
    m[0].kind = LM_ANALYTIC; /* the reference */
    m[1].kind = LM_GRID;     /* the fast method */
    m[1].interp = SHL_INTERP_HERMITE;
    m[2].kind = LM_GRID;
    m[2].interp = SHL_INTERP_TRILINEAR;
    m[3].kind = LM_GRID;
    m[3].interp = SHL_INTERP_TAYLOR;
    m[4].kind = LM_ANALYTIC_F;
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
    const int wrote = write_images(out, &p, img[1], img[0], exposure);

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
    for (int i = 0; i < NM; ++i) {
        char name[96];
        const image_error e = image_compare(s.width, s.height, img[i], img[0], p.mask, exposure);
        const double frame = t[i].prepare + t[i].lighting + t[i].shade + t[i].resolve + raster;
        printf("| %s%s | %.2f | %.2f | %.2f | %.2f | %.2f | %.3g | %.3g | %.2e | %.2e | %.3f |\n", lighting_name(&m[i], name, sizeof name),
               i == 0 ? " = reference" : i == 1 ? " = fast" : "", t[i].prepare * 1e3, t[i].lighting * 1e3,
               t[i].shade * 1e3, t[i].resolve * 1e3, frame * 1e3, e.mae, e.rmse, e.mae / e.mean_ref,
               e.rmse / e.mean_ref, e.mae_srgb * 1e3);
    }
    const image_error fast = image_compare(s.width, s.height, img[1], img[0], p.mask, exposure);
    printf("\nFast method (grid %d^3 + Hermite) vs per-vertex analytic: MAE %.3g (%.2e of the mean radiance %.3g), "
           "RMSE %.3g (%.2e), max %.3g.\n",
           s.grid_res, fast.mae, fast.mae / fast.mean_ref, fast.mean_ref, fast.rmse, fast.rmse / fast.mean_ref, fast.max_abs);
    if (wrote)
        printf("could not write %s.png / .pfm (does the directory exist?)\n", out);
    else
        printf("wrote %s.png and %s.pfm (grid + Hermite), %s-reference.png (per-vertex analytic), %s-error.png "
               "(10 x |difference|)\n", out, out, out, out);
    printf("total run time %.2f s\n", bench_now() - t_start);
    for (int i = 0; i < NM; ++i) free(img[i]);
    prt_free(&p);
    scene_free(&s);
    return wrote ? 1 : 0;
}
