/* `dartspp counts CUBE.npy --output COUNTS.npy --pulses N --scale S [options]`: what a single-photon
 * detector with time-correlated counting (SPAD/TCSPC) records of a transient cube over N laser pulses — an
 * int32 histogram per pixel, (frames, height, width), and a JSON sidecar of the parameters and the time axis;
 * with --coates also the Coates-corrected estimate of the cube from those counts. The model and its units:
 * include/dartspp/sensor.h and docs/sensor.md §1. The options are declared once, in OPTIONS below: parsing,
 * checks and the usage text come from there.
 *
 * The input may also be a lidar's waveforms, (channels, azimuth_steps, bins) float32 with its sidecar
 * <stem>.json (docs/lidar.md §5): then every beam is a pixel, its range bins the histogram's bins (bin k spans
 * path times [2k, 2k+2)·range_bin), the counts are (channels, azimuth_steps, bins), and a value, an energy per
 * bin, expects η·scale·value photons (scale applied per bin's time width: the layout below). */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <unistd.h>

#include <cjson/cJSON.h>

#include "dartspp/cli.h"
#include "dartspp/io.h"
#include "dartspp/sensor.h"

typedef struct {
    const char *cube, *output, *frames;
    spad_params sp;
    double seed;
    const char *channel;
    int coates, channel_given;
} counts_args;

/* Where a pixel's values sit in the input and its counts in the output: the cube's (frames, height, width, 3)
 * and (frames, height, width), or the waveforms' (beams, bins) and (beams, bins). */
typedef struct {
    size_t pixel_step, bin_stride;         /* input: cube 3 and 3·pixels; waveforms bins and 1 */
    size_t out_pixel_step, out_bin_stride; /* output: cube 1 and pixels; waveforms bins and 1 */
} counts_layout;

/* A waveforms file's sidecar (docs/lidar.md §5): what counts needs of it. */
typedef struct {
    int channels, azimuth_steps, bins;
    double range_bin;
} waves_info;

/* One numeric option: its flag, where it goes, its range, its default (NAN: required) and its meaning. */
typedef struct {
    const char *flag;
    size_t offset; /* of a double in counts_args */
    double min, max, def;
    const char *help;
} counts_option;

#define ARG(f) offsetof(counts_args, f)
static const counts_option OPTIONS[] = {
    {"--pulses", ARG(sp.pulses), 1, 1e15, NAN, "laser pulses N (acquisition cycles), an integer"},
    {"--scale", ARG(sp.scale), 0, 1e30, NAN, "photons reaching the detector per pulse, per unit of pixel value and of time"},
    {"--efficiency", ARG(sp.efficiency), 0, 1, 1, "photon detection efficiency η"},
    {"--dark-rate", ARG(sp.dark_rate), 0, 1e30, 0, "dark counts per unit of time"},
    {"--ambient-rate", ARG(sp.ambient_rate), 0, 1e30, 0, "ambient photons reaching the detector per unit of time (detected with η)"},
    {"--dead-time", ARG(sp.dead_time), 0, 1e30, 0, "blind time after a detection within a pulse; 0: none"},
    {"--seed", ARG(seed), 0, 9007199254740992.0, 1, "seed of the Poisson and binomial draws, an integer"},
};
#define OPTION_COUNT (int)(sizeof OPTIONS / sizeof OPTIONS[0])

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp counts CUBE.npy --output COUNTS.npy --pulses N --scale S [options]\n"
               "  (a transient cube of `dartspp render`, (frames, height, width, 3) float32, with its frames CSV;\n"
               "   or a lidar's <stem>_waveforms.npy, (channels, azimuth_steps, bins) float32, with its sidecar\n"
               "   <stem>_waveforms.json: counts (channels, azimuth_steps, bins), η·scale·value photons a bin)\n"
               "  %-15s the int32 histograms (frames, height, width), with the sidecar COUNTS.json (required)\n",
            "--output");
    for (int i = 0; i < OPTION_COUNT; i++) {
        const counts_option *o = &OPTIONS[i];
        if (isnan(o->def)) fprintf(f, "  %-15s %s (required)\n", o->flag, o->help);
        else fprintf(f, "  %-15s %s (default %g)\n", o->flag, o->help, o->def);
    }
    fprintf(f, "  %-15s the cube channel the detector sees: r, g, b or mean (default mean)\n"
               "  %-15s the frames' time axis (default: the cube's <stem>_frames.csv)\n"
               "  %-15s also write COUNTS_coates.npy: the cube estimated back from the counts (needs a dead time\n"
               "  %-15s at least the frames' span: one detection per pulse)\n"
               "  -h, --help      this text\n"
               "Units: times and rates in the scene's time unit (docs/time.md); model: docs/sensor.md.\n",
            "--channel", "--frames", "--coates", "");
}

