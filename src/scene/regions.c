/* Which regions (media, and vacuum) a scene has, and whether light crosses one refractive index in all. */
#include "dartspp/scene.h"

int scene_region_present(const scene *s, int region)
{
    if (s->cam.medium == region) return 1;
    for (int i = 0; i < s->light_count; i++)
        if (s->lights[i].medium == region) return 1;
    for (int i = 0; i < s->surface_count; i++) {
        const surface *sf = &s->surfaces[i];
        if (sf->tri_count > 0 && sf->overrides_media && (sf->int_medium == region || sf->ext_medium == region)) return 1;
    }
    return 0;
}

int scene_eta_uniform(const scene *s)
{
    int seen = 0;
    double eta0 = 0.0;
    for (int r = MEDIUM_VACUUM; r < s->medium_count; r++) {
        if (!scene_region_present(s, r)) continue;
        double eta = medium_eta(s, r);
        if (seen && eta != eta0) return 0;
        eta0 = eta;
        seen = 1;
    }
    return 1;
}

/* A straight segment keeps one refractive index unless it can cross a pass-through surface (null or forward:
 * scene_transmittance goes through those and stops at every other) between regions of different η. */
int scene_eta_uniform_along_segments(const scene *s)
{
    for (int i = 0; i < s->surface_count; i++) {
        const surface *sf = &s->surfaces[i];
        if (sf->tri_count == 0 || !sf->overrides_media || !bsdf_is_passthrough(&s->bsdfs[sf->bsdf])) continue;
        if (medium_eta(s, sf->int_medium) != medium_eta(s, sf->ext_medium)) return 0;
    }
    return 1;
}
