/* The albedo's derivative by scattering order (docs/derivatives.md §4; docs/time.md §7 for the order layers):
 * in a scene without media whose every surface is one Lambertian BSDF of albedo ρ, a path of k scattering
 * events has f ∝ ρ^k, so each contribution's ∂c/∂ρ is k·c/ρ and the order-k layers obey ρ·∂I_k/∂ρ = k·I_k, pixel
 * by pixel, exactly (up to float rounding), whatever the sampling. A missing or double-counted ∂ ln ρ at one
 * kind of vertex (the light path's, the camera walk's, the gather vertex, a surface photon's record) moves a
 * layer off it. With fog (camera and light in it), a path of k events with m medium vertices holds σs^m·ρ^(k−m), so
 * ρ·∂I_k/∂ρ + σs·∂I_k/∂σs|σt = k·I_k (σs moved with σa = σt − σs: no transmittance moves): the medium vertices,
 * volume photons and their records, the gather in fog. The plain, DARTS and uniform-time path tracers;
 * baseline and DARTS photon points (surface and volume photons, control vertices). */
#include "render_fixtures.h"

#include "dartspp/derivative.h"

#define ALBEDO 0.6
#define MAX_BOUNCES 4 /* segments: orders 0..3, each in a layer of its own (bounce_orders 4: layers 0..4) */
#define ORDERS 4

#define SIGMA_S 0.5

/* A box open towards the camera, an area light under its ceiling; everything white; with fog, the camera and
 * light in it. */
static void box_text(char *text, size_t n, const char *integrator, int fog)
{
    const char *media = fog ? "\"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.5,"
                              " \"sigma_a\": 0.1, \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.3 } } ],"
                            : "";
    const char *in_fog = fog ? "\"int_medium\": \"fog\", \"ext_medium\": \"fog\"," : "";
    const char *cam_fog = fog ? "\"medium\": \"fog\"," : "";
    snprintf(text, n,
             "{ %s \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": %g } ],"
             "  \"primitives\": ["
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [2, 1, 2] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 2, 0], \"scale\": [2, 1, 2],"
             "      \"rotation\": [180, 0, 0] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, 1], \"scale\": [2, 1, 2],"
             "      \"rotation\": [-90, 0, 0] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [1, 1, 0], \"scale\": [2, 1, 2],"
             "      \"rotation\": [0, 0, 90] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [-1, 1, 0], \"scale\": [2, 1, 2],"
             "      \"rotation\": [0, 0, -90] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 6, \"pulse_start\": 0.0, \"pulse_width\": 0.5, %s"
             "      \"transform\": { \"position\": [0.1, 1.95, 0.1], \"scale\": [0.6, 1, 0.6], \"rotation\": [180, 0, 0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 60, %s"
             "    \"transform\": { \"position\": [0, 1, -2.4], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"max_bounces\": %d, \"bounce_orders\": %d, \"transient_time_center\": 5.0,"
             "    \"transient_time_width\": 6.0, %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             media, ALBEDO, in_fog, cam_fog, MAX_BOUNCES, ORDERS, integrator);
}

/* Layer `layer` of film f at pixel value i (frame_sum, float). */
static double layer_value(const film *f, long layer, size_t i)
{
    return f->frame_sum[3 * (size_t)f->width * f->height * (size_t)layer + i];
}

/* Renders and checks ρ·∂I_k/∂ρ (+ σs·∂I_k/∂σs at fixed σt, with fog) = k·I_k in every layer, pixel and channel:
 * the worst difference relative to the layer's largest |k·I| must be float rounding; every order 1..3 must have
 * light (each check can fail). With fog, a path of k events has m medium vertices and k − m surface ones: f holds
 * σs^m·ρ^(k−m) and the transmittances, which σs moved with σa = σt − σs leave alone. */
static void check(const char *label, const char *integrator, int fog, long passes)
{
    static char text[8192];
    box_text(text, sizeof text, integrator, fog);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    const char *ptr[1] = {"/bsdfs/0/albedo"};
    scene_load_options lo = {.derivatives = ptr, .derivative_count = 1};
    scene s;
    dp_error err;
    if (scene_load(ts.path, &lo, &s, &err)) fail_msg("%s", err.msg);
    if (fog) { /* ∂/∂σs with σt held: a parameter no pointer names, set as the loader would */
        s.diffs[1] = (diff_param){.kind = DIFF_MEDIUM, .index = 0, .dsigma_s = v3s(1.0), .dsigma_a = v3s(-1.0)};
        s.diff_count = 2;
    }
    render_options ro = {.threads = 2, .seed = 7, .spp = passes};
    film f;
    render_stats st;
    if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.nonfinite, 0);
    assert_int_equal(f.deriv_count, s.diff_count);
    assert_int_equal(f.window.orders, ORDERS + 1);
    size_t np = 3 * (size_t)f.width * f.height;
    double worst = 0.0;
    print_message("  %-16s", label);
    for (int k = 0; k <= ORDERS; k++) {
        long layer = film_order_layer(&f.window, k, -1);
        double scale = 0.0, err_max = 0.0, ti = 0.0, tr = 0.0;
        for (size_t i = 0; i < np; i++) {
            double I = layer_value(&f, layer, i), D = ALBEDO * layer_value(&f.deriv[0], layer, i);
            if (fog) D += SIGMA_S * layer_value(&f.deriv[1], layer, i);
            scale = fmax(scale, fabs(k * I));
            err_max = fmax(err_max, fabs(D - k * I));
            ti += I, tr += ALBEDO * layer_value(&f.deriv[0], layer, i);
        }
        double rel = scale > 0.0 ? err_max / scale : (err_max > 0.0 ? INFINITY : 0.0);
        print_message(" | %d: ρ·dI/I %.3f, err %.0e", k, ti != 0.0 ? tr / ti : 0.0, rel);
        if (k >= 1 && k < MAX_BOUNCES) assert_true(ti > 0.0); /* orders 1..3 lit */
        worst = fmax(worst, rel);
    }
    print_message("\n");
    assert_true(worst <= 1e-4);
    film_free(&f);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

#define PP_KEYS                                                                                               \
    "\"type\": \"progressive_transient_photon_map\", \"photon_count\": 2000, \"gather_photon_count\": 32,"     \
    " \"gather_radius\": 0.2, \"volume_photon_count\": 1e5, \"volume_gather_radius\": 0.1, \"volume_photon_type\": \"points\""

static void test_path_tracers(void **state)
{
    (void)state;
    for (int fog = 0; fog < 2; fog++) {
        check(fog ? "plain, fog" : "plain", "\"type\": \"path_tracer\"", fog, 8);
        check(fog ? "DARTS, fog" : "DARTS", "\"type\": \"path_tracer\", " DARTS_KEYS_TEXT, fog, 8);
        check(fog ? "uniform, fog" : "uniform time", "\"type\": \"path_tracer\", \"time_sampling\": \"uniform\"", fog, 8);
    }
}

static void test_photon_points(void **state)
{
    (void)state;
    for (int fog = 0; fog < 2; fog++) {
        check(fog ? "baseline PP, fog" : "baseline PP", PP_KEYS ", \"enable_guiding\": false", fog, 4);
        check(fog ? "DARTS PP, fog" : "DARTS PP", PP_KEYS ", \"enable_guiding\": true, \"enable_elliptical\": true", fog, 4);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_path_tracers), cmocka_unit_test(test_photon_points)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
