#include "hvlpass.h"
#include "parfor.h"
#include "vec3.h"
#include <stdlib.h>
#include <string.h>

void hvl_free(hvl_set *h)
{
    free(h->h);
    free(h->rgb);
    shl_brdf_table_destroy(h->emit);
    shl_brdf_table_destroy(h->recv);
    memset(h, 0, sizeof *h);
}

/* A primary light as an RSM origin: centre, frame, power (W per colour), hemisphere or sphere. */
typedef struct {
    double c[3], n[3], t[3], b[3], power[3], offset;
    int sphere;
} emitter;

static void polygon_emitter(const scene_polygon *p, emitter *e)
{
    double nrm[3] = {0, 0, 0};
    v3_set(e->c, 0, 0, 0);
    for (int k = 0; k < p->n; ++k) v3_madd(e->c, e->c, p->v + 3 * k, 1.0 / p->n);
    for (int k = 1; k + 1 < p->n; ++k) {
        double e1[3], e2[3], x[3];
        v3_sub(e1, p->v + 3 * k, p->v);
        v3_sub(e2, p->v + 3 * (k + 1), p->v);
        v3_cross(x, e1, e2);
        v3_add(nrm, nrm, x);
    }
    const double area = 0.5 * v3_normalize(nrm);
    memcpy(e->n, nrm, sizeof nrm);
    v3_basis(e->n, e->t, e->b);
    for (int ch = 0; ch < 3; ++ch) e->power[ch] = M_PI * area * p->rgb[ch] * (p->two_sided ? 2 : 1);
    e->offset = 1e-4 * sqrt(area);
    e->sphere = 0;
}

/* Direction of RSM texel (i, j) of k x k: cosine-weighted about n (two-sided: the
 * first half of the rows on the front, the rest on the back), or uniform over the sphere. */
static void texel_dir(const emitter *e, int two_sided, int i, int j, int k, double d[3])
{
    const double v = (j + 0.5) / k;
    if (e->sphere) {
        const double z = 1 - 2 * (i + 0.5) / k, r = sqrt(fmax(0.0, 1 - z * z));
        v3_set(d, r * cos(2 * M_PI * v), r * sin(2 * M_PI * v), z);
        return;
    }
    const int half = (k + 1) / 2, back = two_sided && i >= half;
    const double u = two_sided ? (back ? (i - half + 0.5) / (k - half) : (i + 0.5) / half) : (i + 0.5) / k;
    const double r = sqrt(u), z = sqrt(fmax(0.0, 1 - u)) * (back ? -1.0 : 1.0);
    for (int a = 0; a < 3; ++a) d[a] = r * cos(2 * M_PI * v) * e->t[a] + r * sin(2 * M_PI * v) * e->b[a] + z * e->n[a];
}

