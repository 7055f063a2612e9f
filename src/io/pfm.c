/* Portable float map: "PF\n<w> <h>\n<scale>\n" then float32 rows from the bottom up; a negative scale
 * means little-endian. Written by hand (the format is three header tokens and raw floats). */
#include "dartspp/io.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PFM_HEADER_MAX 256

/* ---- writing ---- */

static void put_le32(unsigned char *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    p[0] = (unsigned char)u;
    p[1] = (unsigned char)(u >> 8);
    p[2] = (unsigned char)(u >> 16);
    p[3] = (unsigned char)(u >> 24);
}

static int write_rows(FILE *f, const image_rgb *img)
{
    size_t row_floats = (size_t)img->width * 3;
    unsigned char *row = malloc(row_floats * 4);
    if (!row) return -1;
    int ok = fprintf(f, "PF\n%d %d\n-1\n", img->width, img->height) > 0;
    for (int y = img->height - 1; ok && y >= 0; --y) {
        const float *src = img->rgb + (size_t)y * row_floats;
        for (size_t i = 0; i < row_floats; ++i) put_le32(row + 4 * i, src[i]);
        ok = fwrite(row, 4, row_floats, f) == row_floats;
    }
    free(row);
    return ok ? 0 : -1;
}

int pfm_write(const char *path, const image_rgb *img, dp_error *err)
{
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: cannot write an empty image", path);
    atomic_file af;
    FILE *f = atomic_fopen(path, "wb", &af, err);
    if (!f) return -1;
    return atomic_fclose(&af, write_rows(f, img) != 0, err);
}

/* ---- reading ---- */

typedef struct {
    int width, height, channels, little_endian;
    size_t data_offset;
} pfm_header;

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* Next whitespace-separated token of buf[*pos..len); at least one whitespace must precede it. */
static int next_token(const char *buf, size_t len, size_t *pos, char *tok, size_t tok_len)
{
    size_t p = *pos, n = 0;
    if (p >= len || !is_space(buf[p])) return -1;
    while (p < len && is_space(buf[p])) ++p;
    while (p < len && !is_space(buf[p]) && n + 1 < tok_len) tok[n++] = buf[p++];
    if (n == 0 || p >= len || !is_space(buf[p])) return -1;
    tok[n] = '\0';
    *pos = p;
    return 0;
}

static int parse_dim(const char *tok, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(tok, &end, 10);
    if (errno || *end || v <= 0 || v > INT_MAX) return -1;
    *out = (int)v;
    return 0;
}

static int parse_header(const char *buf, size_t len, pfm_header *h)
{
    char tok[64];
    size_t pos = 2;
    if (len < 3 || buf[0] != 'P' || (buf[1] != 'F' && buf[1] != 'f')) return -1;
    h->channels = buf[1] == 'F' ? 3 : 1;
    if (next_token(buf, len, &pos, tok, sizeof tok) || parse_dim(tok, &h->width)) return -1;
    if (next_token(buf, len, &pos, tok, sizeof tok) || parse_dim(tok, &h->height)) return -1;
    if (next_token(buf, len, &pos, tok, sizeof tok)) return -1;
    char *end;
    double scale = strtod(tok, &end);
    if (*end || !isfinite(scale) || scale == 0.0) return -1;
    h->little_endian = scale < 0.0;
    h->data_offset = pos + 1; /* exactly one whitespace character ends the header */
    return 0;
}

static float get32(const unsigned char *p, int little_endian)
{
    uint32_t u = little_endian
                     ? (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24
                     : (uint32_t)p[3] | (uint32_t)p[2] << 8 | (uint32_t)p[1] << 16 | (uint32_t)p[0] << 24;
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static void decode_row(const unsigned char *row, const pfm_header *h, float *dst)
{
    for (int x = 0; x < h->width; ++x)
        for (int c = 0; c < 3; ++c)
            dst[3 * x + c] = get32(row + 4 * ((size_t)x * h->channels + (h->channels == 3 ? c : 0)),
                                   h->little_endian);
}

static int read_pixels(FILE *f, const char *path, const pfm_header *h, image_rgb *img, dp_error *err)
{
    size_t row_bytes = (size_t)h->width * (size_t)h->channels * 4;
    unsigned char *row = malloc(row_bytes);
    if (!row) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    int rc = fseek(f, (long)h->data_offset, SEEK_SET);
    for (int i = 0; rc == 0 && i < h->height; ++i) {
        if (fread(row, 1, row_bytes, f) != row_bytes) rc = -1;
        else decode_row(row, h, img->rgb + (size_t)(h->height - 1 - i) * (size_t)h->width * 3);
    }
    free(row);
    return rc == 0 ? 0 : dp_fail(err, "%s: truncated PFM pixel data", path);
}

/* Reads and checks the header against the file size, so a corrupt size never drives an allocation. */
static int read_header(FILE *f, const char *path, pfm_header *h, dp_error *err)
{
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode))
        return dp_fail(err, "%s: not a regular file", path);
    char buf[PFM_HEADER_MAX];
    size_t len = fread(buf, 1, sizeof buf, f);
    if (parse_header(buf, len, h) != 0 || h->data_offset > len)
        return dp_fail(err, "%s: not a PFM file (bad header)", path);
    uint64_t data = (uint64_t)st.st_size - h->data_offset;
    uint64_t pixels = (uint64_t)h->width * (uint64_t)h->height;
    uint64_t px_bytes = (uint64_t)h->channels * 4;
    if ((uint64_t)st.st_size < h->data_offset || data % px_bytes != 0 || data / px_bytes != pixels)
        return dp_fail(err, "%s: truncated or wrong size: %lld bytes of pixel data for %dx%d pixels",
                       path, (long long)st.st_size - (long long)h->data_offset, h->width, h->height);
    return 0;
}

int pfm_read(const char *path, image_rgb *img, dp_error *err)
{
    img->width = img->height = 0;
    img->rgb = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return dp_fail(err, "%s: cannot open: %s", path, strerror(errno));
    pfm_header h = {0, 0, 0, 0, 0};
    int rc = read_header(f, path, &h, err);
    if (rc == 0 && image_alloc(img, h.width, h.height, err) != 0) {
        char why[sizeof err->msg];
        snprintf(why, sizeof why, "%s", err ? err->msg : "");
        rc = dp_fail_kind(err, err ? err->kind : DP_ERROR_INPUT, "%s: %s", path, why);
    }
    if (rc == 0) rc = read_pixels(f, path, &h, img, err);
    fclose(f);
    if (rc != 0) image_free(img);
    return rc;
}
