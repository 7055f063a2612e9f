/* Unit tests of the io module: EXR/PFM round trips and bad files, PNG previews, atomic writes,
 * the frame CSV, quantiles and the error metrics. Expected values are worked out by hand. */
#include "test_util.h"

#include "dartspp/io.h"

#include <dirent.h>
#include <ftw.h>
#include <openexr.h>
#include <png.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>

/* ---- helpers ---- */

static void check_close(double got, double want, double tol, int line)
{
    if (!(fabs(got - want) <= tol)) fail_msg("line %d: got %.17g, want %.17g", line, got, want);
}
#define assert_close(got, want, tol) check_close(got, want, tol, __LINE__)

static int remove_entry(const char *p, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(p);
}

static void remove_tree(char *dir)
{
    nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    free(dir);
}

static void join(char *out, size_t n, const char *dir, const char *name)
{
    snprintf(out, n, "%s/%s", dir, name);
}

static void fill(image_rgb *img, int w, int h, const float *v)
{
    dp_error err;
    assert_int_equal(image_alloc(img, w, h, &err), 0);
    memcpy(img->rgb, v, sizeof(float) * 3 * (size_t)w * (size_t)h);
}

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static size_t read_all(const char *path, unsigned char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    size_t n = fread(buf, 1, cap, f);
    fclose(f);
    return n;
}

/* A read that must fail: non-zero, the path in the message, and an empty image. */
static void expect_read_error(int (*reader)(const char *, image_rgb *, dp_error *), const char *path)
{
    image_rgb img = {7, 7, NULL};
    dp_error err = {{0}};
    assert_int_not_equal(reader(path, &img, &err), 0);
    assert_non_null(strstr(err.msg, path));
    assert_null(img.rgb);
}

static int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

/* A deterministic image with values that do not compress away. */
static void noise_image(image_rgb *img, int w, int h)
{
    dp_error err;
    assert_int_equal(image_alloc(img, w, h, &err), 0);
    uint32_t s = 12345;
    for (size_t i = 0; i < (size_t)w * h * 3; ++i) {
        s = s * 1664525u + 1013904223u;
        img->rgb[i] = (float)(s >> 8) / 16777216.0f;
    }
}

/* ---- image_alloc ---- */

static void test_image_alloc(void **state)
{
    (void)state;
    image_rgb img;
    dp_error err;
    assert_int_equal(image_alloc(&img, 3, 2, &err), 0);
    assert_int_equal(img.width, 3);
    assert_int_equal(img.height, 2);
    for (int i = 0; i < 18; ++i) assert_true(img.rgb[i] == 0.0f);
    image_free(&img);
    assert_null(img.rgb);
    assert_int_not_equal(image_alloc(&img, 0, 5, &err), 0);
    assert_null(img.rgb);
    assert_int_not_equal(image_alloc(&img, -3, 5, &err), 0);
    /* 2^15 x 2^15 = 2^30 pixels is over the 2^28 cap: refused before any allocation */
    assert_int_not_equal(image_alloc(&img, 1 << 15, 1 << 15, &err), 0);
    assert_null(img.rgb);
    assert_non_null(strstr(err.msg, "32768x32768"));
}

/* ---- EXR ---- */

static const float special[18] = {1e-30f, 3e38f, -3e38f, 0.0f,   -0.0f, 1e-40f /* denormal */,
                                  1.0f,   0.5f,  -2.25f, 1.0e7f, 3.14159265f, 123456.789f,
                                  -1e-30f, 65504.0f, 65505.0f, 1e-8f, 7.0f, 0.1f};

static void test_exr_roundtrip_bitexact_and_attributes(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "a.exr");
    image_rgb img, back;
    dp_error err;
    fill(&img, 3, 2, special);
    image_meta meta = {"optical path length in scene units (c = 1)", 1, 2.5, 3.75, 1, 4, "path_tracer", "{\"x\":1}", 7};
    assert_int_equal(exr_write(path, &img, &meta, &err), 0);
    int passes = 0;
    assert_int_equal(exr_read_int_attribute(path, "dartspp.passes", &passes, &err), 0); /* the pass count round trip */
    assert_int_equal(passes, 7);
    assert_int_equal(exr_read(path, &back, &err), 0);
    assert_int_equal(back.width, 3);
    assert_int_equal(back.height, 2);
    assert_memory_equal(back.rgb, special, sizeof special);

    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_read(&ctx, path, NULL), EXR_ERR_SUCCESS);
    const char *s = NULL;
    int32_t len = 0, iv = 0;
    double d = 0;
    exr_compression_t comp;
    assert_int_equal(exr_attr_get_string(ctx, 0, "dartspp.timeUnit", &len, &s), EXR_ERR_SUCCESS);
    assert_string_equal(s, "optical path length in scene units (c = 1)");
    assert_int_equal(exr_attr_get_double(ctx, 0, "dartspp.gateStart", &d), EXR_ERR_SUCCESS);
    assert_true(d == 2.5);
    assert_int_equal(exr_attr_get_double(ctx, 0, "dartspp.gateEnd", &d), EXR_ERR_SUCCESS);
    assert_true(d == 3.75);
    assert_int_equal(exr_attr_get_int(ctx, 0, "dartspp.cameraWarped", &iv), EXR_ERR_SUCCESS);
    assert_int_equal(iv, 1);
    assert_int_equal(exr_attr_get_int(ctx, 0, "dartspp.frame", &iv), EXR_ERR_SUCCESS);
    assert_int_equal(iv, 4);
    assert_int_equal(exr_attr_get_string(ctx, 0, "dartspp.plan", &len, &s), EXR_ERR_SUCCESS);
    assert_string_equal(s, "{\"x\":1}");
    assert_int_equal(exr_get_compression(ctx, 0, &comp), EXR_ERR_SUCCESS);
    assert_int_equal(comp, EXR_COMPRESSION_ZIP);
    const exr_attr_chlist_t *cl = NULL;
    assert_int_equal(exr_get_channels(ctx, 0, &cl), EXR_ERR_SUCCESS);
    assert_int_equal(cl->num_channels, 3);
    for (int i = 0; i < 3; ++i) assert_int_equal(cl->entries[i].pixel_type, EXR_PIXEL_FLOAT);
    exr_finish(&ctx);
    image_free(&img);
    image_free(&back);
    remove_tree(dir);
}

