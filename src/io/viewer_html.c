/* The frames viewer page (io.h): one HTML file with everything embedded — style, script, the metadata as
 * JSON and the frames as base64 of little-endian float32 — so that it opens offline from the file system.
 * The page reads its data from two script elements (id "meta": JSON, id "cube": base64 of
 * embedded × dh × dw × 3 floats in C order) and exposes what it shows in stable ids: "time-slider",
 * "play", "exposure" (stops), "frame-info", "warp-info", "image", "curve" (whose data-curve attribute holds
 * the plotted curve as JSON) and "pixel-readout" (data-x, data-y, data-frame, data-t0, data-t1, data-r,
 * data-g, data-b). The URL hash "#x=X&y=Y&frame=K&exposure=E" (full-size pixel, frame index, stops; any
 * subset) selects a pixel and a frame when the page opens. */
#include "dartspp/io.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static const char PAGE_HEAD[] =
    "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    "<link rel=\"icon\" href=\"data:,\">\n<title>dartspp frames</title>\n<style>\n"
    "body { font: 14px/1.4 sans-serif; margin: 12px; color: #222; background: #f4f4f4; }\n"
    "h1 { font-size: 16px; margin: 0 0 8px; }\n"
    "#controls { display: flex; flex-wrap: wrap; gap: 6px 18px; align-items: center; margin-bottom: 8px; }\n"
    "#views { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; }\n"
    "#image { image-rendering: pixelated; cursor: crosshair; background: #000; }\n"
    "#image-box { position: relative; line-height: 0; }\n"
    "#marker { position: absolute; width: 10px; height: 10px; margin: -6px 0 0 -6px; border: 1px solid #fff;\n"
    "  outline: 1px solid #000; border-radius: 50%; pointer-events: none; }\n"
    "#side { width: 442px; }\n#curve { background: #fff; border: 1px solid #ccc; }\n"
    "#pixel-readout { display: block; font: 13px/1.4 monospace; margin: 8px 0; }\n"
    "p { margin: 4px 0; } .note { color: #555; font-size: 12px; }\n"
    "</style>\n</head>\n<body>\n<h1 id=\"title\">dartspp frames</h1>\n"
    "<div id=\"controls\">\n"
    "<button id=\"play\" type=\"button\">play</button>\n"
    "<label>frame <input id=\"time-slider\" type=\"range\" min=\"0\" max=\"0\" step=\"1\" value=\"0\"></label>\n"
    "<span id=\"frame-info\"></span>\n"
    "<label>exposure <input id=\"exposure\" type=\"range\" min=\"-12\" max=\"12\" step=\"0.1\" value=\"0\"></label>\n"
    "<span><span id=\"exposure-value\">0</span> stops</span>\n"
    "</div>\n<div id=\"views\">\n<div id=\"image-box\"><canvas id=\"image\" width=\"1\" height=\"1\"></canvas>"
    "<div id=\"marker\" hidden></div></div>\n<div id=\"side\">\n"
    "<canvas id=\"curve\" width=\"440\" height=\"280\"></canvas>\n"
    "<output id=\"pixel-readout\">click the image to plot a pixel's transient curve</output>\n"
    "<p id=\"time-info\">time: <span id=\"time-unit\"></span>; <span id=\"warp-info\"></span></p>\n"
    "<p id=\"scale-info\" class=\"note\"></p>\n</div>\n</div>\n";

