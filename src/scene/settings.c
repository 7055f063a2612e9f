/* Integrator and renderer keys: read, checked and resolved by iterating the key table (keys.c); then the
 * rules between keys (the time window, docs/time.md §3; photon points' radii) and the notes on keys that are not
 * read (docs/scene-format.md §2.8). */
#include "settings.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    if (end == text || *end || w < 1 || h < 1 || w > 65536 || h > 65536 || w * h > (1L << 28))
        return dp_fail(c->err, "%s: --set %s: expected resolution=W or resolution=WxH (1 to 65536 per side, at most "
                       "2^28 pixels in all)", c->file, set);
    cJSON *cam = cJSON_GetObjectItemCaseSensitive(root, "camera");
    if (!cJSON_IsObject(cam)) return jfail(c, "camera", NULL, "expected an object");
    cJSON_DeleteItemFromObjectCaseSensitive(cam, "resolution");
    cJSON *r = cJSON_AddArrayToObject(cam, "resolution");
    cJSON_AddItemToArray(r, cJSON_CreateNumber((double)w));
    cJSON_AddItemToArray(r, cJSON_CreateNumber((double)h));
    return 0;
}

/* The names of the keys given with --set, kept in the tree under a member no scene file has, so that the check
 * of unread keys can tell the user's settings from the file's (note_unread_keys). */
#define SET_KEYS_MEMBER "\001dartspp --set keys"

