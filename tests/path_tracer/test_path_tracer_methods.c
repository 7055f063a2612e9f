/* tier: stress */
/* The path tracer's methods against the plain path tracer, per image tile: the DARTS path tracer (DA distance
 * sampling, elliptical control vertices, both, with EDA, with and without the directions toward the next
 * connection (docs/darts.md §14.3, on by default wherever control vertices run), in frame mode,
 * camera-unwarped, with two pulsed lights, behind a glass-free box of Lambertian walls) and the uniform-time
 * path tracer; and (test_surfaces) the directions toward the next connection at surface vertices
 * (docs/darts.md §14.4) on a variant where surfaces carry most of the light. Every method is an
 * unbiased estimator of the same image, so on the fog box (HG g = 0.3, coloured fog, multiple scattering and
 * surfaces, a 0.5-wide gate) each 4 × 4 tile's mean must agree with the plain path tracer's: z from the
 * spread of per-pass tile totals of both renders (thousands of passes, so the standard errors have
 * thousands of degrees of freedom), |z| < 4.2 over 16 tiles per method (Bonferroni: two-sided p ≈ 2.7e-5
 * per tile, 4e-4 per method). The plain reference is rendered once per scene variant.
 * Broken variants these checks were shown failing on are listed in tests/README.md ("Figures") and the
 * header of each case. */
#include "fixtures.h"
#include "render_fixtures.h"

/* Replaces the first `from` in text (of size len) by `to`. */
static void replace_once(char *text, size_t len, const char *from, const char *to)
{
    char *at = strstr(text, from);
    assert_non_null(at);
    char rest[16384];
    snprintf(rest, sizeof rest, "%s", at + strlen(from));
    snprintf(at, len - (size_t)(at - text), "%s%s", to, rest);
}

/* The surfaces variant of the fog box (docs/darts.md §14.4): fog 5 times thinner, so most light reaches the
 * camera by way of the walls, and the red wall a rough plastic (a glossy and a diffuse lobe). */
static void surfaces_variant(char *text, size_t len)
{
    replace_once(text, len, "[0.45, 0.4, 0.5]", "[0.09, 0.08, 0.1]");
    replace_once(text, len, "[0.05, 0.08, 0.03]", "[0.01, 0.016, 0.006]");
    replace_once(text, len, "\"type\": \"lambert\", \"albedo\": [0.7, 0.15, 0.1]",
                 "\"type\": \"rough_plastic\", \"roughness\": 0.3, \"ior\": 1.5, \"albedo\": [0.7, 0.15, 0.1]");
}

/* The fog box (render_fixtures.c) at 16² with the path tracer, a gate or frames (`time`), and the method's
 * keys; lights: NULL for the box's own, else the primitives text replacing it; surfaces: surfaces_variant. */
static void method_totals(const char *time, const char *method, int unwarp, const char *lights, int surfaces,
                          long passes, uint64_t seed, int frames, cell_totals *t, double *seconds)
{
    char integrator[1024], text[16384];
    snprintf(integrator, sizeof integrator, "\"type\": \"path_tracer\", \"max_bounces\": 8, %s%s%s%s", time,
             *method ? ", " : "", method, unwarp ? ", \"camera_unwarp\": true" : "");
    box_scene_text(text, sizeof text, 16, integrator);
    if (lights) { /* replace the box's one light by the given ones */
        char *at = strstr(text, "{ \"type\": \"point\"");
        assert_non_null(at);
        char *end = strstr(at, "} } ],");
        assert_non_null(end);
        char rest[4096];
        snprintf(rest, sizeof rest, "%s", end + strlen("} } ],"));
        snprintf(at, sizeof text - (size_t)(at - text), "%s ],%s", lights, rest);
    }
    if (surfaces) surfaces_variant(text, sizeof text);
    cell_render(text, passes, seed, frames, t, seconds);
}

