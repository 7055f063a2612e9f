/* dp_render: the render command's path (scene, plan, memory guard, reference, warnings, progressive render)
 * without a command line, files or printing, for the Python package. The images are the film's, as the CLI
 * writes them: the same seed and passes give the same floats (tests/python/test_render.py checks it). */
#include "dartspp/api.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/render.h"

const char *const DP_LOG_COLUMN_NAMES[DP_LOG_COLUMNS] = {
    "seconds", "iterations", "photon_paths", "stored_photons", "r_vol", "r_surf", "mse", "rel_mse", "mse_q99",
    "nonfinite_pixels"};

typedef struct {
    const dp_render_request *rq;
    dp_render_result *res;
    dp_stop_flag *stop;
    image_rgb ref;               /* the error log's reference, or rgb NULL */
    double last_row;             /* render time of the last log row */
    int log_capacity;
} api_run;

/* The budget as the CLI reads --spp and --time (docs/cli.md §2.1): one alone is the only limit, neither is the
 * scene's. A budget that nothing ends is refused: a caller in a notebook has no Ctrl-C to count on. */
static int resolve_budget(const dp_render_request *rq, const scene *s, const render_plan *p, long *spp, double *limit,
                          dp_error *err)
{
    *spp = rq->spp;
    *limit = rq->time_limit;
    if (*limit >= 0 && *spp < 0) *spp = 0;
    if (*spp >= 0 && *limit < 0) *limit = 0;
    if (*spp == 0 && *limit == 0)
        return dp_fail(err, "spp 0 and time 0: nothing would end the render (give spp > 0 or time > 0)");
    if (*spp < 0 && !(p->spp > 0) && !(p->timeout > 0))
        return dp_fail(err, "%s: the scene's renderer.spp and renderer.timeout set no limit, and neither spp nor time "
                            "was given: nothing would end the render", s->path);
    return 0;
}

static int load(const dp_render_request *rq, scene *s, dp_error *err)
{
    scene_load_options lo = {.sets = rq->sets, .set_count = rq->set_count, .derivatives = rq->derivatives,
                             .derivative_count = rq->derivative_count};
    if (rq->scene_path) return scene_load(rq->scene_path, &lo, s, err);
    if (!rq->scene_text) return dp_fail(err, "no scene: give a scene file or the scene's JSON text");
    return scene_load_text(rq->scene_text, rq->scene_name ? rq->scene_name : "<scene>", rq->base_dir, &lo, s, err);
}

static int read_reference(api_run *r, const scene *s, dp_error *err)
{
    const dp_render_request *rq = r->rq;
    const char *name = rq->reference_path ? rq->reference_path : "reference";
    if (rq->reference_path && image_read(rq->reference_path, &r->ref, err)) return -1;
    if (rq->reference_rgb) {
        if (rq->ref_width <= 0 || rq->ref_height <= 0) return dp_fail(err, "the reference has no pixels");
        if (image_alloc(&r->ref, rq->ref_width, rq->ref_height, err)) return -1;
        memcpy(r->ref.rgb, rq->reference_rgb, (size_t)rq->ref_width * rq->ref_height * 3 * sizeof(float));
    }
    if (!r->ref.rgb) return 0;
    if (r->ref.width != s->cam.width || r->ref.height != s->cam.height)
        return dp_fail(err, "%s: the reference %s %dx%d but the render is %dx%d (width x height)", name,
                       rq->reference_path ? "is" : "array is", r->ref.width, r->ref.height, s->cam.width,
                       s->cam.height);
    int x, y;
    long bad = image_nonfinite_pixels(&r->ref, &x, &y);
    if (bad) return dp_fail(err, "%s: %ld pixels have a NaN or Inf channel (the first at x %d, y %d)", name, bad, x, y);
    return 0;
}

/* The scene's notes and the pre-render warnings, as the CLI prints them, into res->warnings. */
static int collect_warnings(const scene *s, const render_plan *p, dp_render_result *res, dp_error *err)
{
    size_t n = 0;
    FILE *out = open_memstream(&res->warnings, &n);
    if (!out) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    if (s->notes) fputs(s->notes, out);
    render_warn(out, s, p);
    return fclose(out) ? dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory") : 0;
}

