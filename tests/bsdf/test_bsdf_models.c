/* tier: quick */
/* BSDF models against closed forms (src/bsdf): Fresnel terms at normal incidence, Brewster's angle and
 * under total internal reflection, the hemispherical Fresnel averages, microfacet normalisation and Smith
 * masking by quadrature, the named metals, the reference's defaults, the checks of bsdf_prepare, and the
 * delta lobes' outcomes. Sampling-against-pdf, furnace and reciprocity tests over the public API are in
 * tests/bsdf/test_bsdf.c. */
#include "test_util.h"

#include "dartspp/bsdf.h"


static bsdf prepared(bsdf_type t)
{
    bsdf b;
    bsdf_defaults(&b, t);
    snprintf(b.name, sizeof b.name, "test_%s", bsdf_type_name(t));
    dp_error err;
    if (bsdf_prepare(&b, &err)) fail_msg("%s", err.msg);
    return b;
}

static vec3 dir(double theta, double phi) { return v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)); }

/* Conductor at normal incidence: ((n−1)² + k²) / ((n+1)² + k²); at grazing incidence 1; with k = 0 the
 * dielectric Fresnel term of the same index at every angle. */
static void test_conductor_fresnel(void **state)
{
    (void)state;
    const double nk[][2] = {{0.2, 3.9}, {1.5, 0.0}, {0.14, 3.98}, {2.87, 3.03}, {1.0, 0.5}};
    for (size_t i = 0; i < sizeof nk / sizeof nk[0]; i++) {
        double n = nk[i][0], k = nk[i][1];
        double r0 = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
        ASSERT_NEAR(bsdf_fresnel_conductor(n, k, 1.0), r0, 1e-12);
        ASSERT_NEAR(bsdf_fresnel_conductor(n, k, 0.0), 1.0, 1e-12);
    }
    for (double c = 0.05; c <= 1.0; c += 0.05)
        ASSERT_NEAR(bsdf_fresnel_conductor(1.7, 0.0, c), bsdf_fresnel_dielectric(1.7, c, NULL), 1e-12);
    vec3 f = bsdf_fresnel_conductor3(v3(0.2, 1.0, 2.0), v3(3.0, 2.0, 1.0), 1.0);
    ASSERT_NEAR(f.y, 4.0 / 8.0, 1e-12);
}

/* Dielectric: ((η−1)/(η+1))² at normal incidence from either side, r_p = 0 at Brewster's angle
 * tan θB = η, Snell's law for cos θt, and total internal reflection beyond the critical angle. */
static void test_dielectric_fresnel(void **state)
{
    (void)state;
    double eta = 1.5, r0 = (eta - 1) * (eta - 1) / ((eta + 1) * (eta + 1)), ct;
    ASSERT_NEAR(bsdf_fresnel_dielectric(eta, 1.0, &ct), r0, 1e-14);
    ASSERT_NEAR(ct, 1.0, 1e-14);
    ASSERT_NEAR(bsdf_fresnel_dielectric(eta, -1.0, NULL), r0, 1e-14);
    ASSERT_NEAR(bsdf_fresnel_dielectric(1.0 / eta, 1.0, NULL), r0, 1e-14);
    ASSERT_NEAR(bsdf_fresnel_dielectric(1.0, 0.3, NULL), 0.0, 1e-14);
    /* Brewster: F = r_s² / 2 with r_s = (cos θi − η cos θt) / (cos θi + η cos θt) */
    double tb = atan(eta), ci = cos(tb);
    double F = bsdf_fresnel_dielectric(eta, ci, &ct);
    ASSERT_NEAR(sin(tb), eta * sqrt(1 - ct * ct), 1e-12);
    double rs = (ci - eta * ct) / (ci + eta * ct);
    ASSERT_NEAR(F, 0.5 * rs * rs, 1e-12);
    /* from inside (cos θi < 0): critical angle sin θc = 1/η */
    double tc = asin(1.0 / eta);
    ASSERT_NEAR(bsdf_fresnel_dielectric(eta, -cos(tc + 1e-3), &ct), 1.0, 0.0);
    ASSERT_NEAR(ct, 0.0, 0.0);
    assert_true(bsdf_fresnel_dielectric(eta, -cos(tc - 1e-3), NULL) < 1.0);
    ASSERT_NEAR(bsdf_fresnel_dielectric(1.0 / eta, cos(tc + 1e-3), NULL), 1.0, 0.0);
    ASSERT_NEAR(bsdf_fresnel_dielectric(eta, 0.0, NULL), 1.0, 1e-12);
}

