/* Smooth plastic: a smooth dielectric coat of index ior over a Lambertian base (the reference's model).
 * - SPECULAR: the coat's delta reflection, weight F(cos θi) (not tinted by albedo).
 * - DIFFUSE: light refracted into the coat, reflected diffusely by the base with inter-reflections under
 *   the coat summed in closed form, and refracted out:
 *     f = (1 − F(θi))(1 − F(θo)) / η² · ρ / (1 − ρ·F̄_int) / π · exp(−τ (1/cos θi + 1/cos θo)),
 *   ρ = albedo, F̄_int = the coat's hemispherical internal reflectance (bsdf.diffuse_fresnel), τ =
 *   thickness·sigma_a. The reference applies no Ks to this model.
 * The specular lobe is chosen with probability F / (F + T̄ (1 − F)), T̄ = exp(−2·thickness·avg(sigma_a)). */
#include "bsdf_internal.h"

vec3 bsdf_plastic_substrate(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return v3s(0.0);
    double Fi = bsdf_fresnel_dielectric(b->ior, wi.z, NULL);
    double Fo = bsdf_fresnel_dielectric(b->ior, wo.z, NULL);
    double c = (1.0 - Fi) * (1.0 - Fo) / (b->ior * b->ior) * DP_INV_PI;
    double f[3];
    for (int i = 0; i < 3; i++) {
        double rho = v3_comp(albedo, i), den = 1.0 - rho * b->diffuse_fresnel;
        double v = den > 1e-12 ? c * rho / den : 0.0;
        double tau = b->thickness * v3_comp(b->sigma_a, i);
        if (tau > 0.0) v *= exp(-tau * (1.0 / wo.z + 1.0 / wi.z));
        f[i] = v;
    }
    return bsdf_clean3(v3(f[0], f[1], f[2]));
}

/* Probability of the specular lobe when both lobes are selected. */
static double specular_probability(const bsdf *b, double Fi)
{
    double t = exp(-2.0 * b->thickness * v3_avg(b->sigma_a));
    double den = Fi + t * (1.0 - Fi);
    return den > 0.0 ? Fi / den : 0.5;
}

vec3 bsdf_plastic_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (!(lobes & BSDF_LOBE_DIFFUSE)) return v3s(0.0);
    return bsdf_plastic_substrate(b, albedo, wi, wo);
}

double bsdf_plastic_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)albedo;
    if (!(lobes & BSDF_LOBE_DIFFUSE) || wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    double p = wo.z * DP_INV_PI;
    if (lobes & BSDF_LOBE_SPECULAR) p *= 1.0 - specular_probability(b, bsdf_fresnel_dielectric(b->ior, wi.z, NULL));
    return p;
}

int bsdf_plastic_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    if (wi.z <= 0.0) return 0;
    double Fi = bsdf_fresnel_dielectric(b->ior, wi.z, NULL);
    int spec = (lobes & BSDF_LOBE_SPECULAR) != 0, diff = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double ps = spec && diff ? specular_probability(b, Fi) : (spec ? 1.0 : 0.0);
    if (spec && u[2] < ps) {
        s->wo = bsdf_reflect_z(wi);
        s->pdf = ps;
        s->weight = v3s(Fi / ps);
        s->lobe = BSDF_LOBE_SPECULAR;
        return Fi > 0.0;
    }
    if (!diff) return 0;
    s->wo = sample_cosine_hemisphere(u[0], u[1]);
    if (s->wo.z <= 0.0) return 0;
    s->pdf = (1.0 - ps) * s->wo.z * DP_INV_PI;
    if (!(s->pdf > 0.0)) return 0;
    s->weight = v3_scale(bsdf_plastic_substrate(b, albedo, wi, s->wo), s->wo.z / s->pdf);
    s->lobe = BSDF_LOBE_DIFFUSE;
    return 1;
}
