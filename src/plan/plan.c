/* The render plan: every decision derived from the integrator and renderer keys, taken once. */
#include "dartspp/plan.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double progressive_radius(double r0, double alpha, long iteration, int dims)
{
    double log_ratio = 0.0;
    for (long j = 1; j <= iteration; j++) log_ratio += log((j + alpha) / (j + 1.0));
    return r0 * exp(log_ratio / dims);
}

/* A medium uses EDA when the window is gated and it asks for it (phase "ida"), or the integrator does and
 * the medium scatters (there is no direction to pick where nothing scatters). */
static void resolve_eda(const scene *s, render_plan *p)
{
    const integrator_settings *in = &s->integrator;
    for (int i = 0; i < s->medium_count; i++) {
        const medium *m = &s->media[i];
        eda_plan *e = &p->eda[i];
        e->on = p->type == INTEGRATOR_PHOTON_POINTS && in->window.gated && (m->eda || (in->eda && medium_scatters(m)));
        /* EDA aims at the camera's equal-time ellipsoid, which unwarped time does not have */
        e->asked_unwarped = e->on && in->window.camera_unwarp;
        if (e->asked_unwarped) e->on = 0;
        e->alpha = m->eda_alpha > 0.0 ? m->eda_alpha : in->eda_alpha;
        p->eda_active |= e->on;
    }
}

/* The DARTS samplers run when one of them is on (EDA included), the window is gated and there is a
 * medium. Control vertices need one η over every region of the scene (darts.h). */
static void resolve_darts(const scene *s, render_plan *p)
{
    const integrator_settings *in = &s->integrator;
    darts_plan *d = &p->darts;
    int asked = in->enable_guiding || in->enable_elliptical || in->eda;
    for (int i = 0; i < s->medium_count; i++) asked |= s->media[i].eda;
    d->active = p->type == INTEGRATOR_PHOTON_POINTS && in->window.gated && asked && s->medium_count > 0;
    d->unwarped = in->window.camera_unwarp;
    /* DA distance sampling aims at diffusion towards the camera within the residual time of the camera's
     * ellipsoid: unwarped time has none, so it is off (free flight, unbiased); control vertices become
     * sphere_control_vertex, which needs no η along a camera leg */
    d->distance_sampling = in->enable_guiding && !d->unwarped;
    d->elliptical_asked = in->enable_elliptical;
    d->control_vertices = d->active && in->enable_elliptical && (d->unwarped || scene_eta_uniform(s));
    d->control_vertex_mis = in->control_vertex_mis;
    d->residual = in->ellipse_residual ? RESIDUAL_EXPONENTIAL : RESIDUAL_UNIFORM;
    d->strict = in->strict_time_width;
    d->early_exit = in->early_exit;
    d->da_defensive = in->da_defensive;
    d->eta_lb = d->eta_ub = in->vacuum_eta;
    for (int i = 0; i < s->medium_count; i++) {
        d->eta_lb = dp_fmin(d->eta_lb, s->media[i].eta);
        d->eta_ub = dp_fmax(d->eta_ub, s->media[i].eta);
    }
    d->mirrors = in->darts_mirrors_straight ? DARTS_MIRRORS_STRAIGHT : DARTS_MIRRORS_FULL;
    d->mirror_defensive = in->mirror_defensive;
    d->cv_share[0] = 1.0;
}

/* Behind continued surfaces (full mode): the control-vertex techniques and strict mode's surface test.
 * Shares follow what the camera sees: the straight focus 1 (every camera ray starts with a straight leg),
 * each mirror focus its share of the scanned rays, the defensive free flight the share of rays with no
 * focus, at least mirror_defensive (thin features the scan misses still get photons), then normalised. */
