/* The render plan: every decision derived from the integrator and renderer keys, taken once. */
#include "dartspp/sliced_primitives.h"
#include "dartspp/plan.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double progressive_radius(double r0, double alpha, long iteration, int dims)
{
    double log_ratio = 0.0;
    for (long j = 1; j <= iteration; j++) log_ratio += log((j + alpha) / (j + 1.0));
    return r0 * exp(log_ratio / dims);
}

/* The path tracer's uniform-time sampling (time_sampling "uniform", Jarabo et al. 2014 as the DARTS supplement
 * B.4 corrects it) is a method of its own: it needs a gate, a medium, a light to aim at and one η. */
static int resolve_uniform_time(const scene *s, const render_plan *p)
{
    const integrator_settings *in = &s->integrator;
    return p->type == INTEGRATOR_PATH_TRACER && in->time_sampling == TIME_SAMPLING_UNIFORM && in->window.gated && s->medium_count > 0 &&
           s->light_count > 0 && scene_eta_uniform(s);
}

static void resolve_photon_points(const integrator_settings *in, render_plan *p)
{
    p->photon_count = in->photon_count;
    p->volume_photon_count = in->volume_photon_count;
    p->gather_photon_count = (int)in->gather_photon_count;
    p->volume_photon_type = in->volume_photon_type;
    /* the kernel's dimension: 2 for points, 1 for beams (the 1-D kernel of src/photon_beams); "3d" is the
     * authors' cube root for either */
    int dims = in->radius_schedule == RADIUS_SCHEDULE_3D ? 3 : in->volume_photon_type != VOLUME_PHOTON_POINTS ? 1 : 2; /* sliced types: their beams */
    /* a delta gate adds the temporal kernel's dimension: radius and width both by γ_i^{1/d}, d = 2 for beams
     * (Liu's ProgressivePhotonMapIntegrator, the "spatio-temporal variant" of Marco et al. 2019 with β = 1/2),
     * d = 3 for points (the same rule: the kernel's volume r²·w shrinks by γ_i, Knaus and Zwicker 2011) */
    if (in->window.delta) dims = in->volume_photon_type != VOLUME_PHOTON_POINTS ? 2 : 3;
    p->r_vol = (radius_schedule){in->volume_gather_radius, in->volume_alpha, dims};
    if (in->window.delta) p->w_gate = (radius_schedule){in->window.width, in->volume_alpha, dims};
    p->r_surf = (radius_schedule){in->gather_radius, in->alpha, 2};
    p->include_surfaces = in->include_surfaces;
    p->low_order_scattering = in->low_order_scattering;
    p->surface_chains = in->surface_chains;
    p->surface_direct = in->surface_direct_connections && in->include_surfaces;
    p->surface_paths = in->surface_paths;
    p->chain_share = 1.0;
    p->sensor_parts = SENSOR_SURFACE | SENSOR_VOLUME;
    p->sensor_row_step = 1;
    p->camera_leg = in->camera_leg;
    p->volume_gather = in->volume_gather;
    /* the path tracer's passes weigh 1 and regularize nothing */
    int pp = p->type == INTEGRATOR_PHOTON_POINTS;
    p->pass_weights = pp ? in->pass_weights : PASS_WEIGHTS_EQUAL;
    p->glossy_regularization = pp ? in->glossy_regularization : 0.0;
}

/* Photon points differentiate volume photons only (docs/derivatives.md §4): photon beams and the sliced
 * primitives carry no derivative records, so a render with derivatives refuses them before any work. */
static int deriv_photon_check(const scene *s, const render_plan *p, dp_error *err)
{
    if (!deriv_on(&p->deriv) || p->type != INTEGRATOR_PHOTON_POINTS || p->volume_photon_type == VOLUME_PHOTON_POINTS ||
        s->medium_count == 0)
        return 0;
    const scene_key *k = scene_key_find("volume_photon_type");
    return dp_fail(err, "%s: integrator.volume_photon_type: %s carries no derivatives; --derivative %s needs "
                   "volume_photon_type \"points\" (docs/derivatives.md §4) or the path tracer",
                   s->path, k ? k->choices[p->volume_photon_type] : "this type", p->deriv.param[0].pointer);
}

int plan_resolve(const scene *s, render_plan *p, dp_error *err)
{
    const integrator_settings *in = &s->integrator;
    memset(p, 0, sizeof *p);
    p->type = in->type;
    snprintf(p->type_name, sizeof p->type_name, "%s", in->type_name);
    p->window = in->window;
    p->bounces = (bounce_limits){(int)in->min_bounces, (int)in->max_bounces};
    p->light_selection = in->light_selection;
    p->shading = (surface_shading){in->enable_two_sided_shading, in->enable_consistency_checks, in->glossy_gather_alpha};
    resolve_photon_points(in, p);
    p->enable_rr = in->enable_rr;
    p->time_angular_share = in->time_angular_share;
    p->ellipse_directions = in->ellipse_directions;
    p->ellipse_direction_share = in->ellipse_direction_share;
    p->ellipse_surface_directions = in->ellipse_surface_directions;
    p->uniform_time = resolve_uniform_time(s, p);
    if (darts_plan_resolve(s, p->type, &p->shading, &p->darts, err)) return -1;
    if (sliced_primitives_check(s, p, err)) { /* what the sliced primitives do not support */
        plan_free(p);
        return -1;
    }
    if (deriv_plan_init(&p->deriv, s, err) || deriv_photon_check(s, p, err)) {
        plan_free(p);
        return -1;
    }
    p->spp = s->renderer.spp;
    p->timeout = s->renderer.timeout;
    p->checkpoint_interval = s->renderer.checkpoint_interval;
    return 0;
}

