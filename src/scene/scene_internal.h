/* Internals of the scene module shared between its files. */
#ifndef DARTSPP_SCENE_INTERNAL_H
#define DARTSPP_SCENE_INTERNAL_H

#include "dartspp/scene.h"
#include "json_read.h"

/* Affine transform M = [x y z | position] (columns), as Tungsten's JSON transform builds it. */
typedef struct {
    vec3 x, y, z, pos;
} xform;

int xform_parse(json_ctx *c, const cJSON *v, const char *where, xform *out);
static inline vec3 xform_point(const xform *m, vec3 p)
{
    return v3_add(m->pos, v3_add(v3_scale(m->x, p.x), v3_add(v3_scale(m->y, p.y), v3_scale(m->z, p.z))));
}

/* A triangle list being built: positions (local, float) and vertex indices. */
typedef struct {
    float *pos;       /* 3 per vertex */
    uint32_t *idx;    /* 3 per triangle */
    uint32_t nv, nt;
    uint32_t cap_v, cap_t;
} tri_mesh;

void tri_mesh_free(tri_mesh *m);
int tri_mesh_add_vertex(tri_mesh *m, double x, double y, double z);
int tri_mesh_add_tri(tri_mesh *m, uint32_t a, uint32_t b, uint32_t c);

int mesh_load_wo3(const char *path, tri_mesh *m, dp_error *err);
int mesh_load_obj(const char *path, tri_mesh *m, dp_error *err);
void mesh_make_quad(tri_mesh *m);   /* unit square in the local xz-plane, normal +y */
void mesh_make_cube(tri_mesh *m);   /* [-0.5, 0.5]^3, outward normals */

/* Embree scene over s->verts/s->tris, one geometry per surface (geomID = surface index). */
int scene_build_embree(scene *s, dp_error *err);
void scene_release_embree(scene *s);

#endif
