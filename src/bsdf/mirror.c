/* Ideal mirror: a delta reflection of weight albedo (no Fresnel term). One SPECULAR lobe; eval and pdf of
 * a delta lobe are 0 for any pair of directions. */
#include "bsdf_internal.h"

vec3 bsdf_mirror_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return v3s(0.0);
}

double bsdf_mirror_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return 0.0;
}

int bsdf_mirror_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    (void)b, (void)u;
    if (!(lobes & BSDF_LOBE_SPECULAR) || wi.z <= 0.0) return 0;
    s->wo = bsdf_reflect_z(wi);
    s->pdf = 1.0;
    s->weight = albedo;
    s->lobe = BSDF_LOBE_SPECULAR;
    return 1;
}
