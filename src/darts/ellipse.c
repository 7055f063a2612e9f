/* Ellipse records and elliptical control vertices (reference §3 and §6; paper §5.2, eq. 19–22). */
#include "dartspp/darts.h"

#define REL_EPS 1e-9 /* relative tolerance on residual lengths (scale-free) */

int darts_can_reach(const darts_guide *g, const darts_bin *b, vec3 x, double tau)
{
    return tau + g->eta_lb * v3_len(v3_sub(g->cam, x)) < b->end;
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
    if (!(r->S_hi > r->C * (1.0 + REL_EPS)) || !(r->C > 0.0)) return;
    r->S_lo = fmax(lo, r->C);
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
