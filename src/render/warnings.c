/* Warnings about the scene before a run: what the chosen integrator or the DARTS samplers render with a known
 * bias, or not at all, and how to avoid it. */
#include <stdio.h>

#include "dartspp/darts.h"
#include "dartspp/surface.h"
#include "run_internal.h"

/* Specular and near-specular surfaces break two assumptions, and the user should hear which one applies
 * (src/darts/README.md, mirrors): the path tracer cannot reach a point light through a delta lobe (mirror,
 * smooth metal or glass, a plastic's coat), so light that takes one before any diffuse, glossy or medium
 * vertex is missing; DARTS's time bounds and control vertices assume a straight camera leg, so what the
 * camera sees through a surface it continues through (surface_photon_split) is biased. */
static void warn_mirrors(const scene *s, const render_plan *p)
{
    const char *delta = NULL, *continued = NULL;
    for (int i = 0; i < s->surface_count; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        if (s->surfaces[i].tri_count == 0 || bsdf_is_passthrough(b)) continue;
        if (!delta && (bsdf_lobes(b) & BSDF_LOBE_SPECULAR)) delta = s->surfaces[i].name;
        if (!continued && surface_photon_split(b, &p->shading).cont) continued = s->surfaces[i].name;
    }
    const char *point_like = NULL;
    for (int i = 0; i < s->light_count && !point_like; i++)
        if (!emitter_hittable(&s->lights[i])) point_like = s->lights[i].name;
    if (delta && p->type == INTEGRATOR_PATH_TRACER && point_like)
        fprintf(stderr, "warning: %s: surface '%s' is specular: the path tracer cannot connect through it to lights "
                "without area (point, spot, collimated; here '%s'), so their light reflected or refracted by it before "
                "any diffuse or medium vertex (caustics) is missing from the image; photon points render it\n", s->path,
                delta, point_like);
    const darts_plan *d = &p->darts;
    if (continued && p->type == INTEGRATOR_PHOTON_POINTS && d->active && d->mirrors == DARTS_MIRRORS_STRAIGHT &&
        d->side.seen)
        fprintf(stderr, "warning: %s: the camera sees surface '%s', which is specular or near-specular: camera paths "
                "continue through it, but with darts_mirrors \"straight\" the DARTS time bounds and control vertices "
                "assume a straight camera leg, so what the camera sees through it is too dark; darts_mirrors \"full\" "
                "(the default) renders it without that bias\n", s->path, d->side.first);
}

/* Elliptical control vertices assume one refractive index along the camera leg; when the media and vacuum
 * present in the scene differ in η, the photon pass turns them off (darts_guide.control_vertices) and the
 * user should hear why and how to get them back. */
static void warn_mixed_eta(const scene *s, const render_plan *p)
{
    if (!p->darts.active || !p->darts.elliptical_asked || p->darts.control_vertices) return;
    char list[1024] = "";
    size_t len = 0;
    int media = 0, medium = MEDIUM_VACUUM, vacuum = 0;
    for (int r = MEDIUM_VACUUM; r < s->medium_count; r++) {
        if (!scene_region_present(s, r)) continue;
        if (r == MEDIUM_VACUUM) vacuum = 1;
        else media++, medium = r;
        int n = snprintf(list + len, sizeof list - len, "%s%s%s%s η = %g", len ? ", " : "", r == MEDIUM_VACUUM ? "" : "'",
                         r == MEDIUM_VACUUM ? "vacuum" : s->media[r].name, r == MEDIUM_VACUUM ? "" : "'", medium_eta(s, r));
        if (n > 0 && (size_t)n < sizeof list - len) len += (size_t)n;
    }
    fprintf(stderr, "warning: %s: the refractive index differs between the regions of the scene (%s): elliptical "
            "control vertices are off, since they need one η along the whole camera leg (DA distance sampling and "
            "the other DARTS samplers stay on)", s->path, list);
    if (vacuum && media == 1)
        fprintf(stderr, "; if the camera, the lights and every light path stay inside '%s', "
                "vaccum_speed_of_light = %g (its speed_of_light) restores them", s->media[medium].name,
                1.0 / s->media[medium].eta);
    fprintf(stderr, "\n");
}

/* A light the path tracer cannot reach at all (docs/emitters.md §7): its light is missing from the image. */
static void warn_unreachable_lights(const scene *s, const render_plan *p)
{
    if (p->type != INTEGRATOR_PATH_TRACER) return;
    for (int i = 0; i < s->light_count; i++)
        if (!emitter_connectable(&s->lights[i]) && v3_max(s->lights[i].flux) > 0.0)
            fprintf(stderr, "warning: %s: light '%s' (%s) is a parallel beam of radius 0: the path tracer can neither "
                    "connect to it nor hit it, so its light is missing from the image; give it a radius or a "
                    "divergence, or render with photon points\n", s->path, s->lights[i].name, s->lights[i].type_name);
}

void run_warn(const scene *s, const render_plan *p)
{
    warn_unreachable_lights(s, p);
    warn_mirrors(s, p);
    warn_mixed_eta(s, p);
}
