/* Film → files: gate image, PNG preview, per-frame images, the frame sidecar, the transient cube and its
 * viewer page (docs/cli.md §3), in frame mode as one set staged and moved into place; the check of the
 * output path before any work (with the cleanup of what killed runs left), and the rescue folder when the
 * final write fails anyway. */
#include "dartspp/render.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

/* a path under the staging folder of a frame set: its folder name repeats the stem's base name */
#define STAGED_PATH_MAX (2 * OUTPUT_PATH_MAX + 128)

static int write_one(const char *path, const image_rgb *img, const image_meta *meta, void (*wrote)(const char *),
                     dp_error *err)
{
    if (image_write(path, img, meta, err)) return -1;
    if (wrote) wrote(path);
    return 0;
}

/* Splits PATH.exr / PATH.pfm into its stem and extension; anything else is an error naming the path. */
static int split_output_path(const char *path, char *stem, size_t n, const char **ext, dp_error *err)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash) || (strcasecmp(dot, ".exr") && strcasecmp(dot, ".pfm")))
        return dp_fail(err, "%s: output must end in .exr or .pfm", path);
    if (dot == path || (slash && dot == slash + 1)) /* ".exr": hidden files ".exr", "_cube.npy", ".state" */
        return dp_fail(err, "%s: no file name before the extension (e.g. render.exr)", path);
    if ((size_t)(dot - path) + 32 >= n) return dp_fail(err, "%s: output path too long", path);
    snprintf(stem, n, "%.*s", (int)(dot - path), path);
    *ext = dot;
    return 0;
}

/* Frame k's file: <stem>_<k zero-padded to 4 digits, 5 above 10000 frames><ext> (frame_num <= 100000).
 * The stem is at most OUTPUT_PATH_MAX - 32 long (split_output_path), so the name always fits. */
static void frame_path(char *out, size_t n, const char *stem, int frame_count, int k, const char *ext)
{
    int digits = frame_count > 10000 ? 5 : 4;
    if (snprintf(out, n, "%s_%0*d%s", stem, digits, k, ext) >= (int)n) out[n - 1] = '\0';
}

/* The cube and the viewer, filled frame by frame beside the frame files. */
typedef struct {
    int skip;
    char npy_path[STAGED_PATH_MAX], html_path[STAGED_PATH_MAX];
    npy_file npy;
    int npy_open;
    viewer_cube view;
} frame_extras;

static int extras_open(frame_extras *x, const film *f, const char *stem, int skip, dp_error *err)
{
    const time_window *tw = &f->window;
    x->skip = skip;
    x->npy_open = 0;
    x->view.data = NULL;
    x->view.hist = NULL;
    snprintf(x->npy_path, sizeof x->npy_path, "%s_cube.npy", stem);
    snprintf(x->html_path, sizeof x->html_path, "%s_viewer.html", stem);
    size_t shape[4] = {(size_t)tw->frame_count, (size_t)f->height, (size_t)f->width, 3};
    if (!(skip & RENDER_SKIP_VIEWER) && viewer_cube_init(&x->view, f->width, f->height, tw->frame_count, err))
        return -1;
    if (!(skip & RENDER_SKIP_CUBE)) {
        if (npy_open(&x->npy, x->npy_path, shape, 4, err)) {
            viewer_cube_free(&x->view);
            return -1;
        }
        x->npy_open = 1;
    }
    return 0;
}

static int extras_add(frame_extras *x, int k, const image_rgb *img, dp_error *err)
{
    if (x->view.data) viewer_cube_add(&x->view, k, img);
    if (x->npy_open && npy_append(&x->npy, img->rgb, 3 * (size_t)img->width * img->height, err)) {
        x->npy_open = 0; /* npy_append removed the file */
        return -1;
    }
    return 0;
}

static void extras_abort(frame_extras *x)
{
    if (x->npy_open) npy_abort(&x->npy);
    x->npy_open = 0;
    viewer_cube_free(&x->view);
}

