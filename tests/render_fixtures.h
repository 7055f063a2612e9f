/* Render-level fixtures shared by the test programs, defined in tests/render_fixtures.c (linked into every
 * test program): scene files in a temp folder, renders and their per-pass totals, the scenes of the
 * photon-points tests (the fog box and the fog slab) and single photon passes. */
#ifndef DARTSPP_TEST_RENDER_FIXTURES_H
#define DARTSPP_TEST_RENDER_FIXTURES_H

#include "test_util.h"

#include "dartspp/darts.h"
#include "dartspp/gather.h"
#include "dartspp/photon.h"
#include "dartspp/render.h"

/* ---- scene files in a temp folder ---- */

typedef struct {
    char *dir;
    char path[512];
} tmp_scene;

/* Writes text to <a fresh temp folder>/scene.json. */
void tmp_scene_write(tmp_scene *t, const char *text);
/* Removes the folder of tmp_scene_write. */
void tmp_scene_remove(tmp_scene *t);
/* Loads the scene file with nsets `--set` overrides (sets may be NULL when nsets is 0); fails the test with
 * the loader's message. */
void load_scene(const char *path, const char *const *sets, int nsets, scene *s);

/* ---- renders and their per-pass totals ---- */

/* Per-pass image totals. The passes of a progressive render are independent draws (their random numbers
 * are keyed by seed and pass), so the per-pass totals of one or several renders are independent samples of
 * the estimator's image total: their spread gives the standard error of the mean total with hundreds of
 * degrees of freedom, where a few seeds would give two or three. The radii shrink from pass to pass, so the
 * samples are not identically distributed; the pooled sample variance then exceeds the variance of their
 * mean by the spread of the per-pass expectations, which only makes the standard error conservative. */
typedef struct {
    int images;   /* 1 + frames: image 0 is the gate image (frame mode: the union window), image 1 + k frame k */
    long n, cap;  /* passes recorded */
    double *x;    /* x[(i·images + m)·3 + c]: pass i, image m, channel c */
    double *last; /* the film's totals after the previous pass, images × 3 */
} pass_totals;

void pass_totals_init(pass_totals *t, int frames);
void pass_totals_free(pass_totals *t);
/* Mean over the recorded passes of image m, channel c (c = 3: the sum of the channels), and its standard
 * error from the spread of the passes. */
void pass_totals_mean_se(const pass_totals *t, int m, int c, double *mean, double *se);

/* What a render records after each pass: the per-pass totals, and optionally the mean image after pass
 * snap_pass (for the error of an early iteration count, from the same passes). */
typedef struct {
    pass_totals *t;
    long snap_pass;
    double *snap;
} pass_probe;

/* render_options.after_pass for a pass_probe (ctx). */
int pass_probe_after(void *ctx, const film *f, const render_stats *st, dp_error *err);
/* Mean image of a render as doubles (film sum / weight sum), 3 values per pixel; with probe, its per-pass
 * totals and snapshot are recorded too. The caller frees it. */
double *render_probe(const scene *s, int threads, uint64_t seed, long passes, pass_probe *probe);
/* A render of `passes` passes into f (the caller frees it); every pass ran and no sample was non-finite. */
void render_passes(const scene *s, int threads, uint64_t seed, long passes, film *f, render_stats *st);
/* Mean image of a render as doubles (film sum / weight sum), 3 values per pixel. */
double *render_mean(const scene *s, int threads, uint64_t seed, long passes);
/* Renders `seeds` renders (seeds seed0, seed0 + 1, ...) of `passes` passes, recording their per-pass totals
 * into t (initialised here for the scene's frames). */
void render_totals(const scene *s, uint64_t seed0, int seeds, long passes, pass_totals *t);

/* ---- the photon-points tests' scenes ---- */

/* Photon-pass keys: the DARTS samplers (as the paper's scenes turn them on) or none. */
#define DARTS_KEYS_TEXT "\"enable_guiding\": true, \"enable_elliptical\": true, \"strict_time_width\": true"
extern const char *const DARTS_KEYS;
extern const char *const BASELINE_KEYS;

