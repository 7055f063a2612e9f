/* tier: quick */
/* The paper's own scene files load with the values written in them: the Cornell box of cbox-trans (its four
 * files, volume beams resolved as beams) and the three dragon files (textures, conductors, smooth mesh); Liu,
 * Jiao and Jarosz 2022's three example scenes (liu2022/) as they are, their sliced primitives and delta gates.
 * Skipped when the paper's scenes are not beside the checkout (see test_need_paper_files). Expected values are
 * worked out by hand from the scene files and docs/scene-format.md. */
#include "fixtures.h"

#include "dartspp/render.h"
#include "render_fixtures.h"

#include <glob.h>

/* ---- the Cornell box ---- */

/* The meshes of the paper's Cornell box that every one of its scene files uses, relative to the paper scenes
 * folder; path_tracer.json and transient-beams.json add Cube.001.wo3, transient.json adds scatter.wo3. */
#define CBOX_WALL_MESHES                                                                                         \
    "cbox-trans/meshes/cbox_back.001.wo3", "cbox-trans/meshes/cbox_ceiling.001.wo3",                             \
        "cbox-trans/meshes/cbox_floor.001.wo3", "cbox-trans/meshes/cbox_greenwall.001.wo3",                      \
        "cbox-trans/meshes/cbox_largebox.001.wo3", "cbox-trans/meshes/cbox_redwall.001.wo3",                     \
        "cbox-trans/meshes/cbox_smallbox.001.wo3"

/* dir/cbox-trans/name into out */
static void paper_file(char *out, size_t n, const char *dir, const char *name)
{
    snprintf(out, n, "%s/cbox-trans/%s", dir, name);
}

static void test_shared_scenes_load(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("cbox-trans/path_tracer.json", "cbox-trans/scene.json",
                                            "cbox-trans/transient.json", "cbox-trans/transient-beams.json",
                                            CBOX_WALL_MESHES, "cbox-trans/meshes/Cube.001.wo3",
                                            "cbox-trans/meshes/scatter.wo3", NULL);
    char pattern[4200];
    paper_file(pattern, sizeof pattern, dir, "*.json");
    glob_t *g = fx_keep(calloc(1, sizeof(glob_t)));
    int grc = glob(pattern, 0, NULL, g);
    size_t count = grc == 0 ? g->gl_pathc : 0;
    char **paths = fx_keep(calloc(count + 1, sizeof(char *)));
    for (size_t i = 0; i < count; i++) paths[i] = fx_keep(strdup(g->gl_pathv[i]));
    if (grc == 0) globfree(g);
    if (count < 4) fail_msg("expected at least 4 scene files in %s/cbox-trans, found %zu", dir, count);
    for (size_t i = 0; i < count; i++) {
        const char *path = paths[i];
        char *text = read_all(path, NULL);
        /* The authors' beams scene (volume_photon_type "beams", baseline photon pass): the plan takes beams,
         * not points (src/photon_beams; rendering it is tests/photon_points/test_photon_beams.c's). */
        int beams = strstr(text, "\"volume_photon_type\": \"beams\"") != NULL;
        free(text);
        scene *s = fx_slot();
        dp_error err;
        memset(&err, 0, sizeof err);
        int rc = scene_load(path, NULL, s, &err);
        if (rc == 0) fx_mark(s, 1);
        if (rc) fail_msg("scene_load(%s) failed: %s", path, err.msg);
        if (beams) {
            render_plan p;
            if (plan_resolve(s, &p, &err)) fail_msg("%s: %s", path, err.msg);
            assert_int_equal(p.volume_photon_type, VOLUME_PHOTON_BEAMS);
            assert_int_equal(p.r_vol.dims, 1);
            plan_free(&p);
        }
        assert_true(s->surface_count >= 7); /* back, ceiling, floor, 2 walls, 2 boxes */
        assert_int_equal(s->light_count, 1);
        assert_true(s->tri_count > 0);
        assert_non_null(s->rt_scene);
        fx_drop(s);
    }
}

