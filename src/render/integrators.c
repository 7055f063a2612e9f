/* The table of integrators (integrators.h): one row per integrator type. */
#include "dartspp/path_tracer.h"
#include "dartspp/photon_points.h"
#include "integrators.h"

static const integrator_entry table[INTEGRATOR_COUNT] = {
    [INTEGRATOR_PATH_TRACER] = {.type = INTEGRATOR_PATH_TRACER,
                                .pass = path_tracer_pass,
                                .print_method = summary_print_path_method,
                                .light_technique = summary_path_tracer_light,
                                .warn = warn_path_tracer},
    [INTEGRATOR_PHOTON_POINTS] = {.type = INTEGRATOR_PHOTON_POINTS,
                                  .pass = photon_points_pass,
                                  .prepare = photon_points_choose_chain_share,
                                  .last_pass_figures = photon_points_last_radii,
                                  .memory = photon_points_memory,
                                  .print_method = summary_print_photon_pass,
                                  .light_technique = summary_photon_points_light,
                                  .warn = warn_photon_points},
};

const integrator_entry *integrator_entry_of(integrator_type t)
{
    return &table[t];
}
