/* Surface-map search benchmark: the BVH k-NN search against the FLANN backend on the photons of real
 * iterations, all camera rays' first hits as queries (what the sensor pass asks), 1 thread, same answers
 * checked. Usage: build/surface_knn_bench SCENE.json [--set k=v ...] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/photon.h"
#include "dartspp/scene.h"

static int query_all(const scene *s, const surface_photon_map *m, const vec3 *x, const int *hit, int n, long *sum)
{
    int idx[256];
    double d2[256];
    long found = 0;
    for (int i = 0; i < n; i++)
        if (hit[i]) found += photon_map_query_knn(m, x[i], s->integrator.gather_photon_count, s->integrator.gather_radius, idx, d2);
    *sum = found;
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) return fprintf(stderr, "usage: %s SCENE.json [--set k=v ...]\n", argv[0]), 2;
    const char *sets[32];
    int ns = 0;
    for (int i = 2; i + 1 < argc && ns < 32; i += 2)
        if (!strcmp(argv[i], "--set")) sets[ns++] = argv[i + 1];
    scene s;
    dp_error err;
    scene_load_options lo = {.sets = sets, .set_count = ns};
    if (scene_load(argv[1], &lo, &s, &err)) return fprintf(stderr, "%s\n", err.msg), 2;
    photon_set ps;
    if (photon_pass(&s, NULL, 1, 0, 0.0, NULL, &ps, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    int n = s.cam.width * s.cam.height;
    vec3 *x = malloc(sizeof(vec3) * n);
    int *hit = malloc(sizeof(int) * n);
    for (int i = 0; i < n; i++) {
        hit_record h;
        hit[i] = scene_intersect(&s, s.cam.pos, camera_ray_dir(&s.cam, i % s.cam.width + 0.5, i / s.cam.width + 0.5), INFINITY, &h);
        x[i] = h.p;
    }
    double t0 = dp_seconds();
    surface_photon_map *a = surface_map_build(ps.surf, ps.n_surf, &err);
    double t1 = dp_seconds();
    long fa, fb;
    query_all(&s, a, x, hit, n, &fa);
    double t2 = dp_seconds();
    surface_photon_map *b = surface_map_build_flann(ps.surf, ps.n_surf, &err);
    double t3 = dp_seconds();
    query_all(&s, b, x, hit, n, &fb);
    double t4 = dp_seconds();
    printf("%zu surface photons, %d queries (k %d, R %g), 1 thread\n", ps.n_surf, n, s.integrator.gather_photon_count, s.integrator.gather_radius);
    printf("| search | build (s) | queries (s) | per query (us) | photons found |\n|---|---|---|---|---|\n");
    printf("| BVH (default) | %.3f | %.3f | %.2f | %ld |\n", t1 - t0, t2 - t1, 1e6 * (t2 - t1) / n, fa);
    printf("| FLANN single kd-tree | %.3f | %.3f | %.2f | %ld |\n", t3 - t2, t4 - t3, 1e6 * (t4 - t3) / n, fb);
    surface_map_free(a);
    surface_map_free(b);
    photon_set_free(&ps);
    free(x);
    free(hit);
    scene_free(&s);
    return fa == fb ? 0 : 1;
}
