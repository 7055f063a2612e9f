/* The geometry of Liu, Jiao and Jarosz 2022's temporally sliced photon primitives (Liu et al. 2022 §4): the
 * roots of the 4-D spatio-temporal constraint g′(ξ_a) = 0 and |J|, the absolute Jacobian determinant of g′
 * with respect to the analytic dimensions ξ_a (eq. 24–25), camera-warped (eta_c > 0) or unwarped (eta_c = 0).
 * Conventions: the module's public header; the derivations of the warped Jacobians:
 * docs/sliced_primitives.md §6.
 *
 * g′ = x′_0 − y′_0 (eq. 13) with our time convention: its time entry is eta_p·Σt + eta_c·s − tau (tau: the
 * gate time less the light path's time at the base vertex and the camera path's time at y1), so ∂τ(g′)/∂t_i =
 * eta_p and ∂τ(g′)/∂s = +eta_c (Liu's eq. 37 writes 1/v^p in the s column: the same when eta_c = eta_p). */
#include "slice_geometry.h"

#include <float.h>

/* |J| below this share of its scale is a grazing root: dropped (the contribution would be unbounded). */
#define SLICE_MIN_JACOBIAN 1e-12

/* ---- small dense linear algebra ---- */

double slice_det4(const double a[4][4])
{
    /* Laplace expansion along the first row over 2×2 minors of the last two rows. */
    double m23[4][4];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) m23[i][j] = a[2][i] * a[3][j] - a[2][j] * a[3][i];
    double d = 0.0;
    for (int c = 0; c < 4; c++) {
        /* the 3×3 minor of row 0, column c: rows 1–3, the other columns p < q < r */
        int k[3], n = 0;
        for (int j = 0; j < 4; j++)
            if (j != c) k[n++] = j;
        double minor = a[1][k[0]] * m23[k[1]][k[2]] - a[1][k[1]] * m23[k[0]][k[2]] + a[1][k[2]] * m23[k[0]][k[1]];
        d += (c % 2 ? -1.0 : 1.0) * a[0][c] * minor;
    }
    return d;
}

int slice_solve4(const double a[4][4], const double b[4], double x[4])
{
    double m[4][5];
    double scale = 0.0;
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) m[i][j] = a[i][j], scale = fmax(scale, fabs(a[i][j]));
        m[i][4] = b[i];
    }
    if (!(scale > 0.0) || !isfinite(scale)) return -1;
    for (int c = 0; c < 4; c++) {
        int p = c;
        for (int i = c + 1; i < 4; i++)
            if (fabs(m[i][c]) > fabs(m[p][c])) p = i;
        if (!(fabs(m[p][c]) > 1e-14 * scale)) return -1;
        if (p != c)
            for (int j = 0; j < 5; j++) {
                double t = m[c][j];
                m[c][j] = m[p][j], m[p][j] = t;
            }
        for (int i = c + 1; i < 4; i++) {
            double f = m[i][c] / m[c][c];
            for (int j = c; j < 5; j++) m[i][j] -= f * m[c][j];
        }
    }
    for (int i = 3; i >= 0; i--) {
        double s = m[i][4];
        for (int j = i + 1; j < 4; j++) s -= m[i][j] * x[j];
        x[i] = s / m[i][i];
    }
    for (int i = 0; i < 4; i++)
        if (!isfinite(x[i])) return -1;
    return 0;
}

/* The 4×4 matrix whose columns are the spatio-temporal edges (ω_i, eta_p) and, last, the camera column
 * (−ψ, eta_c) or a fourth edge: eq. 37 and eq. 43. */
static void edge_column(double a[4][4], int c, vec3 w, double eta)
{
    a[0][c] = w.x, a[1][c] = w.y, a[2][c] = w.z, a[3][c] = eta;
}

/* ---- sliced ball / VPL, Liu et al. 2022 §4.5 ---- */

double slice_ball_jacobian(double t1, vec3 w1, vec3 psi, double eta_p, double eta_c)
{
    /* det [t1·∂ω/∂cosθ, t1·∂ω/∂φ, ω1, −ψ; 0, 0, eta_p, eta_c] (eq. 45 with our time row): expanding along the
     * time row, ±t1²·(eta_p·ω1·ψ + eta_c), since ∂ω/∂cosθ × ∂ω/∂φ = ±ω1 (dω = dcosθ dφ). */
    return t1 * t1 * fabs(eta_p * v3_dot(w1, psi) + eta_c);
}

/* The roots s of eta_p·|y1 + s·ψ − x| + eta_c·s = tau along the ray: squared, with d = y1 − x,
 * (eta_p² − eta_c²)·s² + 2·(eta_p²·d·ψ + tau·eta_c)·s + eta_p²·|d|² − tau² = 0, a quadratic (eta_c < eta_p:
 * the sphere eta_c = 0 and other ovals), linear when eta_c = eta_p (the ellipsoid with foci x and y1 of
 * Pediredla et al. 2019: a ray from its focus crosses it once). The squaring adds the roots with
 * tau − eta_c·s < 0 (t1 negative): dropped. Returns the number of candidates written to s[]. */
