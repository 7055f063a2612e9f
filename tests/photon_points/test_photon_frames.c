/* Frame mode with pulsed emitters: DARTS and baseline photon points against the path tracer's frames
 * (per-frame totals and one joint χ² test), and a later pulse moving every frame by exactly its delay. Every
 * tolerance below is derived from a noise estimate measured in the same test (spread over independent seeds or
 * passes) plus a stated bias budget; no expected value comes from an earlier run of this code. */
#include "render_fixtures.h"

/* In place: A (n × n, symmetric positive definite) -> A⁻¹, by Cholesky. Returns 0 if A is not positive
 * definite. */
static int spd_inverse(double *A, int n)
{
    double *L = calloc((size_t)n * n, sizeof(double)), *y = malloc((size_t)n * sizeof(double));
    assert_true(L && y);
    int ok = 1;
    for (int i = 0; i < n && ok; i++)
        for (int j = 0; j <= i; j++) {
            double v = A[i * n + j];
            for (int k = 0; k < j; k++) v -= L[i * n + k] * L[j * n + k];
            if (i == j) {
                if (!(v > 0)) ok = 0;
                else L[i * n + i] = sqrt(v);
            } else L[i * n + j] = v / L[j * n + j];
        }
    for (int col = 0; col < n && ok; col++) { /* solve L Lᵀ x = e_col */
        for (int i = 0; i < n; i++) {
            double v = i == col;
            for (int k = 0; k < i; k++) v -= L[i * n + k] * y[k];
            y[i] = v / L[i * n + i];
        }
        for (int i = n - 1; i >= 0; i--) {
            double v = y[i];
            for (int k = i + 1; k < n; k++) v -= L[k * n + i] * A[k * n + col];
            A[i * n + col] = v / L[i * n + i];
        }
    }
    free(L);
    free(y);
    return ok;
}

/* min over |β_i| <= b_i of (d - β)ᵀ A (d - β), A symmetric positive definite: the squared Mahalanobis
 * distance from d to the box of admissible biases (coordinate descent, exact for this convex quadratic). */
static double box_mahalanobis(const double *A, const double *d, const double *b, int n)
{
    double *beta = calloc((size_t)n, sizeof(double)), *r = malloc((size_t)n * sizeof(double));
    assert_true(beta && r);
    for (int sweep = 0; sweep < 500; sweep++) {
        double change = 0;
        for (int i = 0; i < n; i++) {
            double g = 0; /* (A r)_i with r = d - β */
            for (int j = 0; j < n; j++) g += A[i * n + j] * (d[j] - beta[j]);
            double nb = fmin(b[i], fmax(-b[i], beta[i] + g / A[i * n + i]));
            change = fmax(change, fabs(nb - beta[i]) / (b[i] + 1e-300));
            beta[i] = nb;
        }
        if (change < 1e-12) break;
    }
    double q = 0;
    for (int i = 0; i < n; i++) r[i] = d[i] - beta[i];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) q += r[i] * A[i * n + j] * r[j];
    free(beta);
    free(r);
    return q;
}

/* Sample covariance of the mean of the frame totals (images 1..F, 3 channels each: p = 3F values per pass),
 * added into C (p × p). */
static void add_mean_covariance(const pass_totals *t, double *C)
{
    int p = 3 * (t->images - 1);
    double *mean = calloc((size_t)p, sizeof(double));
    assert_non_null(mean);
    for (long i = 0; i < t->n; i++)
        for (int a = 0; a < p; a++) mean[a] += t->x[(size_t)i * t->images * 3 + 3 + a] / t->n;
    for (long i = 0; i < t->n; i++) {
        const double *x = &t->x[(size_t)i * t->images * 3 + 3];
        for (int a = 0; a < p; a++)
            for (int b = 0; b < p; b++) C[a * p + b] += (x[a] - mean[a]) * (x[b] - mean[b]) / ((t->n - 1.0) * t->n);
    }
    free(mean);
}

#define FR_FRAMES 8
#define FR_PP_SEEDS 12
#define FR_PT_CHUNKS 8

/* Two pulsed emitters (issue 21): the light of slab_scene_text firing at 0, and a second one, lower left,
 * with a box pulse over [0.45, 0.75): the frames hold the first light's wave and, 0.45-0.75 later, the
 * second's. */
#define FR_LIGHTS                                                                                              \
    SLAB_LIGHT ", { \"type\": \"point\", \"emission\": [3, 2, 4], \"pulse_start\": 0.45, \"pulse_width\": 0.3," \
               " \"transform\": { \"position\": [-0.7, -0.5, -2.5] } }"

