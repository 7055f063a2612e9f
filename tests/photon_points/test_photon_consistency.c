/* tier: stress */
/* Photon points against the reference path tracer on a small gated fog box: per-pixel error (NMSE against the
 * measured noise, falling with the iterations) and per-channel image totals, for baseline photon points, DARTS
 * photon points and DARTS with EDA (HG g = 0.3; EDA also at g = 0.5 and −0.3). Every tolerance below is
 * derived from a noise estimate measured in the same test (spread over independent seeds or passes) plus a
 * stated bias budget; no expected value comes from an earlier run of this code. */
#include "fixtures.h"
#include "render_fixtures.h"

#define CO_RES 24
#define CO_PP_SEEDS 6
#define CO_PT_CHUNKS 8
#define CO_PT_PASSES 1024 /* per chunk */

typedef enum { CO_PATH_TRACER, CO_BASELINE, CO_DARTS, CO_DARTS_EDA } co_method;

static char co_table_dir[600]; /* EDA tables of the test, in its temporary folder */

static void co_integrator(char *out, size_t len, co_method m)
{
    const char *common = "\"max_bounces\": 4, \"transient_time_center\": 5.0, \"transient_time_width\": 2.0";
    char darts[768] = "";
    if (m >= CO_DARTS)
        snprintf(darts, sizeof darts, ", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true%s%s%s",
                 m == CO_DARTS_EDA ? ", \"eda\": true, \"eda_shape\": [32, 32, 64], \"eda_table_dir\": \"" : "",
                 m == CO_DARTS_EDA ? co_table_dir : "", m == CO_DARTS_EDA ? "\"" : "");
    if (m == CO_PATH_TRACER) snprintf(out, len, "\"type\": \"path_tracer\", %s", common);
    else
        snprintf(out, len,
                 "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                 " \"photon_count\": 10000, \"volume_photon_count\": 1e6, \"gather_photon_count\": 64,"
                 " \"gather_radius\": 0.1, \"volume_gather_radius\": 0.06, \"alpha\": 0.7, \"volume_alpha\": 0.7, %s%s",
                 common, darts);
}

/* Per-pixel means over `runs` renders (seeds seed0, seed0 + 1, ...) of `passes` passes and the variances of
 * those means from their spread: after all passes (mean, var) and after the first snap_pass passes of the
 * same renders (snap_mean, snap_var; NULL: none). The per-pass image totals go to t (initialised here). */
static void co_mean_var(const scene *s, int runs, uint64_t seed0, long passes, long snap_pass, double *mean, double *var,
                        double *snap_mean, double *snap_var, pass_totals *t)
{
    size_t n = (size_t)s->cam.width * s->cam.height * 3;
    double *sq = calloc(2 * n, sizeof(double)), *snap = malloc(n * sizeof(double));
    assert_true(sq && snap);
    double *means[2] = {mean, snap_mean}, *vars[2] = {var, snap_var};
    for (int j = 0; j < 2; j++)
        if (means[j]) memset(means[j], 0, n * sizeof(double));
    pass_totals_init(t, s->integrator.window.frame_count);
    pass_probe pr = {.t = t, .snap_pass = snap_pass, .snap = snap_mean ? snap : NULL};
    for (int k = 0; k < runs; k++) {
        double *m = render_probe(s, 2, seed0 + k, passes, &pr), *img[2] = {m, snap};
        for (int j = 0; j < 2; j++)
            for (size_t i = 0; means[j] && i < n; i++) {
                means[j][i] += img[j][i] / runs;
                sq[j * n + i] += img[j][i] * img[j][i];
            }
        free(m);
    }
    for (int j = 0; j < 2; j++)
        for (size_t i = 0; means[j] && i < n; i++)
            vars[j][i] = fmax(0.0, (sq[j * n + i] - runs * means[j][i] * means[j][i]) / (runs - 1)) / runs;
    free(sq);
    free(snap);
}

/* A small gated fog box (24 × 24 pixels, volume and surface transport, up to 3 scattering events; the camera
 * outside the fog) rendered by photon points (baseline, DARTS, DARTS with EDA) after 4 and after 64
 * iterations (the first 4 passes of the same renders; 6 seeds), against the path tracer (8 × 1024 passes,
 * rendered here). Error: normalised MSE, Σ(x - ref)² / Σ ref² over all pixels and channels. Its expectation
 * is B² + V_pp + V_ref (squared bias, variance of the photon-points mean, variance of the reference), the
 * variances being measured from the spread over seeds and over reference chunks. And the image totals per
 * channel, with standard errors from the per-pass totals of both methods. */
/* The consistency box scene rendered by one method, in a temporary folder. */
static void co_scene(co_method method, double g, tmp_scene *t, scene *s)
{
    char integ[2048], text[8192];
    co_integrator(integ, sizeof integ, method);
    box_scene_text_cam(text, sizeof text, CO_RES, integ, g, 0);
    tmp_scene_write(t, text);
    load_scene(t->path, NULL, 0, s);
}

