/* Derivative images of photon points (docs/derivatives.md §4) against the path tracer's (themselves checked
 * against finite differences by tests/derivative/test_deriv_fd.c): per image tile, the mean over the passes of
 * each render and a z-test with a bias budget, as the photon-points tile tests compare primal images (photon
 * points are consistent, not unbiased: the kernel smooths). Every parameter kind, baseline and DARTS photon
 * pass, on the fog box of test_deriv_fd.c (a collimated beam of radius 0.3, no point-light singularity, floor,
 * back and red wall for the albedo), gated, 8 × 8 pixels. Also the identity ∂I/∂(pulse start) = −∂I/∂(gate
 * centre), exact pixel by pixel, and the refusal of the other volume photon types. */
#include "fixtures.h"
#include "render_fixtures.h"

#include "dartspp/derivative.h"

enum { P_SIGMA_S, P_SIGMA_A, P_G, P_POWER, P_PULSE_START, P_CENTER, P_WIDTH, P_ALBEDO, P_SPEED, P_PULSE_WIDTH, P_COUNT };
static const char *const NAMES[P_COUNT] = {"sigma_s", "sigma_a", "g", "power", "pulse_start", "gate_centre",
                                           "gate_width", "albedo", "speed_of_light", "pulse_width"};
#define SIGMA_S 0.45
#define POWER 4.0
#define ALBEDO 0.7
#define SPEED 1.0

static void scene_text(char *text, size_t n, const char *integrator)
{
    snprintf(text, n,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": %g, \"sigma_a\": 0.05,"
             "    \"speed_of_light\": %g, \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.3 } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": %g },"
             "               { \"name\": \"red\", \"type\": \"lambert\", \"albedo\": [0.7, 0.15, 0.1] } ],"
             "  \"primitives\": ["
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [2, 1, 2] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, 1], \"scale\": [2, 1, 2],"
             "      \"rotation\": [-90, 0, 0] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"red\", \"transform\": { \"position\": [1, 1, 0], \"scale\": [2, 1, 2],"
             "      \"rotation\": [0, 0, 90] } },"
             "    { \"type\": \"collimated\", \"radius\": 0.3, \"emission\": %g, \"pulse_start\": 0.2,"
             "      \"pulse_width\": 0.6, \"ext_medium\": \"fog\","
             "      \"transform\": { \"position\": [-1.2, 1.6, 0.2], \"look_at\": [1, 0.6, 0.4], \"up\": [0, 1, 0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 1, -2.5], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"max_bounces\": 4, \"transient_time_center\": 4.2, \"transient_time_width\": 1.5, %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             SIGMA_S, SPEED, ALBEDO, POWER, integrator);
}

static diff_param param(int p)
{
    switch (p) {
    case P_SIGMA_S: return (diff_param){.kind = DIFF_MEDIUM, .dsigma_s = v3s(1)};
    case P_SIGMA_A: return (diff_param){.kind = DIFF_MEDIUM, .dsigma_a = v3s(1)};
    case P_G: return (diff_param){.kind = DIFF_PHASE_G};
    case P_POWER: return (diff_param){.kind = DIFF_EMISSION, .dlog = v3s(1.0 / POWER)};
    case P_PULSE_START: return (diff_param){.kind = DIFF_PULSE_START};
    case P_CENTER: return (diff_param){.kind = DIFF_WINDOW, .index = -1, .d_start = 1.0};
    case P_WIDTH: return (diff_param){.kind = DIFF_WINDOW, .index = -1, .d_start = -0.5, .d_width = 1.0};
    case P_ALBEDO: return (diff_param){.kind = DIFF_ALBEDO, .dlog = v3s(1.0 / ALBEDO)};
    case P_SPEED: return (diff_param){.kind = DIFF_MEDIUM, .deta = -1.0 / (SPEED * SPEED)};
    default: return (diff_param){.kind = DIFF_PULSE_WIDTH};
    }
}

#define MAXK DIFF_PARAM_MAX
typedef deriv_tiles probe; /* render_fixtures.h */

