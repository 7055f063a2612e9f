/* tier: quick */
/* The lidar's point cloud and files (include/dartspp/lidar.h, docs/lidar.md §4, §5): points from synthetic
 * waveforms at origin + range·dir with the beam directions computed here from the convention of
 * docs/lidar.md §1 (a beam at azimuth 90° along left, at elevation 90° along up), the threshold as a fraction
 * of the reference peak at max_range, the return numbers in every echo mode, the growth of the cloud; the PLY
 * read back by a small parser written here (header lines, 25-byte little-endian records); the waveforms'
 * sidecar; and `dartspp counts` on a waveforms file: the mean counts over the beams against the Poisson
 * expectation N·(η·scale·value + (η·ambient + dark)·2·range_bin) per bin (z), the Coates estimate back in the
 * waveforms' unit, the counts' sidecar, and the refusals (no sidecar, naming it; a shape that differs; a
 * sidecar without range_bin; --frames and --channel). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <cjson/cJSON.h>

#include "dartspp/io.h"
#include "dartspp/lidar.h"
#include "fixtures.h"
#include "test_util.h"

/* The beam direction by the convention, written out here: elevation el_c = e0 + c·(e1 − e0)/(C − 1) (e0 for
 * one channel), azimuth az_a = a0 + (a + ½)·(a1 − a0)/A, dir = cos el (cos az·F + sin az·L) + sin el·U. */
static vec3 expected_dir(const lidar_params *l, vec3 F, vec3 L, vec3 U, int c, int a)
{
    double el = l->channels > 1 ? l->elevation[0] + c * (l->elevation[1] - l->elevation[0]) / (l->channels - 1)
                                : l->elevation[0];
    double az = l->azimuth[0] + (a + 0.5) * (l->azimuth[1] - l->azimuth[0]) / l->azimuth_steps;
    vec3 d;
    d.x = cos(el) * (cos(az) * F.x + sin(az) * L.x) + sin(el) * U.x;
    d.y = cos(el) * (cos(az) * F.y + sin(az) * L.y) + sin(el) * U.y;
    d.z = cos(el) * (cos(az) * F.z + sin(az) * L.z) + sin(el) * U.z;
    return d;
}

/* A sensor frame turned away from the world axes: forward, left and up orthonormal, right-handed. */
static void tilted_frame(vec3 *F, vec3 *L, vec3 *U)
{
    double a = 0.3, b = -0.7;
    *F = v3(cos(a) * cos(b), sin(a) * cos(b), sin(b));
    *L = v3(-sin(a), cos(a), 0.0);
    *U = v3_cross(*F, *L);
}

static lidar_params base_params(void)
{
    lidar_params l = {0};
    l.channels = 3;
    l.azimuth_steps = 8;
    l.elevation[0] = -0.2, l.elevation[1] = 0.3;
    l.azimuth[0] = -M_PI, l.azimuth[1] = M_PI;
    l.power = 1.0;
    l.pulse.width = 0.0;
    l.max_range = 20.0;
    l.range_bin = 0.25;
    l.bins = 80;
    l.echoes = LIDAR_ECHO_ALL;
    l.echo_threshold = 0.5;
    l.max_echoes = 3;
    return l;
}

/* The scan geometry the points use (lidar_beam_dir) against the convention: every beam of a tilted frame, and
 * the named directions — azimuth 90° is left, −90° right, 0 forward, elevation 90° up. */
