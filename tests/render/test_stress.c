/* tier: stress */
/* Numerical stability on stiff and extreme cases (render level): a matrix of small renders through the public
 * API (scene_load of a JSON text written to a temporary folder, then render_scene), mostly photon points with
 * DARTS on (enable_guiding, enable_elliptical, strict_time_width), some with DARTS off and some with the path
 * tracer.
 *
 * Every case asserts: the scene loads and render_scene returns 0 (or, where stated, fails with a message that
 * names the cause); the requested number of passes ran; render_stats.nonfinite == 0 (suppressed non-finite
 * film contributions and photons dropped for non-finite power); every value of the gate image and of every
 * transient frame is finite and >= 0. One line per case is printed (name, passes, photon paths, mean and max
 * pixel value, seconds); a failing check prints a "FAIL <case>: ..." line and the group goes on with its
 * other cases, then fails.
 *
 * Groups (the fast subset by default; DARTSPP_STRESS=full runs the whole matrix; DARTSPP_STRESS_ONLY=text
 * runs only the cases whose name contains text; DARTSPP_STRESS_KEEP=folder keeps every case's scene there,
 * to reproduce it with `dartspp render`):
 *   1. extinction: σs from 1e-4 to 1e3 per unit length with the light about 3 units from the camera (3e-4 to
 *      3000 mean free paths), albedo 0.01, σs = 0 with σa > 0 (homogeneous: must render; guided_homo and the
 *      `ida` phase: must render, or fail with a message naming the medium and sigma_s).
 *   2. Henyey-Greenstein g in {-0.99, -0.5, 0, 0.5, 0.99}, EDA direction sampling off and on.
 *   3. gates: widths 1e-6, 1e-3, 1 and 1e9 (wider than every arrival); a gate that ends before the earliest
 *      possible arrival (η = 1 and 4/3): the image must be exactly zero; a gate 300 mean free paths of path
 *      length after the direct arrival in thick media, where the diffusion Green's function underflows.
 *   4. scale invariance: the scene scaled by s = 1e-4 and 1e4 (positions, sizes, radii and time keys × s,
 *      σ ÷ s, intensity × s³) against s = 1: region means over K independent seeds, two-sample z-test.
 *   5. geometry: camera in the fog, camera in vacuum outside a fog cube (forward and null boundary), camera
 *      and light inside a fog cube, light in a clear pocket, gate starting exactly at the straight
 *      camera-light time (degenerate first ellipses), light on the central camera ray, the radii of
 *      iteration 1e5.
 *   6. transient frames with DARTS: every frame finite and >= 0, frames entirely before the earliest arrival
 *      exactly zero (the frames' values: tests/photon_points/test_photon_frames.c, DARTS frames against the path tracer).
 * No expected value comes from an earlier run of this code: exact zeros follow from causality, the scale
 * test's tolerance from the spread over seeds measured here. */
#include "test_util.h"

#include <ctype.h>
#include <stdarg.h>

#include "dartspp/render.h"

/* ---------------------------------------------------------------------------------------------------- */
/* cases and scenes                                                                                     */

typedef enum { GEO_OPEN_FOG, GEO_FOG_CUBE, GEO_LIGHT_POCKET } stress_geometry;
typedef enum { INTEG_DARTS, INTEG_BASELINE, INTEG_PATH_TRACER } stress_integrator;

typedef struct {
    char name[128];
    /* medium */
    const char *medium_type;  /* "homogeneous" or "guided_homo" */
    const char *phase;        /* "henyey_greenstein" or "ida" */
    double sigma_s, sigma_a, g, speed;
    /* geometry, in units of the scene at scale 1, relative to the camera */
    stress_geometry geo;
    int camera_in_fog;        /* GEO_FOG_CUBE: the camera inside the cube too */
    const char *boundary;     /* bsdf of the fog cube or the clear pocket: "forward" or "null" */
    vec3 light;
    double scale;             /* every length and time × scale, σ ÷ scale, intensity × scale³ */
    int res;
    /* integrator */
    stress_integrator integ;
    int eda;
    double gate_start, gate_width; /* at scale 1 */
    int frames;                    /* > 0: frame mode, frames of gate_width from gate_start */
    double r_vol, r_surf, alpha;
    int max_bounces;
    double photon_count;
    long passes;
    uint64_t seed;
    /* expectations beyond finiteness */
    int expect_zero;           /* gate image exactly zero everywhere (causality) */
    int expect_lit;            /* gate image not all zero */
    int error_may_mention_sigma_s; /* a load or render error is accepted if it names the medium and sigma_s */
} stress_case;

static int stress_full;            /* DARTSPP_STRESS=full */
static const char *stress_only;    /* DARTSPP_STRESS_ONLY */
static const char *stress_keep;    /* DARTSPP_STRESS_KEEP: a folder that receives a copy of every case's scene */
static int stress_failures;        /* failed checks in the current group */
static char stress_table_dir[600]; /* EDA tables, in the group's temporary folder */

/* The camera sits at ORIGIN (off the world origin, so that no coordinate is exactly 0 and nothing is symmetric
 * about the world axes), looking along +z; every other position is relative to it. */
static const vec3 ORIGIN = {0.5, 0.25, -1.0};
static const vec3 DEFAULT_LIGHT = {0.3, 0.2, 3.0};

