/* run: alone */
/* The command line as a user meets it when things go wrong: outputs refused before any work, the memory
 * guard, interrupts that end a render within a second and keep exactly the completed passes, the rescue
 * folder when the final write fails, and error exits without leaks (the sanitized binary runs with
 * LeakSanitizer on). Every case runs the real `dartspp render` on the shipped demo scene. */
#include "child_process.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <time.h>

#include "dartspp/io.h"

#define DEMO "scenes/fogbox/fogbox.json"
/* A loose bound for a loaded machine: the stop flag is read every batch of light paths and every row. */
#define EXIT_BOUND_S 5.0







static void rm_rf(const char *dir)
{
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    (void)!system(cmd);
}


/* Every test gets a fresh temporary folder as its state, removed by the teardown even when it fails. */
static int setup_dir(void **state)
{
    *state = test_tmpdir();
    return *state ? 0 : -1;
}

static int teardown_dir(void **state)
{
    rm_rf(*state);
    free(*state);
    return 0;
}

/* ---------------------------------------------------------------------------------------------------- */

/* Bad outputs and plans too big end with exit 2 and a message naming the path or key, at once: the scene
 * asks for a 60 s render, so an exit within seconds shows that no work was spent. */
static void test_refused_before_any_work(void **state)
{
    const char *d = *state;
    char blocker[600], cmd[2048], out[8192];
    snprintf(blocker, sizeof blocker, "%s/blocker", d);
    test_write_file(blocker, "a file where a folder should be\n");
    snprintf(cmd, sizeof cmd, "%s/folder.exr", d);
    assert_int_equal(mkdir(cmd, 0755), 0);
    struct {
        const char *args, *expect[2];
    } cases[] = {
        {"--output %s/x.txt", {"x.txt", ".exr or .pfm"}},
        {"--output %s/blocker/sub/x.exr", {"blocker", "Not a directory"}},
        {"--output %s/folder.exr", {"output is a folder", NULL}},
        {"--output %s/a.exr --set photon_count=1e15", {"integrator.photon_count", "memory"}},
        {"--output %s/a.exr --set frame_num=100000 --set resolution=512", {"integrator.frame_num", NULL}},
        {"--output %s/a.exr --max-memory 1M", {"--max-memory", "drives it"}},
        {"--output %s/a.exr --max-memory 12X", {"--max-memory", "expected a size"}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char args[1024];
        snprintf(args, sizeof args, cases[i].args, d);
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --time 60 --quiet %s", args);
        double t0 = now_s();
        int rc = test_run(cmd, out, sizeof out);
        double dt = now_s() - t0;
        print_message("  %-60s exit %d after %.2f s: ", args + strlen(d) - 2, rc, dt);
        print_tail(out);
        assert_int_equal(rc, 2);
        assert_true(dt < 30.0); /* far less than the 60 s asked for (sanitized binary, loaded machine) */
        for (int k = 0; k < 2; k++)
            if (cases[i].expect[k] && !strstr(out, cases[i].expect[k])) fail_msg("message lacks '%s'", cases[i].expect[k]);
        assert_null(strstr(out, "LeakSanitizer"));
    }
    /* nothing was written by any of them */
    snprintf(cmd, sizeof cmd, "ls -A %s", d);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_string_equal(out, "blocker\nfolder.exr\n");
}

/* Bad input of every kind, in every subcommand, exits 2 with a message and without a leak report. */
static void test_error_exits_without_leaks(void **state)
{
    const char *d = *state;
    char bad_json[600], bad_value[600], cmd[2048], out[8192];
    snprintf(bad_json, sizeof bad_json, "%s/broken.json", d);
    test_write_file(bad_json, "{ \"camera\": { \"type\": \"pinhole\", ");
    snprintf(bad_value, sizeof bad_value, "%s/bad_value.json", d);
    test_write_file(bad_value, "{ \"media\": [ { \"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": -1 } ],"
                               "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8] } }");
    const char *cases[] = {
        "render /nonexistent/scene.json",
        "render %s/broken.json",
        "render %s/bad_value.json",
        "render " DEMO " --bogus",
        "render " DEMO " --threads many",
        "render " DEMO " --set integrator.nope",
        "render " DEMO " --set max_bounces=-3 --output %s/a.exr",
        "render " DEMO " --log %s/log.csv --reference %s/missing.exr --output %s/a.exr",
        "compare /nonexistent/a.exr /nonexistent/b.exr",
        "merge %s/m.exr /nonexistent/a.exr /nonexistent/b.exr",
        "patch-mean /nonexistent/a.exr 0 0 1 1",
        "table --sigma-s -1 --sigma-a 0 --g 0 --output %s/t.bin",
        "frobnicate",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char args[1024];
        snprintf(args, sizeof args, cases[i], d, d, d);
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " %s%s", args, strncmp(args, "render", 6) ? "" : " --quiet");
        int rc = test_run(cmd, out, sizeof out);
        print_message("  exit %d: ", rc);
        print_tail(out);
        assert_int_equal(rc, 2);
        assert_true(strstr(out, "dartspp") != NULL);
        assert_null(strstr(out, "LeakSanitizer"));
        assert_null(strstr(out, "AddressSanitizer"));
    }
}

