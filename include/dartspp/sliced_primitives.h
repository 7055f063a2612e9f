/* dartspp sliced photon primitives (src/sliced_primitives): Liu, Jiao and Jarosz 2022's temporally sliced photon
 * primitives. This header starts with their geometry (src/sliced_primitives/slice_geometry.c), public so that
 * tests/sliced_primitives/test_slice_geometry.c can check it (tests include no header under src/); then the
 * estimators (below the geometry).
 *
 * The geometry of the temporally sliced photon primitives (Liu et al. 2022 §4; the paper's text:
 * ../shared/papers/liu-2022-sliced-photon-primitives.txt). Each estimator pre-integrates four dimensions against
 * a 4-D spatio-temporal delta δ⁴(g′) (eq. 20–24): these functions find the roots of g′(ξ_a) = 0 for one
 * primitive and one camera segment and give |J|, the absolute 4×4 Jacobian determinant of g′ with respect to
 * the analytic dimensions (eq. 25), camera-warped or unwarped. Pure functions: no scene, no medium, no
 * transmittance — the caller evaluates the path contribution at each root.
 *
 * Conventions (all times are optical path lengths, as everywhere in dartspp):
 * - The camera segment is y1 + s·ψ, ψ unit, 0 <= s <= s_max; eta_c is the time per unit length along it
 *   (the medium's η when camera-warped, 0 when the segment is the sensor's own and unwarped).
 * - The photon chain starts at the base vertex x (x_1 for a ball, x_2 for a plane, x_3 for a parallelepiped,
 *   x_4 for a parallelotope) and goes on along w[0] = ω_k, ..., w[k-1] = ω_1 (unit, Liu's eq. 11 order);
 *   eta_p is the time per unit length along those segments (one medium).
 * - tau is the time budget of a delta-sliced primitive: the gate time minus the light path's time at x minus
 *   the camera path's time at y1 (for the parallelotope: at y0, the sampled camera point). A root satisfies
 *   eta_p·Σt + eta_c·s = tau exactly.
 * - Roots with any t < 0, s < 0 or s > s_max are not returned. */
#ifndef DARTSPP_SLICED_PRIMITIVES_H
#define DARTSPP_SLICED_PRIMITIVES_H

#include "dartspp/core.h"
#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/photon.h"
#include "dartspp/plan.h"
#include "dartspp/surface_site.h"

typedef struct {
    vec3 y1, psi;    /* camera segment origin and unit direction */
    double s_max;    /* its length */
    double eta_c;    /* time per unit length along it (0: unwarped) */
} slice_ray;

typedef struct {
    double t[4];     /* t_k, ..., t_1 (k entries used) */
    double s;        /* distance along the camera segment */
    vec3 w1;         /* ball only: ω_1*, the direction from x to the root */
    double jacobian; /* |J| at the root, > 0 (roots with |J| below 1e-12 relative are dropped) */
    double time;     /* eta_p·Σt + eta_c·s, the time the root adds to x's (= tau for delta-sliced roots; the
                      * planes' box gate reads it) */
} slice_root;

/* Sliced ball / VPL, Liu et al. 2022 §4.5, ξ_a = {cos θ1, φ1, t1, s1}: the points y1 + s·ψ at distance t1
 * from x with eta_p·t1 + eta_c·s = tau (a sphere when unwarped, the ellipsoid of Pediredla et al. 2019 when
 * eta_c = eta_p, a convex oval between). Up to 2 roots (1 on the ellipsoid); |J| = t1²·|eta_p·(ω1*·ψ) + eta_c|
 * (docs/sliced_primitives.md §6; Liu's formulas below eq. 46 are its eta_c = 0 and eta_c = eta_p cases). */
int slice_ball_roots(vec3 x, double eta_p, double tau, const slice_ray *r, slice_root out[2]);

/* Sliced photon plane, Liu et al. 2022 §4.2, ξ_a = {t2, t1, s1, τ_k} (box gates: no time constraint):
 * x + t2·ω2 + t1·ω1 = y1 + s·ψ, t2 in [0, len[0]], t1 in [0, len[1]] (short planes: the segments as sampled;
 * pass INFINITY for long). At most 1 root; |J| = |(ω2 × ω1)·ψ| (eq. 30, warped or not: the τ_k column is
 * (0, 0, 0, ±1)). root.time is set. */
int slice_plane_root(vec3 x, const vec3 w[2], const double len[2], double eta_p, const slice_ray *r,
                     slice_root *out);

