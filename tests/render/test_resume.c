/* `dartspp render --resume`: a render continued from its checkpoint state equals the uninterrupted render of
 * the same seed and pass count byte for byte (the gate image, every frame and the cube), for DARTS photon
 * points, the path tracer and frame mode, after a SIGKILL in the middle and after a render that simply
 * stopped at fewer passes, and the AMCW sums with them; a checkpoint of another plan, seed or resolution is refused; a re-run that would
 * overwrite a checkpoint holding more passes says so and refuses unless --overwrite. The real sanitized
 * binary on the demo scene at 16x16. The reference is the uninterrupted render of the same command line:
 * what is tested is that resuming changes nothing, so no expected value comes from an earlier run. */
#include "child_process.h"
#include "fixtures.h"

#include <fcntl.h>
#include <signal.h>
#include <time.h>

#include "dartspp/io.h"

#define DEMO "scenes/fogbox/fogbox.json"
#define BASE DARTSPP_BIN " render " DEMO " --set resolution=16 --seed 11 --threads 2"
#define PASSES 6
/* n frames of the gate's width from just before the gate: all of them lit */
#define FRAMES(n) "--set frame_num=" #n " --set start_time=6.45"

static int setup_dir(void **state)
{
    *state = test_tmpdir();
    return *state ? 0 : -1;
}

static char *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc(len > 0 ? (size_t)len : 1);
    *n = buf && len > 0 ? fread(buf, 1, (size_t)len, f) : 0;
    fclose(f);
    return buf;
}

/* Byte-for-byte equality of two files; prints where they first differ. */
static void assert_same_file(const char *a, const char *b)
{
    size_t na = 0, nb = 0;
    char *fa = read_file(a, &na), *fb = read_file(b, &nb);
    if (!fa || !fb) fail_msg("cannot read %s or %s", a, b);
    size_t i = 0;
    while (i < na && i < nb && fa[i] == fb[i]) i++;
    free(fa);
    free(fb);
    if (na != nb || i < na) fail_msg("%s and %s differ at byte %zu (of %zu and %zu)", a, b, i, na, nb);
}

/* An image with light in it (a black image would compare equal however it was resumed). */
static void assert_lit(const char *path)
{
    image_rgb img = {0};
    dp_error err;
    if (image_read(path, &img, &err)) fail_msg("%s", err.msg);
    double sum = 0;
    for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++) sum += img.rgb[i];
    image_free(&img);
    if (!(sum > 0)) fail_msg("%s is black: the comparison would prove nothing", path);
}

static int run(const char *cmd, char *out, size_t n)
{
    int rc = test_run(cmd, out, n);
    if (strstr(out, "Sanitizer") || strstr(out, "runtime error")) {
        print_tail(out);
        fail_msg("sanitizer report from: %s", cmd);
    }
    return rc;
}

/* A render with a checkpoint after every pass and far more passes than PASSES, killed with SIGKILL once its
 * checkpoint state holds at least two passes (one checkpoint replaced by the next); returns the passes the
 * state holds then. */
static long render_and_kill(const char *d, const char *mode)
{
    char cmd[2048], state[600], log[600];
    snprintf(state, sizeof state, "%s/resumed.state", d);
    snprintf(log, sizeof log, "%s/killed.log", d);
    snprintf(cmd, sizeof cmd, "exec " BASE " %s --spp 1000 --checkpoint 1e-9 --output %s/resumed.pfm >%s 2>&1", mode,
             d, log);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    double t0 = now_s();
    long passes = -1;
    while ((passes = state_passes(state)) < 2 && now_s() - t0 < 120 && waitpid(pid, NULL, WNOHANG) == 0)
        usleep(5000);
    kill(pid, SIGKILL);
    int st;
    waitpid(pid, &st, 0);
    assert_true(WIFSIGNALED(st) && WTERMSIG(st) == SIGKILL); /* killed, not ended on its own */
    passes = state_passes(state);
    print_message("  killed after %.1f s; the checkpoint state holds %ld passes\n", now_s() - t0, passes);
    assert_true(passes >= 2);
    assert_true(passes < PASSES); /* the resume must render some passes itself */
    return passes;
}

/* The uninterrupted render of PASSES passes (full.*) and the resumed one (resumed.*), gate image and frames
 * compared byte for byte. kill_it: the first part was SIGKILLed mid-way; else it stopped at `stop` passes. */
