#include "lighting.h"
#include "monomial.h"
#include "parfor.h"
#include "util.h"
#include "vec3.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct lighting {
    lighting_method m;
    const scene *s;
    int lmax, nc;
    shl_ctx *ctx;
    shl_lights *set;
    shl_grid *grid;
    shl_agrid *agrid;
    double *sample;               /* SINGLE / TAYLOR1: per sample 3 nc values, then 9 nc gradients */
    int nsamples;
    double (*normal)[3];          /* per polygon: unit normal (one-sided: the emitting side) */
    double *area;                 /* per polygon */
    double *cdf;                  /* MC light selection: polygons, then spheres */
};

const char *lighting_name(const lighting_method *m, char *buf, size_t len)
{
    static const char *interp[3] = {"trilinear", "Taylor", "Hermite"};
    switch (m->kind) {
    case LM_ANALYTIC: snprintf(buf, len, "per-vertex analytic (double)"); break;
    case LM_ANALYTIC_F: snprintf(buf, len, "per-vertex analytic (float SIMD)"); break;
    case LM_GRID:
        snprintf(buf, len, "grid %d^3 %s%s", m->grid_res, interp[m->interp],
                 m->grid_storage == SHL_GRID_DOUBLE ? " (double)" : "");
        break;
    case LM_AGRID:
        snprintf(buf, len, "adaptive grid %d^3 %s tol %.3g, %ld nodes", m->grid_res,
                 m->agrid_criterion == SHL_AGRID_MEAN ? "mean" : "max", m->agrid_tol, m->agrid_budget);
        break;
    case LM_MC: snprintf(buf, len, "Monte Carlo %ld samples", m->mc_samples); break;
    case LM_MONOMIAL: snprintf(buf, len, "per-vertex monomial baseline"); break;
    case LM_SINGLE: snprintf(buf, len, "single sample"); break;
    case LM_TAYLOR1: snprintf(buf, len, "single sample + gradient"); break;
    }
    return buf;
}

/* rgb (3 nc) += the spherical lights at x (the paths that do not go through the light set). */
static int add_spheres(const lighting *L, const double x[3], double *rgb)
{
    double c[SHL_NCOEFFS(SHL_LMAX_MAX)];
    const int nc = L->nc;
    for (int i = 0; i < L->s->nspheres; ++i) {
        const scene_sphere *sp = &L->s->spheres[i];
        if (shl_sphere(L->ctx, x, sp->center, sp->radius, c) != SHL_OK) return -1;
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < nc; ++k) rgb[ch * nc + k] += sp->rgb[ch] * c[k];
    }
    return 0;
}

static int lit_side(const lighting *L, int i, const double x[3])
{
    const scene_polygon *p = &L->s->polys[i];
    double d[3];
    v3_sub(d, x, p->v);
    return p->two_sided || v3_dot(L->normal[i], d) > 0;
}

