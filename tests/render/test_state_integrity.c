/* The checkpoint state cannot lie (issue 48): an edited header field (weight sum, pass count, seed) is refused
 * as damaged; a state of another scene (its light made a spot, its camera moved, a material's albedo changed)
 * is refused naming what differs; a second run on a state in use is refused naming the first one's process,
 * and a lock left by a killed run does not block; --resume refuses a state older than the images beside it;
 * the rescue folder gets the state with the images and resumes; a second Ctrl-C during the final write lets
 * the write finish. Each refusal is exit 2 with the state file named and the image untouched. The real
 * sanitized binary on the demo scene at 16x16: what is checked is what it refuses and writes, no pixel value. */
#include "child_process.h"
#include "fixtures.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "dartspp/io.h"

#define DEMO "scenes/fogbox/fogbox.json"
/* small photon counts: a pass takes a few tens of milliseconds under the sanitizers */
#define ARGS " --set resolution=16 --set photon_count=20000 --set volume_photon_count=3000 --seed 11 --threads 2" \
             " --quiet"

static int setup_dir(void **state)
{
    *state = test_tmpdir();
    return *state ? 0 : -1;
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

/* A render of `spp` passes of scene to dir/name.exr with a checkpoint after every pass (so a state). */
static void render_state(const char *scene, const char *d, const char *name, int spp, const char *extra)
{
    char cmd[2048], out[16384];
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render %s" ARGS " --spp %d --checkpoint 1e-9 %s --output %s/%s.exr", scene,
             spp, extra, d, name);
    if (run(cmd, out, sizeof out)) {
        print_tail(out);
        fail_msg("%s failed", cmd);
    }
}

/* --resume of dir/name.exr with scene: must be refused (exit 2) naming the state and saying `expect`, with the
 * image and the state as they were. */
static void assert_resume_refused(const char *scene, const char *d, const char *name, const char *extra,
                                  const char *expect)
{
    char cmd[2048], out[16384], img[600], st[600];
    snprintf(img, sizeof img, "%s/%s.exr", d, name);
    snprintf(st, sizeof st, "%s/%s.state", d, name);
    size_t ni = 0, ns = 0, mi = 0, ms = 0;
    char *before = read_all(img, &ni), *sbefore = read_all(st, &ns);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render %s" ARGS " --spp 6 --resume %s --output %s", scene, extra, img);
    int rc = run(cmd, out, sizeof out);
    print_message("  %s: exit %d: ", expect, rc);
    print_tail(out);
    assert_int_equal(rc, 2);
    if (!strstr(out, expect)) fail_msg("the message lacks '%s'", expect);
    if (!strstr(out, st)) fail_msg("the message lacks the state file %s", st);
    char *after = read_all(img, &mi), *safter = read_all(st, &ms);
    assert_true(before && after && ni == mi && !memcmp(before, after, ni)); /* nothing rendered over it */
    assert_true(sbefore && safter && ns == ms && !memcmp(sbefore, safter, ns));
    free(before), free(after), free(sbefore), free(safter);
}

/* The state's text line starting with `key ` replaced by `line` (the sums after the header untouched). */
static void edit_line(const char *path, const char *key, const char *line)
{
    size_t n = 0;
    char *s = read_all(path, &n);
    assert_non_null(s);
    char pat[64];
    snprintf(pat, sizeof pat, "\n%s ", key);
    char *at = strstr(s, pat);
    if (!at) fail_msg("%s has no line '%s'", path, key);
    at++;
    char *end = strchr(at, '\n');
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(s, 1, (size_t)(at - s), f);
    fputs(line, f);
    fwrite(end, 1, n - (size_t)(end - s), f);
    fclose(f);
    free(s);
}

/* The edits of the header: weight_sum halved (p+1 → p+0: the image 2x too bright), 0 (black), passes
 * 3 → 2, seed 11 → 12 resumed with --seed 12; each refused as damaged. Main resumed the first three and, with
 * the matching --seed, the fourth. */
static void test_edited_header_refused(void **state)
{
    const char *d = *state;
    char st[600], copy[700];
    render_state(DEMO, d, "h", 3, "");
    snprintf(st, sizeof st, "%s/h.state", d);
    snprintf(copy, sizeof copy, "%s/h.orig", d);
    size_t n = 0;
    char *orig = read_all(st, &n);
    assert_non_null(orig);
    const char *ws = strstr(orig, "\nweight_sum ");
    assert_non_null(ws);
    char halved[128];
    snprintf(halved, sizeof halved, "%.*s", (int)strcspn(ws + 1, "\n"), ws + 1);
    char *p = strstr(halved, "p+");
    if (!p || p[2] == '0') fail_msg("weight_sum '%s' is not of the form ...p+k with k > 0", halved);
    p[2] = (char)(p[2] - 1);
    const char *edits[][3] = {
        {"weight_sum", halved, ""},
        {"weight_sum", "weight_sum 0x0p+0", ""},
        {"passes", "passes 2", ""},
        {"seed", "seed 12", "--seed 12"},
    };
    for (size_t i = 0; i < sizeof edits / sizeof edits[0]; i++) {
        write_bytes(st, orig, n);
        edit_line(st, edits[i][0], edits[i][1]);
        print_message("  '%s':", edits[i][1]);
        assert_resume_refused(DEMO, d, "h", edits[i][2], "damaged");
    }
    free(orig);
}

