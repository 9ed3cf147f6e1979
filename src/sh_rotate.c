/* SH rotations: ZH -> SH about any axis (HVL Eq. 15) and the rotation of a
 * whole SH vector by a 3x3 matrix.
 *
 * Band matrices by the recurrences of Ivanic & Ruedenberg (J. Phys. Chem. 100,
 * 1996, Eq. 8.1-8.4 and Table 2, with the 1998 erratum): D_l follows from D_1
 * and D_{l-1} in O(1) per entry, O(lmax^3) in all.  The recurrences are written
 * for real SH without the Condon-Shortley phase, where D_1 is R in (y, z, x)
 * order; our basis differs by the sign (-1)^m, so D_l[m][n] gets (-1)^(m+n). */
#include "sh_basis.h"
#include "sh_rotate.h"
#include <stdlib.h>

static size_t band_offset(int l) { return (size_t)l * (2 * l - 1) * (2 * l + 1) / 3; }

size_t shl__rot_size(int lmax) { return band_offset(lmax + 1); }

/* IR's P^l_i(a, b) from D_1 (r1[3(i+1) + j+1]) and D_{l-1} (prev). */
static double ir_p(const double *r1, const double *prev, int l, int i, int a, int b)
{
    const int lp = l - 1, w = 2 * lp + 1;
    const double *row = prev + (a + lp) * w + lp; /* row[q] = D_{l-1}[a][q] */
    const double *ri = r1 + 3 * (i + 1);
    if (b == l) return ri[2] * row[lp] - ri[0] * row[-lp];
    if (b == -l) return ri[2] * row[-lp] + ri[0] * row[lp];
    return ri[1] * row[b];
}

