/* tier: stress */
/* Derivative images against central finite differences with common random numbers (docs/derivatives.md §7):
 * per pass and per image tile, (I(θ + ε) − I(θ − ε))/(2ε) from two renders of the same seed against the
 * derivative image of a third render of that seed at θ; the paired per-pass differences give a z-test per tile
 * and on the image total. Every parameter kind the path tracers differentiate, on the fog box with a point light
 * of a box pulse, with the plain, DARTS and uniform-time path tracers. */
#include "fixtures.h"
#include "render_fixtures.h"

#include "dartspp/derivative.h"

/* The scene with θ written in: %s slots for every parameter, filled from a table of values. */
enum { P_SIGMA_S, P_SIGMA_A, P_G, P_POWER, P_PULSE_START, P_PULSE_WIDTH, P_CENTER, P_WIDTH, P_ALBEDO, P_SPEED, P_COUNT };
static const double BASE[P_COUNT] = {0.45, 0.05, 0.3, 4.0, 0.2, 0.6, 4.2, 1.5, 0.7, 1.0};

static double fd_rel = 0.05;

/* walls: the box's floor, back and red wall (surface paths, the albedo); without: an unbounded fog, where the
 * paths of θ ± ε with common random numbers differ smoothly (no path leaves a wall for another). */
static int walls = 1;
/* steady: no gate (the coefficients' finite differences in a gate are dominated by contributions whose sampled
 * emission time carries them across the gate's edges: a step that common random numbers cannot make smooth) */
static int steady = 0;
/* area_light: a quad emitter instead of the collimated beam */
static int area_light = 0;

static void scene_text(char *text, size_t n, const double *v, const char *integrator)
{
    char prims[1024] = "";
    if (walls)
        snprintf(prims, sizeof prims, "%s",
                 "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [2, 1, 2] } },"
                 "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, 1], \"scale\": [2, 1, 2],"
                 "      \"rotation\": [-90, 0, 0] } },"
                 "    { \"type\": \"quad\", \"bsdf\": \"red\", \"transform\": { \"position\": [1, 1, 0], \"scale\": [2, 1, 2],"
                 "      \"rotation\": [0, 0, 90] } },");
    char light[1024];
    if (area_light) /* a panel facing down into the fog: the DARTS path tracer aims at it */
        snprintf(light, sizeof light,
                 "{ \"type\": \"quad\", \"bsdf\": \"white\", \"emission\": %.17g, \"pulse_start\": %.17g,"
                 "  \"pulse_width\": %.17g, \"int_medium\": \"fog\", \"ext_medium\": \"fog\","
                 "  \"transform\": { \"position\": [0.3, 1.9, 0.1], \"scale\": [0.8, 1, 0.8], \"rotation\": [180, 0, 0] } }",
                 v[P_POWER], v[P_PULSE_START], v[P_PULSE_WIDTH]);
    else /* a collimated beam: no 1/r² singularity (docs/derivatives.md §7) */
        snprintf(light, sizeof light,
                 "{ \"type\": \"collimated\", \"radius\": 0.3, \"emission\": %.17g, \"pulse_start\": %.17g,"
                 "  \"pulse_width\": %.17g, \"ext_medium\": \"fog\","
                 "  \"transform\": { \"position\": [-1.2, 1.6, 0.2], \"look_at\": [1, 0.6, 0.4], \"up\": [0, 1, 0] } }",
                 v[P_POWER], v[P_PULSE_START], v[P_PULSE_WIDTH]);
    snprintf(text, n,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"guided_homo\", \"sigma_s\": %.17g, \"sigma_a\": %.17g,"
             "    \"speed_of_light\": %.17g, \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": %.17g } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": %.17g },"
             "               { \"name\": \"red\", \"type\": \"lambert\", \"albedo\": [0.7, 0.15, 0.1] } ],"
             "  \"primitives\": [ %s"
             "    %s ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 1, -2.5], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 4, \"transient_time_center\": %.17g,"
             "    \"transient_time_width\": %.17g %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             v[P_SIGMA_S], v[P_SIGMA_A], v[P_SPEED], v[P_G], v[P_ALBEDO], prims, light,
             v[P_CENTER], steady ? 0.0 : v[P_WIDTH], integrator);
}

typedef deriv_tiles fd_probe; /* render_fixtures.h: per pass the gate image's tiles, then the derivative's */

