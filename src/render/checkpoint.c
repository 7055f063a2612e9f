/* After every pass of a run: the error log's row when one is due, and the checkpoints. */
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
    if (!c->quiet)
        fprintf(stderr, "%scheckpoint: %ld passes, %.1f s -> %s\n", isatty(2) ? "\r\033[K" : "", st->passes,
                st->seconds, c->out);
    return 0;
}
