/* make bench-tables: the results tables of the four papers, reproduced on this
 * machine with the software-rasterized PRT harness (bench/common).  Writes under
 * -o DIR (default build/bench-tables): RESULTS-tables.md, the CSV files in tables/ and
 * manifest.txt (scenes run, CPU, load, date); `make bench-tables-accept` copies a
 * complete run over the committed bench/RESULTS-tables.md and bench/tables/.
 * Options and sections: bench_tables --help.  The paper scenes read the public test
 * meshes (bench/common/meshes.h); without them it stops before measuring. */
#include "bvh.h"
#include "image.h"
#include "lambert.h"
#include "meshes.h"
#include "parfor.h"
#include "prt.h"
#include "util.h"
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static FILE *md;
static const char *csv_dir = "bench/tables";
static const char *scene_dir = "bench/scenes";
static int nthreads;

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, "bench_tables: out of memory\n");
        exit(1);
    }
    return p;
}

static FILE *csv_open(const char *name, const char *header)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", csv_dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "bench_tables: cannot write %s\n", path);
        exit(1);
    }
    fprintf(f, "%s\n", header);
    return f;
}

static void csv_close(FILE *f, const char *name)
{
    if (!f) return;
    fclose(f);
    fprintf(md, "\nCSV: `%s/%s`\n", csv_dir, name);
}

/* Scenes loaded (each file and status once, with a count), for the manifest. */
static struct {
    char file[64];
    int status, loads;
} scenes_run[64];
static int nscenes_run;

static void note_scene(const char *file, int status)
{
    for (int i = 0; i < nscenes_run; ++i)
        if (!strcmp(scenes_run[i].file, file) && scenes_run[i].status == status) {
            ++scenes_run[i].loads;
            return;
        }
    if (nscenes_run == 64) return;
    snprintf(scenes_run[nscenes_run].file, sizeof scenes_run[0].file, "%s", file);
    scenes_run[nscenes_run].status = status;
    scenes_run[nscenes_run++].loads = 1;
}

/* Load a scene (text: NULL reads scene_dir/file); a missing mesh is reported in the Markdown. */
static int load_scene(const char *file, const char *text, scene *s)
{
    char err[1024], path[1024];
    snprintf(path, sizeof path, "%s/%s", scene_dir, file);
    fprintf(stderr, "[%s]\n", file);
    const int st = text ? scene_parse(text, file, scene_dir, s, err, sizeof err) : scene_load(path, s, err, sizeof err);
    note_scene(file, st);
    if (st == SCENE_MISSING)
        fprintf(md, "\n**%s skipped**: %s - the paper scenes read `../shared/meshes/` beside the checkout, which is "
                    "absent here.\n", file, err);
    else if (st)
        fprintf(md, "\n**%s failed**: %s\n", file, err);
    return st;
}

static void init_prt(prt *p, scene *s)
{
    if (prt_init(p, s, nthreads, NULL, NULL)) {
        fprintf(stderr, "bench_tables: precomputation failed for %s\n", s->name);
        exit(1);
    }
}

static lighting_method method(lighting_kind kind, int lmax)
{
    lighting_method m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    m.lmax = lmax;
    m.grid_res = 8;
    m.interp = SHL_INTERP_HERMITE;
    m.grid_storage = SHL_GRID_FLOAT;
    m.taylor_b = 2.0;
    m.mc_samples = 256;
    return m;
}

static lighting_method grid(int lmax, int res, int interp)
{
    lighting_method m = method(LM_GRID, lmax);
    m.grid_res = res;
    m.interp = interp;
    return m;
}

/* Best (minimum) of reps renders, per stage. */
static prt_times render(prt *p, const lighting_method *m, const int *subset, long nsub, float *img, int reps)
{
    prt_times best = {INFINITY, INFINITY, INFINITY, INFINITY};
    for (int r = 0; r < reps; ++r) {
        prt_times t;
        if (prt_render(p, m, subset, nsub, img, &t)) {
            fprintf(stderr, "bench_tables: render failed (%s)\n", p->s->name);
            exit(1);
        }
        best.prepare = fmin(best.prepare, t.prepare);
        best.lighting = fmin(best.lighting, t.lighting);
        best.shade = fmin(best.shade, t.shade);
        best.resolve = fmin(best.resolve, t.resolve);
    }
    return best;
}

/* Best of reps visibility rasterizations (the same buffer is rebuilt). */
static double raster_time(prt *p, int reps)
{
    double best = INFINITY;
    for (int r = 0; r < reps; ++r) {
        const double t0 = bench_now();
        if (raster_draw(&p->fb, &p->cam, p->rm, 3, nthreads)) exit(1);
        best = fmin(best, bench_now() - t0);
    }
    return best;
}

static size_t img_len(const scene *s) { return 3 * (size_t)s->width * (size_t)s->height; }

/* Reference image: per-vertex analytic (float SIMD) at the vertices visible pixels use;
 * *seconds_all: its lighting time scaled to every vertex. */
static float *reference(prt *p, int lmax, double *seconds_all, long *nvis)
{
    int *idx = xmalloc(sizeof(int) * (size_t)p->s->geom.nv);
    *nvis = prt_visible_vertices(p, idx);
    float *img = xmalloc(sizeof(float) * img_len(p->s));
    const lighting_method m = method(LM_ANALYTIC_F, lmax);
    const prt_times t = render(p, &m, idx, *nvis, img, 1);
    *seconds_all = t.lighting * (double)p->s->geom.nv / (double)(*nvis > 0 ? *nvis : 1);
    free(idx);
    return img;
}

typedef struct {
    const shl_ctx *ctx;
    const shl_lights *lights;
    int nc;
    const double *pts;
    double *out;
} nodes_job;

static void nodes_block(void *arg, long begin, long end, int worker)
{
    (void)worker;
    const nodes_job *j = arg;
    if (shl_lights_eval_batch(j->ctx, j->lights, (int)(end - begin), j->pts + 3 * begin, j->out + 3 * j->nc * begin, NULL) != SHL_OK)
        exit(1);
}

