/* AArch64 NEON instance of the sphere batch kernel (simd/sphere_batch.h): 4 lanes. */
#include "helper.h"
#include "../sphere_batch.h"