static void resolve_camera_side(const scene *s, render_plan *p)
{
    darts_plan *d = &p->darts;
    d->strict_surfaces = d->strict;
    if (!d->active || !(d->control_vertices || d->strict)) return;
    plan_scan_camera_side(s, &p->shading, &d->side);
    if (d->mirrors != DARTS_MIRRORS_FULL || !d->side.seen) return;
    d->strict_surfaces = 0; /* a camera path behind a continued surface has no upper bound on its leg */
    if (!d->control_vertices) return;
    if (d->unwarped) { /* behind a mirror the camera's later segments count: no sphere aims there */
        d->control_vertices = 0;
        d->unwarped_mirror_off = 1;
        return;
    }
    d->cv_multi = 1;
    double sum = 1.0, def = dp_fmax(d->side.other_fraction, d->mirror_defensive);
    for (int k = 0; k < d->side.mirror_count; k++) sum += d->side.mirror_fraction[k];
    sum += def;
    d->cv_share[0] = 1.0 / sum;
    for (int k = 0; k < d->side.mirror_count; k++) d->cv_share[1 + k] = d->side.mirror_fraction[k] / sum;
    d->cv_defensive = def / sum;
}

int plan_resolve(const scene *s, render_plan *p, dp_error *err)
{
    const integrator_settings *in = &s->integrator;
    memset(p, 0, sizeof *p);
    if (in->volume_beams)
        return dp_fail(err, "%s: integrator.volume_photon_type: 'beams' is not supported (supported: points)", s->path);
    p->type = in->type;
    snprintf(p->type_name, sizeof p->type_name, "%s", in->type_name);
    p->window = in->window;
    p->bounces = (bounce_limits){in->min_bounces, in->max_bounces};
    p->enable_rr = in->enable_rr;
    p->shading = (surface_shading){in->two_sided_shading, in->consistency_checks, in->glossy_gather_alpha};
    p->light_paths = in->photon_count;
    p->volume_budget = in->volume_photon_count;
    p->surface_budget = in->photon_count;
    p->r_vol = (radius_schedule){in->volume_gather_radius, in->volume_alpha, in->radius_schedule_3d ? 3 : 2};
    p->r_surf = (radius_schedule){in->gather_radius, in->alpha, 2};
    p->k_surf = in->gather_photon_count;
    p->camera_leg_projected = in->camera_leg_projected;
    p->volume_splat = !in->volume_gather_beam;
    p->include_surfaces = in->include_surfaces;
    p->pass_weights_equal = in->pass_weights_equal;
    p->surface_chains = in->surface_chains;
    p->low_order_scattering = in->low_order_scattering;
    p->medium_count = s->medium_count;
    if (s->medium_count > 0 && !(p->eda = calloc((size_t)s->medium_count, sizeof *p->eda)))
        return dp_fail(err, "%s: out of memory for the render plan", s->path);
    resolve_eda(s, p);
    resolve_darts(s, p);
    resolve_camera_side(s, p);
    snprintf(p->eda_table_dir, sizeof p->eda_table_dir, "%s", in->eda_table_dir);
    memcpy(p->eda_shape, in->eda_shape, sizeof p->eda_shape);
    p->spp = s->renderer.spp;
    p->timeout_seconds = s->renderer.timeout_seconds;
    p->checkpoint_seconds = s->renderer.checkpoint_seconds;
    return 0;
}

void plan_free(render_plan *p)
{
    free(p->eda);
    p->eda = NULL;
}

double plan_surface_slack(const render_plan *p, long iteration)
{
    if (!p->include_surfaces) return 0.0;
    return p->darts.eta_ub * schedule_radius(&p->r_surf, iteration);
}

double plan_pass_weight(const render_plan *p, long iteration)
{
    if (p->type != INTEGRATOR_PHOTON_POINTS || p->pass_weights_equal) return 1.0;
    const radius_schedule *r = p->include_surfaces ? &p->r_surf : &p->r_vol;
    double q = schedule_radius(r, iteration) / r->r0;
    return q * q;
}

