/* Time-angular direction sampling of the uniform-time path tracer (Jarabo et al. 2014 §5.3, corrected by the
 * DARTS supplement §B.4 eq. 21–22; docs/darts.md §13). At a vertex x with the target at x_L, l = x_L − x, and
 * a distance r drawn first, the direction ω makes the time t = r + d₂, d₂ = |x + rω − x_L|, uniform on
 *   [t_min, t_max] = [r + ||l| − r|, 2r + |l|]   (θ = 0 and θ = π, θ measured from l),
 * by eq. 21 cosθ = (|l|² + 2tr − t²)/(2|l|r) = (|l|² + r² − d₂²)/(2|l|r) and φ uniform about l. As
 * |dt/dcosθ| = |l|r/d₂, the solid-angle density is
 *   p_Ω(ω) = |l|r/(2π (t_max − t_min) d₂) = max(r, |l|)/(4π d₂)   (t_max − t_min = 2 min(r, |l|)).
 * Jarabo's eq. 16, r/(4π d₂), is this only for |l| <= r; for |l| > r it integrates to r/|l|. */
#include "dartspp/darts.h"

#define TA_EPS 1e-9 /* relative to r + |l|: below it r, |l| or the time range count as degenerate */

/* The geometry of one vertex: e = l/|l|, L = |l|, r, d₂ ∈ [d_lo, d_lo + span]. */
typedef struct {
    vec3 e;
    double L, r;
    double d_lo; /* ||l| − r| = t_min − r */
    double span; /* t_max − t_min = 2 min(r, |l|) */
} ta_geometry;

/* Fills g; returns 0 in the degenerate cases (r or |l| or the time range tiny relative to r + |l|). */
static int ta_setup(vec3 x, vec3 target, double r, ta_geometry *g)
{
    vec3 l = v3_sub(target, x);
    g->L = v3_len(l);
    g->r = r;
    double s = r + g->L;
    if (!isfinite(s) || !(r > TA_EPS * s) || !(g->L > TA_EPS * s)) return 0;
    g->e = v3_scale(l, 1.0 / g->L);
    g->d_lo = fabs(g->L - r);
    g->span = 2.0 * dp_fmin(r, g->L);
    return g->span > TA_EPS * s;
}

/* d₂ for 1 − cosθ: d₂² = |l|² + r² − 2|l|r cosθ = (|l| − r)² + 2|l|r(1 − cosθ) */
static double ta_d2(const ta_geometry *g, double one_minus_cos)
{
    return sqrt(g->d_lo * g->d_lo + 2.0 * g->L * g->r * one_minus_cos);
}

/* p_Ω = max(r, |l|)/(4π d₂) (header comment) */
static double ta_density(const ta_geometry *g, double d2)
{
    return d2 > 0.0 ? dp_fmax(g->r, g->L) * DP_INV_4PI / d2 : 0.0;
}

/* The unit direction at angle θ from e, given by m = 1 − cosθ ∈ [0, 2] (sinθ = √(m(2 − m)) keeps small angles
 * exact), and azimuth φ = 2πu about e. */
static vec3 ta_direction(vec3 e, double m, double u)
{
    double cos_theta = 1.0 - m, s = sqrt(m * (2.0 - m)), phi = 2.0 * M_PI * u;
    vec3 b1, b2;
    v3_basis(e, &b1, &b2);
    vec3 side = v3_add(v3_scale(b1, s * cos(phi)), v3_scale(b2, s * sin(phi)));
    return v3_norm(v3_add(v3_scale(e, cos_theta), side));
}

int time_angular_sample(vec3 x, vec3 target, double r, double u1, double u2, vec3 *w, double *pdf)
{
    ta_geometry g;
    if (!ta_setup(x, target, r, &g)) return 0;
    /* eq. 22: t = t_min + ξ(t_max − t_min), so d₂ = t − r = ||l| − r| + ξ·2 min(r, |l|) */
    double d2 = g.d_lo + u1 * g.span;
    if (!(d2 > 0.0)) return 0; /* r = |l| and ξ = 0: the target itself, a null set */
    /* eq. 21 with t − r = d₂, as 1 − cosθ = (d₂² − (|l| − r)²)/(2|l|r), clamped to cosθ ∈ [−1, 1] */
    double m = (d2 - g.d_lo) * (d2 + g.d_lo) / (2.0 * g.L * g.r);
    *w = ta_direction(g.e, dp_fmin(2.0, dp_fmax(0.0, m)), u2);
    *pdf = ta_density(&g, d2);
    return 1;
}

double time_angular_pdf(vec3 x, vec3 target, double r, vec3 w)
{
    ta_geometry g;
    if (!ta_setup(x, target, r, &g)) return 0.0;
    vec3 dw = v3_sub(w, g.e); /* 1 − cosθ = |w − e|²/2 for unit w, without cancellation near θ = 0 */
    double m = dp_fmin(2.0, dp_fmax(0.0, 0.5 * v3_dot(dw, dw)));
    return ta_density(&g, ta_d2(&g, m));
}

vec3 time_angular_mix_sample(const phase_function *ph, vec3 w_in, vec3 x, vec3 target, double r, double share,
                             const double u[3], double *weight)
{
    ta_geometry g;
    vec3 w;
    double p_ta;
    if (!(share > 0.0) || !ta_setup(x, target, r, &g)) {
        *weight = 1.0;
        return phase_sample(ph, w_in, u[1], u[2]);
    }
    if (u[0] >= share || !time_angular_sample(x, target, r, u[1], u[2], &w, &p_ta))
        w = phase_sample(ph, w_in, u[1], u[2]);
    double f = phase_eval(ph, w_in, w); /* = p_phase: phase sampling is exact */
    double mix = time_angular_mix_pdf(ph, w_in, x, target, r, share, w);
    *weight = mix > 0.0 ? f / mix : 0.0;
    return w;
}

double time_angular_mix_pdf(const phase_function *ph, vec3 w_in, vec3 x, vec3 target, double r, double share, vec3 w)
{
    ta_geometry g;
    double f = phase_eval(ph, w_in, w);
    if (!(share > 0.0) || !ta_setup(x, target, r, &g)) return f;
    double c = dp_fmin(1.0, share);
    return c * time_angular_pdf(x, target, r, w) + (1.0 - c) * f;
}
