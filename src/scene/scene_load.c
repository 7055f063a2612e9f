/* Scene files: the Tungsten JSON subset of docs/scene-format.md §2. Top level: media, bsdfs,
 * primitives, camera, integrator, renderer. Unknown keys are ignored (listed with verbose). */
#include "scene_internal.h"
#include "settings.h"

#include <errno.h>
#include <float.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

static char *read_text_file(const char *path, dp_error *err)
{
    /* a folder opens for reading on Linux, and its size then reads as LONG_MAX: say what it is */
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        dp_fail(err, "%s: is a folder, not a scene file (give the .json file in it)", path);
        return NULL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        dp_fail(err, "%s: cannot open scene file: %s", path, strerror(errno));
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (n < 0 || n > (1L << 30)) {
        fclose(f);
        dp_fail(err, "%s: cannot read scene file (size %ld)", path, n);
        return NULL;
    }
    char *text = malloc((size_t)n + 1);
    size_t got = text ? fread(text, 1, (size_t)n, f) : 0;
    fclose(f);
    if (!text || got != (size_t)n) {
        free(text);
        dp_fail(err, "%s: cannot read scene file", path);
        return NULL;
    }
    text[n] = 0;
    return text;
}

/* Line and column of a byte offset, for parse errors. */
static void line_col(const char *text, const char *at, int *line, int *col)
{
    *line = 1;
    *col = 1;
    for (const char *p = text; p < at && *p; p++) {
        if (*p == '\n') {
            (*line)++;
            *col = 1;
        } else (*col)++;
    }
}

/* ---- named references (bsdfs; media: media_load.c) ---- */

static int find_bsdf_named(const scene *s, const cJSON *names, const char *name)
{
    for (int i = 0; i < s->bsdf_count; i++) {
        const cJSON *n = cJSON_GetArrayItem(names, i);
        if (n && cJSON_IsString(n) && !strcmp(n->valuestring, name)) return i;
    }
    return -1;
}

/* ---- media ---- */

/* ---- BSDFs (bsdf_load.c) ---- */

static int parse_bsdfs(json_ctx *c, const cJSON *root, scene *s, const cJSON **names)
{
    const cJSON *arr = jget_item(c, root, "bsdfs");
    *names = NULL;
    if (!arr) return 0;
    if (!cJSON_IsArray(arr)) return jfail(c, "bsdfs", NULL, "expected an array");
    s->bsdf_count = cJSON_GetArraySize(arr);
    s->bsdfs = calloc((size_t)s->bsdf_count + 1, sizeof(bsdf));
    cJSON *list = cJSON_CreateArray();
    *names = list;
    for (int i = 0; i < s->bsdf_count; i++) {
        char w[64];
        snprintf(w, sizeof w, "bsdfs[%d]", i);
        const cJSON *v = cJSON_GetArrayItem(arr, i);
        if (bsdf_parse(c, v, w, s, &s->bsdfs[i])) return -1;
        const char *name = "";
        if (jget_string(c, v, w, "name", &name) < 0) return -1;
        cJSON_AddItemToArray(list, cJSON_CreateString(name));
    }
    return 0;
}

/* A BSDF reference: a name or an inline object (appended to s->bsdfs). */
static int bsdf_ref(json_ctx *c, scene *s, const cJSON *names, const cJSON *v, const char *where, int *out)
{
    if (!v) return jfail(c, where, "bsdf", "missing (every surface needs a BSDF)");
    if (cJSON_IsString(v)) {
        int k = names ? find_bsdf_named(s, names, v->valuestring) : -1;
        if (k < 0) return jfail(c, where, "bsdf", "no BSDF named '%s' in bsdfs[]", v->valuestring);
        *out = k;
        return 0;
    }
    if (cJSON_IsArray(v)) return jfail(c, where, "bsdf", "per-triangle BSDF arrays are not supported");
    bsdf *grown = realloc(s->bsdfs, ((size_t)s->bsdf_count + 1) * sizeof(bsdf));
    if (!grown) return jfail(c, where, "bsdf", "out of memory");
    s->bsdfs = grown;
    memset(&s->bsdfs[s->bsdf_count], 0, sizeof(bsdf));
    char w[256];
    snprintf(w, sizeof w, "%s.bsdf", where);
    if (bsdf_parse(c, v, w, s, &s->bsdfs[s->bsdf_count])) return -1;
    *out = s->bsdf_count++;
    return 0;
}

