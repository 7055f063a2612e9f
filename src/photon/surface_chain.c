/* Surface chains: Markov chains over light paths in primary sample space that keep to the paths whose
 * surface photons can count in the gate (Hachisuka and Jensen 2011, "Robust adaptive photon tracing using
 * photon path visibility", with our own target: a path is "visible" when it stores a surface photon that
 * passes the DARTS time test). With a narrow gate only a few percent of the light paths store such a
 * photon (about 3 % on the fog Cornell box), so the surface map is photon-starved; the chains spend most
 * light paths near the visible ones.
 *
 * Each step proposes either an independent light path (a "large step", probability CHAIN_LARGE_STEP, and
 * always until a first visible path is found) or the current path's random numbers moved by a symmetric
 * step (Kelemen et al. 2002: size log-uniform in [CHAIN_STEP_MIN, CHAIN_STEP_MAX], wrapped); a visible
 * proposal is accepted, an invisible one rejected (the target is uniform on the visible set). The kernel is
 * fixed — an acceptance-adapted step size (as Hachisuka and Jensen adapt it) makes a finite chain linger
 * where its steps are small, and biases it. The large steps also estimate the visible fraction P(V); the
 * photon pass scales the chain photons by P̂(V)·(paths traced)/(states counted), so that they stand for as
 * many independent paths (photon_pass.c). Each step's random numbers come from its own stream, keyed by
 * (seed, iteration, chain, step): a path that ends earlier (the DARTS early exit) leaves the chain's next
 * steps unchanged. Written here: no library implements photon-path Markov chains. */
#include <math.h>
#include <string.h>

#include "photon_internal.h"

#define CHAIN_LARGE_STEP 0.25   /* probability of an independent proposal once the chain has a state */
/* The small step's size range in primary sample space, chosen on the fog Cornell box at equal iterations
 * (bench/results/surface_chains.md): [1/4096, 1/64] accepts 47 % of the small steps; 4x larger steps
 * accept 17 % and lose half the gain, 4x smaller ones accept 69 % and lose a third of it. */
#define CHAIN_STEP_MIN (1.0 / 4096)
#define CHAIN_STEP_MAX (1.0 / 64)
static const uint64_t CHAIN_KEY = 0x636861696e73ULL; /* "chains": the chains' random streams */

struct chain_scratch {        /* one per thread, on cache lines of its own (core.h) */
    _Alignas(DP_CACHE_LINE) rng_replay a;
    rng_replay b;            /* a: the current state's random numbers, b: the proposal's */
    thread_bufs pa, pb;      /* the current state's and the proposal's photons */
};

chain_scratch *chain_scratch_new(void) { return dp_calloc_cache_aligned(1, sizeof(chain_scratch)); }

void chain_scratch_free(chain_scratch *cs)
{
    if (!cs) return;
    rng_replay_free(&cs->a);
    rng_replay_free(&cs->b);
    buf_free(&cs->pa.surf);
    buf_free(&cs->pa.vol);
    buf_free(&cs->pb.surf);
    buf_free(&cs->pb.vol);
    free(cs);
}

/* The held state's photons into the thread buffer, once, with their powers times the steps it held (their
 * derivative records, stride bytes each, unchanged: a constant factor moves no ∂ ln f). */
static void flush_state(thread_bufs *dst, const thread_bufs *state, long hold, size_t stride, chain_count *cc)
{
    for (size_t i = 0; i < state->surf.n; i++) {
        photon ph = state->surf.p[i];
        for (int c = 0; c < 3; c++) ph.power[c] *= (float)hold;
        if (buf_push(&dst->surf, &ph, stride ? state->surf.d + i * stride : NULL, stride)) {
            dst->oom = 1;
            return;
        }
        cc->n++;
    }
}

void surface_chain_run(const scene *s, const photon_pass_input *in, long index, int steps, chain_scratch *cs,
                       thread_bufs *tb, chain_count *cc)
{
    rng_replay *cur = &cs->a, *prop = &cs->b;
    thread_bufs *cur_ph = &cs->pa, *prop_ph = &cs->pb;
    long hold = 0;
    int have = 0;
    cc->off = tb->surf.n;
    for (int j = 0; j < steps; j++) {
        dp_rng step = rng_stream(in->seed ^ CHAIN_KEY, (uint64_t)in->iteration, ((uint64_t)index << 20) | (uint64_t)j);
        int large = rng_uniform(&step) < CHAIN_LARGE_STEP || !have;
        prop->fresh = step;
        if (large) rng_replay_restart(prop);
        else rng_replay_mutate(prop, cur, CHAIN_STEP_MIN, CHAIN_STEP_MAX);
        dp_rng r = {.replay = prop};
        path_count pc = {0};
        prop_ph->surf.n = 0;
        trace_light_path(s, in, 0, &r, prop_ph, &pc);
        tb->nonfinite += prop_ph->nonfinite;
        prop_ph->nonfinite = 0;
        tb->oom |= prop_ph->oom;
        int visible = pc.n_surf > 0 && !prop->oom;
        cc->st.traced++;
        cc->st.early_exits += pc.early_exit;
        if (large) {
            cc->st.large++;
            cc->st.visible += visible;
        } else {
            cc->st.small++;
            cc->st.accepted += visible;
        }
        if (visible) {
            if (have) flush_state(tb, cur_ph, hold, in->deriv_stride, cc);
            rng_replay *t = cur;
            cur = prop, prop = t;
            thread_bufs *tp = cur_ph;
            cur_ph = prop_ph, prop_ph = tp;
            hold = 0;
            have = 1;
        }
        if (have) {
            hold++;
            cc->st.states++;
        }
    }
    if (have) flush_state(tb, cur_ph, hold, in->deriv_stride, cc);
}
