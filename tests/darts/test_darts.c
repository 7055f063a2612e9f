/* tier: quick */
/* tier: stress */
/* The DARTS samplers (include/dartspp/darts.h) against independent references, no scene needed:
 *  1. elliptical control vertex (plain and MIS): Monte Carlo mean of W·g(x(t)) over the residual T against
 *     a quadrature over exactly the distances whose path time lands in the bin (boundaries by bisection);
 *  2. DA distance sampling: medium part against ∫ σs e^{−σt t} g(t) 1[reachable] dt (quadrature in the
 *     free-flight CDF variable), surface part against e^{−σt tmax} g(tmax), per channel, for a fresh and a
 *     fixed ellipse record; every weight finite and >= 0, fallbacks only where nothing is reachable;
 *  3. bin sampling: χ² of the drawn frames against the closed-form reachable-time fractions;
 *  1b. control vertices with camera-unwarped time: mean weight against quadrature, χ² of t against the
 *     truncated exponential, every time in the bin;
 *  4. time exactness of control vertices on random inputs;
 *  5. darts_can_reach against its closed form, edges included;
 *  6. sections 1 and 2 on extreme media, anisotropy and gates (fast subset; all with DARTSPP_STRESS=full).
 * Monte Carlo checks use |z| < 4 with the standard error from the sample variance. */
#include "fixtures.h"

#include "dartspp/darts.h"

/* compiled twice (main at the end): each program leaves the other's cases unused */
#pragma GCC diagnostic ignored "-Wunused-function"

#define Z_MAX 4.0

/* ---------------------------------------------------------------- helpers */

/* Gauss–Legendre rule of order GL_N (test_util.h), computed once. */
#define GL_N 16
static double gl_x[GL_N], gl_w[GL_N];
static int gl_ready;

static void gl_init(void)
{
    if (gl_ready) return;
    gauss_legendre(GL_N, gl_x, gl_w);
    gl_ready = 1;
}

typedef double (*integrand_fn)(double, const void *);

/* composite Gauss–Legendre on [a, b] */
static double integrate(integrand_fn f, const void *ctx, double a, double b, int panels)
{
    gl_init();
    if (!(b > a)) return 0.0;
    double h = (b - a) / panels, sum = 0.0;
    for (int p = 0; p < panels; p++) {
        double mid = a + h * (p + 0.5);
        for (int k = 0; k < GL_N; k++) sum += gl_w[k] * 0.5 * h * f(mid + 0.5 * h * gl_x[k], ctx);
    }
    return sum;
}

typedef struct {
    long n;
    double mean, m2;
} stats;

static void st_add(stats *s, double x)
{
    s->n++;
    double d = x - s->mean;
    s->mean += d / s->n;
    s->m2 += d * (x - s->mean);
}

static double st_se(const stats *s) { return s->n > 1 ? sqrt(s->m2 / (s->n - 1) / s->n) : INFINITY; }

/* Relative precision of a reference whose interval ends come from bisection on S(t) ≈ 1 in double precision
 * (and of a sampler that forms T − C from doubles near 1): S is good to about 2 ulps (4e-16), so an interval
 * end is good to 4e-16/(dS/dt); in the shortest intervals of the tests (5e-7, degenerate ellipses with
 * dS/dt ≈ 2) that is 4e-10 of the interval. Bound used: 1e-9 of the reference. Only estimators whose own
 * standard error falls below this (weights constant to 1e-10, measured 2e-10 deviations) ever need it. */
#define REF_REL_PRECISION 1e-9

/* Prints and checks one Monte Carlo mean against its reference; returns 1 on failure. */
static int check_z(const char *what, const stats *s, double ref)
{
    double se = st_se(s), diff = s->mean - ref;
    double z = se > 0.0 ? diff / se : (fabs(diff) <= 1e-12 * fmax(1.0, fabs(ref)) ? 0.0 : INFINITY);
    int bad = !(fabs(z) < Z_MAX) && !(fabs(diff) <= Z_MAX * se + REF_REL_PRECISION * fabs(ref));
    printf("  %-52s MC %.7g ± %.2g  ref %.7g  z %+.2f%s\n", what, s->mean, se, ref, z, bad ? "  <-- FAIL" : "");
    return bad;
}

static vec3 unit_perp(vec3 e)
{
    vec3 a = fabs(e.x) < 0.6 ? v3(1, 0, 0) : v3(0, 1, 0);
    vec3 p = v3_sub(a, v3_scale(e, v3_dot(a, e)));
    return v3_scale(p, 1.0 / v3_len(p));
}

/* unit direction with cosθ = c to e */
static vec3 dir_at(vec3 e, double c)
{
    return v3_add(v3_scale(e, c), v3_scale(unit_perp(e), sqrt(fmax(0.0, 1.0 - c * c))));
}

static vec3 uniform_dir(dp_rng *rng)
{
    double z = 1.0 - 2.0 * rng_uniform(rng), phi = 2.0 * M_PI * rng_uniform(rng);
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    return v3(r * cos(phi), r * sin(phi), z);
}

/* S(t) = t + |x + t·d − cam|, non-decreasing in t */
static double path_S(vec3 x, vec3 d, vec3 cam, double t)
{
    vec3 p = v3_add(x, v3_scale(d, t));
    double dx = p.x - cam.x, dy = p.y - cam.y, dz = p.z - cam.z;
    return t + sqrt(dx * dx + dy * dy + dz * dz);
}