static int extras_close(frame_extras *x, const film *f, const char *stem, void (*wrote)(const char *), dp_error *err)
{
    int rc = 0;
    if (x->npy_open) {
        x->npy_open = 0;
        rc = npy_close(&x->npy, err);
        if (!rc && wrote) wrote(x->npy_path);
    }
    if (!rc && x->view.data) {
        const char *base = strrchr(stem, '/');
        viewer_time vt = {.title = base ? base + 1 : stem, .time_unit = RENDER_TIME_UNIT,
                          .camera_warped = !f->window.camera_unwarp, .start = f->window.start,
                          .width = f->window.width};
        rc = viewer_html_write(x->html_path, &x->view, &vt, err);
        if (!rc && wrote) wrote(x->html_path);
    }
    viewer_cube_free(&x->view);
    return rc;
}

static int write_frames(const film *f, const char *stem, const char *ext, image_meta meta, int skip,
                        void (*wrote)(const char *), dp_error *err)
{
    const time_window *tw = &f->window;
    frame_extras x;
    if (extras_open(&x, f, stem, skip, err)) return -1;
    for (int k = 0; k < tw->frame_count; k++) {
        char path[STAGED_PATH_MAX];
        frame_path(path, sizeof path, stem, tw->frame_count, k, ext);
        image_rgb img = {0};
        if (film_image(f, k, &img, err)) {
            extras_abort(&x);
            return -1;
        }
        meta.frame_index = k;
        meta.gate_start = tw->start + k * tw->width;
        meta.gate_end = tw->start + (k + 1) * tw->width;
        int rc = write_one(path, &img, &meta, wrote, err);
        if (!rc) rc = extras_add(&x, k, &img, err);
        image_free(&img);
        if (rc) {
            extras_abort(&x);
            return -1;
        }
    }
    if (extras_close(&x, f, stem, wrote, err)) return -1;
    char csv[STAGED_PATH_MAX];
    snprintf(csv, sizeof csv, "%s" ATOMIC_SET_MANIFEST, stem); /* the set's manifest (io.h) */
    if (frames_csv_write(csv, tw->frame_count, tw->start, tw->width, err)) return -1;
    if (wrote) wrote(csv);
    return 0;
}

/* The gate image, its PNG and (frame mode) the frame set under `stem`. */
/* integrator.bounce_orders: <stem>_orders.npy, float32 (orders, frames or 1, height, width, 3), the frames (or
 * the gate image) of the paths of each scattering order (docs/time.md §7). */
static int write_orders(const film *f, const char *stem, void (*wrote)(const char *path), dp_error *err)
{
    const time_window *tw = &f->window;
    int frames = tw->frame_count > 0 ? tw->frame_count : 1;
    char path[STAGED_PATH_MAX];
    snprintf(path, sizeof path, "%s_orders.npy", stem);
    size_t shape[5] = {(size_t)tw->orders, (size_t)frames, (size_t)f->height, (size_t)f->width, 3};
    npy_file w;
    if (npy_open(&w, path, shape, 5, err)) return -1;
    for (int o = 0; o < tw->orders; o++)
        for (int k = 0; k < frames; k++) {
            image_rgb img = {0};
            if (film_layer_image(f, film_order_layer(tw, o, tw->frame_count > 0 ? k : -1), &img, err)) {
                npy_abort(&w);
                return -1;
            }
            int rc = npy_append(&w, img.rgb, (size_t)f->width * f->height * 3, err);
            image_free(&img);
            if (rc) return -1;
        }
    if (npy_close(&w, err)) return -1;
    if (wrote) wrote(path);
    return 0;
}

/* renderer.amcw_frequencies (docs/amcw.md §3): <stem>_amcw.npy, complex64 (frequencies, height, width, 3), the
 * AMCW values; <stem>_amcw_depth.npy, float32 (height, width), the depth from the first two frequencies (0 where
 * a pixel has no signal). */
