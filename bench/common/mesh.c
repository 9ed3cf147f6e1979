#include "mesh.h"
#include "vec3.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void mesh_free(mesh *m)
{
    free(m->pos);
    free(m->nrm);
    free(m->tri);
    free(m->mat);
    memset(m, 0, sizeof *m);
}

int mesh_alloc(mesh *m, int nv, int nt)
{
    memset(m, 0, sizeof *m);
    m->pos = malloc(sizeof(double) * 3 * (size_t)nv);
    m->nrm = malloc(sizeof(double) * 3 * (size_t)nv);
    m->tri = malloc(sizeof(int) * 3 * (size_t)nt);
    if (!m->pos || !m->nrm || !m->tri) {
        mesh_free(m);
        return -1;
    }
    m->nv = nv;
    m->nt = nt;
    return 0;
}

/* Make every triangle counter-clockwise about its vertices' mean normal. */
static void orient_to_normals(mesh *m)
{
    for (int t = 0; t < m->nt; ++t) {
        int *v = m->tri + 3 * t;
        double e1[3], e2[3], f[3], s[3] = {0, 0, 0};
        v3_sub(e1, m->pos + 3 * v[1], m->pos + 3 * v[0]);
        v3_sub(e2, m->pos + 3 * v[2], m->pos + 3 * v[0]);
        v3_cross(f, e1, e2);
        for (int k = 0; k < 3; ++k) v3_add(s, s, m->nrm + 3 * v[k]);
        if (v3_dot(f, s) < 0) {
            const int tmp = v[1];
            v[1] = v[2];
            v[2] = tmp;
        }
    }
}

/* Triangles of an (nu+1) x (nv+1) vertex lattice, vertex (i, j) at base + i * (nv+1) + j. */
static void lattice_tris(int *tri, int base, int nu, int nv)
{
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const int a = base + i * (nv + 1) + j, b = a + nv + 1;
            const int q[6] = {a, a + 1, b, b, a + 1, b + 1};
            memcpy(tri, q, sizeof q);
            tri += 6;
        }
}

int mesh_plane(mesh *m, double size, int n)
{
    if (n < 1 || mesh_alloc(m, (n + 1) * (n + 1), 2 * n * n)) return -1;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const int v = i * (n + 1) + j;
            v3_set(m->pos + 3 * v, size * ((double)i / n - 0.5), 0.0, size * ((double)j / n - 0.5));
            v3_set(m->nrm + 3 * v, 0, 1, 0);
        }
    lattice_tris(m->tri, 0, n, n);
    orient_to_normals(m);
    return 0;
}

int mesh_torus(mesh *m, double R, double r, int nu, int nv)
{
    if (nu < 3 || nv < 3 || mesh_alloc(m, (nu + 1) * (nv + 1), 2 * nu * nv)) return -1;
    for (int i = 0; i <= nu; ++i)
        for (int j = 0; j <= nv; ++j) {
            const double u = 2 * M_PI * i / nu, w = 2 * M_PI * j / nv, ring = R + r * cos(w);
            const int v = i * (nv + 1) + j;
            v3_set(m->pos + 3 * v, ring * cos(u), r * sin(w), ring * sin(u));
            v3_set(m->nrm + 3 * v, cos(w) * cos(u), sin(w), cos(w) * sin(u));
        }
    lattice_tris(m->tri, 0, nu, nv);
    orient_to_normals(m);
    return 0;
}

int mesh_box(mesh *m, double sx, double sy, double sz, int n)
{
    const int per = (n + 1) * (n + 1);
    if (n < 1 || mesh_alloc(m, 6 * per, 12 * n * n)) return -1;
    const double h[3] = {sx / 2, sy / 2, sz / 2};
    for (int f = 0; f < 6; ++f) {
        const int ax = f / 2, u = (ax + 1) % 3, w = (ax + 2) % 3;
        const double s = f % 2 ? 1.0 : -1.0;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n; ++j) {
                double *p = m->pos + 3 * (f * per + i * (n + 1) + j), *q = m->nrm + 3 * (f * per + i * (n + 1) + j);
                p[ax] = s * h[ax];
                p[u] = h[u] * (2.0 * i / n - 1.0);
                p[w] = h[w] * (2.0 * j / n - 1.0);
                p[1] += h[1];
                q[0] = q[1] = q[2] = 0.0;
                q[ax] = s;
            }
        lattice_tris(m->tri + 6 * n * n * f, f * per, n, n);
    }
    orient_to_normals(m);
    return 0;
}

/* ---- edges: sorted (key, ref) pairs, key = min << 32 | max, ref = 3 t + k ---- */

