/* tier: quick */
/* Time-angular direction sampling (include/dartspp/darts.h; Jarabo et al. 2014 §5.3, DARTS supplement §B.4
 * eq. 21–22) against independent references, on four geometries: r < |l|, r > |l|, r = |l| and r ≫ |l|.
 *  a. χ² of time_angular_sample over a (cosθ about l, φ) grid against cells of time_angular_pdf integrated by
 *     quadrature in the test's own frame; every sample's pdf equal to time_angular_pdf at its direction;
 *  b. ∫ time_angular_pdf dω = 1 over the sphere (quadrature, relative error < 1e-3);
 *  c. the times t = r + |x + rω − x_L| are uniform on [r + ||l| − r|, 2r + |l|] (χ² over 20 bins);
 *  d. one-sample MIS with the phase function: E[weight·g(ω)] = ∫ρ g dω (|z| < 4), isotropic and HG g = 0.6;
 *  e. Jarabo's own pdf r/(4π d₂) integrates to min(1, r/|l|), and ours is max(r, |l|)/r times it.
 * Cells are integrated in s = √(1 − cosθ), which takes away the 1/d₂ ∝ 1/s peak at θ = 0 when r = |l|.
 * Broken variants of src/darts/time_angular.c, each run once (checks failed, p = 0 or |z| > 20 throughout):
 *  - t_min = |l| − r when |l| >= r (range 3r): a, b, c, d, e on the cases with |l| >= r;
 *  - Jarabo's pdf r/(4π d₂) in place of ours: a, b, d, e on r < |l| (c passes: the directions are right);
 *  - no φ rotation (φ = 0): a, d on all four cases (b, c, e pass: the pdf and the times are right);
 *  - θ measured from −l: c on three cases, a, b on r = |l|, e on all (d passes: sampler and pdf agree). */
#include "fixtures.h"

#include "dartspp/darts.h"

#define Z_MAX 4.0
#define NMU 24
#define NPHI 12
#define NT 20
#define N_CHI2 300000L
#define N_MC 400000L
#define ALPHA (0.01 / 8.0) /* χ² significance over the 8 χ² tests of this program */

typedef struct {
    const char *name;
    vec3 x, target; /* |target − x| = L along a skew direction */
    double r;
} ta_case;

#define N_CASES 4
static ta_case cases[N_CASES];

static vec3 skew_dir(void) { return v3_norm(v3(0.3, -0.5, 0.81)); }

static void cases_init(void)
{
    static const struct { const char *name; double r, L; } def[N_CASES] = {
        {"r < |l| (r 1, |l| 2.5)", 1.0, 2.5},
        {"r > |l| (r 2, |l| 0.7)", 2.0, 0.7},
        {"r = |l| (1, 1)", 1.0, 1.0},
        {"r >> |l| (r 50, |l| 0.3)", 50.0, 0.3},
    };
    vec3 x = v3(0.4, 1.7, -2.2);
    for (int i = 0; i < N_CASES; i++) {
        cases[i].name = def[i].name;
        cases[i].x = x;
        cases[i].target = v3_add(x, v3_scale(skew_dir(), def[i].L));
        cases[i].r = def[i].r;
    }
}

static double case_L(const ta_case *c) { return v3_len(v3_sub(c->target, c->x)); }

/* the seed: $DARTSPP_TA_SEED when set, else fixed */
static uint64_t test_seed(void)
{
    const char *e = getenv("DARTSPP_TA_SEED");
    return e && e[0] ? strtoull(e, NULL, 0) : 0x7a3du;
}


/* ---------------------------------------------------------------- the test's own frame and quadrature */

typedef struct {
    vec3 e, b1, b2;
} frame;

/* an orthonormal frame about e built here, not with v3_basis */
static frame frame_about(vec3 e)
{
    frame f;
    f.e = v3_norm(e);
    vec3 a = fabs(f.e.x) < 0.9 ? v3(1.0, 0.0, 0.0) : v3(0.0, 1.0, 0.0);
    f.b1 = v3_norm(v3_cross(f.e, a));
    f.b2 = v3_cross(f.e, f.b1);
    return f;
}

static vec3 frame_dir(const frame *f, double mu, double phi)
{
    double s = sqrt(fmax(0.0, 1.0 - mu * mu));
    return v3_add(v3_scale(f->e, mu), v3_add(v3_scale(f->b1, s * cos(phi)), v3_scale(f->b2, s * sin(phi))));
}

static void frame_coords(const frame *f, vec3 w, double *mu, double *phi)
{
    *mu = v3_dot(w, f->e);
    *phi = atan2(v3_dot(w, f->b2), v3_dot(w, f->b1));
    if (*phi < 0.0) *phi += 2.0 * M_PI;
}

