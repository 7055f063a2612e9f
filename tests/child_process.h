/* Fixtures for tests that run the real `dartspp` in the background and signal, limit or time it (test_cli.c,
 * test_signals.c), defined in tests/child_process.c and linked into every test program. */
#ifndef DARTSPP_TEST_CHILD_PROCESS_H
#define DARTSPP_TEST_CHILD_PROCESS_H

#include "test_util.h"

#include <sys/types.h>

/* The release programs the MPI tests run (test_mpi.c, test_mpi_faults.c): the same objects in both, so the
 * same arithmetic; mpirun as root in a container: no ssh for one machine, more ranks than cores allowed. */
#define MPI_BIN "build/dartspp-mpi"
#define ONE_BIN "build/dartspp"
#define MPIRUN_PATH "/usr/bin/mpirun"
#define MPIRUN_ARGS "--allow-run-as-root", "--oversubscribe", "--mca", "plm_rsh_agent", "false", "--mca", \
                    "btl_vader_single_copy_mechanism", "none"
#define MPIRUN MPIRUN_PATH " --allow-run-as-root --oversubscribe --mca plm_rsh_agent false --mca btl_vader_single_copy_mechanism none"

/* A command started in the background with its stdout and stderr in one file. */
typedef struct {
    pid_t pid;
    char log[600];
} child;

/* Seconds on the monotonic clock. */
double now_s(void);
/* Starts argv (argv[0] a path) with its output in <dir>/render.log; TMPDIR=tmpdir when not NULL; fsize_limit > 0
 * sets RLIMIT_FSIZE (bytes) in the child before exec, as `ulimit -f` does. */
void child_start(child *c, const char *dir, const char *const *argv, const char *tmpdir, long fsize_limit);
/* Waits up to `bound` seconds; returns the exit status (128 + signal if killed), or -1 after killing a child that
 * did not end in time; the seconds waited go to *waited when it is not NULL. */
int child_wait(child *c, double bound, double *waited);
/* Waits until the child's log contains `what` (up to `bound` seconds); 1 if it did. */
int log_wait_for(const child *c, const char *what, double bound);
/* The first MiB of a text file ("" when it cannot be opened); the caller frees it. */
char *read_text(const char *path);
/* Prints what a command said, at most its last 700 characters, always ending the line (the test runner reads
 * cmocka's result lines at the start of a line). */
void print_tail(const char *what);
int file_exists(const char *path);

#endif
