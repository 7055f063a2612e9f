/* Echoes of a lidar waveform (include/dartspp/lidar.h; docs/lidar.md §4): the reference peak of a white
 * Lambertian target, and the runs of bins above a threshold, one echo each, selected first, strongest, last or
 * all. The threshold is the only guard against the Monte Carlo noise of a rendered waveform: a noisy bin above
 * it is an echo of its own, and a run broken by one bin below it is two echoes (docs/lidar.md §4.1). */
#include <math.h>

#include "dartspp/lidar.h"

double lidar_peak_reference(const lidar_params *l, double R)
{
    /* the echo Φ/(πR²) (docs/lidar.md §3) spread over the pulse's length in range, width/2 (a pulse width is a
     * path-time length and the light goes there and back), or held in one bin when the pulse is shorter */
    double energy = l->power / (M_PI * R * R), length = 0.5 * l->pulse.width;
    return length > l->range_bin ? energy * (l->range_bin / length) : energy;
}

/* The run of bins [b0, b1] as an echo. */
static lidar_echo echo_of(const float *wave, int b0, int b1, double range_bin)
{
    double sum = 0.0, moment = 0.0, peak = -INFINITY;
    for (int b = b0; b <= b1; b++) {
        double w = wave[b];
        sum += w;
        moment += ((double)b + 0.5) * w;
        if (w > peak) peak = w;
    }
    lidar_echo e;
    /* every bin of a run is above the threshold, so sum > 0 unless the threshold is negative: then the
     * run's middle */
    e.range = (sum > 0.0 ? moment / sum : 0.5 * ((double)b0 + (double)b1 + 1.0)) * range_bin;
    e.intensity = sum;
    e.width = (double)(b1 - b0 + 1) * range_bin;
    e.peak = peak;
    e.first_bin = b0;
    e.last_bin = b1;
    return e;
}

int lidar_find_echoes(const float *wave, int bins, double range_bin, double threshold, lidar_echo_mode mode,
                      lidar_echo *out, int max_out)
{
    if (max_out <= 0 || bins <= 0) return 0;
    int n = 0, b = 0;
    while (b < bins) {
        if (!(wave[b] > threshold)) { /* NaN is never above */
            b++;
            continue;
        }
        int b0 = b;
        while (b + 1 < bins && wave[b + 1] > threshold) b++;
        lidar_echo e = echo_of(wave, b0, b, range_bin);
        b++;
        switch (mode) {
        case LIDAR_ECHO_FIRST:
            out[0] = e;
            return 1;
        case LIDAR_ECHO_LAST:
            out[0] = e;
            n = 1;
            break;
        case LIDAR_ECHO_STRONGEST: /* a tie keeps the nearer */
            if (!n || e.intensity > out[0].intensity) out[0] = e;
            n = 1;
            break;
        case LIDAR_ECHO_ALL: /* the nearest max_out */
            out[n++] = e;
            if (n == max_out) return n;
            break;
        }
    }
    return n;
}
