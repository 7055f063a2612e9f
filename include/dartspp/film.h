/* dartspp film: the accumulation of passes — per-pixel sums for the gate image and each transient frame,
 * the pass in progress kept apart until it completes, and the count of suppressed non-finite samples. The
 * integrators write into it; the outputs and error logs read images from it. */
#ifndef DARTSPP_FILM_H
#define DARTSPP_FILM_H

#include "dartspp/io.h"
#include "dartspp/scene.h"

/* Weighted sums of per-pass pixel estimates; the image is sum / weight_sum (pass i weighted by the w_i given
 * at its commit: 1 for the equal mean). Gate image: contributions weighted by
 * 1/width inside [start, end) (steady state: weight 1, no test). Frame k: 1/w inside its own window, so a
 * frame is exactly the gate image of its window (docs/time.md §4). In frame mode the gate image is the image of
 * the union window. A pass splats into the pass layer, which joins the sums at film_commit_pass; an
 * interrupted pass is dropped with film_drop_pass, so the sums only ever hold completed passes. */
typedef struct film film;
struct film {
    int width, height;
    time_window window;
    double *sum;       /* 3 per pixel: completed passes */
    float *frame_sum;  /* time_window_layers(&window) × 3 per pixel, completed passes: the frames, then with
                        * window.orders the order layers (film_order_layer) */
    double *pass;      /* the pass in progress, same layout as sum */
    float *frame_pass; /* the pass in progress, same layout as frame_sum */
    long passes;       /* completed passes */
    double weight_sum; /* Σ of their weights */
    double last_weight;/* the weight of the last completed pass (its estimate is the sums' increment / this) */
    long nonfinite;    /* non-finite contributions suppressed (never written into an image) */
    film *deriv;       /* deriv_count films of the same size and window: the derivative images ∂I/∂θ_k
                        * (include/dartspp/derivative.h), committed, dropped and copied with this one */
    int deriv_count;
    const char *label; /* a derivative film's parameter (its JSON Pointer, owned by the scene); NULL otherwise */
    const camera *lidar; /* a lidar's film, whose pixels are its beams and frames its range bins: the files stage
                          * writes its waveforms, echoes and points (docs/lidar.md §4); NULL otherwise. The
                          * scene's camera, which outlives the film */
    /* AMCW (docs/amcw.md), with window.amcw_count > 0 (never on a derivative film): per pixel, per frequency j,
     * per channel c, the real and imaginary sums of contribution · e^{−i·amcw_k[j]·t}, weight 1 (not the gate's
     * 1/width): amcw_sum[((px · amcw_count + j) · 3 + c) · 2 + {0 re, 1 im}], completed passes; amcw_pass the pass
     * in progress, same layout. NULL without AMCW. */
    double amcw_k[AMCW_FREQ_MAX]; /* 2π f / c₀ in radians per scene unit (the unit a metre): φ = amcw_k · t */
    double *amcw_sum, *amcw_pass;
};

int film_init(film *f, int width, int height, const time_window *tw, dp_error *err);
/* Adds k derivative films (f->deriv) to an initialised film without any, labelled labels[i] (may be NULL).
 * 0, or -1 with err. */
int film_init_derivs(film *f, int k, const char *const *labels, dp_error *err);
/* film_init with the size, window, lidar and derivative films (their labels) of `like`. */
int film_init_like(film *f, const film *like, dp_error *err);
/* Frees the film and its derivative films. */
void film_free(film *f);
/* The completed passes of `from` (sums, pass count, weights, non-finite count) into `to`, a film of the same
 * size, frames and derivative films; the pass in progress is not copied. */
void film_copy_sums(film *to, const film *from);
/* A new film `to` (film_init, its derivative films too) holding the completed passes of `from`. 0, or -1 with
 * err (out of memory). */
int film_copy(film *to, const film *from, dp_error *err);
/* Under a delta gate (window.delta), the box of the pass in progress: [center − w/2, center + w/2) with weight
 * 1/w, the temporal kernel K_τ of this iteration (plan_gate_width); every reader of f->window (film_time_slot,
 * the estimators' time pruning) then sees it. Nothing for a box gate. The sums stay comparable across passes
 * (each contribution is weighted when it is splatted), so a film's reduction, copy and checkpoint do not
 * depend on it. */
static inline void film_set_pass_gate(film *f, double w)
{
    if (!f->window.delta) return;
    for (int k = 0; k < f->deriv_count; k++) film_set_pass_gate(&f->deriv[k], w);
    f->window.width = w;
    f->window.start = f->window.center - 0.5 * w;
}

/* Where a contribution arriving at path time t (tagged with frame, as film_splat) lands: decided once, so
 * that an estimator adding many contributions of one time (a photon splatted into many pixels) divides
 * once. */
