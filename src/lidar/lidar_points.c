/* The lidar's point cloud and its files (include/dartspp/lidar.h; docs/lidar.md §4, §5): the echoes of every
 * beam's waveform as points at origin + range·(the beam's direction), the cloud as binary little-endian PLY,
 * and the JSON sidecar that describes a waveforms file (what `dartspp counts` reads to take it). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "dartspp/io.h"
#include "dartspp/lidar.h"

/* Room for `need` rows; -1 when it cannot be had (pts unchanged). */
static int reserve(lidar_points *pts, size_t *cap, size_t need)
{
    if (need <= *cap) return 0;
    size_t n = *cap ? *cap : 1024;
    while (n < need) {
        if (n > SIZE_MAX / 2 / LIDAR_POINT_COLUMNS / sizeof(float)) return -1;
        n *= 2;
    }
    float *rows = realloc(pts->rows, n * LIDAR_POINT_COLUMNS * sizeof *rows);
    if (!rows) return -1;
    pts->rows = rows;
    *cap = n;
    return 0;
}

int lidar_points_from_waveforms(const lidar_params *l, vec3 origin, vec3 forward, vec3 left, vec3 up,
                                const float *waveforms, lidar_points *pts, dp_error *err)
{
    pts->rows = NULL;
    pts->count = 0;
    if (l->channels < 1 || l->azimuth_steps < 1 || l->bins < 1 || !(l->range_bin > 0.0))
        return dp_fail(err, "lidar points: %d channels, %d azimuth steps, %d bins of %g: nothing to scan", l->channels,
                       l->azimuth_steps, l->bins, l->range_bin);
    int keep = l->echoes == LIDAR_ECHO_ALL ? l->max_echoes : 1;
    if (keep < 1) return dp_fail(err, "lidar points: max_echoes %d: at least 1", l->max_echoes);
    double threshold = l->echo_threshold * lidar_peak_reference(l, l->max_range);
    if (!(threshold >= 0.0) || isinf(threshold))
        return dp_fail(err, "lidar points: the echo threshold %g (echo_threshold %g of the peak at max_range %g) is not a "
                            "number >= 0", threshold, l->echo_threshold, l->max_range);
    lidar_echo *echoes = malloc((size_t)keep * sizeof *echoes);
    if (!echoes) return dp_fail_kind(err, DP_ERROR_MEMORY, "lidar points: out of memory");
    size_t cap = 0, bins = (size_t)l->bins;
    for (int c = 0; c < l->channels; c++)
        for (int a = 0; a < l->azimuth_steps; a++) {
            const float *wave = waveforms + ((size_t)c * (size_t)l->azimuth_steps + (size_t)a) * bins;
            int n = lidar_find_echoes(wave, l->bins, l->range_bin, threshold, l->echoes, echoes, keep);
            if (!n) continue;
            if (reserve(pts, &cap, pts->count + (size_t)n)) {
                size_t had = pts->count;
                free(echoes);
                lidar_points_free(pts);
                return dp_fail_kind(err, DP_ERROR_MEMORY, "lidar points: out of memory for more than %zu points", had);
            }
            vec3 dir = lidar_beam_dir(l, forward, left, up, c, a);
            for (int i = 0; i < n; i++) { /* echoes come in range order */
                vec3 p = v3_add(origin, v3_scale(dir, echoes[i].range));
                float *row = pts->rows + pts->count++ * LIDAR_POINT_COLUMNS;
                row[0] = (float)p.x, row[1] = (float)p.y, row[2] = (float)p.z;
                row[3] = (float)echoes[i].intensity;
                row[4] = (float)(i + 1);
                row[5] = (float)c, row[6] = (float)a;
                row[7] = (float)echoes[i].range;
            }
        }
    free(echoes);
    return 0;
}

void lidar_points_free(lidar_points *pts)
{
    free(pts->rows);
    pts->rows = NULL;
    pts->count = 0;
}

/* Little-endian stores, whatever the host. */
static unsigned char *put_u16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)(v & 0xff), p[1] = (unsigned char)(v >> 8 & 0xff);
    return p + 2;
}
static unsigned char *put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(u >> (8 * i) & 0xff);
    return p + 4;
}

#define PLY_RECORD 25 /* 4 floats, a uchar, 2 ushorts, a float: packed */

