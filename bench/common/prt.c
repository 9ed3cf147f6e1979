#include "prt.h"
#include "sh_basis.h"
#include "parfor.h"
#include "util.h"
#include "vec3.h"
#include "image.h"
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static void stage(prt *p, const char *name, double seconds, const char *fmt, ...)
{
    if (p->nstages == (int)(sizeof p->stage / sizeof p->stage[0])) return;
    prt_stage *st = &p->stage[p->nstages++];
    snprintf(st->name, sizeof st->name, "%s", name);
    st->seconds = seconds;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(st->note, sizeof st->note, fmt, ap);
    va_end(ap);
    if (p->report) {
        fprintf(p->report, "  stage %-28s %9.3f s  %s\n", name, seconds, st->note);
        fflush(p->report);
    }
}

/* Light geometry for display: polygon fans (one-sided ones in emit[0]) and icospheres. */
static int build_emitters(prt *p)
{
    const scene *s = p->s;
    int nv[2] = {0, 0}, nt[2] = {0, 0};
    mesh ball;
    if (mesh_sphere(&ball, 1.0, 3)) return -1;
    for (int i = 0; i < s->npolys; ++i) {
        nv[s->polys[i].two_sided] += s->polys[i].n;
        nt[s->polys[i].two_sided] += s->polys[i].n - 2;
    }
    nv[1] += s->nspheres * ball.nv;
    nt[1] += s->nspheres * ball.nt;
    int st = 0;
    for (int e = 0; e < 2 && !st; ++e) {
        st = mesh_alloc(&p->emit[e], nv[e], nt[e]);
        p->emit_rgb[e] = malloc(sizeof(float) * 3 * (size_t)(nv[e] + 1));
        if (!p->emit_rgb[e]) st = -1;
        nv[e] = nt[e] = 0;
    }
    for (int i = 0; i < s->npolys && !st; ++i) {
        const scene_polygon *q = &s->polys[i];
        mesh *m = &p->emit[q->two_sided];
        float *c = p->emit_rgb[q->two_sided];
        int *v = &nv[q->two_sided], *t = &nt[q->two_sided];
        for (int k = 1; k + 1 < q->n; ++k, ++*t) {
            const int tri[3] = {*v, *v + k, *v + k + 1};
            memcpy(m->tri + 3 * *t, tri, sizeof tri);
        }
        for (int k = 0; k < q->n; ++k, ++*v) {
            memcpy(m->pos + 3 * *v, q->v + 3 * k, sizeof(double) * 3);
            for (int ch = 0; ch < 3; ++ch) c[3 * *v + ch] = (float)q->rgb[ch];
        }
    }
    for (int i = 0; i < s->nspheres && !st; ++i) {
        const scene_sphere *sp = &s->spheres[i];
        for (int t = 0; t < ball.nt; ++t)
            for (int k = 0; k < 3; ++k) p->emit[1].tri[3 * (nt[1] + t) + k] = ball.tri[3 * t + k] + nv[1];
        for (int v = 0; v < ball.nv; ++v) {
            v3_madd(p->emit[1].pos + 3 * (nv[1] + v), sp->center, ball.pos + 3 * v, sp->radius);
            for (int ch = 0; ch < 3; ++ch) p->emit_rgb[1][3 * (nv[1] + v) + ch] = (float)sp->rgb[ch];
        }
        nv[1] += ball.nv;
        nt[1] += ball.nt;
    }
    mesh_free(&ball);
    return st;
}

