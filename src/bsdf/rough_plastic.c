/* Rough plastic: a rough dielectric coat (microfacet reflection only, Walter et al. 2007 eq. 20, scaled by
 * Ks) over the coated Lambertian base of plastic.c. GLOSSY + DIFFUSE.
 * The glossy lobe is chosen with probability F(θi) / (F(θi) + avg(albedo)·T̄·(1 − F(θi))),
 * T̄ = exp(−2·thickness·avg(sigma_a)); its normals are drawn with the widened alpha of rough_dielectric.
 * With both lobes selected the sample's pdf is the mixture and its weight f(both)·cos θo / pdf. */
#include "bsdf_internal.h"

static bsdf_rough_boundary coat_of(const bsdf *b, vec3 wi)
{
    bsdf_rough_boundary rb = {
        .dist = b->distribution,
        .alpha = b->alpha,
        .sample_alpha = bsdf_widened_alpha(b, wi.z),
        .ior = b->ior,
        .fresnel_eta = b->ior,
        .reflect = 1,
        .transmit = 0,
    };
    return rb;
}

static double glossy_probability(const bsdf *b, vec3 albedo, vec3 wi)
{
    double Fi = bsdf_fresnel_dielectric(b->ior, wi.z, NULL);
    double substrate = v3_avg(albedo) * exp(-2.0 * b->thickness * v3_avg(b->sigma_a)) * (1.0 - Fi);
    double den = Fi + fmax(substrate, 0.0);
    return den > 0.0 ? Fi / den : 0.5;
}

vec3 bsdf_rough_plastic_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return v3s(0.0);
    vec3 f = v3s(0.0);
    if (lobes & BSDF_LOBE_GLOSSY) {
        bsdf_rough_boundary rb = coat_of(b, wi);
        f = v3s(b->ks * bsdf_rough_boundary_eval(&rb, wi, wo));
    }
    if (lobes & BSDF_LOBE_DIFFUSE) f = v3_add(f, bsdf_plastic_substrate(b, albedo, wi, wo));
    return f;
}

double bsdf_rough_plastic_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    int gl = (lobes & BSDF_LOBE_GLOSSY) != 0, di = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double pg = gl && di ? glossy_probability(b, albedo, wi) : (gl ? 1.0 : 0.0);
    double p = 0.0;
    if (gl) {
        bsdf_rough_boundary rb = coat_of(b, wi);
        p += pg * bsdf_rough_boundary_pdf(&rb, wi, wo);
    }
    if (di) p += (1.0 - pg) * wo.z * DP_INV_PI;
    return p;
}

int bsdf_rough_plastic_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,
                              bsdf_sample *s)
{
    if (wi.z <= 0.0) return 0;
    int gl = (lobes & BSDF_LOBE_GLOSSY) != 0, di = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double pg = gl && di ? glossy_probability(b, albedo, wi) : (gl ? 1.0 : 0.0);
    if (gl && u[2] < pg) {
        bsdf_rough_boundary rb = coat_of(b, wi);
        double f, p;
        if (!bsdf_rough_boundary_sample(&rb, wi, u, &s->wo, &f, &p)) return 0;
        s->lobe = BSDF_LOBE_GLOSSY;
    } else {
        if (!di) return 0;
        s->wo = sample_cosine_hemisphere(u[0], u[1]);
        s->lobe = BSDF_LOBE_DIFFUSE;
    }
    if (s->wo.z <= 0.0) return 0;
    s->pdf = bsdf_rough_plastic_pdf(b, albedo, wi, s->wo, lobes);
    if (!(s->pdf > 0.0)) return 0;
    s->weight = v3_scale(bsdf_rough_plastic_eval(b, albedo, wi, s->wo, lobes), s->wo.z / s->pdf);
    return 1;
}
