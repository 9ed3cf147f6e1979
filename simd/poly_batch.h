/* Batched polygon SH coefficients (Wang & Ramamoorthi 2018) and gradients
 * (Wu et al. 2020) for many shading points against one polygon, vectorized
 * ACROSS POINTS: each lane of a vector is one point, and every lane runs the
 * same recurrence.  Written once with the verbs of <isa>/helper.h and compiled
 * once per ISA of simd/isa_list.h (Makefile); with the scalar helper it is
 * plain C.  The recurrence is that of src/polygon_zh.h (see its comments),
 * reorganized for registers: for each lobe and edge the band loop runs to the
 * end with the edge's state in registers; the per-band sums over edges
 * accumulate in memory, and the gradient's I_l,e are stored and summed with
 * mu_e afterwards.  Mirror-paired lobes share their dot products.  Orientation: the polygon is used in its input order
 * and every lane multiplies its result by the sign of its own signed solid
 * angle (reversing the order negates every boundary term and S_0, Eq. 24-29),
 * so points that see different sides need no reordering. */
#include "kernel_api.h"
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define VL SHL_VLEN
#define ISA(name) SHL_ISA_SUFFIX(name)
#define ALWAYS_INLINE __attribute__((always_inline)) inline

/* ---- per-vertex / per-edge geometry fields, in vectors of VL lanes ---- */
enum {
    F_RX, F_RY, F_RZ, F_R, F_IR,  /* rel_v = v - x, r_v = |rel_v|, 1/r_v */
    F_WX, F_WY, F_WZ,             /* omega_v = rel_v / r_v */
    F_LX, F_LY, F_LZ,             /* lambda_e = mu_e x omega_e (Eq. 16) */
    F_MX, F_MY, F_MZ,             /* mu_e (Eq. 19) */
    F_DX, F_DY, F_DZ,             /* omega_f - omega_e, from the edge vector */
    F_GAM, F_SIN, F_COS, F_OMC,   /* gamma_e (Eq. 20), sin, cos, 1 - cos */
    F_GX, F_GY, F_GZ, F_FP1, F_I0, /* gradient: g_e, f'(gamma_e), I_0 (polygon_zh.h) */
    NF
};
/* per-band constants, broadcast */
enum { K_A, K_B, K_ALPHA, K_BETA, K_2LM1, K_INV1, NK };

typedef struct { vf x, y, z; } v3;

static inline v3 v3_load(const float *p) { return (v3){vf_load(p), vf_load(p + VL), vf_load(p + 2 * VL)}; }
static inline void v3_store(float *p, v3 a)
{
    vf_store(p, a.x);
    vf_store(p + VL, a.y);
    vf_store(p + 2 * VL, a.z);
}
static inline vf v3_dot(v3 a, v3 b) { return vf_fma(a.x, b.x, vf_fma(a.y, b.y, vf_mul(a.z, b.z))); }
static inline v3 v3_cross(v3 a, v3 b)
{
    return (v3){vf_fms(a.y, b.z, vf_mul(a.z, b.y)), vf_fms(a.z, b.x, vf_mul(a.x, b.z)),
                vf_fms(a.x, b.y, vf_mul(a.y, b.x))};
}
static inline v3 v3_scale(v3 a, vf s) { return (v3){vf_mul(a.x, s), vf_mul(a.y, s), vf_mul(a.z, s)}; }
static inline v3 v3_add(v3 a, v3 b) { return (v3){vf_add(a.x, b.x), vf_add(a.y, b.y), vf_add(a.z, b.z)}; }
static inline v3 v3_set1(const float p[3]) { return (v3){vf_set1(p[0]), vf_set1(p[1]), vf_set1(p[2])}; }
static inline v3 v3_sel(vm m, v3 a, v3 b) { return (v3){vf_sel(m, a.x, b.x), vf_sel(m, a.y, b.y), vf_sel(m, a.z, b.z)}; }

/* atan2(y, x) per lane.  Reduction to t = lo/hi in [0, 1] (lo, hi = min, max of
 * |x|, |y|), then t > tan(pi/8) maps to (lo - hi)/(lo + hi) + pi/4, so one
 * division serves both; atan(t) = t + t^3 P(t^2) on |t| <= tan(pi/8) with P the
 * relative-error minimax cubic (Remez exchange, max relative error 2.1e-8).
 * Full relative accuracy for tiny angles (t = y/x, no cancellation). */
static inline vf vf_atan2(vf y, vf x)
{
    const vf ax = vf_abs(x), ay = vf_abs(y), lo = vf_min(ax, ay), hi = vf_max(ax, ay);
    const vm big = vf_gt(lo, vf_mul(vf_set1(0.414213562f), hi));
    const vf num = vf_sel(big, vf_sub(lo, hi), lo);
    const vf den = vf_max(vf_sel(big, vf_add(lo, hi), hi), vf_set1(FLT_MIN)); /* atan2(0, 0) = 0 */
    const vf t = vf_div(num, den), z = vf_mul(t, t);
    vf p = vf_fma(vf_set1(0.0805372266f), z, vf_set1(-0.138776787f));
    p = vf_fma(p, z, vf_set1(0.199777100f));
    p = vf_fma(p, z, vf_set1(-0.333329491f));
    vf r = vf_fma(vf_mul(p, z), t, t);
    r = vf_add(r, vf_sel(big, vf_set1(0.785398163f), vf_set1(0.0f)));
    r = vf_sel(vf_gt(ay, ax), vf_sub(vf_set1(1.57079633f), r), r);
    r = vf_sel(vf_lt(x, vf_set1(0.0f)), vf_sub(vf_set1(3.14159265f), r), r);
    return vf_copysign(r, y);
}

/* ---- workspace ---- */
typedef struct {
    float *geo;   /* [SHL_MAX_VERTS][NF] vectors */
    float *avtx;  /* [SHL_MAX_VERTS][2]: lobe . omega_v for the current lobe pair */
    float *lane;  /* x, y, z, h, valid: [5] vectors */
    float *kv;    /* [lmax + 2][NK] */
    float *acc;   /* [2 lobes][lmax + 2]: sum_e c_e B_l,e (ACC) */
    float *ib;    /* [2 lobes][SHL_MAX_VERTS][lmax + 2]: I_l,e of the gradient (IB) */
    float *u, *v; /* [nq][lmax + 1 pairs][lmax + 1]: paired sums and differences (zh_tables.h) */
    float *soa;   /* [nq * nc]: SH coefficients of the block, one vector per row (light sets: lobe sums) */
} work_t;

