/* Scalar instance of the sphere batch kernel (simd/sphere_batch.h): one lane, plain C. */
#include "helper.h"
#include "../sphere_batch.h"
