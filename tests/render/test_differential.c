/* tier: stress */
/* Integrators that check each other (issue 48, item 5): a differential fuzz tier. A seeded generator draws
 * small random scenes (8 × 8 pixels) from the object types and the key table -- an open floor, a box open
 * towards the camera or a closed box with the camera inside; no medium, fog everywhere (the camera in it) or a
 * fog cube (the camera inside or outside it), σs and σa per channel and a Henyey–Greenstein g in (−0.9, 0.9);
 * one light of every type (point, spot, area quad, sphere and disk, collimated beams of radius > 0 parallel or
 * diverging, a diverging radius-0 beam, the radius-0 parallel beam and `directional_point`), inside or outside
 * the fog, its `ext_medium` always set to where it is; a sphere of every BSDF model (lambert, conductor,
 * rough conductor, dielectric with and without refraction, rough dielectric, plastic, rough plastic; the rough
 * ones at α 0.3-0.7); box and
 * Gaussian pulses; steady state, a wide gate, a narrow gate or frames; camera-warped or unwarped time. Each
 * scene is rendered by the plain path tracer and by photon points, baseline and DARTS (enable_guiding,
 * enable_elliptical), with independent seeds, and the image mean per channel of the gate image and of every
 * frame must agree (the bound: a Bonferroni z over the run's comparisons from per-pass standard errors, after the bias
 * budget stated at bias_share). A scene where the integrators may legitimately disagree (a delta BSDF with a light the
 * path tracer cannot connect through it: caustics; a radius-0 parallel beam, which the path tracer cannot reach) is not
 * compared: the path tracer's warnings before the render must name the reason.
 *
 * Two more rules: a comparison whose per-pass values are too sparse for a standard error (Kish n_eff < 20, at
 * n_eff) is counted and left out, but a photon-points gate image black where the path tracer's is lit fails;
 * every medium here has η = 1, so a warning that refractive indices differ fails (it did, for unwarped time
 * with a continued surface in view: fixed in src/render/warnings.c).
 *
 * One line per scene: its index, description, per method the channel-mean image mean and its standard error,
 * and the largest z. make test runs DIFF_SCENES scenes, DARTSPP_STRESS=full (make stress) DIFF_STRESS_SCENES.
 * DARTSPP_DIFF_ONLY=i runs scene i alone (with the threshold of the whole run, so that its verdict is the
 * run's); DARTSPP_DIFF_KEEP=folder writes its three scene files there (diff-<i>-<method>.json) for
 * `dartspp render`; DARTSPP_DIFF_VERBOSE=1 prints every comparison's n_eff.
 *
 * Broken variants (tests/README.md quotes them): listed there. */
#include "fixtures.h"
#include "render_fixtures.h"

#include <math.h>
#include <stdarg.h>
#include <time.h>

#include "dartspp/plan.h"
#include "dartspp/render.h"

#define DIFF_SCENES 24
#define DIFF_STRESS_SCENES 300
#define DIFF_SEED 48u
#define DIFF_RES 8
#define DIFF_ALPHA 0.01 /* family-wise false-alarm rate of a run: Bonferroni over all its comparisons */

/* ---- random numbers: a scene's stream depends on its index only, so DARTSPP_DIFF_ONLY reproduces it ---- */

