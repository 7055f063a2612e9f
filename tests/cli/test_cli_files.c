/* Issue 48, items 2 and 6: no command writes over one of its inputs (by device and inode: also through a hard
 * link or a symlink), `counts` refuses a cube with a NaN, Inf or negative value naming the element, `merge`
 * refuses an input given twice, `table` and `counts` refuse an output named like another format, a folder
 * given as the scene is named as one, `.EXR` is an EXR, every command's help lists every flag its parser
 * knows, `--version` prints the Makefile's VERSION, and the shipped scenes render without warnings under the
 * integrators they are meant for. Every case runs the real binary; DARTSPP_TEST_BIN points it at another
 * build (the checks were shown failing on the binary of 2026-11-28, tests/campaign-48/cli.md). */
#include "test_util.h"

#include <errno.h>

static const char *bin(void)
{
    const char *b = getenv("DARTSPP_TEST_BIN");
    return b && *b ? b : DARTSPP_BIN;
}

/* Runs the binary with printf-style arguments; the exit status, the output (stdout and stderr) in out. */
static int run(char *out, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int run(char *out, size_t n, const char *fmt, ...)
{
    char args[3000], cmd[3300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "%s %s", bin(), args);
    int rc = test_run(cmd, out, n);
    print_message("  $ dartspp %s -> exit %d\n", args, rc);
    if (rc != 0 && out[0]) print_message("    %.300s%s", out, out[strlen(out) - 1] == '\n' ? "" : "\n");
    return rc;
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *b = malloc(1 << 22);
    *len = fread(b, 1, 1 << 22, f);
    fclose(f);
    return b;
}

/* The file still holds what it held (compared byte for byte with a copy taken before). */
static void assert_unchanged(const char *path, const char *before, size_t len)
{
    size_t now_len = 0;
    char *now = slurp(path, &now_len);
    if (!now || now_len != len || memcmp(now, before, len)) fail_msg("%s was overwritten", path);
    free(now);
}

static void assert_refused_naming(int rc, const char *out, const char *a, const char *b)
{
    if (rc != 2) fail_msg("expected exit 2, got %d", rc);
    if (!strstr(out, a) || !strstr(out, b)) fail_msg("the message does not name both %s and %s: %s", a, b, out);
}

static int setup_dir(void **state)
{
    *state = test_tmpdir();
    return *state ? 0 : -1;
}

#define RENDER_ARGS "--set type=path_tracer --set resolution=8 --spp 1 --quiet"

/* render: --log over the scene, --output over --reference, through a hard link and a symlink, --log over the
 * render's own image; .EXR accepted. */
static void test_render_outputs_over_inputs(void **state)
{
    const char *d = *state;
    char out[8192], scene[600], ref[600];
    size_t len;
    snprintf(scene, sizeof scene, "%s/scene.json", d);
    snprintf(ref, sizeof ref, "%s/ref.exr", d);
    char *text = slurp("scenes/fogbox/fogbox.json", &len);
    assert_non_null(text);
    FILE *f = fopen(scene, "wb");
    fwrite(text, 1, len, f);
    fclose(f);
    assert_int_equal(run(out, sizeof out, "render %s " RENDER_ARGS " --output %s", scene, ref), 0);
    size_t ref_len;
    char *ref_bytes = slurp(ref, &ref_len);
    assert_non_null(ref_bytes);

    int rc = run(out, sizeof out, "render %s " RENDER_ARGS " --output %s/r.exr --reference %s --log %s", scene, d, ref, scene);
    assert_refused_naming(rc, out, "scene.json (--log)", "(the scene file)");
    assert_unchanged(scene, text, len);
    rc = run(out, sizeof out, "render %s " RENDER_ARGS " --output %s --reference %s --log %s/l.csv", scene, ref, ref, d);
    assert_refused_naming(rc, out, "ref.exr (the image)", "ref.exr (--reference)");
    assert_unchanged(ref, ref_bytes, ref_len);
    char link_path[700];
    snprintf(link_path, sizeof link_path, "%s/hard.exr", d);
    assert_int_equal(link(ref, link_path), 0);
    rc = run(out, sizeof out, "render %s " RENDER_ARGS " --output %s --reference %s --log %s/l.csv", scene, link_path, ref, d);
    assert_refused_naming(rc, out, "hard.exr", "ref.exr (--reference)");
    assert_unchanged(ref, ref_bytes, ref_len);
    snprintf(link_path, sizeof link_path, "%s/sym.exr", d);
    assert_int_equal(symlink(scene, link_path), 0);
    rc = run(out, sizeof out, "render %s " RENDER_ARGS " --output %s", scene, link_path);
    assert_refused_naming(rc, out, "sym.exr", "(the scene file)");
    assert_unchanged(scene, text, len);
    /* the log and the image under one name: one would replace the other */
    rc = run(out, sizeof out, "render %s " RENDER_ARGS " --output %s/q.exr --reference %s --log %s/./q.exr", scene, d, ref, d);
    assert_refused_naming(rc, out, "--log", "q.exr");
    char q[700];
    snprintf(q, sizeof q, "%s/q.exr", d);
    assert_int_not_equal(access(q, F_OK), 0);
    /* an upper-case extension is the same format */
    assert_int_equal(run(out, sizeof out, "render %s " RENDER_ARGS " --output %s/U.EXR", scene, d), 0);
    snprintf(q, sizeof q, "%s/U.EXR", d);
    assert_int_equal(access(q, F_OK), 0);
    free(text);
    free(ref_bytes);
}

/* A cube of shape (2, 4, 5, 3), every value 0.25 but the one at flat index bad (if >= 0) set to v, with its
 * frames CSV beside it. */
static void write_cube(const char *dir, const char *stem, long bad, float v)
{
    char path[700];
    snprintf(path, sizeof path, "%s/%s_cube.npy", dir, stem);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    char head[128];
    int n = snprintf(head, sizeof head, "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 4, 5, 3), }");
    while ((n + 10 + 1) % 64) head[n++] = ' ';
    head[n++] = '\n';
    unsigned char pre[10] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, (unsigned char)n, 0};
    fwrite(pre, 1, 10, f);
    fwrite(head, 1, (size_t)n, f);
    for (long i = 0; i < 2 * 4 * 5 * 3; i++) {
        unsigned char b[4];
        put_f32(b, i == bad ? v : 0.25f);
        fwrite(b, 1, 4, f);
    }
    fclose(f);
    snprintf(path, sizeof path, "%s/%s_frames.csv", dir, stem);
    test_write_file(path, "index,start,end\n0,1,1.5\n1,1.5,2\n");
}