/* Frame mode with two pulsed emitters: the fog slab (slab_scene_text, the lights of FR_LIGHTS) in 8 frames of
 * 0.3 from 3.5 (the fog in view lights up at 2.6, so every frame holds light that has spread into the fog),
 * rendered by DARTS photon points (DA distance sampling, control vertices, strict; each path aims at one frame
 * of the window seen from its own emission time: its photons are divided by that frame's probability and
 * gathered only there), by baseline photon points (12 seeds × 64 iterations each) and by the path tracer
 * (8 × 1024 passes). Compared: the per-frame image totals, per channel, with standard errors and covariances
 * from the per-pass totals (768 and 8192 passes).
 * Bias allowance b = 1 % of each frame's total (the path tracer's): volume photons carry their own path time,
 * so the kernel blurs space, not time, and each frame total has the kernel bias of a total: interior terms
 * (test_single_scatter_total) below (10 + σt s)·r²/(8s²) = 0.12 % at the nearest fog (s = 1.5) for the mean
 * r² of the schedule; the image border cuts through fog where the radiance changes over several pixels (a
 * second-order flux, ~0.1 %); photons within r·sin 21° of the front or back face lose part of their kernel
 * (first order in r, a few tenths of a percent while the light in a frame is spread through the slab: in
 * frames nearer the onset it is concentrated at the front face, -2.5 % at 0.3 after the onset, offline).
 * Checks:
 * (1) every frame and channel, each photon pass: |T_pp - T_pt| < 4·se + b (48 checks at two-sided 6.3e-5: 3e-3);
 * (2) jointly, one test over both photon passes: Q = min over biases β within ±b of (d - β)ᵀ C⁻¹ (d - β), d
 *     the 48 differences (DARTS − path tracer, then baseline − path tracer), C their covariance: the sum of the
 *     covariances of the means, the path tracer's in both blocks and across them (the two differences share
 *     its noise; the channels of a frame are strongly correlated, so Σ z² would not follow χ²). Q is at most the
 *     χ² statistic of the true bias, χ² with 48 degrees of freedom; C is estimated from 768 passes per photon
 *     pass, which inflates Q's mean by (n - 1)/(n - p - 2), corrected for. Required: χ² survival above 1e-3.
 * Checked against a broken variant (2026-11-25): the photon pass starting every light path at time 0 (the
 * second light's pulse ignored there, not in the path tracer): all 48 checks fail (DARTS and baseline −8 to
 * −20 % per frame), Q = 2001. */
static void test_frames_two_pulsed_emitters(void **state)
{
    (void)state;
    char text[8192], time[256];
    snprintf(time, sizeof time, "\"frame_num\": %d, \"start_time\": 3.5, \"transient_time_width\": 0.3", FR_FRAMES);
    enum { DARTS, BASE, PT, METHODS };
    pass_totals t[METHODS];
    const int runs[METHODS] = {FR_PP_SEEDS, FR_PP_SEEDS, FR_PT_CHUNKS};
    const long passes[METHODS] = {64, 64, 1024};
    for (int m = 0; m < METHODS; m++) {
        slab_scene_text_lights(text, sizeof text, 1.0, m == PT ? "path_tracer" : "progressive_transient_photon_map", time,
                               m == DARTS ? DARTS_KEYS : m == BASE ? BASELINE_KEYS : "", FR_LIGHTS);
        tmp_scene ts;
        tmp_scene_write(&ts, text);
        scene s;
        load_scene(ts.path, NULL, 0, &s);
        assert_int_equal(s.integrator.window.frame_count, FR_FRAMES);
        assert_int_equal(s.light_count, 2);
        assert_true(s.lights[1].pulse.start == 0.45 && s.lights[1].pulse.width == 0.3 && s.lights[0].pulse.start == 0);
        darts_guide g;
        scene_guide(&s, &g);
        if (m == DARTS) assert_true(g.active && g.enable_elliptical && g.frames == FR_FRAMES);
        else assert_false(g.active);
        render_totals(&s, 800 + 100 * m, runs[m], passes[m], &t[m]);
        scene_free(&s);
        tmp_scene_remove(&ts);
    }
    enum { F3 = 3 * FR_FRAMES, P = 2 * F3 };
    double d[P], b[P], *C = calloc(P * P, sizeof(double)), *Cm[METHODS];
    assert_non_null(C);
    int failed = 0;
    for (int m = 0; m < PT; m++)
        for (int k = 0; k < FR_FRAMES; k++)
            for (int c = 0; c < 3; c++) {
                double v, se, vr, ser;
                pass_totals_mean_se(&t[m], 1 + k, c, &v, &se);
                pass_totals_mean_se(&t[PT], 1 + k, c, &vr, &ser);
                double sd = sqrt(se * se + ser * ser);
                int i = m * F3 + 3 * k + c;
                d[i] = v - vr;
                b[i] = 0.01 * vr;
                int bad = !(fabs(v - vr) < 4 * sd + b[i]);
                failed += bad;
                if (c == 0 || bad)
                    print_message("  %s frame %d channel %d: %.5g (se %.2g), path tracer %.5g (se %.2g): %+.2f %%,"
                                  " bound %.2f %%%s\n", m == DARTS ? "DARTS" : "baseline", k, c, v, se, vr, ser,
                                  100 * (v - vr) / vr, 100 * (4 * sd + b[i]) / vr, bad ? "  FAIL" : "");
                assert_true(vr > 0 && ser > 0);
            }
    for (int m = 0; m < METHODS; m++) {
        Cm[m] = calloc(F3 * F3, sizeof(double));
        assert_non_null(Cm[m]);
        add_mean_covariance(&t[m], Cm[m]);
    }
    for (int i = 0; i < P; i++)
        for (int j = 0; j < P; j++) {
            int bi = i / F3, bj = j / F3, ii = i % F3, jj = j % F3;
            C[i * P + j] = Cm[PT][ii * F3 + jj] + (bi == bj ? Cm[bi][ii * F3 + jj] : 0.0);
        }
    assert_true(spd_inverse(C, P));
    long n = t[DARTS].n < t[BASE].n ? t[DARTS].n : t[BASE].n;
    double Q = box_mahalanobis(C, d, b, P) * (n - P - 2.0) / (n - 1.0);
    double pval = test_gamma_q(P / 2.0, Q / 2.0);
    print_message("  joint: Q = %.2f for %d degrees of freedom, chi-square survival %.3g (required > 1e-3)\n", Q, P, pval);
    assert_int_equal(failed, 0);
    assert_true(pval > 1e-3);
    free(C);
    for (int m = 0; m < METHODS; m++) {
        free(Cm[m]);
        pass_totals_free(&t[m]);
    }
}

