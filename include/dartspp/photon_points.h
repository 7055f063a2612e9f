/* dartspp photon_points: progressive photon points ("type": "progressive_transient_photon_map"), the
 * integrator the product is built around. One iteration drives the modules below it in order: the photon
 * pass (src/photon, with the DARTS samplers of src/darts), the photon maps built with the iteration's radii
 * (src/photon), the sensor pass that gathers them into the film (src/gather). Iterations are independent
 * draws; the driver (src/render) keeps their weighted mean (plan_pass_weight). */
#ifndef DARTSPP_PHOTON_POINTS_H
#define DARTSPP_PHOTON_POINTS_H

#include "dartspp/darts.h"
#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/photon_beams.h"
#include "dartspp/plan.h"
#include "dartspp/scene.h"

/* One iteration of photon points: photon pass, maps, sensor pass into f's pass layer; its figures (photon
 * paths, photons stored, radii, phase times) added to *st. Returns 0 or -1 with err. Once stop is set it
 * returns early with the pass incomplete (the caller drops it). */
int photon_points_pass(const scene *s, const render_plan *p, const eda_set *eda, film *f, uint64_t seed,
                       long iteration, const dp_stop_flag *stop, render_stats *st, dp_error *err);

/* What iteration i's film can count, for the beam map (beam_map_build): the latest time that counts
 * (plan_window_end) and the window's width (a delta gate's first width). */
beam_time_cut photon_points_beam_cut(const render_plan *p, long iteration);

/* The radii of the last of `passes` passes into st->r_vol and st->r_surf (the schedules depend on the pass index
 * only: the driver sets them once the ranks' figures are summed). */
void photon_points_last_radii(const render_plan *p, long passes, render_stats *st);

/* The memory of a pass at its peak (the memory guard): EDA tables, photon arrays at their budgets (capped by
 * a pilot batch's yield), their maps, the sensor pass's primary lines and splat, the batch buffers. */
void photon_points_memory(const scene *s, const render_plan *p, memory_estimate *m);

/* surface_paths "auto" (src/photon_points/chain_share.c, docs/defaults.md §3.9): whether plan p chooses its
 * chains' share by a pilot; the share for the pilot's surface and volume variances (both with every path);
 * and the pilot itself (saying so on messages, if not NULL), which sets p->chain_share (and st->chain_share,
 * pilot_ratio, t_pilot) from two independent draws of a pass with seed's own streams. Nothing when p does not
 * choose. 0, or -1 with err. */
int photon_points_auto_chains(const render_plan *p);
double photon_points_chain_share_rule(double v_surface, double v_volume);
int photon_points_choose_chain_share(const scene *s, render_plan *p, const eda_set *eda, uint64_t seed,
                                     const dp_stop_flag *stop, FILE *messages, render_stats *st, dp_error *err);

#endif
