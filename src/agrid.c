/* Adaptive multi-level SH grids (include/shlight.h, shl_agrid_*): levels of
 * sparse uniform lattices refined, best first over all levels, where an
 * a-posteriori estimate (the interpolant against the float light-set batch at two
 * points per cell, for level 0 and the children of refined cells) exceeds the
 * tolerance, blended into a C0 interpolant; each level is Wu 2020 Alg. 4 on its cells.  The estimate is one
 * function (estimate_cells) over a list of cells of a level: an a-priori one
 * (e.g. from analytic Hessians) would replace it there. */
#include "agrid.h"
#include "lights.h"
#include "parallel.h"
#include <math.h>
#include <stdlib.h>

/* ---- lattice keys and the hash ---- */

enum { KEY_BITS = 21 }; /* lattice indices < 2^21: (SHL_GRID_RES_MAX - 1) 2^(SHL_AGRID_LEVELS_MAX - 1) < 2^17 */

static uint64_t key3(const int i[3])
{
    return ((uint64_t)i[0] << (2 * KEY_BITS) | (uint64_t)i[1] << KEY_BITS | (uint64_t)i[2]) + 1; /* 0: empty */
}

static void unkey(uint64_t k, int i[3])
{
    k -= 1;
    const uint64_t m = ((uint64_t)1 << KEY_BITS) - 1;
    i[0] = (int)(k >> (2 * KEY_BITS));
    i[1] = (int)(k >> KEY_BITS & m);
    i[2] = (int)(k & m);
}

static size_t slot(uint64_t k, size_t cap)
{
    uint64_t x = k * 0x9E3779B97F4A7C15u;
    x ^= x >> 29;
    return (size_t)x & (cap - 1);
}

/* Index stored under k, or -1. */
static long hfind(const shl__ahash *h, uint64_t k)
{
    if (!h->cap) return -1;
    for (size_t s = slot(k, h->cap);; s = (s + 1) & (h->cap - 1)) {
        if (h->key[s] == k) return (long)h->val[s];
        if (!h->key[s]) return -1;
    }
}

static void hset(shl__ahash *h, uint64_t k, uint32_t v)
{
    size_t s = slot(k, h->cap);
    while (h->key[s]) s = (s + 1) & (h->cap - 1);
    h->key[s] = k;
    h->val[s] = v;
    ++h->count;
}

/* The least table size (a power of two, at least 64) that holds n keys at load <= 1/2. */
static size_t hsize(size_t n)
{
    size_t cap = 64;
    while (cap < 2 * n) cap *= 2;
    return cap;
}

/* h rehashed into an empty table of cap slots (cap >= 2 h->count); SHL_ENOMEM leaves h as it was. */
static int hresize(shl__ahash *h, size_t cap)
{
    shl__ahash n = {shl__calloc(cap, sizeof(uint64_t)), shl__malloc(cap * sizeof(uint32_t)), cap, 0};
    if (!n.key || !n.val) {
        shl__free(n.key);
        shl__free(n.val);
        return SHL_ENOMEM;
    }
    for (size_t s = 0; s < h->cap; ++s)
        if (h->key[s]) hset(&n, h->key[s], h->val[s]);
    shl__free(h->key);
    shl__free(h->val);
    *h = n;
    return SHL_OK;
}

/* Room for one more key (load <= 1/2): after n keys the size is hsize(n); SHL_ENOMEM leaves h as it was. */
static int hreserve(shl__ahash *h)
{
    return 2 * (h->count + 1) <= h->cap ? SHL_OK : hresize(h, h->cap ? 2 * h->cap : 64);
}

/* *p (cap elements of size elem, used first) grown to newcap elements. */
static int regrow(void **p, size_t used, size_t newcap, size_t elem)
{
    void *q = shl__malloc(newcap * elem);
    if (!q) return SHL_ENOMEM;
    if (used) memcpy(q, *p, used * elem);
    shl__free(*p);
    *p = q;
    return SHL_OK;
}

/* ---- levels ---- */

static void level_free(shl__alevel *L)
{
    shl__free(L->nodes.key);
    shl__free(L->nodes.val);
    shl__free(L->cells.key);
    shl__free(L->cells.val);
    shl__free(L->node_key);
    shl__free(L->data);
    shl__free(L->flag);
    shl__free(L->cell);
    shl__free(L->cell_key);
    memset(L, 0, sizeof *L);
}

/* Level l's lattice, with room for its nodes and cells: on level 0 their counts, on a finer
 * level those of the grid's last fill (a refill of similar lights then grows no array; each
 * growth copied the arrays into fresh pages, and the copies and page faults took ~15% of a
 * fill).  SHL_ENOMEM: level_free(L) releases what was allocated. */
static int level_init(const shl_agrid *g, int l, shl__alevel *L)
{
    size_t nodes = 1, cells = 1;
    for (int a = 0; a < 3 && l == 0; ++a) nodes *= (size_t)g->res[a], cells *= (size_t)g->res[a] - 1;
    if (l > 0) nodes = l < g->nlevels ? g->lev[l].nnodes : 0, cells = l < g->nlevels ? g->lev[l].ncells : 0;
    memset(L, 0, sizeof *L);
    for (int a = 0; a < 3; ++a) {
        L->n[a] = (g->res[a] - 1) << l;
        L->h[a] = (g->hi[a] - g->lo[a]) / L->n[a]; /* = h_0 / 2^l exactly: node 2i of level l + 1 is node i of level l */
    }
    if (nodes > 0) {
        if (!(L->node_key = shl__malloc(nodes * sizeof *L->node_key)) || !(L->flag = shl__malloc(nodes)) ||
            !(L->data = shl__malloc(nodes * g->node_len * sizeof *L->data)) || hresize(&L->nodes, hsize(nodes)))
            return SHL_ENOMEM;
        L->node_cap = L->data_cap = nodes;
    }
    if (cells > 0) {
        if (!(L->cell_key = shl__malloc(cells * sizeof *L->cell_key)) || !(L->cell = shl__malloc(cells * sizeof *L->cell)) ||
            hresize(&L->cells, hsize(cells)))
            return SHL_ENOMEM;
        L->cell_cap = cells;
    }
    return SHL_OK;
}