/* ---- primitives ---- */

/* Appends the mesh's triangles in world space, and its shading attributes for surface s->surface_count. */
static int append_surface_mesh(json_ctx *c, scene *s, const tri_mesh *m, const xform *T, surface *sf, const char *where,
                               unsigned flags)
{
    if (m->nt == 0) return jfail(c, where, NULL, "the shape has no triangles");
    uint32_t base = s->vert_count;
    if ((uint64_t)s->vert_count + m->nv > (1u << 31) || (uint64_t)s->tri_count + m->nt > (1u << 31))
        return jfail(c, where, NULL, "the scene has too many triangles");
    float *v = realloc(s->verts, 3 * sizeof(float) * ((size_t)s->vert_count + m->nv));
    if (!v) return jfail(c, where, NULL, "out of memory");
    s->verts = v;
    uint32_t *t = realloc(s->tris, 3 * sizeof(uint32_t) * ((size_t)s->tri_count + m->nt));
    if (!t) return jfail(c, where, NULL, "out of memory");
    s->tris = t;
    for (uint32_t i = 0; i < m->nv; i++) {
        vec3 p = xform_point(T, v3(m->pos[3 * i], m->pos[3 * i + 1], m->pos[3 * i + 2]));
        if (!v3_is_finite(p) || !isfinite((float)p.x) || !isfinite((float)p.y) || !isfinite((float)p.z))
            return jfail(c, where, "transform", "maps a vertex outside the float range");
        if (!(fabs(p.x) <= SCENE_COORD_MAX && fabs(p.y) <= SCENE_COORD_MAX && fabs(p.z) <= SCENE_COORD_MAX))
            return jfail(c, where, "transform", "maps a vertex to (%g, %g, %g), beyond the supported coordinates "
                                                "(|x| <= %g)", p.x, p.y, p.z, SCENE_COORD_MAX);
        s->verts[3 * (size_t)(base + i)] = (float)p.x;
        s->verts[3 * (size_t)(base + i) + 1] = (float)p.y;
        s->verts[3 * (size_t)(base + i) + 2] = (float)p.z;
    }
    for (uint32_t i = 0; i < 3 * m->nt; i++) s->tris[3 * (size_t)s->tri_count + i] = base + m->idx[i];
    if (scene_rt_add_mesh(s, s->surface_count, s->tri_count, m, T, flags)) return jfail(c, where, NULL, "out of memory");
    sf->first_tri = s->tri_count;
    sf->tri_count = m->nt;
    sf->smooth = (flags & SURF_SMOOTH) != 0;
    s->vert_count += m->nv;
    s->tri_count += m->nt;
    return 0;
}

/* Appends a mesh file's resolved path to s->mesh_files (one per line). Without memory the path is left out:
 * only the output-over-input check reads the list. */
static void remember_mesh_file(scene *s, const char *path)
{
    size_t old = s->mesh_files ? strlen(s->mesh_files) : 0, n = strlen(path);
    char *grown = realloc(s->mesh_files, old + n + 2);
    if (!grown) return;
    memcpy(grown + old, path, n);
    grown[old + n] = '\n';
    grown[old + n + 1] = '\0';
    s->mesh_files = grown;
}

/* `smooth`, `backface_culling` and `recompute_normals` of a mesh primitive into SURF_* flags; smooth normals
 * recomputed as Tungsten does when asked, or when a smooth mesh has no vertex normals of its own. */
static int mesh_flags(json_ctx *c, const cJSON *v, const char *where, const char *file, tri_mesh *m, unsigned *flags)
{
    int smooth, cull, recompute;
    if (jget_bool(c, v, where, "smooth", 0, &smooth) || jget_bool(c, v, where, "backface_culling", 0, &cull) ||
        jget_bool(c, v, where, "recompute_normals", 0, &recompute))
        return -1;
    *flags = (smooth ? SURF_SMOOTH : 0u) | (cull ? SURF_CULL : 0u);
    if (!smooth) return 0;
    if (!recompute && !m->has_normals)
        jwarn(c, "%s: smooth mesh '%s' has no vertex normals; computed from its faces as recompute_normals does",
              where, file);
    if ((recompute || !m->has_normals) && tri_mesh_smooth_normals(m)) return jfail(c, where, NULL, "out of memory");
    return 0;
}

