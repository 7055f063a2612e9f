/* `--derivative POINTER`: JSON Pointers (RFC 6901) into the scene file resolved to the diff_param records of
 * scene.h (docs/derivatives.md §1 Parameters): what the parameter moves, as derivatives of the scene's internal
 * values. Run once the scene is parsed, on the same cJSON tree (with the --set overrides applied). Refusals name
 * the file, the pointer and the reason. */
#include "scene_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PTR_TOKENS 8

static const char DIFFERENTIABLE[] =
    "media[i]: sigma_s, sigma_a (or one channel), density, visibility, albedo (with visibility), speed_of_light, "
    "phase_function/g; primitives[i]: "
    "emission or power (or one channel), pulse_start, pulse_width, transform/position/<0|1|2>; bsdfs[i]: albedo "
    "(or one channel); camera/transform/position/<0|1|2>; integrator: transient_time_center, transient_time_width, "
    "start_time, vaccum_speed_of_light";

/* A pointer split into its reference tokens, ~1 and ~0 undone (RFC 6901). */
typedef struct {
    const char *text;
    char tok[PTR_TOKENS][128];
    int n;
} json_ptr;

/* What a resolution works from. */
typedef struct {
    json_ctx *c;
    const cJSON *root;
    scene *s;
    const prim_slot *prims;
    int prim_count;
} diff_ctx;

static int dfail(const diff_ctx *d, const json_ptr *p, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int dfail(const diff_ctx *d, const json_ptr *p, const char *fmt, ...)
{
    char reason[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    return dp_fail(d->c->err, "%s: --derivative %s: %s", d->c->file, p->text, reason);
}

static int ptr_parse(const diff_ctx *d, const char *text, json_ptr *p)
{
    p->text = text;
    p->n = 0;
    if (strlen(text) >= sizeof((diff_param *)0)->pointer)
        return dfail(d, p, "longer than %zu characters", sizeof((diff_param *)0)->pointer - 1);
    if (text[0] != '/')
        return dfail(d, p, "not a JSON Pointer: it must start with '/' (RFC 6901), e.g. /media/0/sigma_s");
    for (const char *q = text; *q == '/';) {
        if (p->n == PTR_TOKENS) return dfail(d, p, "more than %d levels: names nothing in a scene file", PTR_TOKENS);
        char *out = p->tok[p->n++];
        size_t k = 0;
        for (q++; *q && *q != '/'; q++) {
            char ch = *q;
            if (ch == '~') {
                if (q[1] != '0' && q[1] != '1')
                    return dfail(d, p, "bad escape '~%c' (RFC 6901 allows ~0 for '~' and ~1 for '/')", q[1] ? q[1] : ' ');
                ch = *++q == '0' ? '~' : '/';
            }
            if (k + 1 >= sizeof p->tok[0]) return dfail(d, p, "a key longer than %zu characters", sizeof p->tok[0] - 1);
            out[k++] = ch;
        }
        out[k] = 0;
    }
    return 0;
}

/* An array index token: digits without a leading zero (RFC 6901); -1 otherwise. */
static int ptr_index(const char *t)
{
    size_t n = strlen(t);
    if (n == 0 || n > 9 || (n > 1 && t[0] == '0')) return -1;
    for (size_t i = 0; i < n; i++)
        if (t[i] < '0' || t[i] > '9') return -1;
    return atoi(t);
}

/* The pointer's prefix of k tokens, as text, for messages. */
static void ptr_prefix(const json_ptr *p, int k, char *out, size_t n)
{
    out[0] = 0;
    for (int i = 0; i < k; i++) {
        size_t len = strlen(out);
        snprintf(out + len, n - len, "/%s", p->tok[i]);
    }
}

/* Whether the first k tokens are a BSDF or medium reference, which may be a name (src/scene/scene_load.c). */
static int is_reference(const json_ptr *p, int k)
{
    if (k == 3 && !strcmp(p->tok[0], "primitives"))
        return !strcmp(p->tok[2], "bsdf") || !strcmp(p->tok[2], "int_medium") || !strcmp(p->tok[2], "ext_medium");
    return k == 2 && !strcmp(p->tok[0], "camera") && !strcmp(p->tok[1], "medium");
}

/* The value the pointer names: 0; 1 when a reference by name stops the walk (*out the name); or a refusal
 * ("names nothing"). */
static int ptr_walk(const diff_ctx *d, const json_ptr *p, const cJSON **out)
{
    const cJSON *v = d->root;
    char pre[300];
    for (int i = 0; i < p->n; i++) {
        ptr_prefix(p, i + 1, pre, sizeof pre);
        const cJSON *next = NULL;
        if (cJSON_IsArray(v)) {
            int k = ptr_index(p->tok[i]), size = cJSON_GetArraySize(v);
            if (k < 0) return dfail(d, p, "names nothing: '%s' in %s is not an array index (digits, no leading zero)", p->tok[i], pre);
            if (k >= size)
                return dfail(d, p, "names nothing: %s does not exist (the array has %d element%s)", pre, size,
                             size == 1 ? "" : "s");
            next = cJSON_GetArrayItem(v, k);
        } else if (cJSON_IsObject(v)) {
            next = cJSON_GetObjectItemCaseSensitive(v, p->tok[i]);
            if (!next)
                return dfail(d, p, "names nothing: %s is not in the file (a default is not a value of the file: write "
                             "the key, or --set it, to differentiate it)", pre);
        } else if (is_reference(p, i) && cJSON_IsString(v)) {
            *out = v;
            return 1; /* a name: the caller says where what it names is */
        } else {
            return dfail(d, p, "names nothing: %s is inside a %s, which has no members", pre,
                         cJSON_IsString(v) ? "string" : "number");
        }
        v = next;
    }
    *out = v;
    return 0;
}

/* The value as a parameter: a number, or one channel of a 3-vector (chan >= 0), or a whole 3-vector. */
static int is_vec3(const cJSON *v)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) return 0;
    for (int i = 0; i < 3; i++)
        if (!cJSON_IsNumber(cJSON_GetArrayItem(v, i))) return 0;
    return 1;
}

