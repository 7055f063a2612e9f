/* The photon-by-photon volume gather on the primary lines (volume_gather "splat", src/gather/volume_splat.c)
 * against a beam query per camera segment (volume_gather "beam"): the same pairs of photon and camera ray,
 * found two independent ways (tile footprints from the inverse camera projection vs the volume map's BVH),
 * so every pixel agrees up to the order of its floating-point sums. The cases aim at the footprint's edges:
 * a camera in the fog (photons around and behind it), a camera outside (lines that start inside the image
 * of a fog cube), three fog cubes on one line (more segments than a line keeps), a wide and a narrow
 * field of view, non-square images not a multiple of the tile, a radius that holds the camera, and DARTS
 * with frames. Each case first checks that the splat applies, so a splat switched off cannot pass. */
#include "render_fixtures.h"
#include "test_util.h"

#include "dartspp/gather.h"
#include "dartspp/render.h"

typedef struct {
    int width, height;
    double fov;
    int camera_in_fog;
    int cubes;          /* fog cubes on the camera axis (camera outside) */
    double radius;      /* volume_gather_radius */
    const char *darts;  /* extra integrator keys */
} splat_case;

static void case_text(char *text, size_t len, const splat_case *c)
{
    char cubes[1024] = "";
    if (!c->camera_in_fog)
        for (int i = 0; i < c->cubes; i++) {
            char one[256];
            snprintf(one, sizeof one,
                     "{ \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"int_medium\": \"fog\","
                     " \"transform\": { \"position\": [0, 1, %g], \"scale\": [2.2, 2.2, %g] } },",
                     c->cubes == 1 ? 0.0 : -1.5 + 1.5 * i, c->cubes == 1 ? 2.2 : 0.9);
            strncat(cubes, one, sizeof cubes - strlen(cubes) - 1);
        }
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.5, 0.4, 0.6],"
             "    \"sigma_a\": [0.05, 0.1, 0.02], \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.4 } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.7 } ],"
             "  \"primitives\": ["
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [6, 1, 6] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, 2.5], \"scale\": [6, 1, 6],"
             "      \"rotation\": [-90, 0, 0] } },"
             "    %s"
             "    { \"type\": \"point\", \"emission\": [6, 6, 6], \"transform\": { \"position\": [0.4, 1.4, 0.3] }, \"ext_medium\": \"fog\" } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [%d, %d], \"fov\": %g%s,"
             "    \"transform\": { \"position\": [0.1, 1.05, %g], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
             "    \"photon_count\": 3000, \"volume_photon_count\": 3000, \"gather_radius\": 0.1,"
             "    \"volume_gather_radius\": %g, \"alpha\": 0.7, \"volume_alpha\": 0.8, \"max_bounces\": 12,"
             "    \"transient_time_center\": 4.5, \"transient_time_width\": 3 %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             cubes, c->width, c->height, c->fov,
             c->camera_in_fog ? ", \"medium\": \"fog\"" : "", c->camera_in_fog ? -1.2 : -3.5, c->radius,
             c->darts ? c->darts : "");
}

static void load(const char *path, const char *gather, scene *s)
{
    char set[64];
    snprintf(set, sizeof set, "volume_gather=%s", gather);
    const char *sets[] = {set};
    dp_error err;
    scene_load_options lo = {.sets = sets, .set_count = 1};
    if (scene_load(path, &lo, s, &err)) fail_msg("%s", err.msg);
}

/* Renders the case both ways (3 passes, 2 threads) and compares every pixel: |splat − beam| within 1e-9 of
 * the image's largest value (sums of the same terms in another order differ by ~1e-15 of it; one photon
 * missed or counted twice changes a pixel by a kernel value, orders of magnitude more). Returns the
 * number of non-zero pixels, which the caller requires to be many (a case that gathers nothing proves
 * nothing). */
static long compare_case(const splat_case *c)
{
    char text[8192];
    case_text(text, sizeof text, c);
    char *dir = test_tmpdir();
    assert_non_null(dir);
    char path[512];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, text);
    scene sb, ss;
    load(path, "beam", &sb);
    load(path, "splat", &ss);
    photon one = {0};
    gather_input g = {.vol_photons = &one, .n_vol = 1}; /* only the camera and a non-empty photon set matter */
    assert_true(volume_splat_applies(&ss, &g));
    /* seed 7, 3 passes, 2 threads; no non-finite sample either way (render_fixtures.c) */
    double *b = render_mean(&sb, 2, 7, 3), *s = render_mean(&ss, 2, 7, 3);
    size_t n = (size_t)c->width * c->height * 3;
    double peak = 0.0;
    long lit = 0;
    for (size_t i = 0; i < n; i++) peak = fmax(peak, fabs(b[i]));
    for (size_t i = 0; i < n; i++) {
        if (!(fabs(s[i] - b[i]) <= 1e-9 * peak))
            fail_msg("pixel %zu channel %zu: splat %.17g, beam %.17g (peak %g)", i / 3, i % 3, s[i], b[i], peak);
        lit += b[i] > 0.0;
    }
    assert_true(peak > 0.0);
    free(b);
    free(s);
    scene_free(&sb);
    scene_free(&ss);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    (void)!system(cmd);
    free(dir);
    return lit;
}

static void test_camera_in_fog(void **state)
{
    (void)state;
    splat_case c = {37, 23, 60.0, 1, 0, 0.15, NULL};
    assert_true(compare_case(&c) > 37 * 23 * 3 / 2);
}

static void test_camera_outside_one_cube(void **state)
{
    (void)state;
    splat_case c = {40, 33, 50.0, 0, 1, 0.12, NULL};
    assert_true(compare_case(&c) > 40 * 33);
}

static void test_three_cubes_on_the_line(void **state)
{
    (void)state;
    splat_case c = {29, 31, 40.0, 0, 3, 0.12, NULL};
    assert_true(compare_case(&c) > 29 * 31);
}

static void test_wide_and_narrow_fov(void **state)
{
    (void)state;
    splat_case wide = {48, 20, 150.0, 1, 0, 0.1, NULL}, narrow = {17, 40, 8.0, 1, 0, 0.1, NULL};
    assert_true(compare_case(&wide) > 48 * 20);
    assert_true(compare_case(&narrow) > 17 * 40);
}

/* r = 1.5 around photons as near as the camera: footprints that hold the camera's axis (the whole image). */
static void test_radius_holding_the_camera(void **state)
{
    (void)state;
    splat_case c = {24, 24, 70.0, 1, 0, 1.5, NULL};
    assert_true(compare_case(&c) > 24 * 24 * 2);
}

/* DARTS with control vertices and frames: tagged photons, warped time, strict mode. */
static void test_darts_frames(void **state)
{
    (void)state;
    splat_case c = {33, 27, 55.0, 1, 0, 0.15,
                    ", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true, \"frame_num\": 4"};
    assert_true(compare_case(&c) > 33 * 27);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_in_fog),
        cmocka_unit_test(test_camera_outside_one_cube),
        cmocka_unit_test(test_three_cubes_on_the_line),
        cmocka_unit_test(test_wide_and_narrow_fov),
        cmocka_unit_test(test_radius_holding_the_camera),
        cmocka_unit_test(test_darts_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
