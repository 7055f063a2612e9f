/* Integrator and renderer keys (docs/scene-format.md §2.8), time window (docs/time.md §3). */
#include "settings.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const integrator_keys[] = {
    "type", "min_bounces", "max_bounces", "transient_time_center", "transient_time_width", "frame_num", "camera_unwarp",
    "start_time", "vaccum_speed_of_light", "delta_time_gate", "enable_rr", "enable_light_sampling",
    "enable_volume_light_sampling", "photon_count", "volume_photon_count", "gather_photon_count",
    "gather_radius", "volume_gather_radius", "volume_photon_type", "alpha", "volume_alpha",
    "fixed_volume_radius", "include_surfaces", "low_order_scattering", "enable_guiding", "enable_elliptical",
    "strict_time_width", "camera_leg", "volume_gather", "radius_schedule", "pass_weights", "ellipse_residual", "control_vertex_mis", "early_exit", "surface_chains", "da_defensive", "darts_mirrors", "mirror_defensive", "eda", "eda_alpha", "eda_table_dir", "eda_shape", "enable_consistency_checks", "enable_two_sided_shading", "glossy_gather_alpha", "exclude_non_mis", "use_grid",
    NULL};
static const char *const renderer_keys[] = {"spp", "spp_step", "timeout", "checkpoint_interval", "output_file",
                                            "hdr_output_file", "output_buffers", "overwrite_output_files",
                                            "enable_resume_render", "resume_render_file", "stratified_sampler",
                                            "scene_bvh", "adaptive_sampling", "output_directory", NULL};

static int in_list(const char *const *list, const char *key)
{
    for (; *list; list++)
        if (!strcmp(*list, key)) return 1;
    return 0;
}

static cJSON *override_value(const char *text)
{
    cJSON *json = text[0] == '[' ? cJSON_Parse(text) : NULL; /* arrays, e.g. eda_shape=[64,64,128] */
    if (json) return json;
    if (!strcmp(text, "true")) return cJSON_CreateTrue();
    if (!strcmp(text, "false")) return cJSON_CreateFalse();
    char *end;
    double d = strtod(text, &end);
    if (*text && *end == 0 && isfinite(d)) return cJSON_CreateNumber(d);
    return cJSON_CreateString(text);
}

static int override_resolution(json_ctx *c, cJSON *root, const char *set, const char *text)
{
    char *end;
    long w = strtol(text, &end, 10), h = w;
    if (*end == 'x') h = strtol(end + 1, &end, 10);
    if (end == text || *end || w < 1 || h < 1 || w > 65536 || h > 65536)
        return dp_fail(c->err, "%s: --set %s: expected resolution=W or resolution=WxH (1 to 65536)", c->file, set);
    cJSON *cam = cJSON_GetObjectItemCaseSensitive(root, "camera");
    if (!cJSON_IsObject(cam)) return jfail(c, "camera", NULL, "expected an object");
    cJSON_DeleteItemFromObjectCaseSensitive(cam, "resolution");
    cJSON *r = cJSON_AddArrayToObject(cam, "resolution");
    cJSON_AddItemToArray(r, cJSON_CreateNumber((double)w));
    cJSON_AddItemToArray(r, cJSON_CreateNumber((double)h));
    return 0;
}

