/* The render-level fixtures shared by the test programs (declared in render_fixtures.h): scene files in a
 * temp folder, renders and their per-pass totals, the photon-points tests' scenes and photon passes. Every
 * helper here came from test_photon_points.c (split by subject) or was copied between test files. */
#include "render_fixtures.h"

/* ---- scene files in a temp folder ---- */

void tmp_scene_write(tmp_scene *t, const char *text)
{
    t->dir = test_tmpdir();
    assert_non_null(t->dir);
    snprintf(t->path, sizeof t->path, "%s/scene.json", t->dir);
    test_write_file(t->path, text);
}

void tmp_scene_remove(tmp_scene *t)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf %s", t->dir);
    (void)!system(cmd);
    free(t->dir);
    t->dir = NULL;
}

void load_scene(const char *path, const char *const *sets, int nsets, scene *s)
{
    dp_error err;
    scene_load_options lo = {.sets = sets, .set_count = nsets};
    if (scene_load(path, &lo, s, &err)) fail_msg("%s", err.msg);
}

/* ---- renders and their per-pass totals ---- */

void pass_totals_init(pass_totals *t, int frames)
{
    *t = (pass_totals){.images = 1 + frames};
    t->last = calloc((size_t)t->images * 3, sizeof(double));
    assert_non_null(t->last);
}

void pass_totals_free(pass_totals *t)
{
    free(t->x);
    free(t->last);
    *t = (pass_totals){0};
}

/* Mean over the recorded passes of image m, channel c (c = 3: the sum of the channels), and its standard
 * error from the spread of the passes. */
void pass_totals_mean_se(const pass_totals *t, int m, int c, double *mean, double *se)
{
    assert_true(t->n > 1 && m < t->images);
    double s = 0, s2 = 0;
    for (long i = 0; i < t->n; i++) {
        const double *v = &t->x[((size_t)i * t->images + m) * 3];
        double x = c < 3 ? v[c] : v[0] + v[1] + v[2];
        s += x;
        s2 += x * x;
    }
    *mean = s / t->n;
    *se = sqrt(fmax(0.0, (s2 - t->n * *mean * *mean) / (t->n - 1)) / t->n);
}

/* What a render records after each pass (pass_probe): the per-pass totals and the snapshot. */
int pass_probe_after(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    (void)err;
    pass_probe *pr = ctx;
    size_t npx = (size_t)f->width * f->height;
    if (pr->snap && st->passes == pr->snap_pass)
        for (size_t i = 0; i < 3 * npx; i++) pr->snap[i] = f->sum[i] / f->weight_sum;
    pass_totals *t = pr->t;
    if (!t) return 0;
    assert_int_equal(t->images, 1 + f->window.frame_count);
    if (st->passes == 1) memset(t->last, 0, (size_t)t->images * 3 * sizeof(double));
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 256;
        t->x = realloc(t->x, (size_t)t->cap * t->images * 3 * sizeof(double));
        assert_non_null(t->x);
    }
    double *row = &t->x[(size_t)t->n * t->images * 3];
    for (int m = 0; m < t->images; m++) {
        double tot[3] = {0, 0, 0};
        for (size_t p = 0; p < npx; p++)
            for (int c = 0; c < 3; c++)
                tot[c] += m == 0 ? f->sum[3 * p + c] : (double)f->frame_sum[3 * (npx * (size_t)(m - 1) + p) + c];
        for (int c = 0; c < 3; c++) {
            row[3 * m + c] = (tot[c] - t->last[3 * m + c]) / f->last_weight; /* this pass's estimate: the increment of the weighted sum */
            t->last[3 * m + c] = tot[c];
        }
    }
    t->n++;
    return 0;
}

/* Mean image of a render as doubles (film sum / weight sum), 3 values per pixel; with probe, its per-pass
 * totals and snapshot are recorded too. */
