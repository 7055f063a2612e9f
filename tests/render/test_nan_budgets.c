/* Issue 32, items 1 and 3: nothing silently wrong in what a render writes or in how long it runs.
 * - Photon points need radii > 0: gather_radius and volume_gather_radius 0 are refused (they rendered every
 *   pixel NaN: the kernel-area pass weights divide 0 by 0).
 * - The last line of defence: no NaN or Inf reaches an output file. The film's images write a non-finite pixel
 *   as 0 (film_image), the run counts them (film_nonfinite_pixels) and the summary says so; end to end, a light
 *   so bright that every lit pixel is beyond the float range (the old code wrote Inf).
 * - Budgets that mean "forever" are said aloud: a negative scene timeout (the format's "-1") warns, naming the
 *   key and what ends the render; with spp 0 too, that nothing bounds it and how to stop it; `--time 0` or
 *   `--spp 0` alone are refused (exit 2).
 * Expected values: worked out by hand from the scenes (which pixels a render lights comes from a render of the
 * same scene and seed at a normal brightness, so that the count is exact by construction). */
#include "fixtures.h"

#include <math.h>

#include "dartspp/film.h"

/* ---- radii ---- */

static const char PP_KEYS[] = "\"type\": \"progressive_transient_photon_map\", \"photon_count\": 1000, "
                              "\"volume_photon_count\": 1000, \"gather_radius\": 0.1, \"volume_gather_radius\": 0.1, "
                              "\"max_bounces\": 4,";

/* BASE_SCENE as photon points, with `from` replaced by `to` in the photon-points keys. */
static scene *load_pp(const char *from, const char *to, dp_error *err)
{
    char *keys = replace1(PP_KEYS, from, to);
    char *text = replace1(BASE_SCENE, "\"type\": \"path_tracer\", \"max_bounces\": 4,", keys);
    scene *s = fx_load_text("pp.json", text, NULL, err);
    free(keys);
    free(text);
    return s;
}

static void test_radius_zero_refused(void **state)
{
    (void)state;
    dp_error err;
    scene *s = load_pp("\"photon_count\"", "\"photon_count\"", &err); /* unchanged: loads */
    if (!s) fail_msg("%s", err.msg);
    fx_drop(s);
    assert_null(load_pp("\"gather_radius\": 0.1", "\"gather_radius\": 0", &err));
    ASSERT_CONTAINS(err.msg, "pp.json: integrator.gather_radius: must be > 0 (got 0)");
    assert_null(load_pp("\"volume_gather_radius\": 0.1", "\"volume_gather_radius\": 0", &err));
    ASSERT_CONTAINS(err.msg, "pp.json: integrator.volume_gather_radius: must be > 0 (got 0)");
    assert_null(load_pp("\"gather_radius\": 0.1", "\"gather_radius\": -0.5", &err));
    ASSERT_CONTAINS(err.msg, "integrator.gather_radius: must be > 0");
}

/* The command: the demo scene with --set gather_radius=0 rendered all-NaN pixels and exited 0. */
static void test_cli_gather_radius_zero(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char cmd[2048], out[8192], path[512];
    join(path, sizeof path, dir, "g.pfm");
    snprintf(cmd, sizeof cmd,
             "timeout -s INT 120 " DARTSPP_BIN " render scenes/fogbox/fogbox.json --spp 1 --quiet --set resolution=8 "
             "--set photon_count=2000 --set gather_radius=0 --output %s", path);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, "fogbox.json: integrator.gather_radius: must be > 0 (got 0)");
    assert_int_equal(access(path, F_OK), -1);
}

/* ---- no NaN or Inf in an output ---- */

/* A 3x1 film with 2 frames, sums set by hand: a NaN channel in the gate image's pixel 0 and +Inf in frame 1's
 * pixel 2; weight sum 2. Those two pixels are written as 0 in all three channels, the others as sum / 2. Then a
 * steady film whose double sum 1e300 is beyond the float range. */
static film films[2]; /* freed by the teardown, also after a failed assertion */
static image_rgb film_img;

static int teardown_films(void **state)
{
    (void)state;
    film_free(&films[0]);
    film_free(&films[1]);
    image_free(&film_img);
    return 0;
}

