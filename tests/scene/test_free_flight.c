/* tier: quick */
/* Free-flight distance sampling (src/scene/free_flight.c) against closed forms, for grey σt (its own code
 * path) and per-channel σt (spectral MIS), finite and infinite tmax, and a stiff medium:
 *   E[β·1[event]·e^{−a t}] = σs (1 − e^{−(σt+a) tmax}) / (σt + a)   (the medium part, per channel)
 *   E[β·1[pass]]           = e^{−σt tmax}                            (the surface part)
 * each within 4 standard errors measured from the samples; every weight finite and non-negative. */
#include "test_util.h"

#include <math.h>

#include "dartspp/scene.h"

#define N 400000
#define A_TEST 0.3 /* the test function e^{−a t} */

static medium make_medium(vec3 ss, vec3 sa)
{
    medium m = {.sigma_s = ss, .sigma_a = sa, .sigma_t = v3_add(ss, sa), .eta = 1.0, .max_bounces = 1000};
    return m;
}

static void check_channel(const char *what, int c, double mean, double m2, double expect)
{
    double var = fmax(0.0, m2 - mean * mean), se = sqrt(var / N);
    double z = se > 0 ? (mean - expect) / se : (fabs(mean - expect) < 1e-12 ? 0.0 : INFINITY);
    print_message("  %s ch %d: %.6g vs %.6g (se %.2g, z %.2f)\n", what, c, mean, expect, se, z);
    assert_true(fabs(z) < 4.0);
}

static void check_medium(const medium *m, double tmax, uint64_t seed)
{
    dp_rng rng = rng_stream(seed, 1, 2);
    double ev[3] = {0}, ev2[3] = {0}, ps[3] = {0}, ps2[3] = {0};
    for (long i = 0; i < N; i++) {
        vec3 beta = v3s(1.0);
        int event;
        double t = medium_sample_free_flight(m, tmax, &rng, &beta, &event);
        for (int c = 0; c < 3; c++) {
            double b = v3_comp(beta, c);
            assert_true(isfinite(b) && b >= 0.0);
            double e = event ? b * exp(-A_TEST * t) : 0.0, p = event ? 0.0 : b;
            ev[c] += e / N, ev2[c] += e * e / N, ps[c] += p / N, ps2[c] += p * p / N;
        }
        if (event) assert_true(t >= 0.0 && t < tmax);
        else assert_true(t == tmax);
    }
    for (int c = 0; c < 3; c++) {
        double st = v3_comp(m->sigma_t, c), ss = v3_comp(m->sigma_s, c);
        double medium_part = ss * (isinf(tmax) ? 1.0 : -expm1(-(st + A_TEST) * tmax)) / (st + A_TEST);
        check_channel("medium", c, ev[c], ev2[c], medium_part);
        check_channel("pass", c, ps[c], ps2[c], isinf(tmax) ? 0.0 : exp(-st * tmax));
    }
}

static void test_grey(void **state)
{
    (void)state;
    medium m = make_medium(v3s(0.4), v3s(0.01));
    check_medium(&m, 0.7, 1);
    check_medium(&m, 3.0, 2);
    check_medium(&m, INFINITY, 3);
}

static void test_chromatic(void **state)
{
    (void)state;
    medium m = make_medium(v3(0.45, 0.4, 0.5), v3(0.05, 0.08, 0.03));
    check_medium(&m, 0.7, 4);
    check_medium(&m, 3.0, 5);
    check_medium(&m, INFINITY, 6);
}

/* σt = 1e3 over tmax = 10: transmittance e^{−10^4} underflows; the weights must stay finite and the medium
 * part equal σs/(σt + a). A pure absorber (σs = 0) gives zero medium weight. */
static void test_stiff_and_absorbing(void **state)
{
    (void)state;
    medium thick = make_medium(v3s(900.0), v3s(100.0));
    check_medium(&thick, 10.0, 7);
    medium thick_rgb = make_medium(v3(900.0, 500.0, 5.0), v3(100.0, 1.0, 0.1));
    check_medium(&thick_rgb, 10.0, 8);
    medium absorber = make_medium(v3s(0.0), v3s(0.5));
    check_medium(&absorber, 2.0, 9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grey),
        cmocka_unit_test(test_chromatic),
        cmocka_unit_test(test_stiff_and_absorbing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
