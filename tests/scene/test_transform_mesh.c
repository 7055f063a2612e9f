/* tier: quick */
/* Transforms and meshes through the public API: small scenes written to a temp folder, then s.verts,
 * s.tris and s.surfaces inspected. Expected positions and normals are worked out by hand from
 * docs/scene-format.md §1 (.wo3), §2.2 (transform) and §2.5 (quad, cube) and Tungsten's Mat4f::rotYXZ. */
#include "fixtures.h"

#include "dartspp/scene.h"

#include <math.h>

#define POS_TOL 1e-5 /* vertices are stored as float */

/* A scene with the given primitives (JSON array items), a lambert BSDF "w" and a camera on -z looking +z.
 * Returns the loaded scene, or NULL with err filled. */
static scene *load_prims(const char *prims, dp_error *err)
{
    static const char fmt[] =
        "{\"bsdfs\": [{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}],\n"
        " \"primitives\": [%s],\n"
        " \"camera\": {\"resolution\": [4, 4], \"fov\": 45,\n"
        "   \"transform\": {\"position\": [0, 0, -20], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}},\n"
        " \"integrator\": {\"type\": \"path_tracer\"}, \"renderer\": {\"spp\": 1}}\n";
    size_t len = strlen(fmt) + strlen(prims) + 1;
    char *text = malloc(len);
    assert_non_null(text);
    snprintf(text, len, fmt, prims);
    scene *s = fx_load_text("scene.json", text, NULL, err);
    free(text);
    return s;
}

static scene *load_prims_or_fail(const char *prims)
{
    dp_error err;
    scene *s = load_prims(prims, &err);
    if (!s) fail_msg("scene_load failed: %s\nprimitives: %s", err.msg, prims);
    return s;
}

/* ---- geometry helpers ---- */

static vec3 vtx(const scene *s, uint32_t i)
{
    assert_true(i < s->vert_count);
    return v3(s->verts[3 * (size_t)i], s->verts[3 * (size_t)i + 1], s->verts[3 * (size_t)i + 2]);
}

/* corner k (0..2) of triangle t of surface sf */
static vec3 corner(const scene *s, int sf, uint32_t t, int k)
{
    const surface *S = &s->surfaces[sf];
    assert_true(t < S->tri_count);
    assert_true(S->first_tri + t < s->tri_count);
    return vtx(s, s->tris[3 * (size_t)(S->first_tri + t) + k]);
}

static vec3 tri_normal(const scene *s, int sf, uint32_t t)
{
    vec3 p0 = corner(s, sf, t, 0), p1 = corner(s, sf, t, 1), p2 = corner(s, sf, t, 2);
    return v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
}

static int near3(vec3 a, vec3 b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol && fabs(a.z - b.z) <= tol;
}

/* Every triangle corner of surface sf is one of the expected points, and every expected point is used. */
static void assert_corners_are(const scene *s, int sf, const vec3 *pts, int npts)
{
    int used[16] = {0};
    assert_true(npts <= 16);
    const surface *S = &s->surfaces[sf];
    for (uint32_t t = 0; t < S->tri_count; t++)
        for (int k = 0; k < 3; k++) {
            vec3 p = corner(s, sf, t, k);
            int found = 0;
            for (int i = 0; i < npts; i++)
                if (near3(p, pts[i], POS_TOL)) {
                    used[i] = 1;
                    found = 1;
                }
            if (!found) fail_msg("triangle %u corner %d at (%g, %g, %g) is not an expected vertex", t, k, p.x, p.y, p.z);
        }
    for (int i = 0; i < npts; i++)
        if (!used[i]) fail_msg("expected vertex (%g, %g, %g) is not used by any triangle", pts[i].x, pts[i].y, pts[i].z);
}

/* every triangle of surface sf has unit normal n (within tol) */
static void assert_normals(const scene *s, int sf, vec3 n, double tol)
{
    for (uint32_t t = 0; t < s->surfaces[sf].tri_count; t++) {
        vec3 m = v3_norm(tri_normal(s, sf, t));
        if (!near3(m, n, tol))
            fail_msg("triangle %u normal (%g, %g, %g), expected (%g, %g, %g)", t, m.x, m.y, m.z, n.x, n.y, n.z);
    }
}

/* ---- quad ---- */

