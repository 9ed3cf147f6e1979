#include "transfer.h"
#include "parfor.h"
#include "shlight.h"
#include "vec3.h"
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void transfer_free(transfer *t)
{
    free(t->t);
    t->t = NULL;
}

static int alloc_transfer(transfer *out, int lmax, int nv)
{
    out->lmax = lmax;
    out->nc = SHL_NCOEFFS(lmax);
    out->nv = nv;
    out->t = malloc(sizeof(float) * (size_t)out->nc * (size_t)(nv ? nv : 1));
    return out->t ? 0 : -1;
}

typedef struct {
    const mesh *m;
    const bvh *b;
    transfer *out;
    double zh[SHL_LMAX_MAX + 1];
    int rays;
    float eps;
    par_progress *prog;
} job_t;

static void unshadowed_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    const job_t *j = arg;
    const int nc = j->out->nc;
    double sh[SHL_NCOEFFS(SHL_LMAX_MAX)];
    for (long v = begin; v < end; ++v) {
        shl_zh_to_sh(j->out->lmax, j->zh, j->m->nrm + 3 * v, sh);
        for (int k = 0; k < nc; ++k) j->out->t[v * nc + k] = (float)(sh[k] / M_PI);
    }
}

int transfer_unshadowed(const mesh *m, int lmax, int nthreads, transfer *out)
{
    job_t j = {m, NULL, out, {0}, 0, 0, NULL};
    if (alloc_transfer(out, lmax, m->nv)) return -1;
    shl_zh_clamped_cosine(lmax, j.zh);
    par_for(m->nv, 1024, nthreads, unshadowed_job, &j);
    return 0;
}

static double radical_inverse2(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    return (double)i * 0x1.0p-32;
}

/* Control variate: T = T_unshadowed - (1/N) sum over occluded rays of Y(w), rays
 * cosine-weighted (pdf cos/pi), so unoccluded vertices get the exact unshadowed T.
 * Every vertex uses the same Hammersley set in its tangent frame: the estimation
 * error varies smoothly over the surface instead of as per-vertex noise. */
static void shadowed_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    const job_t *j = arg;
    const int nc = j->out->nc, lmax = j->out->lmax;
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)], acc[SHL_NCOEFFS(SHL_LMAX_MAX)];
    for (long v = begin; v < end; ++v) {
        const double *n = j->m->nrm + 3 * v, *p = j->m->pos + 3 * v;
        double t[3], b[3];
        v3_basis(n, t, b);
        const float o[3] = {(float)(p[0] + j->eps * n[0]), (float)(p[1] + j->eps * n[1]), (float)(p[2] + j->eps * n[2])};
        shl_zh_to_sh(lmax, j->zh, n, acc);
        for (int k = 0; k < nc; ++k) acc[k] /= M_PI;
        for (int i = 0; i < j->rays; ++i) {
            const double u = (i + 0.5) / j->rays, w = radical_inverse2((uint32_t)i);
            const double r = sqrt(u), phi = 2 * M_PI * w, z = sqrt(fmax(0.0, 1.0 - u));
            double d[3];
            for (int a = 0; a < 3; ++a) d[a] = r * cos(phi) * t[a] + r * sin(phi) * b[a] + z * n[a];
            const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            if (!bvh_occluded(j->b, o, df, INFINITY)) continue;
            shl_eval_basis(lmax, d, y);
            for (int k = 0; k < nc; ++k) acc[k] -= y[k] / j->rays;
        }
        for (int k = 0; k < nc; ++k) j->out->t[v * nc + k] = (float)acc[k];
    }
    par_progress_add(j->prog, end - begin);
}

enum { CACHE_VERSION = 2 };

static void cache_path(char *path, size_t len, const char *dir, const mesh *m, int lmax, int rays)
{
    uint64_t h = mesh_hash(m);
    const int64_t key[3] = {lmax, rays, CACHE_VERSION};
    for (int i = 0; i < 3; ++i) h = (h ^ (uint64_t)key[i]) * 0x100000001b3ull;
    snprintf(path, len, "%s/transfer-%016llx.bin", dir, (unsigned long long)h);
}

static int cache_read(const char *path, transfer *out)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    int hdr[3];
    const size_t n = (size_t)out->nc * (size_t)out->nv;
    const int ok = fread(hdr, sizeof hdr, 1, f) == 1 && hdr[0] == CACHE_VERSION && hdr[1] == out->nv &&
                   hdr[2] == out->nc && fread(out->t, sizeof(float), n, f) == n;
    fclose(f);
    return ok ? 0 : -1;
}

static void cache_write(const char *dir, const char *path, const transfer *t)
{
    if (mkdir(dir, 0777) && errno != EEXIST) return;
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) return;
    const int hdr[3] = {CACHE_VERSION, t->nv, t->nc};
    const size_t n = (size_t)t->nc * (size_t)t->nv;
    const int ok = fwrite(hdr, sizeof hdr, 1, f) == 1 && fwrite(t->t, sizeof(float), n, f) == n;
    if (fclose(f) || !ok || rename(tmp, path)) remove(tmp);
}

int transfer_shadowed(const mesh *m, const bvh *b, int lmax, int rays, const char *cache_dir, int nthreads,
                      transfer *out, int *cached)
{
    char path[1024];
    *cached = 0;
    if (alloc_transfer(out, lmax, m->nv)) return -1;
    if (cache_dir) {
        cache_path(path, sizeof path, cache_dir, m, lmax, rays);
        if (!cache_read(path, out)) {
            *cached = 1;
            return 0;
        }
    }
    double lo[3], hi[3], d[3];
    mesh_bounds(m, lo, hi);
    v3_sub(d, hi, lo);
    job_t j = {m, b, out, {0}, rays, (float)(1e-4 * v3_len(d)), par_progress_begin("shadowed transfer (ray casting)", m->nv)};
    shl_zh_clamped_cosine(lmax, j.zh);
    par_for(m->nv, 256, nthreads, shadowed_job, &j);
    par_progress_end(j.prog);
    if (cache_dir) cache_write(cache_dir, path, out);
    return 0;
}
