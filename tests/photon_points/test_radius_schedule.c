/* tier: quick */
/* The progressive radius schedule of photon points (volume_photon_type "points"): progressive_radius against
 * its closed form, and the radii the integrator has used after N passes. */
#include "render_fixtures.h"

static void test_radius_schedule_closed_form(void **state)
{
    (void)state;
    const double alphas[] = {0.1, 0.3, 2.0 / 3.0, 0.9, 1.0};
    const long iters[] = {0, 1, 2, 10, 1000, 100000};
    const double r0 = 0.037;
    for (int dims = 2; dims <= 3; dims++)
        for (size_t a = 0; a < sizeof alphas / sizeof *alphas; a++)
            for (size_t k = 0; k < sizeof iters / sizeof *iters; k++) {
                double alpha = alphas[a];
                long i = iters[k];
                double got = progressive_radius(r0, alpha, i, dims), want = radius_closed_form(r0, alpha, i, dims);
                /* lgamma of arguments up to 1e5 (values ~1e6) is good to a few ulp (~1e-10 absolute), and
                 * the sum of 1e5 logs in the library to ~1e5 · 1e-16: 1e-8 relative covers both. */
                if (fabs(got - want) > 1e-8 * want)
                    fail_msg("progressive_radius(%g, %g, %ld, %d) = %.17g, closed form %.17g", r0, alpha, i, dims, got, want);
                if (i == 0) assert_true(got == r0); /* the first iteration uses r0 exactly */
            }
    /* i = 1 by hand: ((1+α)/2)^{1/dims} */
    assert_float_equal(progressive_radius(1.0, 0.5, 1, 2), sqrt(0.75), 1e-15);
    assert_float_equal(progressive_radius(1.0, 0.5, 1, 3), cbrt(0.75), 1e-15);
    /* α < 1: strictly decreasing; α = 1: constant; dims 3 shrinks slower than dims 2 */
    for (size_t a = 0; a < sizeof alphas / sizeof *alphas; a++) {
        double prev2 = progressive_radius(r0, alphas[a], 0, 2), prev3 = progressive_radius(r0, alphas[a], 0, 3);
        for (long i = 1; i <= 300; i++) {
            double r2 = progressive_radius(r0, alphas[a], i, 2), r3 = progressive_radius(r0, alphas[a], i, 3);
            if (alphas[a] < 1.0) {
                assert_true(r2 < prev2);
                assert_true(r3 < prev3);
                assert_true(r3 > r2);
            } else {
                assert_float_equal(r2, r0, 1e-15);
                assert_float_equal(r3, r0, 1e-15);
            }
            prev2 = r2;
            prev3 = r3;
        }
    }
    /* the asymptote: r_i^dims ~ r0^dims · i^{α-1} / Γ(1+α) */
    double alpha = 2.0 / 3.0, i = 1e5;
    double asym = 0.037 * pow(pow(i, alpha - 1.0) / tgamma(1.0 + alpha), 0.5);
    assert_float_equal(progressive_radius(0.037, alpha, (long)i, 2), asym, 1e-4 * asym);
}

/* The integrator uses that schedule: after N passes the last radii are those of iteration N-1, the volume
 * radius from volume_gather_radius / volume_alpha / radius_schedule, the surface one from gather_radius /
 * alpha in 2D. */
static void test_radius_schedule_used_by_integrator(void **state)
{
    (void)state;
    for (int dims = 2; dims <= 3; dims++) {
        char integ[2048], text[8192];
        snprintf(integ, sizeof integ,
                 "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                 " \"photon_count\": 500, \"volume_photon_count\": 2000, \"gather_radius\": 0.08,"
                 " \"volume_gather_radius\": 0.05, \"alpha\": 0.5, \"volume_alpha\": 0.8, \"radius_schedule\": \"%s\","
                 " \"max_bounces\": 4, \"transient_time_center\": 5, \"transient_time_width\": 1",
                 dims == 2 ? "2d" : "3d");
        box_scene_text(text, sizeof text, 8, integ);
        tmp_scene t;
        tmp_scene_write(&t, text);
        scene s;
        load_scene(t.path, NULL, 0, &s);
        film f;
        render_stats st;
        render_passes(&s, 2, 5, 6, &f, &st);
        assert_float_equal(st.r_vol, radius_closed_form(0.05, 0.8, 5, dims), 1e-12);
        assert_float_equal(st.r_surf, radius_closed_form(0.08, 0.5, 5, 2), 1e-12);
        film_free(&f);
        scene_free(&s);
        tmp_scene_remove(&t);
    }
}

/* The glossy regularization floor (plan_glossy_regularization) is glossy_regularization · R_i/R_0 of the
 * surface schedule: the key's value at the first iteration, strictly decreasing to 0 (so the estimate stays
 * consistent), 0 when the key is 0 and for the path tracer. */
static void test_glossy_regularization_schedule(void **state)
{
    (void)state;
    const char *integ[] = {
        "\"type\": \"progressive_transient_photon_map\", \"gather_radius\": 0.08, \"alpha\": 0.5,"
        " \"glossy_regularization\": 0.3, \"transient_time_center\": 5, \"transient_time_width\": 1",
        "\"type\": \"progressive_transient_photon_map\", \"gather_radius\": 0.08, \"alpha\": 0.5,"
        " \"glossy_regularization\": 0, \"transient_time_center\": 5, \"transient_time_width\": 1",
        "\"type\": \"path_tracer\", \"glossy_regularization\": 0.3, \"transient_time_center\": 5"};
    for (int k = 0; k < 3; k++) {
        char text[8192];
        box_scene_text(text, sizeof text, 8, integ[k]);
        tmp_scene t;
        tmp_scene_write(&t, text);
        scene s;
        load_scene(t.path, NULL, 0, &s);
        render_plan p;
        dp_error err;
        if (plan_resolve(&s, &p, &err)) fail_msg("%s", err.msg);
        double prev = INFINITY;
        const long iters[] = {0, 1, 2, 10, 1000, 1000000};
        for (size_t i = 0; i < sizeof iters / sizeof *iters; i++) {
            double a = plan_glossy_regularization(&p, iters[i]);
            if (k > 0) {
                assert_true(a == 0.0);
                continue;
            }
            assert_float_equal(a, 0.3 * radius_closed_form(0.08, 0.5, iters[i], 2) / 0.08, 1e-9);
            assert_true(a < prev);
            prev = a;
        }
        if (k == 0) assert_true(prev < 0.3 * 0.05); /* 1e6 iterations: below a twentieth of the start */
        plan_free(&p);
        scene_free(&s);
        tmp_scene_remove(&t);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_radius_schedule_closed_form),
        cmocka_unit_test(test_radius_schedule_used_by_integrator),
        cmocka_unit_test(test_glossy_regularization_schedule),
    };
    /* DARTSPP_TEST_FILTER=name (cmocka wildcards) runs only the matching tests */
    if (getenv("DARTSPP_TEST_FILTER")) cmocka_set_test_filter(getenv("DARTSPP_TEST_FILTER"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
