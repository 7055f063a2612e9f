/* tier: quick */
/* tier: stress */
/* EDA direction sampling: the table (every cell a CDF, p_E a density on the sphere, deterministic builds,
 * file checks), the EDA branch against its pdf (χ² on the cos bins), and the combined sampler against
 * quadrature: E[W·h(ω)] = ∫ f·h dω for test functions h, for several g. No expected value comes from an
 * earlier run of this code: the references are the table's own CDF (for the χ²) and quadrature of the
 * phase function (for the combined sampler). */
#include "fixtures.h"

#include <omp.h>
#include <unistd.h>

#include "dartspp/darts.h"

/* small shape so that the test builds run in a second under the sanitizers */
#define NR 16
#define NS 12
#define NC 64

static void build_small(eda_table *t, double ss, double sa, double g, double s_max)
{
    dp_error err;
    if (eda_table_build(t, ss, sa, g, NR, NS, NC, s_max, EDA_DEFAULT_R_LO, EDA_DEFAULT_R_HI, NULL, NULL, &err))
        fail_msg("%s", err.msg);
}

static ellipse_record record(double C, double T, vec3 e)
{
    ellipse_record r = {0};
    r.valid = 1;
    r.C = C;
    r.T = T;
    r.e = v3_norm(e);
    r.S_lo = C;
    r.S_hi = T * 1.1;
    r.inv_pdf_T = 1.0;
    return r;
}

/* ∫ fn(ω) dω by the midpoint rule in cosθ (nc cells) and φ (nphi cells) about axis */
typedef double (*sphere_fn)(const void *ctx, vec3 w);
static double sphere_integral(vec3 axis, int nc, int nphi, sphere_fn fn, const void *ctx)
{
    vec3 b1, b2;
    v3_basis(axis, &b1, &b2);
    double sum = 0.0;
    for (int i = 0; i < nc; i++)
        for (int j = 0; j < nphi; j++) {
            double c = -1.0 + (i + 0.5) * 2.0 / nc, s = sqrt(1.0 - c * c), phi = 2.0 * M_PI * (j + 0.5) / nphi;
            sum += fn(ctx, v3_add(v3_scale(axis, c), v3_add(v3_scale(b1, s * cos(phi)), v3_scale(b2, s * sin(phi)))));
        }
    return sum * (2.0 / nc) * (2.0 * M_PI / nphi);
}

typedef struct {
    const eda_table *t;
    const float *cell;
    vec3 e;
} pdf_ctx;

static double pdf_at(const void *ctx, vec3 w)
{
    const pdf_ctx *c = ctx;
    return eda_pdf(c->t, c->cell, c->e, w);
}

/* 1. every cell a CDF; p_E integrates to 1 over the sphere (midpoint rule in cosθ and φ about e) */
static void test_cdfs_and_density(void **state)
{
    (void)state;
    eda_table t;
    build_small(&t, 0.3, 0.01, 0.3, 12.0);
    long bad = 0;
    for (long c = 0; c < (long)NR * NS; c++) {
        const float *F = t.cdf + c * NC;
        for (int k = 0; k < NC; k++)
            if (!(F[k] >= (k ? F[k - 1] : 0.0f)) || !(F[k] <= 1.0f)) bad++;
        if (F[NC - 1] != 1.0f) bad++;
    }
    assert_int_equal(bad, 0);
    vec3 e = v3_norm(v3(0.2, -0.5, 0.8));
    const double cases[4][2] = {{1.0, 1.2}, {3.0, 3.3}, {5.0, 10.0}, {3.0, 11.5}};
    for (int q = 0; q < 4; q++) {
        ellipse_record r = record(cases[q][0], cases[q][1], e);
        const float *cell = eda_cell(&t, &r);
        assert_non_null(cell);
        pdf_ctx pc = {&t, cell, e};
        double sum = sphere_integral(e, 2048, 16, pdf_at, &pc);
        print_message("  cell C %g T %g: integral of p_E over the sphere %.12f\n", cases[q][0], cases[q][1], sum);
        assert_true(fabs(sum - 1.0) < 1e-6);
    }
    /* outside the table's C/T range, or an invalid record: no cell (the phase function alone) */
    ellipse_record r = record(1.0, 10.0, e); /* C/T = 0.1 < 0.2 */
    assert_null(eda_cell(&t, &r));
    r = record(1.0, 1.0005, e); /* C/T > 0.999 */
    assert_null(eda_cell(&t, &r));
    r = record(2.0, 3.0, e);
    r.valid = 0;
    assert_null(eda_cell(&t, &r));
    r = record(40.0, 50.0, e); /* T beyond s_max: the last column */
    assert_true(eda_cell(&t, &r) == t.cdf + ((size_t)((0.8 - 0.2) / 0.799 * NR) * NS + NS - 1) * NC);
    eda_table_free(&t);
}

