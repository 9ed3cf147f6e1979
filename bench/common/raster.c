#include "raster.h"
#include "parfor.h"
#include "vec3.h"
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { TILE = 32, CHUNK = 4096 };

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
    for (int i = 0; i < 4; ++i) {
        fb->work[i] = NULL;
        fb->work_len[i] = 0;
    }
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
    for (int i = 0; i < 4; ++i) free(fb->work[i]);
    memset(fb, 0, sizeof *fb);
}

/* A screen-space triangle after clipping: pixel bounding box, screen
 * positions, 1/depth, and barycentrics (of the source triangle) per vertex. */
typedef struct {
    double x[3], y[3];
    float iw[3], b[3][3];
    int x0, y0, x1, y1; /* pixel centres x0 <= x < x1, y0 <= y < y1 */
    int mesh, tri;       /* tri: as fb->tri reports it (raster_mesh.tri_id) */
    unsigned char back, fan; /* fan: which record of a clipped triangle */
} rtri;

/* A vertex seen by the camera: screen position (valid when z >= znear) and view depth. */
typedef struct {
    double sx, sy, z;
} pvert;

/* A vertex's pixel-centre key: cx = ceil(sx - 0.5) clamped to [0, w], fx = floor(sx - 0.5)
 * clamped to [-1, w - 1], cy and fy likewise.  ceil and floor commute with min and max, so a
 * triangle wholly in front of the near plane has no pixel centre in its bounding box (setup_tri's
 * x0 >= x1 or y0 >= y1, which the clamps preserve) exactly when max fx < min cx or max fy < min cy:
 * setup_job rejects most triangles of a dense mesh (smaller than a pixel) from these 8 bytes per
 * corner instead of the 24 of pvert.  A vertex behind the near plane (or not finite) gets a key
 * that never rejects. */
typedef struct {
    short cx, fx, cy, fy;
} pkey;

typedef struct {
    const camera *cam;
    const raster_mesh *meshes;
    int nmeshes, w, h;
    double right[3], up[3], fwd[3], focal, znear;
    long *first_tri;  /* prefix of the meshes' triangle counts (global triangle index) */
    long *first_vert; /* prefix of the meshes' vertex counts (index into pv) */
    pvert *pv;        /* every mesh's vertices, projected once per draw */
    pkey *key;        /* their pixel-centre keys */
    int keyed;        /* the frame fits the keys' shorts */
    int sort;         /* a mesh is reordered (tri_id): tile lists go back to the unreordered order */
    long maxlist;     /* longest tile list */
    void *tile_buf;   /* per worker: 3 maxlist words (sort_order), the maxlist-long order, then maxlist records (a tile's, in list order) */
    long nchunks, group, ngroups; /* setup: chunks of CHUNK global triangles, `group` chunks per call */
    rtri **chunk_recs; /* per chunk: its records, in triangle order */
    long *chunk_count; /* their number */
    long *bin;         /* per group and tile: its records' references to the tile, then where they go */
    pvert *corners;    /* per worker: 3 CHUNK triangle corners */
    long *cand;        /* per worker: CHUNK triangles the keys do not reject */
    long *tile_first;
    const rtri **tile_list;
    int tiles_x, tiles_y, ntiles;
    framebuf *fb;
} ctx_t;

typedef struct {
    double v[3]; /* view space: right, up, forward */
    float b[3];
} cvert;

static void view_space(const ctx_t *c, const double *x, double v[3])
{
    double d[3];
    v3_sub(d, x, c->cam->eye);
    v3_set(v, v3_dot(d, c->right), v3_dot(d, c->up), v3_dot(d, c->fwd));
}

static double screen_x(const ctx_t *c, const double v[3]) { return 0.5 * c->w + c->focal * v[0] / v[2]; }
static double screen_y(const ctx_t *c, const double v[3]) { return 0.5 * c->h - c->focal * v[1] / v[2]; }

/* ceil(s - 0.5) clamped to [0, n] and floor(s - 0.5) clamped to [-1, n - 1] (s finite), by
 * truncation where it is exact (0 <= t < n). */
static short key_ceil(double s, int n)
{
    const double t = s - 0.5;
    if (t <= 0.0) return 0;
    if (t > n - 1) return (short)n;
    const int k = (int)t;
    return (short)(k + (t > k));
}

static short key_floor(double s, int n)
{
    const double t = s - 0.5;
    return (short)(t < 0.0 ? -1 : t >= n ? n - 1 : (int)t);
}

