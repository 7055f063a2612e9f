/* The sensor's time response (include/dartspp/sensor.h; docs/sensor.md §2): the offset a detection adds to
 * a photon's arrival time. Sampled with a fixed number of random numbers per kind (so that the surface
 * chains' small steps move it smoothly): the Gaussian by Box–Muller (2), the exponential delay by
 * inversion (1), a tabulated density by inverting its piecewise-quadratic CDF (1). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/sensor.h"

#define FWHM_PER_SIGMA 2.3548200450309493 /* 2·sqrt(2 ln 2) */

static int table_fail(sensor_response *r, dp_error *err, const char *path, int line, const char *why)
{
    sensor_response_free(r);
    if (line > 0) return dp_fail(err, "%s:%d: sensor response table: %s", path, line, why);
    return dp_fail(err, "%s: sensor response table: %s", path, why);
}

static int push_knot(sensor_response *r, int *cap, double t, double p)
{
    if (r->n == *cap) {
        int c = *cap ? 2 * *cap : 64;
        double *nt = realloc(r->t, (size_t)c * sizeof *nt);
        if (nt) r->t = nt;
        double *np = nt ? realloc(r->p, (size_t)c * sizeof *np) : NULL;
        if (np) r->p = np;
        if (!nt || !np) return -1;
        *cap = c;
    }
    r->t[r->n] = t, r->p[r->n] = p, r->n++;
    return 0;
}

static int load_table(sensor_response *r, const char *path, dp_error *err)
{
    FILE *f = fopen(path, "r");
    if (!f) return dp_fail(err, "%s: cannot open the sensor response table: %s", path, strerror(errno));
    char line[512];
    int no = 0, cap = 0, rc = 0;
    while (!rc && fgets(line, sizeof line, f)) {
        no++;
        char *s = line;
        while (*s == ' ' || *s == '\t') s++;
        if (*s == '\n' || *s == '\r' || *s == 0 || *s == '#') continue;
        double t, p;
        char extra;
        if (sscanf(s, "%lf , %lf %c", &t, &p, &extra) != 2) {
            if (r->n == 0 && no == 1) continue; /* a header line */
            fclose(f);
            return table_fail(r, err, path, no, "expected \"time,value\"");
        }
        if (!isfinite(t) || !isfinite(p) || p < 0.0) rc = table_fail(r, err, path, no, "a value is negative or not finite");
        else if (r->n > 0 && !(t > r->t[r->n - 1])) rc = table_fail(r, err, path, no, "times must increase");
        else if (push_knot(r, &cap, t, p)) rc = dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    }
    fclose(f);
    if (rc) return rc;
    if (r->n < 2) return table_fail(r, err, path, 0, "fewer than two rows");
    r->cdf = malloc((size_t)r->n * sizeof *r->cdf);
    if (!r->cdf) return table_fail(r, err, path, 0, "out of memory");
    r->cdf[0] = 0.0;
    for (int i = 1; i < r->n; i++) r->cdf[i] = r->cdf[i - 1] + 0.5 * (r->p[i - 1] + r->p[i]) * (r->t[i] - r->t[i - 1]);
    double total = r->cdf[r->n - 1];
    if (!(total > 0.0)) return table_fail(r, err, path, 0, "its area is 0");
    for (int i = 0; i < r->n; i++) r->p[i] /= total, r->cdf[i] /= total;
    return 0;
}

int sensor_response_init(sensor_response *r, double fwhm, double tail, const char *table_path, dp_error *err)
{
    memset(r, 0, sizeof *r);
    if (table_path && table_path[0]) {
        if (fwhm > 0.0 || tail > 0.0)
            return dp_fail(err, "%s: a sensor response table and a jitter FWHM or tail cannot be combined", table_path);
        if (load_table(r, table_path, err)) return -1;
        r->on = 1;
        return 0;
    }
    if (!(fwhm >= 0.0) || !(tail >= 0.0) || !isfinite(fwhm) || !isfinite(tail))
        return dp_fail(err, "sensor response: FWHM %g and tail %g must be finite and >= 0", fwhm, tail);
    r->sigma = fwhm / FWHM_PER_SIGMA;
    r->tail = tail;
    r->on = fwhm > 0.0 || tail > 0.0;
    return 0;
}

/* The offset x in [t_i, t_{i+1}) where the tabulated CDF reaches u: the linear density's area from t_i is
 * A = p_i·h·v + (p_{i+1} − p_i)·h·v²/2 with v = (x − t_i)/h, solved for v in the form without cancellation. */
static double table_sample(const sensor_response *r, double u)
{
    int lo = 0, hi = r->n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (r->cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    double h = r->t[lo + 1] - r->t[lo], p0 = r->p[lo], p1 = r->p[lo + 1], a = (u - r->cdf[lo]) / h;
    double disc = p0 * p0 + 2.0 * (p1 - p0) * a, den = p0 + sqrt(disc > 0.0 ? disc : 0.0);
    double v = den > 0.0 ? 2.0 * a / den : 0.0;
    return r->t[lo] + h * (v < 1.0 ? v : 1.0);
}

double sensor_response_sample(const sensor_response *r, dp_rng *rng)
{
    if (!r->on) return 0.0;
    if (r->n) return table_sample(r, rng_uniform(rng));
    double x = 0.0;
    if (r->sigma > 0.0) {
        double u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        x = r->sigma * sqrt(-2.0 * log1p(-u1)) * cos(2.0 * M_PI * u2);
    }
    if (r->tail > 0.0) x -= r->tail * log1p(-rng_uniform(rng));
    return x;
}

double sensor_response_cdf(const sensor_response *r, double x)
{
    if (!r->on) return x >= 0.0;
    if (r->n) {
        if (x <= r->t[0]) return 0.0;
        if (x >= r->t[r->n - 1]) return 1.0;
        int i = 0;
        while (x >= r->t[i + 1]) i++;
        double h = x - r->t[i], slope = (r->p[i + 1] - r->p[i]) / (r->t[i + 1] - r->t[i]);
        return r->cdf[i] + r->p[i] * h + 0.5 * slope * h * h;
    }
    double s = r->sigma, tau = r->tail;
    if (tau == 0.0) return 0.5 * erfc(-x / (s * M_SQRT2));
    if (s == 0.0) return x > 0.0 ? -expm1(-x / tau) : 0.0;
    /* exponentially modified Gaussian: Φ(x/σ) − e^{−x/τ + σ²/(2τ²)}·Φ(x/σ − σ/τ), the second term as one
     * exponential of erfc's logarithm, which cannot overflow */
    double z = x / s - s / tau, second = 0.5 * erfc(-z / M_SQRT2);
    double term = second > 0.0 ? exp(-x / tau + s * s / (2.0 * tau * tau) + log(second)) : 0.0;
    return 0.5 * erfc(-x / (s * M_SQRT2)) - term;
}

void sensor_response_free(sensor_response *r)
{
    free(r->t);
    free(r->p);
    free(r->cdf);
    r->t = r->p = r->cdf = NULL;
    r->n = 0;
}
