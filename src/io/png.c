/* 8-bit sRGB PNG previews of float images, encoded with libpng. */
#include "dartspp/io.h"

#include <errno.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Linear [0,1] to an 8-bit sRGB code (IEC 61966-2-1 transfer curve). */
static unsigned char srgb8(double v)
{
    if (!(v > 0.0)) return 0; /* also NaN */
    if (v >= 1.0) return 255;
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (unsigned char)(s * 255.0 + 0.5);
}

static void preview_row(const float *src, int width, double scale, png_byte *dst)
{
    for (int i = 0; i < 3 * width; ++i)
        dst[i] = isfinite(src[i]) ? srgb8(src[i] / scale) : 0;
}

/* libpng reports errors through this (its error pointer is our dp_error) and then long-jumps. */
static void png_error_to_dp(png_structp png, png_const_charp msg)
{
    dp_error *err = png_get_error_ptr(png);
    dp_fail_kind(err, DP_ERROR_OUTPUT, "%s", msg);
    png_longjmp(png, 1);
}

static void png_ignore_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

/* Encodes the rows; row must hold 3*width bytes. Returns 0 or -1 with err->msg set by libpng. */
static int encode(FILE *f, const image_rgb *img, double scale, png_byte *row, dp_error *err)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, err, png_error_to_dp,
                                              png_ignore_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        png_destroy_write_struct(&png, NULL);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    for (int y = 0; y < img->height; ++y) {
        preview_row(img->rgb + (size_t)y * (size_t)img->width * 3, img->width, scale, row);
        png_write_row(png, row);
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 0;
}

/* Writes the PNG to the stream (left open); on failure err->msg holds the reason (no path). */
static int write_stream(FILE *f, const image_rgb *img, dp_error *err)
{
    double q = image_quantile(img, 0.99);
    double scale = q > 0.0 ? q : 1.0; /* 0 (or no usable quantile): show the values as they are */
    png_byte *row = malloc((size_t)img->width * 3);
    int rc = row ? encode(f, img, scale, row, err) : dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    int e = errno;
    free(row);
    if (rc != 0 && ferror(f)) /* better than libpng's text */
        rc = dp_fail_kind(err, DP_ERROR_OUTPUT, "write failed: %s", strerror(e));
    return rc;
}

int png_write_preview(const char *path, const image_rgb *img, dp_error *err)
{
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: cannot write an empty image", path);
    atomic_file af;
    FILE *f = atomic_fopen(path, "wb", &af, err);
    if (!f) return -1;
    dp_error local = {0};
    if (write_stream(f, img, &local) != 0) {
        atomic_fabort(&af);
        return dp_fail_kind(err, local.kind, "%s: %s", path, local.msg);
    }
    return atomic_fclose(&af, 0, err); /* a stream error or failed close: "write failed" */
}
