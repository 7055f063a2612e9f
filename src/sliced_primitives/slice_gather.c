/* The sliced primitives along a camera segment: for each primitive the bounds admit, the roots of g′ = 0
 * (slice_geometry.c), and at each root the *long* primitive's contribution: the full path from the base vertex
 * to the camera point with every displaced segment's transmittance and visibility by the scene
 * (scene_transmittance_region, as next-event estimation), σs and the phase function at each displaced vertex,
 * divided by the density of the numerically sampled dimensions and |J| (Liu et al. 2022 eq. 25), times the gate
 * weight 1/p(τ_k). One row per primitive kind in `kinds` below: the only dispatch. */
#include "dartspp/sliced_primitives.h"

#include "slice_geometry.h"

typedef struct {
    const slice_gather *g;
    const scene *s;
    film_pixel *pix;
    const path_vertex *verts;
    int med;
    const medium *m;
    vec3 o, d, thr;
    double len, t_cam, eta_c;
    double span;   /* 1/p(τ_k): the gate's (or frames') span, against the film's 1/(width·frames); a delta gate:
                    * the film's box of this pass, w_i, against its 1/w_i (weight 1: the image is the density) */
    int b_cam, mis;
    dp_rng *rng;
} slice_ctx;

/* The camera side at the root s (x0 = o + s·d) for light arriving along w: σs·f_p(w → −d)·T_cam(s)·thr. */
static vec3 camera_side(const slice_ctx *c, double s, vec3 w)
{
    const medium *m = c->m;
    double f = phase_eval(&m->phase, w, v3_neg(c->d));
    return v3_scale(v3_mul(v3_mul(c->thr, v3_exp_neg(v3_scale(m->sigma_t, s))), m->sigma_s), f);
}

/* Adds val for a path of `segs` light segments beyond vertex v at time t, weighted by the film's gate (or frame)
 * box: a plane's W_τ (its gate is analytic, Liu et al. 2022 §4.2). */
static void splat_at(const slice_ctx *c, const path_vertex *v, int segs, double t, vec3 val)
{
    int light = v->bounce + segs;
    film_slot slot = film_time_slot(c->pix->f, t, -1, light + c->b_cam - 1);
    if (!slot.counts || v3_is_zero(val)) return;
    if (!film_slot_fits(&slot, val)) c->pix->nonfinite++;
    else film_slot_add(c->pix->f, c->pix->px, &slot, val);
}

/* Adds val (already over p·|J|) for a path of `segs` light segments beyond vertex v at time τ_k. */
static void splat(const slice_ctx *c, const path_vertex *v, int segs, double tau, vec3 val)
{
    splat_at(c, v, segs, tau, v3_scale(val, c->span));
}

/* Whether the path may have `segs` more light segments after v (bounce limits; the medium's own limit on
 * medium events since the last surface, the camera point counting as one). */
static int segments_count(const slice_ctx *c, const path_vertex *v, int segs)
{
    if (!bounces_count(&c->g->bounces, v->bounce + segs + c->b_cam)) return 0;
    return v->medium_events + segs <= c->m->max_bounces;
}

/* Where a displaced segment leaving v along w starts: off the surface (a surface vertex, an area light's
 * point) on w's side. */
static vec3 leave_point(const scene *s, const path_vertex *v, vec3 w)
{
    vec3 n = v->kind == PATH_VERTEX_SURFACE ? v->hit.ng : v->kind == PATH_VERTEX_EMITTER ? v->ep.n : v3s(0.0);
    if (v3_is_zero(n)) return v->pos;
    return scene_offset_ray_origin(s, v->pos, v3_dot(w, n) > 0.0 ? n : v3_neg(n));
}

/* ---- balls (Liu et al. 2022 §4.5) ---- */

/* What vertex v sends toward w1 per unit solid angle (the photon's throughput times its scattering
 * distribution), with where its segment to x0 starts and in which region; 0 when nothing. */
