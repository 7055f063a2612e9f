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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