static int parse_number(const char *s, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end == s || *end || errno || !isfinite(*v) ? -1 : 0;
}

static int parse_args(int argc, char **argv, counts_args *a)
{
    memset(a, 0, sizeof *a);
    a->channel = "mean";
    for (int i = 0; i < OPTION_COUNT; i++) *(double *)((char *)a + OPTIONS[i].offset) = OPTIONS[i].def;
    for (int i = 0; i < argc; i++) {
        const char *f = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(f, "--coates")) {
            a->coates = 1;
            continue;
        }
        if (f[0] != '-') {
            if (a->cube) {
                fprintf(stderr, "dartspp counts: two cubes given ('%s' and '%s')\n", a->cube, f);
                return -1;
            }
            a->cube = f;
            continue;
        }
        if (!v) {
            fprintf(stderr, "dartspp counts: %s needs a value\n", f);
            return -1;
        }
        i++;
        if (!strcmp(f, "--output")) a->output = v;
        else if (!strcmp(f, "--frames")) a->frames = v;
        else if (!strcmp(f, "--channel")) a->channel = v, a->channel_given = 1;
        else {
            int k = 0;
            while (k < OPTION_COUNT && strcmp(f, OPTIONS[k].flag)) k++;
            if (k == OPTION_COUNT) {
                fprintf(stderr, "dartspp counts: unknown option '%s'\n", f);
                return -1;
            }
            const counts_option *o = &OPTIONS[k];
            double x;
            if (parse_number(v, &x) || x < o->min || x > o->max) {
                fprintf(stderr, "dartspp counts: %s '%s': expected a number in [%g, %g] (%s)\n", f, v, o->min, o->max, o->help);
                return -1;
            }
            *(double *)((char *)a + o->offset) = x;
        }
    }
    for (int k = 0; k < OPTION_COUNT; k++)
        if (isnan(*(double *)((char *)a + OPTIONS[k].offset))) {
            fprintf(stderr, "dartspp counts: %s is required (%s)\n", OPTIONS[k].flag, OPTIONS[k].help);
            return -1;
        }
    if (!a->cube || !a->output) {
        fprintf(stderr, "dartspp counts: %s\n", !a->cube ? "no cube given" : "--output is required");
        return -1;
    }
    if (a->sp.pulses != floor(a->sp.pulses) || a->seed != floor(a->seed)) {
        fprintf(stderr, "dartspp counts: --pulses and --seed are integers\n");
        return -1;
    }
    const char *names[] = {"r", "g", "b", "mean"};
    a->sp.channel = -1;
    for (int c = 0; c < 4; c++)
        if (!strcmp(a->channel, names[c])) a->sp.channel = c;
    if (a->sp.channel < 0) {
        fprintf(stderr, "dartspp counts: --channel '%s': expected r, g, b or mean\n", a->channel);
        return -1;
    }
    return 0;
}

/* COUNTS.npy → COUNTS<suffix> (the extension replaced). */
static char *beside(const char *path, const char *suffix)
{
    size_t n = strlen(path);
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (dot && (!slash || dot > slash)) n = (size_t)(dot - path);
    char *s = malloc(n + strlen(suffix) + 1);
    if (s) {
        memcpy(s, path, n);
        strcpy(s + n, suffix);
    }
    return s;
}

/* The cube's frames CSV: <stem>_frames.csv for <stem>_cube.npy. */
static char *frames_of(const char *cube)
{
    size_t n = strlen(cube);
    const char *tail = "_cube.npy";
    if (n > strlen(tail) && !strcasecmp(cube + n - strlen(tail), tail)) n -= strlen(tail);
    char *s = malloc(n + 16);
    if (s) snprintf(s, n + 16, "%.*s_frames.csv", (int)n, cube);
    return s;
}

