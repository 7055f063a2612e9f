/* The path tracer: an unbiased time-resolved volumetric path tracer, plain or with its camera paths aimed
 * at a light and a time bin (path_aim.c: the DARTS path tracer, enable_guiding / enable_elliptical / eda,
 * and the uniform-time path tracer, time_sampling "uniform").
 * Free-flight distance sampling (spectral: one channel picked, pdf averaged over channels), phase and BSDF
 * sampling, next-event estimation to every point light through index-matched boundaries, path time η·d on
 * every segment from the light's emission time (pulse_start, a uniform draw across a box pulse), the camera
 * leg included (camera-warped) or, with camera_unwarp, the segment from the sensor to the first scattering
 * vertex left out (docs/time.md §2.2), box gate or frames via the film.
 * Bounces (docs/design.md §5.1): a path of n segments, the light connection included, counts iff
 * n <= max_bounces and n - 1 >= min_bounces. Crossing a null/forward surface does not end a segment. */
#include <omp.h>
#include <stdlib.h>

#include "path_tracer_internal.h"

void pt_connect_light(pixel_ctx *c, const path_state *ps, int i, vec3 x, const phase_function *pf,
                      const surface_site *ss, int draw_emission, double w, int frame)
{
    const scene *s = c->pass->s;
    const point_light *L = &s->lights[i];
    vec3 to = v3_sub(L->pos, x);
    double d2 = v3_dot(to, to);
    if (d2 <= 0.0) return;
    vec3 wl = v3_scale(to, 1.0 / sqrt(d2));
    vec3 f = ss ? surface_eval_cos(ss, wl, BSDF_LOBES_ALL) : v3s(phase_eval(pf, ps->d, wl));
    if (v3_max(f) <= 0.0) return;
    vec3 tr;
    double t = ps->time + (draw_emission ? point_light_emission_time(L, c->rng) : 0.0);
    c->pix->rays += 1;
    vec3 o = ss ? surface_spawn(s, ss, wl) : x;
    if (!scene_transmittance(s, o, ss ? surface_medium_toward(ss, ps->medium, wl) : ps->medium, L->pos, &tr, &t))
        return;
    film_pixel_splat(c->pix, t, v3_scale(v3_mul(v3_mul(v3_mul(ps->beta, tr), L->intensity), f), w / d2), frame);
}

/* NEE from x (a medium vertex, phase pf) or the surface site ss (x = its point): to every point light on a
 * plain path, the contribution β·Tr·I·f/d² with f the phase function or the BSDF with its cosine; to its one
 * light on an aimed path. */
static void connect_lights(pixel_ctx *c, const path_state *ps, vec3 x, const phase_function *pf,
                           const surface_site *ss)
{
    if (c->aim.on) {
        pt_aim_connect(c, ps, x, pf, ss);
        return;
    }
    for (int i = 0; i < c->pass->s->light_count; i++) pt_connect_light(c, ps, i, x, pf, ss, 1, 1.0, -1);
}

/* Time of a segment of length len in a region of index eta: η·len, but nothing for the camera segment
 * adjacent to the sensor (depth 0: no scattering vertex yet) when time is camera-unwarped. */
static double segment_time(const pixel_ctx *c, const path_state *ps, double eta, double len)
{
    return c->pass->p->window.camera_unwarp && ps->depth == 0 ? 0.0 : eta * len;
}

/* Medium vertex: NEE (unless the segment that led here connected by a control vertex), then the new
 * direction. Returns 0 when the path ends. */
static int scatter_medium(pixel_ctx *c, path_state *ps, double t)
{
    const scene *s = c->pass->s;
    const medium *m = &s->media[ps->medium];
    ps->o = v3_add(ps->o, v3_scale(ps->d, t));
    ps->time += segment_time(c, ps, m->eta, t);
    ps->depth++;
    if (++ps->medium_events > m->max_bounces) return 0;
    if (!ps->connected && bounces_count(&c->pass->p->bounces, ps->depth + 1)) connect_lights(c, ps, ps->o, &m->phase, NULL);
    if (c->aim.on) {
        pt_aim_scatter_direction(c, ps);
        return 1;
    }
    double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
    ps->d = phase_sample(&m->phase, ps->d, u1, u2);
    return 1;
}

