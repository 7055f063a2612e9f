/* tier: quick */
/* Quantiles and the error metrics of the io module (compare, the mean of an image) against values worked out
 * by hand and the sorted definition; non-finite values excluded, a zero reference, mismatched sizes. Issue 32:
 * the commands `compare`, `patch-mean` and `merge` refuse what they cannot measure (non-finite pixels, a patch
 * with no finite pixel, an output that is one of merge's inputs) with a message naming the file and exit 2. */
#include "fixtures.h"

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

/* The trimmed MSE (issue 52) by hand: a zero reference and pixel i off by i/1000 in its red channel only.
 * 2000 pixels drop the two of largest error (⌊0.001·2000⌋): Σ_{i<1998} (i/1000)² over 3·1998 values; 999 pixels
 * drop none (the MSE itself); a firefly of 10^6 among 2000 is what is dropped; a NaN pixel counts in
 * neither N (1999 then drop one) nor the sums. */
static double error_of(int i) { return (double)(float)(i / 1000.0); } /* as the float image holds it */

static double trimmed_by_hand(int n, int drop)
{
    double sum = 0.0;
    for (int i = 0; i < n - drop; i++) sum += error_of(i) * error_of(i);
    return sum / (3.0 * (n - drop));
}

static void test_compare_trimmed(void **state)
{
    (void)state;
    const int sizes[2] = {2000, 999};
    for (int k = 0; k < 2; k++) {
        int n = sizes[k];
        image_rgb img, ref;
        image_error e;
        dp_error err;
        assert_int_equal(image_alloc(&img, n, 1, &err), 0);
        assert_int_equal(image_alloc(&ref, n, 1, &err), 0);
        for (int i = 0; i < n; i++) img.rgb[3 * (n - 1 - i)] = (float)(i / 1000.0); /* largest errors first */
        assert_int_equal(image_compare_trimmed(&img, &ref, &e, &err), 0);
        assert_int_equal(e.trimmed, n / 1000);
        assert_close(e.mse_trimmed, trimmed_by_hand(n, n / 1000), 1e-12);
        if (n < 1000) assert_close(e.mse_trimmed, e.mse, 1e-12); /* summed in another order */
        img.rgb[3 * 7 + 1] = 1e6f; /* a firefly: with 2000 pixels it is one of the two dropped */
        img.rgb[3 * 8 + 2] = NAN;  /* left out of everything */
        assert_int_equal(image_compare_trimmed(&img, &ref, &e, &err), 0);
        assert_int_equal(e.pixels, n - 1);
        if (n == 2000) {
            /* 1999 pixels compared drop one, the firefly (pixel 7, i = 1992); pixel 8 (i = 1991) is the NaN */
            double sum = 0.0;
            for (int i = 0; i < n; i++) sum += i == 1991 || i == 1992 ? 0.0 : error_of(i) * error_of(i);
            assert_int_equal(e.trimmed, 1);
            assert_close(e.mse_trimmed, sum / (3.0 * 1998), 1e-12);
        } else {
            assert_close(e.mse_trimmed, e.mse, 1e-12 * e.mse); /* summed in another order */
            assert_true(e.mse > 1e8); /* 10^12 over 3·998 values: the firefly stays */
        }
        image_free(&img);
        image_free(&ref);
    }
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
    dp_error err = {0};
    fill(&img, 3, 1, img3);
    assert_int_equal(image_alloc(&ref, 1, 3, &err), 0);
    assert_int_not_equal(image_compare(&img, &ref, &e, &err), 0);
    assert_non_null(strstr(err.msg, "3x1"));
    assert_non_null(strstr(err.msg, "1x3"));
    image_free(&img);
    image_free(&ref);
}

/* ---- the commands on images that cannot be measured (issue 32, item 2) ---- */

/* Writes a 2x2 PFM <dir>/<name> holding the 12 values v. */
static void write_pfm(char *path, size_t n, const char *dir, const char *name, const float *v)
{
    image_rgb img;
    dp_error err;
    join(path, n, dir, name);
    fill(&img, 2, 2, v);
    assert_int_equal(image_write(path, &img, NULL, &err), 0);
    image_free(&img);
}

/* An all-NaN image against a finite reference was MSE 0, exit 0, "(of 4 compared)": now exit 2 naming the file
 * that holds the NaN or Inf pixels, in either place. A finite pair is scored over all 4 pixels (hand values:
 * every channel off by 1, so MSE 1). */