static const char *MODEL_NAMES[] = {"poisson (no dead time)", "one detection per pulse (dead time at least the span)",
                                    "dead time simulated pulse by pulse"};

/* waves: the waveforms' sidecar and bin width (docs/lidar.md §5), NULL for a cube. */
static int write_sidecar(const char *path, const counts_args *a, const spad_bins *b, const size_t *shape, spad_model m,
                         double total, const char *coates_path, const char *waves_sidecar, const waves_info *waves,
                         dp_error *err)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, waves ? "waveforms" : "cube", a->cube);
    if (waves) cJSON_AddStringToObject(root, "waveforms_sidecar", waves_sidecar);
    for (int i = 0; i < OPTION_COUNT; i++)
        cJSON_AddNumberToObject(root, OPTIONS[i].flag + 2, *(const double *)((const char *)a + OPTIONS[i].offset));
    if (waves) cJSON_AddStringToObject(root, "scale_unit", "photons per unit of waveform value (docs/lidar.md section 5)");
    else cJSON_AddStringToObject(root, "channel", a->channel);
    cJSON_AddStringToObject(root, "model", MODEL_NAMES[m]);
    cJSON_AddStringToObject(root, "dtype", "int32");
    cJSON *sh = cJSON_AddArrayToObject(root, "shape");
    for (int i = 0; i < 3; i++) cJSON_AddItemToArray(sh, cJSON_CreateNumber((double)shape[i]));
    if (waves) {
        cJSON_AddStringToObject(root, "axes", "channel (0 the lowest elevation), azimuth step, range bin");
        cJSON_AddNumberToObject(root, "range_bin", waves->range_bin);
        cJSON_AddNumberToObject(root, "bin_time_width", 2.0 * waves->range_bin);
        cJSON_AddStringToObject(root, "bins_in_time", "bin k spans path times [2k, 2k+2)*range_bin");
    } else {
        cJSON_AddStringToObject(root, "axes", "frame, row (0 at the top), column");
        cJSON *fr = cJSON_AddArrayToObject(root, "frames");
        for (int k = 0; k < b->count; k++) {
            cJSON *pair = cJSON_CreateArray();
            cJSON_AddItemToArray(pair, cJSON_CreateNumber(b->start[k]));
            cJSON_AddItemToArray(pair, cJSON_CreateNumber(b->end[k]));
            cJSON_AddItemToArray(fr, pair);
        }
    }
    cJSON_AddStringToObject(root, "time_unit", "the scene's (docs/time.md)");
    cJSON_AddNumberToObject(root, "total_counts", total);
    if (coates_path) cJSON_AddStringToObject(root, "coates", coates_path);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    int rc = atomic_write_text(path, text, err);
    free(text);
    return rc;
}

/* Every pixel's histogram (one stream per pixel: the counts do not depend on the thread count). sp: the model
 * as applied to the values (a->sp for a cube). */
static int count_pixels(const counts_args *a, const spad_params *sp, const counts_layout *lay, const spad_bins *b,
                        const float *cube, size_t pixels, int32_t *counts, float *coates, double *total, long *odd_bins)
{
    int F = b->count, failed = 0;
    double sum = 0.0;
    long odd = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : sum, odd) reduction(| : failed)
    for (size_t p = 0; p < pixels; p++) {
        double *mu = malloc(3 * (size_t)F * sizeof *mu), *h = mu ? mu + F : NULL, *mh = mu ? mu + 2 * F : NULL;
        if (!mu) {
            failed = 1;
            continue;
        }
        spad_expected(sp, b, cube + lay->pixel_step * p, lay->bin_stride, mu);
        dp_rng rng = rng_stream((uint64_t)a->seed, 0x636f756e7473ULL, p);
        failed |= spad_histogram(sp, b, mu, &rng, h) != 0;
        for (int k = 0; k < F; k++) {
            counts[(size_t)k * lay->out_bin_stride + p * lay->out_pixel_step] = (int32_t)h[k];
            sum += h[k];
        }
        if (coates) {
            odd += spad_coates(h, F, sp->pulses, mh);
            for (int k = 0; k < F; k++)
                coates[(size_t)k * lay->out_bin_stride + p * lay->out_pixel_step] =
                    (float)spad_value_of(sp, mh[k], b->end[k] - b->start[k]);
        }
        free(mu);
    }
    *total = sum;
    *odd_bins = odd;
    return failed ? -1 : 0;
}

