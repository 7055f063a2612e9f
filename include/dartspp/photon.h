/* dartspp photon: photon records, the photon pass, and the two photon maps — volume photons answering
 * "every photon within r of the segment o + tω, 0 <= t <= t_max", surface photons answering "k nearest
 * within R" (exact search; our BVH by default, FLANN's kd-tree kept for comparison). Maps are rebuilt every
 * iteration. */
#ifndef DARTSPP_PHOTON_H
#define DARTSPP_PHOTON_H

#include "dartspp/core.h"
#include "dartspp/darts.h"
#include "dartspp/derivative.h"
#include "dartspp/emitter.h"
#include "dartspp/plan.h"
#include "dartspp/scene.h"

typedef struct {
    float pos[3];
    float dir[3];     /* propagation direction of the segment arriving at pos (unit) */
    float power[3];   /* already divided by the number of light paths (docs/design.md §2.3) */
    int bounce;       /* path segments from the light to this photon */
    int frame;        /* DARTS frame mode: the only frame this photon may be gathered in; -1: any */
    double time;      /* light-to-photon path time (optical path length) */
} photon;

/* A photon's derivative weights (docs/derivatives.md §4), in an array beside the photons, indexed like them,
 * allocated only when the render asks for derivatives (the photon record does not grow): ∂ ln f/∂θ_k of its
 * light path per channel and ∂τ/∂θ_k, the light it left and the offset path_time_offset drew for that path.
 * A record is photon_deriv_stride(K) bytes (16 + 16·K); the kernel of the estimate does not depend on them. */
typedef struct {
    double offset;  /* the path's draw of path_time_offset (its time starts there) */
    int light;      /* the light's index */
    int unused;
    float w[];      /* per derivative k: dlog_k (3 channels), then dtof_k */
} photon_deriv;

static inline size_t photon_deriv_stride(int k) { return k > 0 ? sizeof(photon_deriv) + 4 * (size_t)k * sizeof(float) : 0; }
static inline const photon_deriv *photon_deriv_at(const unsigned char *side, size_t stride, size_t i)
{
    return (const photon_deriv *)(const void *)(side + i * stride);
}
/* The record of a light path's state (src/photon/photon_deriv.c), into `out` (stride of d->count). */
void photon_deriv_write(const deriv_plan *d, const deriv_path *p, int light, double offset, void *out);
/* Adds a record's weights to a camera path's state: the full path's ∂ ln f and ∂τ (a sum over its parts). */
void photon_deriv_add(const deriv_plan *d, deriv_path *p, const photon_deriv *pd);

/* A photon beam (volume_photon_type "beams", src/photon_beams): one medium segment of a light path from a
 * light, surface or medium vertex. Baseline pass: a short beam, to the next vertex (a medium event or a
 * surface) as the free-flight sampler drew it; the flux at distance s along it is power · T(s)/P(s), T the
 * medium's transmittance and P(s) = mean over channels of T(s) the probability that the sampler reaches s (1 in
 * a grey medium). DARTS pass (long_beam): a long beam, to the next surface whatever distance DA sampling drew
 * (its survival function has no closed form), flux power · T(s). Jarosz et al. 2011 (docs/beams.md §1). */
typedef struct {
    float start[3];
    float dir[3];     /* unit */
    float power[3];   /* the path throughput at the start, divided by the number of light paths */
    float length;     /* to the next vertex */
    float eta;        /* its medium's η (time per length): the time at s is time + η·s */
    int medium;       /* index into scene.media */
    int frame;        /* DARTS frame mode: the only frame it may be gathered in; -1: any */
    int long_beam;    /* 1: flux power·T(s) (DARTS pass); 0: power·T(s)/P(s) (short beam) */
    int bounce;       /* path segments from the light to a scattering point on the beam (this segment's index) */
    unsigned from;    /* PATH_VERTEX_* of the light-path vertex the segment leaves (a null surface is no vertex):
                       * which sliced primitive serves the paths it would complete (src/sliced_primitives) */
    double time;      /* light-to-start path time */
} photon_beam;