static void test_quad_position_scale(void **state)
{
    (void)state;
    const scene *s = load_prims_or_fail(
        "{\"type\": \"quad\", \"transform\": {\"position\": [1, 2, 3], \"scale\": [2, 1, 4]}, \"bsdf\": \"w\"}");
    assert_int_equal(s->surface_count, 1);
    assert_int_equal(s->surfaces[0].tri_count, 2);
    assert_int_equal(s->tri_count, 2);
    /* edge0 = T(1,0,0) = (2,0,0), edge1 = T(0,0,1) = (0,0,4), centred on (1,2,3) */
    const vec3 pts[4] = {{0, 2, 1}, {0, 2, 5}, {2, 2, 1}, {2, 2, 5}};
    assert_corners_are(s, 0, pts, 4);
    /* normal +y (edge1 x edge0 = (0,8,0)); each triangle is half of the 2 x 4 quad */
    assert_normals(s, 0, v3(0, 1, 0), 1e-6);
    for (uint32_t t = 0; t < 2; t++) ASSERT_NEAR(0.5 * v3_len(tri_normal(s, 0, t)), 4.0, 1e-5);
}

static void test_quad_rotation_x180(void **state)
{
    (void)state;
    const scene *s = load_prims_or_fail("{\"type\": \"quad\", \"transform\": {\"position\": [1, 2, 3], "
                                        "\"scale\": [2, 1, 4], \"rotation\": [180, 0, 0]}, \"bsdf\": \"w\"}");
    /* Rx(180): y -> -y, z -> -z; the corner set is symmetric so it is unchanged, the normal flips */
    const vec3 pts[4] = {{0, 2, 1}, {0, 2, 5}, {2, 2, 1}, {2, 2, 5}};
    assert_corners_are(s, 0, pts, 4);
    assert_normals(s, 0, v3(0, -1, 0), 1e-6);
}

/* ---- rotation convention: Tungsten Mat4f::rotYXZ (docs/scene-format.md §2.2 step 4) ---- */

/* Tungsten's matrix, row-major, written out from Mat4f::rotYXZ (math/Mat4f.cpp). */
static vec3 tungsten_rot_yxz(vec3 deg, vec3 v)
{
    double rx = deg.x * M_PI / 180, ry = deg.y * M_PI / 180, rz = deg.z * M_PI / 180;
    double c0 = cos(rx), c1 = cos(ry), c2 = cos(rz), s0 = sin(rx), s1 = sin(ry), s2 = sin(rz);
    double m[3][3] = {{c1 * c2 - s1 * s0 * s2, -c1 * s2 - s1 * s0 * c2, -s1 * c0},
                      {c0 * s2, c0 * c2, -s0},
                      {s1 * c2 + c1 * s0 * s2, -s1 * s2 + c1 * s0 * c2, c1 * c0}};
    return v3(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
              m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z);
}

/* A corner tetrahedron: O, X, Y, Z with three faces, each a single triangle. */
static const char TETRA_OBJ[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\n";
static const int TETRA_FACES[3][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}};

/* Checks that each triangle of surface sf is the image of its tetrahedron face under map(), corner for
 * corner up to a cyclic rotation (which keeps the orientation). Returns the number of mismatches. */
