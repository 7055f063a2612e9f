/* Volume photon map: a balanced BVH over the photons, answering "every photon within r of the segment
 * o + t·d, 0 <= t <= tmax" (docs/reference-renderer.md §8.4, §9.3).
 *
 * Layout: a perfect binary tree in implicit (heap) order, node i having children 2i+1 and 2i+2; every leaf
 * sits at the same depth and holds at most LEAF_MAX photons. The photons of the node with index j on level
 * k are the contiguous range [j·n >> k, (j+1)·n >> k) of the tree-ordered arrays, so no ranges are stored.
 * The build splits each range at its middle along the largest extent of its photons (a selection, not a
 * sort: O(n) per level; the long ranges of the top levels by a parallel partition), and each node keeps the
 * float box of its photons grown by r plus a tiny padding that absorbs rounding, and the range of its
 * photons' times (for the queries with a time window). Subtrees are built as OpenMP tasks; each is
 * deterministic, so the map does not depend on the thread count.
 *
 * Query: iterative depth-first traversal (left child first, so the order is fixed by the map) with a slab
 * test that stays exact for zero direction components, then the photon test in double:
 *   w = p - o,  t = w·d,  v = w - t·d,  d2 = v·v   (= |w|^2 - t^2, without its cancellation; never < 0).
 * With a time window, a node is also skipped when no photon in its box, with a time in its range, can have
 * a total time inside the window (window_may_count). */
#include "dartspp/photon.h"

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LEAF_MAX 16                 /* photons per leaf, at most (tuning: bench/results/volume_map.md) */
#define STACK_MAX 64                /* traversal stack; the tree depth is below 32 */
#define PAD_REL 1e-12               /* box padding relative to coordinate size (~4500 double ulps) */
#define TASK_MIN ((size_t)1 << 10)  /* ranges smaller than this are built without spawning tasks */
#define INSERTION_MAX 16            /* selection finishes ranges this short by insertion sort */
#define AXIS_SAMPLES 64             /* points looked at to choose a split axis */
#define PIVOT_SAMPLES 255           /* keys sampled to place a pivot in long ranges */
#define PIVOT_SAMPLE_MIN 4096       /* ranges at least this long use a sampled pivot */
#define WINDOW_MARGIN 1e-9          /* time window widening relative to the magnitudes summed (rounding) */
#define PAR_SELECT_MIN ((size_t)1 << 16) /* ranges at least this long are split by the parallel partition */
#define PAR_CHUNKS 64               /* its fixed chunks: the partition does not depend on the thread count */
#define BAND_SAMPLES_MAX 4096       /* keys sampled, at most, to bracket the wanted rank (band_keys) */

typedef struct {
    float lo[3], hi[3];
} node_box;

/* The photons' times under a node: exact doubles. NaN times (which no window counts) are left out (fmin,
 * fmax), so a node whose photons all have one has a NaN range, which no window prunes and no union keeps. */
typedef struct {
    double lo, hi;
} time_range;

/* A photon position and its index in the caller's array: the build sorts these 16-byte items, and they
 * stay in tree order as the compact position array that the leaf tests read. */
typedef struct {
    float pos[3];
    uint32_t src;
} point_item;

struct volume_photon_map {
    size_t n;
    int depth;          /* level of the leaves; the tree has 2^(depth+1) - 1 nodes */
    double r2;          /* gather radius squared */
    node_box *boxes;    /* per node: photons' box grown by r (+ padding), rounded outward to float */
    time_range *times;  /* per node: its photons' time range (a separate array: the plain query never reads it) */
    point_item *points; /* positions, tree order */
    photon *photons;    /* photon copies, tree order */
};

typedef struct {
    size_t n;
    int depth;
    double pad; /* how far node boxes reach beyond their photons */
    point_item *points;
    node_box *boxes;
    const photon *ph;   /* the caller's photons (points[i].src indexes them): their times */
    time_range *times;
} builder;

/* ---- build ---- */

/* First index of the j-th of the 2^level equal ranges that [0, n) is cut into (n < 2^32, j <= 2^level). */
static size_t range_start(size_t n, size_t j, int level)
{
    return (size_t)(((uint64_t)j * (uint64_t)n) >> level);
}

/* Smallest depth at which ranges of n photons halved that many times hold at most LEAF_MAX photons. */
static int leaf_depth(size_t n)
{
    int depth = 0;
    while (((size_t)LEAF_MAX << depth) < n) depth++;
    return depth;
}

