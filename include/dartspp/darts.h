/* dartspp darts: the samplers of the DARTS photon pass (He et al. 2024), with the camera as the target of
 * every light path — time bins, ellipse records (residual time per vertex), elliptical control vertices
 * and DA (diffusion-approximation) distance sampling by resampled importance sampling.
 *
 * Units. Times are optical path lengths (docs/time.md §1): a geometric length d in a medium of refractive index
 * η takes time η·d. Records convert residual times to geometric residual lengths with the η of the medium
 * the vertex is in (the straight line to the camera is assumed to stay in it; where it does not, DA
 * distance sampling and EDA stay unbiased and only aim less well). Bounds that must never be wrong bound
 * the time of the straight camera leg from x, which lies in [η_lb·|cam − x|, η_ub·|cam − x|] whatever
 * media it crosses (η_lb, η_ub: the smallest and largest η of the scene, vacuum's included): a photon is
 * dropped as too late (early exit, the reachable set of the distance sampler, the end test of the surface
 * time test) against the lower bound, as too early (the start test of strict time mode) against the upper
 * bound. So with straight camera legs strict mode never drops a photon that could be gathered in its bin;
 * where the camera sees a surface camera paths continue through (a mirror, glossy metal) the leg is longer
 * and has no upper bound, so there (darts_mirrors "full") the start test is off (darts_plan.strict_surfaces)
 * and control vertices also aim at the camera's mirror images, with a defensive free flight (cv_techniques). Elliptical control vertices need
 * the exact camera-leg time, which the vertex medium's single η gives only when every region of the scene
 * (each medium present, and vacuum if present) has the same η: otherwise they are off
 * (darts_guide.enable_elliptical), as a control vertex is then placed on the wrong equal-time surface and
 * in-gate places get no photon at all (free-flight volume photons are not stored while they are on). */
#ifndef DARTSPP_DARTS_H
#define DARTSPP_DARTS_H

#include <stdio.h>

#include "dartspp/core.h"
#include "dartspp/scene.h"
#include "dartspp/surface_site.h"

/* ---- the DARTS configuration (darts_plan.c, camera_side.c) ----
 * What the DARTS samplers will run in a render, decided once from the integrator keys and the scene by
 * darts_plan_resolve (called by plan_resolve, src/plan) and kept in render_plan.darts. Fields carry the names
 * of the keys they are decided from. */
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
#define DARTS_MAX_MIRRORS 4

typedef struct {
    int seen;                  /* the scan met some continued surface */
    char first[64];            /* the name of one continued surface seen (messages) */
    int rays;                  /* rays traced */
    int mirror_count;          /* planar reflectors seen (the DARTS_MAX_MIRRORS seen most) */
    int mirror_surface[DARTS_MAX_MIRRORS];
    vec3 focus[DARTS_MAX_MIRRORS];              /* the camera's mirror image in each */
    double mirror_fraction[DARTS_MAX_MIRRORS];  /* share of the rays that continue through it first */
    double other_fraction;     /* share of the rays that continue through something no focus gives exactly */
} camera_side_scan;

/* Scans what the camera sees (above); cheap (one ray per pixel corner and centre, OpenMP). */
void darts_scan_camera_side(const scene *s, const surface_shading *sh, camera_side_scan *out);


/* ---- camera-side control vertices (ours, issue 52; camera_cv.c, docs/darts.md §5.5) ----
 * The point of a record's equal-time ellipsoid in a direction φ drawn from the camera, uniform over the
 * pinhole's film widened by a margin (a fraction of each half-extent): a density ∝ 1/ρ² about the camera
 * (ρ = |y − cam|), as the camera's importance (bounded closer than ρ_thin, where a share (ρ/ρ_thin)² is kept). The
 * photon pass combines it with the vertex-side control vertex by the balance heuristic (camera_control_vertices). */
typedef struct {
    int on;                  /* a pinhole camera */
    vec3 right, up, forward;
    double plane_dist;       /* the image plane's distance: x ∈ [−half_x, half_x], y ∈ [−half_y, half_y] on it */
    double half_x, half_y;
    double share;            /* the share of the vertices that draw one */
    double thin;             /* ρ_thin: of the points closer to the camera than this, a share (ρ/ρ_thin)² is kept (0: all) */
} camera_film;

