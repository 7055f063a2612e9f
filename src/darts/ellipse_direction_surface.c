/* Directions toward the next elliptical connection at a surface vertex of the DARTS path tracer (ours;
 * docs/darts.md §14.4): one-sample MIS (the balance heuristic, Veach 1997 §9.2.4) of ellipse_direction_sample
 * (share c) and the BSDF's own sampler, for BSDFs without delta lobes. With f_c(ω) = f(ω_i, ω)·|n_s·ω| and
 * p_bsdf the BSDF sampler's density (surface_pdf), a direction from either technique weighs
 *   f_c(ω) / (c·p_ell(ω) + (1 − c)·p_bsdf(ω)),
 * an unbiased estimate of ∫ f_c(ω)·g(ω) dω for any g wherever the mixture covers f_c: the ellipse sampler's
 * support is the whole sphere, so with c > 0 it does. Directions of the ellipse sampler where f_c = 0 (below
 * an opaque surface) end the path: zero, unbiased, wasted. */
#include "dartspp/darts.h"

int ellipse_direction_surface_sample(const surface_site *ss, vec3 x, vec3 target, double T, double share,
                                     const double u[4], surface_sample *out)
{
    if (!(share > 0.0) || !ellipse_direction_usable(x, target, T)) return surface_sample_bsdf(ss, u + 1, BSDF_LOBES_ALL, 0, out);
    vec3 w;
    double p_ell;
    if (u[0] < share) {
        if (!ellipse_direction_sample(x, target, T, u[1], u[2], &w, &p_ell)) return 0;
        out->lobe = bsdf_lobes(ss->b) & BSDF_LOBE_GLOSSY ? BSDF_LOBE_GLOSSY : BSDF_LOBE_DIFFUSE;
    } else {
        if (!surface_sample_bsdf(ss, u + 1, BSDF_LOBES_ALL, 0, out)) return 0;
        w = out->w;
        p_ell = ellipse_direction_pdf(x, target, T, w);
    }
    vec3 f = surface_eval_cos(ss, w, BSDF_LOBES_ALL);
    double mix = share * p_ell + (1.0 - share) * surface_pdf(ss, w, BSDF_LOBES_ALL);
    if (!(mix > 0.0) || !isfinite(mix) || !(v3_max(f) > 0.0)) return 0;
    out->w = w;
    out->weight = v3_scale(f, 1.0 / mix);
    return v3_is_finite(out->weight);
}
