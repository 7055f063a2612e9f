/* The photon pass (baseline photon points): light paths from the emitters (include/dartspp/emitter.h), photons stored at medium
 * scattering vertices and at surface hits whose BSDF has gathered lobes (surface_photon_split). Paths are traced in batches in parallel into per-thread buffers
 * and merged in path order, so budgets are cut by path index and the result is thread-count independent. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/darts.h"
#include "dartspp/photon.h"
#include "dartspp/scene.h"
#include "dartspp/surface_site.h"
#include "photon_internal.h"


static void make_photon(photon *ph, vec3 x, vec3 d, vec3 beta, int bounce, double time, int frame)
{
    ph->pos[0] = (float)x.x, ph->pos[1] = (float)x.y, ph->pos[2] = (float)x.z;
    ph->dir[0] = (float)d.x, ph->dir[1] = (float)d.y, ph->dir[2] = (float)d.z;
    ph->power[0] = (float)beta.x, ph->power[1] = (float)beta.y, ph->power[2] = (float)beta.z;
    ph->bounce = bounce;
    ph->frame = frame;
    ph->time = time;
}

/* One light path in flight: where it is, what it carries, and (DARTS) the bin it aims at. */
typedef struct {
    const scene *s;
    const photon_pass_input *in;
    const darts_guide *g;  /* &in->guide; g->active: DARTS samplers on */
    thread_bufs *tb;
    path_count *pc;
    dp_rng *rng;
    int volume_open;       /* the volume budget still has room (decided per batch, in path order) */
    darts_bin bin;         /* target bin; gate mode: the gate with pdf 1 */
    darts_bin reach;       /* the bin widened by the surface slack: the early exit's bound */
    ellipse_record rec;    /* of the current vertex (DARTS, in a medium) */
    cv_techniques cvt;     /* g->cv_multi: the records of every focus at the current vertex (cvt.rec[0] = rec) */
    /* camera-side control vertices (g->film.on): the medium vertex the current segment leaves, if it is one */
    int ccv;               /* 1: the segment leaves a medium vertex (its direction drawn by the phase or EDA) */
    vec3 ccv_w_in;         /* the direction that arrived there */
    vec3 ccv_beta;         /* the throughput there before the direction's weight f/p_ω */
    double ccv_dir_pdf;    /* p_ω of the segment's direction */
    vec3 o, d, beta;
    int med, bounce, medium_events;
    double time;
    /* the last light-path vertex (null surfaces are none): what the next vertex and beam record of it */
    int vkind;             /* path_vertex_kind, -1 before the first */
    unsigned vflags;       /* its PATH_VERTEX_* */
    vec3 vpos, vw_in;
    double vseg;           /* the length of the segment that arrived at it */
    int vregion;
    /* derivatives (in->deriv): the light, the offset its time started at, and ∂ ln f, ∂τ of the path so far */
    int light;
    double offset;
    deriv_path dv;
} light_path;

/* A photon at x with the derivative state dv (in->deriv) of the light path up to it, its vertex included. */
static void store(light_path *lp, photon_buf *b, uint32_t *count, vec3 x, vec3 d, vec3 power, int bounce, double t,
                  const deriv_path *dv)
{
    if (v3_is_zero(power)) return;
    photon ph;
    make_photon(&ph, x, d, v3_scale(power, 1.0 / lp->bin.pdf), bounce, t, lp->bin.frame);
    /* checked as stored: a finite double power can still overflow the float record */
    if (!isfinite(ph.power[0]) || !isfinite(ph.power[1]) || !isfinite(ph.power[2]) || !isfinite(ph.time)) {
        lp->tb->nonfinite++;
        return;
    }
    _Alignas(photon_deriv) unsigned char side[sizeof(photon_deriv) + 4 * DIFF_PARAM_MAX * sizeof(float)];
    if (lp->in->deriv) photon_deriv_write(lp->in->deriv, dv, lp->light, lp->offset, side);
    if (buf_push(b, &ph, side, lp->in->deriv_stride)) lp->tb->oom = 1;
    else (*count)++;
}

/* Derivatives: a segment of length len in region med up to the path's next vertex: its transmittance, a factor
 * of f whatever sampled the distance (f/p weights), and its time. */
static void deriv_segment(const light_path *lp, deriv_path *dv, int med, double len)
{
    if (!lp->in->deriv) return;
    deriv_transmittance(lp->in->deriv, dv, med, len);
    deriv_time(lp->in->deriv, dv, med, len);
}

/* The part of the camera film outside the image that camera-side control vertices also cover (a fraction of
 * each half-extent): photons there still reach the image's edge through their radius. */
#define CAMERA_FILM_MARGIN 0.2

/* The DARTS samplers serve the volume map: they run only while its budget has room. */
static int aims_at_volume(const light_path *lp) { return lp->g->active && lp->volume_open; }

/* A medium segment of the light path as it starts (volume_photon_type "beams"): where, which way, with what
 * throughput and at what time; its length is known once the sampler has chosen the next vertex. */
typedef struct {
    vec3 o, d, beta;
    double time;
    unsigned vflags; /* the PATH_VERTEX_* of the vertex it leaves */
    int med, bounce, medium_events, on;
    int long_beam; /* DARTS: to the next surface, whatever distance DA sampling drew */
} beam_start;

/* ---- the light-path vertices of the sliced primitives (photon_pass_input.vertices) ---- */

/* A vertex as the path reaches it: where, what arrives, and what it knows of the vertex before. */
static path_vertex vertex_begin(const light_path *lp, int kind, vec3 pos, vec3 beta_in, int medium_in)
{
    path_vertex v = {.pos = pos, .w_in = kind == PATH_VERTEX_EMITTER ? v3s(0.0) : lp->d,
                     .beta_in = v3_scale(beta_in, 1.0 / lp->bin.pdf), .prev_pos = lp->vpos, .prev_w_in = lp->vw_in,
                     .prev_seg = lp->vseg, .time = lp->time, .light = -1, .kind = kind,
                     .flags = (kind == PATH_VERTEX_VOLUME ? PATH_VERTEX_MEDIUM : 0u) |
                              (lp->vkind == PATH_VERTEX_VOLUME ? PATH_VERTEX_PREV_MEDIUM : 0u) |
                              (lp->vkind == PATH_VERTEX_VOLUME && (lp->vflags & PATH_VERTEX_PREV_MEDIUM)
                                   ? PATH_VERTEX_PREV2_MEDIUM : 0u),
                     .medium_in = medium_in, .medium_out = medium_in, .prev_region = lp->vregion,
                     .bounce = lp->bounce, .medium_events = lp->medium_events};
    return v;
}