#define COUNTS_ARGS "--pulses 100 --scale 1"

/* counts: NaN, Inf and negative values refused naming the element; the output over the cube; the sidecar over
 * a JSON file of another kind; an output named .exr; the same output twice (its own sidecar replaced). */
static void test_counts_inputs_and_values(void **state)
{
    const char *d = *state;
    char out[8192], p[700];
    /* flat index of (frame 1, row 2, column 3, channel b) in (2, 4, 5, 3) */
    long at = ((1L * 4 + 2) * 5 + 3) * 3 + 2;
    const float bad[3] = {NAN, INFINITY, -0.5f};
    const char *names[3] = {"nan", "inf", "neg"};
    for (int i = 0; i < 3; i++) {
        write_cube(d, names[i], at, bad[i]);
        int rc = run(out, sizeof out, "counts %s/%s_cube.npy --output %s/k%d.npy " COUNTS_ARGS, d, names[i], d, i);
        if (rc != 2 || !strstr(out, "frame 1, row 2, column 3, channel b"))
            fail_msg("a %s value: expected exit 2 naming frame 1, row 2, column 3, channel b; got exit %d", names[i], rc);
        snprintf(p, sizeof p, "%s/k%d.npy", d, i);
        assert_int_not_equal(access(p, F_OK), 0);
    }
    write_cube(d, "c", -1, 0);
    size_t len;
    snprintf(p, sizeof p, "%s/c_cube.npy", d);
    char *cube = slurp(p, &len);
    int rc = run(out, sizeof out, "counts %s --output %s " COUNTS_ARGS, p, p);
    assert_refused_naming(rc, out, "c_cube.npy (--output)", "c_cube.npy (the cube)");
    assert_unchanged(p, cube, len);
    /* through a symlink to the cube */
    char sym[700];
    snprintf(sym, sizeof sym, "%s/alias.npy", d);
    assert_int_equal(symlink(p, sym), 0);
    rc = run(out, sizeof out, "counts %s --output %s " COUNTS_ARGS, p, sym);
    assert_refused_naming(rc, out, "alias.npy", "c_cube.npy (the cube)");
    assert_unchanged(p, cube, len);
    free(cube);
    /* --output scene.npy beside scene.json: the sidecar would replace the scene */
    char json[700];
    snprintf(json, sizeof json, "%s/scene.json", d);
    test_write_file(json, "{\"camera\": {}}\n");
    rc = run(out, sizeof out, "counts %s --output %s/scene.npy " COUNTS_ARGS, p, d);
    assert_refused_naming(rc, out, "scene.npy", "scene.json");
    assert_unchanged(json, "{\"camera\": {}}\n", 15);
    /* a non-image under an image's name */
    rc = run(out, sizeof out, "counts %s --output %s/x.exr " COUNTS_ARGS, p, d);
    assert_refused_naming(rc, out, "x.exr", ".npy");
    /* the same output twice: the second run replaces its own sidecar */
    assert_int_equal(run(out, sizeof out, "counts %s --output %s/k.NPY " COUNTS_ARGS, p, d), 0);
    assert_int_equal(run(out, sizeof out, "counts %s --output %s/k.NPY " COUNTS_ARGS, p, d), 0);
}

