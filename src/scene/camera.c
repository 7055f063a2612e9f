/* Pinhole camera rays (Tungsten PinholeCamera): horizontal fov, image plane x in [-1, 1]. */
#include "dartspp/scene.h"

vec3 camera_ray_dir(const camera *c, double px, double py)
{
    double sx = 2.0 / c->width;
    double x = -1.0 + px * sx;
    double y = (double)c->height / c->width - py * sx;
    vec3 d = v3_add(v3_add(v3_scale(c->right, x), v3_scale(c->up, y)), v3_scale(c->forward, c->plane_dist));
    return v3_norm(d);
}
