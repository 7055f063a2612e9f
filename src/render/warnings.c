/* Warnings about the scene before a run: what the chosen integrator or the DARTS samplers render with a known
 * bias, or not at all, and how to avoid it. */
#include <stdio.h>

#include "dartspp/darts.h"
#include "dartspp/surface_site.h"
#include "integrators.h"
#include "run_internal.h"

/* Specular and near-specular surfaces break two assumptions, and the user should hear which one applies
 * (src/darts/README.md, mirrors): the path tracer cannot reach a point light through a delta lobe (mirror,
 * smooth metal or glass, a plastic's coat), so light that takes one before any diffuse, glossy or medium
 * vertex is missing (warn_caustics); DARTS's time bounds and control vertices assume a straight camera leg, so
 * what the camera sees through a surface it continues through (surface_photon_split) is biased
 * (warn_straight_mirrors). */
static void warn_caustics(FILE *out, const scene *s)
{
    const char *delta = NULL;
    for (int i = 0; i < s->surface_count && !delta; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        if (s->surfaces[i].tri_count == 0 || bsdf_is_passthrough(b)) continue;
        if (bsdf_lobes(b) & BSDF_LOBE_SPECULAR) delta = s->surfaces[i].name;
    }
    const char *point_like = NULL;
    for (int i = 0; i < s->light_count && !point_like; i++)
        if (!emitter_hittable(&s->lights[i])) point_like = s->lights[i].name;
    if (delta && point_like)
        fprintf(out, "warning: %s: surface '%s' is specular: the path tracer cannot connect through it to lights "
                "without area (point, spot, collimated; here '%s'), so their light reflected or refracted by it before "
                "any diffuse or medium vertex (caustics) is missing from the image; photon points render it\n", s->path,
                delta, point_like);
}

static void warn_straight_mirrors(FILE *out, const scene *s, const render_plan *p)
{
    const darts_plan *d = &p->darts;
    if (!d->active || d->darts_mirrors != DARTS_MIRRORS_STRAIGHT || !d->side.seen) return;
    const char *continued = NULL;
    for (int i = 0; i < s->surface_count && !continued; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        if (s->surfaces[i].tri_count == 0 || bsdf_is_passthrough(b)) continue;
        if (surface_photon_split(b, &p->shading).cont) continued = s->surfaces[i].name;
    }
    if (continued)
        fprintf(out, "warning: %s: the camera sees surface '%s', which is specular or near-specular: camera paths "
                "continue through it, but with darts_mirrors \"straight\" the DARTS time bounds and control vertices "
                "assume a straight camera leg, so what the camera sees through it is too dark; darts_mirrors \"full\" "
                "(the default) renders it without that bias\n", s->path, d->side.first);
}

/* Elliptical control vertices assume one refractive index along the camera leg; when the media and vacuum
 * present in the scene differ in η, the photon pass turns them off (darts_guide.enable_elliptical) and the
 * user should hear why and how to get them back. */
static void warn_mixed_eta(FILE *out, const scene *s, const render_plan *p)
{
    if (!p->darts.active || !p->darts.enable_elliptical_asked || p->darts.enable_elliptical) return;
    char list[1024] = "";
    size_t len = 0;
    int media = 0, medium = MEDIUM_VACUUM, vacuum = 0;
    for (int r = MEDIUM_VACUUM; r < s->medium_count; r++) {
        if (!scene_region_present(s, r)) continue;
        if (r == MEDIUM_VACUUM) vacuum = 1;
        else media++, medium = r;
        int n = snprintf(list + len, sizeof list - len, "%s%s%s%s η = %g", len ? ", " : "", r == MEDIUM_VACUUM ? "" : "'",
                         medium_name(s, r), r == MEDIUM_VACUUM ? "" : "'", medium_eta(s, r));
        if (n > 0 && (size_t)n < sizeof list - len) len += (size_t)n;
    }
    fprintf(out, "warning: %s: the refractive index differs between the regions of the scene (%s): elliptical "
            "control vertices are off, since they need one η along the whole camera leg (DA distance sampling and "
            "the other DARTS samplers stay on)", s->path, list);
    if (vacuum && media == 1)
        fprintf(out, "; if the camera, the lights and every light path stay inside '%s', "
                "vaccum_speed_of_light = %g (its speed_of_light) restores them", s->media[medium].name,
                1.0 / s->media[medium].eta);
    fprintf(out, "\n");
}

