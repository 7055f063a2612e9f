/* dartspp emitters: the lights of a scene and their pulses (docs/emitters.md). One table of operations
 * (emitter_ops), one row per type, each defined by its own file in src/emitter: point, spot, collimated (with
 * directional_point as its pencil-beam case) and area lights (an emissive quad, disk, sphere, cube or mesh).
 * Each has its keys (parsed with the loader's messages) and
 *   - emission sampling (a light path's first vertex and direction, with the flux it carries),
 *   - a direct-light sample for next-event estimation from a point x, where one exists,
 *   - the radiance a camera path sees when it hits the emitter (area lights),
 *   - its total flux Φ (light selection by power) and the pulse shape of its emission time.
 * Units follow the Tungsten format (docs/emitters.md §1): `emission` is intensity (point, spot), irradiance
 * across the beam (collimated of radius > 0), flux (collimated of radius 0), flux/(4π) (directional_point)
 * or radiance (area lights); `power` is the total flux Φ for every type. */
#ifndef DARTSPP_EMITTER_H
#define DARTSPP_EMITTER_H

#include <stddef.h>
#include <stdint.h>

#include "dartspp/core.h"

struct scene;

typedef struct emitter_ops emitter_ops;
typedef enum { PULSE_BOX, PULSE_GAUSSIAN } pulse_shape;

/* The emission time τ of a light path or a light connection (docs/time.md §5). width 0: a delta pulse at
 * `start`. Box: uniform on [start, start + width). Gaussian: `width` is the full width at half maximum and
 * the peak is at start + width/2, so a box and a Gaussian of equal keys have the same mean time. */
typedef struct {
    double start, width;
    pulse_shape shape;
} emitter_pulse;

/* Draws τ (a delta pulse draws nothing, so its random numbers are those of a scene without pulses). */
double emitter_pulse_sample(const emitter_pulse *p, dp_rng *rng);

typedef struct {
    char name[64];
    char type_name[24];  /* the scene file's type: point, spot, collimated, directional_point, quad, ... */
    const emitter_ops *ops; /* its type: the row of the table of emitter types (emitter_ops_find) */
    unsigned flags;      /* how the integrators reach it: EMITTER_* below, set by emitter_prepare */
    int medium;          /* ext_medium (MEDIUM_VACUUM without): where light paths start */
    emitter_pulse pulse;
    vec3 value;          /* point: intensity I; spot: I on the axis; collimated: irradiance E across the
                          * disc (radius > 0) or the beam's flux (radius 0); area: radiance L_e */
    vec3 flux;           /* total emitted flux Φ per channel */
    /* point, spot, collimated */
    vec3 pos;            /* the point; collimated: the centre of the beam's disc */
    vec3 axis;           /* spot, collimated: the unit direction of the beam (local +z, toward look_at) */
    vec3 e1, e2;         /* unit axes across the axis (collimated: the disc's; e1 = normalize(up × axis)) */
    /* spot (pbrt-v4's falloff: smoothstep in cosθ between the two cosines) */
    double cos_end;      /* cos(coneangle): black beyond */
    double cos_start;    /* cos(coneangle − conedeltaangle): full intensity inside */
    /* collimated */
    double radius;       /* of the disc the beam leaves (0: a line) */
    double cos_div;      /* cos of the divergence half-angle (1: parallel rays) */
    /* area: the triangles of surface `surface`, sampled in proportion to their area */
    int surface;
    uint32_t first_tri, tri_count;
    double *tri_cdf;     /* tri_count entries, the last 1 */
    double area;
    /* the largest distance from the point the path tracer aims at (pos, or a sampled point on the emitter)
     * to any point that emits: the bounds of bin sampling and early exit are widened by it */
    double extent;
} emitter;

/* ---- what each emitter allows: its flags, set by its type's prepare from its keys ---- */
enum {
    /* Next-event estimation can reach the emitter from some points: every emitter but a parallel beam of
     * radius 0 (collimated with radius 0 and no divergence, directional_point). */
    EMITTER_CONNECTABLE = 1u << 0,
    /* A parallel beam of radius > 0: light arrives only inside the beam's half-cylinder, along the axis; the
     * path tracer connects it by sampling where a camera segment crosses the beam (emitter_beam_crossing). */
    EMITTER_PARALLEL_BEAM = 1u << 1,
    /* Camera paths can hit it (area lights): emitter_hit_radiance. */
    EMITTER_HITTABLE = 1u << 2,
    /* emitter_sample_direct and emitter_sample_point use their two uniforms (area lights, diverging beams of
     * radius > 0); the callers draw none for the others, so that a scene of point lights draws what it
     * always drew. */
    EMITTER_DIRECT_DRAWS = 1u << 3,
    /* Every light path starts at `pos` (point, spot: a delta in position): the photon pass draws a DARTS
     * bin from pos before the emission's uniforms, so that a scene of point lights draws what it always drew. */
    EMITTER_STARTS_AT_POS = 1u << 4,
    /* An aimed camera path connects with a point drawn per connection (emitter_sample_direct), not with its
     * one fixed point of the light (a diverging beam's disc: a fixed point lights only a narrow cone,
     * docs/emitters.md §4). */
    EMITTER_AIM_PER_CONNECTION = 1u << 5,
};

