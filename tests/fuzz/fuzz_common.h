/* Shared pieces of the libFuzzer targets (tests/fuzz/fuzz_*.c): a byte reader
 * that decodes arbitrary input into lmax, counts and coordinates (including NaN,
 * infinities, denormals, 1e300 and -0.0), a builder of exactly planar, simple
 * polygons with an independent long-double geometry reference, guard-filled
 * output buffers, and FUZZ_CHECK, which prints the violated property and aborts
 * so that libFuzzer records the input.  Input format: tests/fuzz/README.md.
 *
 * Everything here is static: each target is one translation unit. */
#ifndef SHL_FUZZ_COMMON_H
#define SHL_FUZZ_COMMON_H

#include "shlight.h"
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* shl__alloc_fail_after: the library is built with -DSHL_ALLOC_HOOKS for the fuzzers. */
#include "internal.h"

/* ---- failure reporting ------------------------------------------------- */
static const char *fz_target_name = "fuzz";

__attribute__((noreturn, format(printf, 3, 4))) static void fz_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "\n%s: property violated at %s:%d: ", fz_target_name, file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
    abort();
}
#define FUZZ_CHECK(cond, ...)                                                  \
    do {                                                                       \
        if (!(cond)) fz_fail(__FILE__, __LINE__, "(" #cond ") " __VA_ARGS__); \
    } while (0)

/* ---- input reader: returns zeros once the input is exhausted ----------- */
typedef struct {
    const uint8_t *p;
    size_t n, i;
} fz_in;

static inline uint8_t fz_u8(fz_in *in) { return in->i < in->n ? in->p[in->i++] : 0; }
static inline uint16_t fz_u16(fz_in *in) { return (uint16_t)(fz_u8(in) | (unsigned)fz_u8(in) << 8); }
static inline uint32_t fz_u32(fz_in *in) { return fz_u16(in) | (uint32_t)fz_u16(in) << 16; }
static inline uint64_t fz_u64(fz_in *in) { return fz_u32(in) | (uint64_t)fz_u32(in) << 32; }

/* A double: one selector byte (low 5 bits: kind, bit 5: sign), then payload.
 * About 1 in 10 values is NaN or infinite. */
static inline double fz_real(fz_in *in)
{
    const uint8_t s = fz_u8(in);
    const double sign = (s & 0x20) ? -1.0 : 1.0;
    double v;
    switch (s & 0x1f) {
    case 0: return NAN;
    case 1: return sign * INFINITY;
    case 2: v = 0.0; break;                                  /* +-0 */
    case 3: v = 0x1p-1074; break;                            /* smallest denormal */
    case 4: v = DBL_MIN; break;
    case 5: v = DBL_MAX; break;
    case 6: v = 1e300; break;
    case 7: v = 1e-300; break;
    case 8: {                                                /* 8 raw bytes: any bit pattern */
        const uint64_t b = fz_u64(in);
        memcpy(&v, &b, sizeof v);
        return v;
    }
    case 9: v = (int8_t)fz_u8(in); break;                    /* small integer */
    case 10: v = (int16_t)fz_u16(in) / 256.0; break;
    case 11: v = 1.0 + (int8_t)fz_u8(in) * DBL_EPSILON; break; /* 1 +- a few ulps */
    case 12: v = ldexp((int16_t)fz_u16(in), (int8_t)fz_u8(in)); break;
    case 13: v = 1e-9 * (int8_t)fz_u8(in); break;
    case 14: v = ldexp((double)fz_u32(in), (int)(fz_u16(in) % 2200) - 1130); break; /* any exponent, denormals */
    case 15: v = (int16_t)fz_u16(in) / 4096.0 + 1e-12 * (int8_t)fz_u8(in); break;
    case 16: v = 1.0 - (int8_t)fz_u8(in) * 1e-9; break;
    case 17: v = 1e150 * (int8_t)fz_u8(in); break;
    case 18: v = 1e-150 * (int8_t)fz_u8(in); break;
    case 19: v = 0x1p-1022 * (int8_t)fz_u8(in); break;      /* denormal range */
    default: v = (int16_t)fz_u16(in) / 64.0; break;           /* ordinary values */
    }
    return sign * v;
}

/* lmax: 0..30 mostly; sometimes an invalid one (31, -1, INT_MIN). */
static inline int fz_lmax(fz_in *in)
{
    const uint8_t b = fz_u8(in);
    if (b == 0xff) return SHL_LMAX_MAX + 1;
    if (b == 0xfe) return -1;
    if (b == 0xfd) return -2147483647 - 1;
    return b % (SHL_LMAX_MAX + 1);
}

/* Vertex count: 3..64 mostly; sometimes invalid (0, 1, 2, 65, -1). */
static inline int fz_count(fz_in *in)
{
    const uint8_t b = fz_u8(in);
    switch (b) {
    case 0xff: return 2;
    case 0xfe: return SHL_MAX_VERTS + 1;
    case 0xfd: return 0;
    case 0xfc: return -1;
    case 0xfb: return 1;
    default: return 3 + b % (SHL_MAX_VERTS - 2);
    }
}

/* v rounded to float, through a volatile (GCC 12.2 -O2 turns a short loop of double ->
 * float -> double round trips into copies: tests/fuzz/crashes/gcc12-slp-float-roundtrip.c). */
static inline float fz_to_float(double v)
{
    volatile float f = (float)v;
    return f;
}

static inline int all_finite_d(const double *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}
static inline int all_finite_f(const float *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* ---- guard-filled output buffers -------------------------------------- *
 * Buffers are malloc'ed at their exact size (ASan sees any overrun) and
 * filled with a signalling-NaN pattern; "untouched" compares the bytes. */
#define FZ_GUARD_BYTE 0xA7
static inline void *fz_guarded(size_t bytes)
{
    void *p = malloc(bytes ? bytes : 1);
    if (!p) abort();
    memset(p, FZ_GUARD_BYTE, bytes ? bytes : 1);
    return p;
}
static inline int fz_untouched(const void *p, size_t bytes)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < bytes; ++i)
        if (c[i] != FZ_GUARD_BYTE) return 0;
    return 1;
}

