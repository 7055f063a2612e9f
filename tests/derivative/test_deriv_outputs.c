/* The derivative images beside the rest of a render (docs/derivatives.md §5): with frames and two
 * `--derivative` pointers every derivative file is written, of the image's size and the frames' shape, finite,
 * named in order by <stem>_derivatives.csv, and moved into place with the frame set (its manifest last); a
 * render of N passes resumed to 2N equals one of 2N passes byte for byte, derivative images included, and a
 * resume with another --derivative list is refused naming the state and both lists; the memory estimate
 * grows by the film's bytes per derivative and a --max-memory between the two refuses only the derivative
 * run; a scene named like a derivative output is refused before any work. The real binary (DARTSPP_TEST_BIN
 * points it at another build) on our fog Cornell box at 16x16, path tracer, 2 frames. */
#include "child_process.h"
#include "fixtures.h"

#include "dartspp/io.h"
#include "dartspp/render.h"

#define SETS "--set type=path_tracer --set frame_num=2 --set start_time=14 --set transient_time_width=2"
#define DERIVS "--derivative /bsdfs/0/albedo --derivative /media/0/sigma_s"
#define PTR0 "/bsdfs/0/albedo"
#define PTR1 "/media/0/sigma_s"

static const char *bin(void)
{
    const char *b = getenv("DARTSPP_TEST_BIN");
    return b && *b ? b : DARTSPP_BIN;
}

static int setup(void **state)
{
    *state = tmpdir_with_cbox_fog(16);
    return *state ? 0 : -1;
}

/* `dartspp render <dir>/box.json SETS <args>`: the exit status, the output in out. */
static int render(const char *dir, const char *args, char *out, size_t n)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s render %s/box.json --threads 1 --seed 5 " SETS " %s", bin(), dir, args);
    int rc = test_run(cmd, out, n);
    print_message("  $ %s -> exit %d\n", cmd + strlen(bin()) + 1, rc);
    if (strstr(out, "Sanitizer") || strstr(out, "runtime error")) {
        print_tail(out);
        fail_msg("sanitizer report");
    }
    return rc;
}

/* Every value of an image finite; returns the sum of their magnitudes. */
static double check_image(const char *path, int w, int h)
{
    image_rgb img = {0};
    dp_error err;
    if (image_read(path, &img, &err)) fail_msg("%s", err.msg);
    if (img.width != w || img.height != h) fail_msg("%s is %dx%d, the image %dx%d", path, img.width, img.height, w, h);
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)w * h * 3; i++) {
        if (!isfinite(img.rgb[i])) fail_msg("%s: value %zu is %g", path, i, img.rgb[i]);
        sum += fabs(img.rgb[i]);
    }
    image_free(&img);
    return sum;
}

/* A float32 .npy of shape (frames, h, w, 3): the shape in its header, the size, every value finite. */
static void check_cube(const char *path, int frames, int w, int h)
{
    size_t n = 0;
    char *b = read_all(path, &n);
    if (!b || n < 10) fail_msg("cannot read %s", path);
    unsigned hl = (unsigned char)b[8] | (unsigned)(unsigned char)b[9] << 8;
    char shape[64], *hdr = strndup(b + 10, hl);
    snprintf(shape, sizeof shape, "'shape': (%d, %d, %d, 3)", frames, h, w);
    if (!strstr(hdr, shape) || !strstr(hdr, "<f4")) fail_msg("%s: header %s lacks %s", path, hdr, shape);
    size_t count = (size_t)frames * h * w * 3;
    assert_int_equal(n, 10 + hl + 4 * count);
    for (size_t i = 0; i < count; i++) {
        float v;
        memcpy(&v, b + 10 + hl + 4 * i, 4);
        if (!isfinite(v)) fail_msg("%s: element %zu is %g", path, i, v);
    }
    free(hdr);
    free(b);
}

