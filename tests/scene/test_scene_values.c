/* tier: quick */
/* The scene loader reads what is written: the camera basis follows Tungsten's JSON transform, `--set`
 * overrides, verbose notes of ignored keys, the texture fallback, every BSDF key and the shading keys and
 * timeout. Our own scenes/cbox-fog and small scenes written by the test; expected values worked out by hand. */
#include "fixtures.h"

/* ---- camera basis ---- */

static void test_camera_axes_cbox(void **state)
{
    (void)state;
    const scene *s = fx_load(CBOX_FOG "/path_tracer.json", NULL); /* the paper's camera */
    const camera *c = &s->cam;
    /* position (2.78,2.73,-8), look_at (2.78,2.73,0): z = (0,0,8) -> (0,0,1); up (0,1,0) kept; the default
     * x (1,0,0) is already orthonormal and x cross y . z = +1, so no flip; Tungsten then negates x. */
    ASSERT_VEC(c->forward, 0, 0, 1, 1e-12);
    ASSERT_VEC(c->up, 0, 1, 0, 1e-12);
    ASSERT_VEC(c->right, -1, 0, 0, 1e-12);
    double pd = 1.0 / tan(0.5 * CBOX_FOV * M_PI / 180.0);
    ASSERT_NEAR(c->plane_dist, pd, 1e-12);
    ASSERT_NEAR(pd, 2.7995, 1e-3); /* tan(19.65385 deg) = 0.35720 */
    /* the image centre looks straight ahead; the right edge (x = +1 on the plane) leans to screen right */
    vec3 d0 = camera_ray_dir(c, 256.0, 256.0);
    ASSERT_VEC(d0, 0, 0, 1, 1e-12);
    vec3 d1 = camera_ray_dir(c, 512.0, 256.0);
    double n = sqrt(1.0 + pd * pd);
    ASSERT_VEC(d1, -1.0 / n, 0, pd / n, 1e-12);
    vec3 d2 = camera_ray_dir(c, 256.0, 0.0); /* top row: y = h/w = 1 */
    ASSERT_VEC(d2, 0, 1.0 / n, pd / n, 1e-12);
}

static const char BASE_CAMERA_TRANSFORM[] =
    "\"transform\": {\"position\": [0, 1, -4], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}";

/* Camera looking down 45 degrees: up is re-orthogonalised against the view direction. */
static void test_camera_axes_tilted(void **state)
{
    (void)state;
    char *text = fx_keep(replace1(BASE_SCENE, BASE_CAMERA_TRANSFORM,
                                  "\"transform\": {\"position\": [0, 0, 0], \"look_at\": [0, -1, 1], \"up\": [0, 1, 0]}"));
    dp_error err;
    const scene *s = fx_load_text("tilt.json", text, NULL, &err);
    if (!s) fail_msg("%s", err.msg);
    /* z = (0,-1,1)/sqrt2; y = up - z (z.up) = (0,1/2,1/2) -> (0,1,1)/sqrt2; x = (1,0,0); x cross y . z = +1 */
    double h = sqrt(0.5);
    ASSERT_VEC(s->cam.forward, 0, -h, h, 1e-12);
    ASSERT_VEC(s->cam.up, 0, h, h, 1e-12);
    ASSERT_VEC(s->cam.right, -1, 0, 0, 1e-12);
    ASSERT_NEAR(s->cam.plane_dist, 1.0 / tan(M_PI / 8), 1e-12);
}

/* Camera looking along +x: the default x axis (1,0,0) is parallel to the view direction. Tungsten's
 * gramSchmidt (io/JsonPtr.cpp) falls back to c = a x b when the third vector collapses: x = z x y =
 * (1,0,0) x (0,1,0) = (0,0,1); then x cross y . z = (-1,0,0).(1,0,0) < 0 flips the non-explicit x to
 * (0,0,-1); the camera negates it: right = (0,0,1) (= forward x up, as for the Cornell box). */