/* The vertex once its outgoing direction is drawn (lp->d and lp->beta after the sample; sampled 0: none, the
 * path ends here): recorded while the volume budget has room, and remembered as the path's last vertex. */
static void vertex_end(light_path *lp, path_vertex *v, int sampled, int delta)
{
    v->w_out = sampled ? lp->d : v3s(0.0);
    v->beta_out = sampled ? v3_scale(lp->beta, 1.0 / lp->bin.pdf) : v3s(0.0);
    v->medium_out = sampled ? lp->med : v->medium_in;
    v->flags |= delta ? PATH_VERTEX_DELTA : 0u;
    if (lp->in->vertices && lp->volume_open && v3_is_finite(v->beta_in) && v3_is_finite(v->beta_out)) {
        if (vertex_buf_push(&lp->tb->verts, v)) lp->tb->oom = 1;
        else lp->pc->n_verts++;
    }
    lp->vkind = v->kind;
    lp->vflags = v->flags;
    lp->vseg = v->kind == PATH_VERTEX_EMITTER ? 0.0 : v3_len(v3_sub(v->pos, lp->vpos));
    lp->vpos = v->pos;
    lp->vw_in = v->w_in;
    lp->vregion = v->kind == PATH_VERTEX_VOLUME ? v->medium_in : v->medium_out;
}

static beam_start beam_begin(const light_path *lp)
{
    beam_start b = {.on = 0};
    if (!lp->in->beams || !lp->volume_open || lp->med == MEDIUM_VACUUM) return b;
    const medium *m = &lp->s->media[lp->med];
    /* a scattering point on the beam is the path's next medium event: none past the medium's limit, and
     * low_order_scattering off, none at the first medium event after a light or surface (as photons) */
    if (!medium_scatters(m) || lp->medium_events + 1 > m->max_bounces ||
        (!lp->in->low_order_scattering && lp->medium_events == 0))
        return b;
    /* the bin's probability divides the power as it divides photons' (store) */
    return (beam_start){.o = lp->o, .d = lp->d, .beta = v3_scale(lp->beta, 1.0 / lp->bin.pdf), .time = lp->time,
                        .vflags = lp->vflags, .med = lp->med, .bounce = lp->bounce + 1,
                        .medium_events = lp->medium_events, .on = 1,
                        .long_beam = aims_at_volume(lp)};
}

/* The segment begun at b ends `length` along it (a medium event or a surface; a long beam: the surface, or
 * INFINITY): its beam, cut where its start time plus the leg passes the window's end (no point beyond can
 * count). */
static void beam_end(light_path *lp, const beam_start *b, double length)
{
    if (!b->on || v3_is_zero(b->beta)) return;
    double eta = lp->s->media[b->med].eta;
    if (isfinite(lp->in->t_end) && eta > 0.0) length = dp_fmin(length, (lp->in->t_end - b->time) / eta);
    if (!(length > 0.0) || !isfinite(length)) return; /* a long beam into an endless medium needs the window's end */
    photon_beam bm = {.start = {(float)b->o.x, (float)b->o.y, (float)b->o.z},
                      .dir = {(float)b->d.x, (float)b->d.y, (float)b->d.z},
                      .power = {(float)b->beta.x, (float)b->beta.y, (float)b->beta.z},
                      .length = (float)length, .eta = (float)eta, .medium = b->med, .frame = lp->bin.frame,
                      .long_beam = b->long_beam, .bounce = b->bounce, .from = b->vflags, .time = b->time};
    if (!isfinite(bm.power[0]) || !isfinite(bm.power[1]) || !isfinite(bm.power[2]) || !isfinite(bm.length)) {
        lp->tb->nonfinite++;
        return;
    }
    if (beam_buf_push(&lp->tb->beams, &bm)) lp->tb->oom = 1;
    else lp->pc->n_beams++;
}


/* The records of the camera's mirror images at the current vertex: the same record with the focus moved. */
static void mirror_records(light_path *lp, const medium *m)
{
    const darts_guide *g = lp->g;
    darts_guide moved = *g;
    cv_techniques *ct = &lp->cvt;
    ct->n = 1 + g->focus_count;
    ct->rec[0] = lp->rec;
    ct->defensive = g->cv_defensive;
    for (int k = 0; k <= g->focus_count; k++) ct->share[k] = g->cv_share[k];
    for (int k = 0; k < g->focus_count; k++) {
        moved.cam = g->focus[k];
        ellipse_record_init(&ct->rec[1 + k], &moved, &lp->bin, lp->o, lp->time, m->eta, g->ellipse_residual, v3_avg(m->sigma_t),
                            rng_uniform(lp->rng));
    }
}

/* A new vertex at lp->o: the ellipse record its samplers share (DARTS, inside a medium). */
static void new_vertex(light_path *lp)
{
    lp->ccv = 0; /* medium_event sets it once it has drawn the direction */
    /* unwarped, the control vertex needs no record and DA and EDA are off (plan.c) */
    if (!aims_at_volume(lp) || lp->med == MEDIUM_VACUUM || lp->g->camera_unwarp) return;
    const medium *m = &lp->s->media[lp->med];
    ellipse_record_init(&lp->rec, lp->g, &lp->bin, lp->o, lp->time, m->eta, lp->g->ellipse_residual, v3_avg(m->sigma_t),
                        rng_uniform(lp->rng));
    if (lp->g->cv_multi) mirror_records(lp, m);
}

/* Surface photons with DARTS: the full path time with a straight camera leg lies in [t_lb, t_ub], the leg
 * taking at least η_lb and at most η_ub times its length. The photon is kept when t_lb is before the bin
 * end and, in strict mode, t_ub is not before its start (docs/reference-renderer.md §8.2: the authors
 * use the lower bound for both, which with η > 1 somewhere drops in-gate photons) — both widened by the
 * slack. The gather tests the time again at the gather point x', up to r away, where the camera leg
 * differs by up to η_ub·r: tested only here, at the photon (as the reference does), a photon that counts
 * at x' could be dropped, and the surfaces near the edges of the in-gate band would come out too dark. */
