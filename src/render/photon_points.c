/* Progressive photon points, one iteration: photon pass → photon maps (radii of this iteration) →
 * sensor pass → film. Iterations are independent draws; the film keeps their mean. */
#include "dartspp/gather.h"
#include "dartspp/render.h"

double progressive_radius(double r0, double alpha, long iteration, int dims)
{
    double log_ratio = 0.0;
    for (long j = 1; j <= iteration; j++) log_ratio += log((j + alpha) / (j + 1.0));
    return r0 * exp(log_ratio / dims);
}

int photon_points_pass(const scene *s, const struct eda_set *eda, film *f, uint64_t seed, long iteration,
                       const dp_stop_flag *stop, render_stats *st, dp_error *err)
{
    const integrator_settings *in = &s->integrator;
    photon_set ps;
    gather_input g = {.k_surf = in->gather_photon_count, .camera_leg_projected = in->camera_leg_projected,
                      .stop = stop};
    g.r_vol = progressive_radius(in->volume_gather_radius, in->volume_alpha, iteration, in->radius_schedule_3d ? 3 : 2);
    g.r_surf = progressive_radius(in->gather_radius, in->alpha, iteration, 2);
    double t0 = dp_seconds();
    if (photon_pass(s, eda, seed, iteration, g.r_surf, stop, &ps, err)) return -1;
    if (ps.interrupted) { /* the iteration is dropped: no maps, no sensor pass */
        photon_set_free(&ps);
        return 0;
    }
    double t1 = dp_seconds();
    volume_photon_map *vm = NULL;
    surface_photon_map *sm = NULL;
    int rc = 0;
    if (ps.n_vol > 0 && !(vm = volume_map_build(ps.vol, ps.n_vol, g.r_vol, err))) rc = -1;
    if (!rc && ps.n_surf > 0 && !(sm = surface_map_build(ps.surf, ps.n_surf, err))) rc = -1;
    double t2 = dp_seconds();
    if (!rc) {
        g.vol = vm;
        g.surf = sm;
        g.surf_photons = ps.surf;
        st->rays += sensor_pass(s, &g, f, seed, iteration, &f->nonfinite);
        st->photon_paths += (double)ps.paths;
        st->early_exits += (double)ps.early_exits;
        st->aimed_paths += (double)ps.aimed_paths;
        st->stored_photons += (double)(ps.n_vol + ps.n_surf);
        st->r_vol = g.r_vol;
        st->r_surf = g.r_surf;
        f->nonfinite += ps.nonfinite;
        st->t_photon += t1 - t0;
        st->t_maps += t2 - t1;
        st->t_gather += dp_seconds() - t2;
    }
    volume_map_free(vm);
    surface_map_free(sm);
    photon_set_free(&ps);
    return rc;
}