static void test_film_image_writes_nonfinite_as_zero(void **state)
{
    (void)state;
    film *f = &films[0], *f2 = &films[1];
    image_rgb *img = &film_img;
    dp_error err;
    time_window tw = {.gated = 1, .start = 0, .width = 1, .frame_count = 2};
    assert_int_equal(film_init(f, 3, 1, &tw, &err), 0);
    for (int i = 0; i < 9; i++) {
        f->sum[i] = i + 1;
        f->frame_sum[i] = (float)(10 + i);
        f->frame_sum[9 + i] = (float)(20 + i);
    }
    f->sum[1] = NAN;
    f->frame_sum[9 + 7] = INFINITY;
    f->passes = 2;
    f->weight_sum = 2.0;
    assert_int_equal(film_nonfinite_pixels(f), 2);
    assert_int_equal(film_image(f, -1, img, &err), 0);
    const float gate[9] = {0, 0, 0, 2, 2.5f, 3, 3.5f, 4, 4.5f};
    for (int i = 0; i < 9; i++) assert_true(img->rgb[i] == gate[i]);
    image_free(img);
    assert_int_equal(film_image(f, 1, img, &err), 0);
    const float frame1[9] = {10, 10.5f, 11, 11.5f, 12, 12.5f, 0, 0, 0};
    for (int i = 0; i < 9; i++) assert_true(img->rgb[i] == frame1[i]);
    image_free(img);
    /* beyond the float range: a double sum of 1e300 is Inf in float32 */
    time_window steady = {0};
    assert_int_equal(film_init(f2, 2, 1, &steady, &err), 0);
    f2->sum[3] = 1e300;
    f2->sum[0] = 7;
    f2->weight_sum = 1.0;
    f2->passes = 1;
    assert_int_equal(film_nonfinite_pixels(f2), 1);
    assert_int_equal(film_image(f2, -1, img, &err), 0);
    assert_true(img->rgb[0] == 7.0f && img->rgb[3] == 0.0f && img->rgb[4] == 0.0f && img->rgb[5] == 0.0f);
}

/* Pixels with a non-zero channel in the image at path; fails on a non-finite value. */
static long lit_pixels(const char *path, long *nonfinite)
{
    image_rgb img;
    dp_error err;
    if (image_read(path, &img, &err)) fail_msg("%s", err.msg);
    long lit = 0;
    for (long i = 0; i < (long)img.width * img.height; i++) {
        const float *p = &img.rgb[3 * i];
        *nonfinite += !(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]));
        lit += p[0] != 0.0f || p[1] != 0.0f || p[2] != 0.0f;
    }
    image_free(&img);
    return lit;
}

/* The cube's float32 values after its NumPy header (the header ends with the first newline). */
static long cube_nonfinite(const char *path)
{
    size_t len;
    char *data = read_all(path, &len);
    char *nl = memchr(data, '\n', len);
    assert_non_null(nl);
    long bad = 0;
    for (const char *p = nl + 1; p + 4 <= data + len; p += 4) {
        float v;
        memcpy(&v, p, 4);
        bad += !isfinite(v);
    }
    free(data);
    return bad;
}

/* Renders BASE_SCENE (path tracer, 8x8, 2 passes, 2 frames of width 20 from 0, so every lit pixel counts) with
 * the light's power `power` to <dir>/<stem>.pfm; returns the exit status, the output in out. */
static int render_base(const char *dir, const char *stem, const char *power, char *out, size_t n)
{
    char *t1 = replace1(BASE_SCENE, "\"power\": 100", power);
    char *t2 = replace1(t1, "\"transient_time_center\": 6,\n    \"transient_time_width\": 0.5",
                        "\"frame_num\": 2, \"start_time\": 0, \"transient_time_width\": 20");
    char scene_path[512], cmd[2048];
    snprintf(scene_path, sizeof scene_path, "%s/%s.json", dir, stem);
    test_write_file(scene_path, t2);
    free(t1);
    free(t2);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render %s --spp 2 --quiet --output %s/%s.pfm", scene_path, dir, stem);
    return test_run(cmd, out, n);
}

/* A light of power 1e70: every lit pixel is beyond the float range (at 100 the pixel values are far above
 * 1e-20, and 1e68 times that exceeds 3.4e38). The old code wrote +Inf into the gate image, the frames and the
 * cube and said "non-finite samples suppressed: 0". Now the film drops every contribution beyond 1e30 before it
 * is summed (film.h FILM_VALUE_MAX) and counts it: every file is finite, each pixel lit at power 100 is 0, and
 * the summary's count is at least the lit pixels of the gate image (each had a contribution in some pass) and
 * at most one per pass, pixel and image (gate and 2 frames). film_image's own guard for what still reaches
 * it (a NaN weight) is test_film_image_writes_nonfinite_as_zero. */
static void test_cli_nonfinite_pixels_never_written(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char out[16384], path[600];
    assert_int_equal(render_base(dir, "dim", "\"power\": 100", out, sizeof out), 0);
    long lit = 0, lit_gate = 0, bad = 0;
    const char *images[3] = {"", "_0000", "_0001"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/dim%s.pfm", dir, images[i]);
        long n = lit_pixels(path, &bad);
        lit += n;
        if (i == 0) lit_gate = n;
    }
    assert_int_equal(bad, 0);
    assert_true(lit_gate >= 8); /* the floor fills the lower half of the view */

    assert_int_equal(render_base(dir, "bright", "\"power\": 1e70", out, sizeof out), 0);
    long bright_lit = 0;
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/bright%s.pfm", dir, images[i]);
        bright_lit += lit_pixels(path, &bad);
    }
    assert_int_equal(bad, 0);
    assert_int_equal(bright_lit, 0); /* each lit pixel's contributions were dropped */
    snprintf(path, sizeof path, "%s/bright_cube.npy", dir);
    assert_int_equal(cube_nonfinite(path), 0);
    const char *at = strstr(out, "non-finite samples suppressed: ");
    assert_non_null(at);
    long suppressed = strtol(at + strlen("non-finite samples suppressed: "), NULL, 10);
    print_message("  lit pixels at power 100: %ld (gate %ld); suppressed at 1e70: %ld\n", lit, lit_gate, suppressed);
    assert_true(suppressed >= lit_gate);
    assert_true(suppressed <= 2L * 8 * 8 * 3);
}

