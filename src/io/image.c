/* The image type: allocation, the quantile used for display scaling, the error metrics of
 * `dartspp compare` and the mean of `dartspp merge`. Knows nothing of files (image_file.c does). */
#include "dartspp/io.h"

#include <stdlib.h>
#include <string.h>

/* Largest image accepted anywhere (also bounds what a corrupt file header can make us allocate). */
#define IMAGE_MAX_PIXELS ((size_t)1 << 28)

int image_alloc(image_rgb *img, int width, int height, dp_error *err)
{
    img->width = img->height = 0;
    img->rgb = NULL;
    if (width <= 0 || height <= 0)
        return dp_fail(err, "invalid image size %dx%d", width, height);
    size_t n = (size_t)width * (size_t)height;
    if (n > IMAGE_MAX_PIXELS)
        return dp_fail(err, "image size %dx%d exceeds the limit of %zu pixels", width, height,
                       IMAGE_MAX_PIXELS);
    img->rgb = calloc(n * 3, sizeof *img->rgb);
    if (!img->rgb) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for a %dx%d image", width, height);
    img->width = width;
    img->height = height;
    return 0;
}

void image_free(image_rgb *img)
{
    if (!img) return;
    free(img->rgb);
    img->rgb = NULL;
    img->width = img->height = 0;
}

static size_t image_values(const image_rgb *img)
{
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0) return 0;
    return (size_t)img->width * (size_t)img->height * 3;
}