static int surface_time_ok(const light_path *lp, vec3 x)
{
    if (!lp->g->active) return 1;
    double dist = darts_leg_length(lp->g, x);
    double t_lb = lp->time + lp->g->eta_lb * dist, t_ub = lp->time + lp->g->eta_ub * dist;
    double slack = lp->in->surface_slack;
    return t_lb < lp->bin.end + slack && (!lp->g->strict_surfaces || t_ub >= lp->bin.start - slack);
}

static int medium_event(light_path *lp, const medium *m, double t, int darts);

/* p_ω at the medium vertex the segment leaves (lp->ccv): the phase function's, or EDA's mixture. */
static double medium_direction_pdf(const light_path *lp, const medium *m, vec3 w)
{
    const eda_table *et = lp->in->eda ? lp->in->eda->table[lp->med] : NULL;
    return et ? eda_direction_pdf(et, lp->in->eda->alpha[lp->med], &m->phase, lp->ccv_w_in, &lp->rec, w)
              : phase_eval(&m->phase, lp->ccv_w_in, w);
}

/* Density in volume measure of the vertex-side control vertex at y = x + t·w (the technique medium_segment
 * draws along the path's direction): p_ω(w)·p(t)/t², p(t) the density in t of the distance technique. */
static double vertex_side_density(const light_path *lp, double dir_pdf, vec3 w, double tmax, double t)
{
    const darts_guide *g = lp->g;
    double sigma = v3_avg(lp->s->media[lp->med].sigma_t);
    double p_t = g->cv_multi ? cv_techniques_pdf(&lp->cvt, w, tmax, g->control_vertex_mis, g->ellipse_residual, sigma, t)
                             : control_vertex_pdf(&lp->rec, w, t, g->control_vertex_mis, g->ellipse_residual, sigma);
    return dir_pdf * p_t / (t * t);
}

/* The camera-side control vertex of the medium vertex the segment leaves (lp->ccv; docs/darts.md §5.5): y on
 * the record's ellipsoid in a film direction from the camera, seen from the vertex (nothing before it along
 * the way), stored with f/(p_vertex + p_camera) in volume measure,
 *   f(y) = β₀·f_p(ω_in, ω)·σs·e^{−σt·t}/t²  (the balance heuristic over the two techniques). */
static void camera_side_control_vertex(light_path *lp, const medium *m)
{
    const darts_guide *g = lp->g;
    double u1 = rng_uniform(lp->rng), u2 = rng_uniform(lp->rng), u3 = rng_uniform(lp->rng), p_cam;
    vec3 y;
    if (!camera_control_vertex(&lp->rec, &g->film, u1, u2, u3, &y, &p_cam)) return;
    vec3 to_y = v3_sub(y, lp->o);
    double t = v3_len(to_y);
    if (!(t > 0.0)) return;
    vec3 w = v3_scale(to_y, 1.0 / t);
    hit_record h;
    double tmax = scene_intersect(lp->s, lp->o, w, INFINITY, &h) ? h.t : INFINITY;
    if (!(t < tmax)) return; /* a surface between: the vertex does not see y */
    double p_vertex = vertex_side_density(lp, medium_direction_pdf(lp, m, w), w, tmax, t);
    double f = phase_eval(&m->phase, lp->ccv_w_in, w) / (t * t);
    vec3 tr = v3_mul(m->sigma_s, v3_exp_neg(v3_scale(m->sigma_t, t)));
    vec3 power = v3_scale(v3_mul(lp->ccv_beta, tr), f / (p_vertex + p_cam));
    store(lp, &lp->tb->vol, &lp->pc->n_vol, y, w, power, lp->bounce + 1, lp->time + m->eta * t, &lp->dv);
}

/* One medium segment up to tmax: the control vertex (elliptical), then the distance sample. Returns 1 for
 * a medium event (lp advanced to the scattering vertex), 0 for the surface at tmax, -1 to end the path. */
static int medium_segment(light_path *lp, double tmax)
{
    const darts_guide *g = lp->g;
    const medium *m = &lp->s->media[lp->med];
    /* nothing to aim where nothing scatters, or once no volume photon can be stored */
    int darts = aims_at_volume(lp) && medium_scatters(m);
    if (darts && g->enable_elliptical && !lp->in->beams) { /* beams cover the segment: no control vertex */
        double t, pdf;
        double sigma = v3_avg(m->sigma_t), u1 = rng_uniform(lp->rng), u2 = rng_uniform(lp->rng);
        int made;
        if (g->camera_unwarp) {
            made = sphere_control_vertex(lp->time, m->eta, &lp->bin, tmax, sigma, u1, &t, &pdf);
        } else if (g->cv_multi) {
            const double u[3] = {u1, u2, rng_uniform(lp->rng)};
            made = cv_techniques_sample(&lp->cvt, lp->d, tmax, g->control_vertex_mis, g->ellipse_residual, sigma, u, &t, &pdf);
        } else {
            made = g->control_vertex_mis ? control_vertex_sample(&lp->rec, lp->d, tmax, g->ellipse_residual, sigma, u1, u2, &t, &pdf)
                                         : ellipse_control_vertex(&lp->rec, lp->d, tmax, &t, &pdf);
        }
        if (made) { /* W = σs e^{−σt t}/p(t) (docs/darts.md §5.2) */
            vec3 w = v3_scale(v3_mul(m->sigma_s, v3_exp_neg(v3_scale(m->sigma_t, t))), 1.0 / pdf);
            vec3 y = v3_add(lp->o, v3_scale(lp->d, t));
            if (lp->ccv) { /* the balance heuristic against the camera-side technique (docs/darts.md §5.5) */
                double p_vertex = lp->ccv_dir_pdf * pdf / (t * t);
                double p_cam = camera_control_vertex_pdf(&lp->rec, &g->film, y, g->ellipse_residual, sigma);
                w = v3_scale(w, p_vertex / (p_vertex + p_cam));
            }
            deriv_path cv = lp->dv; /* the control vertex's segment and σs: factors of its photon only */
            if (lp->in->deriv) {
                deriv_segment(lp, &cv, lp->med, t);
                deriv_medium_vertex(lp->in->deriv, &cv, lp->med);
            }
            store(lp, &lp->tb->vol, &lp->pc->n_vol, y, lp->d, v3_mul(lp->beta, w), lp->bounce + 1, lp->time + m->eta * t,
                  &cv);
        }
        if (lp->ccv) camera_side_control_vertex(lp, m);
    }
    int event;
    double t;
    if (darts && g->enable_guiding && (lp->rec.valid || lp->rec.S_reach > lp->rec.C)) {
        da_sample ds;
        da_sample_distance(m, &lp->rec, lp->d, tmax, g->da_defensive, lp->rng, &ds);
        lp->beta = v3_mul(lp->beta, ds.weight);
        t = ds.t;
        event = ds.medium_event;
    } else {
        t = medium_sample_free_flight(m, tmax, lp->rng, &lp->beta, &event);
    }
    if (!event) return 0;
    return medium_event(lp, m, t, darts);
}

