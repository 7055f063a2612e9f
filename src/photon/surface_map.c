/* Surface photon map: "k nearest photons within R of x", exact, on a FLANN single kd-tree (C API).
 *
 * The map copies the photon positions into one contiguous float array (the FLANN dataset, alive for the
 * index lifetime) and builds FLANN_INDEX_KDTREE_SINGLE over it: one kd-tree split at the middle of the
 * widest box side, no randomness, exact search (eps 0; checks are unlimited, which a single tree ignores
 * anyway — and the C API forwards only `checks` to a search, not eps, sorted or cores).
 *
 * Distances. FLANN's L2 returns float squared distances from a float copy of the query; they are not
 * what a caller gets from |p - x|^2 in double, and near ties they may order points differently. The map
 * therefore uses FLANN only to find candidates, then recomputes every candidate's squared distance in
 * double from the stored float position and the double query,
 *     d2 = (px - x)^2 + (py - y)^2 + (pz - z)^2,
 * keeps d2 < R*R (strict), and sorts by (d2, index). The answer is exactly "the first k of all photons with
 * d2 < R^2 in (d2, index) order" — deterministic, ties included, and equal to a brute-force scan.
 *
 * Getting a large enough candidate set. FLANN's radius search with max_nn = m returns the m nearest
 * within a squared radius (FLANN's radius test is strict: dist < radius). The search radius is R inflated
 * by bounds on the float error (query rounding `a`, relative error RHO, absolute TAU), and m = k plus some
 * slack. If FLANN returns fewer than m, every photon within R is among them. If it returns m, every
 * photon it left out has float distance >= the m-th one, so its double distance is >= a lower bound L;
 * the answer is final when L exceeds the k-th kept d2 (or R^2 when fewer than k are kept). Otherwise
 * (near-ties at the k-th place, e.g. duplicate positions) m doubles and the search repeats; m >= n is a
 * full radius search and always final.
 *
 * Threads. Queries only read the map. FLANN's kd-tree search is const and keeps its state on the stack
 * and in per-call result sets. Every FLANN C call first applies its FLANNParameters to process globals:
 * log_level >= 0 is stored into FLANN's logger and random_seed > 0 calls srand() (reseeding the process's
 * rand()). So the build sets FLANN_LOG_NONE and the fixed seed, while queries and free pass -1 ("leave as is",
 * FLANN's own convention) and random_seed = 0, which makes them write no global state; every call gets
 * its own FLANNParameters on the stack. (Each FLANN search also opens an OpenMP region of one thread,
 * which costs about a microsecond per query in libgomp.)
 *
 * Coordinates are limited to |c| <= COORD_MAX so that FLANN's float squared distances cannot overflow;
 * queries beyond that range (never produced by a scene) are answered by a linear scan. */
#include "dartspp/photon.h"

#include <flann/flann.h>

#include <float.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#define LEAF_MAX_SIZE 12   /* photons per kd-tree leaf */
#define BUILD_SEED 0x5eedL /* FLANN's random seed at build (the single kd-tree draws no random numbers) */
#define COORD_MAX 1e18     /* |coordinate| bound: (2e18)^2 * 3 stays far below FLT_MAX */
#define RHO 1e-4           /* relative error bound of FLANN's float distances and pruning (~1700 ulps) */
#define TAU 1e-37          /* absolute error bound for float subnormal results */
#define STACK_CAND 256     /* candidates kept on the stack; more are malloc'ed */

struct surface_photon_map {
    size_t n;
    volume_photon_map *tree; /* the default search (our BVH, r = 0); NULL with the FLANN backend */
    float *pts;          /* 3n floats: the FLANN dataset, also used for the exact distances */
    flann_index_t index; /* NULL when n == 0 */
};

typedef struct {
    double d2;
    int idx;
} cand;

/* build: FLANN_LOG_NONE and BUILD_SEED; queries and free: log level -1 and seed 0 (no global writes) */
static void flann_params(struct FLANNParameters *p, int build)
{
    memset(p, 0, sizeof *p);
    p->algorithm = FLANN_INDEX_KDTREE_SINGLE;
    p->checks = FLANN_CHECKS_UNLIMITED;
    p->eps = 0.0f;
    p->sorted = 1;
    p->max_neighbors = -1;
    p->cores = 1;
    p->trees = 1;
    p->leaf_max_size = LEAF_MAX_SIZE;
    p->log_level = build ? FLANN_LOG_NONE : (enum flann_log_level_t)-1; /* < 0: FLANN leaves its logger */
    p->random_seed = build ? BUILD_SEED : 0;                              /* > 0: FLANN calls srand() */
}

