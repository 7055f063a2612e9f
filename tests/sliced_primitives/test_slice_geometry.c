/* tier: quick */
/* The geometry of Liu et al. 2022's temporally sliced photon primitives (include/dartspp/sliced_primitives.h,
 * src/sliced_primitives/slice_geometry.c), on random configurations, camera-unwarped (eta_c = 0), warped
 * (eta_c = eta_p) and with eta_c strictly between:
 *  a. every root satisfies g′ = 0: spatial and time residuals below 1e-9 relative;
 *  b. |J| equals |det| of the 4×4 central finite-difference Jacobian of g′ (written here from eq. 28, 35, 42,
 *     45 and our time row) with respect to the analytic dimensions, within 1e-5 relative: the ball in
 *     (cosθ1, φ1, t1, s1) about a random local frame, the others in their t's and s (the plane's 4th: τ_k);
 *  c. the number of roots against a brute-force scan of s along the segment (sign changes of the constraint);
 *     the ellipsoid (warped ball) has exactly 1 root when y1 is inside it and 0 outside, the sphere 0, 1 or 2;
 *  d. a change of variables that does not use the Jacobian formula: ξ_a drawn uniformly in a small box about a
 *     root, the share of g′(ξ_a) landing in a 4-D box of half-width ε about 0 against (2ε)⁴/(|J|·vol(box));
 *  e. the closed forms: the parallelepiped's eq. 38 when unwarped, and ours with the warped term.
 * Broken variants, run by the test itself on the same configurations (each must fail b or d; figures printed
 * and recorded in tests/README.md): Liu's code's unwarped ball Jacobian t1²·eta_p·|ω1·ψ| on a warped ray, a
 * sign flip of the camera's time entry, the t1² left out; eq. 38 (unwarped) on a warped ray. */
#include "fixtures.h"

#include "dartspp/sliced_primitives.h"

#define N_CONFIG 3000
#define N_SCAN 20000
#define N_SCAN_1D 2000 /* the 1-D plane's scan: a 4×4 solve a point */
#define FD_TOL 1e-5
#define RES_TOL 1e-9
#define Z_MAX 4.0

/* ---- g′ written from the paper's equations, for finite differences ---- */

typedef void (*g_fn)(const void *ctx, const double xi[4], double g[4]);

typedef struct {
    vec3 x;             /* base vertex */
    vec3 w[4];          /* its directions, ω_k ... ω_1 */
    slice_ray r;
    double eta_p, tau;
    vec3 y0;            /* parallelotope: the camera point */
    vec3 e1, e2, ez;    /* ball: the local frame of (cosθ1, φ1) */
} geo;

static void put(double g[4], vec3 v, double time)
{
    g[0] = v.x, g[1] = v.y, g[2] = v.z, g[3] = time;
}

/* eq. 45: x1 + t1·ω1(cosθ1, φ1) − (y1 + s1·ψ), time eta_p·t1 + eta_c·s1 − tau */
static void g_ball(const void *ctx, const double xi[4], double g[4])
{
    const geo *c = ctx;
    double ct = xi[0], st = sqrt(fmax(0.0, 1.0 - ct * ct));
    vec3 w = v3_add(v3_add(v3_scale(c->e1, st * cos(xi[1])), v3_scale(c->e2, st * sin(xi[1]))), v3_scale(c->ez, ct));
    vec3 d = v3_sub(v3_add(c->x, v3_scale(w, xi[2])), v3_add(c->r.y1, v3_scale(c->r.psi, xi[3])));
    put(g, d, c->eta_p * xi[2] + c->r.eta_c * xi[3] - c->tau);
}

/* eq. 35: x3 + t3·ω3 + t2·ω2 + t1·ω1 − (y1 + s1·ψ) */
static void g_parallelepiped(const void *ctx, const double xi[4], double g[4])
{
    const geo *c = ctx;
    vec3 p = c->x;
    for (int i = 0; i < 3; i++) p = v3_add(p, v3_scale(c->w[i], xi[i]));
    vec3 d = v3_sub(p, v3_add(c->r.y1, v3_scale(c->r.psi, xi[3])));
    put(g, d, c->eta_p * (xi[0] + xi[1] + xi[2]) + c->r.eta_c * xi[3] - c->tau);
}

/* eq. 42: x4 + Σ t_i·ω_i − y0 */
static void g_parallelotope(const void *ctx, const double xi[4], double g[4])
{
    const geo *c = ctx;
    vec3 p = c->x;
    for (int i = 0; i < 4; i++) p = v3_add(p, v3_scale(c->w[i], xi[i]));
    put(g, v3_sub(p, c->y0), c->eta_p * (xi[0] + xi[1] + xi[2] + xi[3]) - c->tau);
}

/* eq. 28 with the gate time τ_k as the 4th dimension (the light's time at x2 taken as 0) */
static void g_plane(const void *ctx, const double xi[4], double g[4])
{
    const geo *c = ctx;
    vec3 p = v3_add(v3_add(c->x, v3_scale(c->w[0], xi[0])), v3_scale(c->w[1], xi[1]));
    vec3 d = v3_sub(p, v3_add(c->r.y1, v3_scale(c->r.psi, xi[2])));
    put(g, d, c->eta_p * (xi[0] + xi[1]) + c->r.eta_c * xi[2] - xi[3]);
}