static int load_shape(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *type, tri_mesh *m,
                      unsigned *flags)
{
    *flags = 0;
    if (!strcmp(type, "quad")) mesh_make_quad(m);
    else if (!strcmp(type, "cube")) mesh_make_cube(m);
    else if (!strcmp(type, "sphere")) {
        mesh_make_sphere(m);
        *flags = SURF_SMOOTH;
    } else if (!strcmp(type, "disk")) {
        double cone;
        if (jget_number(c, v, where, "cone_angle", 90.0, &cone)) return -1;
        if (cone != 90.0) return jfail(c, where, "cone_angle", "only 90 (the whole hemisphere) is supported (got %g)", cone);
        mesh_make_disk(m);
    }
    else {
        const char *file = NULL;
        if (jget_string(c, v, where, "file", &file) <= 0) return file ? -1 : jfail(c, where, "file", "missing (a mesh needs a file)");
        char path[2100];
        snprintf(path, sizeof path, "%s%s%s", file[0] == '/' ? "" : s->dir, file[0] == '/' ? "" : "/", file);
        size_t n = strlen(file);
        dp_error merr;
        int rc;
        if (n > 4 && !strcasecmp(file + n - 4, ".wo3")) rc = mesh_load_wo3(path, m, &merr);
        else if (n > 4 && !strcasecmp(file + n - 4, ".obj")) rc = mesh_load_obj(path, m, &merr);
        else return jfail(c, where, "file", "'%s': unsupported mesh format (supported: .wo3, .obj)", file);
        if (rc) return jfail(c, where, "file", "%s", merr.msg);
        remember_mesh_file(s, path);
        return mesh_flags(c, v, where, file, m, flags);
    }
    return 0;
}

/* Tungsten's disk and sphere are round whatever the scale: radius = the longest of the axes that span them
 * (docs/emitters.md §2.4), so those axes are stretched to that length before tessellating through T. */
static xform shape_transform(const char *type, const xform *T)
{
    xform r = *T;
    int disk = !strcmp(type, "disk"), sphere = !strcmp(type, "sphere");
    if (!disk && !sphere) return r;
    double lx = v3_len(T->x), ly = v3_len(T->y), lz = v3_len(T->z);
    double R = dp_fmax(lx, lz);
    if (sphere) R = dp_fmax(R, ly);
    if (lx > 0) r.x = v3_scale(T->x, R / lx);
    if (lz > 0) r.z = v3_scale(T->z, R / lz);
    if (sphere && ly > 0) r.y = v3_scale(T->y, R / ly);
    return r;
}

/* A mesh that binds two different media to its sides but whose triangles disagree on which side is the
 * front: across the flipped faces the media swap, so a path reflected there continues in the other medium.
 * Legal (Tungsten does the same), but light and camera paths then disagree about the medium of the same
 * segment, and the path tracer and photon points converge to different images (the paper's dragon scene:
 * its blockage, bench/results/references.md). */
static void warn_mixed_winding(json_ctx *c, const scene *s, const cJSON *v, const tri_mesh *m, const surface *sf,
                               const char *where)
{
    uint32_t shared, flipped;
    if (tri_mesh_winding(m, &shared, &flipped) || flipped == 0) return;
    const cJSON *file = jget_item(c, v, "file");
    jwarn(c, "%s: '%s' binds int_medium (%s) and ext_medium (%s), but %u of the %u edges shared by two of its "
             "triangles join triangles wound in opposite directions: the two media swap sides across them, light "
             "reflected off the flipped faces continues in the other medium, and the path tracer and photon "
             "points converge to different images; wind the mesh consistently, or give both sides the same "
             "medium if its inside is never entered (docs/scene-format.md §2.6)",
          where, cJSON_IsString(file) ? file->valuestring : sf->name, medium_name(s, sf->int_medium),
          medium_name(s, sf->ext_medium), flipped, shared);
}

/* Liu et al.'s fork of Tungsten (Primitive::selectSpeedOfLight): int_speed_of_light / ext_speed_of_light set the
 * speed of light on the back / front side of a surface when that side has no medium (a side's medium keeps its
 * own speed_of_light; a value <= 0 means none, the fork's default -1). dartspp gives such a side a clear region,
 * a medium with σs = σa = 0 and η = 1/speed (media_load.c): Liu's volumetric-caustic times the glass lens this
 * way. The fork also changes the speed on a surface that sets no medium, keeping the medium: not representable
 * here (a region is one medium with one η), refused. */
