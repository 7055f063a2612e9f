/* Camera paths aimed at a light and a time bin: the DARTS path tracer (the DARTS paper §4–5, supplement
 * Alg. 2) and the uniform-time path tracer (Jarabo et al. 2014 §5 as the DARTS supplement §B.4 corrects it).
 * The samplers are those of the DARTS photon pass (src/darts) with the light, not the camera, as the target:
 * the residual of a camera-path vertex is its light leg, which always counts in the path's time.
 *
 * Per camera path: one light, chosen as light_selection says (docs/emitters.md §5), with its emission time
 * (the pulse) drawn first, then one point of it as the target (docs/emitters.md §6), then its target bin (the gate; in frame mode one frame, uniform in time over the
 * reachable part of the window; uniform time: the whole window). Every contribution of the path goes to that
 * light only and is divided by the two probabilities.
 * Per medium segment (docs/darts.md §14): an ellipse record (fresh residual T), the early exit, the light
 * connection through a control vertex on the segment — which replaces the connection of the medium vertices
 * the segment's distance sample lands on (the two estimate the same term) — then the distance (DA-RIS, the
 * uniform-time distance drawn at the previous vertex, or free flight).
 * Per medium vertex: the direction (EDA with MIS; uniform time: time-angular with MIS; else the phase
 * function); with elliptical connections and ellipse_directions, the next segment's record is drawn at the
 * vertex and the direction mixes in the sampler toward its control vertex (docs/darts.md §14.3). Surface
 * vertices connect to the path's light as in the plain path tracer; with BSDFs without delta lobes their
 * direction mixes the same sampler with BSDF sampling (pt_aim_surface_sample, docs/darts.md §14.4). */
#include <stdlib.h>

#include "path_tracer_internal.h"

/* The DARTS guide of one light: the plan's samplers with the light as target. The light leg always counts
 * (unwarped time only drops the camera segment, pt_unwarped_camera_segment); the mirror foci of the photon
 * pass aim at images of the camera and do not apply. */
static void guide_for_light(const render_plan *p, vec3 light, darts_guide *g)
{
    darts_guide_init(&p->darts, &p->window, light, g);
    g->camera_unwarp = 0;
    g->cv_multi = 0;
    g->focus_count = 0;
    g->strict_surfaces = 0;
    if (!p->uniform_time) return;
    /* uniform time: line-to-point connections (the elliptical vertex with a uniform residual, J14 eq. 14–15)
     * over the whole window, free-flight distances; no bin is sampled */
    g->active = 1;
    g->enable_elliptical = 1;
    g->enable_guiding = 0;
    g->control_vertex_mis = 0;
    g->ellipse_residual = RESIDUAL_UNIFORM;
    g->frames = 0;
}

int pt_pass_aim_init(pt_pass *pp, dp_error *err)
{
    const render_plan *p = pp->p;
    const scene *s = pp->s;
    pp->aimed = (p->darts.active || p->uniform_time) && s->light_count > 0;
    if (!pp->aimed) return 0;
    int n = s->light_count;
    pp->guide = calloc((size_t)n, sizeof *pp->guide);
    pp->light_cdf = calloc((size_t)n, sizeof *pp->light_cdf);
    if (!pp->guide || !pp->light_cdf) {
        pt_pass_aim_free(pp);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the path tracer's light guides", s->path);
    }
    /* a light the path tracer cannot reach (a radius-0 parallel beam) is never chosen: its paths would
     * contribute nothing, and leaving it out changes no expectation */
    double acc = 0.0;
    for (int i = 0; i < n; i++) {
        guide_for_light(p, s->lights[i].pos, &pp->guide[i]);
        if (emitter_connectable(&s->lights[i])) acc += emitter_selection_pdf(s, i, p->light_selection == LIGHT_SELECTION_POWER);
        pp->light_cdf[i] = acc;
    }
    for (int i = 0; i < n; i++) pp->light_cdf[i] = acc > 0.0 ? pp->light_cdf[i] / acc : (i + 1.0) / n;
    pp->light_cdf[n - 1] = 1.0;
    return 0;
}