/* What a light-path vertex is, for the sliced primitives' coverage (docs/sliced_primitives.md §4). */
#define PATH_VERTEX_MEDIUM 1u      /* a medium scattering vertex */
#define PATH_VERTEX_DELTA 2u       /* its outgoing direction was drawn from a delta: a specular lobe, a collimated
                                    * (or per-connection aimed) emitter; a ball cannot evaluate it */
#define PATH_VERTEX_PREV_MEDIUM 4u /* the vertex before it is a medium vertex */
#define PATH_VERTEX_PREV2_MEDIUM 8u /* the two vertices before it are medium vertices */

typedef enum { PATH_VERTEX_EMITTER, PATH_VERTEX_SURFACE, PATH_VERTEX_VOLUME } path_vertex_kind;

/* A light-path vertex as the sliced primitives need it (photon_pass_input.vertices; Liu et al. 2022 build their
 * primitives from these, src/sliced_primitives): every emitter point, surface vertex (not null or forward) and
 * medium vertex of the paths under the volume budget. Powers divided by the number of light paths. */
typedef struct {
    vec3 pos;           /* the vertex (an area light: on its surface, not offset) */
    vec3 w_in;          /* the propagation direction arriving (0 at an emitter) */
    vec3 w_out;         /* the sampled outgoing direction (0 when sampling failed: the path ended here) */
    vec3 beta_in;       /* the throughput arriving: at a medium vertex with σs/σt-like event weight included
                         * (what a volume photon carries); at a surface, before the BSDF; at an emitter 1/p_select */
    vec3 beta_out;      /* after the vertex's sampled scattering weight f·|cos|/p (an emitter: its ray's flux) */
    vec3 prev_pos;      /* the vertex before (MIS of balls against parallelepipeds) */
    vec3 prev_w_in;     /* the direction arriving at the vertex before */
    double prev_seg;    /* the length of the segment arriving at the vertex before (0: none) */
    double time;        /* light-to-vertex path time */
    hit_record hit;     /* surface vertices: the hit */
    emitter_point ep;   /* emitter vertices: the point (pdf_a: its area density) */
    int light;          /* emitter vertices: the light's index */
    int kind;           /* path_vertex_kind */
    unsigned flags;     /* PATH_VERTEX_* */
    int medium_in;      /* the region the path arrived in (a surface: the side it came from) */
    int medium_out;     /* the region w_out leaves into */
    int prev_region;    /* the region of the vertex before (its medium when a medium vertex) */
    int bounce;         /* path segments from the light to the vertex */
    int medium_events;  /* medium events since the last surface or light, this one included */
} path_vertex;

/* ---- volume photon map ---- */
typedef struct volume_photon_map volume_photon_map;

/* Builds the map over n photons (copied), each with the same gather radius r >= 0. NULL + err on failure. */
volume_photon_map *volume_map_build(const photon *ph, size_t n, double r, dp_error *err);
void volume_map_free(volume_photon_map *m);
size_t volume_map_size(const volume_photon_map *m);
/* The build's invariant, checked: every node's photon range splits at a plane between its children's
 * photons (some axis with max(left) <= min(right)). The queries stay exact without it (the boxes are the
 * photons' own), so only this check sees a wrong split. O(n log n); for tests. */
int volume_map_splits_ok(const volume_photon_map *m);

/* Called for every photon p with t = (p - o)·d in [0, tmax] and d2 = |p - o|^2 - t^2 <= r^2
 * (d unit; tmax may be INFINITY). Visit order is fixed by the map, so results are deterministic. */
typedef void (*beam_visit_fn)(void *ctx, const photon *p, double t, double d2);
void photon_map_query_beam(const volume_photon_map *m, vec3 o, vec3 d, double tmax, beam_visit_fn visit, void *ctx);

