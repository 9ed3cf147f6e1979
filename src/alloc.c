/* Allocation wrappers.  Tests build the library with SHL_ALLOC_HOOKS defined
 * and set shl__alloc_fail_after to make the N-th allocation fail, so every
 * allocation-failure path can be exercised (not part of the public API). */
#include "internal.h"
#include <stdlib.h>

#ifdef SHL_ALLOC_HOOKS
long shl__alloc_fail_after = -1; /* < 0: never fail */
static int alloc_should_fail(void) { return shl__hook_fails(&shl__alloc_fail_after); }
#else
static int alloc_should_fail(void) { return 0; }
#endif

void *shl__malloc(size_t size)
{
    return alloc_should_fail() ? NULL : malloc(size);
}

void *shl__calloc(size_t count, size_t size)
{
    return alloc_should_fail() ? NULL : calloc(count, size);
}

void shl__free(void *ptr) { free(ptr); }
