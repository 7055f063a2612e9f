/* Control vertices with camera-unwarped time (darts.h, sphere_control_vertex): the ray's chord through the
 * spherical shell of places whose light-leg time falls in the bin, sampled by a truncated exponential. */
#include "dartspp/darts.h"

/* The admissible interval [lo, hi) of distances along the ray; 0 when it is empty. */
static int shell_chord(double tau, double eta, const darts_bin *b, double tmax, double *lo, double *hi)
{
    *lo = dp_fmax(0.0, (b->start - tau) / eta);
    *hi = dp_fmin(tmax, (b->end - tau) / eta);
    return *hi > *lo;
}

int sphere_control_vertex(double tau, double eta, const darts_bin *b, double tmax, double sigma, double u, double *t,
                          double *pdf_t)
{
    double lo, hi;
    if (!shell_chord(tau, eta, b, tmax, &lo, &hi)) return 0;
    double L = hi - lo, a = sigma * L;
    if (!(a > 1e-6)) { /* uniform */
        *t = lo + u * L;
        *pdf_t = 1.0 / L;
        return *t < hi;
    }
    double mass = -expm1(-a);              /* 1 − e^{−σL} */
    double s = -log1p(-u * mass) / sigma;  /* offset from lo, p(s) = σe^{−σs}/(1 − e^{−σL}) */
    if (!(s < L)) return 0;                /* rounding at u → 1: probability ~0 */
    *t = lo + s;
    *pdf_t = sigma * exp(-sigma * s) / mass;
    return isfinite(*pdf_t) && *pdf_t > 0.0;
}

double sphere_control_vertex_pdf(double tau, double eta, const darts_bin *b, double tmax, double sigma, double t)
{
    double lo, hi;
    if (!shell_chord(tau, eta, b, tmax, &lo, &hi) || t < lo || !(t < hi)) return 0.0;
    double L = hi - lo, a = sigma * L;
    if (!(a > 1e-6)) return 1.0 / L;
    return sigma * exp(-sigma * (t - lo)) / -expm1(-a);
}
