/* Translations in the path tracers (docs/derivatives.md §6): the interior term in ray space — the camera
 * path's vertices slide along their fixed rays (deriv_slide), each light leg's ends move — and the boundary
 * term of the shadows that the camera path's medium segments cross (Yi et al. 2021 eq. 16: the jump of
 * the integrand times the normal velocity of the discontinuity, here per ray in closed form). */
#include "path_tracer_internal.h"

void pt_geom_segment(const pixel_ctx *c, path_state *ps, const hit_record *h)
{
    if (!c->pass->geom) return;
    ps->seg_D = h ? h->t : INFINITY;
    deriv_hit_distance(c->pass->deriv, &ps->dv, ps->d, h ? h->ng : v3s(0.0), h ? h->surface : -1, ps->seg_dD);
}

void pt_geom_vertex(const pixel_ctx *c, path_state *ps, double t, int surface)
{
    if (!c->pass->geom) return;
    const scene *s = c->pass->s;
    vec3 sigma_t = ps->medium == MEDIUM_VACUUM ? v3s(0.0) : s->media[ps->medium].sigma_t;
    deriv_slide(c->pass->deriv, &ps->dv, ps->d, t, ps->seg_D, ps->seg_dD, sigma_t, medium_eta(s, ps->medium),
                !pt_unwarped_camera_segment(c, ps), surface);
}

int pt_leg_value(const scene *s, int i, vec3 x, vec3 shift, int med, const phase_function *pf, vec3 w_in,
                 const surface_site *ss, vec3 *value, double *time)
{
    const emitter *L = &s->lights[i];
    const double none[2] = {0.0, 0.0};
    emitter_direct ed;
    /* a point light at pos + shift seen from x is the light at pos seen from x − shift */
    if (!emitter_sample_direct(s, L, v3_sub(x, shift), none, &ed)) return 0;
    vec3 f = ss ? surface_eval_cos(ss, ed.wi, BSDF_LOBES_ALL) : v3s(phase_eval(pf, w_in, ed.wi));
    if (v3_max(f) <= 0.0) return 0;
    vec3 o = x, tr_near = v3s(1.0);
    int region = med;
    *time = 0.0;
    if (ss) {
        vec3 n = v3_dot(ed.wi, ss->ng_hit) > 0.0 ? ss->ng_hit : v3_neg(ss->ng_hit);
        region = surface_medium_toward(ss, med, ed.wi);
        /* x is the site moved with its surface (docs/derivatives.md §6.1): the leg starts where it crosses the
         * site's plane at rest, c along it (c > 0: x behind that plane), and the first c lies in the region
         * the leg leaves into, as it does in the moved scene; without this the static surface occludes the
         * leg of every site moving along its normal */
        double c = -v3_dot(n, v3_sub(x, ss->p)) / v3_dot(n, ed.wi);
        o = scene_offset_ray_origin(s, v3_add(x, v3_scale(ed.wi, c)), n);
        *time = medium_eta(s, region) * c;
        if (region != MEDIUM_VACUUM) tr_near = v3_exp_neg(v3_scale(s->media[region].sigma_t, c));
    }
    vec3 tr;
    double t_far = 0.0;
    if (!scene_transmittance(s, o, region, v3_add(ed.y, shift), &tr, &t_far)) return 0;
    tr = v3_mul(tr, tr_near);
    *time += t_far;
    *value = v3_scale(v3_mul(v3_mul(tr, ed.value), f), 1.0 / ed.denom);
    return 1;
}

static vec3 v3_log_pos(vec3 a, int *ok)
{
    *ok = a.x > 0.0 && a.y > 0.0 && a.z > 0.0;
    return *ok ? v3(log(a.x), log(a.y), log(a.z)) : v3s(0.0);
}

void pt_geom_leg(const pixel_ctx *c, deriv_path *dv, int i, vec3 x, int med, const phase_function *pf, vec3 w_in,
                 const surface_site *ss)
{
    if (!c->pass->geom) return;
    const deriv_plan *D = c->pass->deriv;
    const scene *s = c->pass->s;
    double h = D->geom->eps; /* central differences: the leg is smooth in its ends away from shadow edges */
    for (int k = 0; k < D->count; k++) {
        const diff_param *q = &D->param[k];
        if (q->kind != DIFF_TRANSLATE) continue;
        vec3 vx = dv->dx[k], vy = deriv_light_velocity(q, i);
        if (v3_is_zero(vx) && v3_is_zero(vy)) continue;
        vec3 vp, vm;
        double tp, tm;
        int okp, okm;
        /* both ends displaced by ±h along their velocities; the moved x keeps the site's frame (translations
         * turn no normal) */
        if (!pt_leg_value(s, i, v3_add(x, v3_scale(vx, h)), v3_scale(vy, h), med, pf, w_in, ss, &vp, &tp) ||
            !pt_leg_value(s, i, v3_sub(x, v3_scale(vx, h)), v3_scale(vy, -h), med, pf, w_in, ss, &vm, &tm))
            continue; /* a shadow edge within h: the boundary term's business */
        vec3 lp = v3_log_pos(vp, &okp), lm = v3_log_pos(vm, &okm);
        if (okp && okm) dv->dlog[k] = v3_add(dv->dlog[k], v3_scale(v3_sub(lp, lm), 0.5 / h));
        dv->dtof[k] += (tp - tm) * 0.5 / h;
    }
}

/* ---- the shadows' boundary on a medium segment ---- */

/* Where the ray o + t·d crosses the sheet of rays from y through edge e beyond it: t in (0, tmax), the
 * sheet's unit normal n and λ (the point is y + λ·(e(u) − y), λ > 1). 0 when it does not. */