void pt_pass_aim_free(pt_pass *pp)
{
    free(pp->guide);
    free(pp->light_cdf);
    pp->guide = NULL;
    pp->light_cdf = NULL;
}

int pt_aim_start(pixel_ctx *c, path_state *ps)
{
    const pt_pass *pp = c->pass;
    const scene *s = pp->s;
    pt_aim *a = &c->aim;
    double u = rng_uniform(c->rng);
    int i = 0;
    while (i < s->light_count - 1 && u >= pp->light_cdf[i]) i++;
    a->light = i;
    a->sel_pdf = pp->light_cdf[i] - (i > 0 ? pp->light_cdf[i - 1] : 0.0);
    if (!(a->sel_pdf > 0.0)) return 0;
    const emitter *L = &s->lights[i];
    a->pre_r = -1.0;
    a->rec_ready = 0;
    ps->time = path_time_offset(s, L, c->rng);
    ps->offset = ps->time;
    /* the light's point for this path: the target of its samplers and of its connections */
    double up[2] = {0.0, 0.0};
    if (emitter_direct_draws(L)) up[0] = rng_uniform(c->rng), up[1] = rng_uniform(c->rng);
    emitter_sample_point(s, L, up, &a->pt);
    a->guide = pp->guide[i];
    a->guide.cam = a->pt.y;
    a->g = &a->guide;
    /* the earliest arrival: a straight line camera → light, or (unwarped, the camera segment free) none;
     * emission through another point of the light (hits, beam crossings) can be up to `extent` nearer */
    double slack = a->g->eta_lb * L->extent;
    vec3 from = pp->p->window.camera_unwarp ? a->pt.y : ps->o; /* the camera ray's origin (either camera) */
    if (!darts_sample_bin(a->g, from, ps->time - slack, rng_uniform(c->rng), &a->bin)) return 0;
    a->reach = a->bin;
    a->reach.end += slack;
    a->on = 1;
    return 1;
}

void pt_aim_connect(pixel_ctx *c, const path_state *ps, vec3 x, const phase_function *pf, const surface_site *ss)
{
    const pt_aim *a = &c->aim;
    const scene *s = c->pass->s;
    const emitter *L = &s->lights[a->light];
    emitter_direct ed;
    int ok;
    if (emitter_is_parallel_beam(L)) { /* surfaces only: medium vertices reach a beam by its crossings */
        const double none[2] = {0.0, 0.0};
        ok = !pf && emitter_sample_direct(s, L, x, none, &ed);
    } else if (L->flags & EMITTER_AIM_PER_CONNECTION) {
        /* a diverging beam's disc: a fixed point of it lights only a narrow cone, so each connection draws its
         * own point where x can see it (docs/emitters.md §4) */
        double u[2] = {rng_uniform(c->rng), rng_uniform(c->rng)};
        ok = emitter_sample_direct(s, L, x, u, &ed);
    } else {
        ok = emitter_connect_point(L, &a->pt, x, &ed);
    }
    if (ok) pt_connect_sample(c, ps, a->light, &ed, x, pf, ss, 0, 1.0 / (a->sel_pdf * a->bin.pdf), a->bin.frame);
}

/* An aimed path whose light is a parallel beam: no point of the beam is a target, so no control vertex, DA
 * or EDA; each medium segment connects by its crossing of the beam (in the path's bin), after the early
 * exit. */
static int beam_segment(pixel_ctx *c, path_state *ps, const medium *m, double tmax, int *event, double *t)
{
    pt_aim *a = &c->aim;
    if (a->g->early_exit && medium_scatters(m) && !pt_unwarped_camera_segment(c, ps) &&
        !darts_can_reach(a->g, &a->reach, ps->o, ps->time))
        return 0;
    pt_beam_crossing(c, ps, a->light, tmax, 0, 1.0 / (a->sel_pdf * a->bin.pdf), a->bin.frame);
    *t = medium_sample_free_flight(m, tmax, c->rng, &ps->beta, event);
    return 1;
}