int settings_apply_overrides(json_ctx *c, cJSON *root, const char *const *sets, int count)
{
    cJSON *given = count > 0 ? cJSON_AddArrayToObject(root, SET_KEYS_MEMBER) : NULL;
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
        const scene_key *k = scene_key_find(key);
        if (!k) {
            int count;
            const scene_key *keys = scene_keys(&count);
            key_near near = {0};
            for (int j = 0; j < count; j++) key_near_consider(&near, key, keys[j].name);
            char hint[128] = "";
            if (near.best) snprintf(hint, sizeof hint, "; did you mean '%s'?", near.best);
            return dp_fail(c->err, "%s: --set %s: unknown integrator or renderer key '%s' (dartspp keys lists them%s)",
                           c->file, sets[i], key, hint);
        }
        const char *section = scene_key_section_name(k->section);
        cJSON *obj = cJSON_GetObjectItemCaseSensitive(root, section);
        if (!obj) obj = cJSON_AddObjectToObject(root, section);
        if (!cJSON_IsObject(obj)) return jfail(c, section, NULL, "expected an object");
        cJSON_DeleteItemFromObjectCaseSensitive(obj, key);
        cJSON_AddItemToObject(obj, key, override_value(eq + 1));
        if (given) cJSON_AddItemToArray(given, cJSON_CreateString(key));
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

/* A duration; a negative number (the reference writes "timeout": "-1") means no limit, stored as 0. */
static int get_duration(json_ctx *c, const cJSON *v, const char *where, const char *key, double *out)
{
    *out = 0;
    if (cJSON_IsNumber(v) && v->valuedouble < 0 && isfinite(v->valuedouble)) return 0;
    if (cJSON_IsString(v) && v->valuestring[0] == '-' && parse_duration_seconds(v->valuestring + 1) > 0) return 0;
    if (cJSON_IsNumber(v)) *out = v->valuedouble >= 0 ? v->valuedouble * 60.0 : -1;
    else if (cJSON_IsString(v)) *out = parse_duration_seconds(v->valuestring);
    else *out = -1;
    if (*out < 0 || !isfinite(*out))
        return jfail(c, where, key, "expected a duration (bare number = minutes; suffixes ms, s, m, h, d)");
    return 0;
}

static void *key_field(const scene_key *k, scene *s)
{
    char *base = k->section == KEY_SECTION_INTEGRATOR ? (char *)&s->integrator : (char *)&s->renderer;
    return base + k->offset;
}

static int check_range(json_ctx *c, const scene_key *k, const char *where, double v)
{
    int lo_ok = !(k->bounds & KEY_LO) || (k->bounds & KEY_LO_OPEN ? v > k->lo : v >= k->lo);
    int hi_ok = !(k->bounds & KEY_HI) || v <= k->hi;
    if (lo_ok && hi_ok) return 0;
    if ((k->bounds & KEY_LO) && (k->bounds & KEY_HI))
        return jfail(c, where, k->name, "must be in [%g, %g] (got %.17g)", k->lo, k->hi, v);
    if (!lo_ok) return jfail(c, where, k->name, "must be %s %g (got %.17g)", k->bounds & KEY_LO_OPEN ? ">" : ">=", k->lo, v);
    return jfail(c, where, k->name, "must be <= %g (got %.17g)", k->hi, v);
}

/* The default of a bool, int, number or choice key: its own, or the resolved value of the key it follows
 * (def_from names an earlier number key of the table: volume_alpha follows alpha). */
static double key_default(const scene_key *k, scene *s)
{
    const scene_key *from = k->def_from ? scene_key_find(k->def_from) : NULL;
    return from ? *(const double *)key_field(from, s) : k->def;
}

static int read_number_key(json_ctx *c, const scene_key *k, const char *where, const cJSON *obj, scene *s)
{
    double d;
    if (jget_number(c, obj, where, k->name, key_default(k, s), &d) || check_range(c, k, where, d)) return -1;
    if (k->type == KEY_NUMBER && k->integral && d != floor(d))
        return jfail(c, where, k->name, "expected a whole number, it counts paths or photons (got %.17g)", d);
    if (k->type == KEY_NUMBER) {
        *(double *)key_field(k, s) = d;
        return 0;
    }
    if (d != floor(d)) return jfail(c, where, k->name, "expected an integer (got %.17g)", d);
    *(long *)key_field(k, s) = (long)d;
    return 0;
}

static int read_choice_key(json_ctx *c, const scene_key *k, const char *where, const cJSON *obj, scene *s)
{
    const char *name = k->choices[(int)k->def];
    if (jget_string(c, obj, where, k->name, &name) < 0) return -1;
    for (int i = 0; k->choices[i]; i++)
        if (!strcmp(k->choices[i], name)) {
            *(int *)key_field(k, s) = i;
            return 0;
        }
    char list[256] = "";
    for (int i = 0; k->choices[i]; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", k->choices[i]);
    return jfail(c, where, k->name, "'%s' is not one of %s", name, list);
}

/* [a, b, c]: integers in [lo, hi], the last at least lo + 1 */
static int read_shape_key(json_ctx *c, const scene_key *k, const char *where, const cJSON *v, int *out)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3)
        return jfail(c, where, k->name, "expected three integers in [%g, %g] (the last at least %g)", k->lo, k->hi, k->lo + 1);
    for (int i = 0; i < 3; i++) {
        const cJSON *e = cJSON_GetArrayItem(v, i);
        double d = cJSON_IsNumber(e) ? e->valuedouble : NAN, lo = i == 2 ? k->lo + 1 : k->lo;
        if (!(d >= lo && d <= k->hi && d == floor(d)))
            return jfail(c, where, k->name, "expected three integers in [%g, %g] (the last at least %g)", k->lo, k->hi, k->lo + 1);
        out[i] = (int)d;
    }
    return 0;
}

static int list_value_in_range(const scene_key *k, double v)
{
    int lo_ok = !(k->bounds & KEY_LO) || (k->bounds & KEY_LO_OPEN ? v > k->lo : v >= k->lo);
    return isfinite(v) && lo_ok && (!(k->bounds & KEY_HI) || v <= k->hi);
}

/* [] or 1 to KEY_LIST_MAX distinct numbers in the key's range; a bare number is a list of one. */
static int read_list_key(json_ctx *c, const scene_key *k, const char *where, const cJSON *v, key_number_list *out)
{
    memset(out, 0, sizeof *out);
    if (!v) return 0;
    char range[96];
    scene_key_range_text(k, range, sizeof range);
    if (cJSON_IsNumber(v)) {
        if (!list_value_in_range(k, v->valuedouble))
            return jfail(c, where, k->name, "%.17g is out of range (expected %s)", v->valuedouble, range);
        out->count = 1;
        out->v[0] = v->valuedouble;
        return 0;
    }
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) > KEY_LIST_MAX)
        return jfail(c, where, k->name, "expected %s", range);
    const cJSON *e;
    cJSON_ArrayForEach(e, v) {
        if (!cJSON_IsNumber(e)) return jfail(c, where, k->name, "expected %s", range);
        if (!list_value_in_range(k, e->valuedouble))
            return jfail(c, where, k->name, "%.17g is out of range (expected %s)", e->valuedouble, range);
        for (int i = 0; i < out->count; i++)
            if (out->v[i] == e->valuedouble)
                return jfail(c, where, k->name, "%.17g is given twice (expected %s)", e->valuedouble, range);
        out->v[out->count++] = e->valuedouble;
    }
    return 0;
}