static uint64_t rng_s;
/* splitmix64: consecutive seeds give unrelated streams */
static uint32_t rnd(void) {
    uint64_t z = (rng_s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return (uint32_t)((z ^ (z >> 31)) >> 32);
}
static int pick(int n) { return (int)(rnd() % (uint32_t)n); }
static double unif(double a, double b) { return a + (b - a) * ((rnd() + 0.5) / 4294967296.0); }

/* ---- a scene as drawn ---- */

enum { GEO_OPEN, GEO_BOX, GEO_CLOSED, GEO_N };
enum { FOG_NONE, FOG_ALL, FOG_CUBE, FOG_N };
enum { L_POINT, L_SPOT, L_QUAD, L_SPHERE, L_DISK, L_BEAM, L_BEAM_DIV, L_PENCIL_DIV, L_PENCIL, L_DIRPOINT, L_N };
enum {
    B_LAMBERT,
    B_CONDUCTOR,
    B_ROUGH_CONDUCTOR,
    B_DIELECTRIC,
    B_DIELECTRIC_NOREFR,
    B_ROUGH_DIELECTRIC,
    B_PLASTIC,
    B_ROUGH_PLASTIC,
    B_N
};
enum { T_STEADY, T_WIDE, T_NARROW, T_FRAMES, T_N };
enum { M_PT, M_BASE, M_DARTS, M_N };

static const char *const geo_name[GEO_N] = {"open", "box", "closed"};
static const char *const fog_name[FOG_N] = {"vacuum", "fog-all", "fog-cube"};
static const char *const light_name[L_N] = {"point", "spot",     "quad",       "sphere", "disk",
                                            "beam",  "beam-div", "pencil-div", "pencil", "directional_point"};
static const char *const bsdf_name[B_N] = {"lambert",           "conductor",        "rough_conductor", "dielectric",
                                           "dielectric-norefr", "rough_dielectric", "plastic",         "rough_plastic"};
static const char *const time_name[T_N] = {"steady", "wide", "narrow", "frames"};
static const char *const method_name[M_N] = {"pt", "base", "darts"};

/* The fog cube is centred at CUBE_Y above the floor; a light at LIGHT_IN_Y is inside the small cube, one at
 * LIGHT_OUT_Y outside it (with the margins of a 0.1 sphere and a 0.3 beam disc), the object stays below it. */
#define CUBE_Y 1.1
#define CUBE_SMALL 1.2
#define CUBE_LARGE 2.6
#define LIGHT_IN_Y 1.3
#define LIGHT_OUT_Y 1.85

typedef struct {
    int geo, fog, light, bsdf, time, unwarp, pulse, max_bounces, frames;
    double cube, ss[3], sa[3], g, lx, ly, lz, power, pulse_width;
    double cone, cone_delta, beam_r, divergence, roughness, ior;
    double center, width, start; /* the gate, or the frames' start and width */
    double r_vol, r_surf, alpha; /* photon points' kernels */
    int cam_in_fog, light_in_fog;
} dscene;

static int light_is_area(int l) { return l == L_QUAD || l == L_SPHERE || l == L_DISK; }
static int bsdf_has_delta(int b) {
    return b == B_CONDUCTOR || b == B_DIELECTRIC || b == B_DIELECTRIC_NOREFR || b == B_PLASTIC;
}

/* Where the camera and the light are, and so which medium each starts in: set from the drawn layout. */
static void place(dscene *d) {
    double h = d->cube / 2;
    int light_in_cube = fabs(d->lx) < h && fabs(d->ly - CUBE_Y) < h && fabs(d->lz) < h;
    d->cam_in_fog = d->fog == FOG_ALL || (d->fog == FOG_CUBE && d->geo == GEO_CLOSED && d->cube == CUBE_LARGE);
    d->light_in_fog = d->fog == FOG_ALL || (d->fog == FOG_CUBE && light_in_cube);
}

static void draw_time(dscene *d) {
    d->time = pick(T_N);
    d->unwarp = pick(2);
    d->pulse = pick(3); /* delta, box, gaussian */
    d->pulse_width = d->pulse ? unif(0.2, 1.0) : 0;
    /* path lengths run from about 2 (camera inside the closed box) to about 12 (camera 3 in front of the
     * box); unwarped times leave out the camera leg */
    double c0 = (d->unwarp ? 3.0 : 5.0) - (d->geo == GEO_CLOSED ? 2.0 : 0.0);
    if (d->time == T_WIDE) d->center = c0 + unif(0, 2), d->width = 6;
    if (d->time == T_NARROW) d->center = c0 + unif(0, 2), d->width = 1.5;
    if (d->time == T_FRAMES) d->start = c0 - 1.5 + unif(0, 1), d->width = 1.5, d->frames = 2 + pick(2);
}

static void draw_light(dscene *d) {
    d->light = pick(L_N);
    d->lx = unif(-0.25, 0.25);
    d->lz = unif(-0.25, 0.25);
    d->ly = pick(2) ? LIGHT_IN_Y : LIGHT_OUT_Y;
    d->power = unif(5, 20);
    d->cone = unif(20, 70);
    d->cone_delta = unif(0, 0.5) * d->cone;
    d->beam_r = unif(0.05, 0.3);
    d->divergence = d->light == L_BEAM_DIV || d->light == L_PENCIL_DIV ? unif(5, 30) : 0;
}

static void draw(int idx, dscene *d) {
    memset(d, 0, sizeof *d);
    rng_s = ((uint64_t)DIFF_SEED << 32) + (uint64_t)idx;
    d->geo = pick(GEO_N);
    d->fog = pick(FOG_N);
    d->cube = pick(2) ? CUBE_SMALL : CUBE_LARGE;
    double ss = unif(0.1, 0.8), alb = unif(0.5, 0.95);
    for (int c = 0; c < 3; c++) {
        d->ss[c] = ss * unif(0.6, 1.4);
        d->sa[c] = d->ss[c] * (1 - alb) / alb * unif(0.5, 1.5);
    }
    d->g = unif(-0.9, 0.9);
    draw_light(d);
    /* a delta lobe with a light that has no area is a scene the path tracer warns about and is not compared:
     * drawn for a third of those lights, so that most scenes are compared */
    static const int smooth[] = {B_LAMBERT, B_ROUGH_CONDUCTOR, B_ROUGH_DIELECTRIC, B_ROUGH_PLASTIC};
    d->bsdf = light_is_area(d->light) || pick(3) == 0 ? pick(B_N) : smooth[pick(4)];
    /* rough, not near-specular: below α ≈ 0.3 the path tracer's connections through the lobe to a point light
     * are heavy-tailed (measured: a 400-pass render's per-pass standard error 0.10 against a spread of 0.43
     * over seeds at α = 0.12), and the z test's standard error would not hold */
    d->roughness = unif(0.3, 0.7);
    d->ior = unif(1.3, 1.7);
    draw_time(d);
    d->max_bounces = 3 + pick(4);
    d->r_vol = 0.02;
    d->r_surf = 0.03;
    d->alpha = pick(2) ? 1.0 : 0.7;
    place(d);
}

/* ---- the scene's text ---- */

typedef struct {
    char *p;
    size_t n, cap;
} sbuf;

static void sb_add(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_add(sbuf *b, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (b->n + (size_t)k + 1 > b->cap) {
        b->cap = (b->n + (size_t)k + 1) * 2;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
    va_start(ap, fmt);
    vsnprintf(b->p + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    b->n += (size_t)k;
}

static void add_bsdfs(sbuf *b, const dscene *d) {
    sb_add(b, "\"bsdfs\": [ {\"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.7},"
              " {\"name\": \"red\", \"type\": \"lambert\", \"albedo\": [0.7, 0.2, 0.1]},"
              " {\"name\": \"green\", \"type\": \"lambert\", \"albedo\": [0.15, 0.6, 0.2]},"
              " {\"name\": \"lamp\", \"type\": \"lambert\", \"albedo\": 0}, {\"name\": \"obj\", ");
    double r = d->roughness, n = d->ior;
    switch (d->bsdf) {
    case B_LAMBERT: sb_add(b, "\"type\": \"lambert\", \"albedo\": [0.5, 0.7, 0.8]"); break;
    case B_CONDUCTOR: sb_add(b, "\"type\": \"conductor\", \"material\": \"Au\""); break;
    case B_ROUGH_CONDUCTOR:
        sb_add(b, "\"type\": \"rough_conductor\", \"material\": \"Cu\", \"roughness\": %.4f", r);
        break;
    case B_DIELECTRIC: sb_add(b, "\"type\": \"dielectric\", \"ior\": %.4f", n); break;
    case B_DIELECTRIC_NOREFR:
        sb_add(b, "\"type\": \"dielectric\", \"ior\": %.4f, \"enable_refraction\": false", n);
        break;
    case B_ROUGH_DIELECTRIC:
        sb_add(b, "\"type\": \"rough_dielectric\", \"ior\": %.4f, \"roughness\": %.4f", n, r);
        break;
    case B_PLASTIC: sb_add(b, "\"type\": \"plastic\", \"ior\": %.4f, \"albedo\": [0.6, 0.3, 0.2]", n); break;
    default: sb_add(b, "\"type\": \"rough_plastic\", \"ior\": %.4f, \"roughness\": %.4f, \"albedo\": 0.5", n, r); break;
    }
    sb_add(b, "} ],");
}

static void add_quad(sbuf *b, const char *bsdf, double x, double y, double z, double s, const char *rot) {
    sb_add(b,
           "{\"type\": \"quad\", \"bsdf\": \"%s\", \"transform\": {\"position\": [%g, %g, %g], \"scale\": [%g, 1, "
           "%g]%s}},",
           bsdf, x, y, z, s, s, rot);
}

/* The floor (open scene), or the box of five walls open towards the camera (-z), or six walls. */
static void add_geometry(sbuf *b, const dscene *d) {
    if (d->geo == GEO_OPEN) {
        add_quad(b, "white", 0, 0, 0, 6, "");
        return;
    }
    add_quad(b, "white", 0, 0, 0, 2, "");
    add_quad(b, "white", 0, 2, 0, 2, ", \"rotation\": [180, 0, 0]");
    add_quad(b, "white", 0, 1, 1, 2, ", \"rotation\": [-90, 0, 0]");
    add_quad(b, "green", -1, 1, 0, 2, ", \"rotation\": [0, 0, -90]");
    add_quad(b, "red", 1, 1, 0, 2, ", \"rotation\": [0, 0, 90]");
    if (d->geo == GEO_CLOSED) add_quad(b, "white", 0, 1, -1, 2, ", \"rotation\": [90, 0, 0]");
}

/* The light's medium keys: where it starts its paths (docs/emitters.md §1); a thin area light binds both sides. */
static const char *light_media(const dscene *d) {
    if (!d->light_in_fog) return "";
    return light_is_area(d->light) ? ", \"ext_medium\": \"fog\", \"int_medium\": \"fog\"" : ", \"ext_medium\": \"fog\"";
}

static void add_pulse(sbuf *b, const dscene *d) {
    if (d->pulse)
        sb_add(b, ", \"pulse_width\": %.4f, \"pulse_shape\": \"%s\"", d->pulse_width,
               d->pulse == 1 ? "box" : "gaussian");
}

static void add_light(sbuf *b, const dscene *d) {
    double x = d->lx, y = d->ly, z = d->lz;
    static const char *const type[L_N] = {"point",      "spot",       "quad",       "sphere",     "disk",
                                          "collimated", "collimated", "collimated", "collimated", "directional_point"};
    sb_add(b, "{\"type\": \"%s\", \"power\": %.4f%s", type[d->light], d->power, light_media(d));
    add_pulse(b, d);
    switch (d->light) {
    case L_QUAD:
        sb_add(b,
               ", \"bsdf\": \"lamp\", \"transform\": {\"position\": [%g, %g, %g], \"scale\": [0.4, 1, 0.4], "
               "\"rotation\": [180, 0, 0]}}",
               x, y, z);
        return;
    case L_DISK:
        sb_add(b,
               ", \"bsdf\": \"lamp\", \"transform\": {\"position\": [%g, %g, %g], \"scale\": [0.2, 1, 0.2], "
               "\"rotation\": [180, 0, 0]}}",
               x, y, z);
        return;
    case L_SPHERE:
        sb_add(b, ", \"bsdf\": \"lamp\", \"transform\": {\"position\": [%g, %g, %g], \"scale\": 0.1}}", x, y, z);
        return;
    case L_SPOT: sb_add(b, ", \"coneangle\": %.3f, \"conedeltaangle\": %.3f", d->cone, d->cone_delta); break;
    case L_BEAM:
    case L_BEAM_DIV: sb_add(b, ", \"radius\": %.4f, \"divergence\": %.3f", d->beam_r, d->divergence); break;
    case L_PENCIL_DIV: sb_add(b, ", \"divergence\": %.3f", d->divergence); break;
    default: break;
    }
    /* point-like lights and beams aim down and slightly across, towards the floor in front of the object */
    sb_add(b, ", \"transform\": {\"position\": [%g, %g, %g], \"look_at\": [%g, 0, %g], \"up\": [1, 0, 0]}}", x, y, z,
           -0.6 * x - 0.2, -0.6 * z - 0.2);
}

static void add_primitives(sbuf *b, const dscene *d) {
    sb_add(b, "\"primitives\": [");
    add_geometry(b, d);
    /* a sphere: no edges, where surface photons' discs would hang over (bias_share) */
    sb_add(b, "{\"type\": \"sphere\", \"bsdf\": \"obj\", \"transform\": {\"position\": [0.4, 0.22, 0.35], \"scale\": "
              "0.22}},");
    if (d->fog == FOG_CUBE)
        sb_add(b,
               "{\"type\": \"cube\", \"bsdf\": {\"type\": \"forward\"}, \"int_medium\": \"fog\","
               " \"transform\": {\"position\": [0, %g, 0], \"scale\": %g}},",
               CUBE_Y, d->cube);
    add_light(b, d);
    sb_add(b, "],");
}

static void add_time(sbuf *b, const dscene *d) {
    if (d->time == T_WIDE || d->time == T_NARROW)
        sb_add(b, ", \"transient_time_center\": %.4f, \"transient_time_width\": %.4f", d->center, d->width);
    if (d->time == T_FRAMES)
        sb_add(b, ", \"start_time\": %.4f, \"transient_time_width\": %.4f, \"frame_num\": %d", d->start, d->width,
               d->frames);
    if (d->time != T_STEADY && d->unwarp) sb_add(b, ", \"camera_unwarp\": true");
}

static void add_integrator(sbuf *b, const dscene *d, int m) {
    sb_add(b, "\"integrator\": {\"max_bounces\": %d", d->max_bounces);
    add_time(b, d);
    if (m == M_PT) {
        sb_add(b, ", \"type\": \"path_tracer\"},");
        return;
    }
    /* fixed or shrinking radii; glossy_regularization 0: no biased connection after a glossy bounce */
    sb_add(b,
           ", \"type\": \"progressive_transient_photon_map\", \"photon_count\": 3000, \"volume_photon_count\": 1e6,"
           " \"gather_photon_count\": 64, \"gather_radius\": %g, \"volume_gather_radius\": %g, \"alpha\": %g,"
           " \"volume_alpha\": %g, \"glossy_regularization\": 0%s},",
           d->r_surf, d->r_vol, d->alpha, d->alpha,
           m == M_DARTS ? ", \"enable_guiding\": true, \"enable_elliptical\": true" : "");
}

static char *scene_text(const dscene *d, int m) {
    sbuf b = {0};
    sb_add(&b, "{\"media\": [");
    if (d->fog != FOG_NONE)
        sb_add(&b,
               "{\"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [%.4f, %.4f, %.4f], \"sigma_a\": [%.4f, "
               "%.4f, %.4f],"
               " \"phase_function\": {\"type\": \"henyey_greenstein\", \"g\": %.4f}}",
               d->ss[0], d->ss[1], d->ss[2], d->sa[0], d->sa[1], d->sa[2], d->g);
    sb_add(&b, "],");
    add_bsdfs(&b, d);
    add_primitives(&b, d);
    int inside = d->geo == GEO_CLOSED;
    sb_add(&b,
           "\"camera\": {\"type\": \"pinhole\", \"resolution\": [%d, %d], \"fov\": %d%s, \"transform\": {\"position\": "
           "[0, 1, %g],"
           " \"look_at\": [0, 0.8, 1], \"up\": [0, 1, 0]}},",
           DIFF_RES, DIFF_RES, inside ? 80 : 45, d->cam_in_fog ? ", \"medium\": \"fog\"" : "", inside ? -0.85 : -3.0);
    add_integrator(&b, d, m);
    sb_add(&b, "\"renderer\": {\"spp\": 1}}");
    return b.p;
}

static void describe(const dscene *d, char *out, size_t n) {
    snprintf(out, n, "%s %s%s%s %s%s %s g=%.2f %s%s%s b%d r=%g/%g a=%g", geo_name[d->geo], fog_name[d->fog],
             d->fog == FOG_CUBE ? (d->cube == CUBE_SMALL ? "(1.2)" : "(2.6)") : "", d->cam_in_fog ? " cam-in" : "",
             light_name[d->light], d->light_in_fog ? "(in fog)" : "", bsdf_name[d->bsdf], d->g, time_name[d->time],
             d->time != T_STEADY && d->unwarp ? "-unwarped" : "",
             d->pulse == 1   ? " box-pulse"
             : d->pulse == 2 ? " gauss-pulse"
                             : "",
             d->max_bounces, d->r_vol, d->r_surf, d->alpha);
}

/* ---- what may legitimately differ: the path tracer's warning must say why ---- */

/* The text the path tracer's warning must contain for a scene where the integrators may disagree, or NULL
 * where they must agree: a delta lobe (smooth metal or glass, a plastic's coat) with a light the path tracer
 * cannot connect through it misses caustics (docs/emitters.md §7); a radius-0 parallel beam is not reached. */
static const char *expected_warning(const dscene *d) {
    if (d->light == L_PENCIL || d->light == L_DIRPOINT) return "parallel beam of radius 0";
    if (bsdf_has_delta(d->bsdf) && !light_is_area(d->light)) return "cannot connect through it";
    return NULL;
}

/* Loads the scene of method m and plans it; its warnings (the loader's notes and render_warn's) into *warn. */
static void load_method(const dscene *d, int m, int idx, tmp_scene *t, scene *s, char **warn) {
    char *text = scene_text(d, m);
    tmp_scene_write(t, text);
    const char *keep = getenv("DARTSPP_DIFF_KEEP");
    if (keep && keep[0]) {
        char path[1024];
        snprintf(path, sizeof path, "%s/diff-%d-%s.json", keep, idx, method_name[m]);
        write_bytes(path, text, strlen(text));
    }
    free(text);
    load_scene(t->path, NULL, 0, s);
    dp_error err;
    render_plan p;
    if (plan_resolve(s, &p, &err)) fail_msg("scene %d (%s): %s", idx, method_name[m], err.msg);
    size_t n = 0;
    FILE *f = open_memstream(warn, &n);
    assert_non_null(f);
    if (s->notes) fputs(s->notes, f);
    render_warn(f, s, &p);
    fclose(f);
    plan_free(&p);
}

/* ---- the comparison ---- */

/* Passes per method: the path tracer's passes are one sample per pixel, photon points' one photon pass and one
 * gather; the counts give standard errors of a few per cent of the image mean at similar costs. */
#define PT_PASSES 400
#define PP_PASSES 64

/* The bias budget of photon points against the path tracer. The path tracer is unbiased; photon points are
 * consistent, their bias set by the kernels (volume radius r, surface radius R; with α < 1 they shrink, and the
 * first pass's radii bound the rest). To first order in the radii, three ways the kernel moves light into or
 * out of what an image mean counts (each for light spread evenly at the scale of the radii):
 *   time    a photon counts at the ray point nearest to it, a hop of at most ρ = max(r, R) (R alone without fog;
 *           speed 1 or less), which moves its time by at most ρ; only light arriving within ρ of an end of the
 *           gate or frame can cross it. Taking the arrival density at an edge to be at most twice the larger
 *           mean density (image mean / width) of the two windows it separates (outside a gate, or outside the
 *           frames' union, the window's own), and all of that band to move (DARTS's photons, aimed at the
 *           window, need not move symmetrically): 2ρ · max(m, m_neighbour) / W per edge, absolute (time_allowance);
 *   edges   a surface photon's disc beyond a face's edge is lost: over a face of area A and perimeter P, lit
 *           evenly, the lost share is (2R/(3π))·P/A (the disc's part beyond a line at distance x, integrated
 *           over 0 ≤ x ≤ R, is 2R/(3π)). The walls are 2 × 2 (P/A = 2, the open floor less), the object is a
 *           sphere (no edge) and the lamps' surfaces are black (their photons carry nothing): (4/(3π))·R;
 *   ends    a volume photon counts when its foot falls on the ray's segment. Where the segment ends on a
 *           surface or the fog's boundary tilted by θ, the part of the kernel's cylinder beyond it holds no
 *           photons: a loss of mean length (2r/3)·tan θ/π over the disc, 0.37·r at θ = 60°; at both ends of
 *           segments at least 0.5 long (the small fog cube seen edge-on): 1.5·r.
 * The edges and ends terms are a share of the larger mean (0.043 in fog, 0.013 in vacuum, bias_share); the time
 * term adds 4ρ/W of the image's own mean for a gate of width W (0.08 at W = 1.5 in fog), more for a frame next
 * to a brighter one. Broken variants this comparison was shown failing on: tests/README.md. */
static double rho_of(const dscene *d) { return d->fog != FOG_NONE ? fmax(d->r_vol, d->r_surf) : d->r_surf; }

static double bias_share(const dscene *d) {
    return 4 * d->r_surf / (3 * M_PI) + (d->fog != FOG_NONE ? 1.5 * d->r_vol : 0);
}

/* The time term for image im (0: the gate image, or the frames' union; 1 + k: frame k), channel c, from the
 * largest |mean| of the three methods per image (v, images × 3). */
static double time_allowance(const dscene *d, const double *v, int im, int c) {
    if (d->time == T_STEADY) return 0;
    double rho = rho_of(d);
    if (im == 0) return 2 * 2 * rho * v[c] / (d->width * (d->frames ? d->frames : 1));
    int k = im - 1, left = k > 0 ? im - 1 : im, right = k + 1 < d->frames ? im + 1 : im;
    return 2 * rho / d->width * (fmax(v[3 * im + c], v[3 * left + c]) + fmax(v[3 * im + c], v[3 * right + c]));
}

/* Two-sided normal quantile: z with erfc(z/√2) = p, by bisection. */
static double z_two_sided(double p) {
    double lo = 0, hi = 40;
    for (int k = 0; k < 200; k++) {
        double mid = 0.5 * (lo + hi);
        if (erfc(mid / M_SQRT2) > p)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

/* The images (gate image and frames) × 3 channels × 2 photon methods of a compared scene. */
static int comparisons(const dscene *d) { return expected_warning(d) ? 0 : 2 * 3 * (1 + d->frames); }

/* Kish's effective sample size of the per-pass values of image m, channel c: (Σx)²/Σx². A mean of few rare,
 * large contributions (photons that reach a late frame, sparse as a Poisson count) is heavy-tailed: its
 * per-pass spread says little about the error of the mean (scene 74 of the stress set, DARTS, frame 1: 0.107 ±
 * 0.029 over 64 passes with n_eff 11, against 0.79 over 8 renders of 64 passes from 0.24 to 1.8). */
static double n_eff(const pass_totals *t, int m, int c) {
    double s = 0, s2 = 0;
    for (long i = 0; i < t->n; i++) {
        double x = t->x[((size_t)i * t->images + m) * 3 + c];
        s += x;
        s2 += x * x;
    }
    return s2 > 0 ? s * s / s2 : 0;
}

#define N_EFF_MIN 20 /* below: the comparison is sparse, not made (counted and printed) */

/* z of photon points' image m, channel c against the path tracer's after the bias budget (0 inside it): a share
 * of the larger mean and an absolute allowance. */
static double z_of(const pass_totals *pt, const pass_totals *pp, int m, int c, double share, double extra,
                   double *raw) {
    double a, sa, b, sb;
    pass_totals_mean_se(pt, m, c, &a, &sa);
    pass_totals_mean_se(pp, m, c, &b, &sb);
    double se = hypot(sa, sb), d = fabs(a - b), allowed = share * fmax(fabs(a), fabs(b)) + extra;
    *raw = se > 0 ? d / se : (d > 0 ? INFINITY : 0);
    if (d <= allowed) return 0;
    return se > 0 ? (d - allowed) / se : INFINITY;
}

typedef struct {
    int run, agreed, warned, failed, noted; /* noted: compared scenes with some other warning, printed */
    long compared, sparse;                  /* comparisons made, and left out as sparse */
} diff_counts;

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void render_method(const dscene *d, int m, int idx, pass_totals *t, char **warn) {
    tmp_scene ts;
    scene s;
    load_method(d, m, idx, &ts, &s, warn);
    uint64_t seed = 1000003u * (uint64_t)idx + 17u * (uint64_t)m + 1;
    render_totals(&s, seed, 1, m == M_PT ? PT_PASSES : PP_PASSES, t);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* A scene where the integrators may disagree: the path tracer's warnings must name why. */
static int check_warned(const dscene *d, int idx, const char *desc, diff_counts *n) {
    tmp_scene ts;
    scene s;
    char *warn = NULL;
    load_method(d, M_PT, idx, &ts, &s, &warn);
    scene_free(&s);
    tmp_scene_remove(&ts);
    const char *want = expected_warning(d);
    int ok = warn && strstr(warn, want);
    print_message("diff %4d %-80s warned: %s\n", idx, desc, ok ? want : "MISSING");
    if (!ok)
        print_message("FAIL scene %d: expected a warning containing \"%s\"; got:\n%s\n", idx, want, warn ? warn : "");
    free(warn);
    n->warned += ok;
    n->failed += !ok;
    return ok;
}

/* The comparison with the largest raw z: which method, image (0 the gate image, k frame k) and channel. */
static void print_worst(const pass_totals *t, const int w[3]) {
    double v[M_N], e[M_N];
    for (int m = 0; m < M_N; m++) pass_totals_mean_se(&t[m], w[1], w[2], &v[m], &e[m]);
    print_message("  largest z: %s, image %d channel %d: pt %.5g±%.2g base %.5g±%.2g darts %.5g±%.2g\n",
                  method_name[w[0]], w[1], w[2], v[0], e[0], v[1], e[1], v[2], e[2]);
}

/* Renders scene idx by the three methods and compares; 1 when it agrees. */
static int run_scene(int idx, double zcrit, diff_counts *n) {
    dscene d;
    draw(idx, &d);
    char desc[256];
    describe(&d, desc, sizeof desc);
    n->run++;
    if (expected_warning(&d)) return check_warned(&d, idx, desc, n);
    pass_totals t[M_N];
    char *warn[M_N] = {0};
    double t0 = now_seconds();
    double tm[M_N];
    for (int m = 0; m < M_N; m++) {
        double t1 = now_seconds();
        render_method(&d, m, idx, &t[m], &warn[m]);
        tm[m] = now_seconds() - t1;
    }
    double budget = bias_share(&d), zmax = 0, rawmax = 0, mean[M_N], se[M_N];
    double *v = calloc((size_t)t[0].images * 3, sizeof *v); /* largest |mean| per image and channel */
    assert_non_null(v);
    for (int im = 0; im < t[0].images; im++)
        for (int c = 0; c < 3; c++)
            for (int m = 0; m < M_N; m++) {
                double x, e;
                pass_totals_mean_se(&t[m], im, c, &x, &e);
                v[3 * im + c] = fmax(v[3 * im + c], fabs(x));
            }
    int worst[3] = {0, 0, 0}; /* method, image, channel of the largest raw z */
    for (int m = 0; m < M_N; m++) pass_totals_mean_se(&t[m], 0, 3, &mean[m], &se[m]);
    for (int m = M_BASE; m < M_N; m++)
        for (int im = 0; im < t[0].images; im++)
            for (int c = 0; c < 3; c++) {
                double ne_pt = n_eff(&t[M_PT], im, c), ne = n_eff(&t[m], im, c);
                if (im == 0 && ne == 0 && ne_pt >= N_EFF_MIN) { /* a black gate image where the path tracer's is lit */
                    zmax = INFINITY;
                    continue;
                }
                if (getenv("DARTSPP_DIFF_VERBOSE"))
                    print_message("  %s image %d channel %d: n_eff %.1f, pt %.1f\n", method_name[m], im, c, ne, ne_pt);
                if (fmin(ne, ne_pt) < N_EFF_MIN && v[3 * im + c] > 0) {
                    n->sparse++;
                    continue;
                }
                n->compared++;
                double raw, z = z_of(&t[M_PT], &t[m], im, c, budget, time_allowance(&d, v, im, c), &raw);
                zmax = fmax(zmax, z);
                if (raw > rawmax) rawmax = raw, worst[0] = m, worst[1] = im, worst[2] = c;
            }
    int ok = zmax <= zcrit;
    print_message("diff %4d %-80s pt %.4g±%.2g base %.4g±%.2g darts %.4g±%.2g share %.3f z %.2f (raw %.2f) %.1fs "
                  "(%.1f/%.1f/%.1f)%s\n",
                  idx, desc, mean[0] / 3, se[0] / 3, mean[1] / 3, se[1] / 3, mean[2] / 3, se[2] / 3, budget, zmax,
                  rawmax, now_seconds() - t0, tm[0], tm[1], tm[2], ok ? "" : "  DISAGREE");
    if (!ok || rawmax > 3) print_worst(t, worst);
    free(v);
    for (int m = 0; m < M_N; m++) {
        /* every medium and vacuum here has η = 1: a warning that indices differ is false (it was given for
         * control vertices turned off by unwarped time with a continued surface in view, scenes 21-23) */
        if (warn[m] && strstr(warn[m], "refractive index differs")) {
            print_message("FAIL scene %d: a warning about refractive indices, all of which are 1\n", idx);
            ok = 0;
        }
        if (warn[m] && warn[m][0]) print_message("  %s warned: %s", method_name[m], warn[m]);
        if (warn[m] && warn[m][0]) n->noted++;
        free(warn[m]);
        pass_totals_free(&t[m]);
    }
    n->agreed += ok;
    n->failed += !ok;
    return ok;
}

/* Runs scenes [first, first + count) (or DARTSPP_DIFF_ONLY's alone, when it falls there) at the Bonferroni
 * threshold of all their comparisons. */
static int only_index(void);
static void run_set(int first, int count) {
    long ncmp = 0;
    for (int i = first; i < first + count; i++) {
        dscene d;
        draw(i, &d);
        ncmp += comparisons(&d);
    }
    double zcrit = z_two_sided(DIFF_ALPHA / (double)ncmp);
    int one = only_index();
    if (one >= 0 && (one < first || one >= first + count)) return;
    print_message("differential: scenes %d..%d, %ld comparisons, |z| threshold %.2f (Bonferroni, α %.2g)\n", first,
                  first + count - 1, ncmp, zcrit, DIFF_ALPHA);
    diff_counts n = {0};
    for (int i = first; i < first + count; i++)
        if (one < 0 || i == one) run_scene(i, zcrit, &n);
    print_message("differential: %d scenes run, %d agreed, %d not compared (the expected warning given), %d failed;"
                  " %ld comparisons made, %ld left out as sparse (n_eff < %d); %d other warnings printed\n",
                  n.run, n.agreed, n.warned, n.failed, n.compared, n.sparse, N_EFF_MIN, n.noted);
    assert_int_equal(n.failed, 0);
}

/* DARTSPP_DIFF_ONLY=i, or -1 */
static int only_index(void) {
    const char *only = getenv("DARTSPP_DIFF_ONLY");
    return only && only[0] ? atoi(only) : -1;
}

static void test_differential(void **state) {
    (void)state;
    run_set(0, DIFF_SCENES);
    if (!stress_full() && only_index() >= DIFF_SCENES)
        run_set(DIFF_SCENES, DIFF_STRESS_SCENES); /* a stress scene alone */
}

static void test_differential_stress(void **state) {
    (void)state;
    run_set(DIFF_SCENES, DIFF_STRESS_SCENES);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_differential)};
    const struct CMUnitTest stress_tests[] = {cmocka_unit_test(test_differential_stress)};
    return RUN_TESTS_AND_STRESS(tests, stress_tests);
}
