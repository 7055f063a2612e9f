/* tier: quick */
/* surface_paths "auto" (src/photon_points/chain_share.c, docs/defaults.md §3.9): the rule against its closed
 * form, and the pilot on two fog boxes that differ only in the fog's density: the chains' share follows the
 * two estimates' variances (less where the volume's dominates), the same at any thread count, its time counted
 * in the render's. That a share below 1 keeps the surface map's expectation is test_photon_pass's
 * test_chain_share_keeps_the_surface_map. */
#include "fixtures.h"
#include "render_fixtures.h"

#include <omp.h>

#include "dartspp/photon_points.h"

/* q = sqrt(V_s/V_v), clamped to [1/16, 1]; no volume variance: every path. */
static void test_rule(void **state)
{
    (void)state;
    assert_float_equal(photon_points_chain_share_rule(0.25, 1.0), 0.5, 1e-15);
    assert_float_equal(photon_points_chain_share_rule(0.04, 4.0), 0.1, 1e-15);
    assert_float_equal(photon_points_chain_share_rule(4.0, 1.0), 1.0, 0.0);
    assert_float_equal(photon_points_chain_share_rule(1e-6, 1.0), 1.0 / 16, 0.0);
    assert_float_equal(photon_points_chain_share_rule(0.0, 1.0), 1.0 / 16, 0.0);
    assert_float_equal(photon_points_chain_share_rule(1.0, 0.0), 1.0, 0.0);
}

#define DARTS_BOX                                                                                                  \
    "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","                          \
    " \"photon_count\": 32768, \"volume_photon_count\": 2000, \"gather_photon_count\": 16,"                       \
    " \"gather_radius\": 0.15, \"volume_gather_radius\": 0.08, \"max_bounces\": 40,"                              \
    " \"transient_time_center\": 4.5, \"transient_time_width\": 0.5, \"enable_guiding\": true,"                  \
    " \"enable_elliptical\": true, \"strict_time_width\": true"

/* One pass of the 32² fog box with the fog's σs replaced by sigma_s (16 characters), with `threads`. */
static render_stats one_pass(const char *sigma_s, int threads, const char *set)
{
    char text[8192];
    box_scene_text(text, sizeof text, 32, DARTS_BOX);
    char *a = strstr(text, "[0.45, 0.4, 0.5]");
    assert_non_null(a);
    assert_int_equal(strlen(sigma_s), 16);
    memcpy(a, sigma_s, 16);
    tmp_scene t;
    tmp_scene_write(&t, text);
    scene s;
    const char *sets[] = {set};
    load_scene(t.path, sets, set ? 1 : 0, &s);
    render_options opt = {.threads = threads, .seed = 5, .spp = 1, .time_limit = 0};
    film f;
    render_stats st;
    dp_error err;
    if (render_scene(&s, &opt, &f, &st, &err)) fail_msg("%s", err.msg);
    film_free(&f);
    scene_free(&s);
    tmp_scene_remove(&t);
    return st;
}

static void test_pilot_follows_the_variances(void **state)
{
    (void)state;
    render_stats thick = one_pass("[0.90,0.80,1.00]", 2, NULL), thin = one_pass("[0.02,0.02,0.02]", 2, NULL);
    print_message("  thick fog: surface variance %.4g x the volume's, chains' share %.4f (pilot %.2f s of %.2f s)\n",
                  thick.pilot_ratio, thick.chain_share, thick.t_pilot, thick.seconds);
    print_message("  thin fog:  surface variance %.4g x the volume's, chains' share %.4f\n", thin.pilot_ratio,
                  thin.chain_share);
    /* the share is the rule's of the pilot's ratio, and the ratio orders the two fogs */
    assert_float_equal(thick.chain_share, photon_points_chain_share_rule(thick.pilot_ratio, 1.0), 1e-12);
    assert_float_equal(thin.chain_share, photon_points_chain_share_rule(thin.pilot_ratio, 1.0), 1e-12);
    assert_true(thick.pilot_ratio < thin.pilot_ratio);
    assert_true(thick.chain_share < 1.0);
    assert_true(thin.chain_share > thick.chain_share);
    /* the chains traced that share: fewer light paths than photon_count */
    assert_true(thick.photon_paths < 32768.0);
    /* the pilot's time is the render's */
    assert_true(thick.t_pilot > 0.0 && thick.seconds >= thick.t_pilot);
    /* the same share at one thread: the pilot depends on the scene, the plan and the seed only */
    render_stats one = one_pass("[0.90,0.80,1.00]", 1, NULL);
    assert_true(one.chain_share == thick.chain_share);
    /* "all": no pilot, every path */
    render_stats all = one_pass("[0.90,0.80,1.00]", 2, "surface_paths=all");
    assert_true(all.chain_share == 0.0 && all.t_pilot == 0.0);
    assert_float_equal(all.photon_paths, 32768.0, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rule),
        cmocka_unit_test(test_pilot_follows_the_variances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
