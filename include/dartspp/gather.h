/* dartspp gather: the sensor pass of photon points. One jittered camera ray per pixel, walked through
 * null and forward surfaces and continued through specular and near-specular lobes by sampling them; along
 * every medium segment the point-beam 2D estimator (biweight kernel) over the volume photons; at surface
 * hits the surface estimate over the gathered lobes (k nearest within R, box kernel), by the rule of
 * surface_photon_split; camera-warped time for every photon, or camera-unwarped (camera_unwarp: the camera
 * segment adjacent to the sensor left out); box gate and frames through the film. */
#ifndef DARTSPP_GATHER_H
#define DARTSPP_GATHER_H

#include "dartspp/film.h"
#include "dartspp/photon.h"
#include "dartspp/photon_beams.h"
#include "dartspp/plan.h"
#include "dartspp/sliced_primitives.h"

typedef struct {
    const volume_photon_map *vol;   /* may be NULL */
    const beam_gather *beams;       /* volume_photon_type "beams": the 1-D beam kernel along every medium
                                     * segment instead of volume photons (vol NULL), or NULL */
    const slice_gather *slices;     /* a sliced volume_photon_type: the primitives along every medium segment (with
                                     * `beams` for the paths they do not serve), or NULL */
    const surface_photon_map *surf; /* may be NULL */
    const photon *surf_photons;     /* the array the surface map was built over */
    const photon *vol_photons;      /* the array the volume map was built over (the splat reads it) */
    size_t n_vol;
    int volume_splat;               /* volume_gather "splat": the primary lines' medium segments gathered
                                     * photon by photon (src/gather/volume_splat.c); 0 ("beam"): a beam
                                     * query per segment */
    double r_vol;                   /* volume gather radius of this iteration */
    double r_surf;                  /* surface search radius R of this iteration */
    double alpha_reg;               /* light connections at camera vertices after a glossy bounce evaluate
                                     * microfacet lobes with α at least this (docs/defaults.md §3.7); 0: off */
    int k_surf;                     /* gather_photon_count */
    int row_step;                   /* 0 or 1: every row; k: only the rows y % k == 0 (a pilot's subsample) */
    double eta_lb, eta_ub;          /* the scene's smallest and largest refractive index (darts_plan): a
                                     * straight light connection's time bounds; 0: unknown, every connection
                                     * traced */
    int surface_direct;             /* surface_direct_connections: at gathered lobes, the lights that
                                     * emitter_connects_exactly are connected (the photon pass stored no
                                     * first-bounce photon of theirs) */
    bounce_limits bounces;          /* which light + camera paths count */
    surface_shading shading;        /* BSDF frames and the gather/continue split (same as the photon pass) */
    int camera_leg_projected;       /* 0: Euclidean distance segment origin → photon (reference) */
    int camera_unwarp;              /* the camera segment adjacent to the sensor takes no time (docs/time.md §2.2) */
    /* derivatives (docs/derivatives.md §4): the render's, or NULL; then the photons' photon_deriv records, in
     * the order of vol_photons and surf_photons (a volume map visits its own order: volume_map_source) */
    const deriv_plan *deriv;
    const unsigned char *vol_deriv, *surf_deriv;
    size_t deriv_stride;
    const dp_stop_flag *stop;       /* rows not started once it is set are skipped (may be NULL) */
} gather_input;

/* Adds one camera sample per pixel to f's pass layer (pixel p of iteration i uses rng_stream(seed, i, p));
 * once g->stop is set the remaining rows are skipped and the pass is incomplete (the caller drops it).
 * Returns the rays traced; non-finite contributions are dropped and counted in f->nonfinite. */
double gather_pass(const scene *s, const gather_input *g, film *f, uint64_t seed, long iteration);

/* Whether the photon-by-photon volume gather (volume_gather "splat", src/gather/volume_splat.c) serves the
 * primary lines of a pass over s with g: volume photons in g and a camera with an orthonormal frame; otherwise the sensor pass gathers every segment by beam queries. Public so that a caller (and
 * tests/photon_points/test_volume_splat.c) can tell which of the two ways a pass takes. */
int volume_splat_applies(const scene *s, const gather_input *g);

/* Bytes the sensor pass allocates when the scene has a volume map: its primary lines and, with the splat
 * (volume_gather "splat"), the splat's scratch for `photons` volume photons at radius r, estimated from a
 * sample of n of them (the memory guard). */
double gather_pass_bytes(const scene *s, int splat, const photon *sample, size_t n, double r, double photons);

#endif
