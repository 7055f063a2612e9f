/* The key table: every integrator and renderer key of the scene format, declared once. The loader
 * (settings.c), `--set`, the unknown- and unread-key notes, the plan's JSON (plan.c) and `dartspp keys`
 * (the reference in docs/keys.md) all iterate it; a key's name appears elsewhere only where its resolved
 * value is used. Keys the authors' files write that dartspp does not read are listed too (read_by 0), so
 * that the paper's files load without "unknown key" notes and a user sees that they do nothing. */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "dartspp/scene.h"

#define PT KEY_READ_BY(INTEGRATOR_PATH_TRACER)
#define PP KEY_READ_BY(INTEGRATOR_PHOTON_POINTS)
#define ALL KEY_READ_BY_ALL

/* where the resolved value lives */
#define IN(field) .section = KEY_SECTION_INTEGRATOR, .offset = offsetof(integrator_settings, field), \
                  .size = sizeof(((integrator_settings *)0)->field)
#define RE(field) .section = KEY_SECTION_RENDERER, .offset = offsetof(renderer_settings, field), \
                  .size = sizeof(((renderer_settings *)0)->field)
#define AT_LEAST(a) .lo = (a), .bounds = KEY_LO
#define ABOVE(a) .lo = (a), .bounds = KEY_LO | KEY_LO_OPEN
#define IN_RANGE(a, b) .lo = (a), .hi = (b), .bounds = KEY_LO | KEY_HI
#define CHOICES(...) .type = KEY_CHOICE, .choices = (const char *const[]){__VA_ARGS__, NULL}
/* a key of the format that dartspp accepts and does not read */
#define NOT_READ(n, sec, what) {.name = n, .section = sec, .type = KEY_ANY, .meaning = what}

