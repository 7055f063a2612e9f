/* Albedo bitmaps (.tga, .png and whatever else stb_image decodes), with the conventions of Tungsten's
 * BitmapTexture as a string `albedo` creates it (TextureCache::fetchTexture defaults: gamma_correct true,
 * interpolate true, clamp false):
 * - 8-bit texels go through Tungsten's gamma table, which is floor(255 (c/255)^2.2), then / 255 (a 2.2
 *   power rounded down to 8 bits, not the sRGB curve); the alpha channel is ignored;
 * - the image's top row is v = 1, its bottom row v = 0 (lookup row (1 - v)·height);
 * - bilinear between texel centres ((u·w − ½, (1 − v)·h − ½)), wrapping at every edge.
 * The same file referenced twice is decoded once (files compared by their resolved path). */
#include "scene_internal.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <stb/stb_image.h>

/* Tungsten's 8-bit gamma correction as linear floats */
static void gamma_table(float lut[256])
{
    for (int i = 0; i < 256; i++) lut[i] = (float)(floor(255.0 * pow(i / 255.0, 2.2)) / 255.0);
}

/* The file's bytes as stb_image's callbacks, noting a read past their end: stb_image's decoders read zeros
 * past the end of the data without failing, so a truncated or header-only file (a TGA above all) would
 * decode "fine" as a mostly black image. A refill that finds nothing left, a bulk read that comes up short
 * (stb's refills ask for 128 bytes and may get fewer at the end) or a skip past the end means the image
 * promised more bytes than the file holds. */
typedef struct {
    const unsigned char *data;
    size_t size, pos;
    int past_end;
} texture_bytes;

static int bytes_read(void *user, char *out, int size)
{
    texture_bytes *b = user;
    size_t want = size > 0 ? (size_t)size : 0, n = b->size - b->pos < want ? b->size - b->pos : want;
    if (n < want && (n == 0 || want != 128)) b->past_end = 1;
    memcpy(out, b->data + b->pos, n);
    b->pos += n;
    return (int)n;
}

static void bytes_skip(void *user, int n)
{
    texture_bytes *b = user;
    if (n < 0) b->pos = (size_t)-n > b->pos ? 0 : b->pos - (size_t)-n;
    else if ((size_t)n > b->size - b->pos) {
        b->past_end = 1;
        b->pos = b->size;
    } else b->pos += (size_t)n;
}

static int bytes_eof(void *user)
{
    const texture_bytes *b = user;
    return b->pos >= b->size;
}

static int decode(json_ctx *c, const char *where, const char *key, const char *file, texture *t)
{
    int w = 0, h = 0, n = 0;
    size_t size = 0;
    FILE *f = fopen(t->path, "rb");
    unsigned char *data = NULL;
    if (f && fseek(f, 0, SEEK_END) == 0) {
        long len = ftell(f);
        if (len >= 0 && (unsigned long)len < (unsigned long)INT_MAX && fseek(f, 0, SEEK_SET) == 0) {
            size = (size_t)len;
            data = malloc(size ? size : 1);
            if (data && fread(data, 1, size, f) != size) {
                free(data);
                data = NULL;
            }
        }
    }
    if (f) fclose(f);
    if (!data) return jfail(c, where, key, "cannot read texture '%s' (%s)", file, t->path);
    texture_bytes bytes = {data, size, 0, 0};
    const stbi_io_callbacks io = {bytes_read, bytes_skip, bytes_eof};
    unsigned char *px = stbi_load_from_callbacks(&io, &bytes, &w, &h, &n, 3);
    free(data);
    if (!px && !bytes.past_end) {
        const char *why = stbi_failure_reason();
        return jfail(c, where, key, "cannot decode texture '%s' (%s): %s", file, t->path, why && *why ? why : "unknown reason");
    }
    if (!px) return jfail(c, where, key, "cannot decode texture '%s' (%s): the file is truncated (%zu bytes)", file, t->path, size);
    if (bytes.past_end) {
        stbi_image_free(px);
        return jfail(c, where, key, "texture '%s' (%s) is truncated: its header promises %d x %d pixels, more than "
                     "the file's %zu bytes hold", file, t->path, w, h, size);
    }
    if (w < 1 || h < 1 || (size_t)w * (size_t)h > ((size_t)1 << 28)) {
        stbi_image_free(px);
        return jfail(c, where, key, "texture '%s' (%s): unsupported size %d x %d", file, t->path, w, h);
    }
    t->rgb = malloc((size_t)w * (size_t)h * 3 * sizeof(float));
    if (!t->rgb) {
        stbi_image_free(px);
        return jfail(c, where, key, "texture '%s': out of memory", file);
    }
    float lut[256];
    gamma_table(lut);
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; i++) t->rgb[i] = lut[px[i]];
    stbi_image_free(px);
    t->width = w;
    t->height = h;
    return 0;
}

