/* The frames viewer `<stem>_viewer.html`: how much it embeds (downscale factor and frame stride under the
 * cap, worked out by hand), the box means and the histogram quantile on hand-made data, and the page itself
 * in a real browser: Debian's chromium, headless, drives a frame-mode render's page (slider to a frame,
 * clicks on the image, a selection from the URL hash) through a test page that holds it in an iframe, and
 * the values the page shows are checked against the frame files. Nothing may reach the browser's console. */
#include "test_util.h"

#include "dartspp/io.h"

#include <cjson/cJSON.h>
#include <stdint.h>

static char *tmp; /* the test's folder, also in *state: test_teardown_tmpdir removes it */


/* ---- layout and data, by hand ---- */

static void expect_layout(int w, int h, int frames, int f, int s, int dw, int dh, int embedded)
{
    viewer_layout l;
    viewer_layout_of(w, h, frames, &l);
    if (l.factor != f || l.stride != s || l.dw != dw || l.dh != dh || l.embedded != embedded)
        fail_msg("%dx%d, %d frames: factor %d stride %d %dx%d %d embedded; expected %d %d %dx%d %d", w, h, frames,
                 l.factor, l.stride, l.dw, l.dh, l.embedded, f, s, dw, dh, embedded);
    assert_true((size_t)l.embedded * l.dw * l.dh * 12 <= VIEWER_PAYLOAD_MAX);
}

/* The cap is 8 MiB = 2097152 floats. */
static void test_layout(void **state)
{
    (void)state;
    expect_layout(16, 12, 4, 1, 1, 16, 12, 4);            /* small: everything */
    expect_layout(301, 201, 16, 2, 1, 151, 101, 16);      /* 16·181503 floats > cap; 16·45753 fit */
    /* f = 3 would leave 101 < 128 pixels on the longer side: f stays 2, 2097152 / 45753 = 45 frames fit, so
     * every 2nd of 50 frames */
    expect_layout(301, 201, 50, 2, 2, 151, 101, 25);
    /* 256² × 1000 frames: f = 2 (128 px), 2097152 / 49152 = 42 fit, stride ceil(1000/42) = 24 → 42 frames */
    expect_layout(256, 256, 1000, 2, 24, 128, 128, 42);
    /* one 4096² frame: 3·ceil(4096/f)² <= 2097152 needs ceil(4096/f) <= 836: f = 5 (820) */
    expect_layout(4096, 4096, 1, 5, 1, 820, 820, 1);
}

/* A 3000×1000 frame (9 M floats): factor 3 (334×1000/3: the last block row holds 1 pixel row); each block
 * is the mean of its pixels. Values x + 1000·c + 0.25·y make every block mean distinct. */
static void test_box_means_and_quantile(void **state)
{
    (void)state;
    viewer_cube v;
    dp_error err;
    assert_int_equal(viewer_cube_init(&v, 3000, 1000, 1, &err), 0);
    assert_int_equal(v.l.factor, 3);
    assert_int_equal(v.l.dw, 1000);
    assert_int_equal(v.l.dh, 334);
    image_rgb img;
    assert_int_equal(image_alloc(&img, 3000, 1000, &err), 0);
    for (int y = 0; y < 1000; y++)
        for (int x = 0; x < 3000; x++)
            for (int c = 0; c < 3; c++) img.rgb[3 * ((size_t)y * 3000 + x) + c] = (float)(x + 1000 * c + 0.25 * y);
    viewer_cube_add(&v, 0, &img);
    /* block (bx, by) covers x 3bx..3bx+2: mean x 3bx+1; rows 3by..3by+2 (mean 3by+1), the last only row 999 */
    int bys[] = {0, 5, 332, 333};
    for (int i = 0; i < 4; i++) {
        int by = bys[i];
        double my = by == 333 ? 999 : 3 * by + 1;
        for (int bx = 0; bx < 1000; bx += 111)
            for (int c = 0; c < 3; c++)
                assert_int_equal(v.data[3 * ((size_t)by * 1000 + bx) + c] == (float)(3 * bx + 1 + 1000 * c + 0.25 * my), 1);
    }
    viewer_cube_free(&v);
    image_free(&img);

    /* quantile: the values 1..100 and zeros (left out): the 0.99 quantile is 99 within 1/128 of an octave */
    assert_int_equal(viewer_cube_init(&v, 50, 3, 1, &err), 0);
    assert_int_equal(image_alloc(&img, 50, 3, &err), 0);
    for (int i = 0; i < 100; i++) img.rgb[i] = (float)(i + 1);
    viewer_cube_add(&v, 0, &img);
    assert_true(fabs(log2(viewer_cube_quantile(&v, 0.99) / 99.0)) < 1.0 / 128);
    assert_true(fabs(log2(viewer_cube_quantile(&v, 0.5) / 50.0)) < 1.0 / 128);
    viewer_cube_free(&v);
    image_free(&img);
}