static const scene_key table[] = {
    /* ---- integrator: what every integrator reads ---- */
    {.name = "type", IN(type), CHOICES("path_tracer", "progressive_transient_photon_map"), .read_by = ALL,
     .changes_image = 1, .meaning = "The integrator: the path tracer, or (DARTS) progressive photon points"},
    {.name = "min_bounces", IN(min_bounces), .type = KEY_INT, .read_by = ALL, .changes_image = 1, .def = 0,
     AT_LEAST(0), .meaning = "Paths with fewer than min_bounces + 1 segments (light connection included) do not count"},
    {.name = "max_bounces", IN(max_bounces), .type = KEY_INT, .read_by = ALL, .changes_image = 1, .def = 64,
     IN_RANGE(1, 100000), .meaning = "Most path segments that count, the light connection included"},
    {.name = "transient_time_center", IN(transient_time_center), .type = KEY_NUMBER, .read_by = ALL,
     .changes_image = 1, .def = 0, .meaning = "Centre of the time gate (optical path length); any time key makes the render transient"},
    {.name = "transient_time_width", IN(transient_time_width), .type = KEY_NUMBER, .read_by = ALL,
     .changes_image = 1, .def = 0.1, AT_LEAST(0),
     .meaning = "Width of the gate, or of each frame; 0, or no time key at all: steady state"},
    {.name = "start_time", IN(start_time), .type = KEY_NUMBER, .read_by = ALL, .changes_image = 1, .def = 0,
     .meaning = "Start of the first frame (with frame_num)"},
    {.name = "frame_num", IN(frame_num), .type = KEY_INT, .read_by = ALL, .changes_image = 1, .def = 0,
     IN_RANGE(0, 100000), .meaning = "Frames of width transient_time_width from start_time; 0: one gate image"},
    {.name = "bounce_orders", IN(bounce_orders), .type = KEY_INT, .read_by = ALL, .changes_image = 1, .def = 0,
     IN_RANGE(0, 32), .meaning = "K > 0: also the gate image or frames split by scattering events: 0, 1, ..., K − 1 and K or more (<stem>_orders.npy)"},
    {.name = "delta_time_gate", IN(delta_time_gate), .type = KEY_BOOL, .read_by = ALL, .changes_image = 1, .def = 0,
     .meaning = "The gate is a delta at transient_time_center: the time density there, by a temporal kernel of first width transient_time_width that shrinks (photon points, beams and the sliced primitives but planes; docs/time.md §3.1)"},
    {.name = "camera_unwarp", IN(camera_unwarp), .type = KEY_BOOL, .read_by = ALL, .changes_image = 1, .def = 0,
     .meaning = "Time leaves out the camera segment next to the sensor (camera-unwarped, docs/time.md)"},
    {.name = "sensor_jitter_fwhm", IN(sensor_jitter_fwhm), .type = KEY_NUMBER, .read_by = ALL, .changes_image = 1,
     .def = 0, AT_LEAST(0),
     .meaning = "The sensor's timing jitter: a Gaussian of this FWHM added to every detection time (docs/sensor.md)"},
    {.name = "sensor_jitter_tail", IN(sensor_jitter_tail), .type = KEY_NUMBER, .read_by = ALL, .changes_image = 1,
     .def = 0, AT_LEAST(0), .meaning = "Mean of an exponential delay added to the jitter (the SPAD's diffusion tail); 0: none"},
    {.name = "sensor_response_file", IN(sensor_response_file), .type = KEY_STRING, .read_by = ALL, .changes_image = 1,
     .def_text = "", .meaning = "A tabulated time response instead (CSV \"time,value\", relative to the scene file)"},
    {.name = "vaccum_speed_of_light", IN(vaccum_speed_of_light), .type = KEY_NUMBER, .read_by = ALL, .changes_image = 1,
     .def = 1, ABOVE(0), .meaning = "Speed of light outside media (the format's spelling); time per length is its inverse"},
    {.name = "enable_two_sided_shading", IN(enable_two_sided_shading), .type = KEY_BOOL, .read_by = ALL,
     .changes_image = 1, .def = 1, .meaning = "Opaque surfaces shade both sides"},
    {.name = "enable_consistency_checks", IN(enable_consistency_checks), .type = KEY_BOOL, .read_by = ALL,
     .changes_image = 1, .def = 0,
     .meaning = "A direction on different sides of the shading and geometric normals is refused"},
    {.name = "light_selection", IN(light_selection), CHOICES("power", "uniform"), .read_by = ALL,
     .changes_image = 1, .def = 0,
     .meaning = "How a light path (and an aimed camera path) picks its light: in proportion to the light's flux, or uniformly"},
    /* ---- integrator: the path tracer ---- */
    {.name = "enable_rr", IN(enable_rr), .type = KEY_BOOL, .read_by = PT, .changes_image = 1, .def = 1,
     .meaning = "Russian roulette on the path throughput"},
    {.name = "time_sampling", IN(time_sampling), CHOICES("none", "uniform"), .read_by = PT, .changes_image = 1,
     .def = 0, .meaning = "uniform: the uniform-time path tracer (Jarabo et al. 2014 as the DARTS supplement B.4 corrects it)"},
    {.name = "time_angular_share", IN(time_angular_share), .type = KEY_NUMBER, .read_by = PT, .changes_image = 1,
     .def = 0.5, IN_RANGE(0, 1), .meaning = "Uniform time: share of time-angular directions against the phase function (MIS)"},
    /* ---- integrator: photon points ---- */
    {.name = "photon_count", IN(photon_count), .type = KEY_NUMBER, .integral = 1, .read_by = PP, .changes_image = 1, .def = 1e6,
     AT_LEAST(0), .meaning = "Light paths per iteration, and the surface photon budget"},
    {.name = "volume_photon_count", IN(volume_photon_count), .type = KEY_NUMBER, .integral = 1, .read_by = PP, .changes_image = 1,
     .def = 1e6, AT_LEAST(0), .meaning = "Volume photon budget per iteration"},
    {.name = "gather_photon_count", IN(gather_photon_count), .type = KEY_INT, .read_by = PP, .changes_image = 1,
     .def = 20, IN_RANGE(1, 256), .meaning = "Surface photons gathered per camera hit (k nearest)"},
    {.name = "gather_radius", IN(gather_radius), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1,
     .def = 1e30, ABOVE(0), .meaning = "Initial surface gather radius (a kernel of radius 0 has no area)"},
    {.name = "volume_gather_radius", IN(volume_gather_radius), .type = KEY_NUMBER, .read_by = PP,
     .changes_image = 1, .def_from = "gather_radius", ABOVE(0),
     .meaning = "Initial volume photon radius; photon points need it finite and > 0"},
    {.name = "alpha", IN(alpha), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1, .def = 0.3,
     IN_RANGE(0, 1), .meaning = "Surface radius reduction: the kernel area shrinks by (i+α)/(i+1) per iteration"},
    {.name = "volume_alpha", IN(volume_alpha), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1,
     .def_from = "alpha", IN_RANGE(0, 1), .meaning = "Volume radius reduction, as alpha"},
    {.name = "fixed_volume_radius", IN(fixed_volume_radius), .type = KEY_BOOL, .read_by = PP, .def = 0,
     .meaning = "The authors' switch between fixed and k-NN volume radii; dartspp always uses the progressive "
                "radius (false warns)"},
    {.name = "include_surfaces", IN(include_surfaces), .type = KEY_BOOL, .read_by = PP, .changes_image = 1,
     .def = 1, .meaning = "Store and gather surface photons"},
    {.name = "low_order_scattering", IN(low_order_scattering), .type = KEY_BOOL, .read_by = PP,
     .changes_image = 1, .def = 1, .meaning = "Volume photons at the first medium vertex of a light path"},
    {.name = "volume_photon_type", IN(volume_photon_type), CHOICES("points", "beams", "balls", "volumes", "hypervolumes", "volumes_balls", "mis_volumes_balls",
                                                         "planes", "planes_1d"),
     .read_by = PP, .changes_image = 1, .def = 0,
     .meaning = "Volume photon kind: points (2-D kernel), photon beams (1-D kernel; docs/beams.md), or Liu et al. "
                "2022's temporally sliced primitives with photon beams where they do not serve a path "
                "(docs/sliced_primitives.md)"},
    {.name = "camera_leg", IN(camera_leg), CHOICES("euclidean", "projected"), .read_by = PP,
     .changes_image = 1, .def = 0, .meaning = "Camera leg length of a volume photon's time: along the ray or projected"},
    {.name = "volume_gather", IN(volume_gather), CHOICES("splat", "beam"), .read_by = PP, .changes_image = 1,
     .def = 0, .meaning = "How the sensor pass finds volume photons near camera rays (src/gather/README.md)"},
    {.name = "radius_schedule", IN(radius_schedule), CHOICES("2d", "3d"), .read_by = PP, .changes_image = 1,
     .def = 0, .meaning = "Volume radius shrinks as its kernel's dimension (2-D points, 1-D beams: ours) or by the authors' cube root"},
    {.name = "pass_weights", IN(pass_weights), CHOICES("kernel_area", "equal"), .read_by = PP,
     .changes_image = 1, .def = 0, .meaning = "Iterations averaged by kernel area (inverse variance) or equally"},
    {.name = "glossy_gather_alpha", IN(glossy_gather_alpha), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1,
     .def = 0.5, AT_LEAST(0),
     .meaning = "Glossy lobes at least this rough (microfacet α) gather photons; smoother ones continue camera paths"},
    {.name = "glossy_regularization", IN(glossy_regularization), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1,
     .def = 0.4, AT_LEAST(0),
     .meaning = "Light connections after a glossy camera bounce see microfacet α raised to this, shrinking with the surface radius; 0: off"},
    /* ---- integrator: DARTS (photon points and the path tracer) ---- */
    {.name = "enable_guiding", IN(enable_guiding), .type = KEY_BOOL, .read_by = PT | PP, .changes_image = 1, .def = 0,
     .meaning = "DARTS DA distance sampling: light paths toward the camera, camera paths toward the light"},
    {.name = "enable_elliptical", IN(enable_elliptical), .type = KEY_BOOL, .read_by = PT | PP, .changes_image = 1,
     .def = 0, .meaning = "DARTS elliptical control vertices: volume photons (photon points), light connections (path tracer)"},
    {.name = "strict_time_width", IN(strict_time_width), .type = KEY_BOOL, .read_by = PP, .changes_image = 1,
     .def = 0, .meaning = "DARTS: keep only photons whose path can still land in the gate"},
    {.name = "ellipse_residual", IN(ellipse_residual), CHOICES("uniform", "exponential"), .read_by = PT | PP,
     .changes_image = 1, .def = 0, .meaning = "Residual distance of a control vertex: uniform (authors) or exponential"},
    {.name = "control_vertex_mis", IN(control_vertex_mis), .type = KEY_BOOL, .read_by = PT | PP, .changes_image = 1,
     .def = 1, .meaning = "MIS of the elliptical and free-flight techniques"},
    {.name = "camera_control_vertices", IN(camera_control_vertices), .type = KEY_BOOL, .read_by = PP,
     .changes_image = 1, .def = 1,
     .meaning = "DARTS photon points: a quarter of the medium vertices also place a control vertex found from the camera, by a film direction (MIS with the vertex's own; docs/darts.md §5.5)"},
    {.name = "da_defensive", IN(da_defensive), .type = KEY_NUMBER, .read_by = PT | PP, .changes_image = 1, .def = 0.2,
     IN_RANGE(0, 0.999), .meaning = "Uniform share of the DA-RIS candidate selection"},
    {.name = "ellipse_directions", IN(ellipse_directions), .type = KEY_BOOL, .read_by = PT, .changes_image = 1,
     .def = 1, .meaning = "DARTS path tracer: medium vertices (and surfaces, ellipse_surface_directions) also draw directions toward the next segment's elliptical light connection (MIS)"},
    {.name = "ellipse_direction_share", IN(ellipse_direction_share), .type = KEY_NUMBER, .read_by = PT,
     .changes_image = 1, .def = 0.5, IN_RANGE(0, 1),
     .meaning = "Share of those directions against the phase function (or EDA) in the one-sample MIS"},
    {.name = "ellipse_surface_directions", IN(ellipse_surface_directions), .type = KEY_BOOL, .read_by = PT,
     .changes_image = 1, .def = 1,
     .meaning = "With ellipse_directions: surface vertices (BSDFs without delta lobes) too, against BSDF sampling"},
    {.name = "early_exit", IN(early_exit), .type = KEY_BOOL, .read_by = PT | PP, .changes_image = 1, .def = 1,
     .meaning = "DARTS paths end once their time bin is out of reach"},
    {.name = "surface_chains", IN(surface_chains), .type = KEY_BOOL, .read_by = PP, .changes_image = 1, .def = 1,
     .meaning = "DARTS surface photons from Markov chains over light paths once the volume budget is full"},
    {.name = "surface_direct_connections", IN(surface_direct_connections), .type = KEY_BOOL, .read_by = PP,
     .changes_image = 1, .def = 1,
     .meaning = "Direct light of point, spot and other lights reached without sampling, at the surfaces the sensor "
                "pass gathers: connected from the camera path instead of gathered from first-bounce photons "
                "(docs/defaults.md §3.8)"},
    {.name = "surface_paths", IN(surface_paths), CHOICES("auto", "all"), .read_by = PP, .changes_image = 1, .def = 0,
     .meaning = "DARTS surface chains: trace as many of the light paths left once the volume budget is full as a "
                "pilot finds worth their time (auto), or all of them (docs/defaults.md §3.9)"},
    {.name = "darts_mirrors", IN(darts_mirrors), CHOICES("full", "straight"), .read_by = PP,
     .changes_image = 1, .def = 0,
     .meaning = "Behind mirrors and glossy surfaces: aim at their foci (full) or assume a straight camera leg"},
    {.name = "mirror_defensive", IN(mirror_defensive), .type = KEY_NUMBER, .read_by = PP, .changes_image = 1,
     .def = 0.05, IN_RANGE(0, 0.999), .meaning = "Least defensive share of control vertices where mirrors are seen"},
    {.name = "eda", IN(eda), .type = KEY_BOOL, .read_by = PT | PP, .changes_image = 1, .def = 0,
     .meaning = "EDA direction sampling in every scattering medium"},
    {.name = "eda_alpha", IN(eda_alpha), .type = KEY_NUMBER, .read_by = PT | PP, .changes_image = 1, .def = 0.5,
     ABOVE(0), .meaning = "α of the EDA/phase selection, where the medium's phase sets none"},
    {.name = "eda_shape", IN(eda_shape), .type = KEY_SHAPE3, .read_by = PT | PP, .changes_image = 1,
     .def_text = "[128, 128, 256]", IN_RANGE(1, 4096), .meaning = "EDA tables built: [C/S rows, S columns, cos bins]"},
    {.name = "eda_table_dir", IN(eda_table_dir), .type = KEY_STRING, .read_by = PT | PP, .def_text = "tables",
     .meaning = "Folder of the EDA table cache"},
    /* ---- integrator: the format's keys that dartspp does not read ---- */
    NOT_READ("enable_light_sampling", KEY_SECTION_INTEGRATOR, "Tungsten's switch; dartspp always samples lights"),
    NOT_READ("enable_volume_light_sampling", KEY_SECTION_INTEGRATOR, "Tungsten's switch; dartspp always samples lights"),
    NOT_READ("exclude_non_mis", KEY_SECTION_INTEGRATOR, "The authors' photon switch; not read"),
    NOT_READ("use_grid", KEY_SECTION_INTEGRATOR, "The authors' photon grid; dartspp uses kd-trees"),
    NOT_READ("frustum_culling", KEY_SECTION_INTEGRATOR, "The authors' photon culling switch; not read"),
    /* ---- renderer ---- */
    {.name = "spp", RE(spp), .type = KEY_INT, .read_by = ALL, .def = 64, AT_LEAST(0),
     .meaning = "Progressive passes; 0: no limit (--spp overrides)"},
    {.name = "timeout", RE(timeout), .type = KEY_DURATION, .read_by = ALL, .def_text = "none",
     .meaning = "Time limit; a bare number is minutes; 0: none; negative: none, with a warning (--time overrides)"},
    {.name = "checkpoint_interval", RE(checkpoint_interval), .type = KEY_DURATION, .read_by = ALL,
     .def_text = "none", .meaning = "Interval of checkpoint writes (--checkpoint overrides)"},
    {.name = "hdr_output_file", RE(hdr_output_file), .type = KEY_STRING, .read_by = ALL, .def_text = "<scene>.exr",
     .meaning = "Output image when --output is not given; a relative path goes into a folder named after the scene"},
    {.name = "ground_truth", RE(ground_truth), .type = KEY_BOOL, .read_by = ALL, .def = 0,
     .meaning = "Also write the first surface's depth, the time of first arrival, normal and albedo per pixel (docs/sensor.md)"},
    {.name = "amcw_frequencies", RE(amcw_frequencies), .type = KEY_NUMBER_LIST, .read_by = ALL, .def_text = "[]",
     .lo = 0, .hi = 1e6, .bounds = KEY_LO | KEY_LO_OPEN | KEY_HI,
     .meaning = "AMCW time-of-flight output: per pixel the correlation at each of these modulation frequencies (MHz, "
                "the scene unit a metre), and the depth from the first two (<stem>_amcw.npy, _amcw_depth.npy; docs/amcw.md)"},
    {.name = "output_file", RE(output_file), .type = KEY_STRING, .def_text = "",
     .meaning = "The authors' LDR preview; dartspp writes none"},
    NOT_READ("spp_step", KEY_SECTION_RENDERER, "Tungsten's passes per step; not read"),
    NOT_READ("output_buffers", KEY_SECTION_RENDERER, "Tungsten's extra buffers; frames come from frame_num"),
    NOT_READ("overwrite_output_files", KEY_SECTION_RENDERER, "dartspp always replaces its outputs atomically"),
    NOT_READ("enable_resume_render", KEY_SECTION_RENDERER, "Tungsten's resume switch; not read"),
    NOT_READ("resume_render_file", KEY_SECTION_RENDERER, "Tungsten's resume file; not read"),
    NOT_READ("stratified_sampler", KEY_SECTION_RENDERER, "Tungsten's sampler switch; not read"),
    NOT_READ("scene_bvh", KEY_SECTION_RENDERER, "Tungsten's BVH switch; dartspp uses Embree"),
    NOT_READ("adaptive_sampling", KEY_SECTION_RENDERER, "Tungsten's adaptive sampling; not read"),
    NOT_READ("output_directory", KEY_SECTION_RENDERER, "Tungsten's output folder; not read"),
};