/* Issue 32: numbers on the command line are what they say. A seed is an exact integer from 0 to 2^64 - 1:
 * before, 1.5 became 1 and every seed past 2^64 - 1 was clamped to it (so "different" seeds rendered the
 * same image); a pass count is a whole number (`--spp 1.5` was truncated, `1e30` overflowed); a thread count is a whole number up to 1024 (10000 threads were accepted on 2 cores: 13x
 * slower). Each ends at once with exit 2 and a message naming the option, writing nothing. And
 * `render --help` prints the render usage on stdout and exits 0 (it was "an unknown option"). */
static void test_numbers_and_help(void **state)
{
    const char *d = *state;
    char cmd[2048], out[8192];
    static const char *const bad[][2] = {
        {"--seed 1.5", "--seed"},
        {"--seed 18446744073709551616", "2^64"},
        {"--seed 1e30", "--seed"},
        {"--seed -1", "--seed"},
        {"--seed 0x10", "--seed"},
        {"--threads 10000", "1024"},
        {"--threads 2.5", "--threads"},
        {"--threads -2", "--threads"},
        {"--spp 1.5", "--spp"},
        {"--spp 1e30", "--spp"},
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --spp 1 --quiet --set resolution=8 %s --output %s/a.exr",
                 bad[i][0], d);
        int rc = test_run(cmd, out, sizeof out);
        print_message("  %-32s exit %d: ", bad[i][0], rc);
        print_tail(out);
        if (rc != 2 || !strstr(out, bad[i][1])) failures++;
        char exr[700];
        snprintf(exr, sizeof exr, "%s/a.exr", d);
        if (file_exists(exr)) {
            print_message("  %s wrote %s\n", bad[i][0], exr);
            failures++;
            unlink(exr);
        }
    }
    /* the largest seed is legal, and seeds that differ only past 2^53 (where a double would merge them) render */
    static const char *const good[] = {"--seed 18446744073709551615", "--seed 9007199254740993", "--threads 1"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --spp 1 --quiet --set resolution=8 --no-cube --no-viewer "
                 "%s --output %s/g%zu.exr", good[i], d, i);
        int rc = test_run(cmd, out, sizeof out);
        print_message("  %-32s exit %d\n", good[i], rc);
        if (rc != 0) {
            print_tail(out);
            failures++;
        }
    }
    snprintf(cmd, sizeof cmd, "(" DARTSPP_BIN " render --help 2>/dev/null)");
    int rc = test_run(cmd, out, sizeof out);
    print_message("  render --help: exit %d: ", rc);
    print_tail(out);
    if (rc != 0 || !strstr(out, "usage: dartspp render") || !strstr(out, "--seed")) failures++;
    if (failures) fail_msg("%d command lines not handled as required", failures);
}

/* Issue 32: a render without --output wrote the demo's 45 files (image, preview, frames, cube, viewer) into the
 * working folder (the repository root for the README's commands). Now they go into one folder named after
 * the scene, in the working folder, and nothing else appears there. */
