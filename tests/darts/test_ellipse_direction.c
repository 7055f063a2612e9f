/* tier: quick */
/* Directions toward the next elliptical connection (include/dartspp/darts.h, src/darts/ellipse_direction.c;
 * docs/darts.md §14.3) against independent references, on five geometries of residual T and focal distance C:
 * T well above C, T close to C (T = 1.001 C), C = 0 (the sphere), C ≪ T, and a direction field at T = 1.3 C.
 *  a. χ² of ellipse_direction_sample over (1 − cosθ about x_L − x, φ) cells — 1 − cosθ in geometric steps down to
 *     well inside the peak, 8 azimuths — against ellipse_direction_pdf integrated over each cell by quadrature in
 *     the test's own frame; every sample a unit vector whose returned pdf equals ellipse_direction_pdf there;
 *  b. ∫ ellipse_direction_pdf dω = 1 (quadrature in s = √(1 − cosθ) on geometric panels, relative error < 1e-6);
 *  c. the density is the control vertex's own geometry: pdf(ω)·p(t)·ℓ² is the same for every ω and equals
 *     TC·p(T)/(4πλ) (T²p(T)/(8π) when C = 0), with p(t) from ellipse_control_vertex (src/darts/ellipse.c,
 *     docs/darts.md §5.2) and ℓ the light leg of its vertex;
 *  d. the degenerate cases: T <= C(1 + 1e-6), T = 0, T or C not finite: no sample, pdf 0, not usable.
 * Broken variants (tests/README.md, "Figures"): a normalisation without the factor 2 of ln((T + C)²/(T − C)²);
 * the inverse CDF with λ in place of 2λ; φ not rotated (φ = 0). */
#include "fixtures.h"

#include "dartspp/darts.h"

#define NM 25          /* 1 − cosθ cells: [0, m_min] and 24 geometric steps up to 2 */
#define NPHI 8
#define N_CHI2 300000L
#define ALPHA (0.01 / 5.0) /* χ² significance over the five cases */
#define GL_N 8

typedef struct {
    const char *name;
    double T, C;
} ed_case;

#define N_CASES 5
static const ed_case cases[N_CASES] = {
    {"T 3, C 1", 3.0, 1.0},
    {"T 1.001, C 1 (near)", 1.001, 1.0},
    {"T 1, C 0 (sphere)", 1.0, 0.0},
    {"T 50, C 0.3", 50.0, 0.3},
    {"T 1.3, C 1", 1.3, 1.0},
};

static const vec3 X = {0.4, 1.7, -2.2};

static vec3 case_target(const ed_case *c) { return v3_add(X, v3_scale(v3_norm(v3(0.3, -0.5, 0.81)), c->C)); }

static uint64_t test_seed(void)
{
    const char *e = getenv("DARTSPP_ED_SEED");
    return e && e[0] ? strtoull(e, NULL, 0) : 0x51e7u;
}

/* ---------------------------------------------------------------- the test's own frame and quadrature */

typedef struct {
    vec3 e, b1, b2;
} frame;

/* about the direction to the target (any axis when C = 0), built here, not with v3_basis */
static frame frame_about(vec3 e)
{
    frame f;
    f.e = v3_len(e) > 0.0 ? v3_norm(e) : v3(0.0, 0.0, 1.0);
    vec3 a = fabs(f.e.y) < 0.9 ? v3(0.0, 1.0, 0.0) : v3(1.0, 0.0, 0.0);
    f.b1 = v3_norm(v3_cross(a, f.e));
    f.b2 = v3_cross(f.e, f.b1);
    return f;
}

/* the direction with 1 − cosθ = m and azimuth φ */
static vec3 frame_dir(const frame *f, double m, double phi)
{
    double s = sqrt(fmax(0.0, m * (2.0 - m)));
    return v3_add(v3_scale(f->e, 1.0 - m), v3_add(v3_scale(f->b1, s * cos(phi)), v3_scale(f->b2, s * sin(phi))));
}

static void frame_coords(const frame *f, vec3 w, double *m, double *phi)
{
    vec3 d = v3_sub(w, f->e);
    *m = 0.5 * v3_dot(d, d);
    *phi = atan2(v3_dot(w, f->b2), v3_dot(w, f->b1));
    if (*phi < 0.0) *phi += 2.0 * M_PI;
}

static double gl_x[GL_N], gl_w[GL_N];

/* ∫ pdf dω over 1 − cosθ ∈ [m_a, m_b], φ ∈ [phi_a, phi_b]: m = s², dm = 2s ds, Gauss–Legendre in s (ps panels)
 * and in φ (one panel) */