/* ---- the page in chromium ---- */

/* 50 frames of 301×201: the page embeds every 2nd frame downscaled by 2, with partial blocks at the right
 * and bottom edges (test_layout), so the browser sees both the stride and the box means. */
#define W 301
#define H 201
#define FRAMES 50
#define FACTOR 2
#define STRIDE 2
#define DW 151
#define DH 101
#define START 5.0
#define WIDTH 0.05
#define TIME_UNIT_TEXT "optical path length in scene units (c = 1)"

typedef struct {
    image_rgb frame[FRAMES];
} frames;

/* The mean over the FACTOR×FACTOR block (bx, by) of frame k (fewer pixels at the edges), in double. */
static double block(const frames *fr, int k, int bx, int by, int c)
{
    double sum = 0;
    int n = 0;
    for (int y = by * FACTOR; y < (by + 1) * FACTOR && y < H; y++)
        for (int x = bx * FACTOR; x < (bx + 1) * FACTOR && x < W; x++, n++) sum += fr->frame[k].rgb[3 * (y * W + x) + c];
    return sum / n;
}

/* The page's float32 block mean against ours: the base64 float32 is lossless, so they differ only by the
 * rounding of the mean to float32 (half an ulp, 2^-24 relative); 2^-22 leaves room. */
static void expect_page_value(double got, double want, const char *what, int k, int bx, int by)
{
    if (!(fabs(got - want) <= fabs(want) * 0x1p-22))
        fail_msg("%s of block (%d, %d), frame %d: the page shows %.9g, the frame files give %.9g", what, bx, by, k,
                 got, want);
}

static double num(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (cJSON_IsNumber(v)) return v->valuedouble;
    if (cJSON_IsString(v)) return strtod(v->valuestring, NULL); /* dataset values are strings */
    fail_msg("no %s in the page's result", key);
    return 0;
}

/* The readout (data-* of #pixel-readout) shows block (bx, by) of frame k. */
static void check_readout(const frames *fr, const cJSON *ds, int k, int bx, int by)
{
    assert_int_equal((int)num(ds, "x"), bx);
    assert_int_equal((int)num(ds, "y"), by);
    assert_int_equal((int)num(ds, "frame"), k);
    ASSERT_NEAR(num(ds, "t0"), START + k * WIDTH, 1e-12);
    ASSERT_NEAR(num(ds, "t1"), START + (k + 1) * WIDTH, 1e-12);
    const char *ch[] = {"r", "g", "b"};
    for (int c = 0; c < 3; c++) expect_page_value(num(ds, ch[c]), block(fr, k, bx, by, c), ch[c], k, bx, by);
}

/* The plotted curve (data-curve of #curve): every embedded frame's value of block (bx, by). */
static void check_curve(const frames *fr, const cJSON *curve, int bx, int by)
{
    assert_int_equal((int)num(curve, "x"), bx);
    assert_int_equal((int)num(curve, "y"), by);
    const char *ch[] = {"r", "g", "b"};
    const cJSON *ks = cJSON_GetObjectItemCaseSensitive(curve, "frames"), *ts = cJSON_GetObjectItemCaseSensitive(curve, "t");
    assert_int_equal(cJSON_GetArraySize(ks), FRAMES / STRIDE);
    for (int j = 0; j < FRAMES / STRIDE; j++) {
        int k = j * STRIDE;
        assert_int_equal(cJSON_GetArrayItem(ks, j)->valueint, k);
        ASSERT_NEAR(cJSON_GetArrayItem(ts, j)->valuedouble, START + (k + 0.5) * WIDTH, 1e-12);
        for (int c = 0; c < 3; c++)
            expect_page_value(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(curve, ch[c]), j)->valuedouble,
                         block(fr, k, bx, by, c), ch[c], k, bx, by);
    }
}

