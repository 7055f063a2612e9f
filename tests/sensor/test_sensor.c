/* tier: quick */
/* The photon-counting model (include/dartspp/sensor.h, docs/sensor.md §1) against its closed forms: the
 * exact Poisson and binomial samplers against their pmfs (χ²), the Poisson counts' means and variances,
 * dark and ambient counts and the detection efficiency in μ_k, the one-detection-per-pulse histogram against
 * Coates' pile-up formula, a finite dead time against an independent pulse-by-pulse simulation written here,
 * and the Coates correction recovering μ_k from a piled-up histogram. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "dartspp/core.h"
#include "dartspp/io.h"
#include "dartspp/scene.h"
#include "dartspp/sensor.h"
#include "fixtures.h"
#include "test_util.h"

/* χ² of `draws` samples of an integer variate against its log-pmf, cells k0..k1 (the rest pooled). */
typedef long (*draw_fn)(dp_rng *r, const double *par);
typedef double (*logpmf_fn)(long k, const double *par);

static double chi2_of(draw_fn draw, logpmf_fn lp, const double *par, long k0, long k1, long draws, uint64_t seed)
{
    int n = (int)(k1 - k0 + 1);
    chi_cell *cells = calloc((size_t)n + 2, sizeof *cells);
    assert_non_null(cells);
    double inside = 0.0;
    for (long k = k0; k <= k1; k++) {
        cells[k - k0].exp = draws * exp(lp(k, par));
        inside += exp(lp(k, par));
    }
    cells[n].exp = draws * (1.0 - inside); /* outside [k0, k1], both tails */
    if (cells[n].exp < 0.0) cells[n].exp = 0.0;
    dp_rng r = rng_stream(seed, 1, 2);
    for (long i = 0; i < draws; i++) {
        long k = draw(&r, par);
        if (k >= k0 && k <= k1) cells[k - k0].obs += 1.0;
        else cells[n].obs += 1.0;
    }
    double chi2;
    int dof;
    double p = chi2_pooled(cells, n + 1, &chi2, &dof, NULL);
    print_message("  (%g, %g): chi2 %.1f, %d dof, p = %.3g\n", par[0], par[1], chi2, dof, p);
    free(cells);
    return p;
}

static long draw_poisson(dp_rng *r, const double *par) { return rng_poisson(r, par[0]); }
static double logpmf_poisson(long k, const double *par) { return k * log(par[0]) - par[0] - lgamma(k + 1.0); }
static long draw_binomial(dp_rng *r, const double *par) { return rng_binomial(r, (long)par[0], par[1]); }
static double logpmf_binomial(long k, const double *par)
{
    double n = par[0], p = par[1];
    if (k < 0 || k > n) return -INFINITY;
    return lgamma(n + 1.0) - lgamma(k + 1.0) - lgamma(n - k + 1.0) + k * log(p) + (n - k) * log1p(-p);
}

/* Poisson from a mean of 0.5 (products of uniforms) through 17 (one gamma step) to 10^5 (many). */
static void test_poisson_sampler_matches_its_pmf(void **state)
{
    (void)state;
    const double means[] = {0.5, 12.0, 17.0, 300.0, 1e5};
    for (int i = 0; i < 5; i++) {
        double par[2] = {means[i], 0.0}, sd = sqrt(means[i]);
        long k0 = (long)fmax(0.0, means[i] - 6.0 * sd), k1 = (long)(means[i] + 6.0 * sd) + 2;
        assert_true(chi2_of(draw_poisson, logpmf_poisson, par, k0, k1, 200000, 11 + i) > 1e-3 / 5);
    }
}

/* Binomial from direct counting (n ≤ 64) through the order-statistic recursion (n up to 10^9). */
static void test_binomial_sampler_matches_its_pmf(void **state)
{
    (void)state;
    const double cases[][2] = {{20, 0.3}, {65, 0.5}, {1000, 0.01}, {100000, 0.3}, {1e9, 2e-6}, {5000, 0.999}};
    for (int i = 0; i < 6; i++) {
        double n = cases[i][0], p = cases[i][1], m = n * p, sd = sqrt(n * p * (1.0 - p));
        long k0 = (long)fmax(0.0, m - 6.0 * sd), k1 = (long)fmin(n, m + 6.0 * sd + 2);
        assert_true(chi2_of(draw_binomial, logpmf_binomial, cases[i], k0, k1, 100000, 21 + i) > 1e-3 / 6);
    }
}

static int close_to(double a, double b) { return fabs(a - b) <= 1e-12 * fmax(1.0, fabs(b)); }

/* μ_k = (η·(scale·L_k + ambient) + dark)·Δt_k, with the channel chosen; negative values emit nothing. */
static void test_expected_detections_formula(void **state)
{
    (void)state;
    double start[3] = {1.0, 1.5, 2.5}, end[3] = {1.5, 2.5, 2.75};
    spad_bins b = {start, end, 3};
    float L[9] = {1, 2, 3, 0.5f, 0.5f, 0.5f, -4, 1, 1};
    spad_params sp = {.pulses = 10, .scale = 100, .efficiency = 0.3, .dark_rate = 2, .ambient_rate = 5, .channel = 1};
    double mu[3];
    spad_expected(&sp, &b, L, 3, mu);
    assert_true(close_to(mu[0], (0.3 * (100 * 2 + 5) + 2) * 0.5));
    assert_true(close_to(mu[1], (0.3 * (100 * 0.5 + 5) + 2) * 1.0));
    assert_true(close_to(mu[2], (0.3 * (100 * 1 + 5) + 2) * 0.25));
    sp.channel = 3; /* the mean of the channels; a negative mean counts as 0 */
    spad_expected(&sp, &b, L, 3, mu);
    assert_true(close_to(mu[0], (0.3 * (100 * 2 + 5) + 2) * 0.5));
    assert_true(close_to(mu[2], (0.3 * 5 + 2) * 0.25));
}

