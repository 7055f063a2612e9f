/* tier: quick */
/* `--derivative POINTER` (src/scene/diff_params.c; docs/derivatives.md §1): every kind of parameter resolves to
 * the diff_param the scene's own numbers give (worked out by hand from the file below: density·1 for σs, −η² for
 * a speed of light, 1/value for emission and albedo, the window's d_start and d_width), and every refusal fires
 * with the pointer and its reason in the message; one case through the command line. */
#include "fixtures.h"

/* Media: 0 fog (density 2, η 1/0.8, HG), 1 thin (σs 0 in channel 1, isotropic with a g written), 2 the inline
 * int_medium of primitive 2. BSDFs: 0–3 by name, 4 the inline one of primitive 2. Surfaces: primitive 0 → 0,
 * 2 → 1, 3 → 2. Lights: primitive 1 → 0, 2 → 1. */
static const char SCENE[] =
    "{\"media\": ["
    " {\"name\": \"fog\", \"sigma_s\": [0.5, 0.4, 0.3], \"sigma_a\": 0.1, \"density\": 2, \"speed_of_light\": 0.8,"
    "  \"phase_function\": {\"type\": \"henyey_greenstein\", \"g\": 0.3}},"
    " {\"name\": \"thin\", \"sigma_s\": [0.2, 0, 0.1], \"sigma_a\": 0.05,"
    "  \"phase_function\": {\"type\": \"isotropic\", \"g\": 0.5}}],"
    " \"bsdfs\": ["
    " {\"name\": \"white\", \"type\": \"lambert\", \"albedo\": [0.5, 0.6, 0.7]},"
    " {\"name\": \"shiny\", \"type\": \"plastic\", \"albedo\": 0.5},"
    " {\"name\": \"dark\", \"type\": \"lambert\", \"albedo\": [0.5, 0, 0.5]},"
    " {\"name\": \"tex\", \"type\": \"lambert\", \"albedo\": \"missing.png\"}],"
    " \"primitives\": ["
    " {\"type\": \"quad\", \"bsdf\": \"white\", \"transform\": {\"position\": [0, -1, 0], \"scale\": 4}},"
    " {\"type\": \"point\", \"emission\": [2, 3, 0], \"pulse_start\": 0.1, \"pulse_width\": 0.5,"
    "  \"transform\": {\"position\": [0, 1, 0]}, \"ext_medium\": \"fog\"},"
    " {\"type\": \"quad\", \"power\": 10, \"pulse_width\": 0.25, \"bsdf\": {\"type\": \"lambert\", \"albedo\": 0.8},"
    "  \"int_medium\": {\"name\": \"inl\", \"sigma_s\": 0.3, \"density\": 0.5}, \"ext_medium\": \"fog\","
    "  \"transform\": {\"position\": [1, 2, 3], \"look_at\": [0, 0, 0]}},"
    " {\"type\": \"cube\", \"bsdf\": \"white\", \"transform\": [1, 0, 0, 0.5, 0, 1, 0, 0.25, 0, 0, 1, 2, 0, 0, 0, 1]}],"
    " \"camera\": {\"resolution\": [8, 8], \"fov\": 40, \"medium\": \"fog\","
    "  \"transform\": {\"position\": [0, 0, -5], \"z_axis\": [0, 0, 1], \"up\": [0, 1, 0]}},"
    " \"integrator\": {\"type\": \"path_tracer\", \"max_bounces\": 4, \"transient_time_center\": 6,"
    "  \"transient_time_width\": 2, \"vaccum_speed_of_light\": 2},"
    " \"renderer\": {\"spp\": 1}}";

static int nload;
static scene cur; /* the last scene loaded, freed by the next load and by the teardown */
static int cur_live;

static void drop_cur(void)
{
    if (cur_live) scene_free(&cur);
    cur_live = 0;
}