static size_t level_bytes(const shl__alevel *L, size_t node_len)
{
    return (L->nodes.cap + L->cells.cap) * (sizeof(uint64_t) + sizeof(uint32_t)) +
           L->node_cap * (sizeof(uint64_t) + 1) + L->data_cap * node_len * sizeof(float) +
           L->cell_cap * (sizeof(shl__acell) + sizeof(uint64_t));
}

/* Add node i (not yet present); its data is left for eval_nodes. */
static int add_node(shl__alevel *L, const int i[3], size_t node_len)
{
    if (L->nnodes == L->node_cap) {
        const size_t cap = L->node_cap ? 2 * L->node_cap : 256;
        /* realloc (a large block may move by remapping instead of copying); each array is swapped
         * in as it grows and node_cap set only when all three have: a failure leaves L consistent */
        uint64_t *k = shl__realloc(L->node_key, cap * sizeof *k);
        if (!k) return SHL_ENOMEM;
        L->node_key = k;
        unsigned char *f = shl__realloc(L->flag, cap);
        if (!f) return SHL_ENOMEM;
        L->flag = f;
        float *d = shl__realloc(L->data, cap * node_len * sizeof *d);
        if (!d) return SHL_ENOMEM;
        L->data = d;
        L->node_cap = L->data_cap = cap;
    }
    if (hreserve(&L->nodes)) return SHL_ENOMEM;
    const uint64_t k = key3(i);
    hset(&L->nodes, k, (uint32_t)L->nnodes);
    L->node_key[L->nnodes] = k;
    L->flag[L->nnodes] = 0;
    ++L->nnodes;
    return SHL_OK;
}

/* Add cell c (not yet present); its corners and flags are set by resolve_cell. */
static int add_cell(shl__alevel *L, const int c[3])
{
    if (L->ncells == L->cell_cap) {
        const size_t cap = L->cell_cap ? 2 * L->cell_cap : 256;
        if (regrow((void **)&L->cell_key, L->ncells, cap, sizeof(uint64_t))) return SHL_ENOMEM;
        if (regrow((void **)&L->cell, L->ncells, cap, sizeof(shl__acell))) return SHL_ENOMEM;
        L->cell_cap = cap; /* both arrays hold cap now (cell_key first: a failure of the second leaves it larger) */
    }
    if (hreserve(&L->cells)) return SHL_ENOMEM;
    const uint64_t k = key3(c);
    hset(&L->cells, k, (uint32_t)L->ncells);
    L->cell_key[L->ncells++] = k;
    return SHL_OK;
}

/* Cell c's corner nodes (present: added with the cell), if fresh, and its flags (bit j:
 * corner j flagged; all set on level 0). */
static void resolve_cell(shl__alevel *L, size_t c, int fresh, int level0)
{
    if (fresh) {
        int ci[3];
        unkey(L->cell_key[c], ci);
        for (int j = 0; j < 8; ++j) {
            int v[3];
            for (int a = 0; a < 3; ++a) v[a] = ci[a] + ((j >> a) & 1);
            L->cell[c].node[j] = (uint32_t)hfind(&L->nodes, key3(v));
        }
    }
    unsigned char cf = level0 ? 0xFF : 0;
    for (int j = 0; j < 8; ++j)
        if (L->flag[L->cell[c].node[j]]) cf |= (unsigned char)(1u << j);
    L->cell[c].flags = cf;
}

/* Level 0: every node and cell, nodes in lattice order. */
static int build_level0(const shl_agrid *g, shl__alevel *L)
{
    if (level_init(g, 0, L)) return SHL_ENOMEM;
    int i[3];
    for (i[2] = 0; i[2] <= L->n[2]; ++i[2])
        for (i[1] = 0; i[1] <= L->n[1]; ++i[1])
            for (i[0] = 0; i[0] <= L->n[0]; ++i[0]) {
                if (add_node(L, i, g->node_len)) return SHL_ENOMEM;
                if (i[0] < L->n[0] && i[1] < L->n[1] && i[2] < L->n[2] && add_cell(L, i)) return SHL_ENOMEM;
            }
    for (size_t c = 0; c < L->ncells; ++c) resolve_cell(L, c, 1, 1);
    return SHL_OK;
}

static double node_coord(const shl_agrid *g, const shl__alevel *L, int a, int i)
{
    return i == L->n[a] ? g->hi[a] : g->lo[a] + i * L->h[a];
}

/* ---- the interpolant A ---- */