#define BINS 12
static const double B_START[BINS] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
static const double B_END[BINS] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
static const double B_MU[BINS] = {0.02, 0.05, 0.3, 0.6, 0.2, 0.02, 0.0, 0.01, 0.15, 0.05, 0.02, 0.02};

/* z of a sample mean (over m draws, sum s and sum of squares q) against an expected value. */
static double z_mean(double s, double q, long m, double expected)
{
    double mean = s / m, var = (q - s * s / m) / (m - 1);
    return var > 0.0 ? (mean - expected) / sqrt(var / m) : (mean == expected ? 0.0 : INFINITY);
}

/* No dead time: every bin Poisson(N·μ_k): mean and variance N·μ_k (the variance's z from its own spread). */
static void test_poisson_counts_mean_and_variance(void **state)
{
    (void)state;
    spad_bins b = {B_START, B_END, BINS};
    spad_params sp = {.pulses = 2000, .scale = 1, .efficiency = 1, .channel = 3};
    const long M = 20000;
    double s[BINS] = {0}, q[BINS] = {0}, q4[BINS] = {0}, counts[BINS];
    dp_rng r = rng_stream(5, 0, 0);
    for (long i = 0; i < M; i++) {
        assert_int_equal(spad_histogram(&sp, &b, B_MU, &r, counts), 0);
        for (int k = 0; k < BINS; k++) {
            double d = counts[k] - sp.pulses * B_MU[k];
            s[k] += counts[k], q[k] += counts[k] * counts[k], q4[k] += d * d * d * d;
        }
    }
    double worst_m = 0.0, worst_v = 0.0;
    for (int k = 0; k < BINS; k++) {
        double lam = sp.pulses * B_MU[k];
        if (lam == 0.0) {
            assert_true(s[k] == 0.0);
            continue;
        }
        double zm = z_mean(s[k], q[k], M, lam);
        /* the sample variance about the known mean against λ: Var of (X − λ)² is E(X − λ)^4 − λ² */
        double v = (q[k] - 2 * lam * s[k] + M * lam * lam) / M;
        double v4 = q4[k] / M - v * v, zv = (v - lam) / sqrt(v4 / M);
        worst_m = fmax(worst_m, fabs(zm)), worst_v = fmax(worst_v, fabs(zv));
    }
    print_message("  worst |z|: mean %.2f, variance %.2f\n", worst_m, worst_v);
    assert_true(worst_m < 4.0 && worst_v < 4.0);
}

/* Dark and ambient counts alone (a black cube): N·(dark + η·ambient)·Δt per bin. */
static void test_dark_and_ambient_counts(void **state)
{
    (void)state;
    spad_bins b = {B_START, B_END, BINS};
    spad_params sp = {.pulses = 5000, .scale = 50, .efficiency = 0.25, .dark_rate = 0.002, .ambient_rate = 0.01, .channel = 0};
    float L[3 * BINS] = {0};
    double mu[BINS], counts[BINS], s = 0.0, q = 0.0;
    spad_expected(&sp, &b, L, 3, mu);
    const long M = 4000;
    dp_rng r = rng_stream(6, 0, 0);
    for (long i = 0; i < M; i++) {
        spad_histogram(&sp, &b, mu, &r, counts);
        for (int k = 0; k < BINS; k++) s += counts[k], q += counts[k] * counts[k];
    }
    /* per bin N·(0.002 + 0.25·0.01)·1 = 22.5; pooled over the bins */
    double z = z_mean(s, q, M * BINS, 5000 * (0.002 + 0.25 * 0.01));
    print_message("  mean per bin %.4f (expected 22.5), z %.2f\n", s / (M * BINS), z);
    assert_true(fabs(z) < 4.0);
}

/* Dead time at least the span: one detection per pulse, bin k with p_k = e^{−Σ_{j<k} μ_j}(1 − e^{−μ_k})
 * (Coates 1968): means N·p_k and variances N·p_k(1 − p_k) (multinomial marginals). */
static void test_pile_up_matches_coates_formula(void **state)
{
    (void)state;
    spad_bins b = {B_START, B_END, BINS};
    spad_params sp = {.pulses = 1000, .scale = 1, .efficiency = 1, .dead_time = 12, .channel = 3};
    assert_int_equal(spad_model_of(&sp, &b), SPAD_FIRST_PHOTON);
    const long M = 20000;
    double s[BINS] = {0}, q[BINS] = {0}, counts[BINS];
    dp_rng r = rng_stream(7, 0, 0);
    for (long i = 0; i < M; i++) {
        spad_histogram(&sp, &b, B_MU, &r, counts);
        double total = 0.0;
        for (int k = 0; k < BINS; k++) s[k] += counts[k], q[k] += counts[k] * counts[k], total += counts[k];
        assert_true(total <= sp.pulses);
    }
    double before = 0.0, worst_m = 0.0, worst_v = 0.0;
    for (int k = 0; k < BINS; k++) {
        double p = exp(-before) * -expm1(-B_MU[k]), mean = sp.pulses * p, var = mean * (1.0 - p);
        before += B_MU[k];
        if (p == 0.0) continue;
        double zm = (s[k] / M - mean) / sqrt(var / M);
        double sv = (q[k] - s[k] * s[k] / M) / (M - 1), zv = (sv - var) / (var * sqrt(2.0 / (M - 1)));
        worst_m = fmax(worst_m, fabs(zm)), worst_v = fmax(worst_v, fabs(zv));
    }
    print_message("  worst |z|: mean %.2f, variance %.2f\n", worst_m, worst_v);
    assert_true(worst_m < 4.0 && worst_v < 4.5);
}