/* smallest t >= 0 with S(t) >= target (INFINITY if S stays below it; S grows unless d points at cam) */
static double solve_S(vec3 x, vec3 d, vec3 cam, double target)
{
    if (path_S(x, d, cam, 0.0) >= target) return 0.0;
    double lo = 0.0, hi = 1.0;
    while (path_S(x, d, cam, hi) < target) {
        lo = hi;
        hi *= 2.0;
        if (hi > 1e12) return INFINITY;
    }
    for (int i = 0; i < 400; i++) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        if (path_S(x, d, cam, mid) < target) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* smooth test function of position */
static double g_pos(vec3 p) { return 1.0 + 0.5 * sin(1.3 * p.x + 0.7 * p.y - 0.4 * p.z + 0.2); }

static const vec3 X0 = {0.3, -0.2, 0.5};

static vec3 e_axis(void) { return v3(1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0); }

/* ---------------------------------------------------------------- 1. control vertex */

typedef struct {
    const char *name;
    double C, cos_t;
    double start, end, tau; /* window in time units, elapsed time */
    double eta;             /* medium of the vertex; guide.eta_lb = eta */
    double sigma_s, sigma_t, tmax;
    residual_sampling mode;
    double sigma_res; /* rate of the exponential residual */
    int mis;          /* control_vertex_sample instead of ellipse_control_vertex */
    long n;
} cv_case;

typedef struct {
    vec3 x, d;
    double ss, st;
} cv_quad_ctx;

static double cv_integrand(double t, const void *vp)
{
    const cv_quad_ctx *c = vp;
    return c->ss * exp(-c->st * t) * g_pos(v3_add(c->x, v3_scale(c->d, t)));
}

static int run_cv_case(const cv_case *k, uint64_t seed)
{
    vec3 e = e_axis(), x = X0, cam = v3_add(X0, v3_scale(e, k->C)), d = dir_at(e, k->cos_t);
    darts_guide guide = {.active = 1, .cam = cam, .beg = k->start, .end = k->end, .width = k->end - k->start,
                         .frames = 0, .eta_lb = k->eta};
    darts_bin bin = {.start = k->start, .end = k->end, .pdf = 1.0, .frame = -1};

    /* quadrature: t with τ + η S(t) in [start, end], t in [0, tmax] */
    double ta = solve_S(x, d, cam, (k->start - k->tau) / k->eta);
    double tb = solve_S(x, d, cam, (k->end - k->tau) / k->eta);
    tb = fmin(tb, k->tmax);
    cv_quad_ctx qc = {x, d, k->sigma_s, k->sigma_t};
    double ref = integrate(cv_integrand, &qc, ta, tb, 400);

    dp_rng rng = rng_stream(seed, 1, 0);
    stats s = {0};
    long hits = 0, bad_w = 0;
    for (long i = 0; i < k->n; i++) {
        ellipse_record rec;
        ellipse_record_init(&rec, &guide, &bin, x, k->tau, k->eta, k->mode, k->sigma_res, rng_uniform(&rng));
        double t = 0, pdf = 0, w = 0;
        int ok;
        if (k->mis) {
            double u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);
            ok = control_vertex_sample(&rec, d, k->tmax, k->mode, k->sigma_res, u1, u2, &t, &pdf);
        } else ok = ellipse_control_vertex(&rec, d, k->tmax, &t, &pdf);
        if (ok) {
            w = k->sigma_s * exp(-k->sigma_t * t) / pdf;
            if (!isfinite(w) || w < 0.0) bad_w++;
            else w *= g_pos(v3_add(x, v3_scale(d, t)));
            hits++;
        }
        st_add(&s, isfinite(w) ? w : 0.0);
    }
    char what[128];
    snprintf(what, sizeof what, "%s [t %.4g..%.4g, hits %.3f]", k->name, ta, tb, (double)hits / k->n);
    int fail = check_z(what, &s, ref);
    if (bad_w) {
        printf("    %ld non-finite or negative weights\n", bad_w);
        fail = 1;
    }
    return fail;
}

#define INF INFINITY

static void test_control_vertex_reference_case(void **state)
{
    (void)state;
    /* docs/reference-renderer.md §6 check case: C = 3, cosθ = 0.3, window [4, 4.5], τ = 0, σt = 0.5 with σs = 0.4,
     * tmax = 4; our own g, so the reference's number does not apply */
    const cv_case cases[] = {
        {"ref case, uniform residual", 3, 0.3, 4, 4.5, 0, 1, 0.4, 0.5, 4, RESIDUAL_UNIFORM, 0.5, 0, 1000000},
        {"ref case, exponential residual", 3, 0.3, 4, 4.5, 0, 1, 0.4, 0.5, 4, RESIDUAL_EXPONENTIAL, 0.5, 0, 1000000},
    };
    int fail = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) fail += run_cv_case(&cases[i], 100 + i);
    assert_int_equal(fail, 0);
}

static void test_control_vertex_cases(void **state)
{
    (void)state;
    const cv_case cases[] = {
        {"tmax inf, cos -0.6, tau 1, uniform", 2, -0.6, 5, 7, 1, 1, 0.8, 1.0, INF, RESIDUAL_UNIFORM, 1.0, 0, 600000},
        {"tmax inf, cos -0.6, tau 1, exponential", 2, -0.6, 5, 7, 1, 1, 0.8, 1.0, INF, RESIDUAL_EXPONENTIAL, 1.0, 0,
         600000},
        {"tmax cuts the interval (1.5), uniform", 3, 0.0, 4, 6, 0, 1, 0.3, 0.6, 1.5, RESIDUAL_UNIFORM, 0.6, 0, 600000},
        {"tmax cuts the interval (1.5), exponential", 3, 0.0, 4, 6, 0, 1, 0.3, 0.6, 1.5, RESIDUAL_EXPONENTIAL, 2.0, 0,
         600000},
        {"S_lo = C, cos 0.9, uniform", 2, 0.9, 1.5, 3, 0, 1, 0.5, 0.7, INF, RESIDUAL_UNIFORM, 0.7, 0, 600000},
        {"S_lo = C, cos 0.9, exponential", 2, 0.9, 1.5, 3, 0, 1, 0.5, 0.7, INF, RESIDUAL_EXPONENTIAL, 0.7, 0, 600000},
        {"cos 0.999 towards camera, uniform", 2, 0.999, 1.8, 2.6, 0, 1, 0.9, 1.0, INF, RESIDUAL_UNIFORM, 1.0, 0,
         600000},
        {"eta 1.33, tau 0.5, tmax 3, uniform", 2, 0.1, 3.5, 4.5, 0.5, 1.33, 0.5, 0.7, 3, RESIDUAL_UNIFORM, 0.7, 0,
         600000},
        {"eta 1.33, tau 0.5, tmax 3, exponential", 2, 0.1, 3.5, 4.5, 0.5, 1.33, 0.5, 0.7, 3, RESIDUAL_EXPONENTIAL, 0.7,
         0, 600000},
        {"eta 1.33, cos -0.5, tmax inf, exponential", 1.2, -0.5, 3.0, 5.5, 0.2, 1.33, 0.5, 0.7, INF,
         RESIDUAL_EXPONENTIAL, 1.5, 0, 600000},
    };
    int fail = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) fail += run_cv_case(&cases[i], 200 + i);
    assert_int_equal(fail, 0);
}