static void test_beam_directions(void **state)
{
    (void)state;
    lidar_params l = base_params();
    vec3 F, L, U;
    tilted_frame(&F, &L, &U);
    double worst = 0.0;
    for (int c = 0; c < l.channels; c++)
        for (int a = 0; a < l.azimuth_steps; a++) {
            vec3 d = lidar_beam_dir(&l, F, L, U, c, a), e = expected_dir(&l, F, L, U, c, a);
            worst = fmax(worst, v3_len(v3_sub(d, e)));
        }
    assert_true(worst < 1e-14);
    lidar_params one = base_params();
    one.channels = 1, one.elevation[0] = 0.0, one.elevation[1] = 1.0; /* one channel: elevation[0] */
    one.azimuth_steps = 1, one.azimuth[0] = M_PI / 4, one.azimuth[1] = 3 * M_PI / 4; /* its centre: 90° */
    assert_true(v3_len(v3_sub(lidar_beam_dir(&one, F, L, U, 0, 0), L)) < 1e-15);
    one.azimuth[0] = -3 * M_PI / 4, one.azimuth[1] = -M_PI / 4;
    assert_true(v3_len(v3_add(lidar_beam_dir(&one, F, L, U, 0, 0), L)) < 1e-15);
    one.azimuth[0] = -0.1, one.azimuth[1] = 0.1;
    assert_true(v3_len(v3_sub(lidar_beam_dir(&one, F, L, U, 0, 0), F)) < 1e-15);
    one.elevation[0] = M_PI / 2;
    assert_true(v3_len(v3_sub(lidar_beam_dir(&one, F, L, U, 0, 0), U)) < 1e-15);
    /* two channels: the lowest is elevation[0], the highest elevation[1] (both included) */
    one.channels = 2, one.elevation[0] = -M_PI / 2, one.elevation[1] = M_PI / 2;
    assert_true(v3_len(v3_add(lidar_beam_dir(&one, F, L, U, 0, 0), U)) < 1e-15);
    assert_true(v3_len(v3_sub(lidar_beam_dir(&one, F, L, U, 1, 0), U)) < 1e-15);
}

/* The receiver's cone as the header states it: directions within receiver_fov/2 of the axis, density
 * cosθ/(π sin²θ_r), so the mean of 1/cosθ is the cone's solid angle over the etendue,
 * 2π(1 − cosθ_r)/(π sin²θ_r), and the etendue π sin²θ_r; the mean of cosθ, (2/3)(1 − cos³θ_r)/sin²θ_r. */
static void test_receiver_cone(void **state)
{
    (void)state;
    lidar_params l = base_params();
    l.receiver_fov = 1.2; /* θ_r = 0.6 */
    double cr = cos(0.6), s2 = sin(0.6) * sin(0.6);
    assert_true(fabs(lidar_receiver_etendue(&l) - M_PI * s2) < 1e-15);
    vec3 b = v3_norm(v3(0.3, -0.5, 0.8));
    dp_rng r = rng_stream(11, 3, 4);
    const int n = 200000;
    double s1 = 0, q1 = 0, sc = 0, qc = 0, worst = 1.0;
    for (int i = 0; i < n; i++) {
        double u1 = rng_uniform(&r), u2 = rng_uniform(&r);
        vec3 d = lidar_receiver_dir(&l, b, u1, u2);
        assert_true(fabs(v3_len(d) - 1.0) < 1e-12);
        double c = v3_dot(d, b);
        worst = fmin(worst, c);
        s1 += 1 / c, q1 += 1 / (c * c), sc += c, qc += c * c;
    }
    assert_true(worst >= cr - 1e-12);
    double m1 = s1 / n, e1 = 2 * (1 - cr) / s2, se1 = sqrt((q1 / n - m1 * m1) / n);
    double mc = sc / n, ec = 2.0 / 3.0 * (1 - cr * cr * cr) / s2, sec = sqrt((qc / n - mc * mc) / n);
    print_message("  receiver cone: E[1/cos] %.6f vs %.6f (z %.2f), E[cos] %.6f vs %.6f (z %.2f)\n", m1, e1,
                  (m1 - e1) / se1, mc, ec, (mc - ec) / sec);
    assert_true(fabs(m1 - e1) < 4 * se1 && fabs(mc - ec) < 4 * sec);
}

/* Waveforms of base_params with a box echo of 3 bins in beam (c, a) centred on bin 10 + 8c + a, of height
 * `h` (every 5th beam left empty). */
static float *box_waveforms(const lidar_params *l, float h)
{
    float *w = calloc((size_t)l->channels * l->azimuth_steps * l->bins, sizeof *w);
    assert_non_null(w);
    for (int c = 0; c < l->channels; c++)
        for (int a = 0; a < l->azimuth_steps; a++) {
            if ((c * l->azimuth_steps + a) % 5 == 4) continue;
            float *wave = w + ((size_t)c * l->azimuth_steps + a) * l->bins;
            int b = 10 + 8 * c + a;
            wave[b - 1] = wave[b] = wave[b + 1] = h;
        }
    return w;
}