/* DARTS early exit along the current ray: the distance past which a vertex could no longer reach the
 * bin, τ + η_lb·(h + |o + h·d − cam|) = end (the test of darts_can_reach at each vertex, with the segment
 * itself also taken at the least η: a bound for any η); INFINITY where there is no early exit. */
static double reach_distance(const light_path *lp)
{
    const darts_guide *g = lp->g;
    if (!g->active || !g->early_exit) return INFINITY;
    if (g->camera_unwarp) return dp_fmax(0.0, (lp->reach.end - lp->time) / g->eta_lb); /* τ + η_lb·h = end */
    vec3 to_cam = v3_sub(g->cam, lp->o);
    double C = v3_len(to_cam);
    return darts_reach_along((lp->reach.end - lp->time) / g->eta_lb, C, C > 0.0 ? v3_dot(lp->d, to_cam) / C : 0.0);
}

/* The plain free-flight segment (no DARTS sampler: the volume budget is full, or DARTS is off) in a grey
 * medium, with the distance drawn before the ray is traced and the ray traced only that far, and no
 * farther than the early exit's reach: the same draws and the same photons as medium_segment, at less
 * traversal. Returns 1 for a medium event (lp advanced, as medium_segment), 0 with *h the surface before
 * it (*hit), -1 to end the path; 2 when it does not apply (the caller traces the full ray). */
static int free_flight_first(light_path *lp, hit_record *h, int *hit)
{
    const medium *m = &lp->s->media[lp->med];
    double t;
    if ((aims_at_volume(lp) && medium_scatters(m)) || !medium_free_flight_grey(m, lp->rng, &t)) return 2;
    double reach = reach_distance(lp);
    *hit = scene_intersect(lp->s, lp->o, lp->d, t < reach ? t : reach, h);
    if (*hit) return 0;
    if (reach <= t) { /* the next vertex, surface or medium, is out of reach */
        lp->pc->early_exit = 1;
        return -1;
    }
    if (t == INFINITY) return -1; /* nothing scatters and nothing is hit: the path leaves the scene */
    lp->beta = medium_grey_event_beta(m, lp->beta);
    return medium_event(lp, m, t, 0);
}

/* A medium event at distance t of the current ray: the vertex, a classic photon, the next direction. */
static int medium_event(light_path *lp, const medium *m, double t, int darts)
{
    const photon_pass_input *in = lp->in;
    const darts_guide *g = lp->g;
    lp->o = v3_add(lp->o, v3_scale(lp->d, t));
    lp->time += m->eta * t;
    deriv_segment(lp, &lp->dv, lp->med, t);
    if (in->deriv) deriv_medium_vertex(in->deriv, &lp->dv, lp->med); /* σs of the event weight */
    lp->bounce++;
    if (++lp->medium_events > m->max_bounces) return -1;
    /* classic photons (no control vertices); low_order_scattering off: none at the first vertex after a
     * light or surface */
    if (lp->volume_open && !in->beams && !(darts && g->enable_elliptical) && (in->low_order_scattering || lp->medium_events > 1))
        store(lp, &lp->tb->vol, &lp->pc->n_vol, lp->o, lp->d, lp->beta, lp->bounce, lp->time, &lp->dv);
    new_vertex(lp);
    vec3 w_in = lp->d;
    path_vertex v = vertex_begin(lp, PATH_VERTEX_VOLUME, lp->o, lp->beta, lp->med);
    const eda_table *et = darts && in->eda ? in->eda->table[lp->med] : NULL;
    vec3 beta0 = lp->beta;
    if (et) { /* EDA with MIS against the phase function (docs/darts.md §8.2) */
        double u[4], w;
        for (int k = 0; k < 4; k++) u[k] = rng_uniform(lp->rng);
        lp->d = eda_sample_direction(et, in->eda->alpha[lp->med], &m->phase, lp->d, &lp->rec, u, &w);
        lp->beta = v3_scale(lp->beta, w);
    } else {
        double u1 = rng_uniform(lp->rng), u2 = rng_uniform(lp->rng);
        lp->d = phase_sample(&m->phase, lp->d, u1, u2);
    }
    if (darts && g->film.on && lp->rec.valid) {
        lp->ccv = 1;
        lp->ccv_w_in = w_in;
        lp->ccv_beta = beta0;
        lp->ccv_dir_pdf = medium_direction_pdf(lp, m, lp->d);
    }
    if (in->deriv) deriv_phase(in->deriv, &lp->dv, lp->med, w_in, lp->d); /* f/p weights of either sampler */
    vertex_end(lp, &v, 1, 0);
    return 1;
}

/* At a surface the path reached straight from a light that emitter_connects_exactly, with
 * surface_direct_connections: the sensor pass connects that light at every gathered surface, so the photon
 * here would count the direct light twice (docs/defaults.md §3.8). lp->bounce is already this vertex's. */
static int direct_by_connection(const light_path *lp)
{
    return lp->in->surface_direct && lp->bounce == 1 && emitter_connects_exactly(&lp->s->lights[lp->light]);
}

/* Scattering at a surface hit: a surface photon where the BSDF has lobes the sensor pass gathers
 * (surface_photon_split), then the adjoint BSDF sample. Returns 0 to end the path. */
