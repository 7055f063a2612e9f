/* The boundary term of the shadow edges on the surfaces the camera sees (docs/derivatives.md §6.3): edge
 * sampling (Li et al. 2018; Yi et al. 2021 eq. 16–18 with Zhang et al. 2020's boundary sampling from the
 * light). A point e on a silhouette edge of the point light y's view, uniform in length over all of them,
 * casts the shadow's edge at c, where the ray y → e beyond e meets an opaque surface; the curve C of such
 * points moves over the surface, relative to the camera path's hit there, at the in-surface normal velocity
 * δ' = n_Σ·(v_Σ − v_c)/(n_Σ·m). The term is ∫_C (g₋ − g₊)·δ' dl with g the image's density on the surface
 * (the pinhole's importance times the direct light), each sample splatted where c projects. */
#include "path_tracer_internal.h"

/* The first opaque surface along o + t·d (null and forward surfaces crossed); 0 when none. */
static int first_opaque(const scene *s, vec3 o, vec3 d, hit_record *h)
{
    for (int guard = 0; guard < 64; guard++) {
        if (!scene_intersect(s, o, d, INFINITY, h)) return 0;
        const surface *sf = &s->surfaces[h->surface];
        if (!bsdf_is_passthrough(&s->bsdfs[sf->bsdf])) return 1;
        o = scene_offset_ray_origin(s, h->p, v3_dot(d, h->ng) < 0.0 ? v3_neg(h->ng) : h->ng);
    }
    return 0;
}

/* The pinhole's pixel of point c and its importance per unit area of the surface at c (normal n):
 * pixels per solid angle plane_dist²/(sx²·cos³θ) times the solid angle per area |n·d|/r². -1: not in view. */
static long camera_pixel(const camera *cam, vec3 c, vec3 n, double *imp, vec3 *d, double *r)
{
    vec3 to = v3_sub(c, cam->pos);
    *r = v3_len(to);
    *d = v3_scale(to, 1.0 / *r);
    double z = v3_dot(*d, cam->forward);
    if (!(z > 0.0)) return -1;
    double sx = 2.0 / cam->width;
    double x = v3_dot(*d, cam->right) * cam->plane_dist / z, y = v3_dot(*d, cam->up) * cam->plane_dist / z;
    double px = (x + 1.0) / sx, py = ((double)cam->height / cam->width - y) / sx;
    if (!(px >= 0.0 && px < cam->width && py >= 0.0 && py < cam->height)) return -1;
    *imp = cam->plane_dist * cam->plane_dist / (sx * sx * z * z * z) * fabs(v3_dot(n, *d)) / (*r * *r);
    return (long)py * cam->width + (long)px;
}

typedef struct {
    const pt_pass *pp;
    film *f;
    dp_rng rng;
    double per_sample; /* 1/(samples of the pass) */
} shadow_pass;

