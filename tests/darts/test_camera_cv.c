/* Camera-side control vertices (include/dartspp/darts.h, src/darts/camera_cv.c; docs/darts.md §5.5):
 *  a. the film's directions: E[1/p] over camera_film_direction equals the film's solid angle in closed form,
 *     4·asin(ab/√((a² + d²)(b² + d²))), and camera_film_direction_pdf gives the sample's own density, 0 behind
 *     the camera and off the film;
 *  b. the density in volume measure: E[g(y)/p(y)] over camera_control_vertex (the residual T drawn by
 *     ellipse_record_init, uniform and exponential) equals ∫ g over the places it can reach (T(y) in the
 *     record's window, on the film), that integral by uniform points in a box around
 *     the ellipsoid — no Jacobian of the sampler enters the reference; every sample lies on its record's
 *     ellipsoid and camera_control_vertex_pdf returns its density;
 *  c. in a render (the photon pass's balance heuristic with the vertex-side control vertex): the fog box with
 *     camera_control_vertices on against off, per tile, equal radii (the kernel's bias is then the same).
 * Broken variants (tests/README.md): the density with ρ² in place of ρ³; the vertex-side photon without its
 * MIS weight; the film's density without the factor plane_dist; the thinning's share not the sampler's. */
#include "fixtures.h"
#include "render_fixtures.h"

#include "dartspp/darts.h"

#define Z_MAX 4.0

static camera test_camera(void)
{
    camera c = {.width = 64, .height = 40, .type = CAMERA_PINHOLE, .fov_deg = 50.0, .pos = {0.3, -0.2, 1.1}};
    c.forward = v3_norm(v3(0.2, 0.1, 1.0));
    c.right = v3_norm(v3_cross(v3(0.0, 1.0, 0.0), c.forward));
    c.up = v3_cross(c.forward, c.right);
    c.plane_dist = 1.0 / tan(0.5 * c.fov_deg * M_PI / 180.0);
    return c;
}

static void test_film_directions(void **state)
{
    (void)state;
    camera c = test_camera();
    camera_film f;
    assert_true(camera_film_init(&f, &c, 0.2));
    double a = f.half_x, b = f.half_y, d = f.plane_dist;
    double omega = 4.0 * asin(a * b / sqrt((a * a + d * d) * (b * b + d * d)));
    dp_rng rng = rng_stream(0xca3e7a, 1, 0);
    const long n = 400000;
    double s = 0.0, s2 = 0.0;
    for (long i = 0; i < n; i++) {
        double p;
        vec3 w = camera_film_direction(&f, rng_uniform(&rng), rng_uniform(&rng), &p);
        assert_true(fabs(v3_len(w) - 1.0) < 1e-12);
        double q = camera_film_direction_pdf(&f, w);
        if (!(fabs(q - p) <= 1e-9 * p)) fail_msg("direction %ld: sampled density %.17g, evaluated %.17g", i, p, q);
        s += 1.0 / p, s2 += 1.0 / (p * p);
    }
    double mean = s / n, se = sqrt((s2 / n - mean * mean) / n), z = (mean - omega) / se;
    print_message("film solid angle: E[1/p] %.6f ± %.6f, closed form %.6f (z %+.2f)\n", mean, se, omega, z);
    assert_true(fabs(z) < Z_MAX);
    assert_true(camera_film_direction_pdf(&f, v3_neg(c.forward)) == 0.0);              /* behind */
    vec3 off = v3_norm(v3_add(v3_scale(c.forward, d), v3_scale(c.right, 1.05 * a)));  /* just off the film */
    assert_true(camera_film_direction_pdf(&f, off) == 0.0);
    camera o = c;
    o.type = CAMERA_ORTHOGRAPHIC;
    assert_false(camera_film_init(&f, &o, 0.2));
    assert_true(camera_film_direction_pdf(&f, c.forward) == 0.0);
}

/* ---- b: the density in volume measure ---- */