static int write_amcw(const film *f, const char *stem, void (*wrote)(const char *path), dp_error *err)
{
    const time_window *tw = &f->window;
    size_t npx = (size_t)f->width * f->height;
    float *v = malloc(npx * 6 * (size_t)tw->amcw_count * sizeof(float)), *depth = malloc(npx * sizeof(float));
    if (!v || !depth) {
        free(v);
        free(depth);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the AMCW arrays", stem);
    }
    long dark;
    film_amcw_values(f, v);
    film_amcw_depth(f, depth, &dark);
    char path[STAGED_PATH_MAX], dpath[STAGED_PATH_MAX];
    snprintf(path, sizeof path, "%s_amcw.npy", stem);
    snprintf(dpath, sizeof dpath, "%s_amcw_depth.npy", stem);
    size_t shape[4] = {(size_t)tw->amcw_count, (size_t)f->height, (size_t)f->width, 3};
    size_t dshape[2] = {(size_t)f->height, (size_t)f->width};
    int rc = npy_write_c64(path, shape, 4, v, err);
    if (!rc && wrote) wrote(path);
    if (!rc) rc = npy_write_f32(dpath, dshape, 2, depth, err);
    if (!rc && wrote) wrote(dpath);
    free(v);
    free(depth);
    return rc;
}

/* The derivative images (docs/derivatives.md §5): film k's gate image as <stem>_d<k><ext>, its frames,
 * cube and orders under the stem <stem>_d<k> as the image's (no PNG preview and no viewer: the values are
 * signed), and <stem>_derivatives.csv naming each k's parameter. */
static int write_derivatives(const film *f, const char *stem, const char *dot, image_meta meta, int skip,
                             void (*wrote)(const char *path), dp_error *err)
{
    for (int k = 0; k < f->deriv_count; k++) {
        const film *d = &f->deriv[k];
        char dstem[STAGED_PATH_MAX], path[STAGED_PATH_MAX + 16];
        snprintf(dstem, sizeof dstem, "%s_d%d", stem, k);
        snprintf(path, sizeof path, "%s%s", dstem, dot);
        image_rgb img = {0};
        if (film_image(d, -1, &img, err)) return -1;
        image_meta m = meta;
        m.frame_index = -1;
        int rc = write_one(path, &img, &m, wrote, err);
        image_free(&img);
        if (!rc && d->window.frame_count > 0) rc = write_frames(d, dstem, dot, m, skip | RENDER_SKIP_VIEWER, wrote, err);
        if (!rc && d->window.orders > 0) rc = write_orders(d, dstem, wrote, err);
        if (rc) return -1;
    }
    char csv[STAGED_PATH_MAX + 32];
    snprintf(csv, sizeof csv, "%s_derivatives.csv", stem);
    atomic_file af;
    FILE *fp = atomic_fopen(csv, "w", &af, err);
    if (!fp) return -1;
    fprintf(fp, "k,pointer,image\n");
    const char *base = strrchr(stem, '/');
    base = base ? base + 1 : stem;
    for (int k = 0; k < f->deriv_count; k++)
        fprintf(fp, "%d,\"%s\",%s_d%d%s\n", k, f->deriv[k].label ? f->deriv[k].label : "", base, k, dot);
    if (atomic_fclose(&af, ferror(fp), err)) return -1;
    if (wrote) wrote(csv);
    return 0;
}

static int write_all(const film *f, const char *stem, const char *dot, const char *integrator, const char *plan,
                     int skip, void (*wrote)(const char *path), dp_error *err)
{
    char path[STAGED_PATH_MAX];
    snprintf(path, sizeof path, "%s%s", stem, dot);
    const time_window *tw = &f->window;
    image_meta meta = {.time_unit = RENDER_TIME_UNIT, .gated = tw->gated, .camera_warped = !tw->camera_unwarp,
                       .frame_index = -1, .integrator = integrator, .plan = plan, .passes = f->passes};
    time_window_bounds(tw, &meta.gate_start, &meta.gate_end); /* a delta gate: its instant twice */
    image_rgb img = {0};
    if (film_image(f, -1, &img, err)) return -1;
    char png[STAGED_PATH_MAX];
    snprintf(png, sizeof png, "%s.png", stem);
    int rc = write_one(path, &img, &meta, wrote, err);
    if (!rc) rc = png_write_preview(png, &img, err);
    if (!rc && wrote) wrote(png);
    image_free(&img);
    if (f->lidar) return rc ? rc : lidar_write_outputs(f, stem, wrote, err); /* its frames are range bins: waveforms */
    if (!rc && tw->frame_count > 0) rc = write_frames(f, stem, dot, meta, skip, wrote, err);
    if (!rc && tw->orders > 0) rc = write_orders(f, stem, wrote, err);
    if (!rc && tw->amcw_count > 0) rc = write_amcw(f, stem, wrote, err);
    if (!rc && f->deriv_count > 0) rc = write_derivatives(f, stem, dot, meta, skip, wrote, err);
    return rc;
}

