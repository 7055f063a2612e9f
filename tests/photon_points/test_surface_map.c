/* tier: quick */
/* Unit tests of the surface photon map (FLANN kd-tree): every answer is checked against a brute-force
 * scan — the first k photons with d2 < R^2 in (d2, index) order, d2 = |pos - x|^2 in double — on photons
 * spread over the walls of a Cornell-box-like room, plus the edge cases (empty map, one photon, k > n,
 * R = 0, the strict radius boundary, duplicate positions, far queries) and two OpenMP threads querying
 * one map at once. */
#include "test_util.h"

#include "dartspp/photon.h"

#include <omp.h>

/* ---- helpers ---- */

/* A photon at (x, y, z); the other fields are irrelevant to the map. */
/* Every test runs twice: against the default BVH search and against the FLANN backend. */
static int use_flann;
static surface_photon_map *build_map(const photon *ph, size_t n, dp_error *err)
{
    return use_flann ? surface_map_build_flann(ph, n, err) : surface_map_build(ph, n, err);
}

static photon at(double x, double y, double z)
{
    photon p;
    memset(&p, 0, sizeof p);
    p.pos[0] = (float)x;
    p.pos[1] = (float)y;
    p.pos[2] = (float)z;
    return p;
}

static double sq_dist(const photon *p, vec3 x)
{
    double dx = (double)p->pos[0] - x.x, dy = (double)p->pos[1] - x.y, dz = (double)p->pos[2] - x.z;
    return dx * dx + dy * dy + dz * dz;
}

/* Brute force: the first k photons with d2 < R^2 in (d2, index) order. */
static int brute_knn(const photon *ph, size_t n, vec3 x, int k, double R, int *idx, double *d2)
{
    if (k <= 0 || !(R > 0.0)) return 0;
    double R2 = R * R;
    int cnt = 0;
    for (size_t i = 0; i < n; i++) {
        double d = sq_dist(&ph[i], x);
        if (!(d < R2)) continue;
        if (cnt == k && d >= d2[k - 1]) continue;
        int j = cnt < k ? cnt++ : k - 1;
        for (; j > 0 && d2[j - 1] > d; j--) {
            d2[j] = d2[j - 1];
            idx[j] = idx[j - 1];
        }
        d2[j] = d;
        idx[j] = (int)i;
    }
    return cnt;
}

