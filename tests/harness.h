/* Minimal test harness: SHL_TEST(name) registers a test; CHECK* record
 * failures with the failing values printed as hex floats (%a) for replay. */
#ifndef SHL_TEST_HARNESS_H
#define SHL_TEST_HARNESS_H

#include <stdio.h>

typedef void (*shl_test_fn)(void);
void harness_register(const char *name, shl_test_fn fn);
void harness_fail(const char *file, int line, const char *fmt, ...);
/* Record a measured figure for the current test ("name: value"), printed on its result line. */
void harness_note(const char *fmt, ...);
int harness_failed_current(void);

#define SHL_TEST(name)                                                        \
    static void name(void);                                                   \
    __attribute__((constructor)) static void name##_register(void)            \
    {                                                                         \
        harness_register(#name, name);                                        \
    }                                                                         \
    static void name(void)

#define CHECK(cond)                                                           \
    do {                                                                      \
        if (!(cond)) harness_fail(__FILE__, __LINE__, "%s", #cond);          \
    } while (0)

/* |got - want| <= tol, printed in decimal and hex on failure. */
#define CHECK_NEAR(got, want, tol)                                            \
    do {                                                                      \
        const double g_ = (got), w_ = (want), t_ = (tol);                     \
        if (!(fabs(g_ - w_) <= t_))                                           \
            harness_fail(__FILE__, __LINE__,                                  \
                         "%s = %.17g (%a), want %.17g (%a), |diff| %.3g > tol %.3g", \
                         #got, g_, g_, w_, w_, fabs(g_ - w_), t_);            \
    } while (0)

#endif
