/* The reference integrator: an unbiased time-resolved volumetric path tracer.
 * Free-flight distance sampling (spectral: one channel picked, pdf averaged over channels), phase and BSDF
 * sampling, next-event estimation to every point light through index-matched boundaries, path time η·d on
 * every segment from the light's emission time (pulse_start, a uniform draw across a box pulse), the camera
 * leg included (camera-warped) or, with camera_unwarp, the segment from the sensor to the first scattering
 * vertex left out (docs/time.md §2.2), box gate or frames via the film.
 * Bounces (docs/design.md §5.1): a path of n segments, the light connection included, counts iff
 * n <= max_bounces and n - 1 >= min_bounces. Crossing a null/forward surface does not end a segment. */
#include "dartspp/render.h"
#include "dartspp/surface.h"

#include <omp.h>

typedef struct {
    vec3 o, d;
    int medium;
    vec3 beta;     /* throughput */
    double time;   /* path time from the camera to o (unwarped: from the first scattering vertex) */
    int depth;     /* scattering vertices so far (segments so far) */
} path_state;

typedef struct {
    const scene *s;
    const render_plan *p;
    film_pixel *pix;
    dp_rng *rng;
} pixel_ctx;

/* NEE to every point light from x (a medium vertex), or from the surface site ss (x = its point): the
 * contribution is β·Tr·I·f/d², f the phase function or the BSDF with its cosine. */
static void connect_lights(pixel_ctx *c, const path_state *ps, vec3 x, const phase_function *pf,
                           const surface_site *ss)
{
    const scene *s = c->s;
    for (int i = 0; i < s->light_count; i++) {
        const point_light *L = &s->lights[i];
        vec3 to = v3_sub(L->pos, x);
        double d2 = v3_dot(to, to);
        if (d2 <= 0.0) continue;
        vec3 w = v3_scale(to, 1.0 / sqrt(d2));
        vec3 f = ss ? surface_eval_cos(ss, w, BSDF_LOBES_ALL) : v3s(phase_eval(pf, ps->d, w));
        if (v3_max(f) <= 0.0) continue;
        vec3 tr;
        double t = ps->time + point_light_emission_time(L, c->rng);
        c->pix->rays += 1;
        vec3 o = ss ? surface_spawn(s, ss, w) : x;
        if (!scene_transmittance(s, o, ss ? surface_medium_toward(ss, ps->medium, w) : ps->medium, L->pos, &tr, &t))
            continue;
        film_pixel_splat(c->pix, t, v3_scale(v3_mul(v3_mul(v3_mul(ps->beta, tr), L->intensity), f), 1.0 / d2), -1);
    }
}

/* Time of a segment of length len in a region of index eta: η·len, but nothing for the camera segment
 * adjacent to the sensor (depth 0: no scattering vertex yet) when time is camera-unwarped. */
static double segment_time(const pixel_ctx *c, const path_state *ps, double eta, double len)
{
    return c->p->window.camera_unwarp && ps->depth == 0 ? 0.0 : eta * len;
}

/* Medium vertex: NEE, then phase sampling. Returns 0 when the path ends. */
static int scatter_medium(pixel_ctx *c, path_state *ps, double t, int *medium_events)
{
    const scene *s = c->s;
    const medium *m = &s->media[ps->medium];
    ps->o = v3_add(ps->o, v3_scale(ps->d, t));
    ps->time += segment_time(c, ps, m->eta, t);
    ps->depth++;
    if (++*medium_events > m->max_bounces) return 0;
    if (bounces_count(&c->p->bounces, ps->depth + 1)) connect_lights(c, ps, ps->o, &m->phase, NULL);
    double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
    ps->d = phase_sample(&m->phase, ps->d, u1, u2);
    return 1;
}

/* Surface hit: pass-through, or NEE with the BSDF evaluated and a BSDF sample. Returns 0 when the path
 * ends. The medium beyond follows the sampled direction (refraction enters a dielectric's interior). */
