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
 * one worker: no thread is involved).  Workers 1.. are the process-wide pool's
 * parked threads, the missing ones created before any work starts: if a
 * creation fails, SHL_ETHREAD (fn never ran; the threads created stay parked).
 * While a call on another thread, or one from inside fn, owns the pool, the
 * call runs on its calling thread alone (worker 0). */
int shl__parallel_for(long n, long grain, int nthreads, shl__range_fn fn, void *arg);

/* shl__parallel_for with chunks that shrink as the work runs out: about 1/(4
 * workers) of the items left, a multiple of grain and at least grain (the
 * last may be shorter), for callers whose results do not depend on the chunks
 * (grid interpolation): few claims, and the workers finish within about one
 * grain of each other. */
int shl__parallel_for_guided(long n, long grain, int nthreads, shl__range_fn fn, void *arg);

/* Work on items [begin, end) with the worker's own scratch ws (NULL if none). */
typedef void (*shl__ws_range_fn)(void *arg, void *ws, long begin, long end);

/* shl__parallel_for on shl__parallel_workers(n, grain, nthreads) workers, each
 * with its own ws_bytes of scratch (one allocation, freed on return; none if
 * ws_bytes is 0).  SHL_ENOMEM or SHL_ETHREAD: fn never ran. */
int shl__parallel_for_ws(long n, long grain, int nthreads, size_t ws_bytes, shl__ws_range_fn fn, void *arg);

/* Points per block of the single-light batch entry points (batch.c, sphere_batch.c):
 * a multiple of every vector length, so that blocks split no vector. */
enum { SHL__BATCH_BLOCK = 256 };

/* One light at npts points: outputs of point p at coeffs + nc p and grad + 3 nc p
 * (grad may be NULL); work: the work_bytes of shl__batch_run. */
typedef void (*shl__batch_eval_fn)(const shl_ctx *ctx, const void *light, int npts, const float *pts, float *coeffs,
                                   float *grad, void *work);

/* src/batch.c: the threaded part of a single-light batch entry point (arguments
 * checked, npts > 0): eval over blocks of SHL__BATCH_BLOCK points (the last may
 * be shorter, the same blocks for every thread count) on up to nthreads workers,
 * each with work_bytes of workspace.  SHL_ENOMEM or SHL_ETHREAD: nothing written. */
int shl__batch_run(const shl_ctx *ctx, shl__batch_eval_fn eval, const void *light, size_t work_bytes, int npts,
                   const float *pts, float *coeffs, float *grad, int nthreads);

/* Stride of per-worker scratch slices of `bytes` in one allocation (64-byte multiples). */
static inline size_t shl__ws_stride(size_t bytes) { return (bytes + 63) / 64 * 64; }

/* Argument check of the threaded entry points: 1 <= nthreads <= SHL_MAX_THREADS. */
static inline int shl__check_threads(int nthreads) { return nthreads < 1 || nthreads > SHL_MAX_THREADS; }

#endif