static int surface_event(light_path *lp, const hit_record *h)
{
    const scene *s = lp->s;
    const surface *sf = &s->surfaces[h->surface];
    const bsdf *b = &s->bsdfs[sf->bsdf];
    if (bsdf_is_passthrough(b)) {
        vec3 n_out = v3_dot(lp->d, h->ng) < 0.0 ? v3_neg(h->ng) : h->ng; /* the far side */
        lp->med = surface_next_medium(sf, lp->med, lp->d, h->ng);
        lp->o = scene_offset_ray_origin(lp->s, h->p, n_out);
        new_vertex(lp);
        return 1;
    }
    lp->bounce++;
    lp->medium_events = 0;
    surface_site ss;
    if (!surface_site_init(&ss, s, &lp->in->shading, h, lp->d)) return 0;
    if (surface_photon_split(b, &lp->in->shading).gather && lp->in->include_surfaces && !direct_by_connection(lp) &&
        surface_time_ok(lp, h->p))
        store(lp, &lp->tb->surf, &lp->pc->n_surf, h->p, lp->d, surface_photon_power(&ss, lp->beta), lp->bounce,
              lp->time, &lp->dv);
    path_vertex v = vertex_begin(lp, PATH_VERTEX_SURFACE, h->p, lp->beta, lp->med);
    v.hit = *h;
    double u[3] = {rng_uniform(lp->rng), rng_uniform(lp->rng), rng_uniform(lp->rng)};
    surface_sample smp;
    if (!surface_sample_bsdf(&ss, u, BSDF_LOBES_ALL, 1, &smp)) {
        vertex_end(lp, &v, 0, 0); /* a ball here still evaluates the BSDF */
        return 0;
    }
    lp->beta = v3_mul(lp->beta, smp.weight);
    if (lp->in->deriv) deriv_surface_vertex(lp->in->deriv, &lp->dv, sf->bsdf); /* the albedo in f·|cos|/p */
    lp->d = smp.w;
    lp->med = surface_next_medium(sf, lp->med, lp->d, h->ng);
    lp->o = surface_spawn(s, &ss, lp->d);
    vertex_end(lp, &v, 1, smp.lobe == BSDF_LOBE_SPECULAR);
    new_vertex(lp);
    return 1;
}

/* One light path; bounce = segments from the light. Stops when no later photon could count: past the
 * window end, or (DARTS) when even a straight line to the camera arrives after the target bin (early exit).
 * Once the volume budget is full (volume_open = 0) the path only feeds surface photons, so it is traced with
 * plain free flight and phase sampling: every sampler is unbiased, and DA, control vertices and EDA only pay
 * off for the volume map. Bin sampling, the surface time test and the early exit stay on. */
void trace_light_path(const scene *s, const photon_pass_input *in, int volume_open, dp_rng *rng, thread_bufs *tb,
                      path_count *pc)
{
    const darts_guide *g = &in->guide;
    double sel_pdf = 1.0;
    int li = emitter_select(s, rng_uniform(rng), in->light_selection == LIGHT_SELECTION_POWER, &sel_pdf);
    const emitter *L = &s->lights[li];
    double tau0 = path_time_offset(s, L, rng); /* the path's time starts at its emission */
    /* the start: a light with a position of its own draws it first, so that the bin is drawn from it; a
     * point draws only its direction, after the bin (the draws of a scene of point lights are unchanged) */
    emitter_ray er;
    double u[4] = {0.0, 0.0, 0.0, 0.0};
    int fixed = (L->flags & EMITTER_STARTS_AT_POS) != 0, n = L->ops->ray_uniforms;
    if (!fixed) {
        for (int k = 0; k < n; k++) u[k] = rng_uniform(rng);
        emitter_sample_ray(s, L, u, &er);
    }
    vec3 start = fixed ? L->pos : er.p;
    light_path lp = {.s = s, .in = in, .g = g, .tb = tb, .pc = pc, .rng = rng, .o = start, .med = L->medium,
                     .volume_open = volume_open, .time = tau0, .vkind = -1, .vregion = MEDIUM_VACUUM,
                     .light = li, .offset = tau0,
                     .bin = {.start = -INFINITY, .end = INFINITY, .pdf = 1.0, .frame = -1}};
    if (g->active && !darts_sample_bin(g, start, tau0, rng_uniform(rng), &lp.bin)) return;
    lp.reach = lp.bin; /* the early exit keeps every path whose surface photons could still count */
    lp.reach.end += in->surface_slack;
    if (fixed) {
        for (int k = 0; k < n; k++) u[k] = rng_uniform(rng);
        emitter_sample_ray(s, L, u, &er);
    }
    lp.d = er.d;
    if (!v3_is_zero(er.n)) lp.o = scene_offset_ray_origin(s, er.p, er.n); /* off an area light's surface */
    lp.beta = v3_scale(er.flux, 1.0 / sel_pdf);
    if (in->vertices) { /* the emitter's point: a ball there evaluates its emission (emitter_connect_point) */
        path_vertex v = vertex_begin(&lp, PATH_VERTEX_EMITTER, er.p, v3s(1.0 / sel_pdf), L->medium);
        v.light = li;
        v.ep = (emitter_point){.y = er.p, .n = er.n, .pdf_a = L->area > 0.0 ? 1.0 / L->area : 1.0};
        int ball = emitter_connectable(L) && !emitter_is_parallel_beam(L) && !(L->flags & EMITTER_AIM_PER_CONNECTION);
        vertex_end(&lp, &v, 1, !ball);
    }
    new_vertex(&lp);
    while (lp.bounce + 1 < in->max_bounces && lp.time < in->t_end && !v3_is_zero(lp.beta)) {
        if (g->active && g->early_exit && !darts_can_reach(g, &lp.reach, lp.o, lp.time)) {
            pc->early_exit = 1;
            return;
        }
        hit_record h;
        beam_start bs = beam_begin(&lp);
        int hit = 0, ev = lp.med != MEDIUM_VACUUM ? free_flight_first(&lp, &h, &hit) : 2;
        if (ev < 0) return;
        if (ev == 2) {
            hit = scene_intersect(s, lp.o, lp.d, INFINITY, &h);
            if (lp.med != MEDIUM_VACUUM) {
                ev = medium_segment(&lp, hit ? h.t : INFINITY);
                if (ev < 0) return;
            }
        }
        if (ev == 1) { /* a medium event: lp moved to it along the segment; a long beam goes on to the surface
                        * (DARTS: the segment was traced to it first, in the ev == 2 branch) */
            beam_end(&lp, &bs, bs.long_beam ? (hit ? h.t : INFINITY) : v3_dot(v3_sub(lp.o, bs.o), bs.d));
            continue;
        }
        if (!hit) return;
        beam_end(&lp, &bs, h.t);
        lp.time += medium_eta(s, lp.med) * h.t;
        deriv_segment(&lp, &lp.dv, lp.med, h.t);
        if (!surface_event(&lp, &h)) return;
    }
}