static int ball_source(const slice_ctx *c, const path_vertex *v, vec3 w1, vec3 x0, double t1, vec3 *out, vec3 *start,
                       int *region)
{
    const scene *s = c->s;
    *start = v->pos;
    *region = v->medium_out;
    if (v->kind == PATH_VERTEX_VOLUME) {
        *out = v3_scale(v->beta_in, phase_eval(&s->media[v->medium_in].phase, v->w_in, w1));
        *region = v->medium_in;
    } else if (v->kind == PATH_VERTEX_SURFACE) { /* the adjoint BSDF of the photon pass's sampling weight */
        surface_site ss;
        if (!surface_site_init(&ss, s, &c->g->shading, &v->hit, v->w_in)) return 0;
        vec3 f = surface_eval(&ss, w1, BSDF_LOBES_ALL & ~BSDF_LOBE_SPECULAR);
        *out = v3_scale(v3_mul(surface_photon_power(&ss, v->beta_in), f), fabs(v3_dot(ss.ng_hit, w1)));
        *start = surface_spawn(s, &ss, w1);
        *region = surface_medium_toward(&ss, v->medium_in, w1);
    } else { /* the emitter's intensity toward x0: value/denom carries 1/t1² */
        const emitter *L = &s->lights[v->light];
        emitter_direct ed;
        if (!emitter_connect_point(L, &v->ep, x0, &ed)) return 0;
        *out = v3_scale(v3_mul(v->beta_in, ed.value), t1 * t1 / ed.denom);
        *start = leave_point(s, v, w1);
        *region = L->medium;
    }
    return !v3_is_zero(*out);
}

static void eval_ball(slice_ctx *c, const slice_prim *p)
{
    const path_vertex *v = &c->verts[p->vertex];
    double tau = p->tau - v->time - c->t_cam, eta_p = medium_eta(c->s, v->medium_out);
    if (!(tau > 0.0) || !segments_count(c, v, 1)) return;
    slice_ray r = {c->o, c->d, c->len, c->eta_c};
    slice_root roots[2];
    int n = slice_ball_roots(v->pos, eta_p, tau, &r, roots);
    for (int i = 0; i < n; i++) {
        const slice_root *rt = &roots[i];
        vec3 x0 = v3_add(c->o, v3_scale(c->d, rt->s)), src, start, tr;
        int region, end;
        double time = 0.0;
        if (!ball_source(c, v, rt->w1, x0, rt->t[0], &src, &start, &region)) continue;
        if (!scene_transmittance_region(c->s, start, region, x0, &tr, &time, &end) || end != c->med) continue;
        double w = 1.0;
        if (c->mis && (v->flags & PATH_VERTEX_MEDIUM) && (v->flags & PATH_VERTEX_PREV_MEDIUM)) {
            const vec3 ws[3] = {v->prev_w_in, v->w_in, rt->w1};
            w = slice_mis_weight(c->s, 1, v->prev_seg, v3_len(v3_sub(v->pos, v->prev_pos)), rt->t[0], ws,
                                 v->prev_region, v->medium_in, c->d, eta_p, c->eta_c);
        }
        vec3 val = v3_mul(v3_mul(src, tr), camera_side(c, rt->s, rt->w1));
        splat(c, v, 1, p->tau, v3_scale(val, w / rt->jacobian));
    }
}

/* ---- parallelepipeds and parallelotopes (Liu et al. 2022 §4.3, §4.4): a chain of k displaced segments ---- */

/* The light carried from v along w[0..k−1] through the displaced vertices x[0..k−2] to x0, times σs and the
 * phase function at each displaced vertex (the fresh directions' density divides later); the regions of the
 * displaced vertices into mj. Zero when a segment is blocked or a displaced vertex is not in a scattering
 * medium, or x0 is not in the camera segment's medium. */
static vec3 chain(const slice_ctx *c, const path_vertex *v, const vec3 *w, const vec3 *x, int k, vec3 x0, int *mj)
{
    const scene *s = c->s;
    vec3 f = v->beta_out, start = leave_point(s, v, w[0]), tr;
    int region = v->medium_out, end;
    double time = 0.0;
    for (int j = 0; j < k; j++) {
        vec3 to = j + 1 < k ? x[j] : x0;
        if (!scene_transmittance_region(s, start, region, to, &tr, &time, &end)) return v3s(0.0);
        f = v3_mul(f, tr);
        if (j + 1 == k) return end == c->med ? f : v3s(0.0);
        if (end == MEDIUM_VACUUM || !medium_scatters(&s->media[end])) return v3s(0.0);
        const medium *m = &s->media[end];
        f = v3_scale(v3_mul(f, m->sigma_s), phase_eval(&m->phase, w[j], w[j + 1]));
        mj[j] = end;
        start = to;
        region = end;
    }
    return f;
}