/* An independent pulse-by-pulse simulation of a non-paralyzable detector: the arrivals of each bin as
 * exponential gaps at its rate, dead time d after each detection. */
static void brute_force_pulse(const double *mu, double d, dp_rng *r, double *counts)
{
    double live = 0.0;
    for (int k = 0; k < BINS; k++) {
        double rate = mu[k] / (B_END[k] - B_START[k]);
        if (!(rate > 0.0)) continue;
        double t = B_START[k];
        for (;;) {
            t += -log(1.0 - rng_uniform(r)) / rate;
            if (t >= B_END[k]) break;
            if (t < live) continue;
            counts[k] += 1.0;
            live = t + d;
        }
    }
}

/* A dead time shorter than the span (1.5 and 4 bins; and 1e-9, which must give the Poisson means) against
 * the brute force, bin by bin. */
static void test_dead_time_matches_pulse_by_pulse_simulation(void **state)
{
    (void)state;
    spad_bins b = {B_START, B_END, BINS};
    const double dead[] = {1.5, 4.0, 1e-9};
    double worst = 0.0;
    for (int c = 0; c < 3; c++) {
        spad_params sp = {.pulses = 200, .scale = 1, .efficiency = 1, .dead_time = dead[c], .channel = 3};
        assert_int_equal(spad_model_of(&sp, &b), SPAD_DEAD_TIME);
        const long M = 4000;
        double s1[BINS] = {0}, q1[BINS] = {0}, s2[BINS] = {0}, q2[BINS] = {0}, counts[BINS];
        dp_rng r = rng_stream(8, c, 0), r2 = rng_stream(9, c, 0);
        for (long i = 0; i < M; i++) {
            assert_int_equal(spad_histogram(&sp, &b, B_MU, &r, counts), 0);
            for (int k = 0; k < BINS; k++) s1[k] += counts[k], q1[k] += counts[k] * counts[k];
            double bf[BINS] = {0};
            for (int pulse = 0; pulse < sp.pulses; pulse++) brute_force_pulse(B_MU, dead[c], &r2, bf);
            for (int k = 0; k < BINS; k++) s2[k] += bf[k], q2[k] += bf[k] * bf[k];
        }
        for (int k = 0; k < BINS; k++) {
            if (B_MU[k] == 0.0) {
                assert_true(s1[k] == 0.0 && s2[k] == 0.0);
                continue;
            }
            double m1 = s1[k] / M, m2 = s2[k] / M, v1 = (q1[k] - s1[k] * m1) / (M - 1), v2 = (q2[k] - s2[k] * m2) / (M - 1);
            double z = (m1 - m2) / sqrt((v1 + v2) / M);
            worst = fmax(worst, fabs(z));
            if (c == 2) { /* no pile-up at a vanishing dead time: Poisson means */
                double zp = (m1 - sp.pulses * B_MU[k]) / sqrt(sp.pulses * B_MU[k] / M);
                worst = fmax(worst, fabs(zp));
            }
        }
        print_message("  dead time %g: bin 4 mean %.3f (brute force %.3f, no pile-up %.1f)\n", dead[c], s1[3] / M,
                      s2[3] / M, sp.pulses * B_MU[3]);
    }
    print_message("  worst |z| %.2f\n", worst);
    assert_true(worst < 4.0);
}

/* Coates' correction gives back μ_k from piled-up histograms (N = 10^5, Λ = 1.44: the last bins lose
 * about 70 % of their counts), within 4 standard errors over 300 pixels; a saturated bin is reported. */
static void test_coates_recovers_the_expected_detections(void **state)
{
    (void)state;
    spad_bins b = {B_START, B_END, BINS};
    spad_params sp = {.pulses = 100000, .scale = 1, .efficiency = 1, .dead_time = 100, .channel = 3};
    const long M = 300;
    double s[BINS] = {0}, q[BINS] = {0}, counts[BINS], mu_hat[BINS], raw_last = 0.0;
    dp_rng r = rng_stream(10, 0, 0);
    for (long i = 0; i < M; i++) {
        spad_histogram(&sp, &b, B_MU, &r, counts);
        assert_int_equal(spad_coates(counts, BINS, sp.pulses, mu_hat), 0);
        for (int k = 0; k < BINS; k++) s[k] += mu_hat[k], q[k] += mu_hat[k] * mu_hat[k];
        raw_last += counts[BINS - 1] / sp.pulses;
    }
    double worst = 0.0;
    for (int k = 0; k < BINS; k++) {
        if (B_MU[k] == 0.0) continue;
        worst = fmax(worst, fabs(z_mean(s[k], q[k], M, B_MU[k])));
    }
    print_message("  worst |z| %.2f; last bin: raw counts/N %.4f, Coates %.4f, μ %.4f\n", worst, raw_last / M,
                  s[BINS - 1] / M, B_MU[BINS - 1]);
    assert_true(worst < 4.0);
    double sat[2] = {5, 0}, out[2]; /* 5 of 5 pulses in bin 0: saturated; bin 1 unobservable */
    assert_int_equal(spad_coates(sat, 2, 5, out), 2);
    assert_true(isfinite(out[0]) && out[0] > 0.0 && out[1] == 0.0);
}

/* A cube and its frames CSV as `dartspp render` writes them: (F, H, W, 3) float32, value L in frames 2..4 of
 * every pixel (channel G only), 0 elsewhere; F = 8 frames of width 0.5 from 3.0. */