static int sheet_crossing(vec3 y, const deriv_edge *e, vec3 o, vec3 d, double tmax, double *t, vec3 *n, double *lam)
{
    vec3 E = v3_sub(e->b, e->a), a = v3_sub(e->a, y), axe = v3_cross(a, E);
    double len = v3_len(axe);
    if (!(len > 0.0)) return 0;
    *n = v3_scale(axe, 1.0 / len);
    double nd = v3_dot(*n, d);
    if (fabs(nd) < 1e-12) return 0;
    *t = v3_dot(*n, v3_sub(y, o)) / nd;
    if (!(*t > 0.0 && *t < tmax)) return 0;
    vec3 w = v3_sub(v3_add(o, v3_scale(d, *t)), y);
    /* w = λ·a + λu·E: λ from w × E = λ·a × E, λu from w × a = λu·E × a */
    *lam = v3_dot(v3_cross(w, E), axe) / (len * len);
    double lu = -v3_dot(v3_cross(w, a), axe) / (len * len);
    return *lam > 1.0 && lu >= 0.0 && lu <= *lam;
}

typedef struct {
    int light, frame;
    double w, offset; /* the aimed path's weight and frame; offset: drawn (plain) */
    int draw;
} crossing_target;

static void crossing(pixel_ctx *c, const path_state *ps, const crossing_target *ct, const deriv_edge *e, double t,
                     vec3 n, double lam)
{
    const scene *s = c->pass->s;
    const deriv_plan *D = c->pass->deriv;
    const medium *m = &s->media[ps->medium];
    vec3 x = v3_add(ps->o, v3_scale(ps->d, t));
    double w[DIFF_PARAM_MAX], nd = fabs(v3_dot(n, ps->d));
    int any = 0;
    for (int k = 0; k < D->count; k++) {
        const diff_param *q = &D->param[k];
        w[k] = 0.0;
        if (q->kind != DIFF_TRANSLATE) continue;
        /* the sheet's point at fixed (u, λ) moves by (1 − λ)·v_y + λ·v_e; the path's vertex there by
         * dx + (t/D)·dD·d (its ray-space parametrization): their relative normal velocity */
        vec3 vs = v3_add(v3_scale(deriv_light_velocity(q, ct->light), 1.0 - lam), v3_scale(deriv_surface_velocity(q, e->surface), lam));
        vec3 vx = ps->dv.dx[k];
        if (ps->seg_D < INFINITY) vx = v3_add(vx, v3_scale(ps->d, t / ps->seg_D * ps->seg_dD[k]));
        w[k] = v3_dot(n, v3_sub(vs, vx));
        any |= w[k] != 0.0;
    }
    if (!any) return;
    double off = D->geom->eps * lam;
    vec3 gp = v3s(0.0), gm = v3s(0.0);
    double tp = 0.0, tm = 0.0;
    int hp = pt_leg_value(s, ct->light, v3_add(x, v3_scale(n, off)), v3s(0.0), ps->medium, &m->phase, ps->d, NULL, &gp, &tp);
    int hm = pt_leg_value(s, ct->light, v3_sub(x, v3_scale(n, off)), v3s(0.0), ps->medium, &m->phase, ps->d, NULL, &gm, &tm);
    if (hp == hm && v3_is_zero(v3_sub(gp, gm))) return;
    /* the integrand per unit distance: β·σs·e^{−σt·t}·(the leg) on either side of the sheet */
    vec3 seg = v3_scale(v3_mul(ps->beta, v3_mul(m->sigma_s, v3_exp_neg(v3_scale(m->sigma_t, t)))), ct->w / nd);
    vec3 jump = v3_mul(seg, v3_sub(gm, gp));
    double time = ps->time + (pt_unwarped_camera_segment(c, ps) ? 0.0 : m->eta * t) + (hp ? tp : tm) + ct->offset;
    for (int k = 0; k < D->count; k++)
        if (w[k] != 0.0) deriv_splat_value(D, c->pix, k, time, v3_scale(jump, w[k]), ct->frame, ps->depth + 1);
}

static void light_crossings(pixel_ctx *c, const path_state *ps, double tmax, crossing_target *ct)
{
    const deriv_geometry *g = c->pass->deriv->geom;
    vec3 y = c->pass->s->lights[ct->light].pos;
    int drawn = 0;
    for (int j = 0; j < g->edge_count[ct->light]; j++) {
        double t, lam;
        vec3 n;
        if (!sheet_crossing(y, &g->edge[ct->light][j], ps->o, ps->d, tmax, &t, &n, &lam)) continue;
        if (ct->draw && !drawn) { /* a plain path's emission time, drawn as its connections draw theirs */
            ct->offset = path_time_offset(c->pass->s, &c->pass->s->lights[ct->light], c->rng);
            drawn = 1;
        }
        crossing(c, ps, ct, &g->edge[ct->light][j], t, n, lam);
    }
}

void pt_shadow_crossings(pixel_ctx *c, const path_state *ps, double tmax)
{
    const scene *s = c->pass->s;
    if (!c->pass->geom || !c->pass->deriv->geom->boundary || ps->medium == MEDIUM_VACUUM) return;
    const medium *m = &s->media[ps->medium];
    if (!medium_scatters(m) || ps->medium_events + 1 > m->max_bounces || !bounces_count(&c->pass->p->bounces, ps->depth + 2))
        return;
    if (c->aim.on) {
        crossing_target ct = {c->aim.light, c->aim.bin.frame, 1.0 / (c->aim.sel_pdf * c->aim.bin.pdf), 0.0, 0};
        light_crossings(c, ps, tmax, &ct);
        return;
    }
    for (int i = 0; i < s->light_count; i++) {
        crossing_target ct = {i, -1, 1.0, 0.0, 1};
        light_crossings(c, ps, tmax, &ct);
    }
}
