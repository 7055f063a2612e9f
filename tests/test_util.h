/* Shared helpers for the cmocka tests: temp folders, paths of the shipped scenes, running the CLI. */
#ifndef DARTSPP_TEST_UTIL_H
#define DARTSPP_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* Our own fog Cornell box (quads and cubes with the paper's dimensions, camera, medium, light and gate):
 * the scene of every test that is not about the paper's files themselves. */
#define CBOX_FOG "scenes/cbox-fog"

/* The folder of the paper's scenes (a copy of shared/scenes, holding cbox-trans/): $DARTSPP_PAPER_SCENES when
 * set and not empty, else ../shared/scenes when it is a folder (development and CI), else NULL. A repository
 * alone has none: the tests about the paper's files then skip (test_need_paper_files). */
static inline const char *test_paper_scenes(void)
{
    const char *env = getenv("DARTSPP_PAPER_SCENES");
    if (env && env[0]) return env;
    struct stat st;
    if (stat("../shared/scenes", &st) == 0 && S_ISDIR(st.st_mode)) return "../shared/scenes";
    return NULL;
}

/* For a test about the paper's own files: returns the paper scenes folder when every file of the
 * NULL-terminated list (paths relative to that folder) is readable there. Otherwise prints one line naming
 * the test and the reason and skips the test: cmocka's skip() does not return, so call this before the test
 * allocates anything that only its own code would free. */
#define test_need_paper_files(...) test_need_paper_files_(__func__, __VA_ARGS__)
static inline const char *test_need_paper_files_(const char *test, const char *first, ...)
{
    static const char hint[] = "paper scenes not found: set DARTSPP_PAPER_SCENES=DIR or put shared/ beside the checkout";
    const char *dir = test_paper_scenes();
    if (!dir) {
        print_message("skipped %s: no $DARTSPP_PAPER_SCENES and no ../shared/scenes; %s\n", test, hint);
        skip();
    }
    va_list ap;
    va_start(ap, first);
    for (const char *rel = first; rel; rel = va_arg(ap, const char *)) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, rel);
        if (access(path, R_OK) != 0) {
            va_end(ap);
            print_message("skipped %s: %s is missing; %s\n", test, path, hint);
            skip();
        }
    }
    va_end(ap);
    return dir;
}
/* The sanitized command-line binary built by `make test`. */
#define DARTSPP_BIN "build/san/dartspp"

/* A fresh temp folder for one test; the caller frees the string. */
static inline char *test_tmpdir(void)
{
    char *d = strdup("/tmp/dartspp-test-XXXXXX");
    if (!mkdtemp(d)) { free(d); return NULL; }
    return d;
}

static inline int test_remove_entry_(const char *p, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(p);
}

/* Removes a folder made by test_tmpdir with everything in it, and frees its name; NULL does nothing. */
static inline void test_rmtree(char *dir)
{
    if (dir) nftw(dir, test_remove_entry_, 16, FTW_DEPTH | FTW_PHYS);
    free(dir);
}

/* cmocka teardown of a test that put its test_tmpdir() folder in *state: the folder goes, even after a
 * failed assertion. */
static inline int test_teardown_tmpdir(void **state)
{
    test_rmtree(*state);
    *state = NULL;
    return 0;
}

static inline void test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Runs a shell command and returns its exit status (0..255), capturing stderr+stdout into out. */
static inline int test_run(const char *cmd, char *out, size_t out_len)
{
    char full[4224];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    if (!p) return -1;
    size_t n = 0;
    if (out && out_len) {
        out[0] = 0;
        n = fread(out, 1, out_len - 1, p);
        out[n] = 0;
    } else {
        char buf[4096];
        while (fread(buf, 1, sizeof buf, p) > 0) {}
    }
    int st = pclose(p);
    return (st >= 0 && WIFEXITED(st)) ? WEXITSTATUS(st) : -1;
}

#define ASSERT_NEAR(a, b, tol)                                                                                   \
    do {                                                                                                         \
        double a_ = (a), b_ = (b), t_ = (tol);                                                                   \
        if (!(fabs(a_ - b_) <= t_))                                                                              \
            fail_msg("%s:%d: %s = %.17g, expected %.17g (tolerance %g)", __FILE__, __LINE__, #a, a_, b_, t_);    \
    } while (0)

#define ASSERT_VEC(v, ex, ey, ez, tol)                                                                           \
    do {                                                                                                         \
        vec3 v_ = (v);                                                                                           \
        double t_ = (tol);                                                                                       \
        if (!(fabs(v_.x - (ex)) <= t_ && fabs(v_.y - (ey)) <= t_ && fabs(v_.z - (ez)) <= t_))                    \
            fail_msg("%s:%d: %s = (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g)", __FILE__, __LINE__, #v,      \
                     v_.x, v_.y, v_.z, (double)(ex), (double)(ey), (double)(ez));                                \
    } while (0)

/* Gauss–Legendre nodes x and weights w of order n on [-1, 1], by Newton iteration on P_n (exact for
 * polynomials of degree 2n - 1). */
static inline void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; i++) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16) break;
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* Little-endian writers for hand-made binary files (.wo3 meshes). */
static inline void put_u64(unsigned char *b, uint64_t v)
{
    for (int i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
}

static inline void put_u32(unsigned char *b, uint32_t v)
{
    for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
}

static inline void put_f32(unsigned char *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

/* The regularized upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a): the survival function of χ² with
 * k degrees of freedom at q is Q(k/2, q/2). Tested against closed forms in test_bsdf.c. */
/* Series for P(a, x) = e^{-x} x^a / Γ(a) · Σ_n x^n / (a (a+1) … (a+n)) when x < a + 1, continued fraction
 * for Q (modified Lentz) otherwise (the textbook split, Numerical Recipes §6.2). */
static inline double test_gamma_q(double a, double x)
{
    if (!(x > 0.0)) return 1.0;
    double lead = exp(-x + a * log(x) - lgamma(a));
    if (x < a + 1.0) {
        double ap = a, del = 1.0 / a, sum = del;
        for (int n = 0; n < 1000000; n++) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if (fabs(del) < fabs(sum) * 1e-16) break;
        }
        return fmax(0.0, 1.0 - sum * lead);
    }
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-16) break;
    }
    return lead * h;
}

#endif
