/* tier: quick */
/* The render plan: each decision taken from the keys as the scene file states them (the expected values
 * below are the keys written into the scene text of each case, or the rule the README documents), the
 * per-iteration radii and slack from their closed forms, and the plan's JSON as the EXR header carries it. */
#include "test_util.h"

#include <cjson/cJSON.h>
#include <openexr.h>

#include "dartspp/plan.h"

/* Two media (fog scatters, haze does not), a point light and the camera in the fog; `media_extra` goes into
 * the fog's object, `integrator` is the integrator object's body, `surfaces` extra primitives. */
static void plan_of(const char *media_extra, const char *integrator, const char *surfaces, scene *s, render_plan *p)
{
    char text[8192];
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.5, \"sigma_a\": 0.1 %s },"
             "              { \"name\": \"haze\", \"type\": \"homogeneous\", \"sigma_s\": 0, \"sigma_a\": 0.2 } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": 1, \"ext_medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 0, 2] } } %s ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 40, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s }, \"renderer\": { \"spp\": 7, \"timeout\": \"12s\" } }",
             media_extra, surfaces, integrator);
    char *dir = test_tmpdir();
    assert_non_null(dir);
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, text);
    dp_error err;
    scene_load_options lo = {0};
    int rc = scene_load(path, &lo, s, &err);
    unlink(path);
    rmdir(dir);
    free(dir);
    if (rc) fail_msg("%s", err.msg);
    if (plan_resolve(s, p, &err)) {
        scene_free(s);
        fail_msg("%s", err.msg);
    }
}

static void plan_done(scene *s, render_plan *p)
{
    plan_free(p);
    scene_free(s);
}

#define PP "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\", "
#define R "\"volume_gather_radius\": 0.1, "
#define GATE "\"transient_time_center\": 3, \"transient_time_width\": 0.5, "

/* Budgets, radii, bounce limits and renderer limits come through as the keys say. */
static void test_keys_resolved(void **state)
{
    (void)state;
    scene s;
    render_plan p;
    plan_of("", PP GATE "\"photon_count\": 1234, \"volume_photon_count\": 567, \"gather_radius\": 0.3,"
                        "\"volume_gather_radius\": 0.2, \"alpha\": 0.6, \"volume_alpha\": 0.9, \"gather_photon_count\": 9,"
                        "\"min_bounces\": 1, \"max_bounces\": 5, \"radius_schedule\": \"3d\", \"camera_leg\": \"projected\"",
            "", &s, &p);
    assert_int_equal(p.type, INTEGRATOR_PHOTON_POINTS);
    assert_true(p.photon_count == 1234 && p.volume_photon_count == 567);
    assert_true(p.r_surf.r0 == 0.3 && p.r_surf.alpha == 0.6 && p.r_surf.dims == 2);
    assert_true(p.r_vol.r0 == 0.2 && p.r_vol.alpha == 0.9 && p.r_vol.dims == 3);
    assert_int_equal(p.gather_photon_count, 9);
    assert_true(p.bounces.min == 1 && p.bounces.max == 5);
    assert_true(p.camera_leg == CAMERA_LEG_PROJECTED);
    assert_true(p.window.gated && p.window.start == 2.75 && p.window.width == 0.5);
    assert_true(p.spp == 7 && p.timeout == 12.0);
    /* path segments that count: n <= max and n - 1 >= min */
    assert_false(bounces_count(&p.bounces, 1));
    assert_true(bounces_count(&p.bounces, 2));
    assert_true(bounces_count(&p.bounces, 5));
    assert_false(bounces_count(&p.bounces, 6));
    /* no DARTS key: the baseline */
    assert_false(p.darts.active);
    plan_done(&s, &p);
}

/* DARTS runs only with a switch on, a gated window and a medium; EDA per medium: the integrator's eda in the
 * media that scatter, a medium's own `ida` phase with its alpha. */
