/* tier: quick */
/* Analytic single scattering: infinite homogeneous medium, point light, pinhole camera, max_bounces 2.
 * Each pixel's expected value is computed independently by quadrature (Gauss–Legendre over the pixel
 * footprint × composite Gauss–Legendre along the camera ray, over exactly the distances whose camera-warped
 * path time falls in the gate), and the path tracer's image is checked against it with z-scores from the
 * render's own measured standard error (16 independent seeds). The pulse and time-mode cases (issue 21)
 * use a second quadrature along the ray, written for them: camera-unwarped time (the camera leg left out)
 * and a box pulse, as the average of delta pulses over the pulse's emission times, taken in closed form. */
#include "fixtures.h"
#include "test_util.h"

#include "dartspp/render.h"

/* compiled twice (main at the end): each program leaves the other's cases unused */
#pragma GCC diagnostic ignored "-Wunused-function"

#define SEEDS 16 /* the plain path tracer's cases; check_against_quadrature_seeds takes others */

/* 8-point Gauss–Legendre nodes and weights on [-1, 1]. */
static const double gl_x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                               0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
static const double gl_w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066735252903, 0.3626837833783620,
                               0.3626837833783620, 0.3137066735252903, 0.2223810344533745, 0.1012285362903763};

typedef struct {
    vec3 cam, light, I, ss, st;
    double g, eta;
    int gated;
    double g0, g1;
    int unwarp;        /* the camera leg takes no time */
    double p0, pw;     /* pulse: emission at p0 (pw = 0) or uniformly over [p0, p0 + pw) */
    double rs, rt;     /* the sensor's response: Gaussian σ and exponential tail mean (0, 0: none) */
    int gauss;         /* the pulse is a Gaussian of FWHM pw peaked at p0 + pw/2 (docs/time.md §5), not a box */
} analytic_case;

static double hg(double g, double mu)
{
    double d = 1 + g * g - 2 * g * mu;
    return (1 - g * g) / (4 * M_PI * d * sqrt(d));
}

/* radiance integrand at distance s along ray psi, channel ch */
static double integrand(const analytic_case *a, vec3 psi, double s, int ch)
{
    vec3 x = v3_add(a->cam, v3_scale(psi, s));
    vec3 lx = v3_sub(x, a->light);
    double R = v3_len(lx);
    double mu = v3_dot(v3_scale(lx, 1 / R), v3_neg(psi)); /* light->x propagation vs x->camera */
    return v3_comp(a->ss, ch) * hg(a->g, mu) * v3_comp(a->I, ch) * exp(-v3_comp(a->st, ch) * (s + R)) / (R * R);
}

static double path_time(const analytic_case *a, vec3 psi, double s)
{
    return a->eta * (s + v3_len(v3_sub(v3_add(a->cam, v3_scale(psi, s)), a->light)));
}