static void check_resume(const char *d, const char *mode, int kill_it, long stop, const char *ext, int frames)
{
    char cmd[2048], out[16384], a[600], b[600];
    snprintf(cmd, sizeof cmd, BASE " %s --spp %d --output %s/full%s", mode, PASSES, d, ext);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    long held = stop;
    if (kill_it) held = render_and_kill(d, mode);
    else {
        snprintf(cmd, sizeof cmd, BASE " %s --spp %ld --checkpoint 1e-9 --output %s/resumed%s", mode, stop, d, ext);
        assert_int_equal(run(cmd, out, sizeof out), 0);
        snprintf(a, sizeof a, "%s/resumed.state", d);
        assert_int_equal(state_passes(a), stop);
    }
    /* after the kill with checkpoints on; after the stop with --resume alone (the final write updates the state) */
    snprintf(cmd, sizeof cmd, BASE " %s --spp %d %s --resume --output %s/resumed%s", mode, PASSES,
             kill_it ? "--checkpoint 1e-9" : "", d, kill_it ? ".pfm" : ext);
    int rc = run(cmd, out, sizeof out);
    if (rc) print_tail(out);
    assert_int_equal(rc, 0);
    char expect[128];
    snprintf(expect, sizeof expect, "rendered %d passes (%ld of them resumed from the checkpoint, %ld in this run)",
             PASSES, held, PASSES - held);
    if (!strstr(out, expect)) {
        print_tail(out);
        fail_msg("the summary lacks '%s'", expect);
    }
    const char *e = kill_it ? ".pfm" : ext;
    if (kill_it && strcmp(ext, ".pfm")) fail_msg("the killed case writes PFM");
    snprintf(a, sizeof a, "%s/full%s", d, e);
    snprintf(b, sizeof b, "%s/resumed%s", d, e);
    assert_lit(a);
    assert_same_file(a, b);
    for (int k = 0; k < frames; k++) {
        snprintf(a, sizeof a, "%s/full_%04d%s", d, k, e);
        snprintf(b, sizeof b, "%s/resumed_%04d%s", d, k, e);
        assert_lit(a);
        assert_same_file(a, b);
    }
    if (frames > 0) {
        snprintf(a, sizeof a, "%s/full_cube.npy", d);
        snprintf(b, sizeof b, "%s/resumed_cube.npy", d);
        assert_same_file(a, b);
    }
    if (strstr(mode, "amcw_frequencies")) /* the AMCW sums are in the state too (docs/amcw.md §3) */
        for (int k = 0; k < 2; k++) {
            snprintf(a, sizeof a, "%s/full_%s.npy", d, k ? "amcw_depth" : "amcw");
            snprintf(b, sizeof b, "%s/resumed_%s.npy", d, k ? "amcw_depth" : "amcw");
            assert_same_file(a, b);
        }
    snprintf(a, sizeof a, "%s/resumed.state", d);
    assert_int_equal(state_passes(a), PASSES);
    print_message("  %s: resumed at pass %ld, %d passes byte-identical to the uninterrupted render (%d frames)\n",
                  mode[0] ? mode : "photon points (DARTS)", held, PASSES, frames);
}

static void test_photon_points_killed(void **state) { check_resume(*state, "", 1, 0, ".pfm", 0); }
static void test_path_tracer_killed(void **state) { check_resume(*state, "--set type=path_tracer", 1, 0, ".pfm", 0); }
static void test_frames_killed(void **state) { check_resume(*state, FRAMES(3), 1, 0, ".pfm", 3); }
static void test_photon_points_stopped_exr(void **state) { check_resume(*state, "", 0, 3, ".exr", 0); }
static void test_path_tracer_frames_stopped(void **state)
{
    check_resume(*state, "--set type=path_tracer " FRAMES(2), 0, 2, ".exr", 2);
}
/* A delta gate (docs/time.md §3.1): pass i's box width w_i and weight follow the iteration index, so the resumed
 * passes must continue the schedule at the checkpoint's pass count, not restart it. Broken variant: the width
 * of the run's own pass count (iteration − resumed passes) fails both (the images differ). */
#define DELTA(type) "--set volume_photon_type=" type " --set delta_time_gate=true --set transient_time_width=0.2 " \
                    "--set enable_guiding=false --set enable_elliptical=false --set strict_time_width=false"
/* The AMCW sums (docs/amcw.md): checkpointed, resumed and written like the image's. Broken variant: the state
 * without them (the resumed values hold only the resumed run's passes) fails. */
static void test_amcw_killed(void **state)
{
    check_resume(*state, "--set type=path_tracer --set amcw_frequencies=[20,300] " FRAMES(2), 1, 0, ".pfm", 2);
}
static void test_delta_beams_stopped(void **state) { check_resume(*state, DELTA("beams"), 0, 3, ".exr", 0); }
static void test_delta_points_killed(void **state) { check_resume(*state, DELTA("points"), 1, 0, ".pfm", 0); }

/* A checkpoint of 3 passes, then --resume with a different plan, seed, resolution or frame count, a pass
 * count below the checkpoint's, or without a state: each refused (exit 2) with a message naming the state
 * file and the difference, before any work, and the state untouched. */