/* The central-difference Jacobian matrix ∂g′/∂ξ_a (columns: the dimensions). */
static void fd_matrix(g_fn g, const void *ctx, const double xi[4], double m[4][4])
{
    for (int j = 0; j < 4; j++) {
        double h = 1e-6 * fmax(1.0, fabs(xi[j])), a[4], b[4], lo[4], hi[4];
        memcpy(a, xi, sizeof a), memcpy(b, xi, sizeof b);
        a[j] += h, b[j] -= h;
        g(ctx, a, hi), g(ctx, b, lo);
        for (int i = 0; i < 4; i++) m[i][j] = (hi[i] - lo[i]) / (2.0 * h);
    }
}

static double fd_det(g_fn g, const void *ctx, const double xi[4])
{
    double m[4][4];
    fd_matrix(g, ctx, xi, m);
    return fabs(slice_det4(m));
}

/* Largest spatial residual (relative to the configuration's size) and time residual (relative to tau). */
static void residuals(g_fn g, const void *ctx, const double xi[4], double scale, double tau, double *rs, double *rt)
{
    double v[4];
    g(ctx, xi, v);
    *rs = fmax(*rs, sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / scale);
    *rt = fmax(*rt, fabs(v[3]) / tau);
}

/* ---- random configurations ---- */

static vec3 rand_dir(dp_rng *rng)
{
    double u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    return sample_uniform_sphere(u1, u2);
}

static vec3 rand_point(dp_rng *rng)
{
    double a = rng_uniform(rng), b = rng_uniform(rng), c = rng_uniform(rng);
    return v3(2.0 * a - 1.0, 2.0 * b - 1.0, 2.0 * c - 1.0);
}

/* The camera segment and the speeds; mode 0: unwarped, 1: warped (eta_c = eta_p), 2: eta_c in (0, eta_p). */
static void rand_ray(dp_rng *rng, int mode, geo *c)
{
    c->r.y1 = rand_point(rng);
    c->r.psi = rand_dir(rng);
    c->r.s_max = 0.5 + 3.5 * rng_uniform(rng);
    c->eta_p = 1.0 + 0.5 * rng_uniform(rng);
    c->r.eta_c = mode == 0 ? 0.0 : (mode == 1 ? c->eta_p : c->eta_p * (0.1 + 0.8 * rng_uniform(rng)));
}

static vec3 ray_at(const slice_ray *r, double s) { return v3_add(r->y1, v3_scale(r->psi, s)); }

/* ---- the ball ---- */

/* A ball configuration: half of them with tau set from a chosen point of the segment (at least one root),
 * half with tau at random (often none). */
static void rand_ball(dp_rng *rng, int mode, geo *c)
{
    rand_ray(rng, mode, c);
    c->x = rand_point(rng);
    if (rng_uniform(rng) < 0.5) {
        double s = c->r.s_max * rng_uniform(rng);
        c->tau = c->eta_p * v3_len(v3_sub(ray_at(&c->r, s), c->x)) + c->r.eta_c * s;
    } else {
        c->tau = c->eta_p * 4.0 * rng_uniform(rng);
    }
}

/* F(s) = eta_p·|y1 + sψ − x| + eta_c·s − tau: its sign changes on a fine scan of [0, s_max]. */
static int ball_scan(const geo *c)
{
    int n = 0;
    double prev = 0.0;
    for (int i = 0; i <= N_SCAN; i++) {
        double s = c->r.s_max * i / N_SCAN;
        double f = c->eta_p * v3_len(v3_sub(ray_at(&c->r, s), c->x)) + c->r.eta_c * s - c->tau;
        if (i > 0 && (f > 0.0) != (prev > 0.0)) n++;
        prev = f;
    }
    return n;
}

/* Roots a scan cannot separate or see: two within 3 steps of each other, or one within 3 steps of an end. */
static int scan_ambiguous(const slice_root *o, int n, double s_max)
{
    double step = 3.0 * s_max / N_SCAN;
    for (int i = 0; i < n; i++)
        if (o[i].s < step || o[i].s > s_max - step) return 1;
    return n == 2 && fabs(o[1].s - o[0].s) < step;
}

/* A local frame whose pole is at least 0.45 rad from ω1 (cosθ1 finite-differenced away from ±1). */
static void rand_frame(dp_rng *rng, vec3 w1, geo *c)
{
    do c->ez = rand_dir(rng);
    while (fabs(v3_dot(c->ez, w1)) > 0.9);
    vec3 a = fabs(c->ez.x) < 0.6 ? v3(1, 0, 0) : v3(0, 1, 0);
    c->e1 = v3_norm(v3_cross(a, c->ez));
    c->e2 = v3_cross(c->ez, c->e1);
}

static void ball_xi(const geo *c, const slice_root *o, double xi[4])
{
    xi[0] = v3_dot(o->w1, c->ez);
    xi[1] = atan2(v3_dot(o->w1, c->e2), v3_dot(o->w1, c->e1));
    xi[2] = o->t[0], xi[3] = o->s;
}

/* The broken ball Jacobians the checks must catch. */
enum { BALL_OK, BALL_LIU_CODE, BALL_TIME_SIGN, BALL_NO_T1SQ, BALL_VARIANTS };
static const char *ball_variant_name[BALL_VARIANTS] = {"ours", "Liu's code (unwarped |J| on a warped ray)",
                                                       "time row sign flipped", "t1^2 missing"};