/* ---- contexts (created once; immutable) --------------------------------- */
static shl_ctx *fz_ctxs[SHL_LMAX_MAX + 1];
static inline const shl_ctx *fz_ctx(int lmax)
{
    if (!fz_ctxs[lmax] && shl_ctx_create(lmax, &fz_ctxs[lmax]) != SHL_OK) abort();
    return fz_ctxs[lmax];
}

/* K_l = sqrt((2l+1)/(4 pi)) = max over directions of |Y_lm| (addition theorem). */
static inline double fz_kl(int l) { return sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); }


/* ---- polygons ------------------------------------------------------------ *
 * Structured polygons are exactly planar and simple by construction: 2-D
 * integer points (int16) scaled by 2^e, ordered by an exact integer
 * construction (convex hull, or an x-monotone polygon: lower chain below the
 * line from the leftmost to the rightmost point, upper chain above, which
 * never cross), placed in the plane Z = h or the tilted plane Z = 2^k X (both
 * exact), then the axes permuted and negated (exact).  Repeated vertices may
 * be inserted (the library drops them: results must be bit-identical).  When
 * scaling rounds (under/overflow), the polygon is marked inexact and only the
 * robustness properties are checked.  Raw polygons take any coordinates. */
typedef struct {
    int n;                               /* count passed to the API (may be invalid) */
    int nv;                              /* vertices stored (>= 3 when n is valid) */
    double v[3 * (SHL_MAX_VERTS + 2)];   /* world coordinates */
    double v_nodup[3 * (SHL_MAX_VERTS + 2)];
    int n_nodup, has_dups;
    int structured, exact;
    /* structured geometry, in q-space (before the axis permutation / negation) */
    int perm[3];                         /* world[perm[i]] = sign[i] * q[i] */
    double sign[3];
    int tilted, tk;                      /* plane Z = 2^tk X, else Z = h */
    double h;
    int nd;                              /* distinct vertices in order (q-space, 2-D ints) */
    long long ia[SHL_MAX_VERTS], ib[SHL_MAX_VERTS];
    int e;                               /* 2-D scale 2^e */
} fz_poly;