typedef struct {
    uint64_t key;
    int64_t ref;
} kv;

/* Stable LSD radix sort by key (16-bit digits; constant digits are skipped). */
static int radix_sort(kv *a, size_t n)
{
    kv *tmp = malloc(sizeof *tmp * (n ? n : 1)), *src = a, *dst = tmp;
    size_t *count = malloc(sizeof *count * 65536);
    if (!tmp || !count) {
        free(tmp);
        free(count);
        return -1;
    }
    for (int shift = 0; shift < 64 && n; shift += 16) {
        memset(count, 0, sizeof *count * 65536);
        for (size_t i = 0; i < n; ++i) ++count[(src[i].key >> shift) & 0xffff];
        if (count[(src[0].key >> shift) & 0xffff] == n) continue;
        size_t sum = 0;
        for (int d = 0; d < 65536; ++d) {
            const size_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; ++i) dst[count[(src[i].key >> shift) & 0xffff]++] = src[i];
        kv *t = src;
        src = dst;
        dst = t;
    }
    if (src != a) memcpy(a, src, sizeof *a * n);
    free(tmp);
    free(count);
    return 0;
}

/* Sorted edge entries e[3 nt]; the entries of one edge are consecutive. */
static kv *sorted_edges(const mesh *m)
{
    kv *e = malloc(sizeof *e * 3 * (size_t)(m->nt ? m->nt : 1));
    if (!e) return NULL;
    for (int t = 0; t < m->nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint64_t a = (uint64_t)m->tri[3 * t + k], b = (uint64_t)m->tri[3 * t + (k + 1) % 3];
            e[3 * t + k].key = a < b ? a << 32 | b : b << 32 | a;
            e[3 * t + k].ref = 3 * t + k;
        }
    if (radix_sort(e, 3 * (size_t)m->nt)) {
        free(e);
        return NULL;
    }
    return e;
}

static int grow(mesh *m, int nv, int nt)
{
    double *p = realloc(m->pos, sizeof(double) * 3 * (size_t)nv);
    if (!p) return -1;
    m->pos = p;
    p = realloc(m->nrm, sizeof(double) * 3 * (size_t)nv);
    if (!p) return -1;
    m->nrm = p;
    int *t = realloc(m->tri, sizeof(int) * 3 * (size_t)nt);
    if (!t) return -1;
    m->tri = t;
    if (m->mat) {
        t = realloc(m->mat, sizeof(int) * (size_t)nv);
        if (!t) return -1;
        m->mat = t;
    }
    return 0;
}

/* Vertex `v` at the midpoint of vertices a and b. */
static void midpoint(mesh *m, int v, int a, int b)
{
    double *p = m->pos + 3 * v, *n = m->nrm + 3 * v;
    v3_add(p, m->pos + 3 * a, m->pos + 3 * b);
    v3_scale(p, p, 0.5);
    v3_add(n, m->nrm + 3 * a, m->nrm + 3 * b);
    if (v3_normalize(n) == 0.0) memcpy(n, m->nrm + 3 * a, sizeof(double) * 3);
    if (m->mat) m->mat[v] = m->mat[a];
}