lighting *lighting_prepare(const scene *s, const lighting_method *m, const double lo_in[3], const double hi_in[3],
                           int nthreads, double *fill_seconds)
{
    lighting *L = calloc(1, sizeof *L);
    if (!L) return NULL;
    L->m = *m;
    L->s = s;
    L->lmax = m->lmax;
    L->nc = SHL_NCOEFFS(m->lmax);
    *fill_seconds = 0.0;
    const int np = s->npolys;
    L->normal = malloc(sizeof *L->normal * (size_t)(np + 1));
    L->area = malloc(sizeof *L->area * (size_t)(np + 1));
    L->cdf = malloc(sizeof *L->cdf * (size_t)(np + s->nspheres + 1));
    if (!L->normal || !L->area || !L->cdf || shl_ctx_create(m->lmax, &L->ctx) != SHL_OK || !(L->set = scene_light_set(s)))
        goto fail;
    double total = 0.0;
    for (int i = 0; i < np; ++i) {
        const scene_polygon *p = &s->polys[i];
        double nrm[3] = {0, 0, 0};
        for (int k = 1; k + 1 < p->n; ++k) { /* Newell normal as a fan, as the library's one-sided test */
            double e1[3], e2[3], c[3];
            v3_sub(e1, p->v + 3 * k, p->v);
            v3_sub(e2, p->v + 3 * (k + 1), p->v);
            v3_cross(c, e1, e2);
            v3_add(nrm, nrm, c);
        }
        L->area[i] = 0.5 * v3_normalize(nrm);
        memcpy(L->normal[i], nrm, sizeof nrm);
        const double lum = 0.2126 * fabs(p->rgb[0]) + 0.7152 * fabs(p->rgb[1]) + 0.0722 * fabs(p->rgb[2]);
        total += lum * L->area[i] * (p->two_sided ? 2 : 1) + 1e-300;
        L->cdf[i] = total;
    }
    for (int i = 0; i < s->nspheres; ++i) {
        const scene_sphere *sp = &s->spheres[i];
        const double lum = 0.2126 * fabs(sp->rgb[0]) + 0.7152 * fabs(sp->rgb[1]) + 0.0722 * fabs(sp->rgb[2]);
        total += lum * 4 * M_PI * sp->radius * sp->radius + 1e-300;
        L->cdf[np + i] = total;
    }
    const double t0 = bench_now();
    if (m->kind == LM_GRID || m->kind == LM_AGRID) {
        double lo[3], hi[3];
        for (int a = 0; a < 3; ++a) { /* a flat receiver set still needs a box */
            const double pad = hi_in[a] - lo_in[a] > 1e-9 ? 0.0 : 1e-6 + 1e-6 * fabs(lo_in[a]);
            lo[a] = lo_in[a] - pad;
            hi[a] = hi_in[a] + pad;
        }
        const int res[3] = {m->grid_res, m->grid_res, m->grid_res};
        if (m->kind == LM_AGRID ? shl_agrid_create(L->ctx, lo, hi, res, m->agrid_criterion, m->agrid_tol, m->agrid_budget,
                                                   &L->agrid) != SHL_OK ||
                                      shl_agrid_set_weighted_receivers(L->agrid, m->agrid_receivers ? m->agrid_nreceivers : 0,
                                                                       m->agrid_receivers, m->agrid_receiver_weights) != SHL_OK ||
                                      shl_agrid_fill(L->agrid, L->set, nthreads) != SHL_OK
                                : shl_grid_create(L->ctx, lo, hi, res, m->grid_storage, &L->grid) != SHL_OK ||
                                      shl_grid_fill(L->grid, L->set, nthreads) != SHL_OK)
            goto fail;
    } else if (m->kind == LM_SINGLE || m->kind == LM_TAYLOR1) {
        L->nsamples = m->npoints > 1 ? m->npoints : 1;
        if (L->nsamples > LIGHTING_MAX_SAMPLES) goto fail;
        L->sample = calloc(12 * (size_t)L->nc * (size_t)L->nsamples, sizeof(double));
        if (!L->sample) goto fail;
        for (int j = 0; j < L->nsamples; ++j) {
            double *c = L->sample + 12 * (size_t)L->nc * (size_t)j;
            if (shl_lights_eval(L->ctx, L->set, m->point[j], c, c + 3 * L->nc) != SHL_OK) goto fail;
        }
    } else if (m->kind == LM_MONOMIAL) {
        /* the baseline fills its Legendre table on first use: do it before any thread runs */
        shl__poly_geom g;
        double zh[SHL__ZH_BLOCK];
        const double x[3] = {0, 0, 0}, tri[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1};
        shl__poly_geom_init(&g, x, tri, 3);
        monomial_poly_zh(&g, m->lmax, zh);
    }
    *fill_seconds = bench_now() - t0;
    return L;
fail:
    lighting_free(L);
    return NULL;
}

void lighting_free(lighting *L)
{
    if (!L) return;
    shl_grid_destroy(L->grid);
    shl_agrid_destroy(L->agrid);
    shl_lights_destroy(L->set);
    shl_ctx_destroy(L->ctx);
    free(L->sample);
    free(L->normal);
    free(L->area);
    free(L->cdf);
    free(L);
}

enum { BLOCK = LIGHTING_BLOCK };

typedef struct {
    const lighting *L;
    const double *pts;
    lighting_consumer consume;
    void *arg;
    par_progress *prog;
    double *out, *acc; /* per worker: 3 nc BLOCK outputs, 3 SHL__ZH_BLOCK accumulators */
    float *pf, *coef;  /* per worker: 3 BLOCK float positions, 3 nc BLOCK coefficients */
    int failed[SHL_MAX_THREADS]; /* per worker */
    double t_eval[SHL_MAX_THREADS], t_consume[SHL_MAX_THREADS]; /* per worker, seconds */
} eval_job;