static double lum(const double *rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

int hvl_distribute(const scene *s, const bvh *b, int recv_lmax, hvl_set *out)
{
    memset(out, 0, sizeof *out);
    const int nl = s->npolys + s->nspheres;
    emitter *em = malloc(sizeof *em * (size_t)nl);
    if (!em) return -1;
    double total = 0.0;
    for (int i = 0; i < nl; ++i) {
        if (i < s->npolys)
            polygon_emitter(&s->polys[i], &em[i]);
        else {
            const scene_sphere *sp = &s->spheres[i - s->npolys];
            memcpy(em[i].c, sp->center, sizeof em[i].c);
            for (int ch = 0; ch < 3; ++ch) em[i].power[ch] = 4 * M_PI * M_PI * sp->radius * sp->radius * sp->rgb[ch];
            em[i].offset = sp->radius * 1.0001;
            em[i].sphere = 1;
        }
        total += fmax(0.0, lum(em[i].power));
    }
    const shl_brdf lambert = {SHL_BRDF_PHONG, 1.0, 0.0, 0.0, 0.0, 1.0};
    int st = shl_brdf_table_create(s->hvl_lmax, &lambert, 90, &out->emit) != SHL_OK ||
             shl_brdf_table_create(recv_lmax, &lambert, 90, &out->recv) != SHL_OK;
    int cap = 0;
    for (int i = 0; !st && i < nl; ++i) {
        const double share = total > 0 ? fmax(0.0, lum(em[i].power)) / total : 0.0;
        const int k = (int)lround(sqrt(share * s->hvl_count));
        if (k < 2) continue; /* a light too weak for a 2 x 2 map gets no HVL */
        const int two_sided = i < s->npolys && s->polys[i].two_sided;
        double *pos = malloc(sizeof(double) * 3 * (size_t)k * (size_t)k), *dist = malloc(sizeof(double) * (size_t)k * k);
        double *rad = malloc(sizeof(double) * (size_t)k * (size_t)k), *nrm = malloc(sizeof(double) * 3 * (size_t)k * k);
        int *mat = malloc(sizeof(int) * (size_t)k * (size_t)k);
        if (!pos || !dist || !rad || !nrm || !mat) st = -1;
        for (int i2 = 0; !st && i2 < k; ++i2)
            for (int j = 0; j < k; ++j) {
                const int q = i2 * k + j;
                double d[3], o[3];
                texel_dir(&em[i], two_sided, i2, j, k, d);
                v3_madd(o, em[i].c, d, em[i].offset);
                const float of[3] = {(float)o[0], (float)o[1], (float)o[2]}, df[3] = {(float)d[0], (float)d[1], (float)d[2]};
                float t, u, v;
                const int tri = bvh_closest(b, of, df, INFINITY, &t, &u, &v);
                mat[q] = -1;
                if (tri < 0) { /* a miss: far away, so it barely weighs in its neighbours' radii */
                    v3_madd(pos + 3 * q, o, d, 1e6);
                    dist[q] = 1e6;
                    continue;
                }
                const int *vi = s->geom.tri + 3 * tri;
                v3_madd(pos + 3 * q, o, d, t);
                dist[q] = t + em[i].offset;
                double *n = nrm + 3 * q;
                v3_set(n, 0, 0, 0);
                v3_madd(n, n, s->geom.nrm + 3 * vi[0], 1 - u - v);
                v3_madd(n, n, s->geom.nrm + 3 * vi[1], u);
                v3_madd(n, n, s->geom.nrm + 3 * vi[2], v);
                if (v3_dot(n, d) > 0) v3_scale(n, n, -1.0); /* face the light */
                mat[q] = s->geom.mat[vi[0]];
            }
        if (!st && shl_hvl_radius_grid(k, k, pos, dist, 1e-3, s->hvl_scale, rad) != SHL_OK) st = -1;
        if (!st && out->count + k * k > cap) {
            cap = 2 * (out->count + k * k);
            shl_hvl *h = realloc(out->h, sizeof *h * (size_t)cap);
            if (h) out->h = h;
            double *c = realloc(out->rgb, sizeof(double) * 3 * (size_t)cap);
            if (c) out->rgb = c;
            if (!h || !c) st = -1;
        }
        for (int q = 0; !st && q < k * k; ++q) {
            if (mat[q] < 0 || !(rad[q] > 0)) continue;
            shl_hvl *h = &out->h[out->count];
            memcpy(h->pos, pos + 3 * q, sizeof h->pos);
            memcpy(h->normal, nrm + 3 * q, sizeof h->normal);
            v3_sub(h->to_light, em[i].c, h->pos);
            if (v3_normalize(h->to_light) == 0 || v3_normalize(h->normal) == 0) continue;
            h->radius = rad[q];
            h->power = 1.0;
            h->brdf = out->emit;
            for (int ch = 0; ch < 3; ++ch)
                out->rgb[3 * out->count + ch] = em[i].power[ch] / (k * k) * s->mats[mat[q]].albedo[ch];
            ++out->count;
        }
        free(pos);
        free(dist);
        free(rad);
        free(nrm);
        free(mat);
    }
    free(em);
    if (st) hvl_free(out);
    return st ? -1 : 0;
}

typedef struct {
    const scene *s;
    const hvl_set *h;
    const int *idx;
    float *indirect;
    par_progress *prog;
    int failed[256];
} gather_job;

static void gather_block(void *arg, int worker, long begin, long end)
{
    gather_job *j = arg;
    const mesh *g = &j->s->geom;
    for (long i = begin; i < end; ++i) {
        const long v = j->idx ? j->idx[i] : i;
        const double *x = g->pos + 3 * v, *n = g->nrm + 3 * v, *alb = j->s->mats[g->mat[v]].albedo;
        double sum[3] = {0, 0, 0};
        for (int k = 0; k < j->h->count; ++k) { /* Lambertian receivers: F does not depend on wo; take wo = n */
            double r;
            if (shl_hvl_shade(&j->h->h[k], 1, x, n, n, j->h->recv, &r) != SHL_OK) {
                j->failed[worker] = 1;
                return;
            }
            for (int ch = 0; ch < 3; ++ch) sum[ch] += r * j->h->rgb[3 * k + ch];
        }
        for (int ch = 0; ch < 3; ++ch) j->indirect[3 * v + ch] += (float)(alb[ch] * sum[ch]);
    }
    par_progress_add(j->prog, end - begin);
}

int hvl_gather(const scene *s, const hvl_set *h, const int *idx, long n, float *indirect, int nthreads)
{
    const long count = idx ? n : s->geom.nv;
    gather_job j = {s, h, idx, indirect, par_progress_begin("HVL gather", count), {0}};
    par_for(count, 64, nthreads, gather_block, &j);
    par_progress_end(j.prog);
    for (int w = 0; w < 256; ++w)
        if (j.failed[w]) return -1;
    return 0;
}

/* ---- VPL and VSL baselines (HVL Table 2) ---------------------------------------- */

double vpl_radiance(const shl_hvl *h, const double x[3], const double n[3])
{
    double w[3];
    v3_sub(w, h->pos, x);
    const double d2 = v3_dot(w, w), cx = v3_dot(n, w), cy = -v3_dot(h->normal, w);
    if (!(d2 > 0) || cx <= 0 || cy <= 0) return 0.0;
    return cx * cy / (d2 * d2 * M_PI * M_PI); /* cos_x cos_y / (pi^2 d^2), the cosines' 1/d folded in */
}

static unsigned long long splitmix(unsigned long long *s)
{
    unsigned long long z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

double vsl_radiance(const shl_hvl *h, const double x[3], const double n[3], int k, unsigned long long seed)
{
    double a[3], t[3], b[3];
    v3_sub(a, h->pos, x);
    const double d = v3_normalize(a);
    if (!(d > 0) || k < 1) return 0.0;
    const double sa = h->radius / d, ca = sa < 1 ? sqrt(1 - sa * sa) : 0.0, omega = 2 * M_PI * (1 - ca);
    v3_basis(a, t, b);
    double sum = 0.0;
    for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) { /* uniform on the cone: cos = 1 - u (1 - cos a), pdf 1 / omega */
            const double u = (i + (splitmix(&seed) >> 11) * 0x1p-53) / k, v = (j + (splitmix(&seed) >> 11) * 0x1p-53) / k;
            const double c = 1 - u * (1 - ca), s = sqrt(fmax(0.0, 1 - c * c)), ph = 2 * M_PI * v;
            double w[3];
            for (int q = 0; q < 3; ++q) w[q] = c * a[q] + s * (cos(ph) * t[q] + sin(ph) * b[q]);
            const double cx = v3_dot(n, w), cy = -v3_dot(h->normal, w);
            if (cx > 0 && cy > 0) sum += cx * cy;
        }
    return sum * omega / (k * k) / (M_PI * M_PI) / (M_PI * h->radius * h->radius); /* Hasan 2009 Eq. 5 */
}

typedef struct {
    const scene *s;
    const hvl_set *h;
    int k;
    const int *idx;
    float *indirect;
    par_progress *prog;
} vl_job;

static void vl_block(void *arg, int worker, long begin, long end)
{
    (void)worker;
    vl_job *j = arg;
    const mesh *g = &j->s->geom;
    for (long i = begin; i < end; ++i) {
        const long v = j->idx ? j->idx[i] : i;
        const double *x = g->pos + 3 * v, *n = g->nrm + 3 * v, *alb = j->s->mats[g->mat[v]].albedo;
        double sum[3] = {0, 0, 0};
        for (int q = 0; q < j->h->count; ++q) {
            const double r = j->k ? vsl_radiance(&j->h->h[q], x, n, j->k, (unsigned long long)v * 1000003ull + (unsigned)q)
                                  : vpl_radiance(&j->h->h[q], x, n);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += r * j->h->rgb[3 * q + ch];
        }
        for (int ch = 0; ch < 3; ++ch) j->indirect[3 * v + ch] += (float)(alb[ch] * sum[ch]);
    }
    par_progress_add(j->prog, end - begin);
}

int vl_gather(const scene *s, const hvl_set *h, int vsl_k, const int *idx, long n, float *indirect, int nthreads)
{
    const long count = idx ? n : s->geom.nv;
    vl_job j = {s, h, vsl_k, idx, indirect, par_progress_begin(vsl_k ? "VSL gather" : "VPL gather", count)};
    par_for(count, 64, nthreads, vl_block, &j);
    par_progress_end(j.prog);
    return 0;
}