/* Largest |z| of the method against the reference over the tiles (and frames). Prints both totals. */
static double compare_cells(const char *label, const cell_totals *ref, const cell_totals *m, double t_ref, double t_m)
{
    double zmax = 0.0, tot_r = 0, tot_m = 0, var_r = 0, var_m = 0;
    int cells = NT + m->frames;
    for (int v = 0; v < cells; v++) {
        double mr, sr, mm, sm;
        cell_mean_se(ref, v, &mr, &sr);
        cell_mean_se(m, v, &mm, &sm);
        if (v < NT) {
            tot_r += mr, tot_m += mm, var_r += sr * sr, var_m += sm * sm;
        }
        if (sr == 0.0 && sm == 0.0) {
            assert_true(mr == 0.0 && mm == 0.0);
            continue;
        }
        zmax = fmax(zmax, fabs(mm - mr) / sqrt(sr * sr + sm * sm));
    }
    print_message("  %-34s total %.5g (se %.2g) vs plain %.5g (se %.2g); max |z| %.2f over %d cells; "
                  "seconds %.1f vs %.1f\n", label, tot_m, sqrt(var_m), tot_r, sqrt(var_r), zmax, cells, t_m, t_ref);
    assert_true(tot_r > 0.0);
    return zmax;
}

#define GATE "\"transient_time_center\": 4.75, \"transient_time_width\": 0.5"
#define Z_MAX 4.2

typedef struct {
    const char *label, *keys;
    long passes;
} method_case;

/* DARTSPP_PT_ONLY=text runs only the methods whose label contains text (a broken variant's check). */
static int wanted(const char *label)
{
    const char *only = getenv("DARTSPP_PT_ONLY");
    return !only || strstr(label, only);
}

static void check_methods(const char *time, int unwarp, const char *lights, int surfaces, int frames,
                          const method_case *mc, int n, long ref_passes)
{
    cell_totals ref, m;
    double t_ref, t_m;
    int any = 0;
    for (int i = 0; i < n; i++) any |= wanted(mc[i].label);
    if (!any) return;
    method_totals(time, "", unwarp, lights, surfaces, ref_passes, 11, frames, &ref, &t_ref);
    for (int i = 0; i < n; i++) {
        if (!wanted(mc[i].label)) continue;
        method_totals(time, mc[i].keys, unwarp, lights, surfaces, mc[i].passes, 23 + i, frames, &m, &t_m);
        double z = compare_cells(mc[i].label, &ref, &m, t_ref, t_m);
        free(m.x);
        assert_true(z < Z_MAX);
    }
    free(ref.x);
}

/* The gate on the fog box: every DARTS combination and uniform time. */
static void test_gate(void **state)
{
    (void)state;
    const method_case mc[] = {
        {"DARTS (DA + elliptical)", "\"enable_guiding\": true, \"enable_elliptical\": true", 3000},
        {"DA distance sampling only", "\"enable_guiding\": true", 3000},
        {"elliptical only", "\"enable_elliptical\": true", 3000},
        {"elliptical, no MIS, exp. residual",
         "\"enable_elliptical\": true, \"control_vertex_mis\": false, \"ellipse_residual\": \"exponential\"", 3000},
        {"DARTS + EDA (16 x 16 x 32 table)",
         "\"enable_guiding\": true, \"enable_elliptical\": true, \"eda\": true, \"eda_shape\": [16, 16, 32], "
         "\"eda_table_dir\": \"/tmp/dartspp-test-eda\"", 3000},
        {"uniform time", "\"time_sampling\": \"uniform\"", 3000},
        {"elliptical, directions share 0.9", "\"enable_elliptical\": true, \"ellipse_direction_share\": 0.9", 3000},
        {"DARTS, no ellipse directions",
         "\"enable_guiding\": true, \"enable_elliptical\": true, \"ellipse_directions\": false", 3000},
        {"DARTS, directions share 1", "\"enable_guiding\": true, \"enable_elliptical\": true, \"ellipse_direction_share\": 1",
         3000},
    };
    check_methods(GATE, 0, NULL, 0, 0, mc, (int)(sizeof mc / sizeof mc[0]), 12000);
}

