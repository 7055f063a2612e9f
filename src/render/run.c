/* One run of the render command (render_run): everything that can refuse it before any work
 * (run_prepare.c), the ranks' agreement to start, the progressive render (render.c) with checkpoints and
 * error-log rows (checkpoint.c), the run summary (summary.c) and the outputs, written to a rescue folder when
 * the final write fails. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "run_internal.h"


static void say_error(const dp_error *err, const char *where)
{
    fprintf(stderr, "dartspp render: %s%s\n", err->msg, where);
}

static void print_written(const char *path) { printf("wrote %s\n", path); }

static void start(render_run_job *j, const render_request *rq, const render_cluster *cluster)
{
    memset(j, 0, sizeof *j);
    j->rq = rq;
    j->cl = cluster && cluster->size > 1 ? cluster : NULL;
    j->rank = j->cl ? j->cl->rank : 0;
    j->quiet = rq->quiet || j->rank != 0; /* rank 0 speaks for the job */
    j->ro = (render_options){.threads = rq->threads, .seed = rq->seed, .spp = rq->spp, .time_limit = rq->time_limit,
                             .messages = stderr};
    /* Interrupts count from here: while loading, an interrupt exits at once (nothing to keep yet). */
    interrupt_install(&j->ro);
}

/* Rank 0's seed, pass count, time budget and resumed passes on every rank: the ranks render one job whatever
 * their own command lines say (the seed as two 32-bit halves, exact in doubles), and the rounds of a resumed
 * render start at the state's pass count. */
static int share_options(const render_cluster *c, render_options *ro, long resumed)
{
    double v[5] = {(double)(ro->seed >> 32), (double)(ro->seed & 0xffffffffu), (double)ro->spp, ro->time_limit,
                   (double)resumed};
    if (c->share(c, v, 5)) return -1;
    ro->seed = ((uint64_t)v[0] << 32) | (uint64_t)v[1];
    ro->spp = (long)v[2];
    ro->time_limit = v[3];
    ro->resume_passes = (long)v[4];
    return 0;
}

/* Every rank is ready, or none renders: the ranks agree on the largest exit status so far (`status`, this
 * rank's). Then rank 0's options on every rank and, without --threads, each rank's share of its machine's
 * cores. Returns the job's exit status so far. */
static int agree_to_start(render_run_job *j, int status)
{
    const render_cluster *cl = j->cl;
    int all = cl->agree_rc(cl, status);
    if (all && !status && j->rank == 0)
        fprintf(stderr, "dartspp render: another rank could not start the render (its message is above)\n");
    if (all) return all;
    if (share_options(cl, &j->ro, j->resumed.passes)) return dp_exit_status(DP_ERROR_INTERNAL); /* MPI reports its own failures */
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    if (j->ro.threads == 0 && cores > 0)
        j->ro.threads = cores / cl->ranks_on_node > 0 ? (int)(cores / cl->ranks_on_node) : 1;
    return 0;
}

int render_run_refused(const render_cluster *cluster, int status)
{
    return cluster && cluster->size > 1 ? cluster->agree_rc(cluster, status) : status;
}

/* A budget that means "forever" is said aloud, with how to stop it: a negative scene timeout (the format's
 * "-1", no limit) in use, or neither a pass nor a time limit. */
static void warn_unbounded(const render_run_job *j)
{
    long spp = j->ro.spp >= 0 ? j->ro.spp : j->p.spp;
    double limit = j->ro.time_limit >= 0 ? j->ro.time_limit : j->p.timeout;
    const char *stop = "it runs until Ctrl-C (or SIGTERM), which writes the completed passes";
    if (limit > 0 && spp > 0) return;
    if (j->ro.time_limit < 0 && j->s.renderer.timeout_negative[0] && spp > 0)
        fprintf(stderr, "warning: %s: renderer.timeout \"%s\" is negative, which means no time limit: the render runs "
                "until its %ld passes (spp) are done, or until Ctrl-C\n", j->s.path, j->s.renderer.timeout_negative, spp);
    else if (j->ro.time_limit < 0 && j->s.renderer.timeout_negative[0] && spp == 0)
        fprintf(stderr, "warning: %s: renderer.timeout \"%s\" is negative, which means no time limit, and spp is 0 (no "
                "pass limit): nothing bounds this render; %s (--time S or --spp N bound it)\n", j->s.path,
                j->s.renderer.timeout_negative, stop);
    else if (limit == 0 && spp == 0)
        fprintf(stderr, "warning: %s: no time limit and no pass limit (%s): nothing bounds this render; %s\n", j->s.path,
                j->ro.spp == 0 ? "--spp 0 --time 0" : "spp 0 and no timeout in the scene", stop);
}