/* The light connection of a medium segment through a control vertex at distance t on it (paper §5.2, supplement
 * eq. 10–12): β·σs·e^{−σt·t}/p(t) times the connection from x_ell = o + t·d, whose path time lies in the bin
 * by construction. p(t) is the elliptical density, or (control_vertex_mis) its one-sample mixture with a
 * σ-exponential over the in-bin part of the segment: that mixture contains the plain connection's own
 * density restricted to where it can count, so no further MIS with the plain connection is needed. */
static void connect_control_vertex(pixel_ctx *c, const path_state *ps, const medium *m, double tmax)
{
    const darts_guide *g = c->aim.g;
    const ellipse_record *r = &c->aim.rec;
    double t, pdf, sigma = v3_avg(m->sigma_t);
    double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
    int made = g->control_vertex_mis ? control_vertex_sample(r, ps->d, tmax, g->ellipse_residual, sigma, u1, u2, &t, &pdf)
                                     : ellipse_control_vertex(r, ps->d, tmax, &t, &pdf);
    if (!made || !(pdf > 0.0)) return;
    path_state cv = *ps;
    cv.o = v3_add(ps->o, v3_scale(ps->d, t));
    cv.time = ps->time + m->eta * t;
    cv.tr_done = 0;
    pt_deriv_segment(c, &cv, t);
    pt_geom_vertex(c, &cv, t, 0);
    if (c->pass->deriv) deriv_medium_vertex(c->pass->deriv, &cv.dv, ps->medium);
    cv.depth = ps->depth + 1;
    cv.beta = v3_mul(ps->beta, v3_scale(v3_mul(m->sigma_s, v3_exp_neg(v3_scale(m->sigma_t, t))), 1.0 / pdf));
    pt_aim_connect(c, &cv, cv.o, &m->phase, NULL);
}

/* ∂ ln σt/∂θ per channel, the extended-space surface factor's own term (σt > 0 in every channel there). */
static void predrawn_dlog_sigma_t(const deriv_plan *d, deriv_path *p, const medium *m, int med)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_MEDIUM && q->index == med)
            p->dlog[k] = v3_add(p->dlog[k], v3_mul(v3_add(q->dsigma_s, q->dsigma_a), (vec3){1.0 / m->sigma_t.x, 1.0 / m->sigma_t.y, 1.0 / m->sigma_t.z}));
    }
}

/* Uniform time: the distance drawn at the vertex before its direction (Jarabo et al. 2014 §5.1: exponential, λ = σt), used
 * now that the ray is known. Drawn first, it does not depend on the direction, so the pair (r, ω) is sampled
 * in the extended space where the surface term is e^{−σt·d_s} = ∫_{d_s}^∞ σt·e^{−σt·r} dr: a medium event
 * at r < tmax weighs σs·e^{−σt·r}/p(r), the surface at tmax weighs σt·e^{−σt·r}/p(r), p(r) the channel mean
 * of σt·e^{−σt·r} (grey: σs/σt and 1). */
static void predrawn_distance(pixel_ctx *c, path_state *ps, const medium *m, double tmax, int *event, double *t)
{
    double r = c->aim.pre_r;
    c->aim.pre_r = -1.0;
    vec3 e = v3_exp_neg(v3_scale(m->sigma_t, r));
    double p = v3_avg(v3_mul(m->sigma_t, e));
    *event = r < tmax;
    *t = *event ? r : tmax;
    vec3 f = v3_mul(*event ? m->sigma_s : m->sigma_t, e);
    ps->beta = p > 0.0 ? v3_mul(ps->beta, v3_scale(f, 1.0 / p)) : v3s(0.0);
    if (c->pass->deriv && !*event) { /* the surface's extended-space factor σt·e^{−σt·r} at the drawn r ≥ tmax */
        deriv_transmittance(c->pass->deriv, &ps->dv, ps->medium, r);
        predrawn_dlog_sigma_t(c->pass->deriv, &ps->dv, m, ps->medium);
        ps->tr_done = 1;
    }
}

