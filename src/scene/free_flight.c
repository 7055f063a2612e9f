/* Free-flight distance sampling in a homogeneous medium with per-channel σt (spectral one-sample MIS). */
#include "dartspp/scene.h"

static int is_grey(const medium *m) { return m->sigma_t.x == m->sigma_t.y && m->sigma_t.y == m->sigma_t.z; }

/* Grey σt (the same in every channel, as in most fog scenes): t ~ σt e^{−σt t}, so the weight of a medium
 * event is σs/σt and that of passing tmax is 1; no channel choice and no exponential needed. */
int medium_free_flight_grey(const medium *m, dp_rng *rng, double *t)
{
    if (!is_grey(m)) return 0;
    double st = m->sigma_t.x;
    *t = st > 0.0 ? -log1p(-rng_uniform(rng)) / st : INFINITY;
    return 1;
}

vec3 medium_grey_event_beta(const medium *m, vec3 beta) { return v3_scale(v3_mul(beta, m->sigma_s), 1.0 / m->sigma_t.x); }

double medium_sample_free_flight(const medium *m, double tmax, dp_rng *rng, vec3 *beta, int *event)
{
    double tg;
    if (medium_free_flight_grey(m, rng, &tg)) {
        *event = tg < tmax;
        if (!*event) return tmax;
        *beta = medium_grey_event_beta(m, *beta);
        return tg;
    }
    int ch = (int)(rng_uniform(rng) * 3.0);
    double st = v3_comp(m->sigma_t, ch > 2 ? 2 : ch);
    double t = st > 0.0 ? -log1p(-rng_uniform(rng)) / st : INFINITY;
    *event = t < tmax;
    double dist = *event ? t : tmax;
    vec3 tr = v3_exp_neg(v3_scale(m->sigma_t, dist));
    if (*event) {
        double pdf = v3_avg(v3_mul(m->sigma_t, tr)); /* mean over channels of σt e^{-σt t} */
        *beta = pdf > 0.0 ? v3_scale(v3_mul(*beta, v3_mul(m->sigma_s, tr)), 1.0 / pdf) : v3s(0);
    } else {
        double p = v3_avg(tr); /* probability of passing tmax */
        *beta = p > 0.0 ? v3_scale(v3_mul(*beta, tr), 1.0 / p) : v3s(0);
    }
    return dist;
}
