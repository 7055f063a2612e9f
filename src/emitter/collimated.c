/* The collimated beam (the DARTS authors' `collimated`, with our `divergence`; docs/emitters.md §2.3): a disc
 * of `radius` around the position, across the axis toward look_at.
 *   - divergence 0: every point of the disc sends a parallel ray along the axis. `emission` is the
 *     irradiance E across the beam (flux E·πr²); radius 0 is a single ray whose `emission` is its flux.
 *     Inside the beam's half-cylinder the radiance is E·δ(ω − axis): a point there sees the emitter along
 *     −axis only, with no 1/d² and no cosine (docs/emitters.md §4.1).
 *   - divergence δ > 0: each point of the disc emits a constant radiance L = E/(π sin²δ) into the cone of
 *     half-angle δ about the axis (cosine-weighted directions), so the flux stays E·πr²; radius 0 is a point
 *     with intensity Φ·cosθ/(π sin²δ) inside the cone.
 * directional_point (Liu et al. 2022's pencil beam) is the radius-0, divergence-0 case; the loader turns its
 * units into these. */
#include <string.h>

#include "emitter_internal.h"

#define DEG (M_PI / 180.0)

static double disc_area(const emitter *e) { return M_PI * e->radius * e->radius; }
static double sin2_div(const emitter *e) { return dp_fmax(0.0, 1.0 - e->cos_div * e->cos_div); }

static vec3 collimated_flux(const emitter *e)
{
    return e->radius > 0.0 ? v3_scale(e->value, disc_area(e)) : e->value;
}

/* radius (default 0) and divergence (degrees, default 0, at most 89); directional_point reads neither, and its
 * `emission` is the flux/(4π) (docs/emitters.md §2.3); `power` is the flux Φ = E·πr² (radius 0: Φ itself) */
static int collimated_parse(const scene *s, emitter *e, const emitter_keys *k)
{
    (void)s;
    if (emitter_beam_frame(e, k)) return -1;
    double div = 0.0;
    e->cos_div = 1.0;
    if (!strcmp(k->type, "directional_point")) {
        if (!k->is_power) e->value = v3_scale(e->value, 4.0 * M_PI);
        return 0;
    }
    if (k->number(k, "radius", 0.0, 0.0, 0.0, &e->radius) || k->number(k, "divergence", 0.0, 0.0, 89.0, &div))
        return -1;
    e->cos_div = div > 0.0 ? cos(div * DEG) : 1.0;
    if (k->is_power && e->radius > 0.0) e->value = v3_scale(e->value, 1.0 / (M_PI * e->radius * e->radius));
    return 0;
}

/* a parallel beam of radius 0 reaches no point by next-event estimation; one of radius > 0 reaches those
 * inside it along −axis, and camera segments by their crossings (docs/emitters.md §4.1, §4.2) */
static int collimated_prepare(const scene *s, emitter *e)
{
    (void)s;
    e->flux = collimated_flux(e);
    e->extent = 2.0 * e->radius;
    int disc = e->radius > 0.0, diverging = e->cos_div < 1.0;
    e->flags = 0;
    if (disc || diverging) e->flags |= EMITTER_CONNECTABLE;
    if (disc && !diverging) e->flags |= EMITTER_PARALLEL_BEAM;
    if (disc && diverging) e->flags |= EMITTER_DIRECT_DRAWS | EMITTER_AIM_PER_CONNECTION;
    return 0;
}

/* uniform on the disc (concentric radius sqrt(u)), p_A = 1/(πr²); the centre for radius 0 */
static void collimated_sample_point(const scene *s, const emitter *e, const double u[2], emitter_point *pt)
{
    (void)s;
    pt->n = e->axis;
    if (!(e->radius > 0.0)) {
        pt->y = e->pos;
        pt->pdf_a = 1.0;
        return;
    }
    double rho = e->radius * sqrt(u[0]), phi = 2.0 * M_PI * u[1];
    pt->y = v3_add(e->pos, v3_add(v3_scale(e->e1, rho * cos(phi)), v3_scale(e->e2, rho * sin(phi))));
    pt->pdf_a = 1.0 / disc_area(e);
}

/* a direction in the cone of half-angle δ with density ∝ cosθ: sin²θ = sin²δ·u */
static vec3 cone_cosine_dir(const emitter *e, double u1, double u2)
{
    double s2 = sin2_div(e) * u1, c = sqrt(dp_fmax(0.0, 1.0 - s2)), s = sqrt(s2), phi = 2.0 * M_PI * u2;
    return v3_norm(v3_add(v3_scale(e->axis, c), v3_add(v3_scale(e->e1, s * cos(phi)), v3_scale(e->e2, s * sin(phi)))));
}

static void collimated_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    emitter_point pt;
    collimated_sample_point(s, e, u, &pt);
    r->p = pt.y;
    r->n = v3s(0.0); /* the disc is not a surface: rays start in the emitter's medium as they are */
    r->d = e->cos_div < 1.0 ? cone_cosine_dir(e, u[2], u[3]) : e->axis;
    r->flux = collimated_flux(e); /* position and direction sampled exactly as emitted */
}

