/* Harmonics Virtual Lights (Mezieres et al. 2022, Sec. 5): the contribution of
 * a set of HVLs at a shading point (Eq. 19-22) and the two radius heuristics
 * (Eq. 23-26). */
#include "sh_basis.h"
#include "sphere.h"
#include "brdf.h"
#include <limits.h>

/* S(w) = 3 w^2 - 2 w^3 for 2^-50 <= w <= 1/2, to within 2^-100 relative before
 * the final rounding (w^2, 3 - 2w and their product carried as double-doubles),
 * so that the result is S(w) correctly rounded unless S(w) lies within 2^-100
 * of a rounding midpoint: monotone in w, where the plain product is not (it
 * steps down by an ulp at about 1 in 860 consecutive doubles, measured). */
static double smoothstep_lo(double w)
{
    const double w2 = w * w, w2_lo = fma(w, w, -w2);          /* w^2 = w2 + w2_lo exactly */
    const double r = 3.0 - 2.0 * w, r_lo = (3.0 - r) - 2.0 * w; /* 3 - 2w = r + r_lo exactly */
    const double p = w2 * r, p_lo = fma(w2, r, -p);
    return p + (p_lo + (w2 * r_lo + w2_lo * r));
}

/* HVL Eq. (22) with the clamp range [pi/2 - a, pi/2 + a] (see shlight.h).  With
 * e = pi/2 - theta = asin(cos_theta) the argument of S is (a + e) / (2a), free of
 * the cancellation of a + pi/2 - theta when a << pi/2.  The cap is entirely
 * above the horizon for e >= a (H = 1), entirely below for e <= -a (H = 0).
 * Inside, S is evaluated at w = (a - |e|) / (2a), the distance in S's argument
 * to the nearer end (0 < w <= 1/2, a - |e| exact when |e| >= a/2), and
 * H = S(w) below the horizon, 1 - S(w) above (S(1 - w) = 1 - S(w)).  w < 2^-50
 * puts e within 2^-49 a (8 to 16 ulps of a) of an edge, where the exact H is 0
 * or 1 to 3e-30: H is 0 or 1 there (1 - S(w) rounds to 1 anyway), so that a
 * cap beyond an edge gives exactly 0 or 1 even if asin rounds across it. */
static double overlap(double cos_theta, double a)
{
    if (a == 0.0) return cos_theta > 0.0 ? 1.0 : (cos_theta < 0.0 ? 0.0 : 0.5);
    const double e = asin(cos_theta);
    if (e >= a) return 1.0;
    if (e <= -a) return 0.0;
    const double w = (a - fabs(e)) / (2.0 * a);
    const double s = w < 0x1p-50 ? 0.0 : smoothstep_lo(w);
    return e < 0.0 ? s : 1.0 - s;
}

int shl_hvl_overlap(double cos_theta, double half_angle, double *h)
{
    if (!h) return SHL_ENULL;
    if (!isfinite(cos_theta) || !isfinite(half_angle)) return SHL_ENONFINITE;
    if (fabs(cos_theta) > 1.0 || half_angle < 0.0 || half_angle > 0.5 * M_PI) return SHL_EDOMAIN;
    *h = overlap(cos_theta, half_angle);
    return SHL_OK;
}

static int check_hvl(const shl_hvl *h)
{
    if (!h->brdf) return SHL_ENULL;
    const double v[11] = {h->pos[0], h->pos[1], h->pos[2], h->normal[0], h->normal[1], h->normal[2],
                          h->to_light[0], h->to_light[1], h->to_light[2], h->radius, h->power};
    if (shl__check_finite(v, 11)) return SHL_ENONFINITE;
    if (!(h->radius > 0.0)) return SHL_EDOMAIN;
    double u[3];
    int st;
    if ((st = shl__unit(h->normal, u)) || (st = shl__unit(h->to_light, u))) return st;
    return SHL_OK;
}

/* Emission of HVL h towards the unit direction -u (u from x to the HVL):
 * Phi_j (F'_{w_l} . Y(-w_j)) max(0, n_j . -w_j) / (pi r_j^2) (Eq. 20-21, without H). */
static double emission(const shl_hvl *h, const double u[3])
{
    const shl_brdf_table *t = h->brdf;
    double nj[3], lj[3], fr[9], fp[SHL_NCOEFFS(SHL_LMAX_MAX)], y[SHL_NCOEFFS(SHL_LMAX_MAX)];
    shl__unit(h->normal, nj);
    shl__unit(h->to_light, lj);
    const double cos_out = -shl__dot3(nj, u);
    if (!(cos_out > 0.0)) return 0.0;
    shl__brdf_frame(nj, lj, fr);
    shl__brdf_table_at(t, shl__dot3(lj, fr + 6), shl__dot3(lj, fr), NULL, fp);
    const double dl[3] = {-shl__dot3(fr, u), -shl__dot3(fr + 3, u), -shl__dot3(fr + 6, u)};
    shl__sh_eval(t->lmax, dl[0], dl[1], dl[2], y);
    double e = 0.0;
    for (int k = 0; k < t->nc; ++k) e += fp[k] * y[k]; /* F' . Y(-w_j), Eq. (20) */
    return h->power * e * cos_out / (M_PI * h->radius * h->radius);
}

