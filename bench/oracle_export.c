/* Export of a harness scene for the image check of the Mitsuba oracle (tools/oracle_images.py).
 *   usage: oracle_export <scene-file> <out-dir> <width> <height> <lmax> [<lmax> ...]
 * Renders the scene with the PRT harness (per-vertex analytic lighting, unshadowed diffuse
 * transfer, the software raster) at each lmax, and writes to out-dir:
 *   scene.json          camera, image size, polygon lights, mesh sizes, PRT times
 *   mesh.bin            receivers: float64 positions (3 nv), normals (3 nv), face albedo (3 nt);
 *                       int32 triangles (3 nt) -- counter-clockwise about the normals
 *   pixel_tri.bin       int32 per pixel: receiver triangle seen at the pixel centre, -1 otherwise
 *   prt_<lmax>.bin      float32 rgb per pixel: the PRT render (linear radiance, rows top to bottom)
 *   vertex_<lmax>.bin   float32 rgb per receiver vertex: the radiance the render interpolates
 *   lambert_vertices.bin  float32 rgb per vertex: exact radiance albedo/pi * E (Lambert's closed form)
 *   lambert_vertex.bin  float32 rgb per pixel: lambert_vertices resolved through the same raster
 *                       (the render at lmax = infinity)
 *   lambert_pixel.bin   float32 rgb: the same closed form evaluated at each pixel's own point and
 *                       normalized interpolated normal (what a ray tracer shading per pixel computes)
 * Only scenes of uniform polygon lights with `effects direct` are accepted: the exact references
 * and the oracle's integrator are unshadowed. */
#include "lambert.h"
#include "parfor.h"
#include "prt.h"
#include "util.h"
#include "vec3.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void json_vec(FILE *f, const double *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; ++i) fprintf(f, "%s%.17g", i ? ", " : "", v[i]);
    fputc(']', f);
}

/* Lambert's closed form per pixel at the raster's interpolated point and normal. */
static void lambert_pixels(const prt *p, float *img)
{
    const scene *s = p->s;
    const mesh *g = &s->geom;
    for (size_t q = 0; q < (size_t)p->fb.w * (size_t)p->fb.h; ++q) {
        float *o = img + 3 * q;
        o[0] = o[1] = o[2] = 0.0f;
        if (p->fb.mesh[q] != 0) continue;
        const int *t = g->tri + 3 * (size_t)p->fb.tri[q];
        double x[3] = {0, 0, 0}, n[3] = {0, 0, 0}, e[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            v3_madd(x, x, g->pos + 3 * (size_t)t[k], p->fb.bary[3 * q + k]);
            v3_madd(n, n, g->nrm + 3 * (size_t)t[k], p->fb.bary[3 * q + k]);
        }
        v3_normalize(n);
        for (int j = 0; j < s->npolys; ++j)
            if (lambert_lit(&s->polys[j], x)) {
                const double irr = lambert_irradiance(s->polys[j].v, s->polys[j].n, x, n);
                for (int c = 0; c < 3; ++c) e[c] += s->polys[j].rgb[c] * irr;
            }
        const double *alb = s->mats[g->mat[t[0]]].albedo;
        for (int c = 0; c < 3; ++c) o[c] = (float)(alb[c] / M_PI * e[c]);
    }
}