static void test_control_vertex_mis(void **state)
{
    (void)state;
    const cv_case cases[] = {
        {"MIS: ref case, uniform", 3, 0.3, 4, 4.5, 0, 1, 0.4, 0.5, 4, RESIDUAL_UNIFORM, 0.5, 1, 600000},
        {"MIS: ref case, exponential", 3, 0.3, 4, 4.5, 0, 1, 0.4, 0.5, 4, RESIDUAL_EXPONENTIAL, 0.5, 1, 600000},
        {"MIS: tmax cuts the interval, uniform", 3, 0.0, 4, 6, 0, 1, 0.3, 0.6, 1.5, RESIDUAL_UNIFORM, 0.6, 1, 600000},
        {"MIS: cos 0.999, S_lo = C, uniform", 2, 0.999, 1.8, 2.6, 0, 1, 0.9, 1.0, INF, RESIDUAL_UNIFORM, 1.0, 1,
         600000},
        {"MIS: cos 0.999, S_lo = C, exponential", 2, 0.999, 1.8, 2.6, 0, 1, 0.9, 1.0, INF, RESIDUAL_EXPONENTIAL, 1.0,
         1, 600000},
        {"MIS: eta 1.33, tmax 3, exponential", 2, 0.1, 3.5, 4.5, 0.5, 1.33, 0.5, 0.7, 3, RESIDUAL_EXPONENTIAL, 0.7, 1,
         600000},
    };
    int fail = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) fail += run_cv_case(&cases[i], 300 + i);
    assert_int_equal(fail, 0);
}

/* ---------------------------------------------------------------- 2. DA distance sampling */

typedef struct {
    const char *name;
    double C, cos_t;
    double start, end, tau;
    double eta, eta_lb;
    vec3 sigma_s, sigma_a;
    phase_function phase;
    double tmax;
    residual_sampling mode;
    double sigma_res;
    double kg;          /* frequency of g(t) = 1 + 0.5 sin(kg t + 0.3) */
    int expect_no_fallback;
    long n;
} da_case;

typedef struct {
    double ss, st, kg;
} da_quad_ctx;

static double g_t(double t, double kg) { return 1.0 + 0.5 * sin(kg * t + 0.3); }

static double da_integrand(double t, const void *vp)
{
    const da_quad_ctx *c = vp;
    return c->ss * exp(-c->st * t) * g_t(t, c->kg);
}

static int run_da_case(const da_case *k, int fixed_record, double defensive, uint64_t seed)
{
    vec3 e = e_axis(), x = X0, cam = v3_add(X0, v3_scale(e, k->C)), d = dir_at(e, k->cos_t);
    darts_guide guide = {.active = 1, .cam = cam, .beg = k->start, .end = k->end, .width = k->end - k->start,
                         .frames = 0, .eta_lb = k->eta_lb};
    darts_bin bin = {.start = k->start, .end = k->end, .pdf = 1.0, .frame = -1};
    medium m = {.sigma_s = k->sigma_s, .sigma_a = k->sigma_a, .sigma_t = v3_add(k->sigma_s, k->sigma_a),
                .eta = k->eta, .max_bounces = 1000, .phase = k->phase};

    double S_reach = (k->end - k->tau) / k->eta_lb;
    double tR = solve_S(x, d, cam, S_reach); /* reachable: t < tR */
    double tcut = fmin(tR, k->tmax);

    double ref_med[3], ref_surf[3];
    for (int c = 0; c < 3; c++) {
        double st = v3_comp(m.sigma_t, c), ss = v3_comp(m.sigma_s, c);
        da_quad_ctx qc = {ss, st, k->kg};
        /* [0, tcut] (tcut is finite: the reachable set is bounded), split at 60 mean free paths */
        double split = fmin(tcut, 60.0 / st);
        ref_med[c] = integrate(da_integrand, &qc, 0.0, split, 2000) + integrate(da_integrand, &qc, split, tcut, 200);
        ref_surf[c] = isfinite(k->tmax) ? exp(-st * k->tmax) * g_t(k->tmax, k->kg) : 0.0;
    }

    dp_rng rng = rng_stream(seed, 2, fixed_record);
    ellipse_record rec;
    ellipse_record_init(&rec, &guide, &bin, x, k->tau, k->eta, k->mode, k->sigma_res, 0.37);
    int fail = 0;
    if (fabs(rec.S_reach - S_reach) > 1e-12 * S_reach) {
        printf("  record S_reach %.17g, expected %.17g\n", rec.S_reach, S_reach);
        fail = 1;
    }
    int grey = m.sigma_s.x == m.sigma_s.y && m.sigma_s.y == m.sigma_s.z && m.sigma_a.x == m.sigma_a.y &&
               m.sigma_a.y == m.sigma_a.z;
    const int grey_medium = grey;
    long n_fallback_weight = 0, n_over_bound = 0;
    stats med[3] = {{0}}, surf[3] = {{0}}, tot[3] = {{0}};
    long n_med = 0, n_fallback = 0, n_bad_w = 0, n_fallback_reachable = 0, n_bad_t = 0, n_surf_inf_nonzero = 0;
    for (long i = 0; i < k->n; i++) {
        if (!fixed_record)
            ellipse_record_init(&rec, &guide, &bin, x, k->tau, k->eta, k->mode, k->sigma_res, rng_uniform(&rng));
        da_sample out;
        da_sample_distance(&m, &rec, d, k->tmax, defensive, &rng, &out);
        double w[3] = {out.weight.x, out.weight.y, out.weight.z};
        for (int c = 0; c < 3; c++)
            if (!isfinite(w[c]) || w[c] < 0.0) {
                n_bad_w++;
                w[c] = 0.0;
            }
        double fm = 0.0, fs = 0.0;
        if (out.medium_event) {
            n_med++;
            if (!(out.t >= 0.0 && out.t < k->tmax)) n_bad_t++;
            int reach = path_S(x, d, cam, out.t) < S_reach;
            if (out.fallback) {
                n_fallback++;
                /* plain exponential weight σs e^{−σt t}/(σt e^{−σt t}) = σs/σt (grey media) */
                if (grey_medium && fabs(out.weight.x - m.sigma_s.x / m.sigma_t.x) > 1e-12 * out.weight.x)
                    n_fallback_weight++;
                /* a fallback is allowed only when nothing is reachable, so its own t is not (1e-12 slack) */
                if (path_S(x, d, cam, out.t) < S_reach * (1.0 - 1e-12)) n_fallback_reachable++;
            }
            /* the defensive selection bounds the RIS factor by 1/ε: weight <= σs/(σt·ε) (grey media) */
            if (grey_medium && defensive > 0.0 && out.weight.x > m.sigma_s.x / (m.sigma_t.x * defensive) * (1 + 1e-12))
                n_over_bound++;
            fm = reach ? g_t(out.t, k->kg) : 0.0;
        } else {
            if (out.t != k->tmax) n_bad_t++;
            if (!isfinite(k->tmax) && !v3_is_zero(out.weight)) n_surf_inf_nonzero++;
            fs = isfinite(k->tmax) ? g_t(k->tmax, k->kg) : 0.0;
        }
        for (int c = 0; c < 3; c++) {
            st_add(&med[c], w[c] * fm);
            st_add(&surf[c], w[c] * fs);
            st_add(&tot[c], w[c] * (fm + fs));
        }
    }
    printf(" %s, %s record, defensive %.1f (t_R %.4g, S_reach %.4g, C %.4g): medium %.3f, fallback %.4f\n", k->name,
           fixed_record ? "fixed" : "fresh", defensive, tR, S_reach, k->C, (double)n_med / k->n, (double)n_fallback / k->n);
    for (int c = 0; c < (grey ? 1 : 3); c++) {
        char what[128];
        snprintf(what, sizeof what, "ch %d medium part", c);
        fail += check_z(what, &med[c], ref_med[c]);
        snprintf(what, sizeof what, "ch %d surface part", c);
        fail += check_z(what, &surf[c], ref_surf[c]);
        snprintf(what, sizeof what, "ch %d total", c);
        fail += check_z(what, &tot[c], ref_med[c] + ref_surf[c]);
    }
    printf("  weights non-finite/negative: %ld of %ld; fallbacks at a reachable t: %ld; bad t: %ld; "
           "nonzero escape weight: %ld; fallback weight != sigma_s/sigma_t: %ld; over the defensive bound: %ld\n",
           n_bad_w, 3 * k->n, n_fallback_reachable, n_bad_t, n_surf_inf_nonzero, n_fallback_weight, n_over_bound);
    if (n_bad_w || n_fallback_reachable || n_bad_t || n_surf_inf_nonzero || n_fallback_weight || n_over_bound) fail++;
    if (k->expect_no_fallback && n_fallback) {
        printf("  expected no fallback (every candidate is reachable), got %ld\n", n_fallback);
        fail++;
    }
    return fail;
}

