/* tier: quick */
/* The surface version of the directions toward the next elliptical connection (include/dartspp/darts.h,
 * src/darts/ellipse_direction_surface.c; docs/darts.md §14.4): ellipse_direction_surface_sample mixes the
 * ellipse sampler (share c) with the BSDF's sampler and weighs f·|cos|/(c·p_ell + (1 − c)·p_bsdf).
 *  a. unbiased: for a smooth positive g(ω), the mean of weight·g over the mixture's samples equals the mean of
 *     weight·g over the BSDF sampler alone (surface_sample_bsdf: f·|cos|/p_bsdf, whose pdf and weight
 *     tests/bsdf/test_bsdf.c checks against bsdf_pdf and χ²), per channel, |z| < 4.5 (two-sided p ≈ 7e-6,
 *     Bonferroni over 7 cases × 3 channels); on Lambert, rough plastic (glossy + diffuse lobes), a peaked rough
 *     conductor and a rough dielectric (transmission, the light behind the surface), at shares 0.3 / 0.5 /
 *     0.8 / 1 (asymmetric shares: a swap of c and 1 − c must show), T well above C and T close to C;
 *  b. surface_pdf is the density of surface_sample_bsdf: ∫ g·p_bsdf dω by the sampler (mean of g over its
 *     samples, counting failures as 0) against a quadrature of g·surface_pdf over the sphere;
 *  c. share 0 (and T <= C(1 + 1e-6), where the ellipse sampler does not run) gives the BSDF sample itself.
 * It prints the share of the ellipse sampler's directions lost below an opaque surface (weight 0).
 * Broken variants (tests/README.md, "Figures"): the weight without the BSDF pdf term (f·cos/(c·p_ell));
 * the ellipse pdf at the wrong T (1.05 T); the shares swapped in the mixture pdf. */
#include "fixtures.h"

#include "dartspp/darts.h"

#define N_SAMPLES 400000L
#define Z_MAX 4.5

typedef struct {
    const char *name;
    bsdf_type type;
    double roughness, share, T, C;
    vec3 albedo;
    double cos_in;   /* cosθ of the arriving direction's reverse (ω_i) against the normal */
    double target_z; /* the target's height over the surface in units of C: < 0 behind it */
} surf_case;

#define N_CASES 7
static const surf_case cases[N_CASES] = {
    {"lambert, c 0.5, T 3 C 1", BSDF_LAMBERT, 0.0, 0.5, 3.0, 1.0, {0.7, 0.5, 0.2}, 0.6, 0.5},
    {"lambert, c 1, T 1.3 C 1, light low", BSDF_LAMBERT, 0.0, 1.0, 1.3, 1.0, {0.7, 0.5, 0.2}, 0.9, 0.1},
    {"lambert, c 0.3, T 1.05 C 1, light behind", BSDF_LAMBERT, 0.0, 0.3, 1.05, 1.0, {0.6, 0.6, 0.6}, 0.4, -0.3},
    {"rough plastic 0.3, c 0.3, T 2 C 1", BSDF_ROUGH_PLASTIC, 0.3, 0.3, 2.0, 1.0, {0.7, 0.15, 0.1}, 0.5, 0.7},
    {"rough plastic 0.3, c 0.8, T 1.2 C 1", BSDF_ROUGH_PLASTIC, 0.3, 0.8, 1.2, 1.0, {0.2, 0.6, 0.3}, 0.8, 0.4},
    {"rough conductor 0.1, c 0.8, T 1.5 C 1", BSDF_ROUGH_CONDUCTOR, 0.1, 0.8, 1.5, 1.0, {1, 1, 1}, 0.7, 0.6},
    {"rough dielectric 0.3, c 0.5, T 1.4 C 1, behind", BSDF_ROUGH_DIELECTRIC, 0.3, 0.5, 1.4, 1.0, {1, 1, 1}, 0.6, -0.7},
};

static const vec3 P = {0.3, -1.2, 0.8};
static const vec3 NORMAL = {0.267261241912424, 0.534522483824849, 0.801783725737273}; /* (1, 2, 3)/√14 */

