/* tier: quick */
/* The lidar camera's keys and scan (docs/lidar.md §1, §2): what a lidar sets (film size, bins, the window, its
 * beam as the one light, the pulse centred on t = 0), beam directions against the convention written out here
 * independently, the receiver's cosine-weighted cone against its density (χ² over rings), and every refusal
 * naming the file, the key and the reason. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "test_util.h"

#include "dartspp/lidar.h"
#include "dartspp/scene.h"

static const char *const BASE =
    "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.1, \"sigma_a\": 0.01 } ],"
    "  \"bsdfs\": [], \"primitives\": [],"
    "  \"camera\": { \"type\": \"lidar\", \"medium\": \"fog\", \"channels\": 4, \"elevation\": [-10, 5],"
    "    \"azimuth\": [-90, 90], \"azimuth_steps\": 6, \"max_range\": 10, \"range_bin\": 0.3, \"pulse_width\": 0.6,"
    "    \"transform\": { \"position\": [1, 2, 3], \"look_at\": [1, 2, 4], \"up\": [0, 1, 0] } },"
    "  \"integrator\": { \"type\": \"path_tracer\" }, \"renderer\": { \"spp\": 1 } }";

static int load(const char *text, scene *s, dp_error *err)
{
    return scene_load_text(text, "lidar.json", NULL, NULL, s, err);
}

static void test_lidar_sets_film_window_and_beam(void **state)
{
    (void)state;
    scene s;
    dp_error err;
    if (load(BASE, &s, &err)) fail_msg("%s", err.msg);
    const lidar_params *l = &s.cam.lidar;
    assert_int_equal(s.cam.width, 6);
    assert_int_equal(s.cam.height, 4);
    assert_int_equal(l->bins, 34); /* ceil(10 / 0.3) */
    const time_window *tw = &s.integrator.window;
    assert_true(tw->gated && tw->frame_count == 34 && tw->start == 0.0 && fabs(tw->width - 0.6) < 1e-15);
    assert_int_equal(s.light_count, 1);
    assert_true(fabs(s.lights[0].pulse.start + 0.3) < 1e-15 && s.lights[0].pulse.shape == PULSE_GAUSSIAN);
    assert_true(fabs(v3_len(v3_sub(s.lights[0].pos, v3(1, 2, 3)))) < 1e-15);
    assert_true(fabs(s.lights[0].flux.x - 1.0) < 1e-15);
    scene_free(&s);
}

/* forward +z, up +y, Tungsten's camera x is up × forward = +x and the image's right its negation, so left = +x */
static void test_beam_directions(void **state)
{
    (void)state;
    scene s;
    dp_error err;
    if (load(BASE, &s, &err)) fail_msg("%s", err.msg);
    const lidar_params *l = &s.cam.lidar;
    for (int c = 0; c < 4; c++)
        for (int a = 0; a < 6; a++) {
            double el = (-10.0 + 15.0 * c / 3.0) * M_PI / 180.0, az = (-90.0 + 180.0 * (a + 0.5) / 6.0) * M_PI / 180.0;
            vec3 want = v3(cos(el) * sin(az), sin(el), cos(el) * cos(az));
            vec3 got = lidar_beam_dir(l, s.cam.forward, v3_neg(s.cam.right), s.cam.up, c, a);
            assert_true(v3_len(v3_sub(got, want)) < 1e-12);
            /* pixel (x = a, y = channels − 1 − c) */
            assert_true(v3_len(v3_sub(camera_lidar_beam(&s.cam, a, 3 - c), want)) < 1e-12);
        }
    scene_free(&s);
}

