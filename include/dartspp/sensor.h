/* Sensor models: what a time-resolved detector records of the transient the renderer computes.
 *
 * Photon counting (src/sensor/photon_counts.c; docs/sensor.md §1): a single-photon detector (SPAD) with
 * time-correlated single-photon counting (TCSPC) records, over N laser pulses, a histogram of detection times
 * in the frames' bins. Per pulse, bin k of a pixel expects
 *     μ_k = (η·(scale·L_k + ambient_rate) + dark_rate)·Δt_k
 * detections, where L_k is the cube's value (radiance averaged over the bin), Δt_k the bin width in the
 * scene's time unit, η the detection efficiency and `scale` the photons reaching the detector per unit of
 * pixel value and of time. Arrivals are a Poisson process with that piecewise-constant rate. Without dead
 * time the counts are independent Poisson(N·μ_k); with a dead time d the detector is blind for d after each
 * detection within a pulse (non-paralyzable, recovered by the next pulse), which skews the histogram toward
 * early bins (pile-up). */
#ifndef DARTSPP_SENSOR_H
#define DARTSPP_SENSOR_H

#include "dartspp/core.h"

typedef enum {
    SPAD_POISSON,      /* dead time 0: independent Poisson counts per bin */
    SPAD_FIRST_PHOTON, /* dead time at least the histogram's span: one detection per pulse at most (closed form) */
    SPAD_DEAD_TIME     /* a shorter dead time: simulated pulse by pulse, for the pulses with a detection */
} spad_model;

typedef struct {
    double pulses;       /* N, laser pulses (acquisition cycles) */
    double scale;        /* photons reaching the detector per pulse, per unit of pixel value and of time */
    double efficiency;   /* photon detection efficiency η, in [0, 1] */
    double dark_rate;    /* dark counts per unit of time (not scaled by η) */
    double ambient_rate; /* ambient photons reaching the detector per unit of time (detected with η) */
    double dead_time;    /* in the scene's time unit; 0: none */
    int channel;         /* the cube channel the detector sees: 0, 1, 2 (R, G, B) or 3 (their mean) */
} spad_params;

/* The histogram's bins: [start_k, end_k), increasing and not overlapping (gaps hold no arrivals). */
typedef struct {
    const double *start, *end;
    int count;
} spad_bins;

spad_model spad_model_of(const spad_params *sp, const spad_bins *b);
/* μ_k for one pixel from its values L (the cube's 3 channels per bin, bins·3 floats, bin-major). */
void spad_expected(const spad_params *sp, const spad_bins *b, const float *L, size_t stride, double *mu);
/* One pixel's histogram over sp->pulses pulses into counts[k] (exact for every model above); -1 when out
 * of memory. */
int spad_histogram(const spad_params *sp, const spad_bins *b, const double *mu, dp_rng *rng, double *counts);
/* The expected number of pulses spad_histogram simulates one by one for this pixel (0 unless SPAD_DEAD_TIME):
 * its cost. */
double spad_simulated_pulses(const spad_params *sp, const spad_bins *b, const double *mu);
/* Coates (1968), for a histogram recorded with one detection per pulse at most: the expected detections per
 * pulse behind it, μ̂_k = −ln(1 − h_k / (N − Σ_{j<k} h_j)). A bin that took every remaining pulse
 * (saturated) gets the estimate of half a count less, and one after all pulses were taken (unobservable) 0;
 * returns how many bins were either. */
int spad_coates(const double *counts, int bins, double pulses, double *mu_hat);
/* μ̂_k back in the cube's unit: (μ̂_k/Δt_k − dark_rate − η·ambient_rate)/(η·scale). */
double spad_value_of(const spad_params *sp, double mu_hat, double width);

/* ---- the sensor's time response (src/sensor/time_response.c; docs/sensor.md §2) ----
 * The instrument response: a photon is recorded at its arrival time plus an offset drawn from the response
 * (detector and laser jitter), so every gate image and frame records the transient convolved with it. The
 * offset is drawn once per path, with the light's pulse (scene.h, path_time_offset), before DARTS aims at
 * the gate. Either a Gaussian of full width at half maximum `fwhm` (centred on 0) plus an exponential delay
 * of mean `tail` (the exponentially modified Gaussian of SPAD timing; each may be 0), or a tabulated density:
 * knots t_i (increasing) with values p_i >= 0, linear in between, normalized. */
typedef struct {
    int on;        /* 0: a perfect sensor, no offset and no random numbers drawn */
    double sigma;  /* the Gaussian's standard deviation, fwhm / (2·sqrt(2 ln 2)) */
    double tail;   /* mean of the exponential delay; 0: none */
    int n;         /* tabulated: n >= 2 knots (then sigma and tail are 0) */
    double *t, *p, *cdf;
} sensor_response;

/* From the keys: fwhm and tail (>= 0), or a table file (CSV lines "time,value", an optional header line;
 * path as given). Errors name the file, the line and the reason. */
int sensor_response_init(sensor_response *r, double fwhm, double tail, const char *table_path, dp_error *err);
double sensor_response_sample(const sensor_response *r, dp_rng *rng);
/* Its cumulative distribution at x (for checks and tests). */
double sensor_response_cdf(const sensor_response *r, double x);
void sensor_response_free(sensor_response *r);

#endif
