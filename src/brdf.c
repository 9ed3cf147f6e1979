/* Isotropic BRDF SH tables (HVL Sec. 4.2, Eq. 16-18, after Kautz et al. 2002).
 *
 * Projection.  For wo = (theta_o, phi_o = 0) the integrand is even in phi_i, so
 * with Y_lm(theta, phi) = Y_lm(theta, 0) cos(m phi) (m >= 0; m < 0 vanish)
 *   F'_lm = 2 int_0^{pi/2} Y_lm(theta, 0) c_m(theta) sin(theta) dtheta,
 *   c_m(theta) = int_0^pi f_s(theta, phi) cos(m phi) dphi,
 * and F_lm the same with an extra cos(theta).  Both integrals use
 * Gauss-Legendre panels graded geometrically towards the features of the
 * integrand: in theta towards theta_o (the mirror direction) from both sides,
 * towards the horizon for GGX (the Smith term falls off over ~alpha) and, for
 * Phong, towards where the lobe's cut-off circle r . wi = 0 enters; in phi
 * towards phi = pi with the lobe's azimuthal width at that theta and towards the
 * cut-off circle.  The horizon theta = pi/2 is a panel end, so the cut-off of F'
 * costs no accuracy. */
#include "sh_basis.h"
#include "quad.h"
#include "brdf.h"

enum { NT = 20, NP = 16 }; /* Gauss-Legendre nodes per theta / phi panel */
static int check_brdf(const shl_brdf *b)
{
    if (b->model != SHL_BRDF_GGX && b->model != SHL_BRDF_PHONG) return SHL_EDOMAIN;
    const double v[3] = {b->kd, b->ks, b->model == SHL_BRDF_GGX ? b->alpha : b->exponent};
    if (shl__check_finite(v, 3) || (b->model == SHL_BRDF_GGX && !isfinite(b->f0)))
        return SHL_ENONFINITE;
    if (b->kd < 0.0 || b->ks < 0.0) return SHL_EDOMAIN;
    if (b->model == SHL_BRDF_GGX)
        return (b->alpha >= 1e-3 && b->alpha <= 1.0 && b->f0 >= 0.0 && b->f0 <= 1.0) ? SHL_OK : SHL_EDOMAIN;
    return (b->exponent >= 0.0 && b->exponent <= 1e6) ? SHL_OK : SHL_EDOMAIN;
}

static double smith_lambda(double a2, double c) /* GGX Lambda(w), c = cos theta > 0 */
{
    return 0.5 * (sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)) - 1.0);
}

/* f_s for unit local directions. */
static double brdf_value(const shl_brdf *b, const double wi[3], const double wo[3])
{
    const double ci = wi[2], co = wo[2];
    if (!(ci > 0.0 && co > 0.0)) return 0.0;
    double f = b->kd / M_PI;
    if (b->ks == 0.0) return f;
    if (b->model == SHL_BRDF_PHONG) {
        /* (r . wi)^n, r = (-wo_x, -wo_y, wo_z), as (1 - d)^n with d = 1 - r . wi = |r - wi|^2 / 2:
         * r . wi near 1 carries its rounding (~1e-16 absolute) into the lobe as n 1e-16
         * relative (1e-10 at n = 1e6); the chord's square has no cancellation, and the
         * inputs' length errors change it only in second order */
        const double e[3] = {-wo[0] - wi[0], -wo[1] - wi[1], wo[2] - wi[2]};
        const double d = 0.5 * shl__dot3(e, e);
        if (d < 1.0) f += b->ks * (b->exponent + 2.0) / (2.0 * M_PI) * exp(b->exponent * log1p(-d));
        return f;
    }
    const double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    const double len2 = shl__dot3(h, h), len = sqrt(len2), cd = shl__dot3(wi, h) / len;
    const double a2 = b->alpha * b->alpha;
    const double den = (h[0] * h[0] + h[1] * h[1] + a2 * h[2] * h[2]) / len2; /* sin^2 + a2 cos^2 theta_h */
    const double d = a2 / (M_PI * den * den);
    const double g = 1.0 / (1.0 + smith_lambda(a2, ci) + smith_lambda(a2, co)); /* height-correlated */
    const double fr = b->f0 + (1.0 - b->f0) * pow(1.0 - cd, 5.0);              /* Schlick */
    return f + b->ks * d * g * fr / (4.0 * ci * co);
}

