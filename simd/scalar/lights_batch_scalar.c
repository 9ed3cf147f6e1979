/* Scalar instance of the light-set accumulation (simd/lights_batch.h): one lane, plain C. */
#include "helper.h"
#include "../lights_batch.h"
