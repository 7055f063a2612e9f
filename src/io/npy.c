/* NumPy .npy files of float32, written by hand (the format is a short text header and raw values), streamed
 * so that a transient cube never has to be held in memory at once.
 *
 * Layout of a version 1.0 file, as NumPy writes it (numpy/lib/format.py describes the format):
 *   bytes 0..5   magic "\x93NUMPY"
 *   byte  6, 7   format version: major 1, minor 0
 *   bytes 8, 9   HEADER_LEN, little-endian uint16: the length of the header text that follows
 *   bytes 10..   the header text, a Python dict literal with the keys in this order:
 *                  {'descr': '<f4', 'fortran_order': False, 'shape': (d0, d1, ...), }
 *                (a 1-D shape is written "(d0,)"), padded with spaces and ended by '\n' so that the data
 *                starts at a multiple of 64 bytes: 10 + HEADER_LEN ≡ 0 (mod 64)
 *   then         the values, float32 little-endian, in C order (the last axis varies fastest).
 * Atomic: the file is written to a temporary name and renamed into place by npy_close. Also complex64 ('<c8':
 * each value two float32, real then imaginary) and int32 ('<i4') arrays, written at once. */
#include "dartspp/io.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NPY_ALIGN 64
#define NPY_PREFIX 10 /* magic, version, HEADER_LEN */

/* The dict text "{'descr': '<f4', 'fortran_order': False, 'shape': (...), }" into out; its length or -1. */
static int dict_text(char *out, size_t n, const char *descr, const size_t *shape, int ndim)
{
    size_t len = (size_t)snprintf(out, n, "{'descr': '%s', 'fortran_order': False, 'shape': (", descr);
    for (int i = 0; i < ndim && len < n; i++)
        len += (size_t)snprintf(out + len, n - len, i ? ", %zu" : "%zu", shape[i]);
    if (len < n) len += (size_t)snprintf(out + len, n - len, ndim == 1 ? ",), }" : "), }");
    return len < n ? (int)len : -1;
}

static size_t header_of(unsigned char *out, size_t n, const char *descr, const size_t *shape, int ndim)
{
    char dict[NPY_HEADER_MAX];
    int len = ndim >= 1 ? dict_text(dict, sizeof dict, descr, shape, ndim) : -1;
    if (len < 0) return 0;
    size_t total = ((size_t)NPY_PREFIX + (size_t)len + 1 + NPY_ALIGN - 1) / NPY_ALIGN * NPY_ALIGN;
    size_t header_len = total - NPY_PREFIX;
    if (total > n || header_len > UINT16_MAX) return 0;
    memcpy(out, "\x93NUMPY\x01\x00", 8);
    out[8] = (unsigned char)(header_len & 0xff);
    out[9] = (unsigned char)(header_len >> 8);
    memcpy(out + NPY_PREFIX, dict, (size_t)len);
    memset(out + NPY_PREFIX + len, ' ', header_len - (size_t)len - 1);
    out[total - 1] = '\n';
    return total;
}

size_t npy_header(unsigned char *out, size_t n, const size_t *shape, int ndim)
{
    return header_of(out, n, "<f4", shape, ndim);
}

int npy_open(npy_file *w, const char *path, const size_t *shape, int ndim, dp_error *err)
{
    unsigned char header[NPY_HEADER_MAX];
    size_t n = npy_header(header, sizeof header, shape, ndim);
    if (!n) return dp_fail_kind(err, DP_ERROR_INTERNAL,
                                "%s: cannot describe an array of %d axes in a .npy header", path, ndim);
    w->left = 1;
    for (int i = 0; i < ndim; i++) w->left *= shape[i];
    if (!atomic_fopen(path, "wb", &w->af, err)) return -1;
    if (fwrite(header, 1, n, w->af.f) == n) return 0;
    return atomic_fclose(&w->af, 1, err);
}

/* Little-endian float32, whatever the host's byte order. */
static void put_f32_le(unsigned char *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(u >> (8 * i));
}