/* Hemispherical averages: 0 for a matched boundary, ≈ 0.0918 outside glass of 1.5 (2∫F μ dμ, a classic
 * value), and inside = 1 − (1 − outside)/η² (reciprocity: what enters from the outside hemisphere leaves
 * through the inside one). */
static void test_fresnel_average(void **state)
{
    (void)state;
    ASSERT_NEAR(bsdf_fresnel_average(1.0), 0.0, 1e-12);
    for (double eta = 1.1; eta < 3.0; eta += 0.4) {
        double out = bsdf_fresnel_average(eta), in = bsdf_fresnel_average(1.0 / eta);
        ASSERT_NEAR(in, 1.0 - (1.0 - out) / (eta * eta), 1e-6);
    }
    ASSERT_NEAR(bsdf_fresnel_average(1.5), 0.0918, 5e-4);
    bsdf p = prepared(BSDF_PLASTIC);
    ASSERT_NEAR(p.diffuse_fresnel, bsdf_fresnel_average(1.0 / 1.5), 1e-15);
    ASSERT_NEAR(p.diffuse_fresnel, 0.5963, 5e-4);
}

/* ∫ over microfacet normals of g(m) dω_m, by composite Gauss–Legendre in s with tan θ = α s/(1−s). */
typedef double (*normal_fn)(vec3 m, void *ctx);
static double integrate_normals(double alpha, normal_fn g, void *ctx, int nphi)
{
    enum { PANELS = 48, NODES = 16 };
    double x[NODES], w[NODES];
    gauss_legendre(NODES, x, w);
    double sum = 0.0;
    for (int p = 0; p < PANELS; p++) {
        for (int i = 0; i < NODES; i++) {
            double s = (p + 0.5 * (x[i] + 1.0)) / PANELS, ws = 0.5 * w[i] / PANELS;
            double t = alpha * s / (1.0 - s);               /* tan θ */
            double dtheta = alpha / ((1.0 - s) * (1.0 - s)) / (1.0 + t * t);
            double theta = atan(t);
            double ring = 0.0;
            for (int j = 0; j < nphi; j++) ring += g(dir(theta, 2.0 * M_PI * (j + 0.5) / nphi), ctx);
            sum += ws * dtheta * sin(theta) * ring * 2.0 * M_PI / nphi;
        }
    }
    return sum;
}

typedef struct {
    microfacet_distribution d;
    double alpha;
    vec3 v;
    double tan2_max;
} mf_ctx;

static double projected_D(vec3 m, void *ctx)
{
    mf_ctx *c = ctx;
    double t2 = (1.0 - m.z * m.z) / (m.z * m.z);
    return t2 <= c->tan2_max ? bsdf_mf_D(c->d, c->alpha, m) * m.z : 0.0;
}

static double visible_D(vec3 m, void *ctx)
{
    mf_ctx *c = ctx;
    return bsdf_mf_G1(c->d, c->alpha, c->v, m) * fmax(v3_dot(c->v, m), 0.0) * bsdf_mf_D(c->d, c->alpha, m);
}

/* ∫ D(m) cos θm dω_m = 1, and the share below tan² θ = α² is the sampler's CDF there: 1/2 for GGX
 * (P = T/(α²+T)), 1 − 1/e for Beckmann (P = 1 − exp(−T/α²)). */
static void test_microfacet_normalised(void **state)
{
    (void)state;
    const microfacet_distribution ds[] = {MICROFACET_GGX, MICROFACET_PBRT_GGX, MICROFACET_BECKMANN};
    const double alphas[] = {0.01, 0.1, 0.3, 0.7, 1.0};
    for (int di = 0; di < 3; di++) {
        for (int ai = 0; ai < 5; ai++) {
            mf_ctx c = {ds[di], alphas[ai], v3(0, 0, 1), INFINITY};
            ASSERT_NEAR(integrate_normals(c.alpha, projected_D, &c, 1), 1.0, 1e-6);
            c.tan2_max = c.alpha * c.alpha;
            double cdf = ds[di] == MICROFACET_BECKMANN ? 1.0 - exp(-1.0) : 0.5;
            ASSERT_NEAR(integrate_normals(c.alpha, projected_D, &c, 1), cdf, 1e-3);
            /* the sampler's inverse CDF at u: tan² θ = α² u/(1−u) (GGX), −α² ln(1−u) (Beckmann) */
            vec3 m = bsdf_mf_sample(ds[di], c.alpha, cdf, 0.3);
            ASSERT_NEAR((1.0 - m.z * m.z) / (m.z * m.z), c.alpha * c.alpha, 1e-9 * (1.0 + c.alpha * c.alpha));
            ASSERT_NEAR(bsdf_mf_pdf(ds[di], c.alpha, m), bsdf_mf_D(ds[di], c.alpha, m) * m.z, 1e-12);
        }
    }
}