static void point_bounds(const point_item *pts, size_t count, size_t step, float mn[3], float mx[3])
{
    for (int a = 0; a < 3; a++) mn[a] = mx[a] = pts[0].pos[a];
    for (size_t i = step; i < count; i += step)
        for (int a = 0; a < 3; a++) {
            float x = pts[i].pos[a];
            mn[a] = x < mn[a] ? x : mn[a];
            mx[a] = x > mx[a] ? x : mx[a];
        }
}

/* Axis of largest extent, estimated from about AXIS_SAMPLES evenly strided points (it only steers the
 * split; node boxes are exact). */
static int split_axis(const point_item *pts, size_t count)
{
    float mn[3], mx[3];
    point_bounds(pts, count, count > AXIS_SAMPLES ? count / AXIS_SAMPLES : 1, mn, mx);
    double ext[3];
    for (int a = 0; a < 3; a++) ext[a] = (double)mx[a] - mn[a];
    return ext[0] >= ext[1] ? (ext[0] >= ext[2] ? 0 : 2) : (ext[1] >= ext[2] ? 1 : 2);
}

/* Nearest float <= x (resp. >= x), so that float boxes never shrink. */
static float float_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static float float_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

static void leaf_box(node_box *box, const point_item *pts, size_t count, double pad)
{
    float mn[3], mx[3];
    point_bounds(pts, count, 1, mn, mx);
    for (int a = 0; a < 3; a++) {
        box->lo[a] = float_down((double)mn[a] - pad);
        box->hi[a] = float_up((double)mx[a] + pad);
    }
}

static void union_box(node_box *box, const node_box *l, const node_box *r)
{
    for (int a = 0; a < 3; a++) {
        box->lo[a] = fminf(l->lo[a], r->lo[a]);
        box->hi[a] = fmaxf(l->hi[a], r->hi[a]);
    }
}

static void leaf_times(time_range *tr, const photon *ph, const point_item *pts, size_t count)
{
    double lo = ph[pts[0].src].time, hi = lo;
    for (size_t i = 1; i < count; i++) { /* fmin, not <: a NaN first time must not hide the others */
        lo = fmin(lo, ph[pts[i].src].time);
        hi = fmax(hi, ph[pts[i].src].time);
    }
    tr->lo = lo;
    tr->hi = hi;
}

static void union_times(time_range *tr, const time_range *l, const time_range *r)
{
    tr->lo = fmin(l->lo, r->lo);
    tr->hi = fmax(l->hi, r->hi);
}

static float median_of_three(float a, float b, float c)
{
    if (a > b) { float t = a; a = b; b = t; }
    if (b > c) b = c;
    return a > b ? a : b;
}