static size_t work_floats(int lmax, int nq, work_t *w, float *base)
{
    const size_t L = (size_t)lmax + 1, nc = L * L;
    const size_t sizes[8] = {SHL_MAX_VERTS * NF, 2 * SHL_MAX_VERTS, 5, (L + 1) * NK, 2 * (L + 1),
                             nq > 1 ? 2 * SHL_MAX_VERTS * (L + 1) : 0, nq * L * L, nq * L * L};
    float **dst[8] = {&w->geo, &w->avtx, &w->lane, &w->kv, &w->acc, &w->ib, &w->u, &w->v};
    size_t ofs = 0;
    for (int i = 0; i < 8; ++i) {
        if (base) *dst[i] = base + ofs * VL;
        ofs += sizes[i];
    }
    if (base) w->soa = base + ofs * VL;
    return (ofs + nq * nc) * VL;
}

size_t ISA(shl__poly_work_bytes)(int lmax, int with_grad)
{
    work_t w;
    return sizeof(float) * work_floats(lmax, with_grad ? 4 : 1, &w, NULL) + 64; /* + alignment */
}

#define GEO(w, v, f) ((w)->geo + ((size_t)(v) * NF + (f)) * VL)
#define KV(w, l, k) vf_load((w)->kv + ((size_t)(l) * NK + (k)) * VL)

/* The lanes' set-up runs in double, VD lanes at a time (half a float vector: the
 * ISA's double register) in the compilers' generic vectors (as
 * simd/poly_zh_batch.h): elementwise arithmetic and compares, selects as bit masks. */
#if VL > 1
#define VD (VL / 2)
#else
#define VD 1
#endif
typedef double vdl __attribute__((vector_size(VD * sizeof(double))));
typedef long long vml __attribute__((vector_size(VD * sizeof(long long))));
typedef float vfl __attribute__((vector_size(VD * sizeof(float))));

static inline vdl vdl_set1(double a) /* through memory: see lanes_setup on valgrind */
{
    double t[VD];
    for (int j = 0; j < VD; ++j) t[j] = a;
    vdl v;
    memcpy(&v, t, sizeof v);
    return v;
}
static inline vdl vdl_sel(vml m, vdl a, vdl b) { return (vdl)(((vml)a & m) | ((vml)b & ~m)); } /* m ? a : b */
static inline vdl vdl_abs(vdl a) { return (vdl)((vml)a & ~(vml)vdl_set1(-0.0)); }
static inline void vdl_store_float(float *p, vdl a)
{
    const vfl f = __builtin_convertvector(a, vfl);
    memcpy(p, &f, sizeof f);
}

/* Lanes of a block, in double: the scaled point (stored relative to v_0, as are P->v and
 * P->proxy: a polygon far from the origin stays within float range), the plane test of
 * shl_polygon_f (polygon.c, shl__poly_geom_init; squared form), and h = normal . (v_0 - x).
 * Lanes past nvalid, not kept (keep[j] = 0; keep NULL keeps all), in the plane, or
 * farther than 2^40 extents from the polygon (products of three distances must stay
 * in float range) evaluate the proxy point with valid = 0.  (A valid point is at
 * least 2^-50 extents from every vertex, its height; the rmin2 test only guards that
 * bound.)  Also the points the float geometry cannot resolve (the test and its error
 * analysis: shl__batch_poly_eval, src/batch.c): their indices p0 + j go to redo;
 * returns their number.  to_acc: those get valid = 0 too (the caller adds their
 * scalar-path results). */
static int lanes_setup(const shl__batch_poly *P, const float *pts, int nvalid, const unsigned char *keep, int to_acc,
                       work_t *w, int p0, int *redo)
{
    const double tol = 8.0 * DBL_EPSILON, pp = P->perimeter * P->perimeter * 0x1p10;
    const double hp = -(P->normal[0] * P->proxy[0] + P->normal[1] * P->proxy[1] + P->normal[2] * P->proxy[2]);
    int count = 0;
    for (int j0 = 0; j0 < VL; j0 += VD) {
        double xs[3][VD], ls[VD];
        for (int j = 0; j < VD; ++j) { /* lanes past nvalid or not kept repeat point 0 (finite; masked below) */
            const int in = j0 + j < nvalid && (!keep || keep[j0 + j]);
            const float *pt = pts + 3 * (in ? j0 + j : 0);
            for (int k = 0; k < 3; ++k) xs[k][j] = pt[k] * P->inv_scale;
            ls[j] = in ? j0 + j : VL;
        }
        /* whole-vector loads: element-wise insertion made gcc emit the register form of
         * VEX vmovq (0xD6), which valgrind 3.19 (make test-valgrind) cannot decode */
        vdl x[3], lane;
        memcpy(x, xs, sizeof x);
        memcpy(&lane, ls, sizeof lane);
        vdl rmax2 = vdl_set1(0.0), rmin2 = vdl_set1(HUGE_VAL);
        for (int i = 0; i < P->n; ++i) {
            const vdl d0 = vdl_set1(P->vd[i][0]) - x[0], d1 = vdl_set1(P->vd[i][1]) - x[1];
            const vdl d2 = vdl_set1(P->vd[i][2]) - x[2], r2 = d0 * d0 + d1 * d1 + d2 * d2;
            rmax2 = vdl_sel(r2 > rmax2, r2, rmax2);
            rmin2 = vdl_sel(r2 < rmin2, r2, rmin2);
        }
        const vdl h = vdl_set1(P->normal[0]) * (vdl_set1(P->vd[0][0]) - x[0]) +
                      vdl_set1(P->normal[1]) * (vdl_set1(P->vd[0][1]) - x[1]) +
                      vdl_set1(P->normal[2]) * (vdl_set1(P->vd[0][2]) - x[2]);
        const vdl h2 = h * h;
        const vml seen = (lane < vdl_set1(nvalid)) & (h2 > vdl_set1(tol * tol) * rmax2 * vdl_set1(P->len2)) &
                         (rmax2 <= vdl_set1(0x1p80));
        const vml ok = seen & (rmin2 >= vdl_set1(0x1p-100));
        const vml unres = seen & ((h2 <= vdl_set1(0x1p-32) * rmax2 * vdl_set1(P->len2)) | (rmin2 < vdl_set1(0x1p-32)) |
                                  (vdl_set1(pp) < rmin2) | (vdl_set1(P->perimeter) * rmax2 > vdl_set1(0x1p13) * vdl_abs(h)));
        for (int k = 0; k < 3; ++k) /* relative to v_0, as P->v (float range) */
            vdl_store_float(w->lane + k * VL + j0, vdl_sel(ok, x[k] - vdl_set1(P->vd[0][k]), vdl_set1(P->proxy[k])));
        vdl_store_float(w->lane + 3 * VL + j0, vdl_sel(ok, h, vdl_set1(hp)));
        const vml used = to_acc ? ok & ~unres : ok; /* accumulated lanes: the scalar path adds the unresolved ones */
        vdl_store_float(w->lane + 4 * VL + j0, vdl_sel(used, vdl_set1(1.0), vdl_set1(0.0)));
        for (int j = 0; j < VD; ++j)
            if (unres[j]) redo[count++] = p0 + j0 + j;
    }
    return count;
}