static uint64_t mix64(uint64_t x)
{
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

static double next01(uint64_t *s) { return (double)(mix64(*s += 0x9E3779B97F4A7C15ull) >> 11) * 0x1.0p-53; }

/* Monte Carlo estimate at x into rgb (3 nc); point index p seeds the generator. */
static void monte_carlo(const lighting *L, long p, const double x[3], double *rgb)
{
    const scene *s = L->s;
    const int np = s->npolys, nl = np + s->nspheres, nc = L->nc;
    const long N = L->m.mc_samples;
    const double total = L->cdf[nl - 1];
    uint64_t st = mix64((uint64_t)p * 0x632BE59BD9B4E019ull + 1);
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)];
    memset(rgb, 0, sizeof(double) * 3 * (size_t)nc);
    for (long i = 0; i < N; ++i) {
        const double u = (i + next01(&st)) / (double)N * total; /* stratified light selection */
        int lo = 0, hi = nl - 1;
        while (lo < hi) {
            const int mid = (lo + hi) / 2;
            if (L->cdf[mid] <= u) lo = mid + 1;
            else hi = mid;
        }
        const double prob = (L->cdf[lo] - (lo ? L->cdf[lo - 1] : 0.0)) / total;
        double w[3], f;
        const double *rad;
        if (lo < np) {
            const scene_polygon *q = &s->polys[lo];
            rad = q->rgb;
            if (!lit_side(L, lo, x)) continue;
            double pick = next01(&st) * L->area[lo], a = next01(&st), b = next01(&st), e1[3], e2[3], c[3], y0[3];
            int k = 1;
            for (; k + 2 < q->n; ++k) { /* fan triangle by area */
                v3_sub(e1, q->v + 3 * k, q->v);
                v3_sub(e2, q->v + 3 * (k + 1), q->v);
                v3_cross(c, e1, e2);
                if (pick < 0.5 * v3_len(c)) break;
                pick -= 0.5 * v3_len(c);
            }
            if (a + b > 1) {
                a = 1 - a;
                b = 1 - b;
            }
            v3_sub(e1, q->v + 3 * k, q->v);
            v3_sub(e2, q->v + 3 * (k + 1), q->v);
            for (int j = 0; j < 3; ++j) y0[j] = q->v[j] + a * e1[j] + b * e2[j] - x[j];
            const double r2 = v3_dot(y0, y0);
            if (!(r2 > 0)) continue;
            v3_scale(w, y0, 1.0 / sqrt(r2));
            const double cosl = fabs(v3_dot(w, L->normal[lo]));
            f = L->area[lo] * cosl / r2 / prob;
        } else {
            const scene_sphere *sp = &s->spheres[lo - np];
            rad = sp->rgb;
            double axis[3], t[3], b[3];
            v3_sub(axis, sp->center, x);
            const double dist = v3_normalize(axis), u1 = next01(&st), u2 = next01(&st);
            const double cosa = dist > sp->radius ? sqrt(1.0 - (sp->radius / dist) * (sp->radius / dist)) : -1.0;
            const double z = 1.0 - u1 * (1.0 - cosa), r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2 * M_PI * u2;
            v3_basis(axis, t, b);
            for (int j = 0; j < 3; ++j) w[j] = r * cos(phi) * t[j] + r * sin(phi) * b[j] + z * axis[j];
            f = 2 * M_PI * (1.0 - cosa) / prob;
        }
        shl_eval_basis(L->lmax, w, y);
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < nc; ++k) rgb[ch * nc + k] += rad[ch] * f * y[k];
    }
    for (int k = 0; k < 3 * nc; ++k) rgb[k] /= (double)N;
}

/* Stratified Monte Carlo at x (polygon lights): each fan triangle t of each lit light gets
 * k_t^2 ~ N x its share of the power, jittered strata of the unit square mapped onto the triangle
 * by the area-preserving (u, v) -> (1 - sqrt u) A + sqrt u (1 - v) B + sqrt u v C; estimate
 * area_t / k_t^2 sum L cos_l Y(w) / r^2 (the integrand is smooth over a light, so the error falls
 * about as N^-1 instead of N^-1/2). */