int prt_init(prt *p, scene *s, int nthreads, const char *cache_dir, FILE *report)
{
    memset(p, 0, sizeof *p);
    p->s = s;
    p->nthreads = nthreads;
    p->report = report;
    const mesh *g = &s->geom;
    mesh_bounds(g, p->lo, p->hi);
    memcpy(p->cam.eye, s->eye, sizeof p->cam.eye);
    memcpy(p->cam.target, s->target, sizeof p->cam.target);
    v3_set(p->cam.up, 0, 1, 0);
    p->cam.fov_deg = s->fov_deg;
    p->vrad = malloc(sizeof(float) * 3 * (size_t)g->nv);
    p->mask = malloc((size_t)s->width * (size_t)s->height);
    if (!p->vrad || !p->mask || framebuf_init(&p->fb, s->width, s->height) || build_emitters(p)) goto fail;
    double t0 = bench_now();
    if (mesh_vertex_order(&s->geom)) goto fail;
    stage(p, "vertex order", bench_now() - t0, "%d vertices by Morton code of the position (grid cells, T and radiance in order)",
          g->nv);
    if (s->effects & (FX_SHADOWS | FX_HVL)) {
        t0 = bench_now();
        if (!(p->bvh = bvh_build(g))) goto fail;
        stage(p, "BVH build", bench_now() - t0, "%d triangles (binned SAH)", g->nt);
    }
    t0 = bench_now();
    if (s->effects & FX_SHADOWS) {
        int cached;
        if (transfer_shadowed(g, p->bvh, s->lmax, s->shadow_rays, cache_dir, nthreads, &p->T, &cached)) goto fail;
        stage(p, "transfer: shadowed diffuse", bench_now() - t0, "%d vertices x %d rays, lmax %d%s", g->nv, s->shadow_rays,
              s->lmax, cached ? " (read from the cache)" : cache_dir ? " (cached for the next run)" : "");
    } else {
        if (transfer_unshadowed(g, s->lmax, nthreads, &p->T)) goto fail;
        stage(p, "transfer: unshadowed diffuse", bench_now() - t0, "%d vertices, clamped-cosine ZH rotated to the normal",
              g->nv);
    }
    p->rm[0] = (raster_mesh){g->nv, g->nt, g->pos, g->tri, 0, NULL};
    for (int e = 0; e < 2; ++e)
        p->rm[1 + e] = (raster_mesh){p->emit[e].nv, p->emit[e].nt, p->emit[e].pos, p->emit[e].tri, e == 0, NULL};
    t0 = bench_now();
    int rnv;
    if (mesh_locality_order(g, &p->rpos, &p->rtri, &p->rtri_id, &rnv)) goto fail;
    memcpy(p->rdraw, p->rm, sizeof p->rdraw);
    p->rdraw[0] = (raster_mesh){rnv, g->nt, p->rpos, p->rtri, 0, p->rtri_id};
    stage(p, "raster order", bench_now() - t0, "%d triangles by Morton code of the centroid, vertices by first use", g->nt);
    t0 = bench_now();
    if (raster_draw(&p->fb, &p->cam, p->rdraw, 3, nthreads)) goto fail;
    raster_mask(&p->fb, 0, p->mask);
    p->raster_seconds = bench_now() - t0;
    stage(p, "rasterize (visibility)", p->raster_seconds, "%dx%d, %d + %d triangles", s->width, s->height, g->nt,
          p->emit[0].nt + p->emit[1].nt);
    if (s->effects & FX_HVL) {
        t0 = bench_now();
        if (hvl_distribute(s, p->bvh, s->hvl_lmax, &p->hvl)) goto fail;
        stage(p, "HVL distribution", bench_now() - t0, "%d HVLs (RSM rays, radius heuristic 1 x %.2g)", p->hvl.count,
              s->hvl_scale);
        t0 = bench_now();
        if (!(p->indirect = calloc(3 * (size_t)g->nv, sizeof(float))) || hvl_gather(s, &p->hvl, NULL, 0, p->indirect, nthreads))
            goto fail;
        stage(p, "HVL gather", bench_now() - t0, "%d vertices x %d HVLs, %d emission / %d convolution bands", g->nv,
              p->hvl.count, s->hvl_lmax + 1, s->hvl_lmax + 1);
    }
    return 0;
fail:
    prt_free(p);
    return -1;
}

