/* Derivatives in the sensor pass of photon points (gather_deriv.h; docs/derivatives.md §4). The full path's
 * f is the photon's light path (its record: ∂ ln f and ∂τ up to the photon, its vertex's σs included) times the
 * camera's part (the camera throughput's transmittances and BSDFs, and at the gather point the transmittance
 * along the camera segment and the phase function), times a kernel that no parameter moves; ∂ ln f and ∂τ
 * are the sums of the two parts' (Yi et al. 2021 eq. 10 per factor), and the correlated importance's term is
 * added by deriv_splat at the photon path's own offset. */
#include "gather_deriv.h"

void gather_deriv_segment(const gather_input *g, deriv_path *cam, int med, double len, int timed)
{
    if (!g->deriv) return;
    deriv_transmittance(g->deriv, cam, med, len);
    if (timed) deriv_time(g->deriv, cam, med, len);
}

/* cam + the photon's record, for the parameters of d only (the rest of `out` is not read) */
static void joined(const deriv_plan *d, deriv_path *out, const deriv_path *cam, const photon_deriv *pd)
{
    for (int k = 0; k < d->count; k++) {
        const float *w = &pd->w[4 * k];
        out->dlog[k] = v3_add(cam->dlog[k], v3(w[0], w[1], w[2]));
        out->dtof[k] = cam->dtof[k] + w[3];
    }
}

void gather_deriv_volume(const gather_input *g, film_pixel *pix, const medium *m, vec3 d, const deriv_path *cam,
                         const photon *p, const photon_deriv *pd, double t, double leg, double time, vec3 c, int order)
{
    const deriv_plan *D = g->deriv;
    if (v3_is_zero(c)) return;
    int med = (int)(m - D->s->media);
    deriv_path dv;
    joined(D, &dv, cam, pd);
    deriv_transmittance(D, &dv, med, t); /* e^{−σt·t} from the segment origin to the photon's projection */
    deriv_time(D, &dv, med, leg);        /* the leg's time η·leg (0 on the unwarped sensor segment) */
    deriv_phase(D, &dv, med, v3(p->dir[0], p->dir[1], p->dir[2]), v3_neg(d));
    deriv_splat(D, pix, &dv, pd->light, time, pd->offset, c, p->frame, order);
}

void gather_deriv_surface(const gather_input *g, film_pixel *pix, const deriv_path *at, const photon_deriv *pd,
                          double time, vec3 c, int frame, int order)
{
    deriv_path dv;
    joined(g->deriv, &dv, at, pd);
    deriv_splat(g->deriv, pix, &dv, pd->light, time, pd->offset, c, frame, order);
}

void gather_deriv_leg(void *ctx, int region, double len)
{
    gather_leg *l = ctx;
    deriv_transmittance(l->d, l->p, region, len);
    deriv_time(l->d, l->p, region, len);
}