/* The receiver's directions: within the cone, with density cosθ/(π sin²θ_r): P(θ < x) = sin²x / sin²θ_r */
static void test_receiver_cone_density(void **state)
{
    (void)state;
    lidar_params l = {.receiver_fov = 0.8};
    vec3 b = v3_norm(v3(0.3, -0.5, 0.8));
    enum { RINGS = 10, N = 200000 };
    double sr2 = pow(sin(0.4), 2.0);
    chi_cell cells[RINGS];
    for (int i = 0; i < RINGS; i++) cells[i] = (chi_cell){.obs = 0, .exp = (double)N / RINGS};
    dp_rng rng = rng_stream(5, 0, 0);
    for (int i = 0; i < N; i++) {
        vec3 d = lidar_receiver_dir(&l, b, rng_uniform(&rng), rng_uniform(&rng));
        assert_true(fabs(v3_len(d) - 1.0) < 1e-12);
        double th = acos(fmin(1.0, v3_dot(d, b)));
        assert_true(th <= 0.4 + 1e-9);
        int k = (int)(pow(sin(th), 2.0) / sr2 * RINGS); /* equal-probability rings of sin²θ */
        cells[k < RINGS ? k : RINGS - 1].obs++;
    }
    int dof;
    double chi2, p = chi2_pooled(cells, RINGS, &chi2, &dof, NULL);
    printf("  receiver cone: chi2 %.1f over %d dof, p %.3g\n", chi2, dof, p);
    assert_true(p > 1e-4);
    assert_true(fabs(lidar_receiver_etendue(&l) - M_PI * sr2) < 1e-15);
}

static void expect_refusal(const char *from, const char *to, const char *key, const char *reason)
{
    char *text = replace1(BASE, from, to);
    scene s;
    dp_error err;
    if (!load(text, &s, &err)) fail_msg("accepted: %s", to);
    ASSERT_CONTAINS(err.msg, "lidar.json");
    ASSERT_CONTAINS(err.msg, key);
    ASSERT_CONTAINS(err.msg, reason);
    free(text);
}

static void test_refusals(void **state)
{
    (void)state;
    expect_refusal("\"channels\": 4", "\"channels\": 4.5", "camera.channels", "whole number");
    expect_refusal("\"channels\": 4", "\"channels\": 0", "camera.channels", "must be in");
    expect_refusal("\"range_bin\": 0.3", "\"range_bin\": 0", "camera.range_bin", "must be in (0");
    expect_refusal("\"azimuth\": [-90, 90]", "\"azimuth\": [-190, 190]", "camera.azimuth", "more than 360");
    expect_refusal("\"azimuth\": [-90, 90]", "\"azimuth\": [90, -90]", "camera.azimuth", "min <= max");
    expect_refusal("\"elevation\": [-10, 5]", "\"elevation\": [-10]", "camera.elevation", "[min, max]");
    expect_refusal("\"pulse_width\": 0.6", "\"pulse_width\": 0.6, \"pulse_shape\": \"sin2\"", "camera.pulse_shape",
                   "box, gaussian");
    expect_refusal("\"pulse_width\": 0.6", "\"pulse_width\": 0.6, \"echoes\": \"second\"", "camera.echoes",
                   "first, strongest, last, all");
    expect_refusal("\"pulse_width\": 0.6", "\"pulse_width\": 0.6, \"resolution\": [6, 4]", "camera.resolution",
                   "azimuth_steps");
    expect_refusal("\"max_range\": 10", "\"max_range\": 1e9", "camera.range_bin", "bins");
    expect_refusal("\"type\": \"path_tracer\"", "\"type\": \"path_tracer\", \"frame_num\": 4", "integrator.frame_num",
                   "range bins");
    expect_refusal("\"type\": \"path_tracer\"", "\"type\": \"path_tracer\", \"camera_unwarp\": true",
                   "integrator.camera_unwarp", "receiver's leg");
    expect_refusal("\"type\": \"path_tracer\"", "\"type\": \"progressive_transient_photon_map\", \"volume_gather_radius\": 0.1, \"gather_radius\": 0.1", "integrator.type",
                   "path tracers");
    expect_refusal("\"primitives\": []",
                   "\"primitives\": [ { \"type\": \"point\", \"power\": 1, \"transform\": { \"position\": [0, 0, 0] } } ]",
                   "primitives", "its own light");
}

static void test_narrow_receiver_warns(void **state)
{
    (void)state;
    char *text = replace1(BASE, "\"pulse_width\": 0.6", "\"pulse_width\": 0.6, \"receiver_fov\": 0.001");
    scene s;
    dp_error err;
    if (load(text, &s, &err)) fail_msg("%s", err.msg);
    ASSERT_CONTAINS(s.notes, "receiver_fov");
    ASSERT_CONTAINS(s.notes, "narrower than beam_divergence");
    scene_free(&s);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lidar_sets_film_window_and_beam),
        cmocka_unit_test(test_beam_directions),
        cmocka_unit_test(test_receiver_cone_density),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_narrow_receiver_warns),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