/* Points at origin + range·dir (dir from the convention, written here), range the box's centre (b + ½)·range_bin,
 * intensity 3h, return 1, channel and azimuth index; the beams without an echo give none. The threshold is
 * echo_threshold·Φ/(π·max_range²) = 0.5/(400π) = 3.979e-4: a box of 4.0e-4 is found, one of 3.95e-4 is not. */
static void test_points_at_range_along_beams(void **state)
{
    (void)state;
    lidar_params l = base_params();
    vec3 F, L, U, o = v3(1.5, -2.0, 0.75);
    tilted_frame(&F, &L, &U);
    double thr = 0.5 / (400.0 * M_PI);
    assert_true(fabs(l.echo_threshold * lidar_peak_reference(&l, l.max_range) - thr) < 1e-15);
    float *w = box_waveforms(&l, 4.0e-4f);
    lidar_points pts;
    dp_error err;
    assert_int_equal(lidar_points_from_waveforms(&l, o, F, L, U, w, &pts, &err), 0);
    size_t i = 0;
    double worst = 0.0;
    for (int c = 0; c < l.channels; c++)
        for (int a = 0; a < l.azimuth_steps; a++) {
            if ((c * l.azimuth_steps + a) % 5 == 4) continue;
            assert_true(i < pts.count);
            const float *r = pts.rows + i++ * LIDAR_POINT_COLUMNS;
            double range = (10 + 8 * c + a + 0.5) * l.range_bin;
            vec3 p = v3_add(o, v3_scale(expected_dir(&l, F, L, U, c, a), range));
            worst = fmax(worst, fabs(r[0] - p.x) + fabs(r[1] - p.y) + fabs(r[2] - p.z));
            assert_true(fabs(r[3] - 3 * 4.0e-4) < 1e-9);
            assert_true(r[4] == 1.0f && r[5] == (float)c && r[6] == (float)a);
            assert_true(fabs(r[7] - range) < 1e-5);
        }
    assert_int_equal(pts.count, i);
    print_message("  %zu points, worst |xyz − (o + range·dir)|₁ %.3g\n", pts.count, worst);
    assert_true(worst < 1e-5);
    lidar_points_free(&pts);
    assert_null(pts.rows);
    free(w);
    w = box_waveforms(&l, 3.95e-4f);
    assert_int_equal(lidar_points_from_waveforms(&l, o, F, L, U, w, &pts, &err), 0);
    assert_int_equal(pts.count, 0);
    lidar_points_free(&pts);
    free(w);
}

/* One beam with three echoes at bins 10..12 (1, 2, 1: 4), 30..31 (5, 5: 10) and 50 (3): the points and their
 * return numbers in each mode (1 the nearest kept), and max_echoes capping "all" at the nearest. */
