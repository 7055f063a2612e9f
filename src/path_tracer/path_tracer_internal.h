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

/* Whether a time-0 camera segment (unwarped) is the current one: no DARTS sampler aims along it. */
static inline int pt_unwarped_camera_segment(const pixel_ctx *c, const path_state *ps)
{
    return c->pass->p->window.camera_unwarp && ps->depth == 0;
}

#endif
