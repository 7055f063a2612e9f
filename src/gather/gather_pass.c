/* The sensor pass of photon points (docs/design.md §2.5; the authors' version and where we depart from it:
 * docs/reference-renderer.md §9). */
#include <stdlib.h>

#include "dartspp/gather.h"
#include "dartspp/surface_site.h"
#include "gather_deriv.h"
#include "primary_line.h"

typedef struct {
    const scene *s;
    const gather_input *g;
    film_pixel *pix;
    dp_rng *rng;     /* continuations through specular and near-specular lobes */
    primary_line *line; /* where the primary line's medium segments are recorded for the splat, or NULL */
} pixel_ctx;

typedef struct {
    const gather_input *g;
    film_pixel *pix;
    const medium *m;
    vec3 o, d;
    vec3 thr;        /* camera throughput up to the segment origin */
    double t_cam;    /* camera time up to the segment origin */
    int b_cam;       /* camera segments including this one */
    const deriv_path *cam; /* derivatives: the camera path's state at o (NULL: none) */
} beam_ctx;

static vec3 photon_vec(const float *v) { return v3(v[0], v[1], v[2]); }

void volume_photon_splat_deriv(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, vec3 thr,
                               double t_cam, int b_cam, const photon *p, double t, double d2, const deriv_path *cam,
                               const photon_deriv *pd)
{
    if (!bounces_count(&g->bounces, p->bounce + b_cam)) return;
    double leg = g->camera_leg_projected ? t : v3_len(v3_sub(photon_vec(p->pos), o));
    if (g->camera_unwarp && b_cam == 1) leg = 0.0; /* the sensor's own segment takes no time */
    double time = t_cam + p->time + m->eta * leg;
    int order = p->bounce + b_cam - 1;
    film_slot slot = film_time_slot(pix->f, time, p->frame, order);
    if (!slot.counts) return;
    vec3 c = volume_photon_splat_slot(g, pix, m, d, thr, p, t, d2, &slot); /* before the kernel and exp */
    if (cam && pd) gather_deriv_volume(g, pix, m, d, cam, p, pd, t, leg, time, c, order);
}

void volume_photon_splat(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, vec3 thr,
                         double t_cam, int b_cam, const photon *p, double t, double d2)
{
    volume_photon_splat_deriv(g, pix, m, o, d, thr, t_cam, b_cam, p, t, d2, NULL, NULL);
}

static void visit_volume_photon(void *ctx, const photon *p, double t, double d2)
{
    const beam_ctx *b = ctx;
    const photon_deriv *pd = b->cam && b->g->vol_deriv
                                 ? photon_deriv_at(b->g->vol_deriv, b->g->deriv_stride, volume_map_source(b->g->vol, p))
                                 : NULL;
    volume_photon_splat_deriv(b->g, b->pix, b->m, b->o, b->d, b->thr, b->t_cam, b->b_cam, p, t, d2, b->cam, pd);
}

/* The gate as the beam query's time window: the path time of volume_photon_splat (the sensor's own segment
 * takes no time when unwarped) and the window [start, start + width·frames) that film_time_slot counts.
 * 0 when the film is not gated: every time counts, nothing to prune. */
static int gate_filter(const gather_input *g, const film *f, const medium *m, double t_cam, int b_cam,
                       beam_time_filter *w)
{
    const time_window *tw = &f->window;
    if (!tw->gated || !(tw->width > 0.0)) return 0; /* gated implies width > 0 (settings.c); lo <= hi relies on it */
    *w = (beam_time_filter){.t0 = t_cam, .eta = g->camera_unwarp && b_cam == 1 ? 0.0 : m->eta,
                            .projected = g->camera_leg_projected, .lo = tw->start, .hi = time_window_end(tw)};
    return 1;
}

void volume_beam_gather(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, double len, vec3 thr,
                        double t_cam, int b_cam, const deriv_path *cam)
{
    beam_ctx b = {g, pix, m, o, d, thr, t_cam, b_cam, g->deriv ? cam : NULL};
    beam_time_filter w;
    if (gate_filter(g, pix->f, m, t_cam, b_cam, &w))
        photon_map_query_beam_window(g->vol, o, d, len, &w, visit_volume_photon, &b);
    else
        photon_map_query_beam(g->vol, o, d, len, visit_volume_photon, &b);
}

/* Keeps a medium segment of the primary line for the splat; 0 when the line is full (then the caller
 * queries it). */
static int record_line_segment(primary_line *L, int med, vec3 o, vec3 d, double len, vec3 thr, double t_cam)
{
    if (L->n >= PRIMARY_SEGMENTS) return 0;
    line_segment *sg = &L->seg[L->n++];
    sg->t0 = v3_dot(v3_sub(o, v3(L->o[0], L->o[1], L->o[2])), d);
    sg->t1 = sg->t0 + len;
    sg->t_cam = t_cam;
    sg->thr[0] = thr.x;
    sg->thr[1] = thr.y;
    sg->thr[2] = thr.z;
    sg->medium = med;
    return 1;
}