/* The channels a colour pointer moves: tokens [at] is the key, [at + 1] an optional channel. mask: 1 per
 * channel moved. */
static int channels(const diff_ctx *d, const json_ptr *p, int at, const cJSON *key_value, vec3 *mask)
{
    if (p->n == at + 1) {
        if (!cJSON_IsNumber(key_value) && !is_vec3(key_value))
            return dfail(d, p, "expected a number or [r, g, b] there");
        *mask = v3s(1.0);
        return 0;
    }
    if (p->n > at + 2 || !is_vec3(key_value)) return dfail(d, p, "names nothing dartspp differentiates: %s is %s",
                                                          p->tok[at], cJSON_IsNumber(key_value) ? "one number for all channels (name it whole)" : "not [r, g, b]");
    int k = ptr_index(p->tok[at + 1]);
    *mask = v3s(0.0);
    if (k == 0) mask->x = 1;
    else if (k == 1) mask->y = 1;
    else mask->z = 1;
    return 0;
}

static vec3 json_vec3(const cJSON *v, vec3 def)
{
    if (cJSON_IsNumber(v)) return v3s(v->valuedouble);
    if (!is_vec3(v)) return def;
    return v3(cJSON_GetArrayItem(v, 0)->valuedouble, cJSON_GetArrayItem(v, 1)->valuedouble,
              cJSON_GetArrayItem(v, 2)->valuedouble);
}

/* The first channel moved (mask) where value is 0, or -1. */
static int zero_channel(vec3 value, vec3 mask)
{
    for (int i = 0; i < 3; i++)
        if (v3_comp(mask, i) != 0.0 && v3_comp(value, i) == 0.0) return i;
    return -1;
}

/* 1/value in the channels moved: ∂ ln(value)/∂θ for a parameter the value is proportional to. */
static vec3 dlog_of(vec3 value, vec3 mask)
{
    return v3(mask.x ? 1.0 / value.x : 0.0, mask.y ? 1.0 / value.y : 0.0, mask.z ? 1.0 / value.z : 0.0);
}

/* ---- time: the path time must have a density (derivative.h, time_kernel_has_density) ---- */

