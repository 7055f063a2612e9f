/* The run summary on stdout: the scene and its gate, passes and ray rates, which photon-pass samplers ran,
 * the photon statistics, the cluster's overhead, the memory and the error log's. */
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

#include "dartspp/sliced_primitives.h"
#include "dartspp/darts.h"
#include "integrators.h"
#include "run_internal.h"

/* Where the camera sees a surface it continues through: how control vertices are split, and strict mode. */
static void print_continued_surfaces(const scene *s, const darts_plan *d)
{
    printf("; behind continued surfaces (the camera sees '%s'):", d->side.first);
    if (d->cv_multi) {
        printf(" control vertices %.0f %% straight", 100.0 * d->cv_share[0]);
        for (int k = 0; k < d->side.mirror_count; k++)
            printf(", %.0f %% at the mirror image in '%s'", 100.0 * d->cv_share[1 + k],
                   s->surfaces[d->side.mirror_surface[k]].name);
        printf(", %.0f %% defensive free flight", 100.0 * d->cv_defensive);
    }
    if (d->strict_time_width) printf("%s strict mode keeps every surface photon a camera path could gather", d->cv_multi ? ";" : "");
}

static void print_unwarped(const scene *s, const darts_plan *d)
{
    printf("; camera-unwarped time: control vertices %s", d->enable_elliptical ? "on the light leg's equal-time "
           "spheres" : d->unwarped_mirror_off ? "off (the camera sees a continued surface, whose later camera "
           "segments count)" : "off");
    if (s->integrator.enable_guiding) printf(", DA distance sampling off (it aims at the camera's ellipsoid)");
}

/* EDA per medium, and the media where DARTS does not sample (they do not scatter). */
static void print_media(const scene *s, const render_plan *p)
{
    for (int i = 0; i < s->medium_count; i++)
        if (p->darts.eda[i].asked_unwarped) printf("; EDA off in '%s' (camera-unwarped time)", s->media[i].name);
    const char *sep = "; EDA direction sampling in ";
    for (int i = 0; i < s->medium_count; i++) {
        if (!p->darts.eda[i].on) continue;
        printf("%s'%s' (alpha %g)", sep, s->media[i].name, p->darts.eda[i].alpha);
        sep = ", ";
    }
    printf("%s", sep[0] == ';' ? "; EDA off" : "");
    sep = "; no DARTS sampling in the non-scattering media ";
    for (int i = 0; i < s->medium_count; i++) {
        if (medium_scatters(&s->media[i])) continue;
        printf("%s'%s'", sep, s->media[i].name);
        sep = ", ";
    }
}

/* camera_control_vertices as asked: on, or why not (docs/darts.md §5.5). */
static void print_camera_side_cv(const render_plan *p)
{
    const darts_plan *d = &p->darts;
    const char *off = p->window.camera_unwarp ? "camera-unwarped time"
                      : !d->enable_elliptical ? "no elliptical control vertices"
                      : !d->camera_control_vertices ? "not a pinhole camera"
                      : p->volume_photon_type != VOLUME_PHOTON_POINTS ? "not volume photon points"
                      : deriv_on(&p->deriv) ? "derivatives" : NULL;
    if (off) printf("; camera-side control vertices off (%s)", off);
    else printf("; camera-side control vertices on (%g of the medium vertices)", CAMERA_CV_SHARE);
}

/* surface_direct_connections: how many lights the sensor pass connects at gathered surfaces (docs/defaults.md §3.8). */
static void print_surface_direct(const scene *s, const render_plan *p)
{
    int n = 0;
    for (int i = 0; p->surface_direct && i < s->light_count; i++) n += emitter_connects_exactly(&s->lights[i]);
    if (n > 0)
        printf("surfaces: the direct light of %d of %d lights connected from the camera, not stored as photons "
               "(surface_direct_connections)\n", n, s->light_count);
}

