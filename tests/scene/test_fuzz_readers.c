/* tier: quick */
/* An in-process fuzz of the scene JSON and `.wo3` readers: truncations, replaced bytes, deleted tokens and odd
 * values in our own scenes/cbox-fog (with a `.wo3` mesh added), and truncations, bad header counts, bad
 * indices and mutations of a hand-made `.wo3` floor. Under ASan/UBSan every load must succeed or fail with a
 * message, never crash. */
#include "fixtures.h"

#include <time.h>

static uint64_t lcg_state;
static uint32_t lcg(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (uint32_t)(lcg_state >> 33);
}

typedef struct {
    int loaded, failed;
} fuzz_tally;

/* One fuzz load: success, or failure with a message (err.msg cleared before the call). */
static void fuzz_one(const char *dir, const char *name, const char *data, size_t len, fuzz_tally *t, const char *what)
{
    scene s;
    dp_error err;
    int rc = load_text(dir, name, data, len, NULL, &s, &err);
    if (rc == 0) {
        t->loaded++;
        scene_free(&s);
        return;
    }
    t->failed++;
    if (!err.msg[0]) fail_msg("%s: scene_load failed without a message", what);
    /* a failed load leaves nothing behind */
    if (s.verts || s.rt_scene || s.surfaces) fail_msg("%s: a failed load left memory in the scene", what);
}

/* Token boundaries of a JSON text: strings, numbers and literals, punctuation. */
static size_t json_tokens(const char *t, size_t n, size_t *start, size_t *end, int *is_value, size_t cap)
{
    size_t k = 0, i = 0;
    while (i < n && k < cap) {
        char c = t[i];
        if (c == ' ' || c == '\n' || c == '\t' || c == '\r') {
            i++;
            continue;
        }
        size_t b = i;
        int value = 1;
        if (c == '"') {
            i++;
            while (i < n && t[i] != '"') i += t[i] == '\\' ? 2 : 1;
            i++;
            if (i > n) i = n;
            /* a string followed by ':' is a key */
            size_t j = i;
            while (j < n && (t[j] == ' ' || t[j] == '\n' || t[j] == '\t' || t[j] == '\r')) j++;
            if (j < n && t[j] == ':') value = 0;
        } else if (strchr("{}[],:", c)) {
            i++;
            value = 0;
        } else {
            while (i < n && !strchr(" \n\t\r{}[],:\"", t[i])) i++;
        }
        start[k] = b;
        end[k] = i;
        is_value[k] = value;
        k++;
    }
    return k;
}

/* A Cornell-box floor as a `.wo3` mesh (docs/scene-format.md §1), the size of the paper's cbox_floor.001.wo3:
 * 4 vertices (position, normal +y, uv) at offset 8, triangle count at 136, 2 triangles at 144; 176 bytes. */
#define FLOOR_WO3_SIZE 176
static void make_floor_wo3(unsigned char b[FLOOR_WO3_SIZE])
{
    static const float corner[4][2] = {{0, 0}, {0, 5.592f}, {5.56f, 5.592f}, {5.56f, 0}}; /* x, z */
    static const uint32_t tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
    memset(b, 0, FLOOR_WO3_SIZE);
    put_u64(b, 4);
    for (int i = 0; i < 4; i++) {
        unsigned char *v = b + 8 + 32 * i;
        put_f32(v, corner[i][0]);
        put_f32(v + 4, 0);
        put_f32(v + 8, corner[i][1]);
        put_f32(v + 16, 1); /* normal (0, 1, 0) */
        put_f32(v + 24, corner[i][0] / 5.56f);
        put_f32(v + 28, corner[i][1] / 5.592f);
    }
    put_u64(b + 136, 2);
    for (int t = 0; t < 2; t++)
        for (int k = 0; k < 3; k++) put_u32(b + 144 + 16 * t + 4 * k, tri[t][k]);
}

