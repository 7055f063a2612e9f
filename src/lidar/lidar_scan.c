/* The scan geometry of the lidar camera (include/dartspp/lidar.h; docs/lidar.md §1, §3): the elevation and
 * azimuth of each beam, its world direction, and the receiver's directions drawn in its cone.
 *
 * Placeholder written beside the echoes and points (branch d51-echoes) so that they build and test before the
 * lidar camera lands; the lead's version of this file replaces it at the merge. It implements only what
 * lidar.h declares for the scan geometry, by the header's conventions. */
#include <math.h>

#include "dartspp/lidar.h"

double lidar_channel_elevation(const lidar_params *l, int c)
{
    if (l->channels <= 1) return l->elevation[0];
    return l->elevation[0] + (l->elevation[1] - l->elevation[0]) * (double)c / (double)(l->channels - 1);
}

double lidar_step_azimuth(const lidar_params *l, int a)
{
    return l->azimuth[0] + (l->azimuth[1] - l->azimuth[0]) * ((double)a + 0.5) / (double)l->azimuth_steps;
}

vec3 lidar_beam_dir(const lidar_params *l, vec3 forward, vec3 left, vec3 up, int c, int a)
{
    double el = lidar_channel_elevation(l, c), az = lidar_step_azimuth(l, a);
    vec3 h = v3_add(v3_scale(forward, cos(az)), v3_scale(left, sin(az)));
    return v3_norm(v3_add(v3_scale(h, cos(el)), v3_scale(up, sin(el))));
}

/* A point uniform on the disc of radius sinθ_r lifted to the unit sphere about b: density cosθ/(π sin²θ_r)
 * in solid angle (Malley's method restricted to the cone). */
vec3 lidar_receiver_dir(const lidar_params *l, vec3 b, double u1, double u2)
{
    double s = sin(0.5 * l->receiver_fov), r = s * sqrt(u1), phi = 2.0 * M_PI * u2;
    double x = r * cos(phi), y = r * sin(phi), z = sqrt(fmax(0.0, 1.0 - r * r));
    vec3 e1, e2;
    v3_basis(b, &e1, &e2);
    return v3_norm(v3_add(v3_add(v3_scale(e1, x), v3_scale(e2, y)), v3_scale(b, z)));
}

double lidar_receiver_etendue(const lidar_params *l)
{
    double s = sin(0.5 * l->receiver_fov);
    return M_PI * s * s;
}