/* smallest s with path_time(s) >= t (path_time is non-decreasing in s) */
static double solve_time(const analytic_case *a, vec3 psi, double t)
{
    double lo = 0, hi = 1;
    if (path_time(a, psi, 0) >= t) return 0;
    while (path_time(a, psi, hi) < t) hi *= 2;
    for (int i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (path_time(a, psi, mid) < t) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* ---- pulses and unwarped time: a second quadrature along the ray ----
 * Along psi the light-to-camera time of the vertex at distance s, before emission, is T(s) = η(s + R(s))
 * warped or η·R(s) unwarped (R = |x(s) − light|). A delta pulse at τ0 counts the vertex iff T(s) + τ0 is in
 * the gate; a box pulse over [p0, p0 + pw) of unit weight is the average of delta pulses over τ0 in it,
 * which is the overlap fraction W(s) = |[g0 − T, g1 − T) ∩ [p0, p0 + pw)| / pw, in closed form (the
 * trapezoid of docs/time.md §5). The integrand f(s)·W(s) is smooth between the distances where T(s)
 * crosses g0 − p0 − pw, g0 − p0, g1 − p0 − pw or g1 − p0: composite Gauss–Legendre between those. */
static double light_time(const analytic_case *a, vec3 psi, double s)
{
    double R = v3_len(v3_sub(v3_add(a->cam, v3_scale(psi, s)), a->light));
    return a->eta * (a->unwarp ? R : s + R);
}

/* The exponentially modified Gaussian's CDF, written here from its closed form (the response's offset is a
 * normal deviate of σ plus an exponential of mean τ): Φ(x/σ) − exp(σ²/(2τ²) − x/τ)·Φ(x/σ − σ/τ). */
static double emg_cdf(double x, double s, double t)
{
    double phi = 0.5 * erfc(-x / (s * sqrt(2.0)));
    if (t == 0) return phi;
    return phi - exp(s * s / (2 * t * t) - x / t) * 0.5 * erfc(-(x / s - s / t) / sqrt(2.0));
}

static double pulse_weight(const analytic_case *a, double T)
{
    if (a->gauss) { /* P(T + τ0 in the gate) for τ0 ~ N(p0 + pw/2, (pw / 2·sqrt(2 ln 2))²) */
        double m = a->p0 + 0.5 * a->pw, sd = a->pw / 2.3548200450309493;
        return 0.5 * erfc(-(a->g1 - T - m) / (sd * sqrt(2.0))) - 0.5 * erfc(-(a->g0 - T - m) / (sd * sqrt(2.0)));
    }
    if (a->rs > 0) /* a delta pulse through the response: P(T + p0 + offset in the gate) */
        return emg_cdf(a->g1 - T - a->p0, a->rs, a->rt) - emg_cdf(a->g0 - T - a->p0, a->rs, a->rt);
    if (a->pw == 0) return T + a->p0 >= a->g0 && T + a->p0 < a->g1;
    double lo = fmax(a->g0 - T, a->p0), hi = fmin(a->g1 - T, a->p0 + a->pw);
    return hi > lo ? (hi - lo) / a->pw : 0.0;
}

/* Distances s >= 0 with T(s) = c, appended to out (at most 2). */
static int time_crossings(const analytic_case *a, vec3 psi, double c, double *out)
{
    vec3 l = v3_sub(a->light, a->cam);
    double b = v3_dot(psi, l), D2 = v3_dot(l, l), tau = c / a->eta;
    int n = 0;
    if (a->unwarp) { /* |ψs − l| = τ: s² − 2bs + D² − τ² = 0 */
        double disc = b * b - D2 + tau * tau;
        if (disc < 0 || tau <= 0) return 0;
        double r = sqrt(disc);
        if (b - r >= 0) out[n++] = b - r;
        if (b + r >= 0) out[n++] = b + r;
    } else if (tau > 0 && tau * tau > D2) { /* s + |ψs − l| = τ (τ > D >= b, so s > 0) */
        out[n++] = (tau * tau - D2) / (2 * (tau - b));
    }
    return n;
}

static int cmp_double(const void *x, const void *y)
{
    double u = *(const double *)x, v = *(const double *)y;
    return (u > v) - (u < v);
}

static double ray_radiance_pulse(const analytic_case *a, vec3 psi, int ch)
{
    double cs[4] = {a->g0 - a->p0 - a->pw, a->g0 - a->p0, a->g1 - a->p0 - a->pw, a->g1 - a->p0};
    if (a->gauss) { /* a Gaussian pulse's weight is below 1e-15 beyond 8 σ of its peak */
        double m = a->p0 + 0.5 * a->pw, sd = a->pw / 2.3548200450309493;
        cs[0] = a->g0 - m - 8 * sd, cs[1] = a->g0 - m, cs[2] = a->g1 - m, cs[3] = a->g1 - m + 8 * sd;
    }
    if (a->rs > 0) { /* the response's weight is below 1e-12 beyond these path times */
        cs[0] = a->g0 - a->p0 - 30 * a->rt - 8 * a->rs;
        cs[3] = a->g1 - a->p0 + 8 * a->rs;
    }
    double bp[10] = {0};
    int n = 1;
    for (int k = 0; k < 4; k++) n += time_crossings(a, psi, cs[k], bp + n);
    qsort(bp, (size_t)n, sizeof(double), cmp_double);
    const int panels = 60;
    double sum = 0;
    for (int i = 0; i + 1 < n; i++) {
        double h = (bp[i + 1] - bp[i]) / panels;
        for (int p = 0; p < panels && h > 0; p++)
            for (int k = 0; k < 8; k++) {
                double s = bp[i] + h * (p + 0.5 + 0.5 * gl_x[k]);
                double w = pulse_weight(a, light_time(a, psi, s));
                if (w > 0) sum += gl_w[k] * 0.5 * h * w * integrand(a, psi, s, ch);
            }
    }
    return sum / (a->g1 - a->g0); /* beyond the last crossing T(s) + τ0 >= g1 for every τ0 */
}

static double ray_radiance(const analytic_case *a, vec3 psi, int ch)
{
    if (a->unwarp || a->p0 != 0 || a->pw != 0 || a->rs > 0 || a->gauss) return ray_radiance_pulse(a, psi, ch);
    double s0 = 0, s1;
    if (a->gated) {
        s0 = solve_time(a, psi, a->g0);
        s1 = solve_time(a, psi, a->g1);
    } else s1 = 80.0 / v3_comp(a->st, ch);
    const int panels = 400;
    double h = (s1 - s0) / panels, sum = 0;
    for (int p = 0; p < panels; p++)
        for (int k = 0; k < 8; k++) sum += gl_w[k] * 0.5 * h * integrand(a, psi, s0 + h * (p + 0.5 + 0.5 * gl_x[k]), ch);
    return a->gated ? sum / (a->g1 - a->g0) : sum;
}

static double pixel_value(const analytic_case *a, const camera *cam, int x, int y, int ch)
{
    double sum = 0;
    for (int i = 0; i < 8; i++)
        for (int j = 0; j < 8; j++) {
            vec3 psi = camera_ray_dir(cam, x + 0.5 + 0.5 * gl_x[i], y + 0.5 + 0.5 * gl_x[j]);
            sum += 0.25 * gl_w[i] * gl_w[j] * ray_radiance(a, psi, ch);
        }
    return sum;
}

static void write_scene(const char *path, const char *phase, double speed, const char *window, double p0, double pw,
                        int max_bounces)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.5, 0.35, 0.6],"
             "  \"sigma_a\": [0.1, 0.2, 0.05], \"speed_of_light\": %.17g, \"phase_function\": %s } ],"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": [1, 2, 3], \"ext_medium\": \"fog\","
             "    \"pulse_start\": %.17g, \"pulse_width\": %.17g, \"transform\": { \"position\": [1.5, 0.8, 2.0] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [12, 8], \"fov\": 50, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": %d, %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             speed, phase, p0, pw, max_bounces, window);
    test_write_file(path, text);
}

