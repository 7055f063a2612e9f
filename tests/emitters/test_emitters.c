/* tier: quick */
/* The emitter module (include/dartspp/emitter.h, src/emitter, the loader in src/scene/light_load.c) against
 * references written here, never against figures copied from a run: χ² of every sampler against its density
 * integrated by quadrature in this file, fluxes against the closed forms of docs/emitters.md computed from the
 * keys by hand, next-event estimation against closed-form irradiances and a quadrature over the beam's disc,
 * the beam crossing against a brute-force scan, the loader's conversions and refusals, the pulses against the
 * normal and uniform distributions, and light selection against flux-proportional frequencies.
 *
 * Each check was seen to fail: one change to the code at a time, rebuilt, run, restored (2026-11-26, seed
 * 0x3e17; every other test of the program still passed unless listed):
 *   M1  spot ring sampled uniformly in cosθ, not ∝ smoothstep     spot directions χ² 2.4e6, dof 239, p = 0
 *   M2  area triangle picked uniformly, not by area                mesh positions χ² 1.3e6, dof 29, p = 0;
 *                                                                  sphere irradiance z = 49
 *   M3  Gaussian pulse width used as σ, not as the FWHM            pulse χ² 5.5e7, dof 41, p = 0; share within
 *                                                                  ±FWHM/2 0.383 (want 0.761), z = −560
 *   M4  collimated `power` not divided by πr²                       flux table: radius 0.5 beams by power get
 *                                                                  E = 2 (want 2.546), Φ = 1.571 (want 2)
 *   M5  diverging beam directions uniform in the cone, not cosine   collimated directions χ² 4433, dof 239, p = 0
 *   M6  collimated disc radius r·u, not r·sqrt(u)                   disc positions χ² 4.5e5, dof 79, p = 0;
 *                                                                  diverging-beam NEE z = 215
 *   M7  area NEE without the cosine at the light                    quad irradiance z = 333, sphere z = 411
 *   M8  point light directions on one hemisphere only               point directions χ² 3.6e5, dof 239, p = 0
 *   M9  area light directions uniform on the hemisphere             quad directions χ² 5.8e5, dof 239, p = 0
 *   M10 beam crossing without the cut s > 0 behind the disc         218 of 1500 random rays and 2 of 3 special
 *                                                                  rays disagree with the scan
 *   M11 spot fall-off linear instead of smoothstep                  spot NEE at 20°: 0.69500 (by hand 0.76228)
 *                                                                  (the spot χ² passes: sampling does not use it)
 *   M12 light selection uniform when by power                       selection χ² 87223, dof 2, p = 0; the black
 *                                                                  light chosen 49801 times
 *   M13 disk/sphere radius the shortest axis, not the longest       disk area −44 %, sphere −89 %
 *   M14 parallel beam NEE without the radius test                   a point at ρ = 0.51 > r = 0.5 lit
 *   M15 diverging beam radiance E/π, not E/(π sin²δ)                diverging-beam NEE z = −6830
 *   M16 barycentrics with b0 = 1 − u, not 1 − sqrt(u)               mesh positions χ² 61699, p = 0, 133126
 *                                                                  points off the mesh; quad irradiance z = −367
 *   M17 quad winding reversed (front −y)                            ray normal (0, −1, 0); quad irradiance 0;
 *                                                                  front-side test fails
 *   M18 spot ring weight (cos_start − cos_end)/3, not /2            spot directions χ² 15071, p = 0; Φ and the
 *                                                                  selection pdf off
 *   M19 sphere winding reversed (inward)                            16128 of 16128 triangles inward; the sphere
 *                                                                  irradiance alone does not see it (z = −0.07)
 *
 * Significance: each of the 15 χ² and z tests fails below ALPHA = 1e-4 (|z| > 4), so a correct build fails one
 * by chance with probability about 2e-3. The seed is fixed; $DARTSPP_EM_SEED changes it (seeds 1 to 5 pass).
 * The whole program runs in about 1 s under the sanitizers. */
#include "fixtures.h"

#include "dartspp/emitter.h"

#define ALPHA 1e-4
#define Z_MAX 4.0   /* |z| above this fails (two-sided p ≈ 6e-5) */
#define DEG (M_PI / 180.0)

static uint64_t test_seed(void)
{
    const char *e = getenv("DARTSPP_EM_SEED");
    return e && e[0] ? strtoull(e, NULL, 0) : 0x3e17u;
}

/* ---------------------------------------------------------------- scenes */

/* A scene of the given primitives (the white BSDF is there for the area lights), with a camera and an
 * integrator so that it loads; NULL with err set when the loader refuses it. */
static scene *load_prims(const char *prims, dp_error *err)
{
    static const char head[] = "{ \"bsdfs\": [ {\"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.5} ],\n"
                               "  \"primitives\": [\n";
    static const char tail[] =
        "\n  ],\n"
        "  \"camera\": {\"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 45,\n"
        "    \"transform\": {\"position\": [0, 1, -9], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}},\n"
        "  \"integrator\": {\"type\": \"path_tracer\", \"max_bounces\": 4, \"transient_time_center\": 6,\n"
        "    \"transient_time_width\": 0.5},\n"
        "  \"renderer\": {\"spp\": 1, \"timeout\": \"0\"}\n}\n";
    size_t n = strlen(head) + strlen(prims) + strlen(tail) + 1;
    char *text = fx_keep(malloc(n));
    snprintf(text, n, "%s%s%s", head, prims, tail);
    return fx_load_text("emitters.json", text, NULL, err);
}

static scene *load_ok(const char *prims)
{
    dp_error err;
    scene *s = load_prims(prims, &err);
    if (!s) fail_msg("the scene must load: %s\n%s", err.msg, prims);
    return s;
}

/* The scene's only light, or the first of several. */
static const emitter *light0(const scene *s)
{
    assert_true(s->light_count >= 1);
    return &s->lights[0];
}

/* ---------------------------------------------------------------- the test's own geometry */

typedef struct {
    vec3 a, b1, b2; /* a unit axis and two unit vectors across it */
} frame;

static frame frame_about(vec3 a)
{
    frame f;
    f.a = v3_norm(a);
    vec3 h = fabs(f.a.x) < 0.6 ? v3(1, 0, 0) : v3(0, 1, 0);
    f.b1 = v3_norm(v3_cross(h, f.a));
    f.b2 = v3_cross(f.a, f.b1);
    return f;
}

/* θ from the axis and φ in [0, 2π) of the unit direction d */
static void polar(const frame *f, vec3 d, double *theta, double *phi)
{
    *theta = acos(fmax(-1.0, fmin(1.0, v3_dot(d, f->a))));
    *phi = atan2(v3_dot(d, f->b2), v3_dot(d, f->b1));
    if (*phi < 0.0) *phi += 2.0 * M_PI;
}

static double smoothstep_ref(double t)
{
    t = fmin(1.0, fmax(0.0, t));
    return t * t * (3.0 - 2.0 * t);
}

/* pbrt-v4's spot fall-off from the scene keys (degrees), written out here */
typedef struct {
    double cone, delta;
} spot_keys;

static double spot_falloff_ref(const spot_keys *k, double cos_theta)
{
    double ce = cos(k->cone * DEG), cs = cos((k->cone - k->delta) * DEG);
    if (cos_theta >= cs) return 1.0;
    return smoothstep_ref((cos_theta - ce) / (cs - ce));
}

