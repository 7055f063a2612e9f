/* tier: stress */
/* The photon pass of photon points: the same photons and images for any thread count, the surface map
 * unchanged once the volume budget is full (the fast path) and with surface chains, and the DARTS early exit
 * losing no photon. Every tolerance below is derived from a noise estimate measured in the same test (spread
 * over independent seeds or passes) plus a stated bias budget; no expected value comes from an earlier run of
 * this code. */
#include "fixtures.h"
#include "render_fixtures.h"

#include <omp.h>

/* photon_pass with 1, 2 and 3 OpenMP threads: the same photons in the same order. Returns the 1-thread set. */
static void photon_pass_thread_check(const scene *s, photon_set *p1)
{
    dp_error err;
    omp_set_num_threads(1);
    if (run_photon_pass(s, 9, 1, 0.0, p1, &err)) fail_msg("%s", err.msg);
    for (int threads = 2; threads <= 3; threads++) {
        photon_set p2;
        omp_set_num_threads(threads);
        if (run_photon_pass(s, 9, 1, 0.0, &p2, &err)) fail_msg("%s", err.msg);
        assert_int_equal(p1->paths, p2.paths);
        assert_int_equal(p1->n_vol, p2.n_vol);
        assert_int_equal(p1->n_surf, p2.n_surf);
        assert_int_equal(p1->vol_paths, p2.vol_paths);
        assert_int_equal(p1->surf_paths, p2.surf_paths);
        for (size_t i = 0; i < p1->n_vol; i++) assert_photon_identical(&p1->vol[i], &p2.vol[i]);
        for (size_t i = 0; i < p1->n_surf; i++) assert_photon_identical(&p1->surf[i], &p2.surf[i]);
        photon_set_free(&p2);
    }
}

/* Same seed, 1 vs 2 threads: bit-identical photon-points images (and photon sets) on a 32 × 32 fog box with
 * volume and surface photons; a different seed changes the image. */
static void test_threads_bit_identical(void **state)
{
    (void)state;
    char text[8192];
    box_scene_text(text, sizeof text, 32,
                   "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                   " \"photon_count\": 20000, \"volume_photon_count\": 12000, \"gather_photon_count\": 16,"
                   " \"gather_radius\": 0.15, \"volume_gather_radius\": 0.08, \"alpha\": 0.7, \"volume_alpha\": 0.7,"
                   " \"max_bounces\": 8, \"transient_time_center\": 5, \"transient_time_width\": 1.5");
    tmp_scene t;
    tmp_scene_write(&t, text);
    scene s;
    load_scene(t.path, NULL, 0, &s);

    /* The photon pass on its own. Multiple scattering: the budgets (12000 volume photons, 20000 surface
     * photons) are reached inside the first batch of 8192 paths, so the cut by path index is exercised. */
    photon_set p1;
    photon_pass_thread_check(&s, &p1);
    print_message("  photon pass: %zu volume photons (%ld of %ld paths), %zu surface photons (%ld paths)\n", p1.n_vol,
                  p1.vol_paths, p1.paths, p1.n_surf, p1.surf_paths);
    assert_true(p1.n_vol > 0 && p1.n_surf > 0);
    assert_true(p1.vol_paths < p1.paths && p1.surf_paths < p1.paths);
    photon_set_free(&p1);
    /* Single scattering (at most one photon per path), no volume budget: all 20000 paths in three batches.
     * The direct light's surface photons kept (surface_direct_connections off), else this set has none. */
    {
        const char *sets[] = {"max_bounces=2", "volume_photon_count=1e6", "surface_direct_connections=false"};
        scene s1;
        load_scene(t.path, sets, 3, &s1);
        photon_pass_thread_check(&s1, &p1);
        assert_int_equal(p1.paths, 20000);
        assert_int_equal(p1.vol_paths, 20000);
        assert_int_equal(p1.surf_paths, 20000);
        assert_true(p1.n_vol > 0 && p1.n_surf > 0);
        photon_set_free(&p1);
        scene_free(&s1);
    }

    dp_error err;
    film a, b, c;
    render_stats sa, sb, sc;
    render_passes(&s, 1, 7, 3, &a, &sa);
    render_passes(&s, 2, 7, 3, &b, &sb);
    size_t n = (size_t)s.cam.width * s.cam.height * 3, lit = 0;
    for (size_t i = 0; i < n; i++) lit += a.sum[i] > 0;
    assert_true(lit > n / 2); /* not a comparison of two black images */
    assert_memory_equal(a.sum, b.sum, n * sizeof(double));
    image_rgb ia, ib;
    assert_int_equal(film_image(&a, -1, &ia, &err), 0);
    assert_int_equal(film_image(&b, -1, &ib, &err), 0);
    assert_memory_equal(ia.rgb, ib.rgb, n * sizeof(float));
    assert_true(sa.stored_photons == sb.stored_photons);
    render_passes(&s, 2, 8, 3, &c, &sc); /* a different seed does change the image */
    assert_true(memcmp(a.sum, c.sum, n * sizeof(double)) != 0);
    image_free(&ia);
    image_free(&ib);
    film_free(&a);
    film_free(&b);
    film_free(&c);
    scene_free(&s);
    tmp_scene_remove(&t);
}

