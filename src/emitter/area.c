/* Area lights: an emissive quad, disk, sphere, cube or mesh (Tungsten's semantics, docs/emitters.md §2.4):
 * radiance L_e from the front side of each triangle (the side its winding normal (p1−p0)×(p2−p0) points
 * to), flux π·A·L_e. Points are sampled uniformly in area over the surface's triangles (a triangle by its
 * share of the area, then a uniform barycentric point), directions cosine-weighted, so every light path
 * carries the flux π·A·L_e. Disks and spheres are tessellated by the loader; the area is the
 * tessellation's. */
#include <stdlib.h>

#include "emitter_internal.h"

static vec3 vert(const scene *s, uint32_t v)
{
    return v3(s->verts[3 * (size_t)v], s->verts[3 * (size_t)v + 1], s->verts[3 * (size_t)v + 2]);
}

/* corners and the unnormalised winding normal of global triangle t */
static vec3 tri_corners(const scene *s, uint32_t t, vec3 *p0, vec3 *p1, vec3 *p2)
{
    *p0 = vert(s, s->tris[3 * (size_t)t]);
    *p1 = vert(s, s->tris[3 * (size_t)t + 1]);
    *p2 = vert(s, s->tris[3 * (size_t)t + 2]);
    return v3_cross(v3_sub(*p1, *p0), v3_sub(*p2, *p0));
}

/* the triangle distribution, the area A and the extent (the diagonal of the bounding box); *mid the middle of
 * the box */
static int area_distribution(const scene *s, emitter *e, vec3 *mid)
{
    free(e->tri_cdf);
    e->tri_cdf = malloc(sizeof(double) * (e->tri_count ? e->tri_count : 1));
    if (!e->tri_cdf) return -1;
    double acc = 0.0;
    vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
    for (uint32_t k = 0; k < e->tri_count; k++) {
        vec3 p0, p1, p2;
        acc += 0.5 * v3_len(tri_corners(s, e->first_tri + k, &p0, &p1, &p2));
        e->tri_cdf[k] = acc;
        vec3 c[3] = {p0, p1, p2};
        for (int i = 0; i < 3; i++) {
            lo = v3(dp_fmin(lo.x, c[i].x), dp_fmin(lo.y, c[i].y), dp_fmin(lo.z, c[i].z));
            hi = v3(dp_fmax(hi.x, c[i].x), dp_fmax(hi.y, c[i].y), dp_fmax(hi.z, c[i].z));
        }
    }
    for (uint32_t k = 0; k < e->tri_count; k++) e->tri_cdf[k] = acc > 0.0 ? e->tri_cdf[k] / acc : (k + 1.0) / e->tri_count;
    if (e->tri_count) e->tri_cdf[e->tri_count - 1] = 1.0;
    e->area = acc;
    e->extent = e->tri_count ? v3_len(v3_sub(hi, lo)) : 0.0;
    *mid = v3_scale(v3_add(lo, hi), 0.5);
    return 0;
}

static int area_prepare(const scene *s, emitter *e)
{
    vec3 mid;
    if (area_distribution(s, e, &mid)) return -1;
    e->flux = v3_scale(e->value, M_PI * e->area);
    e->flags = EMITTER_CONNECTABLE | EMITTER_HITTABLE | EMITTER_DIRECT_DRAWS;
    return 0;
}

/* no keys of its own: the surface must have an area, `power` is Φ = π·A·L_e, and the point to aim at and to
 * measure distances from is the middle of its bounding box */
static int area_parse(const scene *s, emitter *e, const emitter_keys *k)
{
    vec3 mid;
    if (area_distribution(s, e, &mid)) return k->fail(k, NULL, "out of memory");
    if (!(e->area > 0.0)) {
        emitter_free(e);
        return k->fail(k, "emission", "the emissive %s has no area", k->type);
    }
    if (k->is_power) e->value = v3_scale(e->value, 1.0 / (M_PI * e->area)); /* L_e = Φ/(π·A) */
    e->pos = mid;
    return 0;
}

/* the triangle of u's CDF interval, and u rescaled to [0,1) inside it */
static uint32_t pick_triangle(const emitter *e, double *u)
{
    uint32_t lo = 0, hi = e->tri_count - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (*u < e->tri_cdf[mid]) hi = mid;
        else lo = mid + 1;
    }
    double c0 = lo ? e->tri_cdf[lo - 1] : 0.0, w = e->tri_cdf[lo] - c0;
    *u = w > 0.0 ? dp_fmin(0x1.fffffffffffffp-1, dp_fmax(0.0, (*u - c0) / w)) : 0.0;
    return lo;
}

static void area_sample_point(const scene *s, const emitter *e, const double u[2], emitter_point *pt)
{
    double u0 = u[0];
    uint32_t k = pick_triangle(e, &u0);
    vec3 p0, p1, p2, n = tri_corners(s, e->first_tri + k, &p0, &p1, &p2);
    double su = sqrt(u0), b0 = 1.0 - su, b1 = u[1] * su; /* uniform barycentrics (Turk 1990) */
    pt->y = v3_add(v3_scale(p0, b0), v3_add(v3_scale(p1, b1), v3_scale(p2, 1.0 - b0 - b1)));
    pt->n = v3_norm(n);
    pt->pdf_a = 1.0 / e->area;
}

static void area_sample_ray(const scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    emitter_point pt;
    area_sample_point(s, e, u, &pt);
    r->p = pt.y;
    r->n = pt.n;
    r->d = sample_cosine_about(pt.n, u[2], u[3]);
    r->flux = v3_scale(e->value, M_PI * e->area); /* L_e·cosθ/((1/A)·(cosθ/π)) */
}

/* L_e·cosθ_y/(|x−y|²·p_A), front side only */
static int area_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    if (!emitter_leg(pt->y, x, out)) return 0;
    double cos_y = -v3_dot(out->wi, pt->n);
    if (!(cos_y > 0.0)) return 0;
    out->value = v3_scale(e->value, cos_y / pt->pdf_a);
    out->n = pt->n;
    return 1;
}

static int area_sample_direct(const scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out)
{
    emitter_point pt;
    area_sample_point(s, e, u, &pt);
    return area_connect_point(e, &pt, x, out);
}

/* L_e on the front side (d·ng < 0), 0 behind: one-sided, as Tungsten's area lights */
static vec3 area_hit_radiance(const emitter *e, vec3 d, vec3 ng)
{
    return v3_dot(d, ng) < 0.0 ? e->value : v3s(0.0);
}

const emitter_ops emitter_area_ops = {
    .name = "area",
    .primitives = NULL, /* the emitter of any shape with emission or power */
    .ray_uniforms = 4,
    .parse = area_parse,
    .prepare = area_prepare,
    .sample_ray = area_sample_ray,
    .sample_point = area_sample_point,
    .connect_point = area_connect_point,
    .sample_direct = area_sample_direct,
    .hit_radiance = area_hit_radiance,
};