/* Coefficients only (no gradients) at the res^3 grid nodes over the receiver box: best of reps. */
static double node_coeffs_time(const prt *p, int res, int reps)
{
    const long n = (long)res * res * res;
    const int nc = SHL_NCOEFFS(p->s->lmax);
    double *pts = xmalloc(sizeof(double) * 3 * (size_t)n), *out = xmalloc(sizeof(double) * 3 * (size_t)nc * (size_t)n);
    for (long i = 0; i < n; ++i) {
        const long ijk[3] = {i % res, i / res % res, i / res / res};
        for (int a = 0; a < 3; ++a) pts[3 * i + a] = p->lo[a] + (p->hi[a] - p->lo[a]) * (double)ijk[a] / (res - 1);
    }
    shl_ctx *ctx;
    shl_lights *l = scene_light_set(p->s);
    if (!l || shl_ctx_create(p->s->lmax, &ctx) != SHL_OK) exit(1);
    nodes_job j = {ctx, l, nc, pts, out};
    double best = INFINITY;
    for (int r = 0; r < reps; ++r) {
        const double t0 = bench_now();
        par_for(n, 8, nthreads, nodes_block, &j);
        best = fmin(best, bench_now() - t0);
    }
    shl_ctx_destroy(ctx);
    shl_lights_destroy(l);
    free(pts);
    free(out);
    return best;
}

/* ---- Wu et al. 2020, Table 1 ----------------------------------------------- */

typedef struct {
    const char *file, *scene, *figure, *tris, *lights;
    double eval, evalgrad, interp, total, fps, mae, ref, speedup;
} wu_row;

static const wu_row wu_rows[] = {
    {"wu-dragon-bunny.scene", "Dragon & Bunny", "Fig. 1", "1.28M", "723", 16.5, 20.2, 6.6, 27.9, 35.8, 0.18, 110e3, 3943},
    {"wu-monkey.scene", "Monkey", "Fig. 7", "71.2K", "118", 1.3, 1.8, 0.4, 3.3, 303, 0.29, 177, 35},
    {"wu-plants.scene", "Plants", "Fig. 8", "190K", "2", 0.08, 0.1, 2.1, 3.1, 323, 0.17, 9.4, 3},
    {"wu-asian-dragon.scene", "Asian Dragon", "Fig. 9", "1.42M", "181", 2.3, 3.0, 8.1, 12.7, 78.7, 1.35, 3.22e3, 254},
    {"wu-room.scene", "Room", "Fig. 10", "1.71M", "344", 4.3, 5.8, 10.3, 17.7, 56.5, 0.34, 6.85e3, 387},
    {"wu-buddha.scene", "Buddha", "Fig. 11", "422K", "210", 4.8, 5.7, 6.0, 12.7, 78.7, 0.07, 28.6e3, 2252},
};

static void section_wu(void)
{
    fprintf(md, "\n## Wu et al. 2020, Table 1: scene statistics, grid 8^3 + Hermite vs per-vertex analytic\n\n"
                "Stand-ins (bench/scenes/wu-*.scene, each file says which mesh and how it is subdivided): the paper's\n"
                "triangle and light counts, meshes from ../shared/meshes subdivided (uniform 1-to-4, then longest-edge\n"
                "bisection) to them, textured lights split into the paper's number of uniform triangles.  lmax 8,\n"
                "unshadowed diffuse transfer (the timed stages do not depend on it), 800x600, %d threads, float grid\n"
                "nodes.  Eval coeff: coefficients only at the 512 nodes (shl_lights_eval_batch); eval coeff & grad:\n"
                "shl_grid_fill; interp: Hermite at every vertex; total adds shading (transfer dot products), the\n"
                "visibility raster and resolving the image.  Reference: per-vertex analytic shading (Wang 2018, our\n"
                "float SIMD path shl_lights_eval_batch_f), computed at the vertices the image uses and its time scaled to\n"
                "all vertices.  MAE: 8-bit sRGB images in [0,1] units (x1e-3, as the paper) and linear relative.\n"
                "Times: best of 3 (reference: 1 run).\n\n",
            nthreads);
    fprintf(md, "| scene (stand-in) | triangles | vertices | lights | grid | eval coeff ms | eval coeff & grad ms | interp ms | "
                "shade + raster ms | total ms | FPS | MAE x1e-3 | rel. MAE | reference ms | speed-up |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    FILE *csv = NULL;
    for (unsigned r = 0; r < sizeof wu_rows / sizeof wu_rows[0]; ++r) {
        const wu_row *w = &wu_rows[r];
        scene s;
        if (load_scene(w->file, NULL, &s)) continue;
        if (!csv)
            csv = csv_open("wu2020_table1.csv", "scene,triangles,vertices,lights,grid,eval_coeff_ms,eval_coeff_grad_ms,interp_ms,"
                                                "shade_raster_ms,total_ms,fps,mae_srgb_1e3,rel_mae,reference_ms,speedup");
        prt p;
        init_prt(&p, &s);
        float *img = xmalloc(sizeof(float) * img_len(&s));
        const lighting_method m = grid(s.lmax, 8, SHL_INTERP_HERMITE);
        const prt_times t = render(&p, &m, NULL, 0, img, 3);
        const double coeff = node_coeffs_time(&p, 8, 3), raster = raster_time(&p, 3);
        double ref_s;
        long nvis;
        float *ref = reference(&p, s.lmax, &ref_s, &nvis);
        const image_error e = image_compare(s.width, s.height, img, ref, p.mask, prt_exposure(&p, ref));
        const double rest = t.shade + raster + t.resolve, total = t.prepare + t.lighting + rest;
        fprintf(md, "| %s | %d | %d | %d | 8^3 | %.1f | %.1f | %.1f | %.1f | %.1f | %.2f | %.2f | %.2e | %.3g | %.1fx |\n",
                w->scene, s.geom.nt, s.geom.nv, s.npolys, coeff * 1e3, t.prepare * 1e3, t.lighting * 1e3, rest * 1e3,
                total * 1e3, 1.0 / total, e.mae_srgb * 1e3, e.mae / e.mean_ref, ref_s * 1e3, ref_s / total);
        fprintf(csv, "%s,%d,%d,%d,8,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.5f,%.4e,%.4f,%.3f\n", w->scene, s.geom.nt, s.geom.nv, s.npolys,
                coeff * 1e3, t.prepare * 1e3, t.lighting * 1e3, rest * 1e3, total * 1e3, 1.0 / total, e.mae_srgb * 1e3,
                e.mae / e.mean_ref, ref_s * 1e3, ref_s / total);
        fflush(md);
        free(img);
        free(ref);
        prt_free(&p);
        scene_free(&s);
    }
    csv_close(csv, "wu2020_table1.csv");
    fprintf(md, "\nThe paper (NVIDIA RTX 2080 Ti, GPU shaders in Falcor; its MAE scale is not stated beyond x1e-3):\n\n"
                "| scene | triangles | lights | grid | eval coeff ms | eval coeff & grad ms | interp ms | total ms | FPS | MAE x1e-3 | reference ms | speed-up |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (unsigned r = 0; r < sizeof wu_rows / sizeof wu_rows[0]; ++r) {
        const wu_row *w = &wu_rows[r];
        fprintf(md, "| %s (%s) | %s | %s | 8^3 | %.2f | %.1f | %.1f | %.1f | %.1f | %.2f | %.3g | %.0fx |\n", w->scene, w->figure,
                w->tris, w->lights, w->eval, w->evalgrad, w->interp, w->total, w->fps, w->mae, w->ref, w->speedup);
    }
}

/* A scene file's text without its `light` lines, for experiments that replace the lights. */
static char *scene_text_without_lights(const char *file)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", scene_dir, file);
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *out = xmalloc(1 << 16), line[4096];
    size_t n = 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "light ", 6) && n + strlen(line) + 1 < (1 << 16)) {
            strcpy(out + n, line);
            n += strlen(line);
        }
    fclose(f);
    out[n] = '\0';
    return out;
}

