#include "bvh.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    float lo[3], hi[3];
    int first; /* leaf: first triangle; inner: left child (right = first + 1) */
    int count; /* leaf: triangle count; inner: 0 */
} node;

typedef struct {
    float v0[3], e1[3], e2[3];
    int id;
} tri_t;

struct bvh {
    node *nodes;
    tri_t *tris;
    int nnodes;
};

enum { BINS = 12, LEAF = 4, DEEP = 48, STACK = 96 }; /* depth <= DEEP + 31 < STACK */

typedef struct {
    float lo[3], hi[3];
} box;

static void box_empty(box *b)
{
    for (int a = 0; a < 3; ++a) {
        b->lo[a] = FLT_MAX;
        b->hi[a] = -FLT_MAX;
    }
}
static void box_grow(box *b, const float *lo, const float *hi)
{
    for (int a = 0; a < 3; ++a) {
        b->lo[a] = fminf(b->lo[a], lo[a]);
        b->hi[a] = fmaxf(b->hi[a], hi[a]);
    }
}
static float box_area(const box *b)
{
    const float x = b->hi[0] - b->lo[0], y = b->hi[1] - b->lo[1], z = b->hi[2] - b->lo[2];
    return x < 0 ? 0 : x * y + y * z + z * x;
}

typedef struct {
    float lo[3], hi[3], c[3];
} prim;

/* Build the subtree of prims idx[first .. first+count) into node n. */
static void build(bvh *b, prim *p, int *idx, int n, int first, int count, int depth)
{
    box bb, cb;
    box_empty(&bb);
    box_empty(&cb);
    for (int i = first; i < first + count; ++i) {
        box_grow(&bb, p[idx[i]].lo, p[idx[i]].hi);
        box_grow(&cb, p[idx[i]].c, p[idx[i]].c);
    }
    node *nd = &b->nodes[n];
    memcpy(nd->lo, bb.lo, sizeof nd->lo);
    memcpy(nd->hi, bb.hi, sizeof nd->hi);
    nd->first = first;
    nd->count = count;
    if (count <= LEAF) return;
    int best_axis = -1, best_split = 0;
    float best_cost = box_area(&bb) * (float)count; /* SAH, scaled by the node's area: a leaf */
    if (depth >= DEEP) best_cost = -1.0f;           /* deep: balanced split, bounds the depth */
    for (int a = 0; a < 3; ++a) {
        const float ext = cb.hi[a] - cb.lo[a];
        if (!(ext > 0)) continue;
        box bin[BINS];
        int cnt[BINS] = {0};
        for (int k = 0; k < BINS; ++k) box_empty(&bin[k]);
        for (int i = first; i < first + count; ++i) {
            int k = (int)((p[idx[i]].c[a] - cb.lo[a]) / ext * BINS);
            k = k < 0 ? 0 : k >= BINS ? BINS - 1 : k;
            ++cnt[k];
            box_grow(&bin[k], p[idx[i]].lo, p[idx[i]].hi);
        }
        float right_area[BINS];
        int right_cnt[BINS];
        box acc;
        box_empty(&acc);
        int c = 0;
        for (int k = BINS - 1; k > 0; --k) {
            box_grow(&acc, bin[k].lo, bin[k].hi);
            c += cnt[k];
            right_area[k] = box_area(&acc);
            right_cnt[k] = c;
        }
        box_empty(&acc);
        c = 0;
        for (int k = 0; k < BINS - 1; ++k) {
            box_grow(&acc, bin[k].lo, bin[k].hi);
            c += cnt[k];
            const float cost = box_area(&bb) + box_area(&acc) * (float)c + right_area[k + 1] * (float)right_cnt[k + 1];
            if (c > 0 && right_cnt[k + 1] > 0 && cost < best_cost) {
                best_cost = cost;
                best_axis = a;
                best_split = k;
            }
        }
    }
    int mid;
    if (best_axis < 0) {
        if (count <= 4 * LEAF && depth < DEEP) return; /* coincident centroids, small set: a leaf */
        mid = first + count / 2;       /* otherwise split in index order */
    } else {
        const float ext = cb.hi[best_axis] - cb.lo[best_axis];
        int i = first, j = first + count - 1;
        while (i <= j) {
            int k = (int)((p[idx[i]].c[best_axis] - cb.lo[best_axis]) / ext * BINS);
            k = k < 0 ? 0 : k >= BINS ? BINS - 1 : k;
            if (k <= best_split)
                ++i;
            else {
                const int t = idx[i];
                idx[i] = idx[j];
                idx[j--] = t;
            }
        }
        mid = i;
    }
    const int left = b->nnodes;
    b->nnodes += 2;
    nd->first = left;
    nd->count = 0;
    build(b, p, idx, left, first, mid - first, depth + 1);
    build(b, p, idx, left + 1, mid, first + count - mid, depth + 1);
}

