/* Real spherical harmonics with the Condon-Shortley phase (index l*(l+1)+m),
 * values and surface gradients, in double and float (kernels in sh_basis_impl.h).
 *
 * Normalized associated Legendre values are built by the standard three-term
 * recurrences with the normalization folded in (no factorials, no overflow at
 * any supported lmax) and every factor read from the generated tables of
 * sh_tables.c; the azimuthal factors sin^m(theta) cos(m phi), sin^m(theta)
 * sin(m phi) are the real and imaginary parts of (x + i y)^m, so no
 * trigonometric call, square root or division is needed. */
#include "sh_basis.h"

#define SHL_REAL_IMPL "sh_basis_impl.h"
#include "real_instances.h"

void shl__sh_eval(int lmax, double x, double y, double z, double *out)
{
    const double u[3] = {x, y, z};
    shl__sh_eval_w_d(lmax, u, NULL, out);
}

/* ---- public entry points --------------------------------------------- */

int shl_eval_basis(int lmax, const double dir[3], double *y)
{
    if (!dir || !y) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    double u[3];
    const int st = shl__unit(dir, u);
    if (st) return st;
    shl__sh_eval(lmax, u[0], u[1], u[2], y);
    return SHL_OK;
}

int shl_eval_basis_f(int lmax, const float dir[3], float *y)
{
    if (!dir || !y) return SHL_ENULL;
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return SHL_ELMAX;
    const double d[3] = {dir[0], dir[1], dir[2]};
    double u[3], yd[SHL_NCOEFFS(SHL_LMAX_MAX)];
    const int st = shl__unit(d, u);
    if (st) return st;
    shl__sh_eval(lmax, u[0], u[1], u[2], yd);
    for (int k = 0; k < SHL_NCOEFFS(lmax); ++k) y[k] = (float)yd[k];
    return SHL_OK;
}