static void render_probe_fd(const char *text, const char *pointer, long passes, fd_probe *t)
{
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    scene_load_options lo = {.derivatives = &pointer, .derivative_count = pointer ? 1 : 0};
    dp_error err;
    if (scene_load(ts.path, &lo, &s, &err)) fail_msg("%s", err.msg);
    deriv_tiles_render(&s, 1, passes, 11, t, NULL); /* one layout with and without the derivative (0 without) */
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* The finite difference against the derivative, per tile and on the total: returns the largest |z|. */
static double fd_compare(const char *label, int p, const char *pointer, const char *integrator, long passes)
{
    /* ε: 5 % of a coefficient; 0.05 of the time unit for the pulse and the gate (their curvature is on the scale
     * of the pulse's width) */
    int timing = p == P_PULSE_START || p == P_PULSE_WIDTH || p == P_CENTER || p == P_WIDTH;
    double lo[P_COUNT], hi[P_COUNT], eps = timing ? 0.05 : fd_rel * BASE[p];
    memcpy(lo, BASE, sizeof lo);
    memcpy(hi, BASE, sizeof hi);
    lo[p] -= eps, hi[p] += eps;
    static char text[8192];
    fd_probe a, b, d;
    scene_text(text, sizeof text, lo, integrator);
    render_probe_fd(text, NULL, passes, &a);
    scene_text(text, sizeof text, hi, integrator);
    render_probe_fd(text, NULL, passes, &b);
    scene_text(text, sizeof text, BASE, integrator);
    render_probe_fd(text, pointer, passes, &d);
    double zmax = 0.0, tot_fd = 0.0, tot_d = 0.0, s_e = 0.0, s_e2 = 0.0;
    for (long i = 0; i < passes; i++) {
        double e_tot = 0.0;
        for (int v = 0; v < NT; v++) {
            double fd = (b.x[i * 2 * NT + v] - a.x[i * 2 * NT + v]) / (2.0 * eps), dv = d.x[i * 2 * NT + NT + v];
            tot_fd += fd / passes, tot_d += dv / passes, e_tot += fd - dv;
        }
        s_e += e_tot, s_e2 += e_tot * e_tot;
    }
    for (int v = 0; v < NT; v++) {
        double s1 = 0, s2 = 0;
        for (long i = 0; i < passes; i++) {
            double e = (b.x[i * 2 * NT + v] - a.x[i * 2 * NT + v]) / (2.0 * eps) - d.x[i * 2 * NT + NT + v];
            s1 += e, s2 += e * e;
        }
        double m = s1 / passes, se = sqrt(fmax(0.0, (s2 - passes * m * m) / (passes - 1)) / passes);
        double z = se > 0 ? fabs(m) / se : (m == 0 ? 0 : INFINITY);
        if (z > zmax) zmax = z;
    }
    double m = s_e / passes, se = sqrt(fmax(0.0, (s_e2 - passes * m * m) / (passes - 1)) / passes);
    double zt = se > 0 ? fabs(m) / se : 0.0;
    print_message("  %-28s total dI %.5g, finite difference %.5g (%+.2f %%), |z| %.2f total, max |z| %.2f over %d tiles\n",
                  label, tot_d, tot_fd, 100.0 * (tot_d - tot_fd) / fabs(tot_fd), zt, zmax, NT);
    free(a.x), free(b.x), free(d.x);
    return fmax(zmax, zt);
}

/* The pointer of parameter p in scene_text's file (the light is the last primitive). */
static void pointer_of(int p, char *out, size_t n)
{
    int light = walls ? 3 : 0;
    switch (p) {
    case P_SIGMA_S: snprintf(out, n, "/media/0/sigma_s"); break;
    case P_SIGMA_A: snprintf(out, n, "/media/0/sigma_a"); break;
    case P_G: snprintf(out, n, "/media/0/phase_function/g"); break;
    case P_POWER: snprintf(out, n, "/primitives/%d/emission", light); break;
    case P_PULSE_START: snprintf(out, n, "/primitives/%d/pulse_start", light); break;
    case P_PULSE_WIDTH: snprintf(out, n, "/primitives/%d/pulse_width", light); break;
    case P_CENTER: snprintf(out, n, "/integrator/transient_time_center"); break;
    case P_WIDTH: snprintf(out, n, "/integrator/transient_time_width"); break;
    case P_ALBEDO: snprintf(out, n, "/bsdfs/0/albedo"); break;
    default: snprintf(out, n, "/media/0/speed_of_light"); break;
    }
}

static const char *const NAMES[P_COUNT] = {"sigma_s", "sigma_a", "g", "emission", "pulse_start", "pulse_width",
                                           "transient_time_center", "transient_time_width", "albedo", "speed_of_light"};

/* Every kind with one integrator: the coefficients in steady state, the rest in the gate; the albedo with the
 * walls, the rest in the unbounded fog. */
static void run_kinds(const char *integrator, long passes)
{
    for (int p = 0; p < P_COUNT; p++) {
        walls = p == P_ALBEDO || getenv("FD_WALLS") || area_light;
        steady = (p == P_SIGMA_S || p == P_SIGMA_A || p == P_G) && !getenv("FD_GATED");
        char pointer[64], label[96];
        pointer_of(p, pointer, sizeof pointer);
        snprintf(label, sizeof label, "%s%s", NAMES[p], steady ? " (steady)" : "");
        double z = fd_compare(label, p, pointer, integrator, passes);
        assert_true(z < 4.0);
    }
}

static long fd_passes(long def) { return getenv("FD_PASSES") ? atol(getenv("FD_PASSES")) : def; }

static void test_plain(void **state)
{
    (void)state;
    area_light = 0;
    run_kinds("", fd_passes(3000));
}

static void test_darts(void **state)
{
    (void)state;
    area_light = 1;
    run_kinds(", " DARTS_KEYS_TEXT, fd_passes(3000));
}

static void test_uniform_time(void **state)
{
    (void)state;
    area_light = 1;
    run_kinds(", \"time_sampling\": \"uniform\"", fd_passes(3000));
}

/* `make test`'s subset: the emission and the albedo, whose finite differences with common random numbers are
 * exact (the image is linear in them: same paths, scaled weights), so 200 passes resolve them */
static void test_linear_kinds(void **state)
{
    (void)state;
    area_light = 0;
    int kinds[2] = {P_POWER, P_ALBEDO};
    for (int i = 0; i < 2; i++) {
        int p = kinds[i];
        walls = p == P_ALBEDO;
        steady = 0;
        char pointer[64];
        pointer_of(p, pointer, sizeof pointer);
        assert_true(fd_compare(NAMES[p], p, pointer, "", 200) < 4.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_linear_kinds)};
    const struct CMUnitTest stress[] = {cmocka_unit_test(test_plain), cmocka_unit_test(test_darts),
                                        cmocka_unit_test(test_uniform_time)};
    return RUN_TESTS_AND_STRESS(tests, stress);
}
