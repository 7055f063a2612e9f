/* dartspp sliced photon primitives (src/sliced_primitives): Liu, Jiao and Jarosz 2022's temporally sliced photon
 * primitives. This header starts with their geometry (src/sliced_primitives/slice_geometry.c), public so that
 * tests/sliced_primitives/test_slice_geometry.c can check it (tests include no header under src/).
 *
 * The geometry of the temporally sliced photon primitives (Liu et al. 2022 §4; the paper's text:
 * ../shared/papers/liu-2022-sliced-photon-primitives.txt). Each estimator pre-integrates four dimensions against
 * a 4-D spatio-temporal delta δ⁴(g′) (eq. 20–24): these functions find the roots of g′(ξ_a) = 0 for one
 * primitive and one camera segment and give |J|, the absolute 4×4 Jacobian determinant of g′ with respect to
 * the analytic dimensions (eq. 25), camera-warped or unwarped. Pure functions: no scene, no medium, no
 * transmittance — the caller evaluates the path contribution at each root.
 *
 * Conventions (all times are optical path lengths, as everywhere in dartspp):
 * - The camera segment is y1 + s·ψ, ψ unit, 0 <= s <= s_max; eta_c is the time per unit length along it
 *   (the medium's η when camera-warped, 0 when the segment is the sensor's own and unwarped).
 * - The photon chain starts at the base vertex x (x_1 for a ball, x_2 for a plane, x_3 for a parallelepiped,
 *   x_4 for a parallelotope) and goes on along w[0] = ω_k, ..., w[k-1] = ω_1 (unit, Liu's eq. 11 order);
 *   eta_p is the time per unit length along those segments (one medium).
 * - tau is the time budget of a delta-sliced primitive: the gate time minus the light path's time at x minus
 *   the camera path's time at y1 (for the parallelotope: at y0, the sampled camera point). A root satisfies
 *   eta_p·Σt + eta_c·s = tau exactly.
 * - Roots with any t < 0, s < 0 or s > s_max are not returned. */
#ifndef DARTSPP_SLICED_PRIMITIVES_H
#define DARTSPP_SLICED_PRIMITIVES_H

#include "dartspp/core.h"

typedef struct {
    vec3 y1, psi;    /* camera segment origin and unit direction */
    double s_max;    /* its length */
    double eta_c;    /* time per unit length along it (0: unwarped) */
} slice_ray;

typedef struct {
    double t[4];     /* t_k, ..., t_1 (k entries used) */
    double s;        /* distance along the camera segment */
    vec3 w1;         /* ball only: ω_1*, the direction from x to the root */
    double jacobian; /* |J| at the root, > 0 (roots with |J| below 1e-12 relative are dropped) */
    double time;     /* eta_p·Σt + eta_c·s, the time the root adds to x's (= tau for delta-sliced roots; the
                      * planes' box gate reads it) */
} slice_root;

/* Sliced ball / VPL, Liu et al. 2022 §4.5, ξ_a = {cos θ1, φ1, t1, s1}: the points y1 + s·ψ at distance t1
 * from x with eta_p·t1 + eta_c·s = tau (a sphere when unwarped, the ellipsoid of Pediredla et al. 2019 when
 * eta_c = eta_p, a convex oval between). Up to 2 roots (1 on the ellipsoid); |J| = t1²·|eta_p·(ω1*·ψ) + eta_c|
 * (docs/sliced_primitives.md §6; Liu's formulas below eq. 46 are its eta_c = 0 and eta_c = eta_p cases). */
int slice_ball_roots(vec3 x, double eta_p, double tau, const slice_ray *r, slice_root out[2]);

/* Sliced photon plane, Liu et al. 2022 §4.2, ξ_a = {t2, t1, s1, τ_k} (box gates: no time constraint):
 * x + t2·ω2 + t1·ω1 = y1 + s·ψ, t2 in [0, len[0]], t1 in [0, len[1]] (short planes: the segments as sampled;
 * pass INFINITY for long). At most 1 root; |J| = |(ω2 × ω1)·ψ| (eq. 30, warped or not: the τ_k column is
 * (0, 0, 0, ±1)). root.time is set. */
int slice_plane_root(vec3 x, const vec3 w[2], const double len[2], double eta_p, const slice_ray *r,
                     slice_root *out);

/* The 1-D-blurred photon plane (planes_1d; Bitterli and Jarosz 2017's "photon plane 1D" as Liu's code has it,
 * made transient with a box gate: docs/sliced_primitives.md §7), ξ_a = {t2, t1, B, τ_k}: x + t2·ω2 + t1·ω1 +
 * B·n = y1 + s·ψ, n = ω2 × ω1 / |ω2 × ω1|, with a box kernel 1/(2r) on the blur B and s left to the caller
 * (numerical). Every s of the camera segment has one root; this gives the interval [s0, s1] of those with
 * 0 <= t2 <= len[0], 0 <= t1 <= len[1], |B| <= r and the root's time eta_p·(t2 + t1) + eta_c·s in
 * [time_lo, time_hi] (the gate less the light's time at x and the camera's at y1), and the roots as linear
 * functions of s. |J| = |ω2 × ω1| (the τ_k column (0, 0, 0, ±1), the B column (n, 0)). */
typedef struct {
    double s0, s1;        /* the interval, s0 < s1 */
    double t2[2], t1[2];  /* t2(s) = t2[0] + t2[1]·s, t1(s) likewise */
    double b[2];          /* B(s) */
    double jacobian;      /* |ω2 × ω1| */
} slice_interval;
int slice_plane1d_interval(vec3 x, const vec3 w[2], const double len[2], double radius, double eta_p,
                           const slice_ray *r, double time_lo, double time_hi, slice_interval *out);

/* Delta-sliced parallelepiped, Liu et al. 2022 §4.3, ξ_a = {t3, t2, t1, s1}: x + t3·ω3 + t2·ω2 + t1·ω1 =
 * y1 + s·ψ with the time constraint (eq. 35–37). At most 1 root; |J| = |det J| of eq. 37 with eta_c in the s
 * column's time entry = |eta_p·ψ·n + eta_c·ω1·(ω2 × ω3)|, n = ω1 × ω2 + ω2 × ω3 + ω3 × ω1 (eq. 38 is its
 * unwarped value; docs/sliced_primitives.md §6). */
int slice_parallelepiped_root(vec3 x, const vec3 w[3], double eta_p, double tau, const slice_ray *r,
                              slice_root *out);

/* Delta-sliced parallelotope, Liu et al. 2022 §4.4, ξ_a = {t4, t3, t2, t1}: x + Σ t_i·ω_i = y0 (a camera
 * point sampled by the caller; warping only moves tau) with eta_p·Σt = tau. At most 1 root (s unused);
 * |J| = |det| of eq. 43. */
int slice_parallelotope_root(vec3 x, const vec3 w[4], double eta_p, double tau, vec3 y0, slice_root *out);

/* |J| of each estimator at a given full path, for score-based MIS (Liu et al. 2022 §4.6), where the path was
 * found by another estimator: the ball's with t1, ω1 (x1 → x0); the parallelepiped's with its three
 * directions. */
double slice_ball_jacobian(double t1, vec3 w1, vec3 psi, double eta_p, double eta_c);
double slice_parallelepiped_jacobian(const vec3 w[3], vec3 psi, double eta_p, double eta_c);

/* Small dense linear algebra, written here (four lines each; no library needed for 4×4). */
double slice_det4(const double a[4][4]);
/* Solves a·x = b by Gaussian elimination with partial pivoting; 0 on success, -1 when singular. */
int slice_solve4(const double a[4][4], const double b[4], double x[4]);

#endif