static inline int emitter_connectable(const emitter *e) { return (e->flags & EMITTER_CONNECTABLE) != 0; }
static inline int emitter_is_parallel_beam(const emitter *e) { return (e->flags & EMITTER_PARALLEL_BEAM) != 0; }
static inline int emitter_hittable(const emitter *e) { return (e->flags & EMITTER_HITTABLE) != 0; }
static inline int emitter_direct_draws(const emitter *e) { return (e->flags & EMITTER_DIRECT_DRAWS) != 0; }
/* Next-event estimation reaches the emitter without drawing a point on it (point, spot, parallel beams):
 * the connection is the exact direct light, so photon points connect it instead of storing first-bounce
 * surface photons (surface_direct_connections, docs/defaults.md §3.8). */
static inline int emitter_connects_exactly(const emitter *e) { return emitter_connectable(e) && !emitter_direct_draws(e); }

/* ---- what a sample gives ---- */
/* Emission: the first vertex and direction of a light path. */
typedef struct {
    vec3 p;      /* the start point */
    vec3 n;      /* area lights: the surface normal at p (rays leave on its side); else 0 */
    vec3 d;      /* the direction, unit */
    vec3 flux;   /* what the path carries: L_e·cosθ/(p_A·p_ω), or I/p_ω, ... (the emitter's flux per path) */
} emitter_ray;

/* Next-event estimation: a light connection from a point x. */
typedef struct {
    vec3 y;      /* the point on the emitter (collimated: where the light entered the beam's disc) */
    vec3 wi;     /* unit direction from x toward y (for a beam: −axis) */
    double dist; /* the light leg's length |x − y| (a beam: the distance along the axis) */
    vec3 value;  /* with denom: the incident radiance integrated against the sample's measure, value/denom;
                  * multiply by f (phase function, or BSDF·|cos|) and the transmittance along the leg */
    double denom;/* point lights: |x − y|² (kept apart so that I/d² rounds as one division); else 1 */
    vec3 n;      /* area lights: the surface normal at y (the shadow ray stops just before the surface); else 0 */
} emitter_direct;

/* The aimed path tracer fixes one point of the emitter per camera path, the target of its samplers. */
typedef struct {
    vec3 y;       /* the point */
    vec3 n;       /* area and beam disc: its normal (the emitting side); else 0 */
    double pdf_a; /* its area density (1 for a point) */
} emitter_point;

/* ---- the table of emitter types ----
 * One row per type, each defined by its own file src/emitter/<type>.c (docs/emitters.md §8 says how to add
 * one). The integrators never ask which type an emitter is: they call the operations below through the
 * emitter_* functions and read the emitter's flags. */

/* What a type's parse reads its own keys with: the scene loader's reader of one primitive or emissive shape,
 * whose messages name the file, the primitive and the key. */
