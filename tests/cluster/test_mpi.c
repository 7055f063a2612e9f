/* dartspp-mpi against one process (`mpirun --oversubscribe`, Open MPI): the same image for the same seed and
 * pass count (photon points and photon beams with and without DARTS, the path tracer, gate and frames) within the bound the
 * accumulation allows, --time with 2 ranks, Ctrl-C on mpirun, and a rank that cannot read its scene.
 * Both binaries are the release build (the same objects, so the same arithmetic). */
#include "child_process.h"
#include "fixtures.h"

#include <sys/time.h>

#include "dartspp/io.h"

static double now(void)
{
    struct timeval tv;
    gettimeofday(&tv, NULL);
    return tv.tv_sec + 1e-6 * tv.tv_usec;
}

/* `sets` rendered by one process and by 3 ranks, K passes, the same seed: the gate image within 2 float
 * ulps (its sums are doubles, added in another order: about 1e-16 relative before the float cast) and each
 * frame within 2K float ulps (frame sums are floats: K additions in a different order). */
static void one_vs_three(const char *name, const char *sets, int frames)
{
    const long K = 5;
    char cmd[4096], out[16384], a[1100], b[1100];
    snprintf(a, sizeof a, "%s/%s-one.exr", cbox_dir, name);
    snprintf(b, sizeof b, "%s/%s-mpi.exr", cbox_dir, name);
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json --threads 1 --spp %ld --seed 9 %s --quiet --output %s", cbox_dir, K,
             sets, a);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    snprintf(cmd, sizeof cmd, MPIRUN " -np 3 " MPI_BIN " render %s/box.json --threads 1 --spp %ld --seed 9 %s --quiet --output %s",
             cbox_dir, K, sets, b);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    assert_int_equal(exr_passes(a), K);
    assert_int_equal(exr_passes(b), K);
    double gate = image_max_rel_diff(b, a);
    print_message("  %-26s gate image: largest relative difference %.3g (bound %.3g)\n", name, gate, 2 * 0x1p-24);
    assert_true(gate <= 2 * 0x1p-24);
    for (int k = 0; k < frames; k++) {
        char fa[1200], fb[1200];
        snprintf(fa, sizeof fa, "%s/%s-one_%04d.exr", cbox_dir, name, k);
        snprintf(fb, sizeof fb, "%s/%s-mpi_%04d.exr", cbox_dir, name, k);
        double d = image_max_rel_diff(fb, fa);
        print_message("  %-26s frame %d: %.3g (bound %.3g)\n", name, k, d, 2.0 * K * 0x1p-24);
        assert_true(d <= 2.0 * K * 0x1p-24);
    }
}

/* The largest |a − b| over two images of signed values (a derivative image) relative to b's largest |value|, b not
 * zero everywhere. Not per pixel: a frame layer is a float sum of signed contributions, rounded in another order
 * on each rank, and where they cancel a pixel's own value is far below the rounding of its terms (2026-11-28:
 * 2.84e-6 of one pixel of the σs derivative's frame, 3 ranks against one). */
static double signed_max_rel_diff(const char *a_path, const char *b_path)
{
    image_rgb a = {0}, b = {0};
    dp_error err;
    if (image_read(a_path, &a, &err) || image_read(b_path, &b, &err)) fail_msg("%s", err.msg);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    double m = 0.0, mag = 0.0;
    for (size_t i = 0; i < (size_t)a.width * a.height * 3; i++) {
        assert_true(isfinite(a.rgb[i]) && isfinite(b.rgb[i]));
        m = fmax(m, fabs((double)a.rgb[i] - b.rgb[i]));
        mag = fmax(mag, fabs((double)b.rgb[i]));
    }
    if (!(mag > 0.0)) fail_msg("%s is zero everywhere: the comparison would prove nothing", b_path);
    image_free(&a);
    image_free(&b);
    return m / mag;
}

/* The derivative images (docs/derivatives.md §5) of the path tracer with a gate and with frames, 3 ranks
 * against one process: each derivative film is reduced as the image's, so the same bounds hold, relative to each
 * image's largest value (signed_max_rel_diff) (a positive
 * albedo derivative and a signed σs one, in the order asked). Broken variant (tests/README.md): the
 * derivative films not reduced (rank 0's zeros) fails at relative difference 1. */
