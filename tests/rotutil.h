/* Random rotations for the tests (unit quaternion -> row-major 3x3 matrix). */
#ifndef SHL_TEST_ROTUTIL_H
#define SHL_TEST_ROTUTIL_H

#include "testutil.h"

static inline void random_rotation(rng_t *r, double m[9])
{
    double q[4], n = 0.0;
    for (int i = 0; i < 4; ++i) {
        q[i] = rng_range(r, -1.0, 1.0);
        n += q[i] * q[i];
    }
    n = sqrt(n);
    const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    const double v[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                         2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(m, v, sizeof v);
}

static inline void mat_mul3(const double a[9], const double b[9], double c[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

static inline void mat_vec3(const double a[9], const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i) out[i] = a[3 * i] * v[0] + a[3 * i + 1] * v[1] + a[3 * i + 2] * v[2];
}

#endif