/* Writes make_floor_wo3 to dir/meshes/floor.wo3. */
static void write_meshes_folder(const char *dir)
{
    char path[1100];
    unsigned char floor[FLOOR_WO3_SIZE];
    make_floor_wo3(floor);
    snprintf(path, sizeof path, "%s/meshes", dir);
    if (mkdir(path, 0700)) fail_msg("cannot create %s", path);
    snprintf(path, sizeof path, "%s/meshes/floor.wo3", dir);
    write_bytes(path, floor, sizeof floor);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_fuzz_scene_json(void **state)
{
    (void)state;
    double t0 = now_seconds();
    /* our fog box with one `.wo3` mesh added, so that mesh file names are fuzzed too */
    char *base = fx_keep(read_all(CBOX_FOG "/transient.json", NULL));
    char *orig = fx_keep(replace1(base, "\"primitives\": [",
                                  "\"primitives\": [\n        {\"name\": \"floor-mesh\", \"type\": \"mesh\", "
                                  "\"file\": \"./meshes/floor.wo3\", \"bsdf\": \"white\", \"smooth\": false},"));
    size_t n = strlen(orig);
    const char *dir = fx_dir();
    write_meshes_folder(dir);
    char *buf = fx_keep(malloc(n + 64));
    fuzz_tally t = {0, 0}, t_trunc, t_mut, t_tok, t_val;

    /* the unmodified copy loads from the temp folder (its mesh from the meshes folder written there) */
    fuzz_one(dir, "orig.json", orig, n, &t, "original");
    assert_int_equal(t.loaded, 1);

    /* (a) truncations at 200 evenly spaced lengths */
    for (int i = 0; i < 200; i++) fuzz_one(dir, "trunc.json", orig, (size_t)i * n / 200, &t, "truncation");
    t_trunc = t;
    /* (b) 300 copies with 1-8 bytes replaced (half of them random bytes, half JSON-ish characters) */
    static const char jsonish[] = "{}[],:\"0123456789.-+eE truefalsn\\";
    lcg_state = 12345;
    for (int i = 0; i < 300; i++) {
        memcpy(buf, orig, n);
        int k = 1 + (int)(lcg() % 8);
        for (int j = 0; j < k; j++) {
            size_t pos = lcg() % n;
            buf[pos] = (lcg() & 1) ? (char)(lcg() & 0xff) : jsonish[lcg() % (sizeof jsonish - 1)];
        }
        fuzz_one(dir, "mut.json", buf, n, &t, "byte mutation");
    }
    t_mut = t;
    /* (c) 200 copies with one token deleted */
    size_t *ts = fx_keep(malloc(n * sizeof *ts)), *te = fx_keep(malloc(n * sizeof *te));
    int *isv = fx_keep(malloc(n * sizeof *isv));
    size_t ntok = json_tokens(orig, n, ts, te, isv, n);
    assert_true(ntok > 100);
    for (int i = 0; i < 200; i++) {
        size_t k = lcg() % ntok;
        memcpy(buf, orig, ts[k]);
        memcpy(buf + ts[k], orig + te[k], n - te[k]);
        fuzz_one(dir, "tok.json", buf, ts[k] + n - te[k], &t, "token deletion");
    }
    t_tok = t;
    /* (d) 1000 copies with one value replaced by an odd one: reaches the typed getters and range checks,
     * which byte noise mostly cannot (it breaks the JSON first) */
    static const char *const odd[] = {"-1", "0", "-0", "1e999", "-1e999", "1e308", "4294967296", "9e18", "0.5",
                                      "\"\"", "\"x\"", "\"1e6\"", "\"nan\"", "\"inf\"", "null", "true", "false",
                                      "[]", "{}", "[1,2]", "[1,2,3]", "[1,\"a\",3]", "[[1,2,3]]", "{\"a\":1}",
                                      "\"./meshes\"", "\"/\"", "\"./meshes/none.wo3\"", "\"gas\"", "\"light\"",
                                      "\"fog\"", "\"white\""};
    char *big = fx_keep(malloc(n + 64));
    size_t nvals = 0;
    for (size_t k = 0; k < ntok; k++) nvals += isv[k];
    assert_true(nvals > 50);
    for (int i = 0; i < 1000; i++) {
        size_t pick = lcg() % nvals, k = 0;
        for (size_t seen = 0;; k++)
            if (isv[k] && seen++ == pick) break;
        const char *v = odd[lcg() % (sizeof odd / sizeof odd[0])];
        size_t lv = strlen(v);
        memcpy(big, orig, ts[k]);
        memcpy(big + ts[k], v, lv);
        memcpy(big + ts[k] + lv, orig + te[k], n - te[k]);
        fuzz_one(dir, "val.json", big, ts[k] + lv + n - te[k], &t, "value replacement");
    }
    t_val = t;
    print_message("fuzz scene json (loaded/refused): truncations %d/%d, bytes %d/%d, tokens %d/%d, values %d/%d; "
                  "%.1f s\n",
                  t_trunc.loaded - 1, t_trunc.failed, t_mut.loaded - t_trunc.loaded, t_mut.failed - t_trunc.failed,
                  t_tok.loaded - t_mut.loaded, t_tok.failed - t_mut.failed, t_val.loaded - t_tok.loaded,
                  t_val.failed - t_tok.failed, now_seconds() - t0);
    assert_true(t.failed > 0);
}

static const char WO3_SCENE[] =
    "{\"bsdfs\": [{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}],\n"
    " \"primitives\": [{\"type\": \"mesh\", \"file\": \"floor.wo3\", \"bsdf\": \"w\"}],\n"
    " \"camera\": {\"resolution\": [4, 4], \"fov\": 40,\n"
    "   \"transform\": {\"position\": [2.78, 2.73, -8], \"look_at\": [2.78, 2.73, 0], \"up\": [0, 1, 0]}},\n"
    " \"integrator\": {\"type\": \"path_tracer\"}, \"renderer\": {\"spp\": 1}}\n";

/* Loads WO3_SCENE with floor.wo3 = data[0..len); returns the scene_load result (the scene is freed). */
static int load_wo3(const char *dir, const unsigned char *data, size_t len, const char *what, uint32_t *tri_count)
{
    char mesh[1100], scn[1100];
    snprintf(mesh, sizeof mesh, "%s/floor.wo3", dir);
    write_bytes(mesh, data, len);
    snprintf(scn, sizeof scn, "%s/wo3.json", dir);
    scene s;
    dp_error err;
    memset(&err, 0, sizeof err);
    int rc = scene_load(scn, NULL, &s, &err);
    if (rc == 0) {
        if (tri_count) *tri_count = s.tri_count;
        scene_free(&s);
    } else if (!err.msg[0]) {
        fail_msg("%s: the load failed without a message", what);
    } else if (!strstr(err.msg, "floor.wo3")) {
        fail_msg("%s: the message does not name the mesh file: %s", what, err.msg);
    }
    return rc;
}

static void test_fuzz_wo3(void **state)
{
    (void)state;
    double t0 = now_seconds();
    unsigned char *orig = fx_keep(malloc(FLOOR_WO3_SIZE));
    make_floor_wo3(orig);
    size_t n = FLOOR_WO3_SIZE;
    /* docs/scene-format.md §1: 176 B = 16 + 4*32 + 2*16 (the floor: 4 vertices, 2 triangles) */
    assert_int_equal(n, 176);
    const char *dir = fx_dir();
    char scn[1100];
    snprintf(scn, sizeof scn, "%s/wo3.json", dir);
    write_bytes(scn, WO3_SCENE, strlen(WO3_SCENE));
    uint32_t nt = 0;
    if (load_wo3(dir, orig, n, "original", &nt)) fail_msg("the unmodified floor mesh does not load");
    assert_int_equal(nt, 2);

    /* every truncation breaks the size identity 16 + 32 nv + 16 nt: all must be refused */
    for (size_t len = 0; len < n; len++) {
        char what[64];
        snprintf(what, sizeof what, "truncation to %zu bytes", len);
        if (load_wo3(dir, orig, len, what, NULL) == 0) fail_msg("%s loaded", what);
    }
    /* so do trailing bytes */
    unsigned char *buf = fx_keep(calloc(n + 64, 1));
    memcpy(buf, orig, n);
    if (load_wo3(dir, buf, n + 16, "16 trailing bytes", NULL) == 0) fail_msg("a .wo3 with 16 trailing bytes loaded");

    /* header counts: nv at offset 0, nt at offset 8 + 32*4 = 136 */
    static const uint64_t nvs[] = {0, 1, 3, 4, 5, 6, 1ULL << 31, (1ULL << 32) + 4, (1ULL << 59) + 4, 1ULL << 63,
                                   UINT64_MAX};
    static const uint64_t nts[] = {0, 1, 2, 3, (1ULL << 32) + 2, (1ULL << 60) + 2, 1ULL << 62, UINT64_MAX};
    for (size_t a = 0; a < sizeof nvs / sizeof nvs[0]; a++)
        for (size_t b = 0; b < sizeof nts / sizeof nts[0]; b++) {
            memcpy(buf, orig, n);
            put_u64(buf, nvs[a]);
            put_u64(buf + 136, nts[b]);
            char what[128];
            snprintf(what, sizeof what, "header nv=%llu nt=%llu", (unsigned long long)nvs[a], (unsigned long long)nts[b]);
            int rc = load_wo3(dir, buf, n, what, NULL);
            /* with nv = 4 the size identity holds (in exact arithmetic) only for nt = 2 */
            if (nvs[a] == 4 && nts[b] != 2 && rc == 0) fail_msg("%s loaded", what);
            if (nvs[a] == 4 && nts[b] == 2 && rc != 0) fail_msg("%s (the original counts) refused", what);
        }
    /* triangle indices out of range (first triangle at offset 144: v0, v1, v2, material) */
    static const uint32_t bad_idx[] = {4, 5, 0x7fffffffu, 0xffffffffu};
    for (size_t i = 0; i < sizeof bad_idx / sizeof bad_idx[0]; i++)
        for (int corner = 0; corner < 3; corner++) {
            memcpy(buf, orig, n);
            put_u32(buf + 144 + 4 * corner, bad_idx[i]);
            char what[64];
            snprintf(what, sizeof what, "index %u in corner %d", bad_idx[i], corner);
            if (load_wo3(dir, buf, n, what, NULL) == 0) fail_msg("%s loaded", what);
        }
    /* the material field is not used as an index: any value loads */
    memcpy(buf, orig, n);
    put_u32(buf + 144 + 12, 12345);
    if (load_wo3(dir, buf, n, "material 12345", NULL)) fail_msg("a material id made the mesh fail");
    /* random byte mutations anywhere */
    lcg_state = 777;
    for (int i = 0; i < 300; i++) {
        memcpy(buf, orig, n);
        int k = 1 + (int)(lcg() % 6);
        for (int j = 0; j < k; j++) buf[lcg() % n] = (unsigned char)(lcg() & 0xff);
        load_wo3(dir, buf, n, "random mutation", NULL);
    }
    print_message("fuzz wo3: %.1f s\n", now_seconds() - t0);
}

#define T(f) cmocka_unit_test_teardown(f, teardown_fx)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_fuzz_scene_json),
        T(test_fuzz_wo3),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