static void test_exr_steady_state_and_null_meta(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), a[512], b[512];
    join(a, sizeof a, dir, "steady.exr");
    join(b, sizeof b, dir, "plain.exr");
    image_rgb img;
    dp_error err;
    fill(&img, 3, 2, special);
    image_meta meta = {"t", 0, 9.0, 10.0, 0, -1, NULL, NULL, 0};
    assert_int_equal(exr_write(a, &img, &meta, &err), 0);
    int passes = -1;
    assert_int_equal(exr_read_int_attribute(a, "dartspp.passes", &passes, &err), -1); /* 0 passes: not written */
    assert_non_null(strstr(err.msg, "dartspp.passes"));
    assert_int_equal(exr_write(b, &img, NULL, &err), 0);
    exr_context_t ctx = NULL;
    double d;
    int32_t iv = 0;
    assert_int_equal(exr_start_read(&ctx, a, NULL), EXR_ERR_SUCCESS);
    assert_int_equal(exr_attr_get_double(ctx, 0, "dartspp.gateStart", &d), EXR_ERR_NO_ATTR_BY_NAME);
    assert_int_equal(exr_attr_get_double(ctx, 0, "dartspp.gateEnd", &d), EXR_ERR_NO_ATTR_BY_NAME);
    assert_int_equal(exr_attr_get_int(ctx, 0, "dartspp.frame", &iv), EXR_ERR_SUCCESS);
    assert_int_equal(iv, -1);
    exr_finish(&ctx);
    assert_int_equal(exr_start_read(&ctx, b, NULL), EXR_ERR_SUCCESS);
    assert_int_equal(exr_attr_get_int(ctx, 0, "dartspp.frame", &iv), EXR_ERR_NO_ATTR_BY_NAME);
    exr_finish(&ctx);
    image_free(&img);
    remove_tree(dir);
}

/* Writes an uncompressed EXR whose channels all have one pixel type, from planar buffers. */
static void write_planar_exr(const char *path, int w, int h, int n, const char *const *names,
                             exr_pixel_type_t type, const void *const *planes)
{
    exr_context_t ctx = NULL;
    int part = 0, bpe = type == EXR_PIXEL_HALF ? 2 : 4;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part), EXR_ERR_SUCCESS);
    assert_int_equal(exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_NONE), 0);
    for (int c = 0; c < n; ++c)
        assert_int_equal(exr_add_channel(ctx, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1), 0);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int y = 0; y < h; ++y) { /* uncompressed: one scanline per chunk */
        exr_chunk_info_t ci;
        assert_int_equal(exr_write_scanline_chunk_info(ctx, part, y, &ci), EXR_ERR_SUCCESS);
        if (y == 0) assert_int_equal(exr_encoding_initialize(ctx, part, &ci, &enc), EXR_ERR_SUCCESS);
        else assert_int_equal(exr_encoding_update(ctx, part, &ci, &enc), EXR_ERR_SUCCESS);
        for (int c = 0; c < enc.channel_count; ++c) {
            int k = 0;
            while (strcmp(names[k], enc.channels[c].channel_name)) ++k;
            enc.channels[c].user_bytes_per_element = (int16_t)bpe;
            enc.channels[c].user_data_type = (uint16_t)type;
            enc.channels[c].user_pixel_stride = bpe;
            enc.channels[c].user_line_stride = bpe * w;
            enc.channels[c].encode_from_ptr = (const uint8_t *)planes[k] + (size_t)y * w * bpe;
        }
        if (y == 0) assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), 0);
        assert_int_equal(exr_encoding_run(ctx, part, &enc), EXR_ERR_SUCCESS);
    }
    exr_encoding_destroy(ctx, &enc);
    assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
}

static void test_exr_reads_half_uint_and_grey(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err;

    /* HALF R,G,B plus an ignored channel A; 1.5 = 0x3E00, 0.25 = 0x3400, -2 = 0xC000, 65504 = 0x7BFF */
    const uint16_t r[2] = {0x3E00, 0x3400}, g[2] = {0xC000, 0x7BFF}, b[2] = {0x0000, 0x3C00},
                   a[2] = {0x3C00, 0x3C00};
    const char *const rgba[4] = {"R", "G", "B", "A"};
    const void *const rgba_planes[4] = {r, g, b, a};
    join(path, sizeof path, dir, "half.exr");
    write_planar_exr(path, 2, 1, 4, rgba, EXR_PIXEL_HALF, rgba_planes);
    assert_int_equal(exr_read(path, &img, &err), 0);
    const float want_half[6] = {1.5f, -2.0f, 0.0f, 0.25f, 65504.0f, 1.0f};
    assert_memory_equal(img.rgb, want_half, sizeof want_half);
    image_free(&img);

    /* UINT Y only: grey copied to R, G, B; 4000000000 is exactly a float (0xEE6B28 << 8) */
    const uint32_t y[2] = {7u, 4000000000u};
    const char *const ynames[1] = {"Y"};
    const void *const yplanes[1] = {y};
    join(path, sizeof path, dir, "uint_y.exr");
    write_planar_exr(path, 1, 2, 1, ynames, EXR_PIXEL_UINT, yplanes);
    assert_int_equal(exr_read(path, &img, &err), 0);
    assert_int_equal(img.width, 1);
    assert_int_equal(img.height, 2);
    const float want_y[6] = {7.0f, 7.0f, 7.0f, 4.0e9f, 4.0e9f, 4.0e9f};
    assert_memory_equal(img.rgb, want_y, sizeof want_y);
    image_free(&img);

    /* neither R, G, B nor Y */
    const char *const znames[1] = {"Z"};
    join(path, sizeof path, dir, "z.exr");
    write_planar_exr(path, 1, 2, 1, znames, EXR_PIXEL_UINT, yplanes);
    expect_read_error(exr_read, path);
    remove_tree(dir);
}