/* Total surface-photon power of one photon pass (all channels; powers are already divided by the paths). */
static double surface_power_total(const photon_set *p)
{
    double t = 0.0;
    for (size_t i = 0; i < p->n_surf; i++) t += (double)p->surf[i].power[0] + p->surf[i].power[1] + p->surf[i].power[2];
    return t;
}

/* Once the volume budget is full, DARTS traces the remaining paths for surface photons only, with free
 * flight and phase sampling instead of DA distance sampling and EDA, and without control vertices. Those
 * samplers are all unbiased, so the surface map must keep its expectation. Two photon passes per iteration
 * share their random streams: A with room for every volume photon (all paths aimed), B with a volume
 * budget that fills in the first batch of 8192 paths (the other 24576 take the fast path). Per iteration,
 * the difference of their surface totals comes only from those paths; over 48 iterations its mean must be
 * within 4 standard errors of 0. The pairing makes it sharp: the standard error is ~0.15 % of the total, so
 * a fast path that weighted each scattering event 1 % too high gives z ~ 2, and 3 % fails. In the grey
 * fog the fast path draws the distance before tracing (free_flight_first); without its σs/σt weight at a
 * medium event (albedo 0.9) it fails. */
static void surface_photons_after_budget(int grey)
{
    char text[8192];
    box_scene_text(text, sizeof text, 16,
                   "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","
                   " \"photon_count\": 32768, \"volume_photon_count\": 1e7, \"gather_photon_count\": 16,"
                   " \"gather_radius\": 0.15, \"volume_gather_radius\": 0.08, \"max_bounces\": 12,"
                   " \"transient_time_center\": 4.5, \"transient_time_width\": 0.5, \"enable_guiding\": true,"
                   " \"enable_elliptical\": true, \"strict_time_width\": true");
    if (grey) box_scene_make_grey(text);
    tmp_scene t;
    tmp_scene_write(&t, text);
    scene sa, sb;
    load_scene(t.path, NULL, 0, &sa);
    const char *sets[] = {"volume_photon_count=2000"};
    load_scene(t.path, sets, 1, &sb);
    enum { ITERS = 48 };
    double diff[ITERS], mean = 0.0, var = 0.0, total_a = 0.0;
    long fast_paths = 0;
    for (int i = 0; i < ITERS; i++) {
        dp_error err;
        photon_set a, b;
        if (run_photon_pass(&sa, 21, i, 0.05, &a, &err) || run_photon_pass(&sb, 21, i, 0.05, &b, &err))
            fail_msg("%s", err.msg);
        assert_int_equal(a.vol_paths, a.paths); /* A never fills its volume budget */
        assert_true(b.vol_paths < 8192);        /* B fills it in the first batch */
        assert_true(b.n_vol <= 2000);
        assert_int_equal(a.aimed_paths, a.paths); /* the count the run summary reports */
        assert_int_equal(b.aimed_paths, 8192);
        assert_int_equal(a.surf_paths, b.surf_paths);
        assert_true(a.n_surf > 100 && b.n_surf > 100);
        fast_paths += b.paths - 8192;
        diff[i] = surface_power_total(&b) - surface_power_total(&a);
        total_a += surface_power_total(&a) / ITERS;
        mean += diff[i] / ITERS;
        photon_set_free(&a);
        photon_set_free(&b);
    }
    for (int i = 0; i < ITERS; i++) var += (diff[i] - mean) * (diff[i] - mean) / (ITERS - 1);
    double se = sqrt(var / ITERS);
    print_message("  %s fog: surface total %.5g; fast minus aimed %.3g (se %.2g, z = %.2f) over %ld fast paths\n",
                  grey ? "grey" : "coloured", total_a, mean, se, mean / se, fast_paths);
    assert_true(se > 0.0);
    assert_true(se < 0.05 * total_a); /* the comparison can see a bias of a few percent */
    assert_true(fabs(mean) < 4.0 * se);
    scene_free(&sa);
    scene_free(&sb);
    tmp_scene_remove(&t);
}

