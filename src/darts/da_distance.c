/* DA distance sampling (docs/darts.md §6; paper §4.3): free-flight surface/medium decision, then resampled
 * importance sampling of the medium distance with a diffusion-approximation target around the camera.
 * Written by hand: no library offers RIS with this target. */
#include "dartspp/darts.h"

#define M_CAND 8
#define TABLE_ROWS 32

/* Candidate uniforms: row r of the table holds one point in each eighth of [0, 1); a random row and a random
 * rotation (mod 1) make every candidate uniform on its own while the eight stay spread out (paper §4.3.3).
 * Offsets inside the strata: the additive recurrence frac((r·8 + j)·φ), φ the golden ratio conjugate. */
static double candidate_uniform(int row, int j, double rotation)
{
    double k = (row * M_CAND + j) * 0.6180339887498949;
    double offset = k - floor(k);
    double u = (j + offset) / M_CAND + rotation;
    return u >= 1.0 ? u - 1.0 : u;
}

/* Φ(s, ℓ) = (4Ds)^{−3/2}·exp(−ℓ²/(4Ds) − σa·s), the DA Green's function of a point source up to constants
 * that cancel in RIS (paper eq. 9), split as amplitude × exp(exponent): the weights are formed as
 * amplitude_j·exp(exponent_j − max exponent), which never underflows to all zeros in thick media (the
 * largest term keeps exp(0) = 1) and needs no logarithm. */
static double phi_exponent(double s, double ell2, double D, double sigma_a, double *amplitude)
{
    double fourDs = 4.0 * D * s;
    *amplitude = 1.0 / (fourDs * sqrt(fourDs));
    return -ell2 / fourDs - sigma_a * s;
}

/* σs·e^{−σt·t}·ris/(q(t)·α) with q·α = σt_c·e^{−σt_c·t}, written as σs·e^{−(σt − σt_c)t}/σt_c so that far
 * distances give no 0/0; a non-finite weight (only possible where nothing can reach the bin) becomes 0. */
static vec3 medium_weight(const medium *m, int c, double t, double ris)
{
    double st_c = v3_comp(m->sigma_t, c);
    vec3 w;
    for (int i = 0; i < 3; i++) {
        double wi = v3_comp(m->sigma_s, i) * exp(-(v3_comp(m->sigma_t, i) - st_c) * t) * ris / st_c;
        *(i == 0 ? &w.x : i == 1 ? &w.y : &w.z) = isfinite(wi) ? wi : 0.0;
    }
    return w;
}

