/* dartspp-mpi when a rank dies (`mpirun --oversubscribe`, Open MPI): rank 1 of 3 is SIGKILLed mid-way on
 * the fog Cornell box at 40×40; the job ends non-zero saying that a rank was lost, the checkpoint state of
 * the last periodic reduction (--reduce-every) is on disk and the watchdog wrote its images with that pass
 * count; `--resume` of that state with 3 ranks, and with one process, completes to K passes and equals a
 * one-process render of K passes within the bound of tests/cluster/test_mpi.c (the gate image's sums are doubles
 * added in another order: 2 float ulps); a one-process state with frames resumes under 3 ranks the same
 * way (frames within 2K ulps); a rank killed before the first reduction leaves nothing and the message says
 * so; a job stopped before the first reduction says that its images cannot be resumed and the next render
 * does not replace them silently. Rank 0 exits with status 4 in the first two (each rank runs in a shell that prints its status: mpirun reports
 * the killed rank's). The release binaries. */
#include "child_process.h"
#include "fixtures.h"

#include <dirent.h>
#include <signal.h>
#include <sys/wait.h>

#include "dartspp/io.h"

/* small photon counts: a pass takes a few tens of milliseconds */
#define SETS "--threads 1 --seed 9 --set photon_count=20000 --set volume_photon_count=3000"

/* sh -c RANK_STATUS program args...: runs the program, then says how it ended */
#define RANK_STATUS "trap '' TERM; \"$0\" \"$@\"; echo \"rank $OMPI_COMM_WORLD_RANK exit $?\""

/* Whether process pid has `var` (e.g. "OMPI_COMM_WORLD_RANK=1") in its environment. */
static int has_env(pid_t pid, const char *var)
{
    char path[64], buf[1 << 16];
    snprintf(path, sizeof path, "/proc/%d/environ", (int)pid);
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    for (size_t i = 0; i < n; i += strlen(buf + i) + 1) {
        buf[n] = 0;
        if (!strcmp(buf + i, var)) return 1;
    }
    return 0;
}

/* The parent of pid, or -1. */
static pid_t parent_of(pid_t pid)
{
    char path[64], line[256];
    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    FILE *f = fopen(path, "r");
    pid_t ppid = -1;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "PPid: %d", &ppid) == 1) break;
    if (f) fclose(f);
    return ppid;
}

/* Whether pid runs dartspp-mpi (its command name). */
static int is_renderer(pid_t pid)
{
    char path[64], name[64] = "";
    snprintf(path, sizeof path, "/proc/%d/comm", (int)pid);
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    int ok = fgets(name, sizeof name, f) && !strcmp(name, "dartspp-mpi\n");
    fclose(f);
    return ok;
}

/* The pid of the dartspp-mpi below mpirun (its grandchild: each rank runs in a shell) whose
 * OMPI_COMM_WORLD_RANK is `rank`, or -1. */
static pid_t rank_pid(pid_t mpirun, int rank)
{
    char var[64];
    snprintf(var, sizeof var, "OMPI_COMM_WORLD_RANK=%d", rank);
    DIR *d = opendir("/proc");
    struct dirent *e;
    pid_t found = -1;
    while (d && found < 0 && (e = readdir(d))) {
        pid_t pid = (pid_t)atoi(e->d_name);
        if (pid > 0 && is_renderer(pid) && parent_of(parent_of(pid)) == mpirun && has_env(pid, var)) found = pid;
    }
    if (d) closedir(d);
    return found;
}

/* 3 ranks rendering `name`.exr for up to a minute, reducing every `reduce_every` seconds. */
static void start_three(child *c, const char *name, const char *reduce_every)
{
    char scene[600], out[600];
    snprintf(scene, sizeof scene, "%s/box.json", cbox_dir);
    snprintf(out, sizeof out, "%s/%s.exr", cbox_dir, name);
    /* each rank in a shell that ignores mpirun's SIGTERM and prints the rank's own exit status */
    const char *argv[] = {MPIRUN_PATH, MPIRUN_ARGS, "-np", "3", "/bin/sh", "-c", RANK_STATUS, MPI_BIN, "render", scene, "--threads", "1", "--seed",
                          "9", "--set", "photon_count=20000", "--set", "volume_photon_count=3000", "--time", "60",
                          "--reduce-every", reduce_every, "--output", out, NULL};
    child_start(c, cbox_dir, argv, NULL, 0);
}