/* The EDA table aims at the camera, the more so the thinner the ellipse: along a direction away from the
 * camera the ellipsoid ends at t_M = (T − C)/2, towards it at (T + C)/2, so the mass towards the camera
 * (cosθ > 0) exceeds one half, and grows with C/T. */
static void test_table_points_at_camera(void **state)
{
    (void)state;
    eda_table t;
    build_small(&t, 0.3, 0.01, 0.0, 12.0);
    vec3 e = v3(0, 0, 1);
    ellipse_record thin = record(4.0, 4.1, e), fat = record(1.0, 4.5, e);
    const float *a = eda_cell(&t, &thin), *b = eda_cell(&t, &fat);
    double fwd_thin = 1.0 - a[NC / 2 - 1], fwd_fat = 1.0 - b[NC / 2 - 1];
    print_message("  mass towards the camera: thin ellipse %.4f, fat ellipse %.4f\n", fwd_thin, fwd_fat);
    assert_true(fwd_fat > 0.5);
    assert_true(fwd_thin > fwd_fat);
    eda_table_free(&t);
}

/* 2. the EDA branch (α → 0 makes γ → 1) samples the cos bins with the table's probabilities: χ² test */
static void test_eda_branch_chi2(void **state)
{
    (void)state;
    eda_table t;
    build_small(&t, 0.5, 0.05, 0.5, 10.0);
    phase_function hg = {PHASE_HENYEY_GREENSTEIN, 0.5, NULL};
    vec3 e = v3_norm(v3(1, 2, -1));
    const double cases[3][2] = {{2.0, 2.2}, {1.0, 3.0}, {6.0, 7.5}};
    for (int q = 0; q < 3; q++) {
        ellipse_record r = record(cases[q][0], cases[q][1], e);
        const float *cell = eda_cell(&t, &r);
        assert_non_null(cell);
        const long n = 200000;
        long hist[NC] = {0};
        dp_rng rng = rng_stream(77, (uint64_t)q, 0);
        for (long i = 0; i < n; i++) {
            double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, w;
            vec3 d = eda_sample_direction(&t, 1e-12, &hg, v3(0, 1, 0), &r, u, &w);
            int k = (int)((v3_dot(d, e) + 1.0) * 0.5 * NC);
            hist[k < 0 ? 0 : k >= NC ? NC - 1 : k]++;
        }
        /* pool bins with expected count < 5 into one */
        double chi2 = 0.0, pooled_e = 0.0, pooled_o = 0.0;
        int dof = -1;
        for (int k = 0; k < NC; k++) {
            double p = cell[k] - (k ? cell[k - 1] : 0.0f), ex = p * n;
            if (ex < 5.0) {
                pooled_e += ex;
                pooled_o += (double)hist[k];
                continue;
            }
            chi2 += (hist[k] - ex) * (hist[k] - ex) / ex;
            dof++;
        }
        if (pooled_e >= 5.0) {
            chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
            dof++;
        }
        /* critical value at p = 0.001: Wilson–Hilferty approximation */
        double z = 3.09, h = 2.0 / (9.0 * dof), crit = dof * pow(1.0 - h + z * sqrt(h), 3);
        print_message("  cell C %g T %g: chi2 %.1f (dof %d, 0.1%% critical %.1f)\n", cases[q][0], cases[q][1], chi2, dof,
                      crit);
        assert_true(dof > 3);
        assert_true(chi2 < crit);
    }
    eda_table_free(&t);
}

/* 3. combined sampler: E[W·h(ω)] = ∫ f(ω_in, ω)·h(ω) dω, the right side by quadrature in the frame of ω_in
 * (Gauss–Legendre-free midpoint rule, 4000 × 64 cells: error far below the Monte Carlo noise) */
static double h_test(vec3 w, int which)
{
    vec3 a = v3_norm(v3(0.3, -0.4, 0.85));
    double c = v3_dot(w, a);
    return which == 0 ? (1.0 + c) * (1.0 + c) : exp(2.0 * w.x) + (w.z > 0.3 ? 1.0 : 0.0);
}

typedef struct {
    const phase_function *ph;
    vec3 w_in;
    int which;
} fh_ctx;

static double f_times_h(const void *ctx, vec3 w)
{
    const fh_ctx *c = ctx;
    return phase_eval(c->ph, c->w_in, w) * h_test(w, c->which);
}

