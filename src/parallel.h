/* One parallel loop on pthreads (grid fill, batch interpolation, the batch entry points). */
#ifndef SHL_PARALLEL_H
#define SHL_PARALLEL_H

#include "internal.h"

/* Work on items [begin, end) as worker `worker` (0 <= worker < worker count). */
typedef void (*shl__range_fn)(void *arg, int worker, long begin, long end);

/* Workers shl__parallel_for will use: min(nthreads, number of chunks), >= 1. */
int shl__parallel_workers(long n, long grain, int nthreads);

/* Run fn over [0, n) in chunks of `grain` items, claimed in order by the
 * workers (worker 0 is the calling thread; 1 <= nthreads <= SHL_MAX_THREADS;
 * one worker: no thread is created).  Every thread is created before any
 * work starts: if a creation fails, the started threads exit without calling
 * fn, are joined, and SHL_ETHREAD is returned (fn never ran). */
int shl__parallel_for(long n, long grain, int nthreads, shl__range_fn fn, void *arg);

/* Points per block of the single-light batch entry points (batch.c, sphere_batch.c):
 * a multiple of every vector length, so that blocks split no vector. */
enum { SHL__BATCH_BLOCK = 256 };

/* Stride of per-worker scratch slices of `bytes` in one allocation (64-byte multiples). */
static inline size_t shl__ws_stride(size_t bytes) { return (bytes + 63) / 64 * 64; }

/* Argument check of the threaded entry points: 1 <= nthreads <= SHL_MAX_THREADS. */
static inline int shl__check_threads(int nthreads) { return nthreads < 1 || nthreads > SHL_MAX_THREADS; }

#endif