/* SIGKILL to rank 1 of the job c; the job's exit status (bounded: the ranks must not hang). */
static int kill_rank_1(child *c, char **log)
{
    pid_t victim = rank_pid(c->pid, 1);
    if (victim < 0) fail_msg("rank 1 not found among mpirun's children");
    kill(victim, SIGKILL);
    double waited = 0;
    int rc = child_wait(c, 20, &waited);
    *log = read_text(c->log);
    print_message("  rank 1 (pid %d) killed; mpirun exit %d %.2f s later\n", (int)victim, rc, waited);
    if (rc < 0) {
        print_tail(*log);
        free(*log);
        fail_msg("the job did not end within 20 s of the kill");
    }
    return rc;
}

/* Renders `name` with one process and K passes (the reference of the resumed renders). */
static void render_one(const char *name, long K, const char *extra)
{
    char cmd[2048], out[16384];
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json " SETS " --spp %ld %s --quiet --output %s/%s.exr", cbox_dir, K,
             extra, cbox_dir, name);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
}

/* Largest |a − b| / (|b| + tiny) of the gate images a and b (lit: a black image would prove nothing). */
static double max_rel_diff(const char *a_name, const char *b_name)
{
    char ap[600], bp[600];
    snprintf(ap, sizeof ap, "%s/%s.exr", cbox_dir, a_name);
    snprintf(bp, sizeof bp, "%s/%s.exr", cbox_dir, b_name);
    return image_max_rel_diff(ap, bp);
}

/* `resumed`.exr holds K passes and equals the one-process render `one` of K passes within 2 float ulps. */
static void assert_same_as_one(const char *resumed, const char *one, long K)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s.exr", cbox_dir, resumed);
    assert_int_equal(exr_passes(path), K);
    double d = max_rel_diff(resumed, one);
    print_message("  %-12s %ld passes: largest relative difference to one process %.3g (bound %.3g)\n", resumed, K, d,
                  2 * 0x1p-24);
    assert_true(d <= 2 * 0x1p-24);
}

static void copy_file(const char *from_name, const char *to_name)
{
    char cmd[1400];
    snprintf(cmd, sizeof cmd, "cp '%s/%s' '%s/%s'", cbox_dir, from_name, cbox_dir, to_name);
    assert_int_equal(system(cmd), 0);
}

/* Resumes `name`.state to K passes: with 3 ranks (np 3) or one process (np 1). */
static void resume(const char *name, long K, int np, const char *extra)
{
    char cmd[2048], out[16384];
    if (np > 1)
        snprintf(cmd, sizeof cmd, MPIRUN " -np %d " MPI_BIN " render %s/box.json " SETS " %s --spp %ld --resume --output %s/%s.exr",
                 np, cbox_dir, extra, K, cbox_dir, name);
    else
        snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json " SETS " %s --spp %ld --resume --output %s/%s.exr", cbox_dir, extra,
                 K, cbox_dir, name);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    assert_non_null(strstr(out, "resuming "));
}

/* Rank 1 of 3 SIGKILLed once the state of a reduction (every 0.5 s) is on disk: non-zero exit, the message,
 * the state and the watchdog's images with the same pass count; then resumed to K passes with 3 ranks and
 * with one process, both equal to one process's K passes. */
static void test_killed_rank_keeps_last_reduction(void **state)
{
    (void)state;
    char st[600], img[600];
    snprintf(st, sizeof st, "%s/killed.state", cbox_dir);
    snprintf(img, sizeof img, "%s/killed.exr", cbox_dir);
    child c;
    start_three(&c, "killed", "0.5");
    double t0 = now_s();
    while (state_passes(st) <= 0 && now_s() - t0 < 20) usleep(10000);
    if (state_passes(st) <= 0) {
        char *log = read_text(c.log);
        kill(c.pid, SIGKILL);
        child_wait(&c, 5, NULL);
        print_tail(log);
        free(log);
        fail_msg("no checkpoint state after %.1f s of rendering with --reduce-every 0.5", now_s() - t0);
    }
    usleep(300000); /* into the next reduction interval: its passes are the ones lost */
    char *log;
    int rc = kill_rank_1(&c, &log);
    long held = state_passes(st);
    print_message("  the state holds %ld passes\n", held);
    if (rc == 0 || !strstr(log, "a rank was lost") || !strstr(log, "continue with --resume") ||
        !strstr(log, "rank 0 exit 4")) {
        print_tail(log);
        free(log);
        fail_msg("exit %d; expected non-zero, the message that a rank was lost and rank 0's exit status 4", rc);
    }
    free(log);
    assert_true(held > 0);
    if (!file_exists(img)) fail_msg("the watchdog wrote no image within mpirun's 1-s grace time");
    assert_int_equal(exr_passes(img), held);
    const long K = held + 7; /* the resume renders passes of its own, on every rank */
    render_one("one", K, "");
    copy_file("killed.state", "single.state");
    resume("killed", K, 3, "");
    assert_same_as_one("killed", "one", K);
    resume("single", K, 1, "");
    assert_same_as_one("single", "one", K);
}

