/* Fresnel reflectance of smooth boundaries: between dielectrics (real index ratio) and of conductors
 * (complex index η + iκ). Formulas: Born & Wolf, Principles of Optics §1.5; the conductor form as in
 * Shirley's thesis (1991) and pbrt-v3 §8.2.1. */
#include "bsdf_internal.h"

double bsdf_fresnel_dielectric(double eta, double cos_i, double *cos_t)
{
    if (cos_i < 0.0) { /* arriving from the back: the roles of the two media swap */
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    cos_i = dp_fmin(cos_i, 1.0);
    if (eta == 1.0) { /* index-matched: no boundary */
        if (cos_t) *cos_t = cos_i;
        return 0.0;
    }
    /* Snell: sin θt = sin θi / η */
    double sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin_t2 >= 1.0 || cos_i <= 0.0) { /* total internal reflection, or grazing */
        if (cos_t) *cos_t = 0.0;
        return 1.0;
    }
    double ct = sqrt(dp_fmax(0.0, 1.0 - sin_t2));
    if (cos_t) *cos_t = ct;
    /* amplitude ratios for s and p polarisation */
    double r_s = (cos_i - eta * ct) / (cos_i + eta * ct);
    double r_p = (eta * cos_i - ct) / (eta * cos_i + ct);
    double f = 0.5 * (r_s * r_s + r_p * r_p);
    return isfinite(f) ? dp_fmin(dp_fmax(f, 0.0), 1.0) : 1.0;
}

double bsdf_fresnel_conductor(double eta, double k, double cos_i)
{
    double c = dp_fmin(fabs(cos_i), 1.0);
    double c2 = c * c, s2 = 1.0 - c2, s4 = s2 * s2;
    /* a² + b² = |(η + iκ)² − sin²θ|, a = Re √((η + iκ)² − sin²θ) */
    double inner = eta * eta - k * k - s2;
    double a2b2 = sqrt(dp_fmax(inner * inner + 4.0 * eta * eta * k * k, 0.0));
    double a = sqrt(dp_fmax(0.5 * (a2b2 + inner), 0.0));
    double rs_den = a2b2 + c2 + 2.0 * a * c;
    double r_s = rs_den > 0.0 ? (a2b2 + c2 - 2.0 * a * c) / rs_den : 1.0;
    double rp_den = c2 * a2b2 + s4 + 2.0 * a * c * s2;
    double r_p = rp_den > 0.0 ? r_s * (c2 * a2b2 + s4 - 2.0 * a * c * s2) / rp_den : r_s;
    double f = 0.5 * (r_s + r_p);
    return isfinite(f) ? dp_fmin(dp_fmax(f, 0.0), 1.0) : 1.0;
}

vec3 bsdf_fresnel_conductor3(vec3 eta, vec3 k, double cos_i)
{
    return v3(bsdf_fresnel_conductor(eta.x, k.x, cos_i), bsdf_fresnel_conductor(eta.y, k.y, cos_i),
              bsdf_fresnel_conductor(eta.z, k.z, cos_i));
}

/* 2∫₀¹ F(μ) μ dμ = ∫₀¹ F(√x) dx. Under total internal reflection (x < x_c = 1 − η²) F = 1 exactly, so
 * that part is added in closed form and Simpson's rule runs over the smooth rest [x_c, 1]. */
double bsdf_fresnel_average(double eta)
{
    double xc = eta < 1.0 ? 1.0 - eta * eta : 0.0;
    const int n = 2000; /* even */
    double h = (1.0 - xc) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double x = xc + i * h;
        double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * bsdf_fresnel_dielectric(eta, sqrt(dp_fmax(x, 0.0)), NULL);
    }
    return xc + sum * h / 3.0;
}