static void monte_carlo_stratified(const lighting *L, long p, const double x[3], double *rgb)
{
    const scene *s = L->s;
    const int nc = L->nc;
    const double total = L->cdf[s->npolys + s->nspheres - 1];
    uint64_t st = mix64((uint64_t)p * 0x632BE59BD9B4E019ull + 1);
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)];
    memset(rgb, 0, sizeof(double) * 3 * (size_t)nc);
    for (int j = 0; j < s->npolys; ++j) {
        const scene_polygon *q = &s->polys[j];
        if (!lit_side(L, j, x)) continue;
        const double share = (L->cdf[j] - (j ? L->cdf[j - 1] : 0.0)) / total;
        for (int t = 1; t + 1 < q->n; ++t) {
            double e1[3], e2[3], c[3];
            v3_sub(e1, q->v + 3 * t, q->v);
            v3_sub(e2, q->v + 3 * (t + 1), q->v);
            v3_cross(c, e1, e2);
            const double area = 0.5 * v3_len(c);
            const int k = (int)fmax(1.0, ceil(sqrt((double)L->m.mc_samples * share * area / L->area[j])));
            double acc[SHL_NCOEFFS(SHL_LMAX_MAX)];
            memset(acc, 0, sizeof(double) * (size_t)nc);
            for (int a = 0; a < k; ++a)
                for (int b = 0; b < k; ++b) {
                    const double u = (a + next01(&st)) / k, v = (b + next01(&st)) / k, su = sqrt(u);
                    double w[3];
                    for (int i = 0; i < 3; ++i) w[i] = q->v[i] + su * (1 - v) * e1[i] + su * v * e2[i] - x[i];
                    const double r2 = v3_dot(w, w);
                    if (!(r2 > 0)) continue;
                    v3_scale(w, w, 1.0 / sqrt(r2));
                    const double f = fabs(v3_dot(w, L->normal[j])) / r2;
                    shl_eval_basis(L->lmax, w, y);
                    for (int i = 0; i < nc; ++i) acc[i] += f * y[i];
                }
            for (int ch = 0; ch < 3; ++ch)
                for (int i = 0; i < nc; ++i) rgb[ch * nc + i] += q->rgb[ch] * area / (k * k) * acc[i];
        }
    }
}

/* Monomial-moment ZH per light, accumulated per colour, one reconstruction per colour (as lights.c). */
static void monomial(const lighting *L, const double x[3], double *rgb, double *acc)
{
    const int lmax = L->lmax, nc = L->nc;
    double zh[SHL__ZH_BLOCK];
    shl__poly_geom g;
    memset(acc, 0, sizeof(double) * 3 * SHL__ZH_BLOCK);
    for (int i = 0; i < L->s->npolys; ++i) {
        if (!lit_side(L, i, x)) continue;
        const scene_polygon *q = &L->s->polys[i];
        shl__poly_geom_init(&g, x, q->v, q->n);
        monomial_poly_zh(&g, lmax, zh);
        for (int ch = 0; ch < 3; ++ch)
            for (int d = 0; d <= 2 * lmax; ++d)
                for (int l = 0; l <= lmax; ++l)
                    acc[ch * SHL__ZH_BLOCK + d * SHL__ZH_STRIDE + l] += q->rgb[ch] * zh[d * SHL__ZH_STRIDE + l];
    }
    for (int ch = 0; ch < 3; ++ch) shl__zh_to_sh(lmax, acc + ch * SHL__ZH_BLOCK, rgb + ch * nc);
}

