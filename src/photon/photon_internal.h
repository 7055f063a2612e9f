/* Inside the photon module: the per-thread photon buffers and one light path, shared by the photon pass
 * (photon_pass.c) and the surface chains (surface_chain.c). */
#ifndef DARTSPP_PHOTON_INTERNAL_H
#define DARTSPP_PHOTON_INTERNAL_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/photon.h"
#include "dartspp/scene.h"

typedef struct {
    photon *p;
    size_t n, cap;
    unsigned char *d; /* with derivatives: the photons' photon_deriv records (stride bytes each), else NULL */
} photon_buf;

#define PHOTON_BUF_FIRST 1024 /* a photon buffer's first capacity; it then doubles (photon_array_bytes) */

/* The capacity of a buffer that must hold `need` items: PHOTON_BUF_FIRST, then doubling. */
static inline size_t buf_capacity(size_t cap, size_t need)
{
    cap = cap ? cap : PHOTON_BUF_FIRST;
    while (cap < need) cap *= 2;
    return cap;
}

/* Grows b to hold at least `need` photons (and their derivative records when stride > 0), its count kept. */
static inline int buf_reserve(photon_buf *b, size_t need, size_t stride)
{
    if (need <= b->cap) return 0;
    size_t cap = buf_capacity(b->cap, need);
    photon *q = realloc(b->p, cap * sizeof(photon));
    if (!q) return -1;
    b->p = q;
    if (stride) {
        unsigned char *e = realloc(b->d, cap * stride);
        if (!e) return -1;
        b->d = e;
    }
    b->cap = cap;
    return 0;
}

/* Appends a photon and, when stride > 0, its derivative record `side` (the same index in b->d). */
static inline int buf_push(photon_buf *b, const photon *ph, const void *side, size_t stride)
{
    if (buf_reserve(b, b->n + 1, stride)) return -1;
    if (stride) memcpy(b->d + b->n * stride, side, stride);
    b->p[b->n++] = *ph;
    return 0;
}

static inline void buf_free(photon_buf *b)
{
    free(b->p);
    free(b->d);
    b->p = NULL;
    b->d = NULL;
}

typedef struct {
    photon_beam *p;
    size_t n, cap;
} beam_buf;

static inline int beam_buf_reserve(beam_buf *b, size_t need)
{
    if (need <= b->cap) return 0;
    size_t cap = buf_capacity(b->cap, need);
    photon_beam *q = realloc(b->p, cap * sizeof(photon_beam));
    if (!q) return -1;
    b->p = q;
    b->cap = cap;
    return 0;
}

static inline int beam_buf_push(beam_buf *b, const photon_beam *bm)
{
    if (beam_buf_reserve(b, b->n + 1)) return -1;
    b->p[b->n++] = *bm;
    return 0;
}

typedef struct {
    path_vertex *p;
    size_t n, cap;
} vertex_buf;

static inline int vertex_buf_reserve(vertex_buf *b, size_t need)
{
    if (need <= b->cap) return 0;
    size_t cap = buf_capacity(b->cap, need);
    path_vertex *q = realloc(b->p, cap * sizeof(path_vertex));
    if (!q) return -1;
    b->p = q;
    b->cap = cap;
    return 0;
}

static inline int vertex_buf_push(vertex_buf *b, const path_vertex *v)
{
    if (vertex_buf_reserve(b, b->n + 1)) return -1;
    b->p[b->n++] = *v;
    return 0;
}

/* Written by one thread per photon stored: on cache lines of its own (core.h, dp_calloc_cache_aligned). */
typedef struct {
    _Alignas(DP_CACHE_LINE) photon_buf vol;
    photon_buf surf;
    beam_buf beams;
    vertex_buf verts;
    long nonfinite;
    int oom;
} thread_bufs;

typedef struct {
    uint32_t n_vol, n_surf;    /* photons this path stored */
    uint32_t n_beams;          /* beams this path stored (photon_pass_input.beams) */
    size_t off_beams;
    uint32_t n_verts;          /* vertices this path recorded (photon_pass_input.vertices) */
    size_t off_verts;
    int early_exit;            /* ended by the DARTS early exit */
    int thread;                /* whose buffers hold them */
    size_t off_vol, off_surf;  /* where they start there */
} path_count;

/* One light path from a light picked with rng, its photons appended to tb and counted in pc. volume_open:
 * the volume budget has room (the DARTS samplers run); 0: the path only feeds surface photons. */
void trace_light_path(const scene *s, const photon_pass_input *in, int volume_open, dp_rng *rng, thread_bufs *tb,
                      path_count *pc);

/* ---- surface chains (surface_chain.c) ---- */
typedef struct {
    photon_chain_stats st;
    int thread;           /* whose buffer holds its photons */
    size_t off;           /* where they start there */
    uint32_t n;           /* how many: each distinct state's photons once, powers times the steps it held */
} chain_count;

typedef struct chain_scratch chain_scratch;
chain_scratch *chain_scratch_new(void);
void chain_scratch_free(chain_scratch *cs);
/* Chain `index` of this pass, `steps` light paths long, its photons appended to tb->surf. */
void surface_chain_run(const scene *s, const photon_pass_input *in, long index, int steps, chain_scratch *cs,
                       thread_bufs *tb, chain_count *cc);

#endif