void prt_free(prt *p)
{
    bvh_free(p->bvh);
    transfer_free(&p->T);
    for (int e = 0; e < 2; ++e) {
        mesh_free(&p->emit[e]);
        free(p->emit_rgb[e]);
    }
    framebuf_free(&p->fb);
    free(p->rpos);
    free(p->rtri);
    free(p->rtri_id);
    hvl_free(&p->hvl);
    free(p->mask);
    free(p->indirect);
    free(p->vrad);
    memset(p, 0, sizeof *p);
}

void prt_print_stages(const prt *p, FILE *out)
{
    fprintf(out, "| precomputation stage | time (s) | detail |\n|---|---|---|\n");
    for (int i = 0; i < p->nstages; ++i)
        fprintf(out, "| %s | %.3f | %s |\n", p->stage[i].name, p->stage[i].seconds, p->stage[i].note);
    const int fx = p->s->effects;
    if (!(fx & FX_SHADOWS)) fprintf(out, "| (skipped) visibility ray casting | - | scene does not call for `shadows` |\n");
    if (!(fx & FX_GLOSSY)) fprintf(out, "| (skipped) view-dependent glossy transfer | - | scene does not call for `glossy` |\n");
    if (!(fx & FX_HVL)) fprintf(out, "| (skipped) HVL pass | - | scene does not call for `hvl-indirect` |\n");
}

typedef struct {
    const prt *p;
    const int *subset;
    int ncl, lmax, glossy;
    const float *lobe; /* per material: the glossy lobe's ZH times sqrt(4 pi / (2l + 1)), l <= lmax: the weights
                          of Y_lm(r) in its SH (HVL Eq. 15) */
} shade_job;

/* s[c] = sum_k L[c ncl + k] y[k], k < n, for the 3 colours c, in float with 4 partial sums per
 * colour (k mod 4; the last n mod 4 terms go to the first): gcc -O2 runs each colour's 4 in one SSE
 * register, a quarter of the additions and no chain of n dependent ones.  Error: at most about
 * (n / 4 + 3) 2^-24 sum_k |L y| (float products and sums). */
static void dot3(const float *L, int ncl, const float *y, int n, float s[3])
{
    for (int c = 0; c < 3; ++c, L += ncl) {
        float a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f;
        int k = 0;
        for (; k + 4 <= n; k += 4) {
            a0 += L[k] * y[k];
            a1 += L[k + 1] * y[k + 1];
            a2 += L[k + 2] * y[k + 2];
            a3 += L[k + 3] * y[k + 3];
        }
        for (; k < n; ++k) a0 += L[k] * y[k];
        s[c] = (a0 + a1) + (a2 + a3);
    }
}

/* Shades points [begin, end) from their coefficients coef (lighting_eval's consumer). */
static void shade_block(void *arg, int worker, long begin, long end, const float *coef)
{
    (void)worker;
    const shade_job *j = arg;
    const prt *p = j->p;
    const scene *s = p->s;
    const int ncl = j->ncl, nct = p->T.nc, nc = ncl < nct ? ncl : nct;
    for (long i = begin; i < end; ++i) {
        const long v = j->subset ? j->subset[i] : i;
        const scene_material *mt = &s->mats[s->geom.mat[v]];
        const float *L = coef + (size_t)(i - begin) * 3 * ncl, *T = p->T.t + (size_t)v * nct;
        float *out = p->vrad + 3 * v;
        float dif[3];
        dot3(L, ncl, T, nc, dif);
        for (int c = 0; c < 3; ++c) out[c] = (float)(mt->albedo[c] * dif[c]);
        if (j->glossy && mt->kind != MAT_DIFFUSE) {
            const double *x = s->geom.pos + 3 * v, *n = s->geom.nrm + 3 * v;
            double d[3], r[3];
            v3_sub(d, p->cam.eye, x);
            const double nd = v3_dot(n, d);
            if (nd > 0) { /* r: the mirror direction of the view, 2 (n . wo) n - wo with wo = d / |d| */
                v3_scale(r, n, 2 * nd);
                v3_sub(r, r, d);
                v3_normalize(r);
                const float u[3] = {(float)r[0], (float)r[1], (float)r[2]};
                float y[SHL_NCOEFFS(SHL_LMAX_MAX)], g[3];
                shl__sh_eval_w_f(j->lmax, u, j->lobe + (size_t)s->geom.mat[v] * (SHL_LMAX_MAX + 1), y);
                dot3(L, ncl, y, ncl, g);
                for (int c = 0; c < 3; ++c) out[c] += (float)(mt->ks * g[c]);
            }
        }
        if (p->indirect)
            for (int ch = 0; ch < 3; ++ch) out[ch] += p->indirect[3 * v + ch];
    }
}