/* ---- budgets that mean "forever" ---- */

/* BASE_SCENE with its renderer object replaced, written to <dir>/<name>. */
static void write_budget_scene(const char *dir, const char *name, const char *renderer, char *path, size_t n)
{
    char *text = replace1(BASE_SCENE, "\"renderer\": {\"spp\": 1, \"timeout\": \"0\"}", renderer);
    snprintf(path, n, "%s/%s", dir, name);
    test_write_file(path, text);
    free(text);
}

/* `--time 0` or `--spp 0` alone left nothing to end the render (the old code rendered until killed: here the
 * test's `timeout` interrupts it after 20 s, exit 130). Now exit 2 at once, naming the flag. */
static void test_cli_zero_budget_flag_alone_refused(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char scene_path[512], cmd[2048], out[8192];
    write_budget_scene(dir, "s.json", "\"renderer\": {\"spp\": 1}", scene_path, sizeof scene_path);
    const char *flags[2] = {"--time 0", "--spp 0"};
    for (int i = 0; i < 2; i++) {
        snprintf(cmd, sizeof cmd, "timeout --preserve-status -s INT 20 " DARTSPP_BIN " render %s %s --quiet --output %s/o.pfm",
                 scene_path, flags[i], dir);
        assert_int_equal(test_run(cmd, out, sizeof out), 2);
        ASSERT_CONTAINS(out, flags[i]);
        ASSERT_CONTAINS(out, "nothing would end the render");
    }
    snprintf(cmd, sizeof cmd, "%s/o.pfm", dir);
    assert_int_equal(access(cmd, F_OK), -1);
}

/* A negative scene timeout ("-5s") with spp 2: no time limit, said aloud with the key and the pass count that
 * ends the render, which renders its 2 passes. --spp on the command line replaces both limits: no warning. */
static void test_cli_negative_timeout_warns(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char scene_path[512], cmd[2048], out[8192];
    write_budget_scene(dir, "neg.json", "\"renderer\": {\"spp\": 2, \"timeout\": \"-5s\"}", scene_path,
                       sizeof scene_path);
    snprintf(cmd, sizeof cmd, "timeout -s INT 60 " DARTSPP_BIN " render %s --quiet --output %s/o.pfm", scene_path, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    ASSERT_CONTAINS(out, "neg.json: renderer.timeout \"-5s\" is negative, which means no time limit: the render "
                         "runs until its 2 passes (spp) are done, or until Ctrl-C");
    ASSERT_CONTAINS(out, "rendered 2 passes");
    snprintf(cmd, sizeof cmd, "timeout -s INT 60 " DARTSPP_BIN " render %s --spp 1 --quiet --output %s/o.pfm",
             scene_path, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_null(strstr(out, "renderer.timeout"));
    assert_null(strstr(out, "nothing bounds"));
}

/* Nothing bounds the render — the format's "timeout": -1 with spp 0, or --spp 0 --time 0 — : a warning at the
 * start says so and how to stop it; the test stops it with SIGINT after 4 s (exit 130, passes written). */
static void test_cli_unbounded_render_says_how_to_stop(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char scene_path[512], cmd[2048], out[8192];
    write_budget_scene(dir, "forever.json", "\"renderer\": {\"spp\": 0, \"timeout\": -1}", scene_path,
                       sizeof scene_path);
    snprintf(cmd, sizeof cmd, "timeout --preserve-status -s INT 4 " DARTSPP_BIN " render %s --quiet --output %s/o.pfm", scene_path, dir);
    int rc = test_run(cmd, out, sizeof out);
    ASSERT_CONTAINS(out, "forever.json: renderer.timeout \"-1\" is negative, which means no time limit, and spp is "
                         "0 (no pass limit): nothing bounds this render; it runs until Ctrl-C");
    assert_int_equal(rc, 130);

    write_budget_scene(dir, "s.json", "\"renderer\": {\"spp\": 1}", scene_path, sizeof scene_path);
    snprintf(cmd, sizeof cmd, "timeout --preserve-status -s INT 4 " DARTSPP_BIN " render %s --spp 0 --time 0 --quiet --output %s/o.pfm",
             scene_path, dir);
    rc = test_run(cmd, out, sizeof out);
    ASSERT_CONTAINS(out, "s.json: no time limit and no pass limit (--spp 0 --time 0): nothing bounds this render; "
                         "it runs until Ctrl-C");
    assert_int_equal(rc, 130);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_radius_zero_refused, teardown_fx),
        cmocka_unit_test_teardown(test_cli_gather_radius_zero, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_film_image_writes_nonfinite_as_zero, teardown_films),
        cmocka_unit_test_teardown(test_cli_nonfinite_pixels_never_written, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cli_zero_budget_flag_alone_refused, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cli_negative_timeout_warns, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cli_unbounded_render_says_how_to_stop, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
