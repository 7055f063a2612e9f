/* tier: quick */
/* Volume photon map: every beam query must return exactly the photons a brute-force scan accepts, with
 * the same t and d2, for random, axis-parallel, inside-the-cloud, zero-length and unbounded segments, zero
 * and huge radii, empty and one-photon maps and duplicate positions; and the visit order must not depend
 * on the build (run twice, or with another thread count); maps large enough for the parallel partition of
 * the top levels, with ties and a sample that misses the median. Photons carry their input index in `bounce`.
 * The query with a time window must visit, in order, the plain query's photons minus some outside the
 * window and never one inside it (the film's gate test, computed as the sensor pass does), for random and
 * boundary times and both camera legs. */
#include "test_util.h"

#include "dartspp/photon.h"

#include <omp.h>

typedef struct {
    int idx;
    double t, d2;
} beam_hit;

typedef struct {
    beam_hit *v;
    size_t n, cap;
} hit_list;

static void hit_push(hit_list *l, int idx, double t, double d2)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 256;
        l->v = realloc(l->v, l->cap * sizeof *l->v);
        assert_non_null(l->v);
    }
    l->v[l->n].idx = idx;
    l->v[l->n].t = t;
    l->v[l->n].d2 = d2;
    l->n++;
}

static void collect_hit(void *ctx, const photon *p, double t, double d2) { hit_push(ctx, p->bounce, t, d2); }

static int by_index(const void *a, const void *b)
{
    int x = ((const beam_hit *)a)->idx, y = ((const beam_hit *)b)->idx;
    return (x > y) - (x < y);
}

/* The definition, scanned over every photon in input order: t = w·d, d2 = |w - t·d|^2 with w = p - o. */
static void brute_force(const photon *ph, size_t n, double r, vec3 o, vec3 d, double tmax, hit_list *out)
{
    for (size_t i = 0; i < n; i++) {
        vec3 w = v3_sub(v3(ph[i].pos[0], ph[i].pos[1], ph[i].pos[2]), o);
        double t = v3_dot(w, d);
        if (!(t >= 0.0 && t <= tmax)) continue;
        vec3 v = v3_sub(w, v3_scale(d, t));
        double d2 = v3_dot(v, v);
        if (d2 <= r * r) hit_push(out, ph[i].bounce, t, d2);
    }
}

static int close_rel(double a, double b, double rel)
{
    return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) || a == b;
}

/* Runs one query on the map and by brute force and asserts the same photons, t and d2. Returns the hits. */
static size_t check_query(const volume_photon_map *m, const photon *ph, size_t n, double r, vec3 o, vec3 d, double tmax)
{
    hit_list got = {0}, want = {0};
    photon_map_query_beam(m, o, d, tmax, collect_hit, &got);
    brute_force(ph, n, r, o, d, tmax, &want);
    if (got.n) qsort(got.v, got.n, sizeof *got.v, by_index);
    if (got.n != want.n)
        fail_msg("o=(%.17g %.17g %.17g) d=(%.17g %.17g %.17g) tmax=%g r=%g: map %zu photons, brute force %zu", o.x, o.y,
                 o.z, d.x, d.y, d.z, tmax, r, got.n, want.n);
    for (size_t i = 0; i < got.n; i++) {
        assert_int_equal(got.v[i].idx, want.v[i].idx);
        assert_true(close_rel(got.v[i].t, want.v[i].t, 1e-9));
        assert_true(close_rel(got.v[i].d2, want.v[i].d2, 1e-9));
        /* and d2 is |p - o|^2 - t^2 (which loses digits to cancellation, hence the scale) */
        const float *p = ph[want.v[i].idx].pos;
        vec3 w = v3_sub(v3(p[0], p[1], p[2]), o);
        assert_true(fabs(got.v[i].d2 - (v3_dot(w, w) - got.v[i].t * got.v[i].t)) <= 1e-12 * (v3_dot(w, w) + 1.0));
    }
    size_t count = got.n;
    free(got.v);
    free(want.v);
    return count;
}

static photon *alloc_photons(size_t n)
{
    photon *ph = calloc(n ? n : 1, sizeof *ph);
    assert_non_null(ph);
    for (size_t i = 0; i < n; i++) ph[i].bounce = (int)i;
    return ph;
}

