/* tier: quick */
/* The key table (src/scene/keys.c) against what the loader, the plan and the documentation do with it:
 * `dartspp keys` lists exactly the keys the loader accepts (checked both ways, on every key written in our
 * scenes and the paper's, and on near-miss names); every key that changes the image changes the plan's JSON
 * (the `dartspp.plan` of every EXR); a key the chosen integrator does not read is reported; every bound and
 * choice of the table is enforced with a message naming the file and key; docs/keys.md is the output of
 * `dartspp keys --markdown`. */
#include "fixtures.h"

#include <cjson/cJSON.h>
#include <dirent.h>

#include "dartspp/plan.h"

#define BASE_SCENE "scenes/fogbox/fogbox.json" /* photon points (DARTS), gated, a small Cornell box */
#define KEYS_DOC "docs/keys.md"
#define MAX_SETS 8

/* Loads the base scene with `--set` overrides (resolution 8 first); 0 or -1 with err. */
static int load_with(const char *const *sets, int count, int verbose, scene *s, dp_error *err)
{
    const char *all[MAX_SETS + 1] = {"resolution=8"};
    for (int i = 0; i < count && i < MAX_SETS; i++) all[1 + i] = sets[i];
    scene_load_options opt = {.sets = all, .set_count = 1 + count, .verbose = verbose};
    memset(err, 0, sizeof *err);
    return scene_load(BASE_SCENE, &opt, s, err);
}

/* The plan's JSON of the base scene with overrides; 0, or -1 when loading or the plan refuses them. */
static int plan_text_with(const char *const *sets, int count, char *json, size_t n)
{
    scene s;
    dp_error err;
    if (load_with(sets, count, 0, &s, &err)) return -1;
    render_plan p;
    int rc = plan_resolve(&s, &p, &err);
    if (!rc) {
        rc = plan_json(&p, &s, json, n);
        plan_free(&p);
    }
    scene_free(&s);
    return rc;
}

static const void *field_of(const scene_key *k, const scene *s)
{
    const char *base = k->section == KEY_SECTION_INTEGRATOR ? (const char *)&s->integrator : (const char *)&s->renderer;
    return base + k->offset;
}

/* `key=value` with the value the scene resolved for k (toggle 0), or a different legal one (toggle 1). */
static void key_setting(const scene_key *k, const scene *s, int toggle, char *out, size_t n)
{
    const void *f = field_of(k, s);
    int len = snprintf(out, n, "%s=", k->name);
    char *v = out + len;
    size_t vn = n - (size_t)len;
    double x;
    switch (k->type) {
    case KEY_BOOL: snprintf(v, vn, "%s", *(const int *)f ^ toggle ? "true" : "false"); return;
    case KEY_CHOICE: {
        int count = 0, i = *(const int *)f;
        while (k->choices[count]) count++;
        snprintf(v, vn, "%s", k->choices[toggle ? (i + 1) % count : i]);
        return;
    }
    case KEY_INT: {
        long i = *(const long *)f;
        if (toggle) i = (k->bounds & KEY_HI) && i + 1 > k->hi ? i - 1 : i + 1;
        snprintf(v, vn, "%ld", i);
        return;
    }
    case KEY_NUMBER:
        x = *(const double *)f;
        if (toggle) x = (k->bounds & KEY_HI) ? (x < k->hi ? 0.5 * (x + k->hi) : 0.5 * (x + k->lo)) : 1.5 * x + 0.5;
        snprintf(v, vn, "%.17g", x);
        return;
    case KEY_SHAPE3: snprintf(v, vn, "%s", toggle ? "[16,16,32]" : "[128,128,256]"); return;
    case KEY_NUMBER_LIST: {
        const key_number_list *l = f;
        if (toggle) {
            snprintf(v, vn, "%s", l->count ? "[]" : "[20,25]");
            return;
        }
        size_t len = (size_t)snprintf(v, vn, "[");
        for (int i = 0; i < l->count && len < vn; i++) len += (size_t)snprintf(v + len, vn - len, i ? ",%.17g" : "%.17g", l->v[i]);
        if (len < vn) snprintf(v + len, vn - len, "]");
        return;
    }
    case KEY_STRING: snprintf(v, vn, "%s", toggle ? "other" : (const char *)f); return;
    case KEY_DURATION: snprintf(v, vn, "%s", toggle ? "2m" : "30s"); return;
    case KEY_ANY: snprintf(v, vn, "true"); return;
    }
}