/* The page's script: decodes the cube, draws frames at one exposure, plots a clicked pixel's curve. */
static const char PAGE_SCRIPT[] =
    "<script>\n(function () {\n\"use strict\";\n"
    "function $(id) { return document.getElementById(id); }\n"
    "var meta = JSON.parse($(\"meta\").textContent);\n"
    "function decode(text) {\n"
    "  var bin = atob(text.replace(/\\s+/g, \"\")), bytes = new Uint8Array(bin.length);\n"
    "  for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);\n"
    "  var view = new DataView(bytes.buffer), out = new Float32Array(bytes.length >> 2);\n"
    "  for (var j = 0; j < out.length; j++) out[j] = view.getFloat32(4 * j, true);\n"
    "  return out;\n}\n"
    "var cube = decode($(\"cube\").textContent);\n"
    "var W = meta.dw, H = meta.dh, M = meta.embedded, F = meta.factor, plane = W * H * 3;\n"
    "var slider = $(\"time-slider\"), exposure = $(\"exposure\"), img = $(\"image\"), curve = $(\"curve\");\n"
    "var readout = $(\"pixel-readout\");\n"
    "img.width = W; img.height = H;\n"
    "var zoom = 400 / Math.max(W, H);\n"
    "img.style.width = (W * zoom) + \"px\"; img.style.height = (H * zoom) + \"px\";\n"
    "var ctx = img.getContext(\"2d\"), pixels = ctx.createImageData(W, H);\n"
    "var lut = new Uint8ClampedArray(4097);\n"
    "for (var i = 0; i <= 4096; i++) {\n"
    "  var c = i / 4096;\n"
    "  lut[i] = Math.round(255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055));\n}\n"
    "var state = { j: 0, sel: null, timer: null };\n"
    "function fmt(x) { return String(Number(Number(x).toPrecision(6))); }\n"
    "function frameOf(j) { return j * meta.stride; }\n"
    "function interval(k) { return [meta.start + k * meta.frame_width, meta.start + (k + 1) * meta.frame_width]; }\n"
    "function value(j, x, y, c) { return cube[j * plane + 3 * (y * W + x) + c]; }\n"
    "function clamp(v, lo, hi) { return Math.min(hi, Math.max(lo, v)); }\n"
    "function draw() {\n"
    "  var scale = Math.pow(2, Number(exposure.value)), base = state.j * plane, d = pixels.data;\n"
    "  for (var p = 0; p < W * H; p++) {\n"
    "    for (var c = 0; c < 3; c++) {\n"
    "      var v = cube[base + 3 * p + c] * scale;\n"
    "      d[4 * p + c] = lut[v >= 1 ? 4096 : v > 0 ? Math.floor(v * 4096) : 0];\n"
    "    }\n"
    "    d[4 * p + 3] = 255;\n  }\n"
    "  ctx.putImageData(pixels, 0, 0);\n}\n"
    "function showTime() {\n"
    "  var k = frameOf(state.j), t = interval(k);\n"
    "  $(\"frame-info\").textContent = \"frame \" + k + \" of \" + meta.frames + \": [\" + fmt(t[0]) + \", \" +\n"
    "    fmt(t[1]) + \")\";\n}\n"
    "function showReadout() {\n"
    "  var s = state.sel;\n"
    "  if (!s) return;\n"
    "  var k = frameOf(state.j), t = interval(k), rgb = [0, 1, 2].map(function (c) { return value(state.j, s.x, s.y, c); });\n"
    "  var ds = readout.dataset;\n"
    "  ds.x = s.x; ds.y = s.y; ds.frame = k; ds.t0 = t[0]; ds.t1 = t[1];\n"
    "  ds.r = rgb[0]; ds.g = rgb[1]; ds.b = rgb[2];\n"
    "  var block = F > 1 ? \" (pixels \" + s.x * F + \"\\u2013\" + (Math.min((s.x + 1) * F, meta.width) - 1) + \" \\u00d7 \" +\n"
    "    s.y * F + \"\\u2013\" + (Math.min((s.y + 1) * F, meta.height) - 1) + \" of the frame)\" : \"\";\n"
    "  readout.textContent = \"x \" + s.x + \", y \" + s.y + block + \", frame \" + k + \" [\" + fmt(t[0]) + \", \" +\n"
    "    fmt(t[1]) + \"): r \" + fmt(rgb[0]) + \", g \" + fmt(rgb[1]) + \", b \" + fmt(rgb[2]);\n}\n"
    "function curveData() {\n"
    "  var s = state.sel, d = { x: s.x, y: s.y, frames: [], t: [], r: [], g: [], b: [] };\n"
    "  for (var j = 0; j < M; j++) {\n"
    "    var k = frameOf(j), t = interval(k);\n"
    "    d.frames.push(k); d.t.push((t[0] + t[1]) / 2);\n"
    "    d.r.push(value(j, s.x, s.y, 0)); d.g.push(value(j, s.x, s.y, 1)); d.b.push(value(j, s.x, s.y, 2));\n"
    "  }\n  return d;\n}\n"
    "function plotCurve() {\n"
    "  if (!state.sel) return;\n"
    "  var d = curveData(), g = curve.getContext(\"2d\"), w = curve.width, h = curve.height;\n"
    "  var L = 64, R = 12, T = 14, B = 44;\n"
    "  curve.setAttribute(\"data-curve\", JSON.stringify(d));\n"
    "  var ymax = 0;\n"
    "  for (var j = 0; j < M; j++) ymax = Math.max(ymax, d.r[j], d.g[j], d.b[j]);\n"
    "  if (!(ymax > 0)) ymax = 1;\n"
    "  var half = meta.frame_width * meta.stride / 2, t0 = d.t[0] - half, t1 = d.t[M - 1] + half;\n"
    "  function X(t) { return L + (t - t0) / (t1 - t0) * (w - L - R); }\n"
    "  function Y(v) { return h - B - v / ymax * (h - T - B); }\n"
    "  g.clearRect(0, 0, w, h);\n"
    "  g.strokeStyle = \"#888\"; g.lineWidth = 1; g.beginPath();\n"
    "  g.moveTo(L, T); g.lineTo(L, h - B); g.lineTo(w - R, h - B); g.stroke();\n"
    "  var now = d.t[state.j];\n"
    "  g.strokeStyle = \"#bbb\"; g.beginPath(); g.moveTo(X(now), T); g.lineTo(X(now), h - B); g.stroke();\n"
    "  [[\"r\", \"#d62728\"], [\"g\", \"#2ca02c\"], [\"b\", \"#1f77b4\"]].forEach(function (ch) {\n"
    "    g.strokeStyle = ch[1]; g.lineWidth = 1.5; g.beginPath();\n"
    "    d[ch[0]].forEach(function (v, j) { if (j) g.lineTo(X(d.t[j]), Y(v)); else g.moveTo(X(d.t[j]), Y(v)); });\n"
    "    g.stroke();\n  });\n"
    "  g.fillStyle = \"#222\"; g.font = \"11px sans-serif\"; g.textAlign = \"right\";\n"
    "  g.fillText(fmt(ymax), L - 4, T + 4); g.fillText(\"0\", L - 4, h - B + 4);\n"
    "  g.textAlign = \"left\"; g.fillText(fmt(t0), L, h - B + 14);\n"
    "  g.textAlign = \"right\"; g.fillText(fmt(t1), w - R, h - B + 14);\n"
    "  g.textAlign = \"center\";\n"
    "  g.fillText(\"time: \" + meta.time_unit, (L + w - R) / 2, h - 8);\n"
    "  g.textAlign = \"left\"; g.fillText(\"pixel \" + d.x + \", \" + d.y + \": r, g, b per frame\", L + 6, T + 4);\n}\n"
    "function setFrame(j) {\n"
    "  state.j = clamp(Math.floor(j), 0, M - 1);\n"
    "  slider.value = state.j;\n"
    "  draw(); showTime(); plotCurve(); showReadout();\n}\n"
    "function setExposure(e) {\n"
    "  exposure.value = e;\n"
    "  $(\"exposure-value\").textContent = Number(exposure.value).toFixed(1);\n"
    "  draw();\n}\n"
    "function select(x, y) {\n"
    "  state.sel = { x: clamp(x, 0, W - 1), y: clamp(y, 0, H - 1) };\n"
    "  var m = $(\"marker\");\n"
    "  m.style.left = ((state.sel.x + 0.5) * zoom) + \"px\"; m.style.top = ((state.sel.y + 0.5) * zoom) + \"px\";\n"
    "  m.hidden = false;\n"
    "  plotCurve(); showReadout();\n}\n"
    "function applyHash() {\n"
    "  var h = {};\n"
    "  location.hash.replace(/^#/, \"\").split(\"&\").forEach(function (kv) {\n"
    "    var p = kv.split(\"=\");\n"
    "    if (p.length === 2 && p[1] !== \"\") h[p[0]] = Number(p[1]);\n  });\n"
    "  if (isFinite(h.exposure)) setExposure(h.exposure);\n"
    "  if (isFinite(h.frame)) setFrame(h.frame / meta.stride);\n"
    "  if (isFinite(h.x) && isFinite(h.y)) select(Math.floor(h.x / F), Math.floor(h.y / F));\n}\n"
    "slider.max = M - 1;\n"
    "var e0 = Math.round(meta.exposure);\n"
    "exposure.min = e0 - 12; exposure.max = e0 + 12;\n"
    "slider.addEventListener(\"input\", function () { setFrame(Number(slider.value)); });\n"
    "exposure.addEventListener(\"input\", function () { setExposure(exposure.value); });\n"
    "img.addEventListener(\"click\", function (e) {\n"
    "  var r = img.getBoundingClientRect();\n"
    "  var x = Math.floor((e.clientX - r.left) / r.width * W), y = Math.floor((e.clientY - r.top) / r.height * H);\n"
    "  if (x >= 0 && y >= 0 && x < W && y < H) select(x, y);\n});\n"
    "$(\"play\").addEventListener(\"click\", function () {\n"
    "  if (state.timer) { clearInterval(state.timer); state.timer = null; this.textContent = \"play\"; return; }\n"
    "  state.timer = setInterval(function () { setFrame((state.j + 1) % M); }, 125);\n"
    "  this.textContent = \"pause\";\n});\n"
    "window.addEventListener(\"hashchange\", applyHash);\n"
    "$(\"title\").textContent = \"dartspp frames: \" + meta.title;\n"
    "document.title = \"dartspp frames: \" + meta.title;\n"
    "$(\"time-unit\").textContent = meta.time_unit;\n"
    "$(\"warp-info\").textContent = meta.camera_warped ? \"camera-warped: the camera leg counts in a path's time\" :\n"
    "  \"camera-unwarped: a path's time leaves out the camera segment adjacent to the sensor\";\n"
    "$(\"scale-info\").textContent = \"Embedded: \" + M + \" of \" + meta.frames + \" frames\" +\n"
    "  (meta.stride > 1 ? \" (every \" + meta.stride + \"th)\" : \"\") + \", \" + meta.width + \"\\u00d7\" + meta.height +\n"
    "  \" downscaled by \" + F + (F > 1 ? \" (each pixel the mean of a \" + F + \"\\u00d7\" + F + \" block)\" : \" (full size)\") +\n"
    "  \" to \" + W + \"\\u00d7\" + H + \"; float32 little-endian, base64 (at most \" + meta.payload_max + \" bytes of floats). \" +\n"
    "  \"Default exposure: the 0.99 quantile of the cube's positive values (\" + fmt(meta.q99) + \") maps to 1.\";\n"
    "setExposure(meta.exposure);\n"
    "setFrame(0);\n"
    "applyHash();\n"
    "})();\n</script>\n</body>\n</html>\n";