/* Whether a medium segment from ps (in m, its record in c->aim.rec) makes its control vertex: the record valid
 * and the connection's bounces counted. depth and medium_events do not change between a medium vertex and the
 * segment it starts, so the vertex can ask too. */
static int segment_connects(const pixel_ctx *c, const path_state *ps, const medium *m)
{
    return c->aim.rec.valid && ps->medium_events + 1 <= m->max_bounces &&
           bounces_count(&c->pass->p->bounces, ps->depth + 2);
}

int pt_aim_medium_segment(pixel_ctx *c, path_state *ps, double tmax, int *event, double *t)
{
    const medium *m = &c->pass->s->media[ps->medium];
    pt_aim *a = &c->aim;
    const darts_guide *g = a->g;
    if (emitter_is_parallel_beam(&c->pass->s->lights[a->light])) return beam_segment(c, ps, m, tmax, event, t);
    int aims = medium_scatters(m) && !pt_unwarped_camera_segment(c, ps);
    int ready = a->rec_ready; /* drawn at the vertex this segment starts from (vertex_record) */
    a->rec_ready = 0;
    if (aims) {
        if (!ready) ellipse_record_init(&a->rec, g, &a->bin, ps->o, ps->time, m->eta, g->ellipse_residual,
                                        v3_avg(m->sigma_t), rng_uniform(c->rng));
        if (g->early_exit && !darts_can_reach(g, &a->reach, ps->o, ps->time)) return 0;
        if (g->enable_elliptical) {
            ps->connected = 1;
            if (segment_connects(c, ps, m)) connect_control_vertex(c, ps, m, tmax);
        }
    }
    if (a->pre_r >= 0.0) {
        predrawn_distance(c, ps, m, tmax, event, t);
    } else if (aims && g->enable_guiding && (a->rec.valid || a->rec.S_reach > a->rec.C)) {
        da_sample ds;
        da_sample_distance(m, &a->rec, ps->d, tmax, g->da_defensive, c->rng, &ds);
        ps->beta = v3_mul(ps->beta, ds.weight);
        *t = ds.t;
        *event = ds.medium_event;
    } else {
        *t = medium_sample_free_flight(m, tmax, c->rng, &ps->beta, event);
    }
    return 1;
}

/* Uniform time at a medium vertex (Jarabo et al. 2014 §5.1, §5.3 as the supplement §B.4 corrects it): the next distance r first, then the
 * direction by time-angular sampling for that r, mixed with the phase function (one-sample MIS). Only where
 * σt > 0 in every channel (the extended-space weights of predrawn_distance need it); else the phase alone. */
static void uniform_time_direction(pixel_ctx *c, path_state *ps, const medium *m)
{
    pt_aim *a = &c->aim;
    double st_min = dp_fmin(m->sigma_t.x, dp_fmin(m->sigma_t.y, m->sigma_t.z));
    if (!(st_min > 0.0)) {
        double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
        ps->d = phase_sample(&m->phase, ps->d, u1, u2);
        return;
    }
    int grey = m->sigma_t.x == m->sigma_t.y && m->sigma_t.y == m->sigma_t.z;
    int ch = grey ? 0 : (int)dp_fmin(2.0, 3.0 * rng_uniform(c->rng));
    a->pre_r = -log1p(-rng_uniform(c->rng)) / v3_comp(m->sigma_t, ch);
    double u[3] = {rng_uniform(c->rng), rng_uniform(c->rng), rng_uniform(c->rng)}, w;
    ps->d = time_angular_mix_sample(&m->phase, ps->d, ps->o, a->pt.y, a->pre_r,
                                    c->pass->p->time_angular_share, u, &w);
    ps->beta = v3_scale(ps->beta, w);
}

