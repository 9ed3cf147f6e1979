/* Frozen copy of shl_polygon's ZH recurrence and ZH -> SH reconstruction as of
 * issue 16 (commit 01a6269^: one lobe at a time, row-by-row dot products), the
 * baseline of bench_polygon's speed-up ratio.  Benchmark-only. */
#ifndef SHL_BENCH_POLY_BASELINE_H
#define SHL_BENCH_POLY_BASELINE_H

#include "polygon.h"

/* shl_polygon's pipeline with the frozen kernels: the set-up is the library's
 * current shl__poly_geom_init (not frozen), then baseline_poly_zh and
 * baseline_zh_to_sh. */
void baseline_polygon(int lmax, const double x[3], const double *verts, int n, double *coeffs);
void baseline_poly_zh(const shl__poly_geom *g, int lmax, double *zh);
void baseline_zh_to_sh(int lmax, const double *zh, double *coeffs);

#endif