/* The time mode and pulse of a case: unwarp 1 adds camera_unwarp to the integrator, (p0, pw) is the light's
 * pulse. */
typedef struct {
    int unwarp;
    double p0, pw;
    double rs, rt; /* the sensor's response (Gaussian σ, tail mean), written as the sensor_jitter_* keys */
    int orders;    /* > 0: max_bounces 8 and bounce_orders 2; the order-1 layer (one scattering event) is checked */
} time_mode;

/* Renders the single-scattering scene at `path` (one medium, one point light, max_bounces 2, or the order-1 layer
 * when `orders`) with `seeds` seeds of `passes` passes and checks every pixel and channel against the quadrature
 * of a, whose camera, light and coefficients are taken from the loaded scene here (the rest: the caller's);
 * q_given: that quadrature already worked out, in the film's order (pixel_value), or NULL. */
static void check_scene_against_quadrature(const char *path, analytic_case a, const char *label, int orders, long passes,
                                           int seeds, const double *q_given)
{
    scene s;
    dp_error err;
    scene_load_options lo = {0};
    if (scene_load(path, &lo, &s, &err)) fail_msg("%s", err.msg);
    a.cam = s.cam.pos, a.light = s.lights[0].pos, a.I = s.lights[0].value;
    a.ss = s.media[0].sigma_s, a.st = s.media[0].sigma_t;
    assert_int_equal(s.cam.response.on, a.rs > 0);
    assert_int_equal(s.integrator.window.camera_unwarp, a.unwarp);
    assert_true(s.lights[0].pulse.start == a.p0 && s.lights[0].pulse.width == a.pw);
    int n = s.cam.width * s.cam.height * 3;
    double *sum = calloc(n, sizeof(double)), *sq = calloc(n, sizeof(double));
    for (int k = 0; k < seeds; k++) {
        render_options ro = {.threads = 2, .seed = 1000 + k, .spp = passes, .time_limit = 0};
        film f;
        render_stats st;
        assert_int_equal(render_scene(&s, &ro, &f, &st, &err), 0);
        assert_int_equal(st.nonfinite, 0);
        const float *layer = orders ? &f.frame_sum[(size_t)n * film_order_layer(&f.window, 1, -1)] : NULL;
        for (int i = 0; i < n; i++) {
            double v = (layer ? (double)layer[i] : f.sum[i]) / f.weight_sum;
            sum[i] += v;
            sq[i] += v * v;
        }
        film_free(&f);
    }
    double z2 = 0, zmax = 0, tot = 0, tot_q = 0, tot_var = 0;
    for (int y = 0; y < s.cam.height; y++)
        for (int x = 0; x < s.cam.width; x++)
            for (int ch = 0; ch < 3; ch++) {
                int i = 3 * (y * s.cam.width + x) + ch;
                double mean = sum[i] / seeds, var = (sq[i] - seeds * mean * mean) / (seeds - 1);
                double q = q_given ? q_given[i] : pixel_value(&a, &s.cam, x, y, ch), se = sqrt(var / seeds);
                assert_true(q > 0);
                assert_true(se > 0);
                double z = (mean - q) / se;
                z2 += z * z;
                zmax = fmax(zmax, fabs(z));
                tot += mean;
                tot_q += q;
                tot_var += var / seeds;
            }
    double zglob = (tot - tot_q) / sqrt(tot_var);
    print_message("  %s: mean z^2 %.3f, max |z| %.2f, total %.6g vs quadrature %.6g (z %.2f, rel se %.2g)\n", label,
                  z2 / n, zmax, tot, tot_q, zglob, sqrt(tot_var) / tot_q);
    /* z follows Student's t with seeds − 1 dof: E[z^2] = 15/13 for 16 seeds (1.07 for 32); the three channels
     * of a pixel are nearly one value, so the mean over 96 pixels has sd ~0.19 (16 seeds), ~0.13 (32) */
    assert_true(z2 / n < 1.6);
    assert_true(zmax < 7.0);
    assert_true(fabs(zglob) < 4.0);
    free(sum);
    free(sq);
    scene_free(&s);
}