/* ∫_a^b g by 32-point Gauss–Legendre on `pieces` equal sub-intervals */
static double integrate(double (*g)(double, const void *), const void *ctx, double a, double b, int pieces)
{
    double x[32], w[32], sum = 0.0, h = (b - a) / pieces;
    gauss_legendre(32, x, w);
    for (int p = 0; p < pieces; p++) {
        double lo = a + p * h;
        for (int i = 0; i < 32; i++) sum += 0.5 * h * w[i] * g(lo + 0.5 * h * (x[i] + 1.0), ctx);
    }
    return sum;
}

/* ---------------------------------------------------------------- χ² of directions */

#define NTH 30 /* polar bins */
#define NPH 8  /* azimuth bins */
#define N_DIRS 400000

/* the polar density w(θ) (per dθ, unnormalised) of a sampler */
typedef double (*polar_density)(double theta, const void *ctx);

typedef struct {
    polar_density w;
    const void *ctx;
} polar_ctx;

static double polar_eval(double theta, const void *p)
{
    const polar_ctx *c = p;
    return c->w(theta, c->ctx);
}

/* χ² of n directions about the axis: NTH polar bins on [0, th_max] × NPH azimuth bins, expected counts from
 * ∫ w(θ) dθ per bin (azimuth uniform); a direction beyond th_max is impossible and fails. Returns p. */
static double chi2_directions(const char *name, const vec3 *dirs, long n, vec3 axis, double th_max, polar_density w,
                              const void *ctx)
{
    frame f = frame_about(axis);
    chi_cell cells[NTH * NPH + 1];
    polar_ctx pc = {w, ctx};
    double total = integrate(polar_eval, &pc, 0.0, th_max, 64);
    for (int i = 0; i < NTH; i++) {
        double lo = th_max * i / NTH, hi = th_max * (i + 1) / NTH;
        double pi = integrate(polar_eval, &pc, lo, hi, 2) / total;
        for (int j = 0; j < NPH; j++) cells[i * NPH + j] = (chi_cell){0.0, n * pi / NPH};
    }
    cells[NTH * NPH] = (chi_cell){0.0, 0.0};
    for (long k = 0; k < n; k++) {
        double th, ph;
        polar(&f, dirs[k], &th, &ph);
        if (th > th_max * (1.0 + 1e-9)) {
            cells[NTH * NPH].obs += 1.0;
            continue;
        }
        int i = (int)(th / th_max * NTH), j = (int)(ph / (2.0 * M_PI) * NPH);
        i = i < 0 ? 0 : i >= NTH ? NTH - 1 : i;
        j = j < 0 ? 0 : j >= NPH ? NPH - 1 : j;
        cells[i * NPH + j].obs += 1.0;
    }
    double chi2;
    int dof;
    long impossible;
    double p = chi2_pooled(cells, NTH * NPH + 1, &chi2, &dof, &impossible);
    print_message("  directions %-28s p %-9.3g (χ² %.1f, dof %d), beyond θmax %ld\n", name, p, chi2, dof, impossible);
    assert_int_equal(impossible, 0);
    return p;
}

/* n emission rays of the light, their directions in dirs (and their start points in pts when not NULL);
 * every ray must carry the light's flux Φ (all samplers here sample exactly as emitted) */
static void draw_rays(const scene *s, const emitter *e, long n, uint64_t stream, vec3 *dirs, vec3 *pts)
{
    dp_rng rng = rng_stream(test_seed(), stream, 1);
    for (long k = 0; k < n; k++) {
        double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
        emitter_ray r;
        emitter_sample_ray(s, e, u, &r);
        if (fabs(v3_len(r.d) - 1.0) > 1e-9 || fabs(r.flux.x - e->flux.x) > 1e-9 * e->flux.x)
            fail_msg("ray %ld: |d| = %.12g, flux %.12g, Φ %.12g", k, v3_len(r.d), r.flux.x, e->flux.x);
        dirs[k] = r.d;
        if (pts) pts[k] = r.p;
    }
}

static double w_sphere(double th, const void *c) { (void)c; return sin(th); }
static double w_cosine(double th, const void *c) { (void)c; return cos(th) * sin(th); }
static double w_spot(double th, const void *c) { return spot_falloff_ref(c, cos(th)) * sin(th); }

/* A skew beam direction shared by the spot and the collimated lights: position → look_at. */
#define SKEW_POS "[0.2, 0.5, -0.3]"
#define SKEW_AT "[1.0, 1.5, 0.7]"
static vec3 skew_axis(void) { return v3_norm(v3(0.8, 1.0, 1.0)); }

/* Point light: directions uniform on the sphere (density sinθ in θ about any axis). */
static void test_point_directions(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"point\", \"emission\": 1, \"transform\": {\"position\": [0, 1, 0]}}");
    vec3 *d = fx_keep(malloc(N_DIRS * sizeof(vec3)));
    draw_rays(s, light0(s), N_DIRS, 1, d, NULL);
    assert_true(chi2_directions("point (uniform sphere)", d, N_DIRS, v3_norm(v3(0.3, -0.5, 0.8)), M_PI, w_sphere, NULL) >
                ALPHA);
}

/* Spot: directions ∝ I(θ) = I·smoothstep over the cone (inner cone uniform, the ring ∝ smoothstep), nothing
 * beyond coneangle. A wide ring (coneangle 40, conedeltaangle 25) so that the ring's shape weighs. */
static void test_spot_directions(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"spot\", \"emission\": 1, \"coneangle\": 40, \"conedeltaangle\": 25,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    spot_keys k = {40.0, 25.0};
    vec3 *d = fx_keep(malloc(N_DIRS * sizeof(vec3)));
    draw_rays(s, light0(s), N_DIRS, 2, d, NULL);
    assert_true(chi2_directions("spot (smoothstep ring)", d, N_DIRS, skew_axis(), 40.0 * DEG, w_spot, &k) > ALPHA);
}

/* Collimated with divergence 45°: directions cosine-weighted in the cone of half-angle δ about the axis. */
static void test_collimated_directions(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"collimated\", \"emission\": 1, \"radius\": 0.5, \"divergence\": 45,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    vec3 *d = fx_keep(malloc(N_DIRS * sizeof(vec3)));
    draw_rays(s, light0(s), N_DIRS, 3, d, NULL);
    assert_true(chi2_directions("collimated δ 45° (cosine in cone)", d, N_DIRS, skew_axis(), 45.0 * DEG, w_cosine,
                                NULL) > ALPHA);
}

/* Area light (a quad, front +y): directions cosine-weighted about the normal, and the ray's normal is +y. */
static void test_area_directions(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 1,"
                             " \"transform\": {\"position\": [0, 1, 0], \"scale\": [2, 1, 3]}}");
    const emitter *e = light0(s);
    vec3 *d = fx_keep(malloc(N_DIRS * sizeof(vec3)));
    draw_rays(s, e, N_DIRS, 4, d, NULL);
    double u[4] = {0.3, 0.6, 0.2, 0.9};
    emitter_ray r;
    emitter_sample_ray(s, e, u, &r);
    ASSERT_VEC(r.n, 0, 1, 0, 1e-12);
    assert_true(chi2_directions("quad (cosine about +y)", d, N_DIRS, v3(0, 1, 0), 0.5 * M_PI, w_cosine, NULL) > ALPHA);
}

/* ---------------------------------------------------------------- χ² of positions */

/* Six disjoint triangles of unequal areas in the plane y = 0, each (o, o + b·z, o + a·x) so that the winding
 * normal is +y; triangle k lies in x ∈ [10k, 10k + a_k]. */
static const double TRI_A[6] = {1.0, 2.0, 3.0, 0.5, 4.0, 1.0}, TRI_B[6] = {1.0, 1.0, 2.0, 0.5, 3.0, 5.0};
#define N_POS 400000
#define NB0 5 /* bins of the barycentric coordinate of the triangle's first corner */