/* The share of the medium vertices that draw a camera-side control vertex (camera_film.share in a render):
 * enough for its density to outweigh the vertex side's near the camera, while the sensor pass's cost of its
 * photons, which lie closer to the camera and cover more pixels, stays small (bench/results/peer.md). */
#define CAMERA_CV_SHARE 0.25
/* ρ_thin in units of the distance r₀·plane_dist at which a disc of the first volume radius r₀ spans the film's
 * half-width: closer than ρ_thin a share (ρ/ρ_thin)² of the camera-side points is kept (docs/darts.md §5.5). */
#define CAMERA_CV_THIN 8.0

/* EDA direction sampling in one medium. */
typedef struct {
    int on;
    double alpha;          /* eda_alpha, or the medium's own: EDA/phase selection α */
    int asked_unwarped;    /* asked for, but off: time is camera-unwarped */
} eda_plan;

typedef struct {
    int active;            /* some DARTS sampler runs: a switch on, the window gated, a medium present */
    int enable_guiding;    /* DA distance sampling runs */
    int enable_elliptical; /* control vertices run: asked, and one η over every region of the scene (or
                            * unwarped photon points: spheres need none) */
    int enable_elliptical_asked; /* as written (control vertices may be off for η) */
    int control_vertex_mis;
    int camera_control_vertices; /* photon points with control vertices, camera-warped, a pinhole camera */
    residual_sampling ellipse_residual;
    int strict_time_width;
    int early_exit;
    double da_defensive;
    double eta_lb, eta_ub; /* smallest and largest η of the scene's regions: bounds of a straight camera leg */
    /* "full" (ours, default): where the camera sees continued surfaces, control vertices also aim at each
     * planar mirror's focus, a defensive share of free-flight volume photons covers the rest, both by
     * one-sample MIS with the straight control vertex, and strict mode keeps every surface photon a camera
     * path could gather; "straight": the authors' behaviour, a straight camera leg assumed everywhere (biased
     * where the camera sees the medium through a mirror or glossy surface). */
    darts_mirrors_choice darts_mirrors;

    camera_side_scan side; /* scanned when DARTS runs control vertices or strict mode */
    /* Control-vertex techniques (full mode, control vertices on, side.seen): selection probabilities of the
     * straight focus, each mirror focus and the defensive free flight; cv_share[0] = 1 and the rest 0 when
     * off (the authors' single technique, bit-identical images). */
    int cv_multi;
    double cv_share[1 + DARTS_MAX_MIRRORS];
    double cv_defensive;
    double mirror_defensive; /* the smallest defensive share where a continued surface is seen */
    int strict_surfaces;   /* strict's start test on surface photons: strict_time_width, and not (full mode and
                            * side.seen) */
    int unwarped_mirror_off; /* control vertices off: camera-unwarped, and the camera sees a continued surface */
    /* EDA: per medium (medium_count entries), whether any medium uses it, and where its tables come from */
    eda_plan *eda;
    int medium_count;
    int eda_active;
    char eda_table_dir[512];
    int eda_shape[3];
} darts_plan;

/* Decides d from the scene's integrator keys (type: the integrator; sh: its shading rules, for the camera-side
 * scan). The path tracer's uniform-time method (time_sampling "uniform") runs no DARTS sampler. 0, or -1 with
 * err (out of memory); darts_plan_free releases d->eda. */
int darts_plan_resolve(const scene *s, integrator_type type, const surface_shading *sh, darts_plan *d, dp_error *err);
void darts_plan_free(darts_plan *d);