/* The demo scene with one substitution; written into d as name. */
static void write_variant(const char *d, const char *name, const char *from, const char *to)
{
    size_t n = 0;
    char *s = read_all(DEMO, &n), path[600];
    assert_non_null(s);
    char *v = replace1(s, from, to);
    if (!v) fail_msg("the demo scene has no '%s'", from);
    snprintf(path, sizeof path, "%s/%s", d, name);
    write_bytes(path, v, strlen(v));
    free(s);
    free(v);
}

/* A state of the demo resumed with another scene: the case (the point light made a spot), the camera
 * moved, the walls' albedo changed; each refused naming that part. The same scene at another path (a copy)
 * resumes. Main blended all three. */
static void test_other_scene_refused(void **state)
{
    const char *d = *state;
    char cmd[2048], out[16384], path[600];
    render_state(DEMO, d, "s", 3, "");
    struct {
        const char *name, *from, *to, *part;
    } v[] = {
        {"spot.json", "\"type\": \"point\",", "\"type\": \"spot\", \"coneangle\": 60,", "lights"},
        {"moved.json", "\"position\": [0, 1, -3.5]", "\"position\": [0, 1.02, -3.5]", "camera"},
        {"albedo.json", "\"albedo\": 0.75", "\"albedo\": 0.7", "materials"},
    };
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        write_variant(d, v[i].name, v[i].from, v[i].to);
        snprintf(path, sizeof path, "%s/%s", d, v[i].name);
        char expect[96];
        snprintf(expect, sizeof expect, "another scene (this run's scene differs in: %s)", v[i].part);
        assert_resume_refused(path, d, "s", "", expect);
    }
    write_variant(d, "same.json", "\"type\": \"point\",", "\"type\": \"point\",");
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render %s/same.json" ARGS " --spp 4 --resume --output %s/s.exr", d, d);
    int rc = run(cmd, out, sizeof out);
    if (rc) print_tail(out);
    assert_int_equal(rc, 0);
    snprintf(path, sizeof path, "%s/s.exr", d);
    assert_int_equal(exr_passes(path), 4);
}

/* A resumed render holding the state (many passes, one thread): a second --resume, a fresh render to the
 * same output with checkpoints, and one without any (it would replace the images), are refused naming the first
 * one's process id; once the first is SIGKILLed,
 * its lock file is left but blocks nothing. Main ran both to exit 0, the shorter overwriting the longer. */
static void test_lock(void **state)
{
    const char *d = *state;
    char cmd[2048], out[16384], lock[600], pid[32], img[600];
    render_state(DEMO, d, "l", 1, "");
    snprintf(img, sizeof img, "%s/l.exr", d);
    snprintf(lock, sizeof lock, "%s/l.state.lock", d);
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=16", "--set", "photon_count=20000", "--set",
                          "volume_photon_count=3000", "--seed", "11", "--threads", "1", "--spp", "100000", "--resume",
                          "--output", img, NULL};
    child c;
    child_start(&c, d, argv, NULL, 0);
    if (!log_wait_for(&c, "resuming", 60)) fail_msg("the first render did not start");
    snprintf(pid, sizeof pid, "process %d", (int)c.pid);
    /* the third: a render that writes no state (no checkpoints, no --resume) to the same output; before the
     * lock covered every render it ran to exit 0 and replaced the running render's images (campaign-48/state.md,
     * probe 23) */
    const char *second[] = {"--spp 6 --resume", "--spp 200000 --checkpoint 1", "--spp 2 --overwrite"};
    for (int i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO ARGS " %s --output %s", second[i], img);
        int rc = run(cmd, out, sizeof out);
        print_message("  second run (%s) while the first runs: exit %d: ", second[i], rc);
        print_tail(out);
        assert_int_equal(rc, 2);
        if (!strstr(out, "is in use") || !strstr(out, pid)) fail_msg("the message must say in use by %s", pid);
    }
    kill(c.pid, SIGKILL);
    child_wait(&c, 20, NULL);
    assert_true(file_exists(lock)); /* left by the killed run */
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO ARGS " --spp 3 --resume --output %s", img);
    int rc = run(cmd, out, sizeof out);
    if (rc) print_tail(out);
    assert_int_equal(rc, 0);
    assert_int_equal(exr_passes(img), 3);
    assert_false(file_exists(lock)); /* removed at the end of the run */
}

/* A checkpointed render of 3 passes, then the same output rendered to 6 passes without checkpoints (no state
 * written: the state still holds 3): --resume is refused, naming both counts, and --resume --overwrite goes
 * ahead. Main resumed from the 3 passes and replaced the 6-pass image. */
