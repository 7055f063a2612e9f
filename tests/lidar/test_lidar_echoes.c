/* tier: quick */
/* Echo detection in lidar waveforms (include/dartspp/lidar.h, docs/lidar.md §4): lidar_find_echoes on
 * synthetic waveforms whose echoes are known — a box and a Gaussian echo (the centroid exact for a symmetric
 * echo), two and three echoes in every mode (first, strongest, last, all, all capped), noise below the
 * threshold, a run split by one bin below it (two echoes: documented), echoes touching the first and the last
 * bin, a bin equal to the threshold (not above), NaN bins; and lidar_peak_reference against Φ/(πR²) and the
 * pulse's length in range. Expected values are worked out here from the waveform, never from the code. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "dartspp/lidar.h"
#include "test_util.h"

#define BINS 64
#define RB 0.5

static void zero(float *w, int n)
{
    for (int i = 0; i < n; i++) w[i] = 0.0f;
}

/* The echo the test expects for bins [b0, b1] of w: its fields summed here in double. */
static void expect_echo(const lidar_echo *e, const float *w, int b0, int b1, double rb)
{
    double s = 0.0, m = 0.0, peak = 0.0;
    for (int b = b0; b <= b1; b++) s += w[b], m += (b + 0.5) * rb * w[b], peak = fmax(peak, w[b]);
    assert_int_equal(e->first_bin, b0);
    assert_int_equal(e->last_bin, b1);
    assert_true(fabs(e->range - m / s) <= 1e-12 * fabs(m / s));
    assert_true(fabs(e->intensity - s) <= 1e-12 * s);
    assert_true(fabs(e->width - (b1 - b0 + 1) * rb) <= 1e-15);
    assert_true(e->peak == peak);
}

/* A box of 5 bins of 3.0 at bins 10..14: centroid the middle bin's centre, 12.5·RB, exactly. */
static void test_box_echo(void **state)
{
    (void)state;
    float w[BINS];
    zero(w, BINS);
    for (int b = 10; b <= 14; b++) w[b] = 3.0f;
    lidar_echo e[4];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 1);
    assert_true(e[0].range == 12.5 * RB);
    assert_true(e[0].intensity == 15.0);
    assert_true(e[0].width == 5 * RB);
    assert_true(e[0].peak == 3.0);
    assert_int_equal(e[0].first_bin, 10);
    assert_int_equal(e[0].last_bin, 14);
}

/* Gaussian echoes, symmetric about a bin centre (bin 20) and about a bin edge (between bins 40 and 41): the
 * centroid is the centre of symmetry to rounding; the run is the bins where 5·exp(−k²/8) > 0.5, |k| ≤ 4
 * (k² < 8 ln 10 = 18.4). */
static void test_gaussian_echo(void **state)
{
    (void)state;
    float w[BINS];
    zero(w, BINS);
    for (int k = -6; k <= 6; k++) w[20 + k] = (float)(5.0 * exp(-k * k / 8.0));
    for (int k = 0; k <= 6; k++) w[41 + k] = w[40 - k] = (float)(5.0 * exp(-(k + 0.5) * (k + 0.5) / 8.0));
    lidar_echo e[4];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 0.5, LIDAR_ECHO_ALL, e, 4), 2);
    expect_echo(&e[0], w, 16, 24, RB);
    assert_true(fabs(e[0].range - 20.5 * RB) < 1e-12);
    assert_true(e[0].peak == 5.0);
    /* about the edge: 5·exp(−(k + ½)²/8) > 0.5 for k + ½ < 4.29: k = 0..3 on each side, bins 37..44 */
    expect_echo(&e[1], w, 37, 44, RB);
    assert_true(fabs(e[1].range - 41.0 * RB) < 1e-12);
    print_message("  Gaussian echoes at %.15g and %.15g (symmetric about %g and %g)\n", e[0].range, e[1].range,
                  20.5 * RB, 41.0 * RB);
}

/* Three echoes A (bins 5..7: 2, 4, 2; intensity 8), B (20..24: 5 × 1.5 = 7.5) and C (30..31: 3, 3 = 6) in each
 * mode, then B raised to 5 × 2 = 10 so that the strongest is not the first. */