/* Checks before any work: the largest expected count fits int32; the cost of a simulated dead time. */
static int check_plan(const counts_args *a, const spad_params *sp, const counts_layout *lay, const spad_bins *b,
                      const float *cube, size_t pixels, spad_model m)
{
    double *mu = malloc((size_t)b->count * sizeof *mu), worst = 0.0, per_pulse = 0.0, simulated = 0.0;
    if (!mu) return -1;
    for (size_t p = 0; p < pixels; p++) {
        spad_expected(sp, b, cube + lay->pixel_step * p, lay->bin_stride, mu);
        double sum = 0.0;
        for (int k = 0; k < b->count; k++) worst = fmax(worst, mu[k]), sum += mu[k];
        per_pulse = fmax(per_pulse, sum);
        simulated += spad_simulated_pulses(sp, b, mu);
    }
    free(mu);
    double expected = a->sp.pulses * worst;
    if (expected + 10.0 * sqrt(expected) > INT32_MAX) {
        fprintf(stderr, "dartspp counts: a bin expects %.3g counts, more than an int32 histogram holds: lower --pulses or --scale\n",
                expected);
        return -1;
    }
    if (simulated > 2e9) {
        fprintf(stderr, "dartspp counts: a dead time shorter than the frames' span is simulated pulse by pulse, and "
                        "%.3g pulses have a detection (more than 2e9): use fewer --pulses, or --dead-time 0 or at least the span\n",
                simulated);
        return -1;
    }
    if (m == SPAD_POISSON && per_pulse > 0.05)
        fprintf(stderr, "dartspp counts: warning: a pixel expects %.3g detections per pulse without dead time; a real "
                        "SPAD piles up above about 0.05 (set --dead-time)\n", per_pulse);
    if (a->sp.efficiency == 0.0) fprintf(stderr, "dartspp counts: warning: --efficiency 0: only dark counts are recorded\n");
    return 0;
}

/* The frames' time bins of a cube of F frames: from --frames or the cube's own <stem>_frames.csv, F rows in
 * time order. Fills start and end (F entries each); 0, or 2 with the message printed. */
static int read_frame_bins(const counts_args *a, const char *frames_path, int F, double *start, double *end)
{
    dp_error err;
    int n = 0;
    const char *fp = a->frames ? a->frames : frames_path;
    if (frames_csv_read(fp, start, end, F, &n, &err)) {
        fprintf(stderr, "dartspp counts: %s\n", err.msg);
        return 2;
    }
    if (n != F) {
        fprintf(stderr, "dartspp counts: %s has %d frames, the cube %s %d\n", fp, n, a->cube, F);
        return 2;
    }
    for (int k = 1; k < F; k++)
        if (start[k] < end[k - 1]) {
            fprintf(stderr, "dartspp counts: %s: frame %d starts before frame %d ends\n", fp, k, k - 1);
            return 2;
        }
    return 0;
}

/* The first NaN, Inf or negative value of the cube, as (frame, row, column, channel): such a value is a render
 * gone wrong, and the detector model would take it for 0 photons (or fail) without a word. 0, or 2 with the
 * message printed. */
static int check_cube_values(const char *path, const float *cube, const size_t *shape)
{
    size_t n = shape[0] * shape[1] * shape[2] * 3, bad = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (!(cube[i] >= 0.0f) || isinf(cube[i])) {
            if (!bad) first = i;
            bad++;
        }
    if (!bad) return 0;
    size_t c = first % 3, x = first / 3 % shape[2], y = first / 3 / shape[2] % shape[1], k = first / 3 / shape[2] / shape[1];
    fprintf(stderr, "dartspp counts: %s: %zu value(s) NaN, Inf or negative; the first, %g, at frame %zu, row %zu, "
                    "column %zu, channel %c: not a radiance a detector can count\n",
            path, bad, (double)cube[first], k, y, x, "rgb"[c]);
    return 2;
}

/* Whether the JSON file at path is a sidecar of this command (written by an earlier run with the same
 * --output): only then may it be replaced. */
