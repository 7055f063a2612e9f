/* The surface module (include/dartspp/surface_site.h) and what only whole renders show of it:
 * 1. the gather/continue rule of photon points, per BSDF;
 * 2. path time through a dielectric: the region's refractive index counts, not the BSDF's ior (our decision,
 *    the reference's convention), for the path tracer and photon points, against the geometry;
 * 3. the adjoint of refraction: a light inside a glass block lighting a floor outside it, where the path
 *    tracer and photon points agree only if light paths take (η_i/η_o)² at each refraction.
 * Broken variants, run by hand on 2026-11-23 (16 + 16 renders):
 * - bsdf_adjoint_scale returning 1 (the reference's choice): floor total of photon points −54.9 % against the
 *   path tracer (bound 9.4 %), image total −16.0 %: test 3 fails. With it: floor +1.5 %, image −0.7 %.
 * - the sensor pass without next-event estimation at continued glossy lobes (direct_light): the light seen
 *   through the rough glass is missing, image total −59 %: test 3 fails.
 * - the interior's time taken from the ior instead of the region: the no-medium case would put its energy
 *   where the medium case does (frame 15, not 10): test 2 fails. */
#include "test_util.h"

#include "dartspp/render.h"
#include "dartspp/surface_site.h"

static void load_text(const char *text, char **dir, scene *s)
{
    *dir = test_tmpdir();
    assert_non_null(*dir);
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", *dir);
    test_write_file(path, text);
    dp_error err;
    scene_load_options lo = {0};
    if (scene_load(path, &lo, s, &err)) fail_msg("%s", err.msg);
}

/* ---- 1. the rule ---- */

static void test_photon_split_rule(void **state)
{
    (void)state;
    surface_shading sh = {.two_sided = 1, .glossy_gather_alpha = 0.1};
    struct {
        bsdf_type type;
        double roughness;
        unsigned gather, cont;
    } cases[] = {
        {BSDF_LAMBERT, 0, BSDF_LOBE_DIFFUSE, 0},
        {BSDF_MIRROR, 0, 0, BSDF_LOBE_SPECULAR},
        {BSDF_CONDUCTOR, 0, 0, BSDF_LOBE_SPECULAR},
        {BSDF_ROUGH_CONDUCTOR, 0.2, BSDF_LOBE_GLOSSY, 0},
        {BSDF_ROUGH_CONDUCTOR, 0.1, BSDF_LOBE_GLOSSY, 0},  /* α = threshold: gathered */
        {BSDF_ROUGH_CONDUCTOR, 0.05, 0, BSDF_LOBE_GLOSSY}, /* smoother: continued */
        {BSDF_PLASTIC, 0, BSDF_LOBE_DIFFUSE, BSDF_LOBE_SPECULAR},
        {BSDF_ROUGH_PLASTIC, 0.3, BSDF_LOBE_DIFFUSE | BSDF_LOBE_GLOSSY, 0},
        {BSDF_ROUGH_PLASTIC, 0.02, BSDF_LOBE_DIFFUSE, BSDF_LOBE_GLOSSY},
        {BSDF_PBRT_PLASTIC, 0.1, BSDF_LOBE_DIFFUSE | BSDF_LOBE_GLOSSY, 0},
        {BSDF_DIELECTRIC, 0, 0, BSDF_LOBE_SPECULAR},
        {BSDF_ROUGH_DIELECTRIC, 0.5, 0, BSDF_LOBE_GLOSSY}, /* transmissive: always continued */
        {BSDF_FORWARD, 0, 0, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bsdf b;
        dp_error err;
        bsdf_defaults(&b, cases[i].type);
        if (cases[i].roughness > 0) b.roughness = cases[i].roughness;
        snprintf(b.name, sizeof b.name, "case%zu", i);
        if (bsdf_prepare(&b, &err)) fail_msg("%s", err.msg);
        photon_split sp = surface_photon_split(&b, &sh);
        print_message("  %-16s roughness %-5g gather %u continue %u\n", bsdf_type_name(b.type), cases[i].roughness,
                      sp.gather, sp.cont);
        assert_int_equal(sp.gather, cases[i].gather);
        assert_int_equal(sp.cont, cases[i].cont);
        assert_int_equal(sp.gather | sp.cont, bsdf_lobes(&b));
        assert_int_equal(sp.gather & sp.cont, 0);
    }
    sh.glossy_gather_alpha = 0; /* the reference: every glossy reflection gathered */
    bsdf b;
    dp_error err;
    bsdf_defaults(&b, BSDF_ROUGH_CONDUCTOR);
    b.roughness = 0.01;
    assert_int_equal(bsdf_prepare(&b, &err), 0);
    assert_int_equal(surface_photon_split(&b, &sh).gather, BSDF_LOBE_GLOSSY);
}

/* ---- 2. time through a dielectric ---- */

/* Camera at the origin looking along +z through a glass slab (z in [1, 1.5], ior 1.5) at a Lambertian wall at
 * z = 3.02, lit by a point light at z = 2.5 between slab and wall. A ray at normal incidence takes
 * 1 + 0.5·η_slab + 1.52 to the wall and the light is 0.52 from it: 3.54 with η_slab = 1 (no medium inside:
 * the ior does not set the speed) and 3.79 with an interior medium of speed_of_light 1/1.5. 2 × 2 pixels over
 * a field of 1°: the extra length of oblique rays is below 2e-4. Frames of 0.05 from 3.0: frame 10 or 15. */
static void slab_text(char *text, size_t len, const char *interior, const char *integrator)
{
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"glassfill\", \"type\": \"homogeneous\", \"sigma_s\": 0, \"sigma_a\": 0,"
             "    \"speed_of_light\": 0.6666666666666666 } ],"
             "  \"bsdfs\": [ { \"name\": \"glass\", \"type\": \"dielectric\", \"ior\": 1.5 },"
             "              { \"name\": \"wall\", \"type\": \"lambert\", \"albedo\": 0.8 } ],"
             "  \"primitives\": ["
             "    { \"type\": \"cube\", \"bsdf\": \"glass\"%s,"
             "      \"transform\": { \"position\": [0, 0, 1.25], \"scale\": [20, 20, 0.5] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"wall\", \"transform\": { \"position\": [0, 0, 3.02],"
             "      \"scale\": [20, 1, 20], \"rotation\": [-90, 0, 0] } },"
             "    { \"type\": \"point\", \"emission\": [1, 1, 1], \"transform\": { \"position\": [0, 0, 2.5] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [2, 2], \"fov\": 1,"
             "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s, \"frame_num\": 20, \"start_time\": 3.0, \"transient_time_width\": 0.05,"
             "    \"max_bounces\": 8 },"
             "  \"renderer\": { \"spp\": 1 } }",
             interior, integrator);
}