static int ball_candidates(vec3 d, vec3 psi, double eta_p, double eta_c, double tau, double s[2])
{
    double ep2 = eta_p * eta_p;
    double A = ep2 - eta_c * eta_c;
    double B = ep2 * v3_dot(d, psi) + tau * eta_c; /* half the linear coefficient */
    double C = ep2 * v3_dot(d, d) - tau * tau;
    double disc = B * B - A * C;
    if (disc < 0.0) return 0;
    /* the stable pair q/A and C/q (A = 0 leaves the linear root −C/(2B) as C/q) */
    double q = -(B + copysign(sqrt(disc), B));
    int n = 0;
    if (q != 0.0) s[n++] = C / q;
    if (A != 0.0) s[n++] = q / A;
    if (n == 2 && s[1] < s[0]) {
        double t = s[0];
        s[0] = s[1], s[1] = t;
    }
    return n;
}

int slice_ball_roots(vec3 x, double eta_p, double tau, const slice_ray *r, slice_root out[2])
{
    if (!(eta_p > 0.0) || !(tau > 0.0) || !(r->eta_c >= 0.0)) return 0;
    vec3 d = v3_sub(r->y1, x);
    double s[2];
    int n = ball_candidates(d, r->psi, eta_p, r->eta_c, tau, s), k = 0;
    for (int i = 0; i < n; i++) {
        if (!(s[i] >= 0.0 && s[i] <= r->s_max)) continue;
        if (tau - r->eta_c * s[i] < 0.0) continue; /* a root of the square only */
        vec3 off = v3_add(d, v3_scale(r->psi, s[i])); /* x0 − x1 = t1·ω1 */
        double t1 = v3_len(off);
        if (!(t1 > 0.0)) continue;
        slice_root *o = &out[k];
        o->t[0] = t1, o->t[1] = o->t[2] = o->t[3] = 0.0;
        o->s = s[i];
        o->w1 = v3_scale(off, 1.0 / t1);
        o->jacobian = slice_ball_jacobian(t1, o->w1, r->psi, eta_p, r->eta_c);
        o->time = eta_p * t1 + r->eta_c * s[i];
        if (!(o->jacobian > SLICE_MIN_JACOBIAN * t1 * t1 * (eta_p + r->eta_c))) continue;
        k++;
    }
    return k;
}

/* ---- delta-sliced parallelepiped, Liu et al. 2022 §4.3 ---- */

static void parallelepiped_matrix(const vec3 w[3], vec3 psi, double eta_p, double eta_c, double a[4][4])
{
    for (int i = 0; i < 3; i++) edge_column(a, i, w[i], eta_p);
    edge_column(a, 3, v3_neg(psi), eta_c); /* eq. 37, the s column with the camera's time per length */
}

double slice_parallelepiped_jacobian(const vec3 w[3], vec3 psi, double eta_p, double eta_c)
{
    double a[4][4];
    parallelepiped_matrix(w, psi, eta_p, eta_c, a);
    return fabs(slice_det4(a));
}

int slice_parallelepiped_root(vec3 x, const vec3 w[3], double eta_p, double tau, const slice_ray *r,
                              slice_root *out)
{
    if (!(eta_p > 0.0) || !(tau > 0.0) || !(r->eta_c >= 0.0)) return 0;
    double a[4][4], sol[4];
    parallelepiped_matrix(w, r->psi, eta_p, r->eta_c, a);
    vec3 d = v3_sub(r->y1, x);
    double b[4] = {d.x, d.y, d.z, tau}; /* eq. 36: J·ξ_a = y′_1 − x′_3 */
    if (slice_solve4(a, b, sol)) return 0;
    if (sol[0] < 0.0 || sol[1] < 0.0 || sol[2] < 0.0 || !(sol[3] >= 0.0 && sol[3] <= r->s_max)) return 0;
    double j = fabs(slice_det4(a));
    if (!(j > SLICE_MIN_JACOBIAN * (eta_p + r->eta_c))) return 0;
    out->t[0] = sol[0], out->t[1] = sol[1], out->t[2] = sol[2], out->t[3] = 0.0;
    out->s = sol[3];
    out->w1 = w[2];
    out->jacobian = j;
    out->time = eta_p * (sol[0] + sol[1] + sol[2]) + r->eta_c * sol[3];
    return 1;
}

/* ---- delta-sliced parallelotope, Liu et al. 2022 §4.4 ---- */

