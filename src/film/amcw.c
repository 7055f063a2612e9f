/* AMCW (amplitude-modulated continuous-wave) time of flight from the film (docs/amcw.md): the per-contribution
 * correlation sums, their mean over passes as complex values, and the depth from one or two frequencies with
 * the two-frequency unwrapping. */
#include "dartspp/film.h"

#include <math.h>
#include <stdint.h>

void film_amcw_add(film *f, size_t px, double t, vec3 c)
{
    int n = f->window.amcw_count;
    double *a = &f->amcw_pass[(size_t)6 * n * px];
    for (int j = 0; j < n; j++, a += 6) {
        double phi = f->amcw_k[j] * t, cs = cos(phi), sn = sin(phi);
        a[0] += c.x * cs;
        a[1] -= c.x * sn;
        a[2] += c.y * cs;
        a[3] -= c.y * sn;
        a[4] += c.z * cs;
        a[5] -= c.z * sn;
    }
}

long film_amcw_values(const film *f, float *out)
{
    int n = f->window.amcw_count;
    if (n <= 0 || !f->amcw_sum) return 0;
    size_t npx = (size_t)f->width * f->height;
    double inv = f->weight_sum > 0.0 ? 1.0 / f->weight_sum : 0.0;
    long bad = 0;
    for (int j = 0; j < n; j++)
        for (size_t px = 0; px < npx; px++) {
            const double *a = &f->amcw_sum[((size_t)n * px + j) * 6];
            float v[6];
            int finite = 1;
            for (int i = 0; i < 6; i++) {
                v[i] = (float)(a[i] * inv);
                finite = finite && isfinite(v[i]);
            }
            bad += !finite;
            if (out)
                for (int i = 0; i < 6; i++) out[((size_t)j * npx + px) * 6 + i] = finite ? v[i] : 0.0f;
        }
    return bad;
}

/* The wrap depth c₀/(2f) of f MHz, in scene units. */
static double wrap_depth(double mhz) { return AMCW_C0 / (2.0 * mhz * 1e6); }

static uint64_t gcd_u64(uint64_t a, uint64_t b)
{
    while (b) {
        uint64_t r = a % b;
        a = b;
        b = r;
    }
    return a;
}

double amcw_unwrap_range(double f1, double f2)
{
    uint64_t a = (uint64_t)llround(f1 * 1e6), b = (uint64_t)llround(f2 * 1e6), g = gcd_u64(a, b);
    double cap = AMCW_UNWRAP_WRAPS * fmax(wrap_depth(f1), wrap_depth(f2));
    return g > 0 ? fmin(AMCW_C0 / (2.0 * (double)g), cap) : cap;
}

double amcw_unwrap(double d1, double f1, double d2, double f2)
{
    /* the lower frequency (the longer wrap depth) is searched, the other follows as its nearest wrap */
    double dl = d1, fl = f1, ds = d2, fs = f2;
    if (f2 < f1) dl = d2, fl = f2, ds = d1, fs = f1;
    double rl = wrap_depth(fl), rs = wrap_depth(fs), range = amcw_unwrap_range(f1, f2);
    double best = INFINITY, depth = 0.5 * (d1 + d2);
    for (long nl = 0; dl + nl * rl < range || nl == 0; nl++) {
        double Dl = dl + nl * rl, ns = fmax(0.0, round((Dl - ds) / rs)), Ds = ds + ns * rs, diff = fabs(Dl - Ds);
        if (diff < best) {
            best = diff;
            depth = 0.5 * (Dl + Ds);
        }
    }
    return depth;
}

/* The wrapped depth of phasor (re, im) = ∫ I e^{−iφ}: φ = −arg ∈ [0, 2π), d = φ/(2k) (depth = t/2). */
static double wrapped_depth(double re, double im, double k)
{
    double phi = atan2(-im, re);
    if (phi < 0.0) phi += 2.0 * M_PI;
    return phi / (2.0 * k);
}

void film_amcw_depth(const film *f, float *out, long *dark)
{
    int n = f->window.amcw_count;
    size_t npx = (size_t)f->width * f->height;
    *dark = 0;
    if (n <= 0 || !f->amcw_sum) return;
    for (size_t px = 0; px < npx; px++) {
        double d[2] = {0.0, 0.0};
        int ok = 1;
        for (int j = 0; j < n && j < 2; j++) {
            const double *a = &f->amcw_sum[((size_t)n * px + j) * 6];
            double re = (a[0] + a[2] + a[4]) / 3.0, im = (a[1] + a[3] + a[5]) / 3.0; /* the weight sum cancels */
            if (!(isfinite(re) && isfinite(im)) || (re == 0.0 && im == 0.0)) ok = 0;
            else d[j] = wrapped_depth(re, im, f->amcw_k[j]);
        }
        double depth = !ok ? 0.0 : n == 1 ? d[0] : amcw_unwrap(d[0], f->window.amcw_mhz[0], d[1], f->window.amcw_mhz[1]);
        *dark += !ok;
        if (out) out[px] = (float)depth;
    }
}
