/* DA distance sampling (docs/darts.md §6; paper §4.3): free-flight surface/medium decision, then resampled
 * importance sampling of the medium distance with a diffusion-approximation target around the camera.
 * The cost (docs/darts.md §6.5): the candidates' distances are exact (double, log1p), the target is evaluated
 * in float with a polynomial exponential, the selection probabilities and the weight both use those same
 * target values, and thin segments get fewer candidates (a count fixed before any candidate is drawn).
 * Written by hand: no library offers RIS with this target. */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "dartspp/darts.h"

#define M_MAX 8
#define M_THIN 4
#define TABLE_ROWS 32
/* the optical depth σt_c·min(t_max, t_R) of the segment's reachable part below which M_THIN candidates are
 * drawn (docs/darts.md §6.5: measured on the fog Cornell box) */
#define THIN_DEPTH 0.5

/* Candidate uniforms: row r of the table holds one point in each M-th of [0, 1); a random row and a random
 * rotation (mod 1) make every candidate uniform on its own while the M stay spread out (paper §4.3.3).
 * Offsets inside the strata: the additive recurrence frac((r·M + j)·φ), φ the golden ratio conjugate. */
static double candidate_uniform(int row, int j, int M, double rotation)
{
    double k = (row * M + j) * 0.6180339887498949;
    double offset = k - floor(k);
    double u = (j + offset) / M + rotation;
    return u >= 1.0 ? u - 1.0 : u;
}

/* 2^y for y <= 0 in float (docs/darts.md §6.5), relative error below 4e-6 (3.4e-6 at most over 2·10^7
 * points of [−126, 0]): 2^⌊y⌋ by the exponent bits, 2^f on [0, 1) as √2·e^{(f − 1/2)·ln 2} by its Taylor
 * polynomial of degree 5. 0 below 2^−126. Only the resampling target uses it: any target > 0 where the
 * integrand is keeps RIS unbiased. */
static float exp2_neg(float y)
{
    if (!(y > -126.0f)) return 0.0f;
    float fl = floorf(y), g = (y - fl - 0.5f) * 0.69314718f;
    float p = 1.0f + g * (1.0f + g * (0.5f + g * (1.0f / 6.0f + g * (1.0f / 24.0f + g * (1.0f / 120.0f)))));
    uint32_t bits = (uint32_t)((int32_t)fl + 127) << 23;
    float scale;
    memcpy(&scale, &bits, sizeof scale);
    return 1.41421356f * p * scale;
}

/* σs·e^{−σt·t}·ris/(q(t)·α) with q·α = σt_c·e^{−σt_c·t}, written as σs·e^{−(σt − σt_c)t}/σt_c so that far
 * distances give no 0/0; a non-finite weight (only possible where nothing can reach the bin) becomes 0. */
static vec3 medium_weight(const medium *m, int c, double t, double ris)
{
    double st_c = v3_comp(m->sigma_t, c);
    vec3 w;
    for (int i = 0; i < 3; i++) {
        double dst = v3_comp(m->sigma_t, i) - st_c;
        double wi = v3_comp(m->sigma_s, i) * (dst == 0.0 ? 1.0 : exp(-dst * t)) * ris / st_c;
        *(i == 0 ? &w.x : i == 1 ? &w.y : &w.z) = isfinite(wi) ? wi : 0.0;
    }
    return w;
}

/* The candidate count of a segment, fixed before its candidates are drawn: M_THIN where the reachable part
 * [0, min(t_max, t_R)) is optically thin, so the candidates are close to uniform there and the target
 * varies little, else M_MAX. t_R: where the straight line to the camera leaves the reachable set. */
static int candidate_count(const ellipse_record *r, vec3 d, double st, double tmax)
{
    double tR = darts_reach_along(r->S_reach, r->C, r->C > 0.0 ? v3_dot(d, r->e) : 0.0);
    return st * dp_fmin(tmax, tR) < THIN_DEPTH ? M_THIN : M_MAX;
}

/* The candidates' targets (scaled): Φ(s, ℓ) = (4Ds)^{−3/2}·exp(−ℓ²/(4Ds) − σa·s), the DA Green's function of a
 * point source up to constants that cancel in RIS (paper eq. 9). Reachability compares squares (ℓ < s ⇔ ℓ² <
 * s², s > 0). The values are scaled by the largest exponent and the smallest 4Ds (RIS is scale-free) so that
 * none overflows and the largest exponential is 1, evaluated in float, and floored at FLT_MIN where reachable:
 * w_j > 0 exactly on the candidates that can still reach the bin. Returns the number of those. */