static void check_against_quadrature_seeds(const char *phase, double g, double speed, const char *window, int gated,
                                           double g0, double g1, long passes, time_mode tm, int seeds)
{
    char *dir = test_tmpdir(), path[512], win[512], label[256];
    snprintf(path, sizeof path, "%s/single.json", dir);
    snprintf(win, sizeof win, "%s%s", window, tm.unwarp ? ", \"camera_unwarp\": true" : "");
    if (tm.rs > 0)
        snprintf(win + strlen(win), sizeof win - strlen(win), ", \"sensor_jitter_fwhm\": %.17g, \"sensor_jitter_tail\": %.17g",
                 tm.rs * 2.3548200450309493, tm.rt);
    if (tm.orders) snprintf(win + strlen(win), sizeof win - strlen(win), ", \"bounce_orders\": 2");
    write_scene(path, phase, speed, win, tm.p0, tm.pw, tm.orders ? 8 : 2);
    analytic_case a = {.g = g, .eta = 1.0 / speed, .gated = gated, .g0 = g0, .g1 = g1, .unwarp = tm.unwarp,
                       .p0 = tm.p0, .pw = tm.pw, .rs = tm.rs, .rt = tm.rt};
    snprintf(label, sizeof label, "%s speed %g %s", phase, speed, gated ? "gated" : "steady");
    check_scene_against_quadrature(path, a, label, tm.orders, passes, seeds, NULL);
    test_rmtree(dir);
}