void shl__rot_build(int lmax, const double rot[9], double *d)
{
    static const int yzx[3] = {1, 2, 0}; /* m = -1, 0, 1 <-> y, z, x */
    double r1[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r1[3 * i + j] = rot[3 * yzx[i] + yzx[j]];
    d[0] = 1.0;
    if (lmax >= 1)
        for (int i = 0; i < 9; ++i) d[1 + i] = r1[i];
    for (int l = 2; l <= lmax; ++l) {
        const double *prev = d + band_offset(l - 1);
        double *cur = d + band_offset(l);
        const int w = 2 * l + 1;
        for (int m = -l; m <= l; ++m) {
            const int am = abs(m), m0 = (m == 0);
            for (int n = -l; n <= l; ++n) {
                const double den = (abs(n) == l) ? 2.0 * l * (2.0 * l - 1.0) : (double)(l + n) * (l - n);
                const double u = sqrt((double)(l + m) * (l - m) / den);
                const double v = 0.5 * sqrt((1.0 + m0) * (l + am - 1.0) * (l + am) / den) * (1 - 2 * m0);
                const double ww = m0 ? 0.0 : -0.5 * sqrt((l - am - 1.0) * (l - am) / den);
                double val = 0.0;
                if (u != 0.0) val += u * ir_p(r1, prev, l, 0, m, n);
                if (m == 0) {
                    val += v * (ir_p(r1, prev, l, 1, 1, n) + ir_p(r1, prev, l, -1, -1, n));
                } else if (m > 0) {
                    const double vv = ir_p(r1, prev, l, 1, m - 1, n) * (m == 1 ? M_SQRT2 : 1.0) -
                                      (m == 1 ? 0.0 : ir_p(r1, prev, l, -1, -m + 1, n));
                    val += v * vv;
                    if (ww != 0.0) val += ww * (ir_p(r1, prev, l, 1, m + 1, n) + ir_p(r1, prev, l, -1, -m - 1, n));
                } else {
                    const double vv = (m == -1 ? 0.0 : ir_p(r1, prev, l, 1, m + 1, n)) +
                                      ir_p(r1, prev, l, -1, -m - 1, n) * (m == -1 ? M_SQRT2 : 1.0);
                    val += v * vv;
                    if (ww != 0.0) val += ww * (ir_p(r1, prev, l, 1, m - 1, n) - ir_p(r1, prev, l, -1, -m + 1, n));
                }
                cur[(m + l) * w + (n + l)] = val;
            }
        }
    }
    for (int l = 1; l <= lmax; ++l) { /* to the Condon-Shortley basis */
        double *cur = d + band_offset(l);
        const int w = 2 * l + 1;
        for (int i = 0; i < w; ++i)
            for (int j = 0; j < w; ++j)
                if ((i + j) & 1) cur[i * w + j] = -cur[i * w + j];
    }
}

void shl__rot_apply(int lmax, const double *d, const double *in, double *out)
{
    double tmp[2 * SHL_LMAX_MAX + 1];
    for (int l = 0; l <= lmax; ++l) {
        const int w = 2 * l + 1;
        const double *dl = d + band_offset(l);
        for (int j = 0; j < w; ++j) tmp[j] = in[l * l + j];
        for (int i = 0; i < w; ++i) {
            double s = 0.0;
            for (int j = 0; j < w; ++j) s += dl[i * w + j] * tmp[j];
            out[l * l + i] = s;
        }
    }
}

int shl_sh_rotate(int lmax, const double rot[9], const double *in, double *out)
{
    if (!rot || !in || !out) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const int nc = SHL_NCOEFFS(lmax);
    if (shl__check_finite(rot, 9) || shl__check_finite(in, nc)) return SHL_ENONFINITE;
    double err = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            err = fmax(err, fabs(shl__dot3(rot + 3 * i, rot + 3 * j) - (i == j)));
    if (!(err <= 1e-6)) return SHL_EDOMAIN;
    const double det = rot[0] * (rot[4] * rot[8] - rot[5] * rot[7]) -
                       rot[1] * (rot[3] * rot[8] - rot[5] * rot[6]) +
                       rot[2] * (rot[3] * rot[7] - rot[4] * rot[6]);
    double *d = shl__malloc(shl__rot_size(lmax) * sizeof *d);
    if (!d) return SHL_ENOMEM;
    double proper[9];
    /* a reflection R = -R', R' proper: f(R^T w) = f(-R'^T w), and Y_l(-w) = (-1)^l Y_l(w) */
    for (int i = 0; i < 9; ++i) proper[i] = det < 0.0 ? -rot[i] : rot[i];
    shl__rot_build(lmax, proper, d);
    shl__rot_apply(lmax, d, in, out);
    if (det < 0.0)
        for (int l = 1; l <= lmax; l += 2)
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) out[k] = -out[k];
    shl__free(d);
    return SHL_OK;
}

int shl_zh_to_sh(int lmax, const double *zh, const double axis[3], double *sh)
{
    if (!zh || !axis || !sh) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (shl__check_finite(zh, lmax + 1)) return SHL_ENONFINITE;
    double u[3];
    const int st = shl__unit(axis, u);
    if (st) return st;
    double f[SHL_LMAX_MAX + 1]; /* zh may alias the start of sh */
    for (int l = 0; l <= lmax; ++l) f[l] = shl__sh_k15_d[l] * zh[l]; /* HVL Eq. (15) */
    shl__sh_eval_w_d(lmax, u, f, sh);
    return SHL_OK;
}

int shl_sh_eval(int lmax, const double *coeffs, const double dir[3], double *value)
{
    if (!coeffs || !dir || !value) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const int nc = SHL_NCOEFFS(lmax);
    if (shl__check_finite(coeffs, nc)) return SHL_ENONFINITE;
    double u[3], y[SHL_NCOEFFS(SHL_LMAX_MAX)];
    const int st = shl__unit(dir, u);
    if (st) return st;
    shl__sh_eval(lmax, u[0], u[1], u[2], y);
    double s = 0.0;
    for (int k = 0; k < nc; ++k) s += coeffs[k] * y[k]; /* HVL Eq. (6) */
    *value = s;
    return SHL_OK;
}