static void test_path_tracer_json_values(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("cbox-trans/path_tracer.json", CBOX_WALL_MESHES,
                                            "cbox-trans/meshes/Cube.001.wo3", NULL);
    char path[4200];
    paper_file(path, sizeof path, dir, "path_tracer.json");
    const scene *s = fx_load(path, NULL);
    assert_int_equal(s->medium_count, 1);
    ASSERT_VEC(s->media[0].sigma_s, 0.01, 0.01, 0.01, 1e-12);
    ASSERT_VEC(s->media[0].sigma_a, 0, 0, 0, 0);
    ASSERT_VEC(s->media[0].sigma_t, 0.01, 0.01, 0.01, 1e-12);
    assert_int_equal(s->media[0].guided, 0);
    assert_int_equal(s->media[0].max_bounces, 160);
    assert_int_equal(s->cam.width, 512);
    assert_int_equal(s->cam.height, 512);
    ASSERT_NEAR(s->cam.fov_deg, CBOX_FOV, 1e-12);
    ASSERT_VEC(s->cam.pos, 2.78, 2.73, -8.0, 1e-12);
    assert_int_equal(s->cam.medium, 0);
    assert_int_equal(s->integrator.type, INTEGRATOR_PATH_TRACER);
    /* transient_time_center 0, transient_time_width 0: not gated */
    assert_int_equal(s->integrator.window.gated, 0);
    ASSERT_NEAR(s->integrator.window.width, 0.0, 0.0);
    assert_int_equal(s->integrator.window.frame_count, 0);
    assert_int_equal(s->integrator.max_bounces, 64);
    assert_int_equal(s->renderer.spp, 50);
    ASSERT_NEAR(s->renderer.timeout, 0.0, 0.0);
    /* emission 1000 is radiant intensity, in the gas */
    ASSERT_VEC(s->lights[0].value, 1000, 1000, 1000, 1e-9);
    ASSERT_VEC(s->lights[0].pos, 2.779, 4.8, 2.4, 1e-12);
    assert_int_equal(s->lights[0].medium, 0);
    /* Cube.001 is the forward-BSDF boundary of the gas (int_medium); the walls have ext_medium gas */
    assert_int_equal(s->surface_count, 8);
    const surface *cube = &s->surfaces[0];
    assert_int_equal(s->bsdfs[cube->bsdf].type, BSDF_FORWARD);
    assert_int_equal(cube->overrides_media, 1);
    assert_int_equal(cube->int_medium, 0);
    assert_int_equal(cube->ext_medium, MEDIUM_VACUUM);
    const surface *back = &s->surfaces[1];
    assert_int_equal(s->bsdfs[back->bsdf].type, BSDF_LAMBERT);
    ASSERT_VEC(s->bsdfs[back->bsdf].albedo, 0.7411765, 0.7411765, 0.7411765, 1e-9);
    assert_int_equal(back->overrides_media, 1);
    assert_int_equal(back->int_medium, MEDIUM_VACUUM);
    assert_int_equal(back->ext_medium, 0);
    const surface *red = &s->surfaces[6]; /* cbox_redwall.001, inline lambert */
    ASSERT_VEC(s->bsdfs[red->bsdf].albedo, 0.8666667, 0.14509805, 0.14509805, 1e-9);
}

