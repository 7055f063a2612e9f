/* The surface interaction shared by the path tracer, the photon pass and the sensor pass. */
#include "dartspp/surface_site.h"

/* Geometric and shading normals agree on the side of w (consistency checks), or no check is asked. */
static int consistent(const surface_site *ss, vec3 w)
{
    if (!ss->consistency_checks) return 1;
    return v3_dot(w, ss->fr.ng) * v3_dot(w, ss->fr.n) > 0.0;
}

int surface_site_init(surface_site *ss, const scene *s, const surface_shading *sh, const hit_record *h, vec3 d)
{
    const bsdf *b = &s->bsdfs[s->surfaces[h->surface].bsdf];
    ss->b = b;
    ss->sf = &s->surfaces[h->surface];
    ss->ng_hit = h->ng;
    ss->p = h->p;
    ss->albedo = scene_albedo(s, b, h);
    ss->consistency_checks = sh->consistency_checks;
    bsdf_frame_init(&ss->fr, b, h->ng, h->ns, d, sh->two_sided);
    ss->wi_world = v3_neg(d);
    ss->wi = bsdf_to_local(&ss->fr, ss->wi_world);
    if (!consistent(ss, ss->wi_world)) return 0;
    return bsdf_transmits(b) || ss->wi.z > 0.0;
}

vec3 surface_eval(const surface_site *ss, vec3 w, unsigned lobes)
{
    if (!consistent(ss, w)) return v3s(0.0);
    return bsdf_eval(ss->b, ss->albedo, ss->wi, bsdf_to_local(&ss->fr, w), lobes);
}

vec3 surface_eval_cos(const surface_site *ss, vec3 w, unsigned lobes)
{
    if (!consistent(ss, w)) return v3s(0.0);
    vec3 wo = bsdf_to_local(&ss->fr, w);
    return v3_scale(bsdf_eval(ss->b, ss->albedo, ss->wi, wo, lobes), fabs(wo.z));
}

double surface_pdf(const surface_site *ss, vec3 w, unsigned lobes)
{
    if (!consistent(ss, w)) return 0.0;
    return bsdf_pdf(ss->b, ss->albedo, ss->wi, bsdf_to_local(&ss->fr, w), lobes);
}

int surface_sample_bsdf(const surface_site *ss, const double u[3], unsigned lobes, int adjoint, surface_sample *out)
{
    bsdf_sample bs;
    if (!bsdf_sample_wo(ss->b, ss->albedo, ss->wi, u, lobes, &bs)) return 0;
    vec3 w = bsdf_to_world(&ss->fr, bs.wo);
    if (!consistent(ss, w)) return 0;
    double gw = v3_dot(w, ss->fr.ng);
    out->w = w;
    out->lobe = bs.lobe;
    out->weight = bs.weight;
    if (adjoint) { /* Veach 1997 §5.2-5.3: the adjoint of refraction, and of shading normals */
        double num = fabs(ss->wi.z) * fabs(gw), den = fabs(v3_dot(ss->wi_world, ss->fr.ng)) * fabs(bs.wo.z);
        if (!(den > 0.0)) return 0;
        out->weight = v3_scale(out->weight, bsdf_adjoint_scale(ss->b, ss->wi, bs.wo) * num / den);
    }
    return v3_is_finite(out->weight);
}

vec3 surface_photon_power(const surface_site *ss, vec3 beta)
{
    double g = fabs(v3_dot(ss->wi_world, ss->fr.ng));
    return g > 0.0 ? v3_scale(beta, fabs(ss->wi.z) / g) : v3s(0.0);
}

vec3 surface_spawn(const scene *s, const surface_site *ss, vec3 w)
{
    vec3 n = v3_dot(w, ss->fr.ng) >= 0.0 ? ss->fr.ng : v3_neg(ss->fr.ng);
    return scene_offset_ray_origin(s, ss->p, n);
}

photon_split surface_photon_split(const bsdf *b, const surface_shading *sh)
{
    unsigned lobes = bsdf_lobes(b);
    unsigned gather = lobes & BSDF_LOBE_DIFFUSE;
    if ((lobes & BSDF_LOBE_GLOSSY) && !bsdf_transmits(b) && b->alpha >= sh->glossy_gather_alpha)
        gather |= BSDF_LOBE_GLOSSY;
    return (photon_split){gather, lobes & ~gather};
}
