/* What the camera sees besides straight lines: the surfaces camera paths continue through, and the
 * camera's mirror image in each planar mirror among them (plan.h, camera_side_scan). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/plan.h"

#define SCAN_MAX_HOPS 64        /* null/forward crossings followed per ray */
#define PLANE_REL_EPS 1e-5      /* planarity tolerance, relative to the scene's size */
#define NORMAL_EPS 1e-6         /* a shading normal this close to ±ng is flat */

typedef enum { SEES_NOTHING, SEES_MIRROR, SEES_OTHER } sight;

/* The first hit from o along d that is not a null/forward surface; 0 when the ray leaves the scene. */
static int first_opaque_hit(const scene *s, vec3 o, vec3 d, hit_record *h)
{
    for (int hop = 0; hop < SCAN_MAX_HOPS; hop++) {
        if (!scene_intersect(s, o, d, INFINITY, h)) return 0;
        if (!bsdf_is_passthrough(&s->bsdfs[s->surfaces[h->surface].bsdf])) return 1;
        o = scene_offset_ray_origin(s, h->p, v3_dot(d, h->ng) < 0.0 ? v3_neg(h->ng) : h->ng);
    }
    return 0;
}

/* Whether every vertex of the surface's triangles lies on the plane of its first one; sets that plane. */
static int surface_is_planar(const scene *s, const surface *sf, vec3 *n, double *c)
{
    if (sf->tri_count == 0) return 0;
    const uint32_t *t0 = &s->tris[3 * sf->first_tri];
    vec3 p[3];
    for (int k = 0; k < 3; k++) {
        const float *v = &s->verts[3 * t0[k]];
        p[k] = v3(v[0], v[1], v[2]);
    }
    vec3 m = v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0]));
    double len = v3_len(m);
    if (!(len > 0.0)) return 0;
    *n = v3_scale(m, 1.0 / len);
    *c = v3_dot(*n, p[0]);
    double eps = PLANE_REL_EPS * s->ray_offset_scale;
    for (uint32_t i = 0; i < 3 * sf->tri_count; i++) {
        const float *v = &s->verts[3 * s->tris[3 * sf->first_tri + i]];
        if (fabs(v3_dot(*n, v3(v[0], v[1], v[2])) - *c) > eps) return 0;
    }
    return 1;
}

/* Continued lobes that are a delta reflection only: one outgoing direction, the mirror direction. */
static int reflects_like_a_mirror(const bsdf *b, const surface_shading *sh)
{
    photon_split split = surface_photon_split(b, sh);
    return split.cont == BSDF_LOBE_SPECULAR && !bsdf_transmits(b);
}

/* What one camera ray continues through: nothing, exactly one planar mirror (*mirror = its surface, the
 * reflected ray then ends on a gathered surface or leaves), or something else. */
static sight classify_ray(const scene *s, const surface_shading *sh, const char *planar, vec3 d, int *mirror)
{
    hit_record h;
    if (!first_opaque_hit(s, s->cam.pos, d, &h)) return SEES_NOTHING;
    const bsdf *b = &s->bsdfs[s->surfaces[h.surface].bsdf];
    if (!surface_photon_split(b, sh).cont) return SEES_NOTHING;
    if (!planar[h.surface] || !reflects_like_a_mirror(b, sh)) return SEES_OTHER;
    vec3 ns = v3_dot(h.ns, h.ng) < 0.0 ? v3_neg(h.ns) : h.ns;
    if (v3_len(v3_sub(ns, h.ng)) > NORMAL_EPS) return SEES_OTHER; /* smooth normals bend the reflection */
    *mirror = h.surface;
    vec3 n = v3_dot(d, h.ng) < 0.0 ? h.ng : v3_neg(h.ng); /* towards the camera */
    vec3 r = v3_sub(d, v3_scale(n, 2.0 * v3_dot(d, n)));
    hit_record h2;
    vec3 o = scene_offset_ray_origin(s, h.p, n);
    if (!first_opaque_hit(s, o, r, &h2)) return SEES_MIRROR;
    return surface_photon_split(&s->bsdfs[s->surfaces[h2.surface].bsdf], sh).cont ? SEES_OTHER : SEES_MIRROR;
}

void plan_scan_camera_side(const scene *s, const surface_shading *sh, camera_side_scan *out)
{
    memset(out, 0, sizeof *out);
    int ns = s->surface_count;
    char *planar = calloc((size_t)(ns > 0 ? ns : 1), 1);
    long *hits = calloc((size_t)(ns > 0 ? ns : 1), sizeof(long));
    if (!planar || !hits) { /* no memory for the scan: assume the worst, no focus and everything other */
        free(planar);
        free(hits);
        out->seen = 1, out->other_fraction = 1.0;
        snprintf(out->first, sizeof out->first, "(unknown: out of memory)");
        return;
    }
    vec3 nrm[1];
    double c;
    for (int i = 0; i < ns; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        planar[i] = !bsdf_is_passthrough(b) && reflects_like_a_mirror(b, sh) && surface_is_planar(s, &s->surfaces[i], nrm, &c);
    }
    int gw = 2 * s->cam.width + 1, gh = 2 * s->cam.height + 1; /* pixel corners and centres */
    long other = 0;
    out->rays = gw * gh;
#pragma omp parallel
    {
        long my_other = 0;
        long *my_hits = calloc((size_t)(ns > 0 ? ns : 1), sizeof(long));
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < gh; y++)
            for (int x = 0; x < gw; x++) {
                int m = -1;
                sight k = classify_ray(s, sh, planar, camera_ray_dir(&s->cam, 0.5 * x, 0.5 * y), &m);
                if (k == SEES_OTHER) my_other++;
                if (k == SEES_MIRROR && my_hits) my_hits[m]++;
                if (k == SEES_MIRROR && !my_hits) my_other++;
            }
#pragma omp critical
        {
            other += my_other;
            for (int i = 0; i < ns && my_hits; i++) hits[i] += my_hits[i];
        }
        free(my_hits);
    }
    /* the mirrors, in surface order (deterministic); beyond PLAN_MAX_MIRRORS they count as other */
    for (int i = 0; i < ns; i++) {
        if (!hits[i]) continue;
        if (out->mirror_count == PLAN_MAX_MIRRORS) {
            other += hits[i];
            continue;
        }
        surface_is_planar(s, &s->surfaces[i], nrm, &c);
        vec3 cam = s->cam.pos;
        int k = out->mirror_count++;
        out->mirror_surface[k] = i;
        out->focus[k] = v3_sub(cam, v3_scale(nrm[0], 2.0 * (v3_dot(nrm[0], cam) - c))); /* reflection in the plane */
        out->mirror_fraction[k] = (double)hits[i] / out->rays;
        if (!out->seen) snprintf(out->first, sizeof out->first, "%s", s->surfaces[i].name);
        out->seen = 1;
    }
    out->other_fraction = (double)other / out->rays;
    if (other > 0 && !out->seen) { /* name one continued surface without a focus */
        for (int i = 0; i < ns && !out->first[0]; i++)
            if (surface_photon_split(&s->bsdfs[s->surfaces[i].bsdf], sh).cont && s->surfaces[i].tri_count)
                snprintf(out->first, sizeof out->first, "%s", s->surfaces[i].name);
    }
    out->seen |= other > 0;
    free(planar);
    free(hits);
}
