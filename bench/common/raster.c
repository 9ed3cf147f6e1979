#include "raster.h"
#include "parfor.h"
#include "vec3.h"
#include <stdlib.h>
#include <string.h>

enum { TILE = 32 };

int framebuf_init(framebuf *fb, int w, int h)
{
    const size_t n = (size_t)w * (size_t)h;
    fb->w = w;
    fb->h = h;
    fb->depth = malloc(sizeof(float) * n);
    fb->mesh = malloc(sizeof(int) * n);
    fb->tri = malloc(sizeof(int) * n);
    fb->bary = malloc(sizeof(float) * 3 * n);
    fb->back = malloc(n);
    if (fb->depth && fb->mesh && fb->tri && fb->bary && fb->back) return 0;
    framebuf_free(fb);
    return -1;
}

void framebuf_free(framebuf *fb)
{
    free(fb->depth);
    free(fb->mesh);
    free(fb->tri);
    free(fb->bary);
    free(fb->back);
    memset(fb, 0, sizeof *fb);
}

/* A screen-space triangle after clipping: pixel bounding box, screen
 * positions, 1/depth, and barycentrics (of the source triangle) per vertex. */
typedef struct {
    double x[3], y[3];
    float iw[3], b[3][3];
    int x0, y0, x1, y1; /* pixel centres x0 <= x < x1, y0 <= y < y1 */
    int mesh, tri;
    unsigned char back;
} rtri;

typedef struct {
    const camera *cam;
    const raster_mesh *meshes;
    int nmeshes, w, h;
    double right[3], up[3], fwd[3], focal, znear;
    long *first_tri;  /* prefix of the meshes' triangle counts (global triangle index) */
    long *count;      /* records per global triangle, then their prefix sum */
    rtri *recs;
    long nrecs;
    int *tile_first, *tile_list, tiles_x, tiles_y;
    framebuf *fb;
} ctx_t;

typedef struct {
    double v[3]; /* view space: right, up, forward */
    float b[3];
} cvert;

/* Clip the triangle to forward >= znear, project, and emit up to 2 records; returns the count. */
static int setup_tri(const ctx_t *c, int m, int t, rtri *out)
{
    const raster_mesh *rm = &c->meshes[m];
    cvert in[3], poly[4];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
        double d[3];
        v3_sub(d, rm->pos + 3 * rm->tri[3 * t + k], c->cam->eye);
        v3_set(in[k].v, v3_dot(d, c->right), v3_dot(d, c->up), v3_dot(d, c->fwd));
        in[k].b[0] = in[k].b[1] = in[k].b[2] = 0.0f;
        in[k].b[k] = 1.0f;
    }
    for (int k = 0; k < 3; ++k) { /* Sutherland-Hodgman against one plane */
        const cvert *a = &in[k], *b = &in[(k + 1) % 3];
        const int ina = a->v[2] >= c->znear, inb = b->v[2] >= c->znear;
        if (ina) poly[n++] = *a;
        if (ina != inb) {
            const double s = (c->znear - a->v[2]) / (b->v[2] - a->v[2]);
            cvert *q = &poly[n++];
            for (int i = 0; i < 3; ++i) {
                q->v[i] = a->v[i] + s * (b->v[i] - a->v[i]);
                q->b[i] = (float)(a->b[i] + s * (b->b[i] - a->b[i]));
            }
        }
    }
    if (n < 3) return 0;
    double sx[4], sy[4];
    for (int k = 0; k < n; ++k) {
        sx[k] = 0.5 * c->w + c->focal * poly[k].v[0] / poly[k].v[2];
        sy[k] = 0.5 * c->h - c->focal * poly[k].v[1] / poly[k].v[2];
    }
    int emitted = 0;
    for (int f = 1; f + 1 < n; ++f) {
        const int id[3] = {0, f, f + 1};
        double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
        for (int k = 0; k < 3; ++k) {
            minx = fmin(minx, sx[id[k]]);
            maxx = fmax(maxx, sx[id[k]]);
            miny = fmin(miny, sy[id[k]]);
            maxy = fmax(maxy, sy[id[k]]);
        }
        const double x0 = fmax(0.0, ceil(minx - 0.5)), x1 = fmin((double)c->w, floor(maxx - 0.5) + 1.0);
        const double y0 = fmax(0.0, ceil(miny - 0.5)), y1 = fmin((double)c->h, floor(maxy - 0.5) + 1.0);
        const double area = (sx[id[1]] - sx[id[0]]) * (sy[id[2]] - sy[id[0]]) - (sx[id[2]] - sx[id[0]]) * (sy[id[1]] - sy[id[0]]);
        if (x0 >= x1 || y0 >= y1 || area == 0.0) continue;
        if (out) {
            rtri *r = &out[emitted];
            const int swap = area < 0; /* orient to positive area; y points down, so front faces have area < 0 */
            const int order[3] = {id[0], swap ? id[2] : id[1], swap ? id[1] : id[2]};
            for (int k = 0; k < 3; ++k) {
                r->x[k] = sx[order[k]];
                r->y[k] = sy[order[k]];
                r->iw[k] = (float)(1.0 / poly[order[k]].v[2]);
                memcpy(r->b[k], poly[order[k]].b, sizeof r->b[k]);
            }
            r->x0 = (int)x0;
            r->x1 = (int)x1;
            r->y0 = (int)y0;
            r->y1 = (int)y1;
            r->mesh = m;
            r->tri = t;
            r->back = !swap;
        }
        ++emitted;
    }
    return emitted;
}

