/* The progressive driver: passes until the pass count or the time budget is reached (or an interrupt),
 * with a progress line on stderr. Passes are independent draws; the film holds their weighted mean
 * (plan_pass_weight). With a cluster (render_cluster, render.h) the ranks render them in rounds and the
 * films are summed onto rank 0. */
#include "dartspp/darts.h"
#include "dartspp/render.h"
#include "integrators.h"

#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

typedef struct {
    int tty;
    double last_print;
    long last_passes; /* the pass count of the last line printed (-1: none) */
} progress_line;

static void progress_print(progress_line *pl, const render_stats *st, long spp, double limit, int final)
{
    double now = st->seconds;
    if (!final && now - pl->last_print < (pl->tty ? 0.25 : 5.0)) return;
    /* a log (not a terminal) gets each line once: the final line of a pass already printed is not repeated */
    if (final && !pl->tty && st->passes == pl->last_passes) return;
    pl->last_print = now;
    pl->last_passes = st->passes;
    char left[64] = "";
    double rem = -1;
    if (limit > 0) rem = limit - now;
    long done = st->passes - st->resumed_passes; /* this run's passes */
    if (spp > 0 && done > 0) {
        double by_spp = (spp - st->passes) * now / done;
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

/* first: the passes the film held at the start (a resumed render); the time budget counts this run's. */
static int keep_going(const render_stats *st, long first, long spp, double limit, const dp_stop_flag *stop)
{
    long done = st->passes - first;
    if (dp_stopped(stop)) return 0;
    if (spp > 0 && st->passes >= spp) return 0;
    if (done == 0) return 1;
    if (limit > 0) {
        double per_pass = st->seconds / done;
        if (st->seconds + 0.5 * per_pass >= limit) return 0;
    }
    return 1;
}

/* Iteration `iteration` of the plan's integrator into the film's pass layer. */
static int render_pass(const scene *s, const render_plan *p, const eda_set *eda, const render_options *opt, film *f,
                       long iteration, render_stats *st, dp_error *err)
{
    return integrator_entry_of(p->type)->pass(s, p, eda, f, opt->seed, iteration, opt->stop, st, err);
}

/* Commits the pass layer as iteration i: the film's weighted sums and the statistics. */
static void commit_iteration(const scene *s, const render_plan *p, film *f, long i, render_stats *st)
{
    film_commit_pass(f, plan_pass_weight(p, i));
    st->camera_rays += (double)s->cam.width * s->cam.height;
    st->passes = f->passes;
}

/* The films and statistics of every rank summed into *total and *all on rank 0 (collective; elsewhere
 * *total is freed again). 0, or -1 with err. */
static int sum_onto_rank0(const render_cluster *c, const film *f, const render_stats *st, film *total,
                          render_stats *all, dp_error *err)
{
    *all = *st;
    if (film_init_like(total, f, err)) return -1;
    if (c->reduce(c, f, total, st, all, err)) {
        film_free(total);
        return -1;
    }
    if (c->rank != 0) film_free(total);
    return 0;
}

/* Rank 0's verdict after round k: another round fits the pass count and, as keep_going judges one process's
 * passes, the time budget. */
static int another_round(long k, long done, long spp, double seconds, double limit)
{
    if (spp > 0 && done >= spp) return 0;
    return !(limit > 0 && seconds + 0.5 * seconds / (k + 1) >= limit);
}

/* The progress line of the whole job, estimated on rank 0 from its own share. */
static void progress_print_job(progress_line *pl, const render_stats *st, int ranks, long done, long spp, double limit)
{
    render_stats est = *st;
    est.passes = done;
    est.camera_rays *= ranks;
    est.rays *= ranks;
    est.photon_paths *= ranks;
    progress_print(pl, &est, spp, limit, 0);
}

/* A reduction that failed (err says which): a rank was lost, and the films can no longer be summed. */
static int lost(dp_error *err)
{
    err->kind = DP_ERROR_LOST;
    return -1;
}

/* Marks rank 0's entries into and exits from collective calls for the run's watchdog (render_options). */
static void exchange_mark(const render_options *opt)
{
    if (opt->exchanges) atomic_fetch_add(opt->exchanges, 1);
}

/* This rank's pass of round k: iteration first + k·size + rank while below spp. A failed or interrupted pass
 * is dropped (and counted: the film then no longer holds a contiguous run of iterations). 1 if it failed. */
static int round_pass(const scene *s, const render_plan *p, const eda_set *eda, const render_options *opt, film *f,
                      long i, render_stats *st, dp_error *err)
{
    int failed = render_pass(s, p, eda, opt, f, i, st, err) != 0;
    if (failed || dp_stopped(opt->stop)) {
        film_drop_pass(f); /* failed, or interrupted inside the pass: it is incomplete */
        st->dropped++;
    } else
        commit_iteration(s, p, f, i, st);
    return failed;
}

/* The films summed onto rank 0 in the middle of the rounds, for after_pass (checkpoints, error-log rows, the
 * checkpoint state). 0, or -1 with err. */
static int gather_now(const render_options *opt, const film *f, render_stats *st, int *failed, dp_error *err)
{
    const render_cluster *c = opt->cluster;
    film total;
    render_stats all;
    exchange_mark(opt);
    int rc = sum_onto_rank0(c, f, st, &total, &all, err);
    exchange_mark(opt);
    if (rc) return -1;
    st->reductions++;
    all.seconds = st->seconds;
    if (c->rank == 0) {
        *failed |= opt->after_pass(opt->after_pass_ctx, &total, &all, err) != 0;
        film_free(&total);
    }
    return 0;
}

/* Several ranks (render_cluster, render.h): in round k this rank renders iteration first + k·size + rank
 * (while below spp; first: the passes of a resumed state, 0 otherwise), then rank 0 decides for all whether
 * another round starts and whether the films are summed now for after_pass (checkpoints, error logs, the
 * checkpoint state); at the end the films and statistics are summed onto rank 0. A rank that fails or is
 * interrupted says so at the round's end and every rank stops there; the completed passes of all ranks are
 * summed even then. A collective that returns an error (a rank lost, with an MPI that reports it instead of
 * aborting the job) ends the render with DP_ERROR_LOST. */
static int render_rounds(const scene *s, const render_plan *p, const eda_set *eda, const render_options *opt,
                         film *f, render_stats *st, long spp, double limit, dp_error *err)
{
    const render_cluster *c = opt->cluster;
    progress_line pl = {.tty = isatty(2), .last_print = -1e9, .last_passes = -1};
    double t0 = dp_seconds(), last_gather = 0.0;
    long first = opt->resume_passes;
    int failed = 0, go = 1;
    for (long k = 0; go; k++) {
        long i = first + k * c->size + c->rank, done = first + (k + 1) * c->size;
        if ((spp <= 0 || i < spp) && !failed) failed = round_pass(s, p, eda, opt, f, i, st, err);
        st->seconds = dp_seconds() - t0;
        if (spp > 0 && done > spp) done = spp;
        go = !failed && !dp_stopped(opt->stop) && (c->rank != 0 || another_round(k, done, spp, st->seconds, limit));
        int gather = c->rank == 0 && go && opt->after_pass && opt->gather_every > 0 &&
                     st->seconds - last_gather >= opt->gather_every;
        double tc = dp_seconds();
        exchange_mark(opt);
        int agreed = c->round(c, &go, &gather) == 0;
        exchange_mark(opt);
        if (!agreed) return dp_fail_kind(err, DP_ERROR_LOST, "the ranks lost contact (MPI): a rank was lost");
        if (gather) {
            if (gather_now(opt, f, st, &failed, err)) return lost(err);
            last_gather = st->seconds;
        }
        st->t_cluster += dp_seconds() - tc;
        if (c->rank == 0 && opt->progress) progress_print_job(&pl, st, c->size, done, spp, limit);
    }
    exchange_mark(opt);
    int any_failed = c->agree_rc(c, failed);
    film total;
    render_stats all;
    double tc = dp_seconds();
    int summed = sum_onto_rank0(c, f, st, &total, &all, err) == 0;
    exchange_mark(opt);
    if (!summed) return lost(err);
    if (c->rank == 0) {
        film_free(f);
        *f = total;
        all.seconds = dp_seconds() - t0;
        all.t_cluster = st->t_cluster + (dp_seconds() - tc);
        all.reductions = st->reductions + 1;
        const integrator_entry *row = integrator_entry_of(p->type);
        if (row->last_pass_figures) row->last_pass_figures(p, all.passes, &all);
        *st = all;
    }
    if (any_failed && !failed)
        return dp_fail_kind(err, DP_ERROR_RANK, "another rank failed (its message is above); the completed passes are kept");
    return failed ? -1 : 0;
}

/* A resumed render: the checkpoint's sums, weights and counts into the fresh film f. 0, or -1 with err. */
static int film_resume(film *f, const film *from, dp_error *err)
{
    if (from->width != f->width || from->height != f->height || from->window.frame_count != f->window.frame_count ||
        from->window.orders != f->window.orders || from->window.amcw_count != f->window.amcw_count)
        return dp_fail(err, "the film to resume is %dx%d with %d frames, the render %dx%d with %d", from->width,
                       from->height, from->window.frame_count, f->width, f->height, f->window.frame_count);
    if (from->deriv_count != f->deriv_count)
        return dp_fail(err, "the film to resume has %d derivative films, the render %d (--derivative)",
                       from->deriv_count, f->deriv_count);
    film_copy_sums(f, from);
    return 0;
}

/* The derivative films the scene asks for (scene.diffs), labelled with their pointers. */
static int render_film_derivs(const scene *s, film *f, dp_error *err)
{
    const char *labels[DIFF_PARAM_MAX];
    for (int k = 0; k < s->diff_count; k++) labels[k] = s->diffs[k].pointer;
    return film_init_derivs(f, s->diff_count, labels, err);
}

/* A lidar's film knows its camera: the files stage writes waveforms and points from it (docs/lidar.md §4). */
static int render_film_lidar(const scene *s, film *f)
{
    f->lidar = s->cam.type == CAMERA_LIDAR ? &s->cam : NULL;
    return 0;
}

/* The integrator's choices that cost work (integrator_entry.prepare) into q, a copy of the plan. */
static int prepare_plan(const scene *s, render_plan *q, const eda_set *eda, const render_options *opt,
                        render_stats *st, dp_error *err)
{
    const integrator_entry *e = integrator_entry_of(q->type);
    return e->prepare ? e->prepare(s, q, eda, opt->seed, opt->stop, opt->messages, st, err) : 0;
}

/* The passes, with the plan resolved and the film initialised. */
static int render_passes(const scene *s, const render_plan *plan, const render_options *opt, film *f,
                         render_stats *st, dp_error *err)
{
    eda_set eda = {0};
    render_plan q = *plan; /* read only but for prepare_plan's choices: its arrays stay plan's */
    const render_plan *p = &q;
    int ready = !eda_set_prepare(s, &p->darts, &p->window, &eda, opt->messages, err) &&
                !film_init(f, s->cam.width, s->cam.height, &p->window, err) && !render_film_derivs(s, f, err) &&
                !render_film_lidar(s, f) &&
                !(opt->resume && film_resume(f, opt->resume, err)) && !prepare_plan(s, &q, &eda, opt, st, err);
    const render_cluster *c = opt->cluster && opt->cluster->size > 1 ? opt->cluster : NULL;
    /* a rank without its EDA tables or film: none starts, and every rank exits with the largest status (2 when
     * a rank's cause is bad input), whichever rank's exit mpirun reports */
    int all = c ? c->agree_rc(c, ready ? 0 : dp_exit_status(err->kind)) : 0;
    if (all && ready)
        ready = !dp_fail_kind(err, all == dp_exit_status(DP_ERROR_INPUT) ? DP_ERROR_INPUT : DP_ERROR_RANK,
                              "another rank could not start the render (its message is above)");
    if (!ready) {
        eda_set_free(&eda);
        return -1;
    }
    long spp = opt->spp >= 0 ? opt->spp : p->spp;
    double limit = opt->time_limit >= 0 ? opt->time_limit : p->timeout;
    progress_line pl = {.tty = isatty(2), .last_print = -1e9, .last_passes = -1};
    double t0 = dp_seconds() - st->t_pilot; /* the pilot's time counts against the time limit */
    int rc = 0;
    st->passes = f->passes; /* 0, or the passes of the film resumed */
    long first = st->resumed_passes = f->passes;
    if (opt->passes_started) *opt->passes_started = 1;
    if (c) {
        rc = render_rounds(s, p, &eda, opt, f, st, spp, limit, err);
        eda_set_free(&eda);
        st->nonfinite = f->nonfinite;
        st->interrupted = st->interrupted || dp_stopped(opt->stop);
        if (opt->progress && c->rank == 0) progress_print(&pl, st, spp, limit, 1);
        return rc ? -1 : 0;
    }
    while (!rc && keep_going(st, first, spp, limit, opt->stop)) {
        if ((rc = render_pass(s, p, &eda, opt, f, st->passes, st, err))) break;
        if (dp_stopped(opt->stop)) { /* interrupted inside the pass: it is incomplete */
            film_drop_pass(f);
            break;
        }
        commit_iteration(s, p, f, st->passes, st);
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