/* The 1-D-blurred photon plane (planes_1d; Bitterli and Jarosz 2017's "photon plane 1D" as Liu's code has it,
 * made transient with a box gate: docs/sliced_primitives.md §7), ξ_a = {t2, t1, B, τ_k}: x + t2·ω2 + t1·ω1 +
 * B·n = y1 + s·ψ, n = ω2 × ω1 / |ω2 × ω1|, with a box kernel 1/(2r) on the blur B and s left to the caller
 * (numerical). Every s of the camera segment has one root; this gives the interval [s0, s1] of those with
 * 0 <= t2 <= len[0], 0 <= t1 <= len[1], |B| <= r and the root's time eta_p·(t2 + t1) + eta_c·s in
 * [time_lo, time_hi] (the gate less the light's time at x and the camera's at y1), and the roots as linear
 * functions of s. |J| = |ω2 × ω1| (the τ_k column (0, 0, 0, ±1), the B column (n, 0)). */
typedef struct {
    double s0, s1;        /* the interval, s0 < s1 */
    double t2[2], t1[2];  /* t2(s) = t2[0] + t2[1]·s, t1(s) likewise */
    double b[2];          /* B(s) */
    double jacobian;      /* |ω2 × ω1| */
} slice_interval;
int slice_plane1d_interval(vec3 x, const vec3 w[2], const double len[2], double radius, double eta_p,
                           const slice_ray *r, double time_lo, double time_hi, slice_interval *out);

/* Delta-sliced parallelepiped, Liu et al. 2022 §4.3, ξ_a = {t3, t2, t1, s1}: x + t3·ω3 + t2·ω2 + t1·ω1 =
 * y1 + s·ψ with the time constraint (eq. 35–37). At most 1 root; |J| = |det J| of eq. 37 with eta_c in the s
 * column's time entry = |eta_p·ψ·n + eta_c·ω1·(ω2 × ω3)|, n = ω1 × ω2 + ω2 × ω3 + ω3 × ω1 (eq. 38 is its
 * unwarped value; docs/sliced_primitives.md §6). */
int slice_parallelepiped_root(vec3 x, const vec3 w[3], double eta_p, double tau, const slice_ray *r,
                              slice_root *out);

/* Delta-sliced parallelotope, Liu et al. 2022 §4.4, ξ_a = {t4, t3, t2, t1}: x + Σ t_i·ω_i = y0 (a camera
 * point sampled by the caller; warping only moves tau) with eta_p·Σt = tau. At most 1 root (s unused);
 * |J| = |det| of eq. 43. */
int slice_parallelotope_root(vec3 x, const vec3 w[4], double eta_p, double tau, vec3 y0, slice_root *out);

/* |J| of each estimator at a given full path, for score-based MIS (Liu et al. 2022 §4.6), where the path was
 * found by another estimator: the ball's with t1, ω1 (x1 → x0); the parallelepiped's with its three
 * directions. */
double slice_ball_jacobian(double t1, vec3 w1, vec3 psi, double eta_p, double eta_c);
double slice_parallelepiped_jacobian(const vec3 w[3], vec3 psi, double eta_p, double eta_c);

/* Small dense linear algebra, written here (four lines each; no library needed for 4×4). */
double slice_det4(const double a[4][4]);
/* Solves a·x = b by Gaussian elimination with partial pivoting; 0 on success, -1 when singular. */
int slice_solve4(const double a[4][4], const double b[4], double x[4]);


/* ---- the estimators ----
 * Liu, Jiao and Jarosz 2022's temporally sliced photon primitives
 * (../shared/papers/liu-2022-sliced-photon-primitives.txt; docs/sliced_primitives.md), as volume photon types of
 * photon points: balls, volumes (parallelepipeds), hypervolumes (parallelotopes), volumes_balls and
 * mis_volumes_balls. The photon pass records every light-path vertex (path_vertex, include/dartspp/photon.h);
 * each iteration builds the primitives from them (a gate time τ_k each, fresh phase directions), a BVH over the
 * bounds their time budgets allow, and the sensor pass (src/gather) evaluates them along every medium segment of
 * the camera walk: the roots of the 4-D delta, each as a *long* primitive (the displaced path's transmittance,
 * visibility, σs and phase functions evaluated by the scene), divided by the numerical dimensions' density
 * and |J|. Paths a type's primitives do not serve are left to photon beams (src/photon_beams), Liu et al. 2022 §5
 * fallback: PATH_VERTEX_* on each beam say which. */

/* The primitive kinds, one row each in the table of slice_gather.c (the estimate) and slice_build.c (the fresh directions). */
typedef enum {
    SLICE_BALL,
    SLICE_PARALLELEPIPED,
    SLICE_PARALLELOTOPE,
    SLICE_PLANE,    /* Liu et al. 2022 §4.2: the box gate analytic, no τ_k drawn (tau: the window's end) */
    SLICE_PLANE_1D, /* the 1-D-blurred plane (docs/sliced_primitives.md §7.2) */
    SLICE_KIND_COUNT
} slice_kind;

