/* tier: quick */
/* The identities the derivative images obey whatever the sampling (docs/derivatives.md §7):
 * - ∂I/∂pulse_start = −∂I/∂gate_centre pixel by pixel (S depends on τ + start − centre);
 * - ∂I/∂σa = −E[c·ℓ_medium]: in a scene that is all fog of speed 1 with camera-warped time, every path that lands in
 *   the gate [c − w/2, c + w/2) with an emission time in [s, s + w_p] has ℓ_medium = τ in
 *   [c − w/2 − s − w_p, c + w/2 − s], so the ratio of the images' totals lies in [−(c + w/2 − s), −(c − w/2 − s − w_p)];
 * - linearity: ∂I/∂density = σs·∂I/∂σs + σa·∂I/∂σa, and a vector's derivative is the sum of its channels'.
 * For the plain, DARTS and uniform-time path tracers. */
#include "render_fixtures.h"

#include "dartspp/derivative.h"

#define C_GATE 3.0
#define W_GATE 1.0
#define S_PULSE 0.1
#define W_PULSE 0.3
#define DENSITY 1.5

static void fog_scene(char *text, size_t n, const char *integrator)
{
    snprintf(text, n,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"guided_homo\", \"sigma_s\": [0.5, 0.4, 0.6], \"sigma_a\": 0.1,"
             "    \"density\": %g, \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.4 } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.6 } ],"
             "  \"primitives\": ["
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [3, 1, 3] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 4, \"pulse_start\": %g, \"pulse_width\": %g,"
             "      \"int_medium\": \"fog\", \"ext_medium\": \"fog\","
             "      \"transform\": { \"position\": [0.2, 1.6, 0.3], \"scale\": [0.6, 1, 0.6], \"rotation\": [180, 0, 0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 60, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 1, -1.5], \"look_at\": [0, 0.8, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 6, \"transient_time_center\": %g,"
             "    \"transient_time_width\": %g %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             DENSITY, S_PULSE, W_PULSE, C_GATE, W_GATE, integrator);
}

/* A render with the derivatives `ptr` (count n); *f holds the films (the caller frees them). */
static void render_derivs(const char *text, const char *const *ptr, int n, long passes, film *f)
{
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    scene_load_options lo = {.derivatives = ptr, .derivative_count = n};
    dp_error err;
    if (scene_load(ts.path, &lo, &s, &err)) fail_msg("%s", err.msg);
    render_options ro = {.threads = 2, .seed = 5, .spp = passes};
    render_stats st;
    if (render_scene(&s, &ro, f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.passes, passes);
    assert_int_equal(st.nonfinite, 0);
    assert_int_equal(f->deriv_count, n);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static double total(const film *f)
{
    double t = 0.0;
    for (size_t i = 0; i < 3 * (size_t)f->width * f->height; i++) t += f->sum[i];
    return t / f->weight_sum;
}

/* The largest |a_i − Σ_j w_j b_j,i| over pixels and channels, relative to the largest |a_i|. */
static double combo_error(const film *a, const film *const *b, const double *w, int nb)
{
    double worst = 0.0, scale = 0.0;
    for (size_t i = 0; i < 3 * (size_t)a->width * a->height; i++) {
        double r = a->sum[i];
        for (int j = 0; j < nb; j++) r -= w[j] * b[j]->sum[i];
        worst = fmax(worst, fabs(r));
        scale = fmax(scale, fabs(a->sum[i]));
    }
    return scale > 0.0 ? worst / scale : INFINITY;
}

static void check_integrator(const char *label, const char *integrator)
{
    static char text[4096];
    fog_scene(text, sizeof text, integrator);
    const char *ptr[8] = {"/primitives/1/pulse_start", "/integrator/transient_time_center", "/media/0/sigma_a",
                          "/media/0/sigma_s", "/media/0/density", "/media/0/sigma_s/0", "/media/0/sigma_s/1",
                          "/media/0/sigma_s/2"};
    film f;
    render_derivs(text, ptr, 8, 60, &f);
    double I = total(&f);
    assert_true(I > 0.0);
    /* pulse start against gate centre */
    const film *centre[1] = {&f.deriv[1]};
    double e_shift = combo_error(&f.deriv[0], centre, (double[]){-1.0}, 1);
    /* σa: the ratio of totals in the path-length bounds */
    double ratio = total(&f.deriv[2]) / I / DENSITY; /* the file's σa: ∂σa/∂θ = density */
    double lo = -(C_GATE + 0.5 * W_GATE - S_PULSE), hi = -(C_GATE - 0.5 * W_GATE - S_PULSE - W_PULSE);
    /* σs = ρ·(0.5, 0.4, 0.6) and σa = ρ·0.1 (ρ the density), so ∂/∂ρ = Σ_c σs_c·∂/∂σs_c + σa·∂/∂σa inside, and the
     * file's coefficients' images are ρ times those inside: ∂/∂ρ = Σ_c (σs_c/ρ)·∂/∂σs_file,c + (σa/ρ)·∂/∂σa_file */
    const film *parts[4] = {&f.deriv[5], &f.deriv[6], &f.deriv[7], &f.deriv[2]};
    double e_density = combo_error(&f.deriv[4], parts, (double[]){0.5 / DENSITY, 0.4 / DENSITY, 0.6 / DENSITY, 0.1 / DENSITY}, 4);
    const film *chans[3] = {&f.deriv[5], &f.deriv[6], &f.deriv[7]};
    double e_channels = combo_error(&f.deriv[3], chans, (double[]){1.0, 1.0, 1.0}, 3);
    print_message("  %-14s I %.4g; pulse vs centre %.2g; dI/dσa / I = %.4f in [%.3f, %.3f]; density %.2g; channels %.2g\n",
                  label, I, e_shift, ratio, lo, hi, e_density, e_channels);
    assert_true(e_shift <= 1e-12);
    assert_true(ratio >= lo && ratio <= hi);
    assert_true(e_density <= 1e-6);
    assert_true(e_channels <= 1e-6);
    film_free(&f);
}

/* Every emitter type at once (area, spot, collimated, point; box pulses over the same [S_PULSE, S_PULSE + W_PULSE)):
 * the gate's centre moves every light's contributions and a pulse only its own, so
 * ∂I/∂gate_centre = −Σ_i ∂I/∂pulse_start_i; the σa bounds hold for every light; σs written as one number. */
static void emitters_scene(char *text, size_t n, const char *integrator)
{
    char pulse[96];
    snprintf(pulse, sizeof pulse, "\"pulse_start\": %g, \"pulse_width\": %g, \"ext_medium\": \"fog\"", S_PULSE, W_PULSE);
    snprintf(text, n,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"guided_homo\", \"sigma_s\": 0.5, \"sigma_a\": 0.1,"
             "    \"density\": %g, \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.4 } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.6 } ],"
             "  \"primitives\": ["
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [3, 1, 3] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 4, \"int_medium\": \"fog\", %s,"
             "      \"transform\": { \"position\": [0.2, 1.6, 0.3], \"scale\": [0.6, 1, 0.6], \"rotation\": [180, 0, 0] } },"
             "    { \"type\": \"spot\", \"emission\": 6, \"coneangle\": 30, \"conedeltaangle\": 10, %s,"
             "      \"transform\": { \"position\": [-0.6, 1.2, -1.2], \"look_at\": [0, 0.4, 0.5], \"up\": [0, 1, 0] } },"
             "    { \"type\": \"collimated\", \"radius\": 0.15, \"emission\": 5, %s,"
             "      \"transform\": { \"position\": [-1.2, 0.9, 0.2], \"look_at\": [1, 0.5, 0.4], \"up\": [0, 1, 0] } },"
             "    { \"type\": \"point\", \"emission\": 0.5, %s, \"transform\": { \"position\": [0.5, 0.9, -0.3] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 60, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 1, -1.5], \"look_at\": [0, 0.8, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 6, \"transient_time_center\": %g,"
             "    \"transient_time_width\": %g %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             DENSITY, pulse, pulse, pulse, pulse, C_GATE, W_GATE, integrator);
}

static void check_emitters(const char *label, const char *integrator)
{
    static char text[8192];
    emitters_scene(text, sizeof text, integrator);
    const char *ptr[8] = {"/primitives/1/pulse_start", "/primitives/2/pulse_start", "/primitives/3/pulse_start",
                          "/primitives/4/pulse_start", "/integrator/transient_time_center", "/media/0/sigma_a",
                          "/media/0/sigma_s", "/media/0/density"};
    film f;
    render_derivs(text, ptr, 8, 40, &f);
    double I = total(&f);
    assert_true(I > 0.0);
    for (int i = 0; i < 4; i++) assert_true(fabs(total(&f.deriv[i])) > 0.0); /* every light reaches the gate */
    const film *pulses[4] = {&f.deriv[0], &f.deriv[1], &f.deriv[2], &f.deriv[3]};
    double e_shift = combo_error(&f.deriv[4], pulses, (double[]){-1.0, -1.0, -1.0, -1.0}, 4);
    double ratio = total(&f.deriv[5]) / I / DENSITY;
    double lo = -(C_GATE + 0.5 * W_GATE - S_PULSE), hi = -(C_GATE - 0.5 * W_GATE - S_PULSE - W_PULSE);
    const film *parts[2] = {&f.deriv[6], &f.deriv[5]};
    double e_density = combo_error(&f.deriv[7], parts, (double[]){0.5 / DENSITY, 0.1 / DENSITY}, 2);
    print_message("  %-14s 4 emitters: I %.4g; centre vs −Σ pulses %.2g; dI/dσa / I = %.4f in [%.3f, %.3f]; density %.2g\n",
                  label, I, e_shift, ratio, lo, hi, e_density);
    assert_true(e_shift <= 1e-12);
    assert_true(ratio >= lo && ratio <= hi);
    assert_true(e_density <= 1e-6);
    film_free(&f);
}

static void test_every_emitter(void **state)
{
    (void)state;
    check_emitters("plain", "");
    check_emitters("DARTS", ", " DARTS_KEYS_TEXT);
    check_emitters("uniform time", ", \"time_sampling\": \"uniform\"");
}

static void test_identities(void **state)
{
    (void)state;
    check_integrator("plain", "");
    check_integrator("DARTS", ", " DARTS_KEYS_TEXT);
    check_integrator("uniform time", ", \"time_sampling\": \"uniform\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_identities), cmocka_unit_test(test_every_emitter)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
