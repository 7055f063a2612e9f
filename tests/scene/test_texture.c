/* tier: quick */
/* Albedo textures, UVs and shading normals through the public API: files written by the test (an 8-texel
 * pattern as TGA, bottom-up and top-down, and as PNG; .obj meshes with vt/vn; a .wo3 with normals), then
 * scene_albedo and scene_intersect against values worked out by hand:
 * - texels follow Tungsten's 8-bit gamma table, floor(255 (c/255)^2.2) / 255 (io/ImageIO.cpp): 128 -> 55/255,
 *   21 -> 1/255, 20 -> 0, 64 -> 12/255, 200 -> 149/255, 250 -> 244/255 (sRGB would give 55.0, 1.9, 1.8, ...);
 * - the image's top row is v = 1 (textures/BitmapTexture.cpp reads row (1 - v)·h), texel centres at
 *   ((i + ½)/w, 1 − (r + ½)/h), bilinear in between, wrapping at every edge;
 * - shading normals: interpolated vertex normals of `smooth` meshes, transformed by the normal matrix and put
 *   on ng's side; `recompute_normals` splits vertices at cos(0.15π) (primitives/TriangleMesh.cpp);
 * - `backface_culling`: a ray from behind passes through, for scene_intersect and scene_transmittance. */
#include "fixtures.h"

#include <stb/stb_image_write.h>

#include "dartspp/scene.h"

/* A scene with the given bsdfs and primitives (JSON array items) and a camera; NULL with err on failure. */
static scene *load_scene(const char *bsdfs, const char *prims, dp_error *err)
{
    static const char fmt[] =
        "{\"bsdfs\": [%s],\n"
        " \"primitives\": [%s],\n"
        " \"camera\": {\"resolution\": [4, 4], \"fov\": 45,\n"
        "   \"transform\": {\"position\": [0, 0, -20], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}},\n"
        " \"integrator\": {\"type\": \"path_tracer\"}, \"renderer\": {\"spp\": 1}}\n";
    size_t len = strlen(fmt) + strlen(bsdfs) + strlen(prims) + 1;
    char *text = malloc(len);
    assert_non_null(text);
    snprintf(text, len, fmt, bsdfs, prims);
    scene *s = fx_load_text("scene.json", text, NULL, err);
    free(text);
    return s;
}

static scene *load_or_fail(const char *bsdfs, const char *prims)
{
    dp_error err;
    scene *s = load_scene(bsdfs, prims, &err);
    if (!s) fail_msg("scene_load failed: %s\nbsdfs: %s\nprimitives: %s", err.msg, bsdfs, prims);
    return s;
}

/* ---- the pattern: 4 x 2 texels, row 0 = the image's top row ---- */

#define TW 4
#define TH 2
static const unsigned char PATTERN[TH][TW][3] = {
    {{128, 21, 250}, {255, 0, 64}, {20, 200, 128}, {64, 250, 0}},
    {{0, 128, 255}, {250, 64, 21}, {200, 20, 0}, {21, 255, 200}},
};

/* Tungsten's gamma table at the values the pattern uses, worked out by hand: floor(255 (c/255)^2.2) */
static double lin(unsigned char c)
{
    switch (c) {
    case 0: return 0.0;
    case 20: return 0.0;
    case 21: return 1.0 / 255.0;
    case 64: return 12.0 / 255.0;
    case 128: return 55.0 / 255.0;
    case 200: return 149.0 / 255.0;
    case 250: return 244.0 / 255.0;
    case 255: return 1.0;
    }
    fail_msg("test bug: no hand value for %d", c);
    return 0;
}

static vec3 texel(int col, int row)
{
    const unsigned char *p = PATTERN[row][col];
    return v3(lin(p[0]), lin(p[1]), lin(p[2]));
}

