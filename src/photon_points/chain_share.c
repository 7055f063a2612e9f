/* surface_paths "auto": how many of the light paths left once the volume budget is full the surface chains
 * trace (docs/defaults.md §3.9).
 *
 * A pass's variance is V = V_v + V_s, the volume estimate's and the surface estimate's, and its time
 * C = C_r + C_s, the chains' C_s and the rest C_r. The surface photons come from the chains, so with a share
 * q of the paths V_s(q) = V_s(1)/q and C_s(q) = q·C_s(1), and the error after a given time, V·C, is least at
 *   q* = sqrt((V_s(1)/V_v)·(C_r/C_s(1))).
 * The variances come from a pilot: two independent draws of a pass, each rendered as its surface estimate
 * alone and its volume estimate alone; half the mean squared difference of the two draws' images is each
 * estimate's variance (chain photons are correlated, and a difference of draws sees that where a sum of
 * squared contributions would not). The times are not measured: they would make the images depend on the
 * machine's load. We take C_r = C_s(1), which the three paper scenes bracket (C_r/C_s about 0.8 on the fog
 * box, 0.9 on the staircase, 2.4 on the dragon, from their phase times); the error is flat near q*, so a
 * factor of two in C_r/C_s costs little. The surface image also holds what does not scale with q (the
 * direct connections, the surface photons of the paths before the volume budget filled): small on those
 * scenes. The pilot's streams are its own (PILOT_KEY), so every pass stays an independent draw given q, and
 * q depends only on the scene, the plan and the seed: the same for every rank, thread count and resume.
 * Written here: no library chooses photon budgets. */
#include <math.h>
#include <stdlib.h>

#include "dartspp/io.h"
#include "dartspp/photon_points.h"

#define PILOT_KEY 0x70696c6f74ULL /* "pilot" */
#define PILOT_SHARE 0.25          /* the pilot's chains trace this share; their variance is scaled to all */
#define PILOT_NO_CHAINS 1e-9      /* the volume draws need no surface photons: their chains trace one path */
#define PILOT_ROW_STEP 4          /* its sensor passes sample every 4th row: both variances by the same rows */
#define CHAIN_SHARE_MIN (1.0 / 16)

int photon_points_auto_chains(const render_plan *p)
{
    return p->type == INTEGRATOR_PHOTON_POINTS && p->surface_paths == SURFACE_PATHS_AUTO && p->darts.active &&
           p->surface_chains && p->include_surfaces && p->volume_photon_type == VOLUME_PHOTON_POINTS &&
           !deriv_on(&p->deriv);
}

double photon_points_chain_share_rule(double v_surface, double v_volume)
{
    if (!(v_volume > 0.0)) return 1.0;
    double q = sqrt(v_surface / v_volume);
    return q >= 1.0 ? 1.0 : q > CHAIN_SHARE_MIN ? q : CHAIN_SHARE_MIN;
}

/* One part (SENSOR_SURFACE or SENSOR_VOLUME) of pilot draw k as an image. */
static int pilot_image(const scene *s, const render_plan *p, int part, const eda_set *eda, uint64_t seed, long k,
                       const dp_stop_flag *stop, image_rgb *img, dp_error *err)
{
    render_plan q = *p; /* read only: its arrays stay p's */
    q.sensor_parts = part;
    q.sensor_row_step = PILOT_ROW_STEP;
    q.chain_share = part == SENSOR_SURFACE ? PILOT_SHARE : PILOT_NO_CHAINS;
    film f;
    render_stats st = {0};
    if (film_init(&f, s->cam.width, s->cam.height, &p->window, err)) return -1;
    /* draw k: a seed of its own, hashed from (seed, k) so that no two seeds share a draw; the radii of
     * iteration 0 (both draws estimate the same pass) */
    dp_rng r = rng_stream(seed, PILOT_KEY, (uint64_t)k);
    int rc = photon_points_pass(s, &q, eda, &f, rng_next_u64(&r), 0, stop, &st, err);
    if (!rc) {
        film_commit_pass(&f, 1.0);
        rc = film_image(&f, -1, img, err);
    }
    film_free(&f);
    return rc;
}

/* Half the mean squared difference of two images: the variance of one. */
static double half_msd(const image_rgb *a, const image_rgb *b)
{
    size_t n = (size_t)a->width * a->height * 3;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)a->rgb[i] - (double)b->rgb[i];
        sum += d * d;
    }
    return n ? 0.5 * sum / (double)n : 0.0;
}

int photon_points_choose_chain_share(const scene *s, render_plan *p, const eda_set *eda, uint64_t seed,
                                     const dp_stop_flag *stop, FILE *messages, render_stats *st, dp_error *err)
{
    if (!photon_points_auto_chains(p)) return 0;
    if (messages) fprintf(messages, "surface_paths auto: a pilot of two draws chooses the surface chains' share\n");
    double t0 = dp_seconds();
    image_rgb im[2][2] = {{{0}}}; /* [draw][surface, volume] */
    int rc = 0;
    for (int k = 0; k < 2 && !rc; k++)
        rc = pilot_image(s, p, SENSOR_SURFACE, eda, seed, k, stop, &im[k][0], err) ||
             pilot_image(s, p, SENSOR_VOLUME, eda, seed, k, stop, &im[k][1], err);
    if (!rc && !dp_stopped(stop)) {
        double v_surface = half_msd(&im[0][0], &im[1][0]) * PILOT_SHARE, v_volume = half_msd(&im[0][1], &im[1][1]);
        p->chain_share = photon_points_chain_share_rule(v_surface, v_volume);
        st->chain_share = p->chain_share;
        st->pilot_ratio = v_volume > 0.0 ? v_surface / v_volume : INFINITY;
    }
    st->t_pilot = dp_seconds() - t0;
    for (int k = 0; k < 2; k++) image_free(&im[k][0]), image_free(&im[k][1]);
    return rc ? -1 : 0;
}