static void test_surface_photons_after_volume_budget_full(void **state)
{
    (void)state;
    surface_photons_after_budget(0);
}

static void test_surface_photons_after_volume_budget_full_grey(void **state)
{
    (void)state;
    surface_photons_after_budget(1);
}

/* DARTS in the box: 32768 paths, a volume budget of 2000 that fills in the first batch, a gate at 4.5 of
 * the given width (a string literal). */
#define DARTS_BOX_32K(width)                                                                                   \
    "\"type\": \"progressive_transient_photon_map\", \"volume_photon_type\": \"points\","                          \
    " \"photon_count\": 32768, \"volume_photon_count\": 2000, \"gather_photon_count\": 16,"                       \
    " \"gather_radius\": 0.15, \"volume_gather_radius\": 0.08, \"max_bounces\": 40,"                              \
    " \"transient_time_center\": 4.5, \"transient_time_width\": " width ", \"enable_guiding\": true,"             \
    " \"enable_elliptical\": true, \"strict_time_width\": true"

/* Surface power (all channels) summed into a 4x4x4 grid over the box [-1, 1] x [0, 2] x [-1, 1]. */
enum { CHAIN_CELLS = 64 };
static void surface_power_cells(const photon_set *p, double *cells)
{
    for (size_t i = 0; i < p->n_surf; i++) {
        const float *x = p->surf[i].pos;
        int k[3];
        for (int a = 0; a < 3; a++) {
            double lo = a == 1 ? 0.0 : -1.0;
            k[a] = (int)floor((x[a] - lo) / 0.5);
            k[a] = k[a] < 0 ? 0 : (k[a] > 3 ? 3 : k[a]);
        }
        cells[k[0] + 4 * k[1] + 16 * k[2]] += (double)p->surf[i].power[0] + p->surf[i].power[1] + p->surf[i].power[2];
    }
}

/* Surface chains (surface_chain.c) replace the independent light paths after the volume budget with Markov
 * chains that keep to the paths whose surface photons can count, and scale their photons by the visible
 * fraction the independent proposals estimate. The surface map must keep its expectation cell by cell:
 * chains on and off, 40 iterations each (32768 paths, the volume budget full after the first batch, a
 * gate 0.1 wide, where about 4 % of the paths are visible), the surface power in each of the 64 cells of
 * a grid over the box. One χ² over the cells with power (the two means' difference over its standard
 * error, estimated across iterations), and the total within 4 standard errors. The chains must also
 * concentrate the work: at least 3x the surface photons of the independent paths. */