static int side_speed(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *key, const surface *sf,
                      int *side)
{
    if (!jget_item(c, v, key)) return 0;
    double speed;
    if (jget_number(c, v, where, key, -1.0, &speed)) return -1;
    if (!(speed > 0)) {
        jwarn(c, "%s: %s %g is not positive: no speed is set (as in Liu et al.'s fork, whose default is -1)", where,
              key, speed);
        return 0;
    }
    if (!sf->overrides_media)
        return jfail(c, where, key, "changes the speed of light without int_medium or ext_medium on the surface: "
                     "not supported (dartspp's regions are media, each with its speed_of_light; give the surface "
                     "int_medium and ext_medium, or a medium with speed_of_light %g)", speed);
    if (*side != MEDIUM_VACUUM) {
        jwarn(c, "%s: %s %g is ignored: that side has medium '%s', whose speed_of_light %g applies (as in Liu et al.'s "
              "fork)", where, key, speed, s->media[*side].name, 1.0 / s->media[*side].eta);
        return 0;
    }
    return clear_region(c, s, speed, where, key, side);
}

static int parse_surface(json_ctx *c, scene *s, const cJSON *names, const cJSON *v, const char *where,
                         const char *type, const xform *T)
{
    surface sf = {0};
    const char *name = "";
    if (jget_string(c, v, where, "name", &name) < 0) return -1;
    snprintf(sf.name, sizeof sf.name, "%s", name[0] ? name : where);
    if (bsdf_ref(c, s, names, jget_item(c, v, "bsdf"), where, &sf.bsdf)) return -1;
    const cJSON *im = jget_item(c, v, "int_medium");
    const cJSON *em = jget_item(c, v, "ext_medium");
    sf.int_medium = sf.ext_medium = MEDIUM_VACUUM;
    sf.overrides_media = im || em;
    if (im && medium_ref(c, s, im, where, "int_medium", &sf.int_medium)) return -1;
    if (em && medium_ref(c, s, em, where, "ext_medium", &sf.ext_medium)) return -1;
    if (side_speed(c, s, v, where, "int_speed_of_light", &sf, &sf.int_medium) ||
        side_speed(c, s, v, where, "ext_speed_of_light", &sf, &sf.ext_medium))
        return -1;
    tri_mesh m = {0};
    unsigned flags;
    int rc = load_shape(c, s, v, where, type, &m, &flags);
    if (!rc && sf.overrides_media && sf.int_medium != sf.ext_medium) warn_mixed_winding(c, s, v, &m, &sf, where);
    xform Ts = shape_transform(type, T);
    if (!rc) rc = append_surface_mesh(c, s, &m, &Ts, &sf, where, flags);
    tri_mesh_free(&m);
    if (rc) return rc;
    sf.emitter = -1;
    if (((jget_item(c, v, "emission") != NULL) || (jget_item(c, v, "power") != NULL)) &&
        light_parse_area(c, s, v, where, type, &sf))
        return -1;
    surface *grown = realloc(s->surfaces, ((size_t)s->surface_count + 1) * sizeof(surface));
    if (!grown) return jfail(c, where, NULL, "out of memory");
    s->surfaces = grown;
    s->surfaces[s->surface_count++] = sf;
    return 0;
}

/* the message names every primitive type: the shapes, then the emitters' in the order of their table */
static int unsupported_primitive(json_ctx *c, const char *where, const char *type)
{
    char lights[256];
    emitter_primitive_list(lights, sizeof lights, ", ");
    return jfail(c, where, "type", "unsupported primitive '%s' (supported: mesh, quad, disk, sphere, cube, %s)", type,
                 lights);
}