static void test_modes(void **state)
{
    (void)state;
    float w[BINS];
    zero(w, BINS);
    w[5] = 2, w[6] = 4, w[7] = 2;
    for (int b = 20; b <= 24; b++) w[b] = 1.5f;
    w[30] = w[31] = 3;
    lidar_echo e[4];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_FIRST, e, 4), 1);
    expect_echo(&e[0], w, 5, 7, RB);
    assert_true(e[0].range == 6.5 * RB); /* symmetric */
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_LAST, e, 4), 1);
    expect_echo(&e[0], w, 30, 31, RB);
    assert_true(e[0].range == 31.0 * RB);
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_STRONGEST, e, 4), 1);
    expect_echo(&e[0], w, 5, 7, RB);
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 3);
    expect_echo(&e[0], w, 5, 7, RB);
    expect_echo(&e[1], w, 20, 24, RB);
    expect_echo(&e[2], w, 30, 31, RB);
    /* all, capped: the nearest two; nothing written past max_out */
    lidar_echo f[3];
    f[2].first_bin = -7;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, f, 2), 2);
    expect_echo(&f[0], w, 5, 7, RB);
    expect_echo(&f[1], w, 20, 24, RB);
    assert_int_equal(f[2].first_bin, -7);
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, f, 0), 0);
    /* the strongest later in range */
    for (int b = 20; b <= 24; b++) w[b] = 2.0f;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_STRONGEST, e, 4), 1);
    expect_echo(&e[0], w, 20, 24, RB);
    assert_true(e[0].intensity == 10.0);
    /* a tie keeps the nearer: C raised to 5 + 5 = 10 */
    w[30] = w[31] = 5;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_STRONGEST, e, 4), 1);
    expect_echo(&e[0], w, 20, 24, RB);
    /* nothing above the threshold: no echo in any mode */
    for (int m = LIDAR_ECHO_FIRST; m <= LIDAR_ECHO_ALL; m++)
        assert_int_equal(lidar_find_echoes(w, BINS, RB, 100.0, (lidar_echo_mode)m, e, 4), 0);
}

/* Noise below the threshold everywhere (uniform in [0, 0.9·threshold)) and one echo: exactly that echo, whose
 * intensity and centroid take in the run's bins as they are (noise included); the noise alone gives none. */
static void test_noise_below_threshold(void **state)
{
    (void)state;
    float w[BINS];
    dp_rng r = rng_stream(7, 1, 2);
    const double thr = 0.2;
    for (int trial = 0; trial < 200; trial++) {
        for (int b = 0; b < BINS; b++) w[b] = (float)(0.9 * thr * rng_uniform(&r));
        lidar_echo e[4];
        assert_int_equal(lidar_find_echoes(w, BINS, RB, thr, LIDAR_ECHO_ALL, e, 4), 0);
        int c = 8 + trial % 40;
        for (int k = -2; k <= 2; k++) w[c + k] += (float)(1.0 - 0.2 * abs(k));
        assert_int_equal(lidar_find_echoes(w, BINS, RB, thr, LIDAR_ECHO_ALL, e, 4), 1);
        expect_echo(&e[0], w, c - 2, c + 2, RB);
    }
}

/* A run split by one bin below the threshold is two echoes (docs/lidar.md §4.1: the threshold is the only
 * guard; no merge gap); a bin equal to the threshold is not above it; a NaN bin is never above it. */
static void test_split_equal_and_nan(void **state)
{
    (void)state;
    float w[BINS];
    zero(w, BINS);
    for (int b = 10; b <= 20; b++) w[b] = 2.0f;
    w[15] = 0.9f;
    lidar_echo e[4];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 2);
    expect_echo(&e[0], w, 10, 14, RB);
    expect_echo(&e[1], w, 16, 20, RB);
    w[15] = 1.0f; /* equal: not above */
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 2);
    w[15] = NAN;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 2);
    expect_echo(&e[1], w, 16, 20, RB);
    w[15] = 1.0000001f;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 1);
    expect_echo(&e[0], w, 10, 20, RB);
}

/* Echoes touching the first and the last bin, a waveform above the threshold everywhere (one echo over every
 * bin), and a single bin at either end. */
