/* The film: per-pixel sums of pass estimates for the gate image and each transient frame. A pass splats into
 * its own layer, which joins the sums only when the pass completes: an interrupted pass is dropped whole. */
#include "dartspp/film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The AMCW sums' doubles: 2 (re, im) per channel, frequency and pixel; 0 without AMCW. */
static size_t film_amcw_count(const film *f)
{
    return (size_t)f->width * f->height * 6 * (size_t)f->window.amcw_count;
}

int film_init(film *f, int width, int height, const time_window *tw, dp_error *err)
{
    memset(f, 0, sizeof *f);
    f->width = width;
    f->height = height;
    f->window = *tw;
    size_t n = (size_t)width * height * 3, nf = n * (size_t)time_window_layers(tw);
    f->sum = calloc(n, sizeof(double));
    f->pass = dp_calloc_cache_aligned(n, sizeof(double)); /* threads splat neighbouring tiles */
    if (nf > 0) {
        f->frame_sum = calloc(nf, sizeof(float));
        f->frame_pass = dp_calloc_cache_aligned(nf, sizeof(float));
    }
    size_t na = film_amcw_count(f);
    for (int j = 0; j < tw->amcw_count; j++) f->amcw_k[j] = amcw_wavenumber(tw->amcw_mhz[j]);
    if (na > 0) {
        f->amcw_sum = calloc(na, sizeof(double));
        f->amcw_pass = dp_calloc_cache_aligned(na, sizeof(double));
    }
    if (!f->sum || !f->pass || (nf > 0 && (!f->frame_sum || !f->frame_pass)) || (na > 0 && (!f->amcw_sum || !f->amcw_pass))) {
        film_free(f);
        return dp_fail_kind(err, DP_ERROR_MEMORY,
                            "out of memory for a %dx%d film with %d frames", width, height, tw->frame_count);
    }
    return 0;
}

int film_init_derivs(film *f, int k, const char *const *labels, dp_error *err)
{
    if (k <= 0) return 0;
    f->deriv = calloc((size_t)k, sizeof *f->deriv);
    if (!f->deriv) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for %d derivative films", k);
    time_window tw = f->window;
    tw.amcw_count = 0; /* AMCW is the image's alone */
    for (int i = 0; i < k; i++) {
        if (film_init(&f->deriv[i], f->width, f->height, &tw, err)) return -1; /* film_free frees the rest */
        f->deriv[i].label = labels ? labels[i] : NULL;
        f->deriv_count = i + 1;
    }
    return 0;
}

int film_init_like(film *f, const film *like, dp_error *err)
{
    if (film_init(f, like->width, like->height, &like->window, err)) return -1;
    f->lidar = like->lidar;
    const char *labels[64] = {0};
    for (int i = 0; i < like->deriv_count && i < 64; i++) labels[i] = like->deriv[i].label;
    if (film_init_derivs(f, like->deriv_count, labels, err)) {
        film_free(f);
        return -1;
    }
    return 0;
}

void film_free(film *f)
{
    for (int i = 0; i < f->deriv_count; i++) film_free(&f->deriv[i]);
    free(f->deriv);
    free(f->sum);
    free(f->pass);
    free(f->frame_sum);
    free(f->frame_pass);
    free(f->amcw_sum);
    free(f->amcw_pass);
    memset(f, 0, sizeof *f);
}

void film_copy_sums(film *to, const film *from)
{
    size_t n = (size_t)from->width * from->height * 3, nf = n * (size_t)time_window_layers(&from->window);
    memcpy(to->sum, from->sum, n * sizeof(double));
    if (nf > 0) memcpy(to->frame_sum, from->frame_sum, nf * sizeof(float));
    if (to->amcw_sum && from->amcw_sum && to->window.amcw_count == from->window.amcw_count)
        memcpy(to->amcw_sum, from->amcw_sum, film_amcw_count(from) * sizeof(double));
    to->passes = from->passes;
    to->weight_sum = from->weight_sum;
    to->last_weight = from->last_weight;
    to->nonfinite = from->nonfinite;
    for (int i = 0; i < from->deriv_count && i < to->deriv_count; i++) film_copy_sums(&to->deriv[i], &from->deriv[i]);
}

int film_copy(film *to, const film *from, dp_error *err)
{
    if (film_init_like(to, from, err)) return -1;
    film_copy_sums(to, from);
    return 0;
}

