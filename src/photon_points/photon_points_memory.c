/* What photon points hold at the peak of a pass (the memory guard, src/render/memory.c): everything of one
 * iteration is alive at once during the sensor pass — the photon sets' arrays at their capacity, both maps,
 * the primary lines and the splat's scratch, the EDA tables. How many photons a light path stores depends on
 * the scene (the DARTS time tests drop most surface photons), so a pilot batch of light paths measures it;
 * the budgets cap the extrapolation. */
#include "dartspp/gather.h"
#include "dartspp/photon.h"
#include "dartspp/photon_beams.h"
#include "dartspp/photon_points.h"
#include "dartspp/sliced_primitives.h"

/* One photon pass of a single batch of light paths (a few milliseconds), without EDA tables and without
 * budget cuts: how many volume and surface photons a light path stores, and a sample of the volume photons
 * for the splat's footprints. *chains: the render's passes will feed the surface map by surface chains once
 * the volume budget is full, which the pilot never is. Returns 0 on failure (then the budgets count). */
static int pilot_pass(const scene *s, const render_plan *p, photon_set *ps, int *chains)
{
    photon_pass_input pilot;
    photon_pass_input_init(&pilot, s, p, NULL, 0x70696c6f74ULL, 0, NULL);
    *chains = photon_pass_uses_chains(&pilot);
    pilot.light_paths = dp_fmin(p->photon_count, PHOTON_PASS_BATCH);
    pilot.volume_budget = pilot.surface_budget = pilot.light_paths * 1e4; /* no budget cut */
    dp_error err;
    if (photon_pass(s, &pilot, ps, &err)) return 0;
    if (ps->paths > 0) return 1;
    photon_set_free(ps);
    return 0;
}

/* Photon points: the EDA tables, the photon arrays at their budgets (capped by a pilot batch's yield), their
 * maps, the sensor pass's primary lines and splat, and the batch buffers. */
void photon_points_memory(const scene *s, const render_plan *p, memory_estimate *m)
{
    memory_item_add(m, "EDA tables", "integrator.eda_shape", (double)eda_set_bytes(s, &p->darts));
    if (photon_points_auto_chains(p)) { /* chain_share.c: a film of its own and four gate images, beside the render's */
        double px = (double)s->cam.width * s->cam.height;
        int layers = time_window_layers(&p->window);
        memory_item_add(m, "surface_paths auto: the pilot's film and images", "integrator.surface_paths",
                        2 * px * 3 * sizeof(double) + 2 * px * 3 * (double)layers * sizeof(float) +
                            4 * px * 3 * sizeof(float));
    }
    double V = p->volume_photon_count, S = p->photon_count, batch_photons = 1.0, batch_beams = 0.0, batch_verts = 0.0;
    photon_set pilot;
    int chains, piloted = pilot_pass(s, p, &pilot, &chains);
    /* the budgets cap what the light paths store; surface chains start once the volume budget is full, which
     * the pilot's single batch never sees, and can fill the surface budget: counted full */
    if (piloted) {
        V = dp_fmin(V, (double)(pilot.n_vol + pilot.n_beams) / pilot.paths * p->photon_count);
        if (!chains) S = dp_fmin(S, (double)pilot.n_surf / pilot.paths * p->photon_count);
        batch_photons = dp_fmax((double)(pilot.n_vol + pilot.n_surf) / pilot.paths * PHOTON_PASS_BATCH, 1.0);
        batch_beams = (double)pilot.n_beams / pilot.paths * PHOTON_PASS_BATCH;
        batch_verts = (double)pilot.n_verts / pilot.paths * PHOTON_PASS_BATCH; /* sliced types' vertices */
    }
    /* each set's array at its capacity, and its map: volume_map_bytes is about (16 + 56) B a photon, 16 B of
     * build scratch and the nodes (the surface map is the same tree); in double for huge budgets */
    double per_mapped = (double)volume_map_bytes(1 << 20) / (1 << 20);
    int volume = s->medium_count > 0, beams = p->volume_photon_type != VOLUME_PHOTON_POINTS;
    int sliced = volume_type_sliced(p->volume_photon_type);
    double V_beams = V; /* sliced types: V counts vertices, and their paths' beams come with them */
    if (sliced && piloted) {
        V = dp_fmin(p->volume_photon_count, (double)pilot.n_verts / pilot.paths * p->photon_count);
        V_beams = pilot.n_verts ? V * (double)pilot.n_beams / (double)pilot.n_verts : 0.0;
    }
    if (volume && sliced) sliced_primitives_memory(p->volume_photon_type, V, m);
    if (volume && beams) /* beams: no volume photons, and the sensor pass queries the beam map per segment */
    {
        beam_time_cut cut = photon_points_beam_cut(p, 0); /* the widest: later ends are earlier */
        photon_beams_memory(piloted ? pilot.beams : NULL, piloted ? pilot.n_beams : 0, schedule_radius(&p->r_vol, 0),
                            &cut, V_beams, m);
    }
    if (volume && !beams)
        memory_item_add(m, "volume photons and their map", "integrator.volume_photon_count", photon_array_bytes(V) + V * per_mapped);
    if (volume && !beams) /* the first pass's radius is the largest: the most footprint entries */
        memory_item_add(m, "primary lines and splat of the sensor pass", "camera.resolution",
            gather_pass_bytes(s, p->volume_gather == VOLUME_GATHER_SPLAT, piloted ? pilot.vol : NULL, piloted ? pilot.n_vol : 0,
                              schedule_radius(&p->r_vol, 0), V));
    if (p->include_surfaces || !volume)
        memory_item_add(m, "surface photons and their map", "integrator.photon_count", photon_array_bytes(S) + S * per_mapped);
    if (deriv_on(&p->deriv)) /* the photons' derivative records (docs/derivatives.md §4), at the arrays' capacity */
        memory_item_add(m, "photon derivative records", "--derivative",
                        (photon_array_bytes(volume && !beams ? V : 0.0) + photon_array_bytes(p->include_surfaces || !volume ? S : 0.0) +
                         photon_array_bytes(batch_photons)) / sizeof(photon) * (double)photon_deriv_stride(p->deriv.count));
    memory_item_add(m, "photon batch buffers", NULL, photon_array_bytes(batch_photons) + photon_beam_array_bytes(batch_beams) +
                    path_vertex_array_bytes(batch_verts));
    if (piloted) photon_set_free(&pilot);
}
