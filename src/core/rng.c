/* Counter-based random streams: a SplitMix64 sequence whose start is a hash of (seed, a, b).
 * SplitMix64 (Steele, Lea, Flood 2014) passes BigCrush and is a few lines; no library ships a
 * keyed-stream generator in C, so it is written here. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    r.replay = NULL;
    return r;
}

uint64_t rng_next_u64(dp_rng *r)
{
    r->state += 0x9e3779b97f4a7c15ULL;
    return mix64(r->state);
}

static double stream_uniform(dp_rng *r)
{
    return (double)(rng_next_u64(r) >> 11) * 0x1.0p-53;
}

static int replay_reserve(rng_replay *r, int need)
{
    if (need <= r->cap) return 0;
    int cap = r->cap ? 2 * r->cap : 256;
    while (cap < need) cap *= 2;
    double *u = realloc(r->u, (size_t)cap * sizeof(double));
    if (!u) return -1;
    r->u = u;
    r->cap = cap;
    return 0;
}

/* src's value i moved by ± s_max·(s_min/s_max)^ξ, wrapped into [0, 1): one 64-bit draw gives the sign
 * (its top bit) and ξ (52 more bits). */
static double mutated(rng_replay *r, int i)
{
    uint64_t x = rng_next_u64(&r->fresh);
    double xi = (double)(x & ((1ULL << 52) - 1)) * 0x1.0p-52, step = r->s_max * exp(r->log_ratio * xi);
    double v = r->src[i] + ((x >> 63) ? -step : step);
    v -= floor(v);
    return v < 1.0 ? v : 0.0; /* floor of a tiny negative v can leave exactly 1 */
}

/* The values are made as they are consumed: a proposal that ends sooner moves fewer of them. */
static double replay_next(rng_replay *r)
{
    int i = r->used;
    double v = i < r->src_n ? mutated(r, i) : stream_uniform(&r->fresh);
    if (replay_reserve(r, r->used + 1)) {
        r->oom = 1;
        return v;
    }
    r->u[r->used++] = v;
    return v;
}

double rng_uniform(dp_rng *r)
{
    return r->replay ? replay_next(r->replay) : stream_uniform(r);
}

void rng_replay_free(rng_replay *r)
{
    free(r->u);
    r->u = NULL;
    r->used = r->cap = 0;
}

void rng_replay_restart(rng_replay *r)
{
    r->used = r->src_n = 0;
    r->src = NULL;
    r->oom = 0;
}

void rng_replay_mutate(rng_replay *r, const rng_replay *src, double s_min, double s_max)
{
    rng_replay_restart(r);
    r->src = src->u;
    r->src_n = src->used;
    r->s_max = s_max;
    r->log_ratio = s_max > 0.0 ? log(s_min / s_max) : 0.0;
}