/* x in the half-cylinder of the parallel beam: s = (x − pos)·axis > 0 and |(x − pos) − s·axis| ≤ r */
static int parallel_beam_direct(const emitter *e, vec3 x, emitter_direct *out)
{
    vec3 w = v3_sub(x, e->pos);
    double s = v3_dot(w, e->axis);
    if (!(s > 0.0)) return 0;
    vec3 perp = v3_sub(w, v3_scale(e->axis, s));
    if (v3_dot(perp, perp) > e->radius * e->radius) return 0;
    out->y = v3_add(e->pos, perp);
    out->wi = v3_neg(e->axis);
    out->dist = s;
    out->value = e->value; /* E: the directional delta absorbs the geometry term */
    out->denom = 1.0;
    return 1;
}

/* the connection from x to a fixed point y of a diverging beam: L·cosθ_y/(|x−y|²·p_A) with L = E/(π sin²δ)
 * (radius 0: I(θ)/|x−y|² with I = Φ·cosθ/(π sin²δ)), zero outside the cone */
static int collimated_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    if (!(e->cos_div < 1.0)) return 0; /* parallel rays: a fixed point cannot reach x */
    if (!emitter_leg(pt->y, x, out)) return 0;
    double cos_y = -v3_dot(out->wi, e->axis);
    if (!(cos_y >= e->cos_div)) return 0;
    out->value = v3_scale(e->value, cos_y / (M_PI * sin2_div(e) * pt->pdf_a));
    return 1;
}

/* A diverging beam of radius > 0 seen from x at the distance s in front of its disc: the points of the disc
 * that send light to x are those within s·tanδ of x's foot on the disc's plane (their ray to x lies in the
 * cone). The sample is drawn uniformly from the smaller of that footprint and the disc, and is zero outside
 * the other: either way the value L·cosθ_y/(d²·p_A) stays below about E/cos²δ, where a uniform point of the
 * whole disc gives up to E·r²/(s²·sin²δ), unbounded as s → 0 (an estimator of infinite variance next to the
 * disc). Written for this emitter; no library samples it. */
static int diverging_disc_direct(const scene *sc, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    double s = v3_dot(v3_sub(x, e->pos), e->axis);
    if (!(s > 0.0)) return 0;
    double tan_div = sqrt(sin2_div(e)) / e->cos_div, rc = s * tan_div;
    if (!(rc < e->radius)) {
        emitter_point pt;
        collimated_sample_point(sc, e, u, &pt);
        return collimated_connect_point(e, &pt, x, out);
    }
    vec3 foot = v3_sub(x, v3_scale(e->axis, s));
    double rho = rc * sqrt(u[0]), phi = 2.0 * M_PI * u[1];
    emitter_point pt = {.y = v3_add(foot, v3_add(v3_scale(e->e1, rho * cos(phi)), v3_scale(e->e2, rho * sin(phi)))),
                        .n = e->axis, .pdf_a = 1.0 / (M_PI * rc * rc)};
    vec3 off = v3_sub(pt.y, e->pos);
    if (v3_dot(off, off) > e->radius * e->radius) return 0;
    return collimated_connect_point(e, &pt, x, out);
}

static int collimated_sample_direct(const scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    if (!(e->cos_div < 1.0)) return e->radius > 0.0 ? parallel_beam_direct(e, x, out) : 0;
    if (e->radius > 0.0) return diverging_disc_direct(s, e, x, u, out);
    emitter_point pt;
    collimated_sample_point(s, e, u, &pt);
    return collimated_connect_point(e, &pt, x, out);
}

/* The ray o + t·d against the half-cylinder {s > 0, |perp| ≤ r}: the quadratic |w⊥ + t·d⊥|² = r² across
 * the axis, cut by s(t) = w·a + t·d·a > 0 and [0, tmax]. */
static int collimated_beam_crossing(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1)
{
    vec3 a = e->axis, w = v3_sub(o, e->pos);
    double wa = v3_dot(w, a), da = v3_dot(d, a);
    vec3 wp = v3_sub(w, v3_scale(a, wa)), dp = v3_sub(d, v3_scale(a, da));
    double A = v3_dot(dp, dp), B = v3_dot(wp, dp), C = v3_dot(wp, wp) - e->radius * e->radius;
    double lo = 0.0, hi = tmax;
    if (A > 1e-300) {
        double disc = B * B - A * C;
        if (!(disc > 0.0)) return 0;
        double q = sqrt(disc);
        lo = dp_fmax(lo, (-B - q) / A);
        hi = dp_fmin(hi, (-B + q) / A);
    } else if (C > 0.0) {
        return 0; /* parallel to the axis, outside the beam */
    }
    if (da > 0.0) lo = dp_fmax(lo, -wa / da);
    else if (da < 0.0) hi = dp_fmin(hi, -wa / da);
    else if (!(wa > 0.0)) return 0;
    if (!(hi > lo) || !isfinite(hi)) return 0;
    *t0 = lo;
    *t1 = hi;
    return 1;
}

const emitter_ops emitter_collimated_ops = {
    .name = "collimated",
    .primitives = (const char *const[]){"collimated", "directional_point", NULL},
    .ray_uniforms = 4,
    .parse = collimated_parse,
    .prepare = collimated_prepare,
    .sample_ray = collimated_sample_ray,
    .sample_point = collimated_sample_point,
    .connect_point = collimated_connect_point,
    .sample_direct = collimated_sample_direct,
    .beam_crossing = collimated_beam_crossing,
};
