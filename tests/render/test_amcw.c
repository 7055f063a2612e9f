/* The AMCW time-of-flight output (renderer key amcw_frequencies, docs/amcw.md): the per-contribution
 * correlation sums of the film, their depth and its two-frequency unwrapping.
 *
 * - The unwrapping alone: every depth on a grid over the unambiguous range of a pair of frequencies, wrapped
 *   at each frequency's c₀/(2f), comes back (amcw_unwrap); the range is c₀/(2·gcd).
 * - A plane at d = 10 (metres) perpendicular to the axis of a pinhole camera of fov 10°, lit by a point light at
 *   the camera, vacuum, path tracer, 20, 25 and 0.001 MHz: per pixel the channel-mean AMCW value against the
 *   closed form, the mean of L(x)·e^{−i·2π f·2|p(x)|/c₀} over a 32 × 32 grid of the pixel's film points (L =
 *   (ρ/π)·I·cosθ/r² of the Lambertian plane lit from the camera, the path 2|p|: the phase 4πf|p|/c₀, 4πfd/c₀ on
 *   the axis), within Z_MAX standard errors of the mean of the jittered samples (their variance over the same
 *   grid) after a bias budget of the path time (TIME_BIAS: the light leg's offset origin). The depth unwrapped from 20 and 25 MHz (single depths wrapping at 7.49 and 6.00) against the pixel's
 *   mean |p|, within the phase's allowance / 2k. At
 *   0.001 MHz the modulus against the steady image (f → 0). Broken variants (run 2026-11-28, docs/amcw.md §6):
 *   e^{+iφ} instead of e^{−iφ}, the phase of half the path (the camera leg left out: here the leg is half).
 * - The same render with 1000 frames of width 0.005 over [2, 7) in the fog box (path tracer, camera in the
 *   fog, so the signal spreads over the window): per pixel, channel and frequency (20, 150, 300 MHz) the AMCW
 *   value against the Fourier sum of the cube, Σ_k frame_k·w·e^{−iφ(t_k)}·sinc(k_f·w/2) (the exact mean of
 *   e^{−iφ} over bin k). Both come from the same contributions, so the difference is the binning alone: for a
 *   contribution c at t in bin k, |c·e^{−iφ(t)} − c·e^{−iφ(t_k)}·sinc| ≤ c·(k_f·w/2)(1 + k_f·w/12), which summed
 *   is the bound asserted (with float32 rounding of the frames: 1e-5 of the total). Broken variant: the gate's
 *   weight 1/(width·frames) applied to the AMCW sums.
 * - The key: bad lists refused naming the key; a delta gate refused. */
#include <complex.h>

#include "fixtures.h"
#include "render_fixtures.h"

#include "dartspp/film.h"

static void render_text_sets(const char *text, const char *const *sets, int nsets, long passes, film *f)
{
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, sets, nsets, &s);
    render_stats st;
    render_passes(&s, 2, 7, passes, f, &st);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* ---- the unwrapping ---- */

static void test_unwrap(void **state)
{
    (void)state;
    const double pairs[3][2] = {{20, 25}, {25, 20}, {80, 100}};
    for (int p = 0; p < 3; p++) {
        double f1 = pairs[p][0], f2 = pairs[p][1];
        double range = amcw_unwrap_range(f1, f2), r1 = AMCW_C0 / (2e6 * f1), r2 = AMCW_C0 / (2e6 * f2);
        ASSERT_NEAR(range, AMCW_C0 / (2e6 * (f1 == 80 ? 20 : 5)), 1e-9);
        double worst = 0.0;
        for (int i = 0; i < 4000; i++) {
            double d = (i + 0.5) / 4000 * range;
            double got = amcw_unwrap(fmod(d, r1), f1, fmod(d, r2), f2);
            worst = fmax(worst, fabs(got - d));
        }
        print_message("  %g and %g MHz: range %.6g, largest |unwrapped − d| over 4000 depths %.3g\n", f1, f2, range, worst);
        assert_true(worst < 1e-9 * range);
    }
}