static int emits(const emitter *L) { return L->flux.x > 0 || L->flux.y > 0 || L->flux.z > 0; }

/* A refusal when time cannot be differentiated here: steady state, a delta gate, or light `light` (-1: any
 * light that emits) with a delta pulse and the sensor's response off. */
static int time_refusal(const diff_ctx *d, const json_ptr *p, int light)
{
    const scene *s = d->s;
    const time_window *tw = &s->integrator.window;
    if (!tw->gated)
        return dfail(d, p, "the render is steady state (no transient_time_width or frame_num): time does not enter "
                           "the image, so a parameter of time has no derivative to render; give the scene a gate "
                           "or frames");
    if (tw->delta)
        return dfail(d, p, "delta_time_gate: the gate is an instant, and the derivatives of time are those of a box "
                           "gate or frames (include/dartspp/derivative.h); set delta_time_gate false");
    if (s->cam.response.on) return 0;
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        if ((light >= 0 && i != light) || (light < 0 && !emits(L)) || L->pulse.width > 0.0) continue;
        return dfail(d, p, "light '%s' has a delta pulse (pulse_width 0) and the sensor's response is off: a delta "
                           "pulse and a box gate make each pixel a step in time; its derivative is a boundary term "
                           "the estimator cannot see; give the pulse a width or the sensor a response "
                           "(sensor_jitter_fwhm)", L->name);
    }
    return 0;
}

/* ---- media ---- */

static int medium_param(const diff_ctx *d, const json_ptr *p, const cJSON *obj, int at, int med, diff_param *r)
{
    const medium *m = &d->s->media[med];
    const char *key = p->tok[at];
    const cJSON *kv = cJSON_GetObjectItemCaseSensitive(obj, key);
    r->kind = DIFF_MEDIUM;
    r->index = med;
    double density = cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(obj, "density"))
                         ? cJSON_GetObjectItemCaseSensitive(obj, "density")->valuedouble : 1.0;
    vec3 mask;
    if (!strcmp(key, "sigma_s") || !strcmp(key, "sigma_a")) {
        if (channels(d, p, at, kv, &mask)) return -1;
        *(key[6] == 's' ? &r->dsigma_s : &r->dsigma_a) = v3_scale(mask, density); /* σ = density·sigma (media_load.c) */
    } else if (!strcmp(key, "density") && p->n == at + 1) {
        r->dsigma_s = json_vec3(cJSON_GetObjectItemCaseSensitive(obj, "sigma_s"), v3s(0));
        r->dsigma_a = json_vec3(cJSON_GetObjectItemCaseSensitive(obj, "sigma_a"), v3s(0));
    } else if (!strcmp(key, "speed_of_light") && p->n == at + 1) {
        r->deta = -m->eta * m->eta; /* η = 1/v: ∂η/∂v = −1/v² = −η² */
        return time_refusal(d, p, -1);
    } else if (!strcmp(key, "visibility") && p->n == at + 1) {
        /* σs, σa ∝ 1/V (media_load.c, medium_visibility_extinction): ∂σ/∂V = −σ/V */
        double vis = cJSON_IsNumber(kv) ? kv->valuedouble : 0.0;
        if (!(vis > 0.0)) return dfail(d, p, "expected a number > 0 there");
        r->dsigma_s = v3_scale(m->sigma_s, -1.0 / vis);
        r->dsigma_a = v3_scale(m->sigma_a, -1.0 / vis);
    } else if (!strcmp(key, "albedo") && p->n == at + 1 && cJSON_GetObjectItemCaseSensitive(obj, "visibility")) {
        /* σs = albedo·σt, σa = (1 − albedo)·σt with σt fixed by the visibility */
        r->dsigma_s = m->sigma_t;
        r->dsigma_a = v3_neg(m->sigma_t);
    } else if (!strcmp(key, "phase_function") && p->n == at + 2 && !strcmp(p->tok[at + 1], "g")) {
        if (m->phase.type == PHASE_TABULATED)
            return dfail(d, p, "medium '%s' has a tabulated phase function (%s), which reads no g: its shape is the "
                               "table's and is not a parameter dartspp differentiates", m->name, m->phase.table->path);
        if (m->phase.type == PHASE_ISOTROPIC)
            return dfail(d, p, "medium '%s' has an isotropic phase function, which reads no g; write type "
                               "henyey_greenstein with g 0 to differentiate g there", m->name);
        r->kind = DIFF_PHASE_G;
        return 0;
    } else {
        return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
    }
    int ch = zero_channel(m->sigma_s, r->dsigma_s);
    if (ch >= 0)
        return dfail(d, p, "medium '%s' has sigma_s 0 in channel %d (density applied), which this moves: no "
                           "scattering vertex is ever sampled there, so the derivative's scattering is never seen; "
                           "give it a small sigma_s (e.g. 1e-3)", m->name, ch);
    return 0;
}