typedef struct {
    const char *name;
    vec3 x;          /* the vertex, relative to the camera along (forward, right, up) */
    double lo, hi;   /* the bin, as residual lengths (tau 0, eta 1) */
    residual_sampling mode;
    double sigma;
    double share, thin; /* camera_film's (0, 0: the defaults, all kept) */
} cv_case;

static vec3 in_camera_frame(const camera *c, vec3 v)
{
    return v3_add(c->pos, v3_add(v3_scale(c->forward, v.x), v3_add(v3_scale(c->right, v.y), v3_scale(c->up, v.z))));
}

/* a smooth test function, positive and varying over the region */
static double g_of(vec3 y, vec3 cam)
{
    vec3 d = v3_sub(y, cam);
    return exp(-0.3 * v3_dot(d, d)) * (1.2 + 0.5 * d.x - 0.3 * d.y + 0.2 * d.z);
}

static void record_for(const cv_case *k, const camera *c, double u, ellipse_record *r)
{
    darts_guide g = {.active = 1, .cam = c->pos, .eta_lb = 1.0, .eta_ub = 1.0};
    darts_bin b = {.start = k->lo, .end = k->hi, .pdf = 1.0, .frame = -1};
    ellipse_record_init(r, &g, &b, in_camera_frame(c, k->x), 0.0, 1.0, k->mode, k->sigma, u);
}

static void density_case(const cv_case *k)
{
    camera c = test_camera();
    camera_film f;
    assert_true(camera_film_init(&f, &c, 0.2));
    if (k->share > 0.0) f.share = k->share, f.thin = k->thin;
    vec3 x = in_camera_frame(&c, k->x);
    /* the sampler: E[g/p] */
    dp_rng rng = rng_stream(0xcc1, 2, 0);
    const long n = 400000;
    double s = 0.0, s2 = 0.0;
    for (long i = 0; i < n; i++) {
        ellipse_record r;
        record_for(k, &c, rng_uniform(&rng), &r);
        assert_true(r.valid);
        vec3 y;
        double p;
        double u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);
        if (!camera_control_vertex(&r, &f, u1, u2, rng_uniform(&rng), &y, &p)) continue;
        double t = v3_len(v3_sub(y, x)), rho = v3_len(v3_sub(y, c.pos));
        if (!(fabs(t + rho - r.T) <= 1e-9 * r.T)) fail_msg("%s: off the ellipsoid: t + ρ = %.15g, T = %.15g", k->name, t + rho, r.T);
        double q = camera_control_vertex_pdf(&r, &f, y, k->mode, k->sigma);
        if (!(fabs(q - p) <= 1e-7 * p)) fail_msg("%s: sampled density %.12g, evaluated %.12g", k->name, p, q);
        double v = g_of(y, c.pos) / p;
        s += v, s2 += v * v;
    }
    double m_s = s / n, se_s = sqrt((s2 / n - m_s * m_s) / n);
    /* the reference: uniform points in the ellipsoid's bounding box (semi-axes hi/2 and √(hi² − C²)/2) */
    double C = v3_len(v3_sub(x, c.pos)), A = 0.5 * k->hi, B = 0.5 * sqrt(k->hi * k->hi - C * C);
    vec3 mid = v3_scale(v3_add(x, c.pos), 0.5), e = v3_scale(v3_sub(c.pos, x), 1.0 / C), b1, b2;
    v3_basis(e, &b1, &b2);
    double volume = 2.0 * A * 2.0 * B * 2.0 * B;
    double r_s = 0.0, r_s2 = 0.0;
    const long nr = 4000000;
    for (long i = 0; i < nr; i++) {
        vec3 y = v3_add(mid, v3_add(v3_scale(e, A * (2.0 * rng_uniform(&rng) - 1.0)),
                                    v3_add(v3_scale(b1, B * (2.0 * rng_uniform(&rng) - 1.0)),
                                           v3_scale(b2, B * (2.0 * rng_uniform(&rng) - 1.0)))));
        double rho = v3_len(v3_sub(y, c.pos)), S = v3_len(v3_sub(y, x)) + rho;
        vec3 phi = v3_scale(v3_sub(y, c.pos), 1.0 / rho);
        double cf = v3_dot(phi, c.forward);
        int on_film = cf > 0.0 && fabs(c.plane_dist * v3_dot(phi, c.right) / cf) <= f.half_x &&
                      fabs(c.plane_dist * v3_dot(phi, c.up) / cf) <= f.half_y;
        double lo = k->lo > C ? k->lo : C;
        if (!(S >= lo && S <= k->hi) || !on_film) continue;
        double v = g_of(y, c.pos) * volume; /* thinned or not, E[g/p] is ∫ g over where p > 0 */
        r_s += v, r_s2 += v * v;
    }
    double m_r = r_s / nr, se_r = sqrt((r_s2 / nr - m_r * m_r) / nr);
    double z = (m_s - m_r) / sqrt(se_s * se_s + se_r * se_r);
    print_message("%s: sampler %.6f ± %.6f, box %.6f ± %.6f (z %+.2f)\n", k->name, m_s, se_s, m_r, se_r, z);
    assert_true(m_r > 0.0);
    if (!(fabs(z) < Z_MAX)) fail_msg("%s: the sampler's E[g/p] disagrees with the integral (z %+.2f)", k->name, z);
}

