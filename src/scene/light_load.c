/* Emitters of the scene file (docs/emitters.md §1): `point`, `spot`, `collimated`, `directional_point`
 * primitives, and any quad, disk, sphere, cube or mesh with `emission` or `power` (an area light). The
 * keys every emitter reads: `emission` or `power` (not both), `pulse_start`, `pulse_width`, `pulse_shape`,
 * `ext_medium`, `name`. Each type converts its `emission` into the emitter's value and its `power` (the total
 * flux Φ) as its own file in src/emitter says. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"

#define DEG (M_PI / 180.0)

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

/* the beam's axis (local +z: toward look_at) and the unit axes across it: e1 = up × axis, e2 = axis × e1 */
static int beam_frame(json_ctx *c, const char *where, const xform *T, emitter *L)
{
    if (!(v3_len(T->z) > 0.0)) return jfail(c, where, "transform", "gives no direction (set look_at away from position)");
    L->axis = v3_norm(T->z);
    vec3 up = v3_len(T->y) > 0.0 ? T->y : v3(0, 1, 0);
    vec3 e1 = v3_cross(up, L->axis);
    if (!(v3_len(e1) > 1e-12)) {
        vec3 a, b;
        v3_basis(L->axis, &a, &b);
        e1 = a;
    }
    L->e1 = v3_norm(e1);
    L->e2 = v3_norm(v3_cross(L->axis, L->e1));
    return 0;
}

static int parse_spot(json_ctx *c, const cJSON *v, const char *where, emitter *L, int is_power)
{
    double cone, delta;
    if (jget_number_range(c, v, where, "coneangle", 30.0, 0.0, 180.0, &cone) ||
        jget_number_range(c, v, where, "conedeltaangle", 5.0, 0.0, 180.0, &delta))
        return -1;
    if (!(cone > 0.0)) return jfail(c, where, "coneangle", "must be > 0 degrees");
    if (delta > cone) return jfail(c, where, "conedeltaangle", "must be <= coneangle (%g; got %g)", cone, delta);
    L->cos_end = cos(cone * DEG);
    L->cos_start = cos((cone - delta) * DEG);
    if (is_power) { /* Φ = 2π·I·[(1 − cos_start) + (cos_start − cos_end)/2] (pbrt-v4) */
        double k = 2.0 * M_PI * ((1.0 - L->cos_start) + 0.5 * (L->cos_start - L->cos_end));
        L->value = v3_scale(L->value, 1.0 / k);
    }
    return 0;
}

static int parse_collimated(json_ctx *c, const cJSON *v, const char *where, emitter *L, int is_power, int pencil)
{
    double div = 0.0;
    L->cos_div = 1.0;
    if (pencil) { /* directional_point: `power` is the flux, `emission` the flux/(4π) (docs/emitters.md §2.3) */
        if (!is_power) L->value = v3_scale(L->value, 4.0 * M_PI);
        return 0;
    }
    if (jget_number_range(c, v, where, "radius", 0.0, 0.0, 0.0, &L->radius) ||
        jget_number_range(c, v, where, "divergence", 0.0, 0.0, 89.0, &div))
        return -1;
    L->cos_div = div > 0.0 ? cos(div * DEG) : 1.0;
    if (is_power && L->radius > 0.0) L->value = v3_scale(L->value, 1.0 / (M_PI * L->radius * L->radius));
    return 0;
}

int light_parse(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, const xform *T)
{
    emitter L = {0};
    if (read_common(c, s, v, where, type, &L)) return -1;
    int is_power;
    char kind[64];
    snprintf(kind, sizeof kind, "a %s light", type);
    if (read_emission(c, v, where, kind, &L.value, &is_power)) return -1;
    L.pos = T->pos;
    int rc = 0;
    if (!strcmp(type, "point")) {
        L.type = EMITTER_POINT;
        if (is_power) L.value = v3_scale(L.value, DP_INV_4PI);
    } else if (!strcmp(type, "spot")) {
        L.type = EMITTER_SPOT;
        rc = beam_frame(c, where, T, &L) || parse_spot(c, v, where, &L, is_power);
    } else {
        L.type = EMITTER_COLLIMATED;
        rc = beam_frame(c, where, T, &L) || parse_collimated(c, v, where, &L, is_power, !strcmp(type, "directional_point"));
    }
    return rc ? -1 : push_light(c, s, where, &L);
}

int light_parse_area(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, surface *sf)
{
    emitter L = {0};
    if (read_common(c, s, v, where, type, &L)) return -1;
    L.type = EMITTER_AREA;
    int is_power;
    char kind[64];
    snprintf(kind, sizeof kind, "an emissive %s", type);
    if (read_emission(c, v, where, kind, &L.value, &is_power)) return -1;
    /* the emitter's medium is the one its light leaves into: the front side's */
    if (sf->overrides_media) L.medium = sf->ext_medium;
    L.surface = s->surface_count;
    L.first_tri = sf->first_tri;
    L.tri_count = sf->tri_count;
    if (emitter_prepare(s, &L)) return jfail(c, where, NULL, "out of memory");
    if (!(L.area > 0.0)) {
        emitter_free(&L);
        return jfail(c, where, "emission", "the emissive %s has no area", type);
    }
    if (is_power) L.value = v3_scale(L.value, 1.0 / (M_PI * L.area)); /* L_e = Φ/(π·A) */
    /* a point to aim at and to measure distances from: the middle of its bounding box */
    vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
    for (uint32_t k = 0; k < 3 * L.tri_count; k++) {
        const float *p = &s->verts[3 * (size_t)s->tris[3 * (size_t)L.first_tri + k]];
        lo = v3(dp_fmin(lo.x, p[0]), dp_fmin(lo.y, p[1]), dp_fmin(lo.z, p[2]));
        hi = v3(dp_fmax(hi.x, p[0]), dp_fmax(hi.y, p[1]), dp_fmax(hi.z, p[2]));
    }
    L.pos = v3_scale(v3_add(lo, hi), 0.5);
    sf->emitter = s->light_count;
    return push_light(c, s, where, &L);
}