/* k-th smallest of keys[0, count) (quickselect; reorders keys). */
static float select_key(float *keys, int count, int k)
{
    int lo = 0, hi = count - 1;
    while (hi > lo) {
        float pivot = median_of_three(keys[lo], keys[lo + (hi - lo) / 2], keys[hi]);
        int i = lo, j = hi;
        while (i <= j) {
            while (keys[i] < pivot) i++;
            while (keys[j] > pivot) j--;
            if (i <= j) { float t = keys[i]; keys[i++] = keys[j]; keys[j--] = t; }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else break;
    }
    return keys[k];
}

/* A pivot for finding rank k in pts[lo, hi]: the same rank among PIVOT_SAMPLES evenly strided keys, so
 * that the first partition already lands close to k; median of three for short ranges. */
static float pick_pivot(const point_item *pts, ptrdiff_t lo, ptrdiff_t hi, ptrdiff_t k, int axis)
{
    ptrdiff_t count = hi - lo + 1;
    if (count < PIVOT_SAMPLE_MIN) return median_of_three(pts[lo].pos[axis], pts[lo + count / 2].pos[axis], pts[hi].pos[axis]);
    float keys[PIVOT_SAMPLES];
    ptrdiff_t step = count / PIVOT_SAMPLES;
    for (int s = 0; s < PIVOT_SAMPLES; s++) keys[s] = pts[lo + s * step + step / 2].pos[axis];
    return select_key(keys, PIVOT_SAMPLES, (int)((k - lo) * PIVOT_SAMPLES / count));
}

/* Moves the items of pts[lo, hi] whose key is < pivot (or <= pivot) to the front, keeping no order;
 * returns the end of that group. Branch-free (Lomuto with a conditional advance): the comparison
 * outcomes are unpredictable, and mispredictions would dominate. */
static ptrdiff_t partition_below(point_item *pts, ptrdiff_t lo, ptrdiff_t hi, int axis, float pivot, int or_equal)
{
    ptrdiff_t end = lo;
    for (ptrdiff_t i = lo; i <= hi; i++) {
        point_item x = pts[i];
        int below = or_equal ? x.pos[axis] <= pivot : x.pos[axis] < pivot;
        pts[i] = pts[end];
        pts[end] = x;
        end += below;
    }
    return end;
}

static void insertion_sort(point_item *pts, ptrdiff_t lo, ptrdiff_t hi, int axis)
{
    for (ptrdiff_t i = lo + 1; i <= hi; i++) {
        point_item x = pts[i];
        ptrdiff_t j = i - 1;
        while (j >= lo && pts[j].pos[axis] > x.pos[axis]) {
            pts[j + 1] = pts[j];
            j--;
        }
        pts[j + 1] = x;
    }
}

/* Reorders pts[0, count) so that pts[k] holds the k-th smallest key along axis, with nothing larger
 * before it and nothing smaller after it. Each round splits the range into < pivot, == pivot, > pivot
 * (the pivot is a key of the range, so every round shrinks it, duplicates included). Deterministic. */
static void select_nth(point_item *pts, size_t count, size_t k, int axis)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)count - 1, kk = (ptrdiff_t)k;
    while (hi - lo >= INSERTION_MAX) {
        float pivot = pick_pivot(pts, lo, hi, kk, axis);
        ptrdiff_t less_end = partition_below(pts, lo, hi, axis, pivot, 0);
        if (kk < less_end) {
            hi = less_end - 1;
            continue;
        }
        ptrdiff_t equal_end = partition_below(pts, less_end, hi, axis, pivot, 1);
        if (kk < equal_end) return;
        lo = equal_end;
    }
    insertion_sort(pts, lo, hi, axis);
}

/* The node's box and time range from its children's */
static void union_children(const builder *b, size_t node)
{
    union_box(&b->boxes[node], &b->boxes[2 * node + 1], &b->boxes[2 * node + 2]);
    union_times(&b->times[node], &b->times[2 * node + 1], &b->times[2 * node + 2]);
}

/* ---- the parallel partition of the top levels ----
 * Quickselect splits a range on one thread: at the root that is a pass over every photon while the other
 * threads wait, and the first levels together cost about two such passes on the critical path. Ranges of
 * at least PAR_SELECT_MIN photons are therefore split in three parallel passes over PAR_CHUNKS fixed chunks
 * (count, scatter to scratch, copy back) around two sampled keys that bracket the wanted rank (a band of
 * 10–20 % of the range), and only the band is then selected on one thread. Written by hand: no library
 * we use offers a parallel selection on our items. */

/* Two keys bracketing rank k of the range: the sample ranks ∓ 5σ around k's among S evenly strided keys,
 * σ = √S/2 the largest standard deviation of a sample rank. S balances the serial costs of a split, about
 * S·c_sample to sample and select the keys against 5/√S·count·c_select for the band: S ≈ (count/4)^(2/3),
 * e.g. 1,626 keys and a 12 % band for 2^18 photons. */
static void band_keys(const point_item *pts, size_t count, size_t k, int axis, float *lo, float *hi)
{
    float keys[BAND_SAMPLES_MAX];
    double want = pow((double)count / 4.0, 2.0 / 3.0);
    int n = want < BAND_SAMPLES_MAX ? (int)want : BAND_SAMPLES_MAX;
    int half = (int)ceil(2.5 * sqrt((double)n));
    size_t step = count / (size_t)n;
    for (int i = 0; i < n; i++) keys[i] = pts[(size_t)i * step + step / 2].pos[axis];
    int r = (int)((double)k * n / (double)count);
    int r_lo = r - half < 0 ? 0 : r - half;
    int r_hi = r + half > n - 1 ? n - 1 : r + half;
    *lo = select_key(keys, n, r_lo);
    *hi = select_key(keys, n, r_hi);
}

/* 0: key below lo, 1: in [lo, hi], 2: above hi */
static int band_group(float key, float lo, float hi) { return (key >= lo) + (key > hi); }

static size_t chunk_start(size_t count, int c) { return count * (size_t)c / PAR_CHUNKS; }