/* One error-log row (the columns of DP_LOG_COLUMN_NAMES) if one is due, as error_log_pass decides. */
static int log_row(api_run *r, const film *f, const render_stats *st, int force, dp_error *err)
{
    dp_render_result *res = r->res;
    if (!r->ref.rgb || (!force && st->seconds - r->last_row < r->rq->log_every)) return 0;
    if (res->log_rows > 0 && (long)res->log[(size_t)(res->log_rows - 1) * DP_LOG_COLUMNS + 1] == st->passes) return 0;
    if (res->log_rows == r->log_capacity) {
        int cap = r->log_capacity ? 2 * r->log_capacity : 64;
        double *grown = realloc(res->log, (size_t)cap * DP_LOG_COLUMNS * sizeof(double));
        if (!grown) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
        res->log = grown;
        r->log_capacity = cap;
    }
    image_rgb img = {0};
    image_error e;
    if (film_image(f, -1, &img, err)) return -1;
    int rc = image_compare(&img, &r->ref, &e, err);
    image_free(&img);
    if (rc) return -1;
    double row[DP_LOG_COLUMNS] = {st->seconds, (double)st->passes, st->photon_paths, st->stored_photons, st->r_vol,
                                  st->r_surf, e.mse, e.rel_mse, e.mse_q99, (double)e.nonfinite};
    memcpy(&res->log[(size_t)res->log_rows++ * DP_LOG_COLUMNS], row, sizeof row);
    r->last_row = st->seconds;
    return 0;
}

static int after_pass(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    api_run *r = ctx;
    if (log_row(r, f, st, 0, err)) return -1;
    if (r->rq->progress && r->rq->progress(r->rq->progress_ctx, st->passes, st->seconds, st->r_vol, st->r_surf))
        *r->stop = 1;
    return 0;
}

_Static_assert(RENDER_FIGURE_COUNT <= DP_STATS_MAX, "dp_render_result.stats has room for every figure");

/* The figures render.h marks for the API (RENDER_FIGURES) into res->stats, in its order. */
static void fill_stats(const render_stats *st, dp_render_result *res)
{
    res->stat_count = 0;
    for (int i = 0; i < RENDER_FIGURE_COUNT; i++) {
        const render_figure *fg = &render_figures[i];
        if (fg->api)
            res->stats[res->stat_count++] = (dp_stat){fg->name, render_figure_get(st, fg), fg->type != RENDER_FIGURE_DOUBLE};
    }
}

/* A film's gate image into image and its frame_count frames into frames (each width × height × 3 floats). */
static int film_images(const film *f, int frame_count, float *image, float *frames, dp_error *err)
{
    size_t px = (size_t)f->width * f->height * 3;
    for (int k = -1; k < frame_count; k++) {
        image_rgb img = {0};
        if (film_image(f, k, &img, err)) return -1;
        memcpy(k < 0 ? image : frames + px * k, img.rgb, px * sizeof(float));
        image_free(&img);
    }
    return 0;
}

/* The derivative films' images (f->deriv, one per parameter asked for, in its order) into res. */
static int fill_derivs(const film *f, int frame_count, dp_render_result *res, dp_error *err)
{
    size_t px = (size_t)f->width * f->height * 3, k_count = (size_t)f->deriv_count;
    res->deriv_count = f->deriv_count;
    if (!f->deriv_count) return 0;
    res->derivs = malloc(k_count * px * sizeof(float));
    res->deriv_frames = frame_count > 0 ? malloc(k_count * frame_count * px * sizeof(float)) : NULL;
    if (!res->derivs || (frame_count > 0 && !res->deriv_frames))
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for %d derivative images", f->deriv_count);
    for (int k = 0; k < f->deriv_count; k++)
        if (film_images(&f->deriv[k], frame_count, res->derivs + px * k,
                        res->deriv_frames ? res->deriv_frames + px * frame_count * k : NULL, err))
            return -1;
    return 0;
}

