/* dartspp photon_beams: progressive transient photon beams (volume_photon_type "beams"; Marco et al. 2019 as
 * Liu et al. 2022 reproduced them, with the DARTS authors' camera-warped time). The photon pass
 * (src/photon, photon_pass_input.beams) keeps the medium segments of its light paths as short beams
 * (photon_beam, include/dartspp/photon.h); this module builds a BVH over them each iteration and evaluates
 * the 1-D beam × camera-ray kernel along the sensor pass's medium segments (src/gather). The rest of the
 * iteration — surface photons, the camera walk, the film — is photon points' (src/photon_points). */
#ifndef DARTSPP_PHOTON_BEAMS_H
#define DARTSPP_PHOTON_BEAMS_H

#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/photon.h"
#include "dartspp/plan.h"

typedef struct beam_map beam_map;

/* What the film can count, for the build to leave out or cut finer: `end`, the latest path time that counts
 * (the gate's end, the last frame's, a delta gate's box of this iteration; INFINITY: steady), and `width`, the
 * narrowest window (the gate's or a frame's width; 0: none). */
typedef struct {
    double end, width;
} beam_time_cut;

/* A BVH over the n beams (copied), each box inflated by the radius r >= 0 of this iteration. With tc (NULL:
 * none), the parts of beams beyond tc->end are left out (their points' path times are past it whatever the
 * camera adds) and the pieces' own time ranges are at most four window widths, so that the nodes' time ranges
 * prune a narrow gate. NULL + err on failure (out of memory). */
beam_map *beam_map_build(const photon_beam *b, size_t n, double r, const beam_time_cut *tc, dp_error *err);
void beam_map_free(beam_map *m);
size_t beam_map_size(const beam_map *m);
/* Bytes beam_map_build allocates at its peak for n beams cut into `pieces` pieces (the memory guard). */
double beam_map_bytes(double n, double pieces);
/* How many pieces beam_map_build cuts the n beams into at radius r (long beams are cut so that their boxes
 * stay tight). */
double beam_map_pieces(const photon_beam *b, size_t n, double r, const beam_time_cut *tc);

/* A time window on a query: a point s along beam b seen at t along the camera line has the path time
 * t0 + b->time + η_b·s + eta·t (η_b its medium's), and only times in [lo, hi) count. */
typedef struct {
    double t0, eta, lo, hi;
} beam_window;

/* Called for every beam b whose line passes within the map's r of the camera line o + t·d (d unit) with the
 * closest points at t in [0, tmax] on the camera line and s in [0, b->length] on the beam; inv_sin = 1/sinθ
 * of the angle between the two. With a window w (or NULL: none), subtrees and beams none of whose points can
 * have a time in it are skipped: bounds from the nodes' time ranges and the slab interval of the camera line
 * through their boxes, widened by 1e-9 relative, so the caller still tests each time and never misses one.
 * Visit order is fixed by the map, so results are deterministic. */
typedef void (*beam_hit_fn)(void *ctx, const photon_beam *b, double t, double s, double inv_sin);
void beam_map_query(const beam_map *m, vec3 o, vec3 d, double tmax, const beam_window *w, beam_hit_fn hit, void *ctx);

/* What the 1-D kernel needs besides the camera segment. */
typedef struct {
    const beam_map *map;
    double r;                 /* kernel half-width of this iteration (the map's r) */
    bounce_limits bounces;    /* which light + camera paths count */
    int camera_unwarp;        /* the camera segment adjacent to the sensor takes no time (docs/time.md §2.2) */
    /* the sliced primitives' fallback (src/sliced_primitives): only the beams keep(keep_type, b->from) accepts;
     * NULL: every beam */
    int (*keep)(int keep_type, unsigned start);
    int keep_type;
} beam_gather;

/* The 1-D beam × camera-ray estimate (Jarosz et al. 2011, "beam × beam 1D"; docs/beams.md §1) of
 * the camera segment o + t·d, 0 <= t <= len, in medium med (thr and t_cam at o, b_cam camera segments):
 * for every beam within r, box kernel 1/(2r), σs·f_p(ω_b → −d)·T_cam(t)·power·T_b(s)/P_b(s) / sinθ,
 * at the path time t_cam + beam time + η·s + η·t (camera-warped; the sensor's own segment takes no time when
 * unwarped), into the film's slot of that time (box gate and frames). */
void photon_beams_gather(const beam_gather *g, const scene *s, film_pixel *pix, int med, vec3 o, vec3 d, double len,
                         vec3 thr, double t_cam, int b_cam);

/* The memory guard's item of the volume part of a beams iteration: V beams (their budget, capped by the
 * caller's pilot) and their BVH at the first (widest) radius r0, with as many pieces per beam as the pilot's n
 * beams (none: one each). */
void photon_beams_memory(const photon_beam *pilot, size_t n, double r0, const beam_time_cut *tc, double V,
                         memory_estimate *m);

#endif
