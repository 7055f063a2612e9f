/* dartspp plan: the scene's integrator and renderer keys (after --set) resolved once into a typed render
 * plan. The keys are declared in the key table (src/scene/keys.c) and read and range-checked by the loader
 * (errors naming file and key); the plan keeps them as resolved (render_plan.keys), and every decision
 * derived from them — which DARTS samplers run, EDA per medium and its α, the radii of
 * each iteration, the surface slack, the bounce limits — is taken here and only here. The stages (photon
 * pass, gather, DARTS samplers, film) take what they need from the plan, never from scene.integrator. */
#ifndef DARTSPP_PLAN_H
#define DARTSPP_PLAN_H

#include "dartspp/darts.h"
#include "dartspp/derivative.h"
#include "dartspp/scene.h"
#include "dartspp/surface_site.h"

/* Which light paths count, in path segments including the light connection (docs/design.md §5.1). */
typedef struct {
    int min, max;
} bounce_limits;

static inline int bounces_count(const bounce_limits *b, int segments)
{
    return segments <= b->max && segments - 1 >= b->min;
}

/* Progressive radius of iteration i (0-based): r0 · (Π_{j=1..i} (j+α)/(j+1))^{1/dims}; dims 2 shrinks the
 * kernel area by (j+α)/(j+1) per step (Knaus & Zwicker 2011), dims 3 is the reference's cube root. */
typedef struct {
    double r0, alpha;
    int dims;
} radius_schedule;

double progressive_radius(double r0, double alpha, long iteration, int dims);
static inline double schedule_radius(const radius_schedule *r, long iteration)
{
    return progressive_radius(r->r0, r->alpha, iteration, r->dims);
}

/* The estimates of photon points' sensor pass (render_plan.sensor_parts). */
enum { SENSOR_SURFACE = 1, SENSOR_VOLUME = 2 };

typedef struct render_plan {
    /* One decided value per setting, named as its key where it is one; the stages read these, never
     * scene.integrator. */
    integrator_type type;
    char type_name[64];
    time_window window;              /* the time keys resolved; camera_unwarp is here only */
    bounce_limits bounces;
    light_selection_choice light_selection; /* how a light path (or an aimed camera path) picks its light */
    surface_shading shading;         /* two-sided shading, consistency checks, the photon-points glossy rule */
    /* photon points */
    double photon_count;             /* light paths per iteration, and the surface photon budget */
    double volume_photon_count;      /* volume photon budget per iteration */
    int gather_photon_count;         /* surface photons gathered per camera hit (k nearest) */
    radius_schedule r_vol;           /* volume_gather_radius, volume_alpha, radius_schedule; beams: dims 1 (their
                                      * kernel is 1-D, Marco et al. 2019's r0·γ_i) unless radius_schedule "3d" */
    radius_schedule r_surf;          /* gather_radius, alpha */
    /* delta_time_gate (window.delta): the temporal kernel's width w_i = w₀·γ_i^{1/d} with the volume's α and d
     * (plan_gate_width), w₀ = transient_time_width; r_vol then shrinks with the same d, the dimension of the
     * joint spatio-temporal kernel: 2 for beams (Liu et al. 2022's progressive photon map: r and w by √γ_i),
     * 3 for points (their 2-D kernel and time). Zero without a delta gate. */
    radius_schedule w_gate;
    int include_surfaces, low_order_scattering, surface_chains;
    int surface_direct;              /* surface_direct_connections, with surfaces included (emitter_connects_exactly) */
    surface_paths_choice surface_paths;
    int sensor_parts;                /* photon points' estimates the sensor pass gathers: SENSOR_SURFACE |
                                      * SENSOR_VOLUME from plan_resolve; the pilot of surface_paths "auto" renders
                                      * each alone (src/photon_points/chain_share.c) */
    int sensor_row_step;             /* the sensor pass samples the rows y % step == 0: 1 from plan_resolve; the
                                      * pilot of surface_paths "auto" takes every 4th */
    double chain_share;              /* the share of the light paths left once the volume budget is full that the
                                      * surface chains trace: 1 from plan_resolve, set by the pilot of
                                      * surface_paths "auto" (photon_points_choose_chain_share) */
    volume_photon_type_choice volume_photon_type; /* points, or short beams (src/photon_beams) */
    camera_leg_choice camera_leg;
    volume_gather_choice volume_gather;
    pass_weights_choice pass_weights;
    double glossy_regularization;
    /* the path tracer */
    int enable_rr;
    double time_angular_share;
    int ellipse_directions;          /* DARTS path tracer with elliptical connections (docs/darts.md §14.3) */
    double ellipse_direction_share;
    int ellipse_surface_directions;  /* and at surface vertices (docs/darts.md §14.4) */
    int uniform_time;                /* time_sampling "uniform" runs: gated, a medium, a light, one η */
    /* DARTS (both integrators) */
    darts_plan darts;
    /* the derivatives the scene asks for (scene.diffs; count 0: none) and their time kernels */
    deriv_plan deriv;
    /* renderer (the command line may override) */
    long spp;
    double timeout, checkpoint_interval; /* seconds */
} render_plan;

/* Resolves the plan of a loaded scene. 0, or -1 with err (out of memory; a plan this code cannot render). */
int plan_resolve(const scene *s, render_plan *p, dp_error *err);
void plan_free(render_plan *p);

/* Widening of the DARTS surface time tests in iteration i: η_ub × the surface gather radius (the camera leg
 * changes by up to that much across the gather disc); 0 without DARTS or surface photons. */
double plan_surface_slack(const render_plan *p, long iteration);

/* The weight of iteration i in the image (film_commit_pass): 1 for the path tracer and with pass_weights
 * "equal"; for photon points by default the kernel area of iteration i relative to iteration 0 — the
 * surface kernel's πR_i² when surfaces are gathered, else the volume kernel's πr_i² (beams: 2r_i) — times
 * w_i/w₀ under a delta gate (the temporal kernel is one more dimension of the kernel). An iteration's
 * estimate has variance about ∝ 1/area (fresh photons, a 2-D kernel), so this is the inverse-variance
 * mean; it stays consistent (every weight > 0, and Σ_i w_i diverges for α > 0: w_i ~ i^{α−1}). */
double plan_pass_weight(const render_plan *p, long iteration);
/* Under a delta gate (window.delta), the width w_i of iteration i's temporal box kernel, centred on the gate's
 * instant with weight 1/w_i (the film's gate of that pass: film_set_pass_gate); else the box gate's width. */
double plan_gate_width(const render_plan *p, long iteration);
/* The end of iteration i's window (the latest path time that counts): the box of a delta gate's iteration, the
 * gate's or the last frame's end, INFINITY when steady. */
double plan_window_end(const render_plan *p, long iteration);
/* Photon points: the microfacet α floor of light connections after a glossy camera bounce in iteration i,
 * glossy_regularization · R_i/R_0 (0 when the key is 0): it shrinks with the surface radius. */
double plan_glossy_regularization(const render_plan *p, long iteration);

/* The plan as one line of JSON (for --verbose, the run summary and the EXR header); returns 0, or -1 when n
 * is too small. */
int plan_json(const render_plan *p, const scene *s, char *out, size_t n);

#endif
