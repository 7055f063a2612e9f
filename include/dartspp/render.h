/* dartspp render: the render command (scene file to images), the progressive driver (passes, time budget,
 * progress, interruption) with its table of integrators (src/path_tracer, src/photon_points), the memory guard
 * and the outputs. */
#ifndef DARTSPP_RENDER_H
#define DARTSPP_RENDER_H

#include <signal.h>
#include <stdio.h>
#include <stdatomic.h>

#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/io.h"
#include "dartspp/plan.h"
#include "dartspp/scene.h"

/* ---- the render command ----
 * `dartspp render`, from the scene file to the images: the scene loaded and its plan resolved, the outputs
 * and the memory checked before any work (a refusal is bad input: exit 2), the progressive render with
 * checkpoints and the error log, the run summary (stdout) and the outputs, written to a rescue folder when
 * that fails. Messages go to stderr, each prefixed "dartspp render: ". */
typedef struct {
    const char *scene_path;
    const char *const *sets;     /* "key=value" overrides (--set), set_count of them */
    int set_count;
    const char *const *derivatives; /* JSON Pointers of the parameters to differentiate (--derivative), derivative_count */
    int derivative_count;
    const char *output;          /* NULL: the scene's hdr_output_file, else <scene stem>.exr */
    int skip;                    /* RENDER_SKIP_CUBE, RENDER_SKIP_VIEWER (--no-cube, --no-viewer) */
    int verbose, quiet;
    int threads;                 /* 0: all cores (several ranks on one machine: their share) */
    uint64_t seed;
    long spp;                    /* passes; < 0: as the scene says */
    double time_limit;           /* seconds; < 0: as the scene says */
    double checkpoint;           /* seconds between checkpoints; < 0: as the scene says; 0: none */
    const char *reference, *log; /* the error log against a reference image (both or neither) */
    double log_every;            /* seconds between its rows; 0: every pass */
    double max_memory;           /* bytes; 0: what the machine has available */
    int resume;                  /* --resume: continue from the checkpoint state "<output stem>.state" */
    int overwrite;               /* --overwrite: replace a checkpoint holding more passes than this run renders */
    double reduce_every;         /* several ranks: seconds between the reductions that keep the checkpoint state
                                  * on disk (--reduce-every; 0: only at checkpoints and the end); this process
                                  * alone: unused */
} render_request;

/* ---- the options of a render, as a user gives them ----
 * One table (src/render/options_check.c) for `dartspp render`'s flags and the embedding API's keywords, so that
 * both refuse the same values with the same message: "<name> (<flag>) <text>: <reason>". */
typedef enum {
    RENDER_OPT_THREADS, RENDER_OPT_SEED, RENDER_OPT_SPP, RENDER_OPT_TIME, RENDER_OPT_CHECKPOINT, RENDER_OPT_LOG_EVERY,
    RENDER_OPT_REDUCE_EVERY, RENDER_OPT_MAX_MEMORY, RENDER_OPT_COUNT
} render_opt;
typedef struct {
    double d;   /* the value (sizes in bytes) */
    uint64_t u; /* whole-number options: the exact value */
} render_opt_value;
/* The option named by its keyword ("max_memory") or flag ("--max-memory"), or -1. */
int render_opt_find(const char *name);
/* Parses an option's text as the user wrote it ("8G", "1e9", "4") and checks its range: 0 with *out, or -1
 * with the message in err (kind input). */
int render_opt_parse(render_opt o, const char *text, render_opt_value *out, dp_error *err);
/* The same range check of a value already held as a number (text: as written, or NULL to print v). */
int render_opt_check(render_opt o, double v, const char *text, dp_error *err);

typedef struct render_cluster render_cluster;

/* Runs the request on this process alone (cluster NULL or of one rank) or shared by the ranks of a cluster:
 * rank 0 checks the outputs and opens the error log, every rank loads the scene and passes the memory guard
 * before any renders, and rank 0 alone prints progress and the summary and writes outputs, checkpoints and
 * the error log. SIGINT and SIGTERM are caught from here on. Returns the exit status of the process:
 * 0, or dp_exit_status of the error that ended the run; a refusal on any rank refuses every rank. */
int render_run(const render_request *rq, const render_cluster *cluster);
/* For a rank whose command line was refused with exit status `status`: joins the ranks' agreement before
 * the render (so that the others do not wait for it) and returns the status they agree on. */
int render_run_refused(const render_cluster *cluster, int status);

/* ---- several processes as one render ----
 * The operations the driver needs from a cluster (src/cluster implements them over MPI). Every iteration is
 * an independent draw whose random numbers and radii depend only on the seed and the iteration index, so
 * rank r of N renders iterations r, r + N, r + 2N, ... ("rounds": in round k every rank renders iteration
 * kN + r), rank 0 decides after each round whether the render goes on, and the films are summed onto rank 0,
 * which alone writes. */

