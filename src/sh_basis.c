/* Real spherical harmonics with the Condon-Shortley phase (index l*(l+1)+m).
 *
 * Normalized associated Legendre values N_l^m(z) = K_lm P_l^m(z) / sin^m(theta)
 * are built by the standard three-term recurrences with the normalization
 * folded in (no factorials, no overflow at any supported lmax); the azimuthal
 * factors sin^m(theta) cos(m phi), sin^m(theta) sin(m phi) are the real and
 * imaginary parts of (x + i y)^m, so no trigonometric call is needed. */
#include "internal.h"
#include <math.h>

void shl__sh_eval(int lmax, double x, double y, double z, double *out)
{
    const double inv_4pi = 0.25 / M_PI;
    double nmm = sqrt(inv_4pi);          /* N_m^m */
    double cm = 1.0, sm = 0.0;           /* Re, Im of (x+iy)^m */
    for (int m = 0; m <= lmax; ++m) {
        if (m > 0) {
            /* N_m^m = -sqrt((2m+1)/(2m)) N_{m-1}^{m-1} (Condon-Shortley sign) */
            nmm *= -sqrt((2.0 * m + 1.0) / (2.0 * m));
            const double c = cm * x - sm * y;
            sm = cm * y + sm * x;
            cm = c;
        }
        const double scale_c = (m == 0) ? 1.0 : M_SQRT2 * cm;
        const double scale_s = M_SQRT2 * sm;
        double p2 = 0.0, p1 = nmm;       /* N_{l-2}^m, N_{l-1}^m */
        for (int l = m; l <= lmax; ++l) {
            double p;
            if (l == m) {
                p = nmm;
            } else if (l == m + 1) {
                p = sqrt(2.0 * m + 3.0) * z * nmm;
            } else {
                const double l2 = (double)l * l, m2 = (double)m * m;
                const double a = sqrt((4.0 * l2 - 1.0) / (l2 - m2));
                const double b = sqrt(((l - 1.0) * (l - 1.0) - m2) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
                p = a * (z * p1 - b * p2);
            }
            if (l > m) { p2 = p1; p1 = p; }
            const int base = l * (l + 1);
            out[base + m] = p * scale_c;
            if (m > 0) out[base - m] = p * scale_s;
        }
    }
}
