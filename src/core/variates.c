/* Non-uniform variates on the counter-based streams: normal, gamma, beta, binomial and Poisson, exact for
 * every parameter (no normal approximation at large counts). The photon-counting model (src/sensor) draws
 * per-bin counts with means from below one to millions, so the discrete ones must be exact and cost
 * O(log n). Written here because the libraries that have them (GSL) are not among our dependencies and the
 * methods are short:
 *   normal   Marsaglia's polar method;
 *   gamma    Marsaglia and Tsang 2000, "A simple method for generating gamma variables" (shape < 1 through
 *            Gamma(a + 1)·U^(1/a));
 *   binomial and Poisson: Knuth, TAOCP vol. 2 §3.4.1 F (binomial through the order statistic Beta(i, n+1−i)
 *            of n uniforms; Poisson through the m-th arrival time Gamma(m) of a unit-rate process), down to
 *            small parameters, which are counted directly. */
#include <math.h>

#include "dartspp/core.h"

double rng_normal(dp_rng *r)
{
    for (;;) {
        double x = 2.0 * rng_uniform(r) - 1.0, y = 2.0 * rng_uniform(r) - 1.0, s = x * x + y * y;
        if (s > 0.0 && s < 1.0) return x * sqrt(-2.0 * log(s) / s);
    }
}

double rng_gamma(dp_rng *r, double shape)
{
    if (!(shape > 0.0)) return 0.0;
    if (shape < 1.0) { /* Gamma(a) = Gamma(a + 1)·U^(1/a) */
        double u = rng_uniform(r);
        return rng_gamma(r, shape + 1.0) * pow(u > 0.0 ? u : 0x1.0p-53, 1.0 / shape);
    }
    double d = shape - 1.0 / 3.0, c = 1.0 / sqrt(9.0 * d);
    for (;;) {
        double x = rng_normal(r), v = 1.0 + c * x;
        if (v <= 0.0) continue;
        v = v * v * v;
        double u = rng_uniform(r), x2 = x * x;
        if (u < 1.0 - 0.0331 * x2 * x2) return d * v;
        if (u > 0.0 && log(u) < 0.5 * x2 + d * (1.0 - v + log(v))) return d * v;
    }
}

double rng_beta(dp_rng *r, double a, double b)
{
    double x = rng_gamma(r, a), y = rng_gamma(r, b);
    return x + y > 0.0 ? x / (x + y) : 0.5;
}

#define DIRECT_MAX 64 /* below this many trials (or a Poisson mean this small), count one by one */

long rng_binomial(dp_rng *r, long n, double p)
{
    long k = 0;
    while (n > DIRECT_MAX && p > 0.0 && p < 1.0) {
        long i = 1 + n / 2;
        double x = rng_beta(r, (double)i, (double)(n + 1 - i)); /* the i-th smallest of n uniforms */
        if (x >= p) {         /* the i − 1 below it are uniform on [0, x): those below p count */
            n = i - 1;
            p = p / x;
        } else {              /* the i up to x count; the n − i above are uniform on (x, 1) */
            k += i;
            n -= i;
            p = (p - x) / (1.0 - x);
        }
    }
    if (n <= 0 || p <= 0.0) return k;
    if (p >= 1.0) return k + n;
    for (long j = 0; j < n; j++) k += rng_uniform(r) < p;
    return k;
}

long rng_poisson(dp_rng *r, double mean)
{
    long k = 0;
    if (!(mean > 0.0)) return 0;
    while (mean > DIRECT_MAX / 4) {
        long m = (long)(0.875 * mean);
        double x = rng_gamma(r, (double)m); /* the m-th arrival of a unit-rate process */
        if (x >= mean) return k + rng_binomial(r, m - 1, mean / x); /* the first m − 1 are uniform on [0, x) */
        k += m;
        mean -= x;
    }
    double limit = exp(-mean), prod = rng_uniform(r); /* arrivals by products of uniforms */
    while (prod > limit) {
        k++;
        prod *= rng_uniform(r);
    }
    return k;
}