struct render_cluster {
    int rank, size;          /* this process, and how many render together */
    int ranks_on_node;       /* processes sharing this machine (the memory guard counts them all) */
    void *ctx;
    /* After every round, on every rank (collective): *go is 1 on entry if this rank would go on (rank 0:
     * its budget allows another round; any rank: not interrupted, no error); on return, 1 only if every rank
     * said 1. *gather is rank 0's wish (ignored elsewhere) to have the films summed now (a checkpoint); on
     * return, rank 0's wish on every rank. 0, or -1 when the communication failed. */
    int (*round)(const render_cluster *c, int *go, int *gather);
    /* Sums the films' pass sums, weight sums, pass counts and non-finite counts, and the statistics, onto
     * rank 0 (collective; total and st_total are written on rank 0 only, total already initialised like
     * mine). 0, or -1 with err. */
    int (*reduce)(const render_cluster *c, const film *mine, film *total,
                  const struct render_stats *st_mine, struct render_stats *st_total, dp_error *err);
    /* Whether any rank had rc != 0 (collective): the largest rc of all ranks, on every rank. */
    int (*agree_rc)(const render_cluster *c, int rc);
    /* Rank 0's values of n doubles, on every rank (collective). */
    int (*share)(const render_cluster *c, double *v, int n);
};

/* ---- the progressive driver ---- */

typedef struct {
    const render_plan *plan; /* the scene's resolved plan; NULL: render_scene resolves it */
    int threads;            /* 0: all cores */
    uint64_t seed;
    long spp;               /* passes; < 0: as the scene says */
    double time_limit;      /* seconds; < 0: as the scene says */
    int progress;           /* progress line on stderr */
    FILE *messages;         /* where the preparations say what they do (an EDA table built); NULL: silent */
    /* Set asynchronously (SIGINT/SIGTERM): the pass in progress stops within a batch of light paths or a row
     * of pixels and is dropped; render_scene returns with the completed passes. May be NULL. */
    const dp_stop_flag *stop;
    /* Set to 1 by render_scene when the first pass starts (before that an interrupt has nothing to keep:
     * the CLI exits at once, even while an EDA table is being built). May be NULL. */
    dp_stop_flag *passes_started;
    /* Called after every completed pass with the film and statistics so far (checkpoints, error logs).
     * A non-zero return stops the render with that error. May be NULL. */
    int (*after_pass)(void *ctx, const film *f, const struct render_stats *st, dp_error *err);
    void *after_pass_ctx;
    /* Several processes as one render (render_cluster above); NULL: this process alone. With a cluster
     * the film and statistics returned are the sums of all ranks on rank 0 (other ranks: their own), and
     * after_pass runs on rank 0 only, with the summed film, after the rounds where the films were summed:
     * every gather_every seconds (0: only at the end). */
    const render_cluster *cluster;
    double gather_every;
    /* A film to continue (--resume): its sums, weights and pass count are copied into the new film, and the
     * render goes on at pass resume->passes, the time budget counting from here. Same size and frames as the
     * scene's. NULL: from pass 0. With a cluster only rank 0 holds it (the others start from zero, so the
     * reduction adds it once) and every rank is told its pass count in resume_passes. */
    const film *resume;
    long resume_passes;     /* several ranks: the iteration the rounds start at (the state's pass count) */
    /* Several ranks, rank 0: odd while the driver is inside a collective call (a round's agreement or a
     * reduction), even outside; every entry and exit adds 1 (the watchdog of a run, run_internal.h, tells a
     * job stuck waiting for a lost rank from one that is working). May be NULL. */
    atomic_long *exchanges;
} render_options;

/* Renders the scene with its integrator into f (initialised here). On return, also with an error or an
 * interrupt, f holds the completed passes (possibly none) and the caller frees it with film_free. */
int render_scene(const scene *s, const render_options *opt, film *f, render_stats *st, dp_error *err);

/* ---- warnings before the render ----
 * Parts of the scene the chosen integrator or the DARTS samplers render with a known bias or not at all, and
 * how to avoid it (warnings.c): one line "warning: <scene>: ..." each, to `out` (the CLI: stderr; the Python
 * API: a buffer turned into Python warnings). */
void render_warn(FILE *out, const scene *s, const render_plan *p);

/* ---- error log: error against run time ----
 * CSV rows "seconds,iterations,photon_paths,stored_photons,r_vol,r_surf,mse,rel_mse,mse_q99,nonfinite_pixels"
 * of the running image against a reference image (EXR/PFM, same size), at most one every `every` seconds
 * of render time (0: every pass). In frame mode, reference frames "<ref stem>_NNNN<ext>" that exist are
 * compared too, into "<csv stem>_frames.csv" (seconds,iterations,frame,mse,rel_mse,mse_q99,nonfinite_pixels). */
typedef struct error_log error_log;
error_log *error_log_open(const char *csv_path, const char *ref_path, int width, int height, int frame_count,
                          double every, dp_error *err);
/* Logs the film after a pass if a row is due (or force); a pass is never logged twice. */
int error_log_pass(error_log *l, const film *f, const struct render_stats *st, int force, dp_error *err);
double error_log_overhead(const error_log *l); /* seconds spent computing and writing rows */
void error_log_close(error_log *l);