/* The brightest block (red) of embedded frame j. */
static void brightest(const frames *fr, int j, int *bx, int *by)
{
    double best = -1;
    for (int y = 0; y < DH; y++)
        for (int x = 0; x < DW; x++) {
            double v = block(fr, j * STRIDE, x, y, 0);
            if (v > best) best = v, *bx = x, *by = y;
        }
    assert_true(best > 0);
}

/* The 0.99 quantile (nearest rank) of the positive values of all frames, by selection. */
static double cube_q99(const frames *fr)
{
    size_t n = 0, cap = (size_t)FRAMES * W * H * 3;
    float *v = malloc(cap * sizeof(float));
    assert_non_null(v);
    for (int k = 0; k < FRAMES; k++)
        for (size_t i = 0; i < (size_t)W * H * 3; i++)
            if (fr->frame[k].rgb[i] > 0) v[n++] = fr->frame[k].rgb[i];
    assert_true(n > 0);
    size_t want = (size_t)ceil(0.99 * n) - 1, lo = 0, hi = n - 1;
    while (lo < hi) { /* quickselect */
        float pivot = v[lo + (hi - lo) / 2];
        size_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pivot) i++;
            while (v[j] > pivot) j--;
            if (i <= j) {
                float t = v[i];
                v[i++] = v[j];
                v[j] = t;
                if (j == 0) break;
                j--;
            }
        }
        if (want <= j) hi = j;
        else if (want >= i) lo = i;
        else break;
    }
    double q = v[want];
    free(v);
    return q;
}

/* The test page: the viewer in two iframes, one driven (slider to embedded frame J, a click on block
 * (BX, BY), then one on the bottom-right corner block), one opened with a URL hash. Console messages and
 * errors inside the frames are collected; everything goes into <pre id="result"> as JSON. */
static const char HARNESS[] =
    "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>viewer test</title></head><body>\n"
    "<pre id=\"result\">pending</pre>\n"
    "<iframe id=\"a\" src=\"fb_viewer.html\" width=\"1000\" height=\"700\"></iframe>\n"
    "<iframe id=\"b\" src=\"fb_viewer.html#x=%d&amp;y=%d&amp;frame=%d\" width=\"1000\" height=\"700\"></iframe>\n"
    "<script>\n"
    "var J = %d, BX = %d, BY = %d, res = { console: [], clicks: [] }, loaded = 0;\n"
    "function watch(w) {\n"
    "  ['error', 'warn'].forEach(function (m) {\n"
    "    var orig = w.console[m];\n"
    "    w.console[m] = function () { res.console.push(m + ': ' + Array.prototype.join.call(arguments, ' ')); orig.apply(w.console, arguments); };\n"
    "  });\n"
    "  w.addEventListener('error', function (e) { res.console.push('error event: ' + e.message); });\n"
    "}\n"
    "function click(w, d, bx, by) {\n"
    "  var c = d.getElementById('image'), r = c.getBoundingClientRect();\n"
    "  c.dispatchEvent(new w.MouseEvent('click', { bubbles: true, clientX: r.left + (bx + 0.5) * r.width / c.width,\n"
    "    clientY: r.top + (by + 0.5) * r.height / c.height }));\n"
    "  res.clicks.push({ ds: Object.assign({}, d.getElementById('pixel-readout').dataset),\n"
    "    text: d.getElementById('pixel-readout').textContent,\n"
    "    curve: JSON.parse(d.getElementById('curve').getAttribute('data-curve')) });\n"
    "}\n"
    "function run() {\n"
    "  try {\n"
    "    var a = document.getElementById('a'), w = a.contentWindow, d = a.contentDocument;\n"
    "    var b = document.getElementById('b').contentDocument;\n"
    "    watch(w); watch(document.getElementById('b').contentWindow);\n"
    "    res.initial = { frameInfo: d.getElementById('frame-info').textContent, exposure: Number(d.getElementById('exposure').value),\n"
    "      warp: d.getElementById('warp-info').textContent, unit: d.getElementById('time-unit').textContent,\n"
    "      scale: d.getElementById('scale-info').textContent };\n"
    "    var s = d.getElementById('time-slider');\n"
    "    s.value = J; s.dispatchEvent(new w.Event('input', { bubbles: true }));\n"
    "    res.frameInfo = d.getElementById('frame-info').textContent;\n"
    "    click(w, d, BX, BY);\n"
    "    click(w, d, %d, %d);\n"
    "    res.hash = Object.assign({}, b.getElementById('pixel-readout').dataset);\n"
    "    res.hashSlider = Number(b.getElementById('time-slider').value);\n"
    "    res.done = true;\n"
    "  } catch (e) { res.harness = String(e); }\n"
    "  document.getElementById('result').textContent = JSON.stringify(res);\n"
    "}\n"
    "['a', 'b'].forEach(function (id) { document.getElementById(id).addEventListener('load', function () { if (++loaded === 2) run(); }); });\n"
    "</script></body></html>\n";

