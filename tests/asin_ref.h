/* Independent long-double reference for asin of a double, shared by tests/test_hvl.c
 * and tests/fuzz/fuzz_hvl.c (the error analysis is in test_hvl.c): the Taylor series
 * sum_n binom(2n, n) / (4^n (2n + 1)) x^(2n+1) for |x| <= 1/2 (term ratio < 1/4, 40
 * terms: 4^-40 ~ 1e-24 relative), pi/2 - 2 asin(sqrt((1 - |c|) / 2)) above. */
#ifndef SHL_TEST_ASIN_REF_H
#define SHL_TEST_ASIN_REF_H

#include <math.h>

static inline long double asin_series(long double x)
{
    long double term = x, sum = x;
    const long double x2 = x * x;
    for (int n = 1; n <= 40; ++n) {
        term *= x2 * (2.0L * n - 1.0L) * (2.0L * n - 1.0L) / ((2.0L * n) * (2.0L * n + 1.0L));
        sum += term;
    }
    return sum;
}

static inline long double asin_ref(double c)
{
    const long double ac = fabsl((long double)c);
    if (ac <= 0.5L) return asin_series(c);
    const long double r = 1.570796326794896619231321691639751442L - 2.0L * asin_series(sqrtl((1.0L - ac) / 2.0L));
    return c < 0.0 ? -r : r;
}

#endif
