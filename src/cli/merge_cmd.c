/* `dartspp merge OUTPUT IMAGE IMAGE...`: the mean of independent renders (e.g. path-tracer reference chunks
 * rendered with different seeds, on one machine or several) and the variance of that mean, the noise the
 * result brings into every error measured against it. */
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "dartspp/cli.h"
#include "dartspp/io.h"

int cli_merge(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: dartspp merge OUTPUT.exr|.pfm IMAGE IMAGE [IMAGE...]   (equal-weight mean)\n");
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
    struct stat out_st, in_st;
    int out_exists = stat(argv[0], &out_st) == 0;
    for (int j = 0; j < k && !rc; j++) {
        int x, y;
        long bad;
        if (out_exists && stat(argv[1 + j], &in_st) == 0 && in_st.st_dev == out_st.st_dev && in_st.st_ino == out_st.st_ino)
            rc = dp_fail(&err, "the output %s is the input %s: merge into a new file", argv[0], argv[1 + j]);
        else if (!(rc = image_read(argv[1 + j], &imgs[j], &err)) && (bad = image_nonfinite_pixels(&imgs[j], &x, &y)))
            rc = dp_fail(&err, "%s: %ld of %ld pixels have a NaN or Inf channel (the first at x %d, y %d): not merged",
                         argv[1 + j], bad, (long)imgs[j].width * imgs[j].height, x, y);
    }
    if (!rc) rc = image_mean_of(imgs, k, &mean, &v, &err);
    if (!rc) rc = image_write(argv[0], &mean, NULL, &err);
    if (rc) fprintf(stderr, "dartspp merge: %s\n", err.msg);
    else printf("wrote %s: mean of %d images; variance of the mean %.9g (per channel value)\n", argv[0], k, v);
    for (int j = 0; j < k; j++) image_free(&imgs[j]);
    free(imgs);
    image_free(&mean);
    return rc ? 2 : 0;
}