static void test_default_output_folder(void **state)
{
    const char *d = *state;
    char cwd[1024], cmd[4096], out[8192];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s/" DARTSPP_BIN "' render '%s/" DEMO "' --spp 1 --quiet --set resolution=8 "
             "--set frame_num=3", d, cwd, cwd);
    int rc = test_run(cmd, out, sizeof out);
    print_message("  exit %d: ", rc);
    print_tail(out);
    assert_int_equal(rc, 0);
    snprintf(cmd, sizeof cmd, "ls -A '%s'", d);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    print_message("  the working folder holds: %s", out);
    assert_string_equal(out, "fogbox\n");
    static const char *const files[] = {"fogbox.exr", "fogbox.png", "fogbox_0000.exr", "fogbox_0002.exr",
                                        "fogbox_frames.csv", "fogbox_cube.npy", "fogbox_viewer.html"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[1200];
        snprintf(path, sizeof path, "%s/fogbox/%s", d, files[i]);
        if (!file_exists(path)) fail_msg("%s was not written", path);
    }
}

/* Starts `dartspp render` with extra arguments (NULL-terminated after the scene), waits until it has been
 * in its first pass for `settle` seconds, sends sig, and checks that it ends within EXIT_BOUND_S having
 * stopped the pass in progress. Returns the seconds from the signal to the exit. */
static double interrupt_mid_pass(const char *dir, const char *const *extra, int sig, double settle, int *status)
{
    const char *argv[32] = {DARTSPP_BIN, "render", DEMO, "--seed", "5"};
    int n = 5;
    for (int i = 0; extra[i]; i++) argv[n++] = extra[i];
    argv[n] = NULL;
    child c;
    child_start(&c, dir, argv, NULL, 0);
    /* the CLI says nothing before its first pass ends, so wait long enough for loading and the pilot */
    usleep((useconds_t)(settle * 1e6));
    double t0 = now_s(), waited;
    kill(c.pid, sig);
    *status = child_wait(&c, EXIT_BOUND_S, &waited);
    char *log = read_text(c.log);
    print_message("  signal %d after %.1f s: exit %d, %.3f s after the signal\n", sig, settle, *status, now_s() - t0);
    print_tail(log);
    /* the signal came inside a pass (not while loading, where the CLI exits at once for other reasons) */
    int mid_pass = strstr(log, "stopping the pass in progress") != NULL, leak = strstr(log, "LeakSanitizer") != NULL;
    free(log);
    if (*status < 0) fail_msg("the render did not end within %.0f s of the signal", EXIT_BOUND_S);
    assert_true(mid_pass);
    assert_false(leak);
    return waited;
}

/* SIGINT inside a photon pass of 30 million light paths (minutes under the sanitizers): the stop flag is
 * read once per batch, so the render ends at once; no pass completed, so nothing is written. */
static void test_interrupt_inside_long_photon_pass(void **state)
{
    const char *d = *state;
    char o[600];
    snprintf(o, sizeof o, "%s/long.exr", d);
    /* surface_paths "all": no pilot before the first pass (an interrupt there exits at once, as while preparing) */
    const char *extra[] = {"--set", "photon_count=3e7", "--set", "volume_photon_count=3e7", "--set", "resolution=16",
                           "--set", "surface_paths=all", "--output", o, NULL};
    int rc;
    double dt = interrupt_mid_pass(d, extra, SIGINT, 3.0, &rc);
    assert_true(dt < EXIT_BOUND_S);
    assert_int_equal(rc, 130);
    assert_false(file_exists(o));
}

/* SIGTERM inside the sensor pass of a 4096 × 4096 image (cheap photon pass: 2000 light paths). */
static void test_interrupt_inside_long_sensor_pass(void **state)
{
    const char *d = *state;
    char o[600];
    snprintf(o, sizeof o, "%s/big.exr", d);
    const char *extra[] = {"--set", "photon_count=2000", "--set", "volume_photon_count=2000", "--set",
                           "resolution=4096", "--set", "surface_paths=all", "--output", o, NULL};
    int rc;
    double dt = interrupt_mid_pass(d, extra, SIGTERM, 4.0, &rc);
    assert_true(dt < EXIT_BOUND_S);
    assert_int_equal(rc, 130);
    assert_false(file_exists(o));
}

/* An interrupted render keeps exactly its completed passes: its image is bit-identical to an uninterrupted
 * render of the same seed and that many passes (a partly splatted pass would show). The passes are long
 * enough (about a second under the sanitizers) that the signal lands inside one. */