/* slots (one per primitive, or NULL): what each primitive became, for the derivatives' pointers */
static int parse_primitives(json_ctx *c, const cJSON *root, scene *s, const cJSON *names, prim_slot *slots)
{
    const cJSON *arr = jget_item(c, root, "primitives");
    if (!arr) return 0;
    if (!cJSON_IsArray(arr)) return jfail(c, "primitives", NULL, "expected an array");
    for (int i = 0; i < cJSON_GetArraySize(arr); i++) {
        int surfaces = s->surface_count, lights = s->light_count;
        char w[64];
        snprintf(w, sizeof w, "primitives[%d]", i);
        const cJSON *v = cJSON_GetArrayItem(arr, i);
        if (!cJSON_IsObject(v)) return jfail(c, w, NULL, "expected an object");
        size_t mark = jread_mark(c);
        const char *type = NULL;
        if (jget_string(c, v, w, "type", &type) <= 0) return type ? -1 : jfail(c, w, "type", "missing");
        xform T;
        if (xform_parse(c, jget_item(c, v, "transform"), w, &T)) return -1;
        int rc;
        if (emitter_ops_find(type))
            rc = light_parse(c, s, v, w, type, &T);
        else if (!strcmp(type, "mesh") || !strcmp(type, "quad") || !strcmp(type, "cube") || !strcmp(type, "disk") ||
                 !strcmp(type, "sphere"))
            rc = parse_surface(c, s, names, v, w, type, &T);
        else rc = unsupported_primitive(c, w, type);
        if (rc) return rc;
        if (slots) slots[i] = (prim_slot){s->surface_count > surfaces ? surfaces : -1, s->light_count > lights ? lights : -1};
        jnote_unread_keys(c, v, w, mark);
    }
    return 0;
}

/* ---- camera ---- */

/* Tungsten's PinholeCamera: the horizontal field of view in degrees. */
static int parse_pinhole(json_ctx *c, const cJSON *v, camera *cam)
{
    if (jget_number(c, v, "camera", "fov", 60.0, &cam->fov_deg)) return -1;
    if (!(cam->fov_deg > 0 && cam->fov_deg < 180)) return jfail(c, "camera", "fov", "must be in (0, 180) degrees (got %g)", cam->fov_deg);
    /* a positive fov so small that the image plane's distance 1/tan(fov/2) overflows gave NaN ray directions */
    if (cam->fov_deg < 1e-6)
        return jfail(c, "camera", "fov", "is too small (got %g; the smallest supported is 1e-6 degrees)", cam->fov_deg);
    return 0;
}

/* Tungsten's OrthographicCamera: orthographic_size, half the film's height in scene units (default 1, as
 * Tungsten's); the film's width follows the resolution's aspect. It reads no fov (a fov in the file is unread,
 * as in Tungsten). */
static int parse_orthographic(json_ctx *c, const cJSON *v, camera *cam)
{
    if (jget_number(c, v, "camera", "orthographic_size", 1.0, &cam->ortho_size)) return -1;
    if (!(cam->ortho_size > 0 && cam->ortho_size < 1e30))
        return jfail(c, "camera", "orthographic_size", "must be a positive length, half the film's height in scene "
                     "units (got %g)", cam->ortho_size);
    cam->fov_deg = 0.0;
    return 0;
}