/* A medium reached through a reference (a surface's int_medium or ext_medium, the camera's medium, a light's
 * ext_medium): inline objects only; a name points to its entry of media[]. */
static int medium_ref_param(const diff_ctx *d, const json_ptr *p, const cJSON *ref, int at, int med, diff_param *r)
{
    if (cJSON_IsString(ref)) {
        for (int i = 0; i < d->s->medium_count; i++)
            if (!strcmp(d->s->media[i].name, ref->valuestring))
                return dfail(d, p, "names nothing: '%s' names medium '%s'; differentiate it at /media/%d/...",
                             p->tok[at - 1], ref->valuestring, i);
        return dfail(d, p, "names nothing: %s is a name, not a medium", p->tok[at - 1]);
    }
    if (!cJSON_IsObject(ref) || med < 0) return dfail(d, p, "names nothing: %s is not a medium object", p->tok[at - 1]);
    return medium_param(d, p, ref, at, med, r);
}

/* ---- BSDFs ---- */

/* The models whose f is albedo ⊙ g(wi, wo), g independent of the albedo (the files of src/bsdf), so that a vertex's
 * ∂ ln f/∂albedo_c = 1/albedo_c. The plastics are not: their substrate is ρ/(1 − ρ F̄) under an albedo-free coat
 * (plastic.c, rough_plastic.c) or albedo/π beside one (pbrt_plastic.c); null and forward read no albedo. */
static int albedo_linear(bsdf_type t)
{
    return t == BSDF_LAMBERT || t == BSDF_MIRROR || t == BSDF_CONDUCTOR || t == BSDF_ROUGH_CONDUCTOR ||
           t == BSDF_DIELECTRIC || t == BSDF_ROUGH_DIELECTRIC;
}

static int bsdf_param(const diff_ctx *d, const json_ptr *p, const cJSON *obj, int at, int b, diff_param *r)
{
    const bsdf *B = &d->s->bsdfs[b];
    if (strcmp(p->tok[at], "albedo"))
        return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
    const cJSON *kv = cJSON_GetObjectItemCaseSensitive(obj, "albedo");
    if (cJSON_IsString(kv) || B->texture >= 0)
        return dfail(d, p, "bsdf '%s' has a textured albedo: its derivative would be one per texel; give a constant "
                           "albedo", B->name);
    if (!albedo_linear(B->type))
        return dfail(d, p, "bsdf '%s' is %s, not linear in its albedo (the ones that are: lambert, mirror, "
                           "conductor, rough_conductor, dielectric, rough_dielectric)", B->name, bsdf_type_name(B->type));
    vec3 mask;
    if (channels(d, p, at, kv, &mask)) return -1;
    int ch = zero_channel(B->albedo, mask);
    if (ch >= 0)
        return dfail(d, p, "bsdf '%s' has albedo 0 in channel %d, which this moves: its paths carry nothing there, "
                           "so ∂ ln f is infinite; give it a small albedo", B->name, ch);
    r->kind = DIFF_ALBEDO;
    r->index = b;
    r->dlog = dlog_of(B->albedo, mask);
    return 0;
}

/* ---- translations ---- */

