/* Inside src/sliced_primitives: what the build hands the map. */
#ifndef DARTSPP_SLICE_INTERNAL_H
#define DARTSPP_SLICE_INTERNAL_H

#include "dartspp/sliced_primitives.h"

/* A primitive's bounds: every root lies in [lo, hi] (the time budget, slice_build.c), c its centre. */
typedef struct {
    float lo[3], hi[3], c[3];
    float budget;      /* τ_k − τ(x): no root once the camera time at the segment origin reaches it */
    uint32_t prim;
} slice_box;

/* The primitives the type builds at the n vertices, with their bounds (*prims and *boxes allocated, *np of
 * each). 0, or -1 out of memory. */
int slice_build(const scene *s, const slice_build_input *in, const path_vertex *v, size_t n, slice_prim **prims,
                slice_box **boxes, size_t *np);

/* The sampling density of the fresh directions: the phase function of the region the base vertex's direction
 * leaves into where it scatters, else uniform on the sphere. */
const phase_function *slice_sampling_phase(const scene *s, int region);

#endif