/* Renders the scene with derivatives ps[0..k) into t; *out (may be NULL) keeps the final film. */
static void render_derivs(const char *integrator, const int *ps, int k, long passes, uint64_t seed, probe *t, film *out)
{
    static char text[8192];
    scene_text(text, sizeof text, integrator);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    for (int i = 0; i < k; i++) s.diffs[i] = param(ps[i]);
    s.diff_count = k;
    deriv_tiles_render(&s, k, passes, seed, t, out);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static void mean_se(const probe *t, int v, double *mean, double *se)
{
    int m = (1 + t->k) * NT;
    double s = 0, s2 = 0;
    for (long i = 0; i < t->n; i++) {
        double x = t->x[(size_t)i * m + v];
        s += x, s2 += x * x;
    }
    *mean = s / t->n;
    *se = sqrt(fmax(0.0, (s2 - t->n * *mean * *mean) / (t->n - 1)) / t->n);
}

/* The bias budget: a fraction of the image's scale, the mean |tile| of the reference's derivative image (the
 * kernel moves light between neighbouring tiles, by an amount set by the image's magnitude, also where a
 * derivative tile crosses 0). Primal photon-points tile tests use 3 % at r = 0.08 (test_emitters_render.c);
 * derivative images are steeper (they hold the light's time profile's slope), so twice that. */
#define BIAS 0.06
#define Z_LIMIT 4.5

/* Image k (0: the gate image, 1 + j: derivative j) of m against ref: prints and returns the largest |z| over the
 * tiles and the total. */
static double compare(const char *label, const probe *ref, const probe *m, int k)
{
    double scale = 0.0, tot_r = 0, tot_m = 0, var_r = 0, var_m = 0, zmax = 0.0;
    for (int v = 0; v < NT; v++) {
        double mr, sr;
        mean_se(ref, k * NT + v, &mr, &sr);
        scale += fabs(mr) / NT;
    }
    for (int v = 0; v < NT; v++) {
        double mr, sr, mm, sm;
        mean_se(ref, k * NT + v, &mr, &sr);
        mean_se(m, k * NT + v, &mm, &sm);
        tot_r += mr, tot_m += mm, var_r += sr * sr, var_m += sm * sm;
        double se = sqrt(sr * sr + sm * sm), d = fmax(0.0, fabs(mm - mr) - BIAS * scale);
        double z = se > 0.0 ? d / se : (d > 0.0 ? INFINITY : 0.0);
        zmax = fmax(zmax, z);
    }
    double zt = fmax(0.0, fabs(tot_m - tot_r) - BIAS * scale * NT) / sqrt(var_r + var_m);
    print_message("  %-34s dI total %.5g (se %.2g) vs path tracer %.5g (se %.2g), %+.2f %%; |z| total %.2f, max |z| "
                  "%.2f over %d tiles\n", label, tot_m, sqrt(var_m), tot_r, sqrt(var_r),
                  100.0 * (tot_m - tot_r) / fabs(tot_r), zt, zmax, NT);
    assert_true(scale > 0.0);
    return fmax(zmax, zt);
}

#define PT_KEYS "\"type\": \"path_tracer\""
/* the keys of photon points but its volume photon type (cJSON keeps the first of two equal keys) */
#define PP_ANY_TYPE                                                                                       \
    "\"type\": \"progressive_transient_photon_map\", \"photon_count\": 3000, \"volume_photon_count\": 1e6," \
    " \"gather_photon_count\": 64, \"gather_radius\": 0.15, \"volume_gather_radius\": 0.08,"              \
    " \"fixed_volume_radius\": true"
#define PP_KEYS PP_ANY_TYPE ", \"volume_photon_type\": \"points\""
#define PP_DARTS ", \"enable_guiding\": true, \"enable_elliptical\": true"
#define PP_BASE ", \"enable_guiding\": false"

static long passes_of(const char *env, long dflt)
{
    const char *e = getenv(env);
    return e ? atol(e) : dflt;
}

/* Every kind in two renders (at most DIFF_PARAM_MAX derivatives each), photon points against the path tracer. */
static void check_kinds(const char *label, const char *pp_keys, long pt_passes, long pp_passes)
{
    static const int groups[2][MAXK] = {{P_SIGMA_S, P_SIGMA_A, P_G, P_POWER, P_PULSE_START, P_CENTER, P_WIDTH, P_ALBEDO},
                                        {P_SPEED, P_PULSE_WIDTH}};
    const int sizes[2] = {8, 2};
    char keys[1024];
    snprintf(keys, sizeof keys, PP_KEYS "%s", pp_keys);
    print_message("  %s\n", label);
    for (int gi = 0; gi < 2; gi++) {
        probe ref, m;
        render_derivs(PT_KEYS, groups[gi], sizes[gi], pt_passes, 11, &ref, NULL);
        render_derivs(keys, groups[gi], sizes[gi], pp_passes, 13, &m, NULL);
        double z = gi == 0 ? compare("image", &ref, &m, 0) : 0.0; /* every kind printed, then the worst judged */
        for (int j = 0; j < sizes[gi]; j++) z = fmax(z, compare(NAMES[groups[gi][j]], &ref, &m, 1 + j));
        assert_true(z < Z_LIMIT);
        free(ref.x);
        free(m.x);
    }
}

/* The default tier's passes (about 35 s under the sanitizers in all); the stress program
 * (test_deriv_photon_points_stress.c) sets more. DERIV_PT_PASSES and DERIV_PP_PASSES override either. */
#ifndef PT_PASSES
#define PT_PASSES 600
#define PP_PASSES 60
#endif

static void test_baseline(void **state)
{
    (void)state;
    check_kinds("baseline photon pass", PP_BASE, passes_of("DERIV_PT_PASSES", PT_PASSES), passes_of("DERIV_PP_PASSES", PP_PASSES));
}

static void test_darts(void **state)
{
    (void)state;
    check_kinds("DARTS photon pass", PP_DARTS, passes_of("DERIV_PT_PASSES", PT_PASSES), passes_of("DERIV_PP_PASSES", PP_PASSES));
}

/* ∂S/∂(pulse start) = −∂S/∂(gate start) for every contribution (S depends on the gate's edges minus the
 * emission time), and neither moves f: the two derivative images are exact negatives, pixel by pixel. */
static void test_start_identity(void **state)
{
    (void)state;
    const int ps[2] = {P_PULSE_START, P_CENTER};
    const char *keys[2] = {PP_KEYS PP_BASE, PP_KEYS PP_DARTS};
    for (int i = 0; i < 2; i++) {
        probe t;
        film f;
        render_derivs(keys[i], ps, 2, 20, 5, &t, &f);
        size_t n = 3 * (size_t)f.width * f.height, lit = 0;
        for (size_t j = 0; j < n; j++) {
            assert_true(f.deriv[0].sum[j] == -f.deriv[1].sum[j]);
            lit += f.deriv[0].sum[j] != 0.0;
        }
        print_message("  %s: dI/d(pulse start) = -dI/d(gate centre) in all %zu values (%zu nonzero)\n",
                      i ? "DARTS" : "baseline", n, lit);
        assert_true(lit > n / 2);
        film_free(&f);
        free(t.x);
    }
}

/* Photon beams and the sliced primitives carry no derivative records: refused at plan time, naming the key. */
static void test_refusals(void **state)
{
    (void)state;
    static const char *types[] = {"beams", "balls", "volumes"};
    for (int i = 0; i < 3; i++) {
        char keys[1024], text[8192];
        snprintf(keys, sizeof keys, PP_ANY_TYPE PP_BASE ", \"volume_photon_type\": \"%s\"", types[i]);
        scene_text(text, sizeof text, keys);
        tmp_scene ts;
        tmp_scene_write(&ts, text);
        scene s;
        load_scene(ts.path, NULL, 0, &s);
        s.diffs[0] = param(P_SIGMA_S);
        snprintf(s.diffs[0].pointer, sizeof s.diffs[0].pointer, "/media/0/sigma_s");
        s.diff_count = 1;
        render_options ro = {.threads = 1, .seed = 1, .spp = 1};
        film f;
        render_stats st;
        dp_error err;
        assert_int_not_equal(render_scene(&s, &ro, &f, &st, &err), 0);
        print_message("  %s: %s\n", types[i], err.msg);
        assert_non_null(strstr(err.msg, "volume_photon_type"));
        assert_non_null(strstr(err.msg, types[i]));
        assert_non_null(strstr(err.msg, "/media/0/sigma_s"));
        scene_free(&s);
        tmp_scene_remove(&ts);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_refusals), cmocka_unit_test(test_start_identity),
                                       cmocka_unit_test(test_baseline), cmocka_unit_test(test_darts)};
#ifdef PP_STRESS_BUILD
    /* the stress program's passes under DARTSPP_STRESS=full only (`make stress`); in `make test` the default
     * program runs the same cases with fewer passes, so this one runs the refusals */
    const struct CMUnitTest refusals[] = {cmocka_unit_test(test_refusals)};
    if (!stress_full()) return cmocka_run_group_tests(refusals, NULL, NULL);
#endif
    return cmocka_run_group_tests(tests, NULL, NULL);
}