int shl_hvl_shade(const shl_hvl *hvls, int count, const double x[3], const double n[3],
                  const double wo[3], const shl_brdf_table *material, double *radiance)
{
    if (!x || !n || !wo || !material || !radiance || (count > 0 && !hvls)) return SHL_ENULL;
    if (count < 0) return SHL_EDOMAIN;
    if (shl__check_finite(x, 3)) return SHL_ENONFINITE;
    double nu[3], ou[3], fx[9];
    int st;
    if ((st = shl__unit(n, nu)) || (st = shl__unit(wo, ou))) return st;
    for (int j = 0; j < count; ++j)
        if ((st = check_hvl(&hvls[j]))) return st;
    const int lmax = material->lmax, nc = material->nc;
    double f[SHL_NCOEFFS(SHL_LMAX_MAX)], cap[SHL_NCOEFFS(SHL_LMAX_MAX)];
    shl__brdf_frame(nu, ou, fx);
    shl__brdf_table_at(material, shl__dot3(ou, fx + 6), shl__dot3(ou, fx), f, NULL);
    double sum = 0.0;
    for (int j = 0; j < count; ++j) {
        const shl_hvl *h = &hvls[j];
        const double v[3] = {h->pos[0] - x[0], h->pos[1] - x[1], h->pos[2] - x[2]};
        double u[3];
        if (shl__unit(v, u)) continue; /* centred exactly at x */
        shl__sphere_geom g;
        shl__sphere_geom_init(&g, x, h->pos, h->radius);
        if (g.inside) { /* clamp to the tangent cap: the hemisphere about w_j */
            g.inside = 0;
            g.s2 = g.t = 1.0;
            g.c = 0.0;
        }
        const double a = atan2(sqrt(g.s2), g.c);
        for (int k = 0; k < 3; ++k) g.u[k] = shl__dot3(fx + 3 * k, u); /* frame change, Sec. 4.2 */
        shl__sphere_sh_d(lmax, &g, cap, NULL);                         /* L, Eq. (15) */
        double lf = 0.0;
        for (int k = 0; k < nc; ++k) lf += cap[k] * f[k]; /* L . F, Eq. (19) */
        const double hj = overlap(fmax(-1.0, fmin(1.0, shl__dot3(nu, u))), a); /* H, Eq. (22) */
        sum += emission(h, u) * hj * lf;
    }
    *radiance = sum;
    return SHL_OK;
}

int shl_hvl_radius_grid(int width, int height, const double *pos, const double *dist, double eps,
                        double scale, double *radius)
{
    if (!pos || !dist || !radius) return SHL_ENULL;
    if (width < 1 || height < 1 || (long long)width * height > INT_MAX / 3 || width * height < 2)
        return SHL_EDOMAIN;
    const int n = width * height;
    if (shl__check_finite(pos, 3 * n) || shl__check_finite(dist, n) || !isfinite(eps) || !isfinite(scale))
        return SHL_ENONFINITE;
    if (!(eps > 0.0) || !(scale > 0.0)) return SHL_EDOMAIN;
    for (int i = 0; i < height; ++i)
        for (int j = 0; j < width; ++j) {
            const int c = i * width + j;
            double num = 0.0, den = 0.0;
            for (int di = -1; di <= 1; ++di)
                for (int dj = -1; dj <= 1; ++dj) {
                    const int ni = i + di, nj = j + dj;
                    if ((di == 0 && dj == 0) || ni < 0 || ni >= height || nj < 0 || nj >= width) continue;
                    const int o = ni * width + nj;
                    const double e[3] = {pos[3 * c] - pos[3 * o], pos[3 * c + 1] - pos[3 * o + 1],
                                         pos[3 * c + 2] - pos[3 * o + 2]};
                    const double w = 1.0 / (fabs(dist[c] - dist[o]) + eps); /* HVL Eq. (23) */
                    num += w * sqrt(shl__dot3(e, e));
                    den += w;
                }
            radius[c] = scale * num / den;
        }
    return SHL_OK;
}

int shl_hvl_radius_fov(int count, const double *dist, double fov, double scale, double *radius)
{
    if (!dist || !radius) return SHL_ENULL;
    if (count < 1) return SHL_EDOMAIN;
    if (shl__check_finite(dist, count) || !isfinite(fov) || !isfinite(scale)) return SHL_ENONFINITE;
    if (!(fov > 0.0 && fov < M_PI) || !(scale > 0.0)) return SHL_EDOMAIN;
    for (int i = 0; i < count; ++i)
        if (dist[i] < 0.0) return SHL_EDOMAIN;
    const double g = M_SQRT2 * fov / sqrt((double)count);   /* HVL Eq. (24) */
    for (int i = 0; i < count; ++i)
        radius[i] = scale * dist[i] * (g + g * g * g / 3.0); /* Eq. (26), Taylor form of Eq. (25) */
    return SHL_OK;
}
