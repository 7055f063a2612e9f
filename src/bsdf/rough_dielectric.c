/* Rough dielectric boundary (Walter, Marschner, Li, Torrance 2007, "Microfacet Models for Refraction
 * through Rough Surfaces"; equation numbers below are theirs): microfacet reflection and transmission as one
 * GLOSSY lobe, the event picked with probability F / 1 − F. Also the reflection-only coat of rough_plastic
 * and pbrt_plastic (bsdf_rough_boundary_*).
 *
 * The transmission term is eq. 21 as written, with η_o² in the numerator: its sampling weight tends to 1 as
 * the roughness goes to 0, matching the smooth dielectric (camera paths carry radiance / η²); light paths
 * take the adjoint through bsdf_adjoint_scale (see bsdf.h and README.md). */
#include "bsdf_internal.h"

double bsdf_widened_alpha(const bsdf *b, double cos_i)
{
    return bsdf_mf_alpha(b->distribution, b->roughness * (1.2 - 0.2 * sqrt(fabs(cos_i))));
}

/* η_o / η_i: the index on the far side of the boundary over the index on wi's side. */
static double eta_across(const bsdf_rough_boundary *rb, vec3 wi) { return wi.z > 0.0 ? rb->ior : 1.0 / rb->ior; }

/* The half vector of a pair, +z side, and whether the pair is a reflection; 0 when there is none. */
static int half_vector(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo, vec3 *h, int *reflect)
{
    if (wi.z == 0.0 || wo.z == 0.0) return 0;
    *reflect = wi.z * wo.z > 0.0;
    vec3 v;
    if (*reflect) {
        v = v3_add(wi, wo); /* eq. 13, signed below */
        if (wi.z < 0.0) v = v3_neg(v);
    } else {
        v = v3_neg(v3_add(wi, v3_scale(wo, eta_across(rb, wi)))); /* eq. 16, divided by η_i */
        if (v.z < 0.0) v = v3_neg(v); /* it points to the denser side: towards −z when ior < 1 */
    }
    double l = v3_len(v);
    if (!(l > 1e-12)) return 0;
    *h = v3_scale(v, 1.0 / l);
    return h->z > 0.0;
}

double bsdf_rough_boundary_eval(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo)
{
    vec3 h;
    int reflect;
    if (!half_vector(rb, wi, wo, &h, &reflect)) return 0.0;
    if (reflect ? !rb->reflect : !rb->transmit) return 0.0;
    double ih = v3_dot(wi, h), oh = v3_dot(wo, h);
    double D = bsdf_mf_D(rb->dist, rb->alpha, h);
    double G = bsdf_mf_G(rb->dist, rb->alpha, wi, wo, h);
    if (D == 0.0 || G == 0.0) return 0.0;
    double F = bsdf_fresnel_dielectric(rb->fresnel_eta, ih, NULL);
    double cos_io = fabs(wi.z * wo.z);
    if (reflect) return bsdf_clean(F * G * D / (4.0 * cos_io)); /* eq. 20 */
    double eta = eta_across(rb, wi);
    double den = ih + eta * oh;
    /* eq. 21 */
    return bsdf_clean(fabs(ih * oh) * eta * eta * (1.0 - F) * G * D / (cos_io * den * den));
}

double bsdf_rough_boundary_pdf(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo)
{
    vec3 h;
    int reflect;
    if (!half_vector(rb, wi, wo, &h, &reflect)) return 0.0;
    if (reflect ? !rb->reflect : !rb->transmit) return 0.0;
    double ih = v3_dot(wi, h), oh = v3_dot(wo, h);
    /* only normals on wi's side of the boundary are kept by the sampler */
    if (ih * wi.z <= 0.0 || oh * wo.z <= 0.0) return 0.0;
    double pm = bsdf_mf_pdf(rb->dist, rb->sample_alpha, h);
    double p;
    if (reflect) {
        p = pm / (4.0 * fabs(ih)); /* eq. 14 */
    } else {
        double eta = eta_across(rb, wi), den = ih + eta * oh;
        p = pm * eta * eta * fabs(oh) / (den * den); /* eq. 17 */
    }
    if (rb->reflect && rb->transmit) {
        double F = bsdf_fresnel_dielectric(rb->fresnel_eta, ih, NULL);
        p *= reflect ? F : 1.0 - F;
    }
    return bsdf_clean(p);
}