static void project_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    int m = 0;
    for (long g = begin; g < end; ++g) {
        while (g >= c->first_vert[m + 1]) ++m;
        double v[3];
        view_space(c, c->meshes[m].pos + 3 * (g - c->first_vert[m]), v);
        pvert *q = &c->pv[g];
        pkey *k = &c->key[g];
        q->z = v[2];
        q->sx = v[2] >= c->znear ? screen_x(c, v) : 0.0;
        q->sy = v[2] >= c->znear ? screen_y(c, v) : 0.0;
        if (c->keyed && v[2] >= c->znear && isfinite(q->sx) && isfinite(q->sy))
            *k = (pkey){key_ceil(q->sx, c->w), key_floor(q->sx, c->w), key_ceil(q->sy, c->h), key_floor(q->sy, c->h)};
        else
            *k = (pkey){SHRT_MIN, SHRT_MAX, SHRT_MIN, SHRT_MAX};
    }
}

/* Clip the triangle to forward >= znear, project, and emit up to 2 records; returns the count.
 * pv: its corners' projections (project_job); a triangle wholly in front of the near plane
 * (the common case) uses them, the same values the clipping path computes. */
static int setup_tri(const ctx_t *c, int m, int t, const pvert pv[3], rtri *out)
{
    const raster_mesh *rm = &c->meshes[m];
    const int *tv = rm->tri + 3 * (size_t)t;
    double sx[4], sy[4], z[4];
    float b[4][3];
    int n = 0;
    if (pv[0].z >= c->znear && pv[1].z >= c->znear && pv[2].z >= c->znear) {
        for (int k = 0; k < 3; ++k) {
            sx[k] = pv[k].sx;
            sy[k] = pv[k].sy;
            z[k] = pv[k].z;
            b[k][0] = b[k][1] = b[k][2] = 0.0f;
            b[k][k] = 1.0f;
        }
        n = 3;
    } else {
        cvert in[3], poly[4];
        for (int k = 0; k < 3; ++k) {
            view_space(c, rm->pos + 3 * tv[k], in[k].v);
            in[k].b[0] = in[k].b[1] = in[k].b[2] = 0.0f;
            in[k].b[k] = 1.0f;
        }
        for (int k = 0; k < 3; ++k) { /* Sutherland-Hodgman against one plane */
            const cvert *a = &in[k], *e = &in[(k + 1) % 3];
            const int ina = a->v[2] >= c->znear, ine = e->v[2] >= c->znear;
            if (ina) poly[n++] = *a;
            if (ina != ine) {
                const double s = (c->znear - a->v[2]) / (e->v[2] - a->v[2]);
                cvert *q = &poly[n++];
                for (int i = 0; i < 3; ++i) {
                    q->v[i] = a->v[i] + s * (e->v[i] - a->v[i]);
                    q->b[i] = (float)(a->b[i] + s * (e->b[i] - a->b[i]));
                }
            }
        }
        if (n < 3) return 0;
        for (int k = 0; k < n; ++k) {
            sx[k] = screen_x(c, poly[k].v);
            sy[k] = screen_y(c, poly[k].v);
            z[k] = poly[k].v[2];
            memcpy(b[k], poly[k].b, sizeof b[k]);
        }
    }
    int emitted = 0;
    for (int f = 1; f + 1 < n; ++f) {
        const int id[3] = {0, f, f + 1};
        double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
        for (int k = 0; k < 3; ++k) {
            minx = sx[id[k]] < minx ? sx[id[k]] : minx; /* finite coordinates: as fmin, fmax */
            maxx = sx[id[k]] > maxx ? sx[id[k]] : maxx;
            miny = sy[id[k]] < miny ? sy[id[k]] : miny;
            maxy = sy[id[k]] > maxy ? sy[id[k]] : maxy;
        }
        /* as fmax(0, .) and fmin(w, .), NaN included, without the library calls */
        const double cx = ceil(minx - 0.5), fx = floor(maxx - 0.5) + 1.0, cy = ceil(miny - 0.5), fy = floor(maxy - 0.5) + 1.0;
        const double x0 = cx > 0.0 ? cx : 0.0, x1 = fx < c->w ? fx : (double)c->w;
        const double y0 = cy > 0.0 ? cy : 0.0, y1 = fy < c->h ? fy : (double)c->h;
        if (x0 >= x1 || y0 >= y1) continue;
        const double area = (sx[id[1]] - sx[id[0]]) * (sy[id[2]] - sy[id[0]]) - (sx[id[2]] - sx[id[0]]) * (sy[id[1]] - sy[id[0]]);
        if (area == 0.0) continue;
        if (out) {
            rtri *r = &out[emitted];
            const int swap = area < 0; /* orient to positive area; y points down, so front faces have area < 0 */
            const int order[3] = {id[0], swap ? id[2] : id[1], swap ? id[1] : id[2]};
            for (int k = 0; k < 3; ++k) {
                r->x[k] = sx[order[k]];
                r->y[k] = sy[order[k]];
                r->iw[k] = (float)(1.0 / z[order[k]]);
                memcpy(r->b[k], b[order[k]], sizeof r->b[k]);
            }
            r->x0 = (int)x0;
            r->x1 = (int)x1;
            r->y0 = (int)y0;
            r->y1 = (int)y1;
            r->mesh = m;
            r->tri = rm->tri_id ? rm->tri_id[t] : t;
            r->back = !swap;
            r->fan = (unsigned char)emitted;
        }
        ++emitted;
    }
    return emitted;
}