static double ball_jacobian_variant(int v, double t1, vec3 w1, vec3 psi, double eta_p, double eta_c)
{
    switch (v) {
    case BALL_LIU_CODE: return t1 * t1 * eta_p * fabs(v3_dot(w1, psi));
    case BALL_TIME_SIGN: return t1 * t1 * fabs(eta_p * v3_dot(w1, psi) - eta_c);
    case BALL_NO_T1SQ: return fabs(eta_p * v3_dot(w1, psi) + eta_c);
    default: return slice_ball_jacobian(t1, w1, psi, eta_p, eta_c);
    }
}

static void test_ball_roots(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 1, 0);
    for (int mode = 0; mode < 3; mode++) {
        double rs = 0.0, rt = 0.0, fd = 0.0, broken[BALL_VARIANTS] = {0};
        int hist[3] = {0}, mism = 0, ambiguous = 0, nroots = 0;
        for (int k = 0; k < N_CONFIG; k++) {
            geo c;
            rand_ball(&rng, mode, &c);
            slice_root o[2];
            int n = slice_ball_roots(c.x, c.eta_p, c.tau, &c.r, o);
            assert_true(n >= 0 && n <= 2);
            hist[n]++;
            if (mode == 1) assert_true(n <= 1); /* the ellipsoid: a ray from its focus crosses it once */
            if (scan_ambiguous(o, n, c.r.s_max)) ambiguous++;
            else if (ball_scan(&c) != n) mism++;
            for (int i = 0; i < n; i++) {
                nroots++;
                double xi[4];
                rand_frame(&rng, o[i].w1, &c);
                ball_xi(&c, &o[i], xi);
                double scale = 1.0 + v3_len(v3_sub(c.x, c.r.y1)) + o[i].t[0] + o[i].s;
                residuals(g_ball, &c, xi, scale, c.tau, &rs, &rt);
                assert_true(fabs(o[i].time - c.tau) <= RES_TOL * c.tau);
                double ref = fd_det(g_ball, &c, xi);
                for (int v = 0; v < BALL_VARIANTS; v++) {
                    double j = v == BALL_OK ? o[i].jacobian
                                            : ball_jacobian_variant(v, o[i].t[0], o[i].w1, c.r.psi, c.eta_p, c.r.eta_c);
                    double e = fabs(j - ref) / ref;
                    if (v == BALL_OK) fd = fmax(fd, e);
                    else broken[v] = fmax(broken[v], e);
                }
            }
        }
        printf("ball eta_c %s: roots 0/1/2 in %d/%d/%d configurations, %d roots; residuals %.2e (space) %.2e "
               "(time); |J| against finite differences %.2e; scan mismatches %d (%d near-tangent or at an end "
               "left out)\n",
               mode == 0 ? "0" : (mode == 1 ? "= eta_p" : "in (0, eta_p)"), hist[0], hist[1], hist[2], nroots, rs,
               rt, fd, mism, ambiguous);
        for (int v = 1; v < BALL_VARIANTS; v++)
            printf("  broken variant \"%s\": largest relative error %.3g%s\n", ball_variant_name[v], broken[v],
                   broken[v] > FD_TOL ? " (caught)"
                                      : (mode == 0 && v != BALL_NO_T1SQ ? " (the same when unwarped)" : ""));
        assert_true(rs < RES_TOL && rt < RES_TOL);
        assert_true(fd < FD_TOL);
        assert_int_equal(mism, 0);
        assert_true(ambiguous < N_CONFIG / 100);
        assert_true(hist[1] > 100);
        if (mode == 0) assert_true(hist[0] > 100 && hist[2] > 100); /* the sphere: 0, 1 or 2 */
        if (mode == 2) assert_true(hist[2] > 0);                    /* eta_c < eta_p: a second crossing exists */
        /* every broken variant fails where it differs: the missing t1² always, the others when warped */
        assert_true(broken[BALL_NO_T1SQ] > 1e-2);
        if (mode != 0) assert_true(broken[BALL_LIU_CODE] > 1e-2 && broken[BALL_TIME_SIGN] > 1e-2);
    }
}

/* The warped ball's ellipsoid: exactly 1 root when y1 is inside it (eta_p·|y1 − x| < tau) and the segment
 * long enough to leave it, 0 outside; the sphere: 1 root when y1 is inside, 0 or 2 outside. Counted on rays
 * 1000 long (F(s) is convex in s and grows without bound, so these counts are exact). */
static void test_ball_root_counts(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 2, 0);
    int inside[2] = {0}, outside2 = 0, outside0 = 0;
    for (int k = 0; k < 4000; k++) {
        int warped = k % 2;
        geo c;
        rand_ball(&rng, warped, &c);
        c.r.s_max = 1000.0;
        c.tau = c.eta_p * 3.0 * rng_uniform(&rng);
        slice_root o[2];
        int n = slice_ball_roots(c.x, c.eta_p, c.tau, &c.r, o);
        int in = c.eta_p * v3_len(v3_sub(c.r.y1, c.x)) < c.tau;
        if (in) assert_int_equal(n, 1), inside[warped]++;
        else if (warped) assert_int_equal(n, 0);
        else {
            assert_true(n == 0 || n == 2);
            if (n == 2) outside2++;
            else outside0++;
        }
    }
    printf("ellipsoid: %d rays from inside, 1 root each; sphere: %d from inside (1 root), %d from outside with 2, "
           "%d with 0\n",
           inside[1], inside[0], outside2, outside0);
    assert_true(inside[0] > 100 && inside[1] > 100 && outside2 > 50 && outside0 > 100);
}

/* ---- the parallelepiped ---- */

static void rand_dirs(dp_rng *rng, int k, vec3 *w)
{
    for (int i = 0; i < k; i++) w[i] = rand_dir(rng);
}

