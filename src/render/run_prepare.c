/* Before any work of a run: the scene loaded, its plan resolved, the outputs checked, the memory guard passed
 * and the error log's reference read. Any of them can refuse the render, and a refusal is bad input whatever
 * its cause (exit 2): nothing has been rendered yet. */
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "run_internal.h"

static int refuse(dp_error *err)
{
    err->kind = DP_ERROR_INPUT;
    return -1;
}

/* --output (relative to the working folder); else the scene's hdr_output_file, else <scene stem>.exr, in a
 * folder named after the scene's stem in the working folder (an absolute hdr_output_file as it is): a render
 * without --output writes its image, preview, frames, cube and viewer into one folder of its own instead of
 * dropping them among the user's files (docs/cli.md §3.1). */
static void output_path(const render_request *rq, const scene *s, char *out, size_t n)
{
    const char *base = strrchr(rq->scene_path, '/');
    base = base ? base + 1 : rq->scene_path;
    const char *dot = strrchr(base, '.');
    int stem = (int)(dot && dot > base ? dot - base : (long)strlen(base));
    /* a scene file without an extension is named like the folder would be: the folder gets "-out" */
    const char *tag = dot && dot > base ? "" : "-out";
    if (rq->output) snprintf(out, n, "%s", rq->output);
    else if (s->renderer.hdr_output_file[0] == '/') snprintf(out, n, "%s", s->renderer.hdr_output_file);
    else if (s->renderer.hdr_output_file[0]) snprintf(out, n, "%.*s%s/%s", stem, base, tag, s->renderer.hdr_output_file);
    else snprintf(out, n, "%.*s%s/%.*s.exr", stem, base, tag, stem, base);
}

static int load_scene(render_run_job *j, dp_error *err)
{
    const render_request *rq = j->rq;
    scene_load_options lo = {.sets = rq->sets, .set_count = rq->set_count, .verbose = rq->verbose,
                            .derivatives = rq->derivatives, .derivative_count = rq->derivative_count};
    double t0 = dp_seconds();
    if (scene_load(rq->scene_path, &lo, &j->s, err)) return -1;
    j->load_seconds = dp_seconds() - t0;
    scene_digest(&j->s, j->digest);
    return 0;
}

static int resolve_plan(render_run_job *j, dp_error *err)
{
    if (plan_resolve(&j->s, &j->p, err)) return -1;
    if (plan_json(&j->p, &j->s, j->plan_json, sizeof j->plan_json))
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: plan too long", j->s.path);
    return 0;
}

/* Rank 0 writes the outputs, so rank 0 checks where they go: over no input, then room and rights. */
static int check_outputs(render_run_job *j, dp_error *err)
{
    if (j->rank != 0) return 0;
    if (render_outputs_refuse_inputs(j->out, &j->s, &j->p, j->rq, err)) return -1;
    return render_outputs_check(j->out, j->s.cam.width, j->s.cam.height, j->p.window.frame_count, j->s.diff_count,
                                j->rq->skip, err);
}

/* The memory guard; every rank on this machine needs as much. */
static int check_memory(render_run_job *j, dp_error *err)
{
    const render_request *rq = j->rq;
    return render_memory_check(&j->s, &j->p, rq->reference != NULL, rq->max_memory, j->cl ? j->cl->ranks_on_node : 1,
                               &j->mem, err);
}

/* Checkpoints are rank 0's, every --checkpoint seconds, else as the scene says. */
static void set_up_checkpoints(render_run_job *j)
{
    const render_request *rq = j->rq;
    j->cp = (checkpoints){.p = &j->p, .plan_json = j->plan_json, .out = j->out, .quiet = j->quiet, .skip = rq->skip,
                          .every = j->rank != 0 ? 0 : rq->checkpoint >= 0 ? rq->checkpoint : j->p.checkpoint_interval};
}

/* --resume: the images at the output must not hold more passes than the state (a run that wrote its images
 * but not its state: a full disk, a rescue folder, a render without checkpoints after the checkpointed one);
 * resuming would render over them from fewer passes. EXR images record their passes; other formats only their
 * time, and an image written after the state is then said aloud. Refused unless --overwrite. */
static int images_not_newer(const render_run_job *j, long state_passes, dp_error *err)
{
    struct stat img, st;
    if (stat(j->out, &img) != 0 || stat(j->state, &st) != 0) return 0;
    int passes = 0;
    dp_error ignored;
    const char *dot = strrchr(j->out, '.');
    int exr = dot && !strcasecmp(dot, ".exr") && !exr_read_int_attribute(j->out, "dartspp.passes", &passes, &ignored);
    if (exr && passes <= state_passes) return 0;
    if (exr && !j->rq->overwrite)
        return dp_fail(err, "%s holds %d passes but its checkpoint state %s only %ld (the state was not written "
                       "with the images): --resume would render over them from the older passes; --resume "
                       "--overwrite does so, or move the images away", j->out, passes, j->state, state_passes);
    int newer = img.st_mtim.tv_sec > st.st_mtim.tv_sec ||
                (img.st_mtim.tv_sec == st.st_mtim.tv_sec && img.st_mtim.tv_nsec > st.st_mtim.tv_nsec);
    /* a warning even with --quiet: the images are about to be replaced */
    if (exr)
        fprintf(stderr, "warning: %s holds %d passes, its checkpoint state %s only %ld: --overwrite: resuming from "
                "the state's passes and replacing the images\n", j->out, passes, j->state, state_passes);
    else if (newer)
        fprintf(stderr, "warning: %s was written after its checkpoint state %s (its format does not record its "
                "passes): they may not hold the same passes; resuming from the state's %ld passes and replacing "
                "the images\n", j->out, j->state, state_passes);
    return 0;
}

