/* Spherical lights (Mezieres et al. 2022, HVL Sec. 4.2): the SH projection of
 * the cap subtended by a sphere, its gradient, and the public entry points.
 * The kernels and the public entry points are in sphere_impl.h, instantiated for
 * double and float. */
#include "sphere.h"

#include <float.h>

/* Bands with an unrolled value kernel (sphere_small in sphere_impl.h). */
#define SHL__SPHERE_SMALL 5
#define SHL__ALWAYS_INLINE __attribute__((always_inline)) inline
#define SHL__NOINLINE __attribute__((noinline))

/* Every non-zero |v_k| and a in [2^-100, 2^100): every product, square and quotient
 * of the set-up below is a normal double both unscaled and in scaled units, so the
 * scale 2^0 gives the scaled result bit for bit (a power of two commutes with each
 * correctly rounded operation) without the exponent extraction.  Tested on the bits
 * (biased exponent in [1023 - 100, 1023 + 100)), one unsigned comparison per value;
 * false for any non-finite value and for a <= 0. */
static inline int moderate1(double v)
{
    uint64_t b;
    memcpy(&b, &v, sizeof b);
    b <<= 1; /* drop the sign */
    return (b == 0) | (b - ((uint64_t)(1023 - 100) << 53) < ((uint64_t)200 << 53));
}
static inline int moderate(const double v[3], double a)
{
    uint64_t b;
    memcpy(&b, &a, sizeof b); /* a < 0: the sign bit puts b out of range */
    return (b - ((uint64_t)(1023 - 100) << 52) < ((uint64_t)200 << 52)) & moderate1(v[0]) & moderate1(v[1]) &
           moderate1(v[2]);
}

/* Not moderate: vs = center - x in scaled units (internal.h), times 2^-e with the
 * largest component in [1, 2) (no overflow in the difference, no overflow or
 * underflow in the norm), and *rs = radius 2^-e; returns e, INT_MIN for the centre
 * at x.  Out of line: the common path stays short. */
static SHL__NOINLINE int geom_scaled(double vs[3], const double x[3], const double center[3], double radius, double *rs)
{
    int e = INT_MIN;
    for (int k = 0; k < 3; ++k) {
        const int ek = shl__ilogb_diff(center[k], x[k]);
        e = ek > e ? ek : e;
    }
    if (e == INT_MIN) return e;
    for (int k = 0; k < 3; ++k) vs[k] = shl__diff_scaled(center[k], x[k], -e);
    *rs = e ? shl__ldexp(radius, -e) : radius;
    return e;
}

/* From vs = center - x and the radius rs in the same units (scaled or not): inside,
 * u, t, s2, c and inv_d_s.  vs = 0 (the centre at x) is inside. */
static inline void geom_units(shl__sphere_geom *g, const double vs[3], double rs)
{
    g->inside = 1;
    const double ds = sqrt(shl__dot3(vs, vs));
    if (ds <= rs) return;
    g->inside = 0;
    const double inv = 1.0 / ds; /* one division for u, sin a, cos a (each within 1.5 ulp) */
    for (int k = 0; k < 3; ++k) g->u[k] = vs[k] * inv;
    const double s = rs * inv;                         /* sin a */
    g->s2 = s * s;
    g->c = sqrt((ds - rs) * (ds + rs)) * inv;          /* cos a, exact difference ds - rs */
    g->t = g->s2 / (1.0 + g->c);                       /* 1 - cos a without cancellation */
    g->inv_d_s = inv;
}

/* The _x values of shl__sphere_geom from s2_x = sin^2 a 2^-s2_e, e the exponent of
 * the scaled units; t_x and k_alpha_x as t and k_alpha_s in geom_units and
 * shl__sphere_geom_init (the same operations on s2_x). */
static void set_tiny_s2(shl__sphere_geom *g, double s2_x, int s2_e, int e)
{
    g->s2_e = s2_e;
    g->s2_x = s2_x;
    g->t_x = s2_x / (1.0 + g->c);
    g->k_alpha_x = s2_x / g->c * g->inv_d_s;
    shl__pow2_split(s2_e - e, g->x_scale);
}