static void global_to_local(const ctx_t *c, long g, int *m, int *t)
{
    int k = 0;
    while (g >= c->first_tri[k + 1]) ++k;
    *m = k;
    *t = (int)(g - c->first_tri[k]);
}

static void count_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    for (long g = begin; g < end; ++g) {
        int m, t;
        global_to_local(c, g, &m, &t);
        c->count[g] = setup_tri(c, m, t, NULL);
    }
}

static void write_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    for (long g = begin; g < end; ++g) {
        int m, t;
        global_to_local(c, g, &m, &t);
        if (c->count[g + 1] > c->count[g]) setup_tri(c, m, t, c->recs + c->count[g]);
    }
}

/* Rasterize the records binned to one tile, in record order (deterministic ties). */
static void tile_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    framebuf *fb = c->fb;
    for (long tile = begin; tile < end; ++tile) {
        const int tx0 = (int)(tile % c->tiles_x) * TILE, ty0 = (int)(tile / c->tiles_x) * TILE;
        const int tx1 = tx0 + TILE < c->w ? tx0 + TILE : c->w, ty1 = ty0 + TILE < c->h ? ty0 + TILE : c->h;
        for (int i = c->tile_first[tile]; i < c->tile_first[tile + 1]; ++i) {
            const rtri *r = &c->recs[c->tile_list[i]];
            const double area = (r->x[1] - r->x[0]) * (r->y[2] - r->y[0]) - (r->x[2] - r->x[0]) * (r->y[1] - r->y[0]);
            double ex[3], ey[3], e0[3];
            int bias[3];
            for (int k = 0; k < 3; ++k) { /* edge k is opposite vertex k: E_k = area * lambda_k */
                const int a = (k + 1) % 3, b = (k + 2) % 3;
                const double dx = r->x[b] - r->x[a], dy = r->y[b] - r->y[a];
                ex[k] = -dy;
                ey[k] = dx;
                e0[k] = dy * r->x[a] - dx * r->y[a];
                bias[k] = dy > 0 || (dy == 0 && dx < 0); /* ties: exactly one of two triangles sharing the edge */
            }
            const int x0 = r->x0 > tx0 ? r->x0 : tx0, x1 = r->x1 < tx1 ? r->x1 : tx1;
            const int y0 = r->y0 > ty0 ? r->y0 : ty0, y1 = r->y1 < ty1 ? r->y1 : ty1;
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const double px = x + 0.5, py = y + 0.5;
                    double l[3];
                    int inside = 1;
                    for (int k = 0; k < 3 && inside; ++k) {
                        l[k] = ex[k] * px + ey[k] * py + e0[k];
                        inside = l[k] > 0 || (l[k] == 0 && bias[k]);
                    }
                    if (!inside) continue;
                    const size_t p = (size_t)y * (size_t)c->w + (size_t)x;
                    const double w0 = l[0] / area * r->iw[0], w1 = l[1] / area * r->iw[1], w2 = l[2] / area * r->iw[2];
                    const double iw = w0 + w1 + w2;
                    if (!(iw > fb->depth[p])) continue;
                    fb->depth[p] = (float)iw;
                    fb->mesh[p] = r->mesh;
                    fb->tri[p] = r->tri;
                    fb->back[p] = r->back;
                    for (int j = 0; j < 3; ++j)
                        fb->bary[3 * p + j] = (float)((w0 * r->b[0][j] + w1 * r->b[1][j] + w2 * r->b[2][j]) / iw);
                }
        }
    }
}

