/* Internals of the scene module shared between its files. */
#ifndef DARTSPP_SCENE_INTERNAL_H
#define DARTSPP_SCENE_INTERNAL_H

#include "dartspp/scene.h"
#include "json_read.h"

/* Affine transform M = [x y z | position] (columns), as Tungsten's JSON transform builds it. */
typedef struct {
    vec3 x, y, z, pos;
} xform;

/* The largest |coordinate| of a position (camera, light, primitive) or of a vertex in world space: three
 * decades inside Embree's ray range (|origin| < 1.8e18, FLT_LARGE), which it asserts. */
#define SCENE_COORD_MAX 1e15

int xform_parse(json_ctx *c, const cJSON *v, const char *where, xform *out);
static inline vec3 xform_point(const xform *m, vec3 p)
{
    return v3_add(m->pos, v3_add(v3_scale(m->x, p.x), v3_add(v3_scale(m->y, p.y), v3_scale(m->z, p.z))));
}

/* A triangle list being built: positions (local, float), per-vertex normals and UVs, vertex indices. */
typedef struct {
    float *pos;       /* 3 per vertex */
    float *nrm;       /* 3 per vertex; zero where the file gives none */
    float *uv;        /* 2 per vertex; zero where the file gives none */
    uint32_t *idx;    /* 3 per triangle */
    uint32_t nv, nt;
    uint32_t cap_v, cap_t;
    int has_normals;  /* the file gave vertex normals */
    int has_uvs;      /* the file gave texture coordinates */
} tri_mesh;

void tri_mesh_free(tri_mesh *m);
/* Edges shared by exactly two triangles (vertices welded by position) and how many of them join triangles
 * wound in opposite directions, so that the front side (ext_medium's) flips across them. -1: out of memory. */
