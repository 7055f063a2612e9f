/* tier: quick */
/* The offset's distribution (include/dartspp/derivative.h, src/derivative/time_kernel.c,
 * docs/derivatives.md §2) for every pulse (delta, box, Gaussian) with every response (off, Gaussian,
 * Gaussian + exponential tail, tail only, a table written here): (1) the CDF against the empirical CDF of
 * 200,000 draws of emitter_pulse_sample + sensor_response_sample (Kolmogorov–Smirnov, α = 1e-3 per case);
 * (2) the density against central differences of the CDF; (3) ∂F/∂width against central differences of the
 * CDF in the width; (4) limits, bounds, monotonicity and no NaN/Inf out to ±1e300. Plus extreme parameters
 * (50,000 draws each) (σ ≪ τ, σ ≫ τ, a box far narrower and far wider than the response, a narrow Gaussian
 * pulse on a table) for (1)–(4), and the one quadrature (Gaussian pulse ⊗ table) against an independent one
 * over the table's variable. Broken variants and how each failed: tests/README.md (derivative/). */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "dartspp/core.h"
#include "dartspp/derivative.h"
#include "dartspp/emitter.h"
#include "dartspp/sensor.h"
#include "test_util.h"

#define DRAWS 200000
#define KS_CRIT_1E3 1.9495 /* sqrt(−ln(α/2)/2), α = 1e-3: D·sqrt(n) beyond it fails */

static const char table_csv[] = "time,value\n-0.2,0.4\n0.3,1.0\n0.5,2.0\n1.0,0.5\n1.6,0.2\n2.0,0.0\n";

typedef struct {
    const char *name;
    double fwhm, tail; /* the response's keys; both 0 and no table: off */
    int table;
} resp_case;

static const resp_case responses[] = {
    {"off", 0.0, 0.0, 0}, {"gaussian", 1.0, 0.0, 0}, {"gaussian+tail", 0.8, 0.7, 0}, {"tail", 0.0, 0.6, 0},
    {"table", 0.0, 0.0, 1},
};

static const struct {
    const char *name;
    emitter_pulse p;
} pulses[] = {
    {"delta", {1.0, 0.0, PULSE_BOX}}, {"box", {1.0, 2.0, PULSE_BOX}}, {"gaussian", {1.0, 2.0, PULSE_GAUSSIAN}},
};