#define GL_N 8
static double gl_x[GL_N], gl_w[GL_N];

typedef double (*sphere_fn)(vec3 w, const void *ctx);

/* ∫ f dω over μ ∈ [mu_a, mu_b], φ ∈ [phi_a, phi_b] about f->e: μ = 1 − s², dμ = 2s ds, composite
 * Gauss–Legendre (ps panels in s, pp in φ) */
static double cell_integral(sphere_fn fn, const void *ctx, const frame *f, double mu_a, double mu_b, double phi_a,
                            double phi_b, int ps, int pp)
{
    static int ready;
    if (!ready) gauss_legendre(GL_N, gl_x, gl_w), ready = 1;
    double s_a = sqrt(fmax(0.0, 1.0 - mu_b)), s_b = sqrt(fmax(0.0, 1.0 - mu_a)), sum = 0.0;
    double hs = (s_b - s_a) / ps, hp = (phi_b - phi_a) / pp;
    for (int i = 0; i < ps; i++)
        for (int a = 0; a < GL_N; a++) {
            double s = s_a + hs * (i + 0.5 * (gl_x[a] + 1.0)), mu = 1.0 - s * s, ws = 0.5 * hs * gl_w[a] * 2.0 * s;
            for (int j = 0; j < pp; j++)
                for (int b = 0; b < GL_N; b++) {
                    double phi = phi_a + hp * (j + 0.5 * (gl_x[b] + 1.0));
                    sum += ws * 0.5 * hp * gl_w[b] * fn(frame_dir(f, mu, phi), ctx);
                }
        }
    return sum;
}

static double sphere_integral(sphere_fn fn, const void *ctx, const frame *f)
{
    return cell_integral(fn, ctx, f, -1.0, 1.0, 0.0, 2.0 * M_PI, 32, 8);
}

static double ta_pdf_fn(vec3 w, const void *ctx)
{
    const ta_case *c = ctx;
    return time_angular_pdf(c->x, c->target, c->r, w);
}

/* Jarabo 2014 eq. 16 per steradian: r/(4π d₂) */
static double jarabo_pdf_fn(vec3 w, const void *ctx)
{
    const ta_case *c = ctx;
    double d2 = v3_len(v3_sub(v3_add(c->x, v3_scale(w, c->r)), c->target));
    return c->r / (4.0 * M_PI * d2);
}

static double rel_dev(double a, double b) { return fabs(a - b) / fmax(fmax(fabs(a), fabs(b)), 1e-300); }

/* ---------------------------------------------------------------- χ² with pooling of small cells */

/* ---------------------------------------------------------------- a. χ² of the directions */

static int chi2_directions(const ta_case *c, int ci)
{
    static chi_cell cells[NMU * NPHI + 1];
    frame f = frame_about(v3_sub(c->target, c->x));
    double total = 0.0;
    for (int i = 0; i < NMU; i++)
        for (int j = 0; j < NPHI; j++) {
            double e = cell_integral(ta_pdf_fn, c, &f, -1.0 + 2.0 * i / NMU, -1.0 + 2.0 * (i + 1) / NMU,
                                     2.0 * M_PI * j / NPHI, 2.0 * M_PI * (j + 1) / NPHI, 2, 1);
            cells[i * NPHI + j] = (chi_cell){0.0, e * N_CHI2};
            total += e;
        }
    dp_rng rng = rng_stream(test_seed(), (uint64_t)ci, 1);
    long fails = 0, bad = 0;
    double worst = 0.0;
    for (long k = 0; k < N_CHI2; k++) {
        vec3 w;
        double pdf, mu, phi;
        double u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);
        if (!time_angular_sample(c->x, c->target, c->r, u1, u2, &w, &pdf)) {
            fails++;
            continue;
        }
        double dev = rel_dev(pdf, time_angular_pdf(c->x, c->target, c->r, w));
        worst = fmax(worst, dev);
        if (!v3_is_finite(w) || fabs(v3_len(w) - 1.0) > 1e-12 || !(pdf > 0.0) || !isfinite(pdf) || dev > 1e-6) bad++;
        frame_coords(&f, w, &mu, &phi);
        int i = (int)floor((mu + 1.0) * 0.5 * NMU), j = (int)floor(phi / (2.0 * M_PI) * NPHI);
        i = i < 0 ? 0 : i >= NMU ? NMU - 1 : i;
        j = j < 0 ? 0 : j >= NPHI ? NPHI - 1 : j;
        cells[i * NPHI + j].obs += 1.0;
    }
    cells[NMU * NPHI] = (chi_cell){(double)fails, fmax(0.0, 1.0 - total) * N_CHI2}; /* failed samples */
    double chi2;
    int dof;
    double p = chi2_pooled(cells, NMU * NPHI + 1, &chi2, &dof, NULL);
    int fail = p < ALPHA || bad > 0;
    print_message("  a. %-26s p %-9.3g (chi2 %.1f, dof %d)  sum of cells %.6f  failed draws %ld  "
                  "max rel dev pdf %.1e  bad %ld%s\n",
                  c->name, p, chi2, dof, total, fails, worst, bad, fail ? "  FAILED" : "");
    return fail;
}

