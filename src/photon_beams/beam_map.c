/* The beam BVH: a binary tree over the beams' boxes (the segment's box inflated by r), built by median splits
 * on the box centres along the largest extent, leaves of at most BEAM_LEAF beams, nodes in depth-first order.
 * Each node also keeps the earliest start time of its beams, so that a query with a time bound skips whole
 * subtrees. Single-threaded build (about 0.1 s per 10^6 beams); the query is a slab test per node and the
 * closest approach of two lines per beam. */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/photon_beams.h"

#define BEAM_LEAF 4

typedef struct {
    float lo[3], hi[3];
    double t_min;      /* earliest start time of its beams */
    uint32_t first;    /* leaf: first beam; inner: index of the right child (the left one follows) */
    uint32_t count;    /* beams of a leaf; 0: inner node */
} beam_node;

struct beam_map {
    photon_beam *beams;
    size_t n;
    beam_node *nodes;
    size_t n_nodes;
    double r;
};

typedef struct {
    float lo[3], hi[3], c[3];
} beam_box;

static void box_of(const photon_beam *b, double r, beam_box *x)
{
    for (int k = 0; k < 3; k++) {
        double a = b->start[k], e = b->start[k] + (double)b->dir[k] * b->length;
        double lo = a < e ? a : e, hi = a < e ? e : a;
        x->lo[k] = (float)(lo - r) - 1e-6f * (1.0f + fabsf((float)lo));
        x->hi[k] = (float)(hi + r) + 1e-6f * (1.0f + fabsf((float)hi));
        x->c[k] = (float)(0.5 * (lo + hi));
    }
}

typedef struct {
    beam_map *m;
    const beam_box *box;
    uint32_t *idx;
    size_t next;
} builder;

/* Partial sort of idx[lo, hi) so that idx[mid] has the median centre along axis (quickselect, the middle
 * element as pivot: deterministic). */
static void select_median(const beam_box *box, uint32_t *idx, size_t lo, size_t hi, size_t mid, int axis)
{
    ptrdiff_t l = (ptrdiff_t)lo, h = (ptrdiff_t)hi - 1, m = (ptrdiff_t)mid;
    while (l < h) {
        float pivot = box[idx[l + (h - l) / 2]].c[axis];
        ptrdiff_t i = l, j = h;
        while (i <= j) {
            while (box[idx[i]].c[axis] < pivot) i++;
            while (box[idx[j]].c[axis] > pivot) j--;
            if (i <= j) {
                uint32_t t = idx[i];
                idx[i++] = idx[j];
                idx[j--] = t;
            }
        }
        if (m <= j) h = j;
        else if (m >= i) l = i;
        else return;
    }
}

static void build(builder *B, size_t lo, size_t hi)
{
    size_t me = B->next++;
    beam_node *nd = &B->m->nodes[me];
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 3; k++) nd->lo[k] = INFINITY, nd->hi[k] = -INFINITY;
    nd->t_min = INFINITY;
    for (size_t i = lo; i < hi; i++) {
        const beam_box *x = &B->box[B->idx[i]];
        for (int k = 0; k < 3; k++) {
            nd->lo[k] = fminf(nd->lo[k], x->lo[k]);
            nd->hi[k] = fmaxf(nd->hi[k], x->hi[k]);
            clo[k] = fminf(clo[k], x->c[k]);
            chi[k] = fmaxf(chi[k], x->c[k]);
        }
        double t = B->m->beams[B->idx[i]].time;
        if (t < nd->t_min) nd->t_min = t;
    }
    if (hi - lo <= BEAM_LEAF) {
        nd->first = (uint32_t)lo;
        nd->count = (uint32_t)(hi - lo);
        return;
    }
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    size_t mid = lo + (hi - lo) / 2;
    select_median(B->box, B->idx, lo, hi, mid, axis);
    nd->count = 0;
    build(B, lo, mid);
    B->m->nodes[me].first = (uint32_t)B->next; /* nd may have moved: nodes is preallocated, it has not */
    build(B, mid, hi);
}

