/* Baseline for Wang 2018 Table 2 ("Monomial" column): ZH integrals from the
 * monomial moments int_Q (w.d)^k dw of Snyder 1996 / Arvo 1995, combined with
 * the Legendre coefficients.  Benchmark-only; same output layout as shl__poly_zh_d. */
#ifndef SHL_BENCH_MONOMIAL_H
#define SHL_BENCH_MONOMIAL_H

#include "polygon.h"

void monomial_poly_zh(const shl__poly_geom *g, int lmax, double *zh);

#endif
