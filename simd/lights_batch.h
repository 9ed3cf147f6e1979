/* Light-set accumulation (src/lights_batch.c, Wu 2020 Alg. 1 line 7: the
 * lights add linearly): y[k] += s x[k] over a point's row of one light's
 * unit-radiance results, x and y distinct.  Vectorized along the row; written
 * once with the verbs of <isa>/helper.h and compiled once per ISA of
 * simd/isa_list.h (Makefile).  Every point's row starts at k = 0, so a
 * point's result does not depend on the batch it is in. */
#include "kernel_api.h"

#define VL SHL_VLEN
#define ISA(name) SHL_ISA_SUFFIX(name)

void ISA(shl__accumulate)(size_t n, float s, const float *x, float *y)
{
    const vf vs = vf_set1(s);
    size_t k = 0;
    for (; k + VL <= n; k += VL) vf_store(y + k, vf_fma(vs, vf_load(x + k), vf_load(y + k)));
    for (; k < n; ++k) y[k] += s * x[k];
}
