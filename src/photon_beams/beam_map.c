/* The beam BVH: a binary tree over pieces of the beams (long beams cut, piece_length) and their boxes (the
 * piece's box inflated by r): the pieces sorted in Morton order of their box centres and split at the middle
 * (a linear BVH), leaves of at most BEAM_LEAF pieces, nodes in depth-first order.
 * Each node also keeps the time range of its pieces, so that a query with a time window skips whole subtrees.
 * Single-threaded build; the query is a slab test per node and the closest approach of two lines per piece. */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/photon_beams.h"

#define BEAM_LEAF 4


typedef struct {
    float lo[3], hi[3];
    double t_min;      /* earliest start time of its beams */
    double t_max;      /* latest end time (start + η·length) of its beams */
    uint32_t first;    /* leaf: first piece; inner: index of the right child (the left one follows) */
    uint32_t count;    /* pieces of a leaf; 0: inner node */
} beam_node;

/* A piece [s0, s1] of a beam: long beams are cut so that the boxes stay tight (a beam across the scene has a
 * box as large as the scene). A point at s belongs to the piece with s0 <= s < s1, the last piece also
 * holding s1 = length, so no point is counted twice. */
typedef struct {
    uint32_t beam;
    float s0, s1;
} beam_piece;

struct beam_map {
    photon_beam *beams;
    size_t n;
    beam_piece *pieces; /* in leaf order */
    size_t n_pieces;
    beam_node *nodes;
    size_t n_nodes;
    double r;
};

typedef struct {
    float lo[3], hi[3], c[4]; /* c[3]: the time at the piece's middle, τ + η·(s0 + s1)/2 */
    uint32_t piece;
} beam_box;


static void box_of(const photon_beam *b, const beam_piece *pc, double r, beam_box *x)
{
    for (int k = 0; k < 3; k++) {
        double a = b->start[k] + (double)b->dir[k] * pc->s0, e = b->start[k] + (double)b->dir[k] * pc->s1;
        double lo = a < e ? a : e, hi = a < e ? e : a;
        x->lo[k] = (float)(lo - r) - 1e-6f * (1.0f + fabsf((float)lo));
        x->hi[k] = (float)(hi + r) + 1e-6f * (1.0f + fabsf((float)hi));
        x->c[k] = (float)(0.5 * (lo + hi));
    }
    x->c[3] = (float)(b->time + (double)b->eta * 0.5 * ((double)pc->s0 + pc->s1));
}

typedef struct {
    beam_map *m;
    const beam_piece *pieces; /* in their original order (box[i].piece indexes them) */
    beam_box *box;
    size_t next;
} builder;

/* Sorts box[0, n) into Morton order of the centres (dp_morton_order): in space, or with `timed` in space and time
 * (the pieces' middle times: with a narrow window, whole subtrees then fall outside it in time). 0, or -1 out of
 * memory. */
static int morton_sort(beam_box *box, size_t n, int timed)
{
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    beam_box *tmp = malloc((n ? n : 1) * sizeof *tmp);
    int rc = order && tmp ? dp_morton_order(box[0].c, sizeof *box / sizeof(float), n, timed ? 4 : 3, order) : -1;
    for (size_t i = 0; !rc && i < n; i++) tmp[i] = box[order[i]];
    if (!rc) memcpy(box, tmp, n * sizeof *box);
    free(order);
    free(tmp);
    return rc;
}

static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

/* A leaf's bounds from its pieces: the boxes and the time range. */
static void leaf_bounds(builder *B, beam_node *nd, size_t lo, size_t hi)
{
    for (int k = 0; k < 3; k++) nd->lo[k] = INFINITY, nd->hi[k] = -INFINITY;
    nd->t_min = INFINITY;
    nd->t_max = -INFINITY;
    for (size_t i = lo; i < hi; i++) {
        const beam_box *x = &B->box[i];
        for (int k = 0; k < 3; k++) nd->lo[k] = min_f(nd->lo[k], x->lo[k]), nd->hi[k] = max_f(nd->hi[k], x->hi[k]);
        const beam_piece *pc = &B->pieces[x->piece];
        const photon_beam *b = &B->m->beams[pc->beam];
        double ta = b->time + (double)b->eta * pc->s0, te = b->time + (double)b->eta * pc->s1;
        if (ta < nd->t_min) nd->t_min = ta;
        if (te > nd->t_max) nd->t_max = te;
    }
}

