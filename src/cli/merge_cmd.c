/* `dartspp merge OUTPUT IMAGE IMAGE...`: the mean of independent renders (e.g. path-tracer reference chunks
 * rendered with different seeds, on one machine or several) and the variance of that mean, the noise the
 * result brings into every error measured against it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/cli.h"
#include "dartspp/io.h"

/* Before any work: the output is none of the inputs, and no input is given twice — the same render counted
 * twice is not an independent sample, and the variance of the mean would be too small (two copies of one
 * image: 0), by device and inode, so also through a link. */
static int check_files(const char *out, char **in, int k, dp_error *err)
{
    if (!io_has_extension(out, ".exr") && !io_has_extension(out, ".pfm"))
        return dp_fail(err, "the output %s: an image, its name must end in .exr or .pfm", out);
    io_file o = {out, "the output"};
    for (int j = 0; j < k; j++) {
        io_file i = {in[j], "an input"};
        if (io_refuse_output_over_input(&o, 1, &i, 1, err)) return -1;
        for (int m = 0; m < j; m++)
            if (io_same_file(in[m], in[j]))
                return dp_fail(err, "the inputs %s and %s are the same file: each render must be given once (an image "
                                    "counted twice makes the variance of the mean too small)", in[m], in[j]);
    }
    return 0;
}

/* Two independent renders of a lit image never agree in every bit; two copies of one do. (Black images may
 * agree: their variance of 0 is true.) */
static int same_pixels(const image_rgb *a, const image_rgb *b)
{
    size_t n = 3 * (size_t)a->width * a->height, lit = 0;
    if (a->width != b->width || a->height != b->height || memcmp(a->rgb, b->rgb, n * sizeof(float))) return 0;
    for (size_t i = 0; i < n && !lit; i++) lit = a->rgb[i] != 0.0f;
    return lit != 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp merge OUTPUT.exr|.pfm IMAGE IMAGE [IMAGE...]   (the equal-weight mean of independent\n"
               "       renders of the same size, and the variance of that mean)\n"
               "  -h, --help  this text\n");
}

int cli_merge(int argc, char **argv)
{
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    if (argc < 3) {
        usage(stderr);
        return 2;
    }
    int k = argc - 1, rc = 0;
    image_rgb *imgs = calloc((size_t)k, sizeof(image_rgb)), mean = {0};
    dp_error err;
    double v = 0.0;
    if (!imgs) {
        fprintf(stderr, "dartspp merge: out of memory\n");
        return 1;
    }
    rc = check_files(argv[0], argv + 1, k, &err);
    for (int j = 0; j < k && !rc; j++) {
        int x, y;
        long bad;
        if (!(rc = image_read(argv[1 + j], &imgs[j], &err)) && (bad = image_nonfinite_pixels(&imgs[j], &x, &y)))
            rc = dp_fail(&err, "%s: %ld of %ld pixels have a NaN or Inf channel (the first at x %d, y %d): not merged",
                         argv[1 + j], bad, (long)imgs[j].width * imgs[j].height, x, y);
    }
    for (int j = 1; j < k && !rc; j++)
        if (imgs[j].width != imgs[0].width || imgs[j].height != imgs[0].height)
            rc = dp_fail(&err, "%s is %dx%d but %s is %dx%d: merge needs renders of one size", argv[1 + j],
                         imgs[j].width, imgs[j].height, argv[1], imgs[0].width, imgs[0].height);
    for (int j = 1; j < k && !rc; j++)
        for (int m = 0; m < j && !rc; m++)
            if (same_pixels(&imgs[m], &imgs[j]))
                rc = dp_fail(&err, "%s and %s hold the same pixel values: copies of one render, not independent "
                                   "renders (the variance of the mean would be too small)", argv[1 + m], argv[1 + j]);
    if (!rc) rc = image_mean_of(imgs, k, &mean, &v, &err);
    if (!rc) rc = image_write(argv[0], &mean, NULL, &err);
    if (rc) fprintf(stderr, "dartspp merge: %s\n", err.msg);
    else printf("wrote %s: mean of %d images; variance of the mean %.9g (per channel value)\n", argv[0], k, v);
    for (int j = 0; j < k; j++) image_free(&imgs[j]);
    free(imgs);
    image_free(&mean);
    return rc ? 2 : 0;
}
