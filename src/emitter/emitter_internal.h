/* The emitter module's per-type functions (one file per emitter), dispatched by emitter.c. */
#ifndef DARTSPP_EMITTER_INTERNAL_H
#define DARTSPP_EMITTER_INTERNAL_H

#include "dartspp/emitter.h"
#include "dartspp/scene.h"

/* The geometry of a connection from x to the emitter point y: out->y, the unit direction out->wi from x
 * toward y, the length out->dist and out->denom = |x − y|² (the callers' 1/d², kept as one division);
 * 0 when x is y. */
static inline int emitter_leg(vec3 y, vec3 x, emitter_direct *out)
{
    vec3 to = v3_sub(y, x);
    double d2 = v3_dot(to, to);
    if (!(d2 > 0.0)) return 0;
    out->y = y;
    out->dist = sqrt(d2);
    out->wi = v3_scale(to, 1.0 / out->dist);
    out->denom = d2;
    return 1;
}

/* point.c */
void point_sample_ray(const emitter *e, const double u[4], emitter_ray *r);
int point_connect(const emitter *e, vec3 x, emitter_direct *out);
vec3 point_flux(const emitter *e);

/* spot.c */
double spot_falloff(const emitter *e, double cos_theta);
void spot_sample_ray(const emitter *e, const double u[4], emitter_ray *r);
int spot_connect(const emitter *e, vec3 x, emitter_direct *out);
vec3 spot_flux(const emitter *e);
/* the smoothstep ring's cosθ from a uniform (inverse of 2t³ − t⁴), exposed for the tests through spot_sample_ray */
double spot_ring_t(double u);

/* collimated.c */
void collimated_sample_point(const emitter *e, const double u[2], emitter_point *pt);
void collimated_sample_ray(const emitter *e, const double u[4], emitter_ray *r);
int collimated_sample_direct(const emitter *e, vec3 x, const double u[2], emitter_direct *out);
int collimated_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out);
int collimated_beam_crossing(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1);
vec3 collimated_flux(const emitter *e);

/* area.c */
int area_prepare(const scene *s, emitter *e);
void area_sample_point(const scene *s, const emitter *e, const double u[2], emitter_point *pt);
void area_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r);
int area_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out);

#endif