int settings_apply_overrides(json_ctx *c, cJSON *root, const char *const *sets, int count)
{
    for (int i = 0; i < count; i++) {
        const char *eq = strchr(sets[i], '=');
        if (!eq || eq == sets[i]) return dp_fail(c->err, "%s: --set %s: expected key=value", c->file, sets[i]);
        char key[128];
        size_t n = (size_t)(eq - sets[i]);
        if (n >= sizeof key) return dp_fail(c->err, "%s: --set %s: key too long", c->file, sets[i]);
        memcpy(key, sets[i], n);
        key[n] = 0;
        if (!strcmp(key, "resolution")) { /* camera resolution: W or WxH */
            if (override_resolution(c, root, sets[i], eq + 1)) return -1;
            continue;
        }
        const char *section = in_list(renderer_keys, key) ? "renderer" : "integrator";
        if (!in_list(renderer_keys, key) && !in_list(integrator_keys, key))
            return dp_fail(c->err, "%s: --set %s: unknown integrator or renderer key '%s'", c->file, sets[i], key);
        cJSON *obj = cJSON_GetObjectItemCaseSensitive(root, section);
        if (!obj) obj = cJSON_AddObjectToObject(root, section);
        if (!cJSON_IsObject(obj)) return jfail(c, section, NULL, "expected an object");
        cJSON_DeleteItemFromObjectCaseSensitive(obj, key);
        cJSON_AddItemToObject(obj, key, override_value(eq + 1));
    }
    return 0;
}

double parse_duration_seconds(const char *text)
{
    char *end;
    double v = strtod(text, &end);
    if (end == text || !isfinite(v) || v < 0) return -1;
    while (*end == ' ') end++;
    if (!*end || !strcmp(end, "m")) return v * 60.0;
    if (!strcmp(end, "ms")) return v * 1e-3;
    if (!strcmp(end, "s")) return v;
    if (!strcmp(end, "h")) return v * 3600.0;
    if (!strcmp(end, "d")) return v * 86400.0;
    return -1;
}

/* A duration key; a negative number (the reference writes "timeout": "-1") means no limit, stored as 0. */
static int get_duration(json_ctx *c, const cJSON *obj, const char *key, double *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    *out = 0;
    if (!v) return 0;
    if (cJSON_IsNumber(v) && v->valuedouble < 0 && isfinite(v->valuedouble)) return 0;
    if (cJSON_IsString(v) && v->valuestring[0] == '-' && parse_duration_seconds(v->valuestring + 1) > 0) return 0;
    if (cJSON_IsNumber(v)) *out = v->valuedouble >= 0 ? v->valuedouble * 60.0 : -1;
    else if (cJSON_IsString(v)) *out = parse_duration_seconds(v->valuestring);
    else *out = -1;
    if (*out < 0 || !isfinite(*out))
        return jfail(c, "renderer", key, "expected a duration (bare number = minutes; suffixes ms, s, m, h, d)");
    return 0;
}

static int parse_window(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    double center, width, start;
    long frames;
    int delta;
    /* no gate and no frames asked for: steady state (as the reference path tracer does) */
    int timed = cJSON_HasObjectItem(v, "transient_time_center") || cJSON_HasObjectItem(v, "frame_num") ||
                cJSON_HasObjectItem(v, "transient_time_width");
    if (jget_number(c, v, "integrator", "transient_time_center", 0.0, &center) ||
        jget_number(c, v, "integrator", "transient_time_width", 0.1, &width) ||
        jget_number(c, v, "integrator", "start_time", 0.0, &start) ||
        jget_int(c, v, "integrator", "frame_num", 0, &frames) ||
        jget_bool(c, v, "integrator", "delta_time_gate", 0, &delta) ||
        jget_bool(c, v, "integrator", "camera_unwarp", 0, &in->window.camera_unwarp))
        return -1;
    if (delta) return jfail(c, "integrator", "delta_time_gate", "delta gates are not supported (use a box gate width)");
    if (width < 0) return jfail(c, "integrator", "transient_time_width", "empty time window: width %g < 0", width);
    if (frames > 100000) return jfail(c, "integrator", "frame_num", "at most 100000 frames (got %ld)", frames);
    if (!timed) width = 0.0;
    time_window *tw = &in->window;
    tw->frame_count = frames > 0 ? (int)frames : 0;
    tw->width = width;
    if (tw->frame_count > 0) {
        if (width <= 0) return jfail(c, "integrator", "transient_time_width", "empty time window: frames need a width > 0");
        tw->gated = 1;
        tw->start = start;
    } else {
        tw->gated = width > 0;
        tw->start = width > 0 ? center - 0.5 * width : 0.0;
    }
    return 0;
}