/* tokens [at..] = "transform", then "position", <axis> (an object) or <3|7|11> (a row-major matrix). */
static int translation(const diff_ctx *d, const json_ptr *p, const cJSON *obj, int at, diff_param *r)
{
    const cJSON *T = cJSON_GetObjectItemCaseSensitive(obj, "transform");
    int axis = -1;
    if (cJSON_IsArray(T) && p->n == at + 2) {
        int k = ptr_index(p->tok[at + 1]);
        axis = k == 3 ? 0 : k == 7 ? 1 : k == 11 ? 2 : -1;
        if (axis < 0)
            return dfail(d, p, "not a parameter dartspp differentiates: of a 16-number transform only the "
                               "translation (elements 3, 7, 11) is (it can: %s)", DIFFERENTIABLE);
    } else if (cJSON_IsObject(T) && p->n >= at + 2 && !strcmp(p->tok[at + 1], "position")) {
        if (p->n != at + 3)
            return dfail(d, p, "a position is a point, not a parameter: name one coordinate (%s/0, /1 or /2)", p->text);
        if (!is_vec3(cJSON_GetObjectItemCaseSensitive(T, "position")))
            return dfail(d, p, "names nothing dartspp differentiates: position is not [x, y, z]");
        axis = ptr_index(p->tok[at + 2]);
        if (cJSON_GetObjectItemCaseSensitive(T, "look_at"))
            return dfail(d, p, "the transform has look_at: moving position also turns it toward look_at, which is "
                               "not a translation; give its axes (x_axis, y_axis, z_axis) or a matrix instead");
    } else {
        return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
    }
    r->kind = DIFF_TRANSLATE;
    r->axis = v3(axis == 0, axis == 1, axis == 2); /* ∂position/∂θ: position is T's translation (transform.c) */
    return time_refusal(d, p, -1);
}

/* ---- primitives ---- */

static int light_param(const diff_ctx *d, const json_ptr *p, const cJSON *obj, int light, diff_param *r)
{
    const emitter *L = &d->s->lights[light];
    const char *key = p->tok[2];
    r->index = light;
    if (!strcmp(key, "emission") || !strcmp(key, "power")) {
        vec3 mask, value = json_vec3(cJSON_GetObjectItemCaseSensitive(obj, key), v3s(0));
        if (channels(d, p, 2, cJSON_GetObjectItemCaseSensitive(obj, key), &mask)) return -1;
        int ch = zero_channel(value, mask);
        if (ch >= 0)
            return dfail(d, p, "light '%s' has %s 0 in channel %d, which this moves: it emits nothing there, so "
                               "∂ ln L_e is infinite; give it a small value", L->name, key, ch);
        r->kind = DIFF_EMISSION; /* the emitted radiance is proportional to emission and to power (light_load.c) */
        r->dlog = dlog_of(value, mask);
        return 0;
    }
    if (!strcmp(key, "pulse_start") && p->n == 3) {
        r->kind = DIFF_PULSE_START;
        return time_refusal(d, p, light);
    }
    if (!strcmp(key, "pulse_width") && p->n == 3) {
        r->kind = DIFF_PULSE_WIDTH;
        if (!(L->pulse.width > 0.0))
            return dfail(d, p, "light '%s' has pulse_width 0 (a delta pulse): a width's derivative there is a "
                               "boundary term; give the pulse a width > 0", L->name);
        return time_refusal(d, p, light);
    }
    return -2;
}

