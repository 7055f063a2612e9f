/* Per-triangle shading attributes (corner normals and UVs) and per-surface flags, kept beside the Embree
 * scene in the scene_rt record (scene_internal.h). Normals go to world space by the normal matrix
 * (inverse transpose of the transform's linear part), as Tungsten's TriangleMesh does. */
#include "scene_internal.h"

#include <stdlib.h>
#include <string.h>

scene_rt *scene_rt_get(scene *s)
{
    if (!s->rt_scene) s->rt_scene = calloc(1, sizeof(scene_rt));
    return s->rt_scene;
}

/* Grows one corner array (per triangle `per` floats) to cap triangles, zero-filling the new part. */
static int grow_corners(float **a, uint32_t old_cap, uint32_t cap, int per)
{
    float *g = realloc(*a, (size_t)cap * (size_t)per * sizeof(float));
    if (!g) return -1;
    memset(g + (size_t)old_cap * (size_t)per, 0, (size_t)(cap - old_cap) * (size_t)per * sizeof(float));
    *a = g;
    return 0;
}

/* Makes room for triangles [0, end) in the corner arrays that exist, and creates the ones `need` asks for
 * (bit 0: normals, bit 1: UVs). */
static int reserve_corners(scene_rt *rt, uint32_t end, unsigned need)
{
    uint32_t cap = rt->corner_cap;
    if (end > cap) {
        cap = cap ? cap : 1024;
        while (cap < end) cap = cap > (1u << 30) ? end : cap * 2;
    }
    if (rt->corner_n && cap > rt->corner_cap && grow_corners(&rt->corner_n, rt->corner_cap, cap, 9)) return -1;
    if (rt->corner_uv && cap > rt->corner_cap && grow_corners(&rt->corner_uv, rt->corner_cap, cap, 6)) return -1;
    if ((need & 1) && !rt->corner_n && grow_corners(&rt->corner_n, 0, cap, 9)) return -1;
    if ((need & 2) && !rt->corner_uv && grow_corners(&rt->corner_uv, 0, cap, 6)) return -1;
    rt->corner_cap = cap;
    return 0;
}

static vec3 normal_to_world(const xform *T, const float *n)
{
    vec3 yz = v3_cross(T->y, T->z), zx = v3_cross(T->z, T->x), xy = v3_cross(T->x, T->y);
    double det = v3_dot(T->x, yz);
    vec3 w = v3_add(v3_scale(yz, n[0]), v3_add(v3_scale(zx, n[1]), v3_scale(xy, n[2])));
    double l = v3_len(w);
    if (!(l > 0.0) || !isfinite(l) || det == 0.0) return v3s(0.0); /* absent: shading falls back to ng */
    return v3_scale(w, (det < 0.0 ? -1.0 : 1.0) / l);
}

int scene_rt_add_mesh(scene *s, int surf, uint32_t first, const tri_mesh *m, const xform *T, unsigned flags)
{
    scene_rt *rt = scene_rt_get(s);
    if (!rt) return -1;
    if (surf >= rt->flag_cap) {
        int cap = rt->flag_cap ? rt->flag_cap * 2 : 64;
        while (cap <= surf) cap *= 2;
        unsigned char *g = realloc(rt->flags, (size_t)cap);
        if (!g) return -1;
        memset(g + rt->flag_cap, 0, (size_t)(cap - rt->flag_cap));
        rt->flags = g;
        rt->flag_cap = cap;
    }
    int smooth = (flags & SURF_SMOOTH) != 0, uvs = m->has_uvs;
    if (uvs) flags |= SURF_UV;
    rt->flags[surf] = (unsigned char)flags;
    if (reserve_corners(rt, first + m->nt, (smooth ? 1u : 0u) | (uvs ? 2u : 0u))) return -1;
    for (uint32_t t = 0; t < m->nt; t++) {
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->idx[3 * (size_t)t + k];
            size_t at = (size_t)(first + t);
            if (smooth) {
                vec3 n = normal_to_world(T, &m->nrm[3 * (size_t)v]);
                float *dst = &rt->corner_n[9 * at + 3 * (size_t)k];
                dst[0] = (float)n.x;
                dst[1] = (float)n.y;
                dst[2] = (float)n.z;
            }
            if (uvs) memcpy(&rt->corner_uv[6 * at + 2 * (size_t)k], &m->uv[2 * (size_t)v], 2 * sizeof(float));
        }
    }
    return 0;
}