static int candidate_targets(const ellipse_record *r, const double *t_c, int M, double perp2, double p_proj,
                             double D, double sa, float *w)
{
    double x[M_MAX], x_min = INFINITY;
    float expo[M_MAX], expo_max = -FLT_MAX;
    int valid = 0;
    for (int j = 0; j < M; j++) {
        double t = t_c[j], dp = p_proj - t;
        double ell2 = perp2 + dp * dp, s = 0.0, sT = r->T - t, sR = r->S_reach - t;
        if (r->valid && sT > 0.0 && sT * sT > ell2) s = sT;   /* causal for the sampled residual */
        else if (sR > 0.0 && sR * sR > ell2) s = sR;          /* reachable only later in the bin */
        x[j] = 4.0 * D * s;
        if (!(x[j] > 0.0) || !isfinite(x[j])) {
            x[j] = 0.0;
            continue;
        }
        double e = -ell2 / x[j] - sa * s;
        expo[j] = e > -FLT_MAX ? (float)e : -FLT_MAX;
        if (x[j] < x_min) x_min = x[j];
        if (expo[j] > expo_max) expo_max = expo[j];
        valid++;
    }
    for (int j = 0; j < M; j++) {
        if (!(x[j] > 0.0)) {
            w[j] = 0.0f;
            continue;
        }
        float ratio = (float)(x_min / x[j]); /* (4Ds_min/4Ds)^{3/2} <= 1 */
        float v = ratio * sqrtf(ratio) * exp2_neg((expo[j] - expo_max) * 1.44269504f);
        w[j] = v > FLT_MIN ? v : FLT_MIN;
    }
    return valid;
}

/* Defensive selection: P_j = (1 − ε)·w_j/W + ε/valid over the reachable candidates, key in (0, 1]. Returns the
 * pick and its P_j, the value the weight 1/(M·P_j) uses. */
static int select_candidate(const float *w, int M, int valid, double eps, double key, double *P)
{
    double W = 0.0, acc = 0.0;
    for (int j = 0; j < M; j++) W += w[j];
    int pick = -1;
    for (int j = 0; j < M; j++) {
        if (!(w[j] > 0.0f)) continue;
        pick = j;
        *P = (1.0 - eps) * w[j] / W + eps / valid;
        acc += *P;
        if (acc >= key) break;
    }
    return pick;
}

void da_sample_distance(const medium *m, const ellipse_record *r, vec3 d, double tmax, double defensive, dp_rng *rng,
                        da_sample *out)
{
    *out = (da_sample){0};
    int c = (int)(rng_uniform(rng) * 3.0);
    if (c > 2) c = 2;
    double st = v3_comp(m->sigma_t, c), ss = v3_comp(m->sigma_s, c), sa = v3_comp(m->sigma_a, c);
    /* medium iff a free flight of rate σt_c ends before tmax: u < α = 1 − e^{−σt_c·tmax} (paper eq. 12) */
    double alpha = !(st > 0.0) ? 0.0 : isfinite(tmax) ? -expm1(-st * tmax) : 1.0;
    if (!(rng_uniform(rng) < alpha)) { /* surface event (or escape): P_surf = avg_c e^{−σt_c·tmax} */
        out->t = tmax;
        vec3 tr = isfinite(tmax) ? v3_exp_neg(v3_scale(m->sigma_t, tmax)) : v3s(0.0);
        double p = v3_avg(tr);
        out->weight = p > 0.0 ? v3_scale(tr, 1.0 / p) : v3s(0.0);
        return;
    }
    out->medium_event = 1;
    double D = 1.0 / (3.0 * (sa + ss * (1.0 - (m->phase.type == PHASE_ISOTROPIC ? 0.0 : m->phase.g))));
    double p_proj = r->C * v3_dot(d, r->e);                  /* (cam − x)·ω */
    double perp2 = dp_fmax(0.0, r->C * r->C - p_proj * p_proj); /* squared distance of the camera to the ray */
    int M = candidate_count(r, d, st, tmax);
    int row = (int)(rng_uniform(rng) * TABLE_ROWS);
    if (row >= TABLE_ROWS) row = TABLE_ROWS - 1;
    double rot = rng_uniform(rng), t_c[M_MAX];
    for (int j = 0; j < M; j++) {
        double t = -log1p(-candidate_uniform(row, j, M, rot) * alpha) / st; /* truncated exponential on [0, tmax) */
        t_c[j] = t < tmax ? t : nextafter(tmax, 0.0);
    }
    float w[M_MAX];
    int valid = candidate_targets(r, t_c, M, perp2, p_proj, D, sa, w);
    if (!valid) { /* nothing reachable: keep candidate 0 with its exponential weight σs e^{−σt t}/(q·α) */
        out->fallback = 1;
        out->t = t_c[0];
        out->weight = medium_weight(m, c, t_c[0], 1.0);
        return;
    }
    /* With the weight 1/(M·P_j) the estimate is unbiased for any P_j > 0 wherever a contribution is possible
     * (E = (1/M)Σ_j E[f(t_j)/q(t_j)]); ε bounds it: 1/(M·P_j) <= valid/(M·ε) <= 1/ε. Plain RIS (ε = 0) has
     * P_j = w_j/W: a candidate with a tiny target is picked rarely but then carries W/(M·w_j). */
    double P = 0.0;
    int pick = select_candidate(w, M, valid, defensive, 1.0 - rng_uniform(rng), &P);
    /* RIS (docs/reference-renderer.md §5.3 step 10 when ε = 0): σs e^{−σt t}/(α·q(t)) × 1/(M·P_pick) */
    out->t = t_c[pick];
    out->weight = medium_weight(m, c, t_c[pick], 1.0 / (M * P));
}
