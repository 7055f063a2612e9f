/* A coaxial lidar in fog against the analytic soft-target integral (docs/lidar.md §7; the single-scattering model
 * of Rasshofer et al. 2011 as LiDAR_fog_sim writes it, with our beam and pulse): the waveform of the paths of one
 * scattering event (bounce_orders' layer 1) in every range bin past the near field, bin by bin, against
 *
 *   E_b = Φ σs p(π) K ∫ e^{−2σt r} / r² · P_b(r) dr,   K = 2(1 − cos³δ) / (3 sin²δ),
 *
 * P_b(r) the share of the box pulse's emission times τ ∈ [−w/2, w/2) for which 2r + τ falls in bin b's path
 * times [2b, 2b + 2)·range_bin, δ the beam's half-angle (the receiver's cone equals the beam's, so the overlap is
 * 1 at every range). A coaxial single scattering returns along its own ray: its scattering angle is exactly π.
 * The noise comes from the spread of per-pass estimates (thousands of passes). The full waveform's excess over
 * layer 1, the multiple scattering, is printed, and the layer of two or more events must be positive in the fog. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "render_fixtures.h"
#include "test_util.h"

#include "dartspp/film.h"
#include "dartspp/lidar.h"

#define SIGMA_S 0.04
#define SIGMA_A 0.004
#define G 0.8
#define DIV 0.01   /* beam_divergence = receiver_fov, full angles */
#define WIDTH 1.0  /* box pulse, path length */
#define BIN 0.5
#define RANGE 20.0
#define BINS 40
#define NEAR 4     /* bins before r = 2 are left out: the 1/r² near field */
#define PASSES 12000

static const char *const SCENE_FMT =
    "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.04, \"sigma_a\": 0.004,"
    "    \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.8 } } ],"
    "  \"bsdfs\": [], \"primitives\": [],"
    "  \"camera\": { \"type\": \"lidar\", \"medium\": \"fog\", \"channels\": 1, \"elevation\": [0, 0],"
    "    \"azimuth\": [-8, 8], \"azimuth_steps\": 16, \"beam_divergence\": 0.01, \"receiver_fov\": 0.01,"
    "    \"power\": 1, \"pulse_shape\": \"box\", \"pulse_width\": 1.0, \"max_range\": 20, \"range_bin\": 0.5,"
    "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
    "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 24, \"bounce_orders\": 2 %s },"
    "  \"renderer\": { \"spp\": 1 } }";

/* ---- the analytic soft target ---- */

/* the box pulse's share of emission times putting 2r + τ in [a, b) */
static double pulse_share(double r, double a, double b)
{
    double lo = fmax(a, 2.0 * r - 0.5 * WIDTH), hi = fmin(b, 2.0 * r + 0.5 * WIDTH);
    return hi > lo ? (hi - lo) / WIDTH : 0.0;
}

/* E_b by composite Simpson over the ranges that reach the bin, r ∈ [b·BIN − w/4, (b + 1)·BIN + w/4] */
static double soft_target_bin(int b)
{
    double st = SIGMA_S + SIGMA_A, d = 0.5 * DIV, p_back = (1.0 - G * G) / (4.0 * M_PI * pow(1.0 + G, 3.0));
    double K = 2.0 * (1.0 - pow(cos(d), 3.0)) / (3.0 * sin(d) * sin(d));
    double r0 = b * BIN - 0.25 * WIDTH, r1 = (b + 1) * BIN + 0.25 * WIDTH;
    int n = 4000;
    double h = (r1 - r0) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double r = r0 + i * h, wgt = i == 0 || i == n ? 1.0 : i % 2 ? 4.0 : 2.0;
        sum += wgt * exp(-2.0 * st * r) / (r * r) * pulse_share(r, 2.0 * b * BIN, 2.0 * (b + 1) * BIN);
    }
    return SIGMA_S * p_back * K * sum * h / 3.0;
}

/* ---- per-pass waveforms, summed over the beams ---- */

typedef struct {
    long n;
    double *x;         /* per pass: BINS values of layer 1, then BINS of all paths, then BINS of layer 2 */
    double last[3 * BINS];
} wave_probe;

/* The film's sums of a frame layer over every beam and channel, as waveform energy: the receiver's etendue
 * π sin²(fov/2) times the bin's path time 2·range_bin times the channels' mean (docs/lidar.md §3). */
static double layer_sum(const film *f, long layer)
{
    size_t n = (size_t)f->width * f->height * 3;
    const float *v = &f->frame_sum[n * (size_t)layer];
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += v[i];
    double sr = sin(0.5 * DIV);
    return s * M_PI * sr * sr * 2.0 * BIN / 3.0;
}

static int probe_after(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    (void)st;
    (void)err;
    wave_probe *p = ctx;
    const time_window *tw = &f->window;
    for (int b = 0; b < BINS; b++) {
        long layers[3] = {film_order_layer(tw, 1, b), b, film_order_layer(tw, 2, b)};
        for (int j = 0; j < 3; j++) {
            double s = layer_sum(f, layers[j]);
            p->x[p->n * 3 * BINS + j * BINS + b] = s - p->last[j * BINS + b]; /* this pass's increment */
            p->last[j * BINS + b] = s;
        }
    }
    p->n++;
    return 0;
}