static int is_counts_sidecar(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char *text = malloc(1 << 20);
    size_t n = text ? fread(text, 1, (1 << 20) - 1, f) : 0;
    fclose(f);
    if (!text) return 0;
    text[n] = 0;
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *dtype = cJSON_GetObjectItemCaseSensitive(root, "dtype");
    int ok = cJSON_IsString(dtype) && !strcmp(dtype->valuestring, "int32") &&
             cJSON_HasObjectItem(root, "total_counts") && cJSON_HasObjectItem(root, "pulses");
    cJSON_Delete(root);
    return ok;
}

/* Before any work: the output a .npy, no output over an input (the cube, its frames CSV; or the waveforms and
 * their sidecar) by device and inode, and the sidecar <stem>.json not a file of another kind (`--output
 * scene.npy` beside scene.json). 0, or 2. */
static int check_files(const counts_args *a, const char *frames_path, const char *waves_sidecar, const char *json,
                       const char *coates_path)
{
    if (!io_has_extension(a->output, ".npy")) {
        fprintf(stderr, "dartspp counts: --output %s: the counts are a NumPy int32 array: the name must end in .npy\n",
                a->output);
        return 2;
    }
    io_file out[] = {{a->output, "--output"}, {json, "the sidecar"}, {coates_path, "the Coates estimate"}};
    io_file in[] = {{a->cube, "the cube"}, {a->frames ? a->frames : frames_path, "the frames' time axis"}};
    if (waves_sidecar) in[0].what = "the waveforms", in[1].path = waves_sidecar, in[1].what = "the waveforms' sidecar";
    dp_error err;
    if (io_refuse_output_over_input(out, 3, in, 2, &err)) {
        fprintf(stderr, "dartspp counts: %s\n", err.msg);
        return 2;
    }
    if (!access(json, F_OK) && !is_counts_sidecar(json)) {
        fprintf(stderr, "dartspp counts: the sidecar of --output %s would replace %s, which is not a sidecar of "
                        "dartspp counts: choose another --output, or move that file\n", a->output, json);
        return 2;
    }
    return 0;
}

/* The counts (and Coates estimates) of every pixel, written with the sidecar; the run's line on stderr.
 * 0, 1 (out of memory, a failed write) or 2 (a plan the checks refuse), the message printed. */
static int write_counts(const counts_args *a, const spad_bins *b, spad_model m, const float *cube, const size_t *shape,
                        const char *json, const char *coates_path, const char *waves_sidecar, const waves_info *waves)
{
    int F = b->count, rc = 1;
    /* a cube's pixels are its rows × columns; the waveforms' are their beams, and a value there is already the
     * bin's integral in time, so scale/Δt turns it into the rate the model takes: η·scale·value photons */
    size_t pixels = waves ? shape[0] * shape[1] : shape[1] * shape[2];
    counts_layout lay = waves ? (counts_layout){(size_t)F, 1, (size_t)F, 1} : (counts_layout){3, 3 * pixels, 1, pixels};
    spad_params sp = a->sp;
    if (waves) sp.scale = a->sp.scale / (2.0 * waves->range_bin), sp.channel = 0;
    if (check_plan(a, &sp, &lay, b, cube, pixels, m)) return 2;
    int32_t *counts = malloc((size_t)F * pixels * sizeof *counts);
    float *coates = a->coates ? malloc((size_t)F * pixels * sizeof *coates) : NULL;
    double total, t0 = dp_seconds();
    long odd;
    dp_error err;
    if (!counts || (a->coates && !coates) || count_pixels(a, &sp, &lay, b, cube, pixels, counts, coates, &total, &odd)) {
        fprintf(stderr, "dartspp counts: out of memory\n");
        goto done;
    }
    size_t out_shape[3] = {(size_t)F, shape[1], shape[2]};
    if (waves) out_shape[0] = shape[0], out_shape[1] = shape[1], out_shape[2] = shape[2];
    if (npy_write_i32(a->output, out_shape, 3, counts, &err) ||
        (coates && npy_write_f32(coates_path, out_shape, 3, coates, &err)) ||
        write_sidecar(json, a, b, out_shape, m, total, coates_path, waves_sidecar, waves, &err)) {
        fprintf(stderr, "dartspp counts: %s\n", err.msg);
        goto done;
    }
    if (waves)
        fprintf(stderr, "dartspp counts: waveforms of %zu channels x %zu azimuth steps, %d bins of %g, %g pulses, %s: %.6g "
                        "counts (%.4g per beam) in %.2f s\n", shape[0], shape[1], F, waves->range_bin, a->sp.pulses,
                MODEL_NAMES[m], total, total / (double)pixels, dp_seconds() - t0);
    else
        fprintf(stderr, "dartspp counts: %d frames of %zux%zu pixels, %g pulses, %s: %.6g counts (%.4g per pixel) in %.2f s\n",
                F, shape[2], shape[1], a->sp.pulses, MODEL_NAMES[m], total, total / (double)pixels, dp_seconds() - t0);
    if (odd) fprintf(stderr, "dartspp counts: warning: %ld bins saturated or after every pulse had its detection: their "
                             "Coates estimates are bounds\n", odd);
    fprintf(stderr, "wrote %s\nwrote %s\n", a->output, json);
    if (coates_path) fprintf(stderr, "wrote %s\n", coates_path);
    rc = 0;
done:
    free(counts);
    free(coates);
    return rc;
}