/* Which photon-pass samplers run (docs/design.md §4.3: the summary says which parts are active). */
void summary_print_photon_pass(const scene *s, const render_plan *p)
{
    const darts_plan *d = &p->darts;
    print_surface_direct(s, p);
    if (volume_type_sliced(p->volume_photon_type)) /* docs/sliced_primitives.md */
        printf("volume: %s (delta-sliced %s; long primitives: unbiased); beams' radius r0*gamma_i\n",
               slice_type_summary(p->volume_photon_type),
               p->window.delta ? "at the gate's instant" : "at a time drawn per primitive in the gate");
    if (p->volume_photon_type == VOLUME_PHOTON_BEAMS) /* docs/beams.md */
        printf("volume: photon beams, 1-D kernel, %s; radius r0*gamma_i\n",
               d->active ? "long beams (to the next surface: DA distances)" : "short beams (to the next vertex)");
    if (!d->active) {
        printf("photon pass: baseline (free-flight distances, photons at scattering vertices)%s\n",
               (d->enable_guiding || d->enable_elliptical_asked) ? "; DARTS samplers off: the scene has no medium or no gate" : "");
        return;
    }
    printf("photon pass: DARTS, %s target bins; DA distance sampling %s; elliptical control vertices %s (residual %s); "
           "strict time %s", p->window.frame_count ? "per-frame" : "gate", d->enable_guiding ? "on" : "off",
           p->window.camera_unwarp ? "off (camera-unwarped time)"
           : p->volume_photon_type == VOLUME_PHOTON_BEAMS ? "off (beams cover their segments)"
           : d->enable_elliptical ? "on"
           : d->enable_elliptical_asked ? "off: refractive index not uniform" : "off",
           d->ellipse_residual == RESIDUAL_EXPONENTIAL ? "exponential" : "uniform", d->strict_time_width ? "on" : "off");
    if (s->integrator.camera_control_vertices) print_camera_side_cv(p);
    if (d->side.seen && d->darts_mirrors == DARTS_MIRRORS_FULL) print_continued_surfaces(s, d);
    if (p->window.camera_unwarp) print_unwarped(s, d);
    print_media(s, p);
    printf("\n");
}

/* Which method the path tracer runs (docs/darts.md §14): plain, DARTS (which samplers) or uniform time. */
void summary_print_path_method(const scene *s, const render_plan *p)
{
    const darts_plan *d = &p->darts;
    const integrator_settings *in = &s->integrator;
    if (p->uniform_time) {
        printf("path tracer: uniform time (Jarabo et al. 2014, corrected as the DARTS supplement B.4): free-flight "
               "distances, line-to-point light connections, time-angular directions (share %g)\n",
               in->time_angular_share);
        return;
    }
    if (!d->active) {
        int asked = in->enable_guiding || in->enable_elliptical || in->time_sampling == TIME_SAMPLING_UNIFORM;
        printf("path tracer: plain%s\n", !asked ? ""
               : s->light_count == 0 ? "; DARTS and uniform time off: the scene has no light"
               : in->time_sampling == TIME_SAMPLING_UNIFORM && p->window.gated && s->medium_count > 0
                   ? "; uniform time off: the refractive index is not uniform"
                   : "; DARTS and uniform time off: the scene has no medium or no gate");
        return;
    }
    printf("path tracer: DARTS toward %s, %s target bins; DA distance sampling %s; elliptical light connections %s "
           "(residual %s, %s)", s->light_count > 1 ? "one light per camera path" : "the light",
           p->window.frame_count ? "per-frame" : "gate", d->enable_guiding ? "on" : "off",
           d->enable_elliptical ? "on" : d->enable_elliptical_asked ? "off: refractive index not uniform" : "off",
           d->ellipse_residual == RESIDUAL_EXPONENTIAL ? "exponential" : "uniform",
           d->control_vertex_mis ? "MIS with an in-bin exponential" : "no MIS");
    if (d->enable_elliptical && p->ellipse_directions)
        printf("; directions toward the next connection (share %g%s)", p->ellipse_direction_share,
               p->ellipse_surface_directions ? ", surfaces too" : "");
    if (p->window.camera_unwarp) printf("; camera-unwarped time: no sampler aims along the camera segment");
    print_media(s, p);
    printf("\n");
}

/* How each integrator reaches one light (docs/emitters.md §7): photon points by its light paths, the path
 * tracer as the light allows. */
const char *summary_photon_points_light(const emitter *e, const render_plan *p)
{
    (void)e, (void)p;
    return "light paths";
}

const char *summary_path_tracer_light(const emitter *e, const render_plan *p)
{
    if (!emitter_connectable(e)) return "cannot be reached (a parallel beam of radius 0: only photon points render it)";
    if (emitter_is_parallel_beam(e))
        return p->darts.active || p->uniform_time ? "beam crossings of the camera segments (no control vertex, DA or EDA "
                                                    "toward it)" : "beam crossings of the camera segments";
    if (emitter_hittable(e)) return "next-event estimation, and hits after the camera or a delta lobe";
    return "next-event estimation";
}

/* The lights: type, flux, the probability a light path (or an aimed camera path) picks it, and how the
 * integrator reaches it. */
