/* Volume photon map benchmark: the kd-tree of src/photon/volume_map.c against two Embree 3 BVHs that
 * enumerate the same photons, on photons spread like the fog Cornell box and its 512x512 camera rays.
 *
 *   map_bench N:SIDE [N:SIDE ...]
 *
 * For each N: N photons (half uniform in the box, half clustered around the light), gather radius 0.1,
 * SIDE x SIDE camera rays spread over the 512x512 image, each segment running from the camera to where it
 * leaves the box. Prints Markdown table rows: build time and mean query time per ray with 1 and 2 threads,
 * mean photons per ray, and the estimated cost of one renderer iteration (one build + 512^2 rays).
 *
 * Embree candidates (both use Embree's float traversal only to find candidates and apply the map's exact
 * double-precision test, so the photons found must equal the kd-tree's):
 *   - user geometry: one primitive per photon with bounds photon ± r; the intersect callback tests and
 *     records the photon and never reports a hit, so the ray keeps its tfar and traversal visits all;
 *   - disc points: ray-facing discs of radius r (Embree hits one iff the ray passes within r, at t = t_p);
 *     an intersection filter records the photon and rejects the hit so traversal continues. */
#include "dartspp/photon.h"

#include <embree3/rtcore.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RADIUS 0.1          /* the fog scene's volume_gather_radius */
#define IMAGE_SIDE 512      /* the renderer's image: rays per iteration = IMAGE_SIDE^2 */
#define FOV_DEG 39.3077     /* horizontal */
#define EMBREE_PAD 1e-4     /* relative growth of Embree's float radii and tfar, so no candidate is lost */
#define BUILD_REPS 2        /* builds timed per structure and thread count; the best is reported */
#define CLUSTER_SHARE 2     /* every CLUSTER_SHARE-th photon is uniform, the others cluster at the light */

static const double box_size[3] = {5.56, 5.49, 5.59};

typedef struct {
    vec3 o, d;
    double tmax;
} query_ray;

typedef struct {
    double count, weight;
} gather_sum;

typedef void (*query_fn)(const void *map, const query_ray *ray, gather_sum *sum);

typedef struct {
    const char *name;
    double build_s[2]; /* 1 and 2 threads */
    double query_us[2];
    double photons_per_ray, weight_per_ray;
} bench_row;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void die(const char *what)
{
    fprintf(stderr, "map_bench: %s\n", what);
    exit(1);
}

/* ---- workload ---- */

static int inside_box(vec3 p)
{
    return p.x >= 0 && p.x <= box_size[0] && p.y >= 0 && p.y <= box_size[1] && p.z >= 0 && p.z <= box_size[2];
}

/* Uniform in the box, or (most photons of a random walk start near the light) at an exponential distance
 * of mean 1 from the light (2.78, 4.8, 2.4) in a uniform direction, kept inside the box. */
static vec3 photon_position(dp_rng *g, size_t i)
{
    if (i % CLUSTER_SHARE == 0) return v3(box_size[0] * rng_uniform(g), box_size[1] * rng_uniform(g), box_size[2] * rng_uniform(g));
    for (;;) {
        double u1 = rng_uniform(g), u2 = rng_uniform(g);
        vec3 p = v3_add(v3(2.78, 4.8, 2.4), v3_scale(sample_uniform_sphere(u1, u2), -log(1.0 - rng_uniform(g))));
        if (inside_box(p)) return p;
    }
}

static photon *make_photons(size_t n)
{
    photon *ph = malloc(n * sizeof *ph);
    if (!ph) die("out of memory for the photons");
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        dp_rng g = rng_stream(2024, i, 0);
        vec3 p = photon_position(&g, i);
        double u1 = rng_uniform(&g), u2 = rng_uniform(&g);
        vec3 dir = sample_uniform_sphere(u1, u2);
        photon *q = &ph[i];
        q->pos[0] = (float)p.x, q->pos[1] = (float)p.y, q->pos[2] = (float)p.z;
        q->dir[0] = (float)dir.x, q->dir[1] = (float)dir.y, q->dir[2] = (float)dir.z;
        for (int c = 0; c < 3; c++) q->power[c] = (float)(1.0 / (double)n);
        q->bounce = 1 + (int)(i % 4);
        q->time = 10.0 * rng_uniform(&g);
    }
    return ph;
}

