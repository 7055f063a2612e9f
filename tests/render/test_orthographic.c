/* The orthographic camera (camera type "orthographic", Tungsten's OrthographicCamera; docs/scene-format.md):
 * its film and footprint, its primary times, and every integrator that renders with it.
 *
 * - An emitter seen orthographically (closed form, every pixel): an emissive quad at distance 3 covering
 *   world x in [−2.5, −1], y in [0.5, 1.5] before a 16 × 8 camera at the origin looking along +z with
 *   orthographic_size 1. The film is 4 × 2 (half height 1, half width 1·16/8 = 2; Tungsten's
 *   _hOrthoSize = _vOrthoSize/ratio), pixels 0.25 on a side; screen right is world −x (Tungsten's JSON
 *   transform completes look_at and up to the right-handed x = y × z = +x, and its Camera negates that
 *   axis: looking along +z with +y up, +x is on the viewer's left). So exactly the pixels x >= 12
 *   (x_world in [−2, −1]) and y < 2 (y_world > 0.5) see the emitter, each with the emitter's radiance Le: a pixel of an orthographic image
 *   is the mean radiance over its footprint, as a pinhole pixel is over its solid angle. Every other pixel
 *   is exactly 0. Path tracer and photon points.
 * - Primary times: a quad covering the whole film, perpendicular to the axis at distance d = 3 in vacuum of
 *   η = 2 (vaccum_speed_of_light 0.5), a delta pulse at 0: every pixel sees it at d·η = 6 (camera-warped, the
 *   rays start on the camera's plane and run along the axis) or 0 (camera-unwarped), so with frames of width
 *   0.02 the frame holding that time is Le/0.02 in every pixel and the others exactly 0. Path tracer and
 *   photon points.
 * - Per 4 × 4 tile: the fog box (render_fixtures.c) seen by an orthographic camera in the fog whose film is the
 *   box's opening (2 × 2), gated [3.2, 5.2): the plain path tracer against baseline photon points (volume
 *   splat on parallel lines) with the 3 % bias budget of the photon-points tiles (tests/emitters), and in the
 *   stress group photon beams, the DARTS and the uniform-time path tracers, unwarped photon points and the
 *   unwarped DARTS path tracer (one path-tracer reference per time mode, shared by its cases).
 *   Measured (2026-11-28, under ASan at load 4–8): photon points −0.23 % to −0.74 %, max |z| 1.05–1.50;
 *   beams −0.56 %, 1.15; DARTS PT −0.10 %, 2.43; uniform-time PT −1.03 %, 1.86; unwarped photon points
 *   +0.34 %, 1.28; unwarped DARTS PT −0.04 %, 2.09 (3000 passes each then).
 * - The DARTS photon pass with it is refused, naming the key. */
#include "fixtures.h"
#include "render_fixtures.h"

#define Z_MAX 4.2     /* |z| per tile: Bonferroni over 16 tiles, two-sided p ≈ 4e-4 per comparison */
#define PP_BIAS 0.03  /* photon points against the path tracer: 3 % of a tile (tests/emitters/test_emitters_render.c) */
#define LE 3.0        /* the quad's emitted radiance */

/* A quad emitter of radiance LE facing −z at z = 3, centred at (cx, cy) with sides sx × sy, seen by a 16 × 8
 * orthographic camera at the origin looking along +z. */
static void quad_scene_text(char *text, size_t len, double cx, double cy, double sx, double sy, const char *integrator)
{
    snprintf(text, len,
             "{ \"bsdfs\": [ { \"name\": \"black\", \"type\": \"lambert\", \"albedo\": 0 } ],"
             "  \"primitives\": [ { \"type\": \"quad\", \"bsdf\": \"black\", \"emission\": [%g, %g, %g],"
             "    \"transform\": { \"position\": [%.17g, %.17g, 3], \"scale\": [%.17g, 1, %.17g], \"rotation\": [-90, 0, 0] } } ],"
             "  \"camera\": { \"type\": \"orthographic\", \"resolution\": [16, 8], \"orthographic_size\": 1,"
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             LE, LE, LE, cx, cy, sx, sy, integrator);
}