static void print_lights(const scene *s, const render_plan *p)
{
    int by_power = p->light_selection == LIGHT_SELECTION_POWER;
    printf("lights (selected %s):", by_power ? "in proportion to flux" : "uniformly");
    for (int i = 0; i < s->light_count; i++) {
        const emitter *e = &s->lights[i];
        printf("%s '%s' (%s, flux %.4g, p %.3g%s): %s", i ? ";" : "", e->name, e->type_name, v3_avg(e->flux),
               emitter_selection_pdf(s, i, by_power),
               e->pulse.width > 0 ? (e->pulse.shape == PULSE_GAUSSIAN ? ", gaussian pulse" : ", box pulse") : "",
               integrator_entry_of(p->type)->light_technique(e, p));
    }
    printf("\n");
    const sensor_response *r = &s->cam.response;
    if (r->n) printf("sensor time response: tabulated, %d knots from %g to %g\n", r->n, r->t[0], r->t[r->n - 1]);
    else if (r->on) printf("sensor time response: Gaussian jitter FWHM %g, exponential tail of mean %g\n",
                           s->integrator.sensor_jitter_fwhm, r->tail);
}

/* The scene, its integrator and size, and the gate or frames. */
static void print_scene(const scene *s, const render_plan *p, double load_seconds)
{
    const time_window *tw = &p->window;
    printf("scene %s (loaded in %.2f s: %u triangles, %d textures): %s, %dx%d, ", s->path, load_seconds, s->tri_count,
           s->texture_count, p->type_name, s->cam.width, s->cam.height);
    if (!tw->gated) printf("steady state (no gate)\n");
    else if (tw->frame_count) printf("%d frames of width %g from %g (%s optical path length)\n", tw->frame_count, tw->width,
                                     tw->start, tw->camera_unwarp ? "camera-unwarped" : "camera-warped");
    else if (tw->delta)
        printf("delta gate at %g (%s optical path length): the time density there, per unit of optical path length, "
               "by a temporal box kernel of width w_i = %g·γ_i^(1/%d) and volume radius r_i = %g·γ_i^(1/%d), "
               "γ_i = Π_{k=1..i} (k + %g)/(k + 1)\n", tw->center, tw->camera_unwarp ? "camera-unwarped" : "camera-warped",
               p->w_gate.r0, p->w_gate.dims, p->r_vol.r0, p->r_vol.dims, p->w_gate.alpha);
    else printf("gate [%g, %g) (%s optical path length)\n", tw->start, time_window_end(tw),
                tw->camera_unwarp ? "camera-unwarped" : "camera-warped");
}

/* renderer.amcw_frequencies: the frequencies, their wrap depths, the unwrapping range and the dark pixels. */
static void print_amcw(const render_plan *p, const render_stats *st)
{
    const time_window *tw = &p->window;
    if (tw->amcw_count <= 0) return;
    printf("amcw: %d modulation frequenc%s (scene unit = 1 m, docs/amcw.md):", tw->amcw_count,
           tw->amcw_count == 1 ? "y" : "ies");
    for (int j = 0; j < tw->amcw_count; j++)
        printf(" %g MHz (wraps at depth %.6g)%s", tw->amcw_mhz[j], AMCW_C0 / (2e6 * tw->amcw_mhz[j]),
               j + 1 < tw->amcw_count ? "," : "");
    if (tw->amcw_count >= 2)
        printf("; depth unwrapped by the first two up to %.6g", amcw_unwrap_range(tw->amcw_mhz[0], tw->amcw_mhz[1]));
    printf("; %ld pixel%s without signal (depth 0)\n", st->amcw_dark_pixels, st->amcw_dark_pixels == 1 ? "" : "s");
}

/* The light paths: early exits, the volume budget, surface chains, rates, times and radii. */
static void print_photon_stats(const render_stats *st)
{
    if (st->early_exits > 0)
        printf("early exit: %.1f%% of the light paths ended as soon as no photon could reach their bin\n",
               100.0 * st->early_exits / st->photon_paths);
    if (st->aimed_paths > 0 && st->aimed_paths < st->photon_paths)
        printf("volume budget: full after %.1f%% of the light paths; the rest fed only the surface map "
               "(free flight, no control vertices)\n",
               100.0 * st->aimed_paths / st->photon_paths);
    if (st->chain_paths > 0)
        printf("surface chains: %.1f%% of the light paths; %.2f%% of the independent ones stored a surface photon "
               "that can count; %.1f%% of the small steps accepted\n",
               100.0 * st->chain_paths / st->photon_paths, 100.0 * st->chain_visible / fmax(st->chain_large, 1.0),
               100.0 * st->chain_accepted / fmax(st->chain_small, 1.0));
    if (st->chain_share > 0)
        printf("surface_paths auto: the chains traced %.1f%% of the light paths left once the volume budget was full "
               "(pilot %.2f s: the surface estimate's variance %.3g times the volume estimate's)\n",
               100.0 * st->chain_share, st->t_pilot, st->pilot_ratio);
    if (st->photon_paths > 0)
        printf("photon points: %.3g photon paths (%.2f M/s in the photon pass), %.3g photons stored; "
               "time in photon pass %.2f s, map builds %.2f s, sensor pass %.2f s; last radii r_vol %.4g, R_surf %.4g\n",
               st->photon_paths, st->t_photon > 0 ? st->photon_paths / st->t_photon * 1e-6 : 0.0, st->stored_photons,
               st->t_photon, st->t_maps, st->t_gather, st->r_vol, st->r_surf);
    if (st->w_gate > 0) printf("delta gate: the last iteration's temporal kernel width w %.4g\n", st->w_gate);
}