/* One uniform 1-to-4 split. */
static int split4(mesh *m)
{
    kv *e = sorted_edges(m);
    int *mid = malloc(sizeof(int) * 3 * (size_t)m->nt);
    if (!e || !mid) goto fail;
    const int nv0 = m->nv, nt0 = m->nt;
    int nv = nv0;
    for (size_t i = 0; i < 3 * (size_t)nt0; ++i) {
        if (i == 0 || e[i].key != e[i - 1].key) ++nv;
        mid[e[i].ref] = nv - 1;
    }
    if (grow(m, nv, 4 * nt0)) goto fail;
    for (size_t i = 0; i < 3 * (size_t)nt0; ++i)
        if (i == 0 || e[i].key != e[i - 1].key) midpoint(m, mid[e[i].ref], (int)(e[i].key >> 32), (int)(e[i].key & 0xffffffffu));
    for (int t = nt0 - 1; t >= 0; --t) {
        const int a = m->tri[3 * t], b = m->tri[3 * t + 1], c = m->tri[3 * t + 2];
        const int ab = mid[3 * t], bc = mid[3 * t + 1], ca = mid[3 * t + 2];
        const int q[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
        memcpy(m->tri + 12 * (size_t)t, q, sizeof q);
    }
    m->nv = nv;
    m->nt = 4 * nt0;
    free(e);
    free(mid);
    return 0;
fail:
    free(e);
    free(mid);
    return -1;
}

/* One pass of longest-edge bisection: edges in decreasing length, each splitting
 * its (not yet split) triangles, until the count reaches target. */
static int bisect_pass(mesh *m, long target)
{
    kv *e = sorted_edges(m), *order = NULL;
    size_t *first = NULL, ne = 0, nchosen = 0;
    unsigned char *busy = calloc((size_t)m->nt, 1);
    const size_t nref = 3 * (size_t)m->nt;
    if (!e || !busy || !(first = malloc(sizeof *first * (nref + 1))) || !(order = malloc(sizeof *order * (nref + 1)))) goto fail;
    for (size_t i = 0; i < nref; ++i)
        if (i == 0 || e[i].key != e[i - 1].key) {
            double d[3];
            v3_sub(d, m->pos + 3 * (e[i].key >> 32), m->pos + 3 * (e[i].key & 0xffffffffu));
            const float len2 = (float)v3_dot(d, d);
            uint32_t bits;
            memcpy(&bits, &len2, sizeof bits);
            order[ne].key = ~(uint64_t)bits; /* ascending key = decreasing length */
            order[ne].ref = (int64_t)ne;
            first[ne++] = i;
        }
    first[ne] = nref;
    if (radix_sort(order, ne)) goto fail;
    long nt = m->nt;
    for (size_t o = 0; o < ne && nt < target; ++o) {
        const size_t u = (size_t)order[o].ref;
        int free_ = 1;
        for (size_t i = first[u]; i < first[u + 1]; ++i) free_ &= !busy[e[i].ref / 3];
        if (!free_) continue;
        for (size_t i = first[u]; i < first[u + 1]; ++i) busy[e[i].ref / 3] = 1;
        nt += (long)(first[u + 1] - first[u]);
        order[nchosen++].ref = (int64_t)u;
    }
    if (nchosen == 0 || nt > 0x7fffffffL || grow(m, m->nv + (int)nchosen, (int)nt)) goto fail;
    int nv = m->nv, ntri = m->nt;
    for (size_t c = 0; c < nchosen; ++c) {
        const size_t u = (size_t)order[c].ref;
        const int v = nv++;
        midpoint(m, v, (int)(e[first[u]].key >> 32), (int)(e[first[u]].key & 0xffffffffu));
        for (size_t i = first[u]; i < first[u + 1]; ++i) {
            int *t = m->tri + 3 * (e[i].ref / 3);
            const int k = (int)(e[i].ref % 3), a = t[k], b = t[(k + 1) % 3], cc = t[(k + 2) % 3];
            t[0] = a;
            t[1] = v;
            t[2] = cc;
            const int q[3] = {v, b, cc};
            memcpy(m->tri + 3 * (size_t)ntri++, q, sizeof q);
        }
    }
    m->nv = nv;
    m->nt = ntri;
    free(e);
    free(order);
    free(first);
    free(busy);
    return 0;
fail:
    free(e);
    free(order);
    free(first);
    free(busy);
    return -1;
}

/* A 10-bit coordinate q spread to bits 0, 3, 6, ... (Morton interleave). */
static uint64_t spread3(uint64_t q)
{
    q = (q | q << 16) & 0x030000FFu;
    q = (q | q << 8) & 0x0300F00Fu;
    q = (q | q << 4) & 0x030C30C3u;
    return (q | q << 2) & 0x09249249u;
}

/* Morton code of point c: 10 bits per axis over the box [lo, hi]. */
static uint64_t morton_code(const double c[3], const double lo[3], const double hi[3])
{
    uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
        const double u = hi[a] > lo[a] ? (c[a] - lo[a]) / (hi[a] - lo[a]) * 1024.0 : 0.0;
        code |= spread3(u < 0.0 ? 0 : u >= 1023.0 ? 1023 : (uint64_t)u) << a;
    }
    return code;
}