static int coord_ok(double c) { return isfinite(c) && fabs(c) <= COORD_MAX; }

/* The first photon with a coordinate that is not coord_ok, n if none (in parallel: a pass over every photon) */
static size_t first_bad_photon(const photon *ph, size_t n)
{
    size_t bad = n;
#pragma omp parallel for schedule(static) reduction(min : bad) default(none) shared(ph, n)
    for (size_t i = 0; i < n; i++)
        if (!(coord_ok(ph[i].pos[0]) && coord_ok(ph[i].pos[1]) && coord_ok(ph[i].pos[2])) && i < bad) bad = i;
    return bad;
}

static surface_photon_map *build(const photon *ph, size_t n, int use_flann, dp_error *err)
{
    if (n > 0 && !ph) {
        dp_fail_kind(err, DP_ERROR_INTERNAL, "surface photon map: no photon array for %zu photons", n);
        return NULL;
    }
    if (n > (size_t)INT_MAX) {
        dp_fail_kind(err, DP_ERROR_INTERNAL, "surface photon map: %zu photons exceed FLANN's limit of %d", n, INT_MAX);
        return NULL;
    }
    size_t bad = first_bad_photon(ph, n);
    if (bad < n) {
        dp_fail_kind(err, DP_ERROR_INTERNAL,
                     "surface photon map: photon %zu has position (%g, %g, %g) (non-finite or beyond %g)", bad,
                     (double)ph[bad].pos[0], (double)ph[bad].pos[1], (double)ph[bad].pos[2], COORD_MAX);
        return NULL;
    }
    surface_photon_map *m = calloc(1, sizeof *m);
    if (!m) {
        dp_fail_kind(err, DP_ERROR_MEMORY, "surface photon map: out of memory");
        return NULL;
    }
    m->n = n;
    if (n == 0) return m;
    if (!use_flann) {
        if (!(m->tree = volume_map_build(ph, n, 0.0, err))) {
            free(m);
            return NULL;
        }
        return m;
    }
    m->pts = malloc(n * 3 * sizeof *m->pts);
    if (!m->pts) {
        dp_fail_kind(err, DP_ERROR_MEMORY, "surface photon map: out of memory for %zu photons", n);
        free(m);
        return NULL;
    }
    for (size_t i = 0; i < n; i++) memcpy(m->pts + 3 * i, ph[i].pos, 3 * sizeof(float));
    struct FLANNParameters p;
    flann_params(&p, 1);
    float speedup = 0.0f;
    m->index = flann_build_index_float(m->pts, (int)n, 3, &speedup, &p);
    if (!m->index) {
        dp_fail_kind(err, DP_ERROR_INTERNAL, "surface photon map: FLANN could not build the kd-tree over %zu photons", n);
        free(m->pts);
        free(m);
        return NULL;
    }
    return m;
}

surface_photon_map *surface_map_build(const photon *ph, size_t n, dp_error *err) { return build(ph, n, 0, err); }
surface_photon_map *surface_map_build_flann(const photon *ph, size_t n, dp_error *err) { return build(ph, n, 1, err); }

void surface_map_free(surface_photon_map *m)
{
    if (!m) return;
    volume_map_free(m->tree);
    if (m->index) {
        struct FLANNParameters p;
        flann_params(&p, 0);
        flann_free_index_float(m->index, &p);
    }
    free(m->pts);
    free(m);
}

static double exact_d2(const float *p, vec3 x)
{
    double dx = (double)p[0] - x.x, dy = (double)p[1] - x.y, dz = (double)p[2] - x.z;
    return dx * dx + dy * dy + dz * dz;
}

static int cand_before(cand a, cand b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.idx < b.idx); }

/* Insertion sort by (d2, index): FLANN returns candidates sorted by its float distance, so they arrive
 * nearly in order and this is close to linear. */
static void cand_sort(cand *c, int n)
{
    for (int i = 1; i < n; i++) {
        cand v = c[i];
        int j = i;
        for (; j > 0 && cand_before(v, c[j - 1]); j--) c[j] = c[j - 1];
        c[j] = v;
    }
}