/* The subtree over box[lo, hi), in Morton order: split at the middle (a linear BVH: each half is a compact
 * region of the Morton curve); an inner node's bounds are its children's union (bottom-up). */
static void build(builder *B, size_t lo, size_t hi)
{
    size_t me = B->next++;
    beam_node *nodes = B->m->nodes;
    if (hi - lo <= BEAM_LEAF) {
        leaf_bounds(B, &nodes[me], lo, hi);
        nodes[me].first = (uint32_t)lo;
        nodes[me].count = (uint32_t)(hi - lo);
        return;
    }
    size_t mid = lo + (hi - lo) / 2;
    size_t left = B->next;
    build(B, lo, mid);
    size_t right = B->next;
    build(B, mid, hi);
    beam_node *nd = &nodes[me], *l = &nodes[left], *r = &nodes[right];
    for (int k = 0; k < 3; k++) nd->lo[k] = min_f(l->lo[k], r->lo[k]), nd->hi[k] = max_f(l->hi[k], r->hi[k]);
    nd->t_min = l->t_min < r->t_min ? l->t_min : r->t_min;
    nd->t_max = l->t_max > r->t_max ? l->t_max : r->t_max;
    nd->first = (uint32_t)right;
    nd->count = 0;
}

/* The pieces' length: a 16th of the largest side of the beams' box, and at least 4 r (shorter pieces would
 * only add pieces to a box the radius already dominates). */
static double piece_length(const photon_beam *b, size_t n, double r)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++) /* both ends: beams from one point light all start at one point */
        for (int k = 0; k < 3; k++) {
            float e = b[i].start[k] + b[i].dir[k] * b[i].length;
            lo[k] = min_f(lo[k], min_f(b[i].start[k], e));
            hi[k] = max_f(hi[k], max_f(b[i].start[k], e));
        }
    double ext = 0.0;
    for (int k = 0; k < 3 && n; k++) ext = dp_fmax(ext, (double)hi[k] - lo[k]);
    return dp_fmax(ext / 16.0, 4.0 * r);
}

#define BEAM_PIECES_MAX 64 /* per beam: a tiny radius (late iterations of a small α) must not explode the count */
#define BEAM_PIECE_WINDOWS 4.0 /* with a window: a piece's own time range is at most this many window widths */
#define BEAM_TIMED_PIECES_MAX 256 /* per beam, when the window's width sets the pieces' length */

/* The part of beam b that can count: a point at s has the path time t_cam + τ + η·s + (camera leg) >= τ + η·s
 * (the camera's times are >= 0; emission and sensor offsets are in τ), so nothing beyond (end − τ)/η reaches a
 * window ending at `end`. The cut is widened by 1e-5 relative (b's float η against its medium's double). 0: the
 * whole beam is too late. */
static double usable_length(const photon_beam *b, const beam_time_cut *tc)
{
    double len = b->length, eta = b->eta;
    if (!tc || !(tc->end < INFINITY) || !(eta > 0.0)) return len;
    double s_end = (tc->end - b->time) / eta;
    if (!(s_end > 0.0)) return 0.0;
    s_end = s_end * (1.0 + 1e-5) + 1e-6;
    return s_end < len ? s_end : len;
}

/* A beam's pieces: of length `len` (piece_length), shorter with a window so that each piece's own time range
 * η·Δs is at most BEAM_PIECE_WINDOWS widths (the nodes' time ranges then prune: a narrow gate), at most
 * BEAM_PIECES_MAX (BEAM_TIMED_PIECES_MAX with a window) a beam; *use the usable length. */