/* Smith masking: ∫ G1(v, m) ⟨v·m⟩ D(m) dω_m = cos θv (the projected area of the microsurface equals that of
 * the macrosurface); exact for GGX, within the rational fit's error for Beckmann (Walter eq. 27). Also
 * G1 = 1 at normal view, and the height-correlated G of pbrt-ggx is at least the separable product. */
static void test_smith_masking(void **state)
{
    (void)state;
    const double alphas[] = {0.1, 0.4, 0.9};
    const double thetas[] = {0.0, 0.6, 1.2, 1.45};
    for (int ai = 0; ai < 3; ai++) {
        for (int ti = 0; ti < 4; ti++) {
            vec3 v = dir(thetas[ti], 0.4);
            mf_ctx g = {MICROFACET_GGX, alphas[ai], v, INFINITY};
            ASSERT_NEAR(integrate_normals(g.alpha, visible_D, &g, 256), v.z, 2e-4);
            mf_ctx bk = {MICROFACET_BECKMANN, alphas[ai], v, INFINITY};
            ASSERT_NEAR(integrate_normals(bk.alpha, visible_D, &bk, 256), v.z, 6e-3 * fmax(v.z, 0.2));
        }
    }
    vec3 n = v3(0, 0, 1);
    ASSERT_NEAR(bsdf_mf_G1(MICROFACET_GGX, 0.5, n, n), 1.0, 0.0);
    ASSERT_NEAR(bsdf_mf_G1(MICROFACET_BECKMANN, 0.5, n, n), 1.0, 0.0);
    vec3 wi = dir(1.1, 0.0), wo = dir(0.7, M_PI), h = v3_norm(v3_add(wi, wo));
    double a = 0.4;
    double sep = bsdf_mf_G(MICROFACET_GGX, a, wi, wo, h);
    double cor = bsdf_mf_G(MICROFACET_PBRT_GGX, a, wi, wo, h);
    double li = 1.0 / bsdf_mf_G1(MICROFACET_GGX, a, wi, h) - 1.0, lo = 1.0 / bsdf_mf_G1(MICROFACET_GGX, a, wo, h) - 1.0;
    ASSERT_NEAR(cor, 1.0 / (1.0 + li + lo), 1e-12);
    assert_true(cor >= sep);
    /* a normal facing away from the direction masks it */
    assert_true(bsdf_mf_G1(MICROFACET_GGX, a, v3_norm(v3(1, 0, 0.2)), v3_norm(v3(-1, 0, 0.3))) == 0.0);
}

/* Named metals: the table's values, the default Cu, the names the reference accepts, Au redder than blue,
 * unknown names refused. */
static void test_conductor_presets(void **state)
{
    (void)state;
    const char *names[] = {"Ag", "Au", "Al", "Cu", "Cr", "Li", "VN", "W", "Ni", "TiN", "a-C", "Hg"};
    vec3 eta, k;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        assert_true(bsdf_conductor_preset(names[i], &eta, &k));
        assert_true(v3_is_finite(eta) && v3_is_finite(k));
    }
    assert_true(bsdf_conductor_preset("Au", &eta, &k));
    ASSERT_VEC(eta, 0.1431189557, 0.3749570432, 1.4424785571, 1e-9);
    ASSERT_VEC(k, 3.9831604247, 2.3857207478, 1.6032152899, 1e-9);
    vec3 F = bsdf_fresnel_conductor3(eta, k, 1.0);
    assert_true(F.x > F.y && F.y > F.z);
    assert_true(bsdf_conductor_preset("Ag", &eta, &k));
    F = bsdf_fresnel_conductor3(eta, k, 1.0);
    assert_true(F.x > 0.9 && F.z > 0.8);
    bsdf c = prepared(BSDF_CONDUCTOR);
    assert_true(bsdf_conductor_preset("Cu", &eta, &k));
    ASSERT_VEC(c.eta, eta.x, eta.y, eta.z, 0.0);
    ASSERT_VEC(c.k, k.x, k.y, k.z, 0.0);
    ASSERT_NEAR(c.eta.x, 0.200438, 1e-6);
    assert_false(bsdf_conductor_preset("Unobtainium", &eta, &k));
    assert_false(bsdf_conductor_preset("au", &eta, &k));
    assert_false(bsdf_conductor_preset("", &eta, &k));
    assert_false(bsdf_conductor_preset(NULL, &eta, &k));
}