/* Film k's sums (k 0: the image's, then each derivative film's) of a state read with its data into f. */
static void state_sums_into(film *f, const resume_state *st, size_t k)
{
    size_t n = (size_t)st->width * st->height * 3, nf = n * (size_t)time_window_layers(&f->window);
    memcpy(f->sum, st->sum + k * n, n * sizeof(double));
    if (nf > 0) memcpy(f->frame_sum, st->frame_sum + k * nf, nf * sizeof(float));
    f->passes = st->passes;
    f->weight_sum = st->weight_sum;
    f->last_weight = st->last_weight;
}

/* The state (resume_check passed: its derivative films are this run's, in order) as j->resumed, the
 * derivative films labelled with the scene's pointers. 0, or -1 with err. */
static int resumed_film(render_run_job *j, const resume_state *st, dp_error *err)
{
    const char *labels[DIFF_PARAM_MAX];
    for (int k = 0; k < j->s.diff_count; k++) labels[k] = j->s.diffs[k].pointer;
    if (film_init(&j->resumed, st->width, st->height, &j->p.window, err)) return -1;
    if (film_init_derivs(&j->resumed, j->s.diff_count, labels, err)) {
        film_free(&j->resumed);
        return -1;
    }
    state_sums_into(&j->resumed, st, 0);
    if (st->amcw_sum && j->resumed.amcw_sum && st->amcw == j->resumed.window.amcw_count)
        memcpy(j->resumed.amcw_sum, st->amcw_sum, (size_t)st->width * st->height * 6 * st->amcw * sizeof(double));
    for (int k = 0; k < j->resumed.deriv_count; k++) state_sums_into(&j->resumed.deriv[k], st, 1 + (size_t)k);
    j->resumed.nonfinite = st->nonfinite;
    return 0;
}

/* The checkpoint state beside the outputs (resume.c), rank 0's: with --resume it is loaded into j->resumed and
 * must fit this run; without, a state holding more passes than this run renders is not overwritten unless
 * --overwrite. This process alone writes it at checkpoints and, with checkpoints or --resume, at the end;
 * several ranks always keep it (after the periodic reductions, --reduce-every, and at the end), so that a
 * lost rank costs only the passes since the last reduction. */
static int set_up_state(render_run_job *j, dp_error *err)
{
    const render_request *rq = j->rq;
    if (j->rank != 0) return 0;
    resume_state_path(j->out, j->state, sizeof j->state);
    if (j->cl || j->cp.every > 0 || rq->resume) { /* --resume alone: the final write updates it */
        j->cp.state = j->state;
        j->cp.seed = rq->seed;
        j->cp.digest = j->digest;
    }
    /* Every render to an output holds its lock, whether it writes the state or not: before the state is read
     * (the run holding it may be about to replace it), and so that two runs to one output cannot replace each
     * other's images (tests/campaign-48/state.md, probe 23). */
    snprintf(j->lock, sizeof j->lock, "%s.lock", j->state);
    if (state_lock_take(j->lock, j->state, &j->lock_fd, err)) return -1;
    j->locked = 1;
    long spp = rq->spp >= 0 ? rq->spp : j->p.spp;
    if (!rq->resume) return rq->overwrite ? 0 : resume_overwrite_check(j->state, spp, err);
    resume_state st;
    if (access(j->state, F_OK) != 0)
        return dp_fail(err, "--resume: %s: no checkpoint state to resume (renders with --checkpoint write one)",
                       j->state);
    /* the header first: a state of another size is refused before its sums are read */
    if (resume_state_read(j->state, 0, &st, err)) return -1;
    int rc = resume_check(&st, j->state, j, spp, err);
    resume_state_free(&st);
    if (rc || resume_state_read(j->state, 1, &st, err)) return -1;
    rc = resume_check(&st, j->state, j, spp, err); /* the same file, unless replaced in between */
    if (!rc) rc = images_not_newer(j, st.passes, err);
    if (!rc) rc = resumed_film(j, &st, err);
    if (!rc && !j->quiet)
        fprintf(stderr, "resuming %s: %ld passes%s\n", j->state, st.passes,
                st.deriv_count ? " (and their derivative images)" : "");
    resume_state_free(&st);
    return rc;
}

/* The error log is rank 0's; its reference is read here, before any rank renders. */
static int open_error_log(render_run_job *j, dp_error *err)
{
    const render_request *rq = j->rq;
    if (j->rank != 0 || !rq->log) return 0;
    j->cp.log = error_log_open(rq->log, rq->reference, j->s.cam.width, j->s.cam.height, j->p.window.frame_count,
                               rq->log_every, err);
    return j->cp.log ? 0 : -1;
}

int run_prepare(render_run_job *j, dp_error *err)
{
    if (load_scene(j, err)) return refuse(err);
    int rc = resolve_plan(j, err);
    output_path(j->rq, &j->s, j->out, sizeof j->out);
    if (!rc) rc = check_outputs(j, err) || check_memory(j, err);
    if (!rc) {
        set_up_checkpoints(j);
        rc = set_up_state(j, err) || open_error_log(j, err);
    }
    if (rc) {
        if (j->locked) state_lock_release(j->lock, j->lock_fd);
        j->locked = 0;
        film_free(&j->resumed);
        plan_free(&j->p);
        scene_free(&j->s);
        return refuse(err);
    }
    j->prepared = 1;
    return 0;
}

void run_release(render_run_job *j)
{
    if (!j->prepared) return;
    error_log_close(j->cp.log);
    if (j->locked) state_lock_release(j->lock, j->lock_fd);
    j->locked = 0;
    film_free(&j->resumed);
    plan_free(&j->p);
    scene_free(&j->s);
    j->prepared = 0;
}