static void test_transient_json_values(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("cbox-trans/transient.json", CBOX_WALL_MESHES,
                                            "cbox-trans/meshes/scatter.wo3", NULL);
    char path[4200];
    paper_file(path, sizeof path, dir, "transient.json");
    const scene *s = fx_load(path, NULL);
    const time_window *tw = &s->integrator.window;
    assert_int_equal(tw->gated, 1);
    assert_int_equal(tw->frame_count, 0);
    ASSERT_NEAR(tw->width, 0.1, 1e-15);
    ASSERT_NEAR(tw->start, 16.15 - 0.05, 1e-9);
    ASSERT_NEAR(time_window_end(tw), 16.15 + 0.05, 1e-9);
    assert_int_equal(s->medium_count, 1);
    assert_int_equal(s->media[0].guided, 1);
    ASSERT_VEC(s->media[0].sigma_s, 0.15, 0.15, 0.15, 1e-12);
    ASSERT_VEC(s->media[0].sigma_t, 0.155, 0.155, 0.155, 1e-12);
    ASSERT_NEAR(s->media[0].eta, 1.0, 0.0);
    assert_int_equal(s->media[0].max_bounces, 120);
    assert_int_equal(s->media[0].phase.type, PHASE_ISOTROPIC);
    ASSERT_NEAR(s->renderer.timeout, 60.0, 1e-9);       /* "1.0": a bare number means minutes */
    ASSERT_NEAR(s->renderer.checkpoint_interval, 60000.0, 1e-6); /* "1000" minutes */
    assert_int_equal(s->renderer.spp, 10000);
    assert_string_equal(s->renderer.hdr_output_file, "test.pfm");
    assert_string_equal(s->renderer.output_file, "./img/TungstenRender.png");
    const integrator_settings *in = &s->integrator;
    assert_int_equal(in->type, INTEGRATOR_PHOTON_POINTS);
    assert_string_equal(in->type_name, "progressive_transient_photon_map");
    ASSERT_NEAR(in->photon_count, 600000, 0);
    ASSERT_NEAR(in->volume_photon_count, 40000, 0);
    assert_int_equal(in->gather_photon_count, 20);
    ASSERT_NEAR(in->gather_radius, 0.05, 1e-15);
    ASSERT_NEAR(in->volume_gather_radius, 0.1, 1e-15);
    ASSERT_NEAR(in->alpha, 0.7, 1e-15);
    ASSERT_NEAR(in->volume_alpha, 0.8, 1e-15);
    assert_int_equal(in->max_bounces, 120);
    assert_int_equal(in->min_bounces, 0);
    assert_int_equal(in->fixed_volume_radius, 1);
    assert_int_equal(in->enable_guiding, 1);
    assert_int_equal(in->enable_elliptical, 1);
    assert_int_equal(in->strict_time_width, 1);
    assert_int_equal(in->include_surfaces, 1);
    assert_int_equal(in->low_order_scattering, 1);
    ASSERT_NEAR(in->vacuum_eta, 1.0, 0.0);
    ASSERT_VEC(s->lights[0].value, 1000, 1000, 1000, 1e-9);
    assert_int_equal(s->lights[0].medium, 0);
    assert_int_equal(s->cam.medium, 0);
    /* scatter.wo3 carries the gas: int_medium gas, no ext_medium -> vacuum outside */
    assert_int_equal(s->surface_count, 8);
    assert_int_equal(s->bsdfs[s->surfaces[0].bsdf].type, BSDF_FORWARD);
    assert_int_equal(s->surfaces[0].int_medium, 0);
    assert_int_equal(s->surfaces[0].ext_medium, MEDIUM_VACUUM);
    assert_int_equal(s->surfaces[1].overrides_media, 0);
}

static void test_scene_json_values(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("cbox-trans/scene.json", CBOX_WALL_MESHES, NULL);
    char path[4200];
    paper_file(path, sizeof path, dir, "scene.json");
    const scene *s = fx_load(path, NULL);
    assert_int_equal(s->medium_count, 0);
    assert_int_equal(s->light_count, 1);
    double I = 200.0 / (4.0 * M_PI); /* "power": 200 -> intensity P / (4 pi) */
    ASSERT_VEC(s->lights[0].value, I, I, I, 1e-12);
    ASSERT_VEC(s->lights[0].pos, 2.779, 4.8, 2.4, 1e-12);
    assert_int_equal(s->lights[0].medium, MEDIUM_VACUUM);
    assert_int_equal(s->cam.medium, MEDIUM_VACUUM);
    assert_int_equal(s->surface_count, 7);
    for (int i = 0; i < s->surface_count; i++) assert_int_equal(s->surfaces[i].overrides_media, 0);
    assert_int_equal(s->renderer.spp, 64);
}

/* scene.json is the plain (steady-state) Cornell box: its path tracer has no transient keys at all.
 * ToF-tungsten's PathTracerSettings::fromJson disables the gate when transient_time_center is absent
 * ("Time-gated output disabled for path tracing"), so it renders the steady-state image. A gate at the
 * table default [0 - 0.05, 0 + 0.05) makes every pixel black (all light paths are longer than 8 units). */
static void test_scene_json_without_time_keys_is_steady(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("cbox-trans/scene.json", CBOX_WALL_MESHES, NULL);
    char path[4200];
    paper_file(path, sizeof path, dir, "scene.json");
    const scene *s = fx_load(path, NULL);
    const time_window *tw = &s->integrator.window;
    if (tw->gated)
        fail_msg("scene.json has no transient_time_center/width but loads gated [%g, %g): the steady-state "
                 "Cornell box renders black",
                 tw->start, time_window_end(tw));
}

/* ---- the dragon scene: textures, conductors, smooth mesh ---- */

#define DRAGON_FILES                                                                                             \
    "dragon/scene-points-darts-short.json", "dragon/scene-points-short.json", "dragon/path_trace.json",         \
        "dragon/models/dragon.wo3", "dragon/models/walls.wo3", "dragon/textures/sig.tga",                          \
        "dragon/textures/camera-man.tga", "dragon/textures/floor.tga", "dragon/textures/walnut.tga"

/* index of the texture whose path ends with `name`, or -1 */
static int texture_named(const scene *s, const char *name)
{
    for (int i = 0; i < s->texture_count; i++) {
        size_t n = strlen(s->textures[i].path), k = strlen(name);
        if (n >= k && !strcmp(s->textures[i].path + n - k, name)) return i;
    }
    return -1;
}