static void check_against_quadrature_mode(const char *phase, double g, double speed, const char *window, int gated,
                                          double g0, double g1, long passes, time_mode tm)
{
    check_against_quadrature_seeds(phase, g, speed, window, gated, g0, g1, passes, tm, SEEDS);
}

static void check_against_quadrature(const char *phase, double g, double speed, const char *window, int gated,
                                     double g0, double g1, long passes)
{
    check_against_quadrature_mode(phase, g, speed, window, gated, g0, g1, passes, (time_mode){0, 0, 0, 0, 0, 0});
}

static void test_gate_isotropic(void **state)
{
    (void)state;
    check_against_quadrature("{\"type\": \"isotropic\"}", 0.0, 1.0,
                             "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5", 1, 3.0, 3.5, 3000);
}

static void test_gate_hg_refractive(void **state)
{
    (void)state;
    /* speed_of_light 0.75: eta = 4/3, every segment takes 4/3 of its length */
    check_against_quadrature("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75,
                             "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6", 1, 4.0, 4.6, 3000);
}

static void test_steady_hg_backward(void **state)
{
    (void)state;
    check_against_quadrature("{\"type\": \"henyey_greenstein\", \"g\": -0.5}", -0.5, 1.0, "\"transient_time_width\": 0",
                             0, 0, 0, 600);
}

/* A box pulse of width 0.6 from 0.4 under the gate [4, 4.6) of refractive index 4/3: the quadrature is the
 * average of delta pulses over the pulse (ray_radiance_pulse). And a delta pulse at 0.4, the gate of
 * test_gate_isotropic moved by 0.4: the quadrature knows nothing of test_gate_isotropic's, so this also checks
 * that the emission time is added once. Checked against broken variants: the box pulse drawn over
 * [start, start + 2·width): mean z² 11617, image total −48 %; the emission time left out of the path
 * tracer's light connections: mean z² 7893, total −57 %. */
static void test_box_pulse(void **state)
{
    (void)state;
    check_against_quadrature_mode("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75,
                                  "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6", 1, 4.0, 4.6, 3000,
                                  (time_mode){0, 0.4, 0.6, 0, 0, 0});
    check_against_quadrature_mode("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                  "\"transient_time_center\": 3.65, \"transient_time_width\": 0.5", 1, 3.4, 3.9, 3000,
                                  (time_mode){0, 0.4, 0, 0, 0, 0});
}

/* Camera-unwarped time: only the light leg counts, so the gate [0.8, 2.6) selects the shell 0.8 <= R < 2.6
 * around the light, which the camera sees in every pixel — while warped, no path reaches the camera before
 * η·|camera − light| = 2.62, so the same gate is exactly black: every pixel 0 in every seed. Unwarped against
 * the quadrature with the camera leg left out (ray_radiance_pulse: the shell's chord along each ray). Checked
 * against a broken variant: camera_unwarp ignored by the path tracer: the image is black, and the check
 * fails (no pixel has a standard error). */
