/* Inside the render module: one run of the render command (render_run), shared by run.c (the sequence),
 * run_prepare.c (everything before any work), checkpoint.c, summary.c, warnings.c and interrupt.c. */
#ifndef DARTSPP_RENDER_RUN_INTERNAL_H
#define DARTSPP_RENDER_RUN_INTERNAL_H

#include <pthread.h>

#include "dartspp/render.h"

#define SCENE_DIGEST_PARTS 5 /* scene_digest.c */

/* Several ranks, rank 0: the film of the last reduction that was written to the checkpoint state, kept in
 * memory with what the watchdog (watchdog.c) needs to write it when the job is stopped while the ranks are
 * exchanging (a rank lost: the collective never returns, and Open MPI kills the job 1 s after its SIGTERM). */
typedef struct {
    pthread_mutex_t lock;  /* held while the film is replaced, and by the watchdog while it writes */
    film f;                /* passes 0: no reduction kept yet */
    double seconds;        /* render seconds of that reduction */
    atomic_long exchanges; /* render_options.exchanges */
    const dp_stop_flag *stop;
    const char *out, *integrator, *plan_json, *state;
    int skip;
    double stuck_seconds;  /* how long in one collective call after an interrupt means stuck */
    atomic_int quit;       /* the render has returned: the watchdog must not fire */
    pthread_t thread;
    int running;
} survivors;

/* After every pass (render_options.after_pass): a row of the error log when one is due, and every `every`
 * seconds of rendering a checkpoint, the outputs of all completed passes written atomically (an
 * interrupted or killed render keeps the last complete set). */
typedef struct {
    const render_plan *p;
    const char *plan_json;
    const char *out;
    double every, last;  /* seconds between checkpoints (0: none), and when the last one was written */
    int quiet;
    int skip;            /* render_write_outputs */
    const char *state;   /* the checkpoint state to write with each checkpoint (resume.c); NULL: none */
    uint64_t seed;
    const uint64_t *digest; /* the scene's (scene_digest), written into the state */
    int state_written;   /* this run wrote the state at least once */
    error_log *log;      /* --log: error against --reference (may be NULL) */
    survivors *keep;     /* several ranks, rank 0: the state is written every state_every seconds of rendering
                          * (after a reduction holding iterations 0..passes−1) and its film kept here; else NULL */
    double state_every, last_state;
} checkpoints;

int checkpoint_after_pass(void *ctx, const film *f, const render_stats *st, dp_error *err);

/* What one run works on: the request, the scene, its plan, and where the images go. */
typedef struct {
    const render_request *rq;
    const render_cluster *cl; /* several ranks; NULL: this process alone */
    int rank;
    int quiet;                /* the request's --quiet; every rank but 0 is quiet */
    int prepared;             /* run_prepare succeeded: the scene and the plan are held */
    scene s;
    render_plan p;
    char plan_json[8192];
    uint64_t digest[SCENE_DIGEST_PARTS]; /* scene_digest(&s) */
    char out[OUTPUT_PATH_MAX];
    memory_estimate mem;
    double load_seconds;      /* scene_load: JSON, meshes, textures, Embree build */
    checkpoints cp;
    render_options ro;
    char state[OUTPUT_PATH_MAX + 16]; /* the checkpoint state beside the outputs (resume.c) */
    char lock[OUTPUT_PATH_MAX + 24];  /* "<state>.lock", held while this run may write the state (state_lock.c) */
    int lock_fd, locked;
    film resumed;             /* --resume: the checkpoint's film (sums, passes), handed to the render */
    survivors keep;           /* several ranks, rank 0 (watchdog.c) */
} render_run_job;

/* ---- the scene's digest (scene_digest.c): one FNV-1a 64 per part, kept in the checkpoint state ---- */
extern const char *const SCENE_DIGEST_NAMES[SCENE_DIGEST_PARTS]; /* geometry, materials, media, lights, camera */
void scene_digest(const scene *s, uint64_t part[SCENE_DIGEST_PARTS]);

/* ---- the checkpoint state (resume.c): "<stem>.state", the film's exact sums for --resume ---- */
typedef struct {
    uint64_t seed;
    int width, height, frames, orders; /* orders: bounce_orders' layers (time_window.orders) */
    int amcw;            /* the AMCW frequencies (time_window.amcw_count); 0 without, and in a state of version 4 */
    long passes, nonfinite;
    int resumable;       /* 0: not a prefix of iterations (resume_state_write) */
    double weight_sum, last_weight;
    uint64_t digest[SCENE_DIGEST_PARTS]; /* scene_digest of the scene it was rendered from */
    char *plan;          /* the plan's JSON */
    int deriv_count;     /* the derivative films (film.h: deriv), their pointers in order */
    char *deriv[DIFF_PARAM_MAX];
    double *sum;         /* (1 + deriv_count)·width·height·3: the image's, then each derivative film's (read with
                          * data only) */
    float *frame_sum;    /* (1 + deriv_count)·layers·width·height·3, layers as time_window_layers (read with data
                          * only) */
    double *amcw_sum;    /* amcw·width·height·6: the image's AMCW sums (film.h), read with data only; NULL without */
} resume_state;