/* Reorders pts[0, count) into the three groups (in chunk order inside each, so the result is the same on
 * any number of threads) through scratch; returns the groups' sizes. */
static void band_partition(point_item *pts, point_item *scratch, size_t count, int axis, float lo, float hi,
                           size_t sizes[3])
{
    size_t n[PAR_CHUNKS][3], off[PAR_CHUNKS][3];
#pragma omp parallel for schedule(static) default(none) shared(pts, count, axis, lo, hi, n)
    for (int c = 0; c < PAR_CHUNKS; c++) {
        n[c][0] = n[c][1] = n[c][2] = 0;
        for (size_t i = chunk_start(count, c); i < chunk_start(count, c + 1); i++)
            n[c][band_group(pts[i].pos[axis], lo, hi)]++;
    }
    size_t at = 0;
    for (int g = 0; g < 3; g++) {
        sizes[g] = at;
        for (int c = 0; c < PAR_CHUNKS; c++) off[c][g] = at, at += n[c][g];
        sizes[g] = at - sizes[g];
    }
#pragma omp parallel for schedule(static) default(none) shared(pts, scratch, count, axis, lo, hi, off)
    for (int c = 0; c < PAR_CHUNKS; c++) {
        size_t o[3] = {off[c][0], off[c][1], off[c][2]};
        for (size_t i = chunk_start(count, c); i < chunk_start(count, c + 1); i++)
            scratch[o[band_group(pts[i].pos[axis], lo, hi)]++] = pts[i];
    }
#pragma omp parallel for schedule(static) default(none) shared(pts, scratch, count)
    for (int c = 0; c < PAR_CHUNKS; c++)
        memcpy(pts + chunk_start(count, c), scratch + chunk_start(count, c),
               (chunk_start(count, c + 1) - chunk_start(count, c)) * sizeof *pts);
}

/* select_nth for long ranges: the band partition, then the selection inside the group that holds rank k
 * (the band, unless the sample missed it: about once in 10^6 ranges, and still exact). */
static void select_nth_parallel(point_item *pts, point_item *scratch, size_t count, size_t k, int axis)
{
    float lo, hi;
    size_t g[3];
    band_keys(pts, count, k, axis, &lo, &hi);
    band_partition(pts, scratch, count, axis, lo, hi, g);
    if (k < g[0]) select_nth(pts, g[0], k, axis);
    else if (k < g[0] + g[1]) select_nth(pts + g[0], g[1], k - g[0], axis);
    else select_nth(pts + g[0] + g[1], g[2], k - g[0] - g[1], axis);
}

/* Builds the subtree of node (the j-th node of level): median split, children, then the node's box as
 * the union of theirs; a leaf's box is its photons' bounds grown by the padding. */
static void build_node(const builder *b, size_t node, int level, size_t j)
{
    size_t lo = range_start(b->n, j, level), hi = range_start(b->n, j + 1, level);
    if (level == b->depth) {
        leaf_box(&b->boxes[node], b->points + lo, hi - lo, b->pad);
        leaf_times(&b->times[node], b->ph, b->points + lo, hi - lo);
        return;
    }
    size_t mid = range_start(b->n, 2 * j + 1, level + 1);
    select_nth(b->points + lo, hi - lo, mid - lo, split_axis(b->points + lo, hi - lo));
    if (hi - lo >= TASK_MIN) {
#pragma omp task default(none) firstprivate(b, node, level, j)
        build_node(b, 2 * node + 1, level + 1, 2 * j);
        build_node(b, 2 * node + 2, level + 1, 2 * j + 1);
#pragma omp taskwait
    } else {
        build_node(b, 2 * node + 1, level + 1, 2 * j);
        build_node(b, 2 * node + 2, level + 1, 2 * j + 1);
    }
    union_children(b, node);
}

/* Copies the positions into build items (in parallel: this is also the first touch of their pages); fails on
 * a non-finite one, naming the first. Returns the largest |coordinate|. */
static int gather_points(const photon *ph, size_t n, point_item *pts, double *max_abs, dp_error *err)
{
    double m = 0.0;
    size_t bad = n; /* the first photon with a non-finite coordinate, n if none */
#pragma omp parallel for schedule(static) reduction(max : m) reduction(min : bad) default(none) shared(ph, n, pts)
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            float x = ph[i].pos[a];
            if (!isfinite(x) && i < bad) bad = i;
            pts[i].pos[a] = x;
            if (fabs((double)x) > m) m = fabs((double)x);
        }
        pts[i].src = (uint32_t)i;
    }
    if (bad < n)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "volume photon map: photon %zu has a non-finite position", bad);
    *max_abs = m;
    return 0;
}