static void test_darts_and_eda_switches(void **state)
{
    (void)state;
    scene s;
    render_plan p;
    plan_of("", PP GATE R "\"enable_guiding\": true, \"strict_time_width\": true, \"eda\": true, \"eda_alpha\": 0.25", "",
            &s, &p);
    assert_true(p.darts.active && p.darts.enable_guiding && p.darts.strict_time_width);
    assert_false(p.darts.enable_elliptical || p.darts.enable_elliptical_asked);
    assert_true(p.darts.eda[0].on && p.darts.eda[0].alpha == 0.25);
    assert_false(p.darts.eda[1].on); /* haze does not scatter */
    assert_true(p.darts.eda_active);
    plan_done(&s, &p);

    plan_of(", \"phase_function\": { \"type\": \"ida\", \"alpha\": 2.5 }", PP GATE R "\"enable_elliptical\": true", "", &s,
            &p);
    assert_true(p.darts.active && p.darts.enable_elliptical && !p.darts.enable_guiding);
    assert_true(p.darts.eda[0].on && p.darts.eda[0].alpha == 2.5);
    plan_done(&s, &p);

    /* steady state: no bins to aim at, nothing of DARTS, no EDA */
    plan_of("", PP R "\"enable_guiding\": true, \"enable_elliptical\": true, \"eda\": true", "", &s, &p);
    assert_false(p.window.gated);
    assert_false(p.darts.active || p.darts.enable_elliptical || p.darts.eda_active || p.darts.eda[0].on);
    plan_done(&s, &p);

    /* the path tracer: DARTS toward the light as the keys ask (docs/darts.md §14), and uniform time */
    plan_of("", "\"type\": \"path_tracer\", " GATE "\"enable_guiding\": true, \"eda\": true", "", &s, &p);
    assert_true(p.darts.active && p.darts.enable_guiding && !p.darts.enable_elliptical && p.darts.eda_active);
    assert_false(p.uniform_time);
    plan_done(&s, &p);
    plan_of("", "\"type\": \"path_tracer\", " GATE "\"time_sampling\": \"uniform\"", "", &s, &p);
    assert_true(p.uniform_time);
    assert_false(p.darts.active || p.darts.eda_active);
    plan_done(&s, &p);
    plan_of("", "\"type\": \"path_tracer\", " R "\"enable_guiding\": true, \"enable_elliptical\": true", "", &s, &p);
    assert_false(p.darts.active || p.uniform_time); /* steady state: nothing to aim at */
    plan_done(&s, &p);
}

/* Control vertices need one η over the scene's regions (darts.h): a fog cube with η 4/3 seen from vacuum
 * turns them off and the bounds span [1, 4/3]; the same η everywhere keeps them. */
static void test_control_vertices_need_one_eta(void **state)
{
    (void)state;
    const char *cube = ", { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"int_medium\": \"fog\","
                       "    \"transform\": { \"position\": [0, 0, 2], \"scale\": [1, 1, 1] } }";
    scene s;
    render_plan p;
    plan_of(", \"speed_of_light\": 0.75", PP GATE R "\"enable_elliptical\": true", cube, &s, &p);
    assert_true(p.darts.active && p.darts.enable_elliptical_asked && !p.darts.enable_elliptical);
    assert_float_equal(p.darts.eta_lb, 1.0, 0.0);
    assert_float_equal(p.darts.eta_ub, 4.0 / 3.0, 1e-15);
    plan_done(&s, &p);
    plan_of(", \"speed_of_light\": 0.75", PP GATE R "\"enable_elliptical\": true, \"vaccum_speed_of_light\": 0.75", cube,
            &s, &p);
    assert_true(p.darts.enable_elliptical);
    plan_done(&s, &p);
}

/* Behind a mirror (darts_mirrors, plan.h camera_side_scan): a mirror floor y = -1 in the lower part of the view
 * gives one focus, the camera (the origin) reflected in that plane, (0, -2, 0); the shares are normalised with
 * the straight focus first and the defensive share at least mirror_defensive; strict mode's start test on
 * surfaces goes off. "straight" keeps one technique and strict's test; a diffuse floor is not seen at all;
 * a bad value is refused naming the key. */