int lidar_points_write_ply(const char *path, const lidar_points *pts, dp_error *err)
{
    /* the integer columns must fit their PLY types before anything is written */
    for (size_t i = 0; i < pts->count; i++) {
        const float *r = pts->rows + i * LIDAR_POINT_COLUMNS;
        if (!(r[4] >= 0.0f && r[4] <= 255.0f) || !(r[5] >= 0.0f && r[5] <= 65535.0f) || !(r[6] >= 0.0f && r[6] <= 65535.0f))
            return dp_fail(err, "%s: point %zu has return %g, ring %g, azimuth index %g: beyond the PLY's uchar and ushort",
                           path, i, (double)r[4], (double)r[5], (double)r[6]);
    }
    atomic_file af;
    FILE *f = atomic_fopen(path, "wb", &af, err);
    if (!f) return -1;
    int failed = fprintf(f,
                         "ply\n"
                         "format binary_little_endian 1.0\n"
                         "comment dartspp lidar point cloud (docs/lidar.md section 4)\n"
                         "element vertex %zu\n"
                         "property float x\n"
                         "property float y\n"
                         "property float z\n"
                         "property float intensity\n"
                         "property uchar return_number\n"
                         "property ushort ring\n"
                         "property ushort azimuth_index\n"
                         "property float range\n"
                         "end_header\n",
                         pts->count) < 0;
    enum { CHUNK = 4096 };
    unsigned char buf[CHUNK * PLY_RECORD];
    for (size_t i = 0; i < pts->count && !failed;) {
        size_t n = 0;
        unsigned char *p = buf;
        for (; n < CHUNK && i < pts->count; n++, i++) {
            const float *r = pts->rows + i * LIDAR_POINT_COLUMNS;
            for (int k = 0; k < 4; k++) p = put_f32(p, r[k]);
            *p++ = (unsigned char)r[4];
            p = put_u16(p, (unsigned)r[5]);
            p = put_u16(p, (unsigned)r[6]);
            p = put_f32(p, r[7]);
        }
        failed = fwrite(buf, PLY_RECORD, n, f) != n;
    }
    return atomic_fclose(&af, failed, err);
}

static const char *ECHO_MODES[] = {"first", "strongest", "last", "all"};

int lidar_waveforms_sidecar_write(const char *path, const lidar_params *l, dp_error *err)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    cJSON_AddStringToObject(root, "format", "dartspp lidar waveforms");
    cJSON_AddStringToObject(root, "dtype", "float32");
    cJSON *sh = cJSON_AddArrayToObject(root, "shape");
    double shape[3] = {l->channels, l->azimuth_steps, l->bins};
    for (int i = 0; i < 3; i++) cJSON_AddItemToArray(sh, cJSON_CreateNumber(shape[i]));
    cJSON_AddStringToObject(root, "axes", "channel (0 the lowest elevation), azimuth step, range bin");
    cJSON_AddNumberToObject(root, "channels", l->channels);
    cJSON_AddNumberToObject(root, "azimuth_steps", l->azimuth_steps);
    cJSON_AddNumberToObject(root, "bins", l->bins);
    cJSON_AddNumberToObject(root, "range_bin", l->range_bin);
    cJSON_AddNumberToObject(root, "max_range", l->max_range);
    cJSON_AddNumberToObject(root, "bin_time_width", 2.0 * l->range_bin);
    cJSON_AddStringToObject(root, "bins_in_range", "bin b spans ranges [b, b+1)*range_bin, path times [2b, 2b+2)*range_bin");
    cJSON_AddStringToObject(root, "unit", "energy per unit aperture area in the bin (docs/lidar.md section 3)");
    cJSON_AddStringToObject(root, "length_unit", "the scene's; times are optical path lengths (docs/time.md)");
    cJSON_AddStringToObject(root, "angle_unit", "radian");
    cJSON *el = cJSON_AddArrayToObject(root, "elevation"), *az = cJSON_AddArrayToObject(root, "azimuth");
    for (int i = 0; i < 2; i++) {
        cJSON_AddItemToArray(el, cJSON_CreateNumber(l->elevation[i]));
        cJSON_AddItemToArray(az, cJSON_CreateNumber(l->azimuth[i]));
    }
    cJSON_AddNumberToObject(root, "beam_divergence", l->beam_divergence);
    cJSON_AddNumberToObject(root, "receiver_fov", l->receiver_fov);
    cJSON_AddNumberToObject(root, "power", l->power);
    cJSON_AddStringToObject(root, "pulse_shape", l->pulse.shape == PULSE_GAUSSIAN ? "gaussian" : "box");
    cJSON_AddNumberToObject(root, "pulse_width", l->pulse.width);
    cJSON_AddStringToObject(root, "echoes", (unsigned)l->echoes < 4 ? ECHO_MODES[l->echoes] : "?");
    cJSON_AddNumberToObject(root, "max_echoes", l->max_echoes);
    cJSON_AddNumberToObject(root, "echo_threshold", l->echo_threshold);
    cJSON_AddNumberToObject(root, "peak_reference_at_max_range", lidar_peak_reference(l, l->max_range));
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    int rc = atomic_write_text(path, text, err);
    free(text);
    return rc;
}