/* Per-vertex and per-edge geometry of the block's points (cf. shl__poly_geom_init),
 * all in float lanes; returns the signed solid angle S_0 (Van Oosterom-Strackee fan). */
static ALWAYS_INLINE vf geometry(const shl__batch_poly *P, work_t *w, const int grad)
{
    const int n = P->n;
    const v3 x = v3_load(w->lane);
    /* |t| = |h| / |normal|: distance to the plane; sign(h) = the side seen */
    const vf h = vf_load(w->lane + 3 * VL), t = vf_mul(vf_abs(h), vf_set1(P->inv_len));
    const v3 nu = v3_set1(P->unit_normal);
    vf omega_foot = vf_set1(0.0f);
    for (int i = 0; i < n; ++i) {
        const v3 rel = {vf_sub(vf_set1(P->v[i][0]), x.x), vf_sub(vf_set1(P->v[i][1]), x.y),
                        vf_sub(vf_set1(P->v[i][2]), x.z)};
        const vf r = vf_sqrt(v3_dot(rel, rel)), ir = vf_div(vf_set1(1.0f), r);
        v3_store(GEO(w, i, F_RX), rel);
        vf_store(GEO(w, i, F_R), r);
        vf_store(GEO(w, i, F_IR), ir);
        v3_store(GEO(w, i, F_WX), v3_scale(rel, ir));
    }
    for (int e = 0; e < n; ++e) {
        const int f = e + 1 == n ? 0 : e + 1;
        const v3 edge = v3_set1(P->edge[e]), rel_e = v3_load(GEO(w, e, F_RX)), rel_f = v3_load(GEO(w, f, F_RX));
        const v3 we = v3_load(GEO(w, e, F_WX));
        const vf r_e = vf_load(GEO(w, e, F_R)), r_f = vf_load(GEO(w, f, F_R));
        const vf ir_e = vf_load(GEO(w, e, F_IR)), ir_f = vf_load(GEO(w, f, F_IR));
        /* = rel_e x rel_f = rel_f x edge, from the nearer vertex (shl__poly_geom_init's cv) */
        const v3 c = v3_cross(v3_sel(vf_lt(r_f, r_e), rel_f, rel_e), edge);
        const vf clen2 = v3_dot(c, c), clen = vf_sqrt(clen2), dot = v3_dot(rel_e, rel_f);
        const vf rr = vf_mul(r_e, r_f), irr = vf_mul(ir_e, ir_f), rsum = vf_add(r_e, r_f);
        /* |c|^2 + dot^2 = (r_e r_f)^2: sin, cos, and 1 - cos = sin^2 / (1 + cos) when cos > 0 */
        const vf sn = vf_mul(clen, irr), cs = vf_mul(dot, irr);
        const vm pos = vf_gt(cs, vf_set1(0.0f));
        const vf omc = vf_sel(pos, vf_div(vf_mul(sn, sn), vf_add(vf_set1(1.0f), vf_max(cs, vf_set1(0.0f)))),
                              vf_sub(vf_set1(1.0f), cs));
        vf_store(GEO(w, e, F_GAM), vf_atan2(clen, dot)); /* Eq. 20 */
        vf_store(GEO(w, e, F_SIN), sn);
        vf_store(GEO(w, e, F_COS), cs);
        vf_store(GEO(w, e, F_OMC), omc);
        /* triangle (foot of x on the plane, v_e, v_f): triple = sign(h) |t| nu.c,
         * den = |t| (r_e r_f + dot + |t| (r_e + r_f)), r_e r_f + dot = |c|^2 / (r_e r_f - dot)
         * when dot < 0 (both arguments times r_e r_f - dot there) */
        const vf k = vf_sel(pos, vf_set1(1.0f), vf_sub(rr, dot));
        const vf den = vf_fma(vf_mul(t, rsum), k, vf_sel(pos, vf_add(rr, dot), clen2));
        omega_foot = vf_add(omega_foot, vf_atan2(vf_mulsign(vf_mul(v3_dot(nu, c), k), h), den));
        /* an underflowed arc (c = 0) contributes nothing: mu = lambda = g = 0 */
        const vf iclen = vf_sel(vf_gt(clen, vf_set1(0.0f)), vf_div(vf_set1(1.0f), vf_max(clen, vf_set1(FLT_MIN))),
                                vf_set1(0.0f));
        const v3 mu = v3_scale(c, iclen), lam = v3_cross(mu, we);
        v3_store(GEO(w, e, F_MX), mu);
        v3_store(GEO(w, e, F_LX), lam);
        /* omega_f - omega_e = edge/r_f + rel_e (r_e - r_f)/(r_e r_f), r_e - r_f = -edge.(rel_e + rel_f)/(r_e + r_f) */
        const vf dr = vf_div(v3_dot(edge, v3_add(rel_e, rel_f)), rsum); /* = r_f - r_e */
        const vf kd = vf_mul(dr, irr);
        v3_store(GEO(w, e, F_DX), (v3){vf_fnma(rel_e.x, kd, vf_mul(edge.x, ir_f)), vf_fnma(rel_e.y, kd, vf_mul(edge.y, ir_f)),
                                       vf_fnma(rel_e.z, kd, vf_mul(edge.z, ir_f))});
        if (grad) {
            /* g_e = q/|q|^2 = (edge x c)/|c|^2, f'(gamma) = omega_f . (g x mu),
             * I_0 = g . (omega_e sin + lambda_e (1 - cos)) */
            const v3 g = v3_scale(v3_scale(v3_cross(edge, c), iclen), iclen);
            v3_store(GEO(w, e, F_GX), g);
            vf_store(GEO(w, e, F_FP1), v3_dot(v3_load(GEO(w, f, F_WX)), v3_cross(g, mu)));
            vf_store(GEO(w, e, F_I0), vf_fma(v3_dot(g, we), sn, vf_mul(v3_dot(g, lam), omc)));
        }
    }
    /* S_0 (Van Oosterom-Strackee): fan of signed triangles (v_0, v_i, v_i+1),
     * 2 atan2(triple, den) each, triple = h fan_i.  It keeps full relative
     * accuracy for small polygons, but den carries an absolute error of
     * ~eps r0 ri rj, fatal near the plane when den ~ 0 (x near a fan diagonal);
     * lanes where some den_i < r0 ri rj (some side > 90 degrees: x close to the
     * polygon) take the fan from the foot of x instead, whose terms have no
     * such cancellation and whose limit on the plane is exact. */
    const v3 rel0 = v3_load(GEO(w, 0, F_RX));
    const vf r0 = vf_load(GEO(w, 0, F_R));
    vf omega = vf_set1(0.0f), margin = vf_set1(0.0f);
    for (int i = 1; i + 1 < n; ++i) {
        const v3 ri = v3_load(GEO(w, i, F_RX)), rj = v3_load(GEO(w, i + 1, F_RX));
        const vf di = vf_load(GEO(w, i, F_R)), dj = vf_load(GEO(w, i + 1, F_R));
        const vf prod = vf_mul(vf_mul(r0, di), dj);
        vf den = vf_fma(v3_dot(rel0, ri), dj, prod);
        den = vf_fma(v3_dot(rel0, rj), di, den);
        den = vf_fma(v3_dot(ri, rj), r0, den);
        margin = vf_min(margin, vf_sub(den, prod));
        omega = vf_add(omega, vf_atan2(vf_mul(h, vf_set1(P->fan[i])), den));
    }
    omega = vf_sel(vf_lt(margin, vf_set1(0.0f)), omega_foot, omega);
    return vf_add(omega, omega);
}