/* The three dragon files load unchanged. Expected values from the files: 11 named BSDFs plus the inline
 * `forward` of the scattering cube; 4 textures (sig, camera-man, floor, walnut; bump2.tga is not used),
 * their sizes from the TGA headers; 87715 triangles summed over the 13 .wo3 files (dragon.wo3 87141). */
static void test_dragon_scenes_load(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files(DRAGON_FILES, NULL);
    static const char *const files[] = {"scene-points-darts-short.json", "scene-points-short.json", "path_trace.json"};
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/dragon/%s", dir, files[f]);
        scene *s = fx_load(path, NULL);
        assert_int_equal(s->bsdf_count, 12);
        assert_int_equal(s->texture_count, 4);
        assert_int_equal(s->tri_count, 87715);
        assert_int_equal(s->surface_count, 13);
        assert_int_equal(s->light_count, 1);
        if (s->notes && strstr(s->notes, "not found")) fail_msg("%s: a texture was not found:\n%s", path, s->notes);
        static const struct {
            const char *name;
            int w, h;
        } tex[] = {{"sig.tga", 1177, 1080}, {"camera-man.tga", 648, 648}, {"floor.tga", 473, 315}, {"walnut.tga", 560, 410}};
        for (size_t i = 0; i < sizeof tex / sizeof tex[0]; i++) {
            int k = texture_named(s, tex[i].name);
            if (k < 0) fail_msg("%s: no texture %s", path, tex[i].name);
            assert_int_equal(s->textures[k].width, tex[i].w);
            assert_int_equal(s->textures[k].height, tex[i].h);
        }
        /* bsdfs[1] "sig-image", [5] "wooden": textured lambert; [4] "top-base": rough_conductor, pbrt-ggx, 0.05,
         * Ag; [7] "Mirror": mirror, albedo 0.9; [8] "dragon": rough_conductor 0.1, Au; [11] the inline forward */
        assert_int_equal(s->bsdfs[1].type, BSDF_LAMBERT);
        assert_int_equal(s->bsdfs[1].texture, texture_named(s, "sig.tga"));
        assert_int_equal(s->bsdfs[5].texture, texture_named(s, "walnut.tga"));
        assert_int_equal(s->bsdfs[4].type, BSDF_ROUGH_CONDUCTOR);
        assert_int_equal(s->bsdfs[4].distribution, MICROFACET_PBRT_GGX);
        ASSERT_NEAR(s->bsdfs[4].roughness, 0.05, 0.0);
        vec3 eta, k;
        assert_true(bsdf_conductor_preset("Ag", &eta, &k));
        ASSERT_VEC(s->bsdfs[4].eta, eta.x, eta.y, eta.z, 0.0);
        ASSERT_VEC(s->bsdfs[4].k, k.x, k.y, k.z, 0.0);
        assert_int_equal(s->bsdfs[7].type, BSDF_MIRROR);
        ASSERT_VEC(s->bsdfs[7].albedo, 0.9, 0.9, 0.9, 0.0);
        assert_int_equal(s->bsdfs[8].type, BSDF_ROUGH_CONDUCTOR);
        ASSERT_NEAR(s->bsdfs[8].roughness, 0.1, 0.0);
        assert_true(bsdf_conductor_preset("Au", &eta, &k));
        ASSERT_VEC(s->bsdfs[8].eta, eta.x, eta.y, eta.z, 0.0);
        assert_int_equal(s->bsdfs[11].type, BSDF_FORWARD);
        /* integrator keys the files set */
        assert_int_equal(s->integrator.enable_two_sided_shading, 1);
        assert_int_equal(s->integrator.enable_consistency_checks, 1);
        ASSERT_NEAR(s->integrator.glossy_gather_alpha, 0.5, 0.0);
        /* path_trace.json: "timeout": "-1" = no limit; the others "14.5834" minutes */
        ASSERT_NEAR(s->renderer.timeout, f == 2 ? 0.0 : 14.5834 * 60.0, 1e-9);
        fx_drop(s);
    }
}

#define T(f) cmocka_unit_test_teardown(f, teardown_fx)

/* ---- Liu, Jiao and Jarosz 2022's example scenes (liu2022/, their README) ---- */

/* Every "warning:" line of text must contain one of the expected phrases; returns how many lines matched
 * each (counts[i]) and fails on any other warning. */