/* Half the configurations built about a chosen root (t's in [0.05, 1.5], s in [0, s_max]), half at random. */
static void rand_parallelepiped(dp_rng *rng, int mode, geo *c)
{
    rand_ray(rng, mode, c);
    rand_dirs(rng, 3, c->w);
    if (rng_uniform(rng) < 0.5) {
        double s = c->r.s_max * rng_uniform(rng), sum = 0.0;
        vec3 p = ray_at(&c->r, s);
        for (int i = 0; i < 3; i++) {
            double t = 0.05 + 1.45 * rng_uniform(rng);
            p = v3_sub(p, v3_scale(c->w[i], t)), sum += t;
        }
        c->x = p;
        c->tau = c->eta_p * sum + c->r.eta_c * s;
    } else {
        c->x = rand_point(rng);
        c->tau = c->eta_p * 4.0 * rng_uniform(rng);
    }
}

/* Brute force: for s on a fine scan, (t3, t2, t1) from the three spatial equations (Cramer), F(s) =
 * eta_p·Σt + eta_c·s − tau; a root where F changes sign with every t ≥ 0 there. */
static int parallelepiped_scan(const geo *c, double *s_at)
{
    double D = v3_dot(c->w[0], v3_cross(c->w[1], c->w[2]));
    int n = 0;
    double prev = 0.0;
    for (int i = 0; i <= N_SCAN; i++) {
        double s = c->r.s_max * i / N_SCAN;
        vec3 d = v3_sub(ray_at(&c->r, s), c->x);
        double t3 = v3_dot(d, v3_cross(c->w[1], c->w[2])) / D;
        double t2 = v3_dot(c->w[0], v3_cross(d, c->w[2])) / D;
        double t1 = v3_dot(c->w[0], v3_cross(c->w[1], d)) / D;
        double f = c->eta_p * (t3 + t2 + t1) + c->r.eta_c * s - c->tau;
        if (i > 0 && (f > 0.0) != (prev > 0.0) && t3 >= 0.0 && t2 >= 0.0 && t1 >= 0.0) n++, *s_at = s;
        prev = f;
    }
    return n;
}

/* Eq. 38 (unwarped) and, with our derivation, the warped term: |eta_p·ψ·n + eta_c·ω1·(ω2 × ω3)|,
 * n = ω1 × ω2 + ω2 × ω3 + ω3 × ω1 (docs/sliced_primitives.md §6). */
static double parallelepiped_closed_form(const vec3 w[3], vec3 psi, double eta_p, double eta_c)
{
    vec3 w3 = w[0], w2 = w[1], w1 = w[2];
    vec3 n = v3_add(v3_add(v3_cross(w1, w2), v3_cross(w2, w3)), v3_cross(w3, w1));
    return fabs(eta_p * v3_dot(psi, n) + eta_c * v3_dot(w1, v3_cross(w2, w3)));
}

static void test_parallelepiped_roots(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 3, 0);
    for (int mode = 0; mode < 3; mode++) {
        double rs = 0.0, rt = 0.0, fd = 0.0, cf = 0.0, eq38 = 0.0, flip = 0.0;
        int hist[2] = {0}, mism = 0, ambiguous = 0;
        for (int k = 0; k < N_CONFIG; k++) {
            geo c;
            rand_parallelepiped(&rng, mode, &c);
            slice_root o;
            int n = slice_parallelepiped_root(c.x, c.w, c.eta_p, c.tau, &c.r, &o);
            hist[n]++;
            double s_scan = -1.0;
            int m = parallelepiped_scan(&c, &s_scan);
            /* a root within 3 steps of an end or of a face (some t near 0) is not resolved by the scan */
            double step = 3.0 * c.r.s_max / N_SCAN;
            int near = n && (o.s < step || o.s > c.r.s_max - step || fmin(o.t[0], fmin(o.t[1], o.t[2])) < 1e-3);
            if (near) ambiguous++;
            else if (m != n) mism++;
            if (!n) continue;
            double xi[4] = {o.t[0], o.t[1], o.t[2], o.s};
            double scale = 1.0 + v3_len(v3_sub(c.x, c.r.y1)) + o.t[0] + o.t[1] + o.t[2] + o.s;
            residuals(g_parallelepiped, &c, xi, scale, c.tau, &rs, &rt);
            double ref = fd_det(g_parallelepiped, &c, xi);
            fd = fmax(fd, fabs(o.jacobian - ref) / ref);
            assert_true(fabs(slice_parallelepiped_jacobian(c.w, c.r.psi, c.eta_p, c.r.eta_c) - o.jacobian) <=
                        1e-12 * o.jacobian);
            cf = fmax(cf, fabs(parallelepiped_closed_form(c.w, c.r.psi, c.eta_p, c.r.eta_c) - ref) / ref);
            /* broken: eq. 38 whatever the camera's time; the camera's time entry with the wrong sign */
            eq38 = fmax(eq38, fabs(parallelepiped_closed_form(c.w, c.r.psi, c.eta_p, 0.0) - ref) / ref);
            flip = fmax(flip, fabs(slice_parallelepiped_jacobian(c.w, c.r.psi, c.eta_p, -c.r.eta_c) - ref) / ref);
        }
        printf("parallelepiped eta_c %s: roots 0/1 in %d/%d configurations; residuals %.2e %.2e; |J| against "
               "finite differences %.2e, against the closed form %.2e; scan mismatches %d (%d at an end or a face "
               "left out); broken: eq. 38 %.3g, time entry sign flipped %.3g\n",
               mode == 0 ? "0" : (mode == 1 ? "= eta_p" : "in (0, eta_p)"), hist[0], hist[1], rs, rt, fd, cf, mism,
               ambiguous, eq38, flip);
        assert_true(rs < RES_TOL && rt < RES_TOL);
        assert_true(fd < FD_TOL && cf < FD_TOL);
        assert_int_equal(mism, 0);
        assert_true(ambiguous < N_CONFIG / 100);
        assert_true(hist[0] > 100 && hist[1] > 100);
        if (mode != 0) assert_true(eq38 > 1e-2 && flip > 1e-2);
    }
}