/* State of one lobe on one edge through the band recurrence (polygon_zh.h). */
typedef struct {
    vf ae, af, da, b1c, s, c2, ce;          /* per edge: Eq. 20, 27, 31 terms */
    vf p1, p2, dp1, dp2, bm1, bm2, dm1, dm2; /* P_l-1(a_e), P_l-2, dP, B, D at l-1, l-2 */
    vf v, i1, j1, j2;                        /* gradient: g . lobe, I_l-1, J_l-1, J_l-2 */
} edge_state;

/* sum_e c_e B_l,e of lobe j; I_l,e of lobe j on edge e (summed with mu_e once all edges are done). */
#define ACC(w, L, j, l) ((w)->acc + ((size_t)(j) * ((L) + 1) + (l)) * VL)
#define IB(w, L, j, e, l) ((w)->ib + (((size_t)(j) * SHL_MAX_VERTS + (e)) * ((L) + 1) + (l)) * VL)

/* *acc += a b, or *acc = a b on the first edge (no zeroing pass). */
static ALWAYS_INLINE void acc_add(float *acc, vf a, vf b, const int first)
{
    vf_store(acc, first ? vf_mul(a, b) : vf_fma(a, b, vf_load(acc)));
}

/* Set-up of one lobe on edge e, and its bands 0 and 1. */
static ALWAYS_INLINE void edge_init(edge_state *st, const work_t *w, int L, int j, int e, vf ae, vf af, vf be,
                                    vf ce, vf da, vf fp1, vf i0, const int first, const int grad)
{
    const vf gam = vf_load(GEO(w, e, F_GAM)), sn = vf_load(GEO(w, e, F_SIN));
    st->ae = ae;
    st->af = af;
    st->da = da;
    st->ce = ce;
    /* Eq. 31 terms: s = a sin - b cos, B_1 = a sin + b (1 - cos) (Eq. 27), c^2 = 1 - a^2 - b^2 */
    st->s = vf_fms(ae, sn, vf_mul(be, vf_load(GEO(w, e, F_COS))));
    st->b1c = vf_fma(ae, sn, vf_mul(be, vf_load(GEO(w, e, F_OMC))));
    st->c2 = vf_mul(ce, ce);
    st->p1 = ae; /* P_1(a_e), P_0 */
    st->p2 = vf_set1(1.0f);
    st->dp1 = da; /* dP_l = P_l(a_f) - P_l(a_e) */
    st->dp2 = vf_set1(0.0f);
    st->bm1 = st->b1c; /* B_1, B_0, D_1, D_0 (Eq. 26-28) */
    st->bm2 = st->dm1 = gam;
    st->dm2 = vf_set1(0.0f);
    acc_add(ACC(w, L, j, 0), ce, gam, first);
    acc_add(ACC(w, L, j, 1), ce, st->b1c, first);
    if (grad) {
        /* I_1 = (V D_1 - [f' P_1]_0^T) / 2, [f' P_l]_0^T = f'(T) dP_l - I_0 P_l(a_e) */
        st->i1 = vf_mul(vf_sub(vf_mul(st->v, gam), vf_fnma(i0, ae, vf_mul(fp1, da))), vf_set1(0.5f));
        st->j1 = i0; /* J_1; J_0 = 0 */
        st->j2 = vf_set1(0.0f);
        vf_store(IB(w, L, j, e, 0), i0);
        vf_store(IB(w, L, j, e, 1), st->i1);
    }
}

/* Band l >= 2 of one lobe on one edge; B_l only with band_b (S_lmax reads B_lmax-1 at most,
 * so band lmax, run for the gradient's I_lmax alone, skips it). */
static ALWAYS_INLINE void edge_step(edge_state *st, const work_t *w, int L, int j, int e, int l, vf fp1, vf i0,
                                    const int first, const int grad, const int band_b)
{
    const vf dl = vf_fma(KV(w, l, K_2LM1), st->bm1, st->dm2); /* Eq. 32 */
    /* Legendre (Eq. 11) at a_e, and its difference along the arc:
     * a_f P(a_f) - a_e P(a_e) = a_f dP + da P(a_e) */
    const vf pl = vf_fms(KV(w, l, K_A), vf_mul(st->ae, st->p1), vf_mul(KV(w, l, K_B), st->p2));
    const vf dpl = vf_fms(KV(w, l, K_A), vf_fma(st->af, st->dp1, vf_mul(st->da, st->p1)), vf_mul(KV(w, l, K_B), st->dp2));
    if (band_b) {
        /* Eq. 30-31 merged: B_l = alpha (B_1 P_l-1 + s dP_l-1 - c^2 D_l-1) + beta B_l-2,
         * alpha = (2l-1)/l^2, beta = ((l-1)/l)^2 */
        const vf xx = vf_fnma(st->c2, st->dm1, vf_fma(st->s, st->dp1, vf_mul(st->b1c, st->p1)));
        const vf bl = vf_fma(KV(w, l, K_ALPHA), xx, vf_mul(KV(w, l, K_BETA), st->bm2));
        acc_add(ACC(w, L, j, l), st->ce, bl, first); /* Eq. 14 */
        st->bm2 = st->bm1;
        st->bm1 = bl;
    }
    if (grad) {
        /* I_l = (V D_l - J_l-1 - [f' P_l]) / (l+1), J_l = (2l-1) I_l-1 + J_l-2 */
        const vf il = vf_mul(vf_sub(vf_fms(st->v, dl, st->j1), vf_fnma(i0, pl, vf_mul(fp1, dpl))), KV(w, l, K_INV1));
        const vf jl = vf_fma(KV(w, l, K_2LM1), st->i1, st->j2);
        st->j2 = st->j1;
        st->j1 = jl;
        st->i1 = il;
        vf_store(IB(w, L, j, e, l), il);
    }
    st->p2 = st->p1;
    st->p1 = pl;
    st->dp2 = st->dp1;
    st->dp1 = dpl;
    st->dm2 = st->dm1;
    st->dm1 = dl;
}

