/* The `transform` of a primitive or camera: a 16-float row-major matrix, or an object with position,
 * look_at, up, x/y/z_axis, scale and rotation, built the way Tungsten builds it (docs/scene-format.md §2.2). */
#include "scene_internal.h"

#include <stdio.h>
#include <string.h>

/* Gram–Schmidt in the order a, b, c: a is kept (normalised), b and c are made orthogonal to it; an axis
 * that collapses (parallel to an earlier one) is replaced by a cross product, as Tungsten does. */
static void gram_schmidt(vec3 *a, vec3 *b, vec3 *c)
{
    *a = v3_norm(*a);
    *b = v3_sub(*b, v3_scale(*a, v3_dot(*a, *b)));
    if (v3_dot(*b, *b) < 1e-10) *b = v3_cross(*a, *c);
    if (v3_dot(*b, *b) < 1e-10) v3_basis(*a, b, c);
    *b = v3_norm(*b);
    *c = v3_sub(v3_sub(*c, v3_scale(*a, v3_dot(*a, *c))), v3_scale(*b, v3_dot(*b, *c)));
    if (v3_dot(*c, *c) < 1e-10) *c = v3_cross(*a, *b);
    *c = v3_norm(*c);
}

/* Rotation by Euler angles in degrees, applied Y·X·Z (Tungsten Mat4f::rotYXZ). */
static vec3 rot_yxz(vec3 deg, vec3 v)
{
    double rx = deg.x * M_PI / 180.0, ry = deg.y * M_PI / 180.0, rz = deg.z * M_PI / 180.0;
    /* Z first */
    vec3 a = v3(v.x * cos(rz) - v.y * sin(rz), v.x * sin(rz) + v.y * cos(rz), v.z);
    /* then X */
    vec3 b = v3(a.x, a.y * cos(rx) - a.z * sin(rx), a.y * sin(rx) + a.z * cos(rx));
    /* then Y, with Tungsten's sign: [c 0 -s; 0 1 0; s 0 c] */
    return v3(b.x * cos(ry) - b.z * sin(ry), b.y, b.x * sin(ry) + b.z * cos(ry));
}

static int parse_matrix16(json_ctx *c, const cJSON *v, const char *where, xform *out)
{
    double m[16];
    for (int i = 0; i < 16; i++) {
        const cJSON *e = cJSON_GetArrayItem(v, i);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return jfail(c, where, "transform", "element %d of the 16-float matrix is not a finite number", i);
        m[i] = e->valuedouble;
    }
    /* row-major: column j is (m[j], m[4+j], m[8+j]) */
    out->x = v3(m[0], m[4], m[8]);
    out->y = v3(m[1], m[5], m[9]);
    out->z = v3(m[2], m[6], m[10]);
    out->pos = v3(m[3], m[7], m[11]);
    return 0;
}

static int xform_parse_any(json_ctx *c, const cJSON *v, const char *where, xform *out);

/* A position beyond SCENE_COORD_MAX is refused: Embree's rays need |origin| below 1.8e18 (FLT_LARGE) and
 * assert otherwise, and the camera, the lights and every hit point are ray origins. */
int xform_parse(json_ctx *c, const cJSON *v, const char *where, xform *out)
{
    if (xform_parse_any(c, v, where, out)) return -1;
    vec3 p = out->pos;
    if (!(fabs(p.x) <= SCENE_COORD_MAX && fabs(p.y) <= SCENE_COORD_MAX && fabs(p.z) <= SCENE_COORD_MAX)) {
        char w[256];
        snprintf(w, sizeof w, "%s.transform", where);
        return jfail(c, w, "position", "(%g, %g, %g) is beyond the supported coordinates (|x| <= %g)", p.x, p.y, p.z,
                     SCENE_COORD_MAX);
    }
    return 0;
}

static int xform_parse_any(json_ctx *c, const cJSON *v, const char *where, xform *out)
{
    out->x = v3(1, 0, 0);
    out->y = v3(0, 1, 0);
    out->z = v3(0, 0, 1);
    out->pos = v3s(0);
    if (!v) return 0;
    if (cJSON_IsArray(v)) {
        if (cJSON_GetArraySize(v) != 16) return jfail(c, where, "transform", "a matrix needs 16 numbers");
        return parse_matrix16(c, v, where, out);
    }
    if (!cJSON_IsObject(v)) return jfail(c, where, "transform", "expected an object or 16 numbers");
    char w[256];
    snprintf(w, sizeof w, "%s.transform", where);
    size_t mark = jread_mark(c);

    vec3 x = out->x, y = out->y, z = out->z, pos, look, scale, rot;
    if (jget_vec3(c, v, w, "position", v3s(0), &pos)) return -1;
    int ex = (jget_item(c, v, "x_axis") != NULL), ey = (jget_item(c, v, "up") != NULL) || (jget_item(c, v, "y_axis") != NULL);
    int ez = (jget_item(c, v, "look_at") != NULL) || (jget_item(c, v, "z_axis") != NULL);
    if ((jget_item(c, v, "look_at") != NULL)) {
        if (jget_vec3(c, v, w, "look_at", v3s(0), &look)) return -1;
        z = v3_sub(look, pos);
    }
    if (jget_vec3(c, v, w, "up", y, &y) || jget_vec3(c, v, w, "x_axis", x, &x) ||
        jget_vec3(c, v, w, "y_axis", y, &y) || jget_vec3(c, v, w, "z_axis", z, &z))
        return -1;
    if ((ex && v3_len(x) == 0) || (ey && v3_len(y) == 0) || (ez && v3_len(z) == 0))
        return jfail(c, w, NULL, "an axis has zero length (look_at equal to position?)");
    switch ((ez ? 4 : 0) + (ey ? 2 : 0) + (ex ? 1 : 0)) {
    case 1: gram_schmidt(&x, &z, &y); break;
    case 2: gram_schmidt(&y, &z, &x); break;
    case 3: gram_schmidt(&y, &x, &z); break;
    case 5: gram_schmidt(&z, &x, &y); break;
    default: gram_schmidt(&z, &y, &x); break;
    }
    if (!v3_is_finite(x) || !v3_is_finite(y) || !v3_is_finite(z) || v3_len(v3_cross(x, y)) < 1e-12)
        return jfail(c, w, NULL, "the axes are parallel (up parallel to the viewing direction?)");
    if (v3_dot(v3_cross(x, y), z) < 0.0) {
        if (!ex) x = v3_neg(x);
        else if (!ey) y = v3_neg(y);
        else z = v3_neg(z);
    }
    if (jget_vec3(c, v, w, "scale", v3s(1), &scale)) return -1;
    x = v3_scale(x, scale.x);
    y = v3_scale(y, scale.y);
    z = v3_scale(z, scale.z);
    if ((jget_item(c, v, "rotation") != NULL)) {
        if (jget_vec3(c, v, w, "rotation", v3s(0), &rot)) return -1;
        x = rot_yxz(rot, x);
        y = rot_yxz(rot, y);
        z = rot_yxz(rot, z);
    }
    out->x = x;
    out->y = y;
    out->z = z;
    out->pos = pos;
    jnote_unread_keys(c, v, w, mark);
    return 0;
}