/* A lidar's waveforms and points (docs/lidar.md §4), the arrays its files hold. */
static int fill_lidar(const film *f, dp_render_result *res, dp_error *err)
{
    if (!f->lidar) return 0;
    const camera *cam = f->lidar;
    const lidar_params *l = &cam->lidar;
    res->lidar_channels = l->channels;
    res->lidar_azimuth_steps = l->azimuth_steps;
    res->lidar_bins = l->bins;
    res->lidar_range_bin = l->range_bin;
    if (lidar_waveforms(f, -1, &res->waveforms, err)) return -1;
    lidar_points pts = {0};
    if (lidar_points_from_waveforms(l, cam->pos, cam->forward, v3_neg(cam->right), cam->up, res->waveforms, &pts, err))
        return -1;
    res->points = pts.rows;
    res->point_count = (long)pts.count;
    return 0;
}

/* The film's images, the time window and the figures of the run into res. */
static int fill_result(const film *f, const render_stats *st, const render_plan *p, dp_render_result *res,
                       dp_error *err)
{
    const time_window *tw = &p->window;
    size_t px = (size_t)f->width * f->height * 3;
    res->width = f->width;
    res->height = f->height;
    res->frame_count = tw->frame_count;
    res->gated = tw->gated;
    res->camera_warped = !tw->camera_unwarp;
    time_window_bounds(tw, &res->gate_start, &res->gate_end); /* a delta gate: its instant twice */
    res->image = malloc(px * sizeof(float));
    res->frames = tw->frame_count > 0 ? malloc(px * tw->frame_count * sizeof(float)) : NULL;
    res->frame_times = tw->frame_count > 0 ? malloc(2 * (size_t)tw->frame_count * sizeof(double)) : NULL;
    if (!res->image || (tw->frame_count > 0 && (!res->frames || !res->frame_times)))
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    if (film_images(f, tw->frame_count, res->image, res->frames, err)) return -1;
    for (int k = 0; k < tw->frame_count; k++) {
        res->frame_times[2 * k] = tw->start + k * tw->width;
        res->frame_times[2 * k + 1] = tw->start + (k + 1) * tw->width;
    }
    if (fill_derivs(f, tw->frame_count, res, err) || fill_lidar(f, res, err)) return -1;
    if (tw->amcw_count > 0) { /* the AMCW values and depth, as <stem>_amcw.npy and _amcw_depth.npy */
        res->amcw_count = tw->amcw_count;
        for (int j = 0; j < tw->amcw_count; j++) res->amcw_mhz[j] = tw->amcw_mhz[j];
        res->amcw = malloc(2 * px * (size_t)tw->amcw_count * sizeof(float));
        res->amcw_depth = malloc((size_t)f->width * f->height * sizeof(float));
        if (!res->amcw || !res->amcw_depth) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for the AMCW arrays");
        long dark;
        film_amcw_values(f, res->amcw);
        film_amcw_depth(f, res->amcw_depth, &dark);
    }
    res->passes = st->passes;
    res->interrupted = st->interrupted;
    res->seconds = st->seconds;
    render_stats figures = *st;
    figures.nonfinite_pixels = film_nonfinite_pixels(f);
    film_amcw_depth(f, NULL, &figures.amcw_dark_pixels);
    fill_stats(&figures, res);
    return 0;
}

static int plan_text(const scene *s, const render_plan *p, dp_render_result *res, dp_error *err)
{
    size_t cap = 1 << 16;
    res->plan_json = malloc(cap);
    res->integrator = strdup(p->type_name);
    if (!res->plan_json || !res->integrator) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    if (plan_json(p, s, res->plan_json, cap)) return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: plan too long", s->path);
    return 0;
}

/* Everything that can refuse the render, before any work; then the render. */
static int run(api_run *r, scene *s, render_plan *p, dp_error *err)
{
    const dp_render_request *rq = r->rq;
    render_options ro = {.plan = p, .seed = rq->seed, .stop = r->stop, .after_pass = after_pass, .after_pass_ctx = r};
    memory_estimate mem;
    if (resolve_budget(rq, s, p, &ro.spp, &ro.time_limit, err)) return -1;
    int have_ref = rq->reference_path || rq->reference_rgb;
    if (plan_text(s, p, r->res, err) || render_memory_check(s, p, have_ref, rq->max_memory, 1, &mem, err) ||
        read_reference(r, s, err) || collect_warnings(s, p, r->res, err)) {
        if (err->kind == DP_ERROR_INTERNAL) return -1;
        err->kind = DP_ERROR_INPUT;
        return -1;
    }
    /* the thread count is the process's OpenMP setting: "all cores" is said explicitly, so that a render after
     * one with threads=1 does not inherit it */
    ro.threads = rq->threads > 0 ? rq->threads : omp_get_num_procs();
    film f;
    render_stats st;
    int rc = render_scene(s, &ro, &f, &st, err);
    if (!rc && f.deriv_count != s->diff_count)
        rc = dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: the render made %d derivative images for the %d parameters "
                                                  "asked for", s->path, f.deriv_count, s->diff_count);
    if (!rc) rc = log_row(r, &f, &st, 1, err);
    if (!rc) rc = fill_result(&f, &st, p, r->res, err);
    film_free(&f);
    return rc;
}