static void test_darts_mirrors(void **state)
{
    (void)state;
    const char *floor_of[] = {"{ \"type\": \"mirror\" }", "{ \"type\": \"lambert\", \"albedo\": 0.5 }"};
    char floor[512];
    scene s;
    render_plan p;
    snprintf(floor, sizeof floor, ", { \"type\": \"quad\", \"name\": \"floor\", \"bsdf\": %s,"
             " \"transform\": { \"position\": [0, -1, 2], \"scale\": [10, 1, 10] } }", floor_of[0]);
    plan_of("", PP GATE R "\"enable_elliptical\": true, \"strict_time_width\": true, \"mirror_defensive\": 0.1", floor,
            &s, &p);
    const darts_plan *d = &p.darts;
    assert_true(d->side.seen && d->side.mirror_count == 1 && d->darts_mirrors == DARTS_MIRRORS_FULL);
    assert_string_equal(s.surfaces[d->side.mirror_surface[0]].name, "floor");
    assert_float_equal(d->side.focus[0].x, 0.0, 1e-6);
    assert_float_equal(d->side.focus[0].y, -2.0, 1e-6);
    assert_float_equal(d->side.focus[0].z, 0.0, 1e-6);
    assert_true(d->side.mirror_fraction[0] > 0.05 && d->side.mirror_fraction[0] < 0.5);
    assert_float_equal(d->side.other_fraction, 0.0, 0.0); /* the reflection ends in the fog: exact */
    assert_true(d->cv_multi && !d->strict_surfaces && d->strict_time_width);
    assert_float_equal(d->cv_share[0] + d->cv_share[1] + d->cv_defensive, 1.0, 1e-12);
    assert_float_equal(d->cv_share[1] / d->cv_share[0], d->side.mirror_fraction[0], 1e-12);
    assert_float_equal(d->cv_defensive / d->cv_share[0], 0.1, 1e-12);
    plan_done(&s, &p);

    plan_of("", PP GATE R "\"enable_elliptical\": true, \"strict_time_width\": true, \"darts_mirrors\": \"straight\"",
            floor, &s, &p);
    assert_true(p.darts.side.seen && p.darts.darts_mirrors == DARTS_MIRRORS_STRAIGHT);
    assert_true(!p.darts.cv_multi && p.darts.strict_surfaces && p.darts.cv_share[0] == 1.0 && p.darts.cv_defensive == 0.0);
    plan_done(&s, &p);

    snprintf(floor, sizeof floor, ", { \"type\": \"quad\", \"name\": \"floor\", \"bsdf\": %s,"
             " \"transform\": { \"position\": [0, -1, 2], \"scale\": [10, 1, 10] } }", floor_of[1]);
    plan_of("", PP GATE R "\"enable_elliptical\": true, \"strict_time_width\": true", floor, &s, &p);
    assert_true(!p.darts.side.seen && !p.darts.cv_multi && p.darts.strict_surfaces && p.darts.cv_share[0] == 1.0);
    plan_done(&s, &p);

    char text[2048];
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.5, \"sigma_a\": 0.1 } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": 1, \"ext_medium\": \"fog\" } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 40, \"medium\": \"fog\" },"
             "  \"integrator\": { " PP GATE R "\"darts_mirrors\": \"sideways\" } }");
    char *dir = test_tmpdir();
    assert_non_null(dir);
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, text);
    dp_error err;
    scene_load_options lo = {0};
    int rc = scene_load(path, &lo, &s, &err);
    unlink(path);
    rmdir(dir);
    free(dir);
    if (rc == 0) scene_free(&s);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err.msg, "darts_mirrors"));
    assert_non_null(strstr(err.msg, "sideways"));
}

/* Camera-unwarped time (issue 21, README "Outputs and time"): the bounds drop the camera leg, so DA distance
 * sampling and EDA (which aim at the camera's ellipsoid) are off, control vertices stay on as spheres even
 * where η differs between regions (they need no η along a camera leg), and where the camera sees a mirror
 * they are off (the later camera segments count); the plan's JSON says which time. */
static void test_camera_unwarp(void **state)
{
    (void)state;
    scene s;
    render_plan p;
    char json[8192];
    plan_of("", PP GATE R "\"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true,"
                          "\"eda\": true, \"camera_unwarp\": true", "", &s, &p);
    assert_true(p.window.camera_unwarp && p.darts.active && p.darts.strict_time_width);
    assert_true(p.darts.enable_elliptical && !p.darts.enable_guiding && !p.darts.unwarped_mirror_off);
    assert_true(!p.darts.eda[0].on && p.darts.eda[0].asked_unwarped && !p.darts.eda_active);
    assert_int_equal(plan_json(&p, &s, json, sizeof json), 0);
    assert_non_null(strstr(json, "\"time\":\"camera-unwarped optical path length\""));
    plan_done(&s, &p);

    /* the same keys warped: everything on */
    plan_of("", PP GATE R "\"enable_guiding\": true, \"enable_elliptical\": true, \"eda\": true", "", &s, &p);
    assert_true(!p.window.camera_unwarp && p.darts.enable_elliptical && p.darts.enable_guiding && p.darts.eda[0].on);
    assert_false(p.darts.eda[0].asked_unwarped);
    assert_int_equal(plan_json(&p, &s, json, sizeof json), 0);
    assert_non_null(strstr(json, "\"time\":\"camera-warped optical path length\""));
    plan_done(&s, &p);

    /* two refractive indices: warped control vertices are off, unwarped ones on */
    const char *cube = ", { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"int_medium\": \"fog\","
                       "    \"transform\": { \"position\": [0, 0, 2], \"scale\": [1, 1, 1] } }";
    plan_of(", \"speed_of_light\": 0.75", PP GATE R "\"enable_elliptical\": true, \"camera_unwarp\": true", cube, &s, &p);
    assert_true(p.darts.enable_elliptical);
    plan_done(&s, &p);

    /* a mirror in view: control vertices off, and said why */
    const char *mirror = ", { \"type\": \"quad\", \"name\": \"floor\", \"bsdf\": { \"type\": \"mirror\" },"
                         " \"transform\": { \"position\": [0, -1, 2], \"scale\": [10, 1, 10] } }";
    plan_of("", PP GATE R "\"enable_elliptical\": true, \"camera_unwarp\": true", mirror, &s, &p);
    assert_true(p.darts.side.seen && !p.darts.enable_elliptical && p.darts.unwarped_mirror_off && !p.darts.cv_multi);
    plan_done(&s, &p);
}

