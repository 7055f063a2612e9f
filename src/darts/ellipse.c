/* Ellipse records and elliptical control vertices (docs/darts.md §3 and §5; paper §5.2, eq. 19–22). */
#include "dartspp/darts.h"

#define REL_EPS 1e-9 /* relative tolerance on residual lengths (scale-free) */
#define CV_ELLIPTICAL_FRACTION 0.5 /* one-sample MIS: probability of the elliptical technique */

int darts_can_reach(const darts_guide *g, const darts_bin *b, vec3 x, double tau)
{
    return tau + darts_leg_lb(g, x) < b->end;
}

/* Residual S on [lo, hi]: uniform (reference) or exponential with rate σ truncated to [lo, hi] (eq. 21–22). */
static double sample_residual(double lo, double hi, residual_sampling mode, double sigma, double u, double *inv_pdf)
{
    double L = hi - lo;
    double a = sigma * L;
    if (mode == RESIDUAL_UNIFORM || !(a > 1e-6)) {
        *inv_pdf = L;
        return lo + u * L;
    }
    double mass = -expm1(-a);                       /* 1 − e^{−σL} */
    double s = -log1p(-u * mass) / sigma;           /* offset from lo */
    if (s > L) s = L;
    *inv_pdf = mass / (sigma * exp(-sigma * s));    /* 1/p(S), p(S) = σe^{−σ(S−lo)}/(1 − e^{−σL}) */
    return lo + s;
}

void ellipse_record_init(ellipse_record *r, const darts_guide *g, const darts_bin *b, vec3 x, double tau,
                         double eta, residual_sampling mode, double sigma_t_avg, double u)
{
    *r = (ellipse_record){0};
    r->x = x;
    vec3 v = v3_sub(g->cam, x);
    r->C = v3_len(v);
    r->e = r->C > 0.0 ? v3_scale(v, 1.0 / r->C) : v3(0, 0, 1);
    r->S_hi = (b->end - tau) / eta;
    r->S_reach = (b->end - tau) / g->eta_lb;
    double lo = (b->start - tau) / eta;
    /* C = 0 (the vertex at the target: a light at the camera) is a valid record: the ellipsoid is the sphere
     * of diameter T about x, paper eq. 19 gives t = T/2 along every direction, and e never counts (it is
     * always multiplied by C) (docs/darts.md §3) */
    if (!(r->S_hi > r->C * (1.0 + REL_EPS))) return;
    r->S_lo = dp_fmax(lo, r->C);
    r->T = sample_residual(r->S_lo, r->S_hi, mode, sigma_t_avg, u, &r->inv_pdf_T);
    r->valid = r->T > r->C && r->inv_pdf_T > 0.0 && isfinite(r->inv_pdf_T);
}

int ellipse_control_vertex(const ellipse_record *r, vec3 d, double tmax, double *t, double *pdf_t)
{
    if (!r->valid) return 0;
    double cos_theta = v3_dot(d, r->e);
    double den = r->T - r->C * cos_theta;              /* >= T − C > 0 */
    double tt = 0.5 * (r->T - r->C) * (r->T + r->C) / den; /* eq. 19: polar distance on the ellipsoid */
    if (!(tt > 0.0) || !(tt < tmax)) return 0;         /* case II (surface first): no control vertex */
    double ell = r->T - tt;                            /* |x(t) − cam| */
    if (!(ell > 0.0)) return 0;
    *t = tt;
    *pdf_t = den / (ell * r->inv_pdf_T);               /* p(T)·dT/dt, dT/dt = (T − C cosθ)/(T − t) */
    return isfinite(*pdf_t) && *pdf_t > 0.0;
}

/* Polar distance on the ellipsoid of residual S (foci x and cam) along a direction with cosθ: eq. 19. */
static double ellipse_distance(double C, double cos_theta, double S)
{
    return 0.5 * (S - C) * (S + C) / (S - C * cos_theta);
}