/* ---- the parallelotope ---- */

/* Half about a chosen root (y0 = x + Σ t_i·ω_i, t's in [0.05, 1.5]), half at random. Residuals and |J|
 * against finite differences; a root exactly when the solution of the 4×4 system has every t ≥ 0 (checked
 * by Cramer's rule on the same system written out here). */
static void test_parallelotope_roots(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 6, 0);
    double rs = 0.0, rt = 0.0, fd = 0.0;
    int hist[2] = {0};
    for (int k = 0; k < N_CONFIG; k++) {
        geo c;
        c.eta_p = 1.0 + 0.5 * rng_uniform(&rng);
        rand_dirs(&rng, 4, c.w);
        c.x = rand_point(&rng);
        if (k % 2) {
            double sum = 0.0;
            c.y0 = c.x;
            for (int i = 0; i < 4; i++) {
                double t = 0.05 + 1.45 * rng_uniform(&rng);
                c.y0 = v3_add(c.y0, v3_scale(c.w[i], t)), sum += t;
            }
            c.tau = c.eta_p * sum;
        } else {
            c.y0 = rand_point(&rng);
            c.tau = c.eta_p * 4.0 * rng_uniform(&rng);
        }
        slice_root o;
        int n = slice_parallelotope_root(c.x, c.w, c.eta_p, c.tau, c.y0, &o);
        hist[n]++;
        /* Cramer on eq. 42 */
        double a[4][4], b[4] = {c.y0.x - c.x.x, c.y0.y - c.x.y, c.y0.z - c.x.z, c.tau}, D;
        for (int j = 0; j < 4; j++) a[0][j] = c.w[j].x, a[1][j] = c.w[j].y, a[2][j] = c.w[j].z, a[3][j] = c.eta_p;
        D = slice_det4(a);
        int want = 1;
        for (int j = 0; j < 4; j++) {
            double aj[4][4];
            memcpy(aj, a, sizeof aj);
            for (int i = 0; i < 4; i++) aj[i][j] = b[i];
            if (slice_det4(aj) / D < 0.0) want = 0;
        }
        if (k % 2) assert_int_equal(n, 1);
        assert_int_equal(n, want);
        if (!n) continue;
        double xi[4] = {o.t[0], o.t[1], o.t[2], o.t[3]};
        double scale = 1.0 + v3_len(v3_sub(c.x, c.y0)) + o.t[0] + o.t[1] + o.t[2] + o.t[3];
        residuals(g_parallelotope, &c, xi, scale, c.tau, &rs, &rt);
        double ref = fd_det(g_parallelotope, &c, xi);
        fd = fmax(fd, fabs(o.jacobian - ref) / ref);
    }
    printf("parallelotope: roots 0/1 in %d/%d configurations; residuals %.2e %.2e; |J| against finite "
           "differences %.2e\n",
           hist[0], hist[1], rs, rt, fd);
    assert_true(rs < RES_TOL && rt < RES_TOL && fd < FD_TOL);
}

/* ---- the photon plane ---- */

/* Half about a chosen root (t2, t1 in [0.05, 1.5], s in [0, s_max]), half at random; lengths finite or
 * INFINITY. The brute force: the signed distance of y1 + sψ to the plane, its sign changes on a scan, with
 * (t2, t1) at the crossing inside the lengths. Broken variant: |ω2 × ω1| (the plane's area element without the
 * camera's direction). */
