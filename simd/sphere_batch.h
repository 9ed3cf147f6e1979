/* Batched SH coefficients (and gradients) of one spherical light (Mezieres et
 * al. 2022, HVL Sec. 4.2) at many shading points, vectorized ACROSS POINTS:
 * each lane is one point.  Per lane the sphere is set up in double (axis u,
 * 1 - cos a, sin^2 a, cos a, the gradient factors), as shl_sphere_f does;
 * then, in float lanes, the
 * cap weights w_l = sqrt(4 pi/(2l+1)) zh_l (HVL Eq. 13-14, the
 * cancellation-free form of shl__cap_weights in src/sphere_impl.h), Y_lm(u)
 * and its tangential gradient by the N_l^m recurrence of shl__sh_eval_grad
 * (same file, which derives it), and L_lm = w_l Y_lm(u) (Eq. 15) with
 * d L_lm/dx = -k_alpha w_l' Y_lm u - (w_l / d) (I - u u^T) grad Y_lm.
 * Written once with the verbs of <isa>/helper.h, compiled once per ISA of
 * simd/isa_list.h (Makefile); with the scalar helper it is plain C. */
#include "kernel_api.h"
#include <math.h>
#include <stdint.h>

#define VL SHL_VLEN
#define ISA(name) SHL_ISA_SUFFIX(name)
#define ALWAYS_INLINE __attribute__((always_inline)) inline

/* per-lane geometry, one vector each */
enum { G_UX, G_UY, G_UZ, G_T, G_S2, G_C, G_KALPHA, G_INVD, G_INSIDE, NG };

/* Workspace: lane geometry, per-call constants of the N_l^m recurrence
 * (indexed l * (lmax + 1) + m), and the block's outputs, one vector per row. */
typedef struct {
    float *geo;     /* [NG] vectors */
    float *rec_a;   /* sqrt((4 l^2 - 1) / (l^2 - m^2)), l >= m + 2 */
    float *rec_b;   /* sqrt(((l-1)^2 - m^2) / (4 (l-1)^2 - 1)), l >= m + 2 */
    float *rec_d;   /* -sqrt((l - m)(l + m + 1)): d N_l^m / dz = rec_d N_l^{m+1} */
    float *soa;     /* [nc] coefficients, then [3 nc] gradients, vectors */
} work_t;

static size_t work_floats(int lmax, int with_grad, work_t *w, float *base)
{
    const size_t L = (size_t)lmax + 1, nc = L * L, rows = with_grad ? 4 * nc : nc;
    if (base) {
        w->geo = base;
        w->rec_a = base + NG * VL;
        w->rec_b = w->rec_a + nc;
        w->rec_d = w->rec_b + nc;
        w->soa = w->rec_d + nc + (VL - (3 * nc) % VL) % VL; /* rows stay VL-aligned */
    }
    return NG * VL + 3 * nc + VL + rows * VL;
}

size_t ISA(shl__sphere_work_bytes)(int lmax, int with_grad)
{
    work_t w;
    return sizeof(float) * work_floats(lmax, with_grad, &w, NULL) + 64; /* + alignment */
}

#define GEO(w, f) vf_load((w)->geo + (f) * VL)

/* Lanes of a block: the cap seen from each point, in double, by the formulas of
 * shl__sphere_geom_init (src/sphere.c) without its rescaling, which float
 * inputs do not need (|center - x|^2 stays within 2^-300..2^260).  Lanes past
 * nvalid and inside the sphere take the full sphere of directions: u = z,
 * cos a = -1, sin a = 0 (so w_0 = 4 pi and w_l = 0 above, exactly), no
 * gradient (k_alpha = 1/d = 0). */
static void lanes_setup(const double center[3], double radius, const float *pts, int nvalid, work_t *w)
{
    for (int j = 0; j < VL; ++j) {
        float geo[NG] = {0.0f, 0.0f, 1.0f, 2.0f, 0.0f, -1.0f, 0.0f, 0.0f, 1.0f}; /* inside */
        if (j < nvalid) {
            const double v[3] = {center[0] - pts[3 * j], center[1] - pts[3 * j + 1], center[2] - pts[3 * j + 2]};
            const double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (d > radius) {
                const double inv_d = 1.0 / d, s = radius * inv_d, s2 = s * s;
                const double c = sqrt((d - radius) * (d + radius)) * inv_d; /* cos a, exact difference d - r */
                geo[G_UX] = (float)(v[0] * inv_d);
                geo[G_UY] = (float)(v[1] * inv_d);
                geo[G_UZ] = (float)(v[2] * inv_d);
                geo[G_T] = (float)(s2 / (1.0 + c)); /* 1 - cos a without cancellation */
                geo[G_S2] = (float)s2;
                geo[G_C] = (float)c;
                geo[G_KALPHA] = (float)(s2 / c * inv_d); /* d cos a / dd = sin^2 a / (d cos a) */
                geo[G_INVD] = (float)inv_d;
                geo[G_INSIDE] = 0.0f;
            }
        }
        for (int f = 0; f < NG; ++f) w->geo[f * VL + j] = geo[f];
    }
}