void shl__sphere_geom_init(shl__sphere_geom *g, const double x[3], const double center[3],
                           double radius)
{
    double vs[3] = {center[0] - x[0], center[1] - x[1], center[2] - x[2]}, rs = radius;
    int e = 0;
    if (!moderate(vs, radius)) {
        e = geom_scaled(vs, x, center, radius, &rs);
        if (e == INT_MIN) { /* centre at x */
            g->inside = 1;
            return;
        }
    }
    geom_units(g, vs, rs);
    if (g->inside) return;
    g->k_alpha_s = g->s2 / g->c * g->inv_d_s;          /* d cos a / dd = sin^2 a / (d cos a) */
    g->s2_e = 0;
    if (g->s2 < SHL__S2_TINY_F && rs > 0.0) {
        /* sin a = rs / ds times 2^m with rs 2^m in [1, 2) (exact): s2_x = sin^2 a 2^2m is a
         * normal double even where sin^2 a underflows (r/d < 2^-511) */
        const int m = -shl__ilogb(rs);
        const double sx = shl__ldexp(rs, m) * g->inv_d_s;
        set_tiny_s2(g, sx * sx, -2 * m, e);
    }
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

/* The float entry points' set-up, in double from the float arguments: every
 * difference c_k - x_k is 0 or of magnitude in [2^-149, 2^129], so every value below
 * (d2 in [2^-298, 2^260], r in [2^-149, 2^128), their products and quotients) is a
 * normal double: no scaling, and the results are exact under a power-of-two scaling of
 * the arguments (u, t, s2, c unchanged).  The inside test is geom_units' (the same
 * ds <= r).  The chain is shorter than geom_units': 1/d2 and the two square roots
 * depend only on d2, where geom_units' cos a waits on sqrt(d2), 1/ds and a second
 * sqrt.  Errors (eps = 2^-53): d2 within 3 eps (v's rounding included), r2 = r r
 * exact (r a float), d2 - r2 exact near tangency (Sterbenz), so cos a = sqrt(d2 - r2) / d
 * is within ~(3/4) eps r / gap (gap = d - r), geom_units' within ~eps r / gap (ds's
 * rounding, amplified by d / (d - r)); u, s2, t within 4 eps away from tangency: far
 * below the float rounding of the kernels' inputs. */
static inline void geom_units_f(shl__sphere_geom *g, const double v[3], double d2, double r)
{
    const double ds = sqrt(d2);
    g->inside = ds <= r;
    if (g->inside) return;
    const double inv2 = 1.0 / d2, e2 = d2 - r * r; /* e2 > 0: ds > r implies d2 > r^2 */
    const double inv = ds * inv2;                      /* 1 / d */
    for (int k = 0; k < 3; ++k) g->u[k] = v[k] * inv;
    g->s2 = r * r * inv2;                              /* sin^2 a */
    g->c = sqrt(e2) * inv;                             /* cos a = sqrt(d^2 - r^2) / d */
    g->t = g->s2 / (1.0 + g->c);                       /* 1 - cos a without cancellation */
    g->inv_d_s = inv;
}

/* shl__sphere_geom_init for the float entry points (geom_units_f), their arguments
 * finite and the radius > 0: the gradient's factors unscaled where moderate() holds
 * (as there), else in units of 2^e with e the exponent of the largest |c_k - x_k|
 * (exact powers of two: the float kernels' results scale with them). */
static void geom_init_f(shl__sphere_geom *g, const double x[3], const double center[3], double radius)
{
    const double v[3] = {center[0] - x[0], center[1] - x[1], center[2] - x[2]};
    geom_units_f(g, v, shl__dot3(v, v), radius);
    if (g->inside) return;
    int e = 0;
    if (!moderate(v, radius)) { /* v != 0: outside */
        e = INT_MIN;
        for (int k = 0; k < 3; ++k)
            if (v[k] != 0.0 && shl__ilogb(v[k]) > e) e = shl__ilogb(v[k]);
    }
    g->inv_d_s = shl__ldexp(g->inv_d_s, e);
    g->k_alpha_s = g->s2 / g->c * g->inv_d_s;
    g->s2_e = 0;
    if (g->s2 < SHL__S2_TINY_F) { /* s2 a normal double here: 2^-s2_e exact */
        const int s2_e = shl__ilogb(g->s2);
        set_tiny_s2(g, shl__ldexp(g->s2, -s2_e), s2_e, e);
    }
    shl__pow2_split(-e, g->grad_scale);
    g->inv_d = g->inv_d_s * g->grad_scale[0] * g->grad_scale[1];
    g->k_alpha = g->k_alpha_s * g->grad_scale[0] * g->grad_scale[1];
}

/* The entry points' common-case set-up (sphere_impl.h): 1 when the arguments need no
 * further check (and then, if need, g is set up unscaled), 0 for the general path.
 * Double: moderate() (sphere.c's top). */
static SHL__ALWAYS_INLINE int entry_geom_d(shl__sphere_geom *g, const double xd[3], const double cd[3], double radius,
                                           int want_grad, int need)
{
    (void)want_grad;
    const double vs[3] = {cd[0] - xd[0], cd[1] - xd[1], cd[2] - xd[2]};
    const int mod = moderate(vs, radius);
    if (mod && need) geom_units(g, vs, radius);
    return mod;
}
/* Float: finite arguments and a radius in (0, FLT_MAX] suffice for the coefficients
 * (d2 finite exactly when every coordinate is: a float difference cannot overflow a
 * double); the gradient's kernels take unscaled factors, so it also needs moderate()
 * and sin^2 a = r^2 / d2 >= SHL__S2_TINY_F (else the general path's sphere_grad_tiny). */
static SHL__ALWAYS_INLINE int entry_geom_f(shl__sphere_geom *g, const double xd[3], const double cd[3], double radius,
                                           int want_grad, int need)
{
    const double v[3] = {cd[0] - xd[0], cd[1] - xd[1], cd[2] - xd[2]};
    const double d2 = shl__dot3(v, v);
    const int grad_ok = moderate(v, radius) & (radius * radius >= SHL__S2_TINY_F * d2);
    const int ok = (d2 <= DBL_MAX) & (radius > 0.0) & (radius <= FLT_MAX) & (!want_grad || grad_ok);
    if (ok && need) geom_units_f(g, v, d2, radius);
    return ok;
}
static inline void geom_init_d(shl__sphere_geom *g, const double x[3], const double center[3], double radius)
{
    shl__sphere_geom_init(g, x, center, radius);
}

static int check_radius(double radius)
{
    if (!isfinite(radius)) return SHL_ENONFINITE;
    return radius > 0.0 ? SHL_OK : SHL_EDOMAIN;
}

#define SHL_REAL_IMPL "sphere_impl.h"
#include "real_instances.h"

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