void plan_free(render_plan *p)
{
    darts_plan_free(&p->darts);
    deriv_plan_free(&p->deriv);
}

double plan_surface_slack(const render_plan *p, long iteration)
{
    if (!p->include_surfaces) return 0.0;
    return p->darts.eta_ub * schedule_radius(&p->r_surf, iteration);
}

/* Path regularization (Kaplanyan and Dachsbacher 2013) of the camera's glossy chains: the floor on α shrinks
 * with the surface radius, α_reg,i = α_reg,0 · R_i/R_0, so the estimate stays consistent (docs/defaults.md §3.7). */
double plan_glossy_regularization(const render_plan *p, long iteration)
{
    double a0 = p->glossy_regularization;
    if (!(a0 > 0.0)) return 0.0;
    return a0 * schedule_radius(&p->r_surf, iteration) / p->r_surf.r0;
}

double plan_pass_weight(const render_plan *p, long iteration)
{
    if (p->pass_weights == PASS_WEIGHTS_EQUAL) return 1.0;
    const radius_schedule *r = p->include_surfaces ? &p->r_surf : &p->r_vol;
    double q = schedule_radius(r, iteration) / r->r0;
    /* beams' 1-D kernel: variance about ∝ 1/r, so the weight is the kernel's width */
    double w = p->window.delta ? plan_gate_width(p, iteration) / p->w_gate.r0 : 1.0; /* the temporal kernel's share */
    if (!p->include_surfaces && p->volume_photon_type != VOLUME_PHOTON_POINTS) return q * w;
    return q * q * w;
}

double plan_gate_width(const render_plan *p, long iteration)
{
    return p->window.delta ? schedule_radius(&p->w_gate, iteration) : p->window.width;
}

double plan_window_end(const render_plan *p, long iteration)
{
    if (!p->window.gated) return INFINITY;
    if (p->window.delta) return p->window.center + 0.5 * plan_gate_width(p, iteration);
    return time_window_end(&p->window);
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
    case KEY_NUMBER_LIST: return cJSON_CreateDoubleArray(((const key_number_list *)f)->v, ((const key_number_list *)f)->count);
    default: return cJSON_CreateNull();
    }
}

/* Every integrator key that changes the image and that this integrator reads, as resolved. */
static void add_keys(cJSON *root, const render_plan *p, const scene *s)
{
    cJSON *keys = cJSON_AddObjectToObject(root, "keys");
    int n;
    const scene_key *table = scene_keys(&n);
    for (int i = 0; i < n; i++)
        if (table[i].section == KEY_SECTION_INTEGRATOR && table[i].changes_image && scene_key_read_by(&table[i], p->type))
            cJSON_AddItemToObject(keys, table[i].name, key_value_json(&table[i], &s->integrator));
}

/* What the DARTS photon pass will run, as derived from the keys and the scene. */
static void add_darts(cJSON *root, const render_plan *p, const scene *s)
{
    const darts_plan *d = &p->darts;
    cJSON *j = cJSON_AddObjectToObject(root, "darts");
    cJSON_AddBoolToObject(j, "active", d->active);
    if (!d->active) return;
    cJSON_AddBoolToObject(j, "distance_sampling", d->enable_guiding);
    cJSON_AddBoolToObject(j, "control_vertices", d->enable_elliptical);
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
    else if (tw->delta) {
        cJSON *d = cJSON_AddObjectToObject(root, "delta_gate");
        cJSON_AddNumberToObject(d, "center", tw->center);
        cJSON_AddNumberToObject(d, "width0", p->w_gate.r0);
        cJSON_AddNumberToObject(d, "alpha", p->w_gate.alpha);
        cJSON_AddNumberToObject(d, "dims", p->w_gate.dims);
        cJSON_AddStringToObject(d, "schedule", "w_i = width0*g_i^(1/dims), r_i = r0*g_i^(1/dims), "
                                               "g_i = prod_{k=1..i} (k+alpha)/(k+1)");
    } else {
        double w[2] = {tw->start, time_window_end(tw)};
        cJSON_AddItemToObject(root, "window", cJSON_CreateDoubleArray(w, 2));
        cJSON_AddNumberToObject(root, "frames", tw->frame_count);
    }
    if (tw->amcw_count > 0) /* the film's AMCW sums: a checkpoint of other frequencies does not resume */
        cJSON_AddItemToObject(root, "amcw_mhz", cJSON_CreateDoubleArray(tw->amcw_mhz, tw->amcw_count));
    add_keys(root, p, s);
    if (p->type == INTEGRATOR_PATH_TRACER)
        cJSON_AddStringToObject(root, "method", p->uniform_time ? "uniform-time path tracer (Jarabo et al. 2014)"
                                                : p->darts.active ? "DARTS path tracer" : "path tracer");
    if (p->type == INTEGRATOR_PHOTON_POINTS || p->darts.active) {
        add_darts(root, p, s);
        cJSON *eda = cJSON_AddObjectToObject(root, "eda");
        for (int i = 0; i < p->darts.medium_count; i++)
            if (p->darts.eda[i].on)
                cJSON_AddNumberToObject(cJSON_AddObjectToObject(eda, s->media[i].name), "alpha", p->darts.eda[i].alpha);
    }
    if (s->diff_count > 0) { /* the derivative images (docs/derivatives.md §5), in their order */
        cJSON *d = cJSON_AddArrayToObject(root, "derivatives");
        for (int k = 0; k < s->diff_count; k++) cJSON_AddItemToArray(d, cJSON_CreateString(s->diffs[k].pointer));
    }
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    int fits = text && strlen(text) < n;
    if (fits) memcpy(out, text, strlen(text) + 1);
    cJSON_free(text);
    return fits ? 0 : -1;
}
