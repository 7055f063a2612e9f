/* dartspp lidar: a scanning lidar camera that is emitter and receiver at once (docs/lidar.md). Each beam —
 * channel c (an elevation) and azimuth step a — is a film pixel (x = a, y = channels − 1 − c: the highest channel
 * on the top row) lit by its own diverging beam; the frames are its range bins. From the film come the
 * waveforms (one per beam), the echoes detected in them and the point cloud.
 *
 * Conventions (docs/lidar.md §1): angles in the sensor's frame — forward (the camera's look_at), left and up;
 * azimuth counter-clockwise about up from forward, elevation from the horizontal plane toward up. Times are
 * optical path lengths as everywhere (docs/time.md §1), so a target at range R returns at t = 2R; the pulse is
 * centred on t = 0 (its mean), so a wall at R gives an echo centred on R. */
#ifndef DARTSPP_LIDAR_H
#define DARTSPP_LIDAR_H

#include <stddef.h>

#include "dartspp/core.h"
#include "dartspp/emitter.h"

typedef enum { LIDAR_ECHO_FIRST, LIDAR_ECHO_STRONGEST, LIDAR_ECHO_LAST, LIDAR_ECHO_ALL } lidar_echo_mode;

/* The lidar keys of the camera (docs/lidar.md §2), angles in radians. */
typedef struct {
    int channels;             /* elevations, evenly spaced from elevation[0] to elevation[1] (both included) */
    int azimuth_steps;        /* azimuths at the centres of azimuth_steps equal steps of [azimuth[0], azimuth[1]] */
    double elevation[2], azimuth[2];
    double beam_divergence;   /* full angle of the transmitted cone (uniform intensity inside) */
    double receiver_fov;      /* full angle of the receiver's field of view (a cone about the beam's axis) */
    double power;             /* the pulse's energy Φ: flux × pulse, the pulse being a density in time */
    emitter_pulse pulse;      /* shape and width (path length); start = −width/2, centring its mean on t = 0 */
    double max_range;         /* range of the last bin's end */
    double range_bin;         /* bin width in range; a bin spans 2·range_bin of path time */
    int bins;                 /* ceil(max_range / range_bin) */
    vec3 offset;              /* transmitter − receiver in the sensor frame (right, up, forward); 0: coaxial */
    lidar_echo_mode echoes;
    double echo_threshold;    /* the detection threshold as a fraction of the peak bin of a white Lambertian
                               * target at max_range in clear air (lidar_peak_reference) */
    int max_echoes;           /* at most this many echoes per beam with echoes = all */
} lidar_params;

/* ---- the scan geometry (src/lidar/lidar_scan.c) ---- */

/* Elevation of channel c and azimuth of step a, radians. */
double lidar_channel_elevation(const lidar_params *l, int c);
double lidar_step_azimuth(const lidar_params *l, int a);
/* The unit world direction of beam (c, a) from the sensor's axes forward, left, up. */
vec3 lidar_beam_dir(const lidar_params *l, vec3 forward, vec3 left, vec3 up, int c, int a);
/* A receiver direction about axis b (unit), drawn in the cone of half-angle receiver_fov/2 with density
 * cosθ/(π sin²θ_r) relative to the sensor's normal b: the film's mean of the radiance L so drawn, times
 * lidar_receiver_etendue, is the irradiance ∫ L cosθ dω at the aperture (docs/lidar.md §3). */
vec3 lidar_receiver_dir(const lidar_params *l, vec3 b, double u1, double u2);
/* π sin²(receiver_fov/2). */
double lidar_receiver_etendue(const lidar_params *l);
/* Points a beam emitter along the unit axis (its frame across the axis too). */
void lidar_beam_set(emitter *e, vec3 axis);

/* ---- each beam's scene (src/lidar/lidar_beam.c) ---- */
struct scene;
/* The scene as the beam of pixel index px sees it: *view a shallow copy of s whose one light is *beam, the
 * lidar's beam template (s->lights[0]) aimed along that pixel's beam. The view shares everything else with s
 * and lives as long as s and beam do. */
void lidar_beam_view(const struct scene *s, size_t px, struct scene *view, emitter *beam);

/* ---- waveforms, echoes and points (src/lidar/lidar_echoes.c, lidar_points.c) ---- */

/* One echo of a waveform: a run of consecutive bins above the threshold. */
typedef struct {
    double range;      /* the run's centroid: Σ (bin centre)·w / Σ w, in range units */
    double intensity;  /* Σ w over the run: the echo's energy per unit aperture area */
    double width;      /* the run's length in range units */
    double peak;       /* its largest bin */
    int first_bin, last_bin;
} lidar_echo;

/* The peak bin a white Lambertian target at range R fills in clear air: its echo Φ/(πR²) (docs/lidar.md §3)
 * spread over the pulse's length in range, width/2, or held in one bin when that is shorter. */
double lidar_peak_reference(const lidar_params *l, double R);

/* The echoes of one waveform (bins values, bin b spanning [b, b+1)·range_bin) above `threshold`, selected by
 * `mode` (first, strongest, last, or all in range order up to max_out). Returns how many were written. */
int lidar_find_echoes(const float *wave, int bins, double range_bin, double threshold, lidar_echo_mode mode,
                      lidar_echo *out, int max_out);

/* One row of the point cloud (docs/lidar.md §4): x, y, z, intensity, return number (1 = nearest of the
 * beam's echoes kept), channel, azimuth index, range. */
#define LIDAR_POINT_COLUMNS 8
typedef struct {
    float *rows;       /* count × LIDAR_POINT_COLUMNS */
    size_t count;
} lidar_points;

/* Echoes of every beam of waveforms (channels × azimuth_steps × bins, C order, channel 0 the lowest) into
 * points: a point sits at origin + range·(the beam's direction). 0, or -1 with err (out of memory). */
int lidar_points_from_waveforms(const lidar_params *l, vec3 origin, vec3 forward, vec3 left, vec3 up,
                                const float *waveforms, lidar_points *pts, dp_error *err);
void lidar_points_free(lidar_points *pts);
/* The point cloud as binary little-endian PLY (x y z intensity as float, return as uchar, ring and azimuth as
 * ushort, range as float), written atomically. */
int lidar_points_write_ply(const char *path, const lidar_points *pts, dp_error *err);

/* ---- the files of a lidar render (src/lidar/lidar_outputs.c) ---- */
struct film;
/* The waveforms (channels × azimuth_steps × bins, channel 0 the lowest) of a lidar's film (film.lidar set): the
 * energy per unit aperture area in each bin (docs/lidar.md §3), of all paths (order −1) or of one order layer
 * (integrator.bounce_orders). *out is malloc'd. 0, or -1 with err. */
int lidar_waveforms(const struct film *f, int order, float **out, dp_error *err);
/* <stem>_waveforms.npy and its sidecar <stem>_waveforms.json, <stem>_waveforms_orders.npy (with bounce_orders),
 * <stem>_points.npy and <stem>_points.ply, each written atomically; wrote (may be NULL) is told each path. */
int lidar_write_outputs(const struct film *f, const char *stem, void (*wrote)(const char *path), dp_error *err);
/* The JSON sidecar of a waveforms file, <stem>_waveforms.json beside <stem>_waveforms.npy (docs/lidar.md §5):
 * its shape and axes, range_bin, max_range, bins, the unit of its values and the lidar's keys; what
 * `dartspp counts` reads to take the waveforms. Written atomically (src/lidar/lidar_points.c). */
int lidar_waveforms_sidecar_write(const char *path, const lidar_params *l, dp_error *err);

#endif