static int int_cmp(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* Same count, the same squared distances in the same order (bit for bit), and within every run of equal
 * distances the same set of indices; fails with a description otherwise. */
static void check_same(int n_got, const int *i_got, const double *d_got, int n_want, const int *i_want,
                       const double *d_want, const char *what, int line)
{
    if (n_got != n_want) fail_msg("line %d (%s): %d results, brute force %d", line, what, n_got, n_want);
    for (int i = 0; i < n_got; i++) {
        if (d_got[i] != d_want[i])
            fail_msg("line %d (%s): result %d has d2 %.17g (index %d), brute force %.17g (index %d)", line, what,
                     i, d_got[i], i_got[i], d_want[i], i_want[i]);
    }
    for (int s = 0; s < n_got;) {
        int e = s + 1;
        while (e < n_got && d_got[e] == d_got[s]) e++;
        int *a = malloc(sizeof(int) * (size_t)(e - s)), *b = malloc(sizeof(int) * (size_t)(e - s));
        assert_true(a && b);
        memcpy(a, i_got + s, sizeof(int) * (size_t)(e - s));
        memcpy(b, i_want + s, sizeof(int) * (size_t)(e - s));
        qsort(a, (size_t)(e - s), sizeof *a, int_cmp);
        qsort(b, (size_t)(e - s), sizeof *b, int_cmp);
        for (int j = 0; j < e - s; j++) {
            if (a[j] != b[j])
                fail_msg("line %d (%s): results %d..%d (d2 %.17g) hold index %d, brute force %d", line, what, s,
                         e - 1, d_got[s], a[j], b[j]);
        }
        free(a);
        free(b);
        s = e;
    }
}

/* Queries the map and the brute force with the same arguments and compares. */
static void check_query(const surface_photon_map *m, const photon *ph, size_t n, vec3 x, int k, double R, int line)
{
    int cap = k > 0 ? k : 1;
    int *ig = malloc(sizeof(int) * (size_t)cap), *iw = malloc(sizeof(int) * (size_t)cap);
    double *dg = malloc(sizeof(double) * (size_t)cap), *dw = malloc(sizeof(double) * (size_t)cap);
    assert_non_null(ig);
    assert_non_null(iw);
    assert_non_null(dg);
    assert_non_null(dw);
    int ng = surface_map_query_knn(m, x, k, R, ig, dg);
    int nw = brute_knn(ph, n, x, k, R, iw, dw);
    char what[160];
    snprintf(what, sizeof what, "x = (%.9g, %.9g, %.9g), k = %d, R = %g", x.x, x.y, x.z, k, R);
    check_same(ng, ig, dg, nw, iw, dw, what, line);
    free(ig);
    free(iw);
    free(dg);
    free(dw);
}
#define CHECK_QUERY(m, ph, n, x, k, R) check_query(m, ph, n, x, k, R, __LINE__)

/* n photons on five walls of the box [-1, 1]^3 (floor, ceiling, back, left, right), with one photon in
 * 50 falling into a tight caustic-like cluster on the floor. */
static photon *room_photons(size_t n, uint64_t seed)
{
    photon *ph = malloc(n * sizeof *ph);
    assert_non_null(ph);
    dp_rng r = rng_stream(seed, 1, 2);
    for (size_t i = 0; i < n; i++) {
        double u = 2.0 * rng_uniform(&r) - 1.0, v = 2.0 * rng_uniform(&r) - 1.0;
        int wall = (int)(rng_uniform(&r) * 5.0);
        if (i % 50 == 0) {
            ph[i] = at(0.3 + 0.002 * u, -1.0, -0.2 + 0.002 * v);
            continue;
        }
        switch (wall) {
        case 0: ph[i] = at(u, -1.0, v); break; /* floor */
        case 1: ph[i] = at(u, 1.0, v); break;  /* ceiling */
        case 2: ph[i] = at(u, v, -1.0); break; /* back */
        case 3: ph[i] = at(-1.0, u, v); break; /* left */
        default: ph[i] = at(1.0, u, v); break; /* right */
        }
    }
    return ph;
}

/* Query i of a mix: near a wall, in the cluster, inside the room, outside it. */
static vec3 room_query(dp_rng *r, int i)
{
    double u = 2.0 * rng_uniform(r) - 1.0, v = 2.0 * rng_uniform(r) - 1.0, w = 2.0 * rng_uniform(r) - 1.0;
    switch (i % 4) {
    case 0: {
        double off = 0.004 * w;
        switch ((int)(rng_uniform(r) * 5.0)) {
        case 0: return v3(u, -1.0 + off, v);
        case 1: return v3(u, 1.0 - off, v);
        case 2: return v3(u, v, -1.0 + off);
        case 3: return v3(-1.0 + off, u, v);
        default: return v3(1.0 - off, u, v);
        }
    }
    case 1: return v3(0.3 + 0.003 * u, -1.0 + 0.001 * w, -0.2 + 0.003 * v);
    case 2: return v3(u, v, w);
    default: return v3(3.0 * u, 3.0 * v, 3.0 * w);
    }
}

static surface_photon_map *build_ok(const photon *ph, size_t n)
{
    dp_error err = {0};
    surface_photon_map *m = build_map(ph, n, &err);
    if (!m) fail_msg("build_map(%zu): %s", n, err.msg);
    return m;
}

/* ---- tests ---- */

/* 2000 queries over 50k wall photons, each with k in {1, 20, 100} and R in {0.01, 0.1, 1e30}. One
 * brute-force scan per query gives the sorted 100 nearest; every (k, R) answer is a prefix of it. */
static void test_random_queries_match_brute_force(void **state)
{
    (void)state;
    const size_t n = 50000;
    const int ks[3] = {1, 20, 100};
    const double Rs[3] = {0.01, 0.1, 1e30};
    photon *ph = room_photons(n, 11);
    surface_photon_map *m = build_ok(ph, n);
    dp_rng r = rng_stream(12, 3, 4);
    int iw[100], ig[100];
    double dw[100], dg[100];
    long nonempty = 0, full = 0, partial = 0;
    for (int q = 0; q < 2000; q++) {
        vec3 x = room_query(&r, q);
        int nw = brute_knn(ph, n, x, 100, 1e30, iw, dw);
        assert_int_equal(nw, 100);
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < 3; b++) {
                int k = ks[a];
                double R2 = Rs[b] * Rs[b];
                int want = 0;
                while (want < k && dw[want] < R2) want++;
                int ng = surface_map_query_knn(m, x, k, Rs[b], ig, dg);
                char what[160];
                snprintf(what, sizeof what, "query %d x = (%.9g, %.9g, %.9g), k = %d, R = %g", q, x.x, x.y, x.z, k,
                         Rs[b]);
                /* the brute-force prefix can end inside a run of equal d2 that continues past it: then
                 * compare against a direct brute force, whose run selection is exact */
                if (want == k && want < 100 && dw[want] == dw[want - 1]) {
                    check_query(m, ph, n, x, k, Rs[b], __LINE__);
                    continue;
                }
                check_same(ng, ig, dg, want, iw, dw, what, __LINE__);
                nonempty += ng > 0;
                full += ng == k;
                partial += ng > 0 && ng < k;
            }
        }
    }
    /* the mix exercises empty, partial (radius-limited) and full (k-limited) answers */
    assert_true(nonempty > 2000);
    assert_true(full > 2000);
    assert_true(partial > 500);
    surface_map_free(m);
    free(ph);
}