/* A JSON string, with '<', '>' and '&' escaped too so that no text can end the script element. */
static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p < 0x20 || *p == '"' || *p == '\\' || *p == '<' || *p == '>' || *p == '&') fprintf(f, "\\u%04x", *p);
        else fputc(*p, f);
    }
    fputc('"', f);
}

static void write_meta(FILE *f, const viewer_cube *v, const viewer_time *t)
{
    const viewer_layout *l = &v->l;
    double q = viewer_cube_quantile(v, 0.99);
    fputs("<script id=\"meta\" type=\"application/json\">{\"title\": ", f);
    json_string(f, t->title ? t->title : "");
    fputs(", \"time_unit\": ", f);
    json_string(f, t->time_unit ? t->time_unit : "");
    fprintf(f, ", \"camera_warped\": %d, \"start\": %.17g, \"frame_width\": %.17g, \"frames\": %d, \"stride\": %d, "
            "\"embedded\": %d, \"width\": %d, \"height\": %d, \"factor\": %d, \"dw\": %d, \"dh\": %d, "
            "\"q99\": %.9g, \"exposure\": %.9g, \"payload_max\": %zu, \"encoding\": \"float32le-base64\"}</script>\n",
            t->camera_warped, t->start, t->width, l->frames, l->stride, l->embedded, l->width, l->height, l->factor,
            l->dw, l->dh, q, q > 0 ? -log2(q) : 0.0, (size_t)VIEWER_PAYLOAD_MAX);
}

