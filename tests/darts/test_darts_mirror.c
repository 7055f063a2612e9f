/* tier: stress */
/* DARTS behind mirrors and glossy surfaces (darts_mirrors, issue 18).
 *
 * 1. test_cv_techniques_chi2: the multi-focus control-vertex sampler (cv_techniques_sample: the straight
 *    focus, a mirror focus, the defensive free flight) against its own density cv_techniques_pdf, by χ² on a
 *    histogram of t (the density integrated per bin by the midpoint rule, the "no photon" outcome as one more
 *    bin), for several directions and segment ends; and control_vertex_pdf against control_vertex_sample
 *    (mis 1) and ellipse_control_vertex (mis 0). Sampling (inverse CDFs) and density (closed forms) are
 *    separate code. Bonferroni threshold 1e-3 over the cases.
 * 2. test_bit_identical_without_mirrors: on the demo fog box (no continued surface) darts_mirrors "full"
 *    and "straight" give the same film bits.
 * 3. test_mirror_agrees_with_baseline: the demo fog box with its back wall a mirror, and with it rough silver
 *    (GGX α 0.1, continued by camera paths), 16² with 4 × 4 tiles, a wider gate (0.5) and constant radii
 *    (alpha = volume_alpha = 1: the kernel bias is then the same for every photon sampler, and with
 *    gather_photon_count 256 the surface disc is R itself, not a density-dependent k-NN radius). DARTS
 *    (enable_guiding, enable_elliptical, strict on) against baseline photon points: per-tile z-scores from the
 *    spread of per-pass tile totals, |z| < 4.0 (Bonferroni over 16 tiles × 2 walls at p ≈ 0.002) for
 *    darts_mirrors "full"; the same check must FAIL for "straight" (the authors' behaviour), which is what
 *    shows it can. */
#include "fixtures.h"

#include "dartspp/darts.h"
#include "dartspp/plan.h"
#include "dartspp/render.h"

#define NBINS 40
#define NSAMPLES 200000
#define P_MIN 1e-3

typedef double (*pdf_fn)(void *ctx, double t);
typedef int (*sample_fn)(void *ctx, const double u[3], double *t);

/* χ² of NSAMPLES draws against the density integrated over NBINS bins of [0, t_hi) plus the miss bin; bins
 * with expected count < 5 are pooled. Returns the p-value and checks the density's mass equals the hit share. */
static double chi2_case(const char *label, pdf_fn pdf, sample_fn sample, void *ctx, double t_hi, uint64_t seed)
{
    double expect[NBINS + 1] = {0}, count[NBINS + 1] = {0}, mass = 0.0;
    double w = t_hi / NBINS;
    for (int b = 0; b < NBINS; b++) { /* midpoint rule, 2048 points per bin: the density jumps inside bins */
        double s = 0.0, h = w / 2048;
        for (int k = 0; k < 2048; k++) s += pdf(ctx, b * w + (k + 0.5) * h);
        expect[b] = s * h;
        mass += expect[b];
    }
    expect[NBINS] = fmax(0.0, 1.0 - mass);
    dp_rng rng = rng_stream(seed, 0, 0);
    long hits = 0;
    for (long i = 0; i < NSAMPLES; i++) {
        double u[3] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)}, t;
        if (sample(ctx, u, &t)) {
            int b = (int)(t / w);
            if (b >= NBINS || b < 0) fail_msg("%s: sample t = %g outside [0, %g)", label, t, t_hi);
            count[b]++;
            hits++;
        } else {
            count[NBINS]++;
        }
    }
    double share = (double)hits / NSAMPLES, se = sqrt(share * (1 - share) / NSAMPLES) + 1e-12;
    if (fabs(mass - share) > 5 * se + 2e-4)
        fail_msg("%s: the density integrates to %.5f over [0, %g), the sampler hits %.5f of the time", label, mass,
                 t_hi, share);
    double chi2 = 0.0, pe = 0.0, pc = 0.0;
    int dof = -1;
    for (int b = 0; b <= NBINS; b++) {
        pe += expect[b] * NSAMPLES;
        pc += count[b];
        if (pe >= 5.0 || b == NBINS) {
            if (pe > 0.0) chi2 += (pc - pe) * (pc - pe) / pe, dof++;
            else if (pc > 0.0) fail_msg("%s: %g samples where the density is 0", label, pc);
            pe = pc = 0.0;
        }
    }
    double p = dof > 0 ? test_gamma_q(0.5 * dof, 0.5 * chi2) : 1.0;
    printf("chi2 %-44s mass %.4f  chi2 %.1f dof %d  p %.3g\n", label, mass, chi2, dof, p);
    return p;
}