static void set_pos(photon *p, double x, double y, double z)
{
    p->pos[0] = (float)x;
    p->pos[1] = (float)y;
    p->pos[2] = (float)z;
}

static vec3 pos_of(const photon *p) { return v3(p->pos[0], p->pos[1], p->pos[2]); }

/* n photons uniform in [0, 1]^3 */
static photon *random_cloud(size_t n, uint64_t seed)
{
    photon *ph = alloc_photons(n);
    dp_rng g = rng_stream(seed, 1, 0);
    for (size_t i = 0; i < n; i++) set_pos(&ph[i], rng_uniform(&g), rng_uniform(&g), rng_uniform(&g));
    return ph;
}

/* k^3 photons on the integer grid {0..k-1}^3: ties at exactly r and exactly t = 0 are common */
static photon *grid_cloud(int k)
{
    photon *ph = alloc_photons((size_t)k * k * k);
    for (int i = 0; i < k * k * k; i++) set_pos(&ph[i], i % k, (i / k) % k, i / (k * k));
    return ph;
}

static volume_photon_map *build_or_fail(const photon *ph, size_t n, double r)
{
    dp_error err = {0};
    volume_photon_map *m = volume_map_build(ph, n, r, &err);
    if (!m) fail_msg("volume_map_build: %s", err.msg);
    assert_int_equal(volume_map_size(m), n);
    assert_true(volume_map_splits_ok(m)); /* the build's invariant, which no query can see */
    return m;
}

static vec3 random_point(dp_rng *g, double lo, double hi)
{
    double s = hi - lo;
    return v3(lo + s * rng_uniform(g), lo + s * rng_uniform(g), lo + s * rng_uniform(g));
}

static vec3 random_dir(dp_rng *g)
{
    double u1 = rng_uniform(g);
    return sample_uniform_sphere(u1, rng_uniform(g));
}

/* the six axis directions, two of them with negative zeros */
static vec3 axis_dir(int k)
{
    static const double s[6][3] = {{1, 0, 0}, {-1, -0.0, 0}, {0, 1, 0}, {0, -1, 0}, {-0.0, -0.0, 1}, {0, 0, -1}};
    return v3(s[k][0], s[k][1], s[k][2]);
}

static void count_callback(void *ctx, const photon *p, double t, double d2)
{
    (void)p;
    (void)t;
    (void)d2;
    (*(size_t *)ctx)++;
}

/* Rays through photons along small integer directions, r = 0: a photon is accepted only where t·d
 * reproduces p - o exactly, and the node boxes (points) must not lose it to slab rounding. */
static void test_rays_through_photons(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = random_cloud(n, 111);
    volume_photon_map *m = build_or_fail(ph, n, 0.0);
    dp_rng g = rng_stream(112, 0, 0);
    size_t found = 0;
    for (int i = 0; i < 2000; i++) {
        vec3 step = v3(0, 0, 0);
        while (v3_is_zero(step))
            step = v3((double)(rng_next_u64(&g) % 7) - 3, (double)(rng_next_u64(&g) % 7) - 3,
                      (double)(rng_next_u64(&g) % 7) - 3);
        vec3 p = pos_of(&ph[rng_next_u64(&g) % n]);
        vec3 o = v3_sub(p, v3_scale(step, 0.5)); /* exact: p - o = step / 2 */
        found += check_query(m, ph, n, 0.0, o, v3_norm(step), INFINITY);
    }
    assert_true(found > 100);
    volume_map_free(m);
    free(ph);
}

/* Photons at perpendicular distance r (to rounding) from axis-parallel rays, with an r that no float
 * equals: about half are accepted, and node boxes must be rounded outward to keep them. */
static void test_photons_at_radius(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 121);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(122, 0, 0);
    size_t found = 0;
    for (int i = 0; i < 1200; i++) {
        vec3 p = pos_of(&ph[rng_next_u64(&g) % n]);
        vec3 d = axis_dir(i % 6);
        int a = (i / 6) % 3;
        if (fabs(v3_comp(d, a)) > 0) a = (a + 1) % 3; /* a transverse axis */
        double side = (i / 18) % 2 ? r : -r;
        vec3 o = v3_sub(p, d);
        if (a == 0) o.x += side;
        else if (a == 1) o.y += side;
        else o.z += side;
        found += check_query(m, ph, n, r, o, d, 2.0) > 0;
    }
    assert_true(found > 100);
    volume_map_free(m);
    free(ph);
}

