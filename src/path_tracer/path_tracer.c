/* The path tracer: an unbiased time-resolved volumetric path tracer, plain or with its camera paths aimed
 * at a light and a time bin (path_aim.c: the DARTS path tracer, enable_guiding / enable_elliptical / eda,
 * and the uniform-time path tracer, time_sampling "uniform").
 * Free-flight distance sampling (spectral: one channel picked, pdf averaged over channels), phase and BSDF
 * sampling, next-event estimation to every light that allows it through index-matched boundaries (a parallel
 * beam by the crossings of the segments), emission where a path from the camera or a delta lobe hits an area
 * light, path time η·d on every segment from the light's emission time (the pulse), the camera
 * leg included (camera-warped) or, with camera_unwarp, the segment from the sensor to the first scattering
 * vertex left out (docs/time.md §2.2), box gate or frames via the film.
 * Bounces (docs/design.md §5.1): a path of n segments, the light connection included, counts iff
 * n <= max_bounces and n - 1 >= min_bounces. Crossing a null/forward surface does not end a segment. */
#include <omp.h>
#include <stdlib.h>

#include "path_tracer_internal.h"

/* Where a shadow ray toward the light sample ends: its point, or just before an area light's surface. */
static vec3 shadow_target(const scene *s, const emitter_direct *ed)
{
    if (v3_is_zero(ed->n)) return ed->y;
    return scene_offset_ray_origin(s, ed->y, v3_dot(ed->wi, ed->n) < 0.0 ? ed->n : v3_neg(ed->n));
}

/* The light leg's pieces into the connection's derivative state (scene_transmittance_segments). */
typedef struct {
    const deriv_plan *d;
    deriv_path *p;
} leg_deriv;

static void leg_segment(void *ctx, int region, double len)
{
    leg_deriv *l = ctx;
    deriv_transmittance(l->d, l->p, region, len);
    deriv_time(l->d, l->p, region, len);
}

void pt_connect_sample(pixel_ctx *c, const path_state *ps, int i, const emitter_direct *ed, vec3 x,
                       const phase_function *pf, const surface_site *ss, int draw_emission, double w, int frame)
{
    const scene *s = c->pass->s;
    const emitter *L = &s->lights[i];
    const deriv_plan *D = c->pass->deriv;
    vec3 wl = ed->wi;
    vec3 f = ss ? surface_eval_cos(ss, wl, BSDF_LOBES_ALL) : v3s(phase_eval(pf, ps->d, wl));
    if (v3_max(f) <= 0.0) return;
    vec3 tr;
    double offset = draw_emission ? path_time_offset(s, L, c->rng) : ps->offset;
    double t = ps->time + (draw_emission ? offset : 0.0);
    c->pix->rays += 1;
    vec3 o = ss ? surface_spawn(s, ss, wl) : x;
    int end;
    deriv_path dv;
    leg_deriv leg = {D, &dv};
    if (D) {
        dv = ps->dv;
        if (!ss) deriv_phase(D, &dv, ps->medium, ps->d, wl);
        pt_geom_leg(c, &dv, i, x, ps->medium, pf, ps->d, ss);
    }
    if (!scene_transmittance_segments(s, o, ss ? surface_medium_toward(ss, ps->medium, wl) : ps->medium,
                                      shadow_target(s, ed), &tr, &t, &end, D ? leg_segment : NULL, &leg))
        return;
    vec3 value = v3_scale(v3_mul(v3_mul(v3_mul(ps->beta, tr), ed->value), f), w / ed->denom);
    film_pixel_splat(c->pix, t, value, frame, ps->depth); /* the vertices so far, this one included */
    if (D) deriv_splat(D, c->pix, &dv, i, t, offset, value, frame, ps->depth);
}

void pt_deriv_segment(const pixel_ctx *c, path_state *ps, double len)
{
    const deriv_plan *D = c->pass->deriv;
    if (!D) return;
    if (!ps->tr_done) deriv_transmittance(D, &ps->dv, ps->medium, len);
    ps->tr_done = 0;
    if (!pt_unwarped_camera_segment(c, ps)) deriv_time(D, &ps->dv, ps->medium, len);
}

/* The light connection of light i from x, by its direct-light sample. A medium vertex does not connect to a
 * parallel beam: the segments' crossings do (pt_beam_crossing). */
