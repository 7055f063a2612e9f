/* The primary line of each pixel: the medium segments of its camera ray before the first surface that
 * scatters (null and forward surfaces pass through, so the ray stays one straight line from the camera; an
 * orthographic camera's lines are parallel, each from its pixel's film point).
 * The camera walk records them; the volume gather on them is then done photon by photon
 * (volume_splat.c), the rest of the walk by beam queries as before. Private to src/gather. */
#ifndef DARTSPP_GATHER_PRIMARY_LINE_H
#define DARTSPP_GATHER_PRIMARY_LINE_H

#include "dartspp/film.h"
#include "dartspp/gather.h"

#define PRIMARY_SEGMENTS 2 /* medium segments kept per line; further ones are gathered by beam queries */

typedef struct {
    double t0, t1; /* along the line, from its origin */
    double t_cam;  /* camera time at t0 */
    double thr[3]; /* camera throughput at t0 */
    int medium;
} line_segment;

typedef struct {
    double o[3];   /* its origin: the camera's position (pinhole) or the pixel's film point (orthographic) */
    double d[3];   /* unit direction from the origin */
    int n;         /* segments recorded */
    line_segment seg[PRIMARY_SEGMENTS];
} primary_line;

/* volume_splat_applies: include/dartspp/gather.h */

/* Bytes of the per-pass buffers for a w × h image (the memory guard's estimate). */
size_t volume_splat_bytes(int width, int height);

/* The splat's scratch (the memory guard's estimate) for `photons` volume photons at radius r, from a sample
 * of n of them: footprints, tile starts and order, and the photon-in-tile entries (at most the cap beyond
 * which the pass gathers by beam queries instead). */
double volume_splat_scratch_bytes(const camera *c, const photon *sample, size_t n, double r, double photons);

/* The point-beam 2D gather of every volume photon into the pixels whose primary line passes within r of
 * it, tile by tile (each tile's photons in index order, so the film does not depend on the thread count).
 * Returns 0, or -1 when the tile lists would exceed their memory cap (the caller then gathers the lines by
 * beam queries). Tiles not started once g->stop is set are skipped. */
int volume_splat(const scene *s, const gather_input *g, film *f, const primary_line *lines);

/* The same gather for one pixel's line by a beam query per segment (the fallback, and the reference the
 * tests compare the splat against). */
void primary_line_gather_beam(const scene *s, const gather_input *g, film_pixel *pix, const primary_line *line);

/* The point-beam 2D estimate of photon p from a camera segment o + t·d (d unit) in medium m, the photon at
 * parameter t and squared distance d2 from it (docs/design.md §2.5): biweight kernel 3/(πr²)(1 − d2/r²)², the
 * phase function, the camera transmittance over t, camera-warped time; thr and t_cam at o, b_cam camera
 * segments. Both gathers (beam queries and the splat) use it. */
void volume_photon_splat(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, vec3 thr,
                         double t_cam, int b_cam, const photon *p, double t, double d2);
/* The same with derivatives (g->deriv): cam the camera path's state at o, pd the photon's record. */
void volume_photon_splat_deriv(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, vec3 thr,
                               double t_cam, int b_cam, const photon *p, double t, double d2, const deriv_path *cam,
                               const photon_deriv *pd);
/* The beam query of a camera segment o + t·d, 0 <= t <= len, in medium m (thr, t_cam at o, b_cam camera
 * segments), each photon found given to volume_photon_splat. On a gated film the query skips the subtrees
 * whose photons all fall outside the gate (photon_map_query_beam_window): the same contributions, less walk. */
void volume_beam_gather(const gather_input *g, film_pixel *pix, const medium *m, vec3 o, vec3 d, double len, vec3 thr,
                        double t_cam, int b_cam, const deriv_path *cam);
/* cam (with g->deriv): the camera path's derivative state at o; NULL without derivatives. */
/* Its second half, once the bounce count is checked and the film slot of the path time is known to
 * count: inline, as the splat calls it for every pixel a photon covers. Returns the contribution added (0 when
 * none). */
static inline vec3 volume_photon_splat_slot(const gather_input *g, film_pixel *pix, const medium *m, vec3 d, vec3 thr,
                                            const photon *p, double t, double d2, const film_slot *slot)
{
    double r2 = g->r_vol * g->r_vol;
    double u = 1.0 - d2 / r2;
    double K = 3.0 / (M_PI * r2) * u * u;
    vec3 wp = v3(p->dir[0], p->dir[1], p->dir[2]);
    double f = K * (phase_is_isotropic(&m->phase) ? DP_INV_4PI : phase_eval(&m->phase, wp, v3_neg(d)));
    vec3 tr = m->sigma_t.x == m->sigma_t.y && m->sigma_t.y == m->sigma_t.z ? v3s(exp(-m->sigma_t.x * t))
                                                                            : v3_exp_neg(v3_scale(m->sigma_t, t));
    vec3 c = v3_scale(v3_mul(v3_mul(thr, tr), v3(p->power[0], p->power[1], p->power[2])), f);
    if (v3_is_zero(c)) return c;
    if (film_slot_fits(slot, c)) {
        film_slot_add(pix->f, pix->px, slot, c);
        return c;
    }
    pix->nonfinite++;
    return v3s(0.0);
}

#endif