int shl_brdf_eval(const shl_brdf *brdf, const double wi[3], const double wo[3], double *value)
{
    if (!brdf || !wi || !wo || !value) return SHL_ENULL;
    int st = check_brdf(brdf);
    if (st) return st;
    double i[3], o[3];
    if ((st = shl__unit(wi, i)) || (st = shl__unit(wo, o))) return st;
    *value = brdf_value(brdf, i, o);
    return SHL_OK;
}

/* Feature points of an integrand (at most 3) for shl__graded_breaks. */
typedef struct {
    int n;
    double pos[3], below[3], above[3];
} features;

static void add_feature(features *f, double pos, double below, double above)
{
    f->pos[f->n] = pos;
    f->below[f->n] = below;
    f->above[f->n++] = above;
}

typedef struct {
    const shl_brdf *b;
    int lmax;
    double wo[3], theta_o, theta_s; /* theta_s: the Phong cut-off circle r . wi = 0 reaches phi = 0 */
    double w_in, squeeze;        /* lobe width in the plane of incidence, compression across */
    double w_cut;                /* grading at the Phong cut-off, where the lobe ~ distance^n */
    double gx[NT], gw[NT], px[NP], pw[NP];
    double c[SHL_LMAX_MAX + 1];  /* c_m(theta) */
    double y[SHL_NCOEFFS(SHL_LMAX_MAX)];
} projector;

/* c_m(theta) = int_0^pi f_s(theta, phi) cos(m phi) dphi, in psi = pi - phi */
static void azimuthal_moments(projector *pj, double th)
{
    const double st = sin(th), ct = cos(th);
    const double w_lobe = fmin(M_PI, pj->squeeze * (pj->w_in + fabs(th - pj->theta_o)) / fmax(st, 1e-300));
    features f = {0, {0}, {0}, {0}};
    add_feature(&f, 0.0, M_PI, w_lobe);
    if (th > pj->theta_s) { /* Phong: r . wi = sin(theta_o) sin(theta) cos(psi) + cos cos > 0 for psi < psi_k */
        const double x = pj->wo[2] * ct / (pj->wo[0] * st);
        add_feature(&f, acos(fmax(-1.0, fmin(1.0, -x))), pj->w_cut, M_PI);
    }
    double brk[SHL__MAX_PANELS + 1];
    const int np = shl__graded_breaks(0.0, M_PI, f.n, f.pos, f.below, f.above, brk);
    for (int m = 0; m <= pj->lmax; ++m) pj->c[m] = 0.0;
    for (int p = 0; p < np; ++p)
        for (int q = 0; q < NP; ++q) {
            const double h = brk[p + 1] - brk[p];
            /* phi = pi - psi: cos, sin of phi from psi (pi - psi would round psi near the lobe) */
            const double psi = brk[p] + 0.5 * h * (pj->px[q] + 1.0), cp = -cos(psi);
            const double wi[3] = {st * cp, st * sin(psi), ct};
            const double fv = 0.5 * h * pj->pw[q] * brdf_value(pj->b, wi, pj->wo);
            double c_prev = 1.0, c_m = cp; /* cos(m phi) by the Chebyshev recurrence */
            pj->c[0] += fv;
            for (int m = 1; m <= pj->lmax; ++m) {
                pj->c[m] += fv * c_m;
                const double c_next = 2.0 * cp * c_m - c_prev;
                c_prev = c_m;
                c_m = c_next;
            }
        }
}