/* The waveforms the files hold (lidar_waveforms, summed over the beams) are the mean of the per-pass increments. */
static void check_waveforms_file(const film *f, const wave_probe *p)
{
    for (int order = -1; order <= 2; order += 3) {
        float *w = NULL;
        dp_error err;
        if (lidar_waveforms(f, order, &w, &err)) fail_msg("%s", err.msg);
        for (int b = NEAR; b < BINS; b++) {
            double sum = 0.0, probe = p->last[(order < 0 ? BINS : 2 * BINS) + b] / p->n;
            for (int beam = 0; beam < f->width * f->height; beam++) sum += w[(size_t)beam * BINS + b];
            assert_true(fabs(sum - probe) <= 1e-4 * fabs(probe) + 1e-30);
        }
        free(w);
    }
}

static void mean_se(const wave_probe *p, int i, double *mean, double *se)
{
    double s = 0.0, s2 = 0.0;
    for (long k = 0; k < p->n; k++) s += p->x[k * 3 * BINS + i];
    *mean = s / p->n;
    for (long k = 0; k < p->n; k++) {
        double d = p->x[k * 3 * BINS + i] - *mean;
        s2 += d * d;
    }
    *se = sqrt(s2 / (p->n - 1) / p->n);
}

/* The path tracer named by `keys` (integrator keys after the common ones) against the soft target. */
static void check_soft_target(const char *label, const char *keys)
{
    char text[4096];
    snprintf(text, sizeof text, SCENE_FMT, keys);
    printf("  %s\n", label);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    assert_int_equal(s.cam.lidar.bins, BINS);
    wave_probe p = {.x = calloc((size_t)PASSES * 3 * BINS, sizeof(double))};
    assert_non_null(p.x);
    render_options ro = {.threads = 1, .seed = 11, .spp = PASSES, .after_pass = probe_after, .after_pass_ctx = &p};
    film f;
    render_stats st;
    dp_error err;
    if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(p.n, PASSES);
    assert_int_equal(st.nonfinite, 0);
    check_waveforms_file(&f, &p);
    int beams = f.width * f.height;
    double zmax = 0.0, sum_m = 0.0, sum_a = 0.0, var = 0.0, ms_sum = 0.0, worst_rel = 0.0;
    for (int b = NEAR; b < BINS; b++) {
        double m, se, a = beams * soft_target_bin(b), all, se_all, ms, se_ms;
        mean_se(&p, b, &m, &se);
        mean_se(&p, BINS + b, &all, &se_all);
        mean_se(&p, 2 * BINS + b, &ms, &se_ms);
        double z = (m - a) / se;
        zmax = fmax(zmax, fabs(z));
        worst_rel = fmax(worst_rel, fabs(m / a - 1.0));
        sum_m += m;
        sum_a += a;
        var += se * se;
        ms_sum += ms;
        if (b % 6 == 4)
            printf("  bin %2d (r %5.2f): order 1 %.4e, analytic %.4e (%+.2f %%, z %+.2f); all orders %.4e (%+.1f %% "
                   "multiple scattering)\n", b, (b + 0.5) * BIN, m, a, 100.0 * (m / a - 1.0), z, all,
                   100.0 * (all / m - 1.0));
    }
    double z_total = (sum_m - sum_a) / sqrt(var);
    printf("  bins %d..%d: max |z| %.2f, worst bin %.2f %%, total %+.3f %% (z %+.2f); layer >= 2 holds %.1f %% of "
           "the past-near-field waveform\n", NEAR, BINS - 1, zmax, 100.0 * worst_rel, 100.0 * (sum_m / sum_a - 1.0),
           z_total, 100.0 * ms_sum / (ms_sum + sum_m));
    assert_true(zmax < 4.0);          /* 36 bins: P(|z| > 4) < 0.3 % in all */
    assert_true(fabs(z_total) < 3.0);
    assert_true(ms_sum > 0.0);        /* multiple scattering in fog adds to the waveform */
    film_free(&f);
    free(p.x);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static void test_plain_path_tracer(void **state)
{
    (void)state;
    check_soft_target("plain path tracer", "");
}

/* the DARTS path tracer: camera paths aimed at the beam (whose point is the receiver's: docs/darts.md §3) */
static void test_darts_path_tracer(void **state)
{
    (void)state;
    check_soft_target("DARTS path tracer", ", \"enable_guiding\": true, \"enable_elliptical\": true");
}

static void test_uniform_time_path_tracer(void **state)
{
    (void)state;
    check_soft_target("uniform-time path tracer", ", \"time_sampling\": \"uniform\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_path_tracer),
        cmocka_unit_test(test_darts_path_tracer),
        cmocka_unit_test(test_uniform_time_path_tracer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