/* Rank 0, before the render: the scene's notes, the plan (--verbose), the warnings and the cluster. */
static void announce(const render_run_job *j)
{
    if (j->rank != 0) return;
    if (j->s.notes) fputs(j->s.notes, stderr);
    if (j->rq->verbose) fprintf(stderr, "plan: %s\n", j->plan_json);
    render_warn(stderr, &j->s, &j->p);
    warn_unbounded(j);
    if (j->cl && !j->quiet)
        fprintf(stderr, "cluster: %d ranks (%d on this machine, %d threads each); iteration i runs on rank i mod %d\n",
                j->cl->size, j->cl->ranks_on_node, j->ro.threads, j->cl->size);
}

static void set_up_render(render_run_job *j)
{
    render_options *ro = &j->ro;
    ro->plan = &j->p;
    ro->progress = !j->quiet;
    ro->after_pass = checkpoint_after_pass;
    ro->after_pass_ctx = &j->cp;
    ro->cluster = j->cl;
    ro->resume = j->resumed.sum ? &j->resumed : NULL;
    /* with several ranks the films are summed for checkpoints and log rows only when one is due */
    double log_every = j->rq->log_every, reduce_every = j->rq->reduce_every;
    ro->gather_every = j->cp.every > 0 ? j->cp.every : 0.0;
    if (j->cp.log && (ro->gather_every == 0.0 || log_every < ro->gather_every))
        ro->gather_every = log_every > 0 ? log_every : 1e-9;
    if (!j->cl) return;
    /* and every reduce_every seconds for the checkpoint state, kept in memory too for the watchdog */
    if (reduce_every > 0 && (ro->gather_every == 0.0 || reduce_every < ro->gather_every))
        ro->gather_every = reduce_every;
    if (j->rank != 0) return;
    double pixels = (double)j->s.cam.width * j->s.cam.height;
    survivors_init(&j->keep, ro->stop, j->out, j->p.type_name, j->plan_json, j->state, j->rq->skip,
                   (1 + j->s.diff_count) * pixels * 3 * (sizeof(double) + time_window_layers(&j->p.window) * sizeof(float)));
    j->cp.keep = &j->keep;
    j->cp.state_every = reduce_every;
    ro->exchanges = &j->keep.exchanges;
    if (watchdog_start(&j->keep))
        fprintf(stderr, "warning: no watchdog thread: if a rank is lost, the last reduction is only in %s\n", j->state);
}

/* The ground truth images beside the output (renderer key ground_truth). */
static int write_ground_truth(const render_run_job *j, dp_error *err)
{
    ground_truth gt;
    if (ground_truth_compute(&j->s, &j->p, &gt, err)) return -1;
    int rc = ground_truth_write(&gt, j->out, print_written, err);
    ground_truth_free(&gt);
    return rc;
}

/* Whether the film may be written as the checkpoint state: this process alone, or several ranks none of which
 * dropped a pass (only then are the sums iterations 0..passes−1, which a resume needs). */
static int resumable(const film *f, long dropped)
{
    return f->passes > 0 && dropped == 0;
}

/* What the state beside the outputs holds after a final write of the state that did not happen there. */
static const char *state_on_disk(const render_run_job *j)
{
    if (access(j->state, F_OK) != 0) return "does not exist";
    return j->cp.state_written || j->resumed.passes > 0 ? "holds fewer passes (an earlier write)"
                                                        : "is that of an earlier render";
}