/* A at p (finite) from levels 0..nl-1 into out[3 nc]; tmp: 3 nc doubles. */
static void composite(const shl_agrid *g, const shl__alevel *lev, int nl, const double p[3], double *out,
                      double *tmp)
{
    const shl__acell *cell[SHL_AGRID_LEVELS_MAX];
    double w[SHL_AGRID_LEVELS_MAX], u[SHL_AGRID_LEVELS_MAX][3], x[3];
    int top = 0; /* finest level with w = 1 (level 0 has it everywhere) */
    for (int a = 0; a < 3; ++a) x[a] = fmin(fmax(p[a], g->lo[a]), g->hi[a]);
    for (int l = 0; l < nl; ++l) {
        const shl__alevel *L = lev + l;
        int c[3];
        for (int a = 0; a < 3; ++a) {
            const double t = (x[a] - g->lo[a]) / L->h[a];
            c[a] = t < L->n[a] ? (int)t : L->n[a] - 1;
            u[l][a] = fmin(t - c[a], 1.0);
        }
        const long ci = hfind(&L->cells, key3(c));
        cell[l] = ci >= 0 ? L->cell + ci : NULL;
        w[l] = 0.0;
        if (!cell[l]) continue;
        const unsigned cf = cell[l]->flags;
        if (cf == 0xFF) {
            w[l] = 1.0;
            top = l;
            continue;
        }
        const double *v = u[l];
        for (int j = 0; j < 8; ++j) /* w_l: trilinear weight of the flagged corners */
            if (cf >> j & 1)
                w[l] += (j & 1 ? v[0] : 1.0 - v[0]) * (j & 2 ? v[1] : 1.0 - v[1]) * (j & 4 ? v[2] : 1.0 - v[2]);
    }
    /* A = sum_{l >= top} w_l prod_{m > l} (1 - w_m) I_l */
    const size_t nv = 3 * (size_t)g->nc;
    double rest = 1.0;
    int first = 1;
    for (int l = nl - 1; l >= top; --l) {
        if (!(w[l] > 0.0)) continue;
        const double coef = w[l] * rest;
        rest *= 1.0 - w[l];
        const shl__alevel *L = lev + l;
        shl__interp_point s;
        for (int a = 0; a < 3; ++a) { /* Hermite basis, Wu 2020 Eq. 33-35 (as interp.c) */
            const double uu = u[l][a], v = 1.0 - uu;
            s.u[a] = uu;
            s.hw[a][0] = (1.0 + 2.0 * uu) * v * v;
            s.hw[a][1] = uu * v * v * L->h[a];
            s.hw[a][2] = uu * uu * (3.0 - 2.0 * uu);
            s.hw[a][3] = -uu * uu * v * L->h[a];
        }
        for (int j = 0; j < 8; ++j) s.ofs[j] = (size_t)cell[l]->node[j] * g->node_len;
        shl__interp_ahead no_ahead = {.nrange = 0}; /* no look-ahead: levels are visited point by point */
        if (first && coef == 1.0) {
            g->isa->interp_f(L->data, SHL_INTERP_HERMITE, g->nc, &s, &no_ahead, out);
            return;
        }
        g->isa->interp_f(L->data, SHL_INTERP_HERMITE, g->nc, &s, &no_ahead, tmp);
        for (size_t i = 0; i < nv; ++i) out[i] = first ? coef * tmp[i] : out[i] + coef * tmp[i];
        first = 0;
    }
}

typedef struct {
    const shl_agrid *g;
    const double *pts;
    double *out;
} interp_job;

static void interp_range(void *arg, int worker, long begin, long end)
{
    const interp_job *job = arg;
    double tmp[3 * SHL_NCOEFFS(SHL_LMAX_MAX)];
    (void)worker;
    for (long p = begin; p < end; ++p)
        composite(job->g, job->g->lev, job->g->nlevels, job->pts + 3 * p, job->out + 3 * (size_t)job->g->nc * p, tmp);
}

int shl_agrid_interp(const shl_agrid *grid, int npts, const double *pts, double *rgb, int nthreads)
{
    if (!grid || (npts > 0 && (!pts || !rgb))) return SHL_ENULL;
    if (npts < 0 || shl__check_threads(nthreads)) return SHL_EDOMAIN;
    if (shl__check_finite(pts, 3 * (size_t)npts)) return SHL_ENONFINITE;
    interp_job job = {grid, pts, rgb};
    return shl__parallel_for(npts, 256, nthreads, interp_range, &job);
}

/* ---- receivers ---- */

/* The bits of x < 2^21 spread to every third bit. */
static uint64_t spread3(uint64_t x)
{
    x &= 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFu;
    x = (x | x << 16) & 0x1F0000FF0000FFu;
    x = (x | x << 8) & 0x100F00F00F00F00Fu;
    x = (x | x << 4) & 0x10C30C30C30C30C3u;
    x = (x | x << 2) & 0x1249249249249249u;
    return x;
}

/* Morton key of lattice cell c: the cells of level l + s inside cell c of level l
 * are the keys (key << 3s) .. ((key + 1) << 3s) - 1, a contiguous range. */
static uint64_t morton(const int c[3])
{
    return spread3((uint64_t)c[0]) | spread3((uint64_t)c[1]) << 1 | spread3((uint64_t)c[2]) << 2;
}

typedef struct shl__arecv keyed;

static int by_key(const void *pa, const void *pb)
{
    const keyed *a = pa, *b = pb;
    if (a->key != b->key) return (a->key > b->key) - (a->key < b->key);
    const int x = memcmp(a->x, b->x, sizeof a->x);
    if (x) return x;
    return (a->w > b->w) - (a->w < b->w); /* a total order: the result does not depend on qsort */
}

/* Receivers with key < k. */
static size_t below(const shl_agrid *g, uint64_t k)
{
    size_t lo = 0, hi = g->nrecv;
    while (lo < hi) {
        const size_t m = lo + (hi - lo) / 2;
        if (g->recv[m].key < k) lo = m + 1;
        else hi = m;
    }
    return lo;
}

/* The receivers' weight in cells key k.. below key k2 (Morton keys of finest-level cells). */
static double weight_between(const shl_agrid *g, uint64_t k, uint64_t k2)
{
    return g->recv_cum[below(g, k2)] - g->recv_cum[below(g, k)];
}

/* The weight of cell c of level l in the refinement priority: the share of the
 * receivers' weight it holds, or without receivers its volume in coarse-cell units 8^-l. */
static double cell_weight(const shl_agrid *g, int l, const int c[3])
{
    if (!g->recv) return ldexp(1.0, -3 * l);
    const int s = 3 * (g->max_levels - 1 - l);
    const uint64_t k = morton(c);
    return weight_between(g, k << s, (k + 1) << s) / g->recv_cum[g->nrecv];
}

