/* Direction sampling helpers and orthonormal bases. */
#include "dartspp/core.h"

void v3_basis(vec3 n, vec3 *s, vec3 *t)
{
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    *s = v3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *t = v3(b, sign + n.y * n.y * a, -n.y);
}

vec3 sample_uniform_sphere(double u1, double u2)
{
    double z = 1.0 - 2.0 * u1;
    double r = sqrt(dp_fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * M_PI * u2;
    return v3(r * cos(phi), r * sin(phi), z);
}

vec3 sample_cosine_hemisphere(double u1, double u2)
{
    double r = sqrt(u1);
    double phi = 2.0 * M_PI * u2;
    return v3(r * cos(phi), r * sin(phi), sqrt(dp_fmax(0.0, 1.0 - u1)));
}

vec3 sample_cosine_about(vec3 n, double u1, double u2)
{
    vec3 l = sample_cosine_hemisphere(u1, u2), t1, t2;
    v3_basis(n, &t1, &t2);
    return v3_norm(v3_add(v3_add(v3_scale(t1, l.x), v3_scale(t2, l.y)), v3_scale(n, l.z)));
}
