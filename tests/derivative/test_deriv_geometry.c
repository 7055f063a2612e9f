/* Translations (docs/derivatives.md §6) against central finite differences with common random numbers, per
 * image tile and on the total (the z-test of tests/derivative/test_deriv_fd.c): a fog cube (a closed forward
 * surface) lit by a point light outside it, seen by a pinhole camera outside it; the camera moving, the light
 * moving, a large wall moving along its normal, and a small occluder moving between the light and the wall —
 * out of the camera's view, its shadow in the fog and on the wall in view — with the boundary terms and, as
 * the broken variant, without them (DARTSPP_DERIV_NO_BOUNDARY); and linearity ∂I/∂θ_x + ∂I/∂θ_y = ∂I/∂θ_(x+y)
 * (Yi et al. 2021 Fig. 7) for the occluder. The finite difference is Richardson-extrapolated with a truncation
 * budget (fd_compare). Default tier: the refusals, linearity, the camera along z and the occluder along y
 * (plain path tracer, 100 and 300 passes); test_deriv_geometry_stress.c: everything, every integrator. */
#include "fixtures.h"
#include "render_fixtures.h"

#ifndef GEO_FULL
#define GEO_FULL 0 /* tests/derivative/test_deriv_geometry_stress.c: 1 */
#endif

#include "dartspp/derivative.h"

enum { T_CAMERA, T_LIGHT, T_WALL, T_OCCLUDER };

typedef struct {
    int wall, occluder, max_bounces, sphere;
    vec3 cam, light, occ; /* positions */
    double wall_z;
    const char *integrator;
} geo_scene;