static void render_text(const char *text, long passes, film *f)
{
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    render_stats st;
    render_passes(&s, 2, 5, passes, f, &st);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static const char *const INTEGRATORS[2] = {
    "\"type\": \"path_tracer\", \"max_bounces\": 4",
    "\"type\": \"progressive_transient_photon_map\", \"max_bounces\": 4, \"photon_count\": 1000,"
    " \"gather_radius\": 0.1, \"volume_gather_radius\": 0.1",
};

/* Broken variants (tests/README.md): orthographic_size read as the film's full height (the lit block becomes
 * 0 pixels), the film's x not negated as Tungsten's (the block moves to x < 4). */
static void test_emitter_footprint(void **state)
{
    (void)state;
    for (int k = 0; k < 2; k++) {
        char text[4096];
        quad_scene_text(text, sizeof text, -1.75, 1.0, 1.5, 1.0, INTEGRATORS[k]);
        film f;
        render_text(text, 4, &f);
        int lit = 0, wrong = 0;
        double worst = 0.0;
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 16; x++) {
                double expect = x >= 12 && y < 2 ? LE : 0.0;
                for (int c = 0; c < 3; c++) {
                    double v = f.sum[3 * ((size_t)y * 16 + x) + c] / f.weight_sum;
                    worst = fmax(worst, fabs(v - expect));
                    wrong += fabs(v - expect) > 1e-9 * LE;
                }
                lit += f.sum[3 * ((size_t)y * 16 + x)] > 0.0;
            }
        print_message("  %s: %d lit pixels (expected 8), largest |pixel − closed form| %.3g, %d values off\n",
                      k ? "photon points" : "path tracer", lit, worst, wrong);
        assert_int_equal(lit, 8);
        assert_int_equal(wrong, 0);
        film_free(&f);
    }
}

/* Broken variants (tests/README.md): the rays from the camera's position instead of the film (a pinhole's
 * times, off-axis pixels later); the camera segment timed when unwarped. */
static void check_times(int unwarp)
{
    double t = unwarp ? 0.0 : 3.0 * 2.0, w = 0.02;
    for (int k = 0; k < 2; k++) {
        char keys[1024], text[4096];
        snprintf(keys, sizeof keys, "%s, \"vaccum_speed_of_light\": 0.5, \"start_time\": %.17g, \"frame_num\": 3, "
                 "\"transient_time_width\": %g, \"camera_unwarp\": %s", INTEGRATORS[k], t - 1.5 * w, w,
                 unwarp ? "true" : "false");
        quad_scene_text(text, sizeof text, 0.0, 0.0, 10.0, 10.0, keys);
        film f;
        render_text(text, 2, &f);
        size_t n = (size_t)16 * 8 * 3;
        int off = 0;
        double worst = 0.0;
        for (int fr = 0; fr < 3; fr++)
            for (size_t i = 0; i < n; i++) {
                double v = f.frame_sum[n * fr + i] / f.weight_sum, expect = fr == 1 ? LE / w : 0.0;
                worst = fmax(worst, fabs(v - expect) / (LE / w));
                off += fabs(v - expect) > 1e-6 * LE / w;
            }
        print_message("  %s, %s: every pixel in the frame of t = %g: %d values off, largest relative error %.2g\n",
                      k ? "photon points" : "path tracer", unwarp ? "unwarped" : "warped", t, off, worst);
        assert_int_equal(off, 0);
        film_free(&f);
    }
}

static void test_primary_times(void **state)
{
    (void)state;
    check_times(0);
    check_times(1);
}

/* ---- per tile against the path tracer ---- */

#define BOX_GATE "\"transient_time_center\": 4.2, \"transient_time_width\": 2.0"
#define BOX_PT "\"type\": \"path_tracer\", \"max_bounces\": 6, " BOX_GATE
#define BOX_PP                                                                                                        \
    "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\", \"max_bounces\": 6,"        \
    " \"photon_count\": 4000, \"volume_photon_count\": 1e6, \"gather_photon_count\": 256, \"gather_radius\": 0.15," \
    " \"volume_gather_radius\": 0.08, \"fixed_volume_radius\": true, \"alpha\": 0.7, \"volume_alpha\": 0.7, " BOX_GATE

/* The fog box at 16² with its camera made orthographic: the film is the box's opening, 2 × 2 (size 1). */
static void ortho_box_text(char *text, size_t len, const char *keys)
{
    box_scene_text(text, len, 16, keys);
    const char *pin = "\"type\": \"pinhole\", \"resolution\": [16, 16], \"fov\": 45";
    const char *ortho = "\"type\": \"orthographic\", \"resolution\": [16, 16], \"orthographic_size\": 1";
    char *at = strstr(text, pin);
    assert_non_null(at);
    char rest[16384];
    snprintf(rest, sizeof rest, "%s", at + strlen(pin));
    snprintf(at, len - (size_t)(at - text), "%s%s", ortho, rest);
}

