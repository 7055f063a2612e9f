/* Film → files: gate image, PNG preview, per-frame images and the frame sidecar (DESIGN §4). */
#include "dartspp/render.h"

#include <stdio.h>
#include <string.h>

#define TIME_UNIT "optical path length in scene units (c = 1)"

static int write_one(const char *path, const image_rgb *img, const image_meta *meta, void (*wrote)(const char *),
                     dp_error *err)
{
    if (image_write(path, img, meta, err)) return -1;
    if (wrote) wrote(path);
    return 0;
}

static int write_frames(const film *f, const char *stem, const char *ext, image_meta meta,
                        void (*wrote)(const char *), dp_error *err)
{
    const time_window *tw = &f->window;
    int digits = 4; /* at most 6: frame_count <= 100000 */
    for (int n = tw->frame_count - 1; n >= 10000; n /= 10) digits++;
    for (int k = 0; k < tw->frame_count; k++) {
        char path[2300];
        if (snprintf(path, sizeof path, "%s_%0*d%s", stem, digits, k, ext) >= (int)sizeof path)
            return dp_fail(err, "%s: output path too long", stem);
        image_rgb img = {0};
        if (film_image(f, k, &img, err)) return -1;
        meta.frame_index = k;
        meta.gate_start = tw->start + k * tw->width;
        meta.gate_end = tw->start + (k + 1) * tw->width;
        int rc = write_one(path, &img, &meta, wrote, err);
        image_free(&img);
        if (rc) return -1;
    }
    char csv[2200];
    snprintf(csv, sizeof csv, "%s_frames.csv", stem);
    if (frames_csv_write(csv, tw->frame_count, tw->start, tw->width, err)) return -1;
    if (wrote) wrote(csv);
    return 0;
}

int render_write_outputs(const scene *s, const film *f, const char *path, const char *integrator,
                         void (*wrote)(const char *path), dp_error *err)
{
    (void)s;
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash) || (strcmp(dot, ".exr") && strcmp(dot, ".pfm")))
        return dp_fail(err, "%s: output must end in .exr or .pfm", path);
    char stem[2048];
    snprintf(stem, sizeof stem, "%.*s", (int)(dot - path), path);
    if (make_parent_dirs(path, err)) return -1;
    const time_window *tw = &f->window;
    image_meta meta = {.time_unit = TIME_UNIT, .gated = tw->gated, .gate_start = tw->start,
                       .gate_end = time_window_end(tw), .camera_warped = 1, .frame_index = -1,
                       .integrator = integrator};
    image_rgb img = {0};
    if (film_image(f, -1, &img, err)) return -1;
    char png[2200];
    snprintf(png, sizeof png, "%s.png", stem);
    int rc = write_one(path, &img, &meta, wrote, err);
    if (!rc) rc = png_write_preview(png, &img, err);
    if (!rc && wrote) wrote(png);
    image_free(&img);
    if (!rc && tw->frame_count > 0) rc = write_frames(f, stem, dot, meta, wrote, err);
    return rc;
}