static int parse_camera(json_ctx *c, const cJSON *root, scene *s)
{
    const cJSON *v = jget_item(c, root, "camera");
    if (!cJSON_IsObject(v)) return jfail(c, "camera", NULL, v ? "expected an object" : "missing");
    size_t mark = jread_mark(c);
    const char *type = "pinhole";
    if (jget_string(c, v, "camera", "type", &type) < 0) return -1;
    camera *cam = &s->cam;
    if (!strcmp(type, "pinhole")) cam->type = CAMERA_PINHOLE;
    else if (!strcmp(type, "orthographic")) cam->type = CAMERA_ORTHOGRAPHIC;
    else if (!strcmp(type, "lidar")) cam->type = CAMERA_LIDAR;
    else return jfail(c, "camera", "type", "unsupported camera '%s' (supported: pinhole, orthographic, lidar)", type);
    cam->width = 512;
    cam->height = 512;
    const cJSON *res = jget_item(c, v, "resolution");
    if (res) {
        double w, h;
        if (cJSON_IsNumber(res)) w = h = res->valuedouble;
        else if (cJSON_IsArray(res) && cJSON_GetArraySize(res) == 2 && cJSON_IsNumber(cJSON_GetArrayItem(res, 0)) &&
                 cJSON_IsNumber(cJSON_GetArrayItem(res, 1))) {
            w = cJSON_GetArrayItem(res, 0)->valuedouble;
            h = cJSON_GetArrayItem(res, 1)->valuedouble;
        } else return jfail(c, "camera", "resolution", "expected [width, height]");
        if (w != floor(w) || h != floor(h))
            return jfail(c, "camera", "resolution", "expected whole numbers of pixels (got %.17g x %.17g)", w, h);
        if (!(w >= 1 && h >= 1 && w <= 65536 && h <= 65536 && w * h <= 1 << 28))
            return jfail(c, "camera", "resolution", "must be 1 to 65536 pixels per side and at most 2^28 (268435456) "
                         "pixels in all (got %g x %g)", w, h);
        cam->width = (int)w;
        cam->height = (int)h;
    }
    if (cam->type == CAMERA_LIDAR ? lidar_parse_camera(c, v, cam)
        : cam->type == CAMERA_ORTHOGRAPHIC ? parse_orthographic(c, v, cam) : parse_pinhole(c, v, cam)) return -1;
    xform T;
    if (xform_parse(c, jget_item(c, v, "transform"), "camera", &T)) return -1;
    cam->pos = T.pos;
    cam->right = v3_neg(v3_norm(T.x)); /* Tungsten negates the camera's x axis */
    cam->up = v3_norm(T.y);
    cam->forward = v3_norm(T.z);
    if (cam->type == CAMERA_PINHOLE) cam->plane_dist = 1.0 / tan(0.5 * cam->fov_deg * M_PI / 180.0);
    cam->medium = MEDIUM_VACUUM;
    const cJSON *m = jget_item(c, v, "medium");
    if (m && medium_ref(c, s, m, "camera", "medium", &cam->medium)) return -1;
    jnote_unread_keys(c, v, "camera", mark);
    return 0;
}

/* ---- top level ---- */

static void set_dir(scene *s, const char *path)
{
    snprintf(s->path, sizeof s->path, "%s", path);
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s", path);
    snprintf(s->dir, sizeof s->dir, "%s", dirname(tmp));
}

/* Scenes that load and can only render black: no light, lights of zero power, or a gate that ends before the
 * earliest time any light path can reach the camera (the pulse start plus the straight light-to-camera
 * distance times the smallest time per length of the scene's regions; a camera-unwarped time leaves out the
 * camera segment, so there only the pulse start bounds it). Warnings, since the file is legal. */
static void warn_dark_scene(json_ctx *c, const scene *s)
{
    if (s->light_count == 0) {
        char lights[256];
        emitter_primitive_list(lights, sizeof lights, " or ");
        jwarn(c, "primitives: the scene has no light (a %s primitive, or a shape with emission or power): the image "
                 "will be black", lights);
        return;
    }
    int lit = 0;
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        if (L->flux.x > 0 || L->flux.y > 0 || L->flux.z > 0) lit++;
        else jwarn(c, "primitives: light '%s' has zero power: it emits nothing", L->name);
    }
    if (!lit) {
        jwarn(c, "primitives: every light has zero power: the image will be black");
        return;
    }
    const time_window *tw = &s->integrator.window;
    if (!tw->gated) return;
    double eta = s->integrator.vacuum_eta;
    for (int m = 0; m < s->medium_count; m++)
        if (s->media[m].eta < eta) eta = s->media[m].eta;
    double earliest = INFINITY, dist = 0;
    const emitter *first = NULL;
    for (int i = 0; i < s->light_count; i++) {
        const emitter *L = &s->lights[i];
        if (!(L->flux.x > 0 || L->flux.y > 0 || L->flux.z > 0)) continue;
        if (L->pulse.shape == PULSE_GAUSSIAN && L->pulse.width > 0.0) return; /* no earliest emission */
        if (s->cam.response.on) return; /* the response can move a detection earlier */
        /* the nearest emitting point is at most `extent` nearer than the light's reference point */
        double d = tw->camera_unwarp ? 0.0 : dp_fmax(0.0, camera_distance(&s->cam, L->pos) - L->extent);
        double t = L->pulse.start + d * eta;
        if (t < earliest) earliest = t, dist = d, first = L;
    }
    double end = time_window_end(tw);
    if (!first || end > earliest) return;
    if (tw->camera_unwarp)
        jwarn(c, "integrator: the time %s ends at %g, before any light emits (the earliest pulse_start is %g, light "
                 "'%s'): the image will be black", tw->frame_count > 0 ? "window of the frames" : "gate", end, earliest,
              first->name);
    else
        jwarn(c, "integrator: the time %s ends at %g, before any light path can reach the camera: the earliest "
                 "arrival is %g (light '%s': pulse_start %g + distance to the camera%s %g x the smallest time per "
                 "length %g): the image will be black; a file written for a renderer that does not time the camera "
                 "segment (Liu et al.'s) renders with camera_unwarp true", tw->frame_count > 0 ? "window of the frames" : "gate", end,
              earliest, first->name, first->pulse.start, s->cam.type == CAMERA_ORTHOGRAPHIC ? "'s plane" : "", dist, eta);
}