/* The box's materials and its five Lambertian walls (2 × 2 × 2, open towards -z), opening the primitives list. */
/* ---- per-tile totals (the per-tile comparisons of unbiased or equally smoothed estimators) ----
 * Per pass: the total of each of TILES × TILES tiles of the gate image (all channels) and, in frame mode,
 * of each frame; the spread over thousands of passes gives standard errors with thousands of degrees of
 * freedom. */
#define TILES 4
#define NT (TILES * TILES)
#define MAX_FRAMES 4
#define CELLS (NT + MAX_FRAMES)
typedef struct {
    int frames;
    long n, cap;
    double *x; /* per pass: CELLS totals */
    double last[CELLS];
} cell_totals;

/* render_options.after_pass for a cell_totals (ctx; frames set, the rest zero). */
int cell_probe(void *ctx, const film *f, const render_stats *st, dp_error *err);
/* Mean over the passes of cell v and its standard error. */
void cell_mean_se(const cell_totals *t, int v, double *mean, double *se);
/* Per cell (the tiles, then each frame's total) of m against the reference ref: the largest |z| after a bias
 * budget of `bias` × the reference's cell, printed with the worst cell and the image totals; *z_total (may be
 * NULL) the totals' |z| after the same budget. Fails the test when a cell is dark in either (the scenes fill
 * the film). */
double cells_z(const char *label, const cell_totals *ref, const cell_totals *m, double bias, double *z_total);
/* Renders the scene `text` (written to a temp folder) for `passes` passes with 2 threads and `seed` into the
 * per-pass cells of t (frames: the frame count to record); *seconds the render's wall time. Fails the test on
 * an error, a suppressed non-finite sample or a missing pass. */
void cell_render(const char *text, long passes, uint64_t seed, int frames, cell_totals *t, double *seconds);

/* ---- per-tile totals of the gate image and its derivative images (tests/derivative/) ----
 * Per pass: the TILES × TILES tile totals (all channels) of the gate image, then of each of its first k derivative
 * images ((1 + k)·NT values per pass, image-major), as this pass's estimate. */
typedef struct {
    int k;        /* the derivative images recorded */
    long n, cap;  /* passes recorded */
    double *x;    /* x[((pass · (1 + k)) + image) · NT + tile]: image 0 the gate image, 1 + j derivative j */
    double last[(1 + DIFF_PARAM_MAX) * NT];
} deriv_tiles;
/* render_options.after_pass for a deriv_tiles (ctx; k set, the rest zero). */
int deriv_tiles_probe(void *ctx, const film *f, const render_stats *st, dp_error *err);
/* Renders s for `passes` passes with 2 threads and `seed` into t (cleared here, recording k derivative images);
 * fails the test on an error, a suppressed non-finite sample or a missing pass. *out (may be NULL) keeps the film. */
void deriv_tiles_render(const scene *s, int k, long passes, uint64_t seed, deriv_tiles *t, film *out);

#define BOX_WALLS                                                                                                  \
    "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.7 },"                                  \
    "               { \"name\": \"red\", \"type\": \"lambert\", \"albedo\": [0.7, 0.15, 0.1] },"                       \
    "               { \"name\": \"green\", \"type\": \"lambert\", \"albedo\": [0.15, 0.6, 0.2] } ],"                   \
    "  \"primitives\": ["                                                                                           \
    "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 0, 0], \"scale\": [2, 1, 2] } }," \
    "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 2, 0], \"scale\": [2, 1, 2],"      \
    "      \"rotation\": [180, 0, 0] } },"                                                                         \
    "    { \"type\": \"quad\", \"bsdf\": \"white\", \"transform\": { \"position\": [0, 1, 1], \"scale\": [2, 1, 2],"      \
    "      \"rotation\": [-90, 0, 0] } },"                                                                         \
    "    { \"type\": \"quad\", \"bsdf\": \"green\", \"transform\": { \"position\": [-1, 1, 0], \"scale\": [2, 1, 2],"     \
    "      \"rotation\": [0, 0, -90] } },"                                                                         \
    "    { \"type\": \"quad\", \"bsdf\": \"red\", \"transform\": { \"position\": [1, 1, 0], \"scale\": [2, 1, 2],"        \
    "      \"rotation\": [0, 0, 90] } },"


/* The fog box's other lights (JSON primitives for lamp_box_text): a ceiling panel facing down (box pulse) and a
 * spot beside the camera in a clear pocket (Gaussian pulse), aimed into the box (the gated camera's flash); a
 * collimated beam of radius 0.08 across the box, from the left wall's side toward the back right. */