/* Reads one key of the table into its field: the value in obj, or the default. */
static int read_key(json_ctx *c, const scene_key *k, const cJSON *obj, scene *s)
{
    const char *where = scene_key_section_name(k->section);
    const cJSON *v = jget_item(c, obj, k->name);
    void *field = key_field(k, s);
    switch (k->type) {
    case KEY_BOOL: return jget_bool(c, obj, where, k->name, (int)k->def, field);
    case KEY_INT:
    case KEY_NUMBER: return read_number_key(c, k, where, obj, s);
    case KEY_CHOICE: return read_choice_key(c, k, where, obj, s);
    case KEY_STRING: {
        const char *text = k->def_text;
        if (jget_string(c, obj, where, k->name, &text) < 0) return -1;
        if (strlen(text) >= k->size) return jfail(c, where, k->name, "too long (at most %zu bytes)", k->size - 1);
        snprintf(field, k->size, "%s", text);
        return 0;
    }
    case KEY_DURATION: return v ? get_duration(c, v, where, k->name, field) : (*(double *)field = 0, 0);
    case KEY_SHAPE3: {
        cJSON *def = v ? NULL : cJSON_Parse(k->def_text);
        int rc = read_shape_key(c, k, where, v ? v : def, field);
        cJSON_Delete(def);
        return rc;
    }
    case KEY_NUMBER_LIST: return read_list_key(c, k, where, v, field);
    case KEY_ANY: return 0;
    }
    return 0;
}

/* Whether the key's resolved value is its default (keys without a scalar default count as set when given). */
static int key_at_default(const scene_key *k, scene *s)
{
    const void *f = key_field(k, s);
    switch (k->type) {
    case KEY_BOOL:
    case KEY_CHOICE: return *(const int *)f == (int)key_default(k, s);
    case KEY_INT: return *(const long *)f == (long)key_default(k, s);
    case KEY_NUMBER: return *(const double *)f == key_default(k, s);
    case KEY_NUMBER_LIST: return ((const key_number_list *)f)->count == 0;
    default: return 0;
    }
}

/* A key of no table row but a few edits from one of its section ("photon_cont"): the warning naming that row
 * (key_suggest.c). 1 when warned. */
static int misspelt_key(json_ctx *c, const char *key, scene_key_section section, const char *where)
{
    int count;
    const scene_key *keys = scene_keys(&count);
    key_near n = {0};
    for (int i = 0; i < count; i++)
        if (keys[i].section == section) key_near_consider(&n, key, keys[i].name);
    jwarn_unknown_key(c, where, key, &n);
    return n.best != NULL;
}

/* Whether --set gave the key (the list of settings_apply_overrides). */
static int given_by_set(const cJSON *given, const char *name)
{
    const cJSON *it;
    cJSON_ArrayForEach(it, given) if (cJSON_IsString(it) && !strcmp(it->valuestring, name)) return 1;
    return 0;
}

/* Keys of a section that nothing will read: not in the table, written by the format and never read, or not
 * read by the chosen integrator. A key set away from its default that the integrator ignores is a warning
 * (the user asked for something that will not happen) — unless the file set it for its own integrator and
 * `--set type=...` chose another: the demo's photon keys under `--set type=path_tracer` are the scene's
 * settings for the integrator it was written for, not a mistake. The rest are notes with --verbose. */
