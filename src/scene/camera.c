/* Camera rays: Tungsten's PinholeCamera (horizontal fov, image plane x in [-1, 1]), OrthographicCamera
 * (parallel rays from a film of 2·orthographic_size in height, in the plane through the camera's position) and
 * the lidar's receiver (a cone about each beam, docs/lidar.md §3). */
#include <math.h>

#include "dartspp/scene.h"

/* Pixel (x, y) of a lidar is beam (channel height − 1 − y, azimuth step x); the fraction of (px, py) inside the
 * pixel draws the receiver's direction in its cone (docs/lidar.md §1). */
static vec3 lidar_ray_dir(const camera *c, double px, double py)
{
    double fx = floor(px), fy = floor(py);
    int x = (int)fmin(fmax(fx, 0.0), c->width - 1), y = (int)fmin(fmax(fy, 0.0), c->height - 1);
    return lidar_receiver_dir(&c->lidar, camera_lidar_beam(c, x, y), px - fx, py - fy);
}

vec3 camera_lidar_beam(const camera *c, int x, int y)
{
    return lidar_beam_dir(&c->lidar, c->forward, v3_neg(c->right), c->up, c->height - 1 - y, x);
}

vec3 camera_ray_dir(const camera *c, double px, double py)
{
    if (c->type == CAMERA_ORTHOGRAPHIC) return c->forward;
    if (c->type == CAMERA_LIDAR) return lidar_ray_dir(c, px, py);
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
