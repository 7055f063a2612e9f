/* Directions toward the next elliptical connection (ours; docs/darts.md §14.3). At a vertex x with the target
 * (the light) at x_L, C = |x_L − x|, e = (x_L − x)/C, and the residual T > C of the next segment's control
 * vertex, the control vertex x + tω's light connection (docs/darts.md §5.1–5.2; ℓ = T − t its light leg,
 * p(t) = p(T)(T − C cosθ)/ℓ) carries
 *   1/(p(t)·ℓ²) = 1/(p(T)(T − C cosθ)ℓ) = 2/(p(T)·(T² + C² − 2TC cosθ)),
 * as ℓ = (T² + C² − 2TC cosθ)/(2(T − C cosθ)); its two transmittances make e^{−σt·T}, the same for every ω,
 * and only the two phase functions and visibility are left out. So ω is drawn with density ∝ 1/(a − bμ),
 * a = T² + C², b = 2TC, μ = cosθ, φ uniform about e:
 *   ∫ dω/(a − bμ) = 2π·(1/b)·ln((a + b)/(a − b)) = 2πλ/(TC),  λ = ln((T + C)/(T − C)),
 *   p(ω) = TC/(2πλ·(a − bμ)),  a − bμ = (T − C)² + 2TC(1 − μ) = |Tω − C e|².
 * Inverse CDF: F(μ) = ln((T + C)²/(a − bμ))/(2λ) = u gives a − bμ = (T + C)² e^{−2λu}, i.e.
 *   1 − μ = (T − C)²·expm1(2λ(1 − u))/(2TC),
 * exact at small angles (u → 1) and uniform in μ as C/T → 0. */
#include "dartspp/darts.h"

#define ED_NEAR 1e-6  /* T <= C(1 + ED_NEAR): the density's peak ~ 1/(T − C)² is left to the phase function */
#define ED_SPHERE 1e-9 /* C <= ED_SPHERE·T: the density is uniform to that precision (C = 0: the sphere) */

/* The geometry of one vertex: e, C, T and λ; sphere when C is negligible. */
typedef struct {
    vec3 e;
    double C, T, lambda;
    int sphere;
} ed_geometry;

/* Fills g; returns 0 where the sampler does not run (T <= C(1 + ED_NEAR), or not finite). */
static int ed_setup(vec3 x, vec3 target, double T, ed_geometry *g)
{
    vec3 l = v3_sub(target, x);
    g->C = v3_len(l);
    g->T = T;
    if (!isfinite(T) || !isfinite(g->C) || !(T > 0.0)) return 0;
    g->sphere = !(g->C > ED_SPHERE * T);
    if (g->sphere) {
        g->e = v3(0, 0, 1);
        return 1;
    }
    if (!(T > g->C * (1.0 + ED_NEAR))) return 0;
    g->e = v3_scale(l, 1.0 / g->C);
    g->lambda = log1p(2.0 * g->C / (T - g->C)); /* ln((T + C)/(T − C)) */
    return g->lambda > 0.0;
}

/* p(ω) for a − bμ = q (header comment). */
static double ed_density(const ed_geometry *g, double q)
{
    if (g->sphere) return DP_INV_4PI;
    return q > 0.0 ? g->T * g->C / (2.0 * M_PI * g->lambda * q) : 0.0;
}

int ellipse_direction_usable(vec3 x, vec3 target, double T)
{
    ed_geometry g;
    return ed_setup(x, target, T, &g);
}

int ellipse_direction_sample(vec3 x, vec3 target, double T, double u1, double u2, vec3 *w, double *pdf)
{
    ed_geometry g;
    if (!ed_setup(x, target, T, &g)) return 0;
    double m; /* 1 − cosθ */
    if (g.sphere) {
        m = 2.0 * u1;
    } else {
        double d = g.T - g.C;
        m = d * d * expm1(2.0 * g.lambda * (1.0 - u1)) / (2.0 * g.T * g.C);
    }
    m = dp_fmin(2.0, dp_fmax(0.0, m));
    double cos_theta = 1.0 - m, s = sqrt(m * (2.0 - m)), phi = 2.0 * M_PI * u2;
    vec3 b1, b2;
    v3_basis(g.e, &b1, &b2);
    *w = v3_norm(v3_add(v3_scale(g.e, cos_theta), v3_add(v3_scale(b1, s * cos(phi)), v3_scale(b2, s * sin(phi)))));
    *pdf = ellipse_direction_pdf(x, target, T, *w);
    return *pdf > 0.0 && isfinite(*pdf);
}

double ellipse_direction_pdf(vec3 x, vec3 target, double T, vec3 w)
{
    ed_geometry g;
    if (!ed_setup(x, target, T, &g)) return 0.0;
    if (g.sphere) return DP_INV_4PI;
    vec3 dw = v3_sub(w, g.e); /* 2(1 − μ) = |ω − e|², no cancellation near θ = 0 */
    double d = g.T - g.C;
    return ed_density(&g, d * d + g.T * g.C * v3_dot(dw, dw));
}
