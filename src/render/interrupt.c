/* Interrupts of a run: the first SIGINT/SIGTERM/SIGHUP (a closed terminal or ssh session) stops the pass in
 * progress within a batch or a row, and the completed passes are written. Before the first pass (loading,
 * EDA tables) there is nothing to keep, and a second signal means "now": both exit at once, removing the
 * temporary files of a write in progress. A second signal while the completed passes are being written (the
 * final write: images, then the state) is the impatient user of a slow write, not a wish to lose the passes:
 * the write finishes (it is atomic, file by file or as a frame set, so stopping it keeps nothing new), and only
 * a third signal exits at once, saying what that loses. SIGXFSZ (a file-size limit, `ulimit -f`) is ignored: the write
 * that crosses the limit fails with EFBIG and goes the way of every failed write (the rescue folder). */
#include <signal.h>
#include <string.h>
#include <unistd.h>

#include "run_internal.h"

static dp_stop_flag stop_requested = 0; /* set by the signal handler, read by the passes */
static dp_stop_flag passes_started = 0; /* set by the driver: from then on an interrupt keeps the passes done */
static volatile sig_atomic_t writing = 0;  /* the final write is in progress (interrupt_writing) */
static volatile sig_atomic_t deferred = 0; /* a second signal came during it and was put off */

static void say(const char *msg) { (void)!write(2, msg, strlen(msg)); }

/* Only async-signal-safe calls here. */
static void on_signal(int sig)
{
    (void)sig;
    if (stop_requested && writing && !deferred) {
        deferred = 1;
        say("\ndartspp render: interrupted again while writing the completed passes: the write finishes first "
            "(interrupt once more to exit at once, losing the file being written)\n");
        return;
    }
    if (!passes_started || stop_requested) {
        atomic_cleanup_on_signal();
        if (writing)
            say("\ndartspp render: interrupted, exiting now: the file being written (or the whole frame set) is "
                "removed; the files written before it stay\n");
        else if (passes_started)
            say("\ndartspp render: interrupted again, exiting now: the completed passes are not written (the last "
                "checkpoint, if any, stays)\n");
        else
            say("\ndartspp render: interrupted, exiting now\n");
        _exit(dp_exit_status(DP_ERROR_INTERRUPTED));
    }
    stop_requested = 1;
    say("\ndartspp render: interrupted: stopping the pass in progress and writing the completed passes "
        "(interrupt again to exit at once; once the write has begun, it finishes first)\n");
}

void interrupt_install(render_options *ro)
{
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGHUP, on_signal);
    signal(SIGXFSZ, SIG_IGN);
    ro->stop = &stop_requested;
    ro->passes_started = &passes_started;
}

void interrupt_writing(int on) { writing = on ? 1 : 0; }
