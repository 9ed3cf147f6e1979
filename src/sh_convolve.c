/* Convolution of SH lighting with circularly symmetric kernels (full SH, O(n^2),
 * and ZH x ZH, O(n): HVL Sec. 6.3 / App. B), and the ZH of three kernels. */
#include "quad.h"

static double band_k(int l) { return sqrt((2.0 * l + 1.0) / (4.0 * M_PI)); } /* K_l */

int shl_sh_convolve(int lmax, const double *sh, const double *kernel_zh, double *out)
{
    if (!sh || !kernel_zh || !out) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (shl__check_finite(sh, SHL_NCOEFFS(lmax)) || shl__check_finite(kernel_zh, lmax + 1))
        return SHL_ENONFINITE;
    for (int l = 0; l <= lmax; ++l) {
        /* Funk-Hecke: int Y_lm(w) k(w . n) dw = sqrt(4 pi/(2l+1)) k_l Y_lm(n) */
        const double f = sqrt(4.0 * M_PI / (2.0 * l + 1.0)) * kernel_zh[l];
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) out[k] = f * sh[k];
    }
    return SHL_OK;
}

int shl_zh_convolve(int lmax, const double *zh, const double *kernel_zh, double cos_angle,
                    double *value)
{
    if (!zh || !kernel_zh || !value) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (shl__check_finite(zh, lmax + 1) || shl__check_finite(kernel_zh, lmax + 1) ||
        !isfinite(cos_angle))
        return SHL_ENONFINITE;
    if (fabs(cos_angle) > 1.0) return SHL_EDOMAIN;
    /* HVL Sec. 6.3: both factors are ZH, so the SH dot product collapses by the
     * addition theorem, sum_m Y_lm(u) Y_lm(n) = (2l+1)/(4 pi) P_l(u . n):
     * sum_l (4 pi/(2l+1)) zh_l k_l sum_m Y_lm(u) Y_lm(n) = sum_l zh_l k_l P_l(u . n) */
    double p_prev = 1.0, p = cos_angle, s = zh[0] * kernel_zh[0];
    for (int l = 1; l <= lmax; ++l) {
        s += zh[l] * kernel_zh[l] * p;
        const double p_next = ((2.0 * l + 1.0) * cos_angle * p - l * p_prev) / (l + 1.0);
        p_prev = p;
        p = p_next;
    }
    *value = s;
    return SHL_OK;
}

/* zh_l = scale K_l int_0^1 t^n P_l(t) dt by the exact ratio recurrence
 * I_0 = 1/(n+1), I_1 = 1/(n+2), I_{l+2} = I_l (n - l) / (n + l + 3). */
static void power_lobe(int lmax, double n, double scale, double *zh)
{
    double i_even = 1.0 / (n + 1.0), i_odd = 1.0 / (n + 2.0);
    for (int l = 0; l <= lmax; ++l) {
        zh[l] = scale * band_k(l) * ((l & 1) ? i_odd : i_even);
        if (l & 1)
            i_odd *= (n - l) / (n + l + 3.0);
        else
            i_even *= (n - l) / (n + l + 3.0);
    }
}

int shl_zh_clamped_cosine(int lmax, double *zh)
{
    if (!zh) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    power_lobe(lmax, 1.0, 2.0 * M_PI, zh); /* zh_l = 2 pi K_l int_0^1 t P_l(t) dt */
    return SHL_OK;
}

int shl_zh_phong(int lmax, double exponent, double *zh)
{
    if (!zh) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (!isfinite(exponent)) return SHL_ENONFINITE;
    if (exponent < 0.0 || exponent > 1e6) return SHL_EDOMAIN;
    power_lobe(lmax, exponent, exponent + 1.0, zh); /* 2 pi (n+1)/(2 pi) K_l I_l */
    return SHL_OK;
}

int shl_zh_ggx(int lmax, double alpha, double *zh)
{
    if (!zh) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (!isfinite(alpha)) return SHL_ENONFINITE;
    if (alpha < 1e-3 || alpha > 1.0) return SHL_EDOMAIN;
    enum { NG = 24 };
    double glx[NG], glw[NG], brk[SHL__MAX_PANELS + 1], acc[SHL_LMAX_MAX + 1] = {0};
    shl__gauss_legendre(NG, glx, glw);
    const double peak = 0.0; /* in beta, the angle from the axis; the lobe is ~2 alpha wide */
    const int np = shl__graded_breaks(0.0, M_PI, 1, &peak, &alpha, &alpha, brk);
    const double a2 = alpha * alpha;
    for (int p = 0; p < np; ++p) {
        double xs[NG], ws[NG];
        shl__gl_panel(NG, glx, glw, brk[p], brk[p + 1], xs, ws);
        for (int i = 0; i < NG; ++i) {
            const double t = cos(xs[i]), ch = cos(0.5 * xs[i]), sh = sin(0.5 * xs[i]);
            const double den = sh * sh + a2 * ch * ch; /* = cos^2 (a2 - 1) + 1 without cancellation */
            const double k = a2 / (M_PI * den * den) / 4.0; /* D(theta_h) / 4, theta_h = beta / 2 */
            const double f = 2.0 * M_PI * ws[i] * sin(xs[i]) * k;
            double p_prev = 1.0, pl = t;
            acc[0] += f;
            for (int l = 1; l <= lmax; ++l) {
                acc[l] += f * pl;
                const double p_next = ((2.0 * l + 1.0) * t * pl - l * p_prev) / (l + 1.0);
                p_prev = pl;
                pl = p_next;
            }
        }
    }
    for (int l = 0; l <= lmax; ++l) zh[l] = band_k(l) * acc[l];
    return SHL_OK;
}
