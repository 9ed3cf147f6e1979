/* AVX2+FMA instance of the batch kernel (simd/poly_batch.h): 8 lanes.  The only
 * object built with -mavx2 -mfma; called only when dispatch.c has checked the CPU and OS. */
#include "helper.h"
#include "../poly_batch.h"