double *render_probe(const scene *s, int threads, uint64_t seed, long passes, pass_probe *probe)
{
    dp_error err;
    film f;
    render_stats st;
    render_options ro = {.threads = threads, .seed = seed, .spp = passes, .time_limit = 0,
                         .after_pass = probe ? pass_probe_after : NULL, .after_pass_ctx = probe};
    if (render_scene(s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.passes, passes);
    assert_int_equal(st.nonfinite, 0);
    size_t n = (size_t)s->cam.width * s->cam.height * 3;
    double *m = malloc(n * sizeof(double));
    assert_non_null(m);
    for (size_t i = 0; i < n; i++) m[i] = f.sum[i] / f.weight_sum;
    film_free(&f);
    return m;
}

void render_passes(const scene *s, int threads, uint64_t seed, long passes, film *f, render_stats *st)
{
    dp_error err;
    render_options ro = {.threads = threads, .seed = seed, .spp = passes, .time_limit = 0};
    if (render_scene(s, &ro, f, st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st->passes, passes);
    assert_int_equal(st->nonfinite, 0);
}

/* Mean image of a render as doubles (film sum / weight sum), 3 values per pixel. */
double *render_mean(const scene *s, int threads, uint64_t seed, long passes)
{
    return render_probe(s, threads, seed, passes, NULL);
}

/* Renders `seeds` renders (seeds seed0, seed0 + 1, ...) of `passes` passes, recording their per-pass totals
 * into t (initialised here for the scene's frames). */
void render_totals(const scene *s, uint64_t seed0, int seeds, long passes, pass_totals *t)
{
    pass_totals_init(t, s->integrator.window.frame_count);
    pass_probe pr = {.t = t};
    for (int k = 0; k < seeds; k++) free(render_probe(s, 2, seed0 + k, passes, &pr));
}

/* ---- the photon-points tests' scenes ---- */

const char *const DARTS_KEYS = DARTS_KEYS_TEXT;
const char *const BASELINE_KEYS = "\"enable_guiding\": false, \"enable_elliptical\": false";

/* A fog box open towards the camera: Lambertian floor, ceiling, back and side walls (2 × 2 × 2), fog
 * everywhere, the camera in the fog outside the box looking in, a point light inside the box. The light sits
 * in a small clear pocket (a 0.3 cube of index-matched boundary with vacuum inside): with a point light in
 * the fog itself, next-event estimation from a phase-sampled medium vertex has infinite variance (the
 * second moment of 1/d^2 over the volume near the light diverges), which would make the path tracer's
 * noise estimates below meaningless. With camera_in_fog 0 the fog fills only an index-matched cube of side
 * 2.1 around the box and the camera is in vacuum 1.95 in front of it: no volume photon comes near the
 * camera. (With the camera in the fog, a volume photon at distance s from it adds ∝ 1/s² to the image, and
 * the image total of a pass has a heavy right tail: kurtosis 91 over 2048 passes here, against 3.4 with the
 * camera outside.) */
void box_scene_text_cam(char *text, size_t len, int res, const char *integrator, double g, int camera_in_fog)
{
    const char *fog_cube = "    { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"int_medium\": \"fog\","
                           "      \"transform\": { \"position\": [0, 1, 0], \"scale\": [2.1, 2.1, 2.1] } },";
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.45, 0.4, 0.5],"
             "    \"sigma_a\": [0.05, 0.08, 0.03], \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": %g } } ],"
             BOX_WALLS
             "    { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"ext_medium\": \"fog\","
             "      \"transform\": { \"position\": [0.3, 1.5, 0.2], \"scale\": [0.3, 0.3, 0.3] } },"
             "%s"
             "    { \"type\": \"point\", \"emission\": [4, 4, 4],"
             "      \"transform\": { \"position\": [0.3, 1.5, 0.2] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [%d, %d], \"fov\": 45%s,"
             "    \"transform\": { \"position\": [0, 1, -3], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             g, camera_in_fog ? "" : fog_cube, res, res, camera_in_fog ? ", \"medium\": \"fog\"" : "", integrator);
}