typedef struct {
    size_t budget;
    int full;      /* a path did not fit: no more paths are counted or stored */
    long paths;    /* complete leading paths */
} budget_state;

typedef struct {
    budget_state bv, bsf;
    photon_buf vol, surf;
    beam_buf beams;    /* photon_pass_input.beams: under the volume budget (bv) */
    vertex_buf verts;  /* photon_pass_input.vertices: under the volume budget, with the same paths' beams */
    long next;         /* independent light paths traced */
    long early, aimed;
    int interrupted;
    photon_chain_stats chains; /* the merged surface chains */
} pass_totals;

/* Where one path's (or chain's) records go in the merged arrays; NO_DEST where the budget dropped them. */
typedef struct {
    size_t vol, surf, beams, verts;
} path_dest;

#define NO_DEST SIZE_MAX

/* Claims n slots of a budget in path order: the slot's start, or NO_DEST once a path did not fit (the budget
 * is then full: no later path is counted or stored). */
static size_t claim(budget_state *bs, size_t *count, size_t n)
{
    if (bs->full) return NO_DEST;
    if (*count + n > bs->budget) {
        bs->full = 1;
        return NO_DEST;
    }
    size_t at = *count;
    *count += n;
    bs->paths++;
    return at;
}

/* The batch's destinations in path order: a prefix sum over its counts (serial, but only over numbers; the
 * copies then run in parallel, merge_copy). With vertices the path's beams go with them under the volume
 * budget. Returns -1 when the merged arrays cannot grow. */
static int merge_plan(pass_totals *pt, const photon_pass_input *in, const path_count *pc, long nb, path_dest *pd)
{
    size_t n_vol = pt->vol.n, n_surf = pt->surf.n, n_beams = pt->beams.n, n_verts = pt->verts.n;
    for (long i = 0; i < nb; i++) {
        const path_count *c = &pc[i];
        path_dest d = {NO_DEST, NO_DEST, NO_DEST, NO_DEST};
        pt->early += c->early_exit;
        if (in->vertices) {
            d.verts = claim(&pt->bv, &n_verts, c->n_verts);
            if (d.verts != NO_DEST) d.beams = n_beams, n_beams += c->n_beams;
        } else if (in->beams) {
            d.beams = claim(&pt->bv, &n_beams, c->n_beams);
        } else {
            d.vol = claim(&pt->bv, &n_vol, c->n_vol);
        }
        d.surf = claim(&pt->bsf, &n_surf, c->n_surf);
        pd[i] = d;
    }
    size_t stride = in->deriv_stride;
    if (buf_reserve(&pt->vol, n_vol, stride) || buf_reserve(&pt->surf, n_surf, stride) ||
        beam_buf_reserve(&pt->beams, n_beams) || vertex_buf_reserve(&pt->verts, n_verts))
        return -1;
    pt->vol.n = n_vol, pt->surf.n = n_surf, pt->beams.n = n_beams, pt->verts.n = n_verts;
    return 0;
}

/* n photons (and their derivative records) from a thread buffer to their place in the merged array */
static void copy_photons(photon_buf *dst, size_t at, const photon_buf *src, size_t off, size_t n, size_t stride)
{
    if (at == NO_DEST || n == 0) return;
    memcpy(dst->p + at, src->p + off, n * sizeof(photon));
    if (stride) memcpy(dst->d + at * stride, src->d + off * stride, n * stride);
}

/* The batch's records to the places merge_plan gave them, in parallel over paths: the merged arrays are in
 * path order whatever the thread count. */
static void merge_copy(pass_totals *pt, const photon_pass_input *in, const thread_bufs *tb, const path_count *pc,
                       const path_dest *pd, long nb, int nt)
{
    size_t stride = in->deriv_stride;
#pragma omp parallel for num_threads(nt) schedule(static, 256) default(none) shared(pt, tb, pc, pd, nb, stride)
    for (long i = 0; i < nb; i++) {
        const thread_bufs *src = &tb[pc[i].thread];
        copy_photons(&pt->vol, pd[i].vol, &src->vol, pc[i].off_vol, pc[i].n_vol, stride);
        copy_photons(&pt->surf, pd[i].surf, &src->surf, pc[i].off_surf, pc[i].n_surf, stride);
        if (pd[i].beams != NO_DEST && pc[i].n_beams)
            memcpy(pt->beams.p + pd[i].beams, src->beams.p + pc[i].off_beams, pc[i].n_beams * sizeof(photon_beam));
        if (pd[i].verts != NO_DEST && pc[i].n_verts)
            memcpy(pt->verts.p + pd[i].verts, src->verts.p + pc[i].off_verts, pc[i].n_verts * sizeof(path_vertex));
    }
}

static void scale_powers(photon *p, size_t n, long paths)
{
    float inv = paths > 0 ? (float)(1.0 / paths) : 0.0f;
#pragma omp parallel for schedule(static) default(none) shared(p, n, inv)
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) p[i].power[c] *= inv;
}