static void note_unread_keys(json_ctx *c, const cJSON *obj, scene_key_section section, scene *s, const cJSON *given)
{
    if (!cJSON_IsObject(obj)) return;
    int switched = given_by_set(given, "type");
    const char *where = scene_key_section_name(section);
    for (const cJSON *it = obj->child; it; it = it->next) {
        const scene_key *k = it->string ? scene_key_find(it->string) : NULL;
        if (k && k->section != section) k = NULL;
        if (k && scene_key_read_by(k, s->integrator.type)) continue;
        if (k && k->read_by && !key_at_default(k, s) && (!switched || given_by_set(given, k->name)))
            jwarn(c, "%s.%s: the %s integrator does not read this key; its value has no effect", where, k->name,
                  s->integrator.type_name);
        else if (!k && misspelt_key(c, it->string, section, where)) continue;
        else if (c->verbose && c->notes && !k)
            strbuf_addf(c->notes, "ignored key: %s.%s (not a key of dartspp)", where, it->string);
        else if (c->verbose && c->notes && !k->read_by)
            strbuf_addf(c->notes, "ignored key: %s.%s (accepted from the format, not read by dartspp)", where, k->name);
        else if (c->verbose && c->notes)
            strbuf_addf(c->notes, "ignored key: %s.%s (not read by %s)", where, k->name, s->integrator.type_name);
    }
}

/* A window narrower than the rounding of its own times: its start and end, and every arrival time compared with
 * them, carry a relative error of 2^-52, so a width below a thousand times that rounding at the window's end (where
 * the rounding would move a thousandth of the gate's detections in or out) (a gate of
 * 1e-300 at 6 is [6, 6); one of 0.5 centred at 1e200 starts and ends at 1e200) holds nothing, or whatever the
 * rounding puts in it: the image is black or wrong (issue 48). Refused, naming the width key. */
static int window_precision(json_ctx *c, const time_window *tw)
{
    if (!tw->gated) return 0;
    double end = tw->start + tw->width * (tw->frame_count > 0 ? tw->frame_count : 1);
    double scale = dp_fmax(fabs(tw->start), fabs(end));
    if (tw->width >= 1e3 * DBL_EPSILON * scale && end > tw->start) return 0;
    return jfail(c, "integrator", "transient_time_width", "%g is below the precision of the window's times (%s at "
                 "%g: arrival times there are rounded by up to %g); a %s needs a width of at least %g there",
                 tw->width, tw->frame_count > 0 ? "frames starting" : "a gate starting", tw->start, scale * DBL_EPSILON,
                 tw->frame_count > 0 ? "frame" : "gate", 1e3 * DBL_EPSILON * scale);
}

/* The time window from the time keys: no time key at all is steady state (as the reference path tracer). */
static int resolve_window(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    int timed = cJSON_HasObjectItem(v, "transient_time_center") || cJSON_HasObjectItem(v, "frame_num") ||
                cJSON_HasObjectItem(v, "transient_time_width");
    double width = timed ? in->transient_time_width : 0.0;
    time_window *tw = &in->window;
    tw->camera_unwarp = in->camera_unwarp;
    tw->frame_count = (int)in->frame_num;
    tw->orders = in->bounce_orders > 0 ? (int)in->bounce_orders + 1 : 0;
    tw->width = width;
    if (tw->frame_count > 0) {
        if (width <= 0) return jfail(c, "integrator", "transient_time_width", "empty time window: frames need a width > 0");
        tw->gated = 1;
        tw->start = in->start_time;
    } else {
        tw->gated = width > 0;
        tw->start = width > 0 ? in->transient_time_center - 0.5 * width : 0.0;
    }
    if (in->delta_time_gate) { /* checked by delta_gate_refusal: photon points or beams, one gate, width > 0 */
        tw->delta = 1;
        tw->center = in->transient_time_center;
    }
    return window_precision(c, tw);
}

/* The volume photon types that estimate a delta gate (delta_time_gate): a temporal box kernel K_τ of width w_i
 * centred on the gate, with the joint schedule of the radius and the width (src/plan, docs/beams.md §5). A type
 * that can: one line here. */
static const int delta_gate_estimated[] = {
    [VOLUME_PHOTON_POINTS] = 1,
    [VOLUME_PHOTON_BEAMS] = 1,
    /* the sliced primitives: τ_k at the instant itself (no temporal kernel); their beams fallback as beams */
    [VOLUME_PHOTON_BALLS] = 1, [VOLUME_PHOTON_VOLUMES] = 1, [VOLUME_PHOTON_HYPERVOLUMES] = 1,
    [VOLUME_PHOTON_VOLUMES_BALLS] = 1, [VOLUME_PHOTON_MIS_VOLUMES_BALLS] = 1,
};

