/* The DARTS configuration of a render (darts.h, darts_plan): which samplers run, decided once from the
 * integrator keys and the scene. */
#include <stdlib.h>
#include <string.h>

#include "dartspp/darts.h"

/* Whether the samplers serve this integrator at all: photon points, or the path tracer's DARTS method (its
 * uniform-time method, time_sampling "uniform", runs no DARTS sampler). */
static int darts_integrator(const integrator_settings *in, integrator_type type)
{
    return type == INTEGRATOR_PHOTON_POINTS ||
           (type == INTEGRATOR_PATH_TRACER && in->time_sampling != TIME_SAMPLING_UNIFORM);
}

/* A medium uses EDA when the window is gated and it asks for it (phase "ida"), or the integrator does and
 * the medium scatters (there is no direction to pick where nothing scatters). */
static void resolve_eda(const scene *s, integrator_type type, darts_plan *d)
{
    const integrator_settings *in = &s->integrator;
    for (int i = 0; i < s->medium_count; i++) {
        const medium *m = &s->media[i];
        eda_plan *e = &d->eda[i];
        e->on = in->window.gated && (m->eda || (in->eda && medium_scatters(m))) && darts_integrator(in, type);
        /* photon points: EDA aims at the camera's equal-time ellipsoid, which unwarped time does not have (the
         * path tracer aims at the light, whose leg always counts) */
        e->asked_unwarped = e->on && in->window.camera_unwarp && type == INTEGRATOR_PHOTON_POINTS;
        if (e->asked_unwarped) e->on = 0;
        e->alpha = m->eda_alpha > 0.0 ? m->eda_alpha : in->eda_alpha;
        d->eda_active |= e->on;
    }
    snprintf(d->eda_table_dir, sizeof d->eda_table_dir, "%s", in->eda_table_dir);
    memcpy(d->eda_shape, in->eda_shape, sizeof d->eda_shape);
}

/* The DARTS samplers run when one of them is on (EDA included), the window is gated and there is a
 * medium (and, in the path tracer, a light to aim at). Control vertices need one η over every region of the
 * scene (above). The path tracer's uniform-time sampling (time_sampling "uniform") is a method of its own:
 * free flight, line-to-point connections and time-angular directions, no DARTS sampler. */
static void resolve_samplers(const scene *s, integrator_type type, darts_plan *d)
{
    const integrator_settings *in = &s->integrator;
    int pt = type == INTEGRATOR_PATH_TRACER, unwarped = in->window.camera_unwarp;
    int asked = in->enable_guiding || in->enable_elliptical || in->eda;
    for (int i = 0; i < s->medium_count; i++) asked |= s->media[i].eda;
    int gated_medium = in->window.gated && s->medium_count > 0 && (!pt || s->light_count > 0);
    d->active = gated_medium && asked && darts_integrator(in, type);
    /* photon points: DA distance sampling aims at diffusion towards the camera within the residual time of
     * the camera's ellipsoid: unwarped time has none, so it is off (free flight, unbiased); control vertices
     * become sphere_control_vertex, which needs no η along a camera leg. The path tracer aims at the light,
     * whose leg always counts: only its camera segment goes without (src/path_tracer/README.md) */
    d->enable_guiding = in->enable_guiding && (pt || !unwarped);
    d->enable_elliptical_asked = in->enable_elliptical;
    d->enable_elliptical = d->active && in->enable_elliptical && ((unwarped && !pt) || scene_eta_uniform(s));
    d->control_vertex_mis = in->control_vertex_mis;
    d->camera_control_vertices = in->camera_control_vertices && type == INTEGRATOR_PHOTON_POINTS &&
                                 d->enable_elliptical && !unwarped && s->cam.type == CAMERA_PINHOLE;
    d->ellipse_residual = in->ellipse_residual ? RESIDUAL_EXPONENTIAL : RESIDUAL_UNIFORM;
    d->strict_time_width = in->strict_time_width;
    d->early_exit = in->early_exit;
    d->da_defensive = in->da_defensive;
    d->eta_lb = d->eta_ub = in->vacuum_eta;
    for (int i = 0; i < s->medium_count; i++) {
        d->eta_lb = dp_fmin(d->eta_lb, s->media[i].eta);
        d->eta_ub = dp_fmax(d->eta_ub, s->media[i].eta);
    }
    d->darts_mirrors = in->darts_mirrors;
    d->mirror_defensive = in->mirror_defensive;
    d->cv_share[0] = 1.0;
}