int dp_option_parse(const char *name, const char *text, double *value, uint64_t *exact, int *whole, dp_error *err)
{
    int o = render_opt_find(name);
    if (o < 0 || (name && name[0] == '-')) return dp_fail(err, "%s: not an option of a render", name ? name : "(none)");
    render_opt_value v;
    if (render_opt_parse((render_opt)o, text, &v, err)) return -1;
    *value = v.d;
    *exact = v.u;
    *whole = o == RENDER_OPT_THREADS || o == RENDER_OPT_SEED || o == RENDER_OPT_SPP;
    return 0;
}

/* The options through the command line's table and check (render.h), so that a value `dartspp render` refuses is
 * refused here with the same message; the sentinels (spp and time < 0: as the scene says; max_memory 0: what the
 * machine has) are the API's own. */
static int check_options(const dp_render_request *rq, dp_error *err)
{
    if (rq->derivative_count < 0 || rq->derivative_count > DIFF_PARAM_MAX || (rq->derivative_count && !rq->derivatives))
        return dp_fail(err, "derivatives: %d pointers given; a render differentiates at most %d parameters",
                       rq->derivative_count, DIFF_PARAM_MAX);
    for (int k = 0; k < rq->derivative_count; k++)
        if (!rq->derivatives[k])
            return dp_fail(err, "derivatives[%d]: no pointer (NULL)", k);
    return render_opt_check(RENDER_OPT_THREADS, rq->threads, NULL, err) ||
           (rq->spp >= 0 && render_opt_check(RENDER_OPT_SPP, (double)rq->spp, NULL, err)) ||
           (!(rq->time_limit < 0) && render_opt_check(RENDER_OPT_TIME, rq->time_limit, NULL, err)) ||
           (rq->max_memory != 0 && render_opt_check(RENDER_OPT_MAX_MEMORY, rq->max_memory, NULL, err)) ||
           render_opt_check(RENDER_OPT_LOG_EVERY, rq->log_every, NULL, err);
}

int dp_render(const dp_render_request *rq, dp_render_result *res, dp_error *err)
{
    memset(res, 0, sizeof *res);
    if (check_options(rq, err)) return -1;
    dp_stop_flag own_stop = 0;
    api_run r = {.rq = rq, .res = res, .stop = rq->stop ? rq->stop : &own_stop, .last_row = -1e300};
    scene s;
    if (load(rq, &s, err)) {
        err->kind = DP_ERROR_INPUT;
        return -1;
    }
    if (s.diff_count != rq->derivative_count) {
        dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: the scene resolved %d of the %d derivatives asked for", s.path,
                     s.diff_count, rq->derivative_count);
        scene_free(&s);
        return -1;
    }
    render_plan p;
    int rc = plan_resolve(&s, &p, err);
    if (rc) err->kind = DP_ERROR_INPUT;
    else {
        rc = run(&r, &s, &p, err);
        plan_free(&p);
    }
    image_free(&r.ref);
    scene_free(&s);
    return rc;
}

void dp_render_result_free(dp_render_result *res)
{
    free(res->image);
    free(res->frames);
    free(res->frame_times);
    free(res->plan_json);
    free(res->integrator);
    free(res->warnings);
    free(res->log);
    free(res->derivs);
    free(res->deriv_frames);
    free(res->waveforms);
    free(res->points);
    free(res->amcw);
    free(res->amcw_depth);
    memset(res, 0, sizeof *res);
}