/* The fog box's walls, fog and camera at 16² with `lights` (JSON primitives) in place of its point light. */
void lamp_box_text(char *text, size_t len, const char *integrator, const char *lights)
{
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.45, 0.4, 0.5],"
             "    \"sigma_a\": [0.05, 0.08, 0.03], \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.3 } } ],"
             BOX_WALLS
             "%s ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [16, 16], \"fov\": 45, \"medium\": \"fog\","
             "    \"transform\": { \"position\": [0, 1, -3], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { %s },"
             "  \"renderer\": { \"spp\": 1 } }",
             lights, integrator);
}

void box_scene_text(char *text, size_t len, int res, const char *integrator)
{
    box_scene_text_cam(text, len, res, integrator, 0.3, 1);
}

/* The box's fog made grey (σs 0.45, σa 0.05 in every channel; σt as the coloured fog's green-ish mean), in
 * place: the photon pass traces free flight distance-first only in grey media (free_flight_first). */
void box_scene_make_grey(char *text)
{
    char *a = strstr(text, "[0.45, 0.4, 0.5]"), *b = strstr(text, "[0.05, 0.08, 0.03]");
    assert_non_null(a);
    assert_non_null(b);
    memcpy(a, "[0.45,0.45,0.45]", 16);
    memcpy(b, "[0.05, 0.05, 0.05]", 18);
}

/* A fog slab (6 × 6 × 3, index-matched boundary, refractive index 1/speed) seen from a camera in vacuum
 * 1.5 in front of it, lit by a point light in vacuum 1 in front of it: volume only, no clear pocket needed
 * (the path tracer's next-event estimation never comes closer to the light than 1), and no volume photon
 * near the camera. The slab is wider than the view (fov 30°), so the image border cuts through the fog and
 * rays leave through the back face. `time` holds the time keys, `darts` the photon-pass keys. */
void slab_scene_text_lights(char *text, size_t len, double speed, const char *type, const char *time,
                            const char *darts, const char *lights)
{
    snprintf(text, len,
             "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": [0.45, 0.4, 0.5],"
             "    \"sigma_a\": [0.05, 0.08, 0.03], \"speed_of_light\": %.17g,"
             "    \"phase_function\": { \"type\": \"henyey_greenstein\", \"g\": 0.3 } } ],"
             "  \"primitives\": ["
             "    { \"type\": \"cube\", \"bsdf\": { \"type\": \"forward\" }, \"int_medium\": \"fog\","
             "      \"transform\": { \"position\": [0, 0, 0], \"scale\": [6, 6, 3] } },"
             "    %s ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [16, 16], \"fov\": 30,"
             "    \"transform\": { \"position\": [0, 0, -3], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"%s\", \"volume_photon_type\": \"points\","
             "    \"photon_count\": 10000, \"volume_photon_count\": 1e6, \"volume_gather_radius\": 0.06,"
             "    \"volume_alpha\": 0.7, \"max_bounces\": 4, %s%s%s },"
             "  \"renderer\": { \"spp\": 1 } }",
             speed, lights, type, time, darts[0] ? ", " : "", darts);
}

void slab_scene_text(char *text, size_t len, double speed, const char *type, const char *time, const char *darts)
{
    slab_scene_text_lights(text, len, speed, type, time, darts, SLAB_LIGHT);
}

/* ---- the progressive radius schedule and the photon pass ---- */

/* r0 · (Π_{j=1..i} (j+α)/(j+1))^{1/dims} with the product as Γ(i+1+α) / (Γ(1+α) Γ(i+2)), via lgamma:
 * Π (j+α) for j = 1..i is Γ(i+1+α)/Γ(1+α) and Π (j+1) is (i+1)! = Γ(i+2). */
double radius_closed_form(double r0, double alpha, long i, int dims)
{
    double log_prod = lgamma(i + 1.0 + alpha) - lgamma(1.0 + alpha) - lgamma(i + 2.0);
    return r0 * exp(log_prod / dims);
}

