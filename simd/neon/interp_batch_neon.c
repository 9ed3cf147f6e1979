/* AArch64 NEON instance of the grid interpolation kernel (simd/interp_batch.h): 4
 * coefficients per vector. */
#include "helper.h"
#include "../interp_batch.h"
