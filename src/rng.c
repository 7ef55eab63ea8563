/* heliodon — deterministic random streams: xoshiro256** keyed by
 * splitmix64(seed, stream). */
#include "heliodon/rng.h"

static uint64_t splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

uint64_t hd_hash64(uint64_t a, uint64_t b)
{
    uint64_t x = a ^ 0x6a09e667f3bcc909ULL;
    uint64_t h = splitmix(&x);
    x = h ^ b;
    return splitmix(&x);
}

void hd_rng_init(hd_rng *r, uint64_t seed, uint64_t stream)
{
    uint64_t x = hd_hash64(seed, stream);
    for (int i = 0; i < 4; i++) r->s[i] = splitmix(&x);
    if (!(r->s[0] | r->s[1] | r->s[2] | r->s[3])) r->s[0] = 1;
}

uint64_t hd_rng_below(hd_rng *r, uint64_t n)
{
    if (n <= 1) return 0;
    uint64_t lim = -n % n; /* 2^64 mod n */
    for (;;) {
        uint64_t x = hd_rng_u64(r);
        if (x >= lim) return x % n;
    }
}
