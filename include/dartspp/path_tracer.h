/* dartspp path_tracer: the path tracers, one integrator ("type": "path_tracer") with three methods — plain
 * (the unbiased reference), DARTS (camera paths aimed at a light and a time bin by DA distance sampling,
 * elliptical control vertices and EDA) and uniform time (Jarabo et al. 2014 as the DARTS supplement §B.4
 * corrects it). The plan says which (render_plan.darts.active, render_plan.uniform_time); src/path_tracer/README.md
 * says how each works. The driver (src/render) calls it through its table of integrators. */
#ifndef DARTSPP_PATH_TRACER_H
#define DARTSPP_PATH_TRACER_H

#include "dartspp/darts.h"
#include "dartspp/film.h"
#include "dartspp/integrator.h"
#include "dartspp/plan.h"
#include "dartspp/scene.h"

/* One pass of the path tracer (plain, DARTS or uniform time, as the plan says; eda: the EDA tables, may
 * be NULL when no medium uses EDA) over every pixel into f's pass layer; adds the rays traced to st->rays.
 * Deterministic: the samples of pixel p in pass i come from rng_stream(seed, i, p). Once stop is set the
 * remaining rows are skipped (the caller drops the pass). 0, or -1 with err (out of memory). */
int path_tracer_pass(const scene *s, const render_plan *p, const eda_set *eda, film *f, uint64_t seed,
                     long pass, const dp_stop_flag *stop, render_stats *st, dp_error *err);

#endif