static void chains_keep_the_surface_map(double share)
{
    char text[8192];
    box_scene_text(text, sizeof text, 16, DARTS_BOX_32K("0.1"));
    box_scene_make_grey(text);
    tmp_scene t;
    tmp_scene_write(&t, text);
    scene son, soff;
    load_scene(t.path, NULL, 0, &son);
    const char *sets[] = {"surface_chains=false"};
    load_scene(t.path, sets, 1, &soff);
    enum { ITERS = 40 };
    static double cell[2][ITERS][CHAIN_CELLS];
    double total[2][ITERS];
    size_t photons[2] = {0, 0};
    photon_chain_stats st = {0};
    memset(cell, 0, sizeof cell);
    for (int i = 0; i < ITERS; i++)
        for (int m = 0; m < 2; m++) {
            dp_error err;
            photon_set p;
            if (run_photon_pass_share(m ? &son : &soff, 31, i, 0.05, m ? share : 1.0, &p, &err)) fail_msg("%s", err.msg);
            /* the chains trace the share of the paths left after the independent ones (ceil) */
            if (m) assert_int_equal(p.chain.traced, (long)ceil((32768.0 - (double)(p.surf_paths - p.chain.traced)) * share));
            else assert_int_equal(p.surf_paths, 32768);
            if (m) {
                assert_true(p.chain.traced > 0);
                st.traced += p.chain.traced, st.large += p.chain.large, st.visible += p.chain.visible;
                st.small += p.chain.small, st.accepted += p.chain.accepted;
            } else {
                assert_int_equal(p.chain.traced, 0);
            }
            surface_power_cells(&p, cell[m][i]);
            total[m][i] = surface_power_total(&p);
            photons[m] += p.n_surf;
            photon_set_free(&p);
        }
    double chi2 = 0.0, mt[2] = {0, 0}, vt[2] = {0, 0};
    int dof = 0;
    for (int c = 0; c < CHAIN_CELLS; c++) {
        double mean[2] = {0, 0}, var[2] = {0, 0};
        for (int m = 0; m < 2; m++) {
            for (int i = 0; i < ITERS; i++) mean[m] += cell[m][i][c] / ITERS;
            for (int i = 0; i < ITERS; i++) var[m] += (cell[m][i][c] - mean[m]) * (cell[m][i][c] - mean[m]) / (ITERS - 1);
        }
        if (var[0] <= 0.0 || var[1] <= 0.0) continue; /* no photon in this cell in some method */
        chi2 += (mean[1] - mean[0]) * (mean[1] - mean[0]) / ((var[0] + var[1]) / ITERS);
        dof++;
    }
    for (int m = 0; m < 2; m++) {
        for (int i = 0; i < ITERS; i++) mt[m] += total[m][i] / ITERS;
        for (int i = 0; i < ITERS; i++) vt[m] += (total[m][i] - mt[m]) * (total[m][i] - mt[m]) / (ITERS - 1);
    }
    double z = (mt[1] - mt[0]) / sqrt((vt[0] + vt[1]) / ITERS), p = test_gamma_q(dof / 2.0, chi2 / 2.0);
    print_message("  chains: %.1f %% of the independent proposals visible, %.1f %% of the small steps accepted; "
                  "surface photons %zu against %zu\n",
                  100.0 * st.visible / st.large, 100.0 * st.accepted / st.small, photons[1], photons[0]);
    print_message("  surface total %.5g (chains) against %.5g (independent): z = %.2f; %d cells: chi2 %.1f, p = %.3f\n",
                  mt[1], mt[0], z, dof, chi2, p);
    assert_true(dof >= 20);
    assert_true(fabs(z) < 4.0);
    assert_true(p > 1e-3);
    assert_true(photons[1] > (share < 1.0 ? 1 : 3) * photons[0]);
    scene_free(&son);
    scene_free(&soff);
    tmp_scene_remove(&t);
}

static void test_surface_chains_keep_the_surface_map(void **state)
{
    (void)state;
    chains_keep_the_surface_map(1.0);
}

/* surface_paths "auto" (docs/defaults.md §3.9): chains that trace a quarter of the paths left keep the surface
 * map's expectation too, their photons standing for the paths they traced. */
static void test_chain_share_keeps_the_surface_map(void **state)
{
    (void)state;
    chains_keep_the_surface_map(0.25);
}

/* The DARTS early exit ends a light path once no later vertex can reach its bin, and the fast path stops
 * a free-flight ray where a vertex would no longer reach it (photon_pass.c, reach_distance). Neither may
 * lose a photon: every stored photon passed the same reachability test at its own vertex, and by the
 * triangle inequality so did every vertex before it. So with the early exit on and off, the same seeds
 * must store exactly the same photons — same positions, times and powers, in the same order — while the
 * early exit ends most paths. Grey fog, so that the reach applies. A reach cut 20 % short loses photons
 * and fails here. */