int tri_mesh_winding(const tri_mesh *m, uint32_t *shared, uint32_t *flipped);
/* Appends a vertex with zero normal and UV (set m->nrm / m->uv of index m->nv - 1 afterwards). */
int tri_mesh_add_vertex(tri_mesh *m, double x, double y, double z);
int tri_mesh_add_tri(tri_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/* Tungsten's smooth vertex normals (`recompute_normals` with `smooth`): a vertex whose faces differ by
 * more than the split angle (cos 0.15π) is duplicated; each vertex gets the area-weighted normal of the
 * faces around its position that lie within the split angle of its own face. -1 when out of memory. */
int tri_mesh_smooth_normals(tri_mesh *m);
#define MESH_SPLIT_COS 0.89100652418836786 /* cos(0.15π) */

int mesh_load_wo3(const char *path, tri_mesh *m, dp_error *err);
int mesh_load_obj(const char *path, tri_mesh *m, dp_error *err);
void mesh_make_quad(tri_mesh *m);   /* unit square in the local xz-plane, normal +y */
void mesh_make_cube(tri_mesh *m);   /* [-0.5, 0.5]^3, outward normals */
/* Tessellations of Tungsten's analytic shapes (the renderer traces triangles only): */
void mesh_make_disk(tri_mesh *m);   /* unit disk in the local xz-plane, normal +y, MESH_DISK_SEGMENTS around */
void mesh_make_sphere(tri_mesh *m); /* unit sphere, outward normals, smooth vertex normals */
#define MESH_DISK_SEGMENTS 256
#define MESH_SPHERE_RINGS 64        /* latitude bands; twice as many longitude segments */

/* ---- per-triangle attributes and per-surface flags, private to the scene module ----
 * scene.rt_scene points to this record (the Embree scene is one of its members), so that the public
 * struct stays as it is. Corner arrays are indexed by the global triangle index and exist only when some
 * surface needs them. */
#define SURF_SMOOTH 1u   /* `smooth`: interpolated vertex normals as shading normal */
#define SURF_CULL 2u     /* `backface_culling`: hits with d·ng > 0 are ignored */
#define SURF_UV 4u       /* the mesh has texture coordinates */
typedef struct {
    void *rtc;               /* RTCScene, once built */
    float *corner_n;         /* 9 floats per triangle: unit world vertex normals of its corners (smooth surfaces) */
    float *corner_uv;        /* 6 floats per triangle: UVs of its corners (surfaces with UVs) */
    uint32_t corner_cap;     /* triangles allocated in each corner array present */
    unsigned char *flags;    /* per surface (geomID): SURF_* bits */
    int flag_cap;
} scene_rt;

/* The record (created on first use; NULL when out of memory). */
scene_rt *scene_rt_get(scene *s);
/* Stores a mesh's attributes for triangles [first, first + m->nt) of surface `surf`: normals (world, by
 * the normal matrix of T) when smooth, UVs when the mesh has them, and the flags. -1 when out of memory. */
int scene_rt_add_mesh(scene *s, int surf, uint32_t first, const tri_mesh *m, const xform *T, unsigned flags);

/* Embree scene over s->verts/s->tris, one geometry per surface (geomID = surface index). */
int scene_build_embree(scene *s, dp_error *err);
void scene_release_embree(scene *s);

/* ---- media and emitters (media_load.c, light_load.c) ---- */
/* The scene file's `media` array into s->media. 0, or -1 with the error in c. */
int parse_media(json_ctx *c, const cJSON *root, scene *s);
/* Frees a medium's tabulated phase function (the scene owns it; scene_free calls this for every medium). */
void medium_free_phase(medium *m);
/* A medium reference: a name, null or "" (vacuum), or an inline object (appended to s->media). */
int medium_ref(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *key, int *out);
/* A clear region (σs = σa = 0) where light travels at `speed`: found among the media or appended (Liu et al.'s
 * int_speed_of_light / ext_speed_of_light on a side of a surface that has no medium). */
int clear_region(json_ctx *c, scene *s, double speed, const char *where, const char *key, int *out);
/* lidar_load.c: a lidar camera's keys into cam (docs/lidar.md §2), then, once the integrator keys are read, its
 * beam as the scene's one light and its range bins as the time window (docs/lidar.md §1). */
int lidar_parse_camera(json_ctx *c, const cJSON *v, camera *cam);
int lidar_finish_scene(json_ctx *c, const cJSON *root, scene *s, int derivatives);

/* A primitive of an emitter type (emitter_ops_find: point, spot, collimated, directional_point), appended to
 * s->lights. */
int light_parse(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, const xform *T);
/* The emission of surface sf (its triangles appended, not yet in s->surfaces): an area light appended to
 * s->lights, sf->emitter set. */
int light_parse_area(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, surface *sf);

/* ---- BSDFs and textures ---- */
/* A bsdf object of the scene file (docs/scene-format.md §2.4); textures are loaded into s->textures. */
int bsdf_parse(json_ctx *c, const cJSON *v, const char *where, scene *s, bsdf *b);
/* The texture file `file` (relative to the scene's folder) for key `key` of `where`: *index into
 * s->textures (a file already loaded is shared), or -1 with a warning in the notes when the file does not
 * exist. Returns -1 with an error naming the file, the key and the decoder's reason when it cannot be read. */
int texture_fetch(json_ctx *c, scene *s, const char *where, const char *key, const char *file, int *index);
vec3 texture_mean(const texture *t);
void texture_free_all(scene *s);

/* ---- derivatives (diff_params.c; docs/derivatives.md §1) ---- */
/* What a JSON primitive became: its surface (or -1) and its light (or -1, an area light's or a light primitive's),
 * recorded by the loader per index of `primitives`. */
typedef struct {
    int surface, light;
} prim_slot;
/* The `--derivative` JSON Pointers into s->diffs[], s->diff_count, against the parsed file (root, with the --set
 * overrides applied) and the loaded scene. 0, or -1 with the error (file, pointer, reason) in c. */
int diff_params_resolve(json_ctx *c, const cJSON *root, scene *s, const prim_slot *prims, int prim_count,
                        const char *const *pointers, int count);

#endif