/* The plain path tracer's tiles with `extra`, rendered once per (extra, passes) and kept for the next case. */
static const cell_totals *pt_reference(const char *extra, long passes, double *seconds)
{
    static cell_totals ref;
    static char key[256];
    static long key_passes;
    static double key_seconds;
    if (ref.x && key_passes == passes && !strcmp(key, extra)) {
        *seconds = key_seconds;
        return &ref;
    }
    free(ref.x);
    char text[16384], k[2048];
    snprintf(k, sizeof k, BOX_PT "%s", extra);
    ortho_box_text(text, sizeof text, k);
    cell_render(text, passes, 11, 0, &ref, &key_seconds);
    snprintf(key, sizeof key, "%s", extra);
    key_passes = passes;
    *seconds = key_seconds;
    return &ref;
}

/* The method `keys` (with `extra`) against the plain path tracer (with `extra`), per tile. */
static void tiles_check(const char *label, const char *keys, const char *extra, double bias, long pt_passes,
                        long passes)
{
    char text[16384], k[2048];
    cell_totals m;
    double t_ref, t_m;
    const cell_totals *ref = pt_reference(extra, pt_passes, &t_ref);
    snprintf(k, sizeof k, "%s%s", keys, extra);
    ortho_box_text(text, sizeof text, k);
    cell_render(text, passes, 29, 0, &m, &t_m);
    double z = cells_z(label, ref, &m, bias, NULL);
    print_message("  seconds: path tracer %.1f, %s %.1f\n", t_ref, label, t_m);
    free(m.x);
    assert_true(z < Z_MAX);
}

/* Broken variants (tests/README.md): the splat's footprint of a pinhole (the tangent range) on the orthographic
 * film; the splat's lines from the camera's position. */
static void test_tiles_photon_points(void **state)
{
    (void)state;
    tiles_check("baseline photon points", BOX_PP, "", PP_BIAS, 1000, 40);
}

static void test_tiles_beams(void **state)
{
    (void)state;
    tiles_check("photon beams", BOX_PP ", \"volume_photon_type\": \"beams\", \"volume_gather_radius\": 0.05", "", PP_BIAS,
                2000, 150);
}

static void test_tiles_path_tracers(void **state)
{
    (void)state;
    tiles_check("DARTS path tracer", BOX_PT ", \"enable_guiding\": true, \"enable_elliptical\": true", "", 0.0, 2000, 2000);
    tiles_check("uniform-time path tracer", BOX_PT ", \"time_sampling\": \"uniform\"", "", 0.0, 2000, 1500);
}

static void test_tiles_unwarped(void **state)
{
    (void)state;
    tiles_check("unwarped photon points", BOX_PP, ", \"camera_unwarp\": true", PP_BIAS, 2000, 150);
    tiles_check("unwarped DARTS path tracer", BOX_PT ", \"enable_guiding\": true, \"enable_elliptical\": true",
                ", \"camera_unwarp\": true", 0.0, 2000, 1000);
}

/* The DARTS photon pass aims at the camera's position: refused with an orthographic camera, naming the key;
 * the same keys with the path tracer load and plan. */
static void test_darts_photon_pass_refused(void **state)
{
    (void)state;
    char text[16384];
    ortho_box_text(text, sizeof text, BOX_PP ", \"enable_guiding\": true, \"enable_elliptical\": true");
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    render_plan p;
    dp_error err;
    assert_int_equal(plan_resolve(&s, &p, &err), -1);
    print_message("  refused: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "integrator.enable_guiding"));
    assert_non_null(strstr(err.msg, "orthographic"));
    scene_free(&s);
    const char *set[] = {"type=path_tracer"};
    load_scene(ts.path, set, 1, &s);
    assert_int_equal(plan_resolve(&s, &p, &err), 0);
    assert_true(p.darts.active);
    plan_free(&p);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* orthographic_size is checked; a pinhole's fov is not read by it (Tungsten's OrthographicCamera reads none). */
static void test_orthographic_keys(void **state)
{
    (void)state;
    char text[4096];
    quad_scene_text(text, sizeof text, 0, 0, 1, 1, INTEGRATORS[0]);
    char *at = strstr(text, "\"orthographic_size\": 1");
    assert_non_null(at);
    memcpy(at, "\"orthographic_size\":-1", 22);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    dp_error err;
    assert_int_equal(scene_load(ts.path, NULL, &s, &err), -1);
    print_message("  refused: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "camera.orthographic_size"));
    tmp_scene_remove(&ts);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emitter_footprint),
        cmocka_unit_test(test_primary_times),
        cmocka_unit_test(test_orthographic_keys),
        cmocka_unit_test(test_darts_photon_pass_refused),
        cmocka_unit_test(test_tiles_photon_points),
    };
    const struct CMUnitTest stress[] = {
        cmocka_unit_test(test_tiles_beams),
        cmocka_unit_test(test_tiles_path_tracers),
        cmocka_unit_test(test_tiles_unwarped),
    };
    return RUN_TESTS_AND_STRESS(tests, stress);
}