/* Item 6: every derivative output of a frame render, and the set's order. */
static void test_outputs(void **state)
{
    const char *d = *state;
    char args[1024], out[65536], p[1200];
    snprintf(args, sizeof args, "--spp 2 " DERIVS " --output %s/o.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    /* the summary names them */
    assert_non_null(strstr(out, "derivatives (2): d0 = dI/d " PTR0 "; d1 = dI/d " PTR1));
    const char *manifest = strstr(out, "/o_frames.csv");
    assert_non_null(manifest);
    for (int k = 0; k < 2; k++) {
        const char *names[] = {"_d%d.exr", "_d%d_0000.exr", "_d%d_0001.exr", "_d%d_cube.npy", "_d%d_frames.csv"};
        for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
            char name[64], wrote[1300];
            snprintf(name, sizeof name, names[i], k);
            snprintf(p, sizeof p, "%s/o%s", d, name);
            if (!file_exists(p)) fail_msg("%s was not written", p);
            snprintf(wrote, sizeof wrote, "wrote %s\n", p);
            const char *at = strstr(out, wrote);
            /* moved into place with the frame set: before its manifest, which moves last */
            if (!at || at > manifest) fail_msg("%s not reported before the set's manifest", p);
        }
        double mag = 0;
        snprintf(p, sizeof p, "%s/o_d%d.exr", d, k);
        mag += check_image(p, 16, 16);
        for (int f = 0; f < 2; f++) {
            snprintf(p, sizeof p, "%s/o_d%d_%04d.exr", d, k, f);
            mag += check_image(p, 16, 16);
        }
        if (!(mag > 0)) fail_msg("derivative %d is zero everywhere: nothing was computed", k);
        snprintf(p, sizeof p, "%s/o_d%d_cube.npy", d, k);
        check_cube(p, 2, 16, 16);
    }
    snprintf(p, sizeof p, "%s/o_derivatives.csv", d);
    char *csv = read_all(p, NULL);
    assert_non_null(csv);
    print_message("  %s:\n%s", p, csv);
    assert_string_equal(csv, "k,pointer,image\n0,\"" PTR0 "\",o_d0.exr\n1,\"" PTR1 "\",o_d1.exr\n");
    free(csv);
    /* nothing of the staging left */
    snprintf(args, sizeof args, "ls -a %s | grep -c '\\.set\\.' || true", d);
    char ls[256];
    test_run(args, ls, sizeof ls);
    assert_int_equal(atoi(ls), 0);
}

static void assert_same_file(const char *a, const char *b)
{
    size_t na = 0, nb = 0;
    char *fa = read_all(a, &na), *fb = read_all(b, &nb);
    if (!fa || !fb) fail_msg("cannot read %s or %s", a, b);
    size_t i = 0;
    while (i < na && i < nb && fa[i] == fb[i]) i++;
    free(fa);
    free(fb);
    if (na != nb || i < na) fail_msg("%s and %s differ at byte %zu (of %zu and %zu)", a, b, i, na, nb);
}