#define CF 8
#define CH 6
#define CW 7
static void write_test_cube(const char *dir, float L)
{
    char path[1024];
    size_t shape[4] = {CF, CH, CW, 3}, n = (size_t)CF * CH * CW * 3;
    float *v = calloc(n, sizeof *v);
    assert_non_null(v);
    for (int k = 2; k <= 4; k++)
        for (int p = 0; p < CH * CW; p++) v[((size_t)k * CH * CW + p) * 3 + 1] = L;
    dp_error err;
    snprintf(path, sizeof path, "%s/t_cube.npy", dir);
    assert_int_equal(npy_write_f32(path, shape, 4, v, &err), 0);
    free(v);
    snprintf(path, sizeof path, "%s/t_frames.csv", dir);
    assert_int_equal(frames_csv_write(path, CF, 3.0, 0.5, &err), 0);
}

/* An int32 .npy of (CF, CH, CW) into v: checks the header our writer makes. */
static void read_counts(const char *path, int32_t *v)
{
    size_t len;
    char *bytes = read_all(path, &len);
    assert_non_null(bytes);
    size_t header = 10 + ((unsigned char)bytes[8] | (size_t)(unsigned char)bytes[9] << 8);
    assert_true(len > header);
    assert_non_null(memmem(bytes + 10, header - 10, "'descr': '<i4'", 14));
    assert_non_null(memmem(bytes + 10, header - 10, "'shape': (8, 6, 7)", 18));
    assert_int_equal(len, header + 4 * (size_t)CF * CH * CW);
    memcpy(v, bytes + header, 4 * (size_t)CF * CH * CW);
    free(bytes);
}

/* `dartspp counts` end to end: the histograms' mean over the pixels against N·μ_k per frame (μ from the
 * options: scale, efficiency, dark and ambient rates, channel g), the sidecar, the Coates file recovering the
 * cube's values, and the input errors (each naming the option or file) with exit 2 before any output. */
static void test_counts_command(void **state)
{
    char *dir = test_tmpdir(), cmd[2048], out[8192], path[1024];
    assert_non_null(dir);
    *state = dir;
    write_test_cube(dir, 2.0f);
    snprintf(cmd, sizeof cmd, "%s counts %s/t_cube.npy --output %s/c.npy --pulses 4000 --scale 0.05 --efficiency 0.5 "
             "--dark-rate 0.01 --ambient-rate 0.02 --channel g --seed 3", DARTSPP_BIN, dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    int32_t *h = malloc(4 * (size_t)CF * CH * CW);
    assert_non_null(h);
    snprintf(path, sizeof path, "%s/c.npy", dir);
    read_counts(path, h);
    double worst = 0.0;
    for (int k = 0; k < CF; k++) {
        double L = k >= 2 && k <= 4 ? 2.0 : 0.0, mu = (0.5 * (0.05 * L + 0.02) + 0.01) * 0.5, s = 0.0;
        for (int p = 0; p < CH * CW; p++) s += h[(size_t)k * CH * CW + p];
        double n = CH * CW, z = (s / n - 4000 * mu) / sqrt(4000 * mu / n);
        worst = fmax(worst, fabs(z));
    }
    print_message("  counts: worst |z| of a frame's mean %.2f\n", worst);
    assert_true(worst < 4.0);
    snprintf(path, sizeof path, "%s/c.json", dir);
    char *json = read_all(path, NULL);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"model\":\t\"poisson (no dead time)\""));
    assert_non_null(strstr(json, "\"pulses\":\t4000"));
    assert_non_null(strstr(json, "\"frames\":"));
    free(json);
    /* one detection per pulse and the Coates estimate back in the cube's unit: 2 where the light is */
    snprintf(cmd, sizeof cmd, "%s counts %s/t_cube.npy --output %s/d.npy --pulses 200000 --scale 0.5 --dead-time 4 "
             "--coates --channel g", DARTSPP_BIN, dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    snprintf(path, sizeof path, "%s/d_coates.npy", dir);
    size_t shape[NPY_MAX_DIMS];
    int ndim;
    float *c;
    dp_error err;
    assert_int_equal(npy_read_f32(path, shape, &ndim, &c, &err), 0);
    assert_int_equal(ndim, 3);
    double s4 = 0.0;
    for (int p = 0; p < CH * CW; p++) s4 += c[(size_t)4 * CH * CW + p];
    print_message("  Coates, frame 4 (after 2 piled-up frames): mean %.4f (cube 2)\n", s4 / (CH * CW));
    assert_true(fabs(s4 / (CH * CW) - 2.0) < 0.008); /* 4 standard errors: 0.012 per pixel, 42 pixels */
    free(c);
    free(h);
    const char *bad[][2] = {
        {"--pulses 10 --scale 1 --efficiency 1.5", "--efficiency"},
        {"--scale 1", "--pulses is required"},
        {"--pulses 10 --scale 1 --channel x", "--channel"},
        {"--pulses 10 --scale 1 --coates", "--coates"},
        {"--pulses 10.5 --scale 1", "integers"},
        {"--pulses 1e14 --scale 1", "int32"},
        {"--pulses 10 --scale 1 --frames /nonexistent.csv", "/nonexistent.csv"},
    };
    for (int i = 0; i < 7; i++) {
        snprintf(cmd, sizeof cmd, "%s counts %s/t_cube.npy --output %s/bad.npy %s", DARTSPP_BIN, dir, dir, bad[i][0]);
        assert_int_equal(test_run(cmd, out, sizeof out), 2);
        if (!strstr(out, bad[i][1])) fail_msg("'%s': no '%s' in: %s", bad[i][0], bad[i][1], out);
        snprintf(path, sizeof path, "%s/bad.npy", dir);
        assert_int_not_equal(access(path, F_OK), 0);
    }
}