static const phase_function ISO = {PHASE_ISOTROPIC, 0.0, NULL};
static const phase_function HG05 = {PHASE_HENYEY_GREENSTEIN, 0.5, NULL};

static int run_da_both(const da_case *k, uint64_t seed)
{
    /* plain RIS (ε = 0, the reference) and the defensive selection (ε = 0.2, our default) */
    return run_da_case(k, 0, 0.0, seed) + run_da_case(k, 1, 0.0, seed + 1000) + run_da_case(k, 0, 0.2, seed + 2000) +
           run_da_case(k, 1, 0.2, seed + 3000);
}

static void test_da_normal(void **state)
{
    (void)state;
    /* S_reach 3.2, reachable t < 1.11; tmax 0.8 cuts inside it */
    const da_case k = {"normal, grey, tmax 0.8", 2, 0.2, 2.5, 3.5, 0.3, 1, 1, v3s(0.8), v3s(0.2), ISO, 0.8,
                       RESIDUAL_UNIFORM, 1.0, 1.3, 0, 400000};
    const da_case k2 = {"normal, grey, tmax 3 (beyond reach)", 2, 0.2, 2.5, 3.5, 0.3, 1, 1, v3s(0.8), v3s(0.2), ISO,
                        3.0, RESIDUAL_EXPONENTIAL, 1.0, 1.3, 0, 400000};
    assert_int_equal(run_da_both(&k, 10) + run_da_both(&k2, 20), 0);
}

static void test_da_infinite_tmax(void **state)
{
    (void)state;
    const da_case k = {"tmax inf, grey, exponential residual", 1.5, -0.4, 2, 4, 0, 1, 1, v3s(0.6), v3s(0.3), ISO,
                       INF, RESIDUAL_EXPONENTIAL, 0.9, 2.0, 0, 400000};
    assert_int_equal(run_da_both(&k, 30), 0);
}

static void test_da_coloured(void **state)
{
    (void)state;
    const da_case k = {"coloured, HG 0.5, tmax 2", 2.5, 0.5, 3, 4.2, 0.2, 1, 1, {0.5, 0.9, 0.3}, {0.1, 0.2, 0.4},
                       HG05, 2.0, RESIDUAL_UNIFORM, 0.8, 1.7, 0, 400000};
    const da_case k2 = {"coloured, tmax inf", 2.5, -0.3, 3, 4.2, 0.2, 1, 1, {0.5, 0.9, 0.3}, {0.1, 0.2, 0.4}, ISO,
                        INF, RESIDUAL_EXPONENTIAL, 0.8, 1.7, 0, 400000};
    assert_int_equal(run_da_both(&k, 40) + run_da_both(&k2, 50), 0);
}

static void test_da_barely_reachable(void **state)
{
    (void)state;
    /* camera 10 away, S_reach 10.05: only t < ~0.05 can still reach the bin; most candidate sets are empty */
    const da_case k = {"barely reachable (C 10, S_reach 10.05)", 10, 0.0, 9.9, 10.05, 0, 1, 1, v3s(0.9), v3s(0.1),
                       ISO, INF, RESIDUAL_UNIFORM, 1.0, 20.0, 0, 400000};
    const da_case k2 = {"barely reachable, tmax 5", 10, 0.0, 9.9, 10.05, 0, 1, 1, v3s(0.9), v3s(0.1), ISO, 5.0,
                        RESIDUAL_UNIFORM, 1.0, 20.0, 0, 400000};
    assert_int_equal(run_da_both(&k, 60) + run_da_both(&k2, 70), 0);
}

static void test_da_thick(void **state)
{
    (void)state;
    /* σt = 200 (σa 50), camera 6 away, residual ~7: log Φ ≈ −1100, far below double's exp range; every candidate
     * lies well inside the reachable set (t_R ≈ 1.8, candidates < 0.2), so there must be no fallback */
    const da_case k = {"thick (sigma_t 200, C 6)", 6, 0.3, 6.8, 7.5, 0, 1, 1, v3s(150), v3s(50), ISO, INF,
                       RESIDUAL_UNIFORM, 200, 300.0, 1, 400000};
    const da_case k2 = {"thick, tmax 0.01", 6, -0.2, 6.8, 7.5, 0, 1, 1, v3s(150), v3s(50), ISO, 0.01,
                        RESIDUAL_EXPONENTIAL, 200, 300.0, 1, 400000};
    assert_int_equal(run_da_both(&k, 80) + run_da_both(&k2, 90), 0);
}

