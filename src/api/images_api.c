/* Images for the embedding API: `dartspp compare`'s metrics, and an image written with a render's header. */
#include "dartspp/api.h"

#include "dartspp/render.h"

int dp_compare(const image_rgb *img, const image_rgb *ref, image_error *e, dp_error *err)
{
    /* a NaN or Inf pixel means the render went wrong there: refused, never scored (docs/cli.md §4) */
    const image_rgb *both[2] = {img, ref};
    const char *names[2] = {"the image", "the reference"};
    for (int i = 0; i < 2; i++) {
        int x, y;
        long bad = image_nonfinite_pixels(both[i], &x, &y);
        if (bad)
            return dp_fail(err, "%s: %ld of %ld pixels have a NaN or Inf channel (the first at x %d, y %d): not "
                                "compared", names[i], bad, (long)both[i]->width * both[i]->height, x, y);
    }
    return image_compare(img, ref, e, err);
}

int dp_write_image(const char *path, const image_rgb *img, const dp_render_result *res, int frame, dp_error *err)
{
    image_meta meta = {.time_unit = RENDER_TIME_UNIT, .gated = res->gated, .gate_start = res->gate_start,
                       .gate_end = res->gate_end, .camera_warped = res->camera_warped, .frame_index = -1,
                       .integrator = res->integrator, .plan = res->plan_json, .passes = res->passes};
    if (frame >= 0) {
        if (frame >= res->frame_count)
            return dp_fail(err, "%s: frame %d of a render with %d frames", path, frame, res->frame_count);
        meta.frame_index = frame;
        meta.gate_start = res->frame_times[2 * frame];
        meta.gate_end = res->frame_times[2 * frame + 1];
    }
    int x, y;
    long bad = image_nonfinite_pixels(img, &x, &y);
    if (bad) /* outputs never hold NaN or Inf */
        return dp_fail(err, "%s: %ld pixels have a NaN or Inf channel (the first at x %d, y %d): not written", path,
                       bad, x, y);
    if (io_make_parent_dirs(path, err)) return -1;
    return image_write(path, img, &meta, err);
}
