/* The primitives' BVH of one iteration: their bounds (slice_build.c) in Morton order of the box centres
 * (dp_morton_order, shared with the beam map of src/photon_beams), split at the middle (a linear BVH), leaves of
 * at most SLICE_LEAF primitives, nodes depth-first with the largest time budget below them. The query is a
 * slab test of the camera segment per node; the visit order is fixed by the tree, so images do not depend on
 * the thread count. */
#include <stdlib.h>
#include <string.h>

#include "slice_internal.h"

#define SLICE_LEAF 4

typedef struct {
    float lo[3], hi[3];
    float budget;      /* the largest τ_k − τ(x) of its primitives */
    uint32_t first;    /* leaf: first primitive; inner: the right child (the left one follows) */
    uint32_t count;    /* leaf: primitives; 0: inner */
} slice_node;

struct slice_map {
    path_vertex *verts;
    size_t n_verts;
    slice_prim *prims; /* in leaf order */
    size_t n;
    slice_node *nodes;
    size_t n_nodes;
};

typedef struct {
    slice_map *m;
    const slice_box *box; /* in Morton order */
    size_t next;
} tree_builder;

static void grow(slice_node *nd, const float *lo, const float *hi, float budget)
{
    for (int k = 0; k < 3; k++) {
        if (lo[k] < nd->lo[k]) nd->lo[k] = lo[k];
        if (hi[k] > nd->hi[k]) nd->hi[k] = hi[k];
    }
    if (budget > nd->budget) nd->budget = budget;
}

static void build_tree(tree_builder *B, size_t lo, size_t hi)
{
    slice_node *nd = &B->m->nodes[B->next++];
    *nd = (slice_node){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, -INFINITY, 0, 0};
    if (hi - lo <= SLICE_LEAF) {
        for (size_t i = lo; i < hi; i++) grow(nd, B->box[i].lo, B->box[i].hi, B->box[i].budget);
        nd->first = (uint32_t)lo;
        nd->count = (uint32_t)(hi - lo);
        return;
    }
    size_t mid = lo + (hi - lo) / 2;
    slice_node *left = &B->m->nodes[B->next];
    build_tree(B, lo, mid);
    slice_node *right = &B->m->nodes[B->next];
    nd->first = (uint32_t)B->next;
    build_tree(B, mid, hi);
    grow(nd, left->lo, left->hi, left->budget);
    grow(nd, right->lo, right->hi, right->budget);
}

slice_map *slice_map_build(const scene *s, const slice_build_input *in, const path_vertex *v, size_t n, dp_error *err)
{
    slice_map *m = calloc(1, sizeof *m);
    slice_prim *prims = NULL;
    slice_box *box = NULL, *sorted = NULL;
    uint32_t *order = NULL;
    size_t np = 0;
    int rc = m ? 0 : -1;
    if (!rc) rc = slice_build(s, in, v, n, &prims, &box, &np);
    if (!rc) {
        m->verts = malloc((n ? n : 1) * sizeof *m->verts);
        m->prims = malloc((np ? np : 1) * sizeof *m->prims);
        m->nodes = malloc((np ? 2 * np : 1) * sizeof *m->nodes);
        order = malloc((np ? np : 1) * sizeof *order);
        sorted = malloc((np ? np : 1) * sizeof *sorted);
        rc = m->verts && m->prims && m->nodes && order && sorted ? 0 : -1;
    }
    if (!rc && np) rc = dp_morton_order(box[0].c, sizeof *box / sizeof(float), np, 3, order);
    if (!rc) {
        if (n) memcpy(m->verts, v, n * sizeof *v);
        m->n_verts = n;
        for (size_t i = 0; i < np; i++) {
            sorted[i] = box[order[i]];
            m->prims[i] = prims[sorted[i].prim];
        }
        m->n = np;
        tree_builder B = {m, sorted, 0};
        if (np) build_tree(&B, 0, np);
        m->n_nodes = B.next;
    }
    free(prims);
    free(box);
    free(sorted);
    free(order);
    if (rc) {
        slice_map_free(m);
        dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory building the sliced primitives", s->path);
        return NULL;
    }
    return m;
}

void slice_map_free(slice_map *m)
{
    if (!m) return;
    free(m->verts);
    free(m->prims);
    free(m->nodes);
    free(m);
}

size_t slice_map_size(const slice_map *m) { return m ? m->n : 0; }
const path_vertex *slice_map_vertices(const slice_map *m) { return m ? m->verts : NULL; }

double slice_map_bytes(int type, double n)
{
    double kinds = 0.0;
    for (int k = 0; k < SLICE_KIND_COUNT; k++) kinds += slice_type_builds(type, k, ~0u & ~PATH_VERTEX_DELTA) ? 1.0 : 0.0;
    double per_prim = 2.0 * sizeof(slice_prim) + 2.0 * sizeof(slice_box) + sizeof(uint32_t) + 2.0 * sizeof(slice_node);
    return n * sizeof(path_vertex) + n * kinds * per_prim;
}

/* Whether the segment o + t·d, t in [0, tmax], meets the box [lo, hi] (slabs; inv = 1/d). */
static int segment_meets(const float *lo, const float *hi, const double *o, const double *inv, double tmax)
{
    double near = 0.0, far = tmax;
    for (int k = 0; k < 3; k++) {
        double ta = ((double)lo[k] - o[k]) * inv[k], tb = ((double)hi[k] - o[k]) * inv[k];
        double a = fmin(ta, tb), b = fmax(ta, tb); /* fmin/fmax drop the NaN of 0·inf (a ray in the plane) */
        if (ta != ta || tb != tb) a = -INFINITY, b = INFINITY;
        near = fmax(near, a);
        far = fmin(far, b);
        if (near > far) return 0;
    }
    return 1;
}

void slice_map_query(const slice_map *m, vec3 o, vec3 d, double tmax, double t_cam, slice_visit_fn visit, void *ctx)
{
    if (!m || m->n == 0) return;
    double oo[3] = {o.x, o.y, o.z}, inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const slice_node *nd = &m->nodes[stack[--top]];
        if (!(nd->budget > t_cam) || !segment_meets(nd->lo, nd->hi, oo, inv, tmax)) continue;
        if (nd->count) {
            for (uint32_t i = 0; i < nd->count; i++) visit(ctx, &m->prims[nd->first + i]);
            continue;
        }
        stack[top++] = nd->first;
        stack[top++] = (uint32_t)(nd - m->nodes) + 1;
    }
}

void sliced_primitives_memory(int type, double V, memory_estimate *m)
{
    memory_item_add(m, "light-path vertices, sliced primitives and their map", "integrator.volume_photon_count",
                    path_vertex_array_bytes(V) + slice_map_bytes(type, V));
}