/* The records' residual T is drawn once per vertex (ellipse_record_init); the densities are marginal over
 * it, so every sample re-draws the records' residuals from the case's own stream. */
typedef struct {
    cv_techniques ct;
    darts_guide g[2];  /* the camera, the mirror focus */
    darts_bin bin;
    vec3 x, d;
    double tmax, sigma;
    int mis;
    dp_rng rng;
} cv_case;

static void redraw(cv_case *k)
{
    for (int i = 0; i < 2; i++)
        ellipse_record_init(&k->ct.rec[i], &k->g[i], &k->bin, k->x, 0.5, 1.0, RESIDUAL_UNIFORM, k->sigma,
                            rng_uniform(&k->rng));
}

static double cv_pdf(void *c, double t)
{
    cv_case *k = c;
    return cv_techniques_pdf(&k->ct, k->d, k->tmax, k->mis, RESIDUAL_UNIFORM, k->sigma, t);
}

static int cv_sample(void *c, const double u[3], double *t)
{
    cv_case *k = c;
    double pdf;
    redraw(k);
    return cv_techniques_sample(&k->ct, k->d, k->tmax, k->mis, RESIDUAL_UNIFORM, k->sigma, u, t, &pdf);
}

static double one_pdf(void *c, double t)
{
    cv_case *k = c;
    return control_vertex_pdf(&k->ct.rec[0], k->d, t, k->mis, RESIDUAL_UNIFORM, k->sigma);
}

static int one_sample(void *c, const double u[3], double *t)
{
    cv_case *k = c;
    double pdf;
    redraw(k);
    return k->mis ? control_vertex_sample(&k->ct.rec[0], k->d, k->tmax, RESIDUAL_UNIFORM, k->sigma, u[0], u[1], t, &pdf)
                  : ellipse_control_vertex(&k->ct.rec[0], k->d, k->tmax, t, &pdf);
}

static void test_cv_techniques_chi2(void **state)
{
    (void)state;
    vec3 cam = v3(0, 0, 4), focus = v3(0, 0, -6), x = v3(0.3, 0.2, 0);
    darts_guide g = {.active = 1, .cam = cam, .beg = 7.0, .end = 9.0, .width = 2.0, .eta_lb = 1.0, .eta_ub = 1.0};
    darts_bin bin = {.start = 7.0, .end = 9.0, .pdf = 1.0, .frame = -1};
    const vec3 dirs[3] = {v3(0, 0, 1), v3_norm(v3(1, 0.5, -0.7)), v3_norm(v3(-0.2, 1, 0.1))};
    const double tmaxes[2] = {INFINITY, 2.5};
    double pmin = 1.0;
    uint64_t seed = 1;
    for (int di = 0; di < 3; di++)
        for (int ti = 0; ti < 2; ti++)
            for (int mis = 0; mis < 2; mis++) {
                cv_case k = {.d = dirs[di], .tmax = tmaxes[ti], .sigma = 0.7, .mis = mis, .bin = bin, .x = x,
                             .g = {g, g}, .rng = rng_stream(seed, 1, 0)};
                k.g[1].cam = focus;
                redraw(&k);
                assert_true(k.ct.rec[0].valid && k.ct.rec[1].valid);
                k.ct.n = 2;
                k.ct.share[0] = 0.6, k.ct.share[1] = 0.3, k.ct.defensive = 0.1;
                double t_hi = fmin(k.tmax, 9.0); /* beyond the reachable set (S_reach = 8.5) nothing lands */
                char label[96];
                snprintf(label, sizeof label, "cv_techniques d%d tmax %g mis %d", di, k.tmax, mis);
                pmin = fmin(pmin, chi2_case(label, cv_pdf, cv_sample, &k, t_hi, seed++));
                snprintf(label, sizeof label, "control_vertex d%d tmax %g mis %d", di, k.tmax, mis);
                pmin = fmin(pmin, chi2_case(label, one_pdf, one_sample, &k, t_hi, seed++));
            }
    printf("chi2 smallest p %.3g (threshold %g)\n", pmin, P_MIN);
    if (pmin < P_MIN) fail_msg("a sampler disagrees with its density: smallest p %.3g < %g", pmin, P_MIN);
}