/* Surface estimate at a hit, over the gathered lobes: k nearest within R, box kernel over the disc of the
 * k-th; each photon contributes P·f(ω_cam, −ω_p), the BSDF without the cosine (docs/reference-renderer.md §9.4). */
static void gather_surface(pixel_ctx *c, const surface_site *ss, unsigned lobes, vec3 thr, double t_cam, int b_cam,
                           const deriv_path *at)
{
    const gather_input *g = c->g;
    if (!g->surf) return;
    int idx[256];
    double d2[256];
    int k = g->k_surf < 256 ? g->k_surf : 256;
    int n = surface_map_query_knn(g->surf, ss->p, k, g->r_surf, idx, d2);
    if (n == 0) return;
    double r2 = n == k ? d2[n - 1] : g->r_surf * g->r_surf;
    if (!(r2 > 0.0)) return;
    vec3 w = v3_scale(thr, 1.0 / (M_PI * r2));
    for (int i = 0; i < n; i++) {
        const photon *p = &g->surf_photons[idx[i]];
        if (!bounces_count(&g->bounces, p->bounce + b_cam)) continue;
        vec3 f = surface_eval(ss, v3_neg(photon_vec(p->dir)), lobes);
        if (v3_is_zero(f)) continue; /* e.g. arrived on the other side of an opaque surface */
        vec3 v = v3_mul(v3_mul(w, f), photon_vec(p->power));
        film_pixel_splat(c->pix, t_cam + p->time, v, p->frame, p->bounce + b_cam - 1); /* scattering events: the path's segments − 1 */
        if (at && g->surf_deriv)
            gather_deriv_surface(g, c->pix, at, photon_deriv_at(g->surf_deriv, g->deriv_stride, (size_t)idx[i]),
                                 t_cam + p->time, v, p->frame, p->bounce + b_cam - 1);
    }
}

/* Whether a straight light connection of length dist, leaving the camera path at path time t, can land in
 * the film's window: its time lies in [t + η_lb·dist, t + η_ub·dist], widened by a margin for the ray
 * offsets. One that cannot is not traced (the film would drop it): with a narrow gate most are not. */
static int connection_can_count(const pixel_ctx *c, double t, double dist)
{
    const time_window *tw = &c->pix->f->window;
    const gather_input *g = c->g;
    if (!tw->gated || g->deriv || !(g->eta_ub > 0.0)) return 1; /* derivatives: the time kernels reach past it */
    double margin = 1e-4 * (1.0 + dist);
    return t + g->eta_lb * dist - margin < time_window_end(tw) && t + g->eta_ub * dist + margin >= tw->start;
}

/* Direct light by next-event estimation (light → surface → camera), with `lobes` evaluated, to every light
 * that allows it, or (exact_only) to those that emitter_connects_exactly.
 * - At a surface the camera path continues through on a non-delta lobe, for every light: the photons stored
 *   here serve the gathered lobes only. Delta lobes see area lights by hits (hit_emission).
 * - At gathered lobes with surface_direct_connections, for the exact lights only: the photon pass stored no
 *   first-bounce photon of theirs (docs/defaults.md §3.8).
 * At a vertex the camera path reached through a glossy bounce (after_glossy), the lobes are evaluated with
 * α raised to g->alpha_reg: a point light seen in a second glossy reflection is otherwise a highlight that
 * the first bounce's sampling finds by chance (the dragon's fireflies, docs/defaults.md §3.7). */