/* Names, lobes and the reference's defaults. */
static void test_names_lobes_defaults(void **state)
{
    (void)state;
    for (int t = 0; t < BSDF_TYPE_COUNT; t++) {
        assert_int_equal(bsdf_type_from_name(bsdf_type_name(t)), t);
        bsdf b = prepared(t);
        ASSERT_VEC(b.albedo, 1, 1, 1, 0);
        assert_int_equal(b.texture, -1);
    }
    assert_int_equal(bsdf_type_from_name("oren_nayar"), -1);
    assert_int_equal(bsdf_type_from_name(NULL), -1);
    assert_int_equal(bsdf_type_from_name("pbrt-plastic"), -1);
    bsdf b = prepared(BSDF_ROUGH_CONDUCTOR);
    assert_true(b.distribution == MICROFACET_GGX && b.roughness == 0.1 && b.alpha == 0.1);
    assert_int_equal(bsdf_lobes(&b), BSDF_LOBE_GLOSSY);
    b = prepared(BSDF_ROUGH_PLASTIC);
    assert_true(b.distribution == MICROFACET_GGX && b.roughness == 0.02 && b.ks == 1.0 && b.ior == 1.5);
    assert_int_equal(bsdf_lobes(&b), BSDF_LOBE_GLOSSY | BSDF_LOBE_DIFFUSE);
    b = prepared(BSDF_PBRT_PLASTIC);
    assert_true(b.distribution == MICROFACET_PBRT_GGX && b.roughness == 0.1 && b.ks == 0.25 && b.ior == 1.5);
    b = prepared(BSDF_PLASTIC);
    assert_true(b.thickness == 1.0 && v3_is_zero(b.sigma_a));
    assert_int_equal(bsdf_lobes(&b), BSDF_LOBE_SPECULAR | BSDF_LOBE_DIFFUSE);
    b = prepared(BSDF_ROUGH_DIELECTRIC);
    assert_true(b.roughness == 0.1 && b.enable_refraction && bsdf_transmits(&b));
    assert_int_equal(bsdf_lobes(&b), BSDF_LOBE_GLOSSY);
    b.enable_refraction = 0;
    assert_false(bsdf_transmits(&b));
    b = prepared(BSDF_DIELECTRIC);
    assert_int_equal(bsdf_lobes(&b), BSDF_LOBE_SPECULAR);
    /* roughness is clamped to 1e-3 before use as alpha */
    b.type = BSDF_ROUGH_DIELECTRIC;
    b.roughness = 0.0;
    dp_error err;
    assert_int_equal(bsdf_prepare(&b, &err), 0);
    ASSERT_NEAR(b.alpha, 1e-3, 0.0);
    b = prepared(BSDF_NULL);
    assert_int_equal(bsdf_lobes(&b), 0);
    assert_true(bsdf_is_passthrough(&b));
}

static void expect_rejected(bsdf *b, const char *what)
{
    dp_error err = {0};
    snprintf(b->name, sizeof b->name, "shiny_thing");
    if (bsdf_prepare(b, &err) == 0) fail_msg("bsdf_prepare accepted %s", what);
    if (!strstr(err.msg, "shiny_thing")) fail_msg("error for %s does not name the bsdf: %s", what, err.msg);
}

/* bsdf_prepare refuses what the user wrote wrong, naming the bsdf. */
static void test_prepare_rejects(void **state)
{
    (void)state;
    bsdf b;
    bsdf_defaults(&b, BSDF_ROUGH_CONDUCTOR);
    b.roughness = -0.1;
    expect_rejected(&b, "negative roughness");
    bsdf_defaults(&b, BSDF_ROUGH_PLASTIC);
    b.roughness = NAN;
    expect_rejected(&b, "NaN roughness");
    bsdf_defaults(&b, BSDF_DIELECTRIC);
    b.ior = 0.0;
    expect_rejected(&b, "ior 0");
    bsdf_defaults(&b, BSDF_ROUGH_DIELECTRIC);
    b.ior = -1.5;
    expect_rejected(&b, "negative ior");
    bsdf_defaults(&b, BSDF_PBRT_PLASTIC);
    b.ior = INFINITY;
    expect_rejected(&b, "infinite ior");
    bsdf_defaults(&b, BSDF_PLASTIC);
    b.sigma_a = v3(0.1, -0.1, 0);
    expect_rejected(&b, "negative sigma_a");
    bsdf_defaults(&b, BSDF_PLASTIC);
    b.thickness = -1;
    expect_rejected(&b, "negative thickness");
    bsdf_defaults(&b, BSDF_LAMBERT);
    b.albedo = v3(0.5, -0.5, 0.5);
    expect_rejected(&b, "negative albedo");
    bsdf_defaults(&b, BSDF_CONDUCTOR);
    b.k = v3(NAN, 1, 1);
    expect_rejected(&b, "NaN k");
    bsdf_defaults(&b, BSDF_ROUGH_PLASTIC);
    b.ks = -1;
    expect_rejected(&b, "negative Ks");
    bsdf_defaults(&b, BSDF_ROUGH_CONDUCTOR);
    b.distribution = (microfacet_distribution)7;
    expect_rejected(&b, "unknown distribution");
    /* an unknown material is refused by the lookup the loader calls */
    vec3 eta, k;
    assert_false(bsdf_conductor_preset("Mithril", &eta, &k));
}