/* tile: each tile the record's pixel box [x0, x1) x [y0, y1) meets, row by row. */
#define FOR_TILES(c, r, tile) \
    for (int ty_ = (r)->y0 / TILE; ty_ <= ((r)->y1 - 1) / TILE; ++ty_) \
        for (int tx_ = (r)->x0 / TILE, tile = ty_ * (c)->tiles_x + tx_; tx_ <= ((r)->x1 - 1) / TILE; ++tx_, ++tile)

/* Set up the triangles of chunks [begin, end) (one group): the keys reject the triangles without
 * a pixel centre in their box, the others' records go to a block for 2 records a candidate, then
 * shrunk to their number; the group's references per tile are counted for the binning. */
static void setup_job(void *arg, int worker, long begin, long end)
{
    ctx_t *c = arg;
    const long ntri = c->first_tri[c->nmeshes];
    pvert *corner = c->corners + 3 * CHUNK * (size_t)worker;
    long *cand = c->cand + CHUNK * (size_t)worker, *bin = c->bin + (size_t)(begin / c->group) * (size_t)c->ntiles;
    for (long ch = begin; ch < end; ++ch) {
        const long g0 = ch * CHUNK, g1 = ntri < g0 + CHUNK ? ntri : g0 + CHUNK;
        long n = 0, nc = 0;
        int m = 0;
        /* loops without data-dependent branches keep many of these scattered loads in flight */
        for (long g = g0; g < g1; ++g) {
            while (g >= c->first_tri[m + 1]) ++m;
            const int *tv = c->meshes[m].tri + 3 * (size_t)(g - c->first_tri[m]);
            const pkey *k = c->key + c->first_vert[m], *a = &k[tv[0]], *b = &k[tv[1]], *d = &k[tv[2]];
            const int maxfx = a->fx > b->fx ? a->fx : b->fx, mincx = a->cx < b->cx ? a->cx : b->cx;
            const int maxfy = a->fy > b->fy ? a->fy : b->fy, mincy = a->cy < b->cy ? a->cy : b->cy;
            const int empty = (maxfx > d->fx ? maxfx : d->fx) < (mincx < d->cx ? mincx : d->cx) ||
                              (maxfy > d->fy ? maxfy : d->fy) < (mincy < d->cy ? mincy : d->cy);
            cand[nc] = g;
            nc += !empty;
        }
        m = 0;
        for (long i = 0; i < nc; ++i) {
            while (cand[i] >= c->first_tri[m + 1]) ++m;
            const int *tv = c->meshes[m].tri + 3 * (size_t)(cand[i] - c->first_tri[m]);
            const pvert *pv = c->pv + c->first_vert[m];
            for (int k = 0; k < 3; ++k) corner[3 * i + k] = pv[tv[k]];
        }
        rtri *recs = nc ? malloc(sizeof(rtri) * 2 * (size_t)nc) : NULL; /* at most 2 records a triangle */
        if (nc && !recs) {
            c->chunk_count[ch] = 1; /* a count without records: out of memory, seen by raster_draw */
            continue;
        }
        m = 0;
        for (long i = 0; i < nc; ++i) {
            while (cand[i] >= c->first_tri[m + 1]) ++m;
            n += setup_tri(c, m, (int)(cand[i] - c->first_tri[m]), corner + 3 * i, recs + n);
        }
        for (long i = 0; i < n; ++i) FOR_TILES(c, &recs[i], t) ++bin[t];
        rtri *fit = n ? realloc(recs, sizeof(rtri) * (size_t)n) : NULL; /* shrinking; NULL: n is 0, or out of memory */
        if (!fit) free(recs);
        c->chunk_recs[ch] = fit;
        c->chunk_count[ch] = n;
    }
}