static void eval_block(void *arg, int worker, long begin, long end)
{
    eval_job *j = arg;
    const lighting *L = j->L;
    const int nc = L->nc, nb = (int)(end - begin);
    const double *pts = j->pts + 3 * begin;
    double *out = j->out + 3 * (size_t)nc * BLOCK * (size_t)worker, *acc = j->acc + 3 * SHL__ZH_BLOCK * (size_t)worker;
    float *pf = j->pf + 3 * BLOCK * (size_t)worker, *coef = j->coef + 3 * (size_t)nc * BLOCK * (size_t)worker;
    const double t0 = bench_now();
    switch (L->m.kind) {
    case LM_ANALYTIC:
        if (shl_lights_eval_batch(L->ctx, L->set, nb, pts, out, NULL) != SHL_OK) goto fail;
        break;
    case LM_ANALYTIC_F: /* the set in float through the SIMD kernels, straight into coef */
        for (int k = 0; k < 3 * nb; ++k) pf[k] = (float)pts[k];
        if (shl_lights_eval_batch_f(L->ctx, L->set, nb, pf, coef, NULL) != SHL_OK)
            goto fail;
        break;
    case LM_GRID:
        if (L->m.grid_storage == SHL_GRID_FLOAT) { /* float sums, straight into coef (shl_grid_interp_f) */
            for (int k = 0; k < 3 * nb; ++k) pf[k] = (float)pts[k];
            if (shl_grid_interp_f(L->grid, L->m.interp, L->m.taylor_b, nb, pf, coef, 1) != SHL_OK) goto fail;
        } else if (shl_grid_interp(L->grid, L->m.interp, L->m.taylor_b, nb, pts, out, 1) != SHL_OK)
            goto fail;
        break;
    case LM_AGRID:
        if (shl_agrid_interp(L->agrid, nb, pts, out, 1) != SHL_OK) goto fail;
        break;
    case LM_MC:
        for (int p = 0; p < nb; ++p)
            (L->m.mc_stratified && L->s->nspheres == 0 ? monte_carlo_stratified : monte_carlo)(L, begin + p, pts + 3 * p,
                                                                                              out + 3 * (size_t)nc * p);
        break;
    case LM_MONOMIAL:
        for (int p = 0; p < nb; ++p) {
            monomial(L, pts + 3 * p, out + 3 * (size_t)nc * p, acc);
            if (add_spheres(L, pts + 3 * p, out + 3 * (size_t)nc * p)) goto fail;
        }
        break;
    case LM_SINGLE:
    case LM_TAYLOR1:
        for (int p = 0; p < nb; ++p) {
            const double *x = pts + 3 * p;
            double w[LIGHTING_MAX_SAMPLES], wsum = 0.0;
            int at = -1; /* a vertex on (or within overflow of) a sample takes it alone: the limit of Eq. 16 */
            for (int j = 0; j < L->nsamples; ++j) {
                double d[3];
                v3_sub(d, x, L->m.point[j]);
                const double r = v3_len(d);
                w[j] = L->nsamples == 1 ? 1.0 : pow(r, -L->m.taylor_b); /* Annen Eq. 16 */
                if (!isfinite(w[j])) at = j;
                else wsum += w[j];
            }
            for (int j = 0; j < L->nsamples; ++j) w[j] = at >= 0 ? (j == at) : w[j] / wsum;
            for (int k = 0; k < 3 * nc; ++k) out[3 * (size_t)nc * p + k] = 0.0;
            for (int j = 0; j < L->nsamples; ++j) {
                if (w[j] == 0.0) continue;
                const double *c = L->sample + 12 * (size_t)nc * (size_t)j, *g = c + 3 * nc;
                for (int ch = 0; ch < 3; ++ch)
                    for (int k = 0; k < nc; ++k) {
                        double v = c[ch * nc + k]; /* Annen Eq. 4 / 15: c_j + grad c_j . d_j */
                        for (int a = 0; L->m.kind == LM_TAYLOR1 && a < 3; ++a)
                            v += g[(ch * 3 + a) * nc + k] * (x[a] - L->m.point[j][a]);
                        out[(3 * (size_t)p + ch) * nc + k] += w[j] * v;
                    }
            }
        }
        break;
    }
    if (L->m.kind != LM_ANALYTIC_F && !(L->m.kind == LM_GRID && L->m.grid_storage == SHL_GRID_FLOAT)) {
        /* rounded to float in runs of 8 (gcc -O2 vectorizes the fixed-count inner loop: the
         * scalar conversion loop took ~10% of the grid path's interpolation time) */
        const size_t total = 3 * (size_t)nc * (size_t)nb, runs = total / 8 * 8;
        for (size_t k = 0; k < runs; k += 8)
            for (size_t r = 0; r < 8; ++r) coef[k + r] = (float)out[k + r];
        for (size_t k = runs; k < total; ++k) coef[k] = (float)out[k];
    }
    const double t1 = bench_now();
    j->consume(j->arg, worker, begin, end, coef);
    j->t_eval[worker] += t1 - t0;
    j->t_consume[worker] += bench_now() - t1;
    par_progress_add(j->prog, nb);
    return;
fail:
    j->failed[worker] = 1;
}

int lighting_eval(const lighting *L, long n, const double *pts, int nthreads, lighting_consumer consume, void *arg,
                  double *eval_share)
{
    char name[128] = "lighting: ";
    lighting_name(&L->m, name + strlen(name), sizeof name - strlen(name));
    const int nw = nthreads < 1 ? 1 : nthreads > SHL_MAX_THREADS ? SHL_MAX_THREADS : nthreads;
    eval_job j = {L, pts, consume, arg, NULL, malloc(sizeof(double) * 3 * (size_t)L->nc * BLOCK * (size_t)nw),
                  malloc(sizeof(double) * 3 * SHL__ZH_BLOCK * (size_t)nw), malloc(sizeof(float) * 3 * BLOCK * (size_t)nw),
                  malloc(sizeof(float) * 3 * (size_t)L->nc * BLOCK * (size_t)nw), {0}, {0}, {0}};
    int st = j.out && j.acc && j.pf && j.coef ? 0 : -1;
    if (!st) {
        j.prog = par_progress_begin(name, n);
        par_for(n, BLOCK, nw, eval_block, &j);
        par_progress_end(j.prog);
        double te = 0.0, tc = 0.0;
        for (int w = 0; w < nw; ++w) {
            if (j.failed[w]) st = -1;
            te += j.t_eval[w];
            tc += j.t_consume[w];
        }
        *eval_share = te + tc > 0.0 ? te / (te + tc) : 1.0;
    }
    free(j.out);
    free(j.acc);
    free(j.pf);
    free(j.coef);
    return st;
}
