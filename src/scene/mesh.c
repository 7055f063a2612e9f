/* Triangle lists: growth, and the built-in quad and cube shapes. */
#include "scene_internal.h"

#include <stdlib.h>

void tri_mesh_free(tri_mesh *m)
{
    free(m->pos);
    free(m->idx);
    *m = (tri_mesh){0};
}

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap) return 0;
    uint32_t c = *cap ? *cap : 64;
    while (c < need) {
        if (c > (1u << 30)) return -1;
        c *= 2;
    }
    void *q = realloc(*p, (size_t)c * elem);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

int tri_mesh_add_vertex(tri_mesh *m, double x, double y, double z)
{
    if (grow((void **)&m->pos, &m->cap_v, m->nv + 1, 3 * sizeof(float))) return -1;
    m->pos[3 * m->nv] = (float)x;
    m->pos[3 * m->nv + 1] = (float)y;
    m->pos[3 * m->nv + 2] = (float)z;
    m->nv++;
    return 0;
}

int tri_mesh_add_tri(tri_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (grow((void **)&m->idx, &m->cap_t, m->nt + 1, 3 * sizeof(uint32_t))) return -1;
    m->idx[3 * m->nt] = a;
    m->idx[3 * m->nt + 1] = b;
    m->idx[3 * m->nt + 2] = c;
    m->nt++;
    return 0;
}

void mesh_make_quad(tri_mesh *m)
{
    /* corners base, base+e1, base+e0, base+e0+e1 with e0 = x, e1 = z: (p1-p0)x(p2-p0) = z x x = +y */
    tri_mesh_add_vertex(m, -0.5, 0, -0.5);
    tri_mesh_add_vertex(m, -0.5, 0, 0.5);
    tri_mesh_add_vertex(m, 0.5, 0, -0.5);
    tri_mesh_add_vertex(m, 0.5, 0, 0.5);
    tri_mesh_add_tri(m, 0, 1, 2);
    tri_mesh_add_tri(m, 1, 3, 2);
}

void mesh_make_cube(tri_mesh *m)
{
    for (int i = 0; i < 8; i++) tri_mesh_add_vertex(m, (i & 1) ? 0.5 : -0.5, (i & 2) ? 0.5 : -0.5, (i & 4) ? 0.5 : -0.5);
    /* two triangles per face, counter-clockwise seen from outside */
    static const uint32_t f[12][3] = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5},  /* -x, +x */
                                      {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},  /* -y, +y */
                                      {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}}; /* -z, +z */
    for (int i = 0; i < 12; i++) tri_mesh_add_tri(m, f[i][0], f[i][1], f[i][2]);
}