static void expect_warnings(const char *label, const char *text, const char *const *expected, int n, int *counts)
{
    for (int i = 0; i < n; i++) counts[i] = 0;
    for (const char *line = text; line && *line;) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        if (!strncmp(line, "warning:", 8)) {
            int hit = -1;
            for (int i = 0; i < n && hit < 0; i++) {
                const char *at = strstr(line, expected[i]);
                if (at && at < line + len) hit = i;
            }
            if (hit < 0) fail_msg("%s: unexpected warning: %.*s", label, (int)len, line);
            counts[hit]++;
        }
        line = end ? end + 1 : NULL;
    }
}

/* His three scenes in ../shared load unchanged (their own volume_photon_type mis_volumes_balls and delta gate;
 * only the resolution set) and render two passes at 32² with no error and no warning but: the unknown key "gather_photon_count_" (his files' disabled key, trailing underscore), and,
 * camera-warped (our default), the gate that ends before any light can reach the camera. His renderer does
 * not time the camera segment: warped, every pixel is exactly 0 (as the warning says); with camera_unwarp
 * true the warning goes and the image is lit. The volumetric caustic's lens (int_speed_of_light 0.66666667,
 * no int_medium) gets a clear region of η = 1.5 inside. */
static void test_liu2022_scenes(void **state)
{
    (void)state;
    static const char *const names[3] = {"cornell-box", "subsurface-scattering", "volumetric-caustic"};
    const char *dir = test_need_paper_files("liu2022/cornell-box/scene.json", "liu2022/subsurface-scattering/scene.json",
                                            "liu2022/volumetric-caustic/scene.json", NULL);
    static const char *const expected[2] = {"unknown key \"gather_photon_count_\"",
                                            "before any light path can reach the camera"};
    for (int i = 0; i < 3; i++)
        for (int unwarp = 0; unwarp < 2; unwarp++) {
            char path[4200], label[256];
            snprintf(path, sizeof path, "%s/liu2022/%s/scene.json", dir, names[i]);
            snprintf(label, sizeof label, "%s (%s)", names[i], unwarp ? "camera_unwarp=true" : "unchanged time");
            const char *sets[2] = {"resolution=32", "camera_unwarp=true"};
            scene *s = fx_slot();
            dp_error err;
            memset(&err, 0, sizeof err);
            scene_load_options o = {.sets = sets, .set_count = unwarp ? 2 : 1};
            if (scene_load(path, &o, s, &err)) fail_msg("%s: %s", label, err.msg);
            fx_mark(s, 1);
            render_plan p;
            if (plan_resolve(s, &p, &err)) fail_msg("%s: %s", label, err.msg);
            char *warned = NULL;
            size_t wlen = 0;
            FILE *w = open_memstream(&warned, &wlen);
            assert_non_null(w);
            render_warn(w, s, &p);
            fclose(w);
            plan_free(&p);
            int load_counts[2], run_counts[2];
            expect_warnings(label, s->notes, expected, 2, load_counts);
            expect_warnings(label, warned, expected, 2, run_counts);
            free(warned);
            assert_int_equal(load_counts[0], 1);
            assert_int_equal(load_counts[1] + run_counts[1], unwarp ? 0 : 1);
            if (i == 2) { /* the lens: dielectric sphere, gas outside, a clear region of speed 2/3 inside */
                int lens = -1;
                for (int k = 0; k < s->surface_count; k++)
                    if (!strcmp(s->surfaces[k].name, "Lens")) lens = k;
                assert_true(lens >= 0);
                const surface *sf = &s->surfaces[lens];
                assert_true(sf->overrides_media && sf->int_medium >= 0 && sf->int_medium != sf->ext_medium);
                const medium *m = &s->media[sf->int_medium];
                assert_float_equal(m->eta, 1.0 / 0.66666667, 1e-12);
                assert_true(v3_is_zero(m->sigma_t));
            }
            film f;
            render_stats st;
            render_passes(s, 2, 7, 1, &f, &st);
            double sum = 0.0;
            for (size_t k = 0; k < (size_t)f.width * f.height * 3; k++) sum += f.sum[k];
            print_message("  %-45s 1 pass at 32²: image total %.4g; warnings as expected\n", label, sum / f.weight_sum);
            if (unwarp) assert_true(sum > 0.0);
            else assert_true(sum == 0.0);
            film_free(&f);
            fx_drop(s);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_shared_scenes_load),
        T(test_path_tracer_json_values),
        T(test_transient_json_values),
        T(test_scene_json_values),
        T(test_scene_json_without_time_keys_is_steady),
        T(test_dragon_scenes_load),
        T(test_liu2022_scenes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