/* Levels whose ranges are all at least PAR_SELECT_MIN long (none below the leaves' level). */
static int parallel_levels(const builder *b)
{
    int levels = 0;
    while (levels < b->depth && range_start(b->n, 1, levels) >= PAR_SELECT_MIN) levels++;
    return levels;
}

/* The top levels breadth first, each range split by the parallel partition; then every subtree below them
 * as a task (build_node); then the top levels' boxes, bottom up. */
static void build_tree(builder *b, point_item *scratch)
{
    int top = parallel_levels(b);
    for (int level = 0; level < top; level++)
        for (size_t j = 0; j < (size_t)1 << level; j++) {
            size_t lo = range_start(b->n, j, level), hi = range_start(b->n, j + 1, level);
            size_t mid = range_start(b->n, 2 * j + 1, level + 1);
            select_nth_parallel(b->points + lo, scratch + lo, hi - lo, mid - lo, split_axis(b->points + lo, hi - lo));
        }
    size_t first = ((size_t)1 << top) - 1; /* the heap index of level top's first node */
#pragma omp parallel default(none) shared(b, top, first)
#pragma omp single
    for (size_t j = 0; j < (size_t)1 << top; j++) {
#pragma omp task default(none) firstprivate(b, top, first, j)
        build_node(b, first + j, top, j);
    }
    for (int level = top - 1; level >= 0; level--)
        for (size_t j = 0; j < (size_t)1 << level; j++) union_children(b, ((size_t)1 << level) - 1 + j);
}

static void copy_photons_in_tree_order(const photon *ph, const point_item *pts, photon *out, size_t n)
{
#pragma omp parallel for schedule(static) default(none) shared(ph, pts, out, n)
    for (size_t i = 0; i < n; i++) out[i] = ph[pts[i].src];
}

size_t volume_map_bytes(size_t n)
{
    if (n == 0) return sizeof(volume_photon_map);
    size_t node_count = ((size_t)2 << leaf_depth(n)) - 1;
    size_t scratch = n >= PAR_SELECT_MIN ? n * sizeof(point_item) : 0; /* the parallel partition's, during the build */
    return sizeof(volume_photon_map) + node_count * (sizeof(node_box) + sizeof(time_range)) +
           n * (sizeof(point_item) + sizeof(photon)) + scratch;
}

volume_photon_map *volume_map_build(const photon *ph, size_t n, double r, dp_error *err)
{
    if (!(r >= 0.0)) {
        dp_fail_kind(err, DP_ERROR_INTERNAL, "volume photon map: the gather radius must be >= 0 (got %g)", r);
        return NULL;
    }
    if (n > UINT32_MAX || (n > 0 && !ph)) {
        dp_fail_kind(err, DP_ERROR_INTERNAL,
                     "volume photon map: %zu photons %s", n, ph ? "are more than 2^32 - 1" : "but no array");
        return NULL;
    }
    volume_photon_map *m = calloc(1, sizeof *m);
    if (!m) {
        dp_fail_kind(err, DP_ERROR_MEMORY, "volume photon map: out of memory");
        return NULL;
    }
    m->n = n;
    m->r2 = r * r;
    if (n == 0) return m;
    m->depth = leaf_depth(n);
    size_t node_count = ((size_t)2 << m->depth) - 1;
    m->boxes = malloc(node_count * sizeof *m->boxes);
    m->times = malloc(node_count * sizeof *m->times);
    m->points = malloc(n * sizeof *m->points);
    m->photons = malloc(n * sizeof *m->photons);
    if (!m->boxes || !m->times || !m->points || !m->photons) {
        dp_fail_kind(err, DP_ERROR_MEMORY, "volume photon map: out of memory for %zu photons", n);
        volume_map_free(m);
        return NULL;
    }
    double max_abs = 0.0;
    if (gather_points(ph, n, m->points, &max_abs, err)) {
        volume_map_free(m);
        return NULL;
    }
    /* boxes reach r beyond their photons, plus PAD_REL of the coordinate scale to cover rounding */
    builder b = {n, m->depth, r + PAD_REL * (r + max_abs), m->points, m->boxes, ph, m->times};
    point_item *scratch = NULL; /* the parallel partition's, while the map is built */
    if (parallel_levels(&b) > 0 && !(scratch = malloc(n * sizeof *scratch))) {
        dp_fail_kind(err, DP_ERROR_MEMORY, "volume photon map: out of memory for %zu photons", n);
        volume_map_free(m);
        return NULL;
    }
    build_tree(&b, scratch);
    free(scratch);
    copy_photons_in_tree_order(ph, m->points, m->photons, n);
    return m;
}

