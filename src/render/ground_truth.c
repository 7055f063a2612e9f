/* Ground truth beside the render (renderer key `ground_truth`; docs/sensor.md §3): for the ray through each
 * pixel's centre, passing through null and forward surfaces, the first surface it meets — its distance
 * (depth), shading normal (facing the camera) and albedo — and the time of first arrival: the earliest time
 * a light's pulse can return to the pixel by that surface alone (pulse start + optical path from the light
 * to the surface + from the surface to the camera, along straight segments, the light unoccluded). 0 where
 * the ray meets no surface (and the arrival 0 where no light sees the surface). One ray per pixel and one
 * connection per light: nothing next to a render's cost. */
#include <math.h>
#include <string.h>

#include "dartspp/render.h"
#include "dartspp/surface_site.h"

/* The first scattering surface along the camera ray; its hit, site and the camera leg's optical length. */
static int first_surface(const scene *s, const surface_shading *sh, vec3 o, vec3 d, hit_record *h, surface_site *ss,
                         double *depth, double *leg, int *med)
{
    *med = s->cam.medium;
    *depth = *leg = 0.0;
    for (int crossing = 0; crossing < 256; crossing++) {
        if (!scene_intersect(s, o, d, INFINITY, h)) return 0;
        *depth += h->t;
        *leg += medium_eta(s, *med) * h->t;
        const surface *sf = &s->surfaces[h->surface];
        if (!bsdf_is_passthrough(&s->bsdfs[sf->bsdf])) return surface_site_init(ss, s, sh, h, d);
        *med = surface_next_medium(sf, *med, d, h->ng);
        o = scene_offset_ray_origin(s, h->p, v3_dot(d, h->ng) > 0.0 ? h->ng : v3_neg(h->ng));
    }
    return 0;
}

/* The earliest return through x over the lights, or 0 when no light reaches x unoccluded. */
static double first_arrival(const scene *s, const surface_site *ss, int med, double camera_leg)
{
    double best = INFINITY;
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        emitter_direct ed;
        const double u[2] = {0.5, 0.5}; /* an area light's middle */
        if (!emitter_sample_direct(s, L, ss->p, u, &ed)) continue;
        vec3 target = v3_is_zero(ed.n) ? ed.y
                      : scene_offset_ray_origin(s, ed.y, v3_dot(ed.wi, ed.n) < 0.0 ? ed.n : v3_neg(ed.n));
        vec3 tr;
        double t = L->pulse.start + camera_leg;
        if (scene_transmittance(s, surface_spawn(s, ss, ed.wi), surface_medium_toward(ss, med, ed.wi), target, &tr, &t))
            best = fmin(best, t);
    }
    return isfinite(best) ? best : 0.0;
}

int ground_truth_compute(const scene *s, const render_plan *p, ground_truth *gt, dp_error *err)
{
    int w = s->cam.width, h = s->cam.height;
    memset(gt, 0, sizeof *gt);
    for (int k = 0; k < GROUND_TRUTH_IMAGES; k++)
        if (image_alloc(&gt->img[k], w, h, err)) {
            ground_truth_free(gt);
            return -1;
        }
    int unwarp = p->window.camera_unwarp;
#pragma omp parallel for schedule(dynamic, 4)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            hit_record hit;
            surface_site ss;
            double depth, leg;
            int med;
            vec3 o, d = camera_ray(&s->cam, x + 0.5, y + 0.5, &o);
            if (!first_surface(s, &p->shading, o, d, &hit, &ss, &depth, &leg, &med)) continue;
            vec3 n = ss.fr.n;
            if (v3_dot(n, d) > 0.0) n = v3_neg(n); /* towards the camera */
            double arrival = first_arrival(s, &ss, med, unwarp ? 0.0 : leg);
            const double v[GROUND_TRUTH_IMAGES][3] = {{depth, depth, depth}, {arrival, arrival, arrival},
                                                      {n.x, n.y, n.z}, {ss.albedo.x, ss.albedo.y, ss.albedo.z}};
            for (int k = 0; k < GROUND_TRUTH_IMAGES; k++)
                for (int c = 0; c < 3; c++) gt->img[k].rgb[3 * ((size_t)y * w + x) + c] = (float)v[k][c];
        }
    return 0;
}

const char *const GROUND_TRUTH_NAMES[GROUND_TRUTH_IMAGES] = {"depth", "arrival", "normal", "albedo"};

void ground_truth_free(ground_truth *gt)
{
    for (int k = 0; k < GROUND_TRUTH_IMAGES; k++) image_free(&gt->img[k]);
}
