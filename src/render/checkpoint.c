/* After every pass of a run: the error log's row when one is due, and the checkpoints (the images, then the
 * checkpoint state for --resume). */
#include <stdio.h>
#include <unistd.h>

#include "run_internal.h"

int checkpoint_after_pass(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    checkpoints *c = ctx;
    if (error_log_pass(c->log, f, st, 0, err)) return -1;
    if (c->every <= 0 || st->seconds - c->last < c->every) return 0;
    c->last = st->seconds;
    dp_error werr;
    if (render_write_outputs(f, c->out, c->p->type_name, c->plan_json, c->skip, NULL, &werr)) {
        /* the render goes on: its end writes again, to a rescue folder if need be */
        fprintf(stderr, "%swarning: checkpoint not written: %s\n", isatty(2) ? "\r\033[K" : "", werr.msg);
        return 0;
    }
    /* the state after the images: it never holds passes that the images lack */
    if (c->state && resume_state_write(c->state, f, c->plan_json, c->seed, &werr))
        fprintf(stderr, "%swarning: checkpoint state not written: %s\n", isatty(2) ? "\r\033[K" : "", werr.msg);
    if (!c->quiet)
        fprintf(stderr, "%scheckpoint: %ld passes, %.1f s -> %s\n", isatty(2) ? "\r\033[K" : "", st->passes,
                st->seconds, c->out);
    return 0;
}