void volume_map_free(volume_photon_map *m)
{
    if (!m) return;
    free(m->boxes);
    free(m->times);
    free(m->points);
    free(m->photons);
    free(m);
}

size_t volume_map_size(const volume_photon_map *m) { return m ? m->n : 0; }

/* Whether the children of the j-th node of level split its range at a plane (volume_map_splits_ok) */
static int node_splits(const volume_photon_map *m, int level, size_t j)
{
    size_t lo = range_start(m->n, j, level), mid = range_start(m->n, 2 * j + 1, level + 1);
    size_t hi = range_start(m->n, j + 1, level);
    for (int a = 0; a < 3; a++) {
        float left_max = -INFINITY, right_min = INFINITY;
        for (size_t i = lo; i < mid; i++) left_max = fmaxf(left_max, m->points[i].pos[a]);
        for (size_t i = mid; i < hi; i++) right_min = fminf(right_min, m->points[i].pos[a]);
        if (left_max <= right_min) return 1;
    }
    return 0;
}

int volume_map_splits_ok(const volume_photon_map *m)
{
    for (int level = 0; m && m->n > 0 && level < m->depth; level++)
        for (size_t j = 0; j < (size_t)1 << level; j++)
            if (!node_splits(m, level, j)) return 0;
    return 1;
}

size_t volume_map_source(const volume_photon_map *m, const photon *p)
{
    return m->points[p - m->photons].src; /* the tree order's permutation, kept by the build */
}

/* ---- query ---- */

typedef struct {
    double o[3], d[3];
    double inv[3];        /* 1/d: ±inf where d is ±0 */
    int near_hi[3];       /* the slab is entered through its hi plane (d negative or -0) */
    double near_shift[3]; /* added to the near plane before scaling by inv: -o, widened by the padding */
    double far_shift[3];
    double tmax;          /* photon test: t <= tmax */
    double t_clip;        /* slab test: tmax, or DBL_MAX when tmax is infinite (so +inf entries miss) */
    double r2;
} beam;

static beam make_beam(vec3 o, vec3 d, double tmax, double r2)
{
    beam q;
    double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z}, o_max = 0.0;
    for (int a = 0; a < 3; a++) o_max = dp_fmax(o_max, fabs(oo[a]));
    double pad = PAD_REL * o_max; /* covers the rounding of p - o for origins far from the photons */
    for (int a = 0; a < 3; a++) {
        q.o[a] = oo[a];
        q.d[a] = dd[a];
        q.inv[a] = 1.0 / dd[a];
        q.near_hi[a] = signbit(q.inv[a]) != 0;
        q.near_shift[a] = q.near_hi[a] ? -oo[a] + pad : -oo[a] - pad;
        q.far_shift[a] = q.near_hi[a] ? -oo[a] - pad : -oo[a] + pad;
    }
    q.tmax = tmax;
    q.t_clip = dp_fmin(tmax, DBL_MAX);
    q.r2 = r2;
    return q;
}

/* Does the segment [0, tmax] meet the box? Where d_a = ±0, (plane - o)·inv is ±inf (no constraint, or a
 * miss: +inf entry / -inf exit, caught because the interval is clipped to finite t) or NaN when o lies on
 * the plane; the comparisons are written so a NaN never changes the interval, which is then the right
 * answer (o on the boundary of the closed slab). */
static int beam_meets_box(const beam *q, const node_box *box)
{
    double enter = 0.0, leave = q->t_clip;
    for (int a = 0; a < 3; a++) {
        double near_plane = q->near_hi[a] ? box->hi[a] : box->lo[a];
        double far_plane = q->near_hi[a] ? box->lo[a] : box->hi[a];
        double t_near = (near_plane + q->near_shift[a]) * q->inv[a];
        double t_far = (far_plane + q->far_shift[a]) * q->inv[a];
        enter = t_near > enter ? t_near : enter;
        leave = t_far < leave ? t_far : leave;
    }
    return enter <= leave;
}

