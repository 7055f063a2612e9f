/* Isotropic microfacet distributions about +z: Beckmann and GGX (Walter et al. 2007, "Microfacet Models
 * for Refraction through Rough Surfaces"), and the reference's "pbrt-ggx": the same GGX D with the
 * height-correlated Smith term of pbrt-v3 (Heitz 2014). Normals are sampled from D(m)·cos θm. */
#include "bsdf_internal.h"

/* The reference clamps roughness to at least 1e-3 and uses it as alpha for all three distributions. */
double bsdf_mf_alpha(microfacet_distribution d, double roughness)
{
    (void)d;
    return dp_fmax(roughness, 1e-3);
}

double bsdf_mf_D(microfacet_distribution d, double alpha, vec3 m)
{
    if (m.z <= 0.0) return 0.0;
    double c2 = m.z * m.z, tan2 = dp_fmax(1.0 - c2, 0.0) / c2, a2 = alpha * alpha;
    double v;
    if (d == MICROFACET_BECKMANN) {
        v = exp(-tan2 / a2) / (M_PI * a2 * c2 * c2); /* Walter eq. 25 */
    } else {
        double t = a2 + tan2;
        v = a2 / (M_PI * c2 * c2 * t * t); /* Walter eq. 33 */
    }
    return bsdf_clean(v);
}

/* tan² θ of direction v against +z (∞ at grazing). */
static double tan2_theta(vec3 v)
{
    double c2 = v.z * v.z;
    return c2 > 0.0 ? dp_fmax(1.0 - c2, 0.0) / c2 : INFINITY;
}

/* Smith Λ of GGX (Heitz 2014, eq. 72): G1 = 1 / (1 + Λ). */
static double ggx_lambda(double alpha, vec3 v)
{
    double t2 = tan2_theta(v);
    if (!isfinite(t2)) return INFINITY;
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

double bsdf_mf_G1(microfacet_distribution d, double alpha, vec3 v, vec3 m)
{
    if (v3_dot(v, m) * v.z <= 0.0) return 0.0; /* χ⁺(v·m / v·n) */
    double t2 = tan2_theta(v);
    if (t2 == 0.0) return 1.0;
    if (!isfinite(t2)) return 0.0;
    if (d == MICROFACET_BECKMANN) {
        /* Walter eq. 27: rational approximation of the Smith term, a = 1 / (α tan θ) */
        double a = 1.0 / (alpha * sqrt(t2));
        if (a >= 1.6) return 1.0;
        return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
    }
    return 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * t2)); /* Walter eq. 34 */
}

double bsdf_mf_G(microfacet_distribution d, double alpha, vec3 wi, vec3 wo, vec3 m)
{
    if (d == MICROFACET_PBRT_GGX) {
        if (v3_dot(wi, m) * wi.z <= 0.0 || v3_dot(wo, m) * wo.z <= 0.0) return 0.0;
        double g = 1.0 / (1.0 + ggx_lambda(alpha, wi) + ggx_lambda(alpha, wo));
        return bsdf_clean(g);
    }
    return bsdf_mf_G1(d, alpha, wi, m) * bsdf_mf_G1(d, alpha, wo, m); /* Walter eq. 23 */
}

vec3 bsdf_mf_sample(microfacet_distribution d, double alpha, double u1, double u2)
{
    double tan2;
    if (d == MICROFACET_BECKMANN)
        tan2 = -alpha * alpha * log(1.0 - u1); /* Walter eq. 28 */
    else
        tan2 = alpha * alpha * u1 / (1.0 - u1); /* Walter eq. 35 */
    double c = 1.0 / sqrt(1.0 + tan2);
    double s = sqrt(dp_fmax(0.0, 1.0 - c * c));
    double phi = 2.0 * M_PI * u2;
    return v3(s * cos(phi), s * sin(phi), c);
}

double bsdf_mf_pdf(microfacet_distribution d, double alpha, vec3 m)
{
    return bsdf_mf_D(d, alpha, m) * dp_fmax(m.z, 0.0); /* Walter eq. 24 */
}