/* The delta lobes' outcomes: mirror weight albedo; conductor weight albedo·F; dielectric reflects with
 * probability F and refracts by Snell's law, both of weight albedo, and without refraction reflects with
 * weight albedo·F; plastic's specular lobe has weight F/P. */
static void test_delta_lobes(void **state)
{
    (void)state;
    vec3 alb = v3(0.9, 0.6, 0.3), wi = dir(0.5, 0.3);
    double u[3] = {0.3, 0.6, 0.9};
    bsdf_sample s;
    bsdf m = prepared(BSDF_MIRROR);
    assert_true(bsdf_sample_wo(&m, alb, wi, u, BSDF_LOBES_ALL, &s));
    ASSERT_VEC(s.wo, -wi.x, -wi.y, wi.z, 1e-15);
    ASSERT_VEC(s.weight, 0.9, 0.6, 0.3, 0);
    assert_true(s.pdf == 1.0 && s.lobe == BSDF_LOBE_SPECULAR);
    assert_false(bsdf_sample_wo(&m, alb, v3(0, 0.6, -0.8), u, BSDF_LOBES_ALL, &s));
    assert_false(bsdf_sample_wo(&m, alb, wi, u, BSDF_LOBE_DIFFUSE, &s));
    ASSERT_VEC(bsdf_eval(&m, alb, wi, v3(-wi.x, -wi.y, wi.z), BSDF_LOBES_ALL), 0, 0, 0, 0);

    bsdf c = prepared(BSDF_CONDUCTOR);
    assert_true(bsdf_sample_wo(&c, alb, v3(0, 0, 1), u, BSDF_LOBES_ALL, &s));
    vec3 r0;
    double n[3] = {c.eta.x, c.eta.y, c.eta.z}, k[3] = {c.k.x, c.k.y, c.k.z}, r[3];
    for (int i = 0; i < 3; i++) r[i] = ((n[i] - 1) * (n[i] - 1) + k[i] * k[i]) / ((n[i] + 1) * (n[i] + 1) + k[i] * k[i]);
    r0 = v3(r[0], r[1], r[2]);
    ASSERT_VEC(s.weight, 0.9 * r0.x, 0.6 * r0.y, 0.3 * r0.z, 1e-12);

    bsdf d = prepared(BSDF_DIELECTRIC);
    double ct, F = bsdf_fresnel_dielectric(1.5, wi.z, &ct);
    double ur[3] = {0.5 * F, 0.5, 0.5}, ut[3] = {0.5 * (1 + F), 0.5, 0.5};
    assert_true(bsdf_sample_wo(&d, alb, wi, ur, BSDF_LOBES_ALL, &s));
    ASSERT_VEC(s.wo, -wi.x, -wi.y, wi.z, 1e-15);
    ASSERT_NEAR(s.pdf, F, 1e-15);
    ASSERT_VEC(s.weight, 0.9, 0.6, 0.3, 1e-15);
    assert_true(bsdf_sample_wo(&d, alb, wi, ut, BSDF_LOBES_ALL, &s));
    ASSERT_NEAR(s.pdf, 1 - F, 1e-15);
    ASSERT_VEC(s.weight, 0.9, 0.6, 0.3, 1e-15);
    ASSERT_NEAR(v3_len(s.wo), 1.0, 1e-12);
    ASSERT_NEAR(sqrt(1 - s.wo.z * s.wo.z) * 1.5, sqrt(1 - wi.z * wi.z), 1e-12); /* Snell */
    ASSERT_NEAR(s.wo.z, -ct, 1e-12);
    assert_true(s.wo.x * wi.x < 0 && s.wo.y * wi.y < 0);
    /* from inside beyond the critical angle: always reflected, probability 1 */
    vec3 w_in = dir(M_PI - 0.9, 0.0);
    assert_true(bsdf_sample_wo(&d, alb, w_in, ut, BSDF_LOBES_ALL, &s));
    ASSERT_VEC(s.wo, -w_in.x, -w_in.y, w_in.z, 1e-15);
    ASSERT_NEAR(s.pdf, 1.0, 0.0);
    d.enable_refraction = 0;
    assert_true(bsdf_sample_wo(&d, alb, wi, ut, BSDF_LOBES_ALL, &s));
    ASSERT_VEC(s.wo, -wi.x, -wi.y, wi.z, 1e-15);
    ASSERT_NEAR(s.pdf, 1.0, 0.0);
    ASSERT_VEC(s.weight, 0.9 * F, 0.6 * F, 0.3 * F, 1e-15);

    bsdf p = prepared(BSDF_PLASTIC);
    F = bsdf_fresnel_dielectric(1.5, wi.z, NULL);
    double P = F / (F + (1 - F)); /* sigma_a = 0: T̄ = 1 */
    double us[3] = {0.5, 0.5, 0.5 * P};
    assert_true(bsdf_sample_wo(&p, alb, wi, us, BSDF_LOBES_ALL, &s));
    assert_true(s.lobe == BSDF_LOBE_SPECULAR);
    ASSERT_NEAR(s.pdf, P, 1e-15);
    ASSERT_VEC(s.weight, F / P, F / P, F / P, 1e-12);
    assert_true(bsdf_sample_wo(&p, alb, wi, us, BSDF_LOBE_SPECULAR, &s));
    ASSERT_VEC(s.weight, F, F, F, 1e-15);
}

