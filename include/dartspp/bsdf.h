/* dartspp bsdf: surface scattering models, one file per model in src/bsdf/, each with eval, sample and pdf.
 *
 * Conventions (every function below):
 * - Directions are unit vectors in the local shading frame (+z = shading normal) and both point AWAY from
 *   the surface: wi towards the previous vertex of the path being traced (the camera side for camera paths,
 *   the light side for light paths), wo the other direction (sampled, or towards the light/photon).
 * - f(wi, wo) is returned WITHOUT the cosine. Sampling weights are f·|cos θo| / pdf (lobe choice included).
 * - Camera paths transport radiance divided by η² ("basic radiance", Veach 1997 §5.2): reflection is
 *   symmetric, f(wi, wo) = f(wo, wi), and a refraction's sampling weight is 1 − F from either side (as the
 *   reference renderer, a Tungsten fork). Transmission then obeys f(wi, wo)/η_o² = f(wo, wi)/η_i², so light
 *   paths (the adjoint) multiply a transmitted sample's weight by bsdf_adjoint_scale. The reference omits
 *   that factor: its photons inside a dielectric carry the wrong power (they cancel on paths that leave it).
 * - z < 0 is the surface's back (inside of a dielectric). Opaque models return 0 unless wi.z > 0 and
 *   wo.z > 0; the caller flips the frame for two-sided shading (bsdf_frame_init).
 * - `albedo` is the BSDF's albedo at the hit point (its texture applied, else bsdf.albedo).
 * - `lobes` selects lobes (BSDF_LOBE_* bits): eval and pdf cover the selected lobes only; sample picks among
 *   the selected lobes only, with pdf and weight of that restricted technique. BSDF_LOBES_ALL: the full BSDF. */
#ifndef DARTSPP_BSDF_H
#define DARTSPP_BSDF_H

#include "dartspp/core.h"

typedef enum {
    BSDF_LAMBERT,
    BSDF_MIRROR,
    BSDF_NULL,
    BSDF_FORWARD,
    BSDF_CONDUCTOR,
    BSDF_ROUGH_CONDUCTOR,
    BSDF_PLASTIC,
    BSDF_ROUGH_PLASTIC,
    BSDF_PBRT_PLASTIC,
    BSDF_DIELECTRIC,
    BSDF_ROUGH_DIELECTRIC,
    BSDF_TYPE_COUNT
} bsdf_type;

typedef enum { MICROFACET_GGX, MICROFACET_PBRT_GGX, MICROFACET_BECKMANN } microfacet_distribution;

/* lobes */
#define BSDF_LOBE_DIFFUSE 1u   /* Lambertian-like, never near-specular */
#define BSDF_LOBE_GLOSSY 2u    /* microfacet lobe (reflection, and transmission for rough_dielectric) */
#define BSDF_LOBE_SPECULAR 4u  /* delta lobes: mirror reflection, smooth refraction */
#define BSDF_LOBES_ALL 7u

typedef struct {
    bsdf_type type;
    char name[64];
    vec3 albedo;               /* constant albedo; the fallback when a texture file is missing */
    int texture;               /* albedo texture: index into scene.textures, -1 none */
    /* microfacet models (rough_*, pbrt_plastic) */
    microfacet_distribution distribution;
    double roughness;          /* as written in the scene */
    double alpha;              /* distribution parameter, from roughness by bsdf_prepare */
    /* conductors: complex index n + ik relative to the outside, per RGB channel */
    vec3 eta, k;
    /* dielectrics and plastics */
    double ior;                /* interior / exterior */
    int enable_refraction;     /* dielectrics: 0 = the transmitted share is absorbed */
    double thickness;          /* plastics: coat thickness (with sigma_a) */
    vec3 sigma_a;              /* plastics: coat absorption per unit thickness */
    double ks;                 /* pbrt_plastic: specular scale `Ks`; plastics: 1 unless given */
    /* derived by bsdf_prepare */
    double diffuse_fresnel;    /* plastics: hemispherical average of the coat's internal Fresnel */
    float coat_scale[33];      /* rough_plastic: s(μ) at μ = k/32, the base's share kept below a rough coat
                                * (1 − R_coat(μ)) / (1 − F(μ)), at most 1 (see rough_plastic.c) */
} bsdf;

/* b with its microfacet α raised to at least alpha_min, for the models whose lobes depend on nothing else
 * derived from it (rough_conductor, pbrt_plastic); other models come back unchanged. The sensor pass's path
 * regularization (docs/defaults.md §3.7). */
bsdf bsdf_regularized(const bsdf *b, double alpha_min);

/* A bsdf with the defaults of its type (the reference's defaults, documented in src/bsdf/README.md). */
void bsdf_defaults(bsdf *b, bsdf_type type);
/* Derives alpha and the cached terms from the parameters; checks ranges. 0, or -1 + err naming b->name. */
int bsdf_prepare(bsdf *b, dp_error *err);
/* Type from the scene-file name ("rough_conductor", ...); -1 if unknown. */
int bsdf_type_from_name(const char *name);
const char *bsdf_type_name(bsdf_type t);
/* Complex index of a named metal (Ag, Au, Al, Cu, Cr, Li, VN, ...); 0 if unknown. Table: src/bsdf/complex_ior.c. */
int bsdf_conductor_preset(const char *material, vec3 *eta, vec3 *k);