const scene_key *scene_keys(int *count)
{
    *count = (int)(sizeof table / sizeof table[0]);
    return table;
}

const scene_key *scene_key_find(const char *name)
{
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (!strcmp(table[i].name, name)) return &table[i];
    return NULL;
}

const char *integrator_type_name(integrator_type t)
{
    return scene_key_find("type")->choices[t];
}

const char *scene_key_section_name(scene_key_section s)
{
    return s == KEY_SECTION_INTEGRATOR ? "integrator" : "renderer";
}

const char *scene_key_type_name(scene_key_type t)
{
    switch (t) {
    case KEY_BOOL: return "bool";
    case KEY_INT: return "integer";
    case KEY_NUMBER: return "number";
    case KEY_CHOICE: return "string (choice)";
    case KEY_STRING: return "string";
    case KEY_DURATION: return "duration";
    case KEY_SHAPE3: return "[int, int, int]";
    case KEY_NUMBER_LIST: return "[number, ...]";
    case KEY_ANY: return "any";
    }
    return "?";
}

void scene_key_default_text(const scene_key *k, char *out, size_t n)
{
    if (k->def_from) snprintf(out, n, "= %s", k->def_from);
    else if (k->type == KEY_BOOL) snprintf(out, n, "%s", k->def ? "true" : "false");
    else if (k->type == KEY_CHOICE) snprintf(out, n, "%s", k->choices[(int)k->def]);
    else if (k->type == KEY_INT || k->type == KEY_NUMBER) snprintf(out, n, "%g", k->def);
    else if (k->def_text) snprintf(out, n, "%s", k->def_text[0] ? k->def_text : "(empty)");
    else snprintf(out, n, "—");
}

