/* Triangle lists: growth, and the built-in quad and cube shapes (with Tungsten's UVs). */
#include "scene_internal.h"

#include <stdlib.h>

void tri_mesh_free(tri_mesh *m)
{
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    free(m->idx);
    *m = (tri_mesh){0};
}

static uint32_t grown_cap(uint32_t cap, uint32_t need)
{
    uint32_t c = cap ? cap : 64;
    while (c < need) {
        if (c > (1u << 30)) return 0;
        c *= 2;
    }
    return c;
}

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap) return 0;
    uint32_t c = grown_cap(*cap, need);
    void *q = c ? realloc(*p, (size_t)c * elem) : NULL;
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

int tri_mesh_add_vertex(tri_mesh *m, double x, double y, double z)
{
    if (m->nv + 1 > m->cap_v) {
        uint32_t c = grown_cap(m->cap_v, m->nv + 1);
        float *p = c ? realloc(m->pos, (size_t)c * 3 * sizeof(float)) : NULL;
        if (p) m->pos = p;
        float *n = p ? realloc(m->nrm, (size_t)c * 3 * sizeof(float)) : NULL;
        if (n) m->nrm = n;
        float *t = n ? realloc(m->uv, (size_t)c * 2 * sizeof(float)) : NULL;
        if (!t) return -1;
        m->uv = t;
        m->cap_v = c;
    }
    float *p = &m->pos[3 * (size_t)m->nv], *n = &m->nrm[3 * (size_t)m->nv], *t = &m->uv[2 * (size_t)m->nv];
    p[0] = (float)x;
    p[1] = (float)y;
    p[2] = (float)z;
    n[0] = n[1] = n[2] = 0.0f;
    t[0] = t[1] = 0.0f;
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

/* Tungsten's quad: u along local x, v along local z, each from 0 at -0.5 to 1 at +0.5. */
void mesh_make_quad(tri_mesh *m)
{
    /* corners base, base+e1, base+e0, base+e0+e1 with e0 = x, e1 = z: (p1-p0)x(p2-p0) = z x x = +y */
    static const float c[4][2] = {{-0.5f, -0.5f}, {-0.5f, 0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}};
    for (int i = 0; i < 4; i++) {
        if (tri_mesh_add_vertex(m, c[i][0], 0, c[i][1])) return;
        m->uv[2 * i] = c[i][0] + 0.5f;
        m->uv[2 * i + 1] = c[i][1] + 0.5f;
    }
    m->has_uvs = 1;
    tri_mesh_add_tri(m, 0, 1, 2);
    tri_mesh_add_tri(m, 1, 3, 2);
}

/* [-0.5, 0.5]^3 with four vertices per face, so that each face carries Tungsten's cube UVs: on the face
 * across axis d, (u, v) = (p[(d+1)%3] + 0.5, p[(d+2)%3] + 0.5). Counter-clockwise seen from outside. */
void mesh_make_cube(tri_mesh *m)
{
    for (int d = 0; d < 3; d++) {
        int a = (d + 1) % 3, b = (d + 2) % 3;
        for (int side = -1; side <= 1; side += 2) {
            uint32_t base = m->nv;
            static const float q[4][2] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
            for (int k = 0; k < 4; k++) {
                float p[3];
                p[d] = 0.5f * (float)side;
                p[a] = q[k][0];
                p[b] = q[k][1];
                if (tri_mesh_add_vertex(m, p[0], p[1], p[2])) return;
                m->uv[2 * (size_t)(base + k)] = q[k][0] + 0.5f;
                m->uv[2 * (size_t)(base + k) + 1] = q[k][1] + 0.5f;
            }
            /* (a, b, d) is a right-handed cycle, so a x b = +d: the order 0,1,2 faces +d */
            if (side > 0) {
                tri_mesh_add_tri(m, base, base + 1, base + 2);
                tri_mesh_add_tri(m, base, base + 2, base + 3);
            } else {
                tri_mesh_add_tri(m, base, base + 2, base + 1);
                tri_mesh_add_tri(m, base, base + 3, base + 2);
            }
        }
    }
    m->has_uvs = 1;
}

/* Tungsten's disk: radius 1 in the local xz-plane, emitting and facing +y. A fan of MESH_DISK_SEGMENTS
 * triangles from the centre; (c, p_{k+1}, p_k) winds to +y. UVs as Tungsten's: (φ/(2π) + ½, ρ). */
void mesh_make_disk(tri_mesh *m)
{
    const int n = MESH_DISK_SEGMENTS;
    if (tri_mesh_add_vertex(m, 0, 0, 0)) return;
    m->uv[0] = 0.5f;
    m->uv[1] = 0.0f;
    for (int k = 0; k <= n; k++) { /* the seam vertex twice, so that u runs 0..1 */
        double phi = 2.0 * M_PI * k / n - M_PI;
        if (tri_mesh_add_vertex(m, cos(phi), 0, sin(phi))) return;
        m->uv[2 * (size_t)(k + 1)] = (float)((double)k / n);
        m->uv[2 * (size_t)(k + 1) + 1] = 1.0f;
    }
    m->has_uvs = 1;
    for (int k = 0; k < n; k++) tri_mesh_add_tri(m, 0, (uint32_t)k + 2, (uint32_t)k + 1);
}

/* Tungsten's sphere: radius 1 about the origin. MESH_SPHERE_RINGS bands of latitude, twice as many
 * segments of longitude, the poles as fans; vertex normals radial; outward winding. */
void mesh_make_sphere(tri_mesh *m)
{
    const int nr = MESH_SPHERE_RINGS, ns = 2 * MESH_SPHERE_RINGS;
    for (int i = 0; i <= nr; i++) {
        double theta = M_PI * i / nr;
        for (int j = 0; j <= ns; j++) {
            double phi = 2.0 * M_PI * j / ns;
            double x = sin(theta) * cos(phi), y = cos(theta), z = sin(theta) * sin(phi);
            if (tri_mesh_add_vertex(m, x, y, z)) return;
            size_t v = m->nv - 1;
            m->nrm[3 * v] = (float)x, m->nrm[3 * v + 1] = (float)y, m->nrm[3 * v + 2] = (float)z;
            m->uv[2 * v] = (float)((double)j / ns);
            m->uv[2 * v + 1] = (float)(1.0 - (double)i / nr);
        }
    }
    m->has_normals = m->has_uvs = 1;
    for (int i = 0; i < nr; i++)
        for (int j = 0; j < ns; j++) {
            uint32_t a = (uint32_t)(i * (ns + 1) + j), b = a + 1, c = a + (uint32_t)(ns + 1), d = c + 1;
            /* seen from outside, (a, b, c) runs counter-clockwise: a at θ_i, b at φ + dφ, c at θ + dθ */
            if (i > 0) tri_mesh_add_tri(m, a, b, c);
            if (i < nr - 1) tri_mesh_add_tri(m, b, d, c);
        }
}
