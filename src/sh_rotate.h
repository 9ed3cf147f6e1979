/* Internal declarations of SH rotation (sh_rotate.c). */
#ifndef SHL_SH_ROTATE_H
#define SHL_SH_ROTATE_H

#include "internal.h"

/* Number of doubles holding the band matrices of bands 0..lmax. */
size_t shl__rot_size(int lmax);
/* Band matrices D_l (band l at offset l(2l-1)(2l+1)/3, row-major (2l+1)^2) of the
 * proper rotation R (row-major): the coefficients of f(R^T w) are D_l f_l. */
void shl__rot_build(int lmax, const double rot[9], double *d);
/* out_l = D_l in_l for every band; out may equal in. */
void shl__rot_apply(int lmax, const double *d, const double *in, double *out);

#endif