static void test_early_exit_keeps_every_photon(void **state)
{
    (void)state;
    char text[8192];
    box_scene_text(text, sizeof text, 16, DARTS_BOX_32K("0.5"));
    box_scene_make_grey(text);
    tmp_scene t;
    tmp_scene_write(&t, text);
    scene son, soff;
    /* independent paths: a surface chain's next proposal depends on how many numbers its current path drew,
     * which the early exit changes (test_surface_chains_keep_the_surface_map covers chains, early exit on) */
    const char *sets_on[] = {"surface_chains=false"}, *sets[] = {"early_exit=false", "surface_chains=false"};
    load_scene(t.path, sets_on, 1, &son);
    load_scene(t.path, sets, 2, &soff);
    long exits = 0, paths = 0;
    size_t surf = 0;
    for (int i = 0; i < 3; i++) {
        dp_error err;
        photon_set a, b;
        if (run_photon_pass(&son, 5, i, 0.05, &a, &err) || run_photon_pass(&soff, 5, i, 0.05, &b, &err))
            fail_msg("%s", err.msg);
        assert_int_equal(a.paths, b.paths);
        assert_int_equal(b.early_exits, 0);
        assert_int_equal(a.n_surf, b.n_surf);
        assert_int_equal(a.n_vol, b.n_vol);
        for (size_t k = 0; k < a.n_surf; k++) assert_photon_identical(&a.surf[k], &b.surf[k]);
        for (size_t k = 0; k < a.n_vol; k++) assert_photon_identical(&a.vol[k], &b.vol[k]);
        exits += a.early_exits;
        paths += a.paths;
        surf += a.n_surf;
        photon_set_free(&a);
        photon_set_free(&b);
    }
    print_message("  %zu surface photons, the same with and without the early exit, which ended %.1f %% of %ld paths\n",
                  surf, 100.0 * exits / paths, paths);
    assert_true(surf > 1000);
    assert_true(exits > paths / 2); /* the early exit and its reach were exercised */
    scene_free(&son);
    scene_free(&soff);
    tmp_scene_remove(&t);
}

/* Thread-written storage (core.h): every block on a 64-byte line and zeroed, the total rounded up to whole
 * lines; sizes that overflow or are empty give NULL. Blocks of several sizes, since plain malloc is 64-byte
 * aligned for some of them by chance. */
static void test_cache_aligned_storage(void **state)
{
    (void)state;
    void *blocks[8];
    for (int k = 0; k < 8; k++) {
        size_t n = (size_t)(k + 1), size = (size_t)(8 + 24 * k);
        unsigned char *p = blocks[k] = dp_calloc_cache_aligned(n, size);
        assert_non_null(p);
        assert_int_equal((uintptr_t)p % DP_CACHE_LINE, 0);
        size_t bytes = (n * size + DP_CACHE_LINE - 1) / DP_CACHE_LINE * DP_CACHE_LINE;
        for (size_t i = 0; i < bytes; i++)
            if (p[i]) fail_msg("byte %zu of a %zu-byte block is %d, not 0", i, bytes, p[i]);
    }
    for (int k = 0; k < 8; k++) free(blocks[k]);
    assert_null(dp_calloc_cache_aligned(0, 64));
    assert_null(dp_calloc_cache_aligned(4, 0));
    assert_null(dp_calloc_cache_aligned(SIZE_MAX / 2, 4));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_bit_identical),
        cmocka_unit_test(test_cache_aligned_storage),
        cmocka_unit_test(test_surface_photons_after_volume_budget_full),
        cmocka_unit_test(test_surface_chains_keep_the_surface_map),
        cmocka_unit_test(test_chain_share_keeps_the_surface_map),
        cmocka_unit_test(test_early_exit_keeps_every_photon),
    };
    /* DARTSPP_TEST_FILTER=name (cmocka wildcards) runs only the matching tests */
    if (getenv("DARTSPP_TEST_FILTER")) cmocka_set_test_filter(getenv("DARTSPP_TEST_FILTER"));
    /* make stress only (14 s on 2 cores): the same with grey media and albedos */
    const struct CMUnitTest stress[] = {
        cmocka_unit_test(test_surface_photons_after_volume_budget_full_grey),
    };
    return RUN_TESTS_AND_STRESS(tests, stress);
}