int main(int argc, char **argv)
{
    const char *args[36];
    const bench_cli cli = {
        "oracle_export", "scene-file out-dir width height lmax [lmax ...]",
        "Exports a harness scene for the image check of the Mitsuba oracle (tools/oracle_images.py, run by\n"
        "make oracle / oracle-check): renders it with the PRT harness (per-vertex analytic lighting,\n"
        "unshadowed diffuse transfer) at width x height for each lmax (0..30, up to 32 values) and writes\n"
        "scene.json, mesh.bin, pixel_tri.bin, prt_<lmax>.bin, vertex_<lmax>.bin and the Lambert\n"
        "references lambert_*.bin into out-dir (created if needed; formats: bench/oracle_export.c).\n"
        "Only scenes of polygon lights with `effects direct`.  Seconds for the small oracle scenes on a\n"
        "2-core machine; a progress line per lmax on stderr.",
        NULL, 0, 36};
    const int nargs = bench_parse(&cli, argc, argv, args);
    if (nargs < 5) {
        fprintf(stderr, "oracle_export: needs a scene file, an output directory, width, height and at least one lmax "
                        "(--help)\n");
        return 2;
    }
    const char *dir = args[1];
    int num[35], lmaxes[32], lmax_hi = 0;
    const int nl = nargs - 4;
    for (int i = 2; i < nargs; ++i) {
        char *end;
        const long v = strtol(args[i], &end, 10);
        if (*end || v < 0 || v > 1 << 16) return fprintf(stderr, "oracle_export: bad number '%s'\n", args[i]), 2;
        num[i - 2] = (int)v;
    }
    const int w = num[0], h = num[1];
    for (int i = 0; i < nl; ++i) {
        lmaxes[i] = num[2 + i];
        if (lmaxes[i] > SHL_LMAX_MAX) return fprintf(stderr, "oracle_export: bad lmax %d\n", lmaxes[i]), 2;
        if (lmaxes[i] > lmax_hi) lmax_hi = lmaxes[i];
    }
    if (w < 1 || h < 1) return fprintf(stderr, "oracle_export: bad image size\n"), 2;
    if (bench_mkdirs(dir)) return fprintf(stderr, "oracle_export: cannot create %s\n", dir), 1;
    scene s;
    char err[1024];
    if (scene_load(args[0], &s, err, sizeof err)) return fprintf(stderr, "oracle_export: %s\n", err), 1;
    if (s.effects != FX_DIRECT || s.nspheres > 0) {
        fprintf(stderr, "oracle_export: %s: only polygon lights and `effects direct` are supported\n", args[0]);
        scene_free(&s);
        return 1;
    }
    s.width = w;
    s.height = h;
    s.lmax = lmax_hi; /* transfer at the highest lmax; each render truncates the lighting */
    prt p;
    if (prt_init(&p, &s, par_threads(), NULL, NULL)) return fprintf(stderr, "oracle_export: out of memory\n"), 1;
    const mesh *g = &s.geom;
    const size_t npix = (size_t)w * (size_t)h;
    float *img = malloc(sizeof(float) * 3 * npix);
    float *vrad = malloc(sizeof(float) * 3 * (size_t)g->nv);
    double *alb = malloc(sizeof(double) * 3 * (size_t)g->nt);
    int *ptri = malloc(sizeof(int) * npix);
    double secs[32];
    int st = !img || !vrad || !alb || !ptri;
    for (int i = 0; i < nl && !st; ++i) {
        lighting_method m;
        prt_times t;
        char name[32];
        memset(&m, 0, sizeof m);
        bench_progress("rendering at lmax %d (%d/%d)...", lmaxes[i], i + 1, nl);
        m.kind = LM_ANALYTIC;
        m.lmax = lmaxes[i];
        st = prt_render(&p, &m, NULL, 0, img, &t);
        secs[i] = t.prepare + t.lighting + t.shade + t.resolve;
        snprintf(name, sizeof name, "prt_%d.bin", lmaxes[i]);
        st = st || bench_write_binary(dir, name, img, sizeof(float), 3 * npix);
        snprintf(name, sizeof name, "vertex_%d.bin", lmaxes[i]);
        st = st || bench_write_binary(dir, name, p.vrad, sizeof(float), 3 * (size_t)g->nv);
    }
    if (!st) {
        const float *colors[3] = {vrad, p.emit_rgb[0], p.emit_rgb[1]};
        lambert_scene(&s, vrad);
        st = bench_write_binary(dir, "lambert_vertices.bin", vrad, sizeof(float), 3 * (size_t)g->nv);
        raster_resolve(&p.fb, p.rm, colors, img, p.nthreads);
        st = st || bench_write_binary(dir, "lambert_vertex.bin", img, sizeof(float), 3 * npix);
        lambert_pixels(&p, img);
        st = st || bench_write_binary(dir, "lambert_pixel.bin", img, sizeof(float), 3 * npix);
        for (size_t q = 0; q < npix; ++q) ptri[q] = p.fb.mesh[q] == 0 ? p.fb.tri[q] : -1;
        st = st || bench_write_binary(dir, "pixel_tri.bin", ptri, sizeof(int), npix);
        for (int t = 0; t < g->nt; ++t) memcpy(alb + 3 * t, s.mats[g->mat[g->tri[3 * t]]].albedo, sizeof(double) * 3);
        st = mesh_write_oracle(g, alb, dir, "mesh.bin") || st;
    }
    if (!st) {
        char path[1024];
        snprintf(path, sizeof path, "%s/scene.json", dir);
        FILE *f = fopen(path, "w");
        st = !f;
        if (f) {
            fprintf(f, "{\"name\": \"%s\", \"width\": %d, \"height\": %d, \"nv\": %d, \"nt\": %d, \"threads\": %d,\n",
                    s.name, w, h, g->nv, g->nt, p.nthreads);
            fprintf(f, " \"eye\": ");
            json_vec(f, s.eye, 3);
            fprintf(f, ", \"target\": ");
            json_vec(f, s.target, 3);
            fprintf(f, ", \"fov_deg\": %.17g,\n \"prt\": [", s.fov_deg);
            for (int i = 0; i < nl; ++i) fprintf(f, "%s{\"lmax\": %d, \"seconds\": %.6g}", i ? ", " : "", lmaxes[i], secs[i]);
            fprintf(f, "],\n \"polygons\": [");
            for (int j = 0; j < s.npolys; ++j) {
                fprintf(f, "%s\n  {\"two_sided\": %d, \"rgb\": ", j ? "," : "", s.polys[j].two_sided);
                json_vec(f, s.polys[j].rgb, 3);
                fprintf(f, ", \"v\": ");
                json_vec(f, s.polys[j].v, 3 * s.polys[j].n);
                fputc('}', f);
            }
            fprintf(f, "]}\n");
            st = fclose(f) != 0;
        }
    }
    if (st) fprintf(stderr, "oracle_export: could not write to %s\n", dir);
    free(img);
    free(vrad);
    free(alb);
    free(ptri);
    prt_free(&p);
    scene_free(&s);
    return st ? 1 : 0;
}