static void eval_parallelepiped(slice_ctx *c, const slice_prim *p)
{
    const path_vertex *v = &c->verts[p->vertex];
    double tau = p->tau - v->time - c->t_cam, eta_p = medium_eta(c->s, v->medium_out);
    if (!(tau > 0.0) || !segments_count(c, v, 3)) return;
    const vec3 w[3] = {v->w_out, p->w[0], p->w[1]};
    slice_ray r = {c->o, c->d, c->len, c->eta_c};
    slice_root rt;
    if (!slice_parallelepiped_root(v->pos, w, eta_p, tau, &r, &rt)) return;
    vec3 x[2];
    x[0] = v3_add(v->pos, v3_scale(w[0], rt.t[0]));
    x[1] = v3_add(x[0], v3_scale(w[1], rt.t[1]));
    int mj[2];
    vec3 f = chain(c, v, w, x, 3, v3_add(c->o, v3_scale(c->d, rt.s)), mj);
    if (v3_is_zero(f)) return;
    double wm = c->mis ? slice_mis_weight(c->s, 0, rt.t[0], rt.t[1], rt.t[2], w, mj[0], mj[1], c->d, eta_p, c->eta_c)
                       : 1.0;
    vec3 val = v3_mul(f, camera_side(c, rt.s, w[2]));
    splat(c, v, 3, p->tau, v3_scale(val, wm / (rt.jacobian * p->pdf)));
}

/* The parallelotope's fourth numerical dimension is the camera point: y0 uniform on the segment (pdf 1/len). */
static void eval_parallelotope(slice_ctx *c, const slice_prim *p)
{
    const path_vertex *v = &c->verts[p->vertex];
    if (!segments_count(c, v, 4) || !(c->len > 0.0) || !isfinite(c->len)) return;
    double s0 = rng_uniform(c->rng) * c->len, eta_p = medium_eta(c->s, v->medium_out);
    double tau = p->tau - v->time - c->t_cam - c->eta_c * s0;
    if (!(tau > 0.0)) return;
    const vec3 w[4] = {v->w_out, p->w[0], p->w[1], p->w[2]};
    vec3 y0 = v3_add(c->o, v3_scale(c->d, s0));
    slice_root rt;
    if (!slice_parallelotope_root(v->pos, w, eta_p, tau, y0, &rt)) return;
    vec3 x[3];
    x[0] = v3_add(v->pos, v3_scale(w[0], rt.t[0]));
    x[1] = v3_add(x[0], v3_scale(w[1], rt.t[1]));
    x[2] = v3_add(x[1], v3_scale(w[2], rt.t[2]));
    int mj[3];
    vec3 f = chain(c, v, w, x, 4, y0, mj);
    if (v3_is_zero(f)) return;
    vec3 val = v3_mul(f, camera_side(c, s0, w[3]));
    splat(c, v, 4, p->tau, v3_scale(val, c->len / (rt.jacobian * p->pdf)));
}

/* ---- photon planes (Liu et al. 2022 §4.2) and 1-D-blurred planes (docs/sliced_primitives.md §7) ---- */

/* The plane at x2 = v: ω2 the photon's own sampled direction, ω1 fresh (density p->pdf); long in t2 and t1 (the
 * chain's transmittance and visibility evaluated), the box gate analytic: the root's path time picks the film's
 * slot and its box weight W_τ. */
static void eval_plane(slice_ctx *c, const slice_prim *p)
{
    const path_vertex *v = &c->verts[p->vertex];
    if (!segments_count(c, v, 2)) return;
    const vec3 w[2] = {v->w_out, p->w[0]};
    const double len[2] = {INFINITY, INFINITY};
    slice_ray r = {c->o, c->d, c->len, c->eta_c};
    slice_root rt;
    if (!slice_plane_root(v->pos, w, len, medium_eta(c->s, v->medium_out), &r, &rt)) return;
    vec3 x1 = v3_add(v->pos, v3_scale(w[0], rt.t[0]));
    int mj[1];
    vec3 f = chain(c, v, w, &x1, 2, v3_add(c->o, v3_scale(c->d, rt.s)), mj);
    if (v3_is_zero(f)) return;
    vec3 val = v3_mul(f, camera_side(c, rt.s, w[1]));
    splat_at(c, v, 2, v->time + c->t_cam + rt.time, v3_scale(val, 1.0 / (rt.jacobian * p->pdf)));
}

