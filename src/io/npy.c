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
 * Atomic: the file is written to a temporary name and renamed into place by npy_close. */
#include "dartspp/io.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define NPY_ALIGN 64
#define NPY_PREFIX 10 /* magic, version, HEADER_LEN */

/* The dict text "{'descr': '<f4', 'fortran_order': False, 'shape': (...), }" into out; its length or -1. */
static int dict_text(char *out, size_t n, const size_t *shape, int ndim)
{
    size_t len = (size_t)snprintf(out, n, "{'descr': '<f4', 'fortran_order': False, 'shape': (");
    for (int i = 0; i < ndim && len < n; i++)
        len += (size_t)snprintf(out + len, n - len, i ? ", %zu" : "%zu", shape[i]);
    if (len < n) len += (size_t)snprintf(out + len, n - len, ndim == 1 ? ",), }" : "), }");
    return len < n ? (int)len : -1;
}

size_t npy_header(unsigned char *out, size_t n, const size_t *shape, int ndim)
{
    char dict[NPY_HEADER_MAX];
    int len = ndim >= 1 ? dict_text(dict, sizeof dict, shape, ndim) : -1;
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