void photon_pass_input_init(photon_pass_input *in, const scene *s, const render_plan *p, const eda_set *eda,
                            uint64_t seed, long iteration, const dp_stop_flag *stop)
{
    *in = (photon_pass_input){.light_paths = p->photon_count, .volume_budget = p->volume_photon_count,
                              .surface_budget = p->photon_count, .light_selection = p->light_selection,
                              .max_bounces = p->bounces.max,
                              .t_end = plan_window_end(p, iteration),
                              .include_surfaces = p->include_surfaces, .low_order_scattering = p->low_order_scattering,
                              .surface_direct = p->surface_direct,
                              .beams = p->volume_photon_type != VOLUME_PHOTON_POINTS,
                              .vertices = volume_type_sliced(p->volume_photon_type),
                              .surface_chains = p->surface_chains, .chain_share = p->chain_share,
                              .surface_slack = plan_surface_slack(p, iteration), .shading = p->shading,
                              .eda = eda, .seed = seed,
                              .deriv = deriv_on(&p->deriv) ? &p->deriv : NULL,
                              .deriv_stride = deriv_on(&p->deriv) ? photon_deriv_stride(p->deriv.count) : 0,
                              .iteration = iteration, .stop = stop};
    darts_guide_init(&p->darts, &p->window, s->cam.pos, &in->guide);
    /* camera-side control vertices: volume photons (not beams or vertices), and no derivative records (their
     * photons would need the derivative state of a direction the path did not take) */
    if (p->darts.camera_control_vertices && !in->beams && !in->vertices && !in->deriv &&
        camera_film_init(&in->guide.film, &s->cam, CAMERA_FILM_MARGIN)) {
        in->guide.film.share = CAMERA_CV_SHARE;
        /* ρ_thin: CAMERA_CV_THIN times where a disc of the first volume radius spans the film's half-width
         * (x = 1 at plane_dist) */
        double r0 = p->r_vol.r0;
        in->guide.film.thin = isfinite(r0) && r0 < 1e10 ? CAMERA_CV_THIN * r0 * s->cam.plane_dist : 0.0;
    }
}

/* Light paths in independent batches; with surface chains on, they stop once the volume budget is full. */
static int independent_paths(const scene *s, const photon_pass_input *in, int nt, thread_bufs *tb, path_count *pc,
                             path_dest *pd, int chains, pass_totals *pt)
{
    long max_paths = (long)in->light_paths;
    const darts_guide *guide = &in->guide;
    int rc = 0;
    while (!rc && pt->next < max_paths && !(pt->bv.full && pt->bsf.full) && !(chains && pt->bv.full)) {
        if ((pt->interrupted = dp_stopped(in->stop))) break; /* read once per batch */
        long nb = max_paths - pt->next < PHOTON_PASS_BATCH ? max_paths - pt->next : PHOTON_PASS_BATCH;
        pt->aimed += guide->active && !pt->bv.full ? nb : 0;
        long next = pt->next;
        int open = !pt->bv.full;
#pragma omp parallel num_threads(nt)
        {
            thread_bufs *mine = &tb[omp_get_thread_num()];
            mine->vol.n = mine->surf.n = mine->beams.n = mine->verts.n = 0;
#pragma omp for schedule(dynamic, 64) /* paths differ in length; any thread may trace any path */
            for (long i = 0; i < nb; i++) {
                dp_rng rng = rng_stream(in->seed ^ 0x70686f746f6eULL, (uint64_t)in->iteration, (uint64_t)(next + i));
                /* counted in a local and stored once: neighbouring entries belong to other threads */
                path_count c = {.thread = omp_get_thread_num(), .off_vol = mine->vol.n, .off_surf = mine->surf.n,
                                .off_beams = mine->beams.n, .off_verts = mine->verts.n};
                trace_light_path(s, in, open, &rng, mine, &c);
                pc[i] = c;
            }
        }
        rc = merge_plan(pt, in, pc, nb, pd); /* merged in path order */
        if (!rc) merge_copy(pt, in, tb, pc, pd, nb, nt);
        pt->next += nb;
    }
    return rc;
}

static void chain_stats_add(photon_chain_stats *sum, const photon_chain_stats *c)
{
    sum->traced += c->traced;
    sum->large += c->large;
    sum->visible += c->visible;
    sum->states += c->states;
    sum->small += c->small;
    sum->accepted += c->accepted;
    sum->early_exits += c->early_exits;
}

/* The chains' photons to the surface array in chain order, under the surface budget (a chain that does not fit
 * closes it and is dropped, with its statistics): the places first, serial over counts, then the copies in
 * parallel. */
static int merge_chains(pass_totals *pt, const photon_pass_input *in, const thread_bufs *tb, const chain_count *cc,
                        size_t *at, int nb, int nt)
{
    size_t n_surf = pt->surf.n, stride = in->deriv_stride;
    for (int i = 0; i < nb; i++) {
        at[i] = claim(&pt->bsf, &n_surf, cc[i].n);
        if (at[i] != NO_DEST) chain_stats_add(&pt->chains, &cc[i].st);
    }
    if (buf_reserve(&pt->surf, n_surf, stride)) return -1;
    pt->surf.n = n_surf;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1) default(none) shared(pt, tb, cc, at, nb, stride)
    for (int i = 0; i < nb; i++) copy_photons(&pt->surf, at[i], &tb[cc[i].thread].surf, cc[i].off, cc[i].n, stride);
    return 0;
}

/* The rest of the light paths as surface chains of CHAIN_STEPS paths each, at least CHAIN_BATCH chains (and 8
 * per thread, so that the chains' unequal lengths even out before the barrier) between two merges; a chain's
 * photons are kept whole or not at all (the surface budget), in chain order: the batch size changes no result. */
#define CHAIN_STEPS 1024
#define CHAIN_BATCH 32
static int chain_paths(const scene *s, const photon_pass_input *in, int nt, thread_bufs *tb, pass_totals *pt)
{
    /* surface_paths "auto": a share of the paths left (photon_points_choose_chain_share); the chain photons
     * stand for the paths the chains traced, so any share keeps the surface map's expectation */
    double share = in->chain_share > 0.0 && in->chain_share < 1.0 ? in->chain_share : 1.0;
    long left = (long)ceil(((double)(long)in->light_paths - (double)pt->next) * share);
    long n_chains = (left + CHAIN_STEPS - 1) / CHAIN_STEPS;
    int batch = 8 * nt > CHAIN_BATCH ? 8 * nt : CHAIN_BATCH;
    chain_count *cc = malloc((size_t)batch * sizeof *cc);
    size_t *at = malloc((size_t)batch * sizeof *at);
    chain_scratch **cs = calloc((size_t)nt, sizeof *cs);
    int rc = cs && cc && at ? 0 : -1;
    for (int t = 0; t < nt && !rc; t++) rc = (cs[t] = chain_scratch_new()) ? 0 : -1;
    for (long c0 = 0; !rc && c0 < n_chains && !pt->bsf.full; c0 += batch) {
        if ((pt->interrupted = dp_stopped(in->stop))) break;
        int nb = n_chains - c0 < batch ? (int)(n_chains - c0) : batch;
#pragma omp parallel num_threads(nt)
        {
            int me = omp_get_thread_num();
            tb[me].surf.n = 0;
#pragma omp for schedule(dynamic, 1)
            for (int i = 0; i < nb; i++) {
                long c = c0 + i, steps = left - c * CHAIN_STEPS < CHAIN_STEPS ? left - c * CHAIN_STEPS : CHAIN_STEPS;
                chain_count count = {.thread = me}; /* counted locally: cc[i ± 1] are other threads' */
                surface_chain_run(s, in, c, (int)steps, cs[me], &tb[me], &count);
                cc[i] = count;
            }
        }
        rc = merge_chains(pt, in, tb, cc, at, nb, nt);
    }
    for (int t = 0; cs && t < nt; t++) chain_scratch_free(cs[t]);
    free(cs);
    free(cc);
    free(at);
    return rc;
}