/* Tests a leaf's photons and visits the accepted ones in order. Acceptance is collected without branches
 * (about a third of the tested photons pass, so a branch per photon would mostly mispredict). */
static void visit_leaf(const volume_photon_map *m, const beam *q, size_t first, size_t end, beam_visit_fn visit,
                       void *ctx)
{
    double ts[LEAF_MAX], d2s[LEAF_MAX];
    int accepted[LEAF_MAX], count = 0;
    for (size_t i = first; i < end; i++) {
        const float *p = m->points[i].pos;
        double wx = p[0] - q->o[0], wy = p[1] - q->o[1], wz = p[2] - q->o[2];
        double t = wx * q->d[0] + wy * q->d[1] + wz * q->d[2];
        /* perpendicular offset v = w - t·d; |v|^2 is |w|^2 - t^2 without the cancellation */
        double vx = wx - t * q->d[0], vy = wy - t * q->d[1], vz = wz - t * q->d[2];
        double d2 = vx * vx + vy * vy + vz * vz;
        ts[count] = t;
        d2s[count] = d2;
        accepted[count] = (int)(i - first);
        count += (t >= 0.0) & (t <= q->tmax) & (d2 <= q->r2);
    }
    for (int k = 0; k < count; k++) visit(ctx, &m->photons[first + (size_t)accepted[k]], ts[k], d2s[k]);
}

/* The leg's range over the photons of a box, and the largest |p - o| (the scale of the leg's rounding):
 * Euclidean, from the nearest point of the box to its farthest corner; projected, the range of (p - o)·d
 * over the box within the visited [0, tmax]. */
static void leg_range(const beam *q, const node_box *box, int projected, double *lo, double *hi, double *far)
{
    double near2 = 0.0, far2 = 0.0, t_lo = 0.0, t_hi = 0.0;
    for (int a = 0; a < 3; a++) {
        double l = box->lo[a] - q->o[a], h = box->hi[a] - q->o[a];
        double gap = l > 0.0 ? l : (h < 0.0 ? -h : 0.0), reach = -l > h ? -l : h;
        near2 += gap * gap;
        far2 += reach * reach;
        double pl = l * q->d[a], ph = h * q->d[a];
        t_lo += pl < ph ? pl : ph;
        t_hi += pl < ph ? ph : pl;
    }
    *far = sqrt(far2);
    *lo = projected ? dp_fmax(t_lo, 0.0) : sqrt(near2);
    *hi = projected ? dp_fmin(t_hi, q->tmax) : *far;
}

/* Can a photon of this node have a total time in [w->lo, w->hi)? Its total lies within the sum of the
 * bounds of its three terms; the window is widened by WINDOW_MARGIN of the magnitudes summed, which covers
 * the rounding of the caller's time and of the film's test. Every NaN (0·inf on infinite boxes, NaN times)
 * makes both comparisons false: the node is kept. */
static int window_may_count(const beam *q, const beam_time_filter *w, const node_box *box, const time_range *tr)
{
    double leg_lo, leg_hi, far;
    leg_range(q, box, w->projected, &leg_lo, &leg_hi, &far);
    double e_lo = w->eta * leg_lo, e_hi = w->eta * leg_hi;
    if (e_lo > e_hi) { double x = e_lo; e_lo = e_hi; e_hi = x; } /* eta < 0 */
    double total_lo = w->t0 + tr->lo + e_lo, total_hi = w->t0 + tr->hi + e_hi;
    double scale = fabs(w->t0) + dp_fmax(fabs(tr->lo), fabs(tr->hi)) + fabs(w->eta) * far + fabs(w->lo) + fabs(w->hi);
    double margin = WINDOW_MARGIN * scale;
    return !(total_hi < w->lo - margin || total_lo >= w->hi + margin);
}