/* ---- a plane at d ---- */

#define Z_MAX 4.9 /* Bonferroni over 512 comparisons: two-sided p ≈ 1e-6 each */
/* The light leg starts at the hit point moved off the plane (scene_offset_ray_origin: 256 float ULPs of its
 * coordinates, 2.4e-4 at z = 10), so every path is that much shorter: measured 2.9e-4 at the centre (a phase
 * lead of 1.2e-4 rad at 20 MHz, 4 standard errors there), allowed as a bias of the path time. */
#define TIME_BIAS 5e-4
#define PLANE_D 10.0
#define PLANE_RES 16
#define PLANE_PASSES 64
static const char PLANE_TEXT[] =
    "{ \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.8 } ],"
    "  \"primitives\": ["
    "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 10], \"scale\": [40, 1, 40],"
    "      \"rotation\": [-90, 0, 0] } },"
    "    { \"type\": \"point\", \"emission\": [100, 100, 100], \"transform\": { \"position\": [0, 0, 0] } } ],"
    "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [16, 16], \"fov\": 10,"
    "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
    "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 4 },"
    "  \"renderer\": { \"spp\": 1, \"amcw_frequencies\": [20, 25, 0.001] } }";

/* The channel-mean phasor of frequency j at pixel px (the film's mean over passes). */
static double complex film_phasor(const film *f, size_t px, int j)
{
    const double *a = &f->amcw_sum[((size_t)f->window.amcw_count * px + j) * 6];
    return ((a[0] + a[2] + a[4]) + I * (a[1] + a[3] + a[5])) / (3.0 * f->weight_sum);
}