static void connect_light(pixel_ctx *c, const path_state *ps, int i, vec3 x, const phase_function *pf,
                          const surface_site *ss)
{
    const emitter *L = &c->pass->s->lights[i];
    if (!emitter_connectable(L) || (pf && emitter_is_parallel_beam(L))) return;
    double u[2] = {0.0, 0.0};
    if (emitter_direct_draws(L)) u[0] = rng_uniform(c->rng), u[1] = rng_uniform(c->rng);
    emitter_direct ed;
    if (emitter_sample_direct(c->pass->s, L, x, u, &ed)) pt_connect_sample(c, ps, i, &ed, x, pf, ss, 1, 1.0, -1);
}

/* NEE from x (a medium vertex, phase pf) or the surface site ss (x = its point): to every light on a plain
 * path, the contribution β·Tr·f·(the light sample's value) with f the phase function or the BSDF with its
 * cosine; to its one light on an aimed path. */
static void connect_lights(pixel_ctx *c, const path_state *ps, vec3 x, const phase_function *pf,
                           const surface_site *ss)
{
    if (c->aim.on) {
        pt_aim_connect(c, ps, x, pf, ss);
        return;
    }
    for (int i = 0; i < c->pass->s->light_count; i++) connect_light(c, ps, i, x, pf, ss);
}

/* One side of the gate on the crossing: keeps t in [*t0, *t1] where A + B·t < lim (below = 1) or >= lim. */
static void keep_side(double A, double B, double lim, int below, double *t0, double *t1)
{
    if (B == 0.0) {
        if (below ? !(A < lim) : !(A >= lim)) *t1 = *t0; /* empty */
        return;
    }
    double tc = (lim - A) / B;
    if ((B > 0.0) == below) *t1 = dp_fmin(*t1, tc);
    else *t0 = dp_fmax(*t0, tc);
}

/* The crossing restricted to a bin [start, end) (docs/emitters.md §4.2): the vertex at t has the path time
 * τ + η·t (η 0 on the unwarped camera segment) plus the leg's, and the leg runs s(t) = (o + t·d − pos)·axis
 * along −axis through regions of η in [η_lb, η_ub], so only t with τ + η·t + η_lb·s(t) < end and
 * τ + η·t + η_ub·s(t) >= start can count: both linear in t. Widened by 1e-9 of the times (rounding). */
static void beam_gate_interval(const path_state *ps, const emitter *L, double tau, double eta, double start,
                               double end, const darts_plan *d, double *t0, double *t1)
{
    double s0 = v3_dot(v3_sub(ps->o, L->pos), L->axis), ds = v3_dot(ps->d, L->axis);
    double slack = 1e-9 * (fabs(end) + fabs(tau) + eta * *t1);
    keep_side(tau + d->eta_lb * s0, eta + d->eta_lb * ds, end + slack, 1, t0, t1);
    keep_side(tau + d->eta_ub * s0, eta + d->eta_ub * ds, start - slack, 0, t0, t1);
}

/* The crossing of a parallel beam (docs/emitters.md §4.2): a vertex at t in [t0, t1], the part of the
 * segment inside the beam, by a σ-exponential truncated to it (uniform where σ·(t1 − t0) is tiny); its
 * estimate β·σs·e^{−σt·t}/p(t) times the deterministic connection along −axis. It estimates the light that
 * the segment's medium vertices would connect to, which they then leave out. Under a gate only the part of
 * [t0, t1] whose time can land in it is drawn: an aimed path's bin, or on a plain path the window, with the
 * emission time drawn first (it shifts the whole time); renders with derivatives keep the whole crossing
 * (their path-space estimate keeps the draw's support fixed). */