static void write_triangles_obj(void)
{
    char text[2048];
    size_t len = 0;
    for (int k = 0; k < 6; k++)
        len += (size_t)snprintf(text + len, sizeof text - len, "v %g 0 0\nv %g 0 %g\nv %g 0 0\n", 10.0 * k, 10.0 * k,
                                TRI_B[k], 10.0 * k + TRI_A[k]);
    for (int k = 0; k < 6; k++) len += (size_t)snprintf(text + len, sizeof text - len, "f %d %d %d\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    write_in_dir("tris.obj", text, len);
}

/* Area light over unequal triangles: the triangle ∝ its area, then uniform inside it: the first corner's
 * barycentric λ0 has P(λ0 ∈ [c, d]) = (1 − c)² − (1 − d)². */
static void test_area_positions(void **state)
{
    (void)state;
    write_triangles_obj();
    const scene *s = load_ok("{\"type\": \"mesh\", \"file\": \"tris.obj\", \"bsdf\": \"white\", \"emission\": 1}");
    const emitter *e = light0(s);
    double area = 0.0;
    for (int k = 0; k < 6; k++) area += 0.5 * TRI_A[k] * TRI_B[k];
    ASSERT_NEAR(e->area, area, 1e-9 * area);
    chi_cell cells[6 * NB0 + 1];
    for (int k = 0; k < 6; k++)
        for (int b = 0; b < NB0; b++) {
            double c = (double)b / NB0, dd = (b + 1.0) / NB0;
            cells[k * NB0 + b] = (chi_cell){0.0, N_POS * (0.5 * TRI_A[k] * TRI_B[k] / area) * ((1 - c) * (1 - c) - (1 - dd) * (1 - dd))};
        }
    cells[6 * NB0] = (chi_cell){0.0, 0.0};
    vec3 *d = fx_keep(malloc(N_POS * sizeof(vec3))), *p = fx_keep(malloc(N_POS * sizeof(vec3)));
    draw_rays(s, e, N_POS, 5, d, p);
    for (long n = 0; n < N_POS; n++) {
        int k = (int)floor(p[n].x / 10.0 + 0.05);
        double l2 = k >= 0 && k < 6 ? (p[n].x - 10.0 * k) / TRI_A[k] : -1.0, l1 = k >= 0 && k < 6 ? p[n].z / TRI_B[k] : -1.0;
        double l0 = 1.0 - l1 - l2, eps = 1e-6;
        if (k < 0 || k >= 6 || l0 < -eps || l1 < -eps || l2 < -eps || fabs(p[n].y) > eps) {
            cells[6 * NB0].obs += 1.0;
            continue;
        }
        int b = (int)(l0 * NB0);
        cells[k * NB0 + (b < 0 ? 0 : b >= NB0 ? NB0 - 1 : b)].obs += 1.0;
    }
    double chi2;
    int dof;
    long impossible;
    double pv = chi2_pooled(cells, 6 * NB0 + 1, &chi2, &dof, &impossible);
    print_message("  positions on 6 unequal triangles: p %-9.3g (χ² %.1f, dof %d), off the mesh %ld\n", pv, chi2, dof,
                  impossible);
    assert_int_equal(impossible, 0);
    assert_true(pv > ALPHA);
}

#define NRHO 10
/* Collimated disc of radius 2: start points uniform on the disc (radial bins ∝ ring area, azimuth uniform), in
 * the plane through the position across the axis; parallel rays along the axis. */
static void test_collimated_disc_positions(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"collimated\", \"emission\": 1, \"radius\": 2,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    const emitter *e = light0(s);
    vec3 c = v3(0.2, 0.5, -0.3), a = skew_axis();
    frame f = frame_about(a);
    chi_cell cells[NRHO * NPH + 1];
    for (int i = 0; i < NRHO * NPH; i++) cells[i] = (chi_cell){0.0, 0.0};
    for (int i = 0; i < NRHO; i++)
        for (int j = 0; j < NPH; j++)
            cells[i * NPH + j].exp = (double)N_POS * ((i + 1.0) * (i + 1.0) - (double)i * i) / (NRHO * NRHO) / NPH;
    cells[NRHO * NPH] = (chi_cell){0.0, 0.0};
    vec3 *d = fx_keep(malloc(N_POS * sizeof(vec3))), *p = fx_keep(malloc(N_POS * sizeof(vec3)));
    draw_rays(s, e, N_POS, 6, d, p);
    long off_axis = 0;
    for (long n = 0; n < N_POS; n++) {
        if (v3_dot(d[n], a) < 1.0 - 1e-12) off_axis++;
        vec3 w = v3_sub(p[n], c);
        double rho = v3_len(w), ph = atan2(v3_dot(w, f.b2), v3_dot(w, f.b1));
        if (ph < 0.0) ph += 2.0 * M_PI;
        if (fabs(v3_dot(w, a)) > 1e-9 || rho > 2.0 * (1.0 + 1e-9)) {
            cells[NRHO * NPH].obs += 1.0;
            continue;
        }
        int i = (int)(rho / 2.0 * NRHO), j = (int)(ph / (2.0 * M_PI) * NPH);
        cells[(i >= NRHO ? NRHO - 1 : i) * NPH + (j >= NPH ? NPH - 1 : j)].obs += 1.0;
    }
    double chi2;
    int dof;
    long impossible;
    double pv = chi2_pooled(cells, NRHO * NPH + 1, &chi2, &dof, &impossible);
    print_message("  positions on the collimated disc: p %-9.3g (χ² %.1f, dof %d), off the disc %ld, off axis %ld\n", pv,
                  chi2, dof, impossible, off_axis);
    assert_int_equal(impossible, 0);
    assert_int_equal(off_axis, 0);
    assert_true(pv > ALPHA);
}

/* ---------------------------------------------------------------- flux and the loader's units */

typedef struct {
    const char *prim;
    vec3 value; /* what the emitter's value must be, by hand from the keys */
    vec3 flux;  /* Φ by hand */
} flux_case;

static int check_flux_case(const flux_case *c)
{
    dp_error err;
    scene *s = load_prims(c->prim, &err);
    if (!s) {
        print_message("  FAILED to load %s: %s\n", c->prim, err.msg);
        return 1;
    }
    const emitter *e = light0(s);
    /* the mean flux a light path carries, over rays drawn with random numbers */
    dp_rng rng = rng_stream(test_seed(), 7, 0);
    vec3 mean = v3s(0.0);
    const int n = 2000;
    for (int k = 0; k < n; k++) {
        double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
        emitter_ray r;
        emitter_sample_ray(s, e, u, &r);
        mean = v3_add(mean, v3_scale(r.flux, 1.0 / n));
    }
    double tol = 1e-9 * (v3_avg(c->flux) + v3_avg(c->value));
    int bad = 0;
    vec3 got[3] = {e->value, e->flux, mean}, want[3] = {c->value, c->flux, c->flux};
    for (int i = 0; i < 3; i++)
        bad |= !(fabs(got[i].x - want[i].x) <= tol && fabs(got[i].y - want[i].y) <= tol && fabs(got[i].z - want[i].z) <= tol);
    print_message("  %-100.100s value %.6g Φ %.6g mean ray flux %.6g (want %.6g, %.6g)%s\n", c->prim, e->value.y,
                  e->flux.y, mean.y, c->value.y, c->flux.y, bad ? "  FAILED" : "");
    fx_drop(s);
    return bad;
}

/* Φ of the spot, closed form: 2πI[(1 − cos_start) + (cos_start − cos_end)/2] */
static double spot_flux_ref(double I, double cone, double delta)
{
    double ce = cos(cone * DEG), cs = cos((cone - delta) * DEG);
    return 2.0 * M_PI * I * ((1.0 - cs) + 0.5 * (cs - ce));
}

static double spot_falloff_of_cos(double c, const void *k) { return spot_falloff_ref(k, c); }

/* Every type's `emission` and `power` converted as the format says, the flux Φ, and the flux the emission
 * rays carry; for the spot, also Φ = ∫ I(ω) dω by quadrature over cosθ. */
static void test_flux_and_units(void **state)
{
    (void)state;
    const double r2 = M_PI * 0.25; /* the area of a disc of radius 0.5 */
    double k40 = spot_flux_ref(1.0, 40, 25), k30 = spot_flux_ref(1.0, 30, 5);
    const flux_case cases[] = {
        {"{\"type\": \"point\", \"emission\": [1, 2, 3]}", v3(1, 2, 3), v3_scale(v3(1, 2, 3), 4 * M_PI)},
        {"{\"type\": \"point\", \"power\": [10, 20, 30]}", v3_scale(v3(10, 20, 30), 0.25 / M_PI), v3(10, 20, 30)},
        {"{\"type\": \"spot\", \"emission\": [1, 2, 3], \"coneangle\": 40, \"conedeltaangle\": 25, "
         "\"transform\": {\"look_at\": [0, -1, 0]}}",
         v3(1, 2, 3), v3_scale(v3(1, 2, 3), k40)},
        {"{\"type\": \"spot\", \"power\": [10, 20, 30], \"transform\": {\"look_at\": [0, -1, 0]}}",
         v3_scale(v3(10, 20, 30), 1.0 / k30), v3(10, 20, 30)},
        {"{\"type\": \"collimated\", \"emission\": [1, 2, 3], \"radius\": 0.5}", v3(1, 2, 3), v3_scale(v3(1, 2, 3), r2)},
        {"{\"type\": \"collimated\", \"power\": [1, 2, 3], \"radius\": 0.5}", v3_scale(v3(1, 2, 3), 1.0 / r2), v3(1, 2, 3)},
        {"{\"type\": \"collimated\", \"power\": [1, 2, 3], \"radius\": 0.5, \"divergence\": 10}",
         v3_scale(v3(1, 2, 3), 1.0 / r2), v3(1, 2, 3)},
        {"{\"type\": \"collimated\", \"emission\": [1, 2, 3]}", v3(1, 2, 3), v3(1, 2, 3)},
        {"{\"type\": \"collimated\", \"power\": [1, 2, 3]}", v3(1, 2, 3), v3(1, 2, 3)},
        {"{\"type\": \"directional_point\", \"emission\": [1, 2, 3]}", v3_scale(v3(1, 2, 3), 4 * M_PI),
         v3_scale(v3(1, 2, 3), 4 * M_PI)},
        {"{\"type\": \"directional_point\", \"power\": [1, 2, 3]}", v3(1, 2, 3), v3(1, 2, 3)},
        {"{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": [1, 2, 3], \"transform\": {\"scale\": [2, 1, 3]}}",
         v3(1, 2, 3), v3_scale(v3(1, 2, 3), 6 * M_PI)},
        {"{\"type\": \"quad\", \"bsdf\": \"white\", \"power\": [1, 2, 3], \"transform\": {\"scale\": [2, 1, 3]}}",
         v3_scale(v3(1, 2, 3), 1.0 / (6 * M_PI)), v3(1, 2, 3)},
        {"{\"type\": \"cube\", \"bsdf\": \"white\", \"power\": [1, 2, 3], \"transform\": {\"scale\": 2}}",
         v3_scale(v3(1, 2, 3), 1.0 / (24 * M_PI)), v3(1, 2, 3)},
    };
    int fails = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) fails += check_flux_case(&cases[i]);
    /* the spot's closed form against ∫ I(ω) dω = 2π ∫ falloff(cosθ) dcosθ */
    spot_keys k = {40.0, 25.0};
    double quad = 2.0 * M_PI * integrate(spot_falloff_of_cos, &k, -1.0, 1.0, 400);
    print_message("  spot Φ/I: closed form %.12g, quadrature %.12g\n", k40, quad);
    ASSERT_NEAR(quad, k40, 1e-6 * k40);
    assert_int_equal(fails, 0);
}

