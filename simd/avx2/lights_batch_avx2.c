/* AVX2+FMA instance of the light-set accumulation (simd/lights_batch.h): 8 floats per
 * vector.  Built with -mavx2 -mfma; called only when dispatch.c has checked the CPU and OS. */
#include "helper.h"
#include "../lights_batch.h"
