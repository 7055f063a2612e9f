/* Lambertian reflection: f = albedo / π, cosine-weighted sampling (weight = albedo). One DIFFUSE lobe. */
#include "bsdf_internal.h"

vec3 bsdf_lambert_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b;
    if (!(lobes & BSDF_LOBE_DIFFUSE) || wi.z <= 0.0 || wo.z <= 0.0) return v3s(0.0);
    return v3_scale(albedo, DP_INV_PI);
}

double bsdf_lambert_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b;
    (void)albedo;
    if (!(lobes & BSDF_LOBE_DIFFUSE) || wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    return wo.z * DP_INV_PI;
}

int bsdf_lambert_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    (void)b;
    if (!(lobes & BSDF_LOBE_DIFFUSE) || wi.z <= 0.0) return 0;
    s->wo = sample_cosine_hemisphere(u[0], u[1]);
    if (s->wo.z <= 0.0) return 0;
    s->pdf = s->wo.z * DP_INV_PI;
    s->weight = albedo;
    s->lobe = BSDF_LOBE_DIFFUSE;
    return 1;
}
