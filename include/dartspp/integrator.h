/* dartspp integrator: what every integrator shares with the driver (src/render) that runs it — the figures a
 * pass reports (render_stats, declared once in RENDER_FIGURES) and the items of memory it needs. Below the
 * integrators (src/path_tracer, src/photon_points) and the driver, so that neither includes the other. */
#ifndef DARTSPP_INTEGRATOR_H
#define DARTSPP_INTEGRATOR_H

#include <stddef.h>

/* ---- per-pass figures ---- */
/* The figures of a render, declared once: X(type, name, how, api, what) each. From this list come the fields
 * of render_stats, the summing of a photon pass's figures (render_stats_add), the sum over ranks of the MPI
 * reduction (render_stats_pack) and the embedding API's figures (api.h; the Python package's Result.stats).
 *   how: RENDER_SUM   adds up: over the passes (render_stats_add) and over the ranks
 *        RENDER_LAST  the last pass's value (render_stats_add replaces it); over the ranks rank 0's
 *        RENDER_MAX   over the ranks the largest; render_stats_add keeps the larger
 *        RENDER_KEPT  the driver's own: render_stats_add leaves it; over the ranks rank 0's
 *   api: 1 when the embedding API returns it (dp_render_result.stats, in this order).
 * A new figure: one line here, and the line that measures it. */
#define RENDER_FIGURES(X)                                                                                              \
    X(double, camera_rays, RENDER_SUM, 1, "primary rays traced")                                                       \
    X(double, rays, RENDER_SUM, 1, "all rays traced (primary, bounce, shadow)")                                        \
    X(double, photon_paths, RENDER_SUM, 1, "light paths traced (photon points)")                                       \
    X(double, stored_photons, RENDER_SUM, 1, "volume + surface photons stored, summed over iterations")                \
    X(double, r_vol, RENDER_LAST, 1, "the volume radius of the last iteration")                                        \
    X(double, r_surf, RENDER_LAST, 1, "the surface radius of the last iteration")                                      \
    X(double, w_gate, RENDER_LAST, 1, "a delta gate's temporal kernel width of the last iteration (0: none)")         \
    X(double, t_photon, RENDER_SUM, 1, "seconds spent in the photon pass")                                             \
    X(double, t_maps, RENDER_SUM, 1, "seconds spent in the map builds")                                                \
    X(double, t_gather, RENDER_SUM, 1, "seconds spent in the sensor pass")                                             \
    X(long, nonfinite_pixels, RENDER_KEPT, 1, "pixels of the images not finite at the end, written as 0 "              \
      "(film_nonfinite_pixels)")                                                                                       \
    X(long, amcw_dark_pixels, RENDER_KEPT, 1, "AMCW: pixels without signal at the depth's frequencies, their "          \
      "amcw_depth written as 0 (film_amcw_depth)")                                                                     \
    X(long, passes, RENDER_KEPT, 0, "passes completed (the film's count)")                                             \
    X(long, resumed_passes, RENDER_KEPT, 0, "of them, held by the film resumed (render_options.resume)")               \
    X(double, seconds, RENDER_KEPT, 0, "render time")                                                                  \
    X(long, nonfinite, RENDER_KEPT, 0, "non-finite contributions dropped (the film's count)")                          \
    X(int, interrupted, RENDER_MAX, 0, "the stop flag ended the render")                                               \
    X(double, early_exits, RENDER_SUM, 0, "light paths ended by the DARTS early exit")                                 \
    X(double, aimed_paths, RENDER_SUM, 0, "light paths traced with the DARTS samplers "                                \
      "(the rest: surface photons only)")                                                                              \
    X(double, chain_paths, RENDER_SUM, 0, "surface chains (photon.h): light paths traced by chains")                   \
    X(double, chain_large, RENDER_SUM, 0, "surface chains: independent (large) steps")                                 \
    X(double, chain_visible, RENDER_SUM, 0, "surface chains: large steps that stored a surface photon "                \
      "that can count")                                                                                                \
    X(double, chain_small, RENDER_SUM, 0, "surface chains: small steps proposed")                                      \
    X(double, chain_accepted, RENDER_SUM, 0, "surface chains: small steps accepted")                                   \
    X(double, chain_share, RENDER_KEPT, 0, "surface_paths auto: the share of the light paths left once the volume "   \
      "budget is full that the chains trace (0: not chosen, all)")                                                    \
    X(double, pilot_ratio, RENDER_KEPT, 0, "surface_paths auto: the pilot's surface variance over its volume "        \
      "variance, both at every path")                                                                                  \
    X(double, t_pilot, RENDER_KEPT, 0, "surface_paths auto: seconds of the pilot")                                    \
    X(double, t_cluster, RENDER_KEPT, 0, "several ranks: rank 0's seconds in the rounds' agreement "                   \
      "and the reductions")                                                                                            \
    X(long, reductions, RENDER_KEPT, 0, "several ranks: film reductions onto rank 0 "                                  \
      "(checkpoints, log rows, the end)")                                                                              \
    X(long, dropped, RENDER_SUM, 0, "several ranks: passes dropped unfinished (interrupt, error), "                    \
      "summed over the ranks by a reduction; 0 means the film holds "                                                  \
      "iterations 0..passes-1 exactly")