static void test_exr_truncated_and_garbage(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "t.exr");
    image_rgb img;
    dp_error err;
    noise_image(&img, 64, 40); /* 3 chunks of 16 scanlines */
    assert_int_equal(exr_write(path, &img, NULL, &err), 0);
    long n = file_size(path);
    assert_true(n > 1000);
    const long cuts[] = {n - 1, n / 2, 300, 40, 10, 3, 0};
    for (size_t i = 0; i < sizeof cuts / sizeof *cuts; ++i) {
        assert_int_equal(truncate(path, cuts[i]), 0);
        expect_read_error(exr_read, path);
    }
    test_write_file(path, "this is not an image at all, just some text\n");
    expect_read_error(exr_read, path);
    const unsigned char magic_then_junk[24] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0, 'x', 'y', 0, 'q'};
    write_bytes(path, magic_then_junk, sizeof magic_then_junk);
    expect_read_error(exr_read, path);
    join(path, sizeof path, dir, "missing.exr");
    expect_read_error(exr_read, path);
    image_free(&img);
    remove_tree(dir);
}

/* Flipping bytes all over a valid file must give an image or an error, never a crash (ASan). */
static void test_exr_corrupted_bytes_never_crash(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "c.exr");
    image_rgb img, back;
    dp_error err;
    noise_image(&img, 20, 20);
    assert_int_equal(exr_write(path, &img, NULL, &err), 0);
    static unsigned char good[1 << 16], bad[1 << 16];
    size_t n = read_all(path, good, sizeof good);
    assert_true(n > 500 && n < sizeof good);
    for (size_t pos = 0; pos < n; pos += 7) {
        memcpy(bad, good, n);
        bad[pos] ^= 0xA5;
        write_bytes(path, bad, n);
        err.msg[0] = 0;
        if (exr_read(path, &back, &err) == 0) image_free(&back);
        else assert_non_null(strstr(err.msg, path));
    }
    image_free(&img);
    remove_tree(dir);
}

/* ---- PFM ---- */

/* OpenEXRCore <= 3.4.7 stores a ZIP chunk whose zlib output has exactly the packed size as zlib bytes, which
 * readers take for raw data (openexr issue #2306); exr_write guards against it. One 64 × 16 chunk (12288
 * bytes) of r random floats and zeros, plus one float with b random low bits: r and b sweep the zlib size
 * through the packed size in steps of a fraction of a byte, so some variant lands on it exactly. Every
 * variant must read back bit-exact. (Without the guard, Debian 12's OpenEXRCore 3.1.5 corrupted variants
 * of this sweep — 2 of 425 — reading back NaN and values near 1e38.) */
static void test_exr_roundtrip_at_the_zip_size_boundary(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "z.exr");
    const int w = 64, h = 16, n = w * h * 3;
    image_rgb img, back;
    dp_error err;
    assert_int_equal(image_alloc(&img, w, h, &err), 0);
    long variants = 0, bad = 0, raw_sized = 0;
    for (int r = n - 24; r <= n; r++)
        for (int b = 0; b <= 32; b += 2) {
            uint64_t x = 0x9e3779b97f4a7c15ULL * (uint64_t)(r * 64 + b + 1);
            for (int i = 0; i < n; i++) {
                x ^= x << 13, x ^= x >> 7, x ^= x << 17;
                uint32_t bits = i < r ? (uint32_t)x : i == r ? (uint32_t)x & (uint32_t)((1ULL << b) - 1) : 0u;
                bits &= 0xbf7fffffu; /* keep it finite: exponent never all ones */
                memcpy(&img.rgb[i], &bits, 4);
            }
            assert_int_equal(exr_write(path, &img, NULL, &err), 0);
            assert_int_equal(exr_read(path, &back, &err), 0);
            bad += memcmp(back.rgb, img.rgb, sizeof(float) * (size_t)n) != 0;
            image_free(&back);
            exr_context_t ctx = NULL;
            exr_chunk_info_t ci;
            assert_int_equal(exr_start_read(&ctx, path, NULL), EXR_ERR_SUCCESS);
            assert_int_equal(exr_read_scanline_chunk_info(ctx, 0, 0, &ci), EXR_ERR_SUCCESS);
            raw_sized += ci.packed_size == ci.unpacked_size;
            exr_finish(&ctx);
            variants++;
        }
    print_message("  %ld variants, %ld stored at the raw size, %ld read back wrong\n", variants, raw_sized, bad);
    assert_true(raw_sized > 0 && raw_sized < variants); /* the sweep crosses the boundary */
    assert_int_equal(bad, 0);
    image_free(&img);
    remove_tree(dir);
}

static void test_pfm_roundtrip_bitexact(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "a.pfm");
    image_rgb img, back;
    dp_error err;
    fill(&img, 2, 3, special);
    img.rgb[4] = NAN;
    img.rgb[7] = -INFINITY;
    assert_int_equal(pfm_write(path, &img, &err), 0);
    assert_int_equal(pfm_read(path, &back, &err), 0);
    assert_int_equal(back.width, 2);
    assert_int_equal(back.height, 3);
    assert_memory_equal(back.rgb, img.rgb, sizeof special);
    image_free(&img);
    image_free(&back);
    remove_tree(dir);
}

