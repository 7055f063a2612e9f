/* The fixtures shared by the test programs (declared in fixtures.h), linked into every test program. */
#include "fixtures.h"

#include <dirent.h>

/* ---- files and folders ---- */

void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f) fail_msg("cannot write %s", path);
    if (n) assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = n >= 0 ? malloc((size_t)n + 1) : NULL;
    size_t got = buf ? fread(buf, 1, (size_t)n, f) : 0;
    fclose(f);
    if (!buf || got != (size_t)n) {
        free(buf);
        fail_msg("cannot read %s", path);
    }
    buf[n] = 0;
    if (len) *len = (size_t)n;
    return buf;
}

/* Copy of s with the first occurrence of `from` replaced by `to`; the test fails if `from` is absent. */
char *replace1(const char *s, const char *from, const char *to)
{
    const char *at = strstr(s, from);
    if (!at) fail_msg("test bug: \"%s\" not found in the base scene", from);
    size_t a = (size_t)(at - s), nf = strlen(from), nt = strlen(to), ns = strlen(s);
    char *r = malloc(ns - nf + nt + 1);
    assert_non_null(r);
    memcpy(r, s, a);
    memcpy(r + a, to, nt);
    memcpy(r + a + nt, at + nf, ns - a - nf + 1);
    return r;
}

void rm_rf(const char *dir)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) print_message("warning: could not remove %s\n", dir);
}

char *tmpdir_or_fail(void)
{
    char *d = test_tmpdir();
    if (!d) fail_msg("cannot create a temp folder");
    return d;
}

/* ---- the per-test fixture: scenes, buffers and one temp folder ---- */

struct test_fixture fx;

void *fx_keep(void *p)
{
    assert_non_null(p);
    if (fx.nmem >= FX_MEM) fail_msg("test bug: too many fixture buffers");
    fx.mem[fx.nmem++] = p;
    return p;
}

const char *fx_dir(void)
{
    if (!fx.dir) fx.dir = tmpdir_or_fail();
    return fx.dir;
}

scene *fx_slot(void)
{
    for (int i = 0; i < FX_SCENES; i++)
        if (!fx.live[i]) return &fx.scenes[i];
    fail_msg("test bug: too many live scenes");
    return NULL;
}

void fx_mark(scene *s, int live)
{
    fx.live[s - fx.scenes] = live;
}

void fx_drop(scene *s)
{
    if (fx.live[s - fx.scenes]) scene_free(s);
    fx_mark(s, 0);
}

int teardown_fx(void **state)
{
    (void)state;
    for (int i = 0; i < FX_SCENES; i++)
        if (fx.live[i]) scene_free(&fx.scenes[i]);
    for (int i = 0; i < fx.nmem; i++) free(fx.mem[i]);
    if (fx.dir) rm_rf(fx.dir);
    free(fx.dir);
    memset(&fx, 0, sizeof fx);
    return 0;
}

/* Loads `text` written to dir/name; err.msg is cleared first so that a message is always fresh. */
int load_text(const char *dir, const char *name, const char *text, size_t len,
              const scene_load_options *opt, scene *s, dp_error *err)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    write_bytes(path, text, len);
    memset(err, 0, sizeof *err);
    return scene_load(path, opt, s, err);
}

/* Loads a scene file into a fixture slot (freed by the teardown); fails the test with the message. */
scene *fx_load(const char *path, const scene_load_options *opt)
{
    scene *s = fx_slot();
    dp_error err;
    memset(&err, 0, sizeof err);
    if (scene_load(path, opt, s, &err)) fail_msg("scene_load(%s) failed: %s", path, err.msg);
    fx_mark(s, 1);
    return s;
}

/* Writes text to <fixture dir>/name and loads it into a fixture slot; returns the scene or NULL (err set). */
scene *fx_load_text(const char *name, const char *text, const scene_load_options *opt, dp_error *err)
{
    scene *s = fx_slot();
    if (load_text(fx_dir(), name, text, strlen(text), opt, s, err)) {
        if (!err->msg[0]) fail_msg("scene_load failed without a message");
        return NULL;
    }
    fx_mark(s, 1);
    return s;
}

