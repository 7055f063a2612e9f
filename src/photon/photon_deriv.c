/* A photon's derivative record (include/dartspp/photon.h, photon_deriv; docs/derivatives.md §4): the light
 * path's ∂ ln f per channel and ∂τ per parameter, in float, with its light and offset; and the record added
 * back to a camera path's state at a gather. The full path's ∂ ln f is the sum of its light and camera parts
 * (f is their product, the kernel aside; Yi et al. 2021 eq. 10 per factor). */
#include <string.h>

#include "dartspp/photon.h"

void photon_deriv_write(const deriv_plan *d, const deriv_path *p, int light, double offset, void *out)
{
    photon_deriv *pd = out;
    pd->offset = offset;
    pd->light = light;
    pd->unused = 0;
    for (int k = 0; k < d->count; k++) {
        float *w = &pd->w[4 * k];
        w[0] = (float)p->dlog[k].x, w[1] = (float)p->dlog[k].y, w[2] = (float)p->dlog[k].z;
        w[3] = (float)p->dtof[k];
    }
}

void photon_deriv_add(const deriv_plan *d, deriv_path *p, const photon_deriv *pd)
{
    for (int k = 0; k < d->count; k++) {
        const float *w = &pd->w[4 * k];
        p->dlog[k] = v3_add(p->dlog[k], v3(w[0], w[1], w[2]));
        p->dtof[k] += w[3];
    }
}
