/* rough_plastic: not implemented yet (stub: no scattering). */
#include "bsdf_internal.h"

vec3 bsdf_rough_plastic_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return v3s(0.0);
}

double bsdf_rough_plastic_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return 0.0;
}

int bsdf_rough_plastic_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    (void)b, (void)albedo, (void)wi, (void)u, (void)lobes, (void)s;
    return 0;
}