/* ---- time window and target bins (docs/darts.md §2) ---- */
typedef struct {
    int active;        /* any DARTS sampler on (and the scene is gated) */
    vec3 cam;          /* the target of every sampler: the pinhole */
    double beg, end;   /* the window: the gate, or the union of the frames */
    double width;      /* gate width, or frame width */
    int frames;        /* 0: gate mode (one bin); else the frame count */
    double eta_lb;     /* smallest refractive index in the scene: time >= eta_lb * distance */
    double eta_ub;     /* largest: time <= eta_ub * distance along a straight segment */
    /* the samplers' switches as darts_plan decided them (the path tracer's guides change some, path_aim.c) */
    int enable_elliptical;  /* elliptical control vertices run */
    int enable_guiding;     /* DA distance sampling */
    int control_vertex_mis; /* control vertices by one-sample MIS with an exponential (control_vertex_sample) */
    camera_film film;       /* camera_control_vertices: medium vertices also place camera-side control vertices
                             * (film.on; set by the photon pass, which knows the camera) */
    residual_sampling ellipse_residual;
    int strict_surfaces;    /* strict time mode's start test on surface photons */
    int early_exit;         /* paths end once no photon can reach their bin */
    double da_defensive;
    /* control-vertex techniques behind continued surfaces (darts_plan.cv_multi; cv_techniques below) */
    int cv_multi;
    int focus_count;                        /* mirror foci */
    vec3 focus[DARTS_MAX_MIRRORS];
    double cv_share[1 + DARTS_MAX_MIRRORS];  /* straight focus, then each mirror focus */
    double cv_defensive;
    /* camera_unwarp: a path's time leaves out the camera segment adjacent to the sensor, so the camera leg
     * of every bound above is 0 (the equal-time set around a vertex is a sphere, not an ellipsoid), control
     * vertices are sphere_control_vertex and the plan turns DA distance sampling, EDA and the mirror foci off */
    int camera_unwarp;
} darts_guide;

typedef struct {
    double start, end; /* the target bin [start, end) */
    double pdf;        /* probability of this bin for this light (1 in gate mode) */
    int frame;         /* -1 in gate mode, else the target frame: the path's photons count only there */
} darts_bin;

/* Fills g from the DARTS plan, the time window and the target (the camera); g->active is 0 when no DARTS
 * sampler runs. */
void darts_guide_init(const darts_plan *d, const time_window *tw, vec3 cam, darts_guide *g);
/* The length of a straight camera leg from x that counts in a path's time: |cam − x|, or 0 when time is
 * unwarped. */
static inline double darts_leg_length(const darts_guide *g, vec3 x)
{
    return g->camera_unwarp ? 0.0 : v3_len(v3_sub(g->cam, x));
}

/* The least time a straight camera leg from x can take: η_lb times its length. */
static inline double darts_leg_lb(const darts_guide *g, vec3 x) { return g->eta_lb * darts_leg_length(g, x); }

/* Samples the target bin of a path emitted at time τ0 from a light at x_light: uniform in time over the part
 * of the window reachable from the light, [max(beg, τ0 + darts_leg_lb(x_light)), end) — the window as seen
 * from that path's emission time. Returns 0 when nothing is reachable. */
int darts_sample_bin(const darts_guide *g, vec3 x_light, double tau0, double u, darts_bin *b);

/* ---- ellipse record (docs/darts.md §3) ----
 * At a vertex x with elapsed time τ: the admissible residual geometric length S ∈ [S_lo, S_hi] with
 * S_hi = (bin end − τ)/η and S_lo = max((bin start − τ)/η, C), C = |cam − x|, and one sampled residual T
 * shared by the samplers of the vertex. `valid` iff S_hi > C (up to a relative 1e-9), C = 0 included (x at the
 * target: the ellipsoid is a sphere, docs/darts.md §3). */
/* residual_sampling (above): RESIDUAL_UNIFORM or RESIDUAL_EXPONENTIAL. */

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
 * τ + darts_leg_lb(x) < bin end (η_lb·C warped, 0 unwarped). */
int darts_can_reach(const darts_guide *g, const darts_bin *b, vec3 x, double tau);
/* Where the reachable set ends along a ray from x: the distance t with t + |x + t·d − cam| = S (in units of
 * η_lb time), an ellipsoid with foci x and the camera, for C = |x − cam| and cos θ = d·(cam − x)/C; 0 when
 * S <= C (nothing on the ray can reach). A vertex farther along the ray cannot reach the bin. */
static inline double darts_reach_along(double S, double C, double cos_theta)
{
    if (!(S > C)) return 0.0;
    return 0.5 * (S - C) * (S + C) / (S - C * cos_theta);
}

