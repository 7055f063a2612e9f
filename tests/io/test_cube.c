/* tier: quick */
/* The transient cube `<stem>_cube.npy`: the writer's exact header on hand-made data, its errors, and a real
 * frame-mode render whose cube, read back by a minimal .npy parser written here (not the writer's code),
 * equals the frame EXR files value for value. */
#include "test_util.h"

#include "dartspp/io.h"

#include <stdint.h>

static char *tmp; /* the test's folder, also in *state: test_teardown_tmpdir removes it */


/* The whole file; the caller frees it. */
static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s: cannot open", path);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)len + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    b[len] = 0;
    *n = (size_t)len;
    return b;
}

static float le_f32(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float v;
    memcpy(&v, &u, 4);
    return v;
}

static uint32_t bits(float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    return u;
}

/* ---- a minimal .npy reader, independent of src/io/npy.c ---- */

typedef struct {
    unsigned char *file;
    size_t size;
    size_t data;      /* offset of the first value */
    long shape[8];
    int ndim;
} npy_read;

/* Parses "(a, b, c)" or "(a,)" after "'shape': " in the header text. */
static void parse_shape(const char *text, npy_read *r)
{
    const char *p = strstr(text, "'shape': (");
    if (!p) fail_msg("no 'shape': ( in the header: %s", text);
    p += strlen("'shape': (");
    r->ndim = 0;
    while (*p && *p != ')') {
        char *end;
        long v = strtol(p, &end, 10);
        if (end == p || r->ndim == 8) fail_msg("bad shape in the header: %s", text);
        r->shape[r->ndim++] = v;
        p = end;
        if (*p == ',') p++;
        while (*p == ' ') p++;
    }
    if (*p != ')') fail_msg("unterminated shape in the header: %s", text);
}

/* Checks everything the format and our promise fix: magic, version 1.0, dict keys, 64-byte alignment,
 * the size of the data; fills r. */
static void npy_parse(const char *path, npy_read *r)
{
    r->file = slurp(path, &r->size);
    const unsigned char *b = r->file;
    assert_true(r->size >= 10);
    assert_memory_equal(b, "\x93NUMPY", 6);
    assert_int_equal(b[6], 1);
    assert_int_equal(b[7], 0);
    size_t hlen = (size_t)b[8] | (size_t)b[9] << 8;
    r->data = 10 + hlen;
    assert_true(r->data <= r->size);
    assert_int_equal(r->data % 64, 0);
    char text[65536];
    memcpy(text, b + 10, hlen);
    text[hlen] = 0;
    assert_int_equal(text[hlen - 1], '\n');
    assert_int_equal(text[0], '{');
    assert_non_null(strstr(text, "'descr': '<f4'"));
    assert_non_null(strstr(text, "'fortran_order': False"));
    parse_shape(text, r);
    size_t count = 1;
    for (int i = 0; i < r->ndim; i++) count *= (size_t)r->shape[i];
    assert_int_equal(r->size, r->data + 4 * count);
}

/* ---- the writer on hand-made data ---- */

/* Shape (2, 1, 2, 3), values 0.5·i - 1: the exact header NumPy 1.0 files carry, then the values. */
static void test_header_by_hand(void **state)
{
    *state = tmp = test_tmpdir();
    char path[512];
    snprintf(path, sizeof path, "%s/hand.npy", tmp);
    float v[12];
    for (int i = 0; i < 12; i++) v[i] = 0.5f * i - 1.0f;
    size_t shape[4] = {2, 1, 2, 3};
    dp_error err;
    assert_int_equal(npy_write_f32(path, shape, 4, v, &err), 0);
    size_t n;
    unsigned char *b = slurp(path, &n);
    const char dict[] = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 1, 2, 3), }";
    assert_int_equal(n, 128 + 48); /* 10 + 66 + 1 rounds up to 128 */
    assert_memory_equal(b, "\x93NUMPY\x01\x00\x76\x00", 10); /* HEADER_LEN 118 = 0x76 */
    assert_memory_equal(b + 10, dict, strlen(dict));
    for (size_t i = 10 + strlen(dict); i < 127; i++) assert_int_equal(b[i], ' ');
    assert_int_equal(b[127], '\n');
    for (int i = 0; i < 12; i++) assert_int_equal(bits(le_f32(b + 128 + 4 * i)), bits(v[i]));
    free(b);

    /* a 1-D shape is the tuple "(5,)" */
    unsigned char h[NPY_HEADER_MAX];
    size_t one[1] = {5};
    size_t len = npy_header(h, sizeof h, one, 1);
    assert_int_equal(len, 128); /* 10 + 58 + 1 rounds up to 128 */
    assert_memory_equal(h + 10, "{'descr': '<f4', 'fortran_order': False, 'shape': (5,), }",
                        strlen("{'descr': '<f4', 'fortran_order': False, 'shape': (5,), }"));
    /* the independent reader agrees with the hand-made file */
    npy_read r;
    npy_parse(path, &r);
    assert_int_equal(r.ndim, 4);
    assert_int_equal(r.shape[0], 2);
    assert_int_equal(r.shape[3], 3);
    free(r.file);
}