static void test_edges(void **state)
{
    (void)state;
    float w[BINS];
    zero(w, BINS);
    w[0] = 4, w[1] = 2, w[2] = 1.5f;
    w[BINS - 2] = 1.5f, w[BINS - 1] = 3;
    lidar_echo e[4];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 2);
    expect_echo(&e[0], w, 0, 2, RB);
    expect_echo(&e[1], w, BINS - 2, BINS - 1, RB);
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_LAST, e, 4), 1);
    expect_echo(&e[0], w, BINS - 2, BINS - 1, RB);
    assert_true(fabs(e[0].range - (1.5 * (BINS - 1.5) + 3 * (BINS - 0.5)) / 4.5 * RB) < 1e-12);
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_FIRST, e, 4), 1);
    expect_echo(&e[0], w, 0, 2, RB);
    for (int b = 0; b < BINS; b++) w[b] = 2.0f;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 1);
    expect_echo(&e[0], w, 0, BINS - 1, RB);
    assert_true(e[0].range == BINS / 2.0 * RB);
    zero(w, BINS);
    w[0] = 2;
    w[BINS - 1] = 2;
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 2);
    assert_true(e[0].range == 0.5 * RB && e[0].width == RB);
    assert_true(e[1].range == (BINS - 0.5) * RB && e[1].first_bin == BINS - 1);
    assert_int_equal(lidar_find_echoes(w, 1, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 1); /* one bin in all */
    assert_int_equal(lidar_find_echoes(w, 0, RB, 1.0, LIDAR_ECHO_ALL, e, 4), 0);
}

/* The reference peak Φ/(πR²)·min(1, range_bin/(width/2)) for a delta, a short and a long pulse, and the
 * discretized box echo it stands for: a pulse of length width/2 = 4 bins in range, aligned with the bins,
 * fills 4 bins of energy/4 each. */
static void test_peak_reference(void **state)
{
    (void)state;
    lidar_params l = {0};
    l.power = 2.0;
    l.range_bin = 0.5;
    l.pulse.width = 0.0;
    double e = 2.0 / (M_PI * 100.0);
    assert_true(fabs(lidar_peak_reference(&l, 10.0) - e) < 1e-15 * e);
    l.pulse.width = 0.6; /* length 0.3 < one bin: held in one bin */
    assert_true(fabs(lidar_peak_reference(&l, 10.0) - e) < 1e-15 * e);
    l.pulse.width = 1.0; /* length 0.5 = one bin */
    assert_true(fabs(lidar_peak_reference(&l, 10.0) - e) < 1e-15 * e);
    l.pulse.width = 4.0; /* length 2 = 4 bins */
    assert_true(fabs(lidar_peak_reference(&l, 10.0) - e / 4.0) < 1e-15 * e);
    assert_true(fabs(lidar_peak_reference(&l, 20.0) - e / 16.0) < 1e-15 * e);
    /* the box echo of a target at R = 10: energy e over [R − 1, R + 1) in range, bins 18..21 */
    float w[BINS];
    zero(w, BINS);
    for (int b = 0; b < BINS; b++) {
        double lo = fmax(b * RB, 9.0), hi = fmin((b + 1) * RB, 11.0);
        if (hi > lo) w[b] = (float)(e * (hi - lo) / 2.0);
    }
    double peak = 0.0;
    for (int b = 0; b < BINS; b++) peak = fmax(peak, w[b]);
    assert_true(fabs(peak - lidar_peak_reference(&l, 10.0)) < 1e-7 * peak);
    lidar_echo ec[2];
    assert_int_equal(lidar_find_echoes(w, BINS, RB, 0.5 * lidar_peak_reference(&l, 10.0), LIDAR_ECHO_ALL, ec, 2), 1);
    expect_echo(&ec[0], w, 18, 21, RB);
    assert_true(fabs(ec[0].range - 10.0) < 1e-12 && fabs(ec[0].intensity - e) < 1e-7 * e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_echo),
        cmocka_unit_test(test_gaussian_echo),
        cmocka_unit_test(test_modes),
        cmocka_unit_test(test_noise_below_threshold),
        cmocka_unit_test(test_split_equal_and_nan),
        cmocka_unit_test(test_edges),
        cmocka_unit_test(test_peak_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