static void test_chi2_directions(void **state)
{
    (void)state;
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) fails += chi2_directions(&cases[i], i);
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- b. normalisation */

static void test_pdf_normalised(void **state)
{
    (void)state;
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) {
        const ta_case *c = &cases[i];
        frame fl = frame_about(v3_sub(c->target, c->x));
        double I = sphere_integral(ta_pdf_fn, c, &fl);
        int fail = !(fabs(I - 1.0) < 1e-3);
        print_message("  b. %-26s integral over the sphere %.8f%s\n", c->name, I, fail ? "  FAILED" : "");
        fails += fail;
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- c. uniform times */

static int chi2_times(const ta_case *c, int ci)
{
    double L = case_L(c), r = c->r, t_min = r + fabs(L - r), t_max = 2.0 * r + L, tol = 1e-9 * (r + L);
    chi_cell cells[NT];
    for (int j = 0; j < NT; j++) cells[j] = (chi_cell){0.0, (double)N_CHI2 / NT};
    dp_rng rng = rng_stream(test_seed(), (uint64_t)ci, 2);
    long outside = 0, fails = 0;
    for (long k = 0; k < N_CHI2; k++) {
        vec3 w;
        double pdf, u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);
        if (!time_angular_sample(c->x, c->target, r, u1, u2, &w, &pdf)) {
            fails++;
            continue;
        }
        double t = r + v3_len(v3_sub(v3_add(c->x, v3_scale(w, r)), c->target));
        if (t < t_min - tol || t > t_max + tol) outside++;
        int j = (int)floor((t - t_min) / (t_max - t_min) * NT);
        cells[j < 0 ? 0 : j >= NT ? NT - 1 : j].obs += 1.0;
    }
    double chi2;
    int dof;
    double p = chi2_pooled(cells, NT, &chi2, &dof, NULL);
    int fail = p < ALPHA || outside > 0 || fails > 0;
    print_message("  c. %-26s t in [%.4g, %.4g]: p %-9.3g (chi2 %.1f, dof %d)  outside %ld  failed draws %ld%s\n",
                  c->name, t_min, t_max, p, chi2, dof, outside, fails, fail ? "  FAILED" : "");
    return fail;
}

static void test_uniform_times(void **state)
{
    (void)state;
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) fails += chi2_times(&cases[i], i);
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- d. the mix sampler's weights */

typedef struct {
    const phase_function *ph;
    vec3 w_in;
} phase_ctx;

/* a smooth test function, not symmetric about l, w_in or the axes */
static double g_test(vec3 w)
{
    return 1.0 + 0.5 * v3_dot(w, v3_norm(v3(-0.6, 0.2, 0.7))) + exp(2.0 * v3_dot(w, v3_norm(v3(0.9, 0.4, -0.2))));
}

static double phase_g_fn(vec3 w, const void *ctx)
{
    const phase_ctx *p = ctx;
    return phase_eval(p->ph, p->w_in, w) * g_test(w);
}

static int mix_case(const ta_case *c, int ci, const phase_function *ph, const char *ph_name, int pi)
{
    vec3 w_in = v3_norm(v3(0.1, 0.8, 0.3));
    phase_ctx pc = {ph, w_in};
    frame f = frame_about(w_in);
    double ref = sphere_integral(phase_g_fn, &pc, &f);
    dp_rng rng = rng_stream(test_seed(), (uint64_t)ci, 3 + (uint64_t)pi);
    double sum = 0.0, sum2 = 0.0, worst = 0.0;
    long bad = 0;
    for (long k = 0; k < N_MC; k++) {
        double u[3] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, wt;
        vec3 w = time_angular_mix_sample(ph, w_in, c->x, c->target, c->r, 0.5, u, &wt);
        double expect = phase_eval(ph, w_in, w) / time_angular_mix_pdf(ph, w_in, c->x, c->target, c->r, 0.5, w);
        worst = fmax(worst, rel_dev(wt, expect));
        if (!(wt >= 0.0) || !isfinite(wt) || rel_dev(wt, expect) > 1e-9) bad++;
        double y = wt * g_test(w);
        sum += y, sum2 += y * y;
    }
    double mean = sum / N_MC, se = sqrt(fmax(sum2 / N_MC - mean * mean, 0.0) / N_MC), z = (mean - ref) / se;
    int fail = !(fabs(z) < Z_MAX) || bad > 0;
    print_message("  d. %-26s %-8s E[w g] %.5f, integral %.5f, z %+.2f  max rel dev weight %.1e  bad %ld%s\n",
                  c->name, ph_name, mean, ref, z, worst, bad, fail ? "  FAILED" : "");
    return fail;
}