int film_splat(film *f, size_t px, double t, vec3 c, int frame, int order)
{
    if (!v3_is_finite(c)) return 0;
    film_slot s = film_time_slot(f, t, frame, order);
    if (!s.counts) return 1;
    if (!film_slot_fits(&s, c)) return 0;
    film_slot_add(f, px, &s, c);
    return 1;
}

/* Adds the pass layer to the sums with weight w (and clears it): the pass counts. */
void film_commit_pass(film *f, double w)
{
    size_t n = (size_t)f->width * f->height * 3, nf = n * (size_t)time_window_layers(&f->window);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        f->sum[i] += w * f->pass[i];
        f->pass[i] = 0.0;
    }
    float wf = (float)w;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nf; i++) {
        f->frame_sum[i] += wf * f->frame_pass[i];
        f->frame_pass[i] = 0.0f;
    }
    size_t na = film_amcw_count(f);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < na; i++) {
        f->amcw_sum[i] += w * f->amcw_pass[i];
        f->amcw_pass[i] = 0.0;
    }
    f->passes++;
    f->weight_sum += w;
    f->last_weight = w;
    for (int i = 0; i < f->deriv_count; i++) film_commit_pass(&f->deriv[i], w);
}

/* Clears the pass layer: an unfinished pass leaves no trace. */
void film_drop_pass(film *f)
{
    size_t n = (size_t)f->width * f->height * 3, nf = n * (size_t)time_window_layers(&f->window);
    memset(f->pass, 0, n * sizeof(double));
    if (nf > 0) memset(f->frame_pass, 0, nf * sizeof(float));
    if (f->amcw_pass) memset(f->amcw_pass, 0, film_amcw_count(f) * sizeof(double));
    for (int i = 0; i < f->deriv_count; i++) film_drop_pass(&f->deriv[i]);
}

/* Image k (k < 0: the gate image; else layer k of frame_sum) as float32 into out (NULL: only counted), a pixel with a non-finite channel
 * as 0 (the last line of defence: a NaN pass weight, a value beyond the float range). Returns those pixels. */
static long image_values_of(const film *f, long k, float *out)
{
    size_t n = (size_t)f->width * f->height;
    double inv = f->weight_sum > 0.0 ? 1.0 / f->weight_sum : 0.0;
    const double *sum = k < 0 ? f->sum : NULL;
    const float *fs = k < 0 ? NULL : &f->frame_sum[3 * n * (size_t)k];
    long bad = 0;
    for (size_t i = 0; i < 3 * n; i += 3) {
        float v[3];
        for (int c = 0; c < 3; c++) v[c] = (float)((sum ? sum[i + c] : (double)fs[i + c]) * inv);
        int finite = isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
        bad += !finite;
        if (out)
            for (int c = 0; c < 3; c++) out[i + c] = finite ? v[c] : 0.0f;
    }
    return bad;
}

int film_image(const film *f, int k, image_rgb *img, dp_error *err)
{
    if (image_alloc(img, f->width, f->height, err)) return -1;
    image_values_of(f, k, img->rgb);
    return 0;
}

int film_layer_image(const film *f, long layer, image_rgb *img, dp_error *err) { return film_image(f, (int)layer, img, err); }

long film_nonfinite_pixels(const film *f)
{
    long bad = 0;
    for (long k = -1; k < time_window_layers(&f->window); k++) bad += image_values_of(f, k, NULL);
    return bad + film_amcw_values(f, NULL); /* and each (frequency, pixel) of the AMCW values not finite */
}

double film_sample_pixels(film *f, const camera *cam, uint64_t seed, long pass, const dp_stop_flag *stop,
                          film_sample_fn sample, void *ctx)
{
    double rays = 0.0;
    long bad = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : rays, bad)
    for (int y = 0; y < cam->height; y++) {
        if (dp_stopped(stop)) continue; /* interrupted: the pass is dropped, finish fast */
        for (int x = 0; x < cam->width; x++) {
            film_pixel pixel = {.f = f, .px = (size_t)y * cam->width + x};
            dp_rng rng = rng_stream(seed, (uint64_t)pass, pixel.px);
            double jx = rng_uniform(&rng), jy = rng_uniform(&rng);
            vec3 o, d = camera_ray(cam, x + jx, y + jy, &o);
            sample(ctx, &pixel, o, d, &rng);
            rays += pixel.rays;
            bad += pixel.nonfinite;
        }
    }
    f->nonfinite += bad; /* a derivative film's dropped contributions count here, with the image's */
    return rays;
}
