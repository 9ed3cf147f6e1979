/* Harness parallel loop on pthreads, and progress reports on stderr. */
#ifndef SHL_BENCH_PARFOR_H
#define SHL_BENCH_PARFOR_H

/* fn processes items [begin, end) as worker `worker` (0 <= worker < nthreads). */
typedef void (*par_fn)(void *arg, long begin, long end, int worker);

/* Worker count: $SHLIGHT_THREADS if set (1..256), else the online CPU count. */
int par_threads(void);

/* Run fn over [0, n) in chunks of `grain` items claimed in order by nthreads
 * workers (the caller is worker 0).  Returns 0, or -1 if no thread could be
 * created (the loop then ran on the calling thread alone). */
int par_for(long n, long grain, int nthreads, par_fn fn, void *arg);

/* A progress line "name: 42%" on stderr, shown only once the task has run
 * for more than a second; par_progress_add is thread-safe. */
typedef struct par_progress par_progress;
par_progress *par_progress_begin(const char *name, long total);
void par_progress_add(par_progress *p, long done);
void par_progress_end(par_progress *p);

#endif