void pt_beam_crossing(pixel_ctx *c, const path_state *ps, int i, double tmax, int draw_emission, double w, int frame)
{
    const scene *s = c->pass->s;
    const render_plan *p = c->pass->p;
    const medium *m = &s->media[ps->medium];
    const emitter *L = &s->lights[i];
    double t0, t1;
    if (!medium_scatters(m) || ps->medium_events + 1 > m->max_bounces ||
        !bounces_count(&p->bounces, ps->depth + 2) || !emitter_beam_crossing(L, ps->o, ps->d, tmax, &t0, &t1))
        return;
    double eta = p->window.camera_unwarp && ps->depth == 0 ? 0.0 : m->eta, tau = ps->time, offset = ps->offset;
    if (p->window.gated && !p->window.delta && !c->pass->deriv) {
        if (c->aim.on) {
            beam_gate_interval(ps, L, tau, eta, c->aim.bin.start, c->aim.bin.end, &p->darts, &t0, &t1);
        } else if (draw_emission) {
            offset = path_time_offset(s, L, c->rng);
            tau += offset;
            draw_emission = 0;
            beam_gate_interval(ps, L, tau, eta, p->window.start, time_window_end(&p->window), &p->darts, &t0, &t1);
        }
        if (!(t1 > t0)) return;
    }
    double len = t1 - t0, sigma = v3_avg(m->sigma_t), a = sigma * len, u = rng_uniform(c->rng), t, pdf;
    if (a > 1e-6) {
        double mass = -expm1(-a);
        t = t0 - log1p(-u * mass) / sigma;
        pdf = sigma * exp(-sigma * (t - t0)) / mass;
    } else {
        t = t0 + u * len;
        pdf = 1.0 / len;
    }
    if (!(pdf > 0.0) || !(t >= t0 && t <= t1)) return;
    path_state v = *ps;
    v.o = v3_add(ps->o, v3_scale(ps->d, t));
    v.time = tau + eta * t;
    v.offset = offset;
    v.tr_done = 0;
    pt_deriv_segment(c, &v, t);
    if (c->pass->deriv) deriv_medium_vertex(c->pass->deriv, &v.dv, ps->medium);
    v.depth = ps->depth + 1;
    v.beta = v3_mul(ps->beta, v3_scale(v3_mul(m->sigma_s, v3_exp_neg(v3_scale(m->sigma_t, t))), 1.0 / pdf));
    emitter_direct ed;
    const double none[2] = {0.0, 0.0};
    if (emitter_sample_direct(s, L, v.o, none, &ed)) pt_connect_sample(c, &v, i, &ed, v.o, &m->phase, NULL, draw_emission, w, frame);
}

/* A camera path hitting an area light: its emission, on a path whose last vertex was the camera or a delta
 * lobe (next-event estimation counts the rest); an aimed path counts only its own light. */
static void hit_emission(pixel_ctx *c, const path_state *ps, const hit_record *h)
{
    const scene *s = c->pass->s;
    int i = s->surfaces[h->surface].emitter;
    if (i < 0 || !ps->after_delta || !bounces_count(&c->pass->p->bounces, ps->depth + 1)) return;
    if (c->aim.on && i != c->aim.light) return;
    const emitter *L = &s->lights[i];
    vec3 le = emitter_hit_radiance(L, ps->d, h->ng);
    if (v3_is_zero(le)) return;
    const deriv_plan *D = c->pass->deriv;
    if (c->aim.on) {
        vec3 v = v3_scale(v3_mul(ps->beta, le), 1.0 / (c->aim.sel_pdf * c->aim.bin.pdf));
        film_pixel_splat(c->pix, ps->time, v, c->aim.bin.frame, ps->depth);
        if (D) deriv_splat(D, c->pix, &ps->dv, i, ps->time, ps->offset, v, c->aim.bin.frame, ps->depth);
        return;
    }
    double offset = path_time_offset(s, L, c->rng);
    film_pixel_splat(c->pix, ps->time + offset, v3_mul(ps->beta, le), -1, ps->depth);
    if (D) deriv_splat(D, c->pix, &ps->dv, i, ps->time + offset, offset, v3_mul(ps->beta, le), -1, ps->depth);
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
    const deriv_plan *D = c->pass->deriv;
    ps->o = v3_add(ps->o, v3_scale(ps->d, t));
    ps->time += segment_time(c, ps, m->eta, t);
    pt_deriv_segment(c, ps, t);
    pt_geom_vertex(c, ps, t, 0);
    if (D) deriv_medium_vertex(D, &ps->dv, ps->medium);
    ps->depth++;
    ps->after_delta = 0;
    if (++ps->medium_events > m->max_bounces) return 0;
    if (!ps->connected && bounces_count(&c->pass->p->bounces, ps->depth + 1)) connect_lights(c, ps, ps->o, &m->phase, NULL);
    vec3 w_in = ps->d;
    if (c->aim.on) {
        pt_aim_scatter_direction(c, ps);
    } else {
        double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
        ps->d = phase_sample(&m->phase, ps->d, u1, u2);
    }
    if (D) deriv_phase(D, &ps->dv, ps->medium, w_in, ps->d);
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
    pt_deriv_segment(c, ps, h->t);
    pt_geom_vertex(c, ps, h->t, 1);
    hit_emission(c, ps, h);
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
    if (c->pass->deriv) deriv_surface_vertex(c->pass->deriv, &ps->dv, sf->bsdf);
    if ((bsdf_lobes(b) & ~BSDF_LOBE_SPECULAR) && bounces_count(&c->pass->p->bounces, ps->depth + 1))
        connect_lights(c, ps, h->p, NULL, &ss);
    surface_sample smp;
    if (c->aim.on) {
        if (!pt_aim_surface_sample(c, ps, &ss, &smp)) return 0;
    } else {
        double u[3] = {rng_uniform(c->rng), rng_uniform(c->rng), rng_uniform(c->rng)};
        if (!surface_sample_bsdf(&ss, u, BSDF_LOBES_ALL, 0, &smp)) return 0;
    }
    ps->beta = v3_mul(ps->beta, smp.weight);
    ps->d = smp.w;
    ps->after_delta = (smp.lobe & BSDF_LOBE_SPECULAR) != 0;
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
    if (!c->pass->p->enable_rr || ps->depth < 5) return 1;
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
    for (int i = 0; i < c->pass->s->light_count; i++)
        if (emitter_is_parallel_beam(&c->pass->s->lights[i])) pt_beam_crossing(c, ps, i, tmax, 1, 1.0, -1);
    *t = medium_sample_free_flight(&c->pass->s->media[ps->medium], tmax, c->rng, &ps->beta, event);
    return 1;
}

