/* The 1-D beam × camera-ray kernel (photon_beams.h). */
#include "dartspp/photon_beams.h"

typedef struct {
    const beam_gather *g;
    const medium *m;
    int med;
    film_pixel *pix;
    vec3 d, thr;
    double t_cam;
    int b_cam, grey;
} beam_ctx;

static void beam_hit(void *ctx, const photon_beam *b, double t, double s, double inv_sin)
{
    const beam_ctx *c = ctx;
    if (b->medium != c->med || !bounces_count(&c->g->bounces, b->bounce + c->b_cam)) return;
    if (c->g->keep && !c->g->keep(c->g->keep_type, b->from)) return; /* a sliced primitive serves its paths */
    const medium *m = c->m;
    double leg = c->g->camera_unwarp && c->b_cam == 1 ? 0.0 : m->eta * t; /* the sensor's own segment: none */
    film_slot slot = film_time_slot(c->pix->f, c->t_cam + b->time + m->eta * s + leg, b->frame, b->bounce + c->b_cam - 1);
    if (!slot.counts) return; /* before the kernel, the phase function and the exponentials */
    vec3 wb = v3(b->dir[0], b->dir[1], b->dir[2]);
    double f = phase_is_isotropic(&m->phase) ? DP_INV_4PI : phase_eval(&m->phase, wb, v3_neg(c->d));
    double k = f * inv_sin / (2.0 * c->g->r); /* box kernel over the offset across both lines */
    vec3 tr, along;
    if (b->long_beam) { /* the DARTS pass: T_b(s), the beam reaching the next surface */
        tr = v3_exp_neg(v3_scale(m->sigma_t, t));
        along = v3_exp_neg(v3_scale(m->sigma_t, s));
    } else if (c->grey) {
        tr = v3s(exp(-m->sigma_t.x * t));
        along = v3s(1.0); /* T_b(s)/P_b(s) = 1: free flight drew the beam's length with this σt */
    } else {
        tr = v3_exp_neg(v3_scale(m->sigma_t, t));
        vec3 tb = v3_exp_neg(v3_scale(m->sigma_t, s));
        double p = v3_avg(tb); /* the chance the channel-mixture sampler reaches s */
        along = p > 0.0 ? v3_scale(tb, 1.0 / p) : v3s(0.0);
    }
    vec3 cst = v3_mul(v3_mul(c->thr, tr), v3_mul(m->sigma_s, along));
    vec3 val = v3_scale(v3_mul(cst, v3(b->power[0], b->power[1], b->power[2])), k);
    if (v3_is_zero(val)) return;
    if (!film_slot_fits(&slot, val)) c->pix->nonfinite++;
    else film_slot_add(c->pix->f, c->pix->px, &slot, val);
}

void photon_beams_gather(const beam_gather *g, const scene *s, film_pixel *pix, int med, vec3 o, vec3 d, double len,
                         vec3 thr, double t_cam, int b_cam)
{
    if (!g->map || med == MEDIUM_VACUUM) return;
    const medium *m = &s->media[med];
    if (!medium_scatters(m)) return;
    beam_ctx c = {g, m, med, pix, d, thr, t_cam, b_cam,
                  m->sigma_t.x == m->sigma_t.y && m->sigma_t.y == m->sigma_t.z};
    /* on a gated film, the gate (all frames) as the query's window: the path time of beam_hit */
    const time_window *tw = &pix->f->window;
    beam_window w = {.t0 = t_cam, .eta = g->camera_unwarp && b_cam == 1 ? 0.0 : m->eta, .lo = tw->start,
                     .hi = time_window_end(tw)};
    beam_map_query(g->map, o, d, len, tw->gated && tw->width > 0.0 ? &w : NULL, beam_hit, &c);
}

void photon_beams_memory(const photon_beam *pilot, size_t n, double r0, const beam_time_cut *tc, double V,
                         memory_estimate *m)
{
    double per_beam = n ? dp_fmax(beam_map_pieces(pilot, n, r0, tc) / (double)n, 1.0) : 1.0;
    memory_item_add(m, "volume beams and their map", "integrator.volume_photon_count",
                    photon_beam_array_bytes(V) + beam_map_bytes(V, V * per_beam));
}