static void test_da_refractive(void **state)
{
    (void)state;
    /* vertex in η = 1.33, scene η_lb = 1: S_reach uses η_lb, the record's T uses η */
    const da_case k = {"eta 1.33, eta_lb 1", 2, -0.1, 3, 4, 0.2, 1.33, 1, v3s(0.7), v3s(0.2), ISO, 2.5,
                       RESIDUAL_UNIFORM, 0.9, 1.1, 0, 400000};
    assert_int_equal(run_da_both(&k, 100), 0);
}

/* ---------------------------------------------------------------- 1b. control vertex, unwarped time */

/* sphere_control_vertex (issue 21): with the camera leg untimed, the photon at distance t along the ray from
 * a vertex of time τ has time τ + η·t, so the places in the bin are t ∈ [(b0 − τ)/η, (b1 − τ)/η) ∩ [0, tmax).
 * Checked per case: (1) E[W·g(x(t))] with W = σs e^{−σt t}/p(t) against the quadrature of σs e^{−σt t} g over
 * that interval (worked out here from τ, η and the bin); (2) χ² of 20 equal-width t bins against the
 * truncated exponential e^{−σ(t − lo)} (σ the rate the sampler is given; uniform when σ·length < 1e-6)
 * integrated in closed form here; (3) every sample's time in the bin; (4) sphere_control_vertex_pdf at each
 * sample equals the returned pdf. */
typedef struct {
    const char *name;
    double tau, eta, b0, b1, tmax, sigma_s, sigma_t, sigma; /* sigma: the sampler's rate (mean σt) */
    long n;
} sphere_case;

static int run_sphere_case(const sphere_case *k, uint64_t seed)
{
    vec3 x = X0, d = dir_at(e_axis(), 0.2);
    darts_bin bin = {.start = k->b0, .end = k->b1, .pdf = 1.0, .frame = -1};
    double lo = fmax(0.0, (k->b0 - k->tau) / k->eta), hi = fmin(k->tmax, (k->b1 - k->tau) / k->eta);
    cv_quad_ctx qc = {x, d, k->sigma_s, k->sigma_t};
    double ref = hi > lo ? integrate(cv_integrand, &qc, lo, hi, 200) : 0.0;
    enum { NB = 20 };
    long count[NB] = {0}, hits = 0, bad = 0;
    dp_rng rng = rng_stream(seed, 7, 0);
    stats s = {0};
    for (long i = 0; i < k->n; i++) {
        double t = 0, pdf = 0, w = 0;
        if (sphere_control_vertex(k->tau, k->eta, &bin, k->tmax, k->sigma, rng_uniform(&rng), &t, &pdf)) {
            double time = k->tau + k->eta * t;
            if (!(t >= lo && t < hi && time >= k->b0 && time < k->b1 && pdf > 0.0 && isfinite(pdf))) bad++;
            if (fabs(sphere_control_vertex_pdf(k->tau, k->eta, &bin, k->tmax, k->sigma, t) - pdf) > 1e-12 * pdf) bad++;
            w = k->sigma_s * exp(-k->sigma_t * t) / pdf * g_pos(v3_add(x, v3_scale(d, t)));
            int j = (int)((t - lo) / (hi - lo) * NB);
            count[j < NB ? j : NB - 1]++;
            hits++;
        }
        st_add(&s, w);
    }
    char what[128];
    snprintf(what, sizeof what, "%s [t %.4g..%.4g]", k->name, lo, hi);
    int fail = check_z(what, &s, ref);
    if (!(hi > lo)) return fail + (hits != 0) + (bad != 0);
    /* the truncated exponential's mass in each t bin, in closed form */
    double L = hi - lo, a = k->sigma * L, chi2 = 0.0;
    for (int j = 0; j < NB; j++) {
        double u0 = (double)j / NB, u1 = (double)(j + 1) / NB;
        double p = a > 1e-6 ? (exp(-a * u0) - exp(-a * u1)) / (1.0 - exp(-a)) : u1 - u0;
        double ex = p * hits;
        chi2 += (count[j] - ex) * (count[j] - ex) / ex;
    }
    double pval = test_gamma_q((NB - 1) / 2.0, chi2 / 2.0);
    printf("    hits %.4f, chi2 %.2f (dof %d, p %.3g), bad %ld\n", (double)hits / k->n, chi2, NB - 1, pval, bad);
    return fail + (pval < 1e-4) + (bad != 0) + (hits < k->n * 0.999);
}

static void test_sphere_control_vertex(void **state)
{
    (void)state;
    const sphere_case cases[] = {
        {"tau 0, eta 1, exponential", 0.0, 1.0, 1.0, 2.5, INFINITY, 0.8, 1.0, 1.0, 400000},
        {"tau 0.5, eta 1.33, tmax cuts (1.2)", 0.5, 1.33, 1.0, 3.0, 1.2, 0.5, 0.9, 0.7, 400000},
        {"vertex already in the bin (lo = 0)", 2.2, 1.0, 2.0, 2.4, INFINITY, 0.6, 0.7, 0.7, 400000},
        {"thin medium: uniform", 0.0, 1.0, 3.0, 3.5, INFINITY, 1e-8, 1e-8, 1e-8, 400000},
        {"thick medium (σL = 40)", 0.0, 1.0, 1.0, 1.5, INFINITY, 60.0, 80.0, 80.0, 400000},
        {"bin behind the vertex: empty", 3.0, 1.0, 1.0, 2.5, INFINITY, 0.8, 1.0, 1.0, 10000},
        {"tmax before the bin: empty", 0.0, 1.0, 2.0, 2.5, 1.5, 0.8, 1.0, 1.0, 10000},
    };
    int fail = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) fail += run_sphere_case(&cases[i], 300 + i);
    assert_int_equal(fail, 0);
}

/* ---------------------------------------------------------------- 3. bin sampling */

/* Wilson–Hilferty upper critical value of χ²_k at p = 1e-4 (normal quantile 3.719) */
static double chi2_crit(int k)
{
    double a = 2.0 / (9.0 * k), z = 3.719;
    double c = 1.0 - a + z * sqrt(a);
    return k * c * c * c;
}