static void test_pfm_bytes_on_disk(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "b.pfm");
    image_rgb img;
    dp_error err;
    /* top row: (1,2,0.5) (-1,0,0); bottom row: (2,2,2) (0.5,1,-1) */
    const float v[12] = {1, 2, 0.5f, -1, 0, 0, 2, 2, 2, 0.5f, 1, -1};
    fill(&img, 2, 2, v);
    assert_int_equal(pfm_write(path, &img, &err), 0);
    /* little-endian IEEE: 1 = 00 00 80 3F, 2 = 00 00 00 40, 0.5 = 00 00 00 3F, -1 = 00 00 80 BF */
    const unsigned char want[] = {
        'P', 'F', '\n', '2', ' ', '2', '\n', '-', '1', '\n',
        /* bottom image row first */
        0, 0, 0, 0x40, 0, 0, 0, 0x40, 0, 0, 0, 0x40, 0, 0, 0, 0x3F, 0, 0, 0x80, 0x3F, 0, 0, 0x80, 0xBF,
        /* then the top row */
        0, 0, 0x80, 0x3F, 0, 0, 0, 0x40, 0, 0, 0, 0x3F, 0, 0, 0x80, 0xBF, 0, 0, 0, 0, 0, 0, 0, 0};
    unsigned char got[256];
    size_t n = read_all(path, got, sizeof got);
    assert_int_equal(n, sizeof want);
    assert_memory_equal(got, want, sizeof want);
    image_free(&img);
    remove_tree(dir);
}

static void test_pfm_grey_and_big_endian(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "g.pfm");
    image_rgb img;
    dp_error err;
    /* "Pf", 2x1, big-endian (scale +1): 2.0 = 40 00 00 00, -0.5 = BF 00 00 00 */
    const unsigned char grey[] = {'P', 'f', '\n', '2', ' ', '1', '\n', '1', '.', '0', '\n',
                                  0x40, 0, 0, 0, 0xBF, 0, 0, 0};
    write_bytes(path, grey, sizeof grey);
    assert_int_equal(pfm_read(path, &img, &err), 0);
    const float want_grey[6] = {2, 2, 2, -0.5f, -0.5f, -0.5f};
    assert_memory_equal(img.rgb, want_grey, sizeof want_grey);
    image_free(&img);
    /* "PF", 1x2, big-endian; file rows bottom-up: bottom (1,2,0.5), top (-1,0,2) */
    const unsigned char rgb[] = {'P', 'F', '\n', '1', ' ', '2', '\n', '1', '\n',
                                 0x3F, 0x80, 0, 0, 0x40, 0, 0, 0, 0x3F, 0, 0, 0,
                                 0xBF, 0x80, 0, 0, 0, 0, 0, 0, 0x40, 0, 0, 0};
    write_bytes(path, rgb, sizeof rgb);
    assert_int_equal(pfm_read(path, &img, &err), 0);
    const float want_rgb[6] = {-1, 0, 2, 1, 2, 0.5f};
    assert_memory_equal(img.rgb, want_rgb, sizeof want_rgb);
    image_free(&img);
    remove_tree(dir);
}

static void test_pfm_bad_inputs(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "bad.pfm");
    const unsigned char four_floats[10 + 16] = {'P', 'F', '\n', '2', ' ', '2', '\n', '-', '1', '\n'};
    write_bytes(path, four_floats, sizeof four_floats); /* 2x2 RGB needs 48 bytes, has 16 */
    expect_read_error(pfm_read, path);
    /* declares 10^5 x 10^5 pixels (120 GB): must fail on the size check, not try to allocate */
    test_write_file(path, "PF\n100000 100000\n-1\n0123456789abcdef");
    expect_read_error(pfm_read, path);
    test_write_file(path, "PF\n2147483647 2147483647\n-1\n");
    expect_read_error(pfm_read, path);
    test_write_file(path, "PF\n-2 2\n-1\n0123");
    expect_read_error(pfm_read, path);
    test_write_file(path, "PF\n1 1\n0\n0123456789ab");
    expect_read_error(pfm_read, path);
    test_write_file(path, "P6\n1 1\n255\nabc");
    expect_read_error(pfm_read, path);
    test_write_file(path, "PF\n1 1");
    expect_read_error(pfm_read, path);
    const unsigned char trailing[10 + 24] = {'P', 'F', '\n', '1', ' ', '1', '\n', '-', '1', '\n'};
    write_bytes(path, trailing, sizeof trailing); /* 1x1 RGB is 12 bytes of data, not 24 */
    expect_read_error(pfm_read, path);
    test_write_file(path, "");
    expect_read_error(pfm_read, path);
    join(path, sizeof path, dir, "missing.pfm");
    expect_read_error(pfm_read, path);
    expect_read_error(pfm_read, dir); /* a folder */
    remove_tree(dir);
}

/* ---- quantile and metrics ---- */