/* The integrator a check of k runs: photon points (the base scene) unless only the path tracer reads it. */
static const char *integrator_for(const scene_key *k)
{
    return scene_key_read_by(k, INTEGRATOR_PHOTON_POINTS) || !k->read_by ? NULL : "type=path_tracer";
}

/* ---- the list and the loader agree ---- */

/* Key names printed by `dartspp keys`, one "section.name" per listed key. */
static int listed_keys(char names[][80], int max)
{
    static char out[1 << 16];
    assert_int_equal(test_run(DARTSPP_BIN " keys", out, sizeof out), 0);
    int n = 0;
    for (char *line = strtok(out, "\n"); line; line = strtok(NULL, "\n")) {
        if (line[0] == ' ') continue; /* the meaning, indented */
        assert_true(n < max);
        snprintf(names[n], sizeof names[n], "%.*s", (int)strcspn(line, " "), line);
        n++;
    }
    return n;
}

static int is_listed(char names[][80], int n, const char *section, const char *key)
{
    char full[128];
    snprintf(full, sizeof full, "%s.%s", section, key);
    for (int i = 0; i < n; i++)
        if (!strcmp(names[i], full)) return 1;
    return 0;
}

/* Whether the loader takes `--set key=...` (a legal value when the table has the key, "1" otherwise). */
static int loader_accepts_set(const char *key, const scene *base)
{
    const scene_key *k = scene_key_find(key);
    char set[256];
    if (k) key_setting(k, base, 0, set, sizeof set);
    else snprintf(set, sizeof set, "%s=1", key);
    const char *sets[2] = {set, k ? integrator_for(k) : NULL};
    scene s;
    dp_error err;
    if (load_with(sets, sets[1] ? 2 : 1, 0, &s, &err)) return 0;
    scene_free(&s);
    return 1;
}

/* Whether the loader takes `key` written in the scene file's section (no "not a key of dartspp" note). */
static int loader_accepts_in_file(const char *section, const char *key, const char *dir)
{
    char text[2048], path[600];
    snprintf(text, sizeof text,
             "{ \"camera\": { \"type\": \"pinhole\", \"resolution\": [4, 4], \"fov\": 40,"
             "  \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
             "  \"primitives\": [ { \"type\": \"point\", \"emission\": 1, \"transform\": { \"position\": [0, 0, 2] } } ],"
             "  \"%s\": { \"%s\": \"not a legal value of any key\" } }",
             section, key);
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path, text);
    scene s;
    dp_error err = {0};
    scene_load_options opt = {.verbose = 1};
    if (scene_load(path, &opt, &s, &err)) return 1; /* read, and refused: the loader knows the key */
    char note[256], misspelt[256]; /* a key far from every key is a note, one a few edits from one a warning */
    snprintf(note, sizeof note, "ignored key: %s.%s (not a key of dartspp)", section, key);
    snprintf(misspelt, sizeof misspelt, "%s: unknown key \"%s\" (did you mean", section, key);
    int unknown = s.notes && (strstr(s.notes, note) || strstr(s.notes, misspelt));
    scene_free(&s);
    return !unknown;
}