/* ---- Wu 2020 Fig. 8: lighting time vs light count ------------------------------ */

static void section_wu_fig8(void)
{
    fprintf(md, "\n## Wu et al. 2020, Fig. 8: SH lighting time at all vertices vs number of lights\n\n"
                "The wu-monkey scene (Suzanne subdivided to 61.4K triangles + floor) lit by the rectangle\n"
                "(-1.5, 2.8, -1.5)-(1.5, 2.8, 1.5), one-sided, as 1 quad or split into N uniform triangles\n"
                "(the paper subdivides a rectangular light up to 512 triangles).  lmax 8, %d threads.  Times are\n"
                "the lighting only (coefficients at every vertex), best of 2; the grid column is fill (with\n"
                "gradients) + Hermite interpolation.  Error: the grid image vs the per-vertex analytic image.\n\n"
                "| lights | per-vertex analytic (double) ms | per-vertex analytic (float SIMD) ms | grid fill ms | Hermite interp ms | grid total ms | speed-up vs double | rel. MAE |\n"
                "|---|---|---|---|---|---|---|---|\n",
            nthreads);
    char *base = scene_text_without_lights("wu-monkey.scene");
    FILE *csv = NULL;
    for (int nl = 1; base && nl <= 512; nl *= 2) {
        char *text = xmalloc(strlen(base) + 256);
        const char *quad = "-1.5 2.8 -1.5  1.5 2.8 -1.5  1.5 2.8 1.5  -1.5 2.8 1.5";
        if (nl == 1)
            sprintf(text, "%slight polygon one-sided 6 5 4  %s\n", base, quad);
        else
            sprintf(text, "%slight textured one-sided %d 6 5 4  6 5 4  %s\n", base, nl, quad);
        scene s;
        const int st = load_scene("wu-monkey.scene", text, &s);
        free(text);
        if (st) break;
        if (!csv)
            csv = csv_open("wu2020_fig8.csv", "lights,pervertex_double_ms,pervertex_float_ms,grid_fill_ms,grid_interp_ms,grid_total_ms,rel_mae");
        prt p;
        init_prt(&p, &s);
        float *a = xmalloc(sizeof(float) * img_len(&s)), *g = xmalloc(sizeof(float) * img_len(&s));
        const lighting_method md_ = method(LM_ANALYTIC, s.lmax), mf = method(LM_ANALYTIC_F, s.lmax), mg = grid(s.lmax, 8, SHL_INTERP_HERMITE);
        const prt_times td = render(&p, &md_, NULL, 0, a, nl <= 64 ? 2 : 1), tf = render(&p, &mf, NULL, 0, a, 2);
        const prt_times tg = render(&p, &mg, NULL, 0, g, 2);
        const image_error e = image_compare(s.width, s.height, g, a, p.mask, 1.0);
        fprintf(md, "| %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1fx | %.2e |\n", nl, td.lighting * 1e3, tf.lighting * 1e3,
                tg.prepare * 1e3, tg.lighting * 1e3, (tg.prepare + tg.lighting) * 1e3, td.lighting / (tg.prepare + tg.lighting),
                e.mae / e.mean_ref);
        fprintf(csv, "%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4e\n", nl, td.lighting * 1e3, tf.lighting * 1e3, tg.prepare * 1e3,
                tg.lighting * 1e3, (tg.prepare + tg.lighting) * 1e3, e.mae / e.mean_ref);
        fflush(md);
        free(a);
        free(g);
        prt_free(&p);
        scene_free(&s);
    }
    csv_close(csv, "wu2020_fig8.csv");
    free(base);
}

/* ---- Wu 2020 Fig. 9: grid resolution vs time and error --------------------------- */

