/* Irradiance: the exact unshadowed irradiance of a unit-radiance polygon
 * (Lambert's formula on the polygon clipped to the receiver's horizon, or a
 * Gauss rule on its plane when it is small), and irradiance from SH radiance
 * (Funk-Hecke with the clamped cosine, Ramamoorthi & Hanrahan 2001).
 *
 * Polygon geometry follows polygon.c: repeated vertices dropped, coordinates
 * taken relative to x and scaled by a power of two (internal.h), a point in the
 * polygon's plane (within a few ulps of the distances) sees nothing. */
#include "quad.h"
#include <float.h>

enum { MAXV = 2 * SHL_MAX_VERTS, /* clipping adds at most one vertex per edge */
       NGAUSS = 5 };

/* A (clipped) polygon seen from x, scaled units: pos[i] = (p_i - x) 2^-E and
 * off[i] = (p_i - v_0) 2^-E, the latter from differences of the input vertices
 * (accurate to eps times the polygon's size, not its distance). */
typedef struct {
    int n;
    double pos[MAXV][3], off[MAXV][3];
} clip_poly;

/* Lambert's formula E = 1/2 sum_e gamma_e (n . u_e) (Lambert 1760; Arvo 1995 Eq. 9):
 * gamma_e = angle of edge e seen from x, atan2(|a x b|, a . b); u_e = a x b / |a x b|,
 * which for a polygon counter-clockwise about the direction of view (polygon.c
 * orientation) points into the polygon, so every term is >= 0 for a polygon
 * straight ahead.  a x b = a x (b - a) = b x (b - a) from the accurate edge vector and the
 * nearer vertex (polygon.c, shl__poly_geom_init). */
static double lambert(const clip_poly *p, const double nrm[3])
{
    double sum = 0.0;
    for (int e = 0; e < p->n; ++e) {
        const int f = e + 1 == p->n ? 0 : e + 1;
        double edge[3], c[3];
        for (int k = 0; k < 3; ++k) edge[k] = p->off[f][k] - p->off[e][k];
        shl__cross3(shl__norm3(p->pos[f]) < shl__norm3(p->pos[e]) ? p->pos[f] : p->pos[e], edge, c);
        const double clen = shl__norm3(c);
        if (!(clen > 0.0)) continue; /* zero arc: no contribution */
        const double gamma = atan2(clen, shl__dot3(p->pos[e], p->pos[f]));
        sum += gamma * (shl__dot3(nrm, c) / clen);
    }
    return fmax(0.0, 0.5 * sum);
}

/* The same integral over the polygon's plane: dw = h dA / r^3 and n . w = n . p / r,
 * E = h int (n . p) / |p|^4 dA (h = height of x under the plane, > 0), on the fan of
 * triangles from vertex 0 (signed areas: concave polygons too), each with the
 * collapsed NGAUSS x NGAUSS Gauss-Legendre product p = A + u (B - A) + u v (C - B),
 * dA = 2 |T| u du dv.  Used when the polygon's size s is below 1/16 of its distance d:
 * the integrand is analytic within 15 s of every point of the polygon, so the rule's
 * relative error is about rho^(-2 NGAUSS), rho ~ 2 (d - s) / (s / 2) >= 60: ~1e-18. */
static double area_rule(const clip_poly *p, const double nrm[3], const double pnrm[3], double height)
{
    double gx[NGAUSS], gw[NGAUSS];
    shl__gauss_legendre(NGAUSS, gx, gw);
    double total = 0.0;
    for (int t = 1; t + 1 < p->n; ++t) {
        double ab[3], bc[3], c[3];
        shl__fan_triangle(p->off, t, ab, bc, c);
        const double area2 = shl__dot3(pnrm, c); /* twice the signed area */
        double tri = 0.0;
        for (int i = 0; i < NGAUSS; ++i) {
            const double u = 0.5 * (gx[i] + 1.0);
            double row = 0.0;
            for (int j = 0; j < NGAUSS; ++j) {
                const double v = 0.5 * (gx[j] + 1.0);
                double q[3];
                for (int k = 0; k < 3; ++k) q[k] = p->pos[0][k] + u * ab[k] + u * v * bc[k];
                const double r2 = shl__dot3(q, q);
                row += gw[j] * fmax(0.0, shl__dot3(nrm, q)) / (r2 * r2);
            }
            tri += gw[i] * u * row;
        }
        total += 0.25 * area2 * tri; /* (du dv on [0,1]^2) = 1/4 (d gx d gy) */
    }
    return fmax(0.0, height * total);
}