static void test_camera_axes_looking_along_x(void **state)
{
    (void)state;
    char *text = fx_keep(replace1(BASE_SCENE, BASE_CAMERA_TRANSFORM,
                                  "\"transform\": {\"position\": [-4, 0, 0], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}"));
    dp_error err;
    const scene *s = fx_load_text("alongx.json", text, NULL, &err);
    if (!s) fail_msg("a camera looking along +x must load (Tungsten's Gram-Schmidt fallback), got: %s", err.msg);
    ASSERT_VEC(s->cam.forward, 1, 0, 0, 1e-12);
    ASSERT_VEC(s->cam.up, 0, 1, 0, 1e-12);
    ASSERT_VEC(s->cam.right, 0, 0, 1, 1e-12);
}

/* ---- --set overrides ---- */

static void test_set_overrides(void **state)
{
    (void)state;
    const char *const sets[] = {"transient_time_width=0.5", "spp=7", "enable_guiding=false"};
    scene_load_options opt = {.sets = sets, .set_count = 3, .verbose = 0};
    scene *s = fx_load(CBOX_FOG "/transient.json", &opt);
    ASSERT_NEAR(s->integrator.window.width, 0.5, 0.0);
    ASSERT_NEAR(s->integrator.window.start, 16.15 - 0.25, 1e-9);
    assert_int_equal(s->integrator.window.gated, 1);
    assert_int_equal(s->renderer.spp, 7);
    assert_int_equal(s->integrator.enable_guiding, 0);
    /* untouched keys keep the file's values */
    assert_int_equal(s->integrator.enable_elliptical, 1);
    ASSERT_NEAR(s->integrator.photon_count, 600000, 0);
    fx_drop(s);

    /* an argument without '=' and an unknown key are errors */
    const char *const bad1[] = {"spp"};
    const char *const bad2[] = {"nosuchkey=1"};
    dp_error err;
    scene_load_options o1 = {.sets = bad1, .set_count = 1};
    memset(&err, 0, sizeof err);
    s = fx_slot();
    if (scene_load(CBOX_FOG "/transient.json", &o1, s, &err) == 0) {
        fx_mark(s, 1);
        fail_msg("--set spp (no '=') was accepted");
    }
    assert_true(err.msg[0] != 0);
    scene_load_options o2 = {.sets = bad2, .set_count = 1};
    memset(&err, 0, sizeof err);
    if (scene_load(CBOX_FOG "/transient.json", &o2, s, &err) == 0) {
        fx_mark(s, 1);
        fail_msg("--set nosuchkey=1 was accepted");
    }
    ASSERT_CONTAINS(err.msg, "nosuchkey");
}

/* ---- unknown keys ---- */

static void test_unknown_keys_notes(void **state)
{
    (void)state;
    scene_load_options verbose = {.verbose = 1}, quiet = {.verbose = 0};
    scene *s = fx_load(CBOX_FOG "/transient.json", &verbose);
    ASSERT_CONTAINS(s->notes, "ignored key");
    ASSERT_CONTAINS(s->notes, "camera.tonemap");
    ASSERT_CONTAINS(s->notes, "camera.reconstruction_filter");
    /* keys the loader does read are not listed */
    if (strstr(s->notes, "camera.fov") || strstr(s->notes, "integrator.photon_count") ||
        strstr(s->notes, "media[0].sigma_s"))
        fail_msg("a key that is read is listed as ignored:\n%s", s->notes);
    fx_drop(s);
    s = fx_load(CBOX_FOG "/transient.json", &quiet);
    if (s->notes && strstr(s->notes, "ignored key")) fail_msg("ignored keys listed without verbose:\n%s", s->notes);
    fx_drop(s);
    s = fx_load(CBOX_FOG "/transient.json", NULL);
    if (s->notes && strstr(s->notes, "ignored key")) fail_msg("ignored keys listed with no options:\n%s", s->notes);
}

/* ---- texture albedo ---- */