/* A 2 x 1 PFM with the given values. */
static void write_pfm(const char *path, float a, float b)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("PF\n2 1\n-1\n", f);
    float v[6] = {a, a, a, b, b, b};
    fwrite(v, sizeof(float), 6, f);
    fclose(f);
}

/* merge: an input twice (by name, by a hard link, by a symlink) and two copies of one lit image refused; the
 * output over an input through a symlink; an output not .exr/.pfm refused before any read; two different
 * images merged. */
static void test_merge_inputs(void **state)
{
    const char *d = *state;
    char out[8192], a[700], b[700], c[700], h[700], s[700];
    snprintf(a, sizeof a, "%s/a.pfm", d);
    snprintf(b, sizeof b, "%s/b.pfm", d);
    snprintf(c, sizeof c, "%s/copy.pfm", d);
    snprintf(h, sizeof h, "%s/hard.pfm", d);
    snprintf(s, sizeof s, "%s/sym.pfm", d);
    write_pfm(a, 1.0f, 2.0f);
    write_pfm(b, 3.0f, 2.0f);
    write_pfm(c, 1.0f, 2.0f);
    assert_int_equal(link(a, h), 0);
    assert_int_equal(symlink(a, s), 0);
    const char *twice[][2] = {{a, a}, {a, h}, {s, a}, {a, c}};
    for (int i = 0; i < 4; i++) {
        int rc = run(out, sizeof out, "merge %s/m%d.pfm %s %s", d, i, twice[i][0], twice[i][1]);
        assert_refused_naming(rc, out, strrchr(twice[i][0], '/') + 1, strrchr(twice[i][1], '/') + 1);
        /* a name or a link is found as the same file; a copy by its pixels */
        if (!strstr(out, i < 3 ? "are the same file" : "hold the same pixel values")) fail_msg("wrong reason: %s", out);
    }
    int rc = run(out, sizeof out, "merge %s %s %s", s, b, a);
    assert_refused_naming(rc, out, "sym.pfm (the output)", "a.pfm (an input)");
    rc = run(out, sizeof out, "merge %s/m.png %s %s/missing.pfm", d, a, d);
    assert_refused_naming(rc, out, "m.png", ".exr or .pfm");
    rc = run(out, sizeof out, "merge %s/m.PFM %s %s", d, a, b);
    if (rc != 0 || !strstr(out, "variance of the mean 0.5 ")) fail_msg("a and b: expected exit 0 and variance 0.5");
}

/* table: an EDA table under an image's name is refused, before the build. */
static void test_table_output_name(void **state)
{
    const char *d = *state;
    char out[8192], p[700];
    int rc = run(out, sizeof out, "table --sigma-s 1 --sigma-a 0 --g 0 --shape 4,4,4 --output %s/t.exr", d);
    assert_refused_naming(rc, out, "t.exr", ".bin");
    snprintf(p, sizeof p, "%s/t.exr", d);
    assert_int_not_equal(access(p, F_OK), 0);
    assert_int_equal(run(out, sizeof out, "table --sigma-s 1 --sigma-a 0 --g 0 --shape 4,4,4 --output %s/t.BIN", d), 0);
}