static void scene_text(char *text, size_t n, const geo_scene *g)
{
    char prims[2048] = "";
    size_t at = 0;
    if (g->wall)
        at += (size_t)snprintf(prims + at, sizeof prims - at,
                               "{ \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, %.17g],"
                               " \"scale\": [6, 1, 6], \"rotation\": [-90, 0, 0] } },", g->wall_z);
    if (g->occluder)
        at += (size_t)snprintf(prims + at, sizeof prims - at,
                               "{ \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [%.17g, %.17g, %.17g],"
                               " \"scale\": [0.5, 1, 0.5] } },", g->occ.x, g->occ.y, g->occ.z);
    if (g->sphere) /* smooth: refused */
        at += (size_t)snprintf(prims + at, sizeof prims - at,
                               "{ \"type\": \"sphere\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, -3, 0],"
                               " \"scale\": 0.5 } },");
    snprintf(text, n,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": %.17g, \"sigma_a\": %.17g,"
             "    \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.3 } } ],"
             "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.7 },"
             "               { \"name\": \"boundary\", \"type\": \"forward\" } ],"
             "  \"primitives\": [ { \"type\": \"cube\", \"bsdf\": \"boundary\", \"int_medium\": \"fog\","
             "      \"transform\": { \"position\": [0, 1, 0], \"scale\": [3, 3, 3] } }, %s"
             "    { \"type\": \"point\", \"power\": 30, \"pulse_start\": 0.2, \"pulse_width\": 0.6,"
             "      \"transform\": { \"position\": [%.17g, %.17g, %.17g] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 30,"
             "    \"transform\": { \"position\": [%.17g, %.17g, %.17g], \"look_at\": [%.17g, %.17g, %.17g],"
             "      \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\", \"max_bounces\": %d, \"transient_time_center\": 7,"
             "    \"transient_time_width\": 6 %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             getenv("GEO_SS") ? atof(getenv("GEO_SS")) : 0.35, getenv("GEO_SA") ? atof(getenv("GEO_SA")) : 0.05, prims, g->light.x, g->light.y, g->light.z, g->cam.x, g->cam.y, g->cam.z, g->cam.x, g->cam.y, g->cam.z + 1.0, getenv("GEO_MB") ? atoi(getenv("GEO_MB")) : g->max_bounces, g->integrator);
}

static const char *const integrator_keys[] = {"", ", " DARTS_KEYS_TEXT, ", \"time_sampling\": \"uniform\""};


static int integrator_index(void)
{
    return getenv("GEO_INT") ? atoi(getenv("GEO_INT")) % 3 : 0;
}

static geo_scene base_scene(void)
{
    return (geo_scene){.wall = 1, .occluder = 0, .max_bounces = 2, .cam = {0, 1, -3}, .light = {0, 3.4, -0.5},
                       .occ = {0, 2.3, 0.37}, .wall_z = 1.0, .integrator = integrator_keys[integrator_index()]};
}

typedef deriv_tiles fd_probe; /* render_fixtures.h: per pass the gate image's tiles, then each derivative's */

static void geo_probe(const geo_scene *g, const diff_param *dp, int nd, long passes, fd_probe *t)
{
    static char text[8192];
    scene_text(text, sizeof text, g);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    for (int k = 0; k < nd; k++) {
        s.diffs[k] = dp[k];
        snprintf(s.diffs[k].pointer, sizeof s.diffs[k].pointer, "/test/%d", k);
    }
    s.diff_count = nd;
    deriv_tiles_render(&s, nd, passes, 11, t, NULL);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* z of the mean of per-pass differences after a bias budget b: max(0, |mean| − b)/se */
static double z_budget(double s1, double s2, long n, double b)
{
    double m = s1 / n, se = sqrt(fmax(0.0, (s2 - n * m * m) / (n - 1)) / n), ex = fmax(0.0, fabs(m) - b);
    return se > 0 ? ex / se : (ex == 0 ? 0 : INFINITY);
}

static geo_scene moved(geo_scene g, int what, vec3 axis, double eps)
{
    switch (what) {
    case T_CAMERA: g.cam = v3_add(g.cam, v3_scale(axis, eps)); break;
    case T_LIGHT: g.light = v3_add(g.light, v3_scale(axis, eps)); break;
    case T_WALL: g.wall_z += eps * axis.z; break;
    default: g.occ = v3_add(g.occ, v3_scale(axis, eps)); break;
    }
    return g;
}

static diff_param param_of(const geo_scene *g, int what, vec3 axis)
{
    diff_param q = {.kind = DIFF_TRANSLATE, .index = -1, .light = -1, .first_surface = -1, .axis = axis};
    if (what == T_CAMERA) q.target = DIFF_TARGET_CAMERA;
    if (what == T_LIGHT) q.target = DIFF_TARGET_LIGHT, q.light = 0;
    if (what == T_WALL) q.target = DIFF_TARGET_SURFACES, q.first_surface = 1, q.surface_count = 1;
    if (what == T_OCCLUDER) q.target = DIFF_TARGET_SURFACES, q.first_surface = 1 + g->wall, q.surface_count = 1;
    return q;
}

/* The finite difference's truncation (docs/derivatives.md §6.5): central differences at ε and 2ε on common
 * random numbers, FD(ε) = I' + c·ε² + O(ε⁴), so Richardson's R = (4·FD(ε) − FD(2ε))/3 = I' + O(ε⁴); per pass and
 * tile the derivative is compared against R. R's own bias −4·c₄·ε⁴ (FD(ε) = I' + c₂ε² + c₄ε⁴ + …) is below the
 * budget b = |FD(ε) − FD(2ε)|/3 = |c₂ε² + 5c₄ε⁴| whenever 9·|c₄|·ε² ≤ |c₂|, i.e. while the expansion at 2ε has
 * its ε⁴ term under 4/9 of its ε² term; z = max(0, |mean(R − dI)| − b)/se, per tile and on the total, b from the
 * same passes (its own noise adds to it: each result prints b beside the se). No tile is exempt. */
static double fd_compare(const char *label, const geo_scene *g, int what, vec3 axis, double eps, long passes)
{
    fd_probe a, b, a2, b2, d;
    diff_param q = param_of(g, what, axis);
    geo_scene lo = moved(*g, what, axis, -eps), hi = moved(*g, what, axis, eps);
    geo_scene lo2 = moved(*g, what, axis, -2.0 * eps), hi2 = moved(*g, what, axis, 2.0 * eps);
    geo_probe(&lo, NULL, 0, passes, &a);
    geo_probe(&hi, NULL, 0, passes, &b);
    geo_probe(&lo2, NULL, 0, passes, &a2);
    geo_probe(&hi2, NULL, 0, passes, &b2);
    geo_probe(g, &q, 1, passes, &d);
    double zmax = 0.0, tot_r = 0.0, tot_d = 0.0, tot_1 = 0.0, tot_2 = 0.0, s_e = 0.0, s_e2 = 0.0, s_d = 0.0, s_d2 = 0.0;
    int worst = 0;
    double tile_s1[NT] = {0}, tile_s2[NT] = {0}, tile_r[NT] = {0}, tile_d[NT] = {0}, tile_b[NT] = {0};
    for (long i = 0; i < passes; i++) {
        double e_tot = 0.0, d_tot = 0.0;
        for (int v = 0; v < NT; v++) {
            size_t at = (size_t)i * NT + v;
            double f1 = (b.x[at] - a.x[at]) / (2.0 * eps), f2 = (b2.x[at] - a2.x[at]) / (4.0 * eps);
            double r = (4.0 * f1 - f2) / 3.0, dv = d.x[i * 2 * NT + NT + v];
            tot_r += r / passes, tot_d += dv / passes, tot_1 += f1 / passes, tot_2 += f2 / passes;
            e_tot += r - dv, d_tot += dv;
            tile_b[v] += (f1 - f2) / (3.0 * passes);
            tile_s1[v] += r - dv, tile_s2[v] += (r - dv) * (r - dv), tile_r[v] += r / passes, tile_d[v] += dv / passes;
        }
        s_e += e_tot, s_e2 += e_tot * e_tot, s_d += d_tot, s_d2 += d_tot * d_tot;
    }
    for (int v = 0; v < NT; v++) {
        double zt = z_budget(tile_s1[v], tile_s2[v], passes, fabs(tile_b[v]));
        if (zt > zmax) zmax = zt, worst = v;
    }
    double zt = z_budget(s_e, s_e2, passes, fabs(tot_1 - tot_2) / 3.0);
    if (getenv("GEO_TILES"))
        for (int v = 0; v < NT; v++)
            print_message("    tile %2d: dI %10.4g  R %10.4g  budget %9.2g  se %9.2g  z %6.2f\n", v, tile_d[v], tile_r[v], fabs(tile_b[v]),
                          sqrt(fmax(0.0, (tile_s2[v] - tile_s1[v] * tile_s1[v] / passes) / (passes - 1)) / passes),
                          z_budget(tile_s1[v], tile_s2[v], passes, fabs(tile_b[v])));
    double se_d = sqrt(fmax(0.0, (s_d2 - passes * tot_d * tot_d) / (passes - 1)) / passes);
    double se_e = sqrt(fmax(0.0, (s_e2 - s_e * s_e / passes) / (passes - 1)) / passes);
    print_message("  %-34s worst tile %d: dI %.5g, Richardson %.5g\n", "", worst, tile_d[worst], tile_r[worst]);
    print_message("  %-34s total dI %.5g (se %.2g, %.1f %%), Richardson %.5g (%+.2f %%, se of the difference %.2g); "
                  "FD(eps) %.5g, FD(2eps) %.5g, budget |FD(eps) - FD(2eps)|/3 %.2g; |z| %.2f total, max |z| %.2f over %d tiles\n",
                  label, tot_d, se_d, 100.0 * se_d / fabs(tot_d), tot_r, 100.0 * (tot_d - tot_r) / fabs(tot_r), se_e, tot_1,
                  tot_2, fabs(tot_1 - tot_2) / 3.0, zt, zmax, NT);
    free(a.x), free(b.x), free(a2.x), free(b2.x), free(d.x);
    assert_true(fabs(tot_r) > 0.0); /* the motion changes the image */
    return fmax(zmax, zt);
}

static double eps_or(double e)
{
    return getenv("FD_EPS") ? atof(getenv("FD_EPS")) : e;
}

static long passes_or(long n)
{
    return getenv("FD_PASSES") ? atol(getenv("FD_PASSES")) : n;
}

/* Every integrator of the stress tier (GEO_INT picks one), or the plain path tracer */
static int integrator_count(void)
{
    return GEO_FULL && !getenv("GEO_INT") ? 3 : 1;
}

static geo_scene scene_for(int i)
{
    geo_scene g = base_scene();
    if (integrator_count() > 1) g.integrator = integrator_keys[i];
    print_message("  [%s]\n", integrator_count() > 1 ? (i == 0 ? "path tracer" : i == 1 ? "DARTS" : "uniform time") : "");
    return g;
}

static void test_camera(void **state)
{
    (void)state;
    for (int i = 0; i < integrator_count(); i++) {
        geo_scene g = scene_for(i);
        if (GEO_FULL) {
            g.wall = 0, g.max_bounces = 4; /* the fog alone: every order */
            assert_true(fd_compare("camera x, fog", &g, T_CAMERA, v3(1, 0, 0), eps_or(0.1), passes_or(1000)) < 4.0);
        }
        g.wall = 1, g.max_bounces = 2; /* hits sliding over the wall */
        assert_true(fd_compare("camera z, fog and wall", &g, T_CAMERA, v3(0, 0, 1), eps_or(0.1), passes_or(GEO_FULL ? 1000 : 100)) < 4.0);
    }
}

static void test_light(void **state)
{
    (void)state;
    for (int i = 0; i < integrator_count(); i++) {
        geo_scene g = scene_for(i);
        g.wall = 0, g.max_bounces = 4;
        assert_true(fd_compare("light x, fog", &g, T_LIGHT, v3(1, 0, 0), eps_or(0.1), passes_or(1000)) < 4.0);
        g.wall = 1, g.max_bounces = 2;
        assert_true(fd_compare("light y, fog and wall", &g, T_LIGHT, v3(0, 1, 0), eps_or(0.1), passes_or(1000)) < 4.0);
    }
}

static void test_wall(void **state)
{
    (void)state;
    for (int i = 0; i < integrator_count(); i++) {
        geo_scene g = scene_for(i);
        assert_true(fd_compare("wall z (along its normal)", &g, T_WALL, v3(0, 0, 1), eps_or(0.1), passes_or(2000)) < 4.0);
    }
}

/* The occluder along y (its shadow grows and shrinks: the total changes) at ε 0.04, its shadow's edges on
 * the wall mid-tile so that 2ε moves none across a tile's border (a kink no extrapolation removes); along x
 * (the total cancels by symmetry: the tiles test it) at ε 0.01 (at 0.02 a corner of the shadow crosses a
 * tile's border: tile 1 gave |z| 4.56 at 64000 passes, and 0.65 at ε 0.01). */
static void test_occluder(void **state)
{
    (void)state;
    for (int i = 0; i < integrator_count(); i++) {
        geo_scene g = scene_for(i);
        g.occluder = 1;
        double z = fd_compare("occluder y", &g, T_OCCLUDER, v3(0, 1, 0), eps_or(0.04), passes_or(GEO_FULL ? 16000 : 300));
        if (GEO_FULL) z = fmax(z, fd_compare("occluder x", &g, T_OCCLUDER, v3(1, 0, 0), eps_or(0.01), passes_or(16000)));
        if (getenv("DARTSPP_DERIV_NO_BOUNDARY")) print_message("  (boundary terms off: the broken variant)\n");
        assert_true(z < 4.0);
    }
}

/* Linearity (Yi et al. 2021 Fig. 7): the occluder along x, along y and along x + y in one render, on the same
 * paths: per pass and tile, ∂I/∂θ_x + ∂I/∂θ_y = ∂I/∂θ_(x+y) to the central differences' rounding. */
static void test_linearity(void **state)
{
    (void)state;
    geo_scene g = base_scene();
    g.occluder = 1;
    diff_param q[3] = {param_of(&g, T_OCCLUDER, v3(1, 0, 0)), param_of(&g, T_OCCLUDER, v3(0, 1, 0)),
                       param_of(&g, T_OCCLUDER, v3(1, 1, 0))};
    fd_probe d;
    long passes = GEO_FULL ? 200 : 40;
    geo_probe(&g, q, 3, passes, &d);
    double worst = 0.0, scale = 0.0;
    for (long i = 0; i < passes; i++)
        for (int v = 0; v < NT; v++) {
            const double *r = &d.x[i * 4 * NT];
            worst = fmax(worst, fabs(r[NT + v] + r[2 * NT + v] - r[3 * NT + v]));
            scale = fmax(scale, fabs(r[3 * NT + v]));
        }
    print_message("  linearity: max |dx + dy - d(x+y)| %.3g against max |d(x+y)| %.3g per pass and tile\n", worst, scale);
    assert_true(scale > 0.0);
    assert_true(worst <= 1e-6 * scale);
    free(d.x);
}

/* What is refused names the pointer: max_bounces 3 with an opaque surface, the occluder's silhouette in view, a
 * smooth surface (a sphere). */
static void test_refusals(void **state)
{
    (void)state;
    static char text[8192];
    geo_scene g = base_scene();
    g.occluder = 1;
    g.occ = v3(0, 1.2, 0.3); /* in view */
    scene_text(text, sizeof text, &g);
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    s.diffs[0] = param_of(&g, T_OCCLUDER, v3(1, 0, 0));
    snprintf(s.diffs[0].pointer, sizeof s.diffs[0].pointer, "/primitives/2/transform/position/0");
    s.diff_count = 1;
    render_options ro = {.threads = 1, .seed = 1, .spp = 1};
    film f;
    render_stats st;
    dp_error err;
    assert_int_not_equal(render_scene(&s, &ro, &f, &st, &err), 0);
    print_message("  refused: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "/primitives/2/transform/position/0"));
    assert_non_null(strstr(err.msg, "silhouette"));
    s.integrator.max_bounces = 3;
    assert_int_not_equal(render_scene(&s, &ro, &f, &st, &err), 0);
    assert_non_null(strstr(err.msg, "max_bounces"));
    scene_free(&s);
    tmp_scene_remove(&ts);
    /* a smooth surface (a sphere) anywhere: its shading normals as hits slide are not differentiated */
    g = base_scene();
    g.sphere = 1;
    scene_text(text, sizeof text, &g);
    tmp_scene_write(&ts, text);
    load_scene(ts.path, NULL, 0, &s);
    s.diffs[0] = param_of(&g, T_CAMERA, v3(1, 0, 0));
    snprintf(s.diffs[0].pointer, sizeof s.diffs[0].pointer, "/camera/transform/position/0");
    s.diff_count = 1;
    assert_int_not_equal(render_scene(&s, &ro, &f, &st, &err), 0);
    print_message("  refused: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "/camera/transform/position/0"));
    assert_non_null(strstr(err.msg, "smooth"));
    scene_free(&s);
    tmp_scene_remove(&ts);
}

int main(void)
{
    const struct CMUnitTest full[] = {cmocka_unit_test(test_refusals), cmocka_unit_test(test_linearity),
                                      cmocka_unit_test(test_camera),   cmocka_unit_test(test_light),
                                      cmocka_unit_test(test_wall),     cmocka_unit_test(test_occluder)};
    const struct CMUnitTest small[] = {cmocka_unit_test(test_refusals), cmocka_unit_test(test_linearity),
                                       cmocka_unit_test(test_camera), cmocka_unit_test(test_occluder)};
    if (getenv("DARTSPP_TEST_FILTER")) cmocka_set_test_filter(getenv("DARTSPP_TEST_FILTER"));
    const struct CMUnitTest refusals[] = {cmocka_unit_test(test_refusals)};
    /* the stress program runs its matrix under DARTSPP_STRESS=full (`make stress`); in `make test`, where the
     * default program already runs the small set, only the refusals */
    if (GEO_FULL) return stress_full() ? cmocka_run_group_tests(full, NULL, NULL) : cmocka_run_group_tests(refusals, NULL, NULL);
    return cmocka_run_group_tests(small, NULL, NULL);
}