static void test_stale_state_refused(void **state)
{
    const char *d = *state;
    char cmd[2048], out[16384], img[600];
    render_state(DEMO, d, "t", 3, "");
    snprintf(img, sizeof img, "%s/t.exr", d);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO ARGS " --spp 6 --output %s", img);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_int_equal(exr_passes(img), 6);
    assert_resume_refused(DEMO, d, "t", "--spp 8", "holds 6 passes but its checkpoint state");
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO ARGS " --spp 7 --resume --overwrite --output %s", img);
    int rc = run(cmd, out, sizeof out);
    if (rc) print_tail(out);
    assert_int_equal(rc, 0);
    assert_int_equal(exr_passes(img), 7);
}

/* The output folder replaced by a file while a resumed render runs (no checkpoints: nothing recreates the folder
 * before the end): the final write fails, the images and the state go to the rescue folder, the message says
 * so, and --resume from there continues it. Main wrote the images there without the state. */
static void test_rescue_keeps_state(void **state)
{
    const char *d = *state;
    char folder[600], o[700], tmp[600], cmd[2048], out[16384];
    snprintf(folder, sizeof folder, "%s/renders", d);
    snprintf(o, sizeof o, "%s/renders/fog.exr", d);
    snprintf(tmp, sizeof tmp, "%s/tmp", d);
    assert_int_equal(mkdir(tmp, 0755), 0);
    assert_int_equal(mkdir(folder, 0755), 0);
    render_state(DEMO, folder, "fog", 1, "");
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=16", "--set", "photon_count=20000", "--set",
                          "volume_photon_count=3000", "--seed", "11", "--threads", "1", "--time", "3", "--resume",
                          "--quiet", "--output", o, NULL};
    child c;
    child_start(&c, d, argv, tmp, 0);
    usleep(1200000);
    rm_rf(folder);
    test_write_file(folder, "not a folder any more\n");
    int rc = child_wait(&c, 60.0, NULL);
    char *log = read_text(c.log), rescued[900] = "", st[900];
    print_message("  output folder replaced by a file: exit %d: ", rc);
    print_tail(log);
    const char *w = strstr(log, "were written to ");
    if (w) snprintf(rescued, sizeof rescued, "%.*s/fog.exr", (int)strcspn(w + 16, " \n"), w + 16);
    int said = strstr(log, "and their checkpoint state were written to") != NULL;
    free(log);
    assert_int_equal(rc, 1);
    assert_true(strncmp(rescued, tmp, strlen(tmp)) == 0);
    if (!said) fail_msg("the message does not say that the state went with the images");
    long passes = exr_passes(rescued);
    snprintf(st, sizeof st, "%.*s.state", (int)(strlen(rescued) - 4), rescued);
    assert_true(passes > 0);
    assert_int_equal(state_passes(st), passes);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " render " DEMO ARGS " --spp %ld --resume --output %s", passes + 1, rescued);
    rc = run(cmd, out, sizeof out);
    if (rc) print_tail(out);
    assert_int_equal(rc, 0);
    assert_int_equal(exr_passes(rescued), passes + 1);
}

/* Ctrl-C, then Ctrl-C again once the final write has begun (a frame set: its staging folder exists): the write
 * finishes, exit 130, and the images hold the completed passes. Main exited at the second Ctrl-C with nothing
 * written. */
static void test_second_interrupt_during_write(void **state)
{
    const char *d = *state;
    char o[600], staging[700], cube[600];
    snprintf(o, sizeof o, "%s/f.pfm", d);
    snprintf(cube, sizeof cube, "%s/f_cube.npy", d);
    const char *argv[] = {DARTSPP_BIN, "render", DEMO, "--set", "resolution=16", "--set", "frame_num=600",
                          "--set", "start_time=6.45", "--set", "type=path_tracer", "--seed", "11", "--threads", "1",
                          "--spp", "100000", "--output", o, NULL};
    child c;
    child_start(&c, d, argv, NULL, 0);
    if (!log_wait_for(&c, "pass 1", 60)) fail_msg("no progress line");
    kill(c.pid, SIGINT);
    snprintf(staging, sizeof staging, "%s/.f.set.tmp.%d", d, (int)c.pid);
    double t0 = now_s();
    while (!file_exists(staging) && now_s() - t0 < 30 && waitpid(c.pid, NULL, WNOHANG) == 0) usleep(1000);
    if (!file_exists(staging)) fail_msg("the write was not caught in progress (%s)", staging);
    kill(c.pid, SIGINT);
    int rc = child_wait(&c, 120, NULL);
    char *log = read_text(c.log);
    print_message("  second SIGINT during the write: exit %d: ", rc);
    print_tail(log);
    int said = strstr(log, "the write finishes first") != NULL;
    free(log);
    assert_int_equal(rc, 130);
    assert_true(said);
    assert_true(file_exists(o));
    assert_true(file_exists(cube));
    assert_false(file_exists(staging));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_edited_header_refused, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_other_scene_refused, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_lock, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_stale_state_refused, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_rescue_keeps_state, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_second_interrupt_during_write, setup_dir, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