static void test_quantile_known_set(void **state)
{
    (void)state;
    image_rgb img;
    /* the values 1..12 shuffled */
    const float v[12] = {7, 3, 12, 1, 9, 5, 11, 2, 8, 10, 4, 6};
    fill(&img, 2, 2, v);
    /* nearest rank: index ceil(q*12)-1 of the sorted values */
    assert_true(image_quantile(&img, 0.5) == 6.0);   /* ceil(6)-1 = 5 */
    assert_true(image_quantile(&img, 0.25) == 3.0);  /* ceil(3)-1 = 2 */
    assert_true(image_quantile(&img, 0.26) == 4.0);  /* ceil(3.12)-1 = 3 */
    assert_true(image_quantile(&img, 0.99) == 12.0); /* ceil(11.88)-1 = 11 */
    assert_true(image_quantile(&img, 1.0) == 12.0);
    assert_true(image_quantile(&img, 0.0) == 1.0); /* clamped to index 0 */
    /* non-finite values are left out: 9 finite values 1..12 minus {12, 1, 5} */
    img.rgb[2] = NAN;
    img.rgb[3] = INFINITY;
    img.rgb[5] = -INFINITY;
    assert_true(image_quantile(&img, 1.0) == 11.0);
    assert_true(image_quantile(&img, 0.0) == 2.0);
    assert_true(image_quantile(&img, 0.5) == 7.0); /* sorted 2,3,4,6,7,..: ceil(4.5)-1 = 4 */
    for (int i = 0; i < 12; ++i) img.rgb[i] = NAN;
    assert_true(image_quantile(&img, 0.5) == 0.0);
    image_free(&img);
}