/* The spot's default keys are coneangle 30 and conedeltaangle 5. */
static void test_spot_defaults(void **state)
{
    (void)state;
    const emitter *e = light0(load_ok("{\"type\": \"spot\", \"emission\": 1, \"transform\": {\"look_at\": [0, 0, 1]}}"));
    ASSERT_NEAR(e->cos_end, cos(30 * DEG), 1e-12);
    ASSERT_NEAR(e->cos_start, cos(25 * DEG), 1e-12);
    ASSERT_VEC(e->axis, 0, 0, 1, 1e-12);
}

/* ---------------------------------------------------------------- next-event estimation */

/* The mean and standard error of (value/denom)·max(0, wi·nr) over n direct samples from x (the irradiance at
 * a receiver of normal nr); nr = 0 gives the mean of value/denom itself. */
static void nee_mean(const scene *s, const emitter *e, vec3 x, vec3 nr, long n, uint64_t stream, double *mean, double *se)
{
    dp_rng rng = rng_stream(test_seed(), stream, 3);
    double sum = 0.0, sum2 = 0.0;
    int cosine = v3_len(nr) > 0.0;
    for (long k = 0; k < n; k++) {
        double u[2] = {rng_uniform(&rng), rng_uniform(&rng)}, v = 0.0;
        emitter_direct d;
        if (emitter_sample_direct(s, e, x, u, &d)) {
            v = d.value.y / d.denom;
            if (cosine) v *= fmax(0.0, v3_dot(d.wi, nr));
        }
        sum += v;
        sum2 += v * v;
    }
    *mean = sum / n;
    *se = sqrt(fmax(0.0, sum2 / n - *mean * *mean) / (n - 1));
}

/* The view factor from a patch to a parallel a × b rectangle at height h, the patch under one corner. */
static double rect_corner_factor(double a, double b, double h)
{
    double A = a / h, B = b / h, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2.0 * M_PI);
}

/* Irradiance below a parallel square light facing down (side 2 at height 0.8, L = 3), off centre: E = π·L·F,
 * F the sum of the four corner rectangles the receiver's foot splits the square into. */
static void test_nee_quad_irradiance(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 3, \"transform\": "
                             "{\"position\": [0, 0.8, 0], \"scale\": [2, 1, 2], \"rotation\": [180, 0, 0]}}");
    double x0 = 0.3, z0 = -0.4, h = 0.8;
    double F = rect_corner_factor(1 - x0, 1 - z0, h) + rect_corner_factor(1 + x0, 1 - z0, h) +
               rect_corner_factor(1 - x0, 1 + z0, h) + rect_corner_factor(1 + x0, 1 + z0, h);
    double want = M_PI * 3.0 * F, mean, se;
    nee_mean(s, light0(s), v3(x0, 0, z0), v3(0, 1, 0), 1000000, 11, &mean, &se);
    double z = (mean - want) / se;
    print_message("  quad irradiance: NEE %.6f ± %.6f, closed form %.6f, z %.2f\n", mean, se, want, z);
    assert_true(fabs(z) < Z_MAX);
    /* above the light (behind its emitting side) NEE finds nothing */
    nee_mean(s, light0(s), v3(0, 1.5, 0), v3s(0), 1000, 12, &mean, &se);
    ASSERT_NEAR(mean, 0.0, 0.0);
}

