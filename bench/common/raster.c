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
    for (size_t i = 0; i < sizeof fb->work / sizeof *fb->work; ++i) {
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
    for (size_t i = 0; i < sizeof fb->work / sizeof *fb->work; ++i) free(fb->work[i]);
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

/* The covered pixel centre of a record whose box holds one pixel centre, resolved in setup: what
 * the depth test and the buffer write need, the values tile_job would compute for it. */
typedef struct {
    double iw;     /* interpolated 1 / view depth (the depth test compares it before rounding) */
    float bary[3];
    int x, y, mesh, tri;
    unsigned char back, fan;
} frag;

/* A vertex seen by the camera: screen position (valid when z >= znear) and view depth. */
typedef struct {
    double sx, sy, z;
} pvert;

/* A vertex's pixel-centre key: cx = ceil(sx - 0.5) clamped to [0, w], fx = floor(sx - 0.5)
 * clamped to [-1, w - 1], cy and fy likewise.  ceil and floor commute with min and max, so a
 * triangle wholly in front of the near plane has no pixel centre in its bounding box (setup_tri's
 * x0 >= x1 or y0 >= y1, which the clamps preserve) exactly when max fx < min cx or max fy < min cy:
 * setup_job rejects most triangles of a dense mesh (smaller than a pixel) from these 8 bytes per
 * corner instead of the 24 of pvert.  fx and fy are stored negated, so a triangle's box (min cx,
 * max fx, min cy, max fy) is the minimum of its corners' keys, lane by lane.  A vertex behind the
 * near plane (or not finite) gets a key that never rejects (all lanes SHRT_MIN). */
typedef struct {
    short cx, nfx, cy, nfy; /* nfx = -fx, nfy = -fy */
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
    long maxlist, maxfrags; /* longest tile list, most fragments of a tile */
    size_t tile_buf_len; /* per worker */
    void *tile_buf;   /* per worker: a tile_z, maxlist records (a tile's, in list order), then 2 (maxlist + maxfrags)
                         keys and as many indices (sort_keys) */
    long nchunks, group, ngroups; /* setup: chunks of CHUNK global triangles, `group` chunks per call */
    rtri **chunk_recs; /* per chunk: its records, in triangle order */
    long *chunk_count; /* their number; -1: out of memory */
    frag **chunk_frags; /* per chunk: its fragments, in triangle order */
    long *chunk_nfrags; /* their number */
    long *bin;         /* per group: per tile its records' references, then per tile its fragments (counts,
                          then where they go) */
    pvert *corners;    /* per worker: 3 CHUNK triangle corners */
    long *cand;        /* per worker: CHUNK triangles the keys do not reject */
    pkey *cand_box;    /* their keys' box: the minimum of the corners' keys */
    long *tile_first, *frag_first;
    const rtri **tile_list;
    frag *tile_frags;  /* the fragments, tile by tile */
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

/* *ceil_key = ceil(s - 0.5) clamped to [0, n] and *floor_key = floor(s - 0.5) clamped to [-1, n - 1]
 * (s finite), from one truncation where it is exact (0 <= t < n). */
static void key_pair(double s, int n, short *ceil_key, short *floor_key)
{
    const double t = s - 0.5;
    const int k = t < 0.0 ? -1 : t >= n ? n - 1 : (int)t;
    *floor_key = (short)k;
    *ceil_key = (short)(t < 0.0 ? 0 : t >= n ? n : k + (t > k));
}

static void project_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    const ctx_t *c = arg;
    const ctx_t cam = *c; /* a copy the stores below cannot alias: its doubles stay in registers */
    int m = 0;
    for (long g = begin; g < end;) { /* mesh by mesh */
        while (g >= cam.first_vert[m + 1]) ++m;
        const long mesh_end = cam.first_vert[m + 1] < end ? cam.first_vert[m + 1] : end;
        const double *x = cam.meshes[m].pos + 3 * (g - cam.first_vert[m]);
        pvert *q = &cam.pv[g];
        pkey *k = &cam.key[g];
        for (; g < mesh_end; ++g, x += 3, ++q, ++k) {
            double v[3];
            view_space(&cam, x, v);
            const int seen = v[2] >= cam.znear;
            q->z = v[2];
            q->sx = seen ? screen_x(&cam, v) : 0.0;
            q->sy = seen ? screen_y(&cam, v) : 0.0;
            if (cam.keyed && seen && isfinite(q->sx) && isfinite(q->sy)) {
                short fx, fy;
                key_pair(q->sx, cam.w, &k->cx, &fx);
                key_pair(q->sy, cam.h, &k->cy, &fy);
                k->nfx = (short)-fx;
                k->nfy = (short)-fy;
            } else
                *k = (pkey){SHRT_MIN, SHRT_MIN, SHRT_MIN, SHRT_MIN};
        }
    }
}

/* The pixel centres x0 <= x < x1, y0 <= y < y1 in the box of the triangle id of (sx, sy); 0 if none. */
static int pixel_box(const ctx_t *c, const double *sx, const double *sy, const int id[3], int *x0, int *x1, int *y0, int *y1)
{
    double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
    for (int k = 0; k < 3; ++k) {
        minx = sx[id[k]] < minx ? sx[id[k]] : minx; /* finite coordinates: as fmin, fmax */
        maxx = sx[id[k]] > maxx ? sx[id[k]] : maxx;
        miny = sy[id[k]] < miny ? sy[id[k]] : miny;
        maxy = sy[id[k]] > maxy ? sy[id[k]] : maxy;
    }
    /* as fmax(0, .) and fmin(w, .), NaN included, without the library calls */
    const double cx = ceil(minx - 0.5), fx = floor(maxx - 0.5) + 1.0, cy = ceil(miny - 0.5), fy = floor(maxy - 0.5) + 1.0;
    const double bx0 = cx > 0.0 ? cx : 0.0, bx1 = fx < c->w ? fx : (double)c->w;
    const double by0 = cy > 0.0 ? cy : 0.0, by1 = fy < c->h ? fy : (double)c->h;
    if (bx0 >= bx1 || by0 >= by1) return 0;
    *x0 = (int)bx0;
    *x1 = (int)bx1;
    *y0 = (int)by0;
    *y1 = (int)by1;
    return 1;
}

/* A record's edge functions. */
typedef struct {
    double area, ax[3], ay[3], ex[3], ey[3], sg[3];
    int bias[3];
} edges;

/* Twice the record's signed screen area (positive: setup_tri orients records so). */
static double record_area(const rtri *r)
{
    return (r->x[1] - r->x[0]) * (r->y[2] - r->y[0]) - (r->x[2] - r->x[0]) * (r->y[1] - r->y[0]);
}

/* From the record's screen positions x, y only. */
static void edge_setup(const rtri *r, edges *e)
{
    e->area = record_area(r);
    for (int k = 0; k < 3; ++k) { /* edge k is opposite vertex k: E_k = area * lambda_k */
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        const double dx = r->x[b] - r->x[a], dy = r->y[b] - r->y[a];
        /* E_k = (p - A) x (B - A) from the edge's lexicographically smaller end A, times -1 if
         * the triangle runs A -> B: the two triangles sharing an edge evaluate the same
         * products and get exactly opposite values, so no pixel centre falls between them */
        const int fwd = r->x[a] < r->x[b] || (r->x[a] == r->x[b] && r->y[a] < r->y[b]);
        const int lo = fwd ? a : b, hi = fwd ? b : a;
        e->ax[k] = r->x[lo];
        e->ay[k] = r->y[lo];
        e->ex[k] = r->x[hi] - r->x[lo];
        e->ey[k] = r->y[hi] - r->y[lo];
        e->sg[k] = fwd ? -1.0 : 1.0;
        e->bias[k] = dy > 0 || (dy == 0 && dx < 0); /* ties: exactly one of two triangles sharing the edge */
    }
}

/* 1 when pixel (x, y)'s centre is inside; l: the edge functions there, E_k. */
static int pixel_inside(const edges *e, int x, int y, double l[3])
{
    const double px = x + 0.5, py = y + 0.5;
    for (int k = 0; k < 3; ++k) {
        l[k] = e->sg[k] * ((px - e->ax[k]) * e->ey[k] - (py - e->ay[k]) * e->ex[k]);
        if (!(l[k] > 0 || (l[k] == 0 && e->bias[k]))) return 0;
    }
    return 1;
}

/* pixel_inside for one pixel, without data-dependent branches (most one-pixel records cover
 * nothing, unpredictably) and without edge_setup.  With the record's directed edge (dx, dy) = B - A
 * and its lexicographically smaller end L, pixel_inside's E_k is -((p - L) x (dx, dy)) up to the
 * sign of a zero: the same products, with negated operands when L is B.  A pixel centre on an edge
 * (some E_k zero) gets pixel_inside's own values. */
static int pixel_covered(const rtri *r, int x, int y, double l[3])
{
    const double px = x + 0.5, py = y + 0.5;
    double minus_e[3];
    int inside = 1, on_edge = 0;
    for (int k = 0; k < 3; ++k) {
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        const double xa = r->x[a], ya = r->y[a], xb = r->x[b], yb = r->y[b];
        const int fwd = (xa < xb) | ((xa == xb) & (ya < yb)), lo = b + fwd * (a - b); /* index arithmetic: no branch */
        const double lx = r->x[lo], ly = r->y[lo], dx = xb - xa, dy = yb - ya;
        minus_e[k] = (px - lx) * dy - (py - ly) * dx;
        inside &= (minus_e[k] < 0) | ((minus_e[k] == 0) & ((dy > 0) | ((dy == 0) & (dx < 0))));
        on_edge |= minus_e[k] == 0;
    }
    if (!inside) return 0;
    if (on_edge) {
        edges e;
        edge_setup(r, &e);
        return pixel_inside(&e, x, y, l);
    }
    for (int k = 0; k < 3; ++k) l[k] = -minus_e[k];
    return 1;
}

/* The perspective-correct weights before normalization at an inside pixel of edge functions l:
 * w[k] = lambda_k / view depth_k; returns their sum, the pixel's 1 / view depth. */
static double pixel_weights(const rtri *r, double area, const double l[3], double w[3])
{
    for (int k = 0; k < 3; ++k) w[k] = l[k] / area * r->iw[k];
    return w[0] + w[1] + w[2];
}

/* The source triangle's barycentrics at a pixel of weights w, iw = w0 + w1 + w2. */
static void pixel_bary(const rtri *r, const double w[3], double iw, float bary[3])
{
    for (int j = 0; j < 3; ++j) bary[j] = (float)((w[0] * r->b[0][j] + w[1] * r->b[1][j] + w[2] * r->b[2][j]) / iw);
}

static int tile_of(const ctx_t *c, int x, int y) { return y / TILE * c->tiles_x + x / TILE; }

/* tile: each tile the record's pixel box [x0, x1) x [y0, y1) meets, row by row. */
#define FOR_TILES(c, r, tile) \
    for (int ty_ = (r)->y0 / TILE; ty_ <= ((r)->y1 - 1) / TILE; ++ty_) \
        for (int tx_ = (r)->x0 / TILE, tile = ty_ * (c)->tiles_x + tx_; tx_ <= ((r)->x1 - 1) / TILE; ++tx_, ++tile)

/* setup_tri's output: records and fragments appended, and counted per tile in bin (a group's
 * counters: records per tile, then fragments per tile). */
typedef struct {
    rtri *recs;
    frag *frags;
    long nrecs, nfrags, *bin;
} setup_out;

/* Clip the triangle to forward >= znear, project, and emit up to 2 records.  A record whose box
 * holds one pixel centre (most triangles of a dense mesh are smaller than a pixel) is resolved
 * here instead: into the fragment of that centre if it covers it, else into nothing.
 * pv: its corners' projections (project_job); a triangle wholly in front of the near plane
 * (the common case) uses them, the same values the clipping path computes.  box: the corners'
 * keys combined (setup_job); when all three are keys (cx >= 0), the pixel box of such a triangle. */
static void setup_tri(const ctx_t *c, int m, int t, const pvert pv[3], const pkey *box, setup_out *out)
{
    const raster_mesh *rm = &c->meshes[m];
    const int *tv = rm->tri + 3 * (size_t)t;
    double sx[4], sy[4], z[4];
    float b[4][3];
    int n = 0;
    const int unclipped = pv[0].z >= c->znear && pv[1].z >= c->znear && pv[2].z >= c->znear;
    if (unclipped) {
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
        if (n < 3) return;
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
        int x0, x1, y0, y1;
        if (unclipped && box->cx >= 0) { /* the same box (pkey) */
            x0 = box->cx;
            x1 = 1 - box->nfx;
            y0 = box->cy;
            y1 = 1 - box->nfy;
        } else if (!pixel_box(c, sx, sy, id, &x0, &x1, &y0, &y1))
            continue;
        const double area = (sx[id[1]] - sx[id[0]]) * (sy[id[2]] - sy[id[0]]) - (sx[id[2]] - sx[id[0]]) * (sy[id[1]] - sy[id[0]]);
        if (area == 0.0) continue;
        rtri *r = &out->recs[out->nrecs];
        const int swap = area < 0; /* orient to positive area; y points down, so front faces have area < 0 */
        const int order[3] = {id[0], swap ? id[2] : id[1], swap ? id[1] : id[2]};
        for (int k = 0; k < 3; ++k) {
            r->x[k] = sx[order[k]];
            r->y[k] = sy[order[k]];
        }
        const int one_pixel = x1 - x0 == 1 && y1 - y0 == 1;
        double l[3];
        if (one_pixel && !pixel_covered(r, x0, y0, l)) {
            ++emitted;
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            r->iw[k] = (float)(1.0 / z[order[k]]);
            memcpy(r->b[k], b[order[k]], sizeof r->b[k]);
        }
        r->x0 = x0;
        r->x1 = x1;
        r->y0 = y0;
        r->y1 = y1;
        r->mesh = m;
        r->tri = rm->tri_id ? rm->tri_id[t] : t;
        r->back = !swap;
        r->fan = (unsigned char)emitted++;
        if (!one_pixel) {
            FOR_TILES(c, r, tile) ++out->bin[tile];
            ++out->nrecs;
            continue;
        }
        frag *fr = &out->frags[out->nfrags++]; /* the record in its one pixel, as draw_record would draw it */
        double w[3];
        fr->iw = pixel_weights(r, record_area(r), l, w);
        pixel_bary(r, w, fr->iw, fr->bary);
        fr->x = x0;
        fr->y = y0;
        fr->mesh = r->mesh;
        fr->tri = r->tri;
        fr->back = r->back;
        fr->fan = r->fan;
        ++out->bin[c->ntiles + tile_of(c, x0, y0)];
    }
}

/* A block of memory shrunk to `bytes` (kept as it is if realloc fails); NULL and freed when bytes is 0. */
static void *shrink(void *block, size_t bytes)
{
    if (!bytes) {
        free(block);
        return NULL;
    }
    void *fit = realloc(block, bytes);
    return fit ? fit : block;
}

/* Set up the triangles of chunks [begin, end) (one group): the keys reject the triangles without
 * a pixel centre in their box, the others' records and fragments (setup_tri) go to blocks for 2
 * a candidate, then shrunk to their number; the group's references and fragments per tile are
 * counted for the binning. */
static void setup_job(void *arg, int worker, long begin, long end)
{
    ctx_t *c = arg;
    const long ntri = c->first_tri[c->nmeshes];
    pvert *corner = c->corners + 3 * CHUNK * (size_t)worker;
    pkey *cand_box = c->cand_box + CHUNK * (size_t)worker;
    long *cand = c->cand + CHUNK * (size_t)worker, *bin = c->bin + (size_t)(begin / c->group) * 2 * (size_t)c->ntiles;
    for (long ch = begin; ch < end; ++ch) {
        const long g0 = ch * CHUNK, g1 = ntri < g0 + CHUNK ? ntri : g0 + CHUNK;
        long nc = 0;
        int m = 0;
        for (long g = g0; g < g1;) { /* mesh by mesh */
            while (g >= c->first_tri[m + 1]) ++m;
            const long mesh_end = c->first_tri[m + 1] < g1 ? c->first_tri[m + 1] : g1;
            const int *tv = c->meshes[m].tri + 3 * (size_t)(g - c->first_tri[m]);
            const pkey *k = c->key + c->first_vert[m];
            /* no data-dependent branches: many of these scattered loads stay in flight */
            for (; g < mesh_end; ++g, tv += 3) {
                const pkey *a = &k[tv[0]], *b = &k[tv[1]], *d = &k[tv[2]];
                pkey box = *a;
                box.cx = b->cx < box.cx ? b->cx : box.cx;
                box.nfx = b->nfx < box.nfx ? b->nfx : box.nfx;
                box.cy = b->cy < box.cy ? b->cy : box.cy;
                box.nfy = b->nfy < box.nfy ? b->nfy : box.nfy;
                box.cx = d->cx < box.cx ? d->cx : box.cx;
                box.nfx = d->nfx < box.nfx ? d->nfx : box.nfx;
                box.cy = d->cy < box.cy ? d->cy : box.cy;
                box.nfy = d->nfy < box.nfy ? d->nfy : box.nfy;
                cand[nc] = g;
                cand_box[nc] = box;
                nc += (box.cx + box.nfx <= 0) & (box.cy + box.nfy <= 0); /* max fx >= min cx, max fy >= min cy */
            }
        }
        m = 0;
        for (long i = 0; i < nc; ++i) {
            while (cand[i] >= c->first_tri[m + 1]) ++m;
            const int *tv = c->meshes[m].tri + 3 * (size_t)(cand[i] - c->first_tri[m]);
            const pvert *pv = c->pv + c->first_vert[m];
            for (int k = 0; k < 3; ++k) corner[3 * i + k] = pv[tv[k]];
        }
        /* at most 2 records a triangle, or their fragments */
        setup_out out = {nc ? malloc(sizeof(rtri) * 2 * (size_t)nc) : NULL, nc ? malloc(sizeof(frag) * 2 * (size_t)nc) : NULL, 0, 0, bin};
        if (nc && (!out.recs || !out.frags)) {
            free(out.recs);
            free(out.frags);
            c->chunk_count[ch] = -1; /* out of memory, seen by raster_draw */
            continue;
        }
        m = 0;
        for (long i = 0; i < nc; ++i) {
            while (cand[i] >= c->first_tri[m + 1]) ++m;
            setup_tri(c, m, (int)(cand[i] - c->first_tri[m]), corner + 3 * i, &cand_box[i], &out);
        }
        c->chunk_recs[ch] = shrink(out.recs, sizeof(rtri) * (size_t)out.nrecs);
        c->chunk_count[ch] = out.nrecs;
        c->chunk_frags[ch] = shrink(out.frags, sizeof(frag) * (size_t)out.nfrags);
        c->chunk_nfrags[ch] = out.nfrags;
    }
}

/* The group's references and fragments into the tile lists, from the offsets the prefix sum left in bin. */
static void bin_job(void *arg, int worker, long begin, long end)
{
    (void)worker;
    ctx_t *c = arg;
    long *bin = c->bin + (size_t)(begin / c->group) * 2 * (size_t)c->ntiles;
    for (long ch = begin; ch < end; ++ch) {
        for (long i = 0; i < c->chunk_count[ch]; ++i) {
            const rtri *r = &c->chunk_recs[ch][i];
            FOR_TILES(c, r, t) c->tile_list[bin[t]++] = r;
        }
        for (long i = 0; i < c->chunk_nfrags[ch]; ++i) {
            const frag *f = &c->chunk_frags[ch][i];
            c->tile_frags[bin[c->ntiles + tile_of(c, f->x, f->y)]++] = *f;
        }
    }
}

/* The drawing order of a record or fragment: that of the unreordered meshes' triangles (tri is
 * raster_mesh.tri_id's), then the fan record. */
static uint64_t order_key(const ctx_t *c, int mesh, int tri, int fan)
{
    return (uint64_t)(c->first_tri[mesh] + tri) << 1 | (uint64_t)fan;
}

/* order[0 .. n): the indices of key[0 .. n) in key order (stable LSD radix sort on 8-bit digits:
 * a tile has a few hundred keys); the keys are left in an unspecified order.  key and order hold
 * 2 n words each, the second n scratch. */
static void sort_keys(const ctx_t *c, uint64_t *key, long *order, long n)
{
    enum { BITS = 8, RADIX = 1 << BITS };
    for (long i = 0; i < n; ++i) order[i] = i;
    uint64_t *k[2] = {key, key + n};
    long *idx[2] = {order, order + n};
    const uint64_t top = (uint64_t)c->first_tri[c->nmeshes] << 1;
    int from = 0;
    for (int shift = 0; shift == 0 || top >> shift; shift += BITS, from ^= 1) {
        long count[RADIX + 1] = {0};
        for (long i = 0; i < n; ++i) ++count[(k[from][i] >> shift & (RADIX - 1)) + 1];
        for (int d = 0; d < RADIX; ++d) count[d + 1] += count[d];
        for (long i = 0; i < n; ++i) {
            const long at = count[k[from][i] >> shift & (RADIX - 1)]++;
            k[from ^ 1][at] = k[from][i];
            idx[from ^ 1][at] = idx[from][i];
        }
    }
    if (from) memcpy(order, idx[1], sizeof(long) * (size_t)n);
}

/* A tile's depth, mesh and triangle, in the cache while its records and fragments are drawn, then
 * copied to the frame buffer; back and bary go to the frame buffer directly. */
typedef struct {
    float depth[TILE * TILE];
    int mesh[TILE * TILE], tri[TILE * TILE];
    int x0, y0; /* the tile's first pixel */
} tile_z;

/* The z-buffer keeps the first of equal depths (deterministic ties): pixel (x, y) gets the fragment
 * when its 1 / depth iw is larger; bary is then written by the caller. */
static int depth_test_store(tile_z *z, framebuf *fb, int x, int y, double iw, int mesh, int tri, unsigned char back)
{
    const int i = (y - z->y0) * TILE + (x - z->x0);
    if (!(iw > z->depth[i])) return 0;
    z->depth[i] = (float)iw;
    z->mesh[i] = mesh;
    z->tri[i] = tri;
    fb->back[(size_t)y * (size_t)fb->w + (size_t)x] = back;
    return 1;
}

/* The record's pixels within [x0, x1) x [y0, y1). */
static void draw_record(const ctx_t *c, tile_z *z, const rtri *r, int x0, int y0, int x1, int y1)
{
    edges e;
    edge_setup(r, &e);
    x0 = r->x0 > x0 ? r->x0 : x0;
    x1 = r->x1 < x1 ? r->x1 : x1;
    y0 = r->y0 > y0 ? r->y0 : y0;
    y1 = r->y1 < y1 ? r->y1 : y1;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            double l[3], w[3];
            if (!pixel_inside(&e, x, y, l)) continue;
            const size_t p = (size_t)y * (size_t)c->w + (size_t)x;
            const double iw = pixel_weights(r, e.area, l, w);
            if (depth_test_store(z, c->fb, x, y, iw, r->mesh, r->tri, r->back)) pixel_bary(r, w, iw, c->fb->bary + 3 * p);
        }
}