static void trace_camera_path(pixel_ctx *c, vec3 o, vec3 d)
{
    const scene *s = c->pass->s;
    path_state ps = {.o = o, .d = d, .medium = s->cam.medium, .beta = v3s(1.0), .after_delta = 1};
    if (c->pass->geom) deriv_camera_start(c->pass->deriv, &ps.dv);
    if (c->pass->aimed && !pt_aim_start(c, &ps)) return;
    for (int guard = 0; guard < 100000; guard++) {
        if (ps.depth >= c->pass->p->bounces.max - 1) return; /* no later path can count */
        hit_record h;
        c->pix->rays += 1;
        int hit = scene_intersect(s, ps.o, ps.d, INFINITY, &h);
        double tmax = hit ? h.t : INFINITY;
        pt_geom_segment(c, &ps, hit ? &h : NULL);
        if (ps.medium != MEDIUM_VACUUM) {
            pt_shadow_crossings(c, &ps, tmax);
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

/* A lidar's beam (docs/lidar.md §1): the pass over the scene as this pixel's beam lights it. */
static void sample_lidar_beam(const pt_pass *pass, film_pixel *pix, vec3 o, vec3 dir, dp_rng *rng)
{
    scene view;
    emitter beam;
    lidar_beam_view(pass->s, pix->px, &view, &beam);
    pt_pass beam_pass = *pass;
    beam_pass.s = &view;
    pixel_ctx c = {.pass = &beam_pass, .pix = pix, .rng = rng};
    trace_camera_path(&c, o, dir);
}

static void sample_pixel(void *ctx, film_pixel *pix, vec3 o, vec3 dir, dp_rng *rng)
{
    const pt_pass *pass = ctx;
    if (pass->s->cam.type == CAMERA_LIDAR) {
        sample_lidar_beam(pass, pix, o, dir, rng);
        return;
    }
    pixel_ctx c = {.pass = pass, .pix = pix, .rng = rng};
    trace_camera_path(&c, o, dir);
}

int path_tracer_pass(const scene *s, const render_plan *p, const eda_set *eda, film *f, uint64_t seed,
                     long pass, const dp_stop_flag *stop, render_stats *st, dp_error *err)
{
    pt_pass pp = {.s = s, .p = p, .eda = eda, .deriv = deriv_on(&p->deriv) ? &p->deriv : NULL};
    pp.geom = pp.deriv && pp.deriv->geom;
    if (pt_pass_aim_init(&pp, err)) return -1;
    st->rays += film_sample_pixels(f, &s->cam, seed, pass, stop, sample_pixel, &pp);
    pt_shadow_surfaces(&pp, f, seed, pass);
    pt_pass_aim_free(&pp);
    return 0;
}
