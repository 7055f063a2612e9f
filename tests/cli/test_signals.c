/* run: alone */
/* Signals and files (issue 32, item 7): the real `dartspp render` on the demo scene, killed or limited the
 * ways a user's run is. A dropped terminal (SIGHUP) keeps the completed passes as SIGTERM does; a file-size
 * limit (`ulimit -f`) ends the run with a message naming the limit, the rescue attempt and no temporary file
 * left; a SIGKILL at a random moment of a 200-frame write leaves the complete old set or the complete new
 * one (each file's `dartspp.passes` header is the set's marker), and the next run removes what the killed
 * one left behind. */
#include "child_process.h"
#include "fixtures.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>

#include "dartspp/io.h"

#define DEMO "scenes/fogbox/fogbox.json"
#define EXIT_BOUND_S 5.0
#define FRAMES 200







/* Entries under dir (recursively) whose name holds `what`; their names go to print_message. */
static int count_named(const char *dir, const char *what)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char p[1200];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        if (strstr(e->d_name, what)) {
            print_message("  left behind: %s\n", p);
            n++;
        }
        struct stat st;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) n += count_named(p, what);
    }
    closedir(d);
    return n;
}

static int passes_of(const char *path)
{
    int v = -1;
    dp_error err;
    if (exr_read_int_attribute(path, "dartspp.passes", &v, &err)) return -1;
    return v;
}

/* ---------------------------------------------------------------------------------------------------- */

/* SIGHUP (the terminal or ssh session went away) inside a pass: the pass in progress stops, the completed
 * passes are written (the header's pass count is the one the summary reports) and the exit status is 130,
 * as for SIGTERM. Before: the default action killed the process with nothing written (exit 129). */
static void test_sighup_writes_completed_passes(void **state)
{
    const char *d = *state;
    char o[600];
    snprintf(o, sizeof o, "%s/hup.exr", d);
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--seed", "5", "--set", "resolution=96", "--spp", "1000",
                          "--threads", "2", "--output", o, NULL};
    child c;
    child_start(&c, d, argv, NULL, 0);
    usleep(6000000); /* loading and a few passes of about a second each under the sanitizers */
    double t0 = now_s();
    kill(c.pid, SIGHUP);
    int rc = child_wait(&c, EXIT_BOUND_S * 4, NULL);
    char *log = read_text(c.log);
    print_message("  SIGHUP: exit %d, %.2f s after the signal\n", rc, now_s() - t0);
    print_tail(log);
    const char *r = strstr(log, "rendered ");
    long passes = r ? strtol(r + 9, NULL, 10) : -1;
    int mid_pass = strstr(log, "stopping the pass in progress") != NULL, leak = strstr(log, "LeakSanitizer") != NULL;
    free(log);
    assert_int_equal(rc, 130);
    assert_true(mid_pass);
    assert_false(leak);
    assert_true(passes >= 1);
    assert_true(file_exists(o));
    assert_int_equal(passes_of(o), passes);
    assert_int_equal(count_named(d, ".tmp."), 0);
}

/* A file-size limit below the size of the outputs (the gate image fits, the 8-frame cube does not): the
 * write fails with EFBIG instead of SIGXFSZ killing the process; the message names the limit, the rescue
 * folder is tried (under the same limit it fails too and says so), the exit status is 1, and no temporary
 * file or staging folder is left in the output folder or under $TMPDIR. Before: killed by SIGXFSZ (exit
 * 153), no message, a half-written *.tmp.* left. */
static void test_file_size_limit(void **state)
{
    const char *d = *state;
    char o[600], out_dir[600], tmp[600];
    snprintf(out_dir, sizeof out_dir, "%s/out", d);
    snprintf(o, sizeof o, "%s/out/lim.exr", d);
    snprintf(tmp, sizeof tmp, "%s/tmp", d);
    assert_int_equal(mkdir(tmp, 0755), 0);
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=64", "--set", "frame_num=8", "--spp",
                          "1", "--quiet", "--output", o, NULL};
    child c;
    child_start(&c, d, argv, tmp, 200 * 1024); /* a frame's 48 KiB fits, the cube's 384 KiB does not */
    int rc = child_wait(&c, 120.0, NULL);
    char *log = read_text(c.log);
    print_message("  ulimit -f 200: exit %d\n", rc);
    print_tail(log);
    int names_limit = strstr(log, "File too large") && strstr(log, "ulimit -f");
    int rescue_said = strstr(log, "rescue folder") || strstr(log, "were written to ");
    int leak = strstr(log, "LeakSanitizer") != NULL;
    free(log);
    assert_int_equal(rc, 1);
    assert_true(names_limit);
    assert_true(rescue_said);
    assert_false(leak);
    assert_int_equal(count_named(d, ".tmp."), 0);
    assert_int_equal(count_named(d, ".set."), 0);
    assert_false(file_exists(o)); /* the set is all or nothing: the gate image went with the rest */
}