/* DARTS at a medium vertex with elliptical connections (docs/darts.md §14.3): the next segment's record is
 * drawn here, from the distribution the segment would draw it from, and its residual T is shared by the
 * direction and the segment (pt_aim_medium_segment takes it as drawn). The direction comes from one-sample MIS
 * of the sampler toward the segment's control vertex (ellipse_direction_sample, share c, only where the segment
 * will make one) and the base technique (EDA with MIS against the phase function, in the same record's cell,
 * or the phase function); the weight ρ/(c·p_ell + (1 − c)·p_base) is conditional on T, as the control vertex's
 * p(T)·dT/dt is on ω, so their product divides by the joint density (docs/darts.md §14, "Per medium vertex"). */
static void ellipse_direction_vertex(pixel_ctx *c, path_state *ps, const medium *m, const eda_table *et)
{
    pt_aim *a = &c->aim;
    const darts_guide *g = a->g;
    ellipse_record_init(&a->rec, g, &a->bin, ps->o, ps->time, m->eta, g->ellipse_residual, v3_avg(m->sigma_t),
                        rng_uniform(c->rng));
    a->rec_ready = 1;
    double share = segment_connects(c, ps, m) && ellipse_direction_usable(ps->o, a->pt.y, a->rec.T)
                       ? c->pass->p->ellipse_direction_share : 0.0;
    double u[5], p_ell, w_base;
    for (int k = 0; k < 5; k++) u[k] = rng_uniform(c->rng);
    vec3 w_in = ps->d, w;
    if (!(u[0] < share && ellipse_direction_sample(ps->o, a->pt.y, a->rec.T, u[1], u[2], &w, &p_ell)))
        w = et ? eda_sample_direction(et, c->pass->eda->alpha[ps->medium], &m->phase, w_in, &a->rec, u + 1, &w_base)
               : phase_sample(&m->phase, w_in, u[1], u[2]);
    double f = phase_eval(&m->phase, w_in, w); /* the phase function's own density (exact sampling) */
    double p_base = et ? eda_direction_pdf(et, c->pass->eda->alpha[ps->medium], &m->phase, w_in, &a->rec, w) : f;
    double mix = share > 0.0 ? share * ellipse_direction_pdf(ps->o, a->pt.y, a->rec.T, w) + (1.0 - share) * p_base
                             : p_base;
    ps->d = w;
    ps->beta = mix > 0.0 ? v3_scale(ps->beta, f / mix) : v3s(0.0);
}

/* Whether the sampler toward the next control vertex runs at the surface site ss (docs/darts.md §14.4): the
 * medium version's gating (elliptical connections on, not a parallel beam, not uniform time) and a BSDF
 * without delta lobes (mixed delta and smooth lobes would need the discrete probabilities in the mixture). */
static int surface_aims(const pixel_ctx *c, const surface_site *ss)
{
    const pt_pass *pp = c->pass;
    unsigned lobes = bsdf_lobes(ss->b);
    return pp->p->ellipse_directions && pp->p->ellipse_surface_directions && !pp->p->uniform_time &&
           c->aim.g->enable_elliptical && c->aim.g->active && !emitter_is_parallel_beam(&pp->s->lights[c->aim.light]) &&
           lobes && !(lobes & BSDF_LOBE_SPECULAR);
}

/* Whether the target can be on the side a direction from ss leaves into: always for a BSDF that transmits, else
 * only where it is on the arriving side of the surface's plane. Behind an opaque surface the ellipse sampler's
 * directions cluster about e, below the surface, and score nothing: its share is then 0. A choice made per vertex,
 * not per direction, so it keeps every estimate unbiased (docs/darts.md §14.4). */