static void test_empty_map(void **state)
{
    (void)state;
    volume_photon_map *m = build_or_fail(NULL, 0, 0.1);
    size_t calls = 0;
    photon_map_query_beam(m, v3(0, 0, 0), v3(0, 0, 1), INFINITY, count_callback, &calls);
    photon_map_query_beam(NULL, v3(0, 0, 0), v3(0, 0, 1), INFINITY, count_callback, &calls);
    assert_int_equal(calls, 0);
    assert_int_equal(volume_map_size(NULL), 0);
    volume_map_free(m);
    volume_map_free(NULL);
}

static void test_bad_input(void **state)
{
    (void)state;
    photon *ph = random_cloud(10, 3);
    dp_error err = {0};
    assert_null(volume_map_build(ph, 10, -1.0, &err));
    assert_non_null(strstr(err.msg, "radius"));
    assert_null(volume_map_build(ph, 10, NAN, &err));
    ph[4].pos[1] = NAN;
    assert_null(volume_map_build(ph, 10, 0.1, &err));
    assert_non_null(strstr(err.msg, "non-finite"));
    free(ph);
}

static void test_single_photon(void **state)
{
    (void)state;
    photon *ph = alloc_photons(1);
    set_pos(ph, 0, 1, 0);
    volume_photon_map *m = build_or_fail(ph, 1, 1.0);
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(-1, 0, 0), v3(1, 0, 0), 5), 1);        /* d2 = r^2 exactly */
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(-1, 0, 0), v3(1, 0, 0), 1), 1);        /* t = tmax exactly */
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(-1, 0, 0), v3(1, 0, 0), 0.999), 0);    /* t > tmax */
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(1, 0, 0), v3(1, 0, 0), INFINITY), 0);  /* behind */
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(0, -0.5, 0), v3(0, 0, 1), 9), 0);      /* 1.5 away */
    assert_int_equal(check_query(m, ph, 1, 1.0, v3(0, 1, 0), v3(0, 0, -1), 0), 1);        /* at the origin */
    dp_rng g = rng_stream(7, 0, 0);
    for (int i = 0; i < 200; i++)
        check_query(m, ph, 1, 1.0, random_point(&g, -2, 3), random_dir(&g), i % 2 ? INFINITY : 2 * rng_uniform(&g));
    volume_map_free(m);
    free(ph);
}

static void test_random_rays(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 11);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(12, 0, 0);
    size_t total = 0;
    for (int i = 0; i < 1000; i++) {
        vec3 o = random_point(&g, -0.5, 1.5);
        vec3 d = random_dir(&g);
        double tmax = i % 4 == 0 ? INFINITY : 2.0 * rng_uniform(&g);
        total += check_query(m, ph, n, r, o, d, tmax);
    }
    assert_true(total > 10000);
    volume_map_free(m);
    free(ph);
}

static void test_axis_parallel_rays(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 21);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(22, 0, 0);
    for (int k = 0; k < 6; k++) {
        vec3 d = axis_dir(k);
        for (int i = 0; i < 100; i++) {
            const photon *target = &ph[rng_next_u64(&g) % n];
            vec3 p = pos_of(target);
            /* back off along the axis: the ray runs exactly through the target (d2 = 0) */
            vec3 o = v3_sub(p, v3_scale(d, 1.5));
            assert_true(check_query(m, ph, n, r, o, d, i % 2 ? INFINITY : 3.0) >= 1);
            /* origin on the target's coordinate planes, offset in the others by up to 2r */
            vec3 shift = v3_scale(v3_sub(random_point(&g, 0, 1), v3s(0.5)), 4 * r);
            vec3 across = v3_sub(shift, v3_scale(d, v3_dot(shift, d)));
            vec3 q = v3_add(o, i % 3 == 0 ? v3(across.x, 0, 0) : (i % 3 == 1 ? v3(0, across.y, 0) : across));
            check_query(m, ph, n, r, q, d, i % 2 ? INFINITY : 3.0);
            check_query(m, ph, n, r, p, d, rng_uniform(&g)); /* starting on the target */
        }
    }
    volume_map_free(m);
    free(ph);
}

