/* The path tracer's shared state (path_tracer.c: the camera path, surfaces, light connections; path_aim.c:
 * the techniques that aim camera paths at a light and its time bin — DARTS and uniform time). */
#ifndef DARTSPP_PATH_TRACER_INTERNAL_H
#define DARTSPP_PATH_TRACER_INTERNAL_H

#include "dartspp/darts.h"
#include "dartspp/path_tracer.h"
#include "dartspp/surface_site.h"

/* One pass: the scene, the plan and, when camera paths are aimed (plan: darts.active or uniform_time), a
 * DARTS guide per light (the light as the target of every sampler) and the light-selection CDF. */
typedef struct {
    const scene *s;
    const render_plan *p;
    const struct eda_set *eda;
    int aimed;
    darts_guide *guide;  /* light_count entries (aimed) */
    double *light_cdf;   /* light_count entries, the last 1 (aimed) */
    const deriv_plan *deriv; /* the derivatives (include/dartspp/derivative.h), or NULL without any */
    int geom;                /* deriv has translations (docs/derivatives.md §6) */
} pt_pass;

/* An aimed camera path (path_aim.c): the one light it serves, chosen with probability sel_pdf, its target
 * bin, and the record of the current segment. Every contribution of the path is divided by sel_pdf·bin.pdf
 * and counts only in bin.frame (frame mode). */
typedef struct {
    int on;
    int light;
    double sel_pdf;
    emitter_point pt;    /* the light's point the path aims at and connects to (area lights, diverging beams) */
    darts_guide guide;   /* the light's guide with pt.y as its target */
    const darts_guide *g;/* &guide */
    darts_bin bin;
    darts_bin reach;     /* the bin's end widened by η_lb·extent: no contribution through any other point of
                          * the light can arrive before the early exit's bound says */
    ellipse_record rec;  /* at the start of the current medium segment (valid: the residual can reach the bin) */
    int rec_ready;       /* rec was drawn at the vertex (medium or surface) the next segment starts from (its T
                          * shared with the vertex's direction, docs/darts.md §14.3–14.4): the segment takes it */
    double pre_r;        /* uniform time: the distance drawn at a medium vertex before its direction; < 0: none */
} pt_aim;

typedef struct {
    vec3 o, d;
    int medium;
    vec3 beta;     /* throughput */
    double time;   /* path time from the camera to o (unwarped: from the first scattering vertex); aimed: from
                    * the light's emission, drawn once for the path */
    int depth;     /* scattering vertices so far (segments so far) */
    int medium_events; /* medium vertices since the last surface (a medium's own max_bounces) */
    int connected; /* the segment that led to the current medium vertex had its light connection (a control
                    * vertex): the vertex makes none */
    int after_delta; /* the last vertex was the camera or a delta lobe: a hit on an area light counts its
                      * emission (elsewhere next-event estimation has counted it) */
    double offset;   /* aimed: the offset path_time_offset drew into time at the start (0 on plain paths) */
    int tr_done;     /* derivatives: the current segment's transmittance term is already in dv (uniform time's
                      * extended-space distance) */
    deriv_path dv;   /* derivatives: ∂ ln f and ∂τ of the path so far (used when pass->deriv) */
    double seg_D;    /* translations: the current segment's distance to the surface ahead (INFINITY: none) */
    double seg_dD[DIFF_PARAM_MAX]; /* and its ∂D/∂θ_k (deriv_hit_distance) */
} path_state;

typedef struct {
    const pt_pass *pass;
    film_pixel *pix;
    dp_rng *rng;
    pt_aim aim;
} pixel_ctx;

/* path_aim.c */
int pt_pass_aim_init(pt_pass *pp, dp_error *err);
void pt_pass_aim_free(pt_pass *pp);
/* Chooses the path's light, its emission time (into ps->time) and its bin; 0 when nothing in the window can
 * be reached (the path contributes nothing). */
int pt_aim_start(pixel_ctx *c, path_state *ps);
/* The start of a medium segment from ps->o along ps->d with the next surface at tmax: the record, the early
 * exit (returns 0: the path ends), the light connection by a control vertex (line-to-point with uniform
 * time), and the distance: *event and the distance t, ps->beta updated. */