/* Closed forms of the coated models: a plastic coat of index 1 is no coat (f = albedo/π exactly); the
 * coated base of index η is (1−Fi)(1−Fo)/η² ρ/(1−ρF̄)/π with absorption exp(−τ(1/cos θi + 1/cos θo));
 * pbrt_plastic's glossy lobe at mirror configuration beyond the critical angle (its inverted index: F = 1)
 * is Ks·D(n)·G/(4cos²θ) with D(n) = 1/(πα²) and G = 1/(1 + 2Λ(θ)). */
static void test_coated_closed_forms(void **state)
{
    (void)state;
    vec3 alb = v3(0.8, 0.5, 0.2), wi = dir(0.7, 0.2), wo = dir(1.1, 2.5);
    bsdf p;
    bsdf_defaults(&p, BSDF_PLASTIC);
    p.ior = 1.0;
    dp_error err;
    assert_int_equal(bsdf_prepare(&p, &err), 0);
    ASSERT_NEAR(p.diffuse_fresnel, 0.0, 1e-12);
    ASSERT_VEC(bsdf_eval(&p, alb, wi, wo, BSDF_LOBES_ALL), 0.8 / M_PI, 0.5 / M_PI, 0.2 / M_PI, 1e-14);

    bsdf_defaults(&p, BSDF_PLASTIC);
    p.sigma_a = v3(0.0, 0.5, 1.0);
    p.thickness = 0.5;
    assert_int_equal(bsdf_prepare(&p, &err), 0);
    double Fi = bsdf_fresnel_dielectric(1.5, wi.z, NULL), Fo = bsdf_fresnel_dielectric(1.5, wo.z, NULL);
    double Fd = bsdf_fresnel_average(1.0 / 1.5), geo = 1.0 / wi.z + 1.0 / wo.z;
    double c = (1 - Fi) * (1 - Fo) / (1.5 * 1.5) / M_PI;
    vec3 f = bsdf_eval(&p, alb, wi, wo, BSDF_LOBES_ALL);
    ASSERT_NEAR(f.x, c * 0.8 / (1 - 0.8 * Fd), 1e-12);
    ASSERT_NEAR(f.y, c * 0.5 / (1 - 0.5 * Fd) * exp(-0.25 * geo), 1e-12);
    ASSERT_NEAR(f.z, c * 0.2 / (1 - 0.2 * Fd) * exp(-0.5 * geo), 1e-12);
    /* rough_plastic's diffuse lobe is the same base, scaled by one factor in (0, 1] for all channels (the
     * share its rough coat leaves, rough_plastic.c; its energy is checked by the furnace of test_bsdf.c) */
    bsdf rp = p;
    rp.type = BSDF_ROUGH_PLASTIC;
    rp.roughness = 0.3;
    assert_int_equal(bsdf_prepare(&rp, &err), 0);
    vec3 g = bsdf_eval(&rp, alb, wi, wo, BSDF_LOBE_DIFFUSE);
    double k = g.x / f.x;
    assert_true(k > 0.5 && k <= 1.0);
    ASSERT_VEC(g, k * f.x, k * f.y, k * f.z, 1e-12);

    bsdf pb = prepared(BSDF_PBRT_PLASTIC);
    double th = 1.0, a = pb.alpha; /* sin 1.0 > 1/1.5 */
    vec3 i = dir(th, 0.0), o = dir(th, M_PI);
    double lam = 0.5 * (sqrt(1 + a * a * tan(th) * tan(th)) - 1);
    double expect = 0.25 * (1.0 / (M_PI * a * a)) / (1 + 2 * lam) / (4 * cos(th) * cos(th));
    f = bsdf_eval(&pb, alb, i, o, BSDF_LOBE_GLOSSY);
    ASSERT_NEAR(f.x, expect, 1e-9 * expect);
    ASSERT_NEAR(f.z, expect, 1e-9 * expect);
    f = bsdf_eval(&pb, alb, i, o, BSDF_LOBE_DIFFUSE);
    ASSERT_VEC(f, 0.8 / M_PI, 0.5 / M_PI, 0.2 / M_PI, 1e-15);
}