/* Integer grid with r = 1: along grid lines, neighbours sit at d2 = r^2 exactly, and with zero-length
 * segments the photons at t = 0 exactly decide the answer. */
static void test_grid_ties(void **state)
{
    (void)state;
    const int k = 12;
    const size_t n = (size_t)k * k * k;
    photon *ph = grid_cloud(k);
    volume_photon_map *m = build_or_fail(ph, n, 1.0);
    dp_rng g = rng_stream(31, 0, 0);
    for (int i = 0; i < 300; i++) {
        vec3 o = v3((double)(rng_next_u64(&g) % k), (double)(rng_next_u64(&g) % k), (double)(rng_next_u64(&g) % k));
        vec3 d = axis_dir(i % 6);
        assert_true(check_query(m, ph, n, 1.0, o, d, INFINITY) >= 3);   /* o + its 2..4 neighbours */
        assert_true(check_query(m, ph, n, 1.0, o, d, 0.0) >= 3);        /* t = 0: the plane through o */
        check_query(m, ph, n, 1.0, v3_sub(o, v3_scale(d, 3)), d, 3.0);  /* tmax = t of o exactly */
        check_query(m, ph, n, 1.0, v3_add(o, v3(0.5, 0.5, 0.5)), d, 4.0);
    }
    volume_map_free(m);
    free(ph);
}

static void test_rays_inside_cloud(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.04;
    photon *ph = random_cloud(n, 41);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(42, 0, 0);
    for (int i = 0; i < 300; i++) {
        vec3 o = i % 2 ? random_point(&g, 0.1, 0.9) : pos_of(&ph[rng_next_u64(&g) % n]);
        vec3 d = random_dir(&g);
        size_t hits = check_query(m, ph, n, r, o, d, i % 3 == 0 ? INFINITY : 0.3);
        if (i % 2 == 0) assert_true(hits >= 1); /* the photon at the origin */
    }
    volume_map_free(m);
    free(ph);
}

static void test_zero_length_segments(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 51);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(52, 0, 0);
    for (int i = 0; i < 200; i++) {
        vec3 o = pos_of(&ph[rng_next_u64(&g) % n]);
        vec3 d = i % 2 ? random_dir(&g) : axis_dir(i % 6);
        assert_true(check_query(m, ph, n, r, o, d, 0.0) >= 1);
        check_query(m, ph, n, r, random_point(&g, 0, 1), d, 0.0);
    }
    volume_map_free(m);
    free(ph);
}

static void test_infinite_segments(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 61);
    volume_photon_map *m = build_or_fail(ph, n, r);
    dp_rng g = rng_stream(62, 0, 0);
    for (int i = 0; i < 200; i++) {
        vec3 o = random_point(&g, -100, 100); /* far away too */
        vec3 toward = v3_norm(v3_sub(random_point(&g, 0, 1), o));
        check_query(m, ph, n, r, o, toward, INFINITY);
        check_query(m, ph, n, r, o, random_dir(&g), INFINITY);
    }
    volume_map_free(m);
    free(ph);
}

static void test_zero_radius(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = random_cloud(n, 71);
    volume_photon_map *m = build_or_fail(ph, n, 0.0);
    dp_rng g = rng_stream(72, 0, 0);
    for (int i = 0; i < 300; i++) {
        vec3 p = pos_of(&ph[rng_next_u64(&g) % n]);
        vec3 d = axis_dir(i % 6);
        assert_true(check_query(m, ph, n, 0.0, v3_sub(p, v3_scale(d, 2)), d, INFINITY) >= 1);
        assert_true(check_query(m, ph, n, 0.0, p, random_dir(&g), 1.0) >= 1);
        check_query(m, ph, n, 0.0, random_point(&g, -1, 2), random_dir(&g), INFINITY);
    }
    volume_map_free(m);
    free(ph);
}