static size_t pieces_of(const photon_beam *b, double len, const beam_time_cut *tc, double *use)
{
    *use = usable_length(b, tc);
    if (!(*use > 0.0)) return 0;
    double cap = BEAM_PIECES_MAX;
    if (tc && tc->width > 0.0 && b->eta > 0.0) {
        double lt = BEAM_PIECE_WINDOWS * tc->width / b->eta;
        if (lt < len) len = lt, cap = BEAM_TIMED_PIECES_MAX;
    }
    double k = ceil(*use / len);
    if (!(k >= 1.0)) return 1; /* also NaN */
    return k > cap ? (size_t)cap : (size_t)k;
}

double beam_map_pieces(const photon_beam *b, size_t n, double r, const beam_time_cut *tc)
{
    double len = piece_length(b, n, r), sum = 0.0, use;
    for (size_t i = 0; i < n; i++) sum += (double)pieces_of(&b[i], len, tc, &use);
    return sum;
}

beam_map *beam_map_build(const photon_beam *b, size_t n, double r, const beam_time_cut *tc, dp_error *err)
{
    double len = piece_length(b, n, r), use;
    size_t np = 0;
    for (size_t i = 0; i < n; i++) np += pieces_of(&b[i], len, tc, &use);
    beam_map *m = calloc(1, sizeof *m);
    beam_box *box = np ? malloc(np * sizeof *box) : NULL;
    beam_piece *pc = np ? malloc(np * sizeof *pc) : NULL;
    if (m) {
        m->n = n;
        m->n_pieces = np;
        m->r = r;
        m->beams = n ? malloc(n * sizeof *m->beams) : NULL;
        m->pieces = np ? malloc(np * sizeof *m->pieces) : NULL;
        m->nodes = np ? malloc(2 * np * sizeof *m->nodes) : NULL; /* < 2 np nodes for any split */
    }
    if (!m || (np && (!box || !pc || !m->beams || !m->pieces || !m->nodes)) || np > UINT32_MAX / 2) {
        free(box);
        free(pc);
        beam_map_free(m);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory building the beam map (%zu beams, %zu pieces)", n, np), NULL;
    }
    if (n) memcpy(m->beams, b, n * sizeof *b);
    size_t j = 0;
    for (size_t i = 0; i < n; i++) {
        size_t k = pieces_of(&b[i], len, tc, &use);
        double step = use / (double)k;
        /* the last piece ends at the beam's end, or where the beam can no longer count (rounded up: a float
         * below `use` would drop a point that counts) */
        float end = use < (double)b[i].length ? nextafterf((float)use, INFINITY) : b[i].length;
        if (end > b[i].length) end = b[i].length;
        for (size_t q = 0; q < k; q++, j++)
            pc[j] = (beam_piece){.beam = (uint32_t)i, .s0 = (float)(q * step), .s1 = q + 1 == k ? end : (float)((q + 1) * step)};
    }
    for (size_t i = 0; i < np; i++) {
        box_of(&b[pc[i].beam], &pc[i], r, &box[i]);
        box[i].piece = (uint32_t)i;
    }
    if (np && morton_sort(box, np, tc && tc->width > 0.0)) {
        free(box);
        free(pc);
        beam_map_free(m);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory building the beam map (%zu beams, %zu pieces)", n, np), NULL;
    }
    if (np) {
        builder B = {m, pc, box, 0};
        build(&B, 0, np);
        m->n_nodes = B.next;
        for (size_t i = 0; i < np; i++) m->pieces[i] = pc[box[i].piece]; /* in leaf order */
    }
    free(box);
    free(pc);
    return m;
}

void beam_map_free(beam_map *m)
{
    if (!m) return;
    free(m->beams);
    free(m->pieces);
    free(m->nodes);
    free(m);
}