/* <over>/<name> when over is given and holds it, else <dir>/<name>. */
static void pick(char *p, size_t n, const char *dir, const char *over, const char *name)
{
    snprintf(p, n, "%s/%s", over ? over : dir, name);
    if (over && !file_exists(p)) snprintf(p, n, "%s/%s", dir, name);
}

/* Reads every file of the set <dir>/<base>*: the gate image's and each frame's pass count; the cube's first
 * and last frames against those frame files. Returns the set's marker (its pass count), or -1 when the files
 * disagree or some are missing (and prints which). `over` is a folder whose files replace the dir's (a commit
 * folder left by a kill while the set was moved into place), or NULL. */
static long set_marker(const char *dir, const char *over, const char *base)
{
    char p[1200], name[200];
    long marker = -2;
    int bad = 0, counts[64] = {0};
    for (int k = -1; k < FRAMES; k++) {
        if (k < 0) snprintf(name, sizeof name, "%s.exr", base);
        else snprintf(name, sizeof name, "%s_%04d.exr", base, k);
        pick(p, sizeof p, dir, over, name);
        int v = passes_of(p);
        if (v >= 0 && v < 64) counts[v]++;
        if (marker == -2) marker = v;
        if (v != marker || v < 0) bad = 1;
    }
    if (bad) {
        print_message("  a mix of sets: files per pass count:");
        for (int v = 0; v < 64; v++)
            if (counts[v]) print_message(" %d passes: %d", v, counts[v]);
        print_message("\n");
        return -1;
    }
    /* the cube against frames 0 and FRAMES-1 (the cube of another set would differ) */
    snprintf(name, sizeof name, "%s_cube.npy", base);
    pick(p, sizeof p, dir, over, name);
    size_t len = 0;
    char *cube = read_all(p, &len);
    if (!cube) return -1;
    for (int k = 0; k < FRAMES && !bad; k += FRAMES - 1) {
        snprintf(name, sizeof name, "%s_%04d.exr", base, k);
        pick(p, sizeof p, dir, over, name);
        image_rgb img = {0};
        dp_error err;
        if (image_read(p, &img, &err)) {
            bad = 1;
            break;
        }
        size_t n = (size_t)img.width * img.height * 3;
        size_t data = len >= 10 ? 10 + ((size_t)(unsigned char)cube[8] | (size_t)(unsigned char)cube[9] << 8) : len;
        if (len != data + (size_t)FRAMES * n * 4 || memcmp(cube + data + (size_t)k * n * 4, img.rgb, n * 4)) {
            print_message("  the cube's frame %d differs from the frame file\n", k);
            bad = 1;
        }
        image_free(&img);
    }
    free(cube);
    return bad ? -1 : marker;
}

/* SIGKILL at a random moment of a 200-frame write, over 5 seeds of the moment: each run renders one pass
 * more than the set on disk, so every file's `dartspp.passes` tells its set. After the kill the folder holds
 * the complete old set or the complete new one; or, when the kill landed while the staged files were being
 * moved into place (renames only), the commit folder completes the new set. The next run to the same output
 * removes the staging folder (or completes the move) with a note, and leaves no temporary file. Before: the
 * frames were renamed into place one by one as written, so most kills left a mix. */