/* Fraction of the image's energy (all frames, all channels) in frame k. */
static double frame_share(const film *f, int k)
{
    size_t npx = (size_t)f->width * f->height;
    double all = 0, in = 0;
    for (int m = 0; m < f->window.frame_count; m++)
        for (size_t i = 0; i < 3 * npx; i++) {
            double v = f->frame_sum[(size_t)m * 3 * npx + i];
            all += v;
            if (m == k) in += v;
        }
    assert_true(all > 0);
    return in / all;
}

static void time_case(const char *interior, const char *integrator, int frame)
{
    char text[4096], *dir;
    slab_text(text, sizeof text, interior, integrator);
    scene s;
    load_text(text, &dir, &s);
    film f;
    render_stats st;
    dp_error err;
    render_options ro = {.threads = 2, .seed = 5, .spp = 16};
    if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    double share = frame_share(&f, frame);
    print_message("  %s, %s: %.4f of the energy in frame %d\n", interior[0] ? "medium inside" : "no medium inside",
                  strstr(integrator, "path_tracer") ? "path tracer" : "photon points", share, frame);
    /* the rest is internal reflections (F ≈ 0.04 per face), arriving later */
    assert_true(share > 0.9);
    film_free(&f);
    scene_free(&s);
    test_rmtree(dir);
}

static void test_time_through_dielectric(void **state)
{
    (void)state;
    const char *pt = "\"type\": \"path_tracer\"";
    const char *pp = "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                     " \"photon_count\": 20000, \"volume_photon_count\": 1000, \"gather_photon_count\": 32,"
                     " \"gather_radius\": 0.05, \"volume_gather_radius\": 0.05, \"enable_guiding\": false,"
                     " \"enable_elliptical\": false";
    time_case("", pt, 10);
    time_case(", \"int_medium\": \"glassfill\"", pt, 15);
    time_case("", pp, 10);
    time_case(", \"int_medium\": \"glassfill\"", pp, 15);
}

/* ---- 3. the adjoint of refraction ---- */

/* A glass cube (side 0.6, lifted 0.2 above the floor, ior 1.5) filled with fog, a point light inside it (in a
 * vacuum bubble of side 0.2: a fog vertex at distance d from a point light adds ∝ 1/d² to the path tracer,
 * whose second moment diverges without the bubble), a Lambertian floor outside, the camera in vacuum. All light reaches the floor through the glass. The path
 * tracer gets it as floor → BSDF sample → refraction into the glass → fog vertex → next-event estimation to
 * the light; photon points as photons refracted out of the glass onto the floor. Camera paths carry
 * radiance / η² (weight 1 − F per refraction); light paths must take the adjoint, (η_i/η_o)² = 2.25 on the way
 * out, or the floor's photons are 2.25 times too dim against the path tracer (the reference's behaviour). */