typedef struct {
    bsdf b;
    surface_site ss;
    vec3 target;
} site_setup;

static void setup_case(const surf_case *c, site_setup *s)
{
    bsdf_defaults(&s->b, c->type);
    s->b.albedo = c->albedo;
    if (c->roughness > 0.0) s->b.roughness = c->roughness;
    dp_error err;
    if (bsdf_prepare(&s->b, &err)) fail_msg("bsdf_prepare: %s", err.msg);
    vec3 t1, t2;
    v3_basis(NORMAL, &t1, &t2);
    double si = sqrt(1.0 - c->cos_in * c->cos_in);
    vec3 wi = v3_add(v3_scale(NORMAL, c->cos_in), v3_scale(t1, si)); /* toward the previous vertex */
    surface_site *ss = &s->ss;
    memset(ss, 0, sizeof *ss);
    ss->b = &s->b;
    ss->albedo = c->albedo;
    ss->p = P;
    ss->ng_hit = NORMAL;
    bsdf_frame_init(&ss->fr, &s->b, NORMAL, NORMAL, v3_neg(wi), 0);
    ss->wi_world = wi;
    ss->wi = bsdf_to_local(&ss->fr, wi);
    /* the target at distance C, its height over the surface target_z·C, to the side of ω_i's reflection */
    double h = c->target_z, side = sqrt(1.0 - h * h);
    s->target = v3_add(P, v3_scale(v3_add(v3_scale(NORMAL, h), v3_scale(t2, side)), c->C));
}

/* A smooth positive test function, not symmetric about the normal or the target. */
static double g_of(vec3 w)
{
    double a = v3_dot(w, v3_norm(v3(0.5, -0.3, 0.8))), b = v3_dot(w, v3_norm(v3(-0.2, 0.9, 0.1)));
    return 1.0 + 0.8 * a + 0.6 * b * b;
}

typedef struct {
    double s[3], s2[3];
    long n;
} moments;

static void add(moments *m, vec3 v)
{
    for (int k = 0; k < 3; k++) {
        double x = v3_comp(v, k);
        m->s[k] += x;
        m->s2[k] += x * x;
    }
}

static void mean_se(const moments *m, int k, double *mean, double *se)
{
    *mean = m->s[k] / m->n;
    double var = m->s2[k] / m->n - *mean * *mean;
    *se = sqrt(fmax(var, 0.0) / m->n);
}

/* a. the mixture's estimate of ∫ f·|cos|·g against the BSDF sampler's */
static void test_mixture_unbiased(void **state)
{
    (void)state;
    for (int i = 0; i < N_CASES; i++) {
        const surf_case *c = &cases[i];
        site_setup s;
        setup_case(c, &s);
        moments mix = {.n = N_SAMPLES}, ref = {.n = N_SAMPLES};
        long ell = 0, lost = 0;
        dp_rng rng = rng_stream(0x5eedu, 1, (uint64_t)i);
        for (long j = 0; j < N_SAMPLES; j++) {
            double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
            surface_sample smp;
            int from_ell = u[0] < c->share;
            ell += from_ell;
            if (ellipse_direction_surface_sample(&s.ss, P, s.target, c->T, c->share, u, &smp)) {
                assert_true(fabs(v3_len(smp.w) - 1.0) < 1e-9);
                assert_false(smp.lobe & BSDF_LOBE_SPECULAR);
                add(&mix, v3_scale(smp.weight, g_of(smp.w)));
            } else if (from_ell) {
                lost++;
            }
            double v[3] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
            if (surface_sample_bsdf(&s.ss, v, BSDF_LOBES_ALL, 0, &smp)) add(&ref, v3_scale(smp.weight, g_of(smp.w)));
        }
        double zmax = 0.0;
        for (int k = 0; k < 3; k++) {
            double mm, sm, mr, sr;
            mean_se(&mix, k, &mm, &sm);
            mean_se(&ref, k, &mr, &sr);
            zmax = fmax(zmax, fabs(mm - mr) / sqrt(sm * sm + sr * sr));
            if (k == 0)
                print_message("  %-48s mixture %.5f (se %.1e) BSDF %.5f (se %.1e); ellipse directions lost %.1f %%",
                              c->name, mm, sm, mr, sr, ell ? 100.0 * lost / ell : 0.0);
        }
        print_message("; max |z| %.2f\n", zmax);
        assert_true(zmax < Z_MAX);
    }
}