/* A light the path tracer cannot reach at all (docs/emitters.md §7): its light is missing from the image. */
static void warn_unreachable_lights(FILE *out, const scene *s)
{
    for (int i = 0; i < s->light_count; i++)
        if (!emitter_connectable(&s->lights[i]) && v3_max(s->lights[i].flux) > 0.0)
            fprintf(out, "warning: %s: light '%s' (%s) is a parallel beam of radius 0: the path tracer can neither "
                    "connect to it nor hit it, so its light is missing from the image; give it a radius or a "
                    "divergence, or render with photon points\n", s->path, s->lights[i].name, s->lights[i].type_name);
}

/* The camera's declared medium against the geometry around it: along a few camera rays (the image centre and
 * the middle of each quadrant), the first surface that sets media tells which medium is on the camera's side
 * of it (ext_medium in front of it, int_medium behind). A camera declared in a medium it sits outside of
 * (the authors' collimated slab scenes put the camera in the slab's medium 1 mm outside the slab) gets that
 * medium along its first leg, where light paths, which follow the surfaces, never see it: the path tracer and
 * photon points then render different scenes. Legal; warned about with both media named. */
static void warn_camera_medium(FILE *out, const scene *s)
{
    static const double at[5][2] = {{0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}};
    for (int k = 0; k < 5; k++) {
        vec3 o = s->cam.pos, d = camera_ray_dir(&s->cam, at[k][0] * s->cam.width, at[k][1] * s->cam.height);
        int med = s->cam.medium;
        hit_record h;
        for (int crossing = 0; crossing < 64 && scene_intersect(s, o, d, INFINITY, &h); crossing++) {
            const surface *sf = &s->surfaces[h.surface];
            if (sf->overrides_media) {
                int here = v3_dot(d, h.ng) < 0.0 ? sf->ext_medium : sf->int_medium;
                if (here != med) {
                    fprintf(out, "warning: %s: the camera is declared in %s%s%s, but surface '%s' in front of it has "
                            "%s%s%s on the camera's side: camera paths take the declared medium up to that surface, "
                            "light paths the surface's, so the path tracer and photon points render different "
                            "scenes; set the camera's medium to the surface's side\n", s->path,
                            med == MEDIUM_VACUUM ? "vacuum" : "medium '", med == MEDIUM_VACUUM ? "" : s->media[med].name,
                            med == MEDIUM_VACUUM ? "" : "'", sf->name, here == MEDIUM_VACUUM ? "vacuum" : "medium '",
                            here == MEDIUM_VACUUM ? "" : s->media[here].name, here == MEDIUM_VACUUM ? "" : "'");
                    return;
                }
                break;
            }
            if (!bsdf_is_passthrough(&s->bsdfs[sf->bsdf])) break; /* an opaque surface first: nothing to tell */
            o = scene_offset_ray_origin(s, h.p, v3_dot(d, h.ng) > 0.0 ? h.ng : v3_neg(h.ng));
        }
    }
}

void render_warn(FILE *out, const scene *s, const render_plan *p)
{
    warn_camera_medium(out, s);
    const integrator_entry *row = integrator_entry_of(p->type);
    if (row->warn) row->warn(out, s, p);
    warn_mixed_eta(out, s, p);
}

/* The path tracer's warnings: lights it cannot reach, and caustics it cannot render. */
void warn_path_tracer(FILE *out, const scene *s, const render_plan *p)
{
    (void)p;
    warn_unreachable_lights(out, s);
    warn_caustics(out, s);
}

/* Photon points' warnings: DARTS assuming straight camera legs where the camera sees mirrors. */
void warn_photon_points(FILE *out, const scene *s, const render_plan *p)
{
    warn_straight_mirrors(out, s, p);
}
