/* Image files by extension: the one place that picks the format (exr.c, pfm.c) for a path. */
#include "dartspp/io.h"

#include <string.h>
#include <strings.h>

/* Case-insensitive test of the file name's extension (ext includes the dot). */
static int has_ext(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n > e && strcasecmp(path + n - e, ext) == 0;
}

int image_write(const char *path, const image_rgb *img, const image_meta *meta, dp_error *err)
{
    if (has_ext(path, ".exr")) return exr_write(path, img, meta, err);
    if (has_ext(path, ".pfm")) return pfm_write(path, img, err);
    return dp_fail(err, "%s: unknown image format (expected .exr or .pfm)", path);
}

int image_read(const char *path, image_rgb *img, dp_error *err)
{
    if (has_ext(path, ".exr")) return exr_read(path, img, err);
    if (has_ext(path, ".pfm")) return pfm_read(path, img, err);
    img->width = img->height = 0;
    img->rgb = NULL;
    return dp_fail(err, "%s: unknown image format (expected .exr or .pfm)", path);
}