/* F (f_cos) and F' (f) at theta_o: HVL Eq. (16) and its cosine-free variant. */
static void project(projector *pj, double theta_o, double *f_cos, double *f)
{
    const shl_brdf *b = pj->b;
    const int lmax = pj->lmax;
    pj->wo[0] = sin(theta_o);
    pj->wo[1] = 0.0;
    pj->wo[2] = cos(theta_o);
    pj->theta_o = theta_o;
    /* lobe width about the mirror direction in the plane of incidence, its
     * compression across it, and the Smith term's fall-off at the horizon.  GGX:
     * at (theta, pi + d) the half vector tilts by (theta - theta_o)/2 in the
     * plane and d sin(theta) / (2 cos theta_o) across it, so the azimuthal width
     * is (2 alpha + |theta - theta_o|) cos(theta_o) / sin(theta). */
    double w_hor = M_PI;
    pj->w_in = M_PI;
    pj->squeeze = 1.0;
    pj->theta_s = M_PI; /* no cut-off circle */
    if (b->ks > 0.0 && b->model == SHL_BRDF_GGX) {
        pj->w_in = 2.0 * b->alpha;
        pj->squeeze = pj->wo[2];
        w_hor = b->alpha;
    } else if (b->ks > 0.0) {
        pj->w_in = 1.0 / sqrt(b->exponent + 1.0);
        /* innermost panel 10^(-12/(n+1)): what it leaves out is below 1e-12 */
        pj->w_cut = fmin(M_PI, 4.0 * pow(10.0, -12.0 / (b->exponent + 1.0)));
        pj->theta_s = 0.5 * M_PI - theta_o;
    }
    features ft = {0, {0}, {0}, {0}};
    add_feature(&ft, theta_o, pj->w_in, pj->w_in);
    add_feature(&ft, 0.5 * M_PI, w_hor, M_PI);
    /* the cut-off circle enters at theta_s: near it (r . wi)^n ~ (eps + k u^2)^n
     * in the azimuth, eps ~ theta_s - theta, so c_m ~ |theta - theta_s|^(n + 1/2) */
    if (pj->theta_s < M_PI) add_feature(&ft, pj->theta_s, pj->w_cut, pj->w_cut);
    double brk[SHL__MAX_PANELS + 1];
    const int np = shl__graded_breaks(0.0, 0.5 * M_PI, ft.n, ft.pos, ft.below, ft.above, brk);
    for (int k = 0; k < SHL_NCOEFFS(lmax); ++k) f_cos[k] = f[k] = 0.0;
    for (int p = 0; p < np; ++p)
        for (int q = 0; q < NT; ++q) {
            const double h = brk[p + 1] - brk[p];
            const double th = brk[p] + 0.5 * h * (pj->gx[q] + 1.0), st = sin(th), ct = cos(th);
            azimuthal_moments(pj, th);
            shl__sh_eval(lmax, st, 0.0, ct, pj->y);
            const double wt = h * pj->gw[q] * st; /* 2 (phi in [-pi, 0]) x h/2 */
            for (int l = 0; l <= lmax; ++l)
                for (int m = 0; m <= l; ++m) {
                    const int k = l * (l + 1) + m;
                    const double v = wt * pj->y[k] * pj->c[m];
                    f[k] += v;
                    f_cos[k] += ct * v;
                }
        }
}

int shl_brdf_table_create(int lmax, const shl_brdf *brdf, int ntheta, shl_brdf_table **out)
{
    if (!out) return SHL_ENULL;
    *out = NULL; /* on every failure below (the exception in shlight.h) */
    if (!brdf) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const int st = check_brdf(brdf);
    if (st) return st;
    if (ntheta < 2 || ntheta > 1024) return SHL_EDOMAIN;
    shl_brdf_table *t = shl__calloc(1, sizeof *t);
    if (!t) return SHL_ENOMEM;
    t->lmax = lmax;
    t->nc = SHL_NCOEFFS(lmax);
    t->ntheta = ntheta;
    t->data = shl__malloc((size_t)2 * ntheta * t->nc * sizeof *t->data);
    if (!t->data) {
        shl__free(t);
        return SHL_ENOMEM;
    }
    projector pj;
    pj.b = brdf;
    pj.lmax = lmax;
    shl__gauss_legendre(NT, pj.gx, pj.gw);
    shl__gauss_legendre(NP, pj.px, pj.pw);
    for (int j = 0; j < ntheta; ++j) /* HVL Eq. (18): Tab_iso[theta_o] = F at (theta_o, 0) */
        project(&pj, j * (0.5 * M_PI / ntheta), t->data + (size_t)2 * j * t->nc,
                t->data + (size_t)(2 * j + 1) * t->nc);
    *out = t;
    return SHL_OK;
}

