/* Camera-side control vertices (ours, issue 52; docs/darts.md §5.5): the point of a vertex's equal-time
 * ellipsoid drawn by its direction from the camera instead of from the vertex. The ellipsoid of residual T
 * has foci x and cam, C = |cam − x|; from the camera focus along the unit direction φ its point is at
 *   ρ = (T² − C²)/(2(T − C·cosφ')),  cosφ' = φ·(x − cam)/C = −φ·e     (paper eq. 19 from the other focus),
 * and the vertex reaches it after t = T − ρ. With φ uniform over the (widened) film, the points are spread
 * over what the camera sees with a density ∝ 1/ρ², the camera's own importance; light paths that come close
 * to the camera, rare for the vertex-side sampler, then leave many small photons there instead of a few
 * large ones. In volume measure, with p_T the residual's density:
 *   p(y) = p_φ(φ)·p_T(T) / (ρ²·dρ/dT),  dρ/dT = t/(T − C·cosφ') = 2ρt/(T² − C²)  at fixed φ,
 * so p(y) = p_φ·p_T·(T² − C²)/(2ρ³t). The photon pass combines it with the vertex-side control vertex (whose
 * density in volume measure is p_ω(ω)·p(t)/t²) by the balance heuristic. */
#include "dartspp/darts.h"

int camera_film_init(camera_film *f, const camera *c, double margin)
{
    *f = (camera_film){0};
    if (c->type != CAMERA_PINHOLE || !(c->plane_dist > 0.0) || c->width <= 0 || c->height <= 0) return 0;
    f->right = c->right, f->up = c->up, f->forward = c->forward;
    f->plane_dist = c->plane_dist;
    /* the image plane spans x ∈ [−1, 1], y ∈ [−h/w, h/w] (camera_ray_dir) */
    f->half_x = 1.0 + margin;
    f->half_y = (double)c->height / c->width * (1.0 + margin);
    f->share = 1.0;
    f->on = 1;
    return 1;
}

/* Solid-angle density of a direction through the film point at distance `dist` from the pinhole: uniform on
 * the film (area 4·half_x·half_y at plane_dist), dω = plane_dist·dA/dist³. */
static double film_density(const camera_film *f, double dist)
{
    return dist * dist * dist / (4.0 * f->half_x * f->half_y * f->plane_dist);
}

vec3 camera_film_direction(const camera_film *f, double u1, double u2, double *pdf)
{
    double a = (2.0 * u1 - 1.0) * f->half_x, b = (2.0 * u2 - 1.0) * f->half_y;
    vec3 p = v3_add(v3_add(v3_scale(f->right, a), v3_scale(f->up, b)), v3_scale(f->forward, f->plane_dist));
    double dist = v3_len(p);
    *pdf = film_density(f, dist);
    return v3_scale(p, 1.0 / dist);
}

double camera_film_direction_pdf(const camera_film *f, vec3 w)
{
    double c = v3_dot(w, f->forward);
    if (!f->on || !(c > 0.0)) return 0.0;
    double a = f->plane_dist * v3_dot(w, f->right) / c, b = f->plane_dist * v3_dot(w, f->up) / c;
    if (!(fabs(a) <= f->half_x && fabs(b) <= f->half_y)) return 0.0;
    return film_density(f, f->plane_dist / c);
}

/* p(y) = p_φ·p_T·(T² − C²)/(2ρ³t) (header comment) */
static double camera_cv_density(double p_phi, double p_T, double T, double C, double rho, double t)
{
    double v = p_phi * p_T * (T - C) * (T + C) / (2.0 * rho * rho * rho * t);
    return isfinite(v) && v > 0.0 ? v : 0.0;
}

/* The share of the samples at distance ρ from the camera that are kept: share·min(1, (ρ/ρ_thin)²). A photon at ρ
 * covers ∝ 1/ρ² pixels of the film, so the quadratic share holds a sample's expected sensor-pass cost to at
 * most that of one at ρ_thin (docs/darts.md §5.5). */
static double kept_share(const camera_film *f, double rho)
{
    double q = f->thin > 0.0 && rho < f->thin ? rho / f->thin : 1.0;
    return f->share * q * q;
}

int camera_control_vertex(const ellipse_record *r, const camera_film *f, double u1, double u2, double u3, vec3 *y,
                          double *pdf_v)
{
    if (!f->on || !r->valid || !(r->C > 0.0)) return 0;
    double p_phi;
    vec3 phi = camera_film_direction(f, u1, u2, &p_phi);
    double T = r->T, C = r->C;
    double den = T + C * v3_dot(phi, r->e);         /* T − C·cosφ' >= T − C > 0 */
    double rho = 0.5 * (T - C) * (T + C) / den;     /* eq. 19 from the camera focus */
    double t = T - rho;                             /* >= (T − C)/2 > 0 */
    double keep = kept_share(f, rho);
    if (!(rho > 0.0) || !(t > 0.0) || !(u3 < keep)) return 0;
    vec3 cam = v3_add(r->x, v3_scale(r->e, C));
    *y = v3_add(cam, v3_scale(phi, rho));
    *pdf_v = keep * camera_cv_density(p_phi, 1.0 / r->inv_pdf_T, T, C, rho, t);
    return *pdf_v > 0.0;
}

double camera_control_vertex_pdf(const ellipse_record *r, const camera_film *f, vec3 y, residual_sampling mode,
                                 double sigma)
{
    if (!f->on || !r->valid || !(r->C > 0.0)) return 0.0;
    vec3 cam = v3_add(r->x, v3_scale(r->e, r->C));
    vec3 from_cam = v3_sub(y, cam);
    double rho = v3_len(from_cam), t = v3_len(v3_sub(y, r->x));
    if (!(rho > 0.0) || !(t > 0.0)) return 0.0;
    double p_phi = camera_film_direction_pdf(f, v3_scale(from_cam, 1.0 / rho));
    if (!(p_phi > 0.0)) return 0.0;
    double S = t + rho;
    return kept_share(f, rho) * camera_cv_density(p_phi, ellipse_residual_pdf(r, S, mode, sigma), S, r->C, rho, t);
}