static int parse_integrator_type(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    const char *type = "path_tracer", *vpt = "points";
    if (jget_string(c, v, "integrator", "type", &type) < 0) return -1;
    snprintf(in->type_name, sizeof in->type_name, "%s", type);
    if (!strcmp(type, "path_tracer")) in->type = INTEGRATOR_PATH_TRACER;
    else if (!strcmp(type, "progressive_transient_photon_map")) in->type = INTEGRATOR_PHOTON_POINTS;
    else return jfail(c, "integrator", "type", "unsupported integrator '%s' (supported: path_tracer, progressive_transient_photon_map)", type);
    if (jget_string(c, v, "integrator", "volume_photon_type", &vpt) < 0) return -1;
    if (strcmp(vpt, "points") && strcmp(vpt, "beams"))
        return jfail(c, "integrator", "volume_photon_type", "'%s' is not supported (supported: points)", vpt);
    in->volume_beams = !strcmp(vpt, "beams");
    return 0;
}

static int parse_photon_keys(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    long k = 0;
    const char *w = "integrator";
    if (jget_number_range(c, v, w, "photon_count", 1e6, 0, 0, &in->photon_count) ||
        jget_number_range(c, v, w, "volume_photon_count", 1e6, 0, 0, &in->volume_photon_count) ||
        jget_int(c, v, w, "gather_photon_count", 20, &k) ||
        jget_number_range(c, v, w, "gather_radius", 1e30, 0, 0, &in->gather_radius) ||
        jget_number_range(c, v, w, "volume_gather_radius", in->gather_radius, 0, 0, &in->volume_gather_radius) ||
        jget_number_range(c, v, w, "alpha", 0.3, 0, 1, &in->alpha) ||
        jget_number_range(c, v, w, "volume_alpha", in->alpha, 0, 1, &in->volume_alpha) ||
        jget_number_range(c, v, w, "da_defensive", 0.2, 0, 0.999, &in->da_defensive) ||
        jget_number_range(c, v, w, "mirror_defensive", 0.05, 0, 0.999, &in->mirror_defensive) ||
        jget_number_range(c, v, w, "eda_alpha", 0.5, 1e-9, 0, &in->eda_alpha) ||
        jget_bool(c, v, w, "eda", 0, &in->eda) ||
        jget_bool(c, v, w, "fixed_volume_radius", 0, &in->fixed_volume_radius) ||
        jget_bool(c, v, w, "include_surfaces", 1, &in->include_surfaces) ||
        jget_bool(c, v, w, "low_order_scattering", 1, &in->low_order_scattering) ||
        jget_bool(c, v, w, "enable_guiding", 0, &in->enable_guiding) ||
        jget_bool(c, v, w, "enable_elliptical", 0, &in->enable_elliptical) ||
        jget_bool(c, v, w, "strict_time_width", 0, &in->strict_time_width) ||
        jget_bool(c, v, w, "control_vertex_mis", 1, &in->control_vertex_mis) ||
        jget_bool(c, v, w, "early_exit", 1, &in->early_exit) ||
        jget_bool(c, v, w, "surface_chains", 1, &in->surface_chains))
        return -1;
    if (k < 1 || k > 256) return jfail(c, w, "gather_photon_count", "must be in [1, 256] (got %ld)", k);
    if (!in->fixed_volume_radius && cJSON_GetObjectItemCaseSensitive(v, "fixed_volume_radius"))
        jwarn(c, "integrator.fixed_volume_radius: false (k-NN radii) is not supported; every volume photon "
                 "gets the progressive radius from volume_gather_radius");
    const char *leg = "euclidean", *sched = "2d", *weights = "kernel_area", *resid = "uniform", *tdir = "tables", *mirrors = "full", *vgather = "splat";
    vec3 shape;
    if (jget_string(c, v, w, "eda_table_dir", &tdir) < 0 || jget_vec3(c, v, w, "eda_shape", v3(128, 128, 256), &shape))
        return -1;
    const double sh[3] = {shape.x, shape.y, shape.z};
    for (int i = 0; i < 3; i++) {
        if (!(sh[i] >= (i == 2 ? 2 : 1) && sh[i] <= 4096 && sh[i] == floor(sh[i])))
            return jfail(c, w, "eda_shape", "expected three integers [rows 1..4096, columns 1..4096, cos bins 2..4096]");
        in->eda_shape[i] = (int)sh[i];
    }
    if (strlen(tdir) >= sizeof in->eda_table_dir) return jfail(c, w, "eda_table_dir", "path too long");
    snprintf(in->eda_table_dir, sizeof in->eda_table_dir, "%s", tdir);
    if (jget_string(c, v, w, "camera_leg", &leg) < 0 || jget_string(c, v, w, "radius_schedule", &sched) < 0 ||
        jget_string(c, v, w, "pass_weights", &weights) < 0 ||
        jget_string(c, v, w, "ellipse_residual", &resid) < 0 || jget_string(c, v, w, "darts_mirrors", &mirrors) < 0 ||
        jget_string(c, v, w, "volume_gather", &vgather) < 0)
        return -1;
    if (strcmp(mirrors, "full") && strcmp(mirrors, "straight"))
        return jfail(c, w, "darts_mirrors", "'%s' is not one of full, straight", mirrors);
    in->darts_mirrors_straight = !strcmp(mirrors, "straight");
    if (strcmp(vgather, "splat") && strcmp(vgather, "beam"))
        return jfail(c, w, "volume_gather", "'%s' is not one of splat, beam", vgather);
    in->volume_gather_beam = !strcmp(vgather, "beam");
    if (strcmp(resid, "uniform") && strcmp(resid, "exponential"))
        return jfail(c, w, "ellipse_residual", "'%s' is not one of uniform, exponential", resid);
    in->ellipse_residual = !strcmp(resid, "exponential");
    if (strcmp(leg, "euclidean") && strcmp(leg, "projected"))
        return jfail(c, w, "camera_leg", "'%s' is not one of euclidean, projected", leg);
    if (strcmp(sched, "2d") && strcmp(sched, "3d"))
        return jfail(c, w, "radius_schedule", "'%s' is not one of 2d, 3d", sched);
    in->camera_leg_projected = !strcmp(leg, "projected");
    in->radius_schedule_3d = !strcmp(sched, "3d");
    if (strcmp(weights, "kernel_area") && strcmp(weights, "equal"))
        return jfail(c, w, "pass_weights", "'%s' is not one of kernel_area, equal", weights);
    in->pass_weights_equal = !strcmp(weights, "equal");
    if (in->type == INTEGRATOR_PHOTON_POINTS && !(in->volume_gather_radius > 0 && in->volume_gather_radius < 1e29))
        return jfail(c, w, "volume_gather_radius", "photon points need a finite radius > 0 (got %g)", in->volume_gather_radius);
    if (in->type == INTEGRATOR_PHOTON_POINTS && !(in->photon_count >= 1))
        return jfail(c, w, "photon_count", "photon points need at least 1 light path per iteration");
    in->gather_photon_count = (int)k;
    return 0;
}