int photon_pass_uses_chains(const photon_pass_input *in)
{
    return in->surface_chains && in->guide.active && in->include_surfaces;
}

int photon_pass(const scene *s, const photon_pass_input *in, photon_set *out, dp_error *err)
{
    memset(out, 0, sizeof *out);
    if (s->light_count == 0) return 0;
    pass_totals pt = {.bv = {.budget = (size_t)in->volume_budget}, .bsf = {.budget = (size_t)in->surface_budget}};
    int nt = omp_get_max_threads();
    thread_bufs *tb = dp_calloc_cache_aligned((size_t)nt, sizeof(thread_bufs));
    path_count *pc = malloc(PHOTON_PASS_BATCH * sizeof(path_count));
    path_dest *pd = malloc(PHOTON_PASS_BATCH * sizeof(path_dest));
    int chains = photon_pass_uses_chains(in);
    int rc = (!tb || !pc || !pd) ? -1 : independent_paths(s, in, nt, tb, pc, pd, chains, &pt);
    size_t n_independent = pt.surf.n; /* surface photons of the independent paths */
    if (!rc && chains && pt.bv.full && !pt.interrupted && pt.next < (long)in->light_paths)
        rc = chain_paths(s, in, nt, tb, &pt);
    out->interrupted = pt.interrupted;
    for (int t = 0; t < nt && tb; t++) {
        out->nonfinite += tb[t].nonfinite;
        rc |= tb[t].oom ? -1 : 0;
        buf_free(&tb[t].vol);
        buf_free(&tb[t].surf);
        free(tb[t].beams.p);
        free(tb[t].verts.p);
    }
    free(tb);
    free(pc);
    free(pd);
    if (rc) {
        buf_free(&pt.vol);
        buf_free(&pt.surf);
        free(pt.beams.p);
        free(pt.verts.p);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory in the photon pass", s->path);
    }
    out->paths = pt.next + pt.chains.traced;
    out->early_exits = pt.early + pt.chains.early_exits;
    out->aimed_paths = pt.aimed;
    out->chain = pt.chains;
    out->vol_paths = pt.bv.full ? pt.bv.paths : pt.next;
    /* the independent paths count once each, the chains as the paths they traced */
    out->surf_paths = (pt.bsf.full && !pt.chains.traced ? pt.bsf.paths : pt.next) + pt.chains.traced;
    scale_powers(pt.vol.p, pt.vol.n, out->vol_paths);
    float inv_paths = out->vol_paths > 0 ? (float)(1.0 / out->vol_paths) : 0.0f;
    for (size_t i = 0; i < pt.beams.n; i++)
        for (int c = 0; c < 3; c++) pt.beams.p[i].power[c] *= inv_paths;
    double inv_vpaths = out->vol_paths > 0 ? 1.0 / (double)out->vol_paths : 0.0;
    for (size_t i = 0; i < pt.verts.n; i++) {
        pt.verts.p[i].beta_in = v3_scale(pt.verts.p[i].beta_in, inv_vpaths);
        pt.verts.p[i].beta_out = v3_scale(pt.verts.p[i].beta_out, inv_vpaths);
    }
    scale_powers(pt.surf.p, n_independent, out->surf_paths);
    if (pt.chains.states > 0) { /* P̂(V)·traced/states: the chain states stand for the paths they replace */
        double p_visible = (double)pt.chains.visible / (double)pt.chains.large;
        double w = p_visible * (double)pt.chains.traced / (double)pt.chains.states / (double)out->surf_paths;
        for (size_t i = n_independent; i < pt.surf.n; i++)
            for (int c = 0; c < 3; c++) pt.surf.p[i].power[c] *= (float)w;
    }
    out->vol = pt.vol.p;
    out->n_vol = pt.vol.n;
    out->vol_deriv = pt.vol.d;
    out->surf_deriv = pt.surf.d;
    out->deriv_stride = in->deriv_stride;
    out->surf = pt.surf.p;
    out->n_surf = pt.surf.n;
    out->beams = pt.beams.p;
    out->n_beams = pt.beams.n;
    out->verts = pt.verts.p;
    out->n_verts = pt.verts.n;
    return 0;
}

double photon_array_bytes(double n)
{
    if (!(n > 0)) return 0;
    if (!isfinite(n)) return HUGE_VAL;
    double cap = PHOTON_BUF_FIRST;
    while (cap < n) cap *= 2;
    return cap * sizeof(photon);
}

double photon_beam_array_bytes(double n)
{
    if (!(n > 0)) return 0;
    if (!isfinite(n)) return HUGE_VAL;
    double cap = PHOTON_BUF_FIRST;
    while (cap < n) cap *= 2;
    return cap * sizeof(photon_beam);
}

double path_vertex_array_bytes(double n)
{
    if (!(n > 0)) return 0;
    if (!isfinite(n)) return HUGE_VAL;
    double cap = PHOTON_BUF_FIRST;
    while (cap < n) cap *= 2;
    return cap * sizeof(path_vertex);
}

void photon_set_free(photon_set *ps)
{
    free(ps->verts);
    free(ps->beams);
    free(ps->vol);
    free(ps->surf);
    free(ps->vol_deriv);
    free(ps->surf_deriv);
    memset(ps, 0, sizeof *ps);
}
