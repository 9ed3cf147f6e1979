/* AArch64 NEON instance of the batch kernel (simd/poly_batch.h): 4 lanes (baseline ISA). */
#include "helper.h"
#include "../poly_batch.h"