int ground_truth_write(const ground_truth *gt, const char *image_path, void (*wrote)(const char *), dp_error *err)
{
    char stem[OUTPUT_PATH_MAX];
    const char *dot;
    if (split_output_path(image_path, stem, sizeof stem, &dot, err)) return -1;
    for (int k = 0; k < GROUND_TRUTH_IMAGES; k++) {
        char path[STAGED_PATH_MAX];
        snprintf(path, sizeof path, "%s_%s%s", stem, GROUND_TRUTH_NAMES[k], dot);
        image_meta meta = {.time_unit = RENDER_TIME_UNIT, .frame_index = -1};
        if (write_one(path, &gt->img[k], &meta, wrote, err)) return -1;
    }
    return 0;
}

static void say_note(const char *msg) { fprintf(stderr, "dartspp render: %s\n", msg); }

/* One image: written in place, atomically. Frame mode: every file into a staging folder, then moved into
 * place (atomic_set in io.h), so that a killed run leaves the old set or the new one, never a mix. */
int render_write_outputs(const film *f, const char *path, const char *integrator, const char *plan, int skip,
                         void (*wrote)(const char *path), dp_error *err)
{
    char stem[OUTPUT_PATH_MAX];
    const char *dot;
    if (split_output_path(path, stem, sizeof stem, &dot, err) || io_make_parent_dirs(path, err)) return -1;
    if (f->window.frame_count <= 0) return write_all(f, stem, dot, integrator, plan, skip, wrote, err);
    atomic_set *set = malloc(sizeof *set); /* large (paths) */
    if (!set) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", stem);
    int rc = atomic_set_open(set, stem, err);
    if (!rc && write_all(f, set->stem, dot, integrator, plan, skip, NULL, err)) {
        atomic_set_abort(set);
        /* the message names the final path, not the staging folder's */
        char *at = strstr(err->msg, set->stem);
        if (at) {
            char rest[sizeof err->msg];
            snprintf(rest, sizeof rest, "%s", at + strlen(set->stem));
            snprintf(at, sizeof err->msg - (size_t)(at - err->msg), "%s%s", stem, rest);
        }
        rc = -1;
    } else if (!rc) {
        rc = atomic_set_commit(set, wrote, err);
    }
    free(set);
    return rc;
}

/* The folder of a file path ("." for a bare name). */
static void parent_dir(const char *path, char *dir, size_t n)
{
    const char *slash = strrchr(path, '/');
    if (!slash) snprintf(dir, n, ".");
    else if (slash == path) snprintf(dir, n, "/");
    else snprintf(dir, n, "%.*s", (int)(slash - path), path);
}

/* Bytes and files of the cube and the viewer (frame mode). */
static void extras_room(int width, int height, int frame_count, int skip, double *bytes, double *files)
{
    if (frame_count <= 0) return;
    if (!(skip & RENDER_SKIP_CUBE)) {
        *bytes += (double)frame_count * width * height * 12 + NPY_HEADER_MAX;
        *files += 1;
    }
    if (!(skip & RENDER_SKIP_VIEWER)) {
        viewer_layout l;
        viewer_layout_of(width, height, frame_count, &l);
        *bytes += viewer_html_bytes_max(&l);
        *files += 1;
    }
}