/* Field by field: the struct has padding, whose bytes are indeterminate. */
void assert_photon_identical(const photon *a, const photon *b)
{
    assert_memory_equal(a->pos, b->pos, sizeof a->pos);
    assert_memory_equal(a->dir, b->dir, sizeof a->dir);
    assert_memory_equal(a->power, b->power, sizeof a->power);
    assert_int_equal(a->bounce, b->bounce);
    assert_int_equal(a->frame, b->frame);
    assert_memory_equal(&a->time, &b->time, sizeof a->time);
}

/* One photon pass of the scene's plan without EDA tables, its DARTS surface tests widened for gathers of
 * radius surface_radius. */
int run_photon_pass(const scene *s, uint64_t seed, long iteration, double surface_radius, photon_set *out,
                    dp_error *err)
{
    return run_photon_pass_share(s, seed, iteration, surface_radius, 1.0, out, err);
}

int run_photon_pass_share(const scene *s, uint64_t seed, long iteration, double surface_radius, double chain_share,
                          photon_set *out, dp_error *err)
{
    render_plan p;
    if (plan_resolve(s, &p, err)) return -1;
    p.chain_share = chain_share;
    photon_pass_input in;
    photon_pass_input_init(&in, s, &p, NULL, seed, iteration, NULL);
    in.surface_slack = p.include_surfaces ? p.darts.eta_ub * surface_radius : 0.0;
    int rc = photon_pass(s, &in, out, err);
    plan_free(&p);
    return rc;
}

/* The DARTS guide of the scene's plan. */
void scene_guide(const scene *s, darts_guide *g)
{
    render_plan p;
    dp_error err;
    if (plan_resolve(s, &p, &err)) fail_msg("%s", err.msg);
    darts_guide_init(&p.darts, &p.window, s->cam.pos, g);
    plan_free(&p);
}


/* ---- per-tile totals ---- */

static double frame_total(const film *f, int k)
{
    double v = 0.0;
    size_t n = (size_t)f->width * f->height * 3;
    for (size_t i = 0; i < n; i++) v += f->frame_sum[n * (size_t)k + i];
    return v;
}

int cell_probe(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    (void)err;
    cell_totals *t = ctx;
    if (st->passes == 1) memset(t->last, 0, sizeof t->last);
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 1024;
        t->x = realloc(t->x, (size_t)t->cap * CELLS * sizeof(double));
        assert_non_null(t->x);
    }
    double v[CELLS] = {0};
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++)
            for (int c = 0; c < 3; c++)
                v[(y * TILES / f->height) * TILES + x * TILES / f->width] += f->sum[3 * ((size_t)y * f->width + x) + c];
    for (int k = 0; k < t->frames; k++) v[NT + k] = frame_total(f, k);
    for (int i = 0; i < CELLS; i++) {
        t->x[(size_t)t->n * CELLS + i] = (v[i] - t->last[i]) / f->last_weight; /* this pass's estimate */
        t->last[i] = v[i];
    }
    t->n++;
    return 0;
}

void cell_mean_se(const cell_totals *t, int v, double *mean, double *se)
{
    double s = 0, s2 = 0;
    for (long i = 0; i < t->n; i++) {
        double x = t->x[(size_t)i * CELLS + v];
        s += x;
        s2 += x * x;
    }
    *mean = s / t->n;
    *se = sqrt(fmax(0.0, (s2 - t->n * *mean * *mean) / (t->n - 1)) / t->n);
}