static void test_cli_compare_refuses_nonfinite(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char nan_img[512], inf_ref[512], ones[512], zeros[512], cmd[2048], out[4096];
    float v[12];
    for (int i = 0; i < 12; i++) v[i] = NAN;
    write_pfm(nan_img, sizeof nan_img, dir, "nan.pfm", v);
    for (int i = 0; i < 12; i++) v[i] = 0.0f;
    write_pfm(zeros, sizeof zeros, dir, "zeros.pfm", v);
    v[4] = INFINITY; /* pixel 1: x 1, y 0 */
    write_pfm(inf_ref, sizeof inf_ref, dir, "inf.pfm", v);
    for (int i = 0; i < 12; i++) v[i] = 1.0f;
    write_pfm(ones, sizeof ones, dir, "ones.pfm", v);

    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s %s", nan_img, zeros);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, nan_img);
    ASSERT_CONTAINS(out, "4 of 4 pixels have a NaN or Inf channel");
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s %s --csv", nan_img, zeros);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s %s", ones, inf_ref);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, inf_ref);
    ASSERT_CONTAINS(out, "1 of 4 pixels have a NaN or Inf channel (the first at x 1, y 0)");

    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s %s", ones, zeros);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    ASSERT_CONTAINS(out, "(of 4 compared)");
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " compare %s %s --csv", ones, zeros);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    ASSERT_CONTAINS(out, "1,1,"); /* mse 1, rmse 1 */
    ASSERT_CONTAINS(out, ",0,4,1,0\n"); /* no non-finite pixel, 4 compared; trimmed MSE 1, none dropped */
}

/* patch-mean printed 0 for a patch without a finite pixel: now exit 2. A patch with one finite pixel averages
 * that pixel alone (hand value (1 + 2 + 6) / 3 = 3) and reports the others. */
static void test_cli_patch_mean_no_finite_pixel(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char path[512], cmd[2048], out[4096];
    float v[12];
    for (int i = 0; i < 12; i++) v[i] = NAN;
    v[9] = 1, v[10] = 2, v[11] = 6; /* pixel (1, 1) */
    write_pfm(path, sizeof path, dir, "p.pfm", v);
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " patch-mean %s 0 0 2 1", path);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, path);
    ASSERT_CONTAINS(out, "no pixel of the rectangle");
    snprintf(cmd, sizeof cmd, DARTSPP_BIN " patch-mean %s 0 0 2 2", path);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    ASSERT_CONTAINS(out, "3 non-finite pixels left out");
    ASSERT_CONTAINS(out, "\n3\n");
}

/* merge wrote NaN pixels with "variance 0" and could overwrite one of its inputs: now an output that is an
 * input (the same path, another spelling of it, a symbolic link to it) is refused with the input unchanged, and a
 * non-finite input is refused by name with no output written. Two finite inputs 1 and 3 everywhere: the mean is 2,
 * V = s²/k = ((1 − 2)² + (3 − 2)²) / 1 / 2 = 1 (by hand). */
static void test_cli_merge_refuses_inputs_as_output_and_nonfinite(void **state)
{
    char *dir = *state = tmpdir_or_fail();
    char a[512], b[512], bad[512], outp[512], link[512], cmd[4096], out[4096];
    float v[12];
    for (int i = 0; i < 12; i++) v[i] = 1.0f;
    write_pfm(a, sizeof a, dir, "a.pfm", v);
    for (int i = 0; i < 12; i++) v[i] = 3.0f;
    write_pfm(b, sizeof b, dir, "b.pfm", v);
    v[7] = NAN;
    write_pfm(bad, sizeof bad, dir, "bad.pfm", v);
    join(outp, sizeof outp, dir, "m.pfm");
    join(link, sizeof link, dir, "link.pfm");
    assert_int_equal(symlink(a, link), 0);
    unsigned char before[256], after[256];
    size_t len_before = read_into(a, before, sizeof before);
    assert_true(len_before > 48 && len_before < sizeof before);

    const char *outputs[3] = {a, link, NULL};
    char spelled[600];
    snprintf(spelled, sizeof spelled, "%s/./a.pfm", dir);
    outputs[2] = spelled;
    for (int i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, DARTSPP_BIN " merge %s %s %s", outputs[i], a, b);
        assert_int_equal(test_run(cmd, out, sizeof out), 2);
        ASSERT_CONTAINS(out, "is the input");
        assert_int_equal(read_into(a, after, sizeof after), len_before);
        assert_memory_equal(after, before, len_before);
    }

    snprintf(cmd, sizeof cmd, DARTSPP_BIN " merge %s %s %s", outp, a, bad);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, bad);
    ASSERT_CONTAINS(out, "1 of 4 pixels have a NaN or Inf channel (the first at x 0, y 1)");
    assert_int_equal(access(outp, F_OK), -1);

    snprintf(cmd, sizeof cmd, DARTSPP_BIN " merge %s %s %s", outp, a, b);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    ASSERT_CONTAINS(out, "variance of the mean 1 ");
    image_rgb m;
    dp_error err;
    assert_int_equal(image_read(outp, &m, &err), 0);
    for (int i = 0; i < 12; i++) assert_true(m.rgb[i] == 2.0f);
    image_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quantile_known_set),
        cmocka_unit_test(test_quantile_negative_values),
        cmocka_unit_test(test_quantile_matches_sorted_definition),
        cmocka_unit_test(test_compare_hand_values),
        cmocka_unit_test(test_compare_trimmed),
        cmocka_unit_test(test_compare_nonfinite_excluded),
        cmocka_unit_test(test_compare_zero_reference),
        cmocka_unit_test(test_compare_size_mismatch),
        cmocka_unit_test(test_mean_of_hand_values),
        cmocka_unit_test_teardown(test_cli_compare_refuses_nonfinite, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cli_patch_mean_no_finite_pixel, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_cli_merge_refuses_inputs_as_output_and_nonfinite, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