static double quad_f_h(const phase_function *ph, vec3 w_in, int which)
{
    fh_ctx c = {ph, w_in, which};
    return sphere_integral(w_in, 4000, 64, f_times_h, &c);
}

static void test_combined_sampler_unbiased(void **state)
{
    (void)state;
    const double gs[3] = {-0.5, 0.0, 0.5};
    int fails = 0;
    for (int gi = 0; gi < 3; gi++) {
        eda_table t;
        build_small(&t, 0.4, 0.02, gs[gi], 10.0);
        phase_function ph = {gs[gi] == 0.0 ? PHASE_ISOTROPIC : PHASE_HENYEY_GREENSTEIN, gs[gi], NULL};
        vec3 w_in = v3_norm(v3(-0.3, 0.9, 0.2)), e = v3_norm(v3(0.5, 0.5, -0.7));
        ellipse_record r = record(2.5, 3.0, e);
        assert_non_null(eda_cell(&t, &r));
        for (int which = 0; which < 2; which++) {
            double ref = quad_f_h(&ph, w_in, which);
            const long n = 400000;
            double m = 0.0, m2 = 0.0, wmin = INFINITY;
            dp_rng rng = rng_stream(1234, (uint64_t)gi, (uint64_t)which);
            for (long i = 0; i < n; i++) {
                double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, w;
                vec3 d = eda_sample_direction(&t, 0.5, &ph, w_in, &r, u, &w);
                double x = w * h_test(d, which);
                m += x;
                m2 += x * x;
                wmin = fmin(wmin, w);
            }
            m /= n;
            double se = sqrt(fmax(0.0, m2 / n - m * m) / n), z = (m - ref) / se;
            print_message("  g %+.1f h%d: MC %.6f ± %.6f, quadrature %.6f, z %+.2f, min weight %.3g\n", gs[gi], which, m,
                          se, ref, z, wmin);
            if (!(fabs(z) < 4.0) || !(wmin >= 0.0)) fails++;
        }
        eda_table_free(&t);
    }
    assert_int_equal(fails, 0);
}

/* 5. extreme media and anisotropy (numerical stability): tables for σs from 1e-4 to 1e3 per unit
 * length (S range 10, so 1e-3 to 1e4 mean free paths), albedo 0.01, g from −0.99 to 0.99. Every cell a finite
 * CDF; the combined sampler's weights finite and >= 0 and unbiased against closed forms that hold for any
 * g: ∫ f dω = 1 and ∫ f·(ω·a) dω = g·(ω_in·a) (the mean cosine of Henyey–Greenstein is g).
 * Fast subset by default, the full cross product with DARTSPP_STRESS=full (make stress). */
static int check_extreme_case(double ss, double sa, double g, long n)
{
    eda_table t;
    build_small(&t, ss, sa, g, 10.0);
    long bad_cdf = 0;
    for (long c = 0; c < (long)NR * NS; c++) {
        const float *F = t.cdf + c * NC;
        for (int k = 0; k < NC; k++)
            if (!isfinite(F[k]) || !(F[k] >= (k ? F[k - 1] : 0.0f)) || !(F[k] <= 1.0f)) bad_cdf++;
        if (F[NC - 1] != 1.0f) bad_cdf++;
    }
    phase_function ph = {g == 0.0 ? PHASE_ISOTROPIC : PHASE_HENYEY_GREENSTEIN, g, NULL};
    vec3 w_in = v3_norm(v3(-0.3, 0.9, 0.2)), e = v3_norm(v3(0.5, 0.5, -0.7)), a = v3_norm(v3(0.3, -0.4, 0.85));
    ellipse_record r = record(2.5, 3.0, e);
    int fails = bad_cdf > 0 || !eda_cell(&t, &r);
    double ref[2] = {1.0, g * v3_dot(w_in, a)};
    double m[2] = {0}, m2[2] = {0};
    long bad_w = 0;
    dp_rng rng = rng_stream(4242, (uint64_t)(1e4 * ss), (uint64_t)(100 * (g + 1)));
    for (long i = 0; i < n; i++) {
        double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, w;
        vec3 d = eda_sample_direction(&t, 0.5, &ph, w_in, &r, u, &w);
        if (!isfinite(w) || w < 0.0 || !v3_is_finite(d)) {
            bad_w++;
            continue;
        }
        double x[2] = {w, w * v3_dot(d, a)};
        for (int k = 0; k < 2; k++) m[k] += x[k], m2[k] += x[k] * x[k];
    }
    for (int k = 0; k < 2; k++) {
        double mean = m[k] / n, se = sqrt(fmax(0.0, m2[k] / n - mean * mean) / n);
        double z = se > 0.0 ? (mean - ref[k]) / se : (fabs(mean - ref[k]) < 1e-12 ? 0.0 : INFINITY);
        print_message("  sigma_s %-6g sigma_a %-6g g %+5.2f  E[W%s] MC %.5f ± %.5f  closed form %.5f  z %+.2f%s\n", ss, sa,
                      g, k ? "(w.a)" : "", mean, se, ref[k], z, fabs(z) < 4.0 ? "" : "  <-- FAIL");
        fails += !(fabs(z) < 4.0);
    }
    if (bad_cdf || bad_w) print_message("  bad CDF entries %ld, non-finite or negative weights %ld\n", bad_cdf, bad_w);
    eda_table_free(&t);
    return fails + (bad_w > 0);
}