static void init_response(sensor_response *r, double fwhm, double tail, int table, const char *dir)
{
    dp_error err = {0};
    char path[600] = "";
    if (table) {
        snprintf(path, sizeof path, "%s/response.csv", dir);
        test_write_file(path, table_csv);
    }
    if (sensor_response_init(r, fwhm, tail, table ? path : NULL, &err)) fail_msg("sensor_response_init: %s", err.msg);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* (1): sup |F_n − F| over the sorted draws (both sides of each step), times sqrt(n) */
static double ks_stat(const time_kernel *k, uint64_t seed, int n)
{
    double *o = malloc((size_t)n * sizeof *o);
    assert_non_null(o);
    dp_rng rng = rng_stream(seed, 50, 2);
    for (int i = 0; i < n; i++) o[i] = emitter_pulse_sample(&k->pulse, &rng) + sensor_response_sample(k->response, &rng);
    qsort(o, (size_t)n, sizeof *o, cmp_double);
    double d = 0.0;
    for (int i = 0; i < n;) {
        int j = i;
        while (j < n && o[j] == o[i]) j++; /* ties (the delta pulse without a response) */
        /* F(o_i) against the share of draws <= o_i, and F just below o_i against the share below it */
        double hi = fabs(time_kernel_cdf(k, o[i]) - (double)j / n);
        double Fm = time_kernel_has_density(k) ? time_kernel_cdf(k, o[i]) : time_kernel_cdf(k, nextafter(o[i], -INFINITY));
        double lo = fabs(Fm - (double)i / n);
        if (lo > d) d = lo;
        if (hi > d) d = hi;
        i = j;
    }
    free(o);
    return d * sqrt((double)n);
}

/* The points where the density (check 2) or F in the width (check 3) jumps or has a jump in its slope, to
 * keep the central differences away from: the response's jumps j (tail only: 0; a table: its ends) at
 * start + j and, with a box, at start + width + j; without a response the pulse's own edges. */
static int near_kink(const time_kernel *k, double x, double h)
{
    const emitter_pulse *p = &k->pulse;
    const sensor_response *r = k->response;
    double s = p->start, w = p->width > 0.0 ? p->width : 0.0;
    double jumps[2], pts[4];
    int nj = 0, n = 0;
    if (p->shape == PULSE_GAUSSIAN && w > 0.0) return 0;
    if (!r->on) jumps[nj++] = 0.0;
    else if (r->n && w == 0.0) { /* a delta pulse: f is the table itself, kinked at every knot */
        for (int i = 0; i < r->n; i++)
            if (fabs(x - s - r->t[i]) < 4.0 * h) return 1;
    } else if (r->n) jumps[nj++] = r->t[0], jumps[nj++] = r->t[r->n - 1];
    else if (r->sigma == 0.0) jumps[nj++] = 0.0;
    for (int i = 0; i < nj; i++) {
        pts[n++] = s + jumps[i];
        if (w > 0.0) pts[n++] = s + w + jumps[i];
    }
    for (int i = 0; i < n; i++)
        if (fabs(x - pts[i]) < 4.0 * h) return 1;
    return 0;
}

typedef struct {
    double pdf_err, dw_err, mono, worst_x;
} diff_report;

/* (2), (3), (4) over x in [lo, hi]; fails with the case's name */
static diff_report check_kernel(const time_kernel *k, const char *name, double lo, double hi, double feature, double tol)
{
    diff_report rep = {0};
    double scale = hi - lo, h = 1e-4 * feature, prevF = 0.0; /* feature: the kernel's shortest length */
    time_kernel kp = *k, km = *k;
    double dw = 1e-5 * (k->pulse.width > 0.0 ? k->pulse.width : 1.0);
    kp.pulse.width += dw;
    km.pulse.width -= dw;
    int steps = 4000;
    for (int i = 0; i <= steps; i++) {
        double x = lo + scale * i / steps;
        double F = time_kernel_cdf(k, x), f = time_kernel_pdf(k, x), d = time_kernel_dcdf_dwidth(k, x);
        if (!(F >= 0.0 && F <= 1.0) || !(f >= 0.0) || !isfinite(f) || !isfinite(d))
            fail_msg("%s: at x = %.17g F %g f %g dF/dw %g", name, x, F, f, d);
        if (i > 0 && prevF - F > rep.mono) rep.mono = prevF - F;
        prevF = F;
        if (!time_kernel_has_density(k)) {
            if (f != 0.0) fail_msg("%s: density %g without one", name, f);
        } else if (!near_kink(k, x, h)) {
            double cd = (time_kernel_cdf(k, x + h) - time_kernel_cdf(k, x - h)) / (2.0 * h);
            double e = fabs(cd - f) / (1.0 + f);
            if (e > rep.pdf_err) rep.pdf_err = e, rep.worst_x = x;
        }
        if (k->pulse.width > 0.0) {
            /* the box without a response: F kinks in w where x = start + w */
            if (!near_kink(k, x, dw)) {
                double cd = (time_kernel_cdf(&kp, x) - time_kernel_cdf(&km, x)) / (2.0 * dw);
                double e = fabs(cd - d) / (1.0 + fabs(d));
                if (e > rep.dw_err) rep.dw_err = e;
            }
        } else if (d != 0.0) {
            fail_msg("%s: dF/dw %g for a delta pulse", name, d);
        }
    }
    /* (4) limits and no NaN far out */
    static const double far[] = {1e6, 1e12, 1e300, DBL_MAX};
    for (size_t i = 0; i < sizeof far / sizeof far[0]; i++) {
        double xs[2] = {-far[i], far[i]};
        for (int sgn = 0; sgn < 2; sgn++) {
            double F = time_kernel_cdf(k, xs[sgn]), f = time_kernel_pdf(k, xs[sgn]), d = time_kernel_dcdf_dwidth(k, xs[sgn]);
            if (F != (double)sgn || f != 0.0 || d != 0.0)
                fail_msg("%s: at x = %g F %g f %g dF/dw %g (expected F %d, f 0, dF/dw 0)", name, xs[sgn], F, f, d, sgn);
        }
    }
    if (rep.pdf_err > tol || rep.dw_err > tol || rep.mono > 1e-13)
        fail_msg("%s: pdf against dF/dx %.3g (worst at x = %g), dF/dw against differences %.3g, "
                 "F decreasing by %.3g (tolerances %g, %g, 1e-13)",
                 name, rep.pdf_err, rep.worst_x, rep.dw_err, rep.mono, tol, tol);
    return rep;
}

/* every pulse × every response: (1)–(4) */
static void test_every_combination(void **state)
{
    char *dir = test_tmpdir();
    *state = dir;
    assert_non_null(dir);
    double worst_ks = 0.0, worst_pdf = 0.0, worst_dw = 0.0;
    int c = 0;
    for (size_t ri = 0; ri < sizeof responses / sizeof responses[0]; ri++) {
        sensor_response r;
        init_response(&r, responses[ri].fwhm, responses[ri].tail, responses[ri].table, dir);
        for (size_t pi = 0; pi < sizeof pulses / sizeof pulses[0]; pi++, c++) {
            char name[96];
            snprintf(name, sizeof name, "pulse %s, response %s", pulses[pi].name, responses[ri].name);
            time_kernel k = {pulses[pi].p, &r};
            assert_int_equal(time_kernel_has_density(&k), pi > 0 || ri > 0);
            double ks = ks_stat(&k, 1000 + (uint64_t)c, DRAWS);
            if (ks > KS_CRIT_1E3) fail_msg("%s: KS statistic sqrt(n)·D = %.3f > %.4f", name, ks, KS_CRIT_1E3);
            diff_report rep = check_kernel(&k, name, -3.0, 9.0, 0.1, 1e-6);
            print_message("%-36s KS sqrt(n)·D %.3f  pdf %.2g  dF/dw %.2g  monotone %.2g\n", name, ks, rep.pdf_err,
                          rep.dw_err, rep.mono);
            if (ks > worst_ks) worst_ks = ks;
            if (rep.pdf_err > worst_pdf) worst_pdf = rep.pdf_err;
            if (rep.dw_err > worst_dw) worst_dw = rep.dw_err;
        }
        sensor_response_free(&r);
    }
    print_message("15 cases: worst KS %.3f (critical %.4f), pdf %.2g, dF/dw %.2g\n", worst_ks, KS_CRIT_1E3, worst_pdf,
                  worst_dw);
}

/* extreme parameters: (2)–(4), and (1) for the EMG deep in its Mills-ratio branch */
static void test_extreme_parameters(void **state)
{
    char *dir = test_tmpdir();
    *state = dir;
    assert_non_null(dir);
    static const struct {
        const char *name;
        emitter_pulse p;
        double fwhm, tail;
        int table;
        double lo, hi, feature;
        int ks;
    } cases[] = {
        {"delta, sigma 1e-6 + tail 1", {0.0, 0.0, PULSE_BOX}, 2.3548200450309493e-6, 1.0, 0, -1.0, 8.0, 1e-6, 1},
        {"delta, sigma 40 + tail 0.5 (sigma/tau 80)", {0.0, 0.0, PULSE_BOX}, 94.19, 0.5, 0, -300.0, 300.0, 0.5, 1},
        {"gaussian 3, sigma 40 + tail 0.5", {0.0, 3.0, PULSE_GAUSSIAN}, 94.19, 0.5, 0, -300.0, 300.0, 0.5, 1},
        {"box 1e-4, gaussian 1", {0.0, 1e-4, PULSE_BOX}, 1.0, 0.0, 0, -4.0, 4.0, 1e-4, 1},
        {"box 1e-4, tail 1", {0.0, 1e-4, PULSE_BOX}, 0.0, 1.0, 0, -1.0, 6.0, 1e-4, 1},
        {"box 1e-4, sigma 1e-3 + tail 1", {0.0, 1e-4, PULSE_BOX}, 2.3548200450309493e-3, 1.0, 0, -1.0, 6.0, 1e-4, 1},
        {"box 100, gaussian 0.1", {-50.0, 100.0, PULSE_BOX}, 0.1, 0.0, 0, -60.0, 60.0, 0.1, 1},
        {"box 100, sigma 1e-3 + tail 0.3", {-50.0, 100.0, PULSE_BOX}, 2.3548200450309493e-3, 0.3, 0, -60.0, 60.0, 1e-3, 1},
        {"box 1e-3, table", {0.0, 1e-3, PULSE_BOX}, 0.0, 0.0, 1, -1.0, 3.0, 1e-3, 1},
        {"box 30, table", {0.0, 30.0, PULSE_BOX}, 0.0, 0.0, 1, -1.0, 33.0, 0.2, 1},
        {"gaussian 1e-3, table", {0.0, 1e-3, PULSE_GAUSSIAN}, 0.0, 0.0, 1, -1.0, 3.0, 1e-3, 1},
        {"gaussian 50, table", {0.0, 50.0, PULSE_GAUSSIAN}, 0.0, 0.0, 1, -40.0, 90.0, 0.2, 1},
        {"gaussian 1e-6, off", {0.0, 1e-6, PULSE_GAUSSIAN}, 0.0, 0.0, 0, -1e-5, 1e-5, 1e-6, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        sensor_response r;
        init_response(&r, cases[i].fwhm, cases[i].tail, cases[i].table, dir);
        time_kernel k = {cases[i].p, &r};
        diff_report rep = check_kernel(&k, cases[i].name, cases[i].lo, cases[i].hi, cases[i].feature, 1e-5);
        double ks = cases[i].ks ? ks_stat(&k, 77 + i, DRAWS / 4) : 0.0;
        print_message("%-44s KS %.3f  pdf %.2g  dF/dw %.2g  monotone %.2g\n", cases[i].name, ks, rep.pdf_err,
                      rep.dw_err, rep.mono);
        if (ks > KS_CRIT_1E3) fail_msg("%s: KS statistic sqrt(n)·D = %.3f > %.4f", cases[i].name, ks, KS_CRIT_1E3);
        sensor_response_free(&r);
    }
}

/* The Gaussian pulse ⊗ table quadrature against an independent one: F(x) = ∫ g(r)·Φ((x − m − r)/σp) dr over
 * the table's variable r, 400 pieces per knot interval × 8 Gauss–Legendre nodes; f likewise with φ/σp, and
 * ∂F/∂w = −f/2 − E[Z·g]/FWHM_PER_SIGMA with E[Z·g] = ∫ g(r)·z·φ(z)/σp dr. */
static void test_gaussian_table_quadrature(void **state)
{
    char *dir = test_tmpdir();
    *state = dir;
    assert_non_null(dir);
    sensor_response r;
    init_response(&r, 0.0, 0.0, 1, dir);
    double gx[8], gw[8];
    gauss_legendre(8, gx, gw);
    static const double widths[] = {0.05, 0.4, 2.0, 8.0};
    double worst[3] = {0};
    for (int wi = 0; wi < 4; wi++) {
        emitter_pulse p = {0.5, widths[wi], PULSE_GAUSSIAN};
        time_kernel k = {p, &r};
        double m = p.start + 0.5 * p.width, sp = p.width / 2.3548200450309493;
        for (int xi = 0; xi <= 200; xi++) {
            double x = -2.0 + 8.0 * xi / 200.0, F = 0.0, f = 0.0, zg = 0.0;
            for (int i = 0; i + 1 < r.n; i++) {
                double a = r.t[i], b = r.t[i + 1], slope = (r.p[i + 1] - r.p[i]) / (b - a);
                for (int s = 0; s < 400; s++) {
                    double a2 = a + (b - a) * s / 400.0, b2 = a + (b - a) * (s + 1) / 400.0;
                    for (int q = 0; q < 8; q++) {
                        double rr = 0.5 * (a2 + b2) + 0.5 * (b2 - a2) * gx[q], wt = 0.5 * (b2 - a2) * gw[q];
                        double g = r.p[i] + slope * (rr - a), z = (x - m - rr) / sp, phi = exp(-0.5 * z * z) / sqrt(2.0 * M_PI);
                        F += wt * g * 0.5 * erfc(-z / M_SQRT2);
                        f += wt * g * phi / sp;
                        zg += wt * g * z * phi / sp;
                    }
                }
            }
            double dF = -0.5 * f - zg / 2.3548200450309493;
            double e[3] = {fabs(time_kernel_cdf(&k, x) - F), fabs(time_kernel_pdf(&k, x) - f),
                           fabs(time_kernel_dcdf_dwidth(&k, x) - dF)};
            for (int j = 0; j < 3; j++)
                if (e[j] > worst[j]) worst[j] = e[j];
        }
    }
    print_message("gaussian pulse x table quadrature: max |error| F %.2g, f %.2g, dF/dw %.2g\n", worst[0], worst[1],
                  worst[2]);
    if (worst[0] > 1e-11 || worst[1] > 1e-10 || worst[2] > 1e-10)
        fail_msg("quadrature error F %.3g, f %.3g, dF/dw %.3g beyond 1e-11, 1e-10, 1e-10", worst[0], worst[1], worst[2]);
    sensor_response_free(&r);
}

/* closed forms at hand-picked points: the box alone, the delta with the response, a Gaussian ⊗ Gaussian */
static void test_closed_forms(void **state)
{
    (void)state;
    sensor_response off = {0}, gauss;
    dp_error err = {0};
    assert_int_equal(sensor_response_init(&gauss, 1.5, 0.0, NULL, &err), 0);
    time_kernel box = {{2.0, 4.0, PULSE_BOX}, &off};
    ASSERT_NEAR(time_kernel_cdf(&box, 3.0), 0.25, 1e-15);
    ASSERT_NEAR(time_kernel_pdf(&box, 3.0), 0.25, 1e-15);
    ASSERT_NEAR(time_kernel_dcdf_dwidth(&box, 3.0), -1.0 / 16.0, 1e-15);
    time_kernel delta = {{2.0, 0.0, PULSE_BOX}, &off};
    assert_int_equal(time_kernel_has_density(&delta), 0);
    assert_true(time_kernel_cdf(&delta, 2.0) == 1.0 && time_kernel_cdf(&delta, nextafter(2.0, 0.0)) == 0.0);
    time_kernel dg = {{2.0, 0.0, PULSE_BOX}, &gauss};
    ASSERT_NEAR(time_kernel_cdf(&dg, 2.7), sensor_response_cdf(&gauss, 0.7), 1e-15);
    /* Gaussian pulse FWHM 3 with a response of FWHM 1.5: a Gaussian of FWHM sqrt(3² + 1.5²), peak at 2 + 1.5 */
    time_kernel gg = {{2.0, 3.0, PULSE_GAUSSIAN}, &gauss};
    double S = sqrt(9.0 + 2.25) / 2.3548200450309493;
    ASSERT_NEAR(time_kernel_cdf(&gg, 4.1), 0.5 * erfc(-(4.1 - 3.5) / (S * M_SQRT2)), 1e-15);
    ASSERT_NEAR(time_kernel_pdf(&gg, 4.1), exp(-0.5 * pow((4.1 - 3.5) / S, 2)) / (S * sqrt(2.0 * M_PI)), 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_every_combination, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_extreme_parameters, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_gaussian_table_quadrature, test_teardown_tmpdir),
        cmocka_unit_test(test_closed_forms),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
