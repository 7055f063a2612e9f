/* Whether a mesh's triangles agree on which side is the front: the side that ext_medium binds
 * (docs/scene-format.md §2.6). Written by hand: a sort of welded edges, no library needed. */
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"

typedef struct {
    float p[3];
    uint32_t i;
} welded_vertex;

typedef struct {
    uint32_t a, b; /* welded ends, a < b */
    int forward;   /* the triangle runs a → b */
} mesh_edge;

static int cmp_vertex(const void *x, const void *y)
{
    const welded_vertex *u = x, *v = y;
    int c = memcmp(u->p, v->p, sizeof u->p); /* any total order that groups equal positions */
    return c ? c : (u->i > v->i) - (u->i < v->i);
}

static int cmp_edge(const void *x, const void *y)
{
    const mesh_edge *u = x, *v = y;
    if (u->a != v->a) return u->a < v->a ? -1 : 1;
    return (u->b > v->b) - (u->b < v->b);
}

/* Vertices at the same position get one id (a .wo3 often repeats a corner per face). */
static uint32_t *weld_vertices(const tri_mesh *m)
{
    welded_vertex *w = malloc((size_t)m->nv * sizeof *w);
    uint32_t *id = malloc((size_t)m->nv * sizeof *id);
    if (!w || !id) {
        free(w), free(id);
        return NULL;
    }
    for (uint32_t i = 0; i < m->nv; i++) {
        memcpy(w[i].p, &m->pos[3 * (size_t)i], sizeof w[i].p);
        w[i].p[0] += 0.0f, w[i].p[1] += 0.0f, w[i].p[2] += 0.0f; /* -0 and +0 alike */
        w[i].i = i;
    }
    qsort(w, m->nv, sizeof *w, cmp_vertex);
    for (uint32_t k = 0, first = 0; k < m->nv; k++) {
        if (k > 0 && memcmp(w[k].p, w[k - 1].p, sizeof w[k].p)) first = k;
        id[w[k].i] = w[first].i;
    }
    free(w);
    return id;
}

int tri_mesh_winding(const tri_mesh *m, uint32_t *shared, uint32_t *flipped)
{
    *shared = *flipped = 0;
    if (m->nt == 0) return 0;
    uint32_t *id = weld_vertices(m);
    mesh_edge *e = malloc(3 * (size_t)m->nt * sizeof *e);
    if (!id || !e) {
        free(id), free(e);
        return -1;
    }
    size_t n = 0;
    for (uint32_t t = 0; t < m->nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = id[m->idx[3 * (size_t)t + k]], v = id[m->idx[3 * (size_t)t + (k + 1) % 3]];
            if (u != v) e[n++] = (mesh_edge){u < v ? u : v, u < v ? v : u, u < v};
        }
    qsort(e, n, sizeof *e, cmp_edge);
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && !cmp_edge(&e[i], &e[j])) j++;
        if (j - i == 2) { /* two consistently wound triangles run their shared edge in opposite directions */
            (*shared)++;
            *flipped += e[i].forward == e[i + 1].forward;
        }
        i = j;
    }
    free(id), free(e);
    return 0;
}
