/* Phase functions: isotropic, Henyey–Greenstein (Tungsten convention: μ = ω_in · ω_out between two
 * propagation directions) and tabulated (phase_table.c: p(θ) linear in θ between a file's rows). `ida` evaluates
 * as HG with its g, as in the reference: EDA changes only how the photon pass samples directions (darts.h). */
#include "dartspp/scene.h"

static double hg_eval(double g, double mu)
{
    double denom = 1.0 + g * g - 2.0 * g * mu;
    return DP_INV_4PI * (1.0 - g * g) / (denom * sqrt(denom));
}

/* The angle between two unit vectors, accurate at 0 and π: 2 atan2(|b − a|, |b + a|). */
static double angle_between(vec3 a, vec3 b)
{
    return 2.0 * atan2(v3_len(v3_sub(b, a)), v3_len(v3_add(b, a)));
}

double phase_eval(const phase_function *pf, vec3 w_in, vec3 w_out)
{
    if (pf->type == PHASE_TABULATED) return phase_table_eval(pf->table, angle_between(w_in, w_out));
    if (phase_is_isotropic(pf)) return DP_INV_4PI;
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
    double mu, sin_t;
    if (pf->type == PHASE_TABULATED) {
        double theta = phase_table_sample_theta(pf->table, u1);
        mu = cos(theta), sin_t = sin(theta);
    } else {
        if (phase_is_isotropic(pf)) return sample_uniform_sphere(u1, u2);
        mu = hg_sample_mu(pf->g, u1);
        sin_t = sqrt(dp_fmax(0.0, 1.0 - mu * mu));
    }
    double phi = 2.0 * M_PI * u2;
    vec3 s, t;
    v3_basis(w_in, &s, &t);
    return v3_norm(v3_add(v3_scale(w_in, mu), v3_add(v3_scale(s, sin_t * cos(phi)), v3_scale(t, sin_t * sin(phi)))));
}