static void section_wu_fig9(void)
{
    fprintf(md, "\n## Wu et al. 2020, Fig. 9: grid resolution vs time and image error\n\n"
                "The wu-monkey scene (118 lights, lmax 8, %d threads).  Reference: per-vertex analytic (float SIMD)\n"
                "at the vertices the image uses.  Float nodes; times best of 2 (32^3: 1).\n\n"
                "| grid | memory MiB | fill ms | Hermite interp ms | frame ms | MAE x1e-3 (sRGB) | rel. MAE |\n"
                "|---|---|---|---|---|---|---|\n",
            nthreads);
    scene s;
    if (load_scene("wu-monkey.scene", NULL, &s)) return;
    FILE *csv = csv_open("wu2020_fig9.csv", "res,memory_mib,fill_ms,interp_ms,frame_ms,mae_srgb_1e3,rel_mae");
    prt p;
    init_prt(&p, &s);
    double ref_s;
    long nvis;
    float *ref = reference(&p, s.lmax, &ref_s, &nvis), *img = xmalloc(sizeof(float) * img_len(&s));
    const double exposure = prt_exposure(&p, ref), raster = raster_time(&p, 3);
    int bpn;
    shl_grid_bytes_per_node(s.lmax, SHL_GRID_FLOAT, &bpn);
    const int res[] = {4, 6, 8, 12, 16, 24, 32};
    for (unsigned i = 0; i < sizeof res / sizeof res[0]; ++i) {
        const lighting_method m = grid(s.lmax, res[i], SHL_INTERP_HERMITE);
        const prt_times t = render(&p, &m, NULL, 0, img, res[i] < 32 ? 2 : 1);
        const image_error e = image_compare(s.width, s.height, img, ref, p.mask, exposure);
        const double frame = t.prepare + t.lighting + t.shade + t.resolve + raster;
        const double mib = (double)res[i] * res[i] * res[i] * bpn / (1 << 20);
        fprintf(md, "| %d^3 | %.2f | %.1f | %.1f | %.1f | %.3f | %.2e |\n", res[i], mib, t.prepare * 1e3, t.lighting * 1e3,
                frame * 1e3, e.mae_srgb * 1e3, e.mae / e.mean_ref);
        fprintf(csv, "%d,%.4f,%.4f,%.4f,%.4f,%.5f,%.4e\n", res[i], mib, t.prepare * 1e3, t.lighting * 1e3, frame * 1e3,
                e.mae_srgb * 1e3, e.mae / e.mean_ref);
        fflush(md);
    }
    csv_close(csv, "wu2020_fig9.csv");
    free(ref);
    free(img);
    prt_free(&p);
    scene_free(&s);
}

/* ---- Wang & Ramamoorthi 2018, Table 2 ------------------------------------------- */

typedef struct {
    const char *file, *scene, *tris;
    int lights;
    double fps, fps_monomial;
} wang_row;

static const wang_row wang_rows[] = {
    {"wang-plant.scene", "Plant (Fig. 5)", "163k", 1, 350.0, 91.0},
    {"wang-buddha.scene", "Buddha (Fig. 1)", "388k", 3, 28.4, 8.2},
    {"wang-dragon.scene", "Dragon (Fig. 9)", "1M", 1, 38.5, 15.3},
    {"wang-face.scene", "Face (Fig. 8)", "98k", 1, 384.6, 150.0},
};

static void section_wang(void)
{
    fprintf(md, "\n## Wang & Ramamoorthi 2018, Table 2: frames per second, ZH recurrence vs monomial baseline\n\n"
                "Stand-ins in bench/scenes/wang-*.scene (paper triangle and light counts).  lmax 8 (the paper's\n"
                "\"order n = 8\", 81 terms), per-vertex evaluation at every vertex, %d threads, best of 2.  Lighting:\n"
                "the SH coefficients of all lights at every vertex - ours through shl_lights_eval_batch (double;\n"
                "one ZH -> SH reconstruction per colour) and shl_lights_eval_batch_f (float SIMD), the baseline with\n"
                "the monomial moments of Snyder 1996 / Arvo 1995 (bench/common/monomial.c) in the same structure.\n"
                "Frame: lighting + shading + visibility raster + resolve (800x600).\n\n"
                "| scene (stand-in) | triangles | vertices | lights | ours double: lighting ms / frame fps | ours float SIMD: lighting ms / fps | monomial: lighting ms / fps | monomial / ours double (lighting) | paper: ours fps | paper: monomial fps |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n",
            nthreads);
    FILE *csv = NULL;
    for (unsigned r = 0; r < sizeof wang_rows / sizeof wang_rows[0]; ++r) {
        const wang_row *w = &wang_rows[r];
        scene s;
        if (load_scene(w->file, NULL, &s)) continue;
        if (!csv)
            csv = csv_open("wang2018_table2.csv", "scene,triangles,vertices,lights,ours_double_ms,ours_double_fps,ours_float_ms,"
                                                  "ours_float_fps,monomial_ms,monomial_fps,paper_fps,paper_monomial_fps");
        prt p;
        init_prt(&p, &s);
        float *img = xmalloc(sizeof(float) * img_len(&s));
        const double raster = raster_time(&p, 2);
        const lighting_method m[3] = {method(LM_ANALYTIC, s.lmax), method(LM_ANALYTIC_F, s.lmax), method(LM_MONOMIAL, s.lmax)};
        double ms[3], fps[3];
        for (int k = 0; k < 3; ++k) {
            const prt_times t = render(&p, &m[k], NULL, 0, img, 2);
            ms[k] = t.lighting * 1e3;
            fps[k] = 1.0 / (t.lighting + t.shade + t.resolve + raster);
        }
        fprintf(md, "| %s | %d | %d | %d | %.1f / %.2f | %.1f / %.2f | %.1f / %.2f | %.2f | %.1f | %.1f |\n", w->scene, s.geom.nt,
                s.geom.nv, s.npolys, ms[0], fps[0], ms[1], fps[1], ms[2], fps[2], ms[2] / ms[0], w->fps, w->fps_monomial);
        fprintf(csv, "%s,%d,%d,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.1f,%.1f\n", w->scene, s.geom.nt, s.geom.nv, s.npolys, ms[0],
                fps[0], ms[1], fps[1], ms[2], fps[2], w->fps, w->fps_monomial);
        fflush(md);
        free(img);
        prt_free(&p);
        scene_free(&s);
    }
    csv_close(csv, "wang2018_table2.csv");
    fprintf(md, "\nPaper: NVIDIA GTX 1080 Ti, vertex shader; \"our algorithm is 2x-4x faster than using the monomial recurrence\".\n");
}

/* ---- Annen et al. 2004, Table 1 --------------------------------------------------- */