/* ---- elliptical control vertex (docs/darts.md §5; paper eq. 19–22, supplement eq. 6–12) ----
 * The point at distance t along unit d from r->x with t + |x + t·d − cam| = T, t = (T² − C²)/(2(T − C·cosθ)).
 * Returns 1 and (t, pdf of t) when 0 < t < tmax; 0 otherwise (no control vertex: case II is not sampled).
 * pdf(t) = p(T)·(T − C·cosθ)/(T − t). The photon weight is σs·e^{−σt·t}/pdf(t). */
int ellipse_control_vertex(const ellipse_record *r, vec3 d, double tmax, double *t, double *pdf_t);

/* Density of the record's residual S (uniform, or the truncated exponential of eq. 21–22); 0 outside
 * [S_lo, S_hi]. */
double ellipse_residual_pdf(const ellipse_record *r, double S, residual_sampling mode, double sigma);

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

/* Density in t of control_vertex_sample (mis = 1) or ellipse_control_vertex (mis = 0) at distance t along d:
 * the same mixture, evaluated (not sampled), so the two can be checked against each other. */
double control_vertex_pdf(const ellipse_record *r, vec3 d, double t, int mis, residual_sampling mode, double sigma);

/* ---- control vertex with camera-unwarped time (ours, issue 21) ----
 * Unwarped, a photon at distance t along the ray from a vertex of time τ in a medium of index η has the path
 * time τ + η·t when the camera sees it directly: the places of the ray inside the bin [b0, b1) are the
 * interval t ∈ [max(0, (b0 − τ)/η), min(tmax, (b1 − τ)/η)) (the ray's chord through a spherical shell
 * around the vertex). t is drawn in it ∝ e^{−σt} (σ = sigma, the mean σt; uniform where σ·length < 1e-6),
 * so every photon lands in the bin and the weight σs·e^{−σt·t}/p(t) stays bounded. u in [0, 1). Returns 1
 * with (t, pdf of t) when the interval is not empty. */
int sphere_control_vertex(double tau, double eta, const darts_bin *b, double tmax, double sigma, double u, double *t,
                          double *pdf_t);
/* Its density at t (0 outside the interval). */
double sphere_control_vertex_pdf(double tau, double eta, const darts_bin *b, double tmax, double sigma, double t);

/* ---- camera-side control vertices: the functions (camera_cv.c) ---- */
/* 1 for a pinhole camera (f->on), 0 otherwise (f->on = 0: no direction has density). */
int camera_film_init(camera_film *f, const camera *c, double margin);
/* A unit direction from the pinhole uniform over the film, with its solid-angle density. */
vec3 camera_film_direction(const camera_film *f, double u1, double u2, double *pdf);
double camera_film_direction_pdf(const camera_film *f, vec3 w);
/* The record's control vertex y in a film direction (u1, u2) from the camera, at its residual T, kept when u3 is
 * below f->share (times (ρ/ρ_thin)² closer than ρ_thin); pdf_v: the density of y in volume measure, the kept share
 * included. 0 when the record is not valid, C = 0, or the point is not kept. */
int camera_control_vertex(const ellipse_record *r, const camera_film *f, double u1, double u2, double u3, vec3 *y,
                          double *pdf_v);
/* Its density in volume measure at any y (0 where φ is off the film or T(y) outside [S_lo, S_hi]). */
double camera_control_vertex_pdf(const ellipse_record *r, const camera_film *f, vec3 y, residual_sampling mode,
                                 double sigma);

/* ---- control vertices behind mirrors (ours; camera_side_scan above, issue 18) ----
 * One-sample MIS over the techniques of one medium segment: the control vertex of the record with focus
 * the camera (rec[0]), of each record with focus a mirror image of the camera (rec[1..n-1]: there a camera
 * path through that mirror has exactly the bin's time), and a defensive free flight, a σ-exponential in t
 * over [0, min(tmax, t_reach)) with t_reach where the straight line to the camera leaves the reachable set
 * (rec[0].S_reach): no later photon can count. Technique k is drawn with probability share[k] (defensive:
 * `defensive`), renormalised over the techniques that can sample at this vertex (a record valid, the
 * reachable set not empty); the photon's pdf is Σ_k share_k·p_k(t) (balance heuristic), positive wherever
 * the defensive technique is: every place a photon can count by any camera path gets photons. */
