/* The offset's distribution (include/dartspp/derivative.h; docs/derivatives.md §2): o = τ_e + r, the light's
 * pulse (emitter_pulse_sample: delta at start, uniform on [start, start + width), or Gaussian of FWHM width
 * peaked at start + width/2) plus the sensor's response (sensor_response_sample: off, Gaussian σ plus an
 * exponential delay of mean τ, or a tabulated piecewise-linear density). Its CDF F, density f and ∂F/∂width
 * enter the correlated importance S(τ) = (F(b − τ) − F(a − τ))/w of Yi et al. 2021 eq. 7.
 *
 * Closed forms: every pulse alone; a delta pulse with any response (the response shifted by start); a
 * Gaussian pulse with a Gaussian/exponential response (the exponentially modified Gaussian of the merged σ);
 * a box pulse with a Gaussian/exponential response (∫G = σΨ(t/σ) − τG(t), Ψ(u) = uΦ(u) + φ(u)); a box pulse
 * with a table (the piecewise-quadratic G integrated exactly: two-point Gauss–Legendre per piece between the
 * knots). Quadrature only for a Gaussian pulse with a table: 8-point Gauss–Legendre over the standard normal
 * variable on [−8.5, 8.5] in 9 pieces, cut at the table's knots; its error is below 1e-12 (measured in
 * tests/derivative/test_time_kernel.c). No allocation; at most (9 + knots in range)·8 evaluations. */
#include <math.h>

#include "dartspp/derivative.h"

#define FWHM_PER_SIGMA 2.3548200450309493 /* 2·sqrt(2 ln 2), as src/emitter/pulse.c */
#define INV_SQRT_2PI 0.39894228040143267794
#define MILLS_FROM 5.0 /* below −5 the normal's tail by the Mills ratio's continued fraction */
#define GH_L 8.5       /* the Gaussian pulse's quadrature over Z in [−L, L] (2Φ(−L) = 1.9e-17) */
#define GH_PIECES 9

static const double gl8_x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
static const double gl8_w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
#define GL2_X 0.57735026918962576451 /* 1/sqrt(3), both weights 1 */

static double npdf(double u) { return INV_SQRT_2PI * exp(-0.5 * u * u); }

/* The continued fraction of the Mills ratio, u >= MILLS_FROM: Φ(−u) = φ(u)/d1 with
 * d1 = u + 1/d2, d2 = u + 2/d3, ... evaluated from k = 8 + 600/u² down (converged to 1e-16 relative: 24
 * terms needed at u = 5, 12 at u = 10, 8 at u = 20; far tails take the fewest). */
static void mills(double u, double *d1, double *d2)
{
    double d = u;
    int top = u < 1e3 ? 8 + (int)(600.0 / (u * u)) : 8;
    for (int k = top; k >= 2; k--) d = u + k / d;
    *d2 = d;
    *d1 = u + 1.0 / d;
}

/* Φ(u) */
static double ncdf(double u)
{
    if (u < -MILLS_FROM) {
        double d1, d2;
        mills(-u, &d1, &d2);
        return npdf(u) / d1;
    }
    return 0.5 * erfc(-u * M_SQRT1_2);
}

/* Ψ(u) = ∫_{−∞}^u Φ = uΦ(u) + φ(u); in the left tail φ(u)/(d1·d2) without the cancellation */
static double npsi(double u)
{
    if (u < -MILLS_FROM) {
        double d1, d2;
        mills(-u, &d1, &d2);
        return npdf(u) / (d1 * d2);
    }
    return u * ncdf(u) + npdf(u);
}

/* ---- the smooth responses: Gaussian σ, exponential τ, or their sum (exponentially modified Gaussian) ----
 * E(t) = e^{−t/τ + σ²/(2τ²)}·Φ(t/σ − σ/τ) = φ(t/σ)·Φ(z)/φ(z), z = t/σ − σ/τ: in the tail (z < −5) the
 * second form, which neither overflows nor underflows while the value is representable. */
typedef struct {
    double sig, tau; /* not both 0 */
} smooth;