/* Straight camera-light time at scale 1 (the earliest possible arrival of any path). */
static double straight_time(const stress_case *c)
{
    double d = v3_len(c->light);
    int light_path_in_fog = c->geo == GEO_OPEN_FOG || (c->geo == GEO_FOG_CUBE && c->camera_in_fog);
    if (!light_path_in_fog && c->speed != 1.0) fail_msg("%s: straight_time needs speed 1 when the line leaves the fog", c->name);
    return d / c->speed;
}

static stress_case case_default(const char *name)
{
    stress_case c = {.medium_type = "homogeneous", .phase = "henyey_greenstein", .sigma_s = 0.5, .sigma_a = 0.05,
                     .g = 0.3, .speed = 1.0, .geo = GEO_OPEN_FOG, .boundary = "forward", .light = DEFAULT_LIGHT,
                     .scale = 1.0, .res = 16, .integ = INTEG_DARTS, .r_vol = 0.1, .r_surf = 0.15, .alpha = 0.7,
                     .max_bounces = 12, .photon_count = 4000, .passes = 3, .seed = 11};
    snprintf(c.name, sizeof c.name, "%s", name);
    /* gate [1.1 T0, 2.5 T0): scattered light and the back wall (light -> wall -> camera = 7 units) */
    double t0 = straight_time(&c);
    c.gate_start = 1.1 * t0;
    c.gate_width = 1.4 * t0;
    return c;
}

