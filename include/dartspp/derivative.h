/* dartspp derivatives (src/derivative; docs/derivatives.md): forward-mode derivatives of every image with
 * respect to the scene's parameters (scene.h, diff_param), after Yi et al. 2021.
 *
 * The sampled path is held fixed (detached sampling decisions): a contribution c = f(x̄)/p(x̄) has the
 * derivative (∂f/∂θ)/p = c·∂ ln f/∂θ, and ∂ ln f/∂θ is a sum over the path's segments and vertices (their
 * transmittance, σs, phase function, BSDF, emission), carried beside the throughput (deriv_path.dlog).
 * Time enters through the correlated importance S_e (Yi eq. 7): a path of time of flight τ counts in a box
 * [a, b) of width w with probability S(τ) = (F(b − τ) − F(a − τ))/w over the offset o its start draws
 * (path_time_offset: the light's pulse plus the sensor's response, of distribution F). The integrators keep
 * drawing o; a contribution that lands in the box then carries c·∂ ln S/∂θ, whose expectation over o is
 * c·∂S/∂θ / S·S = the derivative of the box's expected value (docs/derivatives.md §3). */
#ifndef DARTSPP_DERIVATIVE_H
#define DARTSPP_DERIVATIVE_H

#include "dartspp/film.h"
#include "dartspp/scene.h"

/* ---- the offset's distribution (src/derivative/time_kernel.c) ----
 * o = τ_e + r: the emission time τ_e of light L's pulse (emitter.h: delta, box or Gaussian of FWHM width,
 * peaked at start + width/2) plus the sensor's response offset r (sensor.h: Gaussian with an exponential
 * tail, or a tabulated density; off: r = 0). */
typedef struct {
    emitter_pulse pulse;
    const sensor_response *response;
} time_kernel;

/* Whether o has a density (no atom): a pulse of width > 0 or a response that is on. Without one the box's
 * S(τ) is a step and the derivatives of time (window, pulse start, speed of light, geometry) are boundary
 * terms the interior estimator cannot see: they are refused. */
int time_kernel_has_density(const time_kernel *k);
/* F(x) = P(o <= x), in [0, 1], nondecreasing. */
double time_kernel_cdf(const time_kernel *k, double x);
/* Its density f(x) = F'(x) (0 where o has none). */
double time_kernel_pdf(const time_kernel *k, double x);
/* ∂F(x)/∂(pulse width), the pulse's start held fixed (the Gaussian's peak at start + width/2 moves). */
double time_kernel_dcdf_dwidth(const time_kernel *k, double x);

/* ---- a path's derivative state (src/derivative/deriv_path.c) ---- */
typedef struct {
    vec3 dlog[DIFF_PARAM_MAX];   /* ∂ ln f/∂θ_k of the path so far, per channel */
    double dtof[DIFF_PARAM_MAX]; /* ∂τ/∂θ_k: its time of flight's derivative (speed of light, geometry) */
} deriv_path;

/* The render's derivatives: the scene's parameters and the offset kernel of every light. */
typedef struct {
    const scene *s;
    int count;                /* K = s->diff_count */
    const diff_param *param;  /* s->diffs */
    time_kernel *kernel;      /* light_count entries */
    int camera_unwarp;        /* the camera segment adjacent to the sensor takes no time */
} deriv_plan;

/* Built from the scene (count 0 when it asks for none). Returns 0, or -1 with err (out of memory). */
int deriv_plan_init(deriv_plan *d, const scene *s, dp_error *err);
void deriv_plan_free(deriv_plan *d);
static inline int deriv_on(const deriv_plan *d) { return d && d->count > 0; }

static inline void deriv_path_clear(deriv_path *p) { *p = (deriv_path){0}; }

/* A segment of length len in region `med` (a medium or MEDIUM_VACUUM) whose transmittance e^{−σt·len} is a
 * factor of f: ∂ ln f −= len·∂σt. */
void deriv_transmittance(const deriv_plan *d, deriv_path *p, int med, double len);
/* The same segment's time η·len, when it counts (not the unwarped camera segment): ∂τ += len·∂η. */
void deriv_time(const deriv_plan *d, deriv_path *p, int med, double len);
/* A medium vertex of `med`: its σs, a factor of f (every path through it). */
void deriv_medium_vertex(const deriv_plan *d, deriv_path *p, int med);
/* The phase function of `med` from propagation direction w_in to w_out, a factor of f. */
void deriv_phase(const deriv_plan *d, deriv_path *p, int med, vec3 w_in, vec3 w_out);
/* A surface vertex of BSDF b (its albedo, a factor of f for a BSDF linear in it). */
void deriv_surface_vertex(const deriv_plan *d, deriv_path *p, int b);

/* The film layers of a contribution: adds, for every derivative k, c·(dlog_k + ∂ ln S/∂θ_k) to the
 * derivative film k where the primal c lands (film_time_slot of t, frame, order), S of light `light`'s
 * offset kernel and τ = t − offset (offset: what path_time_offset drew for it). Counts a non-finite one. */
void deriv_splat(const deriv_plan *d, film_pixel *pix, const deriv_path *p, int light, double t, double offset,
                 vec3 c, int frame, int order);

#endif