static int run_bin_case(const char *name, int frames, double beg, double width, double eta_lb, double dist,
                        long n, uint64_t seed)
{
    vec3 cam = v3(1.0, 2.0, -0.5), dir = v3_norm(v3(0.3, -0.8, 0.2));
    vec3 light = v3_add(cam, v3_scale(dir, dist));
    darts_guide g = {.active = 1, .cam = cam, .beg = beg, .end = beg + frames * width, .width = width,
                     .frames = frames, .eta_lb = eta_lb};
    double tmin = fmax(beg, eta_lb * v3_len(v3_sub(cam, light))), range = g.end - tmin;
    double p[64] = {0};
    for (int k = 0; k < frames; k++) {
        double a = fmax(beg + k * width, tmin), b = beg + (k + 1) * width;
        p[k] = b > a ? (b - a) / range : 0.0;
    }
    long count[64] = {0};
    double pdf_seen[64] = {0};
    int fail = 0;
    long bad = 0;
    dp_rng rng = rng_stream(seed, 3, 0);
    for (long i = 0; i < n; i++) {
        darts_bin b;
        if (!darts_sample_bin(&g, light, 0.0, rng_uniform(&rng), &b)) {
            bad++;
            continue;
        }
        int k = b.frame;
        if (k < 0 || k >= frames) {
            bad++;
            continue;
        }
        count[k]++;
        double s0 = beg + k * width;
        if (fabs(b.start - s0) > 1e-12 * fmax(1.0, fabs(s0)) || fabs(b.end - (s0 + width)) > 1e-12 * (s0 + width) ||
            fabs(b.pdf - p[k]) > 1e-12)
            bad++;
        pdf_seen[k] = b.pdf;
    }
    double chi2 = 0.0, psum = 0.0;
    int dof = -1;
    for (int k = 0; k < frames; k++) {
        if (p[k] > 0.0) {
            double ex = p[k] * n;
            chi2 += (count[k] - ex) * (count[k] - ex) / ex;
            dof++;
            psum += pdf_seen[k];
            if (count[k] == 0) bad++;
        } else if (count[k]) bad++; /* an unreachable frame drawn */
    }
    double crit = dof > 0 ? chi2_crit(dof) : 0.0;
    int first = 0;
    while (first < frames - 1 && p[first] == 0.0) first++;
    printf("  %-36s tmin %.4g, frame %d first: pdf %.6g (%ld draws of %ld), chi2 %.2f (dof %d, crit %.2f), "
           "sum pdf %.15g, bad %ld\n",
           name, tmin, first, p[first], count[first], n, chi2, dof, crit, psum, bad);
    if (bad || (dof > 0 && !(chi2 < crit)) || fabs(psum - 1.0) > 1e-12) fail = 1;
    return fail;
}

static void test_bins_frames(void **state)
{
    (void)state;
    int fail = 0;
    /* frames [2, 12), light 4.3 away: frame 2 = [4, 5) partly reachable (0.7 of 7.7) */
    fail += run_bin_case("10 frames, partial first bin", 10, 2.0, 1.0, 1.0, 4.3, 400000, 1);
    /* η_lb 1.33: earliest arrival 1.33·3.3 = 4.389 */
    fail += run_bin_case("10 frames, eta_lb 1.33, partial", 10, 2.0, 1.0, 1.33, 3.3, 400000, 2);
    /* light close: the whole window reachable, uniform 1/N */
    fail += run_bin_case("7 frames, whole window reachable", 7, 3.0, 0.5, 1.0, 1.2, 400000, 3);
    /* earliest arrival exactly on a frame boundary (5 = 2 + 3·1) */
    fail += run_bin_case("10 frames, arrival on a boundary", 10, 2.0, 1.0, 1.0, 5.0, 400000, 4);
    /* only the last frame, partly */
    fail += run_bin_case("5 frames, only part of the last", 5, 0.0, 0.25, 1.0, 1.1, 100000, 5);
    assert_int_equal(fail, 0);
}

static void test_bins_gate_and_unreachable(void **state)
{
    (void)state;
    vec3 cam = v3(0, 0, 0);
    darts_guide gate = {.active = 1, .cam = cam, .beg = 4.0, .end = 4.5, .width = 0.5, .frames = 0, .eta_lb = 1.0};
    darts_guide fr = {.active = 1, .cam = cam, .beg = 2.0, .end = 12.0, .width = 1.0, .frames = 10, .eta_lb = 1.0};
    dp_rng rng = rng_stream(7, 3, 1);
    for (int i = 0; i < 1000; i++) {
        darts_bin b;
        double dist = 4.49 * rng_uniform(&rng); /* reachable, before or inside the gate */
        assert_int_equal(darts_sample_bin(&gate, v3(0, dist, 0), 0.0, rng_uniform(&rng), &b), 1);
        assert_true(b.pdf == 1.0);
        assert_int_equal(b.frame, -1);
        assert_true(b.start == 4.0 && b.end == 4.5);
    }
    darts_bin b;
    /* light cannot reach the window: η_lb·|cam − x| >= end, exactly equal included */
    assert_int_equal(darts_sample_bin(&gate, v3(3, 4, 0) /* 5 */, 0.0, 0.5, &b), 0);
    assert_int_equal(darts_sample_bin(&gate, v3(0, 4.5, 0), 0.0, 0.3, &b), 0);
    assert_int_equal(darts_sample_bin(&fr, v3(0, 0, 12.0), 0.0, 0.3, &b), 0);
    assert_int_equal(darts_sample_bin(&fr, v3(0, 0, 30.0), 0.0, 0.0, &b), 0);
    darts_guide fr_eta = fr;
    fr_eta.eta_lb = 1.5;
    assert_int_equal(darts_sample_bin(&fr_eta, v3(0, 8, 0) /* 12 */, 0.0, 0.9, &b), 0);
    assert_int_equal(darts_sample_bin(&fr_eta, v3(0, 7.9, 0), 0.0, 0.9, &b), 1);
    printf("  gate mode: pdf 1, frame -1 on 1000 draws; unreachable lights return 0\n");
}

/* ---------------------------------------------------------------- 4. time exactness */

