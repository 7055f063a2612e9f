/* Fixtures shared by the test programs, defined in tests/fixtures.c (linked into every test program): files
 * and temp folders, the per-test fixture of scenes and buffers that a teardown releases, the base scene of
 * the loader's tests, and the image helpers of the io tests. Render-level helpers: render_fixtures.h. */
#ifndef DARTSPP_TEST_FIXTURES_H
#define DARTSPP_TEST_FIXTURES_H

#include "test_util.h"

#include "dartspp/io.h"
#include "dartspp/scene.h"

/* ---- files and folders ---- */

#define ASSERT_CONTAINS(hay, needle)                                                                             \
    do {                                                                                                         \
        const char *h_ = (hay), *n_ = (needle);                                                                  \
        if (!h_ || !strstr(h_, n_))                                                                              \
            fail_msg("%s:%d: expected \"%s\" in:\n%s", __FILE__, __LINE__, n_, h_ ? h_ : "(null)");             \
    } while (0)

void write_bytes(const char *path, const void *data, size_t n);
/* The whole file, 0-terminated (its length in *len when len is not NULL); the caller frees it. */
char *read_all(const char *path, size_t *len);
/* Copy of s with the first occurrence of `from` replaced by `to`; the test fails if `from` is absent. */
char *replace1(const char *s, const char *from, const char *to);
void rm_rf(const char *dir);
char *tmpdir_or_fail(void);

/* ---- χ² goodness of fit ---- */

/* Observed and expected counts of one histogram cell. */
typedef struct {
    double obs, exp;
} chi_cell;

/* Pearson's χ² over the cells (sorted in place by expected count), cells expected below 5 pooled into one;
 * the p-value (0 when no degree of freedom is left), with χ² and the degrees of freedom in *chi2_out and
 * *dof_out. With `impossible` given, cells expected 0 are left out and their observations counted there (a
 * sampler producing what its density says cannot happen). */
double chi2_pooled(chi_cell *cells, int n, double *chi2_out, int *dof_out, long *impossible);

/* ---- what a render wrote ---- */

/* The pass count in an EXR's dartspp.passes header (the test fails when it cannot be read). */
long exr_passes(const char *path);
/* The pass count in a checkpoint state's header (<stem>.state), or -1 when there is none (yet). */
long state_passes(const char *path);
/* Our fog Cornell box (scenes/cbox-fog/transient.json) at res × res pixels, written to path. */
void write_cbox_fog(const char *path, int res);
/* A fresh temp folder holding that box as box.json (the MPI tests' scene); NULL when none can be made. */
char *tmpdir_with_cbox_fog(int res);
/* Whether DARTSPP_STRESS=full (`make stress`): the programs with the stress tag line then run their whole
 * matrix and their long statistical cases (tests/README.md, Stress matrix); `make test` runs a fast subset. */
int stress_full(void);
/* cmocka's group run of the cases `make test` runs, then, under DARTSPP_STRESS=full only, the long ones. */
#define RUN_TESTS_AND_STRESS(tests, stress_tests)                                                              \
    (cmocka_run_group_tests_name("tests", tests, NULL, NULL) +                                                \
     (stress_full() ? cmocka_run_group_tests_name("stress", stress_tests, NULL, NULL) : 0))

/* A group's setup and teardown around it: our fog Cornell box at 40×40 pixels in the folder cbox_dir (the MPI
 * tests), removed with the folder by the teardown. */
extern char *cbox_dir;
int setup_cbox_fog40(void **state);
int teardown_cbox_fog(void **state);
/* Largest |a − b| / (|b| + tiny) over two image files of the same size, both finite, b lit (fails otherwise). */
double image_max_rel_diff(const char *a_path, const char *b_path);

/* ---- the per-test fixture: scenes, buffers and one temp folder ---- */

/* Per-test resources, released by the teardown even when an assertion fails part-way (no leak reports
 * from LeakSanitizer hiding the real failure). A test program runs its tests with
 * cmocka_unit_test_teardown(test, teardown_fx). */
#define FX_SCENES 4
#define FX_MEM 16
struct test_fixture {
    scene scenes[FX_SCENES];
    int live[FX_SCENES];
    void *mem[FX_MEM];
    int nmem;
    char *dir;
};
extern struct test_fixture fx;

void *fx_keep(void *p);
const char *fx_dir(void);
scene *fx_slot(void);
void fx_mark(scene *s, int live);
void fx_drop(scene *s);
int teardown_fx(void **state);
/* Writes data to <fixture dir>/name. */
void write_in_dir(const char *name, const void *data, size_t n);
/* Loads `text` written to dir/name; err.msg is cleared first so that a message is always fresh. */
int load_text(const char *dir, const char *name, const char *text, size_t len, const scene_load_options *opt, scene *s,
              dp_error *err);
/* Loads a scene file into a fixture slot (freed by the teardown); fails the test with the message. */
scene *fx_load(const char *path, const scene_load_options *opt);
/* Writes text to <fixture dir>/name and loads it into a fixture slot; returns the scene, or NULL with err set
 * (a failure without a message fails the test). */
scene *fx_load_text(const char *name, const char *text, const scene_load_options *opt, dp_error *err);

/* The field of view of the paper's Cornell box camera (and of scenes/cbox-fog), in degrees. */
#define CBOX_FOV 39.3077
/* A small valid scene: a quad floor, a point light in fog, a pinhole camera, a gated path tracer.
 * The bad-input tests each change one value in it. */
extern const char BASE_SCENE[];

/* ---- images (the io tests) ---- */

/* 3 × 2 pixels of values a float format must keep bit for bit: tiny, huge, ±0, a denormal, half-float limits. */
extern const float special[18];

void check_close(double got, double want, double tol, int line);
#define assert_close(got, want, tol) check_close(got, want, tol, __LINE__)
void join(char *out, size_t n, const char *dir, const char *name);
/* An image of w × h pixels holding the 3·w·h values v. */
void fill(image_rgb *img, int w, int h, const float *v);
long file_size(const char *path);
/* Up to cap bytes of the file into buf; returns how many. */
size_t read_into(const char *path, unsigned char *buf, size_t cap);
/* A read that must fail: non-zero, the path in the message, and an empty image. */
void expect_read_error(int (*reader)(const char *, image_rgb *, dp_error *), const char *path);
/* Files in dir with ".tmp." in their name (atomic writes in progress or left behind). */
int count_temp_files(const char *dir);
/* A deterministic image with values that do not compress away. */
void noise_image(image_rgb *img, int w, int h);

#endif