/* The scene text with the pointers (and --set overrides) given; NULL with err on a refusal. */
static scene *load(const char *text, const char *const *ptrs, int n, const char *const *sets, int nsets, dp_error *err)
{
    char name[64];
    snprintf(name, sizeof name, "diff_%d.json", nload++);
    scene_load_options o = {.derivatives = ptrs, .derivative_count = n, .sets = sets, .set_count = nsets};
    drop_cur();
    if (load_text(fx_dir(), name, text, strlen(text), &o, &cur, err)) {
        if (!err->msg[0]) fail_msg("scene_load failed without a message");
        return NULL;
    }
    cur_live = 1;
    return &cur;
}

static int teardown(void **state)
{
    drop_cur();
    return teardown_fx(state);
}

static const diff_param *one(const char *ptr, const char *const *sets, int nsets)
{
    dp_error err;
    scene *s = load(SCENE, &ptr, 1, sets, nsets, &err);
    if (!s) fail_msg("%s refused: %s", ptr, err.msg);
    assert_int_equal(s->diff_count, 1);
    assert_string_equal(s->diffs[0].pointer, ptr);
    return &s->diffs[0];
}

#define TOL 1e-12
static void v3_is(vec3 got, double x, double y, double z, int line)
{
    check_close(got.x, x, TOL, line);
    check_close(got.y, y, TOL, line);
    check_close(got.z, z, TOL, line);
}

static void test_media(void **state)
{
    (void)state;
    const diff_param *d = one("/media/0/sigma_s", NULL, 0);
    assert_int_equal(d->kind, DIFF_MEDIUM);
    assert_int_equal(d->index, 0);
    v3_is(d->dsigma_s, 2, 2, 2, __LINE__); /* σs = density · sigma_s: ∂/∂sigma_s = density = 2 */
    v3_is(d->dsigma_a, 0, 0, 0, __LINE__);
    check_close(d->deta, 0, TOL, __LINE__);
    d = one("/media/0/sigma_s/1", NULL, 0);
    v3_is(d->dsigma_s, 0, 2, 0, __LINE__);
    d = one("/media/0/sigma_a", NULL, 0);
    v3_is(d->dsigma_a, 2, 2, 2, __LINE__);
    v3_is(d->dsigma_s, 0, 0, 0, __LINE__);
    d = one("/media/0/density", NULL, 0);
    v3_is(d->dsigma_s, 0.5, 0.4, 0.3, __LINE__);
    v3_is(d->dsigma_a, 0.1, 0.1, 0.1, __LINE__);
    d = one("/media/0/speed_of_light", NULL, 0);
    check_close(d->deta, -1.0 / (0.8 * 0.8), TOL, __LINE__); /* η = 1/v: −1/v² */
    v3_is(d->dsigma_s, 0, 0, 0, __LINE__);
    d = one("/integrator/vaccum_speed_of_light", NULL, 0);
    assert_int_equal(d->kind, DIFF_MEDIUM);
    assert_int_equal(d->index, MEDIUM_VACUUM);
    check_close(d->deta, -0.25, TOL, __LINE__);
    d = one("/media/0/phase_function/g", NULL, 0);
    assert_int_equal(d->kind, DIFF_PHASE_G);
    assert_int_equal(d->index, 0);
    d = one("/primitives/2/int_medium/sigma_s", NULL, 0);
    assert_int_equal(d->kind, DIFF_MEDIUM);
    assert_int_equal(d->index, 2);
    v3_is(d->dsigma_s, 0.5, 0.5, 0.5, __LINE__);
}