static void test_sigkill_during_frame_write(void **state)
{
    const char *d = *state;
    char o[600], cmd[2048], out[1 << 14];
    snprintf(o, sizeof o, "%s/set.exr", d);
    /* the first set, and how long its write takes: from the first temporary name to the exit */
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --set resolution=32 --set frame_num=%d --spp 1 --quiet "
             "--output %s", FRAMES, o);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    long marker = set_marker(d, NULL, "set");
    assert_int_equal(marker, 1);
    int old_sets = 0, new_sets = 0, commit_sets = 0, finished = 0;
    double write_s = 0;
    for (int round = 0; round < 6; round++) {
        long spp = marker + 1;
        char spp_s[32], frames_s[32];
        snprintf(spp_s, sizeof spp_s, "%ld", spp);
        snprintf(frames_s, sizeof frames_s, "frame_num=%d", FRAMES);
        const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=32", "--set", frames_s, "--spp", spp_s,
                              "--quiet", "--output", o, NULL};
        child c;
        child_start(&c, d, argv, NULL, 0);
        char tag[64];
        snprintf(tag, sizeof tag, ".tmp.%ld", (long)c.pid);
        /* wait for the write to start: a temporary name of this process appears in the folder */
        double t0 = now_s(), seen = -1;
        int st, exited = 0;
        while (now_s() - t0 < 120 && seen < 0) {
            DIR *dd = opendir(d);
            for (struct dirent *e; dd && (e = readdir(dd));)
                if (strstr(e->d_name, tag)) seen = now_s();
            if (dd) closedir(dd);
            if (seen < 0) usleep(1000);
            if (seen < 0 && waitpid(c.pid, &st, WNOHANG) == c.pid) {
                exited = 1;
                break;
            }
        }
        assert_false(exited);
        assert_true(seen >= 0);
        if (round == 0) {
            /* round 0 measures the write: it is not killed */
            assert_int_equal(child_wait(&c, 120, NULL), 0);
            write_s = now_s() - seen;
            print_message("  the %d-frame write takes %.2f s\n", FRAMES, write_s);
            marker = set_marker(d, NULL, "set");
            assert_int_equal(marker, spp);
            continue;
        }
        srand(1000 + round);
        double delay = write_s * rand() / RAND_MAX;
        usleep((useconds_t)(delay * 1e6));
        kill(c.pid, SIGKILL);
        int rc = child_wait(&c, 60, NULL);
        finished += rc == 0;
        /* a commit folder of the killed process? */
        char commit[700] = "";
        DIR *dd = opendir(d);
        for (struct dirent *e; dd && (e = readdir(dd));)
            if (strstr(e->d_name, ".set.commit.")) snprintf(commit, sizeof commit, "%s/%s", d, e->d_name);
        if (dd) closedir(dd);
        long m = set_marker(d, commit[0] ? commit : NULL, "set");
        print_message("  kill %.3f s into the write: exit %d, the folder holds the set of %ld passes%s\n", delay, rc,
                      m, commit[0] ? " (with the commit folder)" : "");
        assert_true(m == marker || m == spp);
        /* what the killed run left behind; a kill that lands after the last rename (the process still exiting)
         * leaves nothing, and then the next run has nothing to report */
        int leftovers = count_named(d, ".tmp.") + count_named(d, ".set.");
        if (commit[0]) commit_sets++;
        else if (m == marker) old_sets++;
        else new_sets++;
        /* the next run cleans up after the killed one; its set is the marker from here */
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --set resolution=32 --set frame_num=%d --spp %ld "
                 "--quiet --output %s", FRAMES, spp + 1, o);
        assert_int_equal(test_run(cmd, out, sizeof out), 0);
        int noted = strstr(out, "left by a run") || strstr(out, "completed the move");
        if (leftovers > 0 && !noted) {
            print_message("  the run after the kill said nothing of the %d files it left:\n", leftovers);
            print_tail(out);
        }
        assert_true(leftovers == 0 || noted);
        assert_int_equal(count_named(d, ".tmp."), 0);
        assert_int_equal(count_named(d, ".set."), 0);
        marker = set_marker(d, NULL, "set");
        assert_int_equal(marker, spp + 1);
    }
    print_message("  5 kills: %d left the old set, %d the new one, %d a commit folder; %d runs had finished\n", old_sets,
                  new_sets, commit_sets, finished);
    assert_true(old_sets >= 1); /* the kills did land inside writes */
}

/* Interrupts during the write of the outputs: the first stops nothing (the passes are done), a second lets the
 * write finish (issue 48: it used to exit with nothing written; tests/render/test_state_integrity.c), and a
 * third means "exit now": the process ends at once, and the temporary file of the write in progress and the
 * staging folder go with it, the previous set staying as it was. Round 0 writes a set and measures the write;
 * rounds 1-3 interrupt three times at 15, 30 and 45 % of it. Before issue 48 two interrupts did this; before
 * that, the temporary files of the frame and the cube being written were left behind. */
