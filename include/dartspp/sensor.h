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

#endif
