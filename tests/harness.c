/* Test runner: runs every registered test, or those selected by a filter, a
 * comma-separated list of substrings: a test runs if its name contains one of
 * the plain parts (every test when there are none) and none of the parts
 * written -substring.  Prints one line per test with its time, and ends with
 * "N passed, M failed".  Usage: run_tests [FILTER] [--log FILE]: --log also
 * writes those lines to FILE (tools/check_readme_figures.py reads it). */
#include "harness.h"
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_TESTS 1024

static struct { const char *name; shl_test_fn fn; } tests[MAX_TESTS];
static int ntests;
static int current_failures;
static char notes[2048];

void harness_register(const char *name, shl_test_fn fn)
{
    if (ntests < MAX_TESTS) {
        tests[ntests].name = name;
        tests[ntests].fn = fn;
        ++ntests;
    }
}

void harness_fail(const char *file, int line, const char *fmt, ...)
{
    if (++current_failures > 10) return; /* keep the log readable */
    va_list ap;
    va_start(ap, fmt);
    fprintf(stdout, "    %s:%d: ", file, line);
    vfprintf(stdout, fmt, ap);
    fputc('\n', stdout);
    va_end(ap);
}

void harness_note(const char *fmt, ...)
{
    size_t len = strlen(notes);
    if (len + 4 >= sizeof notes) return;
    if (len) { strcat(notes, "; "); len += 2; }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(notes + len, sizeof notes - len, fmt, ap);
    va_end(ap);
}

int harness_failed_current(void) { return current_failures; }

static int matches(const char *name, const char *filter)
{
    if (!filter) return 1;
    int included = 0, any_plain = 0;
    const char *p = filter;
    while (*p) {
        const size_t len = strcspn(p, ",");
        char part[128];
        if (len > 0 && len < sizeof part) {
            memcpy(part, p, len);
            part[len] = '\0';
            if (part[0] == '-') {
                if (part[1] && strstr(name, part + 1)) return 0;
            } else {
                any_plain = 1;
                included |= strstr(name, part) != NULL;
            }
        }
        p += len + (p[len] == ',');
    }
    return included || !any_plain;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

static int by_name(const void *a, const void *b)
{
    const char *na = *(const char *const *)a, *nb = *(const char *const *)b;
    return strcmp(na, nb);
}

static void report(FILE *log, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    if (log) {
        va_start(ap, fmt);
        vfprintf(log, fmt, ap);
        va_end(ap);
    }
}

int main(int argc, char **argv)
{
    const char *filter = NULL, *log_path = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--log") == 0 && i + 1 < argc)
            log_path = argv[++i];
        else
            filter = argv[i];
    }
    FILE *log = log_path ? fopen(log_path, "w") : NULL;
    if (log_path && !log) {
        fprintf(stderr, "run_tests: cannot write %s\n", log_path);
        return 2;
    }
    int passed = 0, failed = 0;
    qsort(tests, (size_t)ntests, sizeof tests[0], by_name);
    for (int i = 0; i < ntests; ++i) {
        if (!matches(tests[i].name, filter)) continue;
        current_failures = 0;
        notes[0] = '\0';
        const double t0 = now_ms();
        tests[i].fn();
        const double ms = now_ms() - t0;
        if (current_failures == 0) {
            ++passed;
            report(log, "ok   %s (%.0f ms)%s%s\n", tests[i].name, ms, notes[0] ? "  -- " : "", notes);
        } else {
            ++failed;
            report(log, "FAIL %s (%d failed checks, %.0f ms)%s%s\n", tests[i].name, current_failures, ms,
                   notes[0] ? "  -- " : "", notes);
        }
        fflush(stdout);
    }
    report(log, "%d passed, %d failed\n", passed, failed);
    if (log && fclose(log) != 0) return 2;
    return failed ? 1 : 0;
}
