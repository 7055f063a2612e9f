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
    vec3 to = v3_sub(e->pos, x);
    double d2 = v3_dot(to, to);
    if (!(d2 > 0.0)) return 0;
    out->y = e->pos;
    out->dist = sqrt(d2);
    out->wi = v3_scale(to, 1.0 / out->dist);
    out->value = e->value;
    out->denom = d2;
    return 1;
}