/* &amp; &lt; &gt; &quot; back to characters, in place. */
static void unescape_html(char *s)
{
    static const char *ent[][2] = {{"&amp;", "&"}, {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}};
    char *o = s;
    for (char *p = s; *p;) {
        int done = 0;
        for (int i = 0; i < 4 && !done; i++)
            if (!strncmp(p, ent[i][0], strlen(ent[i][0]))) {
                *o++ = ent[i][1][0];
                p += strlen(ent[i][0]);
                done = 1;
            }
        if (!done) *o++ = *p++;
    }
    *o = 0;
}

/* Runs chromium headless on the test page; returns the parsed result. The browser's own stderr goes to
 * err_path (console messages appear there as "CONSOLE" lines). */
static cJSON *run_browser(const char *page, const char *err_path)
{
    char cmd[2048];
    if (test_run("command -v chromium", NULL, 0) != 0)
        fail_msg("chromium not found: it is a declared dependency of the tests, run `make deps`");
    char *dom = malloc(1 << 20);
    assert_non_null(dom);
    snprintf(cmd, sizeof cmd,
             "timeout 60 chromium --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir=%s/chromium "
             "--allow-file-access-from-files --enable-logging=stderr --v=0 --virtual-time-budget=20000 "
             "--dump-dom file://%s 2>%s",
             tmp, page, err_path);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t n = fread(dom, 1, (1 << 20) - 1, p);
    dom[n] = 0;
    int st = pclose(p);
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) fail_msg("chromium failed (status %d): see %s", st, err_path);
    char *a = strstr(dom, "<pre id=\"result\">"), *b = a ? strstr(a, "</pre>") : NULL;
    if (!a || !b) fail_msg("no result in the page chromium dumped: %.300s", dom);
    a += strlen("<pre id=\"result\">");
    *b = 0;
    unescape_html(a);
    cJSON *res = cJSON_Parse(a);
    if (!res) fail_msg("the page's result is not JSON: %.300s", a);
    free(dom);
    return res;
}

/* Lines of chromium's stderr that carry a console message ("...:CONSOLE(...)]" or ":CONSOLE:"). */
static void expect_quiet_console(const char *err_path)
{
    FILE *f = fopen(err_path, "r");
    assert_non_null(f);
    char line[4096];
    while (fgets(line, sizeof line, f))
        if (strstr(line, "CONSOLE")) fail_msg("the browser's console got: %s", line);
    fclose(f);
}