/* enable_two_sided_shading, enable_consistency_checks (Tungsten's TraceSettings), glossy_gather_alpha (ours) */
static int parse_shading_keys(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    const char *w = "integrator";
    if (jget_bool(c, v, w, "enable_two_sided_shading", 1, &in->two_sided_shading) ||
        jget_bool(c, v, w, "enable_consistency_checks", 0, &in->consistency_checks) ||
        jget_number(c, v, w, "glossy_gather_alpha", 0.5, &in->glossy_gather_alpha))
        return -1;
    if (!(in->glossy_gather_alpha >= 0.0) || !isfinite(in->glossy_gather_alpha))
        return jfail(c, w, "glossy_gather_alpha", "must be finite and >= 0 (got %g)", in->glossy_gather_alpha);
    return 0;
}

static int parse_integrator(json_ctx *c, const cJSON *root, integrator_settings *in)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, "integrator");
    if (v && !cJSON_IsObject(v)) return jfail(c, "integrator", NULL, "expected an object");
    jnote_unknown_keys(c, v, "integrator", integrator_keys);
    long minb = 0, maxb = 64; /* set by jget_int; initialised for the compiler's flow analysis under LTO */
    double vac_speed;
    if (parse_integrator_type(c, v, in) || jget_int(c, v, "integrator", "min_bounces", 0, &minb) ||
        jget_int(c, v, "integrator", "max_bounces", 64, &maxb) ||
        jget_number(c, v, "integrator", "vaccum_speed_of_light", 1.0, &vac_speed) ||
        jget_bool(c, v, "integrator", "enable_rr", 1, &in->enable_rr) || parse_photon_keys(c, v, in) ||
        parse_shading_keys(c, v, in))
        return -1;
    if (minb < 0) return jfail(c, "integrator", "min_bounces", "must be >= 0 (got %ld)", minb);
    if (maxb < 1 || maxb > 100000) return jfail(c, "integrator", "max_bounces", "must be in [1, 100000] (got %ld)", maxb);
    if (!(vac_speed > 0)) return jfail(c, "integrator", "vaccum_speed_of_light", "must be > 0 (got %g)", vac_speed);
    in->min_bounces = (int)(minb > maxb ? maxb : minb);
    in->max_bounces = (int)maxb;
    in->vacuum_eta = 1.0 / vac_speed;
    if (!isfinite(in->vacuum_eta)) return jfail(c, "integrator", "vaccum_speed_of_light", "too small (got %g)", vac_speed);
    return parse_window(c, v, in);
}