static int primitive_param(const diff_ctx *d, const json_ptr *p, const cJSON *obj, int i, diff_param *r)
{
    if (i >= d->prim_count) return dfail(d, p, "names nothing: primitive %d was not loaded", i);
    prim_slot slot = d->prims[i];
    const char *key = p->tok[2];
    if (!strcmp(key, "transform")) {
        if (translation(d, p, obj, 2, r)) return -1;
        r->target = slot.surface >= 0 ? DIFF_TARGET_SURFACES : DIFF_TARGET_LIGHT;
        r->first_surface = slot.surface;
        r->surface_count = slot.surface >= 0;
        r->light = slot.light;
        r->index = -1;
        return 0;
    }
    if (!strcmp(key, "int_medium") || !strcmp(key, "ext_medium")) {
        int med = -1;
        if (slot.surface >= 0) {
            const surface *sf = &d->s->surfaces[slot.surface];
            med = key[0] == 'i' ? sf->int_medium : sf->ext_medium;
        } else if (slot.light >= 0 && key[0] == 'e') med = d->s->lights[slot.light].medium;
        if (p->n < 4) return dfail(d, p, "names a medium, not a parameter: name one of its parameters");
        return medium_ref_param(d, p, cJSON_GetObjectItemCaseSensitive(obj, key), 3, med, r);
    }
    if (!strcmp(key, "bsdf") && slot.surface >= 0) {
        const cJSON *b = cJSON_GetObjectItemCaseSensitive(obj, "bsdf");
        int bi = d->s->surfaces[slot.surface].bsdf;
        if (cJSON_IsString(b)) return dfail(d, p, "names nothing: bsdf names '%s'; differentiate it at /bsdfs/%d/...", b->valuestring, bi);
        if (p->n < 4) return dfail(d, p, "names a BSDF, not a parameter: name its albedo");
        return bsdf_param(d, p, b, 3, bi, r);
    }
    if (!strcmp(key, "emission") || !strcmp(key, "power") || !strncmp(key, "pulse_", 6)) {
        if (slot.light < 0) return dfail(d, p, "primitive %d is not a light (it has no emission or power)", i);
        int rc = light_param(d, p, obj, slot.light, r);
        if (rc != -2) return rc;
    }
    return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
}

/* ---- the camera and the integrator ---- */

static int camera_param(const diff_ctx *d, const json_ptr *p, const cJSON *obj, diff_param *r)
{
    if (!strcmp(p->tok[1], "medium") && p->n >= 3)
        return medium_ref_param(d, p, cJSON_GetObjectItemCaseSensitive(obj, "medium"), 2, d->s->cam.medium, r);
    if (strcmp(p->tok[1], "transform")) return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
    if (translation(d, p, obj, 1, r)) return -1;
    r->target = DIFF_TARGET_CAMERA;
    r->light = -1;
    r->index = -1;
    return 0;
}

/* The time window of settings.c (resolve_window): a gate [center − w/2, center + w/2), or frames
 * [start_time + k w, start_time + (k + 1) w). */
static int integrator_param(const diff_ctx *d, const json_ptr *p, diff_param *r)
{
    const integrator_settings *in = &d->s->integrator;
    const char *key = p->tok[1];
    int frames = in->window.frame_count > 0;
    if (p->n == 2 && !strcmp(key, "vaccum_speed_of_light")) {
        r->kind = DIFF_MEDIUM;
        r->index = MEDIUM_VACUUM;
        r->deta = -in->vacuum_eta * in->vacuum_eta; /* η = 1/v */
        return time_refusal(d, p, -1);
    }
    r->kind = DIFF_WINDOW;
    r->index = -1;
    if (p->n == 2 && !strcmp(key, "transient_time_center")) {
        if (frames) return dfail(d, p, "with frames (frame_num %ld) the window starts at start_time: "
                                       "transient_time_center is not read", in->frame_num);
        r->d_start = 1.0;
    } else if (p->n == 2 && !strcmp(key, "transient_time_width")) {
        r->d_start = frames ? 0.0 : -0.5; /* a gate stays centred */
        r->d_width = 1.0;
    } else if (p->n == 2 && !strcmp(key, "start_time")) {
        if (!frames) return dfail(d, p, "start_time is read with frames only (frame_num > 0); a gate is centred on "
                                        "transient_time_center");
        r->d_start = 1.0;
    } else {
        return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
    }
    return time_refusal(d, p, -1);
}

/* ---- one pointer ---- */

/* A pointer to sigma_s, sigma_a or density (or a channel of them) inside a medium given by visibility: those keys
 * are absent there (media_load.c refuses them together), so say what to differentiate instead. */