typedef struct {
    int n;                                     /* records: 1 + mirror foci */
    ellipse_record rec[1 + DARTS_MAX_MIRRORS];
    double share[1 + DARTS_MAX_MIRRORS];
    double defensive;
} cv_techniques;

/* u: three uniforms (technique, then the two of the technique). Returns 1 with (t, pdf) when a photon lands
 * at 0 < t < tmax. mis: control_vertex_mis for the record techniques. */
int cv_techniques_sample(const cv_techniques *ct, vec3 d, double tmax, int mis, residual_sampling mode, double sigma,
                         const double u[3], double *t, double *pdf);
/* The pdf of cv_techniques_sample at t (0 <= t < tmax). */
double cv_techniques_pdf(const cv_techniques *ct, vec3 d, double tmax, int mis, residual_sampling mode, double sigma,
                         double t);

/* ---- DA distance sampling (docs/darts.md §6) ----
 * One segment from r->x along d, next surface at tmax (may be INFINITY), channel chosen by u_channel.
 * Surface event by free flight (probability e^{−σt_c·tmax}); a medium event is resampled from 8 (4 on thin
 * segments, docs/darts.md §6.5) truncated-exponential candidates (stratified table, random rotation) with
 * target
 *   p̂(t) = e^{−σt·t}·Φ(s, ℓ(t)),  Φ = (4Ds)^{−3/2}·exp(−ℓ²/(4Ds) − σa·s),  D = 1/(3(σa + σs(1−g))),
 * with s = T − t where the sampled residual T can still reach the camera (T − t > ℓ), and s = S_reach − t
 * on the rest of the reachable set (t + ℓ < S_reach), so that p̂ > 0 wherever a photon can still land in the
 * bin (docs/darts.md §6.3). When no candidate is reachable, the first candidate is kept with its plain
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

/* ---- EDA direction sampling (docs/darts.md §8; paper §5.1, eq. 17–20) ----
 * A table of CDFs over the angle θ between the new direction and the camera direction e, one per cell
 * (C/S, S): how much diffusion-approximated radiance the medium inside the vertex's equal-time ellipsoid
 * sends back along each direction,
 *   I(C, S, θ) = ∫_0^{t_M(θ)} e^{−σt·t}·Φ(ℓ(t), S − t) dt,  t_M = (S² − C²)/(2(S − C cosθ)),
 *   ℓ(t)² = C² − 2Ct·cosθ + t²,  Φ(ℓ, s) = (4πDs)^{−3/2}·exp(−ℓ²/(4Ds) − σa·s),  D = 1/(3(σa + σs(1 − g))).
 * Reading convention (the authors' C++): row i ↔ C/S ∈ [r_lo + iΔ, r_lo + (i+1)Δ), Δ = (r_hi − r_lo)/n_ratio;
 * column j ↔ S ∈ [j, j+1)·s_max/n_s; bin k ↔ cosθ ∈ [−1 + 2k/n_cos, −1 + 2(k+1)/n_cos), bin n_cos − 1 towards
 * the camera; flat index (i·n_s + j)·n_cos + k; each run of n_cos floats a non-decreasing CDF ending at 1.
 * Written by hand: no library tabulates this integral. */
typedef struct eda_table {
    int n_ratio, n_s, n_cos;      /* shape, e.g. 128 × 128 × 256 */
    double sigma_s, sigma_a, g;   /* the medium the table is for */
    double s_max;                 /* S range [0, s_max) (geometric length) */
    double r_lo, r_hi;            /* C/S range [r_lo, r_hi) */
    float *cdf;
} eda_table;

#define EDA_DEFAULT_R_LO 0.2
#define EDA_DEFAULT_R_HI 0.999

/* Computes the table (OpenMP over rows; deterministic: the same arguments give the same bits whatever the
 * thread count). progress(ctx, rows_done, rows) may be NULL. */