/* dir . a and its mirror image in y, (dir_x, -dir_y, dir_z) . a */
static inline void dot_pair(const float d[3], v3 a, vf *plus, vf *minus)
{
    const vf t = vf_fma(vf_set1(d[0]), a.x, vf_mul(vf_set1(d[2]), a.z));
    *plus = vf_fma(vf_set1(d[1]), a.y, t);
    *minus = vf_fnma(vf_set1(d[1]), a.y, t);
}

/* Edge e's contribution to the sums of lobe pair dir (two = 1) or of lobe dir alone. */
static ALWAYS_INLINE void lobes_edge(const work_t *w, int n, int lmax, int e, const float dir[3], const int two,
                                     const int first, const int grad)
{
    const int f = e + 1 == n ? 0 : e + 1, L = lmax + 1, nl = two ? 2 : 1;
    vf be[2], ce[2], da[2], v[2] = {vf_set1(0.0f), vf_set1(0.0f)}, fp1 = v[0], i0 = v[0];
    dot_pair(dir, v3_load(GEO(w, e, F_LX)), &be[0], &be[1]);
    dot_pair(dir, v3_load(GEO(w, e, F_MX)), &ce[0], &ce[1]);
    dot_pair(dir, v3_load(GEO(w, e, F_DX)), &da[0], &da[1]);
    if (grad) {
        dot_pair(dir, v3_load(GEO(w, e, F_GX)), &v[0], &v[1]);
        fp1 = vf_load(GEO(w, e, F_FP1));
        i0 = vf_load(GEO(w, e, F_I0));
    }
    for (int j = 0; j < nl; ++j) { /* one lobe at a time: the state fits the registers */
        edge_state st;
        st.v = v[j];
        edge_init(&st, w, L, j, e, vf_load(w->avtx + (2 * e + j) * VL), vf_load(w->avtx + (2 * f + j) * VL), be[j],
                  ce[j], da[j], fp1, i0, first, grad);
        for (int l = 2; l < lmax; ++l) edge_step(&st, w, L, j, e, l, fp1, i0, first, grad, 1);
        if (grad && lmax >= 2) edge_step(&st, w, L, j, e, lmax, fp1, i0, first, grad, 0); /* I_lmax: D, P, dP at lmax */
    }
}

/* Wu 2020 Eq. 11: sum_e mu_e[a] I_l,e for lobe j, axis a. */
static inline vf grad_sum(const work_t *w, int n, int L, int j, int a, int l)
{
    vf sum = vf_mul(vf_load(GEO(w, 0, F_MX + a)), vf_load(IB(w, L, j, 0, l)));
    for (int e = 1; e < n; ++e) sum = vf_fma(vf_load(GEO(w, e, F_MX + a)), vf_load(IB(w, L, j, e, l)), sum);
    return sum;
}

/* Light sets (src/lights_batch.c): the ZH -> SH reconstruction is linear, so the
 * lights' paired sums u and differences v (times each light's rgb) are accumulated
 * per group of VL points and colour, and reconstructed once per block (as
 * shl__lights_eval does in double).  Compact layout per group, colour and quantity
 * q: u_k(l) at l(l+1)/2 + k (0 <= k <= l), v_k(l) at L(L+1)/2 + l(l-1)/2 + k - 1
 * (1 <= k <= l): nc vectors. */
static ALWAYS_INLINE size_t acc_u(int l, int k) { return (size_t)(l * (l + 1) / 2 + k); }
static ALWAYS_INLINE size_t acc_v(int L, int l, int k) { return (size_t)(L * (L + 1) / 2 + l * (l - 1) / 2 + k - 1); }

/* ZH integrals of lobe pair k (two = 1: lobes 2k-1 = dir and 2k = its mirror
 * image) or of lobe 0 (two = 0), bands 0..lmax: S_l (Eq. 29) and, with grad,
 * sum_e mu_e I_l,e, scaled by sign * K_l (fs; fsg for gradients) and stored as
 * the pair's sum u and difference v (zh_tables.h; lobe 0: u only): in w->u, w->v
 * for the reconstruction, or (to_acc) in w->soa in the accumulators' compact
 * layout, so that acc_light streams them. */
static ALWAYS_INLINE void lobes_zh(const shl__batch_poly *P, work_t *w, int lmax, int k, const float dir[3],
                                   vf omega, vf fs, vf fsg, const float *s_b, const float *s_s, const float *norm,
                                   const int two, const int grad, const int to_acc)
{
    const int n = P->n, L = lmax + 1, nq = grad ? 4 : 1, nl = two ? 2 : 1;
    for (int i = 0; i < n; ++i) {
        vf a0, a1;
        dot_pair(dir, v3_load(GEO(w, i, F_WX)), &a0, &a1);
        vf_store(w->avtx + 2 * i * VL, a0);
        vf_store(w->avtx + (2 * i + 1) * VL, a1);
    }
    lobes_edge(w, n, lmax, 0, dir, two, 1, grad); /* the first edge initializes the sums */
    for (int e = 1; e < n; ++e) lobes_edge(w, n, lmax, e, dir, two, 0, grad);
    /* Eq. 25, 29: S_0 = omega, S_1 = sum c B_0 / 2, S_l = s_b sum c B_l-1 + s_s S_l-2 */
    vf S[2][SHL_LMAX_MAX + 1];
    for (int j = 0; j < nl; ++j) {
        S[j][0] = omega;
        if (lmax >= 1) S[j][1] = vf_mul(vf_set1(0.5f), vf_load(ACC(w, L, j, 0)));
        for (int l = 2; l <= lmax; ++l)
            S[j][l] = vf_fma(vf_set1(s_b[l]), vf_load(ACC(w, L, j, l - 1)), vf_mul(vf_set1(s_s[l]), S[j][l - 2]));
    }
    for (int q = 0; q < nq; ++q)
        for (int l = k; l <= lmax; ++l) { /* band l uses pairs k <= l */
            const vf scale = vf_mul(q ? fsg : fs, vf_set1(norm[l]));
            const vf z0 = vf_mul(scale, q ? grad_sum(w, n, L, 0, q - 1, l) : S[0][l]);
            const size_t qc = (size_t)q * L * L;
            float *u = to_acc ? w->soa + (qc + acc_u(l, k)) * VL : w->u + (((size_t)q * L + k) * L + l) * VL;
            if (two) {
                const vf z1 = vf_mul(scale, q ? grad_sum(w, n, L, 1, q - 1, l) : S[1][l]);
                vf_store(u, vf_add(z0, z1));
                vf_store(to_acc ? w->soa + (qc + acc_v(L, l, k)) * VL : w->v + (((size_t)q * L + k) * L + l) * VL,
                         vf_sub(z0, z1));
            } else {
                vf_store(u, z0);
            }
        }
}