size_t beam_map_size(const beam_map *m) { return m ? m->n : 0; }

double beam_map_bytes(double n, double pieces)
{
    return n * sizeof(photon_beam) + pieces * (2.0 * sizeof(beam_piece) + sizeof(beam_box) + 2.0 * sizeof(beam_node));
}

/* The slab test of the segment o + t·d, t in [0, tmax], against a node's box; [*t_in, *t_out] the part of
 * the segment inside it. */
static int hits_box(const beam_node *nd, const double *o, const double *inv, double tmax, double *t_in, double *t_out)
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
    *t_in = t0;
    *t_out = t1;
    return 1;
}

/* Whether path times in [a + eta·t_in, b + eta·t_out] can meet [w->lo, w->hi), widened by 1e-6 of the
 * magnitudes: the float η and length of the end times, and the caller's own rounding. */
static int window_meets(const beam_window *w, double a, double b, double t_in, double t_out)
{
    double lo = w->t0 + a + w->eta * t_in, hi = w->t0 + b + w->eta * t_out;
    double eps = 1e-6 * (fabs(w->t0) + fabs(a) + fabs(b) + (b - a) + w->eta * t_out + fabs(w->lo) + fabs(w->hi));
    return lo - eps < w->hi && hi + eps >= w->lo;
}

/* Closest approach of the camera line o + t·d and the beam a + s·w (both unit): with w0 = o − a, b = d·w,
 * sin²θ = 1 − b², t = (b (w·w0) − d·w0)/sin²θ, s = (w·w0 − b (d·w0))/sin²θ. */
static void test_beam(const photon_beam *bm, const beam_piece *pc, vec3 o, vec3 d, double tmax, double r2,
                      beam_hit_fn hit, void *ctx)
{
    vec3 w = v3(bm->dir[0], bm->dir[1], bm->dir[2]);
    vec3 w0 = v3_sub(o, v3(bm->start[0], bm->start[1], bm->start[2]));
    double b = v3_dot(d, w), sin2 = 1.0 - b * b;
    if (!(sin2 > 1e-12)) return; /* parallel: the 1-D kernel's 1/sinθ has no finite limit */
    double dw0 = v3_dot(d, w0), ww0 = v3_dot(w, w0);
    double t = (b * ww0 - dw0) / sin2, s = (ww0 - b * dw0) / sin2;
    if (t < 0.0 || t > tmax || s < pc->s0 || s > pc->s1 || (s == pc->s1 && pc->s1 < bm->length)) return;
    vec3 gap = v3_sub(v3_add(w0, v3_scale(d, t)), v3_scale(w, s));
    if (v3_dot(gap, gap) >= r2) return;
    hit(ctx, bm, t, s, 1.0 / sqrt(sin2));
}

void beam_map_query(const beam_map *m, vec3 o, vec3 d, double tmax, const beam_window *w, beam_hit_fn hit, void *ctx)
{
    if (!m || m->n == 0) return;
    double oo[3] = {o.x, o.y, o.z}, inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    double r2 = m->r * m->r;
    uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const beam_node *nd = &m->nodes[stack[--top]];
        double t_in, t_out;
        if (!hits_box(nd, oo, inv, tmax, &t_in, &t_out) || (w && !window_meets(w, nd->t_min, nd->t_max, t_in, t_out)))
            continue;
        if (nd->count) {
            for (uint32_t i = 0; i < nd->count; i++) {
                const beam_piece *pc = &m->pieces[nd->first + i];
                const photon_beam *bm = &m->beams[pc->beam];
                if (!w || window_meets(w, bm->time + (double)bm->eta * pc->s0, bm->time + (double)bm->eta * pc->s1, t_in, t_out))
                    test_beam(bm, pc, o, d, tmax, r2, hit, ctx);
            }
            continue;
        }
        uint32_t left = (uint32_t)(nd - m->nodes) + 1;
        stack[top++] = nd->first; /* right after left */
        stack[top++] = left;
    }
}