/* One delta-sliced primitive of this iteration, built at a light-path vertex. */
typedef struct {
    uint32_t vertex;   /* index into the vertex array */
    int kind;          /* slice_kind */
    double tau;        /* its slice time τ_k (a box gate: drawn uniformly in the gate or frames' span); planes: the
                        * window's end (their bound) */
    vec3 w[3];         /* fresh phase-sampled directions: a parallelepiped's ω2, ω1; a parallelotope's ω3, ω2, ω1;
                        * a plane's ω1 */
    double pdf;        /* their joint density (1 for a ball) */
} slice_prim;

typedef struct slice_map slice_map;

/* What the build needs from the plan. */
typedef struct {
    int type;          /* volume_photon_type_choice (a sliced one) */
    time_window window;
    uint64_t seed;
    long iteration;
    double r;          /* planes_1d: the blur's half-width (the iteration's volume radius) */
} slice_build_input;

/* The primitives of the type at the n vertices (copied) and a BVH over their bounds. NULL + err out of memory.
 * An empty map (no primitive) is valid. */
slice_map *slice_map_build(const scene *s, const slice_build_input *in, const path_vertex *v, size_t n, dp_error *err);
void slice_map_free(slice_map *m);
size_t slice_map_size(const slice_map *m);
const path_vertex *slice_map_vertices(const slice_map *m);
/* Bytes slice_map_build allocates for n vertices of a type (the memory guard). */
double slice_map_bytes(int type, double n);

/* Called for every primitive whose bounds the camera segment o + t·d, 0 <= t <= tmax, enters and whose time
 * budget τ_k − τ(x) exceeds t_cam (the camera time at o), in the map's fixed order. */
typedef void (*slice_visit_fn)(void *ctx, const slice_prim *p);
void slice_map_query(const slice_map *m, vec3 o, vec3 d, double tmax, double t_cam, slice_visit_fn visit, void *ctx);

/* ---- the types: which primitive serves which path (slice_types.c, one table) ---- */
/* Whether the type builds a primitive of kind k at a vertex with PATH_VERTEX_* flags f. */
int slice_type_builds(int type, int kind, unsigned f);
/* Whether a beam leaving a vertex with flags f is gathered (no primitive of the type serves its paths). */
int slice_type_gathers_beam(int type, unsigned f);
/* Whether the type weighs balls against parallelepipeds by score-based MIS (Liu et al. 2022 §4.6). */
int slice_type_mis(int type);
/* 1: the type's primitives are sliced photon planes, 2: 1-D-blurred planes, 0: neither (their gate is analytic). */
int slice_type_plane(int type);
/* The type's line in the render summary. */
const char *slice_type_summary(int type);

/* Refuses, with a message naming the key, what the sliced primitives do not support: DARTS samplers, an
 * ungated window, low_order_scattering false, regions of different refractive index. 0 when fine. */
int sliced_primitives_check(const scene *s, const render_plan *p, dp_error *err);

/* ---- the estimate along a camera segment (slice_gather.c) ---- */
typedef struct {
    const slice_map *map;
    int type;
    bounce_limits bounces;
    surface_shading shading; /* a ball at a surface vertex evaluates its BSDF */
    int camera_unwarp;       /* the camera segment adjacent to the sensor takes no time */
    double r;                /* planes_1d: the blur's half-width (the iteration's volume radius) */
} slice_gather;

/* Every primitive's roots on the camera segment o + t·d, 0 <= t <= len, in medium med (thr and t_cam at o, b_cam
 * camera segments): the long path's contribution at each root over the numerical density and |J|, times the
 * gate weight, into the film's slot of τ_k. rng: the pixel's stream (a parallelotope draws its camera point). */
void sliced_primitives_gather(const slice_gather *g, const scene *s, film_pixel *pix, int med, vec3 o, vec3 d,
                              double len, vec3 thr, double t_cam, int b_cam, dp_rng *rng);

/* The MIS weight of a ball (ball = 1) or a parallelepiped (ball = 0) for the path x3 → x2 → x1 → x0 with
 * segments t3, t2, t1 along ω3, ω2, ω1, x2 in medium m2 and x1 in m1, camera direction ψ: the balance heuristic
 * over q_ball = p_d(t3)·p_d(t2)·|J_ball| and q_pp = f_p(ω2 → ω1)·|J_pp| (the densities of the two estimators
 * with their shared factors cancelled; docs/sliced_primitives.md §5). Both estimators call it with the same
 * path, so the two weights sum to 1. */
double slice_mis_weight(const scene *s, int ball, double t3, double t2, double t1, const vec3 w[3], int m2, int m1,
                        vec3 psi, double eta_p, double eta_c);

/* The memory guard's item of the primitives: V vertices, their primitives and map. */
void sliced_primitives_memory(int type, double V, memory_estimate *m);

#endif
