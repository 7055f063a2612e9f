/* EDA direction sampling at a medium vertex, combined with the phase function by the one-sample balance
 * heuristic (paper §5.1, eq. 20; docs/darts.md §8.2 — the authors' code uses another weight,
 * docs/reference-renderer.md §7.2). */
#include "dartspp/darts.h"

const float *eda_cell(const eda_table *t, const ellipse_record *r)
{
    if (!t || !r->valid || !(r->T > 0.0)) return NULL;
    double ratio = r->C / r->T;
    if (!(ratio >= t->r_lo && ratio < t->r_hi)) return NULL;
    int i = (int)((ratio - t->r_lo) / (t->r_hi - t->r_lo) * t->n_ratio);
    int j = (int)(r->T / t->s_max * t->n_s);
    if (i > t->n_ratio - 1) i = t->n_ratio - 1;
    if (j > t->n_s - 1) j = t->n_s - 1; /* clamped: residuals beyond s_max use the last column */
    return t->cdf + ((size_t)i * t->n_s + j) * t->n_cos;
}

static int cos_bin(const eda_table *t, double cos_theta)
{
    int k = (int)((cos_theta + 1.0) * 0.5 * t->n_cos);
    return k < 0 ? 0 : k > t->n_cos - 1 ? t->n_cos - 1 : k;
}

double eda_pdf(const eda_table *t, const float *cell, vec3 e, vec3 w)
{
    int k = cos_bin(t, v3_dot(w, e));
    double P = (double)cell[k] - (k > 0 ? (double)cell[k - 1] : 0.0);
    return P * t->n_cos * DP_INV_4PI; /* bin probability / (2π · 2/n_cos) */
}

/* First bin k with F[k] >= u, u in (0, 1]: a bin of zero probability is never returned. */
static int cdf_search(const float *F, int n, double u)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if ((double)F[mid] >= u) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

vec3 eda_sample_direction(const eda_table *t, double alpha, const phase_function *ph, vec3 w_in,
                          const ellipse_record *r, const double u[4], double *weight)
{
    const float *cell = eda_cell(t, r);
    if (!cell) {
        *weight = 1.0;
        return phase_sample(ph, w_in, u[1], u[2]);
    }
    double q = r->C / r->T, gamma = q / (q + alpha); /* eq. 20 with C/S */
    vec3 w;
    if (u[0] < gamma) {
        int k = cdf_search(cell, t->n_cos, 1.0 - u[1]);
        double c = -1.0 + (k + u[2]) * 2.0 / t->n_cos;
        c = dp_fmin(1.0, dp_fmax(-1.0, c));
        double s = sqrt(dp_fmax(0.0, 1.0 - c * c)), phi = 2.0 * M_PI * u[3];
        vec3 b1, b2;
        v3_basis(r->e, &b1, &b2);
        w = v3_norm(v3_add(v3_scale(r->e, c), v3_add(v3_scale(b1, s * cos(phi)), v3_scale(b2, s * sin(phi)))));
    } else {
        w = phase_sample(ph, w_in, u[1], u[2]);
    }
    double f = phase_eval(ph, w_in, w); /* = p_phase */
    double mix = gamma * eda_pdf(t, cell, r->e, w) + (1.0 - gamma) * f;
    *weight = mix > 0.0 ? f / mix : 0.0;
    return w;
}

double eda_direction_pdf(const eda_table *t, double alpha, const phase_function *ph, vec3 w_in, const ellipse_record *r,
                         vec3 w)
{
    const float *cell = eda_cell(t, r);
    double f = phase_eval(ph, w_in, w);
    if (!cell) return f;
    double q = r->C / r->T, gamma = q / (q + alpha); /* as eda_sample_direction (eq. 20) */
    return gamma * eda_pdf(t, cell, r->e, w) + (1.0 - gamma) * f;
}
