/* Harness parallel loop: the library's own (shl__parallel_for of src/parallel.h, an internal
 * header: the harness links the static archive, never the shared library), with chunks of at
 * most `grain` items on every path; and progress reports on stderr. */
#ifndef SHL_BENCH_PARFOR_H
#define SHL_BENCH_PARFOR_H

#include "parallel.h"

/* fn processes items [begin, end), end - begin <= grain, as worker `worker`
 * (0 <= worker < nthreads): the library's shl__range_fn. */
typedef shl__range_fn par_fn;

/* Worker count: $SHLIGHT_THREADS if set (1..SHL_MAX_THREADS), else the online CPU count. */
int par_threads(void);

/* Run fn over [0, n) in chunks of `grain` items claimed in order by nthreads
 * workers (the caller is worker 0; nthreads is clamped to 1..SHL_MAX_THREADS).
 * Returns 0, or -1 if a thread could not be created (the loop then ran on the
 * calling thread alone, chunk by chunk). */
int par_for(long n, long grain, int nthreads, par_fn fn, void *arg);

/* A progress line "name: 42%" on stderr, shown only once the task has run
 * for more than a second; par_progress_add is thread-safe. */
typedef struct par_progress par_progress;
par_progress *par_progress_begin(const char *name, long total);
void par_progress_add(par_progress *p, long done);
void par_progress_end(par_progress *p);

#endif
