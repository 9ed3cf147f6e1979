/* Internal declarations of the quadrature rules (quad.c). */
#ifndef SHL_QUAD_H
#define SHL_QUAD_H

#include "internal.h"

/* n-point Gauss-Legendre rule on [-1, 1] (Newton on P_n). */
void shl__gauss_legendre(int n, double *x, double *w);
/* The n-point rule (glx, glw from shl__gauss_legendre) mapped to [a, b]. */
void shl__gl_panel(int n, const double *glx, const double *glw, double a, double b, double *x,
                   double *w);
/* Breakpoints lo = b_0 < ... < b_n = hi graded towards feature points pos[f]
 * (lobe peaks, kinks, cut-offs): near a feature the panel width is about
 * max(w/4, distance to it), so it halves on approach (w = w_below[f]) and
 * doubles away (w = w_above[f]); at most pi/8 elsewhere; every feature inside
 * (lo, hi) is a breakpoint.  Gauss-Legendre on such panels converges
 * geometrically for lobes of width ~w and for algebraic end-point behaviour.
 * Returns n <= SHL__MAX_PANELS; brk has n + 1 entries. */
#define SHL__MAX_PANELS 128
int shl__graded_breaks(double lo, double hi, int nf, const double *pos, const double *w_below,
                       const double *w_above, double *brk);

#endif
