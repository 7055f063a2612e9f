/* bench/mirror_mask SCENE.json SURFACE OUT.pfm [--set key=value ...]: 1 where the camera ray through a pixel's centre first meets
 * SURFACE (a name, or primitives[i] as the run summary prints it) after any null/forward surfaces, else 0.
 * The mask of a mirror's region for `dartspp patch-mean IMAGE ... --mask OUT.pfm` (bench/dragon_mirror.sh). */
#include <stdio.h>
#include <string.h>

#include "dartspp/io.h"
#include "dartspp/scene.h"

static int first_opaque_surface(const scene *s, vec3 o, vec3 d)
{
    hit_record h;
    for (int hop = 0; hop < 64; hop++) {
        if (!scene_intersect(s, o, d, INFINITY, &h)) return -1;
        if (!bsdf_is_passthrough(&s->bsdfs[s->surfaces[h.surface].bsdf])) return h.surface;
        o = scene_offset_ray_origin(s, h.p, v3_dot(d, h.ng) < 0.0 ? v3_neg(h.ng) : h.ng);
    }
    return -1;
}

int main(int argc, char **argv)
{
    const char *sets[64];
    int nsets = 0;
    for (int i = 4; i + 1 < argc && !strcmp(argv[i], "--set") && nsets < 64; i += 2) sets[nsets++] = argv[i + 1];
    if (argc < 4 || argc != 4 + 2 * nsets) {
        fprintf(stderr, "usage: mirror_mask SCENE.json SURFACE OUT.pfm [--set key=value ...]\n");
        return 2;
    }
    scene s;
    dp_error err;
    scene_load_options opt = {.sets = sets, .set_count = nsets};
    if (scene_load(argv[1], &opt, &s, &err)) {
        fprintf(stderr, "mirror_mask: %s\n", err.msg);
        return 2;
    }
    int target = -1;
    for (int i = 0; i < s.surface_count; i++)
        if (!strcmp(s.surfaces[i].name, argv[2])) target = i;
    if (target < 0) {
        fprintf(stderr, "mirror_mask: %s: no surface named '%s'\n", argv[1], argv[2]);
        return 2;
    }
    image_rgb m;
    if (image_alloc(&m, s.cam.width, s.cam.height, &err)) return 2;
    long n = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : n)
    for (int y = 0; y < s.cam.height; y++)
        for (int x = 0; x < s.cam.width; x++) {
            int hit = first_opaque_surface(&s, s.cam.pos, camera_ray_dir(&s.cam, x + 0.5, y + 0.5)) == target;
            for (int c = 0; c < 3; c++) m.rgb[3 * ((size_t)y * s.cam.width + x) + c] = (float)hit;
            n += hit;
        }
    if (image_write(argv[3], &m, NULL, &err)) {
        fprintf(stderr, "mirror_mask: %s\n", err.msg);
        return 2;
    }
    fprintf(stderr, "mirror_mask: %ld of %d pixels see '%s' first\n", n, s.cam.width * s.cam.height, argv[2]);
    image_free(&m);
    scene_free(&s);
    return 0;
}