/* Distance at which the ray leaves the box (slab test; every camera ray has non-zero d.z), 0 on a miss. */
static double box_exit(vec3 o, vec3 d)
{
    double enter = 0.0, leave = INFINITY;
    double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; a++) {
        if (dd[a] == 0.0) {
            if (oo[a] < 0 || oo[a] > box_size[a]) return 0.0;
            continue;
        }
        double t0 = (0.0 - oo[a]) / dd[a], t1 = (box_size[a] - oo[a]) / dd[a];
        enter = fmax(enter, fmin(t0, t1));
        leave = fmin(leave, fmax(t0, t1));
    }
    return enter <= leave ? leave : 0.0;
}

/* side x side pinhole rays through the pixel centres of a side^2 grid covering the image */
static query_ray *make_rays(int side)
{
    query_ray *rays = malloc((size_t)side * side * sizeof *rays);
    if (!rays) die("out of memory for the rays");
    double focal = 1.0 / tan(0.5 * FOV_DEG * M_PI / 180.0);
    for (int j = 0; j < side; j++)
        for (int i = 0; i < side; i++) {
            query_ray *r = &rays[(size_t)j * side + i];
            r->o = v3(2.78, 2.73, -8.0);
            r->d = v3_norm(v3(2.0 * (i + 0.5) / side - 1.0, 1.0 - 2.0 * (j + 0.5) / side, focal));
            r->tmax = box_exit(r->o, r->d);
        }
    return rays;
}

/* What the gather does per photon, minus the phase function and time gate: the 2-D biweight kernel. */
static void gather_visit(void *ctx, const photon *p, double t, double d2)
{
    gather_sum *s = ctx;
    double k = 1.0 - d2 / (RADIUS * RADIUS);
    (void)t;
    s->count += 1.0;
    s->weight += k * k * p->power[0];
}

/* The map's photon test in double (t = w·d, d2 = |w - t·d|^2), for the Embree candidates. */
static void exact_test(const photon *p, vec3 o, vec3 d, double tmax, gather_sum *sum)
{
    vec3 w = v3_sub(v3(p->pos[0], p->pos[1], p->pos[2]), o);
    double t = v3_dot(w, d);
    if (!(t >= 0.0 && t <= tmax)) return;
    vec3 v = v3_sub(w, v3_scale(d, t));
    double d2 = v3_dot(v, v);
    if (d2 <= RADIUS * RADIUS) gather_visit(sum, p, t, d2);
}

/* Mean wall time per ray over all rays with the given thread count; sums what the queries gathered. */
static double time_queries(query_fn query, const void *map, const query_ray *rays, size_t nrays, int threads,
                           gather_sum *total)
{
    double count = 0.0, weight = 0.0, t0 = now_s();
#pragma omp parallel for num_threads(threads) schedule(dynamic, 16) reduction(+ : count, weight)
    for (size_t i = 0; i < nrays; i++) {
        gather_sum s = {0.0, 0.0};
        query(map, &rays[i], &s);
        count += s.count;
        weight += s.weight;
    }
    double elapsed = now_s() - t0;
    total->count = count;
    total->weight = weight;
    return elapsed / (double)nrays;
}

/* ---- kd-tree (the renderer's API) ---- */

static void kd_query(const void *map, const query_ray *ray, gather_sum *sum)
{
    photon_map_query_beam(map, ray->o, ray->d, ray->tmax, gather_visit, sum);
}

/* Best of BUILD_REPS builds (the first one also pays for page faults and thread start-up). */
static volume_photon_map *kd_build(const photon *ph, size_t n, int threads, double *seconds)
{
    dp_error err;
    volume_photon_map *m = NULL;
    omp_set_num_threads(threads);
    *seconds = INFINITY;
    for (int rep = 0; rep < BUILD_REPS; rep++) {
        volume_map_free(m);
        double t0 = now_s();
        m = volume_map_build(ph, n, RADIUS, &err);
        *seconds = fmin(*seconds, now_s() - t0);
        if (!m) die(err.msg);
    }
    return m;
}

/* ---- Embree ---- */

typedef struct {
    RTCDevice device;
    RTCScene scene;
    const photon *photons;
} embree_map;

/* Per-query state. The Embree context comes first: Embree hands its address back to the callbacks. */
typedef struct {
    struct RTCIntersectContext rtc;
    const photon *photons;
    vec3 o, d;
    double tmax;
    gather_sum *sum;
} embree_query;