double ellipse_residual_pdf(const ellipse_record *r, double S, residual_sampling mode, double sigma)
{
    if (!(S >= r->S_lo && S <= r->S_hi)) return 0.0;
    double L = r->S_hi - r->S_lo, a = sigma * L;
    if (mode == RESIDUAL_UNIFORM || !(a > 1e-6)) return 1.0 / L;
    return sigma * exp(-sigma * (S - r->S_lo)) / -expm1(-a);
}

double ellipse_control_vertex_pdf(const ellipse_record *r, vec3 d, double t, residual_sampling mode, double sigma)
{
    if (!r->valid || !(t > 0.0)) return 0.0;
    double cos_theta = v3_dot(d, r->e);
    vec3 to_cam = v3_sub(v3_scale(r->e, r->C), v3_scale(d, t)); /* cam − x(t) */
    double ell = v3_len(to_cam), S = t + ell;
    if (!(ell > 0.0)) return 0.0;
    return ellipse_residual_pdf(r, S, mode, sigma) * (S - r->C * cos_theta) / ell; /* p(S)·dS/dt */
}

int control_vertex_sample(const ellipse_record *r, vec3 d, double tmax, residual_sampling mode, double sigma,
                          double u_select, double u_t, double *t, double *pdf_t)
{
    if (!r->valid) return 0;
    double cos_theta = v3_dot(d, r->e);
    double t_lo = ellipse_distance(r->C, cos_theta, r->S_lo), t_hi = ellipse_distance(r->C, cos_theta, r->S_hi);
    if (!(t_hi > t_lo) || !(t_lo >= 0.0)) return ellipse_control_vertex(r, d, tmax, t, pdf_t);
    /* the second technique: σ-exponential in t on [t_lo, t_hi] (σ > 0), or uniform */
    double span = t_hi - t_lo, a = sigma * span;
    double tt, pdf_e_at;
    if (u_select < CV_ELLIPTICAL_FRACTION) {
        double pe;
        if (!ellipse_control_vertex(r, d, INFINITY, &tt, &pe)) return 0;
    } else {
        double u = u_t;
        tt = a > 1e-6 ? t_lo - log1p(-u * -expm1(-a)) / sigma : t_lo + u * span;
        if (!(tt < t_hi)) tt = nextafter(t_hi, t_lo);
    }
    if (!(tt > 0.0) || !(tt < tmax)) return 0; /* beyond the next surface: no control vertex */
    pdf_e_at = !(tt >= t_lo && tt < t_hi) ? 0.0
               : a > 1e-6 ? sigma * exp(-sigma * (tt - t_lo)) / -expm1(-a) : 1.0 / span;
    double p_ell = ellipse_control_vertex_pdf(r, d, tt, mode, sigma);
    *t = tt;
    *pdf_t = CV_ELLIPTICAL_FRACTION * p_ell + (1.0 - CV_ELLIPTICAL_FRACTION) * pdf_e_at; /* balance heuristic */
    return isfinite(*pdf_t) && *pdf_t > 0.0;
}

double control_vertex_pdf(const ellipse_record *r, vec3 d, double t, int mis, residual_sampling mode, double sigma)
{
    double p_ell = ellipse_control_vertex_pdf(r, d, t, mode, sigma);
    if (!mis || !r->valid) return p_ell;
    double cos_theta = v3_dot(d, r->e);
    double t_lo = ellipse_distance(r->C, cos_theta, r->S_lo), t_hi = ellipse_distance(r->C, cos_theta, r->S_hi);
    if (!(t_hi > t_lo) || !(t_lo >= 0.0)) return p_ell; /* control_vertex_sample's fallback */
    double span = t_hi - t_lo, a = sigma * span;
    double p_exp = !(t >= t_lo && t < t_hi) ? 0.0
                   : a > 1e-6 ? sigma * exp(-sigma * (t - t_lo)) / -expm1(-a) : 1.0 / span;
    return CV_ELLIPTICAL_FRACTION * p_ell + (1.0 - CV_ELLIPTICAL_FRACTION) * p_exp;
}