static void test_quantile_negative_values(void **state)
{
    (void)state;
    image_rgb img;
    /* sorted: -10, -3, -0.5, 0, 1.25, 2 */
    const float v[6] = {-3, -0.5f, 2, -10, 0, 1.25f};
    fill(&img, 2, 1, v);
    assert_true(image_quantile(&img, 0.0) == -10.0);
    assert_true(image_quantile(&img, 0.3) == -3.0);  /* ceil(1.8)-1 = 1 */
    assert_true(image_quantile(&img, 0.34) == -0.5); /* ceil(2.04)-1 = 2 */
    assert_true(image_quantile(&img, 0.5) == -0.5);  /* ceil(3)-1 = 2 */
    assert_true(image_quantile(&img, 0.51) == 0.0);  /* ceil(3.06)-1 = 3 */
    assert_true(image_quantile(&img, 1.0) == 2.0);
    image_free(&img);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Against the definition: sort the finite values, take index ceil(q*n)-1. Random values of both
 * signs and many magnitudes, with repeats, zeros and non-finite values mixed in. */
static void test_quantile_matches_sorted_definition(void **state)
{
    (void)state;
    image_rgb img;
    dp_error err;
    assert_int_equal(image_alloc(&img, 101, 37, &err), 0);
    size_t total = 101 * 37 * 3, n = 0;
    float *sorted = malloc(total * sizeof *sorted);
    assert_non_null(sorted);
    uint32_t s = 99;
    for (size_t i = 0; i < total; ++i) {
        s = s * 1664525u + 1013904223u;
        int kind = (int)(s >> 28);
        float mag = (float)((s >> 8) & 0xfffff) * ldexpf(1.0f, (int)((s >> 3) & 31) - 20);
        img.rgb[i] = kind == 0 ? 0.0f : kind == 1 ? NAN : kind == 2 ? INFINITY : kind == 3 ? 0.75f
                   : (kind & 1) ? -mag : mag;
        if (isfinite(img.rgb[i])) sorted[n++] = img.rgb[i];
    }
    qsort(sorted, n, sizeof *sorted, cmp_float);
    const double qs[] = {0.0, 0.001, 0.1, 0.25, 0.5, 0.7, 0.9, 0.99, 0.999, 1.0};
    for (size_t i = 0; i < sizeof qs / sizeof *qs; ++i) {
        double r = ceil(qs[i] * (double)n) - 1.0;
        size_t k = r < 0 ? 0 : (size_t)r;
        assert_true(image_quantile(&img, qs[i]) == (double)sorted[k]);
    }
    free(sorted);
    image_free(&img);
}

/* Reference (3x1): (1,1,1) (0,0,0) (2,2,2); image differs by (1,0,0) (0,1,0) (0,0,-2).
 * Squared errors 1, 1, 4 over 9 values: mse = 6/9. q99 = index ceil(8.91)-1 = 8 = max = 2. */
static const float ref3[9] = {1, 1, 1, 0, 0, 0, 2, 2, 2};
static const float img3[9] = {2, 1, 1, 0, 1, 0, 2, 2, 0};

static void check_hand_metrics(const image_error *e)
{
    double rel = (1.0 / 1.01 + 1.0 / 0.01 + 4.0 / 4.01) / 9.0;
    assert_close(e->mse, 6.0 / 9.0, 1e-15);
    assert_close(e->rmse, sqrt(6.0 / 9.0), 1e-15);
    assert_close(e->rel_mse, rel, 1e-12);
    assert_true(e->q99 == 2.0);
    assert_close(e->mse_q99, (0.25 + 0.25 + 1.0) / 9.0, 1e-15); /* errors halved */
}

static void test_compare_hand_values(void **state)
{
    (void)state;
    image_rgb img, ref;
    image_error e;
    dp_error err;
    fill(&img, 3, 1, img3);
    fill(&ref, 3, 1, ref3);
    assert_int_equal(image_compare(&img, &ref, &e, &err), 0);
    check_hand_metrics(&e);
    assert_int_equal(e.nonfinite, 0);
    assert_int_equal(e.pixels, 3);
    assert_int_equal(image_compare(&ref, &ref, &e, &err), 0);
    assert_true(e.mse == 0.0 && e.rel_mse == 0.0 && e.mse_q99 == 0.0);
    image_free(&img);
    image_free(&ref);
}

/* Mean of independent renders and the variance of that mean, by hand: values {1, 3} and {2, 2, 5}. */
static void test_mean_of_hand_values(void **state)
{
    (void)state;
    image_rgb in[3], mean;
    dp_error err;
    double v;
    const float a[3] = {1, 2, 0}, b[3] = {3, 2, 0}, c[3] = {0, 5, 0};
    fill(&in[0], 1, 1, a);
    fill(&in[1], 1, 1, b);
    fill(&in[2], 1, 1, c);
    /* k = 2: means (2, 2, 0); s² = (2, 0, 0); V = mean of s²/2 = (1 + 0 + 0)/3 */
    assert_int_equal(image_mean_of(in, 2, &mean, &v, &err), 0);
    assert_true(mean.rgb[0] == 2.0f && mean.rgb[1] == 2.0f && mean.rgb[2] == 0.0f);
    assert_close(v, 1.0 / 3.0, 1e-15);
    image_free(&mean);
    /* k = 3: channel 0 {1,3,0}: mean 4/3, s² = (1/9 + 25/9 + 16/9)/2 = 7/3; channel 1 {2,2,5}: mean 3,
     * s² = (1 + 1 + 4)/2 = 3; V = (7/3 + 3 + 0)/3/3 */
    assert_int_equal(image_mean_of(in, 3, &mean, &v, &err), 0);
    assert_close(mean.rgb[0], 4.0 / 3.0, 1e-7);
    assert_close(mean.rgb[1], 3.0, 1e-7);
    assert_close(v, (7.0 / 3.0 + 3.0) / 9.0, 1e-12);
    image_free(&mean);
    /* a NaN stays in the mean and is left out of V: channel 0 of image 3 */
    in[2].rgb[0] = NAN;
    assert_int_equal(image_mean_of(in, 3, &mean, &v, &err), 0);
    assert_true(isnan(mean.rgb[0]));
    assert_close(v, 3.0 / 3.0 / 2.0, 1e-12); /* (s²/k = 1 for channel 1, 0 for channel 2) over 2 values */
    image_free(&mean);
    /* one image, or different sizes: refused */
    assert_int_equal(image_mean_of(in, 1, &mean, &v, &err), -1);
    image_rgb big;
    const float d[6] = {0};
    fill(&big, 2, 1, d);
    image_rgb pair[2] = {in[0], big};
    assert_int_equal(image_mean_of(pair, 2, &mean, &v, &err), -1);
    assert_non_null(strstr(err.msg, "2x1"));
    image_free(&big);
    for (int j = 0; j < 3; j++) image_free(&in[j]);
}

static void test_compare_nonfinite_excluded(void **state)
{
    (void)state;
    image_rgb img, ref;
    image_error e;
    dp_error err;
    /* the 3x1 case plus a 4th pixel (0.5,0.5,0.5) in both; q99 of 12 values is still the max, 2 */
    float iv[12], rv[12];
    memcpy(iv, img3, sizeof img3);
    memcpy(rv, ref3, sizeof ref3);
    for (int c = 9; c < 12; ++c) iv[c] = rv[c] = 0.5f;
    iv[10] = NAN; /* NaN in the image */
    fill(&img, 2, 2, iv);
    fill(&ref, 2, 2, rv);
    assert_int_equal(image_compare(&img, &ref, &e, &err), 0);
    check_hand_metrics(&e);
    assert_int_equal(e.nonfinite, 1);
    assert_int_equal(e.pixels, 3);
    img.rgb[10] = 0.5f;
    ref.rgb[9] = INFINITY; /* Inf in the reference: 11 finite values, index ceil(10.89)-1 = 10 = 2 */
    assert_int_equal(image_compare(&img, &ref, &e, &err), 0);
    check_hand_metrics(&e);
    assert_int_equal(e.nonfinite, 1);
    assert_int_equal(e.pixels, 3);
    image_free(&img);
    image_free(&ref);
}

static void test_compare_zero_reference(void **state)
{
    (void)state;
    image_rgb img, ref;
    image_error e;
    dp_error err;
    const float zero[12] = {0}, v[12] = {1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, -1};
    fill(&img, 2, 2, v);
    fill(&ref, 2, 2, zero);
    assert_int_equal(image_compare(&img, &ref, &e, &err), 0);
    /* squared errors 1 + 4 + 1 = 6 over 12 values */
    assert_close(e.mse, 0.5, 1e-15);
    assert_true(e.q99 == 0.0);
    assert_true(e.mse_q99 == e.mse);
    assert_close(e.rel_mse, 6.0 / 0.01 / 12.0, 1e-9);
    assert_true(isfinite(e.rmse) && isfinite(e.rel_mse) && isfinite(e.mse_q99));
    image_free(&img);
    image_free(&ref);
}

static void test_compare_size_mismatch(void **state)
{
    (void)state;
    image_rgb img, ref;
    image_error e;
    dp_error err = {{0}};
    fill(&img, 3, 1, img3);
    assert_int_equal(image_alloc(&ref, 1, 3, &err), 0);
    assert_int_not_equal(image_compare(&img, &ref, &e, &err), 0);
    assert_non_null(strstr(err.msg, "3x1"));
    assert_non_null(strstr(err.msg, "1x3"));
    image_free(&img);
    image_free(&ref);
}

/* ---- PNG preview ---- */

static unsigned char *read_png(const char *path, int *w, int *h)
{
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    assert_true(png_image_begin_read_from_file(&pi, path));
    pi.format = PNG_FORMAT_RGB;
    unsigned char *buf = malloc(PNG_IMAGE_SIZE(pi));
    assert_non_null(buf);
    assert_true(png_image_finish_read(&pi, NULL, buf, 0, NULL));
    *w = (int)pi.width;
    *h = (int)pi.height;
    return buf;
}

static void test_png_preview_values(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "p.png");
    image_rgb img;
    dp_error err;
    /* 10 finite values; the 0.99 quantile (index ceil(9.9)-1 = 9) is the largest, 4. Linear 0.5 is sRGB 187.5 -> 188. */
    const float v[12] = {0, 0, 0, NAN, 4, INFINITY, 4, 2, -1, 8, 1e-9f, 2};
    fill(&img, 2, 2, v);
    img.rgb[9] = 3.0f; /* keep 4 the maximum */
    assert_int_equal(png_write_preview(path, &img, &err), 0);
    int w, h;
    unsigned char *px = read_png(path, &w, &h);
    assert_int_equal(w, 2);
    assert_int_equal(h, 2);
    const unsigned char want[12] = {0, 0, 0, 0, 255, 0, 255, 188, 0, 0, 0, 188};
    for (int i = 0; i < 12; ++i)
        if (i != 9 && i != 10) assert_int_equal(px[i], want[i]);
    assert_true(px[9] > 188 && px[9] < 255); /* 3/4 */
    assert_true(px[10] <= 1);                /* 2.5e-10 */
    free(px);
    image_free(&img);
    remove_tree(dir);
}