static void test_interrupt_keeps_completed_passes(void **state)
{
    const char *d = *state;
    char a[600], b[600], cmd[2048], out[8192];
    snprintf(a, sizeof a, "%s/interrupted.exr", d);
    snprintf(b, sizeof b, "%s/straight.exr", d);
    /* surface_paths "all": the passes start at once (the pilot of "auto" takes seconds under the sanitizers) */
    const char *extra[] = {"--set", "resolution=96", "--set", "surface_paths=all", "--spp", "1000", "--threads", "2",
                           "--output", a, NULL};
    int rc;
    interrupt_mid_pass(d, extra, SIGINT, 6.0, &rc);
    assert_int_equal(rc, 130);
    char log[700];
    snprintf(log, sizeof log, "%s/render.log", d);
    char *text = read_text(log);
    const char *r = strstr(text, "rendered ");
    assert_non_null(r);
    long passes = strtol(r + 9, NULL, 10);
    free(text);
    assert_true(passes >= 1);
    assert_true(file_exists(a));
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO " --seed 5 --set resolution=96 --set surface_paths=all --spp %ld --threads 1 --quiet --output %s",
             passes, b);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    image_rgb ia = {0}, ib = {0};
    dp_error err;
    assert_int_equal(image_read(a, &ia, &err), 0);
    assert_int_equal(image_read(b, &ib, &err), 0);
    size_t n = (size_t)ia.width * ia.height * 3, lit = 0;
    assert_int_equal(ia.width, ib.width);
    for (size_t i = 0; i < n; i++) lit += ia.rgb[i] > 0;
    print_message("  %ld completed passes; %zu of %zu values lit\n", passes, lit, n);
    assert_true(lit > n / 10);
    assert_memory_equal(ia.rgb, ib.rgb, n * sizeof(float));
    image_free(&ia);
    image_free(&ib);
}

/* A size as the run summary prints it ("45.0 MiB"), in bytes; -1 for an unknown unit. */
static double summary_bytes(double value, const char *unit)
{
    static const char *units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    for (int i = 0; i < 5; i++)
        if (!strcmp(unit, units[i])) return value * pow(1024.0, i);
    return -1.0;
}

/* The memory guard's estimate against the peak resident size in the run summary, on the optimized binary
 * (the sanitized one's shadow memory would swamp it): the estimate covers the peak and is not far above it.
 * The demo as it is (surface chains, which the pilot batch never reaches, fill the surface map), and with a
 * wide first volume radius and chains off (the splat's photon-in-tile entries: 6 passes, 23 s, where the
 * first pass's radius is the largest). 2 threads and 24 passes of the demo: a heap that grew pass after pass
 * (as it did with huge-page arrays in a heap that is never trimmed) would take the peak over the estimate.
 * A path-traced 8 × 8 render: nearly all of its peak is the runtime's own (the libraries, the threads); the
 * estimate's runtime term of 9.0 MiB fell 1.7 MiB short of it (10.7 MiB, 2026-11-28).
 * Broken variant: the splat's item left out of the estimate, the second case's estimate 43.6 MiB against a
 * peak of 55.1 MiB fails (at 64 × 64 pixels it would not: 39.4 against 39.2). */
static void test_memory_estimate_covers_peak(void **state)
{
    const char *d = *state;
    const char *cases[] = {"--spp 24", "--spp 6 --set volume_photon_count=140000 --set photon_count=300000 "
                                       "--set volume_gather_radius=0.3 --set surface_chains=false",
                           "--spp 2 --set type=path_tracer --set resolution=8"};
    for (int c = 0; c < 3; c++) {
        char cmd[900], out[16384], u_est[8], u_peak[8];
        snprintf(cmd, sizeof cmd, ONE_BIN " render " DEMO " --threads 2 --quiet --no-cube --no-viewer --overwrite "
                 "--output %s/m.exr %s", d, cases[c]);
        assert_int_equal(test_run(cmd, out, sizeof out), 0);
        const char *m = strstr(out, "memory: estimated ");
        assert_non_null(m);
        double est, peak;
        assert_int_equal(sscanf(m, "memory: estimated %lf %7s before the render, peak resident %lf %7s", &est, u_est, &peak,
                                u_peak), 4);
        est = summary_bytes(est, u_est);
        peak = summary_bytes(peak, u_peak);
        print_message("  [%s] estimate %.1f MiB, peak resident %.1f MiB (%.2f)\n", cases[c], est / 1048576.0,
                      peak / 1048576.0, peak / est);
        assert_true(est > 0.0 && peak > 0.0);
        assert_true(peak <= est);
        assert_true(est <= 2.0 * peak);
    }
}

