/* Smooth vertex normals recomputed from the faces (`recompute_normals` with `smooth`), as Tungsten's
 * TriangleMesh::calcSmoothVertexNormals defines them: in local space, before the transform.
 *
 * 1. Each vertex takes the unit normal of the first face that uses it. A later face whose normal is more
 *    than the split angle away (cosine below MESH_SPLIT_COS) gets its own copy of the vertex.
 * 2. Vertices at the same position form a group (files often duplicate a position for UV seams). Each
 *    vertex sums the unnormalised (area-weighted) normals of the faces touching its group whose normal is
 *    within the split angle of its own first face, and is normalised; a vertex with no such face keeps
 *    its face normal. */
#include "scene_internal.h"

#include <stdlib.h>
#include <string.h>

static vec3 pos_of(const tri_mesh *m, uint32_t i)
{
    return v3(m->pos[3 * (size_t)i], m->pos[3 * (size_t)i + 1], m->pos[3 * (size_t)i + 2]);
}

static vec3 face_cross(const tri_mesh *m, uint32_t t)
{
    const uint32_t *c = &m->idx[3 * (size_t)t];
    vec3 p0 = pos_of(m, c[0]);
    return v3_cross(v3_sub(pos_of(m, c[1]), p0), v3_sub(pos_of(m, c[2]), p0));
}

/* unit face normal; +y for a degenerate face (as the reference) */
static vec3 face_unit(const tri_mesh *m, uint32_t t)
{
    vec3 n = face_cross(m, t);
    double l = v3_len(n);
    return l > 0.0 ? v3_scale(n, 1.0 / l) : v3(0, 1, 0);
}

/* Step 1: a vertex copy for every corner whose face disagrees with the vertex's first face. */
static int split_vertices(tri_mesh *m, vec3 **first_n)
{
    vec3 *fn = calloc((size_t)m->nv + 1, sizeof(vec3));
    unsigned char *set = calloc((size_t)m->nv + 1, 1);
    uint32_t cap = m->nv + 1;
    if (!fn || !set) goto oom;
    for (uint32_t t = 0; t < m->nt; t++) {
        vec3 n = face_unit(m, t);
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->idx[3 * (size_t)t + k];
            if (!set[v]) {
                set[v] = 1;
                fn[v] = n;
                continue;
            }
            if (v3_dot(fn[v], n) >= MESH_SPLIT_COS) continue;
            uint32_t w = m->nv;
            if (tri_mesh_add_vertex(m, m->pos[3 * (size_t)v], m->pos[3 * (size_t)v + 1], m->pos[3 * (size_t)v + 2]))
                goto oom;
            memcpy(&m->uv[2 * (size_t)w], &m->uv[2 * (size_t)v], 2 * sizeof(float));
            if (w >= cap) {
                uint32_t c2 = cap * 2 > w + 1 ? cap * 2 : w + 1;
                vec3 *f2 = realloc(fn, (size_t)c2 * sizeof(vec3));
                unsigned char *s2 = f2 ? realloc(set, c2) : NULL;
                if (f2) fn = f2;
                if (!s2) goto oom;
                set = s2;
                cap = c2;
            }
            fn[w] = n;
            set[w] = 1;
            m->idx[3 * (size_t)t + k] = w;
        }
    }
    free(set);
    *first_n = fn;
    return 0;
oom:
    free(fn);
    free(set);
    return -1;
}

typedef struct {
    float p[3];
    uint32_t v;
} pos_key;

static int cmp_key(const void *a, const void *b)
{
    const float *p = ((const pos_key *)a)->p, *q = ((const pos_key *)b)->p;
    for (int i = 0; i < 3; i++)
        if (p[i] != q[i]) return p[i] < q[i] ? -1 : 1;
    return 0;
}

int tri_mesh_smooth_normals(tri_mesh *m)
{
    vec3 *fn = NULL;
    if (split_vertices(m, &fn)) return -1;
    uint32_t nv = m->nv;
    pos_key *keys = malloc((size_t)nv * sizeof(pos_key) + 1);
    uint32_t *group = malloc((size_t)nv * sizeof(uint32_t) + 1); /* vertex -> first slot of its position in keys */
    vec3 *sum = calloc((size_t)nv + 1, sizeof(vec3));
    if (!keys || !group || !sum) {
        free(keys);
        free(group);
        free(sum);
        free(fn);
        return -1;
    }
    for (uint32_t i = 0; i < nv; i++) {
        memcpy(keys[i].p, &m->pos[3 * (size_t)i], 3 * sizeof(float));
        keys[i].v = i;
    }
    qsort(keys, nv, sizeof(pos_key), cmp_key);
    for (uint32_t i = 0, start = 0; i < nv; i++) {
        if (i > 0 && cmp_key(&keys[i - 1], &keys[i]) != 0) start = i;
        group[keys[i].v] = start;
    }
    for (uint32_t t = 0; t < m->nt; t++) {
        vec3 n = face_cross(m, t), nu = face_unit(m, t);
        for (int k = 0; k < 3; k++) {
            uint32_t g = group[m->idx[3 * (size_t)t + k]];
            for (uint32_t j = g; j < nv && cmp_key(&keys[g], &keys[j]) == 0; j++)
                if (v3_dot(fn[keys[j].v], nu) >= MESH_SPLIT_COS) sum[keys[j].v] = v3_add(sum[keys[j].v], n);
        }
    }
    for (uint32_t i = 0; i < nv; i++) {
        double l = v3_len(sum[i]);
        vec3 n = l > 0.0 ? v3_scale(sum[i], 1.0 / l) : fn[i];
        m->nrm[3 * (size_t)i] = (float)n.x;
        m->nrm[3 * (size_t)i + 1] = (float)n.y;
        m->nrm[3 * (size_t)i + 2] = (float)n.z;
    }
    m->has_normals = 1;
    free(keys);
    free(group);
    free(sum);
    free(fn);
    return 0;
}