static void append(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void append(char *buf, size_t cap, const char *fmt, ...)
{
    size_t n = strlen(buf);
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(buf + n, cap - n, fmt, ap);
    va_end(ap);
    assert_true(k >= 0 && (size_t)k < cap - n); /* the scene text fits */
}

/* A position relative to the camera, in scene coordinates at the case's scale, as a JSON array. */
static void append_pos(char *buf, size_t cap, const stress_case *c, vec3 rel)
{
    vec3 p = v3_scale(v3_add(ORIGIN, rel), c->scale);
    append(buf, cap, "[%.17g, %.17g, %.17g]", p.x, p.y, p.z);
}

static void stress_scene_text(const stress_case *c, char *t, size_t cap)
{
    const double s = c->scale;
    t[0] = 0;
    append(t, cap,
           "{ \"media\": [ { \"name\": \"fog\", \"type\": \"%s\", \"sigma_s\": %.17g, \"sigma_a\": %.17g,"
           " \"speed_of_light\": %.17g, \"phase_function\": { \"type\": \"%s\", \"g\": %.17g } } ],"
           "  \"bsdfs\": [ { \"name\": \"wall\", \"type\": \"lambert\", \"albedo\": 0.6 },"
           "               { \"name\": \"boundary\", \"type\": \"%s\" } ],"
           "  \"primitives\": [",
           c->medium_type, c->sigma_s / s, c->sigma_a / s, c->speed, c->phase, c->g, c->boundary);
    /* back wall 5 units ahead (facing the camera) and a floor 1.5 below */
    append(t, cap, " { \"type\": \"quad\", \"bsdf\": \"wall\", \"transform\": { \"position\": ");
    append_pos(t, cap, c, v3(0, 0, 5));
    append(t, cap, ", \"scale\": [%.17g, %.17g, %.17g], \"rotation\": [-90, 0, 0] } },", 8 * s, s, 8 * s);
    append(t, cap, " { \"type\": \"quad\", \"bsdf\": \"wall\", \"transform\": { \"position\": ");
    append_pos(t, cap, c, v3(0, -1.5, 2.5));
    append(t, cap, ", \"scale\": [%.17g, %.17g, %.17g] } },", 8 * s, s, 10 * s);
    const char *light_medium = ", \"ext_medium\": \"fog\"", *camera_medium = ", \"medium\": \"fog\"";
    if (c->geo == GEO_FOG_CUBE) {
        /* index-matched (or null) cube with fog inside; the camera inside it or in vacuum in front of it */
        vec3 centre = c->camera_in_fog ? v3(0, 0, 2) : v3(0, 0, 3), size = c->camera_in_fog ? v3(5, 5, 8) : v3(2.4, 2.4, 2.4);
        append(t, cap, " { \"type\": \"cube\", \"bsdf\": \"boundary\", \"int_medium\": \"fog\", \"transform\": { \"position\": ");
        append_pos(t, cap, c, centre);
        append(t, cap, ", \"scale\": [%.17g, %.17g, %.17g] } },", size.x * s, size.y * s, size.z * s);
        if (!c->camera_in_fog) camera_medium = "";
    } else if (c->geo == GEO_LIGHT_POCKET) {
        /* fog everywhere but a 0.3 cube of vacuum around the light */
        append(t, cap, " { \"type\": \"cube\", \"bsdf\": \"boundary\", \"ext_medium\": \"fog\", \"transform\": { \"position\": ");
        append_pos(t, cap, c, c->light);
        append(t, cap, ", \"scale\": [%.17g, %.17g, %.17g] } },", 0.3 * s, 0.3 * s, 0.3 * s);
        light_medium = "";
    }
    double I = 10.0 * s * s * s;
    append(t, cap, " { \"type\": \"point\", \"emission\": [%.17g, %.17g, %.17g]%s, \"transform\": { \"position\": ", I, 0.8 * I,
           0.6 * I, light_medium);
    append_pos(t, cap, c, c->light);
    append(t, cap, " } } ],  \"camera\": { \"type\": \"pinhole\", \"resolution\": [%d, %d], \"fov\": 40%s,"
                   " \"transform\": { \"position\": ", c->res, c->res, camera_medium);
    append_pos(t, cap, c, v3(0, 0, 0));
    append(t, cap, ", \"look_at\": ");
    append_pos(t, cap, c, v3(0, 0, 1));
    append(t, cap, ", \"up\": [0, 1, 0] } },  \"integrator\": { ");
    if (c->integ == INTEG_PATH_TRACER) append(t, cap, "\"type\": \"path_tracer\"");
    else
        append(t, cap,
               "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\", \"photon_count\": %.17g,"
               " \"volume_photon_count\": 1e7, \"gather_photon_count\": 16, \"gather_radius\": %.17g,"
               " \"volume_gather_radius\": %.17g, \"alpha\": %.17g, \"volume_alpha\": %.17g",
               c->photon_count, c->r_surf * s, c->r_vol * s, c->alpha, c->alpha);
    if (c->integ == INTEG_DARTS)
        append(t, cap, ", \"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true");
    if (c->eda) append(t, cap, ", \"eda\": true, \"eda_shape\": [16, 16, 32], \"eda_table_dir\": \"%s\"", stress_table_dir);
    append(t, cap, ", \"max_bounces\": %d", c->max_bounces);
    if (c->frames > 0)
        append(t, cap, ", \"frame_num\": %d, \"start_time\": %.17g, \"transient_time_width\": %.17g", c->frames,
               c->gate_start * s, c->gate_width * s);
    else
        append(t, cap, ", \"transient_time_center\": %.17g, \"transient_time_width\": %.17g",
               (c->gate_start + 0.5 * c->gate_width) * s, c->gate_width * s);
    append(t, cap, " },  \"renderer\": { \"spp\": 1 } }");
}

/* ---------------------------------------------------------------------------------------------------- */
/* running a case                                                                                       */

static void case_fail(const stress_case *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void case_fail(const stress_case *c, const char *fmt, ...)
{
    char msg[1400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    print_message("  FAIL %s: %s\n", c->name, msg);
    stress_failures++;
}

static int case_selected(const stress_case *c) { return !stress_only || strstr(c->name, stress_only); }

typedef struct {
    int rendered;
    double mean, max;     /* over the values of the gate image */
    double photon_paths;
} case_result;

/* Checks one image (gate: k < 0, else frame k): every value finite and >= 0; returns the number of bad values
 * and fills mean and max. */
static long check_image(const stress_case *c, const image_rgb *img, int k, double *mean, double *max)
{
    size_t n = (size_t)img->width * img->height * 3;
    long bad = 0;
    double sum = 0, mx = 0;
    char what[32] = "gate image";
    if (k >= 0) snprintf(what, sizeof what, "frame %d", k);
    for (size_t i = 0; i < n; i++) {
        float v = img->rgb[i];
        if (!isfinite(v) || v < 0) {
            if (bad == 0)
                case_fail(c, "%s: pixel (%zu, %zu) channel %zu = %g", what, (i / 3) % img->width, (i / 3) / img->width,
                          i % 3, (double)v);
            bad++;
            continue;
        }
        sum += v;
        mx = fmax(mx, v);
    }
    if (bad) case_fail(c, "%s: %ld of %zu values non-finite or negative", what, bad, n);
    *mean = sum / (double)n;
    *max = mx;
    return bad;
}

/* Renders one case in folder dir and runs the checks every case shares. With keep, the film is handed back
 * (the caller frees it) when the render succeeded; res->rendered says whether it did. */
static void run_case(const stress_case *c, const char *dir, case_result *res, film *keep)
{
    *res = (case_result){0};
    char text[16384], path[700];
    stress_scene_text(c, text, sizeof text);
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, text);
    if (stress_keep) { /* for reproducing a case with the command line: <name>.json, spaces etc. as '_' */
        char kept[900];
        int len = snprintf(kept, sizeof kept, "%s/", stress_keep);
        for (const char *q = c->name; *q && len < (int)sizeof kept - 6; q++)
            kept[len++] = isalnum((unsigned char)*q) || *q == '.' || *q == '-' || *q == '+' ? *q : '_';
        snprintf(kept + len, sizeof kept - len, ".json");
        test_write_file(kept, text);
    }
    scene s;
    dp_error err = {0};
    scene_load_options lo = {0};
    double t0 = dp_seconds();
    int rc = scene_load(path, &lo, &s, &err);
    int loaded = rc == 0;
    film f;
    render_stats st = {0};
    if (loaded) {
        render_options ro = {.threads = 2, .seed = c->seed, .spp = c->passes, .time_limit = 0};
        rc = render_scene(&s, &ro, &f, &st, &err);
    }
    if (rc) {
        if (c->error_may_mention_sigma_s) {
            /* accepted: an error that says which medium and why */
            print_message("  %-58s refused at %s: %s\n", c->name, loaded ? "render" : "load", err.msg);
            if (!err.msg[0]) case_fail(c, "error with an empty message");
            else if (!strstr(err.msg, "sigma_s")) case_fail(c, "error does not mention sigma_s: %s", err.msg);
            else if (!strstr(err.msg, "'fog'") && !strstr(err.msg, "media[0]"))
                case_fail(c, "error does not name the medium ('fog' or media[0]): %s", err.msg);
        } else {
            case_fail(c, "%s failed: %s", loaded ? "render_scene" : "scene_load", err.msg);
        }
        if (loaded) scene_free(&s);
        return;
    }
    res->rendered = 1;
    res->photon_paths = st.photon_paths;
    if (st.passes != c->passes) case_fail(c, "%ld passes rendered, %ld asked for", st.passes, c->passes);
    if (st.nonfinite != 0) case_fail(c, "render_stats.nonfinite = %ld", st.nonfinite);
    image_rgb img;
    if (film_image(&f, -1, &img, &err)) fail_msg("%s", err.msg);
    long bad = check_image(c, &img, -1, &res->mean, &res->max);
    if (c->expect_zero && !bad) {
        size_t n = (size_t)img.width * img.height * 3, nonzero = 0, first = 0;
        for (size_t i = 0; i < n; i++)
            if (img.rgb[i] != 0.0f && nonzero++ == 0) first = i;
        if (nonzero)
            case_fail(c, "gate ends before the earliest possible arrival, yet %zu values are nonzero (first: pixel %zu, "
                         "channel %zu = %g)", nonzero, first / 3, first % 3, (double)img.rgb[first]);
    }
    if (c->expect_lit && !(res->mean > 0)) case_fail(c, "the gate image is black where light must arrive");
    image_free(&img);
    for (int k = 0; k < f.window.frame_count; k++) {
        double fm, fx;
        if (film_image(&f, k, &img, &err)) fail_msg("%s", err.msg);
        check_image(c, &img, k, &fm, &fx);
        image_free(&img);
    }
    print_message("  %-58s passes %ld  photon paths %9.0f  mean %-12.5g max %-11.4g (%.2f s)\n", c->name, st.passes,
                  st.photon_paths, res->mean, res->max, dp_seconds() - t0);
    if (keep) *keep = f;
    else film_free(&f);
    scene_free(&s);
}

/* A group's temporary folder (with its EDA table cache) and the failure count. */
static char *group_begin(void)
{
    char *dir = test_tmpdir();
    assert_non_null(dir);
    snprintf(stress_table_dir, sizeof stress_table_dir, "%s/tables", dir);
    stress_failures = 0;
    return dir;
}

static void group_end(char *dir, const char *group)
{
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    (void)!system(cmd);
    free(dir);
    if (stress_failures) fail_msg("%s: %d failed check(s), see the FAIL lines above", group, stress_failures);
}

static void run_matrix(const stress_case *cases, int n, const char *dir)
{
    for (int i = 0; i < n; i++) {
        if (!case_selected(&cases[i])) continue;
        case_result r;
        run_case(&cases[i], dir, &r, NULL);
    }
}

static const char *integ_name(stress_integrator m)
{
    return m == INTEG_DARTS ? "darts" : m == INTEG_BASELINE ? "baseline" : "path tracer";
}

/* ---------------------------------------------------------------------------------------------------- */
/* 1. extinction                                                                                        */

static void test_extinction_sweep(void **state)
{
    (void)state;
    char *dir = group_begin();
    stress_case cases[64];
    int n = 0;
    const double fast_sigma[] = {1e-4, 1, 1e3}, full_sigma[] = {1e-4, 1e-2, 1, 1e2, 1e3};
    const double *sig = stress_full ? full_sigma : fast_sigma;
    int nsig = stress_full ? 5 : 3;
    const stress_integrator fast_m[] = {INTEG_DARTS}, full_m[] = {INTEG_DARTS, INTEG_BASELINE, INTEG_PATH_TRACER};
    for (int i = 0; i < nsig; i++)
        for (int m = 0; m < (stress_full ? 3 : 1); m++) {
            stress_integrator integ = stress_full ? full_m[m] : fast_m[m];
            char name[128];
            snprintf(name, sizeof name, "sigma_s %g albedo 0.9 %s", sig[i], integ_name(integ));
            stress_case c = case_default(name);
            c.sigma_s = sig[i];
            c.sigma_a = sig[i] / 9;
            c.integ = integ;
            /* DARTS always places control vertices in the gate; at <= 1 mean free path the back wall and the
             * fog scatter plenty into it. (At 1e3 per unit length nothing need arrive.) */
            c.expect_lit = integ == INTEG_DARTS && sig[i] <= 1;
            cases[n++] = c;
        }
    /* path tracer at the extremes also in the fast subset */
    if (!stress_full) {
        stress_case c = case_default("sigma_s 1000 albedo 0.9 path tracer");
        c.sigma_s = 1e3;
        c.sigma_a = 1e3 / 9;
        c.integ = INTEG_PATH_TRACER;
        cases[n++] = c;
    }
    /* albedo 0.01: σa = 99 σs */
    const double alb_sigma[] = {1e-2, 1e-4, 1}; /* σt = 1, 0.01, 100 per unit length */
    for (int i = 0; i < (stress_full ? 3 : 1); i++)
        for (int m = 0; m < (stress_full ? 2 : 1); m++) {
            char name[128];
            snprintf(name, sizeof name, "sigma_s %g albedo 0.01 %s", alb_sigma[i], m ? "baseline" : "darts");
            stress_case c = case_default(name);
            c.sigma_s = alb_sigma[i];
            c.sigma_a = 99 * alb_sigma[i];
            c.integ = m ? INTEG_BASELINE : INTEG_DARTS;
            c.expect_lit = c.integ == INTEG_DARTS && alb_sigma[i] <= 1e-2; /* at σt <= 1 the wall and fog show */
            cases[n++] = c;
        }
    /* σs = 0 with σa > 0: the DARTS samplers have nothing to aim at. A plain homogeneous medium must render
     * (surface photons only); guided_homo and the ida phase may be refused, with the reason. */
    {
        stress_case c = case_default("sigma_s 0 sigma_a 0.5 darts");
        c.sigma_s = 0;
        c.sigma_a = 0.5;
        c.expect_lit = 1; /* the back wall: e^{-0.5 * 7} of the light reaches it in the gate */
        cases[n++] = c;
        snprintf(c.name, sizeof c.name, "sigma_s 0 sigma_a 0.5 darts eda");
        c.eda = 1;
        cases[n++] = c;
        snprintf(c.name, sizeof c.name, "sigma_s 0 sigma_a 0.5 guided_homo darts");
        c.eda = 0;
        c.medium_type = "guided_homo";
        c.expect_lit = 0;
        c.error_may_mention_sigma_s = 1;
        cases[n++] = c;
        snprintf(c.name, sizeof c.name, "sigma_s 0 sigma_a 0.5 ida phase darts");
        c.medium_type = "homogeneous";
        c.phase = "ida";
        cases[n++] = c;
        stress_case p = case_default("sigma_s 0 sigma_a 0.5 path tracer");
        p.sigma_s = 0;
        p.sigma_a = 0.5;
        p.integ = INTEG_PATH_TRACER;
        cases[n++] = p;
        if (stress_full) {
            snprintf(p.name, sizeof p.name, "sigma_s 0 sigma_a 0.5 baseline");
            p.integ = INTEG_BASELINE;
            cases[n++] = p;
        }
    }
    assert_true(n <= (int)(sizeof cases / sizeof *cases));
    run_matrix(cases, n, dir);
    group_end(dir, "extinction");
}

/* ---------------------------------------------------------------------------------------------------- */
/* 2. anisotropy, EDA off and on                                                                        */

static void test_anisotropy_eda(void **state)
{
    (void)state;
    char *dir = group_begin();
    stress_case cases[16];
    int n = 0;
    const double gs[] = {-0.99, -0.5, 0, 0.5, 0.99};
    for (int i = 0; i < 5; i++)
        for (int eda = 0; eda <= 1; eda++) {
            int in_fast = (eda && (gs[i] == -0.99 || gs[i] == 0.99)) || (!eda && gs[i] == 0);
            if (!stress_full && !in_fast) continue;
            char name[128];
            snprintf(name, sizeof name, "HG g %g EDA %s", gs[i], eda ? "on" : "off");
            stress_case c = case_default(name);
            c.g = gs[i];
            c.eda = eda;
            c.expect_lit = 1;
            cases[n++] = c;
        }
    run_matrix(cases, n, dir);
    group_end(dir, "anisotropy");
}

/* ---------------------------------------------------------------------------------------------------- */
/* 3. gates                                                                                             */

static void test_gate_extremes(void **state)
{
    (void)state;
    char *dir = group_begin();
    stress_case cases[48];
    int n = 0;
    const double T0 = straight_time(&(stress_case){.light = DEFAULT_LIGHT, .speed = 1.0});
    /* widths from 1e-6 to wider than every arrival, starting after the direct arrival (1e9: from time 0) */
    const double widths[] = {1e-6, 1e-3, 1, 1e9};
    for (int i = 0; i < 4; i++)
        for (int m = 0; m < (stress_full ? 3 : 1); m++) {
            stress_integrator integ = (stress_integrator)m;
            char name[128];
            snprintf(name, sizeof name, "gate width %g %s", widths[i], integ_name(integ));
            stress_case c = case_default(name);
            c.integ = integ;
            c.gate_width = widths[i];
            c.gate_start = widths[i] > 1e6 ? 0.0 : 1.3 * T0;
            c.expect_lit = integ == INTEG_DARTS; /* control vertices land in any gate */
            cases[n++] = c;
        }
    {
        /* EDA with the S range of the table up to 1e9 (every vertex in its first column) */
        stress_case c = case_default("gate width 1e+09 darts eda");
        c.gate_start = 0.0;
        c.gate_width = 1e9;
        c.eda = 1;
        c.expect_lit = 1;
        cases[n++] = c;
        if (stress_full) {
            snprintf(c.name, sizeof c.name, "gate width 1e-06 darts eda");
            c.gate_start = 1.3 * T0;
            c.gate_width = 1e-6;
            cases[n++] = c;
        }
    }
    /* gates that end before the earliest possible arrival: exactly zero */
    for (int eta43 = 0; eta43 <= 1; eta43++)
        for (int m = 0; m < 3; m++) {
            stress_integrator integ = (stress_integrator)m;
            char name[128];
            snprintf(name, sizeof name, "before arrival eta %s %s", eta43 ? "4/3" : "1", integ_name(integ));
            stress_case c = case_default(name);
            c.integ = integ;
            c.speed = eta43 ? 0.75 : 1.0;
            double t_direct = straight_time(&c);
            /* η = 1: [0.5, 0.97) T0. η = 4/3: the gate reaches past the vacuum-speed bound |l| (so the DARTS
             * pass, whose bounds use the smallest η in the scene, 1, still traces paths) but ends before η|l| */
            c.gate_start = 0.5 * t_direct;
            c.gate_width = 0.97 * t_direct - c.gate_start;
            c.expect_zero = 1;
            cases[n++] = c;
        }
    if (stress_full) { /* the same with the camera in vacuum in front of a fog cube, and in a clear light pocket */
        for (int geo = 0; geo < 2; geo++) {
            char name[128];
            snprintf(name, sizeof name, "before arrival %s darts", geo ? "light pocket" : "camera outside fog cube");
            stress_case c = case_default(name);
            c.geo = geo ? GEO_LIGHT_POCKET : GEO_FOG_CUBE;
            c.gate_start = 0.2 * T0;
            c.gate_width = 0.97 * T0 - c.gate_start;
            c.expect_zero = 1;
            cases[n++] = c;
        }
    }
    /* far in the tail: gate start 300 mean free paths of path length after the direct arrival, width 30 */
    const double tail_sigma[][2] = {{100, 1}, {1000, 10}};
    for (int i = 0; i < 2; i++)
        for (int m = 0; m < (stress_full ? 4 : 2); m++) {
            /* fast: darts and darts+EDA; full: also baseline and path tracer */
            stress_integrator integ = m < 2 ? INTEG_DARTS : (m == 2 ? INTEG_BASELINE : INTEG_PATH_TRACER);
            char name[128];
            snprintf(name, sizeof name, "tail 300 mfp sigma_s %g %s%s", tail_sigma[i][0], integ_name(integ),
                     m == 1 ? " eda" : "");
            stress_case c = case_default(name);
            c.sigma_s = tail_sigma[i][0];
            c.sigma_a = tail_sigma[i][1];
            c.integ = integ;
            c.eda = m == 1;
            double mfp = 1.0 / (c.sigma_s + c.sigma_a);
            c.gate_start = T0 + 300 * mfp;
            c.gate_width = 30 * mfp;
            c.max_bounces = 24;
            cases[n++] = c;
        }
    assert_true(n <= (int)(sizeof cases / sizeof *cases));
    run_matrix(cases, n, dir);
    group_end(dir, "gates");
}

/* ---------------------------------------------------------------------------------------------------- */
/* 4. scale invariance                                                                                   */

/* Mean over pixels and channels of the whole image (0) and of its quadrants (1: top left, 2: top right,
 * 3: bottom left, 4: bottom right). */
#define N_REGIONS 5
static const char *const region_names[N_REGIONS] = {"image", "top left", "top right", "bottom left", "bottom right"};

static void region_means(const film *f, double out[N_REGIONS])
{
    double sum[N_REGIONS] = {0};
    long cnt[N_REGIONS] = {0};
    int hw = f->width / 2, hh = f->height / 2;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            size_t p = (size_t)y * f->width + x;
            double v = 0;
            for (int ch = 0; ch < 3; ch++) v += f->sum[3 * p + ch] / f->weight_sum / 3.0;
            int q = 1 + (y >= hh ? 2 : 0) + (x >= hw ? 1 : 0);
            sum[0] += v, cnt[0]++;
            sum[q] += v, cnt[q]++;
        }
    for (int r = 0; r < N_REGIONS; r++) out[r] = sum[r] / cnt[r];
}

/* Renders K seeds of case c at scale s; mean and standard error (over seeds) of every region mean. */
static int scale_stats(stress_case c, double s, int K, uint64_t seed0, const char *dir, double mean[N_REGIONS],
                       double se[N_REGIONS])
{
    c.scale = s;
    double acc[N_REGIONS] = {0}, acc2[N_REGIONS] = {0};
    char base[128];
    snprintf(base, sizeof base, "%s", c.name);
    for (int k = 0; k < K; k++) {
        snprintf(c.name, sizeof c.name, "%.90s scale %g seed %d", base, s, k);
        c.seed = seed0 + (uint64_t)k;
        case_result r;
        film f;
        run_case(&c, dir, &r, &f);
        if (!r.rendered) return 0;
        double m[N_REGIONS];
        region_means(&f, m);
        film_free(&f);
        for (int j = 0; j < N_REGIONS; j++) {
            acc[j] += m[j];
            acc2[j] += m[j] * m[j];
        }
    }
    for (int j = 0; j < N_REGIONS; j++) {
        mean[j] = acc[j] / K;
        double var = fmax(0.0, (acc2[j] - K * mean[j] * mean[j]) / (K - 1));
        se[j] = sqrt(var / K);
    }
    return 1;
}

/* The same scene at scale s: every position, size, radius and time key × s, σs and σa ÷ s, intensity × s³.
 * Why s³: along a camera ray the single-scattered radiance ∫ σs p I e^{-σt(..)} / R² dx keeps its optical
 * depths, gains 1/s from σs, 1/s² from the inverse square and s from dx: 1/s² for the same intensity, and the
 * gate image is that divided by the gate width (× s), so 1/s³ in all; every higher order and the surfaces
 * (albedo dimensionless, photon density per area ÷ s², ...) scale alike. Intensity × s³ makes the expected
 * image identical at every scale, kernel bias included (the radii scale too). Test: for the whole image and
 * each quadrant, the mean over K seeds at scale s against scale 1, z = Δ / sqrt(se_s² + se_1²), |z| < 4
 * (the seeds are independent: distinct seeds for every scale). */
static void scale_invariance_check(const stress_case *base, int K, const char *dir)
{
    const double scales[] = {1e-4, 1e4};
    double m1[N_REGIONS], se1[N_REGIONS];
    if (!scale_stats(*base, 1.0, K, 2000, dir, m1, se1)) return;
    for (int j = 0; j < N_REGIONS; j++) {
        if (!(se1[j] > 0)) case_fail(base, "scale 1, %s: no spread over %d seeds (se %g): the z-test would be void", region_names[j], K, se1[j]);
        if (!(m1[j] > 0)) case_fail(base, "scale 1, %s: black (mean %g)", region_names[j], m1[j]);
    }
    for (int i = 0; i < 2; i++) {
        double ms[N_REGIONS], ses[N_REGIONS];
        if (!scale_stats(*base, scales[i], K, 3000 + 100 * (uint64_t)i, dir, ms, ses)) continue;
        for (int j = 0; j < N_REGIONS; j++) {
            double z = (ms[j] - m1[j]) / sqrt(ses[j] * ses[j] + se1[j] * se1[j]);
            print_message("    %s, scale %g vs 1, %-12s: %.6g (se %.2g) vs %.6g (se %.2g): ratio %.4f, z = %+.2f\n", base->name,
                          scales[i], region_names[j], ms[j], ses[j], m1[j], se1[j], ms[j] / m1[j], z);
            if (!(ses[j] > 0)) case_fail(base, "scale %g, %s: no spread over %d seeds", scales[i], region_names[j], K);
            else if (!(fabs(z) < 4))
                case_fail(base, "scale %g, %s: mean %.6g (se %.2g) vs %.6g (se %.2g) at scale 1, ratio %.4f, z = %+.2f",
                          scales[i], region_names[j], ms[j], ses[j], m1[j], se1[j], ms[j] / m1[j], z);
        }
    }
}

static void test_scale_invariance(void **state)
{
    (void)state;
    char *dir = group_begin();
    int K = stress_full ? 10 : 6;
    stress_case c = case_default("scale: open fog darts");
    c.passes = 4;
    if (stress_full) c.photon_count = 12000;
    if (case_selected(&c)) scale_invariance_check(&c, K, dir);
    /* boundary crossings: the camera in vacuum, the fog in an index-matched cube around the light */
    stress_case q = case_default("scale: camera outside fog cube darts");
    q.geo = GEO_FOG_CUBE;
    q.passes = 4;
    if (stress_full) q.photon_count = 12000;
    if (case_selected(&q)) scale_invariance_check(&q, K, dir);
    if (stress_full) {
        stress_case b = case_default("scale: open fog baseline");
        b.integ = INTEG_BASELINE;
        b.passes = 4;
        b.photon_count = 12000;
        if (case_selected(&b)) scale_invariance_check(&b, K, dir);
        stress_case p = case_default("scale: light pocket darts");
        p.geo = GEO_LIGHT_POCKET;
        p.passes = 4;
        p.photon_count = 12000;
        if (case_selected(&p)) scale_invariance_check(&p, K, dir);
        stress_case e = case_default("scale: open fog darts eda");
        e.eda = 1;
        e.passes = 4;
        e.photon_count = 12000;
        if (case_selected(&e)) scale_invariance_check(&e, K, dir);
        /* the path tracer with the light in a clear pocket (next-event estimation from the fog has finite
         * variance only when the light is not in the fog, see render_fixtures.c) */
        stress_case t = case_default("scale: light pocket path tracer");
        t.geo = GEO_LIGHT_POCKET;
        t.integ = INTEG_PATH_TRACER;
        t.passes = 256;
        if (case_selected(&t)) scale_invariance_check(&t, K, dir);
    }
    group_end(dir, "scale invariance");
}

/* ---------------------------------------------------------------------------------------------------- */
/* 5. geometry edge cases                                                                                */

static void test_geometry_edges(void **state)
{
    (void)state;
    char *dir = group_begin();
    stress_case cases[32];
    int n = 0;
    /* where the camera and the light are with respect to the fog */
    static const struct {
        const char *name;
        stress_geometry geo;
        int camera_in_fog;
        const char *boundary;
        double speed;
    } placements[] = {
        {"camera in open fog", GEO_OPEN_FOG, 1, "forward", 1.0},
        {"camera in vacuum, forward fog cube", GEO_FOG_CUBE, 0, "forward", 1.0},
        {"camera in vacuum, null fog cube", GEO_FOG_CUBE, 0, "null", 1.0},
        {"camera and light in fog cube", GEO_FOG_CUBE, 1, "forward", 1.0},
        /* η = 4/3 in the fog, 1 in the vacuum: DARTS bounds use the smaller one, records the fog's */
        {"camera in vacuum, forward fog cube eta 4/3", GEO_FOG_CUBE, 0, "forward", 0.75},
        {"light in clear pocket", GEO_LIGHT_POCKET, 1, "forward", 1.0},
    };
    for (int m = 0; m < (stress_full ? 3 : 1); m++)
        for (size_t i = 0; i < sizeof placements / sizeof *placements; i++) {
            stress_integrator integ = (stress_integrator)m;
            char name[128];
            snprintf(name, sizeof name, "%s %s", placements[i].name, integ_name(integ));
            stress_case c = case_default(name);
            c.integ = integ;
            c.geo = placements[i].geo;
            c.camera_in_fog = placements[i].camera_in_fog;
            c.boundary = placements[i].boundary;
            c.speed = placements[i].speed;
            c.expect_lit = integ != INTEG_PATH_TRACER; /* photon points: many light paths reach the gate */
            cases[n++] = c;
        }
    {
        /* gate start exactly at the straight camera-light time: the light's ellipse record has S_lo = C */
        stress_case c = case_default("gate start = straight time darts");
        double T0 = straight_time(&c);
        c.gate_start = T0;
        c.gate_width = 0.2 * T0;
        c.expect_lit = 1;
        cases[n++] = c;
        snprintf(c.name, sizeof c.name, "gate start = straight time darts eda");
        c.eda = 1;
        cases[n++] = c;
        /* the light exactly on the central camera ray (odd resolution: the ray through the middle pixel's
         * centre is the axis); photons along the camera ray, alone and with the degenerate gate */
        stress_case a = case_default("light on camera axis darts");
        a.light = v3(0, 0, 3);
        a.res = 15;
        a.expect_lit = 1;
        cases[n++] = a;
        snprintf(a.name, sizeof a.name, "light on camera axis, gate start = straight time darts");
        a.gate_start = straight_time(&a);
        a.gate_width = 0.2 * a.gate_start;
        cases[n++] = a;
        if (stress_full) {
            snprintf(a.name, sizeof a.name, "light on camera axis, gate start = straight time path tracer");
            a.integ = INTEG_PATH_TRACER;
            a.expect_lit = 0;
            cases[n++] = a;
            snprintf(a.name, sizeof a.name, "light on camera axis, gate start = straight time baseline");
            a.integ = INTEG_BASELINE;
            cases[n++] = a;
        }
    }
    {
        /* the radii of iteration 1e5 (2d schedule) for this scene's r0 and alpha, from the first pass on */
        stress_case c = case_default("radii of iteration 1e5 darts");
        c.r_vol = progressive_radius(c.r_vol, c.alpha, 100000, 2);
        c.r_surf = progressive_radius(c.r_surf, c.alpha, 100000, 2);
        if (case_selected(&c)) print_message("  radii after 1e5 iterations: volume %.4g, surface %.4g\n", c.r_vol, c.r_surf);
        cases[n++] = c;
        stress_case d = case_default("");
        c.alpha = 0.1; /* a fast-shrinking schedule: radii ~1/200 of r0 */
        c.r_vol = progressive_radius(d.r_vol, c.alpha, 100000, 2);
        c.r_surf = progressive_radius(d.r_surf, c.alpha, 100000, 2);
        snprintf(c.name, sizeof c.name, "radii of iteration 1e5, alpha 0.1 darts");
        if (case_selected(&c)) print_message("  radii after 1e5 iterations, alpha 0.1: volume %.4g, surface %.4g\n", c.r_vol, c.r_surf);
        cases[n++] = c;
        if (stress_full) {
            snprintf(c.name, sizeof c.name, "radii of iteration 1e5, alpha 0.1 baseline");
            c.integ = INTEG_BASELINE;
            cases[n++] = c;
        }
    }
    assert_true(n <= (int)(sizeof cases / sizeof *cases));
    run_matrix(cases, n, dir);
    group_end(dir, "geometry");
}

/* ---------------------------------------------------------------------------------------------------- */
/* 6. transient frames                                                                                   */

/* Frames [0.7 T0 + k·0.2 T0): frame 0 ends at 0.9 T0, before any light can arrive, so it must be exactly zero.
 * (Whether the frames hold the right values is test_darts_frames_vs_path_tracer's business: the union gate
 * image is written by the same splat as the frames, so comparing them could not fail.) */
static void frames_check(const stress_case *c, const char *dir)
{
    case_result r;
    film f;
    run_case(c, dir, &r, &f);
    if (!r.rendered) return;
    dp_error err;
    int F = f.window.frame_count;
    if (F != c->frames) case_fail(c, "%d frames in the film, %d asked for", F, c->frames);
    image_rgb *fr = calloc((size_t)F, sizeof(image_rgb));
    assert_non_null(fr);
    for (int k = 0; k < F; k++)
        if (film_image(&f, k, &fr[k], &err)) fail_msg("%s", err.msg);
    size_t n = (size_t)f.width * f.height * 3;
    double T0 = straight_time(c);
    int lit_frames = 0;
    for (int k = 0; k < F; k++) {
        int before = c->gate_start + (k + 1) * c->gate_width < T0;
        size_t nonzero = 0;
        for (size_t i = 0; i < n; i++) nonzero += fr[k].rgb[i] != 0.0f;
        lit_frames += nonzero > 0;
        if (before && nonzero) case_fail(c, "frame %d ends before the earliest arrival, yet %zu values are nonzero", k, nonzero);
    }
    if (c->expect_lit && lit_frames == 0) case_fail(c, "every frame is black");
    print_message("    %d of %d frames lit\n", lit_frames, F);
    for (int k = 0; k < F; k++) image_free(&fr[k]);
    free(fr);
    film_free(&f);
}

static void test_transient_frames(void **state)
{
    (void)state;
    char *dir = group_begin();
    for (int v = 0; v < (stress_full ? 4 : 1); v++) {
        const char *names[] = {"frames darts", "frames darts eda", "frames baseline", "frames path tracer"};
        stress_case c = case_default(names[v]);
        double T0 = straight_time(&c);
        c.frames = 8;
        c.gate_start = 0.7 * T0;
        c.gate_width = 0.2 * T0;
        c.eda = v == 1;
        c.integ = v == 2 ? INTEG_BASELINE : v == 3 ? INTEG_PATH_TRACER : INTEG_DARTS;
        c.expect_lit = c.integ != INTEG_PATH_TRACER;
        if (case_selected(&c)) frames_check(&c, dir);
    }
    group_end(dir, "frames");
}

int main(void)
{
    const char *mode = getenv("DARTSPP_STRESS");
    stress_full = mode && !strcmp(mode, "full");
    stress_only = getenv("DARTSPP_STRESS_ONLY");
    stress_keep = getenv("DARTSPP_STRESS_KEEP");
    if (stress_only && !stress_only[0]) stress_only = NULL;
    print_message("stress matrix: %s subset%s%s\n", stress_full ? "full" : "fast (DARTSPP_STRESS=full for all)",
                  stress_only ? ", cases matching " : "", stress_only ? stress_only : "");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_extinction_sweep),
        cmocka_unit_test(test_anisotropy_eda),
        cmocka_unit_test(test_gate_extremes),
        cmocka_unit_test(test_scale_invariance),
        cmocka_unit_test(test_geometry_edges),
        cmocka_unit_test(test_transient_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