int slice_parallelotope_root(vec3 x, const vec3 w[4], double eta_p, double tau, vec3 y0, slice_root *out)
{
    if (!(eta_p > 0.0) || !(tau > 0.0)) return 0;
    double a[4][4], sol[4];
    for (int i = 0; i < 4; i++) edge_column(a, i, w[i], eta_p); /* eq. 43 */
    vec3 d = v3_sub(y0, x);
    double b[4] = {d.x, d.y, d.z, tau}; /* eq. 42: J·ξ_a = y′_0 − x′_4 */
    if (slice_solve4(a, b, sol)) return 0;
    for (int i = 0; i < 4; i++)
        if (sol[i] < 0.0) return 0;
    double j = fabs(slice_det4(a));
    if (!(j > SLICE_MIN_JACOBIAN * eta_p)) return 0;
    for (int i = 0; i < 4; i++) out->t[i] = sol[i];
    out->s = 0.0;
    out->w1 = w[3];
    out->jacobian = j;
    out->time = eta_p * (sol[0] + sol[1] + sol[2] + sol[3]);
    return 1;
}

/* ---- sliced photon plane, Liu et al. 2022 §4.2 ---- */

static double det3(vec3 a, vec3 b, vec3 c) { return v3_dot(a, v3_cross(b, c)); }

int slice_plane_root(vec3 x, const vec3 w[2], const double len[2], double eta_p, const slice_ray *r, slice_root *out)
{
    if (!(eta_p > 0.0) || !(r->eta_c >= 0.0)) return 0;
    /* eq. 28: t2·ω2 + t1·ω1 − s·ψ = y1 − x, by Cramer's rule */
    vec3 mpsi = v3_neg(r->psi), d = v3_sub(r->y1, x);
    double D = det3(w[0], w[1], mpsi);
    /* eq. 29–30: the τ_k column is (0, 0, 0, ±1), so |J| = |det3(ω2, ω1, −ψ)| = |(ω2 × ω1)·ψ| */
    if (!(fabs(D) > SLICE_MIN_JACOBIAN)) return 0;
    double t2 = det3(d, w[1], mpsi) / D, t1 = det3(w[0], d, mpsi) / D, s = det3(w[0], w[1], d) / D;
    if (!(t2 >= 0.0 && t2 <= len[0] && t1 >= 0.0 && t1 <= len[1] && s >= 0.0 && s <= r->s_max)) return 0;
    out->t[0] = t2, out->t[1] = t1, out->t[2] = out->t[3] = 0.0;
    out->s = s;
    out->w1 = w[1];
    out->jacobian = fabs(D);
    out->time = eta_p * (t2 + t1) + r->eta_c * s;
    return 1;
}

/* ---- the 1-D-blurred photon plane (planes_1d), docs/sliced_primitives.md §7 ---- */

/* Clips [*lo, *hi] to the s where lo_v <= a + b·s <= hi_v. */
static void clip_linear(double a, double b, double lo_v, double hi_v, double *lo, double *hi)
{
    if (b == 0.0) {
        if (!(a >= lo_v && a <= hi_v)) *hi = -INFINITY;
        return;
    }
    double s_a = (lo_v - a) / b, s_b = (hi_v - a) / b;
    if (b < 0.0) {
        double t = s_a;
        s_a = s_b, s_b = t;
    }
    if (s_a > *lo) *lo = s_a;
    if (s_b < *hi) *hi = s_b;
}

int slice_plane1d_interval(vec3 x, const vec3 w[2], const double len[2], double radius, double eta_p,
                           const slice_ray *r, double time_lo, double time_hi, slice_interval *out)
{
    if (!(eta_p > 0.0) || !(radius > 0.0) || !(r->eta_c >= 0.0) || !(time_hi > time_lo)) return 0;
    vec3 c = v3_cross(w[0], w[1]);
    double area = v3_len(c); /* [ω2, ω1, n] = |ω2 × ω1| */
    if (!(area > SLICE_MIN_JACOBIAN)) return 0;
    vec3 n = v3_scale(c, 1.0 / area);
    /* the dual basis of (ω2, ω1, n): t2 = (p − x)·(ω1 × n)/area, t1 = (p − x)·(n × ω2)/area, B = (p − x)·n */
    vec3 d2 = v3_scale(v3_cross(w[1], n), 1.0 / area), d1 = v3_scale(v3_cross(n, w[0]), 1.0 / area);
    vec3 q = v3_sub(r->y1, x); /* p(s) − x = q + s·ψ */
    out->t2[0] = v3_dot(q, d2), out->t2[1] = v3_dot(r->psi, d2);
    out->t1[0] = v3_dot(q, d1), out->t1[1] = v3_dot(r->psi, d1);
    out->b[0] = v3_dot(q, n), out->b[1] = v3_dot(r->psi, n);
    double lo = 0.0, hi = r->s_max;
    clip_linear(out->t2[0], out->t2[1], 0.0, len[0], &lo, &hi);
    clip_linear(out->t1[0], out->t1[1], 0.0, len[1], &lo, &hi);
    clip_linear(out->b[0], out->b[1], -radius, radius, &lo, &hi);
    /* the root's time eta_p·(t2 + t1) + eta_c·s */
    clip_linear(eta_p * (out->t2[0] + out->t1[0]), eta_p * (out->t2[1] + out->t1[1]) + r->eta_c, time_lo, time_hi,
                &lo, &hi);
    if (!(hi > lo)) return 0;
    out->s0 = lo, out->s1 = hi;
    out->jacobian = area;
    return 1;
}
