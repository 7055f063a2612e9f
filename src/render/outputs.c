/* Film → files: gate image, PNG preview, per-frame images, the frame sidecar, the transient cube and its
 * viewer page (docs/cli.md §3), in frame mode as one set staged and moved into place; the check of the
 * output path before any work (with the cleanup of what killed runs left), and the rescue folder when the
 * final write fails anyway. */
#include "dartspp/render.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
    if (!dot || (slash && dot < slash) || (strcmp(dot, ".exr") && strcmp(dot, ".pfm")))
        return dp_fail(err, "%s: output must end in .exr or .pfm", path);
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

static int write_all(const film *f, const char *stem, const char *dot, const char *integrator, const char *plan,
                     int skip, void (*wrote)(const char *path), dp_error *err)
{
    char path[STAGED_PATH_MAX];
    snprintf(path, sizeof path, "%s%s", stem, dot);
    const time_window *tw = &f->window;
    image_meta meta = {.time_unit = RENDER_TIME_UNIT, .gated = tw->gated, .gate_start = tw->start,
                       .gate_end = time_window_end(tw), .camera_warped = !tw->camera_unwarp, .frame_index = -1,
                       .integrator = integrator, .plan = plan, .passes = f->passes};
    image_rgb img = {0};
    if (film_image(f, -1, &img, err)) return -1;
    char png[STAGED_PATH_MAX];
    snprintf(png, sizeof png, "%s.png", stem);
    int rc = write_one(path, &img, &meta, wrote, err);
    if (!rc) rc = png_write_preview(png, &img, err);
    if (!rc && wrote) wrote(png);
    image_free(&img);
    if (!rc && tw->frame_count > 0) rc = write_frames(f, stem, dot, meta, skip, wrote, err);
    if (!rc && tw->orders > 0) rc = write_orders(f, stem, wrote, err);
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

int render_outputs_check(const char *path, int width, int height, int frame_count, int skip, dp_error *err)
{
    char stem[OUTPUT_PATH_MAX], dir[OUTPUT_PATH_MAX], probe[STAGED_PATH_MAX];
    const char *ext;
    struct stat st;
    if (split_output_path(path, stem, sizeof stem, &ext, err)) return -1;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return dp_fail(err, "%s: output is a folder", path);
    if (io_make_parent_dirs(path, err)) return -1;
    atomic_clean_stale(stem, say_note);
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