/* A folder given as the scene is named as a folder. */
static void test_scene_is_a_folder(void **state)
{
    const char *d = *state;
    char out[8192];
    int rc = run(out, sizeof out, "render %s --spp 1 --output %s/x.exr", d, d);
    if (rc != 2 || !strstr(out, "is a folder, not a scene file")) fail_msg("expected exit 2 and 'is a folder'");
}

/* The "--flag" literals of a source file (every flag its parser compares against, and the usage text's). */
static int flags_of(const char *src, char flags[][40], int max)
{
    size_t len;
    char *text = slurp(src, &len);
    assert_non_null(text);
    text[len < (1 << 22) ? len : len - 1] = 0;
    int n = 0;
    for (char *q = text; (q = strstr(q, "\"--")) && n < max; q += 3) {
        int k = 0;
        while (k < 38 && (q[1 + k] == '-' || (q[1 + k] >= 'a' && q[1 + k] <= 'z'))) k++;
        if (q[1 + k] != '"' || k < 3) continue; /* the flag alone in its literal */
        snprintf(flags[n], 40, "%.*s", k, q + 1);
        n++;
    }
    free(text);
    return n;
}

/* Every command: -h and --help exit 0, print on stdout only, and list every flag its source compares
 * against; --version and -V print the Makefile's VERSION. */
static void test_help_and_version(void **state)
{
    (void)state;
    const char *cmds[][2] = {{"render", "src/cli/render_cmd.c"},   {"compare", "src/cli/compare_cmd.c"},
                             {"patch-mean", "src/cli/patch_mean_cmd.c"}, {"merge", "src/cli/merge_cmd.c"},
                             {"table", "src/cli/table_cmd.c"},     {"keys", "src/cli/keys_cmd.c"},
                             {"counts", "src/cli/counts_cmd.c"}};
    char out[16384], flags[64][40];
    for (int c = 0; c < 7; c++) {
        int n = flags_of(cmds[c][1], flags, 64);
        for (int h = 0; h < 2; h++) {
            const char *flag = h ? "-h" : "--help";
            char cmd[600];
            snprintf(cmd, sizeof cmd, "( %s %s %s 2>/dev/null )", bin(), cmds[c][0], flag);
            int rc = test_run(cmd, out, sizeof out);
            if (rc != 0) fail_msg("dartspp %s %s: exit %d", cmds[c][0], flag, rc);
            for (int i = 0; i < n; i++)
                if (!strstr(out, flags[i])) fail_msg("dartspp %s %s does not list %s:\n%s", cmds[c][0], flag, flags[i], out);
            if (!strstr(out, "-h, --help")) fail_msg("dartspp %s %s does not list -h, --help", cmds[c][0], flag);
            snprintf(cmd, sizeof cmd, "( %s %s %s >/dev/null )", bin(), cmds[c][0], flag);
            test_run(cmd, out, sizeof out);
            if (out[0]) fail_msg("dartspp %s %s wrote on stderr: %s", cmds[c][0], flag, out);
        }
        print_message("  %s: %d flags listed by --help and -h\n", cmds[c][0], n);
    }
    /* the version, from the Makefile */
    size_t len;
    char *mk = slurp("Makefile", &len), version[64] = "";
    assert_non_null(mk);
    mk[len - 1] = 0;
    char *v = strstr(mk, "\nVERSION  := ");
    assert_non_null(v);
    sscanf(v + strlen("\nVERSION  := "), "%63s", version);
    free(mk);
    const char *vflags[2] = {"--version", "-V"};
    for (int i = 0; i < 2; i++) {
        char want[100];
        snprintf(want, sizeof want, "dartspp %s", version);
        int rc = run(out, sizeof out, "%s", vflags[i]);
        if (rc != 0 || strncmp(out, want, strlen(want))) fail_msg("%s: expected exit 0 and '%s...', got %d: %s", vflags[i], want, rc, out);
    }
}