static int scatter_surface(pixel_ctx *c, path_state *ps, const hit_record *h, int *medium_events)
{
    const scene *s = c->s;
    const surface *sf = &s->surfaces[h->surface];
    const bsdf *b = &s->bsdfs[sf->bsdf];
    ps->time += segment_time(c, ps, medium_eta(s, ps->medium), h->t);
    if (bsdf_is_passthrough(b)) {
        vec3 n_out = v3_dot(ps->d, h->ng) < 0.0 ? v3_neg(h->ng) : h->ng; /* the far side */
        ps->medium = surface_next_medium(sf, ps->medium, ps->d, h->ng);
        ps->o = scene_offset_ray_origin(c->s, h->p, n_out);
        return 1;
    }
    ps->depth++;
    *medium_events = 0;
    surface_site ss;
    if (!surface_site_init(&ss, s, &c->p->shading, h, ps->d)) return 0;
    if ((bsdf_lobes(b) & ~BSDF_LOBE_SPECULAR) && bounces_count(&c->p->bounces, ps->depth + 1))
        connect_lights(c, ps, h->p, NULL, &ss);
    double u[3] = {rng_uniform(c->rng), rng_uniform(c->rng), rng_uniform(c->rng)};
    surface_sample smp;
    if (!surface_sample_bsdf(&ss, u, BSDF_LOBES_ALL, 0, &smp)) return 0;
    ps->beta = v3_mul(ps->beta, smp.weight);
    ps->d = smp.w;
    ps->medium = surface_next_medium(sf, ps->medium, ps->d, h->ng);
    ps->o = surface_spawn(s, &ss, ps->d);
    return 1;
}

/* Russian roulette after a few vertices, and termination once the path time is past the window:
 * every later contribution arrives later still. Returns 0 when the path ends. */
static int survive(pixel_ctx *c, path_state *ps)
{
    const time_window *tw = &c->p->window;
    if (tw->gated && ps->time >= time_window_end(tw)) return 0;
    if (v3_is_zero(ps->beta) || !v3_is_finite(ps->beta)) return 0;
    if (!c->p->keys.enable_rr || ps->depth < 5) return 1;
    double q = dp_fmin(1.0, v3_max(ps->beta));
    if (rng_uniform(c->rng) >= q) return 0;
    ps->beta = v3_scale(ps->beta, 1.0 / q);
    return 1;
}

static void trace_camera_path(pixel_ctx *c, vec3 d)
{
    const scene *s = c->s;
    path_state ps = {.o = s->cam.pos, .d = d, .medium = s->cam.medium, .beta = v3s(1.0)};
    int medium_events = 0;
    for (int guard = 0; guard < 100000; guard++) {
        if (ps.depth >= c->p->bounces.max - 1) return; /* no later path can count */
        hit_record h;
        c->pix->rays += 1;
        int hit = scene_intersect(s, ps.o, ps.d, INFINITY, &h);
        double tmax = hit ? h.t : INFINITY;
        if (ps.medium != MEDIUM_VACUUM) {
            int event;
            double t = medium_sample_free_flight(&s->media[ps.medium], tmax, c->rng, &ps.beta, &event);
            if (event) {
                if (!scatter_medium(c, &ps, t, &medium_events) || !survive(c, &ps)) return;
                continue;
            }
        }
        if (!hit || !scatter_surface(c, &ps, &h, &medium_events) || !survive(c, &ps)) return;
    }
}

typedef struct {
    const scene *s;
    const render_plan *p;
} pass_ctx;

static void sample_pixel(void *ctx, film_pixel *pix, vec3 dir, dp_rng *rng)
{
    const pass_ctx *pass = ctx;
    pixel_ctx c = {.s = pass->s, .p = pass->p, .pix = pix, .rng = rng};
    trace_camera_path(&c, dir);
}

double path_tracer_pass(const scene *s, const render_plan *p, film *f, uint64_t seed, long pass,
                        const dp_stop_flag *stop)
{
    pass_ctx ctx = {s, p};
    return film_sample_pixels(f, &s->cam, seed, pass, stop, sample_pixel, &ctx);
}
