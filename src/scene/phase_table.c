/* Tabulated phase functions (phase_function type "tabulated"; docs/scene-format.md §2.3, docs/lidar.md §6): a
 * CSV file of "theta_deg,value" rows read into p(θ), linear in the scattering angle θ between the rows and
 * normalised so that 2π ∫₀^π p(θ) sinθ dθ = 1.
 *
 * Everything is exact for that interpolant: on a row interval [θ_i, θ_i + h] with p = a + b·s (s = θ − θ_i),
 *   I_i(t) = ∫₀^t (a + b s) sin(θ_i + s) ds
 *          = sinθ_i·(a sin t + b (t sin t − 2 sin²(t/2))) + cosθ_i·(a·2 sin²(t/2) + b (sin t − t cos t)),
 * written so that small t loses no digits (sin t − t cos t by its series below 0.1). The CDF of θ at the rows is
 * 2π Σ I_i(h_i); a sample picks its interval by that CDF and solves 2π I_i(t) = u − cdf[i] for t by Newton's
 * method kept inside a shrinking bracket, so its density per steradian is the interpolant itself and phase_eval
 * returns exactly the sampling pdf (scene.h: the weight phase/pdf is 1). ⟨cosθ⟩ = 2π Σ ∫ p sinθ cosθ dθ uses the
 * same closed form at double angles (sinθ cosθ = sin 2θ / 2). */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/scene.h"

/* sin t − t cos t without cancellation at small t */
static double sin_minus_tcos(double t)
{
    if (fabs(t) < 0.1) {
        double t2 = t * t;
        return t * t2 * (1.0 / 3.0 - t2 * (1.0 / 30.0 - t2 * (1.0 / 840.0 - t2 / 45360.0)));
    }
    return sin(t) - t * cos(t);
}

/* ∫₀^t (a + b s) sin(θ0 + s) ds (header comment) */
static double lin_sin_integral(double theta0, double t, double a, double b)
{
    double st = sin(t), h = sin(0.5 * t), one_minus_cos = 2.0 * h * h;
    double s0 = sin(theta0), c0 = cos(theta0);
    return s0 * (a * st + b * (t * st - one_minus_cos)) + c0 * (a * one_minus_cos + b * sin_minus_tcos(t));
}

void phase_table_free(phase_table *t)
{
    if (!t) return;
    free(t->theta);
    free(t->p);
    free(t->cdf);
    memset(t, 0, sizeof *t);
}

static int tfail(phase_table *t, dp_error *err, const char *path, int line, const char *why)
{
    phase_table_free(t);
    if (line > 0) return dp_fail(err, "%s:%d: phase function table: %s", path, line, why);
    return dp_fail(err, "%s: phase function table: %s", path, why);
}

/* The rows as given, checked: θ from 0 to 180 degrees strictly increasing, values >= 0 and finite. line[i]: the
 * file's line of row i (0 for arrays). */
static int check_rows(phase_table *t, const double *deg, const double *v, const int *line, int n, const char *name,
                      dp_error *err)
{
    for (int i = 0; i < n; i++) {
        int l = line ? line[i] : 0;
        char why[160];
        if (!isfinite(deg[i]) || !isfinite(v[i])) {
            snprintf(why, sizeof why, "row %d: theta and value must be finite", i + 1);
            return tfail(t, err, name, l, why);
        }
        if (v[i] < 0.0) {
            snprintf(why, sizeof why, "row %d: value %g is negative (a phase function is >= 0)", i + 1, v[i]);
            return tfail(t, err, name, l, why);
        }
        if (i > 0 && !(deg[i] > deg[i - 1])) {
            snprintf(why, sizeof why, "row %d: theta %g degrees after %g: theta must increase strictly", i + 1,
                     deg[i], deg[i - 1]);
            return tfail(t, err, name, l, why);
        }
    }
    if (n < 2) return tfail(t, err, name, 0, "fewer than two rows (theta from 0 to 180 degrees)");
    if (deg[0] != 0.0 || deg[n - 1] != 180.0) {
        char why[160];
        snprintf(why, sizeof why, "theta must run from 0 to 180 degrees (got %g to %g)", deg[0], deg[n - 1]);
        return tfail(t, err, name, 0, why);
    }
    return 0;
}