/* Uncompressed 24-bit TGA (type 2, BGR); top_down sets descriptor bit 5 (rows stored top row first). */
static void write_tga(const char *name, int top_down)
{
    unsigned char buf[18 + TW * TH * 3];
    memset(buf, 0, 18);
    buf[2] = 2;
    buf[12] = TW;
    buf[14] = TH;
    buf[16] = 24;
    buf[17] = top_down ? 0x20 : 0x00;
    unsigned char *px = buf + 18;
    for (int k = 0; k < TH; k++) {
        int row = top_down ? k : TH - 1 - k;
        for (int x = 0; x < TW; x++, px += 3) {
            px[0] = PATTERN[row][x][2];
            px[1] = PATTERN[row][x][1];
            px[2] = PATTERN[row][x][0];
        }
    }
    write_in_dir(name, buf, sizeof buf);
}

static void write_png(const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", fx_dir(), name);
    if (!stbi_write_png(path, TW, TH, 3, PATTERN, TW * 3)) fail_msg("cannot write %s", path);
}

/* A unit quad in the xy-plane, front +z, with vt = (x, y): the UV at (x, y, 0) is (x, y). */
static const char QUAD_OBJ[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                               "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                               "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

static vec3 albedo_at(const scene *s, int b, double u, double v)
{
    hit_record h;
    memset(&h, 0, sizeof h);
    h.uv[0] = u;
    h.uv[1] = v;
    return scene_albedo(s, &s->bsdfs[b], &h);
}

#define ASSERT_ALBEDO(s, b, u, v, expect)                                                                           \
    do {                                                                                                           \
        vec3 e_ = (expect), a_ = albedo_at((s), (b), (u), (v));                                                    \
        if (!(fabs(a_.x - e_.x) < 1e-6 && fabs(a_.y - e_.y) < 1e-6 && fabs(a_.z - e_.z) < 1e-6))                  \
            fail_msg("%s:%d: bsdf %d at uv (%g, %g): (%.7f, %.7f, %.7f), expected (%.7f, %.7f, %.7f)", __FILE__,   \
                     __LINE__, (b), (double)(u), (double)(v), a_.x, a_.y, a_.z, e_.x, e_.y, e_.z);                \
    } while (0)

static vec3 avg2(vec3 a, vec3 b) { return v3_scale(v3_add(a, b), 0.5); }

/* three encodings of the pattern and a fourth reference to one of them */
static scene *load_pattern_scene(void)
{
    write_tga("bottom_up.tga", 0);
    write_tga("top_down.tga", 1);
    write_png("pattern.png");
    write_in_dir("quad.obj", QUAD_OBJ, strlen(QUAD_OBJ));
    return load_or_fail("{\"name\": \"a\", \"type\": \"lambert\", \"albedo\": \"bottom_up.tga\"},"
                        "{\"name\": \"b\", \"type\": \"lambert\", \"albedo\": \"top_down.tga\"},"
                        "{\"name\": \"c\", \"type\": \"lambert\", \"albedo\": \"pattern.png\"},"
                        "{\"name\": \"d\", \"type\": \"lambert\", \"albedo\": \"./bottom_up.tga\"}",
                        "{\"type\": \"mesh\", \"file\": \"quad.obj\", \"bsdf\": \"a\"}");
}

/* ---- textures ---- */

static void test_texel_centres(void **state)
{
    (void)state;
    scene *s = load_pattern_scene();
    assert_int_equal(s->bsdf_count, 4);
    assert_int_equal(s->texture_count, 3); /* ./bottom_up.tga is bottom_up.tga: decoded once */
    assert_int_equal(s->bsdfs[3].texture, s->bsdfs[0].texture);
    for (int b = 0; b < 3; b++) {
        assert_true(s->bsdfs[b].texture >= 0);
        assert_int_equal(s->textures[s->bsdfs[b].texture].width, TW);
        assert_int_equal(s->textures[s->bsdfs[b].texture].height, TH);
        for (int row = 0; row < TH; row++)
            for (int col = 0; col < TW; col++)
                ASSERT_ALBEDO(s, b, (col + 0.5) / TW, 1.0 - (row + 0.5) / TH, texel(col, row));
    }
    /* the constant albedo of a textured BSDF is the texture's mean */
    vec3 mean = v3s(0);
    for (int row = 0; row < TH; row++)
        for (int col = 0; col < TW; col++) mean = v3_add(mean, v3_scale(texel(col, row), 1.0 / (TW * TH)));
    ASSERT_VEC(s->bsdfs[0].albedo, mean.x, mean.y, mean.z, 1e-6);
}

static void test_bilinear_and_wrap(void **state)
{
    (void)state;
    scene *s = load_pattern_scene();
    for (int b = 0; b < 3; b++) {
        /* midpoints between horizontal and vertical neighbours, and the centre of four texels */
        ASSERT_ALBEDO(s, b, 0.25, 0.75, avg2(texel(0, 0), texel(1, 0)));
        ASSERT_ALBEDO(s, b, 0.625, 0.5, avg2(texel(2, 0), texel(2, 1)));
        ASSERT_ALBEDO(s, b, 0.5, 0.5, v3_scale(v3_add(avg2(texel(1, 0), texel(2, 0)), avg2(texel(1, 1), texel(2, 1))), 0.5));
        /* a quarter of the way from texel (0,0) to (1,0): weights 3/4, 1/4 */
        ASSERT_ALBEDO(s, b, 0.125 + 0.0625, 0.75, v3_add(v3_scale(texel(0, 0), 0.75), v3_scale(texel(1, 0), 0.25)));
        /* wrapping: u = 0 lies between the last and the first column, v = 1 between the top and bottom rows */
        ASSERT_ALBEDO(s, b, 0.0, 0.75, avg2(texel(3, 0), texel(0, 0)));
        ASSERT_ALBEDO(s, b, 0.375, 1.0, avg2(texel(1, 0), texel(1, 1)));
        ASSERT_ALBEDO(s, b, 0.375, 0.0, avg2(texel(1, 0), texel(1, 1)));
        /* whole periods in u and v, negative included, change nothing */
        ASSERT_ALBEDO(s, b, 1.125, 0.75, texel(0, 0));
        ASSERT_ALBEDO(s, b, -0.875, 0.75, texel(0, 0));
        ASSERT_ALBEDO(s, b, 0.875 + 7.0, 0.25 - 3.0, texel(3, 1));
    }
}

/* The quad's UVs reach scene_albedo through a real hit: ray from +z down onto (x, y, 0). */
static void test_mesh_uvs_in_hits(void **state)
{
    (void)state;
    scene *s = load_pattern_scene();
    static const double pts[][2] = {{0.125, 0.75}, {0.625, 0.25}, {0.3, 0.6}, {0.9, 0.1}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        hit_record h;
        if (!scene_intersect(s, v3(pts[i][0], pts[i][1], 5), v3(0, 0, -1), INFINITY, &h))
            fail_msg("no hit at (%g, %g)", pts[i][0], pts[i][1]);
        ASSERT_NEAR(h.uv[0], pts[i][0], 1e-5);
        ASSERT_NEAR(h.uv[1], pts[i][1], 1e-5);
        assert_true(h.tri < s->tri_count);
        ASSERT_VEC(h.ns, 0, 0, 1, 1e-9); /* not smooth: ns = ng */
        vec3 a = scene_albedo(s, &s->bsdfs[s->surfaces[h.surface].bsdf], &h), e = albedo_at(s, 0, pts[i][0], pts[i][1]);
        ASSERT_VEC(a, e.x, e.y, e.z, 1e-5);
    }
    hit_record h;
    assert_true(scene_intersect(s, v3(0.125, 0.75, 5), v3(0, 0, -1), INFINITY, &h));
    vec3 a = scene_albedo(s, &s->bsdfs[0], &h), e = texel(0, 0);
    ASSERT_VEC(a, e.x, e.y, e.z, 1e-5);
}

/* Quad and cube carry Tungsten's UVs; a mesh without vt has uv = 0. */
static void test_builtin_and_missing_uvs(void **state)
{
    (void)state;
    static const char no_vt[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    write_in_dir("novt.obj", no_vt, strlen(no_vt));
    scene *s = load_or_fail("{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}",
                            "{\"type\": \"mesh\", \"file\": \"novt.obj\", \"bsdf\": \"w\"},"
                            "{\"type\": \"quad\", \"bsdf\": \"w\", \"transform\": {\"position\": [10, 0, 0]}},"
                            "{\"type\": \"cube\", \"bsdf\": \"w\", \"transform\": {\"position\": [20, 0, 0]}}");
    hit_record h;
    assert_true(scene_intersect(s, v3(0.7, 0.2, 5), v3(0, 0, -1), INFINITY, &h));
    assert_true(h.uv[0] == 0.0 && h.uv[1] == 0.0);
    /* quad: u = x + 0.5, v = z + 0.5 (Tungsten's Quad: u along edge0 = x, v along edge1 = z) */
    assert_true(scene_intersect(s, v3(10 + 0.3, 5, -0.1), v3(0, -1, 0), INFINITY, &h));
    ASSERT_NEAR(h.uv[0], 0.8, 1e-6);
    ASSERT_NEAR(h.uv[1], 0.4, 1e-6);
    /* cube, +x face (d = 0): (u, v) = (y + 0.5, z + 0.5) */
    assert_true(scene_intersect(s, v3(25, 0.2, -0.3), v3(-1, 0, 0), INFINITY, &h));
    ASSERT_VEC(h.ng, 1, 0, 0, 1e-9);
    ASSERT_NEAR(h.uv[0], 0.7, 1e-6);
    ASSERT_NEAR(h.uv[1], 0.2, 1e-6);
    /* cube, -y face (d = 1): (u, v) = (z + 0.5, x + 0.5) */
    assert_true(scene_intersect(s, v3(20 - 0.1, -5, 0.25), v3(0, 1, 0), INFINITY, &h));
    ASSERT_VEC(h.ng, 0, -1, 0, 1e-9);
    ASSERT_NEAR(h.uv[0], 0.75, 1e-6);
    ASSERT_NEAR(h.uv[1], 0.4, 1e-6);
}

static void test_missing_texture(void **state)
{
    (void)state;
    scene *s = load_or_fail("{\"name\": \"gone\", \"type\": \"lambert\", \"albedo\": \"textures/nowhere.tga\"}",
                            "{\"type\": \"quad\", \"bsdf\": \"gone\"}");
    if (!s->notes || !strstr(s->notes, "nowhere.tga") || !strstr(s->notes, "not found") || !strstr(s->notes, "0.5"))
        fail_msg("expected a warning naming the file and the constant 0.5:\n%s", s->notes ? s->notes : "(none)");
    assert_int_equal(s->texture_count, 0);
    assert_int_equal(s->bsdfs[0].texture, -1);
    ASSERT_VEC(s->bsdfs[0].albedo, 0.5, 0.5, 0.5, 0.0);
    ASSERT_VEC(albedo_at(s, 0, 0.3, 0.3), 0.5, 0.5, 0.5, 0.0);
}

static void test_corrupt_texture(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        const char *bytes;
    } cases[] = {
        {"garbage.png", "this is not an image at all, only text"},
        {"garbage.tga", "\x01\x02\x03"},
        {"truncated.png", "\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        write_in_dir(cases[i].name, cases[i].bytes, strlen(cases[i].bytes) + (i == 2 ? 4 : 0));
        char bsdfs[256];
        snprintf(bsdfs, sizeof bsdfs, "{\"name\": \"bad\", \"type\": \"lambert\", \"albedo\": \"%s\"}", cases[i].name);
        dp_error err;
        scene *s = load_scene(bsdfs, "{\"type\": \"quad\", \"bsdf\": \"bad\"}", &err);
        if (s) fail_msg("%s loaded", cases[i].name);
        if (!strstr(err.msg, cases[i].name) || !strstr(err.msg, "bsdfs[0].albedo") || !strstr(err.msg, "scene.json") ||
            !strstr(err.msg, "decode"))
            fail_msg("%s: the message must name the scene, the key and the file: %s", cases[i].name, err.msg);
        print_message("%s: %s\n", cases[i].name, err.msg);
    }
}

/* Issue 32: stb_image reads zeros past the end of a file without failing, so a truncated or header-only
 * texture decoded as a mostly black image. Files cut byte by byte from the pattern's TGA (uncompressed and
 * RLE) and PNG must each be an error naming the scene, the key and the file; the whole files, and a whole
 * TGA followed by a TGA 2.0 footer, still load. */
static void test_truncated_texture(void **state)
{
    (void)state;
    write_tga("whole.tga", 0);
    write_png("whole.png");
    char path[1200];
    size_t tga_len, png_len;
    snprintf(path, sizeof path, "%s/whole.tga", fx_dir());
    unsigned char *tga = fx_keep(read_all(path, &tga_len));
    snprintf(path, sizeof path, "%s/whole.png", fx_dir());
    unsigned char *png = fx_keep(read_all(path, &png_len));
    assert_int_equal(tga_len, 18 + TW * TH * 3);
    /* an RLE TGA (type 10) of the pattern: one raw packet per row (0x80 | count - 1 repeats, count - 1 raw) */
    unsigned char rle[18 + TH * (1 + TW * 3)];
    memcpy(rle, tga, 18);
    rle[2] = 10;
    for (int r = 0; r < TH; r++) {
        rle[18 + r * (1 + TW * 3)] = TW - 1;
        memcpy(rle + 18 + r * (1 + TW * 3) + 1, tga + 18 + r * TW * 3, TW * 3);
    }
    static const char footer[] = "\0\0\0\0\0\0\0\0TRUEVISION-XFILE.";
    unsigned char tga_footer[sizeof rle + 64];
    memcpy(tga_footer, tga, tga_len);
    memcpy(tga_footer + tga_len, footer, sizeof footer); /* the 26-byte footer, its final 0 included */
    const struct {
        const char *name;
        const unsigned char *bytes;
        size_t len;
        int ok;
    } cases[] = {
        {"header_only.tga", tga, 18, 0},
        {"half.tga", tga, 18 + TW * TH * 3 / 2, 0},
        {"one_short.tga", tga, tga_len - 1, 0},
        {"header_only_rle.tga", rle, 18, 0},
        {"half_rle.tga", rle, 18 + (1 + TW * 3) + 3, 0},
        {"no_iend.png", png, png_len - 12, 0},
        {"half.png", png, png_len / 2, 0},
        {"whole_again.tga", tga, tga_len, 1},
        {"whole_rle.tga", rle, sizeof rle, 1},
        {"footer.tga", tga_footer, tga_len + sizeof footer, 1},
        {"whole_again.png", png, png_len, 1},
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        write_in_dir(cases[i].name, cases[i].bytes, cases[i].len);
        char bsdfs[256];
        snprintf(bsdfs, sizeof bsdfs, "{\"name\": \"t\", \"type\": \"lambert\", \"albedo\": \"%s\"}", cases[i].name);
        dp_error err;
        scene *s = load_scene(bsdfs, "{\"type\": \"quad\", \"bsdf\": \"t\"}", &err);
        if (s) {
            int same = s->texture_count == 1 && s->textures[0].width == TW && s->textures[0].height == TH;
            for (int k = 0; same && k < TH; k++)
                for (int x = 0; x < TW; x++) {
                    vec3 want = texel(x, k);
                    const float *got = &s->textures[0].rgb[3 * (k * TW + x)];
                    if (got[0] != (float)want.x || got[1] != (float)want.y || got[2] != (float)want.z) same = 0;
                }
            fx_drop(s);
            if (!cases[i].ok || !same) {
                print_message("%s (%zu bytes): loaded%s\n", cases[i].name, cases[i].len,
                              cases[i].ok ? " with texels other than the pattern's" : ", expected an error");
                failures++;
            }
        } else if (cases[i].ok) {
            print_message("%s (%zu bytes, whole): refused: %s\n", cases[i].name, cases[i].len, err.msg);
            failures++;
        } else if (!strstr(err.msg, cases[i].name) || !strstr(err.msg, "bsdfs[0].albedo") || !strstr(err.msg, "scene.json")) {
            print_message("%s: the message must name the scene, the key and the file: %s\n", cases[i].name, err.msg);
            failures++;
        } else print_message("%s (%zu bytes): %s\n", cases[i].name, cases[i].len, err.msg);
    }
    if (failures) fail_msg("%d of %zu texture files not handled as required", failures, sizeof cases / sizeof cases[0]);
}

/* ---- shading normals ---- */

/* One triangle (0,0,0), (1,0,0), (0,1,0) (ng = +z) with the given vertex normals. */
static void write_tri_obj(const char *name, vec3 n0, vec3 n1, vec3 n2)
{
    char text[512];
    snprintf(text, sizeof text, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn %.17g %.17g %.17g\nvn %.17g %.17g %.17g\n"
             "vn %.17g %.17g %.17g\nf 1//1 2//2 3//3\n", n0.x, n0.y, n0.z, n1.x, n1.y, n1.z, n2.x, n2.y, n2.z);
    write_in_dir(name, text, strlen(text));
}

static vec3 ns_at(const scene *s, vec3 o, vec3 d)
{
    hit_record h;
    if (!scene_intersect(s, o, d, INFINITY, &h)) fail_msg("no hit from (%g, %g, %g)", o.x, o.y, o.z);
    ASSERT_NEAR(v3_len(h.ns), 1.0, 1e-9);
    return h.ns;
}

static void test_smooth_normals(void **state)
{
    (void)state;
    const double r = sqrt(0.5);
    write_tri_obj("tri.obj", v3(0, 0, 1), v3(r, 0, r), v3(0, r, r));
    write_tri_obj("against.obj", v3(0.6, 0, -0.8), v3(0.6, 0, -0.8), v3(0.6, 0, -0.8));
    write_tri_obj("tilted.obj", v3(r, 0, r), v3(r, 0, r), v3(r, 0, r));
    scene *s = load_or_fail("{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}",
                            "{\"type\": \"mesh\", \"file\": \"tri.obj\", \"bsdf\": \"w\", \"smooth\": true},"
                            "{\"type\": \"mesh\", \"file\": \"tri.obj\", \"bsdf\": \"w\", \"smooth\": false,"
                            " \"transform\": {\"position\": [10, 0, 0]}},"
                            "{\"type\": \"mesh\", \"file\": \"against.obj\", \"bsdf\": \"w\", \"smooth\": true,"
                            " \"transform\": {\"position\": [20, 0, 0]}},"
                            "{\"type\": \"mesh\", \"file\": \"tilted.obj\", \"bsdf\": \"w\", \"smooth\": true,"
                            " \"transform\": {\"position\": [30, 0, 0], \"scale\": [2, 1, 1]}}");
    /* at barycentrics (u, v) = (0.25, 0.25), i.e. the point (0.25, 0.25, 0): normalise(0.5 n0 + 0.25 n1 + 0.25 n2) */
    vec3 e = v3_norm(v3(0.25 * r, 0.25 * r, 0.5 + 0.5 * r));
    vec3 n = ns_at(s, v3(0.25, 0.25, 5), v3(0, 0, -1));
    ASSERT_VEC(n, e.x, e.y, e.z, 1e-6);
    /* from behind the same point: ns does not depend on the side the ray comes from */
    n = ns_at(s, v3(0.25, 0.25, -5), v3(0, 0, 1));
    ASSERT_VEC(n, e.x, e.y, e.z, 1e-6);
    /* at (0.6, 0.1): normalise(0.3 n0 + 0.6 n1 + 0.1 n2) */
    e = v3_norm(v3(0.6 * r, 0.1 * r, 0.3 + 0.7 * r));
    n = ns_at(s, v3(0.6, 0.1, 5), v3(0, 0, -1));
    ASSERT_VEC(n, e.x, e.y, e.z, 1e-6);
    /* smooth: false ignores the vertex normals */
    n = ns_at(s, v3(10.25, 0.25, 5), v3(0, 0, -1));
    ASSERT_VEC(n, 0, 0, 1, 1e-12);
    /* vertex normals against ng are flipped to its side */
    n = ns_at(s, v3(20.25, 0.25, 5), v3(0, 0, -1));
    ASSERT_VEC(n, -0.6, 0, 0.8, 1e-6);
    /* scale [2, 1, 1]: the normal matrix diag(1/2, 1, 1) takes (1, 0, 1) to (1/2, 0, 1) (a plain vector
     * transform would give (2, 0, 1)) */
    e = v3_norm(v3(0.5, 0, 1));
    n = ns_at(s, v3(30.5, 0.25, 5), v3(0, 0, -1));
    ASSERT_VEC(n, e.x, e.y, e.z, 1e-6);
}

/* .wo3 normals (bytes 12..23 of each vertex) reach the hit record of a smooth mesh. */
static void test_wo3_normals(void **state)
{
    (void)state;
    unsigned char buf[16 + 3 * 32 + 16];
    memset(buf, 0, sizeof buf);
    put_u64(buf, 3);
    static const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const float nn[3][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, 0.6f, 0.8f}};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            put_f32(buf + 8 + 32 * i + 4 * k, p[i][k]);
            put_f32(buf + 8 + 32 * i + 12 + 4 * k, nn[i][k]);
        }
    put_f32(buf + 8 + 32 * 1 + 24, 1.0f); /* uv of vertex 1 = (1, 0), vertex 2 = (0, 1) */
    put_f32(buf + 8 + 32 * 2 + 28, 1.0f);
    put_u64(buf + 8 + 96, 1);
    put_u32(buf + 16 + 96, 0);
    put_u32(buf + 16 + 96 + 4, 1);
    put_u32(buf + 16 + 96 + 8, 2);
    put_u32(buf + 16 + 96 + 12, 0xffffffffu);
    write_in_dir("tri.wo3", buf, sizeof buf);
    scene *s = load_or_fail("{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}",
                            "{\"type\": \"mesh\", \"file\": \"tri.wo3\", \"bsdf\": \"w\", \"smooth\": true}");
    hit_record h;
    assert_true(scene_intersect(s, v3(0.2, 0.5, 5), v3(0, 0, -1), INFINITY, &h));
    vec3 e = v3_norm(v3(0.2 * 0.6, 0.5 * 0.6, 0.3 + 0.7 * 0.8));
    ASSERT_VEC(h.ns, e.x, e.y, e.z, 1e-6);
    ASSERT_NEAR(h.uv[0], 0.2, 1e-6);
    ASSERT_NEAR(h.uv[1], 0.5, 1e-6);
}