typedef struct {
    int counts;        /* inside the window (and in its frame, for a frame-tagged one) */
    int gated;
    double wg;         /* gate image weight 1/(width · frames) */
    double wf;         /* frame weight 1/width */
    long k;            /* frame index, or -1 without frames */
    long order_layer;  /* with window.orders: the layer of its scattering order (and frame); else -1 */
    double t;          /* the path time (the AMCW phase's) */
} film_slot;

/* The layer of scattering order o (the last one: o and more) for frame k (-1: the gate image, without
 * frames): after the frames, orders × max(frames, 1) layers. */
static inline long film_order_layer(const time_window *tw, int o, long k)
{
    int frames = tw->frame_count > 0 ? tw->frame_count : 1;
    if (o >= tw->orders) o = tw->orders - 1;
    return tw->frame_count + (long)o * frames + (k > 0 ? k : 0);
}

/* order: the path's scattering events (surface and medium vertices, its segments − 1). */
static inline film_slot film_time_slot(const film *f, double t, int frame, int order)
{
    const time_window *tw = &f->window;
    film_slot s = {.counts = 1, .gated = tw->gated, .k = -1, .order_layer = -1, .t = t};
    if (!tw->gated) {
        if (tw->orders > 0) s.order_layer = film_order_layer(tw, order, -1);
        return s;
    }
    double rel = (t - tw->start) / tw->width;
    int frames = tw->frame_count > 0 ? tw->frame_count : 1;
    s.counts = rel >= 0.0 && rel < frames && (frame < 0 || (int)rel == frame); /* frame: docs/darts.md §2.2 */
    if (!s.counts) return s;
    s.wg = 1.0 / (tw->width * frames);
    s.wf = 1.0 / tw->width;
    if (tw->frame_count > 0) {
        size_t k = (size_t)rel;
        s.k = k >= (size_t)tw->frame_count ? tw->frame_count - 1 : (long)k;
    }
    if (tw->orders > 0) s.order_layer = film_order_layer(tw, order, s.k);
    return s;
}

/* The largest weighted contribution the film keeps: the frame layers and the output images are float32, so a
 * finite double beyond this (an albedo of 1e308, a tiny gate width's weight) would sum to Inf there; it is
 * dropped and counted with the non-finite ones. 1e30 leaves 8 decades of float range for the sums. */
#define FILM_VALUE_MAX 1e30

/* Whether c is finite and, weighted for slot s, within FILM_VALUE_MAX. */
static inline int film_slot_fits(const film_slot *s, vec3 c)
{
    if (!v3_is_finite(c)) return 0;
    double w = s->gated ? (s->wg > s->wf ? s->wg : s->wf) : 1.0;
    double m = fmax(fabs(c.x), fmax(fabs(c.y), fabs(c.z)));
    return m * w <= FILM_VALUE_MAX;
}

/* The AMCW sums of a contribution c at path time t (docs/amcw.md §2): c·cos φ to the real, −c·sin φ to the
 * imaginary sum of each frequency, φ = amcw_k·t, weight 1. */
void film_amcw_add(film *f, size_t px, double t, vec3 c);

/* Adds a finite c to pixel px in a slot that counts (not thread-safe for one pixel). */
static inline void film_slot_add(film *f, size_t px, const film_slot *s, vec3 c)
{
    if (f->amcw_pass) film_amcw_add(f, px, s->t, c);
    double *p = &f->pass[3 * px];
    if (s->order_layer >= 0) { /* weighted as its frame, or as the gate image without frames */
        double w = !s->gated ? 1.0 : s->k >= 0 ? s->wf : s->wg;
        float *o = &f->frame_pass[3 * ((size_t)f->width * f->height * (size_t)s->order_layer + px)];
        o[0] += (float)(c.x * w);
        o[1] += (float)(c.y * w);
        o[2] += (float)(c.z * w);
    }
    if (!s->gated) {
        p[0] += c.x;
        p[1] += c.y;
        p[2] += c.z;
        return;
    }
    p[0] += c.x * s->wg;
    p[1] += c.y * s->wg;
    p[2] += c.z * s->wg;
    if (s->k >= 0) {
        float *fs = &f->frame_pass[3 * ((size_t)f->width * f->height * (size_t)s->k + px)];
        fs[0] += (float)(c.x * s->wf);
        fs[1] += (float)(c.y * s->wf);
        fs[2] += (float)(c.z * s->wf);
    }
}

/* Adds contribution c arriving at path time t to pixel index px (not thread-safe for one pixel).
 * frame >= 0 (DARTS frame mode): c counts only if t falls in that frame, in the frames and the gate image.
 * Returns 0 when c was non-finite or too large for the film (FILM_VALUE_MAX) and was dropped (the caller
 * counts it). */
