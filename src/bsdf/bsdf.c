/* The bsdf module's front: defaults, parameter checks, names, lobes, the shading frame, and the dispatch of
 * eval / pdf / sample to the model files. */
#include <string.h>

#include "bsdf_internal.h"

static const char *const type_names[BSDF_TYPE_COUNT] = {
    [BSDF_LAMBERT] = "lambert",
    [BSDF_MIRROR] = "mirror",
    [BSDF_NULL] = "null",
    [BSDF_FORWARD] = "forward",
    [BSDF_CONDUCTOR] = "conductor",
    [BSDF_ROUGH_CONDUCTOR] = "rough_conductor",
    [BSDF_PLASTIC] = "plastic",
    [BSDF_ROUGH_PLASTIC] = "rough_plastic",
    [BSDF_PBRT_PLASTIC] = "pbrt_plastic",
    [BSDF_DIELECTRIC] = "dielectric",
    [BSDF_ROUGH_DIELECTRIC] = "rough_dielectric",
};

int bsdf_type_from_name(const char *name)
{
    if (!name) return -1;
    for (int t = 0; t < BSDF_TYPE_COUNT; t++)
        if (strcmp(name, type_names[t]) == 0) return t;
    return -1;
}

const char *bsdf_type_name(bsdf_type t)
{
    return (t >= 0 && t < BSDF_TYPE_COUNT) ? type_names[t] : "unknown";
}

/* The reference's defaults (src/bsdf/README.md lists them per model). */
void bsdf_defaults(bsdf *b, bsdf_type type)
{
    memset(b, 0, sizeof *b);
    b->type = type;
    b->albedo = v3s(1.0);
    b->texture = -1;
    b->distribution = MICROFACET_GGX;
    b->roughness = 0.0;
    b->ior = 1.5;
    b->enable_refraction = 1;
    b->thickness = 1.0;
    b->sigma_a = v3s(0.0);
    b->ks = 1.0;
    bsdf_conductor_preset("Cu", &b->eta, &b->k);
    switch (type) {
    case BSDF_ROUGH_CONDUCTOR:
    case BSDF_ROUGH_DIELECTRIC:
        b->roughness = 0.1;
        break;
    case BSDF_ROUGH_PLASTIC:
        b->roughness = 0.02;
        break;
    case BSDF_PBRT_PLASTIC:
        b->distribution = MICROFACET_PBRT_GGX;
        b->roughness = 0.1;
        b->ks = 0.25;
        break;
    default:
        break;
    }
    b->alpha = bsdf_mf_alpha(b->distribution, b->roughness);
}

static int finite3(vec3 v) { return v3_is_finite(v); }
static int nonneg3(vec3 v) { return v3_is_finite(v) && v.x >= 0.0 && v.y >= 0.0 && v.z >= 0.0; }

static int is_microfacet(bsdf_type t)
{
    return t == BSDF_ROUGH_CONDUCTOR || t == BSDF_ROUGH_PLASTIC || t == BSDF_PBRT_PLASTIC ||
           t == BSDF_ROUGH_DIELECTRIC;
}

bsdf bsdf_regularized(const bsdf *b, double alpha_min)
{
    bsdf r = *b;
    if ((b->type == BSDF_ROUGH_CONDUCTOR || b->type == BSDF_PBRT_PLASTIC) && b->alpha < alpha_min) r.alpha = alpha_min;
    return r;
}

static int has_ior(bsdf_type t)
{
    return t == BSDF_PLASTIC || t == BSDF_ROUGH_PLASTIC || t == BSDF_PBRT_PLASTIC || t == BSDF_DIELECTRIC ||
           t == BSDF_ROUGH_DIELECTRIC;
}

