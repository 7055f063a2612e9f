/* The isotropic point light: intensity I in every direction, flux 4π·I (docs/emitters.md §2.1). */
#include "emitter_internal.h"

static vec3 point_flux(const emitter *e) { return v3_scale(e->value, 4.0 * M_PI); }

/* no keys of its own; `power` is Φ = 4π·I */
static int point_parse(const scene *s, emitter *e, const emitter_keys *k)
{
    (void)s;
    if (k->is_power) e->value = v3_scale(e->value, DP_INV_4PI);
    return 0;
}

static int point_prepare(const scene *s, emitter *e)
{
    (void)s;
    e->flux = point_flux(e);
    e->flags = EMITTER_CONNECTABLE | EMITTER_STARTS_AT_POS;
    return 0;
}

/* position delta, direction uniform on the sphere (p_ω = 1/(4π)): every path carries 4π·I */
static void point_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    (void)s;
    r->p = e->pos;
    r->n = v3s(0.0);
    r->d = sample_uniform_sphere(u[0], u[1]);
    r->flux = point_flux(e);
}

/* NEE: I/|x − p|², a delta in position (no pdf, no MIS) */
static int point_connect(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    (void)pt;
    if (!emitter_leg(e->pos, x, out)) return 0;
    out->value = e->value;
    return 1;
}

static int point_sample_direct(const scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    (void)s, (void)u;
    return point_connect(e, NULL, x, out);
}

const emitter_ops emitter_point_ops = {
    .name = "point",
    .primitives = (const char *const[]){"point", NULL},
    .ray_uniforms = 2,
    .parse = point_parse,
    .prepare = point_prepare,
    .sample_ray = point_sample_ray,
    .sample_point = emitter_point_at_pos,
    .connect_point = point_connect,
    .sample_direct = point_sample_direct,
};
