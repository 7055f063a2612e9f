/* The derivative images of single scattering against the derivative of its quadrature (docs/derivatives.md §7):
 * an infinite homogeneous fog, a point light with a box pulse, a pinhole camera, max_bounces 2, the gate [4, 4.6)
 * of η = 4/3 — the box-pulse case of tests/path_tracer/test_single_scatter.c, whose quadrature (Gauss–Legendre over
 * each pixel × composite Gauss–Legendre along the ray, the pulse's trapezoid in closed form) this program
 * includes. The reference ∂Q/∂θ per pixel is that quadrature differentiated numerically: Richardson's
 * extrapolation (4·D(h/2) − D(h))/3 of central differences, deterministic. Eight parameters at once (σs of one
 * channel, σa of another, g, the speed of light, the emission, the pulse's start and width, the gate's width);
 * every pixel of every derivative image against it, with z-scores from the spread of 16 seeds. */
#define SINGLE_SCATTER_QUADRATURE_ONLY 1
#include "../path_tracer/test_single_scatter.c"

#define NPAR 8

/* With the sensor's response (a delta pulse through a Gaussian jitter of σ RS and an exponential tail of mean RT,
 * docs/sensor.md §2), the pulse has no width to differentiate: the gate's centre instead. */
#define RS 0.15
#define RT 0.1
static const char *const POINTERS_RESPONSE[NPAR] = {
    "/media/0/sigma_s/1",         "/media/0/sigma_a/0",         "/media/0/phase_function/g",
    "/media/0/speed_of_light",    "/primitives/0/emission",     "/primitives/0/pulse_start",
    "/integrator/transient_time_center", "/integrator/transient_time_width",
};
static const char *const POINTERS[NPAR] = {
    "/media/0/sigma_s/1",         "/media/0/sigma_a/0",         "/media/0/phase_function/g",
    "/media/0/speed_of_light",    "/primitives/0/emission",     "/primitives/0/pulse_start",
    "/primitives/0/pulse_width",  "/integrator/transient_time_width",
};

#define SPEED 0.75
#define G_HG 0.4
#define P0 0.4
#define PW 0.6
/* the gate: camera-warped [4, 4.6), or unwarped (the light leg's time alone, docs/time.md §2.2) [1.2, 2.4) */
typedef struct {
    int unwarp;
    double g0, g1;
} gate_case;
static const gate_case WARPED = {0, 4.0, 4.6}, UNWARPED = {1, 1.2, 2.4};

/* pulse: 0 box, 1 Gaussian, 2 a delta pulse through the sensor's response */
static void deriv_scene(const char *path, const char *integrator, int pulse, gate_case gc)
{
    char text[4096], response[160] = "";
    if (pulse == 2)
        snprintf(response, sizeof response, ", \"sensor_jitter_fwhm\": %.17g, \"sensor_jitter_tail\": %.17g",
                 RS * 2.3548200450309493, RT);
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"guided_homo\", \"sigma_s\": [0.5, 0.35, 0.6],"
             "  \"sigma_a\": [0.1, 0.2, 0.05], \"speed_of_light\": %.17g,"
             "  \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": %.17g } } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": [1, 2, 3], \"ext_medium\": \"fog\","
             "    \"pulse_start\": %.17g, \"pulse_width\": %.17g, \"pulse_shape\": \"%s\", \"transform\": { \"position\": [1.5, 0.8, 2.0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [6, 4], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": 2, \"transient_time_center\": %.17g,"
             "    \"transient_time_width\": %.17g, \"camera_unwarp\": %s %s %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             SPEED, G_HG, P0, pulse == 2 ? 0.0 : PW, pulse == 1 ? "gaussian" : "box", 0.5 * (gc.g0 + gc.g1),
             gc.g1 - gc.g0, gc.unwarp ? "true" : "false", response, integrator);
    test_write_file(path, text);
}

/* The case with parameter k moved by d (in the file's units). */
static analytic_case moved(const analytic_case *a0, int k, double d)
{
    analytic_case a = *a0;
    if (k == 6 && a.rs > 0) { /* the response's list: the gate's centre */
        a.g0 += d, a.g1 += d;
        return a;
    }
    switch (k) {
    case 0: a.ss.y += d, a.st.y += d; break;
    case 1: a.st.x += d; break;
    case 2: a.g += d; break;
    case 3: a.eta = 1.0 / (SPEED + d); break;
    case 4: a.I = v3_add(a.I, v3s(d)); break;
    case 5: a.p0 += d; break;
    case 6: a.pw += d; break;
    default: a.g0 -= 0.5 * d, a.g1 += 0.5 * d; break;
    }
    return a;
}

/* ∂Q/∂θ_k of pixel (x, y), channel ch: Richardson of central differences of steps h and h/2. */
static double quadrature_derivative(const analytic_case *a0, const camera *cam, int k, int x, int y, int ch)
{
    const double h = 0.02;
    double d[2];
    for (int i = 0; i < 2; i++) {
        double hi = h / (1 + i);
        analytic_case p = moved(a0, k, hi), m = moved(a0, k, -hi);
        d[i] = (pixel_value(&p, cam, x, y, ch) - pixel_value(&m, cam, x, y, ch)) / (2 * hi);
    }
    return (4 * d[1] - d[0]) / 3;
}

