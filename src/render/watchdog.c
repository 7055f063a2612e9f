/* Several ranks, rank 0: what survives a lost rank. When a rank dies, Open MPI sends SIGTERM to every other
 * rank and SIGKILL 1 s later (odls_base_sigkill_timeout); the ranks waiting in a collective for the dead one
 * never return from it, so the end of the render (the final reduction and write) never comes. Two things
 * keep the work: the checkpoint state written after the periodic reductions (checkpoint.c; on disk, the
 * guarantee), and this watchdog, a thread that writes the images of the last kept reduction when the run was
 * interrupted and the driver has been stuck in the same collective call for a while (the other ranks,
 * interrupted at the same moment, drop their passes within a batch of light paths or a row of pixels and
 * reach the collective well before that when they are alive). The thread calls no MPI. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "run_internal.h"

/* Stuck: 0.3 s in one collective call after the interrupt, leaving 0.7 s of Open MPI's 1-s grace time for
 * the images; plus the time a reduction of the film may legitimately take at 100 MB/s (1 Gbit Ethernet),
 * so that a large film being summed after Ctrl-C is not mistaken for a lost rank (it needs a longer grace
 * time then anyway: --mca odls_base_sigkill_timeout). */
#define STUCK_SECONDS 0.3
#define SLOWEST_LINK 1e8

void survivors_init(survivors *k, const dp_stop_flag *stop, const char *out, const char *integrator,
                    const char *plan_json, const char *state, int skip, double film_bytes)
{
    k->stuck_seconds = STUCK_SECONDS + film_bytes / SLOWEST_LINK;
    memset(&k->f, 0, sizeof k->f);
    pthread_mutex_init(&k->lock, NULL);
    atomic_init(&k->exchanges, 0);
    atomic_init(&k->quit, 0);
    k->stop = stop;
    k->out = out;
    k->integrator = integrator;
    k->plan_json = plan_json;
    k->state = state;
    k->skip = skip;
    k->seconds = 0.0;
    k->running = 0;
}

void survivors_keep(survivors *k, const film *f, double seconds)
{
    film copy;
    dp_error err;
    if (film_copy(&copy, f, &err)) return;
    pthread_mutex_lock(&k->lock);
    film_free(&k->f);
    k->f = copy;
    k->seconds = seconds;
    pthread_mutex_unlock(&k->lock);
}

void survivors_report(survivors *k)
{
    const char *what = "dartspp-mpi: a rank was lost (or the job was stopped) while the ranks were exchanging";
    if (k->f.passes == 0) {
        fprintf(stderr, "%s, before the first reduction: nothing was kept (--reduce-every sets how often the ranks' "
                "films are summed and kept in %s)\n", what, k->state);
        return;
    }
    dp_error err;
    if (render_write_outputs(&k->f, k->out, k->integrator, k->plan_json, k->skip, NULL, &err))
        fprintf(stderr, "%s; the images of the last reduction could not be written (%s); its %ld passes at %.1f s "
                "are in %s: continue with --resume\n", what, err.msg, k->f.passes, k->seconds, k->state);
    else
        fprintf(stderr, "%s; wrote the %ld passes of the last reduction at %.1f s to %s (and %s); continue with "
                "--resume\n", what, k->f.passes, k->seconds, k->out, k->state);
}

/* Stuck: interrupted, and inside the same collective call for k->stuck_seconds since both began. */
static void *watch(void *arg)
{
    survivors *k = arg;
    long seen = -1;
    double since = 0.0, stopped_at = -1.0;
    while (!atomic_load(&k->quit)) {
        usleep(20000); /* a 50 Hz look: 20 ms of the 1-s grace time at most */
        long e = atomic_load(&k->exchanges);
        double now = dp_seconds();
        if (dp_stopped(k->stop) && stopped_at < 0) stopped_at = now;
        if (e != seen) {
            seen = e;
            since = now;
        }
        if (stopped_at < 0 || !(e & 1) || now - (since > stopped_at ? since : stopped_at) < k->stuck_seconds)
            continue;
        pthread_mutex_lock(&k->lock); /* the film is not being replaced, and the render has not returned */
        if (atomic_load(&k->quit)) {
            pthread_mutex_unlock(&k->lock);
            return NULL;
        }
        survivors_report(k);
        _exit(dp_exit_status(DP_ERROR_LOST));
    }
    return NULL;
}

int watchdog_start(survivors *k)
{
    if (pthread_create(&k->thread, NULL, watch, k)) return -1;
    k->running = 1;
    return 0;
}

void watchdog_stop(survivors *k)
{
    if (!k->running) return;
    pthread_mutex_lock(&k->lock);
    atomic_store(&k->quit, 1);
    pthread_mutex_unlock(&k->lock);
    pthread_join(k->thread, NULL);
    k->running = 0;
}

void survivors_free(survivors *k)
{
    film_free(&k->f);
    pthread_mutex_destroy(&k->lock);
}