/* The shading frame: orthonormal, right-handed, flipped towards an arriving path for opaque two-sided
 * shading only. */
static void test_frame(void **state)
{
    (void)state;
    bsdf lam = prepared(BSDF_LAMBERT), glass = prepared(BSDF_DIELECTRIC);
    vec3 ng = v3_norm(v3(0.2, 0.3, 0.9)), ns = v3_norm(v3(0.25, 0.25, 0.9));
    vec3 from_back = v3_norm(v3(0.1, 0.0, 1.0)), from_front = v3_neg(from_back);
    bsdf_frame f;
    bsdf_frame_init(&f, &lam, ng, ns, from_front, 1);
    ASSERT_VEC(f.n, ns.x, ns.y, ns.z, 0);
    ASSERT_NEAR(v3_dot(f.s, f.t), 0.0, 1e-14);
    ASSERT_NEAR(v3_dot(f.s, f.n), 0.0, 1e-14);
    ASSERT_NEAR(v3_dot(v3_cross(f.s, f.t), f.n), 1.0, 1e-14);
    vec3 w = v3_norm(v3(0.3, -0.5, 0.4));
    vec3 back = bsdf_to_world(&f, bsdf_to_local(&f, w));
    ASSERT_VEC(back, w.x, w.y, w.z, 1e-14);
    bsdf_frame_init(&f, &lam, ng, ns, from_back, 1);
    ASSERT_VEC(f.n, -ns.x, -ns.y, -ns.z, 0);
    ASSERT_VEC(f.ng, -ng.x, -ng.y, -ng.z, 0);
    assert_true(bsdf_to_local(&f, v3_neg(from_back)).z > 0.0); /* wi is on the frame's front */
    bsdf_frame_init(&f, &lam, ng, ns, from_back, 0);
    ASSERT_VEC(f.n, ns.x, ns.y, ns.z, 0);
    bsdf_frame_init(&f, &glass, ng, ns, from_back, 1);
    ASSERT_VEC(f.n, ns.x, ns.y, ns.z, 0);
    glass.enable_refraction = 0;
    bsdf_frame_init(&f, &glass, ng, ns, from_back, 1);
    ASSERT_VEC(f.n, -ns.x, -ns.y, -ns.z, 0);
}