int texture_fetch(json_ctx *c, scene *s, const char *where, const char *key, const char *file, int *index)
{
    *index = -1;
    char joined[2100], resolved[PATH_MAX];
    if (file[0] == '/') snprintf(joined, sizeof joined, "%s", file);
    else snprintf(joined, sizeof joined, "%s/%s", s->dir, file);
    struct stat st;
    if (stat(joined, &st) != 0 && errno == ENOENT) {
        jwarn(c, "%s.%s: texture '%s' not found (%s); using the constant albedo 0.5", where, key, file, joined);
        return 0;
    }
    if (!realpath(joined, resolved)) return jfail(c, where, key, "texture '%s' (%s): %s", file, joined, strerror(errno));
    if (strlen(resolved) >= sizeof s->textures[0].path) return jfail(c, where, key, "texture path too long");
    for (int i = 0; i < s->texture_count; i++)
        if (!strcmp(s->textures[i].path, resolved)) {
            *index = i;
            return 0;
        }
    texture *grown = realloc(s->textures, ((size_t)s->texture_count + 1) * sizeof(texture));
    if (!grown) return jfail(c, where, key, "out of memory");
    s->textures = grown;
    texture *t = &s->textures[s->texture_count];
    memset(t, 0, sizeof *t);
    memcpy(t->path, resolved, strlen(resolved) + 1); /* length checked above */
    if (decode(c, where, key, file, t)) return -1;
    *index = s->texture_count++;
    return 0;
}

vec3 texture_mean(const texture *t)
{
    double a[3] = {0, 0, 0};
    size_t n = (size_t)t->width * (size_t)t->height;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) a[k] += t->rgb[3 * i + (size_t)k];
    return n ? v3(a[0] / (double)n, a[1] / (double)n, a[2] / (double)n) : v3s(0.5);
}

void texture_free_all(scene *s)
{
    for (int i = 0; i < s->texture_count; i++) free(s->textures[i].rgb);
    free(s->textures);
    s->textures = NULL;
    s->texture_count = 0;
}

/* texel index along an axis of n texels, wrapped */
static long wrap(double i, int n)
{
    double r = fmod(i, (double)n);
    if (r < 0) r += n;
    long k = (long)r;
    return k >= n ? 0 : k;
}

vec3 scene_albedo(const scene *s, const bsdf *b, const hit_record *h)
{
    if (b->texture < 0 || b->texture >= s->texture_count || !h) return b->albedo;
    const texture *t = &s->textures[b->texture];
    double x = h->uv[0] * t->width - 0.5, y = (1.0 - h->uv[1]) * t->height - 0.5;
    if (!isfinite(x) || !isfinite(y)) return b->albedo;
    double x0 = floor(x), y0 = floor(y), fx = x - x0, fy = y - y0;
    long c0 = wrap(x0, t->width), c1 = wrap(x0 + 1.0, t->width);
    long r0 = wrap(y0, t->height), r1 = wrap(y0 + 1.0, t->height);
    const float *p00 = &t->rgb[3 * ((size_t)r0 * (size_t)t->width + (size_t)c0)];
    const float *p01 = &t->rgb[3 * ((size_t)r0 * (size_t)t->width + (size_t)c1)];
    const float *p10 = &t->rgb[3 * ((size_t)r1 * (size_t)t->width + (size_t)c0)];
    const float *p11 = &t->rgb[3 * ((size_t)r1 * (size_t)t->width + (size_t)c1)];
    double a[3];
    for (int k = 0; k < 3; k++)
        a[k] = (p00[k] * (1.0 - fx) + p01[k] * fx) * (1.0 - fy) + (p10[k] * (1.0 - fx) + p11[k] * fx) * fy;
    return v3(a[0], a[1], a[2]);
}
