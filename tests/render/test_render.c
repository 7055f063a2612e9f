/* tier: quick */
/* Path tracer end to end: determinism across thread counts, frames against the union gate, finite
 * outputs of the command line on our fog Cornell box (scenes/cbox-fog, the paper's fog box rebuilt from
 * quads and cubes) and the demo scene. */
#include "render_fixtures.h"

/* What a test allocates lives here, so that the teardown frees it even when an assertion fails part-way
 * (LeakSanitizer then reports nothing but the real failure). scene_free, film_free and image_free accept
 * zeroed and already freed values. */
static struct {
    scene scenes[3];
    film films[3];
    image_rgb images[8];
    char *dir;
} fx;

static int teardown_fx(void **state)
{
    (void)state;
    for (int i = 0; i < 3; i++) scene_free(&fx.scenes[i]);
    for (int i = 0; i < 3; i++) film_free(&fx.films[i]);
    for (int i = 0; i < 8; i++) image_free(&fx.images[i]);
    if (fx.dir) {
        char cmd[1200];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", fx.dir);
        (void)!system(cmd);
        free(fx.dir);
    }
    memset(&fx, 0, sizeof fx);
    return 0;
}

static void render(const scene *s, int threads, uint64_t seed, long passes, film *f)
{
    dp_error err;
    render_stats st;
    render_options ro = {.threads = threads, .seed = seed, .spp = passes, .time_limit = 0};
    if (render_scene(s, &ro, f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.passes, passes);
    assert_int_equal(st.nonfinite, 0);
}

/* Same seed, 1 vs 2 threads: bit-identical sums, on our fog Cornell box (gated so that time matters). */
static void test_threads_bit_identical(void **state)
{
    (void)state;
    const char *sets[] = {"transient_time_center=14", "transient_time_width=2"};
    scene *s = &fx.scenes[0];
    load_scene(CBOX_FOG "/path_tracer.json", sets, 2, s);
    s->cam.width = 48;
    s->cam.height = 40;
    film *a = &fx.films[0], *b = &fx.films[1], *c = &fx.films[2];
    render(s, 1, 7, 3, a);
    render(s, 2, 7, 3, b);
    size_t n = (size_t)s->cam.width * s->cam.height * 3;
    double total = 0;
    for (size_t i = 0; i < n; i++) total += a->sum[i];
    assert_true(total > 0); /* the comparison is not between two black images */
    assert_memory_equal(a->sum, b->sum, n * sizeof(double));
    render(s, 2, 8, 3, c); /* and a different seed does change it */
    assert_true(memcmp(a->sum, c->sum, n * sizeof(double)) != 0);
}

/* Replaces the bsdf of the box wall whose transform starts with `where` by a smooth gold rough conductor. */
static void make_wall_glossy(char *text, size_t len, const char *where)
{
    char key[160], *at;
    snprintf(key, sizeof key, "\"bsdf\": \"white\", \"transform\": { \"position\": %s", where);
    if (!(at = strstr(text, key))) {
        snprintf(key, sizeof key, "\"bsdf\": \"green\", \"transform\": { \"position\": %s", where);
        at = strstr(text, key);
    }
    assert_non_null(at);
    const char *glossy = "\"bsdf\": { \"type\": \"rough_conductor\", \"material\": \"Au\", \"roughness\": 0.05 }";
    size_t old_len = strlen(at) - strlen(strstr(at, ", \"transform\""));
    assert_true(strlen(text) - old_len + strlen(glossy) < len);
    memmove(at + strlen(glossy), at + old_len, strlen(at + old_len) + 1);
    memcpy(at, glossy, strlen(glossy));
}

/* glossy_regularization acts only at camera vertices reached through a glossy bounce: with one glossy wall
 * (the back wall: the camera's glossy hits continue to diffuse walls and the fog, which are gathered) the
 * image is bit-identical to the unregularized one; with the left wall glossy too (back → left → light
 * connection) it changes. */
static void test_glossy_regularization_scope(void **state)
{
    (void)state;
    const char *integ = "\"type\": \"progressive_transient_photon_map\", \"photon_count\": 3000,"
                        " \"volume_photon_count\": 3000, \"gather_radius\": 0.2, \"volume_gather_radius\": 0.2,"
                        " \"max_bounces\": 6";
    const char *on[] = {"glossy_regularization=0.6"};
    for (int walls = 1; walls <= 2; walls++) {
        char text[8192];
        box_scene_text(text, sizeof text, 12, integ);
        make_wall_glossy(text, sizeof text, "[0, 1, 1]");
        if (walls == 2) make_wall_glossy(text, sizeof text, "[-1, 1, 0]");
        tmp_scene t;
        tmp_scene_write(&t, text);
        load_scene(t.path, NULL, 0, &fx.scenes[0]);
        load_scene(t.path, on, 1, &fx.scenes[1]);
        tmp_scene_remove(&t);
        render(&fx.scenes[0], 2, 5, 2, &fx.films[0]);
        render(&fx.scenes[1], 2, 5, 2, &fx.films[1]);
        size_t n = (size_t)12 * 12 * 3;
        double total = 0;
        for (size_t i = 0; i < n; i++) total += fx.films[0].sum[i];
        assert_true(total > 0);
        int same = memcmp(fx.films[0].sum, fx.films[1].sum, n * sizeof(double)) == 0;
        if (walls == 1 && !same) fail_msg("one glossy wall: the regularization changed the image");
        if (walls == 2 && same) fail_msg("two glossy walls: the regularization changed nothing");
        for (int i = 0; i < 2; i++) {
            scene_free(&fx.scenes[i]);
            film_free(&fx.films[i]);
        }
    }
}

/* Frames k of width w over [start, start + F w) summed and divided by F equal the gate image of the union
 * window rendered with the same seed; each frame equals the gate image of its own window. */
static void test_frames_sum_to_union_gate(void **state)
{
    (void)state;
    /* the plain path tracer: the same random numbers whatever the window (DARTS aims each path at one frame) */
    const char *frames[] = {"frame_num=4", "start_time=7", "transient_time_width=0.5", "type=path_tracer",
                            "enable_guiding=false", "enable_elliptical=false"};
    const char *gate[] = {"transient_time_center=8", "transient_time_width=2", "type=path_tracer",
                          "enable_guiding=false", "enable_elliptical=false"};
    const char *gate1[] = {"transient_time_center=7.25", "transient_time_width=0.5", "type=path_tracer",
                           "enable_guiding=false", "enable_elliptical=false"};
    scene *sf = &fx.scenes[0], *sg = &fx.scenes[1], *s1 = &fx.scenes[2];
    load_scene("scenes/fogbox/fogbox.json", frames, 6, sf);
    load_scene("scenes/fogbox/fogbox.json", gate, 5, sg);
    load_scene("scenes/fogbox/fogbox.json", gate1, 5, s1);
    sf->cam.width = sg->cam.width = s1->cam.width = 32;
    sf->cam.height = sg->cam.height = s1->cam.height = 32;
    film *ff = &fx.films[0], *fg = &fx.films[1], *f1 = &fx.films[2];
    render(sf, 2, 3, 4, ff);
    render(sg, 2, 3, 4, fg);
    render(s1, 2, 3, 4, f1);
    dp_error err;
    image_rgb *union_img = &fx.images[0], *gate_img = &fx.images[1], *gate1_img = &fx.images[2];
    image_rgb *frame = &fx.images[3]; /* 4 frames */
    assert_int_equal(film_image(fg, -1, gate_img, &err), 0);
    assert_int_equal(film_image(ff, -1, union_img, &err), 0);
    assert_int_equal(film_image(f1, -1, gate1_img, &err), 0);
    for (int k = 0; k < 4; k++) assert_int_equal(film_image(ff, k, &frame[k], &err), 0);
    size_t n = 32 * 32 * 3;
    double total = 0, max_rel = 0, max_rel1 = 0;
    for (size_t i = 0; i < n; i++) {
        double sum = 0;
        for (int k = 0; k < 4; k++) sum += frame[k].rgb[i];
        double g = gate_img->rgb[i];
        total += g;
        assert_float_equal(union_img->rgb[i], g, 1e-6 * fabs(g) + 1e-30);
        max_rel = fmax(max_rel, fabs(sum / 4 - g) / fmax(fabs(g), 1e-12));
        max_rel1 = fmax(max_rel1, fabs(frame[0].rgb[i] - gate1_img->rgb[i]) / fmax(fabs(gate1_img->rgb[i]), 1e-12));
    }
    assert_true(total > 0);
    assert_true(max_rel < 1e-5);  /* frames are summed in float */
    assert_true(max_rel1 < 1e-5);
}

/* The film's weighted mean, against values worked by hand: pixel 0 gets 2 then 5 (gate) with weights 1 and
 * 3, so (1·2 + 3·5)/4 = 4.25; frame 1 gets only the second pass's 8: 3·8/4 = 6. Broken variants (dividing
 * by the pass count, or dropping the weight of the frames) give 8.5 and 2.5. */
static void test_film_weighted_mean(void **state)
{
    (void)state;
    film *f = &fx.films[0];
    dp_error err;
    time_window tw = {.gated = 1, .start = 0.0, .width = 1.0, .frame_count = 2};
    if (film_init(f, 2, 1, &tw, &err)) fail_msg("%s", err.msg);
    /* gate image weight 1/(width·frames) = 1/2, frame weight 1/width = 1: splat 2·value into frame 0's
     * window for the gate, and value into frame 1's window */
    assert_true(film_splat(f, 0, 0.5, v3s(4.0), -1, 0));
    film_commit_pass(f, 1.0);
    assert_true(film_splat(f, 0, 1.5, v3s(10.0), -1, 0));
    film_commit_pass(f, 3.0);
    assert_int_equal(f->passes, 2);
    image_rgb *gate = &fx.images[0], *fr1 = &fx.images[1];
    assert_int_equal(film_image(f, -1, gate, &err), 0);
    assert_int_equal(film_image(f, 1, fr1, &err), 0);
    assert_float_equal(gate->rgb[0], (1.0 * 2.0 + 3.0 * 5.0) / 4.0, 1e-6);
    assert_float_equal(fr1->rgb[0], 3.0 * 10.0 / 4.0, 1e-6);
    assert_float_equal(gate->rgb[3], 0.0, 0.0); /* pixel 1 saw nothing */
}

/* plan_pass_weight: the path tracer and pass_weights "equal" weigh 1; photon points weigh iteration i by its
 * kernel area relative to iteration 0, (Π_{j=1..i} (j+α)/(j+1)) for the surface kernel (written here as
 * Γ(i+1+α)/(Γ(1+α)Γ(i+2)), not with the schedule's own product), and the volume kernel's area when no
 * surfaces are gathered (the 3-D schedule: area ∝ γ^{2/3}). */
static void test_pass_weights(void **state)
{
    (void)state;
    const char *pp[] = {"type=progressive_transient_photon_map", "alpha=0.7", "volume_alpha=0.8", "volume_gather_radius=0.1",
                        "gather_radius=0.05"};
    const char *vol[] = {"type=progressive_transient_photon_map", "alpha=0.7", "volume_alpha=0.8", "volume_gather_radius=0.1",
                         "include_surfaces=false", "radius_schedule=3d"};
    const char *eq[] = {"type=progressive_transient_photon_map", "pass_weights=equal"};
    const char *pt[] = {"type=path_tracer"};
    load_scene("scenes/fogbox/fogbox.json", pp, 5, &fx.scenes[0]);
    load_scene("scenes/fogbox/fogbox.json", vol, 6, &fx.scenes[1]);
    load_scene("scenes/fogbox/fogbox.json", eq, 2, &fx.scenes[2]);
    render_plan p[3], q;
    dp_error err;
    for (int k = 0; k < 3; k++)
        if (plan_resolve(&fx.scenes[k], &p[k], &err)) fail_msg("%s", err.msg);
    const long its[] = {0, 1, 2, 9, 200};
    for (size_t k = 0; k < sizeof its / sizeof *its; k++) {
        long i = its[k];
        double g_s = exp(lgamma(i + 1.7) - lgamma(1.7) - lgamma(i + 2.0));
        double g_v = exp(lgamma(i + 1.8) - lgamma(1.8) - lgamma(i + 2.0));
        assert_float_equal(plan_pass_weight(&p[0], i), g_s, 1e-12 * g_s + 1e-15);
        assert_float_equal(plan_pass_weight(&p[1], i), pow(g_v, 2.0 / 3.0), 1e-12);
        assert_float_equal(plan_pass_weight(&p[2], i), 1.0, 0.0);
    }
    assert_true(plan_pass_weight(&p[0], 200) < 0.25); /* the weights do fall */
    scene_free(&fx.scenes[2]);
    load_scene("scenes/fogbox/fogbox.json", pt, 1, &fx.scenes[2]);
    if (plan_resolve(&fx.scenes[2], &q, &err)) fail_msg("%s", err.msg);
    assert_float_equal(plan_pass_weight(&q, 50), 1.0, 0.0);
    for (int k = 0; k < 3; k++) plan_free(&p[k]);
    plan_free(&q);
}

/* Reads into the fixture's last image slot (freed by the teardown if an assertion fails). */
static void assert_all_finite(const char *path)
{
    image_rgb *img = &fx.images[7];
    dp_error err;
    if (image_read(path, img, &err)) fail_msg("%s", err.msg);
    size_t n = (size_t)img->width * img->height * 3, nonzero = 0;
    for (size_t i = 0; i < n; i++) {
        assert_true(isfinite(img->rgb[i]));
        assert_true(img->rgb[i] >= 0);
        nonzero += img->rgb[i] > 0;
    }
    assert_true(nonzero > n / 10);
    image_free(img);
}

/* The command line on our fog Cornell box (gated) and the demo scene (as a 3-frame transient): exit 0,
 * the files it reports exist, no NaN or Inf in any output. */
static void test_cli_outputs_finite(void **state)
{
    (void)state;
    char cmd[2048], out[8192], path[1024];
    const char *dir = fx.dir = test_tmpdir();
    assert_non_null(dir);
    snprintf(cmd, sizeof cmd,
             DARTSPP_BIN " render " CBOX_FOG "/path_tracer.json --spp 2 --quiet --seed 3 --set transient_time_center=12"
                         " --set transient_time_width=4 --output %s/pt.exr",
             dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "wrote"));
    snprintf(path, sizeof path, "%s/pt.exr", dir);
    assert_all_finite(path);
    snprintf(path, sizeof path, "%s/pt.png", dir);
    assert_int_equal(access(path, R_OK), 0);

    snprintf(cmd, sizeof cmd,
             DARTSPP_BIN " render scenes/fogbox/fogbox.json --spp 2 --quiet --set frame_num=3 --set start_time=5"
                         " --set transient_time_width=1 --output %s/fb.pfm",
             dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/fb_%04d.pfm", dir, k);
        assert_all_finite(path);
    }
    snprintf(path, sizeof path, "%s/fb_frames.csv", dir);
    assert_int_equal(access(path, R_OK), 0);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s/fb_0001.pfm %s/fb_0001.pfm --csv", dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_true(strncmp(out, "0,0,0,0,", 8) == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_threads_bit_identical, teardown_fx),
        cmocka_unit_test_teardown(test_film_weighted_mean, teardown_fx),
        cmocka_unit_test_teardown(test_pass_weights, teardown_fx),
        cmocka_unit_test_teardown(test_frames_sum_to_union_gate, teardown_fx),
        cmocka_unit_test_teardown(test_cli_outputs_finite, teardown_fx),
        cmocka_unit_test_teardown(test_glossy_regularization_scope, teardown_fx),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
