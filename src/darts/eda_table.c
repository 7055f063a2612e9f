/* The EDA table: tabulation of I(C, S, θ) (paper eq. 17–19, supplement B.3) into per-cell CDFs over cosθ,
 * in the authors' C++ reading convention (docs/darts.md §8.1; their layout and script:
 * docs/reference-renderer.md §7.3, §7.4). Deterministic quadrature instead of the authors' Monte Carlo
 * script: the same parameters always give the same bits. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/darts.h"

#define SUB 2      /* sub-points per cell along C/S, along S and per cos bin (midpoints of halves) */
#define NODES 16   /* midpoint nodes along t in [0, t_M] */

/* log of the integrand e^{−σt t}·Φ(ℓ(t), S − t), with s = S − t > ℓ inside the ellipsoid */
static double log_integrand(double C, double S, double cos_t, double t, double D, double sigma_t, double sigma_a)
{
    double s = S - t;
    double ell2 = dp_fmax(0.0, C * C - 2.0 * C * t * cos_t + t * t);
    double fourDs = 4.0 * D * s;
    return -sigma_t * t - 1.5 * log(M_PI * fourDs) - ell2 / fourDs - sigma_a * s;
}

/* One cell (row i, column j): the mass of every cos bin, in log space relative to the cell maximum, then the
 * normalised cumulative sum. scratch holds n_cos·SUB³·NODES doubles. */
static void build_cell(const eda_table *t, int i, int j, double D, double *scratch, float *cdf)
{
    const double sigma_t = t->sigma_s + t->sigma_a;
    const double dr = (t->r_hi - t->r_lo) / t->n_ratio, dS = t->s_max / t->n_s, dc = 2.0 / t->n_cos;
    double lmax = -INFINITY;
    size_t q = 0;
    for (int k = 0; k < t->n_cos; k++)
        for (int a = 0; a < SUB; a++)
            for (int b = 0; b < SUB; b++)
                for (int c = 0; c < SUB; c++) {
                    double S = (j + (b + 0.5) / SUB) * dS, C = (t->r_lo + (i + (a + 0.5) / SUB) * dr) * S;
                    double cos_t = -1.0 + (k + (c + 0.5) / SUB) * dc;
                    double tM = 0.5 * (S - C) * (S + C) / (S - C * cos_t); /* eq. 19 */
                    for (int m = 0; m < NODES; m++) {
                        double l = log(tM / NODES) + log_integrand(C, S, cos_t, (m + 0.5) / NODES * tM, D, sigma_t,
                                                                   t->sigma_a);
                        scratch[q++] = l;
                        if (l > lmax) lmax = l;
                    }
                }
    const size_t per_bin = (size_t)SUB * SUB * SUB * NODES;
    double acc = 0.0;
    for (int k = 0; k < t->n_cos; k++) {
        double mass = 0.0;
        for (size_t p = 0; p < per_bin; p++) mass += exp(scratch[k * per_bin + p] - lmax);
        acc += mass;
        scratch[k] = acc; /* bin k's entries are all read by now */
    }
    for (int k = 0; k < t->n_cos; k++) cdf[k] = (float)(scratch[k] / acc);
    cdf[t->n_cos - 1] = 1.0f;
}

static int shape_ok(int n_ratio, int n_s, int n_cos)
{
    return n_ratio >= 1 && n_ratio <= 4096 && n_s >= 1 && n_s <= 4096 && n_cos >= 2 && n_cos <= 4096;
}

int eda_table_build(eda_table *t, double sigma_s, double sigma_a, double g, int n_ratio, int n_s, int n_cos,
                    double s_max, double r_lo, double r_hi, void (*progress)(void *, int, int), void *ctx,
                    dp_error *err)
{
    memset(t, 0, sizeof *t);
    if (!shape_ok(n_ratio, n_s, n_cos))
        return dp_fail(err, "EDA table: shape %dx%dx%d out of range (1..4096, cos bins >= 2)", n_ratio, n_s, n_cos);
    if (!(sigma_s > 0.0 && isfinite(sigma_s)) || !(sigma_a >= 0.0 && isfinite(sigma_a)))
        return dp_fail(err, "EDA table: need sigma_s > 0 and sigma_a >= 0, finite (got %g, %g): the diffusion "
                            "approximation is undefined without scattering", sigma_s, sigma_a);
    if (!(g > -1.0 && g < 1.0)) return dp_fail(err, "EDA table: g must be in (-1, 1) (got %g)", g);
    if (!(s_max > 0.0 && isfinite(s_max))) return dp_fail(err, "EDA table: s_max must be > 0 (got %g)", s_max);
    if (!(r_lo >= 0.0 && r_lo < r_hi && r_hi < 1.0))
        return dp_fail(err, "EDA table: need 0 <= C/S range low < high < 1 (got %g, %g)", r_lo, r_hi);
    *t = (eda_table){n_ratio, n_s, n_cos, sigma_s, sigma_a, g, s_max, r_lo, r_hi, NULL};
    t->cdf = malloc(sizeof(float) * (size_t)n_ratio * n_s * n_cos);
    if (!t->cdf) return dp_fail_kind(err, DP_ERROR_MEMORY, "EDA table: out of memory for %dx%dx%d", n_ratio, n_s, n_cos);
    const double D = 1.0 / (3.0 * (sigma_a + sigma_s * (1.0 - g))); /* paper's D (docs/darts.md §6.3) */
    int done = 0, oom = 0;
#pragma omp parallel
    {
        double *scratch = malloc(sizeof(double) * (size_t)n_cos * SUB * SUB * SUB * NODES);
        if (!scratch) {
#pragma omp atomic write
            oom = 1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int i = 0; i < n_ratio; i++) {
            if (!scratch) continue;
            for (int j = 0; j < n_s; j++) build_cell(t, i, j, D, scratch, t->cdf + ((size_t)i * n_s + j) * n_cos);
            int d;
#pragma omp atomic capture
            d = ++done;
            if (progress && omp_get_thread_num() == 0) progress(ctx, d, n_ratio);
        }
        free(scratch);
    }
    if (oom) {
        eda_table_free(t);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "EDA table: out of memory");
    }
    return 0;
}

void eda_table_free(eda_table *t)
{
    free(t->cdf);
    t->cdf = NULL;
}