static double cell_integral(const ed_case *c, const frame *f, double m_a, double m_b, double phi_a, double phi_b,
                            int ps)
{
    vec3 L = case_target(c);
    double s_a = sqrt(m_a), s_b = sqrt(m_b), hs = (s_b - s_a) / ps, sum = 0.0;
    for (int i = 0; i < ps; i++)
        for (int a = 0; a < GL_N; a++) {
            double s = s_a + hs * (i + 0.5 * (gl_x[a] + 1.0)), ws = 0.5 * hs * gl_w[a] * 2.0 * s;
            for (int b = 0; b < GL_N; b++) {
                double phi = phi_a + (phi_b - phi_a) * 0.5 * (gl_x[b] + 1.0);
                double wp = 0.5 * (phi_b - phi_a) * gl_w[b];
                sum += ws * wp * ellipse_direction_pdf(X, L, c->T, frame_dir(f, s * s, phi));
            }
        }
    return sum;
}

/* the 1 − cosθ cell edges: 0, then m_min·(2/m_min)^(k/(NM − 1)), m_min well inside the peak of width
 * (T − C)²/(2TC) in 1 − cosθ */
static void m_edges(const ed_case *c, double edge[NM + 1])
{
    double width = c->C > 0.0 ? (c->T - c->C) * (c->T - c->C) / (2.0 * c->T * c->C) : INFINITY;
    double m_min = fmin(1e-3, 0.01 * width);
    edge[0] = 0.0;
    for (int k = 1; k <= NM; k++) edge[k] = m_min * pow(2.0 / m_min, (k - 1.0) / (NM - 1.0));
    edge[NM] = 2.0;
}

static int cell_of(const double edge[NM + 1], double m)
{
    int i = 0;
    while (i < NM - 1 && m >= edge[i + 1]) i++;
    return i;
}

static double rel_dev(double a, double b) { return fabs(a - b) / fmax(fmax(fabs(a), fabs(b)), 1e-300); }

/* ---------------------------------------------------------------- a. χ² of the directions */

static int chi2_directions(const ed_case *c, int ci)
{
    static chi_cell cells[NM * NPHI + 1];
    double edge[NM + 1];
    m_edges(c, edge);
    vec3 L = case_target(c);
    frame f = frame_about(v3_sub(L, X));
    double total = 0.0;
    for (int i = 0; i < NM; i++)
        for (int j = 0; j < NPHI; j++) {
            double phi_a = 2.0 * M_PI * j / NPHI, phi_b = 2.0 * M_PI * (j + 1) / NPHI;
            double e = cell_integral(c, &f, edge[i], edge[i + 1], phi_a, phi_b, 4);
            cells[i * NPHI + j] = (chi_cell){0.0, e * N_CHI2};
            total += e;
        }
    dp_rng rng = rng_stream(test_seed(), (uint64_t)ci, 1);
    long fails = 0, bad = 0;
    double worst = 0.0;
    for (long k = 0; k < N_CHI2; k++) {
        vec3 w;
        double pdf, m, phi;
        double u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);
        if (!ellipse_direction_sample(X, L, c->T, u1, u2, &w, &pdf)) {
            fails++;
            continue;
        }
        double dev = rel_dev(pdf, ellipse_direction_pdf(X, L, c->T, w));
        worst = fmax(worst, dev);
        if (!v3_is_finite(w) || fabs(v3_len(w) - 1.0) > 1e-12 || !(pdf > 0.0) || !isfinite(pdf) || dev > 1e-9) bad++;
        frame_coords(&f, w, &m, &phi);
        int j = (int)floor(phi / (2.0 * M_PI) * NPHI);
        j = j < 0 ? 0 : j >= NPHI ? NPHI - 1 : j;
        cells[cell_of(edge, m) * NPHI + j].obs += 1.0;
    }
    cells[NM * NPHI] = (chi_cell){(double)fails, fmax(0.0, 1.0 - total) * N_CHI2}; /* failed samples */
    double chi2;
    int dof;
    double p = chi2_pooled(cells, NM * NPHI + 1, &chi2, &dof, NULL);
    int fail = p < ALPHA || bad > 0 || fails > 0;
    print_message("  a. %-22s p %-9.3g (chi2 %.1f, dof %d)  sum of cells %.8f  failed draws %ld  max rel dev pdf "
                  "%.1e  bad %ld%s\n", c->name, p, chi2, dof, total, fails, worst, bad, fail ? "  FAILED" : "");
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
        const ed_case *c = &cases[i];
        double edge[NM + 1], I = 0.0;
        m_edges(c, edge);
        frame f = frame_about(v3_sub(case_target(c), X));
        for (int k = 0; k < NM; k++) I += cell_integral(c, &f, edge[k], edge[k + 1], 0.0, 2.0 * M_PI, 8);
        int fail = !(fabs(I - 1.0) < 1e-6);
        print_message("  b. %-22s integral over the sphere %.10f%s\n", c->name, I, fail ? "  FAILED" : "");
        fails += fail;
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- c. the control vertex's geometry */

