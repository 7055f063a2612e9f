/* tier: quick */
/* EXR files and images through the io module: image_alloc's limits, EXR round trips (bit-exact floats, the
 * dartspp attributes), steady-state and null metadata, half/uint/grey channels written by OpenEXRCore itself,
 * truncated, garbage and corrupted files, and the guard against OpenEXRCore's ZIP chunk at the packed-size
 * boundary. Expected values are worked out by hand. */
#include "fixtures.h"

#include <openexr.h>

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
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    size_t n = read_into(path, good, sizeof good);
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
    test_rmtree(dir);
}

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
    test_rmtree(dir);
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