static void test_lights_and_bsdfs(void **state)
{
    (void)state;
    const diff_param *d = one("/primitives/1/emission/1", NULL, 0);
    assert_int_equal(d->kind, DIFF_EMISSION);
    assert_int_equal(d->index, 0);
    v3_is(d->dlog, 0, 1.0 / 3.0, 0, __LINE__);
    d = one("/primitives/2/power", NULL, 0);
    assert_int_equal(d->kind, DIFF_EMISSION);
    assert_int_equal(d->index, 1);
    v3_is(d->dlog, 0.1, 0.1, 0.1, __LINE__);
    d = one("/primitives/1/pulse_start", NULL, 0);
    assert_int_equal(d->kind, DIFF_PULSE_START);
    assert_int_equal(d->index, 0);
    d = one("/primitives/2/pulse_width", NULL, 0);
    assert_int_equal(d->kind, DIFF_PULSE_WIDTH);
    assert_int_equal(d->index, 1);
    d = one("/bsdfs/0/albedo", NULL, 0);
    assert_int_equal(d->kind, DIFF_ALBEDO);
    assert_int_equal(d->index, 0);
    v3_is(d->dlog, 2, 1 / 0.6, 1 / 0.7, __LINE__);
    d = one("/bsdfs/0/albedo/2", NULL, 0);
    v3_is(d->dlog, 0, 0, 1 / 0.7, __LINE__);
    d = one("/primitives/2/bsdf/albedo", NULL, 0);
    assert_int_equal(d->index, 4);
    v3_is(d->dlog, 1.25, 1.25, 1.25, __LINE__);
}

static void test_window_and_translations(void **state)
{
    (void)state;
    const diff_param *d = one("/integrator/transient_time_center", NULL, 0);
    assert_int_equal(d->kind, DIFF_WINDOW);
    check_close(d->d_start, 1, TOL, __LINE__);
    check_close(d->d_width, 0, TOL, __LINE__);
    d = one("/integrator/transient_time_width", NULL, 0); /* [c − w/2, c + w/2) */
    check_close(d->d_start, -0.5, TOL, __LINE__);
    check_close(d->d_width, 1, TOL, __LINE__);
    const char *frames[] = {"frame_num=3", "start_time=1"};
    d = one("/integrator/start_time", frames, 2);
    check_close(d->d_start, 1, TOL, __LINE__);
    check_close(d->d_width, 0, TOL, __LINE__);
    d = one("/integrator/transient_time_width", frames, 2); /* frames [start + k w, start + (k + 1) w) */
    check_close(d->d_start, 0, TOL, __LINE__);
    check_close(d->d_width, 1, TOL, __LINE__);
    d = one("/primitives/0/transform/position/0", NULL, 0);
    assert_int_equal(d->kind, DIFF_TRANSLATE);
    assert_int_equal(d->target, DIFF_TARGET_SURFACES);
    assert_int_equal(d->first_surface, 0);
    assert_int_equal(d->surface_count, 1);
    assert_int_equal(d->light, -1);
    v3_is(d->axis, 1, 0, 0, __LINE__);
    d = one("/primitives/3/transform/7", NULL, 0); /* row-major: element 7 is the y translation */
    assert_int_equal(d->target, DIFF_TARGET_SURFACES);
    assert_int_equal(d->first_surface, 2);
    v3_is(d->axis, 0, 1, 0, __LINE__);
    d = one("/primitives/1/transform/position/2", NULL, 0);
    assert_int_equal(d->target, DIFF_TARGET_LIGHT);
    assert_int_equal(d->light, 0);
    assert_int_equal(d->surface_count, 0);
    v3_is(d->axis, 0, 0, 1, __LINE__);
    d = one("/camera/transform/position/2", NULL, 0);
    assert_int_equal(d->target, DIFF_TARGET_CAMERA);
    v3_is(d->axis, 0, 0, 1, __LINE__);
    /* several at once, in order */
    const char *two[] = {"/media/0/sigma_a", "/bsdfs/0/albedo/0"};
    dp_error err;
    scene *s = load(SCENE, two, 2, NULL, 0, &err);
    if (!s) fail_msg("%s", err.msg);
    assert_int_equal(s->diff_count, 2);
    assert_int_equal(s->diffs[1].kind, DIFF_ALBEDO);
}

