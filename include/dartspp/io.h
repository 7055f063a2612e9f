/* dartspp io: float32 images in and out (OpenEXR through its C API, PFM, PNG preview), frame sidecar CSV,
 * the transient cube (.npy) and its viewer page, atomic file writes, and the error metrics of
 * `dartspp compare`. */
#ifndef DARTSPP_IO_H
#define DARTSPP_IO_H

#include "dartspp/core.h"

#include <stdio.h>

/* An RGB float32 image, row 0 at the top, 3 interleaved floats per pixel. */
typedef struct {
    int width, height;
    float *rgb;
} image_rgb;

int image_alloc(image_rgb *img, int width, int height, dp_error *err); /* zero-filled */
void image_free(image_rgb *img);

/* What an EXR header records about the time axis (docs/time.md §6). */
typedef struct {
    const char *time_unit;   /* e.g. "optical path length in scene units (c = 1)" */
    int gated;               /* 0 = steady state (no gate): gate_start/gate_end not written */
    double gate_start;       /* window [gate_start, gate_end) of this image */
    double gate_end;
    int camera_warped;       /* 1: the camera leg counts in the path time */
    int frame_index;         /* -1 for a gate image, k for frame k */
    const char *integrator;  /* e.g. "path_tracer" (may be NULL) */
    const char *plan;        /* the render plan as JSON (plan.h; may be NULL) */
    long passes;             /* completed passes (iterations) in the image; 0: not recorded */
} image_meta;

/* Atomic writes: write to "<path>.tmp.<pid>" in the same folder, then rename over <path>. */
int atomic_open(const char *path, char *tmp_path, size_t tmp_len, dp_error *err); /* returns fd or -1 */
int atomic_commit(int fd, const char *tmp_path, const char *path, dp_error *err);  /* fsync, close, rename */
void atomic_abort(int fd, const char *tmp_path);

/* The same through a stdio stream (it writes through a dup of the temporary file's descriptor). */
typedef struct {
    const char *path;    /* the caller's string: must outlive the write */
    int fd;
    FILE *f;
    char tmp_path[4096];
} atomic_file;

/* Opens the temporary file of <path> as a stream with `mode` ("w" or "wb"); NULL with err set (and
 * nothing left behind) on failure. */
FILE *atomic_fopen(const char *path, const char *mode, atomic_file *af, dp_error *err);
/* Closes the stream and commits. If `failed` (the caller's writing went wrong), the stream has an error
 * or cannot be closed: "<path>: write failed: <errno text>", the temporary file removed, -1. */
int atomic_fclose(atomic_file *af, int failed, dp_error *err);
/* A whole text file: text and a newline, written atomically; text NULL (a failed allocation upstream, e.g.
 * cJSON_Print): "<path>: out of memory" and nothing written. */
int atomic_write_text(const char *path, const char *text, dp_error *err);
/* Closes the stream and removes the temporary file (the caller reports why). */
void atomic_fabort(atomic_file *af);

/* " (the file-size limit ...)" after the errno text of EFBIG, else "". */
const char *io_errno_hint(int e);

/* Removes the temporary files and staging folders of the writes in progress (async-signal-safe: for a
 * handler that ends the process). */
void atomic_cleanup_on_signal(void);

/* A set of files that appears all-or-nothing (the frames, cube, viewer and sidecar of a render): every file
 * is written under `stem` (with the same base name as the final stem) into the staging folder
 * "<dir>/.<base>.set.tmp.<pid>"; commit renames that folder to "<dir>/.<base>.set.commit.<pid>" (the commit
 * point) and moves its files to <dir>. A process killed before the commit point leaves the old files as
 * they were; one killed while moving leaves the commit folder, which the next atomic_clean_stale of the
 * same stem completes. The set's manifest "<base>" ATOMIC_SET_MANIFEST (the frame sidecar) is the reader's sign
 * that the set is whole: its old copy is removed before the first file moves and the new one moves last,
 * also when a later run completes the move, so whenever it exists every file of its set is in place. */
#define ATOMIC_SET_MANIFEST "_frames.csv"
typedef struct {
    char dir[4096], base[4096], stage[4200], stem[8400];
    char manifest[4200];
} atomic_set;
int atomic_set_open(atomic_set *s, const char *final_stem, dp_error *err);
int atomic_set_commit(atomic_set *s, void (*wrote)(const char *path), dp_error *err);
void atomic_set_abort(atomic_set *s);
/* What processes that no longer run left beside the outputs "<stem>*": temporary files "*.tmp.<pid>" and
 * staging folders are removed, commit folders completed; those of a running process are left alone. Each
 * gets a sentence for note(). Returns how many were found. */
int atomic_clean_stale(const char *stem, void (*note)(const char *msg));

/* Float32 RGB EXR (channels R, G, B, ZIP compression) with the metadata as header attributes
 * `dartspp.timeUnit`, `dartspp.gateStart`/`dartspp.gateEnd` (gated images only), `dartspp.cameraWarped`,
 * `dartspp.frame` (-1 for a gate image), `dartspp.passes` (when > 0), `dartspp.integrator` and `dartspp.plan`
 * (when not NULL); none when meta is NULL. */