static void test_mix_weights(void **state)
{
    (void)state;
    phase_function iso = {PHASE_ISOTROPIC, 0.0, NULL}, hg = {PHASE_HENYEY_GREENSTEIN, 0.6, NULL};
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) {
        fails += mix_case(&cases[i], i, &iso, "iso", 0);
        fails += mix_case(&cases[i], i, &hg, "HG 0.6", 1);
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- e. Jarabo's uncorrected pdf */

static void test_jarabo_pdf_not_normalised(void **state)
{
    (void)state;
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) {
        const ta_case *c = &cases[i];
        double L = case_L(c), r = c->r, expect = fmin(1.0, r / L), ratio = fmax(r, L) / r, worst = 0.0;
        frame fl = frame_about(v3_sub(c->target, c->x));
        double I = sphere_integral(jarabo_pdf_fn, c, &fl);
        dp_rng rng = rng_stream(test_seed(), (uint64_t)i, 5);
        for (int k = 0; k < 1000; k++) {
            vec3 w = sample_uniform_sphere(rng_uniform(&rng), rng_uniform(&rng));
            worst = fmax(worst, rel_dev(time_angular_pdf(c->x, c->target, r, w), ratio * jarabo_pdf_fn(w, c)));
        }
        int fail = !(fabs(I - expect) < 1e-3 * expect) || worst > 1e-9;
        print_message("  e. %-26s Jarabo's r/(4 pi d2) integrates to %.8f (r/|l| = %.8f, expected %.8f); "
                      "ours / Jarabo's = max(r, |l|)/r = %.4f to %.1e%s\n",
                      c->name, I, r / L, expect, ratio, worst, fail ? "  FAILED" : "");
        fails += fail;
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- degenerate cases */

static void test_degenerate(void **state)
{
    (void)state;
    vec3 x = v3(1.0, 2.0, 3.0), w = v3(0.0, 0.0, 1.0), out;
    double pdf;
    const struct { vec3 target; double r; } d[] = {
        {{2.0, 2.0, 3.0}, 0.0},   {{2.0, 2.0, 3.0}, 1e-12}, {{1.0, 2.0, 3.0}, 1.0},
        {{1.0 + 1e-12, 2.0, 3.0}, 1.0}, {{2.0, 2.0, 3.0}, INFINITY}, {{2.0, 2.0, 3.0}, NAN},
    };
    phase_function hg = {PHASE_HENYEY_GREENSTEIN, 0.6, NULL};
    for (size_t i = 0; i < sizeof d / sizeof d[0]; i++) {
        assert_int_equal(time_angular_sample(x, d[i].target, d[i].r, 0.3, 0.7, &out, &pdf), 0);
        assert_true(time_angular_pdf(x, d[i].target, d[i].r, w) == 0.0);
        double u[3] = {0.1, 0.4, 0.6}, wt = -1.0;
        vec3 a = time_angular_mix_sample(&hg, w, x, d[i].target, d[i].r, 0.5, u, &wt);
        vec3 b = phase_sample(&hg, w, u[1], u[2]);
        assert_true(wt == 1.0 && a.x == b.x && a.y == b.y && a.z == b.z);
        assert_true(time_angular_mix_pdf(&hg, w, x, d[i].target, d[i].r, 0.5, w) == phase_eval(&hg, w, w));
    }
    /* r = |l| and u1 = 0 aims at the target itself (d₂ = 0): no sample */
    assert_int_equal(time_angular_sample(x, v3(2.0, 2.0, 3.0), 1.0, 0.0, 0.5, &out, &pdf), 0);
}

int main(void)
{
    cases_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_directions),
        cmocka_unit_test(test_pdf_normalised),
        cmocka_unit_test(test_uniform_times),
        cmocka_unit_test(test_mix_weights),
        cmocka_unit_test(test_jarabo_pdf_not_normalised),
        cmocka_unit_test(test_degenerate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
