/* Derivatives in the sensor pass of photon points (docs/derivatives.md §4): the camera path's state, the
 * photon's record, and the factors of the estimate between them. Private to src/gather. */
#ifndef DARTSPP_GATHER_DERIV_H
#define DARTSPP_GATHER_DERIV_H

#include "dartspp/gather.h"

/* A camera segment of length len in region med: its transmittance (a factor of the camera throughput) and, when
 * timed (not the unwarped sensor segment), its time. */
void gather_deriv_segment(const gather_input *g, deriv_path *cam, int med, double len, int timed);

/* The point-beam 2D estimate's derivative (volume_photon_splat_slot's c, landed at time and order): the camera
 * state, the photon's light path, the camera transmittance over t and the leg's time (leg), the phase function
 * between the photon's direction and the camera's. The kernel does not depend on θ. */
void gather_deriv_volume(const gather_input *g, film_pixel *pix, const medium *m, vec3 d, const deriv_path *cam,
                         const photon *p, const photon_deriv *pd, double t, double leg, double time, vec3 c, int order);

/* A surface photon's contribution c at time (frame, order): at is the camera state with the gather vertex's
 * BSDF in it. */
void gather_deriv_surface(const gather_input *g, film_pixel *pix, const deriv_path *at, const photon_deriv *pd,
                          double time, vec3 c, int frame, int order);

/* A light connection's leg, piece by piece (scene_transmittance_segments' callback; ctx a gather_leg). */
typedef struct {
    const deriv_plan *d;
    deriv_path *p;
} gather_leg;
void gather_deriv_leg(void *ctx, int region, double len);

#endif