int exr_write(const char *path, const image_rgb *img, const image_meta *meta, dp_error *err);
/* Reads R,G,B (or Y as grey) of any pixel type into float; other channels ignored. */
int exr_read(const char *path, image_rgb *img, dp_error *err);
/* The int header attribute `name` of part 0 (e.g. "dartspp.passes"): 0, or -1 with err (no such file,
 * attribute or type). */
int exr_read_int_attribute(const char *path, const char *name, int *value, dp_error *err);

/* PFM: "PF\n<w> <h>\n-1\n", little-endian float32 RGB, rows bottom to top. Reader also takes "Pf" (grey)
 * and big-endian (positive scale). */
int pfm_write(const char *path, const image_rgb *img, dp_error *err);
int pfm_read(const char *path, image_rgb *img, dp_error *err);

/* 8-bit sRGB PNG preview: values divided by the 0.99 quantile of the image's finite channel values
 * (1 if that quantile is 0), clamped to [0,1], sRGB-encoded; non-finite values shown as 0. */
int png_write_preview(const char *path, const image_rgb *img, dp_error *err);

/* By extension: ".exr" (meta may be NULL) or ".pfm"; anything else is an error naming the path. */
int image_write(const char *path, const image_rgb *img, const image_meta *meta, dp_error *err);
int image_read(const char *path, image_rgb *img, dp_error *err);

/* The q-quantile (0..1) of all finite channel values (nearest-rank); 0 if none, NaN if out of memory. */
double image_quantile(const image_rgb *img, double q);

/* Error of an image against a reference of the same size. Pixels with a non-finite channel in either
 * image are left out of every mean and counted in `nonfinite`. */
typedef struct {
    double mse;          /* mean over channels and pixels of (x - r)^2 */
    double rmse;         /* sqrt(mse) */
    double rel_mse;      /* mean of (x - r)^2 / (r^2 + 1e-2) */
    double mse_q99;      /* mse after dividing both images by q99 (papers' metric); = mse if q99 == 0 */
    double q99;          /* 0.99 quantile of the reference */
    long nonfinite;      /* pixels left out */
    long pixels;         /* pixels compared (finite in both) */
    double mse_trimmed;  /* image_compare_trimmed only (else 0): mse without the IMAGE_TRIM_SHARE of pixels
                          * with the largest squared error */
    long trimmed;        /* image_compare_trimmed only: pixels it leaves out, floor(IMAGE_TRIM_SHARE·pixels) */
} image_error;

/* The trimmed MSE's share of pixels dropped: the 0.1 % with the largest error summed over the channels (the
 * papers' equal-time tables; issue 52), so a handful of fireflies cannot decide a comparison. */
#define IMAGE_TRIM_SHARE 0.001

int image_compare(const image_rgb *img, const image_rgb *ref, image_error *out, dp_error *err);
/* image_compare and the trimmed MSE (a sort of the pixels' errors: `dartspp compare`, not the error log). */
int image_compare_trimmed(const image_rgb *img, const image_rgb *ref, image_error *out, dp_error *err);
/* Pixels with a NaN or Inf channel, and where the first is (row 0 at the top; -1 when none). */
long image_nonfinite_pixels(const image_rgb *img, int *first_x, int *first_y);

/* The mean of k >= 2 independent renders of the same size (equal weights) and the variance of that mean,
 * averaged over channels and pixels: V = mean of s²/k, s² the unbiased per-value sample variance. V is
 * what a reference's own noise adds to the expected MSE of any image compared against it. Values that are
 * non-finite in any input stay non-finite in the mean and are left out of V. */
int image_mean_of(const image_rgb *imgs, int k, image_rgb *mean, double *var_of_mean, dp_error *err);

/* Frame sidecar: "index,start,end" header and one line per frame k: k, start + k*w, start + (k+1)*w,
 * written with %.17g so that the time axis is exact. Atomic. */
int frames_csv_write(const char *path, int frame_count, double start, double width, dp_error *err);
/* Reads one back: the frames' [start, end) intervals (up to max of them) and their count; a line out of
 * order or with end <= start is an input error naming the file and the line. */
int frames_csv_read(const char *path, double *start, double *end, int max, int *count, dp_error *err);

/* NumPy .npy (format 1.0) of float32 (npy.c documents the layout): header "{'descr': '<f4', 'fortran_order':
 * False, 'shape': (d0, d1, ...), }" padded with spaces and '\n' so that the data starts at a multiple of 64
 * bytes, then the values little-endian in C order. Streamed and atomic: npy_open writes the header to the
 * temporary file, npy_append adds values in order, npy_close renames the file into place once exactly
 * prod(shape) values were given. After an error from any of them the temporary file is already gone;
 * npy_abort is for the caller's own failures between the calls. */
#define NPY_HEADER_MAX 256
typedef struct {
    atomic_file af;
    size_t left;   /* values still to come */
} npy_file;