/* Appends printf-style text; keeps track of overflow. */
static void put(char *out, size_t n, size_t *len, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void put(char *out, size_t n, size_t *len, const char *fmt, ...)
{
    if (*len >= n) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(out + *len, n - *len, fmt, ap);
    va_end(ap);
    *len = k < 0 ? n : *len + (size_t)k;
}

int plan_json(const render_plan *p, const scene *s, char *out, size_t n)
{
    size_t len = 0;
    const time_window *tw = &p->window;
    put(out, n, &len, "{\"integrator\":\"%s\",\"time\":\"camera-%s optical path length\"", p->type_name,
        tw->camera_unwarp ? "unwarped" : "warped");
    if (!tw->gated) put(out, n, &len, ",\"window\":\"steady\"");
    else put(out, n, &len, ",\"window\":[%.17g,%.17g],\"frames\":%d", tw->start, time_window_end(tw), tw->frame_count);
    put(out, n, &len, ",\"bounces\":[%d,%d]", p->bounces.min, p->bounces.max);
    put(out, n, &len, ",\"two_sided_shading\":%s,\"consistency_checks\":%s", p->shading.two_sided ? "true" : "false",
        p->shading.consistency_checks ? "true" : "false");
    if (p->type == INTEGRATOR_PATH_TRACER) {
        put(out, n, &len, ",\"russian_roulette\":%s}", p->enable_rr ? "true" : "false");
        return len < n ? 0 : -1;
    }
    const darts_plan *d = &p->darts;
    put(out, n, &len,
        ",\"light_paths\":%.17g,\"volume_budget\":%.17g,\"surface_budget\":%.17g"
        ",\"r_vol\":{\"r0\":%.17g,\"alpha\":%.17g,\"dims\":%d},\"r_surf\":{\"r0\":%.17g,\"alpha\":%.17g,\"k\":%d}"
        ",\"camera_leg\":\"%s\",\"volume_gather\":\"%s\",\"surfaces\":%s,\"low_order_scattering\":%s,\"glossy_gather_alpha\":%.17g",
        p->light_paths, p->volume_budget, p->surface_budget, p->r_vol.r0, p->r_vol.alpha, p->r_vol.dims, p->r_surf.r0,
        p->r_surf.alpha, p->k_surf, p->camera_leg_projected ? "projected" : "euclidean",
        p->volume_splat ? "splat" : "beam", p->include_surfaces ? "true" : "false", p->low_order_scattering ? "true" : "false",
        p->shading.glossy_gather_alpha);
    put(out, n, &len, ",\"pass_weights\":\"%s\"", p->pass_weights_equal ? "equal" : "kernel_area");
    put(out, n, &len, ",\"darts\":{\"active\":%s", d->active ? "true" : "false");
    if (d->active)
        put(out, n, &len,
            ",\"distance_sampling\":%s,\"control_vertices\":%s,\"control_vertex_mis\":%s,\"residual\":\"%s\""
            ",\"strict\":%s,\"early_exit\":%s,\"da_defensive\":%.17g,\"eta\":[%.17g,%.17g]",
            d->distance_sampling ? "true" : "false", d->control_vertices ? "true" : "false",
            d->control_vertex_mis ? "true" : "false", d->residual == RESIDUAL_EXPONENTIAL ? "exponential" : "uniform",
            d->strict ? "true" : "false", d->early_exit ? "true" : "false", d->da_defensive, d->eta_lb, d->eta_ub);
    if (d->active) {
        put(out, n, &len, ",\"mirrors\":\"%s\",\"strict_surfaces\":%s", d->mirrors == DARTS_MIRRORS_FULL ? "full" : "straight",
            d->strict_surfaces ? "true" : "false");
        if (d->cv_multi) {
            put(out, n, &len, ",\"cv_share\":[%.17g", d->cv_share[0]);
            for (int k = 0; k < d->side.mirror_count; k++)
                put(out, n, &len, ",{\"mirror\":\"%s\",\"share\":%.17g,\"focus\":[%.17g,%.17g,%.17g]}",
                    s->surfaces[d->side.mirror_surface[k]].name, d->cv_share[1 + k], d->side.focus[k].x, d->side.focus[k].y,
                    d->side.focus[k].z);
            put(out, n, &len, ",{\"defensive\":%.17g}]", d->cv_defensive);
        }
    }
    put(out, n, &len, "},\"eda\":{");
    const char *sep = "";
    for (int i = 0; i < p->medium_count; i++) {
        if (!p->eda[i].on) continue;
        put(out, n, &len, "%s\"%s\":{\"alpha\":%.17g}", sep, s->media[i].name, p->eda[i].alpha);
        sep = ",";
    }
    put(out, n, &len, "}}");
    return len < n ? 0 : -1;
}
