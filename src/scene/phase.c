/* Phase functions: isotropic and Henyey–Greenstein (Tungsten convention: μ = ω_in · ω_out between two
 * propagation directions). `ida` evaluates as HG with its g, as in the reference: EDA changes only how the
 * photon pass samples directions (darts.h). */
#include "dartspp/scene.h"

static double hg_eval(double g, double mu)
{
    double denom = 1.0 + g * g - 2.0 * g * mu;
    return DP_INV_4PI * (1.0 - g * g) / (denom * sqrt(denom));
}

double phase_eval(const phase_function *pf, vec3 w_in, vec3 w_out)
{
    if (pf->type == PHASE_ISOTROPIC || pf->g == 0.0) return DP_INV_4PI;
    return hg_eval(pf->g, v3_dot(w_in, w_out));
}

/* Inverse CDF of HG in μ (pbrt-v3 form, written for the propagation-direction convention). */
static double hg_sample_mu(double g, double u)
{
    if (fabs(g) < 1e-3) return 1.0 - 2.0 * u;
    double sq = (1.0 - g * g) / (1.0 + g - 2.0 * g * u);
    double mu = (1.0 + g * g - sq * sq) / (2.0 * g);
    return dp_fmin(1.0, dp_fmax(-1.0, mu));
}

vec3 phase_sample(const phase_function *pf, vec3 w_in, double u1, double u2)
{
    if (pf->type == PHASE_ISOTROPIC || pf->g == 0.0) return sample_uniform_sphere(u1, u2);
    double mu = hg_sample_mu(pf->g, u1);
    double sin_t = sqrt(dp_fmax(0.0, 1.0 - mu * mu)), phi = 2.0 * M_PI * u2;
    vec3 s, t;
    v3_basis(w_in, &s, &t);
    return v3_norm(v3_add(v3_scale(w_in, mu), v3_add(v3_scale(s, sin_t * cos(phi)), v3_scale(t, sin_t * sin(phi)))));
}