/* Adds the integrator and renderer key names of one scene file to names (section.key, no duplicates). */
static void collect_file_keys(const char *path, char names[][80], int *n, int max)
{
    char *text = read_all(path, NULL);
    cJSON *root = cJSON_Parse(text);
    free(text);
    for (int sec = KEY_SECTION_INTEGRATOR; root && sec <= KEY_SECTION_RENDERER; sec++) {
        const cJSON *obj = cJSON_GetObjectItem(root, scene_key_section_name(sec));
        for (const cJSON *it = obj ? obj->child : NULL; it; it = it->next)
            if (!is_listed(names, *n, scene_key_section_name(sec), it->string) && *n < max)
                snprintf(names[(*n)++], 80, "%s.%s", scene_key_section_name(sec), it->string);
    }
    cJSON_Delete(root);
}

static void collect_folder_keys(const char *dir, char names[][80], int *n, int max)
{
    DIR *d = opendir(dir);
    for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        size_t l = strlen(e->d_name);
        if (e->d_name[0] == '.') continue;
        if (l > 5 && !strcmp(e->d_name + l - 5, ".json")) collect_file_keys(path, names, n, max);
        else if (e->d_type == DT_DIR) collect_folder_keys(path, names, n, max);
    }
    if (d) closedir(d);
}

/* Both ways: every listed key loads (by --set and in a file), and every candidate name — each key written in
 * our scenes and the paper's, and near misses of listed names — loads exactly when it is listed. */
static void test_keys_listed_are_the_keys_accepted(void **state)
{
    (void)state;
    static char listed[256][80], candidates[1024][80];
    int n = listed_keys(listed, 256), table_n, c = 0;
    scene_keys(&table_n);
    assert_int_equal(n, table_n);
    scene base;
    dp_error err;
    assert_int_equal(load_with(NULL, 0, 0, &base, &err), 0);
    for (int i = 0; i < n; i++) snprintf(candidates[c++], 80, "%s", listed[i]);
    collect_folder_keys("scenes", candidates, &c, 1024);
    if (test_paper_scenes()) collect_folder_keys(test_paper_scenes(), candidates, &c, 1024);
    const char *near_miss[] = {"integrator.alphas", "integrator.Alpha", "integrator.photon-count", "renderer.spp_steps",
                               "integrator.vacuum_speed_of_light", "renderer.time_out", "integrator.eda_shapes"};
    for (size_t i = 0; i < sizeof near_miss / sizeof *near_miss; i++) snprintf(candidates[c++], 80, "%s", near_miss[i]);
    char *dir = test_tmpdir();
    int wrong = 0;
    for (int i = 0; i < c; i++) {
        char section[32];
        const char *dot = strchr(candidates[i], '.'), *key = dot + 1;
        snprintf(section, sizeof section, "%.*s", (int)(dot - candidates[i]), candidates[i]);
        int in_list = is_listed(listed, n, section, key);
        int by_set = loader_accepts_set(key, &base), in_file = loader_accepts_in_file(section, key, dir);
        if (by_set != in_list || in_file != in_list) {
            print_error("%s: listed %d, accepted by --set %d, accepted in the file %d\n", candidates[i], in_list, by_set, in_file);
            wrong++;
        }
    }
    print_message("  %d candidate names (%d listed keys)\n", c, n);
    test_rmtree(dir);
    scene_free(&base);
    assert_int_equal(wrong, 0);
}

/* ---- the plan ---- */

/* Every key that changes the image, set to another legal value, changes the plan's JSON (or is refused by
 * the plan: no image is made that the plan does not describe). */
static void test_image_keys_change_the_plan(void **state)
{
    (void)state;
    int n, checked = 0, wrong = 0;
    const scene_key *keys = scene_keys(&n);
    scene base;
    dp_error err;
    assert_int_equal(load_with(NULL, 0, 0, &base, &err), 0);
    for (int i = 0; i < n; i++) {
        const scene_key *k = &keys[i];
        if (!k->changes_image) continue;
        assert_int_not_equal(k->read_by, 0); /* a key nothing reads cannot change the image */
        const char *integ = integrator_for(k);
        char set[256], before[16384], after[16384];
        key_setting(k, &base, 1, set, sizeof set);
        const char *sets[2] = {integ ? integ : set, set};
        int count = integ ? 2 : 1;
        assert_int_equal(plan_text_with(sets, count - 1, before, sizeof before), 0);
        int rc = plan_text_with(sets, count, after, sizeof after);
        if (rc == 0 && !strcmp(before, after)) {
            print_error("--set %s leaves the plan as it was:\n%s\n", set, after);
            wrong++;
        }
        checked++;
    }
    scene_free(&base);
    print_message("  %d image-changing keys toggled\n", checked);
    assert_true(checked >= 40);
    assert_int_equal(wrong, 0);
}