beam_map *beam_map_build(const photon_beam *b, size_t n, double r, dp_error *err)
{
    beam_map *m = calloc(1, sizeof *m);
    beam_box *box = n ? malloc(n * sizeof *box) : NULL;
    uint32_t *idx = n ? malloc(n * sizeof *idx) : NULL;
    if (m) {
        m->n = n;
        m->r = r;
        m->beams = n ? malloc(n * sizeof *m->beams) : NULL;
        m->nodes = n ? malloc(2 * n * sizeof *m->nodes) : NULL; /* < 2n nodes for any split */
    }
    if (!m || (n && (!box || !idx || !m->beams || !m->nodes)) || n > UINT32_MAX / 2) {
        free(box);
        free(idx);
        beam_map_free(m);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory building the beam map (%zu beams)", n), NULL;
    }
    for (size_t i = 0; i < n; i++) {
        idx[i] = (uint32_t)i;
        box_of(&b[i], r, &box[i]);
    }
    if (n) {
        memcpy(m->beams, b, n * sizeof *b);
        builder B = {m, box, idx, 0};
        build(&B, 0, n);
        m->n_nodes = B.next;
        /* the beams in leaf order */
        for (size_t i = 0; i < n; i++) m->beams[i] = b[idx[i]];
    }
    free(box);
    free(idx);
    return m;
}

void beam_map_free(beam_map *m)
{
    if (!m) return;
    free(m->beams);
    free(m->nodes);
    free(m);
}

size_t beam_map_size(const beam_map *m) { return m ? m->n : 0; }

double beam_map_bytes(double n) { return n * (sizeof(photon_beam) + 2.0 * sizeof(beam_node)); }

/* The slab test of the segment o + t·d, t in [0, tmax], against a node's box. */
static int hits_box(const beam_node *nd, const double *o, const double *inv, double tmax)
{
    double t0 = 0.0, t1 = tmax;
    for (int k = 0; k < 3; k++) {
        double a = (nd->lo[k] - o[k]) * inv[k], b = (nd->hi[k] - o[k]) * inv[k];
        if (a > b) {
            double t = a;
            a = b;
            b = t;
        }
        if (a != a) a = -INFINITY; /* 0·inf: the ray lies in the slab's plane */
        if (b != b) b = INFINITY;
        t0 = a > t0 ? a : t0;
        t1 = b < t1 ? b : t1;
        if (t0 > t1) return 0;
    }
    return 1;
}

/* Closest approach of the camera line o + t·d and the beam a + s·w (both unit): with w0 = o − a, b = d·w,
 * sin²θ = 1 − b², t = (b (w·w0) − d·w0)/sin²θ, s = (w·w0 − b (d·w0))/sin²θ. */
static void test_beam(const photon_beam *bm, vec3 o, vec3 d, double tmax, double r2, beam_hit_fn hit, void *ctx)
{
    vec3 w = v3(bm->dir[0], bm->dir[1], bm->dir[2]);
    vec3 w0 = v3_sub(o, v3(bm->start[0], bm->start[1], bm->start[2]));
    double b = v3_dot(d, w), sin2 = 1.0 - b * b;
    if (!(sin2 > 1e-12)) return; /* parallel: the 1-D kernel's 1/sinθ has no finite limit */
    double dw0 = v3_dot(d, w0), ww0 = v3_dot(w, w0);
    double t = (b * ww0 - dw0) / sin2, s = (ww0 - b * dw0) / sin2;
    if (t < 0.0 || t > tmax || s < 0.0 || s > bm->length) return;
    vec3 gap = v3_sub(v3_add(w0, v3_scale(d, t)), v3_scale(w, s));
    if (v3_dot(gap, gap) >= r2) return;
    hit(ctx, bm, t, s, 1.0 / sqrt(sin2));
}

void beam_map_query(const beam_map *m, vec3 o, vec3 d, double tmax, double t_hi, beam_hit_fn hit, void *ctx)
{
    if (!m || m->n == 0) return;
    double oo[3] = {o.x, o.y, o.z}, inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    double r2 = m->r * m->r;
    uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const beam_node *nd = &m->nodes[stack[--top]];
        if (!(nd->t_min < t_hi) || !hits_box(nd, oo, inv, tmax)) continue;
        if (nd->count) {
            for (uint32_t i = 0; i < nd->count; i++) {
                const photon_beam *bm = &m->beams[nd->first + i];
                if (bm->time < t_hi) test_beam(bm, o, d, tmax, r2, hit, ctx);
            }
            continue;
        }
        uint32_t left = (uint32_t)(nd - m->nodes) + 1;
        stack[top++] = nd->first; /* right after left */
        stack[top++] = left;
    }
}