bvh *bvh_build(const mesh *m)
{
    bvh *b = calloc(1, sizeof *b);
    prim *p = malloc(sizeof *p * (size_t)(m->nt ? m->nt : 1));
    int *idx = malloc(sizeof *idx * (size_t)(m->nt ? m->nt : 1));
    if (b) {
        b->nodes = malloc(sizeof *b->nodes * (size_t)(2 * m->nt + 1));
        b->tris = malloc(sizeof *b->tris * (size_t)(m->nt ? m->nt : 1));
    }
    if (!b || !p || !idx || !b->nodes || !b->tris) {
        free(p);
        free(idx);
        bvh_free(b);
        return NULL;
    }
    for (int t = 0; t < m->nt; ++t) {
        idx[t] = t;
        for (int a = 0; a < 3; ++a) {
            const double x = m->pos[3 * m->tri[3 * t] + a], y = m->pos[3 * m->tri[3 * t + 1] + a],
                         z = m->pos[3 * m->tri[3 * t + 2] + a];
            p[t].lo[a] = (float)fmin(x, fmin(y, z));
            p[t].hi[a] = (float)fmax(x, fmax(y, z));
            p[t].c[a] = 0.5f * (p[t].lo[a] + p[t].hi[a]);
        }
    }
    b->nnodes = 1;
    build(b, p, idx, 0, 0, m->nt, 0);
    for (int i = 0; i < m->nt; ++i) {
        const int t = idx[i];
        tri_t *q = &b->tris[i];
        const double *v0 = m->pos + 3 * m->tri[3 * t], *v1 = m->pos + 3 * m->tri[3 * t + 1], *v2 = m->pos + 3 * m->tri[3 * t + 2];
        for (int a = 0; a < 3; ++a) {
            q->v0[a] = (float)v0[a];
            q->e1[a] = (float)(v1[a] - v0[a]);
            q->e2[a] = (float)(v2[a] - v0[a]);
        }
        q->id = t;
    }
    free(p);
    free(idx);
    return b;
}

void bvh_free(bvh *b)
{
    if (!b) return;
    free(b->nodes);
    free(b->tris);
    free(b);
}

/* Moller-Trumbore; t in (0, tmax) or INFINITY. */
static inline float hit_tri(const tri_t *q, const float o[3], const float d[3], float tmax, float *u, float *v)
{
    const float px = d[1] * q->e2[2] - d[2] * q->e2[1], py = d[2] * q->e2[0] - d[0] * q->e2[2],
                pz = d[0] * q->e2[1] - d[1] * q->e2[0];
    const float det = q->e1[0] * px + q->e1[1] * py + q->e1[2] * pz;
    if (fabsf(det) < 1e-20f) return INFINITY;
    const float inv = 1.0f / det, sx = o[0] - q->v0[0], sy = o[1] - q->v0[1], sz = o[2] - q->v0[2];
    const float uu = (sx * px + sy * py + sz * pz) * inv;
    if (uu < 0.0f || uu > 1.0f) return INFINITY;
    const float qx = sy * q->e1[2] - sz * q->e1[1], qy = sz * q->e1[0] - sx * q->e1[2], qz = sx * q->e1[1] - sy * q->e1[0];
    const float vv = (d[0] * qx + d[1] * qy + d[2] * qz) * inv;
    if (vv < 0.0f || uu + vv > 1.0f) return INFINITY;
    const float t = (q->e2[0] * qx + q->e2[1] * qy + q->e2[2] * qz) * inv;
    if (!(t > 0.0f && t < tmax)) return INFINITY;
    *u = uu;
    *v = vv;
    return t;
}

/* Entry distance of the ray into the node's box, or INFINITY if it misses before tmax. */
static inline float hit_box(const node *n, const float o[3], const float inv[3], float tmax)
{
    float t0 = 0.0f, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
        float ta = (n->lo[a] - o[a]) * inv[a], tb = (n->hi[a] - o[a]) * inv[a];
        if (ta > tb) {
            const float t = ta;
            ta = tb;
            tb = t;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    return t0 <= t1 ? t0 : INFINITY;
}

static int traverse(const bvh *b, const float o[3], const float d[3], float tmax, int any, float *t, float *u, float *v)
{
    const float inv[3] = {1.0f / d[0], 1.0f / d[1], 1.0f / d[2]};
    int stack[STACK], sp = 0, best = -1;
    if (hit_box(&b->nodes[0], o, inv, tmax) == INFINITY) return -1;
    stack[sp++] = 0;
    while (sp) {
        const node *n = &b->nodes[stack[--sp]];
        if (n->count) {
            for (int i = n->first; i < n->first + n->count; ++i) {
                float uu = 0.0f, vv = 0.0f;
                const float th = hit_tri(&b->tris[i], o, d, tmax, &uu, &vv);
                if (th < tmax) {
                    best = b->tris[i].id;
                    if (any) return best;
                    tmax = th;
                    *t = th;
                    *u = uu;
                    *v = vv;
                }
            }
            continue;
        }
        const int l = n->first, r = l + 1;
        const float tl = hit_box(&b->nodes[l], o, inv, tmax), tr = hit_box(&b->nodes[r], o, inv, tmax);
        if (tl <= tr) {
            if (tr != INFINITY) stack[sp++] = r;
            if (tl != INFINITY) stack[sp++] = l;
        } else {
            if (tl != INFINITY) stack[sp++] = l;
            stack[sp++] = r;
        }
    }
    return best;
}

int bvh_occluded(const bvh *b, const float o[3], const float d[3], float tmax)
{
    float t, u, v;
    return traverse(b, o, d, tmax, 1, &t, &u, &v) >= 0;
}

int bvh_closest(const bvh *b, const float o[3], const float d[3], float tmax, float *t, float *u, float *v)
{
    return traverse(b, o, d, tmax, 0, t, u, v);
}