static void test_huge_radius(void **state)
{
    (void)state;
    const size_t n = 20000;
    photon *ph = random_cloud(n, 81);
    const double radii[2] = {10.0, INFINITY};
    dp_rng g = rng_stream(82, 0, 0);
    for (int k = 0; k < 2; k++) {
        volume_photon_map *m = build_or_fail(ph, n, radii[k]);
        for (int i = 0; i < 40; i++) {
            vec3 o = random_point(&g, -1, 2);
            vec3 d = i % 4 == 0 ? axis_dir(i % 6) : random_dir(&g);
            check_query(m, ph, n, radii[k], o, d, i % 2 ? INFINITY : 0.5);
        }
        /* from beyond the cloud looking at it, every photon */
        assert_int_equal(check_query(m, ph, n, radii[k], v3(0.5, 0.5, -1), v3(0, 0, 1), INFINITY), n);
        volume_map_free(m);
    }
    free(ph);
}

static void test_duplicate_positions(void **state)
{
    (void)state;
    const size_t n = 5000;
    photon *ph = alloc_photons(n);
    dp_rng g = rng_stream(91, 0, 0);
    vec3 sites[7];
    for (int s = 0; s < 7; s++) sites[s] = random_point(&g, 0, 1);
    for (size_t i = 0; i < n; i++) {
        vec3 s = sites[i % 7];
        set_pos(&ph[i], s.x, s.y, s.z);
    }
    volume_photon_map *m = build_or_fail(ph, n, 0.05);
    for (int i = 0; i < 200; i++) {
        vec3 s = pos_of(&ph[i % 7]);
        assert_true(check_query(m, ph, n, 0.05, v3_sub(s, v3_scale(axis_dir(i % 6), 1)), axis_dir(i % 6), 2) >= n / 7);
        check_query(m, ph, n, 0.05, random_point(&g, -0.5, 1.5), random_dir(&g), INFINITY);
    }
    volume_map_free(m);
    /* all in one spot */
    for (size_t i = 0; i < n; i++) set_pos(&ph[i], 0.25, 0.5, 0.75);
    m = build_or_fail(ph, n, 0.0);
    assert_int_equal(check_query(m, ph, n, 0.0, v3(0.25, 0.5, 0), v3(0, 0, 1), INFINITY), n);
    assert_int_equal(check_query(m, ph, n, 0.0, v3(0.25, 0.5, 0.75), random_dir(&g), 0), n);
    assert_int_equal(check_query(m, ph, n, 0.0, v3(0.25, 0.5001, 0), v3(0, 0, 1), INFINITY), 0);
    volume_map_free(m);
    /* all at the origin, queried from the origin: o lies on every plane of every (point) box */
    for (size_t i = 0; i < n; i++) set_pos(&ph[i], 0, 0, 0);
    m = build_or_fail(ph, n, 0.0);
    for (int k = 0; k < 6; k++) {
        assert_int_equal(check_query(m, ph, n, 0.0, v3(0, 0, 0), axis_dir(k), INFINITY), n);
        assert_int_equal(check_query(m, ph, n, 0.0, v3(0, 0, 0), axis_dir(k), 0), n);
    }
    volume_map_free(m);
    free(ph);
}

/* Maps of 300,000 photons: their top levels are split by the parallel partition (ranges of 65,536 photons
 * and more; docs/design.md §2.4). Three clouds: uniform; x on five planes only (the two keys that bracket the
 * median rank are equal, and a fifth of the photons ties with them); and one built so that the sampled keys
 * miss the median rank at the root (the sampled positions hold x ≥ 1, all others x in [0, 0.5] and a thin
 * y, z spread, so x is the split axis): the selection must then fall back to the group that holds the rank.
 * Every node must split at a plane (build_or_fail: volume_map_splits_ok; the queries alone cannot see a
 * wrong split, the boxes being exact), and every query must match the brute-force scan. */