/* out_q[i * ostep] = sum_k wt[i * ncol + k] x_q[k * xstep] for rows i < nrow and the
 * nq quantities (x_q = x + q xq, out_q = out + q oq) that share the matrix.  An FMA
 * has a latency of about 4 cycles and 2 issue per cycle: 8 independent chains keep
 * both FMA units busy, so the rows go two at a time for the 4 quantities of the
 * gradient batch (each x_q load serves both rows, each weight all 4 quantities);
 * one quantity goes four rows at a time.  Every sum runs in k order from 0, so
 * coefficients are the same bits with and without gradients. */
static ALWAYS_INLINE void matvec(const float *wt, int nrow, int ncol, const float *x, ptrdiff_t xstep, ptrdiff_t xq,
                                 float *out, ptrdiff_t ostep, ptrdiff_t oq, const int nq)
{
    const vf zero = vf_set1(0.0f);
    int i = 0;
    if (nq == 4) {
        for (; i + 2 <= nrow; i += 2) {
            const float *w0 = wt + (size_t)i * ncol, *w1 = w0 + ncol;
            vf a0 = zero, a1 = zero, a2 = zero, a3 = zero, b0 = zero, b1 = zero, b2 = zero, b3 = zero;
            for (int k = 0; k < ncol; ++k) {
                const float *xk = x + k * xstep;
                const vf x0 = vf_load(xk), x1 = vf_load(xk + xq), x2 = vf_load(xk + 2 * xq), x3 = vf_load(xk + 3 * xq);
                const vf u = vf_set1(w0[k]), v = vf_set1(w1[k]);
                a0 = vf_fma(u, x0, a0);
                a1 = vf_fma(u, x1, a1);
                a2 = vf_fma(u, x2, a2);
                a3 = vf_fma(u, x3, a3);
                b0 = vf_fma(v, x0, b0);
                b1 = vf_fma(v, x1, b1);
                b2 = vf_fma(v, x2, b2);
                b3 = vf_fma(v, x3, b3);
            }
            float *o = out + i * ostep;
            vf_store(o, a0);
            vf_store(o + oq, a1);
            vf_store(o + 2 * oq, a2);
            vf_store(o + 3 * oq, a3);
            vf_store(o + ostep, b0);
            vf_store(o + ostep + oq, b1);
            vf_store(o + ostep + 2 * oq, b2);
            vf_store(o + ostep + 3 * oq, b3);
        }
        for (; i < nrow; ++i) {
            const float *w0 = wt + (size_t)i * ncol;
            vf a0 = zero, a1 = zero, a2 = zero, a3 = zero;
            for (int k = 0; k < ncol; ++k) {
                const float *xk = x + k * xstep;
                const vf u = vf_set1(w0[k]);
                a0 = vf_fma(u, vf_load(xk), a0);
                a1 = vf_fma(u, vf_load(xk + xq), a1);
                a2 = vf_fma(u, vf_load(xk + 2 * xq), a2);
                a3 = vf_fma(u, vf_load(xk + 3 * xq), a3);
            }
            float *o = out + i * ostep;
            vf_store(o, a0);
            vf_store(o + oq, a1);
            vf_store(o + 2 * oq, a2);
            vf_store(o + 3 * oq, a3);
        }
        return;
    }
    for (; i + 4 <= nrow; i += 4) {
        const float *w0 = wt + (size_t)i * ncol;
        vf a0 = zero, a1 = zero, a2 = zero, a3 = zero;
        for (int k = 0; k < ncol; ++k) {
            const vf xk = vf_load(x + k * xstep);
            a0 = vf_fma(vf_set1(w0[k]), xk, a0);
            a1 = vf_fma(vf_set1(w0[ncol + k]), xk, a1);
            a2 = vf_fma(vf_set1(w0[2 * ncol + k]), xk, a2);
            a3 = vf_fma(vf_set1(w0[3 * ncol + k]), xk, a3);
        }
        vf_store(out + i * ostep, a0);
        vf_store(out + (i + 1) * ostep, a1);
        vf_store(out + (i + 2) * ostep, a2);
        vf_store(out + (i + 3) * ostep, a3);
    }
    for (; i < nrow; ++i) {
        vf a0 = zero;
        for (int k = 0; k < ncol; ++k) a0 = vf_fma(vf_set1(wt[(size_t)i * ncol + k]), vf_load(x + k * xstep), a0);
        vf_store(out + i * ostep, a0);
    }
}

/* Rows i..i+3 of both matrices of band l, one quantity: the even ones (l + 1 columns,
 * from u, to out + r VL) and the odd ones (l columns, from v, to out - (r + 1) VL),
 * i + 4 <= l: 8 independent chains, each summed in k order from 0 as in matvec. */