int film_splat(film *f, size_t px, double t, vec3 c, int frame, int order);
/* The pass layer joins the sums with weight w > 0 (passes + 1), or is cleared (the derivative films' too). */
void film_commit_pass(film *f, double w);
void film_drop_pass(film *f);
/* Layer k of frame_sum (a frame, or an order layer: film_order_layer) as the weighted mean over passes. */
int film_layer_image(const film *f, long layer, image_rgb *img, dp_error *err);
/* Gate image (k < 0) or frame k, as the weighted mean over passes in float32. A pixel with a channel that is
 * not finite there (NaN, or beyond the float range) is written as 0: no NaN or Inf leaves the film. */
int film_image(const film *f, int k, image_rgb *img, dp_error *err);
/* The pixels film_image writes as 0 for not being finite, over the gate image and every frame. */
long film_nonfinite_pixels(const film *f);

/* ---- AMCW (docs/amcw.md) ---- */
#define AMCW_C0 299792458.0 /* m/s: the modulation wavelength of f MHz is AMCW_C0 / (f·1e6) scene units */
/* 2π f / c₀ for f in MHz: the phase per unit of path time (radians per scene unit, the unit a metre). */
static inline double amcw_wavenumber(double mhz) { return 2.0 * M_PI * mhz * 1e6 / AMCW_C0; }
/* The AMCW values as the weighted mean over passes, complex64 interleaved (re, im) in the order (frequency,
 * row, column, channel): 2 · amcw_count · height · width · 3 floats into out (NULL: only counted). A value of
 * which a part is not finite in float32 is written as 0 (its three channels). Returns those (frequency, pixel)
 * values. */
long film_amcw_values(const film *f, float *out);
/* The AMCW depth per pixel (height · width floats, docs/amcw.md §4) from the channel-mean phasor of the first one
 * or two frequencies: d = c₀φ/(4πf) wrapped at c₀/(2f); with two, unwrapped by the two-frequency search
 * (amcw_unwrap). A pixel whose phasor is zero or not finite (no signal) is written as 0 and counted in *dark.
 * out may be NULL (only counted). */
void film_amcw_depth(const film *f, float *out, long *dark);
/* Two wrapped depths d1 ∈ [0, c₀/(2f1)) and d2 ∈ [0, c₀/(2f2)) (f in MHz) to one depth: the wrap counts n1, n2
 * over [0, amcw_unwrap_range(f1, f2)) whose depths d1 + n1·c₀/(2f1) and d2 + n2·c₀/(2f2) differ least; their mean. */
double amcw_unwrap(double d1, double f1, double d2, double f2);
/* The pair's unambiguous range c₀/(2·gcd(f1, f2)), the gcd over whole Hz, at most AMCW_UNWRAP_WRAPS wraps of the
 * longer wrap depth. */
#define AMCW_UNWRAP_WRAPS 1000
double amcw_unwrap_range(double f1, double f2);

/* ---- the pixels of one pass ----
 * Every integrator takes one camera sample per pixel per pass the same way: rows in parallel (dynamic
 * schedule), pixel p of pass i drawing from rng_stream(seed, i, p) — first the jitter of its primary ray,
 * then whatever the integrator needs — so images do not depend on the thread count. */
typedef struct {
    film *f;
    size_t px;        /* pixel index */
    double rays;      /* rays the sample traced */
    long nonfinite;   /* contributions dropped for being non-finite */
} film_pixel;

/* Whether a contribution at path time t (tagged with frame, as film_splat) would be counted: estimators test
 * this first and skip the work of one that falls outside the window. */
static inline int film_counts_time(const film *f, double t, int frame) { return film_time_slot(f, t, frame, 0).counts; }

/* Adds a contribution arriving at path time t to the pixel (frame: as film_splat), counting a non-finite one. */
static inline void film_pixel_splat(film_pixel *p, double t, vec3 c, int frame, int order)
{
    if (v3_is_zero(c)) return;
    if (!film_splat(p->f, p->px, t, c, frame, order)) p->nonfinite++;
}

/* One camera sample: o and dir are the jittered primary ray (camera_ray: o is the camera's position for a
 * pinhole, the film point for an orthographic camera), rng the pixel's stream after the jitter. */
typedef void (*film_sample_fn)(void *ctx, film_pixel *pixel, vec3 o, vec3 dir, dp_rng *rng);

/* One sample of every pixel into the pass layer; rows not started once stop is set are skipped (the pass is
 * then incomplete). Returns the rays traced; the non-finite contributions are added to f->nonfinite. */
double film_sample_pixels(film *f, const camera *cam, uint64_t seed, long pass, const dp_stop_flag *stop,
                          film_sample_fn sample, void *ctx);

#endif