/* Before the first pass there is nothing to keep: an interrupt while an EDA table is being built (tens of
 * seconds) exits at once. */
static void test_interrupt_while_preparing(void **state)
{
    const char *d = *state;
    char o[600], tables[700], set_dir[800];
    snprintf(o, sizeof o, "%s/eda.exr", d);
    snprintf(tables, sizeof tables, "%s/tables", d);
    snprintf(set_dir, sizeof set_dir, "eda_table_dir=%s", tables);
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "eda=true", "--set", "eda_shape=[256,256,256]", "--set",
                          set_dir, "--output", o, NULL};
    child c;
    child_start(&c, d, argv, NULL, 0);
    assert_true(log_wait_for(&c, "EDA", 20.0)); /* the table build announces itself */
    double waited;
    kill(c.pid, SIGINT);
    int rc = child_wait(&c, EXIT_BOUND_S, &waited);
    char *log = read_text(c.log);
    print_message("  exit %d, %.3f s after the signal\n", rc, waited);
    print_tail(log);
    int now = strstr(log, "exiting now") != NULL;
    free(log);
    assert_int_equal(rc, 130);
    assert_true(now);
    assert_false(file_exists(o));
}

/* The output folder is replaced by a file while the render runs: the final write fails, the images go to a
 * rescue folder under $TMPDIR whose path is printed, and the exit status is 1. A folder that is merely
 * removed is created again. */
static void test_rescue_when_output_folder_disappears(void **state)
{
    const char *d = *state;
    char folder[600], o[700], rescue_tmp[600];
    snprintf(folder, sizeof folder, "%s/renders", d);
    snprintf(o, sizeof o, "%s/renders/fog.exr", d);
    snprintf(rescue_tmp, sizeof rescue_tmp, "%s/tmp", d);
    assert_int_equal(mkdir(rescue_tmp, 0755), 0);
    for (int replace = 0; replace < 2; replace++) {
        const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=32", "--time", "4", "--quiet",
                              "--output", o, NULL};
        child c;
        child_start(&c, d, argv, rescue_tmp, 0);
        usleep(1500000);
        rm_rf(folder);
        if (replace) test_write_file(folder, "not a folder any more\n");
        double waited;
        int rc = child_wait(&c, 60.0, &waited);
        char *log = read_text(c.log), rescued[900] = "";
        print_message("  folder %s: exit %d\n", replace ? "replaced by a file" : "removed", rc);
        print_tail(log);
        const char *w = strstr(log, "were written to ");
        if (w) snprintf(rescued, sizeof rescued, "%.*s/fog.exr", (int)strcspn(w + 16, " \n"), w + 16);
        free(log);
        if (!replace) {
            assert_int_equal(rc, 0);
            assert_true(file_exists(o));
            continue;
        }
        assert_int_equal(rc, 1);
        assert_true(strncmp(rescued, rescue_tmp, strlen(rescue_tmp)) == 0);
        image_rgb img = {0};
        dp_error err;
        assert_int_equal(image_read(rescued, &img, &err), 0);
        double sum = 0;
        size_t bad = 0;
        for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++) {
            bad += !isfinite(img.rgb[i]);
            sum += img.rgb[i];
        }
        image_free(&img);
        assert_int_equal(bad, 0);
        assert_true(sum > 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_refused_before_any_work, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_error_exits_without_leaks, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_numbers_and_help, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_default_output_folder, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_interrupt_inside_long_photon_pass, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_interrupt_inside_long_sensor_pass, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_interrupt_keeps_completed_passes, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_interrupt_while_preparing, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_memory_estimate_covers_peak, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_rescue_when_output_folder_disappears, setup_dir, teardown_dir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