static void test_texture_albedo_missing(void **state)
{
    (void)state;
    char *text = fx_keep(replace1(BASE_SCENE, "\"albedo\": 0.5", "\"albedo\": \"textures/no_such_floor.tga\""));
    dp_error err;
    const scene *s = fx_load_text("tex.json", text, NULL, &err);
    if (!s) fail_msg("a texture albedo must load with a warning: %s", err.msg);
    ASSERT_CONTAINS(s->notes, "not found");
    ASSERT_CONTAINS(s->notes, "no_such_floor.tga");
    assert_int_equal(s->bsdf_count, 1);
    ASSERT_VEC(s->bsdfs[0].albedo, 0.5, 0.5, 0.5, 0.0);
}

/* ---- BSDF and shading keys ---- */

/* Every BSDF key reaches its field (values as written in the scene text); a conductor's material wins over
 * eta and k (Tungsten's ConductorBsdf reads material last). */
static void test_bsdf_keys_read(void **state)
{
    (void)state;
    static const char from[] = "{\"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.5}";
    char *text = replace1(BASE_SCENE, from,
                          "{\"name\": \"white\", \"type\": \"lambert\", \"albedo\": [0.2, 0.3, 0.4]},"
                          "{\"name\": \"rc\", \"type\": \"rough_conductor\", \"distribution\": \"beckmann\", \"roughness\": 0.3,"
                          " \"eta\": [0.5, 0.6, 0.7], \"k\": [2.5, 2.6, 2.7]},"
                          "{\"name\": \"ag\", \"type\": \"conductor\", \"eta\": 9, \"k\": 9, \"material\": \"Ag\"},"
                          "{\"name\": \"gl\", \"type\": \"dielectric\", \"ior\": 1.33, \"enable_refraction\": false},"
                          "{\"name\": \"pl\", \"type\": \"rough_plastic\", \"distribution\": \"ggx\", \"roughness\": 0.2,"
                          " \"thickness\": 0.5, \"sigma_a\": [0.1, 0.2, 0.3]},"
                          "{\"name\": \"pp\", \"type\": \"pbrt_plastic\", \"distribution\": \"pbrt-ggx\", \"Ks\": 0.4}");
    dp_error err;
    scene *s = fx_load_text("keys.json", text, NULL, &err);
    free(text);
    if (!s) fail_msg("%s", err.msg);
    assert_int_equal(s->bsdf_count, 6);
    ASSERT_VEC(s->bsdfs[0].albedo, 0.2, 0.3, 0.4, 0.0);
    assert_int_equal(s->bsdfs[0].texture, -1);
    assert_int_equal(s->bsdfs[1].type, BSDF_ROUGH_CONDUCTOR);
    assert_int_equal(s->bsdfs[1].distribution, MICROFACET_BECKMANN);
    ASSERT_NEAR(s->bsdfs[1].roughness, 0.3, 0.0);
    ASSERT_VEC(s->bsdfs[1].eta, 0.5, 0.6, 0.7, 0.0);
    ASSERT_VEC(s->bsdfs[1].k, 2.5, 2.6, 2.7, 0.0);
    vec3 eta, k;
    assert_true(bsdf_conductor_preset("Ag", &eta, &k));
    assert_int_equal(s->bsdfs[2].type, BSDF_CONDUCTOR);
    ASSERT_VEC(s->bsdfs[2].eta, eta.x, eta.y, eta.z, 0.0);
    ASSERT_VEC(s->bsdfs[2].k, k.x, k.y, k.z, 0.0);
    assert_int_equal(s->bsdfs[3].type, BSDF_DIELECTRIC);
    ASSERT_NEAR(s->bsdfs[3].ior, 1.33, 0.0);
    assert_int_equal(s->bsdfs[3].enable_refraction, 0);
    assert_int_equal(s->bsdfs[4].type, BSDF_ROUGH_PLASTIC);
    assert_int_equal(s->bsdfs[4].distribution, MICROFACET_GGX);
    ASSERT_NEAR(s->bsdfs[4].roughness, 0.2, 0.0);
    ASSERT_NEAR(s->bsdfs[4].thickness, 0.5, 0.0);
    ASSERT_VEC(s->bsdfs[4].sigma_a, 0.1, 0.2, 0.3, 0.0);
    assert_int_equal(s->bsdfs[5].type, BSDF_PBRT_PLASTIC);
    assert_int_equal(s->bsdfs[5].distribution, MICROFACET_PBRT_GGX);
    ASSERT_NEAR(s->bsdfs[5].ks, 0.4, 0.0);
    assert_string_equal(s->bsdfs[1].name, "rc");
}