typedef struct {
    const char *file, *model, *verts;
    double fps_single, fps_gradient;
} annen_row;

static const annen_row annen_rows[] = {
    {"annen-planck.scene", "Planck", "25K", 23.8, 19.7},
    {"annen-bird.scene", "Bird", "32K", 8.4, 7.9},
    {"annen-tooth.scene", "Tooth", "2.5K", 40.3, 34.5},
};

static void section_annen(void)
{
    fprintf(md, "\n## Annen et al. 2004, Table 1: single sample vs sample + gradient vs eight samples\n\n"
                "Stand-ins in bench/scenes/annen-*.scene (paper vertex counts; three coloured lights, at mid range\n"
                "for Planck and Bird, close and overlapping for Tooth as in the paper's Fig. 7).  lmax 4,\n"
                "%d threads, 512x512, best of 3.  Single sample: coefficients at the centre of the object's bounding\n"
                "box; + gradient: first-order Taylor extrapolation (Eq. 14); eight samples: a 2^3 grid at the box\n"
                "corners, trilinear (no gradients), inverse-distance-weighted Taylor (Eq. 15-16, b = 2) and Hermite\n"
                "(Wu 2020).  Frame: lighting (incl. sampling) + shading + visibility raster + resolve.  Error vs the\n"
                "per-vertex analytic image.\n\n"
                "| model (stand-in) | vertices | method | frame ms | fps | MAE x1e-3 (sRGB) | rel. MAE | paper fps |\n"
                "|---|---|---|---|---|---|---|---|\n",
            nthreads);
    FILE *csv = NULL;
    for (unsigned r = 0; r < sizeof annen_rows / sizeof annen_rows[0]; ++r) {
        const annen_row *w = &annen_rows[r];
        scene s;
        if (load_scene(w->file, NULL, &s)) continue;
        if (!csv) csv = csv_open("annen2004_table1.csv", "model,vertices,method,frame_ms,fps,mae_srgb_1e3,rel_mae,paper_fps");
        prt p;
        init_prt(&p, &s);
        float *ref = xmalloc(sizeof(float) * img_len(&s)), *img = xmalloc(sizeof(float) * img_len(&s));
        const double raster = raster_time(&p, 3);
        lighting_method mref = method(LM_ANALYTIC, s.lmax);
        render(&p, &mref, NULL, 0, ref, 1);
        const double exposure = prt_exposure(&p, ref);
        lighting_method m[5] = {method(LM_SINGLE, s.lmax), method(LM_TAYLOR1, s.lmax), grid(s.lmax, 2, SHL_INTERP_TRILINEAR),
                                grid(s.lmax, 2, SHL_INTERP_TAYLOR), grid(s.lmax, 2, SHL_INTERP_HERMITE)};
        const char *names[5] = {"single sample", "single sample + gradient", "8 samples, trilinear",
                                "8 samples + gradients (Taylor, b = 2)", "8 samples + gradients (Hermite)"};
        const double paper[5] = {w->fps_single, w->fps_gradient, NAN, NAN, NAN};
        for (int k = 0; k < 5; ++k) {
            for (int a = 0; a < 3; ++a) m[k].point[a] = 0.5 * (p.lo[a] + p.hi[a]);
            const prt_times t = render(&p, &m[k], NULL, 0, img, 3);
            const image_error e = image_compare(s.width, s.height, img, ref, p.mask, exposure);
            const double frame = t.prepare + t.lighting + t.shade + t.resolve + raster;
            char pf[32] = "-";
            if (!isnan(paper[k])) snprintf(pf, sizeof pf, "%.1f", paper[k]);
            fprintf(md, "| %s (%s) | %d | %s | %.2f | %.0f | %.2f | %.2e | %s |\n", w->model, w->verts, s.geom.nv, names[k],
                    frame * 1e3, 1.0 / frame, e.mae_srgb * 1e3, e.mae / e.mean_ref, pf);
            fprintf(csv, "%s,%d,%s,%.4f,%.3f,%.5f,%.4e,%s\n", w->model, s.geom.nv, names[k], frame * 1e3, 1.0 / frame,
                    e.mae_srgb * 1e3, e.mae / e.mean_ref, isnan(paper[k]) ? "" : pf);
        }
        fflush(md);
        free(ref);
        free(img);
        prt_free(&p);
        scene_free(&s);
    }
    csv_close(csv, "annen2004_table1.csv");
    fprintf(md, "\nPaper: 3 GHz PC, Quadro FX 3000, 512x512, lighting sampled from 64x64 cube maps (the sampling cost\n"
                "dominates its frame); it reports fps only - quality shown in Figs. 1, 5, 7.\n");
}

/* ---- HVL (Mezieres et al. 2022), Table 1 ------------------------------------------ */