/* The receiver of b0..b1-1 (their weight > 0) at the fraction q of their cumulative
 * weight: the first j with recv_cum[j + 1] > recv_cum[b0] + q (recv_cum[b1] - recv_cum[b0]).
 * With unit weights that is b0 + floor(q (b1 - b0)). */
static size_t receiver_at(const shl_agrid *g, size_t b0, size_t b1, double q)
{
    const double t = g->recv_cum[b0] + q * (g->recv_cum[b1] - g->recv_cum[b0]);
    size_t lo = b0, hi = b1 - 1; /* the answer is in lo..hi (hi: t rounded up to recv_cum[b1]) */
    while (lo < hi) {
        const size_t m = lo + (hi - lo) / 2;
        if (g->recv_cum[m + 1] > t) hi = m;
        else lo = m + 1;
    }
    return lo;
}

int shl_agrid_set_receivers(shl_agrid *grid, int npts, const double *pts)
{
    return shl_agrid_set_weighted_receivers(grid, npts, pts, NULL);
}

int shl_agrid_set_weighted_receivers(shl_agrid *grid, int npts, const double *pts, const double *weights)
{
    if (!grid || (npts > 0 && !pts)) return SHL_ENULL;
    if (npts < 0) return SHL_EDOMAIN;
    int kept = 0; /* receivers of weight > 0 */
    for (int p = 0; p < npts; ++p) {
        if (shl__check_finite(pts + 3 * (size_t)p, 3) || (weights && !isfinite(weights[p]))) return SHL_ENONFINITE;
        if (weights && (weights[p] < 0.0 || weights[p] > 0x1p100)) return SHL_EDOMAIN;
        kept += !weights || weights[p] > 0.0;
    }
    if (npts > 0 && kept == 0) return SHL_EDOMAIN;
    keyed *k = NULL;
    double *cum = NULL;
    if (kept > 0 && (!(k = shl__malloc((size_t)kept * sizeof *k)) || !(cum = shl__malloc(((size_t)kept + 1) * sizeof *cum)))) {
        shl__free(k);
        return SHL_ENOMEM;
    }
    const int top = grid->max_levels - 1;
    for (int p = 0, q = 0; p < npts; ++p) {
        if (weights && !(weights[p] > 0.0)) continue;
        int c[3];
        for (int a = 0; a < 3; ++a) { /* the finest level's cell, clamped to the box as shl_agrid_interp clamps */
            const int n = (grid->res[a] - 1) << top;
            const double t = floor((pts[3 * p + a] - grid->lo[a]) / (grid->hi[a] - grid->lo[a]) * n);
            c[a] = t < 0.0 ? 0 : t >= n ? n - 1 : (int)t;
            const double x = fmin(fmax(pts[3 * p + a], grid->lo[a]), grid->hi[a]);
            k[q].x[a] = (float)x;
        }
        k[q].key = morton(c);
        k[q++].w = weights ? weights[p] : 1.0;
    }
    if (kept > 0) {
        qsort(k, (size_t)kept, sizeof *k, by_key);
        cum[0] = 0.0;
        for (int p = 0; p < kept; ++p) cum[p + 1] = cum[p] + k[p].w; /* sums in the sorted order: exact for unit weights */
    }
    shl__free(grid->recv);
    shl__free(grid->recv_cum);
    grid->recv = k;
    grid->recv_cum = cum;
    grid->nrecv = (size_t)kept;
    return SHL_OK;
}

/* ---- fill ---- */

enum { BLOCK = SHL__LIGHTS_BLOCK, SAMPLES = 2, CELL_BLOCK = 1024 };

/* A cell (index in its level), its estimate e, its weight w (cell_weight) and its
 * refinement priority p = e w; or, if pending, a refined cell whose children are not
 * estimated yet, e and p bounds on theirs (build()). */
typedef struct {
    double e, p, w;
    uint32_t cell;
    int level, pending;
} ranked;

typedef struct {
    const shl_agrid *g;
    const shl_lights *lights;
    shl_ctx ctx;
    shl__alevel *lev;
    size_t from[SHL_AGRID_LEVELS_MAX]; /* eval_nodes: the nodes from[l].. of each level l are new, */
    long blk[SHL_AGRID_LEVELS_MAX + 1]; /* in blocks blk[l] .. blk[l + 1] - 1 (none crosses a level) */
    size_t cells_from[SHL_AGRID_LEVELS_MAX]; /* and the cells of levels 1.. (from cells_from[l] new) */
    long cblk[SHL_AGRID_LEVELS_MAX + 1];     /* in blocks blk[LEVELS_MAX] + cblk[l] .. (level 0: none) */
    ranked *which;  /* estimate_cells: the cells estimated (any levels), their estimates into .e */
    size_t nwhich;
    char *ws;
    size_t stride, batch_bytes;
    char *wsbuf;    /* run(): the workspaces, kept across a fill's passes (grown when too small) */
    size_t wsbytes;
} fill_job;

/* The new nodes of every level, blocks of BLOCK consecutive nodes of one level,
 * through the float batch with gradients (Wu 2020 Alg. 1 l. 5-7), straight into
 * the node data; and, in blocks of CELL_BLOCK, the corners of the new cells of
 * levels 1.. and the flags of all their cells (refine() flags nodes of old cells
 * too), which the pass's node data does not need: they run beside it instead of
 * on the calling thread before it. */
