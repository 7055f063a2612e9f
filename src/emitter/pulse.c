/* Pulse shapes: the emission time of a light path (docs/emitters.md §3). */
#include "dartspp/emitter.h"

/* FWHM = 2·sqrt(2 ln 2)·σ for a Gaussian */
#define FWHM_PER_SIGMA 2.3548200450309493

double emitter_pulse_sample(const emitter_pulse *p, dp_rng *rng)
{
    if (!(p->width > 0.0)) return p->start;
    if (p->shape == PULSE_BOX) return p->start + p->width * rng_uniform(rng);
    /* Gaussian: one normal deviate by Box–Muller (the second is not kept), peak at start + width/2 */
    double u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    double z = sqrt(-2.0 * log1p(-u1)) * cos(2.0 * M_PI * u2);
    return p->start + 0.5 * p->width + z * (p->width / FWHM_PER_SIGMA);
}