/* ---- keys the integrator does not read ---- */

static void notes_of(const char *const *sets, int count, int verbose, char *out, size_t n)
{
    scene s;
    dp_error err;
    assert_int_equal(load_with(sets, count, verbose, &s, &err), 0);
    snprintf(out, n, "%s", s.notes ? s.notes : "");
    scene_free(&s);
}

/* A key set away from its default that the chosen integrator does not read is a warning naming it; at its
 * default it is a note with --verbose; a key the integrator reads is neither. */
static void test_unread_keys_reported(void **state)
{
    (void)state;
    char notes[8192];
    const char *pt_strict[] = {"type=path_tracer", "strict_time_width=true", "surface_chains=false"};
    notes_of(pt_strict, 3, 0, notes, sizeof notes);
    ASSERT_CONTAINS(notes, "warning: " BASE_SCENE ": integrator.strict_time_width: the path_tracer integrator does not read");
    ASSERT_CONTAINS(notes, "integrator.surface_chains: the path_tracer integrator does not read");
    const char *pt_plain[] = {"type=path_tracer", "strict_time_width=false"};
    notes_of(pt_plain, 2, 1, notes, sizeof notes);
    if (strstr(notes, "strict_time_width: the path_tracer")) fail_msg("a key at its default warned:\n%s", notes);
    ASSERT_CONTAINS(notes, "ignored key: integrator.strict_time_width (not read by path_tracer)");
    const char *pt_guided[] = {"type=path_tracer", "enable_guiding=true", "enable_elliptical=true"};
    notes_of(pt_guided, 3, 0, notes, sizeof notes);
    if (strstr(notes, "enable_guiding")) fail_msg("a key the path tracer reads was reported:\n%s", notes);
    const char *pp_rr[] = {"enable_rr=false"};
    notes_of(pp_rr, 1, 0, notes, sizeof notes);
    ASSERT_CONTAINS(notes, "integrator.enable_rr: the progressive_transient_photon_map integrator does not read");
    const char *pp_read[] = {"enable_guiding=false", "scene_bvh=true"};
    notes_of(pp_read, 2, 1, notes, sizeof notes);
    if (strstr(notes, "enable_guiding")) fail_msg("a key photon points read was reported:\n%s", notes);
    ASSERT_CONTAINS(notes, "ignored key: renderer.scene_bvh (accepted from the format, not read by dartspp)");
}

/* The paper's DARTS path-tracer scene: its DARTS keys are read (no "does not read" warning), and its plan
 * says the DARTS path tracer runs. */
static void test_paper_path_trace_darts_keys_reported(void **state)
{
    (void)state;
    const char *dir = test_need_paper_files("dragon/path_trace.json", NULL);
    char path[1024];
    snprintf(path, sizeof path, "%s/dragon/path_trace.json", dir);
    scene s;
    dp_error err = {0};
    scene_load_options opt = {0};
    assert_int_equal(scene_load(path, &opt, &s, &err), 0);
    if (s.notes && strstr(s.notes, "enable_guiding")) fail_msg("enable_guiding reported:\n%s", s.notes);
    if (s.notes && strstr(s.notes, "enable_elliptical")) fail_msg("enable_elliptical reported:\n%s", s.notes);
    render_plan p;
    assert_int_equal(plan_resolve(&s, &p, &err), 0);
    assert_true(p.darts.active && p.darts.enable_guiding && p.darts.enable_elliptical);
    char json[16384];
    assert_int_equal(plan_json(&p, &s, json, sizeof json), 0);
    ASSERT_CONTAINS(json, "\"method\":\"DARTS path tracer\"");
    plan_free(&p);
    scene_free(&s);
}