static void test_parallel_partition(void **state)
{
    (void)state;
    const size_t n = 300000;
    const double r = 0.02;
    const int keys = (int)pow(n / 4.0, 2.0 / 3.0); /* the root's key sample, as volume_map.c band_keys draws it */
    const size_t step = n / (size_t)keys;
    for (int cloud = 0; cloud < 3; cloud++) {
        photon *ph = random_cloud(n, 141 + (uint64_t)cloud);
        for (size_t i = 0; i < n && cloud == 1; i++) ph[i].pos[0] = 0.25f * (float)(i % 5);
        for (size_t i = 0; i < n && cloud == 2; i++) {
            int sampled = i % step == step / 2 && i / step < (size_t)keys;
            double x = sampled ? 1.0 + 1e-3 * (double)(i / step) : 0.5 * ph[i].pos[0];
            set_pos(&ph[i], x, 0.1 * ph[i].pos[1], 0.1 * ph[i].pos[2]);
        }
        volume_photon_map *m = build_or_fail(ph, n, r);
        dp_rng g = rng_stream(150 + (uint64_t)cloud, 0, 0);
        size_t total = 0;
        for (int i = 0; i < 150; i++) {
            const photon *target = &ph[rng_next_u64(&g) % n];
            vec3 d = random_dir(&g);
            total += check_query(m, ph, n, r, v3_sub(pos_of(target), d), d, i % 2 ? INFINITY : 2.0);
        }
        assert_true(total >= 150); /* every ray runs through its target photon */
        volume_map_free(m);
        free(ph);
    }
}

static void record_order(void *ctx, const photon *p, double t, double d2)
{
    (void)t;
    (void)d2;
    hit_push(ctx, p->bounce, 0, 0);
}

/* Same input, two builds (one thread, then every thread): the same photons in the same order. */
static void test_visit_order_deterministic(void **state)
{
    (void)state;
    const size_t n = 100000; /* large enough for the build to spawn tasks */
    const double r = 0.02;
    photon *ph = random_cloud(n, 101);
    int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    volume_photon_map *a = build_or_fail(ph, n, r);
    omp_set_num_threads(threads > 1 ? threads : 2);
    volume_photon_map *b = build_or_fail(ph, n, r);
    omp_set_num_threads(threads);
    dp_rng g = rng_stream(102, 0, 0);
    for (int i = 0; i < 200; i++) {
        vec3 o = random_point(&g, -0.5, 1.5);
        vec3 d = random_dir(&g);
        hit_list la = {0}, lb = {0};
        photon_map_query_beam(a, o, d, INFINITY, record_order, &la);
        photon_map_query_beam(b, o, d, INFINITY, record_order, &lb);
        assert_int_equal(la.n, lb.n);
        for (size_t k = 0; k < la.n; k++) assert_int_equal(la.v[k].idx, lb.v[k].idx);
        free(la.v);
        free(lb.v);
    }
    volume_map_free(a);
    volume_map_free(b);
    free(ph);
}

/* ---- time windows ---- */

/* A window query's inputs and what it visited: every photon, and those whose total time the film counts. */
typedef struct {
    beam_time_filter w;
    double start, width;
    int frames;
    vec3 o;
    hit_list all, in;
} window_visit;

/* The sensor pass's time (volume_photon_splat) and the gate test of film_time_slot, in the same double
 * operations. */
static int window_counts(const window_visit *v, const photon *p, double t)
{
    double leg = v->w.projected ? t : v3_len(v3_sub(pos_of(p), v->o));
    double rel = (v->w.t0 + p->time + v->w.eta * leg - v->start) / v->width;
    return rel >= 0.0 && rel < v->frames;
}

static void collect_window(void *ctx, const photon *p, double t, double d2)
{
    window_visit *v = ctx;
    hit_push(&v->all, p->bounce, t, d2);
    if (window_counts(v, p, t)) hit_push(&v->in, p->bounce, t, d2);
}

/* Is a (in order) a subsequence of b? */
static int is_subsequence(const hit_list *a, const hit_list *b)
{
    size_t j = 0;
    for (size_t i = 0; i < a->n; i++) {
        while (j < b->n && b->v[j].idx != a->v[i].idx) j++;
        if (j == b->n) return 0;
        j++;
    }
    return 1;
}

/* Runs the plain and the window query; asserts the window query's photons are the plain query's minus some
 * the film would not count, and that the counted ones are the same in the same order. Returns the number
 * of photons the window spared, and adds the counted ones to *counted. */
