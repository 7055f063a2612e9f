/* `dartspp merge OUTPUT IMAGE IMAGE...`: the mean of independent renders (e.g. path-tracer reference chunks
 * rendered with different seeds, on one machine or several) and the variance of that mean, the noise the
 * result brings into every error measured against it. */
#include <stdio.h>
#include <stdlib.h>

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
    for (int j = 0; j < k && !rc; j++) rc = image_read(argv[1 + j], &imgs[j], &err);
    if (!rc) rc = image_mean_of(imgs, k, &mean, &v, &err);
    if (!rc) rc = image_write(argv[0], &mean, NULL, &err);
    if (rc) fprintf(stderr, "dartspp merge: %s\n", err.msg);
    else printf("wrote %s: mean of %d images; variance of the mean %.9g (per channel value)\n", argv[0], k, v);
    for (int j = 0; j < k; j++) image_free(&imgs[j]);
    free(imgs);
    image_free(&mean);
    return rc ? 2 : 0;
}
