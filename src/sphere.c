/* Spherical lights (Mezieres et al. 2022, HVL Sec. 4.2): the SH projection of
 * the cap subtended by a sphere, its gradient, and the public entry points.
 * The kernels are in sphere_impl.h, instantiated for double and float. */
#include "sphere.h"

#define SHL_REAL_IMPL "sphere_impl.h"
#include "real_instances.h"

/* Every non-zero |v_k| and a in [2^-100, 2^100]: every product, square and quotient
 * of the set-up below is a normal double both unscaled and in scaled units, so the
 * scale 2^0 gives the scaled result bit for bit (a power of two commutes with each
 * correctly rounded operation) without the exponent extraction. */
static int moderate(const double v[3], double a)
{
    int ok = a >= 0x1p-100 && a <= 0x1p100;
    for (int k = 0; k < 3; ++k) {
        const double m = fabs(v[k]);
        ok &= m == 0.0 || (m >= 0x1p-100 && m <= 0x1p100);
    }
    return ok;
}

void shl__sphere_geom_init(shl__sphere_geom *g, const double x[3], const double center[3],
                           double radius)
{
    g->inside = 1;
    double vs[3] = {center[0] - x[0], center[1] - x[1], center[2] - x[2]};
    int e = 0;
    if (!moderate(vs, radius)) {
        e = INT_MIN;
        for (int k = 0; k < 3; ++k) {
            const int ek = shl__ilogb_diff(center[k], x[k]);
            e = ek > e ? ek : e;
        }
        if (e == INT_MIN) return; /* centre at x */
        /* scaled units (internal.h): center - x times 2^-e, largest component in [1, 2);
         * no overflow in the difference, no overflow or underflow in the norm */
        for (int k = 0; k < 3; ++k) vs[k] = shl__diff_scaled(center[k], x[k], -e);
    } else if (vs[0] == 0.0 && vs[1] == 0.0 && vs[2] == 0.0) {
        return; /* centre at x */
    }
    const double ds = sqrt(shl__dot3(vs, vs)), rs = e ? shl__ldexp(radius, -e) : radius;
    if (ds <= rs) return;
    g->inside = 0;
    const double inv = 1.0 / ds; /* one division for u, sin a, cos a (each within 1.5 ulp) */
    for (int k = 0; k < 3; ++k) g->u[k] = vs[k] * inv;
    const double s = rs * inv;                         /* sin a */
    g->s2 = s * s;
    g->c = sqrt((ds - rs) * (ds + rs)) * inv;          /* cos a, exact difference ds - rs */
    g->t = g->s2 / (1.0 + g->c);                       /* 1 - cos a without cancellation */
    g->inv_d_s = inv;
    g->k_alpha_s = g->s2 / g->c * inv;                 /* d cos a / dd = sin^2 a / (d cos a) */
    if (!e) {
        g->grad_scale[0] = g->grad_scale[1] = 1.0;
        g->inv_d = g->inv_d_s;
        g->k_alpha = g->k_alpha_s;
        return;
    }
    shl__pow2_split(-e, g->grad_scale);                /* d/dx = 2^-e d/dx_scaled */
    g->inv_d = g->inv_d_s * g->grad_scale[0] * g->grad_scale[1];
    g->k_alpha = g->k_alpha_s * g->grad_scale[0] * g->grad_scale[1];
}

static int check_radius(double radius)
{
    if (!isfinite(radius)) return SHL_ENONFINITE;
    return radius > 0.0 ? SHL_OK : SHL_EDOMAIN;
}

static int sphere_d(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
                    double *coeffs, double *grad, int want_grad)
{
    if (!ctx || !x || !center || !coeffs || (want_grad && !grad)) return SHL_ENULL;
    if (shl__check_finite(x, 3) || shl__check_finite(center, 3)) return SHL_ENONFINITE;
    const int st = check_radius(radius);
    if (st) return st;
    shl__sphere_geom g;
    shl__sphere_geom_init(&g, x, center, radius);
    shl__sphere_sh_d(ctx->lmax, &g, coeffs, want_grad ? grad : NULL);
    return SHL_OK;
}

static int sphere_f(const shl_ctx *ctx, const float x[3], const float center[3], float radius,
                    float *coeffs, float *grad, int want_grad)
{
    if (!ctx || !x || !center || !coeffs || (want_grad && !grad)) return SHL_ENULL;
    if (shl__check_finite_f(x, 3) || shl__check_finite_f(center, 3)) return SHL_ENONFINITE;
    const int st = check_radius(radius);
    if (st) return st;
    const double xd[3] = {x[0], x[1], x[2]}, cd[3] = {center[0], center[1], center[2]};
    shl__sphere_geom g;
    shl__sphere_geom_init(&g, xd, cd, radius);
    shl__sphere_sh_f(ctx->lmax, &g, coeffs, want_grad ? grad : NULL);
    return SHL_OK;
}

int shl_sphere(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
               double *coeffs)
{
    return sphere_d(ctx, x, center, radius, coeffs, NULL, 0);
}

int shl_sphere_grad(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
                    double *coeffs, double *grad)
{
    return sphere_d(ctx, x, center, radius, coeffs, grad, 1);
}

int shl_sphere_f(const shl_ctx *ctx, const float x[3], const float center[3], float radius,
                 float *coeffs)
{
    return sphere_f(ctx, x, center, radius, coeffs, NULL, 0);
}

int shl_sphere_grad_f(const shl_ctx *ctx, const float x[3], const float center[3], float radius,
                      float *coeffs, float *grad)
{
    return sphere_f(ctx, x, center, radius, coeffs, grad, 1);
}

int shl_zh_cap(int lmax, double half_angle, double *zh)
{
    if (!zh) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (!isfinite(half_angle)) return SHL_ENONFINITE;
    if (half_angle < 0.0 || half_angle > M_PI) return SHL_EDOMAIN;
    const double sh = sin(0.5 * half_angle), s = sin(half_angle);
    shl__cap_weights_d(lmax, 2.0 * sh * sh, s * s, cos(half_angle), zh, NULL);
    for (int l = 0; l <= lmax; ++l) zh[l] *= sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); /* HVL Eq. (14) */
    return SHL_OK;
}
