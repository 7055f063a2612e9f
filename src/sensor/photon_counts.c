/* Photon-counting histograms (include/dartspp/sensor.h; docs/sensor.md §1): the SPAD/TCSPC model of a
 * transient cube. The counts are drawn exactly for every dead time:
 *   - none: independent Poisson(N·μ_k) per bin;
 *   - at least the histogram's span: one detection per pulse at most, in bin k with probability
 *     p_k = e^{−Σ_{j<k} μ_j}·(1 − e^{−μ_k}) (Coates 1968), so the histogram is multinomial over the N pulses;
 *     drawn as sequential binomials, h_k ~ Binomial(N − Σ_{j<k} h_j, 1 − e^{−μ_k});
 *   - shorter: pulse by pulse, only for the pulses that have a detection at all (Binomial(N, 1 − e^{−Λ}),
 *     Λ = Σ μ_k), the first detection from the arrival process conditioned on one, the next ones after
 *     each dead time. Written here: no library models TCSPC pile-up. */
#include <math.h>
#include <stdlib.h>

#include "dartspp/sensor.h"

spad_model spad_model_of(const spad_params *sp, const spad_bins *b)
{
    if (!(sp->dead_time > 0.0) || b->count == 0) return SPAD_POISSON;
    return sp->dead_time >= b->end[b->count - 1] - b->start[0] ? SPAD_FIRST_PHOTON : SPAD_DEAD_TIME;
}

void spad_expected(const spad_params *sp, const spad_bins *b, const float *L, size_t stride, double *mu)
{
    for (int k = 0; k < b->count; k++) {
        const float *v = L + (size_t)k * stride;
        double value = sp->channel < 3 ? v[sp->channel] : (v[0] + v[1] + v[2]) / 3.0;
        if (!(value > 0.0)) value = 0.0; /* a negative or non-finite value emits nothing */
        double rate = sp->efficiency * (sp->scale * value + sp->ambient_rate) + sp->dark_rate;
        mu[k] = rate * (b->end[k] - b->start[k]);
    }
}

/* The arrival process's cumulative mean at time t (C: the cumulative μ at each bin's start, count + 1). */
static double cumulative_at(const spad_bins *b, const double *mu, const double *C, double t)
{
    int lo = 0, hi = b->count; /* the last bin starting at or before t */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (b->start[mid] <= t) lo = mid;
        else hi = mid;
    }
    if (t <= b->start[lo]) return C[lo];
    if (t >= b->end[lo]) return C[lo + 1];
    return C[lo] + mu[lo] * (t - b->start[lo]) / (b->end[lo] - b->start[lo]);
}

/* The bin and time where the cumulative mean reaches y (C[0] <= y < C[count]). */
static int arrival_at(const spad_bins *b, const double *mu, const double *C, double y, double *t)
{
    int lo = 0, hi = b->count;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (C[mid] <= y) lo = mid;
        else hi = mid;
    }
    while (lo < b->count - 1 && !(mu[lo] > 0.0)) lo++; /* a bin without arrivals holds none */
    double f = mu[lo] > 0.0 ? (y - C[lo]) / mu[lo] : 0.0;
    *t = b->start[lo] + (f < 1.0 ? f : 1.0) * (b->end[lo] - b->start[lo]);
    return lo;
}

static int dead_time_pulses(const spad_params *sp, const spad_bins *b, const double *mu, dp_rng *rng, double *counts)
{
    double *C = malloc(((size_t)b->count + 1) * sizeof *C);
    if (!C) return -1;
    C[0] = 0.0;
    for (int k = 0; k < b->count; k++) C[k + 1] = C[k] + mu[k];
    double total = C[b->count], p_any = -expm1(-total), span_end = b->end[b->count - 1];
    long pulses = rng_binomial(rng, (long)sp->pulses, p_any);
    for (long i = 0; i < pulses; i++) {
        /* the first arrival, given that there is one: Exp(1) truncated to [0, Λ) */
        double y = -log1p(-rng_uniform(rng) * p_any), t;
        for (;;) {
            int k = arrival_at(b, mu, C, y < total ? y : nextafter(total, 0.0), &t);
            counts[k] += 1.0;
            double live = t + sp->dead_time; /* blind until then */
            if (live >= span_end) break;
            double u = rng_uniform(rng);
            y = cumulative_at(b, mu, C, live) - log(u > 0.0 ? u : 0x1.0p-53);
            if (y >= total) break;
        }
    }
    free(C);
    return 0;
}

int spad_histogram(const spad_params *sp, const spad_bins *b, const double *mu, dp_rng *rng, double *counts)
{
    for (int k = 0; k < b->count; k++) counts[k] = 0.0;
    switch (spad_model_of(sp, b)) {
    case SPAD_POISSON:
        for (int k = 0; k < b->count; k++) counts[k] = (double)rng_poisson(rng, sp->pulses * mu[k]);
        break;
    case SPAD_FIRST_PHOTON: {
        long left = (long)sp->pulses; /* pulses without a detection so far */
        for (int k = 0; k < b->count && left > 0; k++) {
            long h = rng_binomial(rng, left, -expm1(-mu[k]));
            counts[k] = (double)h;
            left -= h;
        }
        break;
    }
    case SPAD_DEAD_TIME:
        return dead_time_pulses(sp, b, mu, rng, counts);
    }
    return 0;
}

double spad_simulated_pulses(const spad_params *sp, const spad_bins *b, const double *mu)
{
    if (spad_model_of(sp, b) != SPAD_DEAD_TIME) return 0.0;
    double total = 0.0;
    for (int k = 0; k < b->count; k++) total += mu[k];
    return sp->pulses * -expm1(-total);
}

int spad_coates(const double *counts, int bins, double pulses, double *mu_hat)
{
    double left = pulses;
    int odd = 0;
    for (int k = 0; k < bins; k++) {
        if (!(left > 0.0)) {
            mu_hat[k] = 0.0; /* every pulse was taken before this bin: nothing is known of it */
            odd++;
            continue;
        }
        double h = counts[k];
        if (h >= left) { /* saturated: the estimate of half a count less */
            h = left - 0.5;
            odd++;
        }
        mu_hat[k] = -log1p(-h / left);
        left -= counts[k];
    }
    return odd;
}

double spad_value_of(const spad_params *sp, double mu_hat, double width)
{
    double detected = mu_hat / width - sp->dark_rate;
    return sp->efficiency > 0.0 && sp->scale > 0.0 ? (detected / sp->efficiency - sp->ambient_rate) / sp->scale : 0.0;
}
