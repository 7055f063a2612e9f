/* Emitters of the scene file (docs/emitters.md §1): `point`, `spot`, `collimated`, `directional_point`
 * primitives, and any quad, disk, sphere, cube or mesh with `emission` or `power` (an area light). The
 * keys every emitter reads: `emission` or `power` (not both), `pulse_start`, `pulse_width`, `pulse_shape`,
 * `ext_medium`, `name`. The rest is the type's: its row of the table of emitter types (emitter_ops, one file
 * per type in src/emitter) parses its own keys and converts its `emission` into the emitter's value and its
 * `power` (the total flux Φ). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"

/* emission (or power, then *is_power) as an RGB triple >= 0; a texture is refused with its reason */
static int read_emission(json_ctx *c, const cJSON *v, const char *where, const char *kind, vec3 *out, int *is_power)
{
    const cJSON *e = jget_item(c, v, "emission"), *p = jget_item(c, v, "power");
    if (e && p) return jfail(c, where, "power", "give either emission or power, not both");
    if (!e && !p) return jfail(c, where, "emission", "%s needs emission or power", kind);
    const char *key = e ? "emission" : "power";
    const cJSON *val = e ? e : p;
    if (cJSON_IsString(val) || cJSON_IsObject(val))
        return jfail(c, where, key, "textured emission is not supported (give a number or [r, g, b])");
    if (jget_vec3(c, v, where, key, v3s(0), out)) return -1;
    if (out->x < 0 || out->y < 0 || out->z < 0) return jfail(c, where, key, "must be >= 0");
    *is_power = p != NULL;
    return 0;
}

static int read_pulse(json_ctx *c, const cJSON *v, const char *where, emitter_pulse *pl)
{
    if (jget_number_range(c, v, where, "pulse_start", 0.0, 0.0, 0.0, &pl->start) ||
        jget_number_range(c, v, where, "pulse_width", 0.0, 0.0, 0.0, &pl->width))
        return -1;
    const char *shape = "box";
    if (jget_string(c, v, where, "pulse_shape", &shape) < 0) return -1;
    if (!strcmp(shape, "box")) pl->shape = PULSE_BOX;
    else if (!strcmp(shape, "gaussian")) pl->shape = PULSE_GAUSSIAN;
    else return jfail(c, where, "pulse_shape", "unknown shape '%s' (supported: box, gaussian)", shape);
    return 0;
}

/* what every emitter reads */
static int read_common(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, emitter *L)
{
    const char *name = "";
    if (jget_string(c, v, where, "name", &name) < 0) return -1;
    snprintf(L->name, sizeof L->name, "%s", name[0] ? name : where);
    snprintf(L->type_name, sizeof L->type_name, "%s", type);
    L->surface = -1;
    if (read_pulse(c, v, where, &L->pulse)) return -1;
    L->medium = MEDIUM_VACUUM;
    const cJSON *em = jget_item(c, v, "ext_medium");
    return em ? medium_ref(c, s, em, where, "ext_medium", &L->medium) : 0;
}

static int push_light(json_ctx *c, scene *s, const char *where, emitter *L)
{
    if (emitter_prepare(s, L)) return jfail(c, where, NULL, "out of memory");
    emitter *grown = realloc(s->lights, ((size_t)s->light_count + 1) * sizeof(emitter));
    if (!grown) {
        emitter_free(L);
        return jfail(c, where, NULL, "out of memory");
    }
    s->lights = grown;
    s->lights[s->light_count++] = *L;
    return 0;
}

/* The reader a type's parse (emitter_ops) reads its own keys with: the loader's context, the primitive's
 * object and its path, so that its messages are the loader's. */
typedef struct {
    json_ctx *c;
    const cJSON *v;
    const char *where;
} key_ctx;

static int keys_number(const emitter_keys *k, const char *key, double def, double lo, double hi, double *out)
{
    const key_ctx *kc = k->ctx;
    return jget_number_range(kc->c, kc->v, kc->where, key, def, lo, hi, out);
}

static int keys_fail(const emitter_keys *k, const char *key, const char *fmt, ...)
{
    const key_ctx *kc = k->ctx;
    char reason[512]; /* jfail's own limit */
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    return jfail(kc->c, kc->where, key, "%s", reason);
}

/* The common keys, then the type's own (its parse). An emissive shape's emitter takes its medium and its
 * triangles from the surface sf; a primitive's its axes from the transform T. */
static int parse_emitter(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, const xform *T,
                         const surface *sf, emitter *L)
{
    if (read_common(c, s, v, where, type, L)) return -1;
    key_ctx kc = {c, v, where};
    emitter_keys k = {.ctx = &kc, .type = type, .number = keys_number, .fail = keys_fail};
    if (T) k.z = T->z, k.y = T->y;
    char what[64];
    snprintf(what, sizeof what, sf ? "an emissive %s" : "a %s light", type);
    if (read_emission(c, v, where, what, &L->value, &k.is_power)) return -1;
    if (sf) {
        if (sf->overrides_media) L->medium = sf->ext_medium; /* the medium its light leaves into: the front side's */
        L->surface = s->surface_count;
        L->first_tri = sf->first_tri;
        L->tri_count = sf->tri_count;
    }
    return L->ops->parse(s, L, &k);
}

int light_parse(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, const xform *T)
{
    emitter L = {.ops = emitter_ops_find(type), .pos = T->pos};
    return parse_emitter(c, s, v, where, type, T, NULL, &L) ? -1 : push_light(c, s, where, &L);
}

int light_parse_area(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, surface *sf)
{
    emitter L = {.ops = emitter_ops_shape()};
    if (parse_emitter(c, s, v, where, type, NULL, sf, &L)) return -1;
    sf->emitter = s->light_count;
    return push_light(c, s, where, &L);
}