/* A time window on a beam query. A photon p visited at parameter t has the total time
 *   t0 + p->time + eta · leg,   leg = t (projected) or |p - o| (Euclidean),
 * and the caller counts it only inside [lo, hi) (lo <= hi; hi may be INFINITY). */
typedef struct {
    double t0;     /* time at the segment origin */
    double eta;    /* time per unit of leg (0: the leg takes no time) */
    int projected; /* leg = t; 0: leg = |p - o| */
    double lo, hi; /* the window */
} beam_time_filter;

/* photon_map_query_beam, skipping the subtrees none of whose photons can have a total time in [lo, hi):
 * bounds from the node's box and its photons' time range, widened by a relative margin (1e-9) for the
 * rounding of the caller's own time computation. So it visits, in the same order, the photons of the plain
 * query minus some outside the window (never one inside it): the caller still tests each photon's time. */
void photon_map_query_beam_window(const volume_photon_map *m, vec3 o, vec3 d, double tmax, const beam_time_filter *w,
                                  beam_visit_fn visit, void *ctx);

/* The index, in the array given to volume_map_build, of a photon a query visited (the map holds its photons in
 * tree order: what is kept beside the photons, such as their photon_deriv records, is found by this). */
size_t volume_map_source(const volume_photon_map *m, const photon *p);

/* The same search as surface_map_query_knn, on a volume map (built with any r): k nearest within R in
 * (d2, index) order, indices into the array given to volume_map_build. */
int volume_map_query_knn(const volume_photon_map *m, vec3 x, int k, double R, int *idx, double *d2);

/* ---- surface photon map ---- */
typedef struct surface_photon_map surface_photon_map;

/* Default backend: our BVH (volume_map_query_knn) — about 10x faster per query than FLANN's C API,
 * whose every call opens an OpenMP region and allocates (bench/results/surface_map.md). The FLANN backend
 * (single kd-tree, exact search, exact double distances over its candidates) is kept for comparison. */
surface_photon_map *surface_map_build(const photon *ph, size_t n, dp_error *err);
surface_photon_map *surface_map_build_flann(const photon *ph, size_t n, dp_error *err);
void surface_map_free(surface_photon_map *m);
/* Up to k photons nearest to x with squared distance < R^2, nearest first: indices into the photon
 * array given to surface_map_build, and their squared distances. Returns the count found. Thread-safe. */
int surface_map_query_knn(const surface_photon_map *m, vec3 x, int k, double R, int *idx, double *d2);

/* Bytes volume_map_build allocates for n photons, the build's scratch included (the memory guard's estimate;
 * the surface map's default backend is the same structure). */
size_t volume_map_bytes(size_t n);

/* ---- photon pass ----
 * Light paths from the point lights (light picked uniformly, direction uniform): photons stored at medium
 * scattering vertices (volume) and at surface hits whose BSDF has lobes the sensor pass gathers
 * (surface_photon_split: diffuse and rough glossy lobes), never on null/forward or purely specular surfaces. Budgets: at most `photon_count` paths; surface and volume budgets `photon_count` and
 * `volume_photon_count`. A map keeps the photons of the leading paths whose photons all fit (the cut is
 * decided by path index, so the result does not depend on the thread count), and its powers are divided
 * by that number of paths. */
#define PHOTON_PASS_BATCH 8192 /* light paths traced between two merges (and two looks at the stop flag) */

/* The surface chains of one photon pass (surface_chain.c). */
typedef struct {
    long traced;          /* light paths the chains traced */
    long large, visible;  /* independent proposals, and those that stored a surface photon */
    long states;          /* chain states counted */
    long small, accepted; /* small steps proposed and accepted */
    long early_exits;     /* chain paths ended by the DARTS early exit */
} photon_chain_stats;