int npy_append(npy_file *w, const float *v, size_t n, dp_error *err)
{
    if (n > w->left) {
        atomic_fabort(&w->af);
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: more values than the .npy shape holds", w->af.path);
    }
    unsigned char buf[4096];
    for (size_t i = 0; i < n;) {
        size_t m = 0;
        for (; m < sizeof buf / 4 && i < n; m++, i++) put_f32_le(buf + 4 * m, v[i]);
        if (fwrite(buf, 4, m, w->af.f) != m) return atomic_fclose(&w->af, 1, err);
    }
    w->left -= n;
    return 0;
}

int npy_close(npy_file *w, dp_error *err)
{
    if (w->left) {
        atomic_fabort(&w->af);
        return dp_fail_kind(err, DP_ERROR_INTERNAL,
                            "%s: %zu values of the .npy shape were never written", w->af.path, w->left);
    }
    return atomic_fclose(&w->af, 0, err);
}

void npy_abort(npy_file *w) { atomic_fabort(&w->af); }

int npy_write_f32(const char *path, const size_t *shape, int ndim, const float *data, dp_error *err)
{
    npy_file w;
    if (npy_open(&w, path, shape, ndim, err)) return -1;
    if (npy_append(&w, data, w.left, err)) return -1;
    return npy_close(&w, err);
}

int npy_write_c64(const char *path, const size_t *shape, int ndim, const float *data, dp_error *err)
{
    unsigned char header[NPY_HEADER_MAX];
    size_t n = header_of(header, sizeof header, "<c8", shape, ndim), count = 2;
    if (!n) return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: cannot describe an array of %d axes in a .npy header", path, ndim);
    for (int i = 0; i < ndim; i++) count *= shape[i];
    npy_file w = {.left = count};
    if (!atomic_fopen(path, "wb", &w.af, err)) return -1;
    if (fwrite(header, 1, n, w.af.f) != n) return atomic_fclose(&w.af, 1, err);
    if (npy_append(&w, data, count, err)) return -1; /* little-endian float32 pairs: '<c8' */
    return npy_close(&w, err);
}

int npy_write_i32(const char *path, const size_t *shape, int ndim, const int32_t *data, dp_error *err)
{
    unsigned char header[NPY_HEADER_MAX];
    size_t n = header_of(header, sizeof header, "<i4", shape, ndim), count = 1;
    if (!n) return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: cannot describe an array of %d axes in a .npy header", path, ndim);
    for (int i = 0; i < ndim; i++) count *= shape[i];
    atomic_file af;
    if (!atomic_fopen(path, "wb", &af, err)) return -1;
    if (fwrite(header, 1, n, af.f) != n) return atomic_fclose(&af, 1, err);
    unsigned char buf[4096];
    for (size_t i = 0; i < count;) {
        size_t m = 0;
        for (; m < sizeof buf / 4 && i < count; m++, i++)
            for (int b = 0; b < 4; b++) buf[4 * m + b] = (unsigned char)((uint32_t)data[i] >> (8 * b));
        if (fwrite(buf, 4, m, af.f) != m) return atomic_fclose(&af, 1, err);
    }
    return atomic_fclose(&af, 0, err);
}

/* ---- reading: float32 arrays in C order, as our cubes are (and as NumPy writes np.float32 arrays) ---- */

/* The value of 'key' in the header dict: a pointer just past "'key':" and its spaces, or NULL. */
static const char *dict_value(const char *dict, const char *key)
{
    char pat[32];
    snprintf(pat, sizeof pat, "'%s':", key);
    const char *p = strstr(dict, pat);
    if (!p) return NULL;
    p += strlen(pat);
    while (*p == ' ') p++;
    return p;
}

