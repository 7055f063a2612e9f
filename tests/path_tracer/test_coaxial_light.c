/* A point light exactly at the pinhole (a coaxial lidar, a flash at the camera) in an infinite HG fog, single
 * scattering (max_bounces 2), gate [4, 4.6) of η = 4/3: the DARTS path tracer (DA + elliptical control vertices,
 * with and without the exponential MIS) and the uniform-time path tracer against the quadrature of
 * tests/path_tracer/test_single_scatter.c (included here), every pixel and channel, z from 32 seeds of 40 passes.
 * Along every camera ray the light lies behind the ray's origin: the equal-time ellipsoid of the camera vertex has
 * coincident foci (C = 0, a sphere of diameter T: docs/darts.md §3), and every light leg is exactly −ω, so the
 * phase function is evaluated at cos = −1 (HG g 0.4 makes that 13 times weaker than forward: a connection taken
 * along +ω would fail). Broken variant (tests/README.md): the record of a vertex at the target refused as invalid,
 * as before: no control vertex on the camera segment, while the segment still stands in for the plain
 * connection of its medium vertices, so the single-scattering image is 0. */
#define SINGLE_SCATTER_QUADRATURE_ONLY 1
#include "test_single_scatter.c"

#define SPEED 0.75
#define G_HG 0.4

/* The scene: write_scene's fog (coloured σ), with the camera and the light at the same point, off the origin. */
static void coaxial_scene(const char *path, const char *integrator)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.5, 0.35, 0.6],"
             "  \"sigma_a\": [0.1, 0.2, 0.05], \"speed_of_light\": %.17g,"
             "  \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": %.17g } } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": [1, 2, 3], \"ext_medium\": \"fog\","
             "    \"transform\": { \"position\": [0.5, -0.25, 1.5] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [12, 8], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0.5, -0.25, 1.5], \"look_at\": [1.5, -0.25, 2.5], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 2, \"transient_time_center\": 4.3,"
             "    \"transient_time_width\": 0.6, %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             SPEED, G_HG, integrator);
    test_write_file(path, text);
}

#define PASSES 40
#define COAXIAL_SEEDS 32

/* The quadrature of every pixel and channel (pixel_value), once for the three cases: the scene differs only in
 * its integrator keys. Checks first that the light and the camera are the same point to the last bit. */
static double *coaxial_quadrature(void)
{
    char *dir = test_tmpdir(), path[512];
    if (!dir) {
        fail_msg("no temporary folder");
        return NULL;
    }
    snprintf(path, sizeof path, "%s/coaxial.json", dir);
    coaxial_scene(path, "\"enable_guiding\": false");
    scene s;
    dp_error err;
    scene_load_options lo = {0};
    if (scene_load(path, &lo, &s, &err)) fail_msg("%s", err.msg);
    assert_true(s.lights[0].pos.x == s.cam.pos.x && s.lights[0].pos.y == s.cam.pos.y && s.lights[0].pos.z == s.cam.pos.z);
    analytic_case a = {.cam = s.cam.pos, .light = s.lights[0].pos, .I = s.lights[0].value, .ss = s.media[0].sigma_s,
                       .st = s.media[0].sigma_t, .g = G_HG, .eta = 1.0 / SPEED, .gated = 1, .g0 = 4.0, .g1 = 4.6};
    double *q = calloc((size_t)3 * s.cam.width * s.cam.height, sizeof(double));
    assert_non_null(q);
    for (int y = 0; y < s.cam.height; y++)
        for (int x = 0; x < s.cam.width; x++)
            for (int ch = 0; ch < 3; ch++) q[3 * (y * s.cam.width + x) + ch] = pixel_value(&a, &s.cam, x, y, ch);
    scene_free(&s);
    test_rmtree(dir);
    return q;
}

static double *quadrature;

static int setup(void **state)
{
    (void)state;
    quadrature = coaxial_quadrature();
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free(quadrature);
    return 0;
}

static void check_coaxial(const char *integrator)
{
    char *dir = test_tmpdir(), path[512];
    if (!dir) {
        fail_msg("no temporary folder");
        return;
    }
    snprintf(path, sizeof path, "%s/coaxial.json", dir);
    coaxial_scene(path, integrator);
    analytic_case a = {.g = G_HG, .eta = 1.0 / SPEED, .gated = 1, .g0 = 4.0, .g1 = 4.6};
    check_scene_against_quadrature(path, a, integrator, 0, PASSES, COAXIAL_SEEDS, quadrature);
    test_rmtree(dir);
}

static void test_darts_pt_coaxial(void **state)
{
    (void)state;
    check_coaxial("\"enable_guiding\": true, \"enable_elliptical\": true");
}

/* the elliptical control vertex alone (p(t) = 2·p(T) on the sphere) and the exponential residual */
static void test_darts_pt_coaxial_no_mis(void **state)
{
    (void)state;
    check_coaxial("\"enable_guiding\": true, \"enable_elliptical\": true, \"control_vertex_mis\": false, "
                  "\"ellipse_residual\": \"exponential\"");
}

static void test_uniform_time_coaxial(void **state)
{
    (void)state;
    check_coaxial("\"time_sampling\": \"uniform\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_darts_pt_coaxial),
        cmocka_unit_test(test_darts_pt_coaxial_no_mis),
        cmocka_unit_test(test_uniform_time_coaxial),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
