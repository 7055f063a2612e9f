/* The error log of a render against a reference image: one CSV row per logged pass (elapsed time,
 * iterations, photon counts, radii and the three error metrics of `dartspp compare`), and in frame mode a
 * second CSV with the error of every frame whose reference exists. Rows are appended and flushed as the
 * render goes, so an interrupted render keeps its log up to the last completed pass. */
#include "dartspp/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct error_log {
    FILE *csv, *frames_csv;
    image_rgb ref;             /* gate (or union-window) reference */
    image_rgb *frame_ref;      /* frame_count entries; .rgb NULL where the reference frame is missing */
    int frame_count;
    double every, last;        /* seconds between rows; time of the last row */
    double overhead;           /* seconds spent logging */
    long last_pass;
};

/* "<stem>_<NNNN><ext>" beside the reference, as render_write_outputs names frames. */
static void frame_ref_path(const char *ref, int k, int frames, char *out, size_t n)
{
    const char *dot = strrchr(ref, '.'), *slash = strrchr(ref, '/');
    if (!dot || (slash && dot < slash)) dot = ref + strlen(ref);
    int digits = 4;
    for (int m = frames - 1; m >= 10000 && digits < 9; m /= 10) digits++;
    if (snprintf(out, n, "%.*s_%0*d%s", (int)(dot - ref), ref, digits, k, dot) >= (int)n) out[0] = 0;
}

void error_log_close(error_log *l)
{
    if (!l) return;
    if (l->csv) fclose(l->csv);
    if (l->frames_csv) fclose(l->frames_csv);
    image_free(&l->ref);
    for (int k = 0; l->frame_ref && k < l->frame_count; k++) image_free(&l->frame_ref[k]);
    free(l->frame_ref);
    free(l);
}

static FILE *open_csv(const char *path, const char *header, dp_error *err)
{
    if (io_make_parent_dirs(path, err)) return NULL;
    FILE *f = fopen(path, "w");
    if (!f) {
        dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot write the error log", path);
        return NULL;
    }
    fputs(header, f);
    fflush(f);
    return f;
}

error_log *error_log_open(const char *csv_path, const char *ref_path, int width, int height, int frame_count,
                          double every, dp_error *err)
{
    error_log *l = calloc(1, sizeof *l);
    if (!l) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory"), NULL;
    l->every = every;
    l->last = -1e300;
    l->last_pass = -1;
    if (image_read(ref_path, &l->ref, err)) goto fail;
    if (l->ref.width != width || l->ref.height != height) {
        dp_fail(err, "%s: the reference is %dx%d but the render is %dx%d", ref_path, l->ref.width, l->ref.height,
                width, height);
        goto fail;
    }
    l->csv = open_csv(csv_path, "seconds,iterations,photon_paths,stored_photons,r_vol,r_surf,mse,rel_mse,mse_q99,nonfinite_pixels\n", err);
    if (!l->csv) goto fail;
    if (frame_count > 0) {
        l->frame_count = frame_count;
        l->frame_ref = calloc((size_t)l->frame_count, sizeof(image_rgb));
        if (!l->frame_ref) {
            dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
            goto fail;
        }
        int found = 0;
        for (int k = 0; k < l->frame_count; k++) {
            char p[4096];
            frame_ref_path(ref_path, k, l->frame_count, p, sizeof p);
            FILE *probe = p[0] ? fopen(p, "rb") : NULL;
            if (!probe) continue;
            fclose(probe);
            if (image_read(p, &l->frame_ref[k], err)) goto fail;
            if (l->frame_ref[k].width != width || l->frame_ref[k].height != height) {
                dp_fail(err, "%s: the reference frame is %dx%d but the render is %dx%d", p, l->frame_ref[k].width,
                        l->frame_ref[k].height, width, height);
                goto fail;
            }
            found++;
        }
        if (found) {
            char p[4096];
            const char *dot = strrchr(csv_path, '.');
            snprintf(p, sizeof p, "%.*s_frames%s", dot ? (int)(dot - csv_path) : (int)strlen(csv_path), csv_path,
                     dot ? dot : ".csv");
            l->frames_csv = open_csv(p, "seconds,iterations,frame,mse,rel_mse,mse_q99,nonfinite_pixels\n", err);
            if (!l->frames_csv) goto fail;
        }
    }
    return l;
fail:
    error_log_close(l);
    return NULL;
}

static int log_image(const film *f, int k, const image_rgb *ref, image_error *e, dp_error *err)
{
    image_rgb img = {0};
    if (film_image(f, k, &img, err)) return -1;
    int rc = image_compare(&img, ref, e, err);
    image_free(&img);
    return rc;
}

int error_log_pass(error_log *l, const film *f, const render_stats *st, int force, dp_error *err)
{
    if (!l || st->passes == l->last_pass || (!force && st->seconds - l->last < l->every)) return 0;
    double t0 = dp_seconds();
    l->last = st->seconds;
    l->last_pass = st->passes;
    image_error e;
    if (log_image(f, -1, &l->ref, &e, err)) return -1;
    fprintf(l->csv, "%.6g,%ld,%.17g,%.17g,%.9g,%.9g,%.9g,%.9g,%.9g,%ld\n", st->seconds, st->passes, st->photon_paths,
            st->stored_photons, st->r_vol, st->r_surf, e.mse, e.rel_mse, e.mse_q99, e.nonfinite);
    fflush(l->csv);
    for (int k = 0; l->frames_csv && k < l->frame_count; k++) {
        if (!l->frame_ref[k].rgb) continue;
        if (log_image(f, k, &l->frame_ref[k], &e, err)) return -1;
        fprintf(l->frames_csv, "%.6g,%ld,%d,%.9g,%.9g,%.9g,%ld\n", st->seconds, st->passes, k, e.mse, e.rel_mse,
                e.mse_q99, e.nonfinite);
    }
    if (l->frames_csv) fflush(l->frames_csv);
    l->overhead += dp_seconds() - t0;
    return 0;
}

double error_log_overhead(const error_log *l) { return l ? l->overhead : 0.0; }