void da_sample_distance(const medium *m, const ellipse_record *r, vec3 d, double tmax, double defensive, dp_rng *rng,
                        da_sample *out)
{
    *out = (da_sample){0};
    int c = (int)(rng_uniform(rng) * 3.0);
    if (c > 2) c = 2;
    double st = v3_comp(m->sigma_t, c), ss = v3_comp(m->sigma_s, c), sa = v3_comp(m->sigma_a, c);
    double t0 = st > 0.0 ? -log1p(-rng_uniform(rng)) / st : INFINITY;
    if (t0 >= tmax) { /* surface event (or escape): P_surf = avg_c e^{−σt_c·tmax} */
        out->t = tmax;
        vec3 tr = isfinite(tmax) ? v3_exp_neg(v3_scale(m->sigma_t, tmax)) : v3s(0.0);
        double p = v3_avg(tr);
        out->weight = p > 0.0 ? v3_scale(tr, 1.0 / p) : v3s(0.0);
        return;
    }
    out->medium_event = 1;
    double alpha = isfinite(tmax) ? -expm1(-st * tmax) : 1.0; /* P(medium | c) */
    double D = 1.0 / (3.0 * (sa + ss * (1.0 - (m->phase.type == PHASE_ISOTROPIC ? 0.0 : m->phase.g))));
    double t_c[M_CAND], expo[M_CAND], amp[M_CAND];
    int ok[M_CAND], any = 0;
    double p_proj = r->C * v3_dot(d, r->e);                  /* (cam − x)·ω */
    double perp2 = dp_fmax(0.0, r->C * r->C - p_proj * p_proj); /* squared distance of the camera to the ray */
    int row = (int)(rng_uniform(rng) * TABLE_ROWS);
    if (row >= TABLE_ROWS) row = TABLE_ROWS - 1;
    double rot = rng_uniform(rng), expo_max = -INFINITY, amp_max = 0.0;
    for (int j = 0; j < M_CAND; j++) {
        double u = candidate_uniform(row, j, rot);
        double t = -log1p(-u * alpha) / st;              /* truncated exponential on [0, tmax) */
        if (!(t < tmax)) t = nextafter(tmax, 0.0);
        t_c[j] = t;
        double ell2 = perp2 + (p_proj - t) * (p_proj - t);
        double ell = sqrt(ell2);
        double s = 0.0;
        if (r->valid && r->T - t > ell) s = r->T - t;          /* causal for the sampled residual */
        else if (r->S_reach - t > ell) s = r->S_reach - t;     /* reachable only later in the bin */
        ok[j] = s > 0.0;
        if (!ok[j]) continue;
        /* w_j = p̂/q with q(t) = σt e^{−σt t}/α: the e^{−σt t} cancels; σt and α are common factors */
        expo[j] = phi_exponent(s, ell2, D, sa, &amp[j]);
        ok[j] = isfinite(expo[j]) && isfinite(amp[j]);
        if (ok[j]) {
            any = 1;
            expo_max = dp_fmax(expo_max, expo[j]);
            amp_max = dp_fmax(amp_max, amp[j]);
        }
    }
    double w[M_CAND], W = 0.0;
    int valid = 0;
    for (int j = 0; any && j < M_CAND; j++) {
        /* scaled by amp_max·e^{max} (RIS is scale-free): every w_j <= 1, so W neither overflows nor, with
         * the largest exponent at exp(0), underflows unless Φ itself is 0 (no scattering: D infinite) */
        w[j] = ok[j] && amp_max > 0.0 ? (amp[j] / amp_max) * exp(expo[j] - expo_max) : 0.0;
        W += w[j];
        valid += w[j] > 0.0;
    }
    if (!valid) { /* nothing reachable: keep candidate 0 with its exponential weight σs e^{−σt t}/(q·α) */
        out->fallback = 1;
        out->t = t_c[0];
        out->weight = medium_weight(m, c, t_c[0], 1.0);
        return;
    }
    /* Defensive selection: P_j = (1 − ε)·w_j/W + ε/valid over the reachable candidates. With the weight
     * 1/(M·P_j) the estimate stays unbiased for any P_j > 0 wherever a contribution is possible
     * (E = (1/M)Σ_j E[f(t_j)/q(t_j)]), and ε bounds it: 1/(M·P_j) <= valid/(M·ε) <= 1/ε. Plain RIS (ε = 0)
     * has P_j = w_j/W, so a candidate with a tiny target weight is picked rarely but then carries
     * W/(M·w_j): a heavy tail, since the Gaussian factor of Φ spans many orders of magnitude. */
    double eps = defensive;
    double key = (1.0 - rng_uniform(rng)), acc = 0.0; /* key in (0, 1] */
    int pick = -1;
    double P = 0.0;
    for (int j = 0; j < M_CAND; j++) {
        if (w[j] <= 0.0) continue;
        pick = j;
        P = (1.0 - eps) * w[j] / W + eps / valid;
        acc += P;
        if (acc >= key) break;
    }
    double t = t_c[pick];
    /* RIS (docs/reference-renderer.md §5.3 step 10 when ε = 0): the medium-event weight is
     * σs e^{−σt t}/(α·q(t)) × 1/(M·P_pick) */
    double ris = 1.0 / (M_CAND * P);
    out->t = t;
    out->weight = medium_weight(m, c, t, ris);
}
