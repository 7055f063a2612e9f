/* The isotropic point light: intensity I in every direction, flux 4π·I (docs/emitters.md §2.1). */
#include "emitter_internal.h"

vec3 point_flux(const emitter *e) { return v3_scale(e->value, 4.0 * M_PI); }

/* position delta, direction uniform on the sphere (p_ω = 1/(4π)): every path carries 4π·I */
void point_sample_ray(const emitter *e, const double u[4], emitter_ray *r)
{
    r->p = e->pos;
    r->n = v3s(0.0);
    r->d = sample_uniform_sphere(u[0], u[1]);
    r->flux = point_flux(e);
}

/* NEE: I/|x − p|², a delta in position (no pdf, no MIS) */
int point_connect(const emitter *e, vec3 x, emitter_direct *out)
{
    if (!emitter_leg(e->pos, x, out)) return 0;
    out->value = e->value;
    return 1;
}