static size_t check_window_query(const volume_photon_map *m, vec3 o, vec3 d, double tmax, const window_visit *setup,
                                 size_t *counted)
{
    window_visit plain = *setup, win = *setup;
    plain.o = win.o = o;
    photon_map_query_beam(m, o, d, tmax, collect_window, &plain);
    photon_map_query_beam_window(m, o, d, tmax, &win.w, collect_window, &win);
    if (win.in.n != plain.in.n)
        fail_msg("o=(%.17g %.17g %.17g) d=(%.17g %.17g %.17g) tmax=%g t0=%.17g eta=%g %s window [%.17g, %.17g): "
                 "plain query %zu photons in the window, window query %zu", o.x, o.y, o.z, d.x, d.y, d.z, tmax,
                 setup->w.t0, setup->w.eta, setup->w.projected ? "projected" : "euclidean", setup->w.lo, setup->w.hi,
                 plain.in.n, win.in.n);
    for (size_t i = 0; i < win.in.n; i++) assert_int_equal(win.in.v[i].idx, plain.in.v[i].idx);
    assert_true(is_subsequence(&win.all, &plain.all));
    size_t spared = plain.all.n - win.all.n;
    *counted += win.in.n;
    free(plain.all.v);
    free(plain.in.v);
    free(win.all.v);
    free(win.in.v);
    return spared;
}

/* A gate as the sensor pass makes it: [start, start + width·frames). */
static window_visit make_window(double t0, double eta, int projected, double start, double width, int frames)
{
    window_visit v = {.start = start, .width = width, .frames = frames > 0 ? frames : 1};
    v.w = (beam_time_filter){.t0 = t0, .eta = eta, .projected = projected, .lo = start, .hi = start + width * v.frames};
    return v;
}

/* Random photons with random times (light paths of length 0..3), random beams, gates and legs. */
static void test_window_random(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 131);
    dp_rng g = rng_stream(132, 0, 0);
    for (size_t i = 0; i < n; i++) ph[i].time = 3.0 * rng_uniform(&g);
    volume_photon_map *m = build_or_fail(ph, n, r);
    static const double etas[3] = {0.0, 1.0, 1.33};
    size_t spared = 0, counted = 0;
    for (int i = 0; i < 2000; i++) {
        vec3 o = random_point(&g, -0.5, 1.5);
        vec3 d = random_dir(&g);
        double tmax = i % 4 == 0 ? INFINITY : 2.0 * rng_uniform(&g);
        double t0 = i % 3 == 0 ? 0.0 : rng_uniform(&g);
        window_visit v = make_window(t0, etas[i % 3], (i / 3) % 2, 5.0 * rng_uniform(&g), 0.02 + 0.5 * rng_uniform(&g),
                                     (int)(rng_next_u64(&g) % 4));
        spared += check_window_query(m, o, d, tmax, &v, &counted);
    }
    assert_true(counted > 2000); /* the windows do count photons (3219) */
    assert_true(spared > 8000);  /* and the query skips many that they do not (13170) */
    volume_map_free(m);
    free(ph);
}

/* A gate whose end the film's test (rel < frames, rel = (t - start)/width) still counts: a photon with a
 * total time of exactly start + width·frames is inside, so only the margin keeps its node. */
static window_visit inclusive_end_window(dp_rng *g, double t0, double eta, int projected)
{
    for (int tries = 0; tries < 100000; tries++) {
        int frames = 1 + (int)(rng_next_u64(g) % 5);
        window_visit v = make_window(t0, eta, projected, 0.1 + 3.0 * rng_uniform(g), 0.05 + rng_uniform(g), frames);
        if ((v.w.hi - v.start) / v.width < v.frames) return v;
    }
    fail_msg("no gate found whose end counts");
    return make_window(0, 0, 0, 0, 1, 1);
}

/* Times on the window's boundaries: eta = 0 (the unwarped sensor segment), photon times exactly at the
 * gate's ends and one ulp either side; then eta > 0 with times that put every photon's Euclidean total
 * within rounding of the end, seen from one origin. The window query must keep every counted photon. */