/* Every option of `dartspp counts --help` is documented in docs/sensor.md. */
static void test_counts_options_documented(void **state)
{
    (void)state;
    char out[8192];
    assert_int_equal(test_run(DARTSPP_BIN " counts --help", out, sizeof out), 0);
    char *doc = read_all("docs/sensor.md", NULL);
    assert_non_null(doc);
    int n = 0;
    for (char *p = out; (p = strstr(p, "  --")); n++) {
        char flag[32];
        assert_int_equal(sscanf(p + 2, "%31s", flag), 1);
        char quoted[40];
        snprintf(quoted, sizeof quoted, "`%s", flag);
        if (!strstr(doc, quoted)) fail_msg("docs/sensor.md does not document %s", flag);
        p += 4;
    }
    assert_true(n >= 10);
    free(doc);
}

/* χ² of 200,000 offsets against the response's CDF over 40 cells between lo and hi (and the two tails). */
static double response_chi2(const sensor_response *r, double lo, double hi, uint64_t seed)
{
    enum { CELLS = 42 };
    chi_cell c[CELLS] = {{0}};
    const long N = 200000;
    double w = (hi - lo) / (CELLS - 2);
    for (int i = 0; i < CELLS; i++) {
        double a = i == 0 ? -INFINITY : lo + (i - 1) * w, b = i == CELLS - 1 ? INFINITY : lo + i * w;
        double Fa = isinf(a) ? 0.0 : sensor_response_cdf(r, a), Fb = isinf(b) ? 1.0 : sensor_response_cdf(r, b);
        c[i].exp = N * (Fb - Fa);
    }
    dp_rng rng = rng_stream(seed, 3, 4);
    for (long k = 0; k < N; k++) {
        double x = sensor_response_sample(r, &rng);
        int i = x < lo ? 0 : x >= hi ? CELLS - 1 : 1 + (int)((x - lo) / w);
        if (x < hi && i > CELLS - 2) i = CELLS - 2; /* rounding at hi */
        c[i].obs += 1.0;
    }
    double chi2;
    int dof;
    double p = chi2_pooled(c, CELLS, &chi2, &dof, NULL);
    print_message("  chi2 %.1f, %d dof, p = %.3g\n", chi2, dof, p);
    return p;
}

/* The time response's offsets against its CDF (χ²): a Gaussian, an exponential tail alone, their sum (the
 * exponentially modified Gaussian, whose CDF is the closed form of docs/sensor.md §2), and a tabulated
 * density (a triangle with a flat shoulder, read from a file with a header line); the CDF itself against a
 * numerical integral of the table's density; bad tables refused with the file, the line and the reason. */
static void test_time_response_samples_its_cdf(void **state)
{
    (void)state;
    sensor_response r;
    dp_error err;
    assert_int_equal(sensor_response_init(&r, 0.3, 0.0, NULL, &err), 0);
    assert_true(fabs(sensor_response_cdf(&r, 0.15) - 0.5 * erfc(-0.15 / (0.3 / 2.3548200450309493) / M_SQRT2)) < 1e-12);
    double worst = response_chi2(&r, -0.5, 0.5, 1);
    assert_int_equal(sensor_response_init(&r, 0.0, 0.2, NULL, &err), 0);
    worst = fmin(worst, response_chi2(&r, 0.0, 1.5, 2));
    assert_int_equal(sensor_response_init(&r, 0.2, 0.15, NULL, &err), 0);
    worst = fmin(worst, response_chi2(&r, -0.4, 1.2, 3));
    /* the EMG's CDF against a direct numerical convolution of its two densities */
    double x = 0.3, num = 0.0, s = 0.2 / 2.3548200450309493, h = 1e-4;
    for (double e = 0.5 * h; e < 3.0; e += h) num += h * exp(-e / 0.15) / 0.15 * 0.5 * erfc(-(x - e) / (s * M_SQRT2));
    print_message("  EMG CDF at 0.3: %.8f, numerical %.8f\n", sensor_response_cdf(&r, x), num);
    assert_true(fabs(sensor_response_cdf(&r, x) - num) < 1e-6);
    char *dir = test_tmpdir(), path[512];
    assert_non_null(dir);
    snprintf(path, sizeof path, "%s/irf.csv", dir);
    test_write_file(path, "time,value\n-0.1,0\n0,2\n0.2,0.5\n0.5,0.5\n0.6,0\n");
    assert_int_equal(sensor_response_init(&r, 0.0, 0.0, path, &err), 0);
    assert_int_equal(r.n, 5);
    double area = 0.0; /* the density (p normalized) integrated by the midpoint rule */
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 1000; k++) {
            double t = r.t[i] + (k + 0.5) * (r.t[i + 1] - r.t[i]) / 1000, f = (t - r.t[i]) / (r.t[i + 1] - r.t[i]);
            area += (r.p[i] + f * (r.p[i + 1] - r.p[i])) * (r.t[i + 1] - r.t[i]) / 1000;
            double end = t + 0.5 * (r.t[i + 1] - r.t[i]) / 1000; /* the area so far is up to the cell's end */
            if (i == 1 && k == 499) assert_true(fabs(sensor_response_cdf(&r, end) - area) < 1e-6);
        }
    assert_true(fabs(area - 1.0) < 1e-9);
    worst = fmin(worst, response_chi2(&r, -0.1, 0.6, 4));
    sensor_response_free(&r);
    assert_true(worst > 1e-3 / 4);
    const char *bad[][2] = {{"0,1\n0,2\n", "times must increase"}, {"0,1\n1,-2\n", "negative"},
                            {"0,1\n", "fewer than two"}, {"0,1\nx\n", ":2:"}, {"0,0\n1,0\n", "area is 0"}};
    for (int i = 0; i < 5; i++) {
        test_write_file(path, bad[i][0]);
        assert_int_equal(sensor_response_init(&r, 0.0, 0.0, path, &err), -1);
        if (!strstr(err.msg, bad[i][1]) || !strstr(err.msg, path)) fail_msg("table %d: %s", i, err.msg);
    }
    assert_int_equal(sensor_response_init(&r, 0.1, 0.0, path, &err), -1);
    test_rmtree(dir);
}

