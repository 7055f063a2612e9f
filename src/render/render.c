/* The progressive driver: passes until the pass count or the time budget is reached (or an interrupt),
 * with a progress line on stderr. Passes are independent draws; the film holds their running mean. */
#include "dartspp/darts.h"
#include "dartspp/render.h"

#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

typedef struct {
    int tty;
    double last_print;
} progress_line;

static void progress_print(progress_line *pl, const render_stats *st, long spp, double limit, int final)
{
    double now = st->seconds;
    if (!final && now - pl->last_print < (pl->tty ? 0.25 : 5.0)) return;
    pl->last_print = now;
    char left[64] = "";
    double rem = -1;
    if (limit > 0) rem = limit - now;
    if (spp > 0 && st->passes > 0) {
        double by_spp = (spp - st->passes) * now / st->passes;
        rem = rem < 0 ? by_spp : (by_spp < rem ? by_spp : rem);
    }
    if (rem >= 0) snprintf(left, sizeof left, ", %.1f s left", rem < 0 ? 0 : rem);
    char total[32] = "";
    if (spp > 0) snprintf(total, sizeof total, "/%ld", spp);
    char photons[96] = "";
    if (st->photon_paths > 0)
        snprintf(photons, sizeof photons, "  %.2f M photon paths/s  r_vol %.4g  R_surf %.4g",
                 now > 0 ? st->photon_paths / now * 1e-6 : 0.0, st->r_vol, st->r_surf);
    fprintf(stderr, "%spass %ld%s  %.1f s%s  %.2f M camera rays/s  %.2f M rays/s%s%s", pl->tty ? "\r\033[K" : "",
            st->passes, total, now, left, now > 0 ? st->camera_rays / now * 1e-6 : 0.0,
            now > 0 ? st->rays / now * 1e-6 : 0.0, photons, pl->tty && !final ? "" : "\n");
    fflush(stderr);
}

static int keep_going(const render_stats *st, long spp, double limit, const dp_stop_flag *stop)
{
    if (dp_stopped(stop)) return 0;
    if (st->passes == 0) return 1;
    if (spp > 0 && st->passes >= spp) return 0;
    if (limit > 0) {
        double per_pass = st->seconds / st->passes;
        if (st->seconds + 0.5 * per_pass >= limit) return 0;
    }
    return 1;
}

/* One pass of the plan's integrator into the film's pass layer. */
static int render_pass(const scene *s, const render_plan *p, const eda_set *eda, const render_options *opt, film *f,
                       render_stats *st, dp_error *err)
{
    if (p->type == INTEGRATOR_PATH_TRACER) {
        st->rays += path_tracer_pass(s, p, f, opt->seed, st->passes, opt->stop);
        return 0;
    }
    return photon_points_pass(s, p, eda, f, opt->seed, st->passes, opt->stop, st, err);
}

/* The passes, with the plan resolved and the film initialised. */
static int render_passes(const scene *s, const render_plan *p, const render_options *opt, film *f, render_stats *st,
                         dp_error *err)
{
    eda_set eda = {0};
    if (p->type == INTEGRATOR_PHOTON_POINTS && eda_set_prepare(s, p, &eda, err)) return -1;
    if (film_init(f, s->cam.width, s->cam.height, &p->window, err)) {
        eda_set_free(&eda);
        return -1;
    }
    long spp = opt->spp >= 0 ? opt->spp : p->spp;
    double limit = opt->time_limit >= 0 ? opt->time_limit : p->timeout_seconds;
    progress_line pl = {.tty = isatty(2), .last_print = -1e9};
    double t0 = dp_seconds();
    int rc = 0;
    if (opt->passes_started) *opt->passes_started = 1;
    while (!rc && keep_going(st, spp, limit, opt->stop)) {
        if ((rc = render_pass(s, p, &eda, opt, f, st, err))) break;
        if (dp_stopped(opt->stop)) { /* interrupted inside the pass: it is incomplete */
            film_drop_pass(f);
            break;
        }
        film_commit_pass(f, plan_pass_weight(p, f->passes));
        st->camera_rays += (double)s->cam.width * s->cam.height;
        st->passes = f->passes;
        st->seconds = dp_seconds() - t0;
        if (opt->progress) progress_print(&pl, st, spp, limit, 0);
        if (opt->after_pass) rc = opt->after_pass(opt->after_pass_ctx, f, st, err);
    }
    eda_set_free(&eda);
    st->seconds = dp_seconds() - t0;
    st->nonfinite = f->nonfinite;
    st->interrupted = dp_stopped(opt->stop);
    if (opt->progress) progress_print(&pl, st, spp, limit, 1);
    return rc ? -1 : 0;
}

int render_scene(const scene *s, const render_options *opt, film *f, render_stats *st, dp_error *err)
{
    *st = (render_stats){0};
    memset(f, 0, sizeof *f);
    if (opt->threads > 0) omp_set_num_threads(opt->threads);
    if (opt->plan) return render_passes(s, opt->plan, opt, f, st, err);
    render_plan p;
    if (plan_resolve(s, &p, err)) return -1;
    int rc = render_passes(s, &p, opt, f, st, err);
    plan_free(&p);
    return rc;
}
