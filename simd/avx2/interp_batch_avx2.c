/* AVX2+FMA instance of the grid interpolation kernel (simd/interp_batch.h): 8
 * coefficients per vector.  Built with -mavx2 -mfma; called only when dispatch.c has
 * checked the CPU and OS. */
#include "helper.h"
#include "../interp_batch.h"