static int light_on_leaving_side(const surface_site *ss, vec3 x, vec3 target)
{
    if (bsdf_transmits(ss->b)) return 1;
    return v3_dot(v3_sub(target, x), ss->ng_hit) * v3_dot(ss->wi_world, ss->ng_hit) > 0.0;
}

int pt_aim_surface_sample(pixel_ctx *c, const path_state *ps, const surface_site *ss, surface_sample *out)
{
    const scene *s = c->pass->s;
    pt_aim *a = &c->aim;
    /* the side the path arrived from: where every reflection leaves into */
    int med = surface_medium_toward(ss, ps->medium, ss->wi_world);
    if (!surface_aims(c, ss) || med == MEDIUM_VACUUM || !medium_scatters(&s->media[med])) {
        double u[3] = {rng_uniform(c->rng), rng_uniform(c->rng), rng_uniform(c->rng)};
        return surface_sample_bsdf(ss, u, BSDF_LOBES_ALL, 0, out);
    }
    const medium *m = &s->media[med];
    const darts_guide *g = a->g;
    vec3 x = surface_spawn(s, ss, ss->wi_world);
    ellipse_record_init(&a->rec, g, &a->bin, x, ps->time, m->eta, g->ellipse_residual, v3_avg(m->sigma_t),
                        rng_uniform(c->rng));
    double share = segment_connects(c, ps, m) && light_on_leaving_side(ss, x, a->pt.y)
                       ? c->pass->p->ellipse_direction_share : 0.0;
    double u[4];
    for (int k = 0; k < 4; k++) u[k] = rng_uniform(c->rng);
    if (!ellipse_direction_surface_sample(ss, x, a->pt.y, a->rec.T, share, u, out)) return 0;
    /* the segment takes the record only where it starts where the record was drawn, in the same medium: then it
     * is the record the segment would draw (docs/darts.md §14.4); elsewhere (a transmission, a reflection whose
     * origin moves to the other geometric side) the segment draws its own */
    vec3 y = surface_spawn(s, ss, out->w);
    a->rec_ready = surface_medium_toward(ss, ps->medium, out->w) == med && v3_is_zero(v3_sub(y, x));
    return 1;
}

void pt_aim_scatter_direction(pixel_ctx *c, path_state *ps)
{
    const pt_pass *pp = c->pass;
    const medium *m = &pp->s->media[ps->medium];
    if (pp->p->uniform_time && !emitter_is_parallel_beam(&pp->s->lights[c->aim.light])) {
        uniform_time_direction(c, ps, m);
        return;
    }
    const eda_table *et = pp->eda && pp->eda->table && !emitter_is_parallel_beam(&pp->s->lights[c->aim.light])
                              ? pp->eda->table[ps->medium] : NULL;
    if (pp->p->ellipse_directions && c->aim.g->enable_elliptical && c->aim.g->active &&
        !emitter_is_parallel_beam(&pp->s->lights[c->aim.light]) && medium_scatters(m)) {
        ellipse_direction_vertex(c, ps, m, et);
        return;
    }
    if (et) { /* EDA toward the light with MIS against the phase function (docs/darts.md §8.2) */
        ellipse_record vr; /* its own residual; the segment's record draws another (docs/darts.md §14) */
        const darts_guide *g = c->aim.g;
        ellipse_record_init(&vr, g, &c->aim.bin, ps->o, ps->time, m->eta, g->ellipse_residual, v3_avg(m->sigma_t),
                            rng_uniform(c->rng));
        double u[4], w;
        for (int k = 0; k < 4; k++) u[k] = rng_uniform(c->rng);
        ps->d = eda_sample_direction(et, pp->eda->alpha[ps->medium], &m->phase, ps->d, &vr, u, &w);
        ps->beta = v3_scale(ps->beta, w);
        return;
    }
    double u1 = rng_uniform(c->rng), u2 = rng_uniform(c->rng);
    ps->d = phase_sample(&m->phase, ps->d, u1, u2);
}