/* A state written by one process (5 passes, 2 frames) resumed by 3 ranks to 12: equal to one process's 12,
 * the gate image within 2 float ulps, each frame within 2K (its sums are floats: K additions in another
 * order). */
static void test_one_process_state_resumes_on_ranks(void **state)
{
    (void)state;
    const char *frames = "--set frame_num=2 --set start_time=15.95 --set transient_time_width=0.1";
    char extra[256];
    snprintf(extra, sizeof extra, "%s --checkpoint 1e-9", frames);
    render_one("from-one", 5, extra);
    render_one("one12", 12, frames);
    resume("from-one", 12, 3, frames);
    assert_same_as_one("from-one", "one12", 12);
    for (int k = 0; k < 2; k++) {
        char a[64], b[64];
        snprintf(a, sizeof a, "from-one_%04d", k);
        snprintf(b, sizeof b, "one12_%04d", k);
        double d = max_rel_diff(a, b);
        print_message("  frame %d: largest relative difference %.3g (bound %.3g)\n", k, d, 2.0 * 12 * 0x1p-24);
        assert_true(d <= 2.0 * 12 * 0x1p-24);
    }
}

/* A rank killed before the first reduction (every 30 s): non-zero exit, the message says that nothing was
 * kept, and no state or image was written. */
static void test_killed_before_any_reduction(void **state)
{
    (void)state;
    char st[600], img[600];
    snprintf(st, sizeof st, "%s/early.state", cbox_dir);
    snprintf(img, sizeof img, "%s/early.exr", cbox_dir);
    child c;
    start_three(&c, "early", "30");
    if (!log_wait_for(&c, "cluster: 3 ranks", 20)) fail_msg("the job did not start");
    usleep(1500000);
    char *log;
    int rc = kill_rank_1(&c, &log);
    if (rc == 0 || !strstr(log, "a rank was lost") || !strstr(log, "nothing was kept") || !strstr(log, "rank 0 exit 4")) {
        print_tail(log);
        free(log);
        fail_msg("exit %d; expected non-zero and the message that nothing was kept", rc);
    }
    free(log);
    assert_false(file_exists(st));
    assert_false(file_exists(img));
}

/* The job stopped (SIGTERM to mpirun, as Ctrl-C or a batch system's end does) before the first periodic
 * reduction: every rank drops its pass, so the final reduction is not iterations 0..N−1 and cannot be resumed.
 * The message says so (main claimed "x.state keeps the last reduction..." with no state on disk), and the next
 * render to the same output refuses to replace the images without --overwrite (main replaced them). */
static void test_stopped_before_any_reduction(void **state)
{
    (void)state;
    char img[600], cmd[2048], out[16384];
    snprintf(img, sizeof img, "%s/stopped.exr", cbox_dir);
    child c;
    start_three(&c, "stopped", "30");
    if (!log_wait_for(&c, "cluster: 3 ranks", 20)) fail_msg("the job did not start");
    usleep(1500000);
    kill(c.pid, SIGTERM);
    int rc = child_wait(&c, 20, NULL);
    char *log = read_text(c.log);
    print_message("  job stopped: mpirun exit %d\n", rc);
    int lie = strstr(log, "keeps the last reduction") != NULL, said = strstr(log, "cannot be resumed") != NULL;
    int watchdog = strstr(log, "nothing was kept") != NULL;
    if (lie || !said) print_tail(log);
    free(log);
    assert_false(lie);
    if (!file_exists(img)) {
        /* on a loaded machine rank 0 may wait in the last collective past the watchdog's 0.3 s: then the
         * job counts as stuck, and what it says must be that nothing was kept */
        print_message("  the watchdog ended the job (a loaded machine): no image\n");
        assert_true(watchdog);
        return;
    }
    assert_true(said);
    long passes = exr_passes(img);
    assert_true(passes > 0);
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json " SETS " --spp 1 --quiet --output %s", cbox_dir, img);
    rc = test_run(cmd, out, sizeof out);
    print_message("  the next render of 1 pass: exit %d: ", rc);
    print_tail(out);
    assert_int_equal(rc, 2);
    assert_non_null(strstr(out, "--overwrite"));
    assert_int_equal(exr_passes(img), passes);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_killed_rank_keeps_last_reduction),
        cmocka_unit_test(test_one_process_state_resumes_on_ranks),
        cmocka_unit_test(test_killed_before_any_reduction),
        cmocka_unit_test(test_stopped_before_any_reduction),
    };
    return cmocka_run_group_tests(tests, setup_cbox_fog40, teardown_cbox_fog);
}