/* The slack of the DARTS surface tests: η_ub times the surface radius of the iteration, from the closed form
 * of the schedule r0 · (Γ(i+1+α) / (Γ(1+α) Γ(i+2)))^{1/2}; none without surface photons. */
static void test_surface_slack(void **state)
{
    (void)state;
    scene s;
    render_plan p;
    plan_of(", \"speed_of_light\": 0.5", PP GATE R "\"enable_guiding\": true, \"gather_radius\": 0.2, \"alpha\": 0.7", "",
            &s, &p);
    for (long i = 0; i < 50; i += 7) {
        double r = 0.2 * exp((lgamma(i + 1.7) - lgamma(1.7) - lgamma(i + 2.0)) / 2);
        assert_float_equal(plan_surface_slack(&p, i), 2.0 * r, 1e-12 * r);
    }
    plan_done(&s, &p);
    plan_of("", PP GATE R "\"enable_guiding\": true, \"include_surfaces\": false", "", &s, &p);
    assert_true(plan_surface_slack(&p, 3) == 0.0);
    plan_done(&s, &p);
}

/* The plan's JSON is valid JSON and says what the plan says. */
static void test_plan_json(void **state)
{
    (void)state;
    scene s;
    render_plan p;
    plan_of("", PP GATE R "\"photon_count\": 4321, \"enable_guiding\": true, \"eda\": true, \"eda_alpha\": 0.75", "", &s,
            &p);
    char json[8192];
    assert_int_equal(plan_json(&p, &s, json, sizeof json), 0);
    cJSON *j = cJSON_Parse(json);
    assert_non_null(j);
    assert_true(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "keys"), "photon_count")->valuedouble == 4321);
    const cJSON *w = cJSON_GetObjectItem(j, "window");
    assert_true(cJSON_GetArrayItem(w, 0)->valuedouble == 2.75 && cJSON_GetArrayItem(w, 1)->valuedouble == 3.25);
    const cJSON *d = cJSON_GetObjectItem(j, "darts");
    assert_true(cJSON_IsTrue(cJSON_GetObjectItem(d, "active")) && cJSON_IsTrue(cJSON_GetObjectItem(d, "distance_sampling")));
    assert_true(cJSON_IsFalse(cJSON_GetObjectItem(d, "control_vertices")));
    const cJSON *e = cJSON_GetObjectItem(cJSON_GetObjectItem(j, "eda"), "fog");
    assert_true(e && cJSON_GetObjectItem(e, "alpha")->valuedouble == 0.75);
    assert_null(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "eda"), "haze"));
    cJSON_Delete(j);
    /* too small a buffer is an error, not a truncated plan */
    assert_int_equal(plan_json(&p, &s, json, 40), -1);
    plan_done(&s, &p);
}

/* `--verbose` prints the plan, and the EXR the render writes carries the same text. */
static void test_plan_in_cli_and_exr(void **state)
{
    (void)state;
    char *dir = test_tmpdir();
    assert_non_null(dir);
    char cmd[1024], out[16384], exr[600];
    snprintf(exr, sizeof exr, "%s/demo.exr", dir);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render scenes/fogbox/fogbox.json --spp 1 --set resolution=16 --verbose --quiet "
             "--output %s", exr);
    int rc = test_run(cmd, out, sizeof out);
    char printed[8192] = "";
    const char *line = strstr(out, "plan: ");
    if (line) snprintf(printed, sizeof printed, "%.*s", (int)strcspn(line + 6, "\n"), line + 6);
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    int opened = exr_start_read(&ctx, exr, &init) == EXR_ERR_SUCCESS;
    const char *attr = NULL;
    int32_t len = 0;
    int found = opened && exr_attr_get_string(ctx, 0, "dartspp.plan", &len, &attr) == EXR_ERR_SUCCESS;
    int same = found && !strcmp(attr, printed);
    if (opened) exr_finish(&ctx);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    (void)!system(cmd);
    free(dir);
    assert_int_equal(rc, 0);
    assert_true(printed[0] == '{');
    assert_true(found);
    assert_true(same);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keys_resolved),
        cmocka_unit_test(test_darts_and_eda_switches),
        cmocka_unit_test(test_control_vertices_need_one_eta),
        cmocka_unit_test(test_darts_mirrors),
        cmocka_unit_test(test_camera_unwarp),
        cmocka_unit_test(test_surface_slack),
        cmocka_unit_test(test_plan_json),
        cmocka_unit_test(test_plan_in_cli_and_exr),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
