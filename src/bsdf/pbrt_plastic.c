/* pbrt_plastic: the DARTS authors' port of pbrt-v3's PlasticMaterial, to match their pbrt-v3 scenes.
 * - GLOSSY: microfacet reflection (Walter et al. 2007 eq. 20) scaled by Ks (default 0.25), not tinted by
 *   albedo. The Fresnel term is pbrt-v3's FresnelDielectric(1.5, 1) reading: computed with the index ratio
 *   inverted, as if light arrived from inside a medium of index ior, so it reaches 1 (total internal
 *   reflection) beyond sin θ = 1/ior. Distribution default pbrt-ggx (GGX D, height-correlated Smith G),
 *   normals drawn with the unwidened alpha; normals facing away from wi are rejected.
 * - DIFFUSE: Lambertian albedo/π, no Fresnel weighting (pbrt-v3's kd term).
 * Each selected lobe is chosen with probability 1/2. */
#include "bsdf_internal.h"

static bsdf_rough_boundary coat_of(const bsdf *b)
{
    bsdf_rough_boundary rb = {
        .dist = b->distribution,
        .alpha = b->alpha,
        .sample_alpha = b->alpha,
        .ior = b->ior,
        .fresnel_eta = 1.0 / b->ior,
        .reflect = 1,
        .transmit = 0,
    };
    return rb;
}

vec3 bsdf_pbrt_plastic_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return v3s(0.0);
    vec3 f = v3s(0.0);
    if (lobes & BSDF_LOBE_GLOSSY) {
        bsdf_rough_boundary rb = coat_of(b);
        f = v3s(b->ks * bsdf_rough_boundary_eval(&rb, wi, wo));
    }
    if (lobes & BSDF_LOBE_DIFFUSE) f = v3_add(f, v3_scale(albedo, DP_INV_PI));
    return f;
}

double bsdf_pbrt_plastic_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)albedo;
    if (wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    int gl = (lobes & BSDF_LOBE_GLOSSY) != 0, di = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double p = 0.0;
    if (gl) {
        bsdf_rough_boundary rb = coat_of(b);
        p += bsdf_rough_boundary_pdf(&rb, wi, wo);
    }
    if (di) p += wo.z * DP_INV_PI;
    return gl + di ? p / (gl + di) : 0.0;
}

int bsdf_pbrt_plastic_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,
                             bsdf_sample *s)
{
    if (wi.z <= 0.0) return 0;
    int gl = (lobes & BSDF_LOBE_GLOSSY) != 0, di = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double pg = gl && di ? 0.5 : (gl ? 1.0 : 0.0);
    bsdf_rough_boundary rb = coat_of(b);
    return bsdf_coat_sample(b, albedo, wi, u, lobes, pg, &rb, bsdf_pbrt_plastic_eval, bsdf_pbrt_plastic_pdf, s);
}
