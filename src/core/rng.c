/* Counter-based random streams: a SplitMix64 sequence whose start is a hash of (seed, a, b).
 * SplitMix64 (Steele, Lea, Flood 2014) passes BigCrush and is a few lines; no library ships a
 * keyed-stream generator in C, so it is written here. */
#include "dartspp/core.h"

static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

dp_rng rng_stream(uint64_t seed, uint64_t a, uint64_t b)
{
    dp_rng r;
    uint64_t h = mix64(seed + 0x9e3779b97f4a7c15ULL);
    h = mix64(h ^ (a + 0x632be59bd9b4e019ULL));
    h = mix64(h ^ (b + 0x85157af5ULL * 0x100000001ULL));
    r.state = h;
    return r;
}

uint64_t rng_next_u64(dp_rng *r)
{
    r->state += 0x9e3779b97f4a7c15ULL;
    return mix64(r->state);
}

double rng_uniform(dp_rng *r)
{
    return (double)(rng_next_u64(r) >> 11) * 0x1.0p-53;
}