int prt_render(prt *p, const lighting_method *m, const int *subset, long nsub, float *img, prt_times *t)
{
    const scene *s = p->s;
    const long n = subset ? nsub : s->geom.nv;
    const int ncl = SHL_NCOEFFS(m->lmax);
    double *pts = NULL;
    float *lobe = NULL;
    lighting *L = NULL;
    int st = -1;
    if (subset) {
        if (!(pts = malloc(sizeof(double) * 3 * (size_t)(n + 1)))) return -1;
        for (long i = 0; i < n; ++i) memcpy(pts + 3 * i, s->geom.pos + 3 * (size_t)subset[i], sizeof(double) * 3);
        memset(p->vrad, 0, sizeof(float) * 3 * (size_t)s->geom.nv);
    }
    const int glossy = (s->effects & FX_GLOSSY) != 0;
    if (!(lobe = calloc((size_t)s->nmats * (SHL_LMAX_MAX + 1), sizeof(float)))) goto done;
    for (int i = 0; glossy && i < s->nmats; ++i) {
        const scene_material *mt = &s->mats[i];
        double z[SHL_LMAX_MAX + 1];
        if (mt->kind == MAT_PHONG && shl_zh_phong(m->lmax, mt->exponent, z) != SHL_OK) goto done;
        if (mt->kind == MAT_GGX && shl_zh_ggx(m->lmax, mt->alpha, z) != SHL_OK) goto done;
        for (int l = 0; mt->kind != MAT_DIFFUSE && l <= m->lmax; ++l)
            lobe[(size_t)i * (SHL_LMAX_MAX + 1) + l] = (float)(shl__sh_k15_d[l] * z[l]);
    }
    if (!(L = lighting_prepare(s, m, p->lo, p->hi, p->nthreads, &t->prepare))) goto done;
    /* Lighting and shading fused per block of LIGHTING_BLOCK vertices (the coefficients stay in
     * cache); their wall time is split between the two by the workers' time in each. */
    double t0 = bench_now(), share;
    shade_job j = {p, subset, ncl, m->lmax, glossy, lobe};
    if (lighting_eval(L, n, subset ? pts : s->geom.pos, p->nthreads, shade_block, &j, &share)) goto done;
    const double wall = bench_now() - t0;
    t->lighting = wall * share;
    t->shade = wall - t->lighting;
    t0 = bench_now();
    const float *colors[3] = {p->vrad, p->emit_rgb[0], p->emit_rgb[1]};
    raster_resolve(&p->fb, p->rm, colors, img, p->nthreads);
    t->resolve = bench_now() - t0;
    st = 0;
done:
    lighting_free(L);
    free(pts);
    free(lobe);
    return st;
}

long prt_visible_vertices(const prt *p, int *idx)
{
    const int nv = p->s->geom.nv;
    unsigned char *used = calloc((size_t)nv + 1, 1);
    if (!used) return -1;
    for (size_t q = 0; q < (size_t)p->fb.w * (size_t)p->fb.h; ++q)
        if (p->fb.mesh[q] == 0)
            for (int k = 0; k < 3; ++k) used[p->s->geom.tri[3 * (size_t)p->fb.tri[q] + k]] = 1;
    long n = 0;
    for (int v = 0; v < nv; ++v)
        if (used[v]) idx[n++] = v;
    free(used);
    return n;
}

double prt_exposure(const prt *p, const float *img)
{
    return p->s->exposure > 0 ? p->s->exposure : image_auto_exposure(p->fb.w, p->fb.h, img, p->mask);
}