/* A spherical light of radius R = 0.5 seen from d = 3 by a receiver facing it: E = π·L·(R/d)². The tessellated
 * sphere (64 rings, 128 segments) is inscribed: its silhouette is within a factor cos(π/128) of R, so E is low
 * by about 6e-4 at most; allowed 2e-3 of E on top of 4σ. */
static void test_nee_sphere_irradiance(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"sphere\", \"bsdf\": \"white\", \"emission\": 2, \"transform\": "
                             "{\"position\": [0.1, 0.2, 0.3], \"scale\": 0.5}}");
    double want = M_PI * 2.0 * (0.5 / 3.0) * (0.5 / 3.0), mean, se;
    vec3 dir = v3_norm(v3(1, -2, 2)), x = v3_add(v3(0.1, 0.2, 0.3), v3_scale(dir, -3.0));
    nee_mean(s, light0(s), x, dir, 1000000, 13, &mean, &se);
    double z = (mean - want) / hypot(se, 2e-3 * want / Z_MAX);
    print_message("  sphere irradiance: NEE %.6f ± %.6f, closed form %.6f (rel %.2e), z incl. budget %.2f\n", mean, se,
                  want, mean / want - 1.0, z);
    assert_true(fabs(z) < Z_MAX);
}

/* Spot NEE: value/denom = I·falloff(θ)/d², by hand at angles inside the inner cone, in the ring and beyond. */
static void test_nee_spot(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"spot\", \"emission\": 5, \"coneangle\": 40, \"conedeltaangle\": 25,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    const emitter *e = light0(s);
    frame f = frame_about(skew_axis());
    vec3 p = v3(0.2, 0.5, -0.3);
    const double deg[] = {0, 10, 14.9, 20, 30, 35, 39.5, 40.5, 60, 120};
    const double d = 2.5, I = 5.0, ce = cos(40 * DEG), cs = cos(15 * DEG);
    for (size_t i = 0; i < sizeof deg / sizeof deg[0]; i++) {
        double th = deg[i] * DEG, ct = cos(th);
        double want = ct >= cs ? 1.0 : ct <= ce ? 0.0 : smoothstep_ref((ct - ce) / (cs - ce));
        want *= I / (d * d);
        vec3 x = v3_add(p, v3_scale(v3_add(v3_scale(f.a, ct), v3_scale(f.b1, sin(th))), d));
        emitter_direct out;
        double u[2] = {0.5, 0.5};
        int ok = emitter_sample_direct(s, e, x, u, &out);
        double got = ok ? out.value.x / out.denom : 0.0;
        print_message("  spot NEE at θ %5.1f°: %.9f, by hand %.9f\n", deg[i], got, want);
        ASSERT_NEAR(got, want, 1e-9);
        assert_int_equal(ok, want > 0.0);
        if (ok) {
            ASSERT_NEAR(out.dist, d, 1e-9);
            ASSERT_NEAR(v3_dot(out.wi, v3_scale(v3_sub(p, x), 1.0 / d)), 1.0, 1e-12);
        }
    }
}

/* The parallel beam (radius 0.5, E = 4): a point inside the half-cylinder sees E along −axis from y = x − s·axis
 * at distance s (no 1/d²); outside the radius, or behind the disc, nothing. */
static void test_nee_parallel_beam(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"collimated\", \"emission\": 4, \"radius\": 0.5,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    const emitter *e = light0(s);
    assert_true(emitter_is_parallel_beam(e));
    frame f = frame_about(skew_axis());
    vec3 p = v3(0.2, 0.5, -0.3);
    const struct { double s, rho; int in; } pts[] = {{2.0, 0.3, 1}, {7.5, 0.49, 1}, {0.01, 0.0, 1}, {2.0, 0.51, 0},
                                                     {-1.0, 0.1, 0}, {3.0, 2.0, 0}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        vec3 perp = v3_add(v3_scale(f.b1, 0.6 * pts[i].rho), v3_scale(f.b2, 0.8 * pts[i].rho));
        vec3 x = v3_add(p, v3_add(v3_scale(f.a, pts[i].s), perp));
        emitter_direct d;
        double u[2] = {0.1, 0.7};
        int ok = emitter_sample_direct(s, e, x, u, &d);
        print_message("  beam NEE at s %.2f, ρ %.2f: %s\n", pts[i].s, pts[i].rho, ok ? "lit" : "dark");
        assert_int_equal(ok, pts[i].in);
        if (!ok) continue;
        ASSERT_NEAR(d.value.x / d.denom, 4.0, 1e-12);
        ASSERT_NEAR(d.dist, pts[i].s, 1e-9);
        ASSERT_VEC(d.wi, -f.a.x, -f.a.y, -f.a.z, 1e-12);
        vec3 y = v3_add(p, perp);
        ASSERT_VEC(d.y, y.x, y.y, y.z, 1e-9);
    }
}

/* Q = ∫_disc L·cosθ_y/|x − y|² [θ_y ≤ δ] dA for a disc of radius r at the origin across +z and x at height h:
 * cosθ_y = h/|x − y|, the cone test is |x⊥ − y| ≤ h·tanδ, so in polar coordinates ρ, φ about x⊥ the radial
 * integral is closed, ∫ h ρ/(ρ² + h²)^{3/2} dρ = 1 − h/sqrt(ρmax² + h²), ρmax(φ) the nearer of the cone's
 * edge and the disc's; the φ integral by a fine midpoint rule (x⊥ inside the disc). */
static double diverging_disc_ref(double L, double r, double delta, vec3 x)
{
    double h = x.z, rc = h * tan(delta), xx = x.x, xy = x.y, q = xx * xx + xy * xy, sum = 0.0;
    const int n = 200000;
    for (int i = 0; i < n; i++) {
        double ph = 2.0 * M_PI * (i + 0.5) / n, b = xx * cos(ph) + xy * sin(ph);
        double rho = fmin(rc, -b + sqrt(b * b - q + r * r));
        sum += 1.0 - h / sqrt(rho * rho + h * h);
    }
    return L * sum * 2.0 * M_PI / n;
}

/* A diverging beam (radius 0.5, δ 20°, E = 2): the mean NEE value against the quadrature of the disc, at a
 * point whose cone of acceptance cuts the disc; and the radius-0 case by hand, I(θ) = Φ·cosθ/(π sin²δ). */
static void test_nee_diverging_beam(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"collimated\", \"emission\": 2, \"radius\": 0.5, \"divergence\": 20,"
                             " \"transform\": {\"look_at\": [0, 0, 1]}}");
    double sd = sin(20 * DEG), L = 2.0 / (M_PI * sd * sd);
    vec3 x = v3(0.35, 0.1, 1.2);
    double want = diverging_disc_ref(L, 0.5, 20 * DEG, x), mean, se;
    nee_mean(s, light0(s), x, v3s(0), 1000000, 14, &mean, &se);
    double z = (mean - want) / se;
    print_message("  diverging beam NEE: %.6f ± %.6f, quadrature %.6f, z %.2f\n", mean, se, want, z);
    assert_true(fabs(z) < Z_MAX);

    const scene *s0 = load_ok("{\"type\": \"collimated\", \"power\": 3, \"divergence\": 20,"
                              " \"transform\": {\"look_at\": [0, 0, 1]}}");
    const double deg[] = {0, 12, 19.5, 20.5, 90};
    for (size_t i = 0; i < sizeof deg / sizeof deg[0]; i++) {
        double th = deg[i] * DEG, d = 1.7;
        double want0 = th <= 20 * DEG ? 3.0 * cos(th) / (M_PI * sd * sd) / (d * d) : 0.0;
        emitter_direct out;
        double u[2] = {0.3, 0.3};
        int ok = emitter_sample_direct(s0, light0(s0), v3(d * sin(th), 0, d * cos(th)), u, &out);
        double got = ok ? out.value.x / out.denom : 0.0;
        print_message("  radius-0 diverging beam at θ %4.1f°: %.9f, by hand %.9f\n", deg[i], got, want0);
        ASSERT_NEAR(got, want0, 1e-9 * (1 + want0));
    }
}