static void test_plane_phase_and_depth(void **state)
{
    (void)state;
    tmp_scene ts;
    tmp_scene_write(&ts, PLANE_TEXT);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    film f;
    render_stats st;
    render_passes(&s, 2, 7, PLANE_PASSES, &f, &st);
    assert_int_equal(f.window.amcw_count, 3);
    double worst_z = 0.0, worst_phase = 0.0, worst_depth = 0.0, worst_depth_tol = 0.0, worst_mod = 0.0, wrapped_off = 1e30;
    int depth_off = 0;
    long dark;
    float depth[PLANE_RES * PLANE_RES];
    film_amcw_depth(&f, depth, &dark);
    assert_int_equal(dark, 0);
    const int G = 32;
    for (int y = 0; y < PLANE_RES; y++)
        for (int x = 0; x < PLANE_RES; x++) {
            size_t px = (size_t)y * PLANE_RES + x;
            double depth_tol = 0.0, r_mean = 0.0;
            for (int j = 0; j < 2; j++) {
                double k = f.amcw_k[j];
                /* the pixel's mean of X = L·e^{−iφ} over its film points, and the variance of one jittered sample */
                double complex want = 0.0, xs[32 * 32];
                double wsum = 0.0, rsum = 0.0, var = 0.0;
                for (int g = 0; g < G * G; g++) {
                    vec3 o, d = camera_ray(&s.cam, x + (g % G + 0.5) / G, y + (g / G + 0.5) / G, &o);
                    vec3 p = v3_add(o, v3_scale(d, (PLANE_D - o.z) / d.z));
                    double r = v3_len(p), L = 0.8 * DP_INV_PI * 100.0 * PLANE_D / (r * r * r); /* (ρ/π)·I·cosθ/r² */
                    xs[g] = L * cexp(-I * k * 2.0 * r);
                    want += xs[g] / (G * G);
                    wsum += L;
                    rsum += L * r;
                }
                for (int g = 0; g < G * G; g++) var += creal((xs[g] - want) * conj(xs[g] - want)) / (G * G);
                double se = sqrt(var / PLANE_PASSES) + 1e-9 * cabs(want);
                double complex got = film_phasor(&f, px, j);
                worst_z = fmax(worst_z, fmax(0.0, cabs(got - want) - cabs(want) * k * TIME_BIAS) / se);
                worst_phase = fmax(worst_phase, fabs(carg(got / want)));
                depth_tol = fmax(depth_tol, Z_MAX * se / cabs(want) / (2.0 * k) + 0.5 * TIME_BIAS); /* phase error / 2k */
                r_mean = rsum / wsum;
            }
            /* depth = t/2 = |p|: the mean over the pixel, unwrapped from two wrapped depths */
            double dd = fabs(depth[px] - r_mean);
            worst_depth = fmax(worst_depth, dd);
            worst_depth_tol = fmax(worst_depth_tol, depth_tol);
            depth_off += dd > depth_tol + 1e-6;
            wrapped_off = fmin(wrapped_off, r_mean - fmod(r_mean, AMCW_C0 / (2e6 * 25)));
            /* f → 0: the modulus is the steady image */
            const double *a = &f.amcw_sum[((size_t)3 * px + 2) * 6];
            for (int c = 0; c < 3; c++) {
                double img = f.sum[3 * px + c], mod = hypot(a[2 * c], a[2 * c + 1]);
                worst_mod = fmax(worst_mod, fabs(mod - img) / img);
            }
        }
    print_message("  plane at %g: largest |AMCW − closed form| / its standard error %.2f over 256 pixels × 20 and 25 MHz "
                  "(largest phase error %.3g rad); unwrapped depth: largest |depth − mean |p|| %.3g (largest allowed "
                  "%.3g, %d pixels off; single-frequency depths wrap by at least %.3g); 0.001 MHz: largest relative "
                  "|modulus − image| %.2g\n",
                  PLANE_D, worst_z, worst_phase, worst_depth, worst_depth_tol, depth_off, wrapped_off, worst_mod);
    assert_true(worst_z < Z_MAX);
    assert_int_equal(depth_off, 0);
    assert_true(wrapped_off > 1.0); /* the unwrapping had work to do */
    assert_true(worst_mod < 1e-6);
    film_free(&f);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* ---- the Fourier transform of the cube of the same render ---- */

static void test_cube_fourier(void **state)
{
    (void)state;
    char text[8192];
    box_scene_text(text, sizeof text, 8, "\"type\": \"path_tracer\", \"max_bounces\": 12");
    const double start = 2.0, w = 0.005;
    const int frames = 1000;
    char s1[64], s2[64], s3[64];
    snprintf(s1, sizeof s1, "start_time=%g", start);
    snprintf(s2, sizeof s2, "frame_num=%d", frames);
    snprintf(s3, sizeof s3, "transient_time_width=%g", w);
    const char *sets[] = {s1, s2, s3, "amcw_frequencies=[20,150,300]"};
    film f;
    render_text_sets(text, sets, 4, 40, &f);
    size_t npx = (size_t)f.width * f.height;
    double worst_ratio = 0.0, worst_rel = 0.0, total_all = 0.0, err_sum[3] = {0}, err_plain[3] = {0}, bound_sum[3] = {0};
    for (int j = 0; j < 3; j++) {
        double k = f.amcw_k[j], sinc = sin(0.5 * k * w) / (0.5 * k * w), bound_rel = 0.5 * k * w * (1.0 + k * w / 12.0);
        for (size_t px = 0; px < npx; px++)
            for (int c = 0; c < 3; c++) {
                double complex ft = 0.0;
                double total = 0.0;
                for (int fr = 0; fr < frames; fr++) {
                    double v = f.frame_sum[3 * (npx * fr + px) + c] * w, tk = start + (fr + 0.5) * w;
                    ft += v * cexp(-I * k * tk) * sinc;
                    total += v;
                }
                const double *a = &f.amcw_sum[((size_t)3 * px + j) * 6 + 2 * c];
                double complex got = a[0] + I * a[1];
                double diff = cabs(got - ft), bound = bound_rel * total + 1e-5 * total + 1e-12;
                err_sum[j] += diff;
                err_plain[j] += cabs(got - ft / sinc);
                bound_sum[j] += bound_rel * total;
                worst_ratio = fmax(worst_ratio, diff / bound);
                if (total > 0) worst_rel = fmax(worst_rel, diff / total);
                total_all += total;
            }
    }
    print_message("  fog box, 1000 frames of 0.005 from 2, 20/150/300 MHz: largest |AMCW − Σ frame·w·e^{−iφ}·sinc| "
                  "%.3g of the pixel's total (bound at 300 MHz %.3g), %.3g of the bound\n",
                  worst_rel, 0.5 * f.amcw_k[2] * w, worst_ratio);
    for (int j = 0; j < 3; j++)
        print_message("    %g MHz: Σ|AMCW − FT| over pixels and channels %.3g of the summed bound with the sinc, %.3g without\n",
                      f.window.amcw_mhz[j], err_sum[j] / bound_sum[j], err_plain[j] / bound_sum[j]);
    assert_true(total_all > 0.0);
    assert_true(worst_ratio <= 1.0);
    film_free(&f);
}

/* ---- the key ---- */

static void refused(const char *set, const char *needle)
{
    tmp_scene ts;
    tmp_scene_write(&ts, PLANE_TEXT);
    scene s;
    dp_error err;
    scene_load_options lo = {.sets = (const char *const[]){set}, .set_count = 1};
    int rc = scene_load(ts.path, &lo, &s, &err);
    if (!rc) scene_free(&s);
    tmp_scene_remove(&ts);
    if (!rc) fail_msg("--set %s was accepted", set);
    ASSERT_CONTAINS(err.msg, "amcw_frequencies");
    ASSERT_CONTAINS(err.msg, needle);
}

static void test_key(void **state)
{
    (void)state;
    refused("amcw_frequencies=[0]", "out of range");
    refused("amcw_frequencies=[20,-1]", "out of range");
    refused("amcw_frequencies=[20,20]", "given twice");
    refused("amcw_frequencies=[1,2,3,4,5]", "expected [] or 1 to 4");
    refused("amcw_frequencies=[\"20\"]", "expected [] or 1 to 4");
    refused("amcw_frequencies=2e6", "out of range");
    /* a bare number is a list of one; [] is none */
    const char *one[] = {"amcw_frequencies=30"}, *none[] = {"amcw_frequencies=[]"};
    tmp_scene ts;
    tmp_scene_write(&ts, PLANE_TEXT);
    scene s;
    load_scene(ts.path, one, 1, &s);
    assert_int_equal(s.integrator.window.amcw_count, 1);
    assert_true(s.integrator.window.amcw_mhz[0] == 30.0);
    scene_free(&s);
    load_scene(ts.path, none, 1, &s);
    assert_int_equal(s.integrator.window.amcw_count, 0);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static void test_delta_gate_refused(void **state)
{
    (void)state;
    char text[8192];
    box_scene_text(text, sizeof text, 8,
                   "\"type\": \"progressive_transient_photon_map\", \"photon_count\": 100, \"volume_gather_radius\": 0.1,"
                   " \"transient_time_center\": 4, \"transient_time_width\": 0.2, \"delta_time_gate\": true");
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    dp_error err;
    scene_load_options lo = {.sets = (const char *const[]){"amcw_frequencies=[20]"}, .set_count = 1};
    int rc = scene_load(ts.path, &lo, &s, &err);
    if (!rc) scene_free(&s);
    tmp_scene_remove(&ts);
    assert_int_equal(rc, -1);
    ASSERT_CONTAINS(err.msg, "amcw_frequencies");
    ASSERT_CONTAINS(err.msg, "delta gate");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unwrap),
        cmocka_unit_test(test_plane_phase_and_depth),
        cmocka_unit_test(test_cube_fourier),
        cmocka_unit_test(test_key),
        cmocka_unit_test(test_delta_gate_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