/* Finite floats mapped to unsigned keys in the same order (sign flipped, negatives inverted). */
static uint32_t float_key(float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

static float key_float(uint32_t k)
{
    uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* Histogram of the finite values by the high 16 bits of their key or, with `low`, by the low 16 bits
 * of those whose high bits equal `high`. Returns how many values were counted. */
static size_t count_keys(const image_rgb *img, size_t *hist, int low, uint32_t high)
{
    size_t total = image_values(img), n = 0;
    memset(hist, 0, 65536 * sizeof *hist);
    for (size_t i = 0; i < total; ++i) {
        if (!isfinite(img->rgb[i])) continue;
        uint32_t k = float_key(img->rgb[i]);
        if (low && (k >> 16) != high) continue;
        hist[low ? (k & 0xffffu) : (k >> 16)]++;
        n++;
    }
    return n;
}

/* The bucket holding the value of rank *k (0-based, < the histogram total); *k becomes its rank
 * inside that bucket. */
static uint32_t find_bucket(const size_t *hist, size_t *k)
{
    uint32_t b = 0;
    while (*k >= hist[b]) *k -= hist[b++];
    return b;
}

/* Nearest rank: the value at index ceil(q*n)-1 (clamped) of the sorted finite values, found by a
 * two-pass radix select (no sort, no copy of the image). Returns -1 when out of memory; *out = 0 when
 * there are no finite values. */
static int quantile_of(const image_rgb *img, double q, double *out)
{
    *out = 0.0;
    size_t *hist = malloc(65536 * sizeof *hist);
    if (!hist) return -1;
    size_t n = count_keys(img, hist, 0, 0);
    if (n > 0) {
        double rank = ceil((isnan(q) ? 0.0 : q) * (double)n) - 1.0;
        size_t k = rank <= 0.0 ? 0 : (rank >= (double)(n - 1) ? n - 1 : (size_t)rank);
        uint32_t high = find_bucket(hist, &k);
        count_keys(img, hist, 1, high);
        *out = key_float(high << 16 | find_bucket(hist, &k));
    }
    free(hist);
    return 0;
}

/* NaN if the histogram cannot be allocated. */
double image_quantile(const image_rgb *img, double q)
{
    double r;
    return quantile_of(img, q, &r) == 0 ? r : NAN;
}

typedef struct {
    double se, rel, se_q;
} error_sums;

static int pixel_finite(const float *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

long image_nonfinite_pixels(const image_rgb *img, int *first_x, int *first_y)
{
    long bad = 0;
    *first_x = *first_y = -1;
    size_t n = image_values(img) / 3;
    for (size_t i = 0; i < n; i++)
        if (!pixel_finite(img->rgb + 3 * i) && bad++ == 0) {
            *first_x = (int)(i % (size_t)img->width);
            *first_y = (int)(i / (size_t)img->width);
        }
    return bad;
}

/* Adds one pixel to the sums; returns its squared error summed over the channels. */
static double add_pixel(error_sums *s, const float *x, const float *r, double q)
{
    double se = 0.0;
    for (int c = 0; c < 3; ++c) {
        double d = (double)x[c] - (double)r[c];
        double dq = (double)x[c] / q - (double)r[c] / q;
        se += d * d;
        s->rel += d * d / ((double)r[c] * (double)r[c] + 1e-2);
        s->se_q += dq * dq;
    }
    s->se += se;
    return se;
}

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The mean squared error per channel value over all but the `drop` pixels of largest error (se: each
 * pixel's squared error summed over its channels; reordered). */
static double trimmed_mse(double *se, size_t n, size_t drop)
{
    qsort(se, n, sizeof *se, by_value);
    double sum = 0.0;
    for (size_t i = 0; i + drop < n; i++) sum += se[i];
    return n > drop ? sum / (3.0 * (double)(n - drop)) : 0.0;
}

/* The metrics of image_compare; with pixel_se (room for every pixel), each compared pixel's squared error
 * summed over its channels too, in pixel order. */
static int compare_pixels(const image_rgb *img, const image_rgb *ref, image_error *out, double *pixel_se,
                          dp_error *err)
{
    memset(out, 0, sizeof *out);
    if (!image_values(img) || !image_values(ref)) return dp_fail(err, "compare: empty image");
    if (img->width != ref->width || img->height != ref->height)
        return dp_fail(err, "compare: image is %dx%d but the reference is %dx%d", img->width,
                       img->height, ref->width, ref->height);
    if (quantile_of(ref, 0.99, &out->q99) != 0) return dp_fail_kind(err, DP_ERROR_MEMORY, "compare: out of memory");
    double q = out->q99 != 0.0 ? out->q99 : 1.0;
    error_sums s = {0, 0, 0};
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; ++i) {
        const float *x = img->rgb + 3 * i, *r = ref->rgb + 3 * i;
        if (!pixel_finite(x) || !pixel_finite(r)) {
            out->nonfinite++;
            continue;
        }
        double se = add_pixel(&s, x, r, q);
        if (pixel_se) pixel_se[out->pixels] = se;
        out->pixels++;
    }
    double count = 3.0 * (double)out->pixels;
    if (count > 0) {
        out->mse = s.se / count;
        out->rel_mse = s.rel / count;
        out->mse_q99 = s.se_q / count;
    }
    out->rmse = sqrt(out->mse);
    return 0;
}

int image_compare(const image_rgb *img, const image_rgb *ref, image_error *out, dp_error *err)
{
    return compare_pixels(img, ref, out, NULL, err);
}

int image_compare_trimmed(const image_rgb *img, const image_rgb *ref, image_error *out, dp_error *err)
{
    size_t n = (size_t)img->width * (size_t)img->height;
    double *pixel_se = malloc((n ? n : 1) * sizeof *pixel_se);
    if (!pixel_se) return dp_fail_kind(err, DP_ERROR_MEMORY, "compare: out of memory");
    int rc = compare_pixels(img, ref, out, pixel_se, err);
    if (!rc) {
        out->trimmed = (long)floor(IMAGE_TRIM_SHARE * (double)out->pixels);
        out->mse_trimmed = trimmed_mse(pixel_se, (size_t)out->pixels, (size_t)out->trimmed);
    }
    free(pixel_se);
    return rc;
}

int image_mean_of(const image_rgb *imgs, int k, image_rgb *mean, double *var_of_mean, dp_error *err)
{
    *var_of_mean = 0.0;
    if (k < 2) return dp_fail(err, "merge: need at least two images (got %d)", k);
    for (int j = 1; j < k; j++)
        if (imgs[j].width != imgs[0].width || imgs[j].height != imgs[0].height)
            return dp_fail(err, "merge: image %d is %dx%d but image 1 is %dx%d", j + 1, imgs[j].width,
                           imgs[j].height, imgs[0].width, imgs[0].height);
    if (image_alloc(mean, imgs[0].width, imgs[0].height, err)) return -1;
    size_t n = 3 * (size_t)imgs[0].width * (size_t)imgs[0].height, used = 0;
    double v = 0.0;
    for (size_t i = 0; i < n; i++) {
        double m = 0.0, m2 = 0.0;
        for (int j = 0; j < k; j++) m += imgs[j].rgb[i];
        m /= k;
        for (int j = 0; j < k; j++) m2 += ((double)imgs[j].rgb[i] - m) * ((double)imgs[j].rgb[i] - m);
        mean->rgb[i] = (float)m;
        if (isfinite(m) && isfinite(m2)) {
            v += m2 / (k - 1) / k;
            used++;
        }
    }
    *var_of_mean = used ? v / (double)used : 0.0;
    return 0;
}