/* A render without frames writes only the gate image and its preview: the frame set of an earlier render to
 * the same name (its manifest, frames, cube and viewer) stays beside them and does not belong to them. Said
 * before the render, not removed (they are the user's files). */
static void warn_older_frame_set(const char *stem, int frame_count)
{
    char manifest[OUTPUT_PATH_MAX + 32];
    snprintf(manifest, sizeof manifest, "%s" ATOMIC_SET_MANIFEST, stem);
    if (frame_count == 0 && access(manifest, F_OK) == 0)
        fprintf(stderr, "warning: %s and the frames, cube and viewer it goes with are from an earlier render with "
                        "frames; this render has none and leaves them as they are: they do not belong to its image\n",
                manifest);
}

int render_outputs_check(const char *path, int width, int height, int frame_count, int derivs, int skip, dp_error *err)
{
    char stem[OUTPUT_PATH_MAX], dir[OUTPUT_PATH_MAX], probe[STAGED_PATH_MAX];
    const char *ext;
    struct stat st;
    if (split_output_path(path, stem, sizeof stem, &ext, err)) return -1;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return dp_fail(err, "%s: output is a folder", path);
    if (io_make_parent_dirs(path, err)) return -1;
    atomic_clean_stale(stem, say_note);
    warn_older_frame_set(stem, frame_count);
    parent_dir(path, dir, sizeof dir);
    /* writability: create and remove a probe file where the outputs will go */
    snprintf(probe, sizeof probe, "%s/.dartspp-probe-XXXXXX", dir);
    int fd = mkstemp(probe);
    if (fd < 0) return dp_fail(err, "%s: cannot write in the output folder %s: %s", path, dir, strerror(errno));
    close(fd);
    unlink(probe);
    /* room: float32 RGB images (an upper bound: EXR's ZIP only shrinks them), the PNG, the frame files, the
     * cube and the viewer */
    double files = 2 + (frame_count > 0 ? frame_count + 1 : 0);
    double bytes = (1.0 + frame_count) * ((double)width * height * 12 + 4096) + (double)width * height * 4;
    extras_room(width, height, frame_count, skip, &bytes, &files);
    /* each derivative: its image, frames, manifest and cube (no preview, no viewer), and the sidecar */
    double d_files = 1 + (frame_count > 0 ? frame_count + 1 : 0);
    double d_bytes = (1.0 + frame_count) * ((double)width * height * 12 + 4096);
    extras_room(width, height, frame_count, skip | RENDER_SKIP_VIEWER, &d_bytes, &d_files);
    if (derivs > 0) {
        files += derivs * d_files + 1;
        bytes += derivs * d_bytes + 4096;
    }
    struct statvfs vfs;
    if (statvfs(dir, &vfs) == 0) {
        double room = (double)vfs.f_bavail * vfs.f_frsize;
        char need[32], have[32];
        memory_format_bytes(bytes, need, sizeof need);
        memory_format_bytes(room, have, sizeof have);
        if (bytes > room)
            return dp_fail(err, "%s: the outputs (%.0f files%s) need up to %s, the folder %s has %s free", path, files,
                           frame_count > 0 ? ", integrator.frame_num" : "", need, dir, have);
        if (vfs.f_files > 0 && files > (double)vfs.f_favail)
            return dp_fail(err, "%s: the outputs are %.0f files, the file system of %s has room for %lu more", path,
                           files, dir, (unsigned long)vfs.f_favail);
    }
    return 0;
}

/* ---- outputs over inputs ---- */

/* A list of paths that owns its strings. */
typedef struct {
    io_file *f;
    int n, cap;
} file_list;

static int list_add(file_list *l, const char *what, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int list_add(file_list *l, const char *what, const char *fmt, ...)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 16;
        io_file *f = realloc(l->f, (size_t)cap * sizeof *f);
        if (!f) return -1;
        l->f = f, l->cap = cap;
    }
    va_list ap;
    va_start(ap, fmt);
    char *path = NULL;
    int rc = vasprintf(&path, fmt, ap);
    va_end(ap);
    if (rc < 0) return -1;
    l->f[l->n++] = (io_file){path, what};
    return 0;
}