/* Cap weights w_l and dw_l = d w_l / d cos a (shl__cap_weights, HVL Eq. 13-14):
 * w_0 = 2 pi (1 - cos a), w_l = 2 pi sin^2 a P_l'(cos a) / (l (l+1)), dw_l = -2 pi P_l. */
static ALWAYS_INLINE void cap_weights(const work_t *w, int lmax, vf *wl, vf *dwl, const int grad)
{
    const float two_pi = (float)(2.0 * M_PI);
    const vf c = GEO(w, G_C), s2pi = vf_mul(vf_set1(two_pi), GEO(w, G_S2));
    wl[0] = vf_mul(vf_set1(two_pi), GEO(w, G_T));
    if (grad) dwl[0] = vf_set1(-two_pi);
    vf p_prev = vf_set1(1.0f), p = c, dp_prev = vf_set1(0.0f), dp = vf_set1(1.0f);
    for (int l = 1; l <= lmax; ++l) {
        wl[l] = vf_mul(s2pi, vf_mul(dp, vf_set1((float)(1.0 / (l * (l + 1.0))))));
        if (grad) dwl[l] = vf_mul(vf_set1(-two_pi), p);
        /* Legendre: P_l+1 = ((2l+1) c P_l - l P_l-1) / (l+1); P'_l+1 = P'_l-1 + (2l+1) P_l */
        const vf p_next = vf_mul(vf_fms(vf_set1((float)(2 * l + 1)), vf_mul(c, p), vf_mul(vf_set1((float)l), p_prev)),
                                 vf_set1((float)(1.0 / (l + 1.0))));
        const vf dp_next = vf_fma(vf_set1((float)(2 * l + 1)), p, dp_prev);
        p_prev = p;
        p = p_next;
        dp_prev = dp;
        dp = dp_next;
    }
}

/* Outputs of (l, m) from Y = Y_lm(u) and its gradient gy of the polynomial
 * extension (sphere_impl.h): coefficient w_l Y (HVL Eq. 15) and, with grad,
 * -(k_alpha dw_l Y) u - (w_l inv_d) (gy - (gy . u) u). */
static ALWAYS_INLINE void emit(float *soa, int nc, int k, vf y, const vf gy[3], vf wl, vf dwl, const vf u[3],
                               vf neg_kalpha, vf invd, const int grad)
{
    vf_store(soa + (size_t)k * VL, vf_mul(wl, y));
    if (!grad) return;
    const vf radial = vf_fma(gy[0], u[0], vf_fma(gy[1], u[1], vf_mul(gy[2], u[2])));
    const vf neg_along = vf_mul(vf_mul(neg_kalpha, dwl), y), tang = vf_mul(wl, invd);
    for (int a = 0; a < 3; ++a) /* tangential part gy - (gy . u) u */
        vf_store(soa + ((size_t)(a + 1) * nc + k) * VL, vf_fnma(tang, vf_fnma(radial, u[a], gy[a]), vf_mul(neg_along, u[a])));
}

