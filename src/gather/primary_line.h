/* The primary line of each pixel: the medium segments of its camera ray before the first surface that
 * scatters (null and forward surfaces pass through, so the ray stays one straight line from the camera).
 * The camera walk records them; the volume gather on them is then done photon by photon
 * (volume_splat.c), the rest of the walk by beam queries as before. Private to src/gather. */
#ifndef DARTSPP_GATHER_PRIMARY_LINE_H
#define DARTSPP_GATHER_PRIMARY_LINE_H

#include "dartspp/film.h"
#include "dartspp/gather.h"

#define PRIMARY_SEGMENTS 2 /* medium segments kept per line; further ones are gathered by beam queries */

typedef struct {
    double t0, t1; /* along the line, from the camera position */
    double t_cam;  /* camera time at t0 */
    double thr[3]; /* camera throughput at t0 */
    int medium;
} line_segment;

typedef struct {
    double d[3];   /* unit direction from the camera position */
    int n;         /* segments recorded */
    line_segment seg[PRIMARY_SEGMENTS];
} primary_line;

/* Whether the photon-by-photon gather can serve this pass (a pinhole with an orthonormal frame and a
 * volume map); otherwise the walk gathers every segment by beam queries. */
int volume_splat_applies(const scene *s, const gather_input *g);

/* Bytes of the per-pass buffers for a w × h image (the memory guard's estimate). */
size_t volume_splat_bytes(int width, int height);

/* The point-beam 2D gather of every volume photon into the pixels whose primary line passes within r of
 * it, tile by tile (each tile's photons in index order, so the film does not depend on the thread count).
 * Returns 0, or -1 when the tile lists would exceed their memory cap (the caller then gathers the lines by
 * beam queries). Tiles not started once g->stop is set are skipped. */
int volume_splat(const scene *s, const gather_input *g, film *f, const primary_line *lines);

/* The same gather for one pixel's line by a beam query per segment (the fallback, and the reference the
 * tests compare the splat against). */
void primary_line_gather_beam(const scene *s, const gather_input *g, film_pixel *pix, const primary_line *line);

/* The point-beam 2D estimate of photon p from a camera segment o + t·d (d unit) in medium m, the photon at
 * parameter t and squared distance d2 from it (reference §9.3): biweight kernel 3/(πr²)(1 − d2/r²)², the
 * phase function, the camera transmittance over t, camera-warped time; thr and t_cam at o, b_cam camera
 * segments. Both gathers (beam queries and the splat) use it. */
void volume_photon_splat(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, vec3 thr,
                         double t_cam, int b_cam, const photon *p, double t, double d2);
/* Its second half, once the bounce count and the path time (counted by the film) are known. */
void volume_photon_splat_timed(const gather_input *g, film_pixel *pix, const medium *m, vec3 d, vec3 thr,
                               const photon *p, double t, double d2, double time);

#endif