static void list_free(file_list *l)
{
    for (int i = 0; i < l->n; i++) free((char *)l->f[i].path);
    free(l->f);
}

/* Every file the render writes for the image path `path` (the same names as write_all, write_frames,
 * ground_truth_write, the checkpoint state of resume.c and the error log of error_log.c). */
static int list_outputs(file_list *l, const char *path, const scene *s, const render_plan *p, const render_request *rq,
                        dp_error *err)
{
    char stem[OUTPUT_PATH_MAX];
    const char *ext;
    if (split_output_path(path, stem, sizeof stem, &ext, err)) return -1;
    const time_window *tw = &p->window;
    int fail = list_add(l, "the image", "%s", path) || list_add(l, "the preview", "%s.png", stem) ||
               list_add(l, "the checkpoint state", "%s.state", stem) ||
               list_add(l, "the checkpoint state's lock", "%s.state.lock", stem);
    for (int k = 0; k < tw->frame_count && !fail; k++) {
        char frame[STAGED_PATH_MAX];
        frame_path(frame, sizeof frame, stem, tw->frame_count, k, ext);
        fail = list_add(l, "a frame", "%s", frame);
    }
    if (tw->frame_count > 0 && !fail)
        fail = list_add(l, "the frames' time axis", "%s" ATOMIC_SET_MANIFEST, stem) ||
               (!(rq->skip & RENDER_SKIP_CUBE) && list_add(l, "the transient cube", "%s_cube.npy", stem)) ||
               (!(rq->skip & RENDER_SKIP_VIEWER) && list_add(l, "the viewer", "%s_viewer.html", stem));
    if (tw->orders > 0 && !fail) fail = list_add(l, "the scattering orders", "%s_orders.npy", stem);
    if (s->cam.type == CAMERA_LIDAR && !fail) /* lidar_write_outputs */
        fail = list_add(l, "the lidar's waveforms", "%s_waveforms.npy", stem) ||
               list_add(l, "the waveforms' sidecar", "%s_waveforms.json", stem) ||
               (tw->orders > 0 && list_add(l, "the waveforms of each order", "%s_waveforms_orders.npy", stem)) ||
               list_add(l, "the lidar's points", "%s_points.npy", stem) ||
               list_add(l, "the lidar's points (PLY)", "%s_points.ply", stem);
    if (tw->amcw_count > 0 && !fail)
        fail = list_add(l, "the AMCW values", "%s_amcw.npy", stem) ||
               list_add(l, "the AMCW depth", "%s_amcw_depth.npy", stem);
    for (int k = 0; k < s->diff_count && !fail; k++) {
        fail = list_add(l, "a derivative image", "%s_d%d%s", stem, k, ext);
        for (int j = 0; j < tw->frame_count && !fail; j++) {
            char dstem[OUTPUT_PATH_MAX + 16], frame[STAGED_PATH_MAX];
            snprintf(dstem, sizeof dstem, "%s_d%d", stem, k);
            frame_path(frame, sizeof frame, dstem, tw->frame_count, j, ext);
            fail = list_add(l, "a derivative frame", "%s", frame);
        }
        if (tw->frame_count > 0 && !fail)
            fail = list_add(l, "a derivative frames' time axis", "%s_d%d" ATOMIC_SET_MANIFEST, stem, k) ||
                   (!(rq->skip & RENDER_SKIP_CUBE) && list_add(l, "a derivative cube", "%s_d%d_cube.npy", stem, k));
        if (tw->orders > 0 && !fail) fail = list_add(l, "a derivative's scattering orders", "%s_d%d_orders.npy", stem, k);
    }
    if (s->diff_count > 0 && !fail) fail = list_add(l, "the derivatives' sidecar", "%s_derivatives.csv", stem);
    for (int k = 0; k < GROUND_TRUTH_IMAGES && s->renderer.ground_truth && !fail; k++)
        fail = list_add(l, "a ground-truth image", "%s_%s%s", stem, GROUND_TRUTH_NAMES[k], ext);
    if (rq->log && !fail) {
        const char *dot = strrchr(rq->log, '.'), *slash = strrchr(rq->log, '/');
        int n = dot && (!slash || dot > slash) ? (int)(dot - rq->log) : (int)strlen(rq->log);
        fail = list_add(l, "--log", "%s", rq->log) ||
               (tw->frame_count > 0 &&
                list_add(l, "--log's frames", "%.*s_frames%s", n, rq->log, n < (int)strlen(rq->log) ? rq->log + n : ".csv"));
    }
    return fail ? dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory") : 0;
}

