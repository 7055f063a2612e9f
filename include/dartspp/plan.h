/* dartspp plan: the scene's integrator and renderer keys (after --set) resolved once into a typed render
 * plan. The keys are declared in the key table (src/scene/keys.c) and read and range-checked by the loader
 * (errors naming file and key); the plan keeps them as resolved (render_plan.keys), and every decision
 * derived from them — which DARTS samplers run, EDA per medium and its α, the radii of
 * each iteration, the surface slack, the bounce limits — is taken here and only here. The stages (photon
 * pass, gather, DARTS samplers, film) take what they need from the plan, never from scene.integrator. */
#ifndef DARTSPP_PLAN_H
#define DARTSPP_PLAN_H

#include "dartspp/scene.h"
#include "dartspp/surface.h"

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

/* The DARTS photon pass as it will run. */
typedef enum { RESIDUAL_UNIFORM = 0, RESIDUAL_EXPONENTIAL = 1 } residual_sampling;

/* What camera paths see besides straight lines (camera_side.c). Camera paths continue through surfaces with
 * `cont` lobes (surface_photon_split): through them the camera leg is longer than the straight line from the
 * pinhole, which the DARTS time bounds and control vertices assume. The scan traces the camera's rays at the
 * corners and centres of every pixel (up to 512² pixels; a 1025² grid over larger images), through
 * null/forward surfaces, to the first surface that is not passthrough. A planar, flat-shaded surface whose
 * continued lobes only reflect (a mirror, smooth or rough metal, a plastic's coat) reflects the medium as
 * seen from the camera's mirror image, its focus: behind a delta reflection whose reflected ray then meets
 * no other continued surface, a camera leg is exactly η·|x − focus|; behind a glossy one, about that.
 * Anything else continued (curved, transmissive, smooth-shaded, a second continued bounce) has no focus. */
#define PLAN_MAX_MIRRORS 4

typedef struct {
    int seen;                  /* the scan met some continued surface */
    char first[64];            /* the name of one continued surface seen (messages) */
    int rays;                  /* rays traced */
    int mirror_count;          /* planar reflectors seen (the PLAN_MAX_MIRRORS seen most) */
    int mirror_surface[PLAN_MAX_MIRRORS];
    vec3 focus[PLAN_MAX_MIRRORS];              /* the camera's mirror image in each */
    double mirror_fraction[PLAN_MAX_MIRRORS];  /* share of the rays that continue through it first */
    double other_fraction;     /* share of the rays that continue through something no focus gives exactly */
} camera_side_scan;

/* Scans what the camera sees (above); cheap (one ray per pixel corner and centre, OpenMP). */
void plan_scan_camera_side(const scene *s, const surface_shading *sh, camera_side_scan *out);

/* darts_mirrors: "full" (ours, default): where the camera sees continued surfaces, control vertices also
 * aim at each planar mirror's focus, a defensive share of free-flight volume photons covers the rest, both
 * by one-sample MIS with the straight control vertex, and strict mode keeps every surface photon a camera
 * path could gather; "straight": the authors' behaviour, a straight camera leg assumed everywhere (biased
 * where the camera sees the medium through a mirror or glossy surface). */
typedef enum { DARTS_MIRRORS_FULL = 0, DARTS_MIRRORS_STRAIGHT = 1 } darts_mirror_mode;

typedef struct {
    int active;            /* some DARTS sampler runs: a switch on, the window gated, a medium present */
    int distance_sampling; /* enable_guiding: DA distance sampling */
    int control_vertices;  /* enable_elliptical, and one η over every region of the scene */
    int elliptical_asked;  /* enable_elliptical as written (control vertices may be off for η) */
    int control_vertex_mis;
    residual_sampling residual;
    int strict;            /* strict_time_width */
    int early_exit;
    double da_defensive;
    double eta_lb, eta_ub; /* smallest and largest η of the scene's regions: bounds of a straight camera leg */
    darts_mirror_mode mirrors;
    camera_side_scan side; /* scanned when DARTS runs control vertices or strict mode */
    /* Control-vertex techniques (full mode, control vertices on, side.seen): selection probabilities of the
     * straight focus, each mirror focus and the defensive free flight; cv_share[0] = 1 and the rest 0 when
     * off (the authors' single technique, bit-identical images). */
    int cv_multi;
    double cv_share[1 + PLAN_MAX_MIRRORS];
    double cv_defensive;
    double mirror_defensive; /* the smallest defensive share where a continued surface is seen (key) */
    int strict_surfaces;   /* strict's start test on surface photons: strict, and not (full mode and side.seen) */
    int unwarped;          /* camera_unwarp: the bounds drop the camera leg, control vertices are spheres around
                            * the vertex (sphere_control_vertex), DA distance sampling and EDA are off */
    int unwarped_mirror_off; /* control vertices off: unwarped, and the camera sees a continued surface */
} darts_plan;

/* EDA direction sampling in one medium. */
typedef struct {
    int on;
    double alpha;          /* EDA/phase selection α */
    int asked_unwarped;    /* asked for, but off: time is camera-unwarped */
} eda_plan;

typedef struct render_plan {
    integrator_settings keys;        /* the integrator keys as resolved (key table, scene.h); the decisions
                                      * below are derived from them */
    integrator_type type;
    char type_name[64];
    time_window window;
    bounce_limits bounces;
    surface_shading shading;         /* two-sided shading, consistency checks, the photon-points glossy rule */
    /* photon points */
    double light_paths;              /* photon_count: light paths per iteration */
    double volume_budget, surface_budget; /* photons per iteration */
    radius_schedule r_vol, r_surf;
    int volume_splat;               /* primary lines gathered photon by photon (volume_gather "splat") */
    darts_plan darts;
    int uniform_time;                /* path tracer, time_sampling "uniform", gated, a medium, one η */
    int medium_count;
    eda_plan *eda;                   /* medium_count entries */
    int eda_active;                  /* some medium uses EDA */
    /* renderer (the command line may override) */
    long spp;
    double timeout_seconds, checkpoint_seconds;
} render_plan;

/* Resolves the plan of a loaded scene. 0, or -1 with err (out of memory; a plan this code cannot render). */
int plan_resolve(const scene *s, render_plan *p, dp_error *err);
void plan_free(render_plan *p);

/* Widening of the DARTS surface time tests in iteration i: η_ub × the surface gather radius (the camera leg
 * changes by up to that much across the gather disc); 0 without DARTS or surface photons. */
double plan_surface_slack(const render_plan *p, long iteration);

/* The weight of iteration i in the image (film_commit_pass): 1 for the path tracer and with pass_weights
 * "equal"; for photon points by default the kernel area of iteration i relative to iteration 0 — the
 * surface kernel's πR_i² when surfaces are gathered, else the volume kernel's πr_i². An iteration's
 * estimate has variance about ∝ 1/area (fresh photons, a 2-D kernel), so this is the inverse-variance
 * mean; it stays consistent (every weight > 0, and Σ_i w_i diverges for α > 0: w_i ~ i^{α−1}). */
double plan_pass_weight(const render_plan *p, long iteration);
/* Photon points: the microfacet α floor of light connections after a glossy camera bounce in iteration i,
 * glossy_regularization · R_i/R_0 (0 when the key is 0): it shrinks with the surface radius. */
double plan_glossy_regularization(const render_plan *p, long iteration);

/* The plan as one line of JSON (for --verbose, the run summary and the EXR header); returns 0, or -1 when n
 * is too small. */
int plan_json(const render_plan *p, const scene *s, char *out, size_t n);

#endif