int raster_draw(framebuf *fb, const camera *cam, const raster_mesh *meshes, int nmeshes, int nthreads)
{
    const size_t npix = (size_t)fb->w * (size_t)fb->h;
    for (size_t p = 0; p < npix; ++p) {
        fb->depth[p] = 0.0f;
        fb->mesh[p] = fb->tri[p] = -1;
    }
    ctx_t c;
    memset(&c, 0, sizeof c);
    c.cam = cam;
    c.meshes = meshes;
    c.nmeshes = nmeshes;
    c.w = fb->w;
    c.h = fb->h;
    c.fb = fb;
    v3_sub(c.fwd, cam->target, cam->eye);
    c.znear = 1e-3 * v3_normalize(c.fwd);
    v3_cross(c.right, c.fwd, cam->up);
    v3_normalize(c.right);
    v3_cross(c.up, c.right, c.fwd);
    c.focal = 0.5 * fb->h / tan(0.5 * cam->fov_deg * M_PI / 180.0);
    c.first_tri = malloc(sizeof(long) * (size_t)(nmeshes + 1));
    int st = -1;
    if (!c.first_tri) goto done;
    c.first_tri[0] = 0;
    for (int m = 0; m < nmeshes; ++m) c.first_tri[m + 1] = c.first_tri[m] + meshes[m].nt;
    const long ntri = c.first_tri[nmeshes];
    c.count = malloc(sizeof(long) * (size_t)(ntri + 1));
    if (!c.count) goto done;
    par_for(ntri, 4096, nthreads, count_job, &c);
    long sum = 0;
    for (long g = 0; g < ntri; ++g) {
        const long k = c.count[g];
        c.count[g] = sum;
        sum += k;
    }
    c.count[ntri] = sum;
    c.nrecs = sum;
    c.recs = malloc(sizeof(rtri) * (size_t)(sum ? sum : 1));
    if (!c.recs) goto done;
    par_for(ntri, 4096, nthreads, write_job, &c);
    c.tiles_x = (fb->w + TILE - 1) / TILE;
    c.tiles_y = (fb->h + TILE - 1) / TILE;
    const int ntiles = c.tiles_x * c.tiles_y;
    c.tile_first = calloc((size_t)ntiles + 1, sizeof(int));
    if (!c.tile_first) goto done;
    long refs = 0;
    for (long i = 0; i < c.nrecs; ++i) { /* binning: count, prefix, fill */
        const rtri *r = &c.recs[i];
        for (int ty = r->y0 / TILE; ty <= (r->y1 - 1) / TILE; ++ty)
            for (int tx = r->x0 / TILE; tx <= (r->x1 - 1) / TILE; ++tx) ++c.tile_first[ty * c.tiles_x + tx + 1];
    }
    for (int t = 0; t < ntiles; ++t) c.tile_first[t + 1] += c.tile_first[t];
    refs = c.tile_first[ntiles];
    c.tile_list = malloc(sizeof(int) * (size_t)(refs ? refs : 1));
    int *fill = malloc(sizeof(int) * (size_t)ntiles);
    if (!c.tile_list || !fill || c.nrecs > 0x7fffffffL) {
        free(fill);
        goto done;
    }
    memcpy(fill, c.tile_first, sizeof(int) * (size_t)ntiles);
    for (long i = 0; i < c.nrecs; ++i) {
        const rtri *r = &c.recs[i];
        for (int ty = r->y0 / TILE; ty <= (r->y1 - 1) / TILE; ++ty)
            for (int tx = r->x0 / TILE; tx <= (r->x1 - 1) / TILE; ++tx) c.tile_list[fill[ty * c.tiles_x + tx]++] = (int)i;
    }
    free(fill);
    par_for(ntiles, 1, nthreads, tile_job, &c);
    st = 0;
done:
    free(c.first_tri);
    free(c.count);
    free(c.recs);
    free(c.tile_first);
    free(c.tile_list);
    return st;
}

typedef struct {
    const framebuf *fb;
    const raster_mesh *meshes;
    const float *const *colors;
    float *rgb;
} resolve_t;

static void resolve_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    const resolve_t *r = arg;
    const framebuf *fb = r->fb;
    for (long p = begin * fb->w; p < end * fb->w; ++p) {
        float *o = r->rgb + 3 * p;
        const int m = fb->mesh[p];
        o[0] = o[1] = o[2] = 0.0f;
        if (m < 0 || (fb->back[p] && r->meshes[m].back_black)) continue;
        const int *v = r->meshes[m].tri + 3 * (size_t)fb->tri[p];
        const float *col = r->colors[m], *b = fb->bary + 3 * p;
        for (int k = 0; k < 3; ++k)
            for (int ch = 0; ch < 3; ++ch) o[ch] += b[k] * col[3 * (size_t)v[k] + ch];
    }
}

void raster_resolve(const framebuf *fb, const raster_mesh *meshes, const float *const *colors, float *rgb, int nthreads)
{
    resolve_t r = {fb, meshes, colors, rgb};
    par_for(fb->h, 16, nthreads, resolve_job, &r);
}

void raster_mask(const framebuf *fb, int m, unsigned char *mask)
{
    for (size_t p = 0; p < (size_t)fb->w * (size_t)fb->h; ++p) mask[p] = fb->mesh[p] == m;
}