/* The group's references into the tile lists, from the offsets the prefix sum left in bin. */
static void bin_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    long *bin = c->bin + (size_t)(begin / c->group) * (size_t)c->ntiles;
    for (long ch = begin; ch < end; ++ch)
        for (long i = 0; i < c->chunk_count[ch]; ++i) {
            const rtri *r = &c->chunk_recs[ch][i];
            FOR_TILES(c, r, t) c->tile_list[bin[t]++] = r;
        }
}

/* order[0 .. n): the indices of rec[0 .. n) sorted by (mesh, tri, fan), i.e. the order the
 * unreordered meshes give: LSD radix sort on 11-bit digits of the key (first_tri[mesh] + tri) * 2 + fan.
 * buf: 3 n words (keys twice, then the other index array). */
static void sort_order(const ctx_t *c, const rtri *rec, long n, long *order, void *buf)
{
    enum { BITS = 11, RADIX = 1 << BITS };
    uint64_t *key[2] = {buf, (uint64_t *)buf + n};
    long *idx[2] = {order, (long *)((uint64_t *)buf + 2 * n)};
    for (long i = 0; i < n; ++i) {
        key[0][i] = ((uint64_t)(c->first_tri[rec[i].mesh] + rec[i].tri) << 1) | rec[i].fan;
        idx[0][i] = i;
    }
    const uint64_t top = (uint64_t)c->first_tri[c->nmeshes] << 1;
    int from = 0;
    for (int shift = 0; shift == 0 || top >> shift; shift += BITS, from ^= 1) {
        long count[RADIX + 1] = {0};
        for (long i = 0; i < n; ++i) ++count[(key[from][i] >> shift & (RADIX - 1)) + 1];
        for (int d = 0; d < RADIX; ++d) count[d + 1] += count[d];
        for (long i = 0; i < n; ++i) {
            const long at = count[key[from][i] >> shift & (RADIX - 1)]++;
            key[from ^ 1][at] = key[from][i];
            idx[from ^ 1][at] = idx[from][i];
        }
    }
    if (from) memcpy(order, idx[1], sizeof(long) * (size_t)n);
}

/* Rasterize the records binned to one tile in the order of the unreordered meshes' triangles
 * (the z-buffer keeps the first of equal depths: deterministic ties). */
