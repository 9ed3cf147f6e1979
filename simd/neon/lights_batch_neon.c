/* AArch64 NEON instance of the light-set accumulation (simd/lights_batch.h): 4 floats per vector. */
#include "helper.h"
#include "../lights_batch.h"