static double emg_e(smooth r, double t)
{
    double z = t / r.sig - r.sig / r.tau;
    if (z < -MILLS_FROM) {
        double d1, d2;
        mills(-z, &d1, &d2);
        return npdf(t / r.sig) / d1;
    }
    return exp(-t / r.tau + r.sig * r.sig / (2.0 * r.tau * r.tau)) * ncdf(z);
}

static double sm_cdf(smooth r, double t)
{
    if (r.tau == 0.0) return ncdf(t / r.sig);
    if (r.sig == 0.0) return t > 0.0 ? -expm1(-t / r.tau) : 0.0;
    double v = ncdf(t / r.sig) - emg_e(r, t);
    return v > 0.0 ? v : 0.0;
}

static double sm_sf(smooth r, double t)
{
    if (r.tau == 0.0) return ncdf(-t / r.sig);
    if (r.sig == 0.0) return t > 0.0 ? exp(-t / r.tau) : 1.0;
    double v = ncdf(-t / r.sig) + emg_e(r, t);
    return v < 1.0 ? v : 1.0;
}

static double sm_pdf(smooth r, double t)
{
    if (r.tau == 0.0) return npdf(t / r.sig) / r.sig;
    if (r.sig == 0.0) return t >= 0.0 ? exp(-t / r.tau) / r.tau : 0.0;
    return emg_e(r, t) / r.tau;
}

/* g'(t), σ > 0 */
static double sm_dpdf(smooth r, double t)
{
    if (r.tau == 0.0) {
        double g = sm_pdf(r, t);
        return g > 0.0 ? -t / r.sig * (g / r.sig) : 0.0; /* 0, not ∞·0, far out */
    }
    return (npdf(t / r.sig) / r.sig - emg_e(r, t) / r.tau) / r.tau;
}

/* σΨ(t/σ), and its limit max(t, 0) at σ = 0 */
static double sig_psi(double sig, double t) { return sig > 0.0 ? sig * npsi(t / sig) : (t > 0.0 ? t : 0.0); }

/* H(t) = ∫_{−∞}^t G = σΨ(t/σ) − τG(t); K(t) = ∫_t^∞ (1 − G) = σΨ(−t/σ) + τ(1 − G(t)) */
static double sm_H(smooth r, double t) { return sig_psi(r.sig, t) - (r.tau > 0.0 ? r.tau * sm_cdf(r, t) : 0.0); }
static double sm_K(smooth r, double t) { return sig_psi(r.sig, -t) + (r.tau > 0.0 ? r.tau * sm_sf(r, t) : 0.0); }

/* ---- the tabulated response (sensor.h: knots t, normalized p and cdf) ---- */
static void tab_eval(const sensor_response *r, double x, double *G, double *g)
{
    int n = r->n;
    if (!(x > r->t[0])) {
        *G = 0.0, *g = 0.0;
        return;
    }
    if (x >= r->t[n - 1]) {
        *G = 1.0, *g = 0.0;
        return;
    }
    int lo = 0, hi = n - 1; /* t[lo] < x < t[hi]... x in [t[lo], t[lo + 1]) */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (r->t[mid] <= x) lo = mid;
        else hi = mid;
    }
    double h = x - r->t[lo], slope = (r->p[lo + 1] - r->p[lo]) / (r->t[lo + 1] - r->t[lo]);
    double v = r->cdf[lo] + r->p[lo] * h + 0.5 * slope * h * h;
    *G = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    double d = r->p[lo] + slope * h;
    *g = d > 0.0 ? d : 0.0;
}