static void section_hvl(void)
{
    static const double paper[3][4] = {{6.6, 7.8, 10.3, 18.6}, {19.8, 23.5, 30.4, 56.1}, {41.0, 48.6, 62.7, 115.3}};
    static const int counts[3] = {64, 196, 400}, bands[4] = {3, 5, 7, 9};
    fprintf(md, "\n## Mezieres et al. 2022 (HVL), Table 1: indirect-light gathering time\n\n"
                "bench/scenes/hvl-teaser.scene: the Stanford bunny (69K triangles) in a room, one light under the\n"
                "ceiling; HVLs from its reflective shadow map (20x20, 14x14, 8x8 rays; radius heuristic 1), emission\n"
                "on 3 bands (lmax 2), convolution on 3/5/7/9 bands (the receiver table's lmax 2/4/6/8).  Gathering\n"
                "(shl_hvl_shade per HVL and shading point) at every 4th receiver vertex, %d threads, best of 2.\n\n",
            nthreads);
    scene s;
    if (load_scene("hvl-teaser.scene", NULL, &s)) return;
    FILE *csv = csv_open("hvl2022_table1.csv", "hvls_requested,hvls,bands,points,ms,us_per_point,ns_per_point_hvl,paper_ms");
    bvh *b = bvh_build(&s.geom);
    const long npts = (s.geom.nv + 3) / 4;
    int *idx = xmalloc(sizeof(int) * (size_t)npts);
    float *ind = xmalloc(sizeof(float) * 3 * (size_t)s.geom.nv);
    for (long i = 0; i < npts; ++i) idx[i] = (int)(4 * i);
    fprintf(md, "Shading points: %ld.\n\n| HVLs (requested / placed) | 3 bands ms | 5 bands ms | 7 bands ms | 9 bands ms | "
                "ns per point-HVL (3 / 9 bands) | paper ms (3 / 5 / 7 / 9) |\n|---|---|---|---|---|---|---|\n", npts);
    for (int c = 0; c < 3 && b; ++c) {
        double ms[4];
        int placed = 0;
        for (int k = 0; k < 4; ++k) {
            hvl_set h;
            s.hvl_count = counts[c];
            s.hvl_lmax = 2;
            if (hvl_distribute(&s, b, bands[k] - 1, &h)) exit(1);
            placed = h.count;
            ms[k] = INFINITY;
            for (int r = 0; r < 2; ++r) {
                memset(ind, 0, sizeof(float) * 3 * (size_t)s.geom.nv);
                const double t0 = bench_now();
                if (hvl_gather(&s, &h, idx, npts, ind, nthreads)) exit(1);
                ms[k] = fmin(ms[k], (bench_now() - t0) * 1e3);
            }
            fprintf(csv, "%d,%d,%d,%ld,%.4f,%.4f,%.3f,%.1f\n", counts[c], placed, bands[k], npts, ms[k], ms[k] * 1e3 / npts,
                    ms[k] * 1e6 / ((double)npts * placed), paper[c][k]);
            hvl_free(&h);
        }
        fprintf(md, "| %d / %d | %.1f | %.1f | %.1f | %.1f | %.0f / %.0f | %.1f / %.1f / %.1f / %.1f |\n", counts[c], placed, ms[0],
                ms[1], ms[2], ms[3], ms[0] * 1e6 / ((double)npts * placed), ms[3] * 1e6 / ((double)npts * placed), paper[c][0],
                paper[c][1], paper[c][2], paper[c][3]);
        fflush(md);
    }
    csv_close(csv, "hvl2022_table1.csv");
    fprintf(md, "\nPaper: Intel Xeon 2.10 GHz + RTX 2080, GLSL, per pixel of its frame (resolution not stated in the\n"
                "table).  Shape to compare: linear in the HVL count, growing with the band count.\n");
    free(idx);
    free(ind);
    bvh_free(b);
    scene_free(&s);
}

/* ---- What accuracy costs in time ------------------------------------------------ */

static void sweep_row(FILE *csv, const char *scene_name, prt *p, const lighting_method *m, const char *param, const float *truth,
                      double exposure, double raster, int reps)
{
    char name[96];
    float *img = xmalloc(sizeof(float) * img_len(p->s));
    const prt_times t = render(p, m, NULL, 0, img, reps);
    const image_error e = image_compare(p->s->width, p->s->height, img, truth, p->mask, exposure);
    const double frame = t.prepare + t.lighting + t.shade + t.resolve + raster;
    lighting_name(m, name, sizeof name);
    const char *family = m->kind == LM_ANALYTIC ? "analytic double"
                         : m->kind == LM_ANALYTIC_F ? "analytic float"
                         : m->kind == LM_MC ? "Monte Carlo"
                         : m->interp == SHL_INTERP_HERMITE ? (m->grid_storage == SHL_GRID_DOUBLE ? "grid Hermite double" : "grid Hermite")
                         : m->interp == SHL_INTERP_TRILINEAR ? "grid trilinear"
                                                             : "grid Taylor";
    fprintf(md, "| %s | %s | %.2f | %.3f | %.2e | %.2e |\n", family, param, frame * 1e3, e.mae_srgb * 1e3, e.mae / e.mean_ref,
            e.rmse / e.mean_ref);
    fprintf(csv, "%s,%s,\"%s\",%.5f,%.5f,%.5f,%.6f,%.5e,%.5e\n", scene_name, family, param, frame * 1e3, (t.prepare + t.lighting) * 1e3,
            t.shade * 1e3, e.mae_srgb * 1e3, e.mae / e.mean_ref, e.rmse / e.mean_ref);
    fflush(md);
    fflush(csv);
    free(img);
}

static void sweep_scene(FILE *csv, const char *file, int glossy)
{
    scene s;
    if (load_scene(file, NULL, &s)) return;
    prt p;
    init_prt(&p, &s);
    float *truth = xmalloc(sizeof(float) * img_len(&s));
    if (glossy) {
        const lighting_method m = method(LM_ANALYTIC, s.lmax);
        render(&p, &m, NULL, 0, truth, 1);
    } else {
        float *v = xmalloc(sizeof(float) * 3 * (size_t)s.geom.nv);
        lambert_scene(&s, v);
        const float *colors[3] = {v, p.emit_rgb[0], p.emit_rgb[1]};
        raster_resolve(&p.fb, p.rm, colors, truth, nthreads);
        free(v);
    }
    const double exposure = prt_exposure(&p, truth), raster = raster_time(&p, 3);
    fprintf(md, "\n### %s: %d vertices, %d lights; truth: %s\n\n| method | parameter | frame ms | MAE x1e-3 (sRGB) | rel. MAE | rel. RMSE |\n"
                "|---|---|---|---|---|---|\n",
            s.name, s.geom.nv, s.npolys, glossy ? "per-vertex analytic at lmax 24" : "Lambert's closed form per vertex (exact)");
    char param[32];
    for (int l = 2; l <= 14; l += 2) {
        snprintf(param, sizeof param, "lmax %d", l);
        const lighting_method md_ = method(LM_ANALYTIC, l), mf = method(LM_ANALYTIC_F, l);
        sweep_row(csv, s.name, &p, &md_, param, truth, exposure, raster, 2);
        sweep_row(csv, s.name, &p, &mf, param, truth, exposure, raster, 2);
    }
    const int res[] = {4, 6, 8, 12, 16, 24, 32};
    for (unsigned i = 0; i < sizeof res / sizeof res[0]; ++i) {
        snprintf(param, sizeof param, "%d^3, lmax 8", res[i]);
        const int interps[3] = {SHL_INTERP_HERMITE, SHL_INTERP_TRILINEAR, SHL_INTERP_TAYLOR};
        for (int k = 0; k < 3; ++k) {
            const lighting_method m = grid(8, res[i], interps[k]);
            sweep_row(csv, s.name, &p, &m, param, truth, exposure, raster, 2);
        }
        lighting_method m = grid(8, res[i], SHL_INTERP_HERMITE);
        m.grid_storage = SHL_GRID_DOUBLE;
        sweep_row(csv, s.name, &p, &m, param, truth, exposure, raster, 2);
    }
    for (long n = 16; n <= 65536; n *= 4) {
        snprintf(param, sizeof param, "%ld samples, lmax 8", n);
        lighting_method m = method(LM_MC, 8);
        m.mc_samples = n;
        sweep_row(csv, s.name, &p, &m, param, truth, exposure, raster, 1);
    }
    free(truth);
    prt_free(&p);
    scene_free(&s);
}