/* Which lobes the model has (a subset of BSDF_LOBES_ALL); 0 for null and forward. */
unsigned bsdf_lobes(const bsdf *b);
/* Whether the model transmits light to the back side (dielectrics with refraction, rough_dielectric). */
int bsdf_transmits(const bsdf *b);
/* null and forward surfaces are crossed as if absent (index-matched boundaries, invisible lights) */
static inline int bsdf_is_passthrough(const bsdf *b) { return b->type == BSDF_NULL || b->type == BSDF_FORWARD; }

vec3 bsdf_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);
double bsdf_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);

typedef struct {
    vec3 wo;        /* local, unit */
    vec3 weight;    /* f·|cos θo| / pdf, lobe choice included (delta lobes: the lobe's weight) */
    double pdf;     /* solid-angle pdf (non-delta), or the discrete probability of the delta outcome */
    unsigned lobe;  /* the single BSDF_LOBE_* bit sampled */
} bsdf_sample;

/* (η_i/η_o)² for a transmission through a dielectric (wi and wo on opposite sides; η of each side: 1 on +z,
 * ior on −z), else 1: the factor that turns a sampled weight into the adjoint's, for light paths. */
double bsdf_adjoint_scale(const bsdf *b, vec3 wi, vec3 wo);

/* Samples wo given wi with three uniforms in [0,1). Returns 0 when nothing can be sampled (below the
 * surface, no selected lobe, a failed microfacet sample): the path ends. */
int bsdf_sample_wo(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, bsdf_sample *s);

/* ---- the building blocks of the models: Fresnel terms (src/bsdf/fresnel.c) and microfacet distributions
 * (src/bsdf/microfacet.c). Public for the closed-form tests (tests/bsdf/test_bsdf_models.c) and for code
 * outside src/bsdf that needs a Fresnel or microfacet term; the models use them through bsdf_eval etc. ---- */
/* Unpolarised reflectance of a smooth boundary between two dielectrics. eta = η(back) / η(front), the
 * index behind the boundary (z < 0) over the index in front; cos_i = cos θ of the incident direction
 * against +z, either sign (cos_i < 0: arriving from the back, the ratio is inverted). Writes |cos θt|
 * (0 under total internal reflection, where 1 is returned) when cos_t is not NULL. */
double bsdf_fresnel_dielectric(double eta, double cos_i, double *cos_t);
/* Reflectance of a conductor of complex index eta + i k (relative to the outside), for |cos_i|. */
double bsdf_fresnel_conductor(double eta, double k, double cos_i);
vec3 bsdf_fresnel_conductor3(vec3 eta, vec3 k, double cos_i);
/* Cosine-weighted hemispherical average 2∫ F(μ) μ dμ of bsdf_fresnel_dielectric(eta, μ) over μ in (0, 1]. */
double bsdf_fresnel_average(double eta);

/* Microfacet distributions: isotropic, about +z, parameter alpha (bsdf.alpha). Normals are sampled from
 * D(m)·cos θm (the full distribution, as the reference); bsdf_mf_pdf is that density of m. */
double bsdf_mf_alpha(microfacet_distribution d, double roughness);
double bsdf_mf_D(microfacet_distribution d, double alpha, vec3 m);
/* Smith masking of direction v for microfacet normal m (0 when v is on the wrong side of m or of +z). */
double bsdf_mf_G1(microfacet_distribution d, double alpha, vec3 v, vec3 m);
/* Shadowing-masking for the pair: the separable product G1·G1 (ggx, beckmann) or the height-correlated
 * 1 / (1 + Λ(wi) + Λ(wo)) (pbrt-ggx). */
double bsdf_mf_G(microfacet_distribution d, double alpha, vec3 wi, vec3 wo, vec3 m);
vec3 bsdf_mf_sample(microfacet_distribution d, double alpha, double u1, double u2);
double bsdf_mf_pdf(microfacet_distribution d, double alpha, vec3 m);

/* ---- the shading frame at a hit (world ↔ local) ---- */
typedef struct {
    vec3 s, t, n;   /* n: shading normal, flipped to the arriving side for two-sided shading */
    vec3 ng;        /* geometric normal, flipped with n */
} bsdf_frame;

/* Frame at a hit with geometric normal ng and shading normal ns (both unit, ns on ng's side), for a path
 * arriving along direction d (propagation). With two_sided and an opaque model, n and ng are flipped to
 * face the arriving path. */
void bsdf_frame_init(bsdf_frame *f, const bsdf *b, vec3 ng, vec3 ns, vec3 d, int two_sided);
static inline vec3 bsdf_to_local(const bsdf_frame *f, vec3 w)
{
    return v3(v3_dot(w, f->s), v3_dot(w, f->t), v3_dot(w, f->n));
}
static inline vec3 bsdf_to_world(const bsdf_frame *f, vec3 l)
{
    return v3_add(v3_add(v3_scale(f->s, l.x), v3_scale(f->t, l.y)), v3_scale(f->n, l.z));
}

#endif
