/* heliodon — deterministic random streams.
 *
 * A stream is keyed by (seed, stream id).  Parallel code never draws from a
 * per-thread generator: work is cut into fixed units (chunk, shard, photon
 * batch) and each unit gets its own stream id, so results are identical
 * whatever the thread count.  Generator: xoshiro256** seeded through
 * splitmix64 of (seed, id). */
#ifndef HELIODON_RNG_H
#define HELIODON_RNG_H

#include <stdint.h>

typedef struct hd_rng { uint64_t s[4]; } hd_rng;

void hd_rng_init(hd_rng *r, uint64_t seed, uint64_t stream);
uint64_t hd_rng_u64(hd_rng *r);
/* Uniform in [0,1) with 53 bits. */
double hd_rng_uniform(hd_rng *r);
/* Uniform integer in [0,n) without modulo bias (n > 0). */
uint64_t hd_rng_below(hd_rng *r, uint64_t n);
/* Mix two 64-bit values (for deriving ids). */
uint64_t hd_hash64(uint64_t a, uint64_t b);

#endif
