/* The render plan: every decision derived from the integrator and renderer keys, taken once. */
#include "dartspp/plan.h"

#include <cjson/cJSON.h>
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
        e->on = in->window.gated && (m->eda || (in->eda && medium_scatters(m))) &&
                (p->type == INTEGRATOR_PHOTON_POINTS || (p->type == INTEGRATOR_PATH_TRACER && !in->time_sampling_uniform));
        /* photon points: EDA aims at the camera's equal-time ellipsoid, which unwarped time does not have (the
         * path tracer aims at the light, whose leg always counts) */
        e->asked_unwarped = e->on && in->window.camera_unwarp && p->type == INTEGRATOR_PHOTON_POINTS;
        if (e->asked_unwarped) e->on = 0;
        e->alpha = m->eda_alpha > 0.0 ? m->eda_alpha : in->eda_alpha;
        p->eda_active |= e->on;
    }
}

/* The DARTS samplers run when one of them is on (EDA included), the window is gated and there is a
 * medium (and, in the path tracer, a light to aim at). Control vertices need one η over every region of the
 * scene (darts.h). The path tracer's uniform-time sampling (time_sampling "uniform") is a method of its own:
 * free flight, line-to-point connections and time-angular directions (p->uniform_time), no DARTS sampler. */
static void resolve_darts(const scene *s, render_plan *p)
{
    const integrator_settings *in = &s->integrator;
    darts_plan *d = &p->darts;
    int pt = p->type == INTEGRATOR_PATH_TRACER;
    int asked = in->enable_guiding || in->enable_elliptical || in->eda;
    for (int i = 0; i < s->medium_count; i++) asked |= s->media[i].eda;
    int gated_medium = in->window.gated && s->medium_count > 0 && (!pt || s->light_count > 0);
    p->uniform_time = pt && in->time_sampling_uniform && gated_medium && scene_eta_uniform(s);
    d->active = gated_medium && asked && (p->type == INTEGRATOR_PHOTON_POINTS || (pt && !in->time_sampling_uniform));
    d->unwarped = in->window.camera_unwarp;
    /* photon points: DA distance sampling aims at diffusion towards the camera within the residual time of
     * the camera's ellipsoid: unwarped time has none, so it is off (free flight, unbiased); control vertices
     * become sphere_control_vertex, which needs no η along a camera leg. The path tracer aims at the light,
     * whose leg always counts: only its camera segment goes without (src/render/README.md) */
    d->distance_sampling = in->enable_guiding && (pt || !d->unwarped);
    d->elliptical_asked = in->enable_elliptical;
    d->control_vertices = d->active && in->enable_elliptical && ((d->unwarped && !pt) || scene_eta_uniform(s));
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
    if (p->type != INTEGRATOR_PHOTON_POINTS || !d->active || !(d->control_vertices || d->strict)) return;
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
    p->keys = *in;
    if (in->volume_beams)
        return dp_fail(err, "%s: integrator.volume_photon_type: 'beams' is not supported (supported: points)", s->path);
    p->type = in->type;
    snprintf(p->type_name, sizeof p->type_name, "%s", in->type_name);
    p->window = in->window;
    p->bounces = (bounce_limits){(int)in->min_bounces, (int)in->max_bounces};
    p->shading = (surface_shading){in->two_sided_shading, in->consistency_checks, in->glossy_gather_alpha};
    p->light_paths = in->photon_count;
    p->volume_budget = in->volume_photon_count;
    p->surface_budget = in->photon_count;
    p->r_vol = (radius_schedule){in->volume_gather_radius, in->volume_alpha, in->radius_schedule_3d ? 3 : 2};
    p->r_surf = (radius_schedule){in->gather_radius, in->alpha, 2};
    p->volume_splat = !in->volume_gather_beam;
    p->medium_count = s->medium_count;
    if (s->medium_count > 0 && !(p->eda = calloc((size_t)s->medium_count, sizeof *p->eda)))
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the render plan", s->path);
    resolve_eda(s, p);
    resolve_darts(s, p);
    resolve_camera_side(s, p);
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
    if (!p->keys.include_surfaces) return 0.0;
    return p->darts.eta_ub * schedule_radius(&p->r_surf, iteration);
}

/* Path regularization (Kaplanyan and Dachsbacher 2013) of the camera's glossy chains: the floor on α shrinks
 * with the surface radius, α_reg,i = α_reg,0 · R_i/R_0, so the estimate stays consistent (docs/defaults.md §3.7). */
double plan_glossy_regularization(const render_plan *p, long iteration)
{
    double a0 = p->keys.glossy_regularization;
    if (p->type != INTEGRATOR_PHOTON_POINTS || !(a0 > 0.0)) return 0.0;
    return a0 * schedule_radius(&p->r_surf, iteration) / p->r_surf.r0;
}

