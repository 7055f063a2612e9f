/* The data of the frames viewer (io.h): how much of the cube the page embeds (the downscale factor and
 * the frame stride under VIEWER_PAYLOAD_MAX), the box-downscaled frames, and a histogram of every value of
 * the cube for the page's default exposure. */
#include "dartspp/io.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int ceil_div(int a, int b) { return (a + b - 1) / b; }

/* Floats of one frame downscaled by f. */
static size_t frame_floats(int width, int height, int f) { return 3 * (size_t)ceil_div(width, f) * (size_t)ceil_div(height, f); }

void viewer_layout_of(int width, int height, int frames, viewer_layout *l)
{
    const size_t cap = VIEWER_PAYLOAD_MAX / sizeof(float);
    int longer = width > height ? width : height, f = 1;
    while ((size_t)frames * frame_floats(width, height, f) > cap && ceil_div(longer, f + 1) >= VIEWER_MIN_SIDE) f++;
    while (frame_floats(width, height, f) > cap) f++; /* one frame must fit, whatever its size */
    size_t fit = cap / frame_floats(width, height, f); /* >= 1 */
    int s = (int)(((size_t)frames + fit - 1) / fit);
    *l = (viewer_layout){.width = width, .height = height, .frames = frames, .factor = f, .stride = s > 0 ? s : 1,
                         .dw = ceil_div(width, f), .dh = ceil_div(height, f)};
    l->embedded = ceil_div(frames, l->stride);
}

double viewer_html_bytes_max(const viewer_layout *l)
{
    double payload = (double)l->embedded * l->dw * l->dh * 12.0;
    return payload * 4.0 / 3.0 + 4.0 + 64.0 * 1024.0; /* base64, and the template with its metadata */
}

int viewer_cube_init(viewer_cube *v, int width, int height, int frames, dp_error *err)
{
    memset(v, 0, sizeof *v);
    if (width <= 0 || height <= 0 || frames <= 0)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "viewer: no frames to show");
    viewer_layout_of(width, height, frames, &v->l);
    v->data = calloc((size_t)v->l.embedded * frame_floats(width, height, v->l.factor), sizeof(float));
    v->hist = calloc(VIEWER_HIST_BINS, sizeof(double));
    if (v->data && v->hist) return 0;
    viewer_cube_free(v);
    return dp_fail_kind(err, DP_ERROR_MEMORY, "viewer: out of memory");
}

/* The mean of the f×f block (bx, by) of img (fewer pixels at the right and bottom edges) into out[3]. */
static void block_mean(const image_rgb *img, int f, int bx, int by, float *out)
{
    double sum[3] = {0, 0, 0};
    int x1 = (bx + 1) * f < img->width ? (bx + 1) * f : img->width;
    int y1 = (by + 1) * f < img->height ? (by + 1) * f : img->height;
    for (int y = by * f; y < y1; y++)
        for (int x = bx * f; x < x1; x++)
            for (int c = 0; c < 3; c++) sum[c] += img->rgb[3 * ((size_t)y * img->width + x) + c];
    double n = (double)(x1 - bx * f) * (y1 - by * f);
    for (int c = 0; c < 3; c++) out[c] = (float)(sum[c] / n);
}

static void count_values(viewer_cube *v, const image_rgb *img)
{
    size_t n = 3 * (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        float x = img->rgb[i];
        if (!(x > 0.0f) || !isfinite(x)) continue;
        uint32_t u;
        memcpy(&u, &x, sizeof u);
        v->hist[u >> 16]++; /* exponent and 7 mantissa bits: monotonic in x */
        v->positives++;
    }
}

void viewer_cube_add(viewer_cube *v, int k, const image_rgb *img)
{
    const viewer_layout *l = &v->l;
    if (k < 0 || k >= l->frames || img->width != l->width || img->height != l->height) return;
    count_values(v, img);
    if (k % l->stride) return;
    float *dst = v->data + (size_t)(k / l->stride) * frame_floats(l->width, l->height, l->factor);
    for (int by = 0; by < l->dh; by++)
        for (int bx = 0; bx < l->dw; bx++) block_mean(img, l->factor, bx, by, dst + 3 * ((size_t)by * l->dw + bx));
}

double viewer_cube_quantile(const viewer_cube *v, double q)
{
    if (!(v->positives > 0)) return 0.0;
    double rank = ceil(q * v->positives), seen = 0;
    if (rank < 1) rank = 1;
    for (uint32_t b = 0; b < VIEWER_HIST_BINS; b++) {
        seen += v->hist[b];
        if (seen < rank) continue;
        uint32_t u = b << 16 | 0x8000u; /* the middle of the bin */
        float x;
        memcpy(&x, &u, sizeof x);
        return x;
    }
    return 0.0;
}

void viewer_cube_free(viewer_cube *v)
{
    free(v->data);
    free(v->hist);
    v->data = NULL;
    v->hist = NULL;
}