/* A point light, a small area light facing the camera (seen directly: its emission is hit) and a small diffuse
 * square beside the light (its surface photons count) in fog just above a glossy gold floor (gate [1.8, 2.6):
 * the floor's light connections count),
 * through which the photon methods' camera paths continue and connect to the light, and a diffuse ceiling
 * for surface photons; its light's pulse and the sensor's response given by
 * `pulse` and `response` (JSON members or ""). */
static void write_response_scene(const char *path, const char *type, const char *pulse, const char *response)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.5, 0.35, 0.6],"
             "  \"sigma_a\": [0.1, 0.2, 0.05], \"phase_function\": {\"type\": \"isotropic\"} } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.7 },"
             "    { \"name\": \"metal\", \"type\": \"rough_conductor\", \"material\": \"Au\", \"roughness\": 0.2 } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": [1, 2, 3], \"ext_medium\": \"fog\" %s,"
             "    \"transform\": { \"position\": [0.5, -0.2, 1.5] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"metal\", \"transform\": { \"position\": [0, -0.5, 3], \"scale\": 10 } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1.2, 3], \"scale\": 10,"
             "      \"rotation\": [180, 0, 0] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0.45, 0.15, 1.7], \"scale\": 0.5,"
             "      \"rotation\": [-90, 0, 0] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 0.5, \"ext_medium\": \"fog\" %s,"
             "      \"transform\": { \"position\": [-0.3, 0.1, 1.4], \"scale\": 0.3, \"rotation\": [-90, 0, 0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [16, 12], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s, \"max_bounces\": 4, \"transient_time_center\": 2.2, \"transient_time_width\": 0.8,"
             "    \"photon_count\": 20000, \"volume_photon_count\": 5000, \"gather_radius\": 0.2, \"volume_gather_radius\": 0.2 %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             pulse, pulse, type, response);
    test_write_file(path, text);
}

/* The response acts where the light's pulse acts, in every integrator: a box pulse of width 0.4 and a
 * tabulated response that is the same box draw the same offsets from the same random numbers (start + 0.4·u),
 * so the two renders must agree pixel for pixel up to rounding — the path tracer, the DARTS and uniform-time
 * path tracers, baseline and DARTS photon points (both the photon pass and the sensor pass's connections). */
static void test_response_acts_like_a_pulse(void **state)
{
    char *dir = test_tmpdir(), a[512], b[512], table[512], cmd[2048], out[4096];
    assert_non_null(dir);
    *state = dir;
    snprintf(table, sizeof table, "%s/box.csv", dir);
    test_write_file(table, "time,value\n0,1\n0.4,1\n");
    const char *types[] = {
        "\"type\": \"path_tracer\"",
        "\"type\": \"path_tracer\", \"enable_guiding\": true, \"enable_elliptical\": true",
        "\"type\": \"path_tracer\", \"time_sampling\": \"uniform\"",
        "\"type\": \"progressive_transient_photon_map\", \"enable_guiding\": false, \"enable_elliptical\": false, \"strict_time_width\": false",
        "\"type\": \"progressive_transient_photon_map\", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true",
    };
    char resp[600];
    snprintf(resp, sizeof resp, ", \"sensor_response_file\": \"box.csv\"");
    for (int t = 0; t < 5; t++) {
        snprintf(a, sizeof a, "%s/pulse.json", dir);
        snprintf(b, sizeof b, "%s/response.json", dir);
        write_response_scene(a, types[t], ", \"pulse_start\": 0, \"pulse_width\": 0.4, \"pulse_shape\": \"box\"", "");
        write_response_scene(b, types[t], "", resp);
        image_rgb img[2];
        for (int k = 0; k < 2; k++) {
            snprintf(cmd, sizeof cmd, "%s render %s --spp 6 --threads 2 --seed 9 --output %s/%d.pfm --no-cube --no-viewer --quiet",
                     DARTSPP_BIN, k ? b : a, dir, k);
            if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
            snprintf(cmd, sizeof cmd, "%s/%d.pfm", dir, k);
            dp_error err;
            assert_int_equal(pfm_read(cmd, &img[k], &err), 0);
        }
        double worst = 0.0, total = 0.0;
        size_t n = (size_t)img[0].width * img[0].height * 3;
        for (size_t i = 0; i < n; i++) {
            worst = fmax(worst, fabs(img[0].rgb[i] - img[1].rgb[i]) / fmax(1e-3, fabs(img[0].rgb[i])));
            total += img[0].rgb[i];
        }
        print_message("  integrator %d: image total %.5g, largest relative difference %.2g\n", t, total, worst);
        assert_true(total > 0.0);
        assert_true(worst < 1e-4);
        image_free(&img[0]);
        image_free(&img[1]);
    }
}

/* Ground truth (renderer key ground_truth, docs/sensor.md §3) against values worked out by hand: a fog of
 * speed 0.8 (η 1.25), a point light at (0.5, 0.5, 0.5) with pulse_start 0.3, a null sheet at z = 1 that the
 * rays pass through, and a diffuse square (albedo 0.6) at z = 2, 2 wide, seen by a 90° camera of 8×8 pixels
 * looking down +z from the origin: inside the square, depth 2/d_z, normal (0, 0, −1), albedo 0.6, arrival
 * 0.3 + 1.25·(depth + |light − x|); outside it, 0 everywhere. Then with camera_unwarp, the arrival without
 * the camera leg. */
