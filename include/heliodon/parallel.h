/* heliodon — one persistent thread pool and a parallel-for over a fixed
 * grid of work units on it.
 *
 * hd_parallel_for() cuts [0,n) into chunks of `chunk` items (the last may be
 * shorter) and runs fn on them from nthreads threads; chunk boundaries do
 * not depend on the thread count, so a computation that seeds its random
 * stream from the chunk index is deterministic.  The threads are the
 * process's pool's (started once, kept between calls); a call made while
 * the pool is busy (from another thread, or nested inside a chunk) runs on
 * threads of its own. */
#ifndef HELIODON_PARALLEL_H
#define HELIODON_PARALLEL_H

#include <stddef.h>
#include "common.h"

/* Called for each chunk: items [begin,end), chunk index, worker index
 * (0..nthreads-1). Returns HD_OK or an error (the first error stops the
 * remaining chunks and is returned, with its message, by hd_parallel_for). */
typedef hd_status (*hd_chunk_fn)(void *ctx, size_t begin, size_t end,
                                 size_t chunk_index, int worker);

hd_status hd_parallel_for(size_t n, size_t chunk, int nthreads,
                          hd_chunk_fn fn, void *ctx);

/* A pool of its own, for a caller that runs many loops from one thread
 * while other threads may use the shared one (the photon-map build):
 * nthreads - 1 workers (<= 0: all processors; fewer if threads cannot be
 * made: the loops still run); the caller is worker 0. */
typedef struct hd_pool hd_pool;
hd_pool *hd_pool_new(int nthreads);
void hd_pool_free(hd_pool *p);
int hd_pool_threads(const hd_pool *p);
/* hd_parallel_for on p's threads (all of them). */
hd_status hd_pool_for(hd_pool *p, size_t n, size_t chunk, hd_chunk_fn fn, void *ctx);
/* hd_parallel_for on p (NULL: the shared pool) with at most nthreads. */
hd_status hd_parallel_for_on(hd_pool *p, size_t n, size_t chunk, int nthreads,
                             hd_chunk_fn fn, void *ctx);
/* Number of online processors (>= 1). */
int hd_ncpus(void);
/* Resolve a -n value: <= 0 means all processors. */
int hd_resolve_threads(int n);

#endif