static void test_volume_density(void **state)
{
    (void)state;
    const cv_case cases[] = {
        {"ahead, uniform residual", {3.0, 0.4, -0.2}, 3.2, 3.9, RESIDUAL_UNIFORM, 0.5, 0.0, 0.0},
        {"ahead, window touching C, exponential", {2.5, -0.3, 0.3}, 2.0, 2.9, RESIDUAL_EXPONENTIAL, 1.3, 0.0, 0.0},
        {"beside, off the film", {0.8, 2.0, 0.4}, 2.3, 2.8, RESIDUAL_UNIFORM, 0.5, 0.0, 0.0},
        {"behind the camera", {-1.5, 0.2, 0.1}, 1.6, 2.6, RESIDUAL_UNIFORM, 0.5, 0.0, 0.0},
        {"ahead, thinned (share 0.4, ρ_thin 1.2)", {3.0, 0.4, -0.2}, 3.2, 3.9, RESIDUAL_UNIFORM, 0.5, 0.4, 1.2},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) density_case(&cases[i]);
}

/* ---- c: in a render ---- */

#define CCV_BOX_KEYS                                                                                                  \
    "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\", \"max_bounces\": 6,"        \
    " \"photon_count\": 6000, \"volume_photon_count\": 4000, \"gather_photon_count\": 256, \"gather_radius\": 0.15,"  \
    " \"volume_gather_radius\": 0.12, \"fixed_volume_radius\": true, \"alpha\": 1, \"volume_alpha\": 1,"              \
    " \"transient_time_center\": 4.6, \"transient_time_width\": 0.6, " DARTS_KEYS_TEXT

static void test_render_agrees(void **state)
{
    (void)state;
    char text[16384];
    cell_totals off = {0}, on = {0};
    double t_off, t_on;
    box_scene_text(text, sizeof text, 16, CCV_BOX_KEYS ", \"camera_control_vertices\": false");
    cell_render(text, 300, 11, 0, &off, &t_off);
    box_scene_text(text, sizeof text, 16, CCV_BOX_KEYS ", \"camera_control_vertices\": true");
    cell_render(text, 300, 29, 0, &on, &t_on);
    double z_total;
    double z = cells_z("camera-side control vertices on ÷ off", &off, &on, 0.0, &z_total);
    print_message("  seconds: off %.1f, on %.1f\n", t_off, t_on);
    free(off.x), free(on.x);
    assert_true(z < Z_MAX);       /* per tile */
    assert_true(z_total < Z_MAX); /* the whole image: a bias spread over every tile shows here first */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_film_directions),
        cmocka_unit_test(test_volume_density),
        cmocka_unit_test(test_render_agrees),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