/* delta_time_gate: refused where no estimator of the time density at the gate's instant runs, or where the
 * combination is not supported (docs/time.md §3.1). */
static int delta_gate_refusal(json_ctx *c, const cJSON *v, const integrator_settings *in)
{
    const char *key = "delta_time_gate";
    if (!in->delta_time_gate) return 0;
    if (in->type == INTEGRATOR_PATH_TRACER)
        return jfail(c, "integrator", key, "the path tracer cannot estimate a delta gate: an unbiased path tracer "
                     "never samples a path of exactly the gate's time (it has probability 0); use a narrow box gate "
                     "(transient_time_width) or progressive_transient_photon_map, whose temporal kernel shrinks");
    int t = in->volume_photon_type, n = (int)(sizeof delta_gate_estimated / sizeof delta_gate_estimated[0]);
    if (t == VOLUME_PHOTON_PLANES || t == VOLUME_PHOTON_PLANES_1D)
        return jfail(c, "integrator", key, "volume_photon_type \"%s\" integrates a box gate analytically "
                     "(Liu et al. 2022 §4.2: the gate is the plane's 4th analytic dimension), and a delta gate "
                     "leaves it nothing to integrate; use a box gate (transient_time_width), or balls, volumes or "
                     "hypervolumes",
                     scene_key_find("volume_photon_type")->choices[t]);
    if (t < 0 || t >= n || !delta_gate_estimated[t])
        return jfail(c, "integrator", key, "volume_photon_type \"%s\" has no delta-gate estimator yet (points, "
                     "beams, balls, volumes, hypervolumes, volumes_balls and mis_volumes_balls do)", scene_key_find("volume_photon_type")->choices[t]);
    if (!cJSON_HasObjectItem(v, "transient_time_center") || !(in->transient_time_width > 0))
        return jfail(c, "integrator", key, "a delta gate needs transient_time_center (its instant) and "
                     "transient_time_width > 0 (the width of the first iteration's temporal kernel)");
    if (in->frame_num > 0)
        return jfail(c, "integrator", key, "frames (frame_num %ld) with a delta gate are not supported: a delta gate "
                     "is one instant; render one scene per instant", in->frame_num);
    if (in->enable_guiding || in->enable_elliptical || in->eda || in->strict_time_width)
        return jfail(c, "integrator", key, "the DARTS samplers (%s) aim at a fixed box window and do not follow the "
                     "delta gate's shrinking width; set enable_guiding, enable_elliptical, eda and strict_time_width "
                     "to false", in->enable_guiding ? "enable_guiding" : in->enable_elliptical ? "enable_elliptical"
                                 : in->eda ? "eda" : "strict_time_width");
    if (t == VOLUME_PHOTON_BEAMS && in->radius_schedule == RADIUS_SCHEDULE_3D)
        return jfail(c, "integrator", key, "radius_schedule \"3d\" (the cube root of a box gate) does not apply to "
                     "beams under a delta gate, whose radius and width both shrink by the square root (Liu et al. "
                     "2022's progressive photon map); leave radius_schedule at \"2d\"");
    return 0;
}

