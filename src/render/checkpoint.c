/* After every pass of a run (with several ranks: after every reduction, on rank 0): the error log's row when
 * one is due, the checkpoints (the images, then the checkpoint state for --resume) and, with several ranks,
 * the checkpoint state every state_every seconds, its film kept in memory for the watchdog (watchdog.c). */
#include <stdio.h>
#include <unistd.h>

#include "run_internal.h"

static const char *line_start(void) { return isatty(2) ? "\r\033[K" : ""; }

/* The images of the film so far; 1 if written. A failure is a warning: the render goes on, and its end
 * writes again, to a rescue folder if need be. */
static int write_images(checkpoints *c, const film *f)
{
    dp_error werr;
    if (!render_write_outputs(f, c->out, c->p->type_name, c->plan_json, c->skip, NULL, &werr)) return 1;
    fprintf(stderr, "%swarning: checkpoint not written: %s\n", line_start(), werr.msg);
    return 0;
}

static void write_state(checkpoints *c, const film *f)
{
    dp_error werr;
    if (resume_state_write(c->state, f, c->plan_json, c->seed, c->digest, 1, &werr))
        fprintf(stderr, "%swarning: checkpoint state not written: %s\n", line_start(), werr.msg);
    else c->state_written = 1;
}

/* Several ranks: the state after a reduction whose film holds iterations 0..passes−1 exactly (no rank
 * dropped a pass: a resume continues at iteration `passes`), when a checkpoint wrote the images or
 * state_every seconds have passed; the same film is kept for the watchdog. */
static void keep_reduction(checkpoints *c, const film *f, const render_stats *st, int images)
{
    if (st->dropped > 0 || f->passes == 0) return;
    if (!images && !(c->state_every > 0 && st->seconds - c->last_state >= c->state_every)) return;
    c->last_state = st->seconds;
    write_state(c, f);
    survivors_keep(c->keep, f, st->seconds);
}

int checkpoint_after_pass(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    checkpoints *c = ctx;
    if (error_log_pass(c->log, f, st, 0, err)) return -1;
    int due = c->every > 0 && st->seconds - c->last >= c->every, images = 0;
    if (due) {
        c->last = st->seconds;
        images = write_images(c, f);
    }
    if (c->keep) keep_reduction(c, f, st, images);
    if (!images) return 0;
    /* this process alone: the state after the images, so that it never holds passes that the images lack */
    if (!c->keep && c->state) write_state(c, f);
    if (!c->quiet)
        fprintf(stderr, "%scheckpoint: %ld passes, %.1f s -> %s\n", line_start(), st->passes, st->seconds, c->out);
    return 0;
}
