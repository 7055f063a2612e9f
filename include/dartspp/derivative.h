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
    vec3 dx[DIFF_PARAM_MAX];     /* ∂x/∂θ_k of the path's current vertex x (translations, DIFF_TRANSLATE; the
                                  * ray-space parametrization of docs/derivatives.md §6) */
} deriv_path;

/* An edge of the scene's triangles that is a silhouette as seen from a point light (a mesh's open edge, or one
 * between a triangle facing the light and one facing away): the shadow's boundary is the sheet of rays from
 * the light through it (src/derivative/deriv_geometry.c). */
typedef struct {
    vec3 a, b;   /* its ends */
    int surface; /* the surface it belongs to */
} deriv_edge;
typedef struct deriv_geometry {
    int light_count;
    deriv_edge **edge;  /* per light: its silhouette edges (NULL for a light that is not a point light) */
    int *edge_count;
    double **edge_cdf;  /* per light: the edges' CDF by length (the last 1) */
    double *edge_total; /* per light: their total length */
    double eps;         /* the offset across a boundary at which its two sides are evaluated */
    int boundary;       /* the boundary terms are on (the environment's DARTSPP_DERIV_NO_BOUNDARY turns them
                         * off: the broken variant of tests/derivative/test_deriv_geometry.c) */
} deriv_geometry;

/* The render's derivatives: the scene's parameters and the offset kernel of every light. */
typedef struct {
    const scene *s;
    int count;                /* K = s->diff_count */
    const diff_param *param;  /* s->diffs */
    time_kernel *kernel;      /* light_count entries */
    int camera_unwarp;        /* the camera segment adjacent to the sensor takes no time */
    deriv_geometry *geom;        /* translations: the light's silhouette edges (NULL without any) */
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

/* Adds `value` (already a derivative, a boundary term's estimate) to derivative film k where a contribution
 * at path time t lands (film_time_slot of t, frame, order). Counts a non-finite one. */
void deriv_splat_value(const deriv_plan *d, film_pixel *pix, int k, double t, vec3 value, int frame, int order);

/* ---- translations (src/derivative/deriv_geometry.c; docs/derivatives.md §6) ----
 * Ray space: the camera path's directions are held fixed, and each distance is a fraction of its segment
 * (from a vertex to the next surface along the ray), so a vertex slides when the camera or the surface ahead
 * moves; light connections are deterministic legs whose ends move. The visibility of moving geometry adds
 * boundary terms (path_tracer: path_geometry_deriv.c, boundary_shadow.c). */

/* Whether any parameter is a translation. */
int deriv_has_geometry(const deriv_plan *d);
/* The refusals (docs/derivatives.md §6.4) and the silhouette edges of every point light: 0, or -1 with err
 * naming the pointer. Called by deriv_plan_init. */
int deriv_geometry_init(deriv_plan *d, const scene *s, dp_error *err);
void deriv_geometry_free(deriv_plan *d);
/* ∂position/∂θ_k of surface `surface` (its translation's axis, or 0), of light `light`, and of the camera. */
vec3 deriv_surface_velocity(const diff_param *q, int surface);
vec3 deriv_light_velocity(const diff_param *q, int light);
vec3 deriv_camera_velocity(const diff_param *q);
/* The camera's vertex: dx = ∂(camera position)/∂θ. */
void deriv_camera_start(const deriv_plan *d, deriv_path *p);
/* ∂D/∂θ_k of the distance D from the vertex x (velocity p->dx) along the fixed direction dir to the plane of
 * unit normal n of surface `surface` (0 for a segment that hits nothing: D infinite): n·(v_surface − dx)/(n·dir). */
void deriv_hit_distance(const deriv_plan *d, const deriv_path *p, vec3 dir, vec3 n, int surface, double dD[DIFF_PARAM_MAX]);
/* The vertex at the fraction t/D of the segment (D = INFINITY: no surface ahead, t fixed): dx += (t/D)·dD·dir;
 * a medium vertex (surface 0) adds ∂ ln of D·σs·e^{−σt·t}, the fraction's Jacobian D included: dD/D − σt·t·dD/D;
 * the surface at t = D (surface 1) ∂ ln e^{−σt·D} = −σt·dD; both ∂τ += η·(t/D)·dD when `timed`. */
void deriv_slide(const deriv_plan *d, deriv_path *p, vec3 dir, double t, double D, const double dD[DIFF_PARAM_MAX],
                 vec3 sigma_t, double eta, int timed, int surface);

#endif
