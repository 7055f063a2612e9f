/* dartspp sliced_primitives: Liu, Jiao and Jarosz 2022's temporally sliced photon primitives
 * (../shared/papers/liu-2022-sliced-photon-primitives.txt; docs/sliced_primitives.md), as volume photon types of
 * photon points: balls, volumes (parallelepipeds), hypervolumes (parallelotopes), volumes_balls and
 * mis_volumes_balls. The photon pass records every light-path vertex (path_vertex, include/dartspp/photon.h);
 * each iteration builds the primitives from them (a gate time τ_k each, fresh phase directions), a BVH over the
 * bounds their time budgets allow, and the sensor pass (src/gather) evaluates them along every medium segment of
 * the camera walk: the roots of the 4-D delta, each as a *long* primitive (the displaced path's transmittance,
 * visibility, σs and phase functions evaluated by the scene), divided by the numerical dimensions' density
 * and |J|. Paths a type's primitives do not serve are left to photon beams (src/photon_beams), Liu's §5
 * fallback: PATH_VERTEX_* on each beam say which. */
#ifndef DARTSPP_SLICED_PRIMITIVES_H
#define DARTSPP_SLICED_PRIMITIVES_H

#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/photon.h"
#include "dartspp/plan.h"
#include "dartspp/surface_site.h"

/* The primitive kinds, one row each in the table of slice_kinds.c. */
typedef enum { SLICE_BALL, SLICE_PARALLELEPIPED, SLICE_PARALLELOTOPE, SLICE_KIND_COUNT } slice_kind;

/* One delta-sliced primitive of this iteration, built at a light-path vertex. */
typedef struct {
    uint32_t vertex;   /* index into the vertex array */
    int kind;          /* slice_kind */
    double tau;        /* its slice time τ_k (a box gate: drawn uniformly in the gate or frames' span) */
    vec3 w[3];         /* fresh phase-sampled directions: a parallelepiped's ω2, ω1; a parallelotope's ω3, ω2, ω1 */
    double pdf;        /* their joint density (1 for a ball) */
} slice_prim;

typedef struct slice_map slice_map;

/* What the build needs from the plan. */
typedef struct {
    int type;          /* volume_photon_type_choice (a sliced one) */
    time_window window;
    uint64_t seed;
    long iteration;
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
/* Whether the type weighs balls against parallelepipeds by score-based MIS (§4.6). */
int slice_type_mis(int type);
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