/* Two triangles of area 1/2 hinged on the x-axis: A = (0,0,0), (1,0,0), (0.5,1,0) with normal +z and
 * B = (1,0,0), (0,0,0), (0.5,-cos θ, sin θ) with normal (0, sin θ, cos θ). The file's own normals are
 * nonsense (+x) so that only recomputed normals can pass. */
static void write_hinge(const char *name, double theta_deg)
{
    double t = theta_deg * M_PI / 180.0;
    char text[512];
    snprintf(text, sizeof text, "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 %.17g %.17g\nvn 1 0 0\n"
             "f 1//1 2//1 3//1\nf 2//1 1//1 4//1\n", -cos(t), sin(t));
    write_in_dir(name, text, strlen(text));
}

static void test_recompute_normals_split(void **state)
{
    (void)state;
    write_hinge("h26.obj", 26.0);
    write_hinge("h28.obj", 28.0);
    scene *s = load_or_fail("{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}",
                            "{\"type\": \"mesh\", \"file\": \"h26.obj\", \"bsdf\": \"w\", \"smooth\": true,"
                            " \"recompute_normals\": true},"
                            "{\"type\": \"mesh\", \"file\": \"h28.obj\", \"bsdf\": \"w\", \"smooth\": true,"
                            " \"recompute_normals\": true, \"transform\": {\"position\": [10, 0, 0]}},"
                            "{\"type\": \"mesh\", \"file\": \"h26.obj\", \"bsdf\": \"w\", \"smooth\": true,"
                            " \"transform\": {\"position\": [20, 0, 0]}}");
    /* the point (0.5, 0.1, 0) of A: barycentrics 0.45, 0.45, 0.1 */
    /* 26° < 27°: the shared vertices take the bisector (0, sin 13°, cos 13°), the apex of A +z */
    double h = 13.0 * M_PI / 180.0;
    vec3 e = v3_norm(v3_add(v3_scale(v3(0, sin(h), cos(h)), 0.9), v3(0, 0, 0.1)));
    vec3 n = ns_at(s, v3(0.5, 0.1, 5), v3(0, 0, -1));
    ASSERT_VEC(n, e.x, e.y, e.z, 1e-6);
    /* 28° > 27°: split, each face keeps its own normal */
    n = ns_at(s, v3(10.5, 0.1, 5), v3(0, 0, -1));
    ASSERT_VEC(n, 0, 0, 1, 1e-6);
    double t = 28.0 * M_PI / 180.0;
    vec3 nb = v3(0, sin(t), cos(t)), q = v3(10.5, -0.5 * cos(t), 0.5 * sin(t)); /* midpoint of B's height */
    n = ns_at(s, v3_add(q, v3_scale(nb, 5)), v3_neg(nb));
    ASSERT_VEC(n, nb.x, nb.y, nb.z, 1e-6);
    /* without recompute_normals, the file's (+x, perpendicular to ng) normals are used as they are */
    n = ns_at(s, v3(20.5, 0.1, 5), v3(0, 0, -1));
    ASSERT_VEC(n, 1, 0, 0, 1e-6);
}

