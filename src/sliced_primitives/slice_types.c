/* The sliced volume photon types: which primitive serves which path, and which beams are left (one table, the
 * only place that lists them; docs/sliced_primitives.md §4). A path is named by its last light vertices before
 * the camera point x0: x1, x2, x3. A ball at x1 needs x1's outgoing distribution to be evaluable (no delta); a
 * parallelepiped at x3 needs x2 and x1 to be medium vertices; a parallelotope at x4 needs x3, x2 and x1 to be.
 * The beam of the segment x1 → x0 is gathered exactly when no primitive of the type serves the path. */
#include "dartspp/sliced_primitives.h"

#define F_MEDIUM PATH_VERTEX_MEDIUM
#define F_DELTA PATH_VERTEX_DELTA
#define F_PREV PATH_VERTEX_PREV_MEDIUM
#define F_PREV2 PATH_VERTEX_PREV2_MEDIUM

/* Paths whose x1 is the vertex with flags f and that a parallelepiped serves: x1 and x2 medium vertices. */
static int pp_serves_x1(unsigned f) { return (f & F_MEDIUM) && (f & F_PREV); }
/* ... that a parallelotope serves: x1, x2, x3 medium vertices. */
static int pt_serves_x1(unsigned f) { return (f & F_MEDIUM) && (f & F_PREV) && (f & F_PREV2); }
static int ball_serves_x1(unsigned f) { return !(f & F_DELTA); }
/* ... that a plane at x2 serves (its ω2 the photon's own, its ω1 fresh): x1 a medium vertex, any x2. */
static int plane_serves_x1(unsigned f) { return (f & F_MEDIUM) != 0; }

typedef struct {
    int type;
    int ball;       /* balls at every non-delta x1 (minus, with volumes_balls, the parallelepipeds' paths) */
    int pp;         /* parallelepipeds at every vertex with a sampled direction */
    int pt;         /* parallelotopes likewise */
    int ball_yields_pp; /* the ball leaves the parallelepipeds' paths to them */
    int mis;        /* balls and parallelepipeds both, weighted (Liu et al. 2022 §4.6) */
    const char *summary;
    int plane;      /* 1: sliced photon planes, 2: 1-D-blurred planes, at every vertex with a sampled direction */
} slice_type_row;

static const slice_type_row types[] = {
    {VOLUME_PHOTON_BALLS, 1, 0, 0, 0, 0, "sliced balls at every non-delta light vertex, beams where x1 is a delta", 0},
    {VOLUME_PHOTON_VOLUMES, 0, 1, 0, 0, 0, "sliced parallelepipeds for paths whose x2, x1 scatter in a medium, beams elsewhere", 0},
    {VOLUME_PHOTON_HYPERVOLUMES, 0, 0, 1, 0, 0,
     "sliced parallelotopes for paths whose x3, x2, x1 scatter in a medium, beams elsewhere", 0},
    {VOLUME_PHOTON_VOLUMES_BALLS, 1, 1, 0, 1, 0,
     "sliced parallelepipeds where x2, x1 scatter in a medium, balls at the other non-delta x1, beams elsewhere", 0},
    {VOLUME_PHOTON_MIS_VOLUMES_BALLS, 1, 1, 0, 0, 1,
     "sliced balls and parallelepipeds, balance-heuristic MIS where both serve, beams where x1 is a delta", 0},
    {.type = VOLUME_PHOTON_PLANES, .plane = 1,
     .summary = "sliced photon planes (box gate analytic) for paths whose x1 scatters in a medium, beams elsewhere"},
    {.type = VOLUME_PHOTON_PLANES_1D, .plane = 2,
     .summary = "1-D-blurred photon planes (box gate analytic) for paths whose x1 scatters in a medium, beams "
                "elsewhere"},
};

static const slice_type_row *row_of(int type)
{
    for (size_t i = 0; i < sizeof types / sizeof *types; i++)
        if (types[i].type == type) return &types[i];
    return NULL;
}

int slice_type_builds(int type, int kind, unsigned f)
{
    const slice_type_row *r = row_of(type);
    if (!r) return 0;
    switch (kind) {
    case SLICE_BALL: return r->ball && ball_serves_x1(f) && !(r->ball_yields_pp && pp_serves_x1(f));
    case SLICE_PARALLELEPIPED: return r->pp;
    case SLICE_PARALLELOTOPE: return r->pt;
    case SLICE_PLANE: return r->plane == 1;
    case SLICE_PLANE_1D: return r->plane == 2;
    default: return 0;
    }
}

int slice_type_gathers_beam(int type, unsigned f)
{
    const slice_type_row *r = row_of(type);
    if (!r) return 1;
    int served = (r->ball && ball_serves_x1(f)) || (r->pp && pp_serves_x1(f)) || (r->pt && pt_serves_x1(f)) ||
                 (r->plane && plane_serves_x1(f));
    return !served;
}

int slice_type_plane(int type)
{
    const slice_type_row *r = row_of(type);
    return r ? r->plane : 0;
}

int slice_type_mis(int type)
{
    const slice_type_row *r = row_of(type);
    return r && r->mis;
}

const char *slice_type_summary(int type)
{
    const slice_type_row *r = row_of(type);
    return r ? r->summary : "";
}

int sliced_primitives_check(const scene *s, const render_plan *p, dp_error *err)
{
    if (p->type != INTEGRATOR_PHOTON_POINTS || !volume_type_sliced(p->volume_photon_type)) return 0;
    const scene_key *k = scene_key_find("volume_photon_type");
    const char *name = k ? k->choices[p->volume_photon_type] : "this type";
    /* a delta gate is refused for planes at load (src/scene/settings.c, delta_gate_refusal) */
    if (slice_type_plane(p->volume_photon_type) && (!p->window.gated || !(p->window.width > 0.0)))
        return dp_fail(err, "%s: integrator.transient_time_width: volume_photon_type %s integrates a box gate "
                       "analytically (Liu et al. 2022 §4.2: the gate is its 4th analytic dimension), so it needs a "
                       "gate of width > 0; steady state is not supported", s->path, name);
    if (!p->window.gated || !(p->window.width > 0.0))
        return dp_fail(err, "%s: integrator.volume_photon_type: %s slices the path space at a time in a gate: it "
                       "needs transient_time_width > 0 (steady state has no time to slice)", s->path, name);
    if (p->darts.active)
        return dp_fail(err, "%s: integrator.volume_photon_type: %s is built from the baseline photon pass: set "
                       "enable_guiding, enable_elliptical and eda to false (DARTS samplers and sliced primitives are "
                       "not combined)", s->path, name);
    if (!p->low_order_scattering)
        return dp_fail(err, "%s: integrator.low_order_scattering: false is not supported with volume_photon_type %s "
                       "(its primitives serve the first medium vertex's paths too)", s->path, name);
    /* the displaced segments are straight and evaluated by scene_transmittance, which stops at every surface
     * but null and forward ones: only those can carry a segment into a region of another speed */
    if (!scene_eta_uniform_along_segments(s))
        return dp_fail(err, "%s: integrator.volume_photon_type: %s solves the time constraint with one refractive "
                       "index along the displaced segments; a null or forward surface of this scene separates "
                       "regions of different speed_of_light", s->path, name);
    return 0;
}