/* Unit Newell normal from off[] (polygon.c's newell_normal, here on scaled offsets);
 * 0 for a zero-area polygon. */
static int newell(const clip_poly *p, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    for (int i = 1; i + 1 < p->n; ++i) {
        double c[3];
        shl__cross3(p->off[i], p->off[i + 1], c);
        for (int k = 0; k < 3; ++k) out[k] += c[k];
    }
    const double len = shl__norm3(out);
    if (!(len > 0.0)) return 0;
    for (int k = 0; k < 3; ++k) out[k] /= len;
    return 1;
}

/* The irradiance, or 0 when x sees nothing; inputs validated, nrm unit. */
static double polygon_irradiance(const double x[3], const double nrm[3], const double *verts, int n)
{
    double kept[SHL_MAX_VERTS * 3];
    const int m = shl__drop_repeated(verts, n, kept); /* as polygon.c */
    if (m < 3) return 0.0;

    /* scaled units: the largest component of v - x in [1, 2) */
    const int ex = shl__scale_exponent(x, kept, m);
    if (ex == INT_MIN) return 0.0; /* x on a vertex: in the plane */
    clip_poly poly;
    poly.n = m;
    double rmax = 0.0;
    for (int i = 0; i < m; ++i)
        for (int k = 0; k < 3; ++k) {
            poly.pos[i][k] = shl__diff_scaled(kept[3 * i + k], x[k], -ex);
            poly.off[i][k] = shl__diff_scaled(kept[3 * i + k], kept[k], -ex);
        }
    for (int i = 0; i < m; ++i) rmax = fmax(rmax, shl__norm3(poly.pos[i]));
    double pnrm[3];
    if (!newell(&poly, pnrm)) return 0.0; /* zero area */
    double height = shl__dot3(pnrm, poly.pos[0]);
    if (fabs(height) <= 8.0 * DBL_EPSILON * rmax) return 0.0; /* in the plane, as polygon.c */
    if (height < 0.0) { /* orient counter-clockwise about the direction of view */
        for (int k = 0; k < 3; ++k) pnrm[k] = -pnrm[k];
        height = -height;
        for (int i = 1, j = m - 1; i < j; ++i, --j) /* keep vertex 0: off[] stays relative to it */
            for (int k = 0; k < 3; ++k) {
                double t = poly.pos[i][k];
                poly.pos[i][k] = poly.pos[j][k];
                poly.pos[j][k] = t;
                t = poly.off[i][k];
                poly.off[i][k] = poly.off[j][k];
                poly.off[j][k] = t;
            }
    }

    /* Sutherland-Hodgman against the tangent plane n . (p - x) >= 0 */
    double side[SHL_MAX_VERTS];
    int above = 0, below = 0;
    for (int i = 0; i < m; ++i) {
        side[i] = shl__dot3(nrm, poly.pos[i]);
        above += side[i] > 0.0;
        below += side[i] < 0.0;
    }
    if (above == 0) return 0.0; /* entirely on or below the horizon */
    clip_poly clip;
    const clip_poly *use = &poly;
    if (below > 0) {
        int c = 0;
        for (int i = 0; i < m; ++i) {
            const int j = i + 1 == m ? 0 : i + 1;
            if (side[i] >= 0.0) {
                memcpy(clip.pos[c], poly.pos[i], sizeof clip.pos[c]);
                memcpy(clip.off[c], poly.off[i], sizeof clip.off[c]);
                ++c;
            }
            if ((side[i] > 0.0 && side[j] < 0.0) || (side[i] < 0.0 && side[j] > 0.0)) {
                const double t = side[i] / (side[i] - side[j]); /* in (0, 1) */
                for (int k = 0; k < 3; ++k) {
                    const double edge = poly.off[j][k] - poly.off[i][k];
                    clip.pos[c][k] = poly.pos[i][k] + t * edge;
                    clip.off[c][k] = poly.off[i][k] + t * edge;
                }
                ++c;
            }
        }
        clip.n = c;
        if (c < 3) return 0.0;
        use = &clip;
    }

    /* small and far (size below 1/16 of the distance): the area rule, whose error does not
     * grow as the polygon shrinks; else Lambert's boundary sum (README: accuracy) */
    double size = 0.0, dmin = INFINITY;
    for (int i = 0; i < use->n; ++i) {
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = use->off[i][k] - use->off[0][k];
        size = fmax(size, shl__norm3(d));
        dmin = fmin(dmin, shl__norm3(use->pos[i]));
    }
    return 16.0 * size <= dmin ? area_rule(use, nrm, pnrm, height) : lambert(use, nrm);
}