static void test_ground_truth(void **state)
{
    char *dir = test_tmpdir(), scene_path[512], cmd[2048], out[4096], path[600];
    assert_non_null(dir);
    *state = dir;
    for (int unwarp = 0; unwarp < 2; unwarp++) {
        char text[4096];
        snprintf(text, sizeof text,
                 "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.05, \"sigma_a\": 0.01,"
                 "  \"speed_of_light\": 0.8 } ],"
                 "  \"bsdfs\": [ { \"name\": \"grey\", \"type\": \"lambert\", \"albedo\": 0.6 }, { \"name\": \"sheet\", \"type\": \"null\" } ],"
                 "  \"primitives\": [ { \"type\": \"point\", \"emission\": 1, \"ext_medium\": \"fog\", \"pulse_start\": 0.3,"
                 "    \"transform\": { \"position\": [0.5, 0.5, 0.5] } },"
                 "    { \"type\": \"quad\", \"bsdf\": \"sheet\", \"transform\": { \"position\": [0, 0, 1], \"scale\": 8, \"rotation\": [-90, 0, 0] } },"
                 "    { \"type\": \"quad\", \"bsdf\": \"grey\", \"transform\": { \"position\": [0, 0, 2], \"scale\": 2, \"rotation\": [-90, 0, 0] } } ],"
                 "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 90, \"medium\": \"fog\","
                 "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
                 "  \"integrator\": { \"type\": \"path_tracer\", \"transient_time_center\": 4, \"transient_time_width\": 1 %s },"
                 "  \"renderer\": { \"spp\": 1, \"ground_truth\": true } }",
                 unwarp ? ", \"camera_unwarp\": true" : "");
        snprintf(scene_path, sizeof scene_path, "%s/gt.json", dir);
        test_write_file(scene_path, text);
        snprintf(cmd, sizeof cmd, "%s render %s --output %s/gt.exr --no-cube --no-viewer --overwrite", DARTSPP_BIN, scene_path, dir);
        if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s", out);
        assert_non_null(strstr(out, "gt_depth.exr"));
        image_rgb img[4];
        const char *names[4] = {"depth", "arrival", "normal", "albedo"};
        for (int k = 0; k < 4; k++) {
            snprintf(path, sizeof path, "%s/gt_%s.exr", dir, names[k]);
            dp_error err;
            if (image_read(path, &img[k], &err)) fail_msg("%s", err.msg);
            assert_int_equal(img[k].width, 8);
        }
        scene s;
        dp_error err;
        scene_load_options lo = {0};
        assert_int_equal(scene_load(scene_path, &lo, &s, &err), 0);
        int inside = 0, outside = 0;
        double worst = 0.0;
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 8; x++) {
                vec3 d = camera_ray_dir(&s.cam, x + 0.5, y + 0.5);
                double t = 2.0 / d.z;
                vec3 p = v3_scale(d, t), l = v3(0.5, 0.5, 0.5);
                size_t i = 3 * ((size_t)y * 8 + x);
                if (fabs(p.x) < 0.999 && fabs(p.y) < 0.999) {
                    double arrival = 0.3 + 1.25 * ((unwarp ? 0.0 : t) + v3_len(v3_sub(l, p)));
                    const double want[4][3] = {{t, t, t}, {arrival, arrival, arrival}, {0, 0, -1}, {0.6, 0.6, 0.6}};
                    for (int k = 0; k < 4; k++)
                        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(img[k].rgb[i + c] - want[k][c]));
                    inside++;
                } else if (fabs(p.x) > 1.001 || fabs(p.y) > 1.001) {
                    for (int k = 0; k < 4; k++)
                        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(img[k].rgb[i + c]));
                    outside++;
                }
            }
        print_message("  camera_unwarp %d: %d pixels on the square, %d beside it; largest error %.2g\n", unwarp, inside,
                      outside, worst);
        assert_true(inside >= 16 && outside >= 16);
        /* the ray leaves the null sheet from an origin moved off it by up to 4/65536 (the scene's largest
         * coordinate over 65536, scene_offset_ray_origin), so depth and arrival may be off by 1.25·2·6.1e-5 */
        assert_true(worst < 1.6e-4);
        for (int k = 0; k < 4; k++) image_free(&img[k]);
        scene_free(&s);
    }
}

/* Scattering-order layers (integrator key bounce_orders, docs/time.md §7): for the path tracer, the DARTS path
 * tracer and DARTS photon points, on the scene above with 5 frames, bounce_orders 3 (orders 0, 1, 2 and 3 or
 * more): the orders of each frame sum to the frame (float sums in another order: within 1e-5 of the pixel's
 * largest channel, plus 1e-7 of the frame's largest value), and the image, frames and cube are bit for bit
 * those of a render without the key; and for the gate image alone (no frames) the orders sum to it. With
 * max_bounces 2 (single scattering only) every contribution is in layer 1 and the others are exactly 0. */
