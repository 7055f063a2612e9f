/* Progressive photon points, one iteration: photon pass → photon maps (radii of this iteration) →
 * sensor pass → film. Iterations are independent draws; the film keeps their mean. */
#include "dartspp/gather.h"
#include "dartspp/photon_beams.h"
#include "dartspp/photon_points.h"
#include "dartspp/sliced_primitives.h"

void photon_points_last_radii(const render_plan *p, long passes, render_stats *st)
{
    if (passes <= 0) return;
    st->r_vol = schedule_radius(&p->r_vol, passes - 1);
    st->r_surf = schedule_radius(&p->r_surf, passes - 1);
    st->w_gate = p->window.delta ? plan_gate_width(p, passes - 1) : 0.0;
}

beam_time_cut photon_points_beam_cut(const render_plan *p, long iteration)
{
    if (!p->window.gated) return (beam_time_cut){INFINITY, 0.0};
    /* pieces by the first (widest) box of a delta gate: their count then never grows over the iterations, and
     * the memory guard's estimate from iteration 0 holds */
    return (beam_time_cut){plan_window_end(p, iteration), p->window.width};
}

int photon_points_pass(const scene *s, const render_plan *p, const eda_set *eda, film *f, uint64_t seed,
                       long iteration, const dp_stop_flag *stop, render_stats *st, dp_error *err)
{
    photon_set ps;
    photon_pass_input pin;
    photon_pass_input_init(&pin, s, p, eda, seed, iteration, stop);
    gather_input g = {.k_surf = p->gather_photon_count, .surface_direct = p->surface_direct,
                      .row_step = p->sensor_row_step, .eta_lb = p->darts.eta_lb, .eta_ub = p->darts.eta_ub,
                      .bounces = p->bounces, .shading = p->shading,
                      .camera_leg_projected = p->camera_leg == CAMERA_LEG_PROJECTED, .camera_unwarp = p->window.camera_unwarp,
                      .volume_splat = p->volume_gather == VOLUME_GATHER_SPLAT,
                      .stop = stop, .r_vol = schedule_radius(&p->r_vol, iteration),
                      .r_surf = schedule_radius(&p->r_surf, iteration),
                      .alpha_reg = plan_glossy_regularization(p, iteration)};
    film_set_pass_gate(f, plan_gate_width(p, iteration)); /* a delta gate's kernel K_τ of this iteration */
    double t0 = dp_seconds();
    if (photon_pass(s, &pin, &ps, err)) return -1;
    if (ps.interrupted) { /* the iteration is dropped: no maps, no sensor pass */
        photon_set_free(&ps);
        return 0;
    }
    double t1 = dp_seconds();
    volume_photon_map *vm = NULL;
    surface_photon_map *sm = NULL;
    beam_map *bm = NULL; /* volume_photon_type "beams": the pass kept beams instead of volume photons */
    beam_gather bg = {.r = g.r_vol, .bounces = p->bounces, .camera_unwarp = p->window.camera_unwarp};
    int sliced = volume_type_sliced(p->volume_photon_type);
    if (sliced) bg.keep = slice_type_gathers_beam, bg.keep_type = p->volume_photon_type; /* beams where no primitive serves */
    slice_map *slm = NULL; /* a sliced volume_photon_type: the primitives built from the pass's vertices */
    slice_gather sg = {.type = p->volume_photon_type, .bounces = p->bounces, .shading = p->shading,
                       .camera_unwarp = p->window.camera_unwarp, .r = g.r_vol};
    slice_build_input sbi = {.type = p->volume_photon_type, .window = p->window, .seed = seed, .iteration = iteration,
                             .r = g.r_vol};
    int rc = 0;
    if (ps.n_vol > 0 && !(vm = volume_map_build(ps.vol, ps.n_vol, g.r_vol, err))) rc = -1;
    beam_time_cut cut = photon_points_beam_cut(p, iteration);
    if (!rc && ps.n_beams > 0 && !(bm = beam_map_build(ps.beams, ps.n_beams, g.r_vol, &cut, err))) rc = -1;
    if (!rc && sliced && !(slm = slice_map_build(s, &sbi, ps.verts, ps.n_verts, err))) rc = -1;
    if (!rc && ps.n_surf > 0 && !(sm = surface_map_build(ps.surf, ps.n_surf, err))) rc = -1;
    double t2 = dp_seconds();
    if (!rc) {
        g.vol = p->sensor_parts & SENSOR_VOLUME ? vm : NULL;
        g.surf = p->sensor_parts & SENSOR_SURFACE ? sm : NULL;
        if (!(p->sensor_parts & SENSOR_SURFACE)) g.surface_direct = 0;
        g.surf_photons = ps.surf;
        g.vol_photons = ps.vol;
        g.n_vol = ps.n_vol;
        g.deriv = pin.deriv; /* derivatives: the photons' records beside them (docs/derivatives.md §4) */
        g.vol_deriv = ps.vol_deriv;
        g.surf_deriv = ps.surf_deriv;
        g.deriv_stride = ps.deriv_stride;
        bg.map = bm;
        g.beams = bm ? &bg : NULL;
        sg.map = slm;
        g.slices = slm ? &sg : NULL;
        render_stats pass = {.rays = gather_pass(s, &g, f, seed, iteration),
                             .photon_paths = (double)ps.paths,
                             .early_exits = (double)ps.early_exits,
                             .aimed_paths = (double)ps.aimed_paths,
                             .chain_paths = (double)ps.chain.traced,
                             .chain_large = (double)ps.chain.large,
                             .chain_visible = (double)ps.chain.visible,
                             .chain_small = (double)ps.chain.small,
                             .chain_accepted = (double)ps.chain.accepted,
                             .stored_photons = (double)(ps.n_vol + ps.n_surf + ps.n_beams + slice_map_size(slm)),
                             .r_vol = g.r_vol,
                             .r_surf = g.r_surf,
                             .w_gate = p->window.delta ? f->window.width : 0.0,
                             .t_photon = t1 - t0,
                             .t_maps = t2 - t1};
        pass.t_gather = dp_seconds() - t2;
        f->nonfinite += ps.nonfinite;
        render_stats_add(st, &pass);
    }
    volume_map_free(vm);
    beam_map_free(bm);
    slice_map_free(slm);
    surface_map_free(sm);
    photon_set_free(&ps);
    return rc;
}