static void test_png_preview_zero_quantile(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "z.png");
    image_rgb img;
    dp_error err;
    /* 40x1: 120 values, one of them 0.5. q99 = index ceil(118.8)-1 = 118 = 0, so the scale is 1. */
    assert_int_equal(image_alloc(&img, 40, 1, &err), 0);
    img.rgb[61] = 0.5f;
    assert_int_equal(png_write_preview(path, &img, &err), 0);
    int w, h;
    unsigned char *px = read_png(path, &w, &h);
    assert_int_equal(w, 40);
    assert_int_equal(h, 1);
    for (int i = 0; i < 120; ++i) assert_int_equal(px[i], i == 61 ? 188 : 0);
    free(px);
    image_free(&img);
    remove_tree(dir);
}

/* ---- atomic writes ---- */

static void test_atomic_no_temp_left(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err;
    fill(&img, 3, 2, special);
    const char *names[] = {"a.exr", "a.pfm", "a.png", "a.csv"};
    for (int round = 0; round < 2; ++round) { /* the second round overwrites */
        join(path, sizeof path, dir, names[0]);
        assert_int_equal(exr_write(path, &img, NULL, &err), 0);
        join(path, sizeof path, dir, names[1]);
        assert_int_equal(pfm_write(path, &img, &err), 0);
        join(path, sizeof path, dir, names[2]);
        assert_int_equal(png_write_preview(path, &img, &err), 0);
        join(path, sizeof path, dir, names[3]);
        assert_int_equal(frames_csv_write(path, 2, 0.0, 1.0, &err), 0);
    }
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        assert_true(file_size(path) > 0);
    }
    assert_int_equal(count_temp_files(dir), 0);
    image_free(&img);
    remove_tree(dir);
}

static void test_atomic_missing_folder_and_make_parent_dirs(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err = {{0}};
    fill(&img, 3, 2, special);
    const char *names[] = {"x/y/z/a.exr", "x/y/z/a.pfm", "x/y/z/a.png", "x/y/z/a.csv"};
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        err.msg[0] = 0;
        int rc = i == 0   ? exr_write(path, &img, NULL, &err)
                 : i == 1 ? pfm_write(path, &img, &err)
                 : i == 2 ? png_write_preview(path, &img, &err)
                          : frames_csv_write(path, 1, 0.0, 1.0, &err);
        assert_int_not_equal(rc, 0);
        assert_non_null(strstr(err.msg, path));
        assert_non_null(strstr(err.msg, "No such file or directory"));
    }
    join(path, sizeof path, dir, names[1]);
    assert_int_equal(io_make_parent_dirs(path, &err), 0);
    assert_int_equal(io_make_parent_dirs(path, &err), 0); /* already there */
    assert_int_equal(pfm_write(path, &img, &err), 0);
    assert_int_equal(count_temp_files(dir), 0);
    /* a file where a folder should be */
    join(path, sizeof path, dir, "x/y/z/a.pfm/b/c.exr");
    assert_int_not_equal(io_make_parent_dirs(path, &err), 0);
    assert_non_null(strstr(err.msg, path));
    image_free(&img);
    remove_tree(dir);
}

/* A write that fails half-way (file size limit) reports the path, leaves the old file untouched
 * and removes its temporary file. */
static void test_atomic_failed_write_keeps_old_file(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err = {{0}};
    noise_image(&img, 64, 64); /* 48 KiB of pixels */
    const char *names[] = {"f.exr", "f.pfm", "f.png", "f.csv"};
    long before[4];
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        test_write_file(path, "old");
        before[i] = file_size(path);
    }
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    lim = old;
    lim.rlim_cur = 4096;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    int rc[4];
    dp_error msgs[4];
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        rc[i] = i == 0   ? exr_write(path, &img, NULL, &msgs[i])
                : i == 1 ? pfm_write(path, &img, &msgs[i])
                : i == 2 ? png_write_preview(path, &img, &msgs[i])
                         : frames_csv_write(path, 1000, 0.0, 1.0, &msgs[i]);
    }
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, old_handler);
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        assert_int_not_equal(rc[i], 0);
        assert_non_null(strstr(msgs[i].msg, path));
        assert_int_equal(file_size(path), before[i]);
    }
    assert_int_equal(count_temp_files(dir), 0);
    (void)err;
    image_free(&img);
    remove_tree(dir);
}