/* The shipped scenes under the integrators they are meant for (their own, and the path tracer that docs name
 * as their reference) print no warning; a --set key the path tracer ignores still does. */
static void test_shipped_scenes_without_warnings(void **state)
{
    const char *d = *state;
    char out[16384];
    const char *scenes[] = {"scenes/fogbox/fogbox.json", "scenes/fogbox/two-pulses.json", "scenes/gated-fog/gated-fog.json",
                            "scenes/cbox-fog/transient.json", "scenes/cbox-fog/path_tracer.json", "scenes/fog-mie/fog-mie.json"};
    for (int i = 0; i < (int)(sizeof scenes / sizeof scenes[0]); i++)
        for (int pt = 0; pt < 2; pt++) {
            int rc = run(out, sizeof out, "render %s %s --set resolution=4 --spp 1 --quiet --output %s/s%d%d.exr", scenes[i],
                         pt ? "--set type=path_tracer" : "", d, i, pt);
            if (rc != 0 || strstr(out, "warning")) fail_msg("%s%s: exit %d or a warning:\n%s", scenes[i], pt ? " (path tracer)" : "", rc, out);
        }
    int rc = run(out, sizeof out, "render %s --set type=path_tracer --set strict_time_width=true --set resolution=4 --spp 1 "
                 "--quiet --output %s/w.exr", scenes[0], d);
    if (rc != 0 || !strstr(out, "integrator.strict_time_width: the path_tracer integrator does not read"))
        fail_msg("a --set key the path tracer ignores: expected its warning");
}

/* Messages that name their files (2026-11-28 probes 24, 27 of tests/campaign-48/driver.md): compare and merge of
 * images of two sizes name both files (before: "compare: image is 2x1 but the reference is 1x1"); a file that
 * is not OpenEXR says so (before: OpenEXR's "Unable to read magic and version flags"); an output with no name
 * before its extension is refused (probe 11: before, hidden files ".exr", ".png" were written); --reduce-every
 * on the one-process binary is said to have no effect (probe 23: before, accepted without a word); a render
 * without frames over an older frame set says that set is not its own (probe 14: before, nothing). */
static void test_messages_name_their_files(void **state)
{
    const char *d = *state;
    char out[8192], a[700], w[700], g[700];
    snprintf(a, sizeof a, "%s/two.pfm", d);
    snprintf(w, sizeof w, "%s/one.pfm", d);
    snprintf(g, sizeof g, "%s/garbage.exr", d);
    write_pfm(a, 1.0f, 2.0f);
    FILE *f = fopen(w, "wb");
    assert_non_null(f);
    fputs("PF\n1 1\n-1\n", f);
    float v[3] = {1, 1, 1};
    fwrite(v, sizeof(float), 3, f);
    fclose(f);
    test_write_file(g, "garbage, not an image");
    int rc = run(out, sizeof out, "compare %s %s", a, w);
    assert_refused_naming(rc, out, "two.pfm is 2x1", "one.pfm is 1x1");
    rc = run(out, sizeof out, "merge %s/m.pfm %s %s", d, a, w);
    assert_refused_naming(rc, out, "two.pfm", "one.pfm is 1x1");
    rc = run(out, sizeof out, "compare %s %s", g, a);
    assert_refused_naming(rc, out, "garbage.exr", "not an OpenEXR image");
    rc = run(out, sizeof out, "render scenes/fogbox/fogbox.json " RENDER_ARGS " --output %s/.exr", d);
    assert_refused_naming(rc, out, "/.exr", "no file name before the extension");
    char hidden[800];
    snprintf(hidden, sizeof hidden, "%s/.png", d);
    assert_int_equal(access(hidden, F_OK), -1);
    rc = run(out, sizeof out, "render scenes/fogbox/fogbox.json " RENDER_ARGS " --reduce-every 5 --output %s/r.exr", d);
    assert_int_equal(rc, 0);
    if (!strstr(out, "--reduce-every has no effect")) fail_msg("no word on --reduce-every: %s", out);
    /* campaign-48/cli.md (open there): a render whose stderr is not a terminal printed its last progress line
     * twice ("pass 1/1" after the pass and again as the final line) */
    assert_int_equal(run(out, sizeof out, "render scenes/fogbox/fogbox.json --set type=path_tracer --set resolution=8 "
                                          "--spp 1 --output %s/p.exr", d), 0);
    const char *first = strstr(out, "pass 1/1");
    if (!first || strstr(first + 1, "pass 1/1")) fail_msg("expected one line 'pass 1/1': %s", out);
    /* probe 14: a render without frames over the name of an earlier frame set (whose manifest, frames, cube and
     * viewer stay) says so; a render with frames replaces the set and says nothing */
    const char *frames = "--set frame_num=2 --set start_time=6";
    assert_int_equal(run(out, sizeof out, "render scenes/fogbox/fogbox.json " RENDER_ARGS " %s --output %s/f.exr", frames, d), 0);
    assert_null(strstr(out, "from an earlier render with frames"));
    assert_int_equal(run(out, sizeof out, "render scenes/fogbox/fogbox.json " RENDER_ARGS " --output %s/f.exr", d), 0);
    if (!strstr(out, "f_frames.csv and the frames, cube and viewer it goes with are from an earlier render"))
        fail_msg("no word on the older frame set: %s", out);
}