/* A light whose paths start in vacuum (no ext_medium) while the camera is in a medium and no surface sets
 * media, so that the whole scene is the camera's medium to camera paths: light paths from it would not
 * scatter or attenuate before they meet a surface, while camera paths connect to it through the medium.
 * Legal, and almost always a forgotten ext_medium. */
static void warn_light_outside_medium(json_ctx *c, const scene *s)
{
    if (s->cam.medium == MEDIUM_VACUUM) return;
    for (int i = 0; i < s->surface_count; i++)
        if (s->surfaces[i].overrides_media) return;
    for (int i = 0; i < s->light_count; i++)
        if (s->lights[i].medium == MEDIUM_VACUUM)
            jwarn(c, "primitives: light '%s' has no ext_medium, so its light paths start in vacuum, while the camera "
                     "is in medium '%s' and no surface sets media: photon points would see it unattenuated and "
                     "camera paths through the medium; set \"ext_medium\": \"%s\" on it", s->lights[i].name,
                  s->media[s->cam.medium].name, s->media[s->cam.medium].name);
}

/* A response's offsets are added to arrival times of the scene's size: an offset of magnitude M rounds the sum
 * to M·2^-52, and once that is more than a millionth of the window's width the detections land in the wrong
 * gate or frame (issue 48: a table at times of 1e200 gave half the undelayed image). Refused, naming the key;
 * a steady-state render has no window for them to miss. */
static int check_response_precision(json_ctx *c, const scene *s)
{
    const sensor_response *r = &s->cam.response;
    const time_window *tw = &s->integrator.window;
    if (!r->on || !tw->gated || !(tw->width > 0.0)) return 0;
    double limit = 1e-6 * tw->width / DBL_EPSILON;
    const char *key = "sensor_response_file";
    double worst = 0.0;
    for (int i = 0; i < r->n; i++) worst = dp_fmax(worst, fabs(r->t[i]));
    if (!r->n) {
        /* the Gaussian reaches about 8 σ and the exponential about 37 τ before their tails round to 0 */
        double fwhm = s->integrator.sensor_jitter_fwhm, tail = s->integrator.sensor_jitter_tail;
        worst = 8.0 * fwhm / 2.3548200450309493 + 37.0 * tail;
        key = 8.0 * fwhm / 2.3548200450309493 >= 37.0 * tail ? "sensor_jitter_fwhm" : "sensor_jitter_tail";
    }
    if (worst <= limit) return 0;
    return jfail(c, "integrator", key, "offsets of the time response reach %g: added to arrival times they round "
                 "them by up to %g, more than a millionth of the %s width %g, so detections would land in the wrong "
                 "%s; the response's offsets must stay within %g here", worst, worst * DBL_EPSILON,
                 tw->frame_count > 0 ? "frames'" : "gate's", tw->width, tw->frame_count > 0 ? "frame" : "gate", limit);
}

/* The camera's time response from the integrator's sensor_* keys (docs/sensor.md §2); a table file is
 * relative to the scene file. */
static int load_sensor_response(json_ctx *c, scene *s)
{
    const integrator_settings *in = &s->integrator;
    const char *file = in->sensor_response_file;
    char path[2100] = "";
    if (file[0]) snprintf(path, sizeof path, "%s%s%s", file[0] == '/' ? "" : s->dir, file[0] == '/' ? "" : "/", file);
    if (file[0] && (in->sensor_jitter_fwhm > 0.0 || in->sensor_jitter_tail > 0.0))
        return jfail(c, "integrator", "sensor_response_file",
                     "a tabulated response replaces sensor_jitter_fwhm and sensor_jitter_tail: give one or the other");
    dp_error e;
    if (sensor_response_init(&s->cam.response, in->sensor_jitter_fwhm, in->sensor_jitter_tail, path, &e))
        return jfail(c, "integrator", file[0] ? "sensor_response_file" : "sensor_jitter_fwhm", "%s", e.msg);
    return check_response_precision(c, s);
}