static int parse_output_buffers(json_ctx *c, const cJSON *v, renderer_settings *r)
{
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(v, "output_buffers");
    if (!arr) return 0;
    if (!cJSON_IsArray(arr)) return jfail(c, "renderer", "output_buffers", "expected an array");
    for (int i = 0; i < cJSON_GetArraySize(arr); i++) {
        const cJSON *b = cJSON_GetArrayItem(arr, i);
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(b, "type");
        if (!cJSON_IsString(t)) return jfail(c, "renderer", "output_buffers", "entry %d has no type", i);
        if (!strcmp(t->valuestring, "transients")) r->transients_buffer = 1;
        else if (strcmp(t->valuestring, "color"))
            jwarn(c, "renderer.output_buffers[%d]: buffer type '%s' is not written (supported: color, transients)", i, t->valuestring);
    }
    return 0;
}

static int parse_renderer(json_ctx *c, const cJSON *root, renderer_settings *r)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, "renderer");
    if (v && !cJSON_IsObject(v)) return jfail(c, "renderer", NULL, "expected an object");
    jnote_unknown_keys(c, v, "renderer", renderer_keys);
    const char *out = NULL, *hdr = NULL;
    if (jget_int(c, v, "renderer", "spp", 64, &r->spp) || get_duration(c, v, "timeout", &r->timeout_seconds) ||
        get_duration(c, v, "checkpoint_interval", &r->checkpoint_seconds) ||
        jget_string(c, v, "renderer", "output_file", &out) < 0 ||
        jget_string(c, v, "renderer", "hdr_output_file", &hdr) < 0 || parse_output_buffers(c, v, r))
        return -1;
    if (r->spp < 0) return jfail(c, "renderer", "spp", "must be >= 0 (got %ld)", r->spp);
    snprintf(r->output_file, sizeof r->output_file, "%s", out ? out : "");
    snprintf(r->hdr_output_file, sizeof r->hdr_output_file, "%s", hdr ? hdr : "");
    return 0;
}

int settings_parse(json_ctx *c, const cJSON *root, scene *s)
{
    return parse_integrator(c, root, &s->integrator) || parse_renderer(c, root, &s->renderer) ? -1 : 0;
}
