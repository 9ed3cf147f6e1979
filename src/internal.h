/* Internal declarations shared by the library's translation units (prefix shl__). */
#ifndef SHL_INTERNAL_H
#define SHL_INTERNAL_H

#include "shlight.h"
#include <stddef.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT2
#define M_SQRT2 1.41421356237309504880
#endif

typedef struct shl__isa shl__isa; /* batch kernels of one instruction set (simd/batch.h) */

struct shl_ctx {
    int lmax;
    int nc; /* SHL_NCOEFFS(lmax) */
    const shl__isa *isa; /* chosen once at creation (dispatch.c) */
};

/* The batch kernels for this CPU, or those forced by SHLIGHT_ISA (dispatch.c). */
const shl__isa *shl__isa_select(void);

/* Allocation hooks: every library allocation goes through these so that
 * tests can inject failures (tests/alloc_hook.c); not part of the public API. */
void *shl__malloc(size_t size);
void *shl__calloc(size_t count, size_t size);
void shl__free(void *ptr);

/* Y_lm at unit direction (x,y,z) for l <= lmax into y[(lmax+1)^2] (sh_basis.c). */
void shl__sh_eval(int lmax, double x, double y, double z, double *out);

/* Argument checks shared by the API entry points (api.c). */
int shl__check_finite(const double *v, int count);
int shl__check_finite_f(const float *v, int count);

#endif