static void test_extreme_media_and_g(void **state)
{
    (void)state;
    const double media_full[][2] = {{1e-4, 0.0}, {1e-2, 1e-3}, {1.0, 99.0}, {1e2, 10.0}, {1e3, 9.9e4}};
    const double g_full[] = {-0.99, -0.5, 0.0, 0.5, 0.99};
    const double media_fast[][2] = {{1e-4, 0.0}, {1e3, 9.9e4}};
    const double g_fast[] = {-0.99, 0.99};
    int full = stress_full(), fails = 0;
    size_t nm = full ? 5 : 2, ng = full ? 5 : 2;
    for (size_t i = 0; i < nm; i++)
        for (size_t j = 0; j < ng; j++) {
            const double *md = full ? media_full[i] : media_fast[i];
            fails += check_extreme_case(md[0], md[1], full ? g_full[j] : g_fast[j], 200000);
        }
    assert_int_equal(fails, 0);
}

/* 6. a tabulated phase function (issue 51 item 3): EDA steers with a table built for HG of the table's ⟨cosθ⟩ and
 * the combined sampler weighs by phase_eval, so it stays unbiased for the shipped Mie table of advection fog:
 * ∫ f dω = 1 and ∫ f·(ω·a) dω = g·(ω_in·a) (any phase function of the scattering angle alone). */
static void test_combined_sampler_tabulated(void **state)
{
    (void)state;
    phase_table pt;
    dp_error err;
    if (phase_table_load(&pt, "tables/mie/fog_advection_905nm.csv", &err)) fail_msg("%s", err.msg);
    phase_function ph = {PHASE_TABULATED, pt.g, &pt};
    eda_table t;
    build_small(&t, 0.4, 0.02, pt.g, 10.0);
    vec3 w_in = v3_norm(v3(-0.3, 0.9, 0.2)), e = v3_norm(v3(0.5, 0.5, -0.7)), a = v3_norm(v3(0.3, -0.4, 0.85));
    ellipse_record r = record(2.5, 3.0, e);
    assert_non_null(eda_cell(&t, &r));
    double ref[2] = {1.0, pt.g * v3_dot(w_in, a)}, m[2] = {0}, m2[2] = {0};
    const long n = 400000;
    dp_rng rng = rng_stream(5151, 0, 0);
    int fails = 0;
    for (long i = 0; i < n; i++) {
        double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, w;
        vec3 d = eda_sample_direction(&t, 0.5, &ph, w_in, &r, u, &w);
        fails += !isfinite(w) || w < 0.0;
        double x[2] = {w, w * v3_dot(d, a)};
        for (int k = 0; k < 2; k++) m[k] += x[k], m2[k] += x[k] * x[k];
    }
    for (int k = 0; k < 2; k++) {
        double mean = m[k] / n, se = sqrt(fmax(0.0, m2[k] / n - mean * mean) / n), z = (mean - ref[k]) / se;
        print_message("  Mie advection table (g %.4f): E[W%s] MC %.5f ± %.5f, closed form %.5f, z %+.2f\n", pt.g,
                      k ? "(w.a)" : "", mean, se, ref[k], z);
        fails += !(fabs(z) < 4.0);
    }
    eda_table_free(&t);
    phase_table_free(&pt);
    assert_int_equal(fails, 0);
}