static void test_control_vertex_geometry(void **state)
{
    (void)state;
    int fails = 0;
    for (int i = 0; i < N_CASES; i++) {
        const ed_case *c = &cases[i];
        vec3 L = case_target(c);
        vec3 l = v3_sub(L, X);
        /* a record with the case's T (p(T) = 1 on [C, T + 1]) built by hand, as ellipse_record_init leaves it */
        ellipse_record r = {.valid = 1, .x = X, .C = c->C, .S_lo = c->C, .S_hi = c->T + 1.0, .T = c->T,
                            .inv_pdf_T = 1.0, .S_reach = c->T + 1.0};
        r.e = c->C > 0.0 ? v3_scale(l, 1.0 / c->C) : v3(0.0, 0.0, 1.0);
        dp_rng rng = rng_stream(test_seed(), (uint64_t)i, 2);
        double lo = INFINITY, hi = 0.0;
        for (int k = 0; k < 2000; k++) {
            vec3 w;
            double pdf, t, pdf_t;
            assert_true(ellipse_direction_sample(X, L, c->T, rng_uniform(&rng), rng_uniform(&rng), &w, &pdf));
            assert_true(ellipse_control_vertex(&r, w, INFINITY, &t, &pdf_t));
            double ell = v3_len(v3_sub(L, v3_add(X, v3_scale(w, t))));
            double ratio = pdf * pdf_t * ell * ell; /* constant iff pdf ∝ 1/(p(t)·ℓ²) */
            lo = fmin(lo, ratio), hi = fmax(hi, ratio);
        }
        /* 1/(p(t)ℓ²) = 2/(p(T)·(T² + C² − 2TC cosθ)), so the ratio is TC/(4πλ) with p(T) = 1, λ = ln((T + C)/(T − C)),
         * and T²/(8π) on the sphere */
        double expect = c->C > 0.0 ? c->T * c->C / (4.0 * M_PI * log((c->T + c->C) / (c->T - c->C)))
                                   : c->T * c->T / (8.0 * M_PI);
        double spread = hi / lo - 1.0, off = rel_dev(0.5 * (lo + hi), expect);
        int fail = !(spread < 1e-8) || !(off < 1e-8);
        print_message("  c. %-22s pdf(w) p(t) l^2 in [%.10g, %.10g]: spread %.1e; TC/(4 pi lambda) %.10g%s\n", c->name,
                      lo, hi, spread, expect, fail ? "  FAILED" : "");
        fails += fail;
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- d. degenerate cases */

static void test_degenerate(void **state)
{
    (void)state;
    vec3 x = v3(1.0, 2.0, 3.0), L = v3(2.0, 2.0, 3.0), w;
    double pdf;
    const double T[] = {1.0, 1.0 + 1e-7, 0.5, 0.0, -1.0, INFINITY, NAN};
    for (size_t i = 0; i < sizeof T / sizeof T[0]; i++) {
        assert_int_equal(ellipse_direction_usable(x, L, T[i]), 0);
        assert_int_equal(ellipse_direction_sample(x, L, T[i], 0.3, 0.7, &w, &pdf), 0);
        assert_true(ellipse_direction_pdf(x, L, T[i], v3(1.0, 0.0, 0.0)) == 0.0);
    }
    assert_int_equal(ellipse_direction_usable(x, v3(INFINITY, 2.0, 3.0), 5.0), 0);
    /* just above the threshold it runs, and its peak toward the target is finite */
    assert_int_equal(ellipse_direction_usable(x, L, 1.0 + 2e-6), 1);
    double peak = ellipse_direction_pdf(x, L, 1.0 + 2e-6, v3(1.0, 0.0, 0.0));
    assert_true(isfinite(peak) && peak > 1e9);
    /* C = 0: the sphere, uniform */
    assert_int_equal(ellipse_direction_usable(x, x, 1.0), 1);
    assert_true(fabs(ellipse_direction_pdf(x, x, 1.0, v3(0.0, -1.0, 0.0)) - 1.0 / (4.0 * M_PI)) < 1e-15);
}

int main(void)
{
    gauss_legendre(GL_N, gl_x, gl_w);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_directions),
        cmocka_unit_test(test_pdf_normalised),
        cmocka_unit_test(test_control_vertex_geometry),
        cmocka_unit_test(test_degenerate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
