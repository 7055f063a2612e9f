/* Interrupts of a run: the first SIGINT/SIGTERM/SIGHUP (a closed terminal or ssh session) stops the pass in
 * progress within a batch or a row, and the completed passes are written. Before the first pass (loading,
 * EDA tables) there is nothing to keep, and a second signal means "now": both exit at once, removing the
 * temporary files of a write in progress. SIGXFSZ (a file-size limit, `ulimit -f`) is ignored: the write
 * that crosses the limit fails with EFBIG and goes the way of every failed write (the rescue folder). */
#include <signal.h>
#include <string.h>
#include <unistd.h>

#include "run_internal.h"

static dp_stop_flag stop_requested = 0; /* set by the signal handler, read by the passes */
static dp_stop_flag passes_started = 0; /* set by the driver: from then on an interrupt keeps the passes done */

static void say(const char *msg) { (void)!write(2, msg, strlen(msg)); }

/* Only async-signal-safe calls here. */
static void on_signal(int sig)
{
    (void)sig;
    if (!passes_started || stop_requested) {
        atomic_cleanup_on_signal();
        say("\ndartspp render: interrupted, exiting now\n");
        _exit(dp_exit_status(DP_ERROR_INTERRUPTED));
    }
    stop_requested = 1;
    say("\ndartspp render: interrupted: stopping the pass in progress and writing the completed passes "
        "(interrupt again to exit at once)\n");
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