static void user_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const photon *p = &((const photon *)args->geometryUserPtr)[args->primID];
    float r = (float)(RADIUS * (1.0 + EMBREE_PAD));
    struct RTCBounds *b = args->bounds_o;
    b->lower_x = p->pos[0] - r, b->lower_y = p->pos[1] - r, b->lower_z = p->pos[2] - r;
    b->upper_x = p->pos[0] + r, b->upper_y = p->pos[1] + r, b->upper_z = p->pos[2] + r;
}

/* Called by rtcIntersect1 (N = 1) for every photon whose box the ray meets; reports no hit. */
static void user_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    if (!args->valid[0]) return;
    const embree_query *q = (const embree_query *)args->context;
    exact_test(&q->photons[args->primID], q->o, q->d, q->tmax, q->sum);
}

/* Called for every disc hit within [tnear, tfar]; records it and rejects it so traversal goes on. */
static void disc_filter(const struct RTCFilterFunctionNArguments *args)
{
    const embree_query *q = (const embree_query *)args->context;
    unsigned prim = ((const unsigned *)args->hit)[5 * args->N]; /* RTCHitN_primID, SoA layout, lane 0 */
    exact_test(&q->photons[prim], q->o, q->d, q->tmax, q->sum);
    args->valid[0] = 0;
}

static RTCGeometry user_geometry(RTCDevice dev, const photon *ph, size_t n)
{
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, (unsigned)n);
    rtcSetGeometryUserData(g, (void *)ph);
    rtcSetGeometryBoundsFunction(g, user_bounds, NULL);
    rtcSetGeometryIntersectFunction(g, user_intersect);
    return g;
}

static RTCGeometry disc_geometry(RTCDevice dev, const photon *ph, size_t n)
{
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_DISC_POINT);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), n);
    if (!v) die("Embree could not allocate the disc vertices");
    float r = (float)(RADIUS * (1.0 + EMBREE_PAD));
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        memcpy(&v[4 * i], ph[i].pos, 3 * sizeof(float));
        v[4 * i + 3] = r;
    }
    rtcSetGeometryIntersectFilterFunction(g, disc_filter);
    return g;
}

static RTCScene embree_scene(RTCDevice dev, const photon *ph, size_t n, int discs)
{
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    /* rebuilt every iteration: the fast (Morton) builder; MEDIUM built slower and queried no faster here */
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    RTCGeometry g = discs ? disc_geometry(dev, ph, n) : user_geometry(dev, ph, n);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) die("Embree failed to build the scene");
    return scene;
}

/* Best of BUILD_REPS builds on a device limited to the given thread count (device start-up not timed). */
static embree_map *embree_build(const photon *ph, size_t n, int threads, int discs, double *seconds)
{
    char config[64];
    snprintf(config, sizeof config, "threads=%d", threads);
    embree_map *m = calloc(1, sizeof *m);
    if (!m) die("out of memory");
    m->device = rtcNewDevice(config);
    if (!m->device) die("cannot create an Embree device");
    m->photons = ph;
    omp_set_num_threads(threads);
    *seconds = INFINITY;
    for (int rep = 0; rep < BUILD_REPS; rep++) {
        if (m->scene) rtcReleaseScene(m->scene);
        double t0 = now_s();
        m->scene = embree_scene(m->device, ph, n, discs);
        *seconds = fmin(*seconds, now_s() - t0);
    }
    return m;
}

static void embree_free(embree_map *m)
{
    rtcReleaseScene(m->scene);
    rtcReleaseDevice(m->device);
    free(m);
}

static void embree_query_ray(const void *map, const query_ray *ray, gather_sum *sum)
{
    const embree_map *m = map;
    embree_query q;
    rtcInitIntersectContext(&q.rtc);
    q.photons = m->photons;
    q.o = ray->o, q.d = ray->d, q.tmax = ray->tmax, q.sum = sum;
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = (float)ray->o.x, rh.ray.org_y = (float)ray->o.y, rh.ray.org_z = (float)ray->o.z;
    rh.ray.dir_x = (float)ray->d.x, rh.ray.dir_y = (float)ray->d.y, rh.ray.dir_z = (float)ray->d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = (float)(ray->tmax * (1.0 + EMBREE_PAD) + EMBREE_PAD);
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m->scene, &q.rtc, &rh);
}

/* ---- driver ---- */

