/* dartspp darts: the samplers of the DARTS photon pass (He et al. 2024), with the camera as the target of
 * every light path — time bins, ellipse records (residual time per vertex), elliptical control vertices
 * and DA (diffusion-approximation) distance sampling by resampled importance sampling.
 *
 * Units. Times are optical path lengths (DESIGN §4): a geometric length d in a medium of refractive index
 * η takes time η·d. Records convert residual times to geometric residual lengths with the η of the medium
 * the vertex is in (the straight line to the camera is assumed to stay in it; where it does not, the
 * samplers stay unbiased and only aim less well). Bounds that must never be wrong (early exit, the
 * reachable set of the distance sampler, the surface time test) use η_lb, the smallest η in the scene. */
#ifndef DARTSPP_DARTS_H
#define DARTSPP_DARTS_H

#include "dartspp/core.h"
#include "dartspp/scene.h"

/* ---- time window and target bins (reference §2) ---- */
typedef struct {
    int active;        /* any DARTS sampler on (and the scene is gated) */
    vec3 cam;          /* the target of every sampler: the pinhole */
    double beg, end;   /* the window: the gate, or the union of the frames */
    double width;      /* gate width, or frame width */
    int frames;        /* 0: gate mode (one bin); else the frame count */
    double eta_lb;     /* smallest refractive index in the scene: time >= eta_lb * distance */
} darts_guide;

typedef struct {
    double start, end; /* the target bin [start, end) */
    double pdf;        /* probability of this bin for this light (1 in gate mode) */
    int frame;         /* -1 in gate mode, else the target frame: the path's photons count only there */
} darts_bin;

/* Fills g from the scene; g->active is 0 when no DARTS sampler is on or the scene is not gated. */
void darts_guide_init(const scene *s, darts_guide *g);
/* Samples the target bin of a path from a light at x_light: uniform in time over the part of the window
 * reachable from the light, [max(beg, η_lb·|cam − x_light|), end). Returns 0 when nothing is reachable. */
int darts_sample_bin(const darts_guide *g, vec3 x_light, double u, darts_bin *b);

/* ---- ellipse record (reference §3) ----
 * At a vertex x with elapsed time τ: the admissible residual geometric length S ∈ [S_lo, S_hi] with
 * S_hi = (bin end − τ)/η and S_lo = max((bin start − τ)/η, C), C = |cam − x|, and one sampled residual T
 * shared by the samplers of the vertex. `valid` iff S_hi > C (up to a relative 1e-9). */
typedef enum { RESIDUAL_UNIFORM = 0, RESIDUAL_EXPONENTIAL = 1 } residual_sampling;

typedef struct {
    int valid;
    vec3 x, e;         /* vertex, unit direction to the camera */
    double C;          /* focal distance |cam − x| */
    double S_lo, S_hi; /* admissible residual interval (geometric length) */
    double T;          /* sampled residual */
    double inv_pdf_T;  /* 1/p(T) */
    double S_reach;    /* residual bound for reachability: (bin end − τ)/η_lb >= S_hi */
} ellipse_record;

/* sigma_t_avg is the rate of the truncated-exponential residual (paper eq. 21–22); u in [0, 1). */
void ellipse_record_init(ellipse_record *r, const darts_guide *g, const darts_bin *b, vec3 x, double tau,
                         double eta, residual_sampling mode, double sigma_t_avg, double u);
/* Whether any later photon of a path at this vertex can still land in its bin (time only grows):
 * τ + η_lb·C < bin end. */
int darts_can_reach(const darts_guide *g, const darts_bin *b, vec3 x, double tau);

/* ---- elliptical control vertex (reference §6; paper eq. 19–22, supplement eq. 6–12) ----
 * The point at distance t along unit d from r->x with t + |x + t·d − cam| = T, t = (T² − C²)/(2(T − C·cosθ)).
 * Returns 1 and (t, pdf of t) when 0 < t < tmax; 0 otherwise (no control vertex: case II is not sampled).
 * pdf(t) = p(T)·(T − C·cosθ)/(T − t). The photon weight is σs·e^{−σt·t}/pdf(t). */
int ellipse_control_vertex(const ellipse_record *r, vec3 d, double tmax, double *t, double *pdf_t);

/* Density in t of ellipse_control_vertex at distance t along d (residual density × dS/dt), 0 outside. */
double ellipse_control_vertex_pdf(const ellipse_record *r, vec3 d, double t, residual_sampling mode, double sigma);

/* The control vertex with multiple importance sampling (our addition, DESIGN-level decision): the
 * elliptical technique alone has weight ∝ (T − t)/(T − C·cosθ), which is unbounded when ω points almost at
 * the camera and T is close to C (the ellipsoid point rushes along the ray for a tiny change of T), giving
 * fireflies of infinite variance. One-sample MIS of the elliptical technique with a σ-exponential in t over
 * the same admissible interval [t(S_lo), t(S_hi)] — every sample still lands exactly in the bin — with the
 * balance heuristic bounds the weight by 2σs/σ̄ (σ = the residual/exponential rate, the mean σt).
 * Returns 1 with (t, mixture pdf) when 0 < t < tmax. */
int control_vertex_sample(const ellipse_record *r, vec3 d, double tmax, residual_sampling mode, double sigma,
                          double u_select, double u_t, double *t, double *pdf_t);

/* ---- DA distance sampling (reference §5 with DESIGN §5.4–5.5) ----
 * One segment from r->x along d, next surface at tmax (may be INFINITY), channel chosen by u_channel.
 * Surface event by free flight (probability e^{−σt_c·tmax}); a medium event is resampled from 8
 * truncated-exponential candidates (stratified table, random rotation) with target
 *   p̂(t) = e^{−σt·t}·Φ(s, ℓ(t)),  Φ = (4Ds)^{−3/2}·exp(−ℓ²/(4Ds) − σa·s),  D = 1/(3(σa + σs(1−g))),
 * with s = T − t where the sampled residual T can still reach the camera (T − t > ℓ), and s = S_reach − t
 * on the rest of the reachable set (t + ℓ < S_reach), so that p̂ > 0 wherever a photon can still land in the
 * bin (DESIGN §5.4). When no candidate is reachable, the first candidate is kept with its plain
 * exponential weight (nothing after it can reach the bin). Weights are per channel, finite and >= 0. */
typedef struct {
    double t;          /* distance */
    int medium_event;  /* 0: the surface at tmax (or escape) */
    vec3 weight;       /* throughput factor: σs·e^{−σt·t}/p (medium) or e^{−σt·tmax}/P_surf (surface) */
    int fallback;      /* medium event with no reachable candidate */
} da_sample;

/* defensive ∈ [0, 1): the share of uniform selection among the reachable candidates (0: plain RIS, as the
 * reference); it bounds the RIS factor by 1/defensive at the cost of a little importance. */
void da_sample_distance(const medium *m, const ellipse_record *r, vec3 d, double tmax, double defensive, dp_rng *rng,
                        da_sample *out);

#endif