/* What the render reads: the scene file, --reference, textures, the sensor's response table and the authors'
 * EDA tables (the meshes are read once, at load, and not kept by name). */
static int list_inputs(file_list *l, const scene *s, const render_request *rq, dp_error *err)
{
    int fail = list_add(l, "the scene file", "%s", rq->scene_path) ||
               (rq->reference && list_add(l, "--reference", "%s", rq->reference));
    for (int i = 0; i < s->texture_count && !fail; i++) fail = list_add(l, "a texture", "%s", s->textures[i].path);
    for (const char *m = s->mesh_files; m && *m && !fail; m += strcspn(m, "\n") + 1)
        fail = list_add(l, "a mesh", "%.*s", (int)strcspn(m, "\n"), m);
    const char *resp = s->integrator.sensor_response_file;
    if (resp[0] && !fail)
        fail = list_add(l, "integrator.sensor_response_file", "%s%s%s", resp[0] == '/' ? "" : s->dir,
                        resp[0] == '/' ? "" : "/", resp);
    for (int i = 0; i < s->medium_count && !fail; i++) {
        const char *t = s->media[i].eda_table_path;
        if (t[0]) fail = list_add(l, "an EDA table (table_path)", "%s%s%s", t[0] == '/' ? "" : s->dir, t[0] == '/' ? "" : "/", t);
    }
    return fail ? dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory") : 0;
}

int render_outputs_refuse_inputs(const char *path, const scene *s, const render_plan *p, const render_request *rq,
                                 dp_error *err)
{
    file_list out = {0}, in = {0};
    int rc = list_outputs(&out, path, s, p, rq, err) || list_inputs(&in, s, rq, err) ||
             io_refuse_output_over_input(out.f, out.n, in.f, in.n, err);
    /* --log is the one output named apart from the image: it must not be one of the render's other files */
    for (int i = 0; !rc && rq->log && i < out.n; i++)
        if (strcmp(out.f[i].what, "--log") && strcmp(out.f[i].what, "--log's frames") && io_same_file(rq->log, out.f[i].path))
            rc = dp_fail(err, "--log %s is %s %s of this render: give the log another name", rq->log, out.f[i].what,
                         out.f[i].path);
    list_free(&out);
    list_free(&in);
    return rc ? -1 : 0;
}

int render_write_rescue(const film *f, const char *path, const char *integrator, const char *plan, int skip,
                        void (*wrote)(const char *path), char *rescue_dir, size_t n, dp_error *err)
{
    const char *tmp = getenv("TMPDIR");
    const char *dirs[] = {tmp && tmp[0] ? tmp : "/tmp", "/tmp", "."};
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    dp_error last = *err;
    for (int i = 0; i < 3; i++) {
        if (i > 0 && !strcmp(dirs[i], dirs[i - 1])) continue;
        if ((size_t)snprintf(rescue_dir, n, "%s/dartspp-rescue-XXXXXX", dirs[i]) >= n || !mkdtemp(rescue_dir)) continue;
        char target[STAGED_PATH_MAX];
        snprintf(target, sizeof target, "%s/%s", rescue_dir, base);
        if (!render_write_outputs(f, target, integrator, plan, skip, wrote, &last)) return 0;
        rmdir(rescue_dir); /* only if it stayed empty */
    }
    rescue_dir[0] = '\0';
    *err = last;
    return -1;
}