/* ---------------------------------------------------------------- the beam crossing */

typedef struct {
    vec3 p, a;
    double r;
} beam_ref;

static int in_beam(const beam_ref *b, vec3 x)
{
    vec3 w = v3_sub(x, b->p);
    double s = v3_dot(w, b->a);
    vec3 perp = v3_sub(w, v3_scale(b->a, s));
    return s > 0.0 && v3_dot(perp, perp) <= b->r * b->r;
}

#define SCAN 4000

/* One ray against the scan: 0 when they agree within a step. */
static int crossing_agrees(const emitter *e, const beam_ref *b, vec3 o, vec3 d, double tmax, int verbose)
{
    double step = tmax / SCAN, first = -1.0, last = -1.0;
    int inside = 0;
    for (int k = 0; k <= SCAN; k++) {
        double t = k * step;
        if (in_beam(b, v3_add(o, v3_scale(d, t)))) {
            if (!inside++) first = t;
            last = t;
        }
    }
    double t0 = 0, t1 = 0;
    int hit = emitter_beam_crossing(e, o, d, tmax, &t0, &t1);
    int bad;
    if (inside >= 2) bad = !hit || fabs(t0 - first) > 1.01 * step || fabs(t1 - last) > 1.01 * step;
    else if (inside == 0) bad = hit && t1 - t0 > 2.0 * step;
    else bad = 0; /* a single sample at the edge: too close to call */
    if (bad && verbose)
        print_message("  crossing mismatch: o (%.3f %.3f %.3f) d (%.3f %.3f %.3f) tmax %.3f: scan %d samples [%.4f, %.4f],"
                      " crossing %d [%.4f, %.4f]\n", o.x, o.y, o.z, d.x, d.y, d.z, tmax, inside, first, last, hit, t0, t1);
    return bad;
}

/* emitter_beam_crossing against a scan of the ray in SCAN steps with the half-cylinder test written here:
 * random rays, and rays along the axis inside and outside and across it behind the disc. */
static void test_beam_crossing(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"collimated\", \"emission\": 1, \"radius\": 0.7,"
                             " \"transform\": {\"position\": " SKEW_POS ", \"look_at\": " SKEW_AT "}}");
    const emitter *e = light0(s);
    beam_ref b = {v3(0.2, 0.5, -0.3), skew_axis(), 0.7};
    frame f = frame_about(b.a);
    dp_rng rng = rng_stream(test_seed(), 15, 0);
    int bad = 0, hits = 0;
    const int n = 1500;
    for (int k = 0; k < n; k++) {
        vec3 o = v3(4 * rng_uniform(&rng) - 2, 4 * rng_uniform(&rng) - 2, 4 * rng_uniform(&rng) - 2);
        vec3 d = sample_uniform_sphere(rng_uniform(&rng), rng_uniform(&rng));
        double tmax = 0.5 + 5.5 * rng_uniform(&rng), t0, t1;
        bad += crossing_agrees(e, &b, o, d, tmax, bad < 5);
        hits += emitter_beam_crossing(e, o, d, tmax, &t0, &t1);
    }
    /* along the axis from behind the disc, inside: enters at the disc (t = 1); outside: never */
    vec3 o_in = v3_add(b.p, v3_add(v3_scale(b.a, -1.0), v3_scale(f.b1, 0.3)));
    vec3 o_out = v3_add(b.p, v3_add(v3_scale(b.a, -1.0), v3_scale(f.b1, 0.9)));
    int bad_special = crossing_agrees(e, &b, o_in, b.a, 4.0, 1) + crossing_agrees(e, &b, o_out, b.a, 4.0, 1);
    /* across the axis behind the disc (s = −0.5): the half-cylinder does not extend there */
    vec3 o_back = v3_add(b.p, v3_add(v3_scale(b.a, -0.5), v3_scale(f.b1, -2.0)));
    bad_special += crossing_agrees(e, &b, o_back, f.b1, 4.0, 1);
    print_message("  beam crossing: %d random rays (%d cross the beam), %d disagree with the scan; %d of 3 special rays\n",
                  n, hits, bad, bad_special);
    assert_true(hits > n / 10);
    assert_int_equal(bad + bad_special, 0);
    double t0, t1;
    assert_true(emitter_beam_crossing(e, o_in, b.a, 4.0, &t0, &t1));
    ASSERT_NEAR(t0, 1.0, 1e-9);
    ASSERT_NEAR(t1, 4.0, 1e-9);
    assert_false(emitter_beam_crossing(e, o_back, f.b1, 4.0, &t0, &t1));
}

/* ---------------------------------------------------------------- loader: sides, shapes, refusals */

/* The winding normal of the light's first triangle, from the scene's vertices. */
static vec3 first_tri_normal(const scene *s, const emitter *e)
{
    const uint32_t *t = &s->tris[3 * (size_t)e->first_tri];
    vec3 p[3];
    for (int i = 0; i < 3; i++) p[i] = v3(s->verts[3 * (size_t)t[i]], s->verts[3 * (size_t)t[i] + 1], s->verts[3 * (size_t)t[i] + 2]);
    return v3_norm(v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0])));
}

/* A quad emits from its local +y side only: radiance L_e seen from above, 0 from below; NEE from below
 * finds nothing. Checked through a ray hitting it too, so the hit's normal is the scene's own. */
static void test_quad_front_side(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": 7}");
    const emitter *e = light0(s);
    vec3 ng = first_tri_normal(s, e);
    ASSERT_VEC(ng, 0, 1, 0, 1e-9);
    hit_record h;
    assert_true(scene_intersect(s, v3(0.1, 2, 0.1), v3(0, -1, 0), 10.0, &h));
    ASSERT_NEAR(emitter_hit_radiance(e, v3(0, -1, 0), h.ng).x, 7.0, 0.0);
    assert_true(scene_intersect(s, v3(0.1, -2, 0.1), v3(0, 1, 0), 10.0, &h));
    ASSERT_NEAR(emitter_hit_radiance(e, v3(0, 1, 0), h.ng).x, 0.0, 0.0);
    double mean, se;
    nee_mean(s, e, v3(0, -1, 0), v3s(0), 1000, 16, &mean, &se);
    ASSERT_NEAR(mean, 0.0, 0.0);
    nee_mean(s, e, v3(0, 1, 0), v3s(0), 1000, 16, &mean, &se);
    assert_true(mean > 0.0);
}

/* Disk and sphere under a non-uniform scale stay round with Tungsten's radius (the disk: the longer of the x
 * and z columns; the sphere: the longest column): every rim vertex at that radius, the area within the
 * inscribed tessellation's deficit of πr² (a 256-gon: 1 − sin(2π/256)/(2π/256) ≈ 1e-4) or 4πr² (64 rings ×
 * 128 segments: about 4e-4; allowed 1e-3), never above it. */