int bsdf_prepare(bsdf *b, dp_error *err)
{
    const char *name = b->name[0] ? b->name : bsdf_type_name(b->type);
    const char *type = bsdf_type_name(b->type);
    if (b->type < 0 || b->type >= BSDF_TYPE_COUNT)
        return dp_fail(err, "bsdf \"%s\": unknown type %d", name, (int)b->type);
    if (!nonneg3(b->albedo))
        return dp_fail(err, "bsdf \"%s\" (%s): albedo (%g, %g, %g) must be finite and non-negative", name, type,
                       b->albedo.x, b->albedo.y, b->albedo.z);
    if (is_microfacet(b->type)) {
        if ((int)b->distribution < MICROFACET_GGX || (int)b->distribution > MICROFACET_BECKMANN)
            return dp_fail(err, "bsdf \"%s\" (%s): unknown microfacet distribution %d", name, type,
                           (int)b->distribution);
        if (!isfinite(b->roughness) || b->roughness < 0.0)
            return dp_fail(err, "bsdf \"%s\" (%s): roughness %g must be finite and non-negative", name, type,
                           b->roughness);
        b->alpha = bsdf_mf_alpha(b->distribution, b->roughness);
    }
    if (b->type == BSDF_CONDUCTOR || b->type == BSDF_ROUGH_CONDUCTOR) {
        /* the shipped table holds a few slightly negative entries (fits to measured data); only η² and
         * k² enter the Fresnel term, so the sign is not checked */
        if (!finite3(b->eta) || !finite3(b->k))
            return dp_fail(err, "bsdf \"%s\" (%s): complex index eta/k must be finite", name, type);
    }
    if (has_ior(b->type) && (!isfinite(b->ior) || b->ior <= 0.0))
        return dp_fail(err, "bsdf \"%s\" (%s): ior %g must be finite and positive", name, type, b->ior);
    if (b->type == BSDF_PLASTIC || b->type == BSDF_ROUGH_PLASTIC) {
        if (!isfinite(b->thickness) || b->thickness < 0.0)
            return dp_fail(err, "bsdf \"%s\" (%s): thickness %g must be finite and non-negative", name, type,
                           b->thickness);
        if (!nonneg3(b->sigma_a))
            return dp_fail(err, "bsdf \"%s\" (%s): sigma_a must be finite and non-negative", name, type);
        /* light leaving the coat from inside: index ratio outside / inside = 1/ior */
        b->diffuse_fresnel = bsdf_fresnel_average(1.0 / b->ior);
    }
    if ((b->type == BSDF_ROUGH_PLASTIC || b->type == BSDF_PBRT_PLASTIC) && (!isfinite(b->ks) || b->ks < 0.0))
        return dp_fail(err, "bsdf \"%s\" (%s): Ks %g must be finite and non-negative", name, type, b->ks);
    if (b->type == BSDF_ROUGH_PLASTIC) bsdf_rough_plastic_prepare(b);
    return 0;
}

unsigned bsdf_lobes(const bsdf *b)
{
    switch (b->type) {
    case BSDF_LAMBERT: return BSDF_LOBE_DIFFUSE;
    case BSDF_MIRROR:
    case BSDF_CONDUCTOR:
    case BSDF_DIELECTRIC: return BSDF_LOBE_SPECULAR;
    case BSDF_ROUGH_CONDUCTOR:
    case BSDF_ROUGH_DIELECTRIC: return BSDF_LOBE_GLOSSY;
    case BSDF_PLASTIC: return BSDF_LOBE_SPECULAR | BSDF_LOBE_DIFFUSE;
    case BSDF_ROUGH_PLASTIC:
    case BSDF_PBRT_PLASTIC: return BSDF_LOBE_GLOSSY | BSDF_LOBE_DIFFUSE;
    default: return 0u;
    }
}

int bsdf_transmits(const bsdf *b)
{
    return (b->type == BSDF_DIELECTRIC || b->type == BSDF_ROUGH_DIELECTRIC) && b->enable_refraction;
}