int mesh_locality_order(const mesh *m, double **pos, int **tri, int **tri_id, int *nv)
{
    double lo[3], hi[3];
    mesh_bounds(m, lo, hi);
    kv *order = malloc(sizeof *order * ((size_t)m->nt + 1));
    int *id = malloc(sizeof(int) * ((size_t)m->nv + 1));
    *pos = malloc(sizeof(double) * 3 * ((size_t)m->nv + 1));
    *tri = malloc(sizeof(int) * 3 * ((size_t)m->nt + 1));
    *tri_id = malloc(sizeof(int) * ((size_t)m->nt + 1));
    if (!order || !id || !*pos || !*tri || !*tri_id) goto fail;
    for (int t = 0; t < m->nt; ++t) {
        const int *v = m->tri + 3 * (size_t)t;
        double c[3];
        for (int a = 0; a < 3; ++a) c[a] = (m->pos[3 * v[0] + a] + m->pos[3 * v[1] + a] + m->pos[3 * v[2] + a]) / 3.0;
        order[t] = (kv){morton_code(c, lo, hi), t};
    }
    if (radix_sort(order, (size_t)m->nt)) goto fail;
    for (int v = 0; v < m->nv; ++v) id[v] = -1;
    *nv = 0;
    for (int i = 0; i < m->nt; ++i) {
        const int t = (int)order[i].ref;
        (*tri_id)[i] = t;
        for (int k = 0; k < 3; ++k) {
            const int v = m->tri[3 * (size_t)t + k];
            if (id[v] < 0) {
                id[v] = (*nv)++;
                memcpy(*pos + 3 * (size_t)id[v], m->pos + 3 * (size_t)v, sizeof(double) * 3);
            }
            (*tri)[3 * (size_t)i + k] = id[v];
        }
    }
    free(order);
    free(id);
    return 0;
fail:
    free(order);
    free(id);
    free(*pos);
    free(*tri);
    free(*tri_id);
    *pos = NULL;
    *tri = *tri_id = NULL;
    return -1;
}

int mesh_vertex_order(mesh *m)
{
    double lo[3], hi[3];
    mesh_bounds(m, lo, hi);
    kv *order = malloc(sizeof *order * ((size_t)m->nv + 1));
    int *id = malloc(sizeof(int) * ((size_t)m->nv + 1));
    double *pos = malloc(sizeof(double) * 3 * ((size_t)m->nv + 1)), *nrm = malloc(sizeof(double) * 3 * ((size_t)m->nv + 1));
    int *mat = m->mat ? malloc(sizeof(int) * ((size_t)m->nv + 1)) : NULL;
    int st = -1;
    if (!order || !id || !pos || !nrm || (m->mat && !mat)) goto done;
    for (int v = 0; v < m->nv; ++v) order[v] = (kv){morton_code(m->pos + 3 * (size_t)v, lo, hi), v};
    if (radix_sort(order, (size_t)m->nv)) goto done;
    for (int i = 0; i < m->nv; ++i) {
        const int v = (int)order[i].ref;
        id[v] = i;
        memcpy(pos + 3 * (size_t)i, m->pos + 3 * (size_t)v, sizeof(double) * 3);
        memcpy(nrm + 3 * (size_t)i, m->nrm + 3 * (size_t)v, sizeof(double) * 3);
        if (mat) mat[i] = m->mat[v];
    }
    for (size_t k = 0; k < 3 * (size_t)m->nt; ++k) m->tri[k] = id[m->tri[k]];
    double *old_pos = m->pos, *old_nrm = m->nrm; /* freed below */
    int *old_mat = m->mat;
    m->pos = pos;
    m->nrm = nrm;
    m->mat = mat;
    pos = old_pos;
    nrm = old_nrm;
    mat = old_mat;
    st = 0;
done:
    free(order);
    free(id);
    free(pos);
    free(nrm);
    free(mat);
    return st;
}

int mesh_subdivide_to(mesh *m, long target)
{
    while (4L * m->nt <= target)
        if (split4(m)) return -1;
    while (m->nt < target)
        if (bisect_pass(m, target)) return -1;
    return 0;
}

