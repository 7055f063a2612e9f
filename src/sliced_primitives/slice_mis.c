/* Score-based MIS of sliced balls and parallelepipeds (Liu et al. 2022 §4.6) for mis_volumes_balls. Each
 * unbiased estimator of the same path integral divides the path's contribution by q = p·|J|: p the density of
 * its numerically sampled dimensions, |J| that of g′ over its analytic ones, both in the same measure (solid
 * angle for directions, length for distances). For a path x3 → x2 → x1 → x0 the two share the density of ω3 and
 * of the light subpath up to x3; what differs: the ball drew t3 and t2 by free flight (and ω2 by the phase
 * function at x2), the parallelepiped drew ω2 and ω1 by the phase function. The ω2 factor is taken as the same
 * in both and cancels, so q_ball = p_d(t3)·p_d(t2)·|J_ball| and q_pp = f_p(ω2 → ω1)·|J_pp|. Any function of the
 * path gives weights summing to 1 as long as both estimators evaluate the same one: slice_mis_weight is that
 * function, called by both. */
#include "dartspp/sliced_primitives.h"

#include "slice_geometry.h"

/* The free-flight density of a distance t in medium m as the photon pass draws it: a channel picked uniformly
 * (spectral MIS), so the mean over channels of σt e^{−σt t} (σt e^{−σt t} in a grey medium). */
static double free_flight_pdf(const scene *s, int m, double t)
{
    if (m == MEDIUM_VACUUM) return 0.0;
    vec3 st = s->media[m].sigma_t;
    return v3_avg(v3_mul(st, v3_exp_neg(v3_scale(st, t))));
}

double slice_mis_weight(const scene *s, int ball, double t3, double t2, double t1, const vec3 w[3], int m2, int m1,
                        vec3 psi, double eta_p, double eta_c)
{
    double jb = slice_ball_jacobian(t1, w[2], psi, eta_p, eta_c);
    double jp = slice_parallelepiped_jacobian(w, psi, eta_p, eta_c);
    double qb = free_flight_pdf(s, m2, t3) * free_flight_pdf(s, m1, t2) * jb;
    double qp = m1 == MEDIUM_VACUUM ? 0.0 : phase_eval(&s->media[m1].phase, w[1], w[2]) * jp;
    double sum = qb + qp;
    if (!(sum > 0.0) || !isfinite(sum)) return ball ? 1.0 : 0.0; /* still 1 in all */
    return (ball ? qb : qp) / sum;
}