static void test_interrupts_during_write(void **state)
{
    const char *d = *state;
    char o[600], frames_s[32];
    snprintf(o, sizeof o, "%s/now.exr", d);
    snprintf(frames_s, sizeof frames_s, "frame_num=%d", FRAMES);
    int left = 0, landed = 0;
    double write_s = 0;
    for (int round = 0; round < 4; round++) {
        const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=64", "--set", frames_s, "--spp", "1",
                              "--quiet", "--output", o, NULL};
        child c;
        child_start(&c, d, argv, NULL, 0);
        char tag[64];
        snprintf(tag, sizeof tag, ".tmp.%ld", (long)c.pid);
        double t0 = now_s(), seen = -1;
        while (seen < 0 && now_s() - t0 < 120) {
            DIR *dd = opendir(d);
            for (struct dirent *e; dd && (e = readdir(dd));)
                if (strstr(e->d_name, tag)) seen = now_s();
            if (dd) closedir(dd);
            if (seen < 0) usleep(1000);
        }
        assert_true(seen >= 0);
        if (round == 0) {
            assert_int_equal(child_wait(&c, 120, NULL), 0);
            write_s = now_s() - seen;
            print_message("  the write takes %.2f s\n", write_s);
            assert_int_equal(set_marker(d, NULL, "now"), 1);
            continue;
        }
        double delay = write_s * 0.15 * round;
        usleep((useconds_t)(delay * 1e6));
        for (int k = 0; k < 3; k++) {
            if (k) usleep(20000);
            kill(c.pid, SIGINT);
        }
        int rc = child_wait(&c, EXIT_BOUND_S * 4, NULL);
        char *log = read_text(c.log);
        int now = strstr(log, "exiting now") != NULL;
        free(log);
        int n = count_named(d, ".tmp.") + count_named(d, ".set.");
        print_message("  three interrupts %.2f s into the write: exit %d, %d temporary entries left\n", delay, rc, n);
        assert_true(rc == 130 || rc == 0); /* 0: the write ended before the interrupts */
        if (rc == 130) {
            assert_true(now);
            landed++;
        }
        assert_int_equal(set_marker(d, NULL, "now"), 1); /* the old set, or the new one (also 1 pass) whole */
        left += n;
    }
    assert_int_equal(left, 0);
    assert_true(landed >= 2);
}

/* The other commands that write: `merge` under a file-size limit below its output's size ends with a
 * message naming the limit, a non-zero exit and no temporary file. Before: killed by SIGXFSZ (exit 153). */
static void test_file_size_limit_merge(void **state)
{
    const char *d = *state;
    char a[600], b[600], o[600];
    snprintf(a, sizeof a, "%s/a.exr", d);
    snprintf(b, sizeof b, "%s/b.exr", d);
    snprintf(o, sizeof o, "%s/m.exr", d);
    image_rgb img;
    dp_error err;
    noise_image(&img, 64, 64); /* 48 KiB of noise: ZIP keeps most of it */
    assert_int_equal(image_write(a, &img, NULL, &err), 0);
    img.rgb[0] += 1.0f; /* two renders, not two copies of one (merge refuses copies) */
    assert_int_equal(image_write(b, &img, NULL, &err), 0);
    image_free(&img);
    const char *argv[] = {DARTSPP_BIN, "merge", o, a, b, NULL};
    child c;
    child_start(&c, d, argv, NULL, 16 * 1024);
    int rc = child_wait(&c, 60.0, NULL);
    char *log = read_text(c.log);
    print_message("  merge under ulimit -f 16: exit %d\n", rc);
    print_tail(log);
    int names_limit = strstr(log, "File too large") && strstr(log, "ulimit -f");
    free(log);
    assert_true(rc >= 1 && rc < 128);
    assert_true(names_limit);
    assert_false(file_exists(o));
    assert_int_equal(count_named(d, ".tmp."), 0);
}

static int setup_dir(void **state)
{
    *state = test_tmpdir();
    return *state ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_sighup_writes_completed_passes, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_file_size_limit, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_file_size_limit_merge, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_interrupts_during_write, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_sigkill_during_frame_write, setup_dir, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
