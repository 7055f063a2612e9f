/* Smooth dielectric boundary of relative index ior (inside / outside): a delta reflection and a delta
 * refraction, picked with probability F and 1 − F (Fresnel of the side wi is on), both of weight albedo.
 * One SPECULAR lobe holding both. With enable_refraction off the boundary only reflects, with weight
 * albedo·F: the transmitted share is lost (as the reference). Works from either side (wi.z < 0: inside). */
#include "bsdf_internal.h"

vec3 bsdf_dielectric_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return v3s(0.0);
}

double bsdf_dielectric_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)b, (void)albedo, (void)wi, (void)wo, (void)lobes;
    return 0.0;
}

int bsdf_dielectric_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    if (!(lobes & BSDF_LOBE_SPECULAR) || wi.z == 0.0) return 0;
    double cos_t;
    double F = bsdf_fresnel_dielectric(b->ior, wi.z, &cos_t);
    s->lobe = BSDF_LOBE_SPECULAR;
    if (!b->enable_refraction) {
        s->wo = bsdf_reflect_z(wi);
        s->pdf = 1.0;
        s->weight = v3_scale(albedo, F);
        return F > 0.0;
    }
    if (u[0] < F) {
        s->wo = bsdf_reflect_z(wi);
        s->pdf = F;
        s->weight = albedo;
        return 1;
    }
    if (F >= 1.0) return 0;
    /* Snell: the tangential part scales by η_i / η_t, the normal part is cos θt on the far side */
    double eta_r = wi.z > 0.0 ? 1.0 / b->ior : b->ior;
    s->wo = v3_norm(v3(-eta_r * wi.x, -eta_r * wi.y, -copysign(cos_t, wi.z)));
    s->pdf = 1.0 - F;
    s->weight = albedo;
    return 1;
}