double plan_pass_weight(const render_plan *p, long iteration)
{
    if (p->type != INTEGRATOR_PHOTON_POINTS || p->keys.pass_weights_equal) return 1.0;
    const radius_schedule *r = p->keys.include_surfaces ? &p->r_surf : &p->r_vol;
    double q = schedule_radius(r, iteration) / r->r0;
    return q * q;
}

/* A key's resolved value as JSON, by its type in the key table. */
static cJSON *key_value_json(const scene_key *k, const integrator_settings *in)
{
    const void *f = (const char *)in + k->offset;
    switch (k->type) {
    case KEY_BOOL: return cJSON_CreateBool(*(const int *)f);
    case KEY_INT: return cJSON_CreateNumber((double)*(const long *)f);
    case KEY_NUMBER: return cJSON_CreateNumber(*(const double *)f);
    case KEY_CHOICE: return cJSON_CreateString(k->choices[*(const int *)f]);
    case KEY_STRING: return cJSON_CreateString((const char *)f);
    case KEY_SHAPE3: return cJSON_CreateIntArray((const int *)f, 3);
    default: return cJSON_CreateNull();
    }
}

/* Every integrator key that changes the image and that this integrator reads, as resolved. */
static void add_keys(cJSON *root, const render_plan *p)
{
    cJSON *keys = cJSON_AddObjectToObject(root, "keys");
    int n;
    const scene_key *table = scene_keys(&n);
    for (int i = 0; i < n; i++)
        if (table[i].section == KEY_SECTION_INTEGRATOR && table[i].changes_image && scene_key_read_by(&table[i], p->type))
            cJSON_AddItemToObject(keys, table[i].name, key_value_json(&table[i], &p->keys));
}

/* What the DARTS photon pass will run, as derived from the keys and the scene. */
static void add_darts(cJSON *root, const render_plan *p, const scene *s)
{
    const darts_plan *d = &p->darts;
    cJSON *j = cJSON_AddObjectToObject(root, "darts");
    cJSON_AddBoolToObject(j, "active", d->active);
    if (!d->active) return;
    cJSON_AddBoolToObject(j, "distance_sampling", d->distance_sampling);
    cJSON_AddBoolToObject(j, "control_vertices", d->control_vertices);
    cJSON_AddBoolToObject(j, "strict_surfaces", d->strict_surfaces);
    double eta[2] = {d->eta_lb, d->eta_ub};
    cJSON_AddItemToObject(j, "eta", cJSON_CreateDoubleArray(eta, 2));
    if (!d->cv_multi) return;
    cJSON *shares = cJSON_AddArrayToObject(j, "cv_share");
    cJSON_AddItemToArray(shares, cJSON_CreateNumber(d->cv_share[0]));
    for (int k = 0; k < d->side.mirror_count; k++) {
        cJSON *m = cJSON_CreateObject();
        cJSON_AddStringToObject(m, "mirror", s->surfaces[d->side.mirror_surface[k]].name);
        cJSON_AddNumberToObject(m, "share", d->cv_share[1 + k]);
        double focus[3] = {d->side.focus[k].x, d->side.focus[k].y, d->side.focus[k].z};
        cJSON_AddItemToObject(m, "focus", cJSON_CreateDoubleArray(focus, 3));
        cJSON_AddItemToArray(shares, m);
    }
    cJSON *def = cJSON_CreateObject();
    cJSON_AddNumberToObject(def, "defensive", d->cv_defensive);
    cJSON_AddItemToArray(shares, def);
}

int plan_json(const render_plan *p, const scene *s, char *out, size_t n)
{
    const time_window *tw = &p->window;
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "integrator", p->type_name);
    cJSON_AddStringToObject(root, "time", tw->camera_unwarp ? "camera-unwarped optical path length"
                                                            : "camera-warped optical path length");
    if (!tw->gated) cJSON_AddStringToObject(root, "window", "steady");
    else {
        double w[2] = {tw->start, time_window_end(tw)};
        cJSON_AddItemToObject(root, "window", cJSON_CreateDoubleArray(w, 2));
        cJSON_AddNumberToObject(root, "frames", tw->frame_count);
    }
    add_keys(root, p);
    if (p->type == INTEGRATOR_PATH_TRACER)
        cJSON_AddStringToObject(root, "method", p->uniform_time ? "uniform-time path tracer (Jarabo et al. 2014)"
                                                : p->darts.active ? "DARTS path tracer" : "path tracer");
    if (p->type == INTEGRATOR_PHOTON_POINTS || p->darts.active) {
        add_darts(root, p, s);
        cJSON *eda = cJSON_AddObjectToObject(root, "eda");
        for (int i = 0; i < p->medium_count; i++)
            if (p->eda[i].on) cJSON_AddNumberToObject(cJSON_AddObjectToObject(eda, s->media[i].name), "alpha", p->eda[i].alpha);
    }
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    int fits = text && strlen(text) < n;
    if (fits) memcpy(out, text, strlen(text) + 1);
    cJSON_free(text);
    return fits ? 0 : -1;
}
