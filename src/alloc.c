/* Allocation wrappers.  Tests build the library with SHL_ALLOC_HOOKS defined
 * and set shl__alloc_fail_after to make the N-th allocation fail, so every
 * allocation-failure path can be exercised (not part of the public API). */
#if defined(__linux__) && !defined(_DEFAULT_SOURCE)
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE (the build is -D_XOPEN_SOURCE=700) */
#endif
#include "internal.h"
#include <stdlib.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

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

void *shl__calloc_large(size_t count, size_t size)
{
    if (size && count > SIZE_MAX / size) return NULL;
    const size_t bytes = count * size, page = SHL__HUGE_PAGE;
    if (bytes < SHL__LARGE_ARRAY || bytes > SIZE_MAX - page) return shl__calloc(count, size);
    if (alloc_should_fail()) return NULL;
    const size_t padded = (bytes + page - 1) / page * page; /* C11 aligned_alloc: a multiple of the alignment */
    void *p = aligned_alloc(page, padded);
    if (!p) return NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    /* Before the first touch, so the faults below can map whole 2 MiB pages
     * (THP "madvise" mode); only advice: its failure changes nothing. */
    (void)madvise(p, padded, MADV_HUGEPAGE);
#endif
    memset(p, 0, bytes);
    return p;
}

void *shl__realloc(void *ptr, size_t size)
{
    return alloc_should_fail() ? NULL : realloc(ptr, size);
}

void shl__free(void *ptr) { free(ptr); }