typedef struct {
    const char *ptr;
    const char *from, *to; /* one replacement in SCENE, or NULL */
    const char *set;       /* one --set, or NULL */
    const char *reason;    /* in the message, besides the file and the pointer */
} refusal;

static void test_refusals(void **state)
{
    (void)state;
    static const char *const W0 = "\"pulse_width\": 0.5";
    static const refusal cases[] = {
        {"media/0/sigma_s", NULL, NULL, NULL, "must start with '/'"},
        {"/media/0/sig~2ma_s", NULL, NULL, NULL, "bad escape '~2'"},
        {"/media/3/sigma_s", NULL, NULL, NULL, "names nothing: /media/3 does not exist (the array has 2 elements)"},
        {"/media/2/sigma_s", NULL, NULL, NULL, "names nothing: /media/2 does not exist (the array has 2 elements)"},
        {"/media/01/sigma_s", NULL, NULL, NULL, "not an array index"},
        {"/primitives/0/pulse_start", NULL, NULL, NULL, "names nothing: /primitives/0/pulse_start is not in the file"},
        {"/integrator/max_bounces", NULL, NULL, NULL, "not a parameter dartspp differentiates (it can:"},
        {"/renderer/spp", NULL, NULL, NULL, "not a parameter dartspp differentiates"},
        {"/media/0", NULL, NULL, NULL, "names an object, not a parameter"},
        {"/media/0/phase_function", NULL, NULL, NULL, "names an object"},
        {"/primitives/0/transform/position", NULL, NULL, NULL, "name one coordinate"},
        {"/media/0/sigma_a/1", NULL, NULL, NULL, "is inside a number"},
        {"/media/1/sigma_s/1", NULL, NULL, NULL, "sigma_s 0 in channel 1"},
        {"/media/1/sigma_s", NULL, NULL, NULL, "sigma_s 0 in channel 1"},
        {"/media/0/density", "\"density\": 2", "\"density\": 0", NULL, "sigma_s 0 in channel 0"},
        {"/media/1/phase_function/g", NULL, NULL, NULL, "isotropic phase function"},
        {"/primitives/1/emission", NULL, NULL, NULL, "emission 0 in channel 2"},
        {"/bsdfs/1/albedo", NULL, NULL, NULL, "not linear in its albedo"},
        {"/bsdfs/3/albedo", NULL, NULL, NULL, "textured albedo"},
        {"/bsdfs/2/albedo/1", NULL, NULL, NULL, "albedo 0 in channel 1"},
        {"/primitives/0/bsdf/albedo", NULL, NULL, NULL, "differentiate it at /bsdfs/0/"},
        {"/camera/medium/sigma_s", NULL, NULL, NULL, "'medium' names medium 'fog'; differentiate it at /media/0/"},
        {"/primitives/1/ext_medium/density", NULL, NULL, NULL, "differentiate it at /media/0/"},
        {"/primitives/2/transform/position/0", NULL, NULL, NULL, "has look_at"},
        {"/primitives/3/transform/0", NULL, NULL, NULL, "only the translation"},
        {"/primitives/1/pulse_start", W0, "\"pulse_width\": 0", NULL, "a delta pulse and a box gate"},
        {"/primitives/1/pulse_width", W0, "\"pulse_width\": 0", NULL, "pulse_width 0"},
        {"/integrator/transient_time_center", W0, "\"pulse_width\": 0", NULL, "light 'primitives[1]' has a delta"},
        {"/media/0/speed_of_light", W0, "\"pulse_width\": 0", NULL, "give the pulse a width or the sensor a response"},
        {"/camera/transform/position/0", W0, "\"pulse_width\": 0", NULL, "a delta pulse and a box gate"},
        {"/integrator/transient_time_width", NULL, NULL, "transient_time_width=0", "steady state"},
        {"/media/0/speed_of_light", NULL, NULL, "transient_time_width=0", "steady state"},
        {"/integrator/transient_time_width", "\"type\": \"path_tracer\"",
         "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"beams\", \"delta_time_gate\": true, \"volume_gather_radius\": 0.1, \"gather_radius\": 0.1",
         NULL, "delta_time_gate: the gate is an instant"},
        {"/integrator/transient_time_center", NULL, NULL, "frame_num=2", "transient_time_center is not read"},
        {"/integrator/start_time", NULL, NULL, "start_time=1", "read with frames only"},
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const refusal *r = &cases[i];
        char *text = r->from ? replace1(SCENE, r->from, r->to) : strdup(SCENE);
        assert_non_null(text);
        dp_error err = {0};
        scene *s = load(text, &r->ptr, 1, &r->set, r->set ? 1 : 0, &err);
        free(text);
        char want[300];
        snprintf(want, sizeof want, "--derivative %s: ", r->ptr);
        int ok = !s && strstr(err.msg, ".json: ") && strstr(err.msg, want) && strstr(err.msg, r->reason);
        print_message("[%s%s%s] %s\n", r->ptr, r->set ? " --set " : "", r->set ? r->set : "", s ? "(loaded)" : err.msg);
        if (!ok) failures++;
    }
    if (failures) fail_msg("%d refusals not as required", failures);
}