static void tile_job(void *arg, int worker, long begin, long end)
{
    ctx_t *c = arg;
    framebuf *fb = c->fb;
    uint64_t *buf = (uint64_t *)c->tile_buf + (4 * (size_t)c->maxlist + sizeof(rtri) / 8 * (size_t)c->maxlist) * (size_t)worker;
    long *order = (long *)(buf + 3 * (size_t)c->maxlist);
    rtri *local = (rtri *)(buf + 4 * (size_t)c->maxlist);
    for (long tile = begin; tile < end; ++tile) {
        const rtri **list = c->tile_list + c->tile_first[tile];
        const long n = c->tile_first[tile + 1] - c->tile_first[tile];
        /* the tile's records gathered first, in memory order (independent loads, many misses in
         * flight), then sorted in the cache by index */
        for (long i = 0; i < n; ++i) local[i] = *list[i];
        if (c->sort) sort_order(c, local, n, order, buf);
        else
            for (long i = 0; i < n; ++i) order[i] = i;
        const int tx0 = (int)(tile % c->tiles_x) * TILE, ty0 = (int)(tile / c->tiles_x) * TILE;
        const int tx1 = tx0 + TILE < c->w ? tx0 + TILE : c->w, ty1 = ty0 + TILE < c->h ? ty0 + TILE : c->h;
        for (long i = 0; i < n; ++i) {
            const rtri *r = &local[order[i]];
            const double area = (r->x[1] - r->x[0]) * (r->y[2] - r->y[0]) - (r->x[2] - r->x[0]) * (r->y[1] - r->y[0]);
            double ax[3], ay[3], ex[3], ey[3], sg[3];
            int bias[3];
            for (int k = 0; k < 3; ++k) { /* edge k is opposite vertex k: E_k = area * lambda_k */
                const int a = (k + 1) % 3, b = (k + 2) % 3;
                const double dx = r->x[b] - r->x[a], dy = r->y[b] - r->y[a];
                /* E_k = (p - A) x (B - A) from the edge's lexicographically smaller end A, times -1 if
                 * the triangle runs A -> B: the two triangles sharing an edge evaluate the same
                 * products and get exactly opposite values, so no pixel centre falls between them */
                const int fwd = r->x[a] < r->x[b] || (r->x[a] == r->x[b] && r->y[a] < r->y[b]);
                const int lo = fwd ? a : b, hi = fwd ? b : a;
                ax[k] = r->x[lo];
                ay[k] = r->y[lo];
                ex[k] = r->x[hi] - r->x[lo];
                ey[k] = r->y[hi] - r->y[lo];
                sg[k] = fwd ? -1.0 : 1.0;
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
                        l[k] = sg[k] * ((px - ax[k]) * ey[k] - (py - ay[k]) * ex[k]);
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

/* fb->work[i] with at least `bytes` bytes (kept for the next draw), or NULL. */
static void *work(framebuf *fb, int i, size_t bytes)
{
    if (bytes > fb->work_len[i]) {
        free(fb->work[i]);
        fb->work_len[i] = 0;
        if (!(fb->work[i] = malloc(bytes))) return NULL;
        fb->work_len[i] = bytes;
    }
    return fb->work[i];
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
    c.first_vert = malloc(sizeof(long) * (size_t)(nmeshes + 1));
    if (!c.first_vert) goto done;
    c.first_vert[0] = 0;
    for (int m = 0; m < nmeshes; ++m) c.first_vert[m + 1] = c.first_vert[m] + meshes[m].nv;
    const long nchunks = c.nchunks = (ntri + CHUNK - 1) / CHUNK;
    const int nw = nthreads < 1 ? 1 : nthreads > SHL_MAX_THREADS ? SHL_MAX_THREADS : nthreads;
    c.keyed = fb->w < SHRT_MAX && fb->h < SHRT_MAX;
    c.tiles_x = (fb->w + TILE - 1) / TILE;
    c.tiles_y = (fb->h + TILE - 1) / TILE;
    const int ntiles = c.ntiles = c.tiles_x * c.tiles_y;
    c.group = 1 + (long)((double)nchunks * ntiles / (1 << 21)); /* at most ~2M bin counters */
    c.ngroups = (nchunks + c.group - 1) / c.group;
    c.pv = work(fb, 0, sizeof(pvert) * (size_t)(c.first_vert[nmeshes] + 1));
    c.key = work(fb, 1, sizeof(pkey) * (size_t)(c.first_vert[nmeshes] + 1));
    c.chunk_recs = calloc((size_t)nchunks + 1, sizeof(rtri *));
    c.chunk_count = malloc(sizeof(long) * (size_t)(nchunks + 1));
    c.bin = calloc((size_t)c.ngroups * (size_t)ntiles + 1, sizeof(long));
    c.corners = work(fb, 2, (sizeof(pvert) * 3 + sizeof(long)) * CHUNK * (size_t)nw);
    if (!c.pv || !c.key || !c.chunk_recs || !c.chunk_count || !c.bin || !c.corners) goto done;
    c.cand = (long *)(c.corners + 3 * CHUNK * (size_t)nw);
    par_for(c.first_vert[nmeshes], 8192, nw, project_job, &c);
    par_for(nchunks, c.group, nw, setup_job, &c);
    for (long ch = 0; ch < nchunks; ++ch)
        if (c.chunk_count[ch] && !c.chunk_recs[ch]) goto done;
    c.tile_first = malloc(sizeof(long) * ((size_t)ntiles + 1));
    if (!c.tile_first) goto done;
    long refs = 0; /* binning: tile lists in tile order, each in record order (group by group) */
    for (int t = 0; t < ntiles; ++t) {
        c.tile_first[t] = refs;
        for (long gr = 0; gr < c.ngroups; ++gr) {
            long *b = &c.bin[(size_t)gr * (size_t)ntiles + (size_t)t];
            const long k = *b;
            *b = refs;
            refs += k;
        }
    }
    c.tile_first[ntiles] = refs;
    c.tile_list = malloc(sizeof(rtri *) * (size_t)(refs ? refs : 1));
    if (!c.tile_list) goto done;
    par_for(nchunks, c.group, nw, bin_job, &c);
    for (int m = 0; m < nmeshes; ++m) c.sort |= meshes[m].tri_id != NULL;
    for (int t = 0; t < ntiles; ++t)
        c.maxlist = c.tile_first[t + 1] - c.tile_first[t] > c.maxlist ? c.tile_first[t + 1] - c.tile_first[t] : c.maxlist;
    if (!(c.tile_buf = work(fb, 3, (sizeof(uint64_t) * 4 + sizeof(rtri)) * (size_t)(c.maxlist + 1) * (size_t)nw))) goto done;
    par_for(ntiles, 1, nw, tile_job, &c);
    st = 0;
done:
    free(c.first_tri);
    free(c.first_vert);
    if (c.chunk_recs)
        for (long ch = 0; ch < c.nchunks; ++ch) free(c.chunk_recs[ch]);
    free(c.chunk_recs);
    free(c.chunk_count);
    free(c.bin);
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