double bsdf_adjoint_scale(const bsdf *b, vec3 wi, vec3 wo)
{
    if (!bsdf_transmits(b) || wi.z * wo.z >= 0.0) return 1.0;
    double eta_i = wi.z > 0.0 ? 1.0 : b->ior, eta_o = wo.z > 0.0 ? 1.0 : b->ior;
    return (eta_i / eta_o) * (eta_i / eta_o); /* Veach 1997 §5.2: f(wi→wo)/η_o² = f(wo→wi)/η_i² */
}

vec3 bsdf_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    lobes &= bsdf_lobes(b);
    if (!lobes) return v3s(0.0);
    vec3 f;
    switch (b->type) {
    case BSDF_LAMBERT: f = bsdf_lambert_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_MIRROR: f = bsdf_mirror_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_CONDUCTOR: f = bsdf_conductor_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_CONDUCTOR: f = bsdf_rough_conductor_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_PLASTIC: f = bsdf_plastic_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_PLASTIC: f = bsdf_rough_plastic_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_PBRT_PLASTIC: f = bsdf_pbrt_plastic_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_DIELECTRIC: f = bsdf_dielectric_eval(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_DIELECTRIC: f = bsdf_rough_dielectric_eval(b, albedo, wi, wo, lobes); break;
    default: return v3s(0.0);
    }
    return bsdf_clean3(f);
}

double bsdf_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes)
{
    lobes &= bsdf_lobes(b);
    if (!lobes) return 0.0;
    double p;
    switch (b->type) {
    case BSDF_LAMBERT: p = bsdf_lambert_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_MIRROR: p = bsdf_mirror_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_CONDUCTOR: p = bsdf_conductor_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_CONDUCTOR: p = bsdf_rough_conductor_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_PLASTIC: p = bsdf_plastic_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_PLASTIC: p = bsdf_rough_plastic_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_PBRT_PLASTIC: p = bsdf_pbrt_plastic_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_DIELECTRIC: p = bsdf_dielectric_pdf(b, albedo, wi, wo, lobes); break;
    case BSDF_ROUGH_DIELECTRIC: p = bsdf_rough_dielectric_pdf(b, albedo, wi, wo, lobes); break;
    default: return 0.0;
    }
    return bsdf_clean(p);
}

int bsdf_sample_wo(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s)
{
    lobes &= bsdf_lobes(b);
    if (!lobes) return 0;
    int ok;
    switch (b->type) {
    case BSDF_LAMBERT: ok = bsdf_lambert_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_MIRROR: ok = bsdf_mirror_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_CONDUCTOR: ok = bsdf_conductor_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_ROUGH_CONDUCTOR: ok = bsdf_rough_conductor_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_PLASTIC: ok = bsdf_plastic_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_ROUGH_PLASTIC: ok = bsdf_rough_plastic_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_PBRT_PLASTIC: ok = bsdf_pbrt_plastic_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_DIELECTRIC: ok = bsdf_dielectric_sample(b, albedo, wi, u, lobes, s); break;
    case BSDF_ROUGH_DIELECTRIC: ok = bsdf_rough_dielectric_sample(b, albedo, wi, u, lobes, s); break;
    default: return 0;
    }
    /* a sample that cannot carry light (zero or non-finite weight or pdf) ends the path */
    if (!ok || !(s->pdf > 0.0) || !isfinite(s->pdf) || !v3_is_finite(s->weight) || !v3_is_finite(s->wo)) return 0;
    s->weight = bsdf_clean3(s->weight);
    return 1;
}

void bsdf_frame_init(bsdf_frame *f, const bsdf *b, vec3 ng, vec3 ns, vec3 d, int two_sided)
{
    f->n = ns;
    f->ng = ng;
    if (two_sided && !bsdf_transmits(b) && v3_dot(d, ng) > 0.0) {
        f->n = v3_neg(ns);
        f->ng = v3_neg(ng);
    }
    v3_basis(f->n, &f->s, &f->t);
}
