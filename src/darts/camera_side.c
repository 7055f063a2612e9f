/* What the camera sees besides straight lines: the surfaces camera paths continue through, and the
 * camera's mirror image in each planar mirror among them (plan.h, camera_side_scan). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/darts.h"

#define SCAN_MAX_HOPS 64        /* null/forward crossings followed per ray */
#define PLANE_REL_EPS 1e-5      /* planarity tolerance, relative to the scene's size */
#define NORMAL_EPS 1e-6         /* a shading normal this close to ±ng is flat */
#define SCAN_MAX_GRID 1025      /* rays a side: 512² pixels get every corner and centre */

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

/* Continued lobes that only reflect (a mirror, smooth or rough metal, a plastic's coat): their camera paths
 * leave about the mirror direction, exactly so for a delta reflection. */
static int reflects_only(const bsdf *b, const surface_shading *sh)
{
    return surface_photon_split(b, sh).cont && !bsdf_transmits(b);
}

static int reflects_exactly(const bsdf *b, const surface_shading *sh)
{
    return surface_photon_split(b, sh).cont == BSDF_LOBE_SPECULAR && !bsdf_transmits(b);
}

/* What one camera ray continues through. Returns 0 when it continues through nothing. Otherwise *mirror is
 * the planar reflector it continues through first (-1: none, a curved, transmissive or smooth-shaded
 * surface) and *exact whether the reflector's focus gives its camera leg exactly: a delta reflection
 * whose reflected ray then ends on a gathered surface or leaves the scene. */
static int classify_ray(const scene *s, const surface_shading *sh, const char *planar, vec3 o, vec3 d, int *mirror,
                        int *exact)
{
    hit_record h;
    *mirror = -1, *exact = 0;
    if (!first_opaque_hit(s, o, d, &h)) return 0;
    const bsdf *b = &s->bsdfs[s->surfaces[h.surface].bsdf];
    if (!surface_photon_split(b, sh).cont) return 0;
    vec3 ns = v3_dot(h.ns, h.ng) < 0.0 ? v3_neg(h.ns) : h.ns;
    if (!planar[h.surface] || v3_len(v3_sub(ns, h.ng)) > NORMAL_EPS) return 1; /* smooth normals bend it */
    *mirror = h.surface;
    if (!reflects_exactly(b, sh)) return 1;
    vec3 n = v3_dot(d, h.ng) < 0.0 ? h.ng : v3_neg(h.ng); /* towards the camera */
    vec3 r = v3_sub(d, v3_scale(n, 2.0 * v3_dot(d, n)));
    hit_record h2;
    vec3 o2 = scene_offset_ray_origin(s, h.p, n);
    *exact = !first_opaque_hit(s, o2, r, &h2) || !surface_photon_split(&s->bsdfs[s->surfaces[h2.surface].bsdf], sh).cont;
    return 1;
}

void darts_scan_camera_side(const scene *s, const surface_shading *sh, camera_side_scan *out)
{
    memset(out, 0, sizeof *out);
    int ns = s->surface_count > 0 ? s->surface_count : 1;
    char *planar = calloc((size_t)ns, 1);
    long *hits = calloc((size_t)ns, sizeof(long)), *exact_hits = calloc((size_t)ns, sizeof(long));
    long *my_hits = calloc((size_t)ns * 2 * omp_get_max_threads(), sizeof(long));
    if (!planar || !hits || !exact_hits || !my_hits) { /* no memory: assume the worst, no focus */
        free(planar), free(hits), free(exact_hits), free(my_hits);
        out->seen = 1, out->other_fraction = 1.0;
        snprintf(out->first, sizeof out->first, "(unknown: out of memory)");
        return;
    }
    vec3 nrm;
    double c;
    for (int i = 0; i < s->surface_count; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        planar[i] = !bsdf_is_passthrough(b) && reflects_only(b, sh) && surface_is_planar(s, &s->surfaces[i], &nrm, &c);
    }
    /* pixel corners and centres, at most SCAN_MAX_GRID points a side (then evenly over the image) */
    int gw = 2 * s->cam.width + 1, gh = 2 * s->cam.height + 1;
    if (gw > SCAN_MAX_GRID) gw = SCAN_MAX_GRID;
    if (gh > SCAN_MAX_GRID) gh = SCAN_MAX_GRID;
    double sx = (double)s->cam.width / (gw - 1), sy = (double)s->cam.height / (gh - 1);
    long other = 0, seen = 0;
    out->rays = gw * gh;
#pragma omp parallel reduction(+ : other, seen)
    {
        long *mine = &my_hits[(size_t)ns * 2 * omp_get_thread_num()]; /* hits, then exact hits */
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < gh; y++)
            for (int x = 0; x < gw; x++) {
                int m, exact;
                vec3 o, d = camera_ray(&s->cam, sx * x, sy * y, &o);
                if (!classify_ray(s, sh, planar, o, d, &m, &exact)) continue;
                seen++;
                if (m >= 0) mine[m]++, mine[ns + m] += exact;
                if (!exact) other++;
            }
    }
    for (int t = 0; t < omp_get_max_threads(); t++)
        for (int i = 0; i < ns; i++) hits[i] += my_hits[(size_t)ns * 2 * t + i], exact_hits[i] += my_hits[(size_t)ns * (2 * t + 1) + i];
    /* the reflectors seen most, at most DARTS_MAX_MIRRORS (ties by surface order) */
    for (int k = 0; k < DARTS_MAX_MIRRORS; k++) {
        int best = -1;
        for (int i = 0; i < ns; i++)
            if (hits[i] > 0 && (best < 0 || hits[i] > hits[best])) best = i;
        if (best < 0) break;
        surface_is_planar(s, &s->surfaces[best], &nrm, &c);
        vec3 cam = s->cam.pos;
        out->mirror_surface[k] = best;
        out->focus[k] = v3_sub(cam, v3_scale(nrm, 2.0 * (v3_dot(nrm, cam) - c))); /* reflection in the plane */
        out->mirror_fraction[k] = (double)hits[best] / out->rays;
        out->mirror_count++;
        hits[best] = exact_hits[best] = 0;
    }
    for (int i = 0; i < ns; i++) other += exact_hits[i]; /* exact reflectors beyond the limit have no focus */
    out->other_fraction = (double)other / out->rays;
    out->seen = seen > 0;
    if (out->mirror_count) snprintf(out->first, sizeof out->first, "%s", s->surfaces[out->mirror_surface[0]].name);
    for (int i = 0; out->seen && i < s->surface_count && !out->first[0]; i++) /* some continued surface */
        if (surface_photon_split(&s->bsdfs[s->surfaces[i].bsdf], sh).cont && s->surfaces[i].tri_count)
            snprintf(out->first, sizeof out->first, "%s", s->surfaces[i].name);
    free(planar), free(hits), free(exact_hits), free(my_hits);
}