/* The path tracer's image of the consistency box: per-pixel mean and its summed variance, and the per-pass
 * totals. */
typedef struct {
    double *img, ref2, Vref;
    pass_totals t;
} co_reference;

static void consistency_check(co_method method, double g, const co_reference *ref)
{
    tmp_scene tq;
    scene sq;
    co_scene(method, g, &tq, &sq);
    size_t n = (size_t)CO_RES * CO_RES * 3;
    double *pp[2], *vpp[2];
    for (int c = 0; c < 2; c++) {
        pp[c] = malloc(n * sizeof(double));
        vpp[c] = malloc(n * sizeof(double));
        assert_true(pp[c] && vpp[c]);
    }
    print_message("  %s photon points, HG g = %g\n",
                  method == CO_DARTS_EDA ? "DARTS with EDA" : method == CO_DARTS ? "DARTS" : "baseline", g);
    const long iters[2] = {4, 64};
    pass_totals tpp;
    co_mean_var(&sq, CO_PP_SEEDS, 300, iters[1], iters[0], pp[1], vpp[1], pp[0], vpp[0], &tpp);
    double nmse[2], Vpp[2], Vref = ref->Vref;
    for (int c = 0; c < 2; c++) {
        double err = 0, v = 0;
        for (size_t i = 0; i < n; i++) {
            err += (pp[c][i] - ref->img[i]) * (pp[c][i] - ref->img[i]);
            v += vpp[c][i];
        }
        nmse[c] = err / ref->ref2;
        Vpp[c] = v / ref->ref2;
        print_message("  %2ld iterations: NMSE %.3g = noise %.3g (photon points %.3g + reference %.3g) %+.3g\n", iters[c],
                      nmse[c], Vpp[c] + Vref, Vpp[c], Vref, nmse[c] - Vpp[c] - Vref);
    }

    /* The error falls. The photon-points part of it, E(n) = NMSE(n) - V_ref, is V_pp(n) + B(n)². With both
     * kernels 2D, one iteration's variance grows at most like 1/r_i² (the photons in a kernel ∝ r_i²), so
     * V_pp(64)/V_pp(4) <= [Σ_{i<64} r0²/r_i² / 64²] / [Σ_{i<4} r0²/r_i² / 4²], computed from the schedule
     * (about 1/8 for α = 0.7); B² ∝ r⁴ shrinks faster still. Required: E(64) < 2 × that ratio × E(4), the
     * factor 2 for the noise of the two estimates. */
    double s4 = 0, s64 = 0;
    for (long i = 0; i < 64; i++) {
        double q = pow(radius_closed_form(1.0, 0.7, i, 2), -2);
        if (i < 4) s4 += q;
        s64 += q;
    }
    double ratio = (s64 / (64.0 * 64.0)) / (s4 / 16.0);
    double e4 = nmse[0] - Vref, e64 = nmse[1] - Vref;
    print_message("  photon-points error E(64)/E(4) = %.3g, schedule bound on the variance ratio %.3g\n", e64 / e4, ratio);
    assert_true(nmse[1] < nmse[0]);
    assert_true(e64 < 2 * ratio * e4);

    /* At 64 iterations the error is noise, give or take a bias of the same size: NMSE < 2 (V_pp + V_ref),
     * i.e. a squared-bias budget equal to the measured noise. A priori the bias is well below that: the
     * volume kernel (r <= 0.06, about half a pixel at the box) and the surface disc (R <= 0.1, 0.7 pixel on
     * the back wall) blur image features a few pixels wide by ~1 % (B² ~ 1e-4), against V_pp + V_ref
     * ~ 1e-3 for these sample counts. The sums run over 1728 values with 5 and 7 degrees of freedom each, so
     * the estimated noise is good to a few percent. */
    assert_true(nmse[1] < 2 * (Vpp[1] + Vref));

    /* The image totals at 64 iterations, per channel: |T_pp - T_pt| < z·sqrt(se_pp² + se_pt²) + b.
     * Standard errors from the per-pass totals (384 and 8192 passes: normal; with the camera outside the fog
     * the per-pass totals have a kurtosis of about 3). z = 4: two-sided 6.3e-5 per check, under 1e-3 for the
     * 15 checks of the consistency tests. Bias allowance b = 1 % of the path tracer's total: the kernel bias
     * of a total cannot be bounded below that here. The volume part can (the single-scattering analysis of
     * test_single_scatter_total with s >= 2, σt <= 0.55, r <= 0.06 bounds the interior terms by 0.1 %, and
     * volume photons within r·sin 31° of the fog's front face lose part of their kernel: below 0.2 %), but the
     * surface disc has terms of first order in R at the box's inner edges: a gather point within R of an
     * edge loses the part of its disc beyond the edge (-(2/3)R³ per unit edge length, against the πR²
     * normalisation) and gathers the photons of the other wall inside its sphere (+(π/3)R³): net +0.12·R
     * times the irradiance per unit edge length on each side, about +1.2 % of the surface image for uniform
     * irradiance at the mean R of 0.06, and the irradiance is not uniform. Offline, with the radii held
     * fixed: R = 0.2 instead of 0.1 raised the total by 1.2 %, r = 0.03 instead of 0.06 by 0.2 %; at the
     * schedule used here all methods came out 0.25 % below the path tracer (16 seeds). The check must see a
     * 2 % bias: z·se + b < 2 % is asserted. With every photon-points contribution scaled by 1.02 (0.98), the
     * baseline's channel 0 came out +1.66 % (-2.33 %) against a bound of 1.50 %. */
    for (int c = 0; c < 3; c++) {
        double m, se, mr, ser;
        pass_totals_mean_se(&tpp, 0, c, &m, &se);
        pass_totals_mean_se(&ref->t, 0, c, &mr, &ser);
        double sd = sqrt(se * se + ser * ser), b = 0.01 * mr;
        print_message("  channel %d: image total %.5g (se %.2g), path tracer %.5g (se %.2g): %+.2f %%, bound %.2f %%"
                      " (4 se %.2f %% + bias 1 %%)\n", c, m, se, mr, ser, 100 * (m - mr) / mr, 100 * (4 * sd + b) / mr,
                      100 * 4 * sd / mr);
        assert_true(4 * sd + b < 0.02 * mr);
        assert_true(fabs(m - mr) < 4 * sd + b);
    }

    for (int c = 0; c < 2; c++) {
        free(pp[c]);
        free(vpp[c]);
    }
    pass_totals_free(&tpp);
    scene_free(&sq);
    tmp_scene_remove(&tq);
}