static int parse_all(json_ctx *c, cJSON *root, scene *s, const scene_load_options *opt)
{
    if (!cJSON_IsObject(root)) return jfail(c, "(top level)", NULL, "expected a JSON object");
    if (settings_apply_overrides(c, root, opt ? opt->sets : NULL, opt ? opt->set_count : 0)) return -1;
    const cJSON *names = NULL;
    int derivs = opt && opt->derivative_count > 0;
    const cJSON *prims = cJSON_GetObjectItemCaseSensitive(root, "primitives");
    int prim_count = derivs && cJSON_IsArray(prims) ? cJSON_GetArraySize(prims) : 0;
    prim_slot *slots = derivs ? calloc((size_t)prim_count + 1, sizeof *slots) : NULL;
    if (derivs && !slots) return jfail(c, "(top level)", NULL, "out of memory");
    int rc = parse_media(c, root, s);
    if (!rc) rc = parse_bsdfs(c, root, s, &names);
    if (!rc) rc = parse_primitives(c, root, s, names, slots);
    if (!rc) rc = parse_camera(c, root, s);
    if (!rc) rc = settings_parse(c, root, s);
    if (!rc) rc = lidar_finish_scene(c, root, s, derivs);
    if (!rc) rc = load_sensor_response(c, s);
    if (!rc) jnote_unread_keys(c, root, "", 0);
    if (!rc) warn_dark_scene(c, s);
    if (!rc) warn_light_outside_medium(c, s);
    if (!rc && derivs) rc = diff_params_resolve(c, root, s, slots, prim_count, opt->derivatives, opt->derivative_count);
    free(slots);
    cJSON_Delete((cJSON *)names);
    return rc;
}

/* The scene's text, parsed and checked, and its Embree scene built; s->path and s->dir are set. */
static int load_text(const char *text, const scene_load_options *opt, scene *s, dp_error *err)
{
    strbuf notes = {0};
    json_ctx c = {.file = s->path, .err = err, .verbose = opt ? opt->verbose : 0, .notes = &notes};
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    int rc;
    if (!root) {
        int line, col;
        const char *at = cJSON_GetErrorPtr();
        line_col(text, at ? at : text, &line, &col);
        rc = dp_fail(err, "%s:%d:%d: malformed JSON", s->path, line, col);
    } else {
        rc = parse_all(&c, root, s, opt);
    }
    cJSON_Delete(root);
    json_ctx_free(&c);
    s->notes = notes.text;
    if (!rc) rc = scene_build_embree(s, err);
    if (rc) scene_free(s);
    return rc;
}

int scene_load(const char *path, const scene_load_options *opt, scene *s, dp_error *err)
{
    memset(s, 0, sizeof *s);
    set_dir(s, path);
    char *text = read_text_file(path, err);
    if (!text) return -1;
    int rc = load_text(text, opt, s, err);
    free(text);
    return rc;
}

int scene_load_text(const char *text, const char *name, const char *base_dir, const scene_load_options *opt, scene *s,
                    dp_error *err)
{
    memset(s, 0, sizeof *s);
    if (snprintf(s->path, sizeof s->path, "%s", name) >= (int)sizeof s->path ||
        snprintf(s->dir, sizeof s->dir, "%s", base_dir && base_dir[0] ? base_dir : ".") >= (int)sizeof s->dir)
        return dp_fail(err, "%s: the scene's name or its base folder is longer than %zu characters", name,
                       sizeof s->dir - 1);
    return load_text(text, opt, s, err);
}

void scene_free(scene *s)
{
    free(s->mesh_files);
    scene_release_embree(s);
    texture_free_all(s);
    free(s->bsdfs);
    for (int i = 0; s->media && i < s->medium_count; i++) medium_free_phase(&s->media[i]);
    free(s->media);
    free(s->surfaces);
    for (int i = 0; i < s->light_count; i++) emitter_free(&s->lights[i]);
    free(s->lights);
    sensor_response_free(&s->cam.response);
    free(s->verts);
    free(s->tris);
    free(s->notes);
    memset(s, 0, sizeof *s);
}