/* A hand-made .npy file: a 1.0 header with the dict text padded to 64 bytes, then raw bytes. */
static void write_npy_by_hand(const char *path, const char *dict, const void *data, size_t n)
{
    unsigned char h[128];
    size_t len = strlen(dict);
    assert_true(len + 11 <= sizeof h);
    memcpy(h, "\x93NUMPY\x01\x00", 8);
    size_t total = (10 + len + 1 + 63) / 64 * 64;
    h[8] = (unsigned char)(total - 10), h[9] = 0;
    memcpy(h + 10, dict, len);
    memset(h + 10 + len, ' ', total - 10 - len - 1);
    h[total - 1] = '\n';
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(h, 1, total, f), total);
    if (n) assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

/* npy_read_f32 (the reader of `dartspp counts`): our files back bit for bit, NumPy's float32 layout from a
 * file made by hand (format 1.0, a 1-D shape), and every other file refused with the file and the reason. */
static void test_reader(void **state)
{
    *state = tmp = test_tmpdir();
    char path[512];
    snprintf(path, sizeof path, "%s/r.npy", tmp);
    float v[24], *got;
    for (int i = 0; i < 24; i++) v[i] = 0.25f * i - 3.0f;
    size_t shape[4] = {2, 3, 4, 1}, sh[NPY_MAX_DIMS];
    int nd;
    dp_error err;
    assert_int_equal(npy_write_f32(path, shape, 4, v, &err), 0);
    assert_int_equal(npy_read_f32(path, sh, &nd, &got, &err), 0);
    assert_int_equal(nd, 4);
    for (int i = 0; i < 4; i++) assert_int_equal(sh[i], shape[i]);
    assert_memory_equal(got, v, sizeof v);
    free(got);
    write_npy_by_hand(path, "{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }", v, 12);
    assert_int_equal(npy_read_f32(path, sh, &nd, &got, &err), 0);
    assert_int_equal(nd, 1);
    assert_int_equal(sh[0], 3);
    assert_true(got[2] == v[2]);
    free(got);
    const struct {
        const char *dict;
        size_t bytes;
        const char *why;
    } bad[] = {
        {"{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }", 24, "dtype"},
        {"{'descr': '<f4', 'fortran_order': True, 'shape': (3,), }", 12, "Fortran"},
        {"{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }", 8, "fewer values"},
        {"{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }", 16, "more bytes"},
        {"{'descr': '<f4', 'fortran_order': False, 'shape': (-3,), }", 12, "shape"},
    };
    for (int i = 0; i < 5; i++) {
        write_npy_by_hand(path, bad[i].dict, v, bad[i].bytes);
        got = (float *)1;
        assert_int_equal(npy_read_f32(path, sh, &nd, &got, &err), -1);
        assert_null(got);
        if (!strstr(err.msg, bad[i].why) || !strstr(err.msg, path)) fail_msg("case %d: %s", i, err.msg);
    }
}