/* b. ∫ g·surface_pdf dω (quadrature in cosθ about the shading normal and φ, Gauss–Legendre panels, finer near
 * the specular direction's cosθ) against the mean of g over the BSDF sampler's samples (failed samples as 0). */
static void test_surface_pdf(void **state)
{
    (void)state;
    static const double gx[4] = {-0.861136311594053, -0.339981043584856, 0.339981043584856, 0.861136311594053};
    static const double gw[4] = {0.347854845137454, 0.652145154862546, 0.652145154862546, 0.347854845137454};
    for (int i = 0; i < N_CASES; i++) {
        site_setup s;
        setup_case(&cases[i], &s);
        const bsdf_frame *fr = &s.ss.fr;
        double quad = 0.0;
        const int NMU = 400, NPH = 128;
        for (int a = 0; a < NMU; a++) {
            for (int qa = 0; qa < 4; qa++) {
                double mu = -1.0 + (a + 0.5 * (gx[qa] + 1.0)) * 2.0 / NMU, st = sqrt(fmax(0.0, 1.0 - mu * mu));
                for (int b = 0; b < NPH; b++) {
                    for (int qb = 0; qb < 4; qb++) {
                        double phi = (b + 0.5 * (gx[qb] + 1.0)) * 2.0 * M_PI / NPH;
                        vec3 w = bsdf_to_world(fr, v3(st * cos(phi), st * sin(phi), mu));
                        double wt = gw[qa] * gw[qb] * (1.0 / NMU) * (M_PI / NPH);
                        quad += wt * g_of(w) * surface_pdf(&s.ss, w, BSDF_LOBES_ALL);
                    }
                }
            }
        }
        double sum = 0.0, sum2 = 0.0;
        dp_rng rng = rng_stream(0x5eedu, 2, (uint64_t)i);
        for (long j = 0; j < N_SAMPLES; j++) {
            double v[3] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
            surface_sample smp;
            double x = surface_sample_bsdf(&s.ss, v, BSDF_LOBES_ALL, 0, &smp) ? g_of(smp.w) : 0.0;
            sum += x, sum2 += x * x;
        }
        double mean = sum / N_SAMPLES, se = sqrt(fmax(0.0, sum2 / N_SAMPLES - mean * mean) / N_SAMPLES);
        double z = fabs(mean - quad) / sqrt(se * se + 1e-5 * 1e-5);
        print_message("  %-48s quadrature %.5f sampler %.5f (se %.1e) |z| %.2f\n", cases[i].name, quad, mean, se, z);
        assert_true(z < Z_MAX);
    }
}

static int same(vec3 a, vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* c. share 0, and T too close to C: the BSDF's own sample, bit for bit. */
static void test_degenerate_share(void **state)
{
    (void)state;
    site_setup s;
    setup_case(&cases[3], &s);
    dp_rng rng = rng_stream(0x5eedu, 3, 0);
    for (int j = 0; j < 1000; j++) {
        double u[4] = {rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng), rng_uniform(&rng)};
        surface_sample a, b, d;
        int oa = ellipse_direction_surface_sample(&s.ss, P, s.target, 2.0, 0.0, u, &a);
        int ob = surface_sample_bsdf(&s.ss, u + 1, BSDF_LOBES_ALL, 0, &b);
        int od = ellipse_direction_surface_sample(&s.ss, P, s.target, 1.0 + 1e-7, 0.7, u, &d); /* C = 1 */
        assert_int_equal(oa, ob);
        assert_int_equal(od, ob);
        if (!ob) continue;
        assert_true(same(a.w, b.w) && same(d.w, b.w) && same(a.weight, b.weight) && same(d.weight, b.weight));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mixture_unbiased),
        cmocka_unit_test(test_surface_pdf),
        cmocka_unit_test(test_degenerate_share),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