static void glass_text(char *text, size_t len, const char *glass, const char *integrator)
{
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 1.5, \"sigma_a\": 0.1 } ],"
             "  \"bsdfs\": [ { \"name\": \"glass\", %s },"
             "              { \"name\": \"floor\", \"type\": \"lambert\", \"albedo\": 0.7 } ],"
             "  \"primitives\": ["
             "    { \"type\": \"cube\", \"bsdf\": \"glass\", \"int_medium\": \"fog\","
             "      \"transform\": { \"position\": [0, 0.5, 0], \"scale\": [0.6, 0.6, 0.6] } },"
             "    { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"ext_medium\": \"fog\","
             "      \"transform\": { \"position\": [0.05, 0.5, 0.02], \"scale\": [0.2, 0.2, 0.2] } },"
             "    { \"type\": \"quad\", \"bsdf\": \"floor\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [3, 1, 3] } },"
             "    { \"type\": \"point\", \"emission\": [1, 1, 1], \"transform\": { \"position\": [0.05, 0.5, 0.02] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [16, 16], \"fov\": 60,"
             "    \"transform\": { \"position\": [0, 1.6, -1.6], \"look_at\": [0, 0.1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s, \"max_bounces\": 8 },"
             "  \"renderer\": { \"spp\": 1 } }",
             glass, integrator);
}

/* Per-render means of the image total and of the bottom four rows (floor only: the glass cube covers rows
 * 5 to 11 at most), over `runs` renders of `passes` passes. */
static void glass_totals(const char *glass, const char *integrator, int runs, long passes, double mean[2], double se[2])
{
    char text[4096], *dir;
    glass_text(text, sizeof text, glass, integrator);
    scene s;
    load_text(text, &dir, &s);
    double sum[2] = {0, 0}, sum2[2] = {0, 0};
    for (int r = 0; r < runs; r++) {
        film f;
        render_stats st;
        dp_error err;
        render_options ro = {.threads = 2, .seed = 100 + (uint64_t)r, .spp = passes};
        if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
        assert_int_equal(st.nonfinite, 0);
        double t[2] = {0, 0};
        for (int y = 0; y < f.height; y++)
            for (int x = 0; x < f.width; x++)
                for (int c = 0; c < 3; c++) {
                    double v = f.sum[3 * ((size_t)y * f.width + x) + c] / f.weight_sum;
                    t[0] += v;
                    if (y >= f.height - 4) t[1] += v;
                }
        for (int k = 0; k < 2; k++) {
            sum[k] += t[k];
            sum2[k] += t[k] * t[k];
        }
        film_free(&f);
    }
    for (int k = 0; k < 2; k++) {
        mean[k] = sum[k] / runs;
        se[k] = sqrt(fmax(0.0, (sum2[k] - runs * mean[k] * mean[k]) / (runs - 1)) / runs);
    }
    scene_free(&s);
    test_rmtree(dir);
}

static void adjoint_case(const char *glass)
{
    const char *pt = "\"type\": \"path_tracer\"";
    const char *pp = "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                     " \"photon_count\": 20000, \"volume_photon_count\": 40000, \"gather_photon_count\": 32,"
                     " \"gather_radius\": 0.04, \"volume_gather_radius\": 0.02, \"enable_guiding\": false,"
                     " \"enable_elliptical\": false";
    double mt[2], st[2], mp[2], sp[2];
    glass_totals(glass, pt, 16, 256, mt, st);
    glass_totals(glass, pp, 16, 24, mp, sp);
    const char *what[2] = {"image", "floor"};
    for (int k = 0; k < 2; k++)
        print_message("  %s: %s total, path tracer %.5g (se %.2g), photon points %.5g (se %.2g): %+.2f %%\n", glass,
                      what[k], mt[k], st[k], mp[k], sp[k], 100 * (mp[k] - mt[k]) / mt[k]);
    for (int k = 0; k < 2; k++) {
        double sd = sqrt(st[k] * st[k] + sp[k] * sp[k]), b = 0.03 * mt[k];
        print_message("  %s: %s total, path tracer %.5g (se %.2g), photon points %.5g (se %.2g): %+.2f %%, bound %.2f %%\n",
                      glass, what[k], mt[k], st[k], mp[k], sp[k], 100 * (mp[k] - mt[k]) / mt[k], 100 * (4 * sd + b) / mt[k]);
        /* z = 4 over 8 + 8 renders, and a kernel-bias budget of 3 %: the surface disc (R <= 0.04) and the
         * volume kernel (r <= 0.02) against a cube of side 0.6 and a floor image without edges in view. The
         * broken adjoint is off by a factor 2.25 on the floor. */
        assert_true(4 * sd + b < 0.15 * mt[k]);
        assert_true(fabs(mp[k] - mt[k]) < 4 * sd + b);
    }
}

static void test_adjoint_refraction(void **state)
{
    (void)state;
    adjoint_case("\"type\": \"rough_dielectric\", \"ior\": 1.5, \"roughness\": 0.3, \"distribution\": \"ggx\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_photon_split_rule),
        cmocka_unit_test(test_time_through_dielectric),
        cmocka_unit_test(test_adjoint_refraction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
