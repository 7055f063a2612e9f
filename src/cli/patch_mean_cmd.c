/* `dartspp patch-mean IMAGE X0 Y0 X1 Y1`: mean over channels and pixels of [X0, X1) × [Y0, Y1), row 0 at the
 * top (for transient curves). Non-finite pixels are left out and reported on stderr; a rectangle with no finite
 * pixel is an error. */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#include "dartspp/cli.h"
#include "dartspp/io.h"

static int parse_int(const char *s, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno) return -1;
    *out = v;
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp patch-mean IMAGE X0 Y0 X1 Y1 [--mask MASK]   (the mean over channels and pixels)\n"
               "  X0 Y0 X1 Y1   integers: the pixel rectangle [X0,X1) x [Y0,Y1), row 0 at the top\n"
               "  --mask MASK   an image of the same size: only its pixels whose first channel is > 0.5\n"
               "  -h, --help    this text\n");
}

int cli_patch_mean(int argc, char **argv)
{
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    long r[4];
    const char *mask_path = NULL;
    if (argc == 7 && !strcmp(argv[5], "--mask")) {
        mask_path = argv[6];
        argc = 5;
    }
    if (argc != 5 || parse_int(argv[1], &r[0]) || parse_int(argv[2], &r[1]) || parse_int(argv[3], &r[2]) ||
        parse_int(argv[4], &r[3])) {
        usage(stderr);
        return 2;
    }
    image_rgb img = {0};
    dp_error err;
    if (image_read(argv[0], &img, &err)) {
        fprintf(stderr, "dartspp patch-mean: %s\n", err.msg);
        return 2;
    }
    if (r[0] < 0 || r[1] < 0 || r[2] > img.width || r[3] > img.height || r[0] >= r[2] || r[1] >= r[3]) {
        fprintf(stderr, "dartspp patch-mean: %s: rectangle [%ld,%ld) x [%ld,%ld) is empty or outside the %dx%d image\n",
                argv[0], r[0], r[2], r[1], r[3], img.width, img.height);
        image_free(&img);
        return 2;
    }
    image_rgb mask = {0};
    if (mask_path && image_read(mask_path, &mask, &err)) {
        fprintf(stderr, "dartspp patch-mean: --mask: %s\n", err.msg);
        image_free(&img);
        return 2;
    }
    if (mask_path && (mask.width != img.width || mask.height != img.height)) {
        fprintf(stderr, "dartspp patch-mean: --mask %s is %dx%d, the image %s %dx%d\n", mask_path, mask.width,
                mask.height, argv[0], img.width, img.height);
        image_free(&img);
        image_free(&mask);
        return 2;
    }
    double sum = 0.0;
    long n = 0, bad = 0;
    for (long y = r[1]; y < r[3]; y++)
        for (long x = r[0]; x < r[2]; x++) {
            size_t i = (size_t)y * img.width + x;
            if (mask_path && !(mask.rgb[3 * i] > 0.5f)) continue;
            const float *p = &img.rgb[3 * i];
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
                bad++;
                continue;
            }
            sum += (double)p[0] + p[1] + p[2];
            n += 3;
        }
    if (bad) fprintf(stderr, "dartspp patch-mean: %s: %ld non-finite pixels left out\n", argv[0], bad);
    if (mask_path && n == 0) {
        fprintf(stderr, "dartspp patch-mean: --mask %s selects no finite pixel of the rectangle\n", mask_path);
        image_free(&img);
        image_free(&mask);
        return 2;
    }
    if (n == 0) {
        fprintf(stderr, "dartspp patch-mean: %s: no pixel of the rectangle [%ld,%ld) x [%ld,%ld) is finite: "
                        "nothing to average\n", argv[0], r[0], r[2], r[1], r[3]);
        image_free(&img);
        image_free(&mask);
        return 2;
    }
    printf("%.9g\n", sum / n);
    image_free(&img);
    image_free(&mask);
    return 0;
}