static int visibility_refusal(const diff_ctx *d, const json_ptr *p)
{
    const cJSON *v = d->root;
    for (int k = 0; k < p->n && v; k++) {
        const char *t = p->tok[k];
        if (cJSON_IsObject(v) && cJSON_GetObjectItemCaseSensitive(v, "visibility") &&
            (!strcmp(t, "sigma_s") || !strcmp(t, "sigma_a") || !strcmp(t, "density"))) {
            const cJSON *name = cJSON_GetObjectItemCaseSensitive(v, "name");
            char pre[300];
            ptr_prefix(p, k, pre, sizeof pre);
            return dfail(d, p, "medium '%s' is given by visibility, so it has no %s in the file: differentiate its "
                               "visibility (the extinction ln(20)/V or ln(50)/V) or its albedo (the split into "
                               "scattering and absorption), e.g. %s/visibility",
                         cJSON_IsString(name) ? name->valuestring : "", t, pre);
        }
        if (cJSON_IsArray(v)) {
            int i = ptr_index(t);
            v = i >= 0 && i < cJSON_GetArraySize(v) ? cJSON_GetArrayItem(v, i) : NULL;
        } else if (cJSON_IsObject(v)) {
            v = cJSON_GetObjectItemCaseSensitive(v, t);
        } else {
            v = NULL;
        }
    }
    return 0;
}

static int resolve_one(const diff_ctx *d, const json_ptr *p, diff_param *r)
{
    const cJSON *v = NULL;
    if (p->n == 1 && !p->tok[0][0]) return dfail(d, p, "names nothing: an empty key at the top level");
    if (visibility_refusal(d, p)) return -1;
    int rc = ptr_walk(d, p, &v);
    if (rc < 0) return -1;
    if (!rc && (cJSON_IsObject(v) || (cJSON_IsArray(v) && !is_vec3(v))))
        return dfail(d, p, "names %s, not a parameter: name one of its values (it can: %s)",
                     cJSON_IsObject(v) ? "an object" : "an array", DIFFERENTIABLE);
    if (!rc && !cJSON_IsNumber(v) && !cJSON_IsArray(v) && !cJSON_IsString(v)) /* a string: said by its reader */
        return dfail(d, p, "not a parameter dartspp differentiates: not a number (it can: %s)", DIFFERENTIABLE);
    *r = (diff_param){.index = -1, .light = -1, .first_surface = -1};
    snprintf(r->pointer, sizeof r->pointer, "%s", p->text);
    const char *top = p->tok[0];
    int i = p->n >= 2 ? ptr_index(p->tok[1]) : -1;
    const cJSON *obj = p->n >= 2 ? cJSON_GetObjectItemCaseSensitive(d->root, top) : NULL;
    if (!strcmp(top, "media") && p->n >= 3) return medium_param(d, p, cJSON_GetArrayItem(obj, i), 2, i, r);
    if (!strcmp(top, "bsdfs") && p->n >= 3) return bsdf_param(d, p, cJSON_GetArrayItem(obj, i), 2, i, r);
    if (!strcmp(top, "primitives") && p->n >= 3) return primitive_param(d, p, cJSON_GetArrayItem(obj, i), i, r);
    if (!strcmp(top, "camera")) return camera_param(d, p, obj, r);
    if (!strcmp(top, "integrator")) return integrator_param(d, p, r);
    return dfail(d, p, "not a parameter dartspp differentiates (it can: %s)", DIFFERENTIABLE);
}

int diff_params_resolve(json_ctx *c, const cJSON *root, scene *s, const prim_slot *prims, int prim_count,
                        const char *const *pointers, int count)
{
    diff_ctx d = {c, root, s, prims, prim_count};
    if (count > DIFF_PARAM_MAX)
        return dp_fail(c->err, "%s: --derivative: %d parameters asked for, at most %d in one render", c->file, count,
                       DIFF_PARAM_MAX);
    for (int k = 0; k < count; k++) {
        json_ptr p;
        if (ptr_parse(&d, pointers[k], &p)) return -1;
        /* the same parameter twice would render the same images twice: refused as the slip it is */
        for (int j = 0; j < k; j++)
            if (!strcmp(pointers[j], pointers[k])) return dfail(&d, &p, "given twice (derivatives %d and %d)", j + 1, k + 1);
        if (resolve_one(&d, &p, &s->diffs[k])) return -1;
        s->diff_count = k + 1;
    }
    return 0;
}