/* A pulse that starts k frame widths later moves every frame by exactly k frames: the slab in 6 frames of
 * 0.3 from 3.5 with the light's pulse_start 0 and 0.6 (k = 2), the same seed. The path tracer and baseline
 * photon points draw the same random numbers either way (a delta pulse draws none), so frame j of the
 * later pulse is frame j − 2 of the first, contribution for contribution: the only differences allowed are
 * those of float summation order (a path cut at the window's end stores fewer photons beyond it, which
 * can reorder the film's additions): 1e-5 relative. Frames 0 and 1 of the later pulse have no counterpart.
 * Checked against broken variants (2026-11-25): the path tracer's light connections without the emission
 * time, and the photon pass's emission time doubled (frames moved by 4): both fail (lit pixels against dark
 * ones: largest relative differences 8e28 and 2e29). Unbroken, the path tracer's frames agree exactly (0). */
static void test_pulse_start_moves_frames(void **state)
{
    (void)state;
    const char *time = "\"frame_num\": 6, \"start_time\": 3.5, \"transient_time_width\": 0.3";
    const char *types[2] = {"path_tracer", "progressive_transient_photon_map"};
    for (int m = 0; m < 2; m++) {
        float *frames[2];
        size_t npx = 0;
        for (int shifted = 0; shifted < 2; shifted++) {
            char text[8192], light[512];
            snprintf(light, sizeof light, "{ \"type\": \"point\", \"emission\": [4, 4, 4], \"pulse_start\": %s,"
                     " \"transform\": { \"position\": [0.6, 0.4, -2.5] } }", shifted ? "0.6" : "0");
            slab_scene_text_lights(text, sizeof text, 1.0, types[m], time, m ? BASELINE_KEYS : "", light);
            tmp_scene ts;
            tmp_scene_write(&ts, text);
            scene s;
            load_scene(ts.path, NULL, 0, &s);
            film f;
            render_stats st;
            render_passes(&s, 2, 31, m ? 3 : 16, &f, &st);
            npx = (size_t)f.width * f.height;
            frames[shifted] = malloc(6 * npx * 3 * sizeof(float));
            assert_non_null(frames[shifted]);
            for (size_t i = 0; i < 6 * npx * 3; i++) frames[shifted][i] = (float)(f.frame_sum[i] / f.weight_sum);
            film_free(&f);
            scene_free(&s);
            tmp_scene_remove(&ts);
        }
        double worst = 0, lit = 0, moved_by_one = 0;
        for (int j = 2; j < 6; j++)
            for (size_t i = 0; i < npx * 3; i++) {
                double a = frames[1][(size_t)j * npx * 3 + i], r = frames[0][(size_t)(j - 2) * npx * 3 + i];
                double one = frames[0][(size_t)(j - 1) * npx * 3 + i];
                worst = fmax(worst, fabs(a - r) / fmax(fabs(r), 1e-30));
                lit += r;
                moved_by_one += fabs(one - r);
            }
        print_message("  %s: frames 2-5 of pulse_start 0.6 against frames 0-3 of pulse_start 0: largest relative"
                      " difference %.3g (sum %.4g; adjacent frames differ by %.4g in all)\n", types[m], worst, lit,
                      moved_by_one);
        assert_true(lit > 0);
        assert_true(moved_by_one > 0.1 * lit); /* the frames differ: a shift by the wrong count would show */
        assert_true(worst < 1e-5);
        free(frames[0]);
        free(frames[1]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frames_two_pulsed_emitters),
        cmocka_unit_test(test_pulse_start_moves_frames),
    };
    /* DARTSPP_TEST_FILTER=name (cmocka wildcards) runs only the matching tests */
    if (getenv("DARTSPP_TEST_FILTER")) cmocka_set_test_filter(getenv("DARTSPP_TEST_FILTER"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
