/* AVX2+FMA instance of the sphere batch kernel (simd/sphere_batch.h): 8 lanes.  Built
 * with -mavx2 -mfma; called only when dispatch.c has checked the CPU and OS. */
#include "helper.h"
#include "../sphere_batch.h"