int shl_polygon_irradiance(const double x[3], const double normal[3], const double *verts, int n,
                           double *irradiance)
{
    if (!x || !normal || !verts || !irradiance) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    double nrm[3];
    const int st = shl__unit(normal, nrm);
    if (st) return st;
    *irradiance = polygon_irradiance(x, nrm, verts, n);
    return SHL_OK;
}

/* sum_l A_l sum_m coeffs[l(l+1)+m] y[l(l+1)+m], A_l = a[l] */
static double sh_irradiance(int lmax, const double *coeffs, const double *y, const double *a)
{
    double e = 0.0;
    for (int l = 0; l <= lmax; ++l) {
        if (a[l] == 0.0) continue; /* odd l >= 3 */
        double band = 0.0;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) band += coeffs[k] * y[k];
        e += a[l] * band;
    }
    return e;
}

/* Y_k(n/|n|) and A_l: Funk-Hecke, E(n) = sum_l A_l sum_m L_lm Y_lm(n),
 * A_l = 2 pi int_0^1 P_l(t) t dt = sqrt(4 pi / (2l+1)) zh_l
 * (sh_convolve.c: zh_l = 2 pi K_l int_0^1 t P_l(t) dt) */
static int irradiance_weights(int lmax, const double normal[3], double *y, double *a)
{
    double nrm[3];
    int st = shl__unit(normal, nrm);
    if (!st) st = shl_eval_basis(lmax, nrm, y);
    if (!st) st = shl_zh_clamped_cosine(lmax, a);
    if (st) return st;
    for (int l = 0; l <= lmax; ++l) a[l] *= sqrt(4.0 * M_PI / (2.0 * l + 1.0));
    return SHL_OK;
}

int shl_sh_irradiance(int lmax, const double *coeffs, const double normal[3], double *irradiance)
{
    if (!coeffs || !normal || !irradiance) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (shl__check_finite(coeffs, SHL_NCOEFFS(lmax))) return SHL_ENONFINITE;
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)], a[SHL_LMAX_MAX + 1];
    const int st = irradiance_weights(lmax, normal, y, a);
    if (st) return st;
    *irradiance = sh_irradiance(lmax, coeffs, y, a);
    return SHL_OK;
}

int shl_sh_irradiance_rgb(int lmax, const double *rgb, const double normal[3], double irradiance[3])
{
    if (!rgb || !normal || !irradiance) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const int nc = SHL_NCOEFFS(lmax);
    if (shl__check_finite(rgb, 3 * nc)) return SHL_ENONFINITE;
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)], a[SHL_LMAX_MAX + 1];
    const int st = irradiance_weights(lmax, normal, y, a);
    if (st) return st;
    for (int c = 0; c < 3; ++c) irradiance[c] = sh_irradiance(lmax, rgb + c * nc, y, a);
    return SHL_OK;
}