/* Item 2: N passes resumed to 2N equal 2N passes byte for byte, every image and cube. */
static void test_resume_same_bytes(void **state)
{
    const char *d = *state;
    char args[1024], out[65536];
    snprintf(args, sizeof args, "--spp 4 --quiet " DERIVS " --output %s/full.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    snprintf(args, sizeof args, "--spp 2 --quiet --checkpoint 1e-9 " DERIVS " --output %s/res.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    snprintf(args, sizeof args, "--spp 4 " DERIVS " --resume --output %s/res.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    assert_non_null(strstr(out, "rendered 4 passes (2 of them resumed from the checkpoint, 2 in this run)"));
    const char *names[] = {".exr", "_0000.exr", "_0001.exr", "_cube.npy", "_d0.exr", "_d0_0000.exr", "_d0_0001.exr",
                           "_d0_cube.npy", "_d1.exr", "_d1_0000.exr", "_d1_0001.exr", "_d1_cube.npy"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char a[1200], b[1200];
        snprintf(a, sizeof a, "%s/full%s", d, names[i]);
        snprintf(b, sizeof b, "%s/res%s", d, names[i]);
        assert_same_file(b, a);
    }
    print_message("  2 passes resumed to 4: %zu files byte-identical to the 4-pass render\n",
                  sizeof names / sizeof names[0]);
}

/* Item 2: a state of one --derivative list resumed with another (order, pointers, none; and a state without
 * derivatives resumed with some): refused, exit 2, naming the state and both lists; the state untouched. */
static void test_resume_other_derivatives(void **state)
{
    const char *d = *state;
    char args[1024], out[65536], st[1100];
    snprintf(args, sizeof args, "--spp 2 --quiet --checkpoint 1e-9 " DERIVS " --output %s/r.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    snprintf(st, sizeof st, "%s/r.state", d);
    size_t n0 = 0;
    char *before = read_all(st, &n0);
    assert_non_null(before);
    struct {
        const char *args, *asked;
    } cases[] = {
        {"--derivative " PTR1 " --derivative " PTR0, "(d0 " PTR1 ", d1 " PTR0 ")"},
        {"--derivative " PTR0, "(d0 " PTR0 ")"},
        {"--derivative " PTR0 " --derivative /media/0/sigma_a", "(d0 " PTR0 ", d1 /media/0/sigma_a)"},
        {"", "(none)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(args, sizeof args, "--spp 4 --quiet --resume %s --output %s/r.exr", cases[i].args, d);
        int rc = render(d, args, out, sizeof out);
        print_tail(out);
        assert_int_equal(rc, 2);
        char expect[600];
        snprintf(expect, sizeof expect, "the checkpoint holds the derivatives (d0 " PTR0 ", d1 " PTR1 "), this run "
                 "asks for %s", cases[i].asked);
        if (!strstr(out, expect)) fail_msg("message lacks '%s'", expect);
        if (!strstr(out, st)) fail_msg("message lacks the state file %s", st);
    }
    size_t n1 = 0;
    char *after = read_all(st, &n1);
    assert_true(after && n0 == n1 && !memcmp(before, after, n0));
    free(before);
    free(after);
    /* a state without derivatives, resumed with one */
    snprintf(args, sizeof args, "--spp 2 --quiet --checkpoint 1e-9 --output %s/plain.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    snprintf(args, sizeof args, "--spp 4 --quiet --resume --derivative " PTR0 " --output %s/plain.exr", d);
    assert_int_equal(render(d, args, out, sizeof out), 2);
    print_tail(out);
    assert_non_null(strstr(out, "the checkpoint holds the derivatives (none), this run asks for (d0 " PTR0 ")"));
}

/* The memory estimate of box.json at 64x64 with SETS and k of the two pointers; *film: the film's item. */
static double estimate(const char *dir, int k, double *film, double *deriv_item)
{
    const char *sets[] = {"type=path_tracer", "frame_num=2", "start_time=14", "transient_time_width=2", "resolution=64"};
    const char *ptrs[] = {PTR0, PTR1};
    scene_load_options lo = {.sets = sets, .set_count = 5, .derivatives = ptrs, .derivative_count = k};
    char path[1100];
    snprintf(path, sizeof path, "%s/box.json", dir);
    scene s;
    render_plan p;
    dp_error err;
    if (scene_load(path, &lo, &s, &err) || plan_resolve(&s, &p, &err)) fail_msg("%s", err.msg);
    memory_estimate m;
    render_memory_estimate(&s, &p, 0, &m);
    *film = *deriv_item = 0;
    for (int i = 0; i < m.count; i++) {
        if (!strncmp(m.item[i].what, "film ", 5)) *film = m.item[i].bytes;
        if (!strcmp(m.item[i].what, MEMORY_DERIV_FILMS)) {
            *deriv_item = m.item[i].bytes;
            assert_string_equal(m.item[i].key, "--derivative");
        }
    }
    plan_free(&p);
    scene_free(&s);
    return m.total;
}

/* Item 3: the estimate grows by the film's bytes per derivative; --max-memory between refuses only the
 * derivative run, before any work, naming --derivative. */
static void test_memory(void **state)
{
    const char *d = *state;
    double film0, film1, film2, item0, item1, item2;
    double e0 = estimate(d, 0, &film0, &item0), e1 = estimate(d, 1, &film1, &item1), e2 = estimate(d, 2, &film2, &item2);
    /* the film of 64x64 pixels with 2 frames: 2 × (3 doubles + 2 × 3 floats) per pixel, sums and pass layer */
    assert_true(film0 == 64.0 * 64 * 2 * (3 * 8 + 2 * 3 * 4));
    print_message("  estimate: %.0f, %.0f, %.0f bytes with 0, 1, 2 derivatives (film %.0f)\n", e0, e1, e2, film0);
    assert_true(item0 == 0 && item1 == film0 && item2 == 2 * film0);
    assert_true(e1 - e0 == film0 && e2 - e0 == 2 * film0);
    char args[1024], out[65536];
    double limit = 0.5 * (e0 + e2);
    snprintf(args, sizeof args, "--spp 1 --quiet --set resolution=64 --max-memory %.0f --output %s/m.exr", limit, d);
    assert_int_equal(render(d, args, out, sizeof out), 0);
    snprintf(args, sizeof args, "--spp 1 --quiet --set resolution=64 --max-memory %.0f " DERIVS " --output %s/md.exr",
             limit, d);
    assert_int_equal(render(d, args, out, sizeof out), 2);
    print_tail(out);
    assert_non_null(strstr(out, "--max-memory"));
    char md[1100];
    snprintf(md, sizeof md, "%s/md.exr", d);
    assert_false(file_exists(md));
}

/* Item 5: a scene file that a derivative output would overwrite (the derivative frames' manifest, a derivative
 * cube, the sidecar; the orders of a derivative with bounce_orders) is refused before any work. */
static void test_output_over_scene(void **state)
{
    const char *d = *state;
    const char *names[] = {"o_d1_frames.csv", "o_d0_cube.npy", "o_derivatives.csv", "o_d1_orders.npy", "o_d0_0001.exr"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char cmd[4096], out[16384], scene[1100];
        snprintf(scene, sizeof scene, "%s/%s", d, names[i]);
        snprintf(cmd, sizeof cmd, "cp %s/box.json %s", d, scene);
        assert_int_equal(test_run(cmd, out, sizeof out), 0);
        snprintf(cmd, sizeof cmd, "%s render %s --threads 1 --spp 1 " SETS " --set bounce_orders=2 " DERIVS
                 " --output %s/o.exr", bin(), scene, d);
        int rc = test_run(cmd, out, sizeof out);
        print_message("  scene %s: exit %d\n", names[i], rc);
        print_tail(out);
        assert_int_equal(rc, 2);
        assert_non_null(strstr(out, scene));
        assert_non_null(strstr(out, "the scene file"));
        char img[1100];
        snprintf(img, sizeof img, "%s/o.exr", d);
        assert_false(file_exists(img));
        unlink(scene);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_outputs, setup, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_resume_same_bytes, setup, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_resume_other_derivatives, setup, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_memory, setup, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_output_over_scene, setup, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