/* The surface vertices' directions toward the next connection (docs/darts.md §14.4) where surfaces matter: the
 * fog 5 times thinner, the red wall a rough plastic (glossy and diffuse lobes), the same gate; the mixture
 * at shares 0.5 and 1 (every surface direction from the ellipse sampler), with and without DA, and the
 * surface version off. */
static void test_surfaces(void **state)
{
    (void)state;
    const method_case mc[] = {
        {"surfaces: DARTS", "\"enable_guiding\": true, \"enable_elliptical\": true", 3000},
        {"surfaces: DARTS, share 1", "\"enable_guiding\": true, \"enable_elliptical\": true, \"ellipse_direction_share\": 1",
         3000},
        {"surfaces: elliptical only, share 1", "\"enable_elliptical\": true, \"ellipse_direction_share\": 1", 3000},
        {"surfaces: DARTS, surface directions off",
         "\"enable_guiding\": true, \"enable_elliptical\": true, \"ellipse_surface_directions\": false", 3000},
    };
    check_methods(GATE, 0, NULL, 1, 0, mc, (int)(sizeof mc / sizeof mc[0]), 12000);
}

/* Frame mode (each DARTS camera path serves one frame, divided by its probability): every tile of the union
 * image and every frame's total. */
static void test_frames(void **state)
{
    (void)state;
    const method_case mc[] = {
        {"DARTS, 4 frames", "\"enable_guiding\": true, \"enable_elliptical\": true", 3000},
        {"uniform time, 4 frames", "\"time_sampling\": \"uniform\"", 3000},
    };
    check_methods("\"start_time\": 4.3, \"transient_time_width\": 0.25, \"frame_num\": 4", 0, NULL, 0, 4, mc, 2, 12000);
}

/* Camera-unwarped time (the camera segment takes no time: no DARTS sampler aims along it) and two lights with
 * pulses (one light per camera path, chosen by intensity; its emission time drawn first). */
static void test_unwarped_and_pulsed_lights(void **state)
{
    (void)state;
    const method_case mc[] = {
        {"DARTS, unwarped", "\"enable_guiding\": true, \"enable_elliptical\": true", 3000},
        {"uniform time, unwarped", "\"time_sampling\": \"uniform\"", 3000},
    };
    check_methods("\"transient_time_center\": 1.75, \"transient_time_width\": 0.5", 1, NULL, 0, 0, mc, 2, 12000);
    const char *lights =
        "{ \"type\": \"point\", \"emission\": [4, 4, 4], \"pulse_start\": 0.2, \"pulse_width\": 0.3,"
        "  \"transform\": { \"position\": [0.3, 1.5, 0.2] } },"
        "{ \"type\": \"point\", \"emission\": [1, 0.5, 2], \"ext_medium\": \"fog\", \"pulse_start\": 0.5,"
        "  \"transform\": { \"position\": [-0.5, 0.6, 0.4] } }";
    const method_case mc2[] = {
        {"DARTS, two pulsed lights", "\"enable_guiding\": true, \"enable_elliptical\": true", 3000},
        {"uniform time, two pulsed lights", "\"time_sampling\": \"uniform\"", 3000},
    };
    check_methods(GATE, 0, lights, 0, 0, mc2, 2, 12000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gate),
        cmocka_unit_test(test_surfaces),
    };
    /* make stress only (85 s on 2 cores): frame mode, camera-unwarped time and two pulsed lights per tile (make
     * test checks the path tracer's frames as the reference of test_photon_frames, unwarped time and pulses
     * against quadrature: test_single_scatter_modes' unwarped early gate and box pulse) */
    const struct CMUnitTest stress[] = {
        cmocka_unit_test(test_frames),
        cmocka_unit_test(test_unwarped_and_pulsed_lights),
    };
    return RUN_TESTS_AND_STRESS(tests, stress);
}