static void test_mismatch_refused(void **state)
{
    const char *d = *state;
    char cmd[2048], out[16384], st[600];
    snprintf(cmd, sizeof cmd, BASE " --spp 3 --checkpoint 1e-9 --quiet --output %s/r.pfm", d);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    snprintf(st, sizeof st, "%s/r.state", d);
    size_t n0 = 0;
    char *before = read_file(st, &n0);
    assert_non_null(before);
    struct {
        const char *args, *expect;
    } cases[] = {
        {"--set alpha=0.5", "another plan"},
        {"--set transient_time_width=0.06", "another plan"},
        {"--set type=path_tracer", "another plan"},
        {"--seed 12", "seed 11, this run has seed 12"},
        {"--set resolution=8", "16x16, this run renders 8x8"},
        {"--set frame_num=2", "0 frames, this run 2"},
        {"--set amcw_frequencies=[20]", "AMCW sums of 0 modulation frequencies, this run 1"},
        {"--spp 2", "holds 3 passes, more than the 2"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(cmd, sizeof cmd, BASE " --spp 6 --checkpoint 1e-9 --quiet --resume --output %s/r.pfm %s", d,
                 cases[i].args);
        int rc = run(cmd, out, sizeof out);
        print_message("  --resume %-36s exit %d: ", cases[i].args, rc);
        print_tail(out);
        assert_int_equal(rc, 2);
        if (!strstr(out, cases[i].expect)) fail_msg("message lacks '%s'", cases[i].expect);
        if (!strstr(out, st)) fail_msg("message lacks the state file %s", st);
    }
    size_t n1 = 0;
    char *after = read_file(st, &n1);
    assert_true(after && n0 == n1 && !memcmp(before, after, n0));
    free(before);
    free(after);
    /* no state to resume */
    snprintf(cmd, sizeof cmd, BASE " --spp 6 --resume --quiet --output %s/none.pfm", d);
    assert_int_equal(run(cmd, out, sizeof out), 2);
    print_tail(out);
    assert_non_null(strstr(out, "no checkpoint state to resume"));
    /* a damaged state (one byte of the sums changed) */
    FILE *f = fopen(st, "r+b");
    assert_non_null(f);
    fseek(f, -5, SEEK_END);
    int c = fgetc(f);
    fseek(f, -5, SEEK_END);
    fputc(c ^ 0x40, f);
    fclose(f);
    snprintf(cmd, sizeof cmd, BASE " --spp 6 --resume --quiet --output %s/r.pfm", d);
    assert_int_equal(run(cmd, out, sizeof out), 2);
    print_tail(out);
    assert_non_null(strstr(out, "checksum"));
}

/* The crash: a render checkpointed at 5 passes, then the same command line with fewer passes (or only
 * a time budget) without --resume: refused, naming the state file and both pass counts, and the images and
 * the state untouched; --overwrite replaces them; equal or more passes go ahead. */
static void test_overwrite_refused(void **state)
{
    const char *d = *state;
    char cmd[2048], out[16384], img[600], st[600];
    snprintf(img, sizeof img, "%s/o.pfm", d);
    snprintf(st, sizeof st, "%s/o.state", d);
    snprintf(cmd, sizeof cmd, BASE " --spp 5 --checkpoint 1e-9 --quiet --output %s", img);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_int_equal(state_passes(st), 5);
    size_t n0 = 0;
    char *before = read_file(img, &n0);
    const char *runs[] = {"--spp 2 --checkpoint 1e-9", "--spp 2", "--time 1"};
    const char *expect[] = {"this run renders 2 passes", "this run renders 2 passes", "an unknown number of passes"};
    for (int i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, BASE " %s --quiet --output %s", runs[i], img);
        int rc = run(cmd, out, sizeof out);
        print_message("  %-28s exit %d: ", runs[i], rc);
        print_tail(out);
        assert_int_equal(rc, 2);
        if (!strstr(out, st) || !strstr(out, "checkpoint of 5 passes") || !strstr(out, expect[i]) ||
            !strstr(out, "--overwrite"))
            fail_msg("the message must name %s, its 5 passes, '%s' and --overwrite", st, expect[i]);
        size_t n1 = 0;
        char *after = read_file(img, &n1);
        assert_true(after && n0 == n1 && !memcmp(before, after, n0)); /* the image untouched */
        free(after);
        assert_int_equal(state_passes(st), 5);
    }
    free(before);
    /* as many passes as the checkpoint: goes ahead */
    snprintf(cmd, sizeof cmd, BASE " --spp 5 --checkpoint 1e-9 --quiet --output %s", img);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_int_equal(state_passes(st), 5);
    /* asked: replaced */
    snprintf(cmd, sizeof cmd, BASE " --spp 2 --checkpoint 1e-9 --overwrite --quiet --output %s", img);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_int_equal(state_passes(st), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_photon_points_killed, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_path_tracer_killed, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_frames_killed, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_photon_points_stopped_exr, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_path_tracer_frames_stopped, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_amcw_killed, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_delta_beams_stopped, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_delta_points_killed, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_mismatch_refused, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_overwrite_refused, setup_dir, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