static void test_derivatives_as_one_process(void **state)
{
    (void)state;
    const long K = 5;
    const char *cases[][3] = {
        {"deriv-gate", "--set type=path_tracer --set transient_time_center=15 --set transient_time_width=2", "0"},
        {"deriv-frames", "--set type=path_tracer --set frame_num=2 --set start_time=14 --set transient_time_width=2", "2"},
    };
    for (int c = 0; c < 2; c++) {
        char sets[1024];
        snprintf(sets, sizeof sets, "%s --derivative /bsdfs/0/albedo --derivative /media/0/sigma_s", cases[c][1]);
        one_vs_three(cases[c][0], sets, atoi(cases[c][2]));
        for (int k = 0; k < 2; k++)
            for (int f = -1; f < atoi(cases[c][2]); f++) {
                char fa[1200], fb[1200], tail[32];
                if (f < 0) snprintf(tail, sizeof tail, "_d%d", k);
                else snprintf(tail, sizeof tail, "_d%d_%04d", k, f);
                snprintf(fa, sizeof fa, "%s/%s-one%s.exr", cbox_dir, cases[c][0], tail);
                snprintf(fb, sizeof fb, "%s/%s-mpi%s.exr", cbox_dir, cases[c][0], tail);
                double bound = f < 0 ? 2 * 0x1p-24 : 2.0 * K * 0x1p-24, d = signed_max_rel_diff(fb, fa);
                print_message("  %-26s %s: %.3g (bound %.3g)\n", cases[c][0], tail + 1, d, bound);
                assert_true(d <= bound);
            }
    }
}

/* The float32 values of a .npy file written by dartspp (complex64 read as its float pairs) into *n floats. */
static float *npy_floats(const char *path, size_t *n)
{
    size_t len = 0;
    char *b = read_all(path, &len);
    if (!b || len < 10) fail_msg("cannot read %s", path);
    size_t head = 10 + ((size_t)(unsigned char)b[8] | (size_t)(unsigned char)b[9] << 8);
    *n = (len - head) / 4;
    float *v = malloc(*n * sizeof *v + 1);
    assert_non_null(v);
    memcpy(v, b + head, *n * sizeof *v);
    free(b);
    return v;
}

/* The AMCW sums (docs/amcw.md) of the path tracer with a gate, 3 ranks against one process: reduced as the
 * image's (doubles), so within 2 float ulps of the largest |value| (signed parts: relative to the largest, as
 * signed_max_rel_diff), and the depth within 2 ulps of the largest depth. Broken variant (tests/README.md): the
 * AMCW sums not reduced (rank 0's zeros) fails at relative difference 1. */
static void test_amcw_as_one_process(void **state)
{
    (void)state;
    one_vs_three("amcw-gate", "--set type=path_tracer --set transient_time_center=15 --set transient_time_width=2 "
                 "--set amcw_frequencies=[20,300]", 0);
    for (int k = 0; k < 2; k++) {
        char fa[1200], fb[1200];
        snprintf(fa, sizeof fa, "%s/amcw-gate-one_%s.npy", cbox_dir, k ? "amcw_depth" : "amcw");
        snprintf(fb, sizeof fb, "%s/amcw-gate-mpi_%s.npy", cbox_dir, k ? "amcw_depth" : "amcw");
        size_t na, nb;
        float *a = npy_floats(fa, &na), *b = npy_floats(fb, &nb);
        assert_int_equal(na, nb);
        double m = 0.0, mag = 0.0;
        for (size_t i = 0; i < na; i++) {
            m = fmax(m, fabs((double)a[i] - b[i]));
            mag = fmax(mag, fabs((double)a[i]));
        }
        free(a);
        free(b);
        if (!(mag > 0.0)) fail_msg("%s is zero everywhere: the comparison would prove nothing", fa);
        print_message("  amcw-gate %s: largest difference %.3g of the largest value (bound %.3g)\n",
                      k ? "depth" : "values", m / mag, 2 * 0x1p-24);
        assert_true(m / mag <= 2 * 0x1p-24);
    }
}

static void test_same_image_as_one_process(void **state)
{
    (void)state;
    const char *small = "--set photon_count=20000 --set volume_photon_count=3000";
    char sets[1024];
    snprintf(sets, sizeof sets, "%s", small);
    one_vs_three("darts-gate", sets, 0);
    snprintf(sets, sizeof sets, "%s --set enable_guiding=false --set enable_elliptical=false", small);
    one_vs_three("baseline-gate", sets, 0);
    snprintf(sets, sizeof sets, "%s --set frame_num=3 --set start_time=15.95 --set transient_time_width=0.1", small);
    one_vs_three("darts-frames", sets, 3);
    /* photon beams (docs/beams.md), baseline and DARTS-fed: the beam map is built from the same beams on
     * every rank */
    snprintf(sets, sizeof sets, "%s --set volume_photon_type=beams --set enable_guiding=false --set enable_elliptical=false",
             small);
    one_vs_three("beams-gate", sets, 0);
    snprintf(sets, sizeof sets, "%s --set volume_photon_type=beams --set frame_num=2 --set start_time=15.95 "
             "--set transient_time_width=0.1", small);
    one_vs_three("darts-beams-frames", sets, 2);
    /* a delta gate (docs/time.md §3.1): each rank sets its film's box to the width of the iteration it renders
     * (k·N + r), and the pass weights follow the iteration index, so 3 ranks sum to one process's passes */
    const char *delta = "--set delta_time_gate=true --set transient_time_width=0.4 --set enable_guiding=false "
                        "--set enable_elliptical=false --set strict_time_width=false";
    snprintf(sets, sizeof sets, "%s --set volume_photon_type=beams %s", small, delta);
    one_vs_three("beams-delta", sets, 0);
    snprintf(sets, sizeof sets, "%s --set volume_photon_type=points %s", small, delta);
    one_vs_three("points-delta", sets, 0);
    one_vs_three("path-tracer-frames", "--set type=path_tracer --set frame_num=2 --set start_time=14 --set transient_time_width=2", 2);
}

