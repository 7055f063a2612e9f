/* A white Lambertian wall at range R in a purely absorbing medium (docs/lidar.md §7): every beam gives exactly one
 * echo, at its range R_b = R / cos(az_b) within half a range bin, its point on the wall, and an intensity equal to
 * the analytic echo energy
 *
 *   E_b = ρ Φ cos(az_b) e^{−2α R_b} / (π R_b²)
 *
 * (the beam's flux spread over its spot, reflected as ρ/π radiance, seen in the spot's solid angle π δ² ·…;
 * docs/lidar.md §3), at two absorption coefficients α, each against the analytic value and the ratio between them
 * against e^{−2(α₂ − α₁) R_b}, within noise measured over seeds. A box pulse one bin long puts the whole echo in
 * at most two bins; the energy is summed over the echo's bins and one more each side, since a sliver of the pulse
 * in a neighbouring bin can fall below the threshold (measured: −2 % at R_b 12.096, where 2 % of the pulse is in
 * the bin before). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "render_fixtures.h"
#include "test_util.h"

#include "dartspp/film.h"
#include "dartspp/lidar.h"

#define R 12.03
#define STEPS 6
#define SEEDS 12
#define PASSES 1500

static const char *const SCENE_FMT =
    "{ \"media\": [ { \"name\": \"air\", \"type\": \"homogeneous\", \"sigma_s\": 0, \"sigma_a\": %g,"
    "    \"phase_function\": { \"type\": \"isotropic\" } } ],"
    "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 1 } ],"
    "  \"primitives\": [ { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, %g],"
    "    \"scale\": [40, 1, 40], \"rotation\": [-90, 0, 0] } } ],"
    "  \"camera\": { \"type\": \"lidar\", \"medium\": \"air\", \"channels\": 1, \"elevation\": [0, 0],"
    "    \"azimuth\": [-12, 12], \"azimuth_steps\": %d, \"beam_divergence\": 0.004, \"receiver_fov\": 0.008,"
    "    \"power\": 2, \"pulse_shape\": \"box\", \"pulse_width\": 0.4, \"max_range\": 20, \"range_bin\": 0.2,"
    "    \"echoes\": \"all\","
    "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
    "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 8 },"
    "  \"renderer\": { \"spp\": 1 } }";

typedef struct {
    double mean[STEPS], se[STEPS];
} beam_intensities;

/* One seed: every beam has one echo at R_b within half a bin, its point on the wall; its intensity into e. */
static void check_seed(const scene *s, uint64_t seed, double *e)
{
    film f;
    render_stats st;
    render_passes(s, 1, seed, PASSES, &f, &st); /* 6 pixels a pass: one thread */
    const lidar_params *l = &s->cam.lidar;
    float *w = NULL;
    dp_error err;
    if (lidar_waveforms(&f, -1, &w, &err)) fail_msg("%s", err.msg);
    double threshold = l->echo_threshold * lidar_peak_reference(l, l->max_range);
    lidar_points pts = {0};
    if (lidar_points_from_waveforms(l, s->cam.pos, s->cam.forward, v3_neg(s->cam.right), s->cam.up, w, &pts, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(pts.count, STEPS);
    for (int a = 0; a < STEPS; a++) {
        lidar_echo echo[4];
        int n = lidar_find_echoes(&w[(size_t)a * l->bins], l->bins, l->range_bin, threshold, LIDAR_ECHO_ALL, echo, 4);
        double az = l->azimuth[0] + (l->azimuth[1] - l->azimuth[0]) * (a + 0.5) / STEPS, Rb = R / cos(az);
        if (n != 1 || !(fabs(echo[0].range - Rb) < 0.5 * l->range_bin))
            fail_msg("beam %d: %d echoes, the first at %g (the wall at %g)", a, n, n ? echo[0].range : NAN, Rb);
        const float *row = &pts.rows[(size_t)a * LIDAR_POINT_COLUMNS];
        assert_true(fabs(row[2] - R) < 0.5 * l->range_bin); /* z on the wall */
        assert_true(fabs(atan2(row[0], row[2]) - az) < 1e-4); /* left is +x here (right = −x, Tungsten's): x = R tan(az) */
        /* the echo's energy: its bins widened by one each side, which holds a sliver of the pulse that fell into a
         * neighbouring bin below the threshold (the echo's intensity leaves it out: docs/lidar.md §4) */
        const float *wave = &w[(size_t)a * l->bins];
        e[a] = 0.0;
        for (int b = echo[0].first_bin - 1; b <= echo[0].last_bin + 1; b++)
            if (b >= 0 && b < l->bins) e[a] += wave[b];
        assert_true(echo[0].intensity <= e[a] * (1.0 + 1e-6));
    }
    lidar_points_free(&pts);
    free(w);
    film_free(&f);
}

static void render_alpha(double alpha, beam_intensities *out)
{
    char text[4096];
    snprintf(text, sizeof text, SCENE_FMT, alpha, R, STEPS);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    double e[SEEDS][STEPS];
    for (int k = 0; k < SEEDS; k++) check_seed(&s, 100 + (uint64_t)k, e[k]);
    for (int a = 0; a < STEPS; a++) {
        double m = 0.0, v = 0.0;
        for (int k = 0; k < SEEDS; k++) m += e[k][a] / SEEDS;
        for (int k = 0; k < SEEDS; k++) v += (e[k][a] - m) * (e[k][a] - m) / (SEEDS - 1);
        out->mean[a] = m;
        out->se[a] = sqrt(v / SEEDS);
    }
    scene_free(&s);
    tmp_scene_remove(&ts);
}

static double beam_azimuth(int a) { return (-12.0 + 24.0 * (a + 0.5) / STEPS) * M_PI / 180.0; }

static void test_wall_echoes_follow_absorption(void **state)
{
    (void)state;
    const double alpha[2] = {0.01, 0.06};
    beam_intensities bi[2];
    double zmax = 0.0;
    for (int i = 0; i < 2; i++) {
        render_alpha(alpha[i], &bi[i]);
        for (int a = 0; a < STEPS; a++) {
            double az = beam_azimuth(a), Rb = R / cos(az);
            double E = 2.0 * cos(az) * exp(-2.0 * alpha[i] * Rb) / (M_PI * Rb * Rb), z = (bi[i].mean[a] - E) / bi[i].se[a];
            zmax = fmax(zmax, fabs(z));
            if (getenv("LIDAR_WALL_VERBOSE") || a == 0 || a == STEPS / 2)
                printf("  alpha %.2f beam %d (R_b %.3f): intensity %.5e, analytic %.5e (%+.2f %%, z %+.2f)\n", alpha[i], a,
                       Rb, bi[i].mean[a], E, 100.0 * (bi[i].mean[a] / E - 1.0), z);
        }
    }
    double zr_max = 0.0;
    for (int a = 0; a < STEPS; a++) {
        double Rb = R / cos(beam_azimuth(a)), ratio = bi[1].mean[a] / bi[0].mean[a];
        double expect = exp(-2.0 * (alpha[1] - alpha[0]) * Rb);
        double se = ratio * hypot(bi[1].se[a] / bi[1].mean[a], bi[0].se[a] / bi[0].mean[a]);
        zr_max = fmax(zr_max, fabs(ratio - expect) / se);
        if (a == STEPS / 2)
            printf("  beam %d: I(0.06)/I(0.01) = %.5f, exp(-2 dα R_b) = %.5f (z %+.2f)\n", a, ratio, expect,
                   (ratio - expect) / se);
    }
    printf("  %d beams x 2 absorptions: max |z| %.2f against the analytic energy, %.2f for the ratio\n", STEPS, zmax,
           zr_max);
    assert_true(zmax < 3.5);
    assert_true(zr_max < 3.5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wall_echoes_follow_absorption),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
