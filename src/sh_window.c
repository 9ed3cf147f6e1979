/* SH windowing against ringing: per-band factors h_l (Hanning, Lanczos sigma,
 * Laplacian penalty of Sloan 2008, spherical de la Vallee Poussin), formulas in
 * include/shlight.h. */
#include "internal.h"

int shl_sh_window_factors(int lmax, int window, double param, double *h)
{
    if (!h) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    if (!isfinite(param)) return SHL_ENONFINITE;
    if (window == SHL_WINDOW_HANNING || window == SHL_WINDOW_LANCZOS) {
        if (!(param > 0.0)) return SHL_EDOMAIN;
        for (int l = 0; l <= lmax; ++l) {
            const double t = M_PI * l / param; /* in [0, pi) for l < w */
            if (l == 0)
                h[l] = 1.0;
            else if (l >= param)
                h[l] = 0.0;
            else
                h[l] = window == SHL_WINDOW_HANNING ? 0.5 * (1.0 + cos(t)) : sin(t) / t;
        }
        return SHL_OK;
    }
    if (window == SHL_WINDOW_LAPLACIAN) {
        if (!(param >= 0.0)) return SHL_EDOMAIN;
        for (int l = 0; l <= lmax; ++l) {
            const double ev = (double)l * (l + 1.0); /* -eigenvalue of the Laplacian on band l */
            h[l] = 1.0 / (1.0 + param * ev * ev);
        }
        return SHL_OK;
    }
    if (window == SHL_WINDOW_POUSSIN) {
        if (!(param >= 0.0 && param <= SHL_LMAX_MAX) || param != floor(param)) return SHL_EDOMAIN;
        /* Funk-Hecke coefficients of ((1 + t)/2)^n over those of band 0:
         * h_l = n! (n+1)! / ((n-l)! (n+l+1)!), so h_{l+1} = h_l (n - l) / (n + l + 2) (0 beyond n) */
        double f = 1.0;
        for (int l = 0; l <= lmax; ++l) {
            h[l] = f;
            f = l < param ? f * (param - l) / (param + l + 2.0) : 0.0;
        }
        return SHL_OK;
    }
    return SHL_EDOMAIN;
}

int shl_sh_window(int lmax, int window, double param, double *coeffs)
{
    if (!coeffs) return SHL_ENULL;
    double h[SHL_LMAX_MAX + 1];
    int st = shl_sh_window_factors(lmax, window, param, h);
    if (!st && shl__check_finite(coeffs, SHL_NCOEFFS(lmax))) st = SHL_ENONFINITE;
    if (st) return st;
    for (int l = 0; l <= lmax; ++l)
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) coeffs[k] *= h[l];
    return SHL_OK;
}
