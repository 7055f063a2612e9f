/* Time window and per-path target bins (reference §2): each light path aims at one bin — the gate, or in
 * frame mode one frame, drawn uniformly in time over the part of the window the light can reach. */
#include "dartspp/darts.h"

void darts_guide_init(const scene *s, darts_guide *g)
{
    const integrator_settings *in = &s->integrator;
    const time_window *tw = &in->window;
    *g = (darts_guide){0};
    int eda = in->eda;
    for (int i = 0; i < s->medium_count; i++) eda |= s->media[i].eda;
    g->active = tw->gated && (in->enable_guiding || in->enable_elliptical || eda) && s->medium_count > 0;
    g->cam = s->cam.pos;
    g->beg = tw->start;
    g->end = time_window_end(tw);
    g->width = tw->width;
    g->frames = tw->frame_count;
    g->eta_lb = g->eta_ub = in->vacuum_eta;
    for (int i = 0; i < s->medium_count; i++) {
        g->eta_lb = fmin(g->eta_lb, s->media[i].eta);
        g->eta_ub = fmax(g->eta_ub, s->media[i].eta);
    }
    g->control_vertices = g->active && in->enable_elliptical && darts_eta_uniform(s);
}

int darts_region_present(const scene *s, int region)
{
    if (s->cam.medium == region) return 1;
    for (int i = 0; i < s->light_count; i++)
        if (s->lights[i].medium == region) return 1;
    for (int i = 0; i < s->surface_count; i++) {
        const surface *sf = &s->surfaces[i];
        if (sf->tri_count > 0 && sf->overrides_media && (sf->int_medium == region || sf->ext_medium == region)) return 1;
    }
    return 0;
}

int darts_eta_uniform(const scene *s)
{
    int seen = 0;
    double eta0 = 0.0;
    for (int r = MEDIUM_VACUUM; r < s->medium_count; r++) {
        if (!darts_region_present(s, r)) continue;
        double eta = medium_eta(s, r);
        if (seen && eta != eta0) return 0;
        eta0 = eta;
        seen = 1;
    }
    return 1;
}

int darts_sample_bin(const darts_guide *g, vec3 x_light, double u, darts_bin *b)
{
    double t_min = fmax(g->beg, g->eta_lb * v3_len(v3_sub(g->cam, x_light)));
    double range = g->end - t_min;
    if (!(range > 0.0)) return 0;
    if (g->frames == 0) {
        *b = (darts_bin){.start = g->beg, .end = g->end, .pdf = 1.0, .frame = -1};
        return 1;
    }
    double t = t_min + u * range;
    int k = (int)floor((t - g->beg) / g->width);
    if (k < 0) k = 0;
    if (k >= g->frames) k = g->frames - 1;
    double start = g->beg + k * g->width, end = k == g->frames - 1 ? g->end : start + g->width;
    double reach = end - fmax(start, t_min); /* the part of this bin after the earliest arrival */
    if (!(reach > 0.0)) return 0;           /* rounding at a bin edge: probability ~0 */
    *b = (darts_bin){.start = start, .end = end, .pdf = reach / range, .frame = k};
    return 1;
}