static void test_plane_roots(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 7, 0);
    for (int mode = 0; mode < 2; mode++) {
        double rs = 0.0, rt = 0.0, fd = 0.0, broken = 0.0;
        int hist[2] = {0}, mism = 0, ambiguous = 0;
        for (int k = 0; k < N_CONFIG; k++) {
            geo c;
            rand_ray(&rng, mode, &c);
            rand_dirs(&rng, 2, c.w);
            double len[2];
            for (int i = 0; i < 2; i++) len[i] = rng_uniform(&rng) < 0.3 ? INFINITY : 0.2 + 1.8 * rng_uniform(&rng);
            if (k % 2) {
                double s = c.r.s_max * rng_uniform(&rng);
                c.x = ray_at(&c.r, s);
                for (int i = 0; i < 2; i++)
                    c.x = v3_sub(c.x, v3_scale(c.w[i], (isinf(len[i]) ? 1.5 : len[i]) * rng_uniform(&rng)));
            } else {
                c.x = rand_point(&rng);
            }
            slice_root o;
            int n = slice_plane_root(c.x, c.w, len, c.eta_p, &c.r, &o);
            hist[n]++;
            /* the scan */
            vec3 nrm = v3_cross(c.w[0], c.w[1]);
            int m = 0;
            double prev = 0.0;
            for (int i = 0; i <= N_SCAN; i++) {
                double s = c.r.s_max * i / N_SCAN;
                vec3 d = v3_sub(ray_at(&c.r, s), c.x);
                double f = v3_dot(d, nrm);
                if (i > 0 && (f > 0.0) != (prev > 0.0)) {
                    /* f is linear in s: the crossing by interpolation, then (t2, t1) of that point in the
                     * plane from the 2×2 normal equations */
                    double sc = s - f * (c.r.s_max / N_SCAN) / (f - prev);
                    d = v3_sub(ray_at(&c.r, sc), c.x);
                    double a11 = v3_dot(c.w[0], c.w[0]), a12 = v3_dot(c.w[0], c.w[1]), a22 = v3_dot(c.w[1], c.w[1]);
                    double b1 = v3_dot(d, c.w[0]), b2 = v3_dot(d, c.w[1]), det = a11 * a22 - a12 * a12;
                    double t2 = (b1 * a22 - b2 * a12) / det, t1 = (a11 * b2 - a12 * b1) / det;
                    if (t2 >= 0.0 && t2 <= len[0] && t1 >= 0.0 && t1 <= len[1]) m++;
                }
                prev = f;
            }
            double step = 3.0 * c.r.s_max / N_SCAN;
            if (n && (o.s < step || o.s > c.r.s_max - step)) ambiguous++;
            else if (m != n) mism++;
            if (!n) continue;
            double xi[4] = {o.t[0], o.t[1], o.s, o.time};
            double scale = 1.0 + v3_len(v3_sub(c.x, c.r.y1)) + o.t[0] + o.t[1] + o.s, time = 0.0;
            residuals(g_plane, &c, xi, scale, 1.0, &rs, &time);
            assert_true(fabs(o.time - (c.eta_p * (o.t[0] + o.t[1]) + c.r.eta_c * o.s)) <= 1e-12 * o.time);
            double ref = fd_det(g_plane, &c, xi);
            fd = fmax(fd, fabs(o.jacobian - ref) / ref);
            broken = fmax(broken, fabs(v3_len(nrm) - ref) / ref);
            rt = fmax(rt, time);
        }
        printf("plane eta_c %s: roots 0/1 in %d/%d configurations; residuals %.2e %.2e; |J| against finite "
               "differences %.2e; scan mismatches %d (%d at an end or an edge left out); broken |w2 x w1| %.3g\n",
               mode ? "= eta_p" : "0", hist[0], hist[1], rs, rt, fd, mism, ambiguous, broken);
        assert_true(rs < RES_TOL && rt < RES_TOL && fd < FD_TOL);
        assert_int_equal(mism, 0);
        assert_true(ambiguous < N_CONFIG / 50);
        assert_true(hist[0] > 100 && hist[1] > 100);
        assert_true(broken > 1e-2);
    }
}

/* ---- the 1-D-blurred photon plane ---- */

/* The point y1 + s·ψ decomposed in (ω2, ω1, n) by a 4×4 solve (the time row a dummy identity), independent of
 * the dual basis the code uses; whether it is inside the blurred plane and the time window. */
static int plane1d_inside(const geo *c, const double len[2], double radius, double lo, double hi, double s)
{
    vec3 n = v3_norm(v3_cross(c->w[0], c->w[1])), d = v3_sub(ray_at(&c->r, s), c->x);
    double a[4][4] = {{c->w[0].x, c->w[1].x, n.x, 0}, {c->w[0].y, c->w[1].y, n.y, 0}, {c->w[0].z, c->w[1].z, n.z, 0},
                      {0, 0, 0, 1}};
    double b[4] = {d.x, d.y, d.z, 0}, t[4];
    if (slice_solve4(a, b, t)) return 0;
    double time = c->eta_p * (t[0] + t[1]) + c->r.eta_c * s;
    return t[0] >= 0 && t[0] <= len[0] && t[1] >= 0 && t[1] <= len[1] && fabs(t[2]) <= radius && time >= lo &&
           time <= hi;
}

/* g′ of the 1-D plane in (t2, t1, B, τ_k) at a fixed s (eq. 28 with the blur B along n) */
typedef struct {
    geo g;
    double s;
} plane1d_ctx;

static void g_plane1d(const void *ctx, const double xi[4], double g[4])
{
    const plane1d_ctx *c = ctx;
    vec3 n = v3_norm(v3_cross(c->g.w[0], c->g.w[1]));
    vec3 p = v3_add(v3_add(v3_add(c->g.x, v3_scale(c->g.w[0], xi[0])), v3_scale(c->g.w[1], xi[1])), v3_scale(n, xi[2]));
    put(g, v3_sub(p, ray_at(&c->g.r, c->s)), c->g.eta_p * (xi[0] + xi[1]) + c->g.r.eta_c * c->s - xi[3]);
}

/* The interval against a scan of s (every scanned s inside the blurred plane and the window lies in [s0, s1]
 * and the reverse, but within a step of the ends); the roots' residuals and |J| against finite differences at
 * three s of the interval. Broken variant: the interval found with the camera's time left out (eta_c = 0) on a
 * warped ray (the time window slid as Liu's code has it). */