/* 4. deterministic builds (also across thread counts), save/load round trip, bad files refused */
static void test_files(void **state)
{
    (void)state;
    eda_table a, b, c;
    build_small(&a, 0.2, 0.01, -0.3, 8.0);
    omp_set_num_threads(1);
    build_small(&b, 0.2, 0.01, -0.3, 8.0);
    omp_set_num_threads(2);
    assert_memory_equal(a.cdf, b.cdf, sizeof(float) * NR * NS * NC);
    char *dir = test_tmpdir(), path[600], bad[600], cmd[2000];
    snprintf(path, sizeof path, "%s/t.bin", dir);
    dp_error err;
    assert_int_equal(eda_table_save(&a, path, &err), 0);
    assert_int_equal(eda_table_load(&c, path, &err), 0);
    assert_int_equal(c.n_ratio, NR);
    assert_int_equal(c.n_cos, NC);
    assert_true(c.sigma_s == 0.2 && c.g == -0.3 && c.s_max == 8.0);
    assert_memory_equal(a.cdf, c.cdf, sizeof(float) * NR * NS * NC);
    eda_table_free(&c);
    /* truncated */
    snprintf(bad, sizeof bad, "%s/trunc.bin", dir);
    snprintf(cmd, sizeof cmd, "head -c 5000 %s > %s", path, bad);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(eda_table_load(&c, bad, &err), -1);
    print_message("  truncated: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "trunc.bin"));
    assert_non_null(strstr(err.msg, "truncated"));
    /* one payload byte changed */
    snprintf(bad, sizeof bad, "%s/flip.bin", dir);
    snprintf(cmd, sizeof cmd, "cp %s %s && printf '\\177' | dd of=%s bs=1 seek=4000 conv=notrunc 2>/dev/null", path, bad, bad);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(eda_table_load(&c, bad, &err), -1);
    print_message("  corrupted: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "corrupted"));
    /* not a table; a headerless file of the wrong size */
    assert_int_equal(eda_table_load(&c, "/etc/hostname", &err), -1);
    assert_int_equal(eda_table_load_raw(&c, path, 10.0, 0.2, 0.999, &err), -1);
    assert_non_null(strstr(err.msg, "16777216"));
    /* the authors' headerless 128x128x256 float32 layout: uniform CDFs load; one decreasing entry is refused */
    {
        const size_t nv = (size_t)128 * 128 * 256;
        float *raw = malloc(nv * sizeof(float));
        assert_non_null(raw);
        for (size_t i = 0; i < nv; i++) raw[i] = (float)((i % 256) + 1) / 256.0f;
        char rawp[700];
        snprintf(rawp, sizeof rawp, "%s/raw.bin", dir);
        FILE *f = fopen(rawp, "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(raw, sizeof(float), nv, f), nv);
        fclose(f);
        assert_int_equal(eda_table_load_raw(&c, rawp, 16.0, 0.2, 0.999, &err), 0);
        assert_true(c.n_ratio == 128 && c.n_s == 128 && c.n_cos == 256 && c.s_max == 16.0);
        ellipse_record r = record(2.0, 3.0, v3(0, 0, 1));
        assert_true(fabs(eda_pdf(&c, eda_cell(&c, &r), r.e, v3(0, 0, 1)) - DP_INV_4PI) < 1e-9); /* uniform */
        eda_table_free(&c);
        raw[5 * 256 + 17] = 0.0f;
        f = fopen(rawp, "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(raw, sizeof(float), nv, f), nv);
        fclose(f);
        assert_int_equal(eda_table_load_raw(&c, rawp, 16.0, 0.2, 0.999, &err), -1);
        print_message("  headerless, corrupted: %s\n", err.msg);
        assert_non_null(strstr(err.msg, "not a CDF"));
        free(raw);
    }
    /* the cache builds once and then loads the same bits */
    assert_int_equal(eda_table_cached(&c, dir, 0.2, 0.01, -0.3, NR, NS, NC, 8.0, 0.2, 0.999, NULL, &err), 0);
    assert_memory_equal(a.cdf, c.cdf, sizeof(float) * NR * NS * NC);
    eda_table_free(&c);
    assert_int_equal(eda_table_cached(&c, dir, 0.2, 0.01, -0.3, NR, NS, NC, 8.0, 0.2, 0.999, NULL, &err), 0);
    assert_memory_equal(a.cdf, c.cdf, sizeof(float) * NR * NS * NC);
    eda_table_free(&c);
    /* a medium without scattering: refused, the reason given */
    assert_int_equal(eda_table_build(&c, 0.0, 0.1, 0.0, NR, NS, NC, 8.0, 0.2, 0.999, NULL, NULL, &err), -1);
    assert_non_null(strstr(err.msg, "diffusion"));
    eda_table_free(&a);
    eda_table_free(&b);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    (void)!system(cmd);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cdfs_and_density),
        cmocka_unit_test(test_table_points_at_camera),
        cmocka_unit_test(test_eda_branch_chi2),
        cmocka_unit_test(test_combined_sampler_unbiased),
        cmocka_unit_test(test_files),
        cmocka_unit_test(test_extreme_media_and_g),
        cmocka_unit_test(test_combined_sampler_tabulated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