static ALWAYS_INLINE void matvec_pair4(const float *we, const float *wo, int l, int i, const float *u, const float *v,
                                       ptrdiff_t xstep, float *out)
{
    const int ne = l + 1;
    const float *e0 = we + (size_t)i * ne, *o0 = wo + (size_t)i * l;
    vf a0 = vf_set1(0.0f), a1 = a0, a2 = a0, a3 = a0, b0 = a0, b1 = a0, b2 = a0, b3 = a0;
    for (int k = 0; k < l; ++k) {
        const vf xu = vf_load(u + k * xstep), xv = vf_load(v + k * xstep);
        a0 = vf_fma(vf_set1(e0[k]), xu, a0);
        a1 = vf_fma(vf_set1(e0[ne + k]), xu, a1);
        a2 = vf_fma(vf_set1(e0[2 * ne + k]), xu, a2);
        a3 = vf_fma(vf_set1(e0[3 * ne + k]), xu, a3);
        b0 = vf_fma(vf_set1(o0[k]), xv, b0);
        b1 = vf_fma(vf_set1(o0[l + k]), xv, b1);
        b2 = vf_fma(vf_set1(o0[2 * l + k]), xv, b2);
        b3 = vf_fma(vf_set1(o0[3 * l + k]), xv, b3);
    }
    const vf xu = vf_load(u + l * xstep);
    float *oe = out + (ptrdiff_t)i * VL, *oo = out - (ptrdiff_t)(i + 1) * VL;
    vf_store(oe, vf_fma(vf_set1(e0[l]), xu, a0));
    vf_store(oe + VL, vf_fma(vf_set1(e0[ne + l]), xu, a1));
    vf_store(oe + 2 * VL, vf_fma(vf_set1(e0[2 * ne + l]), xu, a2));
    vf_store(oe + 3 * VL, vf_fma(vf_set1(e0[3 * ne + l]), xu, a3));
    vf_store(oo, b0);
    vf_store(oo - VL, b1);
    vf_store(oo - 2 * VL, b2);
    vf_store(oo - 3 * VL, b3);
}

/* The sparse ZH -> SH reconstruction (Wang 2018 Eq. 33, zh_tables.h) of every
 * band and quantity, from the paired sums u_k and differences v_k (m = -1 .. -l
 * from v_1 .. v_l).  One quantity: rows of the even and odd matrices four and four
 * together (matvec_pair4), the rest through matvec. */
static ALWAYS_INLINE void reconstruct(const work_t *w, int lmax, const int nq)
{
    const int L = lmax + 1, nc = L * L;
    const ptrdiff_t xs = (ptrdiff_t)L * VL, xq = (ptrdiff_t)L * L * VL, oq = (ptrdiff_t)nc * VL;
    for (int l = 0; l <= lmax; ++l) {
        const float *u = w->u + (size_t)l * VL, *v = w->v + (size_t)(L + l) * VL;
        const float *we = shl__zh_even_w_f + SHL__ZH_EVEN_OFS(l), *wo = shl__zh_odd_w_f + SHL__ZH_ODD_OFS(l);
        float *out = w->soa + (size_t)l * (l + 1) * VL;
        int i = 0;
        if (nq == 1)
            for (; i + 4 <= l; i += 4) matvec_pair4(we, wo, l, i, u, v, xs, out);
        matvec(we + (size_t)i * (l + 1), l + 1 - i, l + 1, u, xs, xq, out + (ptrdiff_t)i * VL, VL, oq, nq);
        if (l > i) matvec(wo + (size_t)i * l, l - i, l, v, xs, xq, out - (ptrdiff_t)(i + 1) * VL, -VL, oq, nq);
    }
}

/* Rows soa[k] (one vector per row, lane j = point j) to out[j * stride + k], j < nvalid. */
static void store_rows(const float *soa, int nrows, float *out, size_t stride, int nvalid)
{
    int k = 0;
    for (; k + VL <= nrows; k += VL) vf_store_transposed(soa + (size_t)k * VL, out + k, stride, nvalid);
    for (; k < nrows; ++k)
        for (int j = 0; j < nvalid; ++j) out[j * stride + k] = soa[(size_t)k * VL + j];
}

size_t ISA(shl__poly_acc_floats)(int lmax, int with_grad, int npts)
{
    const size_t nc = SHL_NCOEFFS(lmax), nq = with_grad ? 4 : 1, groups = ((size_t)npts + VL - 1) / VL;
    return (3 * groups + 1) * nq * nc * VL; /* + one group's rows, point by point (acc_finish) */
}

/* acc[c] += s[c] (u, v) of the light just evaluated (w->soa, compact layout), one group. */
static ALWAYS_INLINE void acc_light(const work_t *w, int lmax, const vf s[3], float *acc, const int nq)
{
    const size_t rows = (size_t)nq * (lmax + 1) * (lmax + 1);
    for (int c = 0; c < 3; ++c, acc += rows * VL)
        for (size_t r = 0; r < rows; ++r)
            vf_store(acc + r * VL, vf_fma(s[c], vf_load(w->soa + r * VL), vf_load(acc + r * VL)));
}

static ALWAYS_INLINE int poly_batch_impl(const shl__batch_poly *P, int lmax, int npts, const float *pts,
                                         const unsigned char *keep, const float *rgb, float *coeffs, float *grad,
                                         void *work, int *redo, const int with_grad, const int to_acc)
{
    int nredo = 0;
    const int L = lmax + 1, nc = L * L, nq = with_grad ? 4 : 1;
    work_t w;
    work_floats(lmax, nq, &w, (float *)(((uintptr_t)work + 63) & ~(uintptr_t)63));
    float s_b[SHL_LMAX_MAX + 1], s_s[SHL_LMAX_MAX + 1], norm[SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax + 1; ++l) {
        const double ld = l, lz = l + (l == 0);
        const float kv[NK] = {(float)((2 * ld - 1) / lz), (float)((ld - 1) / lz), (float)((2 * ld - 1) / (lz * lz)),
                              (float)((ld - 1) * (ld - 1) / (lz * lz)), (float)(2 * ld - 1), (float)(1.0 / (ld + 1))};
        for (int k = 0; k < NK; ++k) vf_store(w.kv + ((size_t)l * NK + k) * VL, vf_set1(kv[k]));
        if (l > lmax) break;
        norm[l] = (float)sqrt((2 * ld + 1) / (4 * M_PI));  /* K_l */
        s_b[l] = (float)((2 * ld - 1) / (ld * (ld + 1) + (l == 0))); /* Eq. 29 weights */
        s_s[l] = (float)((ld - 2) * (ld - 1) / (ld * (ld + 1) + (l == 0)));
    }
    /* inv_scale = gs0 gs1, both floats (up to 2^149 for a denormal extent); gs1 >= 1 is applied
     * after the reconstruction, so a product overflows only if the final gradient does */
    const float gs0 = (float)(P->inv_scale < 0x1p126 ? P->inv_scale : 0x1p126);
    const float gs1 = (float)(P->inv_scale / gs0);
    vf s[3]; /* to_acc: the light's rgb; gradients times gs1 (1 for the lights' polygons) */
    for (int c = 0; to_acc && c < 3; ++c) s[c] = vf_set1(rgb[c]);
    for (int p0 = 0; p0 < npts; p0 += VL) {
        const int nvalid = npts - p0 < VL ? npts - p0 : VL;
        if (keep) {
            int any = 0;
            for (int j = 0; j < nvalid; ++j) any |= keep[p0 + j];
            if (!any) continue;
        }
        nredo += lanes_setup(P, pts + 3 * (size_t)p0, nvalid, keep ? keep + p0 : NULL, to_acc, &w, p0, redo + nredo);
        const vf omega = geometry(P, &w, with_grad);
        /* result = sign(S_0) * (input-order result); masked lanes get 0 */
        const vf fs = vf_mulsign(vf_load(w.lane + 4 * VL), omega);
        const vf fsg = vf_mul(fs, vf_set1(gs0)); /* d/dx = inv_scale d/dx_scaled = gs0 gs1 d/dx_scaled */
        lobes_zh(P, &w, lmax, 0, shl__zh_dir_f[0], omega, fs, fsg, s_b, s_s, norm, 0, with_grad, to_acc);
        for (int k = 1; k <= lmax; ++k) /* lobe pairs (2k-1, 2k), mirror images in y */
            lobes_zh(P, &w, lmax, k, shl__zh_dir_f[2 * k - 1], omega, fs, fsg, s_b, s_s, norm, 1, with_grad, to_acc);
        if (to_acc) {
            float *a = coeffs + (size_t)p0 / VL * 3 * nq * nc * VL;
            for (size_t r = nc; gs1 != 1.0f && r < (size_t)nq * nc; ++r)
                vf_store(w.soa + r * VL, vf_mul(vf_load(w.soa + r * VL), vf_set1(gs1)));
            /* lanes not accumulated (masked, or redone by the caller) add 0 x (their zeros), not
             * rgb x 0: an rgb beyond float range is inf, and inf x 0 = NaN made a point's result
             * depend on its batch (fuzz_lights-masked-lane-inf-rgb-nan) */
            const vm used = vf_gt(vf_load(w.lane + 4 * VL), vf_set1(0.0f));
            const vf s_used[3] = {vf_sel(used, s[0], vf_set1(0.0f)), vf_sel(used, s[1], vf_set1(0.0f)),
                                  vf_sel(used, s[2], vf_set1(0.0f))};
            acc_light(&w, lmax, s_used, a, nq);
            continue;
        }
        reconstruct(&w, lmax, with_grad ? 4 : 1);
        for (size_t r = nc; gs1 != 1.0f && r < (size_t)nq * nc; ++r)
            vf_store(w.soa + r * VL, vf_mul(vf_load(w.soa + r * VL), vf_set1(gs1)));
        store_rows(w.soa, nc, coeffs + (size_t)p0 * nc, (size_t)nc, nvalid);
        if (with_grad) store_rows(w.soa + (size_t)nc * VL, 3 * nc, grad + (size_t)p0 * 3 * nc, 3 * (size_t)nc, nvalid);
    }
    return nredo;
}