int pt_aim_medium_segment(pixel_ctx *c, path_state *ps, double tmax, int *event, double *t);
/* A new direction at the medium vertex ps->o (aimed): EDA or time-angular with MIS, or the phase function;
 * ps->beta updated. */
void pt_aim_scatter_direction(pixel_ctx *c, path_state *ps);
/* The direction at the surface site ss of an aimed path (BSDF sampling; with ellipse_surface_directions the
 * mixture with the sampler toward the next control vertex, docs/darts.md §14.4, whose record the next segment
 * may then take as drawn): as surface_sample_bsdf for a camera path. 0 when the path ends. */
int pt_aim_surface_sample(pixel_ctx *c, const path_state *ps, const surface_site *ss, surface_sample *out);
/* The light connection of the aimed path from x (a medium vertex, or the surface site ss), as
 * connect_lights but to its one light, weighted 1/(sel_pdf·bin.pdf) and counted in its bin only. */
void pt_aim_connect(pixel_ctx *c, const path_state *ps, vec3 x, const phase_function *pf, const surface_site *ss);
/* path_tracer.c: the connection to light i by the sample ed from x (medium vertex, phase pf) or the site ss,
 * scaled by w and counted in `frame` (-1: any); its time is the path's plus the light leg's, plus an
 * emission time drawn for the connection when draw_emission (plain paths: aimed paths drew theirs at the
 * start). */
void pt_connect_sample(pixel_ctx *c, const path_state *ps, int i, const emitter_direct *ed, vec3 x,
                       const phase_function *pf, const surface_site *ss, int draw_emission, double w, int frame);
/* Parallel beams: the connection of a medium segment (ps->o along ps->d, next surface at tmax) to beam i by a
 * vertex sampled where the segment crosses the beam (docs/emitters.md §4.2), scaled by w, in `frame`. */
void pt_beam_crossing(pixel_ctx *c, const path_state *ps, int i, double tmax, int draw_emission, double w, int frame);
/* Derivatives (path_tracer.c): a segment of length len in the path's region up to its next vertex (its
 * transmittance unless ps->tr_done, and its time unless it is the unwarped camera segment). */
void pt_deriv_segment(const pixel_ctx *c, path_state *ps, double len);

/* ---- translations (path_geometry_deriv.c, boundary_shadow.c; docs/derivatives.md §6) ---- */
/* The segment from ps->o along ps->d up to the hit h (NULL: none): ps->seg_D and ps->seg_dD. */
void pt_geom_segment(const pixel_ctx *c, path_state *ps, const hit_record *h);
/* The vertex at distance t of that segment (a medium vertex, or the surface at t = seg_D): its sliding. */
void pt_geom_vertex(const pixel_ctx *c, path_state *ps, double t, int surface);
/* The light leg from vertex x (velocity dv->dx) to point light i: ∂ ln of its transmittance, the light's
 * value and the phase function (pf, arriving along w_in, in region med) or the BSDF·cos of ss, and ∂τ of
 * its time, by central differences along the ends' velocities. */
void pt_geom_leg(const pixel_ctx *c, deriv_path *dv, int i, vec3 x, int med, const phase_function *pf, vec3 w_in,
                 const surface_site *ss);
/* The light leg's value Tr·(I/r²)·f from x to point light i shifted by `shift` (f: pf along w_in, or the
 * site ss) and its time; 0 when the leg is blocked. */
int pt_leg_value(const scene *s, int i, vec3 x, vec3 shift, int med, const phase_function *pf, vec3 w_in,
                 const surface_site *ss, vec3 *value, double *time);
/* The boundary term of the shadows that the current medium segment (ps->o along ps->d up to tmax, throughput
 * ps->beta at its start) crosses: Yi et al. 2021 eq. 16 on the sheets of the point lights' silhouette edges. */
void pt_shadow_crossings(pixel_ctx *c, const path_state *ps, double tmax);
/* The boundary term of the shadow edges on the surfaces the camera sees (edge sampling from the light; run
 * after the pass's pixels, serially): adds to the derivative films' pass layer. */
void pt_shadow_surfaces(const pt_pass *pp, film *f, uint64_t seed, long pass);

/* Whether a time-0 camera segment (unwarped) is the current one: no DARTS sampler aims along it. */
static inline int pt_unwarped_camera_segment(const pixel_ctx *c, const path_state *ps)
{
    return c->pass->p->window.camera_unwarp && ps->depth == 0;
}

#endif
