/* tier: quick */
/* The other image files of the io module: PFM round trips, the bytes on disk, grey and big-endian files and
 * bad inputs; the PNG preview's values and exposure; reading and writing by file extension. Expected values
 * are worked out by hand. */
#include "fixtures.h"

#include <png.h>

/* ---- PFM ---- */

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
    test_rmtree(dir);
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
    size_t n = read_into(path, got, sizeof got);
    assert_int_equal(n, sizeof want);
    assert_memory_equal(got, want, sizeof want);
    image_free(&img);
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    test_rmtree(dir);
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
    test_rmtree(dir);
}

/* ---- dispatch ---- */

static void test_image_dispatch_by_extension(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img, back;
    dp_error err = {0};
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
    test_rmtree(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pfm_roundtrip_bitexact),
        cmocka_unit_test(test_pfm_bytes_on_disk),
        cmocka_unit_test(test_pfm_grey_and_big_endian),
        cmocka_unit_test(test_pfm_bad_inputs),
        cmocka_unit_test(test_png_preview_values),
        cmocka_unit_test(test_png_preview_zero_quantile),
        cmocka_unit_test(test_image_dispatch_by_extension),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
