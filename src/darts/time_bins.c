/* Time window and per-path target bins (docs/darts.md §2): each light path aims at one bin — the gate, or in
 * frame mode one frame, drawn uniformly in time over the part of the window the path can reach from its
 * light and emission time. */
#include "dartspp/darts.h"

void darts_guide_init(const darts_plan *d, const time_window *tw, vec3 cam, darts_guide *g)
{
    *g = (darts_guide){.active = d->active, .cam = cam, .beg = tw->start, .end = time_window_end(tw),
                       .width = tw->width, .frames = tw->frame_count, .eta_lb = d->eta_lb, .eta_ub = d->eta_ub,
                       .enable_elliptical = d->enable_elliptical, .enable_guiding = d->enable_guiding,
                       .control_vertex_mis = d->control_vertex_mis, .ellipse_residual = d->ellipse_residual, .strict_surfaces = d->strict_surfaces,
                       .early_exit = d->early_exit, .da_defensive = d->da_defensive, .cv_multi = d->cv_multi,
                       .focus_count = d->cv_multi ? d->side.mirror_count : 0, .cv_defensive = d->cv_defensive,
                       .camera_unwarp = tw->camera_unwarp};
    for (int k = 0; k < g->focus_count; k++) g->focus[k] = d->side.focus[k];
    for (int k = 0; k <= DARTS_MAX_MIRRORS; k++) g->cv_share[k] = d->cv_share[k];
}

int darts_sample_bin(const darts_guide *g, vec3 x_light, double tau0, double u, darts_bin *b)
{
    double t_min = dp_fmax(g->beg, tau0 + darts_leg_lb(g, x_light));
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
    double reach = end - dp_fmax(start, t_min); /* the part of this bin after the earliest arrival */
    if (!(reach > 0.0)) return 0;           /* rounding at a bin edge: probability ~0 */
    *b = (darts_bin){.start = start, .end = end, .pdf = reach / range, .frame = k};
    return 1;
}
