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

/* The next 64 bits (xoshiro256**).  Inline: photon tracing and path tracing
 * draw several per scattering event. */
static inline uint64_t hd_rng_u64(hd_rng *r)
{
    uint64_t *s = r->s;
    uint64_t x = s[1] * 5;
    uint64_t out = ((x << 7) | (x >> 57)) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = (s[3] << 45) | (s[3] >> 19);
    return out;
}

/* Uniform in [0,1) with 53 bits. */
static inline double hd_rng_uniform(hd_rng *r) { return (double)(hd_rng_u64(r) >> 11) * 0x1.0p-53; }
/* Uniform integer in [0,n) without modulo bias (n > 0). */
uint64_t hd_rng_below(hd_rng *r, uint64_t n);
/* Mix two 64-bit values (for deriving ids). */
uint64_t hd_hash64(uint64_t a, uint64_t b);

#endif