static int check_tetra(const scene *s, int sf, vec3 (*map)(const void *, vec3), const void *ctx, const char *what)
{
    static const vec3 local[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (s->surfaces[sf].tri_count != 3) {
        print_message("[%s] %u triangles, expected 3\n", what, s->surfaces[sf].tri_count);
        return 1;
    }
    int bad = 0;
    for (uint32_t t = 0; t < 3; t++) {
        vec3 want[3], got[3];
        for (int k = 0; k < 3; k++) {
            want[k] = map(ctx, local[TETRA_FACES[t][k]]);
            got[k] = corner(s, sf, t, k);
        }
        int match = 0;
        for (int r = 0; r < 3 && !match; r++)
            match = near3(got[0], want[r], POS_TOL) && near3(got[1], want[(r + 1) % 3], POS_TOL) &&
                    near3(got[2], want[(r + 2) % 3], POS_TOL);
        if (!match) {
            bad++;
            print_message("[%s] triangle %u: (%g,%g,%g) (%g,%g,%g) (%g,%g,%g), expected (%g,%g,%g) (%g,%g,%g) "
                          "(%g,%g,%g)\n",
                          what, t, got[0].x, got[0].y, got[0].z, got[1].x, got[1].y, got[1].z, got[2].x, got[2].y,
                          got[2].z, want[0].x, want[0].y, want[0].z, want[1].x, want[1].y, want[1].z, want[2].x,
                          want[2].y, want[2].z);
        }
    }
    return bad;
}

typedef struct {
    vec3 deg, pos;
} rot_ctx;

static vec3 map_rot(const void *ctx, vec3 p)
{
    const rot_ctx *c = ctx;
    return v3_add(c->pos, tungsten_rot_yxz(c->deg, p));
}

static void test_rotation_matches_tungsten(void **state)
{
    (void)state;
    write_in_dir("tetra.obj", TETRA_OBJ, strlen(TETRA_OBJ));
    /* pure X and Z rotations agree with the textbook right-handed ones; Tungsten's Y block is
     * [c 0 -s; 0 1 0; s 0 c], so rotation [0,90,0] takes local +x to +z and local +z to -x */
    static const double rots[][3] = {{90, 0, 0}, {0, 0, 90}, {90, 0, 90}, {0, 90, 0}, {0, -30, 0}, {30, 45, 60}};
    int failures = 0;
    for (size_t i = 0; i < sizeof rots / sizeof rots[0]; i++) {
        char prims[512], what[64];
        snprintf(prims, sizeof prims,
                 "{\"type\": \"mesh\", \"file\": \"tetra.obj\", \"bsdf\": \"w\", "
                 "\"transform\": {\"position\": [1, 2, 3], \"rotation\": [%g, %g, %g]}}",
                 rots[i][0], rots[i][1], rots[i][2]);
        snprintf(what, sizeof what, "rotation [%g, %g, %g]", rots[i][0], rots[i][1], rots[i][2]);
        scene *s = load_prims_or_fail(prims);
        rot_ctx c = {v3(rots[i][0], rots[i][1], rots[i][2]), v3(1, 2, 3)};
        failures += check_tetra(s, 0, map_rot, &c, what) ? 1 : 0;
        scene_free(s);
        fx.live[s - fx.scenes] = 0;
    }
    /* spot check of the hand-written matrix itself: [0,90,0] maps (1,0,0) to (0,0,1) */
    ASSERT_VEC(tungsten_rot_yxz(v3(0, 90, 0), v3(1, 0, 0)), 0, 0, 1, 1e-12);
    if (failures) fail_msg("%d of %zu rotations differ from Tungsten's rotYXZ", failures, sizeof rots / sizeof rots[0]);
}

/* ---- degenerate default axes (Tungsten's Gram-Schmidt fallback) ---- */

typedef struct {
    vec3 x, y, z, pos;
} basis_ctx;

static vec3 map_basis(const void *ctx, vec3 p)
{
    const basis_ctx *b = ctx;
    return v3_add(b->pos, v3_add(v3_scale(b->x, p.x), v3_add(v3_scale(b->y, p.y), v3_scale(b->z, p.z))));
}

static void test_degenerate_default_axes(void **state)
{
    (void)state;
    write_in_dir("tetra.obj", TETRA_OBJ, strlen(TETRA_OBJ));
    int failures = 0;
    dp_error err;
    /* "up": [0,0,1] alone (case 2: gramSchmidt(y, z, x)): z = (0,0,1) collapses onto y, Tungsten takes
     * randomOrtho(y) = y x (1,0,0) = (0,1,0); x = (1,0,0) stays; x cross y . z = (0,-1,0).(0,1,0) < 0 flips
     * the non-explicit x: basis x = (-1,0,0), y = (0,0,1), z = (0,1,0) (det +1). */
    scene *s = load_prims(
        "{\"type\": \"mesh\", \"file\": \"tetra.obj\", \"bsdf\": \"w\", \"transform\": {\"up\": [0, 0, 1]}}", &err);
    if (!s) {
        print_message("[up (0,0,1)] refused: %s\n", err.msg);
        failures++;
    } else {
        basis_ctx b = {v3(-1, 0, 0), v3(0, 0, 1), v3(0, 1, 0), v3(0, 0, 0)};
        failures += check_tetra(s, 0, map_basis, &b, "up (0,0,1)") ? 1 : 0;
    }
    /* "look_at": [1,0,0] from the origin (case 4: gramSchmidt(z, y, x)): x = (1,0,0) collapses onto z,
     * Tungsten takes z x y = (0,0,1); x cross y . z = (-1,0,0).(1,0,0) < 0 flips it: x = (0,0,-1),
     * y = (0,1,0), z = (1,0,0). */
    s = load_prims(
        "{\"type\": \"mesh\", \"file\": \"tetra.obj\", \"bsdf\": \"w\", \"transform\": {\"look_at\": [1, 0, 0]}}", &err);
    if (!s) {
        print_message("[look_at (1,0,0)] refused: %s\n", err.msg);
        failures++;
    } else {
        basis_ctx b = {v3(0, 0, -1), v3(0, 1, 0), v3(1, 0, 0), v3(0, 0, 0)};
        failures += check_tetra(s, 0, map_basis, &b, "look_at (1,0,0)") ? 1 : 0;
    }
    /* a quad facing +z through "up": corners (+-0.5, +-0.5, 0), normal T(0,1,0) = +z */
    s = load_prims("{\"type\": \"quad\", \"bsdf\": \"w\", \"transform\": {\"position\": [0, 0, 5], \"up\": [0, 0, 1]}}",
                   &err);
    if (!s) {
        print_message("[quad up (0,0,1)] refused: %s\n", err.msg);
        failures++;
    } else {
        /* quad corners (+-0.5, +-0.5, 5) and normal +z: the two triangles are the images of local
         * (-.5,0,-.5), (-.5,0,.5), (.5,0,-.5), (.5,0,.5) under x -> (-1,0,0), z -> (0,1,0) */
        for (uint32_t t = 0; t < s->surfaces[0].tri_count; t++) {
            vec3 n = tri_normal(s, 0, t);
            int ok = v3_len(n) > 0 && near3(v3_norm(n), v3(0, 0, 1), 1e-6);
            for (int k = 0; k < 3; k++) {
                vec3 p = corner(s, 0, t, k);
                ok = ok && fabs(fabs(p.x) - 0.5) < POS_TOL && fabs(fabs(p.y) - 0.5) < POS_TOL && fabs(p.z - 5) < POS_TOL;
            }
            if (!ok) {
                print_message("[quad up (0,0,1)] triangle %u: (%g,%g,%g) (%g,%g,%g) (%g,%g,%g), expected corners "
                              "(+-0.5, +-0.5, 5) and normal +z\n",
                              t, corner(s, 0, t, 0).x, corner(s, 0, t, 0).y, corner(s, 0, t, 0).z, corner(s, 0, t, 1).x,
                              corner(s, 0, t, 1).y, corner(s, 0, t, 1).z, corner(s, 0, t, 2).x, corner(s, 0, t, 2).y,
                              corner(s, 0, t, 2).z);
                failures++;
                break;
            }
        }
    }
    if (failures) fail_msg("%d transforms with a collapsing default axis were refused or misplaced", failures);
}

/* ---- cube ---- */

static void check_cube_outward(const scene *s, int sf, vec3 center)
{
    assert_int_equal(s->surfaces[sf].tri_count, 12);
    for (uint32_t t = 0; t < 12; t++) {
        vec3 c = v3_scale(v3_add(corner(s, sf, t, 0), v3_add(corner(s, sf, t, 1), corner(s, sf, t, 2))), 1.0 / 3.0);
        vec3 n = tri_normal(s, sf, t);
        if (!(v3_len(n) > 0)) fail_msg("cube triangle %u is degenerate", t);
        if (!(v3_dot(n, v3_sub(c, center)) > 0))
            fail_msg("cube triangle %u normal (%g, %g, %g) points inward (centroid (%g, %g, %g))", t, n.x, n.y, n.z, c.x,
                     c.y, c.z);
    }
}

static void test_cube(void **state)
{
    (void)state;
    const scene *s = load_prims_or_fail(
        "{\"type\": \"quad\", \"bsdf\": \"w\"},"
        "{\"type\": \"cube\", \"transform\": {\"position\": [1, 2, 3], \"scale\": [2, 3, 4]}, \"bsdf\": \"w\"},"
        "{\"type\": \"cube\", \"transform\": {\"position\": [-5, 1, 0], \"rotation\": [30, 45, 60]}, \"bsdf\": \"w\"}");
    assert_int_equal(s->surface_count, 3);
    assert_int_equal(s->tri_count, 2 + 12 + 12);
    /* the surfaces partition the triangle list in file order */
    assert_int_equal(s->surfaces[0].first_tri, 0);
    assert_int_equal(s->surfaces[1].first_tri, 2);
    assert_int_equal(s->surfaces[2].first_tri, 14);
    for (size_t i = 0; i < 3 * (size_t)s->tri_count; i++) assert_true(s->tris[i] < s->vert_count);
    /* [-0.5,0.5]^3 scaled by (2,3,4) around (1,2,3): x in [0,2], y in [0.5,3.5], z in [1,5] */
    const vec3 box[8] = {{0, 0.5, 1}, {2, 0.5, 1}, {0, 3.5, 1}, {2, 3.5, 1},
                         {0, 0.5, 5}, {2, 0.5, 5}, {0, 3.5, 5}, {2, 3.5, 5}};
    assert_corners_are(s, 1, box, 8);
    check_cube_outward(s, 1, v3(1, 2, 3));
    /* surface area 2(2*3 + 2*4 + 3*4) = 52 */
    double area = 0;
    for (uint32_t t = 0; t < 12; t++) area += 0.5 * v3_len(tri_normal(s, 1, t));
    ASSERT_NEAR(area, 52.0, 1e-4);
    /* any rotation keeps the normals outward; the corners stay at distance sqrt(3)/2 from the centre */
    check_cube_outward(s, 2, v3(-5, 1, 0));
    for (uint32_t t = 0; t < 12; t++)
        for (int k = 0; k < 3; k++) ASSERT_NEAR(v3_len(v3_sub(corner(s, 2, t, k), v3(-5, 1, 0))), sqrt(0.75), 1e-5);
}

/* ---- 16-float matrix ---- */

static void test_matrix16(void **state)
{
    (void)state;
    write_in_dir("tetra.obj", TETRA_OBJ, strlen(TETRA_OBJ));
    /* row-major: elements [3], [7], [11] are the translation; diag (2,1,3) scales the quad to 2 x 3 */
    const scene *s = load_prims_or_fail(
        "{\"type\": \"quad\", \"bsdf\": \"w\", \"transform\": [2, 0, 0, 5,  0, 1, 0, -2,  0, 0, 3, 7,  0, 0, 0, 1]},"
        "{\"type\": \"mesh\", \"file\": \"tetra.obj\", \"bsdf\": \"w\","
        " \"transform\": [0, 0, 1, 10,  0, 1, 0, 20,  -1, 0, 0, 30,  0, 0, 0, 1]}");
    const vec3 pts[4] = {{4, -2, 5.5}, {4, -2, 8.5}, {6, -2, 5.5}, {6, -2, 8.5}};
    assert_corners_are(s, 0, pts, 4);
    assert_normals(s, 0, v3(0, 1, 0), 1e-6);
    /* rows (0,0,1), (0,1,0), (-1,0,0): M (1,0,0) = column 0 = (0,0,-1), M (0,0,1) = column 2 = (1,0,0) */
    basis_ctx b = {v3(0, 0, -1), v3(0, 1, 0), v3(1, 0, 0), v3(10, 20, 30)};
    if (check_tetra(s, 1, map_basis, &b, "row-major matrix")) fail_msg("the 16-float matrix is not read row-major");
}

/* ---- .wo3 written by hand ---- */

static void test_wo3_handwritten(void **state)
{
    (void)state;
    /* docs/scene-format.md §1: u64 nv | nv × (pos[3], normal[3], uv[2]) f32 | u64 nt | nt × (v0, v1, v2, material) */
    static const float P[4][3] = {{0, 0, 0}, {0, 0, 2}, {3, 0, 0}, {3, 0, 2}};
    static const uint32_t T[2][3] = {{0, 1, 2}, {1, 3, 2}};
    unsigned char buf[16 + 4 * 32 + 2 * 16];
    memset(buf, 0, sizeof buf);
    put_u64(buf, 4);
    for (int i = 0; i < 4; i++) {
        unsigned char *v = buf + 8 + 32 * i;
        for (int k = 0; k < 3; k++) put_f32(v + 4 * k, P[i][k]);
        put_f32(v + 16, 1.0f); /* normal (0,1,0) */
        put_f32(v + 24, 0.25f * (float)i);
    }
    put_u64(buf + 8 + 4 * 32, 2);
    for (int t = 0; t < 2; t++) {
        unsigned char *r = buf + 16 + 4 * 32 + 16 * t;
        for (int k = 0; k < 3; k++) put_u32(r + 4 * k, T[t][k]);
        put_u32(r + 12, 0xffffffffu); /* material -1 */
    }
    assert_int_equal(sizeof buf, 176);
    write_in_dir("two.wo3", buf, sizeof buf);
    const scene *s = load_prims_or_fail(
        "{\"type\": \"mesh\", \"file\": \"two.wo3\", \"bsdf\": \"w\", \"transform\": {\"position\": [10, 0, -1]}}");
    assert_int_equal(s->surfaces[0].tri_count, 2);
    assert_int_equal(s->tri_count, 2);
    /* corners in file order, translated by (10,0,-1) */
    for (int t = 0; t < 2; t++)
        for (int k = 0; k < 3; k++) {
            const float *p = P[T[t][k]];
            ASSERT_VEC(corner(s, 0, (uint32_t)t, k), p[0] + 10.0, p[1], p[2] - 1.0, POS_TOL);
        }
    /* (p1-p0) x (p2-p0) = (0,0,2) x (3,0,0) = (0,6,0): +y, and the same for (1,3,2) */
    assert_normals(s, 0, v3(0, 1, 0), 1e-6);
}

/* ---- .obj ---- */

static void test_obj_faces(void **state)
{
    (void)state;
    static const char *const objs[] = {
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        "# with uvs and normals\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
        "f 1/1/1 2/2/1 3/3/1 4/4/1\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 4/1\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf -4/-1/-1 -3/-1/-1 -2/-1/-1 -1/-1/-1\n",
        "o quad\ng g1\nusemtl m\ns off\nv 0 0 0\nv 1 0 0\r\nv 1 1 0\nv 0 1 0\nf\t1 2 3\nf 1 3 4\n",
        /* negative indices are relative to the vertices read so far, not to the whole file */
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\nv 7 7 7\nv 8 8 8\n",
    };
    const vec3 quad[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    int failures = 0;
    for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
        char name[32], prims[256];
        snprintf(name, sizeof name, "q%zu.obj", i);
        write_in_dir(name, objs[i], strlen(objs[i]));
        snprintf(prims, sizeof prims,
                 "{\"type\": \"mesh\", \"file\": \"%s\", \"bsdf\": \"w\", \"transform\": {\"position\": [0, 0, 2]}}", name);
        dp_error err;
        scene *s = load_prims(prims, &err);
        if (!s) {
            print_message("[obj %zu] refused: %s\n", i, err.msg);
            failures++;
            continue;
        }
        const vec3 pts[4] = {v3_add(quad[0], v3(0, 0, 2)), v3_add(quad[1], v3(0, 0, 2)), v3_add(quad[2], v3(0, 0, 2)),
                             v3_add(quad[3], v3(0, 0, 2))};
        if (s->surfaces[0].tri_count != 2) {
            print_message("[obj %zu] %u triangles, expected 2\n", i, s->surfaces[0].tri_count);
            failures++;
        } else {
            /* two triangles of area 1/2 each, counter-clockwise seen from +z, over the 4 corners */
            assert_corners_are(s, 0, pts, 4);
            assert_normals(s, 0, v3(0, 0, 1), 1e-6);
            for (uint32_t t = 0; t < 2; t++) ASSERT_NEAR(0.5 * v3_len(tri_normal(s, 0, t)), 0.5, 1e-6);
        }
        scene_free(s);
        fx.live[s - fx.scenes] = 0;
    }
    if (failures) fail_msg("%d .obj variants did not load as a quad", failures);
}

static void test_obj_bad(void **state)
{
    (void)state;
    static const char *const objs[] = {
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 5\n", /* index past the end */
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n",          /* 0 is not an index */
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -4 -2 -1\n",       /* negative past the start */
        "v 0 0 0\nv 1 0 0\nf 1 2\n",                      /* two corners */
        "v 0 0 0\nv 1 0 0\nv 1 1 0\n",                    /* no faces */
        "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 1 1 0\n",          /* face before its vertices */
        "v 0 0 zero\nv 1 0 0\nv 1 1 0\nf 1 2 3\n",        /* bad number */
        "v 0 0 1e999\nv 1 0 0\nv 1 1 0\nf 1 2 3\n",       /* non-finite */
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 x\n",           /* bad token */
        "",                                               /* empty file */
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
        char name[32], prims[256];
        snprintf(name, sizeof name, "bad%zu.obj", i);
        write_in_dir(name, objs[i], strlen(objs[i]));
        snprintf(prims, sizeof prims, "{\"type\": \"mesh\", \"file\": \"%s\", \"bsdf\": \"w\"}", name);
        dp_error err;
        scene *s = load_prims(prims, &err);
        if (s) {
            print_message("[bad obj %zu] loaded with %u triangles: %s", i, s->tri_count, objs[i]);
            failures++;
            scene_free(s);
            fx.live[s - fx.scenes] = 0;
        } else if (!strstr(err.msg, name)) {
            print_message("[bad obj %zu] the message does not name %s: %s\n", i, name, err.msg);
            failures++;
        }
    }
    /* a missing .obj and an unknown extension */
    dp_error err;
    if (load_prims("{\"type\": \"mesh\", \"file\": \"nowhere.obj\", \"bsdf\": \"w\"}", &err)) failures++;
    else if (!strstr(err.msg, "nowhere.obj")) failures++;
    write_in_dir("m.ply", "ply\n", 4);
    if (load_prims("{\"type\": \"mesh\", \"file\": \"m.ply\", \"bsdf\": \"w\"}", &err)) failures++;
    else if (!strstr(err.msg, "m.ply")) failures++;
    if (failures) fail_msg("%d bad meshes were not refused with a message naming the file", failures);
}

/* ---- vertices beyond float range ---- */

/* A transform that is finite in double but puts vertices beyond FLT_MAX (3.4e38): the float vertex array
 * (what Embree gets) would hold inf. The load must refuse it or keep every vertex finite. */
static void test_vertices_stay_finite_as_float(void **state)
{
    (void)state;
    dp_error err;
    const scene *s = load_prims("{\"type\": \"quad\", \"bsdf\": \"w\", \"transform\": {\"scale\": [1e39, 1, 1]}}", &err);
    if (!s) {
        if (!err.msg[0]) fail_msg("refused without a message");
        return;
    }
    for (uint32_t i = 0; i < 3 * s->vert_count; i++)
        if (!isfinite(s->verts[i]))
            fail_msg("vertex %u has a non-finite float coordinate %g (scale 1e39 overflows float)", i / 3,
                     (double)s->verts[i]);
}

/* ---- ray queries ---- */

static void test_intersect_quad(void **state)
{
    (void)state;
    const scene *s = load_prims_or_fail(
        "{\"type\": \"quad\", \"bsdf\": \"w\", \"transform\": {\"scale\": [2, 1, 2]}},"
        "{\"type\": \"cube\", \"bsdf\": \"w\", \"transform\": {\"position\": [10, 0, 0]}}");
    hit_record h;
    /* straight down onto the quad (x, z in [-1, 1] at y = 0) */
    memset(&h, 0, sizeof h);
    assert_int_equal(scene_intersect(s, v3(0.3, 5, -0.2), v3(0, -1, 0), INFINITY, &h), 1);
    ASSERT_NEAR(h.t, 5.0, 1e-5);
    ASSERT_VEC(h.p, 0.3, 0.0, -0.2, 1e-5);
    ASSERT_VEC(h.ng, 0, 1, 0, 1e-6);
    assert_int_equal(h.surface, 0);
    /* the same ray with tmax short of the quad misses */
    assert_int_equal(scene_intersect(s, v3(0.3, 5, -0.2), v3(0, -1, 0), 4.9, &h), 0);
    /* from below: same t, the geometric normal does not depend on the side */
    assert_int_equal(scene_intersect(s, v3(0.3, -5, -0.2), v3(0, 1, 0), INFINITY, &h), 1);
    ASSERT_NEAR(h.t, 5.0, 1e-5);
    ASSERT_VEC(h.ng, 0, 1, 0, 1e-6);
    /* oblique: from (0,1,0) along (0.5,-1,0)/|.| hits (0.5,0,0) at t = sqrt(1.25) */
    vec3 d = v3_norm(v3(0.5, -1, 0));
    assert_int_equal(scene_intersect(s, v3(0, 1, 0), d, INFINITY, &h), 1);
    ASSERT_NEAR(h.t, sqrt(1.25), 1e-5);
    ASSERT_VEC(h.p, 0.5, 0.0, 0.0, 1e-5);
    /* beside the quad, and pointing away from it */
    assert_int_equal(scene_intersect(s, v3(3, 5, 0), v3(0, -1, 0), INFINITY, &h), 0);
    assert_int_equal(scene_intersect(s, v3(1.01, 5, 0), v3(0, -1, 0), INFINITY, &h), 0);
    assert_int_equal(scene_intersect(s, v3(0, 5, 0), v3(0, 1, 0), INFINITY, &h), 0);
    /* the cube (unit, centred at (10,0,0)) is surface 1: its top face at y = 0.5 faces +y */
    assert_int_equal(scene_intersect(s, v3(10.1, 5, 0.2), v3(0, -1, 0), INFINITY, &h), 1);
    assert_int_equal(h.surface, 1);
    ASSERT_NEAR(h.t, 4.5, 1e-5);
    ASSERT_VEC(h.ng, 0, 1, 0, 1e-6);
    /* from inside the cube towards -x: the -x face at x = 9.5, outward normal -x */
    assert_int_equal(scene_intersect(s, v3(10, 0.1, 0.1), v3(-1, 0, 0), INFINITY, &h), 1);
    ASSERT_NEAR(h.t, 0.5, 1e-5);
    ASSERT_VEC(h.ng, -1, 0, 0, 1e-6);
    /* rays lying in the quad's plane: no crash; a reported hit is a real point of the quad */
    const vec3 inplane_o[3] = {{-5, 0, 0}, {0, 0, 0}, {-5, 0, 1}};
    const vec3 inplane_d[3] = {{1, 0, 0}, {0, 0, 1}, {1, 0, 0}};
    for (int i = 0; i < 3; i++) {
        memset(&h, 0, sizeof h);
        if (scene_intersect(s, inplane_o[i], inplane_d[i], INFINITY, &h)) {
            assert_true(isfinite(h.t) && h.t > 0);
            if (h.surface == 0) {
                assert_true(fabs(h.p.y) < 1e-5 && fabs(h.p.x) <= 1 + 1e-5 && fabs(h.p.z) <= 1 + 1e-5);
            }
        }
    }
}

/* ---- winding of meshes that bind media (docs/scene-format.md §2.6) ---- */

/* A closed tetrahedron, every face wound outward; FLIPPED turns its last face inward, so the 3 edges
 * of that face are run in the same direction by both of their triangles (of the 6 shared edges). */
static const char TETRA_CLOSED_OBJ[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
static const char TETRA_FLIPPED_OBJ[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 4 3\n";
/* The same faces with a vertex of their own each (as .wo3 files often store them): welded by position. */
static const char TETRA_FLIPPED_SPLIT_OBJ[] = "v 0 0 0\nv 0 1 0\nv 1 0 0\n" "v 0 0 0\nv 1 0 0\nv 0 0 1\n"
                                              "v 0 0 0\nv 0 0 1\nv 0 1 0\n" "v 1 0 0\nv 0 0 1\nv 0 1 0\n"
                                              "f 1 2 3\nf 4 5 6\nf 7 8 9\nf 10 11 12\n";

static scene *load_tetra_with_media(const char *obj, const char *media_keys)
{
    write_in_dir("tetra4.obj", obj, strlen(obj));
    char text[1024];
    snprintf(text, sizeof text,
             "{\"media\": [{\"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.1, \"sigma_a\": 0.0}],\n"
             " \"bsdfs\": [{\"name\": \"w\", \"type\": \"lambert\", \"albedo\": 0.5}],\n"
             " \"primitives\": [{\"type\": \"mesh\", \"file\": \"tetra4.obj\", \"bsdf\": \"w\"%s},\n"
             "   {\"type\": \"point\", \"emission\": 1, \"ext_medium\": \"fog\", \"transform\": {\"position\": [0, 3, 0]}}],\n"
             " \"camera\": {\"resolution\": [4, 4], \"fov\": 45, \"medium\": \"fog\",\n"
             "   \"transform\": {\"position\": [0, 0, -20], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}},\n"
             " \"integrator\": {\"type\": \"path_tracer\"}, \"renderer\": {\"spp\": 1}}\n",
             media_keys);
    dp_error err;
    scene *s = fx_load_text("winding.json", text, NULL, &err);
    if (!s) fail_msg("the winding scene must load: %s", err.msg);
    return s;
}

static int warns_winding(const scene *s) { return s->notes && strstr(s->notes, "wound in opposite directions"); }

static void test_mixed_winding_warning(void **state)
{
    (void)state;
    const char *media = ", \"ext_medium\": \"fog\"";
    scene *s = load_tetra_with_media(TETRA_FLIPPED_OBJ, media);
    if (!warns_winding(s)) fail_msg("a flipped face on a mesh binding fog outside and vacuum inside must warn:\n%s",
                                    s->notes ? s->notes : "(no notes)");
    ASSERT_CONTAINS(s->notes, "3 of the 6 edges");
    ASSERT_CONTAINS(s->notes, "tetra4.obj");
    ASSERT_CONTAINS(s->notes, "int_medium (vacuum) and ext_medium (fog)");
    fx_drop(s);
    s = load_tetra_with_media(TETRA_FLIPPED_SPLIT_OBJ, media);
    if (!warns_winding(s)) fail_msg("unshared corners at the same positions must be welded:\n%s",
                                    s->notes ? s->notes : "(no notes)");
    ASSERT_CONTAINS(s->notes, "3 of the 6 edges");
    /* no warning: consistent winding; the same media on both sides; no media bound at all */
    fx_drop(s);
    s = load_tetra_with_media(TETRA_CLOSED_OBJ, media);
    if (warns_winding(s)) fail_msg("a consistently wound tetrahedron warned:\n%s", s->notes);
    fx_drop(s);
    s = load_tetra_with_media(TETRA_FLIPPED_OBJ, ", \"ext_medium\": \"fog\", \"int_medium\": \"fog\"");
    if (warns_winding(s)) fail_msg("the same medium on both sides warned:\n%s", s->notes);
    fx_drop(s);
    s = load_tetra_with_media(TETRA_FLIPPED_OBJ, "");
    if (warns_winding(s)) fail_msg("a mesh binding no media warned:\n%s", s->notes);
}

#define T(f) cmocka_unit_test_teardown(f, teardown_fx)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_quad_position_scale),
        T(test_quad_rotation_x180),
        T(test_rotation_matches_tungsten),
        T(test_degenerate_default_axes),
        T(test_cube),
        T(test_matrix16),
        T(test_wo3_handwritten),
        T(test_obj_faces),
        T(test_obj_bad),
        T(test_vertices_stay_finite_as_float),
        T(test_intersect_quad),
        T(test_mixed_winding_warning),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