static void test_points_modes(void **state)
{
    (void)state;
    lidar_params l = base_params();
    l.channels = 1, l.azimuth_steps = 1, l.echo_threshold = 0.0; /* threshold 0: any positive bin */
    float w[80] = {0};
    w[10] = 1, w[11] = 2, w[12] = 1, w[30] = w[31] = 5, w[50] = 3;
    double ranges[3] = {11.5 * 0.25, 31.0 * 0.25, 50.5 * 0.25}, intens[3] = {4, 10, 3};
    vec3 F = v3(0, 0, 1), L = v3(-1, 0, 0), U = v3(0, 1, 0);
    struct {
        lidar_echo_mode mode;
        int max, n, first;
    } cases[] = {{LIDAR_ECHO_ALL, 3, 3, 0}, {LIDAR_ECHO_ALL, 2, 2, 0}, {LIDAR_ECHO_ALL, 1, 1, 0},
                 {LIDAR_ECHO_FIRST, 3, 1, 0}, {LIDAR_ECHO_STRONGEST, 3, 1, 1}, {LIDAR_ECHO_LAST, 3, 1, 2}};
    for (int k = 0; k < 6; k++) {
        l.echoes = cases[k].mode, l.max_echoes = cases[k].max;
        lidar_points pts;
        dp_error err;
        assert_int_equal(lidar_points_from_waveforms(&l, v3s(0), F, L, U, w, &pts, &err), 0);
        assert_int_equal(pts.count, cases[k].n);
        vec3 d = expected_dir(&l, F, L, U, 0, 0);
        for (int i = 0; i < cases[k].n; i++) {
            const float *r = pts.rows + i * LIDAR_POINT_COLUMNS;
            int e = cases[k].first + i;
            assert_true(fabs(r[7] - ranges[e]) < 1e-6 && fabs(r[3] - intens[e]) < 1e-6);
            assert_true(r[4] == (float)(i + 1));
            assert_true(fabs(r[0] - ranges[e] * d.x) + fabs(r[1] - ranges[e] * d.y) + fabs(r[2] - ranges[e] * d.z) < 1e-5);
        }
        lidar_points_free(&pts);
    }
    /* max_echoes 0 with "all" is refused with the reason */
    l.echoes = LIDAR_ECHO_ALL, l.max_echoes = 0;
    lidar_points pts;
    dp_error err;
    assert_int_equal(lidar_points_from_waveforms(&l, v3s(0), F, L, U, w, &pts, &err), -1);
    ASSERT_CONTAINS(err.msg, "max_echoes");
}

/* 16 channels × 128 steps × 3 echoes = 6144 points: more than the first allocation; all there, in order. */
static void test_points_grow(void **state)
{
    (void)state;
    lidar_params l = base_params();
    l.channels = 16, l.azimuth_steps = 128, l.echo_threshold = 0.0;
    size_t beams = (size_t)l.channels * l.azimuth_steps;
    float *w = calloc(beams * l.bins, sizeof *w);
    assert_non_null(w);
    for (size_t p = 0; p < beams; p++) w[p * l.bins + 5] = w[p * l.bins + 40] = w[p * l.bins + 79] = 1.0f;
    lidar_points pts;
    dp_error err;
    assert_int_equal(lidar_points_from_waveforms(&l, v3s(0), v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1), w, &pts, &err), 0);
    assert_int_equal(pts.count, 3 * beams);
    for (size_t i = 0; i < pts.count; i++) {
        const float *r = pts.rows + i * LIDAR_POINT_COLUMNS;
        size_t p = i / 3;
        assert_true(r[4] == (float)(i % 3 + 1) && r[5] == (float)(p / 128) && r[6] == (float)(p % 128));
        assert_true(r[7] == (float)((i % 3 == 0 ? 5.5 : i % 3 == 1 ? 40.5 : 79.5) * 0.25));
    }
    lidar_points_free(&pts);
    free(w);
}