/* Grazing and degenerate directions never give non-finite values, for every model and lobe selection. */
static void test_never_non_finite(void **state)
{
    (void)state;
    const vec3 dirs[] = {v3(0, 0, 1), v3(0, 0, -1), v3(1, 0, 0), v3(-1, 0, 0), v3(1, 0, 1e-300),
                         v3(1, 0, -1e-300), v3(0.6, 0, 0.8), v3(-0.6, 0, 0.8), v3(-0.6, 0, -0.8),
                         v3(1, 0, 1e-9), v3(0, 1, 1e-17)};
    const size_t nd = sizeof dirs / sizeof dirs[0];
    const double rough[] = {0.0, 1e-6, 0.3, 2.0};
    const microfacet_distribution ds[] = {MICROFACET_GGX, MICROFACET_PBRT_GGX, MICROFACET_BECKMANN};
    const double us[][3] = {{0, 0, 0}, {0.999999999, 0.5, 0.999999999}, {0.5, 0.25, 0.5}, {1e-300, 0.9, 0.1}};
    vec3 alb = v3(1.0, 0.5, 0.0);
    for (int t = 0; t < BSDF_TYPE_COUNT; t++)
        for (int r = 0; r < 4; r++)
            for (int di = 0; di < 3; di++) {
                bsdf b;
                bsdf_defaults(&b, t);
                b.roughness = rough[r];
                b.distribution = ds[di];
                dp_error err;
                assert_int_equal(bsdf_prepare(&b, &err), 0);
                for (unsigned lobes = 1; lobes <= BSDF_LOBES_ALL; lobes++)
                    for (size_t i = 0; i < nd; i++) {
                        vec3 wi = v3_norm(dirs[i]);
                        for (size_t o = 0; o < nd; o++) {
                            vec3 wo = v3_norm(dirs[o]);
                            vec3 f = bsdf_eval(&b, alb, wi, wo, lobes);
                            double p = bsdf_pdf(&b, alb, wi, wo, lobes);
                            if (!v3_is_finite(f) || !isfinite(p) || p < 0 || f.x < 0 || f.y < 0 || f.z < 0)
                                fail_msg("%s r=%g: eval/pdf not finite", bsdf_type_name(t), rough[r]);
                        }
                        for (size_t k = 0; k < 4; k++) {
                            bsdf_sample s;
                            if (bsdf_sample_wo(&b, alb, wi, us[k], lobes, &s) &&
                                (!v3_is_finite(s.weight) || !(s.pdf > 0) || !isfinite(s.pdf) ||
                                 fabs(v3_len(s.wo) - 1.0) > 1e-9))
                                fail_msg("%s r=%g: sample not finite", bsdf_type_name(t), rough[r]);
                        }
                    }
            }
}

/* bsdf_regularized: a rough conductor or pbrt plastic smoother than the floor evaluates as the same model
 * prepared with roughness = the floor (α = roughness for both distributions); one already rougher, and the
 * other models, evaluate as before. */
static double max_diff(vec3 a, vec3 b) { return fmax(fabs(a.x - b.x), fmax(fabs(a.y - b.y), fabs(a.z - b.z))); }

static void test_regularized(void **state)
{
    (void)state;
    const bsdf_type raised[] = {BSDF_ROUGH_CONDUCTOR, BSDF_PBRT_PLASTIC};
    const bsdf_type kept[] = {BSDF_LAMBERT, BSDF_ROUGH_PLASTIC, BSDF_ROUGH_DIELECTRIC, BSDF_MIRROR};
    vec3 albedo = v3(0.8, 0.6, 0.4);
    for (size_t t = 0; t < sizeof raised / sizeof *raised; t++) {
        bsdf smooth = prepared(raised[t]), rough = prepared(raised[t]);
        smooth.roughness = 0.05;
        rough.roughness = 0.3;
        dp_error err;
        if (bsdf_prepare(&smooth, &err) || bsdf_prepare(&rough, &err)) fail_msg("%s", err.msg);
        bsdf reg = bsdf_regularized(&smooth, 0.3), same = bsdf_regularized(&rough, 0.1);
        int differs = 0;
        for (int i = 0; i < 40; i++) {
            vec3 wi = dir(0.03 * i, 0.7 * i), wo = dir(0.025 * i + 0.01, 0.7 * i + M_PI + 0.02 * i);
            vec3 got = bsdf_eval(&reg, albedo, wi, wo, ~0u), want = bsdf_eval(&rough, albedo, wi, wo, ~0u);
            vec3 before = bsdf_eval(&smooth, albedo, wi, wo, ~0u);
            assert_true(max_diff(got, want) <= 1e-12 * (1.0 + v3_max(want)));
            vec3 kept_eval = bsdf_eval(&same, albedo, wi, wo, ~0u);
            assert_true(max_diff(kept_eval, want) == 0.0);
            differs |= max_diff(before, want) > 1e-6 * (1.0 + v3_max(want));
        }
        assert_true(differs); /* the floor changes the smooth model's values, so the check above can fail */
    }
    for (size_t t = 0; t < sizeof kept / sizeof *kept; t++) {
        bsdf b = prepared(kept[t]), r = bsdf_regularized(&b, 0.9);
        assert_true(memcmp(&b, &r, sizeof b) == 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conductor_fresnel),
        cmocka_unit_test(test_dielectric_fresnel),
        cmocka_unit_test(test_fresnel_average),
        cmocka_unit_test(test_microfacet_normalised),
        cmocka_unit_test(test_smith_masking),
        cmocka_unit_test(test_conductor_presets),
        cmocka_unit_test(test_names_lobes_defaults),
        cmocka_unit_test(test_prepare_rejects),
        cmocka_unit_test(test_delta_lobes),
        cmocka_unit_test(test_coated_closed_forms),
        cmocka_unit_test(test_frame),
        cmocka_unit_test(test_never_non_finite),
        cmocka_unit_test(test_regularized),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