/* Rasterize one tile: its records and fragments in the order of the unreordered meshes' triangles. */
static void tile_job(void *arg, int worker, long begin, long end)
{
    ctx_t *c = arg;
    framebuf *fb = c->fb;
    tile_z *z = (tile_z *)((char *)c->tile_buf + c->tile_buf_len * (size_t)worker);
    rtri *local = (rtri *)(z + 1);
    uint64_t *key = (uint64_t *)(local + c->maxlist);
    long *order = (long *)(key + 2 * (size_t)(c->maxlist + c->maxfrags));
    for (long tile = begin; tile < end; ++tile) {
        const rtri **list = c->tile_list + c->tile_first[tile];
        const long n = c->tile_first[tile + 1] - c->tile_first[tile];
        const frag *fr = c->tile_frags + c->frag_first[tile];
        const long nf = c->frag_first[tile + 1] - c->frag_first[tile];
        /* the tile's records gathered first, in memory order (independent loads, many misses in
         * flight), then sorted in the cache by index */
        for (long i = 0; i < n; ++i) local[i] = *list[i];
        /* the records (indices 0 .. n), then the fragments (n .. n + nf) */
        for (long i = 0; i < n; ++i) key[i] = order_key(c, local[i].mesh, local[i].tri, local[i].fan);
        for (long i = 0; i < nf; ++i) key[n + i] = order_key(c, fr[i].mesh, fr[i].tri, fr[i].fan);
        sort_keys(c, key, order, n + nf);
        const int tx0 = (int)(tile % c->tiles_x) * TILE, ty0 = (int)(tile / c->tiles_x) * TILE;
        const int tx1 = tx0 + TILE < c->w ? tx0 + TILE : c->w, ty1 = ty0 + TILE < c->h ? ty0 + TILE : c->h;
        for (int i = 0; i < TILE * TILE; ++i) {
            z->depth[i] = 0.0f;
            z->mesh[i] = z->tri[i] = -1;
        }
        z->x0 = tx0;
        z->y0 = ty0;
        for (long i = 0; i < n + nf; ++i) {
            const long item = order[i];
            if (item < n) {
                draw_record(c, z, &local[item], tx0, ty0, tx1, ty1);
                continue;
            }
            const frag *f = &fr[item - n];
            if (depth_test_store(z, fb, f->x, f->y, f->iw, f->mesh, f->tri, f->back))
                memcpy(fb->bary + 3 * ((size_t)f->y * (size_t)c->w + (size_t)f->x), f->bary, sizeof f->bary);
        }
        for (int y = ty0; y < ty1; ++y) {
            const size_t p = (size_t)y * (size_t)c->w + (size_t)tx0, len = (size_t)(tx1 - tx0);
            memcpy(fb->depth + p, z->depth + (y - ty0) * TILE, sizeof(float) * len);
            memcpy(fb->mesh + p, z->mesh + (y - ty0) * TILE, sizeof(int) * len);
            memcpy(fb->tri + p, z->tri + (y - ty0) * TILE, sizeof(int) * len);
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
    /* about 16 groups a worker (the prefix sum reads ngroups * ntiles counters), at most ~2M counters */
    c.group = 1 + nchunks / (16 * nw) + (long)((double)nchunks * 2 * ntiles / (1 << 21));
    c.ngroups = (nchunks + c.group - 1) / c.group;
    c.pv = work(fb, 0, sizeof(pvert) * (size_t)(c.first_vert[nmeshes] + 1));
    c.key = work(fb, 1, sizeof(pkey) * (size_t)(c.first_vert[nmeshes] + 1));
    c.chunk_recs = calloc((size_t)nchunks + 1, sizeof(rtri *));
    c.chunk_count = malloc(sizeof(long) * 2 * (size_t)(nchunks + 1));
    c.chunk_nfrags = c.chunk_count + nchunks + 1;
    c.chunk_frags = calloc((size_t)nchunks + 1, sizeof(frag *));
    c.bin = calloc((size_t)c.ngroups * 2 * (size_t)ntiles + 1, sizeof(long));
    c.corners = work(fb, 2, (sizeof(pvert) * 3 + sizeof(long) + sizeof(pkey)) * CHUNK * (size_t)nw);
    if (!c.pv || !c.key || !c.chunk_recs || !c.chunk_count || !c.chunk_frags || !c.bin || !c.corners) goto done;
    c.cand = (long *)(c.corners + 3 * CHUNK * (size_t)nw);
    c.cand_box = (pkey *)(c.cand + CHUNK * (size_t)nw);
    par_for(c.first_vert[nmeshes], 8192, nw, project_job, &c);
    par_for(nchunks, c.group, nw, setup_job, &c);
    for (long ch = 0; ch < nchunks; ++ch)
        if (c.chunk_count[ch] < 0) goto done;
    c.tile_first = malloc(sizeof(long) * 2 * ((size_t)ntiles + 1));
    if (!c.tile_first) goto done;
    c.frag_first = c.tile_first + ntiles + 1;
    long refs = 0, frags = 0; /* binning: tile lists in tile order, each in record order (group by group) */
    for (int t = 0; t < ntiles; ++t) {
        c.tile_first[t] = refs;
        c.frag_first[t] = frags;
        for (long gr = 0; gr < c.ngroups; ++gr) {
            long *b = &c.bin[(size_t)gr * 2 * (size_t)ntiles + (size_t)t], *bf = b + ntiles;
            const long k = *b, kf = *bf;
            *b = refs;
            *bf = frags;
            refs += k;
            frags += kf;
        }
        c.maxlist = refs - c.tile_first[t] > c.maxlist ? refs - c.tile_first[t] : c.maxlist;
        c.maxfrags = frags - c.frag_first[t] > c.maxfrags ? frags - c.frag_first[t] : c.maxfrags;
    }
    c.tile_first[ntiles] = refs;
    c.frag_first[ntiles] = frags;
    c.tile_list = work(fb, 4, sizeof(rtri *) * (size_t)(refs + 1));
    c.tile_frags = work(fb, 5, sizeof(frag) * (size_t)(frags + 1));
    if (!c.tile_list || !c.tile_frags) goto done;
    par_for(nchunks, c.group, nw, bin_job, &c);
    c.tile_buf_len = sizeof(tile_z) + sizeof(rtri) * (size_t)c.maxlist + sizeof(uint64_t) * 4 * (size_t)(c.maxlist + c.maxfrags);
    if (!(c.tile_buf = work(fb, 3, c.tile_buf_len * (size_t)nw + 1))) goto done;
    par_for(ntiles, 1, nw, tile_job, &c);
    st = 0;
done:
    if (st) /* the background: no visibility */
        for (size_t p = 0; p < (size_t)fb->w * (size_t)fb->h; ++p) {
            fb->depth[p] = 0.0f;
            fb->mesh[p] = fb->tri[p] = -1;
        }
    free(c.first_tri);
    free(c.first_vert);
    for (long ch = 0; ch < c.nchunks; ++ch) {
        if (c.chunk_recs) free(c.chunk_recs[ch]);
        if (c.chunk_frags) free(c.chunk_frags[ch]);
    }
    free(c.chunk_recs);
    free(c.chunk_frags);
    free(c.chunk_count);
    free(c.bin);
    free(c.tile_first);
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
