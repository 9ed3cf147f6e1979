/* Shared helpers for the tests: a deterministic PRNG, random geometry, guards. */
#ifndef SHL_TESTUTIL_H
#define SHL_TESTUTIL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

typedef struct { uint64_t s; } rng_t;

static inline double rng_uniform(rng_t *r) /* [0,1), splitmix64 */
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

static inline double rng_range(rng_t *r, double lo, double hi) { return lo + (hi - lo) * rng_uniform(r); }

static inline void rng_unit_vector(rng_t *r, double v[3])
{
    const double z = rng_range(r, -1.0, 1.0), phi = rng_range(r, 0.0, 2.0 * M_PI);
    const double s = sqrt(1.0 - z * z);
    v[0] = s * cos(phi);
    v[1] = s * sin(phi);
    v[2] = z;
}

/* Legendre P_l(t) by the three-term recurrence. */
static inline double legendre_p(int l, double t)
{
    double p0 = 1.0, p1 = t;
    if (l == 0) return 1.0;
    for (int k = 2; k <= l; ++k) {
        const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

/* Fill buf[0..n) with a guard value and check it is intact. */
#define GUARD_VALUE 1234.5678
static inline void guard_fill(double *buf, int n)
{
    for (int i = 0; i < n; ++i) buf[i] = GUARD_VALUE;
}
static inline int guard_intact(const double *buf, int n)
{
    for (int i = 0; i < n; ++i)
        if (buf[i] != GUARD_VALUE) return 0;
    return 1;
}

/* v rounded to float, through a volatile: GCC 12.2 -O2 turns a short loop of double ->
 * float -> double round trips into copies (tests/fuzz/crashes/gcc12-slp-float-roundtrip.c). */
static inline double round_to_float(double v)
{
    volatile float f = (float)v;
    return f;
}

static inline int all_finite(const double *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* |a - ref| / |ref| in the Euclidean (for a matrix: Frobenius) norm over n entries a[i * stride] */
static inline double rel_norm_err(const double *a, int stride, const long double *ref, int n)
{
    long double e = 0.0L, m = 0.0L;
    for (int i = 0; i < n; ++i) e += (a[i * stride] - ref[i]) * (a[i * stride] - ref[i]), m += ref[i] * ref[i];
    return (double)sqrtl(e / m);
}

#endif