/* The two outputs over inputs of campaign-48/cli.md left open there: `--log` naming a mesh the scene reads
 * (before: the scene kept no list of its mesh files; the CSV replaced the mesh), and an output under a folder
 * that does not exist yet whose ".." lands on the reference (`--output new/../ref.exr`: before, the folder was
 * made and the reference replaced). Both exit 2 naming both paths, the input unchanged. */
static void test_outputs_over_meshes_and_unmade_folders(void **state)
{
    const char *d = *state;
    char out[8192], path[800], scene[2000];
    snprintf(path, sizeof path, "%s/tri.obj", d);
    test_write_file(path, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
    snprintf(scene, sizeof scene,
             "{ \"bsdfs\": [ { \"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5 } ],"
             "  \"primitives\": [ { \"type\": \"mesh\", \"file\": \"tri.obj\", \"bsdf\": \"w\" },"
             "    { \"type\": \"point\", \"emission\": [1, 1, 1], \"transform\": { \"position\": [0, 0, -1] } } ],"
             "  \"camera\": { \"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 40,"
             "    \"transform\": { \"position\": [0, 0, -3], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0] } },"
             "  \"integrator\": { \"type\": \"path_tracer\" }, \"renderer\": { \"spp\": 1 } }");
    char sc[800];
    snprintf(sc, sizeof sc, "%s/tri.json", d);
    test_write_file(sc, scene);
    assert_int_equal(run(out, sizeof out, "render %s --spp 1 --quiet --output %s/ref.exr", sc, d), 0);
    size_t mesh_len = 0, ref_len = 0;
    char *mesh = slurp(path, &mesh_len), *ref = NULL;
    snprintf(path, sizeof path, "%s/ref.exr", d);
    ref = slurp(path, &ref_len);
    assert_non_null(mesh);
    assert_non_null(ref);
    int rc = run(out, sizeof out, "render %s --spp 1 --quiet --reference %s/ref.exr --log %s/tri.obj --output %s/o.exr",
                 sc, d, d, d);
    assert_refused_naming(rc, out, "tri.obj (--log)", "a mesh");
    rc = run(out, sizeof out, "render %s --spp 1 --quiet --reference %s/ref.exr --log %s/l.csv --output %s/new/../ref.exr",
             sc, d, d, d);
    assert_refused_naming(rc, out, "new/../ref.exr", "--reference");
    snprintf(path, sizeof path, "%s/tri.obj", d);
    assert_unchanged(path, mesh, mesh_len);
    snprintf(path, sizeof path, "%s/ref.exr", d);
    assert_unchanged(path, ref, ref_len);
    free(mesh);
    free(ref);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_render_outputs_over_inputs, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_counts_inputs_and_values, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_merge_inputs, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_table_output_name, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_scene_is_a_folder, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test(test_help_and_version),
        cmocka_unit_test_setup_teardown(test_shipped_scenes_without_warnings, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_messages_name_their_files, setup_dir, test_teardown_tmpdir),
        cmocka_unit_test_setup_teardown(test_outputs_over_meshes_and_unmade_folders, setup_dir, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