static inline int fz_cmp_pt(const long long *a, const long long *b) { return a[0] != b[0] ? (a[0] < b[0] ? -1 : 1) : (a[1] < b[1] ? -1 : a[1] > b[1]); }
static inline long long fz_orient(const long long *o, const long long *a, const long long *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* Sort distinct points (insertion sort, <= 64 points) and build the polygon order. */
static inline int fz_order_points(long long (*pt)[2], int k, int hull, long long (*out)[2])
{
    for (int i = 1; i < k; ++i)
        for (int j = i; j > 0 && fz_cmp_pt(pt[j - 1], pt[j]) > 0; --j) {
            long long t0 = pt[j][0], t1 = pt[j][1];
            pt[j][0] = pt[j - 1][0], pt[j][1] = pt[j - 1][1];
            pt[j - 1][0] = t0, pt[j - 1][1] = t1;
        }
    int m = 0;
    for (int i = 0; i < k; ++i)
        if (m == 0 || fz_cmp_pt(pt[m - 1], pt[i]) != 0) pt[m][0] = pt[i][0], pt[m][1] = pt[i][1], ++m;
    k = m;
    if (k < 3) {
        for (int i = 0; i < k; ++i) out[i][0] = pt[i][0], out[i][1] = pt[i][1];
        return k;
    }
    int n = 0;
    if (hull) { /* Andrew's monotone chain, strictly convex, counter-clockwise */
        long long h[2 * SHL_MAX_VERTS + 2][2];
        for (int i = 0; i < k; ++i) {
            while (n >= 2 && fz_orient(h[n - 2], h[n - 1], pt[i]) <= 0) --n;
            h[n][0] = pt[i][0], h[n][1] = pt[i][1], ++n;
        }
        for (int i = k - 2, t = n + 1; i >= 0; --i) {
            while (n >= t && fz_orient(h[n - 2], h[n - 1], pt[i]) <= 0) --n;
            h[n][0] = pt[i][0], h[n][1] = pt[i][1], ++n;
        }
        --n; /* the last point repeats the first */
        if (n < 3) n = n < 0 ? 0 : n;
        for (int i = 0; i < n; ++i) out[i][0] = h[i][0], out[i][1] = h[i][1];
        return n;
    }
    /* x-monotone: L, lower chain ascending, R, upper chain descending (counter-clockwise) */
    const long long *L = pt[0], *R = pt[k - 1];
    out[n][0] = L[0], out[n][1] = L[1], ++n;
    for (int i = 1; i < k - 1; ++i)
        if (fz_orient(L, R, pt[i]) <= 0) out[n][0] = pt[i][0], out[n][1] = pt[i][1], ++n;
    out[n][0] = R[0], out[n][1] = R[1], ++n;
    for (int i = k - 2; i >= 1; --i)
        if (fz_orient(L, R, pt[i]) > 0) out[n][0] = pt[i][0], out[n][1] = pt[i][1], ++n;
    return n;
}

/* q-space coordinates of a 2-D point */
static inline void fz_q_of(const fz_poly *P, long long a, long long b, double q[3], int *exact)
{
    const double X = ldexp((double)a, P->e), Y = ldexp((double)b, P->e);
    if (!(ldexp(X, -P->e) == (double)a && ldexp(Y, -P->e) == (double)b)) *exact = 0;
    q[0] = X;
    q[1] = Y;
    if (P->tilted) {
        q[2] = ldexp(X, P->tk);
        if (!(isfinite(q[2]) && ldexp(q[2], -P->tk) == X)) *exact = 0;
    } else {
        q[2] = P->h;
    }
}

static inline void fz_world_of(const fz_poly *P, const double q[3], double w[3])
{
    for (int i = 0; i < 3; ++i) w[P->perm[i]] = P->sign[i] * q[i];
}
static inline void fz_q_of_world(const fz_poly *P, const double w[3], double q[3])
{
    for (int i = 0; i < 3; ++i) q[i] = P->sign[i] * w[P->perm[i]];
}

static const int fz_perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

/* Decode a polygon.  Layout: mode byte, count byte, then mode-specific bytes. */
static inline void fz_polygon_ex(fz_in *in, fz_poly *P, int as_float);
static inline void fz_polygon(fz_in *in, fz_poly *P) { fz_polygon_ex(in, P, 0); }

/* as_float: coordinates meant for the float entry points; the plane offset is
 * rounded to float and the polygon is exact only if every coordinate is a float. */
static inline void fz_polygon_ex(fz_in *in, fz_poly *P, int as_float)
{
    memset(P, 0, sizeof *P);
    const uint8_t mode = fz_u8(in);
    P->n = fz_count(in);
    const int want = P->n >= 3 && P->n <= SHL_MAX_VERTS ? P->n : 3; /* vertices to decode */
    if ((mode & 3) == 3) { /* raw: any coordinates */
        /* q-space = world space, plane Z = 0, for fz_point's "in or near the plane" mode
         * (with the zeroed perm and sign it wrote one coordinate and left two unset) */
        memcpy(P->perm, fz_perms[0], sizeof P->perm);
        P->sign[0] = P->sign[1] = P->sign[2] = 1.0;
        P->nv = want;
        for (int i = 0; i < 3 * want; ++i) P->v[i] = fz_real(in);
        if (mode & 0x80) /* near-duplicates: vertex i+1 = vertex i + tiny */
            for (int i = 1; i < want; ++i)
                if (fz_u8(in) & 1)
                    for (int k = 0; k < 3; ++k) P->v[3 * i + k] = P->v[3 * (i - 1) + k] + 1e-9 * (int8_t)fz_u8(in);
        memcpy(P->v_nodup, P->v, sizeof P->v);
        P->n_nodup = P->n;
        return;
    }
    P->structured = 1;
    P->exact = 1;
    const uint8_t eb = fz_u8(in);
    P->e = eb < 160 ? (int)eb - 80 : ((int)eb - 208) * 22; /* [-80, 79] or [-1056, 1034] */
    const uint8_t pb = fz_u8(in);
    memcpy(P->perm, fz_perms[pb % 6], sizeof P->perm);
    for (int i = 0; i < 3; ++i) P->sign[i] = (pb >> (3 + i)) & 1 ? -1.0 : 1.0;
    P->tilted = (mode >> 2) & 1;
    if (P->tilted) P->tk = (int)(fz_u8(in) % 9) - 4;
    else P->h = as_float ? (double)(float)fz_real(in) : fz_real(in);
    const int small = (mode >> 5) & 1; /* coordinates in -8..7: many collinear / repeated points */
    long long pts[SHL_MAX_VERTS][2], ord[2 * SHL_MAX_VERTS][2];
    for (int i = 0; i < want; ++i) {
        pts[i][0] = small ? (int)(fz_u8(in) & 15) - 8 : (int16_t)fz_u16(in);
        pts[i][1] = small ? (int)(fz_u8(in) & 15) - 8 : (int16_t)fz_u16(in);
    }
    int m = fz_order_points(pts, want, mode & 1, ord);
    if (mode & 8) /* reverse the winding */
        for (int i = 0, j = m - 1; i < j; ++i, --j) {
            long long t0 = ord[i][0], t1 = ord[i][1];
            ord[i][0] = ord[j][0], ord[i][1] = ord[j][1];
            ord[j][0] = t0, ord[j][1] = t1;
        }
    const int rot = m > 0 ? fz_u8(in) % m : 0; /* start vertex */
    P->nd = m;
    for (int i = 0; i < m; ++i) P->ia[i] = ord[(i + rot) % m][0], P->ib[i] = ord[(i + rot) % m][1];
    /* vertices: the ordered points, padded with repeats of the last to reach 3 */
    int nv = 0;
    const uint64_t dupmask = (mode & 0x10) ? fz_u64(in) : 0;
    double q[3];
    for (int i = 0; i < m; ++i) {
        fz_q_of(P, P->ia[i], P->ib[i], q, &P->exact);
        fz_world_of(P, q, P->v_nodup + 3 * i);
    }
    P->n_nodup = m;
    for (int i = 0; i < m && nv < SHL_MAX_VERTS; ++i) {
        memcpy(P->v + 3 * nv++, P->v_nodup + 3 * i, sizeof(double) * 3);
        if (((dupmask >> (i & 63)) & 1) && nv + (m - 1 - i) < SHL_MAX_VERTS) { /* room for the rest */
            memcpy(P->v + 3 * nv++, P->v_nodup + 3 * i, sizeof(double) * 3);
            P->has_dups = 1;
        }
    }
    if (nv == 0) { /* no points at all (cannot happen with want >= 3, kept for safety) */
        fz_q_of(P, 0, 0, q, &P->exact);
        fz_world_of(P, q, P->v);
        nv = 1;
    }
    while (nv < 3) {
        memcpy(P->v + 3 * nv, P->v + 3 * (nv - 1), sizeof(double) * 3);
        ++nv;
        P->has_dups = 1;
    }
    P->nv = nv;
    /* the count passed: nv when the requested one was valid; else the invalid request */
    if (P->n >= 3 && P->n <= SHL_MAX_VERTS) P->n = nv;
    if (P->n_nodup < 3) { /* fewer than 3 distinct points: the no-dup variant is padded too */
        memcpy(P->v_nodup, P->v, sizeof P->v);
        P->n_nodup = nv;
        P->has_dups = 0;
    }
    if (!all_finite_d(P->v, 3 * nv)) P->exact = 0;
    if (as_float)
        for (int i = 0; i < 3 * nv; ++i)
            if ((double)(float)P->v[i] != P->v[i]) P->exact = 0;
}

/* sum_e gamma_e / d_e (as fz_geom's gsum) for any polygon, planar or not, from its raw
 * vertices in long double (no over/underflow for double input; rounding 2^-64 relative):
 * gamma_e = the arc angle of edge e seen from x, d_e = the distance from x to its line, so
 * |d L_lm / d x_a| <= K_l times it (moving-boundary bound: the arc's points move at most
 * 1/ell(t) <= 1/d_e per unit of x).  Zero-length edges add nothing; INFINITY when x lies on
 * an edge's line (or a vertex). */
static inline long double fz_raw_grad_bound(const double *v, int n, const double x[3])
{
    long double sum = 0.0L;
    for (int e = 0; e < n; ++e) {
        const double *a = v + 3 * e, *b = v + 3 * ((e + 1) % n);
        long double ra[3], rb[3], ed[3], c[3], cg[3];
        for (int k = 0; k < 3; ++k) {
            ra[k] = (long double)a[k] - x[k];
            rb[k] = (long double)b[k] - x[k];
            ed[k] = (long double)b[k] - a[k];
        }
        const long double elen = sqrtl(ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2]);
        if (elen == 0.0L) continue;
        c[0] = ra[1] * ed[2] - ra[2] * ed[1], c[1] = ra[2] * ed[0] - ra[0] * ed[2], c[2] = ra[0] * ed[1] - ra[1] * ed[0];
        const long double clen = sqrtl(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (clen == 0.0L) return INFINITY;
        cg[0] = ra[1] * rb[2] - ra[2] * rb[1], cg[1] = ra[2] * rb[0] - ra[0] * rb[2], cg[2] = ra[0] * rb[1] - ra[1] * rb[0];
        const long double gamma =
            atan2l(sqrtl(cg[0] * cg[0] + cg[1] * cg[1] + cg[2] * cg[2]), ra[0] * rb[0] + ra[1] * rb[1] + ra[2] * rb[2]);
        sum += gamma / (clen / elen);
    }
    return sum;
}

/* Independent long-double geometry of a structured, exact polygon seen from x:
 *   omega:   solid angle (fan of Van Oosterom-Strackee triangles; triple
 *            products = plane height x exact 2-D cross products),
 *   perim:   sum of the edges' arc angles (the size of the boundary sums),
 *   gsum:    sum_e gamma_e / d_e (d_e = distance from x to edge e's line):
 *            |d L_lm / d x_a| <= K_l gsum (moving-boundary bound),
 *   g2sum:   sum_e gamma_e / d_e^2 (rate of change of gsum),
 *   height:  |distance of x from the plane|, rmax: max |v_i - x|,
 *   scale:   max |coordinate| of x and the vertices.
 * Returns 0 when x lies on an edge's line or a vertex (geometry undefined). */
typedef struct {
    long double omega, perim, gsum, g2sum, height, rmax, scale, dmin;
} fz_geom;

static inline int fz_poly_geom(const fz_poly *P, const double xw[3], fz_geom *G)
{
    memset(G, 0, sizeof *G);
    double xq[3];
    fz_q_of_world(P, xw, xq);
    const int m = P->nd;
    long double scale = fmaxl(fabsl(xq[0]), fmaxl(fabsl(xq[1]), fabsl(xq[2])));
    long double r[SHL_MAX_VERTS][3], q[SHL_MAX_VERTS][3], dist[SHL_MAX_VERTS];
    for (int i = 0; i < m; ++i) {
        int ex = 1;
        double qd[3];
        fz_q_of(P, P->ia[i], P->ib[i], qd, &ex);
        for (int k = 0; k < 3; ++k) {
            q[i][k] = qd[k];
            r[i][k] = (long double)qd[k] - (long double)xq[k];
            scale = fmaxl(scale, fabsl(q[i][k]));
        }
        dist[i] = sqrtl(r[i][0] * r[i][0] + r[i][1] * r[i][1] + r[i][2] * r[i][2]);
        G->rmax = fmaxl(G->rmax, dist[i]);
    }
    G->scale = scale;
    /* plane normal nq = (-2^tk, 0, 1) or (0, 0, 1); signed height ~ plane(v) - plane(x) */
    long double hs, nlen;
    if (P->tilted) {
        hs = ldexpl((long double)xq[0], P->tk) - (long double)xq[2];
        nlen = sqrtl(1.0L + ldexpl(1.0L, 2 * P->tk));
    } else {
        hs = (long double)P->h - (long double)xq[2];
        nlen = 1.0L;
    }
    G->height = fabsl(hs) / nlen;
    if (m < 3) return 1; /* nothing to see: omega = 0 */
    /* Solid angle: fan of spherical triangles (nadir, v_i, v_i+1) from the foot f of x,
     * whose Van Oosterom-Strackee form, divided by the height h, is
     *   tan(omega_i / 2) = (p_i x p_i+1) / (d_i d_i+1 + p_i . p_i+1 + h^2 + h (d_i + d_i+1)),
     * p_i = in-plane part of v_i - x (so d_i^2 = |p_i|^2 + h^2): nothing cancels except
     * d_i d_j + p_i . p_j when the edge passes under x, which is rewritten as
     * ((p_i x p_j)^2 + h^2 (|p_i|^2 + |p_j|^2 + h^2)) / (d_i d_j - p_i . p_j). */
    const long double h = G->height;
    long double om = 0.0L;
    if (h > 0.0L) {
        long double p[SHL_MAX_VERTS][2];
        const long double u1n = P->tilted ? sqrtl(1.0L + ldexpl(1.0L, 2 * P->tk)) : 1.0L;
        for (int i = 0; i < m; ++i) { /* in-plane coordinates: along u1 = (1, 0, 2^tk)/u1n and y */
            p[i][0] = P->tilted ? (r[i][0] + ldexpl(r[i][2], P->tk)) / u1n : r[i][0];
            p[i][1] = r[i][1];
        }
        for (int i = 0; i < m; ++i) {
            const int j = (i + 1) % m;
            /* edge in plane coordinates, exact: (dX u1n, dY) */
            const long double ex = ldexpl((long double)(P->ia[j] - P->ia[i]), P->e) * u1n;
            const long double ey = ldexpl((long double)(P->ib[j] - P->ib[i]), P->e);
            const long double cr = p[i][0] * ey - p[i][1] * ex; /* p_i x p_j = p_i x (p_j - p_i) */
            if (cr == 0.0L) continue;
            const long double pp = p[i][0] * p[j][0] + p[i][1] * p[j][1];
            const long double ni = p[i][0] * p[i][0] + p[i][1] * p[i][1], nj = p[j][0] * p[j][0] + p[j][1] * p[j][1];
            const long double dd = dist[i] * dist[j];
            const long double core = pp >= 0.0L ? dd + pp : (cr * cr + h * h * (ni + nj + h * h)) / (dd - pp);
            om += 2.0L * atan2l(cr, core + h * h + h * (dist[i] + dist[j]));
        }
    }
    G->omega = fabsl(om);
    G->dmin = INFINITY;
    for (int e = 0; e < m; ++e) {
        const int f = (e + 1) % m;
        const long double ed[3] = {q[f][0] - q[e][0], q[f][1] - q[e][1], q[f][2] - q[e][2]};
        const long double el = sqrtl(ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2]);
        if (el == 0.0L) continue;
        const long double *a = r[e];
        const long double c[3] = {a[1] * ed[2] - a[2] * ed[1], a[2] * ed[0] - a[0] * ed[2], a[0] * ed[1] - a[1] * ed[0]};
        const long double cl = sqrtl(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        const long double *b = r[f];
        const long double gamma = atan2l(cl, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
        const long double d = cl / el;
        if (!(d > 0.0L)) return 0;
        G->dmin = fminl(G->dmin, d);
        G->perim += gamma;
        G->gsum += gamma / d;
        G->g2sum += gamma / d / d;
    }
    for (int i = 0; i < m; ++i)
        if (!(dist[i] > 0.0L)) return 0;
    return 1;
}

/* FZ_VERBOSE=1 in the environment: print the decoded input (replaying a crash). */
static int fz_verbose = -1;
static inline int fz_is_verbose(void)
{
    if (fz_verbose < 0) fz_verbose = getenv("FZ_VERBOSE") != NULL;
    return fz_verbose;
}
static inline void fz_dump_vec(const char *what, const double *v, int n)
{
    if (!fz_is_verbose()) return;
    fprintf(stderr, "%s:", what);
    for (int i = 0; i < n; ++i) fprintf(stderr, "%s%.17g", i % 3 ? ", " : i ? "\n   " : " ", v[i]);
    fprintf(stderr, "\n");
}
static inline void fz_dump_poly(const fz_poly *P)
{
    if (!fz_is_verbose()) return;
    fprintf(stderr, "polygon n=%d nv=%d structured=%d exact=%d dups=%d tilted=%d tk=%d h=%.17g e=%d perm=%d%d%d\n", P->n,
            P->nv, P->structured, P->exact, P->has_dups, P->tilted, P->tk, P->h, P->e, P->perm[0], P->perm[1], P->perm[2]);
    fz_dump_vec("verts", P->v, 3 * P->nv);
}

/* Point near a polygon.  Layout: mode byte, then mode-specific values. */
static inline void fz_point(fz_in *in, const fz_poly *P, double x[3])
{
    const uint8_t mode = fz_u8(in);
    const int nv = P->nv > 0 ? P->nv : 1;
    const double *v = P->v + 3 * (fz_u8(in) % nv);
    switch (mode % 8) {
    case 0: /* anywhere */
    case 1:
        for (int k = 0; k < 3; ++k) x[k] = fz_real(in);
        return;
    case 2: /* near a vertex */
        for (int k = 0; k < 3; ++k) x[k] = v[k] + fz_real(in);
        return;
    case 3:
    case 4: { /* in or near the plane (q-space Z offset by a tiny or special amount) */
        double q[3], w[3];
        fz_q_of_world(P, v, q);
        q[0] += fz_real(in);
        q[1] += fz_real(in);
        if (P->tilted) q[2] = ldexp(q[0], P->tk);
        else q[2] = P->h;
        if (mode % 8 == 4) q[2] += fz_real(in);
        fz_world_of(P, q, w);
        memcpy(x, w, sizeof w);
        return;
    }
    case 5: { /* near an edge midpoint, off the plane */
        const double *u = P->v + 3 * ((fz_u8(in) % nv + 1) % nv);
        const double t = (fz_u8(in) & 1) ? 0.5 : ldexp(1.0, -(fz_u8(in) % 60));
        for (int k = 0; k < 3; ++k) x[k] = v[k] + t * (u[k] - v[k]) + fz_real(in) * 1e-3;
        return;
    }
    case 6: { /* far away along an axis */
        const double d = fz_real(in);
        for (int k = 0; k < 3; ++k) x[k] = v[k] + (k == (int)(mode >> 3) % 3 ? d : 0.0);
        return;
    }
    default: /* a vertex exactly, or a tiny multiple of the plane offset */
        memcpy(x, v, sizeof(double) * 3);
        if (mode & 0x10) x[(mode >> 5) % 3] += fz_real(in);
        return;
    }
}

#endif