int mesh_sphere(mesh *m, double r, int level)
{
    const double p = (1.0 + sqrt(5.0)) / 2.0;
    const double v[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                             {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
    static const int f[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                              3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    if (level < 0 || mesh_alloc(m, 12, 20)) return -1;
    memcpy(m->pos, v, sizeof v);
    memcpy(m->nrm, v, sizeof v);
    memcpy(m->tri, f, sizeof f);
    for (int i = 0; i < level; ++i)
        if (split4(m)) {
            mesh_free(m);
            return -1;
        }
    for (int i = 0; i < m->nv; ++i) {
        double *q = m->pos + 3 * i;
        v3_normalize(q);
        memcpy(m->nrm + 3 * i, q, sizeof(double) * 3);
        v3_scale(q, q, r);
    }
    orient_to_normals(m);
    return 0;
}

void mesh_transform(mesh *m, const double a[12])
{
    /* cofactor matrix = det * inverse transpose; its sign keeps normals outward */
    double c[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            c[3 * i + j] = a[3 * i1 + j1] * a[3 * i2 + j2] - a[3 * i1 + j2] * a[3 * i2 + j1];
        }
    const double det = a[0] * c[0] + a[1] * c[1] + a[2] * c[2];
    for (int v = 0; v < m->nv; ++v) {
        double *p = m->pos + 3 * v, *n = m->nrm + 3 * v, q[3], r[3];
        for (int i = 0; i < 3; ++i) {
            q[i] = a[3 * i] * p[0] + a[3 * i + 1] * p[1] + a[3 * i + 2] * p[2] + a[9 + i];
            r[i] = c[3 * i] * n[0] + c[3 * i + 1] * n[1] + c[3 * i + 2] * n[2];
        }
        memcpy(p, q, sizeof q);
        v3_scale(n, r, det < 0 ? -1.0 : 1.0);
        v3_normalize(n);
    }
    if (det < 0) /* a reflection flips the winding */
        for (int t = 0; t < m->nt; ++t) {
            const int tmp = m->tri[3 * t + 1];
            m->tri[3 * t + 1] = m->tri[3 * t + 2];
            m->tri[3 * t + 2] = tmp;
        }
}

int mesh_append(mesh *dst, const mesh *src, int mat)
{
    const int nv0 = dst->nv, nt0 = dst->nt;
    if (!dst->mat) {
        dst->mat = malloc(sizeof(int) * (size_t)(nv0 ? nv0 : 1));
        if (!dst->mat) return -1;
        for (int i = 0; i < nv0; ++i) dst->mat[i] = 0;
    }
    if ((long)nv0 + src->nv > 0x7fffffffL / 3 || (long)nt0 + src->nt > 0x7fffffffL / 3 ||
        grow(dst, nv0 + src->nv, nt0 + src->nt))
        return -1;
    memcpy(dst->pos + 3 * (size_t)nv0, src->pos, sizeof(double) * 3 * (size_t)src->nv);
    memcpy(dst->nrm + 3 * (size_t)nv0, src->nrm, sizeof(double) * 3 * (size_t)src->nv);
    for (int i = 0; i < src->nv; ++i) dst->mat[nv0 + i] = src->mat ? src->mat[i] : mat;
    for (size_t i = 0; i < 3 * (size_t)src->nt; ++i) dst->tri[3 * (size_t)nt0 + i] = src->tri[i] + nv0;
    dst->nv += src->nv;
    dst->nt += src->nt;
    return 0;
}

void mesh_compute_normals(mesh *m)
{
    memset(m->nrm, 0, sizeof(double) * 3 * (size_t)m->nv);
    for (int t = 0; t < m->nt; ++t) {
        const int *v = m->tri + 3 * t;
        double e1[3], e2[3], f[3];
        v3_sub(e1, m->pos + 3 * v[1], m->pos + 3 * v[0]);
        v3_sub(e2, m->pos + 3 * v[2], m->pos + 3 * v[0]);
        v3_cross(f, e1, e2);
        for (int k = 0; k < 3; ++k) v3_add(m->nrm + 3 * v[k], m->nrm + 3 * v[k], f);
    }
    for (int i = 0; i < m->nv; ++i)
        if (v3_normalize(m->nrm + 3 * i) == 0.0) v3_set(m->nrm + 3 * i, 0, 1, 0);
}

void mesh_bounds(const mesh *m, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; ++a) {
        lo[a] = m->nv ? m->pos[a] : 0.0;
        hi[a] = lo[a];
    }
    for (int i = 0; i < m->nv; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = fmin(lo[a], m->pos[3 * i + a]);
            hi[a] = fmax(hi[a], m->pos[3 * i + a]);
        }
}

static uint64_t fnv(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

uint64_t mesh_hash(const mesh *m)
{
    uint64_t h = 0xcbf29ce484222325ull;
    h = fnv(h, &m->nv, sizeof m->nv);
    h = fnv(h, &m->nt, sizeof m->nt);
    h = fnv(h, m->pos, sizeof(double) * 3 * (size_t)m->nv);
    h = fnv(h, m->nrm, sizeof(double) * 3 * (size_t)m->nv);
    return fnv(h, m->tri, sizeof(int) * 3 * (size_t)m->nt);
}

int mesh_write_oracle(const mesh *m, const double *alb, const char *dir, const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    const size_t nv3 = 3 * (size_t)m->nv, nt3 = 3 * (size_t)m->nt;
    int st = fwrite(m->pos, sizeof(double), nv3, f) != nv3;
    st = st || fwrite(m->nrm, sizeof(double), nv3, f) != nv3;
    st = st || fwrite(alb, sizeof(double), nt3, f) != nt3;
    st = st || fwrite(m->tri, sizeof(int), nt3, f) != nt3;
    st = fclose(f) || st;
    return st ? -1 : 0;
}