static void test_unwarped_early_gate(void **state)
{
    (void)state;
    const char *window = "\"transient_time_center\": 1.7, \"transient_time_width\": 1.8";
    char *dir = test_tmpdir(), path[512];
    snprintf(path, sizeof path, "%s/warped.json", dir);
    write_scene(path, "{\"type\": \"isotropic\"}", 1.0, window, 0, 0, 2);
    scene s;
    dp_error err;
    scene_load_options lo = {0};
    if (scene_load(path, &lo, &s, &err)) fail_msg("%s", err.msg);
    assert_true(v3_len(v3_sub(s.lights[0].pos, s.cam.pos)) > 2.6); /* the gate ends before any warped path */
    for (int k = 0; k < 4; k++) {
        render_options ro = {.threads = 2, .seed = 70 + k, .spp = 500};
        film f;
        render_stats st;
        assert_int_equal(render_scene(&s, &ro, &f, &st, &err), 0);
        for (size_t i = 0; i < (size_t)3 * f.width * f.height; i++) assert_true(f.sum[i] == 0.0);
        film_free(&f);
    }
    scene_free(&s);
    test_rmtree(dir);
    check_against_quadrature_mode("{\"type\": \"isotropic\"}", 0.0, 1.0, window, 1, 0.8, 2.6, 3000, (time_mode){1, 0, 0, 0, 0, 0});
}

/* The DARTS path tracer (DA distance sampling along the camera ray toward the light, the light connection by an
 * elliptical control vertex on it: for single scattering, the whole image comes from control vertices) and the
 * uniform-time path tracer (line-to-point connections) against the same quadratures: the gate, HG with
 * η = 4/3 (one region, so control vertices stay on), a box pulse (its emission time drawn before the bin is
 * aimed at), and camera-unwarped time (no sampler aims along the camera segment). 32 seeds of 300 passes
 * each (these estimators spend every sample in the gate, so fewer passes reach the plain cases' precision). Broken variants (tests/README.md): the control vertex weighted
 * by the elliptical density alone while sampled from the MIS mixture, and the emission time left out of the
 * aimed bin. */
#define DARTS_PT "\"enable_guiding\": true, \"enable_elliptical\": true"
#define UNIFORM_PT "\"time_sampling\": \"uniform\""

/* The isotropic gate, one case per method (the quick tier's consistency render of each). */
static void test_darts_pt_gate(void **state)
{
    (void)state;
    check_against_quadrature_seeds("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                   "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5, " DARTS_PT, 1, 3.0, 3.5,
                                   300, (time_mode){0, 0, 0, 0, 0, 0}, 32);
}

static void test_uniform_time_gate(void **state)
{
    (void)state;
    check_against_quadrature_seeds("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                   "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5, " UNIFORM_PT, 1, 3.0,
                                   3.5, 300, (time_mode){0, 0, 0, 0, 0, 0}, 32);
}

/* HG with η = 4/3 for both methods, a box pulse and camera-unwarped time for the DARTS path tracer. */
static void test_darts_and_uniform_time(void **state)
{
    (void)state;
    const char *methods[2] = {DARTS_PT, UNIFORM_PT};
    char w[512];
    for (int m = 0; m < 2; m++) {
        snprintf(w, sizeof w, "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6, %s", methods[m]);
        check_against_quadrature_seeds("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75, w, 1, 4.0, 4.6, 300,
                                       (time_mode){0, 0, 0, 0, 0, 0}, 32);
    }
    snprintf(w, sizeof w, "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6, %s", DARTS_PT);
    check_against_quadrature_seeds("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75, w, 1, 4.0, 4.6, 300,
                                   (time_mode){0, 0.4, 0.6, 0, 0, 0}, 32);
    snprintf(w, sizeof w, "\"transient_time_center\": 1.7, \"transient_time_width\": 1.8, %s", DARTS_PT);
    check_against_quadrature_seeds("{\"type\": \"isotropic\"}", 0.0, 1.0, w, 1, 0.8, 2.6, 300, (time_mode){1, 0, 0, 0, 0, 0}, 32);
}

/* Scattering orders (integrator key bounce_orders, docs/time.md §7): with max_bounces 8 the paths of one
 * scattering event, the order-1 layer, are exactly what the quadrature integrates; the gate image holds
 * every order (the layers' sum: test_sensor.c). Gated isotropic, and HG with η 4/3 under the DARTS path
 * tracer. Broken variant: the order taken as the camera path's depth + 1 fails both. */