int ISA(shl__poly_batch)(const shl__batch_poly *P, int lmax, int npts, const float *pts, float *coeffs, float *grad,
                         void *work, int *redo)
{
    if (grad) return poly_batch_impl(P, lmax, npts, pts, NULL, NULL, coeffs, grad, work, redo, 1, 0);
    return poly_batch_impl(P, lmax, npts, pts, NULL, NULL, coeffs, NULL, work, redo, 0, 0);
}

int ISA(shl__poly_batch_acc)(const shl__batch_poly *P, int lmax, int npts, const float *pts, const unsigned char *keep,
                             const float rgb[3], int with_grad, float *acc, void *work, int *redo)
{
    if (with_grad) return poly_batch_impl(P, lmax, npts, pts, keep, rgb, acc, NULL, work, redo, 1, 1);
    return poly_batch_impl(P, lmax, npts, pts, keep, rgb, acc, NULL, work, redo, 0, 1);
}

/* y[k] += x[k], k < n (= y + 1 x, as shl__accumulate). */
static void add_row(const float *x, float *y, int n)
{
    int k = 0;
    for (; k + VL <= n; k += VL) vf_store(y + k, vf_add(vf_load(y + k), vf_load(x + k)));
    for (; k < n; ++k) y[k] += x[k];
}

/* The accumulated groups of npts points reconstructed (Wang 2018 Eq. 33) into
 * rgb[j rgb_stride + c nc + k] and grad[j grad_stride + (3c + a) nc + k]: added to
 * them (add), else stored. */
void ISA(shl__poly_acc_finish)(int lmax, int npts, const float *acc, int add, float *rgb, size_t rgb_stride,
                               float *grad, size_t grad_stride, void *work)
{
    const int L = lmax + 1, nc = L * L, nq = grad ? 4 : 1;
    work_t w;
    work_floats(lmax, nq, &w, (float *)(((uintptr_t)work + 63) & ~(uintptr_t)63));
    float *rows = (float *)acc + ISA(shl__poly_acc_floats)(lmax, grad != NULL, npts) - (size_t)nq * nc * VL;
    for (int p0 = 0; p0 < npts; p0 += VL) {
        const int nvalid = npts - p0 < VL ? npts - p0 : VL;
        float *y = rgb + (size_t)p0 * rgb_stride, *g = grad ? grad + (size_t)p0 * grad_stride : NULL;
        for (int c = 0; c < 3; ++c) {
            const float *a = acc + ((size_t)p0 / VL * 3 + c) * nq * nc * VL;
            for (int q = 0; q < nq; ++q, a += (size_t)nc * VL)
                for (int l = 0; l <= lmax; ++l)
                    for (int k = 0; k <= l; ++k) {
                        vf_store(w.u + (((size_t)q * L + k) * L + l) * VL, vf_load(a + acc_u(l, k) * VL));
                        if (k) vf_store(w.v + (((size_t)q * L + k) * L + l) * VL, vf_load(a + acc_v(L, l, k) * VL));
                    }
            reconstruct(&w, lmax, nq);
            if (!add) { /* stored as 0 + x, as the add path does, so that a -0 is +0 either way: the
                         * caller adds when some other point of the block needed it */
                for (size_t r = 0; r < (size_t)nq * nc; ++r)
                    vf_store(w.soa + r * VL, vf_add(vf_set1(0.0f), vf_load(w.soa + r * VL)));
                store_rows(w.soa, nc, y + (size_t)c * nc, rgb_stride, nvalid);
                if (g) store_rows(w.soa + (size_t)nc * VL, 3 * nc, g + (size_t)c * 3 * nc, grad_stride, nvalid);
                continue;
            }
            store_rows(w.soa, nq * nc, rows, (size_t)nq * nc, nvalid);
            for (int j = 0; j < nvalid; ++j) {
                add_row(rows + (size_t)j * nq * nc, y + (size_t)j * rgb_stride + (size_t)c * nc, nc);
                if (g) add_row(rows + (size_t)j * nq * nc + nc, g + (size_t)j * grad_stride + (size_t)c * 3 * nc, 3 * nc);
            }
        }
    }
}
