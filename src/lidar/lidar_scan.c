/* The scan geometry of the lidar camera (docs/lidar.md §1): the beam of each channel and azimuth step, and the
 * receiver's directions about it (docs/lidar.md §3). */
#include <math.h>

#include "dartspp/lidar.h"

double lidar_channel_elevation(const lidar_params *l, int c)
{
    if (l->channels <= 1) return l->elevation[0];
    return l->elevation[0] + (l->elevation[1] - l->elevation[0]) * c / (double)(l->channels - 1);
}

double lidar_step_azimuth(const lidar_params *l, int a)
{
    return l->azimuth[0] + (l->azimuth[1] - l->azimuth[0]) * (a + 0.5) / (double)l->azimuth_steps;
}

/* cos(el)·(cos(az)·forward + sin(az)·left) + sin(el)·up: azimuth counter-clockwise about up (docs/lidar.md §1) */
vec3 lidar_beam_dir(const lidar_params *l, vec3 forward, vec3 left, vec3 up, int c, int a)
{
    double el = lidar_channel_elevation(l, c), az = lidar_step_azimuth(l, a);
    vec3 h = v3_add(v3_scale(forward, cos(az)), v3_scale(left, sin(az)));
    return v3_norm(v3_add(v3_scale(h, cos(el)), v3_scale(up, sin(el))));
}

/* Cosine-weighted in the cone of half-angle θ_r (Malley's method on the disc of radius sin θ_r): a point
 * uniform on that disc lifted to the sphere has density cosθ/(π sin²θ_r) in solid angle. */
vec3 lidar_receiver_dir(const lidar_params *l, vec3 b, double u1, double u2)
{
    double sr = sin(0.5 * l->receiver_fov), rho = sr * sqrt(u1), phi = 2.0 * M_PI * u2;
    double x = rho * cos(phi), y = rho * sin(phi), z = sqrt(fmax(0.0, 1.0 - rho * rho));
    vec3 s, t;
    v3_basis(b, &s, &t);
    return v3_norm(v3_add(v3_scale(b, z), v3_add(v3_scale(s, x), v3_scale(t, y))));
}

/* ∫_cone cosθ dω = π sin²θ_r: the film's mean of L under lidar_receiver_dir times this is ∫ L cosθ dω */
double lidar_receiver_etendue(const lidar_params *l)
{
    double sr = sin(0.5 * l->receiver_fov);
    return M_PI * sr * sr;
}

void lidar_beam_set(emitter *e, vec3 axis)
{
    e->axis = axis;
    v3_basis(axis, &e->e1, &e->e2);
}