/* One edge sample of light i: edge j at fraction u, weighted 1/(its density). */
static void shadow_sample(shadow_pass *sp, int i, const deriv_edge *e, double u, double inv_pdf)
{
    const scene *s = sp->pp->s;
    const deriv_plan *D = sp->pp->deriv;
    const camera *cam = &s->cam;
    vec3 y = s->lights[i].pos, E = v3_sub(e->b, e->a), pe = v3_add(e->a, v3_scale(E, u));
    vec3 a = v3_sub(pe, y), om = v3_norm(a);
    hit_record hl, hc;
    if (!first_opaque(s, v3_add(pe, v3_scale(om, D->geom->eps)), om, &hl)) return;
    vec3 c = hl.p, nw = hl.ng, dc;
    double lam = v3_len(v3_sub(c, y)) / v3_len(a), imp = 0.0, rc;
    long px = camera_pixel(cam, c, nw, &imp, &dc, &rc);
    /* the camera must see c itself: its ray's first opaque hit is c's surface there */
    if (px < 0 || !first_opaque(s, cam->pos, dc, &hc) || hc.surface != hl.surface ||
        v3_len(v3_sub(hc.p, c)) > 1e3 * D->geom->eps)
        return;
    surface_site ss;
    if (!surface_site_init(&ss, s, &sp->pp->p->shading, &hc, dc)) return;
    vec3 trc;
    double tcam = 0.0;
    int region;
    vec3 cs = scene_offset_ray_origin(s, c, v3_dot(dc, nw) < 0.0 ? nw : v3_neg(nw));
    if (!scene_transmittance_region(s, cam->pos, cam->medium, cs, &trc, &tcam, &region)) return;
    vec3 axe = v3_cross(a, E), nS = v3_norm(axe);
    vec3 m = v3_sub(nS, v3_scale(nw, v3_dot(nS, nw)));
    double mlen = v3_len(m);
    if (!(mlen > 1e-9)) return;
    m = v3_scale(m, 1.0 / mlen);
    /* the direct light on either side of C, and the curve's length per unit u: c = y + λ·a(u) on the plane */
    double off = D->geom->eps * lam, tp = 0.0, tm = 0.0;
    vec3 gp = v3s(0.0), gm = v3s(0.0);
    int hp = pt_leg_value(s, i, v3_add(c, v3_scale(m, off)), v3s(0.0), region, NULL, dc, &ss, &gp, &tp);
    int hm = pt_leg_value(s, i, v3_sub(c, v3_scale(m, off)), v3s(0.0), region, NULL, dc, &ss, &gm, &tm);
    if (hp == hm && v3_is_zero(v3_sub(gp, gm))) return;
    double an = v3_dot(a, nw);
    if (fabs(an) < 1e-12) return;
    double dl = lam * v3_len(v3_sub(E, v3_scale(a, v3_dot(E, nw) / an)));
    vec3 g = v3_scale(v3_mul(trc, v3_sub(gm, gp)), imp * dl * inv_pdf * sp->per_sample);
    double t = path_time_offset(s, &s->lights[i], &sp->rng) + (hp ? tp : tm) + (s->integrator.window.camera_unwarp ? 0.0 : tcam);
    film_pixel pix = {.f = sp->f, .px = (size_t)px};
    for (int k = 0; k < D->count; k++) {
        const diff_param *q = &D->param[k];
        if (q->kind != DIFF_TRANSLATE) continue;
        vec3 vs = v3_add(v3_scale(deriv_light_velocity(q, i), 1.0 - lam), v3_scale(deriv_surface_velocity(q, e->surface), lam));
        vec3 vcam = deriv_camera_velocity(q);
        double dD = v3_dot(nw, v3_sub(deriv_surface_velocity(q, hc.surface), vcam)) / v3_dot(nw, dc);
        vec3 vc = v3_add(vcam, v3_scale(dc, dD)); /* c as the camera ray's hit: it slides with the camera */
        double dp = v3_dot(nS, v3_sub(vs, vc)) / v3_dot(nS, m);
        if (dp != 0.0) deriv_splat_value(D, &pix, k, t, v3_scale(g, dp), -1, 1);
    }
    sp->f->nonfinite += pix.nonfinite;
}

void pt_shadow_surfaces(const pt_pass *pp, film *f, uint64_t seed, long pass)
{
    const deriv_geometry *g = pp->geom ? pp->deriv->geom : NULL;
    const scene *s = pp->s;
    if (!pp->geom || !g->boundary || !bounces_count(&pp->p->bounces, 2) || s->light_count == 0) return;
    long n = (long)f->width * f->height;
    shadow_pass sp = {pp, f, rng_stream(seed, (uint64_t)pass, (uint64_t)n + (1ull << 40)), 1.0 / (double)n};
    for (long j = 0; j < n; j++) {
        int i = (int)dp_fmin(s->light_count - 1, rng_uniform(&sp.rng) * s->light_count);
        double u1 = rng_uniform(&sp.rng), u2 = rng_uniform(&sp.rng);
        if (g->edge_count[i] == 0) continue;
        int e = 0;
        while (e < g->edge_count[i] - 1 && u1 >= g->edge_cdf[i][e]) e++;
        const deriv_edge *ed = &g->edge[i][e];
        double len = v3_len(v3_sub(ed->b, ed->a));
        if (!(len > 0.0)) continue;
        /* density per unit u of edge e: (1/lights)·(len/total) */
        shadow_sample(&sp, i, ed, u2, s->light_count * g->edge_total[i] / len);
    }
}
