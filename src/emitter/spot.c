/* The spot: a point light in a cone, pbrt-v4's `spotlight` design with the Tungsten format's keys
 * (docs/emitters.md §2.2): intensity I(ω) = I·smoothstep(t), t = (cosθ − cos_end)/(cos_start − cos_end),
 * θ the angle to the axis; full inside coneangle − conedeltaangle, black beyond coneangle. Light paths
 * sample the inner cone uniformly and the fall-off ring by the smoothstep itself, so every path carries
 * the same flux Φ = 2π·I·[(1 − cos_start) + (cos_start − cos_end)/2]. */
#include "emitter_internal.h"

#define DEG (M_PI / 180.0)

static double smoothstep01(double t)
{
    t = dp_fmin(1.0, dp_fmax(0.0, t));
    return t * t * (3.0 - 2.0 * t);
}

static double spot_falloff(const emitter *e, double cos_theta)
{
    if (cos_theta >= e->cos_start) return 1.0;
    if (cos_theta <= e->cos_end) return 0.0;
    return smoothstep01((cos_theta - e->cos_end) / (e->cos_start - e->cos_end));
}

/* the two sections' weights: the inner cone's solid angle over 2π, and the ring's ∫ smoothstep over 2π */
static void spot_sections(const emitter *e, double *p0, double *p1)
{
    *p0 = 1.0 - e->cos_start;
    *p1 = 0.5 * (e->cos_start - e->cos_end);
}

static vec3 spot_flux(const emitter *e)
{
    double p0, p1;
    spot_sections(e, &p0, &p1);
    return v3_scale(e->value, 2.0 * M_PI * (p0 + p1));
}

/* coneangle (default 30°) and conedeltaangle (default 5°, at most coneangle) */
static int spot_parse(const scene *s, emitter *e, const emitter_keys *k)
{
    (void)s;
    if (emitter_beam_frame(e, k)) return -1;
    double cone, delta;
    if (k->number(k, "coneangle", 30.0, 0.0, 180.0, &cone) || k->number(k, "conedeltaangle", 5.0, 0.0, 180.0, &delta))
        return -1;
    if (!(cone > 0.0)) return k->fail(k, "coneangle", "must be > 0 degrees");
    if (delta > cone) return k->fail(k, "conedeltaangle", "must be <= coneangle (%g; got %g)", cone, delta);
    e->cos_end = cos(cone * DEG);
    e->cos_start = cos((cone - delta) * DEG);
    if (k->is_power) { /* Φ = 2π·I·[(1 − cos_start) + (cos_start − cos_end)/2] (pbrt-v4) */
        double f = 2.0 * M_PI * ((1.0 - e->cos_start) + 0.5 * (e->cos_start - e->cos_end));
        e->value = v3_scale(e->value, 1.0 / f);
    }
    return 0;
}

static int spot_prepare(const scene *s, emitter *e)
{
    (void)s;
    e->flux = spot_flux(e);
    e->flags = EMITTER_CONNECTABLE | EMITTER_STARTS_AT_POS;
    return 0;
}

/* t in [0, 1] with density 2·smoothstep(t): its CDF 2t³ − t⁴ inverted by Newton steps kept inside a
 * bisection bracket (the CDF is increasing, so the bracket always holds the root) */
static double spot_ring_t(double u)
{
    double lo = 0.0, hi = 1.0, t = 0.5;
    for (int k = 0; k < 60; k++) {
        double f = t * t * t * (2.0 - t) - u;
        if (f > 0.0) hi = t;
        else lo = t;
        if (fabs(f) < 1e-15) break;
        double df = 2.0 * t * t * (3.0 - 2.0 * t);
        double next = df > 0.0 ? t - f / df : 0.5 * (lo + hi);
        t = (next > lo && next < hi) ? next : 0.5 * (lo + hi);
    }
    return t;
}

static vec3 spot_dir(const emitter *e, double cos_theta, double phi)
{
    double sin_theta = sqrt(dp_fmax(0.0, 1.0 - cos_theta * cos_theta));
    return v3_norm(v3_add(v3_scale(e->axis, cos_theta),
                          v3_add(v3_scale(e->e1, sin_theta * cos(phi)), v3_scale(e->e2, sin_theta * sin(phi)))));
}

/* u[0] picks the section (∝ p0, p1), u[1] the polar angle in it, u[2] the azimuth */
static void spot_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    (void)s;
    double p0, p1;
    spot_sections(e, &p0, &p1);
    double cos_theta;
    if (u[0] * (p0 + p1) < p0) cos_theta = 1.0 - u[1] * p0;                       /* uniform in the inner cone */
    else cos_theta = e->cos_end + spot_ring_t(u[1]) * (e->cos_start - e->cos_end); /* ∝ smoothstep in the ring */
    r->p = e->pos;
    r->n = v3s(0.0);
    r->d = spot_dir(e, cos_theta, 2.0 * M_PI * u[2]);
    r->flux = spot_flux(e); /* I(ω)/p(ω) = Φ in both sections (pbrt-v4's SpotLight::SampleLe) */
}

/* NEE: I(ω)/|x − p|², a delta in position */
static int spot_connect(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    (void)pt;
    if (!emitter_leg(e->pos, x, out)) return 0;
    double f = spot_falloff(e, -v3_dot(out->wi, e->axis));
    if (!(f > 0.0)) return 0;
    out->value = v3_scale(e->value, f);
    return 1;
}

static int spot_sample_direct(const scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    (void)s, (void)u;
    return spot_connect(e, NULL, x, out);
}

const emitter_ops emitter_spot_ops = {
    .name = "spot",
    .primitives = (const char *const[]){"spot", NULL},
    .ray_uniforms = 3,
    .parse = spot_parse,
    .prepare = spot_prepare,
    .sample_ray = spot_sample_ray,
    .sample_point = emitter_point_at_pos,
    .connect_point = spot_connect,
    .sample_direct = spot_sample_direct,
};
