/* Private to src/bsdf: the per-model entry points the dispatch in bsdf.c calls, and the Fresnel and
 * microfacet helpers the models share. Conventions are those of include/dartspp/bsdf.h (local frame,
 * +z = shading normal, wi and wo pointing away from the surface, f without the cosine). */
#ifndef DARTSPP_BSDF_INTERNAL_H
#define DARTSPP_BSDF_INTERNAL_H

#include "dartspp/bsdf.h"

/* ---- one set of entry points per model ----
 * eval: f(wi, wo) over the selected lobes; pdf: the solid-angle density sample draws from (0 for the
 * delta lobes); sample: 1 and *s filled, or 0 when nothing can be sampled. */
#define BSDF_MODEL_DECLARE(model)                                                                        \
    vec3 bsdf_##model##_eval(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);              \
    double bsdf_##model##_pdf(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);             \
    int bsdf_##model##_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes,    \
                              bsdf_sample *s)

BSDF_MODEL_DECLARE(lambert);
BSDF_MODEL_DECLARE(mirror);
BSDF_MODEL_DECLARE(conductor);
BSDF_MODEL_DECLARE(rough_conductor);
BSDF_MODEL_DECLARE(plastic);
BSDF_MODEL_DECLARE(rough_plastic);
BSDF_MODEL_DECLARE(pbrt_plastic);
BSDF_MODEL_DECLARE(dielectric);
BSDF_MODEL_DECLARE(rough_dielectric);

/* ---- Fresnel (fresnel.c) and microfacet distributions (microfacet.c): include/dartspp/bsdf.h ---- */

/* ---- the dielectric microfacet boundary shared by rough_dielectric and the rough coats (rough_dielectric.c) ----
 * A rough boundary of relative index ior (inside / outside) with parameter alpha; sample_alpha is the
 * alpha normals are drawn with (the reference widens it for rough_dielectric and rough_plastic).
 * `reflect` / `transmit` select the two events; with both, the event is picked with probability F / 1−F.
 * `fresnel_eta`: the ratio the Fresnel term is computed with (ior, or 1/ior for pbrt_plastic's inverted
 * index). Values without albedo. */
typedef struct {
    microfacet_distribution dist;
    double alpha, sample_alpha;
    double ior;          /* geometry of refraction: inside / outside */
    double fresnel_eta;  /* the ratio given to bsdf_fresnel_dielectric */
    int reflect, transmit;
} bsdf_rough_boundary;

double bsdf_rough_boundary_eval(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo);
double bsdf_rough_boundary_pdf(const bsdf_rough_boundary *rb, vec3 wi, vec3 wo);
/* Samples wo; *value = f(wi, wo) and *pdf its density. 0 when the sample fails. */
/* The boundary of a rough dielectric or coat b (its distribution, α, ior), sampled with the α widened for
 * wi; transmit 0: reflection only. */
bsdf_rough_boundary bsdf_rough_boundary_of(const bsdf *b, vec3 wi, int transmit);
int bsdf_rough_boundary_sample(const bsdf_rough_boundary *rb, vec3 wi, const double u[3], vec3 *wo, double *value,
                               double *pdf);
/* The alpha normals are sampled with for wi of cos θi: the roughness widened as Walter et al. 2007 §5.3,
 * (1.2 − 0.2·√|cos θi|)·roughness, then mapped to alpha. */
double bsdf_widened_alpha(const bsdf *b, double cos_i);

/* ---- the coated-diffuse base shared by plastic and rough_plastic (plastic.c) ---- */
/* f of the diffuse lobe under a smooth coat (README.md, plastic), 0 unless wi.z > 0 and wo.z > 0. */
vec3 bsdf_plastic_substrate(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo);
/* rough_plastic: the table b->coat_scale (after alpha, ior and ks are set) */
void bsdf_rough_plastic_prepare(bsdf *b);

/* ---- a rough coat over a diffuse base: the sampling shared by rough_plastic and pbrt_plastic (rough_plastic.c) ----
 * The coat rb's reflection with probability pg (the glossy lobe's share when both lobes are asked), else the
 * cosine-weighted diffuse base; the sample's pdf and weight come from the model's own pdf and eval over the
 * lobes asked. For wi.z > 0: 1 and *s filled, or 0 when nothing can be sampled. */
typedef vec3 bsdf_eval_fn(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);
typedef double bsdf_pdf_fn(const bsdf *b, vec3 albedo, vec3 wi, vec3 wo, unsigned lobes);
int bsdf_coat_sample(const bsdf *b, vec3 albedo, vec3 wi, const double u[3], unsigned lobes, double pg,
                     const bsdf_rough_boundary *rb, bsdf_eval_fn *eval, bsdf_pdf_fn *pdf, bsdf_sample *s);

/* ---- small helpers ---- */
static inline vec3 bsdf_reflect_z(vec3 w) { return v3(-w.x, -w.y, w.z); }
/* A value safe to return: finite and non-negative, else 0. */
static inline double bsdf_clean(double x) { return (isfinite(x) && x > 0.0) ? x : 0.0; }
static inline vec3 bsdf_clean3(vec3 v) { return v3(bsdf_clean(v.x), bsdf_clean(v.y), bsdf_clean(v.z)); }

#endif