static void nodes_range(void *arg, int worker, long begin, long end)
{
    const fill_job *job = arg;
    const shl_agrid *g = job->g;
    void *buf = job->batch_bytes ? job->ws + job->stride * (size_t)worker : NULL;
    float pts[3 * BLOCK];
    for (long b = begin; b < end; ++b) {
        if (b >= job->blk[SHL_AGRID_LEVELS_MAX]) {
            const long cb = b - job->blk[SHL_AGRID_LEVELS_MAX];
            int l = 1;
            while (cb >= job->cblk[l + 1]) ++l;
            shl__alevel *L = job->lev + l;
            const size_t c0 = (size_t)(cb - job->cblk[l]) * CELL_BLOCK;
            const size_t c1 = L->ncells - c0 < CELL_BLOCK ? L->ncells : c0 + CELL_BLOCK;
            for (size_t c = c0; c < c1; ++c) resolve_cell(L, c, c >= job->cells_from[l], 0);
            continue;
        }
        int l = 0;
        while (b >= job->blk[l + 1]) ++l;
        shl__alevel *L = job->lev + l;
        const size_t n0 = job->from[l] + (size_t)(b - job->blk[l]) * BLOCK, left = L->nnodes - n0;
        const int m = left < BLOCK ? (int)left : BLOCK;
        for (int j = 0; j < m; ++j) {
            int i[3];
            unkey(L->node_key[n0 + j], i);
            for (int a = 0; a < 3; ++a) pts[3 * j + a] = (float)node_coord(g, L, a, i[a]);
        }
        float *node = L->data + n0 * g->node_len;
        shl__lights_batch_f_block(&job->ctx, job->lights, m, pts, node, g->node_len, node + 3 * g->nc, g->node_len, buf);
    }
}

/* The estimate of the cells job->which (include/shlight.h), BLOCK / SAMPLES cells a
 * block whatever their levels: A of levels 0..l (l the cell's level) against the
 * float batch (values only) at the samples lo + (c + q) h_l, q = 1/4 and 3/4 on every
 * axis, both rounded to float. */
static void estimate_range(void *arg, int worker, long begin, long end)
{
    const fill_job *job = arg;
    const shl_agrid *g = job->g;
    const size_t nv = 3 * (size_t)g->nc;
    char *w = job->ws + job->stride * (size_t)worker;
    float *rgb = (float *)(void *)(w + shl__ws_stride(job->batch_bytes)), pts[3 * BLOCK];
    double *a = (double *)(void *)(rgb + BLOCK * nv), *tmp = a + nv;
    for (long b = begin; b < end; ++b) {
        const size_t c0 = (size_t)b * (BLOCK / SAMPLES), left = job->nwhich - c0;
        const int mc = left < BLOCK / SAMPLES ? (int)left : BLOCK / SAMPLES;
        for (int j = 0; j < mc; ++j) {
            const ranked *r = job->which + c0 + j;
            const shl__alevel *L = job->lev + r->level;
            int c[3];
            unkey(L->cell_key[r->cell], c);
            size_t at[SAMPLES] = {0, 0};
            if (g->recv) { /* the cell's receivers at 1/4 and 3/4 of their weight, in Morton order */
                const int sh = 3 * (g->max_levels - 1 - r->level);
                const size_t b0 = below(g, morton(c) << sh), b1 = below(g, (morton(c) + 1) << sh);
                for (int q = 0; q < SAMPLES; ++q) at[q] = receiver_at(g, b0, b1, q ? 0.75 : 0.25);
            }
            for (int q = 0; q < SAMPLES; ++q)
                for (int k = 0; k < 3; ++k)
                    pts[3 * (SAMPLES * j + q) + k] = g->recv ? g->recv[at[q]].x[k]
                                                           : (float)(g->lo[k] + (c[k] + (q ? 0.75 : 0.25)) * L->h[k]);
        }
        shl__lights_batch_f_block(&job->ctx, job->lights, SAMPLES * mc, pts, rgb, nv, NULL, 0,
                                  job->batch_bytes ? w : NULL);
        for (int j = 0; j < mc; ++j) {
            double e = 0.0;
            for (int q = 0; q < SAMPLES; ++q) {
                const int s = SAMPLES * j + q;
                const double x[3] = {pts[3 * s], pts[3 * s + 1], pts[3 * s + 2]};
                composite(g, job->lev, job->which[c0 + j].level + 1, x, a, tmp);
                for (int col = 0; col < 3; ++col) {
                    double sum = 0.0;
                    for (int k = 0; k < g->nc; ++k) {
                        const double d = a[col * g->nc + k] - rgb[(size_t)s * nv + col * g->nc + k];
                        sum += d * d;
                    }
                    e = fmax(e, sqrt(sum));
                }
            }
            job->which[c0 + j].e = e;
        }
    }
}

static int run(fill_job *job, long nblocks, int nthreads, shl__range_fn fn, size_t extra)
{
    if (nblocks == 0) return SHL_OK;
    const int nw = shl__parallel_workers(nblocks, 1, nthreads);
    job->stride = shl__ws_stride(shl__ws_stride(job->batch_bytes) + extra);
    const size_t need = job->stride * (size_t)nw;
    if (need > job->wsbytes) { /* a fresh block per pass costs page faults at every round */
        char *w = shl__malloc(need);
        if (!w) return SHL_ENOMEM;
        shl__free(job->wsbuf);
        job->wsbuf = w;
        job->wsbytes = need;
    }
    job->ws = job->wsbuf;
    return shl__parallel_for(nblocks, 1, nw, fn, job);
}

/* The nodes of levels 0..nl-1 not yet evaluated and, if cells, the cells of levels 1..nl-1
 * (those from job->cells_from[l] new), in one parallel pass. */