static void test_time_exactness(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(11, 4, 0);
    vec3 cam = v3(0.5, 1.0, -0.3);
    const double etas[3] = {1.0, 1.33, 1.5};
    long valid = 0, hits = 0, hits_mis = 0, bad = 0;
    double worst = 0.0;
    for (long i = 0; i < 200000; i++) {
        vec3 x = v3(6 * rng_uniform(&rng) - 3, 6 * rng_uniform(&rng) - 3, 6 * rng_uniform(&rng) - 3);
        double eta = etas[(int)(3 * rng_uniform(&rng)) % 3];
        double tau = 5 * rng_uniform(&rng);
        double start = 10 * rng_uniform(&rng), width = 0.05 + 3 * rng_uniform(&rng);
        darts_guide g = {.active = 1, .cam = cam, .beg = start, .end = start + width, .width = width, .frames = 0,
                         .eta_lb = 1.0};
        darts_bin b = {.start = start, .end = start + width, .pdf = 1, .frame = -1};
        residual_sampling mode = rng_uniform(&rng) < 0.5 ? RESIDUAL_UNIFORM : RESIDUAL_EXPONENTIAL;
        double sig = 0.1 + 3 * rng_uniform(&rng);
        ellipse_record r;
        ellipse_record_init(&r, &g, &b, x, tau, eta, mode, sig, rng_uniform(&rng));
        if (!r.valid) continue;
        valid++;
        vec3 d = uniform_dir(&rng);
        for (int tech = 0; tech < 2; tech++) {
            double t, pdf;
            int ok = tech == 0 ? ellipse_control_vertex(&r, d, INFINITY, &t, &pdf)
                               : control_vertex_sample(&r, d, INFINITY, mode, sig, rng_uniform(&rng),
                                                       rng_uniform(&rng), &t, &pdf);
            if (!ok) continue;
            if (tech == 0) hits++;
            else hits_mis++;
            double time = tau + eta * path_S(x, d, cam, t);
            double tol = 1e-9 * fmax(fabs(b.end), 1.0);
            double out = fmax(b.start - time, time - b.end);
            if (out > 0.0) worst = fmax(worst, out / fmax(fabs(b.end), 1.0));
            if (!(time >= b.start - tol && time <= b.end + tol) || !(t > 0.0) || !(pdf > 0.0) || !isfinite(pdf)) {
                if (bad < 5)
                    printf("  out of bin: tech %d time %.17g bin [%.17g, %.17g] t %g pdf %g\n", tech, time, b.start,
                           b.end, t, pdf);
                bad++;
            }
            /* plain technique: S(t) = T exactly */
            if (tech == 0 && fabs(path_S(x, d, cam, t) - r.T) > 1e-9 * r.T) bad++;
        }
    }
    printf("  valid records %ld, control vertices %ld (plain) + %ld (MIS), out of bin %ld, worst rel. excess %.3g\n",
           valid, hits, hits_mis, bad, worst);
    assert_true(valid > 20000 && hits > 10000 && hits_mis > 10000);
    assert_int_equal(bad, 0);
}

/* ---------------------------------------------------------------- 5. darts_can_reach */

static void test_can_reach(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(13, 5, 0);
    long mism = 0, yes = 0;
    for (long i = 0; i < 100000; i++) {
        vec3 cam = v3(4 * rng_uniform(&rng) - 2, 4 * rng_uniform(&rng) - 2, 4 * rng_uniform(&rng) - 2);
        vec3 x = v3(8 * rng_uniform(&rng) - 4, 8 * rng_uniform(&rng) - 4, 8 * rng_uniform(&rng) - 4);
        double eta_lb = 1.0 + 0.6 * rng_uniform(&rng), tau = 6 * rng_uniform(&rng);
        double start = 10 * rng_uniform(&rng), end = start + 0.01 + 4 * rng_uniform(&rng);
        darts_guide g = {.active = 1, .cam = cam, .beg = start, .end = end, .width = end - start, .eta_lb = eta_lb};
        darts_bin b = {.start = start, .end = end, .pdf = 1, .frame = -1};
        double dx = cam.x - x.x, dy = cam.y - x.y, dz = cam.z - x.z;
        int expect = tau + eta_lb * sqrt(dx * dx + dy * dy + dz * dz) < end;
        yes += expect;
        if (darts_can_reach(&g, &b, x, tau) != expect) mism++;
    }
    printf("  random: %ld mismatches of 100000 (%ld reachable)\n", mism, yes);
    assert_int_equal(mism, 0);
    assert_true(yes > 10000 && yes < 90000);

    /* edges: |cam − x| = 5 exactly */
    darts_guide g = {.active = 1, .cam = v3(0, 0, 0), .beg = 0, .end = 6, .width = 6, .eta_lb = 1.0};
    darts_bin b = {.start = 0, .end = 6, .pdf = 1, .frame = -1};
    assert_int_equal(darts_can_reach(&g, &b, v3(3, 4, 0), 1.0), 0);              /* 1 + 5 = 6: equal → 0 */
    b.end = nextafter(6.0, 7.0);
    assert_int_equal(darts_can_reach(&g, &b, v3(3, 4, 0), 1.0), 1);              /* just above */
    g.eta_lb = 1.5;
    b.end = 8.0;
    assert_int_equal(darts_can_reach(&g, &b, v3(3, 4, 0), 0.5), 0);              /* 0.5 + 7.5 = 8: equal → 0 */
    assert_int_equal(darts_can_reach(&g, &b, v3(3, 4, 0), 0.5 - 1e-12), 1);       /* just below */
    assert_int_equal(darts_can_reach(&g, &b, v3(0, 0, 0), 7.9), 1);              /* at the camera */
    assert_int_equal(darts_can_reach(&g, &b, v3(0, 0, 0), 8.0), 0);
}

/* ---------------------------------------------------------------- 6. extreme parameters */

/* The stress matrix of the numerical-stability issue at estimator level: σs from 1e-4 to 1e3 per unit length
 * with the camera 1 away (1e-4 to 1e3 mean free paths), albedo 0.9 and 0.01, Henyey–Greenstein g from −0.99
 * to 0.99 (the diffusion coefficient spans 200×), gates of width 1e-6, ordinary gates, and gates 3000 mean
 * free paths into the tail (where Φ underflows by e^{−3000}); finite and infinite tmax. Every case checks the
 * same quadrature and the same invariants as sections 1 and 2 (weights finite and >= 0, fallbacks only where
 * nothing is reachable). A fast subset runs by default; DARTSPP_STRESS=full (make stress) runs all of it. */
typedef struct {
    const char *name;
    double start, end; /* for C = 1, τ = 0, with st the mean extinction */
} stress_window;