static int build(phase_table *t, const double *deg, const double *v, const int *line, int n, const char *name,
                 dp_error *err)
{
    memset(t, 0, sizeof *t);
    snprintf(t->path, sizeof t->path, "%s", name);
    if (check_rows(t, deg, v, line, n, name, err)) return -1;
    t->n = n;
    t->theta = malloc((size_t)n * sizeof *t->theta);
    t->p = malloc((size_t)n * sizeof *t->p);
    t->cdf = malloc((size_t)n * sizeof *t->cdf);
    if (!t->theta || !t->p || !t->cdf) {
        phase_table_free(t);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the phase function table", name);
    }
    for (int i = 0; i < n; i++) t->theta[i] = deg[i] * (M_PI / 180.0), t->p[i] = v[i];
    t->theta[n - 1] = M_PI;
    double z = 0.0;
    t->cdf[0] = 0.0;
    for (int i = 0; i + 1 < n; i++) {
        double h = t->theta[i + 1] - t->theta[i];
        z += 2.0 * M_PI * lin_sin_integral(t->theta[i], h, t->p[i], (t->p[i + 1] - t->p[i]) / h);
        t->cdf[i + 1] = z;
    }
    if (!(z > 0.0) || !isfinite(z)) return tfail(t, err, name, 0, "its integral over the sphere is 0 (every value is 0 "
                                                                   "where sinθ > 0)");
    double g = 0.0;
    for (int i = 0; i < n; i++) t->p[i] /= z, t->cdf[i] /= z;
    t->cdf[n - 1] = 1.0;
    for (int i = 0; i + 1 < n; i++) {
        double h = t->theta[i + 1] - t->theta[i], b = (t->p[i + 1] - t->p[i]) / h;
        g += 2.0 * M_PI * 0.25 * lin_sin_integral(2.0 * t->theta[i], 2.0 * h, t->p[i], 0.5 * b);
    }
    t->g = dp_fmin(1.0, dp_fmax(-1.0, g));
    return 0;
}

int phase_table_init(phase_table *t, const double *theta_deg, const double *value, int n, const char *name, dp_error *err)
{
    return build(t, theta_deg, value, NULL, n, name, err);
}

int phase_table_load(phase_table *t, const char *path, dp_error *err)
{
    memset(t, 0, sizeof *t);
    FILE *f = fopen(path, "r");
    if (!f) return dp_fail(err, "%s: cannot open the phase function table: %s", path, strerror(errno));
    char buf[512];
    int no = 0, n = 0, cap = 0, rows = 0;
    double *deg = NULL, *val = NULL;
    int *line = NULL;
    int rc = 0;
    while (!rc && fgets(buf, sizeof buf, f)) {
        no++;
        char *s = buf;
        while (*s == ' ' || *s == '\t') s++;
        if (*s == '\n' || *s == '\r' || *s == 0 || *s == '#') continue;
        double a, b;
        char extra;
        if (sscanf(s, "%lf , %lf %c", &a, &b, &extra) != 2) {
            if (rows++ == 0) continue; /* the first non-comment line may be a header */
            rc = dp_fail(err, "%s:%d: phase function table: expected \"theta_deg,value\"", path, no);
            break;
        }
        rows++;
        if (n == cap) {
            int c = cap ? 2 * cap : 256;
            double *nd = realloc(deg, (size_t)c * sizeof *nd);
            if (nd) deg = nd;
            double *nv = nd ? realloc(val, (size_t)c * sizeof *nv) : NULL;
            if (nv) val = nv;
            int *nl = nv ? realloc(line, (size_t)c * sizeof *nl) : NULL;
            if (nl) line = nl;
            if (!nl) {
                rc = dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
                break;
            }
            cap = c;
        }
        deg[n] = a, val[n] = b, line[n] = no, n++;
    }
    fclose(f);
    if (!rc) rc = build(t, deg, val, line, n, path, err);
    free(deg);
    free(val);
    free(line);
    return rc;
}

/* The row interval [θ_i, θ_{i+1}] holding θ: the largest i <= n − 2 with θ_i <= θ. */
static int interval_of(const phase_table *t, double theta)
{
    int lo = 0, hi = t->n - 2;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (t->theta[mid] <= theta) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

double phase_table_eval(const phase_table *t, double theta)
{
    theta = dp_fmin(M_PI, dp_fmax(0.0, theta));
    int i = interval_of(t, theta);
    double h = t->theta[i + 1] - t->theta[i], s = (theta - t->theta[i]) / h;
    return t->p[i] + (t->p[i + 1] - t->p[i]) * s;
}

double phase_table_sample_theta(const phase_table *t, double u)
{
    u = dp_fmin(dp_fmax(u, 0.0), 1.0);
    /* the largest i <= n − 2 with cdf[i] <= u: an interval of zero mass is never chosen (cdf[i + 1] > u) unless
     * u = 1 */
    int lo = 0, hi = t->n - 2;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (t->cdf[mid] <= u) lo = mid;
        else hi = mid - 1;
    }
    int i = lo;
    double th0 = t->theta[i], h = t->theta[i + 1] - th0;
    double a = t->p[i], b = (t->p[i + 1] - a) / h;
    double total = lin_sin_integral(th0, h, a, b);
    double target = dp_fmin(total, dp_fmax(0.0, (u - t->cdf[i]) / (2.0 * M_PI)));
    if (!(total > 0.0)) return th0 + 0.5 * h; /* u = 1 after intervals of zero mass: a null set */
    double x_lo = 0.0, x_hi = h, x = h * target / total;
    for (int it = 0; it < 200; it++) {
        double f = lin_sin_integral(th0, x, a, b) - target;
        if (fabs(f) <= 1e-15 * total) break;
        if (f < 0.0) x_lo = x;
        else x_hi = x;
        if (x_hi - x_lo <= 4.0 * DBL_EPSILON * (th0 + h)) break;
        double d = (a + b * x) * sin(th0 + x), nx = d > 0.0 ? x - f / d : -1.0;
        x = nx > x_lo && nx < x_hi ? nx : 0.5 * (x_lo + x_hi);
    }
    return dp_fmin(M_PI, th0 + x);
}