/* Queries exactly at photon positions: the photon itself comes first with d2 = 0. */
static void test_query_at_photon_positions(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = room_photons(n, 21);
    surface_photon_map *m = build_ok(ph, n);
    for (size_t i = 0; i < n; i += 97) {
        vec3 x = v3(ph[i].pos[0], ph[i].pos[1], ph[i].pos[2]);
        int idx[20];
        double d2[20];
        int got = surface_map_query_knn(m, x, 1, 1e-3, idx, d2);
        assert_int_equal(got, 1);
        assert_int_equal(idx[0], (int)i);
        assert_true(d2[0] == 0.0);
        /* a tiny radius still finds it: 0 < R^2 */
        assert_int_equal(surface_map_query_knn(m, x, 20, 1e-30, idx, d2), 1);
        assert_int_equal(idx[0], (int)i);
        CHECK_QUERY(m, ph, n, x, 20, 0.05);
        CHECK_QUERY(m, ph, n, x, 20, 1e30);
    }
    surface_map_free(m);
    free(ph);
}

/* R = 0, negative, NaN, or so small that R*R underflows: nothing. Nor for k <= 0 or a non-finite x. */
static void test_radius_zero_and_bad_arguments(void **state)
{
    (void)state;
    const size_t n = 1000;
    photon *ph = room_photons(n, 31);
    surface_photon_map *m = build_ok(ph, n);
    vec3 x = v3(ph[5].pos[0], ph[5].pos[1], ph[5].pos[2]);
    int idx[8];
    double d2[8];
    assert_int_equal(surface_map_query_knn(m, x, 8, 0.0, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, x, 8, -1.0, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, x, 8, NAN, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, x, 8, 1e-200, idx, d2), 0); /* R*R == 0 */
    assert_int_equal(surface_map_query_knn(m, x, 0, 1.0, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, x, -3, 1.0, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, v3(NAN, 0, 0), 8, 1.0, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, v3(0, INFINITY, 0), 8, 1e30, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(NULL, x, 8, 1.0, idx, d2), 0);
    /* R = infinity is "no radius limit" */
    CHECK_QUERY(m, ph, n, x, 8, INFINITY);
    surface_map_free(m);
    free(ph);
}

/* k larger than n: every photon within R, nearest first. */
static void test_k_larger_than_n(void **state)
{
    (void)state;
    const size_t n = 37;
    photon *ph = room_photons(n, 41);
    surface_photon_map *m = build_ok(ph, n);
    int idx[100];
    double d2[100];
    assert_int_equal(surface_map_query_knn(m, v3(0, 0, 0), 100, 1e30, idx, d2), 37);
    CHECK_QUERY(m, ph, n, v3(0, 0, 0), 100, 1e30);
    CHECK_QUERY(m, ph, n, v3(0.5, -0.9, 0.1), 100, 1.0);
    CHECK_QUERY(m, ph, n, v3(0.5, -0.9, 0.1), 37, 1e30);
    CHECK_QUERY(m, ph, n, v3(0.5, -0.9, 0.1), 36, 1e30);
    surface_map_free(m);
    free(ph);
}

static void test_empty_map(void **state)
{
    (void)state;
    dp_error err = {0};
    surface_photon_map *m = build_map(NULL, 0, &err);
    assert_non_null(m);
    int idx[4];
    double d2[4];
    assert_int_equal(surface_map_query_knn(m, v3(0, 0, 0), 4, 1e30, idx, d2), 0);
    surface_map_free(m);
    photon p = at(1, 2, 3);
    m = build_map(&p, 0, &err);
    assert_non_null(m);
    assert_int_equal(surface_map_query_knn(m, v3(1, 2, 3), 4, 1.0, idx, d2), 0);
    surface_map_free(m);
    surface_map_free(NULL);
}

/* One photon; the radius test is strict: d2 == R^2 is out. */
static void test_single_photon(void **state)
{
    (void)state;
    photon p = at(0.25, -0.5, 2.0);
    surface_photon_map *m = build_ok(&p, 1);
    int idx[5] = {-1, -1, -1, -1, -1};
    double d2[5];
    assert_int_equal(surface_map_query_knn(m, v3(0.75, -0.5, 2.0), 5, 1.0, idx, d2), 1);
    assert_int_equal(idx[0], 0);
    assert_true(d2[0] == 0.25);
    assert_int_equal(idx[1], -1); /* nothing written past the count */
    assert_int_equal(surface_map_query_knn(m, v3(0.75, -0.5, 2.0), 5, 0.5, idx, d2), 0);
    assert_int_equal(surface_map_query_knn(m, v3(0.75, -0.5, 2.0), 5, nextafter(0.5, 1.0), idx, d2), 1);
    assert_int_equal(surface_map_query_knn(m, v3(0.25, -0.5, 2.0), 1, 1e-20, idx, d2), 1);
    assert_true(d2[0] == 0.0);
    assert_int_equal(surface_map_query_knn(m, v3(-100, 50, 7), 1, 1e30, idx, d2), 1);
    assert_true(d2[0] == sq_dist(&p, v3(-100, 50, 7)));
    surface_map_free(m);
}

/* Photons on an integer grid: many exact distance ties, and photons exactly on the radius. */
static void test_strict_radius_and_ties_on_a_grid(void **state)
{
    (void)state;
    photon ph[5 * 5 * 5];
    size_t n = 0;
    for (int i = -2; i <= 2; i++)
        for (int j = -2; j <= 2; j++)
            for (int l = -2; l <= 2; l++) ph[n++] = at(i, j, l);
    surface_photon_map *m = build_ok(ph, n);
    int idx[125];
    double d2[125];
    /* R = 1 from the centre: only the centre itself (its 6 neighbours sit at d2 == 1) */
    assert_int_equal(surface_map_query_knn(m, v3(0, 0, 0), 125, 1.0, idx, d2), 1);
    assert_int_equal(idx[0], 62);
    /* just past 1: the centre and its 6 neighbours */
    assert_int_equal(surface_map_query_knn(m, v3(0, 0, 0), 125, nextafter(1.0, 2.0), idx, d2), 7);
    for (int k = 1; k <= 125; k++) {
        CHECK_QUERY(m, ph, n, v3(0, 0, 0), k, 1e30);
        CHECK_QUERY(m, ph, n, v3(0.5, 0.5, 0.5), k, 1e30); /* 8 photons at the same distance, and so on */
        CHECK_QUERY(m, ph, n, v3(0.5, 0, 0), k, 1.5);
        CHECK_QUERY(m, ph, n, v3(1, 1, 1), k, 2.0);
    }
    surface_map_free(m);
}

/* Duplicate positions: a stack of 1000 photons at one point plus random ones, and duplicated pairs. The
 * answer is the brute force's (lowest indices among equal distances) and the same on every call. */
static void test_duplicate_positions(void **state)
{
    (void)state;
    const size_t n = 6000;
    photon *ph = room_photons(n, 51);
    for (size_t i = 1000; i < 2000; i++) ph[i] = at(0.125, -1.0, 0.5);
    for (size_t i = 3000; i < 4000; i += 2) ph[i + 1] = ph[i];
    surface_photon_map *m = build_ok(ph, n);
    vec3 x = v3(0.125, -1.0, 0.5);
    int idx[100], idx2[100];
    double d2[100], d22[100];
    assert_int_equal(surface_map_query_knn(m, x, 20, 0.1, idx, d2), 20);
    for (int i = 0; i < 20; i++) {
        assert_int_equal(idx[i], 1000 + i);
        assert_true(d2[i] == 0.0);
    }
    for (int k = 1; k <= 100; k += 11) {
        for (int rep = 0; rep < 3; rep++) {
            int a = surface_map_query_knn(m, v3(0.13, -0.999, 0.5), k, 0.2, idx, d2);
            int b = surface_map_query_knn(m, v3(0.13, -0.999, 0.5), k, 0.2, idx2, d22);
            assert_int_equal(a, b);
            assert_memory_equal(idx, idx2, sizeof(int) * (size_t)a);
            assert_memory_equal(d2, d22, sizeof(double) * (size_t)a);
        }
        CHECK_QUERY(m, ph, n, x, k, 1e30);
        CHECK_QUERY(m, ph, n, v3(0.13, -0.999, 0.5), k, 0.2);
        for (size_t i = 3000; i < 4000; i += 50) {
            vec3 y = v3(ph[i].pos[0], ph[i].pos[1], ph[i].pos[2]);
            CHECK_QUERY(m, ph, n, y, k, 0.05);
            CHECK_QUERY(m, ph, n, v3_add(y, v3(1e-4, 1e-4, 0)), k, 1e30);
        }
    }
    /* every photon at one point */
    photon same[300];
    for (int i = 0; i < 300; i++) same[i] = at(-0.5, 0.25, 1.0);
    surface_photon_map *m2 = build_ok(same, 300);
    for (int k = 1; k <= 100; k += 33) {
        CHECK_QUERY(m2, same, 300, v3(-0.5, 0.25, 1.0), k, 1e-3);
        CHECK_QUERY(m2, same, 300, v3(0, 0, 0), k, 1e30);
    }
    surface_map_free(m2);
    surface_map_free(m);
    free(ph);
}

/* Queries far outside the photons, including beyond the float-safe range (answered by a scan). */
static void test_far_queries(void **state)
{
    (void)state;
    const size_t n = 3000;
    photon *ph = room_photons(n, 61);
    surface_photon_map *m = build_ok(ph, n);
    CHECK_QUERY(m, ph, n, v3(1e6, -2e6, 3e5), 10, 1e30);
    CHECK_QUERY(m, ph, n, v3(1e6, -2e6, 3e5), 10, 2.2e6);
    CHECK_QUERY(m, ph, n, v3(3e20, 0, 0), 10, 1e30);
    CHECK_QUERY(m, ph, n, v3(3e20, 0, 0), 10, 1e300);
    CHECK_QUERY(m, ph, n, v3(1e-30, 1e-30, -1.0), 10, 1e-3);
    surface_map_free(m);
    free(ph);
}

/* Far from the origin a double query is up to ~1e-4 away from its float rounding, a sizeable fraction
 * of R: the answer must still be the double-exact one. */
static void test_queries_between_floats(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = malloc(n * sizeof *ph);
    assert_non_null(ph);
    dp_rng r = rng_stream(91, 0, 0);
    for (size_t i = 0; i < n; i++)
        ph[i] = at(1234.5 + 0.05 * rng_uniform(&r), -1.0, 321.25 + 0.05 * rng_uniform(&r));
    surface_photon_map *m = build_ok(ph, n);
    for (int q = 0; q < 400; q++) {
        vec3 x = v3(1234.5 + 0.05 * rng_uniform(&r), -1.0 + 1e-4 * rng_uniform(&r), 321.25 + 0.05 * rng_uniform(&r));
        CHECK_QUERY(m, ph, n, x, 1, 1e-3);
        CHECK_QUERY(m, ph, n, x, 20, 1e-3);
        CHECK_QUERY(m, ph, n, x, 20, 4e-4);
        CHECK_QUERY(m, ph, n, x, 100, 1e30);
    }
    surface_map_free(m);
    free(ph);
}

/* A position that is not finite or beyond the float-safe range is refused at build. */
static void test_build_rejects_bad_positions(void **state)
{
    (void)state;
    photon ph[3] = {at(0, 0, 0), at(1, 1, 1), at(2, 2, 2)};
    ph[1].pos[2] = NAN;
    dp_error err = {0};
    assert_null(build_map(ph, 3, &err));
    assert_non_null(strstr(err.msg, "photon 1"));
    ph[1].pos[2] = 1e30f;
    err.msg[0] = 0;
    assert_null(build_map(ph, 3, &err));
    assert_non_null(strstr(err.msg, "photon 1"));
    err.msg[0] = 0;
    assert_null(build_map(NULL, 3, &err));
    assert_true(err.msg[0] != 0);
}

/* Two OpenMP threads querying one map at the same time get what one thread gets. */
static void test_concurrent_queries(void **state)
{
    (void)state;
    const size_t n = 50000;
    const int nq = 4000, k = 20;
    photon *ph = room_photons(n, 71);
    surface_photon_map *m = build_ok(ph, n);
    vec3 *xs = malloc(sizeof *xs * (size_t)nq);
    int *cnt1 = malloc(sizeof(int) * (size_t)nq), *cnt2 = malloc(sizeof(int) * (size_t)nq);
    int *idx1 = malloc(sizeof(int) * (size_t)(nq * k)), *idx2 = malloc(sizeof(int) * (size_t)(nq * k));
    double *d1 = malloc(sizeof(double) * (size_t)(nq * k)), *d2 = malloc(sizeof(double) * (size_t)(nq * k));
    assert_true(xs && cnt1 && cnt2 && idx1 && idx2 && d1 && d2);
    dp_rng r = rng_stream(72, 0, 0);
    for (int q = 0; q < nq; q++) xs[q] = room_query(&r, q);
    const double Rs[3] = {0.01, 0.1, 1e30};
    for (int q = 0; q < nq; q++)
        cnt1[q] = surface_map_query_knn(m, xs[q], k, Rs[q % 3], idx1 + (size_t)q * k, d1 + (size_t)q * k);
    memset(idx2, 0xff, sizeof(int) * (size_t)(nq * k));
    memset(d2, 0, sizeof(double) * (size_t)(nq * k));
    int threads = 0;
    int per_thread[2] = {0, 0};
    omp_set_dynamic(0);
#pragma omp parallel num_threads(2)
    {
#pragma omp single
        threads = omp_get_num_threads();
        int t = omp_get_thread_num();
        /* interleaved so that both threads are in FLANN at the same time on neighbouring queries */
#pragma omp for schedule(static, 1)
        for (int q = 0; q < nq; q++) {
            cnt2[q] = surface_map_query_knn(m, xs[q], k, Rs[q % 3], idx2 + (size_t)q * k, d2 + (size_t)q * k);
            per_thread[t]++;
        }
    }
    assert_int_equal(threads, 2);
    assert_int_equal(per_thread[0], nq / 2);
    assert_int_equal(per_thread[1], nq / 2);
    for (int q = 0; q < nq; q++) {
        assert_int_equal(cnt1[q], cnt2[q]);
        assert_memory_equal(idx1 + (size_t)q * k, idx2 + (size_t)q * k, sizeof(int) * (size_t)cnt1[q]);
        assert_memory_equal(d1 + (size_t)q * k, d2 + (size_t)q * k, sizeof(double) * (size_t)cnt1[q]);
    }
    /* and the threaded answers are right, spot-checked against the brute force */
    for (int q = 0; q < nq; q += 40) {
        int iw[20];
        double dw[20];
        int nw = brute_knn(ph, n, xs[q], k, Rs[q % 3], iw, dw);
        check_same(cnt2[q], idx2 + (size_t)q * k, d2 + (size_t)q * k, nw, iw, dw, "threaded", __LINE__);
    }
    free(xs);
    free(cnt1);
    free(cnt2);
    free(idx1);
    free(idx2);
    free(d1);
    free(d2);
    surface_map_free(m);
    free(ph);
}

/* Rebuilding over the same photons gives the same answers (the map is rebuilt every iteration). */
static void test_rebuild_is_deterministic(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = room_photons(n, 81);
    surface_photon_map *a = build_ok(ph, n);
    surface_photon_map *b = build_ok(ph, n);
    dp_rng r = rng_stream(82, 0, 0);
    for (int q = 0; q < 500; q++) {
        vec3 x = room_query(&r, q);
        int ia[20], ib[20];
        double da[20], db[20];
        int na = surface_map_query_knn(a, x, 20, 0.1, ia, da);
        int nb = surface_map_query_knn(b, x, 20, 0.1, ib, db);
        assert_int_equal(na, nb);
        assert_memory_equal(ia, ib, sizeof(int) * (size_t)na);
        assert_memory_equal(da, db, sizeof(double) * (size_t)na);
    }
    surface_map_free(a);
    surface_map_free(b);
    free(ph);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_queries_match_brute_force),
        cmocka_unit_test(test_query_at_photon_positions),
        cmocka_unit_test(test_radius_zero_and_bad_arguments),
        cmocka_unit_test(test_k_larger_than_n),
        cmocka_unit_test(test_empty_map),
        cmocka_unit_test(test_single_photon),
        cmocka_unit_test(test_strict_radius_and_ties_on_a_grid),
        cmocka_unit_test(test_duplicate_positions),
        cmocka_unit_test(test_far_queries),
        cmocka_unit_test(test_queries_between_floats),
        cmocka_unit_test(test_build_rejects_bad_positions),
        cmocka_unit_test(test_concurrent_queries),
        cmocka_unit_test(test_rebuild_is_deterministic),
    };
    int failed = cmocka_run_group_tests_name("surface map, BVH search", tests, NULL, NULL);
    use_flann = 1;
    return failed + cmocka_run_group_tests_name("surface map, FLANN backend", tests, NULL, NULL);
}