static void direct_light(pixel_ctx *c, const surface_site *site, unsigned lobes, int exact_only, int med, vec3 thr,
                         double t_cam, int b_cam, int after_glossy, const deriv_path *at)
{
    const scene *s = c->s;
    if (!bounces_count(&c->g->bounces, b_cam + 1)) return;
    /* after a glossy bounce, the lobes are evaluated regularized (docs/defaults.md §3.7) */
    bsdf smooth;
    surface_site regularized;
    const surface_site *ss = site;
    if (after_glossy && c->g->alpha_reg > 0.0) {
        smooth = bsdf_regularized(site->b, c->g->alpha_reg);
        regularized = *site;
        regularized.b = &smooth;
        ss = &regularized;
    }
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        if (!(exact_only ? emitter_connects_exactly(L) : emitter_connectable(L))) continue;
        double u[2] = {0.0, 0.0};
        if (emitter_direct_draws(L)) u[0] = rng_uniform(c->rng), u[1] = rng_uniform(c->rng);
        emitter_direct ed;
        if (!emitter_sample_direct(s, L, ss->p, u, &ed)) continue;
        vec3 f = surface_eval_cos(ss, ed.wi, lobes);
        if (v3_max(f) <= 0.0) continue;
        vec3 tr;
        double offset = path_time_offset(s, L, c->rng), t = t_cam + offset;
        if (!connection_can_count(c, t, v3_len(v3_sub(ed.y, ss->p)))) continue;
        c->pix->rays += 1;
        vec3 target = v3_is_zero(ed.n) ? ed.y
                      : scene_offset_ray_origin(s, ed.y, v3_dot(ed.wi, ed.n) < 0.0 ? ed.n : v3_neg(ed.n));
        deriv_path dv; /* derivatives: the camera's state and the leg's pieces */
        gather_leg leg = {c->g->deriv, &dv};
        if (at) dv = *at;
        int end;
        if (!scene_transmittance_segments(s, surface_spawn(s, ss, ed.wi), surface_medium_toward(ss, med, ed.wi), target,
                                          &tr, &t, &end, at ? gather_deriv_leg : NULL, &leg))
            continue;
        vec3 v = v3_scale(v3_mul(v3_mul(v3_mul(thr, tr), ed.value), f), 1.0 / ed.denom);
        film_pixel_splat(c->pix, t, v, -1, b_cam);
        if (at) deriv_splat(c->g->deriv, c->pix, &dv, i, t, offset, v, -1, b_cam);
    }
}

/* A camera walk hitting an area light from the camera or through delta lobes only: its emission (light
 * that reached the walk otherwise was gathered from photons or connected by direct_light). */
static void hit_emission(pixel_ctx *c, const hit_record *h, vec3 d, vec3 thr, double t_cam, int b_cam,
                         const deriv_path *cam)
{
    const scene *s = c->s;
    int i = s->surfaces[h->surface].emitter;
    if (i < 0 || !bounces_count(&c->g->bounces, b_cam)) return;
    const emitter *L = &s->lights[i];
    vec3 le = emitter_hit_radiance(L, d, h->ng);
    if (v3_is_zero(le)) return;
    double offset = path_time_offset(s, L, c->rng);
    film_pixel_splat(c->pix, t_cam + offset, v3_mul(thr, le), -1, b_cam - 1);
    if (cam) deriv_splat(c->g->deriv, c->pix, cam, i, t_cam + offset, offset, v3_mul(thr, le), -1, b_cam - 1);
}

/* The camera walk: volume gathers along every medium segment; at a surface, the gather over the lobes the
 * photon map carries and a continuation through the others (surface_photon_split), sampled. */
static void trace_sensor_path(pixel_ctx *c, vec3 o, vec3 d)
{
    const scene *s = c->s;
    vec3 thr = v3s(1.0);
    int med = s->cam.medium, b_cam = 1, after_delta = 1, after_glossy = 0;
    double t_cam = 0.0;
    primary_line *line = c->line; /* set while the walk is still on the primary line */
    deriv_path cdv, *cam = c->g->deriv ? &cdv : NULL; /* derivatives: the camera path's state (gather_deriv.h) */
    if (cam) deriv_path_clear(cam);
    if (line) {
        line->o[0] = o.x;
        line->o[1] = o.y;
        line->o[2] = o.z;
        line->d[0] = d.x;
        line->d[1] = d.y;
        line->d[2] = d.z;
        line->n = 0;
    }
    for (int guard = 0; guard < 10000 && b_cam <= c->g->bounces.max; guard++) {
        hit_record h;
        c->pix->rays += 1;
        int hit = scene_intersect(s, o, d, INFINITY, &h);
        double len = hit ? h.t : INFINITY;
        if (med != MEDIUM_VACUUM) {
            const medium *m = &s->media[med];
            if (c->g->vol && !(line && record_line_segment(line, med, o, d, len, thr, t_cam)))
                volume_beam_gather(c->g, c->pix, m, o, d, len, thr, t_cam, b_cam, cam);
            if (c->g->beams) photon_beams_gather(c->g->beams, s, c->pix, med, o, d, len, thr, t_cam, b_cam);
            if (c->g->slices) sliced_primitives_gather(c->g->slices, s, c->pix, med, o, d, len, thr, t_cam, b_cam, c->rng);
            thr = v3_mul(thr, v3_exp_neg(v3_scale(m->sigma_t, len)));
        }
        if (!hit || v3_is_zero(thr)) return;
        int timed = !(c->g->camera_unwarp && b_cam == 1);
        if (timed) t_cam += medium_eta(s, med) * len;
        if (cam) gather_deriv_segment(c->g, cam, med, len, timed);
        const surface *sf = &s->surfaces[h.surface];
        const bsdf *bs = &s->bsdfs[sf->bsdf];
        if (after_delta) hit_emission(c, &h, d, thr, t_cam, b_cam, cam);
        if (bsdf_is_passthrough(bs)) {
            vec3 n_out = v3_dot(d, h.ng) < 0.0 ? v3_neg(h.ng) : h.ng; /* the far side */
            med = surface_next_medium(sf, med, d, h.ng);
            o = scene_offset_ray_origin(s, h.p, n_out);
            continue;
        }
        line = NULL; /* the walk scatters here: later segments are gathered by beam queries */
        surface_site ss;
        if (!surface_site_init(&ss, s, &c->g->shading, &h, d)) return;
        photon_split split = surface_photon_split(bs, &c->g->shading);
        if (cam) deriv_surface_vertex(c->g->deriv, cam, sf->bsdf); /* every estimate here evaluates the BSDF */
        if (split.gather) gather_surface(c, &ss, split.gather, thr, t_cam, b_cam, cam);
        if (split.gather && c->g->surface_direct)
            direct_light(c, &ss, split.gather, 1, med, thr, t_cam, b_cam, after_glossy, cam);
        if (!split.cont) return;
        if (split.cont & ~BSDF_LOBE_SPECULAR)
            direct_light(c, &ss, split.cont, 0, med, thr, t_cam, b_cam, after_glossy, cam);
        double u[3] = {rng_uniform(c->rng), rng_uniform(c->rng), rng_uniform(c->rng)};
        surface_sample smp;
        if (!surface_sample_bsdf(&ss, u, split.cont, 0, &smp)) return;
        thr = v3_mul(thr, smp.weight);
        d = smp.w;
        after_delta = (smp.lobe & BSDF_LOBE_SPECULAR) != 0;
        after_glossy |= !after_delta;
        med = surface_medium_toward(&ss, med, d);
        o = surface_spawn(s, &ss, d);
        b_cam++;
    }
}

