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
    /* off for another reason: unwarped time with a continued surface in view (the run summary says so); blaming
     * η there named equal indices as different (issue 48, test_differential) */
    if (p->darts.unwarped_mirror_off) return;
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

/* Along the ray (o, d): the first surface that sets media, through invisible and index-matched ones, tells the
 * medium on o's side of it (ext_medium in front, int_medium behind). 1 with *here and *sf, 0 when an opaque
 * surface comes first or nothing is hit. */
static int medium_side(const scene *s, vec3 o, vec3 d, int *here, const surface **sf)
{
    hit_record h;
    for (int crossing = 0; crossing < 64 && scene_intersect(s, o, d, INFINITY, &h); crossing++) {
        *sf = &s->surfaces[h.surface];
        if ((*sf)->overrides_media) {
            *here = v3_dot(d, h.ng) < 0.0 ? (*sf)->ext_medium : (*sf)->int_medium;
            return 1;
        }
        if (!bsdf_is_passthrough(&s->bsdfs[(*sf)->bsdf])) return 0;
        o = scene_offset_ray_origin(s, h.p, v3_dot(d, h.ng) > 0.0 ? h.ng : v3_neg(h.ng));
    }
    return 0;
}

/* "vacuum" or "medium 'fog'" */
static const char *region_words(const scene *s, int m, char *buf, size_t n)
{
    if (m == MEDIUM_VACUUM) return "vacuum";
    snprintf(buf, n, "medium '%s'", s->media[m].name);
    return buf;
}

/* The camera's declared medium against the geometry around it: along a few camera rays (the image centre and
 * the middle of each quadrant), the first surface that sets media tells which medium is on the camera's side
 * of it. A camera declared in a medium it sits outside of (the authors' collimated slab scenes put the camera
 * in the slab's medium 1 mm outside the slab) gets that medium along its first leg, where light paths, which
 * follow the surfaces, never see it: the path tracer and photon points then render different scenes. Legal;
 * warned about with both media named. */
static void warn_camera_medium(FILE *out, const scene *s)
{
    static const double at[5][2] = {{0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}};
    for (int k = 0; k < 5; k++) {
        vec3 o, d = camera_ray(&s->cam, at[k][0] * s->cam.width, at[k][1] * s->cam.height, &o);
        int here, med = s->cam.medium;
        const surface *sf;
        if (!medium_side(s, o, d, &here, &sf) || here == med) continue;
        char a[96], b[96];
        fprintf(out, "warning: %s: the camera is declared in %s, but surface '%s' in front of it has %s on the "
                "camera's side: camera paths take the declared medium up to that surface, light paths the surface's, "
                "so the path tracer and photon points render different scenes; set the camera's medium to the "
                "surface's side\n", s->path, region_words(s, med, a, sizeof a), sf->name,
                region_words(s, here, b, sizeof b));
        return;
    }
}

/* The same mistake for a light (issue 48): a point, spot or collimated light inside a closed fog boundary
 * without "ext_medium" starts its light paths in vacuum, while camera paths connect to it through the fog
 * (photon points 0.0285 against the path tracer's 0.109); an emissive surface inside one whose surface sets no
 * media emits into vacuum likewise (0.0023 against 0.0061). Six rays from the light (from an emissive
 * surface: from its first triangle's centre, on its front side) find the medium the geometry puts there. */
static void warn_light_medium(FILE *out, const scene *s)
{
    static const double dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        vec3 o = L->pos;
        if (L->surface >= 0) {
            const uint32_t *t = &s->tris[3 * (size_t)L->first_tri];
            vec3 p[3];
            for (int k = 0; k < 3; k++)
                p[k] = v3(s->verts[3 * (size_t)t[k]], s->verts[3 * (size_t)t[k] + 1], s->verts[3 * (size_t)t[k] + 2]);
            vec3 n = v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0]));
            o = scene_offset_ray_origin(s, v3_scale(v3_add(v3_add(p[0], p[1]), p[2]), 1.0 / 3.0), n);
        }
        for (int k = 0; k < 6; k++) {
            int here;
            const surface *sf;
            if (!medium_side(s, o, v3(dirs[k][0], dirs[k][1], dirs[k][2]), &here, &sf) || here == L->medium) continue;
            char a[96], b[96];
            fprintf(out, "warning: %s: light '%s' emits into %s (%s), but surface '%s' around it has %s on the "
                    "light's side: its light paths start in the wrong medium while camera paths reach it through "
                    "the surface's, so photon points and the path tracer render different scenes; set %s to the "
                    "surface's side\n", s->path, L->name,
                    region_words(s, L->medium, a, sizeof a),
                    L->surface >= 0 ? "its surface's ext_medium" : "its ext_medium", sf->name,
                    region_words(s, here, b, sizeof b),
                    L->surface >= 0 ? "both its \"int_medium\" and \"ext_medium\"" : "its \"ext_medium\"");
            break;
        }
    }
}

/* A collimated beam far wider than the scene (issue 48: radius 1e4 around a scene of a few units): photon points
 * start its light paths uniformly on the whole disc, so all but a share (R/r)² of them pass beside the geometry
 * and the camera (R: the half-diagonal of the box around the geometry and the camera), and at 1e5 paths a pass
 * stores no photon that counts: a black image. The path tracer connects to the beam where its camera segments
 * cross it and renders it. Warned about with the scene's extent and the radius that covers it. */
static void warn_wide_beams(FILE *out, const scene *s)
{
    vec3 lo = s->cam.pos, hi = s->cam.pos;
    for (uint32_t v = 0; v < s->vert_count; v++) {
        vec3 q = v3(s->verts[3 * (size_t)v], s->verts[3 * (size_t)v + 1], s->verts[3 * (size_t)v + 2]);
        lo = v3(dp_fmin(lo.x, q.x), dp_fmin(lo.y, q.y), dp_fmin(lo.z, q.z));
        hi = v3(dp_fmax(hi.x, q.x), dp_fmax(hi.y, q.y), dp_fmax(hi.z, q.z));
    }
    double R = 0.5 * v3_len(v3_sub(hi, lo));
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        if (!(L->radius > 0.0) || !(L->radius > 30.0 * R)) continue;
        fprintf(out, "warning: %s: light '%s' (%s): radius %g is %.3g times the scene's extent (the geometry and the "
                "camera lie within %g of their centre): photon points start its light paths on the whole disc, so at "
                "most %.2g of them can reach the scene and the image is black or noise; the path tracer renders it, "
                "or give a radius of about %.3g (with the flux per area, emission, unchanged)\n", s->path, L->name,
                L->type_name, L->radius, L->radius / R, R, (R / L->radius) * (R / L->radius), 2.0 * R);
    }
}

void render_warn(FILE *out, const scene *s, const render_plan *p)
{
    warn_camera_medium(out, s);
    warn_light_medium(out, s);
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

/* Photon points' warnings: DARTS assuming straight camera legs where the camera sees mirrors; beams far wider than
 * the scene. */
void warn_photon_points(FILE *out, const scene *s, const render_plan *p)
{
    warn_straight_mirrors(out, s, p);
    warn_wide_beams(out, s);
}
