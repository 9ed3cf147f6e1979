/* Scalar instance of the batch kernel (simd/poly_batch.h): one lane, plain C. */
#include "helper.h"
#include "../poly_batch.h"
