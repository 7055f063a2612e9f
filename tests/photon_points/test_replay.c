/* tier: quick */
/* The primary-sample-space replay (include/dartspp/core.h, rng_replay), which the surface chains mutate:
 * a fresh replay is the plain stream, a copy replays a sample exactly, and the mutation is the symmetric
 * wrapped step it claims to be (its distribution against the uniform density on [u − s, u + s]). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "dartspp/core.h"
#include "test_util.h"

/* With nothing set, a replay returns its fresh stream's values, records them, and counts them. */
static void test_fresh_replay_is_the_stream(void **state)
{
    (void)state;
    rng_replay r = {0};
    r.fresh = rng_stream(7, 1, 2);
    dp_rng plain = rng_stream(7, 1, 2), via = {.replay = &r};
    for (int i = 0; i < 1000; i++) assert_true(rng_uniform(&via) == rng_uniform(&plain));
    assert_int_equal(r.used, 1000);
    assert_false(r.oom);
    rng_replay_free(&r);
}

/* A step of size 0 replays the recorded values in order, then continues with fresh ones from its own
 * stream. */
static void test_zero_step_replays_the_sample(void **state)
{
    (void)state;
    rng_replay a = {0}, b = {0};
    a.fresh = rng_stream(3, 0, 0);
    dp_rng ra = {.replay = &a};
    double first[40];
    for (int i = 0; i < 40; i++) first[i] = rng_uniform(&ra);
    b.fresh = rng_stream(4, 0, 0);
    rng_replay_mutate(&b, &a, 0.0, 0.0);
    dp_rng rb = {.replay = &b}, other = rng_stream(4, 0, 0);
    for (int i = 0; i < 40; i++) rng_uniform(&other); /* the step drew one value per moved value */
    for (int i = 0; i < 40; i++) assert_true(rng_uniform(&rb) == first[i]);
    assert_true(rng_uniform(&rb) == rng_uniform(&other)); /* past the sample: fresh */
    assert_int_equal(b.used, 41);
    rng_replay_restart(&b); /* a restart forgets the sample */
    assert_int_equal(b.used, 0);
    assert_true(rng_uniform(&rb) == rng_uniform(&other));
    rng_replay_free(&a);
    rng_replay_free(&b);
}

/* The step u' − u, wrapped to [−1/2, 1/2), must be ± s_max·(s_min/s_max)^ξ for every u — also next to 0
 * and 1, where the wrap takes over — with u' in [0, 1): ln|step| uniform on [ln s_min, ln s_max] (χ² over
 * 20 bins of 20000 steps) and the sign fair (z of the count). A step clamped at the ends (instead of
 * wrapped) fails the χ² next to 0 and 1 (χ² 17031 and 7380), and a step uniform in size fails it
 * everywhere. s_max = 0 keeps u.
 * Values past the sample's length are fresh and the length is the source's. */
static void test_mutation_is_a_symmetric_wrapped_step(void **state)
{
    (void)state;
    const double cases[][3] = {{0.5, 1e-3, 0.1}, {0.01, 1.0 / 1024, 1.0 / 16}, {0.995, 1e-4, 0.02}, {0.3, 0.01, 0.4},
                               {0.0, 1e-5, 1e-3}};
    enum { BINS = 20, N = 20000 };
    double worst_p = 1.0, worst_z = 0.0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double u0 = cases[c][0], s1 = cases[c][1], s2 = cases[c][2];
        rng_replay src = {0}, r = {0};
        src.fresh = rng_stream(11, c, 0);
        dp_rng rs = {.replay = &src};
        rng_uniform(&rs);
        rng_uniform(&rs);
        src.u[0] = u0; /* the sample: (u0, anything) */
        r.fresh = rng_stream(12, c, 0);
        long hist[BINS] = {0}, positive = 0;
        for (int i = 0; i < N; i++) {
            rng_replay_mutate(&r, &src, s1, s2);
            dp_rng rr = {.replay = &r};
            rng_uniform(&rr);
            rng_uniform(&rr);
            rng_uniform(&rr); /* past the source: fresh */
            assert_int_equal(r.used, 3);
            assert_true(r.u[0] >= 0.0 && r.u[0] < 1.0);
            double d = r.u[0] - u0;
            d -= floor(d + 0.5); /* into [−1/2, 1/2) */
            double a = fabs(d);
            assert_true(a >= s1 * (1.0 - 1e-9) && a <= s2 * (1.0 + 1e-9));
            int k = (int)(log(a / s1) / log(s2 / s1) * BINS);
            hist[k < 0 ? 0 : (k >= BINS ? BINS - 1 : k)]++;
            positive += d > 0.0;
        }
        double chi2 = 0.0, e = (double)N / BINS;
        for (int k = 0; k < BINS; k++) chi2 += (hist[k] - e) * (hist[k] - e) / e;
        double p = test_gamma_q((BINS - 1) / 2.0, chi2 / 2.0), z = (positive - N / 2.0) / sqrt(N / 4.0);
        print_message("  u = %g, steps [%g, %g]: chi2 %.1f (19 dof), p = %.3f; sign z = %.2f\n", u0, s1, s2, chi2, p, z);
        if (p < worst_p) worst_p = p;
        if (fabs(z) > worst_z) worst_z = fabs(z);
        rng_replay_mutate(&r, &src, s1, 0.0);
        dp_rng rr = {.replay = &r};
        assert_true(rng_uniform(&rr) == u0 && rng_uniform(&rr) == src.u[1]);
        rng_replay_free(&src);
        rng_replay_free(&r);
    }
    assert_true(worst_p > 1e-3 / 5); /* Bonferroni over the 5 cases */
    assert_true(worst_z < 4.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fresh_replay_is_the_stream),
        cmocka_unit_test(test_zero_step_replays_the_sample),
        cmocka_unit_test(test_mutation_is_a_symmetric_wrapped_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