int npy_open(npy_file *w, const char *path, const size_t *shape, int ndim, dp_error *err);
int npy_append(npy_file *w, const float *v, size_t n, dp_error *err);
int npy_close(npy_file *w, dp_error *err);
void npy_abort(npy_file *w);
/* All of an array at once. */
int npy_write_f32(const char *path, const size_t *shape, int ndim, const float *data, dp_error *err);
/* A complex64 array at once ('<c8': the AMCW values, docs/amcw.md §3): data holds 2 floats per value, the real
 * then the imaginary part, in C order; atomic like the rest. */
int npy_write_c64(const char *path, const size_t *shape, int ndim, const float *data, dp_error *err);
/* An int32 array at once ('<i4': photon-count histograms), atomic like the rest. */
int npy_write_i32(const char *path, const size_t *shape, int ndim, const int32_t *data, dp_error *err);
/* Reads a whole float32 array ('<f4', C order, .npy format 1.0 to 3.0): its shape (1 to NPY_MAX_DIMS axes) and
 * values (malloc'd, *data). Anything else (another dtype, Fortran order, a short or long file) is an input
 * error naming the file and what is wrong. */
#define NPY_MAX_DIMS 8
int npy_read_f32(const char *path, size_t *shape, int *ndim, float **data, dp_error *err);
/* The header bytes (magic to '\n') of an array into out; their count (a multiple of 64), 0 if it does not
 * fit in n or in the format. */
size_t npy_header(unsigned char *out, size_t n, const size_t *shape, int ndim);

/* ---- the frames viewer: <stem>_viewer.html (viewer_cube.c, viewer_html.c) ----
 * One self-contained page (data, script and style embedded; nothing fetched, so it works from file://):
 * a time slider and play button over the frames, one exposure for all of them, each frame's time interval,
 * and a click on the image plots that pixel's transient curve. The embedded frames are the frames
 * box-downscaled by an integer factor f (each embedded pixel the mean of an f×f block of the frame, the
 * blocks at the right and bottom edges partial) and, when that is not enough, every s-th frame, so that the
 * payload (float32 little-endian, base64 in the page) stays within VIEWER_PAYLOAD_MAX bytes. f grows first,
 * as long as the longer side keeps VIEWER_MIN_SIDE pixels; then s. */
#define VIEWER_PAYLOAD_MAX ((size_t)8 << 20)
#define VIEWER_MIN_SIDE 128
typedef struct {
    int width, height, frames;   /* the full frames */
    int factor, stride;          /* f, s */
    int dw, dh, embedded;        /* ceil(width / f), ceil(height / f), ceil(frames / s) */
} viewer_layout;

void viewer_layout_of(int width, int height, int frames, viewer_layout *l);
/* An upper bound of the page's size in bytes (for the check of the output folder's room). */
double viewer_html_bytes_max(const viewer_layout *l);

/* The embedded frames and a histogram of the cube, filled frame by frame. */
#define VIEWER_HIST_BINS 32768   /* positive floats by their top 15 bits: 1/128 of an octave */
typedef struct {
    viewer_layout l;
    float *data;        /* embedded × dh × dw × 3 */
    double *hist;       /* VIEWER_HIST_BINS counts of the positive channel values of every frame */
    double positives;   /* their count */
} viewer_cube;

int viewer_cube_init(viewer_cube *v, int width, int height, int frames, dp_error *err);
/* Frame k (full size): into the histogram, and box-downscaled into data when k is a multiple of s. */
void viewer_cube_add(viewer_cube *v, int k, const image_rgb *img);
/* The q-quantile (nearest rank) of the positive channel values added, within 1/128 of an octave (the
 * geometric middle of its histogram bin); 0 when there were none. */
double viewer_cube_quantile(const viewer_cube *v, double q);
void viewer_cube_free(viewer_cube *v);

/* What the page says about time. Frame k covers [start + k·width, start + (k+1)·width). */
typedef struct {
    const char *title;      /* e.g. the output's stem */
    const char *time_unit;  /* "optical path length in scene units (c = 1)" */
    int camera_warped;      /* 0: camera-unwarped time */
    double start, width;
} viewer_time;

/* The page, atomically. Its default exposure maps the 0.99 quantile of the cube's positive values to 1. */
int viewer_html_write(const char *path, const viewer_cube *v, const viewer_time *t, dp_error *err);

/* ---- outputs over inputs (same_file.c) ---- */
/* A file a command reads or writes, and what it is to the command, for messages ("the scene file", "--log"). */
typedef struct {
    const char *path; /* NULL: skipped */
    const char *what;
} io_file;
/* Whether a and b are one file: by device and inode when both exist (hard links and symlinks included), by
 * their resolved folder and name when neither does; a name that does not exist is never one that does. */
int io_same_file(const char *a, const char *b);
/* Before any work of a command that writes: an input error naming both paths when an output is an existing
 * input (the same device and inode: also through a hard link or a symlink). 0, or -1 with err. */
int io_refuse_output_over_input(const io_file *outputs, int n_out, const io_file *inputs, int n_in, dp_error *err);
/* Whether the file name (not its folders) ends in ext (".npy"), in any letter case. */
int io_has_extension(const char *path, const char *ext);

/* Create the parent folders of a file path (mkdir -p of dirname); 0 on success. */
int io_make_parent_dirs(const char *path, dp_error *err);

#endif