/* Too few or too many values: an error naming the file, and no file left behind. */
static void test_wrong_count_leaves_nothing(void **state)
{
    *state = tmp = test_tmpdir();
    char path[512];
    snprintf(path, sizeof path, "%s/short.npy", tmp);
    size_t shape[2] = {2, 3};
    float v[7] = {1, 2, 3, 4, 5, 6, 7};
    dp_error err;
    npy_file w;
    assert_int_equal(npy_open(&w, path, shape, 2, &err), 0);
    assert_int_equal(npy_append(&w, v, 5, &err), 0);
    assert_int_not_equal(npy_close(&w, &err), 0);
    assert_non_null(strstr(err.msg, path));
    assert_int_not_equal(access(path, F_OK), 0);
    assert_int_equal(npy_open(&w, path, shape, 2, &err), 0);
    assert_int_not_equal(npy_append(&w, v, 7, &err), 0);
    assert_non_null(strstr(err.msg, path));
    assert_int_not_equal(access(path, F_OK), 0);
    char cmd[600], out[256];
    snprintf(cmd, sizeof cmd, "ls -A %s", tmp);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_string_equal(out, ""); /* no temporary files either */
}

/* ---- a real render ---- */

#define FRAMES 4
#define RENDER " render scenes/fogbox/fogbox.json --spp 2 --quiet --seed 7 --set resolution=16x12 --set frame_num=4" \
               " --set start_time=5 --set transient_time_width=0.5"

/* Every value of the cube is the float of the frame files: bit for bit. */
static void test_cube_equals_frames(void **state)
{
    *state = tmp = test_tmpdir();
    char cmd[1024], out[8192], path[512];
    snprintf(cmd, sizeof cmd, DARTSPP_BIN RENDER " --output %s/fb.exr", tmp);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    snprintf(path, sizeof path, "wrote %s/fb_cube.npy\n", tmp);
    assert_non_null(strstr(out, path));
    snprintf(path, sizeof path, "%s/fb_cube.npy", tmp);
    npy_read r;
    npy_parse(path, &r);
    assert_int_equal(r.ndim, 4);
    assert_int_equal(r.shape[0], FRAMES);
    assert_int_equal(r.shape[1], 12);
    assert_int_equal(r.shape[2], 16);
    assert_int_equal(r.shape[3], 3);
    size_t plane = 12 * 16 * 3, nonzero = 0;
    for (int k = 0; k < FRAMES; k++) {
        image_rgb img;
        dp_error err;
        snprintf(path, sizeof path, "%s/fb_%04d.exr", tmp, k);
        assert_int_equal(exr_read(path, &img, &err), 0);
        assert_int_equal(img.width, 16);
        assert_int_equal(img.height, 12);
        for (size_t i = 0; i < plane; i++) {
            float c = le_f32(r.file + r.data + 4 * (k * plane + i));
            if (bits(c) != bits(img.rgb[i]))
                fail_msg("frame %d value %zu (x %zu, y %zu, channel %zu): cube %.9g, %s %.9g", k, i, i / 3 % 16,
                         i / 48, i % 3, c, path, img.rgb[i]);
            nonzero += c != 0.0f;
        }
        image_free(&img);
    }
    free(r.file);
    assert_true(nonzero > plane / 4); /* the frames saw light: the comparison is not of zeros */
}

/* --no-cube and --no-viewer leave the two files out; the rest is written. */
static void test_switches(void **state)
{
    *state = tmp = test_tmpdir();
    char cmd[1024], out[8192], path[512];
    snprintf(cmd, sizeof cmd, DARTSPP_BIN RENDER " --spp 1 --no-cube --no-viewer --output %s/fb.exr", tmp);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    assert_null(strstr(out, "_cube.npy"));
    assert_null(strstr(out, "_viewer.html"));
    const char *absent[] = {"fb_cube.npy", "fb_viewer.html"}, *present[] = {"fb_0003.exr", "fb_frames.csv"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/%s", tmp, absent[i]);
        assert_int_not_equal(access(path, F_OK), 0);
        snprintf(path, sizeof path, "%s/%s", tmp, present[i]);
        assert_int_equal(access(path, F_OK), 0);
    }
    snprintf(cmd, sizeof cmd, DARTSPP_BIN RENDER " --spp 1 --no-viewer --output %s/fb.exr", tmp);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    snprintf(path, sizeof path, "%s/fb_cube.npy", tmp);
    assert_int_equal(access(path, F_OK), 0);
    snprintf(path, sizeof path, "%s/fb_viewer.html", tmp);
    assert_int_not_equal(access(path, F_OK), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_header_by_hand, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_wrong_count_leaves_nothing, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_reader, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cube_equals_frames, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_switches, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