/* Behind continued surfaces (full mode): the control-vertex techniques and strict mode's surface test.
 * Shares follow what the camera sees: the straight focus 1 (every camera ray starts with a straight leg),
 * each mirror focus its share of the scanned rays, the defensive free flight the share of rays with no
 * focus, at least mirror_defensive (thin features the scan misses still get photons), then normalised. */
static void resolve_camera_side(const scene *s, integrator_type type, const surface_shading *sh, darts_plan *d)
{
    d->strict_surfaces = d->strict_time_width;
    if (type != INTEGRATOR_PHOTON_POINTS || !d->active || !(d->enable_elliptical || d->strict_time_width)) return;
    darts_scan_camera_side(s, sh, &d->side);
    if (d->darts_mirrors != DARTS_MIRRORS_FULL || !d->side.seen) return;
    d->strict_surfaces = 0; /* a camera path behind a continued surface has no upper bound on its leg */
    if (!d->enable_elliptical) return;
    if (s->integrator.window.camera_unwarp) { /* behind a mirror the camera's later segments count: no sphere aims there */
        d->enable_elliptical = 0;
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

/* The DARTS photon pass aims light paths at the camera's position: the ellipsoid of a control vertex has it as
 * a focus, DA and EDA sample diffusion towards it, and the camera is the virtual importons' emitter. An
 * orthographic camera has no such point (its rays start anywhere on its film, all along one axis), so the
 * combination is refused before any work, naming the key that asked for it (docs/darts.md). The DARTS path
 * tracer aims at the light instead and works with either camera. */
static int refuse_orthographic(const scene *s, integrator_type type, const darts_plan *d, dp_error *err)
{
    if (type != INTEGRATOR_PHOTON_POINTS || !d->active || s->cam.type != CAMERA_ORTHOGRAPHIC) return 0;
    const integrator_settings *in = &s->integrator;
    const char *key = in->enable_guiding ? "enable_guiding" : in->enable_elliptical ? "enable_elliptical" : "eda";
    for (int i = 0; i < s->medium_count && !in->enable_guiding && !in->enable_elliptical && !in->eda; i++)
        if (s->media[i].eda) key = "phase_function ida (EDA)";
    return dp_fail(err, "%s: integrator.%s: the DARTS photon pass aims light paths at the camera's position (elliptical "
                   "control vertices, DA and EDA sampling, the camera as the importons' emitter), and an orthographic "
                   "camera has none: not supported; set enable_guiding, enable_elliptical and eda to false (baseline "
                   "photon points), or use the path tracer (its DARTS aims at the light and works with an orthographic "
                   "camera), or a pinhole camera", s->path, key);
}

int darts_plan_resolve(const scene *s, integrator_type type, const surface_shading *sh, darts_plan *d, dp_error *err)
{
    memset(d, 0, sizeof *d);
    d->medium_count = s->medium_count;
    if (s->medium_count > 0 && !(d->eda = calloc((size_t)s->medium_count, sizeof *d->eda)))
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the render plan", s->path);
    resolve_eda(s, type, d);
    resolve_samplers(s, type, d);
    if (refuse_orthographic(s, type, d, err)) {
        darts_plan_free(d);
        return -1;
    }
    resolve_camera_side(s, type, sh, d);
    return 0;
}

void darts_plan_free(darts_plan *d)
{
    free(d->eda);
    d->eda = NULL;
}