/* Y_lm(u) (and gradients) of bands 0..lmax times the cap weights, into soa. */
static ALWAYS_INLINE void sh_block(const work_t *w, int lmax, const vf *wl, const vf *dwl, const int grad)
{
    const int L = lmax + 1, nc = L * L;
    const vf u[3] = {GEO(w, G_UX), GEO(w, G_UY), GEO(w, G_UZ)};
    const vf zero = vf_set1(0.0f), neg_kalpha = vf_sub(zero, GEO(w, G_KALPHA)), invd = GEO(w, G_INVD);
    const vf r2 = vf_set1((float)M_SQRT2);
    vf cm[SHL_LMAX_MAX + 1], sm[SHL_LMAX_MAX + 1], diag[SHL_LMAX_MAX + 1];
    vf col[SHL_LMAX_MAX + 2], next[SHL_LMAX_MAX + 2]; /* N_l^m and N_l^{m+1} over l */
    cm[0] = vf_set1(1.0f);
    sm[0] = vf_set1(0.0f);
    diag[0] = vf_set1((float)sqrt(0.25 / M_PI));
    for (int m = 1; m <= lmax; ++m) { /* (x + i y)^m; N_m^m */
        cm[m] = vf_fnma(sm[m - 1], u[1], vf_mul(cm[m - 1], u[0]));
        sm[m] = vf_fma(cm[m - 1], u[1], vf_mul(sm[m - 1], u[0]));
        diag[m] = vf_mul(diag[m - 1], vf_set1((float)-sqrt((2.0 * m + 1.0) / (2.0 * m))));
    }
    for (int l = 0; l <= lmax + 1; ++l) next[l] = vf_set1(0.0f);
    for (int m = lmax; m >= 0; --m) {
        col[m] = diag[m];
        if (m < lmax) col[m + 1] = vf_mul(vf_set1((float)sqrt(2.0 * m + 3.0)), vf_mul(u[2], diag[m]));
        for (int l = m + 2; l <= lmax; ++l)
            col[l] = vf_mul(vf_set1(w->rec_a[l * L + m]), vf_fnma(vf_set1(w->rec_b[l * L + m]), col[l - 2], vf_mul(u[2], col[l - 1])));
        for (int l = m; l <= lmax; ++l) {
            const int base = l * (l + 1);
            const vf n = col[l], dw = grad ? dwl[l] : zero; /* dN/dz and dw unused without gradients */
            const vf dn = grad ? vf_mul(vf_set1(w->rec_d[l * L + m]), next[l]) : zero;
            vf gy[3];
            if (m == 0) {
                gy[0] = gy[1] = zero;
                gy[2] = dn;
                emit(w->soa, nc, base, n, gy, wl[l], dw, u, neg_kalpha, invd, grad);
                continue;
            }
            const vf rn = vf_mul(r2, n), nm = vf_mul(rn, vf_set1((float)m)), rdn = vf_mul(r2, dn);
            gy[0] = vf_mul(nm, cm[m - 1]); /* Y_l,m = sqrt2 N C_m */
            gy[1] = vf_fnma(nm, sm[m - 1], zero);
            gy[2] = vf_mul(rdn, cm[m]);
            emit(w->soa, nc, base + m, vf_mul(rn, cm[m]), gy, wl[l], dw, u, neg_kalpha, invd, grad);
            gy[0] = vf_mul(nm, sm[m - 1]); /* Y_l,-m = sqrt2 N S_m */
            gy[1] = vf_mul(nm, cm[m - 1]);
            gy[2] = vf_mul(rdn, sm[m]);
            emit(w->soa, nc, base - m, vf_mul(rn, sm[m]), gy, wl[l], dw, u, neg_kalpha, invd, grad);
        }
        if (grad) {
            for (int l = m; l <= lmax; ++l) next[l] = col[l];
            if (m > 0) next[m - 1] = vf_set1(0.0f); /* N_{m-1}^m = 0 */
        }
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

static ALWAYS_INLINE void sphere_batch_impl(int lmax, const double center[3], double radius, int npts,
                                            const float *pts, float *coeffs, float *grad, void *work,
                                            const int with_grad)
{
    const int L = lmax + 1, nc = L * L;
    work_t w;
    work_floats(lmax, with_grad, &w, (float *)(((uintptr_t)work + 63) & ~(uintptr_t)63));
    for (int l = 0; l <= lmax; ++l)
        for (int m = 0; m <= l; ++m) {
            const double l2 = (double)l * l, m2 = (double)m * m;
            w.rec_a[l * L + m] = l >= m + 2 ? (float)sqrt((4.0 * l2 - 1.0) / (l2 - m2)) : 0.0f;
            w.rec_b[l * L + m] = l >= m + 2 ? (float)sqrt(((l - 1.0) * (l - 1.0) - m2) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0)) : 0.0f;
            w.rec_d[l * L + m] = (float)-sqrt((double)(l - m) * (l + m + 1.0));
        }
    vf wl[SHL_LMAX_MAX + 1], dwl[SHL_LMAX_MAX + 1];
    for (int p0 = 0; p0 < npts; p0 += VL) {
        const int nvalid = npts - p0 < VL ? npts - p0 : VL;
        lanes_setup(center, radius, pts + 3 * (size_t)p0, nvalid, &w);
        cap_weights(&w, lmax, wl, dwl, with_grad);
        sh_block(&w, lmax, wl, dwl, with_grad);
        /* inside the sphere: L00 = sqrt(4 pi) exactly, as shl_sphere_f */
        const vm inside = vf_gt(GEO(&w, G_INSIDE), vf_set1(0.0f));
        vf_store(w.soa, vf_sel(inside, vf_set1((float)sqrt(4.0 * M_PI)), vf_load(w.soa)));
        store_rows(w.soa, nc, coeffs + (size_t)p0 * nc, (size_t)nc, nvalid);
        if (with_grad) store_rows(w.soa + (size_t)nc * VL, 3 * nc, grad + (size_t)p0 * 3 * nc, 3 * (size_t)nc, nvalid);
    }
}

void ISA(shl__sphere_batch)(int lmax, const double center[3], double radius, int npts, const float *pts, float *coeffs,
                            float *grad, void *work)
{
    if (grad)
        sphere_batch_impl(lmax, center, radius, npts, pts, coeffs, grad, work, 1);
    else
        sphere_batch_impl(lmax, center, radius, npts, pts, coeffs, NULL, work, 0);
}