static void section_sweep(void)
{
    fprintf(md, "\n## What accuracy costs in time: image error vs frame time, one curve per method\n\n"
                "Two small procedural scenes (bench/scenes/sweep-*.scene), %d threads.  Curves: per-vertex analytic\n"
                "shading at lmax 2..14 in double (shl_lights_eval_batch) and float (shl_lights_eval_batch_f); grids\n"
                "4^3..32^3 at lmax 8 with Hermite, trilinear and Taylor interpolation (float nodes) and Hermite on\n"
                "double nodes; Monte Carlo projection with 16..65536 samples per vertex at lmax 8.  Frame: lighting\n"
                "(+ grid fill) + shading + visibility raster + resolve, best of 2 (Monte Carlo: 1).  Errors against\n"
                "the truth named per scene, over the pixels showing receivers; methods at lmax 8 keep the lmax-8\n"
                "truncation error as a floor.  Plot: `tools/plot.py` (bench/plots/).\n",
            nthreads);
    FILE *csv = csv_open("accuracy_vs_time.csv", "scene,method,parameter,frame_ms,lighting_ms,shade_ms,mae_srgb_1e3,rel_mae,rel_rmse");
    sweep_scene(csv, "sweep-diffuse.scene", 0);
    sweep_scene(csv, "sweep-glossy.scene", 1);
    csv_close(csv, "accuracy_vs_time.csv");
}

static void utc_now(char *buf, size_t len)
{
    const time_t t = time(NULL);
    strftime(buf, len, "%Y-%m-%dT%H:%M:%SZ", gmtime(&t));
}

/* manifest.txt: what ran, where, when; "complete: yes" only after a full run with every scene loaded. */
static int write_manifest(const char *path, int argc, char **argv, const char *meshes, const char *started,
                          const char *load_start, const char *sections, int all_sections, int finished, double seconds)
{
    FILE *f = bench_create(path, "w");
    if (!f) return -1;
    char now[32], load[64];
    utc_now(now, sizeof now);
    bench_loadavg(load, sizeof load);
    int bad = 0;
    for (int i = 0; i < nscenes_run; ++i) bad += scenes_run[i].status != 0;
    fprintf(f, "# bench_tables manifest (bench/bench_tables.c)\ncommand:");
    for (int i = 0; i < argc; ++i) fprintf(f, " %s", argv[i]);
    fprintf(f, "\nstarted: %s\n%s: %s\n", started, finished ? "finished" : "last update (not finished)", now);
    if (finished) fprintf(f, "run time: %.0f s\n", seconds);
    bench_print_machine(f);
    fprintf(f, "threads: %d\nload average at start: %s\nload average now: %s\n", nthreads, load_start, load);
    fprintf(f, "meshes: %s (SHA-256 verified:", meshes);
    for (int i = 0; i < meshes_count; ++i) fprintf(f, " %s", meshes_known[i].file);
    fprintf(f, ")\nsections: %s%s\n", sections, all_sections ? " (all)" : " (a subset)");
    for (int i = 0; i < nscenes_run; ++i)
        fprintf(f, "scene %s: %s (%d load%s)\n", scenes_run[i].file,
                scenes_run[i].status == 0 ? "ran" : scenes_run[i].status == SCENE_MISSING ? "skipped (mesh missing)" : "failed to load",
                scenes_run[i].loads, scenes_run[i].loads > 1 ? "s" : "");
    fprintf(f, "scenes: %d ran, %d skipped or failed\n", nscenes_run - bad, bad);
    fprintf(f, "complete: %s\n", finished && all_sections && bad == 0 ? "yes" : "no");
    return fclose(f) ? -1 : 0;
}