/* Several ranks: the film reductions and rank 0's time in them. */
static void print_cluster(const scene *s, const render_plan *p, const render_stats *st)
{
    double px = (double)s->cam.width * s->cam.height;
    char each[32];
    double film = px * 3 * sizeof(double) + px * 3 * sizeof(float) * time_window_layers(&p->window);
    memory_format_bytes((1 + s->diff_count) * film + 12 * sizeof(double), each, sizeof each);
    printf("cluster: %ld film reductions of %s from each rank; rank 0 spent %.3f s in the rounds' agreement and "
           "the reductions (%.2f%% of the render); photon-pass and sensor-pass times above are summed over the ranks\n",
           st->reductions, each, st->t_cluster, st->seconds > 0 ? 100.0 * st->t_cluster / st->seconds : 0.0);
}

static void print_summary(const scene *s, const render_plan *p, const render_stats *st, double load_seconds)
{
    print_scene(s, p, load_seconds);
    char resumed[96] = "";
    if (st->resumed_passes > 0)
        snprintf(resumed, sizeof resumed, " (%ld of them resumed from the checkpoint, %ld in this run)",
                 st->resumed_passes, st->passes - st->resumed_passes);
    printf("rendered %ld passes%s in %.2f s (%.2f M camera rays/s, %.2f M rays/s)%s; non-finite samples suppressed: %ld",
           st->passes, resumed, st->seconds, st->seconds > 0 ? st->camera_rays / st->seconds * 1e-6 : 0.0,
           st->seconds > 0 ? st->rays / st->seconds * 1e-6 : 0.0, st->interrupted ? " (interrupted)" : "",
           st->nonfinite + st->nonfinite_pixels);
    if (st->nonfinite_pixels > 0)
        printf(" (%ld of them whole pixels of the images, NaN or beyond the float range, written as 0)",
               st->nonfinite_pixels);
    printf("\n");
    print_amcw(p, st);
    integrator_entry_of(p->type)->print_method(s, p);
    if (s->light_count > 0) print_lights(s, p);
    print_photon_stats(st);
    if (st->reductions > 0) print_cluster(s, p, st);
}

/* The estimate's item named `what` (0 bytes when absent). */
static double item_bytes(const memory_estimate *m, const char *what)
{
    for (int i = 0; i < m->count; i++)
        if (!strcmp(m->item[i].what, what)) return m->item[i].bytes;
    return 0.0;
}

static void print_memory(const memory_estimate *m, int derivs)
{
    struct rusage ru;
    char est[32], peak[32] = "unknown", deriv[32];
    memory_format_bytes(m->total, est, sizeof est);
    if (getrusage(RUSAGE_SELF, &ru) == 0) memory_format_bytes(ru.ru_maxrss * 1024.0, peak, sizeof peak);
    printf("memory: estimated %s before the render", est);
    if (derivs > 0) {
        memory_format_bytes(item_bytes(m, MEMORY_DERIV_FILMS), deriv, sizeof deriv);
        printf(" (of which %s for the %d derivative film%s)", deriv, derivs, derivs > 1 ? "s" : "");
    }
    printf(", peak resident %s\n", peak);
}

/* The derivative images and their parameters (docs/derivatives.md §5): <stem>_d<k> is ∂I/∂θ_k. */
static void print_derivatives(const scene *s)
{
    if (s->diff_count <= 0) return;
    printf("derivatives (%d):", s->diff_count);
    for (int k = 0; k < s->diff_count; k++) printf("%s d%d = dI/d %s", k ? ";" : "", k, s->diffs[k].pointer);
    printf("\n");
}

void run_print_summary(const render_run_job *j, const render_stats *st)
{
    print_summary(&j->s, &j->p, st, j->load_seconds);
    print_derivatives(&j->s);
    print_memory(&j->mem, j->s.diff_count);
    const error_log *log = j->cp.log;
    if (log)
        printf("error log: %s (%.3f s spent logging, %.2f%% of the render)\n", j->rq->log, error_log_overhead(log),
               st->seconds > 0 ? 100.0 * error_log_overhead(log) / st->seconds : 0.0);
}