/* --time 3 with 2 ranks: every rank stops after the same round, within a pass of the budget; the pass
 * count reported is the sum over the ranks (even: each round adds one pass per rank) and is the image's.
 * With --checkpoint 1 rank 0 writes checkpoints of the films summed over both ranks (even pass counts). */
static void test_time_budget_two_ranks(void **state)
{
    (void)state;
    char cmd[4096], out[16384], img[1100];
    snprintf(img, sizeof img, "%s/timed.exr", cbox_dir);
    snprintf(cmd, sizeof cmd,
             MPIRUN " -np 2 " MPI_BIN " render %s/box.json --threads 1 --time 3 --seed 4 --set photon_count=20000 "
                    "--set volume_photon_count=3000 --checkpoint 1 --output %s",
             cbox_dir, img);
    double t0 = now();
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    double wall = now() - t0;
    long reported = -1;
    double secs = -1;
    const char *r = strstr(out, "rendered ");
    assert_non_null(r);
    assert_int_equal(sscanf(r, "rendered %ld passes in %lf s", &reported, &secs), 2);
    print_message("  2 ranks, --time 3: %ld passes in %.2f s of rendering, %.2f s in all\n", reported, secs, wall);
    assert_true(reported >= 2 && reported % 2 == 0);
    assert_int_equal(exr_passes(img), reported);
    double per_round = secs / (reported / 2);
    assert_true(secs <= 3.0 + per_round + 0.5);
    assert_true(secs >= 3.0 - 1.5 * per_round);
    int checkpoints = 0;
    for (const char *c = strstr(out, "checkpoint: "); c; c = strstr(c + 1, "checkpoint: ")) {
        long n = -1;
        assert_int_equal(sscanf(c, "checkpoint: %ld passes", &n), 1);
        assert_true(n >= 2 && n % 2 == 0 && n <= reported);
        checkpoints++;
    }
    print_message("  %d checkpoints\n", checkpoints);
    assert_true(checkpoints >= 1);
}

/* Ctrl-C on mpirun while rendering: the image written holds the passes reported. */
static void test_interrupt_writes_completed_passes(void **state)
{
    (void)state;
    char cmd[4096], out[16384], img[1100];
    snprintf(img, sizeof img, "%s/interrupted.exr", cbox_dir);
    snprintf(cmd, sizeof cmd,
             "sh -c '" MPIRUN " -np 2 " MPI_BIN " render %s/box.json --threads 1 --time 60 --seed 5 --set photon_count=20000 "
             "--set volume_photon_count=3000 --output %s & pid=$!; sleep 4; kill -INT $pid; wait $pid; echo exit=$?'",
             cbox_dir, img);
    double t0 = now();
    test_run(cmd, out, sizeof out);
    double wall = now() - t0;
    const char *r = strstr(out, "rendered ");
    if (!r) fail_msg("no summary after the interrupt:\n%s", out);
    long reported = -1;
    assert_int_equal(sscanf(r, "rendered %ld passes", &reported), 1);
    print_message("  interrupted after 4 s: %ld passes reported, %.1f s in all\n", reported, wall);
    assert_true(reported >= 2);
    assert_int_equal(exr_passes(img), reported);
    assert_true(wall < 20.0);
    assert_non_null(strstr(out, "exit="));
}

/* The memory guard counts the ranks sharing the machine: a --max-memory that holds one process's estimate
 * 1.5 times over lets one process render and refuses 2 ranks (exit 2) before any work. */