void shl_brdf_table_destroy(shl_brdf_table *table)
{
    if (!table) return;
    shl__free(table->data);
    shl__free(table);
}

int shl_brdf_table_lmax(const shl_brdf_table *table) { return table ? table->lmax : SHL_ENULL; }

void shl__brdf_frame(const double n[3], const double wo[3], double frame[9])
{
    double *x = frame, *y = frame + 3, *z = frame + 6;
    for (int k = 0; k < 3; ++k) z[k] = n[k];
    const double c = shl__dot3(wo, z);
    double v[3] = {wo[0] - c * z[0], wo[1] - c * z[1], wo[2] - c * z[2]};
    if (!(shl__dot3(v, v) > 1e-24)) { /* wo parallel to n: any x orthogonal to n */
        const int a = (fabs(z[0]) <= fabs(z[1]) && fabs(z[0]) <= fabs(z[2])) ? 0 : (fabs(z[1]) <= fabs(z[2]) ? 1 : 2);
        const double e[3] = {a == 0, a == 1, a == 2};
        v[0] = e[1] * z[2] - e[2] * z[1];
        v[1] = e[2] * z[0] - e[0] * z[2];
        v[2] = e[0] * z[1] - e[1] * z[0];
    }
    const double len = sqrt(shl__dot3(v, v));
    for (int k = 0; k < 3; ++k) x[k] = v[k] / len;
    y[0] = z[1] * x[2] - z[2] * x[1];
    y[1] = z[2] * x[0] - z[0] * x[2];
    y[2] = z[0] * x[1] - z[1] * x[0];
}

void shl__brdf_table_at(const shl_brdf_table *t, double cos_o, double sin_o, double *f_cos,
                        double *f)
{
    const int nc = t->nc;
    double *outs[2] = {f_cos, f};
    if (!(cos_o > 0.0)) {
        for (int o = 0; o < 2; ++o)
            if (outs[o])
                for (int k = 0; k < nc; ++k) outs[o][k] = 0.0;
        return;
    }
    const double pos = atan2(sin_o, cos_o) / (0.5 * M_PI / t->ntheta);
    int j = (int)pos;
    double frac = pos - j;
    if (j >= t->ntheta - 1) {
        j = t->ntheta - 2;
        frac = 1.0;
    }
    for (int o = 0; o < 2; ++o) {
        if (!outs[o]) continue;
        const double *a = t->data + (size_t)(2 * j + o) * nc, *b = a + 2 * nc;
        for (int k = 0; k < nc; ++k) outs[o][k] = (1.0 - frac) * a[k] + frac * b[k];
    }
}

int shl_brdf_frame(const double n[3], const double wo[3], double frame[9])
{
    if (!n || !wo || !frame) return SHL_ENULL;
    double nu[3], ou[3];
    int st;
    if ((st = shl__unit(n, nu)) || (st = shl__unit(wo, ou))) return st;
    shl__brdf_frame(nu, ou, frame);
    return SHL_OK;
}

int shl_brdf_table_lookup(const shl_brdf_table *table, const double n[3], const double wo[3],
                          double frame[9], double *f_cos, double *f)
{
    if (!table || !n || !wo || !frame) return SHL_ENULL;
    double nu[3], ou[3];
    int st;
    if ((st = shl__unit(n, nu)) || (st = shl__unit(wo, ou))) return st;
    shl__brdf_frame(nu, ou, frame);
    /* theta_o from both components: accurate near normal incidence */
    shl__brdf_table_at(table, shl__dot3(ou, frame + 6), shl__dot3(ou, frame), f_cos, f);
    return SHL_OK;
}