static uint32_t le32(const unsigned char *p) { return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static float lef(const unsigned char *p)
{
    uint32_t u = le32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* A PLY written by lidar_points_write_ply read back: the header's lines one by one, then count records of 25
 * bytes, each decoded little-endian by hand and compared with the rows; the file's size exactly header + 25N;
 * no temporary file left. An empty cloud; a ring beyond ushort refused before anything is written; a folder
 * that does not exist named in the error. */
static void test_ply_read_back(void **state)
{
    char *dir = test_tmpdir(), path[1024];
    assert_non_null(dir);
    *state = dir;
    lidar_params l = base_params();
    vec3 F, L, U;
    tilted_frame(&F, &L, &U);
    float *w = box_waveforms(&l, 1.0f);
    w[(size_t)2 * l.bins + 60] = 7.0f; /* a second echo in beam (0, 2) */
    lidar_points pts;
    dp_error err;
    assert_int_equal(lidar_points_from_waveforms(&l, v3(1, 2, 3), F, L, U, w, &pts, &err), 0);
    assert_true(pts.count > 10);
    snprintf(path, sizeof path, "%s/cloud.ply", dir);
    assert_int_equal(lidar_points_write_ply(path, &pts, &err), 0);
    assert_int_equal(count_temp_files(dir), 0);
    size_t len;
    unsigned char *bytes = (unsigned char *)read_all(path, &len);
    assert_non_null(bytes);
    const char *want[] = {"ply", "format binary_little_endian 1.0", NULL /* element */, "property float x",
                          "property float y", "property float z", "property float intensity",
                          "property uchar return_number", "property ushort ring", "property ushort azimuth_index",
                          "property float range", "end_header"};
    size_t pos = 0;
    int k = 0;
    while (k < 12) {
        char *nl = memchr(bytes + pos, '\n', len - pos);
        assert_non_null(nl);
        char line[256];
        size_t n = (size_t)((unsigned char *)nl - (bytes + pos));
        assert_true(n < sizeof line);
        memcpy(line, bytes + pos, n);
        line[n] = 0;
        pos += n + 1;
        if (!strncmp(line, "comment ", 8)) continue;
        if (k == 2) {
            size_t count;
            char tail;
            assert_int_equal(sscanf(line, "element vertex %zu%c", &count, &tail), 1);
            assert_int_equal(count, pts.count);
        } else if (strcmp(line, want[k])) fail_msg("PLY header line %d: '%s', expected '%s'", k, line, want[k]);
        k++;
    }
    assert_int_equal(len, pos + 25 * pts.count);
    int seen_second = 0;
    for (size_t i = 0; i < pts.count; i++) {
        const unsigned char *r = bytes + pos + 25 * i;
        const float *row = pts.rows + i * LIDAR_POINT_COLUMNS;
        for (int c = 0; c < 4; c++) assert_true(lef(r + 4 * c) == row[c]);
        assert_int_equal(r[16], (int)row[4]);
        assert_int_equal(r[17] | r[18] << 8, (int)row[5]);
        assert_int_equal(r[19] | r[20] << 8, (int)row[6]);
        assert_true(lef(r + 21) == row[7]);
        seen_second |= r[16] == 2 && lef(r + 21) == (float)(60.5 * 0.25) && lef(r + 12) == 7.0f;
    }
    assert_true(seen_second);
    free(bytes);
    lidar_points_free(&pts);
    free(w);
    /* empty */
    lidar_points none = {NULL, 0};
    assert_int_equal(lidar_points_write_ply(path, &none, &err), 0);
    char *text = read_all(path, &len);
    assert_non_null(strstr(text, "element vertex 0\n"));
    assert_true(len == (size_t)(strstr(text, "end_header\n") - text) + 11);
    free(text);
    /* a ring of 70000 does not fit a ushort: refused, the old file left as it was */
    float row[LIDAR_POINT_COLUMNS] = {0, 0, 0, 1, 1, 70000, 0, 1};
    lidar_points big = {row, 1};
    assert_int_equal(lidar_points_write_ply(path, &big, &err), -1);
    ASSERT_CONTAINS(err.msg, "ring 70000");
    text = read_all(path, NULL);
    assert_non_null(strstr(text, "element vertex 0\n"));
    free(text);
    snprintf(path, sizeof path, "%s/no/such/folder/cloud.ply", dir);
    assert_int_equal(lidar_points_write_ply(path, &none, &err), -1);
    ASSERT_CONTAINS(err.msg, path);
}

/* The waveforms' sidecar (docs/lidar.md §5): parsed back, every field counts and a reader need. */
static void test_waveforms_sidecar(void **state)
{
    char *dir = test_tmpdir(), path[1024];
    assert_non_null(dir);
    *state = dir;
    lidar_params l = base_params();
    l.pulse.width = 2.0, l.pulse.shape = PULSE_GAUSSIAN;
    snprintf(path, sizeof path, "%s/s_waveforms.json", dir);
    dp_error err;
    assert_int_equal(lidar_waveforms_sidecar_write(path, &l, &err), 0);
    assert_int_equal(count_temp_files(dir), 0);
    char *text = read_all(path, NULL);
    assert_non_null(text);
    cJSON *root = cJSON_Parse(text);
    assert_non_null(root);
    assert_string_equal(cJSON_GetObjectItem(root, "format")->valuestring, "dartspp lidar waveforms");
    assert_string_equal(cJSON_GetObjectItem(root, "dtype")->valuestring, "float32");
    const cJSON *shape = cJSON_GetObjectItem(root, "shape");
    assert_int_equal(cJSON_GetArraySize(shape), 3);
    assert_true(cJSON_GetArrayItem(shape, 0)->valuedouble == 3 && cJSON_GetArrayItem(shape, 1)->valuedouble == 8 &&
                cJSON_GetArrayItem(shape, 2)->valuedouble == 80);
    assert_true(cJSON_GetObjectItem(root, "channels")->valuedouble == 3);
    assert_true(cJSON_GetObjectItem(root, "azimuth_steps")->valuedouble == 8);
    assert_true(cJSON_GetObjectItem(root, "bins")->valuedouble == 80);
    assert_true(cJSON_GetObjectItem(root, "range_bin")->valuedouble == 0.25);
    assert_true(cJSON_GetObjectItem(root, "max_range")->valuedouble == 20.0);
    assert_true(cJSON_GetObjectItem(root, "bin_time_width")->valuedouble == 0.5);
    assert_true(cJSON_IsString(cJSON_GetObjectItem(root, "unit")));
    assert_string_equal(cJSON_GetObjectItem(root, "pulse_shape")->valuestring, "gaussian");
    assert_string_equal(cJSON_GetObjectItem(root, "echoes")->valuestring, "all");
    assert_true(cJSON_GetObjectItem(root, "elevation")->child->valuedouble == -0.2);
    double ref = 1.0 / (M_PI * 400.0) * (0.25 / 1.0);
    assert_true(fabs(cJSON_GetObjectItem(root, "peak_reference_at_max_range")->valuedouble - ref) < 1e-15);
    cJSON_Delete(root);
    free(text);
}

/* ---- dartspp counts on waveforms ---- */

#define WC 4
#define WA 50
#define WB 8
/* Waveforms (WC, WA, WB): beam p holds WAVE·f_p, f_p = 1 + (p mod 7)/4 (so that beams and bins read or written
 * in another order show), and its sidecar (range_bin 0.75: a bin's time width 1.5, so that a value taken as a
 * rate over the bin, or a bin's time taken as range_bin, shows). */
static const float WAVE[WB] = {0.0f, 0.5f, 2.0f, 8.0f, 3.0f, 0.25f, 0.0f, 1.0f};
static double beam_factor(int p) { return 1.0 + (p % 7) / 4.0; }

static void write_waves(const char *dir, const char *stem, int with_sidecar)
{
    char path[1024];
    size_t shape[3] = {WC, WA, WB};
    float *v = malloc(sizeof(float) * WC * WA * WB);
    assert_non_null(v);
    for (int p = 0; p < WC * WA; p++)
        for (int k = 0; k < WB; k++) v[(size_t)p * WB + k] = (float)(WAVE[k] * beam_factor(p));
    dp_error err;
    snprintf(path, sizeof path, "%s/%s_waveforms.npy", dir, stem);
    assert_int_equal(npy_write_f32(path, shape, 3, v, &err), 0);
    free(v);
    if (!with_sidecar) return;
    lidar_params l = base_params();
    l.channels = WC, l.azimuth_steps = WA, l.bins = WB, l.range_bin = 0.75, l.max_range = 6.0;
    snprintf(path, sizeof path, "%s/%s_waveforms.json", dir, stem);
    assert_int_equal(lidar_waveforms_sidecar_write(path, &l, &err), 0);
}

/* An int32 .npy of shape (WC, WA, WB). */
static void read_counts(const char *path, int32_t *v)
{
    size_t len;
    char *bytes = read_all(path, &len);
    assert_non_null(bytes);
    size_t header = 10 + ((unsigned char)bytes[8] | (size_t)(unsigned char)bytes[9] << 8);
    assert_non_null(memmem(bytes + 10, header - 10, "'descr': '<i4'", 14));
    assert_non_null(memmem(bytes + 10, header - 10, "'shape': (4, 50, 8)", 19));
    assert_int_equal(len, header + 4 * (size_t)WC * WA * WB);
    memcpy(v, bytes + header, 4 * (size_t)WC * WA * WB);
    free(bytes);
}

/* The counts per bin, summed over the 200 beams, against Σ N·μ_k with μ_k = η·scale·v_k + (η·ambient + dark)·Δt,
 * Δt = 2·range_bin = 1.5: z per bin and χ² over the 8 bins × 200 beams (each count against its Poisson mean);
 * then one detection per pulse (dead time ≥ the span 2·bins·range_bin = 12) with --coates back in the waveforms'
 * unit; the counts' sidecar; and the refusals. */
static void test_counts_on_waveforms(void **state)
{
    char *dir = test_tmpdir(), cmd[2048], out[8192], path[1024];
    assert_non_null(dir);
    *state = dir;
    write_waves(dir, "w", 1);
    const double N = 3000, scale = 0.02, eta = 0.4, dark = 0.003, amb = 0.01, dt = 1.5;
    snprintf(cmd, sizeof cmd, "%s counts %s/w_waveforms.npy --output %s/c.npy --pulses 3000 --scale 0.02 "
             "--efficiency 0.4 --dark-rate 0.003 --ambient-rate 0.01 --seed 5", DARTSPP_BIN, dir, dir);
    if (test_run(cmd, out, sizeof out)) fail_msg("%s\n%s", cmd, out);
    ASSERT_CONTAINS(out, "waveforms of 4 channels x 50 azimuth steps, 8 bins of 0.75");
    int32_t *h = malloc(4 * (size_t)WC * WA * WB);
    assert_non_null(h);
    snprintf(path, sizeof path, "%s/c.npy", dir);
    read_counts(path, h);
    double worst = 0.0, chi2 = 0.0;
    for (int k = 0; k < WB; k++) {
        double s = 0.0, m = 0.0;
        for (int p = 0; p < WC * WA; p++) {
            double x = h[(size_t)p * WB + k];
            double mu = N * (eta * scale * (double)(float)(WAVE[k] * beam_factor(p)) + (eta * amb + dark) * dt);
            s += x, m += mu;
            chi2 += (x - mu) * (x - mu) / mu;
        }
        double z = (s - m) / sqrt(m); /* the sum of independent Poisson counts is Poisson */
        print_message("  bin %d: mean %.3f, expected %.3f, z %+.2f\n", k, s / (WC * WA), m / (WC * WA), z);
        worst = fmax(worst, fabs(z));
    }
    /* χ² of 1600 cells with 1600 degrees of freedom: mean 1600, sd 56.6; 4 sd */
    print_message("  worst |z| %.2f; chi2 %.1f over %d cells\n", worst, chi2, WC * WA * WB);
    assert_true(worst < 4.0);
    assert_true(fabs(chi2 - WC * WA * WB) < 4.0 * sqrt(2.0 * WC * WA * WB));
    free(h);
    snprintf(path, sizeof path, "%s/c.json", dir);
    char *json = read_all(path, NULL);
    assert_non_null(json);
    cJSON *root = cJSON_Parse(json);
    assert_non_null(root);
    assert_true(strstr(cJSON_GetObjectItem(root, "waveforms")->valuestring, "w_waveforms.npy") != NULL);
    assert_true(strstr(cJSON_GetObjectItem(root, "waveforms_sidecar")->valuestring, "w_waveforms.json") != NULL);
    assert_true(cJSON_GetObjectItem(root, "range_bin")->valuedouble == 0.75);
    assert_true(cJSON_GetObjectItem(root, "bin_time_width")->valuedouble == 1.5);
    assert_string_equal(cJSON_GetObjectItem(root, "dtype")->valuestring, "int32");
    assert_null(cJSON_GetObjectItem(root, "channel"));
    cJSON_Delete(root);
    free(json);
    /* one detection per pulse; Coates back to the waveform's value: bin 4 (3.0) after the piled-up bins 1..3 */
    snprintf(cmd, sizeof cmd, "%s counts %s/w_waveforms.npy --output %s/d.npy --pulses 100000 --scale 0.05 "
             "--dead-time 12 --coates", DARTSPP_BIN, dir, dir);
    if (test_run(cmd, out, sizeof out)) fail_msg("%s\n%s", cmd, out);
    snprintf(path, sizeof path, "%s/d_coates.npy", dir);
    size_t shape[NPY_MAX_DIMS];
    int ndim;
    float *c;
    dp_error err;
    assert_int_equal(npy_read_f32(path, shape, &ndim, &c, &err), 0);
    assert_true(ndim == 3 && shape[0] == WC && shape[1] == WA && shape[2] == WB);
    for (int k = 1; k <= 4; k++) {
        double s = 0.0;
        for (int p = 0; p < WC * WA; p++) s += c[(size_t)p * WB + k] / beam_factor(p);
        /* per beam: μ_k = 0.05·v_k, 1e5 pulses: a relative se of about 1/sqrt(1e5·μ_k·e^{−Σμ}) per beam, /sqrt(200) */
        double mu = 0.05 * WAVE[k], se = WAVE[k] / sqrt(1e5 * mu * exp(-0.05 * 10.5 * 2.5) * WC * WA);
        print_message("  Coates, bin %d: mean %.4f (waveform %.4g, se %.2g)\n", k, s / (WC * WA), WAVE[k], se);
        assert_true(fabs(s / (WC * WA) - WAVE[k]) < 4.0 * se);
    }
    free(c);
    /* refusals, exit 2, no output */
    write_waves(dir, "nosidecar", 0);
    snprintf(cmd, sizeof cmd, "%s counts %s/nosidecar_waveforms.npy --output %s/bad.npy --pulses 10 --scale 1",
             DARTSPP_BIN, dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    snprintf(path, sizeof path, "%s/nosidecar_waveforms.json", dir);
    ASSERT_CONTAINS(out, path);
    ASSERT_CONTAINS(out, "sidecar");
    write_waves(dir, "other", 1); /* a sidecar of other lengths */
    snprintf(path, sizeof path, "%s/other_waveforms.json", dir);
    json = read_all(path, NULL);
    char *changed = replace1(json, "\"bins\":\t8", "\"bins\":\t9");
    test_write_file(path, changed);
    free(changed);
    snprintf(cmd, sizeof cmd, "%s counts %s/other_waveforms.npy --output %s/bad.npy --pulses 10 --scale 1",
             DARTSPP_BIN, dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, "(4, 50, 9)");
    changed = replace1(json, "\"range_bin\":", "\"range_bins\":");
    test_write_file(path, changed);
    free(changed);
    free(json);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, "\"range_bin\"");
    ASSERT_CONTAINS(out, path);
    const char *opts[][2] = {{"--frames x.csv", "--frames"}, {"--channel g", "--channel"},
                             {"--coates", "--coates"}};
    for (int i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, "%s counts %s/w_waveforms.npy --output %s/bad.npy --pulses 10 --scale 1 %s",
                 DARTSPP_BIN, dir, dir, opts[i][0]);
        assert_int_equal(test_run(cmd, out, sizeof out), 2);
        ASSERT_CONTAINS(out, opts[i][1]);
    }
    snprintf(path, sizeof path, "%s/bad.npy", dir);
    assert_int_not_equal(access(path, F_OK), 0);
    /* a negative value named by channel, azimuth step and bin */
    size_t wshape[3] = {WC, WA, WB};
    float *v = calloc((size_t)WC * WA * WB, sizeof *v);
    assert_non_null(v);
    v[((size_t)2 * WA + 7) * WB + 3] = -1.0f;
    snprintf(path, sizeof path, "%s/w_waveforms.npy", dir);
    assert_int_equal(npy_write_f32(path, wshape, 3, v, &err), 0);
    free(v);
    snprintf(cmd, sizeof cmd, "%s counts %s/w_waveforms.npy --output %s/bad.npy --pulses 10 --scale 1", DARTSPP_BIN,
             dir, dir);
    assert_int_equal(test_run(cmd, out, sizeof out), 2);
    ASSERT_CONTAINS(out, "channel 2, azimuth step 7, bin 3");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_beam_directions),
        cmocka_unit_test(test_receiver_cone),
        cmocka_unit_test(test_points_at_range_along_beams),
        cmocka_unit_test(test_points_modes),
        cmocka_unit_test(test_points_grow),
        cmocka_unit_test_teardown(test_ply_read_back, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_waveforms_sidecar, test_teardown_tmpdir),
        cmocka_unit_test_teardown(test_counts_on_waveforms, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