/* "<stem>.state" of the output path <stem>.exr|.pfm. */
void resume_state_path(const char *out, char *path, size_t n);
/* The film's sums, pass count and weights with the plan, seed and scene digest, written atomically. resumable
 * 0: sums that are not iterations 0..passes−1 (several ranks, one dropped a pass), kept only so that the next
 * run does not replace their images silently; --resume refuses them. 0, or -1 with err. */
int resume_state_write(const char *path, const film *f, const char *plan_json, uint64_t seed, const uint64_t *digest,
                       int resumable, dp_error *err);
/* Checks the whole file against its checksum, then reads the header (and, with_data, the sums). 0, or -1 with
 * err (input). */
int resume_state_read(const char *path, int with_data, resume_state *s, dp_error *err);
void resume_state_free(resume_state *s);
/* Whether the state fits this run (seed, resolution, frames, the scene's digest, its derivative films' pointers
 * in order against --derivative, plan; not more passes than spp > 0). */
int resume_check(const resume_state *s, const char *path, const render_run_job *j, long spp, dp_error *err);
/* Without --resume: refuses (-1 with err) when the state at path holds more passes than spp (or any, when
 * spp <= 0: the run's pass count is unknown), or is damaged or of an older version (its passes unknown). */
int resume_overwrite_check(const char *path, long spp, dp_error *err);

/* ---- the state's lock (state_lock.c): "<stem>.state.lock", flock()ed while a run may write the state ---- */
/* Takes the lock at lock_path for the state at state_path, writing this process's id into it: 0 with *fd, or
 * -1 with err naming the other run (its process id) when one holds it. A lock left by a dead process does not
 * block (the kernel released its flock). */
int state_lock_take(const char *lock_path, const char *state_path, int *fd, dp_error *err);
/* Removes the lock file and releases the lock. */
void state_lock_release(const char *lock_path, int fd);

/* Everything that can refuse the render before any work (run_prepare.c): 0, or -1 with err of kind
 * DP_ERROR_INPUT whatever the cause (nothing has been rendered), the job holding nothing. */
int run_prepare(render_run_job *j, dp_error *err);
/* Frees what run_prepare took (the error log, the plan and the scene). */
void run_release(render_run_job *j);

/* ---- the last reduction kept, and the watchdog (watchdog.c; several ranks, rank 0) ---- */
/* Before the render: nothing kept; the outputs and state the report names; film_bytes, the size of the sums
 * a reduction moves, lengthens the time that counts as stuck (watchdog.c). */
void survivors_init(survivors *k, const dp_stop_flag *stop, const char *out, const char *integrator,
                    const char *plan_json, const char *state, int skip, double film_bytes);
/* Replaces the kept film by a copy of f (of `seconds`); a copy that cannot be allocated keeps the older one. */
void survivors_keep(survivors *k, const film *f, double seconds);
/* Starts the thread that, once the run is interrupted (SIGTERM from mpirun when a rank died) and the driver
 * has been stuck in the same collective call for k->stuck_seconds, writes the kept film's images, says so
 * (survivors_report) and exits with dp_exit_status(DP_ERROR_LOST). 0, or -1 (no watchdog: the checkpoint
 * state on disk still holds the last reduction). */
int watchdog_start(survivors *k);
/* The render has returned: the watchdog stops (waiting for it if it is writing, in which case it exits the
 * process). Safe when it was never started. */
void watchdog_stop(survivors *k);
/* Writes the kept film's images and says on stderr that a rank was lost and what was kept (or that nothing
 * was: no reduction yet). */
void survivors_report(survivors *k);
void survivors_free(survivors *k);

/* The run summary on stdout: scene, gate, passes and rates, the photon-pass samplers, statistics, memory
 * and the error log's overhead (summary.c). */
void run_print_summary(const render_run_job *j, const render_stats *st);

/* SIGINT and SIGTERM from here on (interrupt.c): the first one sets ro->stop once ro->passes_started is set
 * (the pass in progress is dropped, the completed passes are written), else the process exits at once. */
void interrupt_install(render_options *ro);
/* The final write of the completed passes begins (1) or ends (0): a second interrupt during it lets it finish. */
void interrupt_writing(int on);

#endif
