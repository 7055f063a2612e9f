/* A lidar's files (docs/lidar.md §4): from the film whose pixels are its beams and whose frames are its range bins,
 * the waveforms (and, with bounce_orders, the waveform of each scattering order), the echoes found in them as a
 * point cloud in NumPy and PLY. */
#include <stdio.h>
#include <stdlib.h>

#include "dartspp/film.h"
#include "dartspp/lidar.h"

/* Waveform value of bin k from the film's mean radiance L̄ there (docs/lidar.md §3): the energy per unit aperture
 * area is the bin's time width 2·range_bin times the irradiance ∫ L cosθ dω = etendue·L̄, L̄ the mean of the three
 * channels (a lidar is monochrome; grey materials and media give three equal ones). */
static double bin_scale(const lidar_params *l) { return lidar_receiver_etendue(l) * 2.0 * l->range_bin; }

int lidar_waveforms(const film *f, int order, float **out, dp_error *err)
{
    const lidar_params *l = &f->lidar->lidar;
    const time_window *tw = &f->window;
    size_t beams = (size_t)f->width * f->height, bins = (size_t)l->bins;
    float *w = malloc(beams * bins * sizeof *w);
    if (!w) return dp_fail_kind(err, DP_ERROR_MEMORY, "lidar waveforms: out of memory (%zu beams × %zu bins)", beams, bins);
    double scale = bin_scale(l);
    for (size_t k = 0; k < bins; k++) {
        image_rgb img = {0};
        long layer = order < 0 ? (long)k : film_order_layer(tw, order, (long)k);
        if (film_layer_image(f, layer, &img, err)) {
            free(w);
            return -1;
        }
        for (int y = 0; y < f->height; y++)
            for (int x = 0; x < f->width; x++) {
                const float *p = &img.rgb[3 * ((size_t)y * f->width + x)];
                size_t beam = (size_t)(f->height - 1 - y) * f->width + x; /* channel 0 is the lowest: the last row */
                w[beam * bins + k] = (float)(scale * ((double)p[0] + p[1] + p[2]) / 3.0);
            }
        image_free(&img);
    }
    *out = w;
    return 0;
}

static int write_waveforms(const film *f, const float *w, const char *stem, void (*wrote)(const char *), dp_error *err)
{
    const lidar_params *l = &f->lidar->lidar;
    char path[4200];
    size_t shape[3] = {(size_t)l->channels, (size_t)l->azimuth_steps, (size_t)l->bins};
    snprintf(path, sizeof path, "%s_waveforms.npy", stem);
    if (npy_write_f32(path, shape, 3, w, err)) return -1;
    if (wrote) wrote(path);
    return 0;
}

/* bounce_orders K: (K + 1, channels, azimuth_steps, bins), the waveform of the paths of 0, 1, ..., K − 1 and of K
 * or more scattering events (docs/time.md §7) */
static int write_order_waveforms(const film *f, const char *stem, void (*wrote)(const char *), dp_error *err)
{
    const lidar_params *l = &f->lidar->lidar;
    int orders = f->window.orders;
    size_t n = (size_t)l->channels * l->azimuth_steps * l->bins;
    size_t shape[4] = {(size_t)orders, (size_t)l->channels, (size_t)l->azimuth_steps, (size_t)l->bins};
    char path[4200];
    snprintf(path, sizeof path, "%s_waveforms_orders.npy", stem);
    npy_file file;
    if (npy_open(&file, path, shape, 4, err)) return -1;
    for (int o = 0; o < orders; o++) {
        float *w = NULL;
        if (lidar_waveforms(f, o, &w, err)) {
            npy_abort(&file);
            return -1;
        }
        int rc = npy_append(&file, w, n, err);
        free(w);
        if (rc) return -1;
    }
    if (npy_close(&file, err)) return -1;
    if (wrote) wrote(path);
    return 0;
}

static int write_points(const film *f, const float *w, const char *stem, void (*wrote)(const char *), dp_error *err)
{
    const camera *cam = f->lidar;
    lidar_points pts = {0};
    int rc = lidar_points_from_waveforms(&cam->lidar, cam->pos, cam->forward, v3_neg(cam->right), cam->up, w, &pts, err);
    char npy[4200], ply[4200];
    snprintf(npy, sizeof npy, "%s_points.npy", stem);
    snprintf(ply, sizeof ply, "%s_points.ply", stem);
    size_t shape[2] = {pts.count, LIDAR_POINT_COLUMNS};
    if (!rc) rc = npy_write_f32(npy, shape, 2, pts.rows, err);
    if (!rc && wrote) wrote(npy);
    if (!rc) rc = lidar_points_write_ply(ply, &pts, err);
    if (!rc && wrote) wrote(ply);
    lidar_points_free(&pts);
    return rc;
}

int lidar_write_outputs(const film *f, const char *stem, void (*wrote)(const char *), dp_error *err)
{
    char sidecar[4200];
    snprintf(sidecar, sizeof sidecar, "%s_waveforms.json", stem);
    float *w = NULL;
    if (lidar_waveforms(f, -1, &w, err)) return -1;
    int rc = write_waveforms(f, w, stem, wrote, err) || lidar_waveforms_sidecar_write(sidecar, &f->lidar->lidar, err);
    if (!rc && wrote) wrote(sidecar);
    if (!rc && f->window.orders > 0) rc = write_order_waveforms(f, stem, wrote, err);
    if (!rc) rc = write_points(f, w, stem, wrote, err);
    free(w);
    return rc ? -1 : 0;
}
