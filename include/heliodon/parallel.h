/* heliodon — a small parallel-for over a fixed grid of work units.
 *
 * hd_parallel_for() cuts [0,n) into chunks of `chunk` items (the last may be
 * shorter) and runs fn on them from nthreads threads; chunk boundaries do
 * not depend on the thread count, so a computation that seeds its random
 * stream from the chunk index is deterministic. */
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
/* Number of online processors (>= 1). */
int hd_ncpus(void);
/* Resolve a -n value: <= 0 means all processors. */
int hd_resolve_threads(int n);

#endif