/* Writes data to <fixture dir>/name. */
void write_in_dir(const char *name, const void *data, size_t n)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", fx_dir(), name);
    FILE *f = fopen(path, "wb");
    if (!f) fail_msg("cannot write %s", path);
    if (n) assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

/* A small valid scene: a quad floor, a point light in fog, a pinhole camera, a gated path tracer.
 * The bad-input tests each change one value in it. */
const char BASE_SCENE[] =
    "{\n"
    "  \"media\": [\n"
    "    {\"name\": \"fog\", \"type\": \"homogeneous\", \"sigma_s\": 0.1, \"sigma_a\": 0.01,\n"
    "     \"phase_function\": {\"type\": \"isotropic\"}}\n"
    "  ],\n"
    "  \"bsdfs\": [\n"
    "    {\"name\": \"white\", \"type\": \"lambert\", \"albedo\": 0.5}\n"
    "  ],\n"
    "  \"primitives\": [\n"
    "    {\"name\": \"floor\", \"type\": \"quad\", \"transform\": {\"scale\": [4, 1, 4]}, \"bsdf\": \"white\"},\n"
    "    {\"name\": \"light\", \"type\": \"point\", \"transform\": {\"position\": [0, 2, 0]}, \"power\": 100,\n"
    "     \"ext_medium\": \"fog\"}\n"
    "  ],\n"
    "  \"camera\": {\"type\": \"pinhole\", \"resolution\": [8, 8], \"fov\": 45, \"medium\": \"fog\",\n"
    "    \"transform\": {\"position\": [0, 1, -4], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}},\n"
    "  \"integrator\": {\"type\": \"path_tracer\", \"max_bounces\": 4, \"transient_time_center\": 6,\n"
    "    \"transient_time_width\": 0.5},\n"
    "  \"renderer\": {\"spp\": 1, \"timeout\": \"0\"}\n"
    "}\n";

/* ---- images (the io tests) ---- */

const float special[18] = {1e-30f, 3e38f, -3e38f, 0.0f,   -0.0f, 1e-40f /* denormal */,
                           1.0f,   0.5f,  -2.25f, 1.0e7f, 3.14159265f, 123456.789f,
                           -1e-30f, 65504.0f, 65505.0f, 1e-8f, 7.0f, 0.1f};

void check_close(double got, double want, double tol, int line)
{
    if (!(fabs(got - want) <= tol)) fail_msg("line %d: got %.17g, want %.17g", line, got, want);
}

void join(char *out, size_t n, const char *dir, const char *name)
{
    snprintf(out, n, "%s/%s", dir, name);
}

void fill(image_rgb *img, int w, int h, const float *v)
{
    dp_error err;
    assert_int_equal(image_alloc(img, w, h, &err), 0);
    memcpy(img->rgb, v, sizeof(float) * 3 * (size_t)w * (size_t)h);
}

long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

size_t read_into(const char *path, unsigned char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    size_t n = fread(buf, 1, cap, f);
    fclose(f);
    return n;
}

/* A read that must fail: non-zero, the path in the message, and an empty image. */
void expect_read_error(int (*reader)(const char *, image_rgb *, dp_error *), const char *path)
{
    image_rgb img = {7, 7, NULL};
    dp_error err = {0};
    assert_int_not_equal(reader(path, &img, &err), 0);
    assert_non_null(strstr(err.msg, path));
    assert_null(img.rgb);
}

int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

/* A deterministic image with values that do not compress away. */
void noise_image(image_rgb *img, int w, int h)
{
    dp_error err;
    assert_int_equal(image_alloc(img, w, h, &err), 0);
    uint32_t s = 12345;
    for (size_t i = 0; i < (size_t)w * h * 3; ++i) {
        s = s * 1664525u + 1013904223u;
        img->rgb[i] = (float)(s >> 8) / 16777216.0f;
    }
}