static void test_window_boundaries(void **state)
{
    (void)state;
    const size_t n = 20000;
    const double r = 0.05;
    photon *ph = random_cloud(n, 141);
    dp_rng g = rng_stream(142, 0, 0);
    size_t spared = 0, counted = 0;
    for (int round = 0; round < 20; round++) {
        window_visit v = inclusive_end_window(&g, 0.0, 0.0, round % 2);
        double ends[6] = {v.w.lo, nextafter(v.w.lo, -INFINITY), nextafter(v.w.lo, INFINITY),
                          v.w.hi, nextafter(v.w.hi, -INFINITY), nextafter(v.w.hi, INFINITY)};
        for (size_t i = 0; i < n; i++) ph[i].time = ends[(i * 7 + (size_t)round) % 6 < 3 ? 3 + i % 3 : i % 3];
        for (size_t i = 0; i < n; i += 2) ph[i].time = ends[3 + i % 3]; /* mostly the end, the hard side */
        volume_photon_map *m = build_or_fail(ph, n, r);
        for (int i = 0; i < 50; i++)
            spared += check_window_query(m, random_point(&g, -0.5, 1.5), random_dir(&g), i % 2 ? INFINITY : 1.0, &v, &counted);
        volume_map_free(m);
    }
    for (int round = 0; round < 20; round++) {
        vec3 o = random_point(&g, -0.5, 1.5);
        window_visit v = inclusive_end_window(&g, rng_uniform(&g), round % 2 ? 1.0 : 1.33, 0);
        for (size_t i = 0; i < n; i++) {
            double leg = v3_len(v3_sub(pos_of(&ph[i]), o));
            double target = i % 2 ? v.w.hi : v.w.lo;
            ph[i].time = target - v.w.t0 - v.w.eta * leg;
        }
        volume_photon_map *m = build_or_fail(ph, n, r);
        for (int i = 0; i < 50; i++)
            spared += check_window_query(m, o, random_dir(&g), i % 2 ? INFINITY : 1.0, &v, &counted);
        volume_map_free(m);
    }
    assert_true(counted > 1000);
    (void)spared;
    free(ph);
}

/* Non-finite times and radii: NaN and infinite times never count, and an infinite radius (infinite node
 * boxes) still gives the plain query's counted photons; half the times NaN, so that a NaN heads many
 * leaves (a range taken from it must not hide the leaf's other photons from its parent). */
static void test_window_nonfinite(void **state)
{
    (void)state;
    const size_t n = 5000;
    photon *ph = random_cloud(n, 151);
    dp_rng g = rng_stream(152, 0, 0);
    static const double odd[3] = {NAN, INFINITY, -INFINITY};
    const double radii[3] = {0.05, INFINITY, 0.05};
    size_t counted = 0;
    for (int k = 0; k < 3; k++) {
        /* one in 5 odd; then half NaN, the others growing along x (so siblings' ranges differ) */
        for (size_t i = 0; i < n; i++)
            ph[i].time = k < 2 ? (i % 5 == 0 ? odd[(i / 5) % 3] : 2.0 * rng_uniform(&g)) : (i % 2 ? NAN : 2.0 * ph[i].pos[0]);
        volume_photon_map *m = build_or_fail(ph, n, radii[k]);
        for (int i = 0; i < 60; i++) {
            window_visit v = make_window(0.5 * rng_uniform(&g), i % 2 ? 1.0 : 0.0, (i / 2) % 2, 2.0 * rng_uniform(&g),
                                         0.1 + 0.3 * rng_uniform(&g), i % 3);
            check_window_query(m, random_point(&g, -0.5, 1.5), random_dir(&g), i % 3 ? INFINITY : 1.0, &v, &counted);
        }
        volume_map_free(m);
    }
    assert_true(counted > 0);
    free(ph);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_map),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_single_photon),
        cmocka_unit_test(test_random_rays),
        cmocka_unit_test(test_axis_parallel_rays),
        cmocka_unit_test(test_grid_ties),
        cmocka_unit_test(test_rays_inside_cloud),
        cmocka_unit_test(test_zero_length_segments),
        cmocka_unit_test(test_infinite_segments),
        cmocka_unit_test(test_zero_radius),
        cmocka_unit_test(test_huge_radius),
        cmocka_unit_test(test_duplicate_positions),
        cmocka_unit_test(test_rays_through_photons),
        cmocka_unit_test(test_photons_at_radius),
        cmocka_unit_test(test_visit_order_deterministic),
        cmocka_unit_test(test_parallel_partition),
        cmocka_unit_test(test_window_random),
        cmocka_unit_test(test_window_boundaries),
        cmocka_unit_test(test_window_nonfinite),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