static void check_derivatives(const char *label, const char *integrator, int pulse, gate_case gc, long passes,
                              int seeds)
{
    const char *const *pointers = pulse == 2 ? POINTERS_RESPONSE : POINTERS;
    char *dir = test_tmpdir(), path[512];
    snprintf(path, sizeof path, "%s/single.json", dir);
    deriv_scene(path, integrator, pulse, gc);
    scene s;
    dp_error err;
    scene_load_options lo = {.derivatives = pointers, .derivative_count = NPAR};
    if (scene_load(path, &lo, &s, &err)) fail_msg("%s", err.msg);
    analytic_case a = {.cam = s.cam.pos, .light = s.lights[0].pos, .I = s.lights[0].value, .ss = s.media[0].sigma_s,
                       .st = s.media[0].sigma_t, .g = G_HG, .eta = 1.0 / SPEED, .gated = 1, .g0 = gc.g0, .g1 = gc.g1, .unwarp = gc.unwarp,
                       .p0 = P0, .pw = pulse == 2 ? 0.0 : PW, .gauss = pulse == 1, .rs = pulse == 2 ? RS : 0.0,
                       .rt = pulse == 2 ? RT : 0.0};
    int n = s.cam.width * s.cam.height * 3;
    double *sum = calloc((size_t)n * NPAR, sizeof(double)), *sq = calloc((size_t)n * NPAR, sizeof(double));
    for (int r = 0; r < seeds; r++) {
        render_options ro = {.threads = 2, .seed = 2000 + r, .spp = passes};
        film f;
        render_stats st;
        if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
        assert_int_equal(st.nonfinite, 0);
        assert_int_equal(f.deriv_count, NPAR);
        for (int k = 0; k < NPAR; k++)
            for (int i = 0; i < n; i++) {
                double v = f.deriv[k].sum[i] / f.deriv[k].weight_sum;
                sum[(size_t)k * n + i] += v, sq[(size_t)k * n + i] += v * v;
            }
        film_free(&f);
    }
    /* the reference, once per gate and pulse (the integrators render the same scene) */
    static double *refs[2][3];
    double *ref = refs[gc.unwarp][pulse];
    if (!ref) {
        ref = refs[gc.unwarp][pulse] = calloc((size_t)n * NPAR, sizeof(double));
        for (int k = 0; k < NPAR; k++)
            for (int y = 0; y < s.cam.height; y++)
                for (int x = 0; x < s.cam.width; x++)
                    for (int ch = 0; ch < 3; ch++)
                        ref[(size_t)k * n + 3 * (y * s.cam.width + x) + ch] = quadrature_derivative(&a, &s.cam, k, x, y, ch);
    }
    double qmax[NPAR] = {0};
    for (int k = 0; k < NPAR; k++)
        for (int i = 0; i < n; i++) qmax[k] = fmax(qmax[k], fabs(ref[(size_t)k * n + i]));
    int failed = 0;
    for (int k = 0; k < NPAR; k++) {
        double z2 = 0, zmax = 0, tot = 0, tot_q = 0, tot_var = 0;
        for (int y = 0; y < s.cam.height; y++)
            for (int x = 0; x < s.cam.width; x++)
                for (int ch = 0; ch < 3; ch++) {
                    size_t i = (size_t)k * n + 3 * (y * s.cam.width + x) + ch;
                    double mean = sum[i] / seeds, var = (sq[i] - seeds * mean * mean) / (seeds - 1);
                    double q = ref[i], se = sqrt(var / seeds);
                    /* the standard error floored at 1e-4 of the image's largest value: a pixel whose paths reach the
                     * gate only through the Gaussian pulse's far tail (unwarped: rays far from the light) renders
                     * exactly 0 in all 16 seeds where the quadrature holds 1e-8 of the image */
                    double z = (mean - q) / fmax(se, 1e-4 * qmax[k]);
                    z2 += z * z, zmax = fmax(zmax, fabs(z));
                    tot += mean, tot_q += q, tot_var += var / seeds;
                }
        double zt = (tot - tot_q) / sqrt(tot_var);
        print_message("  %-13s %-34s total %+.5g vs quadrature %+.5g (%+.2f %%, z %.2f), mean z^2 %.2f, max |z| %.2f\n",
                      label, pointers[k], tot, tot_q, 100 * (tot - tot_q) / fabs(tot_q), zt, z2 / n, zmax);
        /* z ~ Student's t with 15 dof: E z² = 15/13, sd(z²) = sqrt(3·15²/(13·11) − (15/13)²) = 1.84; the three
         * channels of a pixel are nearly one value, so the mean over 24 pixels has sd 1.84/√24 = 0.38: the bound is
         * E + 3 sd = 2.3 */
        failed += !(z2 / n < 2.3 && zmax < 7.0 && fabs(zt) < 4.0);
    }
    assert_int_equal(failed, 0);
    free(sum);
    free(sq);
    scene_free(&s);
    test_rmtree(dir);
}

static void test_plain(void **state)
{
    (void)state;
    check_derivatives("plain", "", 1, WARPED, 1500, 16);
}

static void test_darts_and_uniform(void **state)
{
    (void)state;
    if (getenv("DERIV_PLAIN_ONLY")) return; /* the broken-variant runs (tests/README.md) */
    check_derivatives("DARTS", ", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true", 1, WARPED, 1500, 16);
    check_derivatives("uniform time", ", \"time_sampling\": \"uniform\"", 1, WARPED, 1500, 16);
}

/* Camera-unwarped time: the camera segment takes no time, so the speed of light's derivative counts the light leg
 * only (deriv_time skips the camera segment) */
static void test_unwarped(void **state)
{
    (void)state;
    check_derivatives("plain unwarped", "", 1, UNWARPED, 1500, 16);
}

/* The sensor's response (Gaussian jitter with an exponential tail) behind a delta pulse: S of the exponentially
 * modified Gaussian (docs/derivatives.md §2) */
static void test_response_derivatives(void **state)
{
    (void)state;
    check_derivatives("plain response", "", 2, WARPED, 3000, 16);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_plain), cmocka_unit_test(test_darts_and_uniform),
                                       cmocka_unit_test(test_unwarped), cmocka_unit_test(test_response_derivatives)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
