/* dartspp emitters: the lights of a scene and their pulses (docs/emitters.md). One file per emitter in
 * src/emitter: point, spot, collimated (with directional_point as its pencil-beam case) and area lights
 * (an emissive quad, disk, sphere, cube or mesh). Each has
 *   - emission sampling (a light path's first vertex and direction, with the flux it carries),
 *   - a direct-light sample for next-event estimation from a point x, where one exists,
 *   - the radiance a camera path sees when it hits the emitter (area lights),
 *   - its total flux Φ (light selection by power) and the pulse shape of its emission time.
 * Units follow the Tungsten format (docs/emitters.md §1): `emission` is intensity (point, spot), irradiance
 * across the beam (collimated of radius > 0), flux (collimated of radius 0), flux/(4π) (directional_point)
 * or radiance (area lights); `power` is the total flux Φ for every type. */
#ifndef DARTSPP_EMITTER_H
#define DARTSPP_EMITTER_H

#include <stdint.h>

#include "dartspp/core.h"

struct scene;

typedef enum { EMITTER_POINT, EMITTER_SPOT, EMITTER_COLLIMATED, EMITTER_AREA } emitter_type;
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
    emitter_type type;
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

/* ---- what each kind allows ---- */
/* Next-event estimation can reach the emitter from some points: every emitter but a parallel beam of
 * radius 0 (collimated with radius 0 and no divergence, directional_point). */
int emitter_connectable(const emitter *e);
/* A parallel beam of radius > 0: light arrives only inside the beam's half-cylinder, along the axis; the
 * path tracer connects it by sampling where a camera segment crosses the beam (emitter_beam_crossing). */
int emitter_is_parallel_beam(const emitter *e);
/* Camera paths can hit it (area lights). */
static inline int emitter_hittable(const emitter *e) { return e->type == EMITTER_AREA; }

/* ---- emission: the first vertex and direction of a light path ---- */
typedef struct {
    vec3 p;      /* the start point */
    vec3 n;      /* area lights: the surface normal at p (rays leave on its side); else 0 */
    vec3 d;      /* the direction, unit */
    vec3 flux;   /* what the path carries: L_e·cosθ/(p_A·p_ω), or I/p_ω, ... (the emitter's flux per path) */
} emitter_ray;

/* Four uniforms in [0,1). */
void emitter_sample_ray(const struct scene *s, const emitter *e, const double u[4], emitter_ray *r);

/* ---- next-event estimation ---- */
typedef struct {
    vec3 y;      /* the point on the emitter (collimated: where the light entered the beam's disc) */
    vec3 wi;     /* unit direction from x toward y (for a beam: −axis) */
    double dist; /* the light leg's length |x − y| (a beam: the distance along the axis) */
    vec3 value;  /* with denom: the incident radiance integrated against the sample's measure, value/denom;
                  * multiply by f (phase function, or BSDF·|cos|) and the transmittance along the leg */
    double denom;/* point lights: |x − y|² (kept apart so that I/d² rounds as one division); else 1 */
    vec3 n;      /* area lights: the surface normal at y (the shadow ray stops just before the surface); else 0 */
} emitter_direct;

/* Whether emitter_sample_direct uses its uniforms (area lights, diverging beams of radius > 0); the callers
 * draw none for the others, so that a scene of point lights draws what it always drew. */
int emitter_direct_draws(const emitter *e);

/* A direct-light sample from x with two uniforms; 0 when the emitter cannot light x this way (behind
 * an area light, outside a spot's cone or a beam, a parallel beam of radius 0). A parallel beam of radius
 * > 0 connects deterministically from a point inside it (wi = −axis, no 1/dist², docs/emitters.md §4). */
int emitter_sample_direct(const struct scene *s, const emitter *e, vec3 x, const double u[2], emitter_direct *out);

/* The aimed path tracer fixes one point of the emitter per camera path, the target of its samplers. */
typedef struct {
    vec3 y;       /* the point */
    vec3 n;       /* area and beam disc: its normal (the emitting side); else 0 */
    double pdf_a; /* its area density (1 for a point) */
} emitter_point;

void emitter_sample_point(const struct scene *s, const emitter *e, const double u[2], emitter_point *pt);
/* The connection from x to the fixed point (value: L_e·|cosθ_y|/(|x−y|²·p_A), or I(ω)/|x−y|²). */
int emitter_connect_point(const emitter *e, const emitter_point *pt, vec3 x, emitter_direct *out);

/* ---- hits ---- */
/* The radiance an area light sends back along a ray of direction d that hits it with geometric normal ng:
 * L_e on the front side (d·ng < 0), 0 behind (one-sided, as Tungsten's area lights). */
vec3 emitter_hit_radiance(const emitter *e, vec3 d, vec3 ng);

/* ---- the parallel beam crossing a camera segment ----
 * The interval [t0, t1] of the ray o + t·d (t in [0, tmax]) inside the beam's half-cylinder; 0 when the ray
 * misses it. */
int emitter_beam_crossing(const emitter *e, vec3 o, vec3 d, double tmax, double *t0, double *t1);

/* ---- light selection ---- */
/* The probability of choosing emitter i for a light path or an aimed camera path: in proportion to its flux
 * (channel mean) when by_power, else uniform (integrator key light_selection). */
double emitter_selection_pdf(const struct scene *s, int i, int by_power);
/* Chooses an emitter with the uniform u; *pdf its probability. -1 when the scene has no light. */
int emitter_select(const struct scene *s, double u, int by_power, double *pdf);

/* ---- set-up (scene loading) ---- */
/* Φ, the extent and, for area lights, the triangle distribution (needs the scene's world-space
 * triangles); -1 when out of memory. */
int emitter_prepare(const struct scene *s, emitter *e);
void emitter_free(emitter *e);

#endif