/* Rules between integrator keys, after every key is read. */
static int resolve_integrator(json_ctx *c, const cJSON *v, integrator_settings *in)
{
    snprintf(in->type_name, sizeof in->type_name, "%s", integrator_type_name((integrator_type)in->type));
    if (in->min_bounces > in->max_bounces)
        return jfail(c, "integrator", "min_bounces", "%ld is more than max_bounces (%ld): no path would count",
                     in->min_bounces, in->max_bounces);
    in->vacuum_eta = 1.0 / in->vaccum_speed_of_light;
    if (!isfinite(in->vacuum_eta))
        return jfail(c, "integrator", "vaccum_speed_of_light", "too small (got %g)", in->vaccum_speed_of_light);
    if (in->type == INTEGRATOR_PHOTON_POINTS && !(in->volume_gather_radius > 0 && in->volume_gather_radius < 1e29))
        return jfail(c, "integrator", "volume_gather_radius", "photon points need a finite radius > 0 (got %g)",
                     in->volume_gather_radius);
    if (in->type == INTEGRATOR_PHOTON_POINTS && !(in->photon_count >= 1))
        return jfail(c, "integrator", "photon_count", "photon points need at least 1 light path per iteration");
    if (in->type == INTEGRATOR_PATH_TRACER && in->time_sampling == TIME_SAMPLING_UNIFORM &&
        (in->enable_guiding || in->enable_elliptical || in->eda))
        return jfail(c, "integrator", "time_sampling",
                     "'uniform' is a method of its own (free flight, line-to-point connections, time-angular "
                     "directions) and cannot run with %s; set %s to false, or time_sampling to \"none\" for DARTS",
                     in->enable_guiding ? "enable_guiding" : in->enable_elliptical ? "enable_elliptical" : "eda",
                     in->enable_guiding ? "enable_guiding" : in->enable_elliptical ? "enable_elliptical" : "eda");
    if (in->type == INTEGRATOR_PHOTON_POINTS && !in->fixed_volume_radius &&
        cJSON_GetObjectItemCaseSensitive(v, "fixed_volume_radius"))
        jwarn(c, "integrator.fixed_volume_radius: false (k-NN radii) is not supported; every volume photon "
                 "gets the progressive radius from volume_gather_radius");
    if (delta_gate_refusal(c, v, in)) return -1;
    return resolve_window(c, v, in);
}

static const cJSON *section_object(json_ctx *c, const cJSON *root, scene_key_section section, int *bad)
{
    const char *name = scene_key_section_name(section);
    const cJSON *v = jget_item(c, root, name);
    *bad = v && !cJSON_IsObject(v) ? jfail(c, name, NULL, "expected an object") : 0;
    return v;
}

/* renderer.amcw_frequencies into the time window, which every film is made from (docs/amcw.md §2). */
static int resolve_amcw(json_ctx *c, const renderer_settings *re, integrator_settings *in)
{
    const key_number_list *l = &re->amcw_frequencies;
    time_window *tw = &in->window;
    tw->amcw_count = l->count;
    for (int i = 0; i < l->count; i++) tw->amcw_mhz[i] = l->v[i];
    if (!l->count) return 0;
    if (tw->delta)
        return jfail(c, "renderer", "amcw_frequencies", "AMCW integrates the light over time, a delta gate "
                     "(integrator.delta_time_gate) keeps one instant: use a box gate, frames or steady state");
    if (tw->camera_unwarp)
        jwarn(c, "renderer.amcw_frequencies: with integrator.camera_unwarp the phases leave out the camera leg, so "
                 "<stem>_amcw_depth.npy is not the distance to the camera (docs/amcw.md §4)");
    return 0;
}

int settings_parse(json_ctx *c, const cJSON *root, scene *s)
{
    int bad_in, bad_re, n;
    const cJSON *in = section_object(c, root, KEY_SECTION_INTEGRATOR, &bad_in);
    const cJSON *re = section_object(c, root, KEY_SECTION_RENDERER, &bad_re);
    if (bad_in || bad_re) return -1;
    const scene_key *keys = scene_keys(&n);
    for (int i = 0; i < n; i++)
        if (read_key(c, &keys[i], keys[i].section == KEY_SECTION_INTEGRATOR ? in : re, s)) return -1;
    if (resolve_integrator(c, in, &s->integrator) || resolve_amcw(c, &s->renderer, &s->integrator)) return -1;
    const cJSON *timeout = jget_item(c, re, "timeout");
    if (cJSON_IsNumber(timeout) && timeout->valuedouble < 0)
        snprintf(s->renderer.timeout_negative, sizeof s->renderer.timeout_negative, "%g", timeout->valuedouble);
    else if (cJSON_IsString(timeout) && timeout->valuestring[0] == '-')
        snprintf(s->renderer.timeout_negative, sizeof s->renderer.timeout_negative, "%s", timeout->valuestring);
    const cJSON *given = jget_item(c, root, SET_KEYS_MEMBER);
    note_unread_keys(c, in, KEY_SECTION_INTEGRATOR, s, given);
    note_unread_keys(c, re, KEY_SECTION_RENDERER, s, given);
    return 0;
}