static int eval_nodes(fill_job *job, int nl, int cells, int nthreads)
{
    job->blk[0] = 0;
    for (int l = 0; l < SHL_AGRID_LEVELS_MAX; ++l)
        job->blk[l + 1] = job->blk[l] + (l < nl ? (long)((job->lev[l].nnodes - job->from[l] + BLOCK - 1) / BLOCK) : 0);
    job->cblk[0] = job->cblk[1] = 0;
    for (int l = 1; l < SHL_AGRID_LEVELS_MAX; ++l)
        job->cblk[l + 1] = job->cblk[l] + (cells && l < nl ? (long)((job->lev[l].ncells + CELL_BLOCK - 1) / CELL_BLOCK) : 0);
    const int st = run(job, job->blk[SHL_AGRID_LEVELS_MAX] + job->cblk[SHL_AGRID_LEVELS_MAX], nthreads, nodes_range, 0);
    for (int l = 0; !st && l < nl; ++l) job->from[l] = job->lev[l].nnodes;
    return st;
}

/* The estimates of the cells which[k].cell of level which[k].level, k < n, into which[k].e. */
static int estimate_cells(fill_job *job, ranked *which, size_t nwhich, int nthreads)
{
    job->which = which;
    job->nwhich = nwhich;
    const size_t nv = 3 * (size_t)job->g->nc;
    const long n = (long)((nwhich + BLOCK / SAMPLES - 1) / (BLOCK / SAMPLES));
    return run(job, n, nthreads, estimate_range, BLOCK * nv * sizeof(float) + 2 * nv * sizeof(double));
}

/* The criterion value of r: e (SHL_AGRID_MAX) or its share of the mean error p (SHL_AGRID_MEAN). */
static double crit(const shl_agrid *g, const ranked *r)
{
    return g->criterion == SHL_AGRID_MEAN ? r->p : r->e;
}

static int by_estimate(const void *pa, const void *pb)
{
    const ranked *a = pa, *b = pb;
    if (a->p != b->p) return a->p > b->p ? -1 : 1; /* largest first */
    if (a->level != b->level) return a->level < b->level ? -1 : 1;
    return (a->cell > b->cell) - (a->cell < b->cell);
}

/* Refine cell c of level l: level l + 1 gets the cells within one level-(l+1)
 * spacing of c (4 per axis, clipped to the box) and their nodes, unless that
 * would take the node count *total past max_nodes (returns 1, nothing added); the
 * level-(l+1) nodes of c (3 per axis) are flagged.  The new nodes are counted
 * beforehand only when the region's nodes could pass the budget, and each node is
 * looked up once (its index flags it). */
static int refine(const shl_agrid *g, const shl__alevel *L, shl__alevel *F, uint32_t c, long *total)
{
    int ci[3], lo[3], hi[3], i[3];
    unkey(L->cell_key[c], ci);
    long span = 1; /* nodes of the region, at most 5^3 */
    for (int a = 0; a < 3; ++a) {
        lo[a] = ci[a] > 0 ? 2 * ci[a] - 1 : 0;
        hi[a] = ci[a] + 1 < L->n[a] ? 2 * ci[a] + 3 : 2 * L->n[a];
        span *= hi[a] - lo[a] + 1;
    }
    if (span > g->max_nodes - *total) {
        long add = 0;
        for (i[2] = lo[2]; i[2] <= hi[2]; ++i[2])
            for (i[1] = lo[1]; i[1] <= hi[1]; ++i[1])
                for (i[0] = lo[0]; i[0] <= hi[0]; ++i[0]) add += hfind(&F->nodes, key3(i)) < 0;
        if (add > g->max_nodes - *total) return 1;
    }
    for (i[2] = lo[2]; i[2] <= hi[2]; ++i[2])
        for (i[1] = lo[1]; i[1] <= hi[1]; ++i[1])
            for (i[0] = lo[0]; i[0] <= hi[0]; ++i[0]) {
                long at = hfind(&F->nodes, key3(i));
                if (at < 0) {
                    at = (long)F->nnodes;
                    if (add_node(F, i, g->node_len)) return SHL_ENOMEM;
                    ++*total;
                }
                int own = 1; /* a node of c: 2 ci .. 2 ci + 2 on every axis */
                for (int a = 0; a < 3; ++a) own &= i[a] >= 2 * ci[a] && i[a] <= 2 * ci[a] + 2;
                if (own) F->flag[at] = 1;
                if (i[0] < hi[0] && i[1] < hi[1] && i[2] < hi[2] && hfind(&F->cells, key3(i)) < 0 && add_cell(F, i))
                    return SHL_ENOMEM;
            }
    return SHL_OK;
}

/* A filled level's arrays cut to its node and cell counts, and hash tables larger than
 * hsize of their counts (room from a larger last fill, level_init) rebuilt at that size:
 * the memory held then depends on the counts only, not on earlier fills (each part
 * kept as is if its allocation fails). */
static void trim_level(shl__alevel *L, size_t node_len)
{
    if (L->nnodes > 0 && L->nnodes < L->data_cap) {
        float *d = shl__realloc(L->data, L->nnodes * node_len * sizeof *d);
        if (d) L->data = d, L->data_cap = L->nnodes;
    }
    /* node_cap, cell_cap: the room of both arrays, so the count once the first is cut */
    uint64_t *k;
    if (L->nnodes > 0 && L->nnodes < L->node_cap && (k = shl__realloc(L->node_key, L->nnodes * sizeof *k))) {
        L->node_key = k, L->node_cap = L->nnodes;
        unsigned char *f = shl__realloc(L->flag, L->nnodes);
        if (f) L->flag = f;
    }
    if (L->ncells > 0 && L->ncells < L->cell_cap && (k = shl__realloc(L->cell_key, L->ncells * sizeof *k))) {
        L->cell_key = k, L->cell_cap = L->ncells;
        shl__acell *c = shl__realloc(L->cell, L->ncells * sizeof *c);
        if (c) L->cell = c;
    }
    if (L->nodes.cap > hsize(L->nodes.count)) (void)hresize(&L->nodes, hsize(L->nodes.count));
    if (L->cells.cap > hsize(L->cells.count)) (void)hresize(&L->cells, hsize(L->cells.count));
}