/* The shape tuple "(d0, d1, ...)" (a 1-D one "(d0,)", a scalar "()"). Returns the axes or -1. */
static int parse_shape(const char *p, size_t *shape)
{
    if (!p || *p != '(') return -1;
    p++;
    int ndim = 0;
    for (;;) {
        while (*p == ' ') p++;
        if (*p == ')') return ndim;
        if (ndim == NPY_MAX_DIMS) return -1;
        char *end;
        errno = 0;
        unsigned long long v = strtoull(p, &end, 10);
        if (end == p || errno || *p == '-') return -1;
        shape[ndim++] = (size_t)v;
        p = end;
        while (*p == ' ') p++;
        if (*p == ',') p++;
        else if (*p != ')') return -1;
    }
}

static int read_fail(FILE *f, const char *path, dp_error *err, const char *why)
{
    if (f) fclose(f);
    return dp_fail(err, "%s: not a float32 .npy array we can read: %s", path, why);
}

int npy_read_f32(const char *path, size_t *shape, int *ndim, float **data, dp_error *err)
{
    *data = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return dp_fail(err, "%s: cannot open: %s", path, strerror(errno));
    unsigned char pre[12];
    if (fread(pre, 1, 8, f) != 8 || memcmp(pre, "\x93NUMPY", 6)) return read_fail(f, path, err, "no .npy magic");
    size_t len;
    if (pre[6] == 1) {
        if (fread(pre + 8, 1, 2, f) != 2) return read_fail(f, path, err, "truncated header");
        len = (size_t)pre[8] | (size_t)pre[9] << 8;
    } else if (pre[6] == 2 || pre[6] == 3) {
        if (fread(pre + 8, 1, 4, f) != 4) return read_fail(f, path, err, "truncated header");
        len = (size_t)pre[8] | (size_t)pre[9] << 8 | (size_t)pre[10] << 16 | (size_t)pre[11] << 24;
    } else {
        return read_fail(f, path, err, "unknown format version");
    }
    if (len > 1 << 20) return read_fail(f, path, err, "header longer than 1 MiB");
    char *dict = malloc(len + 1);
    if (!dict) return read_fail(f, path, err, "out of memory");
    if (fread(dict, 1, len, f) != len) {
        free(dict);
        return read_fail(f, path, err, "truncated header");
    }
    dict[len] = 0;
    const char *descr = dict_value(dict, "descr"), *order = dict_value(dict, "fortran_order");
    int n = parse_shape(dict_value(dict, "shape"), shape);
    const char *why = !descr || strncmp(descr, "'<f4'", 5) ? "its dtype is not '<f4' (float32, little-endian)"
                      : !order || strncmp(order, "False", 5) ? "it is in Fortran order"
                      : n < 1 ? "no shape of 1 to 8 axes" : NULL;
    free(dict);
    if (why) return read_fail(f, path, err, why);
    size_t count = 1;
    for (int i = 0; i < n; i++) {
        if (shape[i] && count > SIZE_MAX / 4 / shape[i]) return read_fail(f, path, err, "too many values");
        count *= shape[i];
    }
    float *v = malloc(count ? count * sizeof *v : 1);
    if (!v) {
        fclose(f);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for %zu values", path, count);
    }
    unsigned char buf[4096];
    for (size_t i = 0; i < count;) {
        size_t m = count - i < sizeof buf / 4 ? count - i : sizeof buf / 4;
        if (fread(buf, 4, m, f) != m) {
            free(v);
            return read_fail(f, path, err, "fewer values than its shape says");
        }
        for (size_t j = 0; j < m; j++, i++) {
            uint32_t u = (uint32_t)buf[4 * j] | (uint32_t)buf[4 * j + 1] << 8 | (uint32_t)buf[4 * j + 2] << 16 |
                         (uint32_t)buf[4 * j + 3] << 24;
            memcpy(&v[i], &u, 4);
        }
    }
    if (fgetc(f) != EOF) {
        free(v);
        return read_fail(f, path, err, "more bytes than its shape says");
    }
    fclose(f);
    *ndim = n;
    *data = v;
    return 0;
}