/* ---- memory guard ----
 * The plan's peak memory, item by item (memory_estimate, integrator.h), checked against the memory available
 * before any work is spent. */
/* The item of the derivative films (include/dartspp/derivative.h): K × the film's bytes, key "--derivative". */
#define MEMORY_DERIV_FILMS "derivative films (each as large as the film)"
/* have_reference: an error log holds a reference image. */
void render_memory_estimate(const scene *s, const render_plan *p, int have_reference, memory_estimate *m);
/* The guard: the estimate (into m) against max_memory bytes (0: memory_available()), shared by ranks_on_node
 * processes; 0 when it fits, else -1 with err naming the scene, both sizes and the key that drives the most. */
int render_memory_check(const scene *s, const render_plan *p, int have_reference, double max_memory, int ranks_on_node,
                        memory_estimate *m, dp_error *err);
/* The item with a key that needs the most (NULL if none). */
const memory_item *memory_largest(const memory_estimate *m);
/* Bytes the process can still use: MemAvailable, lowered to the cgroup's limit when there is one; -1 if
 * unknown. */
double memory_available(void);
/* "12.3 MiB" */
void memory_format_bytes(double bytes, char *out, size_t n);

/* ---- outputs ----
 * Writes the gate image to `path` (.exr or .pfm), a PNG preview `<stem>.png`, and in frame mode one image
 * per frame `<stem>_<NNNN>.<ext>` (0-based, zero-padded to at least 4 digits), `<stem>_frames.csv`, the
 * transient cube `<stem>_cube.npy` (float32, shape (frames, height, width, 3): the frame images value for
 * value) and the viewer page `<stem>_viewer.html` (io.h), the last two unless `skip` leaves them out.
 * integrator and plan (JSON, plan_json) go into the EXR headers (either may be NULL). Every file is written
 * atomically; `wrote` (may be NULL) is called with each path written. */
#define RENDER_TIME_UNIT "optical path length in scene units (c = 1)" /* the images' time axis (docs/time.md §6) */
#define RENDER_SKIP_CUBE 1    /* no <stem>_cube.npy (dartspp render --no-cube) */
#define RENDER_SKIP_VIEWER 2  /* no <stem>_viewer.html (--no-viewer) */
/* Ground truth beside the image (renderer key ground_truth; src/render/ground_truth.c, docs/sensor.md §3):
 * per pixel, for the ray through its centre, the first surface's depth (distance from the camera), the time
 * of first arrival through it, its normal (facing the camera) and albedo, as four images <stem>_depth,
 * <stem>_arrival, <stem>_normal, <stem>_albedo (depth and arrival in all three channels). */
#define GROUND_TRUTH_IMAGES 4
extern const char *const GROUND_TRUTH_NAMES[GROUND_TRUTH_IMAGES];
typedef struct {
    image_rgb img[GROUND_TRUTH_IMAGES]; /* in the order of GROUND_TRUTH_NAMES */
} ground_truth;
int ground_truth_compute(const scene *s, const render_plan *p, ground_truth *gt, dp_error *err);
/* Beside image_path (its stem and extension), atomically; wrote(path) after each. */
int ground_truth_write(const ground_truth *gt, const char *image_path, void (*wrote)(const char *), dp_error *err);
void ground_truth_free(ground_truth *gt);

int render_write_outputs(const film *f, const char *path, const char *integrator, const char *plan, int skip,
                         void (*wrote)(const char *path), dp_error *err);

#define OUTPUT_PATH_MAX 2048
/* Before any work: the extension (.exr or .pfm), the folder (created), a probe file created and removed
 * there, the disk room and file count of the gate image, preview, frame files, cube and viewer (skip as
 * above), and of the derivs derivative images' with their frames and cubes. 0 or -1 with err. */
int render_outputs_check(const char *path, int width, int height, int frame_count, int derivs, int skip,
                         dp_error *err);
/* Before any work (first of the output checks): refuses, naming both paths, an output of the render over one
 * of its inputs — any file it writes for `path` (image, preview, frames and their time axis, cube, viewer,
 * scattering orders, ground truth, checkpoint state, --log) that is the scene file, --reference, a texture,
 * the sensor's response table or an EDA table, by device and inode (links included) — and a --log that is
 * one of the render's other outputs. 0 or -1 with err. */
int render_outputs_refuse_inputs(const char *path, const scene *s, const render_plan *p, const render_request *rq,
                                 dp_error *err);
/* When writing to `path` failed at the end: the same outputs, under the same file names, in a new folder
 * dartspp-rescue-XXXXXX in $TMPDIR, else /tmp, else the working folder (the first that takes them);
 * rescue_dir receives that folder. 0, or -1 with err when no folder took them. */
int render_write_rescue(const film *f, const char *path, const char *integrator, const char *plan, int skip,
                        void (*wrote)(const char *path), char *rescue_dir, size_t n, dp_error *err);

#endif