static void test_bounce_orders_sum_to_frames(void **state)
{
    char *dir = test_tmpdir(), a[512], cmd[2048], out[4096], path[600];
    assert_non_null(dir);
    *state = dir;
    const char *types[] = {
        "\"type\": \"path_tracer\"",
        "\"type\": \"path_tracer\", \"enable_guiding\": true, \"enable_elliptical\": true",
        "\"type\": \"progressive_transient_photon_map\", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true",
    };
    for (int t = 0; t < 3; t++)
        for (int framed = 0; framed < 2; framed++) {
            snprintf(a, sizeof a, "%s/orders.json", dir);
            write_response_scene(a, types[t], "", "");
            for (int with = 0; with < 2; with++) {
                snprintf(cmd, sizeof cmd, "%s render %s --spp 4 --threads 2 --seed 3 --output %s/o%d.pfm --no-viewer --quiet %s %s",
                         DARTSPP_BIN, a, dir, with, with ? "--set bounce_orders=3" : "",
                         framed ? "--set frame_num=5 --set start_time=1.8 --set transient_time_width=0.16" : "");
                if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
            }
            /* the image (and the cube) bit for bit, with and without the layers */
            for (int k = 0; k < 1 + framed; k++) {
                char p0[600], p1[600];
                snprintf(p0, sizeof p0, "%s/o0%s", dir, k ? "_cube.npy" : ".pfm");
                snprintf(p1, sizeof p1, "%s/o1%s", dir, k ? "_cube.npy" : ".pfm");
                size_t n0, n1;
                char *b0 = read_all(p0, &n0), *b1 = read_all(p1, &n1);
                assert_true(b0 && b1 && n0 == n1 && memcmp(b0, b1, n0) == 0);
                free(b0);
                free(b1);
            }
            size_t so[NPY_MAX_DIMS];
            int nd;
            float *orders, *whole;
            dp_error err;
            snprintf(path, sizeof path, "%s/o1_orders.npy", dir);
            if (npy_read_f32(path, so, &nd, &orders, &err)) fail_msg("%s", err.msg);
            assert_int_equal(nd, 5);
            assert_int_equal(so[0], 4);
            assert_int_equal(so[1], framed ? 5 : 1);
            size_t layer = so[2] * so[3] * 3, F = so[1];
            if (framed) {
                size_t sc[NPY_MAX_DIMS];
                snprintf(path, sizeof path, "%s/o1_cube.npy", dir);
                if (npy_read_f32(path, sc, &nd, &whole, &err)) fail_msg("%s", err.msg);
            } else {
                image_rgb img;
                snprintf(path, sizeof path, "%s/o1.pfm", dir);
                assert_int_equal(pfm_read(path, &img, &err), 0);
                whole = img.rgb;
            }
            double peak = 0.0, worst = 0.0, orders_total[4] = {0};
            for (size_t i = 0; i < F * layer; i++) peak = fmax(peak, fabs(whole[i]));
            for (size_t k = 0; k < F; k++)
                for (size_t i = 0; i < layer; i++) {
                    double sum = 0.0, big = 0.0;
                    for (int o = 0; o < 4; o++) {
                        double v = orders[(o * F + k) * layer + i];
                        sum += v;
                        big = fmax(big, fabs(v));
                        orders_total[o] += v;
                    }
                    double w = whole[k * layer + i], tol = 1e-5 * fmax(big, fabs(w)) + 1e-7 * peak;
                    worst = fmax(worst, fabs(sum - w) / (tol > 0 ? tol : 1.0));
                }
            print_message("  integrator %d, %s: order totals %.4g %.4g %.4g %.4g; worst |sum − whole| / tolerance %.2g\n", t,
                          framed ? "5 frames" : "gate image", orders_total[0], orders_total[1], orders_total[2],
                          orders_total[3], worst);
            assert_true(worst <= 1.0);
            assert_true(orders_total[1] > 0.0 && orders_total[2] > 0.0 && orders_total[3] > 0.0);
            free(orders);
            free(whole);
        }
    /* max_bounces 2 admits single scattering only: every contribution in layer 1, the others exactly 0 */
    for (int t = 0; t < 3; t++) {
        snprintf(a, sizeof a, "%s/orders.json", dir);
        write_response_scene(a, types[t], "", "");
        snprintf(cmd, sizeof cmd, "%s render %s --spp 4 --threads 2 --seed 3 --output %s/s.pfm --no-viewer --quiet "
                 "--set bounce_orders=3 --set max_bounces=2", DARTSPP_BIN, a, dir);
        if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
        size_t so[NPY_MAX_DIMS];
        int nd;
        float *orders;
        dp_error err;
        image_rgb img;
        snprintf(path, sizeof path, "%s/s_orders.npy", dir);
        if (npy_read_f32(path, so, &nd, &orders, &err)) fail_msg("%s", err.msg);
        snprintf(path, sizeof path, "%s/s.pfm", dir);
        assert_int_equal(pfm_read(path, &img, &err), 0);
        size_t layer = so[2] * so[3] * 3;
        double other = 0.0, diff = 0.0, total = 0.0;
        for (size_t i = 0; i < layer; i++) {
            other += fabs(orders[i]) + fabs(orders[2 * layer + i]) + fabs(orders[3 * layer + i]);
            diff = fmax(diff, fabs(orders[layer + i] - img.rgb[i]) / fmax(1e-30, fabs(img.rgb[i])));
            total += img.rgb[i];
        }
        print_message("  integrator %d, max_bounces 2: image total %.4g, outside layer 1 %.3g, layer 1 vs image %.2g\n",
                      t, total, other, diff);
        assert_true(total > 0.0 && other == 0.0 && diff < 1e-6);
        free(orders);
        image_free(&img);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_poisson_sampler_matches_its_pmf),
        cmocka_unit_test(test_binomial_sampler_matches_its_pmf),
        cmocka_unit_test(test_expected_detections_formula),
        cmocka_unit_test(test_poisson_counts_mean_and_variance),
        cmocka_unit_test(test_dark_and_ambient_counts),
        cmocka_unit_test(test_pile_up_matches_coates_formula),
        cmocka_unit_test(test_dead_time_matches_pulse_by_pulse_simulation),
        cmocka_unit_test(test_coates_recovers_the_expected_detections),
        cmocka_unit_test_teardown(test_counts_command, test_teardown_tmpdir),
        cmocka_unit_test(test_counts_options_documented),
        cmocka_unit_test(test_time_response_samples_its_cdf),
        cmocka_unit_test_teardown(test_response_acts_like_a_pulse, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_ground_truth, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_bounce_orders_sum_to_frames, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
