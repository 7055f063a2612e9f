/* rough_dielectric: not implemented yet (stub: no scattering). */
#include "bsdf_internal.h"

vec3 bsdf_rough_dielectric_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return v3s(0.0);
}

double bsdf_rough_dielectric_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return 0.0;
}

int bsdf_rough_dielectric_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    (void)b, (void)albedo, (void)wi, (void)u, (void)lobes, (void)s;
    return 0;
}

double bsdf_widened_alpha(const bsdf *b, double cos_i)
{
    return bsdf_mf_alpha(b->distribution, b->roughness * (1.2 - 0.2 * sqrt(fabs(cos_i))));
}

double bsdf_rough_boundary_eval(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo)
{
    (void)rb, (void)wi, (void)wo;
    return 0.0;
}

double bsdf_rough_boundary_pdf(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo)
{
    (void)rb, (void)wi, (void)wo;
    return 0.0;
}

int bsdf_rough_boundary_sample(const bsdf_rough_boundary *rb, vec3 wi, const double u[3], vec3 *wo, double *value,
                               double *pdf)
{
    (void)rb, (void)wi, (void)u, (void)wo, (void)value, (void)pdf;
    return 0;
}