static void free_levels(shl__alevel *lev, int n)
{
    for (int l = 0; l < n; ++l) level_free(lev + l);
}

static void fill_stats(const shl_agrid *g, const shl__alevel *lev, int nl, shl_agrid_stats *st)
{
    st->nodes = st->cells = 0;
    size_t bytes = sizeof(shl_agrid);
    st->levels = nl;
    for (int l = 0; l < nl; ++l) {
        st->nodes += (long)lev[l].nnodes;
        st->cells += (long)lev[l].ncells;
        bytes += level_bytes(lev + l, g->node_len);
    }
    st->bytes = (long long)(bytes + g->nrecv * (sizeof(struct shl__arecv) + sizeof(double)) + (g->recv ? sizeof(double) : 0));
}

/* Room for n more entries in the growable array *p (size *cap, used elements used). */
static int reserve(ranked **p, size_t *cap, size_t used, size_t n)
{
    if (used + n <= *cap) return SHL_OK;
    size_t c = *cap ? 2 * *cap : 256;
    while (c < used + n) c *= 2;
    if (regrow((void **)p, used, c, sizeof **p)) return SHL_ENOMEM;
    *cap = c;
    return SHL_OK;
}

/* Levels into lev[] (nl of them), stats of the fill into *st.  Refinement is best
 * first over all levels (include/shlight.h): the cells whose criterion value exceeds
 * the tolerance wait in a queue by priority e 8^-l; each round refines, largest
 * first, those within a factor ROUND of the largest (a round's new nodes then go through
 * the batch kernels together, in full blocks, and so do the estimates of the new
 * cells), until the queue is empty or the budget stops a refinement. */
static int build(const shl_agrid *g, const shl_lights *lights, int nthreads, shl__alevel *lev, int *nl,
                 shl_agrid_stats *st)
{
    static const double ROUND = 0.5;
    fill_job job;
    memset(&job, 0, sizeof job);
    job.g = g;
    job.lights = lights;
    job.ctx = (shl_ctx){g->lmax, g->nc, g->isa};
    job.lev = lev;
    job.batch_bytes = shl__lights_batch_f_bytes(&job.ctx, lights, 1); /* >= the values-only size */
    *nl = 1;
    int status = build_level0(g, lev);
    if (!status) status = eval_nodes(&job, 1, 0, nthreads);
    long total = (long)lev[0].nnodes;
    ranked *queue = NULL, *est = NULL, *done = NULL;
    size_t nq = 0, qcap = 0, ne = 0, ecap = 0, nd = 0, dcap = 0;
    int unknown = g->max_levels < 2; /* cells left unestimated: on the finest level, or children still waiting */
    if (!status && !unknown && !(status = reserve(&est, &ecap, 0, lev[0].ncells)))
        for (size_t c = 0; c < lev[0].ncells; ++c) {
            int ci[3];
            unkey(lev[0].cell_key[c], ci);
            const double w = cell_weight(g, 0, ci);
            if (w > 0.0) est[ne++] = (ranked){0.0, 0.0, w, (uint32_t)c, 0, 0}; /* a cell without receivers: never refined */
        }
    while (!status) {
        /* the new cells' estimates; criterion values above tol join the queue */
        if ((status = estimate_cells(&job, est, ne, nthreads)) || (status = reserve(&queue, &qcap, nq, ne))) break;
        st->samples += SAMPLES * (long)ne;
        for (size_t k = 0; k < ne; ++k) {
            ranked r = est[k];
            r.p = r.e * r.w;
            if (crit(g, &r) > g->tol) queue[nq++] = r;
            else st->max_estimate = fmax(st->max_estimate, crit(g, &r));
        }
        ne = 0;
        if (nq == 0 || st->budget_hit) break;
        qsort(queue, nq, sizeof *queue, by_estimate);
        /* this round: refine the queue's head, or queue the children of its pending entries
         * for estimation */
        const double thr = ROUND * queue[0].p;
        size_t cells0[SHL_AGRID_LEVELS_MAX], k = 0;
        for (int l = 0; l < SHL_AGRID_LEVELS_MAX; ++l) cells0[l] = lev[l].ncells;
        nd = 0;
        for (; k < nq && queue[k].p >= thr; ++k) {
            const int l = queue[k].level;
            if (queue[k].pending) {
                if ((status = reserve(&est, &ecap, ne, 8))) break;
                int ci[3];
                unkey(lev[l].cell_key[queue[k].cell], ci);
                for (int j = 0; j < 8; ++j) {
                    int cc[3];
                    for (int a = 0; a < 3; ++a) cc[a] = 2 * ci[a] + ((j >> a) & 1);
                    const double w = cell_weight(g, l + 1, cc);
                    if (w > 0.0) est[ne++] = (ranked){0.0, 0.0, w, (uint32_t)hfind(&lev[l + 1].cells, key3(cc)), l + 1, 0};
                }
                continue;
            }
            if (l + 1 >= *nl) {
                *nl = l + 2;
                if ((status = level_init(g, l + 1, lev + l + 1))) break;
            }
            const int r = refine(g, lev + l, lev + l + 1, queue[k].cell, &total);
            if (r == 1) st->budget_hit = 1;
            if (r || (status = reserve(&done, &dcap, nd, 1))) {
                status = r < 0 ? r : status;
                break;
            }
            done[nd++] = queue[k];
        }
        memmove(queue, queue + k, (nq - k) * sizeof *queue); /* the refined ones leave it */
        nq -= k;
        if (lev[*nl - 1].ncells == 0) { /* a level begun, but the budget refused its first cell */
            level_free(lev + *nl - 1);
            --*nl;
        }
        if (status) break;
        for (int l = 1; l < *nl; ++l) job.cells_from[l] = cells0[l];
        if ((status = eval_nodes(&job, *nl, 1, nthreads))) break;
        /* a refined cell's children wait in the queue, unestimated, as one pending entry
         * with the bounds the assumption that refinement does not increase e gives
         * (include/shlight.h): e_child <= e, so p_child <= e max_j w_j (= p / 8 without
         * receivers) and, for SHL_AGRID_MEAN, criterion <= that (dropped if <= tol);
         * they are estimated when the entry reaches the head (never, if the budget runs
         * out first).  Children on the finest level allowed are not estimated. */
        if ((status = reserve(&queue, &qcap, nq, nd))) break;
        for (size_t d = 0; d < nd; ++d) {
            if (done[d].level + 2 >= g->max_levels) {
                unknown = 1;
                continue;
            }
            int ci[3];
            unkey(lev[done[d].level].cell_key[done[d].cell], ci);
            double w = 0.0;
            for (int j = 0; j < 8; ++j) {
                int cc[3];
                for (int a = 0; a < 3; ++a) cc[a] = 2 * ci[a] + ((j >> a) & 1);
                w = fmax(w, cell_weight(g, done[d].level + 1, cc));
            }
            const ranked r = {done[d].e, done[d].e * w, w, done[d].cell, done[d].level, 1};
            if (crit(g, &r) > g->tol) queue[nq++] = r;
        }
    }
    if (!status) {
        long real = 0;
        for (size_t k = 0; k < nq; ++k) {
            if (queue[k].pending) {
                unknown = 1;
                continue;
            }
            st->max_estimate = fmax(st->max_estimate, crit(g, queue + k));
            ++real;
        }
        st->unresolved = unknown ? -1 : real;
        for (int l = 0; l < *nl; ++l) trim_level(lev + l, g->node_len);
        fill_stats(g, lev, *nl, st);
    }
    shl__free(queue);
    shl__free(est);
    shl__free(done);
    shl__free(job.wsbuf);
    return status;
}

