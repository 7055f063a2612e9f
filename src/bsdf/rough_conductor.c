/* Rough conductor: microfacet reflection (Walter et al. 2007 eq. 20) with the complex-index Fresnel term
 * F(η, κ, wi·h), tinted by albedo. Normals sampled from D(m)·cos θm with the unwidened alpha (as the
 * reference). One GLOSSY lobe. */
#include "bsdf_internal.h"

/* f without albedo, per channel, and the half vector; 0 when the pair has no value. */
static int conductor_value(const bsdf *b, vec3 wi, vec3 wo, vec3 *f)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return 0;
    vec3 h = v3_add(wi, wo);
    double l = v3_len(h);
    if (!(l > 1e-12)) return 0;
    h = v3_scale(h, 1.0 / l);
    double D = bsdf_mf_D(b->distribution, b->alpha, h);
    double G = bsdf_mf_G(b->distribution, b->alpha, wi, wo, h);
    if (D == 0.0 || G == 0.0) return 0;
    vec3 F = bsdf_fresnel_conductor3(b->eta, b->k, v3_dot(wi, h));
    *f = v3_scale(F, D * G / (4.0 * wi.z * wo.z));
    return 1;
}

vec3 bsdf_rough_conductor_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    vec3 f;
    if (!(lobes & BSDF_LOBE_GLOSSY) || !conductor_value(b, wi, wo, &f)) return v3s(0.0);
    return v3_mul(albedo, f);
}

double bsdf_rough_conductor_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)albedo;
    if (!(lobes & BSDF_LOBE_GLOSSY) || wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    vec3 h = v3_add(wi, wo);
    double l = v3_len(h);
    if (!(l > 1e-12)) return 0.0;
    h = v3_scale(h, 1.0 / l);
    double ih = v3_dot(wi, h);
    if (ih <= 0.0) return 0.0;
    return bsdf_mf_pdf(b->distribution, b->alpha, h) / (4.0 * ih); /* eq. 14 */
}

int bsdf_rough_conductor_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,
                                bsdf_sample *s)
{
    if (!(lobes & BSDF_LOBE_GLOSSY) || wi.z <= 0.0) return 0;
    vec3 m = bsdf_mf_sample(b->distribution, b->alpha, u[0], u[1]);
    double c = v3_dot(wi, m);
    if (c <= 0.0) return 0;
    s->wo = v3_sub(v3_scale(m, 2.0 * c), wi); /* eq. 39 */
    if (s->wo.z <= 0.0) return 0;
    vec3 f;
    double p = bsdf_rough_conductor_pdf(b, albedo, wi, s->wo, lobes);
    if (!(p > 0.0) || !conductor_value(b, wi, s->wo, &f)) return 0;
    s->pdf = p;
    s->weight = v3_scale(v3_mul(albedo, f), s->wo.z / p);
    s->lobe = BSDF_LOBE_GLOSSY;
    return 1;
}