static void test_disk_sphere_area(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"disk\", \"bsdf\": \"white\", \"emission\": 1,"
                             " \"transform\": {\"position\": [1, 2, 3], \"scale\": [2, 5, 1.5]}},\n"
                             "{\"type\": \"sphere\", \"bsdf\": \"white\", \"emission\": 1,"
                             " \"transform\": {\"position\": [-4, 0, 0], \"scale\": [1, 3, 2]}}");
    assert_int_equal(s->light_count, 2);
    const emitter *disk = &s->lights[0], *sph = &s->lights[1];
    double n = 256, da = 1.0 - sin(2 * M_PI / n) / (2 * M_PI / n), want_d = M_PI * 4.0, want_s = 4 * M_PI * 9.0;
    print_message("  disk area %.6f (πr² %.6f, rel %.2e, budget %.2e); sphere %.6f (4πr² %.6f, rel %.2e)\n", disk->area,
                  want_d, disk->area / want_d - 1, da, sph->area, want_s, sph->area / want_s - 1);
    assert_true(disk->area <= want_d * (1 + 1e-6) && disk->area >= want_d * (1 - 1.05 * da - 1e-6));
    assert_true(sph->area <= want_s * (1 + 1e-6) && sph->area >= want_s * (1 - 1e-3));
    ASSERT_VEC(first_tri_normal(s, disk), 0, 1, 0, 1e-6); /* emits toward +y */
    /* every vertex of the light's triangles at the radius from the centre (the disk's centre vertex aside) */
    const emitter *L[2] = {disk, sph};
    vec3 c[2] = {v3(1, 2, 3), v3(-4, 0, 0)};
    double R[2] = {2.0, 3.0};
    for (int i = 0; i < 2; i++)
        for (uint32_t k = 0; k < 3 * L[i]->tri_count; k++) {
            const float *p = &s->verts[3 * (size_t)s->tris[3 * (size_t)L[i]->first_tri + k]];
            double r = v3_len(v3_sub(v3(p[0], p[1], p[2]), c[i]));
            if (!(r < 1e-6 || fabs(r - R[i]) < 1e-5 * R[i])) fail_msg("light %d: a vertex at %.9g from the centre", i, r);
        }
}

/* The triangles of the light whose winding normal points toward its centre c (inward), out of all. */
static uint32_t inward_triangles(const scene *s, const emitter *e, vec3 c)
{
    uint32_t inward = 0;
    for (uint32_t k = 0; k < e->tri_count; k++) {
        const uint32_t *t = &s->tris[3 * (size_t)(e->first_tri + k)];
        vec3 p[3];
        for (int i = 0; i < 3; i++)
            p[i] = v3(s->verts[3 * (size_t)t[i]], s->verts[3 * (size_t)t[i] + 1], s->verts[3 * (size_t)t[i] + 2]);
        vec3 n = v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0])), g = v3_scale(v3_add(p[0], v3_add(p[1], p[2])), 1.0 / 3);
        inward += v3_dot(n, v3_sub(g, c)) <= 0.0;
    }
    return inward;
}

/* Spheres and cubes emit outward: every triangle's winding normal points away from the centre, and a ray from
 * outside toward the centre sees L_e (the sphere's irradiance test cannot tell: from outside, an inward sphere's
 * far side would show the same silhouette). */
static void test_sphere_cube_outward(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"sphere\", \"bsdf\": \"white\", \"emission\": 2,"
                             " \"transform\": {\"position\": [1, 0, 0], \"scale\": 0.5}},\n"
                             "{\"type\": \"cube\", \"bsdf\": \"white\", \"emission\": 3,"
                             " \"transform\": {\"position\": [-2, 0, 0], \"scale\": 0.8}}");
    assert_int_equal(s->light_count, 2);
    uint32_t in_s = inward_triangles(s, &s->lights[0], v3(1, 0, 0)), in_c = inward_triangles(s, &s->lights[1], v3(-2, 0, 0));
    print_message("  inward triangles: sphere %u of %u, cube %u of %u\n", in_s, s->lights[0].tri_count, in_c,
                  s->lights[1].tri_count);
    assert_int_equal(in_s, 0);
    assert_int_equal(in_c, 0);
    const vec3 from[2] = {v3(1, 3, 0.1), v3(-2, 0.1, -3)}, centre[2] = {v3(1, 0, 0), v3(-2, 0, 0)};
    const double L[2] = {2.0, 3.0};
    for (int i = 0; i < 2; i++) {
        hit_record h;
        vec3 d = v3_norm(v3_sub(centre[i], from[i]));
        assert_true(scene_intersect(s, from[i], d, 10.0, &h));
        ASSERT_NEAR(emitter_hit_radiance(&s->lights[i], d, h.ng).x, L[i], 0.0);
    }
}

/* Bad keys are refused, naming the key. */
static void test_refusals(void **state)
{
    (void)state;
    const struct { const char *prim, *key; } bad[] = {
        {"{\"type\": \"spot\", \"emission\": 1, \"coneangle\": 20, \"conedeltaangle\": 25}", "conedeltaangle"},
        {"{\"type\": \"collimated\", \"emission\": 1, \"radius\": -0.5}", "radius"},
        {"{\"type\": \"point\", \"emission\": 1, \"pulse_width\": 1, \"pulse_shape\": \"triangle\"}", "pulse_shape"},
        {"{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": \"tex.png\"}", "emission"},
        {"{\"type\": \"quad\", \"bsdf\": \"white\", \"emission\": {\"type\": \"checker\"}}", "emission"},
        {"{\"type\": \"point\", \"emission\": 1, \"power\": 1}", "power"},
        {"{\"type\": \"disk\", \"bsdf\": \"white\", \"emission\": 1, \"cone_angle\": 60}", "cone_angle"},
        {"{\"type\": \"point\", \"emission\": -1}", "emission"},
    };
    int fails = 0;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        dp_error err;
        scene *s = load_prims(bad[i].prim, &err);
        int ok = !s && strstr(err.msg, bad[i].key);
        print_message("  %-80s -> %s\n", bad[i].prim, s ? "LOADED" : err.msg);
        if (s) fx_drop(s);
        fails += !ok;
    }
    assert_int_equal(fails, 0);
}

/* ---------------------------------------------------------------- pulses */

#define N_PULSE 400000
#define NPB 40

static double normal_cdf(double z) { return 0.5 * erfc(-z / sqrt(2.0)); }

/* A Gaussian pulse (start 1, width = FWHM 2): χ² in bins against the normal CDF of mean 2 and
 * σ = FWHM/(2·sqrt(2 ln 2)); the share within ±FWHM/2 of the peak, erf(sqrt(ln 2)) ≈ 0.761, by a z test. */
static void test_pulse_gaussian(void **state)
{
    (void)state;
    emitter_pulse pl = {.start = 1.0, .width = 2.0, .shape = PULSE_GAUSSIAN};
    double mu = 2.0, sigma = 2.0 / (2.0 * sqrt(2.0 * log(2.0)));
    chi_cell cells[NPB + 2];
    double lo = mu - 4 * sigma, hi = mu + 4 * sigma;
    for (int i = 0; i < NPB; i++)
        cells[i] = (chi_cell){0.0, N_PULSE * (normal_cdf((lo + (hi - lo) * (i + 1) / NPB - mu) / sigma) -
                                               normal_cdf((lo + (hi - lo) * i / NPB - mu) / sigma))};
    cells[NPB] = (chi_cell){0.0, N_PULSE * normal_cdf(-4.0)};
    cells[NPB + 1] = (chi_cell){0.0, N_PULSE * normal_cdf(-4.0)};
    dp_rng rng = rng_stream(test_seed(), 17, 0);
    long within = 0;
    for (long k = 0; k < N_PULSE; k++) {
        double t = emitter_pulse_sample(&pl, &rng);
        within += fabs(t - mu) < 1.0;
        int i = t < lo ? NPB : t >= hi ? NPB + 1 : (int)fmin(NPB - 1, (t - lo) / (hi - lo) * NPB);
        cells[i].obs += 1.0;
    }
    double chi2;
    int dof;
    double p = chi2_pooled(cells, NPB + 2, &chi2, &dof, NULL);
    double q = erf(sqrt(log(2.0))), frac = (double)within / N_PULSE, z = (frac - q) / sqrt(q * (1 - q) / N_PULSE);
    print_message("  gaussian pulse: p %-9.3g (χ² %.1f, dof %d); within ±FWHM/2 %.5f (want %.5f), z %.2f\n", p, chi2,
                  dof, frac, q, z);
    assert_true(p > ALPHA);
    assert_true(fabs(z) < Z_MAX);
}

