/* Rough plastic: a rough dielectric coat (microfacet reflection only, Walter et al. 2007 eq. 20, scaled by
 * Ks) over the coated Lambertian base of plastic.c. GLOSSY + DIFFUSE.
 * The glossy lobe is chosen with probability F(θi) / (F(θi) + avg(albedo)·T̄·(1 − F(θi))),
 * T̄ = exp(−2·thickness·avg(sigma_a)); its normals are drawn with the widened alpha of rough_dielectric.
 * With both lobes selected the sample's pdf is the mixture and its weight f(both)·cos θo / pdf.
 *
 * Energy (our one change to the reference's model): the base is weighted by the smooth coat's 1 − F(θ), but a
 * rough coat reflects R(θ) = Ks·∫ f_coat cos θo dωo, which can exceed F(θ), and then the sum gains energy
 * (0.3 % at beckmann, roughness 0.2, 45°, measured by tests/bsdf/test_bsdf.c). The base term is multiplied by
 * s(μi)·s(μo), s(μ) = min(1, (1 − R(μ)) / (1 − F(μ))): symmetric, 1 wherever the reference conserves energy,
 * and the total at albedo 1 is at most R(μi) + (1 − F(μi))·s(μi) ≤ 1. R is tabulated per BSDF in
 * bsdf_prepare (33 values of μ, 4096 stratified samples of the coat's own sampler each). */
#include "bsdf_internal.h"

/* the coat: the rough dielectric boundary of rough_dielectric.c, reflection only */
static bsdf_rough_boundary coat_of(const bsdf *b, vec3 wi) { return bsdf_rough_boundary_of(b, wi, 0); }

static double glossy_probability(const bsdf *b, vec3 albedo, vec3 wi)
{
    double Fi = bsdf_fresnel_dielectric(b->ior, wi.z, NULL);
    double substrate = v3_avg(albedo) * exp(-2.0 * b->thickness * v3_avg(b->sigma_a)) * (1.0 - Fi);
    double den = Fi + dp_fmax(substrate, 0.0);
    return den > 0.0 ? Fi / den : 0.5;
}

/* R(μ): the coat's directional albedo, Ks·E[f cos θo / pdf] over its sampler (exact in expectation). */
static double coat_albedo(const bsdf *b, double mu)
{
    vec3 wi = v3(sqrt(dp_fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
    bsdf_rough_boundary rb = coat_of(b, wi);
    const int n = 64;
    double sum = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double u[3] = {(i + 0.5) / n, (j + 0.5) / n, 0.5}, f, p;
            vec3 wo;
            if (bsdf_rough_boundary_sample(&rb, wi, u, &wo, &f, &p)) sum += f * wo.z / p;
        }
    return b->ks * sum / (n * n);
}

void bsdf_rough_plastic_prepare(bsdf *b)
{
    for (int k = 0; k <= 32; k++) {
        double mu = dp_fmax(k / 32.0, 1e-3);
        double F = bsdf_fresnel_dielectric(b->ior, mu, NULL), R = coat_albedo(b, mu);
        b->coat_scale[k] = (float)(F < 1.0 ? dp_fmin(1.0, dp_fmax(0.0, 1.0 - R) / (1.0 - F)) : 1.0);
    }
}

static double coat_scale(const bsdf *b, double mu)
{
    double x = dp_fmin(dp_fmax(mu, 0.0), 1.0) * 32.0;
    int k = (int)x;
    if (k >= 32) return b->coat_scale[32];
    double t = x - k;
    return (1.0 - t) * b->coat_scale[k] + t * b->coat_scale[k + 1];
}

vec3 bsdf_rough_plastic_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return v3s(0.0);
    vec3 f = v3s(0.0);
    if (lobes & BSDF_LOBE_GLOSSY) {
        bsdf_rough_boundary rb = coat_of(b, wi);
        f = v3s(b->ks * bsdf_rough_boundary_eval(&rb, wi, wo));
    }
    if (lobes & BSDF_LOBE_DIFFUSE)
        f = v3_add(f, v3_scale(bsdf_plastic_substrate(b, albedo, wi, wo), coat_scale(b, wi.z) * coat_scale(b, wo.z)));
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

int bsdf_coat_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, double pg,
                     const bsdf_rough_boundary *rb, bsdf_eval_fn *eval, bsdf_pdf_fn *pdf, bsdf_sample *s)
{
    if (pg > 0.0 && u[2] < pg) {
        double f, p;
        if (!bsdf_rough_boundary_sample(rb, wi, u, &s->wo, &f, &p)) return 0;
        s->lobe = BSDF_LOBE_GLOSSY;
    } else {
        if (!(lobes & BSDF_LOBE_DIFFUSE)) return 0;
        s->wo = sample_cosine_hemisphere(u[0], u[1]);
        s->lobe = BSDF_LOBE_DIFFUSE;
    }
    if (s->wo.z <= 0.0) return 0;
    s->pdf = pdf(b, albedo, wi, s->wo, lobes);
    if (!(s->pdf > 0.0)) return 0;
    s->weight = v3_scale(eval(b, albedo, wi, s->wo, lobes), s->wo.z / s->pdf);
    return 1;
}

int bsdf_rough_plastic_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,
                              bsdf_sample *s)
{
    if (wi.z <= 0.0) return 0;
    int gl = (lobes & BSDF_LOBE_GLOSSY) != 0, di = (lobes & BSDF_LOBE_DIFFUSE) != 0;
    double pg = gl && di ? glossy_probability(b, albedo, wi) : (gl ? 1.0 : 0.0);
    bsdf_rough_boundary rb = coat_of(b, wi);
    return bsdf_coat_sample(b, albedo, wi, u, lobes, pg, &rb, bsdf_rough_plastic_eval, bsdf_rough_plastic_pdf, s);
}