/* The 1-D-blurred plane: ξ_a = {t2, t1, B, τ_k} with the box kernel 1/(2r) on B; s uniform on the interval of
 * the segment whose roots lie in the blurred plane and the gate (slice_plane1d_interval), density 1/(s1 − s0).
 * The light path ends at the plane's point x1 + t1·ω1, the camera's at y1 + s·ψ, B·n apart. */
static void eval_plane1d(slice_ctx *c, const slice_prim *p)
{
    const path_vertex *v = &c->verts[p->vertex];
    if (!segments_count(c, v, 2) || !(c->g->r > 0.0)) return;
    const vec3 w[2] = {v->w_out, p->w[0]};
    const double len[2] = {INFINITY, INFINITY};
    double eta_p = medium_eta(c->s, v->medium_out), lo = c->pix->f->window.start - v->time - c->t_cam;
    slice_ray r = {c->o, c->d, c->len, c->eta_c};
    slice_interval iv;
    if (!slice_plane1d_interval(v->pos, w, len, c->g->r, eta_p, &r, lo, lo + c->span, &iv)) return;
    double s = iv.s0 + rng_uniform(c->rng) * (iv.s1 - iv.s0);
    double t2 = iv.t2[0] + iv.t2[1] * s, t1 = iv.t1[0] + iv.t1[1] * s;
    vec3 x1 = v3_add(v->pos, v3_scale(w[0], t2));
    int mj[1];
    vec3 f = chain(c, v, w, &x1, 2, v3_add(x1, v3_scale(w[1], t1)), mj);
    if (v3_is_zero(f)) return;
    vec3 val = v3_mul(f, camera_side(c, s, w[1]));
    double t = v->time + c->t_cam + eta_p * (t2 + t1) + c->eta_c * s;
    splat_at(c, v, 2, t, v3_scale(val, (iv.s1 - iv.s0) / (2.0 * c->g->r * iv.jacobian * p->pdf)));
}

/* The primitive kinds: the one table the estimate dispatches on (slice_kind's order). */
static const struct {
    const char *name;
    void (*eval)(slice_ctx *c, const slice_prim *p);
} kinds[SLICE_KIND_COUNT] = {
    [SLICE_BALL] = {"ball", eval_ball},
    [SLICE_PARALLELEPIPED] = {"parallelepiped", eval_parallelepiped},
    [SLICE_PARALLELOTOPE] = {"parallelotope", eval_parallelotope},
    [SLICE_PLANE] = {"plane", eval_plane},
    [SLICE_PLANE_1D] = {"plane_1d", eval_plane1d},
};

static void visit(void *ctx, const slice_prim *p) { kinds[p->kind].eval(ctx, p); }

void sliced_primitives_gather(const slice_gather *g, const scene *s, film_pixel *pix, int med, vec3 o, vec3 d,
                              double len, vec3 thr, double t_cam, int b_cam, dp_rng *rng)
{
    if (!g->map || med == MEDIUM_VACUUM || !medium_scatters(&s->media[med])) return;
    const time_window *tw = &pix->f->window;
    slice_ctx c = {.g = g, .s = s, .pix = pix, .verts = slice_map_vertices(g->map), .med = med, .m = &s->media[med],
                   .o = o, .d = d, .thr = thr, .len = len, .t_cam = t_cam,
                   .eta_c = g->camera_unwarp && b_cam == 1 ? 0.0 : medium_eta(s, med),
                   .span = tw->width * (tw->frame_count > 0 ? tw->frame_count : 1), .b_cam = b_cam,
                   .mis = slice_type_mis(g->type), .rng = rng};
    slice_map_query(g->map, o, d, len, t_cam, visit, &c);
}
