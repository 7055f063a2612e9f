/* Dispatch to the emitter of each type, light selection and set-up (include/dartspp/emitter.h). */
#include <stdlib.h>

#include "emitter_internal.h"

int emitter_connectable(const emitter *e)
{
    return !(e->type == EMITTER_COLLIMATED && !(e->radius > 0.0) && !(e->cos_div < 1.0));
}

int emitter_is_parallel_beam(const emitter *e)
{
    return e->type == EMITTER_COLLIMATED && e->radius > 0.0 && !(e->cos_div < 1.0);
}

void emitter_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    switch (e->type) {
    case EMITTER_POINT: point_sample_ray(e, u, r); break;
    case EMITTER_SPOT: spot_sample_ray(e, u, r); break;
    case EMITTER_COLLIMATED: collimated_sample_ray(e, u, r); break;
    case EMITTER_AREA: area_sample_ray(s, e, u, r); break;
    }
}

void emitter_sample_point(const scene *s, const emitter *e, const double u[2], emitter_point *pt)
{
    switch (e->type) {
    case EMITTER_POINT:
    case EMITTER_SPOT: *pt = (emitter_point){.y = e->pos, .pdf_a = 1.0}; break;
    case EMITTER_COLLIMATED: collimated_sample_point(e, u, pt); break;
    case EMITTER_AREA: area_sample_point(s, e, u, pt); break;
    }
}

int emitter_direct_draws(const emitter *e)
{
    return e->type == EMITTER_AREA || (e->type == EMITTER_COLLIMATED && e->radius > 0.0 && e->cos_div < 1.0);
}

int emitter_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    *out = (emitter_direct){.denom = 1.0};
    switch (e->type) {
    case EMITTER_POINT: return point_connect(e, x, out);
    case EMITTER_SPOT: return spot_connect(e, x, out);
    case EMITTER_COLLIMATED: return collimated_connect_point(e, pt, x, out);
    case EMITTER_AREA: return area_connect_point(e, pt, x, out);
    }
    return 0;
}

int emitter_sample_direct(const scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    *out = (emitter_direct){.denom = 1.0};
    if (e->type == EMITTER_COLLIMATED) return collimated_sample_direct(e, x, u, out);
    emitter_point pt;
    emitter_sample_point(s, e, u, &pt);
    return emitter_connect_point(e, &pt, x, out);
}

vec3 emitter_hit_radiance(const emitter *e, vec3 d, vec3 ng)
{
    return e->type == EMITTER_AREA && v3_dot(d, ng) < 0.0 ? e->value : v3s(0.0);
}

int emitter_beam_crossing(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1)
{
    return emitter_is_parallel_beam(e) && collimated_beam_crossing(e, o, d, tmax, t0, t1);
}

static double selection_weight(const emitter *e, int by_power)
{
    return by_power ? dp_fmax(0.0, v3_avg(e->flux)) : 1.0;
}

double emitter_selection_pdf(const scene *s, int i, int by_power)
{
    double sum = 0.0;
    for (int k = 0; k < s->light_count; k++) sum += selection_weight(&s->lights[k], by_power);
    return sum > 0.0 ? selection_weight(&s->lights[i], by_power) / sum : 1.0 / s->light_count;
}

int emitter_select(const scene *s, double u, int by_power, double *pdf)
{
    int n = s->light_count;
    if (n <= 0) return -1;
    if (n == 1) {
        *pdf = 1.0;
        return 0;
    }
    double sum = 0.0;
    for (int k = 0; k < n; k++) sum += selection_weight(&s->lights[k], by_power);
    if (!(sum > 0.0)) { /* every light black: uniform, as the paths carry nothing anyway */
        int i = (int)(u * n);
        *pdf = 1.0 / n;
        return i < n ? i : n - 1;
    }
    double target = u * sum, acc = 0.0;
    int i = 0;
    for (; i < n - 1; i++) {
        acc += selection_weight(&s->lights[i], by_power);
        if (target < acc) break;
    }
    while (i > 0 && !(selection_weight(&s->lights[i], by_power) > 0.0)) i--; /* rounding past the last lit one */
    *pdf = selection_weight(&s->lights[i], by_power) / sum;
    return i;
}

int emitter_prepare(const scene *s, emitter *e)
{
    e->extent = 0.0;
    switch (e->type) {
    case EMITTER_POINT: e->flux = point_flux(e); break;
    case EMITTER_SPOT: e->flux = spot_flux(e); break;
    case EMITTER_COLLIMATED:
        e->flux = collimated_flux(e);
        e->extent = 2.0 * e->radius;
        break;
    case EMITTER_AREA:
        if (area_prepare(s, e)) return -1;
        e->flux = v3_scale(e->value, M_PI * e->area);
        break;
    }
    return 0;
}

void emitter_free(emitter *e)
{
    free(e->tri_cdf);
    e->tri_cdf = NULL;
}