/* the sensor's response gives a delta pulse's path time a density: the same pointer then resolves */
static void test_response_allows_time(void **state)
{
    (void)state;
    char *text = replace1(SCENE, "\"pulse_width\": 0.5", "\"pulse_width\": 0");
    assert_non_null(text);
    const char *ptr = "/primitives/1/pulse_start", *set = "sensor_jitter_fwhm=0.1";
    dp_error err;
    scene *s = load(text, &ptr, 1, &set, 1, &err);
    free(text);
    if (!s) fail_msg("refused with the response on: %s", err.msg);
    assert_int_equal(s->diffs[0].kind, DIFF_PULSE_START);
}

static void test_count_and_duplicates(void **state)
{
    (void)state;
    const char *many[DIFF_PARAM_MAX + 1];
    for (int i = 0; i <= DIFF_PARAM_MAX; i++) many[i] = "/media/0/sigma_a";
    dp_error err;
    assert_null(load(SCENE, many, DIFF_PARAM_MAX + 1, NULL, 0, &err));
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, "at most 8"));
    const char *twice[] = {"/media/0/sigma_a", "/bsdfs/0/albedo", "/media/0/sigma_a"};
    assert_null(load(SCENE, twice, 3, NULL, 0, &err));
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, "--derivative /media/0/sigma_a: given twice (derivatives 1 and 3)"));
}

static void test_cli(void **state)
{
    (void)state;
    if (access(DARTSPP_BIN, X_OK) != 0) fail_msg("%s is missing: build it first", DARTSPP_BIN);
    char path[1100], exr[1100], cmd[3000];
    snprintf(path, sizeof path, "%s/cli.json", fx_dir());
    snprintf(exr, sizeof exr, "%s/cli.exr", fx_dir());
    write_bytes(path, SCENE, strlen(SCENE));
    static char out[16384];
    snprintf(cmd, sizeof cmd, "%s render '%s' --spp 1 --quiet --output '%s' --derivative /media/0/sigma_s "
             "--derivative /nope", DARTSPP_BIN, path, exr);
    int rc = test_run(cmd, out, 16384);
    print_message("exit %d: %s", rc, out);
    assert_int_equal(rc, 2);
    assert_non_null(strstr(out, "--derivative /nope: names nothing"));
    assert_non_null(strstr(out, "cli.json"));
    assert_int_equal(access(exr, F_OK), -1);
}

#define T(f) cmocka_unit_test_teardown(f, teardown)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_media), T(test_lights_and_bsdfs), T(test_window_and_translations), T(test_refusals),
        T(test_response_allows_time), T(test_count_and_duplicates), T(test_cli),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
