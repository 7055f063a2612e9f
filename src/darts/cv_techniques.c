/* Control vertices behind mirrors: one-sample MIS of the straight focus, the mirror foci and a defensive
 * free flight (darts.h, cv_techniques). Ours: the reference assumes a straight camera leg everywhere. */
#include "dartspp/darts.h"

/* Where the reachable set ends along d (0 when it is empty). */
static double reach_distance(const ellipse_record *r0, vec3 d)
{
    return darts_reach_along(r0->S_reach, r0->C, v3_dot(d, r0->e));
}

/* The defensive technique's interval [0, t_d) and its σ-exponential density. */
static double defensive_end(const cv_techniques *ct, vec3 d, double tmax)
{
    return dp_fmin(tmax, reach_distance(&ct->rec[0], d));
}

static double defensive_pdf(double t_d, double sigma, double t)
{
    if (!(t >= 0.0 && t < t_d)) return 0.0;
    double a = sigma * t_d;
    if (!isfinite(t_d)) return sigma > 0.0 ? sigma * exp(-sigma * t) : 0.0;
    return a > 1e-6 ? sigma * exp(-sigma * t) / -expm1(-a) : 1.0 / t_d;
}

static double defensive_sample(double t_d, double sigma, double u)
{
    double a = sigma * t_d;
    double t = !isfinite(t_d) ? -log1p(-u) / sigma : a > 1e-6 ? -log1p(-u * -expm1(-a)) / sigma : u * t_d;
    return t < t_d ? t : nextafter(t_d, 0.0);
}

/* Selection probabilities over the techniques usable at this vertex along d (sum 1), or 0 if none. */
static int usable_shares(const cv_techniques *ct, double t_d, double sigma, double *share, double *def)
{
    double sum = 0.0;
    for (int k = 0; k < ct->n; k++) sum += share[k] = ct->rec[k].valid ? ct->share[k] : 0.0;
    int def_ok = t_d > 0.0 && (isfinite(t_d) ? 1 : sigma > 0.0);
    sum += *def = def_ok ? ct->defensive : 0.0;
    if (!(sum > 0.0)) return 0;
    for (int k = 0; k < ct->n; k++) share[k] /= sum;
    *def /= sum;
    return 1;
}

static double mixture_pdf(const cv_techniques *ct, const double *share, double def, double t_d, vec3 d, int mis,
                          residual_sampling mode, double sigma, double t)
{
    double p = def * defensive_pdf(t_d, sigma, t);
    for (int k = 0; k < ct->n; k++)
        if (share[k] > 0.0) p += share[k] * control_vertex_pdf(&ct->rec[k], d, t, mis, mode, sigma);
    return p;
}

double cv_techniques_pdf(const cv_techniques *ct, vec3 d, double tmax, int mis, residual_sampling mode, double sigma,
                         double t)
{
    double share[1 + DARTS_MAX_MIRRORS], def, t_d = defensive_end(ct, d, tmax);
    if (!(t >= 0.0 && t < tmax) || !usable_shares(ct, t_d, sigma, share, &def)) return 0.0;
    return mixture_pdf(ct, share, def, t_d, d, mis, mode, sigma, t);
}

int cv_techniques_sample(const cv_techniques *ct, vec3 d, double tmax, int mis, residual_sampling mode, double sigma,
                         const double u[3], double *t, double *pdf)
{
    double share[1 + DARTS_MAX_MIRRORS], def, t_d = defensive_end(ct, d, tmax);
    if (!usable_shares(ct, t_d, sigma, share, &def)) return 0;
    double tt, p_unused, c = u[0];
    int k = 0;
    while (k < ct->n && !(c < share[k])) c -= share[k++];
    if (k == ct->n && !(def > 0.0)) { /* rounding past the last share: the last usable record */
        while (k > 0 && !(share[k - 1] > 0.0)) k--;
        k--;
    }
    if (k < ct->n) {
        int ok = mis ? control_vertex_sample(&ct->rec[k], d, tmax, mode, sigma, u[1], u[2], &tt, &p_unused)
                     : ellipse_control_vertex(&ct->rec[k], d, tmax, &tt, &p_unused);
        if (!ok) return 0;
    } else {
        tt = defensive_sample(t_d, sigma, u[1]);
    }
    if (!(tt > 0.0) || !(tt < tmax)) return 0;
    *t = tt;
    *pdf = mixture_pdf(ct, share, def, t_d, d, mis, mode, sigma, tt);
    return isfinite(*pdf) && *pdf > 0.0;
}