/* The first NaN, Inf or negative value of waveforms (channels, azimuth_steps, bins), named by its channel,
 * azimuth step and bin. 0, or 2 with the message printed. */
static int check_waves_values(const char *path, const float *w, const size_t *shape)
{
    size_t n = shape[0] * shape[1] * shape[2], bad = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (!(w[i] >= 0.0f) || isinf(w[i])) {
            if (!bad) first = i;
            bad++;
        }
    if (!bad) return 0;
    size_t b = first % shape[2], az = first / shape[2] % shape[1], c = first / shape[2] / shape[1];
    fprintf(stderr, "dartspp counts: %s: %zu value(s) NaN, Inf or negative; the first, %g, at channel %zu, azimuth "
                    "step %zu, bin %zu: not an energy a detector can count\n", path, bad, (double)w[first], c, az, b);
    return 2;
}

/* A positive integer field of the waveforms' sidecar. */
static int sidecar_int(const cJSON *root, const char *key, int *v)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!cJSON_IsNumber(x) || !(x->valuedouble >= 1.0 && x->valuedouble <= INT_MAX) || x->valuedouble != floor(x->valuedouble))
        return -1;
    *v = (int)x->valuedouble;
    return 0;
}

/* The sidecar of a waveforms file (docs/lidar.md §5) at path: 0 when there is none there or that JSON is not one
 * (no "format": "dartspp lidar waveforms"), 1 with w filled, 2 (message printed) when it is one that cannot be
 * used. */
static int read_waves_sidecar(const char *path, waves_info *w)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char *text = malloc(1 << 20);
    size_t n = text ? fread(text, 1, (1 << 20) - 1, f) : 0;
    fclose(f);
    if (!text) {
        fprintf(stderr, "dartspp counts: out of memory\n");
        return 2;
    }
    text[n] = 0;
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *format = cJSON_GetObjectItemCaseSensitive(root, "format");
    if (!cJSON_IsString(format) || strcmp(format->valuestring, "dartspp lidar waveforms")) {
        cJSON_Delete(root);
        return 0;
    }
    const cJSON *rb = cJSON_GetObjectItemCaseSensitive(root, "range_bin");
    const char *bad = sidecar_int(root, "channels", &w->channels) ? "channels"
                      : sidecar_int(root, "azimuth_steps", &w->azimuth_steps) ? "azimuth_steps"
                      : sidecar_int(root, "bins", &w->bins) ? "bins"
                      : !cJSON_IsNumber(rb) || !(rb->valuedouble > 0.0) || isinf(rb->valuedouble) ? "range_bin" : NULL;
    if (!bad) w->range_bin = rb->valuedouble;
    cJSON_Delete(root);
    if (bad) {
        fprintf(stderr, "dartspp counts: %s: the waveforms' sidecar has no valid \"%s\" (%s; docs/lidar.md §5)\n", path,
                bad, strcmp(bad, "range_bin") ? "a positive integer" : "a positive number");
        return 2;
    }
    return 1;
}

/* The waveforms' bins as the histogram's: bin k spans path times [2k, 2k+2)·range_bin. */
static void waves_bins(const waves_info *w, double *start, double *end)
{
    for (int k = 0; k < w->bins; k++) start[k] = 2.0 * w->range_bin * k, end[k] = 2.0 * w->range_bin * (k + 1);
}