int main(int argc, char **argv)
{
    static const struct {
        const char *name;
        void (*fn)(void);
    } all[] = {{"wu", section_wu}, {"wu-fig8", section_wu_fig8}, {"wu-fig9", section_wu_fig9}, {"wang", section_wang},
               {"annen", section_annen}, {"hvl", section_hvl}, {"sweep", section_sweep}};
    enum { NALL = sizeof all / sizeof all[0] };
    const char *outdir = "build/bench-tables", *meshes = getenv(MESHES_ENV);
    if (!meshes || !meshes[0]) meshes = MESHES_DEFAULT_DIR;
    const bench_opt opts[] = {
        {"-o", "--out", "DIR", &outdir, "output directory (default build/bench-tables)"},
        {"-m", "--meshes", "DIR", &meshes, "test meshes (default $" MESHES_ENV ", else " MESHES_DEFAULT_DIR ")"},
    };
    const bench_cli cli = {
        "bench_tables", "[-o DIR] [-m DIR] [section ...]",
        "The results tables of four papers (Wu 2020 Table 1 and Figs. 8-9, Wang 2018 Table 2, Annen 2004\n"
        "Table 1, HVL 2022 Table 1) and an accuracy-vs-time sweep, reproduced with the software-rasterized\n"
        "PRT harness on 17 scenes (bench/scenes).  About 4 minutes on an idle 2-core machine (sections:\n"
        "wu 40 s, wu-fig8 60 s, wu-fig9 20 s, wang 10 s, annen 1 s, hvl 10 s, sweep 70 s); progress on stderr.\n"
        "\n"
        "sections: wu wu-fig8 wu-fig9 wang annen hvl sweep (default: all; a subset is marked incomplete).\n"
        "\n"
        "Writes DIR/RESULTS-tables.md, DIR/tables/*.csv and DIR/manifest.txt (command, date, CPU, load\n"
        "average, which scenes ran, \"complete: yes\" for a full run).  It never writes the committed\n"
        "bench/RESULTS-tables.md or bench/tables/: `make bench-tables-accept` copies a complete run there.\n"
        "\n"
        "Needs the public test meshes cow.obj, spot.obj, stanford-bunny.obj, suzanne.obj and teapot.obj\n"
        "(public GitHub repository alecjacobson/common-3d-test-models, folder data/:\n"
        MESHES_SOURCE "), read from --meshes DIR, else $" MESHES_ENV ", else\n"
        MESHES_DEFAULT_DIR " relative to the current directory (the repository root under make).  Their\n"
        "SHA-256 are checked first; a missing or different file stops the run (exit 1) before anything\n"
        "is measured or written.  Run from the repository root (scenes are read from bench/scenes).",
        opts, (int)(sizeof opts / sizeof opts[0]), 16};
    const char *sections[16];
    const int nsec = bench_parse(&cli, argc, argv, sections);
    char sec_list[256] = "";
    for (int i = 0; i < nsec; ++i) {
        int known = 0;
        for (int k = 0; k < NALL; ++k) known |= !strcmp(sections[i], all[k].name);
        if (!known) {
            fprintf(stderr, "bench_tables: unknown section '%s' (sections: wu wu-fig8 wu-fig9 wang annen hvl sweep)\n", sections[i]);
            return 2;
        }
    }
    int nrun = 0;
    for (int k = 0; k < NALL; ++k) {
        int run = nsec == 0;
        for (int i = 0; i < nsec; ++i) run |= !strcmp(sections[i], all[k].name);
        if (!run) continue;
        ++nrun;
        snprintf(sec_list + strlen(sec_list), sizeof sec_list - strlen(sec_list), "%s%s", nrun > 1 ? " " : "", all[k].name);
    }

    char err[4096];
    if (meshes_verify(meshes, err, sizeof err)) {
        fprintf(stderr, "bench_tables: the paper scenes need the public test meshes, and these are missing or differ:\n%s"
                        "Nothing was measured or written.  Get the five OBJ files from the public GitHub repository\n"
                        "alecjacobson/common-3d-test-models, folder data/ (" MESHES_SOURCE "),\n"
                        "into one directory and pass it as --meshes DIR or " MESHES_ENV "=DIR (make bench-tables "
                        MESHES_ENV "=DIR);\nthe default is " MESHES_DEFAULT_DIR " relative to the current directory.  "
                        "Expected SHA-256 (sha256sum):\n", err);
        for (int i = 0; i < meshes_count; ++i) fprintf(stderr, "  %s  %s\n", meshes_known[i].sha256, meshes_known[i].file);
        return 1;
    }
    scene_mesh_dir = meshes;

    char md_path[1024], manifest[1024], csvs[1024], started[32], load[64];
    snprintf(md_path, sizeof md_path, "%s/RESULTS-tables.md", outdir);
    snprintf(manifest, sizeof manifest, "%s/manifest.txt", outdir);
    snprintf(csvs, sizeof csvs, "%s/tables", outdir);
    csv_dir = csvs;
    utc_now(started, sizeof started);
    bench_loadavg(load, sizeof load);
    nthreads = par_threads();
    if (bench_mkdirs(csvs)) return 1;
    DIR *old = opendir(csvs); /* CSV files of an earlier run: the directory holds this run's only */
    for (struct dirent *e; old && (e = readdir(old));) {
        const size_t n = strlen(e->d_name);
        char path[1400];
        snprintf(path, sizeof path, "%s/%s", csvs, e->d_name);
        if (n > 4 && !strcmp(e->d_name + n - 4, ".csv")) remove(path);
    }
    if (old) closedir(old);
    if (write_manifest(manifest, argc, argv, meshes, started, load, sec_list, nrun == NALL, 0, 0.0))
        return 1;
    md = bench_create(md_path, "w");
    if (!md) return 1;
    bench_progress("meshes verified in %s; writing %s, %s/*.csv, %s", meshes, md_path, csvs, manifest);
    const double t0 = bench_now();
    fprintf(md, "# The papers' results tables, reproduced with the PRT harness\n\n"
                "Generated by `make bench-tables` (bench/bench_tables.c; harness in bench/common, scenes in\n"
                "bench/scenes).  The lead merges this file into bench/RESULTS.md.\n\n");
    bench_print_machine(md);
    shl_ctx *ctx;
    shl_ctx_create(0, &ctx);
    fprintf(md, "\nThreads: %d; batch ISA: %s; load average at start: %s (a shared machine: times are minima of\n"
                "repeated runs where stated).\n", nthreads, shl_ctx_isa(ctx), load);
    shl_ctx_destroy(ctx);
    int done = 0;
    for (unsigned k = 0; k < NALL; ++k) {
        int run = nsec == 0;
        for (int i = 0; i < nsec; ++i) run |= !strcmp(sections[i], all[k].name);
        if (!run) continue;
        bench_progress("section %s (%d/%d)...", all[k].name, ++done, nrun);
        const double ts = bench_now();
        all[k].fn();
        fprintf(md, "\n(section %s: %.0f s)\n", all[k].name, bench_now() - ts);
        fflush(md);
        write_manifest(manifest, argc, argv, meshes, started, load, sec_list, nrun == NALL, 0, 0.0);
    }
    fprintf(md, "\n(total %.0f s)\n", bench_now() - t0);
    if (fclose(md)) return 1;
    if (write_manifest(manifest, argc, argv, meshes, started, load, sec_list, nrun == NALL, 1, bench_now() - t0)) return 1;
    bench_progress("done: %s (%s)", manifest, nrun == NALL ? "a full run; make bench-tables-accept copies it" : "a subset of the sections");
    return 0;
}