static stress_window window_of(int which, double st)
{
    switch (which) {
    case 0: return (stress_window){"gate [1.2, 1.5]", 1.2, 1.5};
    case 1: return (stress_window){"gate width 1e-6", 1.3, 1.3 + 1e-6};
    default: return (stress_window){"gate 3000 mfp into the tail", 1.0 + 3000.0 / st, 1.0 + 3000.5 / st};
    }
}

static int run_da_stress(double ss, double albedo, double g, int window, int finite_tmax, long n, uint64_t seed)
{
    double sa = ss * (1.0 - albedo) / albedo, st = ss + sa;
    stress_window w = window_of(window, st);
    phase_function ph = {g == 0.0 ? PHASE_ISOTROPIC : PHASE_HENYEY_GREENSTEIN, g, NULL};
    char name[160];
    snprintf(name, sizeof name, "sigma_s %g, albedo %g, g %+.2f, %s, tmax %s", ss, albedo, g, w.name,
             finite_tmax ? "0.7 mfp" : "inf");
    da_case k = {name, 1.0, 0.3, w.start, w.end, 0.0, 1.0, 1.0, v3s(ss), v3s(sa), ph,
                 finite_tmax ? 0.7 / st : INF, RESIDUAL_EXPONENTIAL, st, 1.3 * st, 0, n};
    return run_da_case(&k, 0, 0.2, seed) + run_da_case(&k, 1, 0.2, seed + 1);
}

static void test_da_extreme(void **state)
{
    (void)state;
    int fail = 0;
    uint64_t seed = 5000;
    if (stress_full()) {
        const double sigmas[] = {1e-4, 1e-2, 1.0, 1e2, 1e3}, albedos[] = {0.9, 0.01}, gs[] = {-0.99, 0.0, 0.99};
        for (int i = 0; i < 5; i++)
            for (int a = 0; a < 2; a++)
                for (int j = 0; j < 3; j++)
                    for (int wdw = 0; wdw < 3; wdw++)
                        for (int tm = 0; tm < 2; tm++, seed += 2)
                            fail += run_da_stress(sigmas[i], albedos[a], gs[j], wdw, tm, 100000, seed);
    } else {
        fail += run_da_stress(1e-4, 0.9, 0.99, 0, 0, 100000, seed);
        fail += run_da_stress(1e3, 0.9, -0.99, 0, 1, 100000, seed + 2);
        fail += run_da_stress(1e3, 0.01, 0.0, 2, 0, 100000, seed + 4);
        fail += run_da_stress(1.0, 0.01, 0.99, 1, 0, 100000, seed + 6);
        fail += run_da_stress(1e-2, 0.9, 0.0, 2, 1, 100000, seed + 8);
    }
    assert_int_equal(fail, 0);
}

static int run_cv_stress(double ss, double albedo, double cos_t, int window, int finite_tmax, int mis, long n,
                         uint64_t seed)
{
    double st = ss / albedo;
    stress_window w = window_of(window, st);
    if (window == 3) w = (stress_window){"T = C (1 + 1e-6) degenerate", 0.5, 1.0 + 1e-6};
    int fail = 0;
    for (int mode = 0; mode < 2; mode++) {
        char name[160];
        snprintf(name, sizeof name, "%ssigma_s %g, albedo %g, cos %g, %s, tmax %s, %s", mis ? "MIS: " : "", ss, albedo,
                 cos_t, w.name, finite_tmax ? "0.7 mfp" : "inf", mode ? "exponential" : "uniform");
        cv_case k = {name, 1.0, cos_t, w.start, w.end, 0.0, 1.0, ss, st, finite_tmax ? 0.7 / st : INF,
                     mode ? RESIDUAL_EXPONENTIAL : RESIDUAL_UNIFORM, st, mis, n};
        fail += run_cv_case(&k, seed + mode);
    }
    return fail;
}

static void test_control_vertex_extreme(void **state)
{
    (void)state;
    int fail = 0;
    uint64_t seed = 7000;
    if (stress_full()) {
        const double sigmas[] = {1e-4, 1e-2, 1.0, 1e2, 1e3}, albedos[] = {0.9, 0.01}, coss[] = {-0.9, 0.3, 0.9999};
        for (int i = 0; i < 5; i++)
            for (int a = 0; a < 2; a++)
                for (int c = 0; c < 3; c++)
                    for (int wdw = 0; wdw < 4; wdw++)
                        for (int tm = 0; tm < 2; tm++, seed += 4)
                            fail += run_cv_stress(sigmas[i], albedos[a], coss[c], wdw, tm, 1, 100000, seed) +
                                    run_cv_stress(sigmas[i], albedos[a], coss[c], wdw, tm, 0, 100000, seed + 2);
    } else {
        fail += run_cv_stress(1e-4, 0.9, 0.3, 1, 0, 1, 100000, seed);
        fail += run_cv_stress(1e3, 0.01, -0.9, 0, 1, 1, 100000, seed + 4);
        fail += run_cv_stress(1.0, 0.9, 0.9999, 3, 0, 1, 100000, seed + 8);
        fail += run_cv_stress(1.0, 0.9, 0.9999, 3, 0, 0, 100000, seed + 12);
        fail += run_cv_stress(1e2, 0.9, 0.3, 2, 0, 1, 100000, seed + 16);
    }
    assert_int_equal(fail, 0);
}

/* Two programs from this file: test_darts (quick tier, and the extreme cases under DARTSPP_STRESS=full) and
 * test_darts_distance (tests/darts/test_darts_distance.c, `make test`), which includes this file with
 * DARTS_DISTANCE for the DA distance cases beyond test_da_normal: infinite t_max, coloured σ, barely reachable,
 * a thick medium, refractive index. */
int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    const struct CMUnitTest tests[] = {
#ifndef DARTS_DISTANCE
        cmocka_unit_test(test_control_vertex_reference_case),
        cmocka_unit_test(test_control_vertex_cases),
        cmocka_unit_test(test_control_vertex_mis),
        cmocka_unit_test(test_sphere_control_vertex),
        cmocka_unit_test(test_da_normal),
        cmocka_unit_test(test_bins_frames),
        cmocka_unit_test(test_bins_gate_and_unreachable),
        cmocka_unit_test(test_time_exactness),
        cmocka_unit_test(test_can_reach),
        cmocka_unit_test(test_da_extreme),
        cmocka_unit_test(test_control_vertex_extreme),
#else
        cmocka_unit_test(test_da_infinite_tmax),
        cmocka_unit_test(test_da_coloured),
        cmocka_unit_test(test_da_barely_reachable),
        cmocka_unit_test(test_da_thick),
        cmocka_unit_test(test_da_refractive),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