typedef enum { RENDER_SUM, RENDER_LAST, RENDER_MAX, RENDER_KEPT } render_combine;

typedef struct render_stats {
#define RENDER_FIGURE_FIELD(type, name, how, api, what) type name;
    RENDER_FIGURES(RENDER_FIGURE_FIELD)
#undef RENDER_FIGURE_FIELD
} render_stats;

/* One entry of RENDER_FIGURES: where the figure lies in render_stats and what it holds. */
typedef enum { RENDER_FIGURE_DOUBLE, RENDER_FIGURE_LONG, RENDER_FIGURE_INT } render_figure_type;
typedef struct {
    const char *name;        /* the field's name, also the API's (and the Python stats dict's) key */
    size_t offset;           /* in render_stats */
    render_figure_type type;
    render_combine how;
    int api;
    const char *what;
} render_figure;

#define RENDER_FIGURE_ONE(type, name, how, api, what) +1
enum { RENDER_FIGURE_COUNT = 0 RENDER_FIGURES(RENDER_FIGURE_ONE) };
#undef RENDER_FIGURE_ONE
extern const render_figure render_figures[RENDER_FIGURE_COUNT]; /* in the order of RENDER_FIGURES */

/* A figure's value as a double, and its setting from one (rounded toward zero for the integer figures). */
double render_figure_get(const render_stats *st, const render_figure *fg);
void render_figure_set(render_stats *st, const render_figure *fg, double v);
/* A pass's figures into the run's: RENDER_SUM added, RENDER_LAST replaced, RENDER_MAX the larger, RENDER_KEPT
 * left as they are. */
void render_stats_add(render_stats *st, const render_stats *pass);
/* The figures combined as `how` into v (at most RENDER_FIGURE_COUNT doubles, in the table's order); returns
 * how many. render_stats_unpack sets them back from v: the MPI reduction sums (and maxes) them between. */
int render_stats_pack(const render_stats *st, render_combine how, double *v);
void render_stats_unpack(render_stats *st, render_combine how, const double *v);

/* ---- memory items ----
 * What a render will hold at its peak, item by item, each with the scene key that drives it (or NULL): the
 * driver counts the scene and the film (render_memory_estimate, render.h), each integrator what it adds. */
#define MEMORY_ITEMS_MAX 16
typedef struct {
    const char *what;  /* e.g. "surface photons and their map" */
    const char *key;   /* e.g. "integrator.photon_count"; NULL for fixed costs */
    double bytes;
} memory_item;

typedef struct {
    memory_item item[MEMORY_ITEMS_MAX];
    int count;
    double total;      /* bytes */
} memory_estimate;
/* Adds an item (the first MEMORY_ITEMS_MAX are kept by name; every item counts in the total). */
void memory_item_add(memory_estimate *m, const char *what, const char *key, double bytes);

#endif