int bsdf_rough_boundary_sample(const bsdf_rough_boundary *rb, vec3 wi, const double u[3], vec3 *wo, double *value,
                               double *pdf)
{
    if (wi.z == 0.0 || !(rb->reflect || rb->transmit)) return 0;
    vec3 m = bsdf_mf_sample(rb->dist, rb->sample_alpha, u[0], u[1]);
    if (!(bsdf_mf_pdf(rb->dist, rb->sample_alpha, m) > 1e-12)) return 0;
    double c = v3_dot(wi, m);
    if (c * wi.z <= 0.0) return 0; /* a back-facing normal: masked, G = 0 */
    double F = bsdf_fresnel_dielectric(rb->fresnel_eta, c, NULL);
    int reflect;
    if (rb->reflect && rb->transmit)
        reflect = u[2] < F;
    else if (rb->transmit) {
        if (F >= 1.0) return 0;
        reflect = 0;
    } else
        reflect = 1;
    if (reflect) {
        *wo = v3_sub(v3_scale(m, 2.0 * c), wi); /* eq. 39 */
        if (wo->z * wi.z <= 0.0) return 0;
    } else {
        double eta_r = 1.0 / eta_across(rb, wi); /* η_i / η_o */
        double sin_t2 = eta_r * eta_r * (1.0 - c * c);
        if (sin_t2 >= 1.0) return 0;
        double cos_t = sqrt(1.0 - sin_t2);
        /* eq. 40 */
        *wo = v3_sub(v3_scale(m, eta_r * c - copysign(cos_t, c)), v3_scale(wi, eta_r));
        *wo = v3_norm(*wo);
        if (wo->z * wi.z >= 0.0) return 0;
    }
    /* value and density from the pair itself, so that they are exactly what eval and pdf return */
    *value = bsdf_rough_boundary_eval(rb, wi, *wo);
    *pdf = bsdf_rough_boundary_pdf(rb, wi, *wo);
    return *pdf > 0.0 && *value > 0.0;
}

bsdf_rough_boundary bsdf_rough_boundary_of(const bsdf *b, vec3 wi, int transmit)
{
    bsdf_rough_boundary rb = {
        .dist = b->distribution,
        .alpha = b->alpha,
        .sample_alpha = bsdf_widened_alpha(b, wi.z),
        .ior = b->ior,
        .fresnel_eta = b->ior,
        .reflect = 1,
        .transmit = transmit,
    };
    return rb;
}

static bsdf_rough_boundary boundary_of(const bsdf *b, vec3 wi)
{
    return bsdf_rough_boundary_of(b, wi, b->enable_refraction);
}

vec3 bsdf_rough_dielectric_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    if (!(lobes & BSDF_LOBE_GLOSSY)) return v3s(0.0);
    bsdf_rough_boundary rb = boundary_of(b, wi);
    return v3_scale(albedo, bsdf_rough_boundary_eval(&rb, wi, wo));
}

double bsdf_rough_dielectric_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    (void)albedo;
    if (!(lobes & BSDF_LOBE_GLOSSY)) return 0.0;
    bsdf_rough_boundary rb = boundary_of(b, wi);
    return bsdf_rough_boundary_pdf(&rb, wi, wo);
}

int bsdf_rough_dielectric_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,
                                 bsdf_sample *s)
{
    if (!(lobes & BSDF_LOBE_GLOSSY)) return 0;
    bsdf_rough_boundary rb = boundary_of(b, wi);
    double f, p;
    if (!bsdf_rough_boundary_sample(&rb, wi, u, &s->wo, &f, &p)) return 0;
    s->pdf = p;
    s->weight = v3_scale(albedo, f * fabs(s->wo.z) / p);
    s->lobe = BSDF_LOBE_GLOSSY;
    return 1;
}