/* The final write failed and the images went to the rescue folder: the state goes with them (the one beside
 * the outputs holds only the last checkpoint's passes, if any), and the message says what is where. */
static void rescue_state(const render_run_job *j, const film *f, const char *rescue)
{
    const char *base = strrchr(j->state, '/');
    char path[2 * OUTPUT_PATH_MAX + 64], image[2 * OUTPUT_PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", rescue, base ? base + 1 : j->state);
    const char *ibase = strrchr(j->out, '/');
    snprintf(image, sizeof image, "%s/%s", rescue, ibase ? ibase + 1 : j->out);
    dp_error err;
    const char *old = state_on_disk(j);
    if (resume_state_write(path, f, j->plan_json, j->cp.seed, j->digest, 1, &err))
        fprintf(stderr, "dartspp render: the images of the %ld completed passes were written to %s instead, but not "
                "their checkpoint state (%s): they cannot be resumed; %s %s\n", f->passes, rescue, err.msg, j->state,
                old);
    else
        fprintf(stderr, "dartspp render: the images of the %ld completed passes and their checkpoint state were "
                "written to %s instead (%s %s): continue with --resume --output %s\n", f->passes, rescue, j->state,
                old, image);
}

/* The completed passes to the output, or to a rescue folder when that fails: finished work is never thrown
 * away. 0, or -1 with err (the write that failed) when the images had to go elsewhere, or nowhere. */
static int write_outputs(const render_run_job *j, const film *f, long dropped, dp_error *err)
{
    const char *integrator = j->p.type_name;
    int skip = j->rq->skip;
    if (!render_write_outputs(f, j->out, integrator, j->plan_json, skip, print_written, err))
        return j->s.renderer.ground_truth ? write_ground_truth(j, err) : 0;
    say_error(err, "");
    char rescue[OUTPUT_PATH_MAX];
    dp_error rescue_err = *err;
    if (render_write_rescue(f, j->out, integrator, j->plan_json, skip, print_written, rescue, sizeof rescue, &rescue_err))
        fprintf(stderr, "dartspp render: no rescue folder took the images either (%s): they are lost\n", rescue_err.msg);
    else if (j->cp.state && resumable(f, dropped))
        rescue_state(j, f, rescue);
    else
        fprintf(stderr, "dartspp render: the images of the %ld completed passes were written to %s instead\n",
                f->passes, rescue);
    return -1;
}

/* Several ranks, after a render in which a rank dropped a pass: the images were written, but the final film
 * is not a prefix of iterations and cannot be the state. What the state on disk holds, truly. */
static void say_kept_state(const render_run_job *j, const film *f)
{
    if (j->cp.state_written)
        fprintf(stderr, "dartspp render: %s keeps the last reduction in which every rank had finished its passes "
                "(fewer than the %ld passes of the images): --resume continues from it\n", j->cp.state, f->passes);
    else if (j->resumed.passes > 0)
        fprintf(stderr, "dartspp render: %s still holds the %ld passes this run resumed from (no reduction of this "
                "run had every rank's passes; the images hold %ld)\n", j->cp.state, j->resumed.passes, f->passes);
    else {
        /* a state that cannot be resumed, so that the next run does not replace the images without a word */
        dp_error err;
        int kept = !resume_state_write(j->cp.state, f, j->plan_json, j->cp.seed, j->digest, 0, &err);
        fprintf(stderr, "dartspp render: no reduction had every rank's passes (--reduce-every sets how often they "
                "are taken): the images hold %ld passes that cannot be resumed%s\n", f->passes,
                kept ? "; a new run to the same output refuses to replace them without --overwrite" : "");
    }
}

/* Several ranks, a collective call failed (an MPI that reports a lost rank instead of ending the job): the
 * films can no longer be summed, so rank 0 writes the last reduction kept and every rank exits with status 4. */
static int lost_rank(render_run_job *j, film *f, const dp_error *err)
{
    say_error(err, j->rank ? " (a rank other than 0)" : "");
    if (j->rank == 0) survivors_report(&j->keep);
    film_free(f);
    return dp_exit_status(DP_ERROR_LOST);
}

/* The render, the error log's last row, the summary and the outputs. Returns
 * the exit status: the first error's (the render's, the error log's, the final write's), else that of an
 * interrupt, else 0. */
static int render_and_write(render_run_job *j)
{
    film f;
    render_stats st;
    dp_error err, werr;
    int failed = render_scene(&j->s, &j->ro, &f, &st, &err) != 0;
    watchdog_stop(&j->keep);
    if (failed && err.kind == DP_ERROR_LOST) return lost_rank(j, &f, &err);
    if (failed) {
        /* a rank stopped by another rank's error leaves the telling to that rank and to rank 0 */
        if (j->rank == 0 || err.kind != DP_ERROR_RANK) say_error(&err, j->rank ? " (a rank other than 0)" : "");
    } else if (j->cp.log && error_log_pass(j->cp.log, &f, &st, 1, &err)) {
        say_error(&err, "");
        failed = 1;
    }
    if (j->rank == 0 && (st.nonfinite_pixels = film_nonfinite_pixels(&f)) > 0)
        fprintf(stderr, "warning: %s: %ld pixels of the images are NaN or beyond the float range; they are written "
                "as 0, so the image is wrong there\n", j->s.path, st.nonfinite_pixels);
    if (j->rank == 0 && f.passes > 0 && f.window.amcw_count > 0) {
        film_amcw_depth(&f, NULL, &st.amcw_dark_pixels);
        if (st.amcw_dark_pixels > 0)
            fprintf(stderr, "warning: %s: %ld of %ld pixels have no AMCW signal (renderer.amcw_frequencies): the AMCW "
                    "depth image holds 0 there\n", j->s.path, st.amcw_dark_pixels, (long)f.width * f.height);
    }
    if (!failed && j->rank == 0) run_print_summary(j, &st);
    if (j->rank != 0) {
        /* nothing to write here: rank 0 holds the summed film */
    } else if (f.passes > 0) {
        interrupt_writing(1);
        if (write_outputs(j, &f, st.dropped, &werr)) {
            if (!failed) {
                err = werr;
                failed = 1;
            }
        } else if (j->cp.state && st.dropped > 0) {
            /* several ranks, some of which dropped a pass: not iterations 0..N−1, which a resume needs */
            say_kept_state(j, &f);
        } else if (j->cp.state && resume_state_write(j->cp.state, &f, j->plan_json, j->cp.seed, j->digest, 1, &werr)) {
            say_error(&werr, "");
            fprintf(stderr, "dartspp render: the images of the %ld passes were written, but not their checkpoint "
                    "state: %s %s (--resume from it is refused while an EXR image holds more passes, warned about for other "
                    "formats)\n", f.passes,
                    j->cp.state, state_on_disk(j));
            if (!failed) {
                err = werr;
                failed = 1;
            }
        }
        interrupt_writing(0);
    } else if (st.interrupted)
        fprintf(stderr, "dartspp render: interrupted before the first pass completed: nothing written\n");
    film_free(&f);
    if (failed) return dp_exit_status(err.kind);
    return st.interrupted ? dp_exit_status(DP_ERROR_INTERRUPTED) : 0;
}

int render_run(const render_request *rq, const render_cluster *cluster)
{
    render_run_job *j = calloc(1, sizeof *j); /* large (the plan's JSON, paths): not on the stack */
    if (!j) {
        fprintf(stderr, "dartspp render: out of memory\n");
        return render_run_refused(cluster, dp_exit_status(DP_ERROR_MEMORY));
    }
    start(j, rq, cluster);
    dp_error err;
    int status = 0;
    if (run_prepare(j, &err)) {
        say_error(&err, "");
        status = dp_exit_status(err.kind);
    }
    if (j->cl) status = agree_to_start(j, status);
    if (!status) {
        announce(j);
        set_up_render(j);
        status = render_and_write(j);
    }
    if (j->cp.keep) survivors_free(&j->keep);
    run_release(j);
    free(j);
    return status;
}
