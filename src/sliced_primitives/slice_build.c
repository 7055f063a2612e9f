/* From the photon pass's light-path vertices to this iteration's delta-sliced primitives (Liu et al. 2022 §5:
 * "we first sample a specific time in the time gate and store the corresponding delta-sliced photon
 * primitive"). Each vertex builds every primitive its type lists for it (slice_types.c) from quantities drawn
 * independently of distances, so that a primitive exists whether or not the photon went on: its slice time
 * τ_k, uniform over the gate (or the frames' span), and for parallelepipeds and parallelotopes fresh
 * phase-sampled directions after the photon's own ω. Bounds from the time budget: the camera time is >= 0,
 * so η·Σt <= τ_k − τ(x) =: η·Λ, every root of a ball lies within Λ of x, a parallelepiped's within the
 * tetrahedron x + Λ·{0, ω3, ω2, ω1}, a parallelotope's within the simplex of its four directions. */
#include <stdlib.h>

#include "slice_internal.h"

const phase_function *slice_sampling_phase(const scene *s, int region)
{
    if (region == MEDIUM_VACUUM || !medium_scatters(&s->media[region])) return NULL;
    return &s->media[region].phase;
}

/* k fresh directions after w0, each drawn from the sampling phase function given the one before (uniform on
 * the sphere where none); their joint density. */
static double fresh_directions(const phase_function *pf, vec3 w0, int k, dp_rng *rng, vec3 *w)
{
    double pdf = 1.0;
    vec3 prev = w0;
    for (int i = 0; i < k; i++) {
        double u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        w[i] = pf ? phase_sample(pf, prev, u1, u2) : sample_uniform_sphere(u1, u2);
        pdf *= pf ? phase_eval(pf, prev, w[i]) : DP_INV_4PI;
        prev = w[i];
    }
    return pdf;
}

/* The box of the points x + Λ·e_j (e_0 = 0 and the n directions). */
static void simplex_box(vec3 x, double lam, const vec3 *e, int n, slice_box *b)
{
    double lo[3] = {x.x, x.y, x.z}, hi[3] = {x.x, x.y, x.z};
    for (int j = 0; j < n; j++) {
        double p[3] = {x.x + lam * e[j].x, x.y + lam * e[j].y, x.z + lam * e[j].z};
        for (int k = 0; k < 3; k++) lo[k] = dp_fmin(lo[k], p[k]), hi[k] = dp_fmax(hi[k], p[k]);
    }
    for (int k = 0; k < 3; k++) {
        double pad = 1e-6 * (1.0 + fabs(lo[k]) + fabs(hi[k])); /* float rounding of the bounds */
        b->lo[k] = (float)(lo[k] - pad);
        b->hi[k] = (float)(hi[k] + pad);
        b->c[k] = (float)(0.5 * (lo[k] + hi[k]));
    }
}

/* Directions each kind draws, and how many of the base vertex's: a ball none (ω1 is analytic). */
static const int fresh_count[SLICE_KIND_COUNT] = {
    [SLICE_BALL] = 0, [SLICE_PARALLELEPIPED] = 2, [SLICE_PARALLELOTOPE] = 3, [SLICE_PLANE] = 1, [SLICE_PLANE_1D] = 1};

/* One primitive of kind k at vertex v (index i); 0 when it has no root anywhere (no time left, no direction). */
static int build_one(const scene *s, const slice_build_input *in, const path_vertex *v, uint32_t i, int k,
                     dp_rng *rng, slice_prim *p, slice_box *b)
{
    const time_window *tw = &in->window;
    double span = tw->width * (tw->frame_count > 0 ? tw->frame_count : 1);
    double u = rng_uniform(rng); /* drawn first, whatever follows: the draws of a vertex do not depend on it */
    /* a delta gate: the instant itself (the image is the time density there; weight 1 against the film's per-pass
     * box, slice_gather.c) */
    *p = (slice_prim){.vertex = i, .kind = k, .tau = tw->delta ? tw->center : tw->start + u * span, .pdf = 1.0};
    if (k == SLICE_PLANE || k == SLICE_PLANE_1D) p->tau = tw->start + span; /* no τ_k (the gate is analytic): the
                                                                             * window's end bounds it */
    vec3 dirs[4] = {v->w_out};
    if (k != SLICE_BALL) {
        p->pdf = fresh_directions(slice_sampling_phase(s, v->medium_out), v->w_out, fresh_count[k], rng, p->w);
        if (v3_is_zero(v->w_out) || v3_is_zero(v->beta_out) || !(p->pdf > 0.0)) return 0;
        for (int j = 0; j < fresh_count[k]; j++) dirs[1 + j] = p->w[j];
    }
    double budget = p->tau - v->time, eta = medium_eta(s, v->medium_out);
    if (!(budget > 0.0) || !(eta > 0.0)) return 0;
    double lam = budget / eta;
    if (k == SLICE_BALL) {
        const vec3 axes[6] = {v3(1, 0, 0), v3(-1, 0, 0), v3(0, 1, 0), v3(0, -1, 0), v3(0, 0, 1), v3(0, 0, -1)};
        simplex_box(v->pos, lam, axes, 6, b);
    } else {
        simplex_box(v->pos, lam, dirs, 1 + fresh_count[k], b);
    }
    if (k == SLICE_PLANE_1D) /* the blur: r along the plane's normal */
        for (int j = 0; j < 3; j++) b->lo[j] -= (float)in->r, b->hi[j] += (float)in->r;
    b->budget = (float)budget * (1.0f + 1e-6f);
    return 1;
}

int slice_build(const scene *s, const slice_build_input *in, const path_vertex *v, size_t n, slice_prim **prims,
                slice_box **boxes, size_t *np)
{
    size_t cap = n * SLICE_KIND_COUNT;
    *np = 0;
    *prims = malloc((cap ? cap : 1) * sizeof **prims);
    *boxes = malloc((cap ? cap : 1) * sizeof **boxes);
    if (!*prims || !*boxes) return -1;
    for (size_t i = 0; i < n; i++) {
        dp_rng rng = rng_stream(in->seed ^ 0x736c69636573ULL, (uint64_t)in->iteration, (uint64_t)i);
        for (int k = 0; k < SLICE_KIND_COUNT; k++) {
            if (!slice_type_builds(in->type, k, v[i].flags)) continue;
            if (build_one(s, in, &v[i], (uint32_t)i, k, &rng, &(*prims)[*np], &(*boxes)[*np])) {
                (*boxes)[*np].prim = (uint32_t)*np;
                (*np)++;
            }
        }
    }
    return 0;
}