/* A box pulse is uniform on [start, start + width); a delta pulse (width 0) is `start` and draws nothing. */
static void test_pulse_box_and_delta(void **state)
{
    (void)state;
    emitter_pulse pl = {.start = 0.5, .width = 3.0, .shape = PULSE_BOX};
    chi_cell cells[NPB + 1];
    for (int i = 0; i < NPB; i++) cells[i] = (chi_cell){0.0, (double)N_PULSE / NPB};
    cells[NPB] = (chi_cell){0.0, 0.0};
    dp_rng rng = rng_stream(test_seed(), 18, 0);
    for (long k = 0; k < N_PULSE; k++) {
        double t = emitter_pulse_sample(&pl, &rng);
        int i = (int)floor((t - 0.5) / 3.0 * NPB);
        cells[i >= 0 && i < NPB && t < 3.5 ? i : NPB].obs += 1.0;
    }
    double chi2;
    int dof;
    long outside;
    double p = chi2_pooled(cells, NPB + 1, &chi2, &dof, &outside);
    print_message("  box pulse: p %-9.3g (χ² %.1f, dof %d), outside [start, start + width) %ld\n", p, chi2, dof, outside);
    assert_int_equal(outside, 0);
    assert_true(p > ALPHA);
    emitter_pulse delta = {.start = 4.25, .width = 0.0, .shape = PULSE_GAUSSIAN};
    dp_rng a = rng_stream(9, 9, 9), b = rng_stream(9, 9, 9);
    ASSERT_NEAR(emitter_pulse_sample(&delta, &a), 4.25, 0.0);
    assert_true(rng_uniform(&a) == rng_uniform(&b));
}

/* The loader reads the pulse keys. */
static void test_pulse_keys(void **state)
{
    (void)state;
    const emitter *e = light0(load_ok("{\"type\": \"point\", \"emission\": 1, \"pulse_start\": 0.25,"
                                      " \"pulse_width\": 1.5, \"pulse_shape\": \"gaussian\"}"));
    ASSERT_NEAR(e->pulse.start, 0.25, 0.0);
    ASSERT_NEAR(e->pulse.width, 1.5, 0.0);
    assert_int_equal(e->pulse.shape, PULSE_GAUSSIAN);
    e = light0(load_ok("{\"type\": \"point\", \"emission\": 1, \"pulse_width\": 1}"));
    assert_int_equal(e->pulse.shape, PULSE_BOX);
}

/* ---------------------------------------------------------------- light selection */

#define N_SEL 200000

/* χ² of emitter_select's choices against the probabilities want[]; each choice's pdf must be want[i]. */
static double chi2_select(const scene *s, int by_power, const double *want, uint64_t stream)
{
    int n = s->light_count;
    chi_cell cells[8];
    for (int i = 0; i < n; i++) cells[i] = (chi_cell){0.0, N_SEL * want[i]};
    dp_rng rng = rng_stream(test_seed(), stream, 0);
    long bad_pdf = 0;
    for (long k = 0; k < N_SEL; k++) {
        double pdf;
        int i = emitter_select(s, rng_uniform(&rng), by_power, &pdf);
        assert_true(i >= 0 && i < n);
        bad_pdf += fabs(pdf - want[i]) > 1e-12;
        cells[i].obs += 1.0;
    }
    double chi2;
    int dof;
    long impossible;
    double p = chi2_pooled(cells, n, &chi2, &dof, &impossible);
    print_message("  selection %s: p %-9.3g (χ² %.1f, dof %d), chosen with zero probability %ld, wrong pdf %ld\n",
                  by_power ? "by power" : "uniform", p, chi2, dof, impossible, bad_pdf);
    for (int i = 0; i < n; i++) ASSERT_NEAR(emitter_selection_pdf(s, i, by_power), want[i], 1e-12);
    assert_int_equal(impossible, 0);
    assert_int_equal(bad_pdf, 0);
    return p;
}

/* Four lights of flux (channel means) 1, 3, 6 and 0: by power, chosen with probabilities 1/10, 3/10, 6/10 and
 * never the black one; uniform, 1/4 each. */
static void test_selection(void **state)
{
    (void)state;
    const scene *s = load_ok("{\"type\": \"point\", \"power\": 1},\n"
                             "{\"type\": \"spot\", \"power\": [1, 3, 5], \"transform\": {\"look_at\": [0, -1, 0]}},\n"
                             "{\"type\": \"quad\", \"bsdf\": \"white\", \"power\": [2, 4, 12]},\n"
                             "{\"type\": \"collimated\", \"power\": 0, \"radius\": 1}");
    assert_int_equal(s->light_count, 4);
    const double by_power[4] = {0.1, 0.3, 0.6, 0.0}, uniform[4] = {0.25, 0.25, 0.25, 0.25};
    assert_true(chi2_select(s, 1, by_power, 19) > ALPHA);
    assert_true(chi2_select(s, 0, uniform, 20) > ALPHA);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_point_directions, teardown_fx),
        cmocka_unit_test_teardown(test_spot_directions, teardown_fx),
        cmocka_unit_test_teardown(test_collimated_directions, teardown_fx),
        cmocka_unit_test_teardown(test_area_directions, teardown_fx),
        cmocka_unit_test_teardown(test_area_positions, teardown_fx),
        cmocka_unit_test_teardown(test_collimated_disc_positions, teardown_fx),
        cmocka_unit_test_teardown(test_flux_and_units, teardown_fx),
        cmocka_unit_test_teardown(test_spot_defaults, teardown_fx),
        cmocka_unit_test_teardown(test_nee_quad_irradiance, teardown_fx),
        cmocka_unit_test_teardown(test_nee_sphere_irradiance, teardown_fx),
        cmocka_unit_test_teardown(test_nee_spot, teardown_fx),
        cmocka_unit_test_teardown(test_nee_parallel_beam, teardown_fx),
        cmocka_unit_test_teardown(test_nee_diverging_beam, teardown_fx),
        cmocka_unit_test_teardown(test_beam_crossing, teardown_fx),
        cmocka_unit_test_teardown(test_quad_front_side, teardown_fx),
        cmocka_unit_test_teardown(test_disk_sphere_area, teardown_fx),
        cmocka_unit_test_teardown(test_sphere_cube_outward, teardown_fx),
        cmocka_unit_test_teardown(test_refusals, teardown_fx),
        cmocka_unit_test_teardown(test_pulse_gaussian, teardown_fx),
        cmocka_unit_test_teardown(test_pulse_box_and_delta, teardown_fx),
        cmocka_unit_test_teardown(test_pulse_keys, teardown_fx),
        cmocka_unit_test_teardown(test_selection, teardown_fx),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