static void test_plane1d_interval(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 8, 0);
    for (int mode = 0; mode < 2; mode++) {
        int found = 0, mism = 0, broken_mism = 0;
        double rs = 0.0, fd = 0.0;
        for (int k = 0; k < N_CONFIG / 3; k++) {
            plane1d_ctx pc;
            geo *c = &pc.g;
            rand_ray(&rng, mode, c);
            rand_dirs(&rng, 2, c->w);
            double len[2], radius = 0.02 + 0.3 * rng_uniform(&rng);
            for (int i = 0; i < 2; i++) len[i] = rng_uniform(&rng) < 0.3 ? INFINITY : 0.2 + 1.8 * rng_uniform(&rng);
            double sx = c->r.s_max * rng_uniform(&rng);
            c->x = ray_at(&c->r, sx);
            for (int i = 0; i < 2; i++)
                c->x = v3_sub(c->x, v3_scale(c->w[i], (isinf(len[i]) ? 1.5 : len[i]) * rng_uniform(&rng)));
            double lo = c->eta_p * 3.0 * rng_uniform(&rng), hi = lo + c->eta_p * (0.1 + rng_uniform(&rng));
            slice_interval iv, bad;
            int n = slice_plane1d_interval(c->x, c->w, len, radius, c->eta_p, &c->r, lo, hi, &iv);
            slice_ray r0 = c->r;
            r0.eta_c = 0.0;
            int nb = slice_plane1d_interval(c->x, c->w, len, radius, c->eta_p, &r0, lo, hi, &bad);
            double step = c->r.s_max / N_SCAN_1D;
            for (int i = 0; i <= N_SCAN_1D; i++) {
                double s = c->r.s_max * i / N_SCAN_1D;
                int in = plane1d_inside(c, len, radius, lo, hi, s);
                int claimed = n && s >= iv.s0 && s <= iv.s1;
                int near = n && (fabs(s - iv.s0) < step || fabs(s - iv.s1) < step);
                if (in != claimed && !near) mism++;
                int bclaimed = nb && s >= bad.s0 && s <= bad.s1;
                int bnear = nb && (fabs(s - bad.s0) < step || fabs(s - bad.s1) < step);
                if (in != bclaimed && !bnear) broken_mism++;
            }
            if (!n) continue;
            found++;
            for (int q = 0; q < 3; q++) {
                pc.s = iv.s0 + (iv.s1 - iv.s0) * (0.1 + 0.4 * q);
                double xi[4] = {iv.t2[0] + iv.t2[1] * pc.s, iv.t1[0] + iv.t1[1] * pc.s, iv.b[0] + iv.b[1] * pc.s, 0.0};
                xi[3] = c->eta_p * (xi[0] + xi[1]) + c->r.eta_c * pc.s;
                double g[4], scale = 1.0 + v3_len(v3_sub(c->x, c->r.y1)) + fabs(xi[0]) + fabs(xi[1]) + pc.s;
                g_plane1d(&pc, xi, g);
                rs = fmax(rs, sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / scale);
                assert_true(fabs(xi[2]) <= radius * (1.0 + 1e-9) && xi[3] >= lo - 1e-9 && xi[3] <= hi + 1e-9);
                double ref = fd_det(g_plane1d, &pc, xi);
                fd = fmax(fd, fabs(iv.jacobian - ref) / ref);
            }
        }
        printf("planes_1d eta_c %s: %d of %d configurations with an interval; scanned points misplaced %d; "
               "residuals %.2e; |J| against finite differences %.2e; broken (camera time left out): %d points "
               "misplaced\n",
               mode ? "= eta_p" : "0", found, N_CONFIG / 3, mism, rs, fd, broken_mism);
        assert_int_equal(mism, 0);
        assert_true(found > 100);
        assert_true(rs < RES_TOL && fd < FD_TOL);
        if (mode) assert_true(broken_mism > 100);
    }
}

/* ---- change of variables without the Jacobian formula ---- */

/* ξ_a drawn uniformly in a box about the root xi0 that holds the preimage of the 4-D box |g′| < ε (sized from
 * the finite-difference matrix's inverse, 1.25 × its extent); the count landing in the ε-box against
 * N·(2ε)⁴ / (|J|·vol(box)) for each candidate |J|. Returns z for each. */
static int cov_check(g_fn g, const void *ctx, const double xi0[4], double eps, const double *jac, int nj, long N,
                     dp_rng *rng, double *z)
{
    double m[4][4], h[4] = {0}, vol = 1.0;
    fd_matrix(g, ctx, xi0, m);
    for (int j = 0; j < 4; j++) {
        double e[4] = {0}, col[4];
        e[j] = 1.0;
        if (slice_solve4(m, e, col)) return -1;
        for (int i = 0; i < 4; i++) h[i] += 1.25 * eps * fabs(col[i]);
    }
    for (int i = 0; i < 4; i++) vol *= 2.0 * h[i];
    long hits = 0;
    for (long k = 0; k < N; k++) {
        double xi[4], v[4];
        for (int i = 0; i < 4; i++) xi[i] = xi0[i] + (2.0 * rng_uniform(rng) - 1.0) * h[i];
        g(ctx, xi, v);
        if (fabs(v[0]) < eps && fabs(v[1]) < eps && fabs(v[2]) < eps && fabs(v[3]) < eps) hits++;
    }
    for (int q = 0; q < nj; q++) {
        double p = pow(2.0 * eps, 4) / (jac[q] * vol);
        if (p > 1.0) p = 1.0;
        z[q] = ((double)hits - N * p) / sqrt(fmax(N * p * (1.0 - p), 1.0));
    }
    return 0;
}