typedef struct {
    photon *vol, *surf;
    size_t n_vol, n_surf;
    unsigned char *vol_deriv, *surf_deriv; /* photon_pass_input.deriv: the photons' photon_deriv records, in the
                                            * same order (NULL without derivatives) */
    size_t deriv_stride;   /* their size, photon_deriv_stride(K) (0 without derivatives) */
    long paths;            /* light paths traced */
    long vol_paths;        /* paths the volume powers are divided by */
    long surf_paths;
    long nonfinite;        /* photons dropped for a non-finite power */
    long early_exits;      /* paths ended by the DARTS early exit */
    long aimed_paths;      /* DARTS: paths traced with its samplers, before the volume budget filled */
    photon_chain_stats chain; /* surface chains (all 0 without them) */
    photon_beam *beams;    /* photon_pass_input.beams: the medium segments, instead of volume photons */
    size_t n_beams;
    path_vertex *verts;    /* photon_pass_input.vertices: the light paths' vertices (under the volume budget, with
                            * the beams of the same paths) */
    size_t n_verts;
    int interrupted;       /* the stop flag ended the pass early: the sets are incomplete */
} photon_set;

/* What one photon pass needs, taken from the render plan by photon_pass_input_init. */
typedef struct {
    double light_paths;             /* light paths traced (photon_count) */
    light_selection_choice light_selection; /* how a path picks its light */
    double volume_budget, surface_budget; /* photons kept per map */
    int max_bounces;                /* path segments; photons of longer paths cannot count */
    double t_end;                   /* the window's end (INFINITY: steady state) */
    int include_surfaces, low_order_scattering;
    int surface_direct;             /* surface_direct_connections: no surface photon at a light path's first
                                     * vertex from a light that emitter_connects_exactly (the sensor pass
                                     * connects that light there) */
    int beams;                      /* volume_photon_type "beams": the volume budget holds beams (the medium
                                     * segments; long ones with DARTS), no volume photons */
    int vertices;                   /* sliced primitives: record every light-path vertex (path_vertex); the volume
                                     * budget counts vertices, and the same paths' beams are kept with them */
    double chain_share;             /* the share of the light paths left once the volume budget is full that
                                     * the chains trace (render_plan.chain_share) */
    int surface_chains;             /* DARTS: once the volume budget is full, the surface photons come from
                                     * Markov chains over light paths (surface_chain.c) */
    darts_guide guide;              /* DARTS bins, bounds and switches; guide.active 0: baseline */
    double surface_slack;           /* widening of the DARTS surface time tests and early exit: the camera-leg
                                     * change across the surface gather radius, so the gather's own gate
                                     * test decides (plan_surface_slack) */
    surface_shading shading;        /* BSDF frames and the gather/continue split (same as the sensor pass) */
    const deriv_plan *deriv;        /* the render's derivatives (the light paths carry a deriv_path and the photons
                                     * their photon_deriv records), or NULL */
    size_t deriv_stride;            /* photon_deriv_stride(deriv->count), 0 without */
    const eda_set *eda;             /* EDA tables per medium, or NULL: phase sampling everywhere */
    uint64_t seed;
    long iteration;
    const dp_stop_flag *stop;       /* read once per batch (may be NULL): once set, the pass ends early with
                                     * out->interrupted = 1 and incomplete sets (the caller drops them) */
} photon_pass_input;

void photon_pass_input_init(photon_pass_input *in, const scene *s, const render_plan *p, const eda_set *eda,
                            uint64_t seed, long iteration, const dp_stop_flag *stop);
/* Whether the pass feeds the surface map by surface chains once the volume budget is full. */
int photon_pass_uses_chains(const photon_pass_input *in);
int photon_pass(const scene *s, const photon_pass_input *in, photon_set *out, dp_error *err);
void photon_set_free(photon_set *ps);

/* Bytes a beam array of n beams holds at its capacity (it grows by doubling). */
double photon_beam_array_bytes(double n);

/* Bytes a vertex array of n vertices holds at its capacity. */
double path_vertex_array_bytes(double n);

/* Bytes a photon set's array of n photons holds at its capacity (it grows by doubling: less than 2n). */
double photon_array_bytes(double n);

#endif