/* enable_two_sided_shading, enable_consistency_checks, glossy_gather_alpha and a negative timeout. */
static void test_shading_keys_and_timeout(void **state)
{
    (void)state;
    dp_error err;
    scene *s = fx_load_text("d.json", BASE_SCENE, NULL, &err);
    if (!s) fail_msg("%s", err.msg);
    assert_int_equal(s->integrator.enable_two_sided_shading, 1); /* defaults */
    assert_int_equal(s->integrator.enable_consistency_checks, 0);
    ASSERT_NEAR(s->integrator.glossy_gather_alpha, 0.5, 0.0);
    fx_drop(s);
    char *text = replace1(BASE_SCENE, "\"max_bounces\": 4,",
                          "\"max_bounces\": 4, \"enable_two_sided_shading\": false, \"enable_consistency_checks\": true, "
                          "\"glossy_gather_alpha\": 0.25,");
    char *t2 = replace1(text, "\"timeout\": \"0\"", "\"timeout\": \"-1\"");
    free(text);
    s = fx_load_text("k.json", t2, NULL, &err);
    free(t2);
    if (!s) fail_msg("%s", err.msg);
    assert_int_equal(s->integrator.enable_two_sided_shading, 0);
    assert_int_equal(s->integrator.enable_consistency_checks, 1);
    ASSERT_NEAR(s->integrator.glossy_gather_alpha, 0.25, 0.0);
    ASSERT_NEAR(s->renderer.timeout, 0.0, 0.0);
    fx_drop(s);
    /* a negative number and a negative duration with a unit are "no limit" too */
    static const char *const neg[] = {"\"timeout\": -2", "\"timeout\": \"-30s\""};
    for (size_t i = 0; i < 2; i++) {
        t2 = replace1(BASE_SCENE, "\"timeout\": \"0\"", neg[i]);
        s = fx_load_text("n.json", t2, NULL, &err);
        free(t2);
        if (!s) fail_msg("%s: %s", neg[i], err.msg);
        ASSERT_NEAR(s->renderer.timeout, 0.0, 0.0);
        fx_drop(s);
    }
    /* glossy_gather_alpha must be finite and >= 0 */
    static const char *const bad[] = {"-0.1", "1e999", "\"wide\""};
    for (size_t i = 0; i < 3; i++) {
        char to[128];
        snprintf(to, sizeof to, "\"max_bounces\": 4, \"glossy_gather_alpha\": %s,", bad[i]);
        t2 = replace1(BASE_SCENE, "\"max_bounces\": 4,", to);
        s = fx_load_text("g.json", t2, NULL, &err);
        free(t2);
        if (s) fail_msg("glossy_gather_alpha %s was accepted", bad[i]);
        ASSERT_CONTAINS(err.msg, "g.json");
        ASSERT_CONTAINS(err.msg, "integrator.glossy_gather_alpha");
    }
}

#define T(f) cmocka_unit_test_teardown(f, teardown_fx)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_camera_axes_cbox),
        T(test_camera_axes_tilted),
        T(test_camera_axes_looking_along_x),
        T(test_set_overrides),
        T(test_unknown_keys_notes),
        T(test_texture_albedo_missing),
        T(test_bsdf_keys_read),
        T(test_shading_keys_and_timeout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