int cli_counts(int argc, char **argv)
{
    counts_args a;
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    int pr = parse_args(argc, argv, &a);
    if (pr) {
        usage(pr > 0 ? stdout : stderr);
        return pr > 0 ? 0 : 2;
    }
    dp_error err;
    size_t shape[NPY_MAX_DIMS];
    int ndim = 0, rc = 2;
    float *cube = NULL;
    char *frames_path = a.frames ? NULL : frames_of(a.cube), *json = beside(a.output, ".json"),
         *coates_path = a.coates ? beside(a.output, "_coates.npy") : NULL, *waves_json = beside(a.cube, ".json");
    double *start = NULL, *end = NULL;
    if (!json || (!a.frames && !frames_path) || (a.coates && !coates_path) || !waves_json) {
        fprintf(stderr, "dartspp counts: out of memory\n");
        rc = 1;
        goto done;
    }
    /* lidar waveforms are known by their sidecar <stem>.json (docs/lidar.md §5) */
    waves_info wv;
    int waves = read_waves_sidecar(waves_json, &wv);
    if (waves == 2) goto done;
    if (waves && (a.frames || a.channel_given)) {
        fprintf(stderr, "dartspp counts: %s: lidar waveforms (sidecar %s) have one value per bin and their time axis "
                        "in the sidecar: %s does not apply\n", a.cube, waves_json, a.frames ? "--frames" : "--channel");
        goto done;
    }
    if (check_files(&a, frames_path, waves ? waves_json : NULL, json, coates_path)) goto done;
    if (npy_read_f32(a.cube, shape, &ndim, &cube, &err)) {
        fprintf(stderr, "dartspp counts: %s\n", err.msg);
        goto done;
    }
    int F;
    if (waves) {
        if (ndim != 3 || shape[0] != (size_t)wv.channels || shape[1] != (size_t)wv.azimuth_steps || shape[2] != (size_t)wv.bins) {
            fprintf(stderr, "dartspp counts: %s: its sidecar %s gives waveforms of shape (%d, %d, %d) (channels, "
                            "azimuth_steps, bins); the file has %d axes%s\n", a.cube, waves_json, wv.channels,
                    wv.azimuth_steps, wv.bins, ndim, ndim == 3 ? " of other lengths" : "");
            goto done;
        }
        if (check_waves_values(a.cube, cube, shape)) goto done;
        F = wv.bins;
    } else {
        if (ndim == 3) {
            fprintf(stderr, "dartspp counts: %s: 3 axes, as lidar waveforms (channels, azimuth_steps, bins), but not "
                            "their sidecar %s, which gives the range bins (docs/lidar.md §5): no such file, or not a "
                            "waveforms sidecar\n", a.cube, waves_json);
            goto done;
        }
        if (ndim != 4 || shape[3] != 3 || shape[0] < 1 || shape[0] > 1000000) {
            fprintf(stderr, "dartspp counts: %s: expected a transient cube of shape (frames, height, width, 3), got %d axes\n",
                    a.cube, ndim);
            goto done;
        }
        if (check_cube_values(a.cube, cube, shape)) goto done;
        F = (int)shape[0];
    }
    start = malloc((size_t)F * sizeof *start), end = malloc((size_t)F * sizeof *end);
    if (!start || !end) {
        fprintf(stderr, "dartspp counts: out of memory\n");
        rc = 1;
        goto done;
    }
    if (waves) waves_bins(&wv, start, end);
    else if (read_frame_bins(&a, frames_path, F, start, end)) goto done;
    spad_bins b = {start, end, F};
    spad_model m = spad_model_of(&a.sp, &b);
    if (a.coates && m != SPAD_FIRST_PHOTON) {
        fprintf(stderr, "dartspp counts: --coates undoes the pile-up of one detection per pulse: it needs --dead-time "
                        "at least the %s span (%g)\n", waves ? "waveforms' bins'" : "frames'", end[F - 1] - start[0]);
        goto done;
    }
    rc = write_counts(&a, &b, m, cube, shape, json, coates_path, waves ? waves_json : NULL, waves ? &wv : NULL);
done:
    free(waves_json);
    free(cube);
    free(start);
    free(end);
    free(frames_path);
    free(json);
    free(coates_path);
    return rc;
}