#define FOG_BOX_PANEL_AND_SPOT                                                                                               \
    "{ \"type\": \"quad\", \"name\": \"panel\", \"bsdf\": \"white\", \"emission\": [3, 2.5, 2], \"int_medium\": \"fog\","   \
    "  \"ext_medium\": \"fog\", \"pulse_width\": 0.3,"                                                                 \
    "  \"transform\": { \"position\": [0.3, 1.96, 0.1], \"scale\": [0.7, 1, 0.7], \"rotation\": [180, 0, 0] } },"     \
    "{ \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"ext_medium\": \"fog\","                              \
    "  \"transform\": { \"position\": [-0.5, 1.2, -2.2], \"scale\": [0.3, 0.3, 0.3] } },"                              \
    "{ \"type\": \"spot\", \"name\": \"flash\", \"emission\": [5, 6, 7], \"coneangle\": 30, \"conedeltaangle\": 10,"   \
    "  \"pulse_start\": 0.1, \"pulse_width\": 0.4, \"pulse_shape\": \"gaussian\","                                      \
    "  \"transform\": { \"position\": [-0.5, 1.2, -2.2], \"look_at\": [0.2, 0.7, 0.8], \"up\": [0, 1, 0] } }"
#define FOG_BOX_COLLIMATED                                                                                                   \
    "{ \"type\": \"collimated\", \"name\": \"laser\", \"radius\": 0.08, \"emission\": [60, 50, 40], \"ext_medium\": \"fog\"," \
    "  \"transform\": { \"position\": [-0.9, 1.4, -0.8], \"look_at\": [0.9, 0.6, 0.9], \"up\": [0, 1, 0] } }"

/* The fog box (render_fixtures.c tells its design): res × res pixels, the integrator's keys, HG g, the
 * camera in the fog or in vacuum outside an index-matched fog cube. */
void box_scene_text_cam(char *text, size_t len, int res, const char *integrator, double g, int camera_in_fog);
/* The fog box (16², camera in HG fog) with `lights`, JSON primitives, in place of its point light: the emitter
 * and beams tiles. */
void lamp_box_text(char *text, size_t len, const char *integrator, const char *lights);
/* The fog box with g = 0.3 and the camera in the fog. */
void box_scene_text(char *text, size_t len, int res, const char *integrator);
/* The box's fog made grey (σs 0.45, σa 0.05 in every channel), in place. */
void box_scene_make_grey(char *text);

/* The light of slab_scene_text; two pulsed lights for the transient tests (issue 21). */
#define SLAB_LIGHT "{ \"type\": \"point\", \"emission\": [4, 4, 4], \"transform\": { \"position\": [0.6, 0.4, -2.5] } }"
/* The fog slab (render_fixtures.c tells its design) lit by `lights` (JSON primitives), integrator `type`,
 * the time keys `time` and the photon-pass keys `darts`. */
void slab_scene_text_lights(char *text, size_t len, double speed, const char *type, const char *time,
                            const char *darts, const char *lights);
/* The fog slab lit by SLAB_LIGHT. */
void slab_scene_text(char *text, size_t len, double speed, const char *type, const char *time, const char *darts);

/* ---- the progressive radius schedule and the photon pass ---- */

/* r0 · (Π_{j=1..i} (j+α)/(j+1))^{1/dims}, the radius of iteration i, by Γ functions. */
double radius_closed_form(double r0, double alpha, long i, int dims);
/* Field by field: the struct has padding, whose bytes are indeterminate. */
void assert_photon_identical(const photon *a, const photon *b);
/* One photon pass of the scene's plan without EDA tables, its DARTS surface tests widened for gathers of
 * radius surface_radius. */
int run_photon_pass(const scene *s, uint64_t seed, long iteration, double surface_radius, photon_set *out,
                    dp_error *err);
/* The same with the plan's chain_share set (surface_paths: the chains trace this share of the paths left). */
int run_photon_pass_share(const scene *s, uint64_t seed, long iteration, double surface_radius, double chain_share,
                          photon_set *out, dp_error *err);
/* The DARTS guide of the scene's plan. */
void scene_guide(const scene *s, darts_guide *g);

#endif