static void measure_queries(bench_row *row, query_fn query, const void *map, const query_ray *rays, size_t nrays)
{
    gather_sum one, two;
    row->query_us[0] = 1e6 * time_queries(query, map, rays, nrays, 1, &one);
    row->query_us[1] = 1e6 * time_queries(query, map, rays, nrays, 2, &two);
    if (one.count != two.count) die("1 and 2 threads found different photon counts");
    row->photons_per_ray = one.count / (double)nrays;
    row->weight_per_ray = one.weight / (double)nrays;
}

static bench_row bench_kd(const photon *ph, size_t n, const query_ray *rays, size_t nrays)
{
    bench_row row = {.name = "kd-tree (volume_map.c)"};
    volume_map_free(kd_build(ph, n, 1, &row.build_s[0]));
    volume_photon_map *m = kd_build(ph, n, 2, &row.build_s[1]);
    measure_queries(&row, kd_query, m, rays, nrays);
    volume_map_free(m);
    return row;
}

static bench_row bench_embree(const photon *ph, size_t n, const query_ray *rays, size_t nrays, int discs)
{
    bench_row row = {.name = discs ? "Embree disc points + filter" : "Embree user geometry"};
    embree_free(embree_build(ph, n, 1, discs, &row.build_s[0]));
    embree_map *m = embree_build(ph, n, 2, discs, &row.build_s[1]);
    measure_queries(&row, embree_query_ray, m, rays, nrays);
    embree_free(m);
    return row;
}

/* one renderer iteration with 2 threads: a build plus IMAGE_SIDE^2 camera rays */
static double iteration_s(const bench_row *row)
{
    return row->build_s[1] + 1e-6 * row->query_us[1] * IMAGE_SIDE * IMAGE_SIDE;
}

static void print_row(size_t n, int side, const bench_row *row, const bench_row *kd)
{
    const char *same = row == kd ? "—" : (row->photons_per_ray == kd->photons_per_ray ? "yes" : "**no**");
    printf("| %.0e | %d² | %s | %.3f | %.3f | %.2f | %.2f | %.1f | %s | %.2f |\n", (double)n, side, row->name,
           row->build_s[0], row->build_s[1], row->query_us[0], row->query_us[1], row->photons_per_ray, same,
           iteration_s(row));
    fflush(stdout);
}

/* Which structure gives the cheaper renderer iteration at each size, and the overall answer. */
static void print_verdict(const size_t *sizes, const double *kd_s, const double *embree_s, int count)
{
    int kd_wins = 0;
    printf("\nCheaper iteration (one build + 512² rays, 2 threads) per size:");
    for (int i = 0; i < count; i++) {
        int kd = kd_s[i] <= embree_s[i];
        kd_wins += kd;
        printf(" %.0e: %s (kd-tree %.2f s, best Embree %.2f s)%s", (double)sizes[i], kd ? "kd-tree" : "Embree", kd_s[i],
               embree_s[i], i + 1 < count ? ";" : ".\n");
    }
    printf("\nFaster: **%s**.\n", kd_wins == count ? "kd-tree at every size" : (kd_wins == 0 ? "Embree at every size" : "depends on the size"));
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 17) die("usage: map_bench N:SIDE [N:SIDE ...] (at most 16)");
    printf("| photons | rays | structure | build 1 thr (s) | build 2 thr (s) | query 1 thr (µs/ray) | "
           "query 2 thr (µs/ray) | photons/ray | same photons as kd-tree | build + 512² rays, 2 thr (s) |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|\n");
    size_t sizes[16];
    double kd_s[16], embree_s[16];
    for (int a = 1; a < argc; a++) {
        size_t n;
        int side;
        if (sscanf(argv[a], "%zu:%d", &n, &side) != 2 || side < 1 || n < 1) die("arguments are N:SIDE");
        photon *ph = make_photons(n);
        query_ray *rays = make_rays(side);
        size_t nrays = (size_t)side * side;
        bench_row rows[3] = {bench_kd(ph, n, rays, nrays), bench_embree(ph, n, rays, nrays, 0),
                             bench_embree(ph, n, rays, nrays, 1)};
        for (int k = 0; k < 3; k++) print_row(n, side, &rows[k], &rows[0]);
        sizes[a - 1] = n;
        kd_s[a - 1] = iteration_s(&rows[0]);
        embree_s[a - 1] = fmin(iteration_s(&rows[1]), iteration_s(&rows[2]));
        free(rays);
        free(ph);
    }
    print_verdict(sizes, kd_s, embree_s, argc - 1);
    return 0;
}