/* ---------------------------------------------------------------------------------------------------- */
/* renders of the demo fog box                                                                          */

#define TILES 4
#define NT (TILES * TILES)
#define RES 16

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *t = malloc((size_t)n + 1);
    assert_non_null(t);
    assert_int_equal(fread(t, 1, (size_t)n, f), (size_t)n);
    t[n] = 0;
    fclose(f);
    return t;
}

/* The demo scene with the back wall's bsdf replaced by `wall` (NULL: unchanged), loaded with `sets`. */
static void demo_scene(const char *wall, const char *const *sets, int nsets, scene *s, char **dir_out)
{
    char *text = read_text("scenes/fogbox/fogbox.json");
    if (!text) fail_msg("scenes/fogbox/fogbox.json: cannot read it (run from the repository root)");
    char *out = malloc(strlen(text) + 512);
    assert_non_null(out);
    char *back = strstr(text, "\"name\": \"back\"");
    char *white = back ? strstr(back, "\"bsdf\": \"white\"") : NULL;
    if (wall && !white) fail_msg("fogbox.json: no back wall with bsdf \"white\"");
    if (wall) {
        size_t head = (size_t)(white - text);
        memcpy(out, text, head);
        sprintf(out + head, "\"bsdf\": %s%s", wall, white + strlen("\"bsdf\": \"white\""));
    } else {
        strcpy(out, text);
    }
    char *dir = test_tmpdir();
    assert_non_null(dir);
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, out);
    free(text);
    free(out);
    dp_error err;
    scene_load_options lo = {.sets = sets, .set_count = nsets};
    if (scene_load(path, &lo, s, &err)) fail_msg("%s", err.msg);
    *dir_out = dir;
}

static void test_bit_identical_without_mirrors(void **state)
{
    (void)state;
    const char *common[] = {"resolution=16", "photon_count=20000", "volume_photon_count=16000", "enable_guiding=true",
                            "enable_elliptical=true", "strict_time_width=true", NULL};
    double *sums[2] = {NULL, NULL};
    size_t n = 0;
    for (int m = 0; m < 2; m++) {
        const char *sets[8];
        int k = 0;
        for (; common[k]; k++) sets[k] = common[k];
        sets[k++] = m ? "darts_mirrors=straight" : "darts_mirrors=full";
        scene s;
        char *dir;
        demo_scene(NULL, sets, k, &s, &dir);
        render_options ro = {.threads = 2, .seed = 5, .spp = 2};
        film f;
        render_stats st;
        dp_error err;
        if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
        n = (size_t)f.width * f.height * 3;
        sums[m] = malloc(n * sizeof(double));
        memcpy(sums[m], f.sum, n * sizeof(double));
        film_free(&f);
        scene_free(&s);
        test_rmtree(dir);
    }
    double total = 0.0;
    for (size_t i = 0; i < n; i++) total += sums[0][i];
    assert_true(total > 0.0);
    assert_memory_equal(sums[0], sums[1], n * sizeof(double));
    free(sums[0]);
    free(sums[1]);
}

typedef struct {
    long n, cap;
    double *x;        /* per pass: NT tile totals */
    double last[NT];
} tile_totals;

static int tile_probe(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    (void)err;
    tile_totals *t = ctx;
    if (st->passes == 1) memset(t->last, 0, sizeof t->last);
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 256;
        t->x = realloc(t->x, (size_t)t->cap * NT * sizeof(double));
        assert_non_null(t->x);
    }
    double v[NT] = {0};
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++)
            for (int c = 0; c < 3; c++)
                v[(y * TILES / f->height) * TILES + x * TILES / f->width] += f->sum[3 * ((size_t)y * f->width + x) + c];
    for (int i = 0; i < NT; i++) {
        t->x[(size_t)t->n * NT + i] = (v[i] - t->last[i]) / f->last_weight; /* this pass's estimate */
        t->last[i] = v[i];
    }
    t->n++;
    return 0;
}