/* Depth-first traversal, left child first; w NULL: no time window. */
static void query_beam(const volume_photon_map *m, vec3 o, vec3 d, double tmax, const beam_time_filter *w,
                       beam_visit_fn visit, void *ctx)
{
    if (!m || m->n == 0 || !visit || !(tmax >= 0.0) || !v3_is_finite(o) || !v3_is_finite(d)) return;
    beam q = make_beam(o, d, tmax, m->r2);
    size_t first_leaf = ((size_t)1 << m->depth) - 1;
    size_t stack[STACK_MAX];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        size_t node = stack[--top];
        if (!beam_meets_box(&q, &m->boxes[node])) continue;
        if (w && !window_may_count(&q, w, &m->boxes[node], &m->times[node])) continue;
        if (node < first_leaf) {
            stack[top++] = 2 * node + 2; /* right below left: the left subtree is visited first */
            stack[top++] = 2 * node + 1;
            continue;
        }
        size_t leaf = node - first_leaf;
        visit_leaf(m, &q, range_start(m->n, leaf, m->depth), range_start(m->n, leaf + 1, m->depth), visit, ctx);
    }
}

void photon_map_query_beam(const volume_photon_map *m, vec3 o, vec3 d, double tmax, beam_visit_fn visit, void *ctx)
{
    query_beam(m, o, d, tmax, NULL, visit, ctx);
}

void photon_map_query_beam_window(const volume_photon_map *m, vec3 o, vec3 d, double tmax, const beam_time_filter *w,
                                  beam_visit_fn visit, void *ctx)
{
    query_beam(m, o, d, tmax, w, visit, ctx);
}

/* ---- k nearest neighbours (the surface map's search) ----
 * Exact: the k smallest (d2, source index) pairs among the photons with d2 < R², d2 computed in double from
 * the float position and the double query. Nodes are visited nearer child first and skipped when their box
 * (a superset of their photons, rounded outward) is farther than the current k-th distance (or R), so the
 * answer does not depend on the visit order. */
typedef struct {
    int k, n;
    double *d2;
    int *idx;
} knn_heap; /* sorted ascending by (d2, idx); n <= k */

static void knn_insert(knn_heap *h, double d2, int idx)
{
    if (h->n == h->k && (d2 > h->d2[h->n - 1] || (d2 == h->d2[h->n - 1] && idx > h->idx[h->n - 1]))) return;
    int i = h->n < h->k ? h->n++ : h->n - 1;
    while (i > 0 && (h->d2[i - 1] > d2 || (h->d2[i - 1] == d2 && h->idx[i - 1] > idx))) {
        h->d2[i] = h->d2[i - 1];
        h->idx[i] = h->idx[i - 1];
        i--;
    }
    h->d2[i] = d2;
    h->idx[i] = idx;
}

static double box_dist2(const node_box *b, const double x[3])
{
    double s = 0.0;
    for (int a = 0; a < 3; a++) {
        double lo = (double)b->lo[a] - x[a], hi = x[a] - (double)b->hi[a]; /* x is finite: no NaN rule needed */
        double e = lo > hi ? lo : hi;
        e = e > 0.0 ? e : 0.0;
        s += e * e;
    }
    return s;
}

int volume_map_query_knn(const volume_photon_map *m, vec3 x, int k, double R, int *idx, double *d2)
{
    if (!m || m->n == 0 || k <= 0 || !(R > 0.0) || !v3_is_finite(x)) return 0;
    double q[3] = {x.x, x.y, x.z}, R2 = R * R;
    knn_heap h = {k, 0, d2, idx};
    size_t first_leaf = ((size_t)1 << m->depth) - 1;
    size_t stack[STACK_MAX];
    double stack_d[STACK_MAX];
    int top = 0;
    stack[top] = 0;
    stack_d[top++] = box_dist2(&m->boxes[0], q);
    while (top > 0) {
        size_t node = stack[--top];
        double bound = h.n == k ? h.d2[k - 1] : R2;
        if (stack_d[top] > bound || stack_d[top] >= R2) continue;
        if (node < first_leaf) {
            size_t a = 2 * node + 1, b = 2 * node + 2;
            double da = box_dist2(&m->boxes[a], q), db = box_dist2(&m->boxes[b], q);
            if (da < db) { /* push the farther child first: the nearer is visited next */
                size_t t = a; a = b; b = t;
                double td = da; da = db; db = td;
            }
            stack[top] = a, stack_d[top++] = da;
            stack[top] = b, stack_d[top++] = db;
            continue;
        }
        size_t leaf = node - first_leaf;
        size_t end = range_start(m->n, leaf + 1, m->depth);
        for (size_t i = range_start(m->n, leaf, m->depth); i < end; i++) {
            const float *p = m->points[i].pos;
            double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
            double e2 = dx * dx + dy * dy + dz * dz;
            if (e2 < R2) knn_insert(&h, e2, (int)m->points[i].src);
        }
    }
    return h.n;
}