double cells_z(const char *label, const cell_totals *ref, const cell_totals *m, double bias, double *z_total)
{
    double zmax = 0.0, tot_r = 0, tot_m = 0, var_r = 0, var_m = 0;
    int worst = 0, dark = 0, cells = NT + m->frames;
    for (int v = 0; v < cells; v++) {
        double mr, sr, mm, sm;
        cell_mean_se(ref, v, &mr, &sr);
        cell_mean_se(m, v, &mm, &sm);
        dark += !(mr > 0.0 && mm > 0.0);
        tot_r += mr, tot_m += mm, var_r += sr * sr, var_m += sm * sm;
        double z = fmax(0.0, fabs(mm - mr) - bias * mr) / sqrt(sr * sr + sm * sm);
        if (z > zmax) zmax = z, worst = v;
    }
    if (dark) print_message("  %s: %d cells dark in one of the two\n", label, dark);
    assert_int_equal(dark, 0);
    double mr, sr, mm, sm;
    cell_mean_se(ref, worst, &mr, &sr);
    cell_mean_se(m, worst, &mm, &sm);
    print_message("  worst cell %d: %.5g (se %.2g) vs path tracer %.5g (se %.2g), %+.2f %%\n", worst, mm, sm, mr, sr,
                  100.0 * (mm - mr) / mr);
    double zt = fmax(0.0, fabs(tot_m - tot_r) - bias * tot_r) / sqrt(var_r + var_m);
    if (z_total) *z_total = zt;
    print_message("  %-34s total %.5g (se %.2g) vs path tracer %.5g (se %.2g), %+.2f %% (|z| %.2f after the budget); "
                  "max |z| %.2f over %d cells\n", label, tot_m, sqrt(var_m), tot_r, sqrt(var_r),
                  100.0 * (tot_m - tot_r) / tot_r, zt, zmax, cells);
    return zmax;
}


void cell_render(const char *text, long passes, uint64_t seed, int frames, cell_totals *t, double *seconds)
{
    tmp_scene ts;
    tmp_scene_write(&ts, text);
    scene s;
    load_scene(ts.path, NULL, 0, &s);
    memset(t, 0, sizeof *t);
    t->frames = frames;
    render_options ro = {.threads = 2, .seed = seed, .spp = passes, .after_pass = cell_probe, .after_pass_ctx = t};
    film f;
    render_stats st;
    dp_error err;
    double t0 = dp_seconds();
    if (render_scene(&s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    *seconds = dp_seconds() - t0;
    assert_int_equal(st.nonfinite, 0);
    assert_int_equal(t->n, passes);
    film_free(&f);
    scene_free(&s);
    tmp_scene_remove(&ts);
}

/* The tile totals of one image (its sums). */
static void deriv_tiles_of(const film *f, double *v)
{
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++)
            for (int c = 0; c < 3; c++)
                v[(y * TILES / f->height) * TILES + x * TILES / f->width] += f->sum[3 * ((size_t)y * f->width + x) + c];
}

int deriv_tiles_probe(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    (void)err;
    deriv_tiles *t = ctx;
    assert_true(t->k >= 0 && t->k <= DIFF_PARAM_MAX);
    int m = (1 + t->k) * NT;
    if (st->passes == 1) memset(t->last, 0, sizeof t->last);
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 1024;
        t->x = realloc(t->x, (size_t)t->cap * m * sizeof(double));
        assert_non_null(t->x);
    }
    double v[(1 + DIFF_PARAM_MAX) * NT] = {0};
    deriv_tiles_of(f, v);
    for (int k = 0; k < t->k && k < f->deriv_count; k++) deriv_tiles_of(&f->deriv[k], v + (1 + k) * NT);
    for (int i = 0; i < m; i++) {
        t->x[(size_t)t->n * m + i] = (v[i] - t->last[i]) / f->last_weight; /* this pass's estimate */
        t->last[i] = v[i];
    }
    t->n++;
    return 0;
}

void deriv_tiles_render(const scene *s, int k, long passes, uint64_t seed, deriv_tiles *t, film *out)
{
    memset(t, 0, sizeof *t);
    t->k = k;
    render_options ro = {.threads = 2, .seed = seed, .spp = passes, .after_pass = deriv_tiles_probe, .after_pass_ctx = t};
    film f;
    render_stats st;
    dp_error err;
    if (render_scene(s, &ro, &f, &st, &err)) fail_msg("%s", err.msg);
    assert_int_equal(st.nonfinite, 0);
    assert_int_equal(t->n, passes);
    if (out) *out = f;
    else film_free(&f);
}