void scene_key_range_text(const scene_key *k, char *out, size_t n)
{
    out[0] = 0;
    if (k->type == KEY_CHOICE) {
        size_t len = 0;
        for (int i = 0; k->choices[i] && len < n; i++)
            len += (size_t)snprintf(out + len, n - len, "%s%s", i ? ", " : "", k->choices[i]);
    } else if (k->type == KEY_SHAPE3) snprintf(out, n, "each in [%g, %g], the last ≥ %g", k->lo, k->hi, k->lo + 1);
    else if (k->type == KEY_NUMBER_LIST)
        snprintf(out, n, "[] or 1 to %d distinct numbers, each in %s%g, %g]", KEY_LIST_MAX,
                 k->bounds & KEY_LO_OPEN ? "(" : "[", k->lo, k->hi);
    else if ((k->bounds & KEY_LO) && (k->bounds & KEY_HI)) snprintf(out, n, "[%g, %g]", k->lo, k->hi);
    else if (k->bounds & KEY_LO) snprintf(out, n, "%s %g%s", k->bounds & KEY_LO_OPEN ? ">" : "≥", k->lo, k->integral ? ", whole" : "");
    else if (k->bounds & KEY_HI) snprintf(out, n, "≤ %g", k->hi);
    else if (k->type == KEY_NUMBER) snprintf(out, n, "finite");
    else snprintf(out, n, "—");
}

void scene_key_readers_text(const scene_key *k, char *out, size_t n)
{
    if (!k->read_by) snprintf(out, n, "none");
    else if (k->read_by == KEY_READ_BY_ALL) snprintf(out, n, "all");
    else {
        size_t len = 0;
        out[0] = 0;
        for (int t = 0; t < INTEGRATOR_COUNT && len < n; t++)
            if (scene_key_read_by(k, t)) len += (size_t)snprintf(out + len, n - len, "%s%s", len ? ", " : "", integrator_type_name(t));
    }
}
