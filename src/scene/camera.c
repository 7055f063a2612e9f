/* Camera rays: Tungsten's PinholeCamera (horizontal fov, image plane x in [-1, 1]) and OrthographicCamera
 * (parallel rays from a film of 2·orthographic_size in height, in the plane through the camera's position). */
#include "dartspp/scene.h"

vec3 camera_ray_dir(const camera *c, double px, double py)
{
    if (c->type == CAMERA_ORTHOGRAPHIC) return c->forward;
    double sx = 2.0 / c->width;
    double x = -1.0 + px * sx;
    double y = (double)c->height / c->width - py * sx;
    vec3 d = v3_add(v3_add(v3_scale(c->right, x), v3_scale(c->up, y)), v3_scale(c->forward, c->plane_dist));
    return v3_norm(d);
}

/* Tungsten's OrthographicCamera::samplePosition(pixel): with vertical half size v and horizontal half size
 * h = v·width/height, the film point of (px, py) is (−h + px·a, v − py·a) along (right, up), a = 2v/height the
 * pixel's side; x grows to the right and y downwards, as for the pinhole. */
static vec3 ortho_origin(const camera *c, double px, double py)
{
    double a = camera_ortho_pixel(c);
    double h = c->ortho_size * c->width / c->height;
    double x = -h + px * a, y = c->ortho_size - py * a;
    return v3_add(c->pos, v3_add(v3_scale(c->right, x), v3_scale(c->up, y)));
}

vec3 camera_ray(const camera *c, double px, double py, vec3 *o)
{
    *o = c->type == CAMERA_ORTHOGRAPHIC ? ortho_origin(c, px, py) : c->pos;
    return camera_ray_dir(c, px, py);
}

double camera_distance(const camera *c, vec3 p)
{
    vec3 w = v3_sub(p, c->pos);
    return c->type == CAMERA_ORTHOGRAPHIC ? fabs(v3_dot(w, c->forward)) : v3_len(w);
}