static void mean_se(const tile_totals *t, int v, double *mean, double *se)
{
    double s = 0, s2 = 0;
    for (long i = 0; i < t->n; i++) {
        double x = t->x[(size_t)i * NT + v];
        s += x;
        s2 += x * x;
    }
    *mean = s / t->n;
    *se = sqrt(fmax(0.0, (s2 - t->n * *mean * *mean) / (t->n - 1)) / t->n);
}

static void render_totals(const char *wall, const char *method, long passes, uint64_t seed, tile_totals *t)
{
    const char *sets[12] = {"resolution=16", "photon_count=20000", "volume_photon_count=16000",
                            "transient_time_width=0.5", "alpha=1", "volume_alpha=1", "gather_photon_count=256",
                            "gather_radius=0.08", "volume_gather_radius=0.08"};
    int k = 9;
    if (!strcmp(method, "baseline")) sets[k++] = "enable_guiding=false", sets[k++] = "enable_elliptical=false";
    else {
        sets[k++] = "enable_guiding=true", sets[k++] = "enable_elliptical=true";
        sets[k++] = !strcmp(method, "full") ? "darts_mirrors=full" : "darts_mirrors=straight";
    }
    scene s;
    char *dir;
    demo_scene(wall, sets, k, &s, &dir);
    render_options ro = {.threads = 2, .seed = seed, .spp = passes, .after_pass = tile_probe, .after_pass_ctx = t};
    film f;
    render_stats st;
    dp_error err;
    if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.nonfinite, 0);
    film_free(&f);
    scene_free(&s);
    test_rmtree(dir);
}

#define Z_CRIT 4.0

/* Largest |z| of DARTS (method) against baseline over the tiles; prints every tile's ratio and z. */
static double max_z(const char *label, const tile_totals *d, const tile_totals *b)
{
    double worst = 0.0;
    printf("%s:", label);
    for (int i = 0; i < NT; i++) {
        double md, sd, mb, sb;
        mean_se(d, i, &md, &sd);
        mean_se(b, i, &mb, &sb);
        double z = (md - mb) / sqrt(sd * sd + sb * sb + 1e-300);
        printf(" %.3f(%+.1f)", mb > 0 ? md / mb : 0.0, z);
        worst = fmax(worst, fabs(z));
    }
    printf("  max |z| %.2f\n", worst);
    return worst;
}

static void wall_case(const char *wall, const char *name, long base_passes, long darts_passes)
{
    tile_totals base = {0}, full = {0}, straight = {0};
    render_totals(wall, "baseline", base_passes, 101, &base);
    render_totals(wall, "full", darts_passes, 202, &full);
    render_totals(wall, "straight", darts_passes, 303, &straight);
    char label[128];
    snprintf(label, sizeof label, "%s, full ÷ baseline per tile (z)", name);
    double zf = max_z(label, &full, &base);
    snprintf(label, sizeof label, "%s, straight ÷ baseline per tile (z)", name);
    double zs = max_z(label, &straight, &base);
    free(base.x), free(full.x), free(straight.x);
    if (zf >= Z_CRIT) fail_msg("%s: darts_mirrors full disagrees with baseline photon points: max |z| %.2f", name, zf);
    if (zs < Z_CRIT)
        fail_msg("%s: the check did not detect the straight camera leg's bias (max |z| %.2f < %.1f)", name, zs, Z_CRIT);
}

static void test_mirror_agrees_with_baseline(void **state)
{
    (void)state;
    wall_case("{ \"type\": \"mirror\" }", "mirror wall", 96, 32);
}

static void test_glossy_agrees_with_baseline(void **state)
{
    (void)state;
    wall_case("{ \"type\": \"rough_conductor\", \"material\": \"Ag\", \"distribution\": \"ggx\", \"roughness\": 0.1 }",
              "rough silver wall", 96, 32);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cv_techniques_chi2),
        cmocka_unit_test(test_bit_identical_without_mirrors),
        cmocka_unit_test(test_mirror_agrees_with_baseline),
    };
    /* the long statistical cases: `make stress` (tests/README.md) */
    const struct CMUnitTest stress_tests[] = {
        cmocka_unit_test(test_glossy_agrees_with_baseline),
    };
    return RUN_TESTS_AND_STRESS(tests, stress_tests);
}
