/* The embedding API: a render in-process, from a scene file or the scene's JSON text, into arrays, without
 * printing anything (warnings come back as text) and without writing files. The Python package (python/) is
 * built on it and on nothing else; its contract is docs/python.md. Plain C types only, so that the API stays
 * stable while the modules behind it change. */
#ifndef DARTSPP_API_H
#define DARTSPP_API_H

#include <stdint.h>

#include "dartspp/core.h"
#include "dartspp/io.h"

/* ---- a render ---- */
typedef struct {
    const char *scene_path;       /* a scene file, or NULL and: */
    const char *scene_text;       /* the scene's JSON text, its name in messages, and the folder its relative */
    const char *scene_name;       /* paths resolve against (NULL: the working folder) */
    const char *base_dir;
    const char *const *sets;      /* "key=value" overrides, as `dartspp render --set` */
    int set_count;
    uint64_t seed;
    long spp;                     /* passes; < 0: as the scene says (or none when only time_limit is given) */
    double time_limit;            /* seconds; < 0: as the scene says (or none when only spp is given) */
    int threads;                  /* 0: all cores */
    double max_memory;            /* bytes; 0: what the machine has available */
    /* The error log (rows as `dartspp render --log`): a reference image from a file, or given as
     * ref_width × ref_height × 3 floats (row 0 at the top); neither: no log. */
    const char *reference_path;
    const float *reference_rgb;
    int ref_width, ref_height;
    double log_every;             /* seconds between rows; 0: every pass */
    /* Called after every completed pass (may be NULL); a non-zero return stops the render after that pass. */
    int (*progress)(void *ctx, long passes, double seconds, double r_vol, double r_surf);
    void *progress_ctx;
    /* Set asynchronously (a signal handler): the pass in progress is dropped; the API sets it too when progress
     * asks to stop. May be NULL. */
    dp_stop_flag *stop;
    /* Derivatives (docs/derivatives.md): JSON Pointers into the scene of the parameters θ_k to differentiate
     * the images by, as `dartspp render --derivative` (at most DIFF_PARAM_MAX); NULL/0: none. */
    const char *const *derivatives;
    int derivative_count;
} dp_render_request;

#define DP_LOG_COLUMNS 10 /* seconds, iterations, photon_paths, stored_photons, r_vol, r_surf, mse, rel_mse,
                           * mse_q99, nonfinite_pixels: the columns of the error log's CSV (render.h) */
extern const char *const DP_LOG_COLUMN_NAMES[DP_LOG_COLUMNS];

/* One of the run's figures (render.h, RENDER_FIGURES): its name (a static string) and value; integer: 1 when
 * the figure is a count (the value is then a whole number). */
#define DP_STATS_MAX 32
typedef struct {
    const char *name;
    double value;
    int integer;
} dp_stat;

typedef struct {
    int width, height, frame_count;
    float *image;                 /* height × width × 3 (the gate image) */
    float *frames;                /* frame_count × height × width × 3, NULL without frames */
    double *frame_times;          /* frame_count × 2: each frame's [start, end) */
    char *plan_json;              /* the resolved plan (plan_json) */
    char *integrator;             /* the plan's integrator name */
    int gated, camera_warped;     /* the time window, as the EXR headers record it */
    double gate_start, gate_end;
    char *warnings;               /* the scene's warnings, one per line, "" when none */
    long passes;
    int interrupted;              /* the stop flag (or the progress callback) ended the render */
    double seconds;
    dp_stat stats[DP_STATS_MAX];  /* the run's figures that render.h marks for the API, in its order */
    int stat_count;
    double *log;                  /* log_rows × DP_LOG_COLUMNS */
    int log_rows;
    int deriv_count;              /* the request's derivative_count */
    float *derivs;                /* deriv_count × height × width × 3: ∂(gate image)/∂θ_k, in the request's order */
    float *deriv_frames;          /* deriv_count × frame_count × height × width × 3, NULL without frames */
    /* A lidar camera (docs/lidar.md): its waveforms and point cloud, as the files <stem>_waveforms.npy and
     * <stem>_points.npy hold them; 0 and NULL for another camera. */
    int lidar_channels, lidar_azimuth_steps, lidar_bins;
    double lidar_range_bin;
    float *waveforms;             /* lidar_channels × lidar_azimuth_steps × lidar_bins */
    float *points;                /* point_count × 8: x, y, z, intensity, return, channel, azimuth index, range */
    long point_count;
    int amcw_count;               /* renderer.amcw_frequencies (docs/amcw.md): 0 without */
    double amcw_mhz[4];           /* those frequencies, MHz */
    float *amcw;                  /* amcw_count × height × width × 3 complex values, (re, im) interleaved; NULL without */
    float *amcw_depth;            /* height × width: the AMCW depth (0 where no signal); NULL without */
} dp_render_result;

/* Loads, checks and renders. Returns 0 with res filled (res->passes may be 0 when stopped before the first
 * pass), or -1 with err: DP_ERROR_INPUT for the scene, the options, the reference or a plan bigger than the
 * memory (before any work), other kinds for failures while rendering. res is valid after both (freed with
 * dp_render_result_free). */
int dp_render(const dp_render_request *rq, dp_render_result *res, dp_error *err);
void dp_render_result_free(dp_render_result *res);

/* One option of a render as the user wrote it ("max_memory", "8G"), parsed and range-checked by the command
 * line's own table (`dartspp render --max-memory 8G`), so that both refuse the same values with the same message.
 * name: the keyword (threads, seed, spp, time, log_every, max_memory, ...). 0 with *value (and *exact, the exact
 * value of a whole-number option), or -1 with err (DP_ERROR_INPUT). */
int dp_option_parse(const char *name, const char *text, double *value, uint64_t *exact, int *whole, dp_error *err);

/* ---- images ---- */
/* `dartspp compare`'s metrics of img against ref (same size; a NaN or Inf pixel in either is refused). */
int dp_compare(const image_rgb *img, const image_rgb *ref, image_error *e, dp_error *err);
/* An EXR (or PFM, by extension) written atomically, with a result's time window, integrator, plan and passes
 * in its header: frame -1 for the gate image, k for frame k (its own window). img: the pixels to write. */
int dp_write_image(const char *path, const image_rgb *img, const dp_render_result *res, int frame, dp_error *err);

/* ---- the key table (docs/keys.md) ---- */
typedef struct {
    const char *section, *name, *type, *meaning;
    char def[64], range[128], readers[128];
    int changes_image;
} dp_key_row;
int dp_key_count(void);
void dp_key_get(int i, dp_key_row *row);

#endif