static void test_memory_guard_counts_ranks(void **state)
{
    (void)state;
    char cmd[4096], out[16384], img[1100];
    snprintf(img, sizeof img, "%s/mem.exr", cbox_dir);
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json --threads 1 --spp 1 --output %s", cbox_dir, img);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    const char *m = strstr(out, "memory: estimated ");
    assert_non_null(m);
    double v = 0;
    char unit[8] = "";
    assert_int_equal(sscanf(m, "memory: estimated %lf %7s", &v, unit), 2);
    double bytes = v * (!strcmp(unit, "GiB") ? 1073741824.0 : !strcmp(unit, "MiB") ? 1048576.0 : 1024.0);
    long limit = (long)(1.5 * bytes);
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json --threads 1 --spp 1 --max-memory %ld --quiet --output %s", cbox_dir,
             limit, img);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("one process under --max-memory %ld: %s", limit, out);
    snprintf(cmd, sizeof cmd, MPIRUN " -np 2 " MPI_BIN " render %s/box.json --threads 1 --spp 1 --max-memory %ld --quiet --output %s",
             cbox_dir, limit, img);
    int rc = test_run(cmd, out, sizeof out);
    if (rc != 2) fail_msg("2 ranks under --max-memory %ld: exit %d, expected 2:\n%s", limit, rc, out);
    assert_non_null(strstr(out, "each of the ranks on this machine"));
}

/* mpirun's multiple-program form: rank 1 is given a scene that does not exist; the job ends with exit 2,
 * the message names the file, and nothing is written. The same when rank 0 cannot read the error log's
 * reference, and when a rank cannot load its EDA table as the render starts (exit 2: a damaged table file). */
static void test_rank_without_scene(void **state)
{
    (void)state;
    char cmd[4096], out[16384], img[1100];
    snprintf(img, sizeof img, "%s/never.exr", cbox_dir);
    snprintf(cmd, sizeof cmd,
             MPIRUN " -np 1 " MPI_BIN " render %s/box.json --spp 2 --quiet --output %s : -np 1 " MPI_BIN
                    " render %s/missing.json --spp 2 --quiet --output %s",
             cbox_dir, img, cbox_dir, img);
    int rc = test_run(cmd, out, sizeof out);
    if (rc != 2) fail_msg("exit %d, expected 2:\n%s", rc, out);
    assert_non_null(strstr(out, "missing.json"));
    assert_int_equal(access(img, F_OK), -1);
    /* rank 0 alone reads the error log's reference: when it cannot, the other ranks do not start either */
    snprintf(cmd, sizeof cmd,
             "timeout 60 " MPIRUN " -np 2 " MPI_BIN " render %s/box.json --spp 2 --quiet --reference %s/missing.exr --log %s/log.csv "
             "--output %s",
             cbox_dir, cbox_dir, cbox_dir, img);
    rc = test_run(cmd, out, sizeof out);
    if (rc != 2) fail_msg("exit %d, expected 2 (124: the ranks waited for each other):\n%s", rc, out);
    assert_non_null(strstr(out, "missing.exr"));
    assert_int_equal(access(img, F_OK), -1);
    /* rank 1 cannot load its EDA table (its cache folder holds a damaged copy of the table rank 0 builds): it
     * fails as the render starts, and rank 0 does not wait for it */
    const char *eda = "--spp 2 --quiet --set eda=true --set eda_shape=[8,8,8] --set eda_table_dir=";
    snprintf(cmd, sizeof cmd, ONE_BIN " render %s/box.json %s%s/tables --output %s/eda-first.exr && mkdir -p %s/damaged && "
             "for f in %s/tables/*.bin; do echo damaged > %s/damaged/$(basename $f); done", cbox_dir, eda, cbox_dir, cbox_dir, cbox_dir, cbox_dir, cbox_dir);
    if (test_run(cmd, out, sizeof out) != 0) fail_msg("%s: %s", cmd, out);
    snprintf(cmd, sizeof cmd,
             "timeout 30 " MPIRUN " -np 1 " MPI_BIN " render %s/box.json %s%s/tables --output %s : -np 1 " MPI_BIN
             " render %s/box.json %s%s/damaged --output %s",
             cbox_dir, eda, cbox_dir, img, cbox_dir, eda, cbox_dir, img);
    rc = test_run(cmd, out, sizeof out);
    if (rc != 2) fail_msg("exit %d, expected 2 (124: the ranks waited for each other):\n%s", rc, out);
    assert_non_null(strstr(out, "/damaged/eda-"));
    assert_int_equal(access(img, F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_image_as_one_process),
        cmocka_unit_test(test_derivatives_as_one_process),
        cmocka_unit_test(test_amcw_as_one_process),
        cmocka_unit_test(test_time_budget_two_ranks),
        cmocka_unit_test(test_interrupt_writes_completed_passes),
        cmocka_unit_test(test_memory_guard_counts_ranks),
        cmocka_unit_test(test_rank_without_scene),
    };
    return cmocka_run_group_tests(tests, setup_cbox_fog40, teardown_cbox_fog);
}
