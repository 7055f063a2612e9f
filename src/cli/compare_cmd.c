/* `dartspp compare IMAGE REFERENCE [--csv]`: error metrics of an image against a reference. */
#include <stdio.h>
#include <string.h>

#include "dartspp/cli.h"
#include "dartspp/io.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp compare IMAGE REFERENCE [--csv]   (EXR or PFM, the same size)\n"
               "  --csv       one line: mse,rmse,rel_mse,mse_q99,q99,nonfinite,pixels,mse_trimmed,trimmed\n"
               "  -h, --help  this text\n");
}

int cli_compare(int argc, char **argv)
{
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    const char *paths[2] = {NULL, NULL};
    int csv = 0, np = 0;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--csv")) csv = 1;
        else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "dartspp compare: unknown option '%s'\n", argv[i]);
            return 2;
        } else if (np < 2) paths[np++] = argv[i];
        else {
            fprintf(stderr, "dartspp compare: too many arguments ('%s')\n", argv[i]);
            return 2;
        }
    }
    if (np != 2) {
        usage(stderr);
        return 2;
    }
    image_rgb img = {0}, ref = {0};
    image_error e;
    dp_error err;
    int rc = image_read(paths[0], &img, &err) || image_read(paths[1], &ref, &err);
    /* A NaN or Inf pixel means the render went wrong there: it is refused, never scored (docs/cli.md §4). */
    for (int i = 0; i < 2 && !rc; i++) {
        int x, y;
        const image_rgb *im = i ? &ref : &img;
        long bad = image_nonfinite_pixels(im, &x, &y);
        if (bad)
            rc = dp_fail(&err, "%s: %ld of %ld pixels have a NaN or Inf channel (the first at x %d, y %d): "
                               "not compared", paths[i], bad, (long)im->width * im->height, x, y);
    }
    if (!rc && (img.width != ref.width || img.height != ref.height))
        rc = dp_fail(&err, "%s is %dx%d but the reference %s is %dx%d: compare needs images of one size", paths[0],
                     img.width, img.height, paths[1], ref.width, ref.height);
    if (!rc) rc = image_compare_trimmed(&img, &ref, &e, &err);
    if (rc) fprintf(stderr, "dartspp compare: %s\n", err.msg);
    else if (csv)
        printf("%.9g,%.9g,%.9g,%.9g,%.9g,%ld,%ld,%.9g,%ld\n", e.mse, e.rmse, e.rel_mse, e.mse_q99, e.q99, e.nonfinite,
               e.pixels, e.mse_trimmed, e.trimmed);
    else
        printf("image              %s\nreference          %s\nmse                %.6g\nrmse               %.6g\n"
               "relative mse       %.6g   (mean of (x-r)^2/(r^2+0.01))\n"
               "mse / q99^2        %.6g   (both divided by the reference's 0.99 quantile %.6g)\n"
               "trimmed mse        %.6g   (without the %ld pixels of largest error, 0.1 %%)\n"
               "non-finite pixels  %ld   (of %ld compared)\n",
               paths[0], paths[1], e.mse, e.rmse, e.rel_mse, e.mse_q99, e.q99, e.mse_trimmed, e.trimmed, e.nonfinite,
               e.pixels);
    image_free(&img);
    image_free(&ref);
    return rc ? 2 : 0;
}
