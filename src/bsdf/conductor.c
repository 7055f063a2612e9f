/* Smooth conductor: a delta reflection weighted by the complex-index Fresnel reflectance F(η, κ, cos θi)
 * per channel, tinted by albedo. One SPECULAR lobe. */
#include "bsdf_internal.h"

vec3 bsdf_conductor_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return v3s(0.0);
}

double bsdf_conductor_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return 0.0;
}

int bsdf_conductor_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    (void)u;
    if (!(lobes & BSDF_LOBE_SPECULAR) || wi.z <= 0.0) return 0;
    s->wo = bsdf_reflect_z(wi);
    s->pdf = 1.0;
    s->weight = v3_mul(albedo, bsdf_fresnel_conductor3(b->eta, b->k, wi.z));
    s->lobe = BSDF_LOBE_SPECULAR;
    return 1;
}