static void test_order_one_layer(void **state)
{
    (void)state;
    char w[512];
    time_mode tm = {0, 0, 0, 0, 0, 1};
    check_against_quadrature_mode("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                  "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5", 1, 3.0, 3.5, 3000, tm);
    snprintf(w, sizeof w, "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6, %s", DARTS_PT);
    check_against_quadrature_seeds("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75, w, 1, 4.0, 4.6, 300, tm, 32);
}

/* The sensor's time response (docs/sensor.md §2): a Gaussian jitter of σ 0.15 with an exponential tail of
 * mean 0.1, and a tail-dominated one (σ 0.05, mean 0.3, which reaches paths of every time down to the
 * earliest, 2.625), on a 0.5-wide gate, against the quadrature of the path time's weight convolved with the
 * response in closed form (emg_cdf), for the path tracer (the offset drawn at the light connection) and the
 * DARTS path tracer (drawn at the aimed path's start). */
static void test_sensor_response(void **state)
{
    (void)state;
    char w[512];
    time_mode tm = {0, 0, 0, 0.15, 0.1, 0}, tail = {0, 0, 0, 0.05, 0.3, 0};
    check_against_quadrature_mode("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                  "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5", 1, 3.0, 3.5, 3000, tm);
    check_against_quadrature_mode("{\"type\": \"isotropic\"}", 0.0, 1.0,
                                  "\"transient_time_center\": 3.25, \"transient_time_width\": 0.5", 1, 3.0, 3.5, 3000, tail);
    snprintf(w, sizeof w, "\"transient_time_center\": 4.3, \"transient_time_width\": 0.6, %s", DARTS_PT);
    check_against_quadrature_seeds("{\"type\": \"henyey_greenstein\", \"g\": 0.4}", 0.4, 0.75, w, 1, 4.0, 4.6, 300, tm, 32);
}

/* Two programs from this file: test_single_scatter (quick tier) holds the plain path tracer's isotropic gate
 * case and one gate case of the DARTS and of the uniform-time path tracer; test_single_scatter_modes
 * (tests/path_tracer/test_single_scatter_modes.c, `make test`) includes this file with SINGLE_SCATTER_MODES for
 * the other cases: the plain path tracer's refractive (HG, η = 4/3) and steady cases, both methods under HG with
 * η = 4/3, box pulses, unwarped time, the sensor response and the order-1 layer. The derivatives' test
 * (tests/derivative/test_deriv_single_scatter.c) includes it with SINGLE_SCATTER_QUADRATURE_ONLY for the
 * quadratures alone. */
#ifndef SINGLE_SCATTER_QUADRATURE_ONLY
int main(void)
{
    const struct CMUnitTest tests[] = {
#ifndef SINGLE_SCATTER_MODES
        cmocka_unit_test(test_gate_isotropic),
        cmocka_unit_test(test_darts_pt_gate),
        cmocka_unit_test(test_uniform_time_gate),
#else
        cmocka_unit_test(test_gate_hg_refractive),
        cmocka_unit_test(test_steady_hg_backward),
        cmocka_unit_test(test_box_pulse),
        cmocka_unit_test(test_unwarped_early_gate),
        cmocka_unit_test(test_sensor_response),
#endif
    };
#ifdef SINGLE_SCATTER_MODES
    /* make stress only (32 s on 2 cores): the DARTS and uniform-time path tracers under HG with η = 4/3 (the
     * quick tier checks both, isotropic) and the order-1 layer of bounce_orders */
    const struct CMUnitTest stress[] = {
        cmocka_unit_test(test_darts_and_uniform_time),
        cmocka_unit_test(test_order_one_layer),
    };
    return RUN_TESTS_AND_STRESS(tests, stress);
#else
    return cmocka_run_group_tests(tests, NULL, NULL);
#endif
}
#endif