static void test_change_of_variables(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 4, 0);
    const long N = 200000;
    const double eps = 1e-3;
    double zmax = 0.0, zb[BALL_VARIANTS] = {0}, zpe[2] = {0};
    int done = 0;
    /* the ball: 4 roots per mode, t1 kept away from 1 (so the missing t1² shows) and |ω1·ψ| from 0 */
    for (int mode = 0; mode < 3; mode++) {
        for (int got = 0, tries = 0; got < 4 && tries < 10000; tries++) {
            geo c;
            rand_ball(&rng, mode, &c);
            slice_root o[2];
            int n = slice_ball_roots(c.x, c.eta_p, c.tau, &c.r, o);
            if (!n || fabs(o[0].t[0] * o[0].t[0] - 1.0) < 0.5 || fabs(v3_dot(o[0].w1, c.r.psi)) < 0.3) continue;
            double xi[4], jac[BALL_VARIANTS], z[BALL_VARIANTS];
            rand_frame(&rng, o[0].w1, &c);
            ball_xi(&c, &o[0], xi);
            for (int v = 0; v < BALL_VARIANTS; v++)
                jac[v] = ball_jacobian_variant(v, o[0].t[0], o[0].w1, c.r.psi, c.eta_p, c.r.eta_c);
            jac[0] = o[0].jacobian;
            if (cov_check(g_ball, &c, xi, eps * fmin(1.0, o[0].t[0]), jac, BALL_VARIANTS, N, &rng, z)) continue;
            zmax = fmax(zmax, fabs(z[0]));
            for (int v = 1; v < BALL_VARIANTS; v++) zb[v] = fmax(zb[v], fabs(z[v]));
            got++, done++;
        }
    }
    /* the parallelepiped: 4 per mode; broken: eq. 38 and the flipped time entry */
    for (int mode = 0; mode < 3; mode++) {
        for (int got = 0, tries = 0; got < 4 && tries < 10000; tries++) {
            geo c;
            rand_parallelepiped(&rng, mode, &c);
            slice_root o;
            if (!slice_parallelepiped_root(c.x, c.w, c.eta_p, c.tau, &c.r, &o)) continue;
            double xi[4] = {o.t[0], o.t[1], o.t[2], o.s}, z[3];
            double jac[3] = {o.jacobian, parallelepiped_closed_form(c.w, c.r.psi, c.eta_p, 0.0),
                             slice_parallelepiped_jacobian(c.w, c.r.psi, c.eta_p, -c.r.eta_c)};
            if (cov_check(g_parallelepiped, &c, xi, eps, jac, 3, N, &rng, z)) continue;
            zmax = fmax(zmax, fabs(z[0]));
            if (mode) zpe[0] = fmax(zpe[0], fabs(z[1])), zpe[1] = fmax(zpe[1], fabs(z[2]));
            got++, done++;
        }
    }
    printf("change of variables: %d roots, %ld draws each, largest |z| %.2f; broken: ball %s %.1f, %s %.1f, %s "
           "%.1f; parallelepiped eq. 38 warped %.1f, time entry flipped %.1f\n",
           done, N, zmax, ball_variant_name[1], zb[1], ball_variant_name[2], zb[2], ball_variant_name[3], zb[3],
           zpe[0], zpe[1]);
    assert_int_equal(done, 24);
    assert_true(zmax < Z_MAX);
    for (int v = 1; v < BALL_VARIANTS; v++) assert_true(zb[v] > Z_MAX);
    assert_true(zpe[0] > Z_MAX && zpe[1] > Z_MAX);
}

/* ---- the 4×4 helpers ---- */

/* det(L·U) = Π diag for random triangular factors; slice_solve4's residual; a singular matrix refused. */
static void test_det_solve(void **state)
{
    (void)state;
    dp_rng rng = rng_stream(49, 5, 0);
    for (int k = 0; k < 200; k++) {
        double L[4][4] = {{0}}, U[4][4] = {{0}}, A[4][4] = {{0}}, b[4], x[4], want = 1.0;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                if (j < i) L[i][j] = 2.0 * rng_uniform(&rng) - 1.0;
                if (j >= i) U[i][j] = 2.0 * rng_uniform(&rng) - 1.0;
            }
        for (int i = 0; i < 4; i++) L[i][i] = 1.0, U[i][i] = 0.2 + rng_uniform(&rng), want *= U[i][i];
        /* a row swap negates the determinant */
        int p = k % 4, q = (k + 1) % 4;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                for (int m = 0; m < 4; m++) A[i == p ? q : (i == q ? p : i)][j] += L[i][m] * U[m][j];
        assert_true(fabs(slice_det4(A) + want) < 1e-12 * fabs(want) + 1e-14);
        for (int i = 0; i < 4; i++) b[i] = 2.0 * rng_uniform(&rng) - 1.0;
        assert_int_equal(slice_solve4(A, b, x), 0);
        for (int i = 0; i < 4; i++) {
            double r = -b[i];
            for (int j = 0; j < 4; j++) r += A[i][j] * x[j];
            assert_true(fabs(r) < 1e-10);
        }
    }
    double S[4][4] = {{1, 2, 3, 4}, {2, 4, 6, 8}, {0, 1, 0, 1}, {1, 0, 1, 0}}, b[4] = {1, 1, 1, 1}, x[4];
    assert_true(fabs(slice_det4(S)) < 1e-14);
    assert_int_equal(slice_solve4(S, b, x), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_det_solve),
        cmocka_unit_test(test_ball_roots),
        cmocka_unit_test(test_ball_root_counts),
        cmocka_unit_test(test_parallelepiped_roots),
        cmocka_unit_test(test_parallelotope_roots),
        cmocka_unit_test(test_plane_roots),
        cmocka_unit_test(test_plane1d_interval),
        cmocka_unit_test(test_change_of_variables),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