/* the first knot index i with t[i] > x (n when none) */
static int tab_upper(const sensor_response *r, double x)
{
    int lo = 0, hi = r->n;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (r->t[mid] > x) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* ---- what the kernel is made of ---- */
typedef enum { R_OFF, R_SMOOTH, R_TABLE } rkind;

static rkind response_kind(const time_kernel *k)
{
    const sensor_response *r = k->response;
    if (!r || !r->on) return R_OFF;
    return r->n >= 2 ? R_TABLE : R_SMOOTH;
}

static smooth response_smooth(const time_kernel *k) { return (smooth){k->response->sigma, k->response->tail}; }

typedef struct {
    double F, f, dF; /* F(x), f(x), ∂F/∂width */
} kval;

static double clamp01(double v) { return v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v; }

/* A box pulse of width w > 0 with a smooth response, t1 = x − start, t0 = t1 − w:
 * F = ∫_0^1 G(t1 − v·w) dv, f = (G(t1) − G(t0))/w, ∂F/∂w = −∫_0^1 v·g(t1 − v·w) dv = (G(t0) − F)/w. */
static kval box_smooth(smooth r, double t1, double w)
{
    kval k;
    double t0 = t1 - w, scale = r.sig > 0.0 ? r.sig : r.tau;
    if (w <= 0.25 * scale) {
        /* narrow box: 8-point Gauss–Legendre in v (cut at the exponential's kink when σ = 0), no cancellation */
        double cut = (r.sig == 0.0 && t1 > 0.0 && t0 < 0.0) ? t1 / w : -1.0;
        double F = 0.0, f = 0.0, dF = 0.0;
        for (int piece = 0; piece < (cut > 0.0 ? 2 : 1); piece++) {
            double a = cut > 0.0 && piece == 1 ? cut : 0.0, b = cut > 0.0 && piece == 0 ? cut : 1.0;
            double c = 0.5 * (a + b), h = 0.5 * (b - a);
            for (int i = 0; i < 8; i++) {
                double v = c + (i < 4 ? -1.0 : 1.0) * h * gl8_x[i & 3], wt = h * gl8_w[i & 3];
                double g = sm_pdf(r, t1 - v * w);
                F += wt * sm_cdf(r, t1 - v * w);
                f += wt * g;
                dF -= wt * v * g;
            }
        }
        k.F = clamp01(F), k.f = f, k.dF = dF;
        return k;
    }
    if (0.5 * (t0 + t1) < r.tau) { /* the left side: F itself is the small number */
        double F = (sm_H(r, t1) - sm_H(r, t0)) / w;
        k.F = clamp01(F);
        k.f = (sm_cdf(r, t1) - sm_cdf(r, t0)) / w;
        k.dF = (sm_cdf(r, t0) - k.F) / w;
    } else { /* the right side: Q = 1 − F */
        double Q = clamp01((sm_K(r, t0) - sm_K(r, t1)) / w);
        k.F = 1.0 - Q;
        k.f = (sm_sf(r, t0) - sm_sf(r, t1)) / w;
        k.dF = (Q - sm_sf(r, t0)) / w;
    }
    if (!(k.f > 0.0)) k.f = 0.0;
    if (k.dF > 0.0) k.dF = 0.0; /* widening a box with its start fixed only delays o */
    return k;
}

/* A box pulse with a table: the same integrals in v, exact (two-point Gauss–Legendre per piece between the
 * knots, where G is quadratic and g linear). */
static kval box_table(const sensor_response *r, double t1, double w)
{
    double t0 = t1 - w, F = 0.0, f = 0.0, dF = 0.0;
    int i = tab_upper(r, t1) - 1; /* knots i, i−1, ... in (t0, t1) are the cuts, in increasing v */
    double a = 0.0;
    for (;;) {
        double b = 1.0;
        if (i >= 0 && r->t[i] > t0) b = (t1 - r->t[i]) / w;
        if (b > 1.0) b = 1.0;
        if (b > a) {
            double c = 0.5 * (a + b), h = 0.5 * (b - a);
            for (int s = -1; s <= 1; s += 2) {
                double v = c + s * h * GL2_X, G, g;
                tab_eval(r, t1 - v * w, &G, &g);
                F += h * G;
                f += h * g;
                dF -= h * v * g;
            }
        }
        if (b >= 1.0) break;
        a = b;
        i--;
    }
    return (kval){clamp01(F), f, dF};
}

/* A Gaussian pulse (mean m, σp > 0) with a table: F = E[G(t − σp·Z)], f = E[g(t − σp·Z)],
 * ∂F/∂σp = −E[Z·g(t − σp·Z)], t = x − m, by Gauss–Legendre over Z cut at the knots. */
static kval gauss_table(const sensor_response *r, double t, double sp)
{
    int n = r->n;
    if (t - sp * GH_L >= r->t[n - 1]) return (kval){1.0, 0.0, 0.0};
    if (t + sp * GH_L <= r->t[0]) return (kval){0.0, 0.0, 0.0};
    double F = 0.0, f = 0.0, zg = 0.0, mass = 0.0;
    /* the knot Z_i = (t − t_i)/σp decreases with i: walk i down from the last knot below t + σp·L */
    int i = tab_upper(r, t + sp * GH_L) - 1;
    double a = -GH_L, step = 2.0 * GH_L / GH_PIECES;
    int j = 1;
    while (a < GH_L) {
        double grid = j < GH_PIECES ? -GH_L + j * step : GH_L, kink = HUGE_VAL;
        while (i >= 0 && (kink = (t - r->t[i]) / sp) <= a) i--, kink = HUGE_VAL;
        double b = kink < grid ? kink : grid;
        if (b > a) {
            double c = 0.5 * (a + b), h = 0.5 * (b - a);
            for (int q = 0; q < 8; q++) {
                double z = c + (q < 4 ? -1.0 : 1.0) * h * gl8_x[q & 3], wt = h * gl8_w[q & 3] * npdf(z), G, g;
                tab_eval(r, t - sp * z, &G, &g);
                F += wt * G;
                f += wt * g;
                zg += wt * z * g;
                mass += wt;
            }
        }
        if (kink < grid) i--;
        else j++;
        a = b;
    }
    F /= mass, f /= mass, zg /= mass;
    /* ∂/∂w: the mean moves by 1/2, σp by 1/FWHM_PER_SIGMA */
    return (kval){clamp01(F), f, -0.5 * f - zg / FWHM_PER_SIGMA};
}

static kval eval(const time_kernel *k, double x)
{
    const emitter_pulse *p = &k->pulse;
    rkind rk = response_kind(k);
    double s = p->start, w = p->width;
    if (!(w > 0.0)) { /* delta pulse: the response shifted by start */
        double t = x - s;
        if (rk == R_OFF) return (kval){t >= 0.0 ? 1.0 : 0.0, 0.0, 0.0};
        if (rk == R_TABLE) {
            double G, g;
            tab_eval(k->response, t, &G, &g);
            return (kval){G, g, 0.0};
        }
        smooth r = response_smooth(k);
        return (kval){sm_cdf(r, t), sm_pdf(r, t), 0.0};
    }
    if (p->shape == PULSE_BOX) {
        double t1 = x - s;
        if (rk == R_OFF) {
            if (!(t1 > 0.0)) return (kval){0.0, 0.0, 0.0};
            if (t1 >= w) return (kval){1.0, 0.0, 0.0};
            return (kval){t1 / w, 1.0 / w, -t1 / (w * w)};
        }
        if (rk == R_TABLE) return box_table(k->response, t1, w);
        return box_smooth(response_smooth(k), t1, w);
    }
    /* Gaussian pulse: mean m = start + w/2, σp = w/FWHM_PER_SIGMA; ∂F/∂w = −f/2 + (∂F/∂σp)/FWHM_PER_SIGMA,
     * and with a Gaussian part of σ_total = sqrt(σp² + σ²), ∂F/∂σp = σp·f'(x) */
    double m = s + 0.5 * w, sp = w / FWHM_PER_SIGMA, t = x - m;
    if (rk == R_TABLE) return gauss_table(k->response, t, sp);
    smooth r = {sp, 0.0};
    if (rk == R_SMOOTH) r = (smooth){hypot(sp, k->response->sigma), k->response->tail};
    double f = sm_pdf(r, t);
    return (kval){sm_cdf(r, t), f, -0.5 * f + sp * sm_dpdf(r, t) / FWHM_PER_SIGMA};
}

int time_kernel_has_density(const time_kernel *k) { return k->pulse.width > 0.0 || response_kind(k) != R_OFF; }

double time_kernel_cdf(const time_kernel *k, double x) { return eval(k, x).F; }

double time_kernel_pdf(const time_kernel *k, double x) { return eval(k, x).f; }

double time_kernel_dcdf_dwidth(const time_kernel *k, double x)
{
    if (!(k->pulse.width > 0.0)) return 0.0;
    return eval(k, x).dF;
}