static void test_page_in_chromium(void **state)
{
    *state = tmp = test_tmpdir();
    char cmd[1024], out[16384], path[600], page[600], errp[600];
    snprintf(cmd, sizeof cmd,
             DARTSPP_BIN " render scenes/fogbox/fogbox.json --spp 1 --quiet --seed 3 --set resolution=%dx%d "
                         "--set frame_num=%d --set start_time=%g --set transient_time_width=%g --output %s/fb.exr",
             W, H, FRAMES, START, WIDTH, tmp);
    assert_int_equal(test_run(cmd, out, sizeof out), 0);
    snprintf(path, sizeof path, "wrote %s/fb_viewer.html\n", tmp);
    assert_non_null(strstr(out, path));
    static frames fr;
    for (int k = 0; k < FRAMES; k++) {
        dp_error err;
        snprintf(path, sizeof path, "%s/fb_%04d.exr", tmp, k);
        assert_int_equal(exr_read(path, &fr.frame[k], &err), 0);
    }
    /* the embedded frame with the most light, and its brightest block */
    int J = 0, bx = 0, by = 0;
    double most = -1;
    for (int j = 0; j < FRAMES / STRIDE; j++) {
        double sum = 0;
        for (size_t i = 0; i < (size_t)W * H * 3; i++) sum += fr.frame[j * STRIDE].rgb[i];
        if (sum > most) most = sum, J = j;
    }
    brightest(&fr, J, &bx, &by);
    int hx = 2 * 37 + 1, hy = 2 * 41, hframe = 2 * 11 + 1; /* hash: full-size pixel (75, 82), frame 23 */
    snprintf(page, sizeof page, "%s/harness.html", tmp);
    FILE *f = fopen(page, "w");
    assert_non_null(f);
    fprintf(f, HARNESS, hx, hy, hframe, J, bx, by, DW - 1, DH - 1);
    fclose(f);
    snprintf(errp, sizeof errp, "%s/chromium.err", tmp);
    cJSON *res = run_browser(page, errp);
    const cJSON *harness = cJSON_GetObjectItemCaseSensitive(res, "harness");
    if (harness) fail_msg("the test page failed: %s", harness->valuestring);
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(res, "done")));
    const cJSON *console = cJSON_GetObjectItemCaseSensitive(res, "console");
    if (cJSON_GetArraySize(console) > 0) fail_msg("console inside the page: %s", cJSON_GetArrayItem(console, 0)->valuestring);
    expect_quiet_console(errp);

    /* what the page says before any input: frame 0, the time unit, warped time, its default exposure */
    const cJSON *init = cJSON_GetObjectItemCaseSensitive(res, "initial");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(init, "frameInfo")->valuestring, "frame 0 of 50: [5, 5.05)");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(init, "unit")->valuestring, TIME_UNIT_TEXT);
    assert_non_null(strstr(cJSON_GetObjectItemCaseSensitive(init, "warp")->valuestring, "camera-warped"));
    assert_non_null(strstr(cJSON_GetObjectItemCaseSensitive(init, "scale")->valuestring, "downscaled by 2"));
    /* the slider snaps to 0.1 stops (0.05) and the histogram is 1/128 of an octave */
    ASSERT_NEAR(num(init, "exposure"), -log2(cube_q99(&fr)), 0.05 + 1.0 / 128);

    /* the slider's frame, two clicks, and the hash */
    char info[64];
    snprintf(info, sizeof info, "frame %d of 50: ", J * STRIDE);
    assert_true(!strncmp(cJSON_GetObjectItemCaseSensitive(res, "frameInfo")->valuestring, info, strlen(info)));
    const cJSON *clicks = cJSON_GetObjectItemCaseSensitive(res, "clicks");
    assert_int_equal(cJSON_GetArraySize(clicks), 2);
    int cx[2] = {bx, DW - 1}, cy[2] = {by, DH - 1};
    for (int i = 0; i < 2; i++) {
        const cJSON *c = cJSON_GetArrayItem(clicks, i);
        check_readout(&fr, cJSON_GetObjectItemCaseSensitive(c, "ds"), J * STRIDE, cx[i], cy[i]);
        check_curve(&fr, cJSON_GetObjectItemCaseSensitive(c, "curve"), cx[i], cy[i]);
    }
    const cJSON *hash = cJSON_GetObjectItemCaseSensitive(res, "hash");
    check_readout(&fr, hash, 22, 37, 41); /* frame 23 is not embedded: the one before it */
    assert_int_equal((int)num(res, "hashSlider"), 11);
    cJSON_Delete(res);
    for (int k = 0; k < FRAMES; k++) image_free(&fr.frame[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout),
        cmocka_unit_test(test_box_means_and_quantile),
        cmocka_unit_test_teardown(test_page_in_chromium, test_teardown_tmpdir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