static void consistency_suite(double g, co_method first, co_method last)
{
    tmp_scene tp;
    scene sp;
    co_scene(CO_PATH_TRACER, g, &tp, &sp);
    size_t n = (size_t)CO_RES * CO_RES * 3;
    co_reference ref = {.img = malloc(n * sizeof(double))};
    double *vref = malloc(n * sizeof(double));
    assert_true(ref.img && vref);
    co_mean_var(&sp, CO_PT_CHUNKS, 101, CO_PT_PASSES, 0, ref.img, vref, NULL, NULL, &ref.t);
    for (size_t i = 0; i < n; i++) {
        ref.ref2 += ref.img[i] * ref.img[i];
        ref.Vref += vref[i];
    }
    ref.Vref /= ref.ref2;
    assert_true(ref.ref2 > 0);
    /* baseline photon points, DARTS photon points (bin sampling, DA distance sampling, elliptical control
     * vertices, strict time mode), and DARTS with EDA direction sampling (HG g = 0.3 here): all must
     * converge to the path tracer's image */
    snprintf(co_table_dir, sizeof co_table_dir, "%s/tables", tp.dir);
    for (co_method method = first; method <= last; method++) consistency_check(method, g, &ref);
    free(ref.img);
    free(vref);
    pass_totals_free(&ref.t);
    scene_free(&sp);
    tmp_scene_remove(&tp);
}

static void test_consistency_vs_path_tracer(void **state)
{
    (void)state;
    consistency_suite(0.3, CO_DARTS, CO_DARTS);
}

/* DARTS with EDA direction sampling on the same box (make stress; make test checks EDA's sampling against its
 * pdf in test_eda and the DARTS path tracer with EDA per tile in test_path_tracer_methods). */
static void test_eda_consistency(void **state)
{
    (void)state;
    consistency_suite(0.3, CO_DARTS_EDA, CO_DARTS_EDA);
}

/* Baseline photon points on the same box (make stress; make test checks the baseline against the path tracer
 * per tile in tests/emitters/test_emitters_render.c and against quadrature in test_photon_single_scatter). */
static void test_baseline_consistency(void **state)
{
    (void)state;
    consistency_suite(0.3, CO_BASELINE, CO_BASELINE);
}

/* EDA with anisotropic fog, forward and backward scattering (issue: EDA direction sampling, end to end) */
static void test_eda_consistency_anisotropic(void **state)
{
    (void)state;
    consistency_suite(0.5, CO_DARTS_EDA, CO_DARTS_EDA);
    consistency_suite(-0.3, CO_DARTS_EDA, CO_DARTS_EDA);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_consistency_vs_path_tracer),
    };
    /* make stress only (200 s on 2 cores): the baseline, and EDA at g = 0.3, 0.5 and -0.3, each against its own
     * path-traced reference; make test checks DARTS end to end at g = 0.3 above */
    const struct CMUnitTest stress[] = {
        cmocka_unit_test(test_baseline_consistency),
        cmocka_unit_test(test_eda_consistency),
        cmocka_unit_test(test_eda_consistency_anisotropic),
    };
    /* DARTSPP_TEST_FILTER=name (cmocka wildcards) runs only the matching tests */
    if (getenv("DARTSPP_TEST_FILTER")) cmocka_set_test_filter(getenv("DARTSPP_TEST_FILTER"));
    return RUN_TESTS_AND_STRESS(tests, stress);
}