int eda_table_build(eda_table *t, double sigma_s, double sigma_a, double g, int n_ratio, int n_s, int n_cos,
                    double s_max, double r_lo, double r_hi, void (*progress)(void *, int, int), void *ctx,
                    dp_error *err);
void eda_table_free(eda_table *t);
/* Our file format (little-endian): "DPEDATAB", u32 version 1, u32 n_ratio, n_s, n_cos, f64 sigma_s,
 * sigma_a, g, s_max, r_lo, r_hi, u64 FNV-1a hash of the float payload, then the floats. Written atomically. */
int eda_table_save(const eda_table *t, const char *path, dp_error *err);
/* Reads our format, checking size, hash and every CDF; a truncated or corrupted file is an error naming it. */
int eda_table_load(eda_table *t, const char *path, dp_error *err);
/* Reads the authors' headerless 128 × 128 × 256 float32 table (exactly 16,777,216 bytes), whose parameters
 * come from the scene (max_T, dT_start, dT_end); checks every CDF. */
int eda_table_load_raw(eda_table *t, const char *path, double s_max, double r_lo, double r_hi, dp_error *err);
/* The cached table for these parameters: DIR/eda-<σs>-<σa>-<g>-<s_max>-<r_lo>-<r_hi>-<shape>.bin, built
 * and stored there first when missing (announced on `messages` with its build time); a folder that cannot
 * store it is a warning there, and the table is used from memory. messages NULL: silent. */
int eda_table_cached(eda_table *t, const char *dir, double sigma_s, double sigma_a, double g, int n_ratio, int n_s,
                     int n_cos, double s_max, double r_lo, double r_hi, FILE *messages, dp_error *err);

/* The CDF of the cell of a record, or NULL where the table does not cover it (record invalid, C/T outside
 * [r_lo, r_hi)); the S index is clamped to the last column. */
const float *eda_cell(const eda_table *t, const ellipse_record *r);
/* Solid-angle density of the EDA branch in the cell: bin probability × n_cos/(4π). */
double eda_pdf(const eda_table *t, const float *cell, vec3 e, vec3 w);
/* A new direction at a medium vertex: with probability γ = (C/T)/(C/T + α) from the table (bin by inverse
 * CDF, cosθ uniform in the bin, azimuth uniform about e), otherwise from the phase function; *weight =
 * f/(γ·p_E + (1 − γ)·p_phase), the one-sample balance heuristic (f = p_phase: phase sampling is exact).
 * Where eda_cell gives NULL: phase sampling, weight 1. u: four uniforms in [0, 1). */
vec3 eda_sample_direction(const eda_table *t, double alpha, const phase_function *ph, vec3 w_in,
                          const ellipse_record *r, const double u[4], double *weight);
/* The density of eda_sample_direction at the unit direction w: γ·p_E + (1 − γ)·ρ, or ρ where eda_cell gives NULL. */
double eda_direction_pdf(const eda_table *t, double alpha, const phase_function *ph, vec3 w_in, const ellipse_record *r,
                         vec3 w);

/* The EDA tables of one render, prepared once before the first iteration: table[i] for medium i, or NULL
 * where EDA is off (phase not `ida` and integrator eda false, or the scene is not gated). */
typedef struct eda_set {
    eda_table *tables;       /* medium_count entries; unused ones zeroed */
    const eda_table **table; /* medium_count pointers */
    double *alpha;           /* α per medium */
    int count, active;       /* active: at least one medium uses EDA */
} eda_set;

/* Loads (table_path), or takes from the cache folder d->eda_table_dir (building it there when
 * missing, said on `messages` unless NULL), the table of every medium the plan gives EDA. A plan without EDA
 * touches no file. */
int eda_set_prepare(const scene *s, const darts_plan *d, const time_window *w, eda_set *set, FILE *messages,
                    dp_error *err);
void eda_set_free(eda_set *set);
/* Bytes the tables of eda_set_prepare will hold (the memory guard's estimate), without touching a file. */
size_t eda_set_bytes(const scene *s, const darts_plan *d);