static void test_atomic_open_commit_abort(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512], tmp[600];
    dp_error err;
    join(path, sizeof path, dir, "f.txt");
    int fd = atomic_open(path, tmp, sizeof tmp, &err);
    assert_true(fd >= 0);
    assert_non_null(strstr(tmp, ".tmp."));
    assert_int_equal(write(fd, "abc", 3), 3);
    atomic_abort(fd, tmp);
    assert_int_equal(file_size(path), -1);
    assert_int_equal(file_size(tmp), -1);
    fd = atomic_open(path, tmp, sizeof tmp, &err);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, "hello", 5), 5);
    assert_int_equal(file_size(path), -1); /* not visible before the commit */
    assert_int_equal(atomic_commit(fd, tmp, path, &err), 0);
    assert_int_equal(file_size(path), 5);
    assert_int_equal(file_size(tmp), -1);
    remove_tree(dir);
}

/* The stream form: nothing visible before the close, nothing left by an abort or a failed write. */
static void test_atomic_fopen_fclose_fabort(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    dp_error err = {{0}};
    atomic_file af;
    join(path, sizeof path, dir, "s.txt");
    FILE *f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("abc", f) >= 0, 1);
    atomic_fabort(&af);
    assert_int_equal(file_size(path), -1);
    assert_int_equal(count_temp_files(dir), 0);
    f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("hello", f) >= 0, 1);
    assert_int_equal(atomic_fclose(&af, 1, &err), -1); /* the caller's write failed */
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "write failed"));
    assert_int_equal(file_size(path), -1);
    assert_int_equal(count_temp_files(dir), 0);
    f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("hello", f) >= 0, 1);
    assert_int_equal(file_size(path), -1); /* not visible before the close */
    assert_int_equal(atomic_fclose(&af, 0, &err), 0);
    assert_int_equal(file_size(path), 5);
    assert_int_equal(count_temp_files(dir), 0);
    join(path, sizeof path, dir, "no/such/s.txt");
    assert_null(atomic_fopen(path, "w", &af, &err));
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "No such file or directory"));
    remove_tree(dir);
}

/* ---- frame CSV ---- */

static void test_frames_csv(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "frames.csv");
    dp_error err;
    char text[512];
    assert_int_equal(frames_csv_write(path, 3, 1.5, 0.25, &err), 0);
    text[read_all(path, (unsigned char *)text, sizeof text - 1)] = 0;
    assert_string_equal(text, "index,start,end\n0,1.5,1.75\n1,1.75,2\n2,2,2.25\n");
    /* 0.1 steps are not exact in binary: the printed values must parse back to the same doubles */
    assert_int_equal(frames_csv_write(path, 3, 0.1, 0.1, &err), 0);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(text, sizeof text, f));
    assert_string_equal(text, "index,start,end\n");
    int k, rows = 0;
    double s, e;
    while (fscanf(f, "%d,%lf,%lf\n", &k, &s, &e) == 3) {
        assert_int_equal(k, rows);
        assert_true(s == 0.1 + k * 0.1);
        assert_true(e == 0.1 + (k + 1) * 0.1);
        ++rows;
    }
    fclose(f);
    assert_int_equal(rows, 3);
    assert_int_not_equal(frames_csv_write(path, -1, 0.0, 1.0, &err), 0);
    remove_tree(dir);
}

/* ---- dispatch ---- */

static void test_image_dispatch_by_extension(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img, back;
    dp_error err = {{0}};
    fill(&img, 3, 2, special);
    const char *ok[] = {"d.exr", "d.pfm", "D.EXR"};
    for (int i = 0; i < 3; ++i) {
        join(path, sizeof path, dir, ok[i]);
        assert_int_equal(image_write(path, &img, NULL, &err), 0);
        assert_int_equal(image_read(path, &back, &err), 0);
        assert_memory_equal(back.rgb, img.rgb, sizeof special);
        image_free(&back);
    }
    join(path, sizeof path, dir, "d.txt");
    assert_int_not_equal(image_write(path, &img, NULL, &err), 0);
    assert_non_null(strstr(err.msg, path));
    assert_int_equal(file_size(path), -1);
    assert_int_not_equal(image_read(path, &back, &err), 0);
    assert_non_null(strstr(err.msg, path));
    image_free(&img);
    remove_tree(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_image_alloc),
        cmocka_unit_test(test_exr_roundtrip_bitexact_and_attributes),
        cmocka_unit_test(test_exr_steady_state_and_null_meta),
        cmocka_unit_test(test_exr_reads_half_uint_and_grey),
        cmocka_unit_test(test_exr_truncated_and_garbage),
        cmocka_unit_test(test_exr_corrupted_bytes_never_crash),
        cmocka_unit_test(test_exr_roundtrip_at_the_zip_size_boundary),
        cmocka_unit_test(test_pfm_roundtrip_bitexact),
        cmocka_unit_test(test_pfm_bytes_on_disk),
        cmocka_unit_test(test_pfm_grey_and_big_endian),
        cmocka_unit_test(test_pfm_bad_inputs),
        cmocka_unit_test(test_quantile_known_set),
        cmocka_unit_test(test_quantile_negative_values),
        cmocka_unit_test(test_quantile_matches_sorted_definition),
        cmocka_unit_test(test_compare_hand_values),
        cmocka_unit_test(test_compare_nonfinite_excluded),
        cmocka_unit_test(test_compare_zero_reference),
        cmocka_unit_test(test_compare_size_mismatch),
        cmocka_unit_test(test_png_preview_values),
        cmocka_unit_test(test_png_preview_zero_quantile),
        cmocka_unit_test(test_atomic_no_temp_left),
        cmocka_unit_test(test_atomic_missing_folder_and_make_parent_dirs),
        cmocka_unit_test(test_atomic_failed_write_keeps_old_file),
        cmocka_unit_test(test_atomic_open_commit_abort),
        cmocka_unit_test(test_atomic_fopen_fclose_fabort),
        cmocka_unit_test(test_frames_csv),
        cmocka_unit_test(test_image_dispatch_by_extension),
        cmocka_unit_test(test_mean_of_hand_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