/* The other objects keep no list of their keys: a key is known where it is read, so a member no reader asked
 * for is listed with --verbose — one the format has but this object's type does not read included — and no
 * member that was read is. */
static void test_object_keys_nobody_reads(void **state)
{
    (void)state;
    char *dir = test_tmpdir();
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    test_write_file(path,
                    "{ \"media\": [ { \"name\": \"fog\", \"sigma_s\": 0.5, \"colour\": 1,"
                    "    \"phase_function\": { \"type\": \"isotropic\", \"g\": 0.5 } } ],"
                    "  \"bsdfs\": [ { \"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.5, \"shininess\": 3 } ],"
                    "  \"primitives\": [ { \"type\": \"point\", \"emission\": 1, \"bsdf\": \"white\", \"ext_medium\": \"fog\","
                    "      \"transform\": { \"position\": [0, 0, 2], \"skew\": 1 } },"
                    "    { \"type\": \"quad\", \"bsdf\": \"white\", \"smooth\": true,"
                    "      \"transform\": { \"position\": [0, -1, 2], \"scale\": 4 } } ],"
                    "  \"camera\": { \"resolution\": [4, 4], \"fov\": 40, \"medium\": \"fog\", \"tonemap\": \"filmic\","
                    "    \"transform\": { \"position\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1, 0] } },"
                    "  \"extras\": { } }");
    scene s;
    dp_error err = {0};
    scene_load_options opt = {.verbose = 1};
    int rc = scene_load(path, &opt, &s, &err);
    test_rmtree(dir);
    if (rc) fail_msg("%s", err.msg);
    const char *expected[] = {"media[0].colour\n", "media[0].phase_function.g\n", "bsdfs[0].shininess\n",
                              "primitives[0].bsdf\n", "primitives[0].transform.skew\n", "primitives[1].smooth\n",
                              "camera.tonemap\n", "ignored key: extras\n"};
    const char *read[] = {"media[0].sigma_s\n", "media[0].name\n", "media[0].phase_function.type\n", "media[0].phase_function\n",
                          "bsdfs[0].albedo\n", "primitives[0].emission\n", "primitives[0].transform.position\n",
                          "primitives[1].bsdf\n", "primitives[1].transform\n", "camera.fov\n", "camera.medium\n",
                          "camera.transform\n", "ignored key: media\n", "ignored key: camera\n"};
    char notes[4096];
    snprintf(notes, sizeof notes, "%s", s.notes ? s.notes : "");
    scene_free(&s);
    print_message("%s", notes);
    for (size_t i = 0; i < sizeof expected / sizeof *expected; i++) ASSERT_CONTAINS(notes, expected[i]);
    for (size_t i = 0; i < sizeof read / sizeof *read; i++)
        if (strstr(notes, read[i])) fail_msg("%s was read, yet listed as ignored", read[i]);
}

/* ---- every bound and choice of the table ---- */

static int refused_with_key(const char *set, const char *section, const char *key, const char *reason)
{
    const char *sets[1] = {set};
    scene s;
    dp_error err;
    if (!load_with(sets, 1, 0, &s, &err)) {
        scene_free(&s);
        print_error("--set %s was accepted\n", set);
        return 0;
    }
    char where[128];
    snprintf(where, sizeof where, BASE_SCENE ": %s.%s: ", section, key);
    if (strstr(err.msg, where) && strstr(err.msg, reason)) return 1;
    print_error("--set %s: message without \"%s\" and \"%s\": %s\n", set, where, reason, err.msg);
    return 0;
}

/* Below lo (at lo when open), above hi, an unknown choice, a non-boolean, a non-integer: each refused with
 * the file, the key and the reason. */