long exr_passes(const char *path)
{
    int v = -1;
    dp_error err;
    if (exr_read_int_attribute(path, "dartspp.passes", &v, &err)) fail_msg("%s", err.msg);
    return v;
}

long state_passes(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    char line[256];
    long passes = -1;
    while (fgets(line, sizeof line, f) && passes < 0)
        if (sscanf(line, "passes %ld", &passes) != 1) passes = -1;
    fclose(f);
    return passes;
}

void write_cbox_fog(const char *path, int res)
{
    char *text = read_all(CBOX_FOG "/transient.json", NULL), size[64];
    snprintf(size, sizeof size, "[%d, %d]", res, res);
    char *resized = replace1(text, "[512, 512]", size);
    write_bytes(path, resized, strlen(resized));
    free(text);
    free(resized);
}

static int cmp_cell_exp(const void *a, const void *b)
{
    double x = ((const chi_cell *)a)->exp, y = ((const chi_cell *)b)->exp;
    return (x > y) - (x < y);
}

double chi2_pooled(chi_cell *cells, int n, double *chi2_out, int *dof_out, long *impossible)
{
    qsort(cells, (size_t)n, sizeof cells[0], cmp_cell_exp);
    double chi2 = 0.0, po = 0.0, pe = 0.0;
    int dof = 0;
    if (impossible) *impossible = 0;
    for (int c = 0; c < n; c++) {
        if (impossible && cells[c].exp == 0.0) {
            *impossible += (long)cells[c].obs;
            continue;
        }
        if (cells[c].exp < 5.0 || (pe > 0.0 && pe < 5.0)) {
            po += cells[c].obs, pe += cells[c].exp;
            continue;
        }
        chi2 += (cells[c].obs - cells[c].exp) * (cells[c].obs - cells[c].exp) / cells[c].exp;
        dof++;
    }
    if (pe > 0.0) chi2 += (po - pe) * (po - pe) / pe, dof++;
    dof -= 1;
    *chi2_out = chi2;
    *dof_out = dof;
    return dof > 0 ? test_gamma_q(0.5 * dof, 0.5 * chi2) : 0.0;
}

char *tmpdir_with_cbox_fog(int res)
{
    char *dir = test_tmpdir(), path[1024];
    if (!dir) return NULL;
    snprintf(path, sizeof path, "%s/box.json", dir);
    write_cbox_fog(path, res);
    return dir;
}

int stress_full(void)
{
    const char *v = getenv("DARTSPP_STRESS");
    return v && !strcmp(v, "full");
}

char *cbox_dir;

int setup_cbox_fog40(void **state)
{
    (void)state;
    cbox_dir = tmpdir_with_cbox_fog(40); /* our fog Cornell box at 40×40 pixels */
    return cbox_dir ? 0 : -1;
}

int teardown_cbox_fog(void **state)
{
    (void)state;
    test_rmtree(cbox_dir);
    cbox_dir = NULL;
    return 0;
}

/* Largest |a − b| / (|b| + tiny) over two image files of the same size (the MPI tests). */
double image_max_rel_diff(const char *a_path, const char *b_path)
{
    image_rgb a = {0}, b = {0};
    dp_error err;
    if (image_read(a_path, &a, &err) || image_read(b_path, &b, &err)) fail_msg("%s", err.msg);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    double m = 0.0, total = 0.0;
    for (size_t i = 0; i < (size_t)a.width * a.height * 3; i++) {
        assert_true(isfinite(a.rgb[i]) && isfinite(b.rgb[i]));
        m = fmax(m, fabs((double)a.rgb[i] - b.rgb[i]) / (fabs((double)b.rgb[i]) + 1e-30));
        total += b.rgb[i];
    }
    assert_true(total > 0.0); /* the comparison saw light */
    image_free(&a);
    image_free(&b);
    return m;
}