/* ---- back-face culling ---- */

static void test_backface_culling(void **state)
{
    (void)state;
    static const char quad[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"; /* front +z */
    write_in_dir("quad.obj", quad, strlen(quad));
    scene *s = load_or_fail("{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}",
                            "{\"type\": \"mesh\", \"file\": \"quad.obj\", \"bsdf\": \"w\", \"backface_culling\": true},"
                            "{\"type\": \"mesh\", \"file\": \"quad.obj\", \"bsdf\": \"w\","
                            " \"transform\": {\"position\": [1, 0, 10], \"rotation\": [0, 180, 0]}},"
                            "{\"type\": \"mesh\", \"file\": \"quad.obj\", \"bsdf\": \"w\", \"backface_culling\": false,"
                            " \"transform\": {\"position\": [5, 0, 0]}}");
    hit_record h;
    /* from the front (+z, d·ng < 0): hit */
    assert_true(scene_intersect(s, v3(0.5, 0.5, 5), v3(0, 0, -1), INFINITY, &h));
    assert_int_equal(h.surface, 0);
    ASSERT_NEAR(h.t, 5.0, 1e-5);
    /* from behind: passes through the culled quad to the far one at z = 10 */
    assert_true(scene_intersect(s, v3(0.5, 0.5, -5), v3(0, 0, 1), INFINITY, &h));
    assert_int_equal(h.surface, 1);
    ASSERT_NEAR(h.t, 15.0, 1e-5);
    /* the far quad (rotated to face -z, not culled) is hit from its back too */
    assert_true(scene_intersect(s, v3(0.5, 0.5, 20), v3(0, 0, -1), INFINITY, &h));
    assert_int_equal(h.surface, 1);
    /* the same quad without culling is hit from behind */
    assert_true(scene_intersect(s, v3(5.5, 0.5, -5), v3(0, 0, 1), 8.0, &h));
    assert_int_equal(h.surface, 2);
    /* transmittance: blocked from the front, free from behind */
    vec3 tr;
    double time = 0;
    assert_int_equal(scene_transmittance(s, v3(0.5, 0.5, 3), MEDIUM_VACUUM, v3(0.5, 0.5, -3), &tr, &time), 0);
    time = 0;
    assert_int_equal(scene_transmittance(s, v3(0.5, 0.5, -3), MEDIUM_VACUUM, v3(0.5, 0.5, 3), &tr, &time), 1);
    ASSERT_VEC(tr, 1, 1, 1, 0.0);
    ASSERT_NEAR(time, 6.0, 1e-9);
}

#define T(f) cmocka_unit_test_teardown(f, teardown_fx)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_texel_centres),
        T(test_bilinear_and_wrap),
        T(test_mesh_uvs_in_hits),
        T(test_builtin_and_missing_uvs),
        T(test_missing_texture),
        T(test_corrupt_texture),
        T(test_truncated_texture),
        T(test_smooth_normals),
        T(test_wo3_normals),
        T(test_recompute_normals_split),
        T(test_backface_culling),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