/* Surface hit: pass-through, or NEE with the BSDF evaluated and a BSDF sample. Returns 0 when the path
 * ends. The medium beyond follows the sampled direction (refraction enters a dielectric's interior). */
static int scatter_surface(pixel_ctx *c, path_state *ps, const hit_record *h)
{
    const scene *s = c->pass->s;
    const surface *sf = &s->surfaces[h->surface];
    const bsdf *b = &s->bsdfs[sf->bsdf];
    ps->time += segment_time(c, ps, medium_eta(s, ps->medium), h->t);
    if (bsdf_is_passthrough(b)) {
        vec3 n_out = v3_dot(ps->d, h->ng) < 0.0 ? v3_neg(h->ng) : h->ng; /* the far side */
        ps->medium = surface_next_medium(sf, ps->medium, ps->d, h->ng);
        ps->o = scene_offset_ray_origin(s, h->p, n_out);
        return 1;
    }
    ps->depth++;
    ps->medium_events = 0;
    surface_site ss;
    if (!surface_site_init(&ss, s, &c->pass->p->shading, h, ps->d)) return 0;
    if ((bsdf_lobes(b) & ~BSDF_LOBE_SPECULAR) && bounces_count(&c->pass->p->bounces, ps->depth + 1))
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
    const time_window *tw = &c->pass->p->window;
    if (tw->gated && ps->time >= time_window_end(tw)) return 0;
    if (v3_is_zero(ps->beta) || !v3_is_finite(ps->beta)) return 0;
    if (!c->pass->p->keys.enable_rr || ps->depth < 5) return 1;
    double q = dp_fmin(1.0, v3_max(ps->beta));
    if (rng_uniform(c->rng) >= q) return 0;
    ps->beta = v3_scale(ps->beta, 1.0 / q);
    return 1;
}

/* The distance of one medium segment up to tmax: aimed (control vertex, DA, uniform time) or free flight.
 * Returns 0 when the path ends. */
static int medium_distance(pixel_ctx *c, path_state *ps, double tmax, int *event, double *t)
{
    ps->connected = 0;
    if (c->aim.on) return pt_aim_medium_segment(c, ps, tmax, event, t);
    *t = medium_sample_free_flight(&c->pass->s->media[ps->medium], tmax, c->rng, &ps->beta, event);
    return 1;
}

static void trace_camera_path(pixel_ctx *c, vec3 d)
{
    const scene *s = c->pass->s;
    path_state ps = {.o = s->cam.pos, .d = d, .medium = s->cam.medium, .beta = v3s(1.0)};
    if (c->pass->aimed && !pt_aim_start(c, &ps)) return;
    for (int guard = 0; guard < 100000; guard++) {
        if (ps.depth >= c->pass->p->bounces.max - 1) return; /* no later path can count */
        hit_record h;
        c->pix->rays += 1;
        int hit = scene_intersect(s, ps.o, ps.d, INFINITY, &h);
        double tmax = hit ? h.t : INFINITY;
        if (ps.medium != MEDIUM_VACUUM) {
            int event;
            double t;
            if (!medium_distance(c, &ps, tmax, &event, &t)) return;
            if (event) {
                if (!scatter_medium(c, &ps, t) || !survive(c, &ps)) return;
                continue;
            }
        }
        if (!hit || !scatter_surface(c, &ps, &h) || !survive(c, &ps)) return;
    }
}

static void sample_pixel(void *ctx, film_pixel *pix, vec3 dir, dp_rng *rng)
{
    pixel_ctx c = {.pass = ctx, .pix = pix, .rng = rng};
    trace_camera_path(&c, dir);
}

int path_tracer_pass(const scene *s, const render_plan *p, const struct eda_set *eda, film *f, uint64_t seed,
                     long pass, const dp_stop_flag *stop, double *rays, dp_error *err)
{
    pt_pass pp = {.s = s, .p = p, .eda = eda};
    if (pt_pass_aim_init(&pp, err)) return -1;
    *rays += film_sample_pixels(f, &s->cam, seed, pass, stop, sample_pixel, &pp);
    pt_pass_aim_free(&pp);
    return 0;
}