typedef struct {
    const scene *s;
    const gather_input *g;
    primary_line *lines; /* per pixel, or NULL */
} pass_ctx;

static void sample_pixel(void *ctx, film_pixel *pix, vec3 o, vec3 dir, dp_rng *rng)
{
    const pass_ctx *p = ctx;
    int step = p->g->row_step;
    if (step > 1 && (pix->px / (size_t)p->s->cam.width) % (size_t)step != 0) { /* a pilot's subsample: not sampled */
        if (p->lines) p->lines[pix->px].n = 0;
        return;
    }
    pixel_ctx c = {.s = p->s, .g = p->g, .pix = pix, .rng = rng, .line = p->lines ? &p->lines[pix->px] : NULL};
    trace_sensor_path(&c, o, dir);
}

/* The fallback when the splat's tile lists would be too big: a beam query per recorded segment. */
static void gather_lines_by_beams(const scene *s, const gather_input *g, film *f, const primary_line *lines)
{
    long bad = 0;
    int w = s->cam.width, h = s->cam.height;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : bad) default(none) shared(s, g, f, lines, w, h)
    for (int y = 0; y < h; y++) {
        if (dp_stopped(g->stop)) continue;
        for (int x = 0; x < w; x++) {
            film_pixel pix = {.f = f, .px = (size_t)y * w + x};
            primary_line_gather_beam(s, g, &pix, &lines[pix.px]);
            bad += pix.nonfinite;
        }
    }
    f->nonfinite += bad;
}

double gather_pass_bytes(const scene *s, int splat, const photon *sample, size_t n, double r, double photons)
{
    double lines = (double)volume_splat_bytes(s->cam.width, s->cam.height);
    return lines + (splat ? volume_splat_scratch_bytes(&s->cam, sample, n, r, photons) : 0.0);
}

/* The camera walks (surface gathers, continuations, beam queries off the primary line), then the volume
 * gather on the primary lines: photon by photon (volume_splat.c) where it applies, else by a beam query
 * per recorded segment (volume_gather "beam", and the splat's fallback). */
double gather_pass(const scene *s, const gather_input *g, film *f, uint64_t seed, long iteration)
{
    pass_ctx p = {s, g, NULL};
    /* NULL: queries in the walk; so with derivatives, whose camera state the walk carries (a primary line would
     * need one per segment) */
    if (g->vol && !g->deriv) p.lines = malloc(volume_splat_bytes(s->cam.width, s->cam.height));
    double rays = film_sample_pixels(f, &s->cam, seed, iteration, g->stop, sample_pixel, &p);
    if (p.lines && !dp_stopped(g->stop)) {
        int splat = g->volume_splat && volume_splat_applies(s, g);
        if (!splat || volume_splat(s, g, f, p.lines)) gather_lines_by_beams(s, g, f, p.lines);
    }
    free(p.lines);
    return rays;
}