static const char B64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* n bytes as base64 (the last group padded with '='). */
static void base64(FILE *f, const unsigned char *b, size_t n)
{
    char out[4];
    for (size_t i = 0; i < n; i += 3) {
        uint32_t g = (uint32_t)b[i] << 16 | (i + 1 < n ? (uint32_t)b[i + 1] << 8 : 0) | (i + 2 < n ? b[i + 2] : 0);
        for (int k = 0; k < 4; k++) out[k] = B64[(g >> (18 - 6 * k)) & 63];
        if (i + 1 >= n) out[2] = '=';
        if (i + 2 >= n) out[3] = '=';
        fwrite(out, 1, 4, f);
    }
}

/* The floats as base64 of little-endian float32, in lines of 4096 characters (chunks of 768 floats, a
 * multiple of 3 bytes, so only the last chunk can need padding). */
static void write_payload(FILE *f, const float *v, size_t n)
{
    unsigned char chunk[768 * 4];
    fputs("<script id=\"cube\" type=\"text/plain\">\n", f);
    for (size_t i = 0; i < n; i += 768) {
        size_t m = n - i < 768 ? n - i : 768;
        for (size_t j = 0; j < m; j++) {
            uint32_t u;
            memcpy(&u, &v[i + j], sizeof u);
            for (int k = 0; k < 4; k++) chunk[4 * j + k] = (unsigned char)(u >> (8 * k));
        }
        base64(f, chunk, 4 * m);
        fputc('\n', f);
    }
    fputs("</script>\n", f);
}

int viewer_html_write(const char *path, const viewer_cube *v, const viewer_time *t, dp_error *err)
{
    const viewer_layout *l = &v->l;
    atomic_file af;
    FILE *f = atomic_fopen(path, "wb", &af, err);
    if (!f) return -1;
    fputs(PAGE_HEAD, f);
    write_meta(f, v, t);
    write_payload(f, v->data, (size_t)l->embedded * l->dw * l->dh * 3);
    fputs(PAGE_SCRIPT, f);
    return atomic_fclose(&af, 0, err);
}