static void test_bounds_and_choices_enforced(void **state)
{
    (void)state;
    int n, checked = 0, ok = 0;
    const scene_key *keys = scene_keys(&n);
    for (int i = 0; i < n; i++) {
        const scene_key *k = &keys[i];
        const char *sec = scene_key_section_name(k->section);
        char set[256];
        if ((k->type == KEY_INT || k->type == KEY_NUMBER) && (k->bounds & KEY_LO)) {
            snprintf(set, sizeof set, "%s=%.17g", k->name, k->bounds & KEY_LO_OPEN ? k->lo : k->lo - 1);
            ok += refused_with_key(set, sec, k->name, k->bounds & KEY_LO_OPEN ? "must be >" : "must be");
            checked++;
        }
        if ((k->type == KEY_INT || k->type == KEY_NUMBER) && (k->bounds & KEY_HI)) {
            snprintf(set, sizeof set, "%s=%.17g", k->name, k->hi + 1);
            ok += refused_with_key(set, sec, k->name, "must be");
            checked++;
        }
        if (k->type == KEY_INT) {
            snprintf(set, sizeof set, "%s=%.17g", k->name, (k->bounds & KEY_LO ? k->lo : 0) + 1.5);
            ok += refused_with_key(set, sec, k->name, "expected an integer");
            checked++;
        }
        if (k->type == KEY_CHOICE) {
            snprintf(set, sizeof set, "%s=nope", k->name);
            ok += refused_with_key(set, sec, k->name, "'nope' is not one of");
            checked++;
        }
        if (k->type == KEY_BOOL) {
            snprintf(set, sizeof set, "%s=maybe", k->name);
            ok += refused_with_key(set, sec, k->name, "expected true or false");
            checked++;
        }
        if (k->type == KEY_SHAPE3) {
            snprintf(set, sizeof set, "%s=[%g,%g,%g]", k->name, k->lo, k->lo, k->lo);
            ok += refused_with_key(set, sec, k->name, "expected three integers");
            checked++;
        }
        if (k->type == KEY_NUMBER_LIST) {
            snprintf(set, sizeof set, "%s=[%.17g]", k->name, k->bounds & KEY_LO_OPEN ? k->lo : k->lo - 1);
            ok += refused_with_key(set, sec, k->name, "out of range");
            snprintf(set, sizeof set, "%s=[%.17g,%.17g]", k->name, k->hi, k->hi);
            ok += refused_with_key(set, sec, k->name, "given twice");
            checked += 2;
        }
    }
    print_message("  %d bad values, %d refused as required\n", checked, ok);
    assert_true(checked >= 40);
    assert_int_equal(ok, checked);
}

/* ---- the documentation ---- */

/* docs/keys.md holds, between its markers, exactly what `dartspp keys --markdown` prints. */
static void test_keys_doc_is_generated(void **state)
{
    (void)state;
    static char printed[1 << 16];
    assert_int_equal(test_run(DARTSPP_BIN " keys --markdown", printed, sizeof printed), 0);
    char *doc = read_all(KEYS_DOC, NULL);
    const char *begin_mark = "<!-- begin: dartspp keys --markdown -->\n", *end_mark = "<!-- end: dartspp keys --markdown -->";
    char *begin = strstr(doc, begin_mark), *end = begin ? strstr(begin, end_mark) : NULL;
    assert_non_null(begin);
    assert_non_null(end);
    begin += strlen(begin_mark);
    *end = 0;
    int same = !strcmp(begin, printed);
    free(doc);
    if (!same)
        fail_msg(KEYS_DOC " differs from `dartspp keys --markdown`: run `make docs-keys`");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keys_listed_are_the_keys_accepted),
        cmocka_unit_test(test_image_keys_change_the_plan),
        cmocka_unit_test(test_unread_keys_reported),
        cmocka_unit_test(test_paper_path_trace_darts_keys_reported),
        cmocka_unit_test(test_object_keys_nobody_reads),
        cmocka_unit_test(test_bounds_and_choices_enforced),
        cmocka_unit_test(test_keys_doc_is_generated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