/* The first k photons with d2 < R2 in (d2, index) order, by a scan, sorted into the caller's arrays. */
static int query_linear(const surface_photon_map *m, vec3 x, int k, double R2, int *idx, double *d2)
{
    int cnt = 0;
    for (size_t i = 0; i < m->n; i++) {
        double d = exact_d2(m->pts + 3 * i, x);
        if (!(d < R2)) continue;
        if (cnt == k && !(d < d2[k - 1])) continue; /* equal d2: the earlier index stays */
        int j = cnt < k ? cnt++ : k - 1;
        while (j > 0 && d2[j - 1] > d) {
            d2[j] = d2[j - 1];
            idx[j] = idx[j - 1];
            j--;
        }
        d2[j] = d;
        idx[j] = (int)i;
    }
    return cnt;
}

/* Double x rounded up to a float (+inf past FLT_MAX). */
static float float_up(double v)
{
    if (!(v <= FLT_MAX)) return INFINITY;
    float f = (float)v;
    return (double)f < v ? nextafterf(f, INFINITY) : f;
}

/* Lower bound on the double squared distance from x of any photon whose FLANN distance is >= df,
 * for a query whose float rounding is a away from x. */
static double lower_bound(float df, double a)
{
    double e = dp_fmin((double)df, (double)FLT_MAX) / (1.0 + RHO) - TAU;
    double s = e > 0.0 ? sqrt(e) - a : 0.0;
    return s > 0.0 ? s * s * (1.0 - 1e-12) : 0.0;
}

int surface_map_query_knn(const surface_photon_map *m, vec3 x, int k, double R, int *idx, double *d2)
{
    if (!m || m->n == 0 || k <= 0 || !(R > 0.0) || !v3_is_finite(x)) return 0;
    double R2 = R * R;
    if (!(R2 > 0.0)) return 0; /* R*R underflows: nothing has d2 < 0 */
    if (m->tree) return volume_map_query_knn(m->tree, x, k, R, idx, d2);
    int n = (int)m->n;
    if (k > n) k = n;
    if (!coord_ok(x.x) || !coord_ok(x.y) || !coord_ok(x.z)) return query_linear(m, x, k, R2, idx, d2);

    float q[3] = {(float)x.x, (float)x.y, (float)x.z};
    double qx = x.x - q[0], qy = x.y - q[1], qz = x.z - q[2];
    double a = sqrt(qx * qx + qy * qy + qz * qz) * (1.0 + 1e-9); /* |x - q| */
    float rf = float_up(((R + a) * (R + a) + TAU) * (1.0 + RHO));

    long long want = (long long)k + k / 8 + 4;
    int mm = want < n ? (int)want : n;
    int fi_s[STACK_CAND];
    float fd_s[STACK_CAND];
    cand cd_s[STACK_CAND];
    int *fi = fi_s;
    float *fd = fd_s;
    cand *cd = cd_s;
    int cnt = -1;
    for (;;) {
        if (mm > STACK_CAND) {
            if (fi != fi_s) {
                free(fi);
                free(fd);
                free(cd);
            }
            fi = malloc((size_t)mm * sizeof *fi);
            fd = malloc((size_t)mm * sizeof *fd);
            cd = malloc((size_t)mm * sizeof *cd);
            if (!fi || !fd || !cd) break;
        }
        struct FLANNParameters p;
        flann_params(&p, 0);
        int c = flann_radius_search_float(m->index, q, fi, fd, mm, rf, &p);
        if (c < 0) break;
        if (c > mm) c = mm;
        int kept = 0;
        float dmax = 0.0f;
        for (int i = 0; i < c; i++) {
            if (fi[i] < 0 || fi[i] >= n) continue;
            if (fd[i] > dmax) dmax = fd[i];
            double d = exact_d2(m->pts + 3 * (size_t)fi[i], x);
            if (d < R2) cd[kept++] = (cand){d, fi[i]};
        }
        cand_sort(cd, kept);
        int got = kept < k ? kept : k;
        int final = c < mm || mm >= n;
        if (!final) {
            double T = got == k ? cd[k - 1].d2 : R2;
            final = lower_bound(dmax, a) > T;
        }
        if (final) {
            for (int i = 0; i < got; i++) {
                idx[i] = cd[i].idx;
                d2[i] = cd[i].d2;
            }
            cnt = got;
            break;
        }
        mm = mm > n / 2 ? n : 2 * mm;
    }
    if (fi != fi_s) {
        free(fi);
        free(fd);
        free(cd);
    }
    return cnt >= 0 ? cnt : query_linear(m, x, k, R2, idx, d2);
}
