/* dartspp surface: what every integrator does at a surface hit, in one place — the shading frame and albedo
 * at the hit (two-sided shading, consistency checks), BSDF evaluation and sampling in world space with the
 * adjoint shading-normal correction for light paths, ray origins on the right side, and the photon-points
 * rule that decides, per BSDF, which lobes are gathered from the surface photon map and which the camera
 * path continues through. */
#ifndef DARTSPP_SURFACE_H
#define DARTSPP_SURFACE_H

#include "dartspp/bsdf.h"
#include "dartspp/scene.h"

typedef struct {
    int two_sided;          /* enable_two_sided_shading */
    int consistency_checks; /* enable_consistency_checks */
    double glossy_gather_alpha; /* photon points: glossy lobes with α below this are continued, not gathered */
} surface_shading;

typedef struct {
    const bsdf *b;
    bsdf_frame fr;
    vec3 albedo;   /* texture applied */
    vec3 p;        /* hit point */
    vec3 wi;       /* local direction towards the previous vertex */
    vec3 wi_world; /* the same in world space */
    const surface *sf;
    vec3 ng_hit;   /* the hit's geometric normal as the mesh has it (media sides) */
    int consistency_checks;
} surface_site;

/* The site of hit h for a path arriving along d (propagation). Returns 0 when the path cannot scatter here:
 * it arrives on the back of an opaque surface (no two-sided shading), or on different sides of the shading
 * and geometric normals under consistency checks. */
int surface_site_init(surface_site *ss, const scene *s, const surface_shading *sh, const hit_record *h, vec3 d);

/* f(wi, w) without the cosine, for a world direction w, over the selected lobes (0 where a consistency
 * check fails). */
vec3 surface_eval(const surface_site *ss, vec3 w, unsigned lobes);
/* f(wi, w)·|n_s·w| for a world direction w, over the selected lobes (0 where a consistency check fails). */
vec3 surface_eval_cos(const surface_site *ss, vec3 w, unsigned lobes);

/* The solid-angle density with which surface_sample_bsdf (lobes, camera paths or light paths alike) returns the
 * world direction w: bsdf_pdf over the selected lobes, 0 where a consistency check fails (the sampler fails
 * there). Delta lobes have none: meaningful for the non-delta lobes only. */
double surface_pdf(const surface_site *ss, vec3 w, unsigned lobes);

typedef struct {
    vec3 w;        /* world direction, unit */
    vec3 weight;   /* f·|cos|/pdf, and for light paths the adjoint shading-normal factor */
    unsigned lobe;
} surface_sample;

/* Samples the selected lobes with three uniforms. adjoint: the path carries flux from a light (photon pass),
 * so the weight takes the adjoint of refraction (bsdf_adjoint_scale) and Veach's shading-normal correction
 * |n_s·wi||n_g·wo| / (|n_g·wi||n_s·wo|).
 * Returns 0 when nothing is sampled. */
int surface_sample_bsdf(const surface_site *ss, const double u[3], unsigned lobes, int adjoint, surface_sample *out);

/* Power of a photon stored at the site for flux beta arriving: beta·|n_s·wi| / |n_g·wi| (the density of
 * arrivals is per geometric area; the gather evaluates the BSDF against the shading normal). */
vec3 surface_photon_power(const surface_site *ss, vec3 beta);

/* The region a ray leaving the site along w travels in, for a path that arrived in region `current`. */
static inline int surface_medium_toward(const surface_site *ss, int current, vec3 w)
{
    return surface_next_medium(ss->sf, current, w, ss->ng_hit);
}

/* Origin of a ray leaving the site along w: offset to w's side of the geometric surface. */
vec3 surface_spawn(const scene *s, const surface_site *ss, vec3 w);

/* Photon points, one rule for both passes: `gather` lobes are estimated from surface photons (the photon
 * pass stores a photon wherever gather != 0; the sensor pass evaluates those lobes against them), `cont`
 * lobes are continued by the camera path by sampling them. Diffuse lobes are gathered; delta lobes are
 * continued; a glossy lobe is gathered when the model is opaque and its α >= glossy_gather_alpha, and
 * continued otherwise (near-specular and transmissive lobes make a density estimate blur or leak across
 * the surface). gather | cont = bsdf_lobes(b), gather & cont = 0. */
typedef struct {
    unsigned gather, cont;
} photon_split;
photon_split surface_photon_split(const bsdf *b, const surface_shading *sh);

#endif
