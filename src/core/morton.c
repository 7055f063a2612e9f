/* Morton order of points (the linear BVHs of src/photon_beams and src/sliced_primitives): the points quantized
 * over their bounds to 21 bits per axis in space (3-D) or 16 bits per axis in space and time (4-D), the bits
 * interleaved, sorted by that key and then by index (a total
 * order, so the trees built from it do not depend on anything but the input). */
#include <stdlib.h>

#include "dartspp/core.h"

static uint64_t spread21(uint32_t v)
{
    uint64_t x = v & 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

/* 16 bits of v spread to every 4th bit (the 4-D Morton code of space and time). */
static uint64_t spread16x4(uint32_t v)
{
    uint64_t x = 0;
    for (int b = 0; b < 16; b++) x |= (uint64_t)((v >> b) & 1u) << (4 * b);
    return x;
}

typedef struct {
    uint64_t key;
    uint32_t at;
} morton_key;

static int key_cmp(const void *a, const void *b)
{
    const morton_key *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->at < y->at ? -1 : x->at > y->at; /* ties by index */
}

int dp_morton_order(const float *c, size_t stride, size_t n, int dims, uint32_t *order)
{
    float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < dims; k++) {
            float v = c[i * stride + k];
            if (v < lo[k]) lo[k] = v;
            if (v > hi[k]) hi[k] = v;
        }
    morton_key *key = malloc((n ? n : 1) * sizeof *key);
    if (!key) return -1;
    double top = dims == 4 ? 65535.0 : 2097151.0; /* 16 bits of each of x, y, z, t; or 21 of x, y, z */
    for (size_t i = 0; i < n; i++) {
        uint64_t code = 0;
        for (int k = 0; k < dims; k++) {
            double ext = (double)hi[k] - lo[k], u = ext > 0.0 ? ((double)c[i * stride + k] - lo[k]) / ext : 0.0;
            uint32_t q = (uint32_t)(u * top);
            code |= dims == 4 ? spread16x4(q) << k : spread21(q) << k;
        }
        key[i] = (morton_key){code, (uint32_t)i};
    }
    qsort(key, n, sizeof *key, key_cmp);
    for (size_t i = 0; i < n; i++) order[i] = key[i].at;
    free(key);
    return 0;
}