/* ---- time-angular direction sampling (uniform-time PT; Jarabo et al. 2014 §5.3, supplement §B.4 eq. 21–22) ----
 * docs/darts.md §13. At a vertex x with the target (light) at x_L, l = x_L − x, and a distance r drawn
 * before the direction: ω such that the time t = r + d₂, d₂ = |x + rω − x_L|, is uniform on
 * [t_min, t_max] = [r + ||l| − r|, 2r + |l|]: cosθ = (|l|² + 2tr − t²)/(2|l|r) about l (eq. 21), φ uniform.
 * Solid-angle density p_Ω(ω) = |l|r/(2π(t_max − t_min)d₂) = max(r, |l|)/(4π d₂) (|dt/dcosθ| = |l|r/d₂;
 * Jarabo's eq. 16, r/(4π d₂), integrates to r/|l| < 1 when |l| > r). */

/* Returns 1 with the unit direction *w and its density *pdf; 0 when r, |l| or t_max − t_min is below 1e-9
 * of r + |l| (and on the null set r = |l|, u1 = 0, where d₂ = 0). u1 picks the time, u2 the azimuth. */
int time_angular_sample(vec3 x, vec3 target, double r, double u1, double u2, vec3 *w, double *pdf);
/* The density of time_angular_sample at the unit direction w; 0 in the degenerate cases. */
double time_angular_pdf(vec3 x, vec3 target, double r, vec3 w);
/* One-sample MIS with the phase function: with probability c = share time-angular (u[1], u[2]), else phase
 * sampling (u[1], u[2]); *weight = ρ(ω)/(c·p_TA + (1 − c)·p_phase), p_phase = ρ (the balance heuristic).
 * Where time-angular sampling is degenerate (or share <= 0): phase sampling, weight 1. u: three uniforms. */
vec3 time_angular_mix_sample(const phase_function *ph, vec3 w_in, vec3 x, vec3 target, double r, double share,
                             const double u[3], double *weight);
/* The density of time_angular_mix_sample at w: c·p_TA + (1 − c)·ρ, or ρ where time-angular is degenerate. */
double time_angular_mix_pdf(const phase_function *ph, vec3 w_in, vec3 x, vec3 target, double r, double share, vec3 w);

/* ---- directions toward the next elliptical connection (DARTS path tracer; ours, docs/darts.md §14.3) ----
 * At a vertex x with the target (light) at x_L, C = |x_L − x|, μ = cosθ of ω against x_L − x, and the residual T
 * of the next segment's control vertex: ω with density p(ω) = TC/(2πλ·(T² + C² − 2TCμ)), λ = ln((T + C)/(T − C)),
 * φ uniform about x_L − x: the control vertex's 1/(p(t)·ℓ²) as a function of ω (docs/darts.md §5.2). Uniform
 * (1/(4π)) when C <= 1e-9·T (C = 0: the sphere); not run when T <= C(1 + 1e-6) (the peak ~ 1/(T − C)²). */

/* Whether the sampler runs for (x, x_L, T): T finite, > 0, and C <= 1e-9·T or T > C(1 + 1e-6). */
int ellipse_direction_usable(vec3 x, vec3 target, double T);
/* Returns 1 with the unit direction *w and its density *pdf (u1 picks cosθ, u2 the azimuth); 0 where not usable. */
int ellipse_direction_sample(vec3 x, vec3 target, double T, double u1, double u2, vec3 *w, double *pdf);
/* The density of ellipse_direction_sample at the unit direction w; 0 where not usable. */
double ellipse_direction_pdf(vec3 x, vec3 target, double T, vec3 w);
/* At the surface site ss of a camera path (a BSDF without delta lobes; docs/darts.md §14.4): with probability
 * share (u[0] < share) the direction from ellipse_direction_sample(x, target, T, u[1], u[2]), else from
 * surface_sample_bsdf(ss, u + 1, all lobes); out->weight = f·|n_s·ω| / (share·p_ell + (1 − share)·p_bsdf)
 * (one-sample balance heuristic), out->lobe a non-delta lobe of the BSDF. share 0, or the ellipse sampler not
 * usable: the BSDF sample as is. Returns 0 when nothing is sampled or the weight is 0 (below an opaque
 * surface). */
int ellipse_direction_surface_sample(const surface_site *ss, vec3 x, vec3 target, double T, double share,
                                     const double u[4], surface_sample *out);

#endif