int shl_agrid_fill(shl_agrid *grid, const shl_lights *lights, int nthreads)
{
    if (!grid || !lights) return SHL_ENULL;
    if (shl__check_threads(nthreads)) return SHL_EDOMAIN;
    shl__alevel lev[SHL_AGRID_LEVELS_MAX];
    memset(lev, 0, sizeof lev);
    shl_agrid_stats st;
    memset(&st, 0, sizeof st);
    int nl = 0;
    const int status = build(grid, lights, nthreads, lev, &nl, &st);
    if (status) {
        free_levels(lev, SHL_AGRID_LEVELS_MAX);
        return status;
    }
    free_levels(grid->lev, grid->nlevels);
    memcpy(grid->lev, lev, sizeof lev);
    grid->nlevels = nl;
    grid->stats = st;
    return SHL_OK;
}

/* ---- create, destroy, stats ---- */

int shl_agrid_create(const shl_ctx *ctx, const double lo[3], const double hi[3], const int res[3], int criterion,
                     double tol, long max_nodes, shl_agrid **out)
{
    if (!out) return SHL_ENULL;
    *out = NULL;
    if (!ctx || !lo || !hi || !res) return SHL_ENULL;
    if (shl__check_finite(lo, 3) || shl__check_finite(hi, 3) || !isfinite(tol)) return SHL_ENONFINITE;
    if (!(tol > 0.0) || (criterion != SHL_AGRID_MAX && criterion != SHL_AGRID_MEAN)) return SHL_EDOMAIN;
    long n0 = 1;
    int levels = SHL_AGRID_LEVELS_MAX;
    for (int a = 0; a < 3; ++a) {
        if (res[a] < 2 || res[a] > SHL_GRID_RES_MAX || !(lo[a] < hi[a])) return SHL_EDOMAIN;
        const double m = fmax(fabs(lo[a]), fabs(hi[a]));
        int la = 0; /* levels whose spacing keeps the float fill of shl_grid_fill */
        for (; la < SHL_AGRID_LEVELS_MAX; ++la) {
            const double h = (hi[a] - lo[a]) / (double)((res[a] - 1) << la);
            if (!(m <= 0x1p126 && isfinite(h) && h >= 0x1p-10 * m && h >= 0x1p-100)) break;
        }
        if (la == 0) return SHL_EDOMAIN;
        levels = la < levels ? la : levels;
        n0 *= res[a];
    }
    if (max_nodes < n0 || max_nodes > 0x7FFFFFFFL) return SHL_EDOMAIN;
    shl_agrid *g = shl__calloc(1, sizeof *g);
    if (!g) return SHL_ENOMEM;
    g->lmax = ctx->lmax;
    g->nc = ctx->nc;
    g->isa = ctx->isa;
    g->node_len = 12 * (size_t)ctx->nc;
    g->tol = tol;
    g->criterion = criterion;
    g->max_nodes = max_nodes;
    g->max_levels = levels;
    memcpy(g->res, res, sizeof g->res);
    memcpy(g->lo, lo, sizeof g->lo);
    memcpy(g->hi, hi, sizeof g->hi);
    if (build_level0(g, g->lev)) {
        level_free(g->lev);
        shl__free(g);
        return SHL_ENOMEM;
    }
    memset(g->lev[0].data, 0, g->lev[0].nnodes * g->node_len * sizeof(float));
    trim_level(g->lev, g->node_len);
    g->nlevels = 1;
    fill_stats(g, g->lev, 1, &g->stats);
    *out = g;
    return SHL_OK;
}

void shl_agrid_destroy(shl_agrid *grid)
{
    if (!grid) return;
    free_levels(grid->lev, grid->nlevels);
    shl__free(grid->recv);
    shl__free(grid->recv_cum);
    shl__free(grid);
}

int shl_agrid_get_stats(const shl_agrid *grid, shl_agrid_stats *stats)
{
    if (!grid || !stats) return SHL_ENULL;
    *stats = grid->stats;
    return SHL_OK;
}