typedef struct emitter_keys {
    void *ctx;           /* the loader's */
    const char *type;    /* the scene file's type of the primitive or shape (directional_point, quad, ...) */
    int is_power;        /* the emitter's value holds `power` (the flux Φ), to be turned into its own unit */
    vec3 z, y;           /* a primitive's transform: local +z (toward look_at, not unit) and local +y (up) */
    /* a number: def when absent; lo <= value, and value <= hi when hi > lo; -1 with the message when bad */
    int (*number)(const struct emitter_keys *k, const char *key, double def, double lo, double hi, double *out);
    /* -1, with "<file>: <where>.<key>: <reason>" (key NULL: "<file>: <where>: <reason>") */
    int (*fail)(const struct emitter_keys *k, const char *key, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
} emitter_keys;

struct emitter_ops {
    const char *name;               /* point, spot, collimated, area */
    /* the scene file's primitive types it is, NULL-terminated (collimated: collimated, directional_point);
     * NULL for the emitter of an emissive shape (area lights) */
    const char *const *primitives;
    int ray_uniforms;               /* how many of sample_ray's four uniforms it reads (the photon pass draws those) */
    /* its own keys, after the common ones (emission or power, pulse, ext_medium, name) and pos: its axes, its
     * parameters, value in its own unit (docs/emitters.md §1); for an emissive shape, after surface,
     * first_tri and tri_count. -1 with the message in k. */
    int (*parse)(const struct scene *s, emitter *e, const emitter_keys *k);
    /* flux, extent and flags from the parsed emitter (and the scene's triangles); -1 when out of memory */
    int (*prepare)(const struct scene *s, emitter *e);
    void (*sample_ray)(const struct scene *s, const emitter *e, const double u[4], emitter_ray *r);
    void (*sample_point)(const struct scene *s, const emitter *e, const double u[2], emitter_point *pt);
    /* connect_point and sample_direct: out comes preset to {.denom = 1} (emitter_connect_point, ...) */
    int (*connect_point)(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out);
    int (*sample_direct)(const struct scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out);
    vec3 (*hit_radiance)(const emitter *e, vec3 d, vec3 ng);   /* NULL unless it sets EMITTER_HITTABLE */
    int (*beam_crossing)(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1);
                                                               /* NULL unless it sets EMITTER_PARALLEL_BEAM */
};

/* The type whose primitive is `type` (point, spot, collimated, directional_point), NULL for another. */
const emitter_ops *emitter_ops_find(const char *type);
/* The type of an emissive shape's emitter (area lights). */
const emitter_ops *emitter_ops_shape(void);
/* The primitive types of the table, in its order, joined by ", " and `last` before the last one. */
void emitter_primitive_list(char *buf, size_t size, const char *last);

/* ---- emission ---- */
/* Four uniforms in [0,1). */
static inline void emitter_sample_ray(const struct scene *s, const emitter *e, const double u[4], emitter_ray *r)
{
    e->ops->sample_ray(s, e, u, r);
}

/* ---- next-event estimation ---- */
/* A direct-light sample from x with two uniforms; 0 when the emitter cannot light x this way (behind
 * an area light, outside a spot's cone or a beam, a parallel beam of radius 0). A parallel beam of radius
 * > 0 connects deterministically from a point inside it (wi = −axis, no 1/dist², docs/emitters.md §4). */
static inline int emitter_sample_direct(const struct scene *s, const emitter *e, vec3 x, const double u[2],
                                        emitter_direct *out)
{
    *out = (emitter_direct){.denom = 1.0};
    return e->ops->sample_direct(s, e, x, u, out);
}

static inline void emitter_sample_point(const struct scene *s, const emitter *e, const double u[2], emitter_point *pt)
{
    e->ops->sample_point(s, e, u, pt);
}

/* The connection from x to the fixed point (value: L_e·|cosθ_y|/(|x−y|²·p_A), or I(ω)/|x−y|²). */
static inline int emitter_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out)
{
    *out = (emitter_direct){.denom = 1.0};
    return e->ops->connect_point(e, pt, x, out);
}

/* ---- hits ---- */
/* The radiance an area light sends back along a ray of direction d that hits it with geometric normal ng:
 * L_e on the front side (d·ng < 0), 0 behind (one-sided, as Tungsten's area lights); 0 for an emitter that
 * cannot be hit. */
static inline vec3 emitter_hit_radiance(const emitter *e, vec3 d, vec3 ng)
{
    return emitter_hittable(e) ? e->ops->hit_radiance(e, d, ng) : v3s(0.0);
}

/* ---- the parallel beam crossing a camera segment ----
 * The interval [t0, t1] of the ray o + t·d (t in [0, tmax]) inside the beam's half-cylinder; 0 when the ray
 * misses it or the emitter is no parallel beam. */
static inline int emitter_beam_crossing(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1)
{
    return emitter_is_parallel_beam(e) && e->ops->beam_crossing(e, o, d, tmax, t0, t1);
}

/* ---- light selection ---- */
/* The probability of choosing emitter i for a light path or an aimed camera path: in proportion to its flux
 * (channel mean) when by_power, else uniform (integrator key light_selection). */
double emitter_selection_pdf(const struct scene *s, int i, int by_power);
/* Chooses an emitter with the uniform u; *pdf its probability. -1 when the scene has no light. */
int emitter_select(const struct scene *s, double u, int by_power, double *pdf);

/* ---- set-up (scene loading) ---- */
/* Φ, the extent, the flags and, for area lights, the triangle distribution (needs the scene's world-space
 * triangles); -1 when out of memory. */
int emitter_prepare(const struct scene *s, emitter *e);
void emitter_free(emitter *e);

#endif
